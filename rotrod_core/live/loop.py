"""The simulator's real-time loop (no ROS import): pacing, commands, publication timing.

Also the marker throttling, pause and reset.

:class:`RealTimeLoop` drives a :class:`~rotrod_core.live.world.World` of rods (or one
:class:`~rotrod_core.live.engine.SimulationEngine`, in a world of its own) from
a thread of its own at a fixed step. Each tick integrates in whole steps up to the
simulated time due now (``real_time_factor`` x wall time; 0 = as fast as possible), so
simulated time does not drift from the clock; it computes the publications a little
ahead (:data:`LEAD`) and hands each to the ``publish`` callback at its due time.
Commands from any source go through one queue (:meth:`RealTimeLoop.submit`, any
thread, O(1)) with their arrival time; the loop's thread applies them between ticks at
the simulated instant they arrived, so a flood of commands cannot hold the physics
off. The thread runs under SCHED_FIFO at ``realtime_priority`` where permitted, and
holds a CPU wake-up latency request of ``cpu_dma_latency`` us while paced
(:mod:`rotrod_core.live.scheduling`).

Paused, the loop steps on request (lockstep): :meth:`RealTimeLoop.request_steps` queues
a :class:`~rotrod_core.live.lockstep.StepRequest` (any thread), which the loop's thread
serves by the rule stated there; each publication that falls due is published at once,
with nothing paced. A loop started paused (``start_paused``) publishes simulated time
as the clock, so that its stamps are simulated time from 0.

Time comes from a clock object (:class:`SystemClock`; a test passes a fake one, whose
waits move its time, to run the loop deterministically with :meth:`RealTimeLoop.cycle`).
Messages are the host's business: the loop calls ``publish(sample, settings, config,
snapshot)`` and ``publish_status(status)`` with plain values (SI units, stamps in s).
"""

from __future__ import annotations

import logging
import math
import threading
import time
import traceback
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Generic, NamedTuple, TypeVar

import rotrod_core.live.scheduling as scheduling
from rotrod_core.command.trajectory import INVALID_GOAL
from rotrod_core.live.drive import FOLLOWS_OMEGA
from rotrod_core.live.engine import ERROR, CommandRejected, SimulationEngine
from rotrod_core.live.execution import Tracking, TrajectoryOutcome
from rotrod_core.live.lockstep import (
    STEPS_CANCELLED,
    STEPS_HALTED,
    STEPS_INTERRUPTED,
    STEPS_NOT_PAUSED,
    STEPS_STOPPING,
    StepRequest,
)
from rotrod_core.live.pacing import Pacer, StampClock
from rotrod_core.live.world import World
from rotrod_core.model.equations import Coefficients, State
from rotrod_core.numerics.checks import finite_number

MAX_BACKLOG = 1.0
"""Wall seconds of physics the thread catches up on after a stall; beyond, it skips."""
PENDING_COMMANDS = 1000
"""Commands received but not yet applied, at most; beyond, the oldest is dropped (and
counted). The thread applies them between ticks: only a sender faster than it can
apply them fills this."""
TICK_COMMAND_BUDGET = 0.001
"""Wall seconds a tick spends at most on commands still queued at its start (normally
none: they are applied between ticks as they come), so that the publication it
computes stays on time."""
IDLE_WAIT = 0.05
"""Wall seconds between checks while paused or halted."""
LEVEL_CHECK = 0.005
"""Wall seconds between looks at the rods' health levels for a change, per LEVEL_RODS
rods (a change is reported within this; as fast as possible, a look per publication
cost 3 % of the thread's time; a look at 100 rods costs ten at one)."""
LEVEL_RODS = 10
"""Rods per LEVEL_CHECK: a world of 100 rods looks every 50 ms."""
READY_WAIT = 0.005
"""Wall seconds between checks of the host's ``ready`` before the run starts."""
LEAD = 0.0025
"""Wall seconds (at most; also at most a quarter publish period) by which a tick runs
ahead of the publications it computes; each publication then waits for its due time,
so its timing does not depend on how long the integration took, nor on a slow
previous publication (a marker array and a whirl estimate take up to a few ms). A
command that arrives within this lead applies at most this late. Chosen by
measurement: docs/realtime.md#lead."""
MAX_PUBLICATION_SPIN = 0.002
"""Largest ``publication_spin``, s (a fifth of the default publish period)."""
SLEEP_ONLY_LATENCY = 0
"""Largest CPU wake-up latency request (us, cpu_dma_latency) under which publications
only sleep to their due time, whatever ``publication_spin``: idle CPUs then wake at
once, and a poll would only burn CPU."""
COMMANDS = ('omega', 'torque', 'trajectory', 'cancel_trajectory')
"""Kinds of command: an angular-velocity setpoint (rad/s), a hub torque (N m), a
:class:`~rotrod_core.live.execution.TrajectoryGoal`, or the token of a goal to cancel."""


