"""The paper's stated facts, each beside the value measured now from the code.

Liu et al. (2014) state, in words and figures, what the Eq. 26 run (Table 1) shows per
stage, how the dynamic frequencies move with speed (Eq. 28, Fig. 9), how the critical
speed falls with eccentricity (Fig. 10, 3.0 mm limit) and give a torque equation
(Eq. 23). Each :class:`Fact` holds the paper's claim, the paper's number where it gives
one, the closed form of docs/model.md where there is one, the value measured now (from
:func:`~rotrod_core.offline.simulate.simulate`, the eigen analysis and the fits of
:func:`~rotrod_core.estimation.whirl.fit_whirls`; never typed in) and a verdict decided by a stated
criterion. SI units inside; the text shows mm, um, Hz and rad/s as labelled.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from rotrod_core.analysis.critical import critical_speed, critical_speed_for_profile, step_response
from rotrod_core.analysis.modes import dynamic_frequencies, modal_analysis, static_deflection
from rotrod_core.analysis.stages import stage_extremes
from rotrod_core.command.profiles import ConstantProfile, Eq26Profile
from rotrod_core.estimation.whirl import fit_whirls
from rotrod_core.model.params import RodParams
from rotrod_core.offline.result import SimulationResult
from rotrod_core.offline.simulate import simulate

TABLE1 = RodParams()
"""The paper's Table 1 (the defaults of RodParams)."""

EQ26 = Eq26Profile()
"""Eq. 26 with the paper's T = 15 s and W = 2 rad/s."""

RUN_LENGTH = 40.0
"""Length of the paper's run, s."""

RUN_STEP = 1e-3
"""Step of the Eq. 26 run, s (accurate to ~1e-14 m: docs/performance.md)."""

FREQUENCY_SPEEDS = (0.0, 1.0, 2.0, 4.0, 6.0, 8.0, 10.0)
"""Constant angular velocities (rad/s) at which the frequencies are measured (Fig. 9)."""

FREQUENCY_RUN = 40.0
"""Length of each constant-speed run for the frequency fit, s."""

FREQUENCY_STEP = 5e-3
"""Step of those runs, s (the Magnus step is exact at constant speed)."""

FREQUENCY_START = {'u': 1e-4}
"""Start of those runs: u = 0.1 mm, at rest in the rotating frame (both whirls excited)."""

DEFLECTION_LIMIT = 3.0e-3
"""The paper's deflection limit for Fig. 10, m."""

CRITICAL_ECCENTRICITIES = (0.0, 1e-4, 0.01, 0.02, 0.05, 0.1, 0.2, 0.3)
"""Eccentricities r0 (m) of the critical-speed table."""

CRITICAL_STEP = 2e-3
"""Step of the numerical critical-speed runs, s."""

STEP_CRITICAL_RUN = 20.0
"""Length of the numerical step-start runs, s (long enough for the two whirls to line up
near the smallest r0, where w1 = w0 - w is slow)."""

STEP_RESPONSE_SPEED = 2.0
"""Constant speed (rad/s) of the Eq. 29 check."""

STEP_RESPONSE_RUN = 60.0
"""Length of the Eq. 29 check run, s."""

AGREES, DIFFERS, IN_PART = 'agrees', 'differs', 'agrees in part'


@dataclass(frozen=True)
class Fact:
    """One statement of the paper beside the value measured now.

    Attributes:
        where: where the paper says it (figure, equation, section).
        claim: what the paper says (quoted or closely paraphrased).
        paper_value: the paper's number or sign, '-' when it gives none.
        closed_form: the docs/model.md closed form evaluated for Table 1, '-' if none.
        measured: the value measured now, as text with units.
        verdict: 'agrees', 'differs' or 'agrees in part'.
        criterion: how the verdict was decided.
        values: the measured numbers (SI units) by name.
    """

    where: str
    claim: str
    paper_value: str
    closed_form: str
    measured: str
    verdict: str
    criterion: str
    values: dict = field(default_factory=dict)


