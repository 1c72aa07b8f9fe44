"""Watching a rig live: its identification, critical speed and distance from nominal.

The rig's natural frequency, eccentricity and damping are identified over a sliding
window, with the critical speed they imply and how far the rig is from its nominal
parameters (no ROS import; the ``rig_monitor`` node is a thin front end).

:class:`RigMonitor` takes the hub's angular velocity (or an encoder's angle) and the tip
deflection (or the tip IMU's acceleration) as they come (from the simulator or a real
rig's sensors, joined on their timestamps), feeds
:class:`~rotrod_core.estimation.identify.RigIdentifier`, and judges the latest estimate: WARN when
|w| comes within ``critical_margin`` of the identified quasi-static critical speed for
``deflection_limit`` (docs/model.md#eq-critical), or when the identified tip stiffness
k = w0^2 M differs from the nominal one by more than ``stiffness_tolerance``.
"""

from __future__ import annotations

import math
from collections import OrderedDict
from dataclasses import dataclass

from rotrod_core.estimation.identify import (
    HUB_INPUTS,
    Accelerometer,
    RigEstimate,
    RigIdentifier,
)
from rotrod_core.live.engine import OK, WARN, Health
from rotrod_core.model.params import RodParams
from rotrod_core.numerics.checks import finite_number

ESTIMATE_FIELDS = (
    ('natural_frequency', 'rad/s'), ('natural_frequency_std', 'rad/s'),
    ('eccentricity', 'm'), ('eccentricity_std', 'm'),
    ('damping_ratio', '1'), ('damping_ratio_std', '1'),
    ('critical_speed', 'rad/s'), ('critical_speed_step', 'rad/s'),
    ('stiffness', 'N/m'), ('stiffness_deviation', '1'),
    ('residual_rms', 'm'), ('window_end', 's'),
)
"""The published estimate, in this order, with units: w0, r0, zeta and their standard
deviations; the quasi-static and sudden-start critical speeds for ``deflection_limit``;
the tip stiffness w0^2 M (M the nominal modal mass) and its relative deviation from the
nominal stiffness; the fit's residual (in m/s^2 from the acceleration); the time of the
window's last sample."""

MEASUREMENTS = ('deflection', 'acceleration')
"""What the monitor measures at the tip: the deflection (m) or the IMU's acceleration
(m/s^2, :class:`~rotrod_core.estimation.identify.Accelerometer`)."""

PENDING = 64
"""Samples waiting for their partner (the other topic at the same stamp), at most."""


@dataclass(frozen=True)
class MonitorConfig:
    """What a :class:`RigMonitor` compares against (SI units).

    Attributes:
        nominal: the rig's nominal parameters (the natural frequency and stiffness the
            identified ones are compared with; the modal mass turns w0 into k).
        window: identification window, s.
        sample_interval: expected interval between samples, s.
        update_interval: time between identifications, s.
        deflection_limit: the critical deflection behind the critical speed, m.
        critical_margin: WARN when |w| >= (1 - margin) x the identified critical speed.
        stiffness_tolerance: WARN when |k_identified / k_nominal - 1| exceeds it.
        measurement: 'deflection' (tip deflection u, v in m) or 'acceleration' (the tip
            IMU's x, y in m/s^2, its tilt and radius from ``nominal``: gravity, rod
            length and masses).
        hub: 'omega' (the hub's angular velocity) or 'angle' (an encoder's angle, w and
            w' fitted from it over ``angle_smoothing`` s; evenly spaced samples).
        angle_smoothing: the span of that fit, s.
    """

    nominal: RodParams = RodParams()
    window: float = 5.0
    sample_interval: float = 0.01
    update_interval: float = 0.1
    deflection_limit: float = 0.003
    critical_margin: float = 0.1
    stiffness_tolerance: float = 0.05
    measurement: str = 'deflection'
    hub: str = 'omega'
    angle_smoothing: float = 0.2

    def __post_init__(self):
        if self.measurement not in MEASUREMENTS:
            raise ValueError(f'measurement must be one of {MEASUREMENTS}, got '
                             f'{self.measurement!r}')
        if self.hub not in HUB_INPUTS:
            raise ValueError(f'hub must be one of {HUB_INPUTS}, got {self.hub!r}')
        finite_number('angle_smoothing', self.angle_smoothing, positive=True)
        if not isinstance(self.nominal, RodParams) or self.nominal.is_batch:
            raise ValueError('nominal must be the RodParams of one rig')
        if not self.nominal.is_isotropic:
            raise ValueError('the rig monitor identifies an isotropic rod (k1 == k2)')
        for name in ('window', 'sample_interval', 'update_interval', 'deflection_limit'):
            finite_number(name, getattr(self, name), positive=True)
        for name in ('critical_margin', 'stiffness_tolerance'):
            value = finite_number(name, getattr(self, name), nonnegative=True)
            if value >= 1:
                raise ValueError(f'{name} must be in [0, 1), got {value!r}')


