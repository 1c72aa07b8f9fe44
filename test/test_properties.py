"""Property-based tests: extreme, non-finite and wrongly typed input never gives a silent NaN.

The common contract of rotrod_core, checked here with hypothesis over the parameters,
the profiles, the real-time stepper and engine, the setpoint shaper, the whirl
estimator and the constant-rotation analysis: every call either raises a clear
ValueError (a :class:`~rotrod_core.live.engine.CommandRejected` for a refused command, a
:class:`~rotrod_core.numerics.checks.NonFiniteStateError` for a step that would overflow; both
keep the previous state), or returns finite numbers. Never NaN or +-inf where a number
is promised, never a ZeroDivisionError, OverflowError or TypeError from the arithmetic.

Inputs mix sane physical ranges with extreme floats (0, -0, negative, subnormal,
1e300, the largest float, nan, +-inf) and wrong types (str, None, bool). Every test is
derandomized and uses no example database, so a run is reproducible (CI).
"""

import math
import re

import numpy as np
import pytest
from hypothesis import HealthCheck, event, given, settings
from hypothesis import strategies as st

from rotrod_core import (
    ConstantProfile,
    Eq26Profile,
    RampProfile,
    RodParams,
    SineSweepProfile,
    StepProfile,
    TableProfile,
    WhirlEstimator,
    WhirlSettings,
    critical_speed,
    dynamic_frequencies,
    estimate_whirl,
    estimate_whirl_frequencies,
    make_profile,
    modal_analysis,
    simulate,
    static_deflection,
)
from rotrod_core.command.shaping import OmegaSetpointShaper
from rotrod_core.live.engine import (
    ERROR,
    MAX_DEFLECTION_RATIO,
    STEP_RESOLUTION,
    CommandRejected,
    EngineConfig,
    SimulationEngine,
    fastest_rate,
)
from rotrod_core.live.stepper import RealTimeStepper
from rotrod_core.model.equations import Coefficients
from rotrod_core.numerics.checks import NonFiniteStateError
from rotrod_core.offline.simulate import time_grid

PROPS = settings(derandomize=True, database=None, deadline=None, print_blob=False,
                 suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                        HealthCheck.filter_too_much])


def props(max_examples: int):
    """Settings of one test: reproducible (derandomized, no database), no deadline."""
    return settings(PROPS, max_examples=max_examples)


TINY = 5e-324                   # the smallest subnormal
HUGE = 1.7976931348623157e308   # the largest float
EXTREME_FLOATS = st.sampled_from([0.0, -0.0, -1.0, TINY, -TINY, 2.2e-308, 1e-300, 1e-150,
                                  1e150, 1e300, HUGE, -1e300, -HUGE,
                                  math.nan, math.inf, -math.inf])
WRONG_TYPES = st.sampled_from(['1 kg', 'fast', None, True, False, 10**400, -10**400])
"""Wrong types, and ints beyond the float range (float() raises OverflowError). (A
numeric string such as '1.0' is a number by design: float('1.0').)"""
CONTAINERS = st.sampled_from([[], (1.0, 2.0), {}])
NON_FINITE = st.sampled_from([math.nan, math.inf, -math.inf])


def anything(sane):
    """A value from a sane range, an extreme float or a wrongly typed value."""
    return st.one_of(sane, sane, EXTREME_FLOATS, st.floats(), WRONG_TYPES)


def finite(x) -> bool:
    """True when every element of x is a finite number."""
    return bool(np.all(np.isfinite(np.asarray(x, dtype=float))))


def is_number(x) -> bool:
    """True for a finite float or int (not a bool): what finite_number accepts, but
    numeric strings."""
    return (isinstance(x, (int, float)) and not isinstance(x, bool)
            and abs(x) <= HUGE and math.isfinite(x))


