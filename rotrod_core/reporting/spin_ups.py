"""The paper's Eq. 26 spin-up beside planned ones (issue 19's report section).

Table 1 from rest to 2 rad/s under the paper's 3 mm: Eq. 26 (T = 15 s) and three
planned spin-ups of the profile registry (``profile: planned``, the options the
profile publisher takes): the fastest (no acceleration bound), the one within the
simulator's default bound, and the one of ``config/planned.yaml`` (robust 0.1).
Every number is computed here by ``simulate``: duration, largest |w'|, peak
deflection, the free whirl left after arrival (``whirl_residual``) on the nominal rod
and the largest over natural frequencies within +-10 % of w0 (stiffness scaled, 21
rods).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rotrod_core.command.planner import whirl_residual
from rotrod_core.command.profiles import Eq26Profile, Profile
from rotrod_core.command.registry import options_with_defaults, plan_from_options
from rotrod_core.model.params import RodParams
from rotrod_core.offline.result import SimulationResult
from rotrod_core.offline.simulate import simulate

OMEGA_TARGET = 2.0
"""The paper's hold speed, rad/s."""

STEP = 1e-3
"""Largest simulation step, s (the step divides each spin-up's duration)."""

BAND = 0.1
"""Half-width of the band of natural frequencies the residual is also measured over."""

BAND_RODS = 21
"""Rods across the band."""

PLANNED: tuple[tuple[str, dict], ...] = (
    ('planned, fastest (max_angular_acceleration 0: no bound)',
     {'max_angular_acceleration': 0.0}),
    ("planned within the simulator's default bound (max_angular_acceleration 0.5)", {}),
    ('planned, config/planned.yaml (robust 0.1, max_angular_acceleration 0.5)',
     {'robust': 0.1, 'max_angular_acceleration': 0.5}),
)
"""(label, options of ``profile: planned``) of the planned rows, 0 -> 2 rad/s."""


@dataclass(frozen=True)
class SpinUp:
    """One spin-up and what ``simulate`` finds (SI units).

    Attributes:
        label: what it is.
        profile: the profile (starting at t = 0).
        duration: time to reach the target speed, s.
        max_angular_acceleration: largest |w'|, rad/s^2.
        peak_deflection: largest |r| during the spin-up, m.
        residual: free whirl about the static deflection at the target, m, after arrival.
        band_residual: the largest residual over natural frequencies (1 +- BAND) w0, m.
        run: the nominal run over the spin-up.
        bound: the residual a plan is held to, m (None: not planned).
        band_bound: the residual a robust plan holds over its band, m (None: none).
    """

    label: str
    profile: Profile
    duration: float
    max_angular_acceleration: float
    peak_deflection: float
    residual: float
    band_residual: float
    run: SimulationResult
    bound: float | None = None
    band_bound: float | None = None


def _arrival(params: RodParams, profile: Profile, duration: float) -> tuple:
    """(run over [0, duration], residual at its end) with the end on the time grid."""
    n = math.ceil(duration / STEP)
    run = simulate(params, profile, duration, dt=duration / n)
    return run, whirl_residual(params, OMEGA_TARGET, run.u[-1], run.v[-1], run.du[-1],
                               run.dv[-1])


def measure(label: str, profile: Profile, duration: float, params: RodParams,
            bound: float | None = None, band_bound: float | None = None) -> SpinUp:
    """Simulate ``profile`` to ``duration`` on ``params`` and across the band."""
    run, residual = _arrival(params, profile, duration)
    band = max(_arrival(params.replace(youngs_modulus=params.youngs_modulus * s * s), profile,
                        duration)[1] for s in np.linspace(1 - BAND, 1 + BAND, BAND_RODS))
    return SpinUp(label=label, profile=profile, duration=duration,
                  max_angular_acceleration=float(np.max(np.abs(run.omega_dot))),
                  peak_deflection=float(np.max(np.hypot(run.u, run.v))), residual=residual,
                  band_residual=band, run=run, bound=bound, band_bound=band_bound)


def spin_ups(params: RodParams | None = None) -> list:
    """Eq. 26's spin-up, then the planned rows of :data:`PLANNED`, each measured."""
    params = RodParams() if params is None else params
    eq26 = Eq26Profile(period=15.0, omega_target=OMEGA_TARGET)
    rows = [measure('Eq. 26 (the paper)', eq26, eq26.period, params)]
    for label, options in PLANNED:
        full = options_with_defaults({'omega_target': OMEGA_TARGET, **options})
        plan = plan_from_options(params, full)
        bound = float(full['residual'])
        rows.append(measure(label, plan, plan.duration, params, bound,
                            bound if full['robust'] else None))
    return rows
