"""Events of a run as it streams in: its stages and the critical deflection (no ROS).

Stages come from the hub's angular velocity w alone, so every run has them, whatever
drove it (the paper's Figs. 5-8 are Eq. 26's spin-up, hold, spin-down and rest):

- rest: w constant and |w| <= ``omega_tol``;
- hold: w constant, not at rest;
- spin-up: |w| growing; spin-down: |w| falling.

"Constant" means |dw/dt| <= ``accel_tol`` between two samples. A new stage is taken
once it has lasted ``dwell`` s and, for a spin-up or spin-down, changed |w| by at least
``min_change`` rad/s; a shorter or smaller excursion stays in the stage it interrupts
(the angular momentum a free rotation trades with the rod's whirl is a hold). The new
stage starts at the sample before its first one (it began in between). Samples whose
stage may still change (the start of an excursion not yet decided) are "pending":
:attr:`StageTracker.decided_until`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

STAGES = ('rest', 'spin-up', 'hold', 'spin-down')
"""The stages, in the order of Eq. 26's run (which starts and ends at rest)."""
OMEGA_TOL = 1e-6
"""|w| at or below which a constant w is rest, rad/s."""
ACCEL_TOL = 1e-9
"""|dw/dt| at or below which w is constant, rad/s^2."""
DWELL = 0.2
"""How long a new stage must last before it is taken, s."""
MIN_CHANGE = 0.01
"""How much a spin-up or spin-down must change |w| to be one, rad/s."""
MAX_PENDING = 5.0
"""Longest stretch of samples left pending, s: an excursion undecided for longer stays
in the current stage (so a writer never holds more back)."""


@dataclass(frozen=True)
class Event:
    """Something a user looks for in a run, at ``time`` (s, the samples' time)."""

    time: float
    kind: str
    """'stage' (a new stage starts), 'critical' (the deflection first passes the
    critical deflection), 'peak' (the largest deflection of that first excursion)."""
    text: str
    """What happened; ``{t}`` stands for the time, which the caller writes as it shows
    time (e.g. from the profile's start)."""
    value: float
    """The value to mark: w (rad/s) for a stage, the deflection (m) otherwise."""


