"""Rig identification (rotrod_core.estimation.identify) on the upright rig's records,
against targets.

    .venv/bin/python bench/bench_identify.py [--seeds 50] [--json FILE]

Prints a Markdown table (measurement, value, target, met) and the Cramer-Rao bound
beside; ``measure()`` returns its rows (bench/results.py). The record: m = 0.3 kg,
k = 32.37 N/m (Young's modulus chosen so that 3 E I / l^3 = 32.37 with the default
rod), r0 = 0.08 m, no damping; a linear ramp at 0.5 rad/s^2 to 2 rad/s (RampProfile,
4 s) then a 10 s hold, sampled at 1 kHz, simulated with rotrod's simulate; w' is not
given to the estimator (it differentiates w). Truth: w0 = sqrt(k/m), r0 as built.

Rows: noise-free errors; 40 dB SNR (noise sigma = RMS|r| / 100 on u and on v,
independently) over ``--seeds`` seeds: the RMS error, the reported standard deviations
against the observed spread, the Cramer-Rao bound at the true parameters, and the
equation-error start alone; the Eq. 26 run (40 s at 1 kHz, from rest) noise-free and at
40 dB: what is identifiable and how well; the cost of a sliding-window update (10 s
window at 100 Hz, every 0.1 s, RigIdentifier), wall-clock and thread CPU time.
"""

import argparse
import gc
import math
import os
import platform
import sys
import time
from pathlib import Path

os.environ.setdefault('OPENBLAS_NUM_THREADS', '1')

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / 'bench'), str(ROOT / 'test')]

import results  # noqa: E402  (bench/results.py)
from results import Row, Target  # noqa: E402
from sensor_records import encoder_angles, imu_xy  # noqa: E402  (test/sensor_records.py)

from rotrod_core import (  # noqa: E402
    Eq26Profile,
    NotIdentifiable,
    RampProfile,
    RigIdentifier,
    RodParams,
    identify_rig,
    rig_cramer_rao,
    simulate,
)
from rotrod_core.estimation.identify import (  # noqa: E402
    Accelerometer,
    _modulating_start,
    _record,
)

K, M, R0 = 32.37, 0.3, 0.08
W0 = math.sqrt(K / M)
I_AREA = math.pi * 0.003**4 / 64
RIG = RodParams(mass=M, youngs_modulus=K * 0.3**3 / (3 * I_AREA), eccentricity=R0)
PROFILE = RampProfile(omega_target=2.0, ramp_time=4.0)
BENCH = 'identify'


def snr40(run):
    return math.sqrt(float(np.mean(run.u**2 + run.v**2))) / 100


def noisy(run, sigma, rng):
    n = len(run.t)
    return run.u + sigma * rng.standard_normal(n), run.v + sigma * rng.standard_normal(n)


def noise_free(run):
    est = identify_rig(run.t, run.u, run.v, run.omega)
    return abs(est.natural_frequency / W0 - 1), abs(est.eccentricity / R0 - 1)


def noise_trials(run, seeds):
    sigma = snr40(run)
    crb = rig_cramer_rao(run.t, run.omega, W0, R0, 0.0, sigma, omega_dot=run.omega_dot)
    rng = np.random.default_rng(2014)
    err, std, start = [], [], []
    for _ in range(seeds):
        u, v = noisy(run, sigma, rng)
        a, _, r0 = _modulating_start(_record(run.t, u, v, run.omega))
        start.append([math.sqrt(a) - W0, r0 - R0])
        est = identify_rig(run.t, u, v, run.omega)
        err.append([est.natural_frequency - W0, est.eccentricity - R0, est.damping_ratio])
        std.append([est.natural_frequency_std, est.eccentricity_std, est.damping_ratio_std])
    return sigma, crb, np.array(err), np.array(std), np.array(start)


def eq26_report(seeds):
    """Identification from the Eq. 26 run: noise-free, and at 40 dB over some seeds."""
    run = simulate(RIG, Eq26Profile(), 40.0, dt=1e-3)
    lines = []
    est = identify_rig(run.t, run.u, run.v, run.omega)
    lines.append(f'noise-free: w0 error {abs(est.natural_frequency / W0 - 1):.2g} rel, '
                 f'r0 error {abs(est.eccentricity / R0 - 1):.2g} rel, zeta '
                 f'{est.damping_ratio:.2g} (all identifiable)')
    sigma = snr40(run)
    crb = rig_cramer_rao(run.t, run.omega, W0, R0, 0.0, sigma, omega_dot=run.omega_dot)
    rng = np.random.default_rng(26)
    err, std, refused = [], [], []
    for _ in range(seeds):
        u, v = noisy(run, sigma, rng)
        try:
            e = identify_rig(run.t, u, v, run.omega)
        except NotIdentifiable as exc:
            refused.append(exc.parameters)
            continue
        err.append([e.natural_frequency - W0, e.eccentricity - R0, e.damping_ratio])
        std.append([e.natural_frequency_std, e.eccentricity_std, e.damping_ratio_std])
    err, std = np.array(err), np.array(std)
    lines.append(f'40 dB (sigma {sigma * 1e6:.3g} um), {seeds} seeds, {len(refused)} '
                 f'refused {sorted(set(refused))}:')
    names = ('w0 (rad/s)', 'r0 (m)', 'zeta')
    keys = ('natural_frequency', 'eccentricity', 'damping_ratio')
    for i, (name, key) in enumerate(zip(names, keys)):
        if len(err):
            lines.append(f'  {name}: RMS error {np.sqrt(np.mean(err[:, i]**2)):.3g}, mean '
                         f'reported std {np.mean(std[:, i]):.3g}, CRB {crb[key]:.3g}')
    return lines, err, std, crb


