import math
import re

import numpy as np
import pytest
from hypothesis import event, given
from hypothesis import strategies as st
from properties import (  # the shared settings and strategies of the property tests
    CONTAINERS,
    EXTREME_FLOATS,
    NONNEGATIVE_FIELDS,
    POSITIVE_FIELDS,
    TINY,
    WRONG_TYPES,
    finite,
    is_number,
    props,
    rod_fields,
)
from reference import I_AREA, W0, K

from rotrod_core import RodParams, disk_inertia
from rotrod_core.model.equations import Coefficients


def test_table1_derived_values():
    p = RodParams()
    assert p.second_moment == pytest.approx(3.976078e-12, rel=1e-6)
    assert p.second_moment == pytest.approx(I_AREA, rel=1e-14)
    assert p.stiffness == pytest.approx(44.178647, rel=1e-7)
    assert p.stiffness == pytest.approx(K, rel=1e-14)
    assert p.natural_frequency == pytest.approx(12.135162, rel=1e-7)
    assert p.natural_frequency / (2 * math.pi) == pytest.approx(1.931371, rel=1e-6)
    assert p.natural_frequency == pytest.approx(W0, rel=1e-14)
    assert p.is_isotropic and not p.is_batch


def test_default_hub_is_a_steel_disk():
    p = RodParams()
    assert p.hub_inertia == pytest.approx(0.5 * 7850 * math.pi * 0.01 * 0.15**4)
    assert disk_inertia(0.15, 0.01) == p.hub_inertia


def test_rectangular_section_has_two_stiffnesses():
    b, h = 0.004, 0.003   # b along e1 (radial), h along e2 (tangential)
    p = RodParams(section='rectangular', section_width=b, section_thickness=h)
    assert p.second_moment_radial == pytest.approx(h * b**3 / 12)
    assert p.second_moment_tangential == pytest.approx(b * h**3 / 12)
    assert p.stiffness_radial / p.stiffness_tangential == pytest.approx((b / h) ** 2)
    assert not p.is_isotropic
    with pytest.raises(ValueError, match='k1 != k2'):
        _ = p.stiffness
    with pytest.raises(ValueError, match='k1 != k2'):
        _ = p.natural_frequency


def test_damping_coefficient():
    p = RodParams(damping_ratio=0.05)
    assert p.damping_radial == pytest.approx(2 * 0.05 * math.sqrt(K * 0.3))


@pytest.mark.parametrize('field', ['mass', 'rod_length', 'rod_diameter', 'youngs_modulus'])
@pytest.mark.parametrize('bad', [0.0, -1.0, float('nan'), float('inf'), '1 kg', True, None])
def test_positive_fields_reject_bad_values(field, bad):
    with pytest.raises(ValueError, match=field):
        RodParams(**{field: bad})


@pytest.mark.parametrize('field', ['eccentricity', 'hub_inertia', 'damping_ratio'])
@pytest.mark.parametrize('bad', [-1e-9, float('nan'), float('-inf')])
def test_nonnegative_fields_reject_bad_values(field, bad):
    with pytest.raises(ValueError, match=field):
        RodParams(**{field: bad})


def test_zero_eccentricity_and_zero_hub_are_allowed():
    assert RodParams(eccentricity=0.0, hub_inertia=0.0).eccentricity == 0.0


def test_section_errors():
    with pytest.raises(ValueError, match='section'):
        RodParams(section='hexagonal')
    with pytest.raises(ValueError, match='section_width'):
        RodParams(section='rectangular', section_thickness=0.003)
    with pytest.raises(ValueError, match="rectangular"):
        RodParams(section_width=0.003)


def test_batch_fields_and_bad_array_entries():
    p = RodParams(eccentricity=np.array([0.05, 0.1]), mass=np.array([[0.3], [0.6]]))
    assert p.shape == (2, 2) and p.is_batch
    assert p.item((1, 0)).mass == 0.6 and p.item((1, 0)).eccentricity == 0.05
    with pytest.raises(ValueError, match='mass'):
        RodParams(mass=np.array([0.3, -0.1]))
    with pytest.raises(ValueError, match='broadcast'):
        RodParams(mass=np.ones(3) * 0.3, eccentricity=np.ones(2) * 0.1)


