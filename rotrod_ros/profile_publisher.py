"""rotrod profile publisher: sends an angular-velocity profile to the simulator.

Node ``rotrod_profile_publisher``: the interfaces below (INTERFACES), parameters after
them, all set at start; docs/nodes.md lists the same. Two ways (``send_as``):

- **trajectory** (the default for ``planned``): the whole profile as one
  ``control_msgs/FollowJointTrajectory`` goal to the simulator's
  ``follow_joint_trajectory`` (:mod:`rotrod_ros.trajectory_client`), which executes it
  at its physics rate on its own clock: the plan reaches the rod as planned. The node
  logs the result and exits; the simulator holds the last speed.
- **stream** (the default for the others): std_msgs/Float64 (rad/s) on ``cmd/omega``
  (relative: follows the namespace) at ``rate`` Hz of the node clock, so under
  ``use_sim_time`` it follows /clock. Sample k carries w(k / rate) of the profile: the
  stream is the profile sampled on a regular grid, whatever the timer's jitter; the
  simulator re-grids it on the samples' arrival (docs/usage.md).

It waits until a subscriber is matched (and 0.5 s more, so that the subscriber has
matched it too), then streams for ``duration`` seconds (0: to the profile's end), logs
start and end, and exits, unless ``loop`` (start over) or ``hold`` (keep publishing
the last value) is set.

Profiles (rotrod_core.command.profiles): eq26 (period, omega_target: docs/model.md's Eq. 26),
constant (omega_target), step (omega_start -> omega_target at t_step), ramp (0 -> omega_target
over ramp_time from t_start), sine_sweep (offset + amplitude sin of a chirp
f_start -> f_end over sweep_time), table (table_file: CSV of time s, omega rad/s),
planned (the fastest vibration-free spin-up omega_start -> omega_target under
deflection_limit, residual, robust and max_angular_acceleration, planned for the
simulator's rod as its ``robot_description`` gives it, within its limits
(:mod:`rotrod_ros.rod_source`; a rod parameter given to this node overrides that field,
with a warning naming it); it logs what it planned).

With ``serve_spin_up`` it sends nothing at start and serves the SpinUp action
``spin_up`` instead (rotrod_interfaces/SpinUp, :mod:`rotrod_ros.spin_up_server`): each
goal is planned from the hub's w on ``joint_states``, sent as one trajectory, and
answered with the motion measured on ``joint_states`` and ``tip/deflection``; the node
runs until stopped.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import sys
import time

import rclpy
from action_msgs.msg import GoalStatus
from geometry_msgs.msg import Vector3Stamped
from rclpy.action import CancelResponse
from rclpy.node import Node
from rotrod_interfaces.action import SpinUp
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64

import rotrod_core.live.scheduling as scheduling
from rotrod_core.command.profiles import Profile
from rotrod_core.command.registry import (
    OPTION_PROFILES,
    PROFILE_OPTIONS,
    describe,
    plan_from_options,
    profile_from_options,
    stream_duration,
)
from rotrod_core.model.description import Description

from . import interfaces, node_main, parameter_specs, rod_source, trajectory_client
from .node_main import ConfigurationError
from .parameter_specs import Spec
from .parameters import ROD_SPECS
from .spin_up_server import SpinUpServer
from .trajectory_client import STATUS_NAMES, TrajectorySender, profile_trajectory

NODE_NAME = 'rotrod_profile_publisher'
QOS_DEPTH = 1000
"""History depth of cmd/omega: a burst of samples (the timer catching up) is kept until
the subscriber has it (reliable delivery), so the stream stays lossless."""

MATCH_SETTLE = 0.5
"""Wall time from the first matched subscriber to the first sample, s. DDS matches the
two sides separately: the subscription the sender counts may not count the sender yet,
and samples sent meanwhile reach it later, all at once (a start burst: a profile
delivered late). Chosen by measurement: docs/realtime.md#match-settle."""

SEND_AS = ('auto', 'trajectory', 'stream')
FROM_DESCRIPTION = ('max_angular_acceleration', 'deflection_limit')
"""The profile options whose default is the simulator's (its robot_description)."""

