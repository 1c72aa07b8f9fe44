"""Real-time benchmark of the simulator node against the targets of its issue.

    .venv/bin/python bench/bench_realtime.py [--duration 60] [--json FILE]

Runs the ``simulator`` console script as a separate process (in a private network
namespace through test/isolate.py, DDS on loopback only) and measures, from this
process's subscriptions:

* CPU of the simulator process, % of one core (1 kHz physics, 100 Hz publishing,
  markers and the estimate on, the rod whirling at 2 rad/s: MOTION), over
  ``--duration`` seconds;
* lag of publication behind simulated time: the DDS source timestamp (wall clock at
  publish) minus the message stamp (simulated time, as wall-clock time at factor 1);
* publish-interval error: the source-timestamp intervals minus the 10 ms period;
* command latency: a cmd/omega step from rest until tip/deflection moves, from the
  command's publish time to the source timestamp of the first moved deflection;
* as-fast-as-possible mode (real_time_factor 0): simulated seconds per wall second
  while publishing every 10 ms of simulated time;
* the machine's floor: how late a bare Python thread at SCHED_FIFO 50 wakes from
  sleeping to 10 ms deadlines (as cyclictest), over the same duration, without and
  with a CPU wake-up latency request of 0 us (idle CPUs poll instead of halting);
* what a wake-up costs: the CPU time of one rclpy publication (std_msgs/Float64, no
  subscriber) in a loop and as the first work after a 10 ms sleep, the simulator's
  pattern (on a virtual machine whose idle CPU halts, the woken thread finds its
  caches and translations cold);
* the same real-time run with ordinary scheduling of the physics thread
  (``realtime_priority:=0``), with the opt-in poll of the clock before each
  publication (``publication_spin``), with the markers and the estimate off (what each
  costs), and tuned: with ``config/realtime.yaml`` (the machine-wide CPU wake-up latency
  request of 0 us while paced), each named in the table's comparison column;
* where the physics thread's CPU goes, part by part (bench/node_cpu_parts.py: the
  node at its defaults in a child process with a timer around each part of its work);
* as fast as possible at the defaults with ``rerun_logger`` started first (the simulator
  waits for its subscriptions, then KEEP_ALL both ways): speed, and the share of the
  publications in its .rrd file.

Every simulator runs at its defaults (the rod's are Table 1's) but for the motion
(MOTION) and the parameter a comparison names; targets are judged at the defaults.

Prints a Markdown table and writes JSON if asked; ``measure()`` returns the rows
(bench/results.py). The node processes run the code of this checkout: PYTHONPATH is
made to start with it (inherited by the nodes), and checked before the runs.
"""

import argparse
import json
import math
import os
import platform
import signal
import subprocess
import sys
import tempfile
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / 'test'), str(ROOT / 'bench')]

if not os.environ.get('ROTROD_ISOLATION'):
    os.execv(sys.executable, [sys.executable, str(ROOT / 'test' / 'isolate.py'),
                              sys.executable, *sys.argv])

import publication_floor  # noqa: E402  (bench/publication_floor.py)
import results  # noqa: E402  (bench/results.py)
from node_probes import collect, cpu_seconds, stamp  # noqa: E402
from results import Comparison, Row, Target  # noqa: E402
from ros_harness import (  # noqa: E402
    HarnessTimeout,
    configure_ros_environment,
    console_script,
    isolation_mode,
    rclpy_test_node,
    ros_arguments,
)

configure_ros_environment()

from geometry_msgs.msg import Vector3Stamped  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
from std_msgs.msg import Float64  # noqa: E402
from std_srvs.srv import Trigger  # noqa: E402

PERIOD = 0.01
REALTIME_PARAMS = ROOT / 'config' / 'realtime.yaml'
"""The opt-in real-time settings of the tuned runs (the named second column)."""
TUNED = 'tuned: config/realtime.yaml (cpu_dma_latency 0: idle CPUs poll, machine-wide)'
"""How the tuned runs are named in the table."""
CPU_TARGET = 6.0
"""The simulator's CPU at its defaults, % of one core: at most this (the issue's)."""
SPIN = 3e-4
"""publication_spin of the comparison run with the opt-in poll, s."""


