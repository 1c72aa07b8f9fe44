"""The rod's description: its physical parameters inside the URDF, written and read back.

ROS tools describe a robot by its URDF, published as ``robot_description`` (a
transient-local topic): robot_state_publisher reads its joints, RViz its visuals. A
simulator's own properties ride in an element of its own that other tools ignore, as
Gazebo's ``<gazebo>``; rotrod's is ``<rotrod>``::

    <rotrod version="1">
      <rod mass="0.3" rod_length="0.3" ... />        every RodParams field, SI units
      <drive max_angular_acceleration="0.5" max_omega="50.0" max_torque="100.0"
             deflection_limit="0.003"/>              the simulator's limits
    </rotrod>

The simulator publishes the URDF of its own parameters (:func:`rotrod_core.model.urdf.
urdf_text`) and every node that needs the rod reads it back here
(:func:`read_description`), so the rod is given once. A description that cannot be
read raises :class:`DescriptionError` naming the element and the field: no node plans
for a rod it guessed. Floats are written as the shortest text that reads back as the
same double, so the rod read back is the simulator's bit for bit.

Model: docs/usage.md#robot-description.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from xml.etree import ElementTree

from rotrod_core.model.interface import ROTOR_FRAME
from rotrod_core.model.params import FIELDS, RodParams

ELEMENT = 'rotrod'
"""The URDF element that carries rotrod's description."""
VERSION = '1'
"""The version of the element's contents this code writes and reads."""


class DescriptionError(ValueError):
    """A robot description that does not describe a rod (the reason names the field)."""


@dataclass(frozen=True)
class DriveLimits:
    """The simulator's limits that a command must stay within (SI units).

    Attributes:
        max_angular_acceleration: largest |w'| the velocity drive follows, rad/s^2.
        max_omega: largest |w|, rad/s.
        max_torque: largest |Q| of the torque drive, N m.
        deflection_limit: the critical deflection it alarms at, m (the paper's 3 mm).
    """

    max_angular_acceleration: float
    max_omega: float
    max_torque: float
    deflection_limit: float

    def __post_init__(self):
        for f in dataclasses.fields(self):
            value = getattr(self, f.name)
            if isinstance(value, bool) or not isinstance(value, (int, float)) or not (
                    math.isfinite(value) and value > 0):
                raise ValueError(f'DriveLimits.{f.name} must be a finite number > 0, got '
                                 f'{value!r}')


DEFAULT_LIMITS = DriveLimits(max_angular_acceleration=0.5, max_omega=50.0, max_torque=100.0,
                             deflection_limit=0.003)
"""The simulator's limits unless configured (its parameters' defaults): |w'| <= 0.5
rad/s^2 (the paper's Eq. 26 peaks at 0.27; 0.5 bends Table 1's rod back by 0.34 mm),
|w| <= 50 rad/s, |Q| <= 100 N m, and the paper's 3 mm critical deflection."""


@dataclass(frozen=True)
class Description:
    """What a robot description says of the rod: its parameters and the drive's limits.

    ``disk_radius`` is the drawn disk's (m: the ``rotor`` link's cylinder), None if the
    URDF draws none.
    """

    params: RodParams
    limits: DriveLimits
    disk_radius: float | None = None


def _num(x) -> str:
    """A float as the shortest text that reads back as the same double."""
    return repr(float(x))


def _attributes(values: dict, pad: str) -> str:
    """``name="value"`` pairs, one per line after the first, aligned under ``pad``."""
    return f'\n{pad}'.join(f'{k}="{v}"' for k, v in values.items())


