"""The profile publisher, the Rerun logger and the main job, as real processes."""

import os
import subprocess
import sys
import time

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from node_probes import namespace
from reference import eq26
from ros_harness import ros_arguments
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Float64

from rotrod_core import Eq26Profile, RodParams, simulate
from rotrod_core.analysis.alignment import profile_delay
from rotrod_core.reporting import recording
from rotrod_ros.install import executable
from rotrod_ros.profile_publisher import MATCH_SETTLE

pytestmark = pytest.mark.ros


def verify(path) -> str:
    """``rerun rrd verify``: exit 0 and one file verified (a truncated file says 0)."""
    rerun = executable('rerun')
    out = subprocess.run([*rerun, 'rrd', 'verify', str(path)], capture_output=True,
                         text=True, timeout=60)
    text = out.stdout + out.stderr
    assert out.returncode == 0 and '1 file verified without error' in text, text
    return text


def test_profile_publisher_waits_streams_the_profile_and_exits(ros_processes, ros_node,
                                                               request):
    ns = namespace(request)
    pub = ros_processes.start_console_script('profile_publisher', *ros_arguments(
        namespace=ns, params={'profile': 'eq26', 'period': 0.5, 'rate': 100.0,
                              'duration': 2.0}))
    pub.wait_for_output('waiting for a subscriber', timeout=30)
    time.sleep(0.5)
    assert pub.running                                   # nobody listening: it waits
    subscribed = time.monotonic()
    got, arrived = [], []
    ros_node.node.create_subscription(Float64, f'{ns}/cmd/omega', lambda m: (
        got.append(m), arrived.append(time.monotonic())), 1000)
    ros_node.spin_until(lambda: pub.poll() is not None, 30, 'the publisher exits')
    ros_node.spin_for(0.3)
    assert pub.returncode == 0
    assert 'start: streaming eq26' in pub.output and 'end: published 201 samples' in pub.output
    if os.geteuid() == 0:                                # permitted: real-time priority
        assert 'streaming at SCHED_FIFO priority 50' in pub.output
    # the sender lets the subscriber match it too before it starts: no start burst
    assert arrived[0] - subscribed >= MATCH_SETTLE
    assert arrived[19] - arrived[0] >= 0.15             # 19 intervals of 10 ms, not together
    values = [m.data for m in got]
    assert len(values) == 201
    expected = [eq26(k / 100.0, T=0.5)[0] for k in range(201)]   # MODEL.md, sample k
    assert values == pytest.approx(expected, abs=1e-12)


def test_profile_publisher_follows_the_sim_clock(ros_processes, ros_node, request):
    ns = namespace(request)
    clock = ros_node.node.create_publisher(Clock, '/clock', 10)
    pub = ros_processes.start_console_script('profile_publisher', *ros_arguments(
        namespace=ns, params={'profile': 'ramp', 'omega_target': 1.0, 'ramp_time': 1.0,
                              'rate': 20.0, 'use_sim_time': True}))
    got = ros_node.subscribe(f'{ns}/cmd/omega', Float64, qos=1000)
    sim = 1.0
    deadline = None
    start = time.monotonic()
    while deadline is None or time.monotonic() < deadline:
        sim += 0.0025                          # simulated time at a quarter of wall time
        clock.publish(Clock(clock=Time(sec=int(sim), nanosec=int(sim % 1 * 1e9))))
        ros_node.spin_for(0.01)
        if deadline is None and got:           # the stream has started (process is up)
            deadline = time.monotonic() + 2.0
        assert time.monotonic() < start + 30, 'no sample within 30 s'
    # about 0.5 s of simulated time since the first sample: ~11 of the 21, not all
    assert 5 <= len(got) <= 15, len(got)
    assert pub.running
    while pub.poll() is None and time.monotonic() < deadline + 30:
        sim += 0.01
        clock.publish(Clock(clock=Time(sec=int(sim), nanosec=int(sim % 1 * 1e9))))
        ros_node.spin_for(0.01)
    ros_node.spin_for(0.3)
    assert pub.returncode == 0
    assert [m.data for m in got] == pytest.approx([k / 20 for k in range(21)], abs=1e-12)


def test_profile_publisher_holds_or_loops_when_asked(ros_processes, ros_node, request):
    ns = namespace(request)
    hold = ros_processes.start_console_script('profile_publisher', *ros_arguments(
        namespace=ns + '_hold', params={'profile': 'constant', 'omega_target': 0.7,
                                        'rate': 50.0, 'hold': True}))
    loop = ros_processes.start_console_script('profile_publisher', *ros_arguments(
        namespace=ns + '_loop', params={'profile': 'ramp', 'omega_target': 1.0,
                                        'ramp_time': 0.2, 'rate': 50.0, 'loop': True}))
    held = ros_node.subscribe(f'{ns}_hold/cmd/omega', Float64, qos=1000)
    looped = ros_node.subscribe(f'{ns}_loop/cmd/omega', Float64, qos=1000)
    ros_node.spin_until(lambda: len(held) > 50 and len(looped) > 50, 20, 'streams')
    assert hold.running and loop.running
    assert {m.data for m in held} == {0.7}
    v = [m.data for m in looped]
    assert v.count(0.0) >= 3 and v.count(1.0) >= 3      # the ramp starts over


