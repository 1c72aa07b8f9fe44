"""A world of rods: one batch, each rod as if alone, a halt disturbs nobody.

The reference for a rod in a world is the same rod in a world of its own (Python floats
through the kernel, step by step). Rods of a torque drive are stepped by the same
kernel on arrays: the same IEEE arithmetic, so their states agree bit for bit. Rods of
a velocity drive take the kernel's step written as its affine map (the kernel gives the
map): hub angle and speed agree bit for bit, the deflection state to rounding. The
physics itself is held to closed forms and invariants by test_engine.py and
test_stepper.py, and through the simulator by test/acceptance/test_world.py.
"""

import math

import numpy as np
import pytest

from rotrod_core import RodParams
from rotrod_core.command.trajectory import TrajectoryPoint
from rotrod_core.live.engine import EngineConfig, SimulationEngine
from rotrod_core.live.execution import TrajectoryGoal
from rotrod_core.live.world import World

RODS = {
    'table1': EngineConfig(),
    'heavy': EngineConfig(params=RodParams(mass=0.4, rod_density=7850.0, gravity=9.81)),
    'damped': EngineConfig(params=RodParams(damping_ratio=0.02, eccentricity=0.05)),
    'rect': EngineConfig(params=RodParams(section='rectangular', section_width=0.003,
                                          section_thickness=0.0035)),
    'torque': EngineConfig(drive='torque', initial={'omega': 1.0, 'u': 1e-3}),
    'paper': EngineConfig(drive='torque', coupling='paper', initial={'omega': 0.5}),
    'timeout': EngineConfig(command_timeout=0.5),
}


def command(name, engine, k):
    """The commands of rod ``name`` at the k-th 10 ms of simulated time."""
    t = engine.time
    if name == 'torque':
        engine.command_torque(0.02 * math.sin(0.3 * k), at=t)
    elif name == 'paper':
        engine.command_torque(0.01, at=t)
    elif name == 'timeout':
        if k < 50:
            engine.command_omega(1.0, at=t)
    elif name == 'heavy' and k == 30:
        engine.command_trajectory(TrajectoryGoal((TrajectoryPoint(2.5, velocity=0.8,
                                                                  acceleration=0.0),)))
    elif k % 7 == 0 and name != 'heavy':
        engine.command_omega(0.8 + 0.1 * math.sin(k), at=t)


def run_alone(name, config, periods):
    engine = SimulationEngine(config)
    states = []
    for k in range(periods):
        command(name, engine, k)
        engine.advance(10)
        states.append(engine.state)
    return states


def run_together(periods):
    world = World(1000.0)
    engines = {name: SimulationEngine(config, world=world, name=name)
               for name, config in RODS.items()}
    states: dict = {name: [] for name in RODS}
    for k in range(periods):
        for name, engine in engines.items():
            command(name, engine, k)
        assert world.advance(10) == 10
        for name, engine in engines.items():
            states[name].append(engine.state)
    return world, engines, states


def same_motion(together, alone, name):
    """States as if alone: theta, w (and a torque drive's everything) bit for bit; a
    velocity drive's u, v, u', v' to rounding: 1e-12 of their largest magnitude."""
    a, b = np.array(together), np.array(alone)
    assert np.array_equal(a[:, 4:], b[:, 4:]), name
    if RODS.get(name, EngineConfig()).drive == 'torque':
        assert np.array_equal(a, b), name
    scale = np.max(np.abs(b[:, :4]), axis=0)
    assert np.all(np.abs(a[:, :4] - b[:, :4]) <= 1e-12 * scale), name


def test_each_rod_in_a_world_moves_as_if_alone_to_rounding():
    _, engines, together = run_together(300)
    for name, config in RODS.items():
        same_motion(together[name], run_alone(name, config, 300), name)
    assert engines['timeout'].timed_out_at is not None          # its timeout ran out
    assert engines['heavy'].trajectory_outcomes[-1].code == 'SUCCESSFUL'


def test_a_world_replays_bit_for_bit():
    assert run_together(120)[2] == run_together(120)[2]


def test_a_rod_that_halts_disturbs_nobody():
    world = World(1000.0)
    calm = SimulationEngine(EngineConfig(), world=world, name='calm')
    wild = SimulationEngine(EngineConfig(params=RodParams(eccentricity=10.0),
                                         max_angular_acceleration=0.4), world=world,
                            name='wild')          # 1 rad/s: 69 mm, past 0.1 l
    calm.command_omega(1.0)
    wild.command_omega(1.0)
    assert world.advance(6000) == 6000
    assert wild.halted and 'validity bound' in wild.halted and calm.halted is None
    alone = SimulationEngine(EngineConfig())
    alone.command_omega(1.0)
    alone.advance(6000)
    same_motion([calm.state], [alone.state], 'calm')
    assert calm.time == alone.time
    frozen = wild.state
    world.advance(100)
    assert wild.state == frozen                                # at its last good state
    assert math.hypot(frozen.u, frozen.v) <= wild.config.max_deflection
    wild.reset()                                               # back in the batch
    wild.command_omega(0.5)
    world.advance(10)
    assert wild.halted is None and wild.state.omega > 0.0


def test_when_every_rod_halts_the_clock_stops_at_the_last_halt():
    world = World(1000.0)
    rod = SimulationEngine(EngineConfig(params=RodParams(eccentricity=10.0),
                                        max_angular_acceleration=0.4), world=world)
    rod.command_omega(1.0)
    taken = world.advance(10_000)
    assert 0 < taken < 10_000 and world.halted
    assert world.time == pytest.approx(taken * world.dt)
    assert world.advance(10) == 0