def test_regression_ints_beyond_the_float_range_are_a_value_error():
    # float(10**400) raises OverflowError, which the validators let through
    big = 10**400
    calls = (lambda: RodParams(mass=big), lambda: Eq26Profile(period=big),
             lambda: Eq26Profile().omega(big), lambda: Eq26Profile().omega([0.0, big]),
             lambda: TableProfile([0, big], [0, 1]), lambda: time_grid(big, 1e-3),
             lambda: dynamic_frequencies(RodParams(), big),
             lambda: critical_speed(RodParams(), big),
             lambda: RealTimeStepper(RodParams()).step_velocity(big),
             lambda: RealTimeStepper(RodParams(), initial={'u': big}),
             lambda: estimate_whirl([0, 1, big], [0, 0, 0], [0, 0, 0]),
             lambda: simulate(RodParams(), torque=big, t_end=0.01),
             lambda: simulate(RodParams(), torque=lambda t: big, t_end=0.01))
    for call in calls:
        with pytest.raises(ValueError):
            call()


# -- RodParams ------------------------------------------------------------------------

POSITIVE_FIELDS = ('mass', 'rod_length', 'rod_diameter', 'youngs_modulus')
NONNEGATIVE_FIELDS = ('eccentricity', 'hub_inertia', 'damping_ratio')
SANE = {
    'mass': st.floats(1e-3, 10.0), 'rod_length': st.floats(0.01, 2.0),
    'rod_diameter': st.floats(1e-4, 0.05), 'youngs_modulus': st.floats(1e9, 400e9),
    'eccentricity': st.floats(0.0, 0.5), 'hub_inertia': st.floats(0.0, 1.0),
    'damping_ratio': st.floats(0.0, 0.2), 'section_width': st.floats(1e-4, 0.05),
    'section_thickness': st.floats(1e-4, 0.05),
}
DERIVED = ('second_moment_radial', 'second_moment_tangential', 'stiffness_radial',
           'stiffness_tangential', 'natural_frequency_radial', 'natural_frequency_tangential')


LAB = {     # near the paper's rig: natural frequencies of a few Hz to ~150 Hz
    'mass': st.floats(0.05, 2.0), 'rod_length': st.floats(0.1, 1.0),
    'rod_diameter': st.floats(1e-3, 6e-3), 'youngs_modulus': st.floats(50e9, 250e9),
    'eccentricity': st.floats(0.0, 0.3), 'hub_inertia': st.floats(0.0, 0.5),
    'damping_ratio': st.floats(0.0, 0.1), 'section_width': st.floats(1e-3, 6e-3),
    'section_thickness': st.floats(1e-3, 6e-3),
}


@st.composite
def rod_fields(draw, sane_only=False, ranges=SANE):
    """Keyword arguments for RodParams: a random subset of fields, sane or not."""
    pick = (lambda name: ranges[name]) if sane_only else (lambda name: anything(ranges[name]))
    section = 'circular'
    if draw(st.booleans()):
        section = 'rectangular' if sane_only else draw(
            st.sampled_from(['rectangular', 'rectangular', 'circular', 'square', None]))
    fields = {'section': section}
    for name in POSITIVE_FIELDS + NONNEGATIVE_FIELDS:
        if name == 'rod_diameter' and section == 'rectangular':
            continue
        if draw(st.booleans()):
            fields[name] = draw(pick(name))
    if section == 'rectangular':
        for name in ('section_width', 'section_thickness'):
            fields[name] = draw(pick(name))
    return fields


def check_rod(p: RodParams):
    """Every derived quantity of a valid RodParams is finite, > 0 (damping >= 0)."""
    for name in DERIVED:
        value = getattr(p, name)
        assert finite(value) and np.all(np.asarray(value) > 0), (name, value)
    for name in ('damping_radial', 'damping_tangential'):
        value = getattr(p, name)
        assert finite(value) and np.all(np.asarray(value) >= 0), (name, value)
    co = Coefficients.from_params(p)
    for name, value in vars(co).items():
        assert finite(value), (name, value)
    assert np.all(co.w1sq > 0) and np.all(co.w2sq > 0)


