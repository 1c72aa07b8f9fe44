"""rosbag2 files (MCAP storage, Jazzy's default) of offline runs, with ``rosbags``.

``rotrod simulate ... --bag DIR`` writes the run as the live simulator would have
published it at ``publish_rate``, faster than real time (stamps in simulated seconds
from 0, as with ``/clock``): the same topics, types, frame ids, joint names and stamps,
with the same settings (:class:`~rotrod_core.live.publication.PublicationSettings`, the
node's) and fields built by the same functions (:mod:`rotrod_core.model.interface`,
:mod:`rotrod_core.model.scene`), so that ``ros2 bag play DIR`` replays it beside a live
run and Foxglove or Rerun open it. Each message's log time is its publication's instant,
its stamp but for the estimate's (its window's middle). rotrod's own
types (``rotrod_interfaces``) are registered with rosbags from their ``.msg`` files
(:func:`interface_definitions`), so the bag carries their definitions and type hashes
and any reader decodes them.

Topics (names relative to ``namespace``, as the node's; types as
:data:`~rotrod_core.model.interface.TOPICS`):

    joint_states           hub theta, w, hub torque; tip_radial, tip_tangential u, v, u', v'
    tip/deflection         (u, v, 0) m in frame ``rotor`` (no sensor noise: the state)
    tip/position           the mass in frame ``world``, m
    frequencies            f1, f2 Hz at the sample's w, with w (Eq. 28 / eigen analysis)
    frequencies/estimate   the whirl estimate from the published (u, v), as the node's,
                           stamped at its window's middle
    markers                disk, rod, mass, trail at ``marker_rate`` (``markers=False``: none)
    /clock                 simulated time at each publication

Left out: ``/diagnostics``, the live session's health (command timeouts, pauses,
halts and their alarms belong to a running node; an offline run has no commands).

``rosbags`` (pure Python, its own type store: no rclpy) is imported when a bag is
written, not with this module, so the core does not need it.
"""

from __future__ import annotations

import os
import shutil
import sys
from collections import deque
from pathlib import Path
from typing import Final

import numpy as np

from rotrod_core.analysis.modes import dynamic_frequencies
from rotrod_core.estimation.whirl import stream_estimator
from rotrod_core.live.publication import SAMPLE_TOPICS, PublicationSettings
from rotrod_core.model import interface
from rotrod_core.model.equations import State
from rotrod_core.model.geometry import rod_centerline, sphere_radius
from rotrod_core.model.scene import scene

STORAGE = 'mcap'
VERSION: Final = 9
"""rosbag2 metadata version written by Jazzy's ``ros2 bag record``."""
QOS_DEPTH = 10
"""History depth of the node's publishers (reliable, volatile: rclpy's default)."""
INFINITE = (9223372036, 854775807)
"""rmw's infinite duration (sec, nsec), as ``ros2 bag record`` writes a default QoS."""
BAG_TOPICS = (*SAMPLE_TOPICS, 'markers', '/clock')
"""The node's topics a bag holds."""
SOURCE_INTERFACES = Path(__file__).resolve().parents[2] / interface.INTERFACES_PACKAGE
"""The interface package's sources in a checkout (used when none is installed)."""


def check_namespace(namespace: str) -> str:
    """``namespace``, or ValueError unless it starts with /."""
    if not namespace.startswith('/'):
        raise ValueError(f'namespace must start with /, got {namespace!r}')
    return namespace


def topic_name(namespace: str, name: str) -> str:
    """The full name of one of the node's topics in ``namespace`` (which starts with /)."""
    check_namespace(namespace)
    if name.startswith('/'):
        return name
    return '/'.join(['', *[p for p in namespace.split('/') if p], name])


def interface_definitions() -> dict:
    """``{'rotrod_interfaces/msg/Name': .msg text}`` of rotrod's messages.

    From the installed package (``share/rotrod_interfaces/msg`` under each
    AMENT_PREFIX_PATH entry, then under this Python's prefix, where run.sh builds it),
    else from the sources beside this package (a checkout). Raises FileNotFoundError.
    """
    package = interface.INTERFACES_PACKAGE
    prefixes = [Path(p) for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep)
                if p] + [Path(sys.prefix)]
    places = [prefix / 'share' / package / 'msg' for prefix in prefixes]
    places.append(SOURCE_INTERFACES / 'msg')
    for place in places:
        files = sorted(place.glob('*.msg'))
        if files:
            return {f'{package}/msg/{f.stem}': f.read_text() for f in files}
    raise FileNotFoundError(f'no {package} message definitions in '
                            f'{", ".join(str(p) for p in places)}')


