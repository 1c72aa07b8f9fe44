"""Prescribed hub angular-velocity profiles w(t) (rad/s) with w'(t) and theta(t).

Each profile evaluates on floats and numpy arrays. ``angle(t)`` is the exact integral
of ``omega`` from 0 to t (rad). ``jumps()`` lists the instants at which omega jumps;
integrators apply the physical jump there (the mass keeps its absolute
velocity, see :func:`rotrod_core.model.equations.omega_jump`).

A time that is not a finite number is a ValueError. w and w' are finite at every
finite time (construction refuses a profile whose slope or phase overflows); the
angle grows without bound and is finite or a ValueError saying it overflows.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.interpolate import BSpline, PchipInterpolator
from scipy.special import fresnel

from rotrod_core.numerics.checks import finite_array, finite_number


def _finite(owner: str, name: str, value, *, positive=False, nonnegative=False) -> float:
    return finite_number(f'{owner}.{name}', value, positive=positive, nonnegative=nonnegative)


def _rescaled(value: float, omega_peak: float) -> float:
    """``value`` scaled to magnitude ``omega_peak``, keeping its sign (+ if zero)."""
    return math.copysign(float(omega_peak), value) if value else float(omega_peak)


def _out(t, value):
    """Return a float for scalar time input, an array otherwise."""
    return float(value) if np.ndim(t) == 0 else value


def _times(where: str, t):
    """``t`` as a float (scalar) or a float array; ValueError unless all finite numbers."""
    if np.ndim(t) == 0:
        return finite_number(f'{where}: time t', t)
    return finite_array(f'{where}: time t', t)


def _evaluation(method):
    """Validate the time of a profile's omega/omega_dot/angle and check its result."""
    @functools.wraps(method)
    def checked(self, t):
        where = f'{type(self).__name__}.{method.__name__}'
        tt = _times(where, t)
        with np.errstate(all='ignore'):     # unselected branches of np.where may overflow
            value = method(self, tt)
        if not np.all(np.isfinite(value)):
            raise ValueError(f'{where}: the result at t = {t!r} s overflows (not finite)')
        return value
    return checked


def _require_finite(where: str, what: str, value: float) -> None:
    """ValueError unless a quantity derived from a profile's fields is finite."""
    if not math.isfinite(value):
        raise ValueError(f'{where}: {what} overflows ({value!r})')


class Profile:
    """Base class of angular-velocity profiles."""

    def jumps(self) -> tuple[tuple[float, float, float], ...]:
        """Instants where w jumps, as ``(time s, w before, w after)`` triples (t > 0)."""
        return ()

    def breakpoints(self) -> tuple[float, ...]:
        """Instants t > 0 where w or one of its first derivatives is not smooth, s.

        Integrators that take large steps put a node on each (a step across one would
        lose its order). By default the jumps and :attr:`end_time`.
        """
        times = {float(j[0]) for j in self.jumps()}
        if self.end_time:
            times.add(float(self.end_time))
        return tuple(sorted(t for t in times if t > 0))

    def omega(self, t):
        """Angular velocity w(t), rad/s."""
        raise NotImplementedError

    def omega_dot(self, t):
        """Angular acceleration w'(t), rad/s^2 (0 at the instants of a jump)."""
        raise NotImplementedError

    def angle(self, t):
        """Hub angle theta(t) = integral of w from 0 to t, rad."""
        raise NotImplementedError

    @property
    def peak(self) -> float:
        """Largest |w| the profile reaches, rad/s."""
        raise NotImplementedError

    @property
    def end_time(self) -> float | None:
        """Time after which the profile is constant, s (None if it never settles)."""
        return None

    def with_peak(self, omega_peak: float) -> Profile:
        """The same shape scaled so that its peak |w| is ``omega_peak`` (rad/s)."""
        raise NotImplementedError


