"""Shared pieces of the property-based tests: extreme, non-finite and wrongly typed input
never gives a silent NaN.

The common contract of rotrod_core, checked with hypothesis over the parameters, the
profiles, the real-time stepper and engine, the setpoint shaper, the whirl estimator,
the constant-rotation analysis and the offline run (each in the test file of its module,
e.g. test/core/live/test_engine.py; this module holds their settings and the strategies
several of them draw from): every call either raises a clear ValueError (a
:class:`~rotrod_core.live.engine.CommandRejected` for a refused command, a
:class:`~rotrod_core.numerics.checks.NonFiniteStateError` for a step that would overflow;
both keep the previous state), or returns finite numbers. Never NaN or +-inf where a
number is promised, never a ZeroDivisionError, OverflowError or TypeError from the
arithmetic.

Inputs mix sane physical ranges with extreme floats (0, -0, negative, subnormal,
1e300, the largest float, nan, +-inf) and wrong types (str, None, bool). Every test is
derandomized and uses no example database, so a run is reproducible (CI).
"""

import math

import numpy as np
from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

from rotrod_core import (
    ConstantProfile,
    Eq26Profile,
    RampProfile,
    SineSweepProfile,
    StepProfile,
)

PROPS = settings(derandomize=True, database=None, deadline=None, print_blob=False,
                 suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                                        HealthCheck.filter_too_much])


def props(max_examples: int):
    """Settings of one test: reproducible (derandomized, no database), no deadline."""
    return settings(PROPS, max_examples=max_examples)


TINY = 5e-324                   # the smallest subnormal
HUGE = 1.7976931348623157e308   # the largest float
EXTREME_FLOATS = st.sampled_from([0.0, -0.0, -1.0, TINY, -TINY, 2.2e-308, 1e-300, 1e-150,
                                  1e150, 1e300, HUGE, -1e300, -HUGE,
                                  math.nan, math.inf, -math.inf])
WRONG_TYPES = st.sampled_from(['1 kg', 'fast', None, True, False, 10**400, -10**400])
"""Wrong types, and ints beyond the float range (float() raises OverflowError). (A
numeric string such as '1.0' is a number by design: float('1.0').)"""
CONTAINERS = st.sampled_from([[], (1.0, 2.0), {}])
NON_FINITE = st.sampled_from([math.nan, math.inf, -math.inf])


def anything(sane):
    """A value from a sane range, an extreme float or a wrongly typed value."""
    return st.one_of(sane, sane, EXTREME_FLOATS, st.floats(), WRONG_TYPES)


def finite(x) -> bool:
    """True when every element of x is a finite number."""
    return bool(np.all(np.isfinite(np.asarray(x, dtype=float))))


def is_number(x) -> bool:
    """True for a finite float or int (not a bool): what finite_number accepts, but
    numeric strings."""
    return (isinstance(x, (int, float)) and not isinstance(x, bool)
            and abs(x) <= HUGE and math.isfinite(x))


# -- RodParams ------------------------------------------------------------------------

POSITIVE_FIELDS = ('mass', 'rod_length', 'rod_diameter', 'youngs_modulus')
NONNEGATIVE_FIELDS = ('eccentricity', 'hub_inertia', 'damping_ratio')
SANE = {
    'mass': st.floats(1e-3, 10.0), 'rod_length': st.floats(0.01, 2.0),
    'rod_diameter': st.floats(1e-4, 0.05), 'youngs_modulus': st.floats(1e9, 400e9),
    'eccentricity': st.floats(0.0, 0.5), 'hub_inertia': st.floats(0.0, 1.0),
    'damping_ratio': st.floats(0.0, 0.2), 'section_width': st.floats(1e-4, 0.05),
    'section_thickness': st.floats(1e-4, 0.05),
}


LAB = {     # near the paper's rig: natural frequencies of a few Hz to ~150 Hz
    'mass': st.floats(0.05, 2.0), 'rod_length': st.floats(0.1, 1.0),
    'rod_diameter': st.floats(1e-3, 6e-3), 'youngs_modulus': st.floats(50e9, 250e9),
    'eccentricity': st.floats(0.0, 0.3), 'hub_inertia': st.floats(0.0, 0.5),
    'damping_ratio': st.floats(0.0, 0.1), 'section_width': st.floats(1e-3, 6e-3),
    'section_thickness': st.floats(1e-3, 6e-3),
}


@st.composite
def rod_fields(draw, sane_only=False, ranges=SANE):
    """Keyword arguments for RodParams: a random subset of fields, sane or not."""
    pick = (lambda name: ranges[name]) if sane_only else (lambda name: anything(ranges[name]))
    section = 'circular'
    if draw(st.booleans()):
        section = 'rectangular' if sane_only else draw(
            st.sampled_from(['rectangular', 'rectangular', 'circular', 'square', None]))
    fields = {'section': section}
    for name in POSITIVE_FIELDS + NONNEGATIVE_FIELDS:
        if name == 'rod_diameter' and section == 'rectangular':
            continue
        if draw(st.booleans()):
            fields[name] = draw(pick(name))
    if section == 'rectangular':
        for name in ('section_width', 'section_thickness'):
            fields[name] = draw(pick(name))
    return fields


# -- profiles -------------------------------------------------------------------------

PROFILE_FIELDS = {
    Eq26Profile: {'period': st.floats(0.1, 100.0), 'omega_target': st.floats(-50.0, 50.0)},
    ConstantProfile: {'omega_target': st.floats(-50.0, 50.0)},
    StepProfile: {'omega_target': st.floats(-50.0, 50.0), 't_step': st.floats(0.0, 100.0),
                  'omega_start': st.floats(-50.0, 50.0)},
    RampProfile: {'omega_target': st.floats(-50.0, 50.0), 'ramp_time': st.floats(0.01, 100.0),
                  't_start': st.floats(0.0, 100.0)},
    SineSweepProfile: {'amplitude': st.floats(-5.0, 5.0), 'f_start': st.floats(0.0, 20.0),
                       'f_end': st.floats(0.0, 20.0), 'duration': st.floats(0.1, 100.0),
                       'offset': st.floats(-50.0, 50.0)},
}
BAD_TIMES = st.one_of(NON_FINITE, st.sampled_from(['1 s', 'now', None, True]))


@st.composite
def profiles(draw, sane_only=False):
    """(a profile class, keyword arguments for it)."""
    cls = draw(st.sampled_from(sorted(PROFILE_FIELDS, key=lambda c: c.__name__)))
    kwargs = {}
    for name, sane in PROFILE_FIELDS[cls].items():
        if draw(st.booleans()):
            kwargs[name] = draw(sane if sane_only else anything(sane))
    return cls, kwargs
