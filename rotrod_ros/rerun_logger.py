"""rotrod Rerun logger: records the simulator's topics to a Rerun file, headlessly.

Node ``rotrod_rerun_logger``. Subscribes (relative names) to joint_states,
tip/deflection, tip/position, frequencies and frequencies/estimate, and writes
``output`` (a .rrd file) with time on the message stamps and a default blueprint,
so the file opens as a dashboard: ``rerun rotrod.rrd``. With ``serve:=true`` it also
serves the recording live on 127.0.0.1:``serve_port`` (``rerun --connect``). With
``record_from:=motion`` it keeps only the last ``pretrigger`` seconds until the hub's
angular velocity first changes: the file begins just before the motion, not when the
logger started.

Data is written in batches every ``flush_period`` seconds. On SIGINT, SIGTERM or the
end of the run the messages already received but not yet handled are taken too, the
last batch is written and the file closed, so ``rerun rrd verify`` accepts it and it
holds every message received up to the signal. Killed outright (SIGKILL), the logger
leaves a file without footer holding everything up to its last write, at most
``flush_period`` old: it loads with ``RrdReader(path).stream()`` and
``rerun rrd optimize FILE -o COPY`` makes a complete copy of it.
"""

from __future__ import annotations

import argparse
import sys

from geometry_msgs.msg import PointStamped, Vector3Stamped
from rcl_interfaces.msg import ParameterDescriptor
from rclpy.clock import Clock, ClockType
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray

from rotrod_core.reporting.recording import RecordingWriter

from . import node_main
from .messages import to_seconds
from .node_main import ConfigurationError

NODE_NAME = 'rotrod_rerun_logger'
QOS_DEPTH = 1000
"""Subscription queue depth: a burst of publications is not dropped."""

PARAMETERS = (
    ('output', 'rotrod.rrd', 'path of the Rerun recording to write'),
    ('serve', False, 'also serve the recording live on 127.0.0.1 (rerun --connect)'),
    ('serve_port', 9876, 'TCP port of the live server (127.0.0.1 only)'),
    ('flush_period', 0.25, 'seconds of wall time between writes of the buffered data'),
    ('record_from', 'start', 'start: record from the first message; motion: keep only '
     'the last pretrigger seconds until the hub\'s angular velocity first differs from '
     'the first one received, then record everything (the file begins just before the '
     'motion, not when the logger started)'),
    ('pretrigger', 0.5, 'with record_from motion: seconds of stamp time kept from before '
     'the hub first moved (>= 0)'),
)
RECORD_FROM = ('start', 'motion')


