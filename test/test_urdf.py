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

from rotrod_core.model import interface
from rotrod_core.model.params import RodParams
from rotrod_core.model.urdf import (
    SHIPPED_FILE,
    rod_params_from_files,
    urdf_for_parameter_files,
    urdf_text,
)
from rotrod_ros.demo import PARAM_FILES

ROOT = Path(__file__).resolve().parent.parent
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
                     interface.TIP_RADIAL_FRAME, interface.TIP_FRAME}
    joints = {e.get('name'): (e.get('type'), e.find('parent').get('link'),
                              e.find('child').get('link'),
                              e.find('axis').get('xyz') if e.find('axis') is not None else None)
              for e in root.iter('joint')}
    assert joints == {
        'hub': ('continuous', 'world', 'rotor', '0 0 1'),
        'rod_mount': ('fixed', 'rotor', 'rod_root', None),
        'tip_radial': ('prismatic', 'rod_root', 'tip_radial_link', '1 0 0'),
        'tip_tangential': ('prismatic', 'tip_radial_link', 'tip', '0 1 0'),
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
    ros_node.spin_until(lambda: stamp(joints[-1][0]) > stamp(joints[0][0]) + 7.0, 30, '7 s')

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
        assert list(msg.effort)[1:] == [0.0, 0.0]
        t = stamp(msg)
        if t not in by_stamp or t not in defl_by_stamp:    # subscribed at different times
            continue
        theta, u, v = msg.position
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
