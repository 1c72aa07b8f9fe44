"""The servo drive and the bearing's friction against the closed forms of a rigid hub."""

import math

import numpy as np
import pytest
from reference import peak_frequency

from rotrod_core.live.engine import EngineConfig, SimulationEngine
from rotrod_core.live.world import World
from rotrod_core.model.params import RodParams

M, R0 = 0.3, 0.1
W0 = math.sqrt(3 * 100e9 * math.pi * 0.003**4 / 64 / 0.3**3 / M)


def run(engine, seconds):
    t, w, q = [], [], []
    for _ in range(round(seconds * engine.config.physics_rate)):
        engine.step()
        t.append(engine.time)
        w.append(float(engine.state.omega))
        q.append(engine.torque)
    return np.array(t), np.array(w), np.array(q)


def ramp_step_response(t, wn, ramp):
    """The critically damped PI loop's response to a reference rising linearly to 1 over
    ``ramp`` s from t = 0: (Y1(t) - Y1(t - ramp)) / ramp, Y1 = the integral of the step
    response 1 - exp(-wn t) (1 - wn t), t - t exp(-wn t)."""
    def integral(x):
        x = np.maximum(x, 0.0)
        return x - x * np.exp(-wn * x)
    return (integral(t) - integral(t - ramp)) / ramp


def test_the_servos_step_response_is_the_pi_loops_closed_form_for_a_rigid_hub():
    """A heavy hub (J = 1 kg m^2: the mass's m r0^2 is 0.3 % of it) and a 1 Hz loop at
    damping 1: a step of 1 rad/s (shaped at 40 rad/s^2) gives the closed loop's response
    to within 1 % of the step, and its peak 1 + exp(-2) (13.5 % overshoot) at 2 / w_n."""
    wn = 2 * math.pi * 1.0
    engine = SimulationEngine(EngineConfig(params=RodParams(hub_inertia=1.0), drive='servo',
                                           servo_bandwidth=1.0, max_angular_acceleration=40.0,
                                           setpoint_delay=0.02))
    engine.command_omega(1.0, at=0.0)
    t, w, _ = run(engine, 3.0)
    assert np.max(np.abs(w - ramp_step_response(t, wn, 1 / 40))) <= 0.01
    assert w.max() == pytest.approx(1 + math.exp(-2), abs=2e-3)
    assert t[w.argmax()] == pytest.approx(2 / wn + 1 / 80, abs=0.02)
    assert w[-1] == pytest.approx(1.0, abs=1e-3)


def test_at_its_torque_limit_the_servo_accelerates_the_rigid_inertia_at_q_max_over_j():
    """max_torque 0.05 N m: a step to 1 rad/s saturates the loop, the torque is the limit
    and w' = Q_max / (J + m r0^2) while it is (the rod turning with the hub); the
    integral does not wind up meanwhile: w settles without more than the loop's own
    overshoot."""
    params = RodParams()
    inertia = float(params.hub_inertia) + M * R0**2
    engine = SimulationEngine(EngineConfig(params=params, drive='servo', max_torque=0.05,
                                           servo_bandwidth=2.0, max_angular_acceleration=40.0))
    engine.command_omega(1.0, at=0.0)
    t, w, q = run(engine, 4.0)
    saturated = (t > 0.2) & (w < 0.7)
    assert np.all(q[saturated] == 0.05)
    slope = np.polyfit(t[saturated], w[saturated], 1)[0]
    assert slope == pytest.approx(0.05 / inertia, rel=0.01)
    assert w.max() <= 1 + math.exp(-2)
    assert w[-1] == pytest.approx(1.0, abs=2e-3)


def test_the_hub_speed_under_the_servo_shows_the_rods_whirl_frequencies():
    """Table 1's rod on its hub, held at 2 rad/s by a 2 Hz servo: the rod's whirl reacts
    on the hub, whose speed then oscillates at the rotating frame's whirl frequencies,
    Eq. 28's f1 = (w0 - w) / 2 pi and f2 = (w0 + w) / 2 pi (the servo shifts them a
    little: within 3 %)."""
    engine = SimulationEngine(EngineConfig(drive='servo', servo_bandwidth=2.0,
                                           max_angular_acceleration=5.0))
    engine.command_omega(2.0, at=0.0)
    t, w, _ = run(engine, 40.0)
    x = w[t > 8] - w[t > 8].mean()
    low, high = (W0 - 2) / (2 * math.pi), (W0 + 2) / (2 * math.pi)
    for centre in (low, high):
        assert peak_frequency(x, 1e-3, 0.9 * centre, 1.1 * centre) == pytest.approx(
            centre, rel=0.03)
    top = peak_frequency(x, 1e-3, 0.5, 5.0)
    assert min(abs(top - low), abs(top - high)) < 0.03 * high        # the largest is one


