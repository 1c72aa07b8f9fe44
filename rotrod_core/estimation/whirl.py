"""Whirl frequencies from the tip motion: forward and backward whirl over a window.

At constant w the free vibration of z = u + i v (m, rotating frame) is

    z(t) = z_s + a1 exp(+i 2pi f1 t) + a2 exp(-i 2pi f2 t)

(docs/model.md, Eq. 28): the forward whirl at the positive frequency f1 = (w0 - w) / 2pi,
the backward whirl at the negative frequency -f2 = -(w0 + w) / 2pi (for 0 <= w < w0;
for w < 0 the two signs swap roles). The sign of the frequency of the complex signal
separates them; z_s is the static (eccentric) deflection.

The estimator is the maximum-likelihood fit, for white noise, of that model with the
offset generalized to a slow drift (a polynomial in time: during a spin-up the
quasi-static deflection follows w^2 and moves within a window) and each whirl allowed
a decay rate:

1. Block averaging: the samples are averaged over blocks of 1 / (4 max_frequency) s
   (10 ms by default). The block mean of an exponential is the same exponential with
   another amplitude, that of a polynomial a polynomial of the same degree: the model
   stays exact. White noise stays white with its variance divided by the block size,
   so almost no information is lost, and the cost is set by ~100 blocks instead of
   the 1000 samples of a 1 s window at 1 kHz. Irregular times (dropped or jittered
   samples) are handled exactly: the model is then averaged over each block's own
   sample times.
2. Start values, from the zero-padded FFT of the block means with the drift projected
   out: its strongest peak gives the first whirl, which is fitted; in the residual,
   the strongest peak of the opposite sign of the likelihood-ratio statistic of one
   tone against the drift alone (the spectrum normalized by what the drift leaves of
   a tone, which finds a whirl slow enough for the drift to take most of it) gives
   the second. The online estimator starts from its previous estimate instead.
3. Joint fit: Gauss-Newton over the two complex poles s = -decay + i 2pi f, with the
   amplitudes and the drift coefficients solved by linear least squares for each
   trial (variable projection), first with a drift of degree ``drift_degree``, then
   again with only the drift terms that stand out of the noise (a drift term fitted
   to noise absorbs part of a slow whirl and costs precision).

At high SNR this reaches the Cramer-Rao bound, where ESPRIT on the same blocks is
above it, and it follows a drifting offset, which ESPRIT can only remove by
differencing, at a large cost in noise (numbers: bench/bench_estimator.py).

No estimate (NaN, and why in ``WhirlEstimate.reason``) when the window has too few
samples or a gap longer than ``max_gap`` of it, when a whirl is not detected above
the noise (``detection_db``, over the whole window) or is at the float round-off of
the offset, when its frequency is outside min_cycles / window .. max_frequency, when
it decays or grows by more than ``max_decay`` nepers over the window, when its
frequency's standard deviation exceeds ``max_relative_std`` of it (the standard
deviation from the residual, inflated by (1 + rho) / (1 - rho) for the residual's
lag-1 correlation rho, so that a misfit does not pass for white noise), or when the
window is not stationary for it: fitted again over each half of the window (from the
whole's poles), the mean of its two frequencies differs from the whole's by more than
``max_split_change`` of it and by more than 3 standard deviations of that mean for a
white residual. (A frequency that drifts linearly, as in a spin-up, has the mean of
the halves at the whole's value; a new vibration started inside the window does not.
A whirl too slow for a half window, which the drift takes there, is not judged.)
When the residual is strongly correlated (variance inflation above 4: the model
misfits the window) and one whirl is too uncertain, the other, fitted jointly, is
dropped too.
Non-finite values, unequal lengths and times that do not increase strictly raise
ValueError.

Limitation: the model is stationary. A window that contains a sudden change of the
drive (a joint of the Eq. 26 profile, where the third derivative of w jumps and
excites a new free vibration, or a correction of a streamed w) does not fit it; the
decay, (inflated) standard deviation and split-window rules reject most such windows
(the bench measures the rest on the Eq. 26 joints).
"""

from __future__ import annotations

import cmath
import dataclasses
import functools
import math
from dataclasses import dataclass, field

import numpy as np
from numpy.polynomial import legendre
from scipy.linalg import lapack

from rotrod_core.numerics.checks import finite_array, finite_number

TWO_PI = 2.0 * math.pi
_REGULAR_JITTER = 1e-3      # steps within this fraction of the median step count as regular
_ROUNDOFF = 1e-10           # amplitudes below this fraction of max |z| are float round-off
_MAX_ITERATIONS = 30
_START_ITERATIONS = 4       # for the first whirl alone: a start value, the other unmodelled
_DRIFT_SIGNIFICANCE = 25.0  # (|c| / std c)^2 above which a drift term is kept
_ZERO_PAD = 8               # periodogram length: this many times the number of blocks
_SPLIT_SIGMAS = 3.0         # a halves' change within this many std is noise (_split_check)
_MISFIT_INFLATION = 4.0     # residual variance inflation above which a window misfits
_SPLIT_TOLERANCE = 1e-5     # rad over a half window: a half's fit to ~1e-5 / (pi f T)
_TOLERANCE = 1e-8           # rad over the window: the estimate's fit converged
_DECISION_TOLERANCE = 1e-3  # rad: a fit that decides the drift degree, converged enough
_DECISION_ITERATIONS = 8    # ... or after this many iterations (a half window's, _half_whirls)
_MEASURABLE = 1e-8          # a predicted decrease below this fraction of the cost is rounding
_AHEAD = 0.1                # a step whose successor would be this x the tolerance ends a fit
_HALF_AHEAD = 1.0           # ... a half window's (_half_whirls: tolerance 1e-5 rad)
MAX_WINDOW_SAMPLES = 1e6    # longest online window, in sample intervals (docs/realtime.md)
_FLOATS = (float, np.float64)  # sample types push takes as they are when finite
_UNIT_BOUND = 2.0 * math.sqrt(2.0)  # |z| < this once scaled by _estimate (parts < 2)


@dataclass(frozen=True)
class WhirlSettings:
    """Model and acceptance limits of the whirl estimator.

    Attributes:
        drift_degree: degree of the polynomial in time that models the offset and its
            drift over the window (0: a constant offset). 4 follows an Eq. 26 spin-up.
        max_frequency: highest whirl frequency sought, Hz. Sets the block interval
            1 / (4 max_frequency) s; motion above 2 max_frequency aliases.
        min_cycles: lowest whirl frequency sought, in cycles per window.
        detection_db: detection threshold on the whirl's energy over the window
            against the noise, N a^2 / sigma^2, dB (N samples, amplitude a, per-sample
            complex noise variance sigma^2).
        max_relative_std: largest accepted standard deviation of a frequency (see
            :class:`Whirl`; inflated for a correlated residual, i.e. model misfit),
            as a fraction of the frequency. 0.2 % keeps the Eq. 26 windows across a
            joint of the profile from passing as estimates several per cent off.
        max_decay: largest accepted |decay rate| x window, nepers. Also the main
            guard against a window that is not stationary (a jump in the drive
            inside it shows as a whirl that grows or decays).
        max_gap: longest accepted interval between samples, fraction of the window.
        max_split_change: largest accepted difference between a whirl's frequency
            over the window and the mean of its frequencies over the window's two
            halves, as a fraction of the frequency (inf: no check). The stationarity
            check: a whirl steady over the window, or whose frequency drifts linearly
            (a spin-up), has the mean of the halves at the whole's value; a new free
            vibration started inside the window (a step or kink of the drive, or a
            correction of a streamed w) puts them apart, often by far more than the
            frequency's standard deviation, which does not see such a misfit.
    """

    drift_degree: int = 4
    max_frequency: float = 25.0
    min_cycles: float = 0.1
    detection_db: float = 20.0
    max_relative_std: float = 0.002
    max_decay: float = 1.0
    max_gap: float = 0.1
    max_split_change: float = 0.01

    def __post_init__(self):
        deg = self.drift_degree
        if isinstance(deg, bool) or not isinstance(deg, (int, np.integer)) or not 0 <= deg <= 8:
            raise ValueError(f'WhirlSettings.drift_degree must be an integer 0..8, got {deg!r}')
        set_ = object.__setattr__
        set_(self, 'drift_degree', int(deg))
        for name in ('max_frequency', 'min_cycles', 'max_relative_std', 'max_decay',
                     'max_gap'):
            set_(self, name, finite_number(f'WhirlSettings.{name}', getattr(self, name),
                                           positive=True))
        split = self.max_split_change
        try:                              # an int past the float range overflows
            number = (float(split) if isinstance(split, (int, float, np.floating))
                      and not isinstance(split, bool) else math.nan)
        except OverflowError:
            number = math.nan
        if not number > 0:                # NaN fails too
            raise ValueError('WhirlSettings.max_split_change must be a positive number or '
                             f'inf, got {split!r}')
        set_(self, 'max_split_change', number)
        set_(self, 'detection_db', finite_number('WhirlSettings.detection_db',
                                                 self.detection_db))
        if not math.isfinite(self.block_interval):
            raise ValueError(f'WhirlSettings.max_frequency {self.max_frequency!r} Hz is too '
                             'small: the block interval 1 / (4 max_frequency) overflows')

    @property
    def block_interval(self) -> float:
        """Averaging block length, s: 1 / (4 max_frequency)."""
        return 0.25 / self.max_frequency

    @property
    def min_blocks(self) -> int:
        """Fewest blocks a window needs: twice the number of complex model parameters."""
        return 2 * (4 + self.drift_degree + 1)


