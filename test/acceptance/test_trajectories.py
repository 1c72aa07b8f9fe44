"""FollowJointTrajectory through the simulator executable (issue #35), against closed forms.

The client here knows only control_msgs, trajectory_msgs and sensor_msgs. A trajectory
of positions, velocities and accelerations is followed as the quintic through them (the
closed form, written out below), its feedback is the publication grid's, every bad goal
gets the standard's code and a sentence while the hub keeps its motion, cancel holds w,
a new goal preempts, a torque drive refuses, and a paused simulator stepped in lockstep
executes a goal bit for bit the same twice. The simulator's ``robot_description`` is the
rod it simulates, and follows a parameter change.
"""

import math

import numpy as np
import pytest
from action_msgs.msg import GoalStatus
from builtin_interfaces.msg import Duration
from control_msgs.action import FollowJointTrajectory
from control_msgs.msg import JointTolerance
from node_probes import namespace, param, set_parameters, stamp, start_simulator
from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from sensor_msgs.msg import JointState
from simulation_interfaces.msg import SimulationState
from simulation_interfaces.srv import ResetSimulation, SetSimulationState, StepSimulation
from std_msgs.msg import String
from trajectory_msgs.msg import JointTrajectoryPoint

from rotrod_core.model.description import read_description
from rotrod_core.model.params import RodParams

pytestmark = pytest.mark.ros

Result = FollowJointTrajectory.Result


def duration(t: float) -> Duration:
    return Duration(sec=math.floor(t), nanosec=round((t - math.floor(t)) * 1e9))


def goal(points, names=('hub',), **fields):
    """A FollowJointTrajectory goal of (t, positions, velocities, accelerations) points."""
    g = FollowJointTrajectory.Goal(**fields)
    g.trajectory.joint_names = list(names)
    for t, *arrays in points:
        p = JointTrajectoryPoint(time_from_start=duration(t))
        p.positions, p.velocities, p.accelerations = (list(a) for a in arrays)
        g.trajectory.points.append(p)
    return g


def nanoseconds(t) -> int:
    """builtin_interfaces Time or Duration in integer ns."""
    return t.sec * 1_000_000_000 + t.nanosec


def client_for(ros_node, ns):
    """The action's client; its feedback subscription keeps 1000 messages (rclpy's
    default, 10, lost feedback while this test process was busy)."""
    from rclpy.action import ActionClient
    from rclpy.qos import QoSProfile
    client = ActionClient(ros_node.node, FollowJointTrajectory, f'{ns}/follow_joint_trajectory',
                          feedback_sub_qos_profile=QoSProfile(depth=1000))
    ros_node.spin_until(client.server_is_ready, 30, 'the trajectory action')
    return client


def send(ros_node, client, g):
    """Send ``g``; its handle, feedback list and result future."""
    feedback = []
    sent = client.send_goal_async(g, feedback_callback=lambda m: feedback.append(m.feedback))
    ros_node.spin_until(sent.done, 30, 'the goal response')
    handle = sent.result()
    assert handle.accepted
    return handle, feedback, handle.get_result_async()


def result_of(ros_node, future, timeout=60.0):
    ros_node.spin_until(future.done, timeout, 'the result')
    return future.result().status, future.result().result


def quintic(h, start, end, x):
    """The quintic through (theta, w, w') at 0 and h, at x: theta, w, w' (closed form)."""
    s = x / h
    basis = np.array([
        [1 - 10 * s**3 + 15 * s**4 - 6 * s**5, s - 6 * s**3 + 8 * s**4 - 3 * s**5,
         0.5 * s**2 - 1.5 * s**3 + 1.5 * s**4 - 0.5 * s**5, 10 * s**3 - 15 * s**4 + 6 * s**5,
         -4 * s**3 + 7 * s**4 - 3 * s**5, 0.5 * s**3 - s**4 + 0.5 * s**5],
        [-30 * s**2 + 60 * s**3 - 30 * s**4, 1 - 18 * s**2 + 32 * s**3 - 15 * s**4,
         s - 4.5 * s**2 + 6 * s**3 - 2.5 * s**4, 30 * s**2 - 60 * s**3 + 30 * s**4,
         -12 * s**2 + 28 * s**3 - 15 * s**4, 1.5 * s**2 - 4 * s**3 + 2.5 * s**4]])
    scale = np.array([1.0, h, h * h, 1.0, h, h * h])
    coef = np.array([*start, *end]) * scale
    theta = basis[0].T @ coef if basis.ndim == 2 else basis[0] @ coef
    omega = (basis[1].T @ coef) / h if basis.ndim == 2 else basis[1] @ coef / h
    return theta, omega


