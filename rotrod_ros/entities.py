"""The simulator's entities through the simulation standard: spawn, delete, query, set.

simulation_interfaces 2.1.0's entity calls, as Gazebo and Isaac Sim serve them, for a
world of rods (docs/simulation_control.md#entities). Each rod is an entity (category
ROBOT) named as it was spawned (``rod3``; the simulator's first rod, when it holds just
one with the plain names, has no name of its own), with two more: its hub
(``rod3/hub``) and its tip mass (``rod3/tip``; ``hub`` and ``tip`` for the first rod).
States are the ground truth in the shared ``world`` frame.

A rod is spawned from the URDF ``rotrod urdf`` writes, as a ``resource_string`` or a
``uri`` (a file, ``file://`` or ``package://``): its ``<rotrod>`` element gives the rod's
physical parameters and the drive's limits (:mod:`rotrod_core.model.description`); the
simulator's own parameters give the rest (drive, coupling, shaping, alarms). It stands
at ``initial_pose`` (its hub's axis vertical: a rotation about z only), its interfaces
under ``entity_namespace`` (default: its name). Every refusal has the standard's code and
a sentence, and changes nothing.
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import Any
from urllib.parse import unquote, urlparse

from geometry_msgs.msg import Vector3
from simulation_interfaces.msg import (
    Bounds,
    EntityCategory,
    EntityInfo,
    EntityState,
    Resource,
    Result,
    Spawnable,
    SpawnResult,
)
from simulation_interfaces.srv import (
    DeleteEntity,
    GetEntities,
    GetEntitiesStates,
    GetEntityInfo,
    GetEntityState,
    GetSpawnables,
    SetEntityState,
    SpawnEntities,
    SpawnEntity,
)

from rotrod_core.live.engine import EngineConfig
from rotrod_core.model.description import Description, DescriptionError, read_description
from rotrod_core.model.equations import make_state
from rotrod_core.model.kinematics import TipMotion
from rotrod_core.model.urdf import ROBOT_NAME, SHIPPED_FILE

from . import messages
from .interfaces import srv
from .rod_io import Pose, RodIO

NAME = re.compile(r'[A-Za-z][A-Za-z0-9_]*(/[A-Za-z][A-Za-z0-9_]*)*')
"""A rod's name: one or more ROS name tokens joined by '/' (it prefixes its topics)."""
NAMESPACE = re.compile(r'/?[A-Za-z_][A-Za-z0-9_]*(/[A-Za-z_][A-Za-z0-9_]*)*/?')
"""A ROS namespace (relative or absolute)."""
PARTS = ('hub', 'tip')
"""The entities of a rod besides itself."""
REQUEST_QUEUE = 1000
"""Requests the spawn and delete services queue (rclpy's default, 10, drops a burst)."""
QUATERNION_TOLERANCE = 1e-6
"""How far from 1 a pose's quaternion's norm may be."""

