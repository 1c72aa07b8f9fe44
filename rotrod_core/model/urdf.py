"""The URDF of the rod on its disk, generated from :class:`RodParams` (no ROS import).

With the simulator's ``joint_states`` (joints ``hub``, ``tip_radial``,
``tip_tangential``), ``robot_state_publisher`` gives ``/tf`` for every frame of
:mod:`rotrod_core.model.interface`, and the ``tip`` frame is where ``tip/position``
puts the mass: (r0 + u, v, l) in the rotating frame ``rotor``, turned by theta about z
into ``world``. The geometry (r0, l, the rod's section, the mass's size) comes from
the parameters; ``urdf/rotrod.urdf`` is this text for the paper's Table 1 (``rotrod
urdf`` writes it for other parameters, also from the simulator's parameter files).

The URDF is kinematic and visual: the dynamics are the simulator's, so it has no
``<inertial>`` (a physics engine must not mistake it for a model of the rod). The tip
joints' limits, which URDF requires of prismatic joints, are +-l (far beyond the
simulator's halt at ``max_deflection_ratio`` x l, 0.1 l by default); their effort
limit is 0 (passive joints); their velocity limit is w0 l, the speed of a free
vibration l in amplitude (indicative: nothing enforces it).

With a :class:`Ros2Control`, the URDF also has a ``<ros2_control>`` block for
``topic_based_ros2_control``'s ``TopicBasedSystem``: the controller manager then
drives the simulator over its ``joint_command`` topic and reads its ``joint_states``
(docs/ros_integration.md).
"""

from __future__ import annotations

import dataclasses
import fnmatch
import math
from dataclasses import dataclass
from pathlib import Path
from xml.sax.saxutils import escape, quoteattr

from rotrod_core.model.description import DEFAULT_LIMITS, DriveLimits, description_element
from rotrod_core.model.geometry import TIP_SLOPE, sphere_radius
from rotrod_core.model.interface import (
    HUB_JOINT,
    ROD_MOUNT_JOINT,
    ROD_ROOT_FRAME,
    ROTOR_FRAME,
    TIP_FRAME,
    TIP_PITCH_FRAME,
    TIP_PITCH_JOINT,
    TIP_RADIAL_FRAME,
    TIP_RADIAL_JOINT,
    TIP_ROLL_JOINT,
    TIP_TANGENTIAL_FRAME,
    TIP_TANGENTIAL_JOINT,
    WORLD_FRAME,
)
from rotrod_core.model.params import DEFAULT_HUB_RADIUS, RodParams
from rotrod_core.model.scene import DISK_COLOR, DISK_THICKNESS, MASS_COLOR, ROD_COLOR

ROBOT_NAME = 'rotrod'
SHIPPED_FILE = 'urdf/rotrod.urdf'
"""The shipped URDF (Table 1), relative to the package's share directory."""
ROD_PARAM_NAMES = ('mass', 'rod_length', 'rod_diameter', 'youngs_modulus', 'eccentricity',
                   'hub_inertia', 'damping_ratio', 'section', 'section_width',
                   'section_thickness', 'gravity', 'rod_density')
"""The simulator's parameters that are RodParams fields."""
SIMULATOR_NODE = 'rotrod_simulator'


TOPIC_BASED_SYSTEM = 'topic_based_ros2_control/TopicBasedSystem'
"""The hardware interface plugin that talks to a simulator over topics."""
HUB_COMMAND_INTERFACES = ('velocity', 'effort')
"""Command interfaces the hub can have: velocity (drive velocity), effort (drive torque)."""


