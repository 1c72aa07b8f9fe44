"""The RK4 steps: fourth order against a closed form; the written-out step for a
prescribed rotation is the generic step to the bit, and exact for theta and w."""

import math
import random
from functools import partial

import rotrod_core.model.equations as model
from rotrod_core.model.equations import Coefficients
from rotrod_core.model.params import RodParams
from rotrod_core.numerics.rk4 import rk4_step, rk4_step_prescribed_rotation


def test_rk4_step_is_fourth_order_on_an_oscillator():
    """x'' = -x from (1, 0) to t = 1: the error against cos t falls 16x per halved step."""
    def rates(y, _):
        return y[1], -y[0]

    def error(n):
        y, h = (1.0, 0.0), 1.0 / n
        for _ in range(n):
            y = rk4_step(rates, y, h, None, None, None)
        return abs(y[0] - math.cos(1.0))
    ratio = error(20) / error(40)
    assert 15.0 < ratio < 17.0


def test_prescribed_rotation_step_is_the_generic_step_to_the_bit():
    co = Coefficients.from_params(RodParams(damping_ratio=0.02))
    rates = partial(model.velocity_drive_rates, co)
    accelerations = partial(model.deflection_accelerations, co)
    rng = random.Random(7)
    for _ in range(500):
        state = tuple(rng.uniform(-1, 1) * 10 ** rng.uniform(-6, 1) for _ in range(6))
        wd, h = rng.uniform(-5, 5), 10 ** rng.uniform(-5, -1)
        assert (rk4_step_prescribed_rotation(accelerations, state, h, wd)
                == rk4_step(rates, state, h, wd, wd, wd))


def test_prescribed_rotation_is_exact_for_theta_and_omega():
    """theta(h) = theta + w h + w' h^2 / 2, w(h) = w + w' h (to rounding)."""
    co = Coefficients.from_params(RodParams())
    accelerations = partial(model.deflection_accelerations, co)
    theta, w, wd, h = 0.3, 2.0, 0.5, 0.01
    out = rk4_step_prescribed_rotation(accelerations, (1e-3, 0, 0, 0, theta, w), h, wd)
    assert math.isclose(out[4], theta + w * h + 0.5 * wd * h * h, rel_tol=1e-15)
    assert math.isclose(out[5], w + wd * h, rel_tol=1e-15)