def publication_indices(t: np.ndarray, publish_rate: float) -> np.ndarray:
    """Indices of the run's samples at k / publish_rate, k = 0, 1, ... (the node's grid).

    Raises ValueError unless the publish period is a whole number of the run's steps.
    """
    if len(t) < 2:
        return np.arange(len(t))
    dt = float(t[1] - t[0])
    period = 1.0 / publish_rate
    every = int(round(period / dt))
    if every < 1 or abs(every * dt - period) > 1e-9 * period:
        raise ValueError(f'the publish period 1/{publish_rate:g} s is not a whole number of '
                         f'the run\'s steps ({dt:g} s)')
    return np.arange(0, len(t), every)


class _Messages:
    """rosbags message objects (its type store for Jazzy), with the node's conventions."""

    def __init__(self):
        from rosbags.interfaces import Nodetype
        from rosbags.typesys import Stores, get_types_from_msg, get_typestore
        self.store = get_typestore(Stores.ROS2_JAZZY)
        for name, text in interface_definitions().items():
            self.store.register(get_types_from_msg(text, name))
        self._nodetype = Nodetype

    def make(self, msgtype: str, **fields):
        """A message of ``msgtype`` with ``fields``; the others zero or empty."""
        cls = self.store.types[msgtype]
        _, defs = self.store.fielddefs[msgtype]
        values = {name: fields[name] if name in fields else self._default(node)
                  for name, node in defs}
        unknown = set(fields) - set(values)
        if unknown:
            raise ValueError(f'{msgtype} has no field(s) {sorted(unknown)}')
        return cls(**values)

    def _default(self, node):
        kind, detail = node
        nt = self._nodetype
        if kind == nt.BASE:
            base = detail[0]
            if base == 'string':
                return ''
            if base == 'bool':
                return False
            return 0.0 if base.startswith('float') else 0
        if kind == nt.NAME:
            return self.make(detail)
        sub, count = detail
        if sub[0] == nt.BASE and sub[1][0] not in ('string', 'bool'):
            dtype = {'float32': np.float32, 'float64': np.float64, 'byte': np.uint8,
                     'char': np.uint8}.get(sub[1][0], sub[1][0])
            return np.zeros(count if kind == nt.ARRAY else 0, dtype=dtype)
        return [self._default(sub) for _ in range(count)] if kind == nt.ARRAY else []

    def time(self, seconds: float):
        sec, nanosec = interface.stamp_parts(seconds)
        return self.make('builtin_interfaces/msg/Time', sec=sec, nanosec=nanosec)

    def header(self, stamp, frame_id: str = ''):
        return self.make('std_msgs/msg/Header', stamp=stamp, frame_id=frame_id)

    def point(self, xyz):
        return self.make('geometry_msgs/msg/Point', x=float(xyz[0]), y=float(xyz[1]),
                         z=float(xyz[2]))

    def joint_state(self, stamp, state: State, torque: float, rod_length: float):
        position, velocity, effort = interface.joint_values(state, torque, rod_length)
        return self.make('sensor_msgs/msg/JointState', header=self.header(stamp),
                         name=list(interface.JOINT_NAMES),
                         position=np.array(position), velocity=np.array(velocity),
                         effort=np.array(effort))

    def deflection(self, stamp, u: float, v: float, frame_id: str):
        vector = self.make('geometry_msgs/msg/Vector3', x=float(u), y=float(v), z=0.0)
        return self.make('geometry_msgs/msg/Vector3Stamped',
                         header=self.header(stamp, frame_id), vector=vector)

    def position(self, stamp, xyz, frame_id: str):
        return self.make('geometry_msgs/msg/PointStamped', header=self.header(stamp, frame_id),
                         point=self.point(xyz))

    def frequencies(self, stamp, omega: float, f1: float, f2: float):
        return self.make(interface.TOPICS['frequencies'], header=self.header(stamp),
                         **interface.frequency_fields(omega, f1, f2))

    def whirl_estimate(self, stamp, estimate):
        return self.make(interface.TOPICS['frequencies/estimate'], header=self.header(stamp),
                         **interface.whirl_fields(estimate))

    def clock(self, stamp):
        return self.make('rosgraph_msgs/msg/Clock', clock=stamp)

    def markers(self, stamp, frame_id: str, shapes):
        out = []
        cls = self.store.types['visualization_msgs/msg/Marker']
        for shape in shapes:
            pose = self.make('geometry_msgs/msg/Pose', position=self.point(shape.position),
                             orientation=self.make('geometry_msgs/msg/Quaternion', w=1.0))
            scale = self.make('geometry_msgs/msg/Vector3', x=float(shape.scale[0]),
                              y=float(shape.scale[1]), z=float(shape.scale[2]))
            r, g, b, a = (float(c) for c in shape.color)
            out.append(self.make(
                'visualization_msgs/msg/Marker', header=self.header(stamp, frame_id),
                ns=interface.MARKER_NAMESPACE, id=shape.id,
                type=getattr(cls, shape.kind.upper()),
                # the typestore's message classes carry their constants; its types do not
                action=cls.ADD,  # type: ignore[attr-defined]
                pose=pose,
                scale=scale, color=self.make('std_msgs/msg/ColorRGBA', r=r, g=g, b=b, a=a),
                points=[self.point(p) for p in shape.points]))
        return self.make('visualization_msgs/msg/MarkerArray', markers=out)