class RigMonitor:
    """Joins (w, u, v) samples by time, identifies the rig, and judges it."""

    def __init__(self, config: MonitorConfig | None = None):
        self.config = config if config is not None else MonitorConfig()
        c = self.config
        sensor = Accelerometer.of(c.nominal) if c.measurement == 'acceleration' else None
        self.identifier = RigIdentifier(c.window, c.sample_interval, c.update_interval,
                                        sensor=sensor, hub=c.hub,
                                        angle_smoothing=c.angle_smoothing)
        self._omega: OrderedDict = OrderedDict()
        self._deflection: OrderedDict = OrderedDict()
        self.omega = 0.0
        """The latest hub angular velocity, rad/s."""
        self.updates = 0

    def add_omega(self, t: float, omega: float) -> RigEstimate | None:
        """The hub's angular velocity (rad/s) at time ``t`` (s); an estimate if one is due."""
        self._expect('hub', 'omega')
        estimate = self._add(self._omega, self._deflection, t, (float(omega),))
        self.omega = float(omega)           # checked finite by _add
        return estimate

    def add_angle(self, t: float, angle: float, omega: float | None = None
                  ) -> RigEstimate | None:
        """The hub's angle (rad, e.g. an encoder's) at time ``t`` (s); an estimate if due.

        ``omega`` (rad/s, e.g. the encoder's own speed) only updates :attr:`omega`, the
        speed the critical-speed warning compares.
        """
        self._expect('hub', 'angle')
        if omega is not None and not math.isfinite(omega):
            raise ValueError(f'non-finite hub speed at t = {t!r}: {omega!r}')
        estimate = self._add(self._omega, self._deflection, t, (float(angle),))
        if omega is not None:
            self.omega = float(omega)
        return estimate

    def add_deflection(self, t: float, u: float, v: float) -> RigEstimate | None:
        """The tip deflection (m) at time ``t`` (s); an estimate if one is due."""
        self._expect('measurement', 'deflection')
        return self._add(self._deflection, self._omega, t, (float(u), float(v)))

    def add_acceleration(self, t: float, x: float, y: float) -> RigEstimate | None:
        """The tip IMU's acceleration x, y (m/s^2, its frame) at ``t`` (s).

        An estimate if one is due.
        """
        self._expect('measurement', 'acceleration')
        return self._add(self._deflection, self._omega, t, (float(x), float(y)))

    def _expect(self, what: str, value: str) -> None:
        if getattr(self.config, what) != value:
            raise ValueError(f'this monitor takes {what} {getattr(self.config, what)!r}, '
                             f'not {value!r}')

    def _add(self, mine, other, t, values):
        t = float(t)
        if not all(math.isfinite(x) for x in (t, *values)):
            raise ValueError(f'non-finite sample at t = {t!r}: {values!r}')
        partner = other.pop(t, None)
        if partner is None:
            mine[t] = values
            while len(mine) > PENDING:
                mine.popitem(last=False)
            return None
        (omega,), (u, v) = (values, partner) if mine is self._omega else (partner, values)
        for old in [s for s in other if s < t]:      # their partners will not come
            del other[old]
        estimate = self.identifier.push(t, u, v, omega)
        if estimate is not None:
            self.updates += 1
        return estimate

    def reset(self) -> None:
        """Forget every sample and estimate (e.g. after the rig was reset)."""
        self.identifier.reset()
        self._omega.clear()
        self._deflection.clear()

    @property
    def estimate(self) -> RigEstimate | None:
        """The latest estimate (None before the first and after a failed update)."""
        return self.identifier.estimate

    @property
    def units(self) -> tuple[tuple[str, str], ...]:
        """:data:`ESTIMATE_FIELDS` with the residual in the measurement's unit."""
        if self.config.measurement == 'deflection':
            return ESTIMATE_FIELDS
        return tuple((n, 'm/s^2' if n == 'residual_rms' else u) for n, u in ESTIMATE_FIELDS)

    def values(self, estimate: RigEstimate) -> tuple[float, ...]:
        """The published numbers of ``estimate``, in :data:`ESTIMATE_FIELDS` order."""
        c = self.config
        stiffness = estimate.natural_frequency ** 2 * float(c.nominal.modal_mass)
        return (estimate.natural_frequency, estimate.natural_frequency_std,
                estimate.eccentricity, estimate.eccentricity_std,
                estimate.damping_ratio, estimate.damping_ratio_std,
                estimate.critical_speed(c.deflection_limit, 'quasi_static'),
                estimate.critical_speed(c.deflection_limit, 'step'),
                stiffness, stiffness / float(c.nominal.stiffness) - 1.0,
                estimate.residual_rms, estimate.end_time)

    def fields(self, estimate: RigEstimate) -> dict:
        """The fields of ``rig/estimate`` (rotrod_interfaces/RigEstimate) for ``estimate``.

        :meth:`values` by their :data:`ESTIMATE_FIELDS` names, with the
        ``deflection_limit`` the critical speeds are for (m) and the ``window`` (s);
        ``window_end`` (s) is the message's stamp.
        """
        out = {name: float(x) for (name, _), x in zip(ESTIMATE_FIELDS, self.values(estimate),
                                                      strict=True)}
        out.update(deflection_limit=float(self.config.deflection_limit),
                   window=float(self.config.window))
        return out

    def health(self) -> Health:
        """OK, or WARN with the reasons.

        WARN near the identified critical speed, with the stiffness off its nominal
        value, or with no estimate yet (saying why).
        """
        c, est = self.config, self.estimate
        nominal = (('nominal_natural_frequency_rad_s', float(c.nominal.natural_frequency)),
                   ('nominal_stiffness_N_m', float(c.nominal.stiffness)),
                   ('omega_rad_s', self.omega), ('updates', self.updates))
        if est is None:
            why = self.identifier.reason or 'the window is filling'
            return Health(WARN, f'no estimate: {why}', nominal)
        values = tuple(zip((f'{n}_{u.replace("/", "_").replace("^", "")}'
                            for n, u in self.units),
                           self.values(est), strict=True))
        named = dict(zip((n for n, _ in ESTIMATE_FIELDS), self.values(est), strict=True))
        warnings = []
        w_cr = named['critical_speed']
        if abs(self.omega) >= (1.0 - c.critical_margin) * w_cr:
            warnings.append(f'|omega| {abs(self.omega):.4g} rad/s within '
                            f'{c.critical_margin:.0%} of the identified critical speed '
                            f'{w_cr:.4g} rad/s (deflection {c.deflection_limit * 1e3:.3g} mm)')
        deviation = named['stiffness_deviation']
        if abs(deviation) > c.stiffness_tolerance:
            warnings.append(f'identified stiffness {named["stiffness"]:.4g} N/m is '
                            f'{deviation:+.1%} off the nominal {float(c.nominal.stiffness):.4g}'
                            f' N/m (natural frequency {est.natural_frequency:.4g} rad/s, '
                            f'nominal {float(c.nominal.natural_frequency):.4g})')
        level = WARN if warnings else OK
        message = '; '.join(warnings) if warnings else (
            f'natural frequency {est.natural_frequency:.4g} rad/s, critical speed '
            f'{w_cr:.4g} rad/s')
        return Health(level, message, (*values, *nominal))


__all__ = ['ESTIMATE_FIELDS', 'MEASUREMENTS', 'MonitorConfig', 'RigMonitor']
