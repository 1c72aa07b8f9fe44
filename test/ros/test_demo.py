"""rotrod_ros.demo's process handling: the nodes a demo or a fleet starts end with it."""

import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

ORCHESTRATOR = """
import os, sys, time
from pathlib import Path
from rotrod_ros.demo import Processes
procs = Processes(Path(sys.argv[1]), os.environ)
child = procs.start('node', [sys.executable, '-c', 'import time; time.sleep(120)'])
print(child.pid, flush=True)
time.sleep(120)
"""


def running(pid: int) -> bool:
    """Alive and not a zombie waiting to be reaped."""
    try:
        state = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()[0]
    except FileNotFoundError:
        return False
    return state != 'Z'


@pytest.mark.skipif(not sys.platform.startswith('linux'), reason='prctl is Linux only')
def test_a_killed_orchestrator_leaves_no_node_running(tmp_path):
    orchestrator = subprocess.Popen([sys.executable, '-c', ORCHESTRATOR, str(tmp_path)],
                                    stdout=subprocess.PIPE, text=True)
    child = int(orchestrator.stdout.readline())
    try:
        assert running(child)
        orchestrator.send_signal(signal.SIGKILL)      # no chance to stop its nodes itself
        orchestrator.wait(timeout=10)
        deadline = time.monotonic() + 10
        while running(child) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert not running(child)
    finally:
        if running(child):
            os.kill(child, signal.SIGKILL)
        orchestrator.stdout.close()
