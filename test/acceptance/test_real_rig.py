"""A real rig (issue #18): gravity's axial load and the rod's own mass.

Every expected value here is computed in this file from closed forms or from
independent integrations (scipy's DOP853, Gauss quadrature of the shape integrals),
never taken from the package's own output. See docs/real_rig.md.
"""

import math

import numpy as np
import pytest
from reference import eq26
from scipy.integrate import solve_ivp
from scipy.optimize import brentq

from rotrod_core import Eq26Profile, RealTimeStepper, RodParams, simulate, simulate_batch
from rotrod_core.analysis.critical import critical_speed, step_response
from rotrod_core.analysis.modes import dynamic_frequencies, modal_analysis, static_deflection
from rotrod_core.live.engine import EngineConfig, SimulationEngine
from rotrod_core.model.equations import Coefficients, angular_momentum, energy

# Table 1
M_TIP, L_ROD, D_ROD, E_MOD, R0 = 0.3, 0.3, 0.003, 100e9, 0.1
I_AREA = math.pi * D_ROD**4 / 64
EI = E_MOD * I_AREA
A_SEC = math.pi * D_ROD**2 / 4
K0 = 3 * EI / L_ROD**3
STEEL = 7850.0
G = 9.81


def k_compression(P, EI=EI, length=L_ROD):
    """Exact lateral tip stiffness of a cantilever under an axial compressive tip load."""
    kappa = math.sqrt(P / EI)
    return P / (math.tan(kappa * length) / kappa - length)


def k_tension(P, EI=EI, length=L_ROD):
    """Exact lateral tip stiffness of a cantilever under an axial tensile tip load P > 0."""
    kappa = math.sqrt(P / EI)
    return P / (length - math.tanh(kappa * length) / kappa)


# the assumed mode shape and its integrals, by Gauss-Legendre quadrature (exact for
# these polynomials), not from the fractions 33/140 and 3/8
XI, WQ = np.polynomial.legendre.leggauss(12)
XI, WQ = 0.5 * (XI + 1.0), 0.5 * WQ
PHI = (3 * XI**2 - XI**3) / 2
DPHI = (6 * XI - 3 * XI**2) / 2          # d phi / d xi
INT_PHI2 = float(WQ @ PHI**2)
INT_PHI = float(WQ @ PHI)
INT_WEIGHT = float(WQ @ ((1 - XI) * DPHI**2))


def rod_mass(density=STEEL):
    return density * A_SEC * L_ROD


# --------------------------------------------------------------- stiffness
@pytest.mark.parametrize('g', [0.5, 2.0, 5.0, 9.81, 20.0, 30.0, 36.0])
def test_standing_rod_stiffness_is_the_exact_compression_formula(g):
    p = RodParams(gravity=g)
    P = M_TIP * g
    assert P < math.pi**2 * EI / (4 * L_ROD**2)
    assert p.stiffness == pytest.approx(k_compression(P), rel=1e-9)
    assert p.natural_frequency == pytest.approx(math.sqrt(k_compression(P) / M_TIP), rel=1e-9)


@pytest.mark.parametrize('g', [-0.5, -2.0, -9.81, -100.0, -1e4])
def test_hanging_rod_stiffness_is_the_exact_tension_formula(g):
    p = RodParams(gravity=g)
    assert p.stiffness == pytest.approx(k_tension(M_TIP * -g), rel=1e-9)
    assert p.stiffness > K0


@pytest.mark.parametrize('g', [1e-12, -1e-12, 1e-7, -1e-7, 1e-4, -1e-4])
def test_tiny_load_gives_the_series_limit(g):
    # k = 3EI/l^3 - (6/5) P/l + (P^2 l / EI) (2/175)... ; the first two terms suffice
    # to 1e-13 here, where the closed forms would cancel catastrophically
    P = M_TIP * g
    y = P * L_ROD**2 / EI
    expected = K0 * (1 - 0.4 * y + (4 / 25 - 17 / 105) * y * y)
    assert RodParams(gravity=g).stiffness == pytest.approx(expected, rel=1e-13)


