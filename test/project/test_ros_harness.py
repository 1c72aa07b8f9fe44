"""Tests of the ROS test harness (``ros_harness.py``) with real ROS 2 processes.

* the per-run environment keeps DDS on this machine (LOCALHOST discovery, own domain id,
  and, when run through ``isolate.py`` where permitted, a loopback-only network namespace);
* a talker and a listener started as separate processes exchange std_msgs/String messages;
* the test process itself subscribes to a node's topic (``ros_node`` fixture);
* ``stop()`` escalates SIGINT -> SIGTERM -> SIGKILL over the whole process group and reaps it;
* a failing or timed-out test gets its processes' output in the report and leaves none behind.
"""

import os
import re
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from ros_harness import (
    HarnessTimeout,
    ProcessExitedError,
    group_members,
    isolation_mode,
    ros_arguments,
)

HERE = Path(__file__).resolve().parents[1]     # test/: the harness and nodes/
TALKER = HERE / 'nodes' / 'talker.py'
LISTENER = HERE / 'nodes' / 'listener.py'


def _topic(request) -> str:
    """A topic name unique to the test (tests of one run share a domain)."""
    return 'harness_' + re.sub(r'\W', '_', request.node.name)


def _pid_gone(pid: int) -> bool:
    """True if ``pid`` no longer exists or is a zombie."""
    try:
        import psutil
    except ImportError:
        try:
            state = Path(f'/proc/{pid}/stat').read_bytes().rsplit(b')', 1)[1].split()[0]
        except OSError:
            return True
        return state in (b'Z', b'X')
    try:
        return psutil.Process(pid).status() == psutil.STATUS_ZOMBIE
    except psutil.NoSuchProcess:
        return True


def test_environment_keeps_dds_local():
    env = os.environ
    domain = int(env['ROS_DOMAIN_ID'])
    assert 1 <= domain <= 101
    assert env['ROS_AUTOMATIC_DISCOVERY_RANGE'] == 'LOCALHOST'
    assert env['RMW_IMPLEMENTATION'] == 'rmw_fastrtps_cpp'
    assert env['PYTHONUNBUFFERED'] == '1'
    assert Path(env['ROS_LOG_DIR']).is_dir()
    for name in ('ROS_STATIC_PEERS', 'ROS_DISCOVERY_SERVER', 'FASTRTPS_DEFAULT_PROFILES_FILE',
                 'FASTDDS_DEFAULT_PROFILES_FILE', 'ROS_LOCALHOST_ONLY'):
        assert name not in env, name
    mode = isolation_mode()
    print(f'isolation: {mode}, ROS_DOMAIN_ID={domain}')
    if env.get('ROTROD_ISOLATION') == 'netns':
        # isolate.py said it created a private namespace: only loopback may be visible.
        import socket
        assert [name for _, name in socket.if_nameindex()] == ['lo']
        assert mode == 'netns'


def test_ros_arguments():
    args = ros_arguments(node_name='sim', namespace='/a', remap={'tip': 'tip2'},
                         params={'rate': 50.0, 'on': True, 'name': 'x', 'v': [1, 2]},
                         log_level='warn')
    assert args == ['--ros-args', '-r', '__node:=sim', '-r', '__ns:=/a', '-r', 'tip:=tip2',
                    '-p', 'rate:=50.0', '-p', 'on:=true', '-p', 'name:=x', '-p', 'v:=[1, 2]',
                    '--log-level', 'warn']


