"""rotrod simulator node: a world of rods on a rotating disk, in real time over ROS 2.

Node ``rotrod_simulator``: topics and services below (INTERFACES), parameters after
them (rotrod_ros.parameters); docs/nodes.md lists the same. It holds a world of rods
(rotrod_core.live.world): one rod with today's names by default, ``rods:=N`` copies of
its rod named rod0 ... (their interfaces under ``rodK/``), and rods spawned and deleted
through the simulation standard (rotrod_ros.entities). Physics runs in a thread of its
own at a fixed step, every rod in one batch, paced to the clock (real_time_factor;
0 = as fast as possible), at SCHED_FIFO realtime_priority where permitted:
rotrod_core's RealTimeLoop (rotrod_core/live/loop.py). This node declares parameters
(checked when set, applied after; the rod's parameters describe the rods it starts
with), converts messages (rotrod_ros.rod_io, per rod) and serves the ROS 2
simulation_interfaces standard (rotrod_ros.simulation_control: play, pause, stop,
step, reset, entity states; docs/simulation_control.md) and its older ~/reset and
~/pause. A command is queued with its arrival time and applied by the physics thread
at the simulated instant it arrived; paused, at the next step.
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
from std_srvs.srv import SetBool, Trigger

import rotrod_core.live.scheduling as scheduling
from rotrod_core.live.engine import EngineConfig, SimulationEngine
from rotrod_core.live.loop import RealTimeLoop, Sample, Status
from rotrod_core.live.world import World
from rotrod_core.model.interface import WORLD_FRAME, stamp_parts

from . import (
    cdr,
    entities,
    interfaces,
    messages,
    node_main,
    parameter_specs,
    rod_io,
    simulation_control,
    trajectory_server,
)
from .interfaces import pub, srv
from .node_main import ConfigurationError
from .parameters import ALL_SPECS, NodeSettings, ParameterValues

NODE_NAME = 'rotrod_simulator'
FLUSH_TIMEOUT = 10.0
"""Wall seconds a lossless simulator waits at its end for its subscribers to
acknowledge what it published (rmw sends acknowledgement requests periodically)."""
STOP_GRACE = 2.0
"""Wall seconds a lossless simulator stopped while a subscriber holds a publication up
goes on trying, so that its last sample is published on every topic (within the 5 s
the stop waits for the physics thread)."""


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
    *rod_io.INTERFACES,
    pub('/diagnostics', messages.DiagnosticArray, 'OK / WARN / ERROR with the reason and '
        'key values, a status per rod'),
    pub('/clock', Clock, 'simulated time, when real_time_factor != 1 or start_paused; '
        'with each publication, also when stepped'),
    *simulation_control.INTERFACES,
    *entities.INTERFACES,
    srv('~/reset', Trigger, 'back to the initial state, the simulated time going on; clears '
        'a halt (kept alias of ~/reset_simulation with SCOPE_STATE)'),
    srv('~/pause', SetBool, 'true: pause, false: resume (kept alias of '
        '~/set_simulation_state STATE_PAUSED / STATE_PLAYING)'),
)
"""The node's interfaces: every rod's (rod_io.INTERFACES, under the rod's prefix), then
the world's."""
ROD_INTERFACES = {i.name for i in rod_io.INTERFACES}


def started_rods(count: int) -> list[tuple[str, str]]:
    """(name, prefix) of the rods a simulator starts with: one as today, or rod0... ."""
    if count == 1:
        return [('', '')]
    return [(f'rod{k}', f'rod{k}/') for k in range(count)]


class SimulatorNode(Node):
    """The simulator: a world of rods, its parameters, topics and services.

    The physics is :attr:`loop`'s (a :class:`~rotrod_core.live.world.World` stepped as one
    batch); each rod's ROS side is a :class:`~rotrod_ros.rod_io.RodIO` in :attr:`rods`.
    """

    stop_grace = STOP_GRACE

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
        self._status_name = f'{self.get_fully_qualified_name()}: simulation'
        self.world = World(engine_config.physics_rate)
        self.rods: dict[str, rod_io.RodIO] = {}
        self._rods_added = 0     # each rod's place: when its whirl estimates fall
        """Each rod's ROS side, by its name in the world ('' for a single started rod)."""
        self.started = [name for name, _ in started_rods(values['rods'])]
        """The rods the parameters describe (the others were spawned)."""
        self._goals: dict[int, trajectory_server.TrajectoryServer] = {}
        self._clock_time: float | None = None
        self._extras: list[tuple[rod_io.RodIO, tuple]] = []   # (rod, its extras) this instant
        self.loop = RealTimeLoop(
            self.world, settings, self._publish, publish_status=self._publish_status,
            snapshot=lambda: {name: io.observation.estimator
                              for name, io in self.rods.items()},
            logger=self.get_logger(), running=self.context.ok,
            inputs={'omega': 'cmd/omega or joint_command',
                    'torque': 'cmd/torque or joint_command'},
            ready=self._subscribers_ready if settings.subscriber_wait()[0] else None,
            on_trajectory=self._on_trajectory, published=self._publish_extras)
        self._wait_deadline: float | None = None
        # the sample topics' QoS is chosen once, at start: KEEP_ALL as fast as possible
        self.lossless = settings.real_time_factor == 0
        self._conditions = {rod_io.LOSSLESS} if self.lossless else set()
        self._control = control = simulation_control.SimulationControl(
            self, self.loop, self._reset, settings.frame_prefix + WORLD_FRAME,
            self._take_pending_commands, remove_spawned=self._remove_spawned,
            max_steps=lambda: self.settings.max_steps_per_request)
        self.entities = entities.EntityServices(self)
        group = control.callback_group
        callbacks = {**control.callbacks(), **self.entities.callbacks()}
        callbacks['~/simulate_steps']['callback_group'] = group
        world_interfaces = [i for i in INTERFACES if i.name not in ROD_INTERFACES]
        self._io = interfaces.create(self, world_interfaces, {
            '~/reset': self._on_reset, '~/pause': self._on_pause, **callbacks},
            callback_groups={i.name: group for i in world_interfaces if i.kind in ('srv',
                                                                                   'action')})
        for name, prefix in started_rods(values['rods']):
            self.add_rod(name, prefix, engine_config, rod_io.ORIGIN)
        self.add_on_set_parameters_callback(self._validate_parameters)
        self.add_post_set_parameters_callback(self._apply_parameters)

    @property
    def engine(self) -> SimulationEngine:
        """The simulation of a single rod (ValueError for a world of several)."""
        return self.loop.engine

    @property
    def settings(self) -> NodeSettings:
        """The node's current settings."""
        return self.loop.settings

    # ----------------------------------------------------------------- rods
    def add_rod(self, name: str, prefix: str, config: EngineConfig,
                pose: rod_io.Pose) -> rod_io.RodIO:
        """A rod joins the world (between steps): its engine and its ROS side."""
        with self.loop.lock:
            engine = SimulationEngine(config, world=self.world, name=name)
            io = rod_io.RodIO(self, self.loop, engine, prefix, pose, self.settings,
                              self._conditions, on_goal=self._goals.__setitem__,
                              stagger=self._rods_added)
            self._rods_added += 1
            self.rods[name] = io
            self._pace_looks()
        io.publish_description(config, self.settings.disk_radius)
        return io

    def _pace_looks(self) -> None:
        """Every rod's period of looks for subscribers, for the world's size now."""
        every = rod_io.look_period(len(self.rods))
        for io in self.rods.values():
            io.look_every = every

    def remove_rod(self, name: str) -> None:
        """A rod leaves the world (between steps): its goals end, its interfaces go."""
        with self.loop.lock:
            io = self.rods.pop(name)
            self._pace_looks()
            engine = self.world.remove(name)
            engine._end_goals('INVALID_GOAL', 'the rod was deleted')
            self.loop._report_outcomes_of(engine)
        io.destroy()

    def _remove_spawned(self) -> list[str]:
        """Take every spawned rod out of the world (ResetSimulation's SCOPE_SPAWNED)."""
        spawned = [name for name in self.rods if name not in self.started]
        for name in spawned:
            self.remove_rod(name)
        return spawned

    def _on_trajectory(self, outcome) -> None:
        """A trajectory's outcome (the loop's thread): to its rod's server."""
        server = self._goals.pop(outcome.token, None)
        if server is not None:
            server.on_outcome(outcome)

    # ----------------------------------------------------------------- parameters
    def _validate_parameters(self, params: list[Parameter]) -> SetParametersResult:
        """On set: check the new values as a whole; change nothing."""
        if any(p.name == 'use_sim_time' and p.value for p in params):
            return SetParametersResult(successful=False, reason='the simulator is the clock '
                                       'source; use_sim_time must stay false')
        try:
            engine_config, _ = self._param_values.check({p.name: p.value for p in params})
            for name in self.rods:
                if name not in self.started:          # a spawned rod keeps its rod and limits
                    self.entities.config_with(engine_config, name)
        except ValueError as exc:
            self.get_logger().warning(f'parameter change rejected: {exc}')
            return SetParametersResult(successful=False, reason=str(exc))
        return SetParametersResult(successful=True)

    def _apply_parameters(self, params: list[Parameter]) -> None:
        """Post set: apply the values the on-set callback checked."""
        engine_config, settings = self._param_values.take({p.name: p.value for p in params})
        configs = {name: (engine_config if name in self.started else
                          self.entities.config_with(engine_config, name))
                   for name in self.rods}
        with self.loop.lock:
            old = self.loop.settings
            if engine_config.physics_rate != self.world.physics_rate:
                self.world.set_physics_rate(engine_config.physics_rate)
            self.loop.reconfigure(configs, settings)
            for io in self.rods.values():
                io.observation.reconfigure(old, settings)
        changed = ', '.join(f'{p.name}={p.value!r}' for p in params)
        self.get_logger().info(f'parameters changed: {changed}')
        for name, io in self.rods.items():
            io.publish_description(configs[name], settings.disk_radius)

    def description(self, rod: str = '') -> str | None:
        """The URDF a rod last published (the first rod's by default)."""
        return self.rods[rod].description

    def _waited_topics(self) -> list[str]:
        return [t for t in rod_io.SAMPLE_TOPICS
                if t != 'frequencies/estimate' or self.settings.estimate_window]

    def _subscribers_ready(self) -> bool:
        """Whether simulated time may start (loop thread).

        Yes once every started rod's sample topics have the subscriptions wanted
        (NodeSettings.subscriber_wait), or when the wait is over.
        """
        wanted, longest = self.settings.subscriber_wait()
        topics = self._waited_topics()
        lacking = [io.prefix + t for io in list(self.rods.values()) for t in topics
                   if io.io[t].get_subscription_count() < wanted]
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
        """Take what the rods' command subscriptions hold now and queue it; how many.

        Called before a step request is queued (in the executor's thread, where the
        subscriptions' callbacks run too): a command that has reached the simulator
        before the request applies at its start even if the executor would have
        taken the request first. Rod by rod, topic by topic, each in its order of
        arrival.
        """
        return sum(io.take_pending_commands() for io in list(self.rods.values()))

    # ----------------------------------------------------------------- services
    def _reset(self, state: bool, time: bool) -> tuple:
        """Reset the loop (``state``, ``time``) and what is shown of it; the loop's result.

        Both (a full reset): the noise sequence starts again from its seed too.
        """
        with self.loop.lock:
            result = self.loop.reset(state=state, time=time)
            for io in self.rods.values():
                io.observation.reset(self.settings, noise=state and time)
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
            for io in self.rods.values():
                io.flush(FLUSH_TIMEOUT)
        held = sum(io.keep_all.held_up for io in self.rods.values())
        dropped = sum(io.keep_all.dropped for io in self.rods.values())
        self.get_logger().info(stop_line(StopReport(
            self.world.time, self.loop.publications, held, dropped,
            self.loop.late_setpoints)))

    # ----------------------------------------------------------------- publishing
    def _publish(self, s: Sample, settings: NodeSettings, config: EngineConfig,
                 estimators: dict) -> None:
        """A rod's sample (the physics thread); /clock once per instant."""
        if settings.publishes_clock and s.time != self._clock_time:
            self._clock_time = s.time
            self._io['/clock'].publish(messages.clock(messages.stamp(s.stamp)))
        io = self.rods.get(s.rod)
        if io is not None:                    # not deleted since the sample was taken
            estimator = estimators.get(s.rod)
            extras = io.publish(s, settings, config, estimator)
            if s.markers or estimator is not None:      # an extras pass has work for it
                self._extras.append((io, extras))

    def _publish_extras(self) -> None:
        """Every rod's estimate and markers of the instant, after all its samples."""
        extras, self._extras = self._extras, []
        for io, args in extras:
            if self.rods.get(io.name) is io:      # not deleted since its samples went
                io.publish_extras(*args)

    def _publish_status(self, statuses: list[Status]) -> None:
        if not statuses:
            return
        fqn = self.get_fully_qualified_name()
        # as bytes (rotrod_ros.cdr): a world's hundred statuses a second cost a fifth
        text = messages.value_text
        sec, nanosec = stamp_parts(statuses[0].stamp)
        self._io['/diagnostics'].publish(cdr.diagnostic_array(
            sec, nanosec,
            [(st.level, self._status_name if not st.rod else f'{fqn}: {st.rod}',
              st.message, fqn, [(str(k), text(v)) for k, v in st.values])
             for st in statuses]))


def _parser() -> argparse.ArgumentParser:
    return node_main.parser('simulator', __doc__, [
        *interfaces.help_lines(INTERFACES),
        'Parameters (--ros-args -p name:=value, or --params-file config/table1.yaml):',
        *parameter_specs.help_lines(ALL_SPECS)])


def _started(node: SimulatorNode) -> None:
    priority = node.settings.realtime_priority
    # said before the loop thread starts, so a user (or a test) reads what the node will
    # wait for before the loop's own "starting: ..." line
    s = node.settings
    c = next(iter(node.world)).config
    wanted, longest = s.subscriber_wait()
    if wanted:
        node.get_logger().info(
            f'waiting for {wanted} subscription(s) on each of '
            f'{", ".join(node._waited_topics())} before simulated time starts '
            f'(wait_for_subscribers {s.wait_for_subscribers}'
            + (f': as fast as possible, for at most {longest:g} s)'
               if math.isfinite(longest) else ')'))
    names = ', '.join(node.world.engines)
    rods = '' if len(node.world) == 1 else f'{len(node.world)} rods ({names}), '
    node.get_logger().info(
        f'ready: {rods}drive={c.drive}, coupling={c.coupling}, physics {c.physics_rate:g} Hz, '
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
