"""Critical speeds (closed forms and from simulations) against their definitions."""

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from properties import (  # the shared settings and strategies of the property tests
    EXTREME_FLOATS,
    HUGE,
    WRONG_TYPES,
    finite,
    props,
    rod_fields,
)
from reference import R0, W0, impulsive_start, step_start

from rotrod_core import (
    ConstantProfile,
    RampProfile,
    RodParams,
    StepProfile,
    critical_speed,
    critical_speed_for_profile,
)

RECT = RodParams(section='rectangular', section_width=0.004, section_thickness=0.003)


@pytest.mark.parametrize('start', ['quasi_static', 'step', 'impulsive'])
def test_closed_form_critical_speeds_meet_their_definitions(start):
    delta = 3e-3
    r0 = np.array([0.0, 0.01, 0.1, 0.5])
    w = critical_speed(RodParams(eccentricity=r0), delta, start)
    assert w[0] == pytest.approx(W0)                  # r0 = 0: the natural frequency
    assert np.all(np.diff(w) < 0)                     # Fig. 10: falls with eccentricity
    w, r0 = w[1:], r0[1:]
    us = w**2 * r0 / (W0**2 - w**2)
    peak = {'quasi_static': us, 'step': 2 * us, 'impulsive': r0 * w / (W0 - w)}[start]
    assert np.allclose(peak, delta, rtol=1e-12)


def test_step_and_impulsive_peaks_approach_the_closed_form_bounds():
    w = 2.0
    t = np.arange(0, 2000, 2e-3)
    us = w**2 * R0 / (W0**2 - w**2)
    assert np.max(np.abs(step_start(t, w))) == pytest.approx(2 * us, rel=2e-3)
    assert np.max(np.abs(impulsive_start(t, w))) == pytest.approx(R0 * w / (W0 - w), rel=2e-3)


def test_numerical_critical_speed_for_a_slow_ramp_is_quasi_static():
    p = RodParams(eccentricity=np.array([0.05, 0.1]))
    w_num = critical_speed_for_profile(p, RampProfile(1.0, 300.0), 3e-3, t_end=300.0, dt=5e-3,
                                       grid=12)
    assert np.allclose(w_num, critical_speed(p, 3e-3, 'quasi_static'), rtol=2e-3)


def test_numerical_critical_speed_for_sudden_starts():
    p = RodParams()
    step = critical_speed_for_profile(p, ConstantProfile(1.0), 3e-3, t_end=120.0, grid=8,
                                      dt=4e-3)
    imp = critical_speed_for_profile(p, StepProfile(1.0, t_step=0.5), 3e-3, t_end=120.0,
                                     grid=8, dt=4e-3)
    # finite runs never quite reach the asymptotic peak: slightly above the closed form
    assert step == pytest.approx(critical_speed(p, 3e-3, 'step'), rel=0.02)
    assert step >= critical_speed(p, 3e-3, 'step') * (1 - 1e-3)
    assert imp == pytest.approx(critical_speed(p, 3e-3, 'impulsive'), rel=0.02)


def test_critical_speed_rejects_bad_input():
    with pytest.raises(ValueError, match='deflection_limit'):
        critical_speed(RodParams(), -1.0)
    with pytest.raises(ValueError, match='deflection_limit'):
        critical_speed(RodParams(), math.nan)
    with pytest.raises(ValueError, match='start'):
        critical_speed(RodParams(), 3e-3, 'gradual')
    with pytest.raises(ValueError, match='k1 != k2'):
        critical_speed(RECT, 3e-3, 'step')


@props(250)
@given(rod_fields(sane_only=True),
       st.one_of(st.floats(1e-6, 1.0), EXTREME_FLOATS, WRONG_TYPES),
       st.sampled_from(['quasi_static', 'step', 'impulsive']),
       st.sampled_from([0.0, 1e-3, 0.1, 1e300, HUGE]))
def test_critical_speed_is_below_w0_and_grows_with_the_limit(fields, limit, start, r0):
    params = RodParams(**{**fields, 'section': 'circular', 'section_width': None,
                          'section_thickness': None, 'eccentricity': r0})
    try:
        w = critical_speed(params, limit, start)
    except ValueError as exc:
        assert 'deflection_limit' in str(exc), str(exc)
        return
    w0 = params.natural_frequency
    assert finite(w) and 0 <= w <= w0 * (1 + 1e-12)
    if float(limit) < HUGE / 2:
        assert critical_speed(params, 2 * float(limit), start) >= w * (1 - 1e-12)
    if r0 == 0:
        assert w == pytest.approx(w0)


def test_regression_critical_speed_when_limit_plus_eccentricity_overflows():
    p = RodParams(eccentricity=HUGE)
    w0 = p.natural_frequency
    assert critical_speed(p, HUGE, 'quasi_static') == pytest.approx(w0 * math.sqrt(0.5))
    assert critical_speed(p, HUGE, 'step') == pytest.approx(w0 * math.sqrt(1 / 3))
    assert critical_speed(p, HUGE, 'impulsive') == pytest.approx(w0 / 2)
