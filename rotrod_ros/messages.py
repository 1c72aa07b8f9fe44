"""Building the simulator's ROS messages from core values (SI units in, SI units out)."""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence

from builtin_interfaces.msg import Time
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from geometry_msgs.msg import Point, PointStamped, Vector3Stamped, WrenchStamped
from rosgraph_msgs.msg import Clock
from rotrod_interfaces.msg import DynamicFrequencies, RigEstimate, WhirlEstimate
from sensor_msgs.msg import Imu, JointState
from std_msgs.msg import ColorRGBA, Header
from visualization_msgs.msg import Marker, MarkerArray

from rotrod_core.model import interface
from rotrod_core.model.interface import (
    JOINT_NAMES,
    frequency_fields,
    joint_values,
    stamp_parts,
    whirl_fields,
)
from rotrod_core.model.scene import TRAIL_ID, Shape, scene

from . import cdr

HUB_JOINT = interface.HUB_JOINT
"""The hub's joint name in joint_states (the nodes that read it look it up by name)."""


def stamp(seconds: float) -> Time:
    """builtin_interfaces/Time for a time in seconds (>= 0)."""
    sec, nanosec = stamp_parts(seconds)
    return Time(sec=sec, nanosec=nanosec)


def yaw_quaternion(yaw: float) -> tuple[float, float, float, float]:
    """(x, y, z, w) of the rotation by ``yaw`` rad about z."""
    half = 0.5 * yaw
    return 0.0, 0.0, math.sin(half), math.cos(half)


def to_seconds(t: Time) -> float:
    """Seconds of a builtin_interfaces/Time."""
    return t.sec + t.nanosec * 1e-9


def header(t: Time, frame_id: str = '') -> Header:
    """A std_msgs/Header."""
    return Header(stamp=t, frame_id=frame_id)


def joint_state(t: Time, state, torque: float, rod_length: float) -> JointState:
    """The joints of the URDF (:data:`JOINT_NAMES`) for a state; ``torque`` in N m.

    hub: theta rad, w rad/s, hub torque N m; tip_radial, tip_tangential: u, v m and
    u', v' m/s; tip_pitch, tip_roll: the tip's tilt a, -b rad and their rates (for a rod
    of ``rod_length`` m); the tip joints' effort 0 (passive). See
    :func:`rotrod_core.model.interface.joint_values`.
    """
    return set_joint_state(JointState(name=list(JOINT_NAMES)), t, state, torque, rod_length)


def set_joint_state(msg: JointState, t: Time, state, torque: float,
                    rod_length: float) -> JointState:
    """:func:`joint_state` written into ``msg`` (made with ``name`` :data:`JOINT_NAMES`)."""
    msg.header.stamp = t
    msg.position, msg.velocity, msg.effort = joint_values(state, torque, rod_length)
    return msg


def deflection(t: Time, u: float, v: float, frame_id: str) -> Vector3Stamped:
    """Tip deflection (u, v, 0) in m, in the rotating frame ``frame_id``."""
    return set_deflection(Vector3Stamped(header=header(t, frame_id)), t, u, v)


def set_deflection(msg: Vector3Stamped, t: Time, u: float, v: float) -> Vector3Stamped:
    """:func:`deflection` written into ``msg`` (its frame kept)."""
    msg.header.stamp = t
    vector = msg.vector
    vector.x, vector.y, vector.z = float(u), float(v), 0.0
    return msg


def position(t: Time, xyz: Sequence[float], frame_id: str) -> PointStamped:
    """Position of the mass in m, in the inertial frame ``frame_id``."""
    return set_position(PointStamped(header=header(t, frame_id)), t, xyz)


def set_position(msg: PointStamped, t: Time, xyz: Sequence[float]) -> PointStamped:
    """:func:`position` written into ``msg`` (its frame kept)."""
    msg.header.stamp = t
    point = msg.point
    point.x, point.y, point.z = float(xyz[0]), float(xyz[1]), float(xyz[2])
    return msg


def _set_fields(msg, values: dict):
    for name, value in values.items():
        setattr(msg, name, value)
    return msg


def frequencies(t: Time, omega: float, f1: float, f2: float) -> DynamicFrequencies:
    """rotrod_interfaces/DynamicFrequencies: f1 <= f2 Hz at the hub's ``omega`` rad/s."""
    return set_frequencies(DynamicFrequencies(), t, omega, f1, f2)


def set_frequencies(msg: DynamicFrequencies, t: Time, omega: float, f1: float,
                    f2: float) -> DynamicFrequencies:
    """:func:`frequencies` written into ``msg``."""
    msg.header.stamp = t
    return _set_fields(msg, frequency_fields(omega, f1, f2))


def whirl_estimate(t: Time, estimate) -> WhirlEstimate:
    """rotrod_interfaces/WhirlEstimate of a whirl estimate, stamped ``t`` (its window's middle).

    ``estimate``: :class:`rotrod_core.estimation.whirl.WhirlEstimate`; the fields are
    :func:`rotrod_core.model.interface.whirl_fields`'.
    """
    return set_whirl_estimate(WhirlEstimate(), t, estimate)


