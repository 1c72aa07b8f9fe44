"""The one propagation kernel of the deflection equations under a prescribed rotation.

For a prescribed hub speed w(t) (rad/s) and acceleration w'(t) (rad/s^2) the deflection
equations (docs/model.md#eq-deflection) are linear in (u, v, u', v') with a forcing:
on the augmented state x = (u, v, u', v', 1) (m, m, m/s, m/s, 1) they read x' = A x.
Everything that propagates that system lives here, and every consumer uses it:
:func:`rotrod_core.simulate`, :func:`rotrod_core.simulate_batch`, the spin-up planner
and rig identification (the live RK4 stepper evaluates the same
:func:`~rotrod_core.model.equations.deflection_accelerations` directly).

- :func:`system_matrix`: A (shape ``(..., 5, 5)``), evaluated from
  :func:`~rotrod_core.model.equations.deflection_accelerations`, the one source of the
  equations, at the unit states (the equations are affine in the state).
- :func:`system_matrix_derivatives`: dA/dw and dA/dw', and
  :func:`complex_system_derivative`: the derivative by a coefficient; exact, by dual
  numbers through the same function (no second copy of the formula).
- :func:`complex_system`: for isotropic rods (k1 = k2, c1 = c2) the same system as a
  complex affine map of (z, z'), z = u + i v: z'' = x10 z + x11 z' + b1.
- Magnus exponents: :func:`magnus4` (two Gauss points, one commutator) and
  :func:`magnus6` (three Gauss points, Blanes, Casas & Ros 2000) for real matrices,
  :func:`magnus4_complex` and :func:`magnus6_complex_features` for complex affine
  tuples, and the derivatives of the fourth-order exponent (:func:`magnus4_derivative`,
  :func:`magnus4_step_derivative`). The same exponent and its derivatives by w and w'
  as combinations of ten matrices per system (:func:`system_features`,
  :func:`magnus4_basis`, :func:`magnus4_coefficients`, :func:`magnus4_combination`):
  one matrix product per system for all the steps of a profile (the planner's).
- Chains: :func:`affine_chain` (states x_k of x_{k+1} = phi_k x_k, blocked products),
  :func:`frechet_boole` (the derivative of a step's exponential applied to the
  state), :func:`sensitivity_chain` (forward sensitivities along the chain) and
  :func:`adjoint_chain` (the derivative of the end state by every earlier one).

Model: docs/model.md#kernel, docs/model.md#eq-deflection.

Complex affine tuples are ``(n11, n12, n21, n22, c1, c2)``: the matrix
[[n11, n12, c1], [n21, n22, c2], [0, 0, 0]] on (z, z', 1); ``None`` is a structural
zero, so the algebra skips it.
"""

from __future__ import annotations

import math

import numpy as np

from rotrod_core.model.equations import Coefficients, deflection_accelerations
from rotrod_core.numerics.dual import Dual, derivative_of, value_of

GAUSS2 = (0.5 - math.sqrt(3.0) / 6.0, 0.5 + math.sqrt(3.0) / 6.0)
"""Gauss-Legendre points of the fourth-order Magnus step, as fractions of the step."""
GAUSS3 = (0.5 - math.sqrt(15.0) / 10.0, 0.5, 0.5 + math.sqrt(15.0) / 10.0)
"""Gauss-Legendre points of the sixth-order Magnus step, as fractions of the step."""
_C4 = math.sqrt(3.0) / 12.0
_S15 = math.sqrt(15.0)
_COMPLEX_COLUMNS = (0, 2)     # u and u': an isotropic system is complex-linear in z, z'
_UNITS = ((1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0), (0.0, 0.0, 1.0, 0.0),
          (0.0, 0.0, 0.0, 1.0))

ISOTROPIC_FIELDS = {'natural_frequency_squared': ('w1sq', 'w2sq'),
                    'damping_rate': ('g1', 'g2'),
                    'load_radius': ('load_radius',)}
"""Coefficient groups of an isotropic rod, by name: w0^2 = k/M (1/s^2), g = c/M (1/s)
and the load radius re (m). Their derivatives are what identification needs."""


# -- the system matrix ----------------------------------------------------------------------

