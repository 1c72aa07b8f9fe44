"""The floor under the simulator's CPU: its four per-sample publications, nothing else.

    python bench/publication_floor.py [--ns NAMESPACE] [--rate HZ]
        [--rods N] [--topics joint_states,tip/deflection,...]       # until SIGINT

A bare rclpy process with the simulator's publishers of the sample topics that go out
with every sample (:data:`PER_SAMPLE`: the types and QoS of
``rotrod_ros.simulator.INTERFACES`` at the defaults), their messages serialised by
``rotrod_ros.messages.SampleMessages`` as the simulator's. One thread, at the physics
thread's default SCHED_FIFO priority where permitted, publishes all four every
1/rate s (default: the simulator's ``publish_rate``) on an absolute deadline,
sleeping in between as the simulator does at its defaults, and changes only the
stamps. No physics, no estimate, no markers, no status, no executor.

With ``--rods N``, the publications of a world of N rods (``rods:=N``): rod0 ..
rod{N-1}'s, their topics and frames under ``rod{k}/``, all from the one thread in one
wake-up; ``--topics`` publishes only those (a world publishes only the sample topics
someone subscribes to).

What the simulator cannot cost less than at its defaults, in this language and
middleware, on this machine: ``bench_realtime.py`` and ``bench_fleet.py`` run it as
they run the simulator, with the same subscribers, and report its CPU beside the
simulator's (docs/realtime.md#floor).
"""

from __future__ import annotations

import argparse
import math
import signal
import sys
import threading
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from rotrod_core.live.loop import LoopSettings  # noqa: E402
from rotrod_core.live.publication import SAMPLE_TOPICS  # noqa: E402

SCRIPT = Path(__file__).resolve()
"""This script, as the benches and its test start it."""
PER_SAMPLE = tuple(t for t in SAMPLE_TOPICS if t != 'frequencies/estimate')
"""The sample topics published with every sample (the estimate goes out every
1/estimate_rate s, not with every sample)."""


def publishers(node, prefix: str = '', topics=PER_SAMPLE) -> list:
    """The simulator's publishers of ``topics`` on ``node``, as the simulator makes them,
    named under ``prefix`` ('' or 'rod3/')."""
    import dataclasses

    from rotrod_ros import interfaces
    from rotrod_ros.simulator import INTERFACES
    wanted = [dataclasses.replace(i, name=prefix + i.name) for i in INTERFACES
              if i.name in topics]
    made = interfaces.create(node, wanted)
    return [made[prefix + name] for name in topics]


def messages(prefix: str = '', topics=PER_SAMPLE) -> list:
    """One writer per topic of ``topics``, as the simulator writes them for the rod of
    ``prefix``: (sec, nanosec) -> bytes.

    The same joints and frames (so the same sizes), serialised as the simulator does
    (:class:`rotrod_ros.messages.SampleMessages`); the values, a rod at w = 2 rad/s
    deflected by (1, 0.1) mm, are only placeholders: the cost does not depend on them.
    """
    from rotrod_core.model.equations import State
    from rotrod_core.model.interface import ROTOR_FRAME, WORLD_FRAME
    from rotrod_ros import messages as m
    sample = m.SampleMessages(prefix + ROTOR_FRAME, WORLD_FRAME)
    state = State(theta=0.1, omega=2.0, u=1e-3, v=1e-4, du=0.0, dv=0.0)
    writers = {'joint_states': lambda s, ns: sample.joint_state(s, ns, state, 0.0, 0.3),
               'tip/deflection': lambda s, ns: sample.deflection(s, ns, 1e-3, 1e-4),
               'tip/position': lambda s, ns: sample.position(s, ns, (0.1, 0.0, 0.5)),
               'frequencies': lambda s, ns: sample.frequencies(s, ns, 2.0, 1.9, 2.1)}
    return [writers[t] for t in topics]


def publish_every(period: float, pubs: list, writers: list, stop: threading.Event,
                  logger) -> None:
    """Publish the ``writers``' messages on ``pubs`` every ``period`` s on an absolute
    deadline, stamped with the wall time.

    At the physics thread's default SCHED_FIFO priority where permitted (else ordinary
    scheduling, with a warning on ``logger``), as the simulator's thread runs.
    """
    from rotrod_core.live.scheduling import run_current_thread_at
    from rotrod_core.model.interface import stamp_parts
    run_current_thread_at(LoopSettings().realtime_priority, logger, 'publishing thread')
    due = time.monotonic()
    while True:
        due += period
        if stop.wait(max(0.0, due - time.monotonic())):
            return
        sec, nanosec = stamp_parts(time.time())
        for pub, write in zip(pubs, writers):
            pub.publish(write(sec, nanosec))


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--ns', default='/', help='the namespace, as a simulator in it')
    ap.add_argument('--rate', type=float, default=LoopSettings().publish_rate,
                    help="samples per second, Hz (default: the simulator's publish_rate)")
    ap.add_argument('--rods', type=int, default=1,
                    help="a world's rods: rod0 .. rod{N-1} (default 1: the rod of a "
                         'simulator alone, no prefix)')
    ap.add_argument('--topics', default=','.join(PER_SAMPLE),
                    help=f"comma-separated, of {', '.join(PER_SAMPLE)} (default: all)")
    args = ap.parse_args(argv)
    if not (math.isfinite(args.rate) and args.rate > 0):
        ap.error(f'--rate must be a positive number, got {args.rate!r}')
    if args.rods < 1:
        ap.error(f'--rods must be at least 1, got {args.rods}')
    topics = tuple(args.topics.split(','))
    if not topics or any(t not in PER_SAMPLE for t in topics):
        ap.error(f'--topics must name some of {", ".join(PER_SAMPLE)}, got {args.topics!r}')
    from rotrod_ros.simulator import started_rods
    prefixes = [prefix for _, prefix in started_rods(args.rods)]
    import rclpy
    from rclpy.node import Node
    rclpy.init(args=[])
    stop = threading.Event()
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    node = Node('publication_floor', namespace=args.ns)
    try:
        pubs = [p for prefix in prefixes for p in publishers(node, prefix, topics)]
        writers = [w for prefix in prefixes for w in messages(prefix, topics)]
        thread = threading.Thread(target=publish_every, daemon=True,
                                  args=(1.0 / args.rate, pubs, writers, stop,
                                        node.get_logger()))
        thread.start()
        print('ready', flush=True)
        while not stop.wait(0.5):
            pass
        thread.join(timeout=2.0)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
