"""The simulator node under load, faults and bad input (issue #8), as a real process.

* a 10 kHz flood of cmd/omega for 10 s: the physics keeps pace with the clock, the
  publications keep coming at 100 Hz, memory stays flat, w stays physical;
* the command publisher (the real profile_publisher) killed mid-spin-up: without
  command_timeout w holds the last setpoint; with it the hub spins down at exactly
  max_angular_acceleration, /diagnostics and the log say so, a command resumes;
* parameter set requests hammered at the running simulator: the valid ones take
  effect, the invalid ones are refused with a reason, the physics goes on.

Timing is measured from the DDS source timestamp of each publication (wall clock at
publish) against the simulated instant it carries (its stamp: wall-clock time at
real_time_factor 1), as bench/bench_realtime.py does.
"""

import math
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Vector3Stamped
from node_probes import collect, namespace, rss, stamp, start_simulator
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import GetParameters, SetParameters
from ros_harness import console_script, ros_arguments
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64

pytestmark = [pytest.mark.ros, pytest.mark.slow]        # each takes 12-20 s

ROOT = Path(__file__).resolve().parents[2]
PERIOD = 0.01                   # publish_rate 100 Hz
A_MAX = 0.5                     # max_angular_acceleration default, rad/s^2


@pytest.fixture(scope='module', autouse=True)
def this_checkout():
    """The node processes run this checkout's code: PYTHONPATH starts with it (as
    bench/bench_realtime.py's use_this_checkout() makes sure), checked by asking the
    console script's own interpreter where it imports the package from."""
    with pytest.MonkeyPatch.context() as mp:
        paths = [p for p in os.environ.get('PYTHONPATH', '').split(os.pathsep) if p]
        if not paths or Path(paths[0]).resolve() != ROOT:
            mp.setenv('PYTHONPATH', os.pathsep.join([str(ROOT), *paths]))
        script = console_script('simulator')
        with open(script[0], 'rb') as f:
            first = f.readline().decode(errors='replace')
        interpreter = first[2:].split() if first.startswith('#!') else [sys.executable]
        out = subprocess.run(
            [*interpreter, '-c', 'import rotrod_ros.simulator as s, rotrod_core.live.engine as e; '
             'print(s.__file__); print(e.__file__)'],
            capture_output=True, text=True, check=True, timeout=60)
        for path in out.stdout.split():
            assert Path(path).resolve().is_relative_to(ROOT), (path, ROOT)
        yield


def statuses(diags, ns):
    return [s for d in diags for s in d.status if s.name.startswith(f'{ns}/rotrod_simulator')]


def values(status) -> dict:
    return {kv.key: kv.value for kv in status.values}


def timing(rows):
    """Lag of each publication behind its simulated instant (source time - stamp), s."""
    st = np.array([stamp(m) for m, _, _ in rows])
    src = np.array([s for _, s, _ in rows])
    return st, src, src - st


def pvalue(value) -> ParameterValue:
    if isinstance(value, bool):
        return ParameterValue(type=ParameterType.PARAMETER_BOOL, bool_value=value)
    if isinstance(value, int):
        return ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=value)
    if isinstance(value, float):
        return ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=value)
    return ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=value)


class ParameterClient:
    """SetParameters / GetParameters of the simulator through one client each."""

    def __init__(self, node, ns):
        self.node = node
        self.set = node.node.create_client(SetParameters, f'{ns}/rotrod_simulator/set_parameters')
        self.get = node.node.create_client(GetParameters, f'{ns}/rotrod_simulator/get_parameters')
        node.spin_until(lambda: self.set.service_is_ready() and self.get.service_is_ready(),
                        10, 'parameter services')

    def call(self, client, request):
        future = client.call_async(request)
        self.node.spin_until(future.done, 10, 'parameter service reply')
        return future.result()

    def set_one(self, name, value):
        req = SetParameters.Request(parameters=[Parameter(name=name, value=pvalue(value))])
        return self.call(self.set, req).results[0]

    def get_one(self, name):
        v = self.call(self.get, GetParameters.Request(names=[name])).values[0]
        return {ParameterType.PARAMETER_BOOL: v.bool_value,
                ParameterType.PARAMETER_INTEGER: v.integer_value,
                ParameterType.PARAMETER_DOUBLE: v.double_value,
                ParameterType.PARAMETER_STRING: v.string_value}[v.type]