@pytest.mark.parametrize('params, reason', [
    ({'profile': 'spiral'}, 'profile must be one of'),
    ({'profile': 'table'}, 'table_file'),
    ({'profile': 'eq26', 'period': -1.0}, 'period'),
    ({'rate': 0.0}, 'rate must be > 0'),
    ({'realtime_priority': 100}, 'realtime_priority'),
    ({'realtime_priority': 5.0}, 'realtime_priority'),
])
def test_profile_publisher_refuses_bad_parameters(ros_processes, params, reason):
    proc = ros_processes.start_console_script('profile_publisher', *ros_arguments(
        params=params))
    assert proc.wait(timeout=30) == 2
    assert 'invalid configuration' in proc.output and reason in proc.output


def test_the_main_job_end_to_end(tmp_path):
    """``rotrod demo``: Eq. 26 through the three nodes; the recording is read back."""
    out = tmp_path / 'demo' / 'rotrod.rrd'
    run = subprocess.run([*executable('rotrod'), 'demo', '-o', str(out)], capture_output=True,
                         text=True, timeout=300)
    assert run.returncode == 0, run.stdout + run.stderr
    for stage in ('spin-up', 'hold', 'spin-down', 'rest'):
        assert stage in run.stdout
    assert f'recording: {out}' in run.stdout
    verify(out)
    paths = set(recording.entity_paths(out))
    for entity in (recording.U, recording.V, recording.OMEGA, recording.TORQUE,
                   recording.F_MODEL, recording.ROTATING_TIP, recording.INERTIAL_TIP):
        assert '/' + entity in paths
    t, w = recording.read_series(out, recording.OMEGA)
    tu, u = recording.read_series(out, recording.U)
    _, v = recording.read_series(out, recording.V)
    profile = Eq26Profile()
    shift = profile_delay(t, w, profile)
    keep = (tu - shift >= 0) & (tu - shift <= 40.0)
    tt = tu[keep] - shift
    assert tt[-1] - tt[0] > 39.5                       # the whole 40 s are recorded
    # the recording begins at most 1 s before the profile (it began up to 15 s before)
    assert 0 <= shift - min(t[0], tu[0]) <= 1.0, (shift, t[0], tu[0])
    assert 'the profile starts' in run.stdout
    offline = simulate(RodParams(), profile, 40.0, dt=1e-3)
    du = np.max(np.abs(u[keep] - np.interp(tt, offline.t, offline.u)))
    dv = np.max(np.abs(v[keep] - np.interp(tt, offline.t, offline.v)))
    assert du <= 0.01 * np.max(offline.u)             # the simulator issue's tolerances
    assert dv <= 0.05 * np.max(np.abs(offline.v))
    _, f = recording.read_series(out, recording.F_MODEL)
    assert f.shape[1] == 2
    # the estimate from the motion, stamped at the end of its 1 s window, tracks Eq. 28
    # at the window's middle during the spin-up once the window has filled (issue 6: 2 %)
    te, fe = recording.read_series(out, recording.F_ESTIMATE)
    middle = te - shift - 0.5
    spin_up = (middle >= 0.5) & (middle <= 14.5)
    w0 = RodParams().natural_frequency
    w_mid = profile.omega(middle[spin_up])
    model = np.column_stack(((w0 - w_mid) / (2 * np.pi), (w0 + w_mid) / (2 * np.pi)))
    given = np.isfinite(fe[spin_up])
    # NaN where a window is not stationary: the spin-up's own whirls are ~0.1 um, and
    # small corrections of the streamed w (delivery hiccups) start new ones
    # (26-65 % measured across runs of the same code, depending on the stream's hiccups)
    print(f"estimates given in {given.mean():.0%} of the spin-up windows")
    assert given.mean() >= 0.2, given.mean()
    assert np.max(np.abs(fe[spin_up][given] / model[given] - 1)) <= 0.02


def test_logger_serves_on_localhost_only(ros_processes, tmp_path):
    port = 19000 + (hash(str(tmp_path)) % 1000)
    logger = ros_processes.start_console_script('rerun_logger', *ros_arguments(
        params={'output': str(tmp_path / 'x.rrd'), 'serve': True, 'serve_port': port}))
    logger.wait_for_output('serving at', timeout=30)
    listening = set()
    for line in open('/proc/net/tcp').read().splitlines()[1:]:
        local, state = line.split()[1], line.split()[3]
        if state == '0A':                              # LISTEN
            addr, p = local.split(':')
            listening.add((addr, int(p, 16)))
    assert ('0100007F', port) in listening             # 127.0.0.1
    assert ('00000000', port) not in listening         # not 0.0.0.0


def test_demo_is_a_module_too():
    out = subprocess.run([sys.executable, '-m', 'rotrod_ros.demo', '--help'],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0 and '--real-time' in out.stdout
