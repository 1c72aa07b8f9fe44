"""A simulation_interfaces client that knows nothing of rotrod: the standard's calls only.

Run by test/ros/test_simulation_control.py against a running simulator, with the
``simulation_interfaces`` package on its path that the test chose (the venv's, or one
built separately into another prefix). Imports rclpy, std_msgs, rosgraph_msgs and
simulation_interfaces; nothing of rotrod. Prints one JSON line (prefix ``@@REPORT@@``)
with what it saw; the test judges it.

The scenario: the features; pause; a full reset (time 0); the command 2 rad/s on
cmd/omega; 2000 steps by StepSimulation, 1000 by SimulateSteps (feedback kept); the
tip's state after each; bad requests (each answered with its code, nothing changed);
a cancelled SimulateSteps; a full reset and the same again; play. With ``--world FILE``
(JSON: rods, each a name, a URDF file, a speed and an x), then a world: pause; spawn the
rods by SpawnEntities from their URDF files (uri), each at its x; command each its
speed on <name>/cmd/omega; step; every tip's state by GetEntitiesStates; a SimulateSteps
goal during which the first rod is deleted (then cancelled); delete the rest.

Usage: python sim_interfaces_client.py [--simulator /rotrod_simulator] [--omega 2.0]
       [--world FILE]
"""

import argparse
import json
import sys
import time

import rclpy
import simulation_interfaces
from rclpy.action import ActionClient
from rclpy.executors import SingleThreadedExecutor
from rclpy.qos import QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from simulation_interfaces.action import SimulateSteps
from simulation_interfaces.msg import EntityFilters, Resource, Result, SimulationState
from simulation_interfaces.msg import SpawnEntity as SpawnRequest
from simulation_interfaces.srv import (
    DeleteEntity,
    GetEntities,
    GetEntitiesStates,
    GetEntityState,
    GetSimulationState,
    GetSimulatorFeatures,
    ResetSimulation,
    SetSimulationState,
    SpawnEntities,
    StepSimulation,
)
from std_msgs.msg import Float64

TIMEOUT = 60.0


def loaded_libraries(name: str) -> list:
    """Paths of the shared libraries mapped into this process whose name has ``name``."""
    with open('/proc/self/maps') as maps:
        paths = {line.split()[-1] for line in maps if name in line and '/' in line}
    return sorted(paths)


class Client:
    """The calls, each waited for (the executor spun meanwhile)."""

    def __init__(self, simulator: str):
        self.node = rclpy.create_node('sim_interfaces_client')
        self.executor = SingleThreadedExecutor()
        self.executor.add_node(self.node)
        n, s = self.node, simulator.rstrip('/')
        self.clients = {
            'features': n.create_client(GetSimulatorFeatures, f'{s}/get_simulator_features'),
            'get_state': n.create_client(GetSimulationState, f'{s}/get_simulation_state'),
            'set_state': n.create_client(SetSimulationState, f'{s}/set_simulation_state'),
            'step': n.create_client(StepSimulation, f'{s}/step_simulation'),
            'reset': n.create_client(ResetSimulation, f'{s}/reset_simulation'),
            'entity': n.create_client(GetEntityState, f'{s}/get_entity_state'),
            'spawn': n.create_client(SpawnEntities, f'{s}/spawn_entities'),
            'delete': n.create_client(DeleteEntity, f'{s}/delete_entity'),
            'entities': n.create_client(GetEntities, f'{s}/get_entities'),
            'states': n.create_client(GetEntitiesStates, f'{s}/get_entities_states'),
        }
        self.action = ActionClient(n, SimulateSteps, f'{s}/simulate_steps')
        reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
        self.omega = n.create_publisher(Float64, 'cmd/omega', reliable)
        self.clock: list = []
        n.create_subscription(Clock, '/clock', lambda m: self.clock.append(
            m.clock.sec * 10**9 + m.clock.nanosec), 100)

    def close(self) -> None:
        """Destroy the action client, then the node (rclpy's destroy_node leaves action
        clients alive, and with them the DDS participant past the process's exit)."""
        self.action.destroy()
        self.node.destroy_node()

    def wait_for(self, done, what: str):
        deadline = time.monotonic() + TIMEOUT
        while not done():
            if time.monotonic() > deadline:
                raise TimeoutError(what)
            self.executor.spin_once(timeout_sec=0.05)

    def call(self, name: str, request):
        client = self.clients[name]
        self.wait_for(lambda: client.service_is_ready(), f'service {client.srv_name}')
        future = client.call_async(request)
        self.wait_for(future.done, f'{client.srv_name} answer')
        return future.result()

    def command(self, omega: float) -> None:
        """Publish a setpoint and wait until the simulator has acknowledged it."""
        self.wait_for(lambda: self.omega.get_subscription_count() > 0, 'cmd/omega subscriber')
        self.omega.publish(Float64(data=omega))
        if not self.omega.wait_for_all_acked(rclpy.duration.Duration(seconds=TIMEOUT)):
            raise TimeoutError('cmd/omega not acknowledged')

    def simulate(self, steps: int, cancel_after: int | None = None) -> dict:
        """SimulateSteps; its feedback, status and result (cancelled after that many
        feedback messages, if given)."""
        self.wait_for(lambda: self.action.server_is_ready(), 'simulate_steps server')
        feedback: list = []
        sent = self.action.send_goal_async(
            SimulateSteps.Goal(steps=steps),
            feedback_callback=lambda m: feedback.append(
                (m.feedback.completed_steps, m.feedback.remaining_steps)))
        self.wait_for(sent.done, 'goal response')
        handle = sent.result()
        if cancel_after is not None:
            self.wait_for(lambda: len(feedback) >= cancel_after, 'feedback before cancel')
            cancelled = handle.cancel_goal_async()
            self.wait_for(cancelled.done, 'cancel response')
        result = handle.get_result_async()
        self.wait_for(result.done, 'action result')
        r = result.result()
        return {'accepted': handle.accepted, 'status': r.status, 'feedback': feedback,
                'result': r.result.result.result, 'message': r.result.result.error_message}


