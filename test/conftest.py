"""Pytest configuration for rotrod: the ROS 2 test harness (see ``ros_harness.py``).

Importing the hooks and fixtures below registers them for every test under ``test/``:

* ``pytest_configure``: per-run ROS environment (LOCALHOST discovery, unique ROS_DOMAIN_ID,
  rmw_fastrtps_cpp, ROS_LOG_DIR in a temporary directory), inherited by child processes;
* ``pytest_report_header``: the isolation in force (private netns or LOCALHOST only);
* ``pytest_runtest_makereport``: stops a failing test's processes and adds their output to
  the failure report;
* fixtures ``ros_processes`` (start/stop node processes) and ``ros_node`` (an rclpy node in
  the test process).
"""

from ros_harness import (  # noqa: F401 (registered by pytest through this module)
    pytest_configure,
    pytest_report_header,
    pytest_runtest_makereport,
    pytest_unconfigure,
    ros_node,
    ros_processes,
)