@props(400)
@given(rod_fields())
def test_rod_params_are_refused_clearly_or_derive_finite_positive_quantities(fields):
    """RodParams(**fields): a ValueError naming the field, or all derived values finite."""
    try:
        p = RodParams(**fields)
    except ValueError as exc:
        event('refused')
        message = str(exc)
        assert message.startswith('RodParams')
        named = [f for f in (*POSITIVE_FIELDS, *NONNEGATIVE_FIELDS, 'section',
                             'section_width', 'section_thickness') if f in message]
        assert named, message
        return
    check_rod(p)


@props(150)
@given(st.sampled_from(POSITIVE_FIELDS + NONNEGATIVE_FIELDS),
       st.one_of(EXTREME_FLOATS, WRONG_TYPES, CONTAINERS))
def test_one_bad_field_is_named_in_the_error(name, value):
    """A single extreme value is either refused naming that field, or is harmless.
    (A sequence of numbers is a batch of systems, by design.)"""
    try:
        p = RodParams(**{name: value})
    except ValueError as exc:
        assert re.match(rf'RodParams(\.{name}\b|: .*\b{name}\b)', str(exc)), str(exc)
        return
    assert is_number(value) or value == (1.0, 2.0)
    check_rod(p)


def test_regression_rod_params_whose_derived_values_overflow_or_vanish_are_refused():
    # d^4 overflowed: the stiffness was inf; d^4 underflowed: k = 0, w0 = 0; l^3
    # overflowed as a Python float: OverflowError
    for fields in ({'rod_diameter': 1e300}, {'rod_diameter': 1e-100},
                   {'youngs_modulus': TINY}, {'rod_length': 1e-200}, {'rod_length': 1e150},
                   {'mass': 1e-320}):
        with pytest.raises(ValueError, match='RodParams'):
            RodParams(**fields)
    # k m overflowed (sqrt(k m) = inf), and with damping_ratio = 0 the damping was 0 x inf
    heavy = RodParams(mass=1e300, youngs_modulus=1e300, rod_diameter=1.0)
    assert heavy.damping_radial == 0.0 and heavy.damping_tangential == 0.0
    assert finite(heavy.replace(damping_ratio=0.1).damping_radial)


@props(60)
@given(st.lists(st.floats(1e-3, 10.0), min_size=1, max_size=4),
       st.sampled_from([1e300, TINY, 1e-100]))
def test_a_batch_with_one_unusable_system_is_refused(masses, diameter):
    diameters = np.full(len(masses), 0.003)
    diameters[-1] = diameter
    with pytest.raises(ValueError, match='RodParams'):
        RodParams(mass=np.array(masses), rod_diameter=diameters)


# -- profiles -------------------------------------------------------------------------

PROFILE_FIELDS = {
    Eq26Profile: {'period': st.floats(0.1, 100.0), 'omega_target': st.floats(-50.0, 50.0)},
    ConstantProfile: {'omega_target': st.floats(-50.0, 50.0)},
    StepProfile: {'omega_target': st.floats(-50.0, 50.0), 't_step': st.floats(0.0, 100.0),
                  'omega_start': st.floats(-50.0, 50.0)},
    RampProfile: {'omega_target': st.floats(-50.0, 50.0), 'ramp_time': st.floats(0.01, 100.0),
                  't_start': st.floats(0.0, 100.0)},
    SineSweepProfile: {'amplitude': st.floats(-5.0, 5.0), 'f_start': st.floats(0.0, 20.0),
                       'f_end': st.floats(0.0, 20.0), 'duration': st.floats(0.1, 100.0),
                       'offset': st.floats(-50.0, 50.0)},
}
TIMES = st.one_of(st.floats(-10.0, 500.0), st.floats(allow_nan=False, allow_infinity=False),
                  st.sampled_from([0.0, -0.0, TINY, 1e-300, 1e300, HUGE, -HUGE]))
BAD_TIMES = st.one_of(NON_FINITE, st.sampled_from(['1 s', 'now', None, True]))


