"""What an incremental encoder on the hub reads: counts, and a speed from counts.

The hub angle theta (rad) reads as the whole number of counts floor(theta / q) it has
passed, q = 2 pi / ``counts_per_revolution``, and as the angle of those counts, count q:
an exact integer multiple of q. The speed is what a drive computes from the counts: the
counts gained over the last ``window`` seconds (or since the first reading, before a
window has gone by), times q, over the time they took. Its error is at most one count
over that time, q / window, whatever the true speed.
"""

from __future__ import annotations

import math
from collections import deque
from typing import NamedTuple

from rotrod_core.numerics.checks import finite_number


class EncoderReading(NamedTuple):
    """One reading: the counts, their angle (counts x q, rad), the speed from counts (rad/s)."""

    counts: int
    angle: float
    speed: float


class Encoder:
    """An incremental encoder on the hub.

    Args:
        counts_per_revolution: counts per turn (an integer >= 1).
        window: the time its speed is taken over, s (> 0).
    """

    def __init__(self, counts_per_revolution: int, window: float) -> None:
        if (isinstance(counts_per_revolution, bool)
                or not isinstance(counts_per_revolution, int) or counts_per_revolution < 1):
            raise ValueError('counts_per_revolution must be an integer >= 1, got '
                             f'{counts_per_revolution!r}')
        self.counts_per_revolution = counts_per_revolution
        self.window = finite_number('window', window, positive=True)
        self.quantum = 2.0 * math.pi / counts_per_revolution
        """q, rad per count."""
        self._history: deque[tuple[float, int]] = deque()

    def count(self, theta: float) -> int:
        """The counts the hub angle ``theta`` (rad, finite) has passed: floor(theta / q)."""
        return math.floor(finite_number('theta', theta) / self.quantum)

    def read(self, t: float, theta: float) -> EncoderReading:
        """The reading at time ``t`` (s, not before the previous one) and angle ``theta``."""
        count = self.advance(t, theta)
        t0, count0 = self._history[0]
        t = self._history[-1][0]
        speed = (count - count0) * self.quantum / (t - t0) if t > t0 else 0.0
        return EncoderReading(count, count * self.quantum, speed)

    def advance(self, t: float, theta: float) -> int:
        """Count at time ``t`` (s) and angle ``theta`` (rad) without a reading: the counts.

        What the encoder does at a sample nobody reads: its later speeds are the same
        as if it had been read (a world's rods pay this at every sample).
        """
        if (type(t) is not float or type(theta) is not float
                or not (math.isfinite(t) and math.isfinite(theta))):
            t, theta = finite_number('t', t), finite_number('theta', theta)
        history = self._history
        if history and t < history[-1][0]:
            raise ValueError(f't must not go back: {t!r} after {history[-1][0]!r}')
        count = math.floor(theta / self.quantum)
        history.append((t, count))
        # the reference: the newest reading at or before t - window (else the oldest)
        while len(history) > 1 and history[1][0] <= t - self.window:
            history.popleft()
        return count

    @property
    def last_time(self) -> float | None:
        """Time of the latest reading, s (None: none since the start or a reset)."""
        return self._history[-1][0] if self._history else None

    def reset(self) -> None:
        """Forget the readings (a reset of the simulation)."""
        self._history.clear()


__all__ = ['Encoder', 'EncoderReading']