def _columns(co: Coefficients, omega, omega_dot, which=(0, 1, 2, 3)) -> tuple[tuple, list]:
    """Forcing (u'', v'') at the zero state, and the response to the unit states ``which``.

    Columns not asked for are None.
    """
    f0 = deflection_accelerations(co, 0.0, 0.0, 0.0, 0.0, omega, omega_dot)
    cols: list = [None] * 4
    for j in which:
        fu, fv = deflection_accelerations(co, *_UNITS[j], omega, omega_dot)
        cols[j] = (fu - f0[0], fv - f0[1])
    return f0, cols


def _assemble(f0, cols, part, kinematics: bool) -> np.ndarray:
    entries = [part(f) for f in f0] + [part(f) for col in cols for f in col]
    shape = np.broadcast_shapes(*(np.shape(e) for e in entries))
    A = np.zeros(shape + (5, 5))
    if kinematics:
        A[..., 0, 2] = 1.0
        A[..., 1, 3] = 1.0
    A[..., 2, 4], A[..., 3, 4] = entries[0], entries[1]
    for j in range(4):
        A[..., 2, j], A[..., 3, j] = entries[2 + 2 * j], entries[3 + 2 * j]
    return A


def system_matrix(co: Coefficients, omega, omega_dot) -> np.ndarray:
    """Augmented matrix A of x = (u, v, u', v', 1): x' = A x, shape ``(..., 5, 5)``.

    ``omega`` (rad/s), ``omega_dot`` (rad/s^2) and the coefficients' fields broadcast
    together (one matrix per time and system). Rows 2 and 3 are
    :func:`~rotrod_core.model.equations.deflection_accelerations` at the unit states,
    the forcing in the last column.
    """
    f0, cols = _columns(co, np.asarray(omega, dtype=float), np.asarray(omega_dot, dtype=float))
    return _assemble(f0, cols, value_of, kinematics=True)


def derivative_parts(co: Coefficients) -> tuple:
    """(D(0), D(1) - D(0), dA/dw') of each system: what :func:`system_matrix_derivatives` needs.

    D(w) is the dual derivative dA/dw at speed w (and w' = 0). The equations are a
    polynomial of degree 2 in w and 1 in w' (their terms are w^2, w, w' and w' times
    the state), so dA/dw = D(0) + w (D(1) - D(0)) and dA/dw' is a constant: both are
    evaluated once per system, not once per time. Shapes ``co``'s + (5, 5).
    """
    shape = np.shape(co.w1sq)
    zero, one = np.zeros(shape), np.ones(shape)
    at_rest = _assemble(*_columns(co, Dual(zero, one), zero), derivative_of, kinematics=False)
    at_one = _assemble(*_columns(co, Dual(one, one), zero), derivative_of, kinematics=False)
    by_acceleration = _assemble(*_columns(co, zero, Dual(zero, one)), derivative_of,
                                kinematics=False)
    return at_rest, at_one - at_rest, by_acceleration


def system_matrix_derivatives(co: Coefficients, omega, omega_dot, parts=None):
    """(dA/dw, dA/dw') at ``omega``, ``omega_dot``: exact, by dual numbers.

    Units: A's entries per rad/s and per rad/s^2. Shapes as :func:`system_matrix`.
    ``parts``: :func:`derivative_parts` of ``co``, when the caller keeps them.
    """
    w = np.asarray(omega, dtype=float)
    wd = np.asarray(omega_dot, dtype=float)
    at_rest, slope, by_acceleration = derivative_parts(co) if parts is None else parts
    out = np.broadcast_shapes(w.shape, wd.shape, np.shape(co.w1sq))
    by_speed = at_rest + w[..., None, None] * slope
    return (np.broadcast_to(by_speed, out + (5, 5)).copy(),
            np.broadcast_to(by_acceleration, out + (5, 5)).copy())


def is_isotropic(co: Coefficients) -> np.ndarray:
    """Whether each system has k1 = k2 and c1 = c2 (the complex form applies)."""
    return ((np.asarray(co.w1sq) == np.asarray(co.w2sq))
            & (np.asarray(co.g1) == np.asarray(co.g2)))


def _complex_from(f0, cols, part):
    """The complex affine tuple of an isotropic system from its real columns."""
    (f0u, f0v), (cu, _, cdu, _) = f0, cols
    x10 = part(cu[0]) + 1j * part(cu[1])
    x11 = part(cdu[0]) + 1j * part(cdu[1])
    b1 = part(f0u) + 1j * part(f0v)
    return x10, x11, b1