def observed_simulator(ros_processes, ros_node, ns, **params):
    """The simulator in ``ns`` (``params``) and this process's views of it: the
    simulator process and the collected joint_states, tip/deflection (lists of
    (message, source time, receive time)) and /diagnostics messages."""
    sim = start_simulator(ros_processes, ns, **params)
    joint = collect(ros_node, f'{ns}/joint_states', JointState)
    defl = collect(ros_node, f'{ns}/tip/deflection', Vector3Stamped)
    diags = ros_node.subscribe('/diagnostics', DiagnosticArray, qos=100)
    return sim, joint, defl, diags


# --------------------------------------------------------------------------- a. flood

@pytest.mark.long       # a 10 s stress measurement (memory flat under a flood)
def test_a_10_khz_command_flood_keeps_the_physics_on_time_and_memory_flat(
        ros_processes, ros_node, request):
    """cmd/omega at 10 kHz for 10 s, 100 times the usual stream and 10 times the physics
    rate: more than rclpy can take in on this machine, so most setpoints are dropped
    (DDS keeps the newest 1000, the node the newest 1000 pending). What must hold: the
    physics keeps publishing every 10 ms of simulated time without skipping, simulated
    time keeps pace with the clock, memory stays flat, and w stays physical and follows
    the stream, ending exactly at its last setpoint."""
    ns = namespace(request)
    sim, joint, defl, diags = observed_simulator(ros_processes, ros_node, ns)  # real time
    assert 'simulator' in Path(f'/proc/{sim.pid}/cmdline').read_text()
    pub = ros_node.node.create_publisher(Float64, f'{ns}/cmd/omega', 1000)
    ros_node.spin_until(lambda: pub.get_subscription_count() > 0 and len(joint) > 50, 20,
                        'simulator publishing and subscribed')
    k = len(joint)
    ros_node.spin_for(1.0)
    _, _, quiet = timing(joint[k:])                          # the lag without a flood

    rate, duration, amp, period = 10_000.0, 10.0, 0.3, 10.0

    def profile(t):                                          # |w'| <= 0.19 rad/s^2
        return amp * np.sin(2 * np.pi * t / period)

    msg, memory = Float64(), []
    sent, next_spin, next_rss = 0, 0.0, 0.0
    t0, e0 = time.monotonic(), time.time()                   # sample k is due at t0 + k/rate
    n0 = len(joint)
    while (now := time.monotonic()) - t0 < duration:
        due = min(int((now - t0) * rate) + 1, int(duration * rate))
        while sent < due:                                    # every sample, in order
            msg.data = float(profile(sent / rate))
            pub.publish(msg)
            sent += 1
        if now >= next_spin:                                 # receive what came meanwhile
            ros_node.executor.spin_once(timeout_sec=0)
            next_spin = now + 0.002
        if now >= next_rss:
            memory.append((now - t0, rss(sim.pid)))
            next_rss = now + 0.25
        ahead = t0 + sent / rate - time.monotonic()
        if ahead > 0:
            time.sleep(ahead)
    elapsed = time.monotonic() - t0
    e1 = time.time()
    w_last = float(profile((sent - 1) / rate))
    # the stream has ended: wait for 2 s of states published after it (DDS source time)
    # and for w at the last setpoint (after the 0.5 s stall bridge), not for 2 s of this
    # process's time, after which a loaded machine had not always delivered them: the
    # value is asserted below
    ros_node.spin_until(lambda: joint[-1][1] >= e1 + 2.0 and abs(
        joint[-1][0].velocity[0] - w_last) <= 1e-12, 30, '2 s on, w at the last setpoint')
    memory.append((time.monotonic() - t0, rss(sim.pid)))
    assert sim.running

    achieved = sent / elapsed
    # by when they were published, not when this busy process got round to them
    burst = [r for r in joint[n0:] if e0 <= r[1] <= e1]
    st, src, lag = timing(burst)
    _, _, after = timing([r for r in joint[n0:] if r[1] > e1])
    mem = np.array(memory)
    warm = mem[mem[:, 0] >= 2.0, 1]
    growth = (warm.max() - warm[0]) / 1e6
    last = statuses(diags, ns)[-1]
    report = values(last)
    print(f'\nflood: sent {sent} setpoints in {elapsed:.2f} s = {achieved:.0f} Hz; the '
          f'simulator applied {report.get("accepted_commands", "?")} (dropped '
          f'{report.get("dropped_commands", "?")} from its queue, the rest by DDS), '
          f'rejected {report["rejected_commands"]}; '
          f'{len(burst)} joint_states; lag behind simulated time: quiet median '
          f'{1e3 * np.median(quiet):.2f} ms, max {1e3 * quiet.max():.2f} ms; flood median '
          f'{1e3 * np.median(lag):.2f} ms, p90 {1e3 * np.percentile(lag, 90):.1f} ms, p99 '
          f'{1e3 * np.percentile(lag, 99):.1f} ms, max {1e3 * lag.max():.1f} ms; after it '
          f'median {1e3 * np.median(after):.2f} ms; RSS {warm[0] / 1e6:.1f} MB after 2 s, '
          f'growth {growth:.2f} MB ({(mem[-1, 1] - mem[0, 1]) / 1e6:.2f} MB from the start)')
    assert achieved >= 5000.0
    # the physics rate is held: every 10 ms of simulated time is published, none
    # skipped (the node skips ahead only after 1 s of backlog, counted as overruns)
    assert np.allclose(np.diff(st), PERIOD, atol=1e-6)
    assert st[-1] - st[0] >= duration - 0.5
    assert report['overruns'] == '0'
    # simulated time keeps pace with the clock: publications leave close to their
    # instants (each is at the mercy of the OS scheduler on a saturated 2-core machine,
    # and the physics thread waits a switch interval for the interpreter lock whenever
    # it gave it up to the executor taking 10,000 messages a second: medians of 3-33 ms
    # were measured), and right after the flood they are on time again: no drift
    assert np.median(lag) < 0.1 and lag.max() < 0.5
    assert np.median(after) < 0.005
    assert growth <= 5.0                                     # memory flat after warm-up
    # the motion stays physical and follows the (lossy, late) stream
    w = np.array([m.velocity[0] for m, _, _ in burst])
    assert np.all(np.isfinite(w))
    assert np.all(np.isfinite([m.effort[0] for m, _, _ in joint]))
    assert np.max(np.abs(np.diff(w))) <= A_MAX * PERIOD * (1 + 1e-9)       # |w'| <= limit
    assert np.max(np.abs(w)) <= amp + 0.5 * A_MAX * 0.5     # + the stall bridge at most
    t = st - e0                                              # the profile's time
    shifts = np.arange(0.0, 1.0, 0.005)
    inside = t > 1.5
    cost = [np.max(np.abs(w[inside] - profile(t[inside] - s))) for s in shifts]
    best = int(np.argmin(cost))
    print(f'w follows the stream {1e3 * shifts[best]:.0f} ms late within '
          f'{cost[best] * 1e3:.1f} mrad/s')
    assert cost[best] < amp / 2          # stuck at 0 would be amp; its mirror image 2 amp
    assert joint[-1][0].velocity[0] == pytest.approx(w_last, abs=1e-12)   # the last one
    uv = np.array([(m.vector.x, m.vector.y) for m, _, _ in defl[n0:]])
    assert np.all(np.isfinite(uv)) and np.max(np.hypot(*uv.T)) < 0.003
    assert last.level in (DiagnosticStatus.OK, DiagnosticStatus.WARN)


