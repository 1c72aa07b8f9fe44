"""Critical angular velocity for a deflection limit: closed forms and numerical.

For an isotropic undamped rod starting from rest, at constant w < w0:

- quasi-static (slow spin-up): the deflection is u_s = w^2 re / (w0^2 - w^2), so
  w_cr = w0 sqrt(delta / (delta + re));
- step (from rest in the rotating frame, Eq. 29): the peak approaches 2 u_s, so
  w_cr = w0 sqrt(delta / (delta + 2 re));
- impulsive (the mass at rest in the inertial frame when w jumps): the peak
  approaches re w / (w0 - w), so w_cr = w0 delta / (re + delta).

Here w0 = sqrt(k/M) (:attr:`RodParams.natural_frequency`, with gravity's axial load
and the rod's modal mass M) and re = (Me / M) r0 is the load radius (r0 for the
paper's massless rod; see :mod:`rotrod_core.model.equations`).
"""

from __future__ import annotations

import math

import numpy as np

from rotrod_core.command.profiles import Profile
from rotrod_core.model.params import RodParams
from rotrod_core.numerics.checks import finite_array
from rotrod_core.offline.simulate import simulate

STARTS = ('quasi_static', 'step', 'impulsive')


def _limit(deflection_limit):
    if isinstance(deflection_limit, bool):
        raise ValueError(f'deflection_limit must be a number, got {deflection_limit!r}')
    d = finite_array('deflection_limit', deflection_limit)
    if not np.all(d > 0):
        raise ValueError(f'deflection_limit must be > 0 m, got {deflection_limit!r}')
    return d


def critical_speed(params: RodParams, deflection_limit, start: str = 'quasi_static'):
    """Closed-form critical angular velocity (rad/s) for a deflection limit (m).

    ``start`` is 'quasi_static', 'step' or 'impulsive' (module docstring). Vectorized:
    ``params.eccentricity`` and ``deflection_limit`` may be arrays (Fig. 10). The
    quasi-static form uses the radial stiffness k1; the others need an isotropic rod.

    Model: docs/model.md#eq-critical.
    """
    _limit(deflection_limit)
    if start not in STARTS:
        raise ValueError(f'start must be one of {STARTS}, got {start!r}')
    w0 = (params.natural_frequency_radial if start == 'quasi_static'
          else params.natural_frequency)
    return critical_speed_from(w0, params.load_radius, deflection_limit, start)


def critical_speed_from(natural_frequency, eccentricity, deflection_limit,
                        start: str = 'quasi_static'):
    """The closed forms of :func:`critical_speed` from plain numbers (rad/s).

    ``natural_frequency`` w0 in rad/s, ``eccentricity`` r0 in m (>= 0; the load radius
    (Me / M) r0 for a rod with mass, which is what identification measures), the deflection
    limit in m; arrays broadcast. Used with identified values
    (:meth:`rotrod_core.RigEstimate.critical_speed`). NaN inputs give NaN.
    """
    d = _limit(deflection_limit)
    if start not in STARTS:
        raise ValueError(f'start must be one of {STARTS}, got {start!r}')
    w0 = np.asarray(natural_frequency, dtype=float)
    r0 = np.asarray(eccentricity, dtype=float)
    # d / (d + r0) as 1 / (1 + r0/d): d + r0 may overflow, r0/d = inf gives the limit 0
    with np.errstate(over='ignore'):
        ratio = r0 / d
        if start == 'quasi_static':
            w = w0 * np.sqrt(1.0 / (1.0 + ratio))
        elif start == 'step':
            w = w0 * np.sqrt(1.0 / (1.0 + 2 * ratio))
        else:
            w = w0 / (1.0 + ratio)
    w = np.asarray(w, dtype=float)
    return float(w) if w.ndim == 0 else w


def step_response(params: RodParams, omega: float, t):
    """Eq. 29: deflection z = u + i v (m) from rest in the rotating frame at constant w.

    z(t) = (w^2 re / (2 w0)) [(1 - exp(i w1 t)) / w1 + (1 - exp(-i w2 t)) / w2] with
    w1 = w0 - w, w2 = w0 + w, for an isotropic undamped rod and 0 < w < w0 (rad/s);
    t in s (array); re = (Me / M) r0 (r0 for a massless rod). Its peak magnitude
    approaches 2 u_s.

    Model: docs/model.md#eq-29.
    """
    if not params.is_isotropic or np.any(np.asarray(params.damping_ratio) > 0):
        raise ValueError('step_response (Eq. 29) needs an isotropic rod without damping')
    w0 = params.natural_frequency
    w = float(omega)
    if not 0 < w < w0:
        raise ValueError(f'step_response needs 0 < omega < w0 = {w0:.6f} rad/s, got {omega!r}')
    w1, w2 = w0 - w, w0 + w
    t = np.asarray(t, dtype=float)
    re = params.load_radius
    return (w * w * re / (2 * w0)) * ((1 - np.exp(1j * w1 * t)) / w1
                                                       + (1 - np.exp(-1j * w2 * t)) / w2)