REAL_RIG = RodParams(gravity=9.81, rod_density=7850.0)
"""Table 1 upright under gravity with a steel rod (config/real_rig.yaml)."""
IMU_SIGMA, IMU_BIAS = 0.02, 0.05
"""The IMU's noise per axis and sample, m/s^2, and its bias's scale (each axis's bias is
drawn from N(IMU_BIAS, (IMU_BIAS / 5)^2) per seed)."""


def sensor_trials(seeds):
    """The real rig from its deflection (40 dB) and from its IMU, 100 Hz, 10 s.

    The record: RampProfile to 2 rad/s at 0.5 rad/s^2 from t = 2 s, then a hold (the
    rig monitor's test). Per seed: the deflection with 40 dB of white noise; the IMU's
    x, y (rotrod_core.sensors.imu) with IMU_SIGMA white noise and a bias; the same with
    w and w' from the encoder's quantised angle (4096 counts). Returns, per source,
    the errors (w0, r0 relative) and reported standard deviations, and the CRBs.
    """
    run = simulate(REAL_RIG, RampProfile(2.0, 4.0, t_start=2.0), 10.0, dt=1e-2)
    w0, r0 = float(REAL_RIG.natural_frequency), float(REAL_RIG.load_radius)
    y = imu_xy(REAL_RIG, run)
    angle, _ = encoder_angles(run)
    sensor = Accelerometer.of(REAL_RIG)
    sigma_u = snr40(run)
    crb = {'deflection': rig_cramer_rao(run.t, run.omega, w0, r0, 0.0, sigma_u),
           'imu': rig_cramer_rao(run.t, run.omega, w0, r0, 0.0, IMU_SIGMA, sensor=sensor)}
    rng = np.random.default_rng(37)
    out: dict = {'deflection': [], 'imu': [], 'imu + encoder': []}
    n = len(run.t)
    for _ in range(seeds):
        u, v = noisy(run, sigma_u, rng)
        bias = complex(*rng.normal(IMU_BIAS, IMU_BIAS / 5, 2))
        m = y + IMU_SIGMA * (rng.standard_normal(n) + 1j * rng.standard_normal(n)) + bias
        hub = RigIdentifier(window=10.0, sample_interval=1e-2, hub='angle',
                            sensor=sensor)
        for t, x, yy, a in zip(run.t, m.real, m.imag, angle):
            hub.push(t, x, yy, a)
        for source, est in (
                ('deflection', identify_rig(run.t, u, v, run.omega)),
                ('imu', identify_rig(run.t, m.real, m.imag, run.omega, sensor=sensor)),
                ('imu + encoder', hub.update())):
            out[source].append([est.natural_frequency / w0 - 1, est.eccentricity / r0 - 1,
                                est.natural_frequency_std / w0,
                                est.eccentricity_std / r0])
    return {k: np.array(v) for k, v in out.items()}, crb, sigma_u, (w0, r0)


def online_cost():
    """(wall, CPU) ms per RigIdentifier update: 10 s window, 100 Hz, every 0.1 s."""
    run = simulate(RIG, PROFILE, 40.0, dt=1e-2)
    rng = np.random.default_rng(7)
    u, v = noisy(run, snr40(run), rng)
    ident = RigIdentifier(window=10.0, sample_interval=1e-2, update_interval=0.1)
    costs, errors = [], []
    gc.collect()
    for sample in zip(run.t, u, v, run.omega):
        c0, t0 = time.thread_time(), time.perf_counter()
        est = ident.push(*sample)
        wall, cpu = time.perf_counter() - t0, time.thread_time() - c0
        if ident._last_update == sample[0]:
            costs.append((1e3 * wall, 1e3 * cpu))
            if est is not None:
                errors.append((est.natural_frequency - W0) / est.natural_frequency_std)
    return np.array(costs), np.array(errors)


