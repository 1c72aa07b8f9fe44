"""What a new user sends first, through the real executables (DDS on this machine only),
checked against closed forms and invariants (docs/model.md), never against rotrod's output.

Each test is one journey: a 2 rad/s setpoint (the paper's speed) at 10 Hz and once, a
ramp past the 3 mm critical deflection and a hold there, torque drive and a coast, two
rods at once, parameters changed while running, pause/resume/reset, and a halt on the
model's validity bound followed by a reset.
"""

import cmath
import math
import time

import numpy as np
import pytest
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus
from geometry_msgs.msg import Vector3Stamped
from node_probes import (
    by_time,
    collect,
    drain,
    get_parameter,
    namespace,
    omega_publisher,
    param,
    set_parameters,
    stamp,
    start_simulator,
)
from reference import ECCENTRIC_MASS_RIG, K_RIG, MODAL_MASS_RIG, R0, W0, W0_RIG, K, M
from ros_harness import ros_arguments
from rotrod_interfaces.msg import DynamicFrequencies
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64
from std_srvs.srv import SetBool, Trigger

pytestmark = pytest.mark.ros

FAST = 4.0
STALLED = 'arrived after their due time'
"""The simulator's warning when setpoints of a stream arrived after their due time."""
"""real_time_factor of the journeys that do not need wall-clock pacing."""
J_HUB = 0.5 * math.pi * 7850.0 * 0.01 * 0.15**4
"""The default hub: a steel disk 0.15 m x 10 mm, J = pi rho t R^4 / 2, kg m^2."""


def static_deflection(w, r0=R0):
    """docs/model.md: u_s = m w^2 r0 / (k - m w^2), m."""
    return M * w * w * r0 / (K - M * w * w)


def whirl_exponents(w, zeta=0.0):
    """Roots of s^2 + (2 zeta w0 + 2 i w) s + (w0^2 - w^2) = 0: the two free whirls at
    constant w in the rotating frame (Eq. 28 undamped: i (w0 - w) and -i (w0 + w))."""
    b = zeta * W0 + 1j * w
    root = cmath.sqrt(b * b - (W0 * W0 - w * w))
    return -b + root, -b - root


def fit_hold(rows, w, zeta=0.0, at=None):
    """Least-squares fit of z = u + i v over a hold at constant ``w``:
    z = C + A exp(s1 t) + B exp(s2 t) with the closed-form exponents.

    Returns (C, |A| + |B|, rms residual / (|A| + |B|)), and the fitted z at the
    times ``at`` (s) if given.
    """
    t0 = rows[0, 0]
    s1, s2 = whirl_exponents(w, zeta)

    def basis(t):
        t = np.asarray(t, dtype=float) - t0
        return np.column_stack([np.ones_like(t), np.exp(s1 * t), np.exp(s2 * t)])

    z = rows[:, 4] + 1j * rows[:, 5]
    coef, *_ = np.linalg.lstsq(basis(rows[:, 0]), z, rcond=None)
    amplitude = abs(coef[1]) + abs(coef[2])
    residual = np.sqrt(np.mean(np.abs(z - basis(rows[:, 0]) @ coef) ** 2))
    fit = (coef[0], amplitude, residual / amplitude)
    return fit if at is None else (*fit, basis(at) @ coef)


def statuses(diags, ns, level=None):
    """The simulator's statuses in ``ns`` received on /diagnostics (of ``level``)."""
    return [s for d in diags for s in d.status
            if s.name.startswith(f'{ns}/rotrod_simulator')
            and (level is None or s.level == level)]


