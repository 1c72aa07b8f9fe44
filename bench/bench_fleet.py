"""Ten rods on this machine, in real time: lag, messages and CPU, at the defaults.

    .venv/bin/python bench/bench_fleet.py [--rods 10] [--duration 60] [--json FILE]

In a private network namespace through test/isolate.py, one subscriber (this process)
takes every rod's ``tip/deflection`` as serialized bytes (reading the stamp from them:
deserializing 1000 messages a second in Python would cost the machine more than a
rod). Four runs (MODES), each every rod at 2 rad/s but the floor's:

- ``defaults``: N ``simulator`` processes as a user starts them, with nothing but a
  namespace (/rod0 .. /rod{N-1}); one setpoint each on ``cmd/omega``. The issue's
  targets are judged here: receive lag at the subscriber (the DDS reception time of
  each message minus its stamp; the time this Python process's callback ran is
  reported beside it) p99 <= 5 ms, every message received, the simulators' CPU <= 60 %
  of a core in total;
- ``fleet``: what ``rotrod fleet`` runs (:func:`rotrod_ros.fleet.start`: config/fleet.yaml
  turns the markers and the estimates off), in the same run;
- ``streamed``: the fleet command with a profile publisher per rod streaming Eq. 26;
- ``floor``: in each namespace, instead of a simulator, bench/publication_floor.py (its
  four per-sample publications, nothing else; no setpoint): the machine's floor under
  the ``defaults`` run (docs/realtime.md#floor).

Per rod: the publication lag behind simulated time (DDS source time minus the stamp)
and the receive lag, at p99 and maximum, and the messages received against the 100 Hz
expected; the CPU of the run's processes and of this observer. The measurement starts
SETTLE s after every rod is at speed: a participant joining the DDS graph (a process
starting) was seen to stall the others' writes by up to 0.3 s.
"""

import argparse
import os
import struct
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
from bench_realtime import use_this_checkout  # noqa: E402
from node_probes import cpu_seconds  # noqa: E402
from results import Comparison, Row, Target  # noqa: E402
from ros_harness import configure_ros_environment, rclpy_test_node  # noqa: E402

configure_ros_environment()

from geometry_msgs.msg import Vector3Stamped  # noqa: E402
from std_msgs.msg import Float64  # noqa: E402

from rotrod_core.live.engine import EngineConfig  # noqa: E402
from rotrod_ros import fleet  # noqa: E402
from rotrod_ros.demo import Processes, ros_environment  # noqa: E402
from rotrod_ros.install import executable  # noqa: E402

PERIOD = 0.01
OMEGA = 2.0
"""The rods' speed, rad/s: the paper's."""
SETTLE = 2.0
"""Wall seconds between the fleet at work and the measurement's start."""


def stamps(node, topic: str, msg_type=Vector3Stamped) -> list:
    """Subscribe to ``topic`` as bytes; return the list of (message bytes, DDS source
    time s, DDS reception time s, time this process's callback ran s), filled as
    messages arrive."""
    out: list = []
    node.node.create_subscription(
        msg_type, topic,
        lambda raw, info: out.append((raw, info['source_timestamp'] * 1e-9,
                                      info['received_timestamp'] * 1e-9, time.time())),
        1000, raw=True)
    return out


def stamp_of(raw: bytes) -> float:
    """header.stamp of a serialized message, s (CDR little endian: int32 s, uint32 ns)."""
    if raw[1] != 1:
        raise ValueError(f'not little-endian CDR: encapsulation {raw[:4]!r}')
    sec, nanosec = struct.unpack_from('<iI', raw, 4)
    return sec + 1e-9 * nanosec


MODES = {
    'defaults': 'a simulator process per rod at its defaults, only a namespace each',
    'fleet': 'the fleet command (config/fleet.yaml: markers and estimates off)',
    'streamed': 'the fleet command, each rod streamed Eq. 26 by a profile publisher of '
                'its own (twice the processes)',
    'floor': "the machine's floor: in each namespace instead of a simulator, its four "
             'per-sample publications from a bare rclpy thread (bench/publication_floor.py: '
             'no physics, estimate or markers)',
}
"""The runs: how the rods are started."""
ROD_PROCESS = {'defaults': 'simulator', 'fleet': 'simulator', 'streamed': 'simulator',
               'floor': 'floor'}
