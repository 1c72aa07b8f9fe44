"""How every node of the package declares its ROS parameters: one :class:`Spec` each.

A spec holds the parameter's name, default, description, SI unit, range (or choices)
and whether it can change at run time. :func:`declare` declares a node's specs with
a ``rcl_interfaces/ParameterDescriptor`` each (description with the unit, a
``FloatingPointRange`` or ``IntegerRange``, read-only where it cannot change), as
turtlesim does, and checks the values given; ``--help`` (:func:`help_lines`) and
``docs/nodes.md`` (:mod:`rotrod_ros.nodes_doc`) list the same specs.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

from rcl_interfaces.msg import FloatingPointRange, IntegerRange, ParameterDescriptor
from rclpy.exceptions import ParameterException
from rclpy.node import Node

from .node_main import ConfigurationError


@dataclass(frozen=True)
class Spec:
    """One parameter: name, default, description, unit, range, run-time changes.

    ``low`` and ``high`` bound a number, inclusive (None: no range); ``choices`` lists
    the values a string may take. The type is the default's (bool, int, float, str).
    """

    name: str
    default: Any
    text: str
    """What the parameter is, without its unit."""
    unit: str = ''
    """SI unit ('1' for a ratio; '' for a bool, a string or a choice)."""
    low: float | None = None
    high: float | None = None
    choices: tuple[str, ...] = ()
    read_only: bool = False
    """True: set at start only (a running node refuses a change)."""

    def __post_init__(self) -> None:
        if (self.low is None) != (self.high is None):
            raise ValueError(f'{self.name}: a range needs both ends')
        if self.bounds is not None and not self.bounds[0] <= self.default <= self.bounds[1]:
            raise ValueError(f'{self.name}: default {self.default!r} outside its range')
        if self.choices and self.default not in self.choices:
            raise ValueError(f'{self.name}: default {self.default!r} not among its choices')

    @property
    def bounds(self) -> tuple[float, float] | None:
        """(low, high), inclusive; None: no range."""
        if self.low is None or self.high is None:
            return None
        return self.low, self.high

    @property
    def description(self) -> str:
        """The text with the unit: 'tip mass m (> 0), kg'."""
        return f'{self.text}, {self.unit}' if self.unit else self.text

    @property
    def integer(self) -> bool:
        """Whether the parameter is an integer (its default is an int)."""
        return isinstance(self.default, int) and not isinstance(self.default, bool)

    @property
    def type_name(self) -> str:
        """The parameter's type: bool, integer, double or string."""
        if isinstance(self.default, bool):
            return 'bool'
        return 'integer' if self.integer else (
            'double' if isinstance(self.default, float) else 'string')


def descriptor(spec: Spec, read_only: bool | None = None) -> ParameterDescriptor:
    """The ROS parameter descriptor of ``spec``: description, range or choices.

    ``read_only`` overrides the spec's (a node whose parameters are all set at start).
    """
    d = ParameterDescriptor(name=spec.name, description=spec.description,
                            read_only=spec.read_only if read_only is None else read_only)
    bounds = spec.bounds
    if spec.choices:
        d.additional_constraints = 'one of: ' + ', '.join(spec.choices)
    elif bounds is not None and spec.integer:
        d.integer_range = [IntegerRange(from_value=int(bounds[0]), to_value=int(bounds[1]),
                                        step=0)]
    elif bounds is not None:
        d.floating_point_range = [FloatingPointRange(from_value=float(bounds[0]),
                                                     to_value=float(bounds[1]), step=0.0)]
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
    bounds = spec.bounds
    if bounds is not None and not bounds[0] <= value <= bounds[1]:
        raise ValueError(f'{spec.name} must be in [{bounds[0]:g}, {bounds[1]:g}], got {value!r}')


def declare(node: Node, specs: Iterable[Spec],
            read_only: bool | None = None) -> dict[str, Any]:
    """Declare ``specs`` on ``node`` (rclpy) with their descriptors; the values by name.

    A value given at start (``-p``, ``--params-file``) of the wrong type, out of
    range or not among the choices raises :class:`ConfigurationError` naming the
    parameter (the node exits with status 2).
    """
    values: dict[str, Any] = {}
    for spec in specs:
        try:
            value = node.declare_parameter(spec.name, spec.default,
                                           descriptor(spec, read_only)).value
            check_value(spec, value)
        except (ParameterException, ValueError) as exc:
            raise ConfigurationError(f'parameter {spec.name}: {exc}') from None
        values[spec.name] = value
    return values


def format_value(value: Any) -> str:
    """A default or range end as written in the help and docs (floats with %g)."""
    if isinstance(value, bool):
        return str(value).lower()
    if isinstance(value, float):
        return f'{value:.6g}'
    return repr(value) if isinstance(value, str) else str(value)


def range_text(spec: Spec) -> str:
    """'[low, high]', 'a | b' for choices, or ''."""
    if spec.choices:
        return ' | '.join(spec.choices)
    if spec.bounds is None:
        return ''
    return f'[{format_value(spec.bounds[0])}, {format_value(spec.bounds[1])}]'


def help_lines(specs: Iterable[Spec], read_only: bool | None = None) -> list[str]:
    """One line per spec for ``--help``: name, text, then unit, range, default."""
    out = []
    for s in specs:
        fixed = s.read_only if read_only is None else read_only
        facts = [s.unit, ('one of ' if s.choices else 'in ') + range_text(s)
                 if range_text(s) else '', f'default {format_value(s.default)}',
                 'read-only' if fixed else '']
        out.append(f'  {s.name}: {s.text} [{", ".join(f for f in facts if f)}]')
    return out
