"""Building the simulator's ROS messages from core values (SI units in, SI units out)."""

from __future__ import annotations

from collections.abc import Iterable, Sequence

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Point, PointStamped, Vector3Stamped
from rosgraph_msgs.msg import Clock
from sensor_msgs.msg import JointState
from std_msgs.msg import ColorRGBA, Float64MultiArray, Header, MultiArrayDimension
from visualization_msgs.msg import Marker, MarkerArray

from rotrod_core.model import interface
from rotrod_core.model.interface import FREQUENCY_LABEL, JOINT_NAMES, joint_values, stamp_parts
from rotrod_core.model.scene import TRAIL_ID, scene

HUB_JOINT = interface.HUB_JOINT
"""The hub's joint name in joint_states (the nodes that read it look it up by name)."""


def stamp(seconds: float) -> Time:
    """builtin_interfaces/Time for a time in seconds (>= 0)."""
    sec, nanosec = stamp_parts(seconds)
    return Time(sec=sec, nanosec=nanosec)


def to_seconds(t: Time) -> float:
    """Seconds of a builtin_interfaces/Time."""
    return t.sec + t.nanosec * 1e-9


def header(t: Time, frame_id: str = '') -> Header:
    """A std_msgs/Header."""
    return Header(stamp=t, frame_id=frame_id)


def joint_state(t: Time, state, torque: float) -> JointState:
    """The joints of the URDF (:data:`JOINT_NAMES`) for a state; ``torque`` in N m.

    hub: theta rad, w rad/s, hub torque N m; tip_radial, tip_tangential: u, v m and
    u', v' m/s, effort 0 (passive). See :func:`rotrod_core.model.interface.joint_values`.
    """
    position, velocity, effort = joint_values(state, torque)
    return JointState(header=header(t), name=list(JOINT_NAMES), position=position,
                      velocity=velocity, effort=effort)


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


_TRAIL_POINTS: dict = {}
"""geometry_msgs/Point of recent trail positions, by (x, y, z): a trail point is drawn
in every marker array until it leaves the trail, and making a Point costs more than
finding one (py-spy: the markers were a fifth of the node's CPU)."""
_MAX_TRAIL_POINTS = 20000


def _trail_points(xyz) -> list:
    cache = _TRAIL_POINTS
    if len(cache) > _MAX_TRAIL_POINTS:
        cache.clear()
    out = []
    for p in xyz:
        point = cache.get(p)
        if point is None:
            point = cache[p] = Point(x=p[0], y=p[1], z=p[2])
        out.append(point)
    return out


def markers(t: Time, frame_id: str, ns: str, *, disk_radius: float, theta: float,
            rod: Sequence[Sequence[float]], rod_diameter: float, mass_radius: float,
            trail: Iterable[Sequence[float]]) -> MarkerArray:
    """Disk (with a radial line at the rod's root, which turns with it), rod, mass, trail.

    ``rod`` is the drawn centreline (root to tip, m, frame ``frame_id``); ``trail`` the
    recent drawn tip positions. The shapes are :func:`rotrod_core.model.scene.scene`'s.
    """
    h = header(t, frame_id)
    out = []
    for shape in scene(disk_radius=disk_radius, theta=theta, rod=rod,
                       rod_diameter=rod_diameter, mass_radius=mass_radius, trail=trail):
        m = Marker(header=h, ns=ns, id=shape.id, type=getattr(Marker, shape.kind.upper()),
                   action=Marker.ADD)
        m.pose.position = Point(x=shape.position[0], y=shape.position[1],
                                z=shape.position[2])
        m.pose.orientation.w = 1.0
        m.scale.x, m.scale.y, m.scale.z = shape.scale
        m.color = ColorRGBA(r=shape.color[0], g=shape.color[1], b=shape.color[2],
                            a=shape.color[3])
        m.points = (_trail_points(shape.points) if shape.id == TRAIL_ID else
                    [Point(x=x, y=y, z=z) for x, y, z in shape.points])
        out.append(m)
    return MarkerArray(markers=out)
