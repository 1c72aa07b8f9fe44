"""Setpoint shaping: linear interpolation of the stream, delayed, bounded, continuous."""

import math
import re

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st
from properties import (  # the shared settings and strategies of the property tests
    EXTREME_FLOATS,
    TINY,
    WRONG_TYPES,
    anything,
    finite,
    props,
)

from rotrod_core.command.profiles import Eq26Profile
from rotrod_core.command.shaping import MAX_PATH_SEGMENTS, LowerEnvelope, OmegaSetpointShaper

T = 0.01


def stream(shaper, omega, n, jitter=0.0, seed=0, start=0.0):
    """Send omega(k T) arriving at start + k T + a latency uniform in [0, jitter]."""
    rng = np.random.default_rng(seed)
    arrivals = []
    for k in range(n):
        a = start + k * T + (rng.uniform(0.0, jitter) if jitter else 0.0)
        a = max(a, arrivals[-1] if arrivals else start)
        shaper.command(omega(k * T), a)
        arrivals.append(a)
    return arrivals


def sample(shaper, t):
    return np.array([shaper.omega(x) for x in t]), np.array([shaper.omega_dot(x) for x in t])


def test_steady_stream_is_its_linear_interpolation_delayed_by_the_delay():
    sh = OmegaSetpointShaper(10.0)
    profile = lambda t: 0.5 * math.sin(2 * t)  # noqa: E731
    stream(sh, profile, 500)
    t = np.linspace(0.5, 4.8, 3001)
    w, _ = sample(sh, t)
    knots = np.arange(500) * T
    expected = np.interp(t - 2 * T, knots, [profile(x) for x in knots])
    assert np.max(np.abs(w - expected)) < 1e-12
    assert sh.interval == pytest.approx(T, rel=1e-9)


@pytest.mark.parametrize('jitter', [0.001, 0.003])
def test_delivery_jitter_does_not_reach_the_angular_acceleration(jitter):
    a = 0.3                                      # rad/s^2: w = a t
    sh = OmegaSetpointShaper(10.0)
    stream(sh, lambda t: a * t, 1500, jitter=jitter, seed=3)
    t = np.linspace(3.0, 14.9, 4001)
    w, wd = sample(sh, t)
    # after the grid fit has a full window, w' is the stream's slope to a few per cent
    assert np.max(np.abs(wd - a)) < 0.05 * a
    # the grid's phase lies within the delivery latencies
    assert np.max(np.abs(w - a * (t - sh.delay))) < a * jitter


def test_an_isolated_step_ramps_at_the_acceleration_limit():
    sh = OmegaSetpointShaper(4.0)
    sh.command(2.0, 1.0)
    assert sh.omega(1.0) == 0.0
    assert sh.omega_dot(1.0) == 4.0
    assert sh.omega(1.25) == pytest.approx(1.0)
    assert sh.target_reached_at == pytest.approx(1.5)
    assert sh.omega(3.0) == 2.0 and sh.omega_dot(3.0) == 0.0


def test_a_small_step_takes_the_delay_not_the_limit():
    sh = OmegaSetpointShaper(100.0)
    sh.command(0.1, 0.0)
    assert sh.target_reached_at == pytest.approx(2 * sh.nominal_interval)


def test_a_new_setpoint_cuts_a_long_ramp_at_once():
    sh = OmegaSetpointShaper(10.0)
    sh.command(20.0, 0.0)                        # a 2 s ramp
    sh.command(0.0, 0.5)                         # changed mind after 0.5 s
    assert sh.omega(0.5) == pytest.approx(5.0)
    assert sh.omega_dot(0.5) == -10.0
    assert sh.omega(1.0) == pytest.approx(0.0)
    assert sh.omega(2.0) == 0.0


def test_angular_velocity_is_continuous_and_acceleration_bounded_under_any_stream():
    rng = np.random.default_rng(7)
    limit = 5.0
    sh = OmegaSetpointShaper(limit)
    t = 0.0
    for _ in range(400):
        t += rng.choice([0.001, 0.01, 0.02, 0.3])
        sh.command(rng.uniform(-10, 10), t)
    grid = np.linspace(0, t + 5, 200001)
    w, wd = sample(sh, grid)
    assert np.max(np.abs(wd)) <= limit + 1e-12
    assert np.max(np.abs(np.diff(w))) <= limit * (grid[1] - grid[0]) * (1 + 1e-9)