INTERFACES = (
    srv('~/spawn_entity', SpawnEntity,
        'simulation_interfaces: a rod from the URDF of rotrod urdf (resource_string, or '
        'uri: a file, file:// or package://) with its <rotrod> element; name (empty: '
        "the URDF's robot name), allow_renaming, entity_namespace (its interfaces' "
        'namespace; default its name), initial_pose (frame world; a rotation about z '
        'only). Codes NAME_NOT_UNIQUE, NAME_INVALID, NAMESPACE_INVALID, NO_RESOURCE, '
        'UNSUPPORTED_FORMAT, RESOURCE_PARSE_ERROR (naming the field), INVALID_POSE; more '
        'than max_rods: RESULT_OPERATION_FAILED. Its queue holds 1000 requests',
        depth=REQUEST_QUEUE),
    srv('~/spawn_entities', SpawnEntities,
        'simulation_interfaces: several spawn requests, each answered as spawn_entity '
        '(ENTITIES_SPAWN_FAILED when one fails; the others are spawned)',
        depth=REQUEST_QUEUE),
    srv('~/delete_entity', DeleteEntity,
        'simulation_interfaces: a rod by name (its goals end, its interfaces go; the '
        'world steps on); unknown: RESULT_NOT_FOUND', depth=REQUEST_QUEUE),
    srv('~/get_entities', GetEntities,
        'simulation_interfaces: the rods and their hub and tip entities, filtered by a '
        'regular expression (re.search) and categories (rods ROBOT, hub and tip OBJECT); '
        'tag and bounds filters: RESULT_FEATURE_UNSUPPORTED'),
    srv('~/get_entity_info', GetEntityInfo,
        'simulation_interfaces: category and a description (the rod: its mass, length, '
        'eccentricity, natural frequency)'),
    srv('~/get_entity_state', GetEntityState,
        "simulation_interfaces: ground truth in frame 'world': a rod (its base at its "
        "pose), its hub (orientation about z: the hub angle; twist and acceleration: w, "
        "w'), its tip (the mass: pose m, twist m/s and rad/s, acceleration m/s^2 and "
        "rad/s^2); the first rod's are 'hub' and 'tip'"),
    srv('~/get_entities_states', GetEntitiesStates,
        'simulation_interfaces: the states of the entities get_entities lists'),
    srv('~/set_entity_state', SetEntityState,
        "simulation_interfaces: a hub's angle (pose) and speed (twist.angular.z); a tip's "
        "position (pose: u, v) and velocity (twist: u', v'), in frame world; the rod "
        'then holds its new speed; acceleration: RESULT_OPERATION_FAILED; a pose off its '
        'rod: INVALID_POSE'),
    srv('~/get_spawnables', GetSpawnables,
        "simulation_interfaces: the package's URDF (the paper's Table 1), and any .urdf "
        'file with a <rotrod> element in the directories given as sources'),
)


def _result(code: int, message: str = '') -> Result:
    return Result(result=code, error_message=message)


class Refused(Exception):
    """A request refused: ``code`` (the standard's) and the reason."""

    def __init__(self, code: int, message: str):
        super().__init__(message)
        self.code = code


def _yaw(q) -> float:
    """The yaw of a quaternion that turns about z only; ValueError otherwise."""
    x, y, z, w = q.x, q.y, q.z, q.w
    norm = math.sqrt(x * x + y * y + z * z + w * w)
    if not math.isfinite(norm) or abs(norm - 1.0) > QUATERNION_TOLERANCE:
        raise ValueError(f'the orientation ({x:g}, {y:g}, {z:g}, {w:g}) is not a unit '
                         'quaternion')
    if abs(x) > QUATERNION_TOLERANCE or abs(y) > QUATERNION_TOLERANCE:
        raise ValueError('the orientation tilts the hub\'s axis: a rod turns about the '
                         'vertical (a rotation about z only)')
    return 2.0 * math.atan2(z, w)


def pose_of(msg, world_frame: str) -> Pose:
    """The Pose of a geometry_msgs/PoseStamped; Refused (INVALID_POSE) with the reason."""
    frame = msg.header.frame_id
    if frame not in ('', world_frame):
        raise Refused(SpawnEntity.Response.INVALID_POSE, f'initial_pose is in frame '
                      f'{frame!r}: the rods stand in {world_frame!r}')
    p = msg.pose.position
    if not all(math.isfinite(c) for c in (p.x, p.y, p.z)):
        raise Refused(SpawnEntity.Response.INVALID_POSE,
                      f'initial_pose position ({p.x}, {p.y}, {p.z}) is not finite')
    q = msg.pose.orientation
    if (q.x, q.y, q.z, q.w) == (0.0, 0.0, 0.0, 0.0):
        return Pose(p.x, p.y, p.z, 0.0)                   # unset: the identity
    try:
        return Pose(p.x, p.y, p.z, _yaw(q))
    except ValueError as exc:
        raise Refused(SpawnEntity.Response.INVALID_POSE, f'initial_pose: {exc}') from None


