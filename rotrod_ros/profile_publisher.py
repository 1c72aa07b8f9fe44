"""rotrod profile publisher: streams an angular-velocity profile on cmd/omega.

Node ``rotrod_profile_publisher``: the topic below (INTERFACES), parameters after it,
all set at start; docs/nodes.md lists the same. Publishes std_msgs/Float64 (rad/s) on
``cmd/omega`` (relative: follows the namespace) at ``rate`` Hz of the node clock, so under
``use_sim_time`` it follows /clock. Sample k carries w(k / rate) of the profile: the
stream is the profile sampled on a regular grid, whatever the timer's jitter.

It waits until a subscriber is matched (and 0.5 s more, so that the subscriber has
matched it too), then streams for ``duration`` seconds (0: to the profile's end), logs
start and end, and exits, unless ``loop`` (start over) or ``hold`` (keep publishing
the last value) is set.

Profiles (rotrod_core.command.profiles): eq26 (period, omega_target: docs/model.md's Eq. 26),
constant (omega_target), step (omega_start -> omega_target at t_step), ramp (0 -> omega_target
over ramp_time from t_start), sine_sweep (offset + amplitude sin of a chirp
f_start -> f_end over sweep_time), table (table_file: CSV of time s, omega rad/s),
planned (the fastest vibration-free spin-up omega_start -> omega_target under
deflection_limit, residual, robust and max_angular_acceleration, planned for the rod
given by the same rod parameters as the simulator's; it logs what it planned and what
the simulator must allow, and by default streams the final speed 1 s past the plan).

With ``serve_spin_up`` it streams nothing at start and serves the SpinUp action
``spin_up`` instead (rotrod_interfaces/SpinUp, :mod:`rotrod_ros.spin_up_server`): each
goal is planned from the hub's w on ``joint_states``, streamed the same way, and
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
from geometry_msgs.msg import Vector3Stamped
from rclpy.action import CancelResponse
from rclpy.node import Node
from rotrod_interfaces.action import SpinUp
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64

import rotrod_core.live.scheduling as scheduling
from rotrod_core.command.profiles import ConstantProfile, Profile
from rotrod_core.command.registry import (
    OPTION_PROFILES,
    PROFILE_OPTIONS,
    describe,
    profile_from_options,
    stream_duration,
)

from . import interfaces, node_main, parameter_specs
from .node_main import ConfigurationError
from .parameter_specs import Spec
from .parameters import ROD_SPECS, rod_params
from .spin_up_server import SpinUpServer

NODE_NAME = 'rotrod_profile_publisher'
QOS_DEPTH = 1000
"""History depth of cmd/omega: a burst of samples (the timer catching up) is kept until
the subscriber has it (reliable delivery), so the stream stays lossless."""

MATCH_SETTLE = 0.5
"""Wall time from the first matched subscriber to the first sample, s. DDS matches the
two sides separately: the subscription the sender counts may not count the sender yet,
and samples sent meanwhile reach it later, all at once (a start burst: a profile
delivered late). Chosen by measurement: docs/realtime.md#match-settle."""

PARAMETERS = (
    Spec('profile', 'eq26', 'the profile to stream', choices=OPTION_PROFILES),
    *(Spec(o.name, o.default, o.description, o.unit, o.low, o.high)
      for o in PROFILE_OPTIONS),
    *(dataclasses.replace(s, text="planned: the rod planned for (as the "
                          f"simulator's): {s.text}") for s in ROD_SPECS),
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
    Spec('realtime_priority', 50, 'SCHED_FIFO priority of the node\'s thread, so the '
         'stream stays punctual on a busy machine, 1..99; 0 = ordinary scheduling. Needs '
         'root or CAP_SYS_NICE; refused with a warning otherwise', '', 0,
         scheduling.MAX_PRIORITY),
)
READ_ONLY = True
"""The publisher's parameters are set at start only."""

