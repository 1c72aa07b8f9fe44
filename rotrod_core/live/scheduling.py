"""Real-time scheduling of the calling thread (Linux SCHED_FIFO), as ros2_control does.

A thread under SCHED_FIFO runs as soon as it is runnable, ahead of every ordinary
(SCHED_OTHER) thread, so its wake-ups are not delayed by other processes on a busy
machine. It needs root or CAP_SYS_NICE (or an ``rtprio`` limit, ``ulimit -r``); where
it is not permitted the thread stays as it was and the reason is returned, for the
caller to log. The kernel's real-time throttling (``sched_rt_runtime_us``, 95 % by
default) keeps a runaway real-time thread from locking up a core.

Python threads share one interpreter lock: a real-time thread that wants it waits
for the thread holding it to give it up, which CPython forces after the switch
interval (5 ms by default). :data:`SWITCH_INTERVAL` shortens that wait.

A thread woken on an idle CPU also waits for the CPU to leave its sleep (C-) state;
in a virtual machine a halted vCPU must first be run again by the host, which is
sometimes milliseconds late. :class:`CpuLatencyRequest` asks the kernel to keep idle
CPUs out of states slower than that to wake (Linux PM QoS, ``/dev/cpu_dma_latency``,
as cyclictest and tuned's latency-performance profile do), for as long as it is held.
"""

from __future__ import annotations

import os
import struct
import sys

MAX_PRIORITY = 99
"""Highest SCHED_FIFO priority on Linux."""

SWITCH_INTERVAL = 0.0005
"""Interpreter-lock switch interval, s, while a thread runs at real-time priority."""

_ORDINARY_SWITCH_INTERVAL = sys.getswitchinterval()
"""The interpreter's switch interval before this module changed it, s."""

CPU_DMA_LATENCY = '/dev/cpu_dma_latency'
"""Linux's system-wide PM QoS CPU latency device: a request written to it (a 32-bit
int, microseconds) holds while the file stays open; reading it gives the limit in
force (the smallest request; 2000000000 with none)."""

MAX_CPU_LATENCY = 1_000_000
"""Largest CPU wake-up latency request accepted, us (1 s: beyond, no C-state differs)."""


def supported() -> bool:
    """Whether this platform has SCHED_FIFO and per-thread scheduling calls."""
    return hasattr(os, 'sched_setscheduler') and hasattr(os, 'SCHED_FIFO')


def set_current_thread_priority(priority: int) -> str | None:
    """Run the calling thread at SCHED_FIFO ``priority`` (1..99), or ordinary at 0.

    Returns None on success, else why it could not be done (the thread's scheduling
    is then unchanged). Also sets the interpreter's switch interval: SWITCH_INTERVAL
    at a real-time priority, back to the one before otherwise.
    """
    if isinstance(priority, bool) or not isinstance(priority, int) or not (
            0 <= priority <= MAX_PRIORITY):
        raise ValueError(f'priority must be an integer in [0, {MAX_PRIORITY}], '
                         f'got {priority!r}')
    if not supported():
        return f'SCHED_FIFO is not available on {sys.platform}'
    policy = os.SCHED_FIFO if priority else os.SCHED_OTHER
    try:
        # pid 0: the calling thread (Linux schedules threads, not processes)
        os.sched_setscheduler(0, policy, os.sched_param(priority))
    except OSError as exc:
        return (f'cannot set SCHED_FIFO priority {priority}: {exc.strerror} (needs root, '
                'CAP_SYS_NICE or an rtprio limit: ulimit -r)')
    sys.setswitchinterval(SWITCH_INTERVAL if priority else _ORDINARY_SWITCH_INTERVAL)
    return None


def run_current_thread_at(priority: int, logger, what: str) -> bool:
    """:func:`set_current_thread_priority`, logged; returns whether it was done.

    Info on success at a real-time priority, a warning with the reason on refusal.
    ``what`` names the thread in the message (e.g. 'physics thread').
    """
    problem = set_current_thread_priority(priority)
    if problem:
        logger.warning(f'realtime_priority: {problem}; {what}: ordinary scheduling')
        return False
    if priority:
        logger.info(f'{what} at SCHED_FIFO priority {priority}')
    return True


def current_thread_priority() -> int:
    """The calling thread's SCHED_FIFO priority (0: not real-time)."""
    if not supported() or os.sched_getscheduler(0) != os.SCHED_FIFO:
        return 0
    return os.sched_getparam(0).sched_priority



