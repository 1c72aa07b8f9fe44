"""Many rods on this machine, in real time: one world against a process per rod.

    .venv/bin/python bench/bench_fleet.py [--rods 10] [--large-rods 100]
        [--duration 60] [--baseline REV] [--json FILE]

In a private network namespace through test/isolate.py, one subscriber (this process)
takes every rod's ``tip/deflection`` as serialized bytes (reading the stamp from them:
deserializing thousands of messages a second in Python would cost the machine more
than the rods). Every rod at 2 rad/s on one setpoint of its own, but the floor's. The
runs (RUNS), side by side:

- ``world``: one ``simulator`` holding ``--rods`` rods (``rods:=N``, nothing else: its
  defaults, markers and whirl estimate on), rod0 .. rod{N-1}. The targets of issue #36
  are judged here: the simulator's CPU <= 50 % of one core, the receive lag at the
  subscriber (DDS reception time minus the stamp) p99 <= 5 ms, every message received;
- ``world_all_topics``: the same world, this process subscribed to all four sample
  topics of every rod (a topic nobody subscribes to is not published: docs/realtime.md);
- ``processes``: ``--rods`` simulator processes at their defaults, one per namespace
  (the layout before worlds, ``rotrod fleet --processes`` without config/fleet.yaml);
- ``floor``: in each namespace, instead of a simulator, bench/publication_floor.py (its
  four per-sample publications, nothing else): the floor of a process per rod;
- ``large_world``: ``rotrod fleet --rods {--large-rods}`` (one world; config/fleet.yaml:
  real time, markers and estimate off). Targets: CPU <= 100 % of one core, every
  message received, receive lag p99 <= 10 ms. Beside it, ``large_processes``: ``rotrod
  fleet --rods {--rods} --processes`` (the same files), its CPU per rod times
  ``--large-rods`` (a hundred processes of their own do not fit this machine's two
  cores: ten already take most of one); and ``large_floor``: one process of
  bench/publication_floor.py publishing the same world's tip/deflection topics
  (``--rods {--large-rods} --topics tip/deflection``: what the large world publishes to
  this subscriber, nothing else), the floor under the large world's CPU;
- ``single`` and ``single_before``: one rod at the defaults, this process subscribed to
  its four sample topics; the simulator of this checkout and the one of ``--baseline``
  (default: the last commit before worlds), three runs each, alternating. The target:
  the single-rod world costs no more than the node before worlds, within the runs'
  spread.

Per rod: the publication lag behind simulated time (DDS source time minus the stamp)
and the receive lag, at p99 and maximum, and the messages received against the 100 Hz
expected; the CPU of the run's processes and of this observer. The measurement starts
SETTLE s after every rod is at speed: a participant joining the DDS graph (a process
starting) was seen to stall the others' writes by up to 0.3 s.
"""

import argparse
import os
import struct
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
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

from geometry_msgs.msg import PointStamped, Vector3Stamped  # noqa: E402
from rotrod_interfaces.msg import DynamicFrequencies  # noqa: E402
from sensor_msgs.msg import JointState  # noqa: E402
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
BASELINE = '3e79217'
"""The last commit before worlds: its simulator is "today's node" of issue #36."""
SINGLE_RUNS = 3
"""Runs of each single-rod simulator, alternating (their spread is the target's)."""
SAMPLE_TOPICS = {'tip/deflection': Vector3Stamped, 'joint_states': JointState,
                 'tip/position': PointStamped, 'frequencies': DynamicFrequencies}
"""The four topics published with every sample; the lags are tip/deflection's."""


def stamps(node, topic: str, msg_type=Vector3Stamped) -> tuple[list, object]:
    """Subscribe to ``topic`` as bytes; return the list of (message bytes, DDS source
    time s, DDS reception time s, time this process's callback ran s), filled as
    messages arrive, and the subscription (destroyed after its run)."""
    out: list = []
    subscription = node.node.create_subscription(
        msg_type, topic,
        lambda raw, info: out.append((raw, info['source_timestamp'] * 1e-9,
                                      info['received_timestamp'] * 1e-9, time.time())),
        1000, raw=True)
    return out, subscription


