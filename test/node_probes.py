"""What the node tests and the real-time bench share: unique namespaces, starting the
simulator, commanding it and setting its parameters, reading stamps and DDS timestamps,
and a process's memory and CPU time."""

import hashlib
import os
import time
from pathlib import Path

import numpy as np
from rcl_interfaces.msg import Parameter, ParameterType, ParameterValue
from rcl_interfaces.srv import GetParameters, SetParameters
from ros_harness import ros_arguments
from std_msgs.msg import Float64

from rotrod_ros.messages import to_seconds


def namespace(request) -> str:
    """A short namespace unique to the test (long DDS names slow discovery down)."""
    return '/t' + hashlib.sha1(request.node.nodeid.encode()).hexdigest()[:10]


CONFIG = Path(__file__).resolve().parent.parent / 'config'
"""The package's parameter files."""


def start_simulator(ros_processes, ns, *params_files, **params):
    """The simulator in namespace ``ns``, once it says it is ready.

    ``params_files`` are names of files in config/ (``'table1.yaml'``), applied in
    order; ``params`` override them.
    """
    ros_args = ros_arguments(namespace=ns, params=params)
    files = [arg for name in params_files for arg in ('--params-file', str(CONFIG / name))]
    proc = ros_processes.start_console_script(
        'simulator', ros_args[0], *files, *ros_args[1:], name=ns.strip('/'))
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


def drain(node, received, quiet: float = 0.3, timeout: float = 10.0,
          what: str = 'messages') -> None:
    """Spin until nothing has been added to ``received`` for ``quiet`` s: what was
    published before now (reliable, queued behind a busy test process) is in."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        n = len(received)
        node.spin_for(quiet)
        if len(received) == n:
            return
    raise AssertionError(f'{what} still arriving after {timeout:g} s')


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


def by_time(joint, deflection):
    """Join joint_states and tip/deflection on their stamps: rows t, theta, w, Q, u, v."""
    d = {stamp(m): (m.vector.x, m.vector.y) for m in deflection}
    rows = [(stamp(j), j.position[0], j.velocity[0], j.effort[0], *d[stamp(j)])
            for j in joint if stamp(j) in d]
    return np.array(sorted(rows))


def hann_mean(x):
    w = np.hanning(len(x))
    return float(np.sum(w * x) / np.sum(w))


def param(name, value) -> Parameter:
    if isinstance(value, str):
        v = ParameterValue(type=ParameterType.PARAMETER_STRING, string_value=value)
    elif isinstance(value, float):
        v = ParameterValue(type=ParameterType.PARAMETER_DOUBLE, double_value=value)
    elif isinstance(value, int) and not isinstance(value, bool):
        v = ParameterValue(type=ParameterType.PARAMETER_INTEGER, integer_value=value)
    else:
        raise TypeError(value)
    return Parameter(name=name, value=v)


def set_parameters(node, ns, *params):
    req = SetParameters.Request(parameters=list(params))
    return node.call_service(SetParameters, f'{ns}/rotrod_simulator/set_parameters', req)


def get_parameter(node, ns, name):
    req = GetParameters.Request(names=[name])
    value = node.call_service(GetParameters, f'{ns}/rotrod_simulator/get_parameters', req)
    v = value.values[0]
    return {ParameterType.PARAMETER_DOUBLE: v.double_value,
            ParameterType.PARAMETER_STRING: v.string_value}[v.type]


def omega_publisher(node, ns):
    pub = node.node.create_publisher(Float64, f'{ns}/cmd/omega', 1000)   # lossless burst
    node.spin_until(lambda: pub.get_subscription_count() > 0, 10, 'cmd/omega subscriber')
    return pub
