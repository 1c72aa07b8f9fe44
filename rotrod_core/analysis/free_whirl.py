"""The free whirl left at constant speed, measured from the tip's motion.

At constant w the tip's deflection z = u + i v about its static position is two
whirls (docs/model.md, Eq. 28): z = c + A exp(i 2 pi f1 t) + B exp(-i 2 pi f2 t) in the
rotating frame, f1, f2 the dynamic frequencies at w. :func:`free_whirl` fits c, A and B
by least squares to samples and returns |A| + |B|, the largest distance of the tip from
its static position: the residual whirl of a spin-up (what the planner bounds).
"""

from __future__ import annotations

import math

import numpy as np

from rotrod_core.analysis.modes import dynamic_frequencies
from rotrod_core.model.params import RodParams


def free_whirl(t, u, v, params: RodParams, omega: float) -> tuple[float, float]:
    """(|A| + |B|, the fit's RMS misfit), m, of samples (t s, u and v m) at ``omega`` rad/s.

    The frequencies are ``params``' at ``omega`` (Eq. 28 for a round undamped rod);
    the static position is fitted. Raises ValueError for fewer than 8 samples or
    non-finite values.
    """
    t, u, v = (np.asarray(x, dtype=float).ravel() for x in (t, u, v))
    if not (len(t) == len(u) == len(v)) or len(t) < 8:
        raise ValueError(f'free_whirl needs >= 8 samples of t, u, v alike, got {len(t)}')
    if not (np.all(np.isfinite(t)) and np.all(np.isfinite(u)) and np.all(np.isfinite(v))):
        raise ValueError('free_whirl: the samples must be finite')
    f1, f2 = (float(f) for f in dynamic_frequencies(params, omega))
    tau = t - t[0]
    z = u + 1j * v
    basis = np.column_stack([np.ones_like(tau), np.exp(2j * math.pi * f1 * tau),
                             np.exp(-2j * math.pi * f2 * tau)])
    coef, *_ = np.linalg.lstsq(basis, z, rcond=None)
    misfit = z - basis @ coef
    return float(abs(coef[1]) + abs(coef[2])), float(np.sqrt(np.mean(np.abs(misfit) ** 2)))


__all__ = ['free_whirl']
