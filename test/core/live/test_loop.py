"""The real-time loop (rotrod_core.live.loop) run deterministically on a fake clock.

The fake clock's waits move its time; commands "arrive" at scheduled fake instants
(while the loop sleeps or idles, as in a real run). Pacing is checked against the
definition of the real-time factor, command timing against the hub's angular
momentum, which only the hub torque changes (exact coupling): L(t) = sum of Q_i times
how long Q_i acted.
"""

import dataclasses
import heapq
import itertools
import struct
import sys
import threading
import time

import numpy as np
import pytest

import rotrod_core.live.scheduling as scheduling
from rotrod_core.live.engine import ERROR, OK, EngineConfig, SimulationEngine
from rotrod_core.live.loop import (
    IDLE_WAIT,
    LEAD,
    MAX_BACKLOG,
    PENDING_COMMANDS,
    LoopSettings,
    RealTimeLoop,
)
from rotrod_core.live.world import World

START = 1000.0          # fake monotonic time at which the loop is made, s
EPOCH = 1.7e9           # fake epoch time then, s
DT = 1e-3               # physics step (physics_rate 1000 Hz), s


class FakeClock:
    """Monotonic and epoch time that move only when the loop waits (or a test says)."""

    def __init__(self):
        self.now = START
        self._events = []
        self._order = itertools.count()
        self.spins = []
        """The spin asked of each sleep_until (s)."""

    def monotonic(self) -> float:
        return self.now

    def epoch(self) -> float:
        return EPOCH + (self.now - START)

    def at(self, t: float, action) -> None:
        """Run ``action`` when the clock reaches monotonic time ``t``."""
        heapq.heappush(self._events, (t, next(self._order), action))

    def _run_until(self, t: float, event=None) -> bool:
        while self._events and self._events[0][0] <= t:
            at, _, action = heapq.heappop(self._events)
            self.now = max(self.now, at)
            action()
            if event is not None and event.is_set():
                return True
        self.now = max(self.now, t)
        return event is not None and event.is_set()

    def advance(self, seconds: float) -> None:
        self._run_until(self.now + seconds)

    def wait(self, event, timeout: float) -> bool:
        if event.is_set():
            return True
        return self._run_until(self.now + timeout, event)

    def sleep_until(self, due: float, stop, spin: float = 0.0) -> bool:
        self.spins.append(spin)
        self._run_until(due)
        return not stop.is_set()


class Logger:
    """Collects (level, message); like rclpy's logger, refuses a call site (file and
    line of the caller) that logs at two severities."""

    def __init__(self):
        self.lines = []
        self.sites = {}

    def __getattr__(self, level):
        def log(message):
            caller = sys._getframe(1)
            site = (caller.f_code.co_filename, caller.f_lineno)
            if self.sites.setdefault(site, level) != level:
                raise ValueError('Logger severity cannot be changed between calls.')
            self.lines.append((level, message))
        return log

    def count(self, text: str) -> int:
        return sum(text in message for _, message in self.lines)


class Run:
    """A loop on a fake clock and what it published: (clock time, sample) and statuses."""

    def __init__(self, config=None, **settings):
        settings = {'realtime_priority': 0, 'cpu_dma_latency': -1, **settings}
        self.clock = FakeClock()
        self.log = Logger()
        self.samples = []
        self.statuses = []
        self.engine = SimulationEngine(config or EngineConfig())
        self.loop = RealTimeLoop(
            self.engine, LoopSettings(**settings), self._publish,
            publish_status=self.statuses.extend, logger=self.log, clock=self.clock,
            inputs={'omega': 'cmd/omega', 'torque': 'cmd/torque'})

    def _publish(self, sample, settings, config, snapshot):
        self.samples.append((self.clock.now, sample))

    def until_wall(self, t: float) -> None:
        """Cycle until the fake clock reaches START + t."""
        while self.clock.now < START + t:
            assert self.loop.cycle()

    def submit_at(self, t: float, kind: str, value: float, source=None) -> None:
        """A command arriving at wall time START + t."""
        self.clock.at(START + t, lambda: self.loop.submit(kind, value, source))

    @property
    def times(self):
        return [s.time for _, s in self.samples]


