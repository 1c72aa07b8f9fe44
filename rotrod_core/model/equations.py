"""Equations of motion of the tip mass on a rod on a rotating hub (rotating frame).

The single source of truth for the dynamics (see docs/model.md). State
``(u, v, du, dv, theta, omega)``: deflection u (radial, e1) and v (tangential, e2) of
the mass in m, their rates in m/s, hub angle theta in rad and angular velocity omega
in rad/s. Every function is plain arithmetic, so it accepts Python floats (fast, for
the real-time stepper) and numpy arrays (batches, vectorized over time) alike.

Deflection equations (Eqs. 16, 17, generalised to k1 != k2, rotating damping and a
rod with mass)::

    u'' = 2 w v' + (w^2 - k1/M) u + w^2 re + w' v - (c1/M) u'
    v'' = -2 w u' + (w^2 - k2/M) v - w' (re + u) - (c2/M) v'

Hub (torque) equation, exact Lagrangian coupling, after eliminating u'' and v''::

    Je w' = Q + tau_rod,   tau_rod = v (k2 (re + u) - k1 u) + c2 (re + u) v' - c1 v u'

tau_rod is the moment about the axis that the rod exerts on the hub. The paper's
Eq. 23 (plus J w') instead reads ``(Je + M rho^2) w' = Q - 2 M w ((re + u) u' + v v')``
with rho^2 = (re + u)^2 + v^2.

For the paper's massless rod M = m, re = r0 and Je = J. A rod with mass (one-mode
Rayleigh-Ritz on the static cantilever shape, ``docs/real_rig.md#lagrangian``) has the
modal mass M = m + (33/140) rho A l, the eccentric mass Me = m + (3/8) rho A l, the
load radius re = (Me / M) r0 and the effective hub inertia
Je = J + r0^2 (m + rho A l - Me^2 / M): its kinetic energy is exactly that of a point
mass M at radius re on a hub of inertia Je (``docs/real_rig.md#equivalence``), so the
equations keep the paper's form with these coefficients. The stiffnesses k1, k2
include the axial load of gravity (:attr:`RodParams.stiffness_radial`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple, TypeAlias

import numpy as np

from rotrod_core.model.params import RodParams
from rotrod_core.numerics.checks import finite_array, finite_number

COUPLINGS = ('exact', 'paper')

Real: TypeAlias = float | np.ndarray
"""A float for a single system, an array for a batch (the same arithmetic serves both)."""


class State(NamedTuple):
    """Full state of the system (SI units; arrays allowed for batches).

    Model: docs/model.md#frames.
    """

    u: Real
    """Radial deflection of the mass, m (rotating frame, e1)."""
    v: Real
    """Tangential deflection of the mass, m (rotating frame, e2)."""
    du: Real
    """Radial deflection rate u', m/s."""
    dv: Real
    """Tangential deflection rate v', m/s."""
    theta: Real
    """Hub angle, rad."""
    omega: Real
    """Hub angular velocity, rad/s."""


STATE_FIELDS = State._fields


def make_state(initial: dict | None = None, *, scalar: bool = False, **defaults) -> State:
    """Build a :class:`State` from a mapping of named initial values (others zero).

    Values may be arrays (a batch) unless ``scalar``. Raises ValueError for an unknown
    name or a value that is not a finite number (booleans and strings included).
    """
    values: dict[str, Real] = dict.fromkeys(STATE_FIELDS, 0.0)
    values.update(defaults)
    for name, value in (initial or {}).items():
        if name not in values:
            raise ValueError(f'unknown initial state {name!r}; expected one of {STATE_FIELDS}')
        values[name] = value
    for name, value in values.items():
        if scalar or isinstance(value, bool):
            values[name] = finite_number(f'initial {name}', value)
            continue
        arr = finite_array(f'initial {name}', value)
        values[name] = float(arr) if arr.ndim == 0 else arr
    return State(**values)


