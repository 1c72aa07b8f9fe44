"""A live simulation session: one rod, its drive, command shaping, limits and health.

:class:`SimulationEngine` is what a real-time front end (the ROS simulator node)
drives: it owns a :class:`~rotrod_core.stepper.RealTimeStepper`, takes timestamped
commands (angular-velocity setpoints or hub torques), advances in whole fixed steps
on its own simulated clock, halts on a state beyond the deflection limit or a
non-finite one (keeping the last good state), and reports its health.
:class:`EngineConfig` holds everything that can be configured, validated as a whole
so that a combination that makes no physical sense is refused with a reason.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from dataclasses import dataclass, field

import numpy as np

from . import model
from .analysis import dynamic_frequencies, modal_analysis, tangential_bending
from .checks import finite_number
from .command import OmegaSetpointShaper
from .critical import critical_speed
from .model import STATE_FIELDS, State, make_state
from .params import RodParams
from .stepper import (
    NonFiniteStateError,
    RealTimeStepper,
    check_coupling,
    check_rotary_inertia,
)

DRIVES = ('velocity', 'torque')

OK, WARN, ERROR = 0, 1, 2
"""Health levels (the values of diagnostic_msgs/DiagnosticStatus)."""

STEP_RESOLUTION = 0.5
"""Largest dt x |lambda| allowed for the fastest deflection mode (RK4 phase error
per radian of that mode ~ (dt |lambda|)^4 / 120, here below 0.06 %)."""


TIMEOUT_DELAYS = 2.0
"""Shortest command_timeout, in units of setpoint_delay: the delay plus two stream
intervals, since setpoint_delay is at least two intervals."""


class CommandRejected(ValueError):
    """A command was refused (reason in the message); the simulation is unchanged."""


def fastest_rate(params: RodParams, max_omega: float) -> float:
    """Bound on |lambda| (rad/s) of the deflection modes for |w| <= ``max_omega`` (rad/s).

    In the rotating frame the modes are the rod's own (|lambda| <= wn max(1, 2 zeta))
    shifted by at most |w|.
    """
    wn = max(params.natural_frequency_radial, params.natural_frequency_tangential)
    return float(wn * max(1.0, 2.0 * float(params.damping_ratio)) + abs(max_omega))


@dataclass(frozen=True)
class EngineConfig:
    """Configuration of a :class:`SimulationEngine` (SI units), validated on creation.

    Attributes:
        params: the rod (one system).
        drive: ``'velocity'`` (w follows setpoints) or ``'torque'`` (free rotation).
        coupling: ``'exact'`` or ``'paper'`` (see :mod:`rotrod_core.model`).
        physics_rate: fixed integration rate, Hz (step dt = 1 / physics_rate).
        max_angular_acceleration: bound on |w'| when following setpoints, rad/s^2.
            The hub's angular acceleration bends the rod backwards: quasi-statically
            v = -w' r0 Me / k2 (Me = m for a massless rod; 0.68 mm per rad/s^2 for
            Table 1), up to twice that when w' is applied suddenly. A bound whose
            quasi-static bending alone exceeds ``deflection_limit`` is refused.
        max_omega: largest |w| accepted as a setpoint, and reached in torque drive
            before the simulation halts, rad/s.
        max_torque: largest |Q| accepted as a torque command, N m.
        deflection_limit: |r| = sqrt(u^2 + v^2) beyond which the simulation halts, m.
        warn_fraction: fraction of ``deflection_limit`` above which health is WARN.
        critical_margin: relative distance to a critical speed within which health
            is WARN (0.05 = within 5 %).
        setpoint_delay: lag of the shaped w behind the setpoint stream, s (at least
            two stream intervals); delivery jitter up to the lag minus one interval
            does not reach w (see :class:`~rotrod_core.command.OmegaSetpointShaper`).
        initial: initial state by name (u, v, du, dv, theta, omega), as
            ``(name, value)`` pairs or a dict; others zero. Used at start and reset.
        command_timeout: simulated seconds without an accepted command on the active
            drive's input after which the hub is stopped (0 = off): velocity drive
            ramps w to 0 at ``max_angular_acceleration``, torque drive sets the hub
            torque to 0 (free coast); health is WARN until a command comes. Off, w
            holds the last setpoint and the torque stays. When on, it must be at
            least :data:`TIMEOUT_DELAYS` x ``setpoint_delay`` (the delay plus at least
            two stream intervals, since the delay is at least two): a normal stream
            never trips it. See :meth:`SimulationEngine.step`.
    """

    params: RodParams = field(default_factory=RodParams)
    drive: str = 'velocity'
    coupling: str = 'exact'
    physics_rate: float = 1000.0
    max_angular_acceleration: float = 0.5
    max_omega: float = 50.0
    max_torque: float = 100.0
    deflection_limit: float = 0.003
    warn_fraction: float = 0.8
    critical_margin: float = 0.05
    setpoint_delay: float = 0.05
    initial: tuple = ()
    command_timeout: float = 0.0

    def __post_init__(self):
        set_ = object.__setattr__
        if not isinstance(self.params, RodParams):
            raise ValueError(f'params must be RodParams, got {self.params!r}')
        if self.params.is_batch:
            raise ValueError('the engine simulates one system; got a batch of RodParams')
        if self.drive not in DRIVES:
            raise ValueError(f'drive must be one of {DRIVES}, got {self.drive!r}')
        check_coupling(self.params, self.coupling)
        for name in ('physics_rate', 'max_angular_acceleration', 'max_omega', 'max_torque',
                     'deflection_limit', 'warn_fraction'):
            set_(self, name, finite_number(name, getattr(self, name), positive=True))
        set_(self, 'critical_margin',
             finite_number('critical_margin', self.critical_margin, nonnegative=True))
        if self.warn_fraction > 1:
            raise ValueError(f'warn_fraction must be in (0, 1], got {self.warn_fraction!r}')
        if not 0 < finite_number('setpoint_delay', self.setpoint_delay) <= 10:
            raise ValueError(f'setpoint_delay must be in (0, 10] s, got '
                             f'{self.setpoint_delay!r}')
        timeout = finite_number('command_timeout', self.command_timeout, nonnegative=True)
        set_(self, 'command_timeout', timeout)
        if 0 < timeout < TIMEOUT_DELAYS * self.setpoint_delay:
            raise ValueError(
                f'command_timeout {timeout:g} s is shorter than {TIMEOUT_DELAYS:g} x '
                f'setpoint_delay ({TIMEOUT_DELAYS * self.setpoint_delay:g} s): a setpoint '
                'is reached setpoint_delay after it arrives and the next one is due '
                'within two stream intervals of that, so a normal stream would trip it '
                '(0 turns the timeout off)')
        if self.critical_margin >= 1:
            raise ValueError(f'critical_margin must be in [0, 1), got {self.critical_margin!r}')
        rate = fastest_rate(self.params, self.max_omega)
        needed = rate / STEP_RESOLUTION
        if self.physics_rate < needed:
            raise ValueError(
                f'physics_rate {self.physics_rate:g} Hz is too low for this rod: the fastest '
                f'deflection mode at |w| <= max_omega ({self.max_omega:g} rad/s) reaches '
                f'{rate:.4g} rad/s, so RK4 needs physics_rate >= {needed:.4g} Hz '
                f'(or a lower max_omega)')
        bend = tangential_bending(self.params, self.max_angular_acceleration)
        if bend > self.deflection_limit:
            raise ValueError(
                f'max_angular_acceleration {self.max_angular_acceleration:g} rad/s^2 bends the '
                f'rod tangentially by {bend * 1e3:.3g} mm (quasi-static w\' r0 Me / k2), beyond '
                f'the {self.deflection_limit * 1e3:.3g} mm deflection_limit: every ramp at '
                'that rate would halt the simulation')
        # the setpoint shaper's own limits (e.g. the largest change of w in a stall),
        # refused here with its reason rather than when the engine starts
        OmegaSetpointShaper(self.max_angular_acceleration, delay=self.setpoint_delay)
        try:
            initial = dict(self.initial)
        except (TypeError, ValueError):
            raise ValueError(f'initial must be (name, value) pairs or a dict, got '
                             f'{self.initial!r}') from None
        state = make_state(initial, scalar=True)
        set_(self, 'initial', tuple(sorted((k, float(v)) for k, v in initial.items())))
        if self.drive == 'torque':
            check_rotary_inertia(self.params, self.coupling, state)
        if abs(state.omega) > self.max_omega:
            raise ValueError(f'initial omega {state.omega:g} rad/s exceeds max_omega '
                             f'{self.max_omega:g} rad/s')
        r = math.hypot(state.u, state.v)
        if r > self.deflection_limit:
            raise ValueError(f'initial deflection {r:g} m exceeds deflection_limit '
                             f'{self.deflection_limit:g} m')
        co = model.Coefficients.from_params(self.params)
        if not (math.isfinite(model.energy(co, state))
                and math.isfinite(model.angular_momentum(co, state))):
            raise ValueError(f'the energy or angular momentum of the initial state {state} '
                             'overflows')

    @property
    def dt(self) -> float:
        """Integration step, s."""
        return 1.0 / self.physics_rate

    @property
    def initial_state(self) -> State:
        """The initial state as a :class:`State`."""
        return make_state(dict(self.initial), scalar=True)

    def replace(self, **changes) -> EngineConfig:
        """A validated copy with some fields changed; RodParams fields go to ``params``."""
        rod = {k: changes.pop(k) for k in list(changes) if k in _ROD_FIELDS}
        if rod:
            changes['params'] = (changes.get('params') or self.params).replace(**rod)
        return dataclasses.replace(self, **changes)


_ROD_FIELDS = {f.name for f in dataclasses.fields(RodParams)}


@dataclass(frozen=True)
class Health:
    """The session's health: ``level`` (OK, WARN, ERROR), a message, named values."""

    level: int
    message: str
    values: tuple = ()


