"""The real-time stepper against Eq. 29, the jump rule and bad input."""

import math

import numpy as np
import pytest
from reference import (
    R0,
    W0,
    rk4_phase_bound,
    step_start,
)

from rotrod_core import (
    RealTimeStepper,
    RodParams,
)
from rotrod_core.model.equations import Coefficients, State, omega_jump


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
