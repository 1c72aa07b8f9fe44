"""Sending a hub trajectory to the simulator's ``follow_joint_trajectory``, and following it.

The profile publisher (``profile:=planned``) and its SpinUp action send their profile as
one ``control_msgs/FollowJointTrajectory`` goal: points of w and w' at the profile's
breakpoints and at most every :data:`MAX_INTERVAL` s between, which the simulator
follows as the cubic through them (exact for a planned spin-up, whose w is cubic
between its knots) at its physics rate on its own clock. Nothing of the network's timing
reaches the hub.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence

from action_msgs.msg import GoalStatus
from control_msgs.action import FollowJointTrajectory
from rclpy.action import ActionClient
from trajectory_msgs.msg import JointTrajectoryPoint

from rotrod_core.command.profiles import Profile
from rotrod_core.command.trajectory import TrajectoryPoint, profile_points, trajectory_times
from rotrod_core.model.interface import HUB_JOINT

from .interfaces import action_client
from .trajectory_server import ACTION_NAME

MAX_INTERVAL = 0.01
"""Longest time between two points of a sent trajectory, s (a planned spin-up is exact at
its knots whatever the spacing; Eq. 26 sampled every 10 ms is within 1e-11 rad/s)."""
INTERFACE = action_client(ACTION_NAME, FollowJointTrajectory,
                          "the simulator's: the profile as one trajectory of joint 'hub' "
                          "(w rad/s, w' rad/s^2 at its breakpoints and every "
                          f'{MAX_INTERVAL:g} s)')
STATUS_NAMES = {GoalStatus.STATUS_SUCCEEDED: 'succeeded', GoalStatus.STATUS_ABORTED: 'aborted',
                GoalStatus.STATUS_CANCELED: 'canceled'}


def _duration(msg, t: float) -> None:
    msg.sec = math.floor(t)
    msg.nanosec = min(999_999_999, round((t - math.floor(t)) * 1e9))


def goal_message(points: Sequence[TrajectoryPoint]) -> FollowJointTrajectory.Goal:
    """The goal of ``points`` for joint 'hub' (stamp 0: at once)."""
    goal = FollowJointTrajectory.Goal()
    goal.trajectory.joint_names = [HUB_JOINT]
    for p in points:
        msg = JointTrajectoryPoint()
        _duration(msg.time_from_start, p.time)
        if p.position is not None:
            msg.positions = [p.position]
        if p.velocity is not None:
            msg.velocities = [p.velocity]
        if p.acceleration is not None:
            msg.accelerations = [p.acceleration]
        goal.trajectory.points.append(msg)
    return goal


def profile_trajectory(profile: Profile, end: float) -> tuple[TrajectoryPoint, ...]:
    """The points of ``profile`` from 0 to ``end`` (s) as sent: w, w' (no positions)."""
    return profile_points(profile, trajectory_times(profile, end, MAX_INTERVAL))


class TrajectorySender:
    """One goal at a time to the simulator's trajectory action, followed to its result.

    ``on_result(status, result)`` is called (executor thread) when a goal ends:
    ``status`` a GoalStatus constant, ``result`` the action's Result (None if the goal
    was not accepted).
    """

    def __init__(self, node, on_result: Callable[[int, object], None]):
        self.node = node
        self.client = ActionClient(node, FollowJointTrajectory, ACTION_NAME)
        self._on_result = on_result
        self._handle = None
        self.active = False
        """A goal was sent and has no result yet."""
        self.accepted_at: float | None = None
        """Node-clock time at which the goal was accepted, s."""

    @property
    def name(self) -> str:
        """The action's full name."""
        return self.node.get_namespace().rstrip('/') + '/' + ACTION_NAME

    def ready(self) -> bool:
        """Whether the simulator's action server is there."""
        return self.client.server_is_ready()

    def send(self, points: Sequence[TrajectoryPoint]) -> None:
        """Send ``points`` as one goal (the previous one, if running, is preempted)."""
        self.active, self.accepted_at = True, None
        future = self.client.send_goal_async(goal_message(points))
        future.add_done_callback(self._on_goal_response)

    def cancel(self) -> None:
        """Cancel the running goal (the simulator holds w)."""
        if self._handle is not None and self.active:
            self._handle.cancel_goal_async()

    def _on_goal_response(self, future) -> None:
        handle = future.result()
        if not handle.accepted:
            self.active = False
            self._on_result(GoalStatus.STATUS_ABORTED, None)
            return
        self._handle = handle
        self.accepted_at = self.node.get_clock().now().nanoseconds * 1e-9
        handle.get_result_async().add_done_callback(
            lambda f, handle=handle: self._on_goal_result(handle, f))

    def _on_goal_result(self, handle, future) -> None:
        if handle is not self._handle:      # a preempted goal's late result
            return
        self.active = False
        response = future.result()
        self._on_result(response.status, response.result)


__all__ = ['INTERFACE', 'MAX_INTERVAL', 'STATUS_NAMES', 'TrajectorySender', 'goal_message',
           'profile_trajectory']
