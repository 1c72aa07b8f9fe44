"""Whirl-frequency estimation against Eq. 28, the Cramer-Rao bound and the Eq. 26 run.

Reference values come from test/reference.py (docs/model.md's closed forms, written apart
from rotrod_core): Eq. 28 gives f1 = (w0 - w) / 2pi for the forward whirl, at positive
frequency of z = u + i v, and f2 = (w0 + w) / 2pi for the backward whirl, at negative
frequency.

Cramer-Rao bound for the frequency of one complex tone z_n = A exp(i(w n dt + phi))
+ e_n in circular complex white noise with E|e_n|^2 = sigma^2 (total over real and
imaginary parts), A, phi, w unknown: the Fisher information of (w, phi) is
(2 A^2 / sigma^2) [[dt^2 sum n^2, dt sum n], [dt sum n, N]], whose inverse gives

    var(w_hat) >= 6 sigma^2 / (A^2 dt^2 N (N^2 - 1))   (rad/s)^2,

so std(f_hat) >= sqrt(6 sigma^2 / (A^2 N (N^2 - 1))) / (2 pi dt) Hz. SNR = A^2 / sigma^2.
"""

import math
import re
from pathlib import Path

import numpy as np
import pytest
from hypothesis import event, given
from hypothesis import strategies as st
from properties import (  # the shared settings and strategies of the property tests
    HUGE,
    NON_FINITE,
    TINY,
    WRONG_TYPES,
    anything,
    finite,
    is_number,
    props,
)
from reference import R0, W0, eq26, step_start

from rotrod_core import (
    ConstantProfile,
    Eq26Profile,
    RodParams,
    WhirlEstimator,
    WhirlSettings,
    estimate_whirl,
    estimate_whirl_frequencies,
    modal_analysis,
    simulate,
)
from rotrod_core.estimation import whirl as whirl_module
from rotrod_core.estimation.whirl import fit_whirls, stream_estimator

P = RodParams()
DT = 1e-3
N = 1000
T = np.arange(N) * DT          # a 1 s window at 1 kHz


def eq28(w):
    return (W0 - w) / (2 * math.pi), (W0 + w) / (2 * math.pi)


def crb_std(amplitude, sigma2, n=N, dt=DT):
    """Cramer-Rao standard deviation (Hz) of a complex tone's frequency (module doc)."""
    return math.sqrt(6 * sigma2 / (amplitude**2 * n * (n * n - 1))) / (2 * math.pi * dt)


def relative_errors(f, w):
    f1, f2 = eq28(w)
    return abs(f[0] / f1 - 1), abs(f[1] / f2 - 1)


def complex_noise(rng, sigma2, n=N):
    return math.sqrt(sigma2 / 2) * (rng.standard_normal(n) + 1j * rng.standard_normal(n))


# -- noise-free: Eq. 28 to 0.1 % across [0, 0.9 w0] -------------------------------------

@pytest.mark.parametrize('fraction', [0.05, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9])
def test_step_start_at_constant_w_gives_eq28(fraction):
    """From rest at constant w (docs/model.md step start): both whirls and the static offset."""
    w = fraction * W0
    run = simulate(P, ConstantProfile(w), (N - 1) * DT, dt=DT)
    assert len(run.t) == N
    est = estimate_whirl(run.t, run.u, run.v)
    assert est.reason == ''
    assert max(relative_errors((est.f1, est.f2), w)) < 1e-3
    # the fitted offset is the static deflection, the amplitudes those of Eq. 29
    u_s = w * w * R0 / (W0 * W0 - w * w)
    assert est.offset.real == pytest.approx(u_s, rel=1e-6)
    scale = w * w * R0 / (2 * W0)
    assert est.forward.amplitude == pytest.approx(scale / (W0 - w), rel=1e-6)
    assert est.backward.amplitude == pytest.approx(scale / (W0 + w), rel=1e-6)


@pytest.mark.parametrize('fraction', [0.0, 0.3, 0.6, 0.9])
def test_plucked_rod_at_constant_w_gives_eq28(fraction):
    """An initial deflection excites both whirls, also at rest (w = 0: f1 = f2 = f0)."""
    w = fraction * W0
    run = simulate(P, ConstantProfile(w), (N - 1) * DT, dt=DT, initial={'u': 1e-3})
    f = estimate_whirl_frequencies(run.t, run.u, run.v)
    assert max(relative_errors(f, w)) < 1e-3


