"""A world of rods in one simulator (issue #36), through the executable, against closed forms.

``rods:=N`` starts N rods named rod0... with their interfaces under rodK/; rods come and
go through simulation_interfaces' SpawnEntity and DeleteEntity, each from the URDF of
``rotrod urdf`` with its own physical parameters. Each rod's steady deflection at its
own speed is the closed form of docs/model.md for that rod, u_s = m w^2 r0 / (k - m w^2)
with k = 3 E I / l^3 written out here; a rod that halts or takes NaN disturbs nobody;
every refusal has the standard's code and a sentence and changes nothing.
"""

import math
import subprocess

import numpy as np
import pytest
from geometry_msgs.msg import PointStamped, PoseStamped, Vector3Stamped
from node_probes import namespace, start_simulator
from rclpy.qos import QoSProfile
from sensor_msgs.msg import JointState
from simulation_interfaces.msg import EntityFilters, Resource, Result, SimulationState
from simulation_interfaces.msg import SpawnEntity as SpawnRequest
from simulation_interfaces.srv import (
    DeleteEntity,
    GetEntities,
    GetEntitiesStates,
    GetEntityState,
    GetSimulatorFeatures,
    ResetSimulation,
    SetEntityState,
    SetSimulationState,
    SpawnEntities,
    SpawnEntity,
)
from std_msgs.msg import Float64

pytestmark = pytest.mark.ros

E, D, L, R0 = 100e9, 0.003, 0.3, 0.1                    # Table 1 (docs/model.md)
K = 3 * E * (math.pi * D**4 / 64) / L**3


def static_deflection(m, w, r0=R0):
    """docs/model.md: u_s = m w^2 r0 / (k - m w^2), m."""
    return m * w * w * r0 / (K - m * w * w)


def urdf(*options) -> str:
    """The URDF ``rotrod urdf`` writes for the options (as a user pipes it)."""
    from rotrod_ros.install import executable
    return subprocess.run([*executable('rotrod'), 'urdf', *options], check=True,
                          capture_output=True, text=True).stdout


def spawn(ros_node, sim, name, text, x=0.0, **fields):
    request = SpawnEntity.Request(name=name, entity_resource=Resource(resource_string=text),
                                  **fields)
    request.initial_pose.pose.position.x = x
    request.initial_pose.pose.orientation.w = 1.0
    return ros_node.call_service(SpawnEntity, f'{sim}/spawn_entity', request)


def command(ros_node, topic, w):
    """Send setpoint ``w`` on ``topic`` once its subscriber is there (a few times: the
    first may leave before the subscriber has matched the publisher)."""
    pub = ros_node.node.create_publisher(Float64, topic, 10)
    ros_node.spin_until(lambda: pub.get_subscription_count() > 0, 10, topic)
    for _ in range(3):
        pub.publish(Float64(data=w))
        ros_node.spin_for(0.1)
    return pub


def stamp_of(msg) -> float:
    return msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9


def settled(ros_node, joints, seconds=14.0):
    """Spin until every rod has run ``seconds`` of simulated time from now: its ramp (at
    0.5 rad/s^2) and ten decay times of its free whirl (damping ratio 0.1)."""
    ros_node.spin_until(lambda: all(joints.values()), 30, 'joint_states of every rod')
    start = max(stamp_of(j[-1]) for j in joints.values())
    ros_node.spin_until(lambda: all(stamp_of(j[-1]) >= start + seconds
                                    for j in joints.values()), 90,
                        f'{seconds:g} s of simulated time')


def steady(ros_node, joint, seconds=1.0):
    """The mean radial deflection u over the last ``seconds`` of joint_states, m."""
    ros_node.spin_for(0.2)
    t_end = joint[-1].header.stamp.sec + joint[-1].header.stamp.nanosec * 1e-9
    u = [m.position[1] for m in joint
         if m.header.stamp.sec + m.header.stamp.nanosec * 1e-9 >= t_end - seconds]
    return float(np.mean(u))


