"""``simulation_interfaces/``: wire-compatible with the published standard, 2.1.0.

The repository holds the part of ros-simulation/simulation_interfaces for simulation
control and the entities of a multi-entity simulator (spawning, deleting, querying,
getting and setting their state), written with rotrod's comments; which of them the
simulator serves: docs/simulation_control.md. A client built against the published
package talks to it only if every type's hash (RIHS01, which Jazzy checks when it
matches endpoints) is the published one; a client that uses the constants needs them
equal too. Both references below were taken from the published files at tag 2.1.0
(commit 172a1b1c1b3ced62b99cddae9b4143e5bcddee8a of
github.com/ros-simulation/simulation_interfaces): :data:`PUBLISHED_DEFINITIONS` is the
SHA-256 of each file with its comments and spacing taken out (``normalized`` in
test/interface_tools.py: the fields, types, defaults, constants and their order remain);
:data:`PUBLISHED_HASHES` are the type hashes rosidl computed when the published package
(all of it) was built with tools/build_interfaces.py into a temporary prefix (the same
generators, pinned in constraints.txt).
"""

from interface_tools import PublishedCopyTests

PUBLISHED_DEFINITIONS = {
    'action/SimulateSteps.action':
        'baf7fb62155466e2be5675382f1e2418d8641f0e8467a1f2c9d874f6397926ae',
    'msg/Bounds.msg': '93a22c8fb85738c3668033bde005a323d69976f977bee7c78236c20620d4c706',
    'msg/EntityCategory.msg': '496ba8ba17bcf5f281df9776e6afee5bf99a35606e09ea43a79da9a6a7d66f6e',
    'msg/EntityFilters.msg': '6c064bd8e08c75dca8d8a5b49fe115a5bb5133e66eeae85026d2ede298b4e70e',
    'msg/EntityInfo.msg': 'f03457413bdc1c6d839c91a2ff26a6d7e9d51597a0fb3e14f32dcae2040bde96',
    'msg/EntityState.msg': '7a6c5ddc795501d3d3572719300a2c4699264c9ff534273a416382a1634779ad',
    'msg/Resource.msg': '1a4f647762137e8809d71f2137ab0503024029333dbd5640d471130a66fb3b47',
    'msg/Result.msg': '9cef7701ab7d2155f869403612a77f1b0ef18df0c891271f40017b84fe838c97',
    'msg/SimulationState.msg': 'db130fe8ab35cd166e5240d775749b17159895ed024be35269463d0a706deb43',
    'msg/SimulatorFeatures.msg':
        'ed1485d41bea2327cadd8dacfc65e76066a7491f8f37d5daddf172726008abe6',
    'msg/SpawnEntity.msg': '712ed84badb8a8c07c82a64ab04b83d9ebbac702cda4a76a94a21c1c80bd942b',
    'msg/SpawnResult.msg': '0a2c65e08aa1bed632dcccd30167ea762c197bbe9ba1394f3bd88c996bd5acf6',
    'msg/Spawnable.msg': 'c86551137175f57b71d2c97bc5d02eafbf84b9aaa69038b12ab48bed2660d0d1',
    'msg/TagsFilter.msg': 'd11e3a0795d50860cd669c44b29af5764620da54f8989c28a0c631f965d40b50',
    'srv/DeleteEntity.srv': '442eb0efcdbf23b59dffe98b9f9cc131cb57ce248049405083c5e4bb3bc906ab',
    'srv/GetEntities.srv': '56b658f93747caded28561e0f7cfb906f20f8fcd9c94d7a6556d3c39686c187a',
    'srv/GetEntitiesStates.srv':
        '4c36498cef417a9f697927e7a737d1f541c32f9c776a2f1c126a4c6a86a323bf',
    'srv/GetEntityBounds.srv': 'ab38c25a5ae13b72bd327a9c9df39a53e7401246a2d24498717d85ebeffa2d65',
    'srv/GetEntityInfo.srv': '78fb3e3bcc1cc4e588f36928bb6b7bf1cca38ccecdfcd42cb9eedc40aa9ee294',
    'srv/GetEntityState.srv': '5d60f1eeb5fe8ba69663e849d9d33296d1551c7ca01e3026e5e4e153c0fa5f96',
    'srv/GetSimulationState.srv':
        'c799fc4985009621013cafa3a4cfce0a8840c5ecda1e1762299ff5e6e306152c',
    'srv/GetSimulatorFeatures.srv':
        '2fe10bfdbbf409ce73b70e9cf8bcf8602e19147a44e14b82cf69a5b0ed3184f4',
    'srv/GetSpawnables.srv': 'a9c73ac20572c8cf2b6f15a9bee81b791ce4929e93b1a38f1b7e1a473fb9272c',
    'srv/ResetSimulation.srv': '0b76a81e471268750545302f43aa5e832ecf456cede644b112a2ff4b03371440',
    'srv/SetEntityState.srv': 'd1d23603a28dedab29f70b1c637e9a2f752bf09c8a19a16731ea61d896ef5e7c',
    'srv/SetSimulationState.srv':
        'b05d9a7f9eaacb6bebb0bed9ff408da3e1ccdf3b6f90c0a853734dda6950e088',
    'srv/SpawnEntities.srv': '9519f3228606b8c66a3b1877a8fb15d6383cc4fa2495650dcf85dc877bbe3dae',
    'srv/SpawnEntity.srv': 'b016ca55e30244bb1ee6fe8190e9fe7d5bd439dcb46fbc6a53c100157b3879a5',
    'srv/StepSimulation.srv': '4bc85e50f3f398709ceadc05691fbbd234192fa50b7263e15df8d74d4be4e637',
}
"""SHA-256 of the normalized published definitions, by file."""

