"""The simulator's FollowJointTrajectory action (control_msgs), as a trajectory controller.

``follow_joint_trajectory`` takes a ``control_msgs/action/FollowJointTrajectory`` goal for
the joint ``hub`` the way ros2_control's joint_trajectory_controller (Jazzy) does, and
the simulator executes it at its physics rate on its own clock
(:mod:`rotrod_core.live.execution`): no network timing reaches the hub. Feedback
(desired, actual, error) goes out with every publication; the result carries the
standard's error code and a sentence.

Where it differs from the controller, on purpose:

- an invalid goal is accepted and then aborted with its code (INVALID_GOAL,
  INVALID_JOINTS, OLD_HEADER_TIMESTAMP) and the reason, where the controller rejects
  it without a word: a client learns why;
- NaN and infinite values, a speed beyond ``max_omega`` and an acceleration beyond
  ``max_angular_acceleration`` anywhere along the path are refused (the controller
  does not check);
- a trajectory may end at a speed (a rotor spun up): the last point's velocity need not
  be 0;
- cancel holds the hub's speed where it is (a rotor cannot hold its position): w' is 0
  from the instant the cancel reaches the physics;
- the goal runs in the velocity or servo drive only (a torque drive is refused with the
  reason).

Like the controller, a new goal preempts a running one (the old one is aborted with
INVALID_GOAL) and starts from the hub's motion; the topic commands (``cmd/omega``,
``joint_command``) take over from a goal too (aborted with INVALID_GOAL).
docs/usage.md#trajectories.
"""

from __future__ import annotations

import itertools
import math
from typing import Any

from control_msgs.action import FollowJointTrajectory
from rclpy.action import CancelResponse
from rclpy.task import Future
from trajectory_msgs.msg import JointTrajectoryPoint

from rotrod_core.command.trajectory import (
    INVALID_GOAL,
    INVALID_JOINTS,
    PASSIVE_JOINTS,
    SUCCESSFUL,
    TrajectoryRejected,
    hub_points,
)
from rotrod_core.live.execution import (
    CANCELED,
    DEFAULT_GOAL,
    DEFAULT_PATH,
    Tracking,
    TrajectoryGoal,
    TrajectoryOutcome,
    goal_time_tolerance,
    merged_tolerance,
)
from rotrod_core.live.loop import RealTimeLoop
from rotrod_core.model.interface import HUB_JOINT

from .interfaces import action

ACTION_NAME = 'follow_joint_trajectory'
FEEDBACK_HISTORY = 100
"""The feedback publisher's history: a second of feedback at 100 Hz. rclpy's default,
10, overwrote feedback a client busy for more than 0.1 s had not yet taken (8 of 300
lost under load, with the client's own history at 1000)."""
INTERFACES = (
    action(ACTION_NAME, FollowJointTrajectory,
           "joint 'hub' along a trajectory (control_msgs, as ros2_control's "
           'joint_trajectory_controller takes it): points of theta rad, w rad/s, w\' rad/s^2 '
           '(quintic through all three, cubic, linear; velocities alone: w cubic through '
           "(w, w'), theta its integral), from the hub's motion, executed at physics_rate on "
           'the simulated clock; header.stamp 0 = at once. Feedback desired, actual, error at '
           'every publication; path and goal tolerances, goal_time_tolerance; cancel holds w; '
           'a new goal or a cmd/omega preempts (INVALID_GOAL). Refused with the code and the '
           "reason: unknown or passive joints, times not increasing, NaN, |w| > max_omega, "
           "|w'| > max_angular_acceleration anywhere, drive torque"),
)

Result = FollowJointTrajectory.Result
_TOKENS = itertools.count(1)
"""The goals' tokens: unique in the process (a world's rods share its loop)."""
CODES = {name: getattr(Result, name) for name in (
    'SUCCESSFUL', 'INVALID_GOAL', 'INVALID_JOINTS', 'OLD_HEADER_TIMESTAMP',
    'PATH_TOLERANCE_VIOLATED', 'GOAL_TOLERANCE_VIOLATED')}