@dataclass(frozen=True)
class Ros2Control:
    """A ``<ros2_control>`` block for ``TopicBasedSystem`` (topic names are absolute).

    Attributes:
        command_interfaces: the hub's, a non-empty subset of
            :data:`HUB_COMMAND_INTERFACES` ('velocity' for drive velocity, 'effort'
            for drive torque; both to switch controllers with the drive).
        joint_commands_topic: where the interface publishes: the simulator's
            ``joint_command`` (e.g. ``/rotrod/joint_command`` for a simulator in
            namespace ``/rotrod``).
        joint_states_topic: where it reads the joints: the simulator's ``joint_states``.
        trigger_joint_command_threshold: the interface publishes a command only when the
            summed |position state - position command| exceeds this; with no position
            command interface that sum is |theta|, 0 at rest, so the default -1 (always
            publish) is needed for the first command to be sent at all.
        name: the block's (hardware component's) name.
    """

    command_interfaces: tuple = ('velocity',)
    joint_commands_topic: str = '/rotrod/joint_command'
    joint_states_topic: str = '/rotrod/joint_states'
    trigger_joint_command_threshold: float = -1.0
    name: str = ROBOT_NAME

    def __post_init__(self):
        given = tuple(self.command_interfaces)
        if not given or len(set(given)) != len(given) or not set(given) <= set(
                HUB_COMMAND_INTERFACES):
            raise ValueError(f'command_interfaces must be distinct names among '
                             f'{HUB_COMMAND_INTERFACES}, got {self.command_interfaces!r}')
        object.__setattr__(self, 'command_interfaces', given)
        for name in ('joint_commands_topic', 'joint_states_topic'):
            topic = getattr(self, name)
            if not (isinstance(topic, str) and topic.startswith('/') and len(topic) > 1
                    and not any(c.isspace() for c in topic)):
                raise ValueError(f'{name} must be an absolute topic name, got {topic!r}')
        if not self.name or any(c.isspace() for c in self.name):
            raise ValueError(f'name must be a non-empty word, got {self.name!r}')


def ros2_control_block(options: Ros2Control) -> str:
    """The ``<ros2_control>`` element (XML text, indented for the robot element).

    Joint ``hub`` only: the command interfaces asked for; state interfaces position
    (theta, rad), velocity (w, rad/s), effort (hub torque, N m). The passive tip joints
    are left out: ``TopicBasedSystem`` names every joint of its block in its commands but
    gives a field entries only for the joints with that command interface, which would
    break sensor_msgs/JointState's contract (a field empty or one entry per name) that
    the simulator holds ``joint_command`` to. Their state (u, v for ``/tf``) is in the
    simulator's ``joint_states`` for ``robot_state_publisher``.
    """
    params = (('joint_commands_topic', options.joint_commands_topic),
              ('joint_states_topic', options.joint_states_topic),
              ('trigger_joint_command_threshold', f'{options.trigger_joint_command_threshold:g}'))
    lines = [f'  <ros2_control name={quoteattr(options.name)} type="system">',
             '    <hardware>',
             f'      <plugin>{TOPIC_BASED_SYSTEM}</plugin>',
             *(f'      <param name="{k}">{escape(v)}</param>' for k, v in params),
             '    </hardware>',
             f'    <joint name="{HUB_JOINT}">',
             *(f'      <command_interface name="{c}"/>' for c in options.command_interfaces),
             *(f'      <state_interface name="{s}"/>' for s in ('position', 'velocity',
                                                                  'effort')),
             '    </joint>',
             '  </ros2_control>']
    return '\n'.join(lines) + '\n'


def _joint(name: str, kind: str, parent: str, child: str, xyz: str, axis: str | None = None,
           limit: str | None = None) -> str:
    """A URDF ``<joint>`` element (its first line unindented, the rest by two spaces)."""
    lines = [f'<joint name="{name}" type="{kind}">', f'    <parent link="{parent}"/>',
             f'    <child link="{child}"/>', f'    <origin xyz="{xyz}" rpy="0 0 0"/>']
    if axis is not None:
        lines.append(f'    <axis xyz="{axis}"/>')
    if limit is not None:
        lines.append(f'    {limit}')
    return '\n'.join([*lines, '  </joint>'])


def _num(x) -> str:
    """A float as the shortest text that reads back as the same double."""
    return repr(float(x))


def _xyz(*values) -> str:
    return ' '.join(_num(v) for v in values)


def _rgba(color) -> str:
    return ' '.join(f'{c:g}' for c in color)


