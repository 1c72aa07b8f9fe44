"""The simulator's names and conventions on the outside: frames, joints, topics, stamps.

One source for the live node's messages (``rotrod_ros.messages``), the URDF
(:mod:`rotrod_core.model.urdf`) and the rosbag2 writer of offline runs
(:mod:`rotrod_core.reporting.bag`), so that a live run, its ``/tf`` and a bag agree:
both build the fields of their messages with the functions here (:func:`joint_values`,
:func:`frequency_fields`, :func:`whirl_fields`, :func:`stamp_parts`).

Frames (URDF links; ``robot_state_publisher`` turns ``joint_states`` into ``/tf``)::

    world --hub (continuous, about z: theta)--> rotor
      rotor --rod_mount (fixed, at (r0, 0, 0))--> rod_root
        rod_root --tip_radial (prismatic along x: u, at height l)--> tip_radial_link
          tip_radial_link --tip_tangential (prismatic along y: v)--> tip

``world`` is inertial; ``rotor`` turns with the hub (x radial through the rod's root, y
tangential, z up the axis), the frame of ``tip/deflection``; ``tip`` is the mass, at
(r0 + u, v, l) in ``rotor``: ``tip/position`` in ``world``.
"""

from __future__ import annotations

import math

from rotrod_core.model.geometry import tip_tilt

WORLD_FRAME = 'world'
"""The inertial frame: tip/position and the markers."""
ROTOR_FRAME = 'rotor'
"""The rotating frame of the hub (the disk link): tip/deflection."""
ROD_ROOT_FRAME = 'rod_root'
"""The rod's root on the disk, at (r0, 0, 0) in the rotor frame."""
TIP_RADIAL_FRAME = 'tip_radial_link'
"""Between the two tip joints: at (r0 + u, 0, l) in the rotor frame."""
TIP_TANGENTIAL_FRAME = 'tip_tangential_link'
"""After the two tip joints: at (r0 + u, v, l) in the rotor frame, not tilted."""
TIP_PITCH_FRAME = 'tip_pitch_link'
"""Between the two tilt joints."""
TIP_FRAME = 'tip'
"""The mass (and the IMU on it, tip/imu): at (r0 + u, v, l) in the rotor frame, tilted
with the rod's tangent at the tip (z along it): Ry(a) Rx(-b) of the rotor's axes
(:func:`rotrod_core.model.geometry.tip_tilt`)."""

HUB_JOINT = 'hub'
"""Continuous joint world -> rotor about z: position theta rad, velocity w rad/s,
effort the hub torque N m (in velocity drive, the torque the drive must supply)."""
ROD_MOUNT_JOINT = 'rod_mount'
"""Fixed joint rotor -> rod_root."""
TIP_RADIAL_JOINT = 'tip_radial'
"""Prismatic joint along the rotor's x: position u m, velocity u' m/s."""
TIP_TANGENTIAL_JOINT = 'tip_tangential'
"""Prismatic joint along the rotor's y: position v m, velocity v' m/s."""
TIP_PITCH_JOINT = 'tip_pitch'
"""Revolute joint about y: position a rad (the tip's tilt toward the radial), a' rad/s."""
TIP_ROLL_JOINT = 'tip_roll'
"""Revolute joint about x: position -b rad (the tilt toward the tangential), -b' rad/s."""
JOINT_NAMES = (HUB_JOINT, TIP_RADIAL_JOINT, TIP_TANGENTIAL_JOINT, TIP_PITCH_JOINT,
               TIP_ROLL_JOINT)
"""The joints in ``joint_states``, in this order."""

INTERFACES_PACKAGE = 'rotrod_interfaces'
"""The ROS package of rotrod's own messages and action (``rotrod_interfaces/``)."""
MARKER_NAMESPACE = 'rotrod'
"""The ``ns`` of the markers."""

TOPICS = {
    'joint_states': 'sensor_msgs/msg/JointState',
    'tip/deflection': 'geometry_msgs/msg/Vector3Stamped',
    'tip/position': 'geometry_msgs/msg/PointStamped',
    'frequencies': 'rotrod_interfaces/msg/DynamicFrequencies',
    'frequencies/estimate': 'rotrod_interfaces/msg/WhirlEstimate',
    'markers': 'visualization_msgs/msg/MarkerArray',
    '/diagnostics': 'diagnostic_msgs/msg/DiagnosticArray',
    '/clock': 'rosgraph_msgs/msg/Clock',
}
"""What the simulator node publishes: topic (relative to its namespace unless it starts
with /) -> message type."""


def joint_values(state, torque: float, rod_length: float) -> tuple:
    """(positions, velocities, efforts) of :data:`JOINT_NAMES` for a state, SI units.

    ``state`` has u, v, du, dv, theta, omega (:class:`rotrod_core.model.equations.State`);
    ``torque`` is the hub torque, N m; ``rod_length`` (m) sets the tip's tilt (the
    tilt joints: a and -b of :func:`rotrod_core.model.geometry.tip_tilt`). The tip
    joints are passive (the rod's elastic and inertial forces are internal to the
    model): their effort is 0.
    """
    u, v, du, dv = float(state.u), float(state.v), float(state.du), float(state.dv)
    a, b, da, db = tip_tilt(u, v, du, dv, rod_length)
    return ((float(state.theta), u, v, a, -b),
            (float(state.omega), du, dv, da, -db),
            (float(torque), 0.0, 0.0, 0.0, 0.0))


def frequency_fields(omega: float, f1: float, f2: float) -> dict:
    """The fields of ``frequencies`` (rotrod_interfaces/DynamicFrequencies) but the header.

    ``omega`` the hub's angular velocity, rad/s; ``f1`` <= ``f2`` the dynamic
    frequencies at it, Hz (Eq. 28 or the eigen analysis).
    """
    return {'omega': float(omega), 'f1': float(f1), 'f2': float(f2)}


def whirl_fields(estimate) -> dict:
    """The fields of ``frequencies/estimate`` (rotrod_interfaces/WhirlEstimate) but the header.

    ``estimate`` is a :class:`rotrod_core.estimation.whirl.WhirlEstimate`: f1 the
    forward whirl, f2 the backward one, Hz, with their standard deviations; a whirl
    is valid when its frequency is finite (NaN otherwise, with the estimate's reason).
    The header's stamp is the window's middle, ``estimate.time``.
    """
    f1, f2 = float(estimate.f1), float(estimate.f2)
    f1_valid, f2_valid = math.isfinite(f1), math.isfinite(f2)
    nan = math.nan
    return {'f1': f1, 'f2': f2,
            'f1_std': float(estimate.forward.frequency_std) if f1_valid else nan,
            'f2_std': float(estimate.backward.frequency_std) if f2_valid else nan,
            'f1_valid': f1_valid, 'f2_valid': f2_valid,
            'reason': '' if f1_valid and f2_valid else str(estimate.reason),
            'window': float(estimate.window), 'samples': int(estimate.samples)}


def stamp_parts(seconds: float) -> tuple:
    """(sec, nanosec) of builtin_interfaces/Time for a time in seconds (>= 0).

    nanosec is the rounded fraction, carried into sec at 1e9.
    """
    sec = math.floor(seconds)
    nanosec = int(round((seconds - sec) * 1e9))
    if nanosec >= 1_000_000_000:
        sec, nanosec = sec + 1, nanosec - 1_000_000_000
    return int(sec), nanosec


def stamp_nanoseconds(seconds: float) -> int:
    """The same instant as :func:`stamp_parts`, in integer nanoseconds."""
    sec, nanosec = stamp_parts(seconds)
    return sec * 1_000_000_000 + nanosec
