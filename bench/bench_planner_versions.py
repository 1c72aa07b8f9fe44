"""Planning time of two versions of the planner, side by side in one run.

    .venv/bin/python bench/bench_planner_versions.py OLD_TREE [--rounds N]

OLD_TREE is a checkout of the code a change replaces (``git worktree add /tmp/old
<rev>``); this tree is the new code. For every request of bench_planner.cases(), each
round plans it cold (a fresh process, the plan cache off: bench_planner.plan_cold) with
the old code and then the new, so that both see the same machine load. Prints, per
request and version: the planning times of the rounds (s), their median, the number of
shape propagations and of sensitivity evaluations (the planner's cost, independent of
the machine's load), and the plan's duration (s).
"""

import argparse
import json
import os
import statistics
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / 'bench')]

import bench_planner  # noqa: E402

COUNTED_PLAN = """
import json, sys, time
from rotrod_core import RodParams, plan_spin_up
from rotrod_core.command import planner
counts = {'propagations': 0, 'sensitivities': 0}
values, model = planner._Limits.values, planner._Limits.model
def counted_values(self, y):
    counts['propagations'] += 1
    return values(self, y)
def counted_model(self, y):
    counts['propagations'] += self._last is None or not (self._last[0] == self.problem
        .control_points(y)).all()
    counts['sensitivities'] += 1
    return model(self, y)
target, options, timed = json.loads(sys.argv[1])
if not timed:
    planner._Limits.values, planner._Limits.model = counted_values, counted_model
t0 = time.perf_counter()
plan = plan_spin_up(RodParams(), target, **options)
seconds = time.perf_counter() - t0
json.dump({'seconds': seconds, 'duration': plan.duration, **counts}, sys.stdout)
"""


def plan(tree: Path, target: float, options: dict, timed: bool) -> dict:
    """One cold plan with the code in ``tree``: timed (no counting) or counted."""
    env = {**os.environ, bench_planner.plan_cache.ENV: bench_planner.plan_cache.OFF}
    out = subprocess.run([sys.executable, '-c', COUNTED_PLAN,
                          json.dumps([target, options, timed])],
                         env=env, cwd=tree, capture_output=True, text=True, check=True)
    return json.loads(out.stdout)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('old', type=Path, help='checkout of the code replaced')
    parser.add_argument('--rounds', type=int, default=3)
    args = parser.parse_args(argv)
    trees = {'old': args.old.resolve(), 'new': ROOT}
    print(f'load average at start: {os.getloadavg()[0]:.2f}; old = {trees["old"]}')
    print('| request | code | planning time, rounds (s) | median (s) | propagations '
          '| sensitivities | duration (s) |')
    print('|---|---|---|---|---|---|---|')
    for label, target, options, *_ in bench_planner.cases():
        shown = label.replace('|', '\\|')
        times: dict = {name: [] for name in trees}
        for _ in range(args.rounds):
            for name, tree in trees.items():
                times[name].append(plan(tree, target, options, True)['seconds'])
        for name, tree in trees.items():
            counted = plan(tree, target, options, False)
            rounds = ', '.join(f'{t:.2f}' for t in times[name])
            print(f'| {shown} | {name} | {rounds} | '
                  f'{statistics.median(times[name]):.2f} | {counted["propagations"]} | '
                  f'{counted["sensitivities"]} | {counted["duration"]:.3f} |')
    return 0


if __name__ == '__main__':
    sys.exit(main())
