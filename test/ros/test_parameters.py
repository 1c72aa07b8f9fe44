"""Pieces of the simulator node that need no running ROS graph: parameters, pacing,
messages, drawing geometry, the Table 1 parameter file."""

import math
from pathlib import Path

import numpy as np
import pytest
import yaml
from reference import R0, D, E, L, M

from rotrod_core import RodParams
from rotrod_core.live.engine import EngineConfig
from rotrod_core.live.pacing import Pacer, StampClock
from rotrod_core.model.equations import Coefficients, State, inertial_position
from rotrod_core.model.geometry import cantilever_shape, rod_centerline, sphere_radius
from rotrod_ros import messages
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
    assert list(doc) == ['/**/rotrod_simulator', '/**/rotrod_profile_publisher']
    values = doc['/**/rotrod_simulator']['ros__parameters']
    assert set(values) <= set(SPECS_BY_NAME)
    assert (values['mass'], values['rod_length'], values['rod_diameter'],
            values['youngs_modulus'], values['eccentricity']) == (M, L, D, E, R0)
    assert values['deflection_limit'] == 0.003          # the paper's 3.0 mm
    build_settings({**defaults(), **values})


@pytest.mark.parametrize('name', ['table1.yaml', 'real_rig.yaml'])
def test_the_profile_publisher_plans_for_the_simulators_rod(name):
    """Each rod file gives the profile publisher the simulator's rod, deflection limit
    and acceleration bound, value for value (its planned spin-up is for that rod)."""
    doc = yaml.safe_load((ROOT / 'config' / name).read_text())
    simulator = doc['/**/rotrod_simulator']['ros__parameters']
    publisher = doc['/**/rotrod_profile_publisher']['ros__parameters']
    shared = {s.name for s in ROD_SPECS} | {'deflection_limit', 'max_angular_acceleration'}
    assert {k: v for k, v in simulator.items() if k in shared} == publisher


def test_pacer_maps_wall_to_simulated_time_and_back():
    p = Pacer(4.0, sim=10.0, wall=100.0)
    assert p.sim_time(100.5) == pytest.approx(12.0)
    assert p.wall_time(12.0) == pytest.approx(100.5)
    p.anchor(1.0, sim=12.0, wall=200.0)                 # e.g. after a pause
    assert p.sim_time(200.25) == pytest.approx(12.25)
    fast = Pacer(0.0, 0.0, 0.0)
    assert not fast.paced
    with pytest.raises(ValueError):
        fast.sim_time(1.0)
    with pytest.raises(ValueError):
        Pacer(-1.0, 0.0, 0.0)


def test_stamps_follow_the_wall_clock_but_never_go_back():
    c = StampClock(origin=1000.0)
    assert c.stamp(5.0) == 1005.0
    c.follow_wall(sim=5.0, epoch=1010.0)                # stood still 5 s: jump forward
    assert c.stamp(5.0) == 1010.0
    c.follow_wall(sim=5.0, epoch=1001.0)                # never backwards
    assert c.stamp(5.0) == 1010.0


@pytest.mark.parametrize('t', [0.0, 1.5, 1795321712.418036928, 2.9999999999])
def test_stamp_round_trip(t):
    s = messages.stamp(t)
    assert 0 <= s.nanosec < 1_000_000_000
    assert messages.to_seconds(s) == pytest.approx(t, abs=1e-9)


def test_messages_carry_units_frames_and_labels():
    t = messages.stamp(1.25)
    js = messages.joint_state(t, State(1e-3, -2e-4, 0.01, -0.02, 0.5, 2.0), -0.01)
    assert list(js.name) == ['hub', 'tip_radial', 'tip_tangential']
    assert list(js.position) == [0.5, 1e-3, -2e-4]
    assert list(js.velocity) == [2.0, 0.01, -0.02]
    assert list(js.effort) == [-0.01, 0.0, 0.0]             # the tip joints are passive
    d = messages.deflection(t, 1e-3, -2e-4, 'rotor')
    assert d.header.frame_id == 'rotor' and (d.vector.x, d.vector.y, d.vector.z) == (
        1e-3, -2e-4, 0.0)
    f = messages.frequencies(1.6, 2.2)
    assert list(f.data) == [1.6, 2.2] and f.layout.dim[0].label == messages.FREQUENCY_LABEL
    diag = messages.diagnostics(t, 'sim', 'hw', 1, 'warn', [('u_m', 1e-3), ('drive', 'x')])
    assert diag.status[0].level == b'\x01'
    assert [(kv.key, kv.value) for kv in diag.status[0].values] == [('u_m', '0.001'),
                                                                   ('drive', 'x')]
    rod = rod_centerline(RodParams(), 1e-3, 0.0, 0.3)
    arr = messages.markers(t, 'world', 'rotrod', disk_radius=0.15, theta=0.3, rod=rod,
                           rod_diameter=0.003, mass_radius=0.02, trail=[rod[-1], rod[-1]])
    assert [m.id for m in arr.markers] == [0, 1, 2, 3, 4]
    assert all(m.header.frame_id == 'world' for m in arr.markers)


def test_the_drawn_rod_is_a_tip_loaded_cantilever_ending_at_the_mass():
    s = np.linspace(0, 1, 101)
    # Euler-Bernoulli, tip load only: w'''' = 0 (a cubic), clamped root w = w' = 0,
    # no moment at the tip w''(1) = 0, unit tip deflection w(1) = 1
    c0, c1, c2, c3 = np.polynomial.polynomial.polyfit(s, cantilever_shape(s), 4)[:4]
    assert np.polynomial.polynomial.polyfit(s, cantilever_shape(s), 4)[4] == pytest.approx(
        0, abs=1e-9)
    assert (c0, c1) == (pytest.approx(0, abs=1e-9), pytest.approx(0, abs=1e-9))
    assert 2 * c2 + 6 * c3 == pytest.approx(0, abs=1e-9)
    assert c0 + c1 + c2 + c3 == pytest.approx(1)
    p = RodParams()
    u, v, theta = 2e-3, -1e-3, 0.7
    line = rod_centerline(p, u, v, theta)
    x, y = inertial_position(Coefficients.from_params(p), u, v, theta)
    assert line[-1] == pytest.approx([x, y, L])
    assert line[0] == pytest.approx([R0 * math.cos(theta), R0 * math.sin(theta), 0])
    assert sphere_radius(4 / 3 * math.pi * 7850.0) == pytest.approx(1.0)
