"""Velocity drive for a batch of systems: exponential integrators vectorised over systems.

For a prescribed w(t) the deflection equations are linear in (u, v, u', v')
(docs/model.md), and every system of a batch shares w(t). Three integrators, each
exact for constant coefficients and all vectorised over the systems:

- **isotropic and undamped** (k1 = k2, zeta = 0: the paper's rod), *exact in the
  inertial frame*. With z = u + i v and Z = e^(i theta) (re + z) the equations read
  Z'' + w0^2 Z = w0^2 re e^(i theta(t)): constant coefficients. Z is the matrix
  exponential (cos, sin) of the initial state plus the Duhamel integral
  w0 re int_0^t sin(w0 (t - s)) e^(i theta(s)) ds, evaluated by 8-point Gauss-Legendre
  quadrature on panels (w0 + |w|) h <= 1 (a truncation error far below rounding),
  as matrix products over all systems at once.
- **isotropic and damped**: the sixth-order Magnus propagator (three Gauss points,
  Blanes, Casas & Ros 2000) of the rotating-frame equation
  z'' + (g + 2 i w) z' + (w0^2 - w^2 + i w') z = re (w^2 - i w'), g = c/M, whose
  augmented 3x3 complex exponential has a closed form (a scaling-and-squaring
  exponential where it is ill-conditioned).
- **k1 != k2**: the same Magnus propagator of the real 5x5 matrix of
  :func:`rotrod_core.model.propagation.system_matrix`, by scaling and squaring.

Every Magnus exponent and system matrix comes from :mod:`rotrod_core.model.propagation`,
the one kernel shared with simulate, the planner and identification.

The step is chosen for the requested ``tolerance`` (m, on u and v along the run):
each integrator is run on representative systems of the batch (the extremes of every
coefficient and of the initial state) with steps h and h/2; the difference, which is
the error of h up to 1/(2^6 - 1), must stay below half the tolerance. The nodes
include every profile breakpoint, jump and output time; the step never exceeds
1 / (w0 + |w|) of the fastest system, so the tip is sampled ~6 times a whirl period
and the peak deflection is found between samples by Newton's method on |r|^2 with
exact one-step propagation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

import rotrod_core.model.equations as model
import rotrod_core.model.propagation as propagation
from rotrod_core.command.profiles import Profile
from rotrod_core.model.equations import Coefficients
from rotrod_core.numerics.checks import NonFiniteStateError
from rotrod_core.numerics.expm import expm_batch

_GAUSS3 = np.array(propagation.GAUSS3)
_GL_X, _GL_W = np.polynomial.legendre.leggauss(8)
_GL_X, _GL_W = 0.5 * (_GL_X + 1.0), 0.5 * _GL_W        # on [0, 1], weights sum to 1
_STEP_CHUNK = 64            # Magnus steps whose propagators are formed at once
_PEAK_CANDIDATES = 2        # sampled local maxima of |r| refined per system
_NEWTON = 3                 # Newton iterations of the peak refinement
MAX_NODES = 2_000_000

KINDS = ('exact', 'magnus_complex', 'magnus_real')


def system_kinds(co: Coefficients) -> np.ndarray:
    """Per system: 0 exact (isotropic, undamped), 1 complex Magnus, 2 real Magnus."""
    w1, w2 = np.asarray(co.w1sq, float), np.asarray(co.w2sq, float)
    g1, g2 = np.asarray(co.g1, float), np.asarray(co.g2, float)
    iso = (w1 == w2) & (g1 == g2)
    return np.where(iso & (g1 == 0), 0, np.where(iso, 1, 2)).astype(int)


def as_arrays(co: Coefficients, shape: tuple | None = None) -> Coefficients:
    """``co`` with every field a flat array (n,), one value per system.

    The fields are broadcast together, or to ``shape`` (the batch's shape; () is
    one system), then flattened.
    """
    values = {k: np.asarray(v, float) for k, v in vars(co).items()}
    if shape is None:
        shape = np.broadcast_shapes(*(v.shape for v in values.values()))
    return Coefficients(**{k: np.broadcast_to(v, shape).ravel().copy()
                           for k, v in values.items()})


def subset(co: Coefficients, idx) -> Coefficients:
    """The coefficients of the systems ``idx`` (arrays stay arrays)."""
    return Coefficients(**{k: (np.asarray(v)[idx] if np.ndim(v) else v)
                           for k, v in vars(co).items()})


# -- the node grid ------------------------------------------------------------------------

def mandatory_times(profile: Profile, t_end: float, output_times) -> np.ndarray:
    """0, t_end, the profile's breakpoints and jumps before t_end, and the output times."""
    points = [0.0, float(t_end)]
    points += [t for t in profile.breakpoints() if 0 < t < t_end]
    points += [float(j[0]) for j in profile.jumps() if 0 < j[0] < t_end]
    if output_times is not None:
        points += list(np.asarray(output_times, float))
    pts = np.unique(np.asarray(points, float))
    keep = np.concatenate([[True], np.diff(pts) > 1e-12 * max(1.0, t_end)])
    pts = pts[keep]
    pts[-1] = t_end
    return pts


