"""Cantilever formulas behind the real-rig extensions of :class:`RodParams`.

Pure functions of numbers (floats or numpy arrays), no dependence on RodParams, so
that :mod:`rotrod_core.model.params` can use them. See ``docs/real_rig.md`` for the
derivations; the anchors named below are in that page.

- :func:`tip_load_stiffness_ratio`: the exact lateral tip stiffness of a cantilever
  carrying an axial (vertical, dead) tip load, relative to 3 EI / l^3
  (``#tip-load-stiffness``), with its power series near zero load (``#series``).
- The shape integrals of the one-mode Rayleigh-Ritz model on the static cantilever
  shape phi(xi) = (3 xi^2 - xi^3) / 2 (``#shape-integrals``).
- :func:`ritz_bending_frequencies`: the non-rotating bending frequencies of a
  uniform rod with a tip mass, axial tip load and its own weight, by a many-term
  Rayleigh-Ritz method (``#next-mode``), to estimate the second mode.
"""

from __future__ import annotations

from fractions import Fraction

import numpy as np

SHAPE_MASS = 33.0 / 140.0
"""Integral of phi^2 over the rod (xi from 0 to 1): the rod's share in the modal mass."""

SHAPE_LOAD = 3.0 / 8.0
"""Integral of phi over the rod: the rod's share in the eccentric (centrifugal) load."""

SHAPE_SELF_WEIGHT = 3.0 / 8.0
"""Integral of (1 - xi) phi'(xi)^2: geometric stiffness of the rod's own weight, per rho A g."""

SERIES_LIMIT = 0.25
"""|y| below which the power series is used instead of the closed form (y = P l^2 / EI)."""


def _tan_over_x_coefficients(count: int) -> list[Fraction]:
    """Exact coefficients t_n of tan(x) / x = sum t_n x^(2n), n = 0 .. count - 1.

    From tan' = 1 + tan^2: (2n + 1) t_n = sum_{i + j = n - 1} t_i t_j, t_0 = 1.
    tanh(x) / x has the same coefficients with alternating signs.
    """
    t = [Fraction(1)]
    for n in range(1, count):
        t.append(sum((t[i] * t[n - 1 - i] for i in range(n)), Fraction(0)) / (2 * n + 1))
    return t


_T = _tan_over_x_coefficients(24)
_G = [float(3 * c) for c in _T[1:]]
"""G(y) = 3 (T(y) - 1) / y = 1 + (2/5) y + (17/105) y^2 + ...; T(y) = tan(x)/x, y = x^2."""


def _series(y):
    """1 / G(y) by Horner (accurate for |y| <= SERIES_LIMIT: terms fall by ~0.1 each)."""
    acc = np.zeros_like(y) + _G[-1]
    for c in reversed(_G[:-1]):
        acc = acc * y + c
    return 1.0 / acc


def tip_load_stiffness_ratio(y):
    """Lateral tip stiffness under an axial tip load, relative to 3 EI / l^3.

    ``y = P l^2 / (E I)`` with P > 0 compression (the tip mass standing on the rod),
    P < 0 tension (hanging). With kappa = sqrt(|P| / EI) and x = kappa l = sqrt(|y|),
    the exact cantilever results are

        compression: k = P / (tan(kappa l) / kappa - l) = (EI/l^3) x^2 / (tan(x)/x - 1)
        tension:     k = |P| / (l - tanh(kappa l) / kappa) = (EI/l^3) x^2 / (1 - tanh(x)/x)

    so the ratio is y / (3 (T(y) - 1)) with T(y) = tan(x)/x for y > 0 and tanh(x)/x
    for y < 0, the same power series sum t_n y^n in both cases. For |y| <=
    :data:`SERIES_LIMIT` the series is summed (the closed forms cancel there); it
    equals exactly 1 at y = 0. Near zero: 1 - (2/5) y, i.e. k = 3EI/l^3 - (6/5) P/l.
    Zero at the buckling load y = pi^2/4; the caller must refuse y >= pi^2/4.
    Accuracy, against a 60-digit evaluation of the closed forms: 2e-15 relative for
    -60 <= y <= 2.4 (97 % of the buckling load), 3e-14 up to 2.467; closer to
    buckling the function itself is ill-conditioned (relative condition number
    ~ y / (pi^2/4 - y)). Vectorized; returns a float for a scalar.
    """
    y = np.asarray(y, dtype=float)
    small = np.abs(y) <= SERIES_LIMIT
    with np.errstate(all='ignore'):
        x = np.sqrt(np.abs(y))
        xs = np.where(small, 1.0, x)
        compression = y / (3.0 * (np.tan(xs) / xs - 1.0))
        tension = -y / (3.0 * (1.0 - np.tanh(xs) / xs))
        out = np.where(small, _series(np.where(small, y, 0.0)),
                       np.where(y > 0, compression, tension))
    return float(out) if out.ndim == 0 else out


def buckling_ratio():
    """The Euler buckling load of a cantilever as y = P l^2 / (E I): pi^2 / 4."""
    return np.pi ** 2 / 4.0


RITZ_TERMS = 10
"""Trial functions of :func:`ritz_bending_frequencies` (orthogonalised xi^2 .. xi^11)."""