def test_in_a_world_the_published_pass_follows_every_rods_sample_of_each_instant():
    """The host's second pass (``published``: estimates, markers) runs once per instant,
    after the sample of every rod of that instant was handed to ``publish``."""
    world = World(1000.0)
    for name in ('a', 'b', 'c'):
        SimulationEngine(EngineConfig(), world=world, name=name)
    events: list = []
    clock = FakeClock()
    loop = RealTimeLoop(world, LoopSettings(realtime_priority=0, cpu_dma_latency=-1),
                        lambda s, *context: events.append((s.time, s.rod)), clock=clock,
                        logger=Logger(), published=lambda: events.append('published'))
    while clock.now < START + 0.2:
        assert loop.cycle()
    assert events and events[-1] == 'published'
    groups: list = []
    current: list = []
    for e in events:
        if e == 'published':
            groups.append(current)
            current = []
        else:
            current.append(e)
    assert len(groups) >= 19
    for k, group in enumerate(groups):
        assert sorted(rod for _, rod in group) == ['a', 'b', 'c']
        times = {t for t, _ in group}
        assert len(times) == 1 and times.pop() == pytest.approx(0.01 * k, abs=1e-12)


def torque_config(**kw):
    return EngineConfig(drive='torque', **kw)


# ----------------------------------------------------------------- pacing

def test_in_real_time_each_publication_is_sent_at_its_simulated_instant():
    run = Run()
    run.until_wall(1.0)
    # every 1/publish_rate = 10 ms of simulated time, from 0, none skipped
    assert run.times == pytest.approx([0.01 * k for k in range(len(run.times))], abs=1e-12)
    assert len(run.times) in (100, 101)
    for sent, s in run.samples:
        # factor 1: simulated time t is due at wall time START + t, and sent then
        assert s.due == pytest.approx(START + s.time, abs=1e-12)
        assert sent == s.due
        # no /clock in real time: stamps are epoch times (simulated time 0 = EPOCH)
        assert s.stamp == pytest.approx(EPOCH + s.time, abs=1e-6)


def test_a_tick_integrates_its_publication_the_lead_ahead_of_its_due_time():
    run = Run()
    ticks = []                      # (clock time, simulated time reached) per integration
    advance = run.engine.world.advance

    def recorded(steps):
        done = advance(steps)
        ticks.append((run.clock.now, run.engine.time))
        return done

    run.engine.world.advance = recorded
    run.until_wall(0.5)
    # after the first tick (at the start: up to LEAD), each 10 ms of simulated time is
    # integrated in one go, LEAD before it is due
    integrated = [(wall, t) for wall, t in ticks if wall > START]
    assert len(integrated) >= 45
    for wall, t in integrated:
        assert wall == pytest.approx(START + t - LEAD, abs=1e-9)


def test_at_twice_real_time_simulated_time_runs_twice_as_fast_and_stamps_are_it():
    run = Run(real_time_factor=2.0)
    run.until_wall(0.5)
    assert len(run.times) in (100, 101)
    for sent, s in run.samples:
        assert sent == pytest.approx(START + s.time / 2.0, abs=1e-12)
        assert s.stamp == s.time                 # /clock: stamps are simulated time


def test_as_fast_as_possible_every_cycle_publishes_without_waiting():
    run = Run(real_time_factor=0.0)
    for _ in range(50):
        assert run.loop.cycle()
    assert run.clock.now == START                # nothing waited
    assert run.times == pytest.approx([0.01 * k for k in range(50)], abs=1e-12)
    assert all(s.due is None for _, s in run.samples)


def test_a_change_of_publish_rate_changes_the_grid_at_once():
    run = Run()
    run.until_wall(0.3)
    n = len(run.samples)
    run.loop.reconfigure(run.engine.config, LoopSettings(publish_rate=50.0,
                                                         realtime_priority=0))
    run.until_wall(0.8)
    gaps = [b - a for a, b in zip(run.times[n:], run.times[n + 1:])]
    assert gaps and all(g == pytest.approx(0.02, abs=1e-12) for g in gaps)


def test_after_a_stall_longer_than_the_backlog_it_skips_ahead_once():
    run = Run()
    run.until_wall(0.2)
    t = run.engine.time
    run.clock.advance(MAX_BACKLOG + 0.5)         # the thread did not run for 1.5 s
    run.until_wall(run.clock.now - START + 0.2)
    assert run.loop.overruns == 1 and run.log.count('skipping ahead') == 1
    # it did not integrate the lost 1.5 s: it goes on from where it was
    assert run.engine.time < t + 0.2 + 0.02
    assert all(b - a == pytest.approx(0.01, abs=1e-12)
               for a, b in zip(run.times, run.times[1:]))


