"""A trajectory of the hub joint, sampled as ros2_control's joint_trajectory_controller does.

No ROS import: the simulator node turns a ``control_msgs/FollowJointTrajectory`` goal
into :func:`hub_points` (the message's joint names and per-point arrays, as plain
values) and the engine executes a :class:`HubTrajectory` built from them at the physics
rate, on its own clock (:mod:`rotrod_core.live.execution`).

The points give the hub's angle theta (rad), speed w (rad/s) and acceleration w'
(rad/s^2) at times from the trajectory's start (s); each field is given at every point
or at none. Between two points, as joint_trajectory_controller's ``Trajectory::sample``
interpolates:

- theta, w and w' given: theta is the quintic through both ends' (theta, w, w');
- theta and w: the cubic through both ends' (theta, w);
- theta only: linear (w jumps at every point: refused here unless it is constant,
  since the hub is driven in velocity and a jump of w is an infinite acceleration);
- no theta (the hub is velocity-driven: a rotor's speed profile): w is the cubic
  through both ends' (w, w') when accelerations are given, else linear; theta is its
  integral.

Before the first point the trajectory runs from the hub's state at its start (theta,
w, w') to the first point by the same rule; a first point at time 0 is that state
itself and must agree with it (w cannot jump). After the last point w holds the last
speed (w' = 0). The hub's joint is continuous: the start angle is taken within pi of
the first point's (the controller's wraparound), so a trajectory in [-pi, pi) drives a
hub that has turned many times.

Every trajectory is checked whole before it runs (:class:`TrajectoryRejected`, with
the standard's reason code and a sentence): finite numbers, increasing times, a
continuous w, and |w| and |w'| within the drive's limits everywhere between the points
(exact: the extremes of each segment's polynomials).

Model: docs/usage.md#trajectories.
"""

from __future__ import annotations

import math
from bisect import bisect_right
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import BPoly, PPoly

from rotrod_core.command.profiles import Profile, _evaluation, _out
from rotrod_core.model.interface import (
    HUB_JOINT,
    TIP_RADIAL_JOINT,
    TIP_TANGENTIAL_JOINT,
)

INVALID_GOAL = 'INVALID_GOAL'
INVALID_JOINTS = 'INVALID_JOINTS'
OLD_HEADER_TIMESTAMP = 'OLD_HEADER_TIMESTAMP'
PATH_TOLERANCE_VIOLATED = 'PATH_TOLERANCE_VIOLATED'
GOAL_TOLERANCE_VIOLATED = 'GOAL_TOLERANCE_VIOLATED'
SUCCESSFUL = 'SUCCESSFUL'
"""The outcomes of a trajectory, named as control_msgs/FollowJointTrajectory's result
codes (the node maps each name to the message's constant)."""

PASSIVE_JOINTS = (TIP_RADIAL_JOINT, TIP_TANGENTIAL_JOINT)
"""The joints of joint_states that nothing drives: the tip's deflection."""
LIMIT_SLACK = 1e-9
"""Relative excess over a limit forgiven as rounding (a plan that rides its bound)."""
FIELDS = ('position', 'velocity', 'acceleration')


class TrajectoryRejected(ValueError):
    """A trajectory that cannot be executed: ``code`` (a result name above), the reason."""

    def __init__(self, code: str, message: str):
        super().__init__(message)
        self.code = code


@dataclass(frozen=True)
class TrajectoryPoint:
    """One point of the hub's trajectory (None: the field is not given).

    Attributes:
        time: time from the trajectory's start, s.
        position: hub angle theta, rad.
        velocity: hub speed w, rad/s.
        acceleration: hub acceleration w', rad/s^2.
    """

    time: float
    position: float | None = None
    velocity: float | None = None
    acceleration: float | None = None


def _invalid(message: str) -> TrajectoryRejected:
    return TrajectoryRejected(INVALID_GOAL, message)


def _hub_column(joint_names: Sequence[str]) -> int:
    """Index of the hub among ``joint_names``; INVALID_JOINTS for any other name."""
    names = list(joint_names)
    if not names:
        raise TrajectoryRejected(INVALID_JOINTS, f'no joint names: the trajectory must name '
                                 f'the joint {HUB_JOINT!r}')
    if len(set(names)) != len(names):
        raise TrajectoryRejected(INVALID_JOINTS, f'joint names repeat: {names}')
    for name in names:
        if name in PASSIVE_JOINTS:
            raise TrajectoryRejected(INVALID_JOINTS, f'joint {name!r} is passive (the tip\'s '
                                     f'deflection): only {HUB_JOINT!r} is driven')
        if name != HUB_JOINT:
            raise TrajectoryRejected(INVALID_JOINTS, f'no joint {name!r}: the one driven '
                                     f'joint is {HUB_JOINT!r}')
    return names.index(HUB_JOINT)


