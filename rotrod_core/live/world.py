"""A world of rods on one simulated clock, stepped as one batch.

Every rod is a :class:`~rotrod_core.live.engine.SimulationEngine`: its own drive,
commands, shaping, trajectory, alarms and halt. The world owns the clock and the
physics: it advances all rods together at one ``physics_rate``, through the one
propagation kernel (:func:`~rotrod_core.numerics.rk4.rk4_step_prescribed_rotation`
and :func:`~rotrod_core.numerics.rk4.rk4_step` over
:func:`~rotrod_core.model.equations.deflection_accelerations`), vectorised across the
rods of each drive: a step is one pass of numpy over all of them, never a Python loop
per rod.

It works in blocks of steps (up to the next publication), as Gazebo's systems run
commands -> physics -> checks over every entity at once:

1. each rod says what drives it over the block (:meth:`SimulationEngine._block_inputs
   <rotrod_core.live.engine.SimulationEngine._block_inputs>`): the hub's target w at
   every step instant (velocity drive: its setpoint shaping or trajectory, vectorised
   over the block) or its torque at every step (torque drive); a rod whose command
   changes course within the block (a trajectory that starts or ends) shortens the
   block to that step;
2. the world takes the block's steps, each one batched over the rods of a drive; a rod
   whose step gives a non-finite state, a deflection past its validity bound or a
   speed past its ``max_omega`` is frozen at its last good state from that step on,
   and the others go on;
3. each rod takes its block's states (:meth:`SimulationEngine._block_done
   <rotrod_core.live.engine.SimulationEngine._block_done>`): its deflection watch, its
   halt, its trajectory's end.

A single rod steps as Python floats through the same functions (numpy's per-call cost
would be ten times the arithmetic). Several rods of a torque drive step as arrays, one
pass of the kernel per step: the same arithmetic, bit for bit. Several rods of a
velocity drive, whose hub speed is prescribed, take the kernel's step as the affine map
of the deflection state it is (:meth:`_Group._run_prescribed`): the kernel computes the
maps of every step and rod of a block in one pass, and a hold reuses them, so a step
costs four multiply-adds over the rods (a hundred rods: a tenth of the per-step pass).
They agree with the rod stepped alone to rounding. Either way the world is
deterministic: the same commands at the same simulated times give the same states, bit
for bit, on every machine (elementwise numpy in a fixed order; no BLAS).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from functools import partial
from typing import Any, Protocol

import numpy as np

import rotrod_core.model.equations as model
from rotrod_core.live.drive import (
    friction_torque,
    overcome_friction,
    rigid_inertia,
    servo_gains,
    servo_torque,
)
from rotrod_core.model.equations import Coefficients
from rotrod_core.numerics.checks import finite_number
from rotrod_core.numerics.rk4 import rk4_step, rk4_step_prescribed_rotation

BLOCK_STEPS = 64
"""Most steps of one block (a caller that asks for more gets them in several)."""
NON_FINITE, TOO_FAR, TOO_FAST = 1, 2, 3
"""Why a rod's step was refused: a non-finite state (or drive value), a deflection past
the validity bound, |w| past max_omega."""


class Rod(Protocol):
    """What the world needs of a rod (:class:`~rotrod_core.live.engine.SimulationEngine`)."""

    config: Any
    halted: str | None
    _coefficients: Coefficients

    @property
    def state(self) -> tuple: ...

    def _block_limit(self, t0: float, steps: int) -> int: ...

    def _block_inputs(self, t0: float, steps: int) -> np.ndarray: ...

    def _block_done(self, t0: float, record: BlockRecord) -> None: ...

    def _time_reset(self) -> None: ...


def _stacked(coefficients: list[Coefficients]) -> Coefficients:
    """The coefficients of several rods as one batch (arrays), or the one rod's."""
    if len(coefficients) == 1:
        return coefficients[0]
    names = ('mass', 'eccentricity', 'hub_inertia', 'k1', 'k2', 'c1', 'c2', 'w1sq', 'w2sq',
             'g1', 'g2', 'modal_mass', 'eccentric_mass', 'load_radius', 'rotor_inertia')
    return Coefficients(**{n: np.array([getattr(c, n) for c in coefficients], dtype=float)
                           for n in names})


