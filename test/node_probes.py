"""What the node tests and the real-time bench share: unique namespaces, starting the
simulator, reading stamps and DDS timestamps, and a process's memory and CPU time."""

import hashlib
import os
from pathlib import Path

from ros_harness import ros_arguments

from rotrod_ros.messages import to_seconds


def namespace(request) -> str:
    """A short namespace unique to the test (long DDS names slow discovery down)."""
    return '/t' + hashlib.sha1(request.node.nodeid.encode()).hexdigest()[:10]


def start_simulator(ros_processes, ns, **params):
    """The simulator in namespace ``ns`` with ``params``, once it says it is ready."""
    proc = ros_processes.start_console_script(
        'simulator', *ros_arguments(namespace=ns, params=params), name=ns.strip('/'))
    proc.wait_for_output('ready', timeout=30)
    return proc


def stamp(msg) -> float:
    """A stamped message's header time, s."""
    return to_seconds(msg.header.stamp)


def collect(node, topic, msg_type, depth: int = 1000):
    """Subscribe; return the list of (message, DDS source time s, receive time s)."""
    out = []
    node.node.create_subscription(
        msg_type, topic, lambda m, info: out.append(
            (m, info['source_timestamp'] * 1e-9, info['received_timestamp'] * 1e-9)), depth)
    return out


def rss(pid: int) -> int:
    """Resident memory of a process, bytes (/proc/<pid>/status VmRSS)."""
    for line in Path(f'/proc/{pid}/status').read_text().splitlines():
        if line.startswith('VmRSS:'):
            return int(line.split()[1]) * 1024
    raise AssertionError(f'no VmRSS for pid {pid}')


def cpu_seconds(pid: int) -> float:
    """User + system CPU time of a process, s."""
    fields = Path(f'/proc/{pid}/stat').read_text().rsplit(')', 1)[1].split()
    return (int(fields[11]) + int(fields[12])) / os.sysconf('SC_CLK_TCK')
