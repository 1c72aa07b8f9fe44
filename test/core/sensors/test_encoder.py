"""The hub encoder: whole counts, their angle, the speed from counts within one count."""

import math

import numpy as np
import pytest

from rotrod_core.sensors.encoder import Encoder


def test_counts_are_whole_and_their_angle_an_exact_multiple_of_the_count():
    encoder = Encoder(4096, 0.01)
    q = 2 * math.pi / 4096
    for theta in np.linspace(-20.0, 20.0, 2001):
        reading = encoder.read(0.0, float(theta))
        assert isinstance(reading.counts, int)
        assert reading.angle == reading.counts * q
        assert reading.angle <= theta < reading.angle + q * (1 + 1e-12)


@pytest.mark.parametrize('omega', [0.3, 2.0, -5.0])
def test_the_speed_from_counts_is_within_one_count_over_the_window(omega):
    cpr, window, dt = 1024, 0.02, 0.001
    encoder = Encoder(cpr, window)
    q = 2 * math.pi / cpr
    speeds = []
    for k in range(2000):
        t = k * dt
        reading = encoder.read(t, 0.1 + omega * t)
        if t >= window:
            assert abs(reading.speed - omega) <= q / window * (1 + 1e-9)
            speeds.append(reading.speed)
    assert np.mean(speeds) == pytest.approx(omega, abs=q / (2000 * dt) * 2)


def test_before_a_window_the_speed_is_from_the_first_reading_and_a_reset_forgets():
    encoder = Encoder(100, 1.0)
    assert encoder.read(0.0, 0.0).speed == 0.0
    q = 2 * math.pi / 100
    assert encoder.read(0.1, 5.5 * q).speed == pytest.approx(5 * q / 0.1)
    encoder.reset()
    assert encoder.read(0.2, 9.5 * q).speed == 0.0


@pytest.mark.parametrize('cpr, window, named', [
    (0, 0.01, 'counts_per_revolution'), (-3, 0.01, 'counts_per_revolution'),
    (2.5, 0.01, 'counts_per_revolution'), (True, 0.01, 'counts_per_revolution'),
    (100, 0.0, 'window'), (100, math.nan, 'window'), (100, -1.0, 'window')])
def test_bad_encoder_settings_are_refused_naming_the_parameter(cpr, window, named):
    with pytest.raises(ValueError, match=named):
        Encoder(cpr, window)


def test_a_reading_back_in_time_or_a_nan_angle_is_refused_and_changes_nothing():
    encoder = Encoder(100, 0.1)
    encoder.read(1.0, 0.5)
    with pytest.raises(ValueError, match='go back'):
        encoder.read(0.5, 0.6)
    with pytest.raises(ValueError, match='theta'):
        encoder.read(1.1, math.nan)
    assert encoder.read(1.1, 0.5).speed == 0.0