def test_stiffness_is_continuous_across_the_series_switch():
    # the package changes from series to closed form at some small load; sweep
    # loads across a wide range and compare with a high-order series / closed form
    for y in np.geomspace(1e-3, 2.0, 60):
        g = y * EI / L_ROD**2 / M_TIP
        for sign in (1, -1):
            P = M_TIP * g
            exact = k_compression(P) if sign > 0 else k_tension(P)
            if y < 0.05:         # closed forms lose digits; the series is exact enough
                s = sign * y
                c = [1, 2 / 5, 17 / 105, 62 / 945, 1382 / 51975, 21844 / 2027025,
                     929569 / 212837625, 6404582 / 3618239625]   # 3 x tan(x)/x's
                exact = K0 / sum(ci * s**i for i, ci in enumerate(c))
            got = RodParams(gravity=sign * g).stiffness
            assert got == pytest.approx(exact, rel=1e-11), (y, sign)


def test_rectangular_section_each_direction_has_its_own_EI():
    b, h = 0.004, 0.003
    p = RodParams(section='rectangular', section_width=b, section_thickness=h, gravity=G)
    ei1, ei2 = E_MOD * h * b**3 / 12, E_MOD * b * h**3 / 12
    P = M_TIP * G
    assert p.stiffness_radial == pytest.approx(k_compression(P, ei1), rel=1e-9)
    assert p.stiffness_tangential == pytest.approx(k_compression(P, ei2), rel=1e-9)
    assert p.buckling_load == pytest.approx(math.pi**2 * ei2 / (4 * L_ROD**2), rel=1e-12)
    hanging = p.replace(gravity=-G)
    assert hanging.stiffness_tangential == pytest.approx(k_tension(P, ei2), rel=1e-9)


def test_table1_numbers():
    p = RodParams(gravity=G)
    assert round(float(p.tip_load), 2) == 2.94
    assert round(float(p.buckling_load), 1) == 10.9
    assert round(float(p.tip_load / p.buckling_load), 2) == 0.27
    assert round(float(p.stiffness), 2) == 32.37
    assert round(float(p.natural_frequency), 3) == 10.387
    assert round(critical_speed(p, 3e-3), 3) == 1.773
    assert round(critical_speed(RodParams(), 3e-3), 3) == 2.071
    assert round(float(RodParams().natural_frequency), 3) == 12.135


def test_defaults_are_the_paper_exactly():
    p = RodParams()
    assert p.gravity == 0.0 and p.rod_density == 0.0
    assert p.stiffness == 3 * E_MOD * (math.pi * D_ROD**4 / 64.0) / L_ROD**3
    assert round(float(p.stiffness), 6) == 44.178647
    assert p.modal_mass == M_TIP and p.eccentric_mass == M_TIP and p.rod_mass == 0.0
    co = Coefficients.from_params(p)
    assert co.modal_mass == M_TIP and co.load_radius == R0
    assert co.rotor_inertia == p.hub_inertia
    assert p.second_mode_frequency == math.inf


def test_arrays_batches_item_and_replace():
    g = np.array([-9.81, 0.0, 9.81, 20.0])
    rho = np.array([[0.0], [STEEL]])
    p = RodParams(gravity=g, rod_density=rho)
    assert p.shape == (2, 4)
    k = p.stiffness
    for i in range(2):
        for j in range(4):
            one = p.item((i, j))
            assert one.gravity == g[j] and one.rod_density == rho[i, 0]
            assert one.stiffness == pytest.approx(k[i, j], rel=1e-15)
    assert p.replace(gravity=0.0).stiffness == RodParams().stiffness
    modes = p.second_mode_frequency
    assert np.all(np.isinf(modes[0])) and np.all(np.isfinite(modes[1]))