class Simulator:
    """The simulator console script as a child process, at its defaults unless
    ``tuned`` (config/realtime.yaml first) or given parameters."""

    extra: dict = {}
    """Parameters given to every simulator started (--param)."""

    def __init__(self, tuned: bool = False, **params):
        ros_args = ros_arguments(params={**Simulator.extra, **params})
        files = ['--params-file', str(REALTIME_PARAMS)] if tuned else []
        cmd = [*console_script('simulator'), ros_args[0], *files, *ros_args[1:]]
        self.proc = subprocess.Popen(cmd, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                                     text=True)

    def stop(self) -> float:
        """SIGINT; return the seconds it took to exit (inf if it had to be killed)."""
        t0 = time.monotonic()
        self.proc.send_signal(signal.SIGINT)
        try:
            self.proc.wait(timeout=5)
            return time.monotonic() - t0
        except subprocess.TimeoutExpired:
            self.proc.kill()
            self.proc.wait()
            return float('inf')


class PublicationFloor(Simulator):
    """bench/publication_floor.py as a child process: the simulator's four per-sample
    publications every 10 ms from a bare rclpy thread, nothing else."""

    def __init__(self):
        self.proc = subprocess.Popen(
            [sys.executable, str(publication_floor.SCRIPT)],
            stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)


MOTION = {'initial.omega': 2.0, 'initial.u': 1e-3}
"""The real-time runs' rod: at the paper's 2 rad/s hold, whirling from a 1 mm deflection
(the estimate has a motion to estimate; at rest it is cheaper)."""


def realtime_run(node, duration: float, tuned: bool = False, floor: bool = False,
                 **params) -> dict:
    """The simulator's real-time run with ``params``; with ``floor``, the same
    measurement of :class:`PublicationFloor` instead."""
    sim = PublicationFloor() if floor else Simulator(tuned, **{**MOTION, **params})
    joint = collect(node, 'joint_states', JointState)
    try:
        node.spin_until(lambda: len(joint) > 50, 30, 'simulator publishing')
        c0, t0, n0 = cpu_seconds(sim.proc.pid), time.monotonic(), len(joint)
        node.spin_for(duration)
        c1, t1 = cpu_seconds(sim.proc.pid), time.monotonic()
    finally:
        exit_s = sim.stop()
    rows = joint[n0:]
    stamps = np.array([stamp(m) for m, _, _ in rows])
    source = np.array([s for _, s, _ in rows])
    lag = source - stamps
    interval_error = np.abs(np.diff(source) - PERIOD)
    return {
        'params': params, 'duration_s': t1 - t0, 'messages': len(rows),
        'expected_messages': round((t1 - t0) / PERIOD),
        'cpu_percent_of_one_core': 100 * (c1 - c0) / (t1 - t0),
        'lag_ms_median': 1e3 * float(np.median(lag)) if len(lag) else None,
        'lag_ms_max': 1e3 * float(np.max(np.abs(lag))) if len(lag) else None,
        'lag_ms_p99': 1e3 * float(np.percentile(np.abs(lag), 99)) if len(lag) else None,
        'lag_drift_ms': 1e3 * float(np.median(lag[-100:]) - np.median(lag[:100]))
        if len(lag) > 200 else None,
        'interval_error_ms_p99': 1e3 * float(np.percentile(interval_error, 99))
        if len(interval_error) else None,
        'interval_error_ms_max': 1e3 * float(np.max(interval_error))
        if len(interval_error) else None,
        'exit_after_sigint_s': exit_s,
    }