# --------------------------------------------------------------------------- b. sender dies

def start_ramp_publisher(ros_processes, ns):
    """The real profile_publisher: w = 0.25 t rad/s (0 -> 2 over 8 s) at 100 Hz."""
    return ros_processes.start_console_script('profile_publisher', *ros_arguments(
        namespace=ns, params={'profile': 'ramp', 'omega_target': 2.0, 'ramp_time': 8.0,
                              'rate': 100.0}))


def kill_mid_spin_up(ros_node, sim, publisher, ns, joint, at_omega):
    """SIGKILL the publisher once the stream has passed ``at_omega`` and the simulator
    follows it; the setpoints received here (message, DDS source time, receive time:
    read them after a wait, the last ones may still be on their way), the time of the
    kill and the simulator's output until just before it."""
    got = collect(ros_node, f'{ns}/cmd/omega', Float64)
    # the publisher starts on its first subscriber, which may be this node: the
    # simulator must be seen to follow (it gets no samples from before it matched)
    ros_node.spin_until(lambda: got and got[-1][0].data >= at_omega and joint
                        and joint[-1][0].velocity[0] >= at_omega - 0.2, 30, 'the spin-up')
    before = sim.output
    publisher.signal_group(signal.SIGKILL)
    killed = time.time()
    assert publisher.wait(timeout=10) == -signal.SIGKILL
    return got, killed, before