# --------------------------------------------------------------- refusals
@pytest.mark.parametrize('g', [37.0, 40.0, 1e6])
def test_buckling_is_refused(g):
    p_cr = math.pi**2 * EI / (4 * L_ROD**2)
    assert M_TIP * g >= p_cr
    with pytest.raises(ValueError, match=r'gravity.*buckling load.*10\.9'):
        RodParams(gravity=g)


def test_buckling_exactly_at_the_load_is_refused():
    g = math.pi**2 * EI / (4 * L_ROD**2) / M_TIP
    while M_TIP * g < math.pi**2 * EI / (4 * L_ROD**2):
        g = math.nextafter(g, math.inf)
    with pytest.raises(ValueError, match='buckling'):
        RodParams(gravity=g)


def test_a_heavy_rod_buckling_under_its_own_weight_is_refused():
    # a long thin rod: (3/8) rho A g > k(P)
    with pytest.raises(ValueError, match=r'rod_density.*buckle'):
        RodParams(rod_length=2.0, mass=1e-3, gravity=G, rod_density=STEEL,
                  rod_diameter=0.003)


@pytest.mark.parametrize('name', ['gravity', 'rod_density'])
@pytest.mark.parametrize('value', [math.nan, math.inf, -math.inf, 'x', None])
def test_non_finite_values_are_refused_naming_the_field(name, value):
    with pytest.raises(ValueError, match=rf'RodParams\.{name}\b'):
        RodParams(**{name: value})


def test_negative_density_is_refused():
    with pytest.raises(ValueError, match=r'RodParams\.rod_density must be a finite number >= 0'):
        RodParams(rod_density=-1.0)


# --------------------------------------------------------------- Eq. 28, static, critical
@pytest.mark.parametrize('g, rho', [(G, 0.0), (-G, 0.0), (G, STEEL), (0.0, STEEL)])
def test_eq28_and_modal_frequencies_with_the_effective_stiffness_and_mass(g, rho):
    p = RodParams(gravity=g, rod_density=rho)
    P = M_TIP * abs(g)
    k = K0 if g == 0 else (k_compression(P) if g > 0 else k_tension(P))
    k -= INT_WEIGHT * rho * A_SEC * g
    mass = M_TIP + INT_PHI2 * rod_mass(rho)
    w0 = math.sqrt(k / mass)
    assert p.natural_frequency == pytest.approx(w0, rel=1e-9)
    w = np.array([0.0, 0.5, 2.0, 9.0, 15.0])
    f1, f2 = dynamic_frequencies(p, w)
    np.testing.assert_allclose(f1, np.abs(w0 - w) / (2 * math.pi), rtol=1e-9)
    np.testing.assert_allclose(f2, (w0 + w) / (2 * math.pi), rtol=1e-9)
    for wi in (0.5, 2.0, 9.0):
        got = modal_analysis(p, wi).frequencies
        assert got == pytest.approx(sorted([abs(w0 - wi) / (2 * math.pi),
                                            (w0 + wi) / (2 * math.pi)]), rel=1e-9)