def _qos():
    from rosbags.interfaces import (
        Qos,
        QosDurability,
        QosHistory,
        QosLiveliness,
        QosReliability,
        QosTime,
    )
    forever = QosTime(*INFINITE)
    return Qos(QosHistory.KEEP_LAST, QOS_DEPTH, QosReliability.RELIABLE,
               QosDurability.VOLATILE, forever, forever, QosLiveliness.AUTOMATIC, forever,
               False)


def write_bag(path: str | Path, run, settings: PublicationSettings | None = None, *,
              namespace: str = '/', clock: bool = True) -> dict:
    """Write an offline run (:class:`~rotrod_core.offline.result.SimulationResult`).

    ``path`` is the bag's directory (it must not exist: rosbag2 does not overwrite);
    ``settings`` the publication's, as the node's (default: the node's defaults);
    ``namespace`` the topics' (e.g. '/offline', to play beside a live run in /);
    ``clock`` whether to write /clock. Returns the number of messages per full topic
    name.
    """
    from rosbags.rosbag2 import StoragePlugin, Writer

    settings = settings or PublicationSettings()
    check_namespace(namespace)
    path = Path(path)
    if path.exists():
        raise ValueError(f'{path} exists: a bag is written into a new directory')
    if not path.parent.is_dir():
        raise ValueError(f'directory {str(path.parent)!r} does not exist')
    keep = publication_indices(np.asarray(run.t), settings.publish_rate)
    f1, f2 = dynamic_frequencies(run.params, run.omega[keep])
    f1, f2 = np.broadcast_to(f1, keep.shape), np.broadcast_to(f2, keep.shape)
    world = settings.frame_prefix + interface.WORLD_FRAME
    rotor = settings.frame_prefix + interface.ROTOR_FRAME
    height = float(run.params.rod_length)
    marker_every = max(1, round(settings.publish_rate / settings.marker_rate))
    trail: deque = deque(maxlen=max(1, settings.marker_trail_length))
    estimator = stream_estimator(settings.estimate_window, settings.publish_rate,
                                 settings.estimate_rate)
    mass_radius = sphere_radius(float(run.params.mass))
    rod_diameter = float(run.params.rod_diameter)

    msgs = _Messages()
    writer = Writer(path, version=VERSION, storage_plugin=StoragePlugin.MCAP)
    writer.open()
    try:
        topics = [t for t in BAG_TOPICS if (t != 'markers' or settings.markers)
                  and (t != 'frequencies/estimate' or estimator is not None)
                  and (t != '/clock' or clock)]
        qos = _qos()
        connections = {t: writer.add_connection(topic_name(namespace, t), interface.TOPICS[t],
                                                typestore=msgs.store, offered_qos_profiles=[qos])
                       for t in topics}
        counts = dict.fromkeys(topics, 0)

        def write(topic: str, ns: int, msg) -> None:
            if topic in connections:
                conn = connections[topic]
                writer.write(conn, ns, msgs.store.serialize_cdr(msg, conn.msgtype))
                counts[topic] += 1

        for j, i in enumerate(keep):
            t = float(run.t[i])
            ns = interface.stamp_nanoseconds(t)
            stamp = msgs.time(t)
            u, v, du, dv, theta, omega = (float(x[i]) for x in (run.u, run.v, run.du, run.dv,
                                                                run.theta, run.omega))
            state = State(u, v, du, dv, theta, omega)
            write('joint_states', ns, msgs.joint_state(stamp, state, float(run.torque[i]),
                                                       height))
            write('tip/deflection', ns, msgs.deflection(stamp, u, v, rotor))
            write('tip/position', ns, msgs.position(stamp, (run.x[i], run.y[i], height),
                                                    world))
            write('frequencies', ns, msgs.frequencies(stamp, omega, f1[j], f2[j]))
            write('/clock', ns, msgs.clock(stamp))
            if estimator is not None:
                estimate = estimator.push(t, u, v)
                if estimate is not None:       # stamped at its window's middle
                    write('frequencies/estimate', ns,
                          msgs.whirl_estimate(msgs.time(estimate.time), estimate))
            if settings.markers and (j + 1) % marker_every == 0:
                rod = rod_centerline(run.params, u, v, theta,
                                     scale=settings.marker_deflection_scale)
                trail.append(tuple(rod[-1]))
                write('markers', ns, msgs.markers(stamp, world, scene(
                    disk_radius=settings.disk_radius, theta=theta, rod=rod,
                    rod_diameter=rod_diameter, mass_radius=mass_radius, trail=list(trail))))
    except BaseException:
        writer.abort()
        shutil.rmtree(path, ignore_errors=True)     # no half-written bag left behind
        raise
    writer.close()
    return {topic_name(namespace, t): n for t, n in counts.items()}