def test_a_killed_sender_leaves_w_at_its_last_setpoint_without_a_command_timeout(
        ros_processes, ros_node, request):
    ns = namespace(request)
    sim, joint, defl, diags = observed_simulator(ros_processes, ros_node, ns)
    ros_node.spin_until(lambda: len(joint) > 10 and len(defl) > 10, 20, 'publishing')
    publisher = start_ramp_publisher(ros_processes, ns)
    setpoints, killed, _ = kill_mid_spin_up(ros_node, sim, publisher, ns, joint, 0.5)
    # the shaper bridges a stall for 0.5 s at the stream's slope, then returns to the
    # last setpoint (at most 0.25 s at 0.5 rad/s^2): held from 1 s after the kill on
    ros_node.spin_until(lambda: stamp(joint[-1][0]) > killed + 3.5, 10, '3.5 s after')
    last = setpoints[-1][0].data                            # all in by now
    st, _, lag = timing(joint)
    w = np.array([m.velocity[0] for m, _, _ in joint])
    held = w[st > killed + 1.0]
    assert len(held) > 200 and np.all(held == held[0])      # constant, exactly
    # the last setpoint (the simulator and this node may differ by the one sample in
    # flight at the kill)
    assert abs(held[0] - last) <= 0.25 * PERIOD + 1e-12, (
        held[0], [m.data for m, _, _ in setpoints[-5:]])
    assert np.max(np.abs(np.diff(w))) <= A_MAX * PERIOD * (1 + 1e-9)
    uv = np.array([(m.vector.x, m.vector.y) for m, _, _ in defl])
    assert np.all(np.isfinite(uv)) and np.max(np.hypot(*uv.T)) < 0.003
    assert np.allclose(np.diff(st), PERIOD, atol=1e-6) and np.median(lag) < 0.005
    assert sim.running and 'command_timeout' not in sim.output
    last_status = statuses(diags, ns)[-1]
    assert last_status.level == DiagnosticStatus.OK and last_status.message == 'running'


