"""Where the parts are in space: the deflected rod's centreline, for drawing.

The paper's rod is massless and loaded only at its tip, so its deflected shape is the
Euler-Bernoulli cantilever under a tip force: along the rod (height z from the root,
0 <= z <= l) the deflection is the tip's times s^2 (3 - s) / 2, s = z / l. The same
shape is the assumed mode of the one-mode model of a rod with mass
(``docs/real_rig.md``); under an axial load (gravity) the true static shape differs
slightly from it, which a drawing does not show.
"""

from __future__ import annotations

import numpy as np

from rotrod_core.model.params import STEEL_DENSITY, RodParams


def cantilever_shape(s):
    """Deflection along a tip-loaded cantilever relative to the tip's, at s = z / l."""
    s = np.asarray(s, dtype=float)
    return s * s * (3.0 - s) / 2.0


def rod_centerline(params: RodParams, u: float, v: float, theta: float, points: int = 12,
                   scale: float = 1.0) -> np.ndarray:
    """Points (``points`` x 3, m) of the rod from root to tip in the inertial frame.

    The root stands at radius r0 on the hub at angle ``theta`` (rad); the tip is
    deflected by (u, v) m in the rotating frame, multiplied by ``scale`` (to make
    millimetres visible in a viewer; 1 = true size).
    """
    if points < 2:
        raise ValueError(f'points must be >= 2, got {points!r}')
    length, r0 = float(params.rod_length), float(params.eccentricity)
    s = np.linspace(0.0, 1.0, points)
    shape = cantilever_shape(s) * scale
    radial = r0 + u * shape
    tangential = v * shape
    c, sn = np.cos(theta), np.sin(theta)
    return np.column_stack([radial * c - tangential * sn, radial * sn + tangential * c,
                            s * length])


def sphere_radius(mass: float, density: float = STEEL_DENSITY) -> float:
    """Radius (m) of a solid sphere of ``mass`` kg and ``density`` kg/m^3 (steel default)."""
    return float((3.0 * mass / (4.0 * np.pi * density)) ** (1.0 / 3.0))