def _finite(value, what: str) -> float:
    try:
        x = float(value)
    except (TypeError, ValueError, OverflowError):
        raise _invalid(f'{what} is not a number: {value!r}') from None
    if not math.isfinite(x):
        raise _invalid(f'{what} is {x!r}, not a finite number')
    return x


def hub_points(joint_names: Sequence[str], points: Sequence[tuple]) -> tuple[TrajectoryPoint, ...]:
    """The hub's points of a joint trajectory message, checked.

    ``points``: per point ``(time_from_start s, positions, velocities, accelerations,
    effort)``, each array empty or one entry per joint name (trajectory_msgs/
    JointTrajectoryPoint). Raises :class:`TrajectoryRejected`: INVALID_JOINTS for names
    other than the hub's, INVALID_GOAL for no points, arrays of the wrong size, a field
    given at some points only, efforts, times not increasing, values not finite, no
    positions nor velocities, accelerations without velocities.
    """
    column = _hub_column(joint_names)
    if not points:
        raise _invalid('the trajectory has no points')
    n = len(joint_names)
    given = None
    out: list[TrajectoryPoint] = []
    for k, (time, *arrays) in enumerate(points):
        sizes = [len(a) for a in arrays]
        for name, size in zip((*FIELDS, 'effort'), sizes):
            if size not in (0, n):
                raise _invalid(f'point {k}: {size} {name} values for {n} joint(s) (empty or '
                               'one per joint)')
        if sizes[3]:
            raise _invalid(f'point {k}: efforts given; the hub is driven by its speed, and '
                           'a trajectory of positions, velocities and accelerations')
        has = tuple(bool(s) for s in sizes[:3])
        if given is None:
            given = has
        elif has != given:
            raise _invalid(f'point {k} gives {_fields(has)}, point 0 gives {_fields(given)}: '
                           'every point must give the same fields')
        t = _finite(time, f'point {k}: time_from_start')
        if t < 0 or (out and t <= out[-1].time):
            raise _invalid(f'point {k}: time_from_start {t:g} s does not increase (times must '
                           'be >= 0 and strictly increasing)')
        values = [_finite(a[column], f'point {k}: {name}') if a else None
                  for name, a in zip(FIELDS, arrays[:3])]
        out.append(TrajectoryPoint(t, *values))
    assert given is not None
    if not (given[0] or given[1]):
        raise _invalid('the points give neither positions nor velocities')
    if given[2] and not given[1]:
        raise _invalid('the points give accelerations without velocities')
    return tuple(out)


def _fields(has) -> str:
    names = [f + 's' for f, h in zip(FIELDS, has) if h]
    return ', '.join(names) if names else 'nothing'


@dataclass(frozen=True)
class HubState:
    """The hub's motion at an instant: theta rad, w rad/s, w' rad/s^2."""

    position: float
    velocity: float
    acceleration: float = 0.0


def _wrapped(angle: float) -> float:
    """``angle`` in [-pi, pi), rad."""
    return (angle + math.pi) % (2.0 * math.pi) - math.pi