# ----------------------------------------------------------------- markers

def test_markers_at_marker_rate_of_simulated_time_in_real_time():
    run = Run(marker_rate=20.0)
    run.until_wall(1.0)
    marked = [s.time for _, s in run.samples if s.markers]
    # every fifth publication (100 Hz / 20 Hz)
    assert marked == pytest.approx([0.04 + 0.05 * k for k in range(len(marked))], abs=1e-12)
    assert len(marked) in (19, 20)


def test_faster_than_real_time_markers_at_most_twice_marker_rate_per_wall_second():
    run = Run(real_time_factor=0.0, marker_rate=20.0)
    marked = []
    for _ in range(400):                         # 4 s of simulated time in 0.4 s of wall
        run.loop.cycle()
        run.clock.advance(0.001)
        if run.samples[-1][1].markers:
            marked.append(run.clock.now)
    # at most one per 1 / (2 x 20 Hz) = 25 ms of wall time: 16 in 0.4 s
    assert 14 <= len(marked) <= 17
    assert min(b - a for a, b in zip(marked, marked[1:])) >= 0.025 - 1e-9


def test_in_a_world_each_rods_markers_come_at_marker_rate_on_its_own_sample():
    """Ten rods, markers every fifth sample: each rod's every fifth sample, two rods'
    per sample, not all ten on one."""
    world = World(1000.0)
    for k in range(10):
        SimulationEngine(EngineConfig(), world=world, name=f'rod{k}')
    marked: dict = {}
    clock = FakeClock()
    loop = RealTimeLoop(world, LoopSettings(realtime_priority=0, cpu_dma_latency=-1,
                                            marker_rate=20.0),
                        lambda s, *context: marked.setdefault(s.time, []).append(
                            (s.rod, s.markers)), clock=clock, logger=Logger())
    while clock.now < START + 1.0:
        assert loop.cycle()
    assert len(marked) >= 100
    for rods in marked.values():
        assert sum(m for _, m in rods) == 2
    for k in range(10):
        times = [t for t, rods in marked.items() if (f'rod{k}', True) in rods]
        assert np.diff(times) == pytest.approx(0.05, abs=1e-12)


def test_markers_off_means_none():
    run = Run(markers=False)
    run.until_wall(0.5)
    assert not any(s.markers for _, s in run.samples)


# ----------------------------------------------------------------- commands

def test_a_command_takes_effect_at_the_simulated_instant_it_arrived():
    run = Run(torque_config())
    q = 0.01
    run.submit_at(0.3037, 'torque', q)     # between two ticks, while the loop idles
    run.until_wall(1.0)
    # torque drive applies a torque from the step instant nearest to its arrival (0.304 s)
    # on; the angular momentum is then exactly q times how long it acted
    assert run.engine.angular_momentum() == pytest.approx(q * (run.engine.time - 0.304),
                                                          rel=1e-9)


def test_with_a_published_clock_a_command_is_dated_from_the_last_publication():
    # at factor 2 a sender on /clock sees simulated time through the publications: the
    # latest one's time plus twice the wall time since (here the same as the pacing)
    run = Run(torque_config(), real_time_factor=2.0)
    q = 0.02
    run.submit_at(0.15185, 'torque', q)    # simulated 0.3037 s
    run.until_wall(0.5)
    assert run.engine.angular_momentum() == pytest.approx(q * (run.engine.time - 0.304),
                                                          rel=1e-9)


def test_commands_apply_in_the_order_they_arrived():
    run = Run(torque_config())
    q1, q2 = 0.01, -0.004
    run.submit_at(0.2003, 'torque', q1)
    run.submit_at(0.5003, 'torque', 0.05)
    run.submit_at(0.5003, 'torque', q2)    # same instant, later: it wins
    run.until_wall(1.0)
    expected = q1 * (0.5 - 0.2) + q2 * (run.engine.time - 0.5)
    assert run.engine.angular_momentum() == pytest.approx(expected, rel=1e-9)
    assert run.engine.accepted_commands == 3