@dataclass(frozen=True)
class FrequencyRow:
    """Dynamic frequencies at one constant speed: Eq. 28 and measured from a simulation.

    Attributes:
        omega: angular velocity, rad/s.
        f1, f2: Eq. 28, Hz.
        f1_measured, f2_measured: forward and backward whirl frequencies fitted to the
            simulated motion, Hz.
        u_static: static deflection m w^2 r0 / (k - m w^2), m.
        u_static_measured: centre of the simulated motion, m.
        fit_residual: fit residual over the motion's semi-major axis.
    """

    omega: float
    f1: float
    f2: float
    f1_measured: float
    f2_measured: float
    u_static: float
    u_static_measured: float
    fit_residual: float


@dataclass(frozen=True)
class CriticalRow:
    """Critical angular velocities (rad/s) at one eccentricity r0 (m) for one limit.

    Closed forms for the quasi-static, step and impulsive starts; numerical ones for
    the Eq. 26 shape and for a step from rest in the rotating frame (inf when nothing
    deflects, r0 = 0).
    """

    eccentricity: float
    quasi_static: float
    step: float
    impulsive: float
    eq26_numerical: float
    step_numerical: float


def eq26_run(params: RodParams = TABLE1) -> SimulationResult:
    """The paper's run: Eq. 26 from rest, 40 s, 1 ms steps."""
    return simulate(params, EQ26, RUN_LENGTH, dt=RUN_STEP)


def measure_frequencies(params: RodParams = TABLE1,
                        speeds=FREQUENCY_SPEEDS) -> list[FrequencyRow]:
    """Eq. 28 beside the whirl frequencies fitted to a simulated constant-speed run."""
    rows = []
    for w in speeds:
        run = simulate(params, ConstantProfile(w), FREQUENCY_RUN, dt=FREQUENCY_STEP,
                       initial=FREQUENCY_START)
        fit = fit_whirls(run.t, run.u, run.v)
        f1, f2 = dynamic_frequencies(params, w)
        rows.append(FrequencyRow(
            omega=float(w), f1=f1, f2=f2, f1_measured=fit.forward_frequency,
            f2_measured=fit.backward_frequency, u_static=static_deflection(params, w)[0],
            u_static_measured=fit.centre.real, fit_residual=fit.relative_residual))
    return rows


def critical_speeds(params: RodParams = TABLE1, eccentricities=CRITICAL_ECCENTRICITIES,
                    limit: float = DEFLECTION_LIMIT, progress=None) -> list[CriticalRow]:
    """Critical speeds vs eccentricity for one deflection limit (m): closed and numerical.

    ``progress``, if given, is called with a short text after each numerical run.
    """
    r0 = np.asarray(eccentricities, dtype=float)
    batch = params.replace(eccentricity=r0)
    closed = {s: np.atleast_1d(critical_speed(batch, limit, s))
              for s in ('quasi_static', 'step', 'impulsive')}

    def report(label):
        return None if progress is None else (lambda n: progress(f'{label}: {n} runs'))

    eq26 = np.atleast_1d(critical_speed_for_profile(batch, EQ26, limit, dt=CRITICAL_STEP,
                                                    progress=report('Eq. 26 shape')))
    step = np.atleast_1d(critical_speed_for_profile(batch, ConstantProfile(1.0), limit,
                                                    t_end=STEP_CRITICAL_RUN, dt=CRITICAL_STEP,
                                                    progress=report('step start')))
    return [CriticalRow(float(r), float(closed['quasi_static'][i]), float(closed['step'][i]),
                        float(closed['impulsive'][i]), float(eq26[i]), float(step[i]))
            for i, r in enumerate(r0)]


def _same_order(measured: float, stated: float) -> bool:
    """True when measured is within a factor sqrt(10) of stated (log10 differs < 0.5)."""
    return abs(math.log10(measured / stated)) < 0.5