def test_rods_come_and_go_between_steps_and_need_the_world_s_rate():
    world = World(1000.0)
    a = SimulationEngine(EngineConfig(), world=world, name='a')
    a.command_omega(1.0)
    world.advance(500)
    b = SimulationEngine(EngineConfig(initial={'omega': 0.5}), world=world, name='b')
    world.advance(500)
    assert b.state.omega == 0.5 and a.state.omega > 0
    assert world.remove('a') is a
    world.advance(10)
    assert list(world.engines) == ['b']
    with pytest.raises(ValueError, match='already in the world'):
        SimulationEngine(EngineConfig(), world=world, name='b')
    with pytest.raises(ValueError, match="is not the world's 1000 Hz"):
        SimulationEngine(EngineConfig(physics_rate=2000.0), world=world, name='c')
    with pytest.raises(RuntimeError, match='step the world'):
        SimulationEngine(EngineConfig(), world=world, name='d').step()


def count_kernel_calls(monkeypatch) -> list:
    """The shape of every call of the equations from now on (its arguments broadcast)."""
    import rotrod_core.live.world as world_module
    calls = []
    original = world_module.model.deflection_accelerations

    def counted(co, *args):
        calls.append(np.broadcast(*args).shape)
        return original(co, *args)
    monkeypatch.setattr(world_module.model, 'deflection_accelerations', counted)
    return calls


def test_a_many_rod_block_is_one_pass_of_the_kernel_not_a_loop_per_rod(monkeypatch):
    """100 rods of a velocity drive: a block of 50 steps is 4 calls of the equations
    (RK4's stages) over every step and rod at once; of a torque drive, 4 per step over
    every rod."""
    calls = count_kernel_calls(monkeypatch)
    world = World(1000.0)
    for i in range(100):
        SimulationEngine(EngineConfig(), world=world, name=f'rod{i}').command_omega(1.0)
    assert world.advance(50) == 50
    assert len(calls) == 4 and set(calls) == {(5, 50, 100)}     # x = 0 and 4 unit states
    assert np.isfinite([e.state.u for e in world]).all()
    calls.clear()
    world = World(1000.0)
    for i in range(100):
        SimulationEngine(EngineConfig(drive='torque'), world=world,
                         name=f'rod{i}').command_torque(0.01)
    assert world.advance(50) == 50
    assert len(calls) == 4 * 50 and set(calls) == {(100,)}


def test_a_hold_reuses_its_maps_and_moves_as_the_steps_taken_one_by_one(monkeypatch):
    """At a constant w the maps are computed once; the motion is still the kernel's."""
    calls = count_kernel_calls(monkeypatch)
    world = World(1000.0)
    rods = [SimulationEngine(EngineConfig(initial={'omega': 1.5, 'u': 1e-4}), world=world,
                             name=f'rod{i}') for i in range(3)]
    for rod in rods:
        rod.command_omega(1.5)
    for _ in range(20):
        world.advance(10)
    assert len(calls) == 4                                     # one block's maps
    alone = SimulationEngine(EngineConfig(initial={'omega': 1.5, 'u': 1e-4}))
    alone.command_omega(1.5)
    alone.advance(200)
    same_motion([rods[2].state], [alone.state], 'hold')


@pytest.mark.parametrize('block', [3, 10])
def test_a_trajectory_ends_at_its_last_point_s_speed_exactly_whatever_its_start(block):
    """The step that ends at the last point's time (to rounding of the clock) ends at
    its speed: w then holds exactly the goal's final speed. A goal with positions (its
    path checked at every step), started at many step instants: before, one start in
    six ended 1e-14 beside it."""
    points = (TrajectoryPoint(1.5, position=0.6, velocity=0.8, acceleration=0.2),
              TrajectoryPoint(3.0, position=2.0, velocity=1.0, acceleration=0.0))
    for offset in range(0, 400, 19):
        world = World(1000.0)
        rod = SimulationEngine(EngineConfig(max_angular_acceleration=2.0), world=world)
        world.advance(offset)
        rod.command_trajectory(TrajectoryGoal(points))
        while world.time < offset / 1000 + 3.5:
            world.advance(block)
        assert rod.trajectory_outcomes[-1].code == 'SUCCESSFUL', offset
        assert rod.state.omega == 1.0, offset


def test_the_critical_deflection_watch_counts_the_same_crossings_whatever_the_block():
    """Rods that cross the 3 mm criterion once and stay beyond, or oscillate about it
    (25 crossings), stepped a step at a time or in blocks of 10 and 64 (whose steps are
    then all beyond it, or all below): the same crossings, the same first crossing and
    "beyond since", the same peak (times and deflections to rounding)."""
    def watched(block):
        world = World(1000.0)
        engines = [SimulationEngine(EngineConfig(params=RodParams(damping_ratio=0.01)),
                                    world=world, name=f'rod{i}') for i in range(6)]
        for i, engine in enumerate(engines):
            engine.command_omega(2.0 + 0.1 * i)
        done = 0
        while done < 20000:
            done += world.advance(min(block, 20000 - done))
        return [(e.limit_crossings, e.first_crossed_at, e.beyond_limit_since,
                 e.peak_deflection, e.peak_deflection_at) for e in engines]

    one = watched(1)
    counts = [w[0] for w in one]
    assert max(counts) >= 20 and counts.count(1) >= 3       # oscillating; once and beyond
    assert sum(w[2] is not None for w in one) >= 4          # still beyond at the end
    for block in (10, 64):
        for a, b in zip(watched(block), one):
            assert a[0] == b[0] and (a[2] is None) == (b[2] is None)
            assert a[1] == pytest.approx(b[1], abs=1e-9)
            assert a[3] == pytest.approx(b[3], rel=1e-9)
            assert a[4] == pytest.approx(b[4], abs=1e-9)
            if b[2] is not None:
                assert a[2] == pytest.approx(b[2], abs=1e-9)
