"""``rotrod reproduce`` and ``rotrod analyze``: files, image sizes, report numbers, errors.

Each command runs once per module (in a temporary directory, through the CLI's main).
The report's numbers are compared with closed forms written here from docs/model.md
(``reference.py``), not with the code that printed them.
"""

import contextlib
import io
import math
import os
import re
import struct
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image
from reference import R0, W0, M

from rotrod_core.cli import main
from rotrod_core.reporting import recording
from rotrod_ros.install import executable

ROOT = Path(__file__).resolve().parents[3]
DOCS = ROOT / 'docs'
PAPER_FIGURES = ('fig03_angular_velocity.png', 'fig04_trajectory.png', 'fig05_spin_up.png',
                 'fig06_hold.png', 'fig07_spin_down.png', 'fig08_rest.png',
                 'fig09_dynamic_frequencies.png', 'fig10_critical_speed.png')
ANALYSIS_FIGURES = {'campbell.png': (1280, 640), 'critical_speed_map.png': (1280, 800),
                    'coupling_drift.png': (1280, 480)}
REPORT_FIGURES = {'spin_ups.png': (1280, 480), 'real_rig_campbell.png': (1280, 640)}
"""Figures of the reproduction report beyond the paper's."""
DELTA = 3.0e-3
E, L_ROD = 100e9, 0.3
VERDICTS = {'agrees', 'differs', 'agrees in part'}


def run_cli(argv):
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        code = main(argv)
    return code, out.getvalue(), err.getvalue()


@pytest.fixture(scope='module')
def reproduced(tmp_path_factory):
    out = tmp_path_factory.mktemp('reproduce') / 'out'     # created by the command
    code, stdout, stderr = run_cli(['reproduce', '--out', str(out)])
    assert code == 0, stderr
    return out, stdout, stderr


@pytest.fixture(scope='module')
def analyzed(tmp_path_factory):
    out = tmp_path_factory.mktemp('analyze')
    code, stdout, stderr = run_cli(['analyze', '--out', str(out)])
    assert code == 0, stderr
    return out, stdout, stderr


# --- Markdown parsing -------------------------------------------------------------------

def split_row(line):
    cells = re.split(r'(?<!\\)\|', line.strip())[1:-1]
    return [c.strip().replace('\\|', '|') for c in cells]


def tables(text):
    """Every Markdown table of text as (header, rows), in order."""
    found, lines, i = [], text.splitlines(), 0
    while i < len(lines):
        if lines[i].startswith('|') and i + 1 < len(lines) and lines[i + 1].startswith('|---'):
            header = split_row(lines[i])
            rows, i = [], i + 2
            while i < len(lines) and lines[i].startswith('|'):
                rows.append(split_row(lines[i]))
                i += 1
            found.append((header, rows))
        else:
            i += 1
    return found


def table_with(text, first_header):
    matches = [t for t in tables(text) if t[0][0] == first_header or first_header in t[0]]
    assert matches, f'no table with column {first_header!r}'
    return matches[0]


def column(table, name):
    header, rows = table
    j = header.index(name)
    return [r[j] for r in rows]


def facts_by_where(text):
    header, rows = table_with(text, "paper's number")
    return [dict(zip(header, r)) for r in rows]


def numbers(text):
    return [float(x) for x in re.findall(r'-?\d+(?:\.\d+)?(?:e[+-]?\d+)?', text)]


# --- files and images -------------------------------------------------------------------

def png_size(path):
    data = path.read_bytes()[:24]
    assert data[:8] == b'\x89PNG\r\n\x1a\n' and data[12:16] == b'IHDR', f'{path} is not a PNG'
    return struct.unpack('>II', data[16:24])


def assert_drawn_image(path, size):
    assert png_size(path) == size
    with Image.open(path) as im:
        pixels = np.asarray(im.convert('L'), dtype=float)
    assert pixels.shape == (size[1], size[0])
    # not blank: many distinct grey levels, ink on a light background
    assert len(np.unique(pixels)) > 20 and pixels.std() > 10
    assert np.mean(pixels < 128) > 0.005


def test_reproduce_writes_every_file(reproduced):
    out, stdout, _ = reproduced
    names = {p.name for p in out.iterdir()}
    assert set(PAPER_FIGURES) | {'report.md', 'eq26.rrd'} <= names
    assert f'report: {out / "report.md"}' in stdout
    assert 'rerun ' + str(out / 'eq26.rrd') in stdout


