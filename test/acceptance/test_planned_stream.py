"""The planned spin-up streamed through the real executables (issue 19), checked against
closed forms (docs/model.md), never against rotrod's own output.

The simulator and the profile publisher take the same params files: the rod
(config/table1.yaml) and the planned spin-up with its acceleration bound
(config/planned.yaml). After the plan the tip must settle about the closed-form static
deflection with a free whirl within 10x the plan's predicted residual and below the
whirl the paper's Eq. 26 leaves, measured the same way; its peak stays under the
limit, and the simulator follows the plan without reaching its acceleration bound.
"""

import math
import re

import numpy as np
import pytest
from geometry_msgs.msg import Vector3Stamped
from node_probes import CONFIG, by_time, namespace, param, stamp, start_simulator
from rcl_interfaces.msg import ParameterType
from rcl_interfaces.srv import GetParameters, SetParameters
from reference import R0, W0, K, M
from ros_harness import ros_arguments
from sensor_msgs.msg import JointState
from std_msgs.msg import Float64

pytestmark = pytest.mark.ros

SPEED = 2.0
"""real_time_factor: the demo's (three Python processes keep up with it)."""
DELAY = 0.2
"""setpoint_delay, s: the demo's."""
SETTLE = 0.5
"""Simulated time after arrival before the whirl is measured, s (the delay and more)."""
WINDOW = 4.0
"""Length of the measured hold, s of simulated time (eight periods of the whirls)."""
LIMIT = 3e-3
"""deflection_limit of config/table1.yaml, m."""
BOUND = 0.5
"""max_angular_acceleration of config/planned.yaml, rad/s^2 (both nodes)."""


def static_deflection(w, r0=R0):
    """docs/model.md: u_s = m w^2 r0 / (k - m w^2), m."""
    return M * w * w * r0 / (K - M * w * w)


def free_whirl(rows, w):
    """Amplitude (m) of the free whirl about the closed-form static deflection at ``w``.

    Least squares on z - u_s = A exp(i (w0 - w) t) + B exp(-i (w0 + w) t) (Eq. 28's
    two whirls in the rotating frame); the amplitude is |A| + |B|, the largest
    distance from the static deflection. Also the largest misfit, m.
    """
    t = rows[:, 0] - rows[0, 0]
    z = rows[:, 4] + 1j * rows[:, 5] - static_deflection(w)
    basis = np.column_stack([np.exp(1j * (W0 - w) * t), np.exp(-1j * (W0 + w) * t)])
    coef, *_ = np.linalg.lstsq(basis, z, rcond=None)
    return float(abs(coef[0]) + abs(coef[1])), float(np.max(np.abs(z - basis @ coef)))


def stream(ros_processes, ros_node, ns, files, params=None):
    """Simulator and profile publisher with ``files`` (config/) and publisher ``params``.

    Returns the publisher's output and the rows t, theta, w, Q, u, v the simulator
    published until SETTLE + WINDOW s after the stream's end.
    """
    sim = start_simulator(ros_processes, ns, *files, real_time_factor=SPEED,
                          setpoint_delay=DELAY, markers=False)
    joint = ros_node.subscribe(f'{ns}/joint_states', JointState, qos=1000)
    deflection = ros_node.subscribe(f'{ns}/tip/deflection', Vector3Stamped, qos=1000)
    ros_args = ros_arguments(namespace=ns, params={'use_sim_time': True, **(params or {})})
    paths = [a for name in files for a in ('--params-file', str(CONFIG / name))]
    pub = ros_processes.start_console_script('profile_publisher', ros_args[0], *paths,
                                             *ros_args[1:], name=ns.strip('/') + '_pub')
    # the publisher plans at start: config/planned.yaml's robust plan takes ~0.5-2 min here
    ros_node.spin_until(lambda: 'end: published' in pub.output, 400, 'the end of the stream')
    t_end = stamp(joint[-1])
    ros_node.spin_until(lambda: stamp(joint[-1]) >= t_end + DELAY + SETTLE + WINDOW, 60,
                        'the hold after the stream')
    # stopped before the next stream: faster than real time the simulator publishes the
    # global /clock, which the next stream's publisher (use_sim_time) would also follow
    sim.stop()
    return pub.output, by_time(joint, deflection)


