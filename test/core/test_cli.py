import re
import subprocess
import sys

import numpy as np
import pytest

from rotrod_core.cli import main


def test_simulate_writes_csv_with_units(tmp_path, capsys):
    out = tmp_path / 'run.csv'
    assert main(['simulate', '--profile', 'constant', '--omega', '2', '--t-end', '5',
                 '-o', str(out)]) == 0
    header = out.read_text().splitlines()[0]
    assert header.startswith('t [s],u [m],v [m],du [m/s],dv [m/s],theta [rad],omega [rad/s]')
    data = np.loadtxt(out, delimiter=',', skiprows=1)
    assert data.shape == (5001, 11)
    assert data[-1, 6] == pytest.approx(2.0)
    assert 'wrote' in capsys.readouterr().out


def test_simulate_torque_drive_to_npz(tmp_path):
    out = tmp_path / 'spin.npz'
    assert main(['simulate', '--drive', 'torque', '--torque', '0.05', '--t-end', '2',
                 '--coupling', 'paper', '--initial', 'omega=1', 'u=0.001', '-o', str(out)]) == 0
    with np.load(out) as z:
        assert z['omega'][-1] > 1.0 and str(z['coupling']) == 'paper'
        assert z['u'][0] == 0.001


def test_simulate_with_parameter_overrides_and_table(tmp_path):
    table = tmp_path / 'w.csv'
    table.write_text('0,0\n2,1\n4,1\n')
    out = tmp_path / 'r.csv'
    assert main(['simulate', '--profile', 'table', '--table', str(table), '--mass', '0.5',
                 '--eccentricity', '0.2', '--t-end', '4', '-o', str(out)]) == 0


@pytest.mark.parametrize('argv, message', [
    (['simulate', '--mass', '-1', '-o', 'x.csv'], 'mass'),
    (['simulate', '--profile', 'table', '-o', 'x.csv'], '--table'),
    (['simulate', '--drive', 'torque', '-o', 'x.csv'], '--torque'),
    (['simulate', '--torque', '1', '-o', 'x.csv'], '--drive torque'),
    (['simulate', '-o', 'x.txt'], '.csv or .npz'),
    (['simulate', '-o', '/nonexistent/dir/x.csv'], 'does not exist'),
    (['simulate', '--initial', 'u', '-o', 'x.csv'], 'NAME=VALUE'),
    (['simulate', '--section', 'rectangular', '-o', 'x.csv'], 'section_width'),
])
def test_simulate_bad_arguments_give_clear_errors(argv, message, capsys, tmp_path,
                                                  monkeypatch):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err and 'error' in err


@pytest.mark.parametrize('argv', [['simulate', '--dt', 'nan', '-o', 'x.csv'],
                                  ['simulate', '--profile', 'zigzag', '-o', 'x.csv'],
                                  ['bogus']])
def test_argparse_rejects_malformed_values(argv):
    with pytest.raises(SystemExit) as e:
        main(argv)
    assert e.value.code == 2


def test_frequencies_and_critical_speed_commands(capsys):
    assert main(['frequencies', '--omega', '2']) == 0
    assert '1.613061' in capsys.readouterr().out
    assert main(['critical-speed', '--eccentricities', '0.1']) == 0
    out = capsys.readouterr().out
    assert '2.071036' in out and '1.475225' in out


def test_console_script_is_installed():
    exe = subprocess.run([sys.executable, '-m', 'rotrod_core.cli', '--help'],
                         capture_output=True, text=True)
    assert exe.returncode == 0 and 'simulate' in exe.stdout


def test_plan_writes_csv_figure_and_summary(tmp_path, capsys):
    out = tmp_path / 'plan.csv'
    assert main(['plan', '--omega', '2', '--max-angular-acceleration', '3', '-o', str(out)]) == 0
    lines = out.read_text().splitlines()
    assert lines[0] == 't_s,omega_rad_s,omega_dot_rad_s2,u_m,v_m'
    data = np.loadtxt(out, delimiter=',', skiprows=1)
    assert data[0, 1] == 0 and data[-1, 1] == pytest.approx(2.0)
    assert np.max(np.abs(data[:, 2])) <= 3.0 + 1e-9
    assert np.max(np.hypot(data[:, 3], data[:, 4])) <= 3e-3
    assert (tmp_path / 'plan.png').read_bytes()[:8] == b'\x89PNG\r\n\x1a\n'
    summary = capsys.readouterr().out
    assert 'duration' in summary and 'peak' in summary and 'residual' in summary


def test_plan_refusal_is_a_clear_error(tmp_path, capsys):
    assert main(['plan', '--omega', '2', '--deflection-limit', '0.002',
                 '-o', str(tmp_path / 'p.csv')]) == 2
    assert 'static deflection' in capsys.readouterr().err


