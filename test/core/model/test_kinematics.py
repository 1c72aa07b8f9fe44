"""The tip's world-frame motion (rotrod_core.model.kinematics) against its own positions.

Along a simulated trajectory (a hub torque ramp: w, w', u, v all changing), the
velocity is the central difference of the positions one step either side, and the
acceleration that of the velocities, to the difference's O(dt^2) error; the position is
the engine's inertial position; the yaw and angular rates are the hub's.
"""

import math

import pytest

from rotrod_core.live.engine import EngineConfig, SimulationEngine

DT = 1e-4


def _trajectory():
    engine = SimulationEngine(EngineConfig(drive='torque', physics_rate=1.0 / DT,
                                           initial={'u': 0.002, 'dv': 0.01}))
    engine.command_torque(0.05)
    motions = []
    for _ in range(3000):
        engine.step()
        motions.append((engine.tip_motion(), engine.inertial_position(), engine.state))
    return motions


@pytest.fixture(scope='module')
def motions():
    return _trajectory()


def test_the_position_is_the_inertial_position_and_the_frame_turns_with_the_hub(motions):
    for motion, position, state in motions[::100]:
        assert motion.position == pytest.approx(position, abs=1e-15)
        assert motion.yaw == float(state.theta)
        assert motion.angular_velocity == (0.0, 0.0, float(state.omega))


@pytest.mark.parametrize('i', [500, 1500, 2900])
def test_velocity_and_acceleration_are_the_derivatives_of_what_they_follow(motions, i):
    before, now, after = motions[i - 1][0], motions[i][0], motions[i + 1][0]
    speed = math.hypot(*now.velocity[:2])
    for k in range(3):
        dp = (after.position[k] - before.position[k]) / (2 * DT)
        assert now.velocity[k] == pytest.approx(dp, abs=1e-6 * max(1.0, speed))
        dv = (after.velocity[k] - before.velocity[k]) / (2 * DT)
        assert now.acceleration[k] == pytest.approx(dv, abs=1e-5)
    dw = (after.angular_velocity[2] - before.angular_velocity[2]) / (2 * DT)
    assert now.angular_acceleration[2] == pytest.approx(dw, rel=1e-6)