def hold(rows, w, t_from):
    """The rows at exactly ``w`` over WINDOW s from ``t_from`` (s)."""
    keep = (rows[:, 2] == w) & (rows[:, 0] >= t_from) & (rows[:, 0] <= t_from + WINDOW)
    assert np.sum(keep) >= 0.95 * WINDOW * 100                   # 100 Hz, none missing
    return rows[keep]


def logged(output, name):
    """A length the profile publisher logged: '<name> X um' or '<name> X mm', in m."""
    found = re.search(rf'{name} ([0-9.eE+-]+) (um|mm)', output)
    assert found, output
    return float(found.group(1)) * (1e-6 if found.group(2) == 'um' else 1e-3)


@pytest.mark.long      # a robust plan takes tens of seconds: .ci/run runs it
def test_the_planned_spin_up_arrives_without_the_whirl_eq26_leaves(
        ros_processes, ros_node, request):
    ns = namespace(request)
    out, rows = stream(ros_processes, ros_node, ns + 'p', ('table1.yaml', 'planned.yaml'))
    duration = float(re.search(r'duration ([0-9.]+) s', out).group(1))
    predicted = logged(out, 'residual whirl <=')       # the bound the plan meets
    assert f'within 0.9 x max_angular_acceleration {BOUND:g} rad/s^2' in out
    assert 'the simulator must allow |w\'| up to' in out
    moving = rows[rows[:, 2] > 0]
    started = moving[0, 0] - 0.01                  # the last sample at rest, s
    assert started - rows[0, 0] >= 2.0             # the stream held its start speed first
    arrived = rows[rows[:, 2] == 2.0][0, 0]
    assert arrived - started == pytest.approx(duration, abs=0.03)   # the plan, not slowed
    # the simulator followed within its bound: w' (over 10 ms) stays under 0.9 x it
    rate = np.abs(np.diff(rows[:, 2]) / np.diff(rows[:, 0]))
    assert np.max(rate) <= 0.9 * BOUND * 1.02
    whirl, misfit = free_whirl(hold(rows, 2.0, arrived + SETTLE), 2.0)
    assert misfit < 0.2 * whirl + 1e-9             # nothing but the two free whirls
    peak = np.max(np.hypot(rows[:, 4], rows[:, 5]))

    out26, rows26 = stream(ros_processes, ros_node, ns + 'e', ('table1.yaml',),
                           {'profile': 'eq26', 'period': 15.0, 'omega_target': 2.0,
                            'duration': 15.0 + SETTLE + WINDOW})
    arrived26 = rows26[rows26[:, 2] == 2.0][0, 0]
    whirl26, _ = free_whirl(hold(rows26, 2.0, arrived26 + SETTLE), 2.0)
    print(f'planned: {duration:g} s, predicted {predicted:.3g} m, measured {whirl:.3g} m, '
          f'peak {peak:.6g} m; Eq. 26: measured {whirl26:.3g} m')
    assert whirl <= 10 * predicted
    # the plan holds the whirl to its bound (0.25 um), Eq. 26 leaves 0.254 um offline;
    # through the stream the timing adds to both (docs/planner.md, "Streaming a plan"):
    # of the same order as Eq. 26's (the loopback's timing varies from run to run: the
    # ratio was 1.6 on a CI run, where the demo left 0.51 um against Eq. 26's
    # 0.25 um offline), in less than half its 15 s
    assert whirl < 3 * whirl26 and duration < 0.5 * 15.0
    assert peak < LIMIT
    assert peak >= static_deflection(2.0)


@pytest.mark.parametrize('files, params, reason', [
    ((), {'robust': 1.0}, 'robust must be < 1'),
    ((), {'residual': 0.0}, 'residual must be > 0'),
    ((), {'deflection_limit': 0.002}, 'static deflection at omega_target = 2 rad/s'),
    ((), {'omega_target': 13.0, 'deflection_limit': 1.0}, 'lowest natural frequency'),
    ((), {'max_angular_acceleration': -1.0}, 'max_angular_acceleration'),
    ((), {'mass': -0.3}, 'mass'),
    # the rod reaches the publisher through the simulator's params file: upright and
    # steel, 2 rad/s is beyond 3 mm already (docs/real_rig.md)
    (('table1.yaml', 'real_rig.yaml'), {}, 'static deflection at omega_target = 2 rad/s'),
])
def test_the_publisher_refuses_a_plan_it_cannot_make_and_says_why(ros_processes, files,
                                                                  params, reason):
    ros_args = ros_arguments(params={'profile': 'planned', **params})
    paths = [a for name in files for a in ('--params-file', str(CONFIG / name))]
    proc = ros_processes.start_console_script('profile_publisher', ros_args[0], *paths,
                                              *ros_args[1:])
    assert proc.wait(timeout=60) == 2
    assert 'invalid configuration' in proc.output and reason in proc.output


