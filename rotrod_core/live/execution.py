"""A hub trajectory executed by the engine: its goal, its tolerances, its outcome.

No ROS import. The simulator node turns a ``control_msgs/FollowJointTrajectory`` goal
into a :class:`TrajectoryGoal`; the engine (:meth:`SimulationEngine.command_trajectory
<rotrod_core.live.engine.SimulationEngine.command_trajectory>`) builds its
:class:`~rotrod_core.command.trajectory.HubTrajectory` from the hub's state at the
instant the goal starts and follows it at the physics rate, on the simulated clock, so
a paused simulation stepped in lockstep executes it bit for bit the same.

The tolerances mean what they mean to ros2_control's joint_trajectory_controller
(Jazzy): a value > 0 is checked, 0 takes the default (:data:`DEFAULT_PATH` and
:data:`DEFAULT_GOAL`), -1 is not checked. The path tolerance is checked at every step
until the last point's time; from then on the goal tolerance, met at once, or within
``goal_time_tolerance`` s (0: waiting as long as it takes), else the goal ends with
GOAL_TOLERANCE_VIOLATED. The error is desired - actual, the angle's taken within
(-pi, pi] (the hub's joint is continuous).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any, NamedTuple

from rotrod_core.command.trajectory import (
    GOAL_TOLERANCE_VIOLATED,
    INVALID_GOAL,
    PATH_TOLERANCE_VIOLATED,
    SUCCESSFUL,
    HubState,
    HubTrajectory,
    TrajectoryPoint,
    TrajectoryRejected,
)

CANCELED = 'CANCELED'
"""The outcome of a cancelled goal (its result code is SUCCESSFUL, as the controller's)."""
NOT_CHECKED = -1.0
"""A tolerance of -1: that quantity is not checked."""


@dataclass(frozen=True)
class Tolerance:
    """Largest |desired - actual| of the hub: theta rad, w rad/s, w' rad/s^2 (None: none)."""

    position: float | None = None
    velocity: float | None = None
    acceleration: float | None = None

    def violation(self, error: HubState) -> str | None:
        """Which quantity ``error`` puts beyond this tolerance, as a phrase (None: none)."""
        for name, unit, limit, value in (
                ('position', 'rad', self.position, error.position),
                ('velocity', 'rad/s', self.velocity, error.velocity),
                ('acceleration', 'rad/s^2', self.acceleration, error.acceleration)):
            if limit is not None and abs(value) > limit:
                return f'{name} error {value:.6g} {unit} beyond {limit:g} {unit}'
        return None


DEFAULT_PATH = Tolerance()
"""The path tolerance a 0 stands for: none (the controller's default)."""
DEFAULT_GOAL = Tolerance(velocity=0.01)
"""The goal tolerance a 0 stands for: w within 0.01 rad/s (the controller's default
``stopped_velocity_tolerance``); theta and w' not checked."""


def merged_tolerance(given: tuple[float, float, float] | None, default: Tolerance,
                     what: str) -> Tolerance:
    """A goal's (position, velocity, acceleration) tolerance over ``default``.

    > 0: that value; 0: the default's; -1: not checked. Anything else (negative, NaN)
    raises :class:`TrajectoryRejected` (INVALID_GOAL) naming ``what``.
    """
    if given is None:
        return default
    values = {}
    for name, value in zip(('position', 'velocity', 'acceleration'), given):
        if not math.isfinite(value) or (value < 0 and value != NOT_CHECKED):
            raise TrajectoryRejected(INVALID_GOAL, f'{what} {name} tolerance {value!r}: it '
                                     'must be > 0, 0 (the default) or -1 (not checked)')
        values[name] = (getattr(default, name) if value == 0 else
                        None if value == NOT_CHECKED else float(value))
    return Tolerance(**values)


def goal_time_tolerance(value: float) -> float | None:
    """``goal_time_tolerance`` (s) as a limit: None for 0 or -1 (as long as it takes)."""
    if not math.isfinite(value) or (value < 0 and value != NOT_CHECKED):
        raise TrajectoryRejected(INVALID_GOAL, f'goal_time_tolerance {value!r} s: it must be '
                                 '>= 0 (0: as long as it takes)')
    return float(value) if value > 0 else None


@dataclass(frozen=True)
class TrajectoryGoal:
    """A trajectory to execute, as the node received it (SI units).

    Attributes:
        points: the hub's points (:func:`~rotrod_core.command.trajectory.hub_points`).
        start_time: simulated time at which time_from_start counts from, s (None:
            when the goal reaches the engine, the header's stamp 0).
        path_tolerance: checked until the last point's time.
        goal_tolerance: checked from then on.
        goal_time_tolerance: s after the last point's time within which the goal
            tolerance must be met (None: as long as it takes).
        token: the host's handle of the goal, returned in its outcome.
    """

    points: tuple[TrajectoryPoint, ...]
    start_time: float | None = None
    path_tolerance: Tolerance = DEFAULT_PATH
    goal_tolerance: Tolerance = DEFAULT_GOAL
    goal_time_tolerance: float | None = None
    token: Any = field(default=None, compare=False)


class TrajectoryOutcome(NamedTuple):
    """How a goal ended: its host token, a code (SUCCESSFUL, ..., CANCELED), a sentence."""

    token: Any
    code: str
    message: str


class Tracking(NamedTuple):
    """The trajectory's desired hub state beside the actual one at simulated ``time``."""

    time: float
    """Time from the trajectory's start, s."""
    desired: HubState
    actual: HubState
    token: Any = None
    """The goal's host token."""

    @property
    def error(self) -> HubState:
        """Desired - actual (the angle within (-pi, pi])."""
        d, a = self.desired, self.actual
        angle = -((a.position - d.position + math.pi) % (2.0 * math.pi) - math.pi)
        return HubState(angle, d.velocity - a.velocity, d.acceleration - a.acceleration)


class TrajectoryExecution:
    """A goal being executed from simulated time ``start`` (s) along ``trajectory``."""

    def __init__(self, goal: TrajectoryGoal, trajectory: HubTrajectory, start: float):
        self.goal = goal
        self.trajectory = trajectory
        self.start = start
        self.end = start + trajectory.end_time
        """Simulated time of the last point, s."""

    @property
    def checks_path(self) -> bool:
        """Whether any path tolerance is checked (else only the end is looked at)."""
        return self.goal.path_tolerance != Tolerance()

    def omega(self, t: float) -> float:
        """The desired w at simulated time ``t``, rad/s."""
        return self.trajectory.omega_at(t - self.start)

    def tracking(self, t: float, position: float, velocity: float,
                 acceleration: float) -> Tracking:
        """Desired and actual at simulated time ``t`` (the hub's theta, w, w')."""
        tau = t - self.start
        tr = self.trajectory
        desired = HubState(float(tr.position(tau)), float(tr.omega(tau)),
                           float(tr.omega_dot(tau)))
        actual = HubState(position + tr.position_offset, velocity, acceleration)
        return Tracking(tau, desired, actual, self.goal.token)

    def check(self, tracking: Tracking) -> TrajectoryOutcome | None:
        """The outcome at this instant, if the goal ends here (None: it goes on)."""
        goal, token = self.goal, self.goal.token
        late = tracking.time - self.trajectory.end_time
        if late < 0:
            problem = goal.path_tolerance.violation(tracking.error)
            if problem:
                return TrajectoryOutcome(token, PATH_TOLERANCE_VIOLATED,
                                         f'path tolerance violated at {tracking.time:.6g} s '
                                         f'of the trajectory: {problem}; holding w')
            return None
        problem = goal.goal_tolerance.violation(tracking.error)
        if problem is None:
            return TrajectoryOutcome(token, SUCCESSFUL, f'reached the last point at '
                                     f'{self.trajectory.end_time:.6g} s; w = '
                                     f'{tracking.actual.velocity:.6g} rad/s')
        limit = goal.goal_time_tolerance
        if limit is not None and late > limit:
            return TrajectoryOutcome(token, GOAL_TOLERANCE_VIOLATED,
                                     f'goal tolerance not met {late:.6f} s after the last '
                                     f'point (goal_time_tolerance {limit:g} s): {problem}; '
                                     'holding w')
        return None


__all__ = ['CANCELED', 'DEFAULT_GOAL', 'DEFAULT_PATH', 'NOT_CHECKED', 'Tolerance',
           'Tracking', 'TrajectoryExecution', 'TrajectoryGoal', 'TrajectoryOutcome',
           'goal_time_tolerance', 'merged_tolerance']
