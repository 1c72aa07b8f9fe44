"""The SpinUp action (rotrod_interfaces/SpinUp), served by the profile publisher.

A goal names the target w and a profile (planned, planned_robust, eq26, ramp; see
:mod:`rotrod_core.command.spin_up`). The server plans it from the hub's current w
(``joint_states``), streams it on ``cmd/omega`` through the publisher's own stream
(the same sampling, start-up wait and acceleration contract as the streaming mode),
and sends feedback (w, the tip deflection, the phase) every 1/``FEEDBACK_RATE`` s.
After the stream, once w has reached the target, it waits ``settle_time`` and
measures the free whirl left over ``residual_window`` from ``tip/deflection``
(:func:`rotrod_core.analysis.free_whirl.free_whirl`). The result: reached or not, the
time from the first change of w to its arrival, the peak deflection over the goal,
the measured residual whirl and the plan's prediction.

A goal that cannot be served is accepted and aborted at once with ``refused: <why>``
in the result's message (rclpy's goal response carries no reason), and logged: an
unknown profile, bad numbers, a plan the planner cannot make, no joint_states yet,
another goal running. Cancel stops the profile where it is and holds: the stream sends
the last setpoint for :data:`~rotrod_core.command.registry.PLAN_HOLD` s more and ends,
so the simulator's shaper ends flat at that w and holds it (with the simulator's
``command_timeout`` > 0 it spins down after that timeout, as for any stream that stops).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any

from rclpy.task import Future
from rotrod_interfaces.action import SpinUp

from rotrod_core.analysis.free_whirl import free_whirl
from rotrod_core.command.profiles import ConstantProfile
from rotrod_core.command.registry import PLAN_HOLD
from rotrod_core.command.spin_up import GoalProfile, goal_profile
from rotrod_core.model.params import RodParams

from .messages import HUB_JOINT, to_seconds

FEEDBACK_RATE = 10.0
"""Feedback messages per second of the node clock."""
ARRIVED = 1e-9
"""|w - target| / max(1, |target|) below which w has arrived."""
WAITING, SPINNING, SETTLING = 'waiting', 'spinning', 'settling'
"""The feedback's phases: before the stream starts, while it runs, after it."""


@dataclass
class _Run:
    """One goal being served."""

    goal_handle: Any
    target: float
    omega_start: float
    plan: GoalProfile
    future: Future
    started: float | None = None            # node clock at the stream's start, s
    arrival: float | None = None            # stamp of the first joint state at target, s
    moved: float | None = None              # stamp of the first joint state off the start
    peak: float = 0.0
    samples: list = field(default_factory=list)     # (stamp s, u m, v m) during the goal
    last_feedback: float = -math.inf


class SpinUpServer:
    """The action's state and callbacks; ``node`` is the profile publisher.

    ``node`` provides ``stream(profile, duration)`` (start streaming a profile),
    ``streaming`` (a stream is running), ``stream_started`` (node-clock time of its
    first sample, None before), ``last_setpoint`` (rad/s) and the clock and logger.
    """

    def __init__(self, node, params: RodParams, max_angular_acceleration: float, *,
                 settle_time: float, residual_window: float, arrival_timeout: float):
        self.node = node
        self.params = params
        self.max_angular_acceleration = max_angular_acceleration
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
        if run is None or run.started is None:
            return
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
        if run is not None and run.started is not None:
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
        self.node.get_logger().info(
            f'SpinUp goal: {goal.profile} {run.omega_start:g} -> {run.target:g} rad/s, '
            f'streaming {p.stream_time:.4g} s (change ends at {p.change_time:.4g} s)'
            + (f', predicted residual {p.predicted_residual:.3g} m'
               if math.isfinite(p.predicted_residual) else ''))
        self.node.stream(p.profile, p.stream_time)
        return await run.future

    def _begin(self, goal_handle, goal) -> _Run:
        if self.run is not None:
            raise ValueError(f'a spin-up to {self.run.target:g} rad/s is running; cancel it '
                             'first')
        if self.omega is None:
            raise ValueError('no joint_states from the simulator yet: the start speed is '
                             'unknown')
        plan = goal_profile(goal.profile, self.omega, goal.omega_target,
                            deflection_limit=goal.deflection_limit, residual=goal.residual,
                            robust_band=goal.robust_band, duration=goal.duration,
                            max_angular_acceleration=self.max_angular_acceleration,
                            params=self.params)
        return _Run(goal_handle, float(goal.omega_target), self.omega, plan, Future())

    def tick(self, now: float) -> None:
        """Called by the node's timer after streaming: started, feedback, cancel, the end."""
        run = self.run
        if run is None:
            return
        if run.started is None and self.node.stream_started is not None:
            run.started = self.node.stream_started
        handle = run.goal_handle
        if handle.is_cancel_requested:
            self._cancel(run)
            return
        if now - run.last_feedback >= 1.0 / FEEDBACK_RATE:
            run.last_feedback = now
            phase = WAITING if run.started is None else (
                SPINNING if self.node.streaming else SETTLING)
            handle.publish_feedback(SpinUp.Feedback(
                omega=math.nan if self.omega is None else self.omega,
                deflection=self.deflection, phase=phase))
        if run.started is None or self.node.streaming:
            return
        ended = run.started + run.plan.stream_time
        if run.arrival is None:
            if now > ended + self.arrival_timeout:
                self._finish(False, f'w did not reach {run.target:g} rad/s within '
                             f'{self.arrival_timeout:g} s of the stream\'s end (w = '
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
            whirl, misfit = free_whirl(t, u, v, self.params, run.target)
        except ValueError as exc:
            self._finish(False, f'residual whirl not measured: {exc}')
            return
        duration = run.arrival - (run.moved if run.moved is not None else run.arrival)
        self._finish(True, f'reached {run.target:g} rad/s; residual whirl {whirl:.3g} m '
                     f'(fit misfit {misfit:.2g} m) over {self.residual_window:g} s from '
                     f'{self.settle_time:g} s after arrival', duration=duration,
                     residual=whirl)

    def _cancel(self, run: _Run) -> None:
        last = self.node.last_setpoint
        self.node.stream(ConstantProfile(last), PLAN_HOLD)
        self.node.get_logger().info(f'SpinUp goal cancelled: holding w = {last:g} rad/s')
        run.goal_handle.canceled()
        self.run = None
        run.future.set_result(_result(False, f'cancelled: holding {last:g} rad/s',
                                      peak=run.peak, predicted=run.plan.predicted_residual))

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