class BlockRecord:
    """The states one rod went through over a block (SI units).

    ``taken`` steps were good; ``rejected`` is (reason, the refused state, drive value)
    of the step after them, if one was refused. ``last`` holds the last good step's
    (u, v, u', v', theta, w, w', torque); ``r_max`` and ``r_min`` the largest and the
    smallest deflection sqrt(u^2 + v^2) over the block (m, 0 without steps), and
    :attr:`r` each step's (read only where needed: a crossing of the critical
    deflection).
    """

    __slots__ = ('_steps', '_index', 'last', 'r_max', 'r_min', 'taken', 'rejected')

    def __init__(self, steps: np.ndarray, index: int, taken: int, rejected, last,
                 r_max: float, r_min: float):
        self._steps, self._index = steps, index        # (steps, 9, rods): the group's
        self.taken, self.rejected, self.last = taken, rejected, last
        self.r_max, self.r_min = r_max, r_min

    @property
    def r(self) -> np.ndarray:
        """The deflection at each good step, m."""
        return self._steps[:self.taken, 8, self._index]


def _values(row, times: np.ndarray) -> np.ndarray:
    """A rod's block inputs as one value per step (see SimulationEngine._block_inputs)."""
    if isinstance(row, tuple):
        w0, w1, t0, t1 = row
        return w0 + (w1 - w0) * ((times - t0) / (t1 - t0))
    return np.broadcast_to(np.asarray(row, dtype=float), times.shape)


def _matrix(rows: list, times: np.ndarray) -> np.ndarray:
    """Block inputs of several rods as (rods, steps): the compact ones in one pass."""
    if all(isinstance(r, tuple) for r in rows):
        w0, w1, t0, t1 = (np.array(c, dtype=float)[:, None] for c in zip(*rows))
        return w0 + (w1 - w0) * ((times[None, :] - t0) / (t1 - t0))
    if all(isinstance(r, float) for r in rows):
        return np.broadcast_to(np.array(rows)[:, None], (len(rows), len(times)))
    return np.stack([_values(r, times) for r in rows])


def _records(out: np.ndarray, bad: np.ndarray, finite: np.ndarray,
             far: np.ndarray) -> list[BlockRecord]:
    """Each rod's record of a block.

    ``out`` (steps, 9, rods) as computed, ``bad`` the refused steps (steps, rods;
    ``finite`` and ``far`` say why). A rod's steps are good up to its first refused one.
    """
    steps, _, n = out.shape
    last = out[-1, :8, :].T.tolist()
    r = out[:, 8, :]
    r_max, r_min = r.max(axis=0).tolist(), r.min(axis=0).tolist()
    records = [BlockRecord(out, i, steps, None, last[i], r_max[i], r_min[i])
               for i in range(n)]
    for i in np.flatnonzero(bad.any(axis=0)).tolist():
        t = int(np.argmax(bad[:, i]))
        reason = NON_FINITE if not finite[t, i] else TOO_FAR if far[t, i] else TOO_FAST
        records[i] = _cut(out, i, t,
                          (reason, tuple(out[t, :6, i].tolist()), float(out[t, 7, i])))
    return records


def _cut(out: np.ndarray, i: int, t: int, rejected: tuple) -> BlockRecord:
    """Rod ``i``'s record of a block whose step ``t`` was refused.

    ``rejected``: as :class:`BlockRecord` holds it; the good steps are those before ``t``.
    """
    good = out[:t, 8, i]
    return BlockRecord(out, i, t, rejected, out[t - 1, :8, i].tolist() if t else None,
                       float(good.max()) if t else 0.0, float(good.min()) if t else 0.0)


