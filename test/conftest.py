"""Pytest configuration for rotrod: the ROS 2 test harness (see ``ros_harness.py``).

Importing the hooks and fixtures below registers them for every test under ``test/``:

* ``pytest_configure``: per-run ROS environment (LOCALHOST discovery, unique ROS_DOMAIN_ID,
  rmw_fastrtps_cpp, ROS_LOG_DIR in a temporary directory), inherited by child processes;
* ``pytest_report_header``: the isolation in force (private netns or LOCALHOST only);
* ``pytest_runtest_makereport``: stops a failing test's processes and adds their output to
  the failure report;
* fixtures ``ros_processes`` (start/stop node processes) and ``ros_node`` (an rclpy node in
  the test process).

Tests marked ``long`` (minutes: the soak) are left out unless the ``-m`` expression names
the marker: ``./run.sh test`` runs the rest, ``./run.sh test -m long`` the long ones
(``.ci/run`` runs both). Unlike ``-m "not long"`` in addopts, this also keeps them out
of a run such as ``-m ros``.
"""

import re

from ros_harness import (  # noqa: F401 (registered by pytest through this module)
    pytest_configure,
    pytest_report_header,
    pytest_runtest_makereport,
    pytest_unconfigure,
    ros_node,
    ros_processes,
)


def pytest_collection_modifyitems(config, items):
    if re.search(r'\blong\b', config.getoption('markexpr') or ''):
        return
    long_tests = [item for item in items if item.get_closest_marker('long')]
    if long_tests:
        config.hook.pytest_deselected(items=long_tests)
        items[:] = [item for item in items if not item.get_closest_marker('long')]
