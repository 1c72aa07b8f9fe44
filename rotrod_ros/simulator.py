"""rotrod simulator node: the coupled rod-and-hub model in real time over ROS 2 topics.

Node ``rotrod_simulator``: topics and services below (INTERFACES), parameters after
them (rotrod_ros.parameters); docs/nodes.md lists the same. Physics runs in a thread
of its own at a fixed step, paced to the clock (real_time_factor; 0 = as fast as
possible), at SCHED_FIFO realtime_priority where permitted: rotrod_core's RealTimeLoop
(rotrod_core/live/loop.py) around a SimulationEngine. This node declares parameters
(checked when set, applied after), converts messages and serves the ROS 2
simulation_interfaces standard (rotrod_ros.simulation_control: play, pause, stop, step,
reset, the tip's state; docs/simulation_control.md) and its older ~/reset and ~/pause.
A command is queued with its arrival time and applied by the physics thread at the
simulated instant it arrived; paused, at the next step.
"""

from __future__ import annotations

import argparse
import gc
import math
import re
import sys
import time
from typing import Any, NamedTuple

from rcl_interfaces.msg import SetParametersResult
from rclpy.node import Node
from rclpy.parameter import Parameter
from rosgraph_msgs.msg import Clock
from rotrod_interfaces.msg import DynamicFrequencies, WhirlEstimate
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64, String
from std_srvs.srv import SetBool, Trigger

import rotrod_core.live.scheduling as scheduling
from rotrod_core.command.joint_command import MalformedJointCommand, hub_command
from rotrod_core.estimation.whirl import WhirlEstimator
from rotrod_core.live.engine import EngineConfig, SimulationEngine
from rotrod_core.live.loop import PENDING_COMMANDS, RealTimeLoop, Sample, Status
from rotrod_core.live.publication import SAMPLE_TOPICS
from rotrod_core.model.geometry import rod_centerline, sphere_radius
from rotrod_core.model.interface import MARKER_NAMESPACE, ROTOR_FRAME, WORLD_FRAME
from rotrod_core.model.scene import scene
from rotrod_core.model.urdf import urdf_text

from . import (
    interfaces,
    messages,
    node_main,
    parameter_specs,
    simulation_control,
    trajectory_server,
)
from .interfaces import pub, srv, sub
from .keep_all import KeepAllPublishing
from .node_main import ConfigurationError
from .observation import Observation
from .parameters import ALL_SPECS, NodeSettings, ParameterValues

NODE_NAME = 'rotrod_simulator'
FLUSH_TIMEOUT = 10.0
"""Wall seconds a lossless simulator waits at its end for its subscribers to
acknowledge what it published (rmw sends acknowledgement requests periodically)."""
STOP_GRACE = 2.0
"""Wall seconds a lossless simulator stopped while a subscriber holds a publication up
goes on trying, so that its last sample is published on every topic (within the 5 s
the stop waits for the physics thread)."""
COMMAND_QOS_DEPTH = PENDING_COMMANDS
"""Queue depth of cmd/omega and cmd/torque: a burst of setpoints (a sender catching up)
must not be dropped, since the setpoint shaper numbers a stream's samples in order."""

COMMAND_TOPICS = ('cmd/omega', 'cmd/torque', 'joint_command')
"""The subscriptions that carry commands."""
SAMPLE_QOS_DEPTH = 100
"""Queue depth of the sample topics when paced: a reliable subscriber that falls behind
(a busy machine's scheduler, a garbage collection) by up to 100 publications (1 s at
100 Hz) still receives every one; a slower one loses the oldest."""

LOSSLESS = 'when started as fast as possible (real_time_factor 0)'
"""The sample topics' keep_all condition: then a reliable KEEP_ALL subscriber (e.g.
rerun_logger) gets every publication, the physics waiting for it when it falls behind."""


class StopReport(NamedTuple):
    """What the simulator says on stopping (its last log line, :func:`stop_line`)."""

    time: float
    """Simulated time, s."""
    publications: int
    held_up: int
    """Publications a KEEP_ALL subscriber held up."""
    dropped: int
    late_setpoints: int


def stop_line(report: StopReport) -> str:
    """The log line of ``report``."""
    return (f'stopped at simulated time {report.time:.3f} s after {report.publications} '
            f'publications ({report.held_up} held up by a KEEP_ALL subscriber, '
            f'{report.dropped} dropped; {report.late_setpoints} late setpoints)')