def description_element(params: RodParams, limits: DriveLimits, indent: str = '  ') -> str:
    """The ``<rotrod>`` element of ``params`` and ``limits`` (XML text, indented)."""
    rod = {}
    for info in FIELDS:
        value = getattr(params, info.name)
        if value is None:
            continue                         # a section size the section does not use
        rod[info.name] = value if info.choices else _num(value)
    drive = {f.name: _num(getattr(limits, f.name)) for f in dataclasses.fields(limits)}
    pad = indent + '  '
    return (f'{indent}<{ELEMENT} version="{VERSION}">\n'
            f'{pad}<!-- the rod\'s physical parameters (SI units) and the simulator\'s limits,\n'
            f'{pad}     read by rotrod\'s nodes; other tools ignore this element -->\n'
            f'{pad}<rod {_attributes(rod, pad + "     ")}/>\n'
            f'{pad}<drive {_attributes(drive, pad + "       ")}/>\n'
            f'{indent}</{ELEMENT}>\n')


def _element(parent, tag: str, where: str):
    found = parent.find(tag)
    if found is None:
        raise DescriptionError(f'robot_description: {where} has no <{tag}> element')
    return found


def _number(element, name: str, where: str) -> float:
    text = element.get(name)
    if text is None:
        raise DescriptionError(f'robot_description: {where} has no attribute {name!r}')
    try:
        return float(text)
    except ValueError:
        raise DescriptionError(f'robot_description: {where} {name}={text!r} is not a '
                               'number') from None


def read_description(text: str) -> Description:
    """The rod and limits of a URDF with a ``<rotrod>`` element; :class:`DescriptionError`.

    Every field of the rod must be there (the section sizes only for a rectangular
    section), each a number that RodParams accepts, and every limit a number > 0.
    """
    if not isinstance(text, str) or not text.strip():
        raise DescriptionError('robot_description is empty')
    try:
        root = ElementTree.fromstring(text)
    except ElementTree.ParseError as exc:
        raise DescriptionError(f'robot_description is not XML: {exc}') from None
    if root.tag != 'robot':
        raise DescriptionError(f'robot_description: the root element is <{root.tag}>, not '
                               '<robot> (a URDF)')
    found = _element(root, ELEMENT, '<robot>')
    if found.get('version') != VERSION:
        raise DescriptionError(f'robot_description: <{ELEMENT}> version '
                               f'{found.get("version")!r}, this rotrod reads {VERSION!r}')
    rod = _element(found, 'rod', f'<{ELEMENT}>')
    section = rod.get('section')
    where = f'<{ELEMENT}><rod>'
    if section is None:
        raise DescriptionError(f'robot_description: {where} has no attribute \'section\'')
    values: dict = {'section': section}
    for info in FIELDS:
        if info.choices or (info.section and info.section != section):
            continue
        values[info.name] = _number(rod, info.name, where)
    try:
        params = RodParams(**values)
    except ValueError as exc:
        raise DescriptionError(f'robot_description: {where}: {exc}') from None
    drive = _element(found, 'drive', f'<{ELEMENT}>')
    where = f'<{ELEMENT}><drive>'
    try:
        limits = DriveLimits(**{f.name: _number(drive, f.name, where)
                                for f in dataclasses.fields(DriveLimits)})
    except ValueError as exc:
        raise DescriptionError(f'robot_description: {where}: {exc}') from None
    return Description(params, limits, _disk_radius(root))


def _disk_radius(root) -> float | None:
    """The radius of the ``rotor`` link's drawn cylinder, m (None: none, or unreadable)."""
    for link in root.iter('link'):
        if link.get('name') == ROTOR_FRAME:
            cylinder = link.find('visual/geometry/cylinder')
            try:
                radius = float(cylinder.get('radius')) if cylinder is not None else None
            except (TypeError, ValueError):
                return None
            return radius if radius is not None and math.isfinite(radius) and radius > 0 \
                else None
    return None


def differences(a: RodParams, b: RodParams) -> list[str]:
    """The fields in which two rods differ, as ``name: a vs b`` (empty: the same rod)."""
    out = []
    for info in FIELDS:
        x, y = getattr(a, info.name), getattr(b, info.name)
        if x != y:
            out.append(f'{info.name}: {x!r} vs {y!r}')
    return out


__all__ = ['DEFAULT_LIMITS', 'Description', 'DescriptionError', 'DriveLimits', 'ELEMENT',
           'VERSION',
           'description_element', 'differences', 'read_description']