def peak_deflection(params: RodParams, profile: Profile, t_end: float, dt: float) -> float:
    """Largest |r| = sqrt(u^2 + v^2) (m) over an offline run from rest."""
    run = simulate(params, profile, t_end, dt=dt)
    return float(np.max(run.deflection))


def critical_speed_for_profile(params: RodParams, profile: Profile, deflection_limit,
                               t_end: float | None = None, dt: float = 2e-3,
                               omega_search_max: float | None = None, grid: int = 40,
                               tolerance: float = 1e-4, progress=None):
    """Numerical critical speed (rad/s) of a profile shape.

    The largest peak angular velocity W such that every run of
    ``profile.with_peak(W')``, W' <= W, from rest keeps |deflection| <= ``deflection_limit``.

    The deflection of a run from rest is proportional to r0 (the forcing is), so one
    sweep of W serves every eccentricity: ``params.eccentricity`` may be an array,
    as may ``deflection_limit``; other fields must be scalars. W is swept on ``grid``
    points up to ``omega_search_max`` (default 1.5 w0) and the first crossing is
    bisected to ``tolerance`` x w0. Where no crossing is found, returns inf.

    Args:
        params: the system (eccentricity may be an array).
        profile: the shape; its peak is rescaled (``with_peak``).
        deflection_limit: delta, m (scalar or array).
        t_end: run length, s (default: the profile's end time plus 10 natural periods).
        dt: step and sampling interval, s (peaks between samples are missed by
            ~(pi f dt)^2/2 relative).
        omega_search_max: top of the W sweep, rad/s.
        grid: number of sweep points.
        tolerance: bisection tolerance relative to w0.
        progress: optional callable, called with the number of runs done after each run.
    """
    d = _limit(deflection_limit)
    if not isinstance(profile, Profile):
        raise ValueError(f'profile must be a rotrod_core Profile, got {profile!r}')
    others = {k: v for k, v in params._numeric().items() if k != 'eccentricity'}
    if any(np.ndim(v) for v in others.values()):
        raise ValueError('only eccentricity may be an array here')
    r0 = np.asarray(params.eccentricity, dtype=float)
    unit = params.replace(eccentricity=1.0)
    w0 = float(np.sqrt(min(unit.stiffness_radial, unit.stiffness_tangential)
                       / unit.modal_mass))
    if t_end is None:
        t_end = (profile.end_time or 0.0) + 10 * 2 * math.pi / w0
    w_max = 1.5 * w0 if omega_search_max is None else float(omega_search_max)
    if not (math.isfinite(w_max) and w_max > 0):
        raise ValueError(f'omega_search_max must be finite and > 0, got {omega_search_max!r}')
    if not (isinstance(grid, int) and grid >= 2):
        raise ValueError(f'grid must be an integer >= 2, got {grid!r}')
    cache: dict = {}

    def per_metre(w):
        if w not in cache:
            cache[w] = peak_deflection(unit, profile.with_peak(w), t_end, dt)
            if progress is not None:
                progress(len(cache))
        return cache[w]

    ws = np.linspace(w_max / grid, w_max, grid)
    envelope = np.maximum.accumulate([per_metre(w) for w in ws])
    thresholds = d / np.where(r0 > 0, r0, np.nan)
    thresholds, shape = np.broadcast_arrays(thresholds, np.zeros(np.broadcast(d, r0).shape))
    out = np.empty(thresholds.shape)
    for idx, thr in np.ndenumerate(thresholds):
        if not np.isfinite(thr):        # r0 = 0: no forcing, never deflects
            out[idx] = np.inf
            continue
        above = np.nonzero(envelope > thr)[0]
        if above.size == 0:
            out[idx] = np.inf
            continue
        i = above[0]
        lo, hi = (0.0 if i == 0 else ws[i - 1]), ws[i]
        while hi - lo > tolerance * w0:
            mid = 0.5 * (lo + hi)
            if per_metre(mid) > thr:
                hi = mid
            else:
                lo = mid
        out[idx] = lo
    return float(out) if out.ndim == 0 else out