def subdivide(points: np.ndarray, h: float) -> np.ndarray:
    """Nodes: each interval of ``points`` cut into equal steps no longer than ``h``."""
    lengths = np.diff(points)
    counts = np.maximum(1, np.ceil(lengths / h - 1e-9).astype(int))
    if counts.sum() > MAX_NODES:
        raise ValueError(f'the batch needs {counts.sum()} steps (> {MAX_NODES}); '
                         'ask for a looser tolerance or a shorter run')
    pieces = [np.linspace(a, b, c + 1)[:-1] for a, b, c in zip(points[:-1], points[1:], counts)]
    return np.concatenate(pieces + [points[-1:]])


def bisect_nodes(nodes: np.ndarray) -> np.ndarray:
    """Every interval of ``nodes`` halved (the old nodes are every other new one)."""
    out = np.empty(2 * len(nodes) - 1)
    out[0::2] = nodes
    out[1::2] = 0.5 * (nodes[:-1] + nodes[1:])
    return out


# -- the Magnus exponents, from the one kernel ---------------------------------------------

def complex_form(co: Coefficients):
    """The complex form's (w0^2, g, re) of isotropic systems, read off the kernel's system.

    z'' = x10 z + x11 z' + b1 (:func:`rotrod_core.model.propagation.complex_system`):
    at rest x10 = -w0^2 and x11 = -g; at w = 1 rad/s, b1 = re (m).
    """
    shape = np.shape(co.w1sq)
    _, _, x10, x11, _, _ = propagation.complex_system(co, np.zeros(shape), np.zeros(shape))
    _, _, _, _, _, b1 = propagation.complex_system(co, np.ones(shape), np.zeros(shape))
    return (-np.real(x10) + np.zeros(shape), -np.real(x11) + np.zeros(shape),
            np.real(b1) + np.zeros(shape))


def omega_complex(co: Coefficients, h, w, wd):
    """Magnus-6 Omega (complex affine tuple) of isotropic systems over steps of length h.

    ``co`` (fields of the systems' shape) broadcasts with ``h`` and with ``w[i], wd[i]``,
    the profile at the three Gauss points (axis 0 of ``w`` and ``wd``).
    """
    features = propagation.complex_system_features(co)
    return propagation.magnus6_complex_features(h, features, w, wd)


def _complex_to_real(entries):
    """The real 5x5 matrices on (u, v, u', v', 1) of complex affine maps on (z, z')."""
    n11, n12, n21, n22, c1, c2 = entries
    R = np.zeros(np.shape(n11) + (5, 5))
    for (r, blocks) in ((0, (n11, n12, c1)), (2, (n21, n22, c2))):
        a, b, c = blocks
        R[..., r, 0], R[..., r, 1] = a.real, -a.imag
        R[..., r + 1, 0], R[..., r + 1, 1] = a.imag, a.real
        R[..., r, 2], R[..., r, 3] = b.real, -b.imag
        R[..., r + 1, 2], R[..., r + 1, 3] = b.imag, b.real
        R[..., r, 4], R[..., r + 1, 4] = c.real, c.imag
    return R


