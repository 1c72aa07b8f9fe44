"""The simulator through the simulation_interfaces standard, from a client that is not rotrod.

The client (``test/sim_interfaces_client.py``, a separate process) imports rclpy, std_msgs,
rosgraph_msgs and ``simulation_interfaces`` only. The default run gives it the venv's
build of ``simulation_interfaces``; the long run gives it the package as colcon
builds it from the upstream definitions in a workspace of its own (the session's
build, test/colcon_workspace.py), that one alone, Python modules and libraries
(checked from the client's /proc/self/maps). Type hashes must then agree on the
wire, as with any client built against the published package.

The simulator runs at real_time_factor 2 with max_angular_acceleration 2 rad/s^2. The
client pauses, resets (time 0), commands 2 rad/s, takes 2000 steps by the service and
1000 by the action, sends bad requests, cancels a long SimulateSteps, does the same
again from a reset, and plays. Checked against definitions, not the code's output:
one step is 1/physics_rate s, so the stamps are 2 s and 3 s exactly; the hub, at its
acceleration limit from 0, reaches 2 rad/s within 1 s + setpoint_delay and holds it,
so that over one step at 3 s it turns by exactly w dt; the tip's velocity is the
derivative of its position (the trapezoid rule over one step); the second run equals
the first float for float; each bad request has the standard's code and changes
nothing. Then the same client spawns ten rods of different masses from the URDFs of
``rotrod urdf`` (uri), commands each its own speed, steps, and reads each tip by
GetEntitiesStates: at steady speed the mass stands at r0 + u_s from its hub, u_s =
m w^2 r0 / (k - m w^2) (docs/model.md, k = 3 E I / l^3 written out here); it deletes
one rod during a SimulateSteps goal (answered, the goal steps on), then the rest.
"""

import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest
from colcon_workspace import BUILD_TIMEOUT, tail
from ros_harness import console_script
from simulation_interfaces.msg import Result, SimulationState, SimulatorFeatures
from simulation_interfaces.srv import SetSimulationState

from rotrod_core import RodParams

pytestmark = pytest.mark.ros

ROOT = Path(__file__).resolve().parents[2]
CLIENT = Path(__file__).resolve().parents[1] / 'sim_interfaces_client.py'
PHYSICS_RATE = 1000.0
OMEGA = 2.0
SIMULATOR_PARAMS = ('-p', 'real_time_factor:=2.0', '-p', 'max_angular_acceleration:=2.0',
                    '-p', f'physics_rate:={PHYSICS_RATE}')
FEATURES = {SimulatorFeatures.ENTITY_STATE_GETTING, SimulatorFeatures.SIMULATION_RESET,
            SimulatorFeatures.SIMULATION_RESET_TIME, SimulatorFeatures.SIMULATION_RESET_STATE,
            SimulatorFeatures.SIMULATION_RESET_SPAWNED,
            SimulatorFeatures.SIMULATION_STATE_GETTING,
            SimulatorFeatures.SIMULATION_STATE_SETTING,
            SimulatorFeatures.SIMULATION_STATE_PAUSE, SimulatorFeatures.STEP_SIMULATION_SINGLE,
            SimulatorFeatures.STEP_SIMULATION_MULTIPLE,
            SimulatorFeatures.STEP_SIMULATION_ACTION, SimulatorFeatures.SPAWNING,
            SimulatorFeatures.DELETING, SimulatorFeatures.ENTITY_CATEGORIES,
            SimulatorFeatures.SPAWNING_RESOURCE_STRING, SimulatorFeatures.ENTITY_STATE_SETTING,
            SimulatorFeatures.ENTITY_INFO_GETTING, SimulatorFeatures.SPAWNABLES,
            SimulatorFeatures.SPAWNING_ENTITIES}
SUCCEEDED, CANCELED, ABORTED = 4, 5, 6          # action_msgs/GoalStatus


E, D, L, R0 = 100e9, 0.003, 0.3, 0.1                    # Table 1 (docs/model.md)
K = 3 * E * (math.pi * D**4 / 64) / L**3
WORLD = [{'name': f'm{i}', 'mass': 0.15 + 0.05 * i, 'omega': 1.0 + 0.1 * i, 'x': 0.5 * i}
         for i in range(10)]
