"""Real-time scheduling of the physics thread (rotrod_core/live/scheduling.py), checked
through the kernel's own view of each thread's policy."""

import os
import subprocess
import sys
import threading

import pytest

from rotrod_core.live import scheduling

ROOT = os.geteuid() == 0
NOBODY = 65534


def in_thread(fn):
    out = {}
    t = threading.Thread(target=lambda: out.setdefault('value', fn()))
    t.start()
    t.join()
    return out['value']


@pytest.mark.skipif(not ROOT, reason='SCHED_FIFO needs root here')
def test_fifo_applies_to_the_calling_thread_only_and_can_be_undone():
    before = sys.getswitchinterval()

    def run():
        tid = threading.get_native_id()
        assert scheduling.set_current_thread_priority(50) is None
        seen = (os.sched_getscheduler(tid), os.sched_getparam(tid).sched_priority,
                scheduling.current_thread_priority(), sys.getswitchinterval(),
                os.sched_getscheduler(main))
        assert scheduling.set_current_thread_priority(0) is None
        return seen, os.sched_getscheduler(tid), sys.getswitchinterval()

    main = threading.get_native_id()
    (policy, prio, current, interval, main_policy), after, restored = in_thread(run)
    assert (policy, prio, current) == (os.SCHED_FIFO, 50, 50)
    assert interval == pytest.approx(scheduling.SWITCH_INTERVAL)
    assert main_policy == os.SCHED_OTHER            # the other threads are untouched
    assert after == os.SCHED_OTHER and scheduling.current_thread_priority() == 0
    assert restored == pytest.approx(before)


@pytest.mark.skipif(not ROOT, reason='dropping to an unprivileged user needs root')
def test_without_privilege_it_is_refused_with_a_reason_and_nothing_changes():
    # the interpreter lives under /root: drop to nobody after it has started
    code = ('import os, resource, sys\n'
            'from rotrod_core.live import scheduling as s\n'
            'resource.setrlimit(resource.RLIMIT_RTPRIO, (0, 0))\n'
            f'os.setgroups([]); os.setgid({NOBODY}); os.setuid({NOBODY})\n'
            'r = s.set_current_thread_priority(50)\n'
            'print(r); print(os.sched_getscheduler(0) == os.SCHED_OTHER, '
            'sys.getswitchinterval())\n')
    out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                         check=True, env={**os.environ, 'PYTHONPATH': os.pathsep.join(sys.path)})
    reason, state = out.stdout.splitlines()
    assert 'cannot set SCHED_FIFO priority 50' in reason and 'CAP_SYS_NICE' in reason
    assert state == f'True {sys.getswitchinterval()}'


@pytest.mark.parametrize('bad', [-1, 100, 1.5, True, '50', None])
def test_a_priority_outside_0_to_99_is_an_error(bad):
    with pytest.raises(ValueError, match='priority must be an integer'):
        scheduling.set_current_thread_priority(bad)



class Log:
    def __init__(self):
        self.lines = []

    def info(self, text):
        self.lines.append(('info', text))

    def warning(self, text):
        self.lines.append(('warning', text))


def test_a_refusal_is_logged_with_its_reason_and_success_with_the_priority(monkeypatch):
    log = Log()
    assert in_thread(lambda: scheduling.run_current_thread_at(0, log, 'physics thread'))
    assert log.lines == []                              # ordinary: nothing to say
    monkeypatch.setattr(scheduling, 'set_current_thread_priority', lambda p: 'no rights')
    assert not scheduling.run_current_thread_at(50, log, 'physics thread')
    assert log.lines == [('warning', 'realtime_priority: no rights; physics thread: '
                                     'ordinary scheduling')]
    if ROOT:
        monkeypatch.undo()
        log = Log()
        assert in_thread(lambda: scheduling.run_current_thread_at(20, log, 'streaming'))
        assert log.lines == [('info', 'streaming at SCHED_FIFO priority 20')]


CAN_REQUEST_LATENCY = os.access(scheduling.CPU_DMA_LATENCY, os.W_OK)


@pytest.mark.skipif(not CAN_REQUEST_LATENCY, reason='/dev/cpu_dma_latency needs root')
def test_a_cpu_latency_request_holds_until_released_or_the_process_ends():
    before = scheduling.cpu_latency_limit()
    assert before is not None and before > 7
    request = scheduling.CpuLatencyRequest()
    assert request.hold(7) is None
    assert scheduling.cpu_latency_limit() == 7 and request.microseconds == 7
    assert request.hold(0) is None                 # the same request, tightened
    assert scheduling.cpu_latency_limit() == 0
    request.release()
    assert scheduling.cpu_latency_limit() == before and request.microseconds is None
    request.release()                              # twice: nothing to do
    # a process killed while holding one: the kernel ends its request
    code = ('import sys, time\nfrom rotrod_core.live import scheduling as s\n'
            'r = s.CpuLatencyRequest(); assert r.hold(0) is None\n'
            'print("held", flush=True); time.sleep(60)\n')
    child = subprocess.Popen([sys.executable, '-c', code], stdout=subprocess.PIPE, text=True,
                             env={**os.environ, 'PYTHONPATH': os.pathsep.join(sys.path)})
    try:
        assert child.stdout.readline().strip() == 'held'
        assert scheduling.cpu_latency_limit() == 0
    finally:
        child.kill()
        child.wait()
    assert scheduling.cpu_latency_limit() == before


def test_a_cpu_latency_request_that_cannot_be_made_says_why_and_holds_nothing(tmp_path):
    request = scheduling.CpuLatencyRequest(device=str(tmp_path / 'missing'))
    reason = request.hold(0)
    assert 'cannot hold a CPU wake-up latency of 0 us' in reason and 'needs root' in reason
    assert request.microseconds is None
    assert scheduling.cpu_latency_limit(str(tmp_path / 'missing')) is None


@pytest.mark.skipif(not ROOT, reason='dropping to an unprivileged user needs root')
def test_without_privilege_a_cpu_latency_request_is_refused():
    code = ('import os\nfrom rotrod_core.live import scheduling as s\n'
            f'os.setgroups([]); os.setgid({NOBODY}); os.setuid({NOBODY})\n'
            'r = s.CpuLatencyRequest(); print(r.hold(0)); print(r.microseconds)\n')
    out = subprocess.run([sys.executable, '-c', code], capture_output=True, text=True,
                         check=True, env={**os.environ, 'PYTHONPATH': os.pathsep.join(sys.path)})
    reason, held = out.stdout.splitlines()
    assert 'cannot hold a CPU wake-up latency' in reason and 'ermission denied' in reason
    assert held == 'None'


@pytest.mark.parametrize('bad', [-1, scheduling.MAX_CPU_LATENCY + 1, 1.5, True, '0', None])
def test_a_cpu_latency_outside_its_range_is_an_error(bad):
    with pytest.raises(ValueError, match='CPU latency must be an integer'):
        scheduling.CpuLatencyRequest().hold(bad)
