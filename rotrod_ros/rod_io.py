"""One rod of the simulator's world on ROS: its topics, its action, its description.

Every rod of the world (:class:`rotrod_core.live.world.World`) has the same interfaces
(:data:`INTERFACES`), relative to its prefix: none for the rod a simulator starts with
(today's names: ``cmd/omega``, ``joint_states``, ...), ``<name>/`` for a rod of
``rods:=N`` or a spawned one (``rod3/cmd/omega``; or the ``entity_namespace`` it was
spawned with). Its frames carry the same prefix (``rod3/rotor``); its hub stands at its
pose (x, y, z m, yaw rad) in the one shared ``world`` frame, where ``tip/position`` and
the markers are. :meth:`RodIO.publish` sends a sample of the rod (called by the loop
in the same wake-up for every rod), :meth:`RodIO.destroy` takes the interfaces down
when the rod leaves the world.
"""

from __future__ import annotations

import dataclasses
import math
from typing import NamedTuple

from builtin_interfaces.msg import Time
from geometry_msgs.msg import WrenchStamped
from sensor_msgs.msg import Imu, JointState
from std_msgs.msg import Float64, String

import rotrod_core.model.equations as model
from rotrod_core.command.joint_command import MalformedJointCommand, hub_command
from rotrod_core.estimation.whirl import WhirlEstimator
from rotrod_core.live.engine import EngineConfig, SimulationEngine
from rotrod_core.live.loop import RealTimeLoop, Sample
from rotrod_core.model.geometry import rod_centerline, sphere_radius
from rotrod_core.model.interface import (
    MARKER_NAMESPACE,
    ROD_ROOT_FRAME,
    ROTOR_FRAME,
    TIP_FRAME,
    WORLD_FRAME,
    stamp_parts,
)
from rotrod_core.model.scene import scene
from rotrod_core.model.urdf import urdf_text

from . import interfaces, messages, trajectory_server
from .interfaces import pub, sub
from .keep_all import KeepAllPublishing
from .observation import Observation
from .parameters import NodeSettings

COMMAND_QOS_DEPTH = 1000
"""Queue depth of cmd/omega and cmd/torque: a burst of setpoints (a sender catching up)
must not be dropped, since the setpoint shaper numbers a stream's samples in order."""
SAMPLE_QOS_DEPTH = 100
"""Queue depth of the sample topics when paced: a reliable subscriber that falls behind
(a busy machine's scheduler, a garbage collection) by up to 100 publications (1 s at
100 Hz) still receives every one; a slower one loses the oldest."""
LOSSLESS = 'when started as fast as possible (real_time_factor 0)'
"""The sample topics' keep_all condition: then a reliable KEEP_ALL subscriber (e.g.
rerun_logger) gets every publication, the physics waiting for it when it falls behind."""
COMMAND_TOPICS = ('cmd/omega', 'cmd/torque', 'joint_command')
"""The subscriptions that carry commands."""