class Observer:
    """The topics a user watches: joint_states, tip/deflection, frequencies, /diagnostics."""

    def __init__(self, node, ns):
        self.node, self.ns = node, ns
        self.joint = node.subscribe(f'{ns}/joint_states', JointState, qos=1000)
        self.deflection = node.subscribe(f'{ns}/tip/deflection', Vector3Stamped, qos=1000)
        self.frequencies = node.subscribe(f'{ns}/frequencies', DynamicFrequencies,
                                          qos=1000)
        self.diags = node.subscribe('/diagnostics', DiagnosticArray, qos=1000)

    def rows(self):
        """t, theta, w, Q, u, v of every published instant so far."""
        return by_time(self.joint, self.deflection)

    def wait_for_omega(self, w, timeout=30.0):
        """Spin until the hub is at exactly ``w``; return that stamp."""
        self.node.spin_until(lambda: self.joint and self.joint[-1].velocity[0] == w, timeout,
                             f'{self.ns} at {w} rad/s')
        return stamp(self.joint[-1])

    def wait_until(self, t, timeout=30.0):
        """Spin until a joint state stamped at or after ``t`` (simulated s) arrived."""
        self.node.spin_until(lambda: self.joint and stamp(self.joint[-1]) >= t, timeout,
                             f'{self.ns} stamped {t:.2f} s')

    def hold(self, t_from, t_to=math.inf):
        rows = self.rows()
        return rows[(rows[:, 0] >= t_from) & (rows[:, 0] <= t_to)]

    def statuses(self, level=None):
        return statuses(self.diags, self.ns, level)

    def drain(self, quiet=0.5, timeout=10.0):
        """Spin until no joint state has arrived for ``quiet`` s: what was published
        before now (reliable, queued behind a busy test process) is in."""
        drain(self.node, self.joint, quiet, timeout, f'{self.ns}/joint_states')


def stamp_published_after(node, sourced, wall, timeout=10.0):
    """The stamp of the first message in ``sourced`` (from node_probes.collect) that
    was published after wall time ``wall`` (its DDS source time).

    After a parameter reply, the simulated time of the change: the last state received
    may be one published well before it, still queued behind a busy test process.
    """
    def first():
        later = None
        for m, source, _ in reversed(sourced):      # in the order published
            if source <= wall:
                break
            later = m
        return later is not None and stamp(later)

    return node.spin_until(first, timeout, 'a state published after the reply')


def check_settled_at_2_rad_s(sim, obs, t_reached):
    """The hold at 2 rad/s: centre, whirls and frequencies against docs/model.md; no halt."""
    hold = obs.hold(t_reached + 1.0)
    assert len(hold) > 500 and np.all(hold[:, 2] == 2.0)
    centre, amplitude, residual = fit_hold(hold, 2.0)
    us = static_deflection(2.0)
    assert us == pytest.approx(2.792e-3, rel=1e-3)
    assert centre.real == pytest.approx(us, rel=0.01)             # the 1 %
    assert abs(centre - us) <= 1e-3 * us and residual < 1e-3      # two Eq. 28 whirls
    f1, f2 = obs.frequencies[-1].f1, obs.frequencies[-1].f2
    assert obs.frequencies[-1].omega == 2.0
    assert (f1, f2) == (pytest.approx((W0 - 2.0) / (2 * math.pi), rel=1e-9),
                        pytest.approx((W0 + 2.0) / (2 * math.pi), rel=1e-9))
    # the whirl carries the tip past the 3 mm criterion: an alarm, not a halt
    peak = np.max(np.hypot(hold[:, 4], hold[:, 5]))
    assert peak > 3e-3 and peak <= us + amplitude * (1 + 1e-3)
    errors = obs.statuses(DiagnosticStatus.ERROR)
    assert errors and all('beyond the critical deflection 3 mm' in s.message for s in errors)
    assert 'halted' not in sim.output and sim.running


@pytest.mark.long   # 20 s of real time: in CI's long run (to keep the default run under 15
# minutes); the default run checks the same hold after a single setpoint, just below
def test_a_2_rad_s_setpoint_at_10_hz_runs_on_past_the_3_mm_criterion(
        ros_processes, ros_node, request):
    ns = namespace(request)
    sim = start_simulator(ros_processes, ns)                      # every default: real time
    obs = Observer(ros_node, ns)
    pub = omega_publisher(ros_node, ns)
    t_reached = None
    # at 10 Hz until 11 s of the hold at 2 rad/s are in (~15 s: the ramp takes 4 s),
    # not for a fixed 15 s, which a loaded machine's late start could leave too short
    deadline = time.monotonic() + 60.0
    while t_reached is None or stamp(obs.joint[-1]) < t_reached + 11.0:
        assert time.monotonic() < deadline, (
            'never reached 2 rad/s' if t_reached is None else 'no 11 s hold within 60 s')
        pub.publish(Float64(data=2.0))
        ros_node.spin_for(0.1)
        if t_reached is None and obs.joint and obs.joint[-1].velocity[0] == 2.0:
            t_reached = stamp(obs.joint[-1])
    check_settled_at_2_rad_s(sim, obs, t_reached)


