"""The integrators against exact solutions, a tight reference and the paper's facts."""

import math
import re

import numpy as np
import pytest
from hypothesis import event, given
from hypothesis import strategies as st
from properties import (  # the shared settings and strategies of the property tests
    LAB,
    anything,
    finite,
    is_number,
    profiles,
    props,
    rod_fields,
)
from reference import (
    R0,
    W0,
    eq26,
    impulsive_start,
    reference_run,
    step_start,
)

from rotrod_core import (
    ConstantProfile,
    Eq26Profile,
    RealTimeStepper,
    RodParams,
    StepProfile,
    simulate,
)
from rotrod_core.numerics.checks import NonFiniteStateError
from rotrod_core.offline.simulate import time_grid


@pytest.fixture(scope='module')
def eq26_run():
    return simulate(RodParams(), Eq26Profile(), 40.0, dt=1e-3)


def test_step_start_matches_eq29():
    w = 2.0
    run = simulate(RodParams(), ConstantProfile(w), 20.0, dt=1e-3)
    z = step_start(run.t, w)
    assert np.max(np.abs(run.u + 1j * run.v - z)) < 1e-12


def test_impulsive_start_matches_closed_form():
    w, ts = 2.0, 1.0
    run = simulate(RodParams(), StepProfile(w, t_step=ts), 11.0, dt=1e-3)
    before = run.t < ts
    assert np.all(run.u[before] == 0) and np.all(run.v[before] == 0)
    after = run.t >= ts
    z = impulsive_start(run.t[after] - ts, w)
    assert np.max(np.abs(run.u[after] + 1j * run.v[after] - z)) < 1e-12
    # the jump itself: relative velocity -w x r0 right at the step
    k = np.searchsorted(run.t, ts)
    assert run.du[k] == pytest.approx(0.0, abs=1e-15)
    assert run.dv[k] == pytest.approx(-w * R0, rel=1e-12)


def test_eq26_run_matches_tight_reference(eq26_run):
    """The issue's accuracy target: within 1e-9 m of DOP853 at rtol 1e-12."""
    w = lambda t: eq26(t)[0]  # noqa: E731
    wd = lambda t: eq26(t)[1]  # noqa: E731
    u, v = reference_run(w, wd, eq26_run.t)
    assert np.max(np.abs(eq26_run.u - u)) < 1e-9
    assert np.max(np.abs(eq26_run.v - v)) < 1e-9


def test_velocity_drive_at_20ms_steps_stays_within_1e10(eq26_run):
    coarse = simulate(RodParams(), Eq26Profile(), 40.0, dt=0.02)
    idx = np.searchsorted(eq26_run.t, coarse.t - 1e-9)
    assert np.max(np.abs(coarse.u - eq26_run.u[idx])) < 1e-10
    assert np.max(np.abs(coarse.v - eq26_run.v[idx])) < 1e-10


def test_paper_facts_for_the_eq26_run(eq26_run):
    r = eq26_run
    up = r.window(0, 15)
    hold = r.window(15, 20)
    down = r.window(20, 35)
    rest = r.window(35, 40)
    # spin-up: out radially, back tangentially; radial ~10x tangential
    assert up.u.max() == pytest.approx(2.79e-3, rel=0.01)
    assert up.v.min() == pytest.approx(-0.19e-3, rel=0.03)
    assert up.v.max() < 0.01 * abs(up.v.min())
    assert 10 <= up.u.max() / abs(up.v.min()) <= 20
    # hold at 2 rad/s: around the static deflection 2.792 mm, tangential oscillation tiny
    u_s = 0.3 * 4 * R0 / (0.3 * W0**2 - 0.3 * 4)
    assert u_s == pytest.approx(2.792e-3, rel=1e-3)
    assert hold.u.mean() == pytest.approx(u_s, rel=1e-3)
    assert np.ptp(hold.v) < 1e-3 * hold.u.mean()
    # spin-down: radial falls, tangential forward (v > 0) up to ~0.19 mm
    assert down.v.max() == pytest.approx(0.19e-3, rel=0.03)
    assert down.v.min() > -0.01 * down.v.max()
    assert down.u[-1] < 0.01 * down.u.max()
    # rest: a small free (elliptical) vibration, sub-micrometre
    assert 0 < np.max(rest.deflection) < 1e-6


def test_hub_torque_in_velocity_drive_is_the_rate_of_angular_momentum(eq26_run):
    r = eq26_run
    dLdt = np.gradient(r.angular_momentum(), r.t)
    inner = slice(5, -5)
    assert np.max(np.abs(dLdt[inner] - r.torque[inner])) < 1e-6 * np.max(np.abs(r.torque))


