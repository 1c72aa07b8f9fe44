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
MAX_WINDOW_SAMPLES = 1e6    # longest online window, in sample intervals (docs/realtime.md)


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

class _Blocks:
    """Block means y of the samples, the drift basis and the exponential basis on them.

    Rows are weighted by sqrt(samples in the block), so that the least-squares fit of
    the block means is the least-squares fit of the samples.
    """

    def __init__(self, t, z, per_block, degree):
        steps = np.diff(t)
        self.dt = float(np.median(steps))
        self.regular = bool(np.all(np.abs(steps - self.dt) <= _REGULAR_JITTER * self.dt))
        if self.regular:     # whole blocks: the oldest len(t) % per_block samples go
            keep = len(t) // per_block * per_block
            t, z = t[len(t) - keep:], z[len(z) - keep:]
        n = len(t)
        self.samples = n
        self.per_block = per_block
        self.interval = per_block * self.dt
        self.t_centre = 0.5 * (t[0] + t[-1])
        self.half_span = 0.5 * (t[-1] - t[0])
        self.z_scale = float(np.max(np.abs(z)))
        tau = t - self.t_centre
        if self.regular:
            m = n // per_block
            tb = tau.reshape(m, per_block).mean(axis=1)
            self.y = z.reshape(m, per_block).mean(axis=1)
            self.weight = np.full(m, math.sqrt(per_block))
            self._tau, self._starts = tb, None
            self.grid, self.grid_tau = self.y, tb
            drift = legendre.legvander(tb / self.half_span, degree)
        else:
            # blocks counted back from the newest sample; empty blocks simply absent
            index = np.floor((t[-1] + 0.5 * self.dt - t) / self.interval).astype(int)
            starts = np.concatenate(([0], np.flatnonzero(np.diff(index)) + 1))
            counts = np.diff(np.append(starts, n)).astype(float)
            self.y = np.add.reduceat(z, starts) / counts
            self.weight = np.sqrt(counts)
            self._tau, self._starts, self._counts = tau, starts, counts
            drift = np.add.reduceat(legendre.legvander(tau / self.half_span, degree), starts,
                                    axis=0) / counts[:, None]
            self.grid, self.grid_tau = self._uniform_grid(t, z, per_block)
        self.m = len(self.y)
        self.drift = drift * self.weight[:, None]
        self.yw = self.y * self.weight

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
        tau = self._tau[:, None]
        e = np.exp(tau * s)
        de = tau * e
        if self._starts is not None:
            c = self._counts[:, None]
            e = np.add.reduceat(e, self._starts) / c
            de = np.add.reduceat(de, self._starts) / c
        w = self.weight[:, None]
        return e * w, de * w


class _Grid:
    """The regular block series (unweighted), for the start values."""

    def __init__(self, y, tau, degree):
        self.y, self.yw, self.tau = y, y, tau
        self.m = len(y)
        self.weight = np.ones(self.m)
        self.drift = legendre.legvander(tau / max(abs(tau[0]), abs(tau[-1])), degree)

    def exponentials(self, s):
        e = np.exp(self.tau[:, None] * s)
        return e, self.tau[:, None] * e


# -- fit -----------------------------------------------------------------------------

@dataclass
class _Fit:
    s: np.ndarray           # complex poles, 1/s
    amplitudes: np.ndarray  # complex block-mean amplitudes at the window centre, m
    drift: np.ndarray       # Legendre coefficients of the drift, m
    residual: np.ndarray    # weighted residual, m
    noise_var: float        # per-sample complex noise variance from the residual, m^2
    unit: np.ndarray        # variances of poles, amplitudes, drift in units of noise_var
    inflation: float = 1.0  # variance factor for a correlated residual (model misfit)


def _solve(a, b):
    """Least-squares solution of a x = b (Householder QR; SVD if that fails)."""
    _, x, info = lapack.zgels(a, b)
    x = x[:a.shape[1]]
    if info != 0 or not np.isfinite(x).all():
        x = np.linalg.lstsq(a, b, rcond=None)[0]
    return x