def test_a_pause_starts_a_new_stream():
    sh = OmegaSetpointShaper(10.0)
    stream(sh, lambda t: 1.0, 100)
    sh.command(1.1, 10.0)                        # long after the stream stopped
    assert sh.omega(10.0) == pytest.approx(1.0)
    assert sh.target_reached_at == pytest.approx(10.0 + 2 * T)


def test_reset_holds_the_given_speed():
    sh = OmegaSetpointShaper(10.0)
    sh.command(3.0, 0.0)
    sh.reset(1.25, 5.0)
    assert sh.omega(6.0) == 1.25 and sh.omega_dot(6.0) == 0.0 and sh.setpoint == 1.25


@pytest.mark.parametrize('value', [math.nan, math.inf, -math.inf, 'fast', None, True])
def test_bad_setpoints_are_refused(value):
    sh = OmegaSetpointShaper(10.0)
    with pytest.raises(ValueError, match='setpoint'):
        sh.command(value, 0.1)


def test_time_must_not_go_back():
    sh = OmegaSetpointShaper(10.0)
    sh.command(1.0, 1.0)
    with pytest.raises(ValueError, match='precedes'):
        sh.command(1.0, 0.5)


@pytest.mark.parametrize('kwargs', [
    {'max_angular_acceleration': 0.0}, {'max_angular_acceleration': math.inf},
    {'max_angular_acceleration': 1.0, 'delay': 0.0},
    {'max_angular_acceleration': 1.0, 'window': 1},
    {'max_angular_acceleration': 1.0, 'nominal_interval': 1.0},
])
def test_bad_configuration_is_refused(kwargs):
    with pytest.raises(ValueError):
        OmegaSetpointShaper(**kwargs)


def test_a_stall_shorter_than_the_delay_does_not_reach_w():
    a = 0.3                                      # rad/s^2: w = a t
    sh = OmegaSetpointShaper(10.0, delay=0.2)
    for k in range(1000):
        arrival = k * T if not 300 <= k < 310 else 310 * T   # 0.1 s stall, then a burst
        sh.command(a * k * T, arrival)
    t = np.linspace(2.5, 9.7, 3001)
    w, wd = sample(sh, t)
    assert np.max(np.abs(wd - a)) < 1e-3 * a
    assert np.max(np.abs(w - a * (t - 0.2))) < 1e-6


@pytest.mark.parametrize('first, stall', [(2, 0.05), (2, 0.15), (5, 0.1), (9, 0.19)])
def test_a_stall_among_a_streams_first_samples_moves_only_its_first_nano_rad_s(first, stall):
    """The paper's Eq. 26 (w' = 0 at t = 0) streamed at 100 Hz whose samples from
    ``first`` on are held up for ``stall`` s and then arrive together: with too few
    arrivals for a grid, the burst ramps from its arrival (the shaper's documented
    catch-up), so w leaves 0 up to the delay early, but only by what Eq. 26 reaches in
    those samples, and from there on w is the stream delayed by the delay."""
    D = 0.2
    eq26 = Eq26Profile(period=15.0, omega_target=2.0).omega     # the stream: 0 -> 2 rad/s
    sh = OmegaSetpointShaper(0.5, delay=D)
    n, last = 1601, first + round(stall / T)                   # 16 s: up to the hold
    for k in range(n):
        sh.command(float(eq26(k * T)), T * (last if first <= k <= last else k))
    t = np.arange(0.0, n * T + 1.0, T / 4)
    w, _ = sample(sh, t)
    moved = t[np.argmax(w != 0.0)]
    assert min(D, last * T) - T / 4 <= moved <= D + T / 4     # not before the burst came
    assert np.max(w[t < D]) <= eq26((last + 1) * T)            # what it moved by, rad/s
    later = t >= D + (last + 1) * T
    stream = eq26(np.arange(n) * T)
    assert np.max(np.abs(w[later] - np.interp(t[later] - D, np.arange(n) * T, stream))) < 1e-9
    assert sh.late_setpoints == 0


