"""Equations of motion of the tip mass on a rod on a rotating hub (rotating frame).

The single source of truth for the dynamics (see docs/model.md). State
``(u, v, du, dv, theta, omega)``: deflection u (radial, e1) and v (tangential, e2) of
the mass in m, their rates in m/s, hub angle theta in rad and angular velocity omega
in rad/s. Every function is plain arithmetic, so it accepts Python floats (fast, for
the real-time stepper) and numpy arrays (batches, vectorized over time) alike.

Deflection equations (Eqs. 16, 17, generalised to k1 != k2 and rotating damping)::

    u'' = 2 w v' + (w^2 - k1/m) u + w^2 r0 + w' v - (c1/m) u'
    v'' = -2 w u' + (w^2 - k2/m) v - w' (r0 + u) - (c2/m) v'

Hub (torque) equation, exact Lagrangian coupling, after eliminating u'' and v''::

    J w' = Q + tau_rod,   tau_rod = v (k2 (r0 + u) - k1 u) + c2 (r0 + u) v' - c1 v u'

tau_rod is the moment about the axis that the rod exerts on the hub. The paper's
Eq. 23 (plus J w') instead reads ``(J + m rho^2) w' = Q - 2 m w ((r0 + u) u' + v v')``.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from .checks import finite_number
from .params import RodParams

COUPLINGS = ('exact', 'paper')


class State(NamedTuple):
    """Full state of the system (SI units; arrays allowed for batches)."""

    u: float
    """Radial deflection of the mass, m (rotating frame, e1)."""
    v: float
    """Tangential deflection of the mass, m (rotating frame, e2)."""
    du: float
    """Radial deflection rate u', m/s."""
    dv: float
    """Tangential deflection rate v', m/s."""
    theta: float
    """Hub angle, rad."""
    omega: float
    """Hub angular velocity, rad/s."""


STATE_FIELDS = State._fields


def make_state(initial: dict | None = None, *, scalar: bool = False, **defaults) -> State:
    """Build a :class:`State` from a mapping of named initial values (others zero).

    Values may be arrays (a batch) unless ``scalar``. Raises ValueError for an unknown
    name or a value that is not a finite number (booleans and strings included).
    """
    values = dict.fromkeys(STATE_FIELDS, 0.0)
    values.update(defaults)
    for name, value in (initial or {}).items():
        if name not in values:
            raise ValueError(f'unknown initial state {name!r}; expected one of {STATE_FIELDS}')
        values[name] = value
    for name, value in values.items():
        if scalar or isinstance(value, bool):
            values[name] = finite_number(f'initial {name}', value)
            continue
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError, OverflowError):
            raise ValueError(f'initial {name} must be a number, got {value!r}') from None
        if not np.all(np.isfinite(arr)):
            raise ValueError(f'initial {name} must be finite, got {value!r}')
        values[name] = float(arr) if arr.ndim == 0 else arr
    return State(**values)


@dataclass(frozen=True)
class Coefficients:
    """Per-unit-mass coefficients of the equations, taken from :class:`RodParams`.

    Plain floats for a single system, arrays for a batch.
    """

    mass: float
    """m, kg."""
    eccentricity: float
    """r0, m."""
    hub_inertia: float
    """J, kg m^2."""
    k1: float
    """Radial tip stiffness, N/m."""
    k2: float
    """Tangential tip stiffness, N/m."""
    c1: float
    """Radial damping coefficient, N s/m."""
    c2: float
    """Tangential damping coefficient, N s/m."""
    w1sq: float
    """k1/m, 1/s^2."""
    w2sq: float
    """k2/m, 1/s^2."""
    g1: float
    """c1/m, 1/s."""
    g2: float
    """c2/m, 1/s."""

    @classmethod
    def from_params(cls, params: RodParams) -> Coefficients:
        """Evaluate the coefficients of ``params`` (floats, or arrays for a batch)."""
        def num(x):
            arr = np.asarray(x, dtype=float)
            return float(arr) if arr.ndim == 0 else arr

        m = num(params.mass)
        k1, k2 = num(params.stiffness_radial), num(params.stiffness_tangential)
        c1, c2 = num(params.damping_radial), num(params.damping_tangential)
        return cls(mass=m, eccentricity=num(params.eccentricity),
                   hub_inertia=num(params.hub_inertia), k1=k1, k2=k2, c1=c1, c2=c2,
                   w1sq=k1 / m, w2sq=k2 / m, g1=c1 / m, g2=c2 / m)


