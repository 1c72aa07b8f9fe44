"""Where the simulator node's physics thread spends its CPU time, part by part.

    python bench/node_cpu_parts.py DURATION [NAME:=VALUE ...]   # prints JSON

Runs ``rotrod_ros.simulator.SimulatorNode`` in this process (its defaults, the given
parameters over them), with a timer around each part of its
physics thread's work: the physics steps, each sample topic's message and publication,
the whirl estimate, the markers' shapes, message and publication, the status check,
the waits' own overhead. The timers read ``time.thread_time`` (CPU time of the
calling thread), so the parts add up to the thread's CPU time less what runs outside
them (the loop itself). Each timer costs about a microsecond per call, which the
thread's total includes.

With ``rods:=N`` the timers are on every rod of the world. Timers that enclose parts
are reported apart, under "wholes": each rod's whole sample publication (its messages,
sends, looks and sensors), its rig sensors read and sent, and the pass of estimates and
markers after an instant's samples.

Run it where something subscribes to the node's topics (``bench_realtime.py`` does,
from another process): without a matched reader, DDS does less per publication.
Prints {"thread_percent": ..., "parts": {name: {"percent": ..., "calls": ...,
"us_per_call": ...}}, "wholes": {...}, "duration_s": ...} on stdout. What the parts
showed, and what was
made cheaper: docs/realtime.md#node-cpu.
"""

from __future__ import annotations

import json
import os
import sys
import time
from collections import Counter
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]


def _timed(owner, attr: str, label: str, spent: Counter, calls: Counter) -> None:
    """Replace ``owner.attr`` by the same callable that adds its thread CPU time."""
    inner = getattr(owner, attr)

    def timed(*args, **kwargs):
        t0 = time.thread_time()
        try:
            return inner(*args, **kwargs)
        finally:
            spent[label] += time.thread_time() - t0
            calls[label] += 1
    setattr(owner, attr, timed)


def _thread_cpu(tid: int) -> float:
    fields = Path(f'/proc/self/task/{tid}/stat').read_text().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')


def measure(duration: float, params: dict) -> dict:
    """Run the node for ``duration`` s after a 3 s start; the thread's CPU by part."""
    import rclpy
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.parameter import Parameter

    import rotrod_ros.messages as messages
    import rotrod_ros.rod_io as rod_io
    import rotrod_ros.simulator as simulator

    values = dict(params)
    spent: Counter = Counter()
    calls: Counter = Counter()
    for fn, label in (('joint_state', 'joint_states message'),
                      ('deflection', 'tip/deflection message'),
                      ('position', 'tip/position message'),
                      ('frequencies', 'frequencies messages')):
        _timed(messages.SampleMessages, fn, label, spent, calls)
    for fn, label in (('set_whirl_estimate', 'frequencies messages'), ('stamp', 'stamps')):
        _timed(messages, fn, label, spent, calls)
    for fn, label in (('rod_centerline', 'markers: rod shape'),
                      ('scene', 'markers: scene shapes')):
        _timed(rod_io, fn, label, spent, calls)
    rclpy.init(args=[])
    try:
        node = simulator.SimulatorNode(parameter_overrides=[
            Parameter(k, value=v) for k, v in values.items()])
        loop = node.loop
        rods = list(node.rods.values())         # the simulator's rods, as started
        rod = rods[0]
        _timed(node.world, 'advance', 'physics steps', spent, calls)
        # enclosing timers (their parts are timed inside them too): apart
        whole: Counter = Counter()
        whole_calls: Counter = Counter()
        _timed(loop, '_publish', "a rod's sample publication, all of it", whole, whole_calls)
        _timed(loop, '_published_hook', 'the estimates and markers pass', whole, whole_calls)
        _timed(loop, 'report', 'status check and /diagnostics', spent, calls)
        _timed(loop, '_samples', "the instant's samples (state, torque, tracking)", spent, calls)
        _timed(loop, '_apply_commands', 'commands', spent, calls)
        _timed(loop.clock, 'sleep_until', 'waits to each due time', spent, calls)
        for rod in rods:
            _timed(rod.keep_all, 'send', 'publish: sample topics', spent, calls)
            _timed(rod.keep_all, 'look', 'publish: looks for subscribers', spent, calls)
            _timed(rod, '_publish_sensors', 'the rig sensors, read and sent', whole,
                   whole_calls)
            _timed(rod.marker_frames, 'frame', 'markers: message', spent, calls)
            _timed(rod.io['markers'], 'publish', 'markers: publish', spent, calls)
            estimator = rod.observation.estimator
            if estimator is not None:
                _timed(estimator, 'push', 'whirl estimate', spent, calls)
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        node.start()
        started = time.monotonic()
        while time.monotonic() < started + 3.0:
            executor.spin_once(timeout_sec=0.1)
        for counter in (spent, calls, whole, whole_calls):
            counter.clear()
        tid = loop._thread.native_id
        c0, t0 = _thread_cpu(tid), time.monotonic()
        while time.monotonic() < t0 + duration:
            executor.spin_once(timeout_sec=0.1)
        c1, wall = _thread_cpu(tid), time.monotonic() - t0
        node.stop()
        node.destroy_node()
    finally:
        rclpy.try_shutdown()
    def table(spent, calls):
        return {k: {'percent': 100 * v / wall, 'calls': calls[k],
                    'us_per_call': 1e6 * v / max(calls[k], 1)}
                for k, v in sorted(spent.items(), key=lambda kv: -kv[1])}
    return {'duration_s': wall, 'thread_percent': 100 * (c1 - c0) / wall,
            'parts': table(spent, calls), 'wholes': table(whole, whole_calls)}


def main(argv: list[str]) -> int:
    duration = float(argv[0])
    params = {}
    for arg in argv[1:]:
        name, _, text = arg.partition(':=')
        params[name] = yaml.safe_load(text)     # as a params file would read it
    print(json.dumps(measure(duration, params)))
    return 0


if __name__ == '__main__':
    sys.exit(main(sys.argv[1:]))
