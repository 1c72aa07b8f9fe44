"""Sensor noise as SDF's ``<noise>`` element defines it and Gazebo applies it.

A channel (one axis of an accelerometer, of a gyroscope, a strain bridge's output) reads
its true value ``x`` as

    y = x + mean + white + bias + dynamic_bias,      then rounded to ``precision``

- ``white``: independent Gaussian, standard deviation ``stddev``, each sample;
- ``bias``: drawn once per run from N(``bias_mean``, ``bias_stddev``), its sign then
  flipped with probability 1/2 (gz-sensors' GaussianNoiseModel: a bias of either sign
  about a positive ``bias_mean``); constant for the run;
- ``dynamic_bias``: a first-order Gauss-Markov process of correlation time
  tau = ``dynamic_bias_correlation_time``, discretised exactly over each sample's dt as
  gz-sensors (after RotorS and Kalibr's IMU noise model) does:
  b_k+1 = exp(-dt / tau) b_k + N(0, s_d), s_d^2 = -sigma^2 tau / 2 expm1(-2 dt / tau),
  sigma = ``dynamic_bias_stddev``. sigma drives the process (a density, units per
  sqrt(s)): its stationary standard deviation is sigma sqrt(tau / 2), its
  autocorrelation exp(-|lag| / tau). It starts from that stationary distribution;
- ``precision`` (> 0, type ``gaussian_quantized``): the output rounded to the nearest
  multiple of it, as gz-sensors rounds (std::round: halves away from zero).

One difference from gz-sensors, on purpose: there, the drawn bias is the Gauss-Markov
process's initial state, so with a dynamic bias the drawn bias decays over tau. Here
the drawn bias stays for the run and the dynamic bias is a zero-mean process added to
it, so each parameter keeps its own meaning (issue #37: "the bias constant within a
run").

Every channel draws from its own generator, seeded from (``seed``, the channel's
key): the same seed replays every channel bit for bit, whatever the other channels do.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from functools import cached_property

import numpy as np

from rotrod_core.numerics.checks import finite_number

NOISE_TYPES = ('none', 'gaussian', 'gaussian_quantized')
"""SDF's noise types this model applies (``none``: the true value)."""


@dataclass(frozen=True)
class NoiseParams:
    """One channel's noise, SDF's ``<noise>`` parameters, in the channel's units.

    Attributes:
        type: one of NOISE_TYPES.
        mean: added to every sample.
        stddev: the white noise's standard deviation (>= 0).
        bias_mean, bias_stddev: the bias's distribution, drawn once per run
            (bias_stddev >= 0).
        dynamic_bias_stddev: sigma, the Gauss-Markov process's driving density
            (>= 0; units per sqrt(s)); 0: no dynamic bias.
        dynamic_bias_correlation_time: tau, s (> 0 when dynamic_bias_stddev > 0).
        precision: the output's resolution (>= 0; > 0 for gaussian_quantized).
    """

    type: str = 'gaussian'
    mean: float = 0.0
    stddev: float = 0.0
    bias_mean: float = 0.0
    bias_stddev: float = 0.0
    dynamic_bias_stddev: float = 0.0
    dynamic_bias_correlation_time: float = 0.0
    precision: float = 0.0

    def __post_init__(self) -> None:
        if self.type not in NOISE_TYPES:
            raise ValueError(f'type must be one of {", ".join(NOISE_TYPES)}, '
                             f'got {self.type!r}')
        for f in fields(self):
            if f.name == 'type':
                continue
            nonnegative = f.name not in ('mean', 'bias_mean')
            object.__setattr__(self, f.name, finite_number(
                f.name, getattr(self, f.name), nonnegative=nonnegative))
        if self.dynamic_bias_stddev > 0 and not self.dynamic_bias_correlation_time > 0:
            raise ValueError('dynamic_bias_correlation_time must be > 0 with a '
                             f'dynamic_bias_stddev ({self.dynamic_bias_stddev:g}), got '
                             f'{self.dynamic_bias_correlation_time!r}')
        if self.type == 'gaussian_quantized' and not self.precision > 0:
            raise ValueError('precision must be > 0 for type gaussian_quantized, got '
                             f'{self.precision!r}')

    @cached_property
    def off(self) -> bool:
        """Whether the channel reads its true value exactly (type none, or all zero).

        Computed once (every sample asks).
        """
        return self.type == 'none' or not any(
            getattr(self, f.name) for f in fields(self) if f.name != 'type')

    @property
    def dynamic_bias_std(self) -> float:
        """The dynamic bias's stationary standard deviation, sigma sqrt(tau / 2)."""
        if not self.dynamic_bias_stddev:
            return 0.0
        return self.dynamic_bias_stddev * math.sqrt(self.dynamic_bias_correlation_time / 2)

    @property
    def variance(self) -> float:
        """The variance the noise adds about the run's bias, units^2 (0 when off).

        The white noise's, the dynamic bias's stationary one and the rounding's
        (precision^2 / 12); the run's constant bias and mean are not in it.
        """
        if self.off:
            return 0.0
        return self.stddev ** 2 + self.dynamic_bias_std ** 2 + self.precision ** 2 / 12.0