@pytest.mark.parametrize('held', [0.02, 0.05, 0.15, 0.18])
@pytest.mark.parametrize('profile', ['eq26', 'sine'])
def test_a_start_burst_shorter_than_the_delay_does_not_reach_w(held, profile):
    """The first samples of a stream held up for ``held`` s (< the delay less an
    interval) and delivered together, as DDS does when the subscriber matches the sender
    after it has started: once the punctual samples show the grid, the burst's
    setpoints are due on it, so w is the stream's linear interpolation delayed by the
    delay from the start, as if every sample had come on time (before, w left its rest
    value at the burst's arrival, up to the delay early)."""
    D, n = 0.2, 800
    omega = (Eq26Profile(period=15.0, omega_target=2.0).omega if profile == 'eq26'
             else (lambda t: 0.5 * (1.0 - np.cos(2.0 * t))))           # |w'| <= 1 rad/s^2
    sh = OmegaSetpointShaper(10.0, delay=D)
    grid = np.arange(n) * T
    values = np.array([float(omega(x)) for x in grid])
    for k in range(n):
        sh.command(values[k], max(grid[k], held))
    t = np.arange(0.0, (n - 1) * T + D, T / 4)
    w, _ = sample(sh, t)
    assert np.max(np.abs(w - np.interp(t - D, grid, values, left=0.0))) < 1e-12
    assert sh.late_setpoints == 0


def brute_force_lower_hull(t):
    """Indices i such that (i, t_i) is a vertex of the lower convex hull (O(n^3))."""
    n = len(t)
    out = []
    for b in range(n):
        hidden = any(a < b < c and (b - a) * (t[c] - t[a]) - (t[b] - t[a]) * (c - a) <= 0
                     for a in range(b) for c in range(b + 1, n))
        if not hidden:
            out.append(b)
    return out


@pytest.mark.parametrize('seed', range(5))
def test_the_sliding_lower_envelope_is_the_convex_hull_of_its_window(seed):
    rng = np.random.default_rng(seed)
    size = 25
    env = LowerEnvelope(size)
    times = []
    for k in range(120):
        # (a small uniform part keeps triples of points away from collinear)
        times.append(k * T + rng.uniform(0, 1e-4) + rng.exponential(0.002) * (rng.random() < 0.5))
        env.add(times[-1])
        window = np.array(times[-size:])
        assert env.vertices() == brute_force_lower_hull(window)
        assert env.count == len(window)
        if len(window) >= 2:
            slope, last = env.line()
            # a supporting line: below every point, touching the hull
            line = last + slope * (np.arange(len(window)) - (len(window) - 1))
            assert np.all(window - line >= -1e-12)
            assert np.min(window - line) <= 1e-12


def test_late_arrivals_of_half_the_stream_do_not_move_the_grid():
    a = 0.3
    rng = np.random.default_rng(11)
    sh = OmegaSetpointShaper(10.0, delay=0.1)
    last = 0.0
    for k in range(1500):
        late = rng.exponential(0.02) if rng.random() < 0.5 else 0.0   # one-sided delays
        last = max(last, k * T + late)
        sh.command(a * k * T, last)
    t = np.linspace(3.0, 14.9, 2001)
    w, wd = sample(sh, t)
    assert sh.interval == pytest.approx(T, rel=1e-6)
    assert np.max(np.abs(w - a * (t - 0.1))) < 1e-9


@pytest.mark.parametrize('held', [30, 66, 150])
@pytest.mark.parametrize('jitter', [0.0, 0.0005])
def test_a_stream_whose_first_samples_arrive_together_is_then_its_delayed_interpolation(
        held, jitter):
    """A subscriber that matches the sender after it has started gets the samples sent
    meanwhile all at once (DDS). The burst ends with a punctual sample; from there on
    w is the stream's linear interpolation delayed by the delay, as if the stream had
    just started, and before it w ramps to the burst's last sample."""
    profile = lambda t: 0.5 * (1.0 - np.cos(2.0 * t))  # noqa: E731  |w'| <= 1 rad/s^2
    D, limit, n = 0.2, 10.0, 600
    sh = OmegaSetpointShaper(limit, delay=D)
    rng = np.random.default_rng(held)
    arrivals = np.maximum(np.arange(n), held - 1) * T + rng.exponential(jitter, n) \
        if jitter else np.maximum(np.arange(n), held - 1) * T
    arrivals = np.maximum.accumulate(arrivals)
    for k in range(n):
        sh.command(profile(k * T), arrivals[k])
    t = np.linspace(0.0, (n - 1) * T + D, 20001)
    w, wd = sample(sh, t)
    assert np.all(np.abs(wd) <= limit * (1 + 1e-9))
    # the ramp to the burst's last sample is within the limit: due with it
    after = t >= (held - 1) * T + D + (2 * T if jitter else 0.0)
    expected = np.interp(t[after] - D, np.arange(n) * T, profile(np.arange(n) * T))
    # on the grid of the punctual samples, whose phase is within the latencies
    err = np.max(np.abs(w[after] - expected))
    print(f'{held} held, jitter {jitter}: max |w - interpolation| {err:.2e} rad/s')
    assert err <= 1e-9 + 1.0 * 4 * jitter
    assert sh.late_setpoints == 0
    assert sh.interval == pytest.approx(T, rel=0.05)


