"""The hub's command from a ``joint_command`` message, as ros2_control's topic interface sends it.

``topic_based_ros2_control``'s ``TopicBasedSystem`` (the hardware interface by which a
ros2_control stack drives a simulator over topics) publishes, at every controller
update, a ``sensor_msgs/JointState`` whose ``name`` lists every joint of its
``<ros2_control>`` block in the block's order, and whose ``position``, ``velocity`` and
``effort`` get one entry for each joint that has that command interface, in the same
order; a joint without it adds none (``TopicBasedSystem::write``). So a field has either
one entry per name (every joint has that command interface), or fewer (the packed
form), or none.

For the rod, only the ``hub`` joint takes commands: ``velocity`` is an angular-velocity
setpoint (rad/s, velocity drive), ``effort`` a hub torque (N m, torque drive). The tip
joints are passive (state interfaces only). Hence:

- a field with one entry per name is read by name: the hub's entry is at the hub's
  index; other joints' entries are ignored;
- a packed field (fewer entries than names) must have exactly one entry, the hub's:
  with more, which entry belongs to which joint depends on the other joints' command
  interfaces, which the message does not say;
- the active drive's field must have the hub's entry; the other drive's field may be
  there too (a hub with both command interfaces) and is then ignored.

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
DRIVE_FIELDS = {'velocity': ('velocity', 'omega'), 'torque': ('effort', 'torque')}
"""For each drive: the field that commands it and the kind of command it is."""


class MalformedJointCommand(ValueError):
    """A joint_command message that cannot be read as a hub command (reason in the text)."""


def _hub_entry(field: str, values: Sequence[float], names: Sequence[str], hub: int):
    """The hub's value in ``field`` (None: none), or MalformedJointCommand."""
    n, count = len(names), len(values)
    if count == 0:
        return None
    if count == n:
        return values[hub]
    if count > n:
        raise MalformedJointCommand(f'{field} has {count} entries for {n} joint names')
    if count == 1:
        return values[0]
    raise MalformedJointCommand(
        f'{field} has {count} entries for {n} joint names: in this packed form (only '
        f'joints with a {field} command interface have an entry) only the one entry of '
        f"joint '{HUB_JOINT}' can be attributed; give {field} one entry per name, or "
        f"command interfaces to '{HUB_JOINT}' only")


def hub_command(names: Sequence[str], position: Sequence[float], velocity: Sequence[float],
                effort: Sequence[float], drive: str) -> tuple[str, float]:
    """The command for joint ``hub`` in a joint_command message, for ``drive``.

    ``names``, ``position``, ``velocity``, ``effort`` are the message's arrays;
    ``drive`` is 'velocity' or 'torque'. Returns ``('omega', w)`` (rad/s) in velocity
    drive or ``('torque', Q)`` (N m) in torque drive. Raises MalformedJointCommand:
    no or repeated ``hub`` name, a field whose length fits neither the names nor the
    packed form, a non-finite value for the hub, or no entry for the hub in the
    active drive's field (e.g. effort only in velocity drive). Limits (max_omega,
    max_torque) are the engine's to check.
    """
    if drive not in DRIVE_FIELDS:
        raise ValueError(f'drive must be one of {tuple(DRIVE_FIELDS)}, got {drive!r}')
    names = list(names)
    if HUB_JOINT not in names:
        listed = ', '.join(repr(n) for n in names[:8]) or 'none'
        raise MalformedJointCommand(f"no joint '{HUB_JOINT}' in the names (got {listed})")
    if names.count(HUB_JOINT) > 1:
        raise MalformedJointCommand(f"joint '{HUB_JOINT}' is named {names.count(HUB_JOINT)} "
                                    'times')
    hub = names.index(HUB_JOINT)
    entries = {}
    for field, values in zip(FIELDS, (position, velocity, effort)):
        value = _hub_entry(field, values, names, hub)
        if value is None:
            continue
        if not math.isfinite(value):
            raise MalformedJointCommand(f"{field} of joint '{HUB_JOINT}' is {value!r}: "
                                        'it must be finite')
        entries[field] = float(value)
    field, kind = DRIVE_FIELDS[drive]
    if field in entries:
        return kind, entries[field]
    other = {f: d for d, (f, _) in DRIVE_FIELDS.items() if d != drive}
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