def _fixed(x: float, digits: int) -> str:
    """Format x with ``digits`` decimals, never as '-0.000'."""
    return f'{round(float(x), digits) + 0.0:.{digits}f}'


def _mm(x):
    return f'{_fixed(1e3 * x, 4)} mm'


def _um(x):
    return f'{_fixed(1e6 * x, 4)} um'


def _profile_fact(profile: Eq26Profile) -> Fact:
    T, W = profile.period, profile.omega_target
    joints = (T, 4 * T / 3, 7 * T / 3)
    at = {t: profile.omega(t) for t in joints}
    eps = 1e-7
    wd_step = max(abs(profile.omega_dot(t + eps) - profile.omega_dot(t - eps)) for t in joints)
    w_step = max(abs(profile.omega(t + eps) - profile.omega(t - eps)) for t in joints)
    t = np.linspace(0.0, RUN_LENGTH, 40001)
    wd = profile.omega_dot(t)
    k = int(np.argmax(wd))
    ok = (abs(at[T] - W) < 1e-12 and abs(at[4 * T / 3] - W) < 1e-12
          and abs(at[7 * T / 3]) < 1e-12 and wd_step < 1e-5 and w_step < 1e-5)
    return Fact(
        where='Eq. 26, Fig. 3',
        claim='spin-up over 15 s to 2 rad/s, constant 2 rad/s from 15 to 20 s, spin-down '
              'from 20 to 35 s, no rotation after 35 s',
        paper_value='T = 15 s, W = 2 rad/s',
        closed_form=f'peak w\' = 2W/T = {2 * W / T:.6f} rad/s^2 at T/2',
        measured=(f'w(15 s) = {_fixed(at[T], 6)}, w(20 s) = {_fixed(at[4 * T / 3], 6)}, '
                  f'w(35 s) = {_fixed(at[7 * T / 3], 6)} rad/s; w and w\' continuous at the '
                  f'joints (largest step of w\' {wd_step:.1e} rad/s^2); peak w\' {wd[k]:.6f} '
                  f'rad/s^2 at {t[k]:.3f} s'),
        verdict=AGREES if ok else DIFFERS,
        criterion='w at the joints as stated to 1e-12 rad/s; no step of w or w\' > 1e-5',
        values={'peak_omega_dot': float(wd[k]), 'omega_dot_step': float(wd_step)})


