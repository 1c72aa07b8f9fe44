"""rotrod simulator node: the coupled rod-and-hub model in real time over ROS 2 topics.

Node ``rotrod_simulator``. All names below are relative to the node's namespace
(``--ros-args -r __ns:=/rod1``) except /diagnostics and /clock.

Subscriptions:
  cmd/omega   std_msgs/Float64   angular-velocity setpoint, rad/s (drive = velocity)
  cmd/torque  std_msgs/Float64   hub torque, N m (drive = torque; free rotation)
  With command_timeout > 0 s, when no command has been accepted on the active one for
  that long (simulated time), velocity drive ramps w to 0 at max_angular_acceleration
  and torque drive sets the torque to 0; /diagnostics WARN until a command comes.
Publications (every 1/publish_rate of simulated time):
  joint_states    sensor_msgs/JointState       joint 'hub': theta rad, w rad/s, torque N m
                  and the URDF's tip joints 'tip_radial', 'tip_tangential': u, v m,
                  u', v' m/s (the true state: no noise), effort 0
  tip/deflection  geometry_msgs/Vector3Stamped (u, v, 0) m in frame 'rotor' (rotating),
                  plus Gaussian noise of deflection_noise m (a sensor's; 0 by default)
  tip/position    geometry_msgs/PointStamped   mass position, m, in frame 'world'
  frequencies     std_msgs/Float64MultiArray   [f1, f2] Hz at the current w
  frequencies/estimate  std_msgs/Float64MultiArray  [f1, f2] Hz estimated from the
                  published (u, v) over the last estimate_window (NaN: no estimate),
                  every 1/estimate_rate; it describes the window's middle
  markers         visualization_msgs/MarkerArray  disk, rod, mass, trail (frame 'world')
  /diagnostics    diagnostic_msgs/DiagnosticArray  OK / WARN / ERROR with the reason
  /clock          rosgraph_msgs/Clock          simulated time, when real_time_factor != 1
Services:
  ~/reset  std_srvs/Trigger   back to the initial state; clears a halt
  ~/pause  std_srvs/SetBool   true: pause, false: resume

Physics runs in its own thread at a fixed step (under SCHED_FIFO at
``realtime_priority`` where the system permits, and holding a CPU wake-up latency
request of ``cpu_dma_latency`` us while paced); each tick integrates in whole steps
up to the simulated time due now (``real_time_factor`` x wall time), so simulated
time does not drift from the clock. The ROS executor only handles commands,
services and parameters; a command is queued with its arrival time and applied by
the physics thread, between ticks, at the simulated instant it arrived (so a flood
of commands cannot hold the physics off). The physics is rotrod_core's
:class:`SimulationEngine`.
"""

from __future__ import annotations

import argparse
import gc
import sys
import threading
import time
import traceback
from collections import deque
from typing import NamedTuple

import numpy as np
from rcl_interfaces.msg import SetParametersResult
from rclpy.exceptions import ParameterException
from rclpy.executors import SingleThreadedExecutor
from rclpy.logging import get_logger
from rclpy.node import Node
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64, Float64MultiArray
from std_srvs.srv import SetBool, Trigger

import rotrod_core.live.scheduling as scheduling
from rotrod_core.estimation.whirl import WhirlEstimator
from rotrod_core.live.engine import ERROR, CommandRejected, SimulationEngine
from rotrod_core.live.pacing import Pacer, StampClock
from rotrod_core.model.equations import State
from rotrod_core.model.geometry import rod_centerline, sphere_radius

from . import messages, node_main
from .node_main import ConfigurationError
from .parameters import ALL_SPECS, SPECS_BY_NAME, build_settings, descriptor