class HubTrajectory(Profile):
    """The hub's w(t), w'(t) and theta(t) through points, from a start state (a Profile).

    Time ``t`` is measured from the trajectory's start (s): w holds the start speed
    before 0 and the last point's speed after :attr:`end_time`; :meth:`angle` is the
    integral of w from 0 (the Profile convention, for an offline run of the same
    trajectory) and :meth:`position` the angle the points are given in.

    Args:
        points: from :func:`hub_points`.
        start: the hub's state at the start.
        max_omega: largest |w| allowed anywhere, rad/s.
        max_angular_acceleration: largest |w'| allowed anywhere, rad/s^2.
        start_tolerance: how far a first point at time 0 may be from ``start``:
            (rad, rad/s).

    Raises :class:`TrajectoryRejected` (INVALID_GOAL) with the reason.
    """

    def __init__(self, points: Sequence[TrajectoryPoint], start: HubState, *,
                 max_omega: float = math.inf, max_angular_acceleration: float = math.inf,
                 start_tolerance: tuple[float, float] = (0.0, 0.0)):
        if not points:
            raise _invalid('the trajectory has no points')
        self.points = tuple(points)
        first = self.points[0]
        self.by_position = first.position is not None
        self.order = 1 + (first.velocity is not None) * (1 + (first.acceleration is not None))
        """Derivatives matched at each point: 1 (values), 2 (and slopes) or 3."""
        self.position_offset = 0.0
        if first.position is not None:
            # continuous joint: the hub's angle within pi of the first point's
            shift = first.position + _wrapped(start.position - first.position) - start.position
            self.position_offset = shift
            start = HubState(start.position + shift, start.velocity, start.acceleration)
        self.start = start
        self._check_start(first, start, start_tolerance)
        nodes = ([] if first.time == 0 else [(0.0, start)]) + [
            (p.time, HubState(p.position if p.position is not None else math.nan,
                              p.velocity if p.velocity is not None else math.nan,
                              p.acceleration if p.acceleration is not None else math.nan))
            for p in self.points]
        self._theta = self._angle_polynomial(nodes)
        self._omega = self._theta.derivative()
        self._omega_dot = self._omega.derivative()
        self._check_limits(max_omega, max_angular_acceleration)
        last = self.points[-1]
        # the last point's speed itself where it is given (held exactly after the end)
        self.final_velocity = (float(self._omega(self.end_time)) if last.velocity is None
                               else last.velocity)
        self.final_position = float(self._theta(self.end_time))
        self._breaks = [float(x) for x in self._omega.x]
        self._segments = [[float(c) for c in column] for column in self._omega.c.T]

    # ------------------------------------------------------------------ construction
    def _check_start(self, first: TrajectoryPoint, start: HubState,
                     tolerance: tuple[float, float]) -> None:
        if first.time != 0:
            return
        if first.velocity is not None and abs(first.velocity - start.velocity) > tolerance[1]:
            raise _invalid(f'the first point, at time 0, asks w = {first.velocity:g} rad/s but '
                           f'the hub turns at {start.velocity:g} rad/s: w cannot jump; give '
                           'the first point a time > 0 (the hub goes there from its motion)')
        if first.position is not None and abs(first.position - start.position) > tolerance[0]:
            raise _invalid(f'the first point, at time 0, asks theta = {first.position:g} rad '
                           f'but the hub is at {start.position:g} rad: theta cannot jump; '
                           'give the first point a time > 0')

    def _angle_polynomial(self, nodes: list) -> PPoly:
        """theta(t) as a piecewise polynomial through the nodes (time, HubState)."""
        times = [t for t, _ in nodes]
        if len(nodes) == 1:            # one point at time 0: the start itself, held
            return PPoly(np.array([[self.start.velocity], [self.start.position]]), [0.0, 1.0])
        if self.by_position:
            values = [[s.position, s.velocity, s.acceleration][:self.order] for _, s in nodes]
            return PPoly.from_bernstein_basis(BPoly.from_derivatives(times, values))
        values = [[s.velocity, s.acceleration][:self.order - 1] for _, s in nodes]
        omega = PPoly.from_bernstein_basis(BPoly.from_derivatives(times, values))
        theta = omega.antiderivative()
        theta.c[-1] += self.start.position
        return theta

    def _check_limits(self, max_omega: float, max_angular_acceleration: float) -> None:
        breaks = self._theta.x
        for k in range(1, len(breaks) - 1):
            t = breaks[k]
            jump = abs(float(self._omega(t)) - self._omega_left(t))
            if jump > LIMIT_SLACK * max(1.0, abs(float(self._omega(t)))):
                raise _invalid(f'w jumps by {jump:g} rad/s at t = {t:g} s (positions alone '
                               'are interpolated linearly: give velocities too)')
        for what, poly, limit, unit in (('|w|', self._omega, max_omega, 'rad/s'),
                                        ("|w'|", self._omega_dot, max_angular_acceleration,
                                         'rad/s^2')):
            t, value = _largest(poly)
            if value > limit * (1.0 + LIMIT_SLACK):
                raise _invalid(f'{what} reaches {value:.6g} {unit} at t = {t:.6g} s, beyond '
                               f'the drive\'s limit {limit:g} {unit}')

    def _omega_left(self, t: float) -> float:
        """W just before the break ``t`` (the left segment's polynomial at its end)."""
        x = self._omega.x
        k = int(np.searchsorted(x, t)) - 1
        c = self._omega.c[:, k]
        return float(np.polyval(c, t - x[k]))

    # ------------------------------------------------------------------ evaluation
    def omega_at(self, t: float) -> float:
        """:meth:`omega` at one time ``t`` (a finite float, s): a step's few microseconds."""
        if t <= 0.0:
            return self.start.velocity if t < 0.0 else self._segments[0][-1]
        if t >= self.end_time:
            return self.final_velocity
        k = bisect_right(self._breaks, t) - 1
        x = t - self._breaks[k]
        value = 0.0
        for c in self._segments[k]:
            value = value * x + c
        return value

    @property
    def end_time(self) -> float:
        """Time of the last point, s from the start."""
        return float(self.points[-1].time)

    @property
    def peak(self) -> float:
        """Largest |w|, rad/s."""
        return max(_largest(self._omega)[1], abs(self.start.velocity))

    @property
    def max_angular_acceleration(self) -> float:
        """Largest |w'| between the start and the last point, rad/s^2."""
        return _largest(self._omega_dot)[1]

    def breakpoints(self) -> tuple[float, ...]:
        """The points' times, s (w's derivatives jump there)."""
        return tuple(float(t) for t in self._theta.x if t > 0)

    def _clipped(self, t):
        return np.clip(np.asarray(t, dtype=float), 0.0, self.end_time)

    @_evaluation
    def omega(self, t):
        """w, rad/s."""
        tt = np.asarray(t, dtype=float)
        w = np.where(tt < 0, self.start.velocity, self._omega(self._clipped(t)))
        return _out(t, np.where(tt >= self.end_time, self.final_velocity, w))

    @_evaluation
    def omega_dot(self, t):
        """w', rad/s^2 (0 after the end; before 0, the start's)."""
        tt = np.asarray(t, dtype=float)
        inside = (tt >= 0) & (tt <= self.end_time)
        d = np.where(inside, self._omega_dot(self._clipped(t)), 0.0)
        return _out(t, np.where(tt < 0, self.start.acceleration, d))

    @_evaluation
    def position(self, t):
        """Theta in the points' terms, rad (the hub's angle + :attr:`position_offset`)."""
        tt = np.asarray(t, dtype=float)
        before = self.start.position + self.start.velocity * np.minimum(tt, 0.0)
        after = self.final_position + self.final_velocity * np.maximum(tt - self.end_time, 0)
        inside = self._theta(self._clipped(t))
        return _out(t, np.where(tt < 0, before, np.where(tt > self.end_time, after, inside)))

    def angle(self, t):
        """Integral of w from 0 to ``t``, rad."""
        return self.position(t) - self.start.position

    def with_peak(self, omega_peak: float) -> Profile:
        """Not defined: a trajectory is executed as given."""
        raise ValueError('HubTrajectory.with_peak: a trajectory is executed as given')