@pytest.mark.parametrize('g, rho', [(G, 0.0), (G, STEEL), (-G, STEEL)])
def test_static_deflection_and_critical_speeds_closed_forms(g, rho):
    p = RodParams(gravity=g, rod_density=rho)
    P = M_TIP * abs(g)
    k = (k_compression(P) if g > 0 else k_tension(P)) - INT_WEIGHT * rho * A_SEC * g
    mass = M_TIP + INT_PHI2 * rod_mass(rho)
    m_ecc = M_TIP + INT_PHI * rod_mass(rho)
    w = np.array([0.5, 1.0, 2.0])
    np.testing.assert_allclose(static_deflection(p, w)[0],
                               m_ecc * w**2 * R0 / (k - mass * w**2), rtol=1e-9)
    delta = 3e-3
    w_qs = critical_speed(p, delta)
    # u_s(w_cr) = delta, solved independently
    u_s = lambda x: m_ecc * x**2 * R0 / (k - mass * x**2) - delta  # noqa: E731
    assert w_qs == pytest.approx(brentq(u_s, 1e-6, math.sqrt(k / mass) * (1 - 1e-12),
                                        xtol=1e-14), rel=1e-9)
    # step start: the peak approaches 2 u_s; impulsive: re w / (w0 - w) = delta
    w0 = math.sqrt(k / mass)
    re = m_ecc / mass * R0
    assert critical_speed(p, delta, 'step') == pytest.approx(
        w0 * math.sqrt(delta / (delta + 2 * re)), rel=1e-12)
    assert critical_speed(p, delta, 'impulsive') == pytest.approx(w0 * delta / (re + delta),
                                                                  rel=1e-12)
    # Eq. 29 against its definition with the effective coefficients
    t = np.linspace(0, 5, 11)
    ws = 2.0
    w1, w2 = w0 - ws, w0 + ws
    z = (ws**2 * re / (2 * w0)) * ((1 - np.exp(1j * w1 * t)) / w1
                                   + (1 - np.exp(-1j * w2 * t)) / w2)
    np.testing.assert_allclose(step_response(p, ws, t), z, rtol=1e-12, atol=1e-18)


# --------------------------------------------------------------- integrations
def ritz_rhs(k, mass, m_ecc, r0=R0):
    """Rotating-frame Lagrange equations of rod + tip mass, one mode (derived here):

    M (u'' - 2 w v' - w' v - w^2 u) + k u = Me w^2 r0
    M (v'' + 2 w u' + w' u - w^2 v) + k v = -Me w' r0
    """
    def f(t, y):
        u, v, du, dv = y
        w, wd = eq26(t)
        ddu = 2 * w * dv + wd * v + w * w * u + (m_ecc * w * w * r0 - k * u) / mass
        ddv = -2 * w * du - wd * u + w * w * v + (-m_ecc * wd * r0 - k * v) / mass
        return [du, dv, ddu, ddv]
    return f


def reference_eq26(k, mass, m_ecc, t):
    """DOP853 at rtol 1e-12, piecewise over the profile's joints."""
    y = [0.0, 0.0, 0.0, 0.0]
    out = np.empty((len(t), 4))
    out[0] = y
    for a, b in ((0, 15), (15, 20), (20, 35), (35, 40)):
        sel = (t > a) & (t <= b)
        sol = solve_ivp(ritz_rhs(k, mass, m_ecc), (a, b), y, method='DOP853', rtol=1e-12,
                        atol=1e-16, t_eval=t[sel])
        assert sol.success
        out[sel] = sol.y.T
        y = sol.y[:, -1]
    return out


@pytest.mark.parametrize('rho', [0.0, STEEL])
def test_eq26_run_matches_an_independent_integration(rho):
    p = RodParams(gravity=G, rod_density=rho)
    run = simulate(p, Eq26Profile(), 40.0, dt=1e-3)
    k = k_compression(M_TIP * G) - INT_WEIGHT * rho * A_SEC * G
    ref = reference_eq26(k, M_TIP + INT_PHI2 * rod_mass(rho), M_TIP + INT_PHI * rod_mass(rho),
                         run.t[::50])
    scale = np.max(np.abs(ref[:, 0]))
    assert np.max(np.abs(run.u[::50] - ref[:, 0])) < 1e-11 * scale
    assert np.max(np.abs(run.v[::50] - ref[:, 1])) < 1e-11 * scale
    # gravity softens the rod: more deflection at 2 rad/s than the paper's 2.79 mm
    # (static: m w^2 r0 / (k - m w^2))
    assert np.max(run.u) > 3.5e-3