def read_resource(resource) -> str:
    """The description text of a simulation_interfaces/Resource; Refused otherwise."""
    R = SpawnEntity.Response
    if resource.resource_string:
        return resource.resource_string
    uri = resource.uri
    if not uri:
        raise Refused(R.NO_RESOURCE, 'the resource has neither a uri nor a resource_string')
    path = resolve_uri(uri)
    if path.suffix.lower() in ('.sdf', '.world', '.usd', '.usda', '.usdc', '.mjcf'):
        raise Refused(R.UNSUPPORTED_FORMAT, f'{uri}: a {path.suffix} file; the simulator '
                      'reads URDF (rotrod urdf) only')
    try:
        return path.read_text()
    except OSError as exc:
        raise Refused(R.RESOURCE_PARSE_ERROR, f'cannot read {uri}: {exc.strerror}') from None


def resolve_uri(uri: str) -> Path:
    """A file path for ``uri``: a path, file:///..., or package://<package>/<path>."""
    parsed = urlparse(uri)
    if parsed.scheme == 'package':
        from ament_index_python.packages import PackageNotFoundError, get_package_share_directory
        try:
            share = get_package_share_directory(parsed.netloc)
        except PackageNotFoundError:
            if parsed.netloc != 'rotrod':
                raise Refused(SpawnEntity.Response.RESOURCE_PARSE_ERROR,
                              f'{uri}: no package {parsed.netloc!r}') from None
            from .install import share_file
            return share_file(unquote(parsed.path).lstrip('/'))
        return Path(share) / unquote(parsed.path).lstrip('/')
    if parsed.scheme == 'file':
        return Path(unquote(parsed.path))
    if parsed.scheme:
        raise Refused(SpawnEntity.Response.UNSUPPORTED_FORMAT,
                      f'{uri}: the scheme {parsed.scheme!r} is not read (a path, file:// or '
                      'package://)')
    return Path(uri)


def parse(text: str) -> Description:
    """The rod a URDF text describes; Refused (UNSUPPORTED_FORMAT, RESOURCE_PARSE_ERROR)."""
    R = SpawnEntity.Response
    head = text.lstrip()[:200].lower()
    if '<sdf' in head:
        raise Refused(R.UNSUPPORTED_FORMAT, 'an SDFormat description; the simulator reads '
                      'URDF (rotrod urdf) only')
    try:
        return read_description(text)
    except DescriptionError as exc:
        raise Refused(R.RESOURCE_PARSE_ERROR, str(exc)) from None


def robot_name(text: str) -> str:
    """The URDF's robot name (ROBOT_NAME if it has none that reads)."""
    found = re.search(r'<robot[^>]*\sname\s*=\s*["\']([^"\']*)["\']', text)
    return found.group(1) if found else ROBOT_NAME


def motion_in(pose: Pose, motion: TipMotion) -> TipMotion:
    """A tip motion about a hub at the origin, for a hub at ``pose``."""
    if pose == Pose():
        return motion
    c, s = math.cos(pose.yaw), math.sin(pose.yaw)

    def turn(v):
        return (c * v[0] - s * v[1], s * v[0] + c * v[1], v[2])
    return TipMotion(pose.place(motion.position), motion.yaw + pose.yaw,
                     turn(motion.velocity), motion.angular_velocity,
                     turn(motion.acceleration), motion.angular_acceleration)


def entity_state(motion: TipMotion, stamp, frame_id: str) -> EntityState:
    """simulation_interfaces/EntityState of a :class:`~rotrod_core.model.kinematics.TipMotion`."""
    msg = EntityState()
    msg.header.stamp, msg.header.frame_id = stamp, frame_id
    p, q = msg.pose.position, msg.pose.orientation
    p.x, p.y, p.z = motion.position
    q.x, q.y, q.z, q.w = messages.yaw_quaternion(motion.yaw)
    for vector, values in ((msg.twist.linear, motion.velocity),
                           (msg.twist.angular, motion.angular_velocity),
                           (msg.acceleration.linear, motion.acceleration),
                           (msg.acceleration.angular, motion.angular_acceleration)):
        vector.x, vector.y, vector.z = values
    return msg


