"""rotrod Rerun logger: records the simulator's topics to a Rerun file, headlessly.

Node ``rotrod_rerun_logger``: topics below (INTERFACES), parameters after them, all
set at start; docs/nodes.md lists the same. It writes ``output`` (a .rrd file) with
time on the message stamps and a default blueprint, so the file opens as a dashboard:
``rerun rotrod.rrd``. With ``serve:=true`` it also
serves the recording live on 127.0.0.1:``serve_port`` (``rerun --connect``). With
``record_from:=motion`` it keeps only the last ``pretrigger`` seconds until the hub's
angular velocity first changes: the file begins just before the motion, not when the
logger started. The recording draws the mechanism in 3D from ``joint_states`` (the hub
angle and the tip joints' true deflection) with the simulator's rod, read from its
``robot_description`` (:mod:`rotrod_ros.rod_source`; a drawn parameter given here
overrides it, with a warning), and marks the run's stages and its first passage of
``deflection_limit``. It opens the recording and subscribes once it has the rod (at
once if every drawn parameter is given here).

Data is written in batches every ``flush_period`` seconds. On SIGINT, SIGTERM or the
end of the run the messages already received but not yet handled are taken too, the
last batch is written and the file closed, so ``rerun rrd verify`` accepts it and it
holds every message received up to the signal. The file has no footer (the index of
its chunks) unless ``footer:=true``: rerun keeps the footer's manifest in memory for the
whole run, so a logger without it keeps a flat memory however long it records (rerun's
advice for long streaming sessions). A file without footer loads in the viewer and with
``RrdReader(path).stream()``; ``rerun rrd verify`` refuses it and
``rerun rrd optimize FILE -o COPY`` makes a complete copy of it. ``footer:=true`` suits
bounded runs (``rotrod demo`` sets it): a clean end writes the footer, so
``rerun rrd verify`` accepts the file. Killed outright (SIGKILL), the logger leaves a
file without footer holding everything up to its last write, at most ``flush_period``
old.
"""

from __future__ import annotations

import argparse
import math
import os
import sys
import time
from collections import deque
from dataclasses import replace

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import PointStamped, Vector3Stamped
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from rotrod_interfaces.msg import DynamicFrequencies, WhirlEstimate
from sensor_msgs.msg import Imu, JointState

from rotrod_core.model.geometry import sphere_radius
from rotrod_core.reporting.recording import RecordingWriter
from rotrod_core.reporting.recording_scene import Mechanism

from . import interfaces, node_main, parameter_specs, rod_source
from .interfaces import ALWAYS
from .messages import to_seconds
from .node_main import ConfigurationError
from .parameter_specs import Spec
from .parameters import SPECS_BY_NAME

NODE_NAME = 'rotrod_rerun_logger'
QOS_DEPTH = 1000
"""Subscription queue depth where the publisher's history is KEEP_LAST (a burst of
publications is not dropped); with a simulator started as fast as possible, KEEP_ALL on
both sides: the simulator waits for the logger instead of dropping (ALWAYS)."""

EARLY_MESSAGES = 100_000
"""Messages kept at most before the recording opens (the simulator's robot_description
normally comes before its first sample)."""
TAKE_BUDGET = 0.05
"""Wall seconds a callback spends at most taking the messages already received (the
flush timer runs between)."""
CLOSE_BUDGET = 10.0
"""Wall seconds the logger spends at most at its end on messages already received."""

RECORD_FROM = ('start', 'motion')
DRAWN = ('mass', 'rod_length', 'rod_diameter', 'eccentricity', 'deflection_limit',
         'marker_deflection_scale', 'disk_radius')