_STOP_LINE = re.compile(r'stopped at simulated time ([0-9.]+) s after (\d+) publications '
                        r'\((\d+) held up by a KEEP_ALL subscriber, (\d+) dropped; (\d+) '
                        r'late setpoints\)')


def stop_report(log: str) -> StopReport | None:
    """The last :func:`stop_line` in a simulator's ``log`` read back (None: none)."""
    found = _STOP_LINE.findall(log)
    if not found:
        return None
    t, *counts = found[-1]
    return StopReport(float(t), *map(int, counts))


INTERFACES = (
    sub('cmd/omega', Float64, 'angular-velocity setpoint, rad/s (drive velocity); with '
        'command_timeout > 0 s, when no command is accepted on the active input for '
        'that long, w ramps to 0 at max_angular_acceleration', COMMAND_QOS_DEPTH),
    sub('cmd/torque', Float64, 'hub torque, N m (drive torque: free rotation); with '
        'command_timeout, the torque is set to 0', COMMAND_QOS_DEPTH),
    sub('joint_command', JointState, "ros2_control's topic interface (topic_based_ros2_control): "
        "joint 'hub''s velocity = setpoint rad/s (drive velocity) or effort = torque N m "
        '(drive torque), read by name; other joints ignored; each field must be empty or '
        'have one entry per name (sensor_msgs/JointState), else the message is rejected '
        'with a warning and changes nothing; the same shaping, limits and timeout as '
        'cmd/omega and cmd/torque (docs/ros_integration.md)', COMMAND_QOS_DEPTH),
    pub('joint_states', JointState, "joint 'hub': position theta rad, velocity w rad/s, "
        "effort = hub torque N m; the URDF's passive tip joints 'tip_radial', "
        "'tip_tangential': u, v m, u', v' m/s (the true state, no noise), effort 0; every "
        '1/publish_rate of simulated time', SAMPLE_QOS_DEPTH, keep_all=LOSSLESS),
    pub('tip/deflection', messages.Vector3Stamped, "(u, v, 0) m in frame 'rotor' (rotating: "
        'x radial, y tangential), plus Gaussian noise of deflection_noise m (a sensor)',
        SAMPLE_QOS_DEPTH, keep_all=LOSSLESS),
    pub('tip/position', messages.PointStamped, "the mass, m, in frame 'world' (inertial; "
        'z = rod length)', SAMPLE_QOS_DEPTH, keep_all=LOSSLESS),
    pub('frequencies', DynamicFrequencies, 'f1 <= f2 Hz at the published w (omega, rad/s; '
        'Eq. 28, or the eigen analysis), stamped as the sample', SAMPLE_QOS_DEPTH,
        keep_all=LOSSLESS),
    pub('frequencies/estimate', WhirlEstimate, 'f1 (forward whirl), f2 (backward) Hz, '
        'their standard deviations, whether each is valid and why not, estimated from the '
        'published (u, v) over the last estimate_window, every 1/estimate_rate; stamped at '
        "the window's middle, which it describes", SAMPLE_QOS_DEPTH, keep_all=LOSSLESS),
    pub('markers', messages.MarkerArray, "disk, rod, mass, trail (frame 'world'), at "
        'marker_rate Hz of simulated time'),
    pub('/diagnostics', messages.DiagnosticArray, 'OK / WARN / ERROR with the reason and '
        'key values'),
    pub('/clock', Clock, 'simulated time, when real_time_factor != 1 or start_paused; '
        'with each publication, also when stepped'),
    pub('robot_description', String, 'the URDF of the rod (rotrod urdf) with its physical '
        'parameters and the drive\'s limits in a <rotrod> element, from the parameters in '
        'use: published at start and after every parameter change; what the other nodes '
        'read the rod from', 1, transient_local=True),
    *trajectory_server.INTERFACES,
    *simulation_control.INTERFACES,
    srv('~/reset', Trigger, 'back to the initial state, the simulated time going on; clears '
        'a halt (kept alias of ~/reset_simulation with SCOPE_STATE)'),
    srv('~/pause', SetBool, 'true: pause, false: resume (kept alias of '
        '~/set_simulation_state STATE_PAUSED / STATE_PLAYING)'),
)


