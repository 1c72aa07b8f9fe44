"""Fit a sampled planar motion z(t) = u + i v to a centre plus two circular whirls.

    z(t) = c + a exp(+i wf t) + b exp(-i wb t)

The forward whirl (amplitude a, circular frequency wf) turns in the sense of +e3, the
backward one (b, wb) against it. Their sum is an ellipse with semi-axes |a| + |b| and
||a| - |b||, whose axis turns at (wf - wb) / 2 rad/s: a fixed ellipse when wf = wb,
a "petal" pattern otherwise. This is how an isotropic rod's free vibration looks at
constant rotation (docs/model.md: wf = w0 - w, wb = w0 + w), so the fit measures the
dynamic frequencies, the static deflection c and the shape of the motion from a
simulated trajectory alone.

Frequencies start from the peaks of a windowed spectrum and are refined by
least squares (variable projection: for given frequencies, c, a and b are linear).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

TWO_PI = 2.0 * math.pi


@dataclass(frozen=True)
class WhirlFit:
    """The fitted motion z(t) = centre + forward e^{i wf t} + backward e^{-i wb t}.

    Attributes:
        centre: c, m (complex: u + i v).
        forward: a, m (complex amplitude at t = 0 of the fitted samples' time origin).
        backward: b, m.
        forward_omega: wf, rad/s (>= 0).
        backward_omega: wb, rad/s (>= 0).
        residual: root-mean-square of |z - fit|, m.
    """

    centre: complex
    forward: complex
    backward: complex
    forward_omega: float
    backward_omega: float
    residual: float

    @property
    def forward_frequency(self) -> float:
        """Wf / 2pi, Hz."""
        return self.forward_omega / TWO_PI

    @property
    def backward_frequency(self) -> float:
        """Wb / 2pi, Hz."""
        return self.backward_omega / TWO_PI

    @property
    def semi_major(self) -> float:
        """Semi-major axis |a| + |b| of the ellipse, m."""
        return abs(self.forward) + abs(self.backward)

    @property
    def semi_minor(self) -> float:
        """Semi-minor axis ||a| - |b|| of the ellipse, m."""
        return abs(abs(self.forward) - abs(self.backward))

    @property
    def precession_rate(self) -> float:
        """Rate at which the ellipse's major axis turns, (wf - wb) / 2, rad/s."""
        return 0.5 * (self.forward_omega - self.backward_omega)

    @property
    def relative_residual(self) -> float:
        """Residual over the semi-major axis (0 for a perfect fit)."""
        return self.residual / self.semi_major if self.semi_major else math.inf


def _design(t, wf, wb):
    return np.column_stack([np.ones_like(t), np.exp(1j * wf * t), np.exp(-1j * wb * t)])


def _solve(t, z, wf, wb):
    A = _design(t, wf, wb)
    coef = np.linalg.lstsq(A, z, rcond=None)[0]
    return coef, z - A @ coef


def spectral_peaks(t, z, min_frequency: float | None = None) -> tuple:
    """Circular frequencies (rad/s) of the strongest forward and backward components of z.

    From the Hann-windowed, zero-padded spectrum of z - mean(z) on a uniform grid ``t``
    (s). Components slower than ``min_frequency`` Hz (default: two cycles over the
    record) are left out, so the centre does not count as a whirl.
    """
    t = np.asarray(t, dtype=float)
    z = np.asarray(z, dtype=complex)
    dt = float(t[1] - t[0])
    span = float(t[-1] - t[0])
    fmin = 2.0 / span if min_frequency is None else float(min_frequency)
    n = len(z)
    nfft = 1 << (8 * n - 1).bit_length()
    spec = np.abs(np.fft.fft((z - z.mean()) * np.hanning(n), nfft))
    freqs = np.fft.fftfreq(nfft, dt)
    fwd = freqs[np.argmax(np.where(freqs > fmin, spec, -1.0))]
    bwd = -freqs[np.argmax(np.where(freqs < -fmin, spec, -1.0))]
    return TWO_PI * fwd, TWO_PI * bwd


def fit_whirls(t, u, v, guess: tuple | None = None) -> WhirlFit:
    """Least-squares fit of samples (t s, u m, v m) to a centre and two whirls.

    Args:
        t: sample times, s (uniform spacing when ``guess`` is not given).
        u, v: the motion, m.
        guess: starting (wf, wb) in rad/s; default from :func:`spectral_peaks`.
    """
    t = np.asarray(t, dtype=float)
    z = np.asarray(u, dtype=float) + 1j * np.asarray(v, dtype=float)
    if len(t) < 8:
        raise ValueError('fit_whirls needs at least 8 samples')
    tt = t - t[0]
    wf0, wb0 = spectral_peaks(t, z) if guess is None else guess

    def residuals(x):
        r = _solve(tt, z, x[0], x[1])[1]
        return np.concatenate([r.real, r.imag])

    scale = max(abs(wf0), abs(wb0), 1e-12)
    sol = least_squares(residuals, x0=[wf0, wb0], x_scale=scale, xtol=1e-15, ftol=1e-15,
                        gtol=1e-15, method='lm')
    wf, wb = float(sol.x[0]), float(sol.x[1])
    coef, r = _solve(tt, z, wf, wb)
    c, a, b = complex(coef[0]), complex(coef[1]), complex(coef[2])
    return WhirlFit(centre=c, forward=a, backward=b, forward_omega=wf, backward_omega=wb,
                    residual=float(np.sqrt(np.mean(np.abs(r) ** 2))))