def test_a_stall_longer_than_the_delay_coasts_at_the_stream_slope_and_rejoins():
    """A smooth profile through a 150 ms stall, 3x the delay: w goes on along the
    stream's extrapolation (w' linear in t), stays within w''' s^3 of the delayed
    profile, and rejoins it exactly."""
    profile = lambda t: 1.0 - np.cos(t)  # noqa: E731  |w'''| <= 1 rad/s^4
    D = 0.05
    sh = OmegaSetpointShaper(10.0, delay=D)
    last = 0.0
    for k in range(600):
        arrival = k * T if not 300 <= k < 315 else 315 * T + (k - 300) * 1e-5
        last = max(last, arrival)
        sh.command(profile(k * T), last)
    assert sh.late_setpoints > 0
    t = np.linspace(2.0, 5.9, 3901)
    w, wd = sample(sh, t)
    assert np.max(np.abs(w - profile(t - D))) < 1.0 * 0.15 ** 3
    coasting = (t > 299 * T + D) & (t < 315 * T)     # no setpoint due here has come yet
    assert np.max(np.abs(wd[coasting] - np.sin(t[coasting] - D))) < 1.0 * 0.15 ** 2
    back = t > 315 * T + D + 2 * T                  # rejoined the delayed interpolation
    knots = np.arange(600) * T
    expected = np.interp(t[back] - D, knots, profile(knots))
    assert np.max(np.abs(w[back] - expected)) < 1e-9


def test_a_stream_that_stops_mid_ramp_ends_at_its_last_setpoint():
    a = 0.3
    sh = OmegaSetpointShaper(10.0, delay=0.05)
    stream(sh, lambda t: a * t, 300)                 # last setpoint a * 2.99 rad/s
    last = a * 299 * T
    t = np.linspace(3.0, 5.0, 2001)
    w, wd = sample(sh, t)
    # it went on at the stream's slope (the next setpoint might have been late) ...
    assert w.max() == pytest.approx(last + a * sh.max_stall, rel=1e-9)
    assert np.max(np.abs(wd)) <= 10.0 + 1e-12
    # ... and came back to the last setpoint, where it holds
    settled = t > 299 * T + 0.05 + sh.max_stall + 0.05 + 1e-9
    assert np.all(w[settled] == pytest.approx(last, abs=1e-12))


def test_ramp_to_leaves_the_path_at_its_time_and_goes_linearly_at_the_limit():
    a = 0.3
    sh = OmegaSetpointShaper(2.0, delay=0.05)
    stream(sh, lambda t: a * t, 300)                 # stops; w goes on at the slope
    w1 = sh.omega(3.2)                               # mid-extrapolation
    ramp = sh.ramp_to(0.0, 3.2)
    assert ramp.start == 3.2 and ramp.end == pytest.approx(3.2 + w1 / 2.0, rel=1e-12)
    assert sh.setpoint == pytest.approx(a * 2.99)    # not a setpoint: the stream's is kept
    t = np.linspace(3.2, ramp.end, 1001)
    w, wd = sample(sh, t[:-1])
    assert np.max(np.abs(w - (w1 - 2.0 * (t[:-1] - 3.2)))) < 1e-12      # w1 - a (t - t1)
    assert np.all(wd == pytest.approx(-2.0, rel=1e-12))
    assert sh.omega(ramp.end) == 0.0 and sh.omega(ramp.end + 10) == 0.0
    assert sh.omega_dot(ramp.end + 10) == 0.0
    before = np.array([sh.omega(x) for x in np.linspace(2.0, 3.2, 501)])
    assert np.max(np.abs(np.diff(before))) <= 2.0 * 1.2 / 500 * (1 + 1e-9)   # continuous
    # the stream has ended: a setpoint after it starts a new one, from the ramp's w
    w_then = sh.omega(3.3)
    sh.command(1.0, 3.3)
    assert sh.omega(3.3) == w_then
    assert sh.target_reached_at == pytest.approx(3.3 + (1.0 - w_then) / 2.0, rel=1e-12)
    t = np.linspace(3.2, 6.0, 28001)
    w, wd = sample(sh, t)
    assert np.max(np.abs(wd)) <= 2.0 + 1e-12
    assert np.max(np.abs(np.diff(w))) <= 2.0 * (t[1] - t[0]) * (1 + 1e-9)
    assert w[-1] == 1.0