@dataclass(frozen=True)
class Whirl:
    """One whirl (one sign of frequency) in a window. NaN fields: not found.

    Attributes:
        frequency: |frequency|, Hz (NaN: no estimate).
        amplitude: radius of the whirl's circle at the window centre, m.
        decay_rate: -Re(s) of the whirl's pole s, 1/s (> 0: it decays).
        snr_db: a^2 / sigma^2 per sample, dB (sigma^2: residual complex variance).
        frequency_std: standard deviation of ``frequency``, Hz, taking the residual
            for white noise: the Cramer-Rao bound at the fitted values, with the other
            whirl and the drift as nuisance parameters. It does not see model
            mismatch (a window that is not stationary).
    """

    frequency: float = math.nan
    amplitude: float = math.nan
    decay_rate: float = math.nan
    snr_db: float = -math.inf
    frequency_std: float = math.nan


@dataclass(frozen=True)
class WhirlEstimate:
    """Whirl frequencies in one window of tip motion.

    Attributes:
        forward: the whirl at positive frequency of z = u + i v (Eq. 28's f1 for
            0 <= w < w0).
        backward: the whirl at negative frequency (Eq. 28's f2).
        time: the instant the estimate describes: the centre of the samples used, s.
            (A frequency that drifts linearly over the window is estimated at its
            centre value: the estimate lags the newest sample by half a window.)
        window: time spanned by the samples used, s.
        samples: number of samples used.
        offset: fitted drift (static deflection) u + i v at ``time``, m.
        noise_rms: residual per-sample complex RMS, m.
        reason: why a whirl is NaN ('' when both were found).
    """

    forward: Whirl = field(default_factory=Whirl)
    backward: Whirl = field(default_factory=Whirl)
    time: float = math.nan
    window: float = 0.0
    samples: int = 0
    offset: complex = complex(math.nan, math.nan)
    noise_rms: float = math.nan
    reason: str = ''

    @property
    def f1(self) -> float:
        """Forward-whirl frequency, Hz (NaN: no estimate)."""
        return self.forward.frequency

    @property
    def f2(self) -> float:
        """Backward-whirl frequency, Hz (NaN: no estimate)."""
        return self.backward.frequency

    @property
    def quality(self) -> float:
        """SNR per sample of the weaker whirl, dB (-inf when a whirl has no estimate)."""
        return min(-math.inf if math.isnan(w.frequency) else w.snr_db
                   for w in (self.forward, self.backward))


def _samples(t, u, v):
    """Validated float arrays ``t`` (s) and ``z = u + i v`` (m); ValueError if unusable."""
    try:
        arrays = [np.asarray(x, dtype=float).ravel() for x in (t, u, v)]
    except (TypeError, ValueError, OverflowError):
        raise ValueError('t, u and v must be arrays of numbers') from None
    t, u, v = arrays
    if not len(t) == len(u) == len(v):
        raise ValueError(f't, u and v must have equal lengths, got {len(t)}, {len(u)}, '
                         f'{len(v)}')
    for name, x in (('t', t), ('u', u), ('v', v)):
        finite_array(name, x)
    if len(t) > 1 and not np.all(np.diff(t) > 0):
        bad = int(np.argmax(np.diff(t) <= 0))
        raise ValueError(f'times must increase strictly: t[{bad}] = {t[bad]!r} s, '
                         f't[{bad + 1}] = {t[bad + 1]!r} s')
    return t, u + 1j * v


def estimate_whirl(t, u, v, settings: WhirlSettings | None = None) -> WhirlEstimate:
    """Forward and backward whirl in one window of samples (module docstring).

    Args:
        t: sample times, s, strictly increasing (gaps and jitter allowed).
        u: radial deflection at those times, m.
        v: tangential deflection, m.
        settings: model and acceptance limits (defaults: :class:`WhirlSettings`).
    """
    t, z = _samples(t, u, v)
    return _estimate(t, z, settings or WhirlSettings())[0]


def estimate_whirl_frequencies(t, u, v, settings: WhirlSettings | None = None
                               ) -> tuple[float, float]:
    """(f1, f2) in Hz, forward and backward whirl of a window; NaN where no estimate.

    See :func:`estimate_whirl` for the arguments and :class:`WhirlEstimate` for more.
    """
    est = estimate_whirl(t, u, v, settings)
    return est.f1, est.f2


# -- blocks --------------------------------------------------------------------------

def _median(x) -> float:
    """np.median of a 1-D float array (the same value), without its overhead."""
    n = len(x)
    half = n // 2
    if n % 2:
        return float(np.partition(x, half)[half])
    part = np.partition(x, (half - 1, half))
    return float((part[half - 1] + part[half]) / 2)


_GRID_MATCH = 1e-12         # normalized block times this close to the ideal grid's share it
_CACHED_BLOCKS = 4096       # longest block series whose drift columns are cached


@functools.lru_cache(maxsize=16)
def _regular_drift(samples, per_block, degree):
    """Normalized block times and weighted Legendre drift columns of an ideal grid (cached).

    ``samples`` evenly spaced samples in blocks of ``per_block``: the block means of
    their times, normalized to [-1, 1] over the samples' span, and legvander of those
    times times sqrt(per_block). A sliding window of regular samples meets the same
    grid on every update.
    """
    m = samples // per_block
    x = (2.0 * per_block * np.arange(m) + (per_block - samples)) / (samples - 1)
    drift = legendre.legvander(x, degree) * math.sqrt(per_block)
    x.flags.writeable = drift.flags.writeable = False
    return x, drift


def _drift_columns(x, degree, samples, per_block):
    """Weighted Legendre drift columns of regular blocks at times ``x``, ideal grid or not.

    ``x``: the normalized block times. The cached ideal grid's when ``x`` is within
    ``_GRID_MATCH`` of it (the float round-off of sample times: the drift polynomials
    then span the same functions to that precision), else computed.
    """
    if len(x) <= _CACHED_BLOCKS:
        ideal, drift = _regular_drift(samples, per_block, degree)
        if len(ideal) == len(x) and float(np.abs(x - ideal).max()) <= _GRID_MATCH:
            return drift, True
    return legendre.legvander(x, degree) * math.sqrt(per_block), False


class _Blocks:
    """Block means y of the samples, the drift basis and the exponential basis on them.

    Rows are weighted by sqrt(samples in the block), so that the least-squares fit of
    the block means is the least-squares fit of the samples. ``steps`` and ``dt``: the
    samples' intervals and their median, when the caller has them; ``regular``: True
    when the caller knows the intervals within ``_REGULAR_JITTER`` of ``dt``;
    ``bound``: an upper bound of |z|, when known (:meth:`roundoff`).

    ``tau`` (complex, (m, 1)) and ``scale``: for regular blocks the weighted block
    means of exp(s tau) are exp(tau s) x ``scale`` (None: 1); None for irregular
    blocks (see :meth:`exponentials`).
    """

    def __init__(self, t, z, per_block, degree, steps=None, dt=None, regular=None,
                 bound=math.inf):
        if regular and dt is not None:
            self.dt, self.regular = dt, True
        else:
            if steps is None:
                steps = t[1:] - t[:-1]
            self.dt = _median(steps) if dt is None else dt
            jitter = _REGULAR_JITTER * self.dt
            self.regular = bool(steps.max() - self.dt <= jitter
                                and self.dt - steps.min() <= jitter)
        if self.regular and len(t) % per_block:     # whole blocks: the oldest go
            keep = len(t) // per_block * per_block
            t, z = t[len(t) - keep:], z[len(z) - keep:]
        n = len(t)
        self.samples = n
        self.per_block = per_block
        self.interval = per_block * self.dt
        first, last = float(t[0]), float(t[-1])
        self.t_centre = 0.5 * (first + last)
        self.half_span = 0.5 * (last - first)
        self._z, self._bound = z, bound
        self.exponent = 0                    # the samples are z 2^exponent (_estimate)
        self.scale: float | None = None
        self.tau: np.ndarray | None = None
        self.mirror = False     # tau is symmetric about 0 (to _GRID_MATCH of the window)
        if self.regular:
            m = n // per_block
            if per_block == 1:
                tau_c = np.subtract(t, self.t_centre, dtype=complex)
                tb = tau_c.real
                self.y = self.yw = z
            else:
                # (np.add.reduce / n is what .mean does, without its overhead)
                tb = np.add.reduce((t - self.t_centre).reshape(m, per_block), axis=1) / per_block
                tau_c = tb.astype(complex)
                self.y = np.add.reduce(z.reshape(m, per_block), axis=1) / per_block
                self.scale = math.sqrt(per_block)
                self.yw = self.y * self.scale
            self.tau = tau_c[:, None]
            self.grid, self.grid_tau = self.y, tb
            self.drift, self.mirror = _drift_columns(tb / self.half_span, degree, n, per_block)
        else:
            # blocks counted back from the newest sample; empty blocks simply absent
            tau = t - self.t_centre
            index = np.floor((t[-1] + 0.5 * self.dt - t) / self.interval).astype(int)
            starts = np.concatenate(([0], np.flatnonzero(np.diff(index)) + 1))
            counts = np.diff(np.append(starts, n)).astype(float)
            self.y = np.add.reduceat(z, starts) / counts
            self.weight = np.sqrt(counts)
            self._tau, self._starts, self._counts = tau[:, None], starts, counts[:, None]
            drift = np.add.reduceat(legendre.legvander(tau / self.half_span, degree), starts,
                                    axis=0) / counts[:, None]
            self.grid, self.grid_tau = self._uniform_grid(t, z, per_block)
            self.drift = drift * self.weight[:, None]
            self.yw = self.y * self.weight
        self.m = len(self.y)

    @functools.cached_property
    def z_scale(self) -> float:
        """Max |z| of the samples used."""
        return float(np.abs(self._z).max())

    def roundoff(self, amplitude) -> bool:
        """Whether ``amplitude`` is at the float round-off of the samples.

        At most ``_ROUNDOFF`` max |z| (max |z| computed only if the bound does not tell).
        """
        return (not amplitude > _ROUNDOFF * self._bound
                and amplitude <= _ROUNDOFF * self.z_scale)

    def _uniform_grid(self, t, z, per_block):
        """Block means of z interpolated onto the regular grid (start values only)."""
        m = int(round((t[-1] - t[0]) / self.dt)) + 1
        tg = t[-1] - self.dt * np.arange(m)[::-1]
        zg = np.interp(tg, t, z.real) + 1j * np.interp(tg, t, z.imag)
        mb = m // per_block
        cut = m - mb * per_block
        return (zg[cut:].reshape(mb, per_block).mean(axis=1),
                (tg[cut:] - self.t_centre).reshape(mb, per_block).mean(axis=1))

    def exponentials(self, s):
        """Weighted block means of exp(s tau) and of tau exp(s tau), (m, len(s))."""
        if self.tau is not None:
            e = np.exp(self.tau * s)
            if self.scale is not None:
                e *= self.scale
            return e, self.tau * e
        tau = self._tau
        e = np.exp(tau * s)
        de = tau * e
        c = self._counts
        e = np.add.reduceat(e, self._starts) / c
        de = np.add.reduceat(de, self._starts) / c
        w = self.weight[:, None]
        return e * w, de * w