@pytest.mark.parametrize('name', PAPER_FIGURES)
def test_paper_figures_are_drawn_images_of_640x480(reproduced, name):
    assert_drawn_image(reproduced[0] / name, (640, 480))


def test_reproduce_shows_numbered_progress(reproduced):
    stderr = reproduced[2]
    steps = re.findall(r'^\[reproduce (\d+)/(\d+)\] ', stderr, re.M)
    # the real rig beside the idealisation (issue 18), Eq. 26 beside planned spin-ups (19)
    assert [int(a) for a, _ in steps] == list(range(1, 11)) and {b for _, b in steps} == {'10'}
    assert stderr.count('done in') == 10 and 'Eq. 26 shape:' in stderr
    assert 'a real rig beside the idealisation' in stderr
    assert 'Eq. 26 beside 3 planned spin-ups' in stderr


def test_report_embeds_every_figure(reproduced):
    text = (reproduced[0] / 'report.md').read_text()
    for name in PAPER_FIGURES + tuple(REPORT_FIGURES):
        assert f']({name})' in text
    for name, size in REPORT_FIGURES.items():
        assert_drawn_image(reproduced[0] / name, size)


def test_planned_spin_ups_beside_eq26(reproduced):
    """Eq. 26's row against docs/model.md's closed forms; each plan within the paper's 3 mm,
    faster than Eq. 26, arriving at the static deflection plus at most its residual, and
    the acceleration bounds the rows name."""
    t = table_with((reproduced[0] / 'report.md').read_text(),
                   'spin-up, Table 1, 0 -> 2 rad/s, 3 mm')
    # cells: numbers, whirls in um ('0.254 um'), a plan's as the bound it meets ('<= 0.25 um')
    rows = {r[0]: [float(re.search(r'[0-9.eE+-]+', x.replace('<=', '')).group(0))
                   for x in r[1:]] for r in t[1]}
    eq26 = rows['Eq. 26 (the paper)']
    assert eq26[0] == 15.0 and eq26[1] == pytest.approx(2 * 2.0 / 15.0, abs=1e-3)  # 2W/T
    us = M * 4.0 * R0 / (M * W0**2 - M * 4.0)                   # static deflection, m
    assert eq26[2] == pytest.approx(1e3 * us, abs=5e-4)          # quasi-static spin-up
    # the whirl after Eq. 26 is the hold's ellipse, fitted to the simulated hold (Fig. 6)
    hold, = [f['measured now'] for f in facts_by_where((reproduced[0] / 'report.md').read_text())
             if f['where'] == 'Fig. 6 (15-20 s)' and 'ellipse' in f['measured now']]
    semi_major = float(re.search(r'ellipse ([0-9.]+) um x', hold).group(1))
    assert eq26[3] == pytest.approx(semi_major, abs=1.5e-3)
    for label, (d, _, p, r, b) in rows.items():
        assert p <= 3.0 and p >= 1e3 * us - 1e-4 and r <= 0.25 or label.startswith('Eq. 26')
        assert d < 15.0 or label.startswith('Eq. 26')
        assert b >= r
    assert rows["planned within the simulator's default bound (max_angular_acceleration 0.5)"
                ][1] <= 0.45 + 1e-3
    robust = rows['planned, config/planned.yaml (robust 0.1, max_angular_acceleration 0.5)']
    assert robust[1] <= 0.45 + 1e-3 and robust[4] <= 0.25 < eq26[4]    # the whole band


# --- report numbers vs docs/model.md ---------------------------------------------------------