def set_whirl_estimate(msg: WhirlEstimate, t: Time, estimate) -> WhirlEstimate:
    """:func:`whirl_estimate` written into ``msg``."""
    msg.header.stamp = t
    return _set_fields(msg, whirl_fields(estimate))


def rig_estimate(monitor, estimate) -> RigEstimate:
    """rotrod_interfaces/RigEstimate of a rig monitor's estimate, stamped at its window's end.

    ``monitor``: :class:`rotrod_core.estimation.monitor.RigMonitor`, ``estimate`` its
    latest; the fields are :meth:`~rotrod_core.estimation.monitor.RigMonitor.fields`.
    """
    values = monitor.fields(estimate)
    return _set_fields(RigEstimate(header=header(stamp(values.pop('window_end')))), values)


class SampleMessages:
    """The messages of the sample topics of one rod, written anew for each sample.

    joint_states, tip/deflection, tip/position and frequencies as the bytes DDS sends
    (:mod:`rotrod_ros.cdr`: their strings are the rod's for its life, so each is one
    ``struct`` of its numbers; what :func:`joint_state`, :func:`deflection`,
    :func:`position` and :func:`frequencies` would serialise to); the whirl estimate,
    whose reasons are text, as a message made once and written anew (setting a few
    fields costs much less than making it: docs/realtime.md#node-cpu).
    Stamps are (sec, nanosec) of :func:`rotrod_core.model.interface.stamp_parts`.
    """

    def __init__(self, rotor_frame: str, world_frame: str) -> None:
        self._joints = cdr.JointStates(JOINT_NAMES)
        self._rotor = cdr.StampedTriple(rotor_frame)
        self._world = cdr.StampedTriple(world_frame)
        self._frequencies = cdr.StampedTriple('')
        self.estimate = WhirlEstimate()

    def joint_state(self, sec: int, nanosec: int, state, torque: float,
                    rod_length: float) -> bytes:
        """sensor_msgs/JointState of :func:`joint_state`."""
        return self._joints.pack(sec, nanosec, *joint_values(state, torque, rod_length))

    def deflection(self, sec: int, nanosec: int, u: float, v: float) -> bytes:
        """geometry_msgs/Vector3Stamped (u, v, 0) m in the rotor frame."""
        return self._rotor.pack(sec, nanosec, float(u), float(v), 0.0)

    def position(self, sec: int, nanosec: int, xyz: Sequence[float]) -> bytes:
        """geometry_msgs/PointStamped of the mass, m, in the world frame."""
        return self._world.pack(sec, nanosec, float(xyz[0]), float(xyz[1]), float(xyz[2]))

    def frequencies(self, sec: int, nanosec: int, omega: float, f1: float,
                    f2: float) -> bytes:
        """rotrod_interfaces/DynamicFrequencies of :func:`frequencies`."""
        fields = frequency_fields(omega, f1, f2)
        return self._frequencies.pack(sec, nanosec, fields['omega'], fields['f1'],
                                      fields['f2'])


class RigMessages:
    """The rig sensors' messages of one rod: tip/imu, hub/encoder, rod/strain.

    Each is made once and written anew for each sample.

    Args:
        tip_frame: the IMU's frame (``<prefix>tip``).
        root_frame: the strain bridge's (``<prefix>rod_root``).
        sensors: the sensors' settings (SensorConfig): the covariances, whether the
            orientation is given.
    """

    def __init__(self, tip_frame: str, root_frame: str, sensors) -> None:
        self.imu = Imu()
        self.imu.header.frame_id = tip_frame
        self.encoder = JointState(name=[HUB_JOINT], position=[0.0], velocity=[0.0])
        self.strain = WrenchStamped()
        self.strain.header.frame_id = root_frame
        self.configure(sensors)

    def configure(self, sensors) -> None:
        """Covariances and the orientation's presence for ``sensors`` (SensorConfig)."""
        imu = self.imu
        imu.orientation_covariance = [0.0] * 9 if sensors.orientation else [-1.0] + [0.0] * 8
        if not sensors.orientation:
            imu.orientation.x = imu.orientation.y = imu.orientation.z = 0.0
            imu.orientation.w = 1.0
        for name in ('linear_acceleration', 'angular_velocity'):
            variance = getattr(sensors, name).variance
            setattr(imu, f'{name}_covariance', [variance, 0.0, 0.0, 0.0, variance, 0.0,
                                                0.0, 0.0, variance])
        self.orientation = sensors.orientation

    def imu_message(self, sec: int, nanosec: int, reading) -> Imu:
        """sensor_msgs/Imu of an ImuReading (REP 145), in the tip's frame."""
        msg = self.imu
        msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
        if self.orientation:
            q = msg.orientation
            q.x, q.y, q.z, q.w = reading.orientation
        a, g = msg.linear_acceleration, msg.angular_velocity
        a.x, a.y, a.z = reading.linear_acceleration
        g.x, g.y, g.z = reading.angular_velocity
        return msg

    def encoder_message(self, sec: int, nanosec: int, reading) -> JointState:
        """sensor_msgs/JointState of joint 'hub': the counts' angle rad, their speed rad/s."""
        msg = self.encoder
        msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
        msg.position[0] = reading.angle
        msg.velocity[0] = reading.speed
        return msg

    def strain_message(self, sec: int, nanosec: int, wrench) -> WrenchStamped:
        """geometry_msgs/WrenchStamped of a RootWrench, N and N m, in the root's frame."""
        msg = self.strain
        msg.header.stamp.sec, msg.header.stamp.nanosec = sec, nanosec
        f, m = msg.wrench.force, msg.wrench.torque
        f.x, f.y, f.z = wrench.force
        m.x, m.y, m.z = wrench.torque
        return msg