def complex_system(co: Coefficients, omega, omega_dot) -> tuple:
    """The isotropic system as a complex affine tuple: z'' = x10 z + x11 z' + b1.

    Returns ``(None, 1.0, x10, x11, None, b1)`` (module docstring) on (z, z', 1),
    z = u + i v (m). Valid where :func:`is_isotropic`; the caller checks. For the
    record: x10 = -(w0^2 - w^2 + i w'), x11 = -(g + 2 i w), b1 = re (w^2 - i w').
    """
    f0, cols = _columns(co, np.asarray(omega, dtype=float), np.asarray(omega_dot, dtype=float),
                        _COMPLEX_COLUMNS)
    x10, x11, b1 = _complex_from(f0, cols, value_of)
    return (None, 1.0, x10, x11, None, b1)


def complex_system_derivative(co: Coefficients, name: str, omega, omega_dot) -> tuple:
    """d(:func:`complex_system`)/d(coefficient group ``name``) (see ISOTROPIC_FIELDS).

    Exact, by dual numbers. Returns ``(None, None, dx10, dx11, None, db1)``.
    """
    if name not in ISOTROPIC_FIELDS:
        raise ValueError(f'name must be one of {tuple(ISOTROPIC_FIELDS)}, got {name!r}')
    values = dict(vars(co))
    for field in ISOTROPIC_FIELDS[name]:
        values[field] = Dual(values[field], 1.0)
    f0, cols = _columns(Coefficients(**values), np.asarray(omega, dtype=float),
                        np.asarray(omega_dot, dtype=float), _COMPLEX_COLUMNS)
    x10, x11, b1 = _complex_from(f0, cols, derivative_of)
    return (None, None, x10, x11, None, b1)


# -- Magnus exponents: real matrices ----------------------------------------------------------

def _commutator(X, Y):
    return X @ Y - Y @ X


def magnus4(h, A1, A2) -> np.ndarray:
    """Fourth-order Magnus exponent of a step of length h (s) from A at its two Gauss points.

    Omega = h/2 (A1 + A2) + (sqrt(3)/12) h^2 [A2, A1]; ``h`` broadcasts with the
    matrices' leading axes.
    """
    hh = np.asarray(h, dtype=float)[..., None, None]
    return 0.5 * hh * (A1 + A2) + _C4 * hh * hh * _commutator(A2, A1)


def magnus4_derivative(h, A1, A2, dA1, dA2) -> np.ndarray:
    """Derivative of :func:`magnus4` along the direction (dA1, dA2) of the matrices.

    Either direction may be 0 (a matrix that does not change).
    """
    hh = np.asarray(h, dtype=float)[..., None, None]
    out = 0.5 * hh * (dA1 + dA2)
    comm = 0.0
    if np.ndim(dA2):
        comm = comm + _commutator(dA2, A1)
    if np.ndim(dA1):
        comm = comm + _commutator(A2, dA1)
    return out + _C4 * hh * hh * comm


def magnus4_step_derivative(h, A1, A2) -> np.ndarray:
    """d(:func:`magnus4`)/dh with the matrices held fixed: (A1 + A2)/2 + 2 c h [A2, A1]."""
    hh = np.asarray(h, dtype=float)[..., None, None]
    return 0.5 * (A1 + A2) + 2.0 * _C4 * hh * _commutator(A2, A1)


def system_features(co: Coefficients) -> tuple:
    """:func:`system_matrix` as F0 + w Fw + w^2 Fw2 + w' Fwd: the matrices (F0, Fw, Fw2, Fwd).

    The equations are a polynomial of degree 2 in w and 1 in w' (:func:`derivative_parts`):
    F0 is the system at rest, Fw = D(0), Fw2 = (D(1) - D(0)) / 2, Fwd = dA/dw'. Shapes
    ``co``'s + (5, 5); units those of A per rad/s, (rad/s)^2 and rad/s^2.
    """
    at_rest, slope, by_acceleration = derivative_parts(co)
    return system_matrix(co, 0.0, 0.0), at_rest, 0.5 * slope, by_acceleration


_PAIRS = ((0, 1), (0, 2), (0, 3), (1, 2), (1, 3), (2, 3))
"""The commutators [F_a, F_b] (a < b) of the four features that a Magnus-4 step needs."""
_FIRST, _SECOND = (np.array(index) for index in zip(*_PAIRS))