def test_dropped_and_jittered_samples_are_handled_exactly():
    """Irregular times: 30 % of the samples dropped at random, the rest jittered."""
    rng = np.random.default_rng(7)
    w = 2.0
    keep = np.sort(rng.choice(N, int(0.7 * N), replace=False))
    t = T[keep] + rng.uniform(-0.3, 0.3, len(keep)) * DT
    z = step_start(t, w)
    est = estimate_whirl(t, z.real, z.imag)
    assert est.samples == len(t) and est.reason == ''
    assert max(relative_errors((est.f1, est.f2), w)) < 1e-9


def test_a_drifting_offset_is_modelled():
    """Whirls on top of an offset that drifts as a cubic in time (as in a spin-up)."""
    w = 2.0
    z = step_start(T, w) + 2e-3 * (1 + 0.5 * T - 0.8 * T**2 + 0.6 * T**3)
    f = estimate_whirl_frequencies(T, z.real, z.imag)
    assert max(relative_errors(f, w)) < 1e-9
    # the same window with the drift modelled as a constant is badly off
    f0 = estimate_whirl_frequencies(T, z.real, z.imag, WhirlSettings(drift_degree=0))
    assert not max(relative_errors(f0, w)) < 1e-3


def test_damped_whirls_give_the_modal_frequencies_and_decay_rates():
    params = RodParams(damping_ratio=0.02)
    run = simulate(params, ConstantProfile(2.0), (N - 1) * DT, dt=DT)
    est = estimate_whirl(run.t, run.u, run.v)
    modes = {m.whirl: m for m in modal_analysis(params, 2.0).modes}
    for whirl, mode in ((est.forward, modes['forward']), (est.backward, modes['backward'])):
        assert whirl.frequency == pytest.approx(mode.frequency, rel=1e-9)
        assert whirl.decay_rate == pytest.approx(-mode.growth_rate, rel=1e-6)


def test_the_sign_of_frequency_separates_the_whirls():
    tone = 1e-3 * np.exp(2j * math.pi * 1.7 * T) + 5e-3
    forward = estimate_whirl(T, tone.real, tone.imag)
    assert forward.f1 == pytest.approx(1.7, rel=1e-12) and math.isnan(forward.f2)
    assert 'backward' in forward.reason
    backward = estimate_whirl(T, tone.real, -tone.imag)       # conjugate: negative f
    assert backward.f2 == pytest.approx(1.7, rel=1e-12) and math.isnan(backward.f1)
    assert 'forward' in backward.reason


def test_a_single_chirping_whirl_is_estimated_at_the_window_centre():
    """One whirl whose frequency falls at 0.04 Hz/s (an Eq. 26 spin-up's largest rate),
    nothing at negative frequency: the estimate is the frequency at the centre."""
    rate, f_centre = -0.04, 1.7
    tau = T - T.mean()
    z = 2.8e-3 + 5e-8 * np.exp(2j * math.pi * (f_centre * tau + 0.5 * rate * tau**2))
    est = estimate_whirl(T, z.real, z.imag)
    assert est.f1 == pytest.approx(f_centre, rel=1e-3) and est.time == pytest.approx(T.mean())
    assert math.isnan(est.f2)


# -- noise: within 3x the Cramer-Rao bound ----------------------------------------------

@pytest.mark.parametrize('w', [0.0, 2.0, 0.5 * W0])
def test_40_db_noise_rms_error_within_three_times_the_cramer_rao_bound(w):
    """200 trials; each whirl at 40 dB SNR (A^2 / sigma^2 = 1e4) beside a static offset."""
    rng = np.random.default_rng(2014)
    f1, f2 = eq28(w)
    amplitude, sigma2 = 1e-3, 1e-10
    clean = (2.8e-3 + amplitude * np.exp(1j * (2 * math.pi * f1 * T + 0.4))
             + amplitude * np.exp(-1j * (2 * math.pi * f2 * T - 1.3)))
    err, std, quality = [], [], []
    for _ in range(200):
        z = clean + complex_noise(rng, sigma2)
        est = estimate_whirl(T, z.real, z.imag)
        err.append((est.f1 - f1, est.f2 - f2))
        std.append((est.forward.frequency_std, est.backward.frequency_std))
        quality.append(est.quality)
    err = np.array(err)
    assert not np.any(np.isnan(err)), 'a whirl went undetected at 40 dB'
    rms = np.sqrt(np.mean(err**2, axis=0))
    bound = crb_std(amplitude, sigma2)
    assert np.all(rms <= 3 * bound), (rms / bound)
    # the reported standard deviation is the bound with nuisance parameters: >= CRB
    assert np.all(np.mean(std, axis=0) >= 0.9 * bound)
    assert np.all(np.mean(std, axis=0) <= 2.0 * bound)
    assert np.median(quality) == pytest.approx(40.0, abs=0.5)


