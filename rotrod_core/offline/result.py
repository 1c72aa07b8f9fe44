"""The record of an offline run, with export to CSV and NPZ."""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

import rotrod_core.model.equations as model
from rotrod_core.model.equations import Coefficients
from rotrod_core.model.params import RodParams

COLUMNS = (
    ('t', 's', 'time'),
    ('u', 'm', 'radial deflection (rotating frame)'),
    ('v', 'm', 'tangential deflection (rotating frame)'),
    ('du', 'm/s', 'radial deflection rate'),
    ('dv', 'm/s', 'tangential deflection rate'),
    ('theta', 'rad', 'hub angle'),
    ('omega', 'rad/s', 'hub angular velocity'),
    ('omega_dot', 'rad/s^2', 'hub angular acceleration'),
    ('torque', 'N m', 'hub torque'),
    ('x', 'm', 'mass position, inertial frame'),
    ('y', 'm', 'mass position, inertial frame'),
)
"""(name, unit, meaning) of each recorded array, in file order."""


@dataclass
class SimulationResult:
    """Time histories of one run (numpy arrays of equal length, SI units).

    In velocity drive ``torque`` is the hub torque the drive must supply; in torque
    drive ``omega_dot`` is the resulting angular acceleration.
    """

    t: np.ndarray
    u: np.ndarray
    v: np.ndarray
    du: np.ndarray
    dv: np.ndarray
    theta: np.ndarray
    omega: np.ndarray
    omega_dot: np.ndarray
    torque: np.ndarray
    x: np.ndarray
    y: np.ndarray
    params: RodParams = field(repr=False, default_factory=RodParams)
    drive: str = 'velocity'
    coupling: str = 'exact'

    @property
    def states(self) -> model.State:
        """The state arrays as a :class:`rotrod_core.model.equations.State`."""
        return model.State(self.u, self.v, self.du, self.dv, self.theta, self.omega)

    @property
    def deflection(self) -> np.ndarray:
        """|r| = sqrt(u^2 + v^2), m."""
        return np.hypot(self.u, self.v)

    def energy(self) -> np.ndarray:
        """Total mechanical energy at each sample, J."""
        return model.energy(Coefficients.from_params(self.params), self.states)

    def angular_momentum(self) -> np.ndarray:
        """Angular momentum about the axis at each sample, kg m^2/s."""
        return model.angular_momentum(Coefficients.from_params(self.params), self.states)

    def window(self, t_start: float, t_stop: float) -> SimulationResult:
        """The samples with t_start <= t <= t_stop."""
        keep = (self.t >= t_start) & (self.t <= t_stop)
        arrays = {name: getattr(self, name)[keep] for name, _, _ in COLUMNS}
        return SimulationResult(**arrays, params=self.params, drive=self.drive,
                                coupling=self.coupling)

    def table(self) -> np.ndarray:
        """All columns stacked, shape (samples, len(COLUMNS))."""
        return np.column_stack([getattr(self, name) for name, _, _ in COLUMNS])

    def to_csv(self, path) -> Path:
        """Write a CSV with a header naming each column and its unit, e.g. ``u [m]``."""
        path = Path(path)
        header = ','.join(f'{name} [{unit}]' for name, unit, _ in COLUMNS)
        np.savetxt(path, self.table(), delimiter=',', header=header, comments='',
                   fmt='%.12e')
        return path

    def to_npz(self, path) -> Path:
        """Write a compressed NPZ holding one array per column and the units."""
        path = Path(path)
        arrays = {name: getattr(self, name) for name, _, _ in COLUMNS}
        units = np.array([f'{name}:{unit}' for name, unit, _ in COLUMNS])
        np.savez_compressed(path, **arrays, units=units, drive=self.drive,
                            coupling=self.coupling)
        return path

    def save(self, path) -> Path:
        """Write CSV or NPZ, chosen by the file suffix (.csv or .npz)."""
        suffix = Path(path).suffix.lower()
        if suffix == '.csv':
            return self.to_csv(path)
        if suffix == '.npz':
            return self.to_npz(path)
        raise ValueError(f'output file must end in .csv or .npz, got {str(path)!r}')