def kinetic_and_momentum(J, rho, r0, state):
    """Kinetic energy and angular momentum of hub, tip mass and rod, by quadrature."""
    u, v, du, dv, _, w = (np.asarray(c, dtype=float)[..., None] for c in state)
    mu = rho * A_SEC * L_ROD
    # every point of the rod (weights WQ, shape PHI) and the tip mass (shape 1)
    pts = [(PHI, mu * WQ), (np.ones(1), np.array([M_TIP]))]
    T = 0.5 * J * w[..., 0] ** 2
    L = J * w[..., 0]
    for shape, dm in pts:
        x, y = r0 + shape * u, shape * v
        vx, vy = shape * du - w * y, shape * dv + w * x      # inertial velocity, rotating axes
        T = T + 0.5 * np.sum(dm * (vx * vx + vy * vy), axis=-1)
        L = L + np.sum(dm * (x * vy - y * vx), axis=-1)
    return T, L


def test_torque_drive_with_rod_mass_conserves_energy_and_angular_momentum():
    J, rho = 2e-3, STEEL
    p = RodParams(gravity=G, rod_density=rho, hub_inertia=J)
    init = {'omega': 2.0, 'u': 2e-3, 'dv': 0.02}
    run = simulate(p, torque=0.0, t_end=20.0, dt=1e-3, initial=init)
    k = k_compression(M_TIP * G) - INT_WEIGHT * rho * A_SEC * G
    T, L = kinetic_and_momentum(J, rho, R0, run.states)
    E = T + 0.5 * k * (run.u**2 + run.v**2)
    assert np.max(np.abs(E - E[0])) / E[0] < 1e-10
    assert np.max(np.abs(L - L[0])) / L[0] < 1e-10
    # the package's invariants are the same functions
    np.testing.assert_allclose(run.energy(), E, rtol=1e-13)
    np.testing.assert_allclose(run.angular_momentum(), L, rtol=1e-13)
    # the test has teeth: the rotation and the vibration exchange energy, and the
    # massless-rod invariants (tip mass only) are far from constant
    assert np.ptp(run.omega) > 1e-3
    T0, L0 = kinetic_and_momentum(J, 0.0, R0, run.states)
    assert np.ptp(L0) / L0[0] > 1e-4


def test_stepper_and_batch_with_rod_mass_conserve_angular_momentum():
    p = RodParams(gravity=G, rod_density=STEEL, hub_inertia=2e-3)
    init = {'omega': 2.0, 'u': 2e-3}
    st = RealTimeStepper(p, dt=1e-3, initial=init)
    L0 = st.angular_momentum()
    for _ in range(3000):
        st.step_torque(0.0)
    assert abs(st.angular_momentum() - L0) / L0 < 1e-11
    b = simulate_batch(p.replace(hub_inertia=np.array([2e-3, 1e-2])), torque=0.0, t_end=3.0,
                       initial=init)
    assert b.final.omega[0] == pytest.approx(st.state.omega, rel=1e-12)
    assert b.final.u[0] == pytest.approx(st.state.u, rel=1e-9)


def test_velocity_drive_torque_is_the_rate_of_the_angular_momentum():
    J = 0.05
    p = RodParams(gravity=G, rod_density=STEEL, hub_inertia=J)
    run = simulate(p, Eq26Profile(), 40.0, dt=1e-3)
    _, L = kinetic_and_momentum(J, STEEL, R0, run.states)
    dL = np.gradient(L, run.t, edge_order=2)
    interior = slice(2, -2)
    scale = np.max(np.abs(run.torque))
    assert np.max(np.abs(run.torque - dL)[interior]) < 1e-5 * scale