def test_40_db_noise_on_simulated_motion():
    """Step start at 2 rad/s plus white noise at 40 dB of the weaker (backward) whirl."""
    rng = np.random.default_rng(28)
    w = 2.0
    run = simulate(P, ConstantProfile(w), (N - 1) * DT, dt=DT)
    clean = run.u + 1j * run.v
    scale = w * w * R0 / (2 * W0)
    a1, a2 = scale / (W0 - w), scale / (W0 + w)
    sigma2 = a2**2 / 1e4
    f = np.array([estimate_whirl_frequencies(T, z.real, z.imag)
                  for z in (clean + complex_noise(rng, sigma2) for _ in range(200))])
    rms = np.sqrt(np.mean((f - eq28(w)) ** 2, axis=0))
    assert rms[0] <= 3 * crb_std(a1, sigma2)
    assert rms[1] <= 3 * crb_std(a2, sigma2)


# -- Eq. 26 spin-up: tracking within 2 % -------------------------------------------------

def test_online_estimator_tracks_the_eq26_spin_up():
    """Every estimate from the first filled window to the end of the spin-up (15 s).

    An estimate describes its window's centre (``time``): a frequency drifting
    linearly over the window is estimated at its centre value. Held against Eq. 28
    at w(centre) and, stricter, at w of the newest sample (half a window later).
    """
    run = simulate(P, Eq26Profile(), 15.0, dt=DT)
    estimator = WhirlEstimator(window=1.0, sample_interval=DT, update_interval=0.1)
    estimates = [e for e in (estimator.push(*s) for s in zip(run.t, run.u, run.v)) if e]
    assert len(estimates) == 141
    assert estimates[0].time == pytest.approx(0.4995)
    for est in estimates:
        centre = relative_errors((est.f1, est.f2), eq26(est.time)[0])
        newest = relative_errors((est.f1, est.f2), eq26(est.time + est.window / 2)[0])
        assert max(centre) <= 0.02, (est.time, centre, est.reason)
        assert max(newest) <= 0.02, (est.time, newest, est.reason)


def test_online_estimate_equals_the_batch_estimate_of_its_window():
    run = simulate(P, Eq26Profile(), 8.0, dt=DT)
    estimator = WhirlEstimator(window=1.0, sample_interval=DT, update_interval=0.5)
    for s in zip(run.t, run.u, run.v):
        estimator.push(*s)
    online = estimator.update()
    batch = estimate_whirl(run.t[-N:], run.u[-N:], run.v[-N:])
    assert online.samples == N and online.time == batch.time
    assert online.f1 == pytest.approx(batch.f1, rel=1e-7)   # fits converged to 1e-8 rad
    assert online.f2 == pytest.approx(batch.f2, rel=1e-7)


def test_online_estimates_fit_each_half_window_once_and_equal_the_batch(monkeypatch):
    """Sliding by 0.1 s over a 1 s window, each window's first half is the second half of
    the window 0.5 s earlier: the online estimator fits it once. Its estimates, accepted
    and rejected alike, are still the batch estimates of their windows (two whirls whose
    frequencies jump by 3 % at t = 3 s: the windows across the jump are not stationary,
    and the split check rejects them)."""
    half_fits = []
    fit_half = whirl_module._half_whirls
    monkeypatch.setattr(whirl_module, '_half_whirls',
                        lambda t, *a: half_fits.append((t[0], len(t))) or fit_half(t, *a))
    t = np.arange(0.0, 6.0, DT)
    jump = np.where(t < 3.0, 1.0, 1.03)
    phase = 2 * np.pi * np.cumsum(jump) * DT
    z = (2e-4 + 1e-3 * np.exp(1j * 1.5 * phase) + 5e-4 * np.exp(-1j * 2.2 * phase)
         + 1e-6 * np.array([1, 1j]) @ np.random.default_rng(7).standard_normal((2, len(t))))
    estimator = WhirlEstimator(window=1.0, sample_interval=DT, update_interval=0.1)
    online = [(i, est) for i, s in enumerate(zip(t, z.real, z.imag))
              if (est := estimator.push(*s)) is not None]
    online_fits = list(half_fits)
    half_fits.clear()
    rejected = 0
    for i, est in online:
        window = slice(i + 1 - N, i + 1)
        batch = estimate_whirl(t[window], z.real[window], z.imag[window])
        assert batch.time == est.time
        for f_online, f_batch in ((est.f1, batch.f1), (est.f2, batch.f2)):
            assert math.isnan(f_online) == math.isnan(f_batch), (est.time, est.reason,
                                                                 batch.reason)
            if math.isnan(f_online):
                rejected += 1
            else:
                assert f_online == pytest.approx(f_batch, rel=1e-7)
    assert rejected > 0 and len(online) > 40
    # the batch fits both halves of every window it checks; online, a half that an
    # earlier window had is not fitted again: each half once, about half as many fits
    assert len(online_fits) == len(set(online_fits)) == len(set(half_fits))
    assert len(online_fits) < 0.7 * len(half_fits)


