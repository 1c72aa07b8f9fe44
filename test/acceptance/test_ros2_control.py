"""ros2_control's topic contract, through the real simulator executable.

Commands are sent as topic_based_ros2_control's TopicBasedSystem sends them
(``TopicBasedSystem::write``): a sensor_msgs/JointState on the simulator's
``joint_command`` with every joint of the <ros2_control> block in ``name`` (the hub
alone, as ``rotrod urdf --ros2-control`` writes it; other stacks' joints too, in any
order), one ``velocity`` or ``effort`` entry per joint with that command interface, at
the controller manager's update rate, with QoS depth 1 (reliable). Each field is empty
or has one entry per name (sensor_msgs/JointState's contract); a message that breaks
it (the issue's ``name: [hub, x]``, ``velocity: [3.0]``) is refused. The motion is
checked against closed forms: velocity drive ramps w at
max_angular_acceleration to the setpoint, as cmd/omega does; in torque drive the
angular momentum about the axis (from joint_states' hub and tip joints, no finite
differences) grows by the torque's integral. Malformed messages are rejected with a
logged reason, counted in /diagnostics, and change nothing.
"""

import math
import time

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray
from node_probes import namespace, stamp, start_simulator
from reference import R0, M
from sensor_msgs.msg import JointState

pytestmark = pytest.mark.ros

UPDATE_RATE = 100.0       # Hz: the controller manager's update_rate (config example)
PERIOD = 0.01             # s: the simulator's publish period (publish_rate 100 Hz)
A_MAX = 0.5               # rad/s^2: the simulator's default max_angular_acceleration


def command_publisher(ros_node, ns):
    """A joint_command publisher with TopicBasedSystem's QoS (reliable, depth 1)."""
    pub = ros_node.node.create_publisher(JointState, f'{ns}/joint_command', 1)
    ros_node.spin_until(lambda: pub.get_subscription_count() > 0, 10, 'joint_command sub')
    return pub


def command(names, velocity=(), effort=(), position=()):
    msg = JointState(name=list(names), position=list(position), velocity=list(velocity),
                     effort=list(effort))
    msg.header.stamp.sec = int(time.time())      # TopicBasedSystem stamps node->now()
    return msg


def stream(ros_node, pub, make, seconds, rate=UPDATE_RATE, until=None):
    """Publish ``make(k)`` at ``rate`` Hz of wall time for ``seconds`` (None: skip).

    With ``until``, publish until it holds instead, failing after ``seconds``: a loaded
    machine can start the simulator's motion late, and a fixed wall-clock length would
    then cut a phase short.
    """
    t0 = time.monotonic()
    for k in range(round(seconds * rate)):
        if until is not None and until():
            return
        due = t0 + k / rate
        while (left := due - time.monotonic()) > 0:
            ros_node.spin_once(min(left, 0.002))
        msg = make(k)
        if msg is not None:
            pub.publish(msg)
    assert until is None or until(), f'not reached in {seconds} s of streaming'


def hub_velocity_held(joint, value, seconds) -> bool:
    """Whether the last ``seconds`` of joint_states all have the hub at ``value`` rad/s."""
    n = round(seconds / PERIOD)
    return len(joint) >= n and all(
        m.velocity[list(m.name).index('hub')] == value for m in joint[-n:])


def hub_values(joint):
    """t, theta, w, Q of the hub and u, v, u', v' of the tip, by joint name.

    t is the stamp from the first message's whole second (exact to the nanosecond).
    """
    rows = []
    sec0 = joint[0].header.stamp.sec
    for m in joint:
        i = {n: k for k, n in enumerate(m.name)}
        h, r, t = i['hub'], i['tip_radial'], i['tip_tangential']
        st = (m.header.stamp.sec - sec0) + m.header.stamp.nanosec * 1e-9
        rows.append((st, m.position[h], m.velocity[h], m.effort[h], m.position[r],
                     m.position[t], m.velocity[r], m.velocity[t]))
    return np.array(sorted(rows))


def malformed_count(diags, ns) -> int:
    for d in reversed(diags):
        for s in d.status:
            if s.name.startswith(f'{ns}/rotrod_simulator'):
                return int({kv.key: kv.value for kv in s.values}['malformed_commands'])
    return -1


def ramp_segments(t, w, start, target):
    """The samples strictly inside the ramp from ``start`` to ``target``."""
    lo, hi = sorted((start, target))
    inside = (w > lo + 1e-12) & (w < hi - 1e-12)
    return t[inside], w[inside]


