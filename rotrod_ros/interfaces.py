"""A node's topics and services, written once in a table.

The node creates them from its table, and ``--help`` and ``docs/nodes.md``
(:mod:`rotrod_ros.nodes_doc`) list them from it.

Names without a leading ``/`` are relative to the node's namespace; ``~/`` is the
node's own (``<namespace>/<node name>/``).
"""

from __future__ import annotations

from dataclasses import dataclass

PUBLISHER, SUBSCRIPTION, SERVICE, ACTION = 'pub', 'sub', 'srv', 'action'
CLIENT, ACTION_CLIENT = 'client', 'action client'
"""A service or action another node serves, which this one calls."""
ALWAYS = 'always'
"""Interface.keep_all: KEEP_ALL history whatever the node's settings."""


@dataclass(frozen=True)
class Interface:
    """A topic the node publishes or subscribes to, a service or action it serves or calls.

    The name of a client may hold ``{placeholders}`` that the node fills in (see
    :func:`create`), e.g. ``{simulator}/step_simulation``.
    """

    kind: str
    """PUBLISHER, SUBSCRIPTION, SERVICE, ACTION, CLIENT or ACTION_CLIENT."""
    name: str
    type: type
    """The message or service class."""
    description: str
    """What it carries, with units."""
    depth: int = 10
    """History depth of a topic's QoS (reliable, volatile: rclpy's default)."""
    keep_all: str = ''
    """When the topic has KEEP_ALL history instead of the last ``depth`` messages:
    '' never, ALWAYS, or a condition the node names when it creates its interfaces
    (see :func:`create`). Reliable and KEEP_ALL on both sides, nothing is dropped: a
    subscriber that falls behind stops acknowledging, and the publisher's publish
    blocks (rmw_fastrtps: 100 ms, then fails) until it catches up."""
    transient_local: bool = False
    """Durability transient local: a subscriber that comes later still gets the last
    ``depth`` messages (a description, as robot_state_publisher's robot_description)."""

    def __post_init__(self):
        if self.kind not in (PUBLISHER, SUBSCRIPTION, SERVICE, ACTION, CLIENT, ACTION_CLIENT):
            raise ValueError(f'{self.name}: kind must be pub, sub, srv, action, client or '
                             f'action client, got {self.kind!r}')

    @property
    def type_name(self) -> str:
        """'package/Type' of the message or service, e.g. 'std_msgs/Float64'."""
        return f'{self.type.__module__.split(".")[0]}/{self.type.__name__}'


def pub(name: str, msg_type: type, description: str, depth: int = 10,
        keep_all: str = '', transient_local: bool = False) -> Interface:
    """A topic the node publishes."""
    return Interface(PUBLISHER, name, msg_type, description, depth, keep_all, transient_local)


def sub(name: str, msg_type: type, description: str, depth: int = 10,
        keep_all: str = '', transient_local: bool = False) -> Interface:
    """A topic the node subscribes to."""
    return Interface(SUBSCRIPTION, name, msg_type, description, depth, keep_all,
                     transient_local)


def srv(name: str, srv_type: type, description: str, depth: int = 10) -> Interface:
    """A service the node offers (``depth``: the requests its queue holds)."""
    return Interface(SERVICE, name, srv_type, description, depth)


def action(name: str, action_type: type, description: str) -> Interface:
    """An action the node serves."""
    return Interface(ACTION, name, action_type, description)


def client(name: str, srv_type: type, description: str) -> Interface:
    """A service the node calls."""
    return Interface(CLIENT, name, srv_type, description)


def action_client(name: str, action_type: type, description: str) -> Interface:
    """An action the node sends goals to."""
    return Interface(ACTION_CLIENT, name, action_type, description)


def qos(interface: Interface, conditions=()):
    """The topic's QoS (reliable, volatile), or its depth for rclpy's default.

    KEEP_ALL history if its ``keep_all`` is ALWAYS or in ``conditions``, else the last
    ``depth`` messages; transient local if the interface says so.
    """
    from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
    if interface.transient_local:
        return QoSProfile(depth=interface.depth, reliability=ReliabilityPolicy.RELIABLE,
                          durability=DurabilityPolicy.TRANSIENT_LOCAL)
    if interface.keep_all and (interface.keep_all == ALWAYS
                               or interface.keep_all in conditions):
        return QoSProfile(history=HistoryPolicy.KEEP_ALL, depth=interface.depth,
                          reliability=ReliabilityPolicy.RELIABLE)
    return interface.depth


def _service_qos(depth: int):
    """The services QoS of rclpy (reliable, volatile) with a queue of ``depth`` requests."""
    from rclpy.qos import QoSProfile, qos_profile_services_default
    return QoSProfile(history=qos_profile_services_default.history, depth=depth,
                      reliability=qos_profile_services_default.reliability,
                      durability=qos_profile_services_default.durability)


def create(node, interfaces, callbacks: dict | None = None, conditions=(),
           callback_groups: dict | None = None, names: dict | None = None) -> dict:
    """Create ``interfaces`` on ``node`` (rclpy); return them by name.

    ``callbacks`` holds each subscription's and service's callback, by name, and each
    action's ActionServer keyword arguments (execute_callback, ...); ``conditions`` the
    ``keep_all`` conditions that hold (see :func:`qos`); ``callback_groups`` a service's
    callback group by name (default: the node's); ``names`` the values of the
    placeholders in clients' names. The result is keyed by the names in the table.
    """
    groups = callback_groups or {}
    fill = names or {}
    callbacks = callbacks or {}
    made = {}
    for i in interfaces:
        if i.kind == PUBLISHER:
            made[i.name] = node.create_publisher(i.type, i.name, qos(i, conditions))
        elif i.kind == SUBSCRIPTION:
            made[i.name] = node.create_subscription(i.type, i.name, callbacks[i.name],
                                                    qos(i, conditions))
        elif i.kind == SERVICE:
            made[i.name] = node.create_service(i.type, i.name, callbacks[i.name],
                                               qos_profile=_service_qos(i.depth),
                                               callback_group=groups.get(i.name))
        elif i.kind == CLIENT:
            made[i.name] = node.create_client(i.type, i.name.format(**fill))
        elif i.kind == ACTION_CLIENT:
            from rclpy.action import ActionClient
            made[i.name] = ActionClient(node, i.type, i.name.format(**fill))
        else:
            from rclpy.action import ActionServer
            made[i.name] = ActionServer(node, i.type, i.name, **callbacks[i.name])
    unused = set(callbacks) - set(made)
    if unused:
        raise ValueError(f'callbacks for interfaces not in the table: {sorted(unused)}')
    return made


def help_lines(interfaces) -> list:
    """``--help`` lines: the interfaces by kind, with type and content."""
    out = []
    for kind, title in ((SUBSCRIPTION, 'Subscriptions'), (PUBLISHER, 'Publications'),
                        (SERVICE, 'Services'), (ACTION, 'Actions'),
                        (CLIENT, 'Services called'), (ACTION_CLIENT, 'Actions called')):
        rows = [i for i in interfaces if i.kind == kind]
        if rows:
            out.append(f'{title}:')
            out += [f'  {i.name}  {i.type_name}  {i.description}' for i in rows]
    return out


def take(subscription):
    """Take a message from ``subscription`` now, as rclpy's executor takes it.

    Returns (message, info), or None: nothing there, or the subscription or its
    context is gone.
    """
    try:
        with subscription.handle:
            return subscription.handle.take_message(subscription.msg_type, subscription.raw)
    except Exception:  # the subscription or its context is gone
        return None