def command_latency(node, trials: int) -> dict:
    sim = Simulator()
    defl = collect(node, 'tip/deflection', Vector3Stamped)
    pub = node.node.create_publisher(Float64, 'cmd/omega', 10)
    latencies = []
    try:
        node.spin_until(lambda: pub.get_subscription_count() > 0 and len(defl) > 20, 30,
                        'simulator ready')
        for trial in range(trials):
            reply = node.call_service(Trigger, 'rotrod_simulator/reset')
            assert reply.success
            node.spin_for(0.2)
            n = len(defl)
            sent = time.time()
            pub.publish(Float64(data=0.5))

            def moved(n=n, sent=sent):
                return [src for m, src, _ in defl[n:]
                        if src > sent and (m.vector.x != 0.0 or m.vector.y != 0.0)]
            try:
                first = node.spin_until(moved, 5, 'deflection moves')[0]
            except HarnessTimeout as exc:
                last = defl[-1][0].vector if defl else None
                raise HarnessTimeout(f'trial {trial}: {exc}; {len(defl) - n} deflections '
                                     f'received since the command, the last {last}, '
                                     f'simulator exit code {sim.proc.poll()}') from None
            latencies.append(first - sent)
    finally:
        sim.stop()
    lat = np.array(latencies)
    return {'trials': trials, 'latency_ms_median': 1e3 * float(np.median(lat)),
            'latency_ms_max': 1e3 * float(np.max(lat)),
            'latency_publish_periods_max': float(np.max(lat) / PERIOD)}


def fast_run(node, duration: float) -> dict:
    sim = Simulator(real_time_factor=0.0)
    joint = collect(node, 'joint_states', JointState)
    try:
        node.spin_until(lambda: len(joint) > 50, 30, 'simulator publishing')
        n0 = len(joint)
        node.spin_for(duration)
        rows = joint[n0:]
    finally:
        sim.stop()
    stamps = np.array([stamp(m) for m, _, _ in rows])
    recv = np.array([r for _, _, r in rows])
    steps = np.diff(stamps)
    return {'wall_s': float(recv[-1] - recv[0]), 'sim_s': float(stamps[-1] - stamps[0]),
            'speed_x_real_time': float((stamps[-1] - stamps[0]) / (recv[-1] - recv[0])),
            'publish_step_sim_ms_median': 1e3 * float(np.median(steps)),
            'received_fraction': float(len(rows) / ((stamps[-1] - stamps[0]) / PERIOD + 1))}


