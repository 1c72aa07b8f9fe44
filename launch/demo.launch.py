"""The main job on a full ROS 2 install: ``ros2 launch rotrod demo.launch.py``.

Starts the same three nodes with the same parameter files as ``rotrod demo``
(config/table1.yaml, then config/demo.yaml): the simulator faster than real time on
/clock, the Rerun logger, and the profile publisher sending Eq. 26 as one trajectory. The logger
writes rotrod.rrd in the working directory; stop with Ctrl-C after the publisher
has finished (it exits at the end of the profile).

Beside them, ``robot_state_publisher`` turns the simulator's ``joint_states`` into
``/tf``, with the URDF generated from the same parameter files (so r0 and the rod's
length are the simulator's; ``rotrod urdf`` prints it). ``use_sim_time:=false`` for a
simulator run at real time (real_time_factor 1, no /clock).
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

from rotrod_core.model.urdf import urdf_for_parameter_files


def generate_launch_description():
    """Simulator, Rerun logger, profile publisher and robot_state_publisher."""
    share = get_package_share_directory('rotrod')
    params = [os.path.join(share, 'config', name) for name in ('table1.yaml', 'demo.yaml')]
    robot_description = urdf_for_parameter_files(params)
    return LaunchDescription([
        DeclareLaunchArgument('use_sim_time', default_value='true',
                              description='robot_state_publisher follows /clock (the '
                                          "demo's simulator runs at 2x and publishes it)"),
        Node(package='rotrod', executable='simulator', name='rotrod_simulator',
             parameters=params, output='screen'),
        Node(package='rotrod', executable='rerun_logger', name='rotrod_rerun_logger',
             parameters=params, output='screen'),
        Node(package='rotrod', executable='profile_publisher', name='rotrod_profile_publisher',
             parameters=params, output='screen'),
        # the simulator publishes robot_description itself (the rod the other nodes read);
        # robot_state_publisher's own publication of it is moved out of its way
        Node(package='robot_state_publisher', executable='robot_state_publisher',
             name='robot_state_publisher', output='screen',
             parameters=[{'robot_description': robot_description,
                          'use_sim_time': LaunchConfiguration('use_sim_time')}],
             remappings=[('robot_description', 'robot_state_publisher/robot_description')]),
    ])