class _Grid:
    """The regular block series (unweighted), for the start values."""

    def __init__(self, y, tau, degree):
        self.y = self.yw = y
        self.m = len(y)
        self.tau = tau.astype(complex)[:, None]
        self.scale = None
        self.drift, self.mirror = _drift_columns(tau / max(abs(tau[0]), abs(tau[-1])),
                                                 degree, self.m, 1)

    def exponentials(self, s):
        e = np.exp(self.tau * s)
        return e, self.tau * e


# -- fit -----------------------------------------------------------------------------

class _Fit:
    """A fitted window (see :class:`_Fitter`).

    Attributes:
        s: complex poles, 1/s (a list).
        amplitudes: complex block-mean amplitudes at the window centre, m (a list).
        drift: Legendre coefficients of the drift, m (``degree`` + 1).
        residual: weighted residual, m.
        noise_var: per-sample complex noise variance from the residual, m^2.
        pole_unit: variances of the poles in units of noise_var (NaN: not computed).
        drift_unit: those of the drift coefficients.
        inflation: variance factor for a correlated residual (model misfit).
        top: (last drift coefficient, its unit variance), when known without
            ``drift`` and ``drift_unit`` (else None).

    ``drift``, ``residual`` and ``drift_unit`` may be given as functions: they are
    then computed when first read.
    """

    def __init__(self, s, amplitudes, drift, residual, noise_var, pole_unit, degree,
                 drift_unit=None, top=None):
        self.s, self.amplitudes, self.degree = s, amplitudes, degree
        self._drift, self._residual, self.noise_var = drift, residual, noise_var
        self.pole_unit = pole_unit
        self._drift_unit = drift_unit
        self._inflation: float | None = None
        self.top: tuple[complex, float] | None = top

    @property
    def drift(self) -> np.ndarray:
        if callable(self._drift):
            self._drift = self._drift()
        return self._drift

    @property
    def residual(self) -> np.ndarray:
        if callable(self._residual):
            self._residual = self._residual()
        return self._residual

    @property
    def drift_unit(self) -> np.ndarray:
        if callable(self._drift_unit):
            self._drift_unit = self._drift_unit()
        if self._drift_unit is None:
            self._drift_unit = np.full(len(self.drift), np.nan)
        return self._drift_unit

    @property
    def inflation(self) -> float:
        if self._inflation is None:
            self._inflation = _correlation_inflation(self.residual)
        return self._inflation


def _solve(a, b):
    """Least-squares solution of a x = b (Householder QR; SVD if that fails)."""
    _, x, info = lapack.zgels(a, b)
    x = x[:a.shape[1]]
    if info != 0 or not np.isfinite(x).all():
        x = np.linalg.lstsq(a, b, rcond=None)[0]
    return x


def _triangular_solve(rows, rhs, first, k):
    """The solution (a list) of R x = rhs, R upper triangular (k, k).

    R = rows[first:first + k][first:first + k] (nested lists; the lower part is not
    read). ZeroDivisionError if R is singular.
    """
    x = [0j] * k
    for i in range(k - 1, -1, -1):
        row = rows[first + i]
        acc = rhs[i]
        for j in range(i + 1, k):
            acc -= row[first + j] * x[j]
        x[i] = acc / row[first + i]
    return x


def _block_solution(block, k):
    """The projection's solution from R's lower-right block (nested lists).

    The block is R's rows and columns from the last drift column on: [[r_d, ...],
    [0, Ree, Reg, ce], [0, 0, Rgg, cg], [0, 0, 0, r]] (the lower part is not read),
    of the columns e (k), de (k) and y: the amplitudes a (Ree a = ce), the Gauss-
    Newton step of the poles (Rgg (a step) = cg), the decrease of the cost it
    predicts (|cg|^2) and the cost (|cg|^2 + |r|^2). ZeroDivisionError for a zero
    diagonal element or amplitude.
    """
    if k == 2:                           # the usual case, written out
        _, r0, r1, r2, r3, r4 = block
        a1 = r1[5] / r1[2]
        a0 = (r0[5] - r0[2] * a1) / r0[1]
        g1 = r3[5] / r3[4]
        g0 = (r2[5] - r2[4] * g1) / r2[3]
        decrease = abs(r2[5]) ** 2 + abs(r3[5]) ** 2
        return [a0, a1], [g0 / a0, g1 / a1], decrease, decrease + abs(r4[5]) ** 2
    amplitudes = _triangular_solve(block, [row[2 * k + 1] for row in block[1:k + 1]], 1, k)
    along = [row[2 * k + 1] for row in block[k + 1:2 * k + 1]]
    gamma = _triangular_solve(block, along, k + 1, k)
    decrease = sum(abs(x) ** 2 for x in along)
    return ([*amplitudes], [g / a for g, a in zip(gamma, amplitudes)], decrease,
            decrease + abs(block[2 * k + 1][2 * k + 1]) ** 2)


def _tail_solve(rows, k):
    """The solution z of R z = c over the block's rows and columns (a list).

    The block as in :func:`_block_solution`: z holds the last drift term's, the
    amplitudes' and the steps' coefficients of the least-squares fit of y by
    [drift, e, de].
    """
    if k == 2:                           # the usual case, written out
        r0, r1, r2, r3, r4 = rows[:5]
        z4 = r4[5] / r4[4]
        z3 = (r3[5] - r3[4] * z4) / r3[3]
        z2 = (r2[5] - r2[3] * z3 - r2[4] * z4) / r2[2]
        z1 = (r1[5] - r1[2] * z2 - r1[3] * z3 - r1[4] * z4) / r1[1]
        z0 = (r0[5] - r0[1] * z1 - r0[2] * z2 - r0[3] * z3 - r0[4] * z4) / r0[0]
        return [z0, z1, z2, z3, z4]
    return _triangular_solve(rows, [row[2 * k + 1] for row in rows[:2 * k + 1]], 0, 2 * k + 1)


def _drift_solve(rows, count, known):
    """The first ``count`` coefficients of R's triangular system, the others ``known``.

    x (a list) with rows[i][:count] x + rows[i][count:count + len(known)] known =
    rows[i][-1], i < count (R's first rows as lists): the drift coefficients from the
    exponentials' and the others' known coefficients.
    """
    x = [0j] * count
    for i in range(count - 1, -1, -1):
        row = rows[i]
        acc = row[-1]
        for j, value in enumerate(known, count):
            acc -= row[j] * value
        for j in range(i + 1, count):
            acc -= row[j] * x[j]
        x[i] = acc / row[i]
    return x


def _first_row_norm(rows, k):
    """Squared norm of the first row of R^-1: the unit variance of the last drift term.

    R: the block's first 2 k + 1 rows and columns (:func:`_block_solution`).
    """
    if k == 2:                           # the usual case, written out
        r0, r1, r2, r3, r4 = rows[:5]
        x0 = 1 / r0[0]
        x1 = -x0 * r0[1] / r1[1]
        x2 = -(x0 * r0[2] + x1 * r1[2]) / r2[2]
        x3 = -(x0 * r0[3] + x1 * r1[3] + x2 * r2[3]) / r3[3]
        x4 = -(x0 * r0[4] + x1 * r1[4] + x2 * r2[4] + x3 * r3[4]) / r4[4]
        return (abs(x0) ** 2 + abs(x1) ** 2 + abs(x2) ** 2 + abs(x3) ** 2
                + abs(x4) ** 2)
    x = [1 / rows[0][0]]
    for j in range(1, 2 * k + 1):
        x.append(-sum(x[i] * rows[i][j] for i in range(j)) / rows[j][j])
    return sum(abs(v) ** 2 for v in x)


def _inverse_row_norms(rows, first, k):
    """Squared norms of the rows of R^-1, R as in :func:`_triangular_solve`."""
    if k == 2:
        (a, b), d = rows[first][first:first + 2], rows[first + 1][first + 1]
        return [abs(1 / a) ** 2 + abs(b / (a * d)) ** 2, abs(1 / d) ** 2]
    norms = [0.0] * k
    for j in range(k):                   # column j of R^-1
        column = _triangular_solve(rows, [1.0 if i == j else 0.0 for i in range(k)], first, k)
        for i in range(k):
            norms[i] += abs(column[i]) ** 2
    return norms


@functools.lru_cache(maxsize=64)
def _identity(n, p):
    """The first p columns of the (n, n) identity, complex."""
    columns = np.eye(n, p, dtype=complex, order='F')
    columns.flags.writeable = False
    return columns


