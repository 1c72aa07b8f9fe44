"""Identify the rig from its motion: natural frequency, eccentricity and damping.

For an isotropic rod with rotating damping (docs/model.md#eq-damping), z = u + i v (m,
rotating frame) obeys, given the hub's angular velocity w(t) (rad/s) and acceleration w'(t),

    z'' + (g + 2 i w) z' + (a - w^2 + i w') z = r0 (w^2 - i w'),
    a = w0^2,  g = 2 zeta w0,

which is linear in the three unknowns a, g and r0. The hub's w(t) is measured (taken as
exact), so w0, zeta and r0 can be identified from any record in which they act on the
motion, with w varying or constant. Two stages (docs/identification.md):

1. Equation error (the start): the differential equation is multiplied by modulating
   functions phi (t^2 (L - t)^2 on windows of length L, at several lengths) and
   integrated by parts, which moves every derivative from the noisy z onto phi and
   leaves the unknown initial state out. Each window gives one complex equation
   linear in (a, g, r0); all are solved together by weighted least squares. It needs
   no derivative of the data, but the noise then sits in the regressors, which biases
   it slightly: it is only the start.
2. Output error (the estimate): least squares of the measured z against the model's
   z(t), simulated with the measured w(t), over (a, g) and the nuisance initial
   deflection and rate z(t0), z'(t0) (complex). The model output is linear in
   (z(t0), z'(t0), r0), so these are solved exactly for every trial (a, g) (variable
   projection) and Gauss-Newton (Levenberg-Marquardt) runs over (a, g) only. The
   simulation is the rotating-frame equation on the sample grid, by the one
   propagation kernel (:mod:`rotrod_core.model.propagation`, shared with simulate,
   simulate_batch and the planner): its isotropic system and fourth-order Magnus
   step (two Gauss points, w and w' there from a cubic Hermite interpolation of
   the samples), the step's exponential in closed form (Cayley-Hamilton for the 2x2
   complex matrix), with the forward sensitivities to a and g carried along in the
   same step matrices, chained by the kernel's blocked products (vectorized).

For white measurement noise on u and v this is the maximum-likelihood estimate: its
covariance sigma^2 (J^T J)^-1 (J: the Jacobian of the real and imaginary parts of the
model output, sigma: the noise standard deviation per component, estimated from the
residual) is the Cramer-Rao bound evaluated at the estimate (:func:`rig_cramer_rao`
evaluates it at given parameters).

What a record cannot identify is refused with :class:`NotIdentifiable` (a ValueError),
naming the parameters and why: a structurally singular information matrix (w = 0
everywhere: the eccentric forcing is zero, so r0 does not act; a deflection that never
changes: only the static relation r0 w^2 / (w0^2 - w^2) is seen, no damping; no motion
at all), or a standard deviation above the limits (``max_relative_std`` of w0 and r0,
``max_damping_std`` of zeta). The exception carries the partial estimate of what is
identifiable. A parameter known beforehand may be fixed (``damping_ratio=``,
``eccentricity=``) and the rest identified.

Limits: the rod must be isotropic (k1 = k2); the noise is taken as white (a misfit or
coloured noise makes the reported standard deviations optimistic); w' comes from
``omega_dot`` when given, else from a cubic spline through w (noise on w is then
differentiated: w should be smooth at the sample rate).
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.signal import savgol_filter

import rotrod_core.model.propagation as propagation
from rotrod_core.analysis.critical import STARTS, critical_speed_from
from rotrod_core.model.equations import Coefficients
from rotrod_core.model.geometry import TIP_SLOPE
from rotrod_core.model.params import RodParams
from rotrod_core.numerics.checks import finite_array, finite_number

MIN_SAMPLES = 20            # fewest samples identify_rig accepts
_TERM_TOLERANCE = 1e-18     # Taylor terms of the step exponential summed to this size
_SINGULAR = 1e-8            # singular value / largest (unit columns): structurally singular
_MAX_ITERATIONS = 50
_DETECTION = 100.0          # energy / noise variance (20 dB) of a motion taken as seen
_NAMES = {'a': 'natural_frequency', 'g': 'damping_ratio', 'r0': 'eccentricity'}


class NotIdentifiable(ValueError):
    """The record does not determine some parameters of the rig.

    Attributes:
        parameters: names of the parameters not identifiable ('natural_frequency',
            'eccentricity', 'damping_ratio'); empty when nothing is (e.g. no motion).
        estimate: the :class:`RigEstimate` of the rest (NaN for ``parameters``), their
            standard deviations taken with ``parameters`` as known; None when nothing
            could be fitted.
    """

    def __init__(self, reason: str, parameters: tuple = (), estimate: RigEstimate | None = None):
        super().__init__(reason)
        self.reason = reason
        self.parameters = tuple(parameters)
        self.estimate = estimate


@dataclass(frozen=True)
class RigEstimate:
    """The rig identified from one record (SI units; NaN: not identified).

    Attributes:
        natural_frequency: w0 = sqrt(k/m), rad/s.
        eccentricity: r0, m.
        damping_ratio: zeta (rotating damping, c = 2 zeta sqrt(k m)).
        natural_frequency_std: standard deviation of w0, rad/s (0 if fixed).
        eccentricity_std: standard deviation of r0, m (0 if fixed).
        damping_ratio_std: standard deviation of zeta (0 if fixed).
        noise_std: measurement noise estimated from the residual, per component (u and
            v each), m.
        residual_rms: RMS of |z - model|, m (about sqrt(2) noise_std for white noise).
        samples: number of samples used.
        start_time: first sample time, s (the nuisance initial state is at this time).
        end_time: last sample time, s.
        initial_deflection: fitted z = u + i v at ``start_time``, m.
        initial_rate: fitted z' at ``start_time``, m/s.
        fixed: names of the parameters given by the caller (not identified), or
            carried from an earlier window (:class:`RigIdentifier`).
        iterations: Gauss-Newton iterations of the output-error fit.
        accelerometer_bias: the accelerometer's fitted bias x + i y, m/s^2 (None from
            the deflection).
        covariance: 3x3 covariance of (natural_frequency, eccentricity, damping_ratio).
    """

    natural_frequency: float
    eccentricity: float
    damping_ratio: float
    natural_frequency_std: float
    eccentricity_std: float
    damping_ratio_std: float
    noise_std: float
    residual_rms: float
    samples: int
    start_time: float
    end_time: float
    initial_deflection: complex = complex(math.nan, math.nan)
    initial_rate: complex = complex(math.nan, math.nan)
    fixed: tuple = ()
    iterations: int = 0
    accelerometer_bias: complex | None = None
    covariance: np.ndarray = field(default_factory=lambda: np.full((3, 3), math.nan),
                                   compare=False, repr=False)

    @property
    def natural_frequency_hz(self) -> float:
        """f0 = w0 / 2pi, Hz."""
        return self.natural_frequency / (2 * math.pi)

    @property
    def stiffness_per_mass(self) -> float:
        """k/m = w0^2, 1/s^2."""
        return self.natural_frequency**2

    def critical_speed(self, deflection_limit, start: str = 'quasi_static'):
        """Critical angular velocity (rad/s) for a deflection limit (m), from the estimate.

        The closed forms of :func:`rotrod_core.critical_speed`: 'quasi_static'
        w0 sqrt(d / (d + r0)), 'step' w0 sqrt(d / (d + 2 r0)), 'impulsive'
        w0 d / (d + r0). The damping is neglected, as in those forms.
        """
        return critical_speed_from(self.natural_frequency, abs(self.eccentricity),
                                   deflection_limit, start)

    def critical_speed_std(self, deflection_limit, start: str = 'quasi_static') -> float:
        """Standard deviation of :meth:`critical_speed`, rad/s.

        First order, from the covariance of w0 and r0.
        """
        if start not in STARTS:
            raise ValueError(f'start must be one of {STARTS}, got {start!r}')
        w0, r0 = self.natural_frequency, abs(self.eccentricity)
        eps_w, eps_r = 1e-6 * w0, 1e-6 * max(r0, 1e-9)
        fw = (critical_speed_from(w0 + eps_w, r0, deflection_limit, start)
              - critical_speed_from(w0 - eps_w, r0, deflection_limit, start)) / (2 * eps_w)
        fr = (critical_speed_from(w0, r0 + eps_r, deflection_limit, start)
              - critical_speed_from(w0, max(r0 - eps_r, 0.0), deflection_limit, start)) \
            / (r0 + eps_r - max(r0 - eps_r, 0.0))
        grad = np.array([fw, math.copysign(1.0, self.eccentricity) * fr])
        cov = np.asarray(self.covariance)[:2, :2]
        return float(math.sqrt(max(grad @ cov @ grad, 0.0)))


# -- input -----------------------------------------------------------------------------

@dataclass(frozen=True)
class Accelerometer:
    """The tip accelerometer's two horizontal axes as the measurement (instead of z).

    An IMU on the tip mass (``tip/imu``, :mod:`rotrod_core.sensors.imu`) reads the
    specific force in its frame, tilted with the rod. Its x + i y (m/s^2) is, to first
    order in the deflection (docs/identification.md#imu),

        y = -(a + c) z - g z' + (rho - 1) r0 (i w' - w^2) + beta,

    the tip's acceleration in the rotor frame z'' + 2 i w z' + (i w' - w^2)(rho r0 + z)
    with z'' from the equation of motion: the rod's restoring and damping forces per
    modal mass, the rigid acceleration of the tip's radius rho r0 beyond the load radius
    r0 the forcing sees, the tilt's share of gravity -c z, and a constant bias beta
    (complex, fitted as two nuisance parameters). The unknowns enter as before: z is
    linear in (z(t0), z'(t0), r0), and so is y.

    Attributes:
        tilt_gravity: c = gravity x TIP_SLOPE / rod_length, 1/s^2 (0 without gravity).
        radius_ratio: rho = M / Me, the tip's radius over the load radius (1 for a
            massless rod; M, Me the modal and eccentric masses).
        bias: whether a constant bias on each axis is fitted (a real accelerometer has
            one; without it a bias shows up as a wrong r0).
    """

    tilt_gravity: float = 0.0
    radius_ratio: float = 1.0
    bias: bool = True

    def __post_init__(self):
        finite_number('tilt_gravity', self.tilt_gravity, nonnegative=True)
        finite_number('radius_ratio', self.radius_ratio, positive=True)

    @classmethod
    def of(cls, params: RodParams, bias: bool = True) -> Accelerometer:
        """The accelerometer of a rig with these (nominal) parameters."""
        return cls(tilt_gravity=float(params.gravity) * TIP_SLOPE / float(params.rod_length),
                   radius_ratio=float(params.modal_mass / params.eccentric_mass), bias=bias)


@dataclass
class _Record:
    """A validated record and the hub's motion at the Gauss points of every interval."""

    t: np.ndarray
    z: np.ndarray
    omega: np.ndarray
    h: np.ndarray
    w1: np.ndarray
    w2: np.ndarray
    wd1: np.ndarray
    wd2: np.ndarray
    slopes: np.ndarray

    @property
    def rigid(self) -> np.ndarray:
        """The rotor frame's acceleration per metre of radius, i w' - w^2, at the samples."""
        return 1j * self.slopes - self.omega**2

    def __post_init__(self):
        # the kernel's isotropic system at the Gauss points for w0^2 = g = 0 and a unit
        # load radius (the forcing per metre of r0), and its derivatives by w0^2 and g
        base = _unit_rod(0.0, 0.0)
        self.X1 = propagation.complex_system(base, self.w1, self.wd1)
        self.X2 = propagation.complex_system(base, self.w2, self.wd2)
        self.by_a = propagation.lin((1.0, propagation.complex_system_derivative(
            base, 'natural_frequency_squared', self.w1, self.wd1)))
        self.by_g = propagation.lin((1.0, propagation.complex_system_derivative(
            base, 'damping_rate', self.w1, self.wd1)))

    @property
    def n(self) -> int:
        return len(self.t)


def _arrays(t, u, v, omega, omega_dot):
    names = ['t', 'u', 'v', 'omega'] + ([] if omega_dot is None else ['omega_dot'])
    values = [t, u, v, omega] + ([] if omega_dot is None else [omega_dot])
    arrays = []
    for name, value in zip(names, values):
        try:
            arr = np.asarray(value, dtype=float)
        except (TypeError, ValueError, OverflowError):
            raise ValueError(f'{name} must be an array of numbers') from None
        if arr.ndim != 1:
            raise ValueError(f'{name} must be one-dimensional, got shape {arr.shape}')
        arrays.append(arr)
    lengths = {name: len(a) for name, a in zip(names, arrays)}
    if len(set(lengths.values())) > 1:
        raise ValueError(f'{", ".join(names)} must have equal lengths, got '
                         + ', '.join(f'{k}: {n}' for k, n in lengths.items()))
    for name, arr in zip(names, arrays):
        finite_array(name, arr)
    t = arrays[0]
    if len(t) < 3:
        raise ValueError(f'the record is too short: {len(t)} samples (identification '
                         f'needs at least {MIN_SAMPLES})')
    steps = np.diff(t)
    if not np.all(steps > 0):
        bad = int(np.argmax(steps <= 0))
        raise ValueError(f'times must increase strictly: t[{bad}] = {t[bad]!r} s, '
                         f't[{bad + 1}] = {t[bad + 1]!r} s')
    return arrays + ([None] if omega_dot is None else [])


def _record(t, u, v, omega, omega_dot=None) -> _Record:
    t, u, v, w, wd = _arrays(t, u, v, omega, omega_dot)
    if len(t) < MIN_SAMPLES:
        raise NotIdentifiable(f'too few samples: {len(t)} (identification needs at least '
                              f'{MIN_SAMPLES})')
    if wd is None:
        slopes = CubicSpline(t, w).derivative()(t)
    else:
        slopes = wd
    h = np.diff(t)
    out = {}
    for name, s in zip(('1', '2'), propagation.GAUSS2):
        # cubic Hermite through (w, w') at the ends of each interval
        h00, h10, h01, h11 = 2 * s**3 - 3 * s**2 + 1, s**3 - 2 * s**2 + s, \
            -2 * s**3 + 3 * s**2, s**3 - s**2
        d00, d10, d01, d11 = 6 * s**2 - 6 * s, 3 * s**2 - 4 * s + 1, \
            -6 * s**2 + 6 * s, 3 * s**2 - 2 * s
        out['w' + name] = h00 * w[:-1] + h10 * h * slopes[:-1] + h01 * w[1:] \
            + h11 * h * slopes[1:]
        out['wd' + name] = (d00 * w[:-1] + d01 * w[1:]) / h + d10 * slopes[:-1] \
            + d11 * slopes[1:]
    return _Record(t=t, z=u + 1j * v, omega=w, h=h, slopes=slopes, **out)


# -- the model: z(t) and its sensitivities for given (a, g) ------------------------------

def _mul2(A, B):
    """Product of 2x2 matrices given as component tuples (a00, a01, a10, a11)."""
    return (A[0] * B[0] + A[1] * B[2], A[0] * B[1] + A[1] * B[3],
            A[2] * B[0] + A[3] * B[2], A[2] * B[1] + A[3] * B[3])


def _affine_expm(x, b, dx10, dx11, db1):
    """Exponential of [[X, b], [0, 0]] for 2x2 complex X, with derivatives.

    ``x`` = (x00, x01, x10, x11) and ``b`` = (b0, b1) are arrays over the steps; the
    directions (leading axis of ``dx10``, ``dx11``, ``db1``) change only x10, x11 and
    b1. Returns the components (e00, e01, e10, e11) of e^X and (phi0, phi1) of
    phi1(X) b, each of shape (1 + directions, steps): the value, then the directional
    derivatives.

    Cayley-Hamilton: X^k = p_k X + q_k I, so e^X and phi1(X) = sum X^k / (k+1)! are
    P X + Q I and P1 X + Q1 I with scalar series (the derivatives follow the same
    recurrences); scaling and squaring for long steps.
    """
    x00, x01, x10, x11 = x
    b0, b1 = b
    tau = x00 + x11
    det = x00 * x11 - x01 * x10
    rho = float(np.max(0.5 * np.abs(tau) + np.sqrt(np.abs(0.25 * tau * tau - det)),
                       initial=0.0))
    s = max(0, math.ceil(math.log2(rho / 0.5))) if rho > 0.5 else 0
    if s:
        f = 0.5**s
        x00, x01, x10, x11, b0, b1 = (c * f for c in (x00, x01, x10, x11, b0, b1))
        dx10, dx11, db1 = dx10 * f, dx11 * f, db1 * f
        tau, det, rho = tau * f, det * f * f, rho * f
    dtau = dx11
    ddet = x00 * dx11 - x01 * dx10
    m, n = dx10.shape
    p = np.zeros((1 + m, n), dtype=complex)
    q = np.zeros((1 + m, n), dtype=complex)
    q[0] = 1.0
    P, Q, P1, Q1 = p.copy(), q.copy(), p.copy(), q.copy()
    k, bound = 0, 1.0
    while bound > _TERM_TOLERANCE and k < 60:
        k += 1
        p0 = p[0]
        p, q = tau * p + q, -det * p
        p[1:] += dtau * p0
        q[1:] -= ddet * p0
        p /= k
        q /= k
        P += p
        Q += q
        P1 += p / (k + 1)
        Q1 += q / (k + 1)
        bound = bound * max(rho, 1e-300) / k if k > 1 else 1.0

    def combine(P, Q):
        M = [P * x00 + Q, P * x01, P * x10, P * x11 + Q]
        M[2][1:] += P[0] * dx10
        M[3][1:] += P[0] * dx11
        return M

    E = combine(P, Q)
    F = combine(P1, Q1)
    phi = [F[0] * b0 + F[1] * b1, F[2] * b0 + F[3] * b1]
    phi[0][1:] += F[1][0] * db1
    phi[1][1:] += F[3][0] * db1
    for _ in range(s):      # (E, phi)^2 = (E E, E phi + phi), with derivatives
        e = [c[0] for c in E]
        de = [c[1:] for c in E]
        ph = [c[0] for c in phi]
        dph = [c[1:] for c in phi]
        d_e = [u + v for u, v in zip(_mul2(de, e), _mul2(e, de))]
        d_phi = [de[0] * ph[0] + de[1] * ph[1] + e[0] * dph[0] + e[1] * dph[1] + dph[0],
                 de[2] * ph[0] + de[3] * ph[1] + e[2] * dph[0] + e[3] * dph[1] + dph[1]]
        e2 = _mul2(e, e)
        ph2 = [e[0] * ph[0] + e[1] * ph[1] + ph[0], e[2] * ph[0] + e[3] * ph[1] + ph[1]]
        E = [np.concatenate([v[None], dv]) for v, dv in zip(e2, d_e)]
        phi = [np.concatenate([v[None], dv]) for v, dv in zip(ph2, d_phi)]
    return E, phi


def _unit_rod(a: float, g: float) -> Coefficients:
    """An isotropic rod with w0^2 = a (1/s^2), g = c/M = a (1/s) and load radius 1 m."""
    return Coefficients(mass=1.0, eccentricity=1.0, hub_inertia=1.0, k1=a, k2=a, c1=g, c2=g,
                        w1sq=a, w2sq=a, g1=g, g2=g)


def _entries(X, n: int, which) -> list:
    """Entries ``which`` of a complex affine tuple as arrays of n (None: zeros)."""
    return [np.broadcast_to(0j if X[i] is None else X[i], (n,)) for i in which]


def _step_matrices(rec: _Record, a: float, g: float, out=None) -> np.ndarray:
    """Magnus step matrices (n-1, 7, 7) of (z, z', r0, dz/da, dz'/da, dz/dg, dz'/dg).

    The kernel's fourth-order Magnus exponent
    (:func:`rotrod_core.model.propagation.magnus4_complex`) of the isotropic system
    z'' = x10 z + x11 z' + r0 b1 on x = (z, z', r0), and its derivatives by a and g.
    The sensitivities obey the same equation, forced by the derivative of the step
    matrix (the Frechet derivative of its exponential). Only x10, x11 and b1 of the
    exponent depend on a and g (z' = z' holds at both Gauss points). Written into
    ``out`` (a :class:`~rotrod_core.model.propagation.ChainWorkspace` step buffer) when
    given.
    """
    h = rec.h
    n = len(h)
    X1 = propagation.lin((1.0, rec.X1), (a, rec.by_a), (g, rec.by_g))
    X2 = propagation.lin((1.0, rec.X2), (a, rec.by_a), (g, rec.by_g))
    omega = _entries(propagation.magnus4_complex(h, X1, X2), n, range(6))
    derivatives = [propagation.magnus4_complex_derivative(h, X1, X2, d, d)
                   for d in (rec.by_a, rec.by_g)]
    for d in derivatives:
        if any(np.any(e != 0) for e in _entries(d, n, (0, 1, 4))):
            raise AssertionError('identification expects the exponent\'s first row to '
                                 'be independent of a and g')
    dx10, dx11, db1 = (np.stack(parts) for parts in zip(
        *(_entries(d, n, (2, 3, 5)) for d in derivatives)))
    E, phi = _affine_expm(omega[:4], omega[4:], dx10, dx11, db1)
    S = np.zeros((n, 7, 7), dtype=complex) if out is None else out[:n]
    S[:, 2, 2] = 1.0
    for j, row in enumerate((0, 3, 5)):
        S[:, row, 0], S[:, row, 1], S[:, row + 1, 0], S[:, row + 1, 1] = (
            E[0][j], E[1][j], E[2][j], E[3][j])
        S[:, row, 2], S[:, row + 1, 2] = phi[0][j], phi[1][j]
        if row:
            S[:, row, row], S[:, row, row + 1] = E[0][0], E[1][0]
            S[:, row + 1, row], S[:, row + 1, row + 1] = E[2][0], E[3][0]
    return S if out is None else out


def _stack(c: np.ndarray) -> np.ndarray:
    """Complex columns (N, p) as real rows (2N, p): real parts, then imaginary parts."""
    return np.concatenate([c.real, c.imag])


@dataclass
class _Point:
    """The output-error problem evaluated at one (a, g)."""

    a: float
    g: float
    rss: float
    residual: np.ndarray        # (2N,)
    linear: np.ndarray          # (z0 re, z0 im, z0' re, z0' im[, r0])
    r0: float
    jacobian: np.ndarray        # (2N, p): free nonlinear columns, then the linear ones
    free: tuple                 # names of the columns of the jacobian
    forced: np.ndarray          # the nonlinear columns without the free vibration (2N, k)
    free_energy: float          # sum |z_h|^2 of the fitted free vibration z_h, m^2


class _Problem:
    """Output-error least squares for one record, with some parameters fixed."""

    def __init__(self, rec: _Record, zeta=None, r0=None,
                 work: propagation.ChainWorkspace | None = None,
                 sensor: Accelerometer | None = None):
        self.rec = rec
        self.work = work or propagation.ChainWorkspace()
        self.zeta = zeta        # fixed damping ratio (g = 2 zeta sqrt(a)), or None
        self.r0 = r0            # fixed eccentricity, or None
        self.sensor = sensor    # the accelerometer measured instead of z, or None
        self.y = _stack(rec.z[:, None])[:, 0]
        self.nonlinear = ('a',) if zeta is not None else ('a', 'g')
        self.free = self.nonlinear + ('z0r', 'z0i', 'dz0r', 'dz0i') \
            + (() if r0 is not None else ('r0',)) \
            + (('bias_x', 'bias_y') if sensor is not None and sensor.bias else ())

    def _outputs(self, a: float, g: float):
        """The output's responses to unit (z0, z0', r0) and their a- and g-derivatives.

        Three (N, 3) arrays; None if the model overflows.
        """
        n = self.rec.n - 1
        rows = (0, 3, 5) if self.sensor is None else (0, 1, 3, 4, 5, 6)
        with np.errstate(all='ignore'):
            S = _step_matrices(self.rec, a, g, out=self.work.steps(n, 7, complex))
            Y = propagation.affine_chain(S, np.eye(7, 3, dtype=complex), rows=rows,
                                         steps=n, work=self.work)
            if self.sensor is None:
                out = Y[:, 0, :], Y[:, 1, :], Y[:, 2, :]
            else:           # y = -(a + c) z - g z' + (rho - 1) r0 (i w' - w^2)
                k = a + self.sensor.tilt_gravity
                z, dz, z_a, dz_a, z_g, dz_g = (Y[:, i, :] for i in range(6))
                basis = -k * z - g * dz
                basis[:, 2] += (self.sensor.radius_ratio - 1.0) * self.rec.rigid
                out = basis, -z - k * z_a - g * dz_a, -dz - k * z_g - g * dz_g
        return out if all(np.all(np.isfinite(x)) for x in out) else None

    def linear_columns(self, basis: np.ndarray) -> list:
        """The output's columns of the free linear parameters, in :attr:`free`'s order.

        z0 and z0' (real and imaginary each), r0 when free, the bias when fitted.
        """
        cols = [basis[:, 0], 1j * basis[:, 0], basis[:, 1], 1j * basis[:, 1]]
        if self.r0 is None:
            cols.append(basis[:, 2])
        if 'bias_x' in self.free:
            ones = np.ones(self.rec.n)
            cols += [ones + 0j, 1j * ones]
        return cols

    def g_of(self, a: float, g: float) -> float:
        return g if self.zeta is None else 2.0 * self.zeta * math.sqrt(max(a, 0.0))

    def evaluate(self, a: float, g: float) -> _Point | None:
        """The fit of the linear parameters at (a, g); None if the model overflows."""
        g = self.g_of(a, g)
        outputs = self._outputs(a, g)
        if outputs is None:
            return None
        basis, da, dg = outputs
        y = self.y
        if self.r0 is not None:
            y = y - self.r0 * _stack(basis[:, 2:3])[:, 0]
        A = _stack(np.stack(self.linear_columns(basis), axis=1))
        norms = np.linalg.norm(A, axis=0)
        norms[norms == 0] = 1.0
        coef = np.linalg.lstsq(A / norms, y, rcond=1e-13)[0] / norms
        r0 = float(coef[4]) if self.r0 is None else self.r0
        x0 = np.array([coef[0] + 1j * coef[1], coef[2] + 1j * coef[3], r0])
        residual = y - A @ coef
        columns = []
        for x in (x0, np.array([0.0, 0.0, r0])):    # and without the free vibration
            Ja, Jg = da @ x, dg @ x
            if self.zeta is None:
                columns.append(_stack(np.stack([Ja, Jg], axis=1)))
            else:       # g = 2 zeta sqrt(a)
                columns.append(_stack((Ja + Jg * (self.zeta / math.sqrt(a)))[:, None]))
        J = np.concatenate([columns[0], A], axis=1)
        z_h = basis[:, :2] @ x0[:2]
        return _Point(a=a, g=g, rss=float(residual @ residual), residual=residual,
                      linear=coef, r0=r0, jacobian=J, free=self.free, forced=columns[1],
                      free_energy=float(np.vdot(z_h, z_h).real))

    def dof(self) -> int:
        return 2 * self.rec.n - len(self.free)


def _scaled(J):
    norms = np.linalg.norm(J, axis=0)
    safe = np.where(norms > 0, norms, 1.0)
    return J / safe, safe, norms


def _moved(point: _Point, step: np.ndarray, k_nl: int) -> _Point:
    """``point`` moved by a Gauss-Newton step, linearized (no new evaluation)."""
    residual = point.residual - point.jacobian @ step
    linear = point.linear + step[k_nl:]
    g = point.g + step[1] if k_nl == 2 else point.g
    r0 = float(linear[4]) if 'r0' in point.free else point.r0
    return dataclasses.replace(point, a=point.a + float(step[0]), g=g, linear=linear, r0=r0,
                               residual=residual, rss=float(residual @ residual))


def _refine(problem: _Problem, a: float, g: float, max_iterations: int = _MAX_ITERATIONS,
            start: _Point | None = None,
            lazy: bool = False) -> tuple[_Point | None, int, bool]:
    """Levenberg-Marquardt over the nonlinear parameters from (a, g).

    Returns (point, iterations, converged); point None when the start overflows. With
    ``lazy``, a first step within half a standard deviation is taken as the linearized
    last step (the warm start of a sliding window, whose optimum moves little).
    """
    first_point = start or problem.evaluate(a, g)
    if first_point is None:
        return None, 0, False
    point: _Point = first_point
    lam = 1e-3
    k_nl = len(problem.nonlinear)
    for iteration in range(1, max_iterations + 1):
        Js, scale, _ = _scaled(point.jacobian)
        JtJ = Js.T @ Js
        grad = Js.T @ point.residual
        dof = max(problem.dof(), 1)
        sigma2 = point.rss / dof
        try:
            cov_nl = np.linalg.pinv(JtJ, rcond=1e-14, hermitian=True)[:k_nl, :k_nl] \
                * sigma2 / np.outer(scale[:k_nl], scale[:k_nl])
        except np.linalg.LinAlgError:
            cov_nl = np.full((k_nl, k_nl), np.inf)
        std_nl = np.sqrt(np.abs(np.diag(cov_nl)))
        accepted = False
        first = True
        for _ in range(12):
            A = JtJ + lam * np.diag(np.diag(JtJ))
            try:
                step = np.linalg.lstsq(A, grad, rcond=1e-15)[0] / scale
            except np.linalg.LinAlgError:
                return point, iteration, False
            if first and np.all(np.abs(step[:k_nl]) <= np.maximum(
                    1e-2 * std_nl, 1e-13 * np.abs([point.a, point.g][:k_nl]) + 1e-300)):
                # the next step would move (a, g) by < 1 % of their standard deviations
                return point, iteration, True
            if first and lazy and np.all(np.abs(step[:k_nl]) <= 0.5 * std_nl):
                return _moved(point, step, k_nl), iteration, True
            first = False
            a_new = point.a + step[0]
            g_new = point.g + step[1] if problem.zeta is None else point.g
            if not a_new > 0:
                lam *= 10
                continue
            trial = problem.evaluate(a_new, g_new)
            if trial is not None and trial.rss <= point.rss * (1 + 1e-15):
                accepted = True
                break
            lam *= 10
        if not accepted or trial is None:
            return point, iteration, True     # no decrease possible: at the minimum
        small = np.all(np.abs(step[:k_nl]) <= np.maximum(
            1e-4 * std_nl, 1e-13 * np.abs([point.a, point.g][:k_nl]) + 1e-300))
        decrease = point.rss - trial.rss
        point = trial
        lam = max(lam / 10, 1e-9)
        if small or decrease <= 1e-14 * point.rss:
            return point, iteration, True
    return point, max_iterations, False


# -- the equation-error start ---------------------------------------------------------

def _uniform(rec: _Record):
    """(dt, z, w, w') of the record on a uniform grid of its span.

    Interpolated when the samples are not uniform.
    """
    t = rec.t
    n = rec.n
    uniform = np.linspace(t[0], t[-1], n)
    if np.max(np.abs(uniform - t)) > 1e-6 * (t[-1] - t[0]) / n:
        z = np.interp(uniform, t, rec.z.real) + 1j * np.interp(uniform, t, rec.z.imag)
        w = np.interp(uniform, t, rec.omega)
        wd = np.interp(uniform, t, rec.slopes)
    else:
        z, w, wd = rec.z, rec.omega, rec.slopes
    return (t[-1] - t[0]) / (n - 1), z, w, wd


def _modulated(signals: np.ndarray, dt: float):
    """Each signal integrated against phi, phi', phi'' over sliding windows.

    phi = s^2 (1 - s)^2 on windows of m samples, m = n/2, n/4, ... >= 9, hopping by m/4.
    Yields, per window length, the integrals (three arrays (signals, windows): against
    phi, phi', phi'') and the equation-error scales of white noise on the signal for
    a = 0 and a = 1 (sqrt(dt sum phi''^2), sqrt(dt sum phi^2)).
    """
    m = signals.shape[1] // 2
    while m >= 9:
        hop = max(1, m // 4)
        s = np.linspace(0.0, 1.0, m)
        L = (m - 1) * dt
        phi = s * s * (1 - s) ** 2
        dphi = 2 * s * (1 - s) * (1 - 2 * s) / L
        ddphi = (2 - 12 * s + 12 * s * s) / L**2
        ddphi[[0, -1]] *= 0.5       # trapezoidal rule (phi and phi' vanish at the ends)
        win = np.lib.stride_tricks.sliding_window_view(signals, m, axis=1)[:, ::hop]
        yield ((win @ phi * dt, win @ dphi * dt, win @ ddphi * dt),
               (math.sqrt(dt * np.sum(ddphi**2)), math.sqrt(dt * np.sum(phi**2))))
        m //= 2


def _equation_error(signals: np.ndarray, dt: float, columns):
    """(a, g, the rest) of the modulated equation a P - g D1 + columns = -D2 + 2i W1 + Q.

    ``signals``: (the measured y, w y, (i w' + w^2) y, then the forcing's signals);
    P, D1, D2 = int phi, phi', phi'' times y, W1 = int phi' w y, Q = int phi (i w' +
    w^2) y; ``columns(integrals)`` gives the forcing's columns (windows, k) from the
    integrals of the signals (:func:`_modulated`). Weighted least squares, the weights
    re-evaluated at the estimate of a (three passes); None if no window fits or a <= 0.
    """
    rows, rhs, scale_dd, scale_p = [], [], [], []
    for (I0, I1, I2), (sd, sp) in _modulated(signals, dt):
        P, D1, D2, W1, Q = I0[0], I1[0], I2[0], I1[1], I0[2]
        rows.append(np.concatenate([np.stack([P, -D1], axis=1), columns(I0, I1, I2)],
                                   axis=1))
        rhs.append(-D2 + 2j * W1 + Q)
        scale_dd.append(np.full(len(P), sd))
        scale_p.append(np.full(len(P), sp))
    if not rows:
        return None
    R = np.concatenate(rows)
    y = np.concatenate(rhs)
    w_dd = np.concatenate(scale_dd)
    w_p = np.concatenate(scale_p)
    a = 0.0
    est = np.zeros(R.shape[1])
    for _ in range(3):
        wt = 1.0 / np.sqrt(w_dd**2 + (a * w_p) ** 2)
        A = _stack(R * wt[:, None])
        b = _stack((y * wt)[:, None])[:, 0]
        norms = np.linalg.norm(A, axis=0)
        norms[norms == 0] = 1.0
        est = np.linalg.lstsq(A / norms, b, rcond=1e-12)[0] / norms
        if not (np.all(np.isfinite(est)) and est[0] > 0):
            return None
        a = float(est[0])
    return est


def _modulating_start(rec: _Record):
    """(a, g, r0) from modulating functions phi = s^2 (1 - s)^2 over windows (module doc).

    For each window: a P - g D1 - r0 F = -D2 + 2i W1 + Q with P, D1, D2 = int phi,
    phi', phi'' times z, W1 = int phi' w z, Q = int phi (i w' + w^2) z,
    F = int phi (w^2 - i w').
    """
    dt, z, w, wd = _uniform(rec)
    signals = np.stack([z, w * z, (1j * wd + w * w) * z, w * w - 1j * wd])
    est = _equation_error(signals, dt, lambda I0, I1, I2: -I0[3][:, None])
    return None if est is None else (float(est[0]), float(est[1]), float(est[2]))


def _accelerometer_start(rec: _Record, sensor: Accelerometer):
    """(a, g, r0) from the accelerometer's y by modulating functions (docs/identification.md).

    Applying the rod's operator L = d^2 + (g + 2 i w) d + (a - w^2 + i w') to
    y = -(a + c) z - g z' + (rho - 1) r0 R + beta (R = i w' - w^2), with L z = -r0 R
    and L z' taken as (L z)' (exact at constant w; it drops g times w' terms):

        L y = r0 (c R + (rho - 1) L0 R) + (a r0) rho R + (g r0) rho R' + beta R + a beta,

    L0 = L at a = g = 0. Linear in a, g, r0 and the products a r0, g r0, beta, a beta
    taken as unknowns of their own; integrated against phi, derivatives moved onto it.
    """
    dt, y, w, wd = _uniform(rec)
    R = 1j * wd - w * w
    c, rho = sensor.tilt_gravity, sensor.radius_ratio
    signals = np.stack([y, w * y, (1j * wd + w * w) * y, R, w * R, (-1j * wd - w * w) * R,
                        np.ones_like(y)])

    def columns(I0, I1, I2):
        L0R = I2[3] - 2j * I1[4] + I0[5]
        return -np.stack([c * I0[3] + (rho - 1) * L0R, rho * I0[3], -rho * I1[3], I0[3],
                          1j * I0[3], I0[6], 1j * I0[6]], axis=1)

    est = _equation_error(signals, dt, columns)
    return None if est is None else (float(est[0]), float(est[1]), float(est[2]))


def _grid_start(problem: _Problem, rec: _Record):
    """Fallback start: the best of a log grid of natural frequencies (zero damping)."""
    span = rec.t[-1] - rec.t[0]
    nyquist = math.pi / float(np.median(rec.h))
    lo = max(2 * math.pi / span / 4, 1e-3)
    best = None
    for w0 in np.geomspace(lo, nyquist, 60):
        point = problem.evaluate(w0 * w0, 0.0)
        if point is not None and (best is None or point.rss < best.rss):
            best = point
    return best


# -- judgement --------------------------------------------------------------------------

@dataclass(frozen=True)
class _Limits:
    max_relative_std: float
    max_damping_std: float


def _covariances(point: _Point, problem: _Problem, drop=()):
    """Covariance sigma^2 (J^T J)^-1 of the free parameters, and sigma^2.

    The ``drop`` parameters are taken as known (their rows and columns are zero).
    """
    keep = [i for i, name in enumerate(point.free) if name not in drop]
    sigma2 = point.rss / max(2 * problem.rec.n - len(keep), 1)
    J = point.jacobian
    k_nl = point.forced.shape[1]
    if not point.free_energy > _DETECTION * 2 * sigma2:
        # A free vibration fitted at the start but not resolved above the noise: its
        # fitted amplitude is noise, and the information it would carry on (a, g) is
        # not there. Take the information without it (as at the true parameters).
        J = np.concatenate([point.forced, J[:, k_nl:]], axis=1)
    J = J[:, keep]
    Js, scale, _ = _scaled(J)
    _, sv, Vt = np.linalg.svd(Js, full_matrices=False)
    inv = np.where(sv > sv[0] * 1e-15, 1.0 / np.maximum(sv, 1e-300) ** 2, 0.0)
    cov = (Vt.T * inv) @ Vt
    cov = cov * sigma2 / np.outer(scale, scale)
    full = np.full((len(point.free), len(point.free)), 0.0)
    full[np.ix_(keep, keep)] = cov
    return full, sigma2


def _physical(point: _Point, problem: _Problem, cov: np.ndarray):
    """Values and 3x3 covariance of (w0, r0, zeta) from (a, g, r0) and their covariance."""
    a, g = float(point.a), float(point.g)
    w0 = math.sqrt(a)
    zeta = g / (2 * w0)
    T = np.zeros((3, len(point.free)))
    idx = {name: i for i, name in enumerate(point.free)}
    T[0, idx['a']] = 0.5 / w0
    if 'r0' in idx:
        T[1, idx['r0']] = 1.0
    if 'g' in idx:
        T[2, idx['a']] = -zeta / (2 * a)
        T[2, idx['g']] = 0.5 / w0
    return (w0, point.r0, zeta), T @ cov @ T.T


def _structural(point: _Point):
    """Sets of physical parameters in the null space of the (unit-column) Jacobian."""
    Js, _, norms = _scaled(point.jacobian)
    names = set()
    for i, name in enumerate(point.free):
        if norms[i] == 0 and name in _NAMES:
            names.add(_NAMES[name])
    _, sv, Vt = np.linalg.svd(Js, full_matrices=False)
    groups = [frozenset([n]) for n in names]
    for k in np.nonzero(sv < _SINGULAR * sv[0])[0]:
        group = frozenset(_NAMES[name] for i, name in enumerate(point.free)
                          if name in _NAMES and abs(Vt[k, i]) > 0.2)
        if group:
            groups.append(group)
    return groups


_WHY = {
    'natural_frequency': 'the motion shows neither a free vibration nor a deflection that '
                         'follows w enough to measure the stiffness',
    'eccentricity': 'the hub turns too little (w and w\' near zero) for the eccentric '
                    'forcing r0 (w^2 - i w\') to act',
    'damping_ratio': 'the record has no free vibration (whirl) whose decay would show the '
                     'damping, and too little deflection rate for the damping force; give '
                     'damping_ratio= if it is known',
}


_WHY_BIASED = {
    'eccentricity': 'the hub turns too little (w and w\' near zero) for the eccentric '
                    'forcing r0 (w^2 - i w\') to act, or w changes too little: the '
                    'forcing\'s share of the acceleration is then nearly constant, as the '
                    'accelerometer\'s bias is (a record with w changing, from rest for one, '
                    'separates them; give eccentricity= if it is known)',
}


def _why(name: str, problem: _Problem) -> str:
    """Why ``name`` is not identifiable, for what the problem measures."""
    if problem.sensor is not None and problem.sensor.bias and name in _WHY_BIASED:
        return _WHY_BIASED[name]
    return _WHY[name]


def _estimate(point, problem, iterations, drop=(), fixed=()):
    cov, sigma2 = _covariances(point, problem, drop)
    (w0, r0, zeta), phys = _physical(point, problem, cov)
    values = {'natural_frequency': w0, 'eccentricity': r0, 'damping_ratio': zeta}
    stds = {name: math.sqrt(max(phys[i, i], 0.0)) if np.isfinite(phys[i, i]) else math.inf
            for i, name in enumerate(values)}
    for name in fixed:
        stds[name] = 0.0
    dropped = {_NAMES[n] for n in drop}
    for name in dropped:
        values[name] = math.nan
        stds[name] = math.nan
    rec = problem.rec
    coef = point.linear
    bias = complex(coef[-2], coef[-1]) if 'bias_x' in point.free else None
    return RigEstimate(
        natural_frequency=values['natural_frequency'],
        eccentricity=values['eccentricity'],
        damping_ratio=values['damping_ratio'],
        natural_frequency_std=stds['natural_frequency'],
        eccentricity_std=stds['eccentricity'],
        damping_ratio_std=stds['damping_ratio'],
        noise_std=math.sqrt(sigma2),
        residual_rms=math.sqrt(point.rss / rec.n),
        samples=rec.n, start_time=float(rec.t[0]), end_time=float(rec.t[-1]),
        initial_deflection=complex(coef[0], coef[1]), initial_rate=complex(coef[2], coef[3]),
        fixed=tuple(fixed), iterations=iterations, covariance=phys,
        accelerometer_bias=bias)


def _judge(point, problem, iterations, limits: _Limits, fixed, unidentified=None):
    """The estimate, or NotIdentifiable naming what the record does not determine."""
    sigma2 = point.rss / max(problem.dof(), 1)
    model = problem.y - point.residual
    n = problem.rec.n
    zhat = model[:n] + 1j * model[n:]
    variation = float(np.sum(np.abs(zhat - zhat.mean()) ** 2))
    if not variation > _DETECTION * 2 * sigma2:
        what, unit = _measured(problem.sensor), _measured(problem.sensor, unit=True)
        raise NotIdentifiable(
            f'no motion above the noise: the fitted {what} varies by '
            f'{math.sqrt(variation / n):.3g} {unit} RMS, against noise of '
            f'{math.sqrt(sigma2):.3g} {unit} per sample (energy ratio '
            f'{variation / (2 * sigma2) if sigma2 else 0.0:.3g}, needs > {_DETECTION:g})',
            tuple(_NAMES[k] for k in ('a', 'r0', 'g')))
    bad = dict(unidentified or {})
    singular = set()
    for group in _structural(point):
        singular |= group
        for name in group:
            if len(group) == 1:
                why = _why(name, problem)
            else:
                others = ' and '.join(sorted(group - {name}))
                why = (f'it enters the motion only in a combination with {others} (a '
                       'deflection that does not change, for one, shows only the static '
                       'r0 w^2 / (w0^2 - w^2))')
            bad.setdefault(name, 'the information matrix is singular: ' + why)
    if not bad:
        est = _estimate(point, problem, iterations, fixed=fixed)
        checks = (
            ('natural_frequency', est.natural_frequency_std,
             limits.max_relative_std * est.natural_frequency,
             f'{limits.max_relative_std:.3g} of the estimate'),
            ('eccentricity', est.eccentricity_std,
             limits.max_relative_std * abs(est.eccentricity),
             f'{limits.max_relative_std:.3g} of the estimate'),
            ('damping_ratio', est.damping_ratio_std, limits.max_damping_std,
             f'{limits.max_damping_std:.3g}'),
        )
        for name, std, limit, text in checks:
            if name not in fixed and not std <= limit:
                value = getattr(est, name)
                bad[name] = (f'its standard deviation {std:.3g} (estimate {value:.6g}) '
                             f'exceeds the limit, {text}: ' + _why(name, problem))
        if not bad:
            return est
    inv = {v: k for k, v in _NAMES.items()}
    # the structurally singular ones are taken as known (else every variance is
    # infinite); the others keep their (marginal) part in the rest's variances
    drop = tuple(inv[name] for name in singular if inv[name] in point.free)
    partial = None
    if len(bad) < len(problem.nonlinear) + ('r0' in point.free):
        partial = _estimate(point, problem, iterations, drop=drop, fixed=fixed)
        partial = dataclasses.replace(partial, **{
            key: math.nan for name in bad for key in (name, name + '_std')})
    names = tuple(n for n in ('natural_frequency', 'eccentricity', 'damping_ratio')
                  if n in bad)
    reason = '; '.join(f'{n} is not identifiable from this record: {bad[n]}' for n in names)
    raise NotIdentifiable(reason, names, partial)


# -- public -----------------------------------------------------------------------------

def _measured(sensor: Accelerometer | None, unit: bool = False) -> str:
    """What the record measures (with its unit)."""
    if sensor is None:
        return 'm' if unit else 'deflection'
    return 'm/s^2' if unit else 'tip acceleration'


def _fixed_value(name, value, *, nonnegative=True):
    if value is None:
        return None
    return finite_number(name, value, nonnegative=nonnegative)


def _fit(rec: _Record, zeta, r0, limits: _Limits, warm=None, max_iterations=_MAX_ITERATIONS,
         work: propagation.ChainWorkspace | None = None, sensor: Accelerometer | None = None):
    """Identify from a record; ``warm`` = (a, g) starts Gauss-Newton there instead.

    With ``sensor`` the record's z is that accelerometer's x + i y, and the
    equation-error start is the accelerometer's.
    """
    fixed = tuple(n for n, v in (('damping_ratio', zeta), ('eccentricity', r0))
                  if v is not None)
    unidentified = {}
    turning = bool(np.any(rec.omega != 0) or np.any(rec.slopes != 0))
    if not turning and not np.any(rec.z != rec.z[0]):
        raise NotIdentifiable(f'no motion: the hub does not turn (w = 0) and the '
                              f'{_measured(sensor)} does not change (no whirl)')
    if not turning and r0 is None:
        unidentified['eccentricity'] = ('the hub does not turn (w = 0 throughout), so the '
                                        'eccentric forcing r0 (w^2 - i w\') is zero')
        r0 = 0.0
    if not np.any(rec.z):
        raise NotIdentifiable(f'no motion: the {_measured(sensor)} is zero throughout, so it '
                              'carries no information on the natural frequency or the '
                              'damping')
    problem = _Problem(rec, zeta=zeta, r0=r0, work=work, sensor=sensor)
    point, iterations, converged = None, 0, False
    if warm is not None:
        point, iterations, converged = _refine(problem, warm[0], warm[1],
                                               max_iterations=max_iterations, lazy=True)
    if point is None or not converged:
        start = _modulating_start(rec) if sensor is None else \
            _accelerometer_start(rec, sensor)
        if start is not None:
            point, iterations, converged = _refine(problem, start[0], start[1])
        if point is None or not converged:
            grid = _grid_start(problem, rec)
            if grid is not None:
                point, iterations, converged = _refine(problem, grid.a, grid.g, start=grid)
    if point is None:
        raise NotIdentifiable('the output-error fit failed: the model overflows from every '
                              'start (no stable rod fits this record)')
    return _judge(point, problem, iterations, limits, fixed, unidentified)


def identify_rig(t, u, v, omega, *, omega_dot=None, damping_ratio=None, eccentricity=None,
                 max_relative_std: float = 0.1, max_damping_std: float = 0.1,
                 sensor: Accelerometer | None = None) -> RigEstimate:
    """Natural frequency, eccentricity and damping of the rig from one record.

    Args:
        t: sample times, s (strictly increasing; irregular allowed).
        u: radial deflection of the mass, m (rotating frame); with ``sensor``, the tip
            accelerometer's x, m/s^2.
        v: tangential deflection, m; with ``sensor``, the accelerometer's y, m/s^2.
        omega: the hub's measured angular velocity at the same times, rad/s.
        omega_dot: its angular acceleration, rad/s^2 (default: from a cubic spline of
            ``omega``).
        damping_ratio: the damping ratio if known (then not identified).
        eccentricity: r0 in m if known (then not identified).
        max_relative_std: largest accepted standard deviation of w0 and of r0, as a
            fraction of the estimate.
        max_damping_std: largest accepted standard deviation of the damping ratio.
        sensor: the :class:`Accelerometer` that ``u`` and ``v`` come from, or None (they
            are the deflection). The estimate's noise_std and residual_rms are then in
            m/s^2, and its initial_deflection and initial_rate are the fit's nuisance
            state all the same (m, m/s).

    Returns:
        :class:`RigEstimate`.

    Raises:
        ValueError: unusable input (lengths, non-finite values, times not increasing,
            fewer than 3 samples).
        NotIdentifiable: (a ValueError) the record does not determine some parameter;
            the exception names them, says why, and carries the estimate of the rest.
    """
    rec = _record(t, u, v, omega, omega_dot)
    zeta = _fixed_value('damping_ratio', damping_ratio)
    r0 = _fixed_value('eccentricity', eccentricity)
    limits = _Limits(finite_number('max_relative_std', max_relative_std, positive=True),
                     finite_number('max_damping_std', max_damping_std, positive=True))
    return _fit(rec, zeta, r0, limits, sensor=sensor)


def rig_cramer_rao(t, omega, natural_frequency, eccentricity, damping_ratio, noise_std, *,
                   omega_dot=None, initial_deflection=0j, initial_rate=0j,
                   sensor: Accelerometer | None = None) -> dict[str, float]:
    """Cramer-Rao standard deviations of (w0, r0, zeta) for a record of this drive.

    White Gaussian noise of ``noise_std`` (m; with ``sensor``, m/s^2 on the
    accelerometer's x and y) on u and on v, the initial state unknown (nuisance, and the
    accelerometer's bias when it fits one): sigma^2 (J^T J)^-1 at the given parameters,
    J the Jacobian of the model output. Returns a dict with 'natural_frequency',
    'eccentricity', 'damping_ratio' (standard deviations) and 'covariance' (3x3).
    """
    w = np.asarray(omega, dtype=float)
    zeros = np.zeros_like(w)
    rec = _record(t, zeros, zeros, w, omega_dot)
    w0 = finite_number('natural_frequency', natural_frequency, positive=True)
    r0 = finite_number('eccentricity', eccentricity)
    zeta = finite_number('damping_ratio', damping_ratio)
    sigma = finite_number('noise_std', noise_std, positive=True)
    a, g = w0 * w0, 2 * zeta * w0
    problem = _Problem(rec, sensor=sensor)
    outputs = problem._outputs(a, g)
    if outputs is None:
        raise ValueError('the model overflows on this record')
    basis, da, dg = outputs
    x0 = np.array([complex(initial_deflection), complex(initial_rate), r0])
    cols = [da @ x0, dg @ x0, *problem.linear_columns(basis)]     # r0's is the 7th
    J = _stack(np.stack(cols, axis=1))
    Js, scale, _ = _scaled(J)
    cov = np.linalg.pinv(Js.T @ Js, hermitian=True) * sigma**2 / np.outer(scale, scale)
    T = np.zeros((3, len(cols)))
    T[0, 0] = 0.5 / w0
    T[1, 6] = 1.0
    T[2, 0] = -zeta / (2 * a)
    T[2, 1] = 0.5 / w0
    phys = T @ cov @ T.T
    stds = np.sqrt(np.maximum(np.diag(phys), 0.0))
    return {'natural_frequency': float(stds[0]), 'eccentricity': float(stds[1]),
            'damping_ratio': float(stds[2]), 'covariance': phys}


# -- online -----------------------------------------------------------------------------

HUB_INPUTS = ('omega', 'angle')
"""What a :class:`RigIdentifier` is fed for the hub: its angular velocity or its angle."""


def _rates_from_angle(t: np.ndarray, angle: np.ndarray, samples: int):
    """(w, w') at the samples from the hub's angle (rad/s, rad/s^2).

    A quadratic Savitzky-Golay fit over ``samples`` samples (odd), the angle unwrapped
    first (an encoder may wrap at 2 pi). The samples must be evenly spaced (to 1 % of
    their interval); NotIdentifiable otherwise.
    """
    h = np.diff(t)
    step = float(np.median(h))
    if not np.all(np.abs(h - step) <= 0.01 * step):
        raise NotIdentifiable('the hub angle is differentiated on evenly spaced samples; '
                              f'these are spaced {h.min():.3g} to {h.max():.3g} s')
    if len(t) < samples:
        raise NotIdentifiable(f'too few samples ({len(t)}) for the hub angle\'s fit over '
                              f'{samples}')
    theta = np.unwrap(angle)
    return (savgol_filter(theta, samples, 2, deriv=1, delta=step),
            savgol_filter(theta, samples, 2, deriv=2, delta=step))


class RigIdentifier:
    """The rig identified over a sliding window of samples, fed one sample at a time.

    For a live node: ``push`` each sample (t, u, v, w[, w']); every ``update_interval``
    seconds of sample time, once the samples span ``window``, the rig is identified
    from the window, starting the Gauss-Newton fit from the previous estimate (warm
    start: one or two iterations when the rig does not change; a fresh start from the
    equation-error estimate when the warm start does not converge). Memory is a ring of
    about twice the window.

    Attributes:
        estimate: the latest update's :class:`RigEstimate` (None before the first one and
            after an update that could not identify the rig).
        reason: '' after a successful update, else why there is no estimate.
        error: the :class:`NotIdentifiable` of the latest update, or None.

    Args:
        window: length of the identification window, s.
        sample_interval: expected interval between samples, s (sizes the buffer; half of
            it is the tolerance on the window's start).
        update_interval: sample time between updates, s.
        damping_ratio: fixed (known) damping ratio, or None to identify it.
        eccentricity: fixed (known) r0 in m, or None to identify it.
        max_relative_std: as in :func:`identify_rig`.
        max_damping_std: as in :func:`identify_rig`.
        warm_iterations: Gauss-Newton iterations allowed to a warm start.
        sensor: the :class:`Accelerometer` whose x, y are pushed as (u, v), or None
            (the deflection).
        hub: what is pushed as ``omega``: 'omega' (the hub's angular velocity, rad/s)
            or 'angle' (its angle, rad, e.g. an encoder's quantised one: w and w' are
            then taken from it over each window by a quadratic Savitzky-Golay fit over
            ``angle_smoothing`` s, which needs evenly spaced samples).
        angle_smoothing: the span of that fit, s (at least 5 samples).
    """

    def __init__(self, window: float = 10.0, sample_interval: float = 0.01,
                 update_interval: float = 0.1, *, damping_ratio=None, eccentricity=None,
                 max_relative_std: float = 0.1, max_damping_std: float = 0.1,
                 warm_iterations: int = 4, sensor: Accelerometer | None = None,
                 hub: str = 'omega', angle_smoothing: float = 0.2):
        self.window = finite_number('RigIdentifier.window', window, positive=True)
        self.sample_interval = finite_number('RigIdentifier.sample_interval',
                                             sample_interval, positive=True)
        self.update_interval = finite_number('RigIdentifier.update_interval',
                                             update_interval, nonnegative=True)
        samples = self.window / self.sample_interval
        if not MIN_SAMPLES <= samples <= 1e6:
            raise ValueError(f'RigIdentifier: window / sample_interval = {samples:.3g} '
                             f'samples; it must be {MIN_SAMPLES}..1e6')
        self.zeta = _fixed_value('damping_ratio', damping_ratio)
        self.r0 = _fixed_value('eccentricity', eccentricity)
        self.limits = _Limits(
            finite_number('max_relative_std', max_relative_std, positive=True),
            finite_number('max_damping_std', max_damping_std, positive=True))
        if isinstance(warm_iterations, bool) or not isinstance(warm_iterations, int) \
                or warm_iterations < 1:
            raise ValueError(f'warm_iterations must be an integer >= 1, got '
                             f'{warm_iterations!r}')
        self.warm_iterations = warm_iterations
        if sensor is not None and not isinstance(sensor, Accelerometer):
            raise ValueError(f'sensor must be an Accelerometer or None, got {sensor!r}')
        self.sensor = sensor
        if hub not in HUB_INPUTS:
            raise ValueError(f'hub must be one of {HUB_INPUTS}, got {hub!r}')
        self.hub = hub
        self.angle_samples = 2 * round(0.5 * finite_number(
            'angle_smoothing', angle_smoothing, positive=True) / self.sample_interval) + 1
        if hub == 'angle' and self.angle_samples < 5:
            raise ValueError(f'angle_smoothing {angle_smoothing!r} s spans fewer than 5 '
                             f'samples of {self.sample_interval!r} s')
        self._capacity = 2 * int(math.ceil(samples)) + 16
        self._work = propagation.ChainWorkspace()
        self.reset()

    def reset(self) -> None:
        """Forget all samples and estimates."""
        self._buf = np.empty((self._capacity, 5))
        self._begin = self._end = 0
        self._first = math.nan
        self._last_update = -math.inf
        self._with_rate: bool | None = None
        self._warm: tuple[float, float] | None = None
        self._eccentricity: RigEstimate | None = None    # the best-determined r0's
        self.estimate: RigEstimate | None = None
        self.reason = 'window not filled'
        self.error: NotIdentifiable | None = None

    @property
    def filled(self) -> bool:
        """True once the samples span the window."""
        if self._end == 0:
            return False
        span = self._buf[self._end - 1, 0] - self._first
        return span >= self.window - 1.5 * self.sample_interval

    def push(self, t: float, u: float, v: float, omega: float,
             omega_dot: float | None = None) -> RigEstimate | None:
        """Add one sample (s, m, m, rad/s[, rad/s^2]); the new estimate if one was due.

        None when no update was due or the update failed (see ``reason``).
        ``omega_dot`` must be given with every sample or with none. Raises ValueError
        for a non-finite value or a time not after the previous one (the sample is then
        not stored).
        """
        values = [finite_number(name, x) for name, x in
                  (('t', t), ('u', u), ('v', v), ('omega', omega))]
        with_rate = omega_dot is not None
        if self._with_rate is not None and with_rate != self._with_rate:
            raise ValueError('omega_dot must be given with every sample or with none')
        values.append(finite_number('omega_dot', omega_dot) if with_rate else 0.0)
        if self._end and not values[0] > self._buf[self._end - 1, 0]:
            raise ValueError(f'sample times must increase strictly: {values[0]!r} s after '
                             f'{self._buf[self._end - 1, 0]!r} s')
        self._with_rate = with_rate
        if self._end == len(self._buf):
            self._make_room()
        self._buf[self._end] = values
        self._end += 1
        if math.isnan(self._first):
            self._first = values[0]
        if self.filled and values[0] - self._last_update >= self.update_interval * (1 - 1e-9):
            return self.update()
        return None

    def update(self) -> RigEstimate | None:
        """Identify from the current window now; the estimate, or None (see ``reason``)."""
        if not self.filled:
            self.estimate, self.error = None, None
            self.reason = 'window not filled'
            return None
        newest = self._buf[self._end - 1, 0]
        self._trim(newest)
        data = self._buf[self._begin:self._end]
        self._last_update = newest
        try:
            if self.hub == 'angle':
                omega, omega_dot = _rates_from_angle(data[:, 0], data[:, 3],
                                                     self.angle_samples)
            else:
                omega, omega_dot = data[:, 3], data[:, 4] if self._with_rate else None
            rec = _record(data[:, 0], data[:, 1], data[:, 2], omega, omega_dot)
            est = self._fit(rec)
        except NotIdentifiable as exc:
            self.estimate, self.error, self.reason = None, exc, exc.reason
            return None
        self.estimate, self.error, self.reason = est, None, ''
        self._warm = (est.natural_frequency**2,
                      2 * est.damping_ratio * est.natural_frequency)
        if 'eccentricity' not in est.fixed and (
                self._eccentricity is None
                or est.eccentricity_std < self._eccentricity.eccentricity_std):
            self._eccentricity = est
        return est

    def _fit(self, rec: _Record) -> RigEstimate:
        """The window's estimate.

        From an accelerometer whose bias this window cannot tell from r0 (w nearly
        constant): r0 is taken from the earlier window that determined it best (its
        value and standard deviation; 'eccentricity' in ``fixed``), and the rest is
        identified.
        """
        fit = functools.partial(_fit, rec, self.zeta, limits=self.limits, warm=self._warm,
                                max_iterations=self.warm_iterations, work=self._work,
                                sensor=self.sensor)
        try:
            return fit(r0=self.r0)
        except NotIdentifiable as exc:
            best = self._eccentricity
            if self.sensor is None or not self.sensor.bias or best is None \
                    or exc.parameters != ('eccentricity',):
                raise
            est = fit(r0=best.eccentricity)
            covariance = est.covariance.copy()
            covariance[1, 1] = best.eccentricity_std**2
            return dataclasses.replace(est, eccentricity_std=best.eccentricity_std,
                                       covariance=covariance)

    def _trim(self, newest):
        oldest = newest - self.window + 0.5 * self.sample_interval
        self._begin += int(np.searchsorted(self._buf[self._begin:self._end, 0], oldest))

    def _make_room(self):
        """Drop samples older than the window; grow the ring if it is still full."""
        self._trim(self._buf[self._end - 1, 0])
        live = self._end - self._begin
        if live > len(self._buf) // 2:
            self._buf = np.concatenate((self._buf, np.empty_like(self._buf)))
        self._buf[:live] = self._buf[self._begin:self._end]
        self._begin, self._end = 0, live
