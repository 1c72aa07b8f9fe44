"""Pacing: wall clock to simulated time and back, and stamps that never go back."""

import pytest

from rotrod_core.live.pacing import Pacer, StampClock


def test_pacer_maps_wall_to_simulated_time_and_back():
    p = Pacer(4.0, sim=10.0, wall=100.0)
    assert p.sim_time(100.5) == pytest.approx(12.0)
    assert p.wall_time(12.0) == pytest.approx(100.5)
    p.anchor(1.0, sim=12.0, wall=200.0)                 # e.g. after a pause
    assert p.sim_time(200.25) == pytest.approx(12.25)
    fast = Pacer(0.0, 0.0, 0.0)
    assert not fast.paced
    with pytest.raises(ValueError):
        fast.sim_time(1.0)
    with pytest.raises(ValueError):
        Pacer(-1.0, 0.0, 0.0)


def test_stamps_follow_the_wall_clock_but_never_go_back():
    c = StampClock(origin=1000.0)
    assert c.stamp(5.0) == 1005.0
    c.follow_wall(sim=5.0, epoch=1010.0)                # stood still 5 s: jump forward
    assert c.stamp(5.0) == 1010.0
    c.follow_wall(sim=5.0, epoch=1001.0)                # never backwards
    assert c.stamp(5.0) == 1010.0
