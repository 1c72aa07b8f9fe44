"""``rotrod reproduce``: the paper's Figs. 3-10, its facts beside measured values, a Rerun file.

Writes into one output directory (checked first, before any work):

- ``fig03_angular_velocity.png`` ... ``fig10_critical_speed.png``: the paper's figures;
- ``report.md``: the fact table, stage extremes, frequencies, critical speeds, figures,
  and a real rig (gravity, a steel rod) beside the paper's idealisation;
- ``real_rig_campbell.png``: Campbell diagrams of both models;
- ``spin_ups.png``: Eq. 26 beside planned spin-ups (w, w', the tip path);
- ``eq26.rrd``: the Eq. 26 run as a Rerun recording (unless ``recording=False``).

Progress goes to stderr, one numbered line per step with its duration. Headless:
matplotlib renders with Agg, rerun-sdk writes to a file.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import rotrod_core.reporting.facts as paper
import rotrod_core.reporting.figures as figures
import rotrod_core.reporting.report as report
from rotrod_core.analysis.coupling_drift import compare_couplings
from rotrod_core.analysis.modes import static_deflection
from rotrod_core.analysis.stages import stage_extremes
from rotrod_core.reporting.output import Progress, prepare_output_dir
from rotrod_core.reporting.rig_comparison import real_rig, summarize
from rotrod_core.reporting.spin_ups import PLANNED, spin_ups

REPORT = 'report.md'
REAL_RIG_CAMPBELL = 'real_rig_campbell.png'
SPIN_UPS = 'spin_ups.png'
RECORDING = 'eq26.rrd'
FIGURES = (
    ('fig03_angular_velocity.png', 'Fig. 3: angular velocity of Eq. 26 vs time'),
    ('fig04_trajectory.png', 'Fig. 4: trajectory of the mass in the rotating frame, 0-40 s'),
    ('fig05_spin_up.png', 'Fig. 5: trajectory during spin-up, 0-15 s'),
    ('fig06_hold.png', 'Fig. 6: trajectory at constant 2 rad/s, 15-20 s (petals)'),
    ('fig07_spin_down.png', 'Fig. 7: trajectory during spin-down, 20-35 s'),
    ('fig08_rest.png', 'Fig. 8: free vibration after rotation stops, 35-40 s (ellipse)'),
    ('fig09_dynamic_frequencies.png', 'Fig. 9: dynamic frequencies vs angular velocity'),
    ('fig10_critical_speed.png', 'Fig. 10: critical angular velocity vs eccentricity, 3.0 mm'),
)
"""(file name, caption) of each figure, in the paper's order."""


@dataclass(frozen=True)
class Reproduction:
    """What ``reproduce`` wrote and found.

    Attributes:
        out_dir: the output directory.
        figures: paths of the PNG files.
        report: path of report.md.
        recording: path of the .rrd file, or None.
        facts: the :class:`~rotrod_core.reporting.facts.Fact` list.
    """

    out_dir: Path
    figures: tuple
    report: Path
    recording: Path | None
    facts: list


def _require(recording: bool) -> None:
    figures.require_matplotlib()
    if recording:
        try:
            import rerun  # noqa: F401
        except ImportError:
            raise ImportError("the recording needs rerun-sdk: pip install 'rotrod[viz]' "
                              '(or use --no-recording)') from None


def _draw(run, frequencies, critical, params, out: Path) -> tuple[Path, ...]:
    profile = paper.EQ26
    u_s = static_deflection(params, profile.omega_target)[0]     # the hold's plot centre
    names = [name for name, _ in FIGURES]
    paths = [
        figures.angular_velocity(run, profile, out / names[0]),
        figures.trajectory(run, profile, out / names[1]),
        figures.stage_trajectory(run, profile, 'spin-up', 5, out / names[2]),
        figures.stage_trajectory(run, profile, 'hold', 6, out / names[3], centre=u_s),
        figures.stage_trajectory(run, profile, 'spin-down', 7, out / names[4]),
        figures.stage_trajectory(run, profile, 'rest', 8, out / names[5]),
        figures.dynamic_frequency_plot(params, frequencies, out / names[6]),
        figures.critical_speed_plot(params, critical, paper.DEFLECTION_LIMIT, out / names[7]),
    ]
    return tuple(paths)


