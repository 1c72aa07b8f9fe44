"""The sample topics' messages as the bytes DDS sends: CDR written from fixed layouts.

rclpy publishes a message by converting the Python object into a C message (a string
is an allocation), serialising that, and writing the bytes. The sample messages of a
rod keep their strings (frame, joint names) for its whole life and change only numbers,
so each has a fixed layout: one ``struct`` packs it, and rclpy publishes the bytes as
they are (``Publisher.publish`` of ``bytes``: what ``ros2 bag play`` does), for about
half the publishing thread's CPU (bench/publish_cost.py, docs/realtime.md#serialised-
samples).

The bytes are what rmw_fastrtps' typesupport writes (``rclpy.serialization
.serialize_message``), byte for byte but the alignment padding (zero here; whatever the
typesupport's buffer held there, which no reader looks at): ROS 2's plain CDR, little
endian (encapsulation CDR_LE, ``00 01 00 00``), every primitive aligned to its size
counted from the first byte after the 4-byte encapsulation, a string as its length with
the terminating NUL (uint32), its bytes and the NUL, a sequence as its count (uint32)
and its elements (test/ros/test_cdr.py compares both over random values and every string
padding).
"""

from __future__ import annotations

import struct
from collections.abc import Sequence

ENCAPSULATION = b'\x00\x01\x00\x00'
"""CDR_LE: plain CDR, little endian, no options."""


class _Layout:
    """A struct format built field by field, with CDR's alignment."""

    def __init__(self) -> None:
        self.format = '<'
        self.size = 0            # bytes after the encapsulation
        self.padding: list[int] = []     # offsets of the alignment bytes, in the message

    def _align(self, n: int) -> None:
        pad = -self.size % n
        if pad:
            self.padding.extend(range(4 + self.size, 4 + self.size + pad))
            self.format += f'{pad}x'
            self.size += pad

    def int32(self, code: str = 'i') -> None:
        self._align(4)
        self.format += code
        self.size += 4

    def string(self, text: str) -> tuple[int, bytes]:
        """A fixed string: its length field and bytes, returned to be packed in place."""
        data = text.encode() + b'\x00'
        self.int32('I')
        self.format += f'{len(data)}s'
        self.size += len(data)
        return len(data), data

    def float64(self, n: int = 1) -> None:
        if not n:                # an empty sequence's elements: no alignment either
            return
        self._align(8)
        self.format += 'd' * n
        self.size += 8 * n

    def header(self, frame_id: str) -> tuple[int, bytes]:
        """std_msgs/Header: stamp (sec int32, nanosec uint32), frame_id; its constants."""
        self.int32('i')
        self.int32('I')
        return self.string(frame_id)

    def struct(self) -> struct.Struct:
        return struct.Struct(self.format)


class StampedTriple:
    """A header of a fixed frame and three float64.

    geometry_msgs/Vector3Stamped and PointStamped, rotrod_interfaces/DynamicFrequencies
    (omega, f1, f2; frame '').
    """

    def __init__(self, frame_id: str) -> None:
        layout = _Layout()
        self._frame = layout.header(frame_id)
        layout.float64(3)
        self._struct = layout.struct()
        self.padding = tuple(layout.padding)
        """Offsets of the alignment bytes (zero here; any value to a reader)."""

    def pack(self, sec: int, nanosec: int, a: float, b: float, c: float) -> bytes:
        """The message's bytes, encapsulation included: stamp (s, ns) and the values."""
        length, data = self._frame
        return ENCAPSULATION + self._struct.pack(sec, nanosec, length, data, a, b, c)


class JointStates:
    """sensor_msgs/JointState of fixed joint names and frame.

    Positions, velocities and efforts, one per joint.
    """

    def __init__(self, names: Sequence[str], frame_id: str = '') -> None:
        layout = _Layout()
        constants: list = list(layout.header(frame_id))
        layout.int32('I')
        constants.append(len(names))
        for name in names:
            constants.extend(layout.string(name))
        self._n = len(names)
        for _ in range(3):
            layout.int32('I')
            layout.float64(self._n)
        self._struct = layout.struct()
        self._constants = tuple(constants)
        self.padding = tuple(layout.padding)
        """Offsets of the alignment bytes (zero here; any value to a reader)."""

    def pack(self, sec: int, nanosec: int, position: Sequence[float],
             velocity: Sequence[float], effort: Sequence[float]) -> bytes:
        """The message's bytes: stamp (s, ns) and one value per joint in each array."""
        n = self._n
        if not len(position) == len(velocity) == len(effort) == n:
            raise ValueError(f'JointState of {n} joints: got {len(position)} positions, '
                             f'{len(velocity)} velocities, {len(effort)} efforts')
        return ENCAPSULATION + self._struct.pack(sec, nanosec, *self._constants,
                                                 n, *position, n, *velocity, n, *effort)


_UINT32 = struct.Struct('<I')
_STAMP = struct.Struct('<iI')


def _align4(out: bytearray, padding: list | None) -> None:
    """Pad ``out`` to a multiple of 4 after the encapsulation (its 4 bytes keep it so)."""
    pad = -len(out) % 4
    if pad:
        if padding is not None:
            padding.extend(range(len(out), len(out) + pad))
        out += bytes(pad)


def _string(out: bytearray, text: str, padding: list | None) -> None:
    data = text.encode()
    _align4(out, padding)
    out += _UINT32.pack(len(data) + 1)
    out += data
    out += b'\x00'


def diagnostic_array(sec: int, nanosec: int, statuses: Sequence[tuple],
                     frame_id: str = '', padding: list | None = None) -> bytes:
    """diagnostic_msgs/DiagnosticArray's bytes, encapsulation included.

    Its length and strings vary, so it is written field by field (~30 us for a rod's
    status of 24 values, against ~150 us to build the message and have rclpy serialise
    it: a world of rods reports a status per rod each second).

    Args:
        sec, nanosec: the header's stamp.
        statuses: each (level, name, message, hardware_id, values): level an int 0-3
            (the status's byte), values (key, value) pairs of strings.
        frame_id: the header's frame.
        padding: if a list, the offsets of the alignment bytes are added to it.
    """
    out = bytearray(ENCAPSULATION)
    out += _STAMP.pack(sec, nanosec)
    _string(out, frame_id, padding)
    _align4(out, padding)
    out += _UINT32.pack(len(statuses))
    for level, name, message, hardware_id, values in statuses:
        out.append(level)                      # a byte: aligned to 1
        _string(out, name, padding)
        _string(out, message, padding)
        _string(out, hardware_id, padding)
        _align4(out, padding)
        out += _UINT32.pack(len(values))
        for key, value in values:
            _string(out, key, padding)
            _string(out, value, padding)
    return bytes(out)


__all__ = ['ENCAPSULATION', 'JointStates', 'StampedTriple', 'diagnostic_array']