def stamp_of(raw: bytes) -> float:
    """header.stamp of a serialized message, s (CDR little endian: int32 s, uint32 ns)."""
    if raw[1] != 1:
        raise ValueError(f'not little-endian CDR: encapsulation {raw[:4]!r}')
    sec, nanosec = struct.unpack_from('<iI', raw, 4)
    return sec + 1e-9 * nanosec


@dataclass(frozen=True)
class Run:
    """How one run starts its rods and what this process subscribes to."""

    label: str
    rods: int
    layout: str         # 'world', 'fleet', 'fleet_processes', 'processes', 'floor',
    #                     'world_floor'
    all_topics: bool = False     # subscribe to the four sample topics, not tip/deflection
    setpoints: bool = True       # one cmd/omega setpoint per rod
    env: dict = field(default_factory=dict)   # the processes' extra environment

    def namespaces(self) -> list[str]:
        return [''] if self.rods == 1 else fleet.namespaces(self.rods)


def start_rods(run: Run, logs: Path) -> tuple[Processes, list[str]]:
    """Start the rods as ``run`` says; return the processes once all are ready, and the
    names of the processes that are the rods (their CPU is the row's)."""
    env = {**os.environ, **run.env}
    if run.layout in ('fleet', 'fleet_processes'):
        procs = fleet.start(run.rods, logs, env=env,
                            processes=run.layout == 'fleet_processes')
        return procs, [n for n in procs.procs if n.endswith('_simulator')]
    procs = Processes(logs, ros_environment(env))
    try:
        if run.layout == 'world_floor':
            name = 'world_floor'
            procs.start(name, [sys.executable, str(publication_floor.SCRIPT), '--rods',
                               str(run.rods), '--topics', 'tip/deflection'])
            procs.wait_for_log(name, 'ready', 120)
            return procs, [name]
        if run.layout == 'world':
            name = 'world_simulator'
            procs.start(name, [*executable('simulator'), '--ros-args',
                               *(['-p', f'rods:={run.rods}', '-p',
                                  f'max_rods:={max(run.rods, 128)}'] if run.rods > 1
                                 else [])])
            procs.wait_for_log(name, 'ready', 120)
            return procs, [name]
        names = []
        for ns in run.namespaces():
            name = f'{ns[1:] or "rod"}_{run.layout}'
            argv = ([sys.executable, str(publication_floor.SCRIPT), '--ns', ns or '/']
                    if run.layout == 'floor' else
                    [*executable('simulator'), '--ros-args', '-r', f'__ns:={ns or "/"}'])
            procs.start(name, argv)
            names.append(name)
        for name in names:
            procs.wait_for_log(name, 'ready', 60)
    except BaseException:
        procs.stop_all()
        raise
    return procs, names


