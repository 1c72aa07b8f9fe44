"""What one sample publication costs the publishing thread: a message object, or its bytes.

    .venv/bin/python bench/publish_cost.py [--rods 100] [--rounds 300]

In a private network namespace through test/isolate.py: ``--rods`` publishers of
tip/deflection (the simulator's type, QoS and frames: rod0/rotor ...), one subscriber
process taking all of them (serialized, as bench_fleet's observer). Every 10 ms, one
publication on each, as a world's physics thread makes them, for ``--rounds`` rounds in
each of three ways:

- ``object``: a geometry_msgs/Vector3Stamped written anew and passed to rclpy (rclpy
  converts it to a C message and serialises it);
- ``bytes``: the same message serialised by :class:`rotrod_ros.messages.SampleMessages`
  (:mod:`rotrod_ros.cdr`: one ``struct``), passed to rclpy as bytes, what the
  simulator does;
- ``bytes made once``: the same bytes every time (rclpy and DDS alone).

Prints the publishing thread's CPU per publication (us, time.thread_time over the
rounds, the sleeps' own system calls included: the same in each way), twice in
alternation (docs/realtime.md#serialised-samples).
"""

import argparse
import os
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / 'test')]

if not os.environ.get('ROTROD_ISOLATION') and __name__ == '__main__':
    os.execv(sys.executable, [sys.executable, str(ROOT / 'test' / 'isolate.py'),
                              sys.executable, *sys.argv])

SUBSCRIBER = """
import signal, sys, time, rclpy
from geometry_msgs.msg import Vector3Stamped
from rclpy.signals import SignalHandlerOptions
rods, seconds = int(sys.argv[1]), float(sys.argv[2])
stop = []
signal.signal(signal.SIGTERM, lambda *_: stop.append(1))
rclpy.init(signal_handler_options=SignalHandlerOptions.NO)
node = rclpy.create_node('publish_cost_subscriber')
for k in range(rods):
    node.create_subscription(Vector3Stamped, f'/rod{k}/tip/deflection', lambda raw: None,
                             1000, raw=True)
end = time.monotonic() + seconds
while time.monotonic() < end and not stop:
    rclpy.spin_once(node, timeout_sec=0.1)
"""


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split('\n')[0])
    ap.add_argument('--rods', type=int, default=100)
    ap.add_argument('--rounds', type=int, default=300)
    args = ap.parse_args()
    import rclpy

    from rotrod_core.model.interface import ROTOR_FRAME, WORLD_FRAME, stamp_parts
    from rotrod_ros import messages
    from rotrod_ros.rod_io import INTERFACES

    qos = next(i for i in INTERFACES if i.name == 'tip/deflection')
    seconds = 6 * args.rounds * 0.011 + 60
    sub = subprocess.Popen([sys.executable, '-c', SUBSCRIBER, str(args.rods), str(seconds)])
    rclpy.init()
    try:
        node = rclpy.create_node('publish_cost')
        import dataclasses

        from rotrod_ros import interfaces
        made = interfaces.create(node, [dataclasses.replace(qos, name=f'/rod{k}/tip/deflection')
                                        for k in range(args.rods)])
        pubs = [made[f'/rod{k}/tip/deflection'] for k in range(args.rods)]
        deadline = time.monotonic() + 60
        while any(p.get_subscription_count() == 0 for p in pubs):
            if time.monotonic() > deadline:
                raise RuntimeError('the subscriber did not match within 60 s')
            time.sleep(0.1)
        time.sleep(1.0)
        objects = [messages.deflection(messages.stamp(0.0), 0.0, 0.0, f'rod{k}/{ROTOR_FRAME}')
                   for k in range(args.rods)]
        samples = [messages.SampleMessages(f'rod{k}/{ROTOR_FRAME}', WORLD_FRAME)
                   for k in range(args.rods)]
        fixed = [s.deflection(1, 2, 1e-3, 2e-4) for s in samples]

        def as_object(k, t, u):
            msg = objects[k]
            messages.set_deflection(msg, messages.stamp(t), u, 2e-4)
            pubs[k].publish(msg)

        def as_bytes(k, t, u):
            sec, nanosec = stamp_parts(t)
            pubs[k].publish(samples[k].deflection(sec, nanosec, u, 2e-4))

        def bytes_made_once(k, t, u):
            pubs[k].publish(fixed[k])

        ways = {'object': as_object, 'bytes': as_bytes, 'bytes made once': bytes_made_once}
        print(f'{args.rods} publishers of tip/deflection, one subscriber process, '
              f'{args.rounds} rounds every 10 ms')
        print('| way | publishing thread CPU per publication [us] |')
        print('|---|---|')
        for _ in range(2):
            for name, publish in ways.items():
                t0 = time.thread_time()
                for r in range(args.rounds):
                    t = time.time()
                    for k in range(args.rods):
                        publish(k, t, 1e-3 + 1e-9 * r)
                    time.sleep(0.01)
                per = (time.thread_time() - t0) / (args.rounds * args.rods) * 1e6
                print(f'| {name} | {per:.1f} |', flush=True)
        node.destroy_node()
    finally:
        rclpy.try_shutdown()
        sub.terminate()
        sub.wait()
    return 0


if __name__ == '__main__':
    sys.exit(main())
