"""What a strain-gauge bridge at the rod's root reads: the wrench the rod puts on the hub.

The rod bends in the cantilever shape (``rotrod_core.model.geometry.cantilever_shape``:
s^2 (3 - s) / 2 of the tip's deflection at height s l), whose curvature at the root is
3 u / l^2 (radial) and 3 v / l^2 (tangential). A bridge calibrated in N m reads the
section's bending moment there, E I times that curvature; it is also the moment about
the root of the force the tip mass puts on the rod, k u at height l, for the paper's
rod (k = 3 E I / l^3).

The wrench is the one the rod exerts on the hub, at the root, in the frame
``<prefix>rod_root`` (rotating with the hub: x radial, y tangential, z up along the
upright rod), SI units:

- force: the lateral force the rod carries, (k1 u, k2 v) with the model's stiffnesses
  (gravity's axial load and the rod's own weight included, as the model has them),
  and the weight it stands under, -(m + m_rod) g along z (pressing on the hub when
  g > 0);
- torque: the bending moments (-3 E I2 v / l^2, 3 E I1 u / l^2, 0): bent outward
  (u > 0), the rod turns the hub's top about +y. There is no torsion in the model.
"""

from __future__ import annotations

from typing import NamedTuple

from rotrod_core.model.params import RodParams


class RootWrench(NamedTuple):
    """The wrench the rod exerts on the hub at its root (frame rod_root)."""

    force: tuple[float, float, float]
    """N."""
    torque: tuple[float, float, float]
    """N m."""


class RootWrenchGains(NamedTuple):
    """The constants that turn a deflection into the root's wrench (one rod)."""

    shear_radial: float
    """k1, N/m."""
    shear_tangential: float
    """k2, N/m."""
    moment_radial: float
    """3 E I1 / l^2, N m per m of u."""
    moment_tangential: float
    """3 E I2 / l^2, N m per m of v."""
    axial: float
    """-(m + m_rod) g, N."""

    @classmethod
    def of(cls, params: RodParams) -> RootWrenchGains:
        """The gains of a rod (scalar parameters)."""
        length_squared = float(params.rod_length) ** 2
        e = float(params.youngs_modulus)
        weight = (float(params.mass) + float(params.rod_mass)) * float(params.gravity)
        return cls(float(params.stiffness_radial), float(params.stiffness_tangential),
                   3.0 * e * float(params.second_moment_radial) / length_squared,
                   3.0 * e * float(params.second_moment_tangential) / length_squared,
                   -weight)

    def wrench(self, u: float, v: float) -> RootWrench:
        """The wrench at the tip deflection (u, v), m (rotating frame)."""
        return RootWrench((self.shear_radial * u, self.shear_tangential * v, self.axial),
                          (-self.moment_tangential * v, self.moment_radial * u, 0.0))


__all__ = ['RootWrench', 'RootWrenchGains']