def deflection_accelerations(co: Coefficients, u, v, du, dv, omega, omega_dot):
    """Accelerations (u'', v'') of the mass in the rotating frame, m/s^2.

    Eqs. 16 and 17 of the paper (with the sign of the tangential initial force as
    derived in docs/model.md), with radial/tangential stiffness k1, k2 and rotating damping.
    ``omega`` and ``omega_dot`` (rad/s, rad/s^2) are the hub's at this instant.
    """
    w2 = omega * omega
    ddu = 2.0 * omega * dv + (w2 - co.w1sq) * u + w2 * co.eccentricity + omega_dot * v - co.g1 * du
    ddv = -2.0 * omega * du + (w2 - co.w2sq) * v - omega_dot * (co.eccentricity + u) - co.g2 * dv
    return ddu, ddv


def rod_torque_on_hub(co: Coefficients, u, v, du, dv):
    """Moment about the axis that the rod exerts on the hub, N m (exact coupling).

    The tip force of the bent rod (k1 u + c1 u', k2 v + c2 v') acts on the rod at the
    mass, at (r0 + u, v) from the axis, and reaches the hub through the massless rod.
    """
    x = co.eccentricity + u
    return v * (co.k2 * x - co.k1 * u) + co.c2 * x * dv - co.c1 * v * du


def hub_angular_acceleration(co: Coefficients, state, torque, coupling: str = 'exact'):
    """Hub angular acceleration w' (rad/s^2) under the hub torque ``torque`` (N m).

    ``coupling='exact'``: the Lagrangian torque equation, J w' = Q + tau_rod; needs
    J > 0 (the 3x3 system's determinant is m^2 J). ``coupling='paper'``: Eq. 23 as
    printed plus the hub's J w', (J + m rho^2) w' = Q - 2 m w ((r0 + u) u' + v v').
    """
    u, v, du, dv, _, omega = state
    if coupling == 'exact':
        return (torque + rod_torque_on_hub(co, u, v, du, dv)) / co.hub_inertia
    if coupling == 'paper':
        x = co.eccentricity + u
        inertia = co.hub_inertia + co.mass * (x * x + v * v)
        return (torque - 2.0 * co.mass * omega * (x * du + v * dv)) / inertia
    raise ValueError(f'coupling must be one of {COUPLINGS}, got {coupling!r}')


def hub_torque(co: Coefficients, state, omega_dot, coupling: str = 'exact'):
    """Hub torque Q (N m) that imposes the angular acceleration ``omega_dot`` (velocity drive).

    The inverse of :func:`hub_angular_acceleration` at the same state.
    """
    u, v, du, dv, _, omega = state
    if coupling == 'exact':
        return co.hub_inertia * omega_dot - rod_torque_on_hub(co, u, v, du, dv)
    if coupling == 'paper':
        x = co.eccentricity + u
        return ((co.hub_inertia + co.mass * (x * x + v * v)) * omega_dot
                + 2.0 * co.mass * omega * (x * du + v * dv))
    raise ValueError(f'coupling must be one of {COUPLINGS}, got {coupling!r}')


def velocity_drive_rates(co: Coefficients, state, omega_dot):
    """Time derivative of the state when the hub's angular acceleration is prescribed."""
    u, v, du, dv, _, omega = state
    ddu, ddv = deflection_accelerations(co, u, v, du, dv, omega, omega_dot)
    return du, dv, ddu, ddv, omega, omega_dot


