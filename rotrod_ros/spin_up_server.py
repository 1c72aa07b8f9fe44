"""The SpinUp action (rotrod_interfaces/SpinUp), served by the profile publisher.

A goal names the target w and a profile (planned, planned_robust, eq26, ramp; see
:mod:`rotrod_core.command.spin_up`). The server plans it from the hub's current w
(``joint_states``) for the simulator's rod and limits (its ``robot_description``, see
:mod:`rotrod_ros.rod_source`), sends it to the simulator as one FollowJointTrajectory
goal (:mod:`rotrod_ros.trajectory_client`: executed on the simulator's clock, no
network timing reaches the hub), and sends feedback (w, the tip deflection, the phase)
every 1/``FEEDBACK_RATE`` s. Once the trajectory has ended and w has reached the
target, it waits ``settle_time`` and measures the free whirl left over
``residual_window`` from ``tip/deflection``
(:func:`rotrod_core.analysis.free_whirl.free_whirl`). The result: reached or not, the
time from the first change of w to its arrival, the peak deflection over the goal,
the measured residual whirl and the plan's prediction.

A goal that cannot be served is accepted and aborted at once with ``refused: <why>``
in the result's message (rclpy's goal response carries no reason), and logged: an
unknown profile, bad numbers, a plan the planner cannot make, no joint_states or no
robot_description yet, another goal running; a trajectory the simulator refuses or
aborts ends the goal with its reason. Cancel cancels the trajectory: the simulator holds
w where it is (with its ``command_timeout`` > 0 it spins down after that timeout, as
for any command that stops).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from action_msgs.msg import GoalStatus
from rclpy.task import Future
from rotrod_interfaces.action import SpinUp

from rotrod_core.analysis.free_whirl import free_whirl
from rotrod_core.command.spin_up import GoalProfile, goal_profile
from rotrod_core.model.params import RodParams

from .messages import HUB_JOINT, to_seconds
from .trajectory_client import STATUS_NAMES, profile_trajectory

FEEDBACK_RATE = 10.0
"""Feedback messages per second of the node clock."""
ARRIVED = 1e-9
"""|w - target| / max(1, |target|) below which w has arrived."""
WAITING, SPINNING, SETTLING = 'waiting', 'spinning', 'settling'
"""The feedback's phases: before the trajectory starts, while it runs, after it."""


@dataclass
class _Run:
    """One goal being served."""

    goal_handle: Any
    target: float
    omega_start: float
    plan: GoalProfile
    params: RodParams
    future: Future
    started: float | None = None            # node clock at the trajectory's acceptance, s
    ended: float | None = None              # node clock at its result, s
    arrival: float | None = None            # stamp of the first joint state at target, s
    moved: float | None = None              # stamp of the first joint state off the start
    peak: float = 0.0
    samples: list = field(default_factory=list)     # (stamp s, u m, v m) during the goal
    last_feedback: float = -math.inf
    cancelling: bool = False


