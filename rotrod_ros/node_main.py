"""The common ``main`` of the package's nodes: arguments, init, spin, clean shutdown."""

from __future__ import annotations

import argparse
import os
import signal
import sys
import threading
import time
from collections.abc import Callable

import rclpy
from rclpy.action import ActionClient, ActionServer
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.signals import SignalHandlerOptions
from rclpy.utilities import remove_ros_args


def parser(prog: str, doc: str, lines: list[str]) -> argparse.ArgumentParser:
    """A node's ``--help``: its docstring's first line, then the rest of it and ``lines``."""
    return argparse.ArgumentParser(
        prog=prog, description=doc.split('\n')[0],
        epilog='\n'.join([doc.split('\n', 2)[2], *lines]),
        formatter_class=argparse.RawDescriptionHelpFormatter)


class ConfigurationError(ValueError):
    """A node's parameters are invalid: it exits with status 2 and the reason."""


SHUTDOWN_GRACE = 1.0
"""Wall seconds an error raised by the executor may precede the context's shutdown.

rclpy's signal handler shuts the context down from a thread of its own: the executor,
woken by the same signal, can fail on a subscription being torn down (seen: a
RuntimeError from take_message) before ``rclpy.ok()`` turns false."""


def _shutting_down() -> bool:
    """Whether the context shuts down within :data:`SHUTDOWN_GRACE` (polled)."""
    deadline = time.monotonic() + SHUTDOWN_GRACE
    while rclpy.ok():
        if time.monotonic() > deadline:
            return False
        time.sleep(0.01)
    return True


_SIGNALLED: list = []
"""The signals :func:`_interrupt` took (own_signals)."""


def _interrupt(signum, frame):
    """A signal ends the spin (own_signals): as Ctrl-C does in Python.

    The KeyboardInterrupt may surface inside rclpy's C++ (a message being taken), which
    turns it into another error: the signal is noted so that run() knows either way.
    """
    _SIGNALLED.append(signum)
    raise KeyboardInterrupt(signal.Signals(signum).name)


def _wake_on_signals(node) -> None:
    """Wake the executor when SIGINT or SIGTERM comes (own_signals).

    Python runs a signal's handler in the main thread between bytecodes, but the
    executor waits in C for as long as nothing happens. The interpreter writes each
    signal's number to a pipe (``signal.set_wakeup_fd``); a thread blocked on the pipe
    triggers a guard condition, which ends the wait, and the handler then runs.
    """
    read_end, write_end = os.pipe()
    os.set_blocking(write_end, False)
    signal.set_wakeup_fd(write_end, warn_on_full_buffer=False)
    guard = node.create_guard_condition(lambda: None)

    def watch():
        while os.read(read_end, 64):
            guard.trigger()

    threading.Thread(target=watch, name='signal_wakeup', daemon=True).start()


def _destroy_node(node) -> None:
    """``node.destroy_node()``, with the node's action servers and clients first.

    rclpy's destroy_node destroys the node's publishers, subscriptions, services,
    clients, timers and guard conditions, not its other waitables: an ActionServer or
    ActionClient left alive holds the rcl node, which is then never finalized. Its
    Fast DDS participant, and rmw's graph listener thread that only that finalization
    stops, would outlive the interpreter: at exit, Fast DDS's static
    DomainParticipantFactory deletes the participant while the listener thread still
    waits on its conditions and takes from its reader, a use after free that now and
    then corrupts the heap (seen: SIGABRT after the last log line,
    ``malloc_consolidate(): unaligned fastbin chunk detected``).
    """
    for waitable in list(node.waitables):
        if isinstance(waitable, (ActionServer, ActionClient)):
            waitable.destroy()
    node.destroy_node()


def single_threaded_blas() -> None:
    """Run BLAS and LAPACK (numpy's and scipy's OpenBLAS) on the calling thread only.

    A node's linear algebra is small (the whirl estimator's fits, the planner's solves)
    and runs at a rate: with a pool, OpenBLAS's worker threads busy-wait after each
    call for the next one, and at the simulator's 100 Hz of estimates they never rest.
    Measured: the simulator at its defaults with one subscriber took 96 % of a core in
    that thread, against 12 % for the rest of the node (docs/realtime.md). The limit
    is threadpoolctl's, for the whole process (the library's pools are shared).
    """
    from threadpoolctl import threadpool_limits
    threadpool_limits(limits=1)


def run(name: str, make_node: Callable, parser: argparse.ArgumentParser,
        args: list | None = None, *,
        until: Callable | None = None, started: Callable | None = None,
        finished: Callable | None = None, own_signals: bool = False,
        status: Callable | None = None) -> int:
    """Parse non-ROS arguments (``--help``), build the node, spin, shut down cleanly.

    Args:
        name: node name for error messages.
        make_node: builds the node (may raise ConfigurationError: exit status 2).
        parser: the executable's argument parser (for ``--help``).
        args: argv (default sys.argv).
        until: spin until it returns true (default: until shutdown).
        started: called with the node before spinning.
        finished: called with the node after spinning (also on a signal).
        own_signals: SIGINT and SIGTERM end the spin with the context still up, so
            ``finished`` can still publish and wait for acknowledgements (Python's
            handlers, woken through a pipe: :func:`_wake_on_signals`).
        status: called with the node after spinning: the exit status (default 0).

    SIGINT and SIGTERM end the spin (rclpy's handlers shut the context down, unless
    ``own_signals``); an error raised by rclpy while the context is shutting down is
    part of that, not a failure.
    """
    argv = list(sys.argv if args is None else args)
    parser.parse_args(remove_ros_args(argv)[1:])
    single_threaded_blas()
    if own_signals:
        rclpy.init(args=argv, signal_handler_options=SignalHandlerOptions.NO)
        for signum in (signal.SIGINT, signal.SIGTERM):
            signal.signal(signum, _interrupt)
    else:
        rclpy.init(args=argv)
    node = executor = None
    try:
        try:
            node = make_node()
        except ConfigurationError as exc:
            print(f'{name}: invalid configuration: {exc}', file=sys.stderr)
            return 2
        executor = SingleThreadedExecutor()
        executor.add_node(node)
        if own_signals:
            _wake_on_signals(node)
        try:
            if started:
                started(node)
            if until is None:
                executor.spin()
            else:
                while rclpy.ok() and not until(node):
                    executor.spin_once(timeout_sec=0.1)
        except (KeyboardInterrupt, ExternalShutdownException):
            pass
        except Exception:
            if not (_SIGNALLED or _shutting_down()):
                raise
        return 0 if status is None else status(node)
    finally:
        if executor is not None:
            executor.shutdown()
        if node is not None:
            if finished:
                finished(node)
            _destroy_node(node)
        try:
            rclpy.try_shutdown()
        except RuntimeError as exc:      # rclpy's signal handler shut it down meanwhile
            if 'already called' not in str(exc):
                raise