QUINTIC = [(1.5, [0.6], [0.8], [0.2]), (3.0, [2.0], [1.0], [0.0])]
"""Two points of theta rad, w rad/s, w' rad/s^2: from rest, quintic segments."""


NS = 1e-8
"""Bound on |theta|, |w| errors of a time rounded to 1 ns: (|w|, |w'| <= 3) x 1 ns, and more."""


def closed_form(tau):
    """(theta, w) of QUINTIC from rest at ``tau`` s after its start."""
    if tau <= 1.5:
        return quintic(1.5, (0.0, 0.0, 0.0), (0.6, 0.8, 0.2), tau)
    return quintic(1.5, (0.6, 0.8, 0.2), (2.0, 1.0, 0.0), tau - 1.5)


def test_a_trajectory_is_followed_as_the_quintic_through_its_points_at_the_physics_rate(
        ros_processes, ros_node, request):
    ns = namespace(request)
    sim = start_simulator(ros_processes, ns, 'table1.yaml', markers=False,
                          max_angular_acceleration=2.0)
    joint = ros_node.subscribe(f'{ns}/joint_states', JointState, qos=1000)
    client = client_for(ros_node, ns)
    ros_node.spin_until(lambda: len(joint) > 5, 10, 'joint_states')
    assert joint[-1].position[0] == 0.0 and joint[-1].velocity[0] == 0.0
    _, feedback, future = send(ros_node, client, goal(QUINTIC))
    status, result = result_of(ros_node, future)
    assert status == GoalStatus.STATUS_SUCCEEDED and result.error_code == Result.SUCCESSFUL
    assert 'reached the last point at 3 s' in result.error_string
    # feedback at every publication (100 Hz) while it ran, desired = the closed form at
    # its time from the start (simulated time: exact, where an epoch stamp as a float
    # resolves 0.2 us only); the joint state of the same sample has the same stamp
    stamps = sorted(nanoseconds(f.header.stamp) for f in feedback)
    assert len(feedback) == pytest.approx(3.0 * 100, abs=1)        # the ends: 299..301
    assert np.all(np.abs(np.diff(stamps) - 10**7) < 10**3)         # none missing
    tau_of = {nanoseconds(f.header.stamp): nanoseconds(f.desired.time_from_start) * 1e-9
              for f in feedback}
    # (a time from start is whole ns: w within |w'| x 1 ns, theta within |w| x 1 ns)
    for f in feedback[::25]:
        tau = tau_of[nanoseconds(f.header.stamp)]
        theta, w = closed_form(tau)
        assert f.desired.positions[0] == pytest.approx(theta, abs=NS)
        assert f.desired.velocities[0] == pytest.approx(w, abs=NS)
        assert f.actual.velocities[0] == pytest.approx(f.desired.velocities[0], abs=1e-14)
        assert abs(f.error.positions[0]) < 1e-6
    # joint_states: w is the quintic's derivative at every instant with feedback; below,
    # one joint state every 10 ms of the goal's 3 s (this subscription keeps 1000), the
    # start a stamp minus its time from start (epoch stamps: ~0.2 us)
    rows = [(tau_of[nanoseconds(m.header.stamp)], m.position[0], m.velocity[0])
            for m in joint if nanoseconds(m.header.stamp) in tau_of]
    assert len(rows) == len(tau_of)
    for tau, theta, w in rows:
        want_theta, want_w = closed_form(tau)
        assert w == pytest.approx(want_w, abs=NS)
        assert theta == pytest.approx(want_theta, abs=2e-6)      # integrated at 1 kHz
    ros_node.spin_for(0.5)
    assert joint[-1].velocity[0] == 1.0                # the last point's speed holds
    start = min(nanoseconds(f.header.stamp) - nanoseconds(f.desired.time_from_start)
              for f in feedback)
    during = [m for m in joint
              if start + 5 * 10**6 < nanoseconds(m.header.stamp) < start + 3005 * 10**6]
    assert len(during) == 300                          # every 10 ms of the goal's 3 s
    assert sim.stop() == 0                             # a clean end on SIGINT


