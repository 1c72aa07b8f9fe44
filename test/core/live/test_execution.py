"""Trajectories executed by the engine: the path, the outcomes, tolerances and preemption.

The reference is the trajectory's own closed form (its points, the cubic through them)
and the offline run of the same trajectory (``simulate``), never the engine's output.
"""

import math

import pytest

from rotrod_core import RodParams, plan_spin_up, simulate, whirl_residual
from rotrod_core.command.trajectory import (
    GOAL_TOLERANCE_VIOLATED,
    INVALID_GOAL,
    OLD_HEADER_TIMESTAMP,
    PATH_TOLERANCE_VIOLATED,
    SUCCESSFUL,
    HubState,
    HubTrajectory,
    TrajectoryPoint,
    TrajectoryRejected,
    profile_points,
    trajectory_times,
)
from rotrod_core.live.engine import EngineConfig, SimulationEngine
from rotrod_core.live.execution import (
    CANCELED,
    DEFAULT_GOAL,
    Tolerance,
    Tracking,
    TrajectoryExecution,
    TrajectoryGoal,
    goal_time_tolerance,
    merged_tolerance,
)

RAMP = (TrajectoryPoint(1.0, velocity=0.5, acceleration=0.5),
        TrajectoryPoint(2.0, velocity=1.0, acceleration=0.0))
"""0 -> 1 rad/s in 2 s: w = 0.5 t^2 / 1 ... a cubic from rest through (1 s, 0.5, 0.5)."""


def engine(**config):
    return SimulationEngine(EngineConfig(**{'max_angular_acceleration': 2.0, **config}))


def run(eng, seconds):
    for _ in range(round(seconds / eng.dt)):
        eng.step()


def outcomes(eng):
    got = list(eng.trajectory_outcomes)
    eng.trajectory_outcomes.clear()
    return got


def test_the_hub_passes_every_point_at_its_time_and_holds_the_last_speed():
    eng = engine()
    eng.command_trajectory(TrajectoryGoal(RAMP, token='g'))
    run(eng, 1.0)
    assert eng.state.omega == pytest.approx(0.5, abs=1e-12)
    assert eng.tracking().desired.acceleration == pytest.approx(0.5, abs=1e-12)
    run(eng, 1.0)
    assert eng.state.omega == pytest.approx(1.0, abs=1e-12)
    [done] = outcomes(eng)
    assert (done.token, done.code) == ('g', SUCCESSFUL)
    run(eng, 0.5)
    assert eng.state.omega == pytest.approx(1.0, abs=1e-12) and eng.execution is None


def test_a_planned_spin_up_executed_leaves_the_whirl_of_its_offline_run():
    params = RodParams()
    plan = plan_spin_up(params, 1.0, max_angular_acceleration=1.0)
    points = profile_points(plan, trajectory_times(plan, plan.end_time, 10.0))
    eng = engine(max_angular_acceleration=1.0)
    eng.command_trajectory(TrajectoryGoal(points))
    run(eng, plan.end_time + 0.0005)
    s = eng.state
    live = whirl_residual(params, 1.0, s.u, s.v, s.du, s.dv)
    offline = simulate(params, HubTrajectory(points, HubState(0.0, 0.0)), eng.time, dt=1e-3)
    ref = whirl_residual(params, 1.0, offline.u[-1], offline.v[-1], offline.du[-1],
                         offline.dv[-1])
    assert live == pytest.approx(ref, rel=0.01)


def test_a_goal_in_torque_drive_or_while_halted_is_refused_with_a_reason():
    eng = engine(drive='torque')
    eng.command_trajectory(TrajectoryGoal(RAMP, token=1))
    [out] = outcomes(eng)
    assert out.code == INVALID_GOAL and "the drive is 'torque'" in out.message
    eng = engine()
    eng.halted = 'a test halt'
    eng.command_trajectory(TrajectoryGoal(RAMP, token=2))
    assert 'halted (a test halt)' in outcomes(eng)[0].message


def test_a_stamp_that_has_passed_is_refused_and_one_ahead_waits():
    eng = engine()
    run(eng, 3.0)
    eng.command_trajectory(TrajectoryGoal(RAMP, start_time=0.5))
    assert outcomes(eng)[0].code == OLD_HEADER_TIMESTAMP
    eng.command_trajectory(TrajectoryGoal(RAMP, start_time=4.0, token='later'))
    run(eng, 0.9)
    assert eng.state.omega == 0.0 and eng.execution is None
    run(eng, 0.1 + 2.0)
    assert eng.state.omega == pytest.approx(1.0, abs=1e-12)
    assert outcomes(eng)[0].code == SUCCESSFUL


def test_a_stamp_in_the_past_runs_the_points_still_ahead_from_the_hub_s_state():
    eng = engine()
    run(eng, 1.5)
    eng.command_trajectory(TrajectoryGoal(RAMP, start_time=eng.time - 0.5))
    assert eng.execution.trajectory.points[0].time == pytest.approx(0.5)
    run(eng, 1.5)
    assert eng.state.omega == pytest.approx(1.0, abs=1e-12)


def test_a_new_goal_preempts_the_running_one_and_starts_from_the_hub_s_motion():
    eng = engine()
    eng.command_trajectory(TrajectoryGoal(RAMP, token='old'))
    run(eng, 1.0)
    w, dw = eng.state.omega, eng.omega_dot
    eng.command_trajectory(TrajectoryGoal(
        (TrajectoryPoint(1.0, velocity=0.0, acceleration=0.0),), token='new'))
    [old] = outcomes(eng)
    assert (old.token, old.code) == ('old', INVALID_GOAL) and 'preempted' in old.message
    eng.step()          # from (w, w') on, continuously
    assert eng.state.omega == pytest.approx(w + dw * eng.dt, abs=2 * eng.dt ** 2 * 2.0)
    run(eng, 1.0)
    assert eng.state.omega == pytest.approx(0.0, abs=1e-12)
    assert outcomes(eng)[0].code == SUCCESSFUL


