"""The simulator node's ROS parameters: declarations, and conversion to core objects.

Each parameter is declared with a description that states its unit, a range where
one applies, and whether it can change at run time. Values are validated as a whole
(:func:`build_settings`): the physics through :class:`rotrod_core.live.engine.EngineConfig`,
the node's own rates here, so a combination that makes no sense is refused with a
reason and nothing changes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor

from rotrod_core.live.engine import DRIVES, EngineConfig
from rotrod_core.live.scheduling import MAX_CPU_LATENCY
from rotrod_core.model.equations import COUPLINGS, STATE_FIELDS
from rotrod_core.model.params import SECTIONS, RodParams

EXECUTORS = ('single_threaded', 'events')
MIN_ESTIMATE_SAMPLES = 20
"""Fewest publications an estimate window may hold."""


@dataclass(frozen=True)
class Spec:
    """One parameter: name, default, description (with unit), numeric range."""

    name: str
    default: Any
    description: str
    low: float | None = None
    high: float | None = None
    choices: tuple = ()
    read_only: bool = False
    integer: bool = False


_ROD = RodParams()
_ENGINE = EngineConfig()

ROD_SPECS = (
    Spec('mass', _ROD.mass, 'tip mass m, kg (> 0)', 0.0, 1e4),
    Spec('rod_length', _ROD.rod_length, 'rod length l, m (> 0)', 0.0, 100.0),
    Spec('rod_diameter', _ROD.rod_diameter, 'rod diameter d of a circular section, m (> 0)',
         0.0, 10.0),
    Spec('youngs_modulus', _ROD.youngs_modulus, "Young's modulus E, Pa (> 0)", 0.0, 1e13),
    Spec('eccentricity', _ROD.eccentricity,
         'radius r0 of the rod root from the rotation axis, m', 0.0, 100.0),
    Spec('hub_inertia', _ROD.hub_inertia,
         'rotary inertia J of the hub (disk) about the axis, kg m^2 (> 0 for the exact '
         'coupling)', 0.0, 1e9),
    Spec('damping_ratio', _ROD.damping_ratio,
         'modal damping ratio zeta of the bending (rotating damping), 1', 0.0, 10.0),
    Spec('section', _ROD.section, 'rod cross-section: circular | rectangular',
         choices=SECTIONS),
    Spec('section_width', 0.0,
         'rectangular section size b along e1 (radial), m; 0 = unused (circular)', 0.0, 10.0),
    Spec('section_thickness', 0.0,
         'rectangular section size h along e2 (tangential), m; 0 = unused (circular)',
         0.0, 10.0),
    Spec('gravity', _ROD.gravity,
         'gravity along the rod, m/s^2: > 0 the rod stands up with the mass on top (its '
         'weight compresses and softens it), < 0 it hangs (tension stiffens it), 0 = the '
         'paper; compression at or past buckling is refused', -1e3, 1e3),
    Spec('rod_density', _ROD.rod_density,
         "density of the rod's material, kg/m^3 (one-mode Rayleigh-Ritz: modal mass "
         'm + 33/140 rho A l); 0 = massless, the paper', 0.0, 1e5),
)

ENGINE_SPECS = (
    Spec('drive', _ENGINE.drive,
         'active input: velocity (cmd/omega setpoints, rad/s) | torque (cmd/torque, N m; '
         'the rotation is free)', choices=DRIVES),
    Spec('coupling', _ENGINE.coupling,
         'hub torque equation: exact (Lagrangian, conserves angular momentum) | paper '
         '(Eq. 23 + J w\')', choices=COUPLINGS),
    Spec('physics_rate', _ENGINE.physics_rate,
         'fixed integration rate, Hz (step 1/physics_rate)', 1.0, 1e6),
    Spec('max_angular_acceleration', _ENGINE.max_angular_acceleration,
         "bound on |w'| when following cmd/omega, rad/s^2 (> 0; bends the rod back by "
         "w' r0 m/k2)", 0.0, 1e6),
    Spec('max_omega', _ENGINE.max_omega,
         'largest |w| accepted on cmd/omega, and reached in torque drive before the '
         'simulation halts, rad/s (> 0)', 0.0, 1e6),
    Spec('max_torque', _ENGINE.max_torque, 'largest |Q| accepted on cmd/torque, N m (> 0)',
         0.0, 1e9),
    Spec('deflection_limit', _ENGINE.deflection_limit,
         'the critical deflection (the paper\'s 3 mm criterion), m (> 0): while the tip '
         'deflection sqrt(u^2 + v^2) is beyond it, diagnostics are ERROR ("beyond the '
         'critical deflection", with the first crossing and the peak); the simulation '
         'goes on and accepts commands', 0.0, 100.0),
    Spec('warn_fraction', _ENGINE.warn_fraction,
         'fraction of deflection_limit above which diagnostics WARN, 1', 0.0, 1.0),
    Spec('max_deflection_ratio', _ENGINE.max_deflection_ratio,
         'model-validity bound on the tip deflection over the rod length, |r| / l, 1: '
         'beyond it the small-deflection model means nothing (its foreshortening '
         '0.6 (|r|/l)^2 is 0.6 % at 0.1) and the simulation halts at the last good state '
         'until ~/reset; 0 = no bound', 0.0, 1.0),
    Spec('critical_margin', _ENGINE.critical_margin,
         'relative distance to a critical speed within which diagnostics WARN, 1', 0.0, 1.0),
    Spec('setpoint_delay', _ENGINE.setpoint_delay,
         'lag of w behind the cmd/omega stream, s (at least two stream intervals); '
         'absorbs delivery jitter up to the lag minus one interval (raise it at a high '
         'real_time_factor)', 0.0, 10.0),
    Spec('command_timeout', _ENGINE.command_timeout,
         'simulated seconds without an accepted command on the active drive\'s topic '
         'after which the hub is stopped: velocity drive ramps w to 0 at '
         'max_angular_acceleration, torque drive sets the torque to 0 (coast); '
         'diagnostics WARN until a command comes. 0 = off (w holds the last setpoint, '
         'the torque stays); else >= 2 x setpoint_delay, s', 0.0, 86400.0),
    *(Spec(f'initial.{name}', 0.0,
           f'initial {name} ({unit}) at start and after ~/reset')
      for name, unit in zip(STATE_FIELDS, ('m', 'm', 'm/s', 'm/s', 'rad', 'rad/s'))),
)

NODE_SPECS = (
    Spec('publish_rate', 100.0,
         'rate of joint_states, tip/*, frequencies (and /clock), Hz of simulated time '
         '(<= physics_rate)', 0.1, 1e4),
    Spec('real_time_factor', 1.0,
         'simulated seconds per wall second; 0 = as fast as possible. /clock is published '
         'whenever it is not 1', 0.0, 1e4),
    Spec('markers', True, 'publish markers (visualization_msgs/MarkerArray) for RViz'),
    Spec('marker_rate', 20.0, 'rate of markers, Hz of simulated time, and at most twice '
         'that in wall time (faster than real time)', 0.1, 1e3),
    Spec('marker_trail_length', 200, 'points kept in the tip trail marker', 0, 100000,
         integer=True),
    Spec('marker_deflection_scale', 20.0,
         'drawn deflection / true deflection in the markers (millimetres are invisible '
         'at true size), 1', 1.0, 1e5),
    Spec('disk_radius', 0.15, 'radius of the hub disk as drawn, m', 0.0, 100.0),
    Spec('frame_prefix', '', 'prefix of the frame ids world and rotor (e.g. "rod1/")',
         read_only=True),
    Spec('diagnostics_rate', 1.0, 'rate of /diagnostics (also sent on a change of level), '
         'Hz of wall time', 0.01, 100.0),
    Spec('deflection_noise', 0.0,
         'standard deviation of Gaussian noise added to the published tip/deflection '
         '(u and v each; a sensor), m; never to the state; 0 = none', 0.0, 1.0),
    Spec('noise_seed', 0, 'seed of the deflection noise: the same seed, the same noise '
         '(a reproducible run)', 0, 2**31 - 1, integer=True),
    Spec('estimate_window', 1.0,
         'window of the whirl-frequency estimate from the published tip motion '
         '(frequencies/estimate), s of simulated time; 0 = no estimate', 0.0, 60.0),
    Spec('estimate_rate', 10.0,
         'rate of frequencies/estimate, Hz of simulated time (<= publish_rate)', 0.01, 1e3),
    Spec('executor', 'single_threaded',
         'rclpy executor for commands, services and parameters: single_threaded | events '
         '(rclpy\'s experimental EventsExecutor: measured worse, see '
         'bench/bench_realtime.py); physics runs in its own thread',
         choices=EXECUTORS, read_only=True),
    Spec('realtime_priority', 50,
         'SCHED_FIFO priority of the physics thread while paced (real_time_factor > 0), '
         '1..99; 0 = ordinary scheduling. Needs root or CAP_SYS_NICE; refused with a '
         'warning otherwise', 0, 99, integer=True, read_only=True),
    Spec('cpu_dma_latency', -1,
         'machine-wide, opt-in (config/realtime.yaml): while paced (real_time_factor > 0), '
         'the CPU wake-up latency the node asks the kernel for (PM QoS, '
         '/dev/cpu_dma_latency, as cyclictest does), us: every idle CPU of the machine '
         'stays out of sleep states slower to leave. 0 keeps them polling (a sleeping '
         'thread wakes at once; idle cores stay busy, costing power); -1 (default) = '
         'leave the machine as it is. Needs root; refused with a warning otherwise',
         -1, MAX_CPU_LATENCY, integer=True, read_only=True),
)

ALL_SPECS = ROD_SPECS + ENGINE_SPECS + NODE_SPECS
SPECS_BY_NAME = {s.name: s for s in ALL_SPECS}


@dataclass(frozen=True)
class NodeSettings:
    """Settings of the node itself (not of the physics); see NODE_SPECS."""

    publish_rate: float = 100.0
    real_time_factor: float = 1.0
    markers: bool = True
    marker_rate: float = 20.0
    marker_trail_length: int = 200
    marker_deflection_scale: float = 20.0
    disk_radius: float = 0.15
    frame_prefix: str = ''
    diagnostics_rate: float = 1.0
    deflection_noise: float = 0.0
    noise_seed: int = 0
    estimate_window: float = 1.0
    estimate_rate: float = 10.0
    executor: str = 'single_threaded'
    realtime_priority: int = 50
    cpu_dma_latency: int = -1

    @property
    def publish_period(self) -> float:
        """Simulated time between publications, s."""
        return 1.0 / self.publish_rate

    @property
    def publishes_clock(self) -> bool:
        """Whether /clock is published (real_time_factor != 1)."""
        return self.real_time_factor != 1.0


def descriptor(spec: Spec) -> ParameterDescriptor:
    """The ROS parameter descriptor of ``spec``: description, range or choices."""
    d = ParameterDescriptor(name=spec.name, description=spec.description,
                            read_only=spec.read_only)
    if spec.choices:
        d.additional_constraints = 'one of: ' + ', '.join(spec.choices)
    elif spec.low is not None and spec.integer:
        d.integer_range = [IntegerRange(from_value=int(spec.low), to_value=int(spec.high),
                                        step=0)]
    elif spec.low is not None:
        d.floating_point_range = [FloatingPointRange(from_value=float(spec.low),
                                                     to_value=float(spec.high), step=0.0)]
    return d


def check_value(spec: Spec, value: Any) -> None:
    """Raise ValueError if ``value`` is not allowed for ``spec`` (type, range, choices)."""
    if spec.choices:
        if value not in spec.choices:
            raise ValueError(f'{spec.name} must be one of {spec.choices}, got {value!r}')
        return
    if isinstance(spec.default, bool) or isinstance(spec.default, str):
        if type(value) is not type(spec.default):
            raise ValueError(f'{spec.name} must be a {type(spec.default).__name__}, '
                             f'got {value!r}')
        return
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise ValueError(f'{spec.name} must be a number, got {value!r}')
    if not math.isfinite(value):
        raise ValueError(f'{spec.name} must be finite, got {value!r}')
    if spec.low is not None and not spec.low <= value <= spec.high:
        raise ValueError(f'{spec.name} must be in [{spec.low:g}, {spec.high:g}], got {value!r}')


def rod_params(values: dict) -> RodParams:
    """The RodParams of the ROD_SPECS values (section sizes 0 = unused); ValueError."""
    rod = {s.name: values[s.name] for s in ROD_SPECS}
    for name in ('section_width', 'section_thickness'):
        if rod[name] == 0.0:
            rod[name] = None
    return RodParams(**rod)


def build_settings(values: dict) -> tuple[EngineConfig, NodeSettings]:
    """Validate a complete set of parameter values; return the engine config and node settings.

    Raises ValueError with the reason for the first problem found.
    """
    for name, value in values.items():
        if name in SPECS_BY_NAME:
            check_value(SPECS_BY_NAME[name], value)
    params = rod_params(values)
    initial = {name: values[f'initial.{name}'] for name in STATE_FIELDS
               if values[f'initial.{name}'] != 0.0}
    engine = EngineConfig(params=params, initial=initial,
                          **{s.name: values[s.name] for s in ENGINE_SPECS
                             if not s.name.startswith('initial.')})
    node = NodeSettings(**{f.name: values[f.name] for f in fields(NodeSettings)})
    if node.publish_rate > engine.physics_rate:
        raise ValueError(f'publish_rate {node.publish_rate:g} Hz exceeds physics_rate '
                         f'{engine.physics_rate:g} Hz: there would be nothing new to publish')
    if node.estimate_window:
        if node.estimate_window < MIN_ESTIMATE_SAMPLES * node.publish_period:
            raise ValueError(f'estimate_window {node.estimate_window:g} s holds fewer than '
                             f'{MIN_ESTIMATE_SAMPLES} publications at publish_rate '
                             f'{node.publish_rate:g} Hz: too few samples to estimate from')
        if node.estimate_rate > node.publish_rate:
            raise ValueError(f'estimate_rate {node.estimate_rate:g} Hz exceeds publish_rate '
                             f'{node.publish_rate:g} Hz: estimates are made on publications')
    return engine, node


def defaults() -> dict:
    """Every parameter's default value by name."""
    return {s.name: s.default for s in ALL_SPECS}