def test_a_flood_beyond_the_pending_bound_drops_the_oldest_and_says_so():
    run = Run(torque_config())
    run.until_wall(0.1)
    for k in range(PENDING_COMMANDS + 5):
        run.loop.submit('torque', 1e-6 * k)
    assert run.loop.dropped_commands == 5
    run.until_wall(0.2)
    assert run.engine.accepted_commands == PENDING_COMMANDS
    assert run.engine.torque_command == pytest.approx(1e-6 * (PENDING_COMMANDS + 4))
    assert run.log.count('5 dropped so far') == 1
    run.loop.report(force=True)
    assert dict(run.statuses[-1].values)['dropped_commands'] == 5


def test_rejections_are_logged_per_source_and_throttled():
    run = Run(torque_config())
    for t in (0.1, 0.2, 0.3):
        run.submit_at(t, 'torque', 1e9)                    # beyond max_torque
        run.submit_at(t, 'omega', 1.0)                     # inactive drive
        run.submit_at(t, 'torque', 1e9, 'joint_command')   # another source of torques
    run.until_wall(0.5)
    assert run.engine.rejected_commands == 9
    # once each within the 1 s throttle; one source does not silence another
    assert run.log.count('cmd/torque rejected: torque 1e+09 N m exceeds') == 1
    assert run.log.count("cmd/omega rejected: omega setpoint ignored: drive is 'torque'") == 1
    assert run.log.count('joint_command rejected') == 1
    run.submit_at(1.35, 'torque', 1e9)
    run.until_wall(1.5)
    assert run.log.count('cmd/torque rejected') == 2


def test_malformed_messages_are_counted_and_logged_throttled_and_change_nothing():
    run = Run(torque_config())
    q = 0.01
    run.submit_at(0.1, 'torque', q, 'joint_command')
    for t in (0.2, 0.3, 0.4):
        run.clock.at(START + t, lambda: run.loop.reject('joint_command', 'no velocity'))
    run.clock.at(START + 0.45, lambda: run.loop.reject('other', 'bad'))
    run.until_wall(1.0)
    assert run.loop.malformed_commands == 4 and run.engine.rejected_commands == 0
    assert run.log.count('joint_command rejected: no velocity') == 1   # 1 s throttle
    assert run.log.count('other rejected: bad') == 1                   # per source
    # the torque accepted before acts throughout: L = q (t - 0.1 s)
    assert run.engine.angular_momentum() == pytest.approx(q * (run.engine.time - 0.1),
                                                          rel=1e-9)
    run.loop.report(force=True)
    assert dict(run.statuses[-1].values)['malformed_commands'] == 4


def test_the_command_timeout_stops_the_torque_once_and_a_command_resumes():
    run = Run(torque_config(command_timeout=0.5))
    q = 0.01
    run.submit_at(0.1003, 'torque', q)
    run.until_wall(1.0)
    # q acted from 0.100 s until the timeout ran out 0.5 s after it was accepted
    assert run.engine.angular_momentum() == pytest.approx(q * 0.5, rel=1e-9)
    assert run.log.count('no command on cmd/torque for 0.5 s (command_timeout) at '
                         'simulated time 0.600 s: hub torque set to 0 (free coast)') == 1
    assert run.statuses[-1].level == 1 and 'coasting' in run.statuses[-1].message
    run.submit_at(1.2, 'torque', 0.0)
    run.until_wall(1.4)
    assert run.log.count('cmd/torque: commands again after the command timeout') == 1


# ----------------------------------------------------------------- pause and reset

def test_pause_stops_simulated_time_and_resume_goes_on_from_there():
    run = Run()
    run.until_wall(0.3)
    assert run.loop.pause(True).startswith('paused at simulated time')
    t, n = run.engine.time, len(run.samples)
    run.until_wall(2.3)                          # 2 s paused
    assert run.engine.time == t and len(run.samples) == n
    assert run.clock.now - START < 2.3 + IDLE_WAIT + 1e-9
    assert run.statuses[-1].message.startswith('paused; ')
    assert run.loop.pause(True) == 'already paused'
    assert run.loop.pause(False).startswith('resumed')
    resumed = run.clock.now
    run.until_wall(2.6)
    times = run.times
    # the grid goes on where it stopped; due times count from the resume
    assert all(b - a == pytest.approx(0.01, abs=1e-12) for a, b in zip(times, times[1:]))
    for sent, s in run.samples[n:]:
        assert sent == pytest.approx(resumed + s.time - t, abs=0.01)
    # stamps follow the wall clock: they jump over the pause, never back
    stamps = [s.stamp for _, s in run.samples]
    assert all(b > a for a, b in zip(stamps, stamps[1:]))
    assert stamps[n] - stamps[n - 1] > 1.9