def test_a_single_2_rad_s_setpoint_runs_on_past_the_3_mm_criterion(
        ros_processes, ros_node, request):
    ns = namespace(request)
    sim = start_simulator(ros_processes, ns, real_time_factor=FAST)
    obs = Observer(ros_node, ns)
    omega_publisher(ros_node, ns).publish(Float64(data=2.0))      # ros2 topic pub --once
    t_reached = obs.wait_for_omega(2.0)
    obs.wait_until(t_reached + 12.0)
    check_settled_at_2_rad_s(sim, obs, t_reached)


def test_a_ramp_past_the_criterion_then_a_hold_is_an_error_and_runs_on(
        ros_processes, ros_node, request):
    ns = namespace(request)
    sim = start_simulator(ros_processes, ns, real_time_factor=FAST)
    obs = Observer(ros_node, ns)
    ramp = ros_processes.start_console_script('profile_publisher', *ros_arguments(
        namespace=ns, params={'profile': 'ramp', 'omega_target': 2.5, 'ramp_time': 8.0,
                              'hold': True, 'use_sim_time': True}), name='ramp')
    t_reached = obs.wait_for_omega(2.5, timeout=40)
    obs.wait_until(t_reached + 10.0)
    hold = obs.hold(t_reached + 1.0)
    us = static_deflection(2.5)                                   # 4.43 mm
    centre, _, residual = fit_hold(hold, 2.5)
    assert centre.real == pytest.approx(us, rel=0.01) and residual < 1e-3
    # the ramp's end leaves a whirl of 0.2 mm about the 4.43 mm: beyond 3 mm all along,
    # an ERROR all along. A busy machine that held the stream up for longer than
    # setpoint_delay (the simulator says so) leaves a larger one, which may dip below
    last = obs.statuses()[-1]
    if STALLED not in sim.output:
        assert np.min(np.hypot(hold[:, 4], hold[:, 5])) > 3e-3
        assert last.level == DiagnosticStatus.ERROR
    # the level is the deflection's, at the status's own instant
    beyond = float(dict((kv.key, kv.value) for kv in last.values)['deflection_m']) > 3e-3
    assert (last.level == DiagnosticStatus.ERROR) == beyond
    last = obs.statuses(DiagnosticStatus.ERROR)[-1]
    assert 'beyond the critical deflection 3 mm' in last.message
    assert 'first crossed at t = ' in last.message and 'peak ' in last.message
    assert 'still running' in last.message and sim.running and 'halted' not in sim.output
    # back below the criterion: commands are still accepted, diagnostics OK again
    ramp.stop()
    omega_publisher(ros_node, ns).publish(Float64(data=1.0))
    t_back = obs.wait_for_omega(1.0, timeout=40)
    ros_node.spin_until(lambda: obs.statuses()[-1].level == DiagnosticStatus.OK, 20,
                        'diagnostics OK below the criterion')
    obs.wait_until(t_back + 6.0)
    centre, _, _ = fit_hold(obs.hold(t_back + 1.0), 1.0)
    assert centre.real == pytest.approx(static_deflection(1.0), rel=0.01)


