"""What the simulator publishes, and how: one set of settings for every publisher of it.

The live node (``rotrod_ros.simulator``, whose ``NodeSettings`` extend these) and the
rosbag2 writer of offline runs (:mod:`rotrod_core.reporting.bag`) take the same
:class:`PublicationSettings`, with the same defaults (the node's parameter defaults)
and the same checks, and publish the same :data:`SAMPLE_TOPICS` with fields built by
:mod:`rotrod_core.model.interface`.
"""

from __future__ import annotations

from dataclasses import dataclass

from rotrod_core.live.loop import LoopSettings
from rotrod_core.model.params import DEFAULT_HUB_RADIUS
from rotrod_core.numerics.checks import finite_number

MIN_ESTIMATE_SAMPLES = 20
"""Fewest publications an estimate window may hold."""
SAMPLE_TOPICS = ('joint_states', 'tip/deflection', 'tip/position', 'frequencies',
                 'frequencies/estimate')
"""The topics published at each sample (the estimate at estimate_rate), in this order."""


@dataclass(frozen=True)
class PublicationSettings(LoopSettings):
    """The loop's settings and what its samples are published as (SI units).

    Attributes (besides :class:`~rotrod_core.live.loop.LoopSettings`'):
        marker_trail_length: trail points drawn in the markers.
        marker_deflection_scale: deflection magnification of the drawn rod, 1.
        disk_radius: radius of the hub disk as drawn, m.
        frame_prefix: prefix of the frame ids world and rotor (e.g. 'rod1/').
        estimate_window: window of the whirl estimate, s of simulated time (0: none).
        estimate_rate: estimates per second of simulated time, Hz (<= publish_rate).
    """

    marker_trail_length: int = 200
    marker_deflection_scale: float = 20.0
    disk_radius: float = DEFAULT_HUB_RADIUS
    frame_prefix: str = ''
    estimate_window: float = 1.0
    estimate_rate: float = 10.0

    def __post_init__(self):
        super().__post_init__()
        finite_number('estimate_window', self.estimate_window, nonnegative=True)
        finite_number('estimate_rate', self.estimate_rate, positive=True)
        if self.estimate_window:
            if self.estimate_window < MIN_ESTIMATE_SAMPLES * self.publish_period:
                raise ValueError(f'estimate_window {self.estimate_window:g} s holds fewer than '
                                 f'{MIN_ESTIMATE_SAMPLES} publications at publish_rate '
                                 f'{self.publish_rate:g} Hz: too few samples to estimate from')
            if self.estimate_rate > self.publish_rate:
                raise ValueError(f'estimate_rate {self.estimate_rate:g} Hz exceeds '
                                 f'publish_rate {self.publish_rate:g} Hz: estimates are made '
                                 'on publications')


__all__ = ['MIN_ESTIMATE_SAMPLES', 'PublicationSettings', 'SAMPLE_TOPICS']
