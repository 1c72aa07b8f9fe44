"""Real-time fixed-step integrator: holds the state and advances it one step at a time."""

from __future__ import annotations

import math
from functools import partial

import rotrod_core.model.equations as model
from rotrod_core.model.equations import Coefficients, State, check_coupling, make_state
from rotrod_core.model.params import RodParams
from rotrod_core.numerics.checks import NonFiniteStateError, finite_number
from rotrod_core.numerics.rk4 import rk4_step, rk4_step_prescribed_rotation


class RealTimeStepper:
    """Classical RK4 at a fixed step ``dt`` under the current command.

    Velocity drive: :meth:`step_velocity` with the hub's angular acceleration over the
    step (w follows linearly); a sudden change of w goes through :meth:`jump_omega`
    (physical: the mass keeps its absolute velocity). Torque drive: :meth:`step_torque`
    with the hub torque; the rotation is free and coupled to the rod (``coupling``).

    A step that would produce a non-finite state raises :class:`NonFiniteStateError`
    and leaves the state untouched.

    Args:
        params: one system (not a batch).
        dt: step, s.
        coupling: ``'exact'`` (Lagrangian, needs J > 0) or ``'paper'`` (Eq. 23 + J w').
        initial: initial state by name (u, v, du, dv, theta, omega); others zero.
    """

    def __init__(self, params: RodParams, dt: float = 1e-3, coupling: str = 'exact',
                 initial: dict | None = None):
        if params.is_batch:
            raise ValueError('RealTimeStepper simulates one system; got a batch of RodParams')
        self.dt = finite_number('dt', dt)
        if not self.dt > 0:
            raise ValueError(f'dt must be > 0, got {dt!r}')
        check_coupling(params, coupling)
        self.params = params
        self.coupling = coupling
        self._co = Coefficients.from_params(params)
        self._accelerations = partial(model.deflection_accelerations, self._co)
        self._torque_rates = partial(model.torque_drive_rates, self._co, coupling=coupling)
        self.reset(initial)

    def reset(self, initial: dict | None = None) -> None:
        """Return to t = 0 and the given initial state (default: at rest, undeflected)."""
        self._state = make_state(initial, scalar=True)
        self.time = 0.0
        self.omega_dot = 0.0
        self.torque = model.hub_torque(self._co, self._state, 0.0, self.coupling)

    @property
    def state(self) -> State:
        """Current state (u, v, du, dv, theta, omega), SI units."""
        return self._state

    @property
    def coefficients(self) -> Coefficients:
        """The equations' coefficients for these parameters."""
        return self._co

    def _accept(self, new: tuple, drive_name: str, drive_value: float) -> State:
        """Take the new state, unless it or the drive's value at its end is not finite."""
        u, v, du, dv, theta, omega = new
        isfinite = math.isfinite
        if not (isfinite(u) and isfinite(v) and isfinite(du) and isfinite(dv)
                and isfinite(theta) and isfinite(omega)):
            raise NonFiniteStateError(
                f'step at t={self.time:.6f} s gave a non-finite state {new}; state kept')
        if not math.isfinite(drive_value):
            raise NonFiniteStateError(
                f'step at t={self.time:.6f} s gave a non-finite {drive_name} {drive_value!r} '
                f'at the state {new}; state kept')
        self._state = State(*new)
        self.time += self.dt
        return self._state

    def step_velocity(self, omega_dot: float = 0.0) -> State:
        """Advance one step with constant hub angular acceleration ``omega_dot`` (rad/s^2).

        Afterwards :attr:`torque` is the hub torque the drive must supply (N m).
        """
        wd = finite_number('omega_dot', omega_dot)
        new = rk4_step_prescribed_rotation(self._accelerations, self._state, self.dt, wd)
        torque = model.hub_torque(self._co, new, wd, self.coupling)
        state = self._accept(new, 'hub torque', torque)
        self.omega_dot = wd
        self.torque = torque
        return state

    def step_torque(self, torque: float, torque_end: float | None = None) -> State:
        """Advance one step under the hub torque (N m), linear to ``torque_end`` if given.

        With the paper's coupling and J = 0, a mass on the axis leaves no rotary
        inertia: w' is undefined, a :class:`NonFiniteStateError` (state kept).
        """
        q0 = finite_number('torque', torque)
        q1 = q0 if torque_end is None else finite_number('torque_end', torque_end)
        try:
            new = rk4_step(self._torque_rates, self._state, self.dt, q0, 0.5 * (q0 + q1), q1)
            omega_dot = model.hub_angular_acceleration(self._co, new, q1, self.coupling)
        except ZeroDivisionError:
            raise NonFiniteStateError(
                f'step at t={self.time:.6f} s: no rotary inertia about the axis (J = 0 and '
                'the mass on the axis), w\' is undefined; state kept') from None
        state = self._accept(new, "hub angular acceleration w'", omega_dot)
        self.torque = q1
        self.omega_dot = omega_dot
        return state

    def jump_omega(self, omega: float) -> State:
        """Change the hub's angular velocity instantly to ``omega`` (rad/s), physically."""
        w = finite_number('omega', omega)
        new = model.omega_jump(self._co, self._state, w)
        if not all(math.isfinite(x) for x in new):
            raise NonFiniteStateError(f'a jump to omega={w!r} rad/s gives a non-finite state '
                                      f'{tuple(new)}; state kept')
        self._state = new
        return self._state

    def set_state(self, **values) -> State:
        """Overwrite some state components by name (validated; others kept)."""
        self._state = make_state({**self._state._asdict(), **values}, scalar=True)
        return self._state

    def _finite(self, what: str, *values) -> None:
        if not all(math.isfinite(x) for x in values):
            raise NonFiniteStateError(f'the {what} of the state {tuple(self._state)} '
                                      f'overflows: {values}')

    def inertial_position(self) -> tuple[float, float]:
        """Position (x, y) of the mass in the inertial frame, m.

        The state is always finite; a quantity derived from it that overflows (an
        extreme state) raises :class:`NonFiniteStateError`, as do :meth:`energy` and
        :meth:`angular_momentum`.
        """
        s = self._state
        x, y = model.inertial_position(self._co, s.u, s.v, s.theta)
        self._finite('inertial position', x, y)
        return float(x), float(y)

    def energy(self) -> float:
        """Total mechanical energy of the current state, J."""
        e = float(model.energy(self._co, self._state))
        self._finite('energy', e)
        return e

    def angular_momentum(self) -> float:
        """Angular momentum about the axis of the current state, kg m^2/s."""
        L = float(model.angular_momentum(self._co, self._state))
        self._finite('angular momentum', L)
        return L
