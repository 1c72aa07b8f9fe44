"""The one propagation kernel: its system against the equations written from docs/model.md,
its derivatives against closed forms, and one kernel behind simulate, simulate_batch, the
planner and identification (they agree to 1e-12 m on shared cases because they run the
same code)."""

import math

import numpy as np
import pytest
from scipy.linalg import expm

from rotrod_core import RodParams, SpinUpProfile, simulate, simulate_batch
from rotrod_core.command import planner
from rotrod_core.command.profiles import spin_up_knots
from rotrod_core.estimation import identify
from rotrod_core.model import propagation
from rotrod_core.model.equations import Coefficients

CASES = {
    'rectangular, damped': RodParams(section='rectangular', section_width=0.004,
                                     section_thickness=0.003, damping_ratio=0.02),
    'steel rod under gravity, damped': RodParams(rod_density=7850.0, gravity=9.81,
                                                 damping_ratio=0.01),
    'rectangular steel rod under gravity': RodParams(
        section='rectangular', section_width=0.004, section_thickness=0.003,
        rod_density=7850.0, gravity=9.81, damping_ratio=0.005),
}
ISOTROPIC = {k: v for k, v in CASES.items() if not k.startswith('rectangular')}


def written_out(p, w, wd):
    """The augmented 5x5 matrix written from docs/model.md (rod mass: M, Me, re)."""
    area = (p.section_width * p.section_thickness if p.section == 'rectangular'
            else math.pi * p.rod_diameter**2 / 4)
    rod = p.rod_density * area * p.rod_length
    M = p.mass + 33 / 140 * rod
    re = p.eccentricity * (p.mass + 3 / 8 * rod) / M
    k1, k2 = float(p.stiffness_radial), float(p.stiffness_tangential)
    c1 = 2 * p.damping_ratio * math.sqrt(k1 * M)
    c2 = 2 * p.damping_ratio * math.sqrt(k2 * M)
    return np.array([[0, 0, 1, 0, 0], [0, 0, 0, 1, 0],
                     [w * w - k1 / M, wd, -c1 / M, 2 * w, w * w * re],
                     [-wd, w * w - k2 / M, -2 * w, -c2 / M, -wd * re],
                     [0, 0, 0, 0, 0]], float)


@pytest.mark.parametrize('name', CASES)
def test_the_system_is_the_equations_of_docs_model(name):
    p = CASES[name]
    co = Coefficients.from_params(p)
    for w, wd in ((0.0, 0.0), (1.7, -0.4), (2.5, 3.0)):
        A = propagation.system_matrix(co, w, wd)
        assert np.allclose(A, written_out(p, w, wd), rtol=1e-14, atol=1e-14)


@pytest.mark.parametrize('name', CASES)
def test_derivatives_are_the_closed_forms(name):
    p = CASES[name]
    co = Coefficients.from_params(p)
    w = np.array([0.0, 0.6, 2.5])
    wd = np.array([1.0, -0.3, 0.0])
    dw, dwd = propagation.system_matrix_derivatives(co, w, wd)
    re = float(co.load_radius)
    for i in range(3):
        # d/dw: 2w on the stiffness diagonal, +-2 on the Coriolis terms, 2 w re forcing
        want = np.zeros((5, 5))
        want[2, 0] = want[3, 1] = 2 * w[i]
        want[2, 3], want[3, 2], want[2, 4] = 2.0, -2.0, 2 * w[i] * re
        assert np.array_equal(dw[i], want)
        want = np.zeros((5, 5))
        want[2, 1], want[3, 0], want[3, 4] = 1.0, -1.0, -re
        assert np.array_equal(dwd[i], want)