@dataclass(frozen=True)
class Eq26Profile(Profile):
    """The paper's Eq. 26: smooth spin-up over T, hold T/3, smooth spin-down over T, rest.

    0..T: w = W (t/T - sin(2 pi t/T) / 2pi); T..4T/3: w = W;
    4T/3..7T/3: w = W (1 - s/T + sin(2 pi s/T) / 2pi), s = t - 4T/3; then w = 0.
    w and w' are continuous and w' = 0 at every joint.

    Attributes:
        period: T, s (paper: 15 s).
        omega_target: W, rad/s (paper: 2 rad/s).

    Model: docs/model.md#eq-26.
    """

    period: float = 15.0
    omega_target: float = 2.0

    def __post_init__(self):
        object.__setattr__(self, 'period', _finite('Eq26Profile', 'period', self.period,
                                                   positive=True))
        object.__setattr__(self, 'omega_target', _finite('Eq26Profile', 'omega_target',
                                                      self.omega_target))
        T, W = self.period, self.omega_target
        _require_finite('Eq26Profile.period', 'the joint 7T/3', 7.0 * T)
        _require_finite('Eq26Profile.period', '2 pi / T', 2.0 * math.pi / T)
        _require_finite('Eq26Profile.period', 'the peak acceleration 2W/T', 2.0 * W / T)

    def _stages(self, t):
        T = self.period
        t = np.asarray(t, dtype=float)
        s = t - 4.0 * T / 3.0
        return T, t, s, (t <= T), (t > T) & (t <= 4 * T / 3), (t > 4 * T / 3) & (t <= 7 * T / 3)

    @_evaluation
    def omega(self, t):
        """Angular velocity w(t), rad/s."""
        T, tt, s, up, hold, down = self._stages(t)
        W, k = self.omega_target, 2.0 * math.pi / T
        w = np.where(up, W * (tt / T - np.sin(k * tt) / (2 * math.pi)), 0.0)
        w = np.where(hold, W, w)
        w = np.where(down, W * (1.0 - s / T + np.sin(k * s) / (2 * math.pi)), w)
        return _out(t, np.where(tt < 0, 0.0, w))

    @_evaluation
    def omega_dot(self, t):
        """Angular acceleration w'(t), rad/s^2."""
        T, tt, s, up, _, down = self._stages(t)
        W, k = self.omega_target, 2.0 * math.pi / T
        a = np.where(up & (tt >= 0), W / T * (1.0 - np.cos(k * tt)), 0.0)
        a = np.where(down, W / T * (np.cos(k * s) - 1.0), a)
        return _out(t, a)

    @_evaluation
    def angle(self, t):
        """Hub angle theta(t), rad (closed form)."""
        T, tt, s, up, hold, down = self._stages(t)
        W, k = self.omega_target, 2.0 * math.pi / T
        c = T / (4.0 * math.pi**2)
        th = np.where(up, W * (tt**2 / (2 * T) + c * (np.cos(k * tt) - 1.0)), 0.0)
        th = np.where(hold, W * (T / 2 + (tt - T)), th)
        th = np.where(down, W * (5 * T / 6 + s - s**2 / (2 * T) + c * (1.0 - np.cos(k * s))), th)
        th = np.where(tt > 7 * T / 3, W * 4 * T / 3, th)
        return _out(t, np.where(tt < 0, 0.0, th))

    @property
    def peak(self) -> float:
        """Largest |w|, rad/s."""
        return abs(self.omega_target)

    @property
    def end_time(self) -> float:
        """7T/3, s."""
        return 7.0 * self.period / 3.0

    def breakpoints(self) -> tuple[float, ...]:
        """The joints T, 4T/3 and 7T/3 (the third derivative of w jumps there), s."""
        T = self.period
        return (T, 4.0 * T / 3.0, 7.0 * T / 3.0)

    def with_peak(self, omega_peak: float) -> Eq26Profile:
        """Same timing, peak |w| ``omega_peak`` rad/s (same sense of rotation)."""
        omega_peak = _finite(type(self).__name__, 'with_peak: omega_peak', omega_peak)
        return dataclasses.replace(self, omega_target=_rescaled(self.omega_target, omega_peak))


