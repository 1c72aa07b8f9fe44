"""The rig monitor (rotrod_core.estimation.monitor): identification of a real rig from its
motion (issue 20).

The rig is Table 1 upright under gravity with a steel rod (config/real_rig.yaml); the
monitor is configured with the paper's Table 1. Its natural frequency and stiffness are
written out here from docs/real_rig.md, not taken from rotrod."""

import math

import numpy as np
import pytest
from reference import LOAD_RADIUS_RIG, STEEL, W0_RIG, G, K, M
from sensor_records import encoder_angles, imu_xy

from rotrod_core import RodParams, simulate
from rotrod_core.command.profiles import RampProfile
from rotrod_core.estimation.monitor import ESTIMATE_FIELDS, MonitorConfig, RigMonitor

FIELD = {name: i for i, (name, _) in enumerate(ESTIMATE_FIELDS)}


def test_the_monitor_identifies_a_real_rig_offline_and_warns():
    rig = RodParams(gravity=G, rod_density=STEEL)
    run = simulate(rig, RampProfile(2.0, 4.0, t_start=2.0), 14.0, dt=0.01)
    rng = np.random.default_rng(3)
    noise = 1e-5                                           # m, RMS |r| / 100 or so
    u = run.u + rng.normal(0, noise, run.u.shape)
    v = run.v + rng.normal(0, noise, run.v.shape)
    monitor = RigMonitor(MonitorConfig())                  # nominal: the paper's Table 1
    assert monitor.health().level == 1 and 'no estimate' in monitor.health().message
    for k, t in enumerate(run.t):
        # the two topics, in either order
        if k % 2:
            monitor.add_omega(t, run.omega[k])
            monitor.add_deflection(t, u[k], v[k])
        else:
            monitor.add_deflection(t, u[k], v[k])
            monitor.add_omega(t, run.omega[k])
        if t == pytest.approx(5.0, abs=1e-9):              # 3 s after the spin-up began
            assert monitor.estimate.natural_frequency == pytest.approx(W0_RIG, rel=5e-3)
    est = monitor.estimate
    values = monitor.values(est)
    assert values[FIELD['natural_frequency']] == pytest.approx(W0_RIG, rel=1e-3)
    assert values[FIELD['eccentricity']] == pytest.approx(LOAD_RADIUS_RIG, rel=1e-2)
    assert values[FIELD['stiffness']] == pytest.approx(W0_RIG**2 * M, rel=2e-3)
    assert values[FIELD['stiffness_deviation']] == pytest.approx(W0_RIG**2 * M / K - 1,
                                                                 abs=2e-3)
    d = 0.003                                              # docs/model.md#eq-critical
    w_cr = values[FIELD['natural_frequency']] * math.sqrt(d / (d + values[FIELD['eccentricity']]))
    assert values[FIELD['critical_speed']] == pytest.approx(w_cr, rel=1e-12)
    health = monitor.health()
    assert health.level == 1
    assert 'within 10% of the identified critical speed' in health.message
    assert 'off the nominal 44.18 N/m' in health.message


def test_the_monitor_refuses_non_finite_samples_and_keeps_its_state():
    monitor = RigMonitor()
    monitor.add_omega(0.0, 1.0)
    with pytest.raises(ValueError, match='non-finite'):
        monitor.add_deflection(0.0, math.nan, 0.0)
    with pytest.raises(ValueError, match='non-finite'):
        monitor.add_omega(math.inf, 1.0)
    with pytest.raises(ValueError, match='non-finite'):
        monitor.add_omega(0.01, math.nan)
    assert monitor.omega == 1.0
    encoder = RigMonitor(MonitorConfig(hub='angle'))
    encoder.add_angle(0.0, 0.5, 1.0)
    for bad in ((0.01, math.nan, 1.0), (0.01, 0.6, math.inf)):
        with pytest.raises(ValueError, match='non-finite'):
            encoder.add_angle(*bad)
    assert encoder.omega == 1.0


@pytest.mark.parametrize('changes, match', [
    ({'window': -1.0}, 'window'), ({'critical_margin': 1.5}, 'critical_margin'),
    ({'measurement': 'imu'}, 'measurement'), ({'hub': 'encoder'}, 'hub'),
    ({'angle_smoothing': 0.0}, 'angle_smoothing'),
    ({'nominal': RodParams(section='rectangular', section_width=0.003,
                           section_thickness=0.002)}, 'isotropic'),
])
def test_bad_monitor_configurations_are_refused(changes, match):
    with pytest.raises(ValueError, match=match):
        MonitorConfig(**changes)


@pytest.mark.parametrize('hub, w0_tolerance', [('omega', 1e-3), ('angle', 5e-3)])
def test_the_monitor_identifies_the_rig_from_its_imu_and_encoder(hub, w0_tolerance):
    """The same rig from what a real one measures: the tip IMU's x, y (its exact tilted
    reading, 0.02 m/s^2 of noise and a bias of (0.05, -0.03) m/s^2) and the hub's true
    speed, or the encoder's quantised angle (4096 counts per turn). The nominal rig is
    the rig (as the simulator's robot_description gives it: gravity, rod length and
    masses set the IMU's tilt and radius). The load radius within 2 % of its closed
    form; w0 within 0.1 % with the true speed, 0.5 % with the encoder's (its quantised
    speed's errors, ~0.01 rad/s, weigh: the accelerometer sees mostly the centripetal
    w^2 (r0 + u), the stiffness only in the small flexible share)."""
    rig = RodParams(gravity=G, rod_density=STEEL)
    run = simulate(rig, RampProfile(2.0, 4.0, t_start=2.0), 10.0, dt=0.01)
    rng = np.random.default_rng(4)
    y = imu_xy(rig, run) + 0.02 * (rng.standard_normal(len(run.t))
                                   + 1j * rng.standard_normal(len(run.t))) + (0.05 - 0.03j)
    angle, speed = encoder_angles(run)
    monitor = RigMonitor(MonitorConfig(nominal=rig, measurement='acceleration', hub=hub,
                                       window=8.0))
    for k, t in enumerate(run.t):
        if hub == 'omega':
            monitor.add_omega(t, run.omega[k])
        else:
            monitor.add_angle(t, angle[k], speed[k])
        monitor.add_acceleration(t, y.real[k], y.imag[k])
    est = monitor.estimate
    assert est is not None, monitor.identifier.reason
    values = monitor.values(est)
    assert values[FIELD['natural_frequency']] == pytest.approx(W0_RIG, rel=w0_tolerance)
    assert values[FIELD['eccentricity']] == pytest.approx(LOAD_RADIUS_RIG, rel=2e-2)
    assert abs(values[FIELD['stiffness_deviation']]) < 2.5 * w0_tolerance    # k = w0^2 M
    assert values[FIELD['residual_rms']] == pytest.approx(0.02 * math.sqrt(2), rel=0.15)
    assert monitor.omega == pytest.approx(2.0, abs=0.02)
    assert ('residual_rms_m_s2', values[FIELD['residual_rms']]) in monitor.health().values
    with pytest.raises(ValueError, match="takes measurement 'acceleration'"):
        monitor.add_deflection(11.0, 0.0, 0.0)