def state_code(client: Client) -> int:
    return client.call('get_state', GetSimulationState.Request()).state.state


def tip(client: Client) -> dict:
    """The tip's EntityState as plain values (floats kept exact: repr round-trips)."""
    r = client.call('entity', GetEntityState.Request(entity='tip'))
    s = r.state
    return {'result': r.result.result, 'frame': s.header.frame_id,
            'stamp_ns': s.header.stamp.sec * 10**9 + s.header.stamp.nanosec,
            'position': [s.pose.position.x, s.pose.position.y, s.pose.position.z],
            'orientation': [s.pose.orientation.x, s.pose.orientation.y,
                            s.pose.orientation.z, s.pose.orientation.w],
            'velocity': [s.twist.linear.x, s.twist.linear.y, s.twist.linear.z],
            'angular_velocity': [s.twist.angular.x, s.twist.angular.y, s.twist.angular.z],
            'acceleration': [s.acceleration.linear.x, s.acceleration.linear.y,
                             s.acceleration.linear.z]}


def set_state(client: Client, state: int) -> int:
    r = client.call('set_state', SetSimulationState.Request(state=SimulationState(state=state)))
    return r.result.result


def run_once(client: Client, omega: float) -> dict:
    """From a full reset: the command, 2000 steps by the service, 1000 by the action."""
    out = {'reset': client.call('reset', ResetSimulation.Request(
        scope=ResetSimulation.Request.SCOPE_ALL)).result.result}
    out['state_after_reset'] = state_code(client)
    out['tip_0'] = tip(client)
    client.command(omega)
    out['step'] = client.call('step', StepSimulation.Request(steps=2000)).result.result
    out['state_after_step'] = state_code(client)
    out['tip_2000'] = tip(client)
    out['action'] = client.simulate(1000)
    out['tip_3000'] = tip(client)
    # the tip one step either side of 3000 steps: its velocity, by central difference
    client.call('step', StepSimulation.Request(steps=1))
    out['tip_3001'] = tip(client)
    return out


def bad_requests(client: Client) -> dict:
    """Requests the simulator must refuse with a code, changing nothing."""
    before = tip(client)
    codes = {
        'step_0': client.call('step', StepSimulation.Request(steps=0)).result.result,
        'unknown_entity': client.call('entity', GetEntityState.Request(
            entity='no_such_thing')).result.result,
        'steps_past_bound': client.call('step', StepSimulation.Request(
            steps=2**63 - 1)).result.result,
        'pause_again': set_state(client, SimulationState.STATE_PAUSED),
        'no_world': set_state(client, SimulationState.STATE_NO_WORLD),
        'unknown_state': set_state(client, 17),
        'quitting': set_state(client, SimulationState.STATE_QUITTING),
    }
    action_0 = client.simulate(0)
    codes['action_0'] = action_0['result']
    return {'codes': codes, 'unchanged': tip(client) == before, 'action_0': action_0}