def test_velocity_commands_as_the_interface_sends_them_ramp_w_as_cmd_omega_does(
        ros_processes, ros_node, request):
    ns = namespace(request)
    sim = start_simulator(ros_processes, ns, real_time_factor=1.0)
    joint = ros_node.subscribe(f'{ns}/joint_states', JointState, qos=1000)
    diags = ros_node.subscribe('/diagnostics', DiagnosticArray, qos=100)
    pub = command_publisher(ros_node, ns)
    w1, w2 = 0.5, 0.25
    # the block rotrod urdf writes: the hub alone
    stream(ros_node, pub, lambda k: command(['hub'], velocity=[w1]), 10.0,
           until=lambda: hub_velocity_held(joint, w1, 0.4))
    # every joint with a velocity interface: one entry per name, read by name
    full = ['tip_tangential', 'tip_radial', 'hub']
    stream(ros_node, pub, lambda k: command(full, velocity=[7.0, -3.0, w2]), 10.0,
           until=lambda: hub_velocity_held(joint, w2, 0.1))
    ros_node.spin_until(lambda: joint and joint[-1].velocity[0] == w2, 5, 'w = w2')
    rows = hub_values(joint)
    t, w = rows[:, 0], rows[:, 2]
    # publications are 10 steps (0.01 s) of simulated time apart; their stamps, epoch
    # seconds as doubles, only to a few 1e-7 s: the slope is judged per publication
    assert np.allclose(np.diff(t), PERIOD, atol=1e-6)
    # up: w ramps at the acceleration limit from 0 to w1 and holds it exactly
    reached = t[np.argmax(w == w1)]
    tu, wu = ramp_segments(t[t < reached], w[t < reached], 0.0, w1)
    assert len(wu) > 0.8 * w1 / A_MAX * UPDATE_RATE
    assert np.diff(wu) == pytest.approx(A_MAX * PERIOD, rel=1e-9)
    assert np.all(w[(t >= reached) & (t < reached + 0.3)] == w1)
    assert np.all(w[t < tu[0]] == 0.0)
    # down: to w2 at the limit; the other joints' entries (7, -3) are ignored
    td, wd = ramp_segments(t[t > reached], w[t > reached], w1, w2)
    assert len(wd) > 0.8 * (w1 - w2) / A_MAX * UPDATE_RATE
    assert np.diff(wd) == pytest.approx(-A_MAX * PERIOD, rel=1e-9)
    assert np.max(w) == w1 and np.min(w[t > td[-1]]) == w2

    # malformed messages interleaved with the stream: rejected, counted, logged
    packed = ['tip_radial', 'hub', 'tip_tangential']
    bad = [command(['hub'], effort=[0.1]),                    # the inactive drive's field
           command(['hub'], velocity=[math.nan]),              # not finite
           command(['hub'], velocity=[1.0, 2.0]),              # lengths do not match
           command(['tip_radial', 'tip_tangential'], velocity=[1.0, 1.0]),   # no hub
           command(packed, velocity=[1.0, 2.0]),               # lengths do not match
           command(['hub', 'x'], velocity=[3.0]),              # the issue's: whose is 3.0?
           command(packed, velocity=[3.0])]                    # the same, three names
    n = len(joint)
    stream(ros_node, pub, lambda k: bad[k // 20] if k % 20 == 10 else
           command(['hub'], velocity=[w2]), len(bad) * 0.2)
    ros_node.spin_until(lambda: malformed_count(diags, ns) == len(bad), 5,
                        'malformed_commands in /diagnostics')
    assert all(m.velocity[0] == w2 for m in joint[n:])
    sim.wait_for_output("joint_command rejected: effort for joint 'hub' ignored: drive is "
                        "'velocity'", timeout=5)
    n = len(joint)
    ros_node.spin_until(lambda: len(joint) > n + 20, 5, 'still publishing')
    assert sim.running


def test_effort_commands_as_the_interface_sends_them_add_the_torques_integral_to_l(
        ros_processes, ros_node, request):
    ns = namespace(request)
    Q, J = 0.01, 0.0624
    sim = start_simulator(ros_processes, ns, real_time_factor=4.0, drive='torque',
                          hub_inertia=J, deflection_limit=0.01)
    joint = ros_node.subscribe(f'{ns}/joint_states', JointState, qos=1000)
    pub = command_publisher(ros_node, ns)
    names = ['tip_tangential', 'hub', 'tip_radial']          # any order; other joints
    stream(ros_node, pub, lambda k: command(names, effort=[0.0, Q, 0.0]), 0.2)
    # a hub with both command interfaces: the active drive's field (effort) counts
    stream(ros_node, pub, lambda k: command(['hub'], velocity=[3.0], effort=[Q]), 0.2)
    ros_node.spin_until(lambda: joint and joint[-1].effort[0] == Q, 5, 'torque applied')
    t_on = stamp(joint[-1])
    ros_node.spin_until(lambda: stamp(joint[-1]) > t_on + 8.0, 30, '8 s of spin-up')
    rows = hub_values(joint)
    rows = rows[rows[:, 3] == Q]
    t, w, q, u, v, du, dv = (rows[:, k] for k in (0, 2, 3, 4, 5, 6, 7))
    assert np.all(q == Q)
    x = R0 + u
    L = (J + M * (x * x + v * v)) * w + M * (x * dv - v * du)      # docs/model.md
    assert w[-1] > 1.0
    # L(t) - L(t_on) = integral of Q dt = Q (t - t_on)
    print(f'max |L - L0 - Q (t - t0)| = {np.max(np.abs((L - L[0]) - Q * (t - t[0]))):.3g} '
          f'kg m^2/s, Q (t - t0) up to {Q * (t[-1] - t[0]):.3g} kg m^2/s')
    assert np.max(np.abs((L - L[0]) - Q * (t - t[0]))) < 1e-9 * Q * (t[-1] - t[0])
    assert 'rejected' not in sim.output
