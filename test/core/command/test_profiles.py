import math

import numpy as np
import pytest
from hypothesis import event, given
from hypothesis import strategies as st
from properties import (  # the shared settings and strategies of the property tests
    BAD_TIMES,
    EXTREME_FLOATS,
    HUGE,
    TINY,
    WRONG_TYPES,
    anything,
    finite,
    profiles,
    props,
)
from reference import eq26
from scipy.integrate import quad

from rotrod_core import (
    ConstantProfile,
    Eq26Profile,
    RampProfile,
    SineSweepProfile,
    SpinUpProfile,
    StepProfile,
    TableProfile,
    make_profile,
)

PROFILES = [Eq26Profile(), Eq26Profile(period=4.0, omega_target=-1.5), ConstantProfile(1.3),
            StepProfile(2.0, t_step=1.0), RampProfile(2.0, 3.0, t_start=0.5),
            TableProfile([0, 1, 2.5, 4], [0, 1.0, 1.5, 0.2]),
            SineSweepProfile(0.3, 0.5, 3.0, duration=5.5, offset=1.0),
            SineSweepProfile(0.2, 4.0, 1.0, duration=6.5), SineSweepProfile(0.1, 2.0, 2.0),
            SpinUpProfile(2.5, [0.5, 0.5, 2.0, 2.0], t_start=1.0)]


def test_eq26_matches_model_md():
    p = Eq26Profile()
    for t in np.linspace(0, 40, 801):
        w, wd = eq26(t)
        assert p.omega(t) == pytest.approx(w, abs=1e-14)
        assert p.omega_dot(t) == pytest.approx(wd, abs=1e-14)


def test_eq26_is_smooth_at_the_joints():
    p = Eq26Profile()
    for tj in (15.0, 20.0, 35.0):
        for f in (p.omega, p.omega_dot):
            assert f(tj - 1e-9) == pytest.approx(f(tj + 1e-9), abs=1e-8)
        assert p.omega_dot(tj) == pytest.approx(0.0, abs=1e-12)
    assert p.omega(0.0) == 0.0 and p.omega(15.0) == 2.0 and p.omega(35.0) == pytest.approx(0)
    assert p.end_time == 35.0 and p.peak == 2.0


@pytest.mark.parametrize('p', PROFILES, ids=repr)
def test_derivative_and_angle_are_consistent(p):
    t = np.linspace(0.01, 6.0, 97)
    h = 1e-6
    numeric = (p.omega(t + h) - p.omega(t - h)) / (2 * h)
    smooth = np.array([all(abs(tt - j[0]) > 1e-3 for j in p.jumps()) for tt in t])
    kinks = {0.5, 3.5, 1.0, 2.5}   # ramp corners and table nodes: one-sided derivatives
    smooth &= np.array([all(abs(tt - k) > 1e-3 for k in kinks) for tt in t])
    assert np.allclose(p.omega_dot(t)[smooth], numeric[smooth], atol=1e-6)
    for tt in (0.3, 1.7, 5.2):
        breaks = [b for b in [j[0] for j in p.jumps()] + sorted(kinks) if 0 < b < tt]
        integral = quad(p.omega, 0, tt, points=breaks or None, limit=200, epsabs=1e-13)[0]
        assert p.angle(tt) == pytest.approx(integral, abs=1e-9)


@pytest.mark.parametrize('p', PROFILES, ids=repr)
def test_arrays_and_scalars_agree(p):
    t = np.array([0.0, 0.7, 2.0, 9.0])
    assert np.allclose(p.omega(t), [p.omega(x) for x in t])
    assert isinstance(p.omega(0.7), float)


@pytest.mark.parametrize('p', PROFILES, ids=repr)
def test_with_peak_rescales_the_shape(p):
    q = p.with_peak(3.0)
    assert q.peak == pytest.approx(3.0)
    t = np.linspace(0, 6, 50)
    assert np.allclose(q.omega(t), p.omega(t) * 3.0 / p.peak)   # same sign, same shape


def test_with_peak_of_an_all_zero_table_is_an_error():
    with pytest.raises(ValueError, match='all-zero'):
        TableProfile([0, 1], [0, 0]).with_peak(2.0)


def test_step_profile_jump_only_after_start():
    assert StepProfile(2.0, t_step=1.0).jumps() == ((1.0, 0.0, 2.0),)
    assert StepProfile(2.0).jumps() == ()


def test_table_interpolates_without_overshoot():
    p = TableProfile([0, 1, 2, 3], [0, 2, 2, 0])
    t = np.linspace(0, 3, 301)
    assert np.all(p.omega(t) <= 2.0 + 1e-12)
    assert p.omega(1.0) == 2.0 and p.omega(10.0) == 0.0


def test_table_from_csv(tmp_path):
    f = tmp_path / 'w.csv'
    f.write_text('time [s],omega [rad/s]\n0,0\n1,1\n2,1.5\n')
    assert TableProfile.from_csv(f).omega(2.0) == 1.5
    with pytest.raises(ValueError, match='cannot read'):
        TableProfile.from_csv(tmp_path / 'missing.csv')