def magnus4_basis(features) -> np.ndarray:
    """The features (:func:`system_features`) and their commutators [F_a, F_b], a < b.

    Shape ``(..., 10, 5, 5)``: every fourth-order Magnus exponent of the system, and
    its derivatives by w and w' at the Gauss points, is a combination of these ten
    matrices with coefficients that depend on the speeds only
    (:func:`magnus4_coefficients`).
    """
    F = [np.asarray(f, dtype=float) for f in features]
    return np.stack(F + [_commutator(F[a], F[b]) for a, b in _PAIRS], axis=-3)


def magnus4_coefficients(h, w1, wd1, w2, wd2, *, derivatives: bool = False) -> np.ndarray:
    """Coefficients of :func:`magnus4` on :func:`magnus4_basis`, one row per step.

    With A_i = sum_a c_a(i) F_a, c(i) = (1, w_i, w_i^2, w'_i) at the Gauss points t1,
    t2 of a step of length h (s): Omega = h/2 (A1 + A2) + (sqrt(3)/12) h^2 [A2, A1] =
    sum_a h/2 (c_a(1) + c_a(2)) F_a + sum_(a<b) (sqrt(3)/12) h^2 (c_a(2) c_b(1) -
    c_b(2) c_a(1)) [F_a, F_b]. Shape ``(N, 10)`` for N steps (``h`` scalar; the speeds,
    rad/s, and accelerations, rad/s^2, of shape (N,)). With ``derivatives``, shape
    ``(N, 5, 10)``: that row, then its derivatives by w(t1), w'(t1), w(t2), w'(t2)
    (:func:`magnus4_derivative` along dA/dw and dA/dw' at either Gauss point).
    """
    w1, wd1, w2, wd2 = (np.asarray(x, dtype=float) for x in (w1, wd1, w2, wd2))
    one, zero = np.ones_like(w1), np.zeros_like(w1)
    c1 = np.stack([one, w1, w1 * w1, wd1], axis=-1)             # (N, 4)
    c2 = np.stack([one, w2, w2 * w2, wd2], axis=-1)

    def row(total, later, earlier):
        """h/2 (sum of the features by ``total``) + c h^2 [later, earlier]'s coefficients."""
        cross = (later[:, _FIRST] * earlier[:, _SECOND] - later[:, _SECOND] * earlier[:, _FIRST])
        return np.concatenate([0.5 * h * total, _C4 * h * h * cross], axis=-1)

    omega = row(c1 + c2, c2, c1)
    if not derivatives:
        return omega
    by_speed = [np.stack([zero, one, 2.0 * w, zero], axis=-1) for w in (w1, w2)]
    by_acceleration = np.stack([zero, zero, zero, one], axis=-1)
    rows = [omega,
            row(by_speed[0], c2, by_speed[0]), row(by_acceleration, c2, by_acceleration),
            row(by_speed[1], by_speed[1], c1), row(by_acceleration, by_acceleration, c1)]
    return np.stack(rows, axis=-2)


def magnus4_combination(coefficients: np.ndarray, basis: np.ndarray) -> np.ndarray:
    """The matrices sum_m coefficients[..., m] basis[..., m, :, :], for every system.

    ``coefficients``: rows of :func:`magnus4_coefficients`, shape ``(N, 10)`` or
    ``(N, P, 10)``; ``basis``: :func:`magnus4_basis`, shape ``(B, 10, 5, 5)`` (B
    systems) or ``(10, 5, 5)``. Returns shape ``(B, N, 5, 5)`` or ``(B, N, P, 5, 5)``
    (without B for one system): one matrix product per system.
    """
    lead, n = basis.shape[:-3], basis.shape[-1]
    rows = coefficients.reshape(-1, coefficients.shape[-1])
    out = rows @ basis.reshape(lead + (basis.shape[-3], n * n))
    return out.reshape(lead + coefficients.shape[:-1] + (n, n))


def magnus6(h, A1, A2, A3) -> np.ndarray:
    """Sixth-order Magnus exponent from A at the three Gauss points of a step of length h.

    alpha1 = h A2, alpha2 = (sqrt(15) h / 3)(A3 - A1), alpha3 = (10 h / 3)(A3 - 2 A2 + A1);
    Omega = alpha1 + alpha3/12 + [-20 alpha1 - alpha3 + C1, alpha2 + C2] / 240 with
    C1 = [alpha1, alpha2], C2 = -[alpha1, 2 alpha3 + C1] / 60 (Blanes et al. 2000).
    """
    hh = np.asarray(h, dtype=float)[..., None, None]
    a1 = hh * A2
    a2 = (_S15 / 3.0) * hh * (A3 - A1)
    a3 = (10.0 / 3.0) * hh * (A3 - 2.0 * A2 + A1)
    c1 = _commutator(a1, a2)
    c2 = -_commutator(a1, 2.0 * a3 + c1) / 60.0
    return a1 + a3 / 12.0 + _commutator(-20.0 * a1 - a3 + c1, a2 + c2) / 240.0