def _fit(data, s, degree, window, tolerance=1e-8, covariance=True,
         iterations=_MAX_ITERATIONS):
    """Least squares over poles ``s`` (1/s), amplitudes and drift, from start poles ``s``.

    Variable projection: the amplitudes and drift are solved exactly for each trial of
    the poles; the poles move along the Gauss-Newton direction of the joint problem
    (Kaufman's approximation), shortened until the residual decreases. Stops when an
    update moves every pole's phase over the window by less than ``tolerance`` rad, or
    after ``iterations``. ``covariance``: also the parameters' variances (else NaN).
    """
    s = np.asarray(s, dtype=complex)
    k = len(s)
    drift = data.drift[:, :degree + 1]
    decay_limit = 50.0 / window          # keeps exp() finite on a wild step

    def project(poles):
        e, de = data.exponentials(poles)
        basis = np.concatenate((e, drift), axis=1)
        lin = _solve(basis, data.yw)
        r = data.yw - basis @ lin
        return basis, de, lin, r, float(np.vdot(r, r).real)

    basis, de, lin, r, cost = project(s)
    for _ in range(iterations):
        step = _solve(np.concatenate((de * lin[:k], basis), axis=1), r)[:k]
        scale = 1.0
        while scale > 1e-4:
            trial = s + scale * step
            if np.abs(trial.real).max() > decay_limit:
                trial = np.clip(trial.real, -decay_limit, decay_limit) + 1j * trial.imag
            new = project(trial)
            if new[-1] <= cost:
                break
            scale *= 0.25
        else:
            break                        # no descent: at the minimum to rounding
        moved = float(np.max(np.abs(trial - s))) * window
        s, (basis, de, lin, r, cost) = trial, new
        if moved < tolerance:
            break
    jac = np.concatenate((de * lin[:k], basis), axis=1)
    unit = np.full(jac.shape[1], np.nan)
    if covariance:
        try:
            unit = np.abs(np.diag(np.linalg.inv(jac.conj().T @ jac)).real)
        except np.linalg.LinAlgError:
            unit[:] = np.inf
    return _Fit(s=s, amplitudes=lin[:k], drift=lin[k:], residual=r,
                noise_var=cost / max(data.m - jac.shape[1], 1), unit=unit,
                inflation=_correlation_inflation(r))


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
    degree = len(fit.drift) - 1
    first = 2 * len(fit.s)
    while degree > 0 and (abs(fit.drift[degree]) ** 2
                          <= _DRIFT_SIGNIFICANCE * fit.noise_var * fit.unit[first + degree]):
        degree -= 1
    return degree


def _whirls(fit, data, cfg, window):
    """(name, whirl, kind, problem, pole) per fitted pole; kind, problem '' if accepted.

    kind: 'noise' (not detected), 'band', 'decay' or 'std' (see the module docstring).
    """
    k = len(fit.s)
    noise_var = fit.noise_var
    c_pole = fit.unit[:k]
    amplitudes = np.abs(fit.amplitudes / _block_gain(data, fit.s))
    threshold_db = cfg.detection_db
    out = []
    for i in range(k):
        f = abs(fit.s[i].imag) / TWO_PI
        decay = -fit.s[i].real
        amp = float(amplitudes[i])
        snr = amp * amp / noise_var if noise_var > 0 else math.inf
        snr_db = 10 * math.log10(snr) if snr > 0 else -math.inf
        total_db = snr_db + 10 * math.log10(data.samples)
        std = math.sqrt(0.5 * noise_var * c_pole[i] * fit.inflation) / TWO_PI
        kind, problem = '', ''
        if amp <= _ROUNDOFF * data.z_scale:
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
        whirl = Whirl(frequency=math.nan if kind else f, amplitude=amp, decay_rate=decay,
                      snr_db=snr_db, frequency_std=std)
        out.append(('forward' if fit.s[i].imag > 0 else 'backward', whirl, kind, problem,
                    fit.s[i]))
    return out


