"""A live simulation session: one rod, its drive, command shaping, limits and health.

:class:`SimulationEngine` is what a real-time front end (the ROS simulator node)
drives: one rod of a :class:`~rotrod_core.live.world.World` (a world of its own unless
given one), which steps it with the world's other rods as one batch. It takes
timestamped commands (angular-velocity setpoints, hub torques, trajectories), advances
in whole fixed steps on the world's simulated clock and reports its health. The
paper's critical deflection (``deflection_limit``, 3 mm) is a criterion it reports
(health ERROR while the tip is beyond it), not a wall: the simulation goes on. It
halts, keeping the last good state, only where the model stops meaning anything: a
non-finite state, a deflection beyond the small-deflection bound
``max_deflection_ratio`` x rod length, or |w| beyond the ``max_omega`` the integration
step was sized for.
:class:`EngineConfig` holds everything that can be configured, validated as a whole
so that a combination that makes no physical sense is refused with a reason.
"""

from __future__ import annotations

import dataclasses
import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import NamedTuple

import numpy as np

import rotrod_core.model.equations as model
from rotrod_core.analysis.critical import critical_speed
from rotrod_core.analysis.modes import (
    dynamic_frequencies,
    eq28,
    has_eq28,
    modal_analysis,
    tangential_bending,
)
from rotrod_core.command.shaping import DEFAULT_MAX_ANGULAR_ACCELERATION, OmegaSetpointShaper
from rotrod_core.command.trajectory import (
    INVALID_GOAL,
    OLD_HEADER_TIMESTAMP,
    PATH_TOLERANCE_VIOLATED,
    HubState,
    HubTrajectory,
    TrajectoryPoint,
    TrajectoryRejected,
)
from rotrod_core.live.drive import FOLLOWS_OMEGA
from rotrod_core.live.execution import (
    CANCELED,
    Tracking,
    TrajectoryExecution,
    TrajectoryGoal,
    TrajectoryOutcome,
)
from rotrod_core.live.world import NON_FINITE, TOO_FAR, BlockRecord, World
from rotrod_core.model.description import DEFAULT_LIMITS, DriveLimits
from rotrod_core.model.equations import (
    STATE_FIELDS,
    Coefficients,
    State,
    check_coupling,
    check_rotary_inertia,
    make_state,
)
from rotrod_core.model.kinematics import TipMotion, tip_motion
from rotrod_core.model.params import RodParams
from rotrod_core.numerics.checks import NonFiniteStateError, finite_number

DRIVES = ('velocity', 'torque', 'servo')

OK, WARN, ERROR = 0, 1, 2
"""Health levels (the values of diagnostic_msgs/DiagnosticStatus)."""

STEP_RESOLUTION = 0.5
"""Largest dt x |lambda| allowed for the fastest deflection mode (RK4 phase error
per radian of that mode ~ (dt |lambda|)^4 / 120, here below 0.06 %)."""


MAX_DEFLECTION_RATIO = 0.1
"""Default model-validity bound on |r| / l (tip deflection over rod length).

The model is linear (small-deflection Euler-Bernoulli): it keeps the mass at the rod's
height and the tip stiffness at 3 E I / l^3 whatever the deflection. On the static
cantilever shape phi = (3 xi^2 - xi^3) / 2 a tip deflection delta shortens the rod's
height by (1/2) integral of (delta phi')^2 dx = 0.6 delta^2 / l, so its relative
foreshortening is 0.6 (delta / l)^2: 0.6 % at delta = 0.1 l (see
:func:`foreshortening`), the order of the neglected geometric terms. Beyond that
the linear model is no longer a small-deflection model; the simulation halts there."""

FORESHORTENING_FACTOR = 0.6
"""Height lost by a cantilever's tip per (deflection^2 / length), 1: integral over the
static shape of (1/2) phi'(x)^2 dx times l, = 3/5."""


