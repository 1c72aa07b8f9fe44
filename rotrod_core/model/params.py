"""Physical parameters of the rod, tip mass and hub, in SI units.

Defaults are the paper's Table 1 (Liu et al. 2014): m = 0.3 kg, l = 0.3 m, d = 3 mm,
E = 100 GPa, r0 = 0.1 m, a massless rod without gravity. Every field may also be a
numpy array (all arrays broadcast together) to describe a batch of systems for
:func:`rotrod_core.simulate_batch`.

A real rig (``docs/real_rig.md``): ``gravity`` loads the rod axially with the tip
mass's weight (compression when it stands, tension when it hangs), which changes its
lateral stiffness; ``rod_density`` gives the rod its own mass, taken into account by
a one-mode Rayleigh-Ritz model. The effective quantities (:attr:`RodParams.modal_mass`,
:attr:`RodParams.eccentric_mass`, :attr:`RodParams.stiffness_radial`, ...) are what the
equations use, through :class:`rotrod_core.model.equations.Coefficients`.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rotrod_core.model.beam import (
    SHAPE_LOAD,
    SHAPE_MASS,
    SHAPE_SELF_WEIGHT,
    buckling_ratio,
    ritz_bending_frequencies,
    tip_load_stiffness_ratio,
)

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



@dataclass(frozen=True)
class FieldInfo:
    """What a :class:`RodParams` field is: its unit, description and range, defined once.

    The nodes' parameters and the CLI's options are made from it.

    Attributes:
        name: the field's name.
        default: its default (None: unused unless ``section`` says otherwise).
        unit: SI unit ('1' for a ratio, '' for a choice).
        description: what it is, without the unit.
        low, high: the range a front end offers (inclusive; None: no range). The
            physical checks are :class:`RodParams`' own, e.g. ``sign``.
        sign: 'positive' (> 0), 'nonnegative' (>= 0) or '' (any finite number),
            checked by :class:`RodParams`.
        section: the cross-section the field applies to ('' for any).
        choices: the allowed values of a choice ('section').
    """

    name: str
    default: Any
    unit: str
    description: str
    low: float | None = None
    high: float | None = None
    sign: str = ''
    section: str = ''
    choices: tuple = ()


_INFO = 'rotrod'
"""Key of a RodParams field's metadata: the keyword arguments of its FieldInfo."""


