"""The main job on a full ROS 2 install: ``ros2 launch rotrod demo.launch.py``.

Starts the same three nodes with the same parameter files as ``rotrod demo``
(config/table1.yaml, then config/demo.yaml): the simulator faster than real time on
/clock, the Rerun logger, and the profile publisher streaming Eq. 26. The logger
writes rotrod.rrd in the working directory; stop with Ctrl-C after the publisher
has finished (it exits at the end of the profile).
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch_ros.actions import Node


def generate_launch_description():
    """Simulator, Rerun logger and profile publisher with the demo's parameter files."""
    share = get_package_share_directory('rotrod')
    params = [os.path.join(share, 'config', name) for name in ('table1.yaml', 'demo.yaml')]
    return LaunchDescription([
        Node(package='rotrod', executable='simulator', name='rotrod_simulator',
             parameters=params, output='screen'),
        Node(package='rotrod', executable='rerun_logger', name='rotrod_rerun_logger',
             parameters=params, output='screen'),
        Node(package='rotrod', executable='profile_publisher', name='rotrod_profile_publisher',
             parameters=params, output='screen'),
    ])