def test_frequency_table_agrees_with_eq28_and_the_static_deflection(reproduced):
    t = table_with((reproduced[0] / 'report.md').read_text(), 'omega [rad/s]')
    omegas = [float(x) for x in column(t, 'omega [rad/s]')]
    assert 2.0 in omegas and 0.0 in omegas and len(omegas) >= 5
    for i, w in enumerate(omegas):
        f1, f2 = (W0 - w) / (2 * math.pi), (W0 + w) / (2 * math.pi)
        u_s = M * w**2 * R0 / (M * W0**2 - M * w**2)
        for name, expected in (('f1 Eq. 28 [Hz]', f1), ('f1 measured [Hz]', f1),
                               ('f2 Eq. 28 [Hz]', f2), ('f2 measured [Hz]', f2)):
            assert float(column(t, name)[i]) == pytest.approx(expected, abs=6e-7), (w, name)
        for name in ('u_s closed form [mm]', 'u_s measured [mm]'):
            assert float(column(t, name)[i]) == pytest.approx(1e3 * u_s, abs=6e-7), (w, name)
    k = omegas.index(2.0)
    assert (column(t, 'f1 Eq. 28 [Hz]')[k], column(t, 'f2 Eq. 28 [Hz]')[k]) == \
        ('1.613061', '2.249681')


def test_critical_speed_table_agrees_with_the_closed_forms(reproduced):
    text = (reproduced[0] / 'report.md').read_text()
    assert '3.0 mm limit' in text
    t = table_with(text, 'r0 [m]')
    r0s = [float(x) for x in column(t, 'r0 [m]')]
    assert 0.1 in r0s and 0.0 in r0s
    for i, r in enumerate(r0s):
        qs = W0 * math.sqrt(DELTA / (DELTA + r))
        step = W0 * math.sqrt(DELTA / (DELTA + 2 * r))
        imp = W0 * DELTA / (DELTA + r)
        assert float(column(t, 'quasi-static [rad/s]')[i]) == pytest.approx(qs, abs=6e-7)
        assert float(column(t, 'step [rad/s]')[i]) == pytest.approx(step, abs=6e-7)
        assert float(column(t, 'impulsive [rad/s]')[i]) == pytest.approx(imp, abs=6e-7)
        eq26 = column(t, 'Eq. 26 shape, numerical [rad/s]')[i]
        step_num = column(t, 'step from rest, numerical [rad/s]')[i]
        if r == 0:
            assert 'no deflection' in eq26 and 'no deflection' in step_num
        elif r >= 0.01:    # slow spin-up: quasi-static; sudden: Eq. 29's factor 2
            assert float(eq26) == pytest.approx(qs, rel=1e-3)
            assert float(step_num) == pytest.approx(step, rel=1e-3)
        else:              # near w0 the spin-up is no longer slow
            assert float(eq26) == pytest.approx(qs, rel=0.02)


def test_stage_extremes_are_the_papers(reproduced):
    t = table_with((reproduced[0] / 'report.md').read_text(), 'stage')
    rows = {r[0]: [float(x) for x in r[2:]] for r in t[1]}
    assert list(rows) == ['spin-up', 'hold', 'spin-down', 'rest']
    u_s = 1e3 * M * 4 * R0 / (M * W0**2 - M * 4)            # mm, w = 2 rad/s
    assert rows['spin-up'][1] == pytest.approx(2.79, rel=0.01)
    assert rows['spin-up'][2] == pytest.approx(-0.19, rel=0.03)
    assert rows['hold'][0] == pytest.approx(u_s, abs=1e-3) and rows['hold'][1] == \
        pytest.approx(u_s, abs=1e-3)
    assert rows['spin-down'][3] == pytest.approx(0.19, rel=0.03)
    assert max(abs(x) for x in rows['rest']) < 1e-3         # sub-micrometre


def test_fact_table_rows_match_model_md(reproduced):
    facts = facts_by_where((reproduced[0] / 'report.md').read_text())
    assert len(facts) >= 12
    assert all(f['verdict'].strip('*') in VERDICTS for f in facts)

    def row(where, word):
        found = [f for f in facts if f['where'].startswith(where) and word in f['the paper says']]
        assert len(found) == 1, (where, word)
        return found[0]

    u_s = 1e3 * M * 4 * R0 / (M * W0**2 - M * 4)
    hold = row('Fig. 6', 'centrifugal')
    assert f'{u_s:.4f} mm' == '2.7921 mm'
    assert f'= {u_s:.4f} mm at w = 2 rad/s' in hold['closed form (docs/model.md)']
    assert numbers(hold['measured now'])[-1] == pytest.approx(u_s, abs=1e-4)
    assert hold['verdict'] == '**agrees**'
    freq = row('Eq. 28', 'dynamic frequencies')
    assert '1.6131 Hz, 2.2497 Hz' in freq['measured now']
    ratio = numbers(row('Fig. 5', 'ten times')['measured now'])[-1]
    assert 10 <= ratio <= 20 and row('Fig. 5', 'ten times')['verdict'] == '**agrees**'
    assert row('Fig. 5', 'backwards')['verdict'] == '**agrees**'
    assert row('Fig. 7', 'forward')['verdict'] == '**agrees**'
    rest = row('Fig. 8', 'elliptical')
    assert f'{W0 / (2 * math.pi):.6f} Hz' in rest['measured now']
    assert rest['verdict'] == '**agrees**'
    petal = row('Fig. 6', 'petal')
    assert 'turning at -2.0000 rad/s' in petal['measured now']
    coupling = row('Eqs. 18-23', 'Q =')
    e_drift, l_drift = numbers(coupling['measured now'].split('Eq. 23 drifts')[1])[:2]
    assert e_drift == pytest.approx(4.3, abs=0.1) and l_drift == pytest.approx(2.2, abs=0.1)
    assert coupling['verdict'] == '**differs**'
    fig10 = row('Fig. 10', 'critical speed')
    assert fig10['verdict'] == '**agrees**' and 'decreasing: yes' in fig10['measured now']