def test_torque_drive_then_zero_torque_coasts_with_constant_omega_and_momentum(
        ros_processes, ros_node, request):
    ns = namespace(request)
    start_simulator(ros_processes, ns, real_time_factor=FAST, drive='torque')
    obs = Observer(ros_node, ns)
    pub = ros_node.node.create_publisher(Float64, f'{ns}/cmd/torque', 10)
    ros_node.spin_until(lambda: pub.get_subscription_count() > 0, 10, 'cmd/torque subscriber')
    # the record must begin at rest: both of the observer's subscriptions deliver before the
    # torque is sent (a tip/deflection subscription matched late dropped the joined rows of
    # the torque's first 0.19 s on a loaded CI machine, and the impulse with them)
    ros_node.spin_until(lambda: len(obs.rows()) > 0, 10, 'joint_states and tip/deflection')
    pub.publish(Float64(data=0.01))                               # N m
    # 8 s of simulated time under the torque, from when it shows: not 2 s of wall time
    # from when it was sent, which a loaded machine (the command taking effect late, the
    # simulator slower than real_time_factor) cut to less
    ros_node.spin_until(lambda: obs.joint and obs.joint[-1].effort[0] == 0.01, 20,
                        'torque applied')
    t_on = stamp(obs.joint[-1])
    obs.wait_until(t_on + 8.0)
    pub.publish(Float64(data=0.0))
    ros_node.spin_until(lambda: obs.joint and obs.joint[-1].effort[0] == 0.0
                        and obs.joint[-1].velocity[0] > 0, 10, 'zero torque')
    t_off = stamp(obs.joint[-1])
    obs.wait_until(t_off + 15.0)
    rows = obs.rows()
    t, w, q, u, v = rows[:, 0], rows[:, 2], rows[:, 3], rows[:, 4], rows[:, 5]
    du, dv = np.gradient(u, t), np.gradient(v, t)
    # docs/model.md: L = (J + m rho^2) w + m ((r0 + u) v' - v u'), rho^2 = (r0 + u)^2 + v^2
    momentum = (J_HUB + M * ((R0 + u) ** 2 + v**2)) * w + M * ((R0 + u) * dv - v * du)
    coast = (t > t_off + 0.5) & (t < t[-2])       # np.gradient is one-sided at the ends
    L = momentum[coast]
    impulse = np.sum(q[:-1] * np.diff(t))                         # the torque's integral
    assert set(np.unique(q)) <= {0.0, 0.01}
    # the integral is exact to one publish period: the record starts at rest and has no
    # gap where the torque switches on or off
    period = np.median(np.diff(t))
    assert q[0] == 0.0 and w[0] == 0.0
    switches = np.flatnonzero(np.diff(q) != 0)
    assert len(switches) == 2 and np.all(np.diff(t)[switches] <= 1.5 * period)
    assert np.max(np.abs(L - L.mean())) <= 1e-5 * L.mean()       # conserved when Q = 0
    assert L.mean() == pytest.approx(impulse, rel=0.01)           # dL/dt = Q
    # a steady spin: w with the centrifugal static deflection, L = (J + m (r0+u_s)^2) w
    w_steady = L.mean() / J_HUB
    for _ in range(50):
        w_steady = L.mean() / (J_HUB + M * (R0 + static_deflection(w_steady)) ** 2)
    assert w[coast].mean() == pytest.approx(w_steady, rel=1e-3)
    assert np.ptp(w[coast]) <= 2e-3 * w_steady


def test_two_rods_in_namespaces_follow_their_own_commands_and_parameters(
        ros_processes, ros_node, request):
    a, b = namespace(request) + '_a', namespace(request) + '_b'
    start_simulator(ros_processes, a, real_time_factor=FAST, frame_prefix='rodA/')
    start_simulator(ros_processes, b, real_time_factor=FAST, frame_prefix='rodB/',
                    eccentricity=0.05)
    rod_a, rod_b = Observer(ros_node, a), Observer(ros_node, b)
    omega_publisher(ros_node, a).publish(Float64(data=2.0))
    omega_publisher(ros_node, b).publish(Float64(data=1.5))
    ta, tb = rod_a.wait_for_omega(2.0), rod_b.wait_for_omega(1.5)
    rod_a.wait_until(ta + 8.0)
    rod_b.wait_until(tb + 8.0)
    for rod, w, r0 in ((rod_a, 2.0, R0), (rod_b, 1.5, 0.05)):
        hold = rod.hold((ta if rod is rod_a else tb) + 1.0)
        assert np.all(hold[:, 2] == w)
        centre, _, residual = fit_hold(hold, w)
        assert centre.real == pytest.approx(static_deflection(w, r0), rel=0.01)
        assert residual < 1e-3
    assert {m.header.frame_id for m in rod_a.deflection} == {'rodA/rotor'}
    assert {m.header.frame_id for m in rod_b.deflection} == {'rodB/rotor'}


