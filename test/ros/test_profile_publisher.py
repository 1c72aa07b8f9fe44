"""The profile publisher, as a real process."""

import os
import time

import numpy as np
import pytest
from builtin_interfaces.msg import Time
from node_probes import collect, namespace
from reference import eq26
from ros_harness import ros_arguments
from rosgraph_msgs.msg import Clock
from std_msgs.msg import Float64

from rotrod_ros.profile_publisher import MATCH_SETTLE

pytestmark = pytest.mark.ros


def test_profile_publisher_waits_streams_the_profile_and_exits(ros_processes, ros_node,
                                                               request):
    ns = namespace(request)
    pub = ros_processes.start_console_script('profile_publisher', *ros_arguments(
        namespace=ns, params={'profile': 'eq26', 'period': 0.5, 'rate': 100.0,
                              'duration': 2.0}))
    pub.wait_for_output('waiting for a subscriber', timeout=30)
    time.sleep(0.5)
    assert pub.running                                   # nobody listening: it waits
    subscribed = time.time()
    received = collect(ros_node, f'{ns}/cmd/omega', Float64)
    ros_node.spin_until(lambda: pub.poll() is not None, 30, 'the publisher exits')
    # what it sent may still be queued behind this process (a loaded machine may hold
    # it up past a fixed 0.3 s): wait for the count it logged, checked exactly below
    ros_node.spin_until(lambda: len(received) >= 201, 10, 'the 201 samples')
    ros_node.spin_for(0.1)
    assert pub.returncode == 0
    assert 'start: streaming eq26' in pub.output and 'end: published 201 samples' in pub.output
    if os.geteuid() == 0:                                # permitted: real-time priority
        assert 'streaming at SCHED_FIFO priority 50' in pub.output
    # the sender lets the subscriber match it too before it starts: no start burst.
    # Timed by DDS (wall clock), not by this process's callbacks, which a loaded machine
    # holds up: the source time (when the sender published) shows that it waited and
    # paced the samples; the reception time (when this subscription's DDS layer got
    # them) that they did not come in together, which is what a start burst is: samples
    # sent before the subscription matched the sender come in later, at once, with
    # their source times still 10 ms apart (with MATCH_SETTLE = 0 under load: 330 ms late)
    sent = np.array([source for _, source, _ in received])
    got = np.array([reception for _, _, reception in received])
    assert sent[0] - subscribed >= MATCH_SETTLE         # it waited after the match
    assert sent[19] - sent[0] >= 0.15                   # 19 intervals of 10 ms, paced ...
    assert got[19] - got[0] >= 0.15                     # ... and delivered so, not together
    values = [m.data for m, _, _ in received]
    assert len(values) == 201
    expected = [eq26(k / 100.0, T=0.5)[0] for k in range(201)]   # docs/model.md, sample k
    assert values == pytest.approx(expected, abs=1e-12)


def test_profile_publisher_follows_the_sim_clock(ros_processes, ros_node, request):
    ns = namespace(request)
    clock = ros_node.node.create_publisher(Clock, '/clock', 10)
    pub = ros_processes.start_console_script('profile_publisher', *ros_arguments(
        namespace=ns, params={'profile': 'ramp', 'omega_target': 1.0, 'ramp_time': 1.0,
                              'rate': 20.0, 'use_sim_time': True}))
    got = ros_node.subscribe(f'{ns}/cmd/omega', Float64, qos=1000)
    sim = 1.0
    steps = None
    start = time.monotonic()
    while steps is None or steps > 0:
        sim += 0.0025                          # simulated time at a quarter of wall time
        clock.publish(Clock(clock=Time(sec=int(sim), nanosec=int(sim % 1 * 1e9))))
        ros_node.spin_for(0.01)
        if steps is None and got:              # the stream has started (process is up):
            steps = 200                        # 0.5 s of simulated time more, then stop
        elif steps is not None:
            steps -= 1
        assert time.monotonic() < start + 30, 'no sample within 30 s'
    # 0.5 s of simulated time since the first sample came: samples 0..10 at least (once
    # they are in), a few more for the time that one took to come in; not all 21
    ros_node.spin_until(lambda: len(got) >= 11, 10, '11 samples')
    ros_node.spin_for(0.3)                     # the clock stands still: no more
    assert len(got) <= 15, len(got)
    assert pub.running
    deadline = time.monotonic()
    while pub.poll() is None and time.monotonic() < deadline + 30:
        sim += 0.01
        clock.publish(Clock(clock=Time(sec=int(sim), nanosec=int(sim % 1 * 1e9))))
        ros_node.spin_for(0.01)
    assert pub.returncode == 0
    ros_node.spin_until(lambda: len(got) >= 21, 10, 'the 21 samples')   # all in, not 0.3 s
    ros_node.spin_for(0.1)
    assert [m.data for m in got] == pytest.approx([k / 20 for k in range(21)], abs=1e-12)


def test_profile_publisher_holds_or_loops_when_asked(ros_processes, ros_node, request):
    ns = namespace(request)
    hold = ros_processes.start_console_script('profile_publisher', *ros_arguments(
        namespace=ns + '_hold', params={'profile': 'constant', 'omega_target': 0.7,
                                        'rate': 50.0, 'hold': True}))
    loop = ros_processes.start_console_script('profile_publisher', *ros_arguments(
        namespace=ns + '_loop', params={'profile': 'ramp', 'omega_target': 1.0,
                                        'ramp_time': 0.2, 'rate': 50.0, 'loop': True}))
    held = ros_node.subscribe(f'{ns}_hold/cmd/omega', Float64, qos=1000)
    looped = ros_node.subscribe(f'{ns}_loop/cmd/omega', Float64, qos=1000)
    ros_node.spin_until(lambda: len(held) > 50 and len(looped) > 50, 20, 'streams')
    assert hold.running and loop.running
    assert {m.data for m in held} == {0.7}
    v = [m.data for m in looped]
    assert v.count(0.0) >= 3 and v.count(1.0) >= 3      # the ramp starts over


@pytest.mark.parametrize('params, reason', [
    ({'profile': 'spiral'}, 'profile must be one of'),
    ({'profile': 'table'}, 'table_file'),
    ({'profile': 'eq26', 'period': -1.0}, 'period'),
    ({'rate': 0.0}, 'rate must be > 0'),
    ({'realtime_priority': 100}, 'realtime_priority'),
    ({'realtime_priority': 5.0}, 'realtime_priority'),
])
def test_profile_publisher_refuses_bad_parameters(ros_processes, params, reason):
    proc = ros_processes.start_console_script('profile_publisher', *ros_arguments(
        params=params))
    assert proc.wait(timeout=30) == 2
    assert 'invalid configuration' in proc.output and reason in proc.output