class _Group:
    """Rods of one drive and coupling, stepped together (arrays, or floats for one)."""

    def __init__(self, drive: str, coupling: str, engines: list):
        self.drive, self.coupling = drive, coupling
        self.engines = engines
        self.single = len(engines) == 1
        self.co = _stacked([e._coefficients for e in engines])
        cfg = [e.config for e in engines]
        self.max_deflection = self._column([c.max_deflection for c in cfg])
        self.max_omega = self._column([c.max_omega for c in cfg])
        self._accelerations = partial(model.deflection_accelerations, self.co)
        self._torque_rates = partial(model.torque_drive_rates, self.co, coupling=coupling)
        self._maps: tuple | None = None     # a hold's affine maps (_run_prescribed)
        # the bearing's friction and the servo (rotrod_core/live/drive.py), per rod
        self.friction = any(c.bearing_viscous_friction or c.bearing_coulomb_friction
                            for c in cfg)
        self.viscous = self._column([c.bearing_viscous_friction for c in cfg])
        self.coulomb = self._column([c.bearing_coulomb_friction for c in cfg])
        self.inertia = self._column([float(rigid_inertia(e._coefficients)) for e in engines])
        self.servo = drive == 'servo'
        if self.servo:
            gains = [servo_gains(e._coefficients, c.servo_bandwidth, c.servo_damping)
                     for e, c in zip(engines, cfg)]
            self.kp = self._column([float(g[0]) for g in gains])
            self.ki = self._column([float(g[1]) for g in gains])
            self.max_torque = self._column([c.max_torque for c in cfg])
        self._integral: Any = 0.0

    def _column(self, values):
        return values[0] if self.single else np.array(values, dtype=float)

    def run(self, rows: list, times: np.ndarray, dt: float) -> list[BlockRecord]:
        """Take a step of dt (s) at each of ``times`` (their ends) under ``rows``."""
        if self.servo:          # the PI loop's integral, from the rods and back
            self._integral = self._column([e._servo_integral for e in self.engines])
        if self.friction:       # Karnopp's band: a step of Coulomb friction's speed
            self._stick = self.coulomb * dt / self.inertia
        if self.single:
            records = [self._run_one(_values(rows[0], times).tolist(), dt)]
        elif self.drive == 'velocity':
            records = self._run_prescribed(_matrix(rows, times), dt)
        else:
            records = self._run_many(_matrix(rows, times), dt)
        if self.servo:
            for i, engine in enumerate(self.engines):
                engine._servo_integral = float(self._integral if self.single
                                               else self._integral[i])
        return records

    def _velocity_torque(self, state, omega_dot):
        """The ideal velocity drive's torque, N m, at ``state`` (its w the target).

        What imposes w' on the coupled rod, and what overcomes the bearing.
        """
        torque = model.hub_torque(self.co, state, omega_dot, self.coupling)
        if self.friction:
            torque = torque + overcome_friction(self.viscous, self.coulomb, state[5])
        return torque

    def _step(self, state, value, dt: float):
        """One step of every rod: (new state, w', torque) under ``value`` per rod."""
        if self.drive == 'velocity':
            wd = (value - state[5]) / dt
            u, v, du, dv, theta, _ = rk4_step_prescribed_rotation(self._accelerations, state,
                                                                   dt, wd)
            new = (u, v, du, dv, theta, value)     # the drive imposes w: exactly its target
            return new, wd, self._velocity_torque(new, wd)
        applied = value                           # torque drive: the commanded torque
        if self.servo:                             # servo: the PI loop's, from w now
            applied, self._integral = servo_torque(self.kp, self.ki, self.max_torque,
                                                   self._integral, value, state[5], dt)
        net = applied
        if self.friction:
            # stiction holds the hub against the drive and the rod's reaction together
            load = applied
            if self.coupling == 'exact':
                load = applied + model.rod_torque_on_hub(self.co, *state[:4])
            net = applied + friction_torque(self.viscous, self.coulomb, self._stick, state[5],
                                            load)
        new = rk4_step(self._torque_rates, state, dt, net, net, net)
        wd = model.hub_angular_acceleration(self.co, new, net, self.coupling)
        return new, wd, applied

    def _run_one(self, values: list, dt: float) -> BlockRecord:
        """The block of a rod alone, in Python floats."""
        state = tuple(self.engines[0].state)
        rows: list = []
        rejected = None
        isfinite, hypot, step = math.isfinite, math.hypot, self._step
        max_deflection, max_omega = self.max_deflection, self.max_omega
        for value in values:
            try:
                new, wd, drive = step(state, value, dt)
            except ZeroDivisionError:          # no rotary inertia at all: w' undefined
                rejected = (NON_FINITE, state, math.nan)
                break
            u, v, du, dv, theta, omega = new
            if not (isfinite(u) and isfinite(v) and isfinite(du) and isfinite(dv)
                    and isfinite(theta) and isfinite(omega) and isfinite(wd)
                    and isfinite(drive)):
                rejected = (NON_FINITE, new, drive)
                break
            r = hypot(u, v)
            if r > max_deflection:
                rejected = (TOO_FAR, new, drive)
                break
            if abs(omega) > max_omega:
                rejected = (TOO_FAST, new, drive)
                break
            state = new
            rows.append((*new, wd, drive, r))
        steps = np.array(rows, dtype=float).reshape(len(rows), 9)[:, :, None]
        return BlockRecord(steps, 0, len(rows), rejected, rows[-1][:8] if rows else None,
                           max((row[8] for row in rows), default=0.0),
                           min((row[8] for row in rows), default=0.0))

    def _run_prescribed(self, inputs: np.ndarray, dt: float) -> list[BlockRecord]:
        """The block of several rods whose hub speed is prescribed (velocity drive).

        With w(t) given, a step of the kernel is affine in the deflection state
        x = (u, v, u', v'): x_{k+1} = P_k x_k + q_k. The kernel itself gives P_k and q_k,
        at every step of the block and every rod in one pass, from the step of the
        states 0 and the unit vectors (x = 0 gives q_k, x = e_j gives P_k e_j + q_k);
        the recursion is then four multiply-adds per step over the rods. theta and w
        come out of the same pass exactly as the kernel gives them (theta adds the
        same increment; w is the target). The same scheme as stepping the rods one by
        one, equal to rounding (~1e-16 of the deflection per step), and deterministic:
        elementwise numpy in a fixed order, whatever the number of rods.
        """
        n, steps = inputs.shape
        start = [np.array(column, dtype=float)
                 for column in zip(*(tuple(e.state) for e in self.engines))]
        target = inputs.T                                         # (steps, rods)
        before = np.vstack([start[5][None, :], target[:-1]])      # w at each step's start
        with np.errstate(all='ignore'):
            wd = (target - before) / dt
            if wd.any():
                p, q, turn = self._affine_maps(before, wd, dt)
            else:
                # a hold (every rod at a constant w): one step's maps serve every step
                # of every block, until the speeds change
                key = (dt, target[0].tobytes())
                if self._maps is None or self._maps[0] != key:
                    self._maps = (key, *self._affine_maps(before[:1], wd[:1], dt))
                p1, q1, turn1 = self._maps[1:]
                p, q, turn = (np.broadcast_to(a, (steps, *a.shape[1:]))
                              for a in (p1, q1, turn1))
            x = np.stack(start[:4])                               # (4, n)
            theta = start[4]
            xs = np.empty((steps, 4, n))
            thetas = np.empty((steps, n))
            for k in range(steps):
                pk = p[k]
                x = q[k] + pk[0] * x[0] + pk[1] * x[1] + pk[2] * x[2] + pk[3] * x[3]
                theta = theta + turn[k]
                xs[k], thetas[k] = x, theta
            new = (xs[:, 0], xs[:, 1], xs[:, 2], xs[:, 3], thetas, target)
            torque = self._velocity_torque(new, wd)
            r = np.hypot(new[0], new[1])
            out_steps = np.stack([*new, wd, torque, r], axis=1)   # (steps, 9, rods)
            finite = np.isfinite(out_steps[:, :8].sum(axis=1))
            far = finite & (r > self.max_deflection)
            fast = finite & ~far & (np.abs(target) > self.max_omega)
            bad = ~finite | far | fast
        return _records(out_steps, bad, finite, far)

    def _affine_maps(self, before: np.ndarray, wd: np.ndarray, dt: float) -> tuple:
        """P_k, q_k and theta's increment of every step (k) and rod, by the kernel.

        ``before``: w at each step's start, ``wd``: w' over each step, (steps, rods).
        Returns P (steps, 4 in, 4 out, rods), q (steps, 4, rods), turn (steps, rods).
        """
        steps, n = before.shape
        basis = np.eye(5, 4)[[4, 0, 1, 2, 3]]                     # x = 0, e_u, e_v, ...
        u, v, du, dv = (basis[:, j, None, None] for j in range(4))
        out = rk4_step_prescribed_rotation(self._accelerations,
                                           (u, v, du, dv, 0.0, before[None]), dt, wd)
        full = [np.broadcast_to(c, (5, steps, n)) for c in out[:4]]
        q = np.stack([c[0] for c in full], axis=1)                # (steps, 4 out, n)
        p = np.stack([c[1:] for c in full], axis=2) - q[None]     # (4 in, steps, 4 out, n)
        turn = np.array(np.broadcast_to(out[4], (5, steps, n))[0])
        return np.ascontiguousarray(p.transpose(1, 0, 2, 3)), q, turn

    def _run_many(self, inputs: np.ndarray, dt: float) -> list[BlockRecord]:
        """The block of several rods, each step one pass over the arrays."""
        n, steps = inputs.shape
        state = tuple(np.array(column, dtype=float)
                      for column in zip(*(tuple(e.state) for e in self.engines)))
        rows = []
        alive = np.ones(n, dtype=bool)
        taken = np.full(n, steps)
        rejected: list = [None] * n
        max_deflection, max_omega = self.max_deflection, self.max_omega
        for k in range(steps):
            with np.errstate(all='ignore'):
                new, wd, drive = self._step(state, inputs[:, k], dt)
                r = np.hypot(new[0], new[1])
                # one sum is not finite if any term is not: the usual step checks once
                total = new[0] + new[1] + new[2] + new[3] + new[4] + new[5] + wd + drive
                good = (np.isfinite(total).all() and (r <= max_deflection).all()
                        and (np.abs(new[5]) <= max_omega).all())
            if not good:
                new, wd, drive, r = self._refuse(k, state, new, wd, drive, r, alive, taken,
                                                 rejected)
            state = new
            rows.append((*new, wd, np.broadcast_to(drive, (n,)), r))
        out = np.array(rows)                                  # (steps, 9, rods)
        r = out[:, 8, :]
        r_max, r_min = r.max(axis=0).tolist(), r.min(axis=0).tolist()
        last = out[-1, :8, :].T.tolist()
        return [BlockRecord(out, i, steps, None, last[i], r_max[i], r_min[i])
                if taken[i] == steps else _cut(out, i, int(taken[i]), rejected[i])
                for i in range(n)]

    def _refuse(self, k: int, state, new, wd, drive, r, alive, taken, rejected):
        """Freeze the rods whose step ``k`` was refused at their last good ``state``."""
        n = len(alive)
        drive = np.broadcast_to(drive, (n,))
        with np.errstate(all='ignore'):
            finite = np.isfinite(wd) & np.isfinite(drive)
            for x in new:
                finite &= np.isfinite(x)
            far = finite & (r > self.max_deflection)
            fast = finite & ~far & (np.abs(new[5]) > self.max_omega)
        bad = alive & (~finite | far | fast)
        for i in np.flatnonzero(bad):
            reason = NON_FINITE if not finite[i] else TOO_FAR if far[i] else TOO_FAST
            rejected[i] = (reason, tuple(float(x[i]) for x in new), float(drive[i]))
            taken[i] = k
        alive &= ~bad
        return (tuple(np.where(alive, x, s) for x, s in zip(new, state)),
                np.where(alive, wd, 0.0), np.where(alive, drive, 0.0),
                np.where(alive, r, 0.0))