def test_eccentricity_and_damping_changed_while_running_take_effect(
        ros_processes, ros_node, request):
    ns = namespace(request)
    start_simulator(ros_processes, ns, real_time_factor=FAST)
    obs = Observer(ros_node, ns)
    sourced = collect(ros_node, f'{ns}/joint_states', JointState)
    omega_publisher(ros_node, ns).publish(Float64(data=2.0))
    t_reached = obs.wait_for_omega(2.0)
    obs.wait_until(t_reached + 2.0)
    # the parameter services, as `ros2 param set` calls them
    assert set_parameters(ros_node, ns, param('eccentricity', 0.05)).results[0].successful
    t_ecc = stamp_published_after(ros_node, sourced, time.time())
    assert get_parameter(ros_node, ns, 'eccentricity') == 0.05
    obs.wait_until(t_ecc + 8.0)
    centre, _, residual = fit_hold(obs.hold(t_ecc + 0.5), 2.0)
    assert centre.real == pytest.approx(static_deflection(2.0, 0.05), rel=0.01)
    assert residual < 1e-3
    assert set_parameters(ros_node, ns, param('damping_ratio', 0.05)).results[0].successful
    t_damp = stamp_published_after(ros_node, sourced, time.time())
    obs.wait_until(t_damp + 8.0)
    hold = obs.hold(t_damp + 0.5)
    centre, _, residual = fit_hold(hold, 2.0, zeta=0.05)         # the damped whirls
    assert centre.real == pytest.approx(static_deflection(2.0, 0.05), rel=0.01)
    assert residual < 1e-3
    whirl = np.abs(hold[:, 4] + 1j * hold[:, 5] - centre)
    assert whirl[-100:].max() < 0.1 * whirl[:100].max()          # it dies out
    # a bad value is refused with the reason and changes nothing
    bad = set_parameters(ros_node, ns, param('damping_ratio', -1.0)).results[0]
    assert not bad.successful and 'damping_ratio' in bad.reason
    assert get_parameter(ros_node, ns, 'damping_ratio') == 0.05


def test_pause_resume_and_reset(ros_processes, ros_node, request):
    ns = namespace(request)
    start_simulator(ros_processes, ns, real_time_factor=FAST)
    obs = Observer(ros_node, ns)
    omega_publisher(ros_node, ns).publish(Float64(data=1.0))
    t_reached = obs.wait_for_omega(1.0)
    obs.wait_until(t_reached + 1.0)
    pause = f'{ns}/rotrod_simulator/pause'
    assert ros_node.call_service(SetBool, pause, SetBool.Request(data=True)).success
    obs.drain(quiet=0.3)            # what was published before the pause is in
    n, last = len(obs.joint), obs.rows()[-1]
    before = obs.hold(t_reached + 0.5)
    ros_node.spin_for(1.0)
    assert len(obs.joint) == n                                    # nothing while paused
    assert ros_node.call_service(SetBool, pause, SetBool.Request(data=False)).success
    ros_node.spin_until(lambda: len(obs.joint) > n + 20, 10, 'publishing again')
    rows = obs.rows()
    after = rows[rows[:, 0] > last[0]]
    assert after[0, 0] == pytest.approx(last[0] + 0.01, abs=1e-6)  # time went on from there
    # ... and the motion too: the whirls fitted before the pause predict the tip after it
    *_, amplitude, _, predicted = fit_hold(before, 1.0, at=after[:50, 0])
    error = np.abs(after[:50, 4] + 1j * after[:50, 5] - predicted)
    assert error.max() < 1e-3 * amplitude
    reset = ros_node.call_service(Trigger, f'{ns}/rotrod_simulator/reset')
    assert reset.success and 'reset to the initial state' in reset.message
    ros_node.spin_until(lambda: obs.joint[-1].velocity[0] == 0.0 and
                        obs.deflection[-1].vector.x == 0.0, 10, 'at rest after the reset')
    assert stamp(obs.joint[-1]) > last[0]                         # the clock goes on


