"""The lockstep controller example: the same closed loop twice, byte for byte, once under load.

One simulator (torque drive, started paused), the controller run twice against it:
first stepping by the StepSimulation service on an idle machine, then by the
SimulateSteps action with two processes spinning on the two cores. Each run starts
with a full reset, so both write the same file, byte for byte. Checked against
definitions as well: the control instants are every control_steps steps of 1 ms, to
the nanosecond; the angular momentum about the axis, L = Je w + m (x vy - y vx) from
what the controller read (Table 1's rod is massless: m at the tip, Je the rotor's),
changes over each control period by exactly the torque commanded at its start times
the period (dL/dt = Q, exact coupling): each command acted from the first step of
its request to the last, no more, no less; and w rises towards the target.
"""

import sys

import pytest

from rotrod_core.model.equations import Coefficients
from rotrod_core.model.params import RodParams

pytestmark = [pytest.mark.ros, pytest.mark.slow]

DURATION = 1.0
CONTROL_STEPS = 10
OMEGA_TARGET = 2.0
RATE = 1.0
HOG = 'while True: pass'


def run_controller(ros_processes, out, stepping: str, name: str) -> None:
    proc = ros_processes.start_console_script(
        'lockstep_controller', '--ros-args', '-p', f'output:={out}', '-p',
        f'stepping:={stepping}', '-p', f'duration:={DURATION}', '-p',
        f'control_steps:={CONTROL_STEPS}', '-p', f'omega_target:={OMEGA_TARGET}', '-p',
        f'rate:={RATE}', name=name)
    assert proc.wait(timeout=300) == 0, proc.output


@pytest.mark.long      # 10 s, twice and under load: CI's long run (the default run's budget)
def test_the_lockstep_controller_gives_the_same_file_twice_once_under_load(ros_processes,
                                                                          tmp_path):
    sim = ros_processes.start_console_script(
        'simulator', '--ros-args', '-p', 'drive:=torque', '-p', 'start_paused:=true')
    sim.wait_for_output('paused at simulated time 0', timeout=30)
    first, second = tmp_path / 'idle.csv', tmp_path / 'loaded.csv'
    run_controller(ros_processes, first, 'service', 'controller_idle')
    hogs = [ros_processes.start([sys.executable, '-c', HOG], name=f'hog{i}') for i in range(2)]
    run_controller(ros_processes, second, 'action', 'controller_loaded')
    assert all(h.running for h in hogs), 'the load was not there all along'
    assert first.read_bytes() == second.read_bytes()

    header, *rows = first.read_text().splitlines()
    assert header == 'stamp_ns,omega,x,y,vx,vy,torque'
    values = [[float(x) for x in row.split(',')] for row in rows]
    period_ns = CONTROL_STEPS * 10**6                      # steps x 1 ms
    assert [int(r[0]) for r in values] == [k * period_ns
                                           for k in range(round(DURATION * 1e9 / period_ns) + 1)]
    co = Coefficients.from_params(RodParams())
    assert co.load_radius == co.eccentricity                 # a massless rod
    momentum = [co.rotor_inertia * w + co.mass * (x * vy - y * vx)
                for _, w, x, y, vx, vy, _ in values]
    period = CONTROL_STEPS * 1e-3
    for k in range(len(values) - 1):
        torque = values[k][6]
        assert momentum[k + 1] - momentum[k] == pytest.approx(torque * period, abs=1e-12), k
    assert all(b[1] > a[1] for a, b in zip(values, values[1:]))     # spinning up
    assert 0.0 < values[-1][1] < OMEGA_TARGET                       # towards the target