def expm_complex(entries, s):
    """The exponential of augmented complex matrices: (E11, E12, E21, E22, y1, y2).

    Closed form: with mu = tr N / 2, d^2 = ((n11 - n22)/2)^2 + n12 n21,
    e^N = e^mu (cosh d I + sinh d / d (N - mu I)), and y = phi1(N) c from
    N y = (e^N - I) c. Where d is small or N (scaled by w0 = sqrt(s)) is
    ill-conditioned, the real 5x5 scaling-and-squaring exponential is used instead.
    """
    shape = np.broadcast_shapes(*(np.shape(x) for x in entries if x is not None))
    n11, n12, n21, n22, c1, c2 = (np.broadcast_to(0j if x is None else x, shape)
                                  for x in entries)
    mu = 0.5 * (n11 + n22)
    nu = 0.5 * (n11 - n22)
    d = np.sqrt(nu * nu + n12 * n21)
    em = np.exp(mu)
    with np.errstate(all='ignore'):
        ep = np.exp(d)
        en = 1.0 / ep
        ch = 0.5 * em * (ep + en)
        sh = 0.5 * em * (ep - en) / d
        E11, E22 = ch + sh * nu, ch - sh * nu
        E12, E21 = sh * n12, sh * n21
        det = n11 * n22 - n12 * n21
        r1 = (E11 - 1.0) * c1 + E12 * c2
        r2 = E21 * c1 + (E22 - 1.0) * c2
        y1 = (n22 * r1 - n12 * r2) / det
        y2 = (n11 * r2 - n21 * r1) / det
        w0 = np.sqrt(np.broadcast_to(s, shape))
        scale = (abs(n11) ** 2 + abs(n22) ** 2 + abs(n12 * w0) ** 2 + abs(n21 / w0) ** 2)
        bad = ~((abs(det) > 1e-3 * scale) & (abs(d) > 0.05)
                & np.isfinite(y1) & np.isfinite(y2) & np.isfinite(E11))
    out = [E11, E12, E21, E22, y1, y2]
    if np.any(bad):
        out = [np.array(x, dtype=complex) for x in out]
        X = expm_batch(_complex_to_real([x[bad] for x in (n11, n12, n21, n22, c1, c2)]))
        for k, (r, c) in enumerate(((0, 0), (0, 2), (2, 0), (2, 2), (0, 4), (2, 4))):
            out[k][bad] = X[:, r, c] + 1j * X[:, r + 1, c]
    return tuple(out)


def omega_real(co: Coefficients, h, w, wd):
    """Magnus-6 Omega (real 5x5) of :func:`rotrod_core.model.propagation.system_matrix`.

    ``co`` arrays of shape (n,); ``h`` broadcastable to (K, n); ``w[i], wd[i]`` of shape
    (K, 1) or (K, n). Returns shape (K, n, 5, 5).
    """
    shape = np.broadcast_shapes(np.shape(h), np.shape(w[0]), np.shape(co.w1sq))
    A = [propagation.system_matrix(co, np.broadcast_to(w[i], shape),
                                   np.broadcast_to(wd[i], shape)) for i in range(3)]
    return propagation.magnus6(np.broadcast_to(h, shape), *A)


def _gauss_profile(profile: Profile, t0, h):
    """The profile's w and w' at the Gauss points of steps [t0, t0 + h]: arrays (3, ...)."""
    gauss = _GAUSS3.reshape((3,) + (1,) * np.ndim(t0))
    ts = np.asarray(t0)[None] + gauss * np.asarray(h)[None]
    return profile.omega(ts), profile.omega_dot(ts)


# -- one step, per element (peak refinement) ----------------------------------------------

