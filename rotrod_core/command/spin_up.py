"""The profile of a spin-up goal (the SpinUp action): what the hub is to follow.

A goal names a target angular velocity and a profile: ``planned`` (the fastest
vibration-free change from the current speed, :func:`rotrod_core.plan_spin_up`),
``planned_robust`` (the same, its residual bound held for natural frequencies within
(1 +- robust_band) w0), ``eq26`` (the spin-up stage of the paper's Eq. 26, over T =
``duration``) or ``ramp`` (a linear ramp over ``duration``). :func:`goal_profile`
builds it through :mod:`rotrod_core.command.registry` (the names mean what they mean
for the profile publisher's parameters and the CLI) or raises ValueError with the
reason a goal is refused. The profile starts at once (no lead at the start speed): it
goes to the simulator as one trajectory, executed on the simulator's clock.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from rotrod_core.command.profiles import Profile
from rotrod_core.command.registry import (
    options_with_defaults,
    plan_from_options,
    profile_from_options,
)
from rotrod_core.model.params import RodParams

GOAL_PROFILES = ('planned', 'planned_robust', 'eq26', 'ramp')
"""The profiles a goal may name (rotrod_interfaces/SpinUp's constants)."""
AT_REST = 1e-9
"""|w| (rad/s) below which the hub is at rest: eq26 and ramp start from rest."""


@dataclass(frozen=True)
class GoalProfile:
    """What the hub follows for a goal: ``profile`` from 0, ending at the target.

    ``change_time`` is when the profile's change ends (s from its start), after which it
    holds the target; ``predicted_residual`` the planner's predicted free whirl after
    arrival (m; NaN for eq26 and ramp).
    """

    profile: Profile
    change_time: float
    predicted_residual: float


def goal_profile(name: str, omega_start: float, omega_target: float, *,
                 deflection_limit: float = 0.0, residual: float = 0.0,
                 robust_band: float = 0.0, duration: float = 0.0,
                 max_angular_acceleration: float | None = None,
                 params: RodParams | None = None) -> GoalProfile:
    """The profile of a goal from ``omega_start`` (the hub's speed now) to ``omega_target``.

    rad/s, m and s; a 0 for ``deflection_limit``, ``residual`` or ``duration`` takes
    the profile's default (:data:`~rotrod_core.command.registry.PROFILE_OPTIONS`);
    ``max_angular_acceleration`` is the simulator's bound (rad/s^2; None: the default).
    Raises ValueError with the reason: an unknown profile, a non-finite number, eq26
    or ramp from a turning hub, planned_robust without a band in (0, 1), or a plan the
    planner cannot make (e.g. a target at or past the lowest natural frequency).
    """
    if name not in GOAL_PROFILES:
        raise ValueError(f'profile must be one of {", ".join(GOAL_PROFILES)}, got {name!r}')
    values = {'omega_start': omega_start, 'omega_target': omega_target,
              'deflection_limit': deflection_limit, 'residual': residual,
              'robust_band': robust_band, 'duration': duration}
    for key, value in values.items():
        if isinstance(value, bool) or not isinstance(value, (int, float)) \
                or not math.isfinite(value):
            raise ValueError(f'{key} must be a finite number, got {value!r}')
    for key in ('deflection_limit', 'residual', 'robust_band', 'duration'):
        if values[key] < 0:
            raise ValueError(f'{key} must be >= 0 (0: the default), got {values[key]!r}')
    options = {'omega_start': omega_start, 'omega_target': omega_target,
               'deflection_limit': deflection_limit or None, 'residual': residual or None,
               'max_angular_acceleration': max_angular_acceleration}
    if name in ('planned', 'planned_robust'):
        if name == 'planned_robust' and not 0.0 < robust_band < 1.0:
            raise ValueError(f'planned_robust needs robust_band in (0, 1), got {robust_band!r}')
        options['robust'] = robust_band if name == 'planned_robust' else 0.0
        plan = plan_from_options(RodParams() if params is None else params, options)
        predicted = plan.band_residual if name == 'planned_robust' else plan.residual_amplitude
        return GoalProfile(plan, plan.end_time,
                           math.nan if predicted is None else float(predicted))
    if abs(omega_start) > AT_REST:
        raise ValueError(f'{name} starts from rest; the hub turns at {omega_start:g} rad/s '
                         '(use planned from a turning hub)')
    o = options_with_defaults({'omega_target': omega_target})
    if name == 'eq26':
        period = duration or o['period']
        profile = profile_from_options('eq26', {'period': period,
                                                'omega_target': omega_target})
    else:
        period = duration or o['ramp_time']
        profile = profile_from_options('ramp', {'ramp_time': period,
                                                'omega_target': omega_target})
    return GoalProfile(profile, period, math.nan)


__all__ = ['AT_REST', 'GOAL_PROFILES', 'GoalProfile', 'goal_profile']
