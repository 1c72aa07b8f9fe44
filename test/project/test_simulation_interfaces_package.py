"""``simulation_interfaces/``: wire-compatible with the published standard, 2.1.0.

The repository holds the part of ros-simulation/simulation_interfaces that the
simulator serves, written with rotrod's comments. A client built against the
published package talks to it only if every type's hash (RIHS01, which Jazzy checks
when it matches endpoints) is the published one; a client that uses the constants
needs them equal too. Both references below were taken from the published files at
tag 2.1.0 (commit 172a1b1c1b3ced62b99cddae9b4143e5bcddee8a of
github.com/ros-simulation/simulation_interfaces): :data:`PUBLISHED_DEFINITIONS` is the
SHA-256 of each file with its comments and spacing taken out (:func:`normalized`: the
fields, types, defaults, constants and their order remain); :data:`PUBLISHED_HASHES`
are the type hashes rosidl computed when those files were built with
tools/build_interfaces.py (the same generators, pinned in constraints.txt).
"""

import hashlib
import json
import re
import sys
from pathlib import Path

import pytest
from interface_tools import build_interfaces

ROOT = Path(__file__).resolve().parents[2]
SOURCE = ROOT / 'simulation_interfaces'
PREFIX = Path(sys.prefix)
SHARE = PREFIX / 'share' / 'simulation_interfaces'

PUBLISHED_DEFINITIONS = {
    'action/SimulateSteps.action':
        'baf7fb62155466e2be5675382f1e2418d8641f0e8467a1f2c9d874f6397926ae',
    'msg/EntityState.msg': '7a6c5ddc795501d3d3572719300a2c4699264c9ff534273a416382a1634779ad',
    'msg/Result.msg': '9cef7701ab7d2155f869403612a77f1b0ef18df0c891271f40017b84fe838c97',
    'msg/SimulationState.msg':
        'db130fe8ab35cd166e5240d775749b17159895ed024be35269463d0a706deb43',
    'msg/SimulatorFeatures.msg':
        'ed1485d41bea2327cadd8dacfc65e76066a7491f8f37d5daddf172726008abe6',
    'srv/GetEntityState.srv': '5d60f1eeb5fe8ba69663e849d9d33296d1551c7ca01e3026e5e4e153c0fa5f96',
    'srv/GetSimulationState.srv':
        'c799fc4985009621013cafa3a4cfce0a8840c5ecda1e1762299ff5e6e306152c',
    'srv/GetSimulatorFeatures.srv':
        '2fe10bfdbbf409ce73b70e9cf8bcf8602e19147a44e14b82cf69a5b0ed3184f4',
    'srv/ResetSimulation.srv': '0b76a81e471268750545302f43aa5e832ecf456cede644b112a2ff4b03371440',
    'srv/SetSimulationState.srv':
        'b05d9a7f9eaacb6bebb0bed9ff408da3e1ccdf3b6f90c0a853734dda6950e088',
    'srv/StepSimulation.srv': '4bc85e50f3f398709ceadc05691fbbd234192fa50b7263e15df8d74d4be4e637',
}
"""SHA-256 of :func:`normalized` published definitions, by file."""

PUBLISHED_HASHES = {
    'action/SimulateSteps':
        'RIHS01_f0837c898e1219cd73bf4c041feab41e8c533e8e1057e982744dba7b093467eb',
    'msg/EntityState': 'RIHS01_2e0464a85eb80a939025075d6c20761eca6a4cb9d6baf2c0ba373467c8b598d0',
    'msg/Result': 'RIHS01_cf43a306adff3337a0a47143d8f5689933bc70a30478f13b077dc1fe3bc5ad17',
    'msg/SimulationState':
        'RIHS01_bb9f87ccdd98fba113052a512d9801e84ce732d0a2b3c2b0cb281828de36e415',
    'msg/SimulatorFeatures':
        'RIHS01_8b101c8529bc0ea3dcf056078254768f39832b9ef0adaf93bd5cea96c0de3305',
    'srv/GetEntityState':
        'RIHS01_749c91f2a2353d98367b64f2995a0f5842ce92a08ec1ffb3e185540a91557fb5',
    'srv/GetSimulationState':
        'RIHS01_3362dcebee4b1afebbf9c4beee5c79c1455385aded62092a892d61fde8644f30',
    'srv/GetSimulatorFeatures':
        'RIHS01_abb9439c8cf196722a469fb6c68b44b484f198c2a1356ac38849a29c2a20a794',
    'srv/ResetSimulation':
        'RIHS01_4ce285d7ff9b8ac70dcc95161f32bf54c05a6f4b13427990e41ab40c36c39646',
    'srv/SetSimulationState':
        'RIHS01_a868b916dce49974f637ba252141258c4b07b0c06858b88af560e3eb6bfbcb30',
    'srv/StepSimulation':
        'RIHS01_913fe0653690ce6bf8f09f316e6a626747012e9fca31e26719910d417aa8565c',
}
"""The published package's type hash of each type (its top-level entry)."""