def world(client: Client, rods: list) -> dict:
    """Spawn ``rods`` (name, urdf file, omega, x), command, step, read, delete."""
    out: dict = {'pause': set_state(client, SimulationState.STATE_PAUSED)}
    requests = []
    for rod in rods:
        request = SpawnRequest(name=rod['name'], entity_resource=Resource(uri=rod['urdf']))
        request.initial_pose.header.frame_id = 'world'
        request.initial_pose.pose.position.x = rod['x']
        request.initial_pose.pose.orientation.w = 1.0
        requests.append(request)
    reply = client.call('spawn', SpawnEntities.Request(spawn_requests=requests))
    out['spawn'] = reply.result.result
    out['spawned'] = [r.entity_name for r in reply.results]
    reliable = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    publishers = {}
    for rod in rods:
        pub = client.node.create_publisher(Float64, f"{rod['name']}/cmd/omega", reliable)
        client.wait_for(lambda p=pub: p.get_subscription_count() > 0,
                        f"{rod['name']}/cmd/omega matched")
        publishers[rod['name']] = pub
    # a command reaches the simulator once its subscription has matched this publisher
    # too (discovery goes both ways): send until every hub has started to move
    waiting = dict(publishers)
    for _ in range(100):
        for name, pub in waiting.items():
            pub.publish(Float64(data=next(r['omega'] for r in rods if r['name'] == name)))
        client.executor.spin_once(timeout_sec=0.1)
        client.call('step', StepSimulation.Request(steps=1))
        hubs = dict(zip(*_states(client, '/hub$')))
        waiting = {name: pub for name, pub in waiting.items()
                   if hubs[f'{name}/hub'].twist.angular.z == 0.0}
        if not waiting:
            break
    out['step'] = client.call('step', StepSimulation.Request(
        steps=rods[0]['steps'])).result.result
    states = client.call('states', GetEntitiesStates.Request(
        filters=EntityFilters(filter='/tip$')))
    out['tips'] = {name: [st.pose.position.x, st.pose.position.y, st.pose.position.z]
                   for name, st in zip(states.entities, states.states)}
    out['hubs'] = {name: st.twist.angular.z for name, st in zip(
        *_states(client, '/hub$'))}
    # the first rod deleted while a SimulateSteps goal runs: answered, the goal goes on
    first = rods[0]['name']
    client.wait_for(lambda: client.action.server_is_ready(), 'simulate_steps server')
    feedback: list = []
    sent = client.action.send_goal_async(
        SimulateSteps.Goal(steps=10**9),
        feedback_callback=lambda m: feedback.append(m.feedback.completed_steps))
    client.wait_for(sent.done, 'goal response')
    handle = sent.result()
    client.wait_for(lambda: len(feedback) >= 2, 'feedback before the delete')
    out['delete_during_goal'] = client.call('delete', DeleteEntity.Request(
        entity=first)).result.result
    before = len(feedback)
    client.wait_for(lambda: len(feedback) >= before + 3, 'feedback after the delete')
    cancelled = handle.cancel_goal_async()
    client.wait_for(cancelled.done, 'cancel response')
    result = handle.get_result_async()
    client.wait_for(result.done, 'action result')
    out['goal_status'] = result.result().status
    out['steps_after_delete'] = feedback[-1] - feedback[before - 1]
    out['delete_rest'] = [client.call('delete', DeleteEntity.Request(
        entity=rod['name'])).result.result for rod in rods[1:]]
    out['delete_again'] = client.call('delete', DeleteEntity.Request(
        entity=first)).result.result
    out['left'] = list(client.call('entities', GetEntities.Request()).entities)
    return out


def _states(client: Client, pattern: str) -> tuple:
    r = client.call('states', GetEntitiesStates.Request(filters=EntityFilters(filter=pattern)))
    return list(r.entities), list(r.states)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n\n')[0])
    ap.add_argument('--simulator', default='/rotrod_simulator')
    ap.add_argument('--omega', type=float, default=2.0)
    ap.add_argument('--world', help='JSON file of rods to spawn, command, read and delete')
    args = ap.parse_args()
    rclpy.init()
    client = Client(args.simulator)
    report: dict = {'module': simulation_interfaces.__file__,
                    'libraries': loaded_libraries('simulation_interfaces')}
    try:
        features = client.call('features', GetSimulatorFeatures.Request()).features
        report['features'] = list(features.features)
        report['state_at_start'] = state_code(client)
        report['step_while_playing'] = client.call(
            'step', StepSimulation.Request(steps=1)).result.result
        report['pause'] = set_state(client, SimulationState.STATE_PAUSED)
        report['first'] = run_once(client, args.omega)
        report['bad'] = bad_requests(client)
        report['cancelled'] = client.simulate(10**9, cancel_after=3)
        report['state_after_cancel'] = state_code(client)
        report['second'] = run_once(client, args.omega)
        paused_at = report['second']['tip_3001']['stamp_ns']
        client.clock.clear()
        report['play'] = set_state(client, SimulationState.STATE_PLAYING)
        report['state_after_play'] = state_code(client)
        client.wait_for(lambda: any(t > paused_at for t in client.clock), '/clock after play')
        report['clock_after_play_ns'] = max(client.clock)
        if args.world:
            with open(args.world) as f:
                report['world'] = world(client, json.load(f))
        report['ok'] = Result.RESULT_OK
    finally:
        print('@@REPORT@@' + json.dumps(report), flush=True)
        client.close()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