INTERFACES = (
    sub('cmd/omega', Float64, 'angular-velocity setpoint, rad/s (drive velocity or servo); with '
        'command_timeout > 0 s, when no command is accepted on the active input for '
        'that long, w ramps to 0 at max_angular_acceleration', COMMAND_QOS_DEPTH),
    sub('cmd/torque', Float64, 'hub torque, N m (drive torque: free rotation); with '
        'command_timeout, the torque is set to 0', COMMAND_QOS_DEPTH),
    sub('joint_command', JointState, "ros2_control's topic interface (topic_based_ros2_control): "
        "joint 'hub''s velocity = setpoint rad/s (drive velocity or servo) or effort = torque N m "
        '(drive torque), read by name; other joints ignored; each field must be empty or '
        'have one entry per name (sensor_msgs/JointState), else the message is rejected '
        'with a warning and changes nothing; the same shaping, limits and timeout as '
        'cmd/omega and cmd/torque (docs/ros_integration.md)', COMMAND_QOS_DEPTH),
    pub('joint_states', JointState, "joint 'hub': position theta rad, velocity w rad/s, "
        "effort = hub torque N m; the URDF's passive tip joints 'tip_radial', "
        "'tip_tangential': u, v m, u', v' m/s, and 'tip_pitch', 'tip_roll': the tip's "
        "tilt a, -b rad and their rates (the true state, no noise), effort 0; every "
        '1/publish_rate of simulated time', SAMPLE_QOS_DEPTH, keep_all=LOSSLESS),
    pub('tip/deflection', messages.Vector3Stamped, "(u, v, 0) m in frame 'rotor' (rotating: "
        'x radial, y tangential), plus Gaussian noise of deflection_noise m (a sensor)',
        SAMPLE_QOS_DEPTH, keep_all=LOSSLESS),
    pub('tip/position', messages.PointStamped, "the mass, m, in frame 'world' (inertial, "
        'shared by every rod: its hub at its pose; z = rod length above the hub)',
        SAMPLE_QOS_DEPTH, keep_all=LOSSLESS),
    pub('frequencies', messages.DynamicFrequencies, 'f1 <= f2 Hz at the published w (omega, '
        'rad/s; Eq. 28, or the eigen analysis), stamped as the sample', SAMPLE_QOS_DEPTH,
        keep_all=LOSSLESS),
    pub('frequencies/estimate', messages.WhirlEstimate, 'f1 (forward whirl), f2 (backward) '
        'Hz, their standard deviations, whether each is valid and why not, estimated from '
        'the published (u, v) over the last estimate_window, every 1/estimate_rate; stamped '
        "at the window's middle, which it describes", SAMPLE_QOS_DEPTH, keep_all=LOSSLESS),
    pub('tip/imu', Imu, "the IMU on the tip mass (REP 145), frame 'tip' (tilted with the "
        "rod's slope at the tip: z along the rod's tangent): orientation in 'world' "
        '(not given, covariance[0] = -1, with imu.orientation false), angular velocity '
        'rad/s and specific force m/s^2 (gravity included) in its frame, with the '
        'imu.* noise; every 1/imu_rate (docs/sensors.md)', SAMPLE_QOS_DEPTH,
        keep_all=LOSSLESS),
    pub('hub/encoder', JointState, "joint 'hub': the encoder's angle, a whole number of "
        '2 pi / encoder.counts_per_revolution rad, and its speed from counts over '
        'encoder.window, rad/s; every 1/publish_rate (docs/sensors.md)', SAMPLE_QOS_DEPTH,
        keep_all=LOSSLESS),
    pub('rod/strain', WrenchStamped, "the wrench the rod exerts on the hub at its root, "
        "frame 'rod_root' (x radial, y tangential, z up the rod): shear force k u, k v "
        'and weight N, bending moments N m (with the strain.* noise); every '
        '1/publish_rate (docs/sensors.md)', SAMPLE_QOS_DEPTH, keep_all=LOSSLESS),
    pub('markers', messages.MarkerArray, "disk, rod, mass, trail (frame 'world'), at "
        'marker_rate Hz of simulated time'),
    pub('robot_description', String, 'the URDF of the rod (rotrod urdf) with its physical '
        'parameters and the drive\'s limits in a <rotrod> element, from the parameters in '
        'use: published when the rod comes and after every change of them; what the other '
        'nodes read the rod from', 1, transient_local=True),
    *trajectory_server.INTERFACES,
)
"""Every rod's interfaces, relative to its prefix (none for the simulator's first rod)."""
SAMPLE_TOPICS = ('joint_states', 'tip/deflection', 'tip/position', 'frequencies',
                 'frequencies/estimate')
SENSOR_TOPICS = ('tip/imu', 'hub/encoder', 'rod/strain')
"""The rig sensors' topics (published, as the sample topics, only to subscribers)."""
LOOKED_AT = SAMPLE_TOPICS + SENSOR_TOPICS + ('markers',)
LOOK = 0.1
"""Wall seconds between looks at who subscribes to a rod's sample topics (a topic
nobody subscribes to is not published; as fast as possible, a look per sample), in a
world of up to LOOK_RODS rods."""
LOOK_RODS = 20
"""In a larger world each rod looks less often (:func:`look_period`), so that the
looks of a world cost what LOOK_RODS rods' do: a look at a topic's subscriber count
costs rclpy ~4 us, a hundred rods' nine topics every 0.1 s 4 % of a core."""