def test_a_10_khz_stream_keeps_its_ramps_small():
    """Each ramp holds its extrapolated path: at most MAX_PATH_SEGMENTS knots of plain
    floats, whatever the stream's rate (a 10 kHz stream once held ~60 kB per ramp)."""
    sh = OmegaSetpointShaper(10.0)
    ramps = [sh.command(0.5 + 0.2 * math.sin(k * 1e-4), k * 1e-4) for k in range(3000)]
    assert sh.interval == pytest.approx(1e-4, rel=1e-6)
    assert max(len(r.times) for r in ramps) <= MAX_PATH_SEGMENTS + 3
    assert any(len(r.times) > 10 for r in ramps)     # the paths are there
    assert all(type(x) is float for r in ramps[-10:] for x in r.times + r.omegas)
    t = np.linspace(0.1, 0.29, 2001)                  # and w still follows the stream
    w, _ = sample(sh, t)
    assert np.max(np.abs(w - (0.5 + 0.2 * np.sin(t - sh.delay)))) < 1e-6


@pytest.mark.parametrize('jump, arrival', [(2.0, 3.2), (0.5, 3.2), (0.9, 3.4)])
def test_a_late_last_setpoint_is_where_w_ends(jump, arrival):
    """A setpoint arriving after its due time rejoins the stream's extrapolation; when
    the limit does not let w reach it within an interval (a jump up or down), w still
    ends at that setpoint if no later one comes (it used to hold the extrapolated
    value: 3.6 rad/s for a last setpoint of 2). The last case is on the extrapolation."""
    limit = 10.0
    sh = OmegaSetpointShaper(limit, delay=0.05)
    stream(sh, lambda t: 0.3 * t, 300)               # stops at 0.897 rad/s, slope 0.3
    sh.command(jump, arrival)                        # late: due at 3.0 + 0.05 s
    assert sh.late_setpoints == 1
    t = np.linspace(arrival, arrival + 3.0, 30001)
    w, wd = sample(sh, t)
    assert np.max(np.abs(wd)) <= limit + 1e-9
    assert np.max(np.abs(np.diff(w))) <= limit * (t[1] - t[0]) * (1 + 1e-9)
    assert sh.omega(arrival + 3.0) == jump and sh.setpoint == jump


def test_a_jump_of_the_envelopes_line_reaches_w_only_as_a_slow_drift(monkeypatch):
    """Every sample 1 ms late but one punctual: the lower envelope's line moves by up
    to 1 ms at once. Taken at once, w' would jump by a x 1 ms / T (10 % of the ramp's
    slope); the grid's filter (GRID_TIME_CONSTANT) spreads it over seconds."""
    import rotrod_core.command.shaping as shaping
    a = 0.3

    def deviation():
        sh = OmegaSetpointShaper(10.0, delay=0.1)
        for k in range(1500):
            late = 0.0 if k == 700 else 0.001
            sh.command(a * k * T, k * T + late)
        t = np.linspace(5.0, 14.5, 9501)
        _, wd = sample(sh, t)
        return np.max(np.abs(wd - a)) / a

    assert deviation() < 0.01
    monkeypatch.setattr(shaping, 'GRID_TIME_CONSTANT', 1e-300)     # the line, unfiltered
    assert deviation() > 0.05


SETPOINTS = st.one_of(st.floats(-100.0, 100.0), st.floats(-100.0, 100.0),
                      st.floats(-1e6, 1e6), st.sampled_from([0.0, TINY, -TINY]))


GAPS = st.one_of(st.sampled_from([0.0, 0.001, 0.01, 0.01, 0.01, 0.02, 0.3, 1.0]),
                 st.floats(0.0, 0.05), st.floats(0.0, 10.0), st.sampled_from([TINY, 1e-300]))


@props(200)
@given(st.floats(1e-3, 1e3), st.floats(1e-3, 1.0), st.floats(-10.0, 10.0),
       st.floats(0.0, 1e6), st.lists(st.tuples(SETPOINTS, GAPS), min_size=1, max_size=60))