"""What each run's process per rod is named after (its CPU is the rods')."""


def start_rods(mode: str, rods: int, logs: Path) -> Processes:
    """Start the rods as ``mode`` says (MODES); return the processes once all are ready."""
    if mode in ('fleet', 'streamed'):
        return fleet.start(rods, logs, profile=mode == 'streamed', env=dict(os.environ))
    procs = Processes(logs, ros_environment(dict(os.environ)))
    try:
        for ns in fleet.namespaces(rods):
            argv = ([sys.executable, str(publication_floor.SCRIPT), '--ns', ns]
                    if mode == 'floor' else
                    [*executable('simulator'), '--ros-args', '-r', f'__ns:={ns}'])
            procs.start(f'{ns[1:]}_{ROD_PROCESS[mode]}', argv)
        for ns in fleet.namespaces(rods):
            procs.wait_for_log(f'{ns[1:]}_{ROD_PROCESS[mode]}', 'ready', 60)
    except BaseException:
        procs.stop_all()
        raise
    return procs


def fleet_run(node, rods: int, duration: float, mode: str) -> dict:
    """One run; per-rod lags and messages of tip/deflection, total CPU."""
    received = {ns: stamps(node, f'{ns}/tip/deflection') for ns in fleet.namespaces(rods)}
    with tempfile.TemporaryDirectory(prefix='rotrod-fleet-') as logs:
        procs = start_rods(mode, rods, Path(logs))
        try:
            node.spin_until(lambda: all(len(r) > 50 for r in received.values()), 60,
                            'every rod publishing')
            publishers = {ns: node.node.create_publisher(Float64, f'{ns}/cmd/omega', 10)
                          for ns in received if mode in ('defaults', 'fleet')}
            for ns, pub in publishers.items():  # one setpoint each, as a user sends it
                node.spin_until(lambda p=pub: p.get_subscription_count() > 0, 30,
                                f'{ns}/cmd/omega matched')
                pub.publish(Float64(data=OMEGA))
            # every rod at speed: the shaper's ramp at the default acceleration bound
            # (a joining participant, a profile publisher, stalls DDS writes ~0.3 s)
            node.spin_for(OMEGA / EngineConfig().max_angular_acceleration)
            node.spin_for(SETTLE)
            pids = {name: p.pid for name, (p, _) in procs.procs.items()}
            c0 = {n: cpu_seconds(p) for n, p in pids.items()}
            own0 = time.process_time()
            t0, n0 = time.monotonic(), {ns: len(r) for ns, r in received.items()}
            node.spin_for(duration)
            c1 = {n: cpu_seconds(p) for n, p in pids.items()}
            own1 = time.process_time()
            t1, n1 = time.monotonic(), {ns: len(r) for ns, r in received.items()}
        finally:
            procs.stop_all()
    span = t1 - t0
    per_rod = {}
    for ns, r in received.items():
        rows = r[n0[ns]:n1[ns]]
        stamp = np.array([stamp_of(raw) for raw, *_ in rows])
        lag = np.array([source for _, source, _, _ in rows]) - stamp
        got = np.array([at for _, _, at, _ in rows]) - stamp
        called = np.array([at for *_, at in rows]) - stamp
        k = np.round((stamp - stamp[0]) / PERIOD)
        per_rod[ns] = {'messages': len(rows), 'expected': int(k[-1]) + 1,
                       'lag_ms_p99': 1e3 * float(np.percentile(np.abs(lag), 99)),
                       'lag_ms_max': 1e3 * float(np.max(np.abs(lag))),
                       'receive_lag_ms_p99': 1e3 * float(np.percentile(got, 99)),
                       'receive_lag_ms_max': 1e3 * float(np.max(got)),
                       'callback_lag_ms_p99': 1e3 * float(np.percentile(called, 99))}
    sims = [n for n in pids if n.endswith('_' + ROD_PROCESS[mode])]
    return {'rods': rods, 'mode': mode, 'duration_s': span, 'per_rod': per_rod,
            'cpu_percent_simulators': 100 * sum(c1[n] - c0[n] for n in sims) / span,
            'cpu_percent_all': 100 * sum(c1[n] - c0[n] for n in pids) / span,
            'cpu_percent_observer': 100 * (own1 - own0) / span}