def test_n_rods_each_under_its_namespace_deflect_as_the_closed_form(
        ros_processes, ros_node, request):
    ns = namespace(request)
    sim = start_simulator(ros_processes, ns, 'table1.yaml', rods=3, damping_ratio=0.1,
                          markers=False, estimate_window=0.0, real_time_factor=4.0)
    speeds = {'rod0': 1.0, 'rod1': 2.0, 'rod2': 3.0}
    joints = {name: ros_node.subscribe(f'{ns}/{name}/joint_states', JointState, qos=1000)
              for name in speeds}
    frames = ros_node.subscribe(f'{ns}/rod1/tip/deflection', Vector3Stamped, qos=10)
    positions = ros_node.subscribe(f'{ns}/rod2/tip/position', PointStamped, qos=10)
    for name, w in speeds.items():
        command(ros_node, f'{ns}/{name}/cmd/omega', w)
    settled(ros_node, joints)
    for name, w in speeds.items():
        assert joints[name][-1].velocity[0] == w
        assert steady(ros_node, joints[name]) == pytest.approx(static_deflection(0.3, w),
                                                               rel=2e-3), name
    assert frames[-1].header.frame_id == 'rod1/rotor'
    assert positions[-1].header.frame_id == 'world'
    assert 'ready: 3 rods (rod0, rod1, rod2)' in sim.output


@pytest.mark.long   # the default run has the same through the standard's own client
                    # (test_simulation_control.py); CI's long run has this one too
def test_rods_spawned_with_their_own_masses_deflect_as_their_closed_forms_and_go(
        ros_processes, ros_node, request):
    ns = namespace(request)
    start_simulator(ros_processes, ns, 'table1.yaml', markers=False, estimate_window=0.0,
                    real_time_factor=4.0)
    sim = f'{ns}/rotrod_simulator'
    features = ros_node.call_service(GetSimulatorFeatures, f'{sim}/get_simulator_features')
    assert list(features.features.spawn_formats) == ['urdf']
    masses = {f'm{i}': 0.15 + 0.05 * i for i in range(10)}
    speeds = {name: 1.0 + 0.1 * i for i, name in enumerate(masses)}
    texts = {name: urdf('--mass', str(m), '--damping-ratio', '0.1') for name, m in
             masses.items()}
    reply = ros_node.call_service(SpawnEntities, f'{sim}/spawn_entities',
                                  SpawnEntities.Request(spawn_requests=[
                                      SpawnRequest(name=name, entity_resource=Resource(
                                          resource_string=texts[name]))
                                      for name in masses]))
    assert reply.result.result == Result.RESULT_OK, reply.result.error_message
    assert [r.entity_name for r in reply.results] == list(masses)
    entities = ros_node.call_service(GetEntities, f'{sim}/get_entities',
                                     GetEntities.Request(filters=EntityFilters(filter='^m[0-9]$')))
    assert list(entities.entities) == list(masses)
    joints = {name: ros_node.subscribe(f'{ns}/{name}/joint_states', JointState, qos=1000)
              for name in masses}
    for name, w in speeds.items():
        command(ros_node, f'{ns}/{name}/cmd/omega', w)
    settled(ros_node, joints)
    for name, w in speeds.items():
        assert steady(ros_node, joints[name]) == pytest.approx(
            static_deflection(masses[name], w), rel=2e-3), name
    # the tip's state through the standard: at r0 + u_s in the rotating frame
    tip = ros_node.call_service(GetEntityState, f'{sim}/get_entity_state',
                                GetEntityState.Request(entity='m3/tip'))
    assert tip.result.result == Result.RESULT_OK
    p = tip.state.pose.position
    assert math.hypot(p.x, p.y) == pytest.approx(R0 + static_deflection(masses['m3'], 1.3),
                                                 rel=1e-3)
    states = ros_node.call_service(GetEntitiesStates, f'{sim}/get_entities_states',
                                   GetEntitiesStates.Request(
                                       filters=EntityFilters(filter='/hub$')))
    hubs = dict(zip(states.entities, states.states))
    assert hubs['m7/hub'].twist.angular.z == pytest.approx(1.7)
    for name in masses:
        done = ros_node.call_service(DeleteEntity, f'{sim}/delete_entity',
                                     DeleteEntity.Request(entity=name))
        assert done.result.result == Result.RESULT_OK
    left = ros_node.call_service(GetEntities, f'{sim}/get_entities', GetEntities.Request())
    assert list(left.entities) == ['hub', 'tip']


