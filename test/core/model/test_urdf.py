"""The URDF: its transforms are the simulation's.

Read with pytransform3d's UrdfTransformManager (a maintained URDF library from PyPI,
not a parser of our own): forward kinematics of the ``tip`` frame against the closed
form (r0 + u, v, l) turned by theta about z, and against ``tip/position`` of a real
simulator process over a spin-up, with the joints set from its ``joint_states``.
"""

import math
import subprocess
import sys
from pathlib import Path
from xml.etree import ElementTree

import numpy as np
import pytest
from pytransform3d.urdf import UrdfTransformManager
from reference import R0, L

from rotrod_core.command.joint_command import MalformedJointCommand, hub_command
from rotrod_core.live.engine import EngineConfig
from rotrod_core.model import interface
from rotrod_core.model.params import RodParams
from rotrod_core.model.urdf import (
    SHIPPED_FILE,
    Ros2Control,
    rod_params_from_files,
    ros2_control_block,
    simulator_parameters,
    urdf_for_parameter_files,
    urdf_text,
)
from rotrod_ros.demo import PARAM_FILES

ROOT = Path(__file__).resolve().parents[3]
SHIPPED = ROOT / SHIPPED_FILE
FK_TOLERANCE = 1e-9
"""m: the issue's bound between the URDF's tip and tip/position."""


def transform_manager(text: str) -> UrdfTransformManager:
    tm = UrdfTransformManager()
    tm.load_urdf(text)
    return tm


def tip_by_fk(tm, theta, u, v, frame='world'):
    tm.set_joint('hub', theta)
    tm.set_joint('tip_radial', u)
    tm.set_joint('tip_tangential', v)
    return tm.get_transform('tip', frame)[:3, 3]


def test_the_urdfs_tip_frame_is_the_imus_tilted_frame():
    """With the joints joint_states publishes (the tilt joints from the state), the
    URDF's ``tip`` frame (pytransform3d's forward kinematics) is the IMU's frame
    (rotrod_core.sensors.imu, written apart): the same rotation, at the mass; and its z
    axis is the rod's tangent at the tip, (3/2 u/l, 3/2 v/l, 1) normalised, turned by
    theta."""
    from scipy.spatial.transform import Rotation

    from rotrod_core.model.equations import Coefficients, State
    from rotrod_core.sensors.imu import imu_reading
    params = RodParams()
    co = Coefficients.from_params(params)
    tm = transform_manager(urdf_text(params))
    rng = np.random.default_rng(5)
    for _ in range(20):
        u, v = rng.uniform(-0.02, 0.02, 2)
        theta = rng.uniform(-7, 7)
        state = State(u, v, 0.1, -0.2, theta, 2.0)
        positions, *_ = interface.joint_values(state, 0.0, L)
        for name, q in zip(interface.JOINT_NAMES, positions):
            tm.set_joint(name, q)
        frame = tm.get_transform('tip', 'world')
        imu = Rotation.from_quat(imu_reading(co, state, 0.0, L, 0.0).orientation).as_matrix()
        assert np.allclose(frame[:3, :3], imu, rtol=0, atol=1e-12)
        assert np.allclose(frame[:3, 3], tip_closed_form(R0, L, theta, u, v), atol=1e-12)
        tangent = np.array([1.5 * u / L, 1.5 * v / L, 1.0])
        c, s = math.cos(theta), math.sin(theta)
        turned = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ (tangent /
                                                                np.linalg.norm(tangent))
        assert np.allclose(frame[:3, 2], turned, atol=1e-12)


def tip_closed_form(r0, length, theta, u, v):
    """docs/model.md: the mass at (r0 + u) e1 + v e2 + l e3, e1 at angle theta."""
    return np.array([(r0 + u) * math.cos(theta) - v * math.sin(theta),
                     (r0 + u) * math.sin(theta) + v * math.cos(theta), length])


