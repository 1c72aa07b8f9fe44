"""The lockstep example's control law, closed around the engine (no ROS, no clock).

Fed what GetEntityState gives (the tip's world motion), every 10 steps of 1 ms: the
hub approaches the target (a first-order approach at k_w), the damping feedback leaves
less tangential vibration after the spin-up than none, and the torque stays within
its bound. The same run twice is the same, float for float.
"""

import math

import pytest

from rotrod_core.command.damped_spin_up import DampedSpinUp
from rotrod_core.live.engine import EngineConfig, SimulationEngine


def closed_loop(law: DampedSpinUp, seconds: float = 6.0, steps: int = 10):
    engine = SimulationEngine(EngineConfig(drive='torque'))
    torques, late = [], 0.0
    while engine.time < seconds - 1e-9:
        m = engine.tip_motion()
        q = law.torque(m.position, m.velocity, m.yaw, m.angular_velocity[2])
        torques.append(q)
        engine.command_torque(q)
        engine.advance(steps)
        if engine.time > seconds - 1.0:
            late = max(late, abs(float(engine.state.v)))
    return engine.state, torques, late


def test_the_hub_reaches_the_target_and_the_damping_takes_the_vibration_out():
    law = DampedSpinUp()
    state, torques, late = closed_loop(law)
    assert float(state.omega) == pytest.approx(law.omega_target, rel=0.01)
    assert max(abs(q) for q in torques) <= law.max_torque
    _, _, undamped = closed_loop(DampedSpinUp(damping=0.0))
    assert late < 0.1 * undamped


def test_the_same_loop_twice_is_the_same_float_for_float():
    assert closed_loop(DampedSpinUp(), seconds=1.0)[:2] == closed_loop(DampedSpinUp(),
                                                                      seconds=1.0)[:2]


def test_the_law_is_a_first_order_approach_on_a_rigid_rotation():
    law = DampedSpinUp(omega_target=3.0, rate=2.0, inertia=0.5, damping=1.0, max_torque=10.0)
    theta, w, r = 0.7, 1.0, 0.1
    position = (r * math.cos(theta), r * math.sin(theta))
    velocity = (-w * position[1], w * position[0])            # no deflection rate
    assert law.torque(position, velocity, theta, w) == pytest.approx(0.5 * 2.0 * 2.0)
    with pytest.raises(ValueError):
        DampedSpinUp(rate=0.0)