@dataclass(frozen=True, init=False)
class Coefficients:
    """Coefficients of the equations, taken from :class:`RodParams`.

    Plain floats for a single system, arrays for a batch. The equations use the
    modal mass M, the load radius re and the effective hub inertia Je (module
    docstring); for the paper's massless rod these are m, r0 and J exactly.
    """

    mass: Real
    """Tip mass m, kg."""
    eccentricity: Real
    """r0 (the rod root's radius: where the undeflected mass stands), m."""
    hub_inertia: Real
    """J, kg m^2 (the hub alone)."""
    k1: Real
    """Radial tip stiffness (with the axial load of gravity), N/m."""
    k2: Real
    """Tangential tip stiffness (with the axial load of gravity), N/m."""
    c1: Real
    """Radial damping coefficient, N s/m."""
    c2: Real
    """Tangential damping coefficient, N s/m."""
    w1sq: Real
    """k1/M, 1/s^2."""
    w2sq: Real
    """k2/M, 1/s^2."""
    g1: Real
    """c1/M, 1/s."""
    g2: Real
    """c2/M, 1/s."""
    modal_mass: Real
    """M = m + (33/140) rho A l, kg (m for a massless rod)."""
    eccentric_mass: Real
    """Me = m + (3/8) rho A l, kg (m for a massless rod)."""
    load_radius: Real
    """re = (Me / M) r0, m: where a point mass M would feel the same eccentric loads."""
    rotor_inertia: Real
    """Je = J + r0^2 (m + rho A l - Me^2 / M) >= J, kg m^2."""

    def __init__(self, mass: Real, eccentricity: Real, hub_inertia: Real, k1: Real, k2: Real,
                 c1: Real, c2: Real, w1sq: Real, w2sq: Real, g1: Real, g2: Real,
                 modal_mass: Real | None = None, eccentric_mass: Real | None = None,
                 load_radius: Real | None = None, rotor_inertia: Real | None = None) -> None:
        # a massless rod unless told otherwise (M = m, re = r0, Je = J)
        set_ = object.__setattr__
        for name, value in (('mass', mass), ('eccentricity', eccentricity),
                            ('hub_inertia', hub_inertia), ('k1', k1), ('k2', k2), ('c1', c1),
                            ('c2', c2), ('w1sq', w1sq), ('w2sq', w2sq), ('g1', g1), ('g2', g2),
                            ('modal_mass', mass if modal_mass is None else modal_mass),
                            ('eccentric_mass', mass if eccentric_mass is None else eccentric_mass),
                            ('load_radius', eccentricity if load_radius is None else load_radius),
                            ('rotor_inertia',
                             hub_inertia if rotor_inertia is None else rotor_inertia)):
            set_(self, name, value)

    @classmethod
    def from_params(cls, params: RodParams) -> Coefficients:
        """Evaluate the coefficients of ``params`` (floats, or arrays for a batch)."""
        def num(x):
            arr = np.asarray(x, dtype=float)
            return float(arr) if arr.ndim == 0 else arr

        m, mm, me = num(params.mass), num(params.modal_mass), num(params.eccentric_mass)
        rod = num(params.rod_mass)
        r0, hub = num(params.eccentricity), num(params.hub_inertia)
        k1, k2 = num(params.stiffness_radial), num(params.stiffness_tangential)
        c1, c2 = num(params.damping_radial), num(params.damping_tangential)
        # m + rho A l - Me^2 / M = rod (17/35 m + 213/2240 rod) / M: exactly 0 without
        # a rod, >= 0 always (Cauchy-Schwarz on the shape integrals)
        extra = rod * (17.0 / 35.0 * m + 213.0 / 2240.0 * rod) / mm
        return cls(mass=m, eccentricity=r0, hub_inertia=hub, k1=k1, k2=k2, c1=c1, c2=c2,
                   w1sq=k1 / mm, w2sq=k2 / mm, g1=c1 / mm, g2=c2 / mm, modal_mass=mm,
                   eccentric_mass=me, load_radius=num(params.load_radius),
                   rotor_inertia=hub + extra * r0 * r0)


