"""The paper's idealisation beside a real upright rig (issue 18's report section).

The real rig is Table 1 standing on a horizontal disk under gravity (the tip's weight
compresses the rod) with a steel rod of its own mass (docs/real_rig.md). Every number
is computed here, from the same functions as the rest of rotrod: the natural
frequency and stiffness, the next bending mode, the critical speed for the paper's
3 mm, and the Eq. 26 run's peak deflection.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rotrod_core.analysis.critical import critical_speed
from rotrod_core.analysis.modes import CampbellDiagram, campbell
from rotrod_core.model.params import STEEL_DENSITY, RodParams
from rotrod_core.offline.simulate import simulate

GRAVITY = 9.81
"""Standard gravity, m/s^2 (the rod stands up: compression)."""

CAMPBELL_OMEGAS = np.linspace(0.0, 15.0, 301)
"""Angular velocities of the two models' Campbell diagrams, rad/s."""


def real_rig(params: RodParams) -> RodParams:
    """``params`` upright under standard gravity with a steel rod."""
    return params.replace(gravity=GRAVITY, rod_density=STEEL_DENSITY)


@dataclass(frozen=True)
class RigSummary:
    """One model's numbers (SI units)."""

    title: str
    params: RodParams
    stiffness: float
    """Lateral tip stiffness k, N/m."""
    natural_frequency: float
    """w0 = sqrt(k / M), rad/s."""
    second_mode: float
    """The next bending mode's circular frequency, rad/s (inf: a massless rod has none)."""
    buckling_fraction: float
    """The tip load over the rod's buckling load, 1."""
    critical_speed: float
    """Quasi-static critical speed for the deflection limit, rad/s."""
    peak_deflection: float
    """Largest |r| of the profile's run from rest, m."""
    campbell: CampbellDiagram


def summarize(title: str, params: RodParams, profile, t_end: float, dt: float,
              deflection_limit: float) -> RigSummary:
    """Compute :class:`RigSummary` for ``params`` under ``profile`` (s, s, m)."""
    run = simulate(params, profile, t_end, dt=dt)
    return RigSummary(
        title=title, params=params, stiffness=float(params.stiffness),
        natural_frequency=float(params.natural_frequency),
        second_mode=float(params.second_mode_frequency),
        buckling_fraction=float(params.tip_load / params.buckling_load),
        critical_speed=float(critical_speed(params, deflection_limit)),
        peak_deflection=float(np.max(np.hypot(run.u, run.v))),
        campbell=campbell(params, CAMPBELL_OMEGAS))


__all__ = ['CAMPBELL_OMEGAS', 'GRAVITY', 'RigSummary', 'real_rig', 'summarize']