@pytest.mark.ros
def test_talker_listener_pubsub(ros_processes, request):
    n = 10
    topic = _topic(request)
    listener = ros_processes.start_python(LISTENER, '--topic', topic, '--count', str(n))
    listener.wait_for_output(r'^listener ready', timeout=20)
    talker = ros_processes.start_python(TALKER, '--topic', topic, '--rate', '20',
                                        '--prefix', 'rotrod')
    assert listener.wait(timeout=30) == 0

    heard = re.findall(r'^heard: (.*)$', listener.output, re.MULTILINE)
    assert len(heard) == n, listener.output
    values = []
    for data in heard:
        m = re.fullmatch(r'rotrod (\d+)', data)
        assert m, f'unexpected message content {data!r}'
        values.append(int(m.group(1)))
    assert values == list(range(values[0], values[0] + n)), f'not consecutive: {values}'
    # Every message heard is one the talker says it published. It says so after
    # publishing: on a loaded machine the listener can hear the last one first.
    talker.wait_for_output(rf'^published: {re.escape(heard[-1])}$', timeout=10)
    published = set(re.findall(r'^published: (.*)$', talker.output, re.MULTILINE))
    assert set(heard) <= published

    # The child processes run with this test run's ROS settings.
    env_line = re.search(r'^env: (.*)$', listener.output, re.MULTILINE).group(1)
    assert f'ROS_DOMAIN_ID={os.environ["ROS_DOMAIN_ID"]}' in env_line
    assert 'ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST' in env_line
    assert 'RMW_IMPLEMENTATION=rmw_fastrtps_cpp' in env_line

    # A clean shutdown on SIGINT, no escalation needed.
    assert talker.stop() == 0
    assert talker.signals_sent == [signal.SIGINT]
    assert 'talker: shutting down on signal' in talker.output
    assert not talker.group_alive()


@pytest.mark.ros
def test_in_process_subscriber(ros_processes, ros_node, request):
    from std_msgs.msg import String

    topic = _topic(request)
    talker = ros_processes.start_python(TALKER, '--topic', topic, '--rate', '20')
    talker.wait_for_output(r'^talker ready', timeout=20)
    assert ros_node.wait_for_publishers(topic, timeout=20) == 1
    msgs = ros_node.wait_for_messages(topic, String, n=5, timeout=20)
    values = [int(m.data.split()[1]) for m in msgs]
    assert all(m.data.startswith('hello ') for m in msgs)
    assert values == list(range(values[0], values[0] + 5))
    with pytest.raises(HarnessTimeout, match='no_such_topic'):
        ros_node.wait_for_messages(topic + '_no_such_topic', String, n=1, timeout=0.3)

    # A service call from the test process: the talker's counter restarts at 0.
    from std_srvs.srv import Trigger

    received = ros_node.subscribe(topic, String)
    ros_node.spin_until(lambda: len(received) >= 3, timeout=20, what='3 messages')
    before = len(received)
    response = ros_node.call_service(Trigger, '/talker/reset', timeout=20)
    assert response.success and response.message == 'counter reset'
    ros_node.spin_until(lambda: any(m.data == 'hello 0' for m in received[before:]),
                        timeout=10, what='hello 0 after reset')
    assert talker.wait_for_output(r'^reset$')


SLEEPER = textwrap.dedent('''
    import signal, subprocess, sys, time
    signal.signal(signal.SIGINT, signal.SIG_IGN)
    child = subprocess.Popen([sys.executable, '-S', '-c',
        'import signal, time\\n'
        'signal.signal(signal.SIGINT, signal.SIG_IGN)\\n'
        'signal.signal(signal.SIGTERM, signal.SIG_IGN)\\n'
        'print("grandchild up", flush=True)\\n'
        'time.sleep(600)\\n'])
    print(f"grandchild {child.pid}", flush=True)
    time.sleep(600)
''')


def test_stop_escalates_and_reaps_the_group(ros_processes):
    proc = ros_processes.start([sys.executable, '-S', '-c', SLEEPER], name='stubborn')
    proc.wait_for_output(r'grandchild up', timeout=10)
    grandchild = int(proc.wait_for_output(r'^grandchild (\d+)', timeout=10).group(1))
    assert set(proc.group_alive()) == {proc.pid, grandchild}

    t0 = time.monotonic()
    rc = proc.stop(sigint_timeout=0.5, sigterm_timeout=0.5, kill_timeout=5)
    elapsed = time.monotonic() - t0
    # SIGINT is ignored by both; SIGTERM kills the parent; only SIGKILL gets the grandchild.
    assert rc == -signal.SIGTERM
    assert proc.signals_sent == [signal.SIGINT, signal.SIGTERM, signal.SIGKILL]
    assert proc.poll() == -signal.SIGTERM
    assert group_members(proc.pgid) == []
    assert _pid_gone(proc.pid) and _pid_gone(grandchild)
    assert elapsed < 4
    # Stopping again is harmless.
    assert proc.stop() == -signal.SIGTERM