@dataclass(frozen=True)
class ConstantProfile(Profile):
    """Constant angular velocity from t = 0 (the rotating frame starts at that speed).

    Attributes:
        omega_target: w, rad/s.
    """

    omega_target: float = 2.0

    def __post_init__(self):
        object.__setattr__(self, 'omega_target',
                           _finite('ConstantProfile', 'omega_target', self.omega_target))

    @_evaluation
    def omega(self, t):
        """Angular velocity, rad/s."""
        return _out(t, np.full(np.shape(t), self.omega_target))

    @_evaluation
    def omega_dot(self, t):
        """Zero, rad/s^2."""
        return _out(t, np.zeros(np.shape(t)))

    @_evaluation
    def angle(self, t):
        """W t, rad."""
        return _out(t, self.omega_target * np.asarray(t, dtype=float))

    @property
    def peak(self) -> float:
        """|w|, rad/s."""
        return abs(self.omega_target)

    @property
    def end_time(self) -> float:
        """0 s: constant from the start."""
        return 0.0

    def with_peak(self, omega_peak: float) -> ConstantProfile:
        """Constant |w| ``omega_peak`` rad/s (same sense of rotation)."""
        omega_peak = _finite(type(self).__name__, 'with_peak: omega_peak', omega_peak)
        return ConstantProfile(_rescaled(self.omega_target, omega_peak))


@dataclass(frozen=True)
class StepProfile(Profile):
    """A sudden change of angular velocity at ``t_step``.

    w = omega_start for t < t_step, omega for t >= t_step. With t_step > 0 the jump
    is applied physically (the mass keeps its absolute velocity: from rest this is the
    "impulsive" start). With t_step = 0 the run starts in the frame already turning
    at ``omega`` (from rest in that frame: the "step" start of docs/model.md).

    Attributes:
        omega_target: w after the step, rad/s.
        t_step: time of the step, s (>= 0).
        omega_start: w before the step, rad/s.
    """

    omega_target: float = 2.0
    t_step: float = 0.0
    omega_start: float = 0.0

    def __post_init__(self):
        set_ = object.__setattr__
        set_(self, 'omega_target', _finite('StepProfile', 'omega_target', self.omega_target))
        set_(self, 't_step', _finite('StepProfile', 't_step', self.t_step, nonnegative=True))
        set_(self, 'omega_start', _finite('StepProfile', 'omega_start', self.omega_start))

    def jumps(self) -> tuple[tuple[float, float, float], ...]:
        """The step, when it happens after the start and changes w."""
        if self.t_step > 0 and self.omega_target != self.omega_start:
            return ((self.t_step, self.omega_start, self.omega_target),)
        return ()

    @_evaluation
    def omega(self, t):
        """Angular velocity, rad/s."""
        tt = np.asarray(t, dtype=float)
        return _out(t, np.where(tt < self.t_step, self.omega_start, self.omega_target))

    @_evaluation
    def omega_dot(self, t):
        """Zero away from the step, rad/s^2."""
        return _out(t, np.zeros(np.shape(t)))

    @_evaluation
    def angle(self, t):
        """Piecewise linear hub angle, rad."""
        tt = np.asarray(t, dtype=float)
        before = self.omega_start * np.minimum(tt, self.t_step)
        return _out(t, before + self.omega_target * np.maximum(tt - self.t_step, 0.0))

    @property
    def peak(self) -> float:
        """max(|omega_start|, |omega_target|), rad/s."""
        return max(abs(self.omega_target), abs(self.omega_start))

    @property
    def end_time(self) -> float:
        """t_step, s."""
        return self.t_step

    def with_peak(self, omega_peak: float) -> StepProfile:
        """Both levels scaled by omega_peak / peak."""
        omega_peak = _finite(type(self).__name__, 'with_peak: omega_peak', omega_peak)
        if self.peak == 0:
            return dataclasses.replace(self, omega_target=omega_peak)
        scale = omega_peak / self.peak
        return dataclasses.replace(self, omega_target=self.omega_target * scale,
                                   omega_start=self.omega_start * scale)