"""The simulator's parameters the recording draws with (the same names and defaults)."""
FROM_DESCRIPTION = ('mass', 'rod_length', 'rod_diameter', 'eccentricity', 'deflection_limit')
"""The drawn parameters the simulator's robot_description gives (the disk radius too)."""
PARAMETERS: tuple[Spec, ...] = (
    Spec('output', 'rotrod.rrd', 'path of the Rerun recording to write'),
    Spec('serve', False, 'also serve the recording live on 127.0.0.1 (rerun --connect)'),
    Spec('serve_port', 9876, 'TCP port of the live server (127.0.0.1 only)', '', 1, 65535),
    Spec('flush_period', 0.25, 'wall time between writes of the buffered data (> 0)', 's',
         0.0, 60.0),
    Spec('footer', False, 'write the RRD footer (an index of every chunk) at a clean end; '
         'rerun keeps it in memory until then, so memory grows with the run: for bounded '
         'runs (without it: rerun rrd optimize FILE -o COPY adds one)'),
    Spec('record_from', 'start', 'start: record from the first message; motion: keep only '
         'the last pretrigger seconds until the hub\'s angular velocity first differs from '
         'the first one received, then record everything (the file begins just before the '
         'motion, not when the logger started)', choices=RECORD_FROM),
    Spec('pretrigger', 0.5, 'with record_from motion: stamp time kept from before the hub '
         'first moved', 's', 0.0, 86400.0),
    *(replace(SPECS_BY_NAME[name], read_only=True,
              text=f"for the 3D scene; not given: the simulator's (robot_description), "
                   f'given: overrides it: {SPECS_BY_NAME[name].text}')
      for name in DRAWN if name != 'marker_deflection_scale'),
    replace(SPECS_BY_NAME['marker_deflection_scale'], read_only=True,
            text=f"for the 3D scene: {SPECS_BY_NAME['marker_deflection_scale'].text}"),
)
READ_ONLY = True
"""The logger's parameters are set at start only."""

SAMPLES = (   # in the order a simulator's tick publishes them (see _take_pending)
    interfaces.sub('joint_states', JointState, "joint 'hub': w rad/s and the hub torque "
                   'N m', QOS_DEPTH, ALWAYS),
    interfaces.sub('tip/deflection', Vector3Stamped, '(u, v) m in the rotating frame',
                   QOS_DEPTH, ALWAYS),
    interfaces.sub('tip/position', PointStamped, 'the mass in the inertial frame, m',
                   QOS_DEPTH, ALWAYS),
    interfaces.sub('frequencies', DynamicFrequencies, 'f1, f2 Hz at the current w, at '
                   'their stamp', QOS_DEPTH, ALWAYS),
    interfaces.sub('tip/imu', Imu, "the tip IMU's specific force m/s^2 and angular velocity "
                   "rad/s in its frame (docs/sensors.md)", QOS_DEPTH, ALWAYS),
    interfaces.sub('frequencies/estimate', WhirlEstimate, 'f1, f2 Hz estimated from the '
                   "motion (NaN where not valid), at their stamp: the window's middle",
                   QOS_DEPTH, ALWAYS),
    interfaces.sub('/diagnostics', DiagnosticArray, "the simulator's of this namespace: a "
                   'halt (and its clearing) is an entry in the recording\'s events', QOS_DEPTH),
)
INTERFACES = (*SAMPLES, rod_source.interface('the rod the recording draws'))
EVERY_TICK = ('joint_states', 'tip/deflection', 'tip/position', 'frequencies', 'tip/imu')
"""The topics a simulator publishes at every tick (the others now and then)."""
SIMULATOR = 'rotrod_simulator'
"""The node name whose diagnostics the logger follows (in the logger's namespace)."""