def foreshortening(deflection_ratio):
    """Relative drop of the tip's height, dz / l, at a tip deflection ``delta / l`` (1).

    Second order in the deflection on the static cantilever shape: 0.6 (delta / l)^2.

    Model: docs/model.md#validity.
    """
    return FORESHORTENING_FACTOR * np.square(deflection_ratio)


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
        drive: ``'velocity'`` (w follows setpoints: an ideal drive), ``'torque'``
            (free rotation under the commanded torque) or ``'servo'`` (a PI speed loop
            with a torque limit follows the setpoints, :mod:`rotrod_core.live.drive`).
        coupling: ``'exact'`` or ``'paper'`` (see :mod:`rotrod_core.model.equations`).
        physics_rate: fixed integration rate, Hz (step dt = 1 / physics_rate).
        max_angular_acceleration: bound on |w'| when following setpoints, rad/s^2.
            The hub's angular acceleration bends the rod backwards: quasi-statically
            v = -w' r0 Me / k2 (Me = m for a massless rod; 0.68 mm per rad/s^2 for
            Table 1), up to twice that when w' is applied suddenly. A bound whose
            quasi-static bending alone exceeds the validity bound
            (``max_deflection_ratio`` x l) is refused.
        max_omega: largest |w| accepted as a setpoint, and reached in torque drive
            before the simulation halts, rad/s. The step is sized for it (see
            ``physics_rate``), so beyond it the integration is not trusted.
        max_torque: largest |Q| accepted as a torque command, N m; the servo's
            torque limit.
        servo_bandwidth: the servo's closed-loop natural frequency for a rigid hub, Hz
            (> 0, at most half the physics rate).
        servo_damping: the servo's closed-loop damping ratio (> 0).
        bearing_viscous_friction: the hub bearing's viscous friction c, N m s/rad.
        bearing_coulomb_friction: the hub bearing's Coulomb friction Q_c, N m.
        deflection_limit: the critical deflection, m (the paper's 3 mm, the
            criterion behind its critical speed): while |r| = sqrt(u^2 + v^2) is
            beyond it, health is ERROR ("beyond the critical deflection"), naming
            when the tip first crossed it and the peak so far; the simulation goes
            on and accepts commands.
        warn_fraction: fraction of ``deflection_limit`` above which health is WARN.
        max_deflection_ratio: model-validity bound on |r| / l: beyond it the
            simulation halts at the last good state until a reset (0 = no bound).
            Default :data:`MAX_DEFLECTION_RATIO` (0.1: 30 mm for Table 1).
        critical_margin: relative distance to a critical speed within which health
            is WARN (0.05 = within 5 %).
        setpoint_delay: lag of the shaped w behind the setpoint stream, s (at least
            two stream intervals); delivery jitter up to the lag minus one interval
            does not reach w (see :class:`~rotrod_core.command.shaping.OmegaSetpointShaper`).
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
    max_angular_acceleration: float = DEFAULT_MAX_ANGULAR_ACCELERATION
    max_omega: float = DEFAULT_LIMITS.max_omega
    max_torque: float = DEFAULT_LIMITS.max_torque
    deflection_limit: float = DEFAULT_LIMITS.deflection_limit
    warn_fraction: float = 0.8
    max_deflection_ratio: float = MAX_DEFLECTION_RATIO
    critical_margin: float = 0.05
    setpoint_delay: float = 0.05
    initial: tuple = ()
    command_timeout: float = 0.0
    servo_bandwidth: float = 5.0
    servo_damping: float = 1.0
    bearing_viscous_friction: float = 0.0
    bearing_coulomb_friction: float = 0.0

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
        for name in ('servo_bandwidth', 'servo_damping'):
            set_(self, name, finite_number(name, getattr(self, name), positive=True))
        if self.servo_bandwidth > 0.5 * self.physics_rate:
            raise ValueError(f'servo_bandwidth {self.servo_bandwidth:g} Hz is beyond half the '
                             f'physics rate ({0.5 * self.physics_rate:g} Hz): a loop closed '
                             'at the physics rate cannot have it')
        for name in ('critical_margin', 'max_deflection_ratio', 'bearing_viscous_friction',
                     'bearing_coulomb_friction'):
            set_(self, name, finite_number(name, getattr(self, name), nonnegative=True))
        if self.max_deflection_ratio > 1:
            raise ValueError(f'max_deflection_ratio must be in [0, 1] (|r| / rod length; '
                             f'0 = no bound), got {self.max_deflection_ratio!r}')
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
        if bend > self.max_deflection:
            raise ValueError(
                f'max_angular_acceleration {self.max_angular_acceleration:g} rad/s^2 bends the '
                f'rod tangentially by {bend * 1e3:.3g} mm (quasi-static w\' r0 Me / k2), beyond '
                f'the model\'s validity bound {self.max_deflection * 1e3:.3g} mm '
                f'(max_deflection_ratio {self.max_deflection_ratio:g} x rod length): every '
                'ramp at that rate would halt the simulation')
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
        if self.drive != 'velocity':
            check_rotary_inertia(self.params, self.coupling, state)
        if abs(float(state.omega)) > self.max_omega:
            raise ValueError(f'initial omega {state.omega:g} rad/s exceeds max_omega '
                             f'{self.max_omega:g} rad/s')
        r = math.hypot(state.u, state.v)
        if r > self.max_deflection:
            raise ValueError(f'initial deflection {r:g} m exceeds the model\'s validity bound '
                             f'{self.max_deflection:g} m (max_deflection_ratio '
                             f'{self.max_deflection_ratio:g} x rod length)')
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
    def drive_limits(self) -> DriveLimits:
        """The limits a command must stay within, as the robot description carries them."""
        return DriveLimits(self.max_angular_acceleration, self.max_omega, self.max_torque,
                           self.deflection_limit)

    @property
    def max_deflection(self) -> float:
        """Validity bound on |r|, m: ``max_deflection_ratio`` x rod length (inf: none)."""
        if not self.max_deflection_ratio:
            return math.inf
        return self.max_deflection_ratio * float(self.params.rod_length)

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


class _Deflections(NamedTuple):
    """Deflections of a block (what :meth:`SimulationEngine._watch_block` reads)."""

    r: np.ndarray
    r_max: float
    r_min: float


