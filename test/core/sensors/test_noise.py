"""Sensor noise against its own statistics: SDF's parameters, Gazebo's process."""

import math

import numpy as np
import pytest

from rotrod_core.sensors.noise import NoiseChannel, NoiseParams, quantize

N = 10_000
"""Samples per statistic (issue #37: over 10,000 samples)."""


def read(params: NoiseParams, value: float = 1.0, dt: float = 0.01, seed: int = 7,
         key: str = 'a', n: int = N) -> np.ndarray:
    channel = NoiseChannel(params, seed, key)
    return np.array([channel.apply(value, dt) for _ in range(n)])


def test_no_noise_reads_the_true_value_exactly():
    for params in (NoiseParams(), NoiseParams(type='none', stddev=1.0, bias_mean=2.0)):
        assert params.off
        assert np.array_equal(read(params, value=0.1234, n=100), np.full(100, 0.1234))
    nan = NoiseChannel(NoiseParams(stddev=0.1), 0, 'a').apply(math.nan, 0.01)
    assert math.isnan(nan)


def test_the_variance_about_the_bias_is_the_readings_variance_and_zero_when_off():
    """NoiseParams.variance (what tip/imu's covariance reports) against the readings: a
    run's white noise, stationary dynamic bias and rounding together (its dynamic bias
    started stationary: the mean of many runs' variances); 0 for type none."""
    params = NoiseParams(type='gaussian_quantized', stddev=0.1, dynamic_bias_stddev=0.4,
                         dynamic_bias_correlation_time=0.02, precision=0.2)
    expected = 0.1**2 + (0.4 * math.sqrt(0.01)) ** 2 + 0.2**2 / 12
    assert params.variance == pytest.approx(expected, rel=1e-12)
    y = read(params, value=0.0, dt=0.01)            # 10,000 samples, 5,000 bias times
    assert np.var(y) == pytest.approx(expected, rel=0.1)
    assert NoiseParams(type='none', stddev=1.0, precision=0.5).variance == 0.0
    assert NoiseParams().variance == 0.0


def test_white_noise_has_the_mean_and_standard_deviation_asked():
    y = read(NoiseParams(mean=0.05, stddev=0.2))
    assert np.std(y) == pytest.approx(0.2, rel=0.03)                # the 3 %
    assert abs(np.mean(y) - 1.05) < 4 * 0.2 / math.sqrt(N)
    lag1 = np.corrcoef(y[:-1], y[1:])[0, 1]
    assert abs(lag1) < 4 / math.sqrt(N)                             # independent samples


def test_the_bias_is_drawn_once_and_constant_within_a_run_of_either_sign():
    params = NoiseParams(bias_mean=0.5, bias_stddev=0.1)
    biases = []
    for seed in range(400):
        y = read(params, value=1.0, seed=seed, n=50)
        assert np.all(y == y[0])                                    # constant in the run
        biases.append(y[0] - 1.0)
    biases = np.array(biases)
    # |bias| ~ N(0.5, 0.1) folded: mean 0.5, std 0.1; signs half and half
    assert np.mean(np.abs(biases)) == pytest.approx(0.5, abs=4 * 0.1 / math.sqrt(400))
    assert np.std(np.abs(biases)) == pytest.approx(0.1, rel=0.15)
    assert 0.4 < np.mean(biases > 0) < 0.6


def test_the_dynamic_bias_is_gauss_markov_with_the_correlation_time_asked():
    sigma, tau, dt = 0.3, 0.05, 0.01
    params = NoiseParams(dynamic_bias_stddev=sigma, dynamic_bias_correlation_time=tau)
    b = read(params, value=0.0, dt=dt)
    # the stationary standard deviation sigma sqrt(tau / 2) (Gazebo's driving density)
    assert params.dynamic_bias_std == pytest.approx(sigma * math.sqrt(tau / 2), rel=1e-15)
    assert np.std(b) == pytest.approx(params.dynamic_bias_std, rel=0.05)
    # autocorrelation exp(-lag / tau): the time it gives at lags of 1 and 3 samples
    b = b - np.mean(b)
    for lag in (1, 3):
        rho = np.dot(b[:-lag], b[lag:]) / np.dot(b, b)
        assert -lag * dt / math.log(rho) == pytest.approx(tau, rel=0.10)   # the 10 %


def test_gaussian_quantized_outputs_are_whole_multiples_of_the_precision():
    precision = 0.01
    y = read(NoiseParams(type='gaussian_quantized', stddev=0.05, precision=precision),
             value=0.123456)
    steps = y / precision
    assert np.max(np.abs(steps - np.round(steps))) < 1e-9
    assert len(np.unique(np.round(steps))) > 10                     # the noise is still there
    assert np.std(y) == pytest.approx(math.sqrt(0.05 ** 2 + precision ** 2 / 12), rel=0.03)
    assert quantize(0.015, 0.01) == pytest.approx(0.02)
    assert quantize(-0.015, 0.01) == pytest.approx(-0.02)
    assert quantize(0.004, 0.01) == 0.0


def test_the_same_seed_replays_every_channel_bit_for_bit_and_channels_differ():
    params = NoiseParams(stddev=0.1, bias_mean=0.2, bias_stddev=0.05,
                         dynamic_bias_stddev=0.1, dynamic_bias_correlation_time=0.5,
                         precision=1e-4)
    a, b = read(params, key='x', n=500), read(params, key='x', n=500)
    assert np.array_equal(a, b)
    assert not np.array_equal(a, read(params, key='y', n=500))
    assert not np.array_equal(a, read(params, key='x', seed=8, n=500))
    channel = NoiseChannel(params, 7, 'x')
    first = [channel.apply(1.0, 0.01) for _ in range(500)]
    channel.reset()
    assert [channel.apply(1.0, 0.01) for _ in range(500)] == first


@pytest.mark.parametrize('kwargs, named', [
    ({'stddev': -0.1}, 'stddev'),
    ({'stddev': math.nan}, 'stddev'),
    ({'mean': math.inf}, 'mean'),
    ({'bias_stddev': -1.0}, 'bias_stddev'),
    ({'dynamic_bias_stddev': 0.1}, 'dynamic_bias_correlation_time'),
    ({'dynamic_bias_stddev': 0.1, 'dynamic_bias_correlation_time': -1.0},
     'dynamic_bias_correlation_time'),
    ({'precision': -0.01}, 'precision'),
    ({'type': 'gaussian_quantized'}, 'precision'),
    ({'type': 'uniform'}, 'type'),
    ({'mean': True}, 'mean'),
])
def test_bad_noise_parameters_are_refused_naming_the_parameter(kwargs, named):
    with pytest.raises(ValueError, match=named):
        NoiseParams(**kwargs)


def test_a_bad_seed_or_dt_is_refused():
    with pytest.raises(ValueError, match='seed'):
        NoiseChannel(NoiseParams(), -1, 'a')
    channel = NoiseChannel(NoiseParams(dynamic_bias_stddev=0.1,
                                       dynamic_bias_correlation_time=1.0), 0, 'a')
    with pytest.raises(ValueError, match='dt'):
        channel.apply(0.0, 0.0)