def test_viscous_friction_spins_a_coasting_hub_down_exponentially():
    """Torque drive at Q = 0 from 2 rad/s, c = 0.01 N m s/rad: w = 2 exp(-c t / J)
    (J = the hub's and the mass's, turning together) to 1 %."""
    params = RodParams()
    inertia = float(params.hub_inertia) + M * R0**2
    engine = SimulationEngine(EngineConfig(drive='torque', bearing_viscous_friction=0.01,
                                           initial={'omega': 2.0, 'u': 0.0}))
    t, w, q = run(engine, 5.0)
    assert np.all(q == 0.0)
    assert np.max(np.abs(w - 2 * np.exp(-0.01 * t / inertia))) <= 0.01 * 2


def test_coulomb_friction_stops_the_hub_and_holds_it_against_a_smaller_torque():
    """Q_c = 0.02 N m: the coasting hub slows at Q_c / J, stops where 2 J / Q_c says and
    stays; a torque of 0.015 N m then leaves it at rest, 0.03 N m turns it at
    (0.03 - 0.02) / J."""
    params = RodParams()
    inertia = float(params.hub_inertia) + M * R0**2
    engine = SimulationEngine(EngineConfig(drive='torque', bearing_coulomb_friction=0.02,
                                           initial={'omega': 0.5}))
    t, w, _ = run(engine, 3.0)
    stop = 0.5 * inertia / 0.02
    moving = t < 0.8 * stop
    assert np.polyfit(t[moving], w[moving], 1)[0] == pytest.approx(-0.02 / inertia, rel=0.02)
    assert np.all(np.abs(w[t > stop + 0.1]) <= 0.02 * 1e-3 / inertia)     # one step's band
    engine.command_torque(0.015)
    t2, w2, _ = run(engine, 1.0)
    assert np.all(np.abs(w2) <= 0.02 * 1e-3 / inertia)
    engine.command_torque(0.03)
    t3, w3, _ = run(engine, 2.0)
    assert np.polyfit(t3[t3 > t3[0] + 0.5], w3[t3 > t3[0] + 0.5], 1)[0] == pytest.approx(
        0.01 / inertia, rel=0.02)


def test_the_ideal_velocity_drive_overcomes_the_bearing():
    """Held at 2 rad/s with the rod at its static deflection (no reaction torque), the
    drive's torque is what the bearing takes: c w + Q_c."""
    u_s = M * 4 * R0 / (M * W0**2 - M * 4)
    engine = SimulationEngine(EngineConfig(bearing_viscous_friction=0.01,
                                           bearing_coulomb_friction=0.02,
                                           initial={'omega': 2.0, 'u': u_s}))
    engine.command_omega(2.0, at=0.0)
    _, _, q = run(engine, 0.5)
    assert q[-1] == pytest.approx(0.01 * 2 + 0.02, rel=1e-6)


def test_servo_rods_in_a_world_move_as_if_alone():
    """Three servo rods of different gains and limits stepped as one batch: each as
    when it is alone in its world, bit for bit (the same arithmetic per rod)."""
    configs = {'a': EngineConfig(drive='servo', servo_bandwidth=1.0),
               'b': EngineConfig(drive='servo', servo_bandwidth=3.0, max_torque=0.05,
                                 bearing_coulomb_friction=0.01),
               'c': EngineConfig(drive='servo', servo_damping=0.5,
                                 bearing_viscous_friction=0.02)}
    world = World(1000.0)
    together = {n: SimulationEngine(c, world=world, name=n) for n, c in configs.items()}
    alone = {n: SimulationEngine(c, name=n) for n, c in configs.items()}
    for engines in (together, alone):
        for engine in engines.values():
            engine.command_omega(1.5, at=0.0)
    world.advance(1500)
    for engine in alone.values():
        engine.advance(1500)
    for name in configs:
        assert together[name].state == alone[name].state, name
        assert together[name].torque == alone[name].torque


@pytest.mark.parametrize('change, named', [
    ({'servo_bandwidth': 600.0}, 'servo_bandwidth'), ({'servo_bandwidth': 0.0}, 'servo_bandwidth'),
    ({'servo_damping': -1.0}, 'servo_damping'), ({'max_torque': 0.0}, 'max_torque'),
    ({'bearing_viscous_friction': -0.1}, 'bearing_viscous_friction'),
    ({'bearing_coulomb_friction': math.nan}, 'bearing_coulomb_friction')])
def test_bad_drive_settings_are_refused_naming_them(change, named):
    with pytest.raises(ValueError, match=named):
        EngineConfig(drive='servo', **change)
