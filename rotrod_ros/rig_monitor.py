"""rotrod rig monitor: identifies a rig live from its motion, warns near its critical speed.

Node ``rotrod_rig_monitor``. Relative names, so ``--ros-args -r __ns:=/rod1`` watches
the rod in /rod1, simulated or real.

Subscriptions:
  joint_states    sensor_msgs/JointState       joint 'hub': velocity w, rad/s
  tip/deflection  geometry_msgs/Vector3Stamped (u, v) m in the rotating frame
  Samples are paired on their header stamps (both topics at the same instants).
Publications:
  rig/estimate    std_msgs/Float64MultiArray   every identification (update_rate Hz of
                  the samples' time), one labelled dimension; in order: natural
                  frequency w0 rad/s and its standard deviation, eccentricity r0 m
                  and its std, damping ratio zeta (1) and its std, the quasi-static
                  and sudden-start critical speeds for deflection_limit rad/s, the
                  tip stiffness w0^2 M N/m (M: the nominal modal mass) and its
                  relative deviation from the nominal stiffness (1), the fit's
                  residual m, and the time of the window's last sample s
  /diagnostics    diagnostic_msgs/DiagnosticArray  WARN near the identified critical
                  speed (critical_margin) or with the stiffness off its nominal value
                  (stiffness_tolerance), and before the first estimate (with why)
The nominal rig is given by the same rod parameters as the simulator's (mass, ...,
gravity, rod_density; defaults: the paper's Table 1). The identification itself is
rotrod_core's (docs/identification.md).
"""

from __future__ import annotations

import argparse
import sys

from diagnostic_msgs.msg import DiagnosticArray
from geometry_msgs.msg import Vector3Stamped
from rclpy.exceptions import ParameterException
from rclpy.node import Node
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64MultiArray, MultiArrayDimension

from rotrod_core.estimation.monitor import ESTIMATE_FIELDS, MonitorConfig, RigMonitor

from . import messages, node_main
from .node_main import ConfigurationError
from .parameters import ROD_SPECS, Spec, check_value, descriptor, rod_params

NODE_NAME = 'rotrod_rig_monitor'
QOS_DEPTH = 1000
ESTIMATE_LABEL = ','.join(f'{name}[{unit}]' for name, unit in ESTIMATE_FIELDS)
"""Label of rig/estimate's single dimension: the fields and their units, in order."""

MONITOR_SPECS = (
    Spec('window', 5.0, 'identification window, s of the samples\' time', 0.2, 600.0),
    Spec('sample_interval', 0.01, 'interval between the published samples, s', 1e-5, 10.0),
    Spec('update_rate', 10.0, 'identifications per second of the samples\' time, Hz',
         0.01, 1000.0),
    Spec('deflection_limit', 0.003, 'the critical deflection behind the critical speed, m',
         1e-9, 100.0),
    Spec('critical_margin', 0.1, 'WARN when |w| is within this fraction of the '
         'identified critical speed, 1', 0.0, 0.99),
    Spec('stiffness_tolerance', 0.05, 'WARN when the identified stiffness is off the '
         'nominal one by more than this fraction, 1', 0.0, 0.99),
)
ALL_SPECS = ROD_SPECS + MONITOR_SPECS


class RigMonitorNode(Node):
    """Subscriptions, publications and parameters around :class:`RigMonitor`."""

    def __init__(self, **kwargs):
        super().__init__(NODE_NAME, **kwargs)
        values = {}
        for spec in ALL_SPECS:
            try:
                d = descriptor(spec)
                d.read_only = True
                values[spec.name] = self.declare_parameter(spec.name, spec.default, d).value
                check_value(spec, values[spec.name])
            except (ParameterException, ValueError) as exc:
                raise ConfigurationError(f'parameter {spec.name}: {exc}') from None
        try:
            config = MonitorConfig(
                nominal=rod_params(values), window=values['window'],
                sample_interval=values['sample_interval'],
                update_interval=1.0 / values['update_rate'],
                deflection_limit=values['deflection_limit'],
                critical_margin=values['critical_margin'],
                stiffness_tolerance=values['stiffness_tolerance'])
            self.monitor = RigMonitor(config)
        except ValueError as exc:
            raise ConfigurationError(str(exc)) from None
        self._last_level = None
        self._status_name = f'{self.get_fully_qualified_name()}: rig'
        self._pub_estimate = self.create_publisher(Float64MultiArray, 'rig/estimate', 10)
        self._pub_diagnostics = self.create_publisher(DiagnosticArray, '/diagnostics', 10)
        self.create_subscription(JointState, 'joint_states', self._on_joint, QOS_DEPTH)
        self.create_subscription(Vector3Stamped, 'tip/deflection', self._on_deflection,
                                 QOS_DEPTH)
        self.create_timer(1.0, lambda: self._diagnose(force=True))
        nominal = config.nominal
        self.get_logger().info(
            f'ready: identifying over {config.window:g} s windows; nominal natural '
            f'frequency {float(nominal.natural_frequency):.6g} rad/s, stiffness '
            f'{float(nominal.stiffness):.6g} N/m')

    def _on_joint(self, msg: JointState) -> None:
        if messages.HUB_JOINT not in msg.name:
            return
        i = list(msg.name).index(messages.HUB_JOINT)
        if i >= len(msg.velocity):
            self.get_logger().warning('joint_states without a velocity for the hub: ignored',
                                      throttle_duration_sec=5.0)
            return
        self._take(self.monitor.add_omega, messages.to_seconds(msg.header.stamp),
                   msg.velocity[i])

    def _on_deflection(self, msg: Vector3Stamped) -> None:
        self._take(self.monitor.add_deflection, messages.to_seconds(msg.header.stamp),
                   msg.vector.x, msg.vector.y)

    def _take(self, add, *sample) -> None:
        try:
            estimate = add(*sample)
        except ValueError as exc:          # a malformed sample: reject it, keep the rest
            self.get_logger().warning(f'sample rejected: {exc}', throttle_duration_sec=5.0)
            return
        if estimate is not None:
            msg = Float64MultiArray(data=[float(x) for x in self.monitor.values(estimate)])
            msg.layout.dim = [MultiArrayDimension(label=ESTIMATE_LABEL,
                                                  size=len(ESTIMATE_FIELDS),
                                                  stride=len(ESTIMATE_FIELDS))]
            self._pub_estimate.publish(msg)
            self._diagnose()

    def _diagnose(self, force: bool = False) -> None:
        health = self.monitor.health()
        if not force and health.level == self._last_level:
            return
        self._last_level = health.level
        stamp = self.get_clock().now().to_msg()
        self._pub_diagnostics.publish(messages.diagnostics(
            stamp, self._status_name, self.get_fully_qualified_name(), health.level,
            health.message, health.values))


def _parser() -> argparse.ArgumentParser:
    return argparse.ArgumentParser(
        prog='rig_monitor', description=__doc__.split('\n')[0],
        epilog=__doc__.split('\n', 2)[2] + '\nParameters (read-only):\n' + '\n'.join(
            f'  {s.name}: {s.description} [default {s.default!r}]' for s in ALL_SPECS),
        formatter_class=argparse.RawDescriptionHelpFormatter)


def main(args: list | None = None) -> int:
    """Entry point of ``ros2 run rotrod rig_monitor``."""
    return node_main.run(NODE_NAME, RigMonitorNode, _parser(), args)


if __name__ == '__main__':
    sys.exit(main())