def torque_drive_rates(co: Coefficients, state, torque, coupling: str = 'exact'):
    """Time derivative of the state when the hub torque is given (free rotation)."""
    alpha = hub_angular_acceleration(co, state, torque, coupling)
    return velocity_drive_rates(co, state, alpha)


def energy(co: Coefficients, state):
    """Total mechanical energy T + V of mass, rod and hub, J.

    T = m/2 [(u' - w v)^2 + (v' + w (r0 + u))^2] + J w^2 / 2, V = (k1 u^2 + k2 v^2) / 2.
    Its rate is dE/dt = Q w - c1 u'^2 - c2 v'^2.
    """
    u, v, du, dv, _, omega = state
    vx = du - omega * v
    vy = dv + omega * (co.eccentricity + u)
    return (0.5 * co.mass * (vx * vx + vy * vy) + 0.5 * co.hub_inertia * omega * omega
            + 0.5 * (co.k1 * u * u + co.k2 * v * v))


def angular_momentum(co: Coefficients, state):
    """Angular momentum of hub and mass about the rotation axis, kg m^2/s.

    L = (J + m rho^2) w + m ((r0 + u) v' - v u'), rho^2 = (r0 + u)^2 + v^2; dL/dt = Q.
    """
    u, v, du, dv, _, omega = state
    x = co.eccentricity + u
    return ((co.hub_inertia + co.mass * (x * x + v * v)) * omega
            + co.mass * (x * dv - v * du))


def inertial_position(co: Coefficients, u, v, theta):
    """Position (x, y) of the mass in the inertial frame, m (z = rod length)."""
    x = co.eccentricity + u
    c, s = np.cos(theta), np.sin(theta)
    return x * c - v * s, x * s + v * c


def omega_jump(co: Coefficients, state, omega_new) -> State:
    """State just after an instantaneous change of the hub's angular velocity.

    The mass keeps its absolute velocity (a finite rod force cannot change it in no
    time), so its velocity relative to the rotating frame changes by
    -(omega_new - omega) e3 x ((r0 + u) e1 + v e2).
    """
    u, v, du, dv, theta, omega = state
    dw = omega_new - omega
    return State(u, v, du + dw * v, dv - dw * (co.eccentricity + u), theta, omega_new)


def rotating_frame_matrix(co: Coefficients, omega, omega_dot):
    """Augmented system matrix A (shape ``(..., 5, 5)``) of the prescribed-rotation model.

    For x = (u, v, u', v', 1): x' = A x, with the forcing in the last column. Built by
    evaluating :func:`deflection_accelerations` (the one source of the equations) at
    the unit states, since the deflection equations are affine in (u, v, u', v').
    ``omega`` and ``omega_dot`` may be arrays (one matrix per time).
    """
    omega = np.asarray(omega, dtype=float)
    omega_dot = np.broadcast_to(np.asarray(omega_dot, dtype=float), omega.shape)
    A = np.zeros(omega.shape + (5, 5))
    A[..., 0, 2] = 1.0
    A[..., 1, 3] = 1.0
    f0u, f0v = deflection_accelerations(co, 0.0, 0.0, 0.0, 0.0, omega, omega_dot)
    A[..., 2, 4], A[..., 3, 4] = f0u, f0v
    for j, unit in enumerate(np.eye(4)):
        fu, fv = deflection_accelerations(co, *unit, omega, omega_dot)
        A[..., 2, j] = fu - f0u
        A[..., 3, j] = fv - f0v
    return A


def omega_jump_matrix(co: Coefficients, delta_omega):
    """The jump of :func:`omega_jump` as a 5x5 matrix on (u, v, u', v', 1)."""
    J = np.eye(5)
    J[2, 1] = delta_omega
    J[3, 0] = -delta_omega
    J[3, 4] = -delta_omega * co.eccentricity
    return J
