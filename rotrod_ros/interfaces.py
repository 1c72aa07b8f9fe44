"""A node's topics and services, written once in a table.

The node creates them from its table, and ``--help`` and ``docs/nodes.md``
(:mod:`rotrod_ros.nodes_doc`) list them from it.

Names without a leading ``/`` are relative to the node's namespace; ``~/`` is the
node's own (``<namespace>/<node name>/``).
"""

from __future__ import annotations

from dataclasses import dataclass

PUBLISHER, SUBSCRIPTION, SERVICE = 'pub', 'sub', 'srv'


@dataclass(frozen=True)
class Interface:
    """One topic the node publishes or subscribes to, or a service it offers."""

    kind: str
    """PUBLISHER, SUBSCRIPTION or SERVICE."""
    name: str
    type: type
    """The message or service class."""
    description: str
    """What it carries, with units."""
    depth: int = 10
    """History depth of a topic's QoS (reliable, volatile: rclpy's default)."""

    def __post_init__(self):
        if self.kind not in (PUBLISHER, SUBSCRIPTION, SERVICE):
            raise ValueError(f'{self.name}: kind must be pub, sub or srv, got {self.kind!r}')

    @property
    def type_name(self) -> str:
        """'package/Type' of the message or service, e.g. 'std_msgs/Float64'."""
        return f'{self.type.__module__.split(".")[0]}/{self.type.__name__}'


def pub(name: str, msg_type: type, description: str, depth: int = 10) -> Interface:
    """A topic the node publishes."""
    return Interface(PUBLISHER, name, msg_type, description, depth)


def sub(name: str, msg_type: type, description: str, depth: int = 10) -> Interface:
    """A topic the node subscribes to."""
    return Interface(SUBSCRIPTION, name, msg_type, description, depth)


def srv(name: str, srv_type: type, description: str) -> Interface:
    """A service the node offers."""
    return Interface(SERVICE, name, srv_type, description)


def create(node, interfaces, callbacks: dict | None = None) -> dict:
    """Create ``interfaces`` on ``node`` (rclpy); return them by name.

    ``callbacks`` holds each subscription's and service's callback, by name.
    """
    callbacks = callbacks or {}
    made = {}
    for i in interfaces:
        if i.kind == PUBLISHER:
            made[i.name] = node.create_publisher(i.type, i.name, i.depth)
        elif i.kind == SUBSCRIPTION:
            made[i.name] = node.create_subscription(i.type, i.name, callbacks[i.name], i.depth)
        else:
            made[i.name] = node.create_service(i.type, i.name, callbacks[i.name])
    unused = set(callbacks) - set(made)
    if unused:
        raise ValueError(f'callbacks for interfaces not in the table: {sorted(unused)}')
    return made


def help_lines(interfaces) -> list:
    """``--help`` lines: the interfaces by kind, with type and content."""
    out = []
    for kind, title in ((SUBSCRIPTION, 'Subscriptions'), (PUBLISHER, 'Publications'),
                        (SERVICE, 'Services')):
        rows = [i for i in interfaces if i.kind == kind]
        if rows:
            out.append(f'{title}:')
            out += [f'  {i.name}  {i.type_name}  {i.description}' for i in rows]
    return out