@pytest.mark.parametrize('runner', ['simulate', 'stepper'])
def test_exact_coupling_conserves_energy_and_angular_momentum(runner):
    p = RodParams(hub_inertia=0.01)
    init = {'omega': 2.0, 'u': 1e-3}
    if runner == 'simulate':
        r = simulate(p, torque=0.0, t_end=40.0, initial=init)
        E, L = r.energy(), r.angular_momentum()
    else:
        st = RealTimeStepper(p, initial=init)
        E, L = [st.energy()], [st.angular_momentum()]
        for _ in range(40000):
            st.step_torque(0.0)
            E.append(st.energy())
            L.append(st.angular_momentum())
        E, L = np.array(E), np.array(L)
    assert np.max(np.abs(E - E[0])) / E[0] < 1e-9
    assert np.max(np.abs(L - L[0])) / L[0] < 1e-9


def test_paper_coupling_drifts_as_model_md_measures():
    r = simulate(RodParams(hub_inertia=0.01), torque=0.0, t_end=40.0, coupling='paper',
                 initial={'omega': 2.0, 'u': 1e-3})
    E, L = r.energy(), r.angular_momentum()
    assert np.max(np.abs(E - E[0])) / E[0] == pytest.approx(0.043, abs=0.002)
    assert np.max(np.abs(L - L[0])) / L[0] == pytest.approx(0.022, abs=0.001)


@pytest.mark.parametrize('zeta', [0.0, 0.03])
def test_energy_rate_under_torque(zeta):
    """dE/dt = Q w - c1 u'^2 - c2 v'^2 and dL/dt = Q, integrated over the run."""
    p = RodParams(damping_ratio=zeta)
    Q = lambda t: 0.02 * math.sin(0.5 * t) + 0.01  # noqa: E731
    r = simulate(p, torque=Q, t_end=20.0, initial={'omega': 0.5})
    power = r.torque * r.omega - p.damping_radial * r.du**2 - p.damping_tangential * r.dv**2
    from scipy.integrate import cumulative_simpson
    E, L = r.energy(), r.angular_momentum()
    work = cumulative_simpson(power, x=r.t, initial=0)
    impulse = cumulative_simpson(r.torque, x=r.t, initial=0)
    assert np.max(np.abs(E - E[0] - work)) < 1e-9 * np.max(E)
    assert np.max(np.abs(L - L[0] - impulse)) < 1e-9 * np.max(L)
    assert r.omega[-1] > 0.5   # the net positive torque spun the hub up


@pytest.mark.parametrize('kwargs, match', [
    ({'profile': Eq26Profile(), 't_end': -1}, 't_end'),
    ({'profile': Eq26Profile(), 't_end': 1.0, 'dt': 0}, 'dt'),
    ({'profile': Eq26Profile(), 't_end': math.nan}, 't_end'),
    ({'profile': Eq26Profile(), 't_end': 1.0, 'dt': 2.0}, 'dt'),
    ({'t_end': 1.0}, 'exactly one'),
    ({'profile': Eq26Profile(), 'torque': 1.0, 't_end': 1.0}, 'exactly one'),
    ({'torque': math.nan, 't_end': 1.0}, 'torque'),
    ({'torque': lambda t: math.inf, 't_end': 1.0}, 'torque'),
    ({'profile': Eq26Profile(), 't_end': 1.0, 'coupling': 'approx'}, 'coupling'),
    ({'profile': Eq26Profile(), 't_end': 1.0, 'initial': {'omega': 1.0}}, 'omega'),
    ({'profile': Eq26Profile(), 't_end': 1.0, 'initial': {'w': 1.0}}, 'unknown'),
    ({'torque': 0.0, 't_end': 1.0, 'initial': {'u': math.nan}}, 'finite'),
])
def test_simulate_rejects_bad_arguments(kwargs, match):
    with pytest.raises(ValueError, match=match):
        simulate(RodParams(), **kwargs)


def test_exact_coupling_needs_hub_inertia():
    with pytest.raises(ValueError, match='hub_inertia'):
        simulate(RodParams(hub_inertia=0.0), torque=0.0, t_end=1.0)
    r = simulate(RodParams(hub_inertia=0.0), torque=0.0, t_end=1.0, coupling='paper',
                 initial={'omega': 1.0})
    assert np.all(np.isfinite(r.omega))


def test_inertial_position_moves_with_the_absolute_velocity(eq26_run):
    """d/dt (x, y) equals the absolute velocity (u' - w v, v' + w (r0 + u)) turned by theta."""
    r = eq26_run
    vx_rot, vy_rot = r.du - r.omega * r.v, r.dv + r.omega * (R0 + r.u)
    c, s = np.cos(r.theta), np.sin(r.theta)
    vx, vy = vx_rot * c - vy_rot * s, vx_rot * s + vy_rot * c
    inner = slice(1, -1)
    assert np.allclose(np.gradient(r.x, r.t)[inner], vx[inner], atol=1e-6)
    assert np.allclose(np.gradient(r.y, r.t)[inner], vy[inner], atol=1e-6)
    assert np.allclose(np.hypot(r.x, r.y), np.hypot(R0 + r.u, r.v), atol=1e-15)


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
