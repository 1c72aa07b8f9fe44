"""What the rig's sensors read along an offline run: the tip IMU's horizontal axes and the
hub encoder, through rotrod_core.sensors (the exact kinematics of the tilted frame and
the quantised counts), for the identification's tests."""

import numpy as np

from rotrod_core.model.equations import Coefficients, State
from rotrod_core.sensors.encoder import Encoder
from rotrod_core.sensors.imu import imu_reading


def imu_xy(params, run) -> np.ndarray:
    """The tip IMU's x + i y (m/s^2) at each sample of ``run`` (a SimulationResult)."""
    co = Coefficients.from_params(params)
    out = np.empty(len(run.t), dtype=complex)
    for k in range(len(run.t)):
        state = State(run.u[k], run.v[k], run.du[k], run.dv[k], run.theta[k], run.omega[k])
        x, y, _ = imu_reading(co, state, run.omega_dot[k], float(params.rod_length),
                              float(params.gravity)).linear_acceleration
        out[k] = x + 1j * y
    return out


def encoder_angles(run, counts_per_revolution: int = 4096, window: float = 0.1):
    """The hub encoder's (angle, speed) at each sample of ``run``: rad, rad/s."""
    encoder = Encoder(counts_per_revolution, window)
    readings = [encoder.read(float(t), float(theta)) for t, theta in zip(run.t, run.theta)]
    return (np.array([r.angle for r in readings]), np.array([r.speed for r in readings]))
