"""Markdown text of the reproduction report and of the analysis report.

Only formatting: every number comes in from the computations (facts, stage extremes,
frequency and critical-speed rows, Campbell diagrams, maps, drifts). Deflections are
shown in mm, frequencies in Hz, angular velocities in rad/s, as the headers say.
"""

from __future__ import annotations

import math

import numpy as np

from rotrod_core.command.planner import residual_bound

MM = 1e3


def cell(text) -> str:
    """A Markdown table cell: pipes escaped, no line breaks."""
    return str(text).replace('|', '\\|').replace('\n', ' ')


def table(header: list, rows: list) -> str:
    """A Markdown table (GitHub style) from a header and rows of cells."""
    lines = ['| ' + ' | '.join(cell(h) for h in header) + ' |',
             '|' + '|'.join('---' for _ in header) + '|']
    lines += ['| ' + ' | '.join(cell(c) for c in row) + ' |' for row in rows]
    return '\n'.join(lines)


def fixed(x: float, digits: int) -> str:
    """Format x with ``digits`` decimals, never as '-0.000'."""
    return f'{round(float(x), digits) + 0.0:.{digits}f}'


def _speed(w: float) -> str:
    return 'no deflection (r0 = 0)' if math.isinf(w) else f'{w:.6f}'


def fact_table(facts: list) -> str:
    """The fact table: where, claim, paper's number, closed form, measured, verdict."""
    header = ['#', 'where', 'the paper says', "paper's number", 'closed form (docs/model.md)',
              'measured now', 'verdict']
    rows = [[i, f.where, f.claim, f.paper_value, f.closed_form, f.measured, f'**{f.verdict}**']
            for i, f in enumerate(facts, 1)]
    return table(header, rows)


def fact_criteria(facts: list) -> str:
    """How each verdict was decided, as a numbered list."""
    return '\n'.join(f'{i}. {f.criterion}' for i, f in enumerate(facts, 1))


def stage_table(stages: list) -> str:
    """Extremes of u and v per Eq. 26 stage, mm."""
    rows = [[s.name, f'{s.start:g}-{s.stop:g}'] + [fixed(MM * x, 5) for x in
                                                    (s.u_min, s.u_max, s.v_min, s.v_max)]
            for s in stages]
    return table(['stage', 't [s]', 'u min [mm]', 'u max [mm]', 'v min [mm]', 'v max [mm]'],
                 rows)


def frequency_table(rows: list) -> str:
    """Eq. 28 and the static deflection beside the values fitted to simulated runs."""
    body = [[f'{r.omega:g}', f'{r.f1:.6f}', f'{r.f1_measured:.6f}', f'{r.f2:.6f}',
             f'{r.f2_measured:.6f}', fixed(MM * r.u_static, 6), fixed(MM * r.u_static_measured, 6),
             f'{r.fit_residual:.1e}'] for r in rows]
    return table(['omega [rad/s]', 'f1 Eq. 28 [Hz]', 'f1 measured [Hz]', 'f2 Eq. 28 [Hz]',
                  'f2 measured [Hz]', 'u_s closed form [mm]', 'u_s measured [mm]',
                  'fit residual'], body)


def critical_table(rows: list) -> str:
    """Critical speeds vs eccentricity: closed forms and numerical."""
    body = [[f'{r.eccentricity:g}', f'{r.quasi_static:.6f}', f'{r.step:.6f}',
             f'{r.impulsive:.6f}', _speed(r.eq26_numerical), _speed(r.step_numerical)]
            for r in rows]
    return table(['r0 [m]', 'quasi-static [rad/s]', 'step [rad/s]', 'impulsive [rad/s]',
                  'Eq. 26 shape, numerical [rad/s]', 'step from rest, numerical [rad/s]'],
                 body)


def campbell_table(cases: dict) -> str:
    """Per Campbell case: stiffnesses, natural frequencies and the unstable bands."""
    rows = []
    for title, (params, c) in cases.items():
        bands = '; '.join(f'{lo:.6f} - {hi:.6f}' for lo, hi in c.unstable_bands) or 'none'
        rows.append([title, f'{float(params.stiffness_radial):.6f}',
                     f'{float(params.stiffness_tangential):.6f}',
                     f'{float(params.natural_frequency_radial):.6f}',
                     f'{float(params.natural_frequency_tangential):.6f}',
                     f'{float(params.damping_ratio):g}', bands])
    return table(['case', 'k1 [N/m]', 'k2 [N/m]', 'sqrt(k1/m) [rad/s]', 'sqrt(k2/m) [rad/s]',
                  'zeta', 'unstable bands [rad/s]'], rows)


def critical_map_table(cmap, label: str, limits_mm: tuple, eccentricities: tuple) -> str:
    """A few rows of the critical-speed map (nearest grid points), rad/s."""
    rows = []
    for dm in limits_mm:
        i = int(np.argmin(np.abs(MM * cmap.limit - dm)))
        for r in eccentricities:
            j = int(np.argmin(np.abs(cmap.eccentricity - r)))
            rows.append([f'{MM * cmap.limit[i]:.4f}', f'{cmap.eccentricity[j]:.5f}']
                        + [f'{cmap.speeds[k][i, j]:.4f}' for k in
                           ('quasi_static', 'step', 'impulsive', label)])
    return table(['delta [mm]', 'r0 [m]', 'quasi-static [rad/s]', 'step [rad/s]',
                  'impulsive [rad/s]', f'{label} numerical [rad/s]'], rows)