def test_a_running_planned_publisher_keeps_its_plan_when_set_a_bad_value(
        ros_processes, ros_node, request):
    """Its parameters are read-only: a change is refused with the reason, and the
    publisher streams the plan it logged (at rest for the lead, then the change)."""
    ns = namespace(request)
    pub = ros_processes.start_console_script('profile_publisher', *ros_arguments(
        namespace=ns, params={'profile': 'planned', 'max_angular_acceleration': 2.0}))
    pub.wait_for_output('waiting for a subscriber', timeout=60)
    service = f'{ns}/rotrod_profile_publisher'
    result = ros_node.call_service(SetParameters, f'{service}/set_parameters',
                                   SetParameters.Request(parameters=[param('robust', 2.0)]))
    assert not result.results[0].successful and 'read-only' in result.results[0].reason
    value = ros_node.call_service(GetParameters, f'{service}/get_parameters',
                                  GetParameters.Request(names=['robust'])).values[0]
    assert value.type == ParameterType.PARAMETER_DOUBLE and value.double_value == 0.0
    assert pub.running
    got = ros_node.subscribe(f'{ns}/cmd/omega', Float64, qos=1000)
    ros_node.spin_until(lambda: len(got) > 320, 30, 'the lead and the start of the change')
    w = [m.data for m in got]
    assert w[:300] == [0.0] * 300 and 0.0 < w[320] < 2.0


STALLED = 'setpoints of the stream reached the simulator after their due time'
"""What ``rotrod demo`` says when the machine held its setpoint stream up."""


@pytest.mark.long      # a robust plan takes tens of seconds: .ci/run runs it
def test_the_demo_streams_the_planned_spin_up_and_compares_it_offline(tmp_path):
    """``rotrod demo --profile planned``: the plan of config/planned.yaml through the
    three nodes; the recorded whirl after arrival is the plan's (within 10x its
    prediction) and of the order of Eq. 26's, the peak under 3 mm."""
    import subprocess

    from rotrod_ros.install import executable
    for attempt in (1, 2):      # once more if the machine held the stream up (it says)
        out = tmp_path / f'demo{attempt}' / 'rotrod.rrd'
        run = subprocess.run([*executable('rotrod'), 'demo', '--profile', 'planned', '-o',
                              str(out)], capture_output=True, text=True, timeout=600)
        assert run.returncode == 0, run.stdout + run.stderr
        if STALLED not in run.stdout:
            break
        print(f'demo run {attempt}: the stream was held up\n{run.stdout}')
    text = run.stdout
    assert 'the planned spin-up of config/planned.yaml' in text and out.is_file()
    whirl, offline = (float(x) for x in
                      re.search(r'whirl after arrival \[um\] +([0-9.]+) +([0-9.]+)', text)
                      .groups())
    predicted = float(re.search(r'the plan predicts ([0-9.]+) um', text).group(1))
    assert re.search(r'Eq. 26 leaves ([0-9.]+) um', text)
    peak = float(re.search(r'peak deflection \[mm\] +([0-9.]+)', text).group(1))
    du, dv = (float(x) for x in re.search(
        r'max \|u - u_offline\| = ([0-9.e+-]+) mm .*max \|v - v_offline\| = ([0-9.e+-]+) mm',
        text).groups())
    assert offline == pytest.approx(predicted, abs=2e-3)
    # the stream (100 Hz setpoints placed on a grid fitted to their arrival times, then
    # interpolated by the simulator's shaper) follows the offline run within 1 % of the
    # peak deflection; the timing of the loopback moves the grid, so the whirl it adds
    # varies from run to run (0.19-0.51 um for Eq. 26's 0.25 um, on machines of this
    # kind): of the order of the plan's own (10x its prediction), and never more than the
    # offline whirl plus the largest distance between the two runs
    apart = 1e3 * math.hypot(du, dv)        # largest distance between the runs, um
    assert apart < 1e-2 * 1e3 * peak, text
    assert whirl <= 10 * predicted, text
    assert whirl <= offline + apart + 1e-3, text
    assert 1e3 * static_deflection(2.0) <= peak < 1e3 * LIMIT