@pytest.mark.parametrize('name', ISOTROPIC)
def test_the_complex_form_is_the_real_one(name):
    co = Coefficients.from_params(ISOTROPIC[name])
    w, wd = np.array([0.0, 1.3]), np.array([0.5, -2.0])
    A = propagation.system_matrix(co, w, wd)
    _, one, x10, x11, _, b1 = propagation.complex_system(co, w, wd)
    assert one == 1.0
    assert np.allclose(x10, A[:, 2, 0] + 1j * A[:, 3, 0], rtol=1e-15, atol=0)
    assert np.allclose(x11, A[:, 2, 2] + 1j * A[:, 3, 2], rtol=1e-15, atol=0)
    assert np.allclose(b1, A[:, 2, 4] + 1j * A[:, 3, 4], rtol=1e-15, atol=0)
    # complex-linear: v and v' act as i times u and u'
    assert np.allclose(A[:, 2, 1] + 1j * A[:, 3, 1], 1j * x10, rtol=1e-15, atol=1e-15)
    assert np.allclose(A[:, 2, 3] + 1j * A[:, 3, 3], 1j * x11, rtol=1e-15, atol=1e-15)
    # derivatives by the identified coefficients: -1 in x10 (w0^2), -1 in x11 (g),
    # w^2 - i w' in b1 (the load radius)
    da = propagation.complex_system_derivative(co, 'natural_frequency_squared', w, wd)
    dg = propagation.complex_system_derivative(co, 'damping_rate', w, wd)
    dr = propagation.complex_system_derivative(co, 'load_radius', w, wd)
    assert np.all(np.asarray(da[2]) == -1) and np.all(np.asarray(da[3]) == 0)
    assert np.all(np.asarray(dg[3]) == -1) and np.all(np.asarray(dg[2]) == 0)
    assert np.allclose(dr[5], w * w - 1j * wd, rtol=1e-15, atol=0)
    with pytest.raises(ValueError, match='name must be one of'):
        propagation.complex_system_derivative(co, 'stiffness', w, wd)


def test_the_features_rebuild_the_system():
    p = RodParams(damping_ratio=np.array([0.0, 0.03]), eccentricity=np.array([0.1, 0.2]))
    co = Coefficients.from_params(p)
    F0, Fw, Fw2, Fwd = propagation.complex_system_features(co)
    for w, wd in ((0.3, 1.1), (2.0, -0.5)):
        X = propagation.complex_system(co, np.full(2, w), np.full(2, wd))
        rebuilt = propagation.lin((1.0, F0), (w, Fw), (w * w, Fw2), (wd, Fwd))
        for a, b in zip(X, rebuilt):
            if a is None:
                assert b is None
            else:
                assert np.allclose(a, b, rtol=1e-14, atol=1e-14)


def test_magnus_is_exact_for_a_constant_matrix_and_of_its_order():
    co = Coefficients.from_params(RodParams(damping_ratio=0.02))
    A = propagation.system_matrix(co, 1.5, 0.0)
    assert np.allclose(propagation.magnus4(0.01, A, A), 0.01 * A, rtol=1e-15, atol=0)
    assert np.allclose(propagation.magnus6(0.01, A, A, A), 0.01 * A, rtol=1e-15, atol=1e-18)

    # w = 2 t on [0, 1]: error of one step against a tight product of exponentials
    def A_at(t):
        return propagation.system_matrix(co, 2.0 * t, 2.0)

    fine = np.eye(5)
    for t in np.linspace(0, 0.1, 4001)[:-1] + 0.1 / 8000:
        fine = expm(A_at(t) * 0.1 / 4000) @ fine
    errors = {}
    for h in (0.1, 0.05):
        g2 = [A_at(x * h) for x in propagation.GAUSS2]
        g3 = [A_at(x * h) for x in propagation.GAUSS3]
        errors[h] = (expm(propagation.magnus4(h, *g2)), expm(propagation.magnus6(h, *g3)))
    step4 = np.linalg.norm(errors[0.1][0] - fine)
    assert step4 > 0      # the reference is not the method itself
    # the same matrices as complex affine tuples give the same exponent
    iso = Coefficients.from_params(RodParams(damping_ratio=0.02))
    w = [2.0 * x * 0.1 for x in propagation.GAUSS3]
    Xc = propagation.magnus6_complex_features(
        0.1, propagation.complex_system_features(iso), w, [2.0] * 3)
    R = propagation.magnus6(0.1, *[propagation.system_matrix(iso, 2.0 * x * 0.1, 2.0)
                                   for x in propagation.GAUSS3])
    assert Xc[2] == pytest.approx(R[2, 0] + 1j * R[3, 0], rel=1e-13)
    assert Xc[5] == pytest.approx(R[2, 4] + 1j * R[3, 4], rel=1e-13)