PARAMETERS = (
    Spec('profile', 'eq26', 'the profile to send', choices=OPTION_PROFILES),
    Spec('send_as', 'auto', 'trajectory: the whole profile as one FollowJointTrajectory goal '
         "to the simulator's follow_joint_trajectory, executed on its clock (to the "
         "profile's end, or duration); stream: setpoints on cmd/omega at rate Hz; auto: "
         'trajectory for planned, stream for the others', choices=SEND_AS),
    *(Spec(o.name, o.default, o.description + (
        "; not given: the simulator's, from its robot_description"
        if o.name in FROM_DESCRIPTION else ''), o.unit, o.low, o.high)
      for o in PROFILE_OPTIONS),
    *(dataclasses.replace(s, text="planned: not given, the simulator's from its "
                          'robot_description; given, it overrides that field (a warning '
                          f'names it): {s.text}') for s in ROD_SPECS),
    Spec('rate', 100.0, 'publishing rate, of the node clock (> 0)', 'Hz', 0.0, 1e5),
    Spec('duration', 0.0, 'how long to stream, of the node clock; 0 = to the profile\'s '
         'end', 's', 0.0, 1e9),
    Spec('loop', False, 'start the profile over at the end'),
    Spec('hold', False, 'after the end, keep publishing the last value until stopped'),
    Spec('serve_spin_up', False, 'serve the SpinUp action spin_up (goals planned from the '
         'hub\'s w on joint_states) instead of streaming the profile above at start; the '
         'node then runs until stopped'),
    Spec('settle_time', 0.5, 'SpinUp: time after w reaches the target before the residual '
         'whirl is measured, of the samples\' time', 's', 0.0, 600.0),
    Spec('residual_window', 4.0, 'SpinUp: length of the residual whirl\'s measurement on '
         'tip/deflection, of the samples\' time (> 0)', 's', 0.0, 600.0),
    Spec('arrival_timeout', 30.0, 'SpinUp: time after the stream\'s end, of the node '
         'clock, within which w must reach the target (else the goal is aborted)', 's',
         0.0, 1e6),
    Spec('realtime_priority', 50, 'send_as stream: SCHED_FIFO priority of the node\'s '
         'thread, so the stream stays punctual on a busy machine, 1..99; 0 = ordinary '
         'scheduling. Needs '
         'root or CAP_SYS_NICE; refused with a warning otherwise', '', 0,
         scheduling.MAX_PRIORITY),
)
READ_ONLY = True
"""The publisher's parameters are set at start only."""

INTERFACES = (
    interfaces.pub('cmd/omega', Float64, 'send_as stream: the profile\'s angular velocity, '
                   'rad/s: sample k is w(k / rate); reliable, none skipped', QOS_DEPTH),
    trajectory_client.INTERFACE,
    rod_source.interface('planned and serve_spin_up: the rod planned for'),
    interfaces.sub('joint_states', JointState, "serve_spin_up only: joint 'hub''s w, rad/s "
                   '(a goal\'s start speed, feedback, arrival)', QOS_DEPTH),
    interfaces.sub('tip/deflection', Vector3Stamped, 'serve_spin_up only: (u, v) m (feedback, '
                   'peak deflection, residual whirl)', QOS_DEPTH),
    interfaces.action('spin_up', SpinUp, 'serve_spin_up only: spin the hub to omega_target '
                      'rad/s along a profile (planned, planned_robust, eq26, ramp); feedback '
                      'w rad/s, deflection m, phase; result reached, duration s, peak '
                      'deflection m, residual whirl m (measured) and the predicted one; '
                      'cancel holds w; a refused goal is aborted with the reason'),
)
SERVE_ONLY = ('joint_states', 'tip/deflection', 'spin_up')
"""The interfaces created only with serve_spin_up."""
MADE_ELSEWHERE = (trajectory_client.ACTION_NAME, rod_source.TOPIC)
"""Interfaces of the table that their own modules create."""


def send_mode(values: dict) -> str:
    """'trajectory' or 'stream': what ``send_as`` means for the profile."""
    if values['send_as'] != 'auto':
        return values['send_as']
    return 'trajectory' if values['profile'] == 'planned' else 'stream'