def test_the_shipped_urdf_is_the_generators_for_table1_and_the_demos_parameter_files():
    assert SHIPPED.read_text() == urdf_text(RodParams())
    # what launch/demo.launch.py gives robot_state_publisher
    assert urdf_for_parameter_files([ROOT / f for f in PARAM_FILES]) == SHIPPED.read_text()


def test_rotrod_urdf_writes_the_shipped_file_and_other_parameters(tmp_path):
    out = tmp_path / 'rod.urdf'
    cmd = [sys.executable, '-m', 'rotrod_core.cli', 'urdf']
    subprocess.run([*cmd, '--params-file', str(ROOT / 'config' / 'table1.yaml'), '-o',
                    str(out)], check=True, cwd=ROOT, capture_output=True)
    assert out.read_text() == SHIPPED.read_text()
    printed = subprocess.run([*cmd, '--eccentricity', '0.05', '--rod-length', '0.25'],
                             check=True, cwd=ROOT, capture_output=True, text=True).stdout
    tm = transform_manager(printed)
    assert tip_by_fk(tm, 0.0, 0.0, 0.0) == pytest.approx([0.05, 0.0, 0.25], abs=1e-15)
    bad = subprocess.run([*cmd, '--rod-length', '-1'], cwd=ROOT, capture_output=True,
                         text=True)
    assert bad.returncode == 2 and 'rod_length' in bad.stderr


def test_frames_and_joints_form_the_documented_tree():
    root = ElementTree.fromstring(SHIPPED.read_text())
    links = {e.get('name') for e in root.iter('link')}
    assert links == {interface.WORLD_FRAME, interface.ROTOR_FRAME, interface.ROD_ROOT_FRAME,
                     interface.TIP_RADIAL_FRAME, interface.TIP_TANGENTIAL_FRAME,
                     interface.TIP_PITCH_FRAME, interface.TIP_FRAME}
    joints = {e.get('name'): (e.get('type'), e.find('parent').get('link'),
                              e.find('child').get('link'),
                              e.find('axis').get('xyz') if e.find('axis') is not None else None)
              for e in root.iter('joint')}
    assert joints == {
        'hub': ('continuous', 'world', 'rotor', '0 0 1'),
        'rod_mount': ('fixed', 'rotor', 'rod_root', None),
        'tip_radial': ('prismatic', 'rod_root', 'tip_radial_link', '1 0 0'),
        'tip_tangential': ('prismatic', 'tip_radial_link', 'tip_tangential_link', '0 1 0'),
        'tip_pitch': ('revolute', 'tip_tangential_link', 'tip_pitch_link', '0 1 0'),
        'tip_roll': ('revolute', 'tip_pitch_link', 'tip', '1 0 0'),
    }
    movable = [name for name, (kind, *_) in joints.items() if kind != 'fixed']
    assert tuple(movable) == interface.JOINT_NAMES
    # the frames the simulator stamps its messages with are links of the URDF
    assert {interface.WORLD_FRAME, interface.ROTOR_FRAME} <= links
    for joint in root.iter('joint'):
        if joint.get('type') == 'prismatic':
            limit = joint.find('limit')
            assert float(limit.get('lower')) == -L and float(limit.get('upper')) == L


@pytest.mark.parametrize('r0, length', [(R0, L), (0.0, 0.5), (0.37, 0.12)])
def test_forward_kinematics_is_the_closed_form(r0, length):
    tm = transform_manager(urdf_text(RodParams(eccentricity=r0, rod_length=length)))
    rng = np.random.default_rng(7)
    for theta, u, v in zip(rng.uniform(-50, 50, 40), rng.uniform(-0.03, 0.03, 40),
                           rng.uniform(-0.03, 0.03, 40)):
        tip = tip_by_fk(tm, theta, u, v)
        assert np.max(np.abs(tip - tip_closed_form(r0, length, theta, u, v))) < 1e-15
        # in the rotating frame: (r0 + u, v, l) whatever theta (tip/deflection's frame)
        assert tip_by_fk(tm, theta, u, v, 'rotor') == pytest.approx(
            [r0 + u, v, length], abs=1e-15)
        assert tm.get_transform('rod_root', 'rotor')[:3, 3] == pytest.approx(
            [r0, 0.0, 0.0], abs=0)


