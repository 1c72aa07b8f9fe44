"""The profile of a SpinUp goal: what the hub is to follow, and why a goal is refused."""

import math

import pytest
from reference import W0

from rotrod_core import RodParams
from rotrod_core.command.spin_up import goal_profile


def test_a_planned_goal_is_the_planners_spin_up_from_the_current_speed():
    g = goal_profile('planned', 0.5, 2.0, max_angular_acceleration=0.5)
    p = g.profile
    assert p.omega(0.0) == 0.5 and p.omega(g.change_time) == pytest.approx(2.0, abs=1e-12)
    assert p.t_start == 0 and g.change_time == p.duration        # at once, no lead
    assert 0 < g.predicted_residual <= 2.5e-7                 # the default residual bound
    assert p.max_angular_acceleration <= 0.9 * 0.5 * (1 + 1e-9)


def test_a_robust_goal_predicts_its_bands_residual():
    g = goal_profile('planned_robust', 0.0, 2.0, robust_band=0.1,
                     max_angular_acceleration=0.5)
    assert g.profile.robust == 0.1 and g.predicted_residual == g.profile.band_residual


@pytest.mark.parametrize('name, T', [('eq26', 15.0), ('ramp', 10.0)])
def test_eq26_and_ramp_spin_up_to_the_target_in_their_duration(name, T):
    g = goal_profile(name, 0.0, 2.0, duration=T)
    assert g.change_time == T
    assert g.profile.omega(0.0) == 0.0
    assert g.profile.omega(T) == pytest.approx(2.0, abs=1e-12)
    assert g.profile.omega(T / 2) == pytest.approx(1.0, abs=1e-12)   # both: w(T/2) = W/2
    assert math.isnan(g.predicted_residual)


@pytest.mark.parametrize('args, kwargs, reason', [
    (('warp', 0.0, 2.0), {}, 'profile must be one of planned, planned_robust, eq26, ramp'),
    (('planned', 0.0, math.nan), {}, 'omega_target must be a finite number'),
    (('planned', 0.0, 2.0), {'residual': -1.0}, 'residual must be >= 0'),
    (('planned_robust', 0.0, 2.0), {}, 'planned_robust needs robust_band in (0, 1)'),
    (('eq26', 1.0, 2.0), {}, 'eq26 starts from rest; the hub turns at 1 rad/s'),
    (('planned', 0.0, 13.0), {'deflection_limit': 1.0}, 'lowest natural frequency'),
    (('planned', 0.0, 2.0), {'deflection_limit': 0.002}, 'static deflection at omega_target'),
])
def test_a_goal_that_cannot_be_served_is_refused_with_the_reason(args, kwargs, reason):
    assert W0 < 13.0                                          # Table 1's w0, 12.1 rad/s
    with pytest.raises(ValueError) as err:
        goal_profile(*args, params=RodParams(), **kwargs)
    assert reason in str(err.value)
