import math

import numpy as np
import pytest
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
