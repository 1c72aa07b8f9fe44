"""rotrod_ros.cdr writes the bytes rclpy's own serialisation writes, byte for byte.

But the alignment padding, which rclpy's leaves as its buffer held it: ours is zero."""

import math

import numpy as np
import pytest
from geometry_msgs.msg import PointStamped, Vector3Stamped
from rclpy.serialization import deserialize_message, serialize_message
from rotrod_interfaces.msg import DynamicFrequencies
from sensor_msgs.msg import JointState

from rotrod_core.model.interface import JOINT_NAMES
from rotrod_ros import cdr, messages

FRAMES = ['', 'a', 'ab', 'abc', 'rotor', 'rod3/rotor', 'world', 'prefix/rod12/rotor',
          'ré/rotor']
"""Every padding after the frame id (lengths 0..9 and more), a multi-byte character."""
SPECIAL = [0.0, -0.0, 1e-300, -5e-324, 1.7976931348623157e308, math.inf, -math.inf]


def same_bytes(raw: bytes, expected: bytes, padding) -> bool:
    """Equal lengths, equal bytes outside ``padding``, zeros in it."""
    pads = set(padding)
    return (len(raw) == len(expected)
            and all(a == b for i, (a, b) in enumerate(zip(raw, expected)) if i not in pads)
            and all(raw[i] == 0 for i in pads))


def values(rng, n):
    return [float(x) for x in rng.normal(size=n) * 10.0 ** rng.integers(-8, 3, size=n)]


@pytest.mark.parametrize('frame', FRAMES)
@pytest.mark.parametrize('msg_type, field', [(Vector3Stamped, 'vector'),
                                             (PointStamped, 'point')])
def test_a_stamped_triple_is_the_serialised_message(frame, msg_type, field):
    rng = np.random.default_rng(len(frame))
    encoder = cdr.StampedTriple(frame)
    for k in range(50):
        sec, nanosec = int(rng.integers(0, 2**31)), int(rng.integers(0, 10**9))
        x, y, z = values(rng, 3) if k else SPECIAL[:3]
        msg = msg_type()
        msg.header.frame_id = frame
        msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
        inner = getattr(msg, field)
        inner.x, inner.y, inner.z = x, y, z
        assert same_bytes(encoder.pack(sec, nanosec, x, y, z), serialize_message(msg),
                          encoder.padding)


def test_dynamic_frequencies_and_a_nan_are_the_serialised_message():
    rng = np.random.default_rng(7)
    encoder = cdr.StampedTriple('')
    for k in range(50):
        omega, f1, f2 = values(rng, 3) if k else (math.nan, 1.0, math.inf)
        msg = messages.frequencies(messages.stamp(12.345), omega, f1, f2)
        raw = encoder.pack(12, msg.header.stamp.nanosec, msg.omega, msg.f1, msg.f2)
        expected = serialize_message(msg)
        if k:
            assert same_bytes(raw, expected, encoder.padding)
        else:   # NaN's bits are the same; what comes back is what went in
            back = deserialize_message(raw, DynamicFrequencies)
            assert math.isnan(back.omega) and (back.f1, back.f2) == (1.0, math.inf)
            assert len(raw) == len(expected)


@pytest.mark.parametrize('names', [JOINT_NAMES, ('hub',), ('a', 'bc', 'def', 'ghij', 'klmno')])
@pytest.mark.parametrize('frame', ['', 'base', 'rod3/base'])
def test_joint_states_are_the_serialised_message(names, frame):
    rng = np.random.default_rng(len(names) + len(frame))
    encoder = cdr.JointStates(names, frame)
    n = len(names)
    for _ in range(30):
        sec, nanosec = int(rng.integers(0, 2**31)), int(rng.integers(0, 10**9))
        position, velocity, effort = values(rng, n), values(rng, n), values(rng, n)
        msg = JointState(name=list(names), position=position, velocity=velocity,
                         effort=effort)
        msg.header.frame_id = frame
        msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
        assert same_bytes(encoder.pack(sec, nanosec, position, velocity, effort),
                          serialize_message(msg), encoder.padding)
        assert deserialize_message(encoder.pack(sec, nanosec, position, velocity, effort),
                                   JointState) == msg


def test_a_joint_state_of_no_joints_reads_back():
    """(rclpy's bytes of it end in 8 bytes its size estimate adds: not compared.)"""
    raw = cdr.JointStates(()).pack(3, 4, (), (), ())
    msg = deserialize_message(raw, JointState)
    assert (msg.header.stamp.sec, msg.header.stamp.nanosec, list(msg.name)) == (3, 4, [])


def test_joint_states_of_the_wrong_length_are_refused():
    encoder = cdr.JointStates(JOINT_NAMES)
    with pytest.raises(ValueError, match='3 joints: got 2 positions'):
        encoder.pack(0, 0, [0.0, 1.0], [0.0] * 3, [0.0] * 3)