def measure_run(node, run: Run, duration: float) -> dict:
    """One run; per-rod lags and messages of tip/deflection, the CPU of its processes."""
    topics = SAMPLE_TOPICS if run.all_topics else {'tip/deflection': Vector3Stamped}
    subscribed = {ns: {t: stamps(node, f'{ns}/{t}', typ) for t, typ in topics.items()}
                  for ns in run.namespaces()}
    received = {ns: {t: out for t, (out, _) in by.items()} for ns, by in subscribed.items()}
    with tempfile.TemporaryDirectory(prefix='rotrod-fleet-') as logs:
        procs, rod_processes = start_rods(run, Path(logs))
        try:
            node.spin_until(lambda: all(len(r['tip/deflection']) > 50
                                        for r in received.values()), 120,
                            'every rod publishing')
            if run.setpoints:
                publishers = {ns: node.node.create_publisher(Float64, f'{ns}/cmd/omega', 10)
                              for ns in received}
                for ns, pub in publishers.items():  # one setpoint each, as a user sends it
                    node.spin_until(lambda p=pub: p.get_subscription_count() > 0, 30,
                                    f'{ns}/cmd/omega matched')
                    pub.publish(Float64(data=OMEGA))
                # every rod at speed: the shaper's ramp at the default acceleration bound
                node.spin_for(OMEGA / EngineConfig().max_angular_acceleration)
                for pub in publishers.values():
                    node.node.destroy_publisher(pub)
            node.spin_for(SETTLE)
            pids = {name: p.pid for name, (p, _) in procs.procs.items()}
            c0 = {n: cpu_seconds(p) for n, p in pids.items()}
            own0 = time.process_time()
            t0 = time.monotonic()
            n0 = {ns: {t: len(r) for t, r in by.items()} for ns, by in received.items()}
            node.spin_for(duration)
            c1 = {n: cpu_seconds(p) for n, p in pids.items()}
            own1 = time.process_time()
            t1 = time.monotonic()
            n1 = {ns: {t: len(r) for t, r in by.items()} for ns, by in received.items()}
        finally:
            procs.stop_all()
            # the next run starts with no subscription of this one: an observer that
            # kept them took every later run's messages on rod0.. once per earlier run
            for by in subscribed.values():
                for _, subscription in by.values():
                    node.node.destroy_subscription(subscription)
    span = t1 - t0
    per_rod = {}
    for ns, by in received.items():
        counts = {}
        for topic, r in by.items():
            rows = r[n0[ns][topic]:n1[ns][topic]]
            stamp = np.array([stamp_of(raw) for raw, *_ in rows])
            k = np.round((stamp - stamp[0]) / PERIOD)
            counts[topic] = (len(rows), int(k[-1]) + 1)
            if topic == 'tip/deflection':
                lag = np.array([source for _, source, _, _ in rows]) - stamp
                got = np.array([at for _, _, at, _ in rows]) - stamp
                called = np.array([at for *_, at in rows]) - stamp
                per_rod[ns or '/'] = {
                    'lag_ms_p99': 1e3 * float(np.percentile(np.abs(lag), 99)),
                    'lag_ms_max': 1e3 * float(np.max(np.abs(lag))),
                    'receive_lag_ms_p99': 1e3 * float(np.percentile(got, 99)),
                    'receive_lag_ms_max': 1e3 * float(np.max(got)),
                    'callback_lag_ms_p99': 1e3 * float(np.percentile(called, 99))}
        per_rod[ns or '/'].update(
            messages=sum(c[0] for c in counts.values()),
            expected=sum(c[1] for c in counts.values()))
    return {'label': run.label, 'rods': run.rods, 'layout': run.layout,
            'duration_s': span, 'per_rod': per_rod,
            'cpu_percent_rods': 100 * sum(c1[n] - c0[n] for n in rod_processes) / span,
            'cpu_percent_all': 100 * sum(c1[n] - c0[n] for n in pids) / span,
            'cpu_percent_observer': 100 * (own1 - own0) / span}


def worst(run: dict) -> dict:
    rods = run['per_rod'].values()
    return {'p99': max(r['lag_ms_p99'] for r in rods),
            'max': max(r['lag_ms_max'] for r in rods),
            'receive_p99': max(r['receive_lag_ms_p99'] for r in rods),
            'receive_max': max(r['receive_lag_ms_max'] for r in rods),
            'callback_p99': max(r['callback_lag_ms_p99'] for r in rods),
            'received': min(100 * r['messages'] / r['expected'] for r in rods),
            'cpu': run['cpu_percent_rods']}


def baseline_tree(rev: str, into: Path) -> Path:
    """The code of commit ``rev`` (git archive) under ``into``; its root."""
    archive = subprocess.run(['git', '-C', str(ROOT), 'archive', rev], check=True,
                             capture_output=True).stdout
    subprocess.run(['tar', '-x', '-C', str(into)], input=archive, check=True)
    return into


