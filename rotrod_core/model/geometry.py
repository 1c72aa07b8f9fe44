"""Where the parts are in space: the deflected rod's centreline, for drawing.

The paper's rod is massless and loaded only at its tip, so its deflected shape is the
Euler-Bernoulli cantilever under a tip force: along the rod (height z from the root,
0 <= z <= l) the deflection is the tip's times s^2 (3 - s) / 2, s = z / l. The same
shape is the assumed mode of the one-mode model of a rod with mass
(``docs/real_rig.md``); under an axial load (gravity) the true static shape differs
slightly from it, which a drawing does not show.
"""

from __future__ import annotations

import math

import numpy as np

from rotrod_core.model.params import STEEL_DENSITY, RodParams


def cantilever_shape(s):
    """Deflection along a tip-loaded cantilever relative to the tip's, at s = z / l."""
    s = np.asarray(s, dtype=float)
    return s * s * (3.0 - s) / 2.0


TIP_SLOPE = 1.5
"""The cantilever shape's slope at the tip over the tip's deflection, times l:
d/ds [s^2 (3 - s) / 2] at s = 1."""


def tip_tilt(u: float, v: float, du: float, dv: float,
             rod_length: float) -> tuple[float, float, float, float]:
    """(a, b, a', b') of the tip's tangent for deflection (u, v) m, rates (u', v') m/s.

    The tangent, (s_u, s_v, 1) with (s_u, s_v) = TIP_SLOPE (u, v) / l, is e_z turned by
    Ry(a) Rx(-b): a = atan(s_u), b = atan2(s_v, sqrt(1 + s_u^2)) (rad); a', b' rad/s.
    The frame of the mass (the IMU's, the URDF's ``tip``) is so tilted.
    """
    k = TIP_SLOPE / rod_length
    su, sv, dsu, dsv = k * u, k * v, k * du, k * dv
    h = math.sqrt(1.0 + su * su)
    a = math.atan(su)
    b = math.atan2(sv, h)
    da = dsu / (1.0 + su * su)
    dh = su * dsu / h
    db = (h * dsv - sv * dh) / (h * h + sv * sv)
    return a, b, da, db


def rod_centerline(params: RodParams, u: float, v: float, theta: float, points: int = 12,
                   scale: float = 1.0) -> np.ndarray:
    """Points (``points`` x 3, m) of the rod from root to tip in the inertial frame.

    The root stands at radius r0 on the hub at angle ``theta`` (rad); the tip is
    deflected by (u, v) m in the rotating frame, multiplied by ``scale`` (to make
    millimetres visible in a viewer; 1 = true size).
    """
    shape = rod_shapes(u, v, eccentricity=float(params.eccentricity),
                       rod_length=float(params.rod_length), points=points, scale=scale)[0]
    c, sn = np.cos(theta), np.sin(theta)
    return np.column_stack([shape[:, 0] * c - shape[:, 1] * sn,
                            shape[:, 0] * sn + shape[:, 1] * c, shape[:, 2]])


def rod_shapes(u, v, *, eccentricity: float, rod_length: float, points: int = 12,
               scale: float = 1.0) -> np.ndarray:
    """The rod from root to tip in the rotating frame, for each deflection: (N, points, 3) m.

    ``u``, ``v`` (m, scalars or N values) the tip's deflection, drawn ``scale`` times
    its size; x radial (the root at ``eccentricity`` m), y tangential, z up the rod
    (``rod_length`` m).
    """
    if points < 2:
        raise ValueError(f'points must be >= 2, got {points!r}')
    u = np.atleast_1d(np.asarray(u, dtype=float))
    v = np.atleast_1d(np.asarray(v, dtype=float))
    s = np.linspace(0.0, 1.0, points)
    shape = cantilever_shape(s) * scale
    out = np.empty((len(u), points, 3))
    out[:, :, 0] = eccentricity + u[:, None] * shape
    out[:, :, 1] = v[:, None] * shape
    out[:, :, 2] = s * rod_length
    return out


def sphere_radius(mass: float, density: float = STEEL_DENSITY) -> float:
    """Radius (m) of a solid sphere of ``mass`` kg and ``density`` kg/m^3 (steel default)."""
    return float((3.0 * mass / (4.0 * np.pi * density)) ** (1.0 / 3.0))