@st.composite
def profiles(draw, sane_only=False):
    """(a profile class, keyword arguments for it)."""
    cls = draw(st.sampled_from(sorted(PROFILE_FIELDS, key=lambda c: c.__name__)))
    kwargs = {}
    for name, sane in PROFILE_FIELDS[cls].items():
        if draw(st.booleans()):
            kwargs[name] = draw(sane if sane_only else anything(sane))
    return cls, kwargs


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


# -- stepper --------------------------------------------------------------------------

ACTIONS = st.lists(st.tuples(st.sampled_from(['velocity', 'torque', 'jump', 'set']),
                             anything(st.floats(-20.0, 20.0))), min_size=1, max_size=25)


@props(120)
@given(rod_fields(sane_only=True), st.sampled_from(['exact', 'paper']),
       st.sampled_from([1e-4, 1e-3, 5e-3]), ACTIONS)
def test_the_stepper_keeps_a_finite_state_under_any_command(fields, coupling, dt, actions):
    """A bad command (not a finite number) is a ValueError; a step, jump or state that
    would overflow a NonFiniteStateError; both keep the state. Otherwise the state,
    torque and w' are finite, and energy, angular momentum and position are finite or,
    for an extreme (1e150) state, a NonFiniteStateError saying they overflow.

    Paper coupling with J = 0 and the mass on the axis has no rotary inertia: w' is
    undefined, a NonFiniteStateError (before: ZeroDivisionError)."""
    params = RodParams(**fields)
    try:
        stepper = RealTimeStepper(params, dt=dt, coupling=coupling)
    except ValueError as exc:
        assert coupling == 'exact' and params.hub_inertia == 0, str(exc)
        return
    for kind, value in actions:
        before, time = stepper.state, stepper.time
        try:
            if kind == 'velocity':
                stepper.step_velocity(value)
            elif kind == 'torque':
                stepper.step_torque(value)
            elif kind == 'jump':
                stepper.jump_omega(value)
            else:
                stepper.set_state(u=value)
        except ValueError:
            event('bad command')
            assert not is_number(value)
            assert stepper.state == before and stepper.time == time
            continue
        except NonFiniteStateError as exc:
            event('overflow refused')
            assert is_number(value) and 'state kept' in str(exc)
            assert stepper.state == before and stepper.time == time
            continue
        assert is_number(value), f'{kind} accepted {value!r}'
        assert finite(stepper.state), stepper.state
        for quantity in (stepper.energy, stepper.angular_momentum, stepper.inertial_position):
            try:
                assert finite(quantity())
            except NonFiniteStateError as exc:
                assert 'overflow' in str(exc)
        assert finite(stepper.torque) and finite(stepper.omega_dot)


def test_regression_paper_coupling_without_rotary_inertia_is_not_a_zero_division():
    stepper = RealTimeStepper(RodParams(hub_inertia=0.0, eccentricity=0.0), coupling='paper')
    with pytest.raises(NonFiniteStateError, match='rotary inertia'):
        stepper.step_torque(1.0)
    assert stepper.time == 0.0 and stepper.state.omega == 0.0
    with pytest.raises(ValueError, match='rotary inertia'):
        EngineConfig(params=RodParams(hub_inertia=0.0, eccentricity=0.0), drive='torque',
                     coupling='paper')
    with pytest.raises(ValueError, match='rotary inertia'):    # was: divide-by-zero, NaN
        simulate(RodParams(hub_inertia=0.0, eccentricity=0.0), torque=1.0, t_end=0.1,
                 coupling='paper')


@props(40)
@given(anything(st.floats(1e-5, 1e-2)))
def test_the_stepper_step_is_a_positive_finite_number(dt):
    try:
        stepper = RealTimeStepper(RodParams(), dt=dt)
    except ValueError as exc:
        assert 'dt' in str(exc)
        return
    assert stepper.dt > 0 and finite(stepper.dt)


# -- engine ---------------------------------------------------------------------------

