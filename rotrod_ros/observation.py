"""What the simulator node shows of its samples besides the state.

The deflection sensor's noise, the whirl-frequency estimator over the published
motion, and the recent tip positions the markers draw as a trail: kept from one
sample to the next, made from the node's settings (:class:`NodeSettings`), remade
when a parameter they depend on changes (:meth:`Observation.reconfigure`) and started
afresh on a reset (:meth:`Observation.reset`).
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence

import numpy as np

from rotrod_core.estimation.whirl import WhirlEstimator, stream_estimator
from rotrod_core.sensors.rig import RigSensors

from .parameters import NodeSettings


def whirl_estimator(settings: NodeSettings, stagger: int = 0) -> WhirlEstimator | None:
    """Whirl-frequency estimator over the published motion (None: estimates off).

    ``stagger``: the rod's place in its world (its estimates come that many samples
    later, modulo the samples per estimate: :func:`stream_estimator`).
    """
    return stream_estimator(settings.estimate_window, settings.publish_rate,
                            settings.estimate_rate, stagger)


class Observation:
    """The sensor noise, whirl estimator and marker trail of the node's samples."""

    def __init__(self, settings: NodeSettings, stagger: int = 0, name: str = '') -> None:
        self.stagger = stagger
        self.name = name
        """The rod's place in its world: when its estimates fall (:func:`whirl_estimator`)."""
        self.estimator = whirl_estimator(settings, stagger)
        """Pushed the published (u, v); replaced, not reset in place (see :meth:`reset`)."""
        self._noise = np.random.default_rng(settings.noise_seed)
        self._trail: deque[tuple[float, ...]] = deque(
            maxlen=max(1, settings.marker_trail_length))
        self.sensors = RigSensors(settings.sensors, settings.noise_seed, name)
        """The rig's sensors (tip/imu, hub/encoder, rod/strain), their noise seeded by
        noise_seed and the rod's name."""

    def reconfigure(self, old: NodeSettings, new: NodeSettings) -> None:
        """Follow a change of settings from ``old`` to ``new``.

        A new estimator for a new window or rate, a new noise sequence for a new seed
        (the rig sensors anew for new settings of theirs or a new seed),
        the trail kept (its newest points) at a new length.
        """
        if (new.estimate_window, new.estimate_rate, new.publish_rate) != (
                old.estimate_window, old.estimate_rate, old.publish_rate):
            self.estimator = whirl_estimator(new, self.stagger)
        if new.noise_seed != old.noise_seed:
            self._noise = np.random.default_rng(new.noise_seed)
        if (new.sensors, new.noise_seed) != (old.sensors, old.noise_seed):
            self.sensors = RigSensors(new.sensors, new.noise_seed, self.name)
        if new.marker_trail_length != old.marker_trail_length:
            self._trail = deque(self._trail, maxlen=max(1, new.marker_trail_length))

    def reset(self, settings: NodeSettings, noise: bool = False) -> None:
        """Start afresh: no trail, a new estimator; with ``noise``, the noise sequence too.

        A new estimator rather than its reset in place: the physics thread may be
        pushing into the current one (its tick's snapshot) meanwhile. The noise from
        its seed again makes a full reset (ResetSimulation) replay the published
        deflection as well as the state.
        """
        self._trail.clear()
        self.estimator = whirl_estimator(settings, self.stagger)
        if noise:
            self._noise = np.random.default_rng(settings.noise_seed)
        self.sensors.reset(noise)

    def deflection(self, u: float, v: float, noise: float) -> tuple[float, float]:
        """The tip deflection (u, v) as the sensor reads it, m.

        Plus Gaussian noise of standard deviation ``noise`` m on each (0: none); the
        state is untouched.
        """
        if noise:
            du, dv = self._noise.normal(0.0, noise, 2)
            u, v = u + float(du), v + float(dv)
        return u, v

    def trail(self, tip: Sequence[float]) -> list[tuple[float, ...]]:
        """The recent drawn tip positions (m), oldest first, after adding ``tip``."""
        self._trail.append(tuple(tip))
        return list(self._trail)