LIVE_WINDOWS = Path(__file__).parent / 'data' / 'live_windows_off_eq28.csv'


def test_live_windows_with_a_new_vibration_inside_are_not_stationary(monkeypatch):
    """37 one-second windows of motion the simulator published in ``rotrod demo`` runs,
    in which the estimate without the stationarity check and without the misfit rule
    for a pair was over 1 % off Eq. 28 (one 2.24 %; issue 6 asks 2 %): small
    corrections of the streamed w start whirls of 1e-8 m beside the spin-up's 5e-8 m
    ones. The two rules reject most of those whirls; every estimate left is within
    1.5 %."""
    data = np.loadtxt(LIVE_WINDOWS, delimiter=',', comments='#', skiprows=7)
    windows = [data[data[:, 0] == k, 1:].T for k in np.unique(data[:, 0])]

    def estimates(settings=None):
        out = []
        for t, u, v, w in windows:
            est = estimate_whirl(t, u, v, settings)
            out.append((est, relative_errors((est.f1, est.f2), w[0])))
        return out

    with monkeypatch.context() as m:
        m.setattr(whirl_module, '_MISFIT_INFLATION', math.inf)
        unchecked = estimates(WhirlSettings(max_split_change=math.inf))
    worst = [max(e for e in errors if not math.isnan(e)) for _, errors in unchecked]
    assert len(worst) == 37 and min(worst) > 0.01 and max(worst) > 0.02
    checked = estimates()
    reasons = ' '.join(est.reason for est, _ in checked)
    assert reasons.count('not stationary') >= 40 and reasons.count('misfit of the model') >= 5
    given = [e for _, errors in checked for e in errors if not math.isnan(e)]
    assert given and max(given) <= 0.015


def test_a_steady_window_passes_the_stationarity_check_unchanged():
    """Two steady whirls at 40 dB, one slow (0.97 Hz: half a cycle per half window,
    which the drift takes there, so a half does not judge it): the same estimate with
    and without the check."""
    rng = np.random.default_rng(7)
    for w in (0.0, 2.0, 0.5 * W0):
        f1, f2 = eq28(w)
        z = (2.8e-3 + 1e-3 * np.exp(2j * math.pi * f1 * T) + 1e-3 * np.exp(-2j * math.pi * f2 * T)
             + complex_noise(rng, 1e-10))
        checked = estimate_whirl(T, z.real, z.imag)
        unchecked = estimate_whirl(T, z.real, z.imag, WhirlSettings(max_split_change=math.inf))
        assert checked == unchecked and not math.isnan(checked.f1 + checked.f2), w


# -- no estimate -------------------------------------------------------------------------

def test_no_motion_and_a_pure_static_offset_give_no_estimate():
    at_rest = simulate(P, ConstantProfile(0.0), (N - 1) * DT, dt=DT)     # z = 0
    w = 2.0
    u_s = w * w * R0 / (W0 * W0 - w * w)
    static = simulate(P, ConstantProfile(w), (N - 1) * DT, dt=DT, initial={'u': u_s})
    for run in (at_rest, static):
        est = estimate_whirl(run.t, run.u, run.v)
        assert math.isnan(est.f1) and math.isnan(est.f2)
        assert est.quality == -math.inf


def test_a_damped_out_vibration_gives_no_estimate():
    """Rotating damping zeta = 0.1: after 30 s the whirls are gone (e^-36)."""
    run = simulate(RodParams(damping_ratio=0.1), ConstantProfile(2.0), 30.0, dt=DT)
    est = estimate_whirl(run.t[-N:], run.u[-N:], run.v[-N:])
    assert math.isnan(est.f1) and math.isnan(est.f2), est
    assert 'no oscillation' in est.reason


