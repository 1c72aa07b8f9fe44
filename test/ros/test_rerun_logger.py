"""The Rerun logger, as a real process."""

import signal
import time

import pytest
from node_probes import namespace, start_simulator
from ros_harness import ros_arguments
from std_msgs.msg import Float64
from std_srvs.srv import Trigger

from rotrod_core.reporting import recording

pytestmark = pytest.mark.ros


def test_logger_serves_on_localhost_only(ros_processes, tmp_path):
    port = 19000 + (hash(str(tmp_path)) % 1000)
    # every drawn parameter given: it records without a simulator's description
    drawn = {'mass': 0.3, 'rod_length': 0.3, 'rod_diameter': 0.003, 'eccentricity': 0.1,
             'deflection_limit': 0.003}
    logger = ros_processes.start_console_script('rerun_logger', *ros_arguments(
        params={'output': str(tmp_path / 'x.rrd'), 'serve': True, 'serve_port': port,
                **drawn}))
    logger.wait_for_output('serving at', timeout=30)
    listening = set()
    for line in open('/proc/net/tcp').read().splitlines()[1:]:
        local, state = line.split()[1], line.split()[3]
        if state == '0A':                              # LISTEN
            addr, p = local.split(':')
            listening.add((addr, int(p, 16)))
    assert ('0100007F', port) in listening             # 127.0.0.1
    assert ('00000000', port) not in listening         # not 0.0.0.0


def test_a_halt_and_its_reset_are_events_in_the_recording(ros_processes, ros_node, request,
                                                           tmp_path):
    """Torque drive past max_omega halts the simulator; its /diagnostics say so, and the
    logger in its namespace writes the halt, then its clearing by ~/reset, as events."""
    ns = namespace(request)
    out = tmp_path / 'halt.rrd'
    logger = ros_processes.start_console_script('rerun_logger', *ros_arguments(
        namespace=ns, params={'output': str(out)}), name='logger')
    logger.wait_for_output('subscribed to the simulator', timeout=30)
    sim = start_simulator(ros_processes, ns, drive='torque', hub_inertia=0.0624,
                          max_omega=1.0)
    torque = ros_node.node.create_publisher(Float64, f'{ns}/cmd/torque', 10)
    ros_node.spin_until(lambda: torque.get_subscription_count() > 0, 10, 'cmd/torque sub')
    # the halt's status is sent once, on the change: the logger must be receiving first
    # (on a loaded machine its subscriptions matched seconds after the simulator began)
    logger.wait_for_output('receiving: first joint state', timeout=30)
    ros_node.spin_until(lambda: ros_node.node.count_subscribers('/diagnostics') > 0, 10,
                        "the logger's /diagnostics subscription")
    torque.publish(Float64(data=0.5))                 # 8 rad/s^2: past 1 rad/s in 0.13 s
    sim.wait_for_output('simulation halted', timeout=30)
    time.sleep(1.5)                                   # a diagnostics period
    assert ros_node.call_service(Trigger, f'{ns}/rotrod_simulator/reset').success
    time.sleep(1.5)
    logger.signal_group(signal.SIGINT)
    assert logger.wait(timeout=60) == 0
    _, texts = recording.read_component(out, recording.EVENTS, 'TextLog:text')
    _, levels = recording.read_component(out, recording.EVENTS, 'TextLog:level')
    entries = [(level[0], text[0]) for level, text in zip(levels, texts)]
    halts = [e for e in entries if e[1].startswith('halted:')]
    assert len(halts) == 1 and halts[0][0] == 'ERROR', entries
    assert 'beyond max_omega 1 rad/s' in halts[0][1]
    assert any(text == 'the halt is cleared (reset)' for _, text in entries), entries
