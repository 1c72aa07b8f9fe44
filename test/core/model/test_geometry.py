"""The drawing geometry: the rod as a tip-loaded cantilever, the mass as a sphere."""

import math

import numpy as np
import pytest
from reference import R0, L

from rotrod_core import RodParams
from rotrod_core.model.equations import Coefficients, inertial_position
from rotrod_core.model.geometry import cantilever_shape, rod_centerline, sphere_radius


def test_the_drawn_rod_is_a_tip_loaded_cantilever_ending_at_the_mass():
    s = np.linspace(0, 1, 101)
    # Euler-Bernoulli, tip load only: w'''' = 0 (a cubic), clamped root w = w' = 0,
    # no moment at the tip w''(1) = 0, unit tip deflection w(1) = 1
    c0, c1, c2, c3 = np.polynomial.polynomial.polyfit(s, cantilever_shape(s), 4)[:4]
    assert np.polynomial.polynomial.polyfit(s, cantilever_shape(s), 4)[4] == pytest.approx(
        0, abs=1e-9)
    assert (c0, c1) == (pytest.approx(0, abs=1e-9), pytest.approx(0, abs=1e-9))
    assert 2 * c2 + 6 * c3 == pytest.approx(0, abs=1e-9)
    assert c0 + c1 + c2 + c3 == pytest.approx(1)
    p = RodParams()
    u, v, theta = 2e-3, -1e-3, 0.7
    line = rod_centerline(p, u, v, theta)
    x, y = inertial_position(Coefficients.from_params(p), u, v, theta)
    assert line[-1] == pytest.approx([x, y, L])
    assert line[0] == pytest.approx([R0 * math.cos(theta), R0 * math.sin(theta), 0])
    assert sphere_radius(4 / 3 * math.pi * 7850.0) == pytest.approx(1.0)