def urdf_text(params: RodParams, *, limits: DriveLimits = DEFAULT_LIMITS,
              disk_radius: float = DEFAULT_HUB_RADIUS,
              ros2_control: Ros2Control | None = None) -> str:
    """The URDF (XML text) of one rod: world, disk (``rotor``), rod, tip joints, mass.

    It carries the rod's description (:mod:`rotrod_core.model.description`): every
    parameter of ``params`` and the simulator's ``limits``, in a ``<rotrod>`` element
    (the hub joint's ``<limit>`` has the speed and torque limits too).
    ``disk_radius`` (m) is the drawn disk's, as the simulator's ``disk_radius``
    parameter; with ``ros2_control``, the URDF ends with that ``<ros2_control>`` block
    (:func:`ros2_control_block`). Raises ValueError for a batch of parameters (one
    URDF, one rod).
    """
    if params.is_batch:
        raise ValueError('urdf_text describes one rod: RodParams holds a batch')
    if not disk_radius > 0:
        raise ValueError(f'disk_radius must be > 0 m, got {disk_radius!r}')
    r0, length = float(params.eccentricity), float(params.rod_length)
    if params.section == 'rectangular':
        size = _xyz(params.section_width, params.section_thickness, length)
        rod_geometry = f'<box size="{size}"/>'
    else:
        rod_geometry = (f'<cylinder radius="{_num(0.5 * params.rod_diameter)}" '
                        f'length="{_num(length)}"/>')
    mass_radius = sphere_radius(float(params.mass))
    speeds = {TIP_RADIAL_JOINT: float(params.natural_frequency_radial) * length,
              TIP_TANGENTIAL_JOINT: float(params.natural_frequency_tangential) * length}

    def tip_limit(joint: str) -> str:
        return (f'<limit lower="{_num(-length)}" upper="{_num(length)}" effort="0.0" '
                f'velocity="{_num(speeds[joint])}"/>')

    def tilt_limit(joint: str) -> str:          # the slope's rate: 3/2 of u' / l
        return (f'<limit lower="{_num(-0.5 * math.pi)}" upper="{_num(0.5 * math.pi)}" '
                f'effort="0.0" velocity="{_num(speeds[joint] * TIP_SLOPE / length)}"/>')

    hub_limit = (f'<limit effort="{_num(limits.max_torque)}" '
                 f'velocity="{_num(limits.max_omega)}"/>')
    hub_joint = _joint(HUB_JOINT, 'continuous', WORLD_FRAME, ROTOR_FRAME, '0 0 0',
                       axis='0 0 1', limit=hub_limit)
    mount_joint = _joint(ROD_MOUNT_JOINT, 'fixed', ROTOR_FRAME, ROD_ROOT_FRAME, _xyz(r0, 0, 0))
    radial_joint = _joint(TIP_RADIAL_JOINT, 'prismatic', ROD_ROOT_FRAME, TIP_RADIAL_FRAME,
                          _xyz(0, 0, length), axis='1 0 0', limit=tip_limit(TIP_RADIAL_JOINT))
    tangential_joint = _joint(TIP_TANGENTIAL_JOINT, 'prismatic', TIP_RADIAL_FRAME,
                              TIP_TANGENTIAL_FRAME, '0 0 0', axis='0 1 0',
                              limit=tip_limit(TIP_TANGENTIAL_JOINT))
    pitch_joint = _joint(TIP_PITCH_JOINT, 'revolute', TIP_TANGENTIAL_FRAME, TIP_PITCH_FRAME,
                         '0 0 0', axis='0 1 0', limit=tilt_limit(TIP_RADIAL_JOINT))
    roll_joint = _joint(TIP_ROLL_JOINT, 'revolute', TIP_PITCH_FRAME, TIP_FRAME, '0 0 0',
                        axis='1 0 0', limit=tilt_limit(TIP_TANGENTIAL_JOINT))
    name = quoteattr(ROBOT_NAME)
    control = '' if ros2_control is None else '\n' + ros2_control_block(ros2_control)
    return f'''<?xml version="1.0"?>
<!-- Generated by rotrod_core.model.urdf (rotrod urdf): do not edit by hand.
     mass {_num(params.mass)} kg, rod_length {_num(length)} m, eccentricity r0 {_num(r0)} m,
     section {params.section}; joints hub (theta), tip_radial (u), tip_tangential (v),
     tip_pitch (a), tip_roll (-b: the tip tilted with the rod's slope, the IMU's frame)
     as published in joint_states by the rotrod simulator. -->
<robot name={name}>
  <material name="disk"><color rgba="{_rgba(DISK_COLOR)}"/></material>
  <material name="rod"><color rgba="{_rgba(ROD_COLOR)}"/></material>
  <material name="mass"><color rgba="{_rgba(MASS_COLOR)}"/></material>

  <link name="{WORLD_FRAME}"/>

  <link name="{ROTOR_FRAME}">
    <visual>
      <origin xyz="{_xyz(0, 0, -0.5 * DISK_THICKNESS)}" rpy="0 0 0"/>
      <geometry><cylinder radius="{_num(disk_radius)}" length="{_num(DISK_THICKNESS)}"/></geometry>
      <material name="disk"/>
    </visual>
  </link>
  {hub_joint}

  <link name="{ROD_ROOT_FRAME}">
    <visual>
      <origin xyz="{_xyz(0, 0, 0.5 * length)}" rpy="0 0 0"/>
      <geometry>{rod_geometry}</geometry>
      <material name="rod"/>
    </visual>
  </link>
  {mount_joint}

  <link name="{TIP_RADIAL_FRAME}"/>
  {radial_joint}

  <link name="{TIP_TANGENTIAL_FRAME}"/>
  {tangential_joint}

  <link name="{TIP_PITCH_FRAME}"/>
  {pitch_joint}

  <link name="{TIP_FRAME}">
    <visual>
      <origin xyz="0 0 0" rpy="0 0 0"/>
      <geometry><sphere radius="{_num(mass_radius)}"/></geometry>
      <material name="mass"/>
    </visual>
  </link>
  {roll_joint}

{description_element(params, limits)}{control}</robot>
'''