BAD_SPAWNS = [
    ({'name': 'a b'}, SpawnEntity.Response.NAME_INVALID, 'name'),
    ({'name': 'dup'}, SpawnEntity.Response.NAME_NOT_UNIQUE, "already named 'dup'"),
    ({'name': 'n', 'entity_namespace': 'bad ns'}, SpawnEntity.Response.NAMESPACE_INVALID,
     'not a ROS namespace'),
    ({'name': 'n', 'text': '<robot name="x"><link name="world"/></robot>'},
     SpawnEntity.Response.RESOURCE_PARSE_ERROR, 'no <rotrod> element'),
    ({'name': 'n', 'text': 'mass="0.3"', 'mass': 'x'}, SpawnEntity.Response.RESOURCE_PARSE_ERROR,
     "mass='heavy' is not a number"),
    ({'name': 'n', 'text': '<sdf version="1.9"><model name="x"/></sdf>'},
     SpawnEntity.Response.UNSUPPORTED_FORMAT, 'SDFormat'),
    ({'name': 'n', 'text': ''}, SpawnEntity.Response.NO_RESOURCE, 'neither a uri'),
    ({'name': 'n', 'tilt': True}, SpawnEntity.Response.INVALID_POSE, 'tilts'),
]


def test_bad_spawns_get_the_standard_codes_and_the_world_keeps_stepping(
        ros_processes, ros_node, request):
    ns = namespace(request)
    start_simulator(ros_processes, ns, 'table1.yaml', markers=False, max_rods=3)
    sim = f'{ns}/rotrod_simulator'
    good = urdf()
    assert spawn(ros_node, sim, 'dup', good).result.result == Result.RESULT_OK
    joint = ros_node.subscribe(f'{ns}/joint_states', JointState, qos=1000)
    for fields, code, sentence in BAD_SPAWNS:
        fields = dict(fields)
        text = fields.pop('text', good)
        if fields.pop('mass', None):
            text = good.replace('mass="0.3"', 'mass="heavy"')
        tilt = fields.pop('tilt', False)
        req = SpawnEntity.Request(entity_resource=Resource(resource_string=text), **fields)
        req.initial_pose.pose.orientation.w = 1.0
        if tilt:
            req.initial_pose.pose.orientation.x = 0.3
            req.initial_pose.pose.orientation.w = math.sqrt(1 - 0.09)
        reply = ros_node.call_service(SpawnEntity, f'{sim}/spawn_entity', req)
        assert reply.result.result == code and sentence in reply.result.error_message, (
            fields, reply.result)
    n = len(joint)
    ros_node.spin_until(lambda: len(joint) > n + 50, 10, 'the world steps on')
    left = ros_node.call_service(GetEntities, f'{sim}/get_entities', GetEntities.Request())
    assert list(left.entities) == ['hub', 'tip', 'dup', 'dup/hub', 'dup/tip']
    # the bound on the world's rods, and a delete of an unknown rod
    assert spawn(ros_node, sim, 'two', good).result.result == Result.RESULT_OK
    third = spawn(ros_node, sim, 'three', good)
    assert third.result.result == Result.RESULT_OPERATION_FAILED
    assert 'max_rods 3' in third.result.error_message
    gone = ros_node.call_service(DeleteEntity, f'{sim}/delete_entity',
                                 DeleteEntity.Request(entity='nobody'))
    assert gone.result.result == Result.RESULT_NOT_FOUND
    # a reset with SCOPE_SPAWNED removes the spawned rods, keeps the first
    reset = ros_node.call_service(ResetSimulation, f'{sim}/reset_simulation',
                                  ResetSimulation.Request(scope=ResetSimulation.Request.SCOPE_ALL))
    assert reset.result.result == Result.RESULT_OK
    left = ros_node.call_service(GetEntities, f'{sim}/get_entities', GetEntities.Request())
    assert list(left.entities) == ['hub', 'tip']