def _field(default, unit: str, description: str, low=None, high=None, **info):
    """A RodParams field with its :class:`FieldInfo` in the metadata."""
    return field(default=default, metadata={_INFO: dict(
        unit=unit, description=description, low=low, high=high, **info)})


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
    """An elastic rod with a tip mass, standing on a rigid rotating hub.

    All quantities in SI units. The rod stands parallel to the rotation axis with its
    root at radius ``eccentricity`` (r0). Deflection u is radial (e1), v tangential (e2).
    By default (the paper) the rod is massless and there is no gravity.

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
        gravity: acceleration of gravity g along the rod, m/s^2; 0 = none (the
            paper). Positive: the rod stands upright with the mass on top, its weight
            m g compresses the rod and softens it sideways; negative: the rod hangs
            from the hub and the weight m |g| stretches (stiffens) it. Compression
            at or beyond the Euler buckling load pi^2 E I / (4 l^2) is refused.
        rod_density: density rho of the rod's material, kg/m^3; 0 = a massless rod
            (the paper). The rod's mass rho A l enters through a one-mode
            Rayleigh-Ritz model (:attr:`modal_mass`, :attr:`eccentric_mass`), and
            with ``gravity`` its own weight adds the geometric stiffness
            -(3/8) rho A g (a Rayleigh estimate with the unloaded shape).

    Model: docs/model.md#table-1.
    """

    mass: Any = _field(0.3, 'kg', 'tip mass m', 0.0, 1e4, sign='positive')
    rod_length: Any = _field(0.3, 'm', 'rod length l', 0.0, 100.0, sign='positive')
    rod_diameter: Any = _field(0.003, 'm', 'rod diameter d of a circular section', 0.0, 10.0,
                               sign='positive', section='circular')
    youngs_modulus: Any = _field(100e9, 'Pa', "Young's modulus E", 0.0, 1e13, sign='positive')
    eccentricity: Any = _field(0.1, 'm', 'radius r0 of the rod root from the rotation axis',
                               0.0, 100.0, sign='nonnegative')
    hub_inertia: Any = _field(DEFAULT_HUB_INERTIA, 'kg m^2',
                              'rotary inertia J of the hub (disk) about the axis (> 0 for the '
                              'exact coupling)', 0.0, 1e9, sign='nonnegative')
    damping_ratio: Any = _field(0.0, '1', 'modal damping ratio zeta of the bending '
                                '(rotating damping)', 0.0, 10.0, sign='nonnegative')
    section: str = _field('circular', '', 'rod cross-section', choices=SECTIONS)
    section_width: Any = _field(None, 'm', 'rectangular section size b along e1 (radial)',
                                0.0, 10.0, sign='positive', section='rectangular')
    section_thickness: Any = _field(None, 'm', 'rectangular section size h along e2 '
                                    '(tangential)', 0.0, 10.0, sign='positive',
                                    section='rectangular')
    gravity: Any = _field(0.0, 'm/s^2', 'gravity along the rod: > 0 the rod stands up with '
                          'the mass on top (its weight compresses and softens it), < 0 it '
                          'hangs (tension stiffens it), 0 = the paper; compression at or past '
                          'buckling is refused', -1e3, 1e3)
    rod_density: Any = _field(0.0, 'kg/m^3', "density of the rod's material (one-mode "
                              'Rayleigh-Ritz: modal mass m + 33/140 rho A l); 0 = massless, '
                              'the paper', 0.0, 1e5, sign='nonnegative')

    def __post_init__(self):
        set_ = object.__setattr__
        if self.section not in SECTIONS:
            raise ValueError(f'RodParams.section must be one of {SECTIONS}, got {self.section!r}')
        for info in FIELDS:
            if info.choices:
                continue
            value = getattr(self, info.name)
            if info.section and info.section != self.section:
                if info.default is None and value is not None:
                    raise ValueError(f"RodParams.{info.name} applies to "
                                     f"section='{info.section}' only")
                continue
            set_(self, info.name, _check(info.name, value, positive=info.sign == 'positive',
                                         nonnegative=info.sign == 'nonnegative'))
        try:
            np.broadcast_shapes(*(np.shape(v) for v in self._numeric().values()))
        except ValueError:
            shapes = {k: np.shape(v) for k, v in self._numeric().items() if np.shape(v)}
            raise ValueError(f'RodParams array fields do not broadcast: {shapes}') from None
        self._check_buckling()
        self._check_derived()

    def _check_buckling(self):
        """Refuse a tip load m g at or beyond the rod's Euler buckling load.

        Then the rod's own weight (Rayleigh estimate): it must leave a positive
        lateral stiffness in both directions.
        """
        with np.errstate(all='ignore'):
            load = np.asarray(self.tip_load, dtype=float)
            for direction in ('radial', 'tangential'):
                critical = np.asarray(getattr(self, f'buckling_load_{direction}'))
                bad = (load > 0) & (load >= critical)
                if np.any(bad):
                    i = int(np.argmax(np.broadcast_to(bad, np.broadcast(load, critical).shape
                                                      ).ravel()))
                    p = float(np.broadcast_to(load, bad.shape).ravel()[i])
                    pc = float(np.broadcast_to(critical, bad.shape).ravel()[i])
                    g = float(np.broadcast_to(np.asarray(self.gravity), bad.shape).ravel()[i])
                    raise ValueError(
                        f'RodParams.gravity = {g!r} m/s^2: the tip load m g = {p:.6g} N '
                        f'is at or beyond the Euler buckling load pi^2 E I / (4 l^2) = '
                        f'{pc:.6g} N of the rod ({direction} bending); it cannot stand '
                        f'upright (use gravity < 0 for a hanging rod)')
        if np.any(np.asarray(self.rod_density) > 0) and np.any(np.asarray(self.gravity) > 0):
            for direction in ('radial', 'tangential'):
                with np.errstate(all='ignore'):
                    k = np.asarray(getattr(self, f'stiffness_{direction}'), dtype=float)
                if np.any(np.isfinite(k) & ~(k > 0)):
                    shown = float(k.ravel()[int(np.argmax((np.isfinite(k) & ~(k > 0)).ravel()))])
                    raise ValueError(
                        f'RodParams.gravity = {self.gravity!r} m/s^2 with rod_density = '
                        f'{self.rod_density!r} kg/m^3: the tip load and the rod\'s own '
                        f'weight buckle the rod (stiffness_{direction} = {shown:.6g} N/m, '
                        f'not > 0; Rayleigh estimate of the self-weight)')

    def _check_derived(self):
        """Refuse fields whose derived quantities overflow, vanish (underflow) or are NaN.

        Each field may be finite and positive while d^4, 3 E I / l^3, k / m or
        sqrt(k m) is not: such a rod has no usable stiffness or natural frequency.
        """
        section = (('rod_diameter',) if self.section == 'circular'
                   else ('section_width', 'section_thickness'))
        stiffness = ('youngs_modulus', *section, 'rod_length', 'mass', 'gravity',
                     'rod_density')
        masses = ('mass', 'rod_density', *section, 'rod_length')
        derived = (
            ('second_moment_radial', section, True),
            ('second_moment_tangential', section, True),
            ('modal_mass', masses, True),
            ('eccentric_mass', masses, True),
            ('stiffness_radial', stiffness, True),
            ('stiffness_tangential', stiffness, True),
            ('natural_frequency_radial', stiffness, True),
            ('natural_frequency_tangential', stiffness, True),
            ('damping_radial', ('damping_ratio', *stiffness), False),
            ('damping_tangential', ('damping_ratio', *stiffness), False),
        )
        with np.errstate(all='ignore'):
            ratios = {'k1 / M': self.stiffness_radial / self.modal_mass,
                      'k2 / M': self.stiffness_tangential / self.modal_mass}
            values = {name: getattr(self, name) for name, _, _ in derived}
        for name, fields, positive in derived:
            value = np.asarray(values[name], dtype=float)
            bad = ~np.isfinite(value) | ~((value > 0) if positive else (value >= 0))
            if np.any(bad):
                shown = value.flat[int(np.argmax(bad.ravel()))]
                given = self._given(fields)
                raise ValueError(f'RodParams: {name} is {float(shown)!r}, not a finite number '
                                 f'{"> 0" if positive else ">= 0"} (overflow or underflow '
                                 f'of {given})')
        for name, ratio in ratios.items():
            if not np.all(np.isfinite(ratio) & (np.asarray(ratio) > 0)):
                given = self._given(stiffness)
                raise ValueError(f'RodParams: {name} is not a finite number > 0 (overflow '
                                 f'or underflow of {given})')

    def _given(self, fields) -> str:
        """'name=value, ...' of ``fields``, leaving out gravity and rod_density when 0."""
        shown = [f for f in fields if f not in ('gravity', 'rod_density')
                 or np.any(np.asarray(getattr(self, f)) != 0)]
        return ', '.join(f'{f}={getattr(self, f)!r}' for f in shown)

    def _numeric(self) -> dict[str, Any]:
        return {f.name: getattr(self, f.name) for f in dataclasses.fields(self)
                if f.name != 'section' and getattr(self, f.name) is not None}

    def replace(self, **changes) -> RodParams:
        """Return a copy with some fields changed (validated again)."""
        return dataclasses.replace(self, **changes)

    @property
    def shape(self) -> tuple[int, ...]:
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
    def section_area(self):
        """Cross-section area A of the rod, m^2 (pi d^2 / 4, or b h)."""
        if self.section == 'circular':
            return math.pi * np.asarray(self.rod_diameter, dtype=float) ** 2 / 4.0 + 0.0
        return np.asarray(self.section_width, dtype=float) * self.section_thickness + 0.0

    @property
    def rod_mass(self):
        """Mass of the rod rho A l, kg (0 for the paper's massless rod)."""
        return self.rod_density * self.section_area * np.asarray(self.rod_length, dtype=float)

    @property
    def modal_mass(self):
        """Modal (effective) mass M = m + (33/140) rho A l of the bending mode, kg.

        The integral of phi^2 over the rod, phi(xi) = (3 xi^2 - xi^3) / 2 the static
        cantilever shape (tip = 1). Exactly ``mass`` for a massless rod.
        """
        return self.mass + SHAPE_MASS * self.rod_mass

    @property
    def eccentric_mass(self):
        """Mass m + (3/8) rho A l that the eccentric loads act on, kg.

        The centrifugal load w^2 r0 and the tangential load -w' r0 of the undeflected
        rod, projected on the mode (the integral of phi). Exactly ``mass`` for a
        massless rod.
        """
        return self.mass + SHAPE_LOAD * self.rod_mass

    @property
    def load_radius(self):
        """The load radius re = (Me / M) r0, m.

        The eccentric loads' radius per unit modal mass (w^2 re drives the bending
        mode); exactly ``eccentricity`` for a massless rod (docs/real_rig.md).
        """
        return self.eccentricity * (self.eccentric_mass / self.modal_mass)

    @property
    def tip_load(self):
        """Axial load of the tip mass on the rod, P = m g, N (> 0 compression)."""
        return self.mass * np.asarray(self.gravity, dtype=float) + 0.0

    def _flexural_rigidity(self, direction: str):
        return self.youngs_modulus * getattr(self, f'second_moment_{direction}')

    def _buckling_load(self, direction: str):
        return (buckling_ratio() * self._flexural_rigidity(direction)
                / np.asarray(self.rod_length, dtype=float) ** 2)

    @property
    def buckling_load_radial(self):
        """Euler buckling load pi^2 E I1 / (4 l^2) of the cantilever (radial bending), N."""
        return self._buckling_load('radial')

    @property
    def buckling_load_tangential(self):
        """Euler buckling load pi^2 E I2 / (4 l^2) of the cantilever (tangential bending), N."""
        return self._buckling_load('tangential')

    @property
    def buckling_load(self):
        """The lower Euler buckling load pi^2 E min(I1, I2) / (4 l^2), N (10.9 for Table 1)."""
        return np.minimum(self.buckling_load_radial, self.buckling_load_tangential)

    def _bending_stiffness(self, direction: str):
        return (3.0 * self.youngs_modulus * getattr(self, f'second_moment_{direction}')
                / self._length_cubed)

    @property
    def bending_stiffness_radial(self):
        """Tip stiffness 3 E I1 / l^3 of the unloaded rod (radial), N/m: the paper's k.

        Model: docs/model.md#eq-stiffness.
        """
        return self._bending_stiffness('radial')

    @property
    def bending_stiffness_tangential(self):
        """Tip stiffness 3 E I2 / l^3 of the unloaded rod (tangential), N/m."""
        return self._bending_stiffness('tangential')

    def _stiffness(self, direction: str):
        base = self._bending_stiffness(direction)
        gravity = np.asarray(self.gravity, dtype=float)
        if not np.any(gravity != 0):
            return base             # the paper: bit for bit 3 E I / l^3
        y = self.tip_load * np.asarray(self.rod_length, dtype=float) ** 2 / \
            self._flexural_rigidity(direction)
        weight = SHAPE_SELF_WEIGHT * self.rod_density * self.section_area * gravity
        return base * tip_load_stiffness_ratio(y) - weight

    @property
    def stiffness_radial(self):
        """Lateral tip stiffness k1 in the radial direction, N/m.

        3 E I1 / l^3 without gravity (44.178647 for Table 1). With gravity, the exact
        stiffness of a cantilever under the axial tip load P = m g,
        P / (tan(kappa l) / kappa - l) in compression, |P| / (l - tanh(kappa l) / kappa)
        in tension, kappa = sqrt(|P| / E I1) (32.37 N/m for Table 1 at g = 9.81),
        minus (3/8) rho A g for the rod's own weight (Rayleigh, unloaded shape).
        """
        return self._stiffness('radial')

    @property
    def stiffness_tangential(self):
        """Lateral tip stiffness k2 in the tangential direction, N/m (as k1, with I2)."""
        return self._stiffness('tangential')

    @property
    def stiffness(self):
        """Tip stiffness k of an isotropic rod, N/m (44.178647 for Table 1)."""
        self._require_isotropic('stiffness')
        return self.stiffness_radial

    @property
    def natural_frequency_radial(self):
        """Non-rotating circular natural frequency sqrt(k1/M) of radial bending, rad/s.

        M is :attr:`modal_mass` (m for a massless rod); k1 includes the axial load.
        """
        return np.sqrt(self.stiffness_radial / self.modal_mass) + 0.0

    @property
    def natural_frequency_tangential(self):
        """Non-rotating circular natural frequency sqrt(k2/M) of tangential bending, rad/s."""
        return np.sqrt(self.stiffness_tangential / self.modal_mass) + 0.0

    @property
    def natural_frequency(self):
        """Circular natural frequency w0 = sqrt(k/M) of an isotropic rod, rad/s.

        Model: docs/model.md#eq-natural-frequency.
        """
        self._require_isotropic('natural_frequency')
        return self.natural_frequency_radial

    def bending_frequencies(self, direction: str = 'radial', count: int = 2):
        """The rod's lowest ``count`` bending circular frequencies (rad/s), not rotating.

        A many-term Rayleigh-Ritz estimate of the uniform rod with its tip mass, the
        tip load m g and the rod's own weight (see
        :func:`rotrod_core.model.beam.ritz_bending_frequencies`); unlike the one-mode model
        it also resolves the higher modes. For a massless rod the first is sqrt(k/m)
        and the others are inf (the tip mass is the only inertia: one mode).
        ``direction`` is 'radial' (I1) or 'tangential' (I2). Shape ``(..., count)``.
        """
        if direction not in ('radial', 'tangential'):
            raise ValueError(f"direction must be 'radial' or 'tangential', got {direction!r}")
        mu = self.rod_density * self.section_area
        return ritz_bending_frequencies(
            self._flexural_rigidity(direction), self.rod_length, self.mass, mu,
            self.tip_load, mu * np.asarray(self.gravity, dtype=float), count=count)

    @property
    def second_mode_frequency_radial(self):
        """Estimated circular frequency of the second bending mode (radial), rad/s.

        From :meth:`bending_frequencies` (non-rotating; rotation shifts it by about
        +-w in the rotating frame). inf for a massless rod, which has one mode only.
        The one-mode model is good while this is far above the frequencies excited.
        """
        out = self.bending_frequencies('radial', 2)[..., 1]
        return float(out) if np.ndim(out) == 0 else out

    @property
    def second_mode_frequency_tangential(self):
        """Estimated circular frequency of the second bending mode (tangential), rad/s."""
        out = self.bending_frequencies('tangential', 2)[..., 1]
        return float(out) if np.ndim(out) == 0 else out

    @property
    def second_mode_frequency(self):
        """Second bending mode of an isotropic rod, rad/s (inf if massless)."""
        self._require_isotropic('second_mode_frequency')
        return self.second_mode_frequency_radial

    @property
    def damping_radial(self):
        """Viscous damping coefficient c1 = 2 zeta sqrt(k1 M) on u', N s/m.

        Model: docs/model.md#eq-damping.
        """
        # sqrt(k1) sqrt(M): k1 M may overflow where c1 does not (0 x inf: NaN)
        return (2.0 * self.damping_ratio * np.sqrt(self.stiffness_radial)
                * np.sqrt(self.modal_mass))

    @property
    def damping_tangential(self):
        """Viscous damping coefficient c2 = 2 zeta sqrt(k2 M) on v', N s/m."""
        return (2.0 * self.damping_ratio * np.sqrt(self.stiffness_tangential)
                * np.sqrt(self.modal_mass))

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
        return self.replace(**changes)


FIELDS = tuple(FieldInfo(f.name, f.default, **f.metadata[_INFO])
               for f in dataclasses.fields(RodParams))
"""Every RodParams field's :class:`FieldInfo`, in the dataclass's order."""
FIELD_UNITS = {f.name: f.unit for f in FIELDS if not f.choices}
"""The numeric fields of :class:`RodParams` and their SI units ('-': dimensionless)."""