@st.composite
def engine_configs(draw):
    """Valid-or-not EngineConfig keyword arguments around the defaults."""
    kwargs = {}
    options = {
        'drive': st.sampled_from(['velocity', 'torque', 'velocity', 'position']),
        'coupling': st.sampled_from(['exact', 'paper']),
        'physics_rate': anything(st.floats(200.0, 5000.0)),
        'max_angular_acceleration': anything(st.floats(0.01, 2.0)),
        'max_omega': anything(st.floats(1.0, 50.0)),
        'max_torque': anything(st.floats(0.01, 10.0)),
        'deflection_limit': anything(st.floats(1e-3, 0.1)),
        'warn_fraction': anything(st.floats(0.1, 1.0)),
        'critical_margin': anything(st.floats(0.0, 0.5)),
        'setpoint_delay': anything(st.floats(0.02, 0.5)),
        'command_timeout': anything(st.floats(0.0, 1.0)),
    }
    for name, strategy in options.items():
        if draw(st.integers(0, 3)) == 0:
            kwargs[name] = draw(strategy)
    if draw(st.booleans()):
        try:
            kwargs['params'] = RodParams(**draw(rod_fields(sane_only=draw(st.booleans()))))
        except ValueError:
            pass
    if draw(st.integers(0, 3)) == 0:
        kwargs['initial'] = {draw(st.sampled_from(['u', 'v', 'du', 'omega'])):
                             draw(anything(st.floats(-1e-3, 1e-3)))}
    return kwargs


@props(300)
@given(engine_configs())
def test_engine_configs_are_refused_with_a_reason_or_work(kwargs):
    try:
        config = EngineConfig(**kwargs)
    except ValueError as exc:
        assert str(exc)
        return
    engine = SimulationEngine(config)
    assert finite(engine.state) and finite(engine.energy()) and finite(engine.frequencies())
    assert all(finite(v) for v in engine.critical_speeds.values())
    health = engine.health()
    if engine.deflection > config.deflection_limit:   # an alarm, not a refusal
        assert health.level == 2 and 'beyond the critical deflection' in health.message
    else:
        assert health.level in (0, 1)


def mostly(sane):
    """Usually a sane value, sometimes anything."""
    return st.one_of(sane, sane, sane, anything(sane))


COMMAND_TIMES = st.one_of(st.none(), st.floats(0.0, 0.3), EXTREME_FLOATS, WRONG_TYPES)
COMMAND_VALUES = {
    'omega': mostly(st.one_of(st.floats(-60.0, 60.0),
                              st.sampled_from([-50.0, -20.0, 20.0, 50.0]))),
    'torque': mostly(st.one_of(st.floats(-30.0, 30.0), st.sampled_from([-20.0, -5.0, 5.0,
                                                                         20.0]))),
}


@st.composite
def commands(draw):
    """(kind, value, at): steps to take, resets, and commands for the engine's drive
    (kind 'command', value {drive: value}) or, sometimes, for the other drive."""
    kind = draw(st.sampled_from(['advance'] * 3 + ['command'] * 3 + ['omega', 'torque',
                                                                        'reset']))
    if kind == 'advance':
        return kind, draw(st.one_of(st.integers(0, 400), st.sampled_from([300, 400]))), None
    if kind == 'reset':
        return kind, None, None
    at = draw(COMMAND_TIMES) if draw(st.integers(0, 3)) == 0 else None
    if kind == 'command':
        return kind, {'velocity': draw(COMMAND_VALUES['omega']),
                      'torque': draw(COMMAND_VALUES['torque'])}, at
    return kind, draw(COMMAND_VALUES[kind]), at


COMMANDS = st.lists(commands(), min_size=1, max_size=20)


@props(150)
@given(rod_fields(sane_only=True, ranges=LAB), st.sampled_from(['velocity', 'torque']),
       st.sampled_from(['exact', 'paper']), st.floats(0.05, 50.0), st.floats(2e-4, 0.05),
       st.floats(1.0, 50.0), COMMANDS, st.sampled_from([0.0, 0.0, 0.1, 0.25]))
