"""Sweeps on Dask: throughput with 1 and 2 LocalCluster workers, overhead vs in-process.

    .venv/bin/python bench/bench_sweep.py [--quick] [--json FILE]

The same Monte Carlo parameter sets (bench_core.monte_carlo_rods, damping ratios 0-0.02,
so most runs take the sixth-order Magnus integrator) run through ``run_sweep`` on a
LocalCluster of 1, then 2 worker processes (one thread each, 127.0.0.1, no dashboard),
on 1 worker started with Dask's default allocator setting, and through
``simulate_batch`` in this process (2 forked processes). Cluster start-up is not timed;
each sweep is timed from its first task to its last result (best of 2).
"""

import argparse
import os
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / 'test'), str(ROOT / 'bench')]

import results  # noqa: E402  (bench/results.py)
from bench_core import monte_carlo_rods  # noqa: E402
from results import Comparison, Row, Target  # noqa: E402

from rotrod_core import Eq26Profile, simulate_batch  # noqa: E402
from rotrod_core.offline.sweep import SweepClient, run_sweep  # noqa: E402


class DaskDefaultCluster:
    """A LocalCluster as Dask starts it by default (MALLOC_TRIM_THRESHOLD_=65536)."""

    def __init__(self, workers):
        self.workers = workers

    def __enter__(self):
        from distributed import Client, LocalCluster
        self.cluster = LocalCluster(n_workers=self.workers, threads_per_worker=1,
                                    host='127.0.0.1', dashboard_address=None)
        self.client = Client(self.cluster)
        return self.client

    def __exit__(self, *exc):
        self.client.close()
        self.cluster.close()
        return False


def sweep_rate(table, workers: int, repeat: int = 2, dask_default: bool = False) -> tuple:
    """(best runs/s, cores other processes kept busy then) of run_sweep on ``workers``.

    Other processes: the machine's busy time less the CPU time of the workers, the
    scheduler and this process.
    """
    n = len(next(iter(table.values())))
    best, others = 0.0, 0.0
    cluster = DaskDefaultCluster(workers) if dask_default else SweepClient(None, workers)
    with cluster as client:
        run_sweep({k: v[:256] for k, v in table.items()}, Eq26Profile(), 40.0,
                  client=client, chunk_size=128)                       # warm the workers
        for _ in range(repeat):
            w0, me0 = client.run(cpu_seconds), cpu_seconds()
            b0, t0 = busy_cores(), time.perf_counter()
            summary = run_sweep(table, Eq26Profile(), 40.0, client=client, chunk_size=1024)
            wall = time.perf_counter() - t0
            ours = sum(client.run(cpu_seconds).values()) - sum(w0.values()) \
                + cpu_seconds() - me0
            if summary.ok != n:
                raise RuntimeError(f'the sweep lost runs: {summary.ok} of {n}')
            if n / wall > best:
                best = n / wall
                others = max(0.0, busy_cores() - b0 - ours) / wall
    return best, others


def cpu_seconds() -> float:
    """CPU seconds of the calling process."""
    t = os.times()
    return t.user + t.system


def busy_cores() -> float:
    """CPU seconds the whole machine has been busy since boot (/proc/stat)."""
    f = [int(x) for x in open('/proc/stat').readline().split()[1:]]
    return (f[0] + f[1] + f[2] + f[5] + f[6]) / os.sysconf('SC_CLK_TCK')


def measure(quick: bool = False) -> list:
    """Run the sweep benchmarks; return their rows."""
    n = 4096 if quick else 16384
    params = monte_carlo_rods(n, damping=0.02)
    fields = ('eccentricity', 'rod_diameter', 'mass', 'youngs_modulus', 'damping_ratio')
    table = {k: getattr(params, k) for k in fields}
    one, others_one = sweep_rate(table, 1)
    two, others_two = sweep_rate(table, 2)
    trimmed, _ = sweep_rate(table, 1, repeat=1, dask_default=True)
    best = 0.0
    for _ in range(2):
        t0 = time.perf_counter()
        simulate_batch(params, Eq26Profile(), 40.0, workers=2)
        best = max(best, n / (time.perf_counter() - t0))
    what = f'{n} Eq. 26 runs x 40 s, damping ratios 0-0.02, chunks of 1024'
    return [
        Row('sweep', f'run_sweep on a LocalCluster of 2 worker processes, {what}: '
                     'throughput (best of 2)', two, 'runs/s', better='higher',
            target=Target('>=', 1.8, text='>= 1.8x the 1-worker throughput', on='ratio'),
            note=f'other processes kept {others_two:.1f} of the 2 cores busy meanwhile',
            comparisons=[Comparison('1 worker process', one,
                                    note=f'others: {others_one:.1f} cores')],
            fmt='.4g'),
        Row('sweep', f'run_sweep on 1 worker process, {what}: throughput', one, 'runs/s',
            better='higher', comparisons=[Comparison(
                "1 worker as Dask starts it by default (MALLOC_TRIM_THRESHOLD_=65536, which "
                'rotrod sweep unsets)', trimmed)], fmt='.4g'),
        Row('sweep', f'run_sweep on 2 workers against simulate_batch in this process, '
                     f'{what}: throughput', two, 'runs/s', better='higher',
            comparisons=[Comparison('simulate_batch, in process, 2 forked processes', best)],
            note=f'overhead {100 * (best / two - 1):.0f} % of the in-process time'
            if two < best else 'no overhead measured', fmt='.4g'),
    ]


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--quick', action='store_true', help='4096 runs instead of 16384')
    ap.add_argument('--json', type=Path, help='write the rows as JSON here')
    args = ap.parse_args()
    return results.report(measure(quick=args.quick), args.json)


if __name__ == '__main__':
    sys.exit(main())