def test_reset_returns_to_the_initial_state_and_drops_pending_commands():
    run = Run(torque_config())
    run.submit_at(0.1, 'torque', 0.05)
    run.until_wall(0.5)
    assert run.engine.state.omega > 0
    run.loop.submit('torque', 0.05)              # pending when the reset comes
    halted, t = run.loop.reset()
    assert halted is None and t == run.engine.time
    run.until_wall(1.0)
    s = run.engine.state
    assert (s.omega, s.u, s.v, s.theta) == (0.0, 0.0, 0.0, 0.0)   # at rest, no torque
    assert run.engine.accepted_commands == 1
    times = run.times
    assert all(b - a == pytest.approx(0.01, abs=1e-12) for a, b in zip(times, times[1:]))


def test_a_halt_reports_error_at_once_stops_publishing_and_a_reset_clears_it():
    run = Run(torque_config(max_omega=2.0))
    run.submit_at(0.05, 'torque', 100.0)         # spins past max_omega within 0.1 s
    run.until_wall(0.5)
    assert run.engine.halted and 'max_omega' in run.engine.halted
    assert run.log.count('simulation halted') == 1
    assert run.statuses[-1].level == ERROR
    n = len(run.samples)
    run.until_wall(1.0)
    assert len(run.samples) == n
    halted, _ = run.loop.reset()
    assert 'max_omega' in halted
    run.until_wall(1.5)
    assert len(run.samples) > n and run.statuses[-1].level == OK


# ----------------------------------------------------------------- status

def test_status_at_diagnostics_rate_with_the_loops_counters():
    run = Run(diagnostics_rate=2.0)
    run.until_wall(3.0)
    assert len(run.statuses) in (6, 7)           # at 0, 0.5, ..., 3.0 s of wall time
    values = dict(run.statuses[-1].values)
    assert values['paused'] is False and values['real_time_factor'] == 1.0
    assert values['overruns'] == 0 and values['dropped_commands'] == 0


def test_in_a_world_each_rods_periodic_status_comes_at_the_rate_spread_over_the_period():
    """Ten rods at 1 Hz: each rod's status once a second, at most two rods' in one
    publication after the first (all, their levels new), not all ten together."""
    world = World(1000.0)
    names = [f'rod{k}' for k in range(10)]
    for name in names:
        SimulationEngine(EngineConfig(), world=world, name=name)
    batches: list = []
    clock = FakeClock()
    loop = RealTimeLoop(world, LoopSettings(realtime_priority=0, cpu_dma_latency=-1),
                        lambda s, *context: None, clock=clock, logger=Logger(),
                        publish_status=batches.append)
    while clock.now < START + 3.0:
        assert loop.cycle()
    assert sorted(st.rod for st in batches[0]) == names and len(batches) > 20
    assert max(len(batch) for batch in batches[1:]) <= 2
    for name in names:
        count = sum(st.rod == name for batch in batches for st in batch)
        assert count in (3, 4)      # at 0, then once a second on the rod's phase


def test_a_failing_publication_is_reported_and_ends_the_loop():
    run = Run()
    calls = []

    def publish(sample, *context):
        calls.append(sample)
        if len(calls) == 3:
            raise RuntimeError('disk on fire')

    run.loop._publish = publish
    run.loop.run()                               # returns: the loop ended
    assert len(calls) == 3
    assert run.log.count("physics thread failed: RuntimeError('disk on fire')") == 1
    assert run.statuses[-1].level == ERROR and 'disk on fire' in run.statuses[-1].message


# ----------------------------------------------------------------- settings, thread

@pytest.mark.parametrize('name, value', [
    ('publish_rate', 0.0), ('real_time_factor', -1.0), ('real_time_factor', float('nan')),
    ('marker_rate', float('inf')), ('realtime_priority', 100), ('realtime_priority', 5.0),
    ('cpu_dma_latency', -2), ('publication_spin', -1e-4), ('publication_spin', 0.01),
    ('publication_spin', float('nan')),
])
def test_bad_settings_are_refused_with_the_name(name, value):
    with pytest.raises(ValueError, match=name):
        LoopSettings(**{name: value})


