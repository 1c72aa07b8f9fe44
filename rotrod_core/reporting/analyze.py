"""``rotrod analyze``: analyses beyond the paper, as figures, CSV data and a Markdown report.

- ``campbell``: Campbell diagrams (both whirls vs w, unstable bands shaded) of a
  circular and a rectangular rod, each without and with rotating damping;
- ``critical-map``: the critical speed over eccentricity and deflection limit for the
  quasi-static, step and impulsive starts (closed forms) and the Eq. 26 shape
  (numerical);
- ``coupling``: free rotation in torque drive, exact coupling vs the paper's Eq. 23:
  the drift of energy and angular momentum over time.

Writes ``campbell.png``, ``critical_speed_map.png`` and ``.csv``, ``coupling_drift.png``
and ``.csv`` and ``analysis.md`` into one output directory (checked first). Progress
goes to stderr.
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from pathlib import Path

import numpy as np

import rotrod_core.reporting.figures as figures
import rotrod_core.reporting.report as report
from rotrod_core.analysis.coupling_drift import DEFAULT_INITIAL, DEFAULT_PARAMS, compare_couplings
from rotrod_core.analysis.critical import STARTS
from rotrod_core.analysis.critical_map import critical_speed_map, log_grid
from rotrod_core.analysis.modes import campbell
from rotrod_core.command.profiles import Eq26Profile
from rotrod_core.model.params import RodParams
from rotrod_core.reporting.output import Progress, prepare_output_dir

PARTS = ('campbell', 'critical-map', 'coupling')
"""The analyses, in the order they run."""

CAMPBELL_OMEGAS = np.linspace(0.0, 30.0, 601)
"""Swept angular velocities of the Campbell diagrams, rad/s."""

ROTATING_DAMPING = 0.02
"""Damping ratio of the damped Campbell cases."""

RECTANGULAR: dict = {'section': 'rectangular', 'section_width': 0.004,
                     'section_thickness': 0.003}
"""A 4 mm (radial) x 3 mm (tangential) rectangular rod, otherwise Table 1."""

CAMPBELL_CASES = {
    'circular d = 3 mm, undamped': RodParams(),
    f'circular d = 3 mm, zeta = {ROTATING_DAMPING:g}': RodParams(damping_ratio=ROTATING_DAMPING),
    'rectangular 4 x 3 mm, undamped': RodParams(**RECTANGULAR),
    f'rectangular 4 x 3 mm, zeta = {ROTATING_DAMPING:g}':
        RodParams(**RECTANGULAR, damping_ratio=ROTATING_DAMPING),
}
"""Title -> system of each Campbell diagram."""

MAP_STEP_FACTOR = 2.0 ** (1.0 / 3.0)
"""Ratio between neighbouring grid values of r0 and of delta."""

MAP_ECCENTRICITIES = log_grid(0.1, MAP_STEP_FACTOR, 15, 3)
"""r0 grid of the map, m (3.1 mm to 0.2 m, through 0.1 m)."""

MAP_LIMITS = log_grid(3e-3, MAP_STEP_FACTOR, 6, 5)
"""Deflection-limit grid of the map, m (0.75 mm to 9.5 mm, through 3 mm)."""

MAP_LIMIT = 3e-3
"""The paper's limit, marked on the maps, m."""

MAP_STEP = 5e-3
"""Step of the numerical map runs, s."""

MAP_LABEL = 'eq26'
"""Key of the numerical (Eq. 26 shape) map."""

DRIFT_RUN, DRIFT_STEP, DRIFT_CSV_INTERVAL = 40.0, 1e-3, 0.05
"""Free-rotation run length and RK4 step, and the CSV sample interval, s."""

REPORT = 'analysis.md'
CAMPBELL_PNG = 'campbell.png'
MAP_PNG, MAP_CSV = 'critical_speed_map.png', 'critical_speed_map.csv'
DRIFT_PNG, DRIFT_CSV = 'coupling_drift.png', 'coupling_drift.csv'


@dataclass(frozen=True)
class Analysis:
    """What ``analyze`` wrote and found (None for the parts not run).

    Attributes:
        out_dir: the output directory.
        files: paths written.
        campbell: title -> (RodParams, CampbellDiagram).
        critical_map: the :class:`~rotrod_core.analysis.critical_map.CriticalSpeedMap`.
        drifts: coupling -> :class:`~rotrod_core.analysis.coupling_drift.InvariantDrift`.
    """

    out_dir: Path
    files: tuple
    campbell: dict | None
    critical_map: object | None
    drifts: dict | None


