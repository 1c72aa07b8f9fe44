"""simulate_batch in velocity drive: its default accuracy against a tight reference.

The reference integrates Eqs. 16/17 (docs/model.md) with k1, k2 and rotating damping,
written out here for a massless rod, by scipy's DOP853 at rtol 1e-12 piece by piece
between the joints of Eq. 26 (written in test/reference.py).
"""

import math

import numpy as np
import pytest
from reference import (
    W0,
    eq26,
    rk4_phase_bound,
    step_start,
)
from scipy.integrate import solve_ivp
from scipy.optimize import minimize_scalar

from rotrod_core import (
    ConstantProfile,
    Eq26Profile,
    RampProfile,
    RodParams,
    StepProfile,
    TableProfile,
    simulate,
    simulate_batch,
)
from rotrod_core.model.equations import Coefficients, State
from rotrod_core.model.propagation import system_matrix
from rotrod_core.offline import batch_velocity

T_END = 40.0
JOINTS = (0.0, 15.0, 20.0, 35.0, T_END)


def closed_form_coefficients(m, E, length, r0, zeta, b, h):
    """k1, k2 (3 E I / l^3 of a b x h section, b radial) and c1, c2 = 2 zeta sqrt(k m)."""
    k1 = 3 * E * (h * b**3 / 12) / length**3
    k2 = 3 * E * (b * h**3 / 12) / length**3
    return k1, k2, 2 * zeta * math.sqrt(k1 * m), 2 * zeta * math.sqrt(k2 * m)


def reference(m, k1, k2, c1, c2, r0, t_out):
    """(u, v) at t_out, (u, v, u', v') at T_END, and max |r| with its time, by DOP853."""
    def rhs(t, y):
        u, v, du, dv = y
        w, wd = eq26(t)
        return [du, dv,
                2 * w * dv + (w * w - k1 / m) * u + w * w * r0 + wd * v - c1 / m * du,
                -2 * w * du + (w * w - k2 / m) * v - wd * (r0 + u) - c2 / m * dv]

    y = np.zeros(4)
    u = np.empty(len(t_out))
    v = np.empty(len(t_out))
    peak, peak_t = 0.0, 0.0
    for a, b in zip(JOINTS[:-1], JOINTS[1:]):
        sol = solve_ivp(rhs, (a, b), y, method='DOP853', rtol=1e-12, atol=1e-16,
                        dense_output=True)
        inside = (t_out >= a) & (t_out <= b)
        u[inside], v[inside] = sol.sol(t_out[inside])[:2]
        scan = np.linspace(a, b, int((b - a) / 2e-3) + 2)
        r = np.hypot(*sol.sol(scan)[:2])
        k = int(np.argmax(r))
        best = minimize_scalar(lambda t, f=sol.sol: -np.hypot(*f(t)[:2]), method='bounded',
                               bounds=(scan[max(k - 1, 0)], scan[min(k + 1, len(scan) - 1)]),
                               options={'xatol': 1e-12})
        if -best.fun > peak:
            peak, peak_t = -best.fun, best.x
        y = sol.y[:, -1]
    return u, v, y, peak, peak_t


# (eccentricity m, damping ratio, section b x h m): undamped round rods (the exact
# inertial-frame solution), damped (complex Magnus), rectangular (real 5x5 Magnus)
SYSTEMS = [
    (0.2, 0.0, (0.003, 0.003)),
    (0.05, 0.0, (0.0036, 0.0036)),
    (0.2, 0.02, (0.003, 0.003)),
    (0.15, 0.0, (0.004, 0.003)),
    (0.1, 0.01, (0.0035, 0.0028)),
]


@pytest.fixture(scope='module')
def default_batch():
    r0 = np.array([s[0] for s in SYSTEMS])
    zeta = np.array([s[1] for s in SYSTEMS])
    b = np.array([s[2][0] for s in SYSTEMS])
    h = np.array([s[2][1] for s in SYSTEMS])
    p = RodParams(eccentricity=r0, damping_ratio=zeta, section='rectangular',
                  section_width=b, section_thickness=h)
    return simulate_batch(p, Eq26Profile(), T_END, output_interval=0.1)


