"""The simulator node's ROS parameters, and their conversion to core objects.

Declared through the package's one mechanism (:mod:`rotrod_ros.parameter_specs`):
each with a description, its unit, a range or choices, and read-only where it cannot
change at run time. The rod's (:data:`ROD_SPECS`, also the rig monitor's) are made
from :data:`rotrod_core.model.params.FIELDS`, where the rod's units, descriptions and
ranges are defined once. Values are validated as a whole (:func:`build_settings`):
the physics through :class:`rotrod_core.live.engine.EngineConfig`, the node's own
rates here, so a combination that makes no sense is refused with a reason and
nothing changes. :class:`ParameterValues` keeps the values in use and checks a change
before it is taken (the node's on-set callback checks, its post-set callback applies).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field, fields
from typing import Any

from rotrod_core.live.engine import DRIVES, EngineConfig
from rotrod_core.live.loop import MAX_PUBLICATION_SPIN
from rotrod_core.live.publication import PublicationSettings
from rotrod_core.live.scheduling import MAX_CPU_LATENCY, MAX_PRIORITY
from rotrod_core.model.equations import COUPLINGS, STATE_FIELDS
from rotrod_core.model.params import FIELDS, FieldInfo, RodParams
from rotrod_core.sensors.noise import NOISE_TYPES, NoiseParams
from rotrod_core.sensors.rig import SensorConfig

from .parameter_specs import Spec, check_value, descriptor

__all__ = ['ALL_SPECS', 'ENGINE_SPECS', 'NODE_SPECS', 'NodeSettings', 'ParameterValues',
           'ROD_SPECS', 'SPECS_BY_NAME', 'Spec', 'build_settings', 'check_value', 'defaults',
           'descriptor', 'rod_params']


def rod_spec(info: FieldInfo) -> Spec:
    """The parameter of a RodParams field: its unit, description and range.

    A field unused by default (a rectangular section's sizes) is 0 when unused.
    """
    text = info.description + (' (> 0)' if info.sign == 'positive' else '')
    if info.default is None:
        text += f'; 0 = unused (not {info.section})'
    default = 0.0 if info.default is None else info.default
    return Spec(info.name, default, text, info.unit, info.low, info.high,
                choices=info.choices)


ROD_SPECS = tuple(rod_spec(info) for info in FIELDS)
_OPTIONAL_ROD_FIELDS = tuple(info.name for info in FIELDS if info.default is None)


AUTO_WAIT = -1
"""``wait_for_subscribers`` by default: wait for one subscription on each sample topic
when started as fast as possible (see :meth:`NodeSettings.subscriber_wait`)."""
AUTO_WAIT_TIMEOUT = 10.0
"""Longest wait of :data:`AUTO_WAIT` for the subscriptions, wall s; then the run starts
(with a warning naming the topics without one)."""


@dataclass(frozen=True)
class NodeSettings(PublicationSettings):
    """Settings of the node (not of the physics); NODE_SPECS.

    The loop's, the publication's (the class a bag is written with,
    :mod:`rotrod_core.live.publication`) and the node's own.
    """

    deflection_noise: float = 0.0
    noise_seed: int = 0
    wait_for_subscribers: int = -1
    rods: int = 1
    max_rods: int = 128
    max_steps_per_request: int = 1_000_000_000
    sensors: SensorConfig = field(default_factory=SensorConfig)
    """The rig sensors' (tip/imu, hub/encoder, rod/strain): SENSOR_SPECS."""

    def subscriber_wait(self) -> tuple[int, float]:
        """Subscriptions wanted on each sample topic before simulated time starts.

        Returns (how many, the longest wait for them in wall seconds: inf = as long as
        it takes).
        ``wait_for_subscribers`` -1 (:data:`AUTO_WAIT`): started as fast as possible, one
        each for at most :data:`AUTO_WAIT_TIMEOUT` s (a recorder started first gets
        every sample from t = 0); paced, none. N > 0: N each, however long. 0: none.
        """
        wanted = self.wait_for_subscribers
        if wanted == AUTO_WAIT:
            return (1, AUTO_WAIT_TIMEOUT) if self.real_time_factor == 0 else (0, 0.0)
        return wanted, math.inf


_ENGINE = EngineConfig()
_NODE = NodeSettings()

ENGINE_SPECS = (
    Spec('drive', _ENGINE.drive,
         'active input: velocity (cmd/omega setpoints, rad/s; an ideal drive imposes w) | '
         'torque (cmd/torque, N m; the rotation is free) | servo (cmd/omega setpoints and '
         'trajectories followed by a PI speed loop with the torque limit max_torque, the '
         "rod's reaction disturbing it)", choices=DRIVES),
    Spec('coupling', _ENGINE.coupling,
         'hub torque equation: exact (Lagrangian, conserves angular momentum) | paper '
         '(Eq. 23 + J w\')', choices=COUPLINGS),
    Spec('physics_rate', _ENGINE.physics_rate,
         'fixed integration rate (step 1/physics_rate)', 'Hz', 1.0, 1e6),
    Spec('max_angular_acceleration', _ENGINE.max_angular_acceleration,
         "bound on |w'| when following cmd/omega (> 0; bends the rod back by "
         "w' r0 m/k2)", 'rad/s^2', 0.0, 1e6),
    Spec('max_omega', _ENGINE.max_omega,
         'largest |w| accepted on cmd/omega, and reached in torque drive before the '
         'simulation halts (> 0)', 'rad/s', 0.0, 1e6),
    Spec('max_torque', _ENGINE.max_torque, 'largest |Q| accepted on cmd/torque, and the '
         "servo drive's torque limit (> 0)", 'N m', 0.0, 1e9),
    Spec('servo_bandwidth', _ENGINE.servo_bandwidth, "drive servo: the PI speed loop's "
         'closed-loop natural frequency for a rigid hub (gains Kp = 2 servo_damping w_n J, '
         'Ki = w_n^2 J, w_n = 2 pi servo_bandwidth, J the rigid inertia of hub, rod and '
         'mass); > 0 and at most physics_rate / 2 (docs/sensors.md#drive)', 'Hz', 0.0, 1e6),
    Spec('servo_damping', _ENGINE.servo_damping, "drive servo: the closed loop's damping "
         'ratio (> 0; 1: 13.5 % overshoot of a step)', '1', 0.0, 100.0),
    Spec('bearing_viscous_friction', _ENGINE.bearing_viscous_friction, 'the hub bearing\'s '
         'viscous friction torque per angular velocity, on the hub in torque and servo '
         'drive (the velocity drive\'s torque overcomes it)', 'N m s/rad', 0.0, 1e6),
    Spec('bearing_coulomb_friction', _ENGINE.bearing_coulomb_friction, "the hub bearing's "
         'Coulomb friction torque (with stiction at rest), on the hub in torque and servo '
         "drive (the velocity drive's torque overcomes it)", 'N m', 0.0, 1e6),
    Spec('deflection_limit', _ENGINE.deflection_limit,
         'the critical deflection (the paper\'s 3 mm criterion, > 0): while the tip '
         'deflection sqrt(u^2 + v^2) is beyond it, diagnostics are ERROR ("beyond the '
         'critical deflection", with the first crossing and the peak); the simulation '
         'goes on and accepts commands', 'm', 0.0, 100.0),
    Spec('warn_fraction', _ENGINE.warn_fraction,
         'fraction of deflection_limit above which diagnostics WARN', '1', 0.0, 1.0),
    Spec('max_deflection_ratio', _ENGINE.max_deflection_ratio,
         'model-validity bound on the tip deflection over the rod length, |r| / l: '
         'beyond it the small-deflection model means nothing (its foreshortening '
         '0.6 (|r|/l)^2 is 0.6 % at 0.1) and the simulation halts at the last good state '
         'until ~/reset; 0 = no bound', '1', 0.0, 1.0),
    Spec('critical_margin', _ENGINE.critical_margin,
         'relative distance to a critical speed within which diagnostics WARN', '1',
         0.0, 1.0),
    Spec('setpoint_delay', _ENGINE.setpoint_delay,
         'lag of w behind the cmd/omega stream (at least two stream intervals); '
         'absorbs delivery jitter up to the lag minus one interval (raise it at a high '
         'real_time_factor)', 's', 0.0, 10.0),
    Spec('command_timeout', _ENGINE.command_timeout,
         'simulated seconds without an accepted command on the active drive\'s topic '
         'after which the hub is stopped: velocity drive ramps w to 0 at '
         'max_angular_acceleration, torque drive sets the torque to 0 (coast); '
         'diagnostics WARN until a command comes. 0 = off (w holds the last setpoint, '
         'the torque stays); else >= 2 x setpoint_delay', 's', 0.0, 86400.0),
    *(Spec(f'initial.{name}', 0.0, f'initial {name} at start and after ~/reset', unit,
           -bound, bound)
      for name, unit, bound in zip(STATE_FIELDS, ('m', 'm', 'm/s', 'm/s', 'rad', 'rad/s'),
                                   (100.0, 100.0, 1e6, 1e6, 1e9, 1e6))),
)

NODE_SPECS = (
    Spec('publish_rate', _NODE.publish_rate,
         'rate of joint_states, tip/*, frequencies (and /clock), of simulated time '
         '(<= physics_rate)', 'Hz', 0.1, 1e4),
    Spec('real_time_factor', _NODE.real_time_factor,
         'simulated seconds per wall second; 0 = as fast as possible. /clock is published '
         'whenever it is not 1', '1', 0.0, 1e4),
    Spec('markers', _NODE.markers, 'publish markers (visualization_msgs/MarkerArray) for '
         'RViz'),
    Spec('marker_rate', _NODE.marker_rate, 'rate of markers, of simulated time, and at most '
         'twice that in wall time (faster than real time)', 'Hz', 0.1, 1e3),
    Spec('marker_trail_length', _NODE.marker_trail_length,
         'points kept in the tip trail marker', '', 0, 100000),
    Spec('marker_deflection_scale', _NODE.marker_deflection_scale,
         'drawn deflection / true deflection in the markers (millimetres are invisible '
         'at true size)', '1', 1.0, 1e5),
    Spec('disk_radius', _NODE.disk_radius, 'radius of the hub disk as drawn', 'm',
         0.0, 100.0),
    Spec('frame_prefix', _NODE.frame_prefix, 'prefix of the frame ids world and rotor '
         '(e.g. "rod1/")', read_only=True),
    Spec('diagnostics_rate', _NODE.diagnostics_rate, 'rate of /diagnostics (also sent on a '
         'change of level), of wall time', 'Hz', 0.01, 100.0),
    Spec('deflection_noise', _NODE.deflection_noise,
         'standard deviation of Gaussian noise added to the published tip/deflection '
         '(u and v each; a sensor); never to the state; 0 = none', 'm', 0.0, 1.0),
    Spec('noise_seed', _NODE.noise_seed, 'seed of the deflection noise: the same seed, the '
         'same noise (a reproducible run)', '', 0, 2**31 - 1),
    Spec('estimate_window', _NODE.estimate_window,
         'window of the whirl-frequency estimate from the published tip motion '
         '(frequencies/estimate), of simulated time; 0 = no estimate', 's', 0.0, 60.0),
    Spec('estimate_rate', _NODE.estimate_rate,
         'rate of frequencies/estimate, of simulated time (<= publish_rate)', 'Hz',
         0.01, 1e3),
    Spec('wait_for_subscribers', _NODE.wait_for_subscribers,
         'simulated time starts (from 0) once each of joint_states, tip/deflection, '
         'tip/position, frequencies (and frequencies/estimate when estimate_window > 0) '
         'has at least this many subscriptions: with rerun_logger started first, a run '
         'as fast as possible is recorded from its first publication. -1 (default) = '
         f'when started as fast as possible (real_time_factor 0) 1, for at most '
         f'{AUTO_WAIT_TIMEOUT:g} s (then it starts, with a warning), else at once; '
         'N > 0 = N, however long; 0 = at once', '', AUTO_WAIT, 1000, read_only=True),
    Spec('start_paused', _NODE.start_paused,
         'start paused at simulated time 0 (simulation_interfaces STATE_STOPPED), for '
         'lockstep stepping (~/step_simulation, ~/simulate_steps) or a later play: a '
         'logger or a controller connects before time starts. Stamps are then simulated '
         'time, published on /clock', read_only=True),
    Spec('rods', _NODE.rods, 'how many rods the simulator starts with: 1 (default) = one '
         'rod with the plain names (cmd/omega, joint_states, ...); N > 1 = N copies of the '
         'rod of these parameters, named rod0 ... rod{N-1}, their interfaces and frames '
         'under rodK/; more come and go through ~/spawn_entity and ~/delete_entity', '',
         1, 10000, read_only=True),
    Spec('max_rods', _NODE.max_rods, 'most rods the world holds: a spawn beyond is refused',
         '', 1, 10000),
    Spec('max_steps_per_request', _NODE.max_steps_per_request, 'most physics steps one '
         'StepSimulation or SimulateSteps request may ask for (beyond: refused with '
         'RESULT_OPERATION_FAILED); a reset, a play, a stop or a cancel ends a running '
         'request at the next publication instant anyway', '', 1, 2**62),
    Spec('realtime_priority', _NODE.realtime_priority,
         'SCHED_FIFO priority of the physics thread while paced (real_time_factor > 0), '
         '1..99; 0 = ordinary scheduling. Needs root or CAP_SYS_NICE; refused with a '
         'warning otherwise', '', 0, MAX_PRIORITY, read_only=True),
    Spec('cpu_dma_latency', _NODE.cpu_dma_latency,
         'machine-wide, opt-in (config/realtime.yaml): while paced (real_time_factor > 0), '
         'the CPU wake-up latency the node asks the kernel for (PM QoS, '
         '/dev/cpu_dma_latency, as cyclictest does): every idle CPU of the machine '
         'stays out of sleep states slower to leave. 0 keeps them polling (a sleeping '
         'thread wakes at once; idle cores stay busy, costing power); -1 (default) = '
         'leave the machine as it is. Needs root; refused with a warning otherwise',
         'us', -1, MAX_CPU_LATENCY, read_only=True),
    Spec('publication_spin', _NODE.publication_spin,
         'while paced, wall time before each publication\'s due time at which the physics '
         'thread stops sleeping and polls the clock (a sleeping thread may wake late on a '
         'VM whose idle CPUs halt); costs about publication_spin x publish_rate of a core '
         '(0.3 ms at 100 Hz: 3 %); ignored while cpu_dma_latency 0 is held; 0 (default) = '
         'sleep to the due time', 's', 0.0, MAX_PUBLICATION_SPIN),
)

NOISE_GROUPS = {'imu.linear_acceleration': ('linear_acceleration', 'm/s^2'),
                'imu.angular_velocity': ('angular_velocity', 'rad/s'),
                'strain': ('strain', 'N m')}
"""The noise parameters' groups: SensorConfig's field and the channel's unit."""
NOISE_FIELDS = {
    'type': ('SDF <noise> type: none | gaussian | gaussian_quantized (then rounded to '
             'precision)', ''),
    'mean': ('added to every sample', None),
    'stddev': ('standard deviation of the white Gaussian noise, each sample', None),
    'bias_mean': ('mean of the bias drawn once per run (its sign then drawn, as '
                  'gz-sensors does)', None),
    'bias_stddev': ('standard deviation of the bias drawn once per run', None),
    'dynamic_bias_stddev': ('driving density sigma of the dynamic bias, a first-order '
                            'Gauss-Markov process (stationary std sigma sqrt(tau / 2)); '
                            '0 = none', '/sqrt(s)'),
    'dynamic_bias_correlation_time': ('correlation time tau of the dynamic bias (> 0 with '
                                      'a dynamic bias)', 's'),
    'precision': ('resolution the output is rounded to (gaussian_quantized; > 0 there)',
                  None),
}
"""Each channel's noise parameters (SDF's <noise>): description, unit (None: the
channel's; '/sqrt(s)': the channel's per square root of a second)."""
_NOISE = NoiseParams()
_SENSORS = SensorConfig()


def _noise_specs() -> tuple[Spec, ...]:
    specs = []
    for group, (_, unit) in NOISE_GROUPS.items():
        for name, (text, own) in NOISE_FIELDS.items():
            full = f'{group}.{name}'
            if name == 'type':
                specs.append(Spec(full, _NOISE.type, text, choices=NOISE_TYPES))
                continue
            shown = unit if own is None else (f'{unit}/sqrt(s)' if own == '/sqrt(s)' else own)
            low = -1e9 if name in ('mean', 'bias_mean') else 0.0
            specs.append(Spec(full, float(getattr(_NOISE, name)), text, shown, low, 1e9))
    return tuple(specs)


SENSOR_SPECS = (
    *_noise_specs(),
    Spec('imu.orientation', _SENSORS.orientation, 'whether tip/imu gives the orientation '
         '(false: a 6-axis IMU, orientation_covariance[0] = -1 as REP 145 marks it not '
         'provided)'),
    Spec('imu_rate', _SENSORS.imu_rate, 'rate of tip/imu, of simulated time (<= '
         'publish_rate): it reads at the first sample within half a sample of each k / '
         'imu_rate, so a rate that does not divide publish_rate keeps its mean (as Gazebo '
         'updates a sensor at the step nearest its time); its noise steps by 1 / imu_rate. '
         '0 (default) = publish_rate', 'Hz', 0.0, 1e4),
    Spec('encoder.counts_per_revolution', _SENSORS.counts_per_revolution,
         "hub/encoder's counts per turn: its position is a whole number of 2 pi / this",
         '', 1, 2**31 - 1),
    Spec('encoder.window', _SENSORS.encoder_window, "time hub/encoder's speed is taken "
         'over (the counts gained over it, times 2 pi / counts_per_revolution, over the '
         'time they took), of simulated time (> 0)', 's', 0.0, 60.0),
)
"""The rig sensors' parameters (:class:`SensorConfig`); the noise seed is noise_seed."""

ALL_SPECS = ROD_SPECS + ENGINE_SPECS + NODE_SPECS + SENSOR_SPECS
SPECS_BY_NAME = {s.name: s for s in ALL_SPECS}


def rod_params(values: Mapping[str, Any]) -> RodParams:
    """The RodParams of the ROD_SPECS values (unused section sizes are 0); ValueError."""
    rod = {s.name: values[s.name] for s in ROD_SPECS}
    for name in _OPTIONAL_ROD_FIELDS:
        if rod[name] == 0.0:
            rod[name] = None
    return RodParams(**rod)


def build_settings(values: Mapping[str, Any]) -> tuple[EngineConfig, NodeSettings]:
    """Validate a complete set of parameter values; return the engine config and node settings.

    Raises ValueError with the reason for the first problem found.
    """
    for name, value in values.items():
        if name in SPECS_BY_NAME:
            check_value(SPECS_BY_NAME[name], value)
    params = rod_params(values)
    initial = tuple((name, values[f'initial.{name}']) for name in STATE_FIELDS
                    if values[f'initial.{name}'] != 0.0)
    engine = EngineConfig(params=params, initial=initial,
                          **{s.name: values[s.name] for s in ENGINE_SPECS
                             if not s.name.startswith('initial.')})
    node = NodeSettings(**{f.name: values[f.name] for f in fields(NodeSettings)
                           if f.name != 'sensors'}, sensors=sensor_config(values))
    if node.publish_rate > engine.physics_rate:
        raise ValueError(f'publish_rate {node.publish_rate:g} Hz exceeds physics_rate '
                         f'{engine.physics_rate:g} Hz: there would be nothing new to publish')
    if node.sensors.imu_rate > node.publish_rate:
        raise ValueError(f'imu_rate {node.sensors.imu_rate:g} Hz exceeds publish_rate '
                         f'{node.publish_rate:g} Hz: the IMU reads at the samples (raise '
                         'publish_rate for a faster IMU)')
    if node.rods > node.max_rods:
        raise ValueError(f'rods {node.rods} exceeds max_rods {node.max_rods}')
    return engine, node


def sensor_config(values: Mapping[str, Any]) -> SensorConfig:
    """The SensorConfig of the SENSOR_SPECS values; ValueError naming the parameter."""
    noise = {}
    for group, (attribute, _) in NOISE_GROUPS.items():
        try:
            noise[attribute] = NoiseParams(**{name: values[f'{group}.{name}']
                                              for name in NOISE_FIELDS})
        except ValueError as exc:
            raise ValueError(f'{group}: {exc}') from None
    if not values['encoder.window'] > 0:
        raise ValueError(f'encoder.window must be > 0 s, got {values["encoder.window"]!r}')
    return SensorConfig(**noise, counts_per_revolution=values['encoder.counts_per_revolution'],
                        encoder_window=values['encoder.window'],
                        orientation=values['imu.orientation'], imu_rate=values['imu_rate'])


def defaults() -> dict[str, Any]:
    """Every parameter's default value by name."""
    return {s.name: s.default for s in ALL_SPECS}


class ParameterValues:
    """The simulator's parameter values in use, and a change checked before it is taken.

    :meth:`check` (the on-set callback's) builds the settings of the values with a
    change and remembers them, changing nothing in use; :meth:`take` (the post-set
    callback's) makes the values with the change the ones in use and returns their
    settings, those :meth:`check` built when it was given the same values. Names not
    among :data:`SPECS_BY_NAME` (rclpy's own, e.g. ``use_sim_time``) are left out.
    Raises ValueError (the reason) on values that make no sense together.
    """

    def __init__(self, values: Mapping[str, Any]) -> None:
        self.values = dict(values)
        """The values in use, by name."""
        self._checked = (self.values, *build_settings(self.values))

    @property
    def checked(self) -> tuple[EngineConfig, NodeSettings]:
        """The engine config and node settings last built (at first: of the values in use)."""
        return self._checked[1], self._checked[2]

    def _with(self, changes: Mapping[str, Any]) -> dict[str, Any]:
        return {**self.values, **{name: value for name, value in changes.items()
                                  if name in SPECS_BY_NAME}}

    def check(self, changes: Mapping[str, Any]) -> tuple[EngineConfig, NodeSettings]:
        """Check the values in use with ``changes`` as a whole (ValueError); none is taken.

        Returns the engine config and node settings they would make.
        """
        values = self._with(changes)
        self._checked = (values, *build_settings(values))
        return self.checked

    def take(self, changes: Mapping[str, Any]) -> tuple[EngineConfig, NodeSettings]:
        """Put the values with ``changes`` in use; their engine config and node settings."""
        values = self._with(changes)
        if self._checked[0] != values:            # not what was checked last
            self._checked = (values, *build_settings(values))
        self.values = values
        return self.checked