def deflection_accelerations(co: Coefficients, u, v, du, dv, omega, omega_dot):
    """Accelerations (u'', v'') of the mass in the rotating frame, m/s^2.

    Eqs. 16 and 17 of the paper (with the sign of the tangential initial force as
    derived in docs/model.md), with radial/tangential stiffness k1, k2, rotating damping
    and the rod's mass (modal mass M, load radius re; module docstring).
    ``omega`` and ``omega_dot`` (rad/s, rad/s^2) are the hub's at this instant.

    Model: docs/model.md#eq-deflection, docs/model.md#eq-complex, docs/model.md#eq-damping.
    """
    w2 = omega * omega
    re = co.load_radius
    ddu = 2.0 * omega * dv + (w2 - co.w1sq) * u + w2 * re + omega_dot * v - co.g1 * du
    ddv = -2.0 * omega * du + (w2 - co.w2sq) * v - omega_dot * (re + u) - co.g2 * dv
    return ddu, ddv


def rod_torque_on_hub(co: Coefficients, u, v, du, dv):
    """Moment about the axis that the rod exerts on the hub, N m (exact coupling).

    For a massless rod: the tip force of the bent rod (k1 u + c1 u', k2 v + c2 v')
    acts on the rod at the mass, at (r0 + u, v) from the axis, and reaches the hub
    through the rod. With the rod's mass the same form holds at the load radius re
    (what remains of the rod's inertia is in the effective hub inertia Je).

    Model: docs/model.md#eq-torque.
    """
    x = co.load_radius + u
    return v * (co.k2 * x - co.k1 * u) + co.c2 * x * dv - co.c1 * v * du


def hub_angular_acceleration(co: Coefficients, state, torque, coupling: str = 'exact'):
    """Hub angular acceleration w' (rad/s^2) under the hub torque ``torque`` (N m).

    ``coupling='exact'``: the Lagrangian torque equation, Je w' = Q + tau_rod; needs
    J > 0 (the 3x3 system's determinant is M^2 Je). ``coupling='paper'``: Eq. 23 as
    printed plus the hub's J w', (Je + M rho^2) w' = Q - 2 M w ((re + u) u' + v v'),
    rho^2 = (re + u)^2 + v^2 (Je + M rho^2 is the rigid moment of inertia of hub, rod
    and mass in the deflected shape).

    Model: docs/model.md#eq-torque, docs/model.md#eq-torque-paper.
    """
    u, v, du, dv, _, omega = state
    if coupling == 'exact':
        return (torque + rod_torque_on_hub(co, u, v, du, dv)) / co.rotor_inertia
    if coupling == 'paper':
        x = co.load_radius + u
        mm = co.modal_mass
        inertia = co.rotor_inertia + mm * (x * x + v * v)
        return (torque - 2.0 * mm * omega * (x * du + v * dv)) / inertia
    raise ValueError(f'coupling must be one of {COUPLINGS}, got {coupling!r}')