def _ldl(B):
    """Exact L D L^T factors (Fractions) of a symmetric positive definite matrix."""
    n = len(B)
    L = [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]
    D = [Fraction(0)] * n
    for j in range(n):
        D[j] = B[j][j] - sum(L[j][k] ** 2 * D[k] for k in range(j))
        for i in range(j + 1, n):
            L[i][j] = (B[i][j] - sum(L[i][k] * L[j][k] * D[k] for k in range(j))) / D[j]
    return L, D


def _lower_inverse(L):
    """Inverse of a unit lower-triangular matrix (Fractions)."""
    n = len(L)
    X = [[Fraction(int(i == j)) for j in range(n)] for i in range(n)]
    for i in range(n):
        for j in range(i):
            X[i][j] = -sum(L[i][k] * X[k][j] for k in range(j, i))
    return X


def _ritz_matrices(n: int):
    """Dimensionless Ritz matrices in a basis orthonormal in the bending energy.

    Trial functions xi^a, a = 2 .. n + 1, combined (exactly, in rational arithmetic)
    so that the integral of psi_i'' psi_j'' over xi in [0, 1] is the identity; this
    keeps the eigenproblem well conditioned where raw monomials are not. Returns
    (tip, rod, axial, weight): psi_i(1) as a vector, and the integrals of psi_i psi_j,
    psi_i' psi_j', (1 - xi) psi_i' psi_j' as matrices.
    """
    ex = range(2, n + 2)
    F = Fraction
    bending = [[F(a * (a - 1) * b * (b - 1), a + b - 3) for b in ex] for a in ex]
    rod = [[F(1, a + b + 1) for b in ex] for a in ex]
    axial = [[F(a * b, a + b - 1) for b in ex] for a in ex]
    weight = [[F(a * b, a + b - 1) - F(a * b, a + b) for b in ex] for a in ex]
    L, D = _ldl(bending)
    X = _lower_inverse(L)

    def transform(A):
        XA = [[sum(X[i][k] * A[k][j] for k in range(n)) for j in range(n)] for i in range(n)]
        return np.array([[float(sum(XA[i][k] * X[j][k] for k in range(n))) for j in range(n)]
                         for i in range(n)])

    scale = 1.0 / np.sqrt(np.array([float(d) for d in D]))
    tip = np.array([float(sum(X[i])) for i in range(n)]) * scale
    mats = [transform(A) * np.outer(scale, scale) for A in (rod, axial, weight)]
    return (tip, *mats)


_RITZ: dict[int, tuple] = {}


def ritz_bending_frequencies(flexural_rigidity, length, tip_mass, line_density, tip_load,
                             line_load, count: int = 2, terms: int = RITZ_TERMS):
    """Lowest ``count`` bending circular frequencies (rad/s) of a non-rotating cantilever.

    A uniform Euler-Bernoulli rod (flexural rigidity EI in N m^2, length l in m, mass
    per length rho A in kg/m) with a point mass at its tip (kg), an axial dead load P
    at the tip (N, > 0 compression) and a distributed axial load q = rho A g along it
    (N/m, > 0 compression, the rod's own weight). Rayleigh-Ritz with ``terms`` trial
    functions spanning xi^2 .. xi^(terms + 1) (they satisfy w(0) = w'(0) = 0):

        K = EI/l^3 [psi''psi''] - P/l [psi'psi'] - q [(1 - xi) psi'psi'],
        M = m [psi(1) psi(1)] + rho A l [psi psi],

    and K a = w^2 M a. The frequencies are upper bounds converging fast with
    ``terms`` (for Table 1 with a steel rod the second is within 1e-9 of the exact
    root of the tip-mass cantilever's frequency equation). A massless rod (rho A = 0)
    has one mode only: the others are inf. A rod that this estimate finds buckled
    (K not positive definite) gives nan. Vectorized over the arguments; returns
    shape ``(..., count)``.
    """
    if terms not in _RITZ:
        _RITZ[terms] = _ritz_matrices(terms)
    tip, rod, axial, weight = _RITZ[terms]
    ei, le, m, mu, p, q = np.broadcast_arrays(*(np.asarray(x, dtype=float) for x in (
        flexural_rigidity, length, tip_mass, line_density, tip_load, line_load)))
    ex = (..., None, None)
    K = (ei / le**3)[ex] * np.eye(terms) - (p / le)[ex] * axial - q[ex] * weight
    M = m[ex] * np.outer(tip, tip) + (mu * le)[ex] * rod
    shape = ei.shape
    Kf, Mf = K.reshape(-1, terms, terms), M.reshape(-1, terms, terms)
    lam = np.full((Kf.shape[0], terms), np.nan)
    for i in range(Kf.shape[0]):
        try:
            C = np.linalg.cholesky(Kf[i])
        except np.linalg.LinAlgError:
            continue            # buckled according to this estimate: nan
        Ci = np.linalg.inv(C)
        lam[i] = np.linalg.eigvalsh(Ci @ Mf[i] @ Ci.T)[::-1]   # 1 / w^2, descending
    lam = lam.reshape(shape + (terms,))[..., :count]
    with np.errstate(divide='ignore', invalid='ignore'):
        w = np.where(lam > 0, 1.0 / np.sqrt(np.where(lam > 0, lam, 1.0)), np.inf)
    w = np.where(np.isnan(lam), np.nan, w)
    # a massless rod: only the tip mass moves, one mode; rounding leaves tiny 1 / w^2
    # for the others, which are inf
    rest = np.zeros(w.shape, dtype=bool)
    rest[..., 1:] = True
    return np.where((mu == 0)[..., None] & rest, np.inf, w)