class RerunLogger(Node):
    """Subscribes to a simulator's topics and writes them with :class:`RecordingWriter`."""

    def __init__(self, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        values = parameter_specs.declare(self, PARAMETERS, read_only=READ_ONLY)
        if not values['output']:
            raise ConfigurationError('output must name a file')
        if not values['flush_period'] > 0:
            raise ConfigurationError(f'flush_period must be in (0, 60] s, got '
                                     f'{values["flush_period"]!r}')
        self._values = values
        self._writer: RecordingWriter | None = None
        self._early: deque = deque(maxlen=EARLY_MESSAGES)
        self._subscribe()
        self.get_logger().info(f'subscribed to the simulator\'s topics in '
                               f'{self.get_namespace()}: the recording opens with its rod')
        self.rod = rod_source.RodSource(self, FROM_DESCRIPTION, self._on_description,
                                        'the recording\'s 3D scene')
        if set(rod_source.explicit_values(self, FROM_DESCRIPTION)) == set(FROM_DESCRIPTION):
            self._open(self._mechanism(values, values['disk_radius']))      # all given
        self._timer = self.create_timer(values['flush_period'], self._flush,
                                        clock=Clock(clock_type=ClockType.STEADY_TIME))

    def _subscribe(self) -> None:
        """Subscribe to the simulator's topics.

        Messages that come before the recording opens are kept, then handled in order.
        """
        self._last_stamp: float | None = None
        self._joints: tuple = ((), None)    # (names, indices of hub, tip_radial, tip_tangential)
        self._height_checked = False
        handlers = {'joint_states': self._on_joint, 'tip/deflection': self._on_deflection,
                    'tip/position': self._on_position, 'tip/imu': self._on_imu,
                    'frequencies': lambda m, info: self._on_frequencies(m, info, False),
                    'frequencies/estimate': lambda m, info: self._on_frequencies(m, info,
                                                                                 True),
                    '/diagnostics': self._on_diagnostics}
        # the statuses of the rod: a simulator's own in this namespace, or those of
        # the rod of a world named as this namespace ('/rotrod_simulator: rod3')
        namespace = self.get_namespace().rstrip('/')
        self._simulator = namespace + '/' + SIMULATOR
        self._rod_status = f': {namespace.lstrip("/")}' if namespace else None
        self._halted = 'no'
        self._handlers = [handlers[i.name] for i in SAMPLES]

        def received(index):
            def callback(msg, info):
                if self._writer is None:             # kept until the recording opens
                    self._early.append((index, msg, info))
                    return
                self._handlers[index](msg, info)
                self._take_pending()
            return callback
        io = interfaces.create(self, SAMPLES, {
            i.name: received(k) for k, i in enumerate(SAMPLES)})
        self._topics = [io[i.name] for i in SAMPLES]     # in a tick's order
        pairs = list(zip(self._topics, self._handlers))
        # every tick publishes these: taken in turn; the others (an estimate every
        # tenth tick, diagnostics) are drained after them, which spares a take that
        # finds nothing per tick (each costs about as much as one that finds a message)
        self._every_tick = [p for i, p in zip(SAMPLES, pairs) if i.name in EVERY_TICK]
        self._sometimes = [p for i, p in zip(SAMPLES, pairs) if i.name not in EVERY_TICK]

    @property
    def writer(self) -> RecordingWriter:
        """The recording (opened once the rod is known: the handlers run after that)."""
        assert self._writer is not None
        return self._writer

    @property
    def recording(self) -> bool:
        """Whether the recording is open."""
        return self._writer is not None

    def _mechanism(self, drawn: dict, disk_radius: float) -> Mechanism:
        try:
            return Mechanism(
                eccentricity=float(drawn['eccentricity']),
                rod_length=float(drawn['rod_length']),
                rod_diameter=float(drawn['rod_diameter']),
                mass_radius=sphere_radius(float(drawn['mass'])), disk_radius=disk_radius,
                deflection_scale=self._values['marker_deflection_scale'],
                deflection_limit=float(drawn['deflection_limit']))
        except ValueError as exc:
            raise ConfigurationError(str(exc)) from None

    def _on_description(self, description) -> None:
        """The simulator's rod: open the recording with it (once)."""
        if self.recording:
            return
        given = rod_source.explicit_values(self, ['disk_radius'])
        disk = given.get('disk_radius', description.disk_radius or self._values['disk_radius'])
        p = description.params
        try:
            self._open(self._mechanism({
                'eccentricity': p.eccentricity, 'rod_length': p.rod_length,
                'rod_diameter': p.rod_diameter, 'mass': p.mass,
                'deflection_limit': description.limits.deflection_limit}, disk))
        except ConfigurationError as exc:
            self.get_logger().error(f'cannot draw the rod: {exc}')

    def _open(self, mechanism: Mechanism) -> None:
        """Open the recording with ``mechanism``; handle the messages kept until now."""
        values = self._values
        self.mechanism = mechanism
        on_motion = values['record_from'] == 'motion'
        try:
            self._writer = RecordingWriter(values['output'],
                                           serve_port=values['serve_port'] if values['serve']
                                           else None,
                                           pretrigger=values['pretrigger'] if on_motion
                                           else None, mechanism=self.mechanism,
                                           footer=values['footer'], imu=True)
        except ValueError as exc:
            raise ConfigurationError(str(exc)) from None
        except Exception as exc:  # rerun raises several kinds for a bad path or port
            raise ConfigurationError(f'cannot open the recording: {exc}') from None
        where = f'; serving at {self.writer.serve_uri}' if self.writer.serve_uri else ''
        footer = ('with a footer at the end' if values['footer'] else
                  'without footer (flat memory; footer:=true writes one at the end)')
        self.get_logger().info(f'recording to {self.writer.path}, {footer}{where}')
        if len(self._early) == self._early.maxlen:
            self.get_logger().warning(f'only the last {EARLY_MESSAGES} messages before the '
                                      'rod\'s description are in the recording')
        while self._early:
            index, msg, info = self._early.popleft()
            self._handlers[index](msg, info)

    def _joint_indices(self, names) -> tuple | None:
        """Indices of hub, tip_radial, tip_tangential in ``names`` (cached per name list).

        None without a hub; the tip's (None, None) without tip joints.
        """
        if names != self._joints[0]:
            names = list(names)
            hub = names.index('hub') if 'hub' in names else None
            tips = ((names.index('tip_radial'), names.index('tip_tangential'))
                    if {'tip_radial', 'tip_tangential'} <= set(names) else (None, None))
            self._joints = (names, None if hub is None else (hub, *tips))
        return self._joints[1]

    def _on_joint(self, msg: JointState, info) -> None:
        found = self._joint_indices(msg.name)
        if found is None:
            return
        i, ju, jv = found
        t, omega = to_seconds(msg.header.stamp), msg.velocity[i]
        if self._last_stamp is None:
            self.get_logger().info(f'receiving: first joint state stamped {t:.3f} s')
        self._last_stamp = t
        armed = self.writer.armed
        self.writer.add_state(t, omega, msg.effort[i])
        position = msg.position
        if ju is not None and len(position) > max(i, ju, jv):
            self.writer.add_pose(t, position[i], position[ju], position[jv])
        if armed and not self.writer.armed:
            self.get_logger().info(f'recording: the hub moved at stamp {t:.3f} s; the file '
                                   f'starts {self.writer.pretrigger:g} s before')

    def _on_deflection(self, msg: Vector3Stamped, info) -> None:
        self.writer.add_deflection(to_seconds(msg.header.stamp), msg.vector.x, msg.vector.y)

    def _on_position(self, msg: PointStamped, info) -> None:
        p = msg.point
        self.writer.add_position(to_seconds(msg.header.stamp), p.x, p.y, p.z)
        if not self._height_checked:
            self._height_checked = True
            length = self.mechanism.rod_length
            if not math.isclose(p.z, length, rel_tol=1e-6):
                self.get_logger().warning(
                    f'the mass is at height {p.z:g} m, the rod_length given to the logger '
                    f'is {length:g} m: the 3D scene draws another rod than the simulator\'s '
                    '(give the logger the simulator\'s rod parameters)')

    def _on_imu(self, msg: Imu, info) -> None:
        a, w = msg.linear_acceleration, msg.angular_velocity
        self.writer.add_imu(to_seconds(msg.header.stamp), (a.x, a.y, a.z), (w.x, w.y, w.z))

    def _on_diagnostics(self, msg: DiagnosticArray, info) -> None:
        for status in msg.status:
            if status.hardware_id != self._simulator and not (
                    self._rod_status and status.name.endswith(self._rod_status)):
                continue
            halted = next((kv.value for kv in status.values if kv.key == 'halted'), 'no')
            if halted != self._halted:
                t = to_seconds(msg.header.stamp)
                if halted != 'no':
                    self.writer.event(t, f'halted: {halted}', 'ERROR')
                else:
                    self.writer.event(t, 'the halt is cleared (reset)', 'WARN')
                self._halted = halted

    def _on_frequencies(self, msg: DynamicFrequencies | WhirlEstimate, info,
                        estimate: bool) -> None:
        self.writer.add_frequencies(to_seconds(msg.header.stamp), msg.f1, msg.f2, estimate)

    def _take_pending(self, budget: float = TAKE_BUDGET) -> int:
        """Handle the messages received but not taken yet, for up to ``budget`` s.

        One message per subscription in turn (a tick's order), taken as rclpy's executor
        and ``wait_for_message`` take them (that also works after the shutdown): one
        executor callback then handles a whole burst, where the executor's own
        round per message cost most of the logger's time (py-spy). The topics not
        published every tick (EVERY_TICK) are drained after the others. Returns how many.
        """
        taken = 0
        deadline = time.monotonic() + budget
        while time.monotonic() < deadline:       # the topics every tick publishes, in turn
            progress = False
            for sub, handle in self._every_tick:
                got = interfaces.take(sub)
                if got is not None:
                    handle(got[0], got[1])
                    taken += 1
                    progress = True
            if not progress:
                break
        for sub, handle in self._sometimes:       # then the others, drained, whatever the
            while (got := interfaces.take(sub)) is not None:    # budget (they come far less often)
                handle(got[0], got[1])
                taken += 1
        return taken

    def _flush(self) -> None:
        if not self.recording:
            return
        try:
            self.writer.flush()
        except Exception as exc:  # a slow or failing disk must not end the recording
            self.get_logger().warning(f'writing the recording: {exc}',
                                      throttle_duration_sec=10.0)

    def close(self) -> None:
        """Handle the messages already received, write what is buffered, close the file."""
        if not self.recording:
            self.get_logger().warning('nothing recorded: the simulator\'s robot_description '
                                      'never came (give the drawn parameters to record '
                                      'without it)')
            return
        drained = self._take_pending(budget=CLOSE_BUDGET)
        self.writer.close()
        if drained:
            self.get_logger().info(f'handled {drained} messages received before the end')
        self.get_logger().info(f'wrote {self.writer.samples} samples to {self.writer.path}')


def _parser() -> argparse.ArgumentParser:
    return node_main.parser('rerun_logger', __doc__, [
        *interfaces.help_lines(INTERFACES), 'Parameters:',
        *parameter_specs.help_lines(PARAMETERS, READ_ONLY)])


RERUN_LOG = 'warn,re_log_encoding::rrd::file_sink=error'
"""rerun's log filter in the logger (unless RUST_LOG is set): its file sink warns at
every start without footer, which is this node's default, and the node says so itself."""


def main(args: list | None = None) -> int:
    """Entry point of ``ros2 run rotrod rerun_logger``."""
    os.environ.setdefault('RUST_LOG', RERUN_LOG)      # before rerun is imported
    return node_main.run(NODE_NAME, RerunLogger, _parser(), args, finished=RerunLogger.close)


if __name__ == '__main__':
    sys.exit(main())
