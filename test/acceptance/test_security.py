"""Security posture (docs/security.md): SROS2 settings fail closed here.

The nodes take an SROS2 enclave like any rclpy node. With ``ROS_SECURITY_STRATEGY=Enforce``
a node must not run unsecured: it refuses to start when its enclave is missing from the
keystore (rcl), and when the enclave's files cannot give it security. The PyPI wheels'
Fast DDS has no DDS Security at all: their rmw refuses any enclave ("This Fast DDS version
doesn't have the security libraries"); a ROS install whose Fast DDS has it refuses the
placeholder (empty) files used here. A secured run is not tested (no sros2 in the venv).
"""

import pytest
from ros_harness import ros_arguments

pytestmark = pytest.mark.ros

ENCLAVE = '/rotrod/simulator'
FILES = ('identity_ca.cert.pem', 'cert.pem', 'key.pem', 'permissions_ca.cert.pem',
         'governance.p7s', 'permissions.p7s')


def enforce(keystore) -> dict:
    return {'ROS_SECURITY_ENABLE': 'true', 'ROS_SECURITY_STRATEGY': 'Enforce',
            'ROS_SECURITY_KEYSTORE': str(keystore)}


def start(ros_processes, env):
    return ros_processes.start_console_script(
        'simulator', *ros_arguments(params={'markers': False}), '--enclave', ENCLAVE,
        extra_env=env)


def test_enforce_without_the_enclave_in_the_keystore_refuses_to_start(ros_processes,
                                                                       tmp_path):
    sim = start(ros_processes, enforce(tmp_path / 'keystore'))
    assert sim.wait(timeout=30) != 0
    assert 'SECURITY ERROR' in sim.output and 'enclaves/rotrod/simulator' in sim.output
    assert 'ready' not in sim.output


def test_enforce_with_an_enclave_it_cannot_use_refuses_to_start(ros_processes, tmp_path):
    enclave = tmp_path / 'keystore' / 'enclaves' / 'rotrod' / 'simulator'
    enclave.mkdir(parents=True)
    for name in FILES:
        (enclave / name).write_text('')
    sim = start(ros_processes, enforce(tmp_path / 'keystore'))
    assert sim.wait(timeout=30) != 0
    assert 'ready' not in sim.output
    assert 'security' in sim.output.lower()


def test_the_enclave_argument_alone_changes_nothing(ros_processes, tmp_path):
    sim = start(ros_processes, {'ROS_SECURITY_KEYSTORE': str(tmp_path / 'keystore')})
    sim.wait_for_output('ready', timeout=30)
    assert sim.stop() == 0
