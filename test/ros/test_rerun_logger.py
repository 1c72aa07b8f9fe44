"""The Rerun logger, as a real process."""

import pytest
from ros_harness import ros_arguments

pytestmark = pytest.mark.ros


def test_logger_serves_on_localhost_only(ros_processes, tmp_path):
    port = 19000 + (hash(str(tmp_path)) % 1000)
    logger = ros_processes.start_console_script('rerun_logger', *ros_arguments(
        params={'output': str(tmp_path / 'x.rrd'), 'serve': True, 'serve_port': port}))
    logger.wait_for_output('serving at', timeout=30)
    listening = set()
    for line in open('/proc/net/tcp').read().splitlines()[1:]:
        local, state = line.split()[1], line.split()[3]
        if state == '0A':                              # LISTEN
            addr, p = local.split(':')
            listening.add((addr, int(p, 16)))
    assert ('0100007F', port) in listening             # 127.0.0.1
    assert ('00000000', port) not in listening         # not 0.0.0.0