BAD = [
    (goal([(1.0, [], [1.0], [])], names=('rotor',)), Result.INVALID_JOINTS, "no joint 'rotor'"),
    (goal([(1.0, [], [1.0, 0.0], [])], names=('hub', 'tip_radial')), Result.INVALID_JOINTS,
     'passive'),
    (goal([(1.0, [], [1.0], []), (0.5, [], [2.0], [])]), Result.INVALID_GOAL,
     'does not increase'),
    (goal([(1.0, [], [math.nan], [])]), Result.INVALID_GOAL, 'velocity is nan'),
    (goal([(1.0, [], [60.0], [])]), Result.INVALID_GOAL, "beyond the drive's limit 50"),
    (goal([(0.1, [], [1.0], [])]), Result.INVALID_GOAL, "|w'| reaches"),
    (goal([]), Result.INVALID_GOAL, 'no points'),
    (goal([(1.0, [], [1.0], [])], goal_tolerance=[JointTolerance(name='wheel')]),
     Result.INVALID_JOINTS, "goal_tolerance names joint 'wheel'"),
]


def test_bad_goals_get_the_standard_code_and_a_sentence_and_the_hub_keeps_its_motion(
        ros_processes, ros_node, request):
    ns = namespace(request)
    sim = start_simulator(ros_processes, ns, 'table1.yaml', markers=False)
    joint = ros_node.subscribe(f'{ns}/joint_states', JointState, qos=1000)
    client = client_for(ros_node, ns)
    # a slow ramp to 0.5 rad/s first: the bad goals come while the hub turns
    _, _, moving = send(ros_node, client, goal([(2.0, [], [0.5], [0.0])]))
    assert result_of(ros_node, moving)[0] == GoalStatus.STATUS_SUCCEEDED
    ros_node.spin_until(lambda: any(m.velocity[0] == 0.5 for m in joint), 5, 'w = 0.5 rad/s')
    held = next(i for i, m in enumerate(joint) if m.velocity[0] == 0.5)  # the ramp's end
    for g, code, sentence in BAD:
        _, _, future = send(ros_node, client, g)
        status, result = result_of(ros_node, future)
        assert status == GoalStatus.STATUS_ABORTED
        assert result.error_code == code and sentence in result.error_string, result
    n = len(joint)
    ros_node.spin_until(lambda: len(joint) > n + 50, 10, 'joint_states after the refusals')
    # nothing changed: from the ramp's end, through the refusals and 50 samples after
    assert all(m.velocity[0] == 0.5 for m in joint[held:])
    assert sim.running
    # torque drive: a goal is refused with the reason
    set_parameters(ros_node, ns, param('drive', 'torque'))
    _, _, future = send(ros_node, client, goal([(1.0, [], [1.0], [])]))
    status, result = result_of(ros_node, future)
    assert status == GoalStatus.STATUS_ABORTED and result.error_code == Result.INVALID_GOAL
    assert "the drive is 'torque'" in result.error_string


