"""Shaping a stream of angular-velocity setpoints into a physical w(t), w'(t).

A drive cannot follow a setpoint stream literally: a jump of w is an infinite
angular acceleration. :class:`OmegaSetpointShaper` makes w(t) continuous and
piecewise linear, w'(t) piecewise constant and never beyond
``max_angular_acceleration``, by linear interpolation of the stream delayed by a
fixed lag D:

- the stream's interval T is estimated from the arrival times;
- arrivals are placed on a regular grid fitted to the recent ones (least-squares
  interval, phase from the punctual arrivals), so that delivery jitter and stalls
  shorter than D - T do not reach w;
- setpoint k is reached at its grid time + D, by a ramp from setpoint k - 1.

A profile streamed at a steady rate is thus reproduced as its linear interpolation
delayed by D, even with jittery delivery; an isolated step (after a pause in the
stream) becomes a ramp over D, or longer at the acceleration limit.
"""

from __future__ import annotations

from bisect import bisect_right
from collections import deque
from dataclasses import dataclass

import numpy as np

from .checks import finite_number

PHASE_QUANTILE = 0.1
"""Quantile of the arrivals' offsets from the fitted line that sets the grid's phase."""


@dataclass(frozen=True)
class Ramp:
    """From ``start`` (s) on, w = ``omega_start`` + ``rate`` (t - start), until ``end``."""

    start: float
    omega_start: float
    rate: float
    end: float

    def omega(self, t: float) -> float:
        """Angular velocity at time ``t`` >= start (held at the target after ``end``), rad/s."""
        return self.omega_start + self.rate * (min(t, self.end) - self.start)


def _fit_line(x, y) -> tuple:
    """Least-squares slope of y(x) and the fitted values."""
    xm, ym = x.mean(), y.mean()
    slope = float(np.dot(x - xm, y - ym) / np.dot(x - xm, x - xm))
    return slope, ym + slope * (x - xm)


