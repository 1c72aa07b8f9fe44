"""The rod's description in the URDF: read back bit for bit, and every defect named."""

import dataclasses
import re

import pytest
from pytransform3d.urdf import UrdfTransformManager

from rotrod_core.live.engine import EngineConfig
from rotrod_core.model.description import (
    DEFAULT_LIMITS,
    DescriptionError,
    DriveLimits,
    differences,
    read_description,
)
from rotrod_core.model.params import RodParams
from rotrod_core.model.urdf import urdf_text

RODS = (RodParams(),
        RodParams(mass=0.4, rod_density=7850.0, gravity=9.81, damping_ratio=0.013),
        RodParams(section='rectangular', section_width=0.003, section_thickness=0.0045,
                  eccentricity=0.1 + 1e-17, hub_inertia=1 / 3, gravity=-9.81))


@pytest.mark.parametrize('params', RODS)
def test_the_rod_and_limits_read_back_are_the_ones_written_bit_for_bit(params):
    limits = DriveLimits(0.45, 12.5, 3.0, 0.0025)
    got = read_description(urdf_text(params, limits=limits, disk_radius=0.21))
    assert got.params == params and differences(got.params, params) == []
    assert got.limits == limits and got.disk_radius == 0.21


def test_the_default_limits_are_the_simulator_s_defaults():
    assert EngineConfig().drive_limits == DEFAULT_LIMITS


def test_a_urdf_library_still_reads_the_urdf_with_the_element():
    tm = UrdfTransformManager()
    tm.load_urdf(urdf_text(RodParams()))
    tm.set_joint('hub', 0.3)
    assert tm.get_transform('tip', 'world').shape == (4, 4)


def edited(pattern, replacement, params=None):
    text = urdf_text(params or RodParams())
    new = re.sub(pattern, replacement, text, count=1)
    assert new != text
    return new


@pytest.mark.parametrize('text, named', [
    ('', 'robot_description is empty'),
    ('<robot', 'not XML'),
    ('<model name="x"/>', 'root element is <model>'),
    (edited(r'(?s)<rotrod version="1">.*</rotrod>', ''), 'has no <rotrod> element'),
    (edited(r'version="1"', 'version="7"'), "version '7'"),
    (edited(r'<rod [^/]*/>', ''), 'has no <rod> element'),
    (edited(r'mass="0.3"', ''), "<rotrod><rod> has no attribute 'mass'"),
    (edited(r'youngs_modulus="[^"]*"', 'youngs_modulus="stiff"'),
     "youngs_modulus='stiff' is not a number"),
    (edited(r'rod_length="0.3"', 'rod_length="-0.3"'), 'RodParams.rod_length must be'),
    (edited(r'eccentricity="0.1"', 'eccentricity="nan"'), 'RodParams.eccentricity'),
    (edited(r'section="circular"', 'section="square"'), 'RodParams.section must be one of'),
    (edited(r'<drive [^/]*/>', ''), 'has no <drive> element'),
    (edited(r'max_omega="50.0"', 'max_omega="0"'), 'DriveLimits.max_omega must be'),
    (edited(r'deflection_limit="0.003"', ''), "<rotrod><drive> has no attribute "
                                                "'deflection_limit'"),
])
def test_a_description_that_cannot_be_read_names_the_field(text, named):
    with pytest.raises(DescriptionError, match=re.escape(named)):
        read_description(text)


def test_a_rectangular_rod_needs_its_sizes():
    rect = RodParams(section='rectangular', section_width=0.003, section_thickness=0.004)
    with pytest.raises(DescriptionError, match="no attribute 'section_width'"):
        read_description(edited(r'section_width="0.003"', '', rect))


def test_differences_name_the_fields():
    a, b = RodParams(), RodParams(mass=0.4, gravity=9.81)
    assert differences(a, b) == ['mass: 0.3 vs 0.4', 'gravity: 0.0 vs 9.81']


def test_limits_must_be_positive_numbers():
    for bad in (0.0, -1.0, float('nan'), True):
        with pytest.raises(ValueError, match='DriveLimits.max_torque'):
            dataclasses.replace(DEFAULT_LIMITS, max_torque=bad)
