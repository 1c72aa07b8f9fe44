"""The tip IMU against closed forms: rigid rotation, rest, the frame's own rates."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from rotrod_core.analysis.modes import static_deflection
from rotrod_core.model.equations import Coefficients, State, deflection_accelerations
from rotrod_core.model.geometry import cantilever_shape
from rotrod_core.model.params import RodParams
from rotrod_core.sensors.imu import TIP_SLOPE, imu_reading, quaternion, tip_tilt

G = 9.81


def rotation(q):
    """The rotation matrix of quaternion (x, y, z, w), by scipy (an independent code)."""
    return Rotation.from_quat(q).as_matrix()


def test_the_tip_slope_is_the_cantilever_shapes():
    h = 1e-6
    slope = (cantilever_shape(1.0 + h) - cantilever_shape(1.0 - h)) / (2 * h)
    assert TIP_SLOPE == pytest.approx(float(slope), rel=1e-9)


@pytest.mark.parametrize('gravity', [0.0, G])
@pytest.mark.parametrize('omega', [0.5, 2.0, -1.5])
def test_in_rigid_rotation_the_imu_reads_the_centripetal_force_and_the_tilted_spin(
        gravity, omega):
    """Constant w, the rod at its static deflection: the specific force is w^2 (r0 + u)
    toward the axis plus gravity, both seen in the frame tilted by the tip's slope a;
    the gyroscope reads the spin w about the tilted axes (the issue's 1e-6)."""
    params = RodParams(gravity=gravity)
    co = Coefficients.from_params(params)
    u, _ = static_deflection(params, omega)
    theta = 0.7
    state = State(u, 0.0, 0.0, 0.0, theta, omega)
    ddu, ddv = deflection_accelerations(co, u, 0.0, 0.0, 0.0, omega, 0.0)
    r = float(params.eccentricity) + u
    assert abs(ddu) < 1e-9 * omega ** 2 * r and ddv == 0.0    # at rest in the rotor
    reading = imu_reading(co, state, 0.0, float(params.rod_length), gravity)
    a = math.atan(TIP_SLOPE * u / float(params.rod_length))
    assert reading.tilt == (pytest.approx(a, rel=1e-12), 0.0)
    centripetal = -omega ** 2 * r
    force = (centripetal * math.cos(a) - gravity * math.sin(a), 0.0,
             centripetal * math.sin(a) + gravity * math.cos(a))
    scale = math.hypot(centripetal, gravity)
    assert np.allclose(reading.linear_acceleration, force, rtol=0, atol=1e-6 * scale)
    gyro = (-omega * math.sin(a), 0.0, omega * math.cos(a))
    assert np.allclose(reading.angular_velocity, gyro, rtol=0, atol=1e-6 * abs(omega))
    # the frame's z axis is the rod's tangent at the tip, turned with the hub
    z_axis = rotation(reading.orientation)[:, 2]
    tangent = np.array([TIP_SLOPE * u / float(params.rod_length), 0.0, 1.0])
    tangent = tangent / np.linalg.norm(tangent)
    c, s = math.cos(theta), math.sin(theta)
    assert np.allclose(z_axis, [c * tangent[0], s * tangent[0], tangent[2]], atol=1e-12)


def test_at_rest_and_upright_the_accelerometer_reads_plus_g_on_z():
    params = RodParams(gravity=G)
    co = Coefficients.from_params(params)
    reading = imu_reading(co, State(0.0, 0.0, 0.0, 0.0, 1.2, 0.0), 0.0,
                          float(params.rod_length), G)
    assert reading.linear_acceleration == pytest.approx((0.0, 0.0, G), abs=1e-15)
    assert reading.angular_velocity == (0.0, 0.0, 0.0)
    assert reading.orientation == pytest.approx((0.0, 0.0, math.sin(0.6), math.cos(0.6)))


def test_the_gyroscope_reads_the_sensor_frames_own_rotation():
    """Skew(w_b) = R^T dR/dt, dR/dt by central differences along the state's rates."""
    params = RodParams()
    co = Coefficients.from_params(params)
    length = float(params.rod_length)
    u, v, du, dv, theta, w = 4e-3, -2.5e-3, 0.03, 0.05, 0.3, 1.7
    reading = imu_reading(co, State(u, v, du, dv, theta, w), 0.4, length, 0.0)
    h = 1e-6

    def frame(t):
        return rotation(imu_reading(co, State(u + du * t, v + dv * t, du, dv, theta + w * t,
                                              w), 0.4, length, 0.0).orientation)
    derivative = (frame(h) - frame(-h)) / (2 * h)
    skew = frame(0.0).T @ derivative
    measured = (skew[2, 1], skew[0, 2], skew[1, 0])
    assert np.allclose(measured, reading.angular_velocity, rtol=0, atol=1e-6 * w)
    a, b, da, db = tip_tilt(u, v, du, dv, length)
    assert reading.tilt == (a, b) and da > 0 and db > 0


def test_a_quaternion_is_scipys_of_the_same_rotation():
    rng = np.random.default_rng(3)
    for angles in rng.uniform(-3.0, 3.0, size=(50, 3)):
        reference = Rotation.from_euler('ZYX', angles)
        q = quaternion(reference.as_matrix())
        assert q == pytest.approx(tuple(reference.as_quat(canonical=True)), abs=1e-12)
