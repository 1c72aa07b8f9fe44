"""A rod's rig sensors together: the tip IMU, the hub encoder, the root strain bridge.

:class:`RigSensors` reads one rod's sample (state, hub angular acceleration) as the
sensors of a real rig do, with their noise (:mod:`rotrod_core.sensors.noise`) on each
channel:

- ``imu.linear_acceleration.{x,y,z}`` (m/s^2) and ``imu.angular_velocity.{x,y,z}``
  (rad/s): the IMU on the tip mass (:mod:`rotrod_core.sensors.imu`);
- ``strain.torque.{x,y}`` (N m): the bridge's two bending moments at the root
  (:mod:`rotrod_core.sensors.strain`; its forces are given without noise);
- the encoder's counts are exact (quantised, :mod:`rotrod_core.sensors.encoder`).

Every channel draws from its own random stream, seeded by (seed, the rod's name, the
channel's key), and draws at every sample whether or not its reading is wanted: the
same seed replays every sensor bit for bit, whoever subscribes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import NamedTuple

from rotrod_core.model.equations import Coefficients, State
from rotrod_core.model.params import RodParams

from .encoder import Encoder, EncoderReading
from .imu import ImuReading, imu_reading
from .noise import NoiseChannel, NoiseParams
from .strain import RootWrench, RootWrenchGains

AXES = ('x', 'y', 'z')
IMU_CHANNELS = ('linear_acceleration', 'angular_velocity')
STRAIN_AXES = ('x', 'y')
"""The strain bridge's noisy channels: the two bending moments."""


@dataclass(frozen=True)
class SensorConfig:
    """The rig sensors' settings (SI units).

    Attributes:
        linear_acceleration, angular_velocity: the IMU's noise, on each axis.
        strain: the bending moments' noise (N m), on each.
        counts_per_revolution: the encoder's counts per turn (an integer >= 1).
        encoder_window: the time the encoder's speed is taken over, s (> 0).
        orientation: whether the IMU gives its orientation (False: a 6-axis IMU, the
            orientation marked not provided).
        imu_rate: the IMU's readings per second of simulated time, Hz (>= 0; 0: at
            every sample). It reads at the samples: the first, then the first sample at
            k/imu_rate after it (within half a sample's interval): imu_rate on average.
            Its noise steps by 1/imu_rate, whatever the samples' rate.
    """

    linear_acceleration: NoiseParams = field(default_factory=NoiseParams)
    angular_velocity: NoiseParams = field(default_factory=NoiseParams)
    strain: NoiseParams = field(default_factory=NoiseParams)
    counts_per_revolution: int = 4096
    encoder_window: float = 0.1
    orientation: bool = True
    imu_rate: float = 0.0

    def __post_init__(self) -> None:
        Encoder(self.counts_per_revolution, self.encoder_window)     # ValueError if bad
        if not (math.isfinite(self.imu_rate) and self.imu_rate >= 0):
            raise ValueError(f'imu_rate must be a finite rate >= 0 Hz (0: every sample), '
                             f'got {self.imu_rate!r}')


class RigReading(NamedTuple):
    """What the rig's sensors read at one sample."""

    imu: ImuReading | None
    """None when it was not asked for, or the IMU does not read at this sample
    (``imu_rate``)."""
    encoder: EncoderReading | None
    """None when it was not asked for."""
    wrench: RootWrench | None
    """None when it was not asked for."""