@dataclass(frozen=True)
class LoopSettings:
    """What the loop is configured with besides the engine (SI units).

    Attributes:
        publish_rate: publications per second of simulated time, Hz.
        real_time_factor: simulated seconds per wall second; 0 = as fast as possible.
        markers: whether samples ever ask for markers.
        marker_rate: markers per second of simulated time, Hz (and at most twice that
            per wall second faster than real time).
        diagnostics_rate: status reports per wall second, Hz (also on a change of level).
        realtime_priority: SCHED_FIFO priority of the thread while paced (0: ordinary).
        cpu_dma_latency: CPU wake-up latency requested while paced, us (-1: none).
        publication_spin: wall seconds before each publication's due time at which the
            thread stops sleeping and polls the clock, s (0: sleep to the due time).
            A sleeping SCHED_FIFO thread may wake late on a VM whose idle vCPUs halt,
            a busy one not; it costs about ``publication_spin x publish_rate`` of a
            core (0.3 ms at 100 Hz: 3 %), so it is opt-in (docs/realtime.md#spin).
        start_paused: start with simulated time standing still at 0, for stepping
            (:meth:`RealTimeLoop.request_steps`) or a later resume; the stamps are
            then simulated time, published as the clock.
    """

    publish_rate: float = 100.0
    real_time_factor: float = 1.0
    markers: bool = True
    marker_rate: float = 20.0
    diagnostics_rate: float = 1.0
    realtime_priority: int = 50
    cpu_dma_latency: int = -1
    publication_spin: float = 0.0
    start_paused: bool = False

    def __post_init__(self):
        for name in ('publish_rate', 'marker_rate', 'diagnostics_rate'):
            finite_number(name, getattr(self, name), positive=True)
        finite_number('real_time_factor', self.real_time_factor, nonnegative=True)
        spin = finite_number('publication_spin', self.publication_spin, nonnegative=True)
        if spin > MAX_PUBLICATION_SPIN:
            raise ValueError(f'publication_spin must be in [0, {MAX_PUBLICATION_SPIN:g}] s, '
                             f'got {spin!r}')
        for name, low, high in (('realtime_priority', 0, scheduling.MAX_PRIORITY),
                                ('cpu_dma_latency', -1, scheduling.MAX_CPU_LATENCY)):
            value = getattr(self, name)
            if isinstance(value, bool) or not isinstance(value, int) or not (
                    low <= value <= high):
                raise ValueError(f'{name} must be an integer in [{low}, {high}], '
                                 f'got {value!r}')

    @property
    def publish_period(self) -> float:
        """Simulated time between publications, s."""
        return 1.0 / self.publish_rate

    @property
    def publishes_clock(self) -> bool:
        """Whether simulated time is published as a clock.

        When real_time_factor != 1, or started paused (a stepped simulation's time is
        its own).
        """
        return self.real_time_factor != 1.0 or self.start_paused


SettingsT = TypeVar('SettingsT', bound=LoopSettings)
"""The settings a loop is given: :class:`LoopSettings` or the host's subclass."""


class Sample(NamedTuple):
    """What is published at one instant."""

    due: float | None
    """Monotonic wall time at which to publish (None: at once)."""
    time: float
    """Simulated time, s."""
    stamp: float
    """Stamp time, s: epoch time in real time, simulated time with a published clock."""
    state: State
    torque: float
    coefficients: Coefficients
    """The rod's coefficients at the sample (what its position and sensors read)."""
    markers: bool
    tracking: Tracking | None = None
    """The executing trajectory's desired and actual hub state (None: no goal)."""
    rod: str = ''
    """The rod's name in its world."""
    omega_dot: float = 0.0
    """The hub's angular acceleration over the last step, rad/s^2."""


class Status(NamedTuple):
    """A status report: a rod's health and the loop's own counters."""

    stamp: float
    level: int
    message: str
    values: tuple
    rod: str = ''
    """The rod's name in its world."""


class SystemClock:
    """The wall clocks and waits of a real run."""

    monotonic = staticmethod(time.monotonic)
    epoch = staticmethod(time.time)

    @staticmethod
    def wait(event: threading.Event, timeout: float) -> bool:
        """Wait for ``event`` up to ``timeout`` s; whether it is set."""
        return event.wait(timeout)

    @staticmethod
    def sleep_until(due: float, stop: threading.Event, spin: float = 0.0) -> bool:
        """Return at monotonic time ``due``: sleep, then poll for the last ``spin`` s.

        False if ``stop`` is set meanwhile.
        """
        early = due - time.monotonic() - spin
        if early > 0 and stop.wait(early):
            return False
        while time.monotonic() < due:
            pass
        return True


def _follow_rods(per_rod: dict, engines, first: Callable[[int, int], Any]) -> list:
    """Keep ``per_rod`` (a value per rod name) to the rods of ``engines``.

    A rod new to it gets ``first(k, n)``, k its place among the n rods (so that the
    rods' periodic work falls on different instants); the rods that left are dropped,
    and their names returned.
    """
    if len(per_rod) == len(engines) and all(name in per_rod for name in engines):
        return []
    n = len(engines)
    for k, name in enumerate(engines):
        if name not in per_rod:
            per_rod[name] = first(k, n)
    gone = [name for name in per_rod if name not in engines]
    for name in gone:
        del per_rod[name]
    return gone