def step_states(kind: int, co: Coefficients, profile: Profile, t0, h, z, p):
    """States (z, z') after one Magnus-6 step of length ``h`` from (z, z') at ``t0``.

    Element-wise: every argument has the systems' shape (``co`` is their subset).
    """
    w, wd = _gauss_profile(profile, t0, h)
    if kind != 2:
        s, _, _ = complex_form(co)
        E11, E12, E21, E22, y1, y2 = expm_complex(omega_complex(co, h, w, wd), s)
        return E11 * z + E12 * p + y1, E21 * z + E22 * p + y2
    X = expm_batch(omega_real(co, h, w, wd))
    x = np.stack([z.real, z.imag, p.real, p.imag, np.ones(np.shape(z))], axis=-1)
    y = np.einsum('...ij,...j->...i', X, x)
    return y[..., 0] + 1j * y[..., 1], y[..., 2] + 1j * y[..., 3]


# -- whole runs on a node grid ------------------------------------------------------------

def _jump_after(profile: Profile, nodes: np.ndarray) -> dict:
    """{node index: omega jump} for the profile's jumps that fall on interior nodes."""
    out = {}
    for tj, before, after in profile.jumps():
        if 0 < tj <= nodes[-1]:
            k = int(np.searchsorted(nodes, tj))
            if k < len(nodes) and abs(nodes[k] - tj) <= 1e-12 * max(1.0, tj):
                out[k] = after - before
    return out


def run_magnus(kind: int, co: Coefficients, profile: Profile, nodes: np.ndarray, z0, p0):
    """The Magnus-6 run: z = u + iv and z' at every node, shape (len(nodes), n)."""
    n = np.size(co.w1sq)
    K = len(nodes) - 1
    Z = np.empty((K + 1, n), complex)
    P = np.empty((K + 1, n), complex)
    z = np.broadcast_to(np.asarray(z0, complex), (n,)).copy()
    p = np.broadcast_to(np.asarray(p0, complex), (n,)).copy()
    Z[0], P[0] = z, p
    jumps = _jump_after(profile, nodes)
    re = np.asarray(co.load_radius, float) + np.zeros(n)
    if kind != 2:
        s, _, _ = complex_form(co)
    for start in range(0, K, _STEP_CHUNK):
        stop = min(start + _STEP_CHUNK, K)
        t0 = nodes[start:stop, None]
        h = np.diff(nodes[start:stop + 1])[:, None]
        w, wd = _gauss_profile(profile, t0, h)
        if kind != 2:
            E11, E12, E21, E22, y1, y2 = expm_complex(omega_complex(co, h, w, wd), s)
            for k in range(stop - start):
                z, p = E11[k] * z + E12[k] * p + y1[k], E21[k] * z + E22[k] * p + y2[k]
                Z[start + k + 1], P[start + k + 1] = z, p
                if start + k + 1 in jumps:
                    p = p - 1j * jumps[start + k + 1] * (z + re)
                    P[start + k + 1] = p
        else:
            X = expm_batch(omega_real(co, h, w, wd))
            x = np.stack([z.real, z.imag, p.real, p.imag, np.ones(n)], axis=-1)
            for k in range(stop - start):
                x = np.einsum('nij,nj->ni', X[k], x)
                kk = start + k + 1
                if kk in jumps:
                    dw = jumps[kk]
                    x[:, 2] += dw * x[:, 1]
                    x[:, 3] -= dw * (re + x[:, 0])
                Z[kk] = x[:, 0] + 1j * x[:, 1]
                P[kk] = x[:, 2] + 1j * x[:, 3]
            z, p = Z[stop].copy(), P[stop].copy()
    return _Stored(Z, P)


class _Stored:
    """z = u + iv and z' stored at every node (the Magnus integrators)."""

    def __init__(self, Z, P):
        self.Z, self.P = Z, P

    def r2(self):
        """|z|^2 at every node, shape (n, nodes): one row per system."""
        return np.ascontiguousarray(((self.Z * self.Z.conj()).real).T)

    def at(self, k, j):
        return self.Z[k, j], self.P[k, j]

    def rows(self, ks):
        return self.Z[ks], self.P[ks]