def runs_of(rods: int, large: int) -> dict[str, Run]:
    """Every run but the single-rod ones, in the order they go."""
    return {
        'world': Run(f'one world of {rods} rods (rods:={rods}) at the defaults', rods,
                     'world'),
        'world_all_topics': Run('the same world, its four sample topics subscribed',
                                rods, 'world', all_topics=True),
        'processes': Run(f'{rods} simulator processes at the defaults, one per namespace '
                         '(the layout before worlds)', rods, 'processes'),
        'floor': Run(f"{rods} processes of the floor: the four per-sample publications "
                     'from a bare rclpy thread each (bench/publication_floor.py: no '
                     'physics, estimate or markers)', rods, 'floor', setpoints=False),
        'large_world': Run(f'rotrod fleet --rods {large}: one world, config/fleet.yaml '
                           '(real time, markers and estimate off)', large, 'fleet'),
        'large_processes': Run(f'rotrod fleet --rods {rods} --processes (the same files)',
                               rods, 'fleet_processes'),
        'large_floor': Run(f'the floor of {large} rods in one process: their tip/deflection '
                           'publications from one bare rclpy thread (bench/'
                           'publication_floor.py --rods, nothing else)', large,
                           'world_floor', setpoints=False),
    }


def measure(rods: int = 10, large: int = 100, duration: float = 60.0,
            baseline: str = BASELINE) -> tuple:
    """The runs; return (:class:`results.Row` list, raw results)."""
    code = use_this_checkout()
    with tempfile.TemporaryDirectory(prefix='rotrod-baseline-') as tmp:
        before = baseline_tree(baseline, Path(tmp))
        single = Run('one rod at the defaults, four topics subscribed', 1, 'processes',
                     all_topics=True)
        single_before = Run(f'the same, the simulator of {baseline} (before worlds)', 1,
                            'processes', all_topics=True,
                            env={'PYTHONPATH': os.pathsep.join(
                                [str(before), *os.environ['PYTHONPATH'].split(os.pathsep)[1:]])})
        with rclpy_test_node('rotrod_fleet_bench') as node:
            runs = {key: measure_run(node, run, duration)
                    for key, run in runs_of(rods, large).items()}
            singles: dict[str, list] = {'single': [], 'single_before': []}
            for _ in range(SINGLE_RUNS):
                for key, run in (('single', single), ('single_before', single_before)):
                    singles[key].append(measure_run(node, run, duration / 2))
    w = {key: worst(run) for key, run in runs.items()}

    def row(title, name, value, unit, **kw):
        return Row('fleet', f'{title}: {name}', value, unit, **kw)

    def cpu_note(run):
        return (f"{run['cpu_percent_rods'] / run['rods']:.1f} % per rod; all the run's "
                f"processes {run['cpu_percent_all']:.0f} %, this observer "
                f"{run['cpu_percent_observer']:.0f} %")

    def others(keys, key, note=None):
        return tuple(Comparison(f"{runs[k]['label']} ({runs[k]['duration_s']:.0f} s run)"
                                + (f'; {note(runs[k])}' if note else ''), w[k][key])
                     for k in keys)

    small = ('world_all_topics', 'processes', 'floor')
    title = (f"{runs['world']['label']}, each at {OMEGA:g} rad/s on one setpoint "
             f"({runs['world']['duration_s']:.0f} s run), one subscriber of every "
             'tip/deflection')
    d = w['world']
    out = [
        row(title, 'CPU of the simulator', d['cpu'], '% of one core',
            target=Target('<=', 50), fmt='.0f', note=cpu_note(runs['world']),
            comparisons=others(small, 'cpu', cpu_note)),
        row(title, 'receive lag at the subscriber (DDS reception time minus the stamp), '
            'p99, worst rod', d['receive_p99'], 'ms', target=Target('<=', 5), fmt='.2f',
            note=f"max {d['receive_max']:.1f} ms; this Python observer's callback ran "
                 f"{d['callback_p99']:.1f} ms after the stamp at p99",
            comparisons=others(small, 'receive_p99')),
        row(title, 'messages received, worst rod', d['received'], '% of expected',
            better='higher', target=Target('>=', 100), fmt='.2f',
            comparisons=others(small, 'received')),
        row(title, 'publication lag (DDS source time minus the stamp) p99, worst rod',
            d['p99'], 'ms', target=Target('<=', 1), fmt='.2f', note=f"max {d['max']:.2f} ms",
            comparisons=others(small, 'p99')),
    ]
    big, per_process = runs['large_world'], runs['large_processes']
    title = (f"{big['label']}, each at {OMEGA:g} rad/s on one setpoint "
             f"({big['duration_s']:.0f} s run), one subscriber of every tip/deflection")
    d = w['large_world']
    scaled = per_process['cpu_percent_rods'] / per_process['rods'] * large
    out += [
        row(title, 'CPU of the simulator', d['cpu'], '% of one core',
            target=Target('<=', 100), fmt='.0f', note=cpu_note(big),
            comparisons=(Comparison(
                f"{per_process['label']} ({per_process['duration_s']:.0f} s run): its CPU "
                f'per rod times {large}', scaled, cpu_note(per_process)),
                *others(('large_floor',), 'cpu', cpu_note))),
        row(title, 'receive lag at the subscriber, p99, worst rod', d['receive_p99'], 'ms',
            target=Target('<=', 10), fmt='.2f', note=f"max {d['receive_max']:.1f} ms",
            comparisons=others(('large_processes', 'large_floor'), 'receive_p99')),
        row(title, 'messages received, worst rod', d['received'], '% of expected',
            better='higher', target=Target('>=', 100), fmt='.2f',
            comparisons=others(('large_processes', 'large_floor'), 'received')),
    ]
    cpu = {k: np.array([r['cpu_percent_rods'] for r in v]) for k, v in singles.items()}
    spread = max(float(np.ptp(c)) for c in cpu.values())
    difference = float(np.mean(cpu['single']) - np.mean(cpu['single_before']))
    least_received = min(worst(r)['received'] for v in singles.values() for r in v)
    out.append(Row(
        'fleet', f'{single.label} ({duration / 2:.0f} s runs, {SINGLE_RUNS} of each, '
        'alternating): CPU of the single-rod world minus the node before worlds '
        f'({baseline}), mean', difference, '% of one core',
        target=Target('<=', spread, text=f'<= the runs\' spread ({spread:.1f} %)'),
        fmt='.1f',
        note=(f"this checkout {', '.join(f'{c:.1f}' for c in cpu['single'])} %; "
              f"{baseline} {', '.join(f'{c:.1f}' for c in cpu['single_before'])} %; "
              f'worst received {least_received:.2f} %')))
    return out, {'simulator_code': code, **runs, **singles}