def test_a_whirl_decaying_fast_within_the_window_gives_no_estimate():
    z = 1e-3 * np.exp((-3.0 + 2j * math.pi * 1.7) * T) + 1e-3 * np.exp(-2j * math.pi * 2.2 * T)
    est = estimate_whirl(T, z.real, z.imag)
    assert math.isnan(est.f1) and 'decays' in est.reason
    assert est.f2 == pytest.approx(2.2, rel=1e-9)


def test_pure_noise_gives_no_estimate():
    rng = np.random.default_rng(5)
    for _ in range(50):
        z = 2.8e-3 + complex_noise(rng, 1e-10)
        f = estimate_whirl_frequencies(T, z.real, z.imag)
        assert np.all(np.isnan(f)), f


def test_whirls_buried_in_noise_give_no_estimate():
    """-30 dB per sample (0 dB over the window): too noisy for a usable frequency."""
    rng = np.random.default_rng(6)
    z = 1e-6 * (np.exp(2j * math.pi * 1.6 * T) + np.exp(-2j * math.pi * 2.2 * T))
    for _ in range(20):
        noisy = z + complex_noise(rng, 1e-9)
        f = estimate_whirl_frequencies(T, noisy.real, noisy.imag)
        assert np.all(np.isnan(f)), f


def test_a_too_short_window_gives_no_estimate():
    z = step_start(T[:100], 2.0)
    est = estimate_whirl(T[:100], z.real, z.imag)
    assert math.isnan(est.f1) and math.isnan(est.f2) and 'too short' in est.reason
    assert estimate_whirl(T[:1], z.real[:1], z.imag[:1]).reason.startswith('too few')


def test_a_long_gap_gives_no_estimate_a_short_one_an_exact_one():
    z = step_start(T, 2.0)
    short = (T < 0.40) | (T >= 0.45)
    long = (T < 0.40) | (T >= 0.55)
    assert max(relative_errors(estimate_whirl_frequencies(T[short], z.real[short],
                                                          z.imag[short]), 2.0)) < 1e-9
    est = estimate_whirl(T[long], z.real[long], z.imag[long])
    assert math.isnan(est.f1) and math.isnan(est.f2) and 'gap' in est.reason


def test_a_whirl_too_slow_for_the_window_gives_no_estimate():
    """At 0.95 w0 the forward whirl makes 0.097 cycles in 1 s: below min_cycles (0.1)."""
    w = 0.95 * W0
    run = simulate(P, ConstantProfile(w), (N - 1) * DT, dt=DT)
    est = estimate_whirl(run.t, run.u, run.v)
    assert math.isnan(est.f1) and 'outside the band' in est.reason
    assert est.f2 == pytest.approx(eq28(w)[1], rel=1e-6)


def test_unusable_input_is_refused():
    z = step_start(T, 2.0)
    u, v = z.real.copy(), z.imag.copy()
    u[10] = np.nan
    with pytest.raises(ValueError, match='finite'):
        estimate_whirl(T, u, v)
    with pytest.raises(ValueError, match='equal lengths'):
        estimate_whirl(T[:-1], z.real, z.imag)
    t = T.copy()
    t[500] = t[499]
    with pytest.raises(ValueError, match='increase strictly'):
        estimate_whirl(t, z.real, z.imag)
    with pytest.raises(ValueError, match='drift_degree'):
        WhirlSettings(drift_degree=-1)
    with pytest.raises(ValueError, match='max_frequency'):
        WhirlSettings(max_frequency=0.0)
    for bad in (0.0, -0.01, math.nan, True, '0.01', None):
        with pytest.raises(ValueError, match='max_split_change'):
            WhirlSettings(max_split_change=bad)


def test_online_estimator_before_the_window_fills_and_on_bad_samples():
    estimator = WhirlEstimator(window=1.0, sample_interval=DT, update_interval=0.1)
    z = step_start(T, 2.0)
    for k in range(N - 1):
        assert estimator.push(T[k], z.real[k], z.imag[k]) is None
    assert not estimator.filled
    assert math.isnan(estimator.estimate.f1) and 'not filled' in estimator.estimate.reason
    assert 'not filled' in estimator.update().reason
    with pytest.raises(ValueError, match='finite'):
        estimator.push(T[-1], math.nan, 0.0)
    with pytest.raises(ValueError, match='increase strictly'):
        estimator.push(T[-2], 0.0, 0.0)
    est = estimator.push(T[-1], z.real[-1], z.imag[-1])     # the refused ones left no trace
    assert estimator.filled and est is estimator.estimate and est.samples == N
    assert max(relative_errors((est.f1, est.f2), 2.0)) < 1e-9
    estimator.reset()
    assert not estimator.filled and math.isnan(estimator.estimate.f2)


