"""Test node: publish ``std_msgs/msg/String`` messages ``'<prefix> <n>'`` with a counter.

Usage: ``python talker.py [--topic T] [--rate HZ] [--prefix P] [--count N] [--ros-args ...]``.
Prints ``published: <data>`` for each message; exits 0 after ``--count`` messages (0 means
run until SIGINT/SIGTERM, which also exits 0). Service ``~/reset`` (std_srvs/srv/Trigger)
sets the counter back to 0.
"""

import argparse
import os
import sys

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.utilities import remove_ros_args
from std_msgs.msg import String
from std_srvs.srv import Trigger


def main(argv=None):
    argv = sys.argv if argv is None else argv
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--topic', default='chatter')
    parser.add_argument('--rate', type=float, default=20.0, help='messages per second')
    parser.add_argument('--prefix', default='hello')
    parser.add_argument('--count', type=int, default=0, help='stop after N messages (0: never)')
    args = parser.parse_args(remove_ros_args(argv)[1:])

    rclpy.init(args=argv)
    node = Node('talker')
    pub = node.create_publisher(String, args.topic, 10)
    counter = 0

    def tick():
        nonlocal counter
        msg = String(data=f'{args.prefix} {counter}')
        pub.publish(msg)
        print(f'published: {msg.data}', flush=True)
        counter += 1

    def reset(request, response):
        nonlocal counter
        counter = 0
        response.success = True
        response.message = 'counter reset'
        print('reset', flush=True)
        return response

    node.create_timer(1.0 / args.rate, tick)
    node.create_service(Trigger, '~/reset', reset)
    print(f'env: ROS_DOMAIN_ID={os.environ.get("ROS_DOMAIN_ID")} '
          f'ROS_AUTOMATIC_DISCOVERY_RANGE={os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE")}',
          flush=True)
    print(f'talker ready on {node.resolve_topic_name(args.topic)}', flush=True)
    try:
        while rclpy.ok() and not (args.count and counter >= args.count):
            rclpy.spin_once(node, timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        print('talker: shutting down on signal', flush=True)
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == '__main__':
    sys.exit(main())