class _Whirls:
    """The inertial whirl amplitudes at every node; z and z' formed where asked."""

    def __init__(self, A, B, r2, w0, re, rot, omega):
        self.A, self.B, self._r2, self.w0, self.re = A, B, r2, w0, re
        self.rot, self.omega = rot, omega               # e^(i theta_k), w(t_k)

    def r2(self):
        """|z|^2 at every node, shape (n, nodes): one row per system."""
        return self._r2

    def at(self, k, j):
        a, b = self.A[k, j], self.B[k, j]
        back = self.rot[k].conj()
        zt = a + b
        z = back * zt - self.re[j]
        p = back * (1j * (self.w0[j] * (a - b) - self.omega[k] * zt))
        return z, p

    def rows(self, ks):
        ks = np.asarray(ks)
        a, b = self.A[ks], self.B[ks]
        back = self.rot[ks].conj()[:, None]
        zt = a + b
        z = back * zt
        z -= self.re
        a -= b
        a *= self.w0
        zt *= self.omega[ks][:, None]
        a -= zt
        a *= back
        a *= 1j
        return z, a


def run_exact(co: Coefficients, profile: Profile, nodes: np.ndarray, z0, p0):
    """The run of isotropic undamped systems, exact in the inertial frame (module doc).

    With Z = e^(i theta)(re + z) (theta from 0), the whirl amplitudes
    a = (Z + Z' / (i w0)) / 2 and b = (Z - Z' / (i w0)) / 2 obey
    a' = i w0 a + F / (2 i w0), b' = -i w0 b - F / (2 i w0), F = w0^2 re e^(i theta):
    over a panel of length h, a <- e^(i w0 h) (a + (w0 re / 2i) S-) with
    S-+ = int_0^h e^(-+ i w0 s) e^(i theta(t_k + s)) ds by Gauss-Legendre.
    """
    s, _, re = complex_form(co)
    w0 = np.sqrt(s)
    n = np.size(s)
    z0 = np.broadcast_to(np.asarray(z0, complex), (n,))
    p0 = np.broadcast_to(np.asarray(p0, complex), (n,))
    K = len(nodes) - 1
    h = np.diff(nodes)
    # panels of (nearly) the same length share their per-system factors
    values, which = np.unique(np.round(h / h.max(), 9), return_inverse=True)
    c = w0 * re / 2j
    hg = np.array([float(np.mean(h[which == g])) for g in range(len(values))])
    s_q = nodes[:-1, None] + hg[which][:, None] * _GL_X[None, :]
    G = (hg[which][:, None] * _GL_W[None, :]) * np.exp(1j * profile.angle(s_q))    # (K, Q)
    minus, plus, turn, back = [], [], [], []
    for g in range(len(values)):
        phase = np.exp(-1j * hg[g] * np.outer(_GL_X, w0))           # (Q, n)
        minus.append(phase * c)
        plus.append(phase.conj() * -c)
        f = np.exp(1j * w0 * hg[g])
        turn.append(f)
        back.append(1.0 / f)
    rot = np.exp(1j * profile.angle(nodes))
    Zin = re + z0
    dZin = p0 + 1j * float(profile.omega(0.0)) * Zin
    A = np.empty((K + 1, n), complex)
    B = np.empty((K + 1, n), complex)
    r2 = np.empty((n, K + 1))
    A[0] = 0.5 * (Zin + dZin / (1j * w0))
    B[0] = 0.5 * (Zin - dZin / (1j * w0))
    C = A[0] + B[0] - rot[0] * re
    r2[:, 0] = C.real ** 2 + C.imag ** 2
    # the panel sums of all steps, by few large matrix products (BLAS)
    Sm = np.empty((K, n), complex)
    Sp = np.empty((K, n), complex)
    for g in range(len(values)):
        rows = np.nonzero(which == g)[0]
        Sm[rows] = G[rows] @ minus[g]
        Sp[rows] = G[rows] @ plus[g]
    for start in range(0, K, _STEP_CHUNK):
        stop = min(start + _STEP_CHUNK, K)
        for k in range(start, stop):
            g = which[k]
            np.add(A[k], Sm[k], out=A[k + 1])
            np.multiply(A[k + 1], turn[g], out=A[k + 1])
            np.add(B[k], Sp[k], out=B[k + 1])
            np.multiply(B[k + 1], back[g], out=B[k + 1])
        C = A[start + 1:stop + 1] + B[start + 1:stop + 1]
        C -= rot[start + 1:stop + 1, None] * re
        r2[:, start + 1:stop + 1] = (C.real ** 2 + C.imag ** 2).T
    return _Whirls(A, B, r2, w0, re, rot, profile.omega(nodes))


