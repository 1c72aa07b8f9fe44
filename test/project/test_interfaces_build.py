"""The message package ``rotrod_interfaces``, built into the venv by tools/build_interfaces.py.

``./run.sh test`` builds it (when its files, the script or the pins changed) before
pytest starts, so these tests check the build the user gets: the venv holds the build
of the current sources; every message and the action import, round-trip through
rclpy's serialization (the C type support) and carry the type hash rosidl computed,
which is also what a publisher announces on the graph; the exported CMake files no
longer point at the wheels' build machine.
"""

import json
import math
import re
import sys
from pathlib import Path

import pytest
from interface_tools import build_interfaces

ROOT = Path(__file__).resolve().parents[2]
SOURCE = ROOT / 'rotrod_interfaces'
PREFIX = Path(sys.prefix)
SHARE = PREFIX / 'share' / 'rotrod_interfaces'
HASH = re.compile(r'RIHS01_[0-9a-f]{64}')




def _interfaces():
    """(kind, name) of every .msg and .action file in the package's source."""
    return sorted((p.parent.name, p.stem) for p in SOURCE.glob('*/*')
                  if p.suffix in ('.msg', '.action'))


def test_the_package_declares_what_cmake_generates():
    cmake = (SOURCE / 'CMakeLists.txt').read_text()
    listed = re.findall(r'"((?:msg|action)/\w+\.(?:msg|action))"', cmake)
    assert sorted(listed) == sorted(f'{k}/{n}.{k}' for k, n in _interfaces())
    assert {'msg', 'action'} == {k for k, _ in _interfaces()}


def test_the_venv_holds_the_build_of_the_current_sources():
    stamp = PREFIX / build_interfaces.STAMP
    assert stamp.is_file(), 'run.sh builds rotrod_interfaces before the tests'
    assert stamp.read_text().strip() == build_interfaces.source_digest()
    for kind, name in _interfaces():
        installed = SHARE / kind / f'{name}.{kind}'
        assert installed.read_text() == (SOURCE / kind / f'{name}.{kind}').read_text()


def test_exported_cmake_paths_are_pointed_at_this_machine_once(tmp_path):
    cmake = tmp_path / 'share' / 'std_msgs' / 'cmake' / 'export.cmake'
    cmake.parent.mkdir(parents=True)
    cmake.write_text('INTERFACE_INCLUDE_DIRECTORIES "/opt/python/cp312-cp312/include/'
                     'python3.12;/opt/python/cp312-cp312/lib/python3.12/site-packages/'
                     'numpy/_core/include"\n')
    other = cmake.with_name('other.cmake')
    other.write_text('set(x "/opt/ros/jazzy")\n')
    assert build_interfaces.fix_exported_paths(tmp_path, '/py/include', '/np/include') == 1
    assert cmake.read_text() == 'INTERFACE_INCLUDE_DIRECTORIES "/py/include;/np/include"\n'
    assert other.read_text() == 'set(x "/opt/ros/jazzy")\n'
    assert build_interfaces.fix_exported_paths(tmp_path, '/py/include', '/np/include') == 0


def test_the_venvs_exported_cmake_files_name_no_build_machine_paths():
    stale = [p for p in (PREFIX / 'share').rglob('*.cmake') if '/opt/python/' in p.read_text()]
    assert stale == []


def test_a_missing_compiler_is_named(monkeypatch):
    monkeypatch.setattr(build_interfaces.shutil, 'which',
                        lambda name: None if name == 'c++' else '/usr/bin/' + name)
    with pytest.raises(build_interfaces.BuildError, match=r'no c\+\+ on PATH.*g\+\+'):
        build_interfaces._check_compilers()


