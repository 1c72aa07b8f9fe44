"""Offline simulation of one system: velocity drive (Magnus) or torque drive (RK4).

Velocity drive: the deflection equations are linear with time-varying coefficients
that depend on w(t) only. Each step applies the fourth-order Magnus propagator
(two Gauss points, one commutator) of the augmented 5x5 system of
:mod:`rotrod_core.model.propagation` (the one kernel), computed for all steps at
once; its error depends on how fast w changes, not on the vibration frequency, so a
1 ms step is accurate to ~1e-14 m on the paper's run. The steps are chained by the
kernel's blocked product (sequential over blocks, vectorized within).

Torque drive: the coupled equations are nonlinear; classical RK4 at fixed step.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np

import rotrod_core.model.equations as model
import rotrod_core.model.propagation as propagation
from rotrod_core.command.profiles import Profile
from rotrod_core.model.equations import (
    Coefficients,
    State,
    check_coupling,
    check_rotary_inertia,
    make_state,
)
from rotrod_core.model.params import RodParams
from rotrod_core.model.propagation import GAUSS2, affine_chain
from rotrod_core.numerics.checks import NonFiniteStateError
from rotrod_core.numerics.expm import expm_batch
from rotrod_core.numerics.rk4 import rk4_step
from rotrod_core.offline.result import SimulationResult

MAX_STEPS = 50_000_000
_CHUNK = 32768


def time_grid(t_end, dt) -> np.ndarray:
    """Sample times 0, dt, 2 dt, ..., ending exactly at ``t_end`` (last step may be short)."""
    for name, value in (('t_end', t_end), ('dt', dt)):
        if isinstance(value, bool) or not isinstance(value, (int, float, np.integer,
                                                             np.floating)):
            raise ValueError(f'{name} must be a number, got {value!r}')
        try:
            finite = math.isfinite(value)
        except OverflowError:           # an int beyond the float range
            finite = False
        if not finite or value <= 0:
            raise ValueError(f'{name} must be a finite number > 0, got {value!r}')
    if dt > t_end:
        raise ValueError(f'dt ({dt} s) must not exceed t_end ({t_end} s)')
    steps = t_end / dt - 1e-9
    if steps > MAX_STEPS:       # also inf (1e300 / 1e-300), which math.ceil refuses
        raise ValueError(f't_end/dt = {steps:.4g} steps exceeds the limit of {MAX_STEPS}')
    n = math.ceil(steps)
    if n > MAX_STEPS:
        raise ValueError(f't_end/dt = {n} steps exceeds the limit of {MAX_STEPS}')
    t = np.arange(n + 1, dtype=float) * dt
    t[-1] = t_end
    return t


def magnus_propagators(co: Coefficients, profile: Profile, nodes: np.ndarray) -> np.ndarray:
    """Fourth-order Magnus step matrices exp(Omega_k) between consecutive ``nodes``."""
    h = np.diff(nodes)
    t1 = nodes[:-1] + GAUSS2[0] * h
    t2 = nodes[:-1] + GAUSS2[1] * h
    A1 = propagation.system_matrix(co, profile.omega(t1), profile.omega_dot(t1))
    A2 = propagation.system_matrix(co, profile.omega(t2), profile.omega_dot(t2))
    return expm_batch(propagation.magnus4(h, A1, A2))


def _velocity_drive(params, co, profile, t, coupling, initial):
    if not isinstance(profile, Profile):
        raise ValueError(f'profile must be a rotrod_core Profile, got {profile!r}')
    init = dict(initial or {})
    if 'omega' in init:
        raise ValueError('in velocity drive omega comes from the profile; do not give it '
                         'in initial')
    s0 = make_state(init)
    jumps = [j for j in profile.jumps() if 0 < j[0] <= t[-1]]
    nodes = np.union1d(t, [j[0] for j in jumps])
    out_index = np.searchsorted(nodes, t)
    x = np.array([s0.u, s0.v, s0.du, s0.dv, 1.0])
    jump_at = {int(np.searchsorted(nodes, tj)): after - before for tj, before, after in jumps}
    pieces = [x[None, :]]
    for start in range(0, len(nodes) - 1, _CHUNK):
        stop = min(start + _CHUNK, len(nodes) - 1)
        phi = magnus_propagators(co, profile, nodes[start:stop + 1])
        for node, dw in jump_at.items():
            if start < node <= stop:
                phi[node - start - 1] = model.omega_jump_matrix(co, dw) @ phi[node - start - 1]
        chained = affine_chain(phi, x)
        pieces.append(chained[1:])
        x = chained[-1]
    X = np.concatenate(pieces)[out_index]
    if not np.all(np.isfinite(X)):
        raise NonFiniteStateError('the velocity-drive run produced non-finite values')
    u, v, du, dv = X[:, 0], X[:, 1], X[:, 2], X[:, 3]
    omega, omega_dot = profile.omega(t), profile.omega_dot(t)
    theta = s0.theta + profile.angle(t)
    torque = model.hub_torque(co, State(u, v, du, dv, theta, omega), omega_dot, coupling)
    return u, v, du, dv, theta, omega, omega_dot, torque


def _torque_function(torque) -> Callable[[float], float]:
    if callable(torque):
        def q(t):
            returned = torque(t)
            try:
                value = float(returned)
            except (TypeError, ValueError, OverflowError):
                raise ValueError(f'torque({t}) returned {returned!r}; torque must be a '
                                 'finite number') from None
            if not math.isfinite(value):
                raise ValueError(f'torque({t}) returned {value!r}; torque must be finite')
            return value
        return q
    if isinstance(torque, bool):
        raise ValueError(f'torque must be a number or a function of time, got {torque!r}')
    try:
        value = float(torque)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(
            f'torque must be a number or a function of time, got {torque!r}') from None
    if not math.isfinite(value):
        raise ValueError(f'torque must be finite, got {torque!r}')
    return lambda t: value


def _torque_drive(params, co, torque, t, coupling, initial):
    q = _torque_function(torque)
    state = make_state(initial, scalar=True)
    check_rotary_inertia(params, coupling, state)
    rates = lambda y, qq: model.torque_drive_rates(co, y, qq, coupling)  # noqa: E731
    out = np.empty((len(t), 6))
    out[0] = state
    qs = np.empty(len(t))
    qs[0] = q(t[0])
    y = tuple(state)
    times = t.tolist()      # Python floats: overflow gives inf, not a RuntimeWarning
    for k in range(len(t) - 1):
        h = times[k + 1] - times[k]
        q_end = q(times[k + 1])
        try:
            y = rk4_step(rates, y, h, float(qs[k]), q(times[k] + 0.5 * h), q_end)
        except ZeroDivisionError:       # paper coupling, J = 0: the mass on the axis
            raise NonFiniteStateError(f'torque-drive run reached a state without rotary '
                                      f'inertia at t={t[k+1]} s') from None
        if not all(math.isfinite(c) for c in y):
            raise NonFiniteStateError(f'torque-drive run became non-finite at t={t[k+1]} s')
        out[k + 1] = y
        qs[k + 1] = q_end
    u, v, du, dv, theta, omega = out.T
    omega_dot = model.hub_angular_acceleration(co, State(u, v, du, dv, theta, omega), qs,
                                               coupling)
    return u, v, du, dv, theta, omega, omega_dot, qs


def simulate(params: RodParams, profile: Profile | None = None, t_end: float | None = None,
             dt: float = 1e-3, *, torque=None, coupling: str = 'exact',
             initial: dict | None = None) -> SimulationResult:
    """Simulate one system offline and return its time histories.

    Velocity drive: ``simulate(params, profile, t_end, dt=...)``: the hub follows the
    profile's w(t); ``torque`` in the result is what the drive must supply.
    Torque drive: ``simulate(params, torque=Q, t_end=..., coupling=..., initial=...)``
    with Q in N m, a number or a function of time; the rotation is free.

    Args:
        params: one system (for many, see :func:`rotrod_core.simulate_batch`).
        profile: angular-velocity profile (velocity drive).
        t_end: duration, s.
        dt: sample interval and integration step, s.
        torque: hub torque (torque drive), N m or callable t -> N m.
        coupling: ``'exact'`` (default) or ``'paper'`` (Eq. 23 + J w').
        initial: initial state by name: u, v (m), du, dv (m/s), theta (rad), and in
            torque drive omega (rad/s). Velocities are relative to the rotating frame.
    """
    if not isinstance(params, RodParams):
        raise ValueError(f'params must be RodParams, got {type(params).__name__}')
    if params.is_batch:
        raise ValueError('simulate runs one system; use simulate_batch for arrays of params')
    if (profile is None) == (torque is None):
        raise ValueError('give exactly one of profile (velocity drive) or torque '
                         '(torque drive)')
    if t_end is None:
        raise ValueError('t_end is required')
    if torque is not None:
        check_coupling(params, coupling)        # the exact torque drive also needs J > 0
    else:
        model.coupling_name(coupling)
    t = time_grid(t_end, dt)
    co = Coefficients.from_params(params)
    if profile is not None:
        u, v, du, dv, theta, omega, omega_dot, q = _velocity_drive(
            params, co, profile, t, coupling, initial)
        drive = 'velocity'
    else:
        u, v, du, dv, theta, omega, omega_dot, q = _torque_drive(params, co, torque, t,
                                                                 coupling, initial)
        drive = 'torque'
    x, y = model.inertial_position(co, u, v, theta)
    return SimulationResult(t=t, u=u, v=v, du=du, dv=dv, theta=theta, omega=omega,
                            omega_dot=omega_dot, torque=q, x=x, y=y, params=params,
                            drive=drive, coupling=coupling)
