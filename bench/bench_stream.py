"""What a planned spin-up leaves when the simulator node follows it from a stream.

    .venv/bin/python bench/bench_stream.py

The profile publisher streams w at 100 Hz; the simulator's engine follows the stream's
linear interpolation on a grid it fits to the arrival times
(``rotrod_core/command/shaping.py``). This replays arrival times recorded from the
nodes on this machine (``bench/data/stream_arrivals/``: 11 runs of the simulator at
2x real time, setpoint_delay 0.2 s) through the engine, for Eq. 26's spin-up and for
planned spin-ups of Table 1 from 0 to 2 rad/s, and prints the free whirl left about
the static deflection at 2 rad/s (``whirl_residual`` of the engine's state, 5 s after
the stream). Each case three ways: exact timing (arrivals on the 10 ms grid), the
recorded timing with the engine's grid filter (``GRID_TIME_CONSTANT``), and the
recorded timing without it (the grid set by the lower envelope's line at each
arrival, as before the filter). And a plan that rides the simulator's acceleration
bound against one within 0.9 of it (``PLANNED_ACCELERATION_FRACTION``), exact timing.

Deterministic: the same numbers on every run (no timing of this machine is measured).
"""

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT)]

import rotrod_core.command.shaping as shaping  # noqa: E402
from rotrod_core import Eq26Profile, RodParams, whirl_residual  # noqa: E402
from rotrod_core.command.registry import PLAN_LEAD, profile_from_options  # noqa: E402
from rotrod_core.live.engine import EngineConfig, SimulationEngine  # noqa: E402

DATA = ROOT / 'bench' / 'data' / 'stream_arrivals'
P = RodParams()
RATE = 100.0
DELAY = 0.2
TAIL = 5.0
CASES = (
    ('Eq. 26, T = 15 s', None, 0.5),
    ('planned, defaults (max_angular_acceleration 0.5)', {}, 0.5),
    ('planned, config/planned.yaml (robust 0.1)', {'robust': 0.1}, 0.5),
    ('planned, robust 0.1, max_angular_acceleration 2', {'robust': 0.1,
                                                         'max_angular_acceleration': 2.0}, 2.0),
    ('planned, max_angular_acceleration 8', {'max_angular_acceleration': 8.0}, 8.0),
)


def arrivals() -> list:
    """The recorded runs: arrival times, s from the first."""
    return [np.loadtxt(f) * 1e-6 for f in sorted(DATA.glob('run*.csv'))]


def follow(times, omegas, bound: float) -> float:
    """Whirl (m) left after the engine follows ``omegas`` arriving at ``times`` (s)."""
    engine = SimulationEngine(EngineConfig(max_angular_acceleration=bound,
                                           setpoint_delay=DELAY))
    times = np.asarray(times) - times[0] + 0.5
    for t, w in zip(times, omegas):
        engine.advance_to(t)
        engine.command_omega(float(w), at=max(t, engine.time))
    engine.advance_to(times[-1] + TAIL)
    s = engine.state
    return whirl_residual(P, float(omegas[-1]), s.u, s.v, s.du, s.dv)


def stream_of(profile, n: int) -> np.ndarray:
    """Samples k = 0..n-1 of ``profile`` at k / RATE (Eq. 26 held after its spin-up)."""
    t = np.arange(n) / RATE
    if isinstance(profile, Eq26Profile):
        t = np.minimum(t, profile.period)
    return profile.omega(t)


def replays(profile, bound: float, runs: list, filtered: bool) -> list:
    """The whirl after each recorded run long enough for the profile (m)."""
    end = profile.period if isinstance(profile, Eq26Profile) else profile.end_time
    saved = shaping.GRID_TIME_CONSTANT
    if not filtered:
        shaping.GRID_TIME_CONSTANT = 1e-300      # the grid follows the envelope's line
    try:
        return [follow(t, stream_of(profile, len(t)), bound) for t in runs
                if t[-1] >= end + 0.1]
    finally:
        shaping.GRID_TIME_CONSTANT = saved


def um(x) -> str:
    return f'{1e6 * x:.3f}'


def main() -> int:
    runs = arrivals()
    print(f'{len(runs)} recorded runs of arrival times ({DATA.relative_to(ROOT)}); whirl left '
          'at 2 rad/s, um\n')
    print('| profile | duration [s] | planner predicts | exact timing | recorded timing, '
          'grid filter: median (max) | recorded timing, no filter: median (max) | runs |')
    print('|---|---|---|---|---|---|---|')
    for label, options, bound in CASES:
        if options is None:
            profile, duration, predicted = Eq26Profile(), 15.0, '-'
        else:
            profile = profile_from_options('planned', options)
            duration, predicted = profile.duration, um(profile.residual_amplitude)
        n = int(round((profile.end_time if options else 15.0) * RATE)) + 100
        exact = follow(np.arange(n) / RATE, stream_of(profile, n), bound)
        on = replays(profile, bound, runs, True)
        off = replays(profile, bound, runs, False)
        print(f'| {label} | {duration:.3g} | {predicted} | {um(exact)} | '
              f'{um(np.median(on))} ({um(max(on))}) | {um(np.median(off))} ({um(max(off))}) '
              f'| {len(on)} |')
    print(f'\nplanned spin-ups start after {PLAN_LEAD:g} s at rest (PLAN_LEAD).')
    from rotrod_core.command import registry
    print('\nA plan at the simulator\'s bound (0.5 rad/s^2), exact timing:')
    for fraction in (1.0, registry.PLANNED_ACCELERATION_FRACTION):
        saved = registry.PLANNED_ACCELERATION_FRACTION
        registry.PLANNED_ACCELERATION_FRACTION = fraction
        try:
            profile = profile_from_options('planned', {})
        finally:
            registry.PLANNED_ACCELERATION_FRACTION = saved
        n = int(round(profile.end_time * RATE)) + 100
        exact = follow(np.arange(n) / RATE, stream_of(profile, n), 0.5)
        print(f"  planned within {fraction:g} x 0.5 rad/s^2: largest |w'| "
              f'{profile.max_angular_acceleration:.4g} rad/s^2, planner predicts '
              f'{um(profile.residual_amplitude)} um, the engine leaves {um(exact)} um')
    return 0


if __name__ == '__main__':
    sys.exit(main())
