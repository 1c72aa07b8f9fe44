"""A rod's rig sensors together: the noise independent of who reads, each rod its own,
the encoder across a reset of time."""

import math

import numpy as np
import pytest

from rotrod_core.model.equations import Coefficients, State
from rotrod_core.model.params import RodParams
from rotrod_core.sensors.imu import imu_reading
from rotrod_core.sensors.noise import NoiseParams
from rotrod_core.sensors.rig import RigSensors, SensorConfig
from rotrod_core.sensors.strain import RootWrenchGains

L = 0.3
NOISY = SensorConfig(linear_acceleration=NoiseParams(stddev=0.1, bias_stddev=0.05),
                     angular_velocity=NoiseParams(dynamic_bias_stddev=0.2,
                                                  dynamic_bias_correlation_time=0.5),
                     strain=NoiseParams(stddev=1e-3))


def sample(k):
    return State(1e-3 * math.cos(0.3 * k), 2e-4 * math.sin(0.2 * k), 1e-3, -2e-3,
                 0.05 * k, 1.0 + 0.01 * k)


def test_without_noise_the_sensors_read_the_true_imu_wrench_and_counts():
    params = RodParams()
    co = Coefficients.from_params(params)
    sensors = RigSensors(SensorConfig(counts_per_revolution=360), seed=0)
    for k in range(5):
        state = sample(k)
        reading = sensors.read(0.01 * k, 0.01, co, params, state, 0.3)
        assert reading.imu == imu_reading(co, state, 0.3, L, 0.0)
        assert reading.wrench == RootWrenchGains.of(params).wrench(state.u, state.v)
        assert reading.encoder.counts == math.floor(state.theta / (2 * math.pi / 360))


def readings(sensors, want, n=30, encoder=lambda k: True):
    params = RodParams()
    co = Coefficients.from_params(params)
    out = []
    for k in range(n):
        r = sensors.read(0.01 * k, 0.01, co, params, sample(k), 0.0, imu=want(k),
                         strain=want(k), encoder=encoder(k))
        out.append(r)
    return out


@pytest.mark.parametrize('config', [SensorConfig(encoder_window=0.05), NOISY],
                         ids=['noise off', 'noisy'])
def test_the_encoder_counts_at_samples_nobody_reads(config):
    """Read at every third sample only (nothing else read either), the encoder gives
    there the readings of one read at every sample: its speed over the window counts
    the samples between (noise off, nobody reads: the cheap path a world's rods take)."""
    every = readings(RigSensors(config, 3, 'rod1'), lambda k: True)
    some = readings(RigSensors(config, 3, 'rod1'), lambda k: k % 3 == 0,
                    encoder=lambda k: k % 3 == 0)
    for k in range(30):
        if k % 3:
            assert some[k] == (None, None, None)
        else:
            assert some[k] == every[k]
    assert len({r.encoder.speed for r in every}) > 3        # the speeds change


def test_the_noise_does_not_depend_on_who_reads_the_imu():
    """The channels draw at every sample: an IMU and a bridge read every third sample
    give, there, the readings of ones read at every sample (the same seed and rod)."""
    every = readings(RigSensors(NOISY, 3, 'rod1'), lambda k: True)
    some = readings(RigSensors(NOISY, 3, 'rod1'), lambda k: k % 3 == 0)
    for k in range(30):
        if k % 3:
            assert some[k].imu is None and some[k].wrench is None
        else:
            assert some[k].imu == every[k].imu and some[k].wrench == every[k].wrench
        assert some[k].encoder == every[k].encoder


def test_each_rod_and_seed_has_its_own_noise_and_a_reset_replays_it():
    a = readings(RigSensors(NOISY, 3, 'rod1'), lambda k: True)
    b = readings(RigSensors(NOISY, 3, 'rod2'), lambda k: True)
    c = readings(RigSensors(NOISY, 4, 'rod1'), lambda k: True)
    accel = [np.array([r.imu.linear_acceleration for r in x]) for x in (a, b, c)]
    assert not np.array_equal(accel[0], accel[1]) and not np.array_equal(accel[0], accel[2])
    sensors = RigSensors(NOISY, 3, 'rod1')
    readings(sensors, lambda k: True)
    sensors.reset()
    assert readings(sensors, lambda k: True) == a


def test_time_going_back_starts_the_encoder_counting_anew():
    """A reset of simulated time without one of the sensors (the node resets both; a
    time-only reset) must not stop the physics: the encoder counts from there."""
    params = RodParams()
    co = Coefficients.from_params(params)
    sensors = RigSensors(SensorConfig(counts_per_revolution=100, encoder_window=0.05), 0)
    for k in range(10):
        sensors.read(0.01 * k, 0.01, co, params, sample(k), 0.0, imu=False)
    again = sensors.read(0.0, 0.01, co, params, sample(0), 0.0, imu=False)
    assert again.encoder.speed == 0.0                      # its first reading


def imu_times(config, interval, duration):
    """(time, linear acceleration) of each IMU reading over samples every ``interval`` s."""
    params = RodParams()
    co = Coefficients.from_params(params)
    sensors = RigSensors(config, 3, 'rod1')
    out = []
    for k in range(round(duration / interval)):
        t = k * interval
        r = sensors.read(t, interval, co, params, sample(round(t / 0.01)), 0.0)
        if r.imu is not None:
            out.append((round(t, 9), r.imu.linear_acceleration))
    return out


def test_the_imu_reads_at_its_own_rate_with_the_same_noise_at_any_sample_rate():
    """imu_rate 25 Hz: readings every 0.04 s, whether the samples come at 100 or 50 Hz,
    and the same readings (its noise steps by 1/imu_rate, not by the samples)."""
    config = SensorConfig(linear_acceleration=NoiseParams(
        stddev=0.1, dynamic_bias_stddev=0.2, dynamic_bias_correlation_time=0.5), imu_rate=25.0)
    fast, slow = imu_times(config, 0.01, 2.0), imu_times(config, 0.02, 2.0)
    assert [t for t, _ in fast] == [round(0.04 * k, 9) for k in range(50)]
    assert fast == slow


def test_an_imu_rate_that_does_not_divide_the_samples_keeps_its_mean_rate():
    """30 Hz from 100 Hz samples: each reading at the first sample within half an
    interval of k/30 s, so 30 readings a second, none drifting."""
    times = [t for t, _ in imu_times(SensorConfig(imu_rate=30.0), 0.01, 3.0)]
    assert len(times) == 90
    assert all(abs(t - k / 30) <= 0.005 + 1e-12 for k, t in enumerate(times))


def test_a_bad_imu_rate_is_refused_by_name():
    for bad in (-1.0, math.nan, math.inf):
        try:
            SensorConfig(imu_rate=bad)
        except ValueError as exc:
            assert 'imu_rate' in str(exc)
        else:
            raise AssertionError(f'imu_rate {bad} accepted')