def _finite(values) -> bool:
    """Whether all values are finite (their sum is, or overflows: then not trusted)."""
    return cmath.isfinite(sum(values))


class _Fitter:
    """The least-squares fit of :func:`_fit`, run in stages.

    ``run(tolerance)`` iterates until an update moves every pole's phase over the
    window by less than ``tolerance`` rad, and may be called again with a smaller one
    (the iterations are those of one run to the smaller tolerance); ``result()`` is
    the fit so far.

    Each trial of the poles is one Householder QR of A = [drift, e, de, y] (e the
    exponentials, de their derivatives in s): its leading columns solve the amplitudes
    and drift (variable projection), its last column's tail is the residual, and the
    de block, which the QR has orthogonalized against the drift and exponentials, gives
    Kaufman's Gauss-Newton direction; R also gives the variances (J = [de a, e, drift]
    is A's first columns scaled, so (J^H J)^-1 is R^-1 R^-H scaled). A trial whose QR
    is singular (or not finite) is solved as the full least-squares problems instead
    (:func:`_solve`).

    A step that does not lower the cost although its Gauss-Newton model predicts a
    decrease below ``_MEASURABLE`` of it ends the fit as one that finds no shorter
    step that does: a decrease that small is at the rounding of the cost (or moves the
    poles by ~1e-4 of their standard deviation).

    A Gauss-Newton step shorter than the tolerance ends the run: it is the update that
    would stop a run (and smaller than the tolerance whatever the line search made of
    it), and it is taken without a new projection (``pending``). So is a step after
    which the next one would be shorter than ``ahead`` x the tolerance if the steps
    keep shrinking as the last two did (the last taken whole; near the minimum they
    shrink by 1e-2 or faster per step, the estimate's windows measured): the poles then
    end nearer the minimum than after a run that takes the step and stops at the next.
    The result has the poles after the pending step, and the amplitudes and drift of
    the Gauss-Newton model there (the least-squares fit of y by [drift, e, de], exact
    to second order in the step); the noise variance is the residual of that model,
    and the parameters' variances are those before the step (they change with it to
    first order, by about the step's phase over the window in relative terms: ~1e-6 or
    less for a whole window's fit, ~1e-3 for a half's).
    """

    def __init__(self, data, s, degree, window, iterations=_MAX_ITERATIONS, pool=None):
        """``pool``: a dict that keeps work arrays between fits (:meth:`release`)."""
        self.data = data
        self.s = [complex(x) for x in s]
        k = self.k = len(self.s)
        p = self.p = degree + 1
        n = self.n = p + 2 * k
        self.drift = data.drift[:, :p]
        self.window = window
        self.decay_limit = 50.0 / window          # keeps exp() finite on a wild step
        self.left = iterations
        self.moved = math.inf
        self.pending: list[complex] | None = None   # the last step, short enough
        self.pending_size = math.inf
        self.decrease = math.inf
        self.last = 0.0          # the last step's length, if taken whole (else 0)
        self.stuck = False
        self.qr = data.m > n     # else the least-squares problems are solved whole
        self._spare = None       # a work array no state uses (see _work)
        self._kept = None        # the work array of the last result
        # work arrays of earlier fits with these drift columns (the ideal grid's):
        # pool[(id(drift), p, k)] = (drift, [work arrays])
        self._pooled: list | None = None
        if pool is not None and data.mirror and self.qr:
            key = (id(data.drift), p, k)
            entry = pool.get(key)
            if entry is None or entry[0] is not data.drift:
                entry = pool[key] = (data.drift, [])
            self._pooled = entry[1]
        self.state = self._project(self.s)

    def _work(self):
        """A copy of A's drift and y columns, and views of its e and de columns.

        A spare one (a rejected trial's or a replaced state's), one from the pool,
        else a new one.
        """
        work = self._spare
        if work is not None:
            self._spare = None
            return work
        data, k, p, n = self.data, self.k, self.p, self.n
        m, half = data.m, data.m // 2
        if self._pooled:
            a, e, de, mirror = self._pooled.pop()
            a[:, n] = data.yw
            return a, e, de, (mirror[0], data.tau[:m - half], mirror[2], mirror[3])
        a = np.empty((m, n + 1), dtype=complex, order='F')
        a[:, :p] = self.drift
        a[:, n] = data.yw
        e, de = a[:, p:p + k], a[:, p + k:n]
        mirror = (e[:m - half], data.tau[:m - half], e[half - 1::-1], e[m - half:]) \
            if data.mirror else None
        return a, e, de, mirror

    def release(self):
        """Give the work arrays back to the pool (the results are no longer read)."""
        if self._pooled is not None:
            for work in (self._spare, self._kept, self.state[1] if self.state[0] == 'qr'
                         else None):
                if work is not None and all(work is not w for w in self._pooled):
                    self._pooled.append(work)
            self._spare = self._kept = None

    def _recycle(self, state):
        if state[0] == 'qr' and state[1] is not self._kept:
            self._spare = state[1]

    @property
    def cost(self) -> float:
        return self.state[-1]

    def _project(self, poles):
        """The linear solution at ``poles``.

        ('qr', A, QR, R's lower-right block as lists, amplitudes, step, its decrease,
        cost) (:func:`_block_solution`; step None if not finite), or ('lstsq', e, de,
        amplitudes and drift, residual, cost).
        """
        data, k, p, n = self.data, self.k, self.p, self.n
        if self.qr:
            s = poles
            work = self._work()
            a, e, de, mirror = work
            if data.tau is not None:
                if mirror:               # exp(s tau) at -tau is 1 / exp(s tau)
                    head, tau, source, target = mirror
                    np.exp(np.multiply(tau, s, out=head), out=head)
                    np.divide(1.0, source, out=target)
                else:
                    np.exp(np.multiply(data.tau, s, out=e), out=e)
                if data.scale is not None:
                    e *= data.scale
                np.multiply(data.tau, e, out=de)
            else:
                e[...], de[...] = data.exponentials(np.array(s))
            qr, _, _, info = lapack.zgeqrf(a, lwork=n + 1)
            if info == 0:
                block = qr[p - 1:n + 1, p - 1:n + 1].tolist()
                try:
                    amplitudes, step, decrease, cost = _block_solution(block, k)
                except ZeroDivisionError:
                    amplitudes, step = [math.nan], None
                if _finite(amplitudes) and math.isfinite(cost):
                    if step is not None and not _finite(step):
                        step = None
                    return 'qr', work, qr, block, amplitudes, step, decrease, cost
            e, de = e.copy(), de.copy()
        else:
            e, de = data.exponentials(np.array(poles))
        basis = np.concatenate((e, self.drift), axis=1)
        lin = _solve(basis, data.yw)
        residual = data.yw - basis @ lin
        return 'lstsq', e, de, lin, residual, float(np.vdot(residual, residual).real)

    def _columns(self, state):
        """(e, de) of a projection."""
        if state[0] == 'qr':
            return state[1][1], state[1][2]
        return state[1], state[2]

    def _linear(self, state):
        """(amplitudes, drift coefficients, residual) of a projection.

        For a 'qr' one, the drift coefficients and the residual as functions that
        compute them.
        """
        k, p, n = self.k, self.p, self.n
        if state[0] == 'lstsq':
            lin = state[3]
            return lin[:k], lin[k:], state[4]
        a, qr = state[1][0], state[2]
        amplitudes = np.array(state[4])
        solved: list[np.ndarray] = []

        def drift():                     # R_dd x = c_d - R_de amplitudes
            if solved:
                return solved[0]
            try:
                x = np.array(_drift_solve(qr[:p, :n + 1].tolist(), p, state[4]))
            except ZeroDivisionError:    # (a singular drift: not met)
                x = np.linalg.lstsq(a[:, :p], a[:, n] - a[:, p:p + k] @ amplitudes,
                                    rcond=None)[0]
            solved.append(x)
            return x

        def residual():
            x = solved[0] if solved else drift()
            return self.data.yw - a[:, :p] @ x - a[:, p:p + k] @ amplitudes
        return amplitudes, drift, residual

    def _direction(self, state):
        """The Gauss-Newton step of the poles and the decrease of the cost it predicts.

        Kaufman's variable-projection Jacobian; the decrease is inf when not known.
        """
        k = self.k
        if state[0] == 'qr' and state[5] is not None:
            return state[5], state[6]
        e, de = self._columns(state)
        amplitudes, _, residual = self._linear(state)
        if callable(residual):           # (a 'qr' projection without a finite step)
            residual = residual()
        step = _solve(np.concatenate((de * amplitudes, e, self.drift), axis=1),
                      residual)[:k]
        return step.tolist(), math.inf

    def done(self, tolerance) -> bool:
        """Whether :meth:`run` to ``tolerance`` would not iterate (any more)."""
        return (self.left <= 0 or self.stuck or self.moved < tolerance
                or self.pending_size < tolerance)

    @property
    def poles(self) -> list[complex]:
        """The poles, after a pending step."""
        if self.pending is None:
            return self.s
        return self._clip([x + d for x, d in zip(self.s, self.pending)])

    def _clip(self, poles):
        limit = self.decay_limit
        if max(abs(x.real) for x in poles) > limit:
            return [complex(min(max(x.real, -limit), limit), x.imag) for x in poles]
        return poles

    def run(self, tolerance, iterations=None, ahead=_AHEAD):
        """Iterate until an update moves the poles by less than ``tolerance`` rad.

        Or for at most ``iterations`` in this call; ``ahead``: see the class.
        """
        window = self.window
        stop = -1 if iterations is None else self.left - iterations
        while not self.done(tolerance) and self.left > stop:
            if self.pending is None:
                self.left -= 1
                step, decrease = self._direction(self.state)
                size = max(map(abs, step)) * window
                # the next step's length if the steps keep shrinking as the last two did
                after = size * size / self.last if self.last else math.inf
                if size < tolerance or after < ahead * tolerance:
                    self.pending, self.decrease = step, decrease
                    self.pending_size = size if size < tolerance else after / ahead
                    break
            else:                                # a pending step, now too long
                step, self.pending, self.pending_size = self.pending, None, math.inf
                size = max(map(abs, step)) * window
                decrease = self.decrease
            scale = 1.0
            while True:
                trial = self._clip([x + scale * d for x, d in zip(self.s, step)])
                new = self._project(trial)
                if new[-1] <= self.cost:
                    break
                self._recycle(new)
                scale *= 0.25
                # no descent: at the minimum to rounding
                if scale <= 1e-4 or decrease <= _MEASURABLE * self.cost:
                    self.stuck = True
                    break
            if self.stuck:
                break
            self.moved = max(abs(x - y) for x, y in zip(trial, self.s)) * window
            self.last = size if scale == 1.0 else 0.0
            self._recycle(self.state)
            self.s, self.state = trial, new
        return self

    def result(self, covariance=True) -> _Fit:
        """The fit at the current poles.

        ``covariance``: also the parameters' variances (in units of the noise
        variance; else NaN).
        """
        k, p, n = self.k, self.p, self.n
        state = self.state
        if state[0] == 'qr':     # its columns stay: the result reads them
            self._kept = state[1]
        if self.pending is not None and state[0] == 'qr':
            return self._stepped(covariance)
        amplitudes, coefficients, residual = self._linear(state)
        noise_var = state[-1] / max(self.data.m - n, 1)
        pole_unit = [math.nan] * k
        drift_unit = None
        if covariance and state[0] == 'qr':
            # The diagonal of (J^H J)^-1: the squared row norms of R^-1, the poles'
            # divided by |amplitude|^2. The poles' rows are those of R's last block's
            # inverse (R is triangular).
            norms = _inverse_row_norms(state[3], k + 1, k)
            pole_unit = [x / abs(a) ** 2 if a else math.inf
                         for x, a in zip(norms, state[4])]
            r = state[2][:n, :n]

            def drift_unit():        # the rows of R^-1 are the columns of R^-T
                columns, info = lapack.ztrtrs(r, _identity(n, p), trans=1)
                if info != 0:
                    return np.full(p, np.inf)
                columns = np.abs(columns)
                return (columns * columns).sum(axis=0)
        elif covariance:
            e, de = self._columns(state)
            jac = np.concatenate((de * amplitudes, e, self.drift), axis=1)
            try:
                unit = np.abs(np.diag(np.linalg.inv(jac.conj().T @ jac)).real)
            except np.linalg.LinAlgError:
                unit = np.full(n, np.inf)
            pole_unit, drift_unit = unit[:k].tolist(), unit[2 * k:]
        top = None
        if covariance and state[0] == 'qr':
            row, amps = state[3][0], state[4]      # R's row of the last drift term
            try:
                top = ((row[2 * k + 1] - sum(r * a for r, a in zip(row[1:k + 1], amps)))
                       / row[0], _first_row_norm(state[3], k))
            except ZeroDivisionError:
                pass
        amplitudes = state[4] if state[0] == 'qr' else amplitudes.tolist()
        return _Fit(list(self.poles), amplitudes, coefficients, residual, noise_var,
                    pole_unit, p - 1, drift_unit, top)

    def _stepped(self, covariance):
        """:meth:`result` after a pending step, from the Gauss-Newton model.

        The least-squares fit of y by [drift, e, de] (R z = c), whose drift and e
        coefficients are those after the step to second order in it.
        """
        k, p, n = self.k, self.p, self.n
        _, work, qr, block, amplitudes, _, _, _ = self.state
        tail = _tail_solve(block, k)     # z from the last drift term on
        y = self.data.yw
        solved: list[np.ndarray] = []

        def drift():
            if solved:
                return solved[0][:p]
            try:
                z = np.array(_drift_solve(qr[:p - 1, :n + 1].tolist(), p - 1, tail) + tail)
            except ZeroDivisionError:    # (a singular drift: not met)
                z = np.linalg.lstsq(work[0][:, :n], y, rcond=None)[0]
            solved.append(z)
            return z[:p]

        def residual():
            if not solved:
                drift()
            return y - work[0][:, :n] @ solved[0]
        pole_unit = [math.nan] * k
        drift_unit = top = None
        if covariance:
            norms = _inverse_row_norms(block, k + 1, k)
            pole_unit = [x / abs(a) ** 2 if a else math.inf for x, a in zip(norms, amplitudes)]
            r = qr[:n, :n]

            def drift_unit():
                columns, info = lapack.ztrtrs(r, _identity(n, p), trans=1)
                if info != 0:
                    return np.full(p, np.inf)
                columns = np.abs(columns)
                return (columns * columns).sum(axis=0)
            top = (tail[0], _first_row_norm(block, k))
        noise_var = abs(block[2 * k + 1][2 * k + 1]) ** 2 / max(self.data.m - n, 1)
        return _Fit(list(self.poles), tail[1:k + 1], drift, residual,
                    noise_var, pole_unit, p - 1, drift_unit, top)


