"""The real-time stepper against Eq. 29, the jump rule and bad input."""

import math

import numpy as np
import pytest
from hypothesis import event, given
from hypothesis import strategies as st
from properties import (  # the shared settings and strategies of the property tests
    anything,
    finite,
    is_number,
    props,
    rod_fields,
)
from reference import (
    R0,
    W0,
    rk4_phase_bound,
    step_start,
)

from rotrod_core import (
    RealTimeStepper,
    RodParams,
    simulate,
)
from rotrod_core.live.engine import (
    EngineConfig,
)
from rotrod_core.model.equations import Coefficients, State, omega_jump
from rotrod_core.numerics.checks import NonFiniteStateError


def test_stepper_matches_eq29():
    w, dt = 2.0, 1e-3
    st = RealTimeStepper(RodParams(), dt=dt, initial={'omega': w})
    zs = []
    for _ in range(5000):
        s = st.step_velocity(0.0)
        zs.append(s.u + 1j * s.v)
    t = dt * np.arange(1, 5001)
    z = step_start(t, w)
    bound = rk4_phase_bound(dt, W0 + w, t[-1], np.max(np.abs(z)))
    assert np.max(np.abs(np.array(zs) - z)) < bound


def test_stepper_jump_keeps_absolute_velocity():
    p = RodParams()
    co = Coefficients.from_params(p)
    s = State(1e-3, -2e-4, 3e-3, 1e-3, 0.4, 1.0)
    n = omega_jump(co, s, 2.5)

    def absolute(s):
        return (s.du - s.omega * s.v, s.dv + s.omega * (R0 + s.u))

    assert absolute(n) == pytest.approx(absolute(s), abs=1e-15)
    st = RealTimeStepper(p, initial=s._asdict())
    assert tuple(st.jump_omega(2.5)) == pytest.approx(tuple(n))


def test_non_finite_step_keeps_the_state():
    st = RealTimeStepper(RodParams())
    st.step_velocity(1.0)
    before = st.state
    for bad in (math.nan, math.inf, 'x'):
        with pytest.raises(ValueError):
            st.step_velocity(bad)
        with pytest.raises(ValueError):
            st.step_torque(bad)
        with pytest.raises(ValueError):
            st.jump_omega(bad)
    assert st.state == before
    from rotrod_core import NonFiniteStateError
    st.jump_omega(1e200)
    kept = st.state
    with pytest.raises(NonFiniteStateError):
        st.step_velocity(0.0)
    assert st.state == kept


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