class NoiseChannel:
    """The noise of one channel over a run (see the module's formula).

    Args:
        params: its parameters.
        seed: the run's seed (an integer >= 0).
        key: the channel's name in the sensor ('imu.linear_acceleration.x', ...): with
            the seed, it picks the channel's own random stream.
    """

    def __init__(self, params: NoiseParams, seed: int, key: str) -> None:
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise ValueError(f'seed must be an integer >= 0, got {seed!r}')
        self.params = params
        self._seed, self._key = int(seed), key
        self.reset()

    def reset(self) -> None:
        """Start the run again: the same bias and the same sequence as at the start."""
        p = self.params
        entropy = [self._seed, *self._key.encode()]
        self._rng = np.random.Generator(np.random.PCG64(np.random.SeedSequence(entropy)))
        bias = float(self._rng.normal(p.bias_mean, p.bias_stddev)) if (
            p.bias_mean or p.bias_stddev) else 0.0
        if self._rng.uniform() < 0.5:
            bias = -bias
        self.bias = bias
        """The bias drawn for this run."""
        self.dynamic_bias = (float(self._rng.normal(0.0, p.dynamic_bias_std))
                             if p.dynamic_bias_stddev else 0.0)
        """The Gauss-Markov process's current value."""

    def apply(self, value: float, dt: float) -> float:
        """``value`` as the channel reads it; ``dt``: s since its previous sample (> 0).

        A non-finite ``value`` reads as itself plus the noise (NaN stays NaN).
        """
        p = self.params
        if p.off:
            return value
        out = value + p.mean + self.bias
        if p.stddev:
            out += float(self._rng.normal(0.0, p.stddev))
        if p.dynamic_bias_stddev:
            dt = finite_number('dt', dt, positive=True)
            tau = p.dynamic_bias_correlation_time
            step = math.sqrt(-p.dynamic_bias_stddev ** 2 * tau / 2 * math.expm1(-2 * dt / tau))
            self.dynamic_bias = (math.exp(-dt / tau) * self.dynamic_bias
                                 + float(self._rng.normal(0.0, step)))
            out += self.dynamic_bias
        if p.precision:
            out = quantize(out, p.precision)
        return out


def quantize(value: float, precision: float) -> float:
    """``value`` rounded to the nearest multiple of ``precision`` (> 0).

    Halves away from zero (C's round, as gz-sensors); a non-finite value as it is.
    """
    q = value / precision
    return math.copysign(math.floor(abs(q) + 0.5), q) * precision if math.isfinite(q) else value


__all__ = ['NOISE_TYPES', 'NoiseChannel', 'NoiseParams', 'quantize']