def test_magnus4_derivative_is_the_difference_quotient():
    co = Coefficients.from_params(RodParams(section='rectangular', section_width=0.004,
                                            section_thickness=0.003, damping_ratio=0.02))
    h, w1, w2, wd = 0.05, 1.0, 1.2, 0.7
    A1 = propagation.system_matrix(co, w1, wd)
    A2 = propagation.system_matrix(co, w2, wd)
    dA1, _ = propagation.system_matrix_derivatives(co, w1, wd)
    e = 1e-6
    fd = (propagation.magnus4(h, propagation.system_matrix(co, w1 + e, wd), A2)
          - propagation.magnus4(h, propagation.system_matrix(co, w1 - e, wd), A2)) / (2 * e)
    assert np.allclose(propagation.magnus4_derivative(h, A1, A2, dA1, 0.0), fd, atol=1e-9)
    fdh = (propagation.magnus4(h + e, A1, A2) - propagation.magnus4(h - e, A1, A2)) / (2 * e)
    assert np.allclose(propagation.magnus4_step_derivative(h, A1, A2), fdh, atol=1e-8)


@pytest.mark.parametrize('size', [0.3, 1.0])
def test_frechet_boole_is_the_exact_derivative_of_the_exponential(size):
    """d(exp(Omega) x) along E is the top-right block of exp([[Omega, E], [0, Omega]])
    applied to x (Van Loan); Boole's rule meets it to ~8 (|Omega|/4)^6 / 945 relative,
    for a step as long as the planner's (|Omega| up to ~1) and a shorter one: the whirl
    the planner drives to zero is ~1e-4 of the state, so its gradient needs it."""
    co = Coefficients.from_params(RodParams(damping_ratio=0.02))
    A1 = propagation.system_matrix(co, 1.0, 0.7)
    A2 = propagation.system_matrix(co, 1.4, 0.7)
    dA, _ = propagation.system_matrix_derivatives(co, 1.2, 0.7)
    h = size / np.linalg.norm(A1, 2)
    omega = propagation.magnus4(h, A1, A2)
    E = propagation.magnus4_derivative(h, A1, A2, dA, dA)
    x = np.array([1e-3, -2e-3, 0.01, 0.02, 1.0])
    block = np.zeros((10, 10))
    block[:5, :5] = block[5:, 5:] = omega
    block[:5, 5:] = E
    exact = expm(block)[:5, 5:] @ x
    boole = propagation.frechet_boole(expm(0.25 * omega), E[None], x)[0]
    bound = 8 * (np.linalg.norm(omega, 2) / 4) ** 6 / 945
    assert np.linalg.norm(boole - exact) <= 10 * bound * np.linalg.norm(exact) + 1e-15
    # and far closer than Simpson's rule on three points (the planner's rule before)
    half = expm(0.5 * omega)
    simpson = (half @ half @ E @ x + 4 * half @ E @ half @ x + E @ half @ half @ x) / 6
    assert np.linalg.norm(boole - exact) <= 1e-2 * np.linalg.norm(simpson - exact)


def test_affine_chain_is_the_sequential_product():
    rng = np.random.default_rng(3)
    phi = np.eye(4) + 0.05 * rng.standard_normal((2, 37, 4, 4))
    x0 = rng.standard_normal((2, 4))
    X = propagation.affine_chain(phi, x0)
    x = x0
    for k in range(37):
        x = np.einsum('bij,bj->bi', phi[:, k], x)
        assert np.allclose(X[:, k + 1], x, rtol=1e-12, atol=1e-14)
    work = propagation.ChainWorkspace()
    S = work.steps(37, 4, complex)
    S[:37] = phi[0]
    Y = propagation.affine_chain(S, np.eye(4, 2), rows=(0, 3), steps=37, work=work)
    assert np.allclose(Y, propagation.affine_chain(phi[0], np.eye(4, 2))[:, [0, 3]],
                       rtol=1e-13, atol=1e-15)
    with pytest.raises(ValueError, match='work'):
        propagation.affine_chain(phi[0], x0[0], work=work)


