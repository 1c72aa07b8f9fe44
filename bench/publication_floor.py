"""The floor under the simulator's CPU: its four per-sample publications, nothing else.

    python bench/publication_floor.py [--ns NAMESPACE] [--rate HZ]   # until SIGINT

A bare rclpy process with the simulator's publishers of the sample topics that go out
with every sample (:data:`PER_SAMPLE`: the types and QoS of
``rotrod_ros.simulator.INTERFACES`` at the defaults), their messages made once by
``rotrod_ros.messages`` as the simulator makes them. One thread, at the physics
thread's default SCHED_FIFO priority where permitted, publishes all four every
1/rate s (default: the simulator's ``publish_rate``) on an absolute deadline,
sleeping in between as the simulator does at its defaults, and changes only the
stamps. No physics, no estimate, no markers, no status, no executor.

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


def publishers(node) -> list:
    """The simulator's publishers of PER_SAMPLE on ``node``, as the simulator makes them."""
    from rotrod_ros import interfaces
    from rotrod_ros.simulator import INTERFACES
    wanted = [i for i in INTERFACES if i.name in PER_SAMPLE]
    made = interfaces.create(node, wanted)
    return [made[name] for name in PER_SAMPLE]


def messages() -> list:
    """One message per PER_SAMPLE topic, as the simulator fills them.

    The same joints and frames (so the same sizes); the values, a rod at w = 2 rad/s
    deflected by (1, 0.1) mm, are only placeholders: the cost does not depend on them.
    """
    from rotrod_core.model.equations import State
    from rotrod_core.model.interface import ROTOR_FRAME, WORLD_FRAME
    from rotrod_ros import messages as m
    sample = m.SampleMessages(ROTOR_FRAME, WORLD_FRAME)
    t = m.stamp(0.0)
    state = State(theta=0.1, omega=2.0, u=1e-3, v=1e-4, du=0.0, dv=0.0)
    return [m.set_joint_state(sample.joint_state, t, state, 0.0),
            m.set_deflection(sample.deflection, t, 1e-3, 1e-4),
            m.set_position(sample.position, t, (0.1, 0.0, 0.5)),
            m.set_frequencies(sample.frequencies, t, 2.0, 1.9, 2.1)]


def publish_every(period: float, pubs: list, msgs: list, stop: threading.Event,
                  logger) -> None:
    """Publish ``msgs`` on ``pubs`` every ``period`` s on an absolute deadline.

    At the physics thread's default SCHED_FIFO priority where permitted (else ordinary
    scheduling, with a warning on ``logger``), as the simulator's thread runs.
    """
    from rotrod_core.live.scheduling import run_current_thread_at
    from rotrod_ros.messages import stamp
    run_current_thread_at(LoopSettings().realtime_priority, logger, 'publishing thread')
    due = time.monotonic()
    while True:
        due += period
        if stop.wait(max(0.0, due - time.monotonic())):
            return
        t = stamp(time.time())
        for pub, msg in zip(pubs, msgs):
            msg.header.stamp = t
            pub.publish(msg)


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--ns', default='/', help='the namespace, as a simulator in it')
    ap.add_argument('--rate', type=float, default=LoopSettings().publish_rate,
                    help="samples per second, Hz (default: the simulator's publish_rate)")
    args = ap.parse_args(argv)
    if not (math.isfinite(args.rate) and args.rate > 0):
        ap.error(f'--rate must be a positive number, got {args.rate!r}')
    import rclpy
    from rclpy.node import Node
    rclpy.init(args=[])
    stop = threading.Event()
    signal.signal(signal.SIGINT, lambda *_: stop.set())
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    node = Node('publication_floor', namespace=args.ns)
    try:
        thread = threading.Thread(target=publish_every, daemon=True,
                                  args=(1.0 / args.rate, publishers(node), messages(), stop,
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