def test_a_rod_that_takes_nan_or_halts_disturbs_nobody(ros_processes, ros_node, request):
    ns = namespace(request)
    sim = start_simulator(ros_processes, ns, 'table1.yaml', rods=2, markers=False,
                          estimate_window=0.0, real_time_factor=10.0)
    joints = {name: ros_node.subscribe(f'{ns}/{name}/joint_states', JointState, qos=1000)
              for name in ('rod0', 'rod1')}
    command(ros_node, f'{ns}/rod0/cmd/omega', 1.0)
    wild = command(ros_node, f'{ns}/rod1/cmd/omega', math.nan)     # refused, with a warning
    wild.publish(Float64(data=13.0))                  # past w0: the deflection grows
    settled(ros_node, joints, 40.0)
    sim.wait_for_output('rod1: simulation halted', timeout=10)
    w1 = joints['rod1'][-1].velocity[0]
    n = len(joints['rod1'])
    ros_node.spin_for(1.0)
    assert len(joints['rod1']) > n + 50                # still published, frozen
    assert all(m.velocity[0] == w1 for m in joints['rod1'][n:])
    assert abs(joints['rod1'][-1].position[1]) <= 0.03    # at its last good state
    assert 'rod1 rejected' in sim.output or 'rejected: omega setpoint' in sim.output
    # rod0 went on, unmoved by either: exactly its own 1 rad/s throughout
    assert all(m.velocity[0] == 1.0 for m in joints['rod0'][-3000:])


def test_spawn_pose_places_the_rod_in_the_shared_world_frame(ros_processes, ros_node,
                                                              request):
    ns = namespace(request)
    start_simulator(ros_processes, ns, 'table1.yaml', markers=False, start_paused=True)
    sim = f'{ns}/rotrod_simulator'
    req = SpawnEntity.Request(name='far', entity_resource=Resource(resource_string=urdf()))
    req.initial_pose = PoseStamped()
    req.initial_pose.header.frame_id = 'world'
    req.initial_pose.pose.position.x, req.initial_pose.pose.position.y = 2.0, -1.0
    yaw = 0.7
    req.initial_pose.pose.orientation.z = math.sin(yaw / 2)
    req.initial_pose.pose.orientation.w = math.cos(yaw / 2)
    assert ros_node.call_service(SpawnEntity, f'{sim}/spawn_entity',
                                 req).result.result == Result.RESULT_OK
    tip = ros_node.call_service(GetEntityState, f'{sim}/get_entity_state',
                                GetEntityState.Request(entity='far/tip')).state
    assert (tip.pose.position.x, tip.pose.position.y, tip.pose.position.z) == pytest.approx(
        (2.0 + R0 * math.cos(yaw), -1.0 + R0 * math.sin(yaw), L), abs=1e-12)