class SimulatorNode(Node):
    """The simulator: parameters, topics, services; the physics is :attr:`loop`'s."""

    def __init__(self, **kwargs: Any) -> None:
        super().__init__(NODE_NAME, **kwargs)
        values = parameter_specs.declare(self, ALL_SPECS)
        if self.get_parameter('use_sim_time').value:
            raise ConfigurationError('use_sim_time must be false: the simulator is the clock '
                                     'source (it publishes /clock when real_time_factor != 1)')
        try:
            self._param_values = ParameterValues(values)
        except ValueError as exc:
            raise ConfigurationError(str(exc)) from None
        engine_config, settings = self._param_values.checked
        self._observation = Observation(settings)
        prefix = settings.frame_prefix
        self._rotor_frame, self._world_frame = prefix + ROTOR_FRAME, prefix + WORLD_FRAME
        self._marker_frames = messages.MarkerFrames(self._world_frame, MARKER_NAMESPACE)
        self._messages = messages.SampleMessages(self._rotor_frame, self._world_frame)
        self._status_name = f'{self.get_fully_qualified_name()}: simulation'
        self.loop = RealTimeLoop(
            SimulationEngine(engine_config), settings, self._publish,
            publish_status=self._publish_status,
            snapshot=lambda: self._observation.estimator,
            logger=self.get_logger(), running=self.context.ok,
            inputs={'omega': 'cmd/omega or joint_command',
                    'torque': 'cmd/torque or joint_command'},
            ready=self._subscribers_ready if settings.subscriber_wait()[0] else None,
            on_trajectory=lambda outcome: self._trajectories.on_outcome(outcome))
        self._trajectories: trajectory_server.TrajectoryServer = \
            trajectory_server.TrajectoryServer(self, self.loop)
        self._wait_deadline: float | None = None
        submit = self.loop.submit
        self._control = control = simulation_control.SimulationControl(
            self, self.loop, self._reset, self._world_frame, self._take_pending_commands)
        group = control.callback_group
        control_callbacks = control.callbacks()
        control_callbacks['~/simulate_steps']['callback_group'] = group
        # the sample topics' QoS is chosen once, at start: KEEP_ALL as fast as possible
        self.lossless = settings.real_time_factor == 0
        self._io = interfaces.create(self, INTERFACES, {
            'cmd/omega': lambda msg: submit('omega', msg.data, 'cmd/omega'),
            'cmd/torque': lambda msg: submit('torque', msg.data, 'cmd/torque'),
            'joint_command': self._on_joint_command,
            '~/reset': self._on_reset, '~/pause': self._on_pause, **control_callbacks,
            **self._trajectories.callbacks()},
            conditions={LOSSLESS} if self.lossless else (),
            callback_groups={i.name: group for i in simulation_control.INTERFACES})
        # paced, a held-up publication is dropped; as fast as possible, the physics waits
        # (and on a stop, finishes publishing its sample: up to STOP_GRACE)
        self._keep_all = KeepAllPublishing(self._io, self.get_logger(), self.context.ok,
                                           lambda: self.loop.running, STOP_GRACE)
        self.add_on_set_parameters_callback(self._validate_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)
        self._description: str | None = None
        self._publish_description()

    @property
    def engine(self) -> SimulationEngine:
        """The simulation."""
        return self.loop.engine

    @property
    def settings(self) -> NodeSettings:
        """The node's current settings."""
        return self.loop.settings

    # ----------------------------------------------------------------- parameters
    def _validate_parameters(self, params: list[Parameter]) -> SetParametersResult:
        """On set: check the new values as a whole; change nothing."""
        if any(p.name == 'use_sim_time' and p.value for p in params):
            return SetParametersResult(successful=False, reason='the simulator is the clock '
                                       'source; use_sim_time must stay false')
        try:
            self._param_values.check({p.name: p.value for p in params})
        except ValueError as exc:
            self.get_logger().warning(f'parameter change rejected: {exc}')
            return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, params: list[Parameter]) -> None:
        """Post set: apply the values the on-set callback checked."""
        engine_config, settings = self._param_values.take({p.name: p.value for p in params})
        with self.loop.lock:
            old = self.loop.settings
            self.loop.reconfigure(engine_config, settings)
            self._observation.reconfigure(old, settings)
        changed = ', '.join(f'{p.name}={p.value!r}' for p in params)
        self.get_logger().info(f'parameters changed: {changed}')
        self._publish_description()

    def description(self) -> str:
        """The URDF of the rod in use, with its <rotrod> description."""
        config = self.engine.config
        return urdf_text(config.params, limits=config.drive_limits,
                         disk_radius=self.settings.disk_radius)

    def _publish_description(self) -> None:
        """robot_description: the URDF of the parameters in use (if it changed)."""
        text = self.description()
        if text != self._description:
            self._description = text
            self._io['robot_description'].publish(String(data=text))

    def _waited_topics(self) -> list[str]:
        return [t for t in SAMPLE_TOPICS
                if t != 'frequencies/estimate' or self.settings.estimate_window]

    def _subscribers_ready(self) -> bool:
        """Whether simulated time may start (loop thread).

        Yes once every sample topic has the subscriptions wanted
        (NodeSettings.subscriber_wait), or when the wait is over.
        """
        wanted, longest = self.settings.subscriber_wait()
        topics = self._waited_topics()
        lacking = [t for t in topics if self._io[t].get_subscription_count() < wanted]
        if not lacking:
            self.get_logger().info(f'starting: {wanted} subscription(s) on each of '
                                   f'{", ".join(topics)}')
            return True
        now = time.monotonic()
        if self._wait_deadline is None:
            self._wait_deadline = now + longest
        if now < self._wait_deadline:
            return False
        self.get_logger().warning(
            f'starting after {longest:g} s without {wanted} subscription(s) on '
            f'{", ".join(lacking)}: a subscriber that comes later misses what was '
            'published before it (wait_for_subscribers N > 0 waits as long as it takes)')
        return True

    # ----------------------------------------------------------------- commands
    def _take_pending_commands(self) -> int:
        """Take what the command subscriptions hold now and queue it; how many.

        Called before a step request is queued (in the executor's thread, where the
        subscriptions' callbacks run too): a command that has reached the simulator
        before the request applies at its start even if the executor would have
        taken the request first. Topic by topic, each in its order of arrival.
        """
        taken = 0
        for name in COMMAND_TOPICS:
            subscription = self._io[name]
            while (got := interfaces.take(subscription)) is not None:
                subscription.callback(got[0])
                taken += 1
        return taken

    def _on_joint_command(self, msg: JointState) -> None:
        """joint_command: the hub's entry into the command queue, or a logged rejection."""
        try:
            kind, value = hub_command(msg.name, msg.position, msg.velocity, msg.effort,
                                      self.loop.engine.config.drive)
        except MalformedJointCommand as exc:
            self.loop.reject('joint_command', str(exc))
            return
        self.loop.submit(kind, value, 'joint_command')

    # ----------------------------------------------------------------- services
    def _reset(self, state: bool, time: bool) -> tuple:
        """Reset the loop (``state``, ``time``) and what is shown of it; the loop's result.

        Both (a full reset): the noise sequence starts again from its seed too.
        """
        with self.loop.lock:
            result = self.loop.reset(state=state, time=time)
            self._observation.reset(self.settings, noise=state and time)
        return result

    def _on_reset(self, request: Trigger.Request,
                  response: Trigger.Response) -> Trigger.Response:
        was_halted, t = self._reset(True, False)
        if self.loop.paused:
            self._control.stopped = False
        response.success = True
        response.message = f'reset to the initial state at simulated time {t:.3f} s'
        if was_halted:
            response.message += f' (cleared the halt: {was_halted})'
        self.get_logger().info(response.message)
        return response

    def _on_pause(self, request: SetBool.Request,
                  response: SetBool.Response) -> SetBool.Response:
        response.message = self.loop.pause(request.data)
        if not request.data:
            self._control.stopped = False
        response.success = True
        self.get_logger().info(response.message)
        return response

    def start(self) -> None:
        """Start the physics thread."""
        self.loop.start()

    def stop(self) -> None:
        """Stop the physics thread (returns when it has ended); say what was published.

        Lossless (started as fast as possible), first wait up to FLUSH_TIMEOUT for the
        reliable subscribers to acknowledge every sample already published.
        """
        self.loop.stop()
        if self.lossless:
            self._keep_all.flush(SAMPLE_TOPICS, FLUSH_TIMEOUT)
        sent = self._keep_all
        self.get_logger().info(stop_line(StopReport(
            self.engine.time, self.loop.publications, sent.held_up, sent.dropped,
            self.engine.late_setpoints)))

    # ----------------------------------------------------------------- publishing
    def _publish(self, s: Sample, settings: NodeSettings, config: EngineConfig,
                 estimator: WhirlEstimator | None) -> None:
        st, stamp, obs = s.state, messages.stamp(s.stamp), self._observation
        wait = not settings.real_time_factor       # as fast as possible: lossless
        send, m = self._keep_all.send, self._messages
        u, v = obs.deflection(float(st.u), float(st.v), settings.deflection_noise)
        send('joint_states', messages.set_joint_state(m.joint_state, stamp, st, s.torque), wait)
        send('tip/deflection', messages.set_deflection(m.deflection, stamp, u, v), wait)
        send('tip/position', messages.set_position(m.position, stamp, s.position), wait)
        send('frequencies', messages.set_frequencies(m.frequencies, stamp, float(st.omega),
                                                     *s.frequencies), wait)
        self._trajectories.feedback(stamp, s.tracking)
        io = self._io
        if settings.publishes_clock:
            io['/clock'].publish(messages.clock(stamp))
        if estimator is not None:
            estimate = estimator.push(s.time, u, v)
            if estimate is not None:       # stamped at its window's middle
                middle = messages.stamp(s.stamp - (s.time - estimate.time))
                send('frequencies/estimate',
                     messages.set_whirl_estimate(m.estimate, middle, estimate), wait)
        if s.markers:
            theta = float(st.theta)
            rod = rod_centerline(config.params, float(st.u), float(st.v), theta,
                                 scale=settings.marker_deflection_scale).tolist()
            io['markers'].publish(self._marker_frames.frame(stamp, scene(
                disk_radius=settings.disk_radius, theta=theta, rod=rod,
                rod_diameter=float(config.params.rod_diameter),
                mass_radius=sphere_radius(float(config.params.mass)),
                trail=obs.trail(rod[-1]))))

    def _publish_status(self, status: Status) -> None:
        self._io['/diagnostics'].publish(messages.diagnostics(
            messages.stamp(status.stamp), self._status_name, self.get_fully_qualified_name(),
            status.level, status.message, status.values))