class RealTimeLoop(Generic[SettingsT]):
    """A world of rods stepped in real time, commands applied, publications on time.

    Args:
        world: the simulation: a :class:`~rotrod_core.live.world.World`, or one
            :class:`~rotrod_core.live.engine.SimulationEngine` (its world).
        settings: :class:`LoopSettings` (or a subclass: the host's settings).
        publish: called in the loop's thread as ``publish(sample, settings, config,
            snapshot)`` for each rod's sample at their due time (every rod's in the
            same wake-up), with the settings and that rod's engine config the sample
            was computed with and what ``snapshot()`` returned then.
        publish_status: called with the list of every rod's :class:`Status` at
            ``diagnostics_rate`` and on a change of a level.
        snapshot: called under the lock with each tick's samples (e.g. the host's
            estimator, which a reset replaces).
        logger: has ``info``, ``warning``, ``error`` and ``fatal`` (an rclpy logger or
            a :class:`logging.Logger`); repeated warnings are throttled here.
        clock: :class:`SystemClock` or a test's fake.
        running: false once the host is shutting down (an error is then no failure).
        inputs: what the log calls each kind's input, e.g. {'omega': 'cmd/omega'}
            (default the kind).
        ready: called in the loop's thread before the run starts, every READY_WAIT s,
            until it returns true (e.g. the host's subscribers are there); simulated
            time starts then (default: at once).
        on_trajectory: called in the loop's thread with each
            :class:`~rotrod_core.live.execution.TrajectoryOutcome` (a trajectory goal
            refused or ended), as soon as the engine has it.
        published: called in the same wake-up once every rod's sample of an instant was
            handed to ``publish``: the host's second pass, for what can wait behind
            every rod's samples (the whirl estimates, the markers).
    """

    def __init__(self, world: World | SimulationEngine, settings: SettingsT, publish, *,
                 publish_status=None, snapshot=None, logger=None, clock=None,
                 running=None, inputs=None, ready=None, on_trajectory=None,
                 published=None):
        self.world = world if isinstance(world, World) else world.world
        self.settings = settings
        self._publish = publish
        self._publish_status = publish_status or (lambda statuses: None)
        self._snapshot = snapshot or (lambda: None)
        self._logger = logger or logging.getLogger(__name__)
        self.clock = clock or SystemClock()
        self._running = running or (lambda: True)
        self._inputs = {kind: kind for kind in COMMANDS} | dict(inputs or {})
        self._ready = ready
        self._on_trajectory = on_trajectory or (lambda outcome: None)
        self._published_hook = published or (lambda: None)
        self.lock = threading.RLock()
        """Held while the engine or the loop's state changes (re-entrant)."""
        self._stop = threading.Event()
        self.paused = settings.start_paused
        self._step_requests: deque[StepRequest] = deque()
        self._interrupts = 0
        self._serving = False
        """Whether a step request is being served (parameter changes wait for its end)."""
        self._deferred: list = []
        """Resets and plays so far: a step request being served ends at the next one."""
        self.steps_taken = 0
        """Physics steps taken on request (:meth:`request_steps`) so far."""
        self.overruns = 0
        """Times the thread fell more than MAX_BACKLOG behind and skipped ahead."""
        self.publications = 0
        """Samples handed to ``publish`` so far."""
        self.failure: str | None = None
        self._scheduling = scheduling.ThreadScheduling(self._logger, 'physics thread')
        now = self.clock.monotonic()
        self._pacer = Pacer(settings.real_time_factor, self.world.time, now)
        self._stamps = StampClock(0.0 if settings.publishes_clock else self.clock.epoch())
        self._countdown = 0
        self._published = (self.world.time, now)  # (simulated, wall) of the last publication
        self._marker_state: dict[str, list] = {}
        """Each rod's [samples since its markers, wall time of its next markers]."""
        self._commands: deque = deque(maxlen=PENDING_COMMANDS)
        self._command_arrived = threading.Event()
        self.dropped_commands = 0
        self.malformed_commands = 0
        """Command messages the host could not read as a command (see :meth:`reject`)."""
        self._drops_logged = 0
        self._late_logged: dict[str, int] = {}
        self._timeouts_logged = {name: e.timeouts for name, e in self.world.engines.items()}
        self._halts_logged: dict[str, str | None] = {}
        self._levels: dict[str, int] = {}
        """Each rod's level at its last look."""
        self._status_due: dict[str, float] = {}
        """Each rod's next periodic status (monotonic wall time, s)."""
        self._next_status = 0.0
        self._next_level_check = 0.0
        self._quiet_until: dict = {}
        self._thread: threading.Thread | None = None

    @property
    def engine(self) -> SimulationEngine:
        """The rod of a world of one (ValueError for a world of several)."""
        return self._rod(None)

    def _rod(self, name: str | None) -> SimulationEngine:
        """The rod ``name``, or the only one for None; KeyError or ValueError."""
        engines = self.world.engines
        if name is None:
            if len(engines) != 1:
                raise ValueError(f'the world holds {len(engines)} rods: name one')
            return next(iter(engines.values()))
        return engines[name]

    def _named(self, engine: SimulationEngine, text: str) -> str:
        """``text`` about ``engine``, naming it when the world holds more than one rod."""
        return text if len(self.world) == 1 else f'{engine.name}: {text}'

    # ----------------------------------------------------------------- logging
    def _log(self, level: str, message: str, key: str | None = None,
             throttle: float = 0.0) -> None:
        """Log; with a ``key``, at most once per ``throttle`` wall seconds per key."""
        if key is not None:
            now = self.clock.monotonic()
            if now < self._quiet_until.get(key, -1.0):
                return
            self._quiet_until[key] = now + throttle
        # one call site per severity: rclpy's logger binds a call site to one
        if level == 'info':
            self._logger.info(message)
        else:
            self._logger.warning(message)

    # ----------------------------------------------------------------- timing
    @property
    def paced(self) -> bool:
        """False when running as fast as possible (real_time_factor 0)."""
        return self._pacer.paced

    @property
    def _publish_steps(self) -> int:
        """Physics steps between publications (publication instants are step instants)."""
        return max(1, round(self.world.physics_rate / self.settings.publish_rate))

    @property
    def _lead(self) -> float:
        """Wall seconds a tick runs ahead: LEAD, at most a quarter publish period."""
        return min(LEAD, 0.25 * self.settings.publish_period / self.settings.real_time_factor)

    @property
    def _spin(self) -> float:
        """The poll before each publication, s.

        ``publication_spin``, or 0 while a CPU wake-up latency of at most
        SLEEP_ONLY_LATENCY is held.
        """
        held = self._scheduling.cpu_latency
        if held is not None and held <= SLEEP_ONLY_LATENCY:
            return 0.0
        return self.settings.publication_spin

    @property
    def _marker_every(self) -> int:
        return max(1, round(self.settings.publish_rate / self.settings.marker_rate))

    def simulated_time(self, stamp: float) -> float:
        """The simulated time (s) that stamps as ``stamp`` (s): :meth:`stamp_now`'s inverse."""
        return stamp - self._stamps.origin

    def stamp_now(self) -> float:
        """The stamp time of the current simulated time, s (lock held)."""
        return self._stamps.stamp(self.world.time)

    def _restart_clock(self) -> None:
        """Re-anchor the wall-to-simulated mapping at the current instant."""
        now = self.clock.monotonic()
        self._pacer.anchor(self.settings.real_time_factor, self.world.time, now)
        self._published = (self.world.time, now)
        if not self.settings.publishes_clock:
            self._stamps.follow_wall(self.world.time, self.clock.epoch())

    # ----------------------------------------------------------------- commands
    def submit(self, kind: str, value, source: str | None = None,
               rod: str | None = None) -> None:
        """Queue a command for ``rod`` (any thread; O(1)), stamped with its arrival time.

        ``kind`` is one of :data:`COMMANDS`: 'omega' (``value`` rad/s), 'torque' (N m),
        'trajectory' (a TrajectoryGoal, started at its stamp or its arrival) or
        'cancel_trajectory' (a goal's token); ``source`` names where it came from in log
        lines (default: the kind's input, see ``inputs``); ``rod`` the rod's name (None:
        the world's only rod). The loop's thread applies it at the simulated instant it
        arrived (a command for a rod gone by then is dropped); the oldest of
        PENDING_COMMANDS pending is dropped (and counted) when a sender outpaces it (a
        goal dropped so ends with INVALID_GOAL).
        """
        if kind not in COMMANDS:
            raise ValueError(f'command kind must be one of {COMMANDS}, got {kind!r}')
        if len(self._commands) == PENDING_COMMANDS:
            self.dropped_commands += 1
            try:
                dropped = self._commands.popleft()
            except IndexError:                       # the loop's thread took it meanwhile
                dropped = None
            if dropped is not None and dropped[0] == 'trajectory':
                self._on_trajectory(TrajectoryOutcome(
                    dropped[1].token, INVALID_GOAL, 'dropped: commands arrive faster than '
                    f'the simulator applies them (the oldest of {PENDING_COMMANDS} pending)'))
        self._commands.append((kind, value, self.clock.monotonic(),
                               source or self._inputs.get(kind, kind), rod))
        self._command_arrived.set()

    def reject(self, source: str, reason: str) -> None:
        """A command message from ``source`` that could not be read (any thread).

        Counted and logged with its reason, throttled per source (at most once a
        wall second); nothing else changes.
        """
        self.malformed_commands += 1
        self._log('warning', f'{source} rejected: {reason}', 'rejected ' + source, 1.0)

    def _command_time(self, arrived: float) -> float | None:
        """Simulated time at which a command arrived at ``arrived`` takes effect, or None.

        ``arrived`` is a monotonic wall time; None means at once (the engine's time).

        In real time (factor 1) the simulated time due then. With a published clock,
        senders run on simulated time and see only what was published, so the latest
        publication's simulated time plus the wall time from it, at the factor: it
        follows the simulation's actual progress also when the machine cannot keep
        up. Not capped above, since when the thread lags, a cap would date a run of
        arrivals early, and the setpoint shaper relies on delivery delays being
        one-sided (late, not early). The engine moves a time before its own forward.
        """
        if self.paused or self.world.halted or not self._pacer.paced:
            return None
        if self.settings.publishes_clock:
            sim, wall = self._published
            return sim + (arrived - wall) * self._pacer.factor
        return self._pacer.sim_time(arrived)

    def _apply_commands(self, deadline: float | None = None) -> None:
        """Apply queued commands in order, until none is left or monotonic ``deadline``.

        Called with the lock held. Each takes effect at the simulated time it arrived.
        """
        commands, clock = self._commands, self.clock
        n = 0
        while commands:
            if deadline is not None and n % 8 == 0 and clock.monotonic() >= deadline:
                break
            n += 1
            kind, value, arrived, source, rod = commands.popleft()
            try:
                engine = self._rod(rod)
            except (KeyError, ValueError):
                self._log('warning', f'{source} dropped: no rod {rod!r} in the world',
                          'no rod ' + str(rod), 1.0)
                if kind == 'trajectory':
                    self._on_trajectory(TrajectoryOutcome(
                        value.token, INVALID_GOAL, f'no rod {rod!r} in the world'))
                continue
            timed_out = engine.timed_out_at is not None
            at = self._command_time(arrived)
            try:
                if kind == 'omega':
                    engine.command_omega(value, at=at)
                elif kind == 'torque':
                    engine.command_torque(value, at=at)
                elif kind == 'trajectory':
                    engine.command_trajectory(value, at=at)
                else:
                    engine.cancel_trajectory(value)
            except CommandRejected as exc:
                # throttled per source: a rejection on one must not silence another's
                self._log('warning', f'{source} rejected: {exc}', 'rejected ' + source, 1.0)
                continue
            if timed_out:
                self._log('info', f'{source}: commands again after the command timeout',
                          'again ' + source, 1.0)
        if self.dropped_commands != self._drops_logged:
            self._log('warning', f'commands arrive faster than they can be applied: '
                      f'{self.dropped_commands} dropped so far (the oldest of '
                      f'{PENDING_COMMANDS} pending)', 'dropped', 1.0)
            self._drops_logged = self.dropped_commands
        self._report_outcomes()
        for name, engine in self.world.engines.items():
            late = engine.late_setpoints
            if late != self._late_logged.get(name, 0):
                self._log('warning', self._named(engine, f'{late} angular-velocity setpoints '
                          'so far arrived after their due time (the stream stalled for longer '
                          'than setpoint_delay): meanwhile w followed the stream\'s '
                          'extrapolation'), 'late setpoints ' + name, 1.0)
                self._late_logged[name] = late

    @property
    def late_setpoints(self) -> int:
        """Late setpoints of every rod so far (see SimulationEngine.late_setpoints)."""
        return sum(e.late_setpoints for e in self.world)

    def _report_outcomes(self) -> None:
        """Hand the rods' trajectory outcomes to the host, oldest first."""
        for engine in self.world:
            self._report_outcomes_of(engine)

    def _report_outcomes_of(self, engine: SimulationEngine) -> None:
        """Hand ``engine``'s trajectory outcomes to the host (a rod leaving the world too)."""
        outcomes = engine.trajectory_outcomes
        while outcomes:
            self._on_trajectory(outcomes.popleft())

    def _log_timeout(self) -> None:
        """Warn once per command-timeout event (throttled: a flapping stream cannot flood)."""
        for name, eng in self.world.engines.items():
            if eng.timeouts == self._timeouts_logged.get(name, 0):
                continue
            self._timeouts_logged[name] = eng.timeouts
            if eng.timed_out_at is None:       # already over (a halt and a reset since)
                continue
            cfg = eng.config
            action = (f'spinning down to 0 at max_angular_acceleration '
                      f'{cfg.max_angular_acceleration:g} rad/s^2' if cfg.drive in FOLLOWS_OMEGA
                      else 'hub torque set to 0 (free coast)')
            kind = 'omega' if cfg.drive in FOLLOWS_OMEGA else 'torque'
            self._log('warning', self._named(eng, f'no command on {self._inputs[kind]} for '
                      f'{cfg.command_timeout:g} s (command_timeout) at simulated time '
                      f'{eng.timed_out_at:.3f} s: {action}'), 'timeout ' + name, 1.0)

    def _log_halts(self) -> None:
        """Log each rod's halt once (an error: the rod stands still until a reset)."""
        for name, eng in self.world.engines.items():
            if eng.halted != self._halts_logged.get(name):
                self._halts_logged[name] = eng.halted
                if eng.halted:
                    self._logger.error(self._named(eng, f'simulation halted: {eng.halted}; '
                                                        'call ~/reset'))

    # ----------------------------------------------------------------- control
    def reconfigure(self, config, settings: SettingsT) -> None:
        """Switch to (validated) engine configs and settings, keeping states and clock.

        ``config``: an EngineConfig for a world of one rod, else a mapping of rod names
        to their new configs (the others keep theirs). Commands that came before the
        change are applied first, under the old config.
        """
        configs = config if isinstance(config, dict) else {self.engine.name: config}
        with self.lock:
            if self._serving:               # between requests: at the end of this one
                self._deferred.append((configs, settings))
                return
            self._reconfigure(configs, settings)

    def _reconfigure(self, configs: dict, settings: SettingsT) -> None:
        """:meth:`reconfigure`, the lock held."""
        self._apply_commands()
        for name, cfg in configs.items():
            engine = self.world.engines.get(name)   # (deleted while the change waited)
            if engine is not None and cfg != engine.config:
                engine.reconfigure(cfg)
        old, self.settings = self.settings, settings
        if settings.real_time_factor != old.real_time_factor:
            self._restart_clock()
        self._countdown = min(self._countdown, self._publish_steps)
        self._report_outcomes()

    def reset(self, state: bool = True, time: bool = False) -> tuple:
        """Back to the initial ``state`` (clears a halt) and/or simulated ``time`` 0.

        Either way the pending commands are dropped (superseded). Returns (the halt
        cleared or None, the simulated time). With the state alone the publication
        grid goes on, so the first state after the reset is stamped after any
        publication the thread still has to send from before it. With the time, the
        grid starts again: the state at 0 is published first (at once, or with the
        next step while paused), and what follows replays a run from the start.
        """
        with self.lock:
            self._commands.clear()
            self._interrupts += 1            # a step request being served ends here
            was_halted = None
            if state:
                halts = [(n, e.halted) for n, e in self.world.engines.items() if e.halted]
                if halts:
                    was_halted = halts[0][1] if len(self.world) == 1 else '; '.join(
                        f'{n}: {h}' for n, h in halts)
            if time:
                self.world.reset_time()
                self._countdown = 0
            if state:
                for engine in self.world:
                    engine.reset()
            self._restart_clock()
            self._report_outcomes()
            return was_halted, self.world.time

    def pause(self, paused: bool) -> str:
        """Pause (True) or resume (False) simulated time; what was done, as a sentence."""
        with self.lock:
            if paused and not self.paused:
                self.paused = True
                return f'paused at simulated time {self.world.time:.3f} s'
            if not paused and self.paused:
                self.paused = False
                self._interrupts += 1        # a step request being served ends here
                self._restart_clock()
                return f'resumed at simulated time {self.world.time:.3f} s'
            return 'already ' + ('paused' if self.paused else 'running')

    # ----------------------------------------------------------------- lockstep
    def request_steps(self, request: StepRequest) -> str | None:
        """Queue ``request`` (any thread); None, or why it cannot be (not paused, halted).

        The rule (lockstep): the loop's thread serves requests one at a time, in the
        order they came. At a request's start, every command that has arrived
        (:meth:`submit`) is applied, in arrival order, at the current simulated time,
        i.e. before the first step; commands arriving during a request wait for the
        next one. A parameter change (:meth:`reconfigure`) takes effect when made,
        between requests (one made during a request at its end). Then the steps are
        taken; each publication that falls due (every
        physics_rate/publish_rate steps, counted from simulated time 0 or the last
        reset of time, and the state at that instant if not yet published) is
        published at once. Nothing depends on the wall clock, so the same requests
        and commands from the same state give the same states, bit for bit.
        """
        with self.lock:
            if self._stop.is_set():
                return STEPS_STOPPING
            if not self.paused:
                return STEPS_NOT_PAUSED
            if self.world.halted:
                return f'{STEPS_HALTED}: {self.world.halted}; reset first'
            self._step_requests.append(request)
        self._command_arrived.set()                     # wake the thread
        return None

    def _serve_steps(self, request: StepRequest) -> None:
        """Take a request's steps and publish what falls due (the loop's thread).

        Under the lock from one publication instant to the next, not longer: between
        them a service takes its turn (a parameter change waits for the end). A reset,
        a play or a stop
        (:attr:`_interrupts`) and a cancel end the request at the next publication
        instant, so no request, however many steps it asks, takes the world away
        from its users.
        """
        completed, problem = 0, None
        with self.lock:
            self._serving = True
            interrupts = self._interrupts
            if not self.paused:
                problem = STEPS_NOT_PAUSED
            else:
                self._apply_commands()
        while problem is None:
            with self.lock:
                if self._interrupts != interrupts:
                    problem = STEPS_INTERRUPTED
                    break
                if self._countdown == 0:                  # due, not yet published
                    self._publish_now()
                    self._countdown = self._publish_steps
                if completed == request.steps:
                    break
                if completed:
                    request._progress(completed, request.steps - completed)
                if request._cancelled():
                    problem = STEPS_CANCELLED
                elif self._stop.is_set():
                    problem = STEPS_STOPPING
                else:
                    n = min(self._countdown, request.steps - completed)
                    done = self.world.advance(n)
                    completed += done
                    self.steps_taken += done
                    self._countdown -= done
                    self._log_halts()
                    if done < n:
                        problem = f'{STEPS_HALTED}: {self.world.halted}'
                self._log_timeout()
        with self.lock:
            self._serving = False
            for configs, settings in self._deferred:
                self._reconfigure(configs, settings)
            self._deferred.clear()
        self.report()
        request.finish(completed, problem)

    def _context(self) -> tuple:
        """What samples are computed with: (settings, each rod's config, snapshot)."""
        return (self.settings, {n: e.config for n, e in self.world.engines.items()},
                self._snapshot())

    def _publish_now(self) -> None:
        """Publish every rod's state now, with the current settings (lock held)."""
        self._send(self._samples(), self._context())

    def _send(self, samples: list, context: tuple) -> None:
        """Hand each rod's sample of an instant to the host (one wake-up) and count them.

        ``context``: the (settings, configs by rod, snapshot) they were computed with.
        """
        if not samples:
            return
        settings, configs, snapshot = context
        self._published = (samples[0].time, self.clock.monotonic())
        publish = self._publish
        for sample in samples:
            publish(sample, settings, configs[sample.rod], snapshot)
        self._published_hook()
        self.publications += 1

    def _finish_step_requests(self, problem: str) -> None:
        """End every queued request with ``problem`` (none is left waiting)."""
        while self._step_requests:
            self._step_requests.popleft().finish(0, problem)

    # ----------------------------------------------------------------- the thread
    @property
    def running(self) -> bool:
        """Whether the loop's thread is to go on (not stopped)."""
        return not self._stop.is_set()

    def start(self) -> None:
        """Start the loop's thread; simulated time starts from now."""
        with self.lock:
            self._restart_clock()
        self._thread = threading.Thread(target=self.run, name='rotrod_physics', daemon=True)
        self._thread.start()

    def stop(self) -> None:
        """Stop the loop's thread (returns when it has ended)."""
        self._stop.set()
        self._command_arrived.set()
        if self._thread is not None and self._thread.is_alive():
            self._thread.join(timeout=5.0)

    def run(self) -> None:
        """The thread's body: cycles until stopped; a failure is logged and reported."""
        try:
            while not self._stop.is_set() and self.cycle():
                pass
        except Exception as exc:  # report any failure, then stop the physics
            if self._stop.is_set() or not self._running():
                return
            self.failure = f'physics thread failed: {exc!r}'
            self._logger.fatal(self.failure + '\n' + traceback.format_exc())
            self.report(force=True)
        finally:
            with self.lock:
                self._stop.set()            # no request is queued after this
                self._finish_step_requests(STEPS_STOPPING)
            self._scheduling.release()

    def cycle(self) -> bool:
        """One pass: commands, a tick, its publications on time, status, idle to the next.

        Returns False when stopping. A step request queued while paused is served
        instead (:meth:`request_steps`).
        """
        if self._step_requests:
            self._serve_steps(self._step_requests.popleft())
            return True
        if self._schedule():
            # the clock starts (or goes on) from here: the change and its log lines took
            # tens of ms at the node's start (measured: 44 ms), which the first tick
            # would otherwise have caught up on in a burst of late publications
            with self.lock:
                self._restart_clock()
        with self.lock:
            self._apply_commands(deadline=self.clock.monotonic() + TICK_COMMAND_BUDGET)
            instants, wake = self._tick()
            # what the samples were computed with, also if a service or a parameter
            # change replaces it while they are being published
            context = self._context()
        spin = self._spin
        for samples in instants:          # every rod's sample of an instant in one wake-up
            due = samples[0].due if samples else None
            if due is not None and not self.clock.sleep_until(due, self._stop, spin):
                return False
            self._send(samples, context)
        self.report()
        # the next tick is due at an absolute time: the publication's wait and the work
        # after it (estimate, status) must not delay it
        return wake is None or self._idle_until(wake)

    def _markers_due(self, engines) -> set:
        """The rods whose sample of now carries markers.

        Each rod's every ``_marker_every`` samples, the k-th rod of a world's k samples
        before the first rod's (modulo that), so that the rods' marker arrays (a few
        hundred us each) do not all fall on one sample.
        """
        every, state = self._marker_every, self._marker_state
        _follow_rods(state, engines, lambda k, n: [-k % every, 0.0])
        now, due = None, set()
        for name in engines:
            rod = state[name]
            rod[0] += 1
            if rod[0] >= every:
                # a viewer shows markers in wall time: faster than real time, at most
                # twice marker_rate per wall second (as fast as possible, markers every
                # 10 ms of simulated time cost a third of the speed)
                now = self.clock.monotonic() if now is None else now
                if now >= rod[1]:
                    rod[0], rod[1] = 0, now + 0.5 / self.settings.marker_rate
                    due.add(name)
        return due

    def _samples(self) -> list[Sample]:
        """Every running rod's sample of now (a halted rod's too while others run)."""
        engines = self.world.engines
        markers = self._markers_due(engines) if self.settings.markers else set()
        t = self.world.time
        due = self._pacer.wall_time(t) if self._pacer.paced and not self.paused else None
        stamp = self._stamps.stamp(t)
        # what only some subscribers read (the tip's position, the frequencies) is
        # computed from the sample where it is published, not here for every rod
        return [Sample(due, t, stamp, eng.state, eng.torque, eng.coefficients,
                       name in markers, eng.tracking(), name, eng.omega_dot)
                for name, eng in self.world.engines.items()]

    def _tick(self) -> tuple[list, float | None]:
        """Integrate up to the time due now (lock held).

        Returns the samples to publish (a list of every rod's per instant) and the
        monotonic wall time at which the next tick is due (None: at once).
        """
        world = self.world
        if self._ready is not None:
            if not self._ready():
                return [], self.clock.monotonic() + READY_WAIT
            self._ready = None                  # started: simulated time runs from now
            self._restart_clock()
        if self.paused or world.halted or not len(world):
            return [], self.clock.monotonic() + IDLE_WAIT
        pacer = self._pacer
        if pacer.paced:
            now = self.clock.monotonic()
            target = pacer.sim_time(now + self._lead)
            if target - world.time > MAX_BACKLOG * pacer.factor:
                self.overruns += 1
                self._log('warning', f'fell {target - world.time:.3f} s of simulated time '
                          'behind the clock; skipping ahead', 'backlog', 5.0)
                self._restart_clock()
                target = world.time
        instants = []
        while True:
            n = self._countdown
            if pacer.paced:
                n = min(n, world.steps_until(target))
                if n == 0 and self._countdown > 0:
                    break
            done = world.advance(n)
            self._countdown -= done
            self._log_halts()
            if done < n:                      # every rod halted
                break
            if self._countdown == 0:
                instants.append(self._samples())
                self._countdown = self._publish_steps
                if not pacer.paced:
                    break
        self._log_timeout()
        wake = None
        if pacer.paced and not world.halted:
            wake = pacer.wall_time(world.time + self._countdown * world.dt) - self._lead
        return instants, wake

    def _idle_until(self, wake: float) -> bool:
        """Apply commands as they come until monotonic time ``wake``; False if stopping."""
        event, clock = self._command_arrived, self.clock
        while not self._stop.is_set():
            left = wake - clock.monotonic()
            if left <= 0 or self._step_requests:
                return True
            event.clear()
            if self._commands:
                with self.lock:
                    self._apply_commands(deadline=wake)
            else:
                clock.wait(event, left)
        return False

    def _schedule(self) -> bool:
        """Run at ``realtime_priority`` and hold ``cpu_dma_latency`` while paced.

        As fast as possible there is nothing to be on time for (and a real-time thread
        that never sleeps would starve ordinary ones), so then neither.

        Returns whether anything was changed (or tried and refused).
        """
        s, paced = self.settings, self._pacer.paced
        return self._scheduling.update(s.realtime_priority if paced else 0,
                                       s.cpu_dma_latency if paced else -1)

    # ----------------------------------------------------------------- status
    def report(self, force: bool = False) -> None:
        """Send each rod's :class:`Status` when due (diagnostics_rate) or ``force``.

        Between, the status of each rod whose level changed is sent. The rods' periodic
        statuses are spread over the period (rod k of n first at (k + 1) / n of it), not
        sent together: a status costs ~0.2 ms to build and publish, and a hundred rods'
        at one instant delayed that instant's and the next ones' samples by ~20 ms.

        The levels are looked at most every LEVEL_CHECK wall seconds per LEVEL_RODS
        rods (as fast as possible a cycle is one publication: thousands a second).
        """
        if any(e.trajectory_outcomes for e in self.world):
            with self.lock:
                self._report_outcomes()
        now = self.clock.monotonic()
        if not force and now < self._next_level_check and now < self._next_status:
            return
        check = force or now >= self._next_level_check
        if check:
            self._next_level_check = now + LEVEL_CHECK * max(1.0, len(self.world) / LEVEL_RODS)
        with self.lock:
            engines = self.world.engines
            period = 1.0 / self.settings.diagnostics_rate
            due_at = self._status_due
            # a new rod's first periodic status (k + 1) / n of a period from now (its
            # very first, a change of level from none, goes out at once)
            for name in _follow_rods(due_at, engines,
                                     lambda k, n: now + period * (k + 1) / n):
                self._levels.pop(name, None)
            sent = []
            for name in engines:
                due = now >= due_at[name]
                if not (check or due):
                    continue
                level = ERROR if self.failure else engines[name].level()
                if due:                 # its next in a period, on its own phase
                    due_at[name] = max(due_at[name] + period, now)
                if force or due or self._levels.get(name) != level:
                    sent.append(name)
                self._levels[name] = level
            self._next_status = min(due_at.values(), default=math.inf)
            if not sent:
                return
            loop_values = (('paused', self.paused),
                           ('real_time_factor', self.settings.real_time_factor),
                           ('overruns', self.overruns), ('publications', self.publications),
                           ('dropped_commands', self.dropped_commands),
                           ('malformed_commands', self.malformed_commands))
            stamp = self._stamps.stamp(self.world.time)
            conditions = [(name, ERROR, self.failure) if self.failure
                          else (name, *engines[name].condition()) for name in sent]
            if self.paused and not self.failure:
                conditions = [(name, level, 'paused; ' + message)
                              for name, level, message in conditions]
            statuses = [Status(stamp, level, message,
                               (*engines[name].status_values(), *loop_values), name)
                        for name, level, message in conditions]
        self._publish_status(statuses)
