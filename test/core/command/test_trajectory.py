"""Hub trajectories against the closed forms of their interpolation and their limits."""

import math

import numpy as np
import pytest

from rotrod_core import RodParams, plan_spin_up
from rotrod_core.command.trajectory import (
    INVALID_GOAL,
    INVALID_JOINTS,
    HubState,
    HubTrajectory,
    TrajectoryPoint,
    TrajectoryRejected,
    hub_points,
    profile_points,
    trajectory_times,
)

REST = HubState(0.0, 0.0, 0.0)


def quintic(h, start, end, x):
    """Closed-form quintic Hermite through (p, v, a) at 0 and h, evaluated at x in [0, h]."""
    s = x / h
    h00 = 1 - 10 * s**3 + 15 * s**4 - 6 * s**5
    h10 = s - 6 * s**3 + 8 * s**4 - 3 * s**5
    h20 = 0.5 * s**2 - 1.5 * s**3 + 1.5 * s**4 - 0.5 * s**5
    h01 = 10 * s**3 - 15 * s**4 + 6 * s**5
    h11 = -4 * s**3 + 7 * s**4 - 3 * s**5
    h21 = 0.5 * s**3 - s**4 + 0.5 * s**5
    (p0, v0, a0), (p1, v1, a1) = start, end
    return (h00 * p0 + h10 * h * v0 + h20 * h * h * a0
            + h01 * p1 + h11 * h * v1 + h21 * h * h * a1)


def test_positions_velocities_and_accelerations_give_the_quintic_from_the_start_state():
    start = HubState(0.2, 0.5, -0.1)
    points = [TrajectoryPoint(1.5, 1.0, 1.2, 0.3), TrajectoryPoint(2.5, 2.5, 1.0, 0.0)]
    tr = HubTrajectory(points, start)
    x = np.linspace(0.0, 1.5, 31)
    assert tr.position(x) == pytest.approx(
        quintic(1.5, (0.2, 0.5, -0.1), (1.0, 1.2, 0.3), x), abs=1e-12)
    y = np.linspace(0.0, 1.0, 21)
    assert tr.position(1.5 + y) == pytest.approx(
        quintic(1.0, (1.0, 1.2, 0.3), (2.5, 1.0, 0.0), y), abs=1e-12)
    # w and w' are its derivatives: central differences of theta
    h = 1e-5
    for t in (0.3, 1.1, 2.2):
        assert tr.omega(t) == pytest.approx((tr.position(t + h) - tr.position(t - h)) / (2 * h),
                                            abs=1e-8)
        assert tr.omega_dot(t) == pytest.approx((tr.omega(t + h) - tr.omega(t - h)) / (2 * h),
                                                abs=1e-6)


def test_velocities_and_accelerations_alone_reproduce_a_cubic_speed_exactly():
    def w(t):
        return 0.3 + 0.8 * t - 0.5 * t**2 + 0.1 * t**3

    def dw(t):
        return 0.8 - t + 0.3 * t**2

    times = [0.0, 0.7, 1.9, 3.0]
    points = [TrajectoryPoint(t, velocity=w(t), acceleration=dw(t)) for t in times]
    tr = HubTrajectory(points, HubState(5.0, w(0.0), dw(0.0)))
    t = np.linspace(0, 3, 61)
    assert tr.omega(t) == pytest.approx(w(t), abs=1e-13)
    # theta is the exact integral from the start angle
    theta = 5.0 + 0.3 * t + 0.4 * t**2 - t**3 / 6 + 0.025 * t**4
    assert tr.position(t) == pytest.approx(theta, abs=1e-12)
    assert tr.omega_at(1.234) == pytest.approx(w(1.234), abs=1e-13)
    # after the end the last speed holds, theta grows at it
    assert tr.omega(4.0) == tr.omega(3.0) == pytest.approx(w(3.0), abs=1e-13)
    assert tr.position(4.0) == pytest.approx(tr.position(3.0) + w(3.0), abs=1e-12)


def test_velocities_alone_are_a_linear_speed_and_a_first_point_at_zero_is_the_start():
    points = [TrajectoryPoint(0.0, velocity=1.0), TrajectoryPoint(2.0, velocity=2.0)]
    tr = HubTrajectory(points, HubState(0.0, 1.0), start_tolerance=(0.0, 1e-12))
    assert tr.omega(1.0) == pytest.approx(1.5, abs=1e-14)
    assert tr.omega_dot(0.5) == pytest.approx(0.5, abs=1e-14)
    with pytest.raises(TrajectoryRejected, match='w cannot jump') as err:
        HubTrajectory(points, HubState(0.0, 0.9))
    assert err.value.code == INVALID_GOAL


def test_positions_alone_are_linear_so_a_change_of_speed_is_refused():
    steady = [TrajectoryPoint(1.0, 1.0), TrajectoryPoint(2.0, 2.0)]
    assert HubTrajectory(steady, HubState(0.0, 1.0)).omega(1.5) == pytest.approx(1.0)
    with pytest.raises(TrajectoryRejected, match='w jumps by 1 rad/s at t = 1 s'):
        HubTrajectory([TrajectoryPoint(1.0, 1.0), TrajectoryPoint(2.0, 3.0)],
                      HubState(0.0, 1.0))


