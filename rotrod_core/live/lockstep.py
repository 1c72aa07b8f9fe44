"""Steps asked of a paused simulation (lockstep): the request, its outcome, the reasons.

A host (the simulator node's StepSimulation and SimulateSteps) makes a
:class:`StepRequest` and hands it to
:meth:`rotrod_core.live.loop.RealTimeLoop.request_steps`, whose docstring states the
rule by which the loop's thread serves it; the loop reports a :class:`StepOutcome`
through the request. No ROS import.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple


class StepOutcome(NamedTuple):
    """How a :class:`StepRequest` ended."""

    completed: int
    """Steps taken."""
    problem: str | None
    """None when every step was taken; else why not (see the STEPS_* reasons)."""


STEPS_NOT_PAUSED = 'the simulation is not paused'
STEPS_CANCELLED = 'cancelled'
STEPS_STOPPING = 'the simulator is stopping'
STEPS_HALTED = 'halted'
STEPS_INTERRUPTED = 'interrupted by a reset or a play'
"""The reasons a :class:`StepRequest` ends early (the halt's text follows STEPS_HALTED)."""


class StepRequest:
    """Steps asked for while paused; served by the loop's thread (lockstep).

    Args:
        steps: how many physics steps of 1/physics_rate, >= 1.
        done: called once in the loop's thread with a :class:`StepOutcome`.
        progress: called in the loop's thread as ``progress(completed, remaining)``
            after each run of steps up to a publication instant (every
            physics_rate/publish_rate steps) that leaves steps to take.
        cancelled: polled in the loop's thread before each period's steps; true ends
            the request there (:data:`STEPS_CANCELLED`).
    """

    def __init__(self, steps: int, done: Callable[[StepOutcome], None], *,
                 progress: Callable[[int, int], None] | None = None,
                 cancelled: Callable[[], bool] | None = None):
        if isinstance(steps, bool) or not isinstance(steps, int) or steps < 1:
            raise ValueError(f'steps must be a whole number >= 1, got {steps!r}')
        self.steps = steps
        self._done = done
        self._progress = progress or (lambda completed, remaining: None)
        self._cancelled = cancelled or (lambda: False)

    def finish(self, completed: int, problem: str | None) -> None:
        """Report how the request ended (once)."""
        self._done(StepOutcome(completed, problem))


__all__ = ['STEPS_CANCELLED', 'STEPS_HALTED', 'STEPS_INTERRUPTED', 'STEPS_NOT_PAUSED',
           'STEPS_STOPPING',
           'StepOutcome', 'StepRequest']