def run_kind(kind: int, co, profile, nodes, z0, p0):
    """The run at the nodes by the integrator of ``kind`` (see :data:`KINDS`).

    Returns an object with ``r2()`` (|z|^2 at every node), ``at(k, j)`` and
    ``rows(ks)`` ((z, z') at nodes k of systems j, or whole rows).
    """
    if kind == 0:
        return run_exact(co, profile, nodes, z0, p0)
    return run_magnus(kind, co, profile, nodes, z0, p0)


# -- choosing the step ----------------------------------------------------------------------

def representatives(co: Coefficients, z0, p0, limit: int = 12) -> np.ndarray:
    """Indices of the systems at the extremes of every coefficient and initial state."""
    n = np.size(co.w1sq)
    picks = {0}
    for v in (co.w1sq, co.w2sq, co.g1, co.g2, co.load_radius):
        arr = np.broadcast_to(np.asarray(v, float), (n,))
        picks.update((int(np.argmin(arr)), int(np.argmax(arr))))
    for v in (z0, p0):
        arr = np.abs(np.broadcast_to(np.asarray(v, complex), (n,)))
        picks.add(int(np.argmax(arr)))
    return np.array(sorted(picks))[:limit]


def choose_step(kind: int, co, profile, points, z0, p0, tolerance: float, h_cap: float,
                h_start: float) -> tuple[float, float]:
    """The largest step (<= h_cap) whose estimated error on z is below tolerance / 2.

    Returns (h, estimated error of the representatives at h, m).
    """
    idx = representatives(co, z0, p0)
    sub = subset(co, idx)
    zz = np.broadcast_to(np.asarray(z0, complex), (np.size(co.w1sq),))[idx]
    pp = np.broadcast_to(np.asarray(p0, complex), (np.size(co.w1sq),))[idx]
    h = min(h_start, h_cap)
    best = None
    for _ in range(8):
        nodes = subdivide(points, h)
        fine = bisect_nodes(nodes)
        Z1, _ = run_kind(kind, sub, profile, nodes, zz, pp).rows(np.arange(len(nodes)))
        Z2, _ = run_kind(kind, sub, profile, fine, zz, pp).rows(np.arange(0, len(fine), 2))
        err = float(np.max(np.abs(Z1 - Z2))) * 64.0 / 63.0
        if not math.isfinite(err):
            raise NonFiniteStateError('the batch run became non-finite while its step was '
                                      'being chosen')
        if err <= 0.5 * tolerance:
            best = (h, err)
            grow = 0.9 * (0.5 * tolerance / max(err, 1e-300)) ** (1.0 / 6.0)
            if h >= h_cap or grow < 1.2:
                break
            h = min(h_cap, h * min(grow, 4.0))
        else:
            if best is not None and best[0] < h:
                break
            h *= max(0.1, 0.9 * (0.5 * tolerance / err) ** (1.0 / 6.0))
    if best is None:
        raise ValueError(f'no step reaches the tolerance {tolerance:g} m (last estimate '
                         f'{err:.3g} m at h = {h:.3g} s)')
    return best


# -- the plan and the run -------------------------------------------------------------------

@dataclass(frozen=True)
class VelocityPlan:
    """Node grids chosen once for a whole batch (so that any chunking gives the same result).

    Attributes:
        output_times: the times of the recorded histories, s (None: none recorded).
        nodes: per kind (0, 1, 2), the integration nodes, s (None where no system).
        steps: per kind, the largest step, s.
        estimates: per kind, the estimated largest error on u, v of the representatives, m.
    """

    output_times: np.ndarray | None
    nodes: tuple[np.ndarray | None, ...]
    steps: tuple[float | None, ...]
    estimates: tuple[float | None, ...]
    tolerance: float