class RerunLogger(Node):
    """Subscribes to a simulator's topics and writes them with :class:`RecordingWriter`."""

    def __init__(self, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        values = {name: self.declare_parameter(
            name, default, ParameterDescriptor(description=text, read_only=True)).value
            for name, default, text in PARAMETERS}
        if not values['output']:
            raise ConfigurationError('output must name a file')
        if not 0 < values['flush_period'] <= 60:
            raise ConfigurationError(f'flush_period must be in (0, 60] s, got '
                                     f'{values["flush_period"]!r}')
        if not 0 < values['serve_port'] < 65536:
            raise ConfigurationError(f'serve_port must be a TCP port, got {values["serve_port"]}')
        if values['record_from'] not in RECORD_FROM:
            raise ConfigurationError(f'record_from must be one of {RECORD_FROM}, got '
                                     f'{values["record_from"]!r}')
        on_motion = values['record_from'] == 'motion'
        try:
            self.writer = RecordingWriter(values['output'],
                                          serve_port=values['serve_port'] if values['serve']
                                          else None,
                                          pretrigger=values['pretrigger'] if on_motion
                                          else None)
        except ValueError as exc:
            raise ConfigurationError(str(exc)) from None
        except Exception as exc:  # rerun raises several kinds for a bad path or port
            raise ConfigurationError(f'cannot open the recording: {exc}') from None
        self._last_stamp: float | None = None
        self._omega_at_rest = 0.0
        self._topics = [   # in the order a tick publishes them (see _drain)
            self.create_subscription(JointState, 'joint_states', self._on_joint, QOS_DEPTH),
            self.create_subscription(Vector3Stamped, 'tip/deflection', self._on_deflection,
                                     QOS_DEPTH),
            self.create_subscription(PointStamped, 'tip/position', self._on_position,
                                     QOS_DEPTH),
            self.create_subscription(Float64MultiArray, 'frequencies',
                                     lambda m: self._on_frequencies(m, False), QOS_DEPTH),
            self.create_subscription(Float64MultiArray, 'frequencies/estimate',
                                     lambda m: self._on_frequencies(m, True), QOS_DEPTH),
        ]
        self._timer = self.create_timer(values['flush_period'], self._flush,
                                        clock=Clock(clock_type=ClockType.STEADY_TIME))
        where = f'; serving at {self.writer.serve_uri}' if self.writer.serve_uri else ''
        self.get_logger().info(f'recording to {self.writer.path}{where}')

    def _on_joint(self, msg: JointState) -> None:
        if 'hub' not in msg.name:
            return
        i = list(msg.name).index('hub')
        t, omega = to_seconds(msg.header.stamp), msg.velocity[i]
        if self._last_stamp is None:
            self.get_logger().info(f'receiving: first joint state stamped {t:.3f} s')
            self._omega_at_rest = omega
        self._last_stamp = t
        self.writer.add_state(t, omega, msg.effort[i])
        if self.writer.armed and omega != self._omega_at_rest:
            self.writer.trigger()
            self.get_logger().info(f'recording: the hub moved at stamp {t:.3f} s; the file '
                                   f'starts {self.writer.pretrigger:g} s before')

    def _on_deflection(self, msg: Vector3Stamped) -> None:
        self.writer.add_deflection(to_seconds(msg.header.stamp), msg.vector.x, msg.vector.y)

    def _on_position(self, msg: PointStamped) -> None:
        p = msg.point
        self.writer.add_position(to_seconds(msg.header.stamp), p.x, p.y, p.z)

    def _on_frequencies(self, msg: Float64MultiArray, estimate: bool) -> None:
        # Float64MultiArray has no stamp: it is published with the joint state of the
        # same instant, so it takes that stamp.
        if self._last_stamp is None or len(msg.data) < 2:
            return
        self.writer.add_frequencies(self._last_stamp, msg.data[0], msg.data[1], estimate)

    def _flush(self) -> None:
        try:
            self.writer.flush()
        except Exception as exc:  # a slow or failing disk must not end the recording
            self.get_logger().warning(f'writing the recording: {exc}',
                                      throttle_duration_sec=10.0)

    def _drain(self) -> int:
        """Handle the messages received but not taken yet; return how many.

        A signal stops the executor at once, possibly with the last tick's messages
        still queued: they were received before the signal, so they belong in the file.
        One message per subscription in turn keeps each tick's messages together (the
        frequencies take the stamp of the joint state before them). Taken as rclpy's
        executor and ``wait_for_message`` take them, which works after the shutdown.
        """
        taken = 0
        for _ in range(QOS_DEPTH):
            progress = False
            for sub in self._topics:
                try:
                    with sub.handle:
                        got = sub.handle.take_message(sub.msg_type, sub.raw)
                except Exception:  # the subscription or its context is gone
                    got = None
                if got is not None:
                    sub.callback(got[0])
                    taken += 1
                    progress = True
            if not progress:
                break
        return taken

    def close(self) -> None:
        """Handle the messages already received, write what is buffered, close the file."""
        drained = self._drain()
        self.writer.close()
        if drained:
            self.get_logger().info(f'handled {drained} messages received before the end')
        self.get_logger().info(f'wrote {self.writer.samples} samples to {self.writer.path}')


def _parser() -> argparse.ArgumentParser:
    return argparse.ArgumentParser(
        prog='rerun_logger', description=__doc__.split('\n')[0],
        epilog=__doc__.split('\n', 2)[2] + '\nParameters:\n' + '\n'.join(
            f'  {n}: {d} [default {v!r}]' for n, v, d in PARAMETERS),
        formatter_class=argparse.RawDescriptionHelpFormatter)


def main(args: list | None = None) -> int:
    """Entry point of ``ros2 run rotrod rerun_logger``."""
    return node_main.run(NODE_NAME, RerunLogger, _parser(), args, finished=RerunLogger.close)


if __name__ == '__main__':
    sys.exit(main())
