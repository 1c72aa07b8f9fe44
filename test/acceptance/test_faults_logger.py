"""The Rerun logger stopped by a signal mid-run (issue #8, faults).

SIGTERM: nothing is lost. Every joint state, tip deflection and tip position the
simulator published before the signal (as received by a subscriber in this process)
is in the file, contiguous at 100 Hz from the logger's first sample. With
``footer:=true`` the file is complete (``rerun rrd verify``); by default it has no
footer (flat memory), which ``rerun rrd verify`` says ("Missing RRD footer").

SIGKILL: the process gets no chance to write anything more, so the file has no footer
and ``rerun rrd verify`` rejects it ("Missing RRD footer"). It still loads: rerun's
``RrdReader(path).stream()`` reads every chunk written (``rotrod_core.reporting.recording``
reads through it), and ``rerun rrd optimize`` rewrites it into a verified file. Its
data is contiguous from the start and ends at most ``flush_period`` (+ a margin for
the executor) before the kill.
"""

import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from geometry_msgs.msg import PointStamped, Vector3Stamped
from node_probes import namespace, stamp
from ros_harness import ros_arguments
from sensor_msgs.msg import JointState

from rotrod_core.reporting import recording
from rotrod_ros.install import executable

# rerun warns on every read of a file without footer, which a killed one is by design
pytestmark = pytest.mark.filterwarnings('ignore:RRD file has no footer')

ROOT = Path(__file__).resolve().parents[2]
STEP = 0.01
"""The simulator's publish period at its default 100 Hz, s."""
MARGIN = 0.25
"""SIGKILL: how much later than ``flush_period`` the last write may be, s (the flush
timer shares the logger's executor with ~500 message callbacks a second)."""

TOPICS = {   # topic -> (message type, entities written from it)
    'joint_states': (JointState, (recording.OMEGA, recording.TORQUE)),
    'tip/deflection': (Vector3Stamped, (recording.U, recording.V, recording.ROTATING_TIP)),
    'tip/position': (PointStamped, (recording.INERTIAL_TIP,)),
}


def rrd(*args: str) -> subprocess.CompletedProcess:
    return subprocess.run([*executable('rerun'), 'rrd', *args], capture_output=True,
                          text=True, timeout=120)


def run_simulator_and_logger(ros_processes, ros_node, ns: str, out, flush_period: float,
                             seconds_of_data: float = 3.0, footer: bool = False):
    """Simulator + logger; this process subscribes to the same topics.

    Returns (logger process, {topic: list of received messages}) once the logger has
    recorded for about ``seconds_of_data`` s.
    """
    ros_processes.start_console_script('simulator', *ros_arguments(namespace=ns)
                                       ).wait_for_output('ready', timeout=30)
    # subscribed before the logger starts, so this process sees everything it records
    got = {topic: ros_node.subscribe(f'{ns}/{topic}', msg_type, qos=1000)
           for topic, (msg_type, _) in TOPICS.items()}
    logger = ros_processes.start_console_script('rerun_logger', *ros_arguments(
        namespace=ns, params={'output': str(out), 'flush_period': flush_period,
                              'footer': footer}))
    logger.wait_for_output('subscribed to the simulator', timeout=30)
    ros_node.spin_until(lambda: all(ros_node.node.count_subscribers(f'{ns}/{topic}') >= 2
                                    for topic in TOPICS), 30, 'the logger subscribed')
    first = float(logger.wait_for_output(r'receiving: first joint state stamped ([0-9.]+) s',
                                         timeout=30).group(1))
    joint = got['joint_states']
    ros_node.spin_until(lambda: joint and stamp(joint[-1]) >= first + seconds_of_data, 30,
                        f'{seconds_of_data:g} s of joint states')
    return logger, got


def grid_index(t: np.ndarray, t0: float) -> np.ndarray:
    """Sample numbers of stamps on the 100 Hz grid starting at ``t0`` (checked on it)."""
    k = (t - t0) / STEP
    off = np.abs(k - np.round(k))
    assert np.all(off < 1e-3), f'stamps off the {STEP} s grid by up to {off.max() * STEP} s'
    return np.round(k).astype(int)


def contiguous(path, entity) -> np.ndarray:
    """The entity's stamps in the file, asserted to be every 100 Hz sample, none twice."""
    t, _ = recording.read_series(path, entity)
    assert len(t) > 0, entity
    k = grid_index(t, t[0])
    missing = np.setdiff1d(np.arange(k[-1] + 1), k)
    assert len(missing) == 0 and len(k) == k[-1] + 1, (
        f'{entity}: {len(missing)} samples missing (first at {t[0] + STEP * missing[:5]}), '
        f'{len(k) - len(np.unique(k))} duplicated')
    return t