WORLD_STEPS = 15000
"""15 s: the ramp at 2 rad/s^2, then ten decay times 1 / (zeta w0) of the free whirl
(zeta 0.1, w0 >= 8.6 rad/s for the heaviest)."""


def world_file(tmp_path) -> Path:
    """The client's rods: each a URDF file that ``rotrod urdf`` wrote for its mass."""
    rods = []
    for rod in WORLD:
        urdf = tmp_path / f"{rod['name']}.urdf"
        urdf.write_text(subprocess.run(
            [*console_script('rotrod'), 'urdf', '--mass', str(rod['mass']),
             '--damping-ratio', '0.1'], check=True, capture_output=True, text=True).stdout)
        rods.append({'name': rod['name'], 'urdf': str(urdf), 'omega': rod['omega'],
                     'x': rod['x'], 'steps': WORLD_STEPS})
    path = tmp_path / 'world.json'
    path.write_text(json.dumps(rods))
    return path


def run_client(ros_processes, tmp_path, extra_env=None) -> dict:
    sim = ros_processes.start_console_script('simulator', '--ros-args', *SIMULATOR_PARAMS)
    sim.wait_for_output('ready: drive=velocity', timeout=30)
    client = ros_processes.start([sys.executable, str(CLIENT), '--omega', str(OMEGA),
                                  '--world', str(world_file(tmp_path))],
                                 name='sim_interfaces_client', extra_env=extra_env)
    assert client.wait(timeout=240) == 0, client.output
    lines = [ln for ln in client.output.splitlines() if ln.startswith('@@REPORT@@')]
    assert lines, client.output
    return json.loads(lines[-1][len('@@REPORT@@'):])


def check_run(run: dict) -> None:
    """One run from a full reset: codes, exact times, the hub's speed, the tip's motion."""
    dt = 1.0 / PHYSICS_RATE
    assert run['reset'] == Result.RESULT_OK
    assert run['state_after_reset'] == SimulationState.STATE_STOPPED
    assert run['step'] == Result.RESULT_OK
    assert run['state_after_step'] == SimulationState.STATE_PAUSED
    for key, steps in (('tip_0', 0), ('tip_2000', 2000), ('tip_3000', 3000),
                       ('tip_3001', 3001)):
        tip = run[key]
        assert tip['result'] == Result.RESULT_OK and tip['frame'] == 'world'
        assert tip['stamp_ns'] == steps * 10**6          # steps x 1 ms, to the nanosecond
        assert tip['position'][2] == pytest.approx(float(RodParams().rod_length))
    action = run['action']
    assert action['accepted'] and action['status'] == SUCCEEDED
    assert action['result'] == Result.RESULT_OK
    feedback = action['feedback']
    assert feedback and all(c + r == 1000 for c, r in feedback)
    assert [c for c, _ in feedback] == sorted({c for c, _ in feedback})
    # 2 rad/s reached (2 rad/s^2 from rest: 1 s, plus the setpoint delay) and held
    for key in ('tip_2000', 'tip_3000', 'tip_3001'):
        assert run[key]['angular_velocity'] == [0.0, 0.0, pytest.approx(OMEGA, abs=1e-12)]
    a, b = run['tip_3000'], run['tip_3001']
    turned = (_yaw(b['orientation']) - _yaw(a['orientation'])) % (2 * math.pi)
    assert turned == pytest.approx(OMEGA * dt, abs=1e-12)
    for k in range(3):
        mean_velocity = (b['position'][k] - a['position'][k]) / dt
        assert mean_velocity == pytest.approx(0.5 * (a['velocity'][k] + b['velocity'][k]),
                                              abs=1e-6)


def _yaw(q) -> float:
    """The rotation about z of a quaternion (x, y, z, w) that has no other, rad."""
    x, y, z, w = q
    assert x == 0.0 and y == 0.0
    return 2.0 * math.atan2(z, w)