def plan(co: Coefficients, profile: Profile, t_end: float, tolerance: float,
         output_times=None, max_step: float | None = None, z0=0j, p0=0j) -> VelocityPlan:
    """Choose the node grid of every integrator for the batch ``co`` (module docstring)."""
    co = as_arrays(co)
    kinds = system_kinds(co)
    points = mandatory_times(profile, t_end, output_times)
    sampled = np.linspace(0.0, t_end, 2001)
    w_max = max(float(np.max(np.abs(profile.omega(sampled)))), profile.peak
                if _has_peak(profile) else 0.0)
    n = np.size(co.w1sq)
    z0 = np.broadcast_to(np.asarray(z0, complex), (n,))
    p0 = np.broadcast_to(np.asarray(p0, complex), (n,))
    nodes: list[np.ndarray | None] = [None] * 3
    steps: list[float | None] = [None] * 3
    estimates: list[float | None] = [None] * 3
    for kind in range(3):
        idx = np.nonzero(kinds == kind)[0]
        if idx.size == 0:
            continue
        sub = subset(co, idx)
        w0 = math.sqrt(max(float(np.max(sub.w1sq)), float(np.max(sub.w2sq))))
        h_cap = 1.0 / (w0 + w_max)
        if max_step is not None:
            h_cap = min(h_cap, max_step)
        h_start = h_cap if kind == 0 else min(h_cap, 0.6 / (w0 + w_max))
        h, err = choose_step(kind, sub, profile, points, z0[idx], p0[idx], tolerance, h_cap,
                             h_start)
        nodes[kind], steps[kind], estimates[kind] = subdivide(points, h), h, err
    return VelocityPlan(None if output_times is None else np.asarray(output_times, float),
                        tuple(nodes), tuple(steps), tuple(estimates), float(tolerance))


def _has_peak(profile) -> bool:
    try:
        return math.isfinite(profile.peak)
    except (NotImplementedError, AttributeError):
        return False


def _refine_peaks(kind, co, profile, nodes, traj):
    """Largest |z| over the run and its time: sampled maxima refined by Newton's method.

    The largest few local maxima of the sampled |z|^2 are each refined on the node
    interval where d|z|^2/dt changes sign: a secant start, then Newton steps on
    d|z|^2/dt whose states come from one exact step from the interval's first node.
    The result is never below the largest sample.
    """
    r2 = traj.r2()                                      # (n, nodes)
    n, K1 = r2.shape
    if K1 < 2:
        return np.sqrt(r2[:, 0]), np.full(n, nodes[0])
    scored = r2.copy()
    scored[:, 1:][r2[:, 1:] < r2[:, :-1]] = -np.inf     # local maxima of the samples only
    scored[:, :-1][r2[:, :-1] < r2[:, 1:]] = -np.inf
    cols = np.arange(n)
    candidates, kept = [], []
    for _ in range(min(_PEAK_CANDIDATES, K1)):
        k = np.argmax(scored, axis=1)
        candidates.append(k)
        kept.append(np.isfinite(scored[cols, k]))
        scored[cols, k] = -np.inf
    best, best_t = r2[cols, candidates[0]], nodes[candidates[0]]     # the largest sample
    cand, keep = np.array(candidates), np.array(kept)
    cols = np.broadcast_to(cols, cand.shape)
    k, j = cand[keep], cols[keep]
    zk, pk = traj.at(k, j)
    slope = 2.0 * (zk.conj() * pk).real
    a = np.where(((slope >= 0) & (k < K1 - 1)) | (k == 0), k, k - 1)
    ok = (a >= 0) & (a < K1 - 1)
    a, j = a[ok], j[ok]
    if a.size == 0:
        return np.sqrt(best), best_t
    t_a, L = nodes[a], nodes[a + 1] - nodes[a]
    za, pa = traj.at(a, j)
    zb, pb = traj.at(a + 1, j)
    fa = 2.0 * (za.conj() * pa).real
    fb = 2.0 * (zb.conj() * pb).real
    with np.errstate(all='ignore'):
        tau = np.clip(np.where(fa > fb, L * fa / (fa - fb), 0.5 * L), 0.0, L)
    tau = np.where(np.isfinite(tau), tau, 0.5 * L)
    sub = subset(co, j)
    top, top_t = np.full(a.size, -np.inf), t_a.copy()
    for _ in range(_NEWTON):
        z, p = step_states(kind, sub, profile, t_a, tau, za, pa)
        t = t_a + tau
        u, v, du, dv = z.real, z.imag, p.real, p.imag
        ddu, ddv = model.deflection_accelerations(sub, u, v, du, dv, profile.omega(t),
                                                  profile.omega_dot(t))
        f = u * u + v * v
        better = f > top
        top = np.where(better, f, top)
        top_t = np.where(better, t, top_t)
        f1 = 2.0 * (u * du + v * dv)
        f2 = 2.0 * (du * du + dv * dv + u * ddu + v * ddv)
        with np.errstate(all='ignore'):
            newton = tau - f1 / f2
        tau = np.where((f2 < 0) & np.isfinite(newton), np.clip(newton, 0.0, L), tau)
    refined = np.full(n, -np.inf)
    np.maximum.at(refined, j, top)
    refined_t = np.zeros(n)
    winner = top == refined[j]
    refined_t[j[winner]] = top_t[winner]
    up = refined > best
    return np.sqrt(np.where(up, refined, best)), np.where(up, refined_t, best_t)