# -- Magnus exponents: complex affine tuples (None is a structural zero) ----------------------

def _mul(a, b):
    return None if a is None or b is None else a * b


def _sum(*terms):
    out = None
    for t in terms:
        if t is not None:
            out = t if out is None else out + t
    return out


def _neg(a):
    return None if a is None else -a


def lin(*pairs) -> tuple:
    """Sum of c X over (c, X) pairs of complex affine tuples; a constant 0 becomes None."""
    out = []
    for i in range(6):
        total = _sum(*(None if X[i] is None else c * X[i] for c, X in pairs))
        if total is not None and np.ndim(total) == 0 and total == 0:
            total = None
        out.append(total)
    return tuple(out)


def commutator(X, Y) -> tuple:
    """[X, Y] of complex affine tuples."""
    x11, x12, x21, x22, xb1, xb2 = X
    y11, y12, y21, y22, yb1, yb2 = Y
    c11 = _sum(_mul(x12, y21), _neg(_mul(y12, x21)))
    c12 = _sum(_mul(x11, y12), _mul(x12, y22), _neg(_mul(y11, x12)), _neg(_mul(y12, x22)))
    c21 = _sum(_mul(x21, y11), _mul(x22, y21), _neg(_mul(y21, x11)), _neg(_mul(y22, x21)))
    cb1 = _sum(_mul(x11, yb1), _mul(x12, yb2), _neg(_mul(y11, xb1)), _neg(_mul(y12, xb2)))
    cb2 = _sum(_mul(x21, yb1), _mul(x22, yb2), _neg(_mul(y21, xb1)), _neg(_mul(y22, xb2)))
    return (c11, c12, c21, _neg(c11), cb1, cb2)


def magnus4_complex(h, X1, X2) -> tuple:
    """:func:`magnus4` for complex affine tuples."""
    return lin((0.5 * h, X1), (0.5 * h, X2), (_C4 * h * h, commutator(X2, X1)))


def magnus4_complex_derivative(h, X1, X2, dX1, dX2) -> tuple:
    """:func:`magnus4_derivative` for complex affine tuples."""
    return lin((0.5 * h, dX1), (0.5 * h, dX2), (_C4 * h * h, commutator(dX2, X1)),
               (_C4 * h * h, commutator(X2, dX1)))


def _magnus6_from_alphas(alpha1, alpha2, alpha3) -> tuple:
    c1 = commutator(alpha1, alpha2)
    c2 = lin((-1.0 / 60.0, commutator(alpha1, lin((2.0, alpha3), (1.0, c1)))))
    tail = commutator(lin((-20.0, alpha1), (-1.0, alpha3), (1.0, c1)),
                      lin((1.0, alpha2), (1.0, c2)))
    return lin((1.0, alpha1), (1.0 / 12.0, alpha3), (1.0 / 240.0, tail))


def _uniform(x):
    """An array whose entries are all equal as that scalar (cheaper broadcasting)."""
    if x is None or np.ndim(x) == 0:
        return x
    flat = np.ravel(x)
    return flat[0] if np.all(flat == flat[0]) else x


def complex_system_features(co: Coefficients) -> tuple:
    """:func:`complex_system` as F0 + w Fw + w^2 Fw2 + w' Fwd: the tuples (F0, Fw, Fw2, Fwd).

    The system is a polynomial in w (degree 2) and w' (degree 1); its parts come out
    exactly by dual numbers. Entries equal across the systems are scalars, so that
    combinations over time stay as small as the profile's arrays.
    """
    shape = np.shape(co.w1sq)
    zero, one = np.zeros(shape), np.ones(shape)
    cols = _COMPLEX_COLUMNS

    def part(f0, columns, which):
        x10, x11, b1 = _complex_from(f0, columns, which)
        return lin((1.0, tuple(_uniform(e) for e in (None, None, x10, x11, None, b1))))
    at_rest = part(*_columns(co, zero, zero, cols), value_of)
    by_speed_0 = part(*_columns(co, Dual(zero, one), zero, cols), derivative_of)
    by_speed_1 = part(*_columns(co, Dual(one, one), zero, cols), derivative_of)
    by_acceleration = part(*_columns(co, zero, Dual(zero, one), cols), derivative_of)
    F0 = (None, 1.0) + at_rest[2:]
    Fw2 = lin((0.5, by_speed_1), (-0.5, by_speed_0))
    return F0, by_speed_0, Fw2, by_acceleration


