"""The named profiles built from options (one registry for the CLI and the profile
publisher), with the planned spin-up among them: its options, its refusals, and the
acceleration contract with the simulator."""

import inspect
import math
from pathlib import Path

import numpy as np
import pytest
from reference import R0, K, M

from rotrod_core import RodParams, plan_spin_up
from rotrod_core.command import registry
from rotrod_core.command.profiles import Eq26Profile, RampProfile, SpinUpProfile
from rotrod_core.command.registry import (
    OPTION_PROFILES,
    PLAN_HOLD,
    PLAN_LEAD,
    PLANNED_ACCELERATION_FRACTION,
    PLANNED_OPTIONS,
    PROFILE_OPTIONS,
    describe,
    profile_from_options,
    stream_duration,
)
from rotrod_core.live.engine import EngineConfig

ROOT = Path(__file__).resolve().parents[3]


@pytest.fixture(scope='module')
def planned():
    """The planned profile of the defaults: Table 1, 0 -> 2 rad/s within 0.9 x 0.5."""
    return profile_from_options('planned', {})


def test_every_option_has_a_unit_a_description_and_a_range():
    for o in PROFILE_OPTIONS:
        assert o.description
        if isinstance(o.default, float):
            assert o.unit and o.low is not None and o.low <= o.default <= o.high, o


def test_the_planned_options_are_the_planners_arguments_with_its_defaults():
    signature = inspect.signature(plan_spin_up).parameters
    assert set(PLANNED_OPTIONS) == set(signature) - {'params'}
    options = {o.name: o for o in PROFILE_OPTIONS}
    for name in PLANNED_OPTIONS:
        assert 'planned' in options[name].description
        if name != 'max_angular_acceleration' and name != 'omega_target':
            assert options[name].default == signature[name].default
    assert 'planned' in OPTION_PROFILES


def test_the_default_bound_is_the_simulators():
    options = {o.name: o for o in PROFILE_OPTIONS}
    assert options['max_angular_acceleration'].default == EngineConfig().max_angular_acceleration


def test_planned_holds_its_start_then_arrives_within_the_bound_and_the_limit(planned):
    assert isinstance(planned, SpinUpProfile) and planned.t_start == PLAN_LEAD
    t = np.linspace(0.0, planned.end_time + 2.0, 20001)
    w, wd = planned.omega(t), planned.omega_dot(t)
    assert np.all(w[t <= PLAN_LEAD] == 0.0) and np.all(w[t >= planned.end_time] == 2.0)
    assert planned.end_time == pytest.approx(PLAN_LEAD + planned.duration)
    bound = PLANNED_ACCELERATION_FRACTION * 0.5
    assert np.max(np.abs(wd)) <= bound * (1 + 1e-9)
    assert planned.max_angular_acceleration <= bound * (1 + 1e-9)
    # at least the time the bound allows: |dw| / bound
    assert planned.duration >= 2.0 / bound
    assert planned.peak_deflection <= 3e-3 and planned.residual_amplitude <= 2.5e-7


def test_the_lead_only_delays_the_plan(planned):
    plan = plan_spin_up(RodParams(), 2.0, max_angular_acceleration=0.45)
    assert plan.duration == planned.duration
    t = np.linspace(0.0, plan.duration, 501)
    assert np.allclose(planned.omega(t + PLAN_LEAD), plan.omega(t), rtol=0, atol=1e-12)
    assert planned.angle(PLAN_LEAD + 1.0) == pytest.approx(plan.angle(1.0), abs=1e-12)
    assert planned.residual_amplitude == plan.residual_amplitude


def test_zero_plans_without_a_bound_and_says_what_the_simulator_must_allow():
    fast = profile_from_options('planned', {'max_angular_acceleration': 0.0})
    assert fast.duration == pytest.approx(plan_spin_up(RodParams(), 2.0).duration)
    assert fast.max_angular_acceleration > 0.5
    lines = describe(fast, {'max_angular_acceleration': 0.0})
    need = math.ceil(fast.max_angular_acceleration * 1e3 * (1 - 1e-9)) / 1e3
    assert 'no bound (max_angular_acceleration 0)' in lines[0]
    assert f'max_angular_acceleration to at least {need:g} rad/s^2' in lines[1]


def test_describe_says_what_was_planned_and_the_bound_it_honoured(planned):
    plan, must = describe(planned, {})
    assert f'duration {planned.duration:.3f} s' in plan
    assert f'peak deflection {planned.peak_deflection * 1e3:.3f} mm' in plan
    assert planned.residual_amplitude <= 2.5e-7 and 'residual whirl <= 0.25 um' in plan
    assert 'within 0.9 x max_angular_acceleration 0.5 rad/s^2' in plan
    assert 'the simulator must allow' in must and 'max_angular_acceleration 0.5' in must
    assert describe(Eq26Profile(), {}) == []