class EntityServices:
    """The entity calls over the simulator node (its world, loop and rods)."""

    def __init__(self, node) -> None:
        self.node = node
        self.descriptions: dict[str, Description] = {}
        """The spawned rods' descriptions, by name (their rod and limits)."""

    def callbacks(self) -> dict[str, Any]:
        """The callbacks by interface name, for :func:`rotrod_ros.interfaces.create`."""
        return {'~/spawn_entity': self.spawn_entity, '~/spawn_entities': self.spawn_entities,
                '~/delete_entity': self.delete_entity, '~/get_entities': self.get_entities,
                '~/get_entity_info': self.get_entity_info,
                '~/get_entity_state': self.get_entity_state,
                '~/get_entities_states': self.get_entities_states,
                '~/set_entity_state': self.set_entity_state,
                '~/get_spawnables': self.get_spawnables}

    @property
    def _world_frame(self) -> str:
        return self.node.settings.frame_prefix + 'world'

    # ----------------------------------------------------------------- configs
    def config_with(self, base: EngineConfig, name: str) -> EngineConfig:
        """A spawned rod's config: the node's ``base`` with its rod and limits (ValueError)."""
        d = self.descriptions[name]
        try:
            return base.replace(params=d.params, initial=(), **d.limits.__dict__)
        except ValueError as exc:
            raise ValueError(f'{name}: {exc}') from None

    # ----------------------------------------------------------------- spawning
    def spawn(self, request) -> str:
        """Spawn one rod; its unique name, or Refused with the standard's code."""
        node = self.node
        R = SpawnEntity.Response
        text = read_resource(request.entity_resource)
        description = parse(text)
        name = request.name or (robot_name(text) if request.allow_renaming else '')
        if not name:
            raise Refused(R.NAME_INVALID, 'no name: give one, or allow_renaming')
        if not NAME.fullmatch(name):
            if not request.allow_renaming:
                raise Refused(R.NAME_INVALID, f'name {name!r}: letters, digits and _, '
                              "tokens joined by '/', each starting with a letter")
            name = re.sub(r'[^A-Za-z0-9_]', '_', name).strip('_') or ROBOT_NAME
            if not name[0].isalpha():
                name = 'rod_' + name
        if name in node.rods or name in PARTS:
            if not request.allow_renaming:
                raise Refused(R.NAME_NOT_UNIQUE, f'an entity is already named {name!r}')
            base, k = name, 1
            while f'{base}_{k}' in node.rods:
                k += 1
            name = f'{base}_{k}'
        namespace = request.entity_namespace or name
        if not NAMESPACE.fullmatch(namespace):
            raise Refused(R.NAMESPACE_INVALID, f'entity_namespace {namespace!r} is not a ROS '
                          'namespace (tokens of letters, digits and _ joined by /)')
        prefix = namespace.rstrip('/') + '/'
        if any(io.prefix == prefix for io in node.rods.values()):
            raise Refused(R.NAMESPACE_INVALID, f'entity_namespace {namespace!r} is another '
                          "rod's: the interfaces would mix")
        pose = pose_of(request.initial_pose, self._world_frame)
        if len(node.rods) >= node.settings.max_rods:
            raise Refused(Result.RESULT_OPERATION_FAILED, f'the world holds max_rods '
                          f'{node.settings.max_rods} rods already')
        base = node._param_values.checked[0]
        self.descriptions[name] = description
        try:
            config = self.config_with(base, name)
        except ValueError as exc:
            del self.descriptions[name]
            raise Refused(Result.RESULT_OPERATION_FAILED, str(exc)) from None
        node.add_rod(name, prefix, config, pose)
        node.get_logger().info(
            f'spawned {name!r} (interfaces under {prefix}) at ({pose.x:g}, {pose.y:g}, '
            f'{pose.z:g}) m, yaw {pose.yaw:g} rad: mass {float(config.params.mass):g} kg, '
            f'w0 {float(config.params.natural_frequency_radial):.6g} rad/s')
        return name

    def spawn_entity(self, request, response):
        """SpawnEntity."""
        try:
            response.entity_name = self.spawn(request)
            response.result = _result(Result.RESULT_OK)
        except Refused as exc:
            response.result = _result(exc.code, str(exc))
            self.node.get_logger().warning(f'spawn refused: {exc}')
        return response

    def spawn_entities(self, request, response):
        """SpawnEntities: each request as SpawnEntity; ENTITIES_SPAWN_FAILED if one fails."""
        failed = 0
        for one in request.spawn_requests:
            result = SpawnResult()
            try:
                result.entity_name = self.spawn(one)
                result.result = _result(Result.RESULT_OK)
            except Refused as exc:
                failed += 1
                result.result = _result(exc.code, str(exc))
            response.results.append(result)
        response.result = (_result(Result.RESULT_OK) if not failed else _result(
            SpawnEntities.Response.ENTITIES_SPAWN_FAILED,
            f'{failed} of {len(request.spawn_requests)} requests failed (see results)'))
        return response

    def delete_entity(self, request, response):
        """DeleteEntity: a rod by name."""
        name = request.entity
        if name not in self.node.rods or name == '':
            response.result = _result(Result.RESULT_NOT_FOUND, self._unknown(name, rods=True))
            return response
        self.node.remove_rod(name)
        self.descriptions.pop(name, None)
        self.node.get_logger().info(f'deleted {name!r}')
        response.result = _result(Result.RESULT_OK)
        return response

    # ----------------------------------------------------------------- listing
    def entities(self) -> list[tuple[str, str, str]]:
        """(entity, rod, part) of every entity: a rod ('' part), its hub and its tip."""
        out = []
        for rod in list(self.node.rods):
            if rod:
                out.append((rod, rod, ''))
            out += [(f'{rod}/{part}' if rod else part, rod, part) for part in PARTS]
        return out

    def _unknown(self, name: str, rods: bool = False) -> str:
        names = [e for e, _, part in self.entities() if not rods or part == '']
        return (f'no entity {name!r}; there are {len(names)}'
                + (f': {", ".join(names[:10])}' + (', ...' if len(names) > 10 else '')
                   if names else ''))

    def _filtered(self, filters) -> list[tuple[str, str, str]]:
        """The entities that pass ``filters``; Refused for what is not supported."""
        if filters.tags.tags:
            raise Refused(Result.RESULT_FEATURE_UNSUPPORTED, 'tags: no entity has tags')
        if filters.bounds.type != Bounds.TYPE_EMPTY:
            raise Refused(Result.RESULT_FEATURE_UNSUPPORTED, 'bounds filters are not served')
        try:
            pattern = re.compile(filters.filter) if filters.filter else None
        except re.error as exc:
            raise Refused(Result.RESULT_OPERATION_FAILED, f'filter {filters.filter!r}: '
                          f'{exc}') from None
        categories = {c.category for c in filters.categories}
        return [e for e in self.entities()
                if (pattern is None or pattern.search(e[0]))
                and (not categories or self._category(e[2]) in categories)]

    @staticmethod
    def _category(part: str) -> int:
        return EntityCategory.CATEGORY_ROBOT if part == '' else EntityCategory.CATEGORY_OBJECT

    def get_entities(self, request, response):
        """GetEntities."""
        try:
            response.entities = [e for e, _, _ in self._filtered(request.filters)]
            response.result = _result(Result.RESULT_OK)
        except Refused as exc:
            response.result = _result(exc.code, str(exc))
        return response

    def _find(self, name: str) -> tuple[str, str]:
        for entity, rod, part in self.entities():
            if entity == name:
                return rod, part
        raise Refused(Result.RESULT_NOT_FOUND, self._unknown(name))

    def get_entity_info(self, request, response):
        """GetEntityInfo."""
        try:
            rod, part = self._find(request.entity)
        except Refused as exc:
            response.result = _result(exc.code, str(exc))
            return response
        engine = self.node.rods[rod].engine
        p = engine.config.params
        what = {'': (f'a point mass of {float(p.mass):g} kg on a rod {float(p.rod_length):g} '
                     f'm long, {float(p.eccentricity):g} m off the axis of a rotating disk; '
                     f'w0 {float(p.natural_frequency_radial):.6g} rad/s'),
                'hub': 'the rotating disk (joint hub): angle about z, speed w',
                'tip': 'the tip mass: its ground-truth position and motion'}[part]
        response.info = EntityInfo(category=EntityCategory(category=self._category(part)),
                                   description=what)
        response.result = _result(Result.RESULT_OK)
        return response

    # ----------------------------------------------------------------- states
    def _state(self, rod: str, part: str, stamp) -> EntityState:
        io: RodIO = self.node.rods[rod]
        engine, pose = io.engine, io.pose
        if part == 'tip':
            return entity_state(motion_in(pose, engine.tip_motion()), stamp,
                                self._world_frame)
        s = engine.state
        spin = part == 'hub'
        motion = TipMotion((pose.x, pose.y, pose.z), pose.yaw + (float(s.theta) if spin else 0),
                           (0.0, 0.0, 0.0), (0.0, 0.0, float(s.omega) if spin else 0.0),
                           (0.0, 0.0, 0.0), (0.0, 0.0, engine.omega_dot if spin else 0.0))
        return entity_state(motion, stamp, self._world_frame)

    def get_entity_state(self, request, response):
        """GetEntityState."""
        loop = self.node.loop
        try:
            rod, part = self._find(request.entity)
            with loop.lock:
                response.state = self._state(rod, part, messages.stamp(loop.stamp_now()))
        except Refused as exc:
            response.result = _result(exc.code, str(exc))
            return response
        response.result = _result(Result.RESULT_OK)
        return response

    def get_entities_states(self, request, response):
        """GetEntitiesStates: the states of the entities that pass the filters."""
        loop = self.node.loop
        try:
            with loop.lock:            # one instant for all
                found = self._filtered(request.filters)
                stamp = messages.stamp(loop.stamp_now())
                response.states = [self._state(rod, part, stamp) for _, rod, part in found]
            response.entities = [e for e, _, _ in found]
            response.result = _result(Result.RESULT_OK)
        except Refused as exc:
            response.result = _result(exc.code, str(exc))
        return response

    def set_entity_state(self, request, response):
        """SetEntityState: a hub's angle and speed, a tip's position and velocity."""
        try:
            self._set(request)
            response.result = _result(Result.RESULT_OK)
        except Refused as exc:
            response.result = _result(exc.code, str(exc))
        return response

    def _set(self, request) -> None:
        rod, part = self._find(request.entity)
        F = Result.RESULT_OPERATION_FAILED
        if part == '':
            raise Refused(F, f'{request.entity!r} is a rod: set its hub ({rod}/hub) or its '
                          f'tip ({rod}/tip)')
        if request.set_acceleration:
            raise Refused(F, 'acceleration is not a state of the model (it follows from the '
                          'commands)')
        state = request.state
        if state.header.frame_id not in ('', self._world_frame):
            raise Refused(SetEntityState.Response.INVALID_POSE, f'frame '
                          f'{state.header.frame_id!r}: states are set in {self._world_frame!r}')
        io = self.node.rods[rod]
        loop = self.node.loop
        with loop.lock:
            engine = io.engine
            values = dict(engine.state._asdict())
            if part == 'hub':
                self._set_hub(values, request, io.pose)
            else:
                self._set_tip(values, request, io.pose, engine)
            try:
                engine.set_state(**make_state(values, scalar=True)._asdict())
            except ValueError as exc:
                raise Refused(F, str(exc)) from None

    @staticmethod
    def _set_hub(values: dict, request, pose: Pose) -> None:
        state = request.state
        if request.set_pose:
            try:
                values['theta'] = _yaw(state.pose.orientation) - pose.yaw
            except ValueError as exc:
                raise Refused(SetEntityState.Response.INVALID_POSE, str(exc)) from None
        if request.set_twist:
            t = state.twist
            if any(abs(c) > 0 for c in (t.linear.x, t.linear.y, t.linear.z, t.angular.x,
                                         t.angular.y)):
                raise Refused(Result.RESULT_OPERATION_FAILED, 'a hub turns about z only: '
                              'twist.angular.z is its speed, the rest must be 0')
            values['omega'] = float(t.angular.z)

    @staticmethod
    def _set_tip(values: dict, request, pose: Pose, engine) -> None:
        """The tip's world position and velocity, read back as (u, v) and (u', v')."""
        state = request.state
        r0 = float(engine._coefficients.eccentricity)
        theta, w = values['theta'], values['omega']
        c, s = math.cos(theta + pose.yaw), math.sin(theta + pose.yaw)
        if request.set_pose:
            p = state.pose.position
            x, y = p.x - pose.x, p.y - pose.y
            u, v = c * x + s * y - r0, -s * x + c * y
            height = float(engine.config.params.rod_length) + pose.z
            if not (math.isfinite(u) and math.isfinite(v)) or abs(p.z - height) > 1e-6 * max(
                    1.0, height):
                raise Refused(SetEntityState.Response.INVALID_POSE, f'the tip is at height '
                              f'{height:g} m on its rod, not {p.z:g} m (small deflection: '
                              'it moves in the plane of rotation)')
            values['u'], values['v'] = u, v
        if request.set_twist:
            t = state.twist.linear
            # world velocity = R (u' - w v, v' + w (r0 + u)): solved for (u', v')
            a, b = c * t.x + s * t.y, -s * t.x + c * t.y
            values['du'] = a + w * values['v']
            values['dv'] = b - w * (r0 + values['u'])

    # ----------------------------------------------------------------- spawnables
    def get_spawnables(self, request, response):
        """GetSpawnables: the package's URDF, and the rotrod URDFs in ``sources``."""
        from .install import share_file
        found = [('package://rotrod/' + SHIPPED_FILE, share_file(SHIPPED_FILE))]
        for source in request.sources:
            directory = Path(source)
            if not directory.is_dir():
                response.result = _result(Result.RESULT_NOT_FOUND,
                                          f'source {source!r} is not a directory')
                return response
            found += [(str(path), path) for path in sorted(directory.glob('*.urdf'))]
        for uri, path in found:
            try:
                d = read_description(path.read_text())
            except (OSError, DescriptionError):
                continue                         # not a rod's URDF
            p = d.params
            size = float(d.disk_radius or 0.15) + float(p.eccentricity)
            response.spawnables.append(Spawnable(
                entity_resource=Resource(uri=uri),
                description=f'a rod: mass {float(p.mass):g} kg, length '
                            f'{float(p.rod_length):g} m, r0 {float(p.eccentricity):g} m, w0 '
                            f'{float(p.natural_frequency_radial):.6g} rad/s',
                spawn_bounds=Bounds(type=Bounds.TYPE_BOX, points=[
                    Vector3(x=-size, y=-size, z=-0.01),
                    Vector3(x=size, y=size, z=float(p.rod_length) + 0.05)])))
        response.result = _result(Result.RESULT_OK)
        return response


__all__ = ['EntityServices', 'INTERFACES', 'Refused', 'entity_state', 'motion_in', 'parse',
           'pose_of', 'read_resource']
