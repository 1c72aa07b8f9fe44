"""Constant-rotation analysis: dynamic frequencies, modes, stability, Campbell sweep.

At constant w the deflection equations are linear time-invariant. Their free
vibration in the rotating frame has, for an isotropic undamped rod, the two circular
frequencies |w0 - w| (forward whirl below w0) and w0 + w (backward whirl): Eq. 28.
The general eigen analysis covers k1 != k2 and rotating damping.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

import rotrod_core.model.propagation as propagation
from rotrod_core.model.equations import Coefficients
from rotrod_core.model.params import RodParams
from rotrod_core.numerics.checks import finite_array

TWO_PI = 2.0 * math.pi


def _omega_array(omega, name='omega'):
    if isinstance(omega, bool):
        raise ValueError(f'{name} must be a number, got {omega!r}')
    return finite_array(name, omega)


def has_eq28(params: RodParams) -> bool:
    """Whether Eq. 28 gives the dynamic frequencies: an isotropic rod without damping."""
    return bool(params.is_isotropic and not np.any(np.asarray(params.damping_ratio) > 0))


def eq28(w0, omega) -> tuple:
    """Eq. 28: (f1, f2) = (|w0 - |w|| / 2pi, (w0 + |w|) / 2pi) Hz, w0 and w in rad/s.

    For floats (a live engine, per sample, with w0 cached) or arrays; see
    :func:`dynamic_frequencies` for when it applies.

    Model: docs/model.md#eq-28.
    """
    a = abs(omega)
    return abs(w0 - a) / TWO_PI, (w0 + a) / TWO_PI


def dynamic_frequencies(params: RodParams, omega):
    """The two dynamic frequencies (f1, f2) in Hz at constant angular velocity ``omega``.

    Eq. 28: f1 = |w0 - |w|| / 2pi, f2 = (w0 + |w|) / 2pi, for an isotropic rod (the
    sense of rotation does not matter), w0 = sqrt(k/M) (:attr:`RodParams.natural_frequency`,
    with the axial load of gravity and the rod's modal mass). For k1 != k2 or with
    damping, the two damped frequencies of :func:`modal_analysis`, lower first.
    Vectorized over ``omega``.

    Model: docs/model.md#eq-28.
    """
    w = _omega_array(omega)
    if has_eq28(params):
        f1, f2 = eq28(params.natural_frequency, w)
    else:
        modes = [modal_analysis(params, wi) for wi in w.ravel()]
        f1 = np.array([m.frequencies[0] for m in modes]).reshape(w.shape)
        f2 = np.array([m.frequencies[1] for m in modes]).reshape(w.shape)
    if w.ndim == 0:
        return float(f1), float(f2)
    return f1, f2


@dataclass(frozen=True)
class Mode:
    """One vibration mode at constant rotation (a complex-conjugate eigenvalue pair).

    Attributes:
        frequency: damped frequency |Im lambda| / 2pi, Hz (0 for a real eigenvalue).
        growth_rate: Re lambda, 1/s (> 0: the mode grows, unstable).
        damping_ratio: -Re lambda / |lambda| (negative when growing).
        whirl: 'forward' (in the sense of rotation, seen in the rotating frame),
            'backward', or 'none' for a non-oscillating (real) mode.
        eigenvalue: lambda, 1/s (Im >= 0 representative).
    """

    frequency: float
    growth_rate: float
    damping_ratio: float
    whirl: str
    eigenvalue: complex


@dataclass(frozen=True)
class ModalAnalysis:
    """Modes at one constant angular velocity ``omega`` (rad/s)."""

    omega: float
    modes: tuple

    @property
    def frequencies(self) -> tuple[float, ...]:
        """Damped frequencies of the modes, Hz, ascending."""
        return tuple(m.frequency for m in self.modes)

    @property
    def max_growth_rate(self) -> float:
        """Largest Re lambda, 1/s."""
        return max(m.growth_rate for m in self.modes)

    @property
    def stable(self) -> bool:
        """True when no mode grows (max Re lambda <= a rounding-level tolerance)."""
        scale = max(abs(m.eigenvalue) for m in self.modes) or 1.0
        return self.max_growth_rate <= 1e-9 * scale


def state_matrix(params: RodParams, omega: float) -> np.ndarray:
    """4x4 matrix of the free (homogeneous) deflection dynamics at constant ``omega``."""
    co = Coefficients.from_params(params)
    return propagation.system_matrix(co, omega, 0.0)[:4, :4]


def modal_analysis(params: RodParams, omega: float) -> ModalAnalysis:
    """Eigen analysis of the free vibration at constant ``omega`` (rad/s).

    Valid for any k1, k2 and damping. Modes are ordered by frequency.

    Model: docs/model.md#stability.
    """
    if params.is_batch:
        raise ValueError('modal_analysis takes one system, not a batch')
    w = float(_omega_array(omega))
    with np.errstate(over='ignore', invalid='ignore'):
        a = state_matrix(params, w)
    if not np.all(np.isfinite(a)):
        raise ValueError(f'omega = {w!r} rad/s is too large for the eigen analysis: its '
                         'state matrix overflows (w^2)')
    lam, vec = np.linalg.eig(a)
    modes = []
    used = np.zeros(4, dtype=bool)
    for i in np.argsort(-lam.imag):
        if used[i]:
            continue
        used[i] = True
        # its conjugate partner (or, for a real eigenvalue, leave it single)
        if abs(lam[i].imag) > 1e-12 * max(1.0, abs(lam[i])):
            partner = np.argmin(np.where(used, np.inf, np.abs(lam - np.conj(lam[i]))))
            used[partner] = True
            phi_u, phi_v = vec[0, i], vec[1, i]
            fwd, bwd = abs(phi_u + 1j * phi_v), abs(phi_u - 1j * phi_v)
            whirl = 'forward' if fwd > bwd else 'backward'
        else:
            whirl = 'none'
        mag = abs(lam[i])
        modes.append(Mode(frequency=float(abs(lam[i].imag) / TWO_PI),
                          growth_rate=float(lam[i].real),
                          damping_ratio=float(-lam[i].real / mag) if mag else 0.0,
                          whirl=whirl, eigenvalue=complex(lam[i])))
    modes.sort(key=lambda m: m.frequency)
    # Coincident pairs (e.g. an isotropic rod at rest): the eigenspace holds both
    # circular whirls and the solver's basis is arbitrary, so name one of each.
    for i, j in zip(range(len(modes)), range(1, len(modes))):
        ma, mb = modes[i], modes[j]
        close = abs(ma.eigenvalue - mb.eigenvalue) <= 1e-9 * abs(ma.eigenvalue)
        if ma.whirl != 'none' and close:
            modes[i] = dataclasses.replace(ma, whirl='forward')
            modes[j] = dataclasses.replace(mb, whirl='backward')
    return ModalAnalysis(omega=w, modes=tuple(modes))


@dataclass(frozen=True)
class CampbellDiagram:
    """Frequencies and stability over a sweep of constant angular velocities.

    Attributes:
        omega: swept angular velocities, rad/s.
        frequencies: (len(omega), n_modes) damped frequencies, Hz, ascending per row.
        growth_rates: matching Re lambda, 1/s.
        whirl: matching whirl directions.
        stable: stability at each omega.
        unstable_bands: (start, end) intervals of omega (rad/s) where some mode grows,
            edges refined by bisection.
    """

    omega: np.ndarray
    frequencies: np.ndarray
    growth_rates: np.ndarray
    whirl: np.ndarray
    stable: np.ndarray
    unstable_bands: tuple


def _unstable(params, w):
    return not modal_analysis(params, w).stable


def _refine_edge(params, lo, hi, tol):
    """Bisect for the stability change between lo and hi (stability differs at the two)."""
    s_lo = _unstable(params, lo)
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if _unstable(params, mid) == s_lo:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def campbell(params: RodParams, omegas, edge_tolerance: float = 1e-9) -> CampbellDiagram:
    """Sweep the modal analysis over ``omegas`` (rad/s, ascending) and find unstable bands.

    A band is reported from the sweep's stability flags; its edges are refined to
    ``edge_tolerance`` rad/s by bisection. Bands narrower than the sweep step may be
    missed: sweep finely enough.
    """
    w = np.sort(_omega_array(omegas, 'omegas').ravel())
    analyses = [modal_analysis(params, wi) for wi in w]
    n = max(len(a.modes) for a in analyses)

    def column(getter, fill):
        return np.array([[getter(m) for m in a.modes] + [fill] * (n - len(a.modes))
                         for a in analyses])

    stable = np.array([a.stable for a in analyses])
    bands = []
    i = 0
    while i < len(w):
        if stable[i]:
            i += 1
            continue
        j = i
        while j + 1 < len(w) and not stable[j + 1]:
            j += 1
        start = w[i] if i == 0 else _refine_edge(params, w[i - 1], w[i], edge_tolerance)
        end = w[j] if j == len(w) - 1 else _refine_edge(params, w[j], w[j + 1], edge_tolerance)
        bands.append((float(start), float(end)))
        i = j + 1
    return CampbellDiagram(omega=w, frequencies=column(lambda m: m.frequency, np.nan),
                           growth_rates=column(lambda m: m.growth_rate, np.nan),
                           whirl=column(lambda m: m.whirl, ''), stable=stable,
                           unstable_bands=tuple(bands))


def static_deflection(params: RodParams, omega):
    """Steady (eccentric) deflection (u_s, v_s) in m at constant ``omega`` (rad/s).

    u_s = Me w^2 r0 / (k1 - M w^2), v_s = 0 (also with damping and any k2), with the
    modal and eccentric masses M, Me (both m for a massless rod: the paper's
    m w^2 r0 / (k1 - m w^2)) and k1 including the axial load of gravity. Infinite at
    w^2 = k1/M; negative above it (an equilibrium that is not reached from rest).
    Vectorized over ``omega`` and batch parameters.

    Model: docs/model.md#eq-static.
    """
    w = _omega_array(omega)
    k1, m = params.stiffness_radial, params.modal_mass
    re = params.load_radius
    # u_s = re / (k1 / (M w^2) - 1): finite where M w^2 overflows (u_s -> -re) or
    # underflows (u_s -> 0), where the quotient of the two overflowed was NaN
    with np.errstate(divide='ignore', over='ignore', invalid='ignore'):
        q = k1 / (m * (w * w)) - 1.0
        u = np.where(q == 0, np.inf, re / np.where(q == 0, 1.0, q))
    u = u + 0.0 * np.asarray(re)
    v = np.zeros_like(u)
    if u.ndim == 0:
        return float(u), 0.0
    return u, v


def tangential_bending(params: RodParams, omega_dot):
    """Quasi-static tangential deflection |v| (m) under a steady hub acceleration.

    From Eq. 17 with v'' = v' = 0 and w small: k2 v = -Me w' r0 (Me = m for a
    massless rod), so |v| = |w'| r0 Me / k2 for an angular acceleration
    ``omega_dot`` (rad/s^2). A sudden w' overshoots to twice this. Vectorized. +inf
    where the product overflows (beyond any deflection limit).
    """
    wd = np.abs(_omega_array(omega_dot, 'omega_dot'))
    with np.errstate(over='ignore'):
        v = wd * params.eccentricity * params.eccentric_mass / params.stiffness_tangential
    v = np.asarray(v, dtype=float)
    return float(v) if v.ndim == 0 else v
