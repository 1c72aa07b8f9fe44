"""The rod a node serves, read from its simulator's ``robot_description``.

The simulator publishes the URDF of its parameters with the rod's description in a
``<rotrod>`` element (:mod:`rotrod_core.model.description`), transient local, on
``robot_description`` in its namespace. A node that needs the rod (the profile
publisher's planner, the rig monitor's nominal rod, the recording's geometry) reads it
there: the rod is given once, to the simulator.

A rod parameter (or limit) given to the node itself, on its command line or in a
parameters file, overrides that field: allowed, and reported as a warning naming each
field that then differs from the simulator's. A description that cannot be read is
logged with the field it lacks, and the node goes on waiting for one it can read: no
node plans for a rod it guessed. While none has come, the node says every
:data:`WAIT_LOG` s what it waits for.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable, Iterable
from typing import Any

from rclpy.qos import DurabilityPolicy, QoSProfile, ReliabilityPolicy
from std_msgs.msg import String

from rotrod_core.model.description import (
    Description,
    DescriptionError,
    DriveLimits,
    differences,
    read_description,
)
from rotrod_core.model.params import FIELDS

from .interfaces import sub

TOPIC = 'robot_description'
WAIT_LOG = 5.0
"""Wall seconds between the log lines of a node still waiting for the description."""
ROD_FIELDS = tuple(f.name for f in FIELDS)
LIMIT_FIELDS = tuple(f.name for f in dataclasses.fields(DriveLimits))
OPTIONAL_ROD_FIELDS = tuple(f.name for f in FIELDS if f.default is None)


def interface(use: str):
    """The node's subscription to robot_description, for its INTERFACES table."""
    return sub(TOPIC, String, "the simulator's URDF with the rod's parameters and limits "
               f'(<rotrod> element), transient local: {use}', 1, transient_local=True)


def explicit_values(node, names: Iterable[str]) -> dict[str, Any]:
    """The values of ``names`` given to ``node`` itself (command line, parameter files).

    rclpy keeps a node's overrides from its arguments (``-p``, ``--params-file``) as
    it starts; a parameter left at its default is not among them.
    """
    given = getattr(node, '_parameter_overrides', {})
    return {name: given[name].value for name in names if name in given}


class RodSource:
    """Waits for the simulator's description, applies the node's overrides, reports.

    Args:
        node: the node (its logger, clock and parameter overrides).
        names: the rod and limit parameters the node declares (each may override).
        on_description: called with the :class:`Description` to use (the node's
            overrides applied), at the first readable description and again whenever
            the simulator's changes.
        what: what the node uses the rod for, in log lines ('the plan', ...).
    """

    def __init__(self, node, names: Iterable[str],
                 on_description: Callable[[Description], None], what: str):
        self.node = node
        given = explicit_values(node, names)
        self.rod_overrides = {k: (None if k in OPTIONAL_ROD_FIELDS and v == 0.0 else v)
                              for k, v in given.items() if k in ROD_FIELDS}
        self.limit_overrides = {k: v for k, v in given.items() if k in LIMIT_FIELDS}
        self._use = on_description
        self._what = what
        self.simulators: Description | None = None
        """The simulator's own description, as last read."""
        self.description: Description | None = None
        """The description in use: the simulator's with this node's overrides."""
        self._subscription = node.create_subscription(
            String, TOPIC, self._on_message,
            QoSProfile(depth=1, reliability=ReliabilityPolicy.RELIABLE,
                       durability=DurabilityPolicy.TRANSIENT_LOCAL))
        self._timer = node.create_timer(WAIT_LOG, self._say_waiting)

    @property
    def topic(self) -> str:
        """The description's full topic name."""
        return self._subscription.topic_name

    def _say_waiting(self) -> None:
        if self.description is None:
            self.node.get_logger().info(f'waiting for the rod\'s description on {self.topic} '
                                        '(the simulator publishes it)')

    def _on_message(self, msg: String) -> None:
        try:
            simulators = read_description(msg.data)
        except DescriptionError as exc:
            self.node.get_logger().error(f'{exc}: not used; waiting for a readable one')
            return
        try:
            params = simulators.params.replace(**self.rod_overrides)
            limits = dataclasses.replace(simulators.limits, **self.limit_overrides)
        except ValueError as exc:
            self.node.get_logger().error(f'the rod parameters given to this node do not '
                                         f'make a rod with the simulator\'s: {exc}')
            return
        first = self.description is None
        self.simulators = simulators
        self.description = Description(params, limits, simulators.disk_radius)
        self._report(first)
        self._use(self.description)

    def _report(self, first: bool) -> None:
        assert self.simulators is not None and self.description is not None
        log = self.node.get_logger()
        changed = differences(self.simulators.params, self.description.params) + [
            f'{k}: {getattr(self.simulators.limits, k)!r} vs {v!r}'
            for k, v in self.limit_overrides.items()
            if getattr(self.simulators.limits, k) != v]
        if changed:
            log.warning(f'{self._what} uses parameters given to this node, not the '
                        f'simulator\'s ({self.topic}): ' + '; '.join(
                            f'{c} (simulator vs this node)' for c in changed))
        else:
            log.info(f'{self._what}: the simulator\'s rod from {self.topic}'
                     + ('' if first else ' (changed)'))


__all__ = ['LIMIT_FIELDS', 'ROD_FIELDS', 'RodSource', 'TOPIC', 'explicit_values',
           'interface']