def test_the_batch_uses_each_integrator(default_batch):
    kinds = default_batch.info['integrators']
    assert kinds['exact']['systems'] == 2
    assert kinds['magnus_complex']['systems'] == 1
    assert kinds['magnus_real']['systems'] == 2


@pytest.mark.parametrize('i', range(len(SYSTEMS)))
def test_default_batch_is_within_1e10_m_along_the_run_at_the_end_and_at_the_peak(
        default_batch, i):
    r0, zeta, (b, h) = SYSTEMS[i]
    k1, k2, c1, c2 = closed_form_coefficients(0.3, 100e9, 0.3, r0, zeta, b, h)
    u, v, end, peak, peak_t = reference(0.3, k1, k2, c1, c2, r0, default_batch.t)
    res = default_batch
    assert np.max(np.abs(res.u[i] - u)) <= 1e-10
    assert np.max(np.abs(res.v[i] - v)) <= 1e-10
    assert abs(res.final.u[i] - end[0]) <= 1e-10 and abs(res.final.v[i] - end[1]) <= 1e-10
    assert abs(res.final.du[i] - end[2]) <= 1e-8 and abs(res.final.dv[i] - end[3]) <= 1e-8
    assert abs(res.peak_deflection[i] - peak) <= 1e-10
    assert abs(res.peak_time[i] - peak_t) <= 1e-3


def test_batch_equals_simulate_per_system_with_initial_states_and_a_jump():
    rng = np.random.default_rng(7)
    n = 6
    p = RodParams(eccentricity=rng.uniform(0.02, 0.2, n),
                  rod_diameter=0.003 * (1 + 0.05 * rng.standard_normal(n)),
                  mass=0.3 * (1 + 0.05 * rng.standard_normal(n)),
                  damping_ratio=np.array([0, 0, 0, 0.01, 0.03, 0.0]))
    initial = {'u': rng.uniform(-1e-3, 1e-3, n), 'v': rng.uniform(-1e-3, 1e-3, n),
               'du': rng.uniform(-1e-2, 1e-2, n), 'dv': 0.0, 'theta': 0.5}
    profile = StepProfile(omega_target=3.0, t_step=1.5, omega_start=1.0)
    b = simulate_batch(p, profile, 6.0, initial=initial, output_interval=0.25)
    for i in range(n):
        one = simulate(p.item(i), profile, 6.0, dt=1e-3,
                       initial={k: float(np.broadcast_to(x, (n,))[i])
                                for k, x in initial.items()})
        at = np.searchsorted(one.t, b.t - 1e-9)
        assert np.max(np.abs(b.u[i] - one.u[at])) <= 1e-10
        assert np.max(np.abs(b.v[i] - one.v[at])) <= 1e-10
        assert b.final.u[i] == pytest.approx(one.u[-1], abs=1e-10)
        assert b.final.dv[i] == pytest.approx(one.dv[-1], abs=1e-8)
        assert b.final.theta[i] == pytest.approx(one.theta[-1], rel=1e-12)
        assert b.final.omega[i] == 3.0
        assert b.peak_deflection[i] >= np.max(np.hypot(one.u, one.v)) - 1e-10


def test_a_looser_tolerance_takes_longer_steps_and_keeps_its_bound():
    p = RodParams(damping_ratio=np.array([0.01, 0.02]), eccentricity=0.2,
                  section='rectangular', section_width=0.003, section_thickness=0.003)
    tight = simulate_batch(p, Eq26Profile(), T_END)
    loose = simulate_batch(p, Eq26Profile(), T_END, tolerance=1e-7, output_interval=0.5)
    info_t = tight.info['integrators']['magnus_complex']
    info_l = loose.info['integrators']['magnus_complex']
    assert info_l['step_s'] > 1.5 * info_t['step_s']
    k1, k2, c1, c2 = closed_form_coefficients(0.3, 100e9, 0.3, 0.2, 0.02, 0.003, 0.003)
    u, v, *_ = reference(0.3, k1, k2, c1, c2, 0.2, loose.t)
    assert np.max(np.abs(loose.u[1] - u)) <= 1e-7
    assert np.max(np.abs(loose.v[1] - v)) <= 1e-7