def test_recording_loads_and_holds_the_eq26_run(reproduced):
    path = reproduced[0] / 'eq26.rrd'
    out = subprocess.run([*executable('rerun'), 'rrd', 'verify', str(path)],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 0 and '1 file verified without error' in out.stdout + out.stderr
    paths = set(recording.entity_paths(path))
    for entity in (recording.U, recording.V, recording.OMEGA, recording.TORQUE,
                   recording.F_MODEL, recording.ROTATING_TIP, recording.INERTIAL_TIP):
        assert '/' + entity in paths
    t, u = recording.read_series(path, recording.U)
    assert len(t) == 4001 and t[-1] == pytest.approx(40.0)
    hold = (t >= 15) & (t <= 20)
    u_s = M * 4 * R0 / (M * W0**2 - M * 4)
    assert np.mean(u[hold]) == pytest.approx(u_s, rel=1e-3)
    _, f = recording.read_series(path, recording.F_MODEL)
    assert f[hold][0] == pytest.approx([(W0 - 2) / (2 * math.pi), (W0 + 2) / (2 * math.pi)])


# --- errors ---------------------------------------------------------------------------

def unwritable_dirs(tmp_path):
    blocker = tmp_path / 'a_file'
    blocker.write_text('x')
    cases = [(blocker / 'out', 'cannot create the output directory')]
    if sys.platform.startswith('linux'):
        cases.append((Path('/proc/self'), 'cannot write to the output directory'))
    if os.geteuid() != 0:
        locked = tmp_path / 'locked'
        locked.mkdir(mode=0o500)
        cases.append((locked, 'cannot write to the output directory'))
    return cases


@pytest.mark.parametrize('command', ['reproduce', 'analyze'])
def test_unwritable_output_directory_is_a_clear_error(tmp_path, command):
    for path, message in unwritable_dirs(tmp_path):
        code, stdout, stderr = run_cli([command, '--out', str(path)])
        assert code == 2, (path, stderr)
        assert f'rotrod {command}: error: {message} {str(path)!r}' in stderr
        assert f'[{command} 1/' not in stderr          # refused before any work
        assert stdout == ''


def test_commands_are_headless(tmp_path):
    """A fresh interpreter with no display and a GUI backend asked for still draws."""
    env = dict(os.environ, MPLBACKEND='TkAgg', PYTHONPATH=str(ROOT))
    env.pop('DISPLAY', None)
    env.pop('WAYLAND_DISPLAY', None)
    out = subprocess.run([sys.executable, '-m', 'rotrod_core.cli', 'analyze', '--out',
                          str(tmp_path), '--only', 'coupling'], capture_output=True,
                         text=True, timeout=300, env=env)
    assert out.returncode == 0, out.stderr
    assert_drawn_image(tmp_path / 'coupling_drift.png', ANALYSIS_FIGURES['coupling_drift.png'])


# --- analyze ------------------------------------------------------------------------------

def test_analyze_writes_every_file(analyzed):
    out, stdout, stderr = analyzed
    for name, size in ANALYSIS_FIGURES.items():
        assert_drawn_image(out / name, size)
    for name in ('critical_speed_map.csv', 'coupling_drift.csv', 'analysis.md'):
        assert (out / name).stat().st_size > 0 and f'wrote {out / name}' in stdout
    assert re.findall(r'^\[analyze (\d)/4\]', stderr, re.M) == ['1', '2', '3', '4']


def test_campbell_bands(analyzed):
    t = table_with((analyzed[0] / 'analysis.md').read_text(), 'unstable bands [rad/s]')
    bands = dict(zip(column(t, 'case'), column(t, 'unstable bands [rad/s]')))
    # rectangular 4 x 3 mm: I = h b^3 / 12 about each axis
    k_radial = 3 * E * (0.003 * 0.004**3 / 12) / L_ROD**3
    k_tangential = 3 * E * (0.004 * 0.003**3 / 12) / L_ROD**3
    lo, hi = sorted([math.sqrt(k_radial / M), math.sqrt(k_tangential / M)])
    assert numbers(bands['rectangular 4 x 3 mm, undamped']) == \
        [pytest.approx(lo, abs=2e-6), pytest.approx(hi, abs=2e-6)]
    assert bands['circular d = 3 mm, undamped'] == 'none'
    start, end = numbers(bands['circular d = 3 mm, zeta = 0.02'])
    assert start == pytest.approx(W0, abs=2e-6) and end == 30.0    # to the sweep's end
    assert numbers(bands['rectangular 4 x 3 mm, zeta = 0.02'])[0] == pytest.approx(lo, abs=2e-6)


def test_exact_coupling_conserves_while_eq23_drifts(analyzed):
    path = analyzed[0] / 'coupling_drift.csv'
    header = path.read_text().splitlines()[0].split(',')
    data = np.loadtxt(path, delimiter=',', skiprows=1)
    col = {h: data[:, i] for i, h in enumerate(header)}
    assert col['t [s]'][-1] == pytest.approx(40.0)
    assert np.max(np.abs(col['exact angular momentum drift [-]'])) < 1e-12
    assert np.max(np.abs(col['exact energy drift [-]'])) < 1e-9
    paper_l = np.abs(col['paper angular momentum drift [-]'])
    paper_e = np.abs(col['paper energy drift [-]'])
    assert np.max(paper_l) == pytest.approx(0.022, abs=0.001)     # docs/model.md
    assert np.max(paper_e) == pytest.approx(0.043, abs=0.002)
    t = table_with((analyzed[0] / 'analysis.md').read_text(), 'coupling')
    assert float(column(t, 'max |L - L0| / L0')[1]) == pytest.approx(np.max(paper_l), rel=1e-3)


def test_critical_map_values(analyzed):
    path = analyzed[0] / 'critical_speed_map.csv'
    data = np.loadtxt(path, delimiter=',', skiprows=1)
    r0, d, qs, step, imp, eq26 = data.T
    assert np.any(np.isclose(d, DELTA)) and len(data) >= 100
    assert qs == pytest.approx(W0 * np.sqrt(d / (d + r0)), rel=1e-8)
    assert step == pytest.approx(W0 * np.sqrt(d / (d + 2 * r0)), rel=1e-8)
    assert imp == pytest.approx(W0 * d / (d + r0), rel=1e-8)
    assert np.max(np.abs(eq26 / qs - 1)) < 0.01
    # the numerical critical speed depends on delta / r0 only
    ratio = np.round(np.log2(d / r0) * 3).astype(int)
    for k in np.unique(ratio):
        same = eq26[ratio == k]
        assert np.ptp(same) <= 1e-3 * same.mean()


# --- docs -----------------------------------------------------------------------------------

def same_text_and_numbers(a, b):
    """Equal text; numbers equal to their last printed digit, or both at rounding level."""
    pat = r'-?\d+(?:\.\d+)?(?:e[+-]?\d+)?'
    if re.sub(pat, '#', a) != re.sub(pat, '#', b):
        return False
    for x, y in zip(re.findall(pat, a), re.findall(pat, b)):
        fx, fy = float(x), float(y)
        mant = x.split('e')[0]
        ulp = 10.0 ** -(len(mant.split('.')[1]) if '.' in mant else 0)
        if 'e' in x:
            ulp *= 10.0 ** int(x.split('e')[1])
        if not (abs(fx - fy) <= 1.01 * ulp or max(abs(fx), abs(fy)) < 1e-9):
            return False
    return True


PLANNER_SPREAD: dict[int, float] = {}
"""Columns of the spin-up table that a planned row may fill differently on other CPUs,
with the relative spread allowed. None since the planner decides durations by a
converged minimax value: its rows are equal to the printed digit under the OpenBLAS
kernels tried (docs/planner.md#limits-and-doubts)."""


PLANNER_FIGURES = {'spin_ups.png'}
"""Figures that draw the planner's plans: their shapes move with the CPU's arithmetic
(docs/planner.md#limits-and-doubts), so they are checked as drawn, not pixel by pixel."""


def same_within(a, b, spread):
    """Equal text; every number within ``spread`` (relative) of the other."""
    pat = r'-?\d+(?:\.\d+)?(?:e[+-]?\d+)?'
    if re.sub(pat, '#', a) != re.sub(pat, '#', b):
        return False
    return all(abs(float(x) - float(y)) <= spread * max(abs(float(x)), abs(float(y)))
               for x, y in zip(re.findall(pat, a), re.findall(pat, b)))


def assert_same_table(documented, generated, where):
    assert documented[0] == generated[0], where
    assert len(documented[1]) == len(generated[1]), where
    planned = documented[0][0].startswith('spin-up, ')
    for d, g in zip(documented[1], generated[1]):
        for k, (dc, gc) in enumerate(zip(d, g)):
            if planned and d[0].startswith('planned') and k in PLANNER_SPREAD:
                assert same_within(dc, gc, PLANNER_SPREAD[k]), (where, dc, gc)
            else:
                assert same_text_and_numbers(dc, gc), (where, dc, gc)


def test_docs_tables_are_the_ones_the_commands_generate(reproduced, analyzed):
    """docs/reproduce.md and docs/figures/*.md hold today's numbers (else: regenerate)."""
    generated = (tables((reproduced[0] / 'report.md').read_text())
                 + tables((analyzed[0] / 'analysis.md').read_text()))
    by_header = {tuple(h): (h, rows) for h, rows in generated}
    page = tables((DOCS / 'reproduce.md').read_text())
    shown = [t for t in page if t[0][0] != 'command'       # the command table is prose
             and any(t[0])]                                  # the gallery has no header
    assert len(shown) == 9                     # with the fact table and the spin-ups
    for table in shown:
        assert tuple(table[0]) in by_header, table[0]
        assert_same_table(table, by_header[tuple(table[0])], 'docs/reproduce.md')
    for name, fresh in (('report.md', reproduced[0]), ('analysis.md', analyzed[0])):
        documented = tables((DOCS / 'figures' / name).read_text())
        new = tables((fresh / name).read_text())
        assert len(documented) == len(new), name
        for d, g in zip(documented, new):
            assert_same_table(d, g, f'docs/figures/{name}')
    facts = facts_by_where((DOCS / 'reproduce.md').read_text())
    assert len(facts) == len(facts_by_where((reproduced[0] / 'report.md').read_text()))


def test_docs_figures_are_the_ones_the_commands_draw(reproduced, analyzed):
    """Every figure docs/reproduce.md shows is in docs/figures and looks like a fresh one."""
    text = (DOCS / 'reproduce.md').read_text()
    linked = re.findall(r'!\[[^\]]*\]\(figures/([^)]+\.png)\)', text)
    assert len(linked) >= 6
    sizes = dict.fromkeys(PAPER_FIGURES, (640, 480)) | ANALYSIS_FIGURES | REPORT_FIGURES
    for name in linked:
        assert_drawn_image(DOCS / 'figures' / name, sizes[name])
        fresh = (analyzed[0] if name in ANALYSIS_FIGURES else reproduced[0]) / name
        if name in PLANNER_FIGURES:     # drawn from plans: their shapes move with the CPU
            continue
        with Image.open(DOCS / 'figures' / name) as a, Image.open(fresh) as b:
            diff = np.abs(np.asarray(a.convert('L'), float) - np.asarray(b.convert('L'), float))
        assert diff.mean() < 2.0, f'docs/figures/{name} is stale: rerun the command'
    total = sum(p.stat().st_size for p in (DOCS / 'figures').iterdir())
    assert total < 1.5e6
    assert 'rotrod reproduce --out docs/figures' in text and \
        'rotrod analyze --out docs/figures' in text