def _fit(data, s, degree, window, tolerance=_TOLERANCE, covariance=True,
         iterations=_MAX_ITERATIONS):
    """Least squares over poles ``s`` (1/s), amplitudes and drift, from start poles ``s``.

    Variable projection: the amplitudes and drift are solved exactly for each trial of
    the poles; the poles move along the Gauss-Newton direction of the joint problem
    (Kaufman's approximation), shortened until the residual decreases. Stops when an
    update moves every pole's phase over the window by less than ``tolerance`` rad, or
    after ``iterations``. ``covariance``: also the parameters' variances (else NaN).
    (:class:`_Fitter` does it.)
    """
    return _Fitter(data, s, degree, window, iterations).run(tolerance).result(covariance)


def _correlation_inflation(r) -> float:
    """Variance inflation (1 + rho) / (1 - rho) for a residual with lag-1 correlation rho.

    White noise leaves a residual with rho ~ 0 (factor ~ 1). A model misfit (the
    motion is not two steady whirls on a smooth drift, e.g. a window across a kink
    of w') leaves a smooth residual, rho near 1: the white-noise variances would
    then understate the frequencies' uncertainty by this factor (an AR(1) residual
    has that many times fewer independent samples).
    """
    power = float(np.vdot(r, r).real)
    if not power > 0.0 or len(r) < 3:
        return 1.0
    rho = float(np.vdot(r[:-1], r[1:]).real) / power
    rho = min(max(rho, 0.0), 0.999)
    return (1.0 + rho) / (1.0 - rho)


@functools.lru_cache(maxsize=16)
def _deflation(m, degree):
    """Orthonormal drift basis on m regular points, |its projection of a tone|^2, nfft."""
    nfft = 1 << int(math.ceil(math.log2(_ZERO_PAD * m)))
    q = np.linalg.qr(legendre.legvander(np.linspace(-1, 1, m), degree))[0]
    captured = np.sum(np.abs(np.fft.fft(q, nfft, axis=0)) ** 2, axis=1)
    return q, np.maximum(m - captured, 0.0), nfft


def _peak(stat, freqs, allowed):
    """Frequency (Hz) of the largest ``stat`` where allowed, parabolic between bins."""
    masked = np.where(allowed, stat, -1.0)
    k = int(np.argmax(masked))
    if masked[k] <= 0:
        return math.nan
    f = freqs[k]
    lo, hi = masked[k - 1], masked[(k + 1) % len(masked)]
    if lo > 0 and hi > 0:
        a, b, c = np.log(lo), np.log(masked[k]), np.log(hi)
        if a - 2 * b + c < 0:
            f += 0.5 * (a - c) / (a - 2 * b + c) * (freqs[1] - freqs[0])
    return float(f)


def _start_values(grid, interval, cfg, window):
    """Start poles (1/s): the strongest whirl, then the strongest of the other sign.

    With the drift projected out (y_perp), the first is the frequency that captures
    most energy, |b_f^H y_perp|^2 for a tone b_f at f; it is then fitted. The second
    maximizes |b_f^H r|^2 / |b_f_perp|^2 in the residual r: the likelihood-ratio test
    of one tone against the drift alone, which also finds a whirl so slow that the
    drift takes most of it. (With two whirls present the ratio is not safe for the
    first: the little the drift leaves of a slow tone makes the other whirl's leakage
    look large at low frequency.)
    """
    q, tone_norm, nfft = _deflation(grid.m, cfg.drift_degree)
    freqs = np.fft.fftfreq(nfft, interval)
    in_band = ((np.abs(freqs) >= cfg.min_cycles / window)
               & (np.abs(freqs) <= cfg.max_frequency) & (tone_norm > 1e-9 * grid.m))
    y_perp = grid.y - q @ (q.T @ grid.y)
    f_first = _peak(np.abs(np.fft.fft(y_perp, nfft)) ** 2, freqs, in_band)
    if math.isnan(f_first):
        return []
    first = _fit(grid, [1j * TWO_PI * f_first], cfg.drift_degree, window, tolerance=1e-3,
                 covariance=False, iterations=_START_ITERATIONS)
    f_first = first.s[0].imag / TWO_PI
    other = in_band & (freqs * f_first < 0)
    ratio = np.abs(np.fft.fft(first.residual, nfft)) ** 2 / np.where(in_band, tone_norm, 1.0)
    f_second = _peak(ratio, freqs, other)
    return [first.s[0]] + ([] if math.isnan(f_second) else [1j * TWO_PI * f_second])


# -- estimate ------------------------------------------------------------------------

def _no_estimate(reason, **kw):
    return WhirlEstimate(reason=reason, **kw), []


