"""Sweeps: grids and tables, simulate_batch on a Dask client, failures, rotrod sweep.

Local clusters here listen on 127.0.0.1 only (processes), or have no network at all
(processes=False, in-process transport).
"""

import json
import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import psutil
import pytest

from rotrod_core import Eq26Profile, NonFiniteStateError, RodParams, simulate_batch
from rotrod_core.offline import sweep
from rotrod_core.offline.batch import BLOCK

ROOT = Path(__file__).resolve().parents[3]
pq = pytest.importorskip('pyarrow.parquet')
pytest.importorskip('distributed')


def test_grid_axes_ranges_lists_and_the_product():
    table = sweep.grid_table(['eccentricity=0.0:0.01:5', 'damping_ratio=0,0.01'])
    assert np.allclose(table['eccentricity'], np.repeat([0, 0.0025, 0.005, 0.0075, 0.01], 2))
    assert np.allclose(table['damping_ratio'], [0, 0.01] * 5)
    one = sweep.grid_table(['eccentricity_m=0.12', 'mass_kg=0.2:0.4:3'])
    assert list(one) == ['eccentricity', 'mass'] and np.allclose(one['mass'], [0.2, 0.3, 0.4])


@pytest.mark.parametrize('spec, message', [
    (['colour=1'], 'unknown parameter'),
    (['eccentricity=0:1'], 'START:STOP:COUNT'),
    (['eccentricity=0:1:2.5'], 'whole number'),
    (['eccentricity=0:1:0'], 'whole number'),
    (['mass=abc'], 'not a number'),
    (['mass=nan'], 'finite'),
    (['mass'], 'NAME='),
    (['mass=1', 'mass_kg=2'], 'twice'),
    ([], 'at least one axis'),
])
def test_bad_grids_are_refused(spec, message):
    with pytest.raises(ValueError, match=message):
        sweep.grid_table(spec)


def test_a_csv_of_parameter_sets(tmp_path):
    path = tmp_path / 'sets.csv'
    path.write_text('eccentricity_m,damping_ratio\n0.1,0\n0.2,0.01\n\n')
    table = sweep.read_table(path)
    assert np.allclose(table['eccentricity'], [0.1, 0.2])
    assert np.allclose(table['damping_ratio'], [0, 0.01])
    path.write_text('eccentricity,damping_ratio\n0.1\n')
    with pytest.raises(ValueError, match='line 2'):
        sweep.read_table(path)


def _collect(table, **kwargs):
    chunks = []
    summary = sweep.run_sweep(table, Eq26Profile(), 10.0, on_chunk=chunks.append, **kwargs)
    rows = {}
    for c in chunks:
        for pos, i in enumerate(c.index):
            rows[int(i)] = ({k: v[pos] for k, v in c.results.items()}, c.status[pos],
                            {k: v[pos] for k, v in c.parameters.items()})
    return summary, rows


def test_a_sweep_equals_simulate_batch_and_reports_invalid_sets():
    table = {'eccentricity': np.linspace(0.02, 0.2, 12),
             'damping_ratio': np.tile([0.0, 0.01, 0.0], 4),
             'mass': np.array([0.3] * 5 + [-1.0] + [0.3] * 6)}
    table['rod_diameter'] = np.where(np.arange(12) >= 8, 0.0, 0.003)    # a whole bad chunk
    summary, rows = _collect(table, chunk_size=4)
    assert summary.runs == 12 and summary.ok == 7 and summary.chunks == 3
    bad = {i: status for i, _, status in summary.problems}
    assert sorted(bad) == [5, 8, 9, 10, 11]
    assert 'mass' in bad[5] and bad[5].startswith('invalid:')
    assert 'rod_diameter' in bad[8]
    assert summary.problems[0][1]['mass'] == -1.0          # the offending set, as given
    good = [i for i in range(12) if i not in bad]
    ref = simulate_batch(RodParams(eccentricity=table['eccentricity'][good],
                                   damping_ratio=table['damping_ratio'][good]),
                         Eq26Profile(), 10.0)
    for k, i in enumerate(good):
        res, status, params = rows[i]
        assert status == 'ok' and params['hub_inertia'] == RodParams().hub_inertia
        assert res['peak_deflection'] == pytest.approx(ref.peak_deflection[k], abs=1e-15)
        assert res['final_u'] == pytest.approx(ref.final.u[k], abs=1e-15)
    assert np.isnan(rows[5][0]['peak_deflection']) and rows[5][2]['mass'] == -1.0


def test_a_chunk_that_fails_is_reported_and_the_rest_completes(monkeypatch):
    real = sweep.velocity_chunk

    def failing(co, *args):
        if np.any(np.asarray(co.eccentricity) > 0.15):
            raise NonFiniteStateError('the run became non-finite')
        return real(co, *args)
    monkeypatch.setattr(sweep, 'velocity_chunk', failing)
    summary, rows = _collect({'eccentricity': np.linspace(0.05, 0.2, 6)}, chunk_size=3)
    assert summary.ok == 3
    assert [i for i, _, _ in summary.problems] == [3, 4, 5]
    assert all(s == 'failed: the run became non-finite' for _, _, s in summary.problems)