DERIVED = ('second_moment_radial', 'second_moment_tangential', 'stiffness_radial',
           'stiffness_tangential', 'natural_frequency_radial', 'natural_frequency_tangential')


def check_rod(p: RodParams):
    """Every derived quantity of a valid RodParams is finite, > 0 (damping >= 0)."""
    for name in DERIVED:
        value = getattr(p, name)
        assert finite(value) and np.all(np.asarray(value) > 0), (name, value)
    for name in ('damping_radial', 'damping_tangential'):
        value = getattr(p, name)
        assert finite(value) and np.all(np.asarray(value) >= 0), (name, value)
    co = Coefficients.from_params(p)
    for name, value in vars(co).items():
        assert finite(value), (name, value)
    assert np.all(co.w1sq > 0) and np.all(co.w2sq > 0)


@props(400)
@given(rod_fields())
def test_rod_params_are_refused_clearly_or_derive_finite_positive_quantities(fields):
    """RodParams(**fields): a ValueError naming the field, or all derived values finite."""
    try:
        p = RodParams(**fields)
    except ValueError as exc:
        event('refused')
        message = str(exc)
        assert message.startswith('RodParams')
        named = [f for f in (*POSITIVE_FIELDS, *NONNEGATIVE_FIELDS, 'section',
                             'section_width', 'section_thickness') if f in message]
        assert named, message
        return
    check_rod(p)


@props(150)
@given(st.sampled_from(POSITIVE_FIELDS + NONNEGATIVE_FIELDS),
       st.one_of(EXTREME_FLOATS, WRONG_TYPES, CONTAINERS))
def test_one_bad_field_is_named_in_the_error(name, value):
    """A single extreme value is either refused naming that field, or is harmless.
    (A sequence of numbers is a batch of systems, by design.)"""
    try:
        p = RodParams(**{name: value})
    except ValueError as exc:
        assert re.match(rf'RodParams(\.{name}\b|: .*\b{name}\b)', str(exc)), str(exc)
        return
    assert is_number(value) or value == (1.0, 2.0)
    check_rod(p)


def test_regression_rod_params_whose_derived_values_overflow_or_vanish_are_refused():
    # d^4 overflowed: the stiffness was inf; d^4 underflowed: k = 0, w0 = 0; l^3
    # overflowed as a Python float: OverflowError
    for fields in ({'rod_diameter': 1e300}, {'rod_diameter': 1e-100},
                   {'youngs_modulus': TINY}, {'rod_length': 1e-200}, {'rod_length': 1e150},
                   {'mass': 1e-320}):
        with pytest.raises(ValueError, match='RodParams'):
            RodParams(**fields)
    # k m overflowed (sqrt(k m) = inf), and with damping_ratio = 0 the damping was 0 x inf
    heavy = RodParams(mass=1e300, youngs_modulus=1e300, rod_diameter=1.0)
    assert heavy.damping_radial == 0.0 and heavy.damping_tangential == 0.0
    assert finite(heavy.replace(damping_ratio=0.1).damping_radial)


@props(60)
@given(st.lists(st.floats(1e-3, 10.0), min_size=1, max_size=4),
       st.sampled_from([1e300, TINY, 1e-100]))
def test_a_batch_with_one_unusable_system_is_refused(masses, diameter):
    diameters = np.full(len(masses), 0.003)
    diameters[-1] = diameter
    with pytest.raises(ValueError, match='RodParams'):
        RodParams(mass=np.array(masses), rod_diameter=diameters)


def test_the_load_radius_is_r0_without_a_rod_and_r0_me_over_m_with_one():
    """re = (Me / M) r0: the shape integrals' 3/8 and 33/140 of the rod's mass."""
    assert RodParams().load_radius == RodParams().eccentricity
    heavy = RodParams(rod_density=7850.0)
    rod = 7850.0 * heavy.section_area * heavy.rod_length
    m = heavy.mass
    assert heavy.load_radius == pytest.approx(
        heavy.eccentricity * (m + 3 / 8 * rod) / (m + 33 / 140 * rod), rel=1e-15)