def stage_facts(run: SimulationResult, params: RodParams = TABLE1) -> list[Fact]:
    """The paper's statements about the four stages of the Eq. 26 run (Figs. 4-8)."""
    period = EQ26.period
    st = {s.name: s for s in stage_extremes(run, period)}
    up, hold, down = st['spin-up'], st['hold'], st['spin-down']
    facts = []

    ok = (up.u_max > 0 and abs(up.u_min) < 0.01 * up.u_max and up.v_min < 0
          and up.v_max < 0.01 * abs(up.v_min))
    facts.append(Fact(
        where='Fig. 5 (0-15 s)',
        claim='the mass moves radially outwards and tangentially backwards (v negative)',
        paper_value='u > 0, v < 0', closed_form='-',
        measured=(f'u in [{_mm(up.u_min)}, {_mm(up.u_max)}], '
                  f'v in [{_mm(up.v_min)}, {_mm(up.v_max)}]'),
        verdict=AGREES if ok else DIFFERS,
        criterion='u_max > 0, v_min < 0, and the opposite excursions < 1 % of them',
        values={'u_min': up.u_min, 'u_max': up.u_max, 'v_min': up.v_min, 'v_max': up.v_max}))

    w = run.window(0.0, period)
    k = int(np.argmin(w.v))
    t_peak, v_end = float(w.t[k]), float(w.v[-1])
    ok = 0.05 * period < t_peak < 0.95 * period and abs(v_end) < 0.05 * abs(w.v[k])
    facts.append(Fact(
        where='Fig. 5 (0-15 s)',
        claim='the tangential deflection increases in the early stage and then converges '
              'to a small amplitude (the tangential inertia force rises and falls)',
        paper_value='-', closed_form=f'tangential force -m r0 w\' peaks at T/2 = {period / 2} s',
        measured=(f'v peaks at {_mm(w.v[k])} at {t_peak:.3f} s; v(15 s) = {_mm(v_end)} '
                  f'({100 * abs(v_end / w.v[k]):.2f} % of the peak)'),
        verdict=AGREES if ok else DIFFERS,
        criterion='peak inside the stage, |v| at its end < 5 % of the peak',
        values={'t_peak': t_peak, 'v_end': v_end}))

    ratio = up.u_max / abs(up.v_min)
    facts.append(Fact(
        where='Fig. 5 (0-15 s)',
        claim='the radial deflection is more or less ten times the tangential one',
        paper_value='~10', closed_form='-',
        measured=f'max u / max |v| = {ratio:.2f}',
        verdict=AGREES if _same_order(ratio, 10.0) else DIFFERS,
        criterion='same order of magnitude (within a factor sqrt(10))',
        values={'ratio': ratio}))

    h = run.window(period, 4 * period / 3)
    fit = fit_whirls(h.t, h.u, h.v)
    w_hold = EQ26.omega_target
    u_s = static_deflection(params, w_hold)[0]
    ok = (fit.relative_residual < 0.01 and fit.semi_minor > 0.01 * fit.semi_major
          and abs(fit.precession_rate) > 0.1 * w_hold)
    facts.append(Fact(
        where='Fig. 6 (15-20 s)',
        claim='a petal pattern: each elliptical trace rotates (only the Coriolis force acts '
              'on it)',
        paper_value='-',
        closed_form=(f'whirls at (w0 - w)/2pi = {dynamic_frequencies(params, w_hold)[0]:.4f} '
                     f'Hz forward and (w0 + w)/2pi = '
                     f'{dynamic_frequencies(params, w_hold)[1]:.4f} Hz backward: an ellipse '
                     f'turning at -w = {-w_hold:.4f} rad/s'),
        measured=(f'fit: whirls at {fit.forward_frequency:.4f} Hz forward and '
                  f'{fit.backward_frequency:.4f} Hz backward; ellipse {_um(fit.semi_major)} x '
                  f'{_um(fit.semi_minor)} (semi-axes) turning at {fit.precession_rate:.4f} '
                  f'rad/s; fit residual {fit.relative_residual:.1e} of the semi-major axis'),
        verdict=AGREES if ok else DIFFERS,
        criterion='two-whirl fit residual < 1 %, a true ellipse (minor > 1 % of major) whose '
                  'axis turns (|rate| > 0.1 w)',
        values={'precession_rate': fit.precession_rate, 'semi_major': fit.semi_major,
                'semi_minor': fit.semi_minor, 'f_forward': fit.forward_frequency,
                'f_backward': fit.backward_frequency}))

    v_amp = max(abs(hold.v_min), abs(hold.v_max))
    orders = math.log10(hold.u_max / v_amp)
    facts.append(Fact(
        where='Fig. 6 (15-20 s)',
        claim='the radial deflection is about three orders of magnitude more than the '
              'tangential deflection',
        paper_value='~10^3', closed_form='-',
        measured=f'max u / max |v| = {hold.u_max / v_amp:.0f} (10^{orders:.2f})',
        verdict=AGREES if hold.u_max / v_amp >= 1e3 else DIFFERS,
        criterion='three or more orders of magnitude (ratio >= 10^3), as docs/model.md reads '
                  'the claim',
        values={'ratio': hold.u_max / v_amp}))

    ok = abs(fit.centre.real - u_s) < 1e-3 * u_s
    facts.append(Fact(
        where='Fig. 6 (15-20 s)',
        claim='the radial deflection is produced jointly by the centrifugal force and the '
              'elastic restoring force',
        paper_value='-',
        closed_form=f'u_s = m w^2 r0 / (k - m w^2) = {_mm(u_s)} at w = {w_hold:g} rad/s',
        measured=f'centre of the hold motion (fit) u = {_mm(fit.centre.real)}',
        verdict=AGREES if ok else DIFFERS,
        criterion='within 0.1 % of u_s',
        values={'u_hold': fit.centre.real, 'u_static': u_s}))

    ok = down.v_max > 0 and abs(down.v_min) < 0.01 * down.v_max and \
        run.window(4 * period / 3, 7 * period / 3).u[-1] < 0.01 * down.u_max
    u_end = float(run.window(4 * period / 3, 7 * period / 3).u[-1])
    facts.append(Fact(
        where='Fig. 7 (20-35 s)',
        claim='the radial deflection decreases and the tangential deflection moves forward '
              '(v positive)',
        paper_value='u falls, v > 0', closed_form='-',
        measured=(f'u from {_mm(down.u_max)} to {_mm(u_end)} at 35 s; '
                  f'v in [{_mm(down.v_min)}, {_mm(down.v_max)}]'),
        verdict=AGREES if ok else DIFFERS,
        criterion='v_max > 0 with |v_min| < 1 % of it; u at 35 s < 1 % of its maximum',
        values={'u_end': u_end, 'v_min': down.v_min, 'v_max': down.v_max}))

    r = run.window(7 * period / 3, run.t[-1])
    fit = fit_whirls(r.t, r.u, r.v)
    f0 = float(params.natural_frequency) / (2 * math.pi)
    ok = (fit.relative_residual < 1e-6 and fit.semi_minor > 0.01 * fit.semi_major
          and abs(fit.precession_rate) < 1e-6 * 2 * math.pi * f0
          and abs(fit.forward_frequency / f0 - 1) < 1e-6 and fit.semi_major < 1e-6)
    facts.append(Fact(
        where='Fig. 8 (35-40 s)',
        claim='a stable elliptical trajectory, the conventional free vibration of a mass with '
              'two degrees of freedom',
        paper_value='-', closed_form=f'free vibration at f0 = sqrt(k/m)/2pi = {f0:.6f} Hz',
        measured=(f'ellipse {_um(fit.semi_major)} x {_um(fit.semi_minor)} (semi-axes), axis '
                  f'turning at {fit.precession_rate:.1e} rad/s (fixed), traced at '
                  f'{fit.forward_frequency:.6f} Hz; fit residual {fit.relative_residual:.1e}'),
        verdict=AGREES if ok else DIFFERS,
        criterion='exact ellipse (residual < 1e-6, minor > 1 % of major), fixed axis, at f0 to '
                  '1e-6, sub-micrometre',
        values={'semi_major': fit.semi_major, 'semi_minor': fit.semi_minor,
                'frequency': fit.forward_frequency, 'f0': f0}))
    return facts