class SimulationEngine:
    """One rod simulated in fixed steps on its world's clock, driven by timestamped commands.

    The simulated clock :attr:`time` (s, the world's) starts at 0 and only moves
    forward, but for :meth:`reset_time` (:meth:`reset` returns the state, not the
    clock, to the start). Commands may carry a time ``at`` (s, not before :attr:`time`):
    they take effect then, so a front end that advances in batches of steps still
    applies each command at the instant it arrived.

    Args:
        config: the rod, its drive and limits.
        world: the world it joins as ``name`` (default: a world of its own, which
            :meth:`step` and :meth:`advance` step).
    """

    def __init__(self, config: EngineConfig | None = None, *, world: World | None = None,
                 name: str = 'rod'):
        self.config = config if config is not None else EngineConfig()
        self.world = World(self.config.physics_rate) if world is None else world
        self.name = name
        self._coefficients = Coefficients.from_params(self.config.params)
        self._state = self.config.initial_state
        self.halted: str | None = None
        self._reset_watch()
        self.rejected_commands = 0
        self.accepted_commands = 0
        self.late_setpoints = 0
        """Angular-velocity setpoints that arrived after their due time (a stall of the
        stream longer than ``setpoint_delay``): meanwhile w followed the stream's
        extrapolation, or returned to the last setpoint after the shaper's longest stall,
        so the shaped w was not the stream's delayed interpolation."""
        self.timeouts = 0
        """Number of command-timeout events so far (see :attr:`timed_out_at`)."""
        self.execution: TrajectoryExecution | None = None
        """The trajectory being executed (velocity drive), if any."""
        self._pending_goal: TrajectoryGoal | None = None
        self.trajectory_outcomes: deque[TrajectoryOutcome] = deque()
        """How trajectory goals ended, oldest first, for the host to take."""
        self._reset_commands()
        self._cache_limits()
        self.world.add(name, self)

    # ----------------------------------------------------------------- construction
    def _reset_watch(self) -> None:
        """Forget crossings of the critical deflection and the peak (start and reset)."""
        self.peak_deflection = self.deflection
        """Largest |r| since the start or the last reset, m."""
        self.peak_deflection_at = self.time
        """Simulated time of :attr:`peak_deflection`, s."""
        self.first_crossed_at: float | None = None
        """When |r| first went beyond ``deflection_limit`` since the start or reset, s."""
        self.beyond_limit_since: float | None = None
        """Start of the current excursion beyond ``deflection_limit`` (None: within), s."""
        self.limit_crossings = 0
        """Excursions beyond ``deflection_limit`` since the start or the last reset."""
        self._watch_deflection(self.deflection)

    def _reset_commands(self) -> None:
        cfg = self.config
        self._shaper = OmegaSetpointShaper(cfg.max_angular_acceleration,
                                           delay=cfg.setpoint_delay,
                                           omega=float(self.state.omega), time=self.time)
        self._torque_schedule: deque = deque()
        self.torque_command = 0.0
        self._torque = (0.0 if cfg.drive != 'velocity' else float(model.hub_torque(
            self._coefficients, self._state, 0.0, cfg.coupling)))
        self._servo_integral = 0.0
        """The servo's integral term, N m (servo drive; carried from block to block)."""
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
        self._w0 = float(p.natural_frequency) if has_eq28(p) else None
        """w0, rad/s, where Eq. 28 gives the frequencies (None: the eigen analysis)."""

    # ----------------------------------------------------------------- state
    @property
    def time(self) -> float:
        """Simulated time, s (the world's)."""
        return self.world.time

    @property
    def dt(self) -> float:
        """Integration step, s."""
        return self.config.dt

    @property
    def state(self) -> State:
        """Current state (u, v, du, dv, theta, omega), SI units."""
        return self._state

    @property
    def torque(self) -> float:
        """Hub torque, N m.

        The applied torque in torque drive; in velocity drive, the torque the drive
        must supply to impose w'.
        """
        return self._torque

    @property
    def coefficients(self) -> Coefficients:
        """The equations' coefficients of the rod in use."""
        return self._coefficients

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

    def set_state(self, **values) -> State:
        """Set some of the state by name (the others kept): a rod moved by hand.

        Validated like an initial state (finite; within the validity bound and
        ``max_omega``: ValueError). The commands start afresh from the new motion
        (velocity drive holds the new w; a trajectory ends), the deflection watch
        judges the new deflection.
        """
        state = make_state({**self._state._asdict(), **values}, scalar=True)
        cfg = self.config
        r = math.hypot(state.u, state.v)
        if r > cfg.max_deflection:
            raise ValueError(f'deflection {r:g} m is beyond the model\'s validity bound '
                             f'{cfg.max_deflection:g} m')
        omega = float(state.omega)
        if abs(omega) > cfg.max_omega:
            raise ValueError(f'|omega| {abs(omega):g} rad/s exceeds max_omega '
                             f'{cfg.max_omega:g} rad/s')
        self._state = state
        self._end_goals(INVALID_GOAL, 'the state was set')
        self._reset_commands()
        self._watch_deflection(r)
        return state

    def _finite(self, what: str, *values) -> None:
        if not all(math.isfinite(x) for x in values):
            raise NonFiniteStateError(f'the {what} of the state {tuple(self._state)} '
                                      f'overflows: {values}')

    def inertial_position(self) -> tuple:
        """Position (x, y, z) of the mass in the inertial frame, m (z = rod length).

        A quantity of the (always finite) state that overflows raises
        :class:`NonFiniteStateError`, as do :meth:`energy` and :meth:`angular_momentum`.
        """
        s = self._state
        x, y = (float(c) for c in model.inertial_position(self._coefficients, s.u, s.v,
                                                           s.theta))
        self._finite('inertial position', x, y)
        return x, y, float(self.config.params.rod_length)

    def tip_motion(self) -> TipMotion:
        """The tip mass's pose, velocity and acceleration in the world frame (SI units).

        w' is the hub's over the last step (:attr:`omega_dot`).
        """
        return tip_motion(self._coefficients, self.state, self._omega_dot,
                          float(self.config.params.rod_length))

    def energy(self) -> float:
        """Total mechanical energy, J."""
        e = float(model.energy(self._coefficients, self._state))
        self._finite('energy', e)
        return e

    def angular_momentum(self) -> float:
        """Angular momentum about the axis, kg m^2/s."""
        L = float(model.angular_momentum(self._coefficients, self._state))
        self._finite('angular momentum', L)
        return L

    def frequencies(self, omega: float | None = None) -> tuple:
        """Dynamic frequencies (f1, f2) in Hz of the rod in use (Eq. 28 or eigen analysis).

        At w = ``omega`` rad/s (default: the current w).
        """
        w = self.state.omega if omega is None else omega
        if self._w0 is not None:
            return eq28(self._w0, w)
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
        if self.config.drive not in (FOLLOWS_OMEGA if drive == 'velocity' else (drive,)):
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
        self._end_goals(INVALID_GOAL, 'preempted by an angular-velocity setpoint')
        late = self._shaper.late_setpoints
        try:
            self._shaper.command(w, t)
        except ValueError as exc:       # beyond what the shaper can represent
            self._reject(str(exc))
        self.late_setpoints += self._shaper.late_setpoints - late
        self._accepted(t)

    def command_torque(self, torque, at=None) -> None:
        """Hub torque (N m) from time ``at`` (s) on; torque drive."""
        q = self._check_command('torque', torque, 'torque', self.config.max_torque, 'N m')
        t = self._command_time(at)
        if self._torque_schedule and self._torque_schedule[-1][0] > t:
            t = self._torque_schedule[-1][0]
        self._torque_schedule.append((t, q))
        self._accepted(t)

    # ----------------------------------------------------------------- trajectories
    def command_trajectory(self, goal: TrajectoryGoal, at=None) -> None:
        """Execute ``goal`` from its start time (or ``at``, s, its arrival); velocity drive.

        It starts at the step instant nearest its start (now, if that has passed): from
        the hub's state then, a running goal is ended (INVALID_GOAL, preempted). Points
        whose time has already passed (a stamp in the past) are left out. Every refusal
        is an outcome in :attr:`trajectory_outcomes`, as is the goal's end.
        """
        t = self._command_time(at)
        if self.config.drive not in FOLLOWS_OMEGA:
            self._outcome(goal, INVALID_GOAL, f'the drive is {self.config.drive!r}: a '
                          'trajectory of the hub needs the velocity or servo drive (set '
                          "drive to 'velocity' or 'servo')")
            return
        if self.halted:
            self._outcome(goal, INVALID_GOAL, f'the simulation is halted ({self.halted}); '
                          'reset first')
            return
        start = t if goal.start_time is None else goal.start_time
        end = start + goal.points[-1].time
        if end < self.time:
            self._outcome(goal, OLD_HEADER_TIMESTAMP, f'the trajectory ended at simulated '
                          f'time {end:.6f} s, before now ({self.time:.6f} s): its header '
                          'stamp is too old')
            return
        self._end_goals(INVALID_GOAL, 'preempted by a new trajectory goal')
        self._pending_goal = goal
        self._start_goal_if_due(self.time)
        self.accepted_commands += 1

    def cancel_trajectory(self, token) -> None:
        """Cancel the goal with ``token`` if it is pending or executing: w holds."""
        pending, ex = self._pending_goal, self.execution
        if pending is not None and pending.token is token:
            self._pending_goal = None
            self._outcome(pending, CANCELED, 'cancelled before it started')
        elif ex is not None and ex.goal.token is token:
            self._finish_execution(TrajectoryOutcome(
                token, CANCELED, f'cancelled at {self.time - ex.start:.6g} s of the '
                f'trajectory: holding w = {float(self.state.omega):.6g} rad/s'))

    def _goal_start(self, goal: TrajectoryGoal) -> float:
        return goal.start_time if goal.start_time is not None else self.time

    def _start_goal_if_due(self, t: float) -> None:
        """Start the pending goal at step instant ``t`` (s) if its start is due by then."""
        goal = self._pending_goal
        if goal is None or (goal.start_time is not None
                            and goal.start_time > t + 0.5 * self.config.dt):
            return
        self._pending_goal = None
        elapsed = t - self._goal_start(goal)
        points = goal.points
        if elapsed > 0:                     # a stamp in the past: the points still ahead
            points = tuple(TrajectoryPoint(p.time - elapsed, p.position, p.velocity,
                                           p.acceleration) for p in points if p.time > elapsed)
        cfg, state = self.config, self.state
        omega = float(state.omega)
        try:
            trajectory = HubTrajectory(
                points, HubState(float(state.theta), omega, self._omega_dot),
                max_omega=cfg.max_omega, max_angular_acceleration=cfg.max_angular_acceleration,
                start_tolerance=(abs(omega) * cfg.dt + 1e-9,
                                 cfg.max_angular_acceleration * cfg.dt))
        except TrajectoryRejected as exc:
            self._outcome(goal, exc.code, str(exc))
            return
        self.execution = TrajectoryExecution(goal, trajectory, t)
        self.timed_out_at = None

    def _outcome(self, goal: TrajectoryGoal, code: str, message: str) -> None:
        self.trajectory_outcomes.append(TrajectoryOutcome(goal.token, code, message))

    def _finish_execution(self, outcome: TrajectoryOutcome) -> None:
        """End the execution with ``outcome``: w holds where it is (the shaper's)."""
        self.trajectory_outcomes.append(outcome)
        self.execution = None
        cfg = self.config
        self._shaper = OmegaSetpointShaper(cfg.max_angular_acceleration,
                                           delay=cfg.setpoint_delay,
                                           omega=float(self.state.omega), time=self.time)
        self._restart_timer()

    def _end_goals(self, code: str, message: str) -> None:
        """End the pending and the executing goal, if any, with ``code`` and ``message``."""
        if self._pending_goal is not None:
            self._outcome(self._pending_goal, code, message + ' (before it started)')
            self._pending_goal = None
        if self.execution is not None:
            self._finish_execution(TrajectoryOutcome(self.execution.goal.token, code,
                                                     message))

    def _recheck_execution(self) -> None:
        """After a change of limits: end the execution if it now goes beyond them."""
        ex, cfg = self.execution, self.config
        assert ex is not None
        tr = ex.trajectory
        for what, value, limit in (('|w|', tr.peak, cfg.max_omega),
                                   ("|w'|", tr.max_angular_acceleration,
                                    cfg.max_angular_acceleration)):
            if value > limit * (1.0 + 1e-9):
                self._finish_execution(TrajectoryOutcome(
                    ex.goal.token, INVALID_GOAL, f'the limits changed: the trajectory\'s '
                    f'{what} {value:.6g} is beyond the new limit {limit:g}'))
                return

    def tracking(self) -> Tracking | None:
        """The executing trajectory's desired and actual hub state now (None: no goal)."""
        ex = self.execution
        if ex is None:
            return None
        s = self.state
        return ex.tracking(self.time, float(s.theta), float(s.omega), self._omega_dot)

    def _track(self, omega_dot: float) -> None:
        """After a step: check the executing goal's tolerances; end it when it is over."""
        ex = self.execution
        assert ex is not None
        if self.time < ex.end - 1e-9 * self.config.dt and not ex.checks_path:
            return
        s = self.state
        outcome = ex.check(ex.tracking(self.time, float(s.theta), float(s.omega), omega_dot))
        if outcome is not None:
            self._finish_execution(outcome)

    def _accepted(self, t: float) -> None:
        """A command taking effect at time ``t`` was accepted: it restarts the timeout."""
        self._last_command = max(self._last_command, t)
        self.timed_out_at = None
        self.accepted_commands += 1

    def _timeout_step(self, t0: float, steps: int) -> int | None:
        """Start a timeout event if the command timeout runs out within the block.

        The block is ``steps`` steps from ``t0`` (s). Velocity drive: w ramps to 0 at the
        acceleration limit from the instant the timeout runs out (through the setpoint
        shaper, so w is continuous and |w'| bounded). Torque drive: the torque is 0 from
        the step in which it runs out (commands apply at step instants too); returns
        that step's index in the block (None: no timeout in it).
        """
        timeout = self.config.command_timeout
        if (not timeout or self.timed_out_at is not None or self.execution is not None
                or self._pending_goal is not None):
            return None
        dt = self.config.dt
        deadline = self._last_command + timeout
        if self.config.drive in FOLLOWS_OMEGA:
            if deadline > t0 + steps * dt:
                return None
            self.timed_out_at = max(deadline, t0)
            self._shaper.ramp_to(0.0, self.timed_out_at)
            self.timeouts += 1
            return None
        k = max(0, math.ceil((deadline - t0) / dt - 0.5))
        if k >= steps:
            return None
        self.timed_out_at = t0 + k * dt
        self.torque_command = 0.0
        self.timeouts += 1
        return k

    # ----------------------------------------------------------------- stepping
    # The world steps its rods together, in blocks (rotrod_core/live/world.py): each
    # rod says how far it can plan (_block_limit) and what drives it over the block
    # (_block_inputs), and takes the states the world computed (_block_done).

    def _block_limit(self, t0: float, steps: int) -> int:
        """How many of ``steps`` steps from ``t0`` (s) can be planned now (>= 1).

        A trajectory that starts or ends within them ends the block at that step (the
        start needs the hub's state then; the end changes what drives it), and one whose
        path is checked goes a step at a time.
        """
        dt = self.config.dt
        goal = self._pending_goal
        if goal is not None and goal.start_time is not None:
            k = math.ceil((goal.start_time - t0) / dt - 0.5)
            if k > 0:
                return min(steps, k)
        ex = self.execution
        if ex is not None:
            if ex.checks_path or t0 >= ex.end - 1e-9 * dt:
                return 1
            return max(1, min(steps, math.ceil((ex.end - t0) / dt - 1e-9)))
        return steps

    def _block_inputs(self, t0: float, steps: int):
        """What drives the hub over the block of ``steps`` steps from ``t0`` (s).

        Velocity drive: the target w (rad/s) at the end of each step (its trajectory's,
        or the shaped setpoints'); torque drive: the hub torque (N m) over each step.
        As an array of ``steps`` values, or compactly (what most blocks are): a float,
        the same value for every step, or a tuple (w0, w1, t0, t1), the linear piece
        w0 + (w1 - w0) ((t - t0) / (t1 - t0)) at each step's end t.
        """
        if self._pending_goal is not None:
            self._start_goal_if_due(t0)
        dt = self.config.dt
        torque = self.torque_command                     # torque drive, before a timeout
        timeout = self._timeout_step(t0, steps)
        if self.config.drive in FOLLOWS_OMEGA:
            ex = self.execution
            if ex is not None:
                times = t0 + dt * np.arange(1, steps + 1)
                # the step that ends at the last point's time (to rounding) ends at its
                # speed exactly: w then holds the goal's final speed, not 1e-14 beside it
                taus = np.where(times >= ex.end - 1e-9 * dt, ex.trajectory.end_time,
                                times - ex.start)
                return np.asarray(ex.trajectory.omega(taus), dtype=float)
            held = self._shaper.held(t0 + dt)
            if held is not None:
                return held
            piece = self._shaper.segment(t0 + dt, t0 + steps * dt)
            if piece is not None:
                return piece
            return self._shaper.omegas(t0 + dt * np.arange(1, steps + 1))
        schedule = self._torque_schedule
        if not schedule and timeout is None:
            return torque
        torques = np.full(steps, torque)
        while schedule and schedule[0][0] <= t0 + (steps - 0.5) * dt:
            t, q = schedule.popleft()
            torques[max(0, math.ceil((t - t0) / dt - 0.5)):] = q
            self.torque_command = q
        if timeout is not None:
            torques[timeout:] = 0.0
            self.torque_command = 0.0
        return torques

    def _block_done(self, t0: float, record: BlockRecord) -> None:
        """Take the states of the block from ``t0`` (s) the world computed."""
        n = record.taken
        if n:
            last = record.last
            self._state = State(*last[:6])
            self._omega_dot, self._torque = last[6], last[7]
            self._watch_block(record, t0)
        if record.rejected is not None:
            self._halt(t0 + (n + 1) * self.config.dt, *record.rejected)
            return
        if self.execution is not None and n:
            self._track(self._omega_dot)
        if self._shaper.ramp_count > 1:         # a 10 kHz stream leaves a ramp per setpoint
            self._shaper.forget_before(self.time)

    def _halt(self, t: float, reason: int, refused: tuple, drive_value: float) -> None:
        """Halt at the last good state: the step ending at ``t`` (s) was refused."""
        cfg = self.config
        if reason == NON_FINITE:
            self.halted = f'non-finite state at t = {t:.6f} s'
        else:
            u, v, omega = refused[0], refused[1], refused[5]
            if reason == TOO_FAR:
                problem = (f'deflection {math.hypot(u, v) * 1e3:.4g} mm beyond the model\'s '
                           f'validity bound {cfg.max_deflection * 1e3:.4g} mm '
                           f'(max_deflection_ratio {cfg.max_deflection_ratio:g} x rod '
                           f'length; small-deflection model) at t = {t:.4f} s')
            else:
                problem = (f'|omega| {abs(omega):.4g} rad/s beyond max_omega '
                           f'{cfg.max_omega:.4g} rad/s at t = {t:.4f} s')
            self.halted = problem + '; halted at the last good state'
        self._end_goals(PATH_TOLERANCE_VIOLATED, f'the simulation halted: {self.halted}')
        self.world.changed()

    def _watch_block(self, record, t0: float) -> None:
        """:meth:`_watch_deflection` over a block's steps from ``t0`` (s).

        ``record``: its ``r`` (the deflection at each step, m), ``r_max`` and ``r_min``.
        """
        dt, r_max, limit = self.config.dt, record.r_max, self.config.deflection_limit
        if r_max > self.peak_deflection:
            i = int(np.argmax(record.r))
            self.peak_deflection, self.peak_deflection_at = r_max, t0 + (i + 1) * dt
        if r_max <= limit:
            self.beyond_limit_since = None
            return
        if record.r_min > limit and self.beyond_limit_since is not None:
            return                  # beyond it all along: no crossing, still beyond since
        r = record.r
        above = r > limit
        times = t0 + dt * np.arange(1, len(r) + 1)
        before = np.concatenate(([self.beyond_limit_since is not None], above[:-1]))
        starts = np.flatnonzero(above & ~before)
        if len(starts):
            self.limit_crossings += len(starts)
            if self.first_crossed_at is None:
                self.first_crossed_at = float(times[starts[0]])
        if not above[-1]:
            self.beyond_limit_since = None
        elif len(starts):
            self.beyond_limit_since = float(times[starts[-1]])

    def _watch_deflection(self, r: float) -> None:
        """Follow the critical-deflection criterion: crossings, and the peak so far."""
        self._watch_block(_Deflections(np.array([r]), r, r), self.time - self.config.dt)

    def _own_world(self) -> World:
        if len(self.world) != 1:
            raise RuntimeError(f'{self.name} is one of {len(self.world)} rods of a world: '
                               'step the world')
        return self.world

    def step(self) -> bool:
        """Advance one step; False (and no change) if halted or the step was refused.

        For a rod in a world of its own (else :meth:`World.advance`).
        """
        return self._own_world().advance(1) == 1

    def advance(self, steps: int) -> int:
        """Take up to ``steps`` steps (fewer if halted); return how many were taken."""
        return self._own_world().advance(steps)

    def steps_until(self, t: float) -> int:
        """Number of whole steps from :attr:`time` to reach time ``t`` (s), >= 0."""
        return self.world.steps_until(t)

    def advance_to(self, t: float) -> int:
        """Take the whole steps that do not pass time ``t`` (s); return how many."""
        return self.advance(self.steps_until(t))

    # ----------------------------------------------------------------- control
    def reset(self) -> None:
        """Back to the configured initial state (clock keeps running); clears a halt."""
        self._state = self.config.initial_state
        self.halted = None
        self._end_goals(INVALID_GOAL, 'the simulation was reset')
        self._reset_commands()
        self._reset_watch()
        self.world.changed()

    def reset_time(self) -> None:
        """Simulated time back to 0, keeping the state; commands start afresh.

        The world's clock (every rod's): see :meth:`_time_reset` for what a rod does.
        """
        self.world.reset_time()

    def _time_reset(self) -> None:
        """The world's time went back to 0: commands start afresh.

        The setpoint shaper and the torque schedule hold times: they restart from the
        current motion (velocity drive holds the current w, torque drive has zero
        torque), as after :meth:`reset`; the command timeout and the deflection watch
        count from 0. With :meth:`reset` too, the session is as at its start.
        """
        self._end_goals(INVALID_GOAL, 'the simulated time was reset')
        self._reset_commands()
        self._reset_watch()

    def reconfigure(self, config: EngineConfig) -> None:
        """Switch to ``config`` (already validated), keeping the state and the clock.

        A change of drive starts the new drive from the current motion: velocity
        drive holds the current w, torque drive starts with zero torque. A change of
        drive, ``max_angular_acceleration``, ``setpoint_delay`` or ``command_timeout``
        restarts the command timeout and ends a timeout event in course (velocity
        drive then holds the w reached; torque drive keeps zero torque). A new
        ``deflection_limit`` judges the current deflection against it at once; a
        validity bound below the current deflection halts the next step. A new
        ``physics_rate`` is the world's: allowed for a rod alone in its world.
        """
        if not isinstance(config, EngineConfig):
            raise ValueError(f'config must be an EngineConfig, got {config!r}')
        if config.physics_rate != self.world.physics_rate:
            self._own_world().set_physics_rate(config.physics_rate)
        time = self.time
        old = self.config
        self.config = config
        self._coefficients = Coefficients.from_params(config.params)
        if config.drive != old.drive:
            self._end_goals(INVALID_GOAL, f'the drive changed to {config.drive!r}')
        elif self.execution is not None:
            self._recheck_execution()
        if (config.drive != old.drive
                or config.max_angular_acceleration != old.max_angular_acceleration
                or config.setpoint_delay != old.setpoint_delay):
            self._reset_commands()
        elif config.command_timeout != old.command_timeout:
            if self.timed_out_at is not None and config.drive in FOLLOWS_OMEGA:
                self._shaper.ramp_to(self._shaper.omega(time), time)    # hold w here
            self._restart_timer()
        if config.deflection_limit != old.deflection_limit:
            self._watch_deflection(self.deflection)     # an excursion is judged anew
        self._cache_limits()
        self.world.changed()

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
        """The session's health level, its reason and the values behind them.

        :meth:`condition`'s level and message with :meth:`status_values`.
        """
        level, message = self.condition()
        return Health(level, message, self.status_values())

    def status_values(self) -> tuple:
        """(name, value) pairs of the session's state and counters, SI units in names."""
        cfg, s = self.config, self.state
        return (('time_s', self.time), ('omega_rad_s', s.omega), ('u_m', s.u), ('v_m', s.v),
                ('deflection_m', self.deflection),
                ('deflection_limit_m', cfg.deflection_limit),
                ('hub_torque_Nm', self.torque), ('drive', cfg.drive),
                ('coupling', cfg.coupling),
                *((f'critical_speed_{k}_rad_s', v) for k, v in self.critical_speeds.items()),
                ('accepted_commands', self.accepted_commands),
                ('rejected_commands', self.rejected_commands),
                ('late_setpoints', self.late_setpoints),
                ('command_timeout_s', cfg.command_timeout),
                ('command_age_s', self.command_age), ('command_timeouts', self.timeouts),
                ('peak_deflection_m', self.peak_deflection),
                ('peak_deflection_time_s', self.peak_deflection_at),
                ('critical_deflection_first_crossed_s',
                 'never' if self.first_crossed_at is None else self.first_crossed_at),
                ('critical_deflection_crossings', self.limit_crossings),
                ('max_deflection_m', cfg.max_deflection),
                ('halted', self.halted or 'no'))

    def condition(self) -> tuple[int, str]:
        """The session's health level and its reason, without the values (cheap).

        ERROR when halted, or while the deflection is beyond ``deflection_limit`` (the
        critical deflection: the simulation goes on); WARN when the deflection is
        above ``warn_fraction`` of it, |w| is near a critical speed, w is in an
        unstable range, or the command timeout has run out (until a command comes);
        else OK. Whatever the level, every other reason is in the message too.
        """
        if self.halted:
            return ERROR, self.halted
        reasons = self._reasons()
        errors = [text() for level, text in reasons if level == ERROR]
        warnings = [text() for level, text in reasons if level == WARN]
        if errors:
            return ERROR, '; '.join(errors + warnings)
        if warnings:
            return WARN, '; '.join(warnings)
        return OK, 'running'

    def level(self) -> int:
        """The level of :meth:`condition`, its message not written.

        Cheaper still: a world looks at every rod's level several times a second.
        """
        if self.halted:
            return ERROR
        return max((level for level, _ in self._reasons()), default=OK)

    def _reasons(self) -> list[tuple[int, Callable[[], str]]]:
        """Each reason for a level above OK but a halt: (level, its text when asked)."""
        cfg = self.config
        omega = float(self.state.omega)
        r, w = self.deflection, abs(omega)
        reasons: list[tuple[int, Callable[[], str]]] = []
        beyond = self.beyond_limit_since is not None
        if beyond:
            reasons.append((ERROR, lambda: (
                f'deflection {r * 1e3:.4g} mm beyond the critical deflection '
                f'{cfg.deflection_limit * 1e3:.4g} mm (deflection_limit) since '
                f't = {self.beyond_limit_since:.3f} s; first crossed at '
                f't = {self.first_crossed_at:.3f} s, peak {self.peak_deflection * 1e3:.4g} mm '
                f'at t = {self.peak_deflection_at:.3f} s; still running')))
        if self.timed_out_at is not None:
            if cfg.drive == 'torque':
                action = 'hub torque 0, coasting'
            elif self._shaper.target_reached_at > self.time:
                action = 'spinning down'
            else:
                action = 'spun down, at rest'
            reasons.append((WARN, lambda: (
                f'no command for {self.command_age:.3g} s (command_timeout '
                f'{cfg.command_timeout:g} s): {action}')))
        if r > cfg.warn_fraction * cfg.deflection_limit and not beyond:
            reasons.append((WARN, lambda: (
                f'deflection {r * 1e3:.3g} mm above {cfg.warn_fraction:.0%} of '
                f'the {cfg.deflection_limit * 1e3:.3g} mm limit')))
        for name, wc in self.critical_speeds.items():
            if abs(w - wc) <= cfg.critical_margin * wc:
                reasons.append((WARN, partial(_near_critical, w, wc, cfg.critical_margin, name)))
        if not self.stable_at(omega):
            reasons.append((WARN, lambda: (f'omega {omega:.4g} rad/s is in an unstable '
                                           'range: the free vibration grows')))
        return reasons


def _near_critical(w: float, wc: float, margin: float, name: str) -> str:
    return (f'|omega| {w:.4g} rad/s within {margin:.0%} of the critical speed {wc:.4g} '
            f'rad/s ({name.replace("_", " ")})')


__all__ = ['CommandRejected', 'DRIVES', 'ERROR', 'EngineConfig', 'Health',
           'MAX_DEFLECTION_RATIO', 'OK', 'foreshortening',
           'STATE_FIELDS', 'SimulationEngine', 'WARN', 'fastest_rate']
