"""Stages of a run from its hub angular velocity, and the critical deflection's events."""

import math

import numpy as np
import pytest

from rotrod_core.analysis.run_events import CriticalDeflectionWatch, StageTracker
from rotrod_core.analysis.stages import eq26_stages
from rotrod_core.command.profiles import Eq26Profile

STEP = 0.01


def feed(tracker, t, w, sizes):
    """Push (t, w) in batches of the given sizes (cycled); return the events."""
    events, i, k = [], 0, 0
    while i < len(t):
        n = sizes[k % len(sizes)]
        events += tracker.push(t[i:i + n], w[i:i + n])
        i, k = i + n, k + 1
    tracker.finish()
    return events


@pytest.mark.parametrize('sizes', [[1], [7, 1, 30], [100000]])
def test_eq26_stages_are_found_from_omega_alone_in_any_batches(sizes):
    profile = Eq26Profile(period=15.0, omega_target=2.0)
    t = np.round(np.arange(-0.5, 40.0 + STEP / 2, STEP), 10)
    w = np.where(t < 0, 0.0, profile.omega(np.maximum(t, 0.0)))
    tracker = StageTracker()
    events = feed(tracker, t, w, sizes)
    expected = [('rest', -0.5)] + [(name, start) for name, start, _ in eq26_stages(15.0, 40.0)]
    assert tracker.stages == [name for name, _ in expected]
    # each stage starts at its closed-form time, to one sample
    assert np.allclose(tracker.starts, [start for _, start in expected], atol=STEP + 1e-9)
    assert [e.time for e in events] == tracker.starts
    assert [e.kind for e in events] == ['stage'] * 5
    assert [e.value for e in events][1:4] == pytest.approx([0.0, 2.0, 2.0], abs=1e-6)
    # every sample has its stage: the one its time falls in
    index = tracker.stage_index(t)
    assert index.min() == 0 and tracker.decided_until == math.inf


def test_a_free_rotation_trading_momentum_with_the_whirl_is_one_hold():
    t = np.arange(0.0, 20.0, STEP)
    w = 2.0 + 1e-3 * np.sin(2 * np.pi * 2.0 * t)       # |dw| per half period < MIN_CHANGE
    tracker = StageTracker()
    assert [e.text.split()[0] for e in feed(tracker, t, w, [25])] == ['hold']


def test_a_spin_up_in_the_negative_sense_is_a_spin_up():
    t = np.arange(0.0, 6.0, STEP)
    w = -np.clip(t - 1.0, 0.0, 3.0)                     # rest, then |w| grows to 3, hold
    tracker = StageTracker()
    feed(tracker, t, w, [40])
    assert tracker.stages == ['rest', 'spin-up', 'hold']
    assert tracker.starts[1:] == pytest.approx([1.0, 4.0], abs=STEP + 1e-9)


def test_pending_samples_are_those_of_an_undecided_excursion():
    tracker = StageTracker()
    t = np.arange(0.0, 1.0, STEP)
    tracker.push(t, np.zeros_like(t))                    # at rest: all decided
    assert tracker.decided_until > t[-1]
    t2 = np.arange(1.0, 1.1, STEP)                       # starts moving: 0.1 s < DWELL
    tracker.push(t2, 0.5 * (t2 - 0.99))
    assert tracker.decided_until == pytest.approx(t[-1])    # from the last rest sample on
    assert tracker.stages == ['rest']


def test_the_first_crossing_of_the_critical_deflection_and_its_peak():
    limit, peak = 3e-3, 4e-3
    t = np.arange(0.0, 20.0, STEP)
    r = peak * np.sin(np.pi * t / 10.0) ** 2             # two excursions beyond the limit
    phase = 0.3
    u, v = r * np.cos(phase), r * np.sin(phase)
    watch = CriticalDeflectionWatch(limit)
    events = []
    for i in range(0, len(t), 37):
        events += watch.push(t[i:i + 37], u[i:i + 37], v[i:i + 37])
    events += watch.finish()
    crossed = 10.0 / np.pi * np.arcsin(np.sqrt(limit / peak))     # r(t) = limit
    assert [e.kind for e in events] == ['critical', 'peak']      # the first excursion only
    assert events[0].time == pytest.approx(crossed, abs=STEP)
    assert events[0].time > crossed
    assert events[1].time == pytest.approx(5.0, abs=1e-9)
    assert events[1].value == pytest.approx(peak)
    assert watch.peak == (events[1].time, events[1].value)


def test_an_excursion_still_beyond_the_limit_at_the_end_has_its_peak_so_far():
    watch = CriticalDeflectionWatch(3e-3)
    t = np.arange(0.0, 1.0, STEP)
    assert [e.kind for e in watch.push(t, 2e-3 + 2e-3 * t, 0 * t)] == ['critical']
    (peak,) = watch.finish()
    assert (peak.time, peak.value) == (pytest.approx(t[-1]), pytest.approx(2e-3 + 2e-3 * t[-1]))
