"""rotrod rig monitor: identifies a rig live from its motion, warns near its critical speed.

Node ``rotrod_rig_monitor``: topics below (INTERFACES), parameters after them, all set
at start; docs/nodes.md lists the same. Relative names, so ``--ros-args -r
__ns:=/rod1`` watches the rod in /rod1, simulated or real. The tip is measured by
tip/deflection or, with ``tip_sensor: imu``, by the IMU on the tip mass (tip/imu's
horizontal specific force); the hub by joint_states' velocity or, with ``hub_sensor:
encoder``, by hub/encoder's angle. Samples are paired on their header stamps (the
topics at the same instants).
The nominal rig is the simulator's rod, read from its ``robot_description``
(:mod:`rotrod_ros.rod_source`; a rod parameter given here overrides that field, with a
warning naming it): the monitor starts identifying once it has it. The identification
itself is rotrod_core's (docs/identification.md).
"""

from __future__ import annotations

import argparse
import sys

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Vector3Stamped
from rclpy.node import Node
from rotrod_interfaces.msg import RigEstimate
from sensor_msgs.msg import Imu, JointState

from rotrod_core.estimation.monitor import MonitorConfig, RigMonitor
from rotrod_core.model.params import RodParams

from . import interfaces, messages, node_main, parameter_specs, rod_source
from .interfaces import pub, sub
from .node_main import ConfigurationError
from .parameter_specs import Spec
from .parameters import ROD_SPECS

NODE_NAME = 'rotrod_rig_monitor'
QOS_DEPTH = 1000

MONITOR_SPECS = (
    Spec('window', 5.0, 'identification window, of the samples\' time', 's', 0.2, 600.0),
    Spec('sample_interval', 0.01, 'interval between the published samples', 's',
         1e-5, 10.0),
    Spec('update_rate', 10.0, 'identifications per second of the samples\' time', 'Hz',
         0.01, 1000.0),
    Spec('deflection_limit', 0.003, 'the critical deflection behind the critical speed; '
         "not given: the simulator's (robot_description)", 'm', 1e-9, 100.0),
    Spec('critical_margin', 0.1, 'WARN when |w| is within this fraction of the '
         'identified critical speed', '1', 0.0, 0.99),
    Spec('stiffness_tolerance', 0.05, 'WARN when the identified stiffness is off the '
         'nominal one by more than this fraction', '1', 0.0, 0.99),
    Spec('tip_sensor', 'deflection', "what measures the tip: deflection (tip/deflection's "
         "(u, v), m) | imu (tip/imu's linear acceleration x, y, m/s^2: a real rig's "
         "accelerometer, its tilt and radius from the nominal rig's gravity, rod length "
         'and masses; a constant bias is fitted)', choices=('deflection', 'imu')),
    Spec('hub_sensor', 'joint_states', "what measures the hub: joint_states (its 'hub' "
         "velocity, rad/s) | encoder (hub/encoder's angle, rad: w and w' from a quadratic "
         'fit over angle_smoothing; evenly spaced samples)',
         choices=('joint_states', 'encoder')),
    Spec('angle_smoothing', 0.2, "span of the fit of w and w' to the encoder's angle "
         '(hub_sensor encoder; at least 5 samples)', 's', 1e-4, 10.0),
)
ALL_SPECS = ROD_SPECS + MONITOR_SPECS
READ_ONLY = True
"""The monitor's parameters are set at start only."""

TOPIC_CHOICES = {'tip_sensor': {'deflection': 'tip/deflection', 'imu': 'tip/imu'},
                 'hub_sensor': {'joint_states': 'joint_states', 'encoder': 'hub/encoder'}}
"""The topic each choice of tip_sensor and hub_sensor subscribes to (the others' are
not subscribed)."""

INTERFACES = (
    sub('joint_states', JointState, "joint 'hub': velocity w, rad/s (hub_sensor "
        'joint_states)', QOS_DEPTH),
    sub('hub/encoder', JointState, "joint 'hub': the encoder's angle, rad, and speed, "
        'rad/s (hub_sensor encoder)', QOS_DEPTH),
    sub('tip/deflection', Vector3Stamped, '(u, v) m in the rotating frame (tip_sensor '
        'deflection)', QOS_DEPTH),
    sub('tip/imu', Imu, 'linear_acceleration x, y, m/s^2, in the tip frame (tip_sensor '
        'imu)', QOS_DEPTH),
    pub('rig/estimate', RigEstimate, 'every identification (update_rate Hz of the '
        "samples' time), stamped at the window's last sample: w0 rad/s, r0 m, zeta and "
        'their standard deviations, the quasi-static and sudden-start critical speeds for '
        'deflection_limit rad/s, the tip stiffness w0^2 M N/m and its relative deviation '
        'from the nominal one, the residual m (m/s^2 from the IMU), the window s'),
    pub('/diagnostics', DiagnosticArray, 'WARN near the identified critical speed '
        '(critical_margin), with the stiffness off its nominal value '
        '(stiffness_tolerance), and before the first estimate (with why)'),
    rod_source.interface('the nominal rig'),
)