def _samples():
    from builtin_interfaces.msg import Time
    from rotrod_interfaces.action import SpinUp
    from rotrod_interfaces.msg import DynamicFrequencies, RigEstimate, WhirlEstimate
    from std_msgs.msg import Header
    header = Header(stamp=Time(sec=12, nanosec=345), frame_id='')
    return [
        DynamicFrequencies(header=header, omega=2.0, f1=1.613061, f2=2.249681),
        WhirlEstimate(header=header, f1=1.6, f2=math.nan, f1_std=1e-3, f2_std=math.nan,
                      f1_valid=True, f2_valid=False, reason='not stationary', window=1.0,
                      samples=100),
        RigEstimate(header=header, natural_frequency=12.1, natural_frequency_std=0.01,
                    eccentricity=0.1, eccentricity_std=1e-4, damping_ratio=0.001,
                    damping_ratio_std=1e-4, deflection_limit=0.003, critical_speed=2.07,
                    critical_speed_step=1.47, stiffness=44.2, stiffness_deviation=0.001,
                    residual_rms=1e-6, window=5.0),
        SpinUp.Goal(omega_target=2.0, profile=SpinUp.Goal.PLANNED, deflection_limit=0.003),
        SpinUp.Feedback(omega=1.0, deflection=0.002, phase='spinning'),
        SpinUp.Result(reached=True, message='ok', duration=3.0, peak_deflection=0.0029,
                      residual_whirl=1e-5, predicted_residual=1e-5),
    ]


@pytest.mark.parametrize('index', range(6))
def test_messages_round_trip_through_rclpys_serialization(index):
    from rclpy.serialization import deserialize_message, serialize_message
    msg = _samples()[index]
    back = deserialize_message(serialize_message(msg), type(msg))
    for name in msg.get_fields_and_field_types():
        a, b = getattr(msg, name), getattr(back, name)
        assert a == b or (a != a and b != b), name           # NaN stays NaN


@pytest.mark.parametrize('kind,name', _interfaces())
def test_each_interface_carries_its_type_hash(kind, name):
    description = json.loads((SHARE / kind / f'{name}.json').read_text())
    hashes = {h['type_name']: h['hash_string'] for h in description['type_hashes']}
    assert HASH.fullmatch(hashes[f'rotrod_interfaces/{kind}/{name}'])


@pytest.mark.ros
def test_a_publisher_announces_the_type_and_its_hash(ros_node):
    from rotrod_interfaces.msg import DynamicFrequencies
    node = ros_node.node
    node.create_publisher(DynamicFrequencies, 'typed_frequencies', 10)
    (info,) = node.get_publishers_info_by_topic('typed_frequencies')
    assert info.topic_type == 'rotrod_interfaces/msg/DynamicFrequencies'
    description = json.loads((SHARE / 'msg' / 'DynamicFrequencies.json').read_text())
    assert str(info.topic_type_hash) == description['type_hashes'][0]['hash_string']


def _ros_install_providing(package: str, tmp_path: Path, monkeypatch) -> Path:
    """A stand-in for a sourced ROS install that provides ``package``: a directory on
    PYTHONPATH holding it. Returns the package's directory."""
    fake = tmp_path / 'opt_ros' / package
    fake.mkdir(parents=True)
    (fake / '__init__.py').write_text('')
    monkeypatch.setenv('PYTHONPATH', str(fake.parent))
    return fake


def test_a_package_the_venv_imports_from_elsewhere_is_not_built(tmp_path, monkeypatch):
    """A sourced ROS install's simulation_interfaces (here: a directory on PYTHONPATH)
    is used instead of a build; the venv's own build is not 'elsewhere'."""
    assert build_interfaces.provided_elsewhere('simulation_interfaces', PREFIX) is None
    fake = _ros_install_providing('simulation_interfaces', tmp_path, monkeypatch)
    found = build_interfaces.provided_elsewhere('simulation_interfaces', PREFIX)
    assert found is not None and Path(found).parent == fake
    assert build_interfaces.stamp_name('simulation_interfaces') != build_interfaces.STAMP


def test_the_distributions_control_msgs_is_used_and_none_built(tmp_path, monkeypatch,
                                                                capsys):
    """On a ROS install control_msgs comes with the distribution (all of it, where the
    repository has the FollowJointTrajectory part): the build tool leaves it alone."""
    assert 'control_msgs' in build_interfaces.PACKAGES
    _ros_install_providing('control_msgs', tmp_path, monkeypatch)

    def no_build(*args, **kwargs):
        raise AssertionError(f'built {kwargs.get("package")}')

    monkeypatch.setattr(build_interfaces, 'ensure_built', no_build)
    argv = ['--prefix', str(PREFIX), '--package', 'control_msgs', '--no-install']
    assert build_interfaces.main(argv) == 0
    assert 'rotrod: control_msgs comes from' in capsys.readouterr().err