def _estimate(t, z, cfg: WhirlSettings, start=None, halves=None):
    """The estimate of one window, and the poles (1/s) of its whirls.

    The model is linear in z: the fit runs on z scaled by a power of two (exact) to
    a largest component in [1, 2), so that squares neither overflow (|z| ~ 1e300)
    nor underflow (|z| ~ 1e-300); amplitudes, offset and noise are scaled back.
    ``halves``: the half-window fits of earlier windows (:func:`_split_check`).
    """
    if len(z) == 0:
        return _estimate_unit(t, z, cfg, start, halves)
    largest = float(max(np.max(np.abs(z.real)), np.max(np.abs(z.imag))))
    if largest == 0:
        return _estimate_unit(t, z, cfg, start, halves)
    e = math.frexp(largest)[1] - 1
    unit = np.empty_like(z)
    unit.real, unit.imag = np.ldexp(z.real, -e), np.ldexp(z.imag, -e)
    est, poles = _estimate_unit(t, unit, cfg, start, halves)

    def back(x):
        with np.errstate(over='ignore'):
            return float(np.ldexp(x, e))
    est = dataclasses.replace(
        est, offset=complex(back(est.offset.real), back(est.offset.imag)),
        noise_rms=back(est.noise_rms),
        forward=dataclasses.replace(est.forward, amplitude=back(est.forward.amplitude)),
        backward=dataclasses.replace(est.backward, amplitude=back(est.backward.amplitude)))
    return est, poles


def _estimate_unit(t, z, cfg: WhirlSettings, start=None, halves=None):
    """:func:`_estimate` on data of order 1.

    The poles include whirls rejected for decay or uncertainty: they are the start
    values for the next window. ``start``: poles to start from (else searched).
    """
    n = len(t)
    if n < 2:
        return _no_estimate(f'too few samples ({n})', samples=n)
    span = float(t[-1] - t[0])
    gap = float(np.max(np.diff(t)))
    if gap > cfg.max_gap * span:
        return _no_estimate(f'gap of {gap:.3g} s between samples (> {cfg.max_gap:g} of the '
                            f'{span:.3g} s window)', samples=n, window=span)
    dt = float(np.median(np.diff(t)))
    # (a subnormal dt makes the ratio inf: more samples per block than there are)
    per_block = max(1, int(math.floor(min(cfg.block_interval / dt, n + 1.0) + 1e-6)))
    if n // per_block < cfg.min_blocks:
        return _no_estimate(f'window too short: {n} samples make {n // per_block} blocks of '
                            f'{per_block}, {cfg.min_blocks} needed', samples=n, window=span)
    data = _Blocks(t, z, per_block, cfg.drift_degree)
    window = 2.0 * data.half_span
    common = dict(time=data.t_centre, window=window, samples=data.samples)
    if data.m < cfg.min_blocks or len(data.grid) < cfg.min_blocks:
        return _no_estimate(f'window too short: {data.m} blocks, {cfg.min_blocks} needed',
                            **common)
    if start:
        warm, lost, poles = _fitted_estimate(data, cfg, window, start, common)
        if not lost:
            return _split_check(t, z, cfg, per_block, warm, poles, halves), poles
    grid = _Grid(data.grid, data.grid_tau, cfg.drift_degree)
    poles = _start_values(grid, data.interval, cfg, window)
    if not poles:
        return _no_estimate('no frequency in the band', **common)
    estimate, _, poles = _fitted_estimate(data, cfg, window, poles, common)
    return _split_check(t, z, cfg, per_block, estimate, poles, halves), poles


def _half_whirls(t, z, cfg, per_block, poles):
    """{'forward'/'backward': (frequency, its white-noise std), Hz} over (t, z).

    The whole window's procedure (all drift terms, then the significant ones) from the
    whole window's poles. A whirl not detected above the noise is left out, and so is
    a sign with two poles; nothing when the samples make fewer than ``min_blocks``
    blocks. The standard deviation is the one for a white residual (not inflated):
    the spread of the frequency if the model fits.
    """
    if len(t) // per_block < cfg.min_blocks:
        return {}
    data = _Blocks(t, z, per_block, cfg.drift_degree)
    if data.m < cfg.min_blocks:
        return {}
    window = 2.0 * data.half_span
    fit = _fit(data, poles, cfg.drift_degree, window, tolerance=_SPLIT_TOLERANCE)
    degree = _drift_degree(fit)
    if degree < cfg.drift_degree:
        fit = _fit(data, fit.s, degree, window, tolerance=_SPLIT_TOLERANCE)
    whirls = _whirls(fit, data, cfg, window)
    names = [name for name, *_ in whirls]
    return {name: (abs(pole.imag) / TWO_PI, whirl.frequency_std / math.sqrt(fit.inflation))
            for name, whirl, kind, _, pole in whirls
            if kind != 'noise' and names.count(name) == 1}


_KEPT_HALVES = 64
"""Half-window fits an online estimator keeps (the newest)."""