def measure(seeds=50, eq26_seeds=10):
    rows = []
    run = simulate(RIG, PROFILE, 14.0, dt=1e-3)

    ew, er = noise_free(run)
    rows.append(Row(BENCH, 'noise-free: w0 relative error', ew, 'relative', Target('<=', 1e-6)))
    rows.append(Row(BENCH, 'noise-free: r0 relative error', er, 'relative', Target('<=', 1e-6)))

    t0 = time.perf_counter()
    sigma, crb, err, std, start = noise_trials(run, seeds)
    per_fit = (time.perf_counter() - t0) / seeds
    rms = np.sqrt(np.mean(err**2, axis=0))
    worst = np.max(np.abs(err), axis=0)
    rep = np.mean(std, axis=0)
    note = f'{seeds} seeds, sigma {sigma * 1e6:.3g} um'
    rows.append(Row(BENCH, '40 dB: w0 worst relative error', worst[0] / W0, 'relative',
                    Target('<=', 1e-4), note=f'{note}; RMS {rms[0] / W0:.2g}, CRB '
                    f'{crb["natural_frequency"] / W0:.2g}'))
    rows.append(Row(BENCH, '40 dB: r0 worst relative error', worst[1] / R0, 'relative',
                    Target('<=', 1e-3), note=f'RMS {rms[1] / R0:.2g}, CRB '
                    f'{crb["eccentricity"] / R0:.2g}'))
    keys = ('natural_frequency', 'eccentricity', 'damping_ratio')
    for i, (name, key) in enumerate(zip(('w0', 'r0', 'zeta'), keys)):
        ratio = rep[i] / rms[i]
        rows.append(Row(BENCH, f'40 dB: reported std / observed RMS error, {name}',
                        max(ratio, 1 / ratio), 'x', Target('<=', 2.0, text='within 2x'),
                        note=f'reported {rep[i]:.3g}, observed {rms[i]:.3g}, CRB '
                        f'{crb[key]:.3g}'))
    srms = np.sqrt(np.mean(start**2, axis=0))
    rows.append(Row(BENCH, '40 dB: equation-error start alone, w0 RMS relative error',
                    srms[0] / W0, 'relative', note=f'r0 {srms[1] / R0:.2g}; refined to '
                    f'{rms[0] / W0:.2g} and {rms[1] / R0:.2g}'))
    rows.append(Row(BENCH, 'offline fit, 14001 samples', 1e3 * per_fit, 'ms'))

    trials, crb, sigma_u, (w0, r0) = sensor_trials(min(seeds, 20))
    noise = {'deflection': f'40 dB (sigma {sigma_u * 1e6:.3g} um)',
             'imu': f'{IMU_SIGMA:g} m/s^2, bias ~{IMU_BIAS:g} m/s^2',
             'imu + encoder': f'{IMU_SIGMA:g} m/s^2, bias ~{IMU_BIAS:g}, 4096 counts'}
    for source, a in trials.items():
        rms = np.sqrt(np.mean(a[:, :2] ** 2, axis=0))
        bound = crb.get(source)
        crb_text = '' if bound is None else (
            f'; CRB {bound["natural_frequency"] / w0:.2g}, {bound["eccentricity"] / r0:.2g}')
        rows.append(Row(BENCH, f'real rig from the {source}: w0 RMS relative error',
                        float(rms[0]), 'relative', Target('<=', 5e-3),
                        note=f'{noise[source]}, {len(a)} seeds; mean {a[:, 0].mean():+.2g}; '
                        f'reported {a[:, 2].mean():.2g}{crb_text}'))
        rows.append(Row(BENCH, f'real rig from the {source}: r0 RMS relative error',
                        float(rms[1]), 'relative', Target('<=', 5e-2),
                        note=f'mean {a[:, 1].mean():+.2g}; reported {a[:, 3].mean():.2g}'))

    lines, _, _, _ = eq26_report(eq26_seeds)
    costs, z = online_cost()
    warm = costs[1:]
    rows.append(Row(BENCH, 'sliding window update (1000 samples), CPU p99',
                    float(np.percentile(warm[:, 1], 99)), 'ms', Target('<=', 5.0),
                    note=f'median {np.median(warm[:, 1]):.2f}, max {warm[:, 1].max():.2f}; '
                    f'wall p99 {np.percentile(warm[:, 0], 99):.2f}; first (cold) '
                    f'{costs[0, 1]:.1f}; {len(costs)} updates; w0 error / std RMS '
                    f'{np.sqrt(np.mean(z**2)):.2f}'))
    return rows, lines


def main():
    parser = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    parser.add_argument('--seeds', type=int, default=50)
    parser.add_argument('--eq26-seeds', type=int, default=10)
    parser.add_argument('--json', type=Path)
    args = parser.parse_args()
    rows, lines = measure(args.seeds, args.eq26_seeds)
    print(f'# bench_identify ({platform.processor() or platform.machine()}, '
          f'{os.cpu_count()} CPUs, numpy {np.__version__})\n')
    print(results.markdown(rows, bench_column=False))
    print('\nEq. 26 run (40 s at 1 kHz, from rest):')
    for line in lines:
        print('  ' + line)
    if args.json:
        results.dump(args.json, rows)


if __name__ == '__main__':
    main()
