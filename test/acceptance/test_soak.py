"""Soak test (issue #8): the simulator at 1 kHz physics for 10 minutes under a command stream.

Marked ``long``: the default run (``./run.sh test``) leaves it out, ``./run.sh test -m long``
runs it (``.ci/run`` does both). ``ROTROD_SOAK_SECONDS`` shortens or lengthens it
(default 600).

The simulator runs with its defaults (1 kHz physics, 100 Hz publishing, markers on, the
whirl estimate on), driven by ``profile_publisher`` looping Eq. 26 (spin-up, hold and
spin-down over 35 s, then again) and recorded by ``rerun_logger``. The profile peaks at
1.5 rad/s, not the paper's 2: at 2 rad/s the static deflection (2.79 mm) is 7 % under
the 3 mm ``deflection_limit``, and a command stall longer than the 0.5 s the simulator
bridges (a loaded machine) can then halt the run: offline, a 0.6 s stall 7 s into the
spin-up halts it at 3.002 mm, and in one 10-minute run on a loaded shared 2-core
machine the joint states stopped after 189 s, most likely so. A halt still fails this
test, but the soak is about memory and time. Every ``RSS_EVERY`` seconds the resident
memory (VmRSS in /proc/<pid>/status) of the simulator and of the logger is sampled.
After a warm-up (the first ``WARMUP`` s: imports, DDS discovery, the first Eq. 26
cycles, the estimator's window filling), the first and the last ``WINDOW`` seconds
are compared by their medians, so a single sample (a burst, a garbage collection)
does not decide:

* simulator RSS grows by at most 5 MB (5e6 bytes);
* simulated time does not drift from the clock: the median lag of joint_states
  (DDS source timestamp minus the simulated instant it carries) changes by at most
  1 ms between the two windows;
* at least 99.9 % of the joint states published are received here, and the stream
  follows the commands (omega reaches the profile's peak), without a halt;
* the logger's RSS grows by at most ``LOGGER_RSS_RATE_MAX`` per minute, and its file
  holds every sample. At its default (no footer) nothing is kept per chunk written;
  with ``footer:=true`` rerun's file sink keeps a manifest entry of every chunk for
  the footer (about 15 chunks per ``flush_period``), which in the failed run of this
  test that led to the default was 7.2 MB a minute at 0.25 s.

The measured numbers are printed (``-rA`` shows them for a passing run);
``ROTROD_SOAK_DUMP=FILE.npz`` also saves the samples (RSS, stamps, source times).
"""

import os
import re
import time

import numpy as np
import pytest
from node_probes import cpu_seconds, namespace
from node_probes import rss as vm_rss
from ros_harness import ros_arguments
from sensor_msgs.msg import JointState

from rotrod_core.reporting import recording

SOAK_SECONDS = float(os.environ.get('ROTROD_SOAK_SECONDS', 600))
WARMUP = min(60.0, SOAK_SECONDS / 5)
WINDOW = min(60.0, (SOAK_SECONDS - WARMUP) / 3)
RSS_EVERY = 2.0
PERIOD = 0.01                      # 100 Hz publishing
RSS_GROWTH_MAX = 5e6               # bytes
LOGGER_RSS_RATE_MAX = 1e6          # bytes per minute
OMEGA_MAX = 1.5                    # rad/s, the profile's peak
DRIFT_MAX = 1e-3                   # s
RECEIVED_MIN = 0.999

pytestmark = [pytest.mark.long, pytest.mark.ros]


def windows(t: np.ndarray, start: float, end: float) -> tuple:
    """Masks of the first and the last WINDOW seconds of [start, end]."""
    return (t >= start) & (t < start + WINDOW), (t > end - WINDOW) & (t <= end)