def test_online_estimator_outgrows_a_wrong_sample_interval():
    """Samples ten times denser than announced: the ring grows, the estimate is exact."""
    estimator = WhirlEstimator(window=1.0, sample_interval=10 * DT, update_interval=0.5)
    t = np.arange(3 * N) * DT
    z = step_start(t, 2.0)
    for s in zip(t, z.real, z.imag):
        estimator.push(*s)
    est = estimator.update()
    assert est.samples >= N - 10
    assert max(relative_errors((est.f1, est.f2), 2.0)) < 1e-9


def test_online_estimator_with_dropped_messages():
    """A fifth of the messages lost at random: the estimates stay exact."""
    rng = np.random.default_rng(11)
    t = np.arange(3 * N) * DT
    t = t[rng.random(len(t)) > 0.2]
    z = step_start(t, 2.0)
    estimator = WhirlEstimator(window=1.0, sample_interval=DT, update_interval=0.25)
    estimates = [e for e in (estimator.push(*s) for s in zip(t, z.real, z.imag)) if e]
    assert len(estimates) >= 8
    for est in estimates:
        assert max(relative_errors((est.f1, est.f2), 2.0)) < 1e-9, est.reason


def test_fit_recovers_a_centre_and_two_whirls():
    t = np.arange(0.0, 20.0, 0.01)
    c, a, b = 1e-3 + 2e-4j, 3e-6 * np.exp(0.3j), 1e-6 * np.exp(-1.1j)
    wf, wb = 7.3, 11.9
    z = c + a * np.exp(1j * wf * t) + b * np.exp(-1j * wb * t)
    fit = fit_whirls(t, z.real, z.imag)
    assert fit.forward_omega == pytest.approx(wf, rel=1e-10)
    assert fit.backward_omega == pytest.approx(wb, rel=1e-10)
    assert abs(fit.centre - c) < 1e-15 and abs(fit.forward - a) < 1e-15
    assert abs(fit.backward - b) < 1e-15 and fit.relative_residual < 1e-9
    assert fit.precession_rate == pytest.approx((wf - wb) / 2, rel=1e-9)
    assert fit.forward_frequency == pytest.approx(wf / (2 * math.pi), rel=1e-10)


def test_fit_semi_axes_are_the_ellipse_of_the_samples():
    t = np.arange(0.0, 10.0, 1e-3)
    a, b, w = 2e-6 * np.exp(0.4j), 0.5e-6 * np.exp(2.0j), 5.0
    z = a * np.exp(1j * w * t) + b * np.exp(-1j * w * t)
    fit = fit_whirls(t, z.real, z.imag)
    r = np.abs(z - fit.centre)
    assert fit.semi_major == pytest.approx(r.max(), rel=1e-6)
    assert fit.semi_minor == pytest.approx(r.min(), rel=1e-6)
    assert fit.semi_minor == pytest.approx(1.5e-6, rel=1e-9)
    assert abs(fit.precession_rate) < 1e-9


@st.composite
def whirl_windows(draw, sane=None):
    """(t, u, v): two whirls plus noise and an offset, at an extreme scale; half of
    them at a usual sampling (1 kHz, 0.5 to 1 s), the others at extreme sampling."""
    if sane is None:
        sane = draw(st.booleans())
    if sane:
        n = draw(st.sampled_from([500, 1000]))
        dt = 1e-3
        t0 = draw(st.sampled_from([0.0, -5.0, 1.7e9]))
    else:
        n = draw(st.sampled_from([0, 1, 2, 5, 40, 300, 1000]))
        dt = draw(st.sampled_from([1e-3, 1e-4, 0.02, TINY, 1e-310, 1e-300, 1e3, 1e305]))
        t0 = draw(st.sampled_from([0.0, -5.0, 1.7e9, 1e15, 1e300, -1e300, -1e308, 1e308]))
    t = t0 + dt * np.arange(n)
    if draw(st.booleans()):         # dropped samples and jitter
        rng = np.random.default_rng(draw(st.integers(0, 9)))
        keep = rng.random(n) > 0.2
        t = (t + rng.uniform(0, 0.3 * dt, n))[keep]
    n = len(t)
    scale = draw(st.sampled_from([1.0, 1e-3, TINY, 1e-300, 1e-150, 1e150, 1e300, HUGE]))
    f1, f2 = draw(st.floats(0.0, 30.0)), draw(st.floats(0.0, 30.0))
    offset = draw(st.sampled_from([0.0, 1e-3, 1.0]))
    noise = draw(st.sampled_from([0.0, 1e-6, 1e-4, 10.0]))
    tau = t - (t[0] if n else 0.0)
    rng = np.random.default_rng(draw(st.integers(0, 9)))
    with np.errstate(all='ignore'):     # phases of windows at 1e300 s; u beyond the range
        z = (offset + 1e-3 * np.exp(2j * np.pi * f1 * tau)
             + 2e-3 * np.exp(-2j * np.pi * f2 * tau)
             + noise * (rng.standard_normal(n) + 1j * rng.standard_normal(n)))
        u, v = scale * z.real, scale * z.imag
    return t, u, v