def test_a_rectangular_rod_is_drawn_as_a_box_and_a_batch_is_refused():
    params = RodParams(section='rectangular', section_width=0.004, section_thickness=0.002)
    root = ElementTree.fromstring(urdf_text(params))
    (box,) = root.iter('box')
    assert [float(x) for x in box.get('size').split()] == [0.004, 0.002, L]
    with pytest.raises(ValueError, match='batch'):
        urdf_text(RodParams(eccentricity=np.array([0.1, 0.2])))
    with pytest.raises(ValueError, match='disk_radius'):
        urdf_text(RodParams(), disk_radius=0.0)


def topic_based_system_write(block, values):
    """The JointState TopicBasedSystem::write publishes for a <ros2_control> block.

    As topic_based_ros2_control's source does: every joint of the block in ``name`` in
    block order; each command interface's value appended to its field (``values``:
    interface -> value).
    """
    fields = {'position': [], 'velocity': [], 'effort': []}
    names = []
    for joint in block.iter('joint'):
        names.append(joint.get('name'))
        for command in joint.iter('command_interface'):
            fields[command.get('name')].append(values[command.get('name')])
    return names, fields['position'], fields['velocity'], fields['effort']


@pytest.mark.parametrize('interfaces', [('velocity',), ('effort',), ('effort', 'velocity')])
def test_the_ros2_control_block_is_topic_based_systems_for_the_hub(interfaces):
    options = Ros2Control(interfaces, '/rod1/joint_command', '/rod1/joint_states')
    text = urdf_text(RodParams(), ros2_control=options)
    without = text.replace(ros2_control_block(options), '')
    assert without.replace('\n\n</robot>', '\n</robot>') == SHIPPED.read_text()
    root = ElementTree.fromstring(text)
    (block,) = root.iter('ros2_control')
    assert block.get('type') == 'system'
    assert block.find('hardware/plugin').text == 'topic_based_ros2_control/TopicBasedSystem'
    params = {e.get('name'): e.text for e in block.iter('param')}
    assert params == {'joint_commands_topic': '/rod1/joint_command',
                      'joint_states_topic': '/rod1/joint_states',
                      'trigger_joint_command_threshold': '-1'}
    joints = {j.get('name'): ([c.get('name') for c in j.iter('command_interface')],
                              [s.get('name') for s in j.iter('state_interface')])
              for j in block.iter('joint')}
    # the hub alone: with the passive tip joints in the block, TopicBasedSystem would name
    # them in its commands without entries, against JointState's contract
    assert tuple(joints) == (interface.HUB_JOINT,)
    assert joints['hub'] == (list(interfaces), ['position', 'velocity', 'effort'])
    # the URDF's kinematics are unchanged by the block
    tm = transform_manager(text)
    assert tip_by_fk(tm, 1.0, 0.001, 0.002) == pytest.approx(
        tip_closed_form(R0, L, 1.0, 0.001, 0.002), abs=1e-15)
    # what the interface sends for this block is the hub's command
    message = topic_based_system_write(block, {'velocity': 1.25, 'effort': -0.03})
    assert all(len(field) in (0, len(message[0])) for field in message[1:])
    for drive, expected in (('velocity', ('omega', 1.25)), ('torque', ('torque', -0.03))):
        wanted = {'velocity': 'velocity', 'torque': 'effort'}[drive]
        if wanted in interfaces:
            assert hub_command(*message, drive) == expected
        else:
            with pytest.raises(MalformedJointCommand, match='ignored: drive is'):
                hub_command(*message, drive)


