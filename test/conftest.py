"""Pytest configuration for rotrod: the ROS 2 test harness (see ``ros_harness.py``).

Importing the hooks and fixtures below registers them for every test under ``test/``:

* ``pytest_configure``: per-run ROS environment (LOCALHOST discovery, unique ROS_DOMAIN_ID,
  rmw_fastrtps_cpp, ROS_LOG_DIR in a temporary directory), inherited by child processes;
* ``pytest_report_header``: the isolation in force (private netns or LOCALHOST only);
* ``pytest_runtest_makereport``: stops a failing test's processes and adds their output to
  the failure report;
* fixtures ``ros_processes`` (start/stop node processes) and ``ros_node`` (an rclpy node in
  the test process);
* fixture ``colcon_interfaces``: the repository and its three message packages built by
  colcon once per session (test/colcon_workspace.py), for the tests that check that
  build and those that talk through it.

Plans (``rotrod_core.command.plan_cache``) are cached for the run in a temporary
directory of its own (``ROTROD_PLAN_CACHE``, inherited by child processes): each
request is planned once per run, never read from a user's cache or an earlier run.

Tests marked ``long`` (minutes: the soak) are left out unless the ``-m`` expression names
the marker: ``./run.sh test`` runs the rest, ``./run.sh test -m long`` the long ones
(``.ci/run`` runs both). Unlike ``-m "not long"`` in addopts, this also keeps them out
of a run such as ``-m ros``.
"""

import os
import re
import shutil
import tempfile

import colcon_workspace
import pytest
import ros_harness
from ros_harness import (  # noqa: F401 (registered by pytest through this module)
    pytest_report_header,
    pytest_runtest_makereport,
    ros_node,
    ros_processes,
)

from rotrod_core.command import plan_cache

_PLAN_CACHE = pytest.StashKey[str]()


def pytest_configure(config):
    ros_harness.pytest_configure(config)
    config.stash[_PLAN_CACHE] = os.environ[plan_cache.ENV] = tempfile.mkdtemp(
        prefix='rotrod-plans-')


def pytest_unconfigure(config):
    folder = config.stash.get(_PLAN_CACHE, None)
    if folder:
        shutil.rmtree(folder, ignore_errors=True)
    ros_harness.pytest_unconfigure(config)


@pytest.fixture(scope='session')
def colcon_interfaces(tmp_path_factory):
    """``colcon build`` of the sources and the message packages (a
    :class:`colcon_workspace.ColconBuild`; minutes: tests using it are ``long``)."""
    return colcon_workspace.build_with_interfaces(tmp_path_factory.mktemp('colcon') / 'ws')


def pytest_collection_modifyitems(config, items):
    if re.search(r'\blong\b', config.getoption('markexpr') or ''):
        return
    long_tests = [item for item in items if item.get_closest_marker('long')]
    if long_tests:
        config.hook.pytest_deselected(items=long_tests)
        items[:] = [item for item in items if not item.get_closest_marker('long')]