def test_a_killed_sender_is_spun_down_at_the_acceleration_limit_with_a_command_timeout(
        ros_processes, ros_node, request):
    ns = namespace(request)
    timeout = 0.5
    sim, joint, defl, diags = observed_simulator(ros_processes, ros_node, ns,
                                                 command_timeout=timeout)
    ros_node.spin_until(lambda: len(joint) > 10 and len(defl) > 10, 20, 'publishing')
    publisher = start_ramp_publisher(ros_processes, ns)
    setpoints, _, before_kill = kill_mid_spin_up(ros_node, sim, publisher, ns, joint, 0.5)
    pattern = re.compile(
        r'no command on cmd/omega or joint_command for 0\.5 s \(command_timeout\)')
    # (the node may already have timed out once at rest, before the stream began): the
    # warnings before the kill, counted from the output read before it, not after it,
    # by when a loaded machine's simulator may already have logged this one
    logged = len(pattern.findall(before_kill))
    n = len(diags)
    ros_node.spin_until(lambda: joint[-1][0].velocity[0] == 0.0, 10, 'spun down to 0')
    t_zero = stamp(joint[-1][0])
    ros_node.spin_until(lambda: stamp(joint[-1][0]) > t_zero + 1.0, 10, '1 s at rest')
    # the timeout runs from the last setpoint: when it was sent (DDS source time; this
    # node and the simulator may differ by the one in flight at the kill), not when
    # this process got round to the kill (a loaded machine may stall the sender before)
    last_sent = setpoints[-1][1]
    st, _, lag = timing(joint)
    w = np.array([m.velocity[0] for m, _, _ in joint])
    after = st > last_sent
    # publications are 10 ms of simulated time apart (checked below); the epoch-sized
    # stamps themselves are rounded to ~0.2 us, too coarse for a slope to 1e-9
    slope = np.diff(w[after]) / PERIOD
    full = np.nonzero(np.isclose(slope, -A_MAX, rtol=1e-9, atol=0.0))[0]
    first, end = full[0], full[-1] + 1
    where = f'slopes after the kill: {np.round(slope[: end + 3], 4)}'
    # one run at exactly the limit, >= 0.5 s long ...
    assert first > 20 and np.array_equal(full, np.arange(first, end)) and end - first > 50, where
    # ... with at most one publication interval holding its start and one its end: w
    # does not fall before the timeout runs out, ends at 0 and stays there
    assert np.all(slope[: first - 1] >= 0.0), where
    assert -A_MAX < slope[end] <= 0.0 and np.all(w[after][end + 2:] == 0.0), where
    assert np.all(np.abs(slope) <= A_MAX * (1 + 1e-9))       # |w'| bounded throughout
    # it starts command_timeout after the last setpoint (delivered within ~ms)
    t_first, w_first = st[after][first], w[after][first]
    t_start = t_first - (np.max(w[after]) - w_first) / A_MAX  # back along the ramp to its top
    assert last_sent - 0.1 + timeout < t_start < last_sent + timeout + 0.1, (
        t_start - last_sent)
    uv = np.array([(m.vector.x, m.vector.y) for m, _, _ in defl])
    assert np.all(np.isfinite(uv)) and np.max(np.hypot(*uv.T)) < 0.003
    assert np.allclose(np.diff(st), PERIOD, atol=1e-6) and np.median(lag) < 0.005
    # reported: WARN on /diagnostics, one (throttled) warning in the log for the event
    warn = [s for s in statuses(diags[n:], ns) if s.level == DiagnosticStatus.WARN]
    assert warn and re.search(r'no command for [\d.]+ s \(command_timeout 0.5 s\): '
                              r'(spinning down|spun down, at rest)', warn[-1].message)
    assert values(warn[-1])['command_timeout_s'] == '0.5'
    assert len(pattern.findall(sim.output)) == logged + 1
    # a command resumes normal operation (streamed, so it does not time out again)
    pub = ros_node.node.create_publisher(Float64, f'{ns}/cmd/omega', 1000)
    ros_node.spin_until(lambda: pub.get_subscription_count() > 0, 10, 'cmd/omega subscriber')
    n = len(diags)

    def resumed():
        ok = statuses(diags[n:], ns)
        return (joint[-1][0].velocity[0] == 0.2 and ok
                and ok[-1].level == DiagnosticStatus.OK)

    # until it shows (a loaded machine delays what this process receives), at most 10 s
    deadline = time.monotonic() + 10.0
    while not resumed():
        assert time.monotonic() < deadline, (
            joint[-1][0].velocity[0], [x.message for x in statuses(diags[n:], ns)][-3:])
        pub.publish(Float64(data=0.2))
        ros_node.spin_for(PERIOD)
    sim.wait_for_output('cmd/omega: commands again after the command timeout', timeout=5)
    assert sim.running


# --------------------------------------------------------------------------- c. parameters

VALID = [
    ('publish_rate', 50.0), ('publish_rate', 200.0), ('publish_rate', 100.0),
    ('marker_rate', 10.0), ('marker_rate', 20.0), ('markers', False), ('markers', True),
    ('marker_trail_length', 50), ('marker_trail_length', 200),
    ('marker_deflection_scale', 40.0), ('damping_ratio', 0.02), ('damping_ratio', 0.0),
    ('coupling', 'paper'), ('coupling', 'exact'), ('estimate_rate', 5.0),
    ('command_timeout', 1.0), ('command_timeout', 0.0),
    ('drive', 'torque'), ('drive', 'velocity'),
]
INVALID = [
    ('mass', -1.0, 'Parameter mass out of range'),       # rclpy, from the descriptor
    ('physics_rate', 20.0, 'physics_rate 20 Hz is too low'),
    ('publish_rate', 5000.0, 'publish_rate'),
    ('command_timeout', 0.05, 'shorter than 2 x setpoint_delay'),
    ('command_timeout', math.nan, 'Parameter command_timeout out of range'),
    ('drive', 'position', 'drive must be one of'),
    ('estimate_window', 0.05, 'estimate_window'),
    ('max_angular_acceleration', 50.0, 'bends the rod tangentially'),
    ('mass', 'heavy', 'Wrong parameter type'),
]


REQUESTS = 1500
"""Set requests hammered (every third one invalid): a fixed number, not as many as fit
in a fixed time, which a loaded machine answered too few of (about 640 a second here)."""