class CpuLatencyRequest:
    """A request that idle CPUs wake within a given latency, held until released.

    :meth:`hold` asks the kernel (PM QoS) to keep every CPU out of idle states that
    take longer than that many microseconds to leave; 0 keeps idle CPUs polling
    instead of halting, so a sleeping thread wakes at once. The cost is power: idle
    cores stay busy (in a virtual machine the host sees busy vCPUs). The request ends
    with :meth:`release` or with the process (the kernel drops it when the file
    closes).
    """

    def __init__(self, device: str = CPU_DMA_LATENCY):
        self._device = device
        self._fd: int | None = None
        self.microseconds: int | None = None
        """The latency held, us (None: none)."""

    def hold(self, microseconds: int) -> str | None:
        """Hold a limit of ``microseconds`` (0..MAX_CPU_LATENCY), replacing any held.

        Returns None on success, else why it could not be done (nothing is then held).
        """
        if isinstance(microseconds, bool) or not isinstance(microseconds, int) or not (
                0 <= microseconds <= MAX_CPU_LATENCY):
            raise ValueError(f'CPU latency must be an integer in [0, {MAX_CPU_LATENCY}] us, '
                             f'got {microseconds!r}')
        try:
            if self._fd is None:
                self._fd = os.open(self._device, os.O_WRONLY | os.O_CLOEXEC)
            # a later write on the same file updates this request
            os.write(self._fd, struct.pack('=i', microseconds))
        except OSError as exc:
            self.release()
            return (f'cannot hold a CPU wake-up latency of {microseconds} us through '
                    f'{self._device}: {exc.strerror} (needs root)')
        self.microseconds = microseconds
        return None

    def release(self) -> None:
        """End the request (nothing if none is held)."""
        if self._fd is not None:
            os.close(self._fd)
        self._fd = None
        self.microseconds = None


def cpu_latency_limit(device: str = CPU_DMA_LATENCY) -> int | None:
    """The system-wide CPU wake-up latency limit in force, us (None: unreadable)."""
    try:
        fd = os.open(device, os.O_RDONLY | os.O_CLOEXEC)
    except OSError:
        return None
    try:
        data = os.read(fd, 4)
    finally:
        os.close(fd)
    return struct.unpack('=i', data)[0] if len(data) == 4 else None


class ThreadScheduling:
    """The calling thread's SCHED_FIFO priority and a CPU latency request, kept as asked.

    :meth:`update` is called from the thread itself whenever the wanted settings may
    have changed; it changes only what differs, logs each change, and does not ask
    again for what the system refused.
    """

    def __init__(self, logger, what: str, device: str = CPU_DMA_LATENCY):
        self._logger = logger
        self._what = what
        self.priority = 0
        """The thread's SCHED_FIFO priority (0: ordinary)."""
        self._priority_refused: int | None = None
        self._latency = CpuLatencyRequest(device)
        self._latency_refused = False

    @property
    def cpu_latency(self) -> int | None:
        """The CPU wake-up latency request held, us (None: none)."""
        return self._latency.microseconds

    def update(self, priority: int, cpu_latency: int) -> bool:
        """Run at ``priority`` (0: ordinary) and hold ``cpu_latency`` us (-1: none).

        Returns whether anything was changed (or tried and refused).
        """
        changed = self._hold(cpu_latency)
        if priority in (self.priority, self._priority_refused):
            return changed
        if run_current_thread_at(priority, self._logger, self._what):
            self.priority = priority
        else:
            self._priority_refused = priority
        return True

    def _hold(self, want: int) -> bool:
        held = self._latency.microseconds
        if want < 0:
            if held is None:
                return False
            self._latency.release()
            self._logger.info('cpu_dma_latency: released (not paced)')
            return True
        if want == held or self._latency_refused:
            return False
        problem = self._latency.hold(want)
        if problem:
            self._latency_refused = True
            self._logger.warning(f'cpu_dma_latency: {problem}; idle CPUs may wake '
                                 'late (set cpu_dma_latency:=-1 to not ask)')
        else:
            self._logger.info(f'cpu_dma_latency: idle CPUs wake within {want} us '
                              'while paced')
        return True

    def release(self) -> None:
        """Drop the CPU latency request (the priority stays: the thread is ending)."""
        self._latency.release()