def test_the_complex_form_is_the_models_system_matrix():
    p = RodParams(damping_ratio=np.array([0.0, 0.05]), rod_density=np.array([0.0, 7850.0]))
    co = Coefficients.from_params(p)
    s, g, re = batch_velocity.complex_form(co)
    w, wd = 1.7, -0.3
    A = system_matrix(co, np.full(2, w), np.full(2, wd))
    for i in range(2):
        # z'' = -(g + 2iw) z' - (w0^2 - w^2 + iw') z + re (w^2 - iw'), z = u + iv
        def ddz(z, dz, i=i):
            return -(g[i] + 2j * w) * dz - (s[i] - w * w + 1j * wd) * z + re[i] * (
                w * w - 1j * wd)
        for unit in np.eye(4):
            x = np.append(unit, 1.0)
            real = A[i] @ x
            z, dz = unit[0] + 1j * unit[1], unit[2] + 1j * unit[3]
            assert ddz(z, dz) == pytest.approx(real[2] + 1j * real[3], rel=1e-14, abs=1e-14)


def test_the_complex_exponential_matches_the_real_one_where_it_falls_back():
    # near the critical speed (det N -> 0) and at critical damping (d -> 0)
    w0 = math.sqrt(RodParams().stiffness / 0.3)
    p = RodParams(damping_ratio=np.array([1e-9, 1.0, 0.02]))
    co = Coefficients.from_params(p)
    s, g, re = batch_velocity.complex_form(co)
    h = 0.04
    ws = np.array([w0, 0.0, 1.0])
    w = np.stack([ws, ws, ws])
    wd = np.zeros_like(w)
    entries = batch_velocity.omega_complex(co, h, w, wd)
    fast = batch_velocity.expm_complex(entries, s)
    from scipy.linalg import expm
    for i in range(3):
        N = np.zeros((3, 3), complex)
        e = [np.broadcast_to(0j if x is None else x, (3,))[i] for x in entries]
        N[0, 0], N[0, 1], N[1, 0], N[1, 1], N[0, 2], N[1, 2] = e
        X = expm(N)
        got = [f[i] for f in fast]
        want = [X[0, 0], X[0, 1], X[1, 0], X[1, 1], X[0, 2], X[1, 2]]
        assert np.allclose(got, want, rtol=1e-12, atol=1e-14)


def test_outputs_and_compatibility_arguments():
    p = RodParams(eccentricity=np.array([0.1, 0.2]))
    b = simulate_batch(p, ConstantProfile(2.0), 1.0, dt=1e-3, record_every=100)
    assert np.allclose(b.t, np.arange(0, 1.0 + 1e-9, 0.1))
    assert b.u.shape == (2, 11) and b.omega.shape == (2, 11) and np.all(b.omega == 2.0)
    plain = simulate_batch(p, ConstantProfile(2.0), 1.0)
    assert plain.u is None and plain.t.size == 0
    one = simulate_batch(RodParams(), ConstantProfile(2.0), 1.0)
    assert one.peak_deflection.shape == (1,) and one.shape == ()


@pytest.mark.parametrize('kwargs, message', [
    ({'tolerance': 0.0}, 'tolerance'),
    ({'tolerance': float('nan')}, 'tolerance'),
    ({'output_interval': -1.0}, 'output_interval'),
    ({'method': 'euler'}, 'method'),
    ({'output_interval': 0.1, 'record_every': 2}, 'not both'),
    ({'chunk_size': 0}, 'chunk_size'),
    ({'initial': {'u': [1e-3, 2e-3, 3e-3]}}, 'broadcast'),
])
def test_bad_arguments_are_refused(kwargs, message):
    p = RodParams(eccentricity=np.array([0.1, 0.2]))
    with pytest.raises(ValueError, match=message):
        simulate_batch(p, Eq26Profile(), 2.0, **kwargs)


def test_torque_drive_is_rk4_only():
    with pytest.raises(ValueError, match='rk4'):
        simulate_batch(RodParams(), torque=0.0, t_end=1.0, method='exponential')
    b = simulate_batch(RodParams(hub_inertia=np.array([0.01, 0.02])), torque=0.0, t_end=1.0,
                       initial={'omega': 1.0})
    assert b.method == 'rk4' and b.info['dt_s'] == 1e-3