def test_the_engine_state_stays_finite_or_it_halts_with_a_reason(fields, drive, coupling,
                                                                  accel, limit, max_omega,
                                                                  commands, timeout):
    """Any command sequence: accepted, or CommandRejected (counted, nothing changes); the
    state, energy, momentum, torque and frequencies stay finite; in velocity drive |w'|
    stays within max_angular_acceleration (command-timeout spin-downs included); a halt
    has a reason and refuses steps."""
    params = RodParams(**fields)
    if coupling == 'exact' and params.hub_inertia == 0:
        coupling = 'paper'
    rate = max(1000.0, 2.5 * fastest_rate(params, max_omega) / STEP_RESOLUTION)
    bound = MAX_DEFLECTION_RATIO * params.rod_length      # the default validity bound
    with np.errstate(all='ignore'):     # an acceleration bound that the rod can bear
        accel = min(accel, 0.5 * bound * params.stiffness_tangential / params.mass
                    / params.eccentricity)
    try:
        config = EngineConfig(params=params, drive=drive, coupling=coupling,
                              physics_rate=rate, max_angular_acceleration=accel,
                              deflection_limit=limit, max_omega=max_omega, max_torque=20.0,
                              command_timeout=timeout)
    except ValueError as exc:       # no rotary inertia for the torque drive
        assert 'rotary inertia' in str(exc), str(exc)
        return
    engine = SimulationEngine(config)
    for kind, value, at in commands:
        before, time, rejected = engine.state, engine.time, engine.rejected_commands
        if kind == 'command':
            kind, value = {'velocity': 'omega', 'torque': 'torque'}[drive], value[drive]
        if kind in ('omega', 'torque'):
            try:
                getattr(engine, f'command_{kind}')(value, at=at)
            except CommandRejected as exc:
                assert str(exc)
                assert engine.rejected_commands == rejected + 1
                assert engine.state == before and engine.time == time
        elif kind == 'advance':
            done = engine.advance(value)
            assert 0 <= done <= value
            assert (done == value) or engine.halted
            if drive == 'velocity':     # w' of the last step, to rounding of w / dt
                rounding = 4 * np.spacing(max_omega) / engine.dt
                assert abs(engine.omega_dot) <= config.max_angular_acceleration + rounding
        else:
            engine.reset()
        assert finite(engine.state), engine.state
        for x in (engine.energy(), engine.angular_momentum(), engine.torque,
                  engine.omega_dot, engine.frequencies(), engine.inertial_position()):
            assert finite(x)
        health = engine.health()
        event(f'halted: {engine.halted.split(" ")[0]}' if engine.halted else 'running')
        if engine.halted:
            assert health.level == ERROR and health.message == engine.halted
            assert re.search(r'beyond|non-finite', engine.halted)
            assert not engine.step()


@props(60)
@given(st.one_of(BAD_TIMES, CONTAINERS, st.floats(), st.integers(-5, 5)))
def test_engine_clock_arguments_are_validated(value):
    """advance_to / steps_until take a finite time (before: OverflowError for inf, a
    bare "cannot convert float NaN to integer" for nan); advance takes a whole number of
    steps (before: NaN meant zero steps, silently, and '3' a TypeError)."""
    engine = SimulationEngine()
    numeric = isinstance(value, (int, float)) and not isinstance(value, bool)
    for method in (engine.advance_to, engine.steps_until):
        if numeric and math.isfinite(value):
            if value <= 1.0:
                assert method(value) >= 0
        else:
            with pytest.raises(ValueError, match=r'\bt\b'):
                method(value)
    if isinstance(value, int) and not isinstance(value, bool):
        assert engine.advance(value) == max(0, value)
    else:
        with pytest.raises(ValueError, match='steps'):
            engine.advance(value)
    with pytest.raises(ValueError, match='steps'):
        engine.steps_until(HUGE)           # (HUGE - time) / dt overflows


def test_regression_a_bad_command_time_is_a_rejected_command():
    engine = SimulationEngine()
    with pytest.raises(CommandRejected, match='command time'):
        engine.command_omega(1.0, at=math.nan)
    assert engine.rejected_commands == 1 and engine.setpoint == 0.0
    with pytest.raises(ValueError, match='t must be finite'):
        engine.advance_to(math.inf)