def reproduce(out_dir, *, recording: bool = True, stream=None,
              command: str = 'rotrod reproduce') -> Reproduction:
    """Regenerate the paper's figures, the fact report and the Eq. 26 recording.

    Args:
        out_dir: output directory (created; must be writable).
        recording: also write the Rerun recording ``eq26.rrd``.
        stream: where progress lines go (default stderr).
        command: the command line shown in the report.

    Raises:
        OutputDirectoryError: the directory cannot be created or written.
        ImportError: matplotlib (or rerun-sdk for the recording) is missing.
    """
    out = prepare_output_dir(out_dir)
    _require(recording)
    params = paper.TABLE1
    progress = Progress('reproduce', 9 + bool(recording), stream=stream)
    with progress.step('Eq. 26 run (Table 1, 40 s, dt = 1 ms)'):
        run = paper.eq26_run(params)
    with progress.step(f'dynamic frequencies at {len(paper.FREQUENCY_SPEEDS)} constant speeds '
                       '(simulated runs, whirl fits)'):
        frequencies = paper.measure_frequencies(params)
    with progress.step(f'critical speeds at {len(paper.CRITICAL_ECCENTRICITIES)} '
                       'eccentricities (numerical: Eq. 26 shape and step start)'):
        critical = paper.critical_speeds(params, progress=progress.note)
    with progress.step('torque drive without torque: exact coupling vs Eq. 23 (2 x 40 s)'):
        drift = compare_couplings()
    with progress.step('facts (and the Eq. 29 and w = w0 runs)'):
        facts = paper.paper_facts(run, frequencies, critical, drift, params)
    with progress.step('a real rig beside the idealisation (gravity, steel rod; '
                       'two Eq. 26 runs, Campbell diagrams)'):
        summaries = [summarize(title, p, paper.EQ26, paper.RUN_LENGTH, paper.RUN_STEP,
                               paper.DEFLECTION_LIMIT)
                     for title, p in (("the paper's idealisation", params),
                                      ('real rig', real_rig(params)))]
    with progress.step(f'Eq. 26 beside {len(PLANNED)} planned spin-ups (simulate, each also '
                       'on 21 rods with w0 x 0.9..1.1)'):
        spin_up_rows = spin_ups(params)
    with progress.step(f'{len(FIGURES) + 2} figures'):
        paths = _draw(run, frequencies, critical, params, out)
        paths += (figures.campbell_plot({s.title: s.campbell for s in summaries},
                                        out / REAL_RIG_CAMPBELL),
                  figures.spin_up_comparison(spin_up_rows, out / SPIN_UPS,
                                             paper.DEFLECTION_LIMIT))
    rrd = None
    if recording:
        with progress.step(f'Rerun recording {RECORDING}'):
            from rotrod_core.reporting.recording import write_run
            rrd = out / RECORDING
            write_run(rrd, run)
    with progress.step(REPORT):
        text = report.paper_report(
            facts=facts, stages=stage_extremes(run, paper.EQ26.period),
            frequencies=frequencies, critical=critical, limit=paper.DEFLECTION_LIMIT,
            figures=list(FIGURES), recording=RECORDING if recording else None,
            command=command,
            real_rig=(summaries, REAL_RIG_CAMPBELL, paper.EQ26.omega_target),
            spin_ups=(spin_up_rows, SPIN_UPS))
        report_path = out / REPORT
        report_path.write_text(text, encoding='utf-8')
    verdicts = ', '.join(f'{sum(f.verdict == v for f in facts)} {v}'
                         for v in sorted({f.verdict for f in facts}))
    progress.finish(f'wrote {len(paths)} figures, {REPORT}'
                    + (f', {RECORDING}' if recording else '') + f' to {out} ({verdicts})')
    return Reproduction(out_dir=out, figures=paths, report=report_path, recording=rrd,
                        facts=facts)
