"""Shaping a stream of angular-velocity setpoints into a physical w(t), w'(t).

A drive cannot follow a setpoint stream literally: a jump of w is an infinite
angular acceleration. :class:`OmegaSetpointShaper` makes w(t) continuous and
piecewise linear, w'(t) piecewise constant and never beyond
``max_angular_acceleration``, by linear interpolation of the stream delayed by a
fixed lag D:

- arrivals are placed on a regular grid: the lower envelope (convex hull) of the
  recent arrival times against their sequence numbers. Delivery delays are
  one-sided -- a message can be late, never early -- so the punctual arrivals set
  the grid, and jitter, stalls and catch-up bursts do not move it. Once the stream
  is established, the grid follows that envelope's line smoothly (a first-order
  filter with time constant ``GRID_TIME_CONSTANT``): the line jumps when a new
  punctual arrival or the window's middle changes its contact with the hull, and a
  jump of the grid by d while w changes is an error of w' d in w, an impulse that
  leaves the rod whirling;
- setpoint k is reached at its grid time + D, by a ramp from setpoint k - 1;
- setpoints that come before the grid is known (the first of a stream, or a start
  burst: samples held up until the subscriber matched the sender, then delivered
  together) are due D after their arrival, w waiting as long as the limit lets it;
  once the grid is known, those still ahead are placed on it, so a start burst held
  up for less than D does not reach w either;
- a setpoint that arrives too late for that (a stall longer than D) is not chased:
  until it comes, w follows the stream extrapolated from its last three setpoints
  (w' going on linearly, within the acceleration limit), and then rejoins the
  delayed interpolation within one interval. If no setpoint comes within
  ``max_stall``, w returns to the last one.

A profile streamed at a steady rate is thus reproduced as its linear interpolation
delayed by D, even with jittery delivery; a smooth profile survives a stall of
length s > D with an error of order w''' s^3; an isolated step (after a pause in
the stream) becomes a ramp over D, or longer at the acceleration limit.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections import deque
from dataclasses import dataclass

import numpy as np

from rotrod_core.model.description import DEFAULT_LIMITS
from rotrod_core.numerics.checks import finite_number

MIN_STREAM = 10
"""Arrivals after which a stream is established: its slope is extrapolated when late."""

GRID_TIME_CONSTANT = 3.0
"""Time constant of the grid's phase correction, s: once a stream is established, each
arrival moves the grid towards the lower envelope's line by interval / this of the
difference. The line jumps by up to ~0.5 ms at a time on this machine's loopback, and
each jump during a change of speed is an impulse w' x jump on the rod; filtered over
3 s (six periods of Table 1's rod) such jumps become slow drifts of the timing
(``bench/bench_stream.py`` replays arrival times recorded from the nodes, with and
without the filter)."""

MAX_PATH_SEGMENTS = 50
"""Most segments of an extrapolated path (one per interval, fewer for a stream faster than
100 Hz). Every ramp of a stream holds its path, and a fast stream keeps a ramp per
setpoint for the delay ahead: with 1000 segments a 10 kHz stream held ~160 MB of them."""

DEFAULT_MAX_ANGULAR_ACCELERATION = DEFAULT_LIMITS.max_angular_acceleration
"""The default bound on |w'| of a shaped stream, rad/s^2: the simulator's
``max_angular_acceleration`` unless configured, and the bound the profile publisher's
planned spin-up honours by default (one value for both; see
:data:`~rotrod_core.model.description.DEFAULT_LIMITS`)."""

MAX_OMEGA = 1e300
"""Largest |w| accepted as a setpoint or initial speed, rad/s: w and its differences
stay finite (a bound for float range, not a physical one)."""


def _within_limit(times: list, omegas: list, limit: float) -> None:
    """Delay knots by float rounding steps where a segment's slope exceeds ``limit``.

    The knots are placed so that every slope is within the limit, but at large times
    the rounding of t + d - t (d a duration) can exceed it by parts in 1e9.
    """
    dt, dw = np.diff(times), np.abs(np.diff(omegas))
    with np.errstate(all='ignore'):
        if np.all((dw == 0) | ((dt > 0) & (dw / dt <= limit))):
            return                      # the usual case, checked at numpy speed
    for i in range(1, len(times)):
        if not math.isfinite(times[i - 1]):
            break
        dw = abs(omegas[i] - omegas[i - 1])
        while dw and (times[i] <= times[i - 1] or dw / (times[i] - times[i - 1]) > limit):
            times[i] = math.nextafter(times[i], math.inf)


@dataclass(frozen=True)
class Ramp:
    """A piecewise-linear w(t) through knots ``times`` (s) and ``omegas`` (rad/s).

    The first segment is the ramp proper, from the start to the target at ``end``;
    w holds the last knot's value after it. A streamed setpoint's ramp goes on (coasts)
    at the stream's slope in case the next setpoint is late, then returns to the
    setpoint if none has come.
    """

    times: tuple
    omegas: tuple

    @property
    def start(self) -> float:
        """Start time, s."""
        return self.times[0]

    @property
    def end(self) -> float:
        """Time at which the ramp proper reaches its target, s."""
        return self.times[1]

    def _segment(self, t: float) -> int:
        return max(0, bisect_right(self.times, t) - 1)

    def omega(self, t: float) -> float:
        """Angular velocity at time ``t`` >= start, rad/s."""
        i = self._segment(t)
        if i == len(self.times) - 1:
            return self.omegas[-1]
        t0, t1, w0, w1 = self.times[i], self.times[i + 1], self.omegas[i], self.omegas[i + 1]
        return w0 + (w1 - w0) * ((t - t0) / (t1 - t0))

    def omega_array(self, t: np.ndarray) -> np.ndarray:
        """:meth:`omega` at each of the times ``t`` (>= start), rad/s: the same arithmetic."""
        first, last = self._segment(float(t[0])), self._segment(float(t[-1]))
        if first == last:                       # the usual case: one segment
            if first == len(self.times) - 1:
                return np.full(t.shape, float(self.omegas[-1]))
            t0, t1 = self.times[first], self.times[first + 1]
            w0, w1 = self.omegas[first], self.omegas[first + 1]
            return w0 + (w1 - w0) * ((t - t0) / (t1 - t0))
        knots = np.asarray(self.times, dtype=float)
        values = np.asarray(self.omegas, dtype=float)
        i = np.maximum(np.searchsorted(knots, t, side='right') - 1, 0)
        last = i == len(knots) - 1
        j = np.minimum(i, len(knots) - 2) if len(knots) > 1 else i
        t0, w0 = knots[j], values[j]
        t1, w1 = knots[np.minimum(j + 1, len(knots) - 1)], values[np.minimum(j + 1,
                                                                          len(knots) - 1)]
        with np.errstate(all='ignore'):      # the segments not selected may divide by 0
            inside = w0 + (w1 - w0) * ((t - t0) / (t1 - t0))
        return np.where(last, values[-1], inside)

    def omega_dot(self, t: float) -> float:
        """Angular acceleration just after time ``t`` >= start, rad/s^2."""
        i = self._segment(t)
        if i == len(self.times) - 1:
            return 0.0
        t0, t1, w0, w1 = self.times[i], self.times[i + 1], self.omegas[i], self.omegas[i + 1]
        return (w1 - w0) / (t1 - t0)


def _start(ramp: Ramp) -> float:
    return ramp.start


def _omega(name: str, value) -> float:
    """A finite angular velocity within +-MAX_OMEGA, rad/s; else ValueError."""
    w = finite_number(name, value)
    if not abs(w) <= MAX_OMEGA:
        raise ValueError(f'{name} must be within +-{MAX_OMEGA:g} rad/s, got {value!r}')
    return w


class LowerEnvelope:
    """Lower convex hull of the points (i, t_i), i = 0, 1, 2, ..., over a sliding window.

    Points come in order of i (a setpoint's sequence number; t_i its arrival time,
    s). Adding a point costs O(1) amortized (Andrew's monotone chain); dropping the
    oldest rebuilds only the hull's first edge.
    """

    def __init__(self, size: int):
        self.size = size
        self.clear()

    def clear(self) -> None:
        """Forget every point."""
        self._t: list = []
        self._head = 0            # index of the oldest point in the window
        self._hull: list = []     # indices of the hull's vertices, in order

    @property
    def count(self) -> int:
        """Number of points in the window."""
        return len(self._t) - self._head

    def _below(self, a: int, b: int, c: int) -> bool:
        """True if b lies on or above the segment a-c (so b is not a hull vertex)."""
        t = self._t
        return (b - a) * (t[c] - t[a]) - (t[b] - t[a]) * (c - a) <= 0.0

    def _push(self, i: int) -> None:
        hull = self._hull
        while len(hull) >= 2 and self._below(hull[-2], hull[-1], i):
            hull.pop()
        hull.append(i)

    def add(self, t: float) -> None:
        """Add the next point, at time ``t`` (s)."""
        self._t.append(t)
        self._push(len(self._t) - 1)
        if self.count > self.size:
            self._drop_oldest()

    def _drop_oldest(self) -> None:
        oldest = self._head
        self._head += 1
        if self._hull[0] == oldest:
            # points hidden by the first edge may now be vertices: rebuild that edge
            rest = self._hull[1:]
            self._hull = []
            for i in range(oldest + 1, rest[0] + 1):
                self._push(i)
            for i in rest[1:]:
                self._push(i)
        if self._head >= self.size:           # compact the storage
            h = self._head
            self._t = self._t[h:]
            self._hull = [i - h for i in self._hull]
            self._head = 0

    def vertices(self) -> list[int]:
        """Positions in the window (0 = oldest) of the hull's vertices."""
        return [i - self._head for i in self._hull]

    def mean_interval(self) -> float:
        """Mean spacing of the window's times: (newest - oldest) / (count - 1), s.

        Unlike the hull's slopes it counts every point, so a burst does not bias it
        below the stream's interval (only the oldest and newest delays enter it).
        """
        return (self._t[-1] - self._t[self._head]) / (self.count - 1)

    def line(self) -> tuple[float, float]:
        """The grid: (slope, value at the newest point) of a supporting line.

        The hull's supporting line at the window's middle: of the lines below every
        point, the one closest to them on average.
        """
        hull, t = self._hull, self._t
        middle = 0.5 * (self._head + len(t) - 1)
        j = min(max(bisect_right(hull, middle), 1), len(hull) - 1)
        a, b = hull[j - 1], hull[j]
        slope = (t[b] - t[a]) / (b - a)
        return slope, t[a] + slope * (len(t) - 1 - a)


class OmegaSetpointShaper:
    """Continuous w(t) from timestamped angular-velocity setpoints.

    Args:
        max_angular_acceleration: bound on |w'|, rad/s^2 (> 0).
        nominal_interval: setpoint interval reported before the stream shows its own,
            s (default 0.01 s, i.e. 100 Hz).
        min_interval, max_interval: bounds of the interval estimate, s.
        max_stall: longest gap between arrivals taken as a stall of the stream, s; after
            a longer one (a pause) the next setpoint starts a new stream. During a
            stall, w follows the stream's extrapolation for at most this long.
        window: number of recent arrivals the grid is fitted to.
        delay: how long after its grid time a setpoint is reached, s (a fixed lag;
            at least two stream intervals). Delivery jitter and stalls up to
            ``delay`` minus half an interval do not reach w; during a longer stall
            w follows the stream's extrapolation. The stream is taken as lossless
            (reliable delivery): arrivals are numbered in order.
        omega: initial angular velocity, rad/s; time: initial time, s.
    """

    def __init__(self, max_angular_acceleration: float, *, nominal_interval: float = 0.01,
                 min_interval: float = 1e-4, max_interval: float = 0.25,
                 max_stall: float = 0.5,
                 window: int = 1000, delay: float = 0.02, omega: float = 0.0, time: float = 0.0):
        self.max_angular_acceleration = finite_number(
            'max_angular_acceleration', max_angular_acceleration, positive=True)
        self.nominal_interval = finite_number('nominal_interval', nominal_interval, positive=True)
        self.min_interval = finite_number('min_interval', min_interval, positive=True)
        self.max_interval = finite_number('max_interval', max_interval, positive=True)
        self.max_stall = finite_number('max_stall', max_stall, positive=True)
        if not (self.min_interval <= self.nominal_interval <= self.max_interval
                <= self.max_stall):
            raise ValueError('need min_interval <= nominal_interval <= max_interval '
                             '<= max_stall')
        if not self.max_angular_acceleration * self.max_stall <= MAX_OMEGA:
            raise ValueError(f'max_angular_acceleration x max_stall (the largest change of w '
                             f'during a stall) must be <= {MAX_OMEGA:g} rad/s')
        if isinstance(window, bool) or not isinstance(window, int) or window < 2:
            raise ValueError(f'window must be an integer >= 2, got {window!r}')
        self.window = window
        self.delay = finite_number('delay', delay, positive=True)
        self._envelope = LowerEnvelope(window)
        self.reset(omega, time)

    def reset(self, omega: float = 0.0, time: float = 0.0) -> None:
        """Hold ``omega`` (rad/s) from ``time`` (s) on; forget the stream."""
        w, t = _omega('omega', omega), finite_number('time', time)
        self._ramps = [Ramp((t, t), (w, w))]
        self._last_arrival: float | None = None
        # (due time, setpoint) of the latest ones
        self._recent: deque[tuple[float, float]] = deque(maxlen=3)
        self._envelope.clear()
        # (due time, setpoint) of the stream's latest arrivals placed without a grid,
        # and the start of the first one's ramp (s)
        self._ungridded: list[tuple[float, float]] = []
        self._ungridded_from = t
        # grid time of the latest setpoint of an established stream
        self._grid: float | None = None
        self.interval = self.nominal_interval
        self.setpoint = w
        self.late_setpoints = 0

    def _ramp_at(self, t: float) -> Ramp:
        ramps = self._ramps
        if len(ramps) == 1:                     # the usual case, twice per rod per block
            return ramps[0]
        return ramps[max(0, bisect_right(ramps, t, key=_start) - 1)]

    def omega(self, t: float) -> float:
        """Shaped angular velocity at time ``t`` (s), rad/s."""
        t = finite_number('time', t)
        return self._ramp_at(t).omega(t)

    def held(self, t: float) -> float | None:
        """The constant w (rad/s) from time ``t`` (s) on, else None.

        Constant when every ramp has ended by then: a rod holding its speed, most blocks.
        """
        ramps = self._ramps
        if len(ramps) == 1 and t >= ramps[0].times[-1]:
            return ramps[0].omegas[-1]
        return None

    @property
    def ramp_count(self) -> int:
        """How many ramps are kept (one: the one in force; more: some may be dropped)."""
        return len(self._ramps)

    def segment(self, t_first: float, t_last: float) -> tuple | None:
        """The one linear piece of w(t) over [t_first, t_last] (s), if one covers it.

        (w0, w1, t0, t1): w(t) = w0 + (w1 - w0) ((t - t0) / (t1 - t0)), the arithmetic of
        :meth:`omega` (a constant w0 has w1 = w0). None when w bends in between.
        """
        ramp = self._ramp_at(t_first)
        if ramp is not self._ramp_at(t_last):
            return None
        i = ramp._segment(t_first)
        if i != ramp._segment(t_last):
            return None
        if i == len(ramp.times) - 1:
            w = ramp.omegas[-1]
            return (w, w, t_first, t_first + 1.0)
        return (ramp.omegas[i], ramp.omegas[i + 1], ramp.times[i], ramp.times[i + 1])

    def omegas(self, times: np.ndarray) -> np.ndarray:
        """:meth:`omega` at each of the increasing, finite ``times`` (s), rad/s.

        The same arithmetic as :meth:`omega`, vectorised (a block of simulation steps).
        """
        times = np.asarray(times, dtype=float)
        first = self._ramp_at(float(times[0]))
        if first is self._ramp_at(float(times[-1])):      # the usual case: one ramp
            return first.omega_array(times)
        starts = [r.start for r in self._ramps]
        which = np.maximum(np.searchsorted(starts, times, side='right') - 1, 0)
        out = np.empty(times.shape)
        for i in np.unique(which):
            chosen = which == i
            out[chosen] = self._ramps[int(i)].omega_array(times[chosen])
        return out

    def omega_dot(self, t: float) -> float:
        """Shaped angular acceleration just after time ``t`` (s), rad/s^2."""
        t = finite_number('time', t)
        return self._ramp_at(t).omega_dot(t)

    @property
    def last_command_time(self) -> float:
        """Arrival time (s) of the latest setpoint (or the reset time)."""
        return self._last_arrival if self._last_arrival is not None else self._ramps[0].start

    @property
    def target_reached_at(self) -> float:
        """Time (s) at which w reaches the latest setpoint (or its extrapolation)."""
        return self._ramps[-1].end

    def _place_on_grid(self, t: float) -> float | None:
        """Grid time of a setpoint arriving at ``t``, or None if it starts a stream.

        The grid is the lower envelope's supporting line through the stream's recent
        arrivals (sequence number -> time); its slope is the stream's interval.
        """
        envelope = self._envelope
        previous, self._grid = self._grid, None
        if self._last_arrival is not None and t - self._last_arrival > self.max_stall:
            envelope.clear()                       # a pause: a new stream starts here
            self._ungridded.clear()
            previous = None
        self._last_arrival = t
        envelope.add(t)
        if envelope.count < 2:
            return None
        slope, grid = envelope.line()
        if slope < 0.5 * envelope.mean_interval():
            # the window's middle is a burst: samples held up and delivered together,
            # as when a stream starts before its subscriber has matched the sender. Its
            # spacing is no interval of the stream, and lines across it run below the
            # punctual samples after it: the grid starts over from this arrival
            # (the setpoints of the burst, taken without a grid, stay the ones before it)
            envelope.clear()
            envelope.add(t)
            return None
        if not self.min_interval <= slope <= self.max_interval:
            # a burst with no punctual arrival yet (or a stream too fast to track):
            # the grid is unknown, the setpoint is taken as it comes
            return None
        self.interval = slope
        if previous is not None and envelope.count > MIN_STREAM:
            # established: move smoothly towards the envelope's line, unless it is
            # more than half an interval away (then the stream itself has moved)
            step = previous + slope
            if abs(grid - step) <= 0.5 * slope:
                grid = step + min(1.0, slope / GRID_TIME_CONSTANT) * (grid - step)
        self._grid = grid
        return grid

    def command(self, setpoint: float, time: float) -> Ramp:
        """Take setpoint ``setpoint`` (rad/s) arriving at ``time`` (s); return its ramp.

        Arrival times must not decrease. On time, the ramp starts where the previous
        one ends (or at the arrival) and reaches the setpoint at its grid time plus
        the delay, or later if the acceleration limit requires. Too late for that,
        the ramp starts at the arrival and reaches, one interval later, the stream's
        extrapolation.
        """
        w_set, t = _omega('setpoint', setpoint), finite_number('time', time)
        if self._last_arrival is not None and t < self._last_arrival:
            raise ValueError(f'setpoint time {t} s precedes the previous one '
                             f'({self._last_arrival} s)')
        t = max(t, self._ramps[0].start)
        grid = self._place_on_grid(t)
        due = (t if grid is None else grid) + self.delay
        recent = self._recent
        if grid is None:
            recent.clear()
        elif self._ungridded:
            self._place_ungridded(t, grid)
        recent.append((due, w_set))
        limit = self.max_angular_acceleration
        path = None
        if grid is not None and self._envelope.count >= MIN_STREAM and len(recent) == 3:
            path = self._extrapolation()
        last = self._ramps[-1]
        if due >= t + 0.5 * self.interval:       # on time: reach the setpoint when due
            # from where the previous ramp ends, if the limit lets w get from there to
            # the setpoint by its due time; else (a burst: due times together) from now,
            # straight to the setpoint, leaving the previous one unreached
            chained = (t <= last.end <= due and abs(w_set - last.omegas[1])
                       <= limit * (due - last.end))
            if chained:
                start = last.end
            elif grid is None and last.end > t:
                # setpoints together before the stream's grid is known (a start burst):
                # w waits as long as the limit lets it still reach this one when due,
                # so that the grid, once known, can place them where they belong
                w_now = self.omega(t)
                start = max(t, min(due - self.interval, due - abs(w_set - w_now) / limit))
            else:
                start = t
            reach, target = due, w_set
        else:                                   # late: rejoin the extrapolated stream
            self.late_setpoints += 1
            start = t
            reach = t + self.interval
            target = float(np.interp(reach, *path)) if path else w_set
        w0 = self.omega(start)
        while len(self._ramps) > 1 and self._ramps[-1].start >= start:
            self._ramps.pop()
        end = max(reach, start + abs(target - w0) / limit)
        times, omegas = [start, end], [w0, target]
        if path and end == reach and path[0][-1] > end:
            # no later setpoint yet: follow the stream's extrapolation for up to
            # max_stall, then return to this setpoint
            after = path[0] > end
            times += path[0][after].tolist()
            omegas += path[1][after].tolist()
            times.append(times[-1] + max(self.delay, abs(omegas[-1] - w_set) / limit))
            omegas.append(w_set)
        elif target != w_set:
            # late, and the extrapolation cannot be followed (w too far from it for the
            # limit, or past its end): still, a stream that stops ends at its last
            # setpoint, so w returns to it unless a later one comes
            times.append(end + max(self.delay, abs(target - w_set) / limit))
            omegas.append(w_set)
        _within_limit(times, omegas, limit)
        ramp = Ramp(tuple(times), tuple(omegas))
        self._ramps.append(ramp)
        self.setpoint = w_set
        if grid is None:
            if not self._ungridded:
                self._ungridded_from = start
            self._ungridded.append((due, w_set))
        return ramp

    def _place_ungridded(self, t: float, grid: float) -> None:
        """Place the setpoints that came before the grid was known on it (at ``t``, s).

        ``grid`` is the grid time (s) of the arrival that made the grid known; the
        setpoints before it are the previous sequence numbers, one interval apart. A
        start burst (samples held up until the subscriber matched the sender) came in
        together at the time of its last sample: its setpoints are due earlier on the
        grid, and while those due times are still ahead, w goes through them there, as
        if they had come on time. Not when that would need more than the acceleration
        limit, or moves no due time (a punctual start).
        """
        placed = self._ungridded
        self._ungridded = []
        n = len(placed)
        knots = [(grid - (n - i) * self.interval + self.delay, w)
                 for i, (_, w) in enumerate(placed)]
        if all(abs(new - old) <= 1e-9 for (new, _), (old, _) in zip(knots, placed)):
            return
        # from where their ramps begin: the ramps before them stay
        begin = max(t, self._ungridded_from)
        ahead = [(d, w) for d, w in knots if d > begin]
        if not ahead:
            return
        times = [begin] + [d for d, _ in ahead]
        omegas = [self.omega(begin)] + [w for _, w in ahead]
        limit = self.max_angular_acceleration
        dt, dw = np.diff(times), np.abs(np.diff(omegas))
        if np.any(dt <= 0) or np.any(dw > limit * dt):
            return
        while len(self._ramps) > 1 and self._ramps[-1].start >= begin:
            self._ramps.pop()
        _within_limit(times, omegas, limit)
        for i in range(1, len(times)):              # one ramp per setpoint, chained
            self._ramps.append(Ramp((times[i - 1], times[i]), (omegas[i - 1], omegas[i])))

    def _extrapolation(self) -> tuple[np.ndarray, np.ndarray]:
        """The stream extrapolated from its latest setpoint for ``max_stall``.

        Knot times (s) and angular velocities (rad/s): w' goes on linearly (slope and
        curvature from the last three setpoints), bounded by the acceleration limit.
        """
        (d0, w0), (d1, w1), (d2, w2) = self._recent
        if d0 < d1 < d2:
            slope = (w2 - w1) / (d2 - d1)
            curvature = (slope - (w1 - w0) / (d1 - d0)) / (0.5 * (d2 - d0))
        else:           # due times equal to rounding (intervals below the time's ulp)
            slope = curvature = math.nan
        if not (math.isfinite(slope) and math.isfinite(curvature)):
            slope = curvature = 0.0     # no usable trend: hold the latest setpoint
        n = max(1, min(math.ceil(self.max_stall / self.interval), MAX_PATH_SEGMENTS))
        h = self.max_stall / n
        tau = h * np.arange(n + 1)
        limit = self.max_angular_acceleration
        rates = np.clip(slope + curvature * (tau[1:] - 0.5 * h), -limit, limit)
        omegas = w2 + np.concatenate(([0.0], np.cumsum(rates * h)))
        return d2 + tau, omegas

    def ramp_to(self, target: float, time: float) -> Ramp:
        """From ``time`` (s) on, go to ``target`` (rad/s) at the limit; return the ramp.

        Not a setpoint (:attr:`setpoint` stays the latest one received): w leaves
        whatever path it was on at ``time`` (w continuous, w' bounded by the limit),
        changes linearly at exactly the limit and holds ``target`` from the end on.
        The stream is taken as ended: the next setpoint starts a new one, reached
        ``delay`` after it arrives (not placed on the old grid, whose extrapolation
        this ramp has left). The engine's command-timeout spin-down (target 0) is
        this ramp.
        """
        w_target, t = _omega('target', target), finite_number('time', time)
        t = max(t, self._ramps[0].start)
        self._envelope.clear()
        self._ungridded.clear()
        self._grid = None
        self._recent.clear()
        w0 = self.omega(t)
        while len(self._ramps) > 1 and self._ramps[-1].start >= t:
            self._ramps.pop()
        times = [t, t + abs(w_target - w0) / self.max_angular_acceleration]
        omegas = [w0, w_target]
        _within_limit(times, omegas, self.max_angular_acceleration)
        ramp = Ramp(tuple(times), tuple(omegas))
        self._ramps.append(ramp)
        return ramp

    def forget_before(self, t: float) -> None:
        """Drop ramps that ended before time ``t`` (s); keeps memory bounded."""
        if len(self._ramps) < 2:                # the one in force (each rod, each block)
            return
        i = max(0, bisect_right(self._ramps, t, key=_start) - 1)
        if i:
            del self._ramps[:i]