def _write_map_csv(cmap, path: Path) -> Path:
    names = list(STARTS) + [MAP_LABEL]
    with open(path, 'w', newline='', encoding='utf-8') as fh:
        w = csv.writer(fh)
        w.writerow(['eccentricity [m]', 'deflection limit [m]']
                   + [f'{n} [rad/s]' for n in names])
        for i, d in enumerate(cmap.limit):
            for j, r in enumerate(cmap.eccentricity):
                w.writerow([f'{r:.9g}', f'{d:.9g}']
                           + [f'{cmap.speeds[n][i, j]:.9g}' for n in names])
    return path


def _write_drift_csv(drifts: dict, path: Path) -> Path:
    first = next(iter(drifts.values()))
    dt = float(first.t[1] - first.t[0])
    keep = np.arange(0, len(first.t), max(1, int(round(DRIFT_CSV_INTERVAL / dt))))
    header = ['t [s]']
    cols = [first.t[keep]]
    for name, d in drifts.items():
        header += [f'{name} energy drift [-]', f'{name} angular momentum drift [-]',
                   f'{name} omega [rad/s]']
        cols += [d.energy[keep], d.angular_momentum[keep], d.omega[keep]]
    np.savetxt(path, np.column_stack(cols), delimiter=',', header=','.join(header),
               comments='', fmt='%.12e')
    return path


def analyze(out_dir, parts=PARTS, *, stream=None, command: str = 'rotrod analyze') -> Analysis:
    """Run the chosen analyses and write their figures, data and report.

    Args:
        out_dir: output directory (created; must be writable).
        parts: any of :data:`PARTS`.
        stream: where progress lines go (default stderr).
        command: the command line shown in the report.

    Raises:
        OutputDirectoryError: the directory cannot be created or written.
        ImportError: matplotlib is missing.
        ValueError: an unknown part.
    """
    unknown = [p for p in parts if p not in PARTS]
    if unknown or not parts:
        raise ValueError(f'parts must be some of {PARTS}, got {list(parts)!r}')
    out = prepare_output_dir(out_dir)
    figures.require_matplotlib()
    progress = Progress('analyze', len(set(parts)) + 1, stream=stream)
    files, cases, cmap, drifts = [], None, None, None
    if 'campbell' in parts:
        with progress.step(f'Campbell diagrams: {len(CAMPBELL_CASES)} rods x '
                           f'{len(CAMPBELL_OMEGAS)} speeds'):
            cases = {title: (p, campbell(p, CAMPBELL_OMEGAS))
                     for title, p in CAMPBELL_CASES.items()}
            files.append(figures.campbell_plot({t: c for t, (_, c) in cases.items()},
                                               out / CAMPBELL_PNG))
    if 'critical-map' in parts:
        with progress.step(f'critical-speed map: {len(MAP_ECCENTRICITIES)} x {len(MAP_LIMITS)} '
                           f'(r0, delta), Eq. 26 shape numerically (dt = {MAP_STEP:g} s)'):
            cmap = critical_speed_map(RodParams(), MAP_ECCENTRICITIES, MAP_LIMITS,
                                      Eq26Profile(), MAP_LABEL, dt=MAP_STEP,
                                      progress=lambda n: progress.note(f'{n} runs'))
            files.append(figures.critical_map_plot(cmap, MAP_LABEL, MAP_LIMIT, out / MAP_PNG))
            files.append(_write_map_csv(cmap, out / MAP_CSV))
    if 'coupling' in parts:
        with progress.step(f'torque drive, Q = 0: exact coupling vs Eq. 23 '
                           f'(2 x {DRIFT_RUN:g} s, dt = {DRIFT_STEP:g} s)'):
            drifts = compare_couplings(DEFAULT_PARAMS, DRIFT_RUN, DRIFT_STEP)
            files.append(figures.coupling_drift_plot(drifts, out / DRIFT_PNG))
            files.append(_write_drift_csv(drifts, out / DRIFT_CSV))
    with progress.step(REPORT):
        setup = (f'Table 1 with J = {DEFAULT_PARAMS.hub_inertia:g} kg m^2, no hub torque, '
                 f'start w = {DEFAULT_INITIAL["omega"]:g} rad/s, '
                 f'u = {1e3 * DEFAULT_INITIAL["u"]:g} mm, {DRIFT_RUN:g} s of RK4 at '
                 f'{DRIFT_STEP:g} s.')
        text = report.analysis_report(
            command=command, campbell=cases, campbell_figure=CAMPBELL_PNG, cmap=cmap,
            map_label=MAP_LABEL, map_limit=MAP_LIMIT, map_figure=MAP_PNG, map_csv=MAP_CSV,
            drifts=drifts, drift_figure=DRIFT_PNG, drift_csv=DRIFT_CSV, drift_setup=setup)
        path = out / REPORT
        path.write_text(text, encoding='utf-8')
        files.append(path)
    progress.finish(f'wrote {", ".join(p.name for p in files)} to {out}')
    return Analysis(out_dir=out, files=tuple(files), campbell=cases, critical_map=cmap,
                    drifts=drifts)