def drift_table(drifts: dict) -> str:
    """Largest relative drift of energy and angular momentum per coupling."""
    rows = [[name, f'{d.max_energy_drift:.3e}', f'{d.max_angular_momentum_drift:.3e}',
             f'{d.omega[-1]:.6f}'] for name, d in drifts.items()]
    return table(['coupling', 'max |E - E0| / E0', 'max |L - L0| / L0',
                  'omega at the end [rad/s]'], rows)


def figure_list(figures: list) -> str:
    """Markdown images, one per (file name, caption)."""
    return '\n\n'.join(f'![{caption}]({name})\n\n*{caption}*' for name, caption in figures)


def real_rig_table(summaries: list, limit: float) -> str:
    """The paper's idealisation beside the real rig.

    From :mod:`rotrod_core.reporting.rig_comparison`.
    """
    def mode(w):
        return 'none (massless rod)' if not np.isfinite(w) else f'{w:.2f}'
    rows = [
        ('gravity g [m/s^2]', *(f'{s.params.gravity:g}' for s in summaries)),
        ('rod density [kg/m^3]', *(f'{s.params.rod_density:g}' for s in summaries)),
        ('tip load / buckling load', *(f'{100 * s.buckling_fraction:.1f} %'
                                       for s in summaries)),
        ('lateral tip stiffness k [N/m]', *(f'{s.stiffness:.4f}' for s in summaries)),
        ('natural frequency w0 [rad/s]', *(f'{s.natural_frequency:.4f}' for s in summaries)),
        ('next bending mode [rad/s]', *(mode(s.second_mode) for s in summaries)),
        (f'quasi-static critical speed, {MM * limit:.1f} mm [rad/s]',
         *(f'{s.critical_speed:.4f}' for s in summaries)),
        ('Eq. 26 run: peak deflection |r| [mm]',
         *(f'{MM * s.peak_deflection:.4f}' for s in summaries)),
    ]
    return table(['', *(s.title for s in summaries)], rows)


def spin_up_table(rows: list) -> str:
    """Eq. 26 beside planned spin-ups (:mod:`rotrod_core.reporting.spin_ups`)."""
    header = ['spin-up, Table 1, 0 -> 2 rad/s, 3 mm', 'duration [s]', "largest |w'| [rad/s^2]",
              'peak deflection [mm]', 'residual whirl', 'largest residual, w0 x 0.9..1.1']
    return table(header, [[r.label, f'{r.duration:.3f}', f'{r.max_angular_acceleration:.3g}',
                           f'{MM * r.peak_deflection:.3f}', _whirl(r.residual, r.bound),
                           _whirl(r.band_residual, r.band_bound)] for r in rows])


def _whirl(value: float, bound: float | None) -> str:
    """A measured whirl (m) in um; a planned one as the bound it meets."""
    if bound is None:
        return f'{1e6 * value:.3g} um'
    return residual_bound(value, bound)