def hub_torque(co: Coefficients, state, omega_dot, coupling: str = 'exact'):
    """Hub torque Q (N m) that imposes the angular acceleration ``omega_dot`` (velocity drive).

    The inverse of :func:`hub_angular_acceleration` at the same state.
    """
    u, v, du, dv, _, omega = state
    if coupling == 'exact':
        return co.rotor_inertia * omega_dot - rod_torque_on_hub(co, u, v, du, dv)
    if coupling == 'paper':
        x = co.load_radius + u
        mm = co.modal_mass
        return ((co.rotor_inertia + mm * (x * x + v * v)) * omega_dot
                + 2.0 * mm * omega * (x * du + v * dv))
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

    T = M/2 [(u' - w v)^2 + (v' + w (re + u))^2] + Je w^2 / 2, exactly the kinetic
    energy of hub, tip mass and rod (for a massless rod M = m, re = r0, Je = J).
    V = (k1 u^2 + k2 v^2) / 2: the elastic energy together with the potential of
    gravity in its linearised (geometric-stiffness) form, which k1, k2 include.
    Its rate is dE/dt = Q w - c1 u'^2 - c2 v'^2.

    Model: docs/model.md#invariants.
    """
    u, v, du, dv, _, omega = state
    vx = du - omega * v
    vy = dv + omega * (co.load_radius + u)
    return (0.5 * co.modal_mass * (vx * vx + vy * vy) + 0.5 * co.rotor_inertia * omega * omega
            + 0.5 * (co.k1 * u * u + co.k2 * v * v))


def angular_momentum(co: Coefficients, state):
    """Angular momentum of hub, rod and mass about the rotation axis, kg m^2/s.

    L = (Je + M rho^2) w + M ((re + u) v' - v u'), rho^2 = (re + u)^2 + v^2; dL/dt = Q.
    (For a massless rod M = m, re = r0, Je = J. With the rod: Je + M rho^2 =
    J + (m + rho A l) r0^2 + 2 Me r0 u + M (u^2 + v^2) and M (re + u) = Me r0 + M u.)

    Model: docs/model.md#eq-momentum, docs/model.md#invariants.
    """
    u, v, du, dv, _, omega = state
    x = co.load_radius + u
    mm = co.modal_mass
    return ((co.rotor_inertia + mm * (x * x + v * v)) * omega
            + mm * (x * dv - v * du))


def inertial_position(co: Coefficients, u, v, theta):
    """Position (x, y) of the mass in the inertial frame, m (z = rod length).

    Model: docs/model.md#eq-inertial.
    """
    x = co.eccentricity + u
    if isinstance(theta, float):            # a rod's state: math's, a tenth of numpy's cost
        c, s = math.cos(theta), math.sin(theta)
    else:
        c, s = np.cos(theta), np.sin(theta)
    return x * c - v * s, x * s + v * c


def omega_jump(co: Coefficients, state, omega_new) -> State:
    """State just after an instantaneous change of the hub's angular velocity.

    The mass keeps its absolute velocity (a finite rod force cannot change it in no
    time), so its velocity relative to the rotating frame changes by
    -(omega_new - omega) e3 x ((r0 + u) e1 + v e2). With the rod's mass it is the
    deflection's generalised momenta M (u' - w v), M (v' + w (re + u)) that are kept
    (the impulse acts on the hub's angle only): the same with re for r0.
    """
    u, v, du, dv, theta, omega = state
    dw = omega_new - omega
    return State(u, v, du + dw * v, dv - dw * (co.load_radius + u), theta, omega_new)


def omega_jump_matrix(co: Coefficients, delta_omega):
    """The jump of :func:`omega_jump` as a 5x5 matrix on (u, v, u', v', 1)."""
    J = np.eye(5)
    J[2, 1] = delta_omega
    J[3, 0] = -delta_omega
    J[3, 4] = -delta_omega * co.load_radius
    return J


def coupling_name(coupling: str) -> str:
    """``coupling`` if it is one of :data:`COUPLINGS`, else ValueError."""
    if coupling not in COUPLINGS:
        raise ValueError(f'coupling must be one of {COUPLINGS}, got {coupling!r}')
    return coupling


def check_coupling(params: RodParams, coupling: str) -> None:
    """Raise ValueError for an unknown coupling, or the exact one with J = 0."""
    coupling_name(coupling)
    if coupling == 'exact' and not (params.hub_inertia > 0):
        raise ValueError('the exact coupling needs hub_inertia > 0 (its 3x3 system has '
                         'determinant m^2 J); use a disk inertia or coupling="paper"')


def check_rotary_inertia(params: RodParams, coupling: str, state: State) -> None:
    """Raise ValueError if the torque drive has no rotary inertia at ``state``.

    With the paper's coupling and J = 0 the inertia is M rho^2 (+ the rod's share
    of r0^2), zero with the mass on the axis: w' is undefined there.
    """
    co = Coefficients.from_params(params)
    x = float(co.load_radius) + state.u
    if coupling == 'paper' and not co.rotor_inertia + co.modal_mass * (
            x * x + state.v * state.v) > 0:
        raise ValueError('torque drive with the paper coupling needs rotary inertia: '
                         'hub_inertia > 0, or the mass off the axis (eccentricity > 0 or '
                         'an initial deflection)')