def per_rod_table(run: dict) -> str:
    lines = ['| rod | lag p99 [ms] | lag max [ms] | received |', '|---|---|---|---|']
    for ns, r in run['per_rod'].items():
        lines.append(f"| {ns} | {r['lag_ms_p99']:.2f} | {r['lag_ms_max']:.2f} | "
                     f"{r['messages']} / {r['expected']} |")
    return '\n'.join(lines)


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--rods', type=int, default=10)
    ap.add_argument('--large-rods', type=int, default=100)
    ap.add_argument('--duration', type=float, default=60.0, help='each run, s (>= 5)')
    ap.add_argument('--baseline', default=BASELINE,
                    help='the commit whose simulator the single rod is compared with')
    ap.add_argument('--json', type=Path, help='write the rows and raw results as JSON here')
    args = ap.parse_args()
    if args.duration < 5:
        ap.error('--duration must be at least 5 s')
    rows, raw = measure(args.rods, args.large_rods, args.duration, args.baseline)
    print(f'# rotrod fleet benchmark ({args.rods} and {args.large_rods} rods, '
          f'{args.duration:g} s runs, {os.cpu_count()} cores)\n')
    print(results.markdown(rows, bench_column=False))
    for name, run in raw.items():
        if isinstance(run, dict) and 'per_rod' in run and run['rods'] <= 20:
            print(f'\n{name}:\n\n{per_rod_table(run)}')
    if args.json:
        results.dump(args.json, rows, date=datetime.now(timezone.utc).isoformat(), **raw)
    return 0


if __name__ == '__main__':
    sys.exit(main())