def check_report(report: dict) -> None:
    assert set(report['features']) == FEATURES
    assert report['state_at_start'] == SimulationState.STATE_PLAYING
    assert report['step_while_playing'] == Result.RESULT_INCORRECT_STATE
    assert report['pause'] == Result.RESULT_OK
    check_run(report['first'])
    bad = report['bad']
    assert bad['codes'] == {
        'step_0': Result.RESULT_OPERATION_FAILED, 'unknown_entity': Result.RESULT_NOT_FOUND,
        'steps_past_bound': Result.RESULT_OPERATION_FAILED,
        'pause_again': SetSimulationState.Response.ALREADY_IN_TARGET_STATE,
        'no_world': SetSimulationState.Response.INCORRECT_TRANSITION,
        'unknown_state': SetSimulationState.Response.INCORRECT_TRANSITION,
        'quitting': Result.RESULT_FEATURE_UNSUPPORTED,
        'action_0': Result.RESULT_OPERATION_FAILED}
    assert bad['unchanged'] and bad['action_0']['status'] == ABORTED
    cancelled = report['cancelled']
    assert cancelled['status'] == CANCELED and cancelled['result'] == Result.RESULT_OK
    assert cancelled['message'].startswith('cancelled: ')
    assert report['state_after_cancel'] == SimulationState.STATE_PAUSED
    check_run(report['second'])
    tips = ('tip_0', 'tip_2000', 'tip_3000', 'tip_3001')
    assert [report['second'][k] for k in tips] == [report['first'][k] for k in tips]
    assert report['play'] == Result.RESULT_OK
    assert report['state_after_play'] == SimulationState.STATE_PLAYING
    assert report['clock_after_play_ns'] > report['second']['tip_3001']['stamp_ns']
    check_world(report['world'])


def check_world(world: dict) -> None:
    """Ten rods spawned, each at its own steady deflection; deleted, one mid-goal."""
    names = [rod['name'] for rod in WORLD]
    assert world['spawn'] == Result.RESULT_OK and world['spawned'] == names
    assert world['step'] == Result.RESULT_OK
    for rod in WORLD:
        name, m, w = rod['name'], rod['mass'], rod['omega']
        assert world['hubs'][f'{name}/hub'] == pytest.approx(w, abs=1e-12)
        x, y, z = world['tips'][f'{name}/tip']
        u_s = m * w * w * R0 / (K - m * w * w)
        assert math.hypot(x - rod['x'], y) - R0 == pytest.approx(u_s, rel=2e-3), name
        assert z == pytest.approx(L)
    assert world['delete_during_goal'] == Result.RESULT_OK
    assert world['steps_after_delete'] > 0                  # the world stepped on
    assert world['goal_status'] == CANCELED
    assert world['delete_rest'] == [Result.RESULT_OK] * (len(WORLD) - 1)
    assert world['delete_again'] == Result.RESULT_NOT_FOUND
    assert world['left'] == ['hub', 'tip']


@pytest.mark.long      # 32 s: CI's long run, to keep the default run under 15 min
def test_a_standard_client_steps_resets_replays_plays_and_spawns_rods(ros_processes,
                                                                       tmp_path):
    report = run_client(ros_processes, tmp_path)
    check_report(report)
    venv = Path(sys.prefix).resolve()
    assert Path(report['module']).resolve().is_relative_to(venv)


@pytest.mark.long      # the session's colcon build (minutes), .ci/run's builds
@pytest.mark.timeout(BUILD_TIMEOUT + 300)     # that build, beside the soak in .ci/run
def test_a_client_with_a_separately_built_package_talks_to_the_simulator(
        ros_processes, tmp_path, colcon_interfaces):
    assert colcon_interfaces.returncode == 0, tail(colcon_interfaces.output)
    separate = colcon_interfaces.install('simulation_interfaces')
    site = next(separate.glob('lib/python3*/site-packages'))
    lib = separate / 'lib'
    env = {'PYTHONPATH': os.pathsep.join([str(site), os.environ.get('PYTHONPATH', '')]),
           'LD_LIBRARY_PATH': os.pathsep.join([str(lib),
                                               os.environ.get('LD_LIBRARY_PATH', '')])}
    report = run_client(ros_processes, tmp_path, extra_env=env)
    check_report(report)
    separate = separate.resolve()
    assert Path(report['module']).resolve().is_relative_to(separate)
    assert report['libraries'], 'no simulation_interfaces library mapped'
    for path in report['libraries']:
        assert Path(path).resolve().is_relative_to(separate), path