@pytest.mark.ros
@pytest.mark.parametrize('footer', [False, True])
def test_sigterm_to_the_logger_loses_nothing_published_before_it(ros_processes, ros_node,
                                                                 request, tmp_path, footer):
    out = tmp_path / 'run.rrd'
    logger, got = run_simulator_and_logger(ros_processes, ros_node, namespace(request), out,
                                           flush_period=0.25, footer=footer)
    before = {topic: [stamp(m) for m in msgs] for topic, msgs in got.items()}
    logger.signal_group(signal.SIGTERM)
    assert logger.wait(timeout=30) == 0
    check = rrd('verify', str(out))
    said = check.stdout + check.stderr
    if footer:
        assert check.returncode == 0 and '1 file verified without error' in said, said
    else:
        assert check.returncode != 0 and 'Missing RRD footer' in said, said
    for topic, (_, entities) in TOPICS.items():
        sent = np.array(before[topic])
        for entity in entities:
            t = contiguous(out, entity)
            # everything received here before the signal, from the logger's first sample
            k = grid_index(sent[sent > t[0] - STEP / 2], t[0])
            assert k.max() <= len(t) - 1, (
                f'{entity}: the file ends {STEP * (k.max() - len(t) + 1):.3f} s before the '
                f'last {topic} published before SIGTERM')
            assert np.isin(k, np.arange(len(t))).all()
            assert t[0] <= sent[-1] - 2.5      # the logger recorded from the start of the run


@pytest.mark.ros
@pytest.mark.parametrize('flush_period', [0.25, 1.0])
def test_sigkill_to_the_logger_leaves_a_loadable_file_up_to_the_last_flush(
        ros_processes, ros_node, request, tmp_path, flush_period):
    out = tmp_path / 'run.rrd'
    logger, got = run_simulator_and_logger(ros_processes, ros_node, namespace(request), out,
                                           flush_period, seconds_of_data=3.0 + flush_period)
    last_seen = {topic: stamp(msgs[-1]) for topic, msgs in got.items()}
    logger.signal_group(signal.SIGKILL)
    assert logger.wait(timeout=30) == -signal.SIGKILL
    # no footer: verify refuses the file, the chunk stream reads it
    assert out.stat().st_size > 0
    for topic, (_, entities) in TOPICS.items():
        for entity in entities:
            t = contiguous(out, entity)                   # RrdReader(out).stream()
            lost = last_seen[topic] - t[-1]
            assert lost <= flush_period + MARGIN, (
                f'{entity}: the file ends {lost:.3f} s before the last {topic} seen before '
                f'the kill (flush_period {flush_period} s)')
            assert t[-1] - t[0] >= 2.5                    # from the start of the recording
            print(f'{entity}: {len(t)} samples over {t[-1] - t[0]:.2f} s, ending {lost:.3f} s '
                  f'before the last {topic} seen before the kill')
    # `rerun rrd optimize` writes a complete (verified) copy with the same samples
    repaired = tmp_path / 'repaired.rrd'
    fix = rrd('optimize', str(out), '-o', str(repaired))
    assert fix.returncode == 0, fix.stderr
    check = rrd('verify', str(repaired))
    assert check.returncode == 0, check.stdout + check.stderr
    t_killed, w_killed = recording.read_series(out, recording.OMEGA)
    t_fixed, w_fixed = recording.read_series(repaired, recording.OMEGA)
    assert np.array_equal(t_killed, t_fixed) and np.array_equal(w_killed, w_fixed)


WRITE_THEN_KILL = """
import os, signal, sys
from rotrod_core.reporting.recording import RecordingWriter
writer = RecordingWriter(sys.argv[1])
for k in range(1000):
    t = k * 0.01
    writer.add_state(t, 1.0, 0.1)
    writer.add_deflection(t, 1e-3, 1e-4)
    writer.add_position(t, 0.1, 0.2, 0.3)
    if k % 25 == 24:
        writer.flush()
os.kill(os.getpid(), signal.SIGKILL)      # at once: no time for rerun's own threads
"""


@pytest.mark.parametrize('attempt', range(3))
def test_what_the_writer_flushed_is_in_the_file_when_the_process_dies_at_once(
        tmp_path, attempt):
    # rerun-sdk writes from a thread of its own; without waiting for it, a kill right
    # after flush() was measured to lose up to a second of some entities
    out = tmp_path / 'killed.rrd'
    env = dict(os.environ, PYTHONPATH=os.pathsep.join(
        [str(ROOT), *filter(None, [os.environ.get('PYTHONPATH')])]))
    proc = subprocess.run([sys.executable, '-c', WRITE_THEN_KILL, str(out)], env=env,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == -signal.SIGKILL, proc.stderr
    for entity in (recording.OMEGA, recording.TORQUE, recording.U, recording.V,
                   recording.ROTATING_TIP, recording.INERTIAL_TIP):
        t = contiguous(out, entity)
        assert len(t) == 1000 and t[-1] == pytest.approx(9.99), entity