@dataclass(frozen=True)
class RampProfile(Profile):
    """Linear ramp from rest to ``omega_target`` over ``ramp_time``, starting at ``t_start``.

    w is continuous; w' is constant (omega_target / ramp_time) during the ramp.

    Attributes:
        omega_target: final angular velocity, rad/s.
        ramp_time: duration of the ramp, s (> 0).
        t_start: start of the ramp, s (>= 0).
    """

    omega_target: float = 2.0
    ramp_time: float = 15.0
    t_start: float = 0.0

    def __post_init__(self):
        set_ = object.__setattr__
        set_(self, 'omega_target', _finite('RampProfile', 'omega_target', self.omega_target))
        set_(self, 'ramp_time', _finite('RampProfile', 'ramp_time', self.ramp_time,
                                        positive=True))
        set_(self, 't_start', _finite('RampProfile', 't_start', self.t_start, nonnegative=True))
        _require_finite('RampProfile.ramp_time', 'the acceleration omega_target / ramp_time',
                        self.omega_target / self.ramp_time)
        _require_finite('RampProfile.t_start', 'the end t_start + ramp_time',
                        self.t_start + self.ramp_time)

    @_evaluation
    def omega(self, t):
        """Angular velocity, rad/s."""
        tt = np.asarray(t, dtype=float)
        frac = np.clip((tt - self.t_start) / self.ramp_time, 0.0, 1.0)
        return _out(t, self.omega_target * frac)

    @_evaluation
    def omega_dot(self, t):
        """omega_target / ramp_time during the ramp, else 0, rad/s^2."""
        tt = np.asarray(t, dtype=float)
        on = (tt >= self.t_start) & (tt < self.t_start + self.ramp_time)
        return _out(t, np.where(on, self.omega_target / self.ramp_time, 0.0))

    @_evaluation
    def angle(self, t):
        """Hub angle, rad."""
        tt = np.asarray(t, dtype=float)
        tau = np.clip(tt - self.t_start, 0.0, self.ramp_time)
        after = np.maximum(tt - self.t_start - self.ramp_time, 0.0)
        return _out(t, self.omega_target * (tau**2 / (2 * self.ramp_time) + after))

    @property
    def peak(self) -> float:
        """|omega_target|, rad/s."""
        return abs(self.omega_target)

    @property
    def end_time(self) -> float:
        """End of the ramp, s."""
        return self.t_start + self.ramp_time

    def breakpoints(self) -> tuple[float, ...]:
        """Start and end of the ramp (the acceleration jumps there), s."""
        return tuple(t for t in (self.t_start, self.end_time) if t > 0)

    def with_peak(self, omega_peak: float) -> RampProfile:
        """Same timing, final |w| ``omega_peak`` (same sense of rotation)."""
        omega_peak = _finite(type(self).__name__, 'with_peak: omega_peak', omega_peak)
        return dataclasses.replace(self, omega_target=_rescaled(self.omega_target, omega_peak))