def _block_gain(data, s):
    """Ratio of a block mean of exp(s tau) to exp(s tau) at the block's mean time."""
    if data.per_block == 1 or not data.regular:
        return np.ones(len(s))
    j = (np.arange(data.per_block) - 0.5 * (data.per_block - 1)) * data.dt
    return np.mean(np.exp(np.outer(s, j)), axis=1)


def _drift_degree(fit):
    """Highest drift degree whose coefficient stands out of the noise: |c| > 5 std(c).

    Strict on purpose: a drift term kept for noise costs the whirls up to tens of times
    their variance (it absorbs a slow whirl), one dropped while marginal biases them by
    less than the noise does.
    """
    degree = fit.degree
    while degree > 0:
        coefficient, unit = (fit.top if degree == fit.degree and fit.top is not None
                             else (fit.drift[degree], fit.drift_unit[degree]))
        if abs(coefficient) ** 2 > _DRIFT_SIGNIFICANCE * fit.noise_var * unit:
            break
        degree -= 1
    return degree


def _amplitudes(fit, data) -> list[float]:
    """|amplitude| of each fitted whirl, m (block means corrected for their gain)."""
    if data.per_block == 1 or not data.regular:
        return [abs(a) for a in fit.amplitudes]
    return np.abs(np.array(fit.amplitudes) / _block_gain(data, fit.s)).tolist()


def _snr_db(amplitude, noise_var) -> float:
    snr = amplitude * amplitude / noise_var if noise_var > 0 else math.inf
    return 10 * math.log10(snr) if snr > 0 else -math.inf


def _undetected(amplitude, noise_var, data, cfg) -> bool:
    """Whether a whirl is 'noise' (:func:`_whirls`)."""
    return (data.roundoff(amplitude)
            or _snr_db(amplitude, noise_var) + 10 * math.log10(data.samples)
            < cfg.detection_db)


def _whirls(fit, data, cfg, window):
    """(name, whirl, kind, problem, pole) per fitted pole; kind, problem '' if accepted.

    kind: 'noise' (not detected), 'band', 'decay' or 'std' (see the module docstring).
    """
    poles = fit.s
    noise_var = fit.noise_var
    c_pole = fit.pole_unit
    amplitudes = _amplitudes(fit, data)
    threshold_db = cfg.detection_db
    out = []
    for i, pole in enumerate(poles):
        f = abs(pole.imag) / TWO_PI
        decay = -pole.real
        amp = amplitudes[i]
        snr_db = _snr_db(amp, noise_var)
        total_db = snr_db + 10 * math.log10(data.samples)
        std = math.sqrt(0.5 * noise_var * c_pole[i] * fit.inflation) / TWO_PI
        kind, problem = '', ''
        if data.roundoff(amp):
            kind, problem = 'noise', 'no oscillation (amplitude at float round-off of the offset)'
        elif total_db < threshold_db:
            kind, problem = 'noise', (f'no oscillation above the noise ({total_db:.1f} dB < '
                                      f'{threshold_db:g} dB over the window)')
        elif not cfg.min_cycles / window <= f <= cfg.max_frequency:
            kind, problem = 'band', f'frequency {f:.4g} Hz outside the band'
        elif abs(decay) * window > cfg.max_decay:
            kind, problem = 'decay', (f'decays or grows by {abs(decay) * window:.2g} Np over '
                                      f'the window (> {cfg.max_decay:g})')
        elif not std <= cfg.max_relative_std * f:
            kind, problem = 'std', (f'frequency too uncertain: std {std:.2g} Hz > '
                                    f'{cfg.max_relative_std:g} x {f:.4g} Hz')
        whirl = Whirl(frequency=math.nan if kind else f,
                      amplitude=_scaled(amp, data.exponent) if data.exponent else amp,
                      decay_rate=decay, snr_db=snr_db, frequency_std=std)
        out.append(('forward' if pole.imag > 0 else 'backward', whirl, kind, problem, pole))
    return out


def _estimate(t, z, cfg: WhirlSettings, start=None, halves=None):
    """The estimate of one window, and the poles (1/s) of its whirls.

    The model is linear in z: the fit runs on z scaled by a power of two (exact) to
    a largest component in [1, 2), so that squares neither overflow (|z| ~ 1e300)
    nor underflow (|z| ~ 1e-300); amplitudes, offset and noise are scaled back.
    ``halves``: the half-window fits of earlier windows (:func:`_split_check`).
    """
    if isinstance(halves, _Memo):
        halves.exponent = 0
    if len(z) == 0:
        return _estimate_unit(t, z, cfg, start, halves)
    try:
        parts = z.view(np.float64)
    except ValueError:                   # (not contiguous)
        parts = np.concatenate((z.real, z.imag))
    largest = float(np.abs(parts).max())
    if largest == 0:
        return _estimate_unit(t, z, cfg, start, halves)
    e = math.frexp(largest)[1] - 1
    if isinstance(halves, _Memo):
        halves.exponent = e
    if -1000 < e < 1000:
        unit = z * math.ldexp(1.0, -e)
    else:
        unit = np.empty_like(z)
        unit.real, unit.imag = np.ldexp(z.real, -e), np.ldexp(z.imag, -e)
    # (amplitudes, offset and noise are scaled back as the estimate is made: _scaled)
    return _estimate_unit(t, unit, cfg, start, halves, e)


def _scaled(x: float, exponent: int) -> float:
    """X 2^exponent (inf past the float range)."""
    try:
        return math.ldexp(x, exponent)
    except OverflowError:
        return math.copysign(math.inf, x)


def _estimate_unit(t, z, cfg: WhirlSettings, start=None, halves=None, exponent=0):
    """:func:`_estimate` on data of order 1: z 2^exponent are the samples.

    The poles include whirls rejected for decay or uncertainty: they are the start
    values for the next window. ``start``: poles to start from (else searched).
    """
    n = len(t)
    if n < 2:
        return _no_estimate(f'too few samples ({n})', samples=n)
    span = float(t[-1] - t[0])
    steps = t[1:] - t[:-1]
    gap = float(steps.max())
    if gap > cfg.max_gap * span:
        return _no_estimate(f'gap of {gap:.3g} s between samples (> {cfg.max_gap:g} of the '
                            f'{span:.3g} s window)', samples=n, window=span)
    dt = _median(steps)
    # (a subnormal dt makes the ratio inf: more samples per block than there are)
    per_block = max(1, int(math.floor(min(cfg.block_interval / dt, n + 1.0) + 1e-6)))
    if n // per_block < cfg.min_blocks:
        return _no_estimate(f'window too short: {n} samples make {n // per_block} blocks of '
                            f'{per_block}, {cfg.min_blocks} needed', samples=n, window=span)
    data = _Blocks(t, z, per_block, cfg.drift_degree, steps, dt, bound=_UNIT_BOUND)
    data.exponent = exponent
    window = 2.0 * data.half_span
    common = dict(time=data.t_centre, window=window, samples=data.samples)
    if data.m < cfg.min_blocks or len(data.grid) < cfg.min_blocks:
        return _no_estimate(f'window too short: {data.m} blocks, {cfg.min_blocks} needed',
                            **common)
    memo = halves if isinstance(halves, _Memo) else None
    regular_dt = data.dt if data.regular else None
    if start:
        warm, lost, poles = _fitted_estimate(data, cfg, window, start, common, memo)
        if not lost:
            return _split_check(t, z, cfg, per_block, warm, poles, halves, regular_dt), poles
    grid = _Grid(data.grid, data.grid_tau, cfg.drift_degree)
    poles = _start_values(grid, data.interval, cfg, window)
    if not poles:
        return _no_estimate('no frequency in the band', **common)
    estimate, _, poles = _fitted_estimate(data, cfg, window, poles, common, memo)
    return _split_check(t, z, cfg, per_block, estimate, poles, halves, regular_dt), poles


def _half_whirls(t, z, cfg, per_block, poles, memo=None, dt=None):
    """{'forward'/'backward': (frequency, its white-noise std), Hz} over (t, z).

    The whole window's procedure (all drift terms, then the significant ones) from the
    whole window's poles. A whirl not detected above the noise is left out, and so is
    a sign with two poles; nothing when the samples make fewer than ``min_blocks``
    blocks. The standard deviation is the one for a white residual (not inflated):
    the spread of the frequency if the model fits. ``dt``: the window's sample
    interval when its samples are regular (so are the half's).

    When the drift terms are dropped (the last half did so too, or no ``memo``), the
    choice is made from the fit with all of them once its poles move by less than
    ``_DECISION_TOLERANCE`` or after ``_DECISION_ITERATIONS``: such a fit over half a
    window often lets the drift take the whirls, and wanders slowly through a flat
    minimum far from the whirls' poles (no more than noise decides where it ends);
    the fit that follows starts from the whole's poles. When that fit keeps them all,
    it runs to the end and decides again.
    """
    if len(t) // per_block < cfg.min_blocks:
        return {}
    data = _Blocks(t, z, per_block, cfg.drift_degree, dt=dt, regular=dt is not None,
                   bound=_UNIT_BOUND)
    if data.m < cfg.min_blocks:
        return {}
    window = 2.0 * data.half_span
    pool = memo.pool if memo is not None else None
    fitters = [_Fitter(data, poles, cfg.drift_degree, window, pool=pool)]
    fitter = fitters[0]
    if memo is None or memo.half_drops is not False:
        fitter.run(_DECISION_TOLERANCE, _DECISION_ITERATIONS)
    else:
        fitter.run(_SPLIT_TOLERANCE, ahead=_HALF_AHEAD)
    while True:
        fit = fitter.result()
        degree = _drift_degree(fit)
        if degree < cfg.drift_degree or fitter.done(_SPLIT_TOLERANCE):
            break
        fitter.run(_SPLIT_TOLERANCE, ahead=_HALF_AHEAD)
    if memo is not None:
        memo.half_drops = degree < cfg.drift_degree
    if degree < cfg.drift_degree:
        # from the whole's poles: all drift terms may take a whirl over a half window,
        # and move its pole far (a start there found a wrong minimum now and then)
        fitters.append(_Fitter(data, poles, degree, window, pool=pool))
        fit = fitters[-1].run(_SPLIT_TOLERANCE, ahead=_HALF_AHEAD).result()
    found: dict[str, list] = {}      # per sign: (frequency, std) or None if undetected
    for pole, amplitude, unit in zip(fit.s, _amplitudes(fit, data), fit.pole_unit):
        found.setdefault('forward' if pole.imag > 0 else 'backward', []).append(
            None if _undetected(amplitude, fit.noise_var, data, cfg) else
            (abs(pole.imag) / TWO_PI, math.sqrt(0.5 * fit.noise_var * unit) / TWO_PI))
    for used in fitters:
        used.release()
    return {name: fits[0] for name, fits in found.items()
            if len(fits) == 1 and fits[0] is not None}