class RigMonitorNode(Node):
    """Subscriptions, publications and parameters around :class:`RigMonitor`."""

    def __init__(self, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        values = parameter_specs.declare(self, ALL_SPECS, read_only=READ_ONLY)
        self._values = values
        try:        # the monitor's own settings, checked now on Table 1's rod
            RigMonitor(self._config(RodParams(), values['deflection_limit']))
        except ValueError as exc:
            raise ConfigurationError(str(exc)) from None
        self.monitor: RigMonitor | None = None
        self._last_level = None
        self._status_name = f'{self.get_fully_qualified_name()}: rig'
        topics = [choices[values[name]] for name, choices in TOPIC_CHOICES.items()]
        callbacks = {'joint_states': self._on_joint, 'hub/encoder': self._on_joint,
                     'tip/deflection': self._on_deflection, 'tip/imu': self._on_imu}
        io = interfaces.create(self, [i for i in INTERFACES if i.name in topics
                                      or i.kind != interfaces.SUBSCRIPTION],
                               {topic: callbacks[topic] for topic in topics})
        self._pub_estimate, self._pub_diagnostics = io['rig/estimate'], io['/diagnostics']
        self.create_timer(1.0, lambda: self._diagnose(force=True))
        self.rod = rod_source.RodSource(self, [s.name for s in ROD_SPECS] + ['deflection_limit'],
                                        self._on_description, 'the nominal rig')

    def _config(self, nominal: RodParams, deflection_limit: float) -> MonitorConfig:
        values = self._values
        return MonitorConfig(
            nominal=nominal, window=values['window'],
            sample_interval=values['sample_interval'],
            update_interval=1.0 / values['update_rate'], deflection_limit=deflection_limit,
            critical_margin=values['critical_margin'],
            stiffness_tolerance=values['stiffness_tolerance'],
            measurement='acceleration' if values['tip_sensor'] == 'imu' else 'deflection',
            hub='angle' if values['hub_sensor'] == 'encoder' else 'omega',
            angle_smoothing=values['angle_smoothing'])

    def _on_description(self, description) -> None:
        """The simulator's rod (or a change of it): identify against it, from scratch."""
        try:
            config = self._config(description.params, description.limits.deflection_limit)
            self.monitor = RigMonitor(config)
        except ValueError as exc:
            self.get_logger().error(f'cannot monitor this rod: {exc}')
            return
        nominal = config.nominal
        self.get_logger().info(
            f'ready: identifying over {config.window:g} s windows; nominal natural '
            f'frequency {float(nominal.natural_frequency_radial):.6g} rad/s, stiffness '
            f'{float(nominal.stiffness_radial):.6g} N/m')

    def _on_joint(self, msg: JointState) -> None:
        if messages.HUB_JOINT not in msg.name:
            return
        if self.monitor is None:
            return
        i = list(msg.name).index(messages.HUB_JOINT)
        t = messages.to_seconds(msg.header.stamp)
        if self.monitor.config.hub == 'angle':
            if i >= len(msg.position):
                self.get_logger().warning('hub/encoder without a position for the hub: '
                                          'ignored', throttle_duration_sec=5.0)
                return
            speed = msg.velocity[i] if i < len(msg.velocity) else None
            self._take(self.monitor.add_angle, t, msg.position[i], speed)
            return
        if i >= len(msg.velocity):
            self.get_logger().warning('joint_states without a velocity for the hub: ignored',
                                      throttle_duration_sec=5.0)
            return
        self._take(self.monitor.add_omega, t, msg.velocity[i])

    def _on_deflection(self, msg: Vector3Stamped) -> None:
        if self.monitor is None:
            return
        self._take(self.monitor.add_deflection, messages.to_seconds(msg.header.stamp),
                   msg.vector.x, msg.vector.y)

    def _on_imu(self, msg: Imu) -> None:
        if self.monitor is None:
            return
        self._take(self.monitor.add_acceleration, messages.to_seconds(msg.header.stamp),
                   msg.linear_acceleration.x, msg.linear_acceleration.y)

    def _take(self, add, *sample) -> None:
        try:
            estimate = add(*sample)
        except ValueError as exc:          # a malformed sample: reject it, keep the rest
            self.get_logger().warning(f'sample rejected: {exc}', throttle_duration_sec=5.0)
            return
        if estimate is not None:
            self._pub_estimate.publish(messages.rig_estimate(self.monitor, estimate))
            self._diagnose()

    def _diagnose(self, force: bool = False) -> None:
        if self.monitor is None:
            return
        health = self.monitor.health()
        if not force and health.level == self._last_level:
            return
        self._last_level = health.level
        stamp = self.get_clock().now().to_msg()
        self._pub_diagnostics.publish(messages.diagnostics(
            stamp, self._status_name, self.get_fully_qualified_name(), health.level,
            health.message, health.values))


def _parser() -> argparse.ArgumentParser:
    return node_main.parser('rig_monitor', __doc__, [
        *interfaces.help_lines(INTERFACES), 'Parameters:',
        *parameter_specs.help_lines(ALL_SPECS, READ_ONLY)])


def main(args: list | None = None) -> int:
    """Entry point of ``ros2 run rotrod rig_monitor``."""
    return node_main.run(NODE_NAME, RigMonitorNode, _parser(), args)


if __name__ == '__main__':
    sys.exit(main())