def _largest(poly: PPoly) -> tuple[float, float]:
    """(t, |p(t)|) of the largest |p| over the piecewise polynomial ``poly``'s breaks.

    Exact up to rounding: on each segment at its ends and at the real roots of p'.
    """
    best_t, best = float(poly.x[0]), -1.0
    slope = poly.derivative()
    for k in range(len(poly.x) - 1):
        a, b = poly.x[k], poly.x[k + 1]
        candidates = [0.0, b - a]
        coeffs = np.trim_zeros(slope.c[:, k], 'f')
        if coeffs.size > 1:
            roots = np.roots(coeffs)
            candidates += [r.real for r in roots
                           if abs(r.imag) <= 1e-12 * max(1.0, abs(r)) and 0 < r.real < b - a]
        for x in candidates:
            value = abs(float(np.polyval(poly.c[:, k], x)))
            if value > best:
                best_t, best = float(a + x), value
    return best_t, best


def trajectory_times(profile: Profile, end: float, max_interval: float) -> np.ndarray:
    """Times (s) at which to sample ``profile`` for a trajectory to ``end``.

    0, its breakpoints, ``end``, and between them as many evenly spaced times as keep
    every interval within ``max_interval`` (s).
    """
    marks = sorted({0.0, float(end), *(t for t in profile.breakpoints() if 0 < t < end)})
    times = [0.0]
    for a, b in zip(marks[:-1], marks[1:]):
        n = max(1, math.ceil((b - a) / max_interval - 1e-9))
        times += [a + (b - a) * k / n for k in range(1, n + 1)]
    return np.array(times)


def profile_points(profile: Profile, times) -> tuple[TrajectoryPoint, ...]:
    """The points (w, w') of ``profile`` at ``times`` (s from its start; an array), no positions.

    Between two such points the hub's w is the cubic through both ends' (w, w'): exact
    for a profile cubic between them (a planned spin-up at its spline's knots), and
    within h^4 max|w''''| / 384 otherwise (h the spacing).
    """
    t = np.asarray(times, dtype=float)
    w, dw = np.atleast_1d(profile.omega(t)), np.atleast_1d(profile.omega_dot(t))
    return tuple(TrajectoryPoint(float(a), velocity=float(b), acceleration=float(c))
                 for a, b, c in zip(t, w, dw))


__all__ = ['FIELDS', 'GOAL_TOLERANCE_VIOLATED', 'HubState', 'HubTrajectory', 'INVALID_GOAL',
           'INVALID_JOINTS', 'OLD_HEADER_TIMESTAMP', 'PASSIVE_JOINTS',
           'PATH_TOLERANCE_VIOLATED', 'SUCCESSFUL', 'TrajectoryPoint', 'TrajectoryRejected',
           'hub_points', 'profile_points', 'trajectory_times']
