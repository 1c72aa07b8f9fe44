"""A fleet of rods on a full ROS 2 install: ``ros2 launch rotrod fleet.launch.py rods:=10``.

One simulator holds ``rods`` rods (default 10) as one world, their interfaces in the
namespaces rod0 .. rod{rods-1}, with config/table1.yaml and config/fleet.yaml (real
time, markers off); ``processes:=true`` starts a simulator process per rod instead (the
layout before worlds); with ``profiles:=true`` a profile publisher per rod streams Eq. 26
in a loop; with ``record:=true`` a rerun logger per rod writes ``rodK.rrd`` in the
working directory. The same fleet without ``launch``: ``python -m rotrod_ros.fleet
--rods 10 [--processes] [--profile] [--record]``.
"""

import os

from ament_index_python.packages import get_package_share_directory
from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument, OpaqueFunction
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node


def rods(context):
    """The world's simulator (or one per rod), and a profile publisher per rod if asked."""
    share = get_package_share_directory('rotrod')
    params = [os.path.join(share, 'config', name) for name in ('table1.yaml', 'fleet.yaml')]
    count = int(LaunchConfiguration('rods').perform(context))
    profiles = LaunchConfiguration('profiles').perform(context).lower() == 'true'
    processes = LaunchConfiguration('processes').perform(context).lower() == 'true'
    record = LaunchConfiguration('record').perform(context).lower() == 'true'
    actions = []
    if not processes:
        actions.append(Node(package='rotrod', executable='simulator',
                            name='rotrod_simulator', output='screen',
                            parameters=[*params, {'rods': count,
                                                  'max_rods': max(count, 128)}]))
    for k in range(count):
        ns = f'rod{k}'
        if processes:
            actions.append(Node(package='rotrod', executable='simulator', namespace=ns,
                                name='rotrod_simulator', output='screen',
                                parameters=[*params, {'frame_prefix': f'{ns}/'}]))
        if profiles:
            actions.append(Node(package='rotrod', executable='profile_publisher',
                                namespace=ns, name='rotrod_profile_publisher',
                                parameters=params, output='screen'))
        if record:
            actions.append(Node(package='rotrod', executable='rerun_logger', namespace=ns,
                                name='rotrod_rerun_logger', output='screen',
                                parameters=[{'output': f'{ns}.rrd'}]))
    return actions


def generate_launch_description():
    """The fleet: launch arguments rods (10), processes, profiles and record (false)."""
    return LaunchDescription([
        DeclareLaunchArgument('rods', default_value='10', description='number of rods'),
        DeclareLaunchArgument('processes', default_value='false',
                              description='a simulator process per rod instead of one world'),
        DeclareLaunchArgument('profiles', default_value='false',
                              description='a profile publisher per rod'),
        DeclareLaunchArgument('record', default_value='false',
                              description='a rerun logger per rod (rodK.rrd)'),
        OpaqueFunction(function=rods),
    ])