class StageTracker:
    """Stages of a run from its hub angular velocity, fed in batches (see module doc)."""

    def __init__(self, *, dwell: float = DWELL, omega_tol: float = OMEGA_TOL,
                 accel_tol: float = ACCEL_TOL, min_change: float = MIN_CHANGE,
                 max_pending: float = MAX_PENDING):
        self.dwell, self.omega_tol, self.accel_tol = dwell, omega_tol, accel_tol
        self.min_change, self.max_pending = min_change, max_pending
        self.starts: list[float] = []
        """Start time (s) of each stage taken, in order."""
        self.stages: list[str] = []
        """The stages taken, in order (:data:`STAGES` names)."""
        self.decided_until = -math.inf
        """Samples before this time (s) have their final stage; later ones are pending."""
        self._last: tuple[float, float] | None = None   # (t, |w|) of the last sample
        self._pending: list | None = None     # [stage, t_first, |w| before, t_last, |w| last]

    @property
    def stage(self) -> str | None:
        """The current stage (None before the first sample)."""
        return self.stages[-1] if self.stages else None

    def _take(self, stage: str, t: float, omega: float) -> Event:
        self.starts.append(t)
        self.stages.append(stage)
        return Event(t, 'stage', f'{stage} from t = {{t}}: w = {omega:.4g} rad/s', omega)

    def push(self, t, omega) -> list[Event]:
        """Add samples (t in s, increasing; w in rad/s); return the stages taken."""
        t = np.asarray(t, dtype=float)
        w = np.asarray(omega, dtype=float)
        events: list[Event] = []
        if len(t) == 0:
            return events
        if self._last is None:
            events.append(self._take('rest' if abs(w[0]) <= self.omega_tol else 'hold',
                                     float(t[0]), float(w[0])))
            self._last = (float(t[0]), abs(float(w[0])))
            t, w = t[1:], w[1:]
            if len(t) == 0:
                self.decided_until = self._last[0]
                return events
        a = np.abs(w)
        prev_t = np.concatenate(([self._last[0]], t[:-1]))
        prev_a = np.concatenate(([self._last[1]], a[:-1]))
        dt = np.maximum(t - prev_t, 1e-12)
        rate = (a - prev_a) / dt
        raw = np.where(rate > self.accel_tol, 1, np.where(rate < -self.accel_tol, 3,
                                                           np.where(a <= self.omega_tol, 0, 2)))
        bounds = np.concatenate(([0], np.flatnonzero(np.diff(raw)) + 1, [len(raw)]))
        for i, j in zip(bounds[:-1], bounds[1:]):
            stage = STAGES[int(raw[i])]
            p = self._pending
            if p is not None and p[0] == stage:
                p[3], p[4] = float(t[j - 1]), float(a[j - 1])
            else:
                p = None
                if stage != self.stage:
                    p = [stage, float(prev_t[i]), float(prev_a[i]), float(t[j - 1]),
                         float(a[j - 1])]
            self._pending = p
            if p is None:
                continue
            lasted = p[3] - p[1] >= self.dwell
            changed = stage in ('rest', 'hold') or abs(p[4] - p[2]) >= self.min_change
            if lasted and changed:
                sign = -1.0 if w[i] < 0 else 1.0
                events.append(self._take(stage, p[1], sign * p[2]))
                self._pending = None
            elif p[3] - p[1] > self.max_pending:
                self._pending = None
        self._last = (float(t[-1]), float(a[-1]))
        self.decided_until = (self._pending[1] if self._pending is not None
                              else self._last[0] + 1e-9)
        return events

    def finish(self) -> None:
        """At the end of the run: pending samples keep the current stage."""
        self._pending = None
        self.decided_until = math.inf

    def stage_index(self, t) -> np.ndarray:
        """Index into :attr:`stages` of the stage each time (s) falls in (-1: before all)."""
        return np.searchsorted(np.asarray(self.starts), np.asarray(t, dtype=float),
                               side='right') - 1


class CriticalDeflectionWatch:
    """The first time the tip's deflection passes ``limit`` (m), and that excursion's peak.

    Fed (t, u, v) in batches; the peak is known once the deflection is back within the
    limit (or at :meth:`finish`).
    """

    def __init__(self, limit: float):
        self.limit = float(limit)
        self.crossed: float | None = None
        """Time (s) of the first sample beyond the limit."""
        self.peak: tuple[float, float] | None = None
        """(time s, deflection m) of the first excursion's largest deflection, once over."""
        self._best: tuple[float, float] | None = None

    def push(self, t, u, v) -> list[Event]:
        """Add samples (t s, u and v m); return the events they complete."""
        if self.peak is not None or not (self.limit > 0):
            return []
        t = np.asarray(t, dtype=float)
        r = np.hypot(np.asarray(u, dtype=float), np.asarray(v, dtype=float))
        events: list[Event] = []
        start = 0
        if self.crossed is None:
            beyond = np.flatnonzero(r > self.limit)
            if len(beyond) == 0:
                return events
            start = int(beyond[0])
            self.crossed = float(t[start])
            events.append(Event(self.crossed, 'critical', f'deflection {1e3 * r[start]:.4g} mm '
                                f'first beyond the critical deflection {1e3 * self.limit:g} mm '
                                'at t = {t}', float(r[start])))
        within = np.flatnonzero(r[start:] <= self.limit)
        stop = start + int(within[0]) if len(within) else len(r)
        if stop > start:
            k = start + int(np.argmax(r[start:stop]))
            if self._best is None or r[k] > self._best[1]:
                self._best = (float(t[k]), float(r[k]))
        if len(within):
            events += self.finish()
        return events

    def finish(self) -> list[Event]:
        """The peak of an excursion still going on at the end (or just over)."""
        if self._best is None or self.peak is not None:
            return []
        self.peak = self._best
        return [Event(self.peak[0], 'peak', f'peak deflection {1e3 * self.peak[1]:.4g} mm '
                      f'at t = {{t}} (beyond the critical deflection '
                      f'{1e3 * self.limit:g} mm)', self.peak[1])]