NODE_NAME = 'rotrod_simulator'
MAX_BACKLOG = 1.0
"""Wall seconds of physics the thread catches up on after a stall; beyond, it skips."""
COMMAND_QOS_DEPTH = 1000
"""Queue depth of cmd/omega and cmd/torque: a burst of setpoints (a sender catching up)
must not be dropped, since the setpoint shaper numbers a stream's samples in order."""
PENDING_COMMANDS = COMMAND_QOS_DEPTH
"""Commands received but not yet applied, at most; beyond, the oldest is dropped (and
counted). The physics thread applies them between ticks: only a sender faster than
it can apply them fills this."""
TICK_COMMAND_BUDGET = 0.001
"""Wall seconds a tick spends at most on commands still queued at its start (normally
none: they are applied between ticks as they come), so that the publication it
computes stays on time."""
IDLE_WAIT = 0.05
"""Wall seconds between checks while paused or halted."""
LEAD = 0.0025
"""Wall seconds (at most; also at most a quarter publish period) by which a tick runs
ahead of the publications it computes; each publication then waits for its due time,
so its timing does not depend on how long the integration took, nor on a slow
previous publication (a marker array and a whirl estimate take up to a few ms). A
command that arrives within this lead applies at most this late. Measured (60 s runs,
bench_realtime's lag): 2 ms gave a largest lag of 4.4 and 10.2 ms, 2.5 ms of 1.0 and
5.7 ms."""
SPIN = 0.0003
"""Wall seconds before a publication's due time at which its thread stops sleeping and
polls the clock: this machine (a VM) sometimes wakes a sleeping SCHED_FIFO thread
milliseconds late, a busy one not. Costs about SPIN x publish_rate of a core (3 % at
100 Hz). With LEAD: largest lag 1.9 and 2.1 ms in 60 s runs, p99 0.3-0.4 ms."""


class Sample(NamedTuple):
    """What is published at one instant."""

    due: float | None
    """Monotonic wall time at which to publish (None: at once)."""
    time: float
    """Simulated time, s."""
    stamp: object
    state: State
    torque: float
    frequencies: tuple
    position: tuple
    markers: bool