def paper_report(*, facts, stages, frequencies, critical, limit, figures, recording,
                 command, real_rig=None, spin_ups=None) -> str:
    """The whole reproduction report (Markdown).

    ``real_rig``: (the two :class:`~rotrod_core.reporting.rig_comparison.RigSummary`, the Campbell
    figure's file name, the Eq. 26 hold speed in rad/s), or None.
    ``spin_ups``: (the :class:`~rotrod_core.reporting.spin_ups.SpinUp` rows, the figure's
    file name), or None.
    """
    verdicts: dict[str, int] = {}
    for f in facts:
        verdicts[f.verdict] = verdicts.get(f.verdict, 0) + 1
    summary = ', '.join(f'{n} {v}' for v, n in sorted(verdicts.items()))
    parts = [
        '# Liu et al. (2014) reproduced',
        f'Generated by `{command}`. Table 1 parameters (m = 0.3 kg, l = 0.3 m, d = 3 mm, '
        'E = 100 GPa, r0 = 0.1 m); the Eq. 26 run (T = 15 s, W = 2 rad/s) from rest over '
        '40 s in 1 ms steps. Every "measured" value below comes from a simulation, an '
        'eigen analysis or a fit to a simulated trajectory, computed by this command.',
        '## Facts the paper states, measured now',
        f'{len(facts)} facts: {summary}.',
        fact_table(facts),
        'How each verdict is decided:',
        fact_criteria(facts),
        '## Eq. 26 run: extremes per stage (Figs. 5-8)',
        stage_table(stages),
        '## Dynamic frequencies at constant speed (Eq. 28, Fig. 9)',
        'Measured: a two-whirl fit (centre + forward + backward circular whirl) to a '
        'simulated run of 40 s from u = 0.1 mm at each constant speed.',
        frequency_table(frequencies),
        f'## Critical speed vs eccentricity for a {MM * limit:.1f} mm limit (Fig. 10)',
        'Closed forms of docs/model.md for three starts; numerical: the largest peak speed whose '
        'run from rest keeps |r| within the limit (Eq. 26 shape rescaled; a step to '
        'constant speed in the rotating frame, 20 s runs).',
        critical_table(critical),
        '## Figures',
        figure_list(figures),
    ]
    if real_rig is not None:
        summaries, campbell_figure, hold = real_rig
        rig = summaries[-1]
        parts += [
            '## A real rig beside the paper\'s idealisation',
            'The paper\'s rod is massless and feels no gravity. A real rig stands upright on '
            f'a horizontal disk (g = {rig.params.gravity:g} m/s^2: the tip\'s weight '
            'compresses the rod and softens it sideways) with a steel rod of its own mass '
            '(docs/real_rig.md, `config/real_rig.yaml`). Same Table 1, same Eq. 26 run:',
            real_rig_table(summaries, limit),
            f'On the real rig the paper\'s own {hold:g} rad/s hold is '
            + ('beyond' if rig.critical_speed < hold else 'within')
            + f' the {MM * limit:.1f} mm criterion.',
            f'![Campbell diagrams of both models]({campbell_figure})\n\n'
            '*Campbell diagrams: the paper\'s idealisation and the real rig*',
        ]
    if spin_ups is not None:
        rows, spin_up_figure = spin_ups
        parts += [
            '## Eq. 26 beside planned spin-ups',
            'The same spin-up to the paper\'s 2 rad/s under its 3 mm, planned '
            '(`profile: planned` of the profile publisher and `rotrod simulate`; '
            'docs/planner.md). Every value by `simulate` (steps of at most 1 ms, the '
            'arrival on the grid): the free whirl left about the static deflection at '
            '2 rad/s, on the nominal rod and the largest over 21 rods with natural '
            'frequencies within +-10 % (stiffness scaled).',
            spin_up_table(rows),
            f'![Eq. 26 beside planned spin-ups]({spin_up_figure})\n\n'
            '*Eq. 26 beside planned spin-ups: angular velocity, angular acceleration, tip '
            'path*',
        ]
    if recording:
        parts += ['## Rerun recording',
                  f'`{recording}`: the Eq. 26 run at 100 Hz (u, v, omega, hub torque, f1 and '
                  'f2, the tip in the rotating and inertial frames). Open it with '
                  f'`rerun {recording}`.']
    return '\n\n'.join(parts) + '\n'


def analysis_report(*, command, campbell, campbell_figure, cmap, map_label, map_limit,
                    map_figure, map_csv, drifts, drift_figure, drift_csv, drift_setup) -> str:
    """The analysis report (Markdown): whichever of the three parts were computed."""
    parts = ['# Beyond the paper', f'Generated by `{command}`.']
    if campbell is not None:
        parts += [
            '## Campbell diagrams',
            'Modal analysis at constant speed (rotating frame): damped frequencies coloured '
            'by whirl direction, growth rates below; red: speeds where some mode grows. A '
            'rectangular rod (k1 != k2) is unstable between its two natural frequencies; '
            'rotating damping makes every rod unstable above its lower natural frequency.',
            campbell_table(campbell), figure_list([(campbell_figure, 'Campbell diagrams')])]
    if cmap is not None:
        worst = float(np.max(np.abs(cmap.speeds[map_label] / cmap.speeds['quasi_static'] - 1)))
        parts += [
            '## Critical-speed map',
            f'Grid: r0 from {cmap.eccentricity[0]:.4g} to {cmap.eccentricity[-1]:.4g} m, '
            f'delta from {MM * cmap.limit[0]:.4g} to {MM * cmap.limit[-1]:.4g} mm '
            f'({len(cmap.eccentricity)} x {len(cmap.limit)} points). The {map_label} shape is '
            f'integrated with dt = {cmap.numerical_step:g} s; it stays within '
            f'{100 * worst:.3f} % of the quasi-static closed form over the grid. Every '
            'critical speed depends on delta / r0 only. All values: '
            f'`{map_csv}`.',
            critical_map_table(cmap, map_label, (MM * map_limit,), (0.0125, 0.025, 0.05, 0.1,
                                                                    0.2)),
            figure_list([(map_figure, 'Critical-speed maps')])]
    if drifts is not None:
        exact = drifts['exact']
        kept = max(exact.max_energy_drift, exact.max_angular_momentum_drift)
        parts += [
            '## Torque drive: exact coupling vs Eq. 23',
            f'{drift_setup} The exact coupling keeps energy and angular momentum within '
            f"{kept:.0e} (the integrator's error); the paper's Eq. 23 (here with the hub's "
            "J w' added) omits the relative angular momentum m ((r0 + u) v' - v u'), and "
            'E and L swing by '
            f'{100 * drifts["paper"].max_energy_drift:.1f} % and '
            f'{100 * drifts["paper"].max_angular_momentum_drift:.1f} %. Time series: '
            f'`{drift_csv}`.',
            drift_table(drifts), figure_list([(drift_figure, 'Drift of the invariants')])]
    return '\n\n'.join(parts) + '\n'