@pytest.mark.long       # 16 s of stress: in CI's long run, to keep the default run under 15 min
def test_parameter_updates_hammered_while_stepping_take_effect_or_are_refused(
        ros_processes, ros_node, request):
    ns = namespace(request)
    sim, joint, defl, diags = observed_simulator(ros_processes, ros_node, ns)
    ros_processes.start_console_script('profile_publisher', *ros_arguments(
        namespace=ns, params={'profile': 'sine_sweep', 'offset': 0.5, 'amplitude': 0.2,
                              'f_start': 0.05, 'f_end': 0.2, 'sweep_time': 60.0,
                              'rate': 100.0}))
    ros_node.spin_until(lambda: joint and joint[-1][0].velocity[0] > 0.1, 30, 'streaming')
    client = ParameterClient(ros_node, ns)
    n0 = len(joint)
    accepted = refused = 0
    latencies = []
    t0 = time.monotonic()
    for i in range(REQUESTS):
        if i % 3 == 2:
            name, value, reason = INVALID[(i // 3) % len(INVALID)]
            result = client.set_one(name, value)
            assert not result.successful, (name, value)
            assert reason in result.reason, (name, value, result.reason)
            refused += 1
        else:
            name, value = VALID[i % len(VALID)]
            sent = time.monotonic()
            result = client.set_one(name, value)
            latencies.append(time.monotonic() - sent)
            assert result.successful, (name, value, result.reason)
            accepted += 1
    hammer = (time.monotonic() - t0, len(joint))
    # the end state is the one asked for; a set of values reflected
    for name, value in [('publish_rate', 100.0), ('drive', 'velocity'),
                        ('damping_ratio', 0.01), ('markers', True)]:
        assert client.set_one(name, value).successful
        assert client.get_one(name) == value
    assert client.get_one('mass') == 0.3 and client.get_one('physics_rate') == 1000.0
    # the publication rate follows publish_rate: the states stamped from 0.3 s to 1.3 s
    # after the reply (simulated time, wall-clock time at real_time_factor 1, is at most
    # the wall clock: they come after the change), once all are in. By stamp, not by DDS
    # source time: a count over a wall-clock window moves with the publications' lag
    assert client.set_one('publish_rate', 50.0).successful
    changed = time.time()
    ros_node.spin_until(lambda: stamp(joint[-1][0]) >= changed + 1.3, 20, '1.3 s at 50 Hz')
    slow = np.diff([stamp(m) for m, _, _ in joint
                    if changed + 0.3 <= stamp(m) < changed + 1.3])
    assert client.set_one('publish_rate', 100.0).successful
    assert np.allclose(slow, 0.02, atol=1e-6) and 45 <= len(slow) <= 55
    ros_node.spin_for(0.5)

    rows = joint[n0:]
    st, src, lag = timing(rows)
    gaps = np.diff(src)
    print(f'\nparameters: {accepted} accepted, {refused} refused in {hammer[0]:.1f} s '
          f'({(accepted + refused) / hammer[0]:.0f} requests/s; valid ones answered in '
          f'median {1e3 * np.median(latencies):.1f} ms, max {1e3 * max(latencies):.1f} ms); '
          f'publication gaps max {1e3 * gaps.max():.1f} ms; lag behind simulated time '
          f'median {1e3 * np.median(lag):.2f} ms, p99 {1e3 * np.percentile(lag, 99):.2f} ms, '
          f'max {1e3 * lag.max():.1f} ms')
    # publication never stopped (50 Hz at the slowest), no step skipped, time kept pace
    assert gaps.max() < 0.1
    assert np.all(np.diff(st) > 0)
    steps = np.round(np.diff(st) / 0.001)                    # whole physics steps
    assert np.allclose(np.diff(st), steps * 0.001, atol=1e-6) and steps.min() >= 5
    assert np.median(lag) < 0.005 and lag.max() < 0.1
    assert abs(np.median(lag[-50:]) - np.median(lag[:50])) < 0.005
    # the state stayed finite and within the limits; no halt, no failure
    w = np.array([m.velocity[0] for m, _, _ in rows])
    assert np.all(np.isfinite(w)) and np.all(np.abs(w) < 1.0)
    uv = np.array([(m.vector.x, m.vector.y) for m, _, _ in defl[n0:]])
    assert np.all(np.isfinite(uv)) and np.max(np.hypot(*uv.T)) < 0.003
    levels = {s.level for s in statuses(diags, ns)}
    assert DiagnosticStatus.ERROR not in levels
    assert values(statuses(diags, ns)[-1])['overruns'] == '0'
    assert 'parameter change rejected' in sim.output and 'halted' not in sim.output
    assert sim.running
