"""Step requests (rotrod_core.live.lockstep) served by the paused real-time loop.

On a clock that never moves: nothing here depends on the wall clock; the loop's
thread is this test's (``cycle``), the clock's waits return at once. One step is
1/physics_rate s of simulated time; a publication falls due every
physics_rate/publish_rate steps from simulated time 0; a command applies at the start
of the next request; after a reset of state and time the same requests and commands
give the same states bit for bit.
"""

import struct
import threading

import pytest

from rotrod_core.live.engine import EngineConfig, SimulationEngine
from rotrod_core.live.lockstep import (
    STEPS_CANCELLED,
    STEPS_HALTED,
    STEPS_NOT_PAUSED,
    StepRequest,
)
from rotrod_core.live.loop import LoopSettings, RealTimeLoop

PHYSICS_RATE = 1000.0
PUBLISH_RATE = 100.0


class StillClock:
    """Monotonic and epoch time that move only by the loop's own waits."""

    def __init__(self):
        self.now = 0.0

    def monotonic(self) -> float:
        return self.now

    def epoch(self) -> float:
        return 1.7e9 + self.now

    def wait(self, event: threading.Event, timeout: float) -> bool:
        self.now += timeout
        return event.is_set()

    def sleep_until(self, due: float, stop, spin: float = 0.0) -> bool:
        self.now = max(self.now, due)
        return not stop.is_set()


class Stepped:
    """A loop started paused, its publications, and its requests' outcomes."""

    def __init__(self, config: EngineConfig | None = None, **settings):
        settings = {'realtime_priority': 0, 'publish_rate': PUBLISH_RATE,
                    'start_paused': True, **settings}
        self.engine = SimulationEngine(config or EngineConfig(physics_rate=PHYSICS_RATE))
        self.samples = []
        self.loop = RealTimeLoop(self.engine, LoopSettings(**settings),
                                 lambda sample, *context: self.samples.append(sample),
                                 clock=StillClock())

    def step(self, steps: int, **kwargs):
        """Request ``steps`` and serve them; the StepOutcome."""
        outcomes = []
        assert self.loop.request_steps(StepRequest(steps, outcomes.append, **kwargs)) is None
        assert self.loop.cycle()
        (outcome,) = outcomes
        return outcome


def raw(state) -> bytes:
    """The state's floats as bytes: equal bytes, bit-identical states."""
    return struct.pack('6d', *(float(x) for x in state))


def test_a_loop_started_paused_publishes_nothing_and_stamps_simulated_time():
    run = Stepped()
    assert run.loop.paused and run.loop.settings.publishes_clock
    for _ in range(3):
        assert run.loop.cycle()
    assert run.samples == [] and run.engine.time == 0.0
    assert run.loop.stamp_now() == 0.0