def check_estimate(est, settings=None):
    settings = settings or WhirlSettings()
    for f in (est.f1, est.f2):
        assert not math.isinf(f)
        assert math.isnan(f) or 0 <= f <= settings.max_frequency
    if math.isnan(est.f1) or math.isnan(est.f2):
        assert est.reason, est


# windows of ~1e307 s overflow inside the fit: the estimate is then NaN with a reason
@pytest.mark.filterwarnings('ignore:overflow encountered in matmul:RuntimeWarning')
@pytest.mark.filterwarnings('ignore:invalid value encountered in matmul:RuntimeWarning')
@props(120)
@given(whirl_windows())
def test_the_whirl_estimate_is_in_band_or_nan_with_a_reason(window):
    """Finite input: (f1, f2) finite in [0, max_frequency] or NaN with a reason, never
    +-inf, and no error but ValueError (non-finite values, times not increasing)."""
    t, u, v = window
    try:
        est = estimate_whirl(t, u, v)
    except ValueError as exc:
        event('ValueError')
        assert re.search(r'finite|increase', str(exc)), str(exc)
        return
    event('no estimate' if math.isnan(est.f1) and math.isnan(est.f2) else 'estimate')
    check_estimate(est)
    for x in (est.forward.amplitude, est.noise_rms, est.offset.real):
        assert not math.isinf(x)


@props(80)
@given(whirl_windows(sane=True), st.sampled_from([2.0**-1070, 2.0**-500, 0.5, 2.0**500,
                                                  2.0**1000]))
def test_the_whirl_estimate_does_not_depend_on_the_unit(window, factor):
    """u, v scaled by a power of two (exact): the same frequencies, bit for bit, and
    amplitudes scaled by it (before: NaN below ~1e-150 m, overflow above ~1e150 m)."""
    t, u, v = window
    try:
        ref = estimate_whirl(t, u, v)
    except ValueError:      # the window's values overflowed (scale 1.8e308)
        return
    with np.errstate(over='ignore'):
        su, sv = u * factor, v * factor
    if not (finite(su) and finite(sv)) or np.max(np.abs(np.concatenate((u, v)))) * factor \
            < 2.0**-1000:   # beyond the float range, or into subnormals (not exact)
        return
    est = estimate_whirl(t, su, sv)
    event('estimate' if math.isfinite(ref.f1) or math.isfinite(ref.f2) else 'no estimate')
    assert repr((est.f1, est.f2)) == repr((ref.f1, ref.f2))
    for a, b in ((est.forward, ref.forward), (est.backward, ref.backward)):
        assert repr(a.amplitude) == repr(b.amplitude * factor) or (
            a.amplitude == pytest.approx(b.amplitude * factor, rel=1e-12))


def test_regression_whirl_scale_and_sampling_extremes():
    t = np.arange(1000) * 1e-3
    for scale in (1e-300, 1.0, 1e300):      # the estimate does not depend on the unit
        f1, f2 = estimate_whirl_frequencies(t, scale * np.cos(20 * t), scale * np.sin(20 * t))
        assert f1 == pytest.approx(20 / (2 * np.pi), rel=1e-9) and math.isnan(f2)
    # subnormal sample interval: the block size overflowed int() (OverflowError)
    est = estimate_whirl(np.arange(40) * 1e-310, np.ones(40), np.zeros(40))
    assert math.isnan(est.f1) and 'too short' in est.reason


@props(100)
@given(st.sampled_from(['t', 'u', 'v']), st.one_of(NON_FINITE, WRONG_TYPES),
       st.sampled_from(['length', 'value', 'order']))
def test_bad_whirl_input_is_a_value_error(name, bad, kind):
    t = np.arange(100) * 1e-3
    arrays = {'t': t, 'u': np.cos(t), 'v': np.sin(t)}
    if kind == 'length':
        arrays[name] = arrays[name][:-1]
    elif kind == 'order':
        arrays['t'] = t[::-1].copy()
    else:
        if isinstance(bad, bool):
            return      # numpy reads a bool in an array as 0 or 1: a number
        arrays[name] = arrays[name].astype(object)
        arrays[name][7] = bad
    with pytest.raises(ValueError):
        estimate_whirl_frequencies(arrays['t'], arrays['u'], arrays['v'])