def test_velocity_drive_rod_mass_without_gravity_matches_ritz_integration():
    p = RodParams(rod_density=STEEL, eccentricity=0.2)
    run = simulate(p, Eq26Profile(), 40.0, dt=1e-3)
    mass, m_ecc = M_TIP + INT_PHI2 * rod_mass(), M_TIP + INT_PHI * rod_mass()
    t = run.t[::100]
    y = [0.0, 0.0, 0.0, 0.0]
    out = [y]
    for a, b in ((0, 15), (15, 20), (20, 35), (35, 40)):
        sel = (t > a) & (t <= b)
        sol = solve_ivp(ritz_rhs(K0, mass, m_ecc, 0.2), (a, b), y, method='DOP853',
                        rtol=1e-12, atol=1e-16, t_eval=t[sel])
        out.extend(sol.y.T)
        y = sol.y[:, -1]
    ref = np.array(out)
    scale = np.max(np.abs(ref[:, 0]))
    assert np.max(np.abs(run.u[::100] - ref[:, 0])) < 1e-11 * scale
    assert np.max(np.abs(run.v[::100] - ref[:, 1])) < 1e-11 * scale


# --------------------------------------------------------------- the next mode
def cantilever_tip_mass_roots(ratio, count):
    """Roots beta of 1 + cos b cosh b + ratio b (cos b sinh b - sin b cosh b) = 0."""
    f = lambda b: (1 + math.cos(b) * math.cosh(b)  # noqa: E731
                   + ratio * b * (math.cos(b) * math.sinh(b) - math.sin(b) * math.cosh(b)))
    grid = np.linspace(1e-3, 15, 30001)
    vals = [f(b) for b in grid]
    roots = [brentq(f, grid[i], grid[i + 1], xtol=1e-15)
             for i in range(len(grid) - 1) if vals[i] * vals[i + 1] < 0]
    return roots[:count]


@pytest.mark.parametrize('rho', [STEEL, 2700.0, 100.0])
def test_bending_frequencies_match_the_tip_mass_cantilever_equation(rho):
    p = RodParams(rod_density=rho)
    mu = rho * A_SEC
    betas = cantilever_tip_mass_roots(M_TIP / (mu * L_ROD), 3)
    exact = [b * b * math.sqrt(EI / (mu * L_ROD**4)) for b in betas]
    got = p.bending_frequencies(count=3)
    assert got[0] == pytest.approx(exact[0], rel=1e-9)
    assert got[1] == pytest.approx(exact[1], rel=1e-8)
    assert got[2] == pytest.approx(exact[2], rel=1e-4)
    assert p.second_mode_frequency == pytest.approx(exact[1], rel=1e-8)
    # the one-mode model's frequency is close to the exact first mode
    assert p.natural_frequency == pytest.approx(exact[0], rel=2e-3)


def test_massless_rod_has_one_mode_and_the_ritz_tip_stiffness_is_the_exact_one():
    for g in (G, -G):
        p = RodParams(gravity=g)
        f = p.bending_frequencies(count=3)
        assert np.all(np.isinf(f[1:])) and p.second_mode_frequency == math.inf
        # the many-term Ritz tip stiffness under the axial load is the exact one
        k = k_compression(M_TIP * G) if g > 0 else k_tension(M_TIP * G)
        assert f[0] == pytest.approx(math.sqrt(k / M_TIP), rel=1e-9)


def test_gravity_lowers_the_second_mode_a_little():
    up, flat = RodParams(gravity=G, rod_density=STEEL), RodParams(rod_density=STEEL)
    assert up.second_mode_frequency < flat.second_mode_frequency
    assert up.second_mode_frequency > 0.95 * flat.second_mode_frequency
    assert RodParams(gravity=-G, rod_density=STEEL).second_mode_frequency > \
        flat.second_mode_frequency


# --------------------------------------------------------------- consumers
def test_engine_reports_the_softened_critical_speed():
    engine = SimulationEngine(EngineConfig(params=RodParams(gravity=G)))
    assert round(engine.critical_speeds['deflection_limit'], 3) == 1.773
    assert engine.critical_speeds['radial_natural_frequency'] == pytest.approx(
        math.sqrt(k_compression(M_TIP * G) / M_TIP), rel=1e-9)