def test_ros2_control_options_are_checked_and_rotrod_urdf_adds_the_block():
    for bad in ((), ('position',), ('velocity', 'velocity')):
        with pytest.raises(ValueError, match='command_interfaces'):
            Ros2Control(bad)
    with pytest.raises(ValueError, match='joint_states_topic must be an absolute'):
        Ros2Control(joint_states_topic='joint_states')
    cmd = [sys.executable, '-m', 'rotrod_core.cli', 'urdf']
    printed = subprocess.run([*cmd, '--ros2-control', 'velocity', '--ros2-control', 'effort',
                              '--joint-commands-topic', '/r/joint_command'], check=True,
                             cwd=ROOT, capture_output=True, text=True).stdout
    assert printed == urdf_text(RodParams(), ros2_control=Ros2Control(
        ('velocity', 'effort'), '/r/joint_command'))
    bad = subprocess.run([*cmd, '--joint-states-topic', '/x'], cwd=ROOT, capture_output=True,
                         text=True)
    assert bad.returncode == 2 and 'go with --ros2-control' in bad.stderr


def test_the_ros2_control_example_configures_the_simulator_and_the_hubs_controllers():
    import yaml
    path = ROOT / 'config' / 'ros2_control_example.yaml'
    sim = simulator_parameters([path], namespace='/rotrod')
    assert sim == {'drive': 'velocity', 'command_timeout': 0.5}
    EngineConfig(drive=sim['drive'], command_timeout=sim['command_timeout'])   # accepted
    assert simulator_parameters([path]) == {}          # not the root namespace's simulator
    doc = yaml.safe_load(path.read_text())
    manager = doc['controller_manager']['ros__parameters']
    types = {name: v['type'] for name, v in manager.items() if isinstance(v, dict)}
    assert types == {
        'joint_state_broadcaster': 'joint_state_broadcaster/JointStateBroadcaster',
        'hub_velocity_controller': 'velocity_controllers/JointGroupVelocityController',
        'hub_trajectory_controller': 'joint_trajectory_controller/JointTrajectoryController',
        'hub_effort_controller': 'effort_controllers/JointGroupEffortController'}
    for name in types:
        if name != 'joint_state_broadcaster':
            assert doc[name]['ros__parameters']['joints'] == ['hub']
    jtc = doc['hub_trajectory_controller']['ros__parameters']
    # a velocity command interface alone needs position and velocity states (JTC's docs)
    assert jtc['command_interfaces'] == ['velocity']
    assert set(jtc['state_interfaces']) == {'position', 'velocity'}


def test_parameter_files_apply_in_order_to_the_named_node_in_its_namespace(tmp_path):
    a = tmp_path / 'a.yaml'
    a.write_text('/**:\n  ros__parameters:\n    eccentricity: 0.2\n    rod_length: 0.4\n'
                 '/rod1/rotrod_simulator:\n  ros__parameters:\n    eccentricity: 0.05\n'
                 '/**/other_node:\n  ros__parameters:\n    rod_length: 9.0\n'
                 'rotrod_simulator:\n  ros__parameters:\n    mass: 0.5\n'
                 '    publish_rate: 50.0\n    section_width: 0.0\n')
    p = rod_params_from_files([a])
    assert (p.eccentricity, p.rod_length, p.mass) == (0.2, 0.4, 0.5)
    rod1 = rod_params_from_files([a], namespace='/rod1')
    assert (rod1.eccentricity, rod1.mass) == (0.05, 0.3)   # 'rotrod_simulator': root only
    assert rod_params_from_files([a], namespace='/rod2').eccentricity == 0.2
    b = tmp_path / 'b.yaml'
    b.write_text('/*/rotrod_simulator:\n  ros__parameters:\n    rod_length: 0.35\n')
    assert rod_params_from_files([a, b], namespace='/rod1').rod_length == 0.35
    assert rod_params_from_files([a, b]).rod_length == 0.4        # /* needs one level
    c = tmp_path / 'c.yaml'
    c.write_text('/**/rotrod_simulator:\n  ros__parameters:\n    disk_radius: 0.25\n')
    (cylinder,) = [e for e in ElementTree.fromstring(urdf_for_parameter_files([a, c])).iter(
        'cylinder') if e.get('length') == '0.01']                 # the disk
    assert float(cylinder.get('radius')) == 0.25
    bad = tmp_path / 'bad.yaml'
    bad.write_text('- 1\n')
    with pytest.raises(ValueError, match='not a ROS 2 parameter file'):
        rod_params_from_files([bad])
    bad.write_text('/**:\n  ros__parameters:\n    rod_length: -1.0\n')
    with pytest.raises(ValueError, match='rod_length'):
        rod_params_from_files([bad])


