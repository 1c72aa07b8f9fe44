"""Benchmarks of rotrod_core against the targets of its issue, measured in one run.

    .venv/bin/python bench/bench_core.py [--quick] [--json FILE]

Prints a Markdown table: accuracy of the 40 s Eq. 26 run against a tight DOP853
reference, speed against scipy's DOP853 at the same accuracy class, the real-time
stepper's cost per step, and batch throughput.
"""

import argparse
import json
import platform
import sys
import time
from datetime import datetime, timezone
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / 'test')]

from reference import eq26 as eq26_scalar  # noqa: E402  (MODEL.md's Eq. 26, scalar)

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


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--quick', action='store_true', help='smaller batch (1000 systems)')
    ap.add_argument('--json', type=Path)
    args = ap.parse_args()
    prof = Eq26Profile()
    rows = []

    fine = simulate(P, prof, 40.0, dt=1e-3)
    ref = solve_ivp(rhs, (0, 40), [0, 0, 0, 0], method='DOP853', rtol=1e-12, atol=1e-15,
                    t_eval=fine.t)
    err_1ms = max_error(fine.u, fine.v, ref.y[0], ref.y[1])
    rows.append(('accuracy: 40 s Eq. 26 run, dt = 1 ms, max |error| vs DOP853 rtol 1e-12',
                 f'{err_1ms:.2e} m', '<= 1e-9 m', err_1ms <= 1e-9))

    dt_fast = 0.02
    t_ours, coarse = best_of(lambda: simulate(P, prof, 40.0, dt=dt_fast), 5)
    idx = np.searchsorted(fine.t, coarse.t - 1e-9)
    err_ours = max_error(coarse.u, coarse.v, ref.y[0][idx], ref.y[1][idx])
    t_dop, sol = best_of(lambda: solve_ivp(rhs, (0, 40), [0, 0, 0, 0], method='DOP853',
                                           rtol=1e-9, atol=1e-12, t_eval=coarse.t), 3)
    err_dop = max_error(sol.y[0], sol.y[1], ref.y[0][idx], ref.y[1][idx])
    ratio = t_dop / t_ours
    rows.append((f'simulate (Magnus, dt = {dt_fast} s): time / max error',
                 f'{1e3 * t_ours:.1f} ms / {err_ours:.1e} m', 'error <= 1e-10 m',
                 err_ours <= 1e-10))
    rows.append(('solve_ivp DOP853 rtol 1e-9 atol 1e-12, same grid: time / max error',
                 f'{1e3 * t_dop:.1f} ms / {err_dop:.1e} m', '', True))
    rows.append(('speed-up of simulate over solve_ivp', f'{ratio:.1f}x', '>= 5x', ratio >= 5))

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
        rows.append((f'RealTimeStepper, {drive} drive, 1 ms step', f'{us:.2f} us/step',
                     '<= 10 us', us <= 10))

    n_sys = 1000 if args.quick else 10000
    batch = RodParams(eccentricity=np.linspace(0.01, 0.2, n_sys))
    t0 = time.perf_counter()
    simulate_batch(batch, prof, 40.0, dt=1e-3)
    t_batch = time.perf_counter() - t0
    # the target is for 10,000 systems; --quick only shows the throughput
    target, ok = ('<= 30 s', t_batch <= 30.0) if n_sys == 10000 else ('(quick run)', True)
    rows.append((f'simulate_batch: {n_sys} systems x 40 s Eq. 26, dt = 1 ms (RK4)',
                 f'{t_batch:.1f} s', target, ok))

    stamp = (f'{platform.node()} ({platform.machine()}, {platform.python_implementation()} '
             f'{platform.python_version()}), {datetime.now(timezone.utc):%Y-%m-%d %H:%M} UTC')
    print(f'rotrod_core benchmark on {stamp}\n')
    print('| measurement | value | target | met |\n|---|---|---|---|')
    for name, value, target, ok in rows:
        print(f'| {name} | {value} | {target} | {"yes" if ok else "NO"} |')
    if args.json:
        args.json.write_text(json.dumps({'stamp': stamp, 'rows': rows}, indent=1))
    return 0 if all(r[3] for r in rows) else 1


if __name__ == '__main__':
    sys.exit(main())