def test_cli_takes_gravity_and_rod_density(capsys):
    from rotrod_core.cli import PARAM_FIELDS, UNITS, main
    assert {'gravity', 'rod_density'} <= set(PARAM_FIELDS)
    assert UNITS['gravity'] == 'm/s^2' and UNITS['rod_density'] == 'kg/m^3'
    assert main(['critical-speed', '--limit', '0.003', '--gravity', '9.81']) == 0
    assert '1.772' in capsys.readouterr().out
    assert main(['frequencies', '--omega', '0', '--gravity', '40']) == 2
    assert 'buckling' in capsys.readouterr().err


def test_energy_function_is_the_lagrangian_energy_for_any_state():
    p = RodParams(gravity=-G, rod_density=STEEL, hub_inertia=0.03, eccentricity=0.15)
    co = Coefficients.from_params(p)
    rng = np.random.default_rng(1)
    s = (rng.normal(0, 1e-3, 50), rng.normal(0, 1e-3, 50), rng.normal(0, 1e-2, 50),
         rng.normal(0, 1e-2, 50), np.zeros(50), rng.normal(0, 3, 50))
    T, L = kinetic_and_momentum(0.03, STEEL, 0.15, s)
    k = k_tension(M_TIP * G) + INT_WEIGHT * STEEL * A_SEC * G
    np.testing.assert_allclose(energy(co, s), T + 0.5 * k * (s[0]**2 + s[1]**2), rtol=1e-12)
    np.testing.assert_allclose(angular_momentum(co, s), L, rtol=1e-12)


def test_the_reproduction_report_puts_the_real_rig_beside_the_paper():
    from rotrod_core.reporting import report
    from rotrod_core.reporting.rig_comparison import real_rig, summarize
    paper_rig = RodParams()
    rig = real_rig(paper_rig)
    assert (rig.gravity, rig.rod_density) == (G, STEEL)
    rows = [summarize(t, p, Eq26Profile(), 40.0, 1e-3, 3e-3)
            for t, p in (('paper', paper_rig), ('rig', rig))]
    # written out here: the exact tip-load stiffness, the rod's weight as a Rayleigh
    # geometric stiffness, one-mode Rayleigh-Ritz masses (docs/real_rig.md)
    area = math.pi * 0.003**2 / 4
    ei = 100e9 * math.pi * 0.003**4 / 64
    kappa = math.sqrt(0.3 * G / ei)
    k = 0.3 * G / (math.tan(kappa * 0.3) / kappa - 0.3) - 3 / 8 * STEEL * area * G
    modal = 0.3 + 33 / 140 * STEEL * area * 0.3
    load_radius = 0.1 * (0.3 + 3 / 8 * STEEL * area * 0.3) / modal
    w0 = math.sqrt(k / modal)
    assert rows[1].stiffness == pytest.approx(k, rel=1e-9)
    assert rows[1].natural_frequency == pytest.approx(w0, rel=1e-9)
    assert rows[1].critical_speed == pytest.approx(w0 * math.sqrt(3e-3 / (3e-3 + load_radius)),
                                                   rel=1e-9)
    assert rows[1].buckling_fraction == pytest.approx(0.3 * G / (math.pi**2 * ei / 0.36),
                                                      rel=1e-9)
    assert rows[0].critical_speed == pytest.approx(2.0710357, rel=1e-7)
    # the Eq. 26 hold at 2 rad/s sits at the static deflection (plus a sub-um whirl)
    us = (0.3 + 3 / 8 * STEEL * area * 0.3) * 4 * 0.1 / (k - modal * 4)
    assert rows[1].peak_deflection == pytest.approx(us, rel=1e-3)
    text = report.real_rig_table(rows, 3e-3)
    assert f'| {w0:.4f} |' in text and f'| {k:.4f} |' in text
