"""A fleet of ten rods on this machine, in real time: lag, messages and CPU per rod.

    .venv/bin/python bench/bench_fleet.py [--rods 10] [--duration 60] [--json FILE]

Starts the fleet as a user does (:func:`rotrod_ros.fleet.start`: N simulators in the
namespaces rod0..rod{N-1} with config/table1.yaml, config/fleet.yaml and the opt-in
real-time settings of config/realtime.yaml), in a private network namespace through
test/isolate.py, and subscribes to every rod's ``joint_states``. Over ``--duration``
seconds it measures, per rod: the publication lag behind simulated time (the DDS
source timestamp minus the stamp) at p99 and maximum, and the messages received
against the 100 Hz expected; and the CPU of all the fleet's processes. Two runs: every
rod fed by its own profile publisher (Eq. 26 in a loop, the fleet at work), and the
simulators alone, for comparison. The measurement starts SETTLE s after every rod moves:
a participant joining the DDS graph (a process starting) was seen to stall the
others' writes by up to 0.3 s. The issue's targets: every rod p99 lag <= 1 ms,
max <= 5 ms, 100 % of the messages.
"""

import argparse
import os
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

import results  # noqa: E402  (bench/results.py)
from bench_realtime import REALTIME_PARAMS, use_this_checkout  # noqa: E402
from node_probes import collect, cpu_seconds, stamp  # noqa: E402
from results import Comparison, Row, Target  # noqa: E402
from ros_harness import configure_ros_environment, rclpy_test_node  # noqa: E402

configure_ros_environment()

from sensor_msgs.msg import JointState  # noqa: E402

from rotrod_ros import fleet  # noqa: E402

PERIOD = 0.01
SETTLE = 2.0
"""Wall seconds between the fleet at work and the measurement's start."""


def fleet_run(node, rods: int, duration: float, profile: bool) -> dict:
    """One run of the fleet; per-rod lag and messages, total CPU."""
    joints = {ns: collect(node, f'{ns}/joint_states', JointState)
              for ns in fleet.namespaces(rods)}
    with tempfile.TemporaryDirectory(prefix='rotrod-fleet-') as logs:
        procs = fleet.start(rods, Path(logs), profile=profile,
                            params_files=[REALTIME_PARAMS], env=dict(os.environ))
        try:
            node.spin_until(lambda: all(len(j) > 50 for j in joints.values()), 60,
                            'every rod publishing')
            if profile:         # every stream under way: a joining participant (the
                node.spin_until(  # publisher starting) stalls DDS writes up to ~0.3 s
                    lambda: all(j[-1][0].velocity[0] > 0 for j in joints.values()), 60,
                    'every rod streamed')
            node.spin_for(SETTLE)
            pids = {name: p.pid for name, (p, _) in procs.procs.items()}
            c0 = {n: cpu_seconds(p) for n, p in pids.items()}
            t0, n0 = time.monotonic(), {ns: len(j) for ns, j in joints.items()}
            node.spin_for(duration)
            c1 = {n: cpu_seconds(p) for n, p in pids.items()}
            t1, n1 = time.monotonic(), {ns: len(j) for ns, j in joints.items()}
        finally:
            procs.stop_all()
    span = t1 - t0
    per_rod = {}
    for ns, j in joints.items():
        rows = j[n0[ns]:n1[ns]]
        lag = np.array([s for _, s, _ in rows]) - np.array([stamp(m) for m, _, _ in rows])
        per_rod[ns] = {'messages': len(rows), 'expected': round(span / PERIOD),
                       'lag_ms_p99': 1e3 * float(np.percentile(np.abs(lag), 99)),
                       'lag_ms_max': 1e3 * float(np.max(np.abs(lag)))}
    sims = [n for n in pids if n.endswith('_simulator')]
    return {'rods': rods, 'profile': profile, 'duration_s': span, 'per_rod': per_rod,
            'cpu_percent_simulators': 100 * sum(c1[n] - c0[n] for n in sims) / span,
            'cpu_percent_all': 100 * sum(c1[n] - c0[n] for n in pids) / span}


def worst(run: dict) -> dict:
    rods = run['per_rod'].values()
    return {'p99': max(r['lag_ms_p99'] for r in rods),
            'max': max(r['lag_ms_max'] for r in rods),
            'received': min(100 * r['messages'] / r['expected'] for r in rods)}


def measure(rods: int = 10, duration: float = 60.0) -> tuple:
    """Both fleet runs; return (:class:`results.Row` list, raw results)."""
    code = use_this_checkout()
    with rclpy_test_node('rotrod_fleet_bench') as node:
        busy = fleet_run(node, rods, duration, profile=True)
        alone = fleet_run(node, rods, duration, profile=False)
    w, a = worst(busy), worst(alone)
    label = f'{rods} simulators without profile publishers ({alone["duration_s"]:.0f} s run)'
    title = f'fleet of {rods} rods, each streamed Eq. 26 ({busy["duration_s"]:.0f} s run)'

    def row(name, value, unit, **kw):
        return Row('fleet', f'{title}: {name}', value, unit, **kw)

    out = [
        row('publication lag p99, worst rod', w['p99'], 'ms', target=Target('<=', 1),
            fmt='.2f', comparisons=[Comparison(label, a['p99'])]),
        row('publication lag max, worst rod', w['max'], 'ms', target=Target('<=', 5),
            fmt='.2f', comparisons=[Comparison(label, a['max'])]),
        row('messages received, worst rod', w['received'], '% of expected',
            better='higher', target=Target('>=', 100), fmt='.2f',
            comparisons=[Comparison(label, a['received'])]),
        row('CPU of the simulators, total', busy['cpu_percent_simulators'], '% of one core',
            fmt='.0f', note=f"{busy['cpu_percent_simulators'] / rods:.1f} % per rod; all "
                            f"processes {busy['cpu_percent_all']:.0f} %",
            comparisons=[Comparison(label, alone['cpu_percent_simulators'])]),
    ]
    return out, {'simulator_code': code, 'busy': busy, 'alone': alone}


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
    for name in ('busy', 'alone'):
        print(f'\n{name}:\n\n{per_rod_table(raw[name])}')
    if args.json:
        results.dump(args.json, rows, date=datetime.now(timezone.utc).isoformat(), **raw)
    return 0


if __name__ == '__main__':
    sys.exit(main())