INTERFACES = (
    interfaces.pub('cmd/omega', Float64, 'the profile\'s angular velocity, rad/s: sample k '
                   'is w(k / rate); reliable, none skipped', QOS_DEPTH),
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


def make_profile(values: dict) -> Profile:
    """The profile described by the parameter values (raises ValueError with the reason)."""
    params = rod_params(values) if values['profile'] == 'planned' else None
    return profile_from_options(values['profile'], values, params)


class ProfilePublisher(Node):
    """Streams a profile on cmd/omega on the node clock."""

    def __init__(self, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        values = parameter_specs.declare(self, PARAMETERS, read_only=READ_ONLY)
        serving = values['serve_spin_up']
        if not values['rate'] > 0:
            raise ConfigurationError(f'rate must be > 0 Hz, got {values["rate"]!r}')
        self.rate = values['rate']
        self.realtime_priority = values['realtime_priority']
        self.server: SpinUpServer | None = None
        self.last_setpoint = 0.0
        self._waiting_logged = False
        self._matched_at: float | None = None
        if serving:
            if not values['residual_window'] > 0:
                raise ConfigurationError('residual_window must be > 0 s, got '
                                         f'{values["residual_window"]!r}')
            try:
                params = rod_params(values)
            except ValueError as exc:
                raise ConfigurationError(str(exc)) from None
            self.server = SpinUpServer(
                self, params, values['max_angular_acceleration'],
                settle_time=values['settle_time'], residual_window=values['residual_window'],
                arrival_timeout=values['arrival_timeout'])
            self.stream(ConstantProfile(0.0), 0.0)      # nothing to stream until a goal
            self.done = True
            server = self.server
            io = interfaces.create(self, INTERFACES, {
                'joint_states': server.on_joint_state, 'tip/deflection': server.on_deflection,
                'spin_up': {'execute_callback': server.execute,
                            'cancel_callback': lambda goal: CancelResponse.ACCEPT}})
            self.get_logger().info('serving the SpinUp action spin_up (rotrod_interfaces/'
                                   'SpinUp)')
        else:
            try:
                self.profile: Profile = make_profile(values)
            except ValueError as exc:
                raise ConfigurationError(str(exc)) from None
            for line in describe(self.profile, values):
                self.get_logger().info(line)
            self.duration = values['duration'] or stream_duration(self.profile)
            self.loop, self.hold = values['loop'], values['hold']
            self.name = values['profile']
            self._reset_stream(done=False)
            io = interfaces.create(self, [i for i in INTERFACES if i.name not in SERVE_ONLY])
        self._pub = io['cmd/omega']
        self._timer = self.create_timer(1.0 / self.rate, self._on_timer)

    def _reset_stream(self, done: bool) -> None:
        self.done = done
        self._start: float | None = None
        self._last_k = -1
        self.published = 0

    def stream(self, profile: Profile, duration: float) -> None:
        """Stream ``profile`` from now for ``duration`` s (the SpinUp server's goals)."""
        self.profile, self.duration, self.name = profile, duration, 'spin_up'
        self.loop = self.hold = False
        self._reset_stream(done=False)

    @property
    def streaming(self) -> bool:
        """Whether a stream is running (or waiting for its subscriber)."""
        return not self.done

    @property
    def stream_started(self) -> float | None:
        """Node-clock time of the current stream's first sample, s (None before it)."""
        return self._start

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
        if not self.done:
            self._stream_due(now)
        if self.server is not None:
            self.server.tick(now)

    def _stream_due(self, now: float) -> None:
        """Publish the samples due at ``now`` (node clock, s), in order, none skipped."""
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
            self._start = now
            self.get_logger().info(
                f'start: streaming {self.name} {self.profile!r} on {self._pub.topic_name} at '
                f'{self.rate:g} Hz for {self.duration:g} s')
        due = math.floor((now - self._start) * self.rate + 1e-6)
        end = self.samples
        # every sample in order, none skipped: a late timer sends the missed ones now
        for k in range(self._last_k + 1, due + 1):
            t = min(k, end) / self.rate
            self.last_setpoint = float(self.profile.omega(t))
            self._pub.publish(Float64(data=self.last_setpoint))
            self.published += 1
            self._last_k = k
            if k >= end and not self.hold:
                if self.loop:
                    self._start += (end + 1) / self.rate
                    self._last_k = -1
                    self.get_logger().info('end of the profile: starting over (loop)')
                else:
                    self.done = True
                    self.get_logger().info(f'end: published {self.published} samples over '
                                           f'{self.duration:g} s')
                return

    def schedule(self) -> None:
        """Run the calling (executor) thread at ``realtime_priority``, or say why not."""
        if self.realtime_priority:
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
                         own_signals=True)


if __name__ == '__main__':
    sys.exit(main())