def normalized(text: str) -> str:
    """A definition without comments, blank lines and spacing: what goes on the wire."""
    out = []
    for line in text.splitlines():
        line = line.split('#', 1)[0].strip()
        if line:
            out.append(re.sub(r'\s+', ' ', re.sub(r'\s*=\s*', '=', line)))
    return '\n'.join(out)


def _files():
    return sorted(str(p.relative_to(SOURCE)) for p in SOURCE.glob('*/*')
                  if p.suffix in ('.msg', '.srv', '.action'))


def test_the_package_holds_the_served_types_and_cmake_generates_each():
    assert _files() == sorted(PUBLISHED_DEFINITIONS)
    cmake = (SOURCE / 'CMakeLists.txt').read_text()
    listed = re.findall(r'"((?:msg|srv|action)/\w+\.(?:msg|srv|action))"', cmake)
    assert sorted(listed) == _files()
    xml = (SOURCE / 'package.xml').read_text()
    assert '<name>simulation_interfaces</name>' in xml and '<version>2.1.0</version>' in xml


@pytest.mark.parametrize('name', sorted(PUBLISHED_DEFINITIONS))
def test_each_definition_is_the_published_one_but_for_comments(name):
    text = normalized((SOURCE / name).read_text())
    assert hashlib.sha256(text.encode()).hexdigest() == PUBLISHED_DEFINITIONS[name], text


def test_the_venv_holds_the_build_of_the_current_sources():
    stamp = PREFIX / build_interfaces.stamp_name('simulation_interfaces')
    assert stamp.is_file(), 'run.sh builds simulation_interfaces before the tests'
    assert stamp.read_text().strip() == build_interfaces.source_digest(SOURCE)


@pytest.mark.parametrize('name', sorted(PUBLISHED_HASHES))
def test_each_built_type_carries_the_published_type_hash(name):
    description = json.loads((SHARE / f'{name}.json').read_text())
    hashes = {h['type_name']: h['hash_string'] for h in description['type_hashes']}
    assert hashes[f'simulation_interfaces/{name}'] == PUBLISHED_HASHES[name]


def test_the_generated_classes_carry_the_standards_constants_and_defaults():
    from simulation_interfaces.msg import Result, SimulatorFeatures
    from simulation_interfaces.srv import ResetSimulation, SetSimulationState, StepSimulation
    assert (Result.RESULT_OK, Result.RESULT_INCORRECT_STATE) == (1, 3)
    assert SimulatorFeatures.STEP_SIMULATION_ACTION == 33
    assert ResetSimulation.Request.SCOPE_ALL == 255
    assert SetSimulationState.Response.INCORRECT_TRANSITION == 103
    assert StepSimulation.Request().steps == 1


def test_a_request_round_trips_through_rclpys_serialization():
    from rclpy.serialization import deserialize_message, serialize_message
    from simulation_interfaces.action import SimulateSteps
    from simulation_interfaces.srv import GetEntityState
    response = GetEntityState.Response()
    response.state.pose.position.x = 0.125
    response.result.error_message = 'ok'
    back = deserialize_message(serialize_message(response), GetEntityState.Response)
    assert back.state.pose.position.x == 0.125 and back.result.error_message == 'ok'
    feedback = SimulateSteps.Feedback(completed_steps=2**63, remaining_steps=1)
    assert deserialize_message(serialize_message(feedback),
                               SimulateSteps.Feedback).completed_steps == 2**63