def test_cancel_holds_w_and_a_new_goal_preempts_from_the_hub_s_motion(
        ros_processes, ros_node, request):
    ns = namespace(request)
    start_simulator(ros_processes, ns, 'table1.yaml', markers=False)
    joint = ros_node.subscribe(f'{ns}/joint_states', JointState, qos=1000)
    client = client_for(ros_node, ns)
    slow = goal([(8.0, [], [2.0], [0.0])])       # 0 -> 2 rad/s in 8 s, w' <= 0.375
    handle, feedback, future = send(ros_node, client, slow)
    ros_node.spin_until(lambda: feedback and feedback[-1].actual.velocities[0] > 0.5, 30,
                        'w > 0.5 rad/s')
    cancel = handle.cancel_goal_async()
    ros_node.spin_until(cancel.done, 10, 'the cancel response')
    status, result = result_of(ros_node, future)
    assert status == GoalStatus.STATUS_CANCELED and result.error_code == Result.SUCCESSFUL
    held = float(result.error_string.split('holding w = ')[1].split(' rad/s')[0])
    n = len(joint)
    ros_node.spin_until(lambda: len(joint) > n + 100, 10, '1 s more')
    assert all(m.velocity[0] == pytest.approx(held, abs=1e-6) for m in joint[n:])
    # a new goal while one runs: the old one is aborted, the new one starts from w
    first, _, first_future = send(ros_node, client, goal([(8.0, [], [0.0], [0.0])]))
    ros_node.spin_for(1.0)
    _, _, second_future = send(ros_node, client, goal([(4.0, [], [1.0], [0.0])]))
    status, result = result_of(ros_node, first_future)
    assert status == GoalStatus.STATUS_ABORTED and result.error_code == Result.INVALID_GOAL
    assert 'preempted by a new trajectory goal' in result.error_string
    status, result = result_of(ros_node, second_future)
    assert status == GoalStatus.STATUS_SUCCEEDED
    ros_node.spin_for(0.3)                  # the joint states up to the result
    w = np.array([m.velocity[0] for m in joint[n:]])
    assert np.max(np.abs(np.diff(w))) < 0.4 * 0.01 * 1.01      # continuous: |w'| <= 0.375
    assert w[-1] == pytest.approx(1.0, abs=1e-12)


def test_a_goal_stepped_in_lockstep_replays_bit_for_bit(ros_processes, ros_node, request):
    ns = namespace(request)
    start_simulator(ros_processes, ns, 'table1.yaml', markers=False, start_paused=True,
                    max_angular_acceleration=2.0)
    joint = ros_node.subscribe(f'{ns}/joint_states', JointState, qos=1000)
    client = client_for(ros_node, ns)
    sim = f'{ns}/rotrod_simulator'

    def run():
        n = len(joint)
        _, _, future = send(ros_node, client, goal(QUINTIC))
        ros_node.spin_for(0.3)       # the goal reaches the simulator's queue
        for _ in range(4):
            reply = ros_node.call_service(StepSimulation, f'{sim}/step_simulation',
                                          StepSimulation.Request(steps=1000))
            assert reply.result.result == 1, reply.result.error_message
        status, result = result_of(ros_node, future)
        assert status == GoalStatus.STATUS_SUCCEEDED, result
        ros_node.spin_for(0.3)
        return [(stamp(m), *m.position, *m.velocity) for m in joint[n:]]

    first = run()
    ros_node.call_service(ResetSimulation, f'{sim}/reset_simulation', ResetSimulation.Request())
    ros_node.spin_for(0.3)
    second = run()
    assert len(first) >= 400 and first == second
    state = ros_node.call_service(SetSimulationState, f'{sim}/set_simulation_state',
                                  SetSimulationState.Request(
                                      state=SimulationState(state=SimulationState.STATE_PLAYING)))
    assert state.result.result == 1


def test_robot_description_is_the_simulated_rod_and_follows_its_parameters(
        ros_processes, ros_node, request):
    ns = namespace(request)
    start_simulator(ros_processes, ns, 'table1.yaml', markers=False, mass=0.4,
                    rod_density=7850.0, gravity=9.81)
    latched = QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                         durability=DurabilityPolicy.TRANSIENT_LOCAL)
    ros_node.spin_for(1.0)           # a late subscriber still gets it
    got = ros_node.subscribe(f'{ns}/robot_description', String, qos=latched)
    ros_node.spin_until(lambda: got, 10, 'robot_description')
    description = read_description(got[-1].data)
    assert description.params == RodParams(mass=0.4, rod_density=7850.0, gravity=9.81,
                                           hub_inertia=RodParams().hub_inertia)
    assert description.limits.max_angular_acceleration == 0.5     # config/table1.yaml
    set_parameters(ros_node, ns, param('eccentricity', 0.12))
    ros_node.spin_until(lambda: len(got) > 1, 10, 'the new description')
    assert read_description(got[-1].data).params.eccentricity == 0.12
