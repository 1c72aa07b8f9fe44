"""Mapping between wall-clock time and simulated time (no ROS import).

The simulator integrates in whole fixed steps up to "now": :class:`Pacer` says what
simulated time "now" is at a real-time factor, and when (in wall time) a given
simulated instant is due. Re-anchoring after a pause, a halt or a change of the
factor keeps the mapping continuous. :class:`StampClock` gives the time written in
message stamps and on /clock.
"""

from __future__ import annotations

import math


class Pacer:
    """Simulated time = ``sim0 + factor * (wall - wall0)``; factor 0 means unpaced.

    Times in seconds; ``wall`` is a monotonic clock reading.
    """

    def __init__(self, factor: float, sim: float, wall: float):
        self.anchor(factor, sim, wall)

    def anchor(self, factor: float, sim: float, wall: float) -> None:
        """Start the mapping afresh: simulated time ``sim`` at wall time ``wall``."""
        if not (math.isfinite(factor) and factor >= 0):
            raise ValueError(f'real-time factor must be finite and >= 0, got {factor!r}')
        self.factor, self.sim0, self.wall0 = float(factor), float(sim), float(wall)

    @property
    def paced(self) -> bool:
        """False when running as fast as possible (factor 0)."""
        return self.factor > 0

    def sim_time(self, wall: float) -> float:
        """Simulated time that is due at wall time ``wall``."""
        if not self.paced:
            raise ValueError('an unpaced run has no simulated time for a wall time')
        return self.sim0 + self.factor * (wall - self.wall0)

    def wall_time(self, sim: float) -> float:
        """Wall time at which simulated time ``sim`` is due."""
        if not self.paced:
            raise ValueError('an unpaced run has no wall time for a simulated time')
        return self.wall0 + (sim - self.sim0) / self.factor


class StampClock:
    """Time for stamps and /clock: ``origin + simulated time``, never going back.

    In real time without /clock (factor 1) the origin is the epoch time at which
    simulated time was 0, so stamps are wall-clock times; :meth:`follow_wall` moves the
    origin forward after the simulation stood still (pause, halt). With /clock the
    origin stays put, so /clock is simulated time itself.
    """

    def __init__(self, origin: float = 0.0):
        self.origin = float(origin)

    def stamp(self, sim: float) -> float:
        """Stamp time (s) of simulated time ``sim``."""
        return self.origin + sim

    def follow_wall(self, sim: float, epoch: float) -> None:
        """Make simulated time ``sim`` stamp as epoch time ``epoch`` (only forwards)."""
        self.origin = max(self.origin, epoch - sim)