# -- setpoint shaper ------------------------------------------------------------------

SETPOINTS = st.one_of(st.floats(-100.0, 100.0), st.floats(-100.0, 100.0),
                      st.floats(-1e6, 1e6), st.sampled_from([0.0, TINY, -TINY]))
GAPS = st.one_of(st.sampled_from([0.0, 0.001, 0.01, 0.01, 0.01, 0.02, 0.3, 1.0]),
                 st.floats(0.0, 0.05), st.floats(0.0, 10.0), st.sampled_from([TINY, 1e-300]))


@props(200)
@given(st.floats(1e-3, 1e3), st.floats(1e-3, 1.0), st.floats(-10.0, 10.0),
       st.floats(0.0, 1e6), st.lists(st.tuples(SETPOINTS, GAPS), min_size=1, max_size=60))
def test_the_shaper_gives_a_continuous_w_within_the_acceleration_limit(limit, delay, w0, t0,
                                                                       stream):
    """Any stream of finite setpoints at non-decreasing times: w(t) is finite, continuous
    (Lipschitz with the limit, to rounding of w) and |w'| <= max_angular_acceleration
    (before: 69.0000001 for 69 rad/s^2 at t = 2.6e5 s)."""
    shaper = OmegaSetpointShaper(limit, delay=delay, omega=w0, time=t0)
    t, ramps = t0, []
    for setpoint, gap in stream:
        t += gap
        ramps.append(shaper.command(setpoint, t))
    knots = sorted({k for r in ramps for k in r.times if math.isfinite(k)})
    end = max(knots[-1], t) + 1.0
    grid = np.union1d(np.linspace(t0, end, 2001), [k for k in knots if k <= end])
    w = np.array([shaper.omega(x) for x in grid])
    wd = np.array([shaper.omega_dot(x) for x in grid])
    assert finite(w) and finite(wd)
    scale = max(1.0, float(np.max(np.abs(w))))
    assert np.max(np.abs(wd)) <= limit     # exactly: knots are placed after rounding
    jumps = np.abs(np.diff(w)) - limit * np.diff(grid) * (1 + 1e-9)
    assert np.max(jumps) <= 1e-9 * scale


def test_regression_shaper_extremes():
    # intervals below the time's rounding: equal due times gave ZeroDivisionError, and
    # max_stall / interval = 5e299 path knots an unclear numpy 'Maximum allowed size'
    shaper = OmegaSetpointShaper(1.0, min_interval=1e-300, nominal_interval=1e-300)
    t = 0.0
    for k in range(30):
        shaper.command(1e9 * (k % 2), t)
        t += 1e-300
    assert finite([shaper.omega(t + x) for x in (0.0, 0.1, 1.0, 1e3)])
    # |w| near the float range: w1 - w0 overflowed to inf (then inf x 0 = NaN)
    with pytest.raises(ValueError, match='setpoint must be within'):
        shaper.command(1e308, t)
    with pytest.raises(ValueError, match='max_stall'):
        OmegaSetpointShaper(1e308, max_stall=10.0)
    # at t ~ 2.6e5 s the rounding of the ramp's end made |w'| exceed the limit by 4e-9
    shaper = OmegaSetpointShaper(69.0, delay=1.0, time=262143.0)
    shaper.command(0.0, 262143.0)
    ramp = shaper.command(1.0, 262143.0)
    assert abs(ramp.omega_dot(ramp.start)) <= 69.0
    with pytest.raises(ValueError, match='time'):
        shaper.omega(math.nan)


@props(150)
@given(st.lists(st.tuples(anything(st.floats(-10.0, 10.0)),
                          anything(st.floats(0.0, 10.0))), min_size=1, max_size=12))