class ProfilePublisher(Node):
    """Sends a profile to the simulator: one trajectory, or a stream on cmd/omega."""

    def __init__(self, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        values = parameter_specs.declare(self, PARAMETERS, read_only=READ_ONLY)
        self.values = values
        serving = values['serve_spin_up']
        if not values['rate'] > 0:
            raise ConfigurationError(f'rate must be > 0 Hz, got {values["rate"]!r}')
        self.rate = values['rate']
        self.realtime_priority = values['realtime_priority']
        self.server: SpinUpServer | None = None
        self.sender: TrajectorySender | None = None
        self.rod: rod_source.RodSource | None = None
        self.last_setpoint = 0.0
        self.mode = 'trajectory' if serving else send_mode(values)
        self._points: tuple | None = None            # a trajectory to send, once ready
        self._waiting_logged = False
        self._matched_at: float | None = None
        self.profile: Profile | None = None
        self.duration = 0.0
        self.loop, self.hold = values['loop'], values['hold']
        self.name = values['profile']
        self._reset_stream(done=False)
        self.failed = False
        """The profile could not be planned, or the simulator refused or aborted it."""
        planned = serving or values['profile'] == 'planned'
        if planned:
            self.rod = rod_source.RodSource(
                self, [s.name for s in ROD_SPECS] + list(FROM_DESCRIPTION),
                self._on_description,
                'the SpinUp goals\' plans' if serving else 'the planned spin-up')
        if self.mode == 'trajectory':
            self.sender = TrajectorySender(self, self._on_trajectory_result)
        if serving:
            if not values['residual_window'] > 0:
                raise ConfigurationError('residual_window must be > 0 s, got '
                                         f'{values["residual_window"]!r}')
            self.server = SpinUpServer(
                self, settle_time=values['settle_time'],
                residual_window=values['residual_window'],
                arrival_timeout=values['arrival_timeout'])
            self.done = True
            server = self.server
            io = interfaces.create(self, [i for i in INTERFACES if i.name not in MADE_ELSEWHERE], {
                'joint_states': server.on_joint_state, 'tip/deflection': server.on_deflection,
                'spin_up': {'execute_callback': server.execute,
                            'cancel_callback': lambda goal: CancelResponse.ACCEPT}})
            self.get_logger().info('serving the SpinUp action spin_up (rotrod_interfaces/'
                                   'SpinUp)')
        else:
            if not planned:
                self._use_profile(self._make_profile(None))
            io = interfaces.create(self, [i for i in INTERFACES
                                          if i.name not in SERVE_ONLY + MADE_ELSEWHERE])
        self._pub = io['cmd/omega']
        self._timer = self.create_timer(1.0 / self.rate, self._on_timer)

    # ------------------------------------------------------------ the profile
    def _make_profile(self, description: Description | None) -> Profile:
        """The profile of the parameters, planned for ``description``'s rod if planned."""
        values = self.values
        try:
            if values['profile'] != 'planned':
                return profile_from_options(values['profile'], values)
            assert description is not None
            options = {**values, **{k: getattr(description.limits, k)
                                    for k in FROM_DESCRIPTION}}
            if self.mode == 'stream':        # streamed: a lead at the start speed
                return profile_from_options('planned', options, description.params)
            return plan_from_options(description.params, options)
        except ValueError as exc:
            raise ConfigurationError(str(exc)) from None

    def _use_profile(self, profile: Profile) -> None:
        """Log what the profile is; get it ready to send."""
        self.profile = profile
        values = self.values
        lines = describe(profile, values)
        for line in lines[:1] if self.mode == 'trajectory' else lines:
            self.get_logger().info(line)
        self.duration = values['duration'] or stream_duration(profile)
        if self.mode == 'trajectory':
            end = values['duration'] or profile.end_time
            if not end:
                raise ConfigurationError(f'profile {values["profile"]} never ends: give '
                                         'duration to send it as a trajectory')
            self._points = profile_trajectory(profile, end)

    def _on_description(self, description: Description) -> None:
        """The simulator's rod is known (or changed): plan, once."""
        if self.server is not None or self.profile is not None or self.done:
            return                       # the SpinUp server reads it per goal; planned once
        try:
            self._use_profile(self._make_profile(description))
        except ConfigurationError as exc:
            self.get_logger().error(f'cannot plan: {exc}')
            self.done = True
            self.failed = True

    @property
    def description(self) -> Description | None:
        """The rod and limits planned for (the simulator's, with this node's overrides)."""
        return None if self.rod is None else self.rod.description

    # ------------------------------------------------------------ the trajectory
    def _send_when_ready(self) -> None:
        sender = self.sender
        if self._points is None or sender is None or sender.active:
            return
        if not sender.ready():
            if not self._waiting_logged:
                self.get_logger().info(f'waiting for the simulator\'s {sender.name}')
                self._waiting_logged = True
            return
        points, self._points = self._points, None
        self.get_logger().info(
            f'start: sending {self.name} {self.profile!r} to {sender.name} as one '
            f'trajectory of {len(points)} points over {points[-1].time:.6g} s')
        sender.send(points)

    def _on_trajectory_result(self, status: int, result) -> None:
        if self.server is not None:
            self.server.on_trajectory_result(status, result)
            return
        text = 'not accepted' if result is None else result.error_string
        if status == GoalStatus.STATUS_SUCCEEDED:
            self.get_logger().info(f'end: the simulator executed the trajectory: {text}')
        else:
            self.failed = True
            self.get_logger().error(f'end: the trajectory was {STATUS_NAMES.get(status, status)}'
                                    f' by the simulator: {text}')
        self.done = True

    def _reset_stream(self, done: bool) -> None:
        self.done = done
        self._start: float | None = None
        self._last_k = -1
        self.published = 0

    @property
    def finished(self) -> bool:
        """Whether the node is done: its stream ended, and it serves no action."""
        return self.done and self.server is None

    @property
    def samples(self) -> int:
        """Index of the last sample of one pass (at ``duration``)."""
        return max(0, round(self.duration * self.rate))

    def _on_timer(self) -> None:
        now = self.get_clock().now().nanoseconds * 1e-9
        if self.mode == 'trajectory':
            self._send_when_ready()
        elif not self.done and self.profile is not None:
            self._stream_due(now)
        if self.server is not None:
            self.server.tick(now)

    def _stream_due(self, now: float) -> None:
        """Publish the samples due at ``now`` (node clock, s), in order, none skipped.

        Sample k is due k periods after the timer tick that started the stream: on the
        timer's grid, so each tick sends its own sample (a start between ticks, at the
        callback's ``now``, would hold a sample back to the next tick whenever a callback
        ran earlier in its period than the first one did: a period of jitter, and under
        ``use_sim_time`` a sample not sent until the clock passes the next tick).
        """
        if self._start is None:
            if self._pub.get_subscription_count() == 0:
                if not self._waiting_logged:
                    self.get_logger().info('waiting for a subscriber on '
                                           f'{self._pub.topic_name}')
                    self._waiting_logged = True
                self._matched_at = None
                return
            if self._matched_at is None:
                self._matched_at = time.monotonic()
            if time.monotonic() - self._matched_at < MATCH_SETTLE:
                return
            self._start = self._tick_time(now)
            self.get_logger().info(
                f'start: streaming {self.name} {self.profile!r} on {self._pub.topic_name} at '
                f'{self.rate:g} Hz for {self.duration:g} s')
        due = math.floor((now - self._start) * self.rate + 1e-6)
        # every sample in order, none skipped: a late timer sends the missed ones now
        for k in range(self._last_k + 1, due + 1):
            if self._publish_sample(k):
                return

    def _tick_time(self, now: float) -> float:
        """The node-clock time (s) of the timer tick being run at ``now`` (s)."""
        until = self._timer.time_until_next_call()       # ns to the next tick
        if until is None or until < 0:
            return now
        return now + until * 1e-9 - 1.0 / self.rate

    def _publish_sample(self, k: int) -> bool:
        """Publish sample ``k`` (w at k / rate); True when it ends a pass."""
        end = self.samples
        assert self.profile is not None
        self.last_setpoint = float(self.profile.omega(min(k, end) / self.rate))
        self._pub.publish(Float64(data=self.last_setpoint))
        self.published += 1
        self._last_k = k
        if k < end or self.hold:
            return False
        if self.loop:
            assert self._start is not None
            self._start += (end + 1) / self.rate
            self._last_k = -1
            self.get_logger().info('end of the profile: starting over (loop)')
        else:
            self.done = True
            self.get_logger().info(f'end: published {self.published} samples over '
                                   f'{self.duration:g} s')
        return True

    def schedule(self) -> None:
        """Run the calling (executor) thread at ``realtime_priority``, or say why not.

        A stream only: a trajectory's timing is the simulator's.
        """
        if self.realtime_priority and self.mode == 'stream':
            scheduling.run_current_thread_at(self.realtime_priority, self.get_logger(),
                                             'streaming')

    def flush(self, timeout: float = 2.0) -> bool:
        """Wait until subscribers have acknowledged every sample (reliable QoS)."""
        return self._pub.wait_for_all_acked(rclpy.duration.Duration(seconds=timeout))


def _parser() -> argparse.ArgumentParser:
    return node_main.parser('profile_publisher', __doc__, [
        *interfaces.help_lines(INTERFACES), 'Parameters:',
        *parameter_specs.help_lines(PARAMETERS, READ_ONLY)])


def main(args: list | None = None) -> int:
    """Entry point of ``ros2 run rotrod profile_publisher``."""
    return node_main.run(NODE_NAME, ProfilePublisher, _parser(), args,
                         until=lambda node: node.finished, started=ProfilePublisher.schedule,
                         finished=lambda node: node.finished and node.flush(),
                         own_signals=True, status=lambda node: int(node.failed))


if __name__ == '__main__':
    sys.exit(main())
