"""A fleet of rods from one command (python -m rotrod_ros.fleet), and its launch file.

Three rods, each streamed the paper's Eq. 26 by its own profile publisher: every rod
publishes in its own namespace and frames at the full rate, and its tip follows the
quasi-static closed form of its own speed.
"""

import ast
import math
import os
import re
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from geometry_msgs.msg import Vector3Stamped
from node_probes import stamp
from reference import R0, K, M
from ros_harness import console_script
from sensor_msgs.msg import JointState

from rotrod_ros import fleet

ROOT = Path(__file__).resolve().parents[2]
RODS = 3
ZETA = 0.05


@pytest.mark.ros
def test_three_rods_from_one_command_each_on_its_own_stream(ros_processes, ros_node,
                                                            tmp_path):
    joint = {ns: ros_node.subscribe(f'{ns}/joint_states', JointState, qos=1000)
             for ns in fleet.namespaces(RODS)}
    # the user's one command: `rotrod fleet` (python -m rotrod_ros.fleet underneath)
    # a damped rod (as any real one): the whirl that the streams' start leaves dies out
    # (1 / (zeta w0) = 1.7 s) before w reaches the checked speeds; an undamped rod keeps
    # it (see docs/ros_integration.md#a-fleet-of-rods)
    damped = tmp_path / 'damped.yaml'
    damped.write_text(f'/**/rotrod_simulator:\n  ros__parameters:\n    damping_ratio: {ZETA}\n')
    proc = ros_processes.start([*console_script('rotrod'), 'fleet', '--rods', str(RODS),
                                '--profile', '--duration', '120', '--log-dir', str(tmp_path),
                                '--params-file', str(damped)], name='fleet')
    proc.wait_for_output(f'fleet: {RODS} rods running', timeout=60)
    ros_node.spin_until(lambda: all(j and j[-1].velocity[0] > 1.0 for j in joint.values()),
                        60, 'every rod spinning up')
    for ns in fleet.namespaces(RODS):                # each rod's sensor in its own frame
        sensed = ros_node.wait_for_messages(f'{ns}/tip/deflection', Vector3Stamped, 3)
        assert {m.header.frame_id for m in sensed} == {f'{ns[1:]}/rotor'}
    stop = time.time()              # the stamps are wall-clock times (real time, no /clock)
    os.kill(proc.pid, signal.SIGINT)            # Ctrl-C: the fleet stops every node
    assert proc.wait(timeout=30) == 0
    for ns in fleet.namespaces(RODS):
        # every rod published at the full rate: one sample per 10 ms of its simulated time
        # (as its log says on stopping), every publication (KEEP_LAST depth 100) on the
        # 10 ms grid; the observer of this test, an ordinary Python process sharing two
        # cores with six real-time ones, may miss some while it waits for a core
        log = (tmp_path / f'{ns[1:]}_simulator.log').read_text()
        assert 'ready' in log
        stopped = re.search(r'stopped at simulated time ([0-9.]+) s after (\d+) publications', log)
        assert stopped, log[-2000:]
        t_stop, published = float(stopped[1]), int(stopped[2])
        assert abs(published - (math.floor(t_stop * 100 + 1e-6) + 1)) <= 1, (t_stop, published)
        # the true state (u in the tip joint 'tip_radial'), by stamp
        rows = np.array(sorted((stamp(j), j.velocity[0], j.position[1]) for j in joint[ns]))
        t, w, u = rows.T
        steps = np.diff(t) / 0.01
        assert np.max(np.abs(steps - np.round(steps))) < 1e-3 and np.min(steps) > 0.5
        # while streamed: on Ctrl-C the profile publishers may stop before the
        # simulators, and then w leaves Eq. 26 (the shaper's end of a stream)
        moving = (w > 0.3) & (t < stop)
        assert moving.sum() > 100
        # Eq. 26 is slow against w0: the tip sits at u_s = m w^2 r0 / (k - m w^2)
        # (rotating damping leaves the static deflection as it is)
        u_s = M * w[moving] ** 2 * R0 / (K - M * w[moving] ** 2)
        assert np.max(np.abs(u[moving] - u_s)) < 0.01 * np.max(u_s) + 2e-6


def test_bad_fleet_sizes_are_refused_with_the_reason():
    for rods in (0, -1, fleet.MAX_RODS + 1, 2.5, True):
        with pytest.raises(ValueError, match='rods must be an integer'):
            fleet.namespaces(rods)
    with pytest.raises(SystemExit) as exc:
        fleet.main(['--rods', '0'])
    assert exc.value.code == 2
    out = subprocess.run([*console_script('rotrod'), 'fleet', '--rods', '0'],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 2 and 'rods must be an integer 1..100, got 0' in out.stderr
    out = subprocess.run([*console_script('rotrod'), 'fleet', '--help'],
                         capture_output=True, text=True, timeout=60)
    assert out.returncode == 0 and '--rods' in out.stdout and '--profile' in out.stdout


def test_fleet_commands_name_every_rod_its_namespace_files_and_frames():
    cmds = fleet.fleet_commands(2, profile=True)
    assert sorted(cmds) == ['rod0_profile_publisher', 'rod0_simulator',
                            'rod1_profile_publisher', 'rod1_simulator']
    sim = cmds['rod1_simulator']
    assert '__ns:=/rod1' in sim and 'frame_prefix:=rod1/' in sim
    files = [sim[i + 1] for i, a in enumerate(sim) if a == '--params-file']
    assert [Path(f).name for f in files] == ['table1.yaml', 'fleet.yaml']


def test_fleet_launch_file_starts_the_same_nodes_with_the_same_files():
    launch = ROOT / 'launch' / 'fleet.launch.py'
    tree = ast.parse(launch.read_text())
    executables = {ast.literal_eval(kw.value) for node in ast.walk(tree)
                   if isinstance(node, ast.Call) and getattr(node.func, 'id', '') == 'Node'
                   for kw in node.keywords if kw.arg == 'executable'}
    assert executables == {'simulator', 'profile_publisher'}
    files = [c for c in ast.walk(tree) if isinstance(c, ast.Tuple)
             and all(isinstance(e, ast.Constant) and str(e.value).endswith('.yaml')
                     for e in c.elts)]
    assert [f'config/{e.value}' for e in files[0].elts] == list(fleet.PARAM_FILES)
    compile(launch.read_text(), str(launch), 'exec')