class SimulationEngine:
    """One rod simulated in fixed steps on its own clock, driven by timestamped commands.

    The simulated clock :attr:`time` (s) starts at 0 and only moves forward (a reset
    returns the state, not the clock, to the start). Commands may carry a time ``at``
    (s, not before :attr:`time`): they take effect then, so a front end that advances
    in batches of steps still applies each command at the instant it arrived.
    """

    def __init__(self, config: EngineConfig | None = None):
        self.config = config if config is not None else EngineConfig()
        self._origin = 0.0
        self._steps = 0
        self._stepper = self._make_stepper(self.config, self.config.initial_state)
        self.halted: str | None = None
        self.rejected_commands = 0
        self.accepted_commands = 0
        self.timeouts = 0
        """Number of command-timeout events so far (see :attr:`timed_out_at`)."""
        self._reset_commands()
        self._cache_limits()

    # ----------------------------------------------------------------- construction
    @staticmethod
    def _make_stepper(config: EngineConfig, state: State) -> RealTimeStepper:
        stepper = RealTimeStepper(config.params, config.dt, config.coupling)
        stepper.set_state(**state._asdict())
        return stepper

    def _reset_commands(self) -> None:
        cfg = self.config
        self._shaper = OmegaSetpointShaper(cfg.max_angular_acceleration,
                                           delay=cfg.setpoint_delay,
                                           omega=self.state.omega, time=self.time)
        self._torque_schedule: deque = deque()
        self.torque_command = 0.0
        st = self._stepper
        self._torque = (0.0 if cfg.drive == 'torque' else
                        float(model.hub_torque(st.coefficients, st.state, 0.0, st.coupling)))
        self._omega_dot = 0.0
        self._restart_timer()

    def _restart_timer(self) -> None:
        """The command timeout counts from now; a timeout event in course ends."""
        self._last_command = self.time
        self.timed_out_at: float | None = None

    def _cache_limits(self) -> None:
        p, cfg = self.config.params, self.config
        self.critical_speeds = {
            'deflection_limit': float(critical_speed(p, cfg.deflection_limit)),
            'radial_natural_frequency': float(p.natural_frequency_radial),
            'tangential_natural_frequency': float(p.natural_frequency_tangential),
        }
        self._always_stable = bool(p.is_isotropic and not float(p.damping_ratio) > 0)
        self._stability: dict = {}
        self._frequencies: dict = {}

    # ----------------------------------------------------------------- state
    @property
    def time(self) -> float:
        """Simulated time, s."""
        return self._origin + self._steps * self.config.dt

    @property
    def dt(self) -> float:
        """Integration step, s."""
        return self.config.dt

    @property
    def state(self) -> State:
        """Current state (u, v, du, dv, theta, omega), SI units."""
        return self._stepper.state

    @property
    def torque(self) -> float:
        """Hub torque, N m.

        The applied torque in torque drive; in velocity drive, the torque the drive
        must supply to impose w'.
        """
        return self._torque

    @property
    def omega_dot(self) -> float:
        """Hub angular acceleration over the last step, rad/s^2."""
        return self._omega_dot

    @property
    def setpoint(self) -> float:
        """Latest accepted angular-velocity setpoint, rad/s (velocity drive)."""
        return self._shaper.setpoint

    @property
    def command_age(self) -> float:
        """Simulated time since the latest accepted command (or the timer's restart), s."""
        return max(0.0, self.time - self._last_command)

    @property
    def deflection(self) -> float:
        """|r| = sqrt(u^2 + v^2) of the mass, m."""
        s = self.state
        return math.hypot(s.u, s.v)

    def inertial_position(self) -> tuple:
        """Position (x, y, z) of the mass in the inertial frame, m (z = rod length)."""
        x, y = self._stepper.inertial_position()
        return x, y, float(self.config.params.rod_length)

    def energy(self) -> float:
        """Total mechanical energy, J."""
        return self._stepper.energy()

    def angular_momentum(self) -> float:
        """Angular momentum about the axis, kg m^2/s."""
        return self._stepper.angular_momentum()

    def frequencies(self) -> tuple:
        """Dynamic frequencies (f1, f2) in Hz at the current w (Eq. 28 or eigen analysis)."""
        w = self.state.omega
        f = self._frequencies.get(w)
        if f is None:
            if len(self._frequencies) > 64:
                self._frequencies.clear()
            f = self._frequencies[w] = dynamic_frequencies(self.config.params, w)
        return f

    # ----------------------------------------------------------------- commands
    def _command_time(self, at) -> float:
        try:
            t = self.time if at is None else finite_number('command time', at)
        except ValueError as exc:
            self._reject(str(exc))
        return max(t, self.time, self._shaper.last_command_time)

    def _reject(self, reason: str):
        self.rejected_commands += 1
        raise CommandRejected(reason)

    def _check_command(self, name: str, value, drive: str, limit: float, unit: str) -> float:
        try:
            x = finite_number(name, value)
        except ValueError as exc:
            self._reject(str(exc))
        if abs(x) > limit:
            self._reject(f'{name} {x:g} {unit} exceeds the limit {limit:g} {unit}')
        if self.config.drive != drive:
            self._reject(f'{name} ignored: drive is {self.config.drive!r} '
                         f'(set drive to {drive!r} to use it)')
        if self.halted:
            self._reject(f'{name} ignored: simulation halted ({self.halted}); reset first')
        return x

    def command_omega(self, setpoint, at=None) -> None:
        """Angular-velocity setpoint (rad/s) from time ``at`` (s) on; velocity drive."""
        w = self._check_command('omega setpoint', setpoint, 'velocity',
                                self.config.max_omega, 'rad/s')
        t = self._command_time(at)
        try:
            self._shaper.command(w, t)
        except ValueError as exc:       # beyond what the shaper can represent
            self._reject(str(exc))
        self._accepted(t)

    def command_torque(self, torque, at=None) -> None:
        """Hub torque (N m) from time ``at`` (s) on; torque drive."""
        q = self._check_command('torque', torque, 'torque', self.config.max_torque, 'N m')
        t = self._command_time(at)
        if self._torque_schedule and self._torque_schedule[-1][0] > t:
            t = self._torque_schedule[-1][0]
        self._torque_schedule.append((t, q))
        self._accepted(t)

    def _accepted(self, t: float) -> None:
        """A command taking effect at time ``t`` was accepted: it restarts the timeout."""
        self._last_command = max(self._last_command, t)
        self.timed_out_at = None
        self.accepted_commands += 1

    def _check_timeout(self, t0: float, dt: float) -> None:
        """Start a timeout event if the command timeout runs out in the step from ``t0``.

        Velocity drive: w ramps to 0 at the acceleration limit from the instant the
        timeout runs out (through the setpoint shaper, so w is continuous and |w'|
        bounded). Torque drive: the torque is 0 from this step on (commands apply at
        step instants too).
        """
        timeout = self.config.command_timeout
        if not timeout or self.timed_out_at is not None:
            return
        deadline = self._last_command + timeout
        if self.config.drive == 'velocity':
            if deadline > t0 + dt:
                return
            self.timed_out_at = max(deadline, t0)
            self._shaper.ramp_to(0.0, self.timed_out_at)
        else:
            if deadline > t0 + 0.5 * dt:
                return
            self.timed_out_at = t0
            self.torque_command = 0.0
        self.timeouts += 1

    # ----------------------------------------------------------------- stepping
    def step(self) -> bool:
        """Advance one step; False (and no change) if halted or the step was refused."""
        if self.halted:
            return False
        stepper, cfg, dt = self._stepper, self.config, self.config.dt
        before = stepper.state
        t0 = self.time
        self._check_timeout(t0, dt)
        try:
            if cfg.drive == 'velocity':
                omega_dot = (self._shaper.omega(t0 + dt) - before.omega) / dt
                state = stepper.step_velocity(omega_dot)
            else:
                while self._torque_schedule and self._torque_schedule[0][0] <= t0 + 0.5 * dt:
                    self.torque_command = self._torque_schedule.popleft()[1]
                state = stepper.step_torque(self.torque_command)
        except NonFiniteStateError:
            self.halted = f'non-finite state at t = {t0 + dt:.6f} s'
            return False
        r = math.hypot(state.u, state.v)
        problem = None
        if r > cfg.deflection_limit:
            problem = (f'deflection {r * 1e3:.4g} mm beyond the limit '
                       f'{cfg.deflection_limit * 1e3:.4g} mm at t = {t0 + dt:.4f} s')
        elif abs(state.omega) > cfg.max_omega:
            problem = (f'|omega| {abs(state.omega):.4g} rad/s beyond max_omega '
                       f'{cfg.max_omega:.4g} rad/s at t = {t0 + dt:.4f} s')
        if problem:
            stepper.set_state(**before._asdict())
            self.halted = problem + '; halted at the last good state'
            return False
        self._steps += 1
        self._torque = stepper.torque
        self._omega_dot = stepper.omega_dot
        if self._steps % 32 == 0:     # a 10 kHz stream leaves a ramp per setpoint
            self._shaper.forget_before(self.time)
        return True

    def advance(self, steps: int) -> int:
        """Take up to ``steps`` steps (fewer if halted); return how many were taken."""
        if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)):
            raise ValueError(f'steps must be a whole number, got {steps!r}')
        done = 0
        while done < steps and self.step():
            done += 1
        return done

    def steps_until(self, t: float) -> int:
        """Number of whole steps from :attr:`time` to reach time ``t`` (s), >= 0."""
        n = (finite_number('t', t) - self.time) / self.config.dt + 1e-9
        if not math.isfinite(n):
            raise ValueError(f't = {t!r} s is too many steps of {self.config.dt:g} s away')
        return max(0, math.floor(n))

    def advance_to(self, t: float) -> int:
        """Take the whole steps that do not pass time ``t`` (s); return how many."""
        return self.advance(self.steps_until(t))

    # ----------------------------------------------------------------- control
    def reset(self) -> None:
        """Back to the configured initial state (clock keeps running); clears a halt."""
        self._stepper.set_state(**self.config.initial_state._asdict())
        self.halted = None
        self._reset_commands()

    def reconfigure(self, config: EngineConfig) -> None:
        """Switch to ``config`` (already validated), keeping the state and the clock.

        A change of drive starts the new drive from the current motion: velocity
        drive holds the current w, torque drive starts with zero torque. A change of
        drive, ``max_angular_acceleration``, ``setpoint_delay`` or ``command_timeout``
        restarts the command timeout and ends a timeout event in course (velocity
        drive then holds the w reached; torque drive keeps zero torque).
        """
        if not isinstance(config, EngineConfig):
            raise ValueError(f'config must be an EngineConfig, got {config!r}')
        state = self.state
        time = self.time
        stepper = self._make_stepper(config, state)
        old = self.config
        self.config, self._stepper = config, stepper
        self._origin, self._steps = time, 0
        if (config.drive != old.drive
                or config.max_angular_acceleration != old.max_angular_acceleration
                or config.setpoint_delay != old.setpoint_delay):
            self._reset_commands()
        elif config.command_timeout != old.command_timeout:
            if self.timed_out_at is not None and config.drive == 'velocity':
                self._shaper.ramp_to(self._shaper.omega(time), time)    # hold w here
            self._restart_timer()
        self._cache_limits()

    # ----------------------------------------------------------------- health
    def stable_at(self, omega: float) -> bool:
        """Whether the free vibration at constant ``omega`` (rad/s) decays or persists."""
        if self._always_stable:
            return True
        stable = self._stability.get(omega)
        if stable is None:
            if len(self._stability) > 64:
                self._stability.clear()
            stable = self._stability[omega] = modal_analysis(self.config.params, omega).stable
        return stable

    def health(self) -> Health:
        """The session's health level and its reason.

        ERROR when halted; WARN when the deflection is above ``warn_fraction`` of the
        limit, |w| is near a critical speed, w is in an unstable range, or the command
        timeout has run out (until a command comes); else OK.
        """
        cfg, s = self.config, self.state
        r = self.deflection
        w = abs(s.omega)
        values = (('time_s', self.time), ('omega_rad_s', s.omega), ('u_m', s.u), ('v_m', s.v),
                  ('deflection_m', r), ('deflection_limit_m', cfg.deflection_limit),
                  ('hub_torque_Nm', self.torque), ('drive', cfg.drive),
                  ('coupling', cfg.coupling),
                  *((f'critical_speed_{k}_rad_s', v) for k, v in self.critical_speeds.items()),
                  ('accepted_commands', self.accepted_commands),
                  ('rejected_commands', self.rejected_commands),
                  ('command_timeout_s', cfg.command_timeout),
                  ('command_age_s', self.command_age), ('command_timeouts', self.timeouts))
        if self.halted:
            return Health(ERROR, self.halted, values)
        warnings = []
        if self.timed_out_at is not None:
            if cfg.drive == 'torque':
                action = 'hub torque 0, coasting'
            elif self._shaper.target_reached_at > self.time:
                action = 'spinning down'
            else:
                action = 'spun down, at rest'
            warnings.append(f'no command for {self.command_age:.3g} s (command_timeout '
                            f'{cfg.command_timeout:g} s): {action}')
        if r > cfg.warn_fraction * cfg.deflection_limit:
            warnings.append(f'deflection {r * 1e3:.3g} mm above {cfg.warn_fraction:.0%} of '
                            f'the {cfg.deflection_limit * 1e3:.3g} mm limit')
        for name, wc in self.critical_speeds.items():
            if abs(w - wc) <= cfg.critical_margin * wc:
                warnings.append(f'|omega| {w:.4g} rad/s within {cfg.critical_margin:.0%} of '
                                f'the critical speed {wc:.4g} rad/s '
                                f'({name.replace("_", " ")})')
        if not self.stable_at(s.omega):
            warnings.append(f'omega {s.omega:.4g} rad/s is in an unstable range: '
                            'the free vibration grows')
        if warnings:
            return Health(WARN, '; '.join(warnings), values)
        return Health(OK, 'running', values)


__all__ = ['CommandRejected', 'DRIVES', 'ERROR', 'EngineConfig', 'Health', 'OK',
           'STATE_FIELDS', 'SimulationEngine', 'WARN', 'fastest_rate']
