"""Benchmark of the spin-up planner against the targets of its issue (#19), in one run.

    .venv/bin/python bench/bench_planner.py [--json FILE]

Table 1 parameters, 0 -> 2 rad/s under a 3 mm deflection limit: the nominal plan
(residual <= 0.25 um) and the robust one (residual <= 1 um for every natural
frequency within +-10 % of w0); then the same two within the ROS simulator's
default |w'| bound (0.5 rad/s^2). For each: planning time (best of 3), duration,
peak deflection and residual (the planner's
predictions, then re-measured by ``simulate`` with the plan's end on the time grid),
largest |w'|. Eq. 26 (15 s spin-up) gives the residual to compare with.
``measure()`` returns the rows (bench/results.py).
"""

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / 'bench')]

import results  # noqa: E402  (bench/results.py)
from results import Comparison, Row, Target  # noqa: E402

from rotrod_core import (  # noqa: E402
    Eq26Profile,
    RodParams,
    plan_spin_up,
    simulate,
    whirl_residual,
)
from rotrod_core.command import plan_cache  # noqa: E402

os.environ[plan_cache.ENV] = plan_cache.OFF     # the time of planning, not of a cache read
P = RodParams()
CASES = (('nominal', {}, 1.5, 2.5e-7), ('robust 0.1', {'robust': 0.1, 'residual': 1e-6}, 4.0,
                                         1e-6),
         ('nominal, |w\'| <= 0.5 rad/s^2', {'max_angular_acceleration': 0.5}, 6.0, 2.5e-7),
         ('robust 0.1, |w\'| <= 0.5 rad/s^2',
          {'robust': 0.1, 'residual': 1e-6, 'max_angular_acceleration': 0.5}, 8.0, 1e-6))


def best_of(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def simulated(plan, params=P):
    """Largest |r| and the residual at the plan's end, by simulate (end on the grid)."""
    run = simulate(params, plan, plan.duration, dt=plan.duration / 2000)
    peak = float(np.max(np.hypot(run.u, run.v)))
    return peak, whirl_residual(params, plan.omega_target, run.u[-1], run.v[-1], run.du[-1],
                                run.dv[-1])


def eq26_residual() -> float:
    """Free whirl left by Eq. 26's 15 s spin-up, at 15 s (simulate, 1 ms)."""
    run = simulate(P, Eq26Profile(), 15.0, dt=1e-3)
    return whirl_residual(P, 2.0, run.u[-1], run.v[-1], run.du[-1], run.dv[-1])


def measure() -> list:
    """Run the planner benchmarks; return their :class:`results.Row` list."""
    rows = []
    eq26 = eq26_residual()

    def row(name, value, unit, **kw):
        rows.append(Row('planner', name, float(value), unit, **kw))

    for label, kwargs, duration_target, residual_target in CASES:
        repeat = 1 if 'max_angular_acceleration' in kwargs else 3
        t_plan, plan = best_of(lambda kwargs=kwargs: plan_spin_up(P, 2.0, **kwargs), repeat)
        what = f'{label}, Table 1, 0 -> 2 rad/s, 3 mm'
        row(f'{what}: planning time (best of {repeat})', t_plan, 's', fmt='.3g')
        row(f'{what}: duration', plan.duration, 's', target=Target('<=', duration_target),
            comparisons=[Comparison('Eq. 26 spin-up', 15.0)], fmt='.3f')
        peak, residual = simulated(plan)
        row(f'{what}: peak |r| (simulate)', 1e3 * peak, 'mm', target=Target('<=', 3.0),
            note=f'planner predicts {1e3 * plan.peak_deflection:.6g} mm', fmt='.6g')
        row(f'{what}: residual whirl after arrival (simulate)', 1e6 * residual, 'um',
            target=Target('<=', 1e6 * residual_target),
            comparisons=[Comparison('Eq. 26, 15 s', 1e6 * eq26)],
            note=f'planner predicts {1e6 * plan.residual_amplitude:.3g} um', fmt='.3g')
        if kwargs.get('robust'):
            worst = 0.0
            for scale in np.linspace(0.9, 1.1, 21):
                p = P.replace(youngs_modulus=P.youngs_modulus * scale**2)
                worst = max(worst, simulated(plan, p)[1])
            row(f'{what}: largest residual over w0 x 0.9..1.1 (simulate, 21 rods)',
                1e6 * worst, 'um', target=Target('<=', 1e6 * residual_target),
                note=f'planner predicts {1e6 * plan.band_residual:.3g} um', fmt='.3g')
        row(f"{what}: largest |w'|", plan.max_angular_acceleration, 'rad/s^2',
            note='the ROS simulator allows 0.5 rad/s^2 by default', fmt='.3g')
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--json', type=Path, help='write the rows as JSON here')
    args = ap.parse_args()
    rows = measure()
    return results.report(rows, args.json, title='rotrod planner benchmark', stamp=results.host())


if __name__ == '__main__':
    sys.exit(main())