def frequency_facts(rows: list, params: RodParams = TABLE1) -> list[Fact]:
    """Eq. 28 / Fig. 9 statements against the fitted frequencies."""
    worst = max(max(abs(r.f1_measured - r.f1) / r.f1, abs(r.f2_measured - r.f2) / r.f2)
                for r in rows)
    at2 = next((r for r in rows if r.omega == 2.0), rows[0])
    w0 = float(params.natural_frequency)
    facts = [Fact(
        where='Eq. 28, Fig. 9',
        claim='two dynamic frequencies f1 = (w0 - w)/2pi and f2 = (w0 + w)/2pi; both equal '
              'the natural frequency without rotation',
        paper_value='formula (Fig. 9 plots it)',
        closed_form=f'at w = {at2.omega:g} rad/s: f1 = {at2.f1:.4f} Hz, f2 = {at2.f2:.4f} Hz',
        measured=(f'at w = {at2.omega:g} rad/s: {at2.f1_measured:.4f} Hz, '
                  f'{at2.f2_measured:.4f} Hz (whirl fit of a simulated run); largest '
                  f'relative difference over w = '
                  f'{", ".join(f"{r.omega:g}" for r in rows)} rad/s: {worst:.1e}'),
        verdict=AGREES if worst < 1e-6 else DIFFERS,
        criterion='every measured frequency within 1e-6 (relative) of Eq. 28',
        values={'worst_relative_difference': worst})]

    f1_at_w0 = min(modal_analysis(params, w0).frequencies)
    run = simulate(params, ConstantProfile(w0), 20.0, dt=RUN_STEP)
    d10 = float(np.max(run.deflection[run.t <= 10.0]))
    d20 = float(np.max(run.deflection))
    above = 1.2 * w0
    undamped = modal_analysis(params, above)
    damped = modal_analysis(params.replace(damping_ratio=0.02), above)
    unbounded = f1_at_w0 < 1e-9 and d20 / d10 > 1.8
    facts.append(Fact(
        where='Section 4, Eq. 27',
        claim='f1 falls to zero at w = w0; once this speed is approached, stability of the '
              'linear system is definitely lost',
        paper_value='w = w0',
        closed_form=f'w0 = {w0:.6f} rad/s; u_s -> infinity at w0',
        measured=(f'f1(w0) = {f1_at_w0:.2e} Hz; from rest at w0 max |r| = {d10:.3f} m by '
                  f'10 s, {d20:.3f} m by 20 s (linear model; grows with t); at 1.2 w0 '
                  f'undamped max Re(lambda) = '
                  f'{undamped.max_growth_rate:.1e} 1/s (stable again, gyroscopic), with '
                  f'rotating damping zeta = 0.02 {damped.max_growth_rate:.4f} 1/s (unstable)'),
        verdict=(AGREES if unbounded and not undamped.stable else
                 IN_PART if unbounded else DIFFERS),
        criterion='unbounded at w0 (f1 = 0, |r| doubles from 10 to 20 s); "agrees in part" '
                  'when the undamped rod is stable again above w0',
        values={'f1_at_w0': f1_at_w0, 'growth_10_to_20': d20 / d10,
                'growth_rate_above_undamped': undamped.max_growth_rate,
                'growth_rate_above_damped': damped.max_growth_rate}))
    return facts