PUBLISHED_HASHES = {
    'action/SimulateSteps':
        'RIHS01_f0837c898e1219cd73bf4c041feab41e8c533e8e1057e982744dba7b093467eb',
    'msg/Bounds': 'RIHS01_e8624fe51f0f5548197542697d924c5699ac7198f1e4c68e50c3ca2af73f5b3f',
    'msg/EntityCategory':
        'RIHS01_43bdf7933fddf75f6970f7a8fe7078524355d821d390b3954bb46ac36c03dfe1',
    'msg/EntityFilters': 'RIHS01_8e7b12e8ea062f14c55de4877221fe1b7cd9749665a7ad8a4ab855fc4b148303',
    'msg/EntityInfo': 'RIHS01_3b9a2e7fa00f9a59d325b6e47904044c421561a385682027c7fc06c359806319',
    'msg/EntityState': 'RIHS01_2e0464a85eb80a939025075d6c20761eca6a4cb9d6baf2c0ba373467c8b598d0',
    'msg/Resource': 'RIHS01_2bb1939cf80f8d2f284afba53cbec60b5ff33759bd39b714128ea8867a34c51a',
    'msg/Result': 'RIHS01_cf43a306adff3337a0a47143d8f5689933bc70a30478f13b077dc1fe3bc5ad17',
    'msg/SimulationState':
        'RIHS01_bb9f87ccdd98fba113052a512d9801e84ce732d0a2b3c2b0cb281828de36e415',
    'msg/SimulatorFeatures':
        'RIHS01_8b101c8529bc0ea3dcf056078254768f39832b9ef0adaf93bd5cea96c0de3305',
    'msg/SpawnEntity': 'RIHS01_94a349a865ccf673c18c080520299c88c3d8d5f4842ecf1482d6c997ac4b69f9',
    'msg/SpawnResult': 'RIHS01_dbc277304b6c24bfb2a631cea8f52e2b005d583ec0a6c86b11613f5ce6486da1',
    'msg/Spawnable': 'RIHS01_8675aa686f0df1ed7874a6ec210fdce1ac1c07f4e49fc26ec7fb6fe729f6772e',
    'msg/TagsFilter': 'RIHS01_5c3efc51e8ed04c266c09cb4691ec95b964cd410558e01d8c83646b038826b45',
    'srv/DeleteEntity': 'RIHS01_ff7e96a5b83dc8e2bb34b8b034480028b3a24d9f8376b2c0590bac3704be3e28',
    'srv/GetEntities': 'RIHS01_cb90004c48cd50f37732fb008e22c34c261dd680a723bf0f85d8437ea4498bf7',
    'srv/GetEntitiesStates':
        'RIHS01_0a76170d0c1c90e1eaf805cfab78ea801d1f82df309a28c1f0fae4b570f19754',
    'srv/GetEntityBounds':
        'RIHS01_17be8d36231178a5eed0de0344b55c19975581627a9aec30a4fee9926a35deed',
    'srv/GetEntityInfo': 'RIHS01_953b7ab6bfc35063f5c9a72463c6ce489baa10249a7fa510926d342a34b0d29e',
    'srv/GetEntityState':
        'RIHS01_749c91f2a2353d98367b64f2995a0f5842ce92a08ec1ffb3e185540a91557fb5',
    'srv/GetSimulationState':
        'RIHS01_3362dcebee4b1afebbf9c4beee5c79c1455385aded62092a892d61fde8644f30',
    'srv/GetSimulatorFeatures':
        'RIHS01_abb9439c8cf196722a469fb6c68b44b484f198c2a1356ac38849a29c2a20a794',
    'srv/GetSpawnables': 'RIHS01_3e25fd827d8bcbd9db5e36ccb190efa22d6f6313897861268ab923bf091a992a',
    'srv/ResetSimulation':
        'RIHS01_4ce285d7ff9b8ac70dcc95161f32bf54c05a6f4b13427990e41ab40c36c39646',
    'srv/SetEntityState':
        'RIHS01_fba636c91d38832dbd4f6896ffce54ff98fd9929962b0533546b56ce00f988ac',
    'srv/SetSimulationState':
        'RIHS01_a868b916dce49974f637ba252141258c4b07b0c06858b88af560e3eb6bfbcb30',
    'srv/SpawnEntities': 'RIHS01_41703a359ee032bf4fc230f144f531705ba039a2e97edeae1f7997dd83b04857',
    'srv/SpawnEntity': 'RIHS01_66860313e11009faddbfc8568e5d410d1a11607fe75eeb1308671dc0406fe3a7',
    'srv/StepSimulation':
        'RIHS01_913fe0653690ce6bf8f09f316e6a626747012e9fca31e26719910d417aa8565c',
}
"""The published package's type hash of each type (its top-level entry)."""