@dataclass(frozen=True)
class SineSweepProfile(Profile):
    """Angular velocity oscillating about ``offset`` with a linearly rising frequency.

    For 0 <= t <= duration: w = offset + amplitude sin(phi), phi = 2 pi (f_start t +
    (f_end - f_start) t^2 / (2 duration)) (a linear chirp); after it w holds its end
    value. The hub's oscillating angular acceleration w' excites the rod
    tangentially across the band f_start..f_end: a frequency-response sweep. w starts
    at ``offset`` (0 by default: from rest).

    Attributes:
        amplitude: amplitude of w, rad/s.
        f_start: frequency of the oscillation at t = 0, Hz (>= 0).
        f_end: frequency at t = duration, Hz (>= 0).
        duration: length of the sweep, s (> 0).
        offset: mean angular velocity, rad/s.
    """

    amplitude: float = 0.2
    f_start: float = 0.5
    f_end: float = 4.0
    duration: float = 30.0
    offset: float = 0.0

    def __post_init__(self):
        set_ = object.__setattr__
        for name in ('amplitude', 'offset'):
            set_(self, name, _finite('SineSweepProfile', name, getattr(self, name)))
        for name in ('f_start', 'f_end'):
            set_(self, name, _finite('SineSweepProfile', name, getattr(self, name),
                                     nonnegative=True))
        set_(self, 'duration', _finite('SineSweepProfile', 'duration', self.duration,
                                       positive=True))
        f_max = max(self.f_start, self.f_end)
        _require_finite('SineSweepProfile.amplitude', 'the peak |offset| + |amplitude|',
                        abs(self.offset) + abs(self.amplitude))
        _require_finite('SineSweepProfile.f_end', 'the sweep rate (f_end - f_start) / duration',
                        self._rate)
        _require_finite('SineSweepProfile.duration', 'the final phase pi (f_start + f_end) '
                        'duration', math.pi * (self.f_start + self.f_end) * self.duration)
        _require_finite('SineSweepProfile.amplitude', 'the peak acceleration 2 pi '
                        'max(f_start, f_end) amplitude', 2 * math.pi * f_max * self.amplitude)

    @property
    def _rate(self) -> float:
        """Frequency slope (f_end - f_start) / duration, Hz/s."""
        return (self.f_end - self.f_start) / self.duration

    def _phase(self, tau):
        return 2 * np.pi * (self.f_start * tau + 0.5 * self._rate * tau * tau)

    @_evaluation
    def omega(self, t):
        """Angular velocity, rad/s."""
        tau = np.clip(np.asarray(t, dtype=float), 0.0, self.duration)
        return _out(t, self.offset + self.amplitude * np.sin(self._phase(tau)))

    @_evaluation
    def omega_dot(self, t):
        """Angular acceleration, rad/s^2 (0 after the sweep)."""
        tt = np.asarray(t, dtype=float)
        tau = np.clip(tt, 0.0, self.duration)
        rate = 2 * np.pi * (self.f_start + self._rate * tau)
        wd = self.amplitude * rate * np.cos(self._phase(tau))
        return _out(t, np.where((tt >= 0) & (tt < self.duration), wd, 0.0))

    def _sine_integral(self, tau):
        """Integral of sin(phi) from 0 to tau (exact: Fresnel integrals)."""
        k, f0 = self._rate, self.f_start
        if k == 0:
            if f0 == 0:
                return np.zeros_like(tau)
            return (1 - np.cos(2 * np.pi * f0 * tau)) / (2 * np.pi * f0)
        # phi = pi k (tau + f0/k)^2 - pi f0^2 / k; x = sqrt(2 |k|) (tau + f0/k)
        sign = 1.0 if k > 0 else -1.0
        scale = math.sqrt(2 * abs(k))
        c = math.pi * f0 * f0 / k

        def antiderivative(x):
            s_x, c_x = fresnel(x)
            return (math.cos(c) * sign * s_x - math.sin(c) * c_x) / scale
        x0 = scale * f0 / k
        return antiderivative(scale * (tau + f0 / k)) - antiderivative(x0)

    @_evaluation
    def angle(self, t):
        """Hub angle, rad."""
        tt = np.asarray(t, dtype=float)
        tau = np.clip(tt, 0.0, self.duration)
        theta = self.offset * tau + self.amplitude * self._sine_integral(tau)
        after = np.maximum(tt - self.duration, 0.0) * self.omega(self.duration)
        return _out(t, theta + after)

    @property
    def peak(self) -> float:
        """|offset| + |amplitude| (a bound on |w|), rad/s."""
        return abs(self.offset) + abs(self.amplitude)

    @property
    def end_time(self) -> float:
        """End of the sweep, s."""
        return self.duration

    def with_peak(self, omega_peak: float) -> SineSweepProfile:
        """Offset and amplitude scaled together so that |offset| + |amplitude| = omega_peak."""
        omega_peak = _finite(type(self).__name__, 'with_peak: omega_peak', omega_peak)
        if self.peak == 0:
            raise ValueError('SineSweepProfile.with_peak: a zero sweep has no shape to scale')
        scale = omega_peak / self.peak
        return dataclasses.replace(self, amplitude=self.amplitude * scale,
                                   offset=self.offset * scale)


