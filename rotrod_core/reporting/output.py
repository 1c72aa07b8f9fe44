"""Output directory checks and progress lines for the long commands (reproduce, analyze, sweep)."""

from __future__ import annotations

import math
import os
import sys
import tempfile
import time
from contextlib import contextmanager
from pathlib import Path


class OutputDirectoryError(ValueError):
    """The output directory cannot be created or written to."""


def prepare_output_dir(path) -> Path:
    """Create ``path`` (with parents) and check that a file can be written in it.

    Raises :class:`OutputDirectoryError` with the reason, before any work is done.
    """
    out = Path(path)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputDirectoryError(
            f'cannot create the output directory {str(out)!r}: {exc.strerror or exc}') from None
    if not out.is_dir():
        raise OutputDirectoryError(f'the output path {str(out)!r} is not a directory')
    try:
        fd, probe = tempfile.mkstemp(prefix='.rotrod-write-test-', dir=out)
        os.close(fd)
        os.unlink(probe)
    except OSError as exc:
        raise OutputDirectoryError(
            f'cannot write to the output directory {str(out)!r}: {exc.strerror or exc}') from None
    return out


class Progress:
    """Numbered progress lines on a stream (stderr by default), with elapsed times.

    ``with progress.step('text'):`` prints ``[name 2/7] text ...`` and, at the end,
    the seconds it took; :meth:`note` prints an indented line at most every
    ``min_interval`` seconds (for counters inside a long step).
    """

    def __init__(self, name: str, total: int, stream=None, min_interval: float = 2.0):
        self.name = name
        self.total = total
        self.stream = sys.stderr if stream is None else stream
        self.min_interval = min_interval
        self.done = 0
        self.started = time.perf_counter()
        self._last_note = 0.0

    def _print(self, text: str) -> None:
        print(text, file=self.stream, flush=True)

    @contextmanager
    def step(self, text: str):
        """Announce one numbered step; report its duration when it ends."""
        self.done += 1
        self._print(f'[{self.name} {self.done}/{self.total}] {text} ...')
        t0 = time.perf_counter()
        self._last_note = t0
        yield self
        self._print(f'    done in {time.perf_counter() - t0:.1f} s')

    def note(self, text: str, force: bool = False) -> None:
        """An indented progress line, rate-limited to one per ``min_interval`` seconds."""
        now = time.perf_counter()
        if force or now - self._last_note >= self.min_interval:
            self._last_note = now
            self._print(f'    {text}')

    def finish(self, text: str) -> None:
        """The closing line, with the total elapsed time."""
        self._print(f'[{self.name}] {text} ({time.perf_counter() - self.started:.1f} s)')


class ProgressBar:
    """A one-line progress bar on a stream (stderr by default): runs done, rate, time left.

    On a terminal the line is redrawn in place; otherwise a line is printed at most
    every ``min_interval`` seconds, and at the end.
    """

    def __init__(self, name: str, total: int, stream=None, width: int = 30,
                 min_interval: float = 2.0):
        self.name, self.total, self.width = name, max(0, int(total)), width
        self.stream = sys.stderr if stream is None else stream
        self.min_interval = min_interval
        self.tty = bool(getattr(self.stream, 'isatty', lambda: False)())
        self.started = time.perf_counter()
        self._last = -math.inf
        self.done = self.problems = 0

    def line(self) -> str:
        """The bar's text for the current counts."""
        elapsed = time.perf_counter() - self.started
        frac = self.done / self.total if self.total else 1.0
        filled = int(round(self.width * frac))
        rate = self.done / elapsed if elapsed > 0 else 0.0
        left = (self.total - self.done) / rate if rate > 0 else math.inf
        eta = f'{left:.0f} s left' if math.isfinite(left) else 'time left unknown'
        bad = f', {self.problems} without result' if self.problems else ''
        return (f'[{self.name}] |{"#" * filled}{"." * (self.width - filled)}| '
                f'{100 * frac:5.1f} % {self.done}/{self.total} runs, {rate:.0f} runs/s, '
                f'{eta}{bad}')

    def update(self, done: int, problems: int = 0) -> None:
        """Add ``done`` finished runs (``problems`` of them without a result)."""
        self.done += done
        self.problems += problems
        now = time.perf_counter()
        last = self.done >= self.total
        if self.tty:
            print('\r' + self.line(), end='\n' if last else '', file=self.stream, flush=True)
        elif last or now - self._last >= self.min_interval:
            self._last = now
            print(self.line(), file=self.stream, flush=True)