@pytest.mark.parametrize('make', [
    lambda: Eq26Profile(period=0), lambda: Eq26Profile(period=-1),
    lambda: Eq26Profile(omega_target=math.nan), lambda: ConstantProfile(math.inf),
    lambda: StepProfile(2.0, t_step=-1), lambda: RampProfile(2.0, ramp_time=0),
    lambda: TableProfile([0, 1], [0]), lambda: TableProfile([0, 0], [0, 1]),
    lambda: TableProfile([1, 0], [0, 1]), lambda: TableProfile([0, 1], [0, math.nan]),
    lambda: make_profile('sawtooth'), lambda: make_profile('eq26', bogus=1),
    lambda: Eq26Profile(period='fast'),
])
def test_bad_profiles_are_rejected(make):
    with pytest.raises(ValueError):
        make()


def test_sine_sweep_is_a_linear_chirp():
    p = SineSweepProfile(amplitude=0.2, f_start=0.5, f_end=4.0, duration=30.0)
    assert p.omega(0.0) == 0.0 and p.omega_dot(0.0) == pytest.approx(0.2 * 2 * math.pi * 0.5)
    # instantaneous frequency = f_start + (f_end - f_start) t / T: zero crossings of w
    t = np.linspace(0, 30, 3_000_001)
    w = p.omega(t)
    crossings = t[1:][np.sign(w[1:]) != np.sign(w[:-1])]
    # the number of half cycles is 2 * integral of f = 2 (0.5 + 4) / 2 * 30 = 135
    assert len(crossings) == pytest.approx(135, abs=1)
    assert p.omega(40.0) == p.omega(30.0) and p.omega_dot(40.0) == 0.0
    assert p.peak == 0.2 and p.end_time == 30.0
    assert make_profile('sine_sweep', amplitude=0.1).amplitude == 0.1


def test_eq26_peak_angular_acceleration_is_2w_over_t():
    # docs/usage.md and config/table1.yaml quote it (0.27 rad/s^2) against the default
    # max_angular_acceleration of the simulator (0.5 rad/s^2)
    t = np.linspace(0, 40, 400001)
    peak = np.max(np.abs(Eq26Profile().omega_dot(t)))
    assert peak == pytest.approx(2 * 2.0 / 15.0, rel=1e-9)
    assert round(peak, 2) == 0.27


TIMES = st.one_of(st.floats(-10.0, 500.0), st.floats(allow_nan=False, allow_infinity=False),
                  st.sampled_from([0.0, -0.0, TINY, 1e-300, 1e300, HUGE, -HUGE]))


@st.composite
def tables(draw, sane_only=False):
    """Keyword arguments of a TableProfile: increasing times, angular velocities."""
    n = draw(st.integers(2, 8))
    value = st.floats(-50.0, 50.0) if sane_only else anything(st.floats(-50.0, 50.0))
    steps = st.floats(1e-3, 10.0) if sane_only else anything(st.floats(1e-3, 10.0))
    if draw(st.booleans()) or sane_only:
        raw = draw(st.lists(st.floats(1e-3, 10.0) if sane_only else st.one_of(
            st.floats(1e-3, 10.0), st.floats(1e-300, 1e300)), min_size=n, max_size=n))
        times = list(np.cumsum(raw) - raw[0])
    else:
        times = draw(st.lists(steps, min_size=n, max_size=n))
    omegas = draw(st.lists(value, min_size=n, max_size=n))
    return {'times': times, 'omegas': omegas}


def evaluate(profile, t):
    """omega, omega_dot at t (finite: the contract) and angle (finite or ValueError)."""
    w, wd = profile.omega(t), profile.omega_dot(t)
    assert finite(w) and finite(wd), (profile, t, w, wd)
    if np.ndim(t) == 0:
        assert type(w) is float and type(wd) is float
    else:
        assert np.shape(w) == np.shape(t) == np.shape(wd)
    try:
        theta = profile.angle(t)
    except ValueError as exc:
        assert 'overflow' in str(exc), str(exc)
    else:
        assert finite(theta), (profile, t, theta)
    return w, wd


@props(500)
@given(profiles(), st.lists(TIMES, min_size=1, max_size=6))
def test_profiles_are_refused_clearly_or_finite_at_every_finite_time(spec, times):
    """Construction: a ValueError naming the class and field, or a profile whose w and
    w' are finite at every finite time (scalar or array: huge, negative, subnormal).
    The angle grows without bound (W t): finite, or a ValueError saying it overflows."""
    cls, kwargs = spec
    try:
        profile = cls(**kwargs)
    except ValueError as exc:
        event('refused')
        assert str(exc).startswith(cls.__name__ + '.'), str(exc)
        return
    w, wd = evaluate(profile, np.array(times))
    for i, t in enumerate(times):           # a scalar time and an array agree
        assert evaluate(profile, t) == (w[i], wd[i])
    assert finite(profile.peak) and profile.peak >= 0
    assert profile.end_time is None or finite(profile.end_time)


