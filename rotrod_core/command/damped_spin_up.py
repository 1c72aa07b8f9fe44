"""A torque drive that spins the hub up while damping the rod's tangential vibration.

The example controller of lockstep testing (``rotrod_ros.lockstep_controller``): what a
controller under test might be, computed from what a tracker sees of the tip mass, its
position and velocity in the world frame and the hub's angle and rate.

From the tip, in the rotor frame (x radial, y tangential; the frame turns by theta at
w): the tangential deflection rate v' = y-velocity in that frame - w x (the rigid
rotation's part taken out). The hub torque

    Q = J k_w (w_target - w) + c v',   clipped to [-max_torque, max_torque],

drives w to the target at the rate k_w (1/s; J the rotor's inertia, kg m^2, so that
J k_w (w_target - w) is the torque of a first-order approach) and feeds the rod's
tangential vibration back as a damping torque (c, N s: a rod that lags, v' < 0, gets
less torque). The defaults are for Table 1's rod (J its rotor's inertia); on it, the
damping leaves far less vibration after the spin-up than c = 0 does
(test/core/command/test_damped_spin_up.py).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rotrod_core.model.equations import Coefficients
from rotrod_core.model.params import RodParams
from rotrod_core.numerics.checks import finite_number

TABLE1_ROTOR_INERTIA = float(Coefficients.from_params(RodParams()).rotor_inertia)
"""The rotor's inertia about the axis with Table 1's rod (RodParams' defaults), kg m^2."""


@dataclass(frozen=True)
class DampedSpinUp:
    """The law's constants (SI units), checked on creation.

    Attributes:
        omega_target: w to reach, rad/s.
        rate: k_w, 1/s (> 0).
        inertia: J, the rotor's inertia about the axis the law assumes, kg m^2 (> 0).
        damping: c, N s (>= 0).
        max_torque: |Q| at most, N m (> 0).
    """

    omega_target: float = 2.0
    rate: float = 1.0
    inertia: float = TABLE1_ROTOR_INERTIA
    damping: float = 2.0
    max_torque: float = 1.0

    def __post_init__(self):
        finite_number('omega_target', self.omega_target)
        for name in ('rate', 'inertia', 'max_torque'):
            finite_number(name, getattr(self, name), positive=True)
        finite_number('damping', self.damping, nonnegative=True)

    def torque(self, position: tuple, velocity: tuple, theta: float, omega: float) -> float:
        """The hub torque Q, N m.

        From the tip's world ``position`` (m) and ``velocity`` (m/s), x and y first,
        the hub angle ``theta`` (rad) and rate ``omega`` (rad/s).
        """
        c, s = math.cos(theta), math.sin(theta)
        radial = position[0] * c + position[1] * s
        tangential_velocity = -velocity[0] * s + velocity[1] * c
        deflection_rate = tangential_velocity - omega * radial
        q = (self.inertia * self.rate * (self.omega_target - omega)
             + self.damping * deflection_rate)
        return max(-self.max_torque, min(self.max_torque, q))


__all__ = ['DampedSpinUp', 'TABLE1_ROTOR_INERTIA']