_KEPT_HALVES = 64
_LEGENDRE_AT_0 = (1.0, 0.0, -0.5, 0.0, 0.375, 0.0, -0.3125, 0.0, 0.2734375)  # P_j(0), j <= 8
"""Half-window fits an online estimator keeps (the newest)."""


class _Memo(dict):
    """An online estimator's memory of earlier windows.

    Its half-window fits (the dict, by the half's samples as given), whether the last
    whole and half windows dropped drift terms or components (None: not known), and
    the fits' work arrays. The latter two order the work and spare allocations
    (:func:`_fitted_estimate`, :func:`_half_whirls`, :class:`_Fitter`).
    """

    whole_drops: bool | None = None
    half_drops: bool | None = None
    exponent = 0            # the window's samples are scaled by 2^-exponent (_estimate)

    def __init__(self):
        super().__init__()
        self.pool: dict = {}                # the fits' work arrays (_Fitter)


def _kept_half_whirls(halves, t, z, cfg, per_block, poles, dt=None):
    """:func:`_half_whirls`, from ``halves`` when these samples were fitted before."""
    if halves is None or not len(t):
        return _half_whirls(t, z, cfg, per_block, poles, None, dt)
    memo = halves if isinstance(halves, _Memo) else None
    # by the samples as given (the fit is on them scaled by a power of two, which gives
    # the same frequencies to the bit)
    e = memo.exponent if memo is not None else 0
    first, last = z[[0, -1]].tolist()
    key = (float(t[0]), float(t[-1]), len(t), math.ldexp(first.real, e),
           math.ldexp(first.imag, e), math.ldexp(last.real, e), math.ldexp(last.imag, e),
           per_block)
    found = halves.get(key)
    if found is None:
        found = halves[key] = _half_whirls(t, z, cfg, per_block, poles, memo, dt)
        if len(halves) > _KEPT_HALVES:
            del halves[next(iter(halves))]
    return found


def _split_check(t, z, cfg, per_block, estimate, poles, halves=None, dt=None):
    """``estimate`` without the whirls whose halves of the window disagree with the whole.

    A whirl is rejected when the mean of its frequencies over the two halves differs
    from its frequency over the whole by more than ``cfg.max_split_change`` of it and
    by more than ``_SPLIT_SIGMAS`` standard deviations of that mean for a white
    residual: a difference that matters and that noise does not explain (a slow whirl
    that the drift takes over a half window has a large standard deviation there, and
    is not judged on it). Whirls a half does not detect, and windows too short to fit
    the model over each half (fewer than ``min_blocks`` blocks), are not checked.

    ``halves`` (a dict, the online estimator's): half-window fits kept from earlier
    windows, by the half's samples. A sliding window whose update interval divides
    half the window meets its first half again as an earlier window's second half:
    the same samples, fitted to the same tolerance (from that window's poles).
    ``dt``: the window's sample interval when its samples are regular.
    """
    accepted = [name for name in ('forward', 'backward')
                if not math.isnan(getattr(estimate, name).frequency)]
    if not accepted or math.isinf(cfg.max_split_change):
        return estimate
    poles = [complex(x) for x in poles]
    half = len(t) // 2
    first = _kept_half_whirls(halves, t[:half], z[:half], cfg, per_block, poles, dt)
    second = _kept_half_whirls(halves, t[half:], z[half:], cfg, per_block, poles, dt)
    changes, reasons = {}, [estimate.reason] if estimate.reason else []
    for name in accepted:
        if name not in first or name not in second:    # a half cannot judge it
            continue
        whirl = getattr(estimate, name)
        (f_a, std_a), (f_b, std_b) = first[name], second[name]
        change = abs(0.5 * (f_a + f_b) - whirl.frequency)
        noise = _SPLIT_SIGMAS * 0.5 * math.hypot(std_a, std_b)
        if not change <= max(cfg.max_split_change * whirl.frequency, noise):
            changes[name] = dataclasses.replace(whirl, frequency=math.nan)
            reasons.append(f'{name}: not stationary over the window (its halves give '
                           f'{f_a:.4g} and {f_b:.4g} Hz, the whole {whirl.frequency:.4g} Hz)')
    if not changes:
        return estimate
    return dataclasses.replace(estimate, reason='; '.join(reasons), **changes)


def _fitted_estimate(data, cfg, window, poles, common, memo=None):
    """Fit from start ``poles``, choose the drift, judge and name the whirls.

    Returns the estimate, whether a whirl was lost (a sign without a detected, in-band
    component: a start from the previous estimate then needs a fresh search), and the
    poles of the whirls detected in band. ``memo``: see :class:`_Memo`.
    """
    # Refit with the significant drift terms only, without components that are only
    # noise, and without the smaller of two components of one sign (they would model
    # together a modulation of one whirl, e.g. a chirp, and misplace it): none of these
    # may cost the whirls' frequencies precision. (When the last window dropped some,
    # or not known, decided from the fit with all drift terms once its poles move by
    # less than _DECISION_TOLERANCE, and again once it has converged if that drops
    # nothing.)
    pool = memo.pool if memo is not None else None
    fitter = _Fitter(data, poles, cfg.drift_degree, window, pool=pool)
    fitter.run(_DECISION_TOLERANCE if memo is None or memo.whole_drops is not False
               else _TOLERANCE)
    while True:
        fit = fitter.result()
        whirls = _whirls(fit, data, cfg, window)
        degree = _drift_degree(fit)
        largest: dict[str, tuple[float, int]] = {}
        for i, (name, whirl, kind, _, _) in enumerate(whirls):
            if kind != 'noise' and whirl.amplitude > largest.get(name, (-1.0, 0))[0]:
                largest[name] = (whirl.amplitude, i)
        keep = sorted(i for _, i in largest.values())
        refit = bool(keep) and (degree < cfg.drift_degree or len(keep) < len(whirls))
        if refit or fitter.done(_TOLERANCE):
            break
        fitter.run(_TOLERANCE)
    if memo is not None:
        memo.whole_drops = refit
    fitters = [fitter]
    if refit:
        fitters.append(_Fitter(data, [fit.s[i] for i in keep], degree, window, pool=pool))
        fit = fitters[-1].run(_TOLERANCE).result()
        dropped = [rec for rec in whirls if rec[0] not in largest]
        whirls = _whirls(fit, data, cfg, window) + dropped
    chosen: dict[str, tuple] = {}
    for name, whirl, kind, problem, pole in whirls:   # per sign: accepted, else largest
        rank = (kind == '', whirl.amplitude)
        if name not in chosen or rank > chosen[name][0]:
            chosen[name] = (rank, whirl, kind, problem, pole)
    reasons, lost = [], False
    for name in ('forward', 'backward'):
        if name not in chosen:
            reasons.append(f'{name}: none found')
            lost = True
        elif chosen[name][2]:
            reasons.append(f'{name}: {chosen[name][3]}')
            lost = lost or chosen[name][2] in ('noise', 'band')
    whirls_out = {name: c[1] for name, c in chosen.items()}
    if fit.inflation > _MISFIT_INFLATION and any(c[2] == 'std' for c in chosen.values()):
        # the model misfits the window, and one whirl's fit shows it: the other whirl,
        # fitted jointly, shares the misfit (measured on live windows: it was then up to
        # several times further off Eq. 28 than in windows where both pass)
        for name, c in chosen.items():
            if not c[2]:
                whirls_out[name] = dataclasses.replace(c[1], frequency=math.nan)
                reasons.append(f'{name}: fitted beside a whirl made too uncertain by a '
                               f'misfit of the model (residual correlation: variance '
                               f'x{fit.inflation:.3g})')
    offset = sum(c * p for c, p in zip(fit.drift.tolist(), _LEGENDRE_AT_0))
    e = data.exponent
    estimate = WhirlEstimate(
        forward=whirls_out.get('forward', Whirl()),
        backward=whirls_out.get('backward', Whirl()),
        offset=complex(_scaled(offset.real, e), _scaled(offset.imag, e)),
        noise_rms=_scaled(math.sqrt(fit.noise_var), e), reason='; '.join(reasons), **common)
    poles = [c[4] for c in chosen.values() if c[2] not in ('noise', 'band')]
    for used in fitters:
        used.release()
    return estimate, lost, poles