def fast_recorded_run(duration: float) -> dict:
    """As fast as possible with rerun_logger recording (KEEP_ALL both ways): speed, and
    the share of the simulator's publications in the .rrd file."""
    import tempfile

    from rotrod_core.reporting.recording import U, read_series
    from rotrod_ros.simulator import stop_report
    out = Path(tempfile.mkdtemp(prefix='rotrod-bench-')) / 'fast.rrd'
    logger = subprocess.Popen([*console_script('rerun_logger'),
                               *ros_arguments(params={'output': str(out)})],
                              stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    try:
        while 'subscribed to the simulator' not in logger.stderr.readline():
            if logger.poll() is not None:
                raise RuntimeError('rerun_logger did not start')
        sim = Simulator(real_time_factor=0.0)    # waits for the logger by default
        while 'starting:' not in (line := sim.proc.stderr.readline()):
            if not line and sim.proc.poll() is not None:
                raise RuntimeError('the simulator did not start')
        t0 = time.monotonic()
        c0 = cpu_seconds(sim.proc.pid), cpu_seconds(logger.pid)
        time.sleep(duration)
        c1 = cpu_seconds(sim.proc.pid), cpu_seconds(logger.pid)
        wall = time.monotonic() - t0
        sim.stop()
        done = stop_report(sim.proc.stderr.read())
    finally:
        logger.send_signal(signal.SIGINT)
        logger.communicate(timeout=120)
    t_end, published = done.time, done.publications
    t, _ = read_series(out, U)
    k = np.round(t / PERIOD).astype(int)
    contiguous = bool(np.array_equal(k, np.arange(len(k))))
    out.unlink()
    return {'wall_s': wall, 'sim_s': t_end, 'speed_x_real_time': t_end / wall,
            'published': published, 'recorded': int(len(t)), 'contiguous': contiguous,
            'recorded_percent': 100.0 * min(len(t), published) / published,
            'simulator_cpu_percent': 100 * (c1[0] - c0[0]) / wall,
            'logger_cpu_percent': 100 * (c1[1] - c0[1]) / wall}


SLEEP_FLOOR = """
import json, os, sys, threading, time
from rotrod_core.live.scheduling import CpuLatencyRequest
priority, duration, period = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3])
latency = int(sys.argv[4])
request = CpuLatencyRequest()
if latency >= 0 and request.hold(latency):
    sys.exit('cannot hold the CPU latency request')
late = []
def run():
    if priority:
        os.sched_setscheduler(0, os.SCHED_FIFO, os.sched_param(priority))
    due = time.monotonic() + period
    end = due + duration
    while due < end:
        left = due - time.monotonic()
        if left > 0:
            time.sleep(left)
        late.append(time.monotonic() - due)
        due += period
thread = threading.Thread(target=run)
thread.start()
thread.join()
print(json.dumps(late))
"""


WAKE_COST = """
import json, sys, time
import rclpy
from std_msgs.msg import Float64
sleep, trials = float(sys.argv[1]), int(sys.argv[2])
rclpy.init()
node = rclpy.create_node('rotrod_wake_cost')
publisher = node.create_publisher(Float64, 'rotrod_wake_cost', 10)
msg = Float64()
def cost():
    t0 = time.thread_time()
    publisher.publish(msg)
    return time.thread_time() - t0
hot = [cost() for _ in range(trials)]
first, second = [], []
for _ in range(trials):
    time.sleep(sleep)
    first.append(cost())
    second.append(cost())
print(json.dumps({'hot': hot, 'first': first, 'second': second}))
"""


def wake_cost(sleep: float = PERIOD, trials: int = 500) -> dict:
    """CPU time (thread) of one rclpy publication, hot in a loop and as the first and
    second work after a ``sleep`` s sleep (the simulator sleeps to each publication),
    in a child process of its own: what waking up costs on this machine."""
    out = subprocess.run([sys.executable, '-c', WAKE_COST, str(sleep), str(trials)],
                         capture_output=True, text=True, check=True, timeout=120)
    r = json.loads(out.stdout)
    return {'sleep_s': sleep, 'trials': trials,
            'hot_us': 1e6 * float(np.median(r['hot'])),
            'after_sleep_us': 1e6 * float(np.median(r['first'])),
            'second_us': 1e6 * float(np.median(r['second']))}


def sleep_floor(duration: float, priority: int = 50, cpu_latency: int = -1) -> dict:
    """The machine's own wake-up lateness: a bare Python thread (no ROS, no work) at
    SCHED_FIFO ``priority`` sleeping to deadlines every 10 ms for ``duration`` s, as
    cyclictest does in C, holding a CPU wake-up latency request of ``cpu_latency`` us
    (-1: none). What the simulator's publication lag cannot go below when it only
    sleeps (by default it does not poll the clock before a publication)."""
    out = subprocess.run([sys.executable, '-c', SLEEP_FLOOR, str(priority), str(duration),
                          str(PERIOD), str(cpu_latency)], capture_output=True, text=True,
                         check=True, timeout=duration + 60)
    late = np.array(json.loads(out.stdout))
    return {'priority': priority, 'cpu_latency': cpu_latency, 'wakeups': len(late),
            'late_ms_max': 1e3 * float(late.max()),
            'late_ms_p99': 1e3 * float(np.percentile(late, 99)),
            'late_ms_median': 1e3 * float(np.median(late))}


def simulator_code() -> str:
    """Where the simulator console script imports ``rotrod_ros.simulator`` from.

    Asked of the script's own interpreter (its ``#!`` line) with this process's
    environment, which the node inherits; the bench makes PYTHONPATH start with this
    checkout, so the code measured is the code beside this file.
    """
    script = console_script('simulator')
    interpreter = [sys.executable]
    with open(script[0], 'rb') as f:
        first = f.readline().decode(errors='replace')
    if first.startswith('#!') and 'python' in first:
        interpreter = first[2:].split()
    out = subprocess.run([*interpreter, '-c', 'import rotrod_ros.simulator as m; '
                          'print(m.__file__)'], capture_output=True, text=True, check=True)
    return out.stdout.strip()


def use_this_checkout() -> str:
    """Put this checkout first on the node processes' PYTHONPATH; return the code path."""
    paths = [p for p in os.environ.get('PYTHONPATH', '').split(os.pathsep) if p]
    if not paths or Path(paths[0]).resolve() != ROOT:
        os.environ['PYTHONPATH'] = os.pathsep.join([str(ROOT), *paths])
    code = simulator_code()
    if not Path(code).resolve().is_relative_to(ROOT):
        raise RuntimeError(f'the simulator would run {code}, not the code under {ROOT}')
    return code


def cpu_parts(node, duration: float) -> dict:
    """The physics thread's CPU by part (bench/node_cpu_parts.py), the node in a child
    process with the real-time runs' parameters, this process subscribed as in them."""
    params = [f'{k}:={v}' for k, v in {**MOTION, **Simulator.extra}.items()]
    with tempfile.TemporaryFile('w+') as log:
        proc = subprocess.Popen([sys.executable, str(ROOT / 'bench' / 'node_cpu_parts.py'),
                                 str(duration), *params], stdout=subprocess.PIPE,
                                stderr=log, text=True)
        joint = collect(node, 'joint_states', JointState)
        while proc.poll() is None:
            node.spin_for(0.1)
        out = proc.stdout.read() if proc.stdout else ''
        if proc.returncode != 0 or not joint:
            log.seek(0)
            raise RuntimeError(f'node_cpu_parts.py failed (exit {proc.returncode}, '
                               f'{len(joint)} joint_states received): {log.read()[-2000:]}')
    return json.loads(out)


def measure(duration: float = 60.0) -> tuple:
    """Run the real-time benchmarks; return (:class:`results.Row` list, raw results)."""
    code = use_this_checkout()
    with rclpy_test_node('rotrod_bench') as node:
        rt = realtime_run(node, duration)
        latency = command_latency(node, trials=20)
        fast = fast_run(node, min(20.0, duration))
    recorded = fast_recorded_run(min(20.0, duration))
    with rclpy_test_node('rotrod_bench') as node:
        no_markers = realtime_run(node, min(20.0, duration), markers=False)
        no_estimate = realtime_run(node, min(20.0, duration), estimate_window=0.0)
        spin = realtime_run(node, min(20.0, duration), publication_spin=SPIN)
        parts = cpu_parts(node, min(20.0, duration))
        ordinary = realtime_run(node, duration, realtime_priority=0)
        tuned = realtime_run(node, duration, tuned=True)
        publishing = realtime_run(node, duration, floor=True)
    floor = sleep_floor(duration)
    floor_awake = sleep_floor(duration, cpu_latency=0)
    wake = wake_cost()
    raw = {'simulator_code': code, 'rmw': os.environ.get('RMW_IMPLEMENTATION'),
           'isolation': isolation_mode(), 'realtime': rt, 'command_latency': latency,
           'fast': fast, 'fast_recorded': recorded, 'wake_cost': wake,
           'ordinary_scheduling': ordinary, 'no_markers': no_markers,
           'no_estimate': no_estimate, 'publication_spin': spin, 'cpu_parts': parts,
           'tuned': tuned, 'publication_floor': publishing, 'sleep_floor': floor,
           'sleep_floor_cpu_latency_0': floor_awake}
    od = f"ordinary scheduling, realtime_priority 0 ({ordinary['duration_s']:.0f} s run)"
    tu = f"{TUNED} ({tuned['duration_s']:.0f} s run)"
    sp = (f"publication_spin {SPIN * 1e3:g} ms: polls the clock before each publication "
          f"({spin['duration_s']:.0f} s run)")

    def floor_note(percent):
        if percent >= CPU_TARGET:
            return (f'already above the {CPU_TARGET:g} % target before the 1 kHz physics, '
                    'the estimate and the markers')
        return (f'leaves {CPU_TARGET - percent:.1f} % of the {CPU_TARGET:g} % target for '
                'the 1 kHz physics, the estimate and the markers')

    def exit_note(seconds):
        return '' if math.isfinite(seconds) else 'did not exit within 5 s; killed'

    def row(name, value, unit, **kw):
        return Row('realtime', name, value, unit, **kw)

    def received(r):
        return 100 * r['messages'] / r['expected_messages']

    rows = [
        row(f'simulator CPU at its defaults, 1 kHz physics + 100 Hz publishing + markers and '
            f'estimate ({duration:g} s run)',
            rt['cpu_percent_of_one_core'], '% of one core', target=Target('<=', CPU_TARGET),
            comparisons=[
                Comparison(tu, tuned['cpu_percent_of_one_core']),
                Comparison(sp, spin['cpu_percent_of_one_core']),
                Comparison(f"markers off ({no_markers['duration_s']:.0f} s run)",
                           no_markers['cpu_percent_of_one_core']),
                Comparison(f"estimate off, estimate_window 0 "
                           f"({no_estimate['duration_s']:.0f} s run)",
                           no_estimate['cpu_percent_of_one_core'])], fmt='.1f'),
        row(f"machine floor: the simulator's four per-sample publications every 10 ms "
            f"from a bare rclpy thread, sleeping in between (bench/publication_floor.py: "
            f"no physics, estimate, markers or status; joint_states subscribed as above; "
            f"{publishing['duration_s']:.0f} s run)",
            publishing['cpu_percent_of_one_core'], '% of one core', fmt='.1f',
            note=f"{publishing['messages']} / {publishing['expected_messages']} joint_states "
                 f"received; {floor_note(publishing['cpu_percent_of_one_core'])}"),
        *(row(f"physics thread CPU by part at the defaults ({parts['duration_s']:.0f} s run, "
              f"a timer around each, in-process): {name}", part['percent'], '% of one core',
              fmt='.2f', note=f"{part['us_per_call']:.0f} us x {part['calls']} calls")
          for name, part in parts['parts'].items()),
        row(f"physics thread CPU by part ({parts['duration_s']:.0f} s run): the loop and "
            "timers, outside the parts", parts['thread_percent'] - sum(
                part['percent'] for part in parts['parts'].values()), '% of one core',
            fmt='.2f', note=f"thread total {parts['thread_percent']:.2f} %"),
        row('publication lag behind simulated time at the defaults, p99', rt['lag_ms_p99'],
            'ms', target=Target('<=', 1), fmt='.2f',
            note=f"max {rt['lag_ms_max']:.2f} ms, median {rt['lag_ms_median']:.2f} ms",
            comparisons=[Comparison(tu, tuned['lag_ms_p99'],
                                    f"max {tuned['lag_ms_max']:.2f} ms"),
                         Comparison(sp, spin['lag_ms_p99'], f"max {spin['lag_ms_max']:.2f} ms"),
                         Comparison(od, ordinary['lag_ms_p99'],
                                    f"max {ordinary['lag_ms_max']:.2f} ms")]),
        row('publication lag behind simulated time at the defaults, max', rt['lag_ms_max'],
            'ms', target=Target('<=', 2), fmt='.2f',
            comparisons=[Comparison(tu, tuned['lag_ms_max']),
                         Comparison(sp, spin['lag_ms_max']),
                         Comparison(od, ordinary['lag_ms_max'])]),
        row('drift of simulated time from the clock: median lag, last 100 minus first 100 '
            'publications', rt['lag_drift_ms'], 'ms', fmt='+.3f'),
        row(f"machine floor: a bare Python thread at SCHED_FIFO {floor['priority']} sleeping "
            f"to 10 ms deadlines, lateness (max of {floor['wakeups']}, no ROS)",
            floor['late_ms_max'], 'ms', fmt='.2f',
            note=f"p99 {floor['late_ms_p99']:.2f} ms, median {floor['late_ms_median']:.2f} ms",
            comparisons=[Comparison(
                'the same thread holding cpu_dma_latency 0 (idle CPUs poll)',
                floor_awake['late_ms_max'], f"p99 {floor_awake['late_ms_p99']:.2f} ms")]),
        row('publish-interval error (jitter), p99', rt['interval_error_ms_p99'], 'ms',
            target=Target('<=', 1), note=f"max {rt['interval_error_ms_max']:.2f} ms",
            fmt='.3f', comparisons=[Comparison(
                tu, tuned['interval_error_ms_p99'],
                f"max {tuned['interval_error_ms_max']:.2f} ms"), Comparison(
                od, ordinary['interval_error_ms_p99'],
                f"max {ordinary['interval_error_ms_max']:.2f} ms")]),
        row('messages received', received(rt), '% of expected', better='higher', fmt='.2f',
            note=f"{rt['messages']} / {rt['expected_messages']}"),
        row(f"machine: CPU time of the first rclpy publication after a "
            f"{wake['sleep_s'] * 1e3:g} ms sleep (std_msgs/Float64, no subscriber, median "
            f"of {wake['trials']}, no other work)", wake['after_sleep_us'], 'us', fmt='.1f',
            note=f"the next one {wake['second_us']:.1f} us",
            comparisons=[Comparison('the same publication in a loop, without sleeping',
                                    wake['hot_us'])]),
        row(f"cmd/omega -> tip/deflection latency (max of {latency['trials']})",
            latency['latency_ms_max'], 'ms',
            target=Target('<=', 2e3 * PERIOD, text='<= 2 publish periods (20 ms)'),
            note=f"{latency['latency_publish_periods_max']:.2f} periods, median "
                 f"{latency['latency_ms_median']:.1f} ms", fmt='.1f'),
        row('as fast as possible (real_time_factor 0), publishing every 10 ms',
            fast['speed_x_real_time'], 'x real time', better='higher',
            target=Target('>=', 20), fmt='.1f',
            note=f"publication step {fast['publish_step_sim_ms_median']:.0f} ms, "
                 f"{100 * fast['received_fraction']:.1f} % received, "
                 f"{fast['wall_s']:.0f} s run"),
        row('as fast as possible at the defaults, rerun_logger started first (the simulator '
            'waits for its subscriptions, then KEEP_ALL: for it)',
            recorded['speed_x_real_time'], 'x real time', better='higher',
            target=Target('>=', 30), fmt='.1f',
            note=f"{recorded['recorded_percent']:.2f} % of {recorded['published']} "
                 f"publications in the .rrd"
                 f"{'' if recorded['contiguous'] else ' (NOT contiguous)'}; CPU simulator "
                 f"{recorded['simulator_cpu_percent']:.0f} %, logger "
                 f"{recorded['logger_cpu_percent']:.0f} % of a core; "
                 f"{recorded['wall_s']:.0f} s run"),
        row('exit after SIGINT', rt['exit_after_sigint_s'], 's', fmt='.2f',
            note=exit_note(rt['exit_after_sigint_s'])),
    ]
    return rows, raw


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--duration', type=float, default=60.0,
                    help='length of the real-time run, s (the issue asks >= 60; at least 5)')
    ap.add_argument('--json', type=Path, help='write the rows and raw results as JSON here')
    ap.add_argument('--param', action='append', default=[], metavar='NAME:=VALUE',
                    help='a simulator parameter for every run (exploration; the README '
                         'table is made with the defaults)')
    args = ap.parse_args()
    for p in args.param:
        name, _, value = p.partition(':=')
        Simulator.extra[name] = value     # passed as written (YAML)
    if args.duration < 5:
        ap.error('--duration must be at least 5 s (the drift compares 100 publications '
                 'at each end)')
    rows, raw = measure(args.duration)
    print(f'# rotrod simulator real-time benchmark ({args.duration:g} s run, '
          f'{platform.processor() or platform.machine()}, {os.cpu_count()} cores, '
          f'Python {platform.python_version()})\n')
    print(f"simulator code: {raw['simulator_code']}\n")
    print(results.markdown(rows, bench_column=False))
    if args.json:
        results.dump(args.json, rows, date=datetime.now(timezone.utc).isoformat(), **raw)
    return 0


if __name__ == '__main__':
    sys.exit(main())