def test_the_plan_is_for_the_rod_given():
    """A stiffer rod (E x 1.21: w0 x 1.1) deflects less; the upright steel rod of
    config/real_rig.yaml holds 2 rad/s beyond 3 mm, which no plan can avoid."""
    stiff = RodParams(youngs_modulus=1.21e11)
    plan = profile_from_options('planned', {'max_angular_acceleration': 0.0}, stiff)
    us = M * 4.0 * R0 / (1.21 * K - M * 4.0)       # docs/model.md, static deflection
    assert plan.peak_deflection >= us
    assert plan.duration != pytest.approx(profile_from_options(
        'planned', {'max_angular_acceleration': 0.0}).duration, rel=1e-3)
    rig = RodParams(gravity=9.81, rod_density=7850.0)
    with pytest.raises(ValueError, match='static deflection at omega_target'):
        profile_from_options('planned', {}, rig)


@pytest.mark.parametrize('options, message', [
    ({'robust': 1.0}, 'robust must be < 1'),
    ({'robust': -0.1}, 'robust must be >= 0'),
    ({'residual': 0.0}, 'residual must be > 0'),
    ({'deflection_limit': 0.0}, 'deflection_limit must be > 0'),
    ({'deflection_limit': 0.002}, 'static deflection at omega_target = 2 rad/s'),
    ({'max_angular_acceleration': -1.0}, 'max_angular_acceleration must be >= 0'),
    ({'max_angular_acceleration': math.nan}, 'max_angular_acceleration must be finite'),
    ({'omega_target': -2.0}, 'omega_target must be >= 0'),
    ({'omega_target': 0.0}, 'nothing to plan'),
    ({'omega_target': 13.0, 'deflection_limit': 100.0}, 'lowest natural frequency'),
    ({'robust': 0.5, 'omega_target': 7.0, 'deflection_limit': 100.0},
     'x (1 - robust = 0.5)'),
    ({'omega_target': 'fast'}, 'omega_target must be a number'),
])
def test_bad_planned_options_are_refused_with_the_reason(options, message):
    with pytest.raises(ValueError, match=r'^profile planned: ') as refused:
        profile_from_options('planned', options)
    assert message in str(refused.value)


def test_an_unknown_profile_names_the_known_ones():
    with pytest.raises(ValueError, match='planned'):
        profile_from_options('spiral', {})


def test_options_of_other_nodes_and_none_are_ignored():
    ramp = profile_from_options('ramp', {'omega_target': None, 'rate': 100.0, 'mass': 1.0})
    assert ramp == RampProfile(2.0, 15.0)


def test_a_planned_stream_goes_on_past_the_plan_the_others_end_at_theirs(planned):
    assert stream_duration(planned) == planned.end_time + PLAN_HOLD
    assert stream_duration(Eq26Profile()) == 35.0
    assert stream_duration(profile_from_options('constant', {})) == 0.0


def test_the_fraction_is_applied_to_the_bound(monkeypatch):
    assert registry.planned_bound(0.5) == pytest.approx(0.45)
    assert registry.planned_bound(0) is None
    with pytest.raises(ValueError, match='max_angular_acceleration'):
        registry.planned_bound(math.inf)


def test_a_plan_is_exactly_at_its_end_speeds_outside_the_change(planned):
    """The streamed speeds before and after the change are the requested ones, to the
    bit (the spline's value at its ends is not). The robust plan of config/planned.yaml
    (half a minute to plan) is held to the same through the nodes by the long tests
    (test_spin_up_action: w arrives at exactly 2 rad/s)."""
    plan = planned
    t = np.array([0.0, plan.t_start, plan.end_time, plan.end_time + 7.3])
    assert list(plan.omega(t)) == [0.0, 0.0, 2.0, 2.0]
    assert list(plan.omega_dot(t[[0, 3]])) == [0.0, 0.0]


def test_the_reports_planned_row_is_config_planned_yaml():
    """docs/reproduce.md's robust row plans what config/planned.yaml sends."""
    import yaml

    from rotrod_core.reporting.spin_ups import PLANNED
    doc = yaml.safe_load((ROOT / 'config' / 'planned.yaml').read_text())
    bound = doc['/**/rotrod_simulator']['ros__parameters']['max_angular_acceleration']
    streamed = {'max_angular_acceleration': bound,      # the simulator's, as it plans
                **doc['/**/rotrod_profile_publisher']['ros__parameters']}
    assert streamed.pop('profile') == 'planned'
    label, options = PLANNED[-1]
    assert 'config/planned.yaml' in label
    assert registry.options_with_defaults(streamed) == registry.options_with_defaults(options)
