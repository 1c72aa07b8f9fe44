"""Whirl-frequency estimators on the same windows: rotrod_core.estimation.whirl against baselines.

    .venv/bin/python bench/bench_estimator.py [--json FILE]

Prints a Markdown table; ``measure()`` returns its rows (bench/results.py). Methods:
the maximum-likelihood estimator of rotrod_core.estimation.whirl (ML), ESPRIT on the same 10 ms
block means after one difference (removes a constant offset exactly) and after five
(removes a quartic drift, the ML estimator's drift model), and a plain interpolated FFT
peak (linear trend removed, Hann window, parabolic interpolation of log |Z| on each
sign of frequency). All see 1 s windows at 1 kHz of z = u + i v.

Rows: the error against Eq. 28 at constant w over [0, 0.9 w0] (noise-free step and
plucked starts), the RMS error at 40 dB SNR over 200 trials against the Cramer-Rao
bound of a complex tone, the tracking error over the Eq. 26 spin-up, the windows that
straddle a joint of Eq. 26 (outside the targets: the model is stationary), and the
cost per window, as wall-clock time and as CPU time of the thread (the difference is
time spent waiting for a CPU held by other processes): online, at 1 kHz and as the
simulator node runs it (the tip published at 100 Hz, stream_estimator(1.0, 100.0, 10.0)),
and per batch call.
"""

import argparse
import gc
import math
import os
import sys
import time
from pathlib import Path

# Small matrices: BLAS threads only add hand-over costs (ESPRIT's SVD took 10x longer
# with them on this 2-CPU machine); a node would run single-threaded BLAS too.
os.environ.setdefault('OPENBLAS_NUM_THREADS', '1')

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / 'test'), str(ROOT / 'bench')]

import results  # noqa: E402  (bench/results.py)
from reference import W0, eq26  # noqa: E402  (docs/model.md's closed forms)
from results import Comparison, Row, Target  # noqa: E402

from rotrod_core import (  # noqa: E402
    ConstantProfile,
    Eq26Profile,
    RodParams,
    WhirlEstimator,
    estimate_whirl_frequencies,
    simulate,
)
from rotrod_core.estimation.whirl import stream_estimator  # noqa: E402

P = RodParams()
DT, N = 1e-3, 1000
T = np.arange(N) * DT
BLOCK = 10                  # samples per block for ESPRIT (the ML estimator's 10 ms)
F_MAX = 25.0                # Hz, the ML estimator's band
NODE_RATE = 100.0           # Hz: the rate at which the simulator node publishes the tip
NODE_P99 = 1.5              # ms per update, p99: 10 rods x 10 estimates/s <= 15 % of a core


def eq28(w):
    return np.array([(W0 - w) / (2 * math.pi), (W0 + w) / (2 * math.pi)])


def crb_std(amplitude, sigma2, n=N, dt=DT):
    """Cramer-Rao standard deviation (Hz) of one complex tone's frequency (test_whirl)."""
    return math.sqrt(6 * sigma2 / (amplitude**2 * n * (n * n - 1))) / (2 * math.pi * dt)


# -- baselines ---------------------------------------------------------------------------

def fft_peak(t, u, v):
    """Interpolated FFT peak on each sign of frequency, (f1, f2) Hz."""
    z = u + 1j * v
    z = z - np.polyval(np.polyfit(t - t[0], z, 1), t - t[0])
    spec = np.abs(np.fft.fft(z * np.hanning(len(z))))
    freqs = np.fft.fftfreq(len(z), t[1] - t[0])
    out = []
    for sign in (1, -1):
        allowed = (sign * freqs > 0) & (np.abs(freqs) <= F_MAX)
        k = int(np.argmax(np.where(allowed, spec, -1.0)))
        a, b, c = np.log(spec[[k - 1, k, (k + 1) % len(z)]] + 1e-300)
        den = a - 2 * b + c
        delta = 0.5 * (a - c) / den if den < 0 else 0.0
        out.append(abs(freqs[k] + delta * (freqs[1] - freqs[0])))
    return tuple(out)


