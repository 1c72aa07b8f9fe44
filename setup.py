"""Build script for the ``rotrod`` ROS 2 (ament_python) package.

The same file serves a colcon build (executables into ``lib/rotrod``, data into
``share/rotrod``) and a pip install into a virtual environment (executables on PATH).
"""

from glob import glob

from setuptools import find_packages, setup

PACKAGE = 'rotrod'

# Executables: `ros2 run rotrod <name>` in a ROS install, `<name>` on PATH in a venv.
CONSOLE_SCRIPTS = [
    'rotrod = rotrod_core.cli:main',
    'simulator = rotrod_ros.simulator:main',
    'profile_publisher = rotrod_ros.profile_publisher:main',
    'rerun_logger = rotrod_ros.rerun_logger:main',
    'rig_monitor = rotrod_ros.rig_monitor:main',
    'lockstep_controller = rotrod_ros.lockstep_controller:main',
]

setup(
    name=PACKAGE,
    version='0.1.0',
    description='Rigid-flexible coupled rotating rod with a tip mass: real-time ROS 2 '
                'simulation and analysis (Liu et al. 2014, done exactly).',
    license='Apache-2.0',
    python_requires='>=3.10',
    packages=find_packages(include=['rotrod_core', 'rotrod_core.*',
                                    'rotrod_ros', 'rotrod_ros.*']),
    data_files=[
        ('share/ament_index/resource_index/packages', ['resource/' + PACKAGE]),
        ('share/' + PACKAGE, ['package.xml']),
        ('share/' + PACKAGE + '/config', glob('config/*.yaml')),
        ('share/' + PACKAGE + '/launch', glob('launch/*.launch.py')),
        ('share/' + PACKAGE + '/urdf', glob('urdf/*.urdf')),
    ],
    install_requires=['numpy', 'scipy', 'PyYAML', 'threadpoolctl'],
    extras_require={
        # rclpy and the standard messages from PyPI wheels (a ROS install provides them).
        'ros': ['ros-jazzy-rclpy[fastrtps]', 'ros-jazzy-common-interfaces'],
        'viz': ['rerun-sdk', 'matplotlib'],
        # parameter sweeps on a Dask cluster and their Parquet files (docs/sweeps.md)
        'sweep': ['dask[distributed]', 'pyarrow'],
        # rosbag2 (MCAP) files of offline runs: rotrod simulate --bag (no rclpy needed)
        'bag': ['rosbags'],
        # pytransform3d: the URDF's forward kinematics; mcap, mcap-ros2-support: an
        # independent reader of the bags (test/core/model/test_urdf.py,
        # test/core/reporting/test_bag.py)
        'dev': ['pytest', 'pytest-timeout', 'hypothesis', 'ruff', 'mypy',
                'catkin-pkg', 'colcon-core', 'colcon-ros', 'colcon-python-setup-py',
                'pytransform3d', 'mcap', 'mcap-ros2-support'],
    },
    zip_safe=True,
    maintainer='rotrod developers',
    maintainer_email='dev@rotrod.invalid',
    entry_points={'console_scripts': CONSOLE_SCRIPTS},
)