class SimulatorNode(Node):
    """The simulator: parameters, topics, services, and the physics thread."""

    def __init__(self, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        self._values = self._declare_parameters()
        try:
            engine_config, self.settings = build_settings(self._values)
        except ValueError as exc:
            raise ConfigurationError(str(exc)) from None
        self.engine = SimulationEngine(engine_config)
        self._lock = threading.RLock()
        self._stop = threading.Event()
        self._paused = False
        self._overruns = 0
        self._failure: str | None = None
        self._priority = 0
        """SCHED_FIFO priority the physics thread runs at (0: ordinary)."""
        self._priority_refused: int | None = None
        """A priority the system refused (not asked for again)."""
        self._cpu_latency = scheduling.CpuLatencyRequest()
        self._cpu_latency_refused = False
        self._pacer = Pacer(self.settings.real_time_factor, 0.0, time.monotonic())
        self._stamps = StampClock(time.time() if not self.settings.publishes_clock else 0.0)
        self._countdown = 0
        self._published = (0.0, time.monotonic())
        self._samples_since_marker = 0
        self._next_marker_wall = 0.0         # monotonic time of the next allowed markers
        self._trail: deque = deque(maxlen=max(1, self.settings.marker_trail_length))
        self._last_level: int | None = None
        self._timeouts_logged = 0
        self._commands: deque = deque(maxlen=PENDING_COMMANDS)   # (topic, value, wall time)
        self._command_arrived = threading.Event()
        self.dropped_commands = 0
        self._drops_logged = 0
        self._next_diagnostics = 0.0
        prefix = self.settings.frame_prefix
        self._rotor_frame, self._world_frame = prefix + 'rotor', prefix + 'world'
        self._status_name = f'{self.get_fully_qualified_name()}: simulation'

        self._pub_joint = self.create_publisher(JointState, 'joint_states', 10)
        self._pub_deflection = self.create_publisher(
            messages.Vector3Stamped, 'tip/deflection', 10)
        self._pub_position = self.create_publisher(messages.PointStamped, 'tip/position', 10)
        self._pub_frequencies = self.create_publisher(Float64MultiArray, 'frequencies', 10)
        self._pub_estimate = self.create_publisher(
            Float64MultiArray, 'frequencies/estimate', 10)
        self._estimator = self._make_estimator(self.settings)
        self._noise = np.random.default_rng(self.settings.noise_seed)
        self._pub_markers = self.create_publisher(messages.MarkerArray, 'markers', 10)
        self._pub_diagnostics = self.create_publisher(
            messages.DiagnosticArray, '/diagnostics', 10)
        self._pub_clock = self.create_publisher(Clock, '/clock', 10)
        self.create_subscription(Float64, 'cmd/omega', self._on_omega, COMMAND_QOS_DEPTH)
        self.create_subscription(Float64, 'cmd/torque', self._on_torque, COMMAND_QOS_DEPTH)
        self.create_service(Trigger, '~/reset', self._on_reset)
        self.create_service(SetBool, '~/pause', self._on_pause)
        self.add_on_set_parameters_callback(self._on_set_parameters)
        self._thread = threading.Thread(target=self._run, name='rotrod_physics', daemon=True)

    # ----------------------------------------------------------------- parameters
    def _declare_parameters(self) -> dict:
        values = {}
        for spec in ALL_SPECS:
            try:
                param = self.declare_parameter(spec.name, spec.default, descriptor(spec))
            except ParameterException as exc:
                raise ConfigurationError(f'parameter {spec.name}: {exc}') from None
            values[spec.name] = param.value
        if self.get_parameter('use_sim_time').value:
            raise ConfigurationError('use_sim_time must be false: the simulator is the clock '
                                     'source (it publishes /clock when real_time_factor != 1)')
        return values

    def _on_set_parameters(self, params) -> SetParametersResult:
        values = dict(self._values)
        for p in params:
            if p.name == 'use_sim_time' and p.value:
                return SetParametersResult(
                    successful=False, reason='the simulator is the clock source; '
                                             'use_sim_time must stay false')
            if p.name in SPECS_BY_NAME:
                values[p.name] = p.value
        try:
            engine_config, settings = build_settings(values)
        except ValueError as exc:
            self.get_logger().warning(f'parameter change rejected: {exc}')
            return SetParametersResult(successful=False, reason=str(exc))
        with self._lock:
            self._apply_commands()          # those that came before the change, first
            if engine_config != self.engine.config:
                self.engine.reconfigure(engine_config)
            self._apply_settings(settings)
            self._values = values
        changed = ', '.join(f'{p.name}={p.value!r}' for p in params)
        self.get_logger().info(f'parameters changed: {changed}')
        return SetParametersResult(successful=True)

    @staticmethod
    def _make_estimator(settings) -> WhirlEstimator | None:
        """Whirl-frequency estimator over the published motion (None: estimates off)."""
        if not settings.estimate_window:
            return None
        return WhirlEstimator(settings.estimate_window, settings.publish_period,
                              1.0 / settings.estimate_rate)

    def _apply_settings(self, settings) -> None:
        old, self.settings = self.settings, settings
        if (settings.estimate_window, settings.estimate_rate, settings.publish_rate) != (
                old.estimate_window, old.estimate_rate, old.publish_rate):
            self._estimator = self._make_estimator(settings)
        if settings.real_time_factor != old.real_time_factor:
            self._restart_clock()
        self._countdown = min(self._countdown, self._publish_steps)
        if settings.noise_seed != old.noise_seed:
            self._noise = np.random.default_rng(settings.noise_seed)
        if settings.marker_trail_length != old.marker_trail_length:
            self._trail = deque(self._trail, maxlen=max(1, settings.marker_trail_length))

    @property
    def _publish_steps(self) -> int:
        """Physics steps between publications (publication instants are step instants)."""
        return max(1, round(self.engine.config.physics_rate / self.settings.publish_rate))

    @property
    def _lead(self) -> float:
        """Wall seconds a tick runs ahead: LEAD, at most a quarter publish period."""
        return min(LEAD, 0.25 * self.settings.publish_period / self.settings.real_time_factor)

    @property
    def _marker_every(self) -> int:
        return max(1, round(self.settings.publish_rate / self.settings.marker_rate))

    # ----------------------------------------------------------------- commands
    def _command_time(self, arrived: float) -> float | None:
        """Simulated time at which a command arrived at ``arrived`` takes effect, or None.

        ``arrived`` is a monotonic wall time; None means at once (the engine's time).

        In real time (factor 1) the simulated time due then. With /clock, senders run
        on simulated time and see only what was published, so the latest
        publication's simulated time plus the wall time from it, at the factor: it
        follows the simulation's actual progress also when the machine cannot keep
        up. Not capped above, since when the physics thread lags, a cap would date a
        run of arrivals early, and the setpoint shaper relies on delivery delays being
        one-sided (late, not early). The engine moves a time before its own forward.
        """
        if self._paused or self.engine.halted or not self._pacer.paced:
            return None
        if self.settings.publishes_clock:
            sim, wall = self._published
            at = sim + (arrived - wall) * self._pacer.factor
        else:
            at = self._pacer.sim_time(arrived)
        return at

    def _queue(self, topic: str, value: float) -> None:
        """Queue a command with its arrival time (executor thread; no lock, O(1))."""
        if len(self._commands) == PENDING_COMMANDS:
            self.dropped_commands += 1               # the deque drops the oldest
        self._commands.append((topic, value, time.monotonic()))
        self._command_arrived.set()

    def _on_omega(self, msg: Float64) -> None:
        self._queue('omega', msg.data)

    def _on_torque(self, msg: Float64) -> None:
        self._queue('torque', msg.data)

    def _apply_commands(self, deadline: float | None = None) -> None:
        """Apply queued commands in order, until none is left or monotonic ``deadline``.

        Called with the lock held. Each takes effect at the simulated time it arrived.
        """
        commands = self._commands
        n = 0
        while commands:
            if deadline is not None and n % 8 == 0 and time.monotonic() >= deadline:
                break
            n += 1
            topic, value, arrived = commands.popleft()
            # two call sites, one per topic: rclpy throttles a log call per call site,
            # and a rejection on one topic must not silence the other's
            timed_out = self.engine.timed_out_at is not None
            at = self._command_time(arrived)
            if topic == 'omega':
                try:
                    self.engine.command_omega(value, at=at)
                except CommandRejected as exc:
                    self.get_logger().warning(f'cmd/omega rejected: {exc}',
                                              throttle_duration_sec=1.0)
                    continue
            else:
                try:
                    self.engine.command_torque(value, at=at)
                except CommandRejected as exc:
                    self.get_logger().warning(f'cmd/torque rejected: {exc}',
                                              throttle_duration_sec=1.0)
                    continue
            if timed_out:
                self.get_logger().info(f'cmd/{topic}: commands again after the command '
                                       'timeout', throttle_duration_sec=1.0)
        if self.dropped_commands != self._drops_logged:
            self.get_logger().warning(
                f'commands arrive faster than they can be applied: '
                f'{self.dropped_commands} dropped so far (the oldest of '
                f'{PENDING_COMMANDS} pending)', throttle_duration_sec=1.0)
            self._drops_logged = self.dropped_commands

    def _wait_until(self, due: float) -> bool:
        """Return at monotonic time ``due``: sleep, then poll for the last SPIN s.

        False if the node is stopping.
        """
        early = due - time.monotonic() - SPIN
        if early > 0 and self._stop.wait(early):
            return False
        while time.monotonic() < due:
            pass
        return True

    def _idle_until(self, wake: float) -> bool:
        """Apply commands as they come until monotonic time ``wake``; False if stopping."""
        event = self._command_arrived
        while not self._stop.is_set():
            left = wake - time.monotonic()
            if left <= 0:
                return True
            event.clear()
            if self._commands:
                with self._lock:
                    self._apply_commands(deadline=wake)
            else:
                event.wait(left)
        return False

    def _log_timeout(self) -> None:
        """Warn once per command-timeout event (throttled: a flapping stream cannot flood)."""
        eng = self.engine
        if eng.timeouts == self._timeouts_logged:
            return
        self._timeouts_logged = eng.timeouts
        if eng.timed_out_at is None:       # already over (a halt and a reset since)
            return
        cfg = eng.config
        action = (f'spinning down to 0 at max_angular_acceleration '
                  f'{cfg.max_angular_acceleration:g} rad/s^2' if cfg.drive == 'velocity'
                  else 'hub torque set to 0 (free coast)')
        topic = 'cmd/omega' if cfg.drive == 'velocity' else 'cmd/torque'
        self.get_logger().warning(
            f'no command on {topic} for {cfg.command_timeout:g} s (command_timeout) at '
            f'simulated time {eng.timed_out_at:.3f} s: {action}', throttle_duration_sec=1.0)

    # ----------------------------------------------------------------- services
    def _restart_clock(self) -> None:
        """Re-anchor the wall-to-simulated mapping at the current instant."""
        now = time.monotonic()
        self._pacer.anchor(self.settings.real_time_factor, self.engine.time, now)
        self._published = (self.engine.time, now)
        if not self.settings.publishes_clock:
            self._stamps.follow_wall(self.engine.time, time.time())

    def _on_reset(self, request, response):
        with self._lock:
            # commands that came before the reset are superseded by it
            self._commands.clear()
            was_halted = self.engine.halted
            self.engine.reset()
            self._trail.clear()
            # a fresh estimator, not reset() in place: the physics thread may be
            # pushing into the current one outside the lock. The publication grid goes
            # on, so the first state after the reset is stamped after any publication
            # the physics thread still has to send from before it.
            self._estimator = self._make_estimator(self.settings)
            self._restart_clock()
            t = self.engine.time
        response.success = True
        response.message = f'reset to the initial state at simulated time {t:.3f} s'
        if was_halted:
            response.message += f' (cleared the halt: {was_halted})'
        self.get_logger().info(response.message)
        return response

    def _on_pause(self, request, response):
        with self._lock:
            if request.data and not self._paused:
                self._paused = True
                response.message = f'paused at simulated time {self.engine.time:.3f} s'
            elif not request.data and self._paused:
                self._paused = False
                self._restart_clock()
                response.message = f'resumed at simulated time {self.engine.time:.3f} s'
            else:
                response.message = 'already ' + ('paused' if self._paused else 'running')
        response.success = True
        self.get_logger().info(response.message)
        return response

    # ----------------------------------------------------------------- physics thread
    def start(self) -> None:
        """Start the physics thread."""
        self._restart_clock()
        self._thread.start()

    def stop(self) -> None:
        """Stop the physics thread (returns when it has ended)."""
        self._stop.set()
        self._command_arrived.set()
        if self._thread.is_alive():
            self._thread.join(timeout=5.0)

    def _sample(self) -> Sample:
        eng = self.engine
        self._samples_since_marker += 1
        markers = self.settings.markers and self._samples_since_marker >= self._marker_every
        if markers:
            # a viewer shows markers in wall time: faster than real time, at most twice
            # marker_rate per wall second (as fast as possible, markers every 10 ms of
            # simulated time cost a third of the speed)
            now = time.monotonic()
            markers = now >= self._next_marker_wall
            if markers:
                self._samples_since_marker = 0
                self._next_marker_wall = now + 0.5 / self.settings.marker_rate
        due = self._pacer.wall_time(eng.time) if self._pacer.paced else None
        return Sample(due, eng.time, messages.stamp(self._stamps.stamp(eng.time)), eng.state,
                      eng.torque, eng.frequencies(), eng.inertial_position(), markers)

    def _tick(self) -> tuple[list, float | None]:
        """Integrate up to the time due now.

        Returns the samples to publish and the monotonic wall time at which the next
        tick is due (None: at once).
        """
        eng = self.engine
        if self._paused or eng.halted:
            return [], time.monotonic() + IDLE_WAIT
        pacer = self._pacer
        if pacer.paced:
            now = time.monotonic()
            target = pacer.sim_time(now + self._lead)
            if target - eng.time > MAX_BACKLOG * pacer.factor:
                self._overruns += 1
                self.get_logger().warning(
                    f'fell {target - eng.time:.3f} s of simulated time behind the clock; '
                    'skipping ahead', throttle_duration_sec=5.0)
                self._restart_clock()
                target = eng.time
        samples = []
        while True:
            n = self._countdown
            if pacer.paced:
                n = min(n, eng.steps_until(target))
                if n == 0 and self._countdown > 0:
                    break
            done = eng.advance(n)
            self._countdown -= done
            if done < n:                      # halted
                self.get_logger().error(f'simulation halted: {eng.halted}; call ~/reset')
                break
            if self._countdown == 0:
                samples.append(self._sample())
                self._countdown = self._publish_steps
                if not pacer.paced:
                    break
        self._log_timeout()
        wake = None
        if pacer.paced and not eng.halted:
            wake = pacer.wall_time(eng.time + self._countdown * eng.dt) - self._lead
        return samples, wake

    def _schedule(self) -> bool:
        """Run this (the physics) thread at ``realtime_priority`` while paced.

        As fast as possible there is nothing to be on time for, and a real-time thread
        that never sleeps would starve ordinary ones; so it then runs as ordinary.
        Returns whether anything was changed (or tried and refused).
        """
        changed = self._hold_cpu_latency()
        want = self.settings.realtime_priority if self._pacer.paced else 0
        if want == self._priority or want == self._priority_refused:
            return changed
        if scheduling.run_current_thread_at(want, self.get_logger(), 'physics thread'):
            self._priority = want
        else:
            self._priority_refused = want
        return True

    def _hold_cpu_latency(self) -> bool:
        """Hold the ``cpu_dma_latency`` request while paced; release it otherwise.

        Returns whether anything was changed (or tried and refused).
        """
        want = self.settings.cpu_dma_latency if self._pacer.paced else -1
        held = self._cpu_latency.microseconds
        if want < 0:
            if held is None:
                return False
            self._cpu_latency.release()
            self.get_logger().info('cpu_dma_latency: released (not paced)')
            return True
        if want == held or self._cpu_latency_refused:
            return False
        problem = self._cpu_latency.hold(want)
        if problem:
            self._cpu_latency_refused = True
            self.get_logger().warning(f'cpu_dma_latency: {problem}; idle CPUs may wake '
                                      'late (set cpu_dma_latency:=-1 to not ask)')
        else:
            self.get_logger().info(f'cpu_dma_latency: idle CPUs wake within {want} us '
                                   'while paced')
        return True

    def _run(self) -> None:
        try:
            while not self._stop.is_set():
                if self._schedule():
                    # the clock starts (or goes on) from here: the change and its log
                    # lines took tens of ms at the node's start (measured: 44 ms), which
                    # the first tick would otherwise have caught up on in a burst of
                    # late publications
                    with self._lock:
                        self._restart_clock()
                with self._lock:
                    self._apply_commands(deadline=time.monotonic() + TICK_COMMAND_BUDGET)
                    samples, wake = self._tick()
                    # what the samples were computed with, also if a service or a
                    # parameter change replaces it while they are being published
                    context = self.settings, self.engine.config, self._estimator
                for sample in samples:
                    if sample.due is not None and not self._wait_until(sample.due):
                        return
                    self._publish(sample, *context)
                self._publish_diagnostics()
                # the next tick is due at an absolute time: the publication's wait and
                # the work after it (estimate, diagnostics) must not delay it
                if wake is not None and not self._idle_until(wake):
                    return
        except Exception as exc:  # report any failure, then stop the physics
            if self._stop.is_set() or not self.context.ok():
                return
            self._failure = f'physics thread failed: {exc!r}'
            self.get_logger().fatal(self._failure + '\n' + traceback.format_exc())
            self._publish_diagnostics(force=True)
        finally:
            self._cpu_latency.release()

    # ----------------------------------------------------------------- publishing
    def _publish(self, s: Sample, settings, config, estimator) -> None:
        self._published = (s.time, time.monotonic())
        st = s.state
        u, v = st.u, st.v
        if settings.deflection_noise:              # a sensor's noise: the state is untouched
            du, dv = self._noise.normal(0.0, settings.deflection_noise, 2)
            u, v = u + float(du), v + float(dv)
        self._pub_joint.publish(messages.joint_state(s.stamp, st, s.torque))
        self._pub_deflection.publish(messages.deflection(s.stamp, u, v, self._rotor_frame))
        self._pub_position.publish(messages.position(s.stamp, s.position, self._world_frame))
        self._pub_frequencies.publish(messages.frequencies(*s.frequencies))
        if settings.publishes_clock:
            self._pub_clock.publish(messages.clock(s.stamp))
        if estimator is not None:
            estimate = estimator.push(s.time, u, v)
            if estimate is not None:
                self._pub_estimate.publish(messages.frequencies(estimate.f1, estimate.f2))
        if s.markers:
            scale = settings.marker_deflection_scale
            rod = rod_centerline(config.params, st.u, st.v, st.theta, scale=scale)
            self._trail.append(tuple(rod[-1]))
            self._pub_markers.publish(messages.markers(
                s.stamp, self._world_frame, 'rotrod', disk_radius=settings.disk_radius,
                theta=st.theta, rod=rod, rod_diameter=float(config.params.rod_diameter),
                mass_radius=sphere_radius(float(config.params.mass)),
                trail=list(self._trail)))

    def _publish_diagnostics(self, force: bool = False) -> None:
        with self._lock:
            health = self.engine.health()
            level, message = health.level, health.message
            if self._failure:
                level, message = ERROR, self._failure
            elif self._paused:
                message = 'paused; ' + message
            now = time.monotonic()
            if not force and level == self._last_level and now < self._next_diagnostics:
                return
            self._last_level = level
            self._next_diagnostics = now + 1.0 / self.settings.diagnostics_rate
            values = (*health.values, ('paused', self._paused),
                      ('real_time_factor', self.settings.real_time_factor),
                      ('overruns', self._overruns),
                      ('dropped_commands', self.dropped_commands))
            stamp = messages.stamp(self._stamps.stamp(self.engine.time))
        self._pub_diagnostics.publish(messages.diagnostics(
            stamp, self._status_name, self.get_fully_qualified_name(), level, message, values))


def _parser() -> argparse.ArgumentParser:
    return argparse.ArgumentParser(
        prog='simulator', description=__doc__.split('\n')[0],
        epilog=__doc__.split('\n', 2)[2] + '\nParameters (--ros-args -p name:=value, or '
        '--params-file config/table1.yaml):\n' + '\n'.join(
            f'  {s.name}: {s.description} [default {s.default!r}]' for s in ALL_SPECS),
        formatter_class=argparse.RawDescriptionHelpFormatter)


def make_executor(name: str, context=None):
    """The rclpy executor named by the ``executor`` parameter."""
    if name == 'events':
        from rclpy.experimental import EventsExecutor
        get_logger(NODE_NAME).warning(
            'executor=events: the experimental EventsExecutor busy-waits on a full core and '
            'does not stop on SIGINT here (bench/bench_realtime.py); single_threaded is '
            'the measured better choice')
        return EventsExecutor(context=context)
    return SingleThreadedExecutor(context=context)


def _started(node: SimulatorNode) -> None:
    priority = node.settings.realtime_priority
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
    s, c = node.settings, node.engine.config
    node.get_logger().info(
        f'ready: drive={c.drive}, coupling={c.coupling}, physics {c.physics_rate:g} Hz, '
        f'publish {s.publish_rate:g} Hz, real_time_factor {s.real_time_factor:g}, '
        f'executor {s.executor}')


def main(args: list | None = None) -> int:
    """Entry point of ``ros2 run rotrod simulator`` and the ``simulator`` console script."""
    return node_main.run(NODE_NAME, SimulatorNode, _parser(), args,
                         make_executor=lambda node: make_executor(node.settings.executor),
                         started=_started, finished=SimulatorNode.stop)


if __name__ == '__main__':
    sys.exit(main())
