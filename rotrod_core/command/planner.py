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
B-spline (w' = 0 at both ends). At a fixed duration T its free control points
minimise the largest of the constraint ratios (every band sample's whirl, every grid
node's deflection, each as a squared norm over its limit), within the acceleration
bound: a minimax problem solved to convergence (a step predicting less than 1e-6 of
M) by sequential quadratic programming with the ratios' Gauss-Newton curvature, from
the exact gradients of the fourth-order Magnus propagator (forward sensitivities for
the deflection on every node, the adjoint for the end states). Its value M(T) decides
feasibility (M <= 1); the duration is the shortest whole number of milliseconds
found feasible by bracketing and bisection, each solve warm-started from the
nearest duration solved; with an acceleration bound, from a first guess of 1.3x
the shortest duration the bound allows and, once M at the bracket's infeasible end
is near 1, by the secant of log M (close to linear in T there), each such solve
started from the shapes the secant went through. The result is checked afterwards
on finer grids (time steps and the robust band).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np
from scipy.interpolate import BSpline
from scipy.optimize import nnls

import rotrod_core.model.propagation as propagation
from rotrod_core.command import plan_cache
from rotrod_core.command.profiles import SpinUpProfile, spin_up_knots
from rotrod_core.model.equations import Coefficients
from rotrod_core.model.params import RodParams
from rotrod_core.numerics.checks import finite_number
from rotrod_core.numerics.expm import expm_batch_grouped

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
BAND_SAMPLES = 5
"""Fewest natural-frequency samples across a robust band used by the optimiser."""
BAND_CHECK = 41
"""Natural-frequency samples across the band in the final check."""
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
DURATION_STEP = 1e-3
"""The durations tried are whole multiples of this (s): the answer is the shortest
multiple whose minimax value is <= 1, so machines that decide alike print it alike."""
MINIMAX_ITERATIONS = 200
"""Most steps of one minimax solve."""
CLEARLY_FEASIBLE = 0.99
"""A minimax solve stops once M is this far below 1: the duration is feasible whatever
the rest of the iteration would do. The plan's own solve runs to convergence."""
MINIMAX_TOLERANCE = 1e-6
"""A minimax solve stops when a step predicts less decrease than this (relative): M is
then within ~1e-5 of where the iteration goes, inside the margins by which the
durations visited are decided (the closest seen: 5e-5, M = 1.0000473 at 0.947 s of
test_planner's spin-down). Below it the iteration creeps (linear convergence at a
damping that no longer shrinks) for up to MINIMAX_ITERATIONS steps, which was most of
the planning time at 1e-9."""
TRAPEZOID = 1.3
"""With an acceleration bound, the duration search first tries TRAPEZOID x the shortest
duration the bound allows (|w'| at the bound for about 3/4 of the change), then the
first guess as without one (1.6 x that, or what the band takes if longer)."""
SECANT_BELOW = 3.0
"""With an acceleration bound, the duration search steps by the secant of log M once the
minimax value at the bracket's infeasible end is at most this (log M is close to linear
in T there); bisection above it."""
DAMPING = 1e-3
"""First Levenberg-Marquardt damping of a minimax solve (ratios scaled to 1, per unit of
the free control points squared)."""


@dataclass(frozen=True)
class _Sample:
    """One system of the band: coefficients, start state, target state, residual rows."""

    co: Coefficients
    start: np.ndarray       # (u, v, u', v', 1) at omega_start, at rest about its static
    target: np.ndarray      # (u, v, u', v') static at omega_target
    rows: np.ndarray        # complex (n, 4): residual = sum |rows @ (x - target)|


def _coefficients(params: RodParams, scale: float) -> Coefficients:
    """The equations' coefficients with the natural frequencies scaled by ``scale``.

    The stiffness scales by scale^2, as a change of Young's modulus would.
    """
    return Coefficients.from_params(params.replace(youngs_modulus=params.youngs_modulus
                                                   * scale * scale))


class _Batch:
    """Samples as the kernel takes them, built once per problem (B samples).

    ``co``: coefficients, arrays (B,); ``basis``: the matrices whose combinations are
    every step's Magnus exponent and its derivatives
    (:func:`~rotrod_core.model.propagation.magnus4_basis`), (B, 10, 5, 5);
    ``starts``: start states (B, 5). ``balanced``: the basis of a quarter step's
    exponent in the coordinates (u, v, u' / s, v' / s, 1), s the power of 2 nearest the
    highest natural frequency (rad/s). There the exponent's norm is about h (w0 + 2 |w|)
    instead of h w0^2, so that its exponential needs no squarings; ``unbalance``
    multiplies that exponential back, exactly (powers of 2).
    """

    def __init__(self, samples):
        self.co = Coefficients(**{k: np.array([float(getattr(s.co, k)) for s in samples])
                                  for k in vars(samples[0].co)})
        self.basis = propagation.magnus4_basis(propagation.system_features(self.co))
        self.starts = np.array([s.start for s in samples])
        fastest = math.sqrt(max(np.max(self.co.w1sq), np.max(self.co.w2sq)))
        s = 2.0 ** round(math.log2(fastest)) if fastest > 0 else 1.0
        scale = np.array([1.0, 1.0, s, s, 1.0])
        self.balanced = 0.25 * self.basis * (scale[None, :] / scale[:, None])
        self.unbalance = scale[:, None] / scale[None, :]


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
    return _Sample(co, np.r_[states[0], 1.0], states[1], _residual_rows(co, omega_target))


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


class _Run:
    """One shape propagated over the grid for every sample of a batch (B samples, N steps).

    ``X`` (B, N + 1, 5): the states on the grid nodes. Kept for the derivatives
    (:func:`_sensitivities`): the speeds ``w1``, ``w2`` (rad/s) and accelerations
    ``wd1``, ``wd2`` (rad/s^2) at the two Gauss points of every step, (N,), and the
    exponentials of a quarter step and of the step, ``quarter`` and ``phi`` (B, N, 5, 5).
    The Magnus exponent and the chain are the kernel's
    (:mod:`rotrod_core.model.propagation`).
    """

    def __init__(self, batch: _Batch, grid: _Grid, T: float, c: np.ndarray):
        self.T, self.h = T, T / grid.n
        self.w1, self.wd1 = grid.w1 @ c, grid.d1 @ c / T
        self.w2, self.wd2 = grid.w2 @ c, grid.d2 @ c / T
        coefficients = propagation.magnus4_coefficients(self.h, self.w1, self.wd1, self.w2,
                                                        self.wd2)
        balanced = propagation.magnus4_combination(coefficients, batch.balanced)
        self.quarter = expm_batch_grouped(balanced) * batch.unbalance
        half = self.quarter @ self.quarter
        self.phi = half @ half
        self.X = propagation.affine_chain(self.phi, batch.starts)


def _propagate(samples, grid: _Grid, T: float, c: np.ndarray) -> tuple[np.ndarray, _Run]:
    """States on the grid nodes for every sample, shape (B, N + 1, 5), and the run."""
    run = _Run(_Batch(samples), grid, T, c)
    return run.X, run


def _sensitivities(run: _Run, batch: _Batch,
                   shape_derivatives: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """d(state)/d(control points): the nominal's (u, v) on every node, every sample's end.

    Returns (N, 2, k) for nodes 1..N of the nominal sample and (B, 4, k) for the end
    states (u, v, u', v') of all samples (m and m/s per rad/s). ``shape_derivatives``
    (N, 4, k): d(w, w' at the two Gauss points of each step)/d(the k control points).
    Per step, the derivatives of its Magnus exponent by w and w' at its Gauss points
    and the Frechet derivative of the step's exponential along them; then the nominal
    sample's forward sensitivities on every node, and every sample's end by the adjoint
    chain (the end's derivative by each step's state). All the kernel's.
    """
    coefficients = propagation.magnus4_coefficients(run.h, run.w1, run.wd1, run.w2, run.wd2,
                                                    derivatives=True)[:, 1:]
    E = propagation.magnus4_combination(coefficients, batch.basis)     # (B, N, 4, 5, 5)
    dx = propagation.frechet_boole(run.quarter, np.moveaxis(E, -3, 0), run.X[:, :-1])
    by_step = np.moveaxis(dx, 0, -1)                       # (B, N, 5, 4): d(step)/d(w, w')
    nominal = propagation.sensitivity_chain(run.phi[0], by_step[0] @ shape_derivatives)
    lam = propagation.adjoint_chain(run.phi, np.eye(4, 5))             # (B, N + 1, 4, 5)
    ends = lam[:, 1:] @ by_step                                        # (B, N, 4, 4)
    B, N = ends.shape[:2]
    ends = np.moveaxis(ends, 1, 2).reshape(B, 4, N * 4) @ shape_derivatives.reshape(N * 4, -1)
    return nominal[1:, :2], ends


def _residuals(samples, X) -> np.ndarray:
    """Residual amplitude (m) of each sample at the end of the states X: sum of moduli."""
    return np.array([np.abs(s.rows @ (X[b, -1, :4] - s.target)).sum()
                     for b, s in enumerate(samples)])


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
        self.batch = _Batch(self.samples)
        self.steps = steps
        self.grid = _Grid(n_free, steps)
        # whirl components that are not identically zero (a round rod without damping
        # whirls in circles: one of each pair's two components vanishes)
        self.whirl = _Whirl([s.rows[np.linalg.norm(s.rows, axis=1)
                                    > 1e-9 * np.linalg.norm(s.rows)] for s in self.samples],
                            [s.target for s in self.samples])
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
        """The control points (rad/s) of the free points y (normalised by the change)."""
        c = np.empty(self.n_free + 4)
        c[:2], c[2:-2], c[-2:] = self.ws, self.ws + self.dw * np.asarray(y), self.wf
        return c

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

    def limits(self, T: float) -> _Limits:
        """The constraint ratios of this problem at duration T (s)."""
        return _Limits(self, T)

    def minimax(self, T, y0, clear=CLEARLY_FEASIBLE, iterations=MINIMAX_ITERATIONS):
        """The shape at duration T (s) that minimises the largest constraint ratio: (y, M).

        M = max over the ratios of :class:`_Limits` (every band sample's squared
        residual bound / aim^2, every grid node's |r|^2 / d2) among the shapes within
        the acceleration bound and the box: the duration is feasible iff M <= 1.
        Solved to convergence by sequential quadratic programming in epigraph form
        (:func:`_minimax_step`) from ``y0`` (first moved into the linear bounds): M is
        the value the iteration converges to, not the first iterate that happens to
        pass, so the decision M <= 1 moves with the machine's rounding only where M is
        within the solver's tolerance of 1. The curvature of each step's QP is weighted
        by the multipliers of the QP that led to y, plus those of every QP whose step
        was rejected at y since: a steep ratio that only a rejected step brought up
        then bends the next model, instead of the damping alone shrinking the step
        (docs/planner.md compares the two).
        """
        lim = self.limits(T)
        y = self._within_bounds(lim, np.asarray(y0, dtype=float))
        g, G, C = lim.model(y)
        weights = (g >= g.max()).astype(float)
        damping = DAMPING * _hessian(weights, C).trace() / self.n_free
        for _ in range(iterations):
            m = float(g.max())
            if m <= clear:
                break
            step = _minimax_step(g, G, _hessian(weights, C), damping, *self._bounds(lim, y))
            if step is None:
                break
            d, multipliers, predicted = step
            if predicted <= MINIMAX_TOLERANCE * max(m, 1.0):
                break
            trial = np.clip(y + d, *self.bounds[0])
            gain = (m - float(lim.values(trial).max())) / predicted
            if gain > 0.1:
                y = trial
                g, G, C = lim.model(y)
                weights = multipliers
                if gain > 0.75:
                    damping /= 4.0
            else:
                # y stays; the next QP's curvature adds that of the ratios the rejected
                # step's QP found active (its multipliers: estimates at y as well)
                damping *= 4.0
                weights = weights + multipliers
                weights /= max(weights.sum(), 1e-300)
        return y, float(g.max())

    def _bounds(self, lim: _Limits, y: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Linear constraints L d <= l on a step d from y: the box and |w'| <= max_acc."""
        lo, hi = self.bounds[0]
        eye = np.eye(self.n_free)
        L, rhs = [eye, -eye], [hi - y, y - lo]
        if lim.acc_matrix is not None:
            L.append(lim.acc_matrix)
            rhs.append(lim.acc_bound - lim.acc_matrix @ y)
        return np.concatenate(L), np.concatenate(rhs)

    def _within_bounds(self, lim: _Limits, y: np.ndarray) -> np.ndarray:
        """The point nearest y (Euclidean) within the box and the acceleration bound."""
        y = np.clip(y, *self.bounds[0])
        L, rhs = self._bounds(lim, y)
        if np.all(rhs >= 0):
            return y
        out = _quadratic_program(np.eye(self.n_free), np.zeros(self.n_free), L, rhs)
        return y if out is None else np.clip(y + out[0], *self.bounds[0])

    def check(self, T, y):
        """Check on a 4x finer time grid: (peak, nominal residual, band max, its scale).

        The band (robust only) is checked on BAND_CHECK natural frequencies, or 4 per
        optimised sample if more.
        """
        fine = _Grid(self.n_free, 4 * self.steps)
        c = self.control_points(y)
        X, _ = _propagate(self.samples[:1], fine, T, c)
        peak = _peak(X[0, :, 0] ** 2 + X[0, :, 1] ** 2)
        nominal = float(_residuals(self.samples[:1], X)[0])
        band, worst = nominal, 1.0
        eps = max(abs(s - 1.0) for s in self.scales)
        if eps > 0:
            scales = np.linspace(1 - eps, 1 + eps, max(BAND_CHECK, 4 * len(self.scales)))
            samples = [_sample(self.params, s, self.ws, self.wf) for s in scales]
            Xb, _ = _propagate(samples, fine, T, c)
            res = _residuals(samples, Xb)
            band, worst = float(res.max()), float(scales[np.argmax(res)])
        return peak, nominal, band, worst


class _Limits:
    """The constraint ratios of one shape problem at one duration, and their local model.

    values(y) = (m_b sum_j |a_bj|^2 / aim^2 for every band sample b, |r|^2 / d2 at every
    grid node after the start), a_bj the whirl components of sample b (m_b of them): a
    shape y meets the limits on the optimisation grid when all are <= 1 (aim and d2
    carry the margins; by Cauchy-Schwarz the residual, sum_j |a_bj|, is then <= aim).
    Each ratio is a squared norm of components smooth in y: model(y) gives their
    gradients and Gauss-Newton curvature factors (C_i with curvature C_i^T C_i), from
    the kernel's exact sensitivities.
    """

    def __init__(self, problem: _Problem, T: float):
        self.problem, self.T = problem, T
        self._last: tuple[np.ndarray, _Run] | None = None
        self.aim = problem.residual * (1 - RESIDUAL_MARGIN)
        self.d2 = (problem.limit * (1 - LIMIT_MARGIN)) ** 2
        grid, free = problem.grid, problem.free
        # d(w, w' at the Gauss points)/d(control points): (N, 4, len(free)), per rad/s
        self.shape_derivatives = np.stack([grid.w1[:, free], grid.d1[:, free] / T,
                                           grid.w2[:, free], grid.d2[:, free] / T], axis=1)
        self.acc_matrix = self.acc_bound = None
        if problem.max_acc is not None:
            # w' = (diff @ c) / T, linear in y: |w'| <= max_acc as A y <= b
            A = problem.diff[:, problem.free] * problem.dw / T
            a0 = problem.diff @ problem.control_points(np.zeros(problem.n_free)) / T
            self.acc_matrix, self.acc_bound = np.r_[A, -A], problem.max_acc - np.r_[a0, -a0]

    def run(self, y) -> _Run:
        """The propagation of the shape y, kept for the next call.

        The model of a step just tried (:meth:`values`, then :meth:`model` when the step
        is taken) propagates it once.
        """
        p = self.problem
        c = p.control_points(y)
        if self._last is None or not np.array_equal(self._last[0], c):
            self._last = (c, _Run(p.batch, p.grid, self.T, c))
        return self._last[1]

    def values(self, y) -> np.ndarray:
        X = self.run(y).X
        whirl = self.problem.whirl.components(X[:, -1, :4]) / self.aim
        r2 = X[0, 1:, 0] ** 2 + X[0, 1:, 1] ** 2
        return np.concatenate([self.problem.whirl.squared(whirl), r2 / self.d2])

    def model(self, y) -> tuple[np.ndarray, np.ndarray, list]:
        """(values, gradients (k, n), Gauss-Newton curvature factors) of every ratio at y.

        Each ratio is a squared norm m |a(y)|^2 of components a smooth in y (scaled by
        the limit): its gradient is 2 m Re(a^H J) and its Gauss-Newton curvature
        2 m J^T J, given as the factor sqrt(2 m) J (real rows), J = da/dy from the
        kernel's sensitivities.
        """
        p = self.problem
        run = self.run(y)
        X = run.X
        nodes, ends = _sensitivities(run, p.batch, self.shape_derivatives)
        whirl = p.whirl
        a = whirl.components(X[:, -1, :4]) / self.aim          # (B, m)
        J = whirl.rows @ (ends * (p.dw / self.aim))            # (B, m, n)
        gradients = 2 * whirl.count[:, None] * np.einsum('bm,bmn->bn', np.conj(a), J).real
        factors = [math.sqrt(2 * m) * np.concatenate([Jb[:m].real, Jb[:m].imag])
                   for m, Jb in zip(whirl.count, J)]
        u, v = X[0, 1:, 0], X[0, 1:, 1]
        Ju, Jv = nodes[:, 0] * p.dw, nodes[:, 1] * p.dw
        values = np.concatenate([whirl.squared(a), (u * u + v * v) / self.d2])
        gradients = np.concatenate([gradients,
                                    2 * (u[:, None] * Ju + v[:, None] * Jv) / self.d2])
        factors.append(math.sqrt(2 / self.d2) * np.stack([Ju, Jv], axis=1))    # (N, 2, n)
        return values, gradients, factors


class _Whirl:
    """The whirl components of every band sample, padded to one array.

    ``rows`` (B, m, 4) complex, each sample's rows (:func:`_residual_rows`, the
    identically zero ones left out) then zero rows; ``count`` (B,) how many are its
    own; ``targets`` (B, 4): the static states at the target speed (m, m/s).
    """

    def __init__(self, rows: list, targets: list):
        self.count = np.array([len(r) for r in rows])
        self.rows = np.zeros((len(rows), int(self.count.max()), 4), dtype=complex)
        for b, r in enumerate(rows):
            self.rows[b, :len(r)] = r
        self.targets = np.array(targets)

    def components(self, ends: np.ndarray) -> np.ndarray:
        """The whirl components (m, complex) of the end states ``ends`` (B, 4): (B, m)."""
        return np.einsum('bmi,bi->bm', self.rows, ends - self.targets)

    def squared(self, components: np.ndarray) -> np.ndarray:
        """m_b sum_j |a_bj|^2 for every sample b (Cauchy-Schwarz: >= (sum_j |a_bj|)^2)."""
        return self.count * np.sum(components.real ** 2 + components.imag ** 2, axis=1)


def _hessian(weights: np.ndarray, factors: list) -> np.ndarray:
    """sum_i weights_i C_i^T C_i over the ratios (the last factor: all grid nodes)."""
    *residuals, nodes = factors
    B = len(residuals)
    H = sum((w * C.T @ C for w, C in zip(weights[:B], residuals) if w > 0),
            np.zeros((nodes.shape[-1],) * 2))
    w = weights[B:]
    if np.any(w > 0):
        H = H + np.einsum('k,kan,kam->nm', w, nodes, nodes)
    return H


def _minimax_step(g, G, H, damping, L, rhs):
    """One SQP step of min_y max_i g_i(y): (d, multipliers, predicted decrease) or None.

    The quadratic program min t + 1/2 d^T (H + damping I) d over (d, t) subject to
    g_i + G_i d <= t for every ratio and L d <= rhs, scaled by max g; H is the
    multiplier-weighted Gauss-Newton curvature of the ratios (the Lagrangian's), the
    damping a Levenberg-Marquardt trust region. The predicted decrease is
    max g - (max_i (g_i + G_i d) + 1/2 d^T H d).
    """
    m = float(g.max())
    n = G.shape[1]
    Q = np.zeros((n + 1, n + 1))
    Q[:n, :n] = (H + damping * np.eye(n)) / m
    Q[n, n] = 1e-2                              # strictly convex in t as well
    A = np.zeros((len(g) + len(L), n + 1))
    A[:len(g), :n], A[:len(g), n], A[len(g):, :n] = G / m, -1.0, L
    q = np.zeros(n + 1)
    q[n] = 1.0
    out = _quadratic_program(Q, q, A, np.concatenate([-g / m, rhs]))
    if out is None:
        return None
    x, multipliers = out
    d = x[:n]
    predicted = m - (float((g + G @ d).max()) + 0.5 * d @ H @ d)
    weights = np.maximum(multipliers[:len(g)], 0.0)
    return d, weights / max(weights.sum(), 1e-300), predicted


def _quadratic_program(Q, q, A, b):
    """The x minimising 1/2 x^T Q x + q^T x subject to A x <= b (Q positive definite).

    Returns (x, multipliers of the rows of A), or None if the constraints are
    incompatible. Least-distance form solved by non-negative least squares (Lawson and
    Hanson, Solving Least Squares Problems, ch. 23; what SLSQP does inside): with
    Q = L L^T and u = L^T x + L^-1 q, minimise |u| subject to G u >= h.
    """
    L = np.linalg.cholesky(Q)
    Lq = np.linalg.solve(L, q)
    AL = np.linalg.solve(L, A.T).T             # A L^-T
    G, h = -AL, -(b + AL @ Lq)
    E = np.concatenate([G.T, h[None, :]])
    f = np.zeros(len(q) + 1)
    f[-1] = 1.0
    lam = nnls(E, f, maxiter=50 * E.shape[1])[0]
    r = E @ lam - f
    if abs(r[-1]) < 1e-12:
        return None
    x = np.linalg.solve(L.T, -r[:-1] / r[-1] - Lq)
    return x, lam / (1.0 - h @ lam)


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
    request = {'params': dataclasses.asdict(params), 'omega_target': wf, 'omega_start': ws,
               'deflection_limit': limit, 'residual': residual, 'robust': robust,
               'max_angular_acceleration': max_acc}
    return plan_cache.cached_plan(request, lambda: _search(family))


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

    def minimax(self, T: float, c, clear: float = CLEARLY_FEASIBLE):
        """The minimax shape at duration T (s) from the shape ``c`` (None: Eq. 26's): (c, M).

        The solve stops once M <= ``clear`` (0: run to convergence).
        """
        problem = self.problem(T)
        y0 = problem.initial_shape() if c is None else problem.fit(c)
        y, m = problem.minimax(T, y0, clear)
        return problem.control_points(y), m

    def extrapolated(self, T: float, first, second) -> np.ndarray:
        """Control points at T on the line through two (duration, control points)."""
        problem = self.problem(T)
        (T1, c1), (T2, c2) = first, second
        y1, y2 = problem.fit(c1), problem.fit(c2)
        y = np.clip(y2 + (y2 - y1) * (T - T2) / (T2 - T1), *problem.bounds[0])
        return problem.control_points(y)

    def check(self, T: float, c):
        problem = self.problem(T)
        return problem.check(T, problem.fit(c))


class _Durations:
    """Minimax solves at durations k x DURATION_STEP, each warm-started from a shape solved.

    ``solve(k)`` returns M(k); the shapes are kept, and a solve starts from the shape of
    the nearest duration already solved (continuation), or from Eq. 26's for the first;
    ``solve(k, start=j)`` from the shape at j, ``solve(k, through=(i, j))`` from the
    line through the shapes at i and j (:meth:`_Family.extrapolated`). ``forget()``
    drops the values (not the shapes) when the family's grid or band samples change.
    """

    def __init__(self, family: _Family):
        self.family = family
        self.shapes: dict[int, np.ndarray] = {}
        self.values: dict[int, float] = {}

    def solve(self, k: int, start: int | None = None,
              through: tuple[int, int] | None = None) -> float:
        if k not in self.values:
            c0: np.ndarray | None
            if through is not None:
                (i, ci), (j, cj) = ((n, self.shapes[n]) for n in through)
                c0 = self.family.extrapolated(k * DURATION_STEP, (i * DURATION_STEP, ci),
                                              (j * DURATION_STEP, cj))
            else:
                if start is None:
                    start = min(self.shapes, key=lambda j: (abs(j - k), j), default=None)
                c0 = None if start is None else self.shapes[start]
            c, m = self.family.minimax(k * DURATION_STEP, c0)
            self.shapes[k], self.values[k] = c, m
        return self.values[k]

    def forget(self):
        self.values.clear()


def _search(family: _Family) -> SpinUpProfile:
    """The shortest duration k x DURATION_STEP whose minimax value M is <= 1, and its shape.

    M(T) (:meth:`_Problem.minimax`) is bracketed by factors of 1.6 from a first guess
    (with an acceleration bound, TRAPEZOID x the shortest duration it allows is tried
    before), then the bracket is narrowed down to one DURATION_STEP (:func:`_narrow`:
    bisection, and with an acceleration bound the secant of log M near the answer),
    each solve warm-started from the shape of the nearest duration solved or of the
    bracket's infeasible end (continuation). The plan is the shape at the shortest
    feasible duration, solved to convergence. The result is checked on finer grids;
    when the check fails, the optimisation grid is refined, or the band's worst
    frequency joins the optimised samples, and the search goes on from the bracket.
    """
    lower = abs(family.wf - family.ws) / family.max_acc if family.max_acc else 0.0
    T_max = max(MAX_PERIODS * family.period, 4.0 * lower)
    eps = family.eps
    # a first guess: two periods, or what resolving the band takes (~ 1 / (eps w0))
    first = family.period * max(2.0, 0.7 / eps if eps else 0.0)
    runs = _Durations(family)
    bad = math.floor(lower / DURATION_STEP)     # w' = 0 at both ends: lower itself fails
    good = _feasible_from(runs, max(math.ceil(max(first, 1.6 * lower) / DURATION_STEP),
                                    bad + 1), T_max,
                          math.ceil(max(first, TRAPEZOID * lower) / DURATION_STEP))
    bad = max([bad] + [k for k, m in runs.values.items() if m > 1.0 and k < good])
    for _ in range(8):
        bad, good = _narrow(runs, bad, good)
        T = good * DURATION_STEP
        c, _ = family.minimax(T, runs.shapes[good], clear=0.0)     # converged: the plan
        peak, nominal, band, worst = family.check(T, c)
        if peak <= family.limit and nominal <= family.residual and band <= family.residual:
            return SpinUpProfile(T, c, peak_deflection=peak, residual_amplitude=nominal,
                                 band_residual=band, robust=eps)
        coarse = peak > family.limit or nominal > family.residual
        if coarse and family.steps < MAX_STEPS_PER_KNOT:
            family.steps *= 2
        elif not coarse and worst not in family.scales(T):
            family.extra.append(worst)      # a cutting plane in the band
        else:       # the check failed at good with the finest settings: search above it
            bad = good
            good = _feasible_from(runs, math.ceil(good * 1.02) + 1, T_max)
            continue
        runs.forget()
        if runs.solve(good) > 1.0:
            bad = good
            good = _feasible_from(runs, math.ceil(good * 1.02) + 1, T_max)
    raise ValueError(f'no plan from {family.ws:g} to {family.wf:g} rad/s passed the final '
                     f'check on a finer grid (last tried {good * DURATION_STEP:g} s): the '
                     'constraints are too close to what the linear model can resolve')


def _narrow(runs: _Durations, bad: int, good: int) -> tuple[int, int]:
    """The bracket (bad, good), M(bad) > 1 >= M(good), narrowed to good = bad + 1.

    Bisection, each solve from the nearest shape solved (the bracket's infeasible end);
    with an acceleration bound, the secant of log M where it is close to linear. Once
    M(bad) <= SECANT_BELOW, the next duration is where the line through log M at the
    two longest infeasible durations solved, i and bad, crosses 0, rounded up, its solve
    started from the bracket's infeasible end, or from the line through the shapes at i
    and bad when the step beyond bad is a quarter of their distance or more (up to all
    of it). A secant step that finds its duration feasible is followed by the duration
    just below it (the answer when the secant was right). A bisection instead whenever
    the secant crosses 0 at or above ``good`` or the last two steps did not halve the
    bracket, so that it halves within any three steps: at most three times bisection's
    solves (over random decreasing M, cliffs and plateaus included: at most 1.33 and on
    average 0.77 times, test_planner).

    Without an acceleration bound, M near the answer is nearly flat (within a few
    per cent of 1 over tens of milliseconds) and its converged value depends on the
    shape a solve starts from by more than its distance from 1 (the minimax problem
    has local minima): reached by secant steps, Table 1's nominal plan came out 1 ms
    either side of bisection's answer and a rectangular rod's 1 ms longer, so
    those requests keep bisection, visiting the durations they always did. With the
    bound, M rises steeply below the answer and the secant steps reached bisection's
    answer on every request tried (18: Table 1's, steel, rig, rectangular, damped and
    heavy rods; spin-ups and spin-downs, nominal and robust; 0.2 to 1 rad/s^2).
    """
    secant = runs.family.max_acc is not None
    widths = [good - bad]
    landed = False          # the last step was a secant step, and found its k feasible
    while good - bad > 1:
        k, start, through, step = (good + bad) // 2, None, None, False
        below = sorted((j, m) for j, m in runs.values.items() if j <= bad and m > 1.0)[-2:]
        halving = len(widths) < 3 or 2 * widths[-1] <= widths[-3]
        if (secant and halving and len(below) == 2 and below[-1][0] == bad
                and below[-1][1] <= SECANT_BELOW):
            (i, mi), (_, mb) = below
            fi, fb = math.log(mi), math.log(mb)
            x = bad + fb * (bad - i) / (fi - fb) if fi > fb else math.inf
            root = math.ceil(x - 1e-9) if x < good else good
            if root < good:
                k, start, step = max(root, bad + 1), bad, True
            elif landed:
                k, start = good - 1, bad
            if step and bad - i <= 4 * (k - bad) <= 4 * (bad - i):
                through = (i, bad)
        if runs.solve(k, start=start, through=through) <= 1.0:
            good, landed = k, step
        else:
            bad, landed = k, False
        widths.append(good - bad)
    return bad, good


def _feasible_from(runs: _Durations, k: int, T_max: float, before: int = 0) -> int:
    """The first k going up from k by factors of 1.6 whose minimax value is <= 1.

    ``before``, when between the longest infeasible duration solved and k, is tried first.
    """
    low = max([0] + [j for j, m in runs.values.items() if m > 1.0])
    if low < before < k and runs.solve(before) <= 1.0:
        return before
    while k * DURATION_STEP <= T_max:
        if runs.solve(k) <= 1.0:
            return k
        k = math.ceil(1.6 * k)
    raise ValueError(_infeasible_message(runs.family, T_max))


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
