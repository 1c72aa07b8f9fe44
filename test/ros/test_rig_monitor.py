"""The rig monitor: identification of a real rig from its motion, live (issue 20).

The rig is Table 1 upright under gravity with a steel rod (config/real_rig.yaml); the
monitor is configured with the paper's Table 1. Its natural frequency and stiffness are
written out here from docs/real_rig.md, not taken from rotrod."""

import math

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from node_probes import namespace, omega_publisher, stamp, start_simulator
from reference import LOAD_RADIUS_RIG, STEEL, W0_RIG, G, K, M
from ros_harness import ros_arguments
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64, Float64MultiArray

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
    assert monitor.omega == 1.0


@pytest.mark.parametrize('changes, match', [
    ({'window': -1.0}, 'window'), ({'critical_margin': 1.5}, 'critical_margin'),
    ({'nominal': RodParams(section='rectangular', section_width=0.003,
                           section_thickness=0.002)}, 'isotropic'),
])
def test_bad_monitor_configurations_are_refused(changes, match):
    with pytest.raises(ValueError, match=match):
        MonitorConfig(**changes)


@pytest.mark.ros
def test_live_the_monitor_finds_the_real_rig_within_10_s_of_a_spin_up(
        ros_processes, ros_node, request):
    ns = namespace(request)
    start_simulator(ros_processes, ns, 'table1.yaml', 'real_rig.yaml', real_time_factor=2.0,
                    deflection_noise=1e-5, noise_seed=7)
    monitor = ros_processes.start_console_script(
        'rig_monitor', *ros_arguments(namespace=ns), name='rig_monitor')   # Table 1
    monitor.wait_for_output('ready: identifying', timeout=30)
    estimates = ros_node.subscribe(f'{ns}/rig/estimate', Float64MultiArray, qos=1000)
    joint = ros_node.subscribe(f'{ns}/joint_states', JointState, qos=1000)
    diags = ros_node.subscribe('/diagnostics', DiagnosticArray, qos=1000)
    ros_node.spin_for(2.0)
    omega_publisher(ros_node, ns).publish(Float64(data=2.0))
    ros_node.spin_until(lambda: any(m.velocity[0] > 0 for m in joint), 20, 'spin-up')
    start = min(stamp(m) for m in joint if m.velocity[0] > 0)
    ros_node.spin_until(lambda: estimates and
                        estimates[-1].data[FIELD['window_end']] >= start + 10.0, 60,
                        'estimates 10 s into the spin-up')
    label = estimates[-1].layout.dim[0].label
    assert label.startswith('natural_frequency[rad/s],natural_frequency_std[rad/s]')
    by_10_s = [m for m in estimates if m.data[FIELD['window_end']] <= start + 10.0]
    assert by_10_s
    w0 = by_10_s[-1].data[FIELD['natural_frequency']]
    assert w0 == pytest.approx(W0_RIG, rel=5e-3)                   # the 0.5 %
    ours = [s for d in diags for s in d.status
            if s.name.startswith(f'{ns}/rotrod_rig_monitor')]
    assert ours[-1].level == DiagnosticStatus.WARN
    assert 'off the nominal 44.18 N/m' in ours[-1].message
    assert 'identified critical speed' in ours[-1].message         # at 2 rad/s, past 1.75