def test_bad_setpoints_and_times_are_a_value_error_that_keeps_the_shaper(commands):
    """Bad setpoint (not a finite number), bad time (not finite, or before the previous
    one): ValueError, and the shaped w(t) is unchanged."""
    shaper = OmegaSetpointShaper(2.0)
    probe = np.linspace(0.0, 12.0, 49)
    for setpoint, t in commands:
        before = [shaper.omega(x) for x in probe]
        try:
            shaper.command(setpoint, t)
        except ValueError as exc:
            assert re.search(r'setpoint|time', str(exc)), str(exc)
            assert [shaper.omega(x) for x in probe] == before
        assert finite([shaper.omega(x) for x in probe])


@props(60)
@given(st.sampled_from(['max_angular_acceleration', 'delay', 'nominal_interval', 'max_stall',
                        'min_interval', 'max_interval', 'omega', 'time']),
       st.one_of(EXTREME_FLOATS, WRONG_TYPES))
def test_the_shaper_configuration_is_validated(name, value):
    kwargs = {'max_angular_acceleration': 1.0, name: value}
    try:
        shaper = OmegaSetpointShaper(**kwargs)
    except ValueError as exc:
        assert name in str(exc) or 'interval' in str(exc), str(exc)
        return
    shaper.command(1.0, shaper.last_command_time + 1.0)
    assert finite([shaper.omega(shaper.last_command_time + x) for x in (0.0, 1.0, 1e3)])


# -- whirl estimator ------------------------------------------------------------------

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
                                        'max_gap']),
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


# -- constant-rotation analysis, critical speed, simulate ------------------------------

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


@props(100)
@given(anything(st.floats(0.01, 1.0)), anything(st.floats(1e-3, 0.01)))
def test_time_grid_is_a_value_error_or_finite(t_end, dt):
    """A grid 0, dt, ..., t_end, or a ValueError naming t_end or dt."""
    try:
        t = time_grid(t_end, dt)
    except ValueError as exc:
        assert re.search(r't_end|dt', str(exc)), str(exc)
        return
    assert finite(t) and t[0] == 0.0 and t[-1] == t_end and np.all(np.diff(t) > 0)


def test_regression_time_grid_whose_step_count_overflows():
    # t_end / dt = inf: math.ceil raised OverflowError
    with pytest.raises(ValueError, match='steps exceeds'):
        time_grid(1e300, 1e-300)
    with pytest.raises(ValueError, match='steps exceeds'):
        simulate(RodParams(), Eq26Profile(), 1e300, dt=1e-300)


@props(60)
@given(rod_fields(sane_only=True, ranges=LAB), st.sampled_from(['exact', 'paper']),
       anything(st.floats(-1.0, 1.0)),
       st.dictionaries(st.sampled_from(['u', 'v', 'du', 'dv', 'theta', 'omega']),
                       anything(st.floats(-1e-3, 1e-3)), max_size=2))
def test_offline_torque_runs_are_finite_or_a_clear_error(fields, coupling, torque, initial):
    """simulate(torque=Q, initial=...): ValueError for bad input (incl. no rotary
    inertia), NonFiniteStateError for a run that overflows, else finite histories."""
    params = RodParams(**fields)
    try:
        run = simulate(params, torque=torque, t_end=0.05, dt=1e-3, coupling=coupling,
                       initial=initial)
    except ValueError as exc:
        event('refused')
        assert str(exc)
        return
    except NonFiniteStateError as exc:
        event('overflow')
        assert 'non-finite' in str(exc)
        return
    event('finite')
    assert is_number(torque) and all(is_number(x) for x in initial.values())
    for name in ('u', 'v', 'du', 'dv', 'theta', 'omega', 'omega_dot', 'torque', 'x', 'y'):
        assert finite(getattr(run, name)), name


@props(30)
@given(rod_fields(sane_only=True), profiles(sane_only=True))
def test_short_offline_runs_are_finite_or_refused(fields, spec):
    cls, kwargs = spec
    params = RodParams(**fields)
    try:
        run = simulate(params, cls(**kwargs), 0.2, dt=5e-3)
    except NonFiniteStateError:
        return
    for name in ('u', 'v', 'du', 'dv', 'theta', 'omega', 'omega_dot', 'torque', 'x', 'y'):
        assert finite(getattr(run, name)), name
