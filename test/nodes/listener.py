"""Test node: subscribe to ``std_msgs/msg/String`` and exit 0 after receiving N messages.

Usage: ``python listener.py --count N [--topic T] [--ros-args ...]``. Prints an ``env:`` line
with the ROS settings it sees, ``listener ready``, then ``heard: <data>`` per message.
"""

import argparse
import os
import sys

import rclpy
from rclpy.executors import ExternalShutdownException
from rclpy.node import Node
from rclpy.utilities import remove_ros_args
from std_msgs.msg import String


def main(argv=None):
    argv = sys.argv if argv is None else argv
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument('--topic', default='chatter')
    parser.add_argument('--count', type=int, required=True)
    args = parser.parse_args(remove_ros_args(argv)[1:])

    rclpy.init(args=argv)
    node = Node('listener')
    heard = []

    def on_msg(msg):
        heard.append(msg.data)
        print(f'heard: {msg.data}', flush=True)

    node.create_subscription(String, args.topic, on_msg, 10)
    print(f'env: ROS_DOMAIN_ID={os.environ.get("ROS_DOMAIN_ID")} '
          f'ROS_AUTOMATIC_DISCOVERY_RANGE={os.environ.get("ROS_AUTOMATIC_DISCOVERY_RANGE")} '
          f'RMW_IMPLEMENTATION={os.environ.get("RMW_IMPLEMENTATION")}', flush=True)
    print(f'listener ready on {node.resolve_topic_name(args.topic)}', flush=True)
    try:
        while rclpy.ok() and len(heard) < args.count:
            rclpy.spin_once(node, timeout_sec=0.1)
    except (KeyboardInterrupt, ExternalShutdownException):
        print(f'listener: interrupted after {len(heard)} messages', flush=True)
        return 1
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    print(f'listener: done after {len(heard)} messages', flush=True)
    return 0


if __name__ == '__main__':
    sys.exit(main())