@pytest.mark.long   # 17 s: in CI's long run, to keep the default run under 15 minutes
def test_a_thousand_spawns_are_each_answered_and_the_world_keeps_its_rate(
        ros_processes, ros_node, request):
    """1000 SpawnEntity requests at once against max_rods 20: 19 spawned, 981 refused
    with the bound in a sentence; meanwhile the first rod publishes every 10 ms of its
    simulated time (real time), none missing."""
    ns = namespace(request)
    start_simulator(ros_processes, ns, 'table1.yaml', markers=False, estimate_window=0.0,
                    max_rods=20)
    sim = f'{ns}/rotrod_simulator'
    joint = ros_node.subscribe(f'{ns}/joint_states', JointState, qos=1000)
    text = urdf()
    spawn(ros_node, sim, 'warm', text)                 # the client discovered, warmed up
    # the requests all at once: the client's queue holds their answers
    client = ros_node.node.create_client(SpawnEntity, f'{sim}/spawn_entity',
                                         qos_profile=QoSProfile(depth=1000))
    ros_node.spin_until(client.service_is_ready, 10, 'spawn_entity')
    ros_node.spin_until(lambda: len(joint) > 10, 10, 'joint_states')
    first = len(joint)
    futures = []
    for i in range(1000):
        req = SpawnEntity.Request(name=f'r{i}',
                                  entity_resource=Resource(resource_string=text))
        req.initial_pose.pose.orientation.w = 1.0
        futures.append(client.call_async(req))
    ros_node.spin_until(lambda: all(f.done() for f in futures), 120, '1000 answers')
    codes = [f.result().result.result for f in futures]
    assert codes.count(Result.RESULT_OK) == 18                 # 20 with the first and warm
    refused = [f.result().result for f in futures
               if f.result().result.result != Result.RESULT_OK]
    assert len(refused) == 982 and all(
        r.result == Result.RESULT_OPERATION_FAILED and 'max_rods 20' in r.error_message
        for r in refused)
    ros_node.spin_for(0.5)
    stamps = np.array([stamp_of(m) for m in joint[first:]])
    steps = np.diff(stamps) / 0.01
    assert len(stamps) > 100 and np.allclose(steps, 1.0, atol=1e-3), steps.max()


def test_set_entity_state_moves_a_hub_and_a_tip_and_the_rod_goes_on_from_there(
        ros_processes, ros_node, request):
    ns = namespace(request)
    start_simulator(ros_processes, ns, 'table1.yaml', markers=False, estimate_window=0.0,
                    start_paused=True, real_time_factor=4.0)
    sim = f'{ns}/rotrod_simulator'
    damped = urdf('--damping-ratio', '0.1')
    assert spawn(ros_node, sim, 'far', damped, x=1.0).result.result == Result.RESULT_OK
    hub = SetEntityState.Request(entity='far/hub', set_twist=True)
    hub.state.twist.angular.z = 1.5
    assert ros_node.call_service(SetEntityState, f'{sim}/set_entity_state',
                                 hub).result.result == Result.RESULT_OK
    tip = SetEntityState.Request(entity='far/tip', set_pose=True)
    tip.state.header.frame_id = 'world'
    tip.state.pose.position.x = 1.0 + R0 + 2e-3        # u = 2 mm at hub angle 0
    tip.state.pose.position.z = L
    assert ros_node.call_service(SetEntityState, f'{sim}/set_entity_state',
                                 tip).result.result == Result.RESULT_OK
    got = ros_node.call_service(GetEntityState, f'{sim}/get_entity_state',
                                GetEntityState.Request(entity='far/tip')).state
    assert (got.pose.position.x, got.pose.position.y) == pytest.approx((1.0 + R0 + 2e-3, 0.0),
                                                                       abs=1e-12)
    assert got.twist.angular.z == 1.5
    # refused, nothing changed: an acceleration; a tip off its rod's plane
    bad = SetEntityState.Request(entity='far/hub', set_acceleration=True)
    assert ros_node.call_service(SetEntityState, f'{sim}/set_entity_state',
                                 bad).result.result == Result.RESULT_OPERATION_FAILED
    tip.state.pose.position.z = 2 * L
    answer = ros_node.call_service(SetEntityState, f'{sim}/set_entity_state', tip).result
    assert answer.result == SetEntityState.Response.INVALID_POSE and 'height' in \
        answer.error_message
    # the rod goes on from the state set, holding 1.5 rad/s: it settles at u_s there
    joint = ros_node.subscribe(f'{ns}/far/joint_states', JointState, qos=1000)
    ros_node.call_service(SetSimulationState, f'{sim}/set_simulation_state',
                          SetSimulationState.Request(state=SimulationState(
                              state=SimulationState.STATE_PLAYING)))
    settled(ros_node, {'far': joint}, 12.0)
    assert all(m.velocity[0] == 1.5 for m in joint)
    assert steady(ros_node, joint) == pytest.approx(static_deflection(0.3, 1.5), rel=2e-3)