class OmegaSetpointShaper:
    """Continuous w(t) from timestamped angular-velocity setpoints.

    Args:
        max_angular_acceleration: bound on |w'|, rad/s^2 (> 0).
        nominal_interval: setpoint interval assumed before the stream shows its own,
            s (default 0.01 s, i.e. 100 Hz).
        min_interval, max_interval: bounds of the interval estimate, s; a gap longer
            than ``max_interval`` is a pause in the stream, after which the next
            setpoint starts a new stream.
        window: number of recent arrivals the grid is fitted to.
        delay: how long after its grid time a setpoint is reached, s (a fixed lag;
            at least two stream intervals). Delivery jitter and stalls up to
            ``delay`` minus one interval do not reach w; a later arrival holds w
            until it comes. The stream is taken as lossless (reliable delivery):
            arrivals are numbered in order.
        omega: initial angular velocity, rad/s; time: initial time, s.
    """

    def __init__(self, max_angular_acceleration: float, *, nominal_interval: float = 0.01,
                 min_interval: float = 1e-4, max_interval: float = 0.25,
                 window: int = 1000, delay: float = 0.02, omega: float = 0.0, time: float = 0.0):
        self.max_angular_acceleration = finite_number(
            'max_angular_acceleration', max_angular_acceleration, positive=True)
        self.nominal_interval = finite_number('nominal_interval', nominal_interval, positive=True)
        self.min_interval = finite_number('min_interval', min_interval, positive=True)
        self.max_interval = finite_number('max_interval', max_interval, positive=True)
        if not self.min_interval <= self.nominal_interval <= self.max_interval:
            raise ValueError('need min_interval <= nominal_interval <= max_interval')
        if isinstance(window, bool) or not isinstance(window, int) or window < 2:
            raise ValueError(f'window must be an integer >= 2, got {window!r}')
        self.window = window
        self.delay = finite_number('delay', delay, positive=True)
        self.reset(omega, time)

    def reset(self, omega: float = 0.0, time: float = 0.0) -> None:
        """Hold ``omega`` (rad/s) from ``time`` (s) on; forget the stream."""
        w, t = finite_number('omega', omega), finite_number('time', time)
        self._ramps = [Ramp(t, w, 0.0, t)]
        self._starts = [t]
        self._last_arrival = None
        self._window: deque = deque()
        self.interval = self.nominal_interval
        self.setpoint = w

    def _ramp_at(self, t: float) -> Ramp:
        return self._ramps[max(0, bisect_right(self._starts, t) - 1)]

    def omega(self, t: float) -> float:
        """Shaped angular velocity at time ``t`` (s), rad/s."""
        return self._ramp_at(t).omega(t)

    def omega_dot(self, t: float) -> float:
        """Shaped angular acceleration just after time ``t`` (s), rad/s^2."""
        ramp = self._ramp_at(t)
        return ramp.rate if t < ramp.end else 0.0

    @property
    def last_command_time(self) -> float:
        """Arrival time (s) of the latest setpoint (or the reset time)."""
        return self._last_arrival if self._last_arrival is not None else self._starts[0]

    @property
    def target_reached_at(self) -> float:
        """Time (s) at which w reaches the latest setpoint."""
        return self._ramps[-1].end

    def _place_on_grid(self, t: float) -> float:
        """Grid time of a setpoint arriving at ``t``; updates the interval estimate.

        The interval is the slope of the least-squares line through the stream's
        recent arrivals (arrival number -> time). Delivery delays are one-sided (late,
        in bursts after a stall), so the grid's phase is the line moved down to a low
        quantile of the arrivals, not their mean: the punctual arrivals set it.
        """
        window = self._window
        if self._last_arrival is not None and t - self._last_arrival > self.max_interval:
            window.clear()                        # a pause: a new stream starts here
        self._last_arrival = t
        k = window[-1][0] + 1 if window else 0
        window.append((k, t))
        if len(window) > self.window:
            window.popleft()
        n = len(window)
        if n < 2:
            return t
        data = np.array(window, dtype=float)
        ks = data[:, 0] - data[0, 0]
        ts = data[:, 1] - data[0, 1]
        slope, line = _fit_line(ks, ts)
        if n >= 10:
            # refit through the punctual half: late bursts do not tilt the grid
            punctual = ts - line <= np.median(ts - line)
            if np.count_nonzero(punctual) >= 2 and np.ptp(ks[punctual]) > 0:
                slope, _ = _fit_line(ks[punctual], ts[punctual])
                line = np.mean(ts[punctual]) + slope * (ks - np.mean(ks[punctual]))
        slope = min(max(slope, self.min_interval), self.max_interval)
        phase = float(np.quantile(ts - line, PHASE_QUANTILE)) if n >= 10 else 0.0
        grid = data[0, 1] + line[-1] + phase
        tolerance = max(self.delay - slope, slope)
        if not -tolerance < t - grid < tolerance:  # lost the phase: resynchronise
            window.clear()
            window.append((0, t))
            return t
        self.interval = slope
        return grid

    def command(self, setpoint: float, time: float) -> Ramp:
        """Take setpoint ``setpoint`` (rad/s) arriving at ``time`` (s); return its ramp.

        Arrival times must not decrease. The ramp starts where the previous one ends
        (if that is within one interval) or at the arrival, and reaches the setpoint
        at the arrival's grid time plus one interval, or later if the acceleration
        limit requires.
        """
        w_set, t = finite_number('setpoint', setpoint), finite_number('time', time)
        if self._last_arrival is not None and t < self._last_arrival:
            raise ValueError(f'setpoint time {t} s precedes the previous one '
                             f'({self._last_arrival} s)')
        t = max(t, self._starts[0])
        lag = self.delay
        deadline = self._place_on_grid(t) + lag
        previous_end = self._ramps[-1].end
        start = previous_end if t <= previous_end <= t + lag else t
        w0 = self.omega(start)
        while len(self._ramps) > 1 and self._starts[-1] >= start:
            self._ramps.pop()
            self._starts.pop()
        delta = w_set - w0
        end = max(deadline, start + abs(delta) / self.max_angular_acceleration)
        rate = delta / (end - start) if end > start else 0.0
        ramp = Ramp(start, w0, rate, end if rate else start)
        self._ramps.append(ramp)
        self._starts.append(start)
        self.setpoint = w_set
        return ramp

    def forget_before(self, t: float) -> None:
        """Drop ramps that ended before time ``t`` (s); keeps memory bounded."""
        i = max(0, bisect_right(self._starts, t) - 1)
        if i:
            del self._ramps[:i]
            del self._starts[:i]