def test_the_shaper_gives_a_continuous_w_within_the_acceleration_limit(limit, delay, w0, t0,
                                                                       stream):
    """Any stream of finite setpoints at non-decreasing times: w(t) is finite, continuous
    (Lipschitz with the limit, to rounding of w) and |w'| <= max_angular_acceleration
    (before: 69.0000001 for 69 rad/s^2 at t = 2.6e5 s)."""
    shaper = OmegaSetpointShaper(limit, delay=delay, omega=w0, time=t0)
    t, ramps = t0, []
    for setpoint, gap in stream:
        t += gap
        ramps.append(shaper.command(setpoint, t))
    knots = sorted({k for r in ramps for k in r.times if math.isfinite(k)})
    end = max(knots[-1], t) + 1.0
    grid = np.union1d(np.linspace(t0, end, 2001), [k for k in knots if k <= end])
    w = np.array([shaper.omega(x) for x in grid])
    wd = np.array([shaper.omega_dot(x) for x in grid])
    assert finite(w) and finite(wd)
    scale = max(1.0, float(np.max(np.abs(w))))
    assert np.max(np.abs(wd)) <= limit     # exactly: knots are placed after rounding
    jumps = np.abs(np.diff(w)) - limit * np.diff(grid) * (1 + 1e-9)
    assert np.max(jumps) <= 1e-9 * scale


def test_regression_shaper_extremes():
    # intervals below the time's rounding: equal due times gave ZeroDivisionError, and
    # max_stall / interval = 5e299 path knots an unclear numpy 'Maximum allowed size'
    shaper = OmegaSetpointShaper(1.0, min_interval=1e-300, nominal_interval=1e-300)
    t = 0.0
    for k in range(30):
        shaper.command(1e9 * (k % 2), t)
        t += 1e-300
    assert finite([shaper.omega(t + x) for x in (0.0, 0.1, 1.0, 1e3)])
    # |w| near the float range: w1 - w0 overflowed to inf (then inf x 0 = NaN)
    with pytest.raises(ValueError, match='setpoint must be within'):
        shaper.command(1e308, t)
    with pytest.raises(ValueError, match='max_stall'):
        OmegaSetpointShaper(1e308, max_stall=10.0)
    # at t ~ 2.6e5 s the rounding of the ramp's end made |w'| exceed the limit by 4e-9
    shaper = OmegaSetpointShaper(69.0, delay=1.0, time=262143.0)
    shaper.command(0.0, 262143.0)
    ramp = shaper.command(1.0, 262143.0)
    assert abs(ramp.omega_dot(ramp.start)) <= 69.0
    with pytest.raises(ValueError, match='time'):
        shaper.omega(math.nan)


@props(150)
@given(st.lists(st.tuples(anything(st.floats(-10.0, 10.0)),
                          anything(st.floats(0.0, 10.0))), min_size=1, max_size=12))
def test_bad_setpoints_and_times_are_a_value_error_that_keeps_the_shaper(commands):
    """Bad setpoint (not a finite number), bad time (not finite, or before the previous
    one): ValueError, and the shaped w(t) is unchanged."""
    shaper = OmegaSetpointShaper(2.0)
    probe = np.linspace(0.0, 12.0, 49)
    for setpoint, t in commands:
        before = [shaper.omega(x) for x in probe]
        try:
            shaper.command(setpoint, t)
        except ValueError as exc:
            assert re.search(r'setpoint|time', str(exc)), str(exc)
            assert [shaper.omega(x) for x in probe] == before
        assert finite([shaper.omega(x) for x in probe])


@props(60)
@given(st.sampled_from(['max_angular_acceleration', 'delay', 'nominal_interval', 'max_stall',
                        'min_interval', 'max_interval', 'omega', 'time']),
       st.one_of(EXTREME_FLOATS, WRONG_TYPES))
def test_the_shaper_configuration_is_validated(name, value):
    kwargs = {'max_angular_acceleration': 1.0, name: value}
    try:
        shaper = OmegaSetpointShaper(**kwargs)
    except ValueError as exc:
        assert name in str(exc) or 'interval' in str(exc), str(exc)
        return
    shaper.command(1.0, shaper.last_command_time + 1.0)
    assert finite([shaper.omega(shaper.last_command_time + x) for x in (0.0, 1.0, 1e3)])