@pytest.mark.parametrize('profile', [
    RampProfile(omega_target=3.0, ramp_time=5.0, t_start=1.0),
    TableProfile([0.0, 1.0, 2.5, 4.0, 6.0], [0.0, 1.0, 2.5, 2.0, 2.2]),
])
def test_profiles_with_kinks_step_on_their_breakpoints(profile):
    # w' jumps at the ramp's ends, w'' at the table's times: nodes go there
    assert set(profile.breakpoints()) <= set(
        batch_velocity.mandatory_times(profile, 8.0, None).tolist())
    p = RodParams(eccentricity=np.array([0.1, 0.2]), damping_ratio=np.array([0.0, 0.01]))
    b = simulate_batch(p, profile, 8.0, output_interval=0.5)
    for i in range(2):
        one = simulate(p.item(i), profile, 8.0, dt=1e-3)
        at = np.searchsorted(one.t, b.t - 1e-9)
        assert np.max(np.abs(b.u[i] - one.u[at])) <= 1e-10
        assert np.max(np.abs(b.v[i] - one.v[at])) <= 1e-10


def _closed_form_peak(w, r):
    """Largest |Eq. 29| over 10 s: a 0.1 ms scan, then a bounded search at its peak."""
    from scipy.optimize import minimize_scalar
    t = np.arange(0, 10.0 + 1e-9, 1e-4)
    k = int(np.argmax(np.abs(step_start(t, w, r0=r))))
    best = minimize_scalar(lambda s: -abs(step_start(s, w, r0=r)), method='bounded',
                           bounds=(t[max(k - 1, 0)], t[min(k + 1, len(t) - 1)]),
                           options={'xatol': 1e-12})
    return -best.fun


def test_batch_matches_closed_form_over_eccentricity():
    r0 = np.array([0.0, 0.05, 0.1, 0.2])
    w, t_end = 2.0, 10.0
    b = simulate_batch(RodParams(eccentricity=r0), ConstantProfile(w), t_end,
                       output_interval=0.01)
    assert b.method == 'exponential'
    for i, r in enumerate(r0):
        z = step_start(b.t, w, r0=r)
        assert np.max(np.abs(b.u[i] + 1j * b.v[i] - z)) <= 1e-12
        # the peak between samples, not only the largest sample
        assert b.peak_deflection[i] == pytest.approx(_closed_form_peak(w, r), abs=1e-12)
    # the previous fixed-step RK4, kept as method='rk4': within its phase-error bound
    old = simulate_batch(RodParams(eccentricity=r0), ConstantProfile(w), t_end, dt=1e-3,
                         record_every=10, method='rk4')
    for i, r in enumerate(r0):
        z = step_start(old.t, w, r0=r)
        bound = rk4_phase_bound(1e-3, W0 + w, t_end, np.max(np.abs(z)))
        assert np.max(np.abs(old.u[i] + 1j * old.v[i] - z)) <= bound
        assert old.peak_deflection[i] <= _closed_form_peak(w, r) + 1e-15 + bound


def test_batch_torque_drive_conserves_invariants():
    J = np.array([0.01, 0.05, 0.2])
    b = simulate_batch(RodParams(hub_inertia=J), torque=0.0, t_end=10.0,
                       initial={'omega': 2.0, 'u': 1e-3})
    from rotrod_core.model.equations import angular_momentum
    co = Coefficients.from_params(RodParams(hub_inertia=J))
    s0 = State(1e-3, 0.0, 0.0, 0.0, 0.0, 2.0)
    assert np.allclose(angular_momentum(co, b.final), angular_momentum(co, s0), rtol=1e-10)


def test_batch_in_worker_processes_matches_single_process():
    r0 = np.linspace(0.05, 0.15, 4000)
    p = RodParams(eccentricity=r0)
    for method in ('rk4', 'exponential'):
        one = simulate_batch(p, Eq26Profile(), 2.0, workers=1, method=method)
        two = simulate_batch(p, Eq26Profile(), 2.0, workers=2, method=method)
        assert np.array_equal(one.peak_deflection, two.peak_deflection)
        assert np.array_equal(one.final.u, two.final.u)