@pytest.mark.parametrize('argv, omega_end', [
    (['--profile', 'eq26', '--period', '3', '--omega-target', '1.5'], 0.0),
    (['--profile', 'constant', '--omega', '1.5'], 1.5),
    (['--profile', 'step', '--omega-target', '1.5', '--omega-start', '0.5', '--t-step', '1'],
     1.5),
    (['--profile', 'ramp', '--omega-target', '1.5', '--ramp-time', '2', '--t-start', '1'],
     1.5),
    # w = offset + amplitude sin(2 pi (f_start t + (f_end - f_start) t^2 / (2 T))) for
    # t <= T (here the phase at T is 2 pi x 3: back to the offset)
    (['--profile', 'sine_sweep', '--amplitude', '0.3', '--f-start', '1', '--f-end', '2',
      '--sweep-time', '4', '--offset', '1'], 1.0),
    (['--profile', 'table'], 1.0),
    (['--profile', 'planned', '--omega', '1.5', '--max-angular-acceleration', '2'], 1.5),
])
def test_simulate_runs_every_profile(argv, omega_end, tmp_path):
    from rotrod_core.command.registry import OPTION_PROFILES
    table = tmp_path / 'w.csv'
    table.write_text('0,0\n2,1\n4,1\n')
    if argv[-1] == 'table':
        argv = [*argv, '--table', str(table)]
    out = tmp_path / 'run.csv'
    assert main(['simulate', *argv, '--t-end', '9', '-o', str(out)]) == 0
    data = np.loadtxt(out, delimiter=',', skiprows=1)
    t, omega = data[:, 0], data[:, 6]
    assert omega[-1] == pytest.approx(omega_end, abs=1e-9)
    assert argv[1] in OPTION_PROFILES
    if argv[1] == 'sine_sweep':
        tt = t[t <= 4.0]
        phase = 2 * np.pi * (1.0 * tt + (2.0 - 1.0) * tt**2 / (2 * 4.0))
        assert np.max(np.abs(omega[t <= 4.0] - (1.0 + 0.3 * np.sin(phase)))) < 1e-9


def test_every_registered_profile_has_a_cli_test():
    from rotrod_core.command.profiles import PROFILES
    from rotrod_core.command.registry import OPTION_PROFILES
    tested = {argv[1] for argv, _ in test_simulate_runs_every_profile.pytestmark[0].args[1]}
    assert tested == set(OPTION_PROFILES)
    # spin_up is the class of `rotrod plan` and of `planned`, tested above and below
    assert set(PROFILES) - tested == {'spin_up'}


def test_simulate_planned_arrives_without_whirl_under_its_bounds(tmp_path, capsys):
    """The planned profile offline: |w'| within 0.9 x the bound, |r| under the limit, and
    the motion after arrival a free whirl about docs/model.md's static deflection no larger
    than the residual asked for."""
    from reference import R0, W0, K, M
    out = tmp_path / 'planned.csv'
    assert main(['simulate', '--profile', 'planned', '--omega', '2', '--max-angular-acceleration',
                 '2', '--deflection-limit', '0.003', '--residual', '2.5e-7', '--t-end', '12',
                 '--dt', '0.002', '-o', str(out)]) == 0
    said = capsys.readouterr().out
    duration = float(re.search(r'duration ([0-9.]+) s', said).group(1))
    assert 'planned 0 -> 2 rad/s after 3 s at the start speed' in said
    data = np.loadtxt(out, delimiter=',', skiprows=1)
    t, u, v, omega, omega_dot = data[:, 0], data[:, 1], data[:, 2], data[:, 6], data[:, 7]
    assert np.all(omega[t <= 3.0] == 0.0)                    # the lead: at rest
    assert np.max(np.abs(omega_dot)) <= 0.9 * 2.0 + 1e-9
    assert np.max(np.hypot(u, v)) <= 3e-3
    after = t >= 3.0 + duration
    assert np.all(omega[after] == pytest.approx(2.0, abs=1e-12))
    us = M * 4.0 * R0 / (K - M * 4.0)                         # static deflection at 2 rad/s
    # free whirl about it: z - us = A e^{i (w0 - w) t} + B e^{-i (w0 + w) t}
    tt = t[after] - t[after][0]
    basis = np.column_stack([np.exp(1j * (W0 - 2.0) * tt), np.exp(-1j * (W0 + 2.0) * tt)])
    z = u[after] + 1j * v[after] - us
    coef, *_ = np.linalg.lstsq(basis, z, rcond=None)
    assert np.max(np.abs(z - basis @ coef)) < 1e-9          # nothing but the two whirls
    assert abs(coef[0]) + abs(coef[1]) <= 2.5e-7


def test_offline_demo_of_the_planned_spin_up(tmp_path, capsys):
    assert main(['demo', '--offline', '--profile', 'planned', '--out', str(tmp_path)]) == 0
    out = capsys.readouterr().out
    assert 'config/planned.yaml' in out and 'duration' in out
    data = np.loadtxt(tmp_path / 'planned_run.csv', delimiter=',', skiprows=1)
    assert data[0, 6] == 0.0 and data[-1, 6] == 2.0