def worst(run: dict) -> dict:
    rods = run['per_rod'].values()
    return {'p99': max(r['lag_ms_p99'] for r in rods),
            'max': max(r['lag_ms_max'] for r in rods),
            'receive_p99': max(r['receive_lag_ms_p99'] for r in rods),
            'receive_max': max(r['receive_lag_ms_max'] for r in rods),
            'callback_p99': max(r['callback_lag_ms_p99'] for r in rods),
            'received': min(100 * r['messages'] / r['expected'] for r in rods)}


def measure(rods: int = 10, duration: float = 60.0) -> tuple:
    """The runs (MODES); return (:class:`results.Row` list, raw results)."""
    code = use_this_checkout()
    with rclpy_test_node('rotrod_fleet_bench') as node:
        runs = {mode: fleet_run(node, rods, duration, mode) for mode in MODES}
    w = {mode: worst(run) for mode, run in runs.items()}
    title = (f'{rods} rods in real time, each at {OMEGA:g} rad/s on one setpoint, '
             f"{MODES['defaults']} ({runs['defaults']['duration_s']:.0f} s run), one "
             f'subscriber of all {rods} tip/deflection')

    def row(name, value, unit, **kw):
        return Row('fleet', f'{title}: {name}', value, unit, **kw)

    def cpu_note(run):
        return (f"{run['cpu_percent_simulators'] / rods:.1f} % per rod; all the run's "
                f"processes {run['cpu_percent_all']:.0f} %, this observer "
                f"{run['cpu_percent_observer']:.0f} %")

    def others(key, note=None):
        return [Comparison(f"{MODES[m]} ({runs[m]['duration_s']:.0f} s run)"
                           + (f'; {note(runs[m])}' if note else ''), w[m][key]
                           if key in w[m] else runs[m][key])
                for m in ('fleet', 'streamed', 'floor')]

    d = w['defaults']
    out = [
        row('receive lag at the subscriber (DDS reception time minus the stamp), p99, '
            'worst rod', d['receive_p99'], 'ms', target=Target('<=', 5), fmt='.2f',
            note=f"max {d['receive_max']:.1f} ms; this Python observer's callback ran "
                 f"{d['callback_p99']:.1f} ms after the stamp at p99",
            comparisons=others('receive_p99')),
        row('messages received, worst rod', d['received'], '% of expected',
            better='higher', target=Target('>=', 100), fmt='.2f',
            comparisons=others('received')),
        row('CPU of the simulators, total', runs['defaults']['cpu_percent_simulators'],
            '% of one core', target=Target('<=', 60), fmt='.0f',
            note=cpu_note(runs['defaults']),
            comparisons=others('cpu_percent_simulators', cpu_note)),
        row('publication lag (DDS source time minus the stamp) p99, worst rod', d['p99'],
            'ms', target=Target('<=', 1), fmt='.2f', note=f"max {d['max']:.2f} ms",
            comparisons=others('p99')),
    ]
    return out, {'simulator_code': code, **runs}


def per_rod_table(run: dict) -> str:
    lines = ['| rod | lag p99 [ms] | lag max [ms] | received |', '|---|---|---|---|']
    for ns, r in run['per_rod'].items():
        lines.append(f"| {ns} | {r['lag_ms_p99']:.2f} | {r['lag_ms_max']:.2f} | "
                     f"{r['messages']} / {r['expected']} |")
    return '\n'.join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--rods', type=int, default=10)
    ap.add_argument('--duration', type=float, default=60.0, help='each run, s (>= 5)')
    ap.add_argument('--json', type=Path, help='write the rows and raw results as JSON here')
    args = ap.parse_args()
    if args.duration < 5:
        ap.error('--duration must be at least 5 s')
    rows, raw = measure(args.rods, args.duration)
    print(f'# rotrod fleet benchmark ({args.rods} rods, {args.duration:g} s runs, '
          f'{os.cpu_count()} cores)\n')
    print(results.markdown(rows, bench_column=False))
    for name in MODES:
        print(f'\n{name}:\n\n{per_rod_table(raw[name])}')
    if args.json:
        results.dump(args.json, rows, date=datetime.now(timezone.utc).isoformat(), **raw)
    return 0


if __name__ == '__main__':
    sys.exit(main())