class TableProfile(Profile):
    """A user table of (time, omega) points, interpolated smoothly (monotone cubic, PCHIP).

    PCHIP keeps w and w' continuous and never overshoots the tabulated values. Before
    the first point and after the last, w holds the end value.

    Args:
        times: strictly increasing times, s (at least 2, the first >= 0).
        omegas: angular velocities at those times, rad/s.
    """

    def __init__(self, times, omegas):
        try:
            t = np.asarray(times, dtype=float).ravel()
            w = np.asarray(omegas, dtype=float).ravel()
        except (TypeError, ValueError, OverflowError):
            raise ValueError('TableProfile: times and omegas must be numbers') from None
        if t.size < 2 or t.size != w.size:
            raise ValueError(f'TableProfile needs >= 2 (time, omega) pairs of equal length, '
                             f'got {t.size} times and {w.size} omegas')
        if not (np.all(np.isfinite(t)) and np.all(np.isfinite(w))):
            raise ValueError('TableProfile: times and omegas must be finite')
        if t[0] < 0 or np.any(np.diff(t) <= 0):
            raise ValueError('TableProfile: times must start at >= 0 and increase strictly')
        self.times, self.omegas = t, w
        overflow = ValueError("TableProfile: the interpolated w or w' overflows (omegas too "
                              'large for the spacing of the times)')
        with np.errstate(all='ignore'):
            # PCHIP's cubic terms stay below ~50 x max(|w|, |slope| x interval): keep
            # them finite, and the quartic of the angle over the longest interval
            if not (math.isfinite(64.0 * np.max(np.abs(w)))
                    and math.isfinite(64.0 * np.max(np.abs(np.diff(w) / np.diff(t))))):
                raise overflow
            if not math.isfinite(np.max(np.diff(t)) ** 4):
                raise ValueError('TableProfile: an interval between times is too long '
                                 '(its 4th power, in the angle, overflows)')
            try:
                self._w = PchipInterpolator(t, w, extrapolate=False)
            except ValueError:          # scipy: the slopes dydx are not finite
                raise overflow from None
            self._dw = self._w.derivative()
            self._theta = self._w.antiderivative()
        if not (np.all(np.isfinite(self._w.c)) and np.all(np.isfinite(self._dw.c))):
            raise overflow

    def __repr__(self):
        return f'TableProfile({len(self.times)} points, {self.times[0]}..{self.times[-1]} s)'

    @_evaluation
    def omega(self, t):
        """Angular velocity, rad/s."""
        tt = np.clip(np.asarray(t, dtype=float), self.times[0], self.times[-1])
        return _out(t, self._w(tt))

    @_evaluation
    def omega_dot(self, t):
        """Angular acceleration, rad/s^2 (0 outside the table)."""
        tt = np.asarray(t, dtype=float)
        inside = (tt >= self.times[0]) & (tt <= self.times[-1])
        d = self._dw(np.clip(tt, self.times[0], self.times[-1]))
        return _out(t, np.where(inside, d, 0.0))

    @_evaluation
    def angle(self, t):
        """Hub angle, rad."""
        tt = np.asarray(t, dtype=float)
        t0, t1 = self.times[0], self.times[-1]
        head = self.omegas[0] * np.minimum(tt, t0)
        mid = self._theta(np.clip(tt, t0, t1))
        tail = self.omegas[-1] * np.maximum(tt - t1, 0.0)
        return _out(t, head + mid + tail)

    @property
    def peak(self) -> float:
        """Largest |w| (PCHIP does not overshoot the table), rad/s."""
        return float(np.max(np.abs(self.omegas)))

    @property
    def end_time(self) -> float:
        """Last table time, s."""
        return float(self.times[-1])

    def breakpoints(self) -> tuple[float, ...]:
        """The table's times (PCHIP's second derivative jumps there), s."""
        return tuple(float(t) for t in self.times if t > 0)

    def with_peak(self, omega_peak: float) -> TableProfile:
        """Omegas scaled so the largest |w| is ``omega_peak``."""
        omega_peak = _finite(type(self).__name__, 'with_peak: omega_peak', omega_peak)
        if self.peak == 0:
            raise ValueError('TableProfile.with_peak: an all-zero table has no shape to scale')
        return TableProfile(self.times, self.omegas * (omega_peak / self.peak))

    @classmethod
    def from_csv(cls, path) -> TableProfile:
        """Read a two-column CSV (time s, omega rad/s); a header line is allowed."""
        try:
            data = np.genfromtxt(path, delimiter=',', dtype=float, comments='#')
        except OSError as exc:
            raise ValueError(f'cannot read profile table {path}: {exc}') from None
        data = np.atleast_2d(data)
        data = data[~np.all(np.isnan(data), axis=1)]
        if data.ndim != 2 or data.shape[1] != 2:
            raise ValueError(f'profile table {path} must have two columns: time, omega')
        return cls(data[:, 0], data[:, 1])


