"""Building the simulator's ROS messages from core values (SI units in, SI units out)."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Point, PointStamped, Vector3Stamped
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import ColorRGBA, Float64MultiArray, Header, MultiArrayDimension
from visualization_msgs.msg import Marker, MarkerArray

HUB_JOINT = 'hub'
FREQUENCY_LABEL = 'f1_f2_hz'
"""Label of the single dimension of ``frequencies``: [f1, f2] in Hz, f1 <= f2."""


def stamp(seconds: float) -> Time:
    """builtin_interfaces/Time for a time in seconds (>= 0)."""
    sec = math.floor(seconds)
    nanosec = int(round((seconds - sec) * 1e9))
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    return Time(sec=int(sec), nanosec=nanosec)


def to_seconds(t: Time) -> float:
    """Seconds of a builtin_interfaces/Time."""
    return t.sec + t.nanosec * 1e-9


def header(t: Time, frame_id: str = '') -> Header:
    """A std_msgs/Header."""
    return Header(stamp=t, frame_id=frame_id)


def joint_state(t: Time, theta: float, omega: float, torque: float) -> JointState:
    """The hub joint: position theta (rad), velocity w (rad/s), effort Q (N m)."""
    return JointState(header=header(t), name=[HUB_JOINT], position=[float(theta)],
                      velocity=[float(omega)], effort=[float(torque)])


def deflection(t: Time, u: float, v: float, frame_id: str) -> Vector3Stamped:
    """Tip deflection (u, v, 0) in m, in the rotating frame ``frame_id``."""
    msg = Vector3Stamped(header=header(t, frame_id))
    msg.vector.x, msg.vector.y, msg.vector.z = float(u), float(v), 0.0
    return msg


def position(t: Time, xyz: Sequence[float], frame_id: str) -> PointStamped:
    """Position of the mass in m, in the inertial frame ``frame_id``."""
    return PointStamped(header=header(t, frame_id),
                        point=Point(x=float(xyz[0]), y=float(xyz[1]), z=float(xyz[2])))


def frequencies(f1: float, f2: float) -> Float64MultiArray:
    """[f1, f2] in Hz, one labelled dimension."""
    msg = Float64MultiArray(data=[float(f1), float(f2)])
    msg.layout.dim = [MultiArrayDimension(label=FREQUENCY_LABEL, size=2, stride=2)]
    return msg


def clock(t: Time) -> Clock:
    """rosgraph_msgs/Clock."""
    return Clock(clock=t)


def diagnostics(t: Time, name: str, hardware_id: str, level: int, message: str,
                values: Iterable[tuple]) -> DiagnosticArray:
    """A DiagnosticArray with one status; values are written as text (floats to 6 digits)."""
    kv = [KeyValue(key=str(k), value=f'{v:.6g}' if isinstance(v, float) else str(v))
          for k, v in values]
    status = DiagnosticStatus(level=bytes([level]), name=name, message=message,
                              hardware_id=hardware_id, values=kv)
    return DiagnosticArray(header=header(t), status=[status])


def _color(r: float, g: float, b: float, a: float = 1.0) -> ColorRGBA:
    return ColorRGBA(r=r, g=g, b=b, a=a)


def _points(rows) -> list:
    return [Point(x=float(x), y=float(y), z=float(z)) for x, y, z in rows]


def markers(t: Time, frame_id: str, ns: str, *, disk_radius: float, theta: float,
            rod: Sequence[Sequence[float]], rod_diameter: float, mass_radius: float,
            trail: Iterable[Sequence[float]]) -> MarkerArray:
    """Disk (with a radial line at the rod's root, which turns with it), rod, mass, trail.

    ``rod`` is the drawn centreline (root to tip, m, frame ``frame_id``); ``trail`` the
    recent drawn tip positions.
    """
    h = header(t, frame_id)
    disk = Marker(header=h, ns=ns, id=0, type=Marker.CYLINDER, action=Marker.ADD)
    disk.pose.position.z = -0.005
    disk.pose.orientation.w = 1.0
    disk.scale.x = disk.scale.y = 2.0 * disk_radius
    disk.scale.z = 0.01
    disk.color = _color(0.6, 0.6, 0.65)
    spoke = Marker(header=h, ns=ns, id=1, type=Marker.LINE_LIST, action=Marker.ADD)
    spoke.pose.orientation.w = 1.0
    spoke.scale.x = 0.004
    spoke.color = _color(0.15, 0.15, 0.2)
    spoke.points = _points([(0.0, 0.0, 0.001),
                            (disk_radius * math.cos(theta), disk_radius * math.sin(theta),
                             0.001)])
    rod_m = Marker(header=h, ns=ns, id=2, type=Marker.LINE_STRIP, action=Marker.ADD)
    rod_m.pose.orientation.w = 1.0
    rod_m.scale.x = max(rod_diameter, 0.002)
    rod_m.color = _color(0.2, 0.4, 0.9)
    rod_m.points = _points(rod)
    mass = Marker(header=h, ns=ns, id=3, type=Marker.SPHERE, action=Marker.ADD)
    tip = rod[-1]
    mass.pose.position = Point(x=float(tip[0]), y=float(tip[1]), z=float(tip[2]))
    mass.pose.orientation.w = 1.0
    mass.scale.x = mass.scale.y = mass.scale.z = 2.0 * mass_radius
    mass.color = _color(0.9, 0.3, 0.1)
    trail_m = Marker(header=h, ns=ns, id=4, type=Marker.LINE_STRIP, action=Marker.ADD)
    trail_m.pose.orientation.w = 1.0
    trail_m.scale.x = 0.002
    trail_m.color = _color(0.9, 0.6, 0.1, 0.8)
    trail_m.points = _points(trail)
    out = [disk, spoke, rod_m, mass]
    if len(trail_m.points) >= 2:
        out.append(trail_m)
    return MarkerArray(markers=out)
