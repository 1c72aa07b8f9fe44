"""What an IMU on the tip mass reads: its frame, angular velocity and specific force.

The sensor sits on the mass, its z axis along the rod's tangent at the tip. The rod bends
in the cantilever shape (``rotrod_core.model.geometry.cantilever_shape``, s^2 (3 - s) / 2
of the tip's deflection at height s l), whose slope at the tip is TIP_SLOPE = 3/2 of the
tip's deflection over the length: s_u = 3/2 u / l toward the radial x, s_v = 3/2 v / l
toward the tangential y of the rotor frame. The sensor's frame, in the world frame, is

    R = Rz(theta) Ry(a) Rx(-b),   a = atan(s_u),  b = atan2(s_v, sqrt(1 + s_u^2))

(yaw with the hub, then the tilt), so that its z axis R e_z = (s_u, s_v, 1) / |.| is
the tangent exactly. Upright (u = v = 0) it is the rotor frame turned by theta.

- **Angular velocity** (gyroscope), in the sensor's frame: the frame's own,
  w_b = (Ry(a) Rx(-b))^T (0, 0, theta') + Rx(-b)^T (0, a', 0) + (-b', 0, 0).
- **Linear acceleration** (accelerometer), in the sensor's frame: the specific force
  R^T (a_tip - g_world), with a_tip the mass's inertial acceleration
  (``rotrod_core.model.kinematics.tip_motion``) and g_world = (0, 0, -g), g the model's
  ``gravity`` (0 in the paper): at rest and upright z reads +g.

REP 145: a 6- or 9-axis IMU publishes the specific force (gravity included) and the
angular velocity in its own frame, orientation as a quaternion of that frame in the
reference (here ``world``) frame.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from rotrod_core.model.equations import Coefficients, State
from rotrod_core.model.geometry import TIP_SLOPE, tip_tilt
from rotrod_core.model.kinematics import tip_motion


class ImuReading(NamedTuple):
    """An IMU's true reading (no noise), SI units, REP 145's conventions."""

    orientation: tuple[float, float, float, float]
    """The sensor's frame in the world frame, quaternion (x, y, z, w)."""
    angular_velocity: tuple[float, float, float]
    """rad/s, in the sensor's frame."""
    linear_acceleration: tuple[float, float, float]
    """The specific force, m/s^2, in the sensor's frame."""
    tilt: tuple[float, float]
    """(a, b), rad: the frame's tilt about the rotor's y, then about its x (as -b)."""


def _rot_x(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rot_y(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


def _rot_z(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def quaternion(rotation: np.ndarray) -> tuple[float, float, float, float]:
    """The unit quaternion (x, y, z, w), w >= 0, of a rotation matrix.

    scipy's ``Rotation.from_euler(...).as_quat(canonical=True)`` gives the same (to
    1e-16, test_imu.py) at about four times the cost (47 against 13 us): every rod's
    IMU sample will make one.
    """
    m = rotation
    trace = m[0, 0] + m[1, 1] + m[2, 2]
    if trace > 0:
        s = 2.0 * math.sqrt(1.0 + trace)
        q = ((m[2, 1] - m[1, 2]) / s, (m[0, 2] - m[2, 0]) / s, (m[1, 0] - m[0, 1]) / s, s / 4)
    elif m[0, 0] > m[1, 1] and m[0, 0] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[0, 0] - m[1, 1] - m[2, 2])
        q = (s / 4, (m[0, 1] + m[1, 0]) / s, (m[0, 2] + m[2, 0]) / s, (m[2, 1] - m[1, 2]) / s)
    elif m[1, 1] > m[2, 2]:
        s = 2.0 * math.sqrt(1.0 + m[1, 1] - m[0, 0] - m[2, 2])
        q = ((m[0, 1] + m[1, 0]) / s, s / 4, (m[1, 2] + m[2, 1]) / s, (m[0, 2] - m[2, 0]) / s)
    else:
        s = 2.0 * math.sqrt(1.0 + m[2, 2] - m[0, 0] - m[1, 1])
        q = ((m[0, 2] + m[2, 0]) / s, (m[1, 2] + m[2, 1]) / s, s / 4, (m[1, 0] - m[0, 1]) / s)
    sign = -1.0 if q[3] < 0 else 1.0
    return tuple(sign * float(c) for c in q)  # type: ignore[return-value]


def imu_reading(co: Coefficients, state: State, omega_dot: float, rod_length: float,
                gravity: float) -> ImuReading:
    """The IMU's true reading at ``state``, the hub turning at w' = ``omega_dot``.

    ``rod_length`` (m) sets the tip's slope, ``gravity`` (m/s^2, >= 0) the specific
    force's share of it.
    """
    u, v, du, dv, theta, w = (float(x) for x in state)
    a, b, da, db = tip_tilt(u, v, du, dv, rod_length)
    tilt = _rot_y(a) @ _rot_x(-b)
    frame = _rot_z(theta) @ tilt
    gyro = tilt.T @ np.array([0.0, 0.0, w]) + _rot_x(-b).T @ np.array([0.0, da, 0.0]) \
        + np.array([-db, 0.0, 0.0])
    motion = tip_motion(co, state, omega_dot, rod_length)
    force = frame.T @ (np.array(motion.acceleration) + np.array([0.0, 0.0, float(gravity)]))
    return ImuReading(quaternion(frame), tuple(float(x) for x in gyro),  # type: ignore[arg-type]
                      tuple(float(x) for x in force), (a, b))  # type: ignore[arg-type]


__all__ = ['ImuReading', 'TIP_SLOPE', 'imu_reading', 'quaternion', 'tip_tilt']