def test_an_unknown_command_kind_is_refused():
    run = Run()
    with pytest.raises(ValueError, match='command kind'):
        run.loop.submit('position', 1.0)


def test_the_thread_on_the_system_clock_publishes_in_real_time_and_stops():
    published = []
    loop = RealTimeLoop(SimulationEngine(), LoopSettings(realtime_priority=0), lambda s, *c:
                        published.append((time.monotonic(), s)), logger=Logger())
    loop.start()
    time.sleep(0.5)
    loop.stop()
    assert not any(t.name == 'rotrod_physics' for t in threading.enumerate())
    n = len(published)
    assert 40 <= n <= 52                          # 100 Hz for 0.5 s
    late = [sent - s.due for sent, s in published]
    assert min(late) >= 0                         # never before its time


# ----------------------------------------------------------------- scheduling

def test_real_time_priority_while_paced_only_and_the_clock_starts_after_the_change(
        monkeypatch):
    asked = []

    def slow(priority, logger, what):           # the change and its logging take 60 ms
        asked.append(priority)
        run.clock.advance(0.06)
        return priority != 40                   # 40 is refused

    monkeypatch.setattr(scheduling, 'run_current_thread_at', slow)
    run = Run(realtime_priority=30)
    run.until_wall(0.3)
    assert asked == [30]
    # the pacing starts after the change: no publication late, none in a burst
    assert all(sent == s.due for sent, s in run.samples)
    assert run.samples[0][1].due == pytest.approx(START + 0.06, abs=1e-9)
    fast = LoopSettings(real_time_factor=0.0, realtime_priority=30)
    run.loop.reconfigure(run.engine.config, fast)
    run.loop.cycle()
    run.loop.reconfigure(run.engine.config, LoopSettings(realtime_priority=40))
    run.until_wall(run.clock.now - START + 0.1)
    run.until_wall(run.clock.now - START + 0.1)
    assert asked == [30, 0, 40]                 # ordinary as fast as possible; 40 once


def test_publications_sleep_and_poll_only_when_asked_and_not_while_cpus_are_held_awake(tmp_path):
    device = tmp_path / 'cpu_dma_latency'
    device.write_bytes(b'')
    run = Run(cpu_dma_latency=0)
    run.loop._scheduling = scheduling.ThreadScheduling(run.log, 'physics thread',
                                                       device=str(device))
    run.until_wall(0.2)
    assert len(run.clock.spins) >= 19 and set(run.clock.spins) == {0.0}
    run.loop.reconfigure(run.engine.config,
                         dataclasses.replace(run.loop.settings, cpu_dma_latency=-1))
    n = len(run.clock.spins)
    run.until_wall(0.4)
    # by default a publication only sleeps to its due time, with or without the request
    assert len(run.clock.spins) - n >= 19 and set(run.clock.spins[n + 1:]) == {0.0}
    # the opt-in poll, only while no request of at most SLEEP_ONLY_LATENCY is held
    run.loop.reconfigure(run.engine.config,
                         dataclasses.replace(run.loop.settings, publication_spin=3e-4))
    n = len(run.clock.spins)
    run.until_wall(0.6)
    assert len(run.clock.spins) - n >= 19 and set(run.clock.spins[n + 1:]) == {3e-4}
    run.loop.reconfigure(run.engine.config,
                         dataclasses.replace(run.loop.settings, cpu_dma_latency=0))
    n = len(run.clock.spins)
    run.until_wall(0.8)
    assert len(run.clock.spins) - n >= 19 and set(run.clock.spins[n + 1:]) == {0.0}
    assert all(sent == s.due for sent, s in run.samples)


def test_the_cpu_latency_request_is_held_as_asked_and_released(tmp_path):
    device = tmp_path / 'cpu_dma_latency'
    device.write_bytes(b'')
    log = Logger()
    held = scheduling.ThreadScheduling(log, 'test thread', device=str(device))
    assert held.update(0, 0) and device.read_bytes() == struct.pack('=i', 0)
    assert not held.update(0, 0)                # nothing changes, nothing said
    assert held.update(0, -1)
    assert log.count('idle CPUs wake within 0 us') == 1 and log.count('released') == 1
    missing = scheduling.ThreadScheduling(log, 'test thread', str(tmp_path / 'none'))
    assert missing.update(0, 5) and not missing.update(0, 5)    # refused once, not again
    assert log.count('cannot hold a CPU wake-up latency of 5 us') == 1
