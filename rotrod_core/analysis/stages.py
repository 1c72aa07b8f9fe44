"""The four stages of the Eq. 26 run and their extreme deflections."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rotrod_core.offline.result import SimulationResult


@dataclass(frozen=True)
class StageExtremes:
    """Extremes of u and v (m) within one stage [start, stop] (s)."""

    name: str
    start: float
    stop: float
    u_min: float
    u_max: float
    v_min: float
    v_max: float


def eq26_stages(period: float, t_end: float) -> list[tuple[str, float, float]]:
    """(name, start, stop) of spin-up, hold, spin-down and rest for Eq. 26 with period T."""
    T = period
    stages = [('spin-up', 0.0, T), ('hold', T, 4 * T / 3), ('spin-down', 4 * T / 3, 7 * T / 3),
              ('rest', 7 * T / 3, t_end)]
    return [(n, a, min(b, t_end)) for n, a, b in stages if a < t_end]


def stage_extremes(result: SimulationResult, period: float) -> list[StageExtremes]:
    """Extreme u and v in each Eq. 26 stage of ``result`` (a list of StageExtremes)."""
    return series_stage_extremes(result.t, result.u, result.v, period)


def series_stage_extremes(t, u, v, period: float,
                          t_end: float | None = None) -> list[StageExtremes]:
    """Extreme u and v (m) in each Eq. 26 stage of sampled series (t in s from the start).

    Stages end at ``t_end`` (default: the last sample); a stage with no sample is left out.
    """
    t, u, v = (np.asarray(x, dtype=float) for x in (t, u, v))
    out = []
    for name, a, b in eq26_stages(period, float(t[-1] if t_end is None else t_end)):
        keep = (t >= a) & (t <= b)
        if not np.any(keep):
            continue
        uu, vv = u[keep], v[keep]
        out.append(StageExtremes(name, a, b, float(np.min(uu)), float(np.max(uu)),
                                 float(np.min(vv)), float(np.max(vv))))
    return out


def format_stage_table(rows: list, reference: list | None = None) -> str:
    """A plain-text table of stage extremes in mm, optionally beside a reference run."""
    head = f'{"stage":<10} {"t [s]":>13} {"u min":>9} {"u max":>9} {"v min":>9} {"v max":>9}'
    if reference:
        head += '   max |diff| vs reference [mm]'
    lines = [head + '   (deflections in mm)']
    for i, r in enumerate(rows):
        vals = (r.u_min, r.u_max, r.v_min, r.v_max)
        line = (f'{r.name:<10} {r.start:6.2f}-{r.stop:6.2f} '
                + ' '.join(f'{1e3 * x:9.5f}' for x in vals))
        if reference:
            ref = reference[i]
            diff = max(abs(a - b) for a, b in zip(vals, (ref.u_min, ref.u_max, ref.v_min,
                                                         ref.v_max)))
            line += f'   {1e3 * diff:.2e}'
        lines.append(line)
    return '\n'.join(lines)