def clock(t: Time) -> Clock:
    """rosgraph_msgs/Clock."""
    return Clock(clock=t)


def value_text(value) -> str:
    """A diagnostic value as its KeyValue's text: a float to 6 digits, else str()."""
    return f'{value:.6g}' if isinstance(value, float) else str(value)


def diagnostic_status(name: str, hardware_id: str, level: int, message: str,
                      values: Iterable[tuple]) -> DiagnosticStatus:
    """A DiagnosticStatus; values are written as text (:func:`value_text`)."""
    kv = [KeyValue(key=str(k), value=value_text(v)) for k, v in values]
    return DiagnosticStatus(level=bytes([level]), name=name, message=message,
                            hardware_id=hardware_id, values=kv)


def diagnostics(t: Time, name: str, hardware_id: str, level: int, message: str,
                values: Iterable[tuple]) -> DiagnosticArray:
    """A DiagnosticArray with one status (see :func:`diagnostic_status`)."""
    return diagnostics_array(t, [(name, hardware_id, level, message, values)])


def diagnostics_array(t: Time, statuses: Iterable[tuple]) -> DiagnosticArray:
    """A DiagnosticArray of several statuses.

    Each (name, hardware_id, level, message, values) as :func:`diagnostic_status` takes.
    """
    return DiagnosticArray(header=header(t),
                           status=[diagnostic_status(*status) for status in statuses])


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


class MarkerFrames:
    """The markers of successive frames, made once and updated in place.

    A frame's MarkerArray is the same object each time, its markers changed where the
    shapes changed: making a Marker and its nested messages costs more than setting a
    few fields (docs/realtime.md#node-cpu). Publish (or copy) one frame before making
    the next.
    """

    def __init__(self, frame_id: str, ns: str) -> None:
        self._header = Header(frame_id=frame_id)
        self._ns = ns
        self._markers: dict[int, tuple[Marker, Shape]] = {}
        self._array = MarkerArray()

    def frame(self, t: Time, shapes: Iterable[Shape]) -> MarkerArray:
        """The MarkerArray of ``shapes`` (:func:`rotrod_core.model.scene.scene`) at ``t``."""
        self._header.stamp = t
        out = []
        for shape in shapes:
            entry = self._markers.get(shape.id)
            last: Shape | None = None
            if entry is not None and entry[1].kind == shape.kind:
                m, last = entry
            else:
                m = Marker(header=self._header, ns=self._ns, id=shape.id,
                           type=getattr(Marker, shape.kind.upper()), action=Marker.ADD)
                m.pose.orientation.w = 1.0
            if last is None or last.position != shape.position:
                m.pose.position = Point(x=shape.position[0], y=shape.position[1],
                                        z=shape.position[2])
            if last is None or last.scale != shape.scale:
                m.scale.x, m.scale.y, m.scale.z = shape.scale
            if last is None or last.color != shape.color:
                m.color = ColorRGBA(r=shape.color[0], g=shape.color[1], b=shape.color[2],
                                    a=shape.color[3])
            if last is None or last.points != shape.points:
                m.points = (_trail_points(shape.points) if shape.id == TRAIL_ID else
                            [Point(x=x, y=y, z=z) for x, y, z in shape.points])
            self._markers[shape.id] = m, shape
            out.append(m)
        self._array.markers = out
        return self._array


def markers(t: Time, frame_id: str, ns: str, *, disk_radius: float, theta: float,
            rod: Sequence[Sequence[float]], rod_diameter: float, mass_radius: float,
            trail: Iterable[Sequence[float]]) -> MarkerArray:
    """Disk (with a radial line at the rod's root, which turns with it), rod, mass, trail.

    ``rod`` is the drawn centreline (root to tip, m, frame ``frame_id``); ``trail`` the
    recent drawn tip positions. The shapes are :func:`rotrod_core.model.scene.scene`'s;
    a new array (:class:`MarkerFrames` updates one in place).
    """
    return MarkerFrames(frame_id, ns).frame(t, scene(
        disk_radius=disk_radius, theta=theta, rod=rod, rod_diameter=rod_diameter,
        mass_radius=mass_radius, trail=trail))