def step_response_fact(params: RodParams = TABLE1) -> Fact:
    """Eq. 29 (deflection from rest at constant speed) against a simulation."""
    w = STEP_RESPONSE_SPEED
    run = simulate(params, ConstantProfile(w), STEP_RESPONSE_RUN, dt=RUN_STEP)
    err = float(np.max(np.abs(run.u + 1j * run.v - step_response(params, w, run.t))))
    u_s = static_deflection(params, w)[0]
    amp = float(np.max(run.deflection)) / u_s
    ok = err < 1e-9 and 1.9 < amp <= 2.0
    return Fact(
        where='Eq. 29',
        claim='at constant w the deflection is a periodic part (two whirls) plus an eccentric '
              'part set by w and r0',
        paper_value='-',
        closed_form=(f'from rest: z = (w^2 r0/2w0) [(1 - e^(i w1 t))/w1 + (1 - e^(-i w2 t))/w2]'
                     f', peak -> 2 u_s = {_mm(2 * u_s)} at w = {w:g} rad/s'),
        measured=(f'simulation from rest at {w:g} rad/s, {STEP_RESPONSE_RUN:g} s: '
                  f'max |z - Eq. 29| = {err:.1e} m; peak |r| = {amp:.4f} u_s'),
        verdict=AGREES if ok else DIFFERS,
        criterion='within 1e-9 m of Eq. 29; peak between 1.9 and 2 u_s',
        values={'max_error': err, 'peak_over_u_static': amp})