def esprit(t, u, v, differences):
    """ESPRIT (order 2) on block means after ``differences`` differences, (f1, f2) Hz."""
    z = u + 1j * v
    m = len(z) // BLOCK
    y = np.diff(z[len(z) - m * BLOCK:].reshape(m, BLOCK).mean(axis=1), differences)
    rows = np.lib.stride_tricks.sliding_window_view(y, len(y) // 3)
    basis = np.linalg.svd(rows, full_matrices=False)[2][:2].T
    shift = np.linalg.lstsq(basis[:-1], basis[1:], rcond=None)[0]
    f = np.angle(np.linalg.eigvals(shift)) / (2 * math.pi * BLOCK * (t[1] - t[0]))
    pos, neg = f[f > 0], f[f < 0]
    return (pos.max() if len(pos) else math.nan, -neg.min() if len(neg) else math.nan)


METHODS = {
    'ML': estimate_whirl_frequencies,
    'ESPRIT d=1': lambda t, u, v: esprit(t, u, v, 1),
    'ESPRIT d=5': lambda t, u, v: esprit(t, u, v, 5),
    'FFT peak': fft_peak,
}


def fmt(x, spec):
    return 'NaN' if x is None or not math.isfinite(x) else format(x, spec)


# -- measurements ------------------------------------------------------------------------

def constant_w_windows():
    """Noise-free 1 s windows: step start over (0, 0.9 w0], plucked start at 0..0.9 w0."""
    windows = []
    for w in np.linspace(0.05, 0.9, 18) * W0:
        run = simulate(P, ConstantProfile(w), (N - 1) * DT, dt=DT)
        windows.append((w, run.t, run.u, run.v))
    for w in np.array([0.0, 0.3, 0.6, 0.9]) * W0:
        run = simulate(P, ConstantProfile(w), (N - 1) * DT, dt=DT, initial={'u': 1e-3})
        windows.append((w, run.t, run.u, run.v))
    return windows


def max_relative_error(method, windows):
    worst = 0.0
    for w, t, u, v in windows:
        err = np.abs(np.array(method(t, u, v)) / eq28(w) - 1)
        worst = max(worst, np.inf if np.any(np.isnan(err)) else float(err.max()))
    return worst


def noise_trials(method, w, trials=200, seed=2014):
    """RMS error / CRB (worse whirl) and missing estimates at 40 dB, equal whirls + offset."""
    rng = np.random.default_rng(seed)
    amplitude, sigma2 = 1e-3, 1e-10
    f = eq28(w)
    clean = (2.8e-3 + amplitude * np.exp(1j * (2 * math.pi * f[0] * T + 0.4))
             + amplitude * np.exp(-1j * (2 * math.pi * f[1] * T - 1.3)))
    err = []
    for _ in range(trials):
        z = clean + math.sqrt(sigma2 / 2) * (rng.standard_normal(N)
                                             + 1j * rng.standard_normal(N))
        err.append(np.array(method(T, z.real, z.imag)) - f)
    err = np.array(err)
    missing = int(np.isnan(err).any(axis=1).sum())
    rms = np.sqrt(np.nanmean(err**2, axis=0)) if missing < trials else np.full(2, np.nan)
    return float(np.max(rms)) / crb_std(amplitude, sigma2), missing


def eq26_windows(run, ends):
    for end in ends:
        k = int(round(end / DT))
        yield run.t[k - N + 1:k + 1], run.u[k - N + 1:k + 1], run.v[k - N + 1:k + 1]


def tracking(method, run, ends):
    """Max relative error vs Eq. 28 at w(window centre) and w(newest sample); NaN count."""
    centre = newest = 0.0
    missing = 0
    for t, u, v in eq26_windows(run, ends):
        f = np.array(method(t, u, v))
        if np.any(np.isnan(f)):
            missing += 1
            continue
        centre = max(centre, float(np.max(np.abs(f / eq28(eq26(0.5 * (t[0] + t[-1]))[0]) - 1))))
        newest = max(newest, float(np.max(np.abs(f / eq28(eq26(t[-1])[0]) - 1))))
    return centre, newest, missing


def joint_windows(run):
    """Windows ending within 1 s after a joint of Eq. 26 (15, 20, 35 s): accepted error."""
    ends = np.concatenate([np.arange(j + 0.1, j + 0.95, 0.1) for j in (15.0, 20.0, 35.0)])
    worst, missing = 0.0, 0
    for t, u, v in eq26_windows(run, ends):
        f = np.array(estimate_whirl_frequencies(t, u, v))
        ref = eq28(eq26(0.5 * (t[0] + t[-1]))[0])
        err = np.abs(f / ref - 1)
        missing += int(np.isnan(err).sum())
        worst = max(worst, float(np.nanmax(err)) if not np.all(np.isnan(err)) else 0.0)
    return worst, missing, 2 * len(ends)


def timed(fn):
    """fn() and its cost in ms: wall clock, and CPU time of this thread (which leaves
    out the time the thread waits while other processes hold the CPUs)."""
    c0, t0 = time.thread_time(), time.perf_counter()
    out = fn()
    return out, 1e3 * (time.perf_counter() - t0), 1e3 * (time.thread_time() - c0)


def online_cost(run, estimator=None, stride=1):
    """(wall, CPU) ms per WhirlEstimator update, fed every ``stride``-th sample of the run.

    By default a 1 s window at 1 kHz, an estimate every 0.1 s.
    """
    if estimator is None:
        estimator = WhirlEstimator(window=1.0, sample_interval=DT, update_interval=0.1)
    costs = []
    gc.collect()
    for s in zip(run.t[::stride], run.u[::stride], run.v[::stride]):
        est, wall, cpu = timed(lambda s=s: estimator.push(*s))
        if est is not None:
            costs.append((wall, cpu))
    return np.array(costs)


def batch_cost(method, run, repeat=300):
    """(wall, CPU) ms per call on 1 s windows of the Eq. 26 run (cold start)."""
    ends = np.linspace(2.0, 39.0, repeat)
    gc.collect()
    return np.array([timed(lambda w=w: method(*w))[1:] for w in eq26_windows(run, ends)])


def measure() -> list:
    """Run the estimator benchmarks; return their :class:`results.Row` list.

    The value is the ML estimator's; the baselines' values on the same windows are its
    comparisons.
    """
    names = list(METHODS)
    baselines = names[1:]
    rows = []

    def row(name, value, unit, **kw):
        rows.append(Row('estimator', name, float(value), unit, **kw))

    def nan_note(missing, total):
        return f'{missing} of {total} NaN' if missing else ''

    windows = constant_w_windows()
    errs = {n: max_relative_error(METHODS[n], windows) for n in names}
    row('constant w in [0, 0.9 w0], noise-free, 22 windows: max relative error',
        100 * errs['ML'], '%', target=Target('<=', 0.1), fmt='.3g',
        comparisons=[Comparison(n, 100 * errs[n], '' if math.isfinite(errs[n])
                                else 'NaN estimates') for n in baselines])

    trials = 200
    missing_total = {n: 0 for n in names}
    for label, w in (('w = 0', 0.0), ('w = 2 rad/s', 2.0), ('w = 0.5 w0', 0.5 * W0)):
        res = {n: noise_trials(METHODS[n], w, trials) for n in names}
        for n in names:
            missing_total[n] += res[n][1]
        ratio, missing = res['ML']
        row(f'40 dB SNR, {label}, {trials} trials: RMS error / CRB (worse whirl)', ratio,
            'x CRB', target=Target('<=', 3), note=nan_note(missing, trials), fmt='.3g',
            comparisons=[Comparison(n, res[n][0], nan_note(res[n][1], trials)
                                    or ('' if math.isfinite(res[n][0]) else 'no estimate'))
                         for n in baselines])
    for label, w in (('0.7 w0', 0.7 * W0), ('0.8 w0', 0.8 * W0), ('0.9 w0', 0.9 * W0)):
        ratio, missing = noise_trials(METHODS['ML'], w, trials)
        given = (f'RMS / CRB of the estimates given {ratio:.3g}' if math.isfinite(ratio)
                 else 'no estimate given')
        row(f'40 dB SNR, w = {label} (f1 = {eq28(w)[0]:.2f} Hz), {trials} trials: trials '
            'without an estimate (NaN; no target)', missing, f'of {trials}', note=given,
            fmt='.0f')

    run = simulate(P, Eq26Profile(), 40.0, dt=DT)
    spin_up = np.round(np.arange(0.999, 15.0005, 0.1), 3)
    res = {n: tracking(METHODS[n], run, spin_up) for n in names}
    for n in names:
        missing_total[n] += res[n][2]
    for i, what in ((0, 'centre'), (1, 'newest sample')):
        row(f'Eq. 26 spin-up, {len(spin_up)} windows to 15 s: max error vs Eq. 28 at '
            f'w(window {what})', 100 * res['ML'][i], '%', target=Target('<=', 2),
            note=nan_note(res['ML'][2], len(spin_up)), fmt='.3g',
            comparisons=[Comparison(n, 100 * res[n][i], nan_note(res[n][2], len(spin_up)))
                         for n in baselines])
    row(f'estimates missing (NaN): the 3 x {trials} trials above with a target and the '
        f'{len(spin_up)} spin-up windows', missing_total['ML'], 'NaN',
        target=Target('<=', 0, text='none'), fmt='.0f',
        comparisons=[Comparison(n, missing_total[n]) for n in baselines])
    worst, missing, total = joint_windows(run)
    row('Eq. 26, windows straddling a joint (15, 20, 35 s): max error of the estimates '
        'given (no target: the model is stationary)', 100 * worst, '%',
        note=f'{missing} of {total} NaN', fmt='.3g')

    online = online_cost(run)
    node = online_cost(run, stream_estimator(1.0, NODE_RATE, 10.0),
                       int(round(1 / (NODE_RATE * DT))))
    costs = {n: batch_cost(METHODS[n], run) for n in names}
    for i, clock in ((0, 'wall clock'), (1, 'CPU time')):
        row(f'cost per WhirlEstimator update, 1 s window at 1 kHz, {len(online)} updates: '
            f'p99, {clock}', np.percentile(online[:, i], 99), 'ms', target=Target('<=', 2),
            note=f'median {np.median(online[:, i]):.2f} ms', fmt='.2f')
        row(f'cost per WhirlEstimator update, the node\'s: the Eq. 26 run published at '
            f'{NODE_RATE:g} Hz, stream_estimator(1.0, {NODE_RATE:g}, 10.0) (1 s window, an '
            f'estimate every 0.1 s), {len(node)} updates: p99, {clock}',
            np.percentile(node[:, i], 99), 'ms', target=Target('<=', NODE_P99),
            note=f'median {np.median(node[:, i]):.2f} ms', fmt='.2f')
        row(f'cost per batch call (cold start), 1 s window, {len(costs["ML"])} windows: '
            f'median, {clock}', np.median(costs['ML'][:, i]), 'ms', fmt='.2f',
            note=f'p99 {np.percentile(costs["ML"][:, i], 99):.2f} ms',
            comparisons=[Comparison(n, float(np.median(costs[n][:, i])),
                                    f'p99 {np.percentile(costs[n][:, i], 99):.2f} ms')
                         for n in baselines])
    return rows


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument('--json', type=Path, help='write the rows as JSON here')
    args = ap.parse_args()
    load = os.getloadavg()
    rows = measure()
    return results.report(rows, args.json, title='whirl estimator benchmark',
                          stamp=results.host(load),
                          preface='Value: the ML estimator (rotrod_core.estimation.whirl); '
                                  'compared: the baselines on the same windows.')


if __name__ == '__main__':
    sys.exit(main())
