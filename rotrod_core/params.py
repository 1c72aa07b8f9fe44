"""Physical parameters of the rod, tip mass and hub, in SI units.

Defaults are the paper's Table 1 (Liu et al. 2014): m = 0.3 kg, l = 0.3 m, d = 3 mm,
E = 100 GPa, r0 = 0.1 m. Every field may also be a numpy array (all arrays broadcast
together) to describe a batch of systems for :func:`rotrod_core.simulate_batch`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

STEEL_DENSITY = 7850.0
"""Density of steel, kg/m^3 (used for the default hub)."""

DEFAULT_HUB_RADIUS = 0.15
"""Radius of the default hub disk, m (it must carry the rod at r0 = 0.1 m)."""

DEFAULT_HUB_THICKNESS = 0.01
"""Thickness of the default hub disk, m."""


def disk_inertia(radius: float, thickness: float, density: float = STEEL_DENSITY) -> float:
    """Rotary inertia of a solid disk about its axis, J = pi rho t R^4 / 2 (kg m^2).

    Args:
        radius: disk radius R in m.
        thickness: disk thickness t in m.
        density: material density rho in kg/m^3 (steel by default).
    """
    return 0.5 * math.pi * density * thickness * radius**4


DEFAULT_HUB_INERTIA = disk_inertia(DEFAULT_HUB_RADIUS, DEFAULT_HUB_THICKNESS)
"""Default hub inertia: a steel disk 0.15 m in radius and 10 mm thick (~0.0624 kg m^2)."""

SECTIONS = ('circular', 'rectangular')


def _check(name: str, value: Any, *, positive: bool = False, nonnegative: bool = False,
           optional: bool = False):
    """Validate one field: finite numbers (scalar or array), with a sign constraint."""
    if value is None:
        if optional:
            return None
        raise ValueError(f'RodParams.{name} is required (got None)')
    if isinstance(value, bool):
        raise ValueError(f'RodParams.{name} must be a number, got {value!r}')
    try:
        arr = np.asarray(value, dtype=float)
    except (TypeError, ValueError, OverflowError):
        raise ValueError(f'RodParams.{name} must be a number, got {value!r}') from None
    if arr.size == 0:
        raise ValueError(f'RodParams.{name} is empty')
    bad = ~np.isfinite(arr)
    if positive:
        bad |= ~(arr > 0)
        what = 'a finite number > 0'
    elif nonnegative:
        bad |= ~(arr >= 0)
        what = 'a finite number >= 0'
    else:
        what = 'a finite number'
    if np.any(bad):
        shown = arr.flat[int(np.argmax(bad.ravel()))] if arr.ndim else float(arr)
        raise ValueError(f'RodParams.{name} must be {what}, got {shown!r}')
    return float(arr) if arr.ndim == 0 else arr


@dataclass(frozen=True)
class RodParams:
    """A massless elastic rod with a tip mass, standing on a rigid rotating hub.

    All quantities in SI units. The rod stands parallel to the rotation axis with its
    root at radius ``eccentricity`` (r0). Deflection u is radial (e1), v tangential (e2).

    Attributes:
        mass: tip mass m, kg.
        rod_length: rod length l, m.
        rod_diameter: diameter d of a circular section, m.
        youngs_modulus: Young's modulus E, Pa.
        eccentricity: radius r0 of the rod root from the rotation axis, m.
        hub_inertia: rotary inertia J of the hub (disk) about the axis, kg m^2.
            Default: a steel disk 0.15 m x 10 mm (see :data:`DEFAULT_HUB_INERTIA`).
        damping_ratio: modal damping ratio zeta of the rod's bending (rotating
            damping on the relative deflection rate, c = 2 zeta sqrt(k m)); 0 = none.
        section: ``'circular'`` (uses rod_diameter) or ``'rectangular'``.
        section_width: rectangular section size b along e1 (radial), m.
        section_thickness: rectangular section size h along e2 (tangential), m.
    """

    mass: Any = 0.3
    rod_length: Any = 0.3
    rod_diameter: Any = 0.003
    youngs_modulus: Any = 100e9
    eccentricity: Any = 0.1
    hub_inertia: Any = DEFAULT_HUB_INERTIA
    damping_ratio: Any = 0.0
    section: str = 'circular'
    section_width: Any = None
    section_thickness: Any = None

    def __post_init__(self):
        set_ = object.__setattr__
        if self.section not in SECTIONS:
            raise ValueError(f'RodParams.section must be one of {SECTIONS}, got {self.section!r}')
        for name in ('mass', 'rod_length', 'youngs_modulus'):
            set_(self, name, _check(name, getattr(self, name), positive=True))
        for name in ('eccentricity', 'hub_inertia', 'damping_ratio'):
            set_(self, name, _check(name, getattr(self, name), nonnegative=True))
        if self.section == 'circular':
            set_(self, 'rod_diameter', _check('rod_diameter', self.rod_diameter, positive=True))
            for name in ('section_width', 'section_thickness'):
                if getattr(self, name) is not None:
                    raise ValueError(f"RodParams.{name} applies to section='rectangular' only")
        else:
            for name in ('section_width', 'section_thickness'):
                set_(self, name, _check(name, getattr(self, name), positive=True))
        try:
            np.broadcast_shapes(*(np.shape(v) for v in self._numeric().values()))
        except ValueError:
            shapes = {k: np.shape(v) for k, v in self._numeric().items() if np.shape(v)}
            raise ValueError(f'RodParams array fields do not broadcast: {shapes}') from None
        self._check_derived()

    def _check_derived(self):
        """Refuse fields whose derived quantities overflow, vanish (underflow) or are NaN.

        Each field may be finite and positive while d^4, 3 E I / l^3, k / m or
        sqrt(k m) is not: such a rod has no usable stiffness or natural frequency.
        """
        section = (('rod_diameter',) if self.section == 'circular'
                   else ('section_width', 'section_thickness'))
        stiffness = ('youngs_modulus', *section, 'rod_length')
        derived = (
            ('second_moment_radial', section, True),
            ('second_moment_tangential', section, True),
            ('stiffness_radial', stiffness, True),
            ('stiffness_tangential', stiffness, True),
            ('natural_frequency_radial', ('mass', *stiffness), True),
            ('natural_frequency_tangential', ('mass', *stiffness), True),
            ('damping_radial', ('damping_ratio', 'mass', *stiffness), False),
            ('damping_tangential', ('damping_ratio', 'mass', *stiffness), False),
        )
        with np.errstate(all='ignore'):
            ratios = {'k1 / m': self.stiffness_radial / self.mass,
                      'k2 / m': self.stiffness_tangential / self.mass}
            values = {name: getattr(self, name) for name, _, _ in derived}
        for name, fields, positive in derived:
            value = np.asarray(values[name], dtype=float)
            bad = ~np.isfinite(value) | ~((value > 0) if positive else (value >= 0))
            if np.any(bad):
                shown = value.flat[int(np.argmax(bad.ravel()))]
                given = ', '.join(f'{f}={getattr(self, f)!r}' for f in fields)
                raise ValueError(f'RodParams: {name} is {float(shown)!r}, not a finite number '
                                 f'{"> 0" if positive else ">= 0"} (overflow or underflow '
                                 f'of {given})')
        for name, ratio in ratios.items():
            if not np.all(np.isfinite(ratio) & (np.asarray(ratio) > 0)):
                given = ', '.join(f'{f}={getattr(self, f)!r}' for f in ('mass', *stiffness))
                raise ValueError(f'RodParams: {name} is not a finite number > 0 (overflow '
                                 f'or underflow of {given})')

    def _numeric(self) -> dict:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                if f.name != 'section' and getattr(self, f.name) is not None}

    def replace(self, **changes) -> RodParams:
        """Return a copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    @property
    def shape(self) -> tuple:
        """Broadcast shape of the array fields; () for a single system."""
        return np.broadcast_shapes(*(np.shape(v) for v in self._numeric().values()))

    @property
    def is_batch(self) -> bool:
        """True when any field is an array (a batch of systems)."""
        return self.shape != ()

    @property
    def is_isotropic(self) -> bool:
        """True when the rod is equally stiff radially and tangentially (k1 == k2)."""
        return bool(np.all(self.second_moment_radial == self.second_moment_tangential))

    @property
    def second_moment_radial(self):
        """Second moment of area I1 for bending in the radial direction e1, m^4."""
        if self.section == 'circular':
            return math.pi * np.asarray(self.rod_diameter) ** 4 / 64.0 + 0.0
        return self.section_thickness * np.asarray(self.section_width, dtype=float) ** 3 / 12.0

    @property
    def second_moment_tangential(self):
        """Second moment of area I2 for bending in the tangential direction e2, m^4."""
        if self.section == 'circular':
            return self.second_moment_radial
        return self.section_width * np.asarray(self.section_thickness, dtype=float) ** 3 / 12.0

    @property
    def second_moment(self):
        """Second moment of area I of an isotropic section, m^4 (pi d^4 / 64 if circular)."""
        self._require_isotropic('second_moment')
        return self.second_moment_radial

    @property
    def _length_cubed(self):
        """l^3 in m^3 (numpy: inf on overflow, where a Python float raises)."""
        return np.asarray(self.rod_length, dtype=float) ** 3

    @property
    def stiffness_radial(self):
        """Tip stiffness k1 = 3 E I1 / l^3 in the radial direction, N/m."""
        return 3.0 * self.youngs_modulus * self.second_moment_radial / self._length_cubed

    @property
    def stiffness_tangential(self):
        """Tip stiffness k2 = 3 E I2 / l^3 in the tangential direction, N/m."""
        return 3.0 * self.youngs_modulus * self.second_moment_tangential / self._length_cubed

    @property
    def stiffness(self):
        """Tip stiffness k = 3 E I / l^3 of an isotropic rod, N/m (44.178647 for Table 1)."""
        self._require_isotropic('stiffness')
        return self.stiffness_radial

    @property
    def natural_frequency_radial(self):
        """Non-rotating circular natural frequency sqrt(k1/m) of radial bending, rad/s."""
        return np.sqrt(self.stiffness_radial / self.mass) + 0.0

    @property
    def natural_frequency_tangential(self):
        """Non-rotating circular natural frequency sqrt(k2/m) of tangential bending, rad/s."""
        return np.sqrt(self.stiffness_tangential / self.mass) + 0.0

    @property
    def natural_frequency(self):
        """Circular natural frequency w0 = sqrt(k/m) of an isotropic rod, rad/s."""
        self._require_isotropic('natural_frequency')
        return self.natural_frequency_radial

    @property
    def damping_radial(self):
        """Viscous damping coefficient c1 = 2 zeta sqrt(k1 m) on u', N s/m."""
        # sqrt(k1) sqrt(m): k1 m may overflow where c1 does not (0 x inf: NaN)
        return 2.0 * self.damping_ratio * np.sqrt(self.stiffness_radial) * np.sqrt(self.mass)

    @property
    def damping_tangential(self):
        """Viscous damping coefficient c2 = 2 zeta sqrt(k2 m) on v', N s/m."""
        return (2.0 * self.damping_ratio * np.sqrt(self.stiffness_tangential)
                * np.sqrt(self.mass))

    def _require_isotropic(self, what: str):
        if not self.is_isotropic:
            raise ValueError(
                f'RodParams.{what} is undefined for a section with k1 != k2; use '
                f'{what}_radial / {what}_tangential')

    def item(self, index) -> RodParams:
        """The single system at ``index`` of a batch (fields broadcast first)."""
        shape = self.shape
        changes = {}
        for name, value in self._numeric().items():
            changes[name] = float(np.broadcast_to(value, shape)[index])
        return dataclasses.replace(self, **changes)