def test_a_halt_on_the_validity_bound_then_reset_and_normal_operation(
        ros_processes, ros_node, request):
    ns = namespace(request)
    sim = start_simulator(ros_processes, ns, real_time_factor=FAST)   # bound: 0.1 l = 30 mm
    obs = Observer(ros_node, ns)
    pub = omega_publisher(ros_node, ns)
    assert static_deflection(6.0) > 0.03
    pub.publish(Float64(data=6.0))
    sim.wait_for_output('simulation halted', timeout=40)
    obs.drain()     # the states published before the halt may still be on their way
    halted = obs.statuses(DiagnosticStatus.ERROR)[-1].message
    assert "beyond the model's validity bound 30 mm" in halted, halted
    assert any('beyond the critical deflection' in s.message
               for s in obs.statuses(DiagnosticStatus.ERROR))   # it crossed 3 mm first
    assert np.max(np.hypot(obs.rows()[:, 4], obs.rows()[:, 5])) <= 0.03
    n = len(obs.joint)
    pub.publish(Float64(data=1.0))                                # refused while halted
    ros_node.spin_for(0.5)
    assert len(obs.joint) <= n + 1
    assert ros_node.call_service(Trigger, f'{ns}/rotrod_simulator/reset').success
    ros_node.spin_until(lambda: len(obs.joint) > n + 5 and obs.joint[-1].velocity[0] == 0.0,
                        10, 'running again at rest')
    pub.publish(Float64(data=1.0))
    t_reached = obs.wait_for_omega(1.0)
    obs.wait_until(t_reached + 6.0)
    centre, _, residual = fit_hold(obs.hold(t_reached + 1.0), 1.0)
    assert centre.real == pytest.approx(static_deflection(1.0), rel=0.01) and residual < 1e-3
    ros_node.spin_until(lambda: obs.statuses()[-1].level == DiagnosticStatus.OK, 10,
                        'diagnostics OK')


def test_the_real_rig_params_file_settles_at_its_softened_static_deflection(
        ros_processes, ros_node, request):
    """config/real_rig.yaml: Table 1 upright under gravity with a steel rod (issue 18)."""
    ns = namespace(request)
    start_simulator(ros_processes, ns, 'table1.yaml', 'real_rig.yaml', real_time_factor=FAST)
    obs = Observer(ros_node, ns)
    omega_publisher(ros_node, ns).publish(Float64(data=1.5))
    t_reached = obs.wait_for_omega(1.5)
    obs.wait_until(t_reached + 8.0)
    # the real rig's closed forms (test/reference.py, docs/real_rig.md)
    us = ECCENTRIC_MASS_RIG * 1.5**2 * R0 / (K_RIG - MODAL_MASS_RIG * 1.5**2)
    hold = obs.hold(t_reached + 1.0)
    w0 = W0_RIG
    t = hold[:, 0] - hold[0, 0]
    z = hold[:, 4] + 1j * hold[:, 5]
    basis = np.column_stack([np.ones_like(t), np.exp(1j * (w0 - 1.5) * t),
                             np.exp(-1j * (w0 + 1.5) * t)])
    coef, *_ = np.linalg.lstsq(basis, z, rcond=None)
    residual = np.sqrt(np.mean(np.abs(z - basis @ coef) ** 2))
    assert coef[0].real == pytest.approx(us, rel=0.01)
    assert residual < 1e-3 * (abs(coef[1]) + abs(coef[2]))
    assert us > static_deflection(1.5) * 1.3                      # softer than the paper's
    f1, f2 = obs.frequencies[-1].f1, obs.frequencies[-1].f2
    assert obs.frequencies[-1].omega == 1.5
    assert (f1, f2) == (pytest.approx((w0 - 1.5) / (2 * math.pi), rel=1e-6),
                        pytest.approx((w0 + 1.5) / (2 * math.pi), rel=1e-6))