class SpinUpServer:
    """The action's state and callbacks; ``node`` is the profile publisher.

    ``node`` provides ``description`` (the rod and limits planned for, None before the
    simulator's robot_description), ``sender`` (its
    :class:`~rotrod_ros.trajectory_client.TrajectorySender`, whose results it passes to
    :meth:`on_trajectory_result`) and the clock and logger.
    """

    def __init__(self, node, *, settle_time: float, residual_window: float,
                 arrival_timeout: float):
        self.node = node
        self.settle_time = settle_time
        self.residual_window = residual_window
        self.arrival_timeout = arrival_timeout
        self.omega: float | None = None       # the hub's last w, rad/s
        self.deflection = math.nan            # the tip's last |r|, m
        self.run: _Run | None = None

    # ------------------------------------------------------------ subscriptions
    def on_joint_state(self, msg) -> None:
        """joint_states: the hub's w (and, during a goal, its motion and arrival)."""
        if HUB_JOINT not in msg.name:
            return
        i = list(msg.name).index(HUB_JOINT)
        if i >= len(msg.velocity):
            return
        if self.omega is None:
            self.node.get_logger().info(f'joint_states received: w = {msg.velocity[i]:g} '
                                        'rad/s; ready for goals')
        self.omega = w = float(msg.velocity[i])
        run = self.run
        if run is None:           # from the goal's start w on: the simulator starts the
            return                # trajectory on acceptance, before this node's tick knows
        t = to_seconds(msg.header.stamp)
        if run.moved is None and w != run.omega_start:
            run.moved = t
        if run.arrival is None and abs(w - run.target) <= ARRIVED * max(1.0, abs(run.target)):
            run.arrival = t                   # w is monotonic along every goal profile

    def on_deflection(self, msg) -> None:
        """tip/deflection: the tip's |r| (and, during a goal, the samples and the peak)."""
        u, v = float(msg.vector.x), float(msg.vector.y)
        self.deflection = math.hypot(u, v)
        run = self.run
        if run is not None:
            run.samples.append((to_seconds(msg.header.stamp), u, v))
            run.peak = max(run.peak, self.deflection)

    # ------------------------------------------------------------ goals
    async def execute(self, goal_handle):
        """The action's execute callback: refuse with the reason, or serve to the end."""
        goal = goal_handle.request
        try:
            run = self._begin(goal_handle, goal)
        except ValueError as exc:
            self.node.get_logger().warning(f'SpinUp goal refused: {exc}')
            goal_handle.abort()
            return _result(False, f'refused: {exc}')
        self.run = run
        p = run.plan
        points = profile_trajectory(p.profile, p.change_time)
        self.node.get_logger().info(
            f'SpinUp goal: {goal.profile} {run.omega_start:g} -> {run.target:g} rad/s, '
            f'a trajectory of {len(points)} points over {p.change_time:.4g} s'
            + (f', predicted residual {p.predicted_residual:.3g} m'
               if math.isfinite(p.predicted_residual) else ''))
        self.node.sender.send(points)
        return await run.future

    def _begin(self, goal_handle, goal) -> _Run:
        if self.run is not None:
            raise ValueError(f'a spin-up to {self.run.target:g} rad/s is running; cancel it '
                             'first')
        if self.omega is None:
            raise ValueError('no joint_states from the simulator yet: the start speed is '
                             'unknown')
        description = self.node.description
        if description is None:
            raise ValueError('no robot_description from the simulator yet: its rod is '
                             'unknown')
        limits = description.limits
        plan = goal_profile(goal.profile, self.omega, goal.omega_target,
                            deflection_limit=goal.deflection_limit or limits.deflection_limit,
                            residual=goal.residual, robust_band=goal.robust_band,
                            duration=goal.duration,
                            max_angular_acceleration=limits.max_angular_acceleration,
                            params=description.params)
        return _Run(goal_handle, float(goal.omega_target), self.omega, plan,
                    description.params, Future())

    def on_trajectory_result(self, status: int, result) -> None:
        """The sender's result: the trajectory ended (or was refused)."""
        run = self.run
        if run is None:
            return
        run.ended = self.node.get_clock().now().nanoseconds * 1e-9
        if status == GoalStatus.STATUS_SUCCEEDED:
            return                                  # then w's arrival and the residual
        text = 'not accepted' if result is None else result.error_string
        if status == GoalStatus.STATUS_CANCELED and run.goal_handle.is_cancel_requested:
            self._cancelled(run, text)
            return
        self._finish(False, f'the simulator {STATUS_NAMES.get(status, status)} the '
                     f'trajectory: {text}')

    def tick(self, now: float) -> None:
        """Called by the node's timer: started, feedback, cancel, the end."""
        run = self.run
        if run is None:
            return
        sender = self.node.sender
        if run.started is None and sender.accepted_at is not None:
            run.started = sender.accepted_at
        handle = run.goal_handle
        if handle.is_cancel_requested and not run.cancelling:
            run.cancelling = True
            sender.cancel()                      # the simulator holds w; its result ends it
            return
        if now - run.last_feedback >= 1.0 / FEEDBACK_RATE:
            run.last_feedback = now
            phase = WAITING if run.started is None else (
                SPINNING if run.ended is None else SETTLING)
            handle.publish_feedback(SpinUp.Feedback(
                omega=math.nan if self.omega is None else self.omega,
                deflection=self.deflection, phase=phase))
        if run.ended is None:
            return
        ended = run.ended
        if run.arrival is None:
            if now > ended + self.arrival_timeout:
                self._finish(False, f'w did not reach {run.target:g} rad/s within '
                             f'{self.arrival_timeout:g} s of the trajectory\'s end (w = '
                             f'{self.omega:g} rad/s): the simulator\'s limits or drive?')
            return
        start = run.arrival + self.settle_time
        end = start + self.residual_window
        if not run.samples or run.samples[-1][0] < end:
            if now > ended + self.arrival_timeout + self.settle_time + self.residual_window:
                self._finish(False, 'no tip/deflection samples to measure the residual whirl')
            return
        window = [s for s in run.samples if start <= s[0] <= end]
        t, u, v = ([s[k] for s in window] for k in range(3))
        try:
            whirl, misfit = free_whirl(t, u, v, run.params, run.target)
        except ValueError as exc:
            self._finish(False, f'residual whirl not measured: {exc}')
            return
        duration = run.arrival - (run.moved if run.moved is not None else run.arrival)
        self._finish(True, f'reached {run.target:g} rad/s; residual whirl {whirl:.3g} m '
                     f'(fit misfit {misfit:.2g} m) over {self.residual_window:g} s from '
                     f'{self.settle_time:g} s after arrival', duration=duration,
                     residual=whirl)

    def _cancelled(self, run: _Run, text: str) -> None:
        """The trajectory was cancelled: the simulator holds w (``text`` says where)."""
        self.node.get_logger().info(f'SpinUp goal cancelled: {text}')
        run.goal_handle.canceled()
        self.run = None
        run.future.set_result(_result(False, f'cancelled: {text}', peak=run.peak,
                                      predicted=run.plan.predicted_residual))

    def _finish(self, reached: bool, message: str, *, duration: float = math.nan,
                residual: float = math.nan) -> None:
        run = self.run
        assert run is not None
        result = _result(reached, message, duration=duration, peak=run.peak,
                         residual=residual, predicted=run.plan.predicted_residual)
        if reached:
            run.goal_handle.succeed()
            self.node.get_logger().info(f'SpinUp goal: {message}')
        else:
            run.goal_handle.abort()
            self.node.get_logger().warning(f'SpinUp goal failed: {message}')
        self.run = None
        run.future.set_result(result)


def _result(reached: bool, message: str, *, duration: float = math.nan,
            peak: float = math.nan, residual: float = math.nan,
            predicted: float = math.nan):
    return SpinUp.Result(reached=reached, message=message, duration=float(duration),
                         peak_deflection=float(peak), residual_whirl=float(residual),
                         predicted_residual=float(predicted))
