"""Benchmarks of rotrod_core against the targets of its issue, measured in one run.

    .venv/bin/python bench/bench_core.py [--quick] [--json FILE]

Prints a Markdown table: accuracy of the 40 s Eq. 26 run against a tight DOP853
reference, speed and accuracy against scipy's DOP853 at the same accuracy class, the
real-time stepper's cost per step against the 1 kHz budget, and ``simulate_batch`` at its
defaults (10,000 runs: time and accuracy of every run) against the RK4 batch it
replaced and a loop of ``simulate``, measured in the same run. ``measure()`` returns
the rows (bench/results.py).
"""

import argparse
import os
import sys
import time
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

    rows += measure_world()
    rows += measure_batch(quick)
    return rows


def measure_world() -> list:
    """The simulator's physics: a world of 1, 10 and 100 rods (velocity drive, each
    commanded its own speed), stepped in blocks of 10 (one 100 Hz publication at 1 kHz),
    ramping and holding; the cost per physics step of the whole world."""
    from rotrod_core.live.engine import EngineConfig, SimulationEngine
    from rotrod_core.live.world import World
    rows = []
    for rods in (1, 10, 100):
        for phase, settle in (('ramping at 0.5 rad/s^2', 500), ('holding its speed', 8000)):
            world = World(1000.0)
            for i in range(rods):
                SimulationEngine(EngineConfig(), world=world,
                                 name=f'rod{i}').command_omega(2.0 + 0.01 * i)
            world.advance(settle)
            blocks = 100

            def run(world=world, blocks=blocks):
                for _ in range(blocks):
                    world.advance(10)
            t, _ = best_of(run, 3)
            us = 1e6 * t / (10 * blocks)
            rows.append(Row(
                'core', f'World of {rods} rod{"s" * (rods > 1)}, velocity drive, '
                f'{phase}, 1 ms steps in blocks of 10: cost per step of the whole world '
                f'(best of 3 x {10 * blocks})', us, 'us',
                target=Target('<=', 10) if rods == 1 else None,
                note=f'{us / rods:.2f} us per rod; {us / 10:.2f} % of the 1 ms budget at '
                     '1 kHz', fmt='.3g'))
    return rows


class CpuShare:
    """Wall time, this process's CPU time (its waited-for children included), and the
    cores other processes kept busy meanwhile (from /proc/stat)."""

    @staticmethod
    def _busy():
        try:
            f = [int(x) for x in open('/proc/stat').readline().split()[1:]]
        except (OSError, ValueError):
            return float('nan')
        return (f[0] + f[1] + f[2] + f[5] + f[6]) / os.sysconf('SC_CLK_TCK')

    @staticmethod
    def _own():
        t = os.times()
        return t.user + t.system + t.children_user + t.children_system

    def __enter__(self):
        self.t0, self.b0, self.c0 = time.perf_counter(), self._busy(), self._own()
        return self

    def __exit__(self, *exc):
        self.wall = time.perf_counter() - self.t0
        self.mine = self._own() - self.c0
        self.others = max(0.0, self._busy() - self.b0 - self.mine) / self.wall
        return False


def eq26_rhs(w0sq, r0):
    """Eqs. 16/17 of an undamped round rod, hand-written (a reference independent of the code)."""
    def f(t, y):
        u, v, du, dv = y
        w, wd = eq26_scalar(t)
        return [du, dv, 2 * w * dv - (w0sq - w * w) * u + wd * v + w * w * r0,
                -2 * w * du - (w0sq - w * w) * v - wd * u - wd * r0]
    return f


def dop853(w0sq, r0, t_out):
    """(u, v) at t_out by DOP853 rtol 1e-12 atol 1e-16, piece by piece between the joints."""
    joints = (0.0, 15.0, 20.0, 35.0, 40.0)
    y, u, v = np.zeros(4), np.empty(len(t_out)), np.empty(len(t_out))
    for a, b in zip(joints[:-1], joints[1:]):
        sol = solve_ivp(eq26_rhs(w0sq, r0), (a, b), y, method='DOP853', rtol=1e-12,
                        atol=1e-16, dense_output=True)
        inside = (t_out >= a) & (t_out <= b)
        u[inside], v[inside] = sol.sol(t_out[inside])[:2]
        y = sol.y[:, -1]
    return u, v


def monte_carlo_rods(n: int, damping: float = 0.0, seed: int = 22) -> RodParams:
    """Table 1 with a manufacturing spread: r0 0.01..0.2 m, d, m +-1 %, E +-2 % (1 sigma)."""
    rng = np.random.default_rng(seed)
    return RodParams(eccentricity=rng.uniform(0.01, 0.2, n),
                     rod_diameter=0.003 * (1 + 0.01 * rng.standard_normal(n)),
                     mass=0.3 * (1 + 0.01 * rng.standard_normal(n)),
                     youngs_modulus=100e9 * (1 + 0.02 * rng.standard_normal(n)),
                     damping_ratio=damping * rng.uniform(0, 1, n))


