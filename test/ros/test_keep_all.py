"""KeepAllPublishing: a publication a KEEP_ALL subscriber holds up (rmw raises RCLError
after blocking) is waited for or dropped, and counted; a stop finishes the sample."""

import time

import pytest
from rclpy._rclpy_pybind11 import RCLError

from rotrod_ros.keep_all import KeepAllPublishing


class HeldUpPublisher:
    """Raises RCLError for the first ``refusals`` publications, then takes them."""

    def __init__(self, refusals: int, on_refusal=None) -> None:
        self.refusals, self.sent, self.on_refusal = refusals, [], on_refusal

    def publish(self, msg) -> None:
        if self.refusals:
            self.refusals -= 1
            if self.on_refusal:
                self.on_refusal()
            raise RCLError('publish failed: history full')
        self.sent.append(msg)


class Logger:
    def __init__(self) -> None:
        self.lines = []

    def info(self, text, **kw) -> None:
        self.lines.append(text)

    warning = info


def publishing(publisher, running=lambda: True, ok=lambda: True, stop_grace=0.0):
    return KeepAllPublishing({'joint_states': publisher}, Logger(), ok, running, stop_grace)


def test_a_held_up_publication_is_waited_for_or_dropped_and_counted():
    waited = HeldUpPublisher(3)
    sent = publishing(waited)
    sent.send('joint_states', 'a', wait=True)
    assert waited.sent == ['a'] and (sent.held_up, sent.dropped) == (1, 0)
    dropped = HeldUpPublisher(1)
    sent = publishing(dropped)
    sent.send('joint_states', 'b', wait=False)
    sent.send('joint_states', 'c', wait=False)
    assert dropped.sent == ['c'] and (sent.held_up, sent.dropped) == (1, 1)


def test_a_stop_while_held_up_still_publishes_the_sample_within_the_grace():
    """The lossless run's last sample: the source stops while a subscriber holds its
    publication up (before: dropped at once, one topic short of the others)."""
    running = [True]
    publisher = HeldUpPublisher(5, on_refusal=lambda: running.__setitem__(0, False))
    sent = publishing(publisher, running=lambda: running[0], stop_grace=2.0)
    sent.send('joint_states', 'last', wait=True)
    assert publisher.sent == ['last'] and sent.dropped == 0


def test_the_grace_after_a_stop_is_bounded():
    publisher = HeldUpPublisher(10**9)
    sent = publishing(publisher, running=lambda: False, stop_grace=0.2)
    start = time.monotonic()
    sent.send('joint_states', 'x', wait=True)
    first = time.monotonic() - start
    sent.send('joint_states', 'y', wait=True)          # the grace is spent: at once
    second = time.monotonic() - start - first
    assert 0.2 <= first < 2.0 and second < 0.5, (first, second)
    assert publisher.sent == [] and (sent.held_up, sent.dropped) == (2, 2)


def test_an_error_while_the_context_shuts_down_is_raised():
    sent = publishing(HeldUpPublisher(1), ok=lambda: False)
    with pytest.raises(RCLError):
        sent.send('joint_states', 'z', wait=True)


class CountedPublisher:
    """Counts the looks at its subscribers."""

    def __init__(self) -> None:
        self.looks = 0

    def get_subscription_count(self) -> int:
        self.looks += 1
        return 1


def test_publishers_made_together_look_for_subscribers_at_their_own_phase(monkeypatch):
    """Two rods' looks every 0.1 s: both at once at first, then the one of phase 0.5
    half a period after the one of phase 0; each once a period from then on."""
    now = [100.0]
    monkeypatch.setattr(time, 'monotonic', lambda: now[0])
    counted = {phase: CountedPublisher() for phase in (0.0, 0.5)}
    rods = {phase: KeepAllPublishing({'joint_states': p}, Logger(), lambda: True,
                                     lambda: True, phase=phase)
            for phase, p in counted.items()}
    looked = []
    for k in range(40):                        # 10 ms apart: 0.4 s
        now[0] = 100.0 + 0.01 * k + 1e-6
        for phase, rod in rods.items():
            before = counted[phase].looks
            rod.look(['joint_states'], 0.1)
            if counted[phase].looks > before:
                looked.append((k, phase))
    assert looked[:2] == [(0, 0.0), (0, 0.5)]
    assert [k for k, phase in looked if phase == 0.0] == [0, 10, 20, 30]
    assert [k for k, phase in looked if phase == 0.5] == [0, 15, 25, 35]
    with pytest.raises(ValueError, match='phase'):
        KeepAllPublishing({}, Logger(), lambda: True, lambda: True, phase=1.0)


def test_a_large_world_s_rods_look_less_often_so_that_its_looks_cost_twenty_rods_looks():
    from rotrod_ros.rod_io import LOOK, LOOK_RODS, look_period
    assert look_period(1) == look_period(LOOK_RODS) == LOOK == 0.1
    for rods in (21, 40, 100):                  # looks per second of the whole world
        assert rods / look_period(rods) == pytest.approx(LOOK_RODS / LOOK)
    assert look_period(100) == pytest.approx(0.5)
