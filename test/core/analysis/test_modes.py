"""Frequencies and stability at constant speed against closed forms and simulations."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from properties import (  # the shared settings and strategies of the property tests
    EXTREME_FLOATS,
    WRONG_TYPES,
    finite,
    props,
    rod_fields,
)
from reference import R0, W0

from rotrod_core import (
    ConstantProfile,
    RodParams,
    campbell,
    dynamic_frequencies,
    modal_analysis,
    simulate,
    static_deflection,
)

RECT = RodParams(section='rectangular', section_width=0.004, section_thickness=0.003)


def test_eq28_at_2_rad_s():
    f1, f2 = dynamic_frequencies(RodParams(), 2.0)
    assert f1 == pytest.approx((W0 - 2) / (2 * math.pi), rel=1e-12)
    assert f2 == pytest.approx((W0 + 2) / (2 * math.pi), rel=1e-12)
    assert (round(f1, 4), round(f2, 4)) == (1.6131, 2.2497)
    f1, f2 = dynamic_frequencies(RodParams(), np.array([0.0, W0]))
    assert f1[0] == f2[0] == pytest.approx(W0 / (2 * math.pi))
    assert f1[1] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize('w', [0.0, 1.0, 2.0, 6.0, 11.0, 15.0])
def test_eq28_equals_eigenvalues(w):
    modes = modal_analysis(RodParams(), w)
    expected = sorted([abs(W0 - w), W0 + w])
    assert np.allclose(modes.frequencies, np.array(expected) / (2 * math.pi), rtol=1e-10)
    assert modes.stable
    if 0 < w < W0:
        assert [m.whirl for m in modes.modes] == ['forward', 'backward']
    if w > W0:   # the slow mode whirls backwards in the rotating frame above w0
        assert [m.whirl for m in modes.modes] == ['backward', 'backward']


@pytest.mark.parametrize('w', [0.5, 2.0, 6.0])
def test_eq28_equals_the_spectrum_of_a_simulated_response(w):
    """FFT of z = u + i v: forward whirl at +f1, backward at -f2 (docs/model.md)."""
    dt, t_end = 5e-3, 200.0
    run = simulate(RodParams(), ConstantProfile(w), t_end, dt=dt)
    z = run.u + 1j * run.v
    z = z - z.mean()
    n = len(z)
    win = np.hanning(n)
    spec = np.abs(np.fft.fft(z * win))
    freqs = np.fft.fftfreq(n, dt)

    def peak(sign):
        k = np.argmax(np.where(sign * freqs > 0.2, spec, 0))
        a, b, c = np.log(spec[k - 1:k + 2])
        return freqs[k] + 0.5 * (a - c) / (a - 2 * b + c) * (freqs[1] - freqs[0])

    f1, f2 = dynamic_frequencies(RodParams(), w)
    assert peak(+1) == pytest.approx(f1, rel=1e-3)
    assert -peak(-1) == pytest.approx(f2, rel=1e-3)


def test_static_deflection_at_2_rad_s():
    u, v = static_deflection(RodParams(), 2.0)
    assert u == pytest.approx(0.3 * 4 * R0 / (0.3 * W0**2 - 1.2), rel=1e-12)
    assert u == pytest.approx(2.792e-3, rel=1e-3) and v == 0.0
    assert static_deflection(RodParams(), W0)[0] == math.inf


def test_rectangular_rod_is_unstable_exactly_between_its_natural_frequencies():
    wa, wb = sorted([RECT.natural_frequency_radial, RECT.natural_frequency_tangential])
    c = campbell(RECT, np.linspace(0, 30, 121))
    assert len(c.unstable_bands) == 1
    lo, hi = c.unstable_bands[0]
    assert lo == pytest.approx(wa, rel=1e-8) and hi == pytest.approx(wb, rel=1e-8)
    assert modal_analysis(RECT, 0.5 * (wa + wb)).max_growth_rate > 0
    assert modal_analysis(RECT, 0.99 * wa).stable and modal_analysis(RECT, 1.01 * wb).stable


def test_unstable_band_grows_in_simulation_at_the_eigen_rate():
    w = 21.0
    p = RECT.replace(eccentricity=0.0)
    rate = modal_analysis(p, w).max_growth_rate
    run = simulate(p, ConstantProfile(w), 4.0, dt=1e-3, initial={'u': 1e-9})
    assert modal_analysis(p, w).modes[0].whirl == 'none'    # a real pair: divergence
    d = run.deflection
    k1, k2 = np.searchsorted(run.t, [2.0, 4.0])
    measured = math.log(d[k2] / d[k1]) / (run.t[k2] - run.t[k1])
    assert measured == pytest.approx(rate, rel=1e-3)


def test_rotating_damping_destabilises_above_w0():
    p = RodParams(damping_ratio=0.02)
    c = campbell(p, np.linspace(0, 20, 81))
    assert len(c.unstable_bands) == 1
    assert c.unstable_bands[0][0] == pytest.approx(W0, rel=1e-5)
    assert c.unstable_bands[0][1] == 20.0
    assert modal_analysis(p, 5.0).max_growth_rate < 0


def test_damped_free_vibration_decays_below_w0():
    p = RodParams(damping_ratio=0.02, eccentricity=0.0)
    slowest = max(m.growth_rate for m in modal_analysis(p, 5.0).modes)
    assert slowest < 0
    run = simulate(p, ConstantProfile(5.0), 10.0, initial={'u': 1e-3})
    assert np.max(run.deflection[run.t > 9]) < 1.05e-3 * math.exp(slowest * 9)


OMEGAS = st.one_of(st.floats(-100.0, 100.0), EXTREME_FLOATS, WRONG_TYPES,
                   st.floats(allow_nan=False))


@props(250)
@given(rod_fields(sane_only=True), OMEGAS)
def test_dynamic_frequencies_and_modes_are_finite_or_a_clear_error(fields, omega):
    """Eq. 28 / the eigen analysis: finite, 0 <= f1 <= f2, or a ValueError naming omega
    (not a finite number, or |w| so large that w^2 overflows the state matrix)."""
    params = RodParams(**fields)
    try:
        f1, f2 = dynamic_frequencies(params, omega)
    except ValueError as exc:
        assert 'omega' in str(exc), str(exc)
        assert not (isinstance(omega, float) and abs(omega) <= 1e6)
        return
    assert finite([f1, f2]) and 0 <= f1 <= f2
    try:
        modes = modal_analysis(params, omega)
    except ValueError as exc:   # w^2 overflows (before: numpy's LinAlgError)
        assert 'omega' in str(exc) and abs(omega) > 1e150, str(exc)
        return
    assert finite(modes.frequencies) and finite(modes.max_growth_rate)


@props(250)
@given(rod_fields(sane_only=True), OMEGAS)
def test_static_deflection_is_finite_except_at_resonance(fields, omega):
    """u_s = m w^2 r0 / (k1 - m w^2): finite for every finite w except exactly at
    w^2 = k1/m (documented: +inf there); -> -r0 as |w| -> inf (before: NaN for
    |w| > 1e154, where w^2 overflowed)."""
    params = RodParams(**fields)
    try:
        u, v = static_deflection(params, omega)
    except ValueError as exc:
        assert 'omega' in str(exc), str(exc)
        return
    assert v == 0.0
    if params.mass * omega * omega == params.stiffness_radial:
        assert u == math.inf or params.eccentricity == 0
    else:
        assert finite(u), (omega, u)
        r0 = params.eccentricity
        assert u >= 0 if omega * omega * params.mass < params.stiffness_radial else u <= -r0