@props(100)
@given(st.lists(st.tuples(anything(st.floats(0.0, 0.01)), anything(st.floats(-1e-3, 1e-3)),
                          anything(st.floats(-1e-3, 1e-3))), min_size=1, max_size=30))
def test_whirl_estimator_push_refuses_bad_samples_and_keeps_its_state(samples):
    """push(t, u, v) with a value that is not a finite number, or a time not after the
    last: ValueError, and the estimator is as if that sample had never come (a twin fed
    only the accepted samples gives the same estimates)."""
    def make():
        return WhirlEstimator(window=0.05, sample_interval=1e-3, update_interval=0.01,
                              settings=WhirlSettings(max_frequency=50.0, drift_degree=0))
    est, twin = make(), make()
    clock = 0.0
    for dt, u, v in samples:
        t = clock + dt if is_number(dt) else dt
        try:
            result = est.push(t, u, v)
        except ValueError as exc:
            assert re.search(r'\b[tuv]\b|times', str(exc)), str(exc)
            assert not (is_number(t) and is_number(u) and is_number(v) and t > clock)
            continue
        assert repr(result) == repr(twin.push(t, u, v))
        assert repr(est.estimate) == repr(twin.estimate)
        clock = t
        if result is not None:
            check_estimate(result, est.settings)


@props(150)
@given(st.dictionaries(st.sampled_from(['drift_degree', 'max_frequency', 'min_cycles',
                                        'detection_db', 'max_relative_std', 'max_decay',
                                        'max_gap', 'max_split_change']),
                       anything(st.floats(0.05, 50.0)), max_size=3),
       anything(st.floats(0.05, 5.0)), anything(st.floats(1e-4, 0.01)),
       anything(st.floats(0.0, 0.5)))
def test_whirl_settings_and_estimator_are_refused_clearly_or_usable(kwargs, window,
                                                                    sample_interval, update):
    """A ValueError naming the field (before: OverflowError for max_frequency = 5e-324,
    numpy's 'Maximum allowed dimension exceeded' for a 1e300 s window, 1.2 GB for a
    1e4 s one), or an estimator that takes samples."""
    try:
        settings = WhirlSettings(**kwargs)
        est = WhirlEstimator(window, sample_interval, update, settings)
    except ValueError as exc:
        assert re.search(r'WhirlSettings\.|WhirlEstimator\.', str(exc)), str(exc)
        return
    for k in range(5):
        result = est.push(k * est.sample_interval, 1e-3, 0.0)
        assert result is None or not math.isinf(result.f1)


def test_stream_estimator_estimates_at_its_update_rate_over_its_window():
    """At 100 Hz, a 1 s window, 10 estimates a second: the first once the window holds a
    second of samples, then every tenth sample; Eq. 28's f1 at constant w; 0 s: None."""
    assert stream_estimator(0.0, 100.0, 10.0) is None
    est = stream_estimator(1.0, 100.0, 10.0)
    w = 1.0
    t = np.arange(300) / 100.0
    z = step_start(t, w)
    due = [k for k in range(300) if est.push(t[k], z[k].real, z[k].imag) is not None]
    assert due[0] in (99, 100) and np.all(np.diff(due) == 10)
    assert est.estimate.f1 == pytest.approx((W0 - w) / (2 * math.pi), rel=1e-6)


def test_staggered_estimators_update_k_samples_later_with_the_same_estimates():
    """The k-th rod of a world (stagger k) estimates k samples after the first, modulo
    the ten samples per estimate, every tenth sample after; at constant w, Eq. 28's f1
    all the same. A phase of a whole interval or more is refused."""
    t = np.arange(400) / 100.0
    z = step_start(t, 1.0)
    first = None
    for k in (0, 1, 3, 9, 10, 13):
        est = stream_estimator(1.0, 100.0, 10.0, stagger=k)
        due = [j for j in range(400) if est.push(t[j], z[j].real, z[j].imag) is not None]
        first = due[0] if k == 0 else first
        assert due[0] == first + k % 10 and np.all(np.diff(due) == 10)
        assert est.estimate.f1 == pytest.approx((W0 - 1.0) / (2 * math.pi), rel=1e-6)
    with pytest.raises(ValueError, match='phase'):
        WhirlEstimator(1.0, 0.01, 0.1, phase=0.1)