def test_a_setpoint_preempts_a_goal_and_a_cancel_holds_the_speed():
    eng = engine()
    eng.command_trajectory(TrajectoryGoal(RAMP, token='a'))
    run(eng, 1.0)
    eng.command_omega(0.2)
    assert outcomes(eng)[0].message == 'preempted by an angular-velocity setpoint'
    run(eng, 2.0)
    assert eng.state.omega == pytest.approx(0.2)
    eng.command_trajectory(TrajectoryGoal(RAMP, token='b'))
    run(eng, 1.0)
    w = eng.state.omega
    eng.cancel_trajectory('other')                  # not this goal: nothing happens
    assert eng.execution is not None
    eng.cancel_trajectory('b')
    [out] = outcomes(eng)
    assert out.code == CANCELED and 'holding w' in out.message
    run(eng, 1.0)
    assert eng.state.omega == w


def test_reset_halt_and_a_drive_change_end_the_goal():
    eng = engine()
    eng.command_trajectory(TrajectoryGoal(RAMP, token='r'))
    run(eng, 0.5)
    eng.reset()
    assert outcomes(eng)[0].message == 'the simulation was reset'
    eng.command_trajectory(TrajectoryGoal(RAMP, token='d'))
    eng.reconfigure(eng.config.replace(drive='torque'))
    assert "drive changed to 'torque'" in outcomes(eng)[0].message
    # 10 m out, 1 rad/s deflects the rod by 69 mm: beyond 0.1 l, the model's bound
    eng = engine(params=RodParams(eccentricity=10.0), max_angular_acceleration=0.4)
    eng.command_trajectory(TrajectoryGoal(
        (TrajectoryPoint(4.0, velocity=1.0, acceleration=0.0),), token='h'))
    run(eng, 4.0)
    [out] = outcomes(eng)
    assert out.code == PATH_TOLERANCE_VIOLATED and 'halted' in out.message


def test_lowering_a_limit_below_the_trajectory_ends_it():
    eng = engine()
    eng.command_trajectory(TrajectoryGoal(RAMP))
    eng.reconfigure(eng.config.replace(max_angular_acceleration=0.6))    # the ramp needs 0.75
    assert "beyond the new limit 0.6" in outcomes(eng)[0].message


def test_a_path_tolerance_is_checked_at_every_step():
    # the engine holds w' over each step: 1 rad/s^3 of jerk leaves up to dt/2 of error in w'
    eng = engine()
    eng.command_trajectory(TrajectoryGoal(RAMP, path_tolerance=Tolerance(acceleration=1e-4)))
    run(eng, 0.01)
    [out] = outcomes(eng)
    assert out.code == PATH_TOLERANCE_VIOLATED and 'acceleration error' in out.message
    eng = engine()
    eng.command_trajectory(TrajectoryGoal(RAMP, path_tolerance=Tolerance(1e-6, 1e-12, 0.01)))
    run(eng, 2.5)
    assert outcomes(eng)[0].code == SUCCESSFUL


def test_the_goal_tolerance_waits_up_to_the_goal_time_then_gives_up():
    traj = HubTrajectory(RAMP, HubState(0.0, 0.0))
    goal = TrajectoryGoal(RAMP, goal_tolerance=Tolerance(velocity=0.01), goal_time_tolerance=0.1)
    ex = TrajectoryExecution(goal, traj, start=10.0)
    off = HubState(1.0, 0.98, 0.0)           # 0.02 rad/s short of the last point
    assert ex.check(Tracking(2.05, traj_state(traj, 2.05), off)) is None
    late = ex.check(Tracking(2.2, traj_state(traj, 2.2), off))
    assert late.code == GOAL_TOLERANCE_VIOLATED and 'velocity error 0.02' in late.message
    on = ex.check(Tracking(2.2, traj_state(traj, 2.2), HubState(
        traj.position(2.2), 1.0, 0.0)))
    assert on.code == SUCCESSFUL


def traj_state(traj, t):
    return HubState(float(traj.position(t)), float(traj.omega(t)), float(traj.omega_dot(t)))


def test_tolerances_merge_as_the_controller_s_zero_default_minus_one_off():
    merged = merged_tolerance((0.0, -1.0, 0.3), DEFAULT_GOAL, 'goal')
    assert merged == Tolerance(None, None, 0.3)
    assert merged_tolerance((0.0, 0.0, 0.0), DEFAULT_GOAL, 'goal') == DEFAULT_GOAL
    for bad in (-0.5, math.nan):
        with pytest.raises(TrajectoryRejected, match='goal velocity tolerance'):
            merged_tolerance((0.0, bad, 0.0), DEFAULT_GOAL, 'goal')
    assert goal_time_tolerance(0.0) is None and goal_time_tolerance(-1.0) is None
    assert goal_time_tolerance(0.25) == 0.25
    with pytest.raises(TrajectoryRejected):
        goal_time_tolerance(-2.0)


def test_lockstep_replays_of_a_goal_are_bit_identical():
    def replay():
        eng = engine()
        run(eng, 0.123)
        eng.command_trajectory(TrajectoryGoal(RAMP))
        run(eng, 2.5)
        return eng.state
    assert replay() == replay()