def _parser() -> argparse.ArgumentParser:
    return node_main.parser('simulator', __doc__, [
        *interfaces.help_lines(INTERFACES),
        'Parameters (--ros-args -p name:=value, or --params-file config/table1.yaml):',
        *parameter_specs.help_lines(ALL_SPECS)])


def _started(node: SimulatorNode) -> None:
    priority = node.settings.realtime_priority
    # said before the loop thread starts, so a user (or a test) reads what the node will
    # wait for before the loop's own "starting: ..." line
    s, c = node.settings, node.engine.config
    wanted, longest = s.subscriber_wait()
    if wanted:
        node.get_logger().info(
            f'waiting for {wanted} subscription(s) on each of '
            f'{", ".join(node._waited_topics())} before simulated time starts '
            f'(wait_for_subscribers {s.wait_for_subscribers}'
            + (f': as fast as possible, for at most {longest:g} s)'
               if math.isfinite(longest) else ')'))
    node.get_logger().info(
        f'ready: drive={c.drive}, coupling={c.coupling}, physics {c.physics_rate:g} Hz, '
        f'publish {s.publish_rate:g} Hz, real_time_factor {s.real_time_factor:g}'
        + (', paused at simulated time 0 (start_paused): step or play through '
           '~/step_simulation, ~/simulate_steps or ~/set_simulation_state'
           if s.start_paused else ''))
    # the objects made so far (modules, node, messages) live as long as the process:
    # out of the collector's sight, so that a collection in the physics thread scans
    # only what the run makes (measured with gc.callbacks: without it, generation-1
    # collections took several milliseconds, the largest publication lags)
    gc.collect()
    gc.freeze()
    node.start()
    if priority > 1:
        # the executor thread stamps a command's arrival: one below the physics, so a
        # busy machine does not delay commands past setpoint_delay either
        scheduling.run_current_thread_at(priority - 1, node.get_logger(), 'executor thread')


def main(args: list[str] | None = None) -> int:
    """Entry point of ``ros2 run rotrod simulator`` and the ``simulator`` console script."""
    return node_main.run(NODE_NAME, SimulatorNode, _parser(), args,
                         started=_started, finished=SimulatorNode.stop, own_signals=True)


if __name__ == '__main__':
    sys.exit(main())