class World:
    """Rods on one clock at one physics rate (Hz), stepped as one batch.

    The simulated clock :attr:`time` (s) starts at 0 and only moves forward, but for
    :meth:`reset_time`. Rods are added and removed between steps (:meth:`add`,
    :meth:`remove`), each a :class:`~rotrod_core.live.engine.SimulationEngine` whose
    ``physics_rate`` must be the world's.
    """

    def __init__(self, physics_rate: float):
        self._rate = finite_number('physics_rate', physics_rate, positive=True)
        self._origin = 0.0
        self._steps = 0
        self.engines: dict[str, Any] = {}
        """The rods by name (:class:`Rod`: SimulationEngine), in the order they came."""
        self._groups: list[_Group] | None = None

    # ----------------------------------------------------------------- the clock
    @property
    def physics_rate(self) -> float:
        """Steps per second of simulated time, Hz."""
        return self._rate

    @property
    def dt(self) -> float:
        """Step, s."""
        return 1.0 / self._rate

    @property
    def time(self) -> float:
        """Simulated time, s."""
        return self._origin + self._steps * self.dt

    def set_physics_rate(self, rate: float) -> None:
        """A new rate from now on (the clock keeps its time)."""
        rate = finite_number('physics_rate', rate, positive=True)
        self._origin, self._steps, self._rate = self.time, 0, rate

    def reset_time(self) -> None:
        """Simulated time back to 0 (every rod's commands start afresh)."""
        self._origin, self._steps = 0.0, 0
        for engine in self.engines.values():
            engine._time_reset()

    def steps_until(self, t: float) -> int:
        """Number of whole steps from :attr:`time` to reach time ``t`` (s), >= 0."""
        n = (finite_number('t', t) - self.time) / self.dt + 1e-9
        if not math.isfinite(n):
            raise ValueError(f't = {t!r} s is too many steps of {self.dt:g} s away')
        return max(0, math.floor(n))

    # ----------------------------------------------------------------- the rods
    def add(self, name: str, engine: Rod) -> None:
        """Add ``engine`` as ``name`` (its physics_rate must be the world's)."""
        if name in self.engines:
            raise ValueError(f'a rod named {name!r} is already in the world')
        if engine.config.physics_rate != self._rate:
            raise ValueError(f'{name}: physics_rate {engine.config.physics_rate:g} Hz is not '
                             f"the world's {self._rate:g} Hz")
        self.engines[name] = engine
        self.changed()

    def remove(self, name: str) -> Any:
        """Take the rod ``name`` out of the world; return it."""
        engine = self.engines.pop(name)
        self.changed()
        return engine

    def changed(self) -> None:
        """A rod was added or removed, or changed its drive, rod or limits: regroup."""
        self._groups = None

    def __iter__(self) -> Iterator[Any]:
        return iter(self.engines.values())

    def __len__(self) -> int:
        return len(self.engines)

    @property
    def halted(self) -> str | None:
        """Every rod's halt when all have halted (a world of none never halts), else None."""
        if not self.engines or any(not e.halted for e in self.engines.values()):
            return None
        return '; '.join(f'{name}: {e.halted}' for name, e in self.engines.items())

    def _grouped(self) -> list[_Group]:
        """The running rods by drive and coupling (rebuilt after :meth:`changed`)."""
        if self._groups is None:
            by_kind: dict[tuple, list] = {}
            for engine in self.engines.values():
                if engine.halted:
                    continue
                key = (engine.config.drive, engine.config.coupling)
                by_kind.setdefault(key, []).append(engine)
            self._groups = [_Group(drive, coupling, engines)
                            for (drive, coupling), engines in by_kind.items()]
        return self._groups

    # ----------------------------------------------------------------- stepping
    def advance(self, steps: int) -> int:
        """Take up to ``steps`` steps of every rod still running; return how many.

        Fewer only when every rod has halted (a halted rod stays at its last good state
        while the others go on).
        """
        if isinstance(steps, bool) or not isinstance(steps, (int, np.integer)):
            raise ValueError(f'steps must be a whole number, got {steps!r}')
        done = 0
        while done < steps:
            running = [e for e in self.engines.values() if not e.halted]
            if not running:
                break
            done += self._block(running, min(steps - done, BLOCK_STEPS))
        return done

    def advance_to(self, t: float) -> int:
        """Take the whole steps that do not pass time ``t`` (s); return how many."""
        return self.advance(self.steps_until(t))

    def _block(self, running: list, steps: int) -> int:
        """One block of at most ``steps`` steps of the running rods; how many taken."""
        t0, dt = self.time, self.dt
        for engine in running:
            steps = min(steps, engine._block_limit(t0, steps))
        inputs = {id(e): e._block_inputs(t0, steps) for e in running}
        times = t0 + dt * np.arange(1, steps + 1)
        records = {}
        for group in self._grouped():
            for engine, record in zip(group.engines, group.run(
                    [inputs[id(e)] for e in group.engines], times, dt)):
                records[id(engine)] = record
        # the clock goes on while a rod does; when all halt, to the last one's halt
        if all(r.rejected is not None for r in records.values()):
            steps = max(r.taken for r in records.values())
        self._steps += steps
        for engine in running:
            engine._block_done(t0, records[id(engine)])
        return steps


__all__ = ['BLOCK_STEPS', 'BlockRecord', 'NON_FINITE', 'TOO_FAR', 'TOO_FAST', 'World']