def run(co: Coefficients, profile: Profile, the_plan: VelocityPlan, z0, p0) -> dict:
    """Run a chunk of systems on the plan's grids.

    Returns a dict with ``z``, ``p`` (final z = u + iv and z', complex arrays (n,)),
    ``peak``, ``peak_time`` (n,), and ``u``, ``v``, ``du``, ``dv`` (n, len(output_times))
    if recorded.
    """
    co = as_arrays(co)
    n = np.size(co.w1sq)
    kinds = system_kinds(co)
    z0 = np.broadcast_to(np.asarray(z0, complex), (n,))
    p0 = np.broadcast_to(np.asarray(p0, complex), (n,))
    out = {'z': np.empty(n, complex), 'p': np.empty(n, complex), 'peak': np.empty(n),
           'peak_time': np.empty(n)}
    output_times = the_plan.output_times
    if output_times is not None:
        nout = len(output_times)
        for name in ('u', 'v', 'du', 'dv'):
            out[name] = np.empty((n, nout))
    for kind in range(3):
        idx = np.nonzero(kinds == kind)[0]
        if idx.size == 0:
            continue
        nodes = the_plan.nodes[kind]
        if nodes is None:
            raise ValueError(f'the plan has no grid for the {KINDS[kind]} integrator')
        sub = subset(co, idx)
        traj = run_kind(kind, sub, profile, nodes, z0[idx], p0[idx])
        zf, pf = traj.rows([len(nodes) - 1])
        if not (np.all(np.isfinite(zf)) and np.all(np.isfinite(pf))):
            raise NonFiniteStateError('the velocity-drive batch produced non-finite values')
        out['z'][idx], out['p'][idx] = zf[0], pf[0]
        peak, peak_time = _refine_peaks(kind, sub, profile, nodes, traj)
        if not np.all(np.isfinite(peak)):
            raise NonFiniteStateError('the velocity-drive batch produced non-finite values')
        out['peak'][idx], out['peak_time'][idx] = peak, peak_time
        if output_times is not None:
            at = np.searchsorted(nodes, output_times - 1e-12 * max(1.0, nodes[-1]))
            Zo, Po = traj.rows(at)
            out['u'][idx], out['v'][idx] = Zo.real.T, Zo.imag.T
            out['du'][idx], out['dv'][idx] = Po.real.T, Po.imag.T
    return out
