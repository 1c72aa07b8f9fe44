"""Benchmarks of rotrod_core against the targets of its issue, measured in one run.

    .venv/bin/python bench/bench_core.py [--quick] [--json FILE]

Prints a Markdown table: accuracy of the 40 s Eq. 26 run against a tight DOP853
reference, speed and accuracy against scipy's DOP853 at the same accuracy class, the
real-time stepper's cost per step against the 1 kHz budget, and batch throughput
against a loop of ``simulate``. ``measure()`` returns the rows (bench/results.py).
"""

import argparse
import platform
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / 'test'), str(ROOT / 'bench')]

import results  # noqa: E402  (bench/results.py)
from reference import eq26 as eq26_scalar  # noqa: E402  (docs/model.md's Eq. 26, scalar)
from results import Comparison, Row, Target  # noqa: E402

from rotrod_core import (  # noqa: E402
    Eq26Profile,
    RealTimeStepper,
    RodParams,
    simulate,
    simulate_batch,
)

P = RodParams()
W0SQ, R0 = P.stiffness / P.mass, P.eccentricity


def rhs(t, y):
    """Eqs. 16/17, hand-written with scalar floats (a fast baseline for solve_ivp)."""
    u, v, du, dv = y
    w, wd = eq26_scalar(t)
    return [du, dv, 2 * w * dv - (W0SQ - w * w) * u + wd * v + w * w * R0,
            -2 * w * du - (W0SQ - w * w) * v - wd * u - wd * R0]


def max_error(u, v, u_ref, v_ref):
    """Largest |error| of u and v against a reference, m."""
    return max(np.abs(u - u_ref).max(), np.abs(v - v_ref).max())


def best_of(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t0)
    return min(times), out


def measure(quick: bool = False) -> list:
    """Run the core benchmarks; return their :class:`results.Row` list."""
    prof = Eq26Profile()
    rows = []

    def row(name, value, unit, **kw):
        rows.append(Row('core', name, float(value), unit, **kw))

    fine = simulate(P, prof, 40.0, dt=1e-3)
    ref = solve_ivp(rhs, (0, 40), [0, 0, 0, 0], method='DOP853', rtol=1e-12, atol=1e-15,
                    t_eval=fine.t)
    err_1ms = max_error(fine.u, fine.v, ref.y[0], ref.y[1])
    row('accuracy: 40 s Eq. 26 run, dt = 1 ms, max |error| vs DOP853 rtol 1e-12',
        err_1ms, 'm', target=Target('<=', 1e-9), fmt='.2e')

    dt_fast = 0.02
    t_ours, coarse = best_of(lambda: simulate(P, prof, 40.0, dt=dt_fast), 5)
    idx = np.searchsorted(fine.t, coarse.t - 1e-9)
    err_ours = max_error(coarse.u, coarse.v, ref.y[0][idx], ref.y[1][idx])
    t_dop, sol = best_of(lambda: solve_ivp(rhs, (0, 40), [0, 0, 0, 0], method='DOP853',
                                           rtol=1e-9, atol=1e-12, t_eval=coarse.t), 3)
    err_dop = max_error(sol.y[0], sol.y[1], ref.y[0][idx], ref.y[1][idx])
    dop = 'solve_ivp DOP853 rtol 1e-9 atol 1e-12, same grid'
    row(f'simulate (Magnus, dt = {dt_fast} s), 40 s Eq. 26: max error vs the same reference',
        err_ours, 'm', target=Target('<=', 1e-10), comparisons=[Comparison(dop, err_dop)],
        fmt='.2e')
    row(f'simulate (Magnus, dt = {dt_fast} s), 40 s Eq. 26: time (best of 5; solve_ivp '
        'best of 3)', 1e3 * t_ours, 'ms', comparisons=[Comparison(dop, 1e3 * t_dop)],
        target=Target('>=', 5, text='speed-up >= 5x over solve_ivp', on='ratio'), fmt='.3g')

    n = 20000
    for drive in ('velocity', 'torque'):
        st = RealTimeStepper(P, initial={'omega': 1.0})
        step = st.step_velocity if drive == 'velocity' else st.step_torque
        arg = 0.1 if drive == 'velocity' else 0.01

        def loop(step=step, arg=arg):
            for _ in range(n):
                step(arg)
        t_step, _ = best_of(loop, 3)
        us = 1e6 * t_step / n
        row(f'RealTimeStepper, {drive} drive, 1 ms step: cost per step (best of 3 x {n})',
            us, 'us', target=Target('<=', 10),
            note=f'{us / 10:.2f} % of the 1 ms budget at 1 kHz', fmt='.3g')

    n_sys = 1000 if quick else 10000
    batch = RodParams(eccentricity=np.linspace(0.01, 0.2, n_sys))
    t0 = time.perf_counter()
    simulate_batch(batch, prof, 40.0, dt=1e-3)
    t_batch = time.perf_counter() - t0
    n_loop = 10 if quick else 20
    t0 = time.perf_counter()
    for e in np.linspace(0.01, 0.2, n_loop):
        simulate(P.replace(eccentricity=float(e)), prof, 40.0, dt=1e-3)
    t_loop = time.perf_counter() - t0
    # the target is for 10,000 systems; --quick only shows the throughput
    target = None if quick else Target('>=', 10000 / 30,
                                       text='>= 333 runs/s (10,000 runs in <= 30 s)')
    row(f'simulate_batch (RK4): {n_sys} systems x 40 s Eq. 26, dt = 1 ms: throughput',
        n_sys / t_batch, 'runs/s', better='higher', target=target,
        note=f'{n_sys} runs in {t_batch:.1f} s' + (', quick run' if quick else ''),
        comparisons=[Comparison(f'a loop of simulate (Magnus, dt = 1 ms), {n_loop} runs',
                                n_loop / t_loop)], fmt='.3g')
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--quick', action='store_true', help='smaller batch (1000 systems)')
    ap.add_argument('--json', type=Path, help='write the rows as JSON here')
    args = ap.parse_args()
    rows = measure(quick=args.quick)
    stamp = (f'{platform.node()} ({platform.machine()}, {platform.python_implementation()} '
             f'{platform.python_version()}), {datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC')
    print(f'rotrod_core benchmark on {stamp}\n')
    print(results.markdown(rows, bench_column=False))
    if args.json:
        results.dump(args.json, rows, stamp=stamp)
    return 0 if all(r.met is not False for r in rows) else 1


if __name__ == '__main__':
    sys.exit(main())