def magnus6_complex_features(h, features, w, wd) -> tuple:
    """:func:`magnus6` for complex affine tuples, from :func:`complex_system_features`.

    ``w[i]``, ``wd[i]``: the speed (rad/s) and acceleration (rad/s^2) at the three
    Gauss points of each step of length ``h`` (s). The differences between Gauss
    points are formed from the features, so the parts common to every system keep
    the profile's shape.
    """
    F0, Fw, Fw2, Fwd = features

    def at(i):
        return lin((1.0, F0), (w[i], Fw), (w[i] * w[i], Fw2), (wd[i], Fwd))

    def combo(a, b, c):      # a X1 + b X2 + c X3 without the constant part (a + b + c = 0)
        return lin((a * w[0] + b * w[1] + c * w[2], Fw),
                   (a * w[0] * w[0] + b * w[1] * w[1] + c * w[2] * w[2], Fw2),
                   (a * wd[0] + b * wd[1] + c * wd[2], Fwd))
    return _magnus6_from_alphas(lin((h, at(1))), lin((_S15 * h / 3.0, combo(-1.0, 0.0, 1.0))),
                                lin((10.0 * h / 3.0, combo(1.0, -2.0, 1.0))))


# -- chains ---------------------------------------------------------------------------------

class ChainWorkspace:
    """Buffers of :func:`affine_chain` kept between calls of one size.

    Fresh arrays of a long chain's size are mapped from the system on every call and
    cost more in page faults than the arithmetic in them (identification re-chains
    the same record many times). :meth:`steps` hands out the step buffer to fill.
    """

    def __init__(self):
        self._key: tuple | None = None

    def steps(self, N: int, n: int, dtype=float) -> np.ndarray:
        """A zeroed step buffer of N steps (padded to whole blocks with the identity)."""
        key = (N, n, np.dtype(dtype))
        if key != self._key:
            self._key = key
            self.block = max(1, math.isqrt(N))
            self.blocks = -(-N // self.block)
            size = self.blocks * self.block
            self.phi = np.zeros((size, n, n), dtype=dtype)
            self.phi[N:] = np.eye(n)
            self.cum = np.empty((self.blocks, self.block, n, n), dtype=dtype)
            self._out: dict = {}
        return self.phi

    def out(self, m: int, rows: int) -> np.ndarray:
        """The output buffer for m initial states and ``rows`` kept components."""
        if (m, rows) not in self._out:
            self._out[(m, rows)] = np.empty((self.blocks * self.block + 1, rows, m),
                                            dtype=self.phi.dtype)
        return self._out[(m, rows)]


def _blocked(phi: np.ndarray) -> tuple[np.ndarray, tuple, int, int, int, int]:
    """The chains' blocks of B ~ sqrt(N) steps: (padded phi, leading axes, N, n, B, nb).

    phi is padded with identity steps to nb x B steps: they leave every product of the
    chain unchanged.
    """
    *lead_list, N, n, _ = phi.shape
    lead = tuple(lead_list)
    B = max(1, math.isqrt(N))
    nb = -(-N // B)
    pad = nb * B - N
    if pad:
        eye = np.broadcast_to(np.eye(n, dtype=phi.dtype), lead + (pad, n, n))
        phi = np.concatenate([phi, eye], axis=-3)
    return phi, lead, N, n, B, nb


def affine_chain(phi: np.ndarray, x0: np.ndarray, *, rows=None, steps: int | None = None,
                 work: ChainWorkspace | None = None) -> np.ndarray:
    """States x_0..x_N of x_{k+1} = phi_k x_k.

    ``phi`` has shape ``(..., N, n, n)`` (leading axes: independent systems), ``x0``
    ``(..., n)`` or ``(..., n, m)`` (m initial states at once); the result has shape
    ``(..., N + 1, n)`` or ``(..., N + 1, n, m)``, or only the components ``rows``.
    Blocked: the cumulative products within blocks of ~sqrt(N) steps are formed for
    all blocks at once, then the blocks are chained sequentially. With ``work`` (no
    leading axes), ``phi`` is its :meth:`ChainWorkspace.steps` buffer holding ``steps``
    steps, and the result is a view of its output buffer (valid until the next call).
    """
    phi = np.asarray(phi)
    x0 = np.asarray(x0)
    if work is not None:
        if steps is None or phi is not work.phi:
            raise ValueError('affine_chain with work: phi must be work.steps(...) and steps '
                             'its number of steps')
        lead: tuple = ()
        N, n = steps, phi.shape[-1]
        B, nb = work.block, work.blocks
        cum = work.cum
    else:
        phi, lead, N, n, B, nb = _blocked(phi)
        cum = np.empty(lead + (nb, B, n, n), dtype=phi.dtype)
    vector = x0.ndim == len(lead) + 1
    x = x0[..., None] if vector else x0
    m = x.shape[-1]
    P = phi.reshape(lead + (nb, B, n, n))
    cum[..., 0, :, :] = P[..., 0, :, :]
    for j in range(1, B):
        np.matmul(P[..., j, :, :], cum[..., j - 1, :, :], out=cum[..., j, :, :])
    dtype = np.result_type(phi.dtype, x.dtype)
    starts = np.empty(lead + (nb, n, m), dtype=dtype)
    for i in range(nb):
        starts[..., i, :, :] = x
        x = cum[..., i, -1, :, :] @ x
    kept = list(range(n)) if rows is None else list(rows)
    if work is not None and np.dtype(dtype) == work.phi.dtype:
        out = work.out(m, len(kept))
    else:
        out = np.empty(lead + (nb * B + 1, len(kept), m), dtype=dtype)
    first = x0[..., None] if vector else x0
    out[..., 0, :, :] = first[..., kept, :]
    block_rows = cum if rows is None else cum[..., kept, :]
    np.matmul(block_rows, starts[..., None, :, :],
              out=out[..., 1:, :, :].reshape(lead + (nb, B, len(kept), m)))
    out = out[..., :N + 1, :, :]
    return out[..., 0] if vector else out


def frechet_boole(quarter: np.ndarray, E: np.ndarray, x: np.ndarray) -> np.ndarray:
    """d(exp(Omega) x)/dp along dOmega/dp = E, by Boole's rule.

    The Frechet derivative of the exponential, integral_0^1 exp(s Omega) E
    exp((1 - s) Omega) ds, applied to x, on the five points s = 0, 1/4, ..., 1, with
    ``quarter`` = exp(Omega / 4); error ~ 8 (|Omega| / 4)^6 / 945 relative (Simpson's rule
    on three points leaves ~|Omega|^4 / 2880, too coarse for a whirl 1e-4 of the
    deflection). Shapes: ``quarter`` ``(..., n, n)``, ``E`` ``(P, ..., n, n)`` (P
    directions), ``x`` ``(..., n)``; returns ``(P, ..., n)``.

    The P directions go together: each E applied to the five states exp(k Omega / 4) x
    at once, then Horner's scheme in exp(Omega / 4) on the n x P columns.
    """
    P, n = E.shape[0], E.shape[-1]
    rows = np.moveaxis(E, 0, -3)                 # (..., P, n, n): the directions' rows
    rows = rows.reshape(rows.shape[:-3] + (P * n, n))
    later = [np.asarray(x)[..., None]]           # exp(k Omega / 4) x, k = 0..4, as columns
    for _ in range(4):
        later.append(quarter @ later[-1])
    applied = rows @ np.concatenate(later, axis=-1)                 # (..., P n, 5)
    applied = np.moveaxis(applied.reshape(applied.shape[:-2] + (P, n, 5)), -3, -1)
    total = 7.0 * applied[..., 0, :]             # s = 1: exp(Omega) E x, by Horner below
    for k, weight in zip(range(1, 5), (32.0, 12.0, 32.0, 7.0)):
        total = quarter @ total + weight * applied[..., k, :]       # (..., n, P)
    return np.moveaxis(total / 90.0, -1, 0)


def adjoint_chain(phi: np.ndarray, final: np.ndarray) -> np.ndarray:
    """Row vectors lambda_N = ``final``, lambda_k = lambda_k+1 phi_k: d(final x_N)/dx_k.

    For the chain x_k+1 = phi_k x_k (:func:`affine_chain`), lambda_k is the derivative
    of ``final`` x_N by the state at node k, so that a change dx_k made in step k moves
    final x_N by lambda_k+1 dx_k. ``phi`` ``(..., N, n, n)``, ``final`` ``(r, n)`` or
    ``(..., r, n)``; returns ``(..., N + 1, r, n)``.

    Blocked as :func:`affine_chain`: within blocks of ~sqrt(N) steps, the products from
    each step to the block's end are formed for all blocks at once; the blocks are then
    chained backwards, and every lambda is the row of its block's end times its product
    (~2 sqrt(N) batched products instead of N).
    """
    phi, lead, N, n, B, nb = _blocked(phi)
    P = phi.reshape(lead + (nb, B, n, n))
    to_end = np.empty(lead + (nb, B, n, n), dtype=phi.dtype)   # phi_end-1 ... phi_bB+j
    to_end[..., B - 1, :, :] = P[..., B - 1, :, :]
    for j in range(B - 2, -1, -1):
        np.matmul(to_end[..., j + 1, :, :], P[..., j, :, :], out=to_end[..., j, :, :])
    final = np.broadcast_to(final, lead + np.shape(final)[-2:])
    ends = np.empty(lead + (nb + 1,) + final.shape[-2:],
                    dtype=np.result_type(phi.dtype, final.dtype))
    ends[..., nb, :, :] = final                    # lambda at each block's end node
    for b in range(nb - 1, -1, -1):
        np.matmul(ends[..., b + 1, :, :], to_end[..., b, 0, :, :], out=ends[..., b, :, :])
    lam = np.empty(lead + (nb * B + 1,) + final.shape[-2:], dtype=ends.dtype)
    np.matmul(ends[..., 1:, None, :, :], to_end,
              out=lam[..., :nb * B, :, :].reshape(lead + (nb, B) + final.shape[-2:]))
    lam = lam[..., :N + 1, :, :]
    lam[..., N, :, :] = final
    return lam


def sensitivity_chain(phi: np.ndarray, forcing: np.ndarray) -> np.ndarray:
    """S_0 = 0, S_{k+1} = phi_k S_k + forcing_k: sensitivities of the chained states.

    ``phi`` ``(..., N, n, n)``, ``forcing`` ``(..., N, n, p)`` (p parameters); returns
    ``(..., N + 1, n, p)``.

    Blocked as :func:`affine_chain`: within blocks of ~sqrt(N) steps, for all blocks at
    once, S at the block's j-th node is C_j S_start + D_j (C_j the product of the
    block's first j steps, D_j the chain from zero); the blocks' start values are then
    chained, and every S follows in one batched product (~3 sqrt(N) batched products
    instead of N).
    """
    phi, lead, N, n, B, nb = _blocked(phi)
    p = forcing.shape[-1]
    if nb * B > N:      # no forcing on the identity steps after the last
        forcing = np.concatenate([forcing, np.zeros(lead + (nb * B - N, n, p),
                                                    dtype=forcing.dtype)], axis=-3)
    P = phi.reshape(lead + (nb, B, n, n))
    F = forcing.reshape(lead + (nb, B, n, p))
    dtype = np.result_type(phi.dtype, forcing.dtype)
    C = np.empty(lead + (nb, B + 1, n, n), dtype=phi.dtype)   # from the block's start
    D = np.empty(lead + (nb, B + 1, n, p), dtype=dtype)       # the chain from S = 0
    C[..., 0, :, :] = np.eye(n)
    D[..., 0, :, :] = 0.0
    for j in range(B):
        np.matmul(P[..., j, :, :], C[..., j, :, :], out=C[..., j + 1, :, :])
        np.matmul(P[..., j, :, :], D[..., j, :, :], out=D[..., j + 1, :, :])
        D[..., j + 1, :, :] += F[..., j, :, :]
    starts = np.empty(lead + (nb, n, p), dtype=dtype)
    s = np.zeros(lead + (n, p), dtype=dtype)
    for b in range(nb):
        starts[..., b, :, :] = s
        s = C[..., b, B, :, :] @ s + D[..., b, B, :, :]
    S = np.empty(lead + (nb * B + 1, n, p), dtype=dtype)
    S[..., 0, :, :] = 0.0
    body = S[..., 1:, :, :].reshape(lead + (nb, B, n, p))
    np.matmul(C[..., 1:, :, :], starts[..., None, :, :], out=body)
    body += D[..., 1:, :, :]
    return S[..., :N + 1, :, :]