def _kept_half_whirls(halves, t, z, cfg, per_block, poles):
    """:func:`_half_whirls`, from ``halves`` when these samples were fitted before."""
    if halves is None or not len(t):
        return _half_whirls(t, z, cfg, per_block, poles)
    key = (float(t[0]), float(t[-1]), len(t), complex(z[0]), complex(z[-1]), per_block)
    found = halves.get(key)
    if found is None:
        found = halves[key] = _half_whirls(t, z, cfg, per_block, poles)
        if len(halves) > _KEPT_HALVES:
            del halves[next(iter(halves))]
    return found


def _split_check(t, z, cfg, per_block, estimate, poles, halves=None):
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
    """
    accepted = [name for name in ('forward', 'backward')
                if not math.isnan(getattr(estimate, name).frequency)]
    if not accepted or math.isinf(cfg.max_split_change):
        return estimate
    poles = np.asarray(poles, dtype=complex)
    half = len(t) // 2
    first = _kept_half_whirls(halves, t[:half], z[:half], cfg, per_block, poles)
    second = _kept_half_whirls(halves, t[half:], z[half:], cfg, per_block, poles)
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


def _fitted_estimate(data, cfg, window, poles, common):
    """Fit from start ``poles``, choose the drift, judge and name the whirls.

    Returns the estimate, whether a whirl was lost (a sign without a detected, in-band
    component: a start from the previous estimate then needs a fresh search), and the
    poles of the whirls detected in band.
    """
    fit = _fit(data, poles, cfg.drift_degree, window)
    whirls = _whirls(fit, data, cfg, window)
    # Refit with the significant drift terms only, without components that are only
    # noise, and without the smaller of two components of one sign (they would model
    # together a modulation of one whirl, e.g. a chirp, and misplace it): none of these
    # may cost the whirls' frequencies precision.
    degree = _drift_degree(fit)
    largest: dict[str, tuple[float, int]] = {}
    for i, (name, whirl, kind, _, _) in enumerate(whirls):
        if kind != 'noise' and whirl.amplitude > largest.get(name, (-1.0, 0))[0]:
            largest[name] = (whirl.amplitude, i)
    keep = sorted(i for _, i in largest.values())
    if keep and (degree < cfg.drift_degree or len(keep) < len(whirls)):
        fit = _fit(data, fit.s[keep], degree, window)
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
    estimate = WhirlEstimate(
        forward=whirls_out.get('forward', Whirl()),
        backward=whirls_out.get('backward', Whirl()),
        offset=complex(legendre.legval(0.0, fit.drift)), noise_rms=math.sqrt(fit.noise_var),
        reason='; '.join(reasons), **common)
    poles = [c[4] for c in chosen.values() if c[2] not in ('noise', 'band')]
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
    at_start = fit.amplitudes * np.exp(fit.s * (t[0] - data.t_centre))
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
    is kept and not repeated (each update then fits one half window, not two).

    Args:
        window: length of the analysed window, s (1 s resolves whirls above 0.1 Hz).
        sample_interval: expected interval between samples, s (sizes the buffer;
            half of it is the tolerance on the window's edges).
        update_interval: sample time between estimates, s.
        settings: model and acceptance limits (:class:`WhirlSettings`).
    """

    def __init__(self, window: float = 1.0, sample_interval: float = 1e-3,
                 update_interval: float = 0.1, settings: WhirlSettings | None = None):
        self.window = finite_number('WhirlEstimator.window', window, positive=True)
        self.sample_interval = finite_number('WhirlEstimator.sample_interval',
                                             sample_interval, positive=True)
        self.update_interval = finite_number('WhirlEstimator.update_interval',
                                             update_interval, nonnegative=True)
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
        self._halves: dict = {}
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
        if self.filled and t - self._last_update >= self.update_interval * (1 - 1e-9):
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


def stream_estimator(window: float, sample_rate: float,
                     update_rate: float) -> WhirlEstimator | None:
    """The estimator over a published stream, as the simulator node and its bags run it.

    ``window`` s of samples published at ``sample_rate`` Hz, an estimate every
    1/``update_rate`` s of sample time; None when ``window`` is 0 (estimates off).
    """
    if not window:
        return None
    return WhirlEstimator(window, 1.0 / sample_rate, 1.0 / update_rate)
