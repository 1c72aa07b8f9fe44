"""As fast as possible, recorded losslessly: every publication of the simulator is in the
Rerun logger's .rrd, also when the logger stalls (issue #22, part 3).

The simulator is started at real_time_factor 0 and nothing else about waiting (by
default it starts simulated time once the logger, started first, has subscribed to
every sample topic; issue #30); its sample topics are then reliable
KEEP_ALL, as the logger's subscriptions are, so a logger that falls behind holds the
physics up instead of losing messages. The run is a free rotation in torque drive
(w = 2 rad/s, u = 1 mm at t = 0, no torque); mid-run the logger is stopped (SIGSTOP) for
a second. The simulator says at its end how many samples it published; the file must
hold every one of them, on the 10 ms grid of simulated time from 0 with none missing,
with the values of the offline run from the same initial state (to 1e-7 of their
largest value: the same RK4 steps, rounded differently over ~1e5 of them); every
frequencies message with its own sample's stamp (Eq. 28 at that sample's w), every
estimate at its 0.1 s.
"""

import signal
import time

import numpy as np
import pytest
from node_probes import namespace, stamp
from ros_harness import ros_arguments
from sensor_msgs.msg import JointState

from rotrod_core import RodParams, simulate
from rotrod_core.analysis.modes import dynamic_frequencies
from rotrod_core.reporting import recording
from rotrod_ros.simulator import stop_report

pytestmark = pytest.mark.ros

STEP = 0.01            # s: the publish period (publish_rate 100 Hz) of simulated time
J = 0.0624             # kg m^2: hub inertia (torque drive needs one)
INITIAL = {'omega': 2.0, 'u': 1e-3}


def test_an_as_fast_as_possible_run_is_in_the_recording_to_the_last_sample(
        ros_processes, request, tmp_path):
    ns = namespace(request)
    out = tmp_path / 'fast.rrd'
    logger = ros_processes.start_console_script('rerun_logger', *ros_arguments(
        namespace=ns, params={'output': str(out)}), name='logger')
    logger.wait_for_output('subscribed to the simulator', timeout=30)
    sim = ros_processes.start_console_script('simulator', *ros_arguments(
        namespace=ns, params={'real_time_factor': 0.0, 'drive': 'torque', 'hub_inertia': J,
                              'deflection_limit': 0.01,
                              **{f'initial.{k}': v for k, v in INITIAL.items()}}),
        name='simulator')
    sim.wait_for_output('starting: 1 subscription', timeout=30)
    assert 'as fast as possible, for at most 10 s' in sim.output
    t0 = time.monotonic()
    time.sleep(2.0)
    logger.signal_group(signal.SIGSTOP)         # the slowest subscriber: stalled for 1 s
    time.sleep(1.0)
    logger.signal_group(signal.SIGCONT)
    time.sleep(2.0)
    wall = time.monotonic() - t0             # to the signal: t_end is simulated time then
    sim.signal_group(signal.SIGINT)
    assert sim.wait(timeout=30) == 0
    done = stop_report(sim.output)
    t_end, published = done.time, done.publications
    assert 'not every publication acknowledged' not in sim.output
    logger.signal_group(signal.SIGINT)
    assert logger.wait(timeout=60) == 0
    print(f'{published} publications, {t_end:.2f} s of simulated time in about {wall:.1f} s '
          f'of wall time ({t_end / wall:.1f}x real time, with a 1 s stall of the logger)')
    # as fast as possible, not paced (paced at 1x, and the logger's 1 s stall holding the
    # physics up, it would be below 1x; a loaded 2-core machine ran it at 3x)
    assert t_end / wall > 1.5

    offline = simulate(RodParams(hub_inertia=J), torque=0.0, t_end=t_end + STEP, dt=1e-3,
                       initial=INITIAL)
    for entity in (recording.U, recording.V, recording.OMEGA):
        t, x = recording.read_series(out, entity)
        k = np.round(t / STEP).astype(int)
        assert np.allclose(t, k * STEP, atol=1e-9)
        # every sample from t = 0, none missing, none twice; the last one may have been
        # sent in part when the signal came (the count is of complete samples)
        assert np.array_equal(k, np.arange(len(k))), (
            f'{entity}: {len(np.setdiff1d(np.arange(k[-1] + 1), k))} samples missing')
        assert len(k) in (published, published + 1), (entity, len(k), published)
        reference = {recording.U: offline.u, recording.V: offline.v,
                     recording.OMEGA: offline.omega}[entity]
        error = np.max(np.abs(x - np.interp(t, offline.t, reference)))
        print(f'{entity}: {len(k)} samples, max |live - offline| {error:.3g}')
        # the same RK4 steps; rounding differs over ~1e5 steps (one run: 2e-11 m in u)
        assert error <= 1e-7 * np.max(np.abs(reference)), entity
    # the frequencies take the stamp of their joint state: Eq. 28 at its w, every sample
    t_w, w = recording.read_series(out, recording.OMEGA)
    t_f, f = recording.read_series(out, recording.F_MODEL)
    assert np.array_equal(t_f, t_w)
    assert np.array_equal(f, np.column_stack(dynamic_frequencies(RodParams(hub_inertia=J), w)))
    # an estimate every 0.1 s of simulated time once the 1 s window has filled, stamped
    # at its window's middle (the first window: samples 0 .. 1 s - STEP)
    t_e, _ = recording.read_series(out, recording.F_ESTIMATE)
    assert t_e[0] == pytest.approx(0.5 * (1.0 - STEP), abs=1e-9)
    assert np.allclose(np.diff(t_e), 0.1, atol=1e-9)
    assert t_end - t_e[-1] < 0.5 * (1.0 - STEP) + 0.1 + 1e-9


@pytest.mark.long      # waits the 10 s timeout: CI's long run (the default run's budget)
def test_as_fast_as_possible_without_a_subscriber_starts_after_the_wait_and_says_so(
        ros_processes, ros_node, request):
    """Nobody subscribes: simulated time starts after AUTO_WAIT_TIMEOUT, with a warning
    naming the topics, and runs as fast as possible; paced, nothing waits."""
    ns = namespace(request)
    sim = ros_processes.start_console_script('simulator', *ros_arguments(
        namespace=ns, params={'real_time_factor': 0.0}), name='alone')
    sim.wait_for_output('ready', timeout=30)
    t0 = time.monotonic()
    sim.wait_for_output('starting after 10 s without 1 subscription', timeout=30)
    assert ('on joint_states, tip/deflection, tip/position, frequencies, '
            'frequencies/estimate: a subscriber that comes later misses') in sim.output
    assert time.monotonic() - t0 >= 9.0
    joint = ros_node.wait_for_messages(f'{ns}/joint_states', JointState, 20)
    assert stamp(joint[-1]) - stamp(joint[0]) > 0
    paced = ros_processes.start_console_script('simulator', *ros_arguments(
        namespace=ns + '_paced'), name='paced')
    paced.wait_for_output('ready', timeout=30)
    assert 'waiting for' not in paced.output
    ros_node.wait_for_messages(f'{ns}_paced/joint_states', JointState, 5, timeout=10)