def test_wait_errors_carry_the_output(ros_processes):
    quitter = ros_processes.start(
        [sys.executable, '-S', '-c', 'print("some output"); raise SystemExit(3)'])
    with pytest.raises(ProcessExitedError, match=r'(?s)exit status 3.*some output'):
        quitter.wait_for_output('never printed', timeout=10)
    assert quitter.returncode == 3

    sleeper = ros_processes.start([sys.executable, '-S', '-c',
                                   'print("waiting", flush=True); import time; time.sleep(60)'])
    sleeper.wait_for_output('waiting', timeout=10)
    with pytest.raises(HarnessTimeout, match=r'(?s)did not print .*waiting'):
        sleeper.wait_for_output('never printed', timeout=0.3)
    with pytest.raises(HarnessTimeout, match='did not exit'):
        sleeper.wait(timeout=0.2)
    assert sleeper.running
    missing = ros_processes.start(['/nonexistent/rotrod-exe'])
    assert missing.wait(timeout=10) == 127
    assert 'cannot execute' in missing.output
    # The fixture stops `sleeper` at teardown.


INNER_TESTS = '''
import sys
from pathlib import Path
import time

import pytest

CHILD = ('import os, time; print("{marker}", os.getpid(), flush=True); '
         'time.sleep(120)')


def _start(ros_processes, marker, name):
    proc = ros_processes.start([sys.executable, '-S', '-c', CHILD.format(marker=marker)],
                               name=name)
    proc.wait_for_output(marker, timeout=10)
    Path(f'{name}.pid').write_text(str(proc.pid))
    return proc


def test_fails(ros_processes):
    _start(ros_processes, 'INNER-FAIL-MARKER', 'failing_node')
    assert 1 + 1 == 3, 'deliberate failure'


@pytest.mark.timeout(10)     # the child's start-up included (1 s was tight under load)
def test_times_out(ros_processes):
    _start(ros_processes, 'INNER-TIMEOUT-MARKER', 'hanging_node')
    time.sleep(60)


def test_passes(ros_processes):
    proc = _start(ros_processes, 'INNER-PASS-MARKER', 'passing_node')
    assert proc.running
'''


@pytest.mark.long   # 12 s, a pytest session of its own: in CI's long run (the default run
# was at 14:30-15:14 of its 15 minutes); the harness's other tests stay in the default run
def test_failure_report_shows_output_and_cleans_up(tmp_path):
    """Run a small pytest session with the harness; check reports and cleanup."""
    (tmp_path / 'pytest.ini').write_text('[pytest]\n')
    (tmp_path / 'conftest.py').write_text(
        f'import sys\nsys.path.insert(0, {str(HERE)!r})\n'
        'from ros_harness import (pytest_configure, pytest_report_header,  # noqa\n'
        '    pytest_runtest_makereport, pytest_unconfigure, ros_processes)\n')
    (tmp_path / 'test_inner.py').write_text(INNER_TESTS)
    proc = subprocess.run(
        [sys.executable, '-m', 'pytest', '-p', 'no:cacheprovider', '-rA',
         '--timeout-method=signal', 'test_inner.py'],
        cwd=tmp_path, capture_output=True, text=True, timeout=120, check=False)
    out = proc.stdout + proc.stderr
    print(out)
    assert proc.returncode == 1, out
    assert re.search(r'2 failed, 1 passed', out), out
    assert 'rotrod ROS isolation:' in out
    # Each failing test's report has its process's section with the output.
    assert re.search(r'ros process failing_node output.*\n(.*\n)*.*INNER-FAIL-MARKER', out), out
    assert re.search(r'ros process hanging_node output.*\n(.*\n)*.*INNER-TIMEOUT-MARKER',
                     out), out
    assert 'Timeout' in out
    # A passing test's processes are not dumped.
    assert 'ros process passing_node output' not in out
    for name in ('failing_node', 'hanging_node', 'passing_node'):
        pid = int((tmp_path / f'{name}.pid').read_text())
        assert _pid_gone(pid), f'{name} (pid {pid}) is still running'