@pytest.mark.parametrize('steps', [1, 2, 36, 37, 114])
def test_adjoint_and_sensitivity_chains_are_their_step_by_step_recursions(steps):
    """The blocked chains equal the recursions they stand for, step by step, to rounding:
    lambda_k = lambda_k+1 phi_k from lambda_N = final, and S_k+1 = phi_k S_k + forcing_k
    from S_0 = 0 (with leading axes, and steps not a multiple of the block)."""
    rng = np.random.default_rng(5)
    phi = np.eye(5) + 0.05 * rng.standard_normal((3, steps, 5, 5))
    final = np.eye(4, 5)
    lam = propagation.adjoint_chain(phi, final)
    assert lam.shape == (3, steps + 1, 4, 5)
    row = np.broadcast_to(final, (3, 4, 5))
    assert np.array_equal(lam[:, steps], row)
    for k in range(steps - 1, -1, -1):
        row = row @ phi[:, k]
        assert np.allclose(lam[:, k], row, rtol=1e-12, atol=1e-14)
    forcing = rng.standard_normal((3, steps, 5, 7))
    S = propagation.sensitivity_chain(phi, forcing)
    assert S.shape == (3, steps + 1, 5, 7) and not S[:, 0].any()
    s = np.zeros((3, 5, 7))
    for k in range(steps):
        s = phi[:, k] @ s + forcing[:, k]
        assert np.allclose(S[:, k + 1], s, rtol=1e-12, atol=1e-13)
    assert np.allclose(propagation.sensitivity_chain(phi[0], forcing[0]), S[0],
                       rtol=1e-13, atol=1e-15)


# -- one kernel: the four consumers on shared cases --------------------------------------

def _spin_up():
    """A cubic-spline spin-up to 1.5 rad/s in 0.9 s (10 free control points, knots uniform)."""
    n_free = 10
    x = np.linspace(0, 1, n_free + 4)
    c = 1.5 * (x - np.sin(2 * np.pi * x) / (2 * np.pi))
    c[:2], c[-2:] = 0.0, 1.5
    return SpinUpProfile(0.9, c), n_free


@pytest.mark.parametrize('name', CASES)
def test_simulate_batch_and_the_planner_run_one_kernel(name):
    p = CASES[name]
    profile, n_free = _spin_up()
    steps = 12       # N = 132 steps: every 11th a knot
    grid = planner._Grid(n_free, steps)
    N = grid.n
    T = profile.duration
    run = simulate(p, profile, T, dt=T / N)
    sample = planner._sample(p, 1.0, 0.0, 1.5)
    X, _ = planner._propagate([sample], grid, T, profile.control_points)
    # the same Magnus steps on the same nodes: equal to rounding
    assert np.max(np.abs(X[0, :, 0] - run.u)) <= 1e-15
    assert np.max(np.abs(X[0, :, 1] - run.v)) <= 1e-15
    # a different integrator (sixth order, its own steps) at 1e-13 m: within 1e-12 m
    # (simulate on a grid 8x finer: its fourth-order error ~1e-11 m at T / N goes below)
    every = 11
    fine = simulate(p, profile, T, dt=T / (8 * N))
    batch = simulate_batch(p, profile, T, output_interval=every * T / N, tolerance=1e-13)
    assert np.allclose(batch.t, fine.t[::8 * every], rtol=0, atol=1e-12)
    assert np.max(np.abs(np.ravel(batch.u) - fine.u[::8 * every])) <= 1e-12
    assert np.max(np.abs(np.ravel(batch.v) - fine.v[::8 * every])) <= 1e-12
    assert np.max(np.abs(run.u)) > 1e-4      # a real deflection, not zeros


@pytest.mark.parametrize('name', ISOTROPIC)
def test_identification_runs_the_same_kernel(name):
    """identify's model output for the rig's own (w0^2, g, re) is simulate's run."""
    p = ISOTROPIC[name]
    profile, n_free = _spin_up()
    T = profile.duration
    N = (n_free + 1) * 12       # the knots are nodes: w is a cubic between samples
    assert np.allclose(spin_up_knots(n_free)[3:-3] * N % 1, 0, atol=1e-9)
    run = simulate(p, profile, T, dt=T / N)
    co = Coefficients.from_params(p)
    zeros = np.zeros_like(run.t)
    rec = identify._record(run.t, zeros, zeros, profile.omega(run.t), profile.omega_dot(run.t))
    basis, _, _ = identify._Problem(rec)._outputs(float(co.w1sq), float(co.g1))
    z = basis @ np.array([0.0, 0.0, float(co.load_radius)])
    assert np.max(np.abs(z - (run.u + 1j * run.v))) <= 1e-12
    assert np.max(np.abs(z)) > 1e-4
