"""The hub's command from a ``joint_command`` message (sensor_msgs/JointState).

The contract is sensor_msgs/JointState's: ``position``, ``velocity`` and ``effort``
are each either empty or one entry per ``name``. A message that breaks it is refused
whole (the simulator logs a warning, counts it, and changes nothing): with a field of
another length, which entry belongs to which joint is a guess (e.g. ``name: [hub, x]``,
``velocity: [3.0]`` could be either joint's).

For the rod only the ``hub`` joint takes commands: ``velocity`` is an
angular-velocity setpoint (rad/s, velocity drive), ``effort`` a hub torque (N m,
torque drive); the hub's entry is the one at its index in ``name``, other joints'
entries are ignored. The active drive's field must have the hub's entry; the other
drive's field may be there too (a hub with both command interfaces) and is then
ignored.

``topic_based_ros2_control``'s ``TopicBasedSystem`` (the hardware interface by which
a ros2_control stack drives a simulator over topics) names every joint of its
``<ros2_control>`` block and gives a field one entry per joint that has that command
interface: so its messages keep the contract when every joint in the block has the
same command interfaces. ``rotrod urdf --ros2-control`` writes a block with the hub
only (:mod:`rotrod_core.model.urdf`).

:func:`hub_command` returns ``('omega', rad/s)`` or ``('torque', N m)``, or raises
:class:`MalformedJointCommand` with the reason. No ROS import: the node passes the
message's arrays.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

from rotrod_core.model.interface import HUB_JOINT

FIELDS = ('position', 'velocity', 'effort')
"""The JointState arrays, in message order."""
DRIVE_FIELDS = {'velocity': ('velocity', 'omega'), 'torque': ('effort', 'torque'),
                'servo': ('velocity', 'omega')}
"""For each drive: the field that commands it and the kind of command it is."""


class MalformedJointCommand(ValueError):
    """A joint_command message that cannot be read as a hub command (reason in the text)."""


def check_lengths(names: Sequence[str], **fields: Sequence[float]) -> None:
    """MalformedJointCommand unless each field is empty or has one entry per name."""
    n = len(names)
    for field, values in fields.items():
        if len(values) not in (0, n):
            raise MalformedJointCommand(
                f'{field} has {len(values)} entries for {n} joint names: a JointState '
                'field is empty or has one entry per name (which joint an entry belongs to '
                'would be a guess)')


def hub_command(names: Sequence[str], position: Sequence[float], velocity: Sequence[float],
                effort: Sequence[float], drive: str) -> tuple[str, float]:
    """The command for joint ``hub`` in a joint_command message, for ``drive``.

    ``names``, ``position``, ``velocity``, ``effort`` are the message's arrays;
    ``drive`` is 'velocity', 'servo' or 'torque'. Returns ``('omega', w)`` (rad/s) in
    velocity or servo drive or ``('torque', Q)`` (N m) in torque drive. Raises
    MalformedJointCommand: a field neither empty nor one entry per name (checked
    first: such a message breaks JointState's contract), no or repeated ``hub`` name,
    a non-finite value for the hub, or no entry for the hub in the active drive's
    field (e.g. effort only in velocity drive). Limits (max_omega, max_torque) are
    the engine's to check.
    """
    if drive not in DRIVE_FIELDS:
        raise ValueError(f'drive must be one of {tuple(DRIVE_FIELDS)}, got {drive!r}')
    names = list(names)
    check_lengths(names, position=position, velocity=velocity, effort=effort)
    if HUB_JOINT not in names:
        listed = ', '.join(repr(n) for n in names[:8]) or 'none'
        raise MalformedJointCommand(f"no joint '{HUB_JOINT}' in the names (got {listed})")
    if names.count(HUB_JOINT) > 1:
        raise MalformedJointCommand(f"joint '{HUB_JOINT}' is named {names.count(HUB_JOINT)} "
                                    'times')
    hub = names.index(HUB_JOINT)
    entries = {}
    for field, values in zip(FIELDS, (position, velocity, effort)):
        if len(values) == 0:
            continue
        value = values[hub]
        if not math.isfinite(value):
            raise MalformedJointCommand(f"{field} of joint '{HUB_JOINT}' is {value!r}: "
                                        'it must be finite')
        entries[field] = float(value)
    field, kind = DRIVE_FIELDS[drive]
    if field in entries:
        return kind, entries[field]
    other: dict[str, str] = {}               # field -> the first drive it commands
    for d, (f, _) in DRIVE_FIELDS.items():
        if f != field:
            other.setdefault(f, d)
    given = [f for f in entries if f in other]
    if given:
        raise MalformedJointCommand(
            f"{given[0]} for joint '{HUB_JOINT}' ignored: drive is {drive!r} (set drive to "
            f"{other[given[0]]!r} to use it; {field} commands drive {drive!r})")
    if 'position' in entries:
        raise MalformedJointCommand(
            f"position commands for joint '{HUB_JOINT}' are not supported: give {field} "
            f'(drive {drive!r})')
    raise MalformedJointCommand(f"no {field} for joint '{HUB_JOINT}' (drive {drive!r})")
