"""The named profiles built from options: one table for the CLI and the profile publisher.

:data:`PROFILE_OPTIONS` names every setting (its unit, range and the profiles that use
it), :data:`OPTION_PROFILES` the profiles, and :func:`profile_from_options` builds one.
``rotrod simulate --profile NAME`` (options as flags) and the ``profile_publisher`` node
(options as parameters of the same names) both build their profiles here, so a name
means the same profile everywhere.

The planned spin-up (``planned``) is one entry: :func:`rotrod_core.plan_spin_up` with
the planner's own argument names, for a given rod. This module sits above
:mod:`~rotrod_core.command.profiles` and :mod:`~rotrod_core.command.planner` (which
returns a profile), so neither imports the other's registry.

The acceleration contract with the simulator (docs/planner.md): a planned profile stays
within :data:`PLANNED_ACCELERATION_FRACTION` of ``max_angular_acceleration``, whose
default is the simulator's (:data:`~rotrod_core.command.shaping.DEFAULT_MAX_ANGULAR_ACCELERATION`);
the profile publisher reads the simulator's from its robot_description. 0 plans
without a bound, and :func:`describe` says what the simulator must then allow.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

from rotrod_core.command.planner import plan_spin_up, residual_bound
from rotrod_core.command.profiles import (
    ConstantProfile,
    Eq26Profile,
    Profile,
    RampProfile,
    SineSweepProfile,
    SpinUpProfile,
    StepProfile,
    TableProfile,
)
from rotrod_core.command.shaping import DEFAULT_MAX_ANGULAR_ACCELERATION
from rotrod_core.model.params import RodParams
from rotrod_core.numerics.checks import finite_number

PLANNED_ACCELERATION_FRACTION = 0.9
"""A planned profile keeps |w'| within this fraction of ``max_angular_acceleration``.