class TestThePublishedCopy(PublishedCopyTests):
    PACKAGE = 'simulation_interfaces'
    VERSION = '2.1.0'
    DEFINITIONS = PUBLISHED_DEFINITIONS
    HASHES = PUBLISHED_HASHES


def test_the_generated_classes_carry_the_standards_constants_and_defaults():
    from simulation_interfaces.msg import (
        Bounds,
        EntityCategory,
        Result,
        SimulatorFeatures,
        SpawnResult,
        TagsFilter,
    )
    from simulation_interfaces.srv import (
        ResetSimulation,
        SetEntityState,
        SetSimulationState,
        SpawnEntities,
        SpawnEntity,
        StepSimulation,
    )
    assert (Result.RESULT_OK, Result.RESULT_INCORRECT_STATE) == (1, 3)
    assert SimulatorFeatures.STEP_SIMULATION_ACTION == 33
    assert SimulatorFeatures.SPAWNING_ENTITIES == 50
    assert ResetSimulation.Request.SCOPE_ALL == 255
    assert SetSimulationState.Response.INCORRECT_TRANSITION == 103
    assert StepSimulation.Request().steps == 1
    assert SpawnEntity.Response.INVALID_POSE == SpawnResult.INVALID_POSE == 109
    assert SpawnEntities.Response.ENTITIES_SPAWN_FAILED == 150
    assert SetEntityState.Response.INVALID_POSE == 101
    assert (EntityCategory.CATEGORY_HUMAN, EntityCategory.CATEGORY_STATIC_OBJECT) == (2, 5)
    assert (Bounds.TYPE_EMPTY, Bounds.TYPE_SPHERE) == (0, 3)
    assert TagsFilter.FILTER_MODE_ALL == 1


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


def test_the_entity_types_round_trip_through_rclpys_serialization():
    from geometry_msgs.msg import Vector3
    from rclpy.serialization import deserialize_message, serialize_message
    from simulation_interfaces.msg import Bounds, EntityCategory, SpawnEntity
    from simulation_interfaces.srv import GetEntitiesStates, SpawnEntities
    request = GetEntitiesStates.Request()
    request.filters.filter = '^tip$'
    request.filters.categories = [EntityCategory(category=EntityCategory.CATEGORY_ROBOT)]
    request.filters.tags.tags = ['rod']
    request.filters.bounds = Bounds(type=Bounds.TYPE_SPHERE,
                                    points=[Vector3(), Vector3(x=0.5)])
    back = deserialize_message(serialize_message(request), GetEntitiesStates.Request)
    assert back.filters == request.filters
    spawn = SpawnEntities.Request(spawn_requests=[SpawnEntity(name='rod', allow_renaming=True)])
    spawn.spawn_requests[0].entity_resource.uri = 'package://rotrod/urdf/rotrod.urdf'
    back = deserialize_message(serialize_message(spawn), SpawnEntities.Request)
    assert back.spawn_requests[0].entity_resource.uri.endswith('rotrod.urdf')
    assert back.spawn_requests[0].allow_renaming