"""The result code of each outcome name."""


def _seconds(duration) -> float:
    """builtin_interfaces/Duration (or Time) in s."""
    return duration.sec + duration.nanosec * 1e-9


def _tolerance(entries, default, what: str):
    """The hub's tolerance among a goal's JointTolerance ``entries`` (INVALID_JOINTS else)."""
    given = None
    for entry in entries:
        if entry.name != HUB_JOINT:
            detail = 'passive' if entry.name in PASSIVE_JOINTS else 'not a joint of this rod'
            raise TrajectoryRejected(INVALID_JOINTS, f'{what} names joint {entry.name!r} '
                                     f'({detail}): only {HUB_JOINT!r} is driven')
        given = (entry.position, entry.velocity, entry.acceleration)
    return merged_tolerance(given, default, what)


def trajectory_goal(request, start_time, token) -> TrajectoryGoal:
    """A :class:`TrajectoryGoal` of a FollowJointTrajectory goal (raises TrajectoryRejected).

    ``start_time(stamp_s)`` converts the header's stamp to simulated time (s).
    """
    trajectory = request.trajectory
    if request.multi_dof_trajectory.joint_names or request.multi_dof_trajectory.points:
        raise TrajectoryRejected(INVALID_JOINTS, 'a multi-DOF trajectory: this rod has none; '
                                 f'give {HUB_JOINT!r} in trajectory')
    if request.component_path_tolerance or request.component_goal_tolerance:
        raise TrajectoryRejected(INVALID_GOAL, 'component tolerances apply to multi-DOF '
                                 f'joints; give {HUB_JOINT!r}\'s in path_tolerance and '
                                 'goal_tolerance')
    points = hub_points(trajectory.joint_names, [
        (_seconds(p.time_from_start), p.positions, p.velocities, p.accelerations, p.effort)
        for p in trajectory.points])
    stamp = _seconds(trajectory.header.stamp)
    return TrajectoryGoal(
        points, start_time=start_time(stamp) if stamp else None,
        path_tolerance=_tolerance(request.path_tolerance, DEFAULT_PATH, 'path_tolerance'),
        goal_tolerance=_tolerance(request.goal_tolerance, DEFAULT_GOAL, 'goal_tolerance'),
        goal_time_tolerance=goal_time_tolerance(_seconds(request.goal_time_tolerance)),
        token=token)


def _point(msg: JointTrajectoryPoint, state, time: float) -> JointTrajectoryPoint:
    msg.positions, msg.velocities, msg.accelerations = (
        [state.position], [state.velocity], [state.acceleration])
    msg.time_from_start.sec = math.floor(time)
    msg.time_from_start.nanosec = min(999_999_999, round((time - math.floor(time)) * 1e9))
    return msg


