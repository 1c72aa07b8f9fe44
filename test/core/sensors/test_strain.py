"""The strain bridge at the rod's root against the cantilever's closed forms."""

import math

import pytest

from rotrod_core.model.params import RodParams
from rotrod_core.sensors.strain import RootWrenchGains

M, L, D, E = 0.3, 0.3, 0.003, 100e9
I_AREA = math.pi * D**4 / 64
K = 3 * E * I_AREA / L**3


def test_the_root_wrench_of_table_1_is_the_cantilevers_shear_and_moment():
    """Table 1's rod (k = 3 E I / l^3, no gravity, massless): shear k (u, v), moment
    3 E I / l^2 (u about y, -v about x) = k l u, the tip force's moment about the root."""
    gains = RootWrenchGains.of(RodParams())
    u, v = 2.5e-3, -0.7e-3
    wrench = gains.wrench(u, v)
    assert wrench.force == (pytest.approx(K * u, rel=1e-12), pytest.approx(K * v, rel=1e-12),
                            0.0)
    assert wrench.torque == (pytest.approx(-K * L * v, rel=1e-12),
                             pytest.approx(K * L * u, rel=1e-12), 0.0)


def test_under_gravity_with_a_rod_mass_the_root_carries_both_weights():
    params = RodParams(gravity=9.81, rod_density=7850.0)
    rod_mass = 7850.0 * math.pi * D**2 / 4 * L
    wrench = RootWrenchGains.of(params).wrench(0.0, 0.0)
    assert wrench.force[2] == pytest.approx(-(M + rod_mass) * 9.81, rel=1e-12)
    # the bending moment is the curvature's, E I 3 u / l^2, whatever the axial load
    assert RootWrenchGains.of(params).wrench(1e-3, 0).torque[1] == pytest.approx(
        3 * E * I_AREA * 1e-3 / L**2, rel=1e-12)