def look_period(rods: int) -> float:
    """Wall seconds between a rod's looks for subscribers in a world of ``rods`` rods."""
    return LOOK * max(1.0, rods / LOOK_RODS)

GOLDEN = (5 ** 0.5 - 1) / 2
"""The k-th rod looks for subscribers k * GOLDEN (mod 1) of a LOOK period after the
first: spread evenly over the period whatever the number of rods."""


HUB_SHAPES = (0, 1)
"""The ids of the scene's shapes drawn about the hub (disk, spoke): placed at its pose;
the rod, mass and trail are drawn from the rod's points, placed already."""


class Pose(NamedTuple):
    """Where a rod's hub stands in the world frame: position m, yaw about z rad."""

    x: float = 0.0
    y: float = 0.0
    z: float = 0.0
    yaw: float = 0.0

    def place(self, point) -> tuple[float, float, float]:
        """``point`` (x, y, z m, relative to the hub) in the world frame."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        x, y, z = point
        return (self.x + c * x - s * y, self.y + s * x + c * y, self.z + z)


ORIGIN = Pose()


class RodIO:
    """A rod's ROS interfaces and what they show of it.

    Args:
        node: the simulator node.
        loop: the world's loop (commands go to it, for this rod).
        engine: the rod.
        prefix: its interfaces' prefix ('' or ending in '/': 'rod3/').
        pose: its hub in the world frame.
        settings: the node's settings (frame prefix, noise, estimate, ...).
        conditions: keep_all conditions that hold (see :func:`rotrod_ros.interfaces.qos`).
        on_goal: registers a trajectory goal's token with its server (see the node).
        stagger: the rod's place in the world (0 for the first): its whirl estimates
            come that many samples after the first rod's, modulo the samples per
            estimate, so that the rods' estimates do not all fall on one sample; its
            looks for subscribers are spread the same way.
    """

    def __init__(self, node, loop: RealTimeLoop, engine: SimulationEngine, prefix: str,
                 pose: Pose, settings: NodeSettings, conditions=(), on_goal=None,
                 stagger: int = 0):
        self.node, self.loop, self.engine = node, loop, engine
        self.name, self.prefix, self.pose = engine.name, prefix, pose
        frame_prefix = settings.frame_prefix
        self.rotor_frame = frame_prefix + prefix + ROTOR_FRAME
        self.world_frame = frame_prefix + WORLD_FRAME
        self.observation = Observation(settings, stagger, engine.name)
        self.messages = messages.SampleMessages(self.rotor_frame, self.world_frame)
        self.rig = messages.RigMessages(frame_prefix + prefix + TIP_FRAME,
                                        frame_prefix + prefix + ROD_ROOT_FRAME,
                                        settings.sensors)
        self._sensors = settings.sensors
        self.marker_frames = messages.MarkerFrames(self.world_frame,
                                                   prefix + MARKER_NAMESPACE)
        self.trajectories = trajectory_server.TrajectoryServer(
            node, loop, rod=self.name, action_name=prefix + trajectory_server.ACTION_NAME,
            on_goal=on_goal)
        name = self.name
        submit = loop.submit
        callbacks = {
            'cmd/omega': lambda msg: submit('omega', msg.data, self._source('cmd/omega'), name),
            'cmd/torque': lambda msg: submit('torque', msg.data, self._source('cmd/torque'),
                                             name),
            'joint_command': self._on_joint_command,
            **self.trajectories.callbacks()}
        table = [dataclasses.replace(i, name=prefix + i.name) for i in INTERFACES]
        made = interfaces.create(node, table, {prefix + k: v for k, v in callbacks.items()},
                                 conditions=conditions)
        self.io = {i.name: made[prefix + i.name] for i in INTERFACES}
        self.keep_all = KeepAllPublishing(self.io, node.get_logger(), node.context.ok,
                                          lambda: loop.running, node.stop_grace,
                                          phase=(stagger * GOLDEN) % 1.0)
        self._description: str | None = None
        self.look_every = LOOK
        """Wall seconds between its looks for subscribers (the node sets
        :func:`look_period` of its world's size)."""

    def _source(self, topic: str) -> str:
        return self.prefix + topic

    @property
    def entity(self) -> str:
        """The rod's entity name in the simulation standard ('' for the first rod)."""
        return self.name

    # ----------------------------------------------------------------- commands
    def _on_joint_command(self, msg: JointState) -> None:
        """joint_command: the hub's entry into the command queue, or a logged rejection."""
        source = self._source('joint_command')
        try:
            kind, value = hub_command(msg.name, msg.position, msg.velocity, msg.effort,
                                      self.engine.config.drive)
        except MalformedJointCommand as exc:
            self.loop.reject(source, str(exc))
            return
        self.loop.submit(kind, value, source, self.name)

    def take_pending_commands(self) -> int:
        """Take what the command subscriptions hold now and queue it; how many."""
        taken = 0
        for topic in COMMAND_TOPICS:
            subscription = self.io[topic]
            while (got := interfaces.take(subscription)) is not None:
                subscription.callback(got[0])
                taken += 1
        return taken

    # ----------------------------------------------------------------- description
    def publish_description(self, config: EngineConfig, disk_radius: float) -> None:
        """robot_description: the URDF of the rod in use (if it changed)."""
        text = urdf_text(config.params, limits=config.drive_limits, disk_radius=disk_radius)
        if text != self._description:
            self._description = text
            self.io['robot_description'].publish(String(data=text))

    @property
    def description(self) -> str | None:
        """The URDF last published."""
        return self._description

    # ----------------------------------------------------------------- publishing
    def publish(self, s: Sample, settings: NodeSettings, config: EngineConfig,
                estimator: WhirlEstimator | None) -> tuple:
        """Publish the rod's sample topics and trajectory feedback (the physics thread).

        Returns the arguments of :meth:`publish_extras`, which the node calls once every
        rod's samples of the instant are out: an estimate or a marker array costs many
        samples' publications, and the rods after it would wait for it.
        """
        st, obs = s.state, self.observation
        sec, nanosec = stamp_parts(s.stamp)
        wait = not settings.real_time_factor       # as fast as possible: lossless
        keep_all = self.keep_all
        # who listens: at every sample as fast as possible (lossless), else every
        # look_every s
        keep_all.look(LOOKED_AT, 0.0 if wait else self.look_every)
        send, subscribed, m = keep_all.send, keep_all.subscribed, self.messages
        # the sensor reads the tip whether or not anyone listens (its noise sequence
        # and the estimate do not depend on the subscribers)
        u, v = obs.deflection(float(st.u), float(st.v), settings.deflection_noise)
        if subscribed('joint_states'):
            send('joint_states', m.joint_state(sec, nanosec, st, s.torque,
                                               float(config.params.rod_length)), wait)
        if subscribed('tip/deflection'):
            send('tip/deflection', m.deflection(sec, nanosec, u, v), wait)
        if subscribed('tip/position'):
            x, y = model.inertial_position(s.coefficients, st.u, st.v, st.theta)
            position = (x, y, float(config.params.rod_length))
            if self.pose is not ORIGIN:
                position = self.pose.place(position)
            send('tip/position', m.position(sec, nanosec, position), wait)
        if subscribed('frequencies'):
            omega = float(st.omega)
            send('frequencies', m.frequencies(sec, nanosec, omega,
                                              *self.engine.frequencies(omega)), wait)
        self._publish_sensors(s, sec, nanosec, settings, config, wait)
        if s.tracking is not None:
            self.trajectories.feedback(Time(sec=sec, nanosec=nanosec), s.tracking)
        return s, u, v, settings, config, estimator

    def _publish_sensors(self, s: Sample, sec: int, nanosec: int, settings: NodeSettings,
                         config: EngineConfig, wait: bool) -> None:
        """tip/imu, hub/encoder, rod/strain: the rig's sensors read the sample.

        They read every sample whether or not anyone listens (their noise sequences
        and the encoder's counts do not depend on the subscribers).
        """
        send, subscribed, rig = self.keep_all.send, self.keep_all.subscribed, self.rig
        if settings.sensors is not self._sensors:
            self._sensors = settings.sensors
            rig.configure(settings.sensors)
        reading = self.observation.sensors.read(
            s.time, 1.0 / settings.publish_rate, s.coefficients, config.params,
            s.state, s.omega_dot, imu=subscribed('tip/imu'), strain=subscribed('rod/strain'),
            encoder=subscribed('hub/encoder'))
        if reading.imu is not None:
            send('tip/imu', rig.imu_message(sec, nanosec, reading.imu), wait)
        if reading.encoder is not None:
            send('hub/encoder', rig.encoder_message(sec, nanosec, reading.encoder), wait)
        if reading.wrench is not None:
            send('rod/strain', rig.strain_message(sec, nanosec, reading.wrench), wait)

    def publish_extras(self, s: Sample, u: float, v: float,
                       settings: NodeSettings, config: EngineConfig,
                       estimator: WhirlEstimator | None) -> None:
        """The sample's whirl estimate (when one is due) and markers (when due).

        ``u``, ``v``: the deflection the sensor read for the sample (m).
        """
        wait = not settings.real_time_factor
        send, subscribed, m = self.keep_all.send, self.keep_all.subscribed, self.messages
        if estimator is not None:
            estimate = estimator.push(s.time, u, v)
            if estimate is not None and subscribed('frequencies/estimate'):
                # stamped at its window's middle
                middle = messages.stamp(s.stamp - (s.time - estimate.time))
                send('frequencies/estimate',
                     messages.set_whirl_estimate(m.estimate, middle, estimate), wait)
        if s.markers and subscribed('markers'):
            self._publish_markers(s, messages.stamp(s.stamp), settings, config)

    def _publish_markers(self, s: Sample, stamp, settings: NodeSettings,
                         config: EngineConfig) -> None:
        st = s.state
        theta = float(st.theta) + self.pose.yaw
        rod = rod_centerline(config.params, float(st.u), float(st.v), theta,
                             scale=settings.marker_deflection_scale).tolist()
        if self.pose[:3] != (0.0, 0.0, 0.0):
            rod = [[x + self.pose.x, y + self.pose.y, z + self.pose.z] for x, y, z in rod]
        shapes = scene(disk_radius=settings.disk_radius, theta=theta, rod=rod,
                       rod_diameter=float(config.params.rod_diameter),
                       mass_radius=sphere_radius(float(config.params.mass)),
                       trail=self.observation.trail(rod[-1]))
        if self.pose[:3] != (0.0, 0.0, 0.0):    # the disk and its spoke, at the hub
            shapes = [shape._replace(position=(shape.position[0] + self.pose.x,
                                               shape.position[1] + self.pose.y,
                                               shape.position[2] + self.pose.z))
                      if shape.id in HUB_SHAPES else shape for shape in shapes]
        self.io['markers'].publish(self.marker_frames.frame(stamp, shapes))

    def flush(self, timeout: float) -> None:
        """Wait for the sample topics' subscribers to acknowledge every publication."""
        self.keep_all.flush(SAMPLE_TOPICS + SENSOR_TOPICS, timeout)

    def destroy(self) -> None:
        """Take the rod's interfaces down (it left the world), through the node.

        The node's own calls: a publisher's or a subscription's event handlers are the
        node's waitables too, which the entity's destroy() alone would leave behind.
        """
        from rclpy.publisher import Publisher
        from rclpy.subscription import Subscription
        node = self.node
        for entity in self.io.values():
            if isinstance(entity, Publisher):
                node.destroy_publisher(entity)
            elif isinstance(entity, Subscription):
                node.destroy_subscription(entity)
            else:                                   # the action server
                entity.destroy()
        self.trajectories.destroy()


__all__ = ['COMMAND_TOPICS', 'INTERFACES', 'ORIGIN', 'Pose', 'RodIO', 'SAMPLE_TOPICS',
           'SENSOR_TOPICS', 'look_period']