@pytest.mark.timeout(SOAK_SECONDS + 300)
def test_soak_at_1khz_memory_and_simulated_time_hold(ros_processes, ros_node, request,
                                                     tmp_path):
    assert SOAK_SECONDS >= 30, 'ROTROD_SOAK_SECONDS below 30 s leaves no window to compare'
    ns = namespace(request)
    out = tmp_path / 'soak.rrd'
    joint = []                       # (stamp, source time, omega) per joint state

    def on_joint(msg, info):
        joint.append((msg.header.stamp.sec + msg.header.stamp.nanosec * 1e-9,
                      info['source_timestamp'] * 1e-9, msg.velocity[0]))

    ros_node.node.create_subscription(JointState, f'{ns}/joint_states', on_joint, 1000)
    sim = ros_processes.start_console_script('simulator', *ros_arguments(namespace=ns))
    sim.wait_for_output('ready', timeout=30)
    logger = ros_processes.start_console_script('rerun_logger', *ros_arguments(
        namespace=ns, params={'output': str(out)}))
    logger.wait_for_output('subscribed to the simulator', timeout=30)
    ros_processes.start_console_script('profile_publisher', *ros_arguments(
        namespace=ns, params={'profile': 'eq26', 'omega_target': OMEGA_MAX, 'loop': True}))
    ros_node.spin_until(lambda: len(joint) > 10, 30, 'joint states')
    logger.wait_for_output('receiving: first joint state', timeout=30)

    rss = []                         # (time since start, simulator RSS, logger RSS)
    start, start_wall = time.monotonic(), time.time()
    cpu0 = cpu_seconds(sim.pid)
    while (now := time.monotonic() - start) < SOAK_SECONDS:
        assert sim.running and logger.running
        rss.append((now, vm_rss(sim.pid), vm_rss(logger.pid)))
        ros_node.spin_for(min(RSS_EVERY, SOAK_SECONDS - now))
    end_wall = time.time()
    elapsed = time.monotonic() - start
    cpu = (cpu_seconds(sim.pid) - cpu0) / elapsed
    rss.append((elapsed, vm_rss(sim.pid), vm_rss(logger.pid)))
    assert logger.stop() == 0
    ros_node.spin_for(0.5)

    t_rss, sim_rss, log_rss = (np.array(c, dtype=float) for c in zip(*rss))
    first, last = windows(t_rss, WARMUP, elapsed)
    sim_growth = np.median(sim_rss[last]) - np.median(sim_rss[first])
    log_growth = np.median(log_rss[last]) - np.median(log_rss[first])
    minutes = (elapsed - WARMUP - WINDOW) / 60       # between the windows' middles

    stamp, source, omega = (np.array(c) for c in zip(*joint))
    lag = source - stamp
    first_lag, last_lag = windows(source - start_wall, WARMUP, elapsed)
    drift = np.median(lag[last_lag]) - np.median(lag[first_lag])
    k = np.round((stamp - stamp[0]) / PERIOD).astype(int)
    # published from the first joint state received to the end of the soak
    expected = int((end_wall - source[0]) / PERIOD) + 1
    received = len(np.unique(k[source <= end_wall]))
    gaps = np.diff(np.unique(k))
    t_file, _ = recording.read_series(out, recording.OMEGA)
    k_file = np.round((t_file - t_file[0]) / PERIOD).astype(int)
    overruns = len(re.findall('skipping ahead', sim.output))
    trouble = [line for line in sim.output.splitlines() if re.search(r'\b(ERROR|FATAL)\b|halt',
                                                                    line)]

    report = (
        f'soak {elapsed:.0f} s (warm-up {WARMUP:g} s, windows {WINDOW:g} s): '
        f'simulator RSS {np.median(sim_rss[first]) / 1e6:.1f} -> '
        f'{np.median(sim_rss[last]) / 1e6:.1f} MB (growth {sim_growth / 1e6:+.2f} MB, '
        f'min {sim_rss.min() / 1e6:.1f}, max {sim_rss.max() / 1e6:.1f} MB over the run); '
        f'logger RSS {np.median(log_rss[first]) / 1e6:.1f} -> '
        f'{np.median(log_rss[last]) / 1e6:.1f} MB (growth {log_growth / 1e6:+.2f} MB, '
        f'{log_growth / 1e6 / minutes:+.2f} MB/min); '
        f'simulator CPU {100 * cpu:.1f} % of one core; '
        f'lag median {1e3 * np.median(lag[first_lag]):.3f} -> '
        f'{1e3 * np.median(lag[last_lag]):.3f} ms (drift {1e3 * drift:+.3f} ms), '
        f'p99 {1e3 * np.percentile(lag, 99):.2f} ms, max {1e3 * lag.max():.2f} ms at '
        f'{source[np.argmax(lag)] - start_wall:+.1f} s (before 0: as the nodes joined); '
        f'joint states received {received} of {expected} '
        f'({100 * received / expected:.3f} %, largest gap {gaps.max() if len(gaps) else 0} '
        f'periods); max omega {omega.max():.3f} rad/s; overrun warnings {overruns}; '
        f'recording {len(t_file)} samples, {out.stat().st_size / 1e6:.1f} MB; '
        f'simulator errors: {trouble[:3] or "none"}')
    print(report)
    if os.environ.get('ROTROD_SOAK_DUMP'):
        np.savez(os.environ['ROTROD_SOAK_DUMP'], rss=np.array(rss), stamp=stamp, source=source,
                 omega=omega, t_file=t_file)
    assert sim_growth <= RSS_GROWTH_MAX, report
    assert abs(drift) <= DRIFT_MAX, report
    assert received / expected >= RECEIVED_MIN, report
    assert not trouble, report
    assert omega.max() >= OMEGA_MAX - 0.01, report     # the command stream was applied
    assert log_growth / minutes <= LOGGER_RSS_RATE_MAX, report
    # the logger's file: every sample from its first on, none missing
    assert len(np.unique(k_file)) == k_file[-1] + 1, report