class TrajectoryServer:
    """The action's callbacks over the simulator's loop.

    Args:
        node: the simulator node (a guard condition of its own wakes the executor when
            the physics thread has an outcome).
        loop: the simulator's RealTimeLoop, whose ``on_trajectory`` must reach
            :meth:`on_outcome` for this server's goals.
        rod: the rod's name in the loop's world ('': its only rod).
        action_name: the action's name (the rod's prefix + ACTION_NAME).
        on_goal: called with each goal's token and this server before the goal goes
            to the loop (the host routes its outcome back here).
    """

    def __init__(self, node, loop: RealTimeLoop, *, rod: str = '',
                 action_name: str = ACTION_NAME, on_goal=None) -> None:
        self.loop = loop
        self.rod, self.action_name = rod, action_name
        self._on_goal = on_goal or (lambda token, server: None)
        self._node = node
        self._logger = node.get_logger()
        self._wake = node.create_guard_condition(lambda: None)
        self._running: dict[int, tuple[Any, Future]] = {}
        self._tokens: dict[bytes, int] = {}       # goal id -> token, while running
        self._feedback = FollowJointTrajectory.Feedback(joint_names=[HUB_JOINT])

    def destroy(self) -> None:
        """Release the guard condition (the rod left the world)."""
        self._node.destroy_guard_condition(self._wake)

    def callbacks(self) -> dict[str, Any]:
        """The action's ActionServer arguments, for :func:`rotrod_ros.interfaces.create`."""
        from rclpy.qos import QoSProfile
        return {ACTION_NAME: {'execute_callback': self.execute,
                              'cancel_callback': self.cancel,
                              'feedback_pub_qos_profile': QoSProfile(depth=FEEDBACK_HISTORY)}}

    def _submit(self, kind: str, value) -> None:
        self.loop.submit(kind, value, self.action_name, self.rod)

    async def execute(self, goal_handle):
        """Execute callback: refuse with the code and reason, or run to the outcome."""
        token = next(_TOKENS)
        try:
            goal = trajectory_goal(goal_handle.request, self.loop.simulated_time, token)
        except TrajectoryRejected as exc:
            return self._end(goal_handle, TrajectoryOutcome(token, exc.code, str(exc)))
        future = Future()
        self._running[token] = (goal_handle, future)
        key = bytes(goal_handle.goal_id.uuid)
        self._tokens[key] = token
        last = goal.points[-1]
        self._logger.info(f'{self.action_name} goal {token}: {len(goal.points)} point(s) '
                          f'to {last.time:g} s')
        self._on_goal(token, self)
        self._submit('trajectory', goal)
        if goal_handle.is_cancel_requested:         # cancelled before it was known here
            self._submit('cancel_trajectory', token)
        outcome = await future
        self._tokens.pop(key, None)
        return self._end(goal_handle, outcome)

    def cancel(self, goal_handle) -> CancelResponse:
        """Cancel callback: the physics holds w from the cancel's arrival; always accepted."""
        token = self._tokens.get(bytes(goal_handle.goal_id.uuid))
        if token is not None:
            self._submit('cancel_trajectory', token)
        return CancelResponse.ACCEPT

    def on_outcome(self, outcome: TrajectoryOutcome) -> None:
        """The loop's ``on_trajectory`` (its thread): the goal's future gets its outcome."""
        running = self._running.pop(outcome.token, None)
        if running is not None:
            running[1].set_result(outcome)
            self._wake.trigger()

    def _end(self, goal_handle, outcome: TrajectoryOutcome):
        """Put the goal in its final state; its result."""
        code = SUCCESSFUL if outcome.code == CANCELED else outcome.code
        result = Result(error_code=CODES[code], error_string=outcome.message)
        if outcome.code == CANCELED and goal_handle.is_cancel_requested:
            goal_handle.canceled()
        elif outcome.code == SUCCESSFUL:
            goal_handle.succeed()
        else:
            goal_handle.abort()
        line = f'{self.action_name} goal {outcome.token}: {outcome.code}: {outcome.message}'
        # one call site per severity: rclpy's logger binds a call site to one
        if outcome.code in (SUCCESSFUL, CANCELED):
            self._logger.info(line)
        else:
            self._logger.warning(line)
        return result

    def feedback(self, stamp, tracking: Tracking | None) -> None:
        """Publish the goal's feedback for a sample (the physics thread)."""
        if tracking is None:
            return
        running = self._running.get(tracking.token)
        if running is None:
            return
        msg = self._feedback
        msg.header.stamp = stamp
        _point(msg.desired, tracking.desired, tracking.time)
        _point(msg.actual, tracking.actual, tracking.time)
        _point(msg.error, tracking.error, 0.0)
        running[0].publish_feedback(msg)


__all__ = ['ACTION_NAME', 'CODES', 'INTERFACES', 'TrajectoryServer', 'trajectory_goal']