The simulator follows the stream's linear interpolation on a grid it fits to the
arrival times, at most at its bound: a plan that rides the bound exactly is slowed
wherever rounding or the fitted grid steepens a segment by a hair, and the lag leaves
a whirl (``bench/bench_stream.py`` streams a plan at the bound and one at 0.9 of it
through the simulator's engine)."""

PLAN_LEAD = 3.0
"""A planned profile begins its change after this long (s) at its start speed. The
simulator places streamed samples on a grid it fits to their arrival times; a
stream's first samples fix that grid poorly, and while w changes an error of the grid
is an error of w' x it in w. Seconds of the start speed first let the grid settle
(``GRID_TIME_CONSTANT`` of :mod:`rotrod_core.command.shaping`;
``bench/bench_stream.py``)."""

PLAN_HOLD = 1.0
"""After a planned profile's end the profile publisher streams its final speed this
long (s) by default: the simulator bridges a stream that stops by extrapolating its
last three samples for up to 0.5 s, and the last samples of a plan still curve."""


@dataclass(frozen=True)
class ProfileOption:
    """One setting of the named profiles, shared by the CLI and the profile publisher."""

    name: str
    default: Any
    unit: str
    description: str
    low: float | None = None
    high: float | None = None


PROFILE_OPTIONS = (
    ProfileOption('period', 15.0, 's', 'eq26: stage length T', 0.0, 1e6),
    ProfileOption('omega_target', 2.0, 'rad/s', 'eq26 and ramp: top speed; constant: the '
                  'speed; step: the speed after the step; planned: the speed to arrive at '
                  '(>= 0)', -1e4, 1e4),
    ProfileOption('omega_start', 0.0, 'rad/s', 'step: the speed before the step; planned: '
                  'the speed the plan starts from (>= 0; the hub already turning at it, the '
                  'rod at rest about its static deflection there)', -1e4, 1e4),
    ProfileOption('t_step', 1.0, 's', 'step: time of the step', 0.0, 1e6),
    ProfileOption('ramp_time', 15.0, 's', 'ramp: duration of the ramp', 0.0, 1e6),
    ProfileOption('t_start', 0.0, 's', 'ramp: start of the ramp', 0.0, 1e6),
    ProfileOption('amplitude', 0.2, 'rad/s', 'sine_sweep: amplitude of w', -1e4, 1e4),
    ProfileOption('f_start', 0.5, 'Hz', 'sine_sweep: frequency at the start', 0.0, 1e4),
    ProfileOption('f_end', 4.0, 'Hz', 'sine_sweep: frequency at the end', 0.0, 1e4),
    ProfileOption('sweep_time', 30.0, 's', 'sine_sweep: duration of the sweep', 0.0, 1e6),
    ProfileOption('offset', 0.0, 'rad/s', 'sine_sweep: mean speed', -1e4, 1e4),
    ProfileOption('table_file', '', '', 'table: CSV file of (time s, omega rad/s) rows'),
    ProfileOption('deflection_limit', 0.003, 'm', 'planned: largest tip deflection '
                  'sqrt(u^2 + v^2) during the change (> 0; the simulator\'s critical '
                  'deflection of the same name)', 0.0, 100.0),
    ProfileOption('residual', 2.5e-7, 'm', 'planned: largest free whirl left after '
                  'arrival, about the static deflection at omega_target (> 0)', 0.0, 1.0),
    ProfileOption('robust', 0.0, '1', 'planned: the residual bound holds for every '
                  'natural frequency within (1 +- robust) w0 (0 <= robust < 1)', 0.0, 1.0),
    ProfileOption('max_angular_acceleration', DEFAULT_MAX_ANGULAR_ACCELERATION, 'rad/s^2',
                  "planned: the simulator's bound on |w'| (give both nodes the same "
                  f'value); the plan stays within {PLANNED_ACCELERATION_FRACTION:g} x it. '
                  '0 = no bound (the fastest plan; the simulator must then allow its '
                  "largest |w'|, which is logged)", 0.0, 1e6),
)
"""The settings of :func:`profile_from_options`, one naming for the CLI and the nodes."""

OPTION_PROFILES = ('eq26', 'constant', 'step', 'ramp', 'sine_sweep', 'table', 'planned')
"""The profiles :func:`profile_from_options` builds from options."""

PLANNED_OPTIONS = ('omega_target', 'omega_start', 'deflection_limit', 'residual', 'robust',
                   'max_angular_acceleration')
"""The options of ``planned``: :func:`rotrod_core.plan_spin_up`'s arguments."""


def options_with_defaults(options: dict) -> dict:
    """Every option of :data:`PROFILE_OPTIONS`: those given (not None), else the default."""
    o = {opt.name: opt.default for opt in PROFILE_OPTIONS}
    o.update({k: v for k, v in options.items() if k in o and v is not None})
    return o


def planned_bound(max_angular_acceleration) -> float | None:
    """The |w'| bound a plan is given for ``max_angular_acceleration`` (rad/s^2; 0: none)."""
    bound = finite_number('max_angular_acceleration', max_angular_acceleration,
                          nonnegative=True)
    return PLANNED_ACCELERATION_FRACTION * bound if bound else None


def plan_from_options(params: RodParams, options: dict) -> SpinUpProfile:
    """The planned spin-up of :data:`PLANNED_OPTIONS` for the rod ``params``.

    Raises ValueError naming the option or the constraint that cannot be met.
    """
    o = options_with_defaults(options)
    try:
        return plan_spin_up(params, o['omega_target'], omega_start=o['omega_start'],
                            deflection_limit=o['deflection_limit'], residual=o['residual'],
                            robust=o['robust'],
                            max_angular_acceleration=planned_bound(
                                o['max_angular_acceleration']))
    except ValueError as exc:
        bound = o['max_angular_acceleration']
        within = (f' (|w\'| planned within {PLANNED_ACCELERATION_FRACTION:g} x '
                  f'max_angular_acceleration {bound:g} rad/s^2)'
                  if 'max_angular_acceleration' in str(exc) else '')
        raise ValueError(f'profile planned: {exc}{within}') from None


def profile_from_options(name: str, options: dict, params: RodParams | None = None) -> Profile:
    """The profile ``name`` built from :data:`PROFILE_OPTIONS` values (missing: default).

    ``params`` is the rod a ``planned`` profile is planned for (default: Table 1);
    the other profiles do not depend on it. A planned profile holds its start speed
    for :data:`PLAN_LEAD` s before the change (its ``t_start``). Raises ValueError
    with the reason (unknown name, bad values, no table file, a plan that cannot be
    made).
    """
    o = options_with_defaults(options)
    if name == 'eq26':
        return Eq26Profile(period=o['period'], omega_target=o['omega_target'])
    if name == 'constant':
        return ConstantProfile(o['omega_target'])
    if name == 'step':
        return StepProfile(o['omega_target'], t_step=o['t_step'], omega_start=o['omega_start'])
    if name == 'ramp':
        return RampProfile(o['omega_target'], o['ramp_time'], t_start=o['t_start'])
    if name == 'sine_sweep':
        return SineSweepProfile(o['amplitude'], o['f_start'], o['f_end'],
                                duration=o['sweep_time'], offset=o['offset'])
    if name == 'table':
        if not o['table_file']:
            raise ValueError('profile table needs a table file (table_file, --table)')
        return TableProfile.from_csv(o['table_file'])
    if name == 'planned':
        plan = plan_from_options(RodParams() if params is None else params, o)
        return plan.started_at(PLAN_LEAD)
    raise ValueError(f'profile must be one of {", ".join(OPTION_PROFILES)}; got {name!r}')


def stream_duration(profile: Profile) -> float:
    """How long to stream ``profile`` by default, s: to its end (0 if it never settles).

    A planned spin-up is followed by :data:`PLAN_HOLD` s of its final speed, so that
    the stream arrives before it stops (see :data:`PLAN_HOLD`).
    """
    end = profile.end_time or 0.0
    return end + PLAN_HOLD if isinstance(profile, SpinUpProfile) else end


def describe(profile: Profile, options: dict) -> list:
    """Lines that say what a planned profile is and what the simulator must allow.

    Empty for the other profiles. The first line: duration, peak deflection, the
    bound the residual whirl meets (and over the band), largest |w'| and the
    acceleration bound honoured; the
    second: the ``max_angular_acceleration`` the simulator needs.
    """
    if not isinstance(profile, SpinUpProfile):
        return []
    o = options_with_defaults(options)
    bound = float(o['max_angular_acceleration'])
    peak_acc = profile.max_angular_acceleration
    nan = math.nan          # a SpinUpProfile made by hand has no planner's predictions
    peak = nan if profile.peak_deflection is None else profile.peak_deflection
    residual = nan if profile.residual_amplitude is None else profile.residual_amplitude
    band_residual = nan if profile.band_residual is None else profile.band_residual
    band = (f', {residual_bound(band_residual, o["residual"])} for natural frequencies '
            f'within (1 +- {profile.robust:g}) w0' if profile.robust else '')
    honoured = (f'within {PLANNED_ACCELERATION_FRACTION:g} x max_angular_acceleration '
                f'{bound:g} rad/s^2' if bound else 'no bound (max_angular_acceleration 0)')
    lead = f' after {profile.t_start:g} s at the start speed' if profile.t_start else ''
    plan = (f'planned {profile.omega_start:g} -> {profile.omega_target:g} rad/s{lead}: '
            f'duration {profile.duration:.3f} s, peak deflection '
            f'{peak * 1e3:.3f} mm '
            f'(deflection_limit {o["deflection_limit"] * 1e3:g} mm), residual whirl '
            f'{residual_bound(residual, o["residual"])}{band}, largest |w\'| {peak_acc:.3g} '
            f'rad/s^2 ({honoured})')
    # rounded up to 1e-3, but a plan that rides its bound (to rounding) needs the bound
    need = math.ceil(peak_acc * 1e3 * (1 - 1e-9)) / 1e3
    if bound:
        must = (f'the simulator must allow |w\'| up to {need:g} rad/s^2: give it the same '
                f'max_angular_acceleration {bound:g} rad/s^2 (one params file for both '
                'nodes, e.g. config/planned.yaml)')
    else:
        must = (f'the simulator must allow |w\'| up to {need:g} rad/s^2: set its '
                f'max_angular_acceleration to at least {need:g} rad/s^2 (default '
                f'{DEFAULT_MAX_ANGULAR_ACCELERATION:g}), or it slows the plan and a whirl '
                'remains')
    if profile.omega_start:
        must += (f'; the hub must already turn at {profile.omega_start:g} rad/s with the rod '
                 'at rest about its static deflection there')
    return [plan, must]