# -- a whole record ------------------------------------------------------------------

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
        forward_decay, backward_decay: decay rates of the whirls, 1/s (> 0: decays;
            0 for a steady whirl).
    """

    centre: complex
    forward: complex
    backward: complex
    forward_omega: float
    backward_omega: float
    residual: float
    forward_decay: float = 0.0
    backward_decay: float = 0.0

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


def fit_whirls(t, u, v, guess: tuple | None = None) -> WhirlFit:
    """A whole record (t s, u m, v m) fitted as a centre plus two whirls.

    The same least-squares fit as the estimator's (variable projection over the two
    poles, :func:`_fit`), on every sample (no blocks) and with a constant centre: for
    a record of free motion at constant w, such as a hold of a simulated run. The
    model is z(t) = c + a exp(s_f (t - t0)) + b exp(s_b (t - t0)), t0 = t[0], with
    s_f = -decay_f + i wf and s_b = -decay_b - i wb.

    Args:
        t: sample times, s, strictly increasing.
        u, v: the motion, m.
        guess: starting (wf, wb) in rad/s; by default the estimator's start values
            (the strongest whirl of each sign in the spectrum).

    Raises ValueError for unusable samples, fewer than 8, or a record without a
    whirl of each sign.
    """
    t, z = _samples(t, u, v)
    if len(t) < 8:
        raise ValueError('fit_whirls needs at least 8 samples')
    data = _Blocks(t, z, 1, 0)
    window = 2.0 * data.half_span
    if guess is None:
        dt = data.dt
        cfg = WhirlSettings(drift_degree=0, max_frequency=0.5 / dt, min_cycles=2.0)
        poles = _start_values(_Grid(data.grid, data.grid_tau, 0), dt, cfg, window)
    else:
        wf, wb = (finite_number('guess', x) for x in guess)
        poles = [1j * wf, -1j * wb]
    signs = sorted(np.sign(np.imag(poles)))
    if len(poles) != 2 or signs != [-1.0, 1.0]:
        raise ValueError('fit_whirls: the record does not hold a whirl of each sign')
    fit = _fit(data, poles, 0, window, tolerance=1e-13, covariance=False)
    forward, backward = (0, 1) if fit.s[0].imag > 0 else (1, 0)
    if not fit.s[forward].imag > 0 > fit.s[backward].imag:
        raise ValueError('fit_whirls: the fit did not keep a whirl of each sign')
    at_start = np.array(fit.amplitudes) * np.exp(np.array(fit.s) * (t[0] - data.t_centre))
    return WhirlFit(centre=complex(fit.drift[0]), forward=complex(at_start[forward]),
                    backward=complex(at_start[backward]),
                    forward_omega=float(fit.s[forward].imag),
                    backward_omega=float(-fit.s[backward].imag),
                    residual=float(np.sqrt(np.mean(np.abs(fit.residual) ** 2))),
                    forward_decay=float(-fit.s[forward].real),
                    backward_decay=float(-fit.s[backward].real))


# -- online --------------------------------------------------------------------------

class WhirlEstimator:
    """Whirl frequencies over a sliding window, fed one sample at a time.

    The window holds the samples of the last ``window`` seconds; every
    ``update_interval`` seconds of sample time (once the window has filled) ``push``
    runs :func:`estimate_whirl` on it, starting the fit from the previous estimate's
    whirls (and searching afresh when that start loses one). Samples may arrive
    irregularly (dropped, jittered): the estimate handles that, and reports NaN for a
    gap longer than ``settings.max_gap`` of the window. Memory is a ring of about
    twice the window. When ``update_interval`` divides half the window, a window's
    first half is an earlier window's second half: its fit for the stationarity check
    is kept and not repeated (each update then fits one half window, not two). It also
    remembers whether the last window's fits dropped drift terms (the next ones decide
    that first when they did: before the fit with all of them has converged to the
    end) and keeps the fits' work arrays; these change the cost, not the procedure.

    Args:
        window: length of the analysed window, s (1 s resolves whirls above 0.1 Hz).
        sample_interval: expected interval between samples, s (sizes the buffer;
            half of it is the tolerance on the window's edges).
        update_interval: sample time between estimates, s.
        settings: model and acceptance limits (:class:`WhirlSettings`).
        phase: sample time by which the first estimate after the window fills (and so
            every later one) comes later, s, 0 <= phase < update_interval: estimators
            filled at one instant (the rods of a world) update at different samples,
            their work spread over the interval instead of falling on one.
    """

    def __init__(self, window: float = 1.0, sample_interval: float = 1e-3,
                 update_interval: float = 0.1, settings: WhirlSettings | None = None,
                 phase: float = 0.0):
        self.window = finite_number('WhirlEstimator.window', window, positive=True)
        self.sample_interval = finite_number('WhirlEstimator.sample_interval',
                                             sample_interval, positive=True)
        self.update_interval = finite_number('WhirlEstimator.update_interval',
                                             update_interval, nonnegative=True)
        self.phase = finite_number('WhirlEstimator.phase', phase, nonnegative=True)
        if self.phase and not self.phase < self.update_interval:
            raise ValueError(f'WhirlEstimator.phase ({phase} s) must be shorter than the '
                             f'update interval ({update_interval} s)')
        if self.sample_interval >= self.window:
            raise ValueError(f'WhirlEstimator.sample_interval ({sample_interval} s) must be '
                             f'shorter than the window ({window} s)')
        if not self.window / self.sample_interval <= MAX_WINDOW_SAMPLES:
            raise ValueError(f'WhirlEstimator.window / sample_interval = '
                             f'{self.window / self.sample_interval:.3g} samples; at most '
                             f'{MAX_WINDOW_SAMPLES:g} (its buffer and tables grow with it)')
        self.settings = settings or WhirlSettings()
        capacity = 2 * int(math.ceil(self.window / self.sample_interval)) + 16
        self._t = np.empty(capacity)
        self._z = np.empty(capacity, dtype=complex)
        # the start-value tables for the expected window, now rather than in an update
        samples = int(round(self.window / self.sample_interval))
        per_block = max(1, int(math.floor(min(self.settings.block_interval
                                              / self.sample_interval, samples + 1.0) + 1e-6)))
        blocks = samples // per_block
        if blocks >= self.settings.min_blocks:
            _deflation(blocks, self.settings.drift_degree)
        self.reset()

    def reset(self) -> None:
        """Forget all samples and the last estimate."""
        self._begin = self._end = 0
        self._first = math.nan
        self._last_update = -math.inf
        self._poles: list[complex] = []
        self._halves = _Memo()
        self.estimate = WhirlEstimate(reason='window not filled')

    @property
    def filled(self) -> bool:
        """True once the samples span the window."""
        if self._end == 0:
            return False
        span = self._t[self._end - 1] - self._first
        return span >= self.window - 1.5 * self.sample_interval

    def push(self, t: float, u: float, v: float) -> WhirlEstimate | None:
        """Add one sample (t in s, u and v in m); the new estimate if one was due, else None.

        Raises ValueError for a non-finite value or a time not after the previous one
        (the sample is then not stored).
        """
        if not (type(t) in _FLOATS and type(u) in _FLOATS and type(v) in _FLOATS
                and math.isfinite(t + u + v)):     # (a float sum overflows: checked below)
            t, u, v = (finite_number(name, x) for name, x in (('t', t), ('u', u), ('v', v)))
        if self._end and not t > self._t[self._end - 1]:
            raise ValueError(f'sample times must increase strictly: {t!r} s after '
                             f'{self._t[self._end - 1]!r} s')
        if self._end == len(self._t):
            self._make_room()
        self._t[self._end] = t
        self._z[self._end] = complex(u, v)
        self._end += 1
        if math.isnan(self._first):
            self._first = t
        if self.filled:
            if self._last_update == -math.inf:    # just filled: the first one is due
                self._last_update = t + self.phase - self.update_interval
            if t - self._last_update >= self.update_interval * (1 - 1e-9):
                return self.update()
        return None

    def update(self) -> WhirlEstimate:
        """Estimate from the current window now (NaN until the window has filled)."""
        if not self.filled:
            span = self._t[self._end - 1] - self._first if self._end else 0.0
            self.estimate = WhirlEstimate(reason=f'window not filled ({span:.3g} of '
                                                 f'{self.window:g} s)')
            return self.estimate
        newest = self._t[self._end - 1]
        oldest = newest - self.window + 0.5 * self.sample_interval
        self._begin += int(np.searchsorted(self._t[self._begin:self._end], oldest))
        self.estimate, self._poles = _estimate(self._t[self._begin:self._end],
                                               self._z[self._begin:self._end],
                                               self.settings, start=self._poles,
                                               halves=self._halves)
        self._last_update = newest
        return self.estimate

    def _make_room(self):
        """Drop samples older than the window; grow the ring if it is still full."""
        newest = self._t[self._end - 1]
        oldest = newest - self.window + 0.5 * self.sample_interval
        self._begin += int(np.searchsorted(self._t[self._begin:self._end], oldest))
        live = self._end - self._begin
        if live > len(self._t) // 2:
            self._t = np.concatenate((self._t, np.empty(len(self._t))))
            self._z = np.concatenate((self._z, np.empty(len(self._z), dtype=complex)))
        self._t[:live] = self._t[self._begin:self._end]
        self._z[:live] = self._z[self._begin:self._end]
        self._begin, self._end = 0, live


def stream_estimator(window: float, sample_rate: float, update_rate: float,
                     stagger: int = 0) -> WhirlEstimator | None:
    """The estimator over a published stream, as the simulator node and its bags run it.

    ``window`` s of samples published at ``sample_rate`` Hz, an estimate every
    1/``update_rate`` s of sample time; None when ``window`` is 0 (estimates off).
    ``stagger``: the k-th rod of a world (0: the first, and a single rod) updates
    k samples later, modulo the samples per update (:attr:`WhirlEstimator.phase`).
    """
    if not window:
        return None
    per_update = max(1, int(round(sample_rate / update_rate)))
    return WhirlEstimator(window, 1.0 / sample_rate, 1.0 / update_rate,
                          phase=(stagger % per_update) / sample_rate)
