"""bench/publication_floor.py publishes what it stands for: the simulator's four
per-sample topics, with the simulator's types and stamps, every 10 ms on a deadline.

The benches report its CPU as the floor under the simulator's (docs/realtime.md#floor);
a floor that published less, or other types, or slower, would understate it.
"""

import signal
import sys
from pathlib import Path

import numpy as np
import pytest
from node_probes import collect, namespace, stamp

from rotrod_core.model.interface import JOINT_NAMES, ROTOR_FRAME, WORLD_FRAME
from rotrod_ros.simulator import INTERFACES

pytestmark = pytest.mark.ros

FLOOR = Path(__file__).resolve().parents[2] / 'bench' / 'publication_floor.py'
PER_SAMPLE = ('joint_states', 'tip/deflection', 'tip/position', 'frequencies')
"""The topics the simulator publishes with every sample, named here independently of
the floor's own list (rotrod_ros.simulator publishes these four with each sample)."""
PERIOD = 0.01
"""The simulator's default publish period, s (publish_rate 100 Hz)."""


def test_the_floor_publishes_the_simulators_sample_topics_every_10_ms(
        ros_processes, ros_node, request):
    ns = namespace(request)
    types = {i.name: i.type for i in INTERFACES}
    received = {t: collect(ros_node, f'{ns}/{t}', types[t]) for t in PER_SAMPLE}
    floor = ros_processes.start([sys.executable, str(FLOOR), '--ns', ns], name='floor')
    floor.wait_for_output('ready', timeout=30)
    ros_node.spin_until(lambda: all(len(r) >= 150 for r in received.values()), 30,
                        '150 messages on each sample topic')
    floor.signal_group(signal.SIGINT)
    assert floor.wait(timeout=10) == 0
    for topic, rows in received.items():
        stamps = np.array([stamp(m) for m, _, _ in rows])
        source = np.array([s for _, s, _ in rows])
        steps = np.diff(stamps)
        assert np.all(steps > 0), topic
        # on an absolute 10 ms deadline: the median step is the period, and the
        # stamps keep to the grid (no drift over the run)
        assert abs(np.median(steps) - PERIOD) < 5e-4, (topic, np.median(steps))
        span = stamps[-1] - stamps[0]
        assert abs(span / PERIOD - (len(stamps) - 1)) < 3, (topic, span, len(stamps))
        # stamped as it is published (the simulator's stamp is its publication instant)
        assert np.percentile(np.abs(source - stamps), 50) < 5e-3, topic
    # the messages the simulator sends: its joints (3 values each) and its frames
    joints = received['joint_states'][-1][0]
    assert list(joints.name) == list(JOINT_NAMES)
    for field in (joints.position, joints.velocity, joints.effort):
        assert len(field) == len(JOINT_NAMES)
    assert received['tip/deflection'][-1][0].header.frame_id == ROTOR_FRAME
    assert received['tip/position'][-1][0].header.frame_id == WORLD_FRAME


def test_the_floor_refuses_a_rate_that_is_not_a_positive_number(ros_processes):
    started = [(rate, ros_processes.start([sys.executable, str(FLOOR), '--rate', rate],
                                          name=f'floor_{rate}'))
               for rate in ('0', '-100', 'nan', 'inf')]         # together: each imports rclpy
    for rate, proc in started:
        assert proc.wait(timeout=30) == 2, rate
        assert '--rate must be a positive number' in proc.output, proc.output