def measure_batch(quick: bool = False) -> list:
    """simulate_batch at its defaults against today's RK4 batch and a loop of simulate.

    Every run's trajectory (every 0.1 s) and final state is compared with the RK4 batch
    at dt = 1 ms (itself checked against DOP853 on the extreme runs), and the extreme
    runs with DOP853 rtol 1e-12 directly.
    """
    rows = []
    prof = Eq26Profile()
    n = 1000 if quick else 10000
    tag = f'{n} Eq. 26 runs x 40 s (Table 1, r0 0.01-0.2 m, d, m +-1 %, E +-2 %)'
    batch = monte_carlo_rods(n)
    timings = []
    for _ in range(3 if quick else 5):
        with CpuShare() as share:
            new = simulate_batch(batch, prof, 40.0, output_interval=0.1)
        timings.append((share.wall, share.mine, share.others))
    t_new, cpu_new, others = min(timings)
    t0 = time.perf_counter()
    old = simulate_batch(batch, prof, 40.0, dt=1e-3, record_every=100, method='rk4')
    t_old = time.perf_counter() - t0
    n_loop = 10 if quick else 20
    t0 = time.perf_counter()
    for i in range(n_loop):
        simulate(batch.item(i), prof, 40.0, dt=0.01)
    t_loop = (time.perf_counter() - t0) / n_loop * n
    err_rk4 = max(np.max(np.abs(new.u - old.u)), np.max(np.abs(new.v - old.v)))
    err_end = max(np.max(np.abs(new.final.u - old.final.u)),
                  np.max(np.abs(new.final.v - old.final.v)))
    extremes = sorted({int(np.argmin(batch.eccentricity)), int(np.argmax(batch.eccentricity)),
                       int(np.argmin(batch.natural_frequency)),
                       int(np.argmax(batch.natural_frequency))})
    err_dop = err_old_dop = 0.0
    for i in extremes:
        one = batch.item(i)
        u, v = dop853(one.natural_frequency ** 2, one.eccentricity, new.t)
        err_dop = max(err_dop, np.max(np.abs(new.u[i] - u)), np.max(np.abs(new.v[i] - v)))
        err_old_dop = max(err_old_dop, np.max(np.abs(old.u[i] - u)),
                          np.max(np.abs(old.v[i] - v)))
    target = None if quick else Target('<=', 0.5)
    rows.append(Row('core', f'simulate_batch (default: tolerance 1e-10 m), {tag}, '
                            'u, v every 0.1 s: time (best of 5)',
                    t_new, 's', target=target,
                    note=f'{n / t_new:.0f} runs/s; CPU time {cpu_new:.2f} s; other '
                         f'processes used {others:.1f} of the 2 cores meanwhile; ' + ', '.join(
                        f'{k}: {v["systems"]} runs, {v["nodes"]} nodes'
                        for k, v in new.info['integrators'].items())
                    + (', quick run' if quick else ''),
                    comparisons=[Comparison('RK4 batch (before this change), dt = 1 ms'
                                            + (', 2 processes' if n >= 4000 else ''), t_old),
                                 Comparison(f'a loop of simulate (Magnus 4, dt = 10 ms), '
                                            f'{n_loop} runs scaled to {n}', t_loop)],
                    fmt='.3g'))
    rows.append(Row('core', f'simulate_batch (default), {tag}: largest |error| of u, v '
                            'over every run, every 0.1 s and at the end, vs the RK4 batch '
                            'at dt = 1 ms', max(err_rk4, err_end), 'm',
                    target=Target('<=', 1e-10),
                    note=f'the RK4 reference within {err_old_dop:.1e} m of DOP853 on the '
                         f'{len(extremes)} extreme runs', fmt='.2e'))
    rows.append(Row('core', f'simulate_batch (default), the {len(extremes)} extreme runs '
                            '(r0, w0): largest |error| every 0.1 s vs DOP853 rtol 1e-12',
                    err_dop, 'm', target=Target('<=', 1e-10),
                    comparisons=[Comparison('RK4 batch, dt = 1 ms', err_old_dop)], fmt='.2e'))
    damped = monte_carlo_rods(n, damping=0.02)
    t0 = time.perf_counter()
    res = simulate_batch(damped, prof, 40.0, output_interval=0.1)
    t_damped = time.perf_counter() - t0
    info = res.info['integrators']['magnus_complex']
    rows.append(Row('core', f'simulate_batch (default), the same {n} runs with damping '
                            'ratios 0-0.02 (sixth-order Magnus): time (no target)',
                    t_damped, 's', note=f'{n / t_damped:.0f} runs/s, step '
                    f'{info["step_s"] * 1e3:.1f} ms chosen, estimated error '
                    f'{info["estimated_error_m"]:.1e} m', fmt='.3g'))
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--quick', action='store_true', help='smaller batch (1000 systems)')
    ap.add_argument('--json', type=Path, help='write the rows as JSON here')
    args = ap.parse_args()
    rows = measure(quick=args.quick)
    return results.report(rows, args.json, title='rotrod_core benchmark', stamp=results.host())


if __name__ == '__main__':
    sys.exit(main())