def _matches(key: str, full_name: str) -> bool:
    """Whether a parameter file's node key matches the node's fully qualified name.

    Keys: ``/**/name``, ``/ns/name``, ``name``. ``**`` is any number of namespace
    levels, ``*`` one level or part of a name; a key without a leading / is in the
    root namespace (as rclcpp reads it).
    """
    pattern = [p for p in key.split('/') if p]
    name = [p for p in full_name.split('/') if p]

    def match(i: int, j: int) -> bool:
        if i == len(pattern):
            return j == len(name)
        if pattern[i] == '**':
            return any(match(i + 1, k) for k in range(j, len(name) + 1))
        return j < len(name) and fnmatch.fnmatchcase(name[j], pattern[i]) and match(i + 1, j + 1)

    return match(0, 0)


def simulator_parameters(paths, *, node: str = SIMULATOR_NODE, namespace: str = '/') -> dict:
    """The parameters ROS 2 parameter files (``--params-file``) give a node.

    As the node named ``node`` in ``namespace`` gets them, the files applied in order
    (later ones win). Raises ValueError for a file that is not a parameter file.
    """
    import yaml

    full_name = '/'.join(['', *[p for p in namespace.split('/') if p], node])
    values: dict = {}
    for path in paths:
        try:
            doc = yaml.safe_load(Path(path).read_text())
        except yaml.YAMLError as exc:
            raise ValueError(f'{path}: not YAML: {exc}') from None
        if not isinstance(doc, dict):
            raise ValueError(f'{path}: not a ROS 2 parameter file (no node keys)')
        for key, body in doc.items():
            if not _matches(str(key), full_name):
                continue
            params = body.get('ros__parameters') if isinstance(body, dict) else None
            if not isinstance(params, dict):
                raise ValueError(f'{path}: {key}: no ros__parameters mapping')
            values.update(params)
    return values


def rod_params_from_files(paths, *, node: str = SIMULATOR_NODE,
                          namespace: str = '/') -> RodParams:
    """The RodParams of a simulator node from ROS 2 parameter files (``--params-file``).

    See :func:`simulator_parameters`; unset fields keep the defaults (Table 1). A
    section size of 0 means unused, as for the node. Raises ValueError for bad values.
    """
    given = simulator_parameters(paths, node=node, namespace=namespace)
    values = {k: v for k, v in given.items() if k in ROD_PARAM_NAMES}
    for name in ('section_width', 'section_thickness'):
        if values.get(name) == 0.0:
            values[name] = None
    return RodParams(**values)


def drive_limits_from_files(paths, *, namespace: str = '/') -> DriveLimits:
    """The simulator's limits the parameter files give it (else the defaults)."""
    given = simulator_parameters(paths, namespace=namespace)
    return dataclasses.replace(DEFAULT_LIMITS, **{
        f.name: given[f.name] for f in dataclasses.fields(DriveLimits) if f.name in given})


def urdf_for_parameter_files(paths, *, namespace: str = '/') -> str:
    """The URDF of the simulator node the parameter files configure (its disk_radius too)."""
    values = simulator_parameters(paths, namespace=namespace)
    return urdf_text(rod_params_from_files(paths, namespace=namespace),
                     limits=drive_limits_from_files(paths, namespace=namespace),
                     disk_radius=float(values.get('disk_radius', DEFAULT_HUB_RADIUS)))
