"""Programs that end when the process that started them ends, even if it is killed.

The node processes a demo, a fleet or the test harness starts run in sessions of their
own (a Ctrl-C meant for one does not reach the others), so they would outlive a starter
that dies without stopping them, at real-time priority. :func:`ending_with_this_process`
wraps a command in a small trampoline that asks Linux for ``PR_SET_PDEATHSIG`` (kept
across ``exec``) and then executes the command. A trampoline rather than a
``preexec_fn``: the starter may hold threads (rclpy's, Fast DDS's), where running
Python between fork and exec can deadlock.
"""

from __future__ import annotations

import os
import signal
import sys
from collections.abc import Sequence

_TRAMPOLINE = (
    'import ctypes, os, sys\n'
    'try:\n'
    '    ctypes.CDLL(None, use_errno=True).prctl(1, int(sys.argv[2]))  # PR_SET_PDEATHSIG\n'
    'except (OSError, AttributeError):\n'
    '    pass\n'
    'if os.getppid() != int(sys.argv[1]):  # the starter ended before the request\n'
    '    os._exit(128 + int(sys.argv[2]))\n'
    'try:\n'
    '    os.execvp(sys.argv[3], sys.argv[3:])\n'
    'except OSError as exc:\n'
    '    print(f"cannot execute {sys.argv[3]!r}: {exc}", flush=True)\n'
    '    os._exit(127)\n'
)


def ending_with_this_process(cmd: Sequence[str],
                             sig: signal.Signals = signal.SIGTERM) -> list[str]:
    """The argv that runs ``cmd`` and sends it ``sig`` when this process ends (Linux).

    Elsewhere ``cmd`` itself: nothing is asked.
    """
    if not sys.platform.startswith('linux'):
        return list(cmd)
    return [sys.executable, '-S', '-c', _TRAMPOLINE, str(os.getpid()), str(int(sig)),
            *cmd]