def test_simulate_batch_on_a_client_comes_back_in_input_order():
    n = 2 * BLOCK + 300
    p = RodParams(eccentricity=np.linspace(0.02, 0.2, n),
                  damping_ratio=np.where(np.arange(n) % 5 == 0, 0.01, 0.0))
    local = simulate_batch(p, Eq26Profile(), 5.0, output_interval=0.5)
    with sweep.SweepClient(None, workers=2, processes=False) as client:
        whole = simulate_batch(p, Eq26Profile(), 5.0, output_interval=0.5, client=client)
        odd = simulate_batch(p, Eq26Profile(), 5.0, output_interval=0.5, client=client,
                             chunk_size=700)
        rk4 = simulate_batch(p, Eq26Profile(), 1.0, method='rk4', client=client,
                             chunk_size=900)
    # whole blocks per task: bit for bit the local run
    for name in ('peak_deflection', 'peak_time'):
        assert np.array_equal(getattr(local, name), getattr(whole, name))
    assert np.array_equal(local.u, whole.u) and np.array_equal(local.final.dv, whole.final.dv)
    # other chunks: the same runs in the same order, to rounding
    assert np.allclose(local.u, odd.u, rtol=0, atol=1e-15)
    assert np.allclose(local.peak_deflection, odd.peak_deflection, rtol=0, atol=1e-15)
    one = simulate_batch(p, Eq26Profile(), 1.0, method='rk4')
    assert np.array_equal(one.final.u, rk4.final.u)


def test_a_worker_killed_mid_sweep_does_not_lose_the_sweep():
    n = 3000
    table = {'eccentricity': np.linspace(0.02, 0.2, n), 'damping_ratio': np.full(n, 0.01)}
    killed = {}
    with sweep.SweepClient(None, workers=2, processes=True) as client:
        pids = client.run(os.getpid)
        # scheduler, nannies and workers listen on the loopback interface only
        listening = [c.laddr.ip for proc in [psutil.Process(), *psutil.Process().children(
            recursive=True)] for c in proc.net_connections('inet') if c.status == 'LISTEN']
        assert listening and set(listening) == {'127.0.0.1'}
        assert all(a.startswith('tcp://127.0.0.1:') for a in client.scheduler_info()['workers'])

        def on_chunk(chunk):
            if killed:
                return
            busy = [w for w, keys in client.processing().items() if keys]
            assert busy, 'no task was running when the worker was to be killed'
            killed['pid'] = pids[busy[0]]
            os.kill(killed['pid'], signal.SIGKILL)
        chunks = []

        def both(chunk):
            chunks.append(chunk)
            on_chunk(chunk)
        summary = sweep.run_sweep(table, Eq26Profile(), 10.0, client=client, chunk_size=100,
                                  on_chunk=both)
        alive = set(client.run(os.getpid).values())
    assert killed['pid'] not in alive                      # the worker did die
    assert summary.ok == n and not summary.problems        # and no row was lost
    index = np.concatenate([c.index for c in chunks])
    assert np.array_equal(np.sort(index), np.arange(n))
    peak = np.empty(n)
    for c in chunks:
        peak[c.index] = c.results['peak_deflection']
    ref = simulate_batch(RodParams(eccentricity=table['eccentricity'], damping_ratio=0.01),
                         Eq26Profile(), 10.0)
    assert np.allclose(peak, ref.peak_deflection, rtol=0, atol=1e-15)


def test_rotrod_sweep_writes_every_row_to_parquet(tmp_path):
    out = tmp_path / 'sweep.parquet'
    cmd = [sys.executable, '-m', 'rotrod_core.cli', 'sweep', '--grid',
           'eccentricity=0.05:0.15:3', 'damping_ratio=0,0.01', 'mass=0.3,-1', '--t-end', '5',
           '--workers', '2', '--chunk-size', '4', '-o', str(out)]
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    proc = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=120)
    assert proc.returncode == 1, proc.stderr           # some sets are invalid
    assert 'invalid: RodParams.mass must be a finite number > 0' in proc.stderr
    assert '100.0 %' in proc.stderr and f'wrote {out}' in proc.stdout
    assert not out.with_name(out.name + '.partial').exists()
    table = pq.read_table(out).to_pydict()
    order = np.argsort(table['run_index'])
    assert np.array_equal(np.asarray(table['run_index'])[order], np.arange(12))
    status = np.asarray(table['status'])[order]
    mass = np.asarray(table['mass_kg'])[order]
    assert np.all((status == 'ok') == (mass > 0))
    peak = np.asarray(table['peak_deflection_m'])[order]
    ok = status == 'ok'
    ref = simulate_batch(RodParams(eccentricity=np.asarray(table['eccentricity_m'])[order][ok],
                                   damping_ratio=np.asarray(table['damping_ratio'])[order][ok]),
                         Eq26Profile(), 5.0)
    assert np.allclose(peak[ok], ref.peak_deflection, rtol=0, atol=1e-15)
    assert np.all(np.isnan(peak[~ok]))
    meta = json.loads(pq.read_schema(out).metadata[b'rotrod.sweep'])
    assert meta['units']['peak_deflection_m'] == 'm' and meta['t_end_s'] == 5.0


def test_rotrod_sweep_refuses_bad_input(tmp_path, capsys):
    from rotrod_core.cli import main
    assert main(['sweep', '--grid', 'colour=1', '-o', str(tmp_path / 'a.parquet')]) == 2
    assert 'unknown parameter' in capsys.readouterr().err
    assert main(['sweep', '--grid', 'mass=0.3', '-o', str(tmp_path / 'a.csv')]) == 2
    assert 'must end in .parquet' in capsys.readouterr().err
    assert main(['sweep', '-o', str(tmp_path / 'a.parquet')]) == 2
    assert '--grid' in capsys.readouterr().err
