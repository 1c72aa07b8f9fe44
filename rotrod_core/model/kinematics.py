"""The tip mass's motion in the inertial (world) frame: pose, velocity, acceleration.

The state is written in the rotating rotor frame (x radial, y tangential, z up the
rod): the mass is at p = (r0 + u, v, l) there, and that frame turns by theta about z
at w = theta', w' = the hub's angular acceleration. In the world frame (Model:
docs/model.md#eq-inertial for the position) with R(theta) the rotation about z:

* position R(theta) p;
* velocity R(theta) (u' - w v, v' + w (r0 + u), 0);
* acceleration R(theta) (u'' - 2 w v' - w' v - w^2 (r0 + u),
  v'' + 2 w u' + w' (r0 + u) - w^2 v, 0), with (u'', v'') from the equations of motion
  (:func:`rotrod_core.model.equations.deflection_accelerations`).

The mass is a point; the frame attached to it (the URDF's ``tip`` link, moved by the
prismatic joints tip_radial and tip_tangential) turns with the rotor: yaw theta,
angular velocity w and angular acceleration w' about z.
"""

from __future__ import annotations

import math
from typing import NamedTuple

from rotrod_core.model.equations import Coefficients, State, deflection_accelerations


class TipMotion(NamedTuple):
    """The tip's motion in the world frame (SI units)."""

    position: tuple[float, float, float]
    """m."""
    yaw: float
    """Rotation of the tip's frame about z, rad (the hub angle theta)."""
    velocity: tuple[float, float, float]
    """m/s."""
    angular_velocity: tuple[float, float, float]
    """rad/s: (0, 0, w)."""
    acceleration: tuple[float, float, float]
    """m/s^2."""
    angular_acceleration: tuple[float, float, float]
    """rad/s^2: (0, 0, w')."""


def tip_motion(co: Coefficients, state: State, omega_dot: float,
               rod_length: float) -> TipMotion:
    """The tip's world-frame motion at ``state``, the hub turning at w' = ``omega_dot``.

    ``omega_dot`` in rad/s^2, ``rod_length`` (the height of the mass) in m.
    """
    u, v, du, dv, theta, w = (float(x) for x in state)
    wd = float(omega_dot)
    x = float(co.eccentricity) + u
    ddu, ddv = (float(a) for a in deflection_accelerations(co, u, v, du, dv, w, wd))
    c, s = math.cos(theta), math.sin(theta)

    def world(a: float, b: float) -> tuple[float, float]:
        return a * c - b * s, a * s + b * c

    px, py = world(x, v)
    vx, vy = world(du - w * v, dv + w * x)
    ax, ay = world(ddu - 2.0 * w * dv - wd * v - w * w * x,
                   ddv + 2.0 * w * du + wd * x - w * w * v)
    return TipMotion((px, py, float(rod_length)), theta, (vx, vy, 0.0), (0.0, 0.0, w),
                     (ax, ay, 0.0), (0.0, 0.0, wd))


__all__ = ['TipMotion', 'tip_motion']
