import math

import numpy as np
import pytest
from reference import I_AREA, W0, K

from rotrod_core import RodParams, disk_inertia


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
