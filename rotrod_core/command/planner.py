"""The fastest vibration-free change of hub speed under a tip-deflection limit.

:func:`plan_spin_up` returns a :class:`~rotrod_core.command.profiles.SpinUpProfile` that takes
the hub from ``omega_start`` to ``omega_target`` in the shortest duration it finds such
that the tip deflection |r| stays under a limit, the free whirl left after arrival
(about the static deflection at the target speed) is below ``residual``, optionally
for every natural frequency in a band (1 +- eps) w0, and |w'| stays under a bound.

Method (docs/planner.md): for a given w(t) the deflection equations are linear, so
the end state of the run fixes the free vibration that follows in closed form: its
offset from the static deflection, split on the eigenvectors of the constant-speed
state matrix, gives the two whirls and their amplitudes. w(t) is a clamped cubic
B-spline (w' = 0 at both ends). For a fixed duration its free control points are
found by constrained Gauss-Newton steps on the whirl components (then, if needed,
SLSQP on the largest residual), subject to the deflection and acceleration limits,
with exact gradients from a forward sensitivity of the fourth-order Magnus
propagator. The duration is found by bracketing and bisection on feasibility, and
the result is checked afterwards on finer grids (time steps and the robust band).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from scipy.interpolate import BSpline
from scipy.optimize import lsq_linear, minimize

import rotrod_core.model.propagation as propagation
from rotrod_core.command.profiles import SpinUpProfile, spin_up_knots
from rotrod_core.model.equations import Coefficients
from rotrod_core.model.params import RodParams
from rotrod_core.numerics.checks import finite_number
from rotrod_core.numerics.expm import expm_batch

STEPS_PER_KNOT = 6
"""Magnus steps per knot interval while optimising (4x more for the final check)."""
MAX_STEPS_PER_KNOT = 24
"""Finest optimisation grid, reached by doubling when the final check disagrees."""
MAGNUS_STEP = 1.0
"""Largest Magnus step times the fastest free-vibration rate, w0 (1 + eps) + |w|."""
MIN_FREE = 10
"""Fewest free control points (2 more with a robust band)."""
MAX_FREE = 40
"""Most free control points."""
KNOT_SPACING = 0.35
"""Knot spacing, in periods of the lowest natural frequency, until MAX_FREE is reached:
the shape must resolve the vibration it cancels."""
"""Finest optimisation grid, reached by doubling when the final check disagrees."""
BAND_SAMPLES = 5
"""Fewest natural-frequency samples across a robust band used by the optimiser."""
BAND_CHECK = 41
"""Natural-frequency samples across the band in the final check."""
WINDOWS = 40
"""Deflection-limit constraints: the largest |r| in each of this many time windows."""
SHAPE_BOUND = 0.3
"""Control points stay within the start..target range widened by this fraction."""
RESIDUAL_MARGIN = 0.1
"""The optimiser aims at (1 - margin) x residual; the final check uses residual."""
LIMIT_MARGIN = 5e-4
"""The optimiser keeps |r| <= (1 - margin) x deflection_limit on its time grid."""
RESOLUTION = 1e-7
"""Smallest residual asked for, relative to the static deflections of the request: the
optimisation grid computes the end state to ~1e-9 of them."""
MAX_PERIODS = 1000
"""The duration search gives up beyond this many periods of w0 (or 4x the shortest
duration the acceleration bound allows, if longer)."""
DURATION_TOLERANCE = 0.02
"""Relative width of the final duration bracket."""
GAUSS_NEWTON = True
"""Start each shape optimisation with constrained Gauss-Newton steps (then SLSQP)."""
GIVE_UP = 3.0
"""After Gauss-Newton, a duration is judged infeasible without SLSQP when the largest
residual is still above this multiple of the aim while the deflection stays clear of
its limit (the residual, not the limit, stalled)."""
STALL = 25
"""An optimisation stops as infeasible when the best of its last STALL iterations
is still above 1.5x the aim and less than 20 % below the best before them."""


@dataclass(frozen=True)
class _Sample:
    """One system of the band: coefficients, start state, target state, residual rows."""

    co: Coefficients
    start: np.ndarray       # (u, v, u', v', 1) at omega_start, at rest about its static
    target: np.ndarray      # (u, v, u', v') static at omega_target
    rows: np.ndarray        # complex (n, 4): residual = sum |rows @ (x - target)|
    parts: tuple            # propagation.derivative_parts(co): dA/dw, dA/dw' of this rod


def _coefficients(params: RodParams, scale: float) -> Coefficients:
    """The equations' coefficients with the natural frequencies scaled by ``scale``.

    The stiffness scales by scale^2, as a change of Young's modulus would.
    """
    return Coefficients.from_params(params.replace(youngs_modulus=params.youngs_modulus
                                                   * scale * scale))


def _stacked(samples) -> tuple[Coefficients, tuple]:
    """The samples' coefficients as arrays of shape (B, 1), and their derivative parts.

    One row per sample; the parts (:func:`~rotrod_core.model.propagation.derivative_parts`,
    each sample's own, evaluated once in :func:`_sample`) stacked to (B, 1, 5, 5).
    """
    co = Coefficients(**{k: np.array([float(getattr(s.co, k)) for s in samples])[:, None]
                         for k in vars(samples[0].co)})
    parts = tuple(np.stack([s.parts[i] for s in samples])[:, None] for i in range(3))
    return co, parts


def _free_matrix(co: Coefficients, omega: float) -> np.ndarray:
    """The 5x5 system at a constant speed ``omega`` (rad/s), from the kernel."""
    return propagation.system_matrix(co, omega, 0.0)


def _sample(params: RodParams, scale: float, omega_start: float,
            omega_target: float) -> _Sample:
    co = _coefficients(params, scale)
    states = []
    for w in (omega_start, omega_target):
        A = _free_matrix(co, w)
        lam = np.linalg.eigvals(A[:4, :4])
        if np.max(lam.real) > 1e-9 * np.max(np.abs(lam)):
            raise ValueError(f'the rod is unstable at a constant {w:g} rad/s (natural '
                             f'frequencies x {scale:g}): no residual-free arrival or start '
                             'exists there')
        states.append(np.linalg.solve(A[:4, :4], -A[:4, 4]))
    return _Sample(co, np.r_[states[0], 1.0], states[1], _residual_rows(co, omega_target),
                   propagation.derivative_parts(co))


def _residual_rows(co: Coefficients, omega: float) -> np.ndarray:
    """Rows R (complex, n x 4) with: free-whirl amplitude = sum |R @ (x - x_static)|.

    At constant w a free motion is x(t) = sum_i q_i phi_i exp(lambda_i t), q = V^-1 x.
    A complex pair (lambda, conj lambda) moves the tip as z = u + i v = a+ exp(lambda t)
    + a- exp(conj(lambda) t) with a+- = q (phi_u +- i phi_v) in the form
    a+ = q (phi_u + i phi_v), conj(a-) = q (phi_u - i phi_v): an ellipse whose
    semi-major axis (the whirl's amplitude) is |a+| + |a-|. A real eigenvalue moves it
    along a line, amplitude |q| |(phi_u, phi_v)|.
    """
    lam, V = np.linalg.eig(_free_matrix(co, omega)[:4, :4])
    W = np.linalg.inv(V)
    scale = np.max(np.abs(lam))
    rows = []
    for i in range(4):
        if lam[i].imag > 1e-12 * scale:
            a, b = V[0, i] * W[i], V[1, i] * W[i]
            rows += [a + 1j * b, a - 1j * b]
        elif abs(lam[i].imag) <= 1e-12 * scale:
            rows.append(math.hypot(abs(V[0, i]), abs(V[1, i])) * W[i])
    return np.array(rows, dtype=complex)


def whirl_residual(params: RodParams, omega: float, u, v, du, dv) -> float:
    """Free-whirl amplitude (m) of a state about the static deflection at ``omega``.

    The state is (u, v, u', v'); the amplitude is the sum of the semi-major axes of the whirls the
    rod performs if w stays at ``omega`` from now on (at this instant, for a damped rod).
    """
    s = _sample(params, 1.0, omega, omega)
    e = np.array([u, v, du, dv], dtype=float) - s.target
    return float(np.sum(np.abs(s.rows @ e)))


def fitted_whirl_residual(params: RodParams, omega: float, t, u, v) -> tuple[float, float]:
    """Free-whirl amplitude (m) of a measured motion at constant ``omega``, and the misfit.

    The motion (``t`` s, ``u``, ``v`` m; e.g. published after a spin-up) is fitted by
    least squares to the static deflection at ``omega`` plus the free motion of the
    rod at that speed, x(t) = exp(A (t - t[0])) x0 (every mode, k1 != k2 and damping
    included); the amplitude is :func:`whirl_residual`'s of the fitted x0. Returns
    (amplitude m, root-mean-square misfit m).
    """
    s = _sample(params, 1.0, omega, omega)
    t = np.asarray(t, dtype=float)
    z = np.r_[np.asarray(u, dtype=float) - s.target[0], np.asarray(v, dtype=float)
              - s.target[1]]
    if t.size < 4 or z.size != 2 * t.size or not np.all(np.isfinite(z)):
        raise ValueError('fitted_whirl_residual needs >= 4 finite samples of t, u and v')
    lam, V = np.linalg.eig(_free_matrix(s.co, omega)[:4, :4])
    W = np.linalg.inv(V)
    grow = np.exp(np.outer(t - t[0], lam))                   # (n, 4)
    design = np.r_[((V[0] * grow) @ W).real, ((V[1] * grow) @ W).real]
    x0, *_ = np.linalg.lstsq(design, z, rcond=None)
    misfit = float(np.sqrt(np.mean((design @ x0 - z) ** 2)))
    return float(np.sum(np.abs(s.rows @ x0))), misfit


def _basis(n_free: int, x: np.ndarray):
    spline = BSpline(spin_up_knots(n_free), np.eye(n_free + 4), 3)
    return spline(x), spline.derivative()(x)


class _Grid:
    """Magnus steps aligned with the knots (the spline is a polynomial within each)."""

    def __init__(self, n_free: int, steps_per_knot: int):
        self.n = (n_free + 1) * steps_per_knot
        x0 = np.arange(self.n) / self.n
        g1, g2 = propagation.GAUSS2
        self.x1, self.x2 = x0 + g1 / self.n, x0 + g2 / self.n
        self.w1, self.d1 = _basis(n_free, self.x1)
        self.w2, self.d2 = _basis(n_free, self.x2)


def _propagate(samples, grid: _Grid, T: float, c: np.ndarray, free=None):
    """States on the grid nodes for every sample, shape (B, N + 1, 5).

    With ``free``, also their derivatives with respect to those control points and
    to T, shape (B, N + 1, 5, len(free) + 1). The system, its Magnus exponent, their
    derivatives and the chains are the kernel's (:mod:`rotrod_core.model.propagation`).
    """
    co, parts = _stacked(samples)
    h = T / grid.n
    w1, wd1 = grid.w1 @ c, grid.d1 @ c / T
    w2, wd2 = grid.w2 @ c, grid.d2 @ c / T
    A1 = propagation.system_matrix(co, w1, wd1)
    A2 = propagation.system_matrix(co, w2, wd2)
    omega = propagation.magnus4(h, A1, A2)
    half = expm_batch(0.5 * omega)
    phi = half @ half
    X = propagation.affine_chain(phi, np.array([s.start for s in samples]))
    if free is None:
        return X, None
    # d(Omega)/dp for p = w(t1), w'(t1), w(t2), w'(t2), and T at fixed speeds
    dw1, da1 = propagation.system_matrix_derivatives(co, w1, wd1, parts)
    dw2, da2 = propagation.system_matrix_derivatives(co, w2, wd2, parts)
    E = np.stack([propagation.magnus4_derivative(h, A1, A2, dw1, 0.0),
                  propagation.magnus4_derivative(h, A1, A2, da1, 0.0),
                  propagation.magnus4_derivative(h, A1, A2, 0.0, dw2),
                  propagation.magnus4_derivative(h, A1, A2, 0.0, da2),
                  propagation.magnus4_step_derivative(h, A1, A2) * (h / T)])
    dx = propagation.frechet_simpson(half, phi, E, X[:, :-1], X[:, 1:])
    z = np.zeros((grid.n, 1))
    dp = np.stack([np.c_[grid.w1[:, free], z], np.c_[grid.d1[:, free] / T, -wd1[:, None] / T],
                   np.c_[grid.w2[:, free], z], np.c_[grid.d2[:, free] / T, -wd2[:, None] / T],
                   np.c_[np.zeros((grid.n, len(free))), z + 1]])
    D = np.einsum('pbni,pnk->bnik', dx, dp)
    return X, propagation.sensitivity_chain(phi, D)


def _residuals(samples, X, S=None, parts=False):
    """Residual amplitude of each sample at the end (and its gradient).

    With ``parts``, also the whirl components (complex, all samples) and their
    derivatives, whose moduli the amplitudes add up.
    """
    out, grad, vals, dvals = [], [], [], []
    for b, s in enumerate(samples):
        val = s.rows @ (X[b, -1, :4] - s.target)
        mag = np.abs(val)
        out.append(mag.sum())
        if S is not None:
            dval = s.rows @ S[b, -1, :4]
            grad.append(((np.conj(val)[:, None] * dval).real
                         / np.maximum(mag, 1e-300)[:, None]).sum(axis=0))
            vals.append(val)
            dvals.append(dval)
    if parts:
        return np.array(out), np.array(grad), np.concatenate(vals), np.concatenate(dvals)
    return np.array(out), (np.array(grad) if S is not None else None)


class _Problem:
    """The shape optimisation at one duration, and the feasibility checks."""

    def __init__(self, params, omega_start, omega_target, limit, residual, scales,
                 max_acc, n_free, steps=STEPS_PER_KNOT):
        self.params = params
        self.ws, self.wf = omega_start, omega_target
        self.dw = omega_target - omega_start
        self.limit, self.residual, self.max_acc = limit, residual, max_acc
        self.n_free = n_free
        self.free = np.arange(2, n_free + 2)
        self.scales = list(scales)
        self.samples = [_sample(params, s, omega_start, omega_target) for s in self.scales]
        self.steps = steps
        self.grid = _Grid(n_free, steps)
        self.windows = np.array_split(np.arange(self.grid.n + 1), WINDOWS)
        lo, hi = sorted((omega_start, omega_target))
        cap = _speed_cap(params, max(self.scales[0], min(self.scales)))
        lo, hi = max(lo - SHAPE_BOUND * (hi - lo), 0.0), min(hi + SHAPE_BOUND * (hi - lo),
                                                              cap)
        bounds = sorted(((lo - self.ws) / self.dw, (hi - self.ws) / self.dw))
        self.bounds = [tuple(bounds)] * n_free
        t = spin_up_knots(n_free)
        n = n_free + 4
        # w' of a cubic B-spline is a quadratic one with control points
        # 3 (c_i+1 - c_i) / (t_i+4 - t_i+1): bounding them bounds |w'| (convex hull)
        self.diff = np.zeros((n - 1, n))
        for i in range(n - 1):
            f = 3.0 / (t[i + 4] - t[i + 1])
            self.diff[i, i], self.diff[i, i + 1] = -f, f

    def control_points(self, y) -> np.ndarray:
        return np.r_[self.ws, self.ws, self.ws + self.dw * np.asarray(y), self.wf, self.wf]

    def initial_shape(self) -> np.ndarray:
        """Free control points of the shape x - sin(2 pi x) / 2 pi (Eq. 26's spin-up)."""
        x = np.linspace(0.0, 1.0, 200)
        Bw, _ = _basis(self.n_free, x)
        target = x - np.sin(2 * np.pi * x) / (2 * np.pi) - Bw[:, -2:].sum(axis=1)
        return np.linalg.lstsq(Bw[:, self.free], target, rcond=None)[0]

    def fit(self, c) -> np.ndarray:
        """Free points (normalised) of this problem's spline closest to control points c."""
        c = np.asarray(c, dtype=float)
        if c.size == self.n_free + 4:
            return (c[2:-2] - self.ws) / self.dw
        x = np.linspace(0.0, 1.0, 20 * (max(c.size, self.n_free) + 1))
        w = BSpline(spin_up_knots(c.size - 4), c, 3)(x)
        Bw, _ = _basis(self.n_free, x)
        fixed = Bw[:, :2].sum(axis=1) * self.ws + Bw[:, -2:].sum(axis=1) * self.wf
        full = np.linalg.lstsq(Bw[:, self.free], w - fixed, rcond=None)[0]
        return np.clip((full - self.ws) / self.dw, *self.bounds[0])

    def evaluate(self, T, y):
        X, S = _propagate(self.samples, self.grid, T, self.control_points(y), self.free)
        S = S[..., :-1] * self.dw
        res, dres, val, dval = _residuals(self.samples, X, S, parts=True)
        r2 = X[0, :, 0] ** 2 + X[0, :, 1] ** 2
        dr2 = 2 * (X[0, :, 0, None] * S[0, :, 0] + X[0, :, 1, None] * S[0, :, 1])
        return res, dres, r2, dr2, val, dval

    def gauss_newton(self, T, y, ev, feasible, aim, d2, acc, iterations=30):
        """Drive the whirl components to zero by constrained Gauss-Newton steps.

        Each step minimises sum_b weight_b |components_b + J_b d|^2 (scaled by the
        aim) over the step d, with the deflection limit linearised in each window and
        within a trust region; a step is kept when it lowers that sum plus a penalty
        on the deflection excess. When the steps stall, the samples of the band are
        reweighted in proportion to their residuals (Lawson's iteration towards the
        smallest largest residual).
        """
        sizes = [len(s.rows) for s in self.samples]
        owner = np.repeat(np.arange(len(sizes)), sizes)
        weights = np.ones(len(sizes))

        def merit(e):
            _, _, r2, _, val, _ = e
            peaks = np.array([r2[w].max() for w in self.windows])
            return (np.sum(weights[owner] * np.abs(val) ** 2) / aim**2
                    + 1e3 * np.sum(np.maximum(peaks / d2 - 1.0, 0.0)))

        lo, hi = self.bounds[0]
        radius = 0.2
        e = ev(y)
        m = merit(e)
        history = [e[0].max()]
        for _ in range(iterations):
            if feasible(y):
                return y
            res, _, r2, dr2, val, dval = e
            sw = np.sqrt(weights[owner])
            r = np.r_[sw * val.real, sw * val.imag] / aim
            J = np.r_[sw[:, None] * dval.real, sw[:, None] * dval.imag] / aim
            at = [w[np.argmax(r2[w])] for w in self.windows]
            C, c = dr2[at] / d2, 1.0 - r2[at] / d2          # C d <= c, linearised
            if acc is not None:
                C, c = np.r_[C, acc[0]], np.r_[c, acc[1] - acc[0] @ y]
            bounds = (np.maximum(lo - y, -radius), np.minimum(hi - y, radius))
            d = _bounded_least_squares(J, -r, C, c, bounds)
            stalled = not np.all(np.isfinite(d)) or np.max(np.abs(d)) < 1e-8
            if not stalled:
                e_new = ev(y + d)
                m_new = merit(e_new)
                if m_new < m:
                    y, e, m = y + d, e_new, m_new
                    radius = min(2 * radius, 0.5)
                else:
                    radius *= 0.3
                    stalled = radius < 1e-4
            if stalled:
                if len(weights) == 1:
                    break
                weights = weights * e[0] / np.max(e[0])     # Lawson: weight the worst
                weights /= weights.max()
                m = merit(e)
                radius = 0.2
            history.append(e[0].max())
            # far from the aim and no longer improving, the limit not in the way
            if len(history) > 6 and history[-1] > GIVE_UP * aim \
                    and history[-1] > 0.7 * history[-7] and e[2].max() < 0.98 * d2:
                break
        return y

    def solve(self, T, y0, maxiter=60):
        """Look for a feasible shape at duration T from y0: (y, feasible).

        Gauss-Newton first; if that stalls close enough to the aim, SLSQP minimises
        the largest residual (epigraph form) and stops at the first feasible iterate.
        """
        cache: dict[bytes, tuple[np.ndarray, ...]] = {}

        def ev(z):
            key = z[:-1].tobytes()      # the evaluation does not depend on the slack
            if key not in cache:
                if len(cache) > 4:
                    cache.pop(next(iter(cache)))
                cache[key] = self.evaluate(T, z[:-1])
            return cache[key]

        aim = self.residual * (1 - RESIDUAL_MARGIN)
        d2 = (self.limit * (1 - LIMIT_MARGIN)) ** 2

        def cons(z):
            res, _, r2, _, _, _ = ev(z)
            peaks = np.array([r2[w].max() for w in self.windows])
            return np.r_[z[-1] - res / aim, 1.0 - peaks / d2]

        def jac(z):
            res, dres, r2, dr2, _, _ = ev(z)
            at = [w[np.argmax(r2[w])] for w in self.windows]
            return np.r_[np.c_[-dres / aim, np.ones(len(res))],
                         np.c_[-dr2[at] / d2, np.zeros(len(at))]]

        constraints: list[dict[str, Any]] = [{'type': 'ineq', 'fun': cons, 'jac': jac}]
        if self.max_acc is not None:
            A = self.diff[:, self.free] * self.dw / T
            a0 = self.diff @ self.control_points(np.zeros(self.n_free)) / T
            Az = np.c_[np.r_[A, -A], np.zeros(2 * len(A))]
            b = self.max_acc - np.r_[a0, -a0]
            constraints.append({'type': 'ineq', 'fun': lambda z: b - Az @ z,
                                'jac': lambda z: -Az})
        def feasible(y):
            res, _, r2, _, _, _ = ev(np.r_[y, 0.0])
            ok = res.max() <= aim and r2.max() <= d2
            if ok and self.max_acc is not None:
                ok = bool(np.all(constraints[1]['fun'](np.r_[y, 0.0]) >= -1e-12))
            return bool(ok)

        found = []

        history = []

        def stop_when_feasible(intermediate_result):
            y = intermediate_result.x[:-1]
            if feasible(y):
                found.append(y)
                raise StopIteration
            # give up when the largest residual has stalled well above the aim
            history.append(ev(np.r_[y, 0.0])[0].max() / aim)
            if len(history) > 2 * STALL and min(history[-STALL:]) > max(
                    1.5, 0.8 * min(history[:-STALL])):
                raise StopIteration

        y0 = np.clip(y0, *self.bounds[0])
        if feasible(y0):
            return y0, True
        if GAUSS_NEWTON:
            acc = None
            if self.max_acc is not None:
                acc = (Az[:, :-1], b)
            y0 = self.gauss_newton(T, y0, lambda y: ev(np.r_[y, 0.0]), feasible, aim, d2, acc)
            if feasible(y0):
                return y0, True
            res, _, r2, _, _, _ = ev(np.r_[y0, 0.0])
            if res.max() > GIVE_UP * aim and r2.max() < 0.98 * d2:
                return y0, False        # the residual stalled, the limit is not in the way
        z0 = np.r_[y0, ev(np.r_[y0, 0.0])[0].max() / aim * 1.01]
        sol = minimize(lambda z: z[-1], z0, jac=lambda z: np.r_[np.zeros(self.n_free), 1.0],
                       method='SLSQP', constraints=constraints,
                       bounds=self.bounds + [(0.0, None)], callback=stop_when_feasible,
                       options={'maxiter': maxiter, 'ftol': 1e-10})
        if found:
            return found[0], True
        y = sol.x[:-1]
        if np.all(np.isfinite(y)):
            return y, feasible(y)
        return y0, False

    def check(self, T, y):
        """Check on a 4x finer time grid: (peak, nominal residual, band max, its scale).

        The band (robust only) is checked on BAND_CHECK natural frequencies, or 4 per
        optimised sample if more.
        """
        fine = _Grid(self.n_free, 4 * self.steps)
        c = self.control_points(y)
        X, _ = _propagate(self.samples[:1], fine, T, c)
        peak = _peak(X[0, :, 0] ** 2 + X[0, :, 1] ** 2)
        nominal = float(_residuals(self.samples[:1], X)[0][0])
        band, worst = nominal, 1.0
        eps = max(abs(s - 1.0) for s in self.scales)
        if eps > 0:
            scales = np.linspace(1 - eps, 1 + eps, max(BAND_CHECK, 4 * len(self.scales)))
            samples = [_sample(self.params, s, self.ws, self.wf) for s in scales]
            Xb, _ = _propagate(samples, fine, T, c)
            res = _residuals(samples, Xb)[0]
            band, worst = float(res.max()), float(scales[np.argmax(res)])
        return peak, nominal, band, worst


def _bounded_least_squares(J, rhs, C, c, bounds, rounds=6):
    """Least squares |J d - rhs| within bounds and C d <= c (linear), by an active set.

    Rows of C that a solution breaks join the least-squares problem as heavily
    weighted equations C_i d = c_i (they would be active), until none is broken.
    """
    weight = 1e4 * max(float(np.linalg.norm(J)), 1.0)
    active = np.flatnonzero(c < 0)
    lower, upper = bounds
    lower = np.minimum(lower, 0.0)
    upper = np.maximum(upper, 0.0)
    for _ in range(rounds):
        scale = weight / np.maximum(np.linalg.norm(C[active], axis=1), 1e-300)
        A = np.r_[J, scale[:, None] * C[active]]
        b = np.r_[rhs, scale * c[active]]
        d = lsq_linear(A, b, bounds=(lower, upper), method='bvls').x
        broken = np.setdiff1d(np.flatnonzero(C @ d > c + 1e-9 * (1 + np.abs(c))), active)
        if broken.size == 0:
            break
        active = np.union1d(active, broken)
    return d


def _peak(r2: np.ndarray) -> float:
    """Largest |r| from |r|^2 on equal steps: a parabola through the largest sample."""
    k = int(np.argmax(r2))
    top = r2[k]
    if 0 < k < len(r2) - 1:
        a, b, c = r2[k - 1], r2[k], r2[k + 1]
        curv = a - 2 * b + c
        if curv < 0:
            top = b - 0.125 * (c - a) ** 2 / curv
    return float(math.sqrt(top))


def residual_bound(value: float, bound: float | None = None) -> str:
    """A whirl amplitude (m) as the bound it meets: '<= X um'.

    X is ``bound`` (m) when the value is within it, else the value rounded up to two
    digits. What a plan leaves is a bound met, not one machine's rounding: a residual
    far below its bound is where the planner's search stopped, and its digits move
    with the arithmetic of the machine (docs/planner.md#limits-and-doubts).
    """
    value = float(value)
    if not math.isfinite(value):
        return 'nan um'
    if bound is not None and value <= bound:
        return f'<= {bound * 1e6:g} um'
    um = value * 1e6
    if um <= 0.0:
        return '<= 0 um'
    unit = 10.0 ** (math.floor(math.log10(um)) - 1)
    rounded = float(f'{math.ceil(um / unit * (1 - 1e-12)) * unit:.2g}')
    return f'<= {rounded:g} um'


def _speed_cap(params: RodParams, scale: float) -> float:
    """Speeds kept below this in a plan: 0.98 x the lowest natural frequency (scaled)."""
    return 0.98 * scale * min(float(params.natural_frequency_radial),
                              float(params.natural_frequency_tangential))


def _check_inputs(params, omega_target, omega_start, limit, residual, robust, max_acc):
    if not isinstance(params, RodParams):
        raise ValueError(f'params must be RodParams, got {type(params).__name__}')
    if params.is_batch:
        raise ValueError('plan_spin_up plans for one system, not a batch of parameters')
    wf = finite_number('omega_target', omega_target, nonnegative=True)
    ws = finite_number('omega_start', omega_start, nonnegative=True)
    limit = finite_number('deflection_limit', limit, positive=True)
    residual = finite_number('residual', residual, positive=True)
    robust = finite_number('robust', robust, nonnegative=True)
    if robust >= 1:
        raise ValueError(f'robust must be < 1 (a band (1 +- robust) w0), got {robust!r}')
    if max_acc is not None:
        max_acc = finite_number('max_angular_acceleration', max_acc, positive=True)
    if wf == ws:
        raise ValueError(f'omega_target equals omega_start ({ws!r} rad/s): nothing to plan')
    return wf, ws, limit, residual, robust, max_acc


def plan_spin_up(params: RodParams, omega_target: float, *, omega_start: float = 0.0,
                 deflection_limit: float = 0.003, residual: float = 2.5e-7,
                 robust: float = 0.0, max_angular_acceleration: float | None = None,
                 ) -> SpinUpProfile:
    """The shortest smooth change of speed that leaves no vibration, found numerically.

    The hub goes from ``omega_start`` (the rod at rest about its static deflection
    there) to ``omega_target`` (rad/s, both >= 0; below the start: a spin-down) along
    a :class:`SpinUpProfile` with w and w' continuous and w' = 0 at both ends, such that

    - |r(t)| <= ``deflection_limit`` (m) throughout, nominal parameters;
    - after the change, the free whirl about the static deflection at ``omega_target``
      (sum of the two whirls' amplitudes) is <= ``residual`` (m), for every natural
      frequency in [(1 - robust) w0, (1 + robust) w0] when ``robust`` > 0 (stiffness
      scaled, as by Young's modulus);
    - |w'| <= ``max_angular_acceleration`` (rad/s^2) when given.

    The profile carries the planner's predictions ``peak_deflection``,
    ``residual_amplitude`` (nominal) and ``band_residual`` (largest over the band).
    Raises ValueError naming the input or the constraint that cannot be met.
    """
    wf, ws, limit, residual, robust, max_acc = _check_inputs(
        params, omega_target, omega_start, deflection_limit, residual, robust,
        max_angular_acceleration)
    cap = _speed_cap(params, 1.0 - robust) / 0.98
    if max(ws, wf) >= cap:
        what = 'omega_target' if wf >= ws else 'omega_start'
        band = f' x (1 - robust = {1 - robust:g})' if robust else ''
        raise ValueError(f'{what} = {max(ws, wf):g} rad/s reaches the lowest natural '
                         f'frequency{band}, {cap:g} rad/s: no vibration-free arrival there '
                         '(the static deflection is unbounded or the rod unstable)')
    family = _Family(params, ws, wf, limit, residual, robust, max_acc)
    problem = family.problem(0.0)
    for name, w, state in (('omega_target', wf, problem.samples[0].target),
                           ('omega_start', ws, problem.samples[0].start)):
        static = math.hypot(state[0], state[1])
        room = residual if name == 'omega_target' else 0.0
        if static + room > limit:
            raise ValueError(f'deflection_limit = {limit:g} m cannot be met: the static '
                             f'deflection at {name} = {w:g} rad/s is already {static:g} m'
                             + (f' (+ the residual {residual:g} m)' if room else ''))
    scale = max(math.hypot(*problem.samples[0].target[:2]),
                math.hypot(*problem.samples[0].start[:2]), r0_floor(params))
    if residual < RESOLUTION * scale:
        raise ValueError(f'residual = {residual:g} m is below what the planner resolves: '
                         f'{RESOLUTION:g} x the deflection scale {scale:g} m')
    return _search(family)


def r0_floor(params: RodParams) -> float:
    """A deflection scale that is never zero: the static deflection at 1 % of w0."""
    w = 0.01 * min(float(params.natural_frequency_radial),
                   float(params.natural_frequency_tangential))
    return max(w * w * float(params.eccentricity) / (
        float(params.stiffness_radial) / float(params.mass)), 1e-12)


class _Family:
    """The shape problems of one request: the knot count grows with the duration.

    A shape is carried between durations as its control points (rad/s), refitted
    by least squares when the knot count changes.
    """

    def __init__(self, params, ws, wf, limit, residual, robust, max_acc):
        self.args = (params, ws, wf, limit, residual)
        self.params, self.ws, self.wf, self.limit, self.residual = self.args
        self.eps, self.max_acc = robust, max_acc
        self.extra: list[float] = []   # band frequencies added by the final checks
        self.steps = STEPS_PER_KNOT
        self.min_free = MIN_FREE + (2 if robust else 0)
        w0 = min(float(params.natural_frequency_radial),
                 float(params.natural_frequency_tangential))
        self.period = 2 * math.pi / w0
        self._problems = {}

    def problem(self, T: float) -> _Problem:
        n_free = int(np.clip(math.ceil(T / (KNOT_SPACING * self.period)) - 1, self.min_free,
                             MAX_FREE))
        # the Magnus series needs h |A| well below pi: h (w0 + |w|) <= MAGNUS_STEP
        w0 = 2 * math.pi / self.period
        fastest = w0 * (1 + self.eps) + max(self.ws, self.wf)
        steps = max(self.steps, math.ceil(T * fastest / (MAGNUS_STEP * (n_free + 1))))
        scales = self.scales(T)
        key = (n_free, steps, tuple(scales))
        if key not in self._problems:
            self._problems[key] = _Problem(*self.args, scales, self.max_acc, n_free, steps)
        return self._problems[key]

    def scales(self, T: float) -> list[float]:
        """Natural-frequency factors optimised at duration T, nominal first.

        The residual, as a function of w0, oscillates about once per 2 pi / T: the
        band is sampled ~3 times per oscillation, BAND_SAMPLES at least.
        """
        if not self.eps:
            return [1.0]
        w0 = 2 * math.pi / self.period
        n = max(BAND_SAMPLES, math.ceil(3 * self.eps * w0 * T / math.pi) + 1)
        n += 1 - n % 2          # odd: the nominal is one of them
        band = np.linspace(1 - self.eps, 1 + self.eps, n)
        return [1.0] + [float(s) for s in band if abs(s - 1.0) > 1e-12] + self.extra

    def solve(self, T: float, c):
        """Feasible control points at duration T from the shape ``c``: (c, ok)."""
        problem = self.problem(T)
        y0 = problem.initial_shape() if c is None else problem.fit(c)
        y, ok = problem.solve(T, y0)
        return problem.control_points(y), ok

    def check(self, T: float, c):
        problem = self.problem(T)
        return problem.check(T, problem.fit(c))


def _search(family: _Family) -> SpinUpProfile:
    """Bracket and bisect the duration on the feasibility of the shape optimisation.

    The result is checked on finer grids; when the check fails, the optimisation
    grid is refined, or the band's worst frequency joins the optimised samples, or
    the duration grows.
    """
    lower = abs(family.wf - family.ws) / family.max_acc if family.max_acc else 0.0
    T_max = max(MAX_PERIODS * family.period, 4.0 * lower)
    eps = family.eps
    # a first guess: two periods, or what resolving the band takes (~ 1 / (eps w0))
    first = family.period * max(2.0, 0.7 / eps if eps else 0.0)
    good = _feasible_from(family, max(first, 1.6 * lower), None, T_max)
    bad = lower
    for _ in range(8):
        while good[0] - bad > DURATION_TOLERANCE * good[0]:
            T = max(0.5 * (good[0] + bad), 0.6 * good[0])
            c, ok = family.solve(T, good[1])
            if ok:
                good = (T, c)
            else:
                bad = T
        peak, nominal, band, worst = family.check(*good)
        if peak <= family.limit and nominal <= family.residual and band <= family.residual:
            T, c = good
            return SpinUpProfile(T, c, peak_deflection=peak, residual_amplitude=nominal,
                                 band_residual=band, robust=eps)
        coarse = peak > family.limit or nominal > family.residual
        if coarse and family.steps < MAX_STEPS_PER_KNOT:
            family.steps *= 2
        elif not coarse and worst not in family.scales(good[0]):
            family.extra.append(worst)      # a cutting plane in the band
        else:       # the check failed at good with the finest settings: search above it
            bad = good[0]
            good = _feasible_from(family, good[0] * (1 + DURATION_TOLERANCE), good[1], T_max)
            continue
        c, ok = family.solve(*good)
        if ok:
            good = (good[0], c)
        else:
            bad = good[0]
            good = _feasible_from(family, good[0] * (1 + DURATION_TOLERANCE), good[1], T_max)
    raise ValueError(f'no plan from {family.ws:g} to {family.wf:g} rad/s passed the final '
                     f'check on a finer grid (last tried {good[0]:g} s): the constraints are '
                     'too close to what the linear model can resolve')


def _feasible_from(family: _Family, T: float, c, T_max: float):
    """The first feasible (T, control points) going up from T by factors of 1.6."""
    while T <= T_max:
        c_new, ok = family.solve(T, c)
        if ok:
            return T, c_new
        T *= 1.6
    raise ValueError(_infeasible_message(family, T_max))


def _infeasible_message(problem: _Family, T_max: float) -> str:
    parts = [f'deflection_limit = {problem.limit:g} m', f'residual = {problem.residual:g} m']
    if problem.eps:
        parts.append(f'robust = {problem.eps:g}')
    if problem.max_acc is not None:
        parts.append(f'max_angular_acceleration = {problem.max_acc:g} rad/s^2')
    return (f'no spin-up from {problem.ws:g} to {problem.wf:g} rad/s found within '
            f'{T_max:g} s that meets {", ".join(parts)} together: the residual could not '
            'be brought under its bound within the deflection limit'
            + (' and the acceleration bound' if problem.max_acc is not None else ''))