def test_each_step_is_one_physics_step_and_each_due_publication_is_sent():
    run = Stepped()
    outcome = run.step(2000)
    assert outcome.completed == 2000 and outcome.problem is None
    assert run.engine.time == 2000 * (1.0 / PHYSICS_RATE) == 2.0
    every = round(PHYSICS_RATE / PUBLISH_RATE)
    # the state at 0 (never published before), then every `every` steps to the end
    assert [s.time * PHYSICS_RATE for s in run.samples] == pytest.approx(
        [k * every for k in range(2000 // every + 1)], abs=1e-9)
    assert all(s.due is None for s in run.samples)          # at once, not paced
    assert [s.stamp for s in run.samples] == [s.time for s in run.samples]


def test_publications_keep_their_grid_across_requests_of_any_length():
    run = Stepped()
    for n in (3, 4, 13, 1, 9):                                # 30 steps in all
        run.step(n)
    assert [round(s.time * PHYSICS_RATE) for s in run.samples] == [0, 10, 20, 30]


def test_progress_comes_after_each_run_up_to_a_publication_and_cancel_ends_there():
    run = Stepped()
    seen = []
    outcome = run.step(25, progress=lambda done, left: seen.append((done, left)))
    assert seen == [(10, 15), (20, 5)] and outcome.completed == 25
    outcome = run.step(100, cancelled=lambda: len(seen) >= 4,
                       progress=lambda done, left: seen.append((done, left)))
    assert outcome.problem == STEPS_CANCELLED
    assert outcome.completed == 15                 # 5 to the grid at 30, then 10 more
    assert run.engine.time == 40 / PHYSICS_RATE


def test_steps_are_refused_while_playing_or_halted():
    run = Stepped(start_paused=False, real_time_factor=0.0)
    assert run.loop.request_steps(StepRequest(1, lambda o: None)) == STEPS_NOT_PAUSED
    with pytest.raises(ValueError, match='steps'):
        StepRequest(0, lambda o: None)
    with pytest.raises(ValueError, match='steps'):
        StepRequest(-3, lambda o: None)
    run = Stepped(EngineConfig(physics_rate=PHYSICS_RATE, drive='torque', max_omega=1.0))
    run.loop.submit('torque', 50.0)
    outcome = run.step(10_000)
    assert outcome.problem.startswith(STEPS_HALTED) and outcome.completed < 10_000
    assert run.loop.request_steps(StepRequest(1, lambda o: None)).startswith(STEPS_HALTED)


def test_a_command_while_paused_applies_at_the_next_step_not_before():
    run = Stepped(EngineConfig(physics_rate=PHYSICS_RATE, drive='torque'))
    run.step(5)
    run.loop.submit('torque', 2.0)
    assert run.engine.torque_command == 0.0                # not yet applied
    before = run.engine.angular_momentum()
    run.step(100)
    # dL/dt = Q (exact coupling): 2 N m over 100 steps of 1 ms
    assert run.engine.angular_momentum() - before == pytest.approx(2.0 * 0.1, rel=1e-9)


def _closed_loop(run: Stepped) -> list:
    """A torque command from the state every 7 steps; the states after each request."""
    states = []
    for _ in range(60):
        s = run.engine.state
        run.loop.submit('torque', -0.5 * float(s.omega - 2.0) - 3.0 * float(s.v))
        run.step(7)
        states.append(raw(run.engine.state))
    return states


def test_after_a_reset_of_state_and_time_the_same_steps_replay_bit_for_bit():
    run = Stepped(EngineConfig(physics_rate=PHYSICS_RATE, drive='torque'))
    first = _closed_loop(run)
    published = [raw(s.state) for s in run.samples]
    run.loop.reset(state=True, time=True)
    assert run.engine.time == 0.0
    run.samples.clear()
    assert _closed_loop(run) == first
    assert [raw(s.state) for s in run.samples] == published


def test_a_reset_of_time_alone_keeps_the_state_and_restarts_the_grid():
    run = Stepped(EngineConfig(physics_rate=PHYSICS_RATE, initial={'omega': 1.0}))
    run.step(123)
    state = run.engine.state
    run.loop.reset(state=False, time=True)
    assert run.engine.time == 0.0 and raw(run.engine.state) == raw(state)
    run.samples.clear()
    run.step(10)
    assert [s.time for s in run.samples] == [0.0, 10 / PHYSICS_RATE]


def test_a_parameter_change_during_a_request_takes_effect_at_its_end():
    """Between requests, as before the world released its lock at each publication:
    the request's samples are all at the old publish rate, the next one's at the new."""
    run = Stepped()
    changed = []

    def change(done, left):
        if not changed:         # from another thread in the node: mid-request here
            run.loop.reconfigure(run.engine.config, LoopSettings(
                realtime_priority=0, publish_rate=PUBLISH_RATE / 2, start_paused=True))
            changed.append(run.loop.settings.publish_rate)
    run.step(40, progress=change)
    assert changed == [PUBLISH_RATE]                     # not yet, within the request
    assert run.loop.settings.publish_rate == PUBLISH_RATE / 2    # at its end
    assert [round(s.time * PHYSICS_RATE) for s in run.samples] == [0, 10, 20, 30, 40]
    run.step(40)
    # the grid goes on from the change: the next instant as it was, then every 20 steps
    assert [round(s.time * PHYSICS_RATE) for s in run.samples][5:] == [50, 70]
