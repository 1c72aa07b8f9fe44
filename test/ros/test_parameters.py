"""The nodes' parameters without a running ROS graph: their specs, defaults and checks,
and the parameter files (Table 1, the real rig)."""

import math
from pathlib import Path

import pytest
import yaml
from reference import R0, D, E, L, M

from rotrod_core import RodParams
from rotrod_core.live.engine import EngineConfig
from rotrod_ros.parameters import (
    ALL_SPECS,
    ROD_SPECS,
    SPECS_BY_NAME,
    build_settings,
    check_value,
    defaults,
)

ROOT = Path(__file__).resolve().parents[2]


def test_parameter_defaults_are_the_core_defaults_and_in_range():
    engine, node = build_settings(defaults())
    assert engine == EngineConfig()
    assert engine.params == RodParams()
    assert {s.name for s in ROD_SPECS} == set(RodParams.__dataclass_fields__)
    for spec in ALL_SPECS:
        check_value(spec, spec.default)
        assert spec.description and len(spec.description) > 10
    assert node.publish_rate == 100.0 and node.real_time_factor == 1.0
    assert engine.physics_rate == 1000.0 and engine.deflection_limit == 0.003


@pytest.mark.parametrize('name, value, match', [
    ('mass', -1.0, 'mass must be in'),
    ('mass', math.nan, 'mass must be finite'),
    ('mass', 'heavy', 'mass must be a number'),
    ('markers', 1, 'markers must be a bool'),
    ('drive', 'position', 'drive must be one of'),
    ('publish_rate', 2000.0, 'exceeds physics_rate'),
    ('physics_rate', 50.0, 'too low'),
    ('section', 'rectangular', 'section_width'),
    ('section_width', 0.004, 'applies to section=.rectangular. only'),
    ('command_timeout', -1.0, 'command_timeout must be in'),
    ('command_timeout', math.inf, 'command_timeout must be finite'),
    ('command_timeout', 0.05, r'shorter than 2 x setpoint_delay \(0.1 s\)'),
])
def test_bad_values_and_combinations_are_refused_with_a_reason(name, value, match):
    values = defaults()
    values[name] = value
    with pytest.raises(ValueError, match=match):
        build_settings(values)


def test_command_timeout_is_off_by_default_passed_to_the_engine_and_documented():
    spec = SPECS_BY_NAME['command_timeout']
    assert spec.default == 0.0 and spec.low == 0.0 and ', s' in spec.description
    engine, _ = build_settings({**defaults(), 'command_timeout': 0.5})
    assert engine.command_timeout == 0.5
    engine, _ = build_settings({**defaults(), 'command_timeout': 0.4, 'setpoint_delay': 0.2})
    assert engine.command_timeout == 0.4
    readme = (ROOT / 'docs' / 'usage.md').read_text()
    assert '`command_timeout` (s; 0 = off' in readme
    assert 'at least 2 × `setpoint_delay`' in readme


def test_a_rectangular_section_is_built_from_its_two_sizes():
    values = {**defaults(), 'section': 'rectangular', 'section_width': 0.004,
              'section_thickness': 0.002}
    engine, _ = build_settings(values)
    assert engine.params.stiffness_radial == pytest.approx(4 * engine.params.stiffness_tangential)


def test_table1_file_holds_the_papers_parameters_and_known_names():
    doc = yaml.safe_load((ROOT / 'config' / 'table1.yaml').read_text())
    assert list(doc) == ['/**/rotrod_simulator']
    values = doc['/**/rotrod_simulator']['ros__parameters']
    assert set(values) <= set(SPECS_BY_NAME)
    assert (values['mass'], values['rod_length'], values['rod_diameter'],
            values['youngs_modulus'], values['eccentricity']) == (M, L, D, E, R0)
    assert values['deflection_limit'] == 0.003          # the paper's 3.0 mm
    build_settings({**defaults(), **values})


@pytest.mark.parametrize('name', sorted(p.name for p in (ROOT / 'config').glob('*.yaml')))
def test_the_rod_is_given_to_the_simulator_alone(name):
    """No parameters file repeats a rod parameter for another node: they read the rod
    from the simulator's robot_description (issue #35)."""
    doc = yaml.safe_load((ROOT / 'config' / name).read_text()) or {}
    rod = {s.name for s in ROD_SPECS}
    for key, body in doc.items():
        if key.endswith('rotrod_simulator') or not isinstance(body, dict):
            continue
        given = set((body.get('ros__parameters') or {}))
        assert not given & rod, f'{name}: {key} repeats {sorted(given & rod)}'


def test_the_drawn_parameters_are_the_simulators():
    """The logger's drawn parameters have the simulator's defaults, units and ranges."""
    from rotrod_ros.rerun_logger import DRAWN, PARAMETERS
    specs = {s.name: s for s in PARAMETERS}
    for name in DRAWN:
        sim = SPECS_BY_NAME[name]
        assert (specs[name].default, specs[name].unit, specs[name].bounds) == (
            sim.default, sim.unit, sim.bounds)