# ------------------------------------------------------------------ a real simulator run
@pytest.mark.ros
def test_the_urdfs_tip_is_tip_position_over_a_spin_up(ros_processes, ros_node, request):
    from geometry_msgs.msg import PointStamped, Vector3Stamped
    from node_probes import collect, namespace, omega_publisher, stamp, start_simulator
    from sensor_msgs.msg import JointState
    from std_msgs.msg import Float64

    ns = namespace(request)
    start_simulator(ros_processes, ns, 'table1.yaml', real_time_factor=4.0)
    joints = collect(ros_node, f'{ns}/joint_states', JointState)
    positions = collect(ros_node, f'{ns}/tip/position', PointStamped)
    deflections = collect(ros_node, f'{ns}/tip/deflection', Vector3Stamped)
    ros_node.spin_until(lambda: len(joints) > 5, 20, 'joint_states')
    omega_publisher(ros_node, ns).publish(Float64(data=2.0))   # a 4 s ramp at 0.5 rad/s^2
    ros_node.spin_until(lambda: joints[-1][0].velocity[0] == 2.0, 30, 'w = 2 rad/s')
    at_speed = stamp(joints[-1][0])     # then 4 rad turned: 3 s more at 2 rad/s is 10 rad
    ros_node.spin_until(lambda: stamp(joints[-1][0]) > at_speed + 3.0, 30, '3 s at speed')

    graph = dict(ros_node.node.get_topic_names_and_types())
    for topic, msgtype in interface.TOPICS.items():
        name = topic if topic.startswith('/') else f'{ns}/{topic}'
        if topic != '/clock':        # /clock: real_time_factor 4 publishes it too
            assert graph[name] == [msgtype], topic

    tm = transform_manager(SHIPPED.read_text())
    by_stamp = {stamp(m): m for m, *_ in positions}
    defl_by_stamp = {stamp(m): m for m, *_ in deflections}
    errors, rotor_errors, thetas, us = [], [], [], []
    for msg, *_ in joints:
        assert list(msg.name) == list(interface.JOINT_NAMES)
        assert list(msg.effort)[1:] == [0.0] * 4
        t = stamp(msg)
        if t not in by_stamp or t not in defl_by_stamp:    # subscribed at different times
            continue
        theta, u, v = msg.position[:3]
        point = by_stamp[t]
        assert point.header.frame_id == interface.WORLD_FRAME
        fk = tip_by_fk(tm, theta, u, v)
        errors.append(np.max(np.abs(fk - [point.point.x, point.point.y, point.point.z])))
        d = defl_by_stamp[t]
        assert d.header.frame_id == interface.ROTOR_FRAME
        rotor = tip_by_fk(tm, theta, u, v, 'rotor')
        rotor_errors.append(np.max(np.abs(rotor - [R0 + d.vector.x, d.vector.y, L])))
        thetas.append(theta)
        us.append(u)
    print(f'{len(errors)} matched stamps, theta up to {max(thetas):.3f} rad, u up to '
          f'{1e3 * max(us):.4f} mm; max |FK - tip/position| = {max(errors):.2e} m, '
          f'max |FK in rotor - (r0 + u, v, l)| = {max(rotor_errors):.2e} m')
    assert len(errors) >= 0.95 * len(joints) and len(errors) > 500
    assert max(thetas) > 8.0 and max(us) > 2.5e-3           # the hub turned, the rod bent
    assert max(errors) <= FK_TOLERANCE
    assert max(rotor_errors) <= FK_TOLERANCE
