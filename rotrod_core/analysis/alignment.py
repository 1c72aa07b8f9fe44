"""Aligning a measured run with the profile that drove it: the time shift."""

from __future__ import annotations

import numpy as np

from rotrod_core.command.profiles import Profile


def profile_delay(t, omega, profile: Profile, *, search: float | None = None,
                  resolution: float = 1e-4) -> float:
    """Time s (s) such that ``omega(t)`` best matches ``profile.omega(t - s)``.

    Least squares over shifts within ``search`` s (default: a fifth of the profile's
    length, at least 1 s) of the instant the measured w first moves by 1 % of its
    range, on a coarse grid, then refined to ``resolution``.
    ``t`` in s, ``omega`` in rad/s (e.g. the published joint states of a streamed
    profile; the shift is when the profile's t = 0 happened).
    """
    t = np.asarray(t, dtype=float)
    w = np.asarray(omega, dtype=float)
    if t.shape != w.shape or t.size < 3:
        raise ValueError('t and omega must be equal-length series of >= 3 samples')
    span = float(np.max(w) - np.min(w))
    if not span > 0:
        raise ValueError('omega never changes: nothing to align')
    guess = t[np.nonzero(np.abs(w - w[0]) > 0.01 * span)[0][0]]
    if search is None:
        search = max(1.0, 0.2 * (profile.end_time or 0.0))

    def cost(s):
        return float(np.sum((w - profile.omega(np.clip(t - s, 0.0, None))) ** 2))

    lo, hi, step = guess - search, guess + search, search / 100
    while True:
        shifts = np.arange(lo, hi + step / 2, step)
        best = shifts[int(np.argmin([cost(s) for s in shifts]))]
        if step <= resolution:
            return float(best)
        lo, hi, step = best - step, best + step, step / 10