@props(200)
@given(tables(), st.lists(TIMES, min_size=1, max_size=6))
def test_tables_are_refused_clearly_or_finite_without_overshoot(kwargs, times):
    """A table: ValueError, or w, w' finite and w within the tabulated values (PCHIP
    does not overshoot; up to rounding of the largest |w|)."""
    try:
        profile = TableProfile(**kwargs)
    except ValueError as exc:
        assert str(exc).startswith('TableProfile'), str(exc)
        return
    tol = 1e-12 * np.max(np.abs(profile.omegas))    # PCHIP's rounding, of the largest |w|
    lo, hi = min(profile.omegas) - tol, max(profile.omegas) + tol
    for t in [*times, np.array(times)]:
        w, _ = evaluate(profile, t)
        assert np.all((lo <= w) & (w <= hi))


@props(200)
@given(st.one_of(profiles(sane_only=True), tables(sane_only=True)),
       st.one_of(EXTREME_FLOATS, WRONG_TYPES, st.floats(-1e3, 1e3)))
def test_with_peak_is_refused_clearly_or_a_finite_profile(spec, peak):
    """with_peak(W): a ValueError, or a profile of the same kind with |peak| = |W|
    (up to rounding) whose w, w' are finite."""
    profile = TableProfile(**spec) if isinstance(spec, dict) else spec[0](**spec[1])
    try:
        scaled = profile.with_peak(peak)
    except ValueError as exc:
        assert 'Profile' in str(exc) or 'peak' in str(exc), str(exc)
        return
    assert type(scaled) is type(profile)
    assert scaled.peak == pytest.approx(abs(float(peak)), rel=1e-9, abs=1e-300)
    evaluate(scaled, np.linspace(-1.0, 2 * (scaled.end_time or 1.0), 7))


@props(150)
@given(st.one_of(profiles(sane_only=True), tables(sane_only=True)), BAD_TIMES,
       st.sampled_from(['omega', 'omega_dot', 'angle']), st.booleans())
def test_a_non_finite_or_non_numeric_time_is_a_clear_error(spec, t, method, as_array):
    """Contract: t must be a finite number (or an array of them); else ValueError naming t.

    (Before, nan gave 0 from Eq26Profile and NaN from the others, silently.)"""
    profile = TableProfile(**spec) if isinstance(spec, dict) else spec[0](**spec[1])
    if as_array and isinstance(t, bool):
        return      # numpy reads [0.5, True] as [0.5, 1.0]: a bool in a list is a number
    arg = [0.5, t, 1.0] if as_array else t
    with pytest.raises(ValueError, match=r'\btime\b|\bt\b'):
        getattr(profile, method)(arg)


@props(300)
@given(st.floats(1e-3, 1e3), st.floats(-1e3, 1e3), st.floats(-1.0, 3.0), st.floats(-1.0, 3.0))
def test_eq26_is_continuous_and_its_acceleration_is_bounded_by_2w_over_t(T, W, a, b):
    """Eq. 26: |w'| <= 2|W|/T everywhere and w is Lipschitz with that constant; w stays
    between 0 and W."""
    p = Eq26Profile(period=T, omega_target=W)
    bound = 2 * abs(W) / T
    t1, t2 = a * T * 7 / 3, b * T * 7 / 3
    w1, w2 = p.omega(t1), p.omega(t2)
    assert abs(p.omega_dot(t1)) <= bound * (1 + 1e-12)
    assert abs(w2 - w1) <= bound * abs(t2 - t1) * (1 + 1e-9) + 1e-12 * abs(W)
    assert min(0.0, W) - 1e-12 * abs(W) <= w1 <= max(0.0, W) + 1e-12 * abs(W)
    for joint in (0.0, T, 4 * T / 3, 7 * T / 3):     # continuous across the joints
        h = 1e-9 * T
        assert abs(p.omega(joint + h) - p.omega(joint - h)) <= 2 * bound * h + 1e-12 * abs(W)


def test_regression_profiles_whose_slope_or_phase_overflows_are_refused():
    for make in (lambda: Eq26Profile(period=1e-320), lambda: Eq26Profile(period=TINY,
                                                                         omega_target=0.0),
                 lambda: RampProfile(ramp_time=1e-320),
                 lambda: RampProfile(t_start=HUGE, ramp_time=HUGE),
                 lambda: SineSweepProfile(f_end=1e300, duration=1e10),
                 lambda: SineSweepProfile(amplitude=HUGE, offset=HUGE),
                 lambda: TableProfile([0, 1e-300], [-1e308, 1e308])):
        with pytest.raises(ValueError, match='Profile'):
            make()
    with pytest.raises(ValueError, match='overflow'):
        ConstantProfile(1e308).angle(10.0)


@props(60)
@given(st.one_of(st.text(max_size=5), st.sampled_from(['eq26', 'ramp', 'table'])),
       st.dictionaries(st.sampled_from(['period', 'omega_target', 'bogus', 'times']),
                       anything(st.floats(0.1, 10.0)), max_size=3))
def test_make_profile_raises_value_error_only(name, kwargs):
    try:
        profile = make_profile(name, **kwargs)
    except ValueError:
        return
    evaluate(profile, 1.0)
