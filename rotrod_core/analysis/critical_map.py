"""Critical angular velocity over eccentricity and deflection limit, for several starts.

For each pair (r0, delta) of a grid: the closed forms of the quasi-static, step and
impulsive starts (:func:`~rotrod_core.analysis.critical.critical_speed`) and the numerical
critical speed of a profile shape
(:func:`~rotrod_core.analysis.critical.critical_speed_for_profile`).
A run from rest deflects in proportion to r0, so every critical speed depends on the
ratio delta / r0 only; on log-spaced axes with one common ratio step, the grid holds
few distinct ratios, and the numerical map costs little more than one line of it.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rotrod_core.analysis.critical import STARTS, critical_speed, critical_speed_for_profile
from rotrod_core.command.profiles import Profile
from rotrod_core.model.params import RodParams


@dataclass(frozen=True)
class CriticalSpeedMap:
    """Critical speeds on a grid of eccentricity and deflection limit.

    Attributes:
        eccentricity: r0 values, m, shape (n_r,).
        limit: deflection limits delta, m, shape (n_d,).
        speeds: start name -> critical speeds, rad/s, shape (n_d, n_r); the closed
            forms under 'quasi_static', 'step', 'impulsive', the numerical one under
            the profile's label.
        natural_frequency: w0 (the lower of the two for k1 != k2), rad/s.
        numerical_step: step of the numerical runs, s.
    """

    eccentricity: np.ndarray
    limit: np.ndarray
    speeds: dict
    natural_frequency: float
    numerical_step: float


def log_grid(anchor: float, step_factor: float, below: int, above: int) -> np.ndarray:
    """Values anchor * q^k for k = -below .. above (ascending), q = ``step_factor`` > 1.

    Two such grids with the same q give ratios on one lattice (few distinct ratios).
    """
    if not (anchor > 0 and step_factor > 1 and below >= 0 and above >= 0):
        raise ValueError('log_grid needs anchor > 0, step_factor > 1, below, above >= 0')
    return anchor * step_factor ** np.arange(-below, above + 1, dtype=float)


def critical_speed_map(params: RodParams, eccentricities, limits, profile: Profile,
                       label: str, dt: float = 5e-3, progress=None) -> CriticalSpeedMap:
    """Closed-form and numerical critical speeds over (limit, eccentricity).

    Args:
        params: the system (its eccentricity is replaced by the grid).
        eccentricities: r0 values, m.
        limits: deflection limits, m.
        profile: the shape whose numerical critical speed is mapped.
        label: the key of the numerical map in ``speeds``.
        dt: step of the numerical runs, s.
        progress: optional callable, called with the number of runs done.
    """
    r0 = np.asarray(eccentricities, dtype=float)
    d = np.asarray(limits, dtype=float)
    grid = params.replace(eccentricity=r0[None, :])
    speeds = {s: np.broadcast_to(critical_speed(grid, d[:, None], s), (len(d), len(r0)))
              for s in STARTS}
    speeds[label] = np.asarray(critical_speed_for_profile(grid, profile, d[:, None], dt=dt,
                                                          progress=progress))
    w0 = float(np.sqrt(min(np.min(params.stiffness_radial),
                           np.min(params.stiffness_tangential)) / np.min(params.modal_mass)))
    return CriticalSpeedMap(eccentricity=r0, limit=d, speeds=speeds, natural_frequency=w0,
                            numerical_step=dt)