class RigSensors:
    """One rod's rig sensors over a run.

    Args:
        config: their settings.
        seed: the run's noise seed (an integer >= 0).
        name: the rod's name in its world (each rod its own noise).
    """

    def __init__(self, config: SensorConfig, seed: int, name: str = '') -> None:
        self.config = config
        self.encoder = Encoder(config.counts_per_revolution, config.encoder_window)
        self._imu = [[NoiseChannel(getattr(config, kind), seed, f'{name}/imu.{kind}.{axis}')
                      for axis in AXES] for kind in IMU_CHANNELS]
        self._strain = [NoiseChannel(config.strain, seed, f'{name}/strain.torque.{axis}')
                        for axis in STRAIN_AXES]
        self._gains: tuple[RodParams, RootWrenchGains] | None = None
        self._imu_due: float | None = None      # simulated time of the IMU's next reading
        self._quiet = all(p.off for p in (config.linear_acceleration, config.angular_velocity,
                                          config.strain))
        """No channel draws noise: a sample nobody reads only counts the encoder."""

    def reset(self, noise: bool = True) -> None:
        """Forget the encoder's counts (the hub may jump).

        With ``noise``, every channel's bias and sequence start again too (the run
        starts again).
        """
        if noise:
            for channel in (*self._imu[0], *self._imu[1], *self._strain):
                channel.reset()
        self.encoder.reset()
        self._imu_due = None

    def _imu_step(self, t: float, dt: float) -> float | None:
        """The IMU's noise step at the sample at ``t`` (s), or None: it does not read.

        The step of its dynamic bias is ``dt`` at every sample, else 1/imu_rate (s).

        Its instants are k/imu_rate from its first reading; it reads at the first sample
        within half a sample's interval ``dt`` of each, so the mean rate is imu_rate.
        """
        rate, due = self.config.imu_rate, self._imu_due
        if not rate:
            return dt
        if due is None or t < due - 1.0 / rate:     # the first reading, or time went back
            self._imu_due = t + 1.0 / rate
            return 1.0 / rate
        if t < due - 0.5 * dt:
            return None
        while due <= t + 0.5 * dt:
            due += 1.0 / rate
        self._imu_due = due
        return 1.0 / rate

    def _wrench_gains(self, params: RodParams) -> RootWrenchGains:
        if self._gains is None or self._gains[0] is not params:
            self._gains = (params, RootWrenchGains.of(params))
        return self._gains[1]

    def read(self, t: float, dt: float, co: Coefficients, params: RodParams, state: State,
             omega_dot: float, *, imu: bool = True, strain: bool = True,
             encoder: bool = True) -> RigReading:
        """The sensors' reading of the sample at simulated time ``t`` (s).

        ``dt``: s since the previous sample (the dynamic biases' step); ``co``,
        ``params``: the rod's; ``state``, ``omega_dot`` (rad/s^2): the sample's. Without
        ``imu`` (nobody reads it) the IMU's reading is None, without ``strain`` the
        wrench, their channels drawing their noise all the same; without ``encoder`` its
        reading is None, the encoder counting all the same. The IMU reads (and draws)
        only at its own instants (``imu_rate``).
        """
        if not (imu or strain or encoder) and self._quiet:
            # nobody reads and no channel draws: what is left is the IMU's schedule and
            # the encoder's counts (a world's rods pay this at every sample)
            self._imu_step(t, dt)
            self._count(t, state)
            return _UNREAD
        accel, gyro = self._imu
        imu_dt = self._imu_step(t, dt)
        reading: ImuReading | None = None
        if imu and imu_dt is not None:
            true = imu_reading(co, state, omega_dot, float(params.rod_length),
                               float(params.gravity))
            ax, ay, az = (c.apply(x, imu_dt) for c, x in zip(accel, true.linear_acceleration))
            gx, gy, gz = (c.apply(x, imu_dt) for c, x in zip(gyro, true.angular_velocity))
            reading = true._replace(linear_acceleration=(ax, ay, az),
                                    angular_velocity=(gx, gy, gz))
        elif imu_dt is not None:
            if not (self.config.linear_acceleration.off and self.config.angular_velocity.off):
                for c in (*accel, *gyro):
                    c.apply(0.0, imu_dt)
        if strain:
            true_wrench = self._wrench_gains(params).wrench(float(state.u), float(state.v))
            mx, my = (c.apply(x, dt) for c, x in zip(self._strain, true_wrench.torque[:2]))
            wrench: RootWrench | None = true_wrench._replace(torque=(mx, my, 0.0))
        else:
            wrench = None
            if not self.config.strain.off:
                for c in self._strain:
                    c.apply(0.0, dt)
        if not encoder:
            self._count(t, state)
            return RigReading(reading, None, wrench)
        self._rewind(t)
        return RigReading(reading, self.encoder.read(t, float(state.theta)), wrench)

    def _rewind(self, t: float) -> None:
        """Time went back before ``t`` (s), a reset: the encoder counts anew."""
        last = self.encoder.last_time
        if last is not None and t < last:
            self.encoder.reset()

    def _count(self, t: float, state: State) -> None:
        """The encoder counts the sample's angle; nobody reads it."""
        self._rewind(t)
        self.encoder.advance(t, float(state.theta))


_UNREAD = RigReading(None, None, None)


__all__ = ['AXES', 'RigReading', 'RigSensors', 'SensorConfig']