def spin_up_knots(n_free: int) -> np.ndarray:
    """Knots (normalised time 0..1) of a :class:`SpinUpProfile` with ``n_free`` free points.

    A clamped cubic B-spline with uniform interior knots.
    """
    return np.r_[[0.0] * 4, np.linspace(0.0, 1.0, n_free + 2)[1:-1], [1.0] * 4]


class SpinUpProfile(Profile):
    """A smooth change of angular velocity over ``duration``: a clamped cubic B-spline.

    w(t) = sum_i c_i B_i(t / duration) for 0 <= t <= duration, with the B_i the cubic
    B-splines on :func:`spin_up_knots` (uniform interior knots). The first two control
    points are equal (w = c_0, w' = 0 at t = 0) and so are the last two (w = c_-1,
    w' = 0 at the end), so w is twice continuously differentiable from the constant
    w = c_0 before 0 to the constant w = c_-1 after ``duration``. This is the shape
    :func:`rotrod_core.plan_spin_up` returns; it also fills the planner's predictions.
    With ``t_start`` > 0 the same change begins at ``t_start`` (t / duration above
    becomes (t - t_start) / duration): w holds c_0 until then.

    Args:
        duration: length of the change, s (> 0).
        control_points: B-spline coefficients, rad/s (at least 4; c_0 = c_1 and
            c_-2 = c_-1).
        peak_deflection: the planner's predicted largest |r| over the whole run, m.
        residual_amplitude: the planner's predicted free-whirl amplitude left about
            the static deflection at the final speed, m (nominal parameters).
        band_residual: the largest predicted residual over the planner's robust band
            of natural frequencies, m (equals ``residual_amplitude`` without one).
        robust: half-width eps of that band, (1 +- eps) w0.
        t_start: when the change begins, s (>= 0; default 0).
    """

    peak_deflection: float | None
    residual_amplitude: float | None
    band_residual: float | None

    def __init__(self, duration, control_points, *, peak_deflection=None,
                 residual_amplitude=None, band_residual=None, robust=0.0, t_start=0.0):
        self.duration = _finite('SpinUpProfile', 'duration', duration, positive=True)
        self.t_start = _finite('SpinUpProfile', 't_start', t_start, nonnegative=True)
        try:
            c = np.array(control_points, dtype=float).ravel()
        except (TypeError, ValueError, OverflowError):
            raise ValueError('SpinUpProfile: control_points must be numbers') from None
        if c.size < 4 or not np.all(np.isfinite(c)):
            raise ValueError(f'SpinUpProfile needs >= 4 finite control points, got {c.size}')
        if c[0] != c[1] or c[-2] != c[-1]:
            raise ValueError("SpinUpProfile: the first two and the last two control points "
                             "must be equal (w' = 0 at both ends)")
        self.control_points = c
        for name, value in (('peak_deflection', peak_deflection),
                            ('residual_amplitude', residual_amplitude),
                            ('band_residual', band_residual)):
            setattr(self, name, None if value is None else _finite(
                'SpinUpProfile', name, value, nonnegative=True))
        self.robust = _finite('SpinUpProfile', 'robust', robust, nonnegative=True)
        T = self.duration
        _require_finite('SpinUpProfile.duration', "the slope w' ~ c / duration",
                        64.0 * float(np.max(np.abs(c))) / T)
        _require_finite('SpinUpProfile.duration', 'the angle ~ c duration',
                        float(np.max(np.abs(c))) * T)
        _require_finite('SpinUpProfile.t_start', 'the end t_start + duration', self.t_start + T)
        self._w = BSpline(spin_up_knots(c.size - 4), c, 3, extrapolate=False)
        self._dw = self._w.derivative()
        self._theta = self._w.antiderivative()

    def __repr__(self):
        start = f' from {self.t_start:g} s' if self.t_start else ''
        return (f'SpinUpProfile({self.omega_start:g} -> {self.omega_target:g} rad/s in '
                f'{self.duration:.4g} s{start}, {self.control_points.size} control points)')

    def started_at(self, t_start: float) -> SpinUpProfile:
        """The same change (and predictions) beginning at ``t_start`` (s) instead."""
        return SpinUpProfile(self.duration, self.control_points,
                             peak_deflection=self.peak_deflection,
                             residual_amplitude=self.residual_amplitude,
                             band_residual=self.band_residual, robust=self.robust,
                             t_start=t_start)

    @property
    def omega_start(self) -> float:
        """Angular velocity before and at t = 0, rad/s."""
        return float(self.control_points[0])

    @property
    def omega_target(self) -> float:
        """Angular velocity at and after ``duration``, rad/s."""
        return float(self.control_points[-1])

    def _x(self, t):
        return np.clip((np.asarray(t, dtype=float) - self.t_start) / self.duration, 0.0, 1.0)

    @_evaluation
    def omega(self, t):
        """Angular velocity, rad/s: exactly the end speeds outside the change."""
        x = self._x(t)
        w = np.where(x <= 0.0, self.omega_start,
                     np.where(x >= 1.0, self.omega_target, self._w(x)))
        return _out(t, w)

    @_evaluation
    def omega_dot(self, t):
        """Angular acceleration, rad/s^2 (0 before 0 and after ``duration``)."""
        tt = np.asarray(t, dtype=float) - self.t_start
        inside = (tt >= 0) & (tt <= self.duration)
        return _out(t, np.where(inside, self._dw(self._x(t)) / self.duration, 0.0))

    @_evaluation
    def angle(self, t):
        """Hub angle, rad (integral of the spline, exact)."""
        tt = np.asarray(t, dtype=float)
        T = self.duration
        mid = T * self._theta(self._x(t))
        head = self.omega_start * np.minimum(tt, self.t_start)
        tail = self.omega_target * np.maximum(tt - self.t_start - T, 0.0)
        return _out(t, head + mid + tail)

    @property
    def max_angular_acceleration(self) -> float:
        """Largest |w'| over the change, rad/s^2.

        Exact: w'' is piecewise linear, so |w'| peaks on a knot or a zero of w''.
        """
        d2 = self._dw.derivative()
        knots = np.unique(self._w.t)
        x: list[np.ndarray | list[float]] = [knots]
        for a, b in zip(knots[:-1], knots[1:]):
            ya, yb = d2(a + 1e-15 * (b - a)), d2(b - 1e-15 * (b - a))
            if ya * yb < 0:
                x.append([a + (b - a) * ya / (ya - yb)])
        return float(np.max(np.abs(self._dw(np.concatenate(x))))) / self.duration

    @property
    def peak(self) -> float:
        """Largest |w|, rad/s (a spline lies within its control points: found on a grid)."""
        x = np.linspace(0.0, 1.0, 2001)
        return float(max(np.max(np.abs(self._w(x))), abs(self.omega_start),
                         abs(self.omega_target)))

    @property
    def end_time(self) -> float:
        """``t_start + duration``, s."""
        return self.t_start + self.duration

    def breakpoints(self) -> tuple[float, ...]:
        """The spline's knots in time (its third derivative jumps there), s.

        From ``t_start`` on; the start itself too when it is after 0.
        """
        return tuple(self.t_start + float(x) * self.duration for x in np.unique(self._w.t)
                     if self.t_start + float(x) * self.duration > 0)

    def with_peak(self, omega_peak: float) -> SpinUpProfile:
        """Control points scaled so the peak |w| is ``omega_peak``.

        The planner's predictions are dropped: the scaled profile is not the plan.
        """
        omega_peak = _finite(type(self).__name__, 'with_peak: omega_peak', omega_peak)
        if self.peak == 0:
            raise ValueError('SpinUpProfile.with_peak: an all-zero profile has no shape')
        return SpinUpProfile(self.duration, self.control_points * (omega_peak / self.peak),
                             t_start=self.t_start)


PROFILES = {
    'eq26': Eq26Profile,
    'constant': ConstantProfile,
    'step': StepProfile,
    'ramp': RampProfile,
    'sine_sweep': SineSweepProfile,
    'table': TableProfile,
    'spin_up': SpinUpProfile,
}


def make_profile(name: str, **kwargs: Any) -> Profile:
    """Build a profile by name (eq26, constant, step, ramp, sine_sweep, table, spin_up)."""
    try:
        cls = PROFILES[name]
    except KeyError:
        raise ValueError(f'unknown profile {name!r}; expected one of {tuple(PROFILES)}') from None
    try:
        return cls(**kwargs)
    except TypeError as exc:
        raise ValueError(f'bad arguments for profile {name!r}: {exc}') from None