def critical_fact(rows: list, params: RodParams = TABLE1,
                  limit: float = DEFLECTION_LIMIT) -> Fact:
    """Fig. 10 (critical speed vs eccentricity) against the numerical critical speeds."""
    w0 = float(params.natural_frequency)
    forced = [r for r in rows if r.eccentricity > 0]
    num = np.array([r.eq26_numerical for r in forced])
    decreasing = bool(np.all(np.diff(num) < 0))
    first, last = forced[0], forced[-1]
    ok = decreasing and first.eq26_numerical > 0.95 * w0 and last.eq26_numerical < 0.15 * w0
    worst_qs = max(abs(r.eq26_numerical / r.quasi_static - 1) for r in forced)
    return Fact(
        where='Fig. 10',
        claim=f'for a {1e3 * limit:.1f} mm limit the critical speed equals the natural '
              'frequency at r0 = 0 and decreases with the eccentricity until vanishing',
        paper_value='w_cr(0) = w0, falling to 0',
        closed_form=(f'quasi-static w0 sqrt(d/(d + r0)), step w0 sqrt(d/(d + 2 r0)); '
                     f'w0 = {w0:.4f} rad/s'),
        measured=(f'Eq. 26 shape, numerical: {first.eq26_numerical:.4f} rad/s at r0 = '
                  f'{first.eccentricity:g} m, {last.eq26_numerical:.4f} rad/s at '
                  f'{last.eccentricity:g} m, decreasing: {"yes" if decreasing else "no"}; '
                  f'within {100 * worst_qs:.2f} % of the quasi-static form'),
        verdict=AGREES if ok else DIFFERS,
        criterion='strictly decreasing; > 0.95 w0 at the smallest r0, < 0.15 w0 at the '
                  'largest',
        values={'decreasing': decreasing, 'worst_vs_quasi_static': worst_qs})


def coupling_fact(drift: dict) -> Fact:
    """Eq. 23 (the paper's torque equation) against the exact coupling, in free rotation."""
    exact, paper = drift['exact'], drift['paper']
    ok = exact.max_angular_momentum_drift < 1e-9 and paper.max_angular_momentum_drift > 1e-6
    return Fact(
        where='Eqs. 18-23',
        claim='Q = 2m(r0 u\' + u u\' + v v\') w + m(r0^2 + 2 r0 u + u^2 + v^2) w\' governs '
              'the rotation (with Eqs. 16, 17)',
        paper_value='Eq. 23',
        closed_form='with Q = 0, E and L = (J + m rho^2) w + m((r0 + u) v\' - v u\') are '
                    'constant',
        measured=(f'Q = 0, J = 0.01 kg m^2, w(0) = 2 rad/s, u(0) = 1 mm, {exact.t[-1]:g} s: '
                  f'Eq. 23 drifts {100 * paper.max_energy_drift:.2f} % in E and '
                  f'{100 * paper.max_angular_momentum_drift:.2f} % in L; exact coupling '
                  f'{exact.max_energy_drift:.0e} and {exact.max_angular_momentum_drift:.0e}'),
        verdict=DIFFERS if ok else AGREES,
        criterion='differs when Eq. 23 loses L (> 1e-6) while the exact coupling keeps it '
                  '(< 1e-9)',
        values={'paper_energy': paper.max_energy_drift,
                'paper_angular_momentum': paper.max_angular_momentum_drift,
                'exact_energy': exact.max_energy_drift,
                'exact_angular_momentum': exact.max_angular_momentum_drift})


def paper_facts(run: SimulationResult, frequencies: list, critical: list, drift: dict,
                params: RodParams = TABLE1) -> list[Fact]:
    """Every fact, in the paper's order."""
    return ([_profile_fact(EQ26)] + stage_facts(run, params)
            + frequency_facts(frequencies, params) + [step_response_fact(params),
                                                      critical_fact(critical, params),
                                                      coupling_fact(drift)])