def test_the_limits_hold_between_the_points_not_only_at_them():
    # a cubic through w = 0 at both ends with w' = 2 and -2: it peaks between them
    points = [TrajectoryPoint(1.0, velocity=0.0, acceleration=2.0),
              TrajectoryPoint(2.0, velocity=0.0, acceleration=-2.0)]
    tr = HubTrajectory(points, HubState(0.0, 0.0, -2.0))
    dense = np.linspace(0, 2, 200001)
    peak = np.max(np.abs(tr.omega(dense)))
    assert tr.peak == pytest.approx(peak, rel=1e-9)
    assert tr.max_angular_acceleration == pytest.approx(
        np.max(np.abs(tr.omega_dot(dense))), rel=1e-9)
    with pytest.raises(TrajectoryRejected, match=r"\|w\| reaches .* beyond the drive's limit"):
        HubTrajectory(points, HubState(0.0, 0.0, -2.0), max_omega=0.99 * peak)
    HubTrajectory(points, HubState(0.0, 0.0, -2.0), max_omega=peak)        # at it: allowed
    with pytest.raises(TrajectoryRejected, match=r"\|w'\| reaches"):
        HubTrajectory(points, HubState(0.0, 0.0, -2.0), max_angular_acceleration=1.0)


def test_a_continuous_joint_starts_within_pi_of_the_first_point():
    # the hub has turned 15.9 turns (100 rad); the points are given in [-pi, pi)
    hub = 100.0
    first = math.remainder(hub, 2 * math.pi) + 0.1
    points = [TrajectoryPoint(1.0, first, 0.0), TrajectoryPoint(2.0, first + 0.5, 0.0)]
    tr = HubTrajectory(points, HubState(hub, 0.0))
    assert tr.position(0.0) == pytest.approx(first - 0.1, abs=1e-9)
    assert tr.position_offset == pytest.approx(2 * math.pi * round((first - 0.1 - hub)
                                                                   / (2 * math.pi)), abs=1e-9)
    assert abs(tr.position_offset / (2 * math.pi) - round(tr.position_offset / (2 * math.pi))) \
        < 1e-12
    assert tr.peak < 1.0                # 0.1 rad, not 100 rad back


def message(*points, names=('hub',)):
    """hub_points's arguments from (time, positions, velocities, accelerations, effort)."""
    return list(names), [tuple(p) for p in points]


@pytest.mark.parametrize('names, points, code, match', [
    ([], [(1.0, [], [1.0], [], [])], INVALID_JOINTS, 'no joint names'),
    (['rotor'], [(1.0, [], [1.0], [], [])], INVALID_JOINTS, "no joint 'rotor'"),
    (['hub', 'tip_radial'], [(1.0, [], [1.0, 0.0], [], [])], INVALID_JOINTS, 'passive'),
    (['hub', 'hub'], [(1.0, [], [1.0, 1.0], [], [])], INVALID_JOINTS, 'repeat'),
    (['hub'], [], INVALID_GOAL, 'no points'),
    (['hub'], [(1.0, [], [1.0, 2.0], [], [])], INVALID_GOAL, '2 velocity values for 1'),
    (['hub'], [(1.0, [], [1.0], [], [3.0])], INVALID_GOAL, 'efforts'),
    (['hub'], [(1.0, [], [1.0], [], []), (1.0, [], [2.0], [], [])], INVALID_GOAL,
     'does not increase'),
    (['hub'], [(-1.0, [], [1.0], [], [])], INVALID_GOAL, 'does not increase'),
    (['hub'], [(math.nan, [], [1.0], [], [])], INVALID_GOAL, 'time_from_start is nan'),
    (['hub'], [(1.0, [], [math.inf], [], [])], INVALID_GOAL, 'velocity is inf'),
    (['hub'], [(1.0, [], [1.0], [], []), (2.0, [1.0], [1.0], [], [])], INVALID_GOAL,
     'same fields'),
    (['hub'], [(1.0, [], [], [], [])], INVALID_GOAL, 'neither positions nor velocities'),
    (['hub'], [(1.0, [1.0], [], [0.0], [])], INVALID_GOAL, 'accelerations without'),
])
def test_a_malformed_trajectory_is_refused_with_the_standard_code_and_a_sentence(
        names, points, code, match):
    with pytest.raises(TrajectoryRejected, match=match) as err:
        hub_points(names, points)
    assert err.value.code == code


def test_the_hub_column_is_read_by_name():
    points = hub_points(['hub'], [(0.5, [1.0], [2.0], [3.0], [])])
    assert points == (TrajectoryPoint(0.5, 1.0, 2.0, 3.0),)


def test_a_planned_spin_up_at_its_knots_is_the_plan_itself():
    plan = plan_spin_up(RodParams(), 1.0, max_angular_acceleration=2.0)
    points = profile_points(plan, trajectory_times(plan, plan.end_time, 10.0))
    tr = HubTrajectory(points, REST, max_angular_acceleration=2.0)
    t = np.linspace(0, plan.end_time + 0.5, 4001)
    assert np.max(np.abs(tr.omega(t) - plan.omega(t))) < 1e-13
    assert np.max(np.abs(tr.omega_dot(t) - plan.omega_dot(t))) < 1e-11
    assert np.max(np.abs(tr.angle(t) - plan.angle(t))) < 1e-12


def test_trajectory_times_keep_the_breakpoints_and_the_interval():
    plan = plan_spin_up(RodParams(), 1.0, max_angular_acceleration=2.0)
    times = trajectory_times(plan, plan.end_time + 1.0, 0.05)
    assert times[0] == 0.0 and times[-1] == plan.end_time + 1.0
    assert np.max(np.diff(times)) <= 0.05 + 1e-12
    assert set(plan.breakpoints()) <= set(times.tolist())
