"""rotrod_ros.cdr writes the bytes rclpy's own serialisation writes, byte for byte.

But the alignment padding, which rclpy's leaves as its buffer held it: ours is zero."""

import math

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
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
    n = len(JOINT_NAMES)
    with pytest.raises(ValueError, match=f'{n} joints: got 2 positions'):
        encoder.pack(0, 0, [0.0, 1.0], [0.0] * n, [0.0] * n)


STATUS_TEXTS = ['', 'a', 'ab', 'abc', 'abcd', 'rotrod_simulator: rod3', 'ré', 'deflection 2.98 mm']


@pytest.mark.parametrize('frame', ['', 'a', 'ab', 'abc'])
def test_a_diagnostic_array_is_the_serialised_message(frame):
    """Every padding of each string, several statuses, none, and values of each length."""
    rng = np.random.default_rng(len(frame))
    for n_statuses in (0, 1, 3):
        statuses = []
        for _ in range(n_statuses):
            texts = [STATUS_TEXTS[i] for i in rng.integers(len(STATUS_TEXTS), size=3)]
            values = [(STATUS_TEXTS[i], messages.value_text(float(x)))
                      for i, x in zip(rng.integers(len(STATUS_TEXTS), size=int(rng.integers(5))),
                                      rng.normal(size=5))]
            statuses.append((int(rng.integers(4)), *texts, values))
        sec, nanosec = int(rng.integers(2**31)), int(rng.integers(10**9))
        padding: list = []
        raw = cdr.diagnostic_array(sec, nanosec, statuses, frame, padding)
        msg = DiagnosticArray()
        msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
        msg.header.frame_id = frame
        msg.status = [DiagnosticStatus(level=bytes([level]), name=name, message=message,
                                       hardware_id=hardware_id,
                                       values=[KeyValue(key=k, value=v) for k, v in values])
                      for level, name, message, hardware_id, values in statuses]
        assert same_bytes(raw, serialize_message(msg), padding)
        assert deserialize_message(raw, DiagnosticArray) == msg
