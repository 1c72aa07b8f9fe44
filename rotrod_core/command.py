"""Shaping a stream of angular-velocity setpoints into a physical w(t), w'(t).

A drive cannot follow a setpoint stream literally: a jump of w is an infinite
angular acceleration. :class:`OmegaSetpointShaper` makes w(t) continuous and
piecewise linear, w'(t) piecewise constant and never beyond
``max_angular_acceleration``, by linear interpolation of the stream delayed by one
setpoint interval:

- the stream's interval T is estimated from the arrival times;
- arrivals are placed on a regular grid fitted to the recent ones (least squares),
  so that delivery jitter of less than T does not reach w;
- setpoint k is reached at its grid time + T, by a ramp from setpoint k - 1.

A profile streamed at a steady rate is thus reproduced as its linear interpolation
delayed by T, even with jittery delivery; an isolated step (after a pause in the
stream) becomes a ramp over one interval or at the acceleration limit.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections import deque
from dataclasses import dataclass


def _finite(name: str, value, *, positive: bool = False) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise ValueError(f'{name} must be a number, got {value!r}') from None
    if isinstance(value, bool) or not math.isfinite(x):
        raise ValueError(f'{name} must be a finite number, got {value!r}')
    if positive and not x > 0:
        raise ValueError(f'{name} must be > 0, got {value!r}')
    return x


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
        delay: how many intervals after its grid time a setpoint is reached (>= 1).
            Delivery jitter up to ``delay - 1`` intervals does not reach w; a later
            arrival holds w until it comes. The stream is taken as lossless (reliable
            delivery): arrivals are numbered in order.
        omega: initial angular velocity, rad/s; time: initial time, s.
    """

    def __init__(self, max_angular_acceleration: float, *, nominal_interval: float = 0.01,
                 min_interval: float = 1e-4, max_interval: float = 0.25,
                 window: int = 200, delay: float = 2.0, omega: float = 0.0, time: float = 0.0):
        self.max_angular_acceleration = _finite(
            'max_angular_acceleration', max_angular_acceleration, positive=True)
        self.nominal_interval = _finite('nominal_interval', nominal_interval, positive=True)
        self.min_interval = _finite('min_interval', min_interval, positive=True)
        self.max_interval = _finite('max_interval', max_interval, positive=True)
        if not self.min_interval <= self.nominal_interval <= self.max_interval:
            raise ValueError('need min_interval <= nominal_interval <= max_interval')
        if isinstance(window, bool) or not isinstance(window, int) or window < 2:
            raise ValueError(f'window must be an integer >= 2, got {window!r}')
        self.window = window
        self.delay = _finite('delay', delay, positive=True)
        if self.delay < 1:
            raise ValueError(f'delay must be >= 1 interval, got {delay!r}')
        self.reset(omega, time)

    def reset(self, omega: float = 0.0, time: float = 0.0) -> None:
        """Hold ``omega`` (rad/s) from ``time`` (s) on; forget the stream."""
        w, t = _finite('omega', omega), _finite('time', time)
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

        The grid is the least-squares line through the stream's recent arrivals
        (arrival number -> time), so its phase and interval average the jitter out.
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
        k0, t0 = window[0]
        ks = [kk - k0 for kk, _ in window]
        ts = [tt - t0 for _, tt in window]
        k_mean, t_mean = sum(ks) / n, sum(ts) / n
        skk = sum((kk - k_mean) ** 2 for kk in ks)
        skt = sum((kk - k_mean) * (tt - t_mean) for kk, tt in zip(ks, ts))
        slope = min(max(skt / skk, self.min_interval), self.max_interval)
        grid = t0 + t_mean + slope * (k - k0 - k_mean)
        tolerance = max(1.0, self.delay - 1.0) * slope
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
        w_set, t = _finite('setpoint', setpoint), _finite('time', time)
        if self._last_arrival is not None and t < self._last_arrival:
            raise ValueError(f'setpoint time {t} s precedes the previous one '
                             f'({self._last_arrival} s)')
        t = max(t, self._starts[0])
        lag = self.delay * self.interval
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
