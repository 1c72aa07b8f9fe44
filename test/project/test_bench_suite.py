"""bench/run_all.py without running the benches: rewriting docs/performance.md, the table."""

import importlib.util
import math
import shutil
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]


def _load(name):
    sys.path.insert(0, str(ROOT / 'bench'))
    try:
        spec = importlib.util.spec_from_file_location(f'bench_{name}', ROOT / 'bench'
                                                      / f'{name}.py')
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    finally:
        sys.path.remove(str(ROOT / 'bench'))
    return module


run_all = _load('run_all')
results = run_all.results          # bench/results.py, as run_all uses it
Row, Target, Comparison = results.Row, results.Target, results.Comparison


def rows():
    return [
        Row('core', 'stepper cost', 6.5, 'us', target=Target('<=', 10)),
        Row('core', 'speed', 4.0, 'ms', target=Target('>=', 5, on='ratio'),
            comparisons=[Comparison('solve_ivp', 80.0)]),
        Row('realtime', 'lag', 2.8, 'ms', target=Target('<=', 2), note='p99 0.7 ms'),
        Row('estimator', 'misses', 0, 'NaN', target=Target('<=', 0, text='none'),
            comparisons=[Comparison('FFT', 3), Comparison('ESPRIT', math.nan, 'all NaN')]),
        Row('realtime', 'speed', 30.0, 'x real time', better='higher'),
    ]


def stamp():
    s = run_all.machine_stamp('.venv/bin/python bench/run_all.py --quick', (0.5, 1.0, 1.5))
    s['run time'] = '3 s'
    return s


def test_readme_block_is_rewritten_in_place(tmp_path):
    readme = tmp_path / 'README.md'
    shutil.copy(ROOT / 'docs' / 'performance.md', readme)
    original = readme.read_text()
    assert original.count(run_all.BEGIN) == 1 and original.count(run_all.END) == 1
    before = original[:original.index(run_all.BEGIN) + len(run_all.BEGIN)]
    after = original[original.index(run_all.END):]

    block = run_all.build_block(rows(), stamp(), ('a note',))
    run_all.rewrite_file(readme, block)
    new = readme.read_text()
    assert new.startswith(before) and new.endswith(after)       # outside: untouched
    inside = new[len(before):len(new) - len(after)]
    assert inside == '\n' + block + '\n'
    for key in ('date', 'machine', 'load average at start', 'command', 'packages'):
        assert f'- {key}: ' in inside
    assert ' UTC' in inside and 'numpy ' in inside and '0.50, 1.00, 1.50' in inside
    assert '`.venv/bin/python bench/run_all.py --quick`' in inside
    assert '| realtime | lag | 2.8 ms (p99 0.7 ms) | <= 2 ms | **NO** |' in inside
    assert 'solve_ivp: 80 ms, ratio 20' in inside
    assert 'Targets not met: 1 of 4: realtime: lag: 2.8 ms (target <= 2 ms).' in inside

    # a second run replaces the first block, not adds to it
    run_all.rewrite_file(readme, 'second')
    assert readme.read_text() == before + '\nsecond\n' + after


def test_the_performance_page_has_one_block_and_the_readme_links_it():
    text = (ROOT / 'docs' / 'performance.md').read_text()
    assert text.count(run_all.BEGIN) == 1 and text.count(run_all.END) == 1
    assert '(docs/performance.md)' in (ROOT / 'README.md').read_text()


@pytest.mark.parametrize('text, message', [
    ('no markers at all\n', 'occurs 0 times'),
    (f'{run_all.BEGIN}\n{run_all.END}\n{run_all.BEGIN}\n', 'occurs 2 times'),
    (f'{run_all.END}\nx\n{run_all.BEGIN}\n', 'comes before'),
    (f'text {run_all.BEGIN}\n{run_all.END}\n', 'line of its own'),
    (f'{run_all.BEGIN}\n', 'occurs 0 times'),
])
def test_rewrite_refuses_bad_markers(text, message):
    with pytest.raises(ValueError, match=message):
        run_all.rewrite(text, 'block')


@pytest.mark.parametrize('change', [
    {'value': None}, {'value': math.nan}, {'value': math.inf}, {'value': '6.5'},
    {'value': True}, {'unit': ''}, {'name': ' '}, {'bench': ''},
    {'target': Target('<=', None)}, {'target': Target('<', 1)},
    {'target': Target('>=', 5, on='ratio')},                    # a ratio never measured
    {'comparisons': [Comparison('baseline', None)]},
    {'comparisons': [Comparison('baseline', math.nan)]},       # NaN without a note
    {'better': 'smaller'},
])
def test_table_builder_rejects_missing_values(change):
    good = rows()
    assert run_all.build_table(good)                           # the good rows pass
    bad = Row(**{**results.to_dict(good[0]), **change})
    with pytest.raises(ValueError):
        run_all.build_table([*good, bad])
    with pytest.raises(ValueError):
        run_all.build_block([*good, bad], stamp())


def test_table_builder_rejects_an_empty_table_and_an_incomplete_stamp():
    with pytest.raises(ValueError, match='no benchmark rows'):
        run_all.build_table([])
    for key in ('date', 'machine', 'load average at start', 'command', 'run time'):
        s = stamp()
        s[key] = ''
        with pytest.raises(ValueError, match=key):
            run_all.build_block(rows(), s)


def test_met_and_ratios_are_computed_from_the_values():
    r = rows()
    assert [x.met for x in r] == [True, True, False, True, None]
    assert r[1].ratio(r[1].comparisons[0]) == pytest.approx(20.0)      # lower is better
    assert r[4].ratio(Comparison('loop', 10.0)) == pytest.approx(3.0)  # higher is better
    assert r[3].ratio(r[3].comparisons[0]) is None                     # value 0


def test_rows_survive_the_json_round_trip(tmp_path):
    path = tmp_path / 'rows.json'
    results.dump(path, rows(), extra=1)
    back = results.load(path)
    assert run_all.build_table(back) == run_all.build_table(rows())


def test_run_all_stops_before_writing_when_a_bench_writes_no_results(tmp_path, monkeypatch):
    readme = tmp_path / 'README.md'
    readme.write_text(f'keep\n{run_all.BEGIN}\nold\n{run_all.END}\nkeep\n')

    def failing(script, args, json_path, timeout):
        raise RuntimeError(f'{script} wrote no results')
    monkeypatch.setattr(run_all, 'run_bench', failing)
    with pytest.raises(RuntimeError):
        run_all.main(['--page', str(readme)])
    assert readme.read_text() == f'keep\n{run_all.BEGIN}\nold\n{run_all.END}\nkeep\n'


def test_run_all_end_to_end_with_stand_in_benches(tmp_path, monkeypatch, capsys):
    readme = tmp_path / 'README.md'
    shutil.copy(ROOT / 'docs' / 'performance.md', readme)
    original = readme.read_text()
    calls = []

    def stand_in(script, args, json_path, timeout):
        calls.append((script, args))
        results.dump(json_path, rows(), simulator_code='/x/rotrod_ros/simulator.py',
                     rmw='rmw_test', isolation='netns')
        return results.load(json_path)
    monkeypatch.setattr(run_all, 'run_bench', stand_in)

    assert run_all.main(['--quick', '--page', str(readme)]) == 1   # a target not met
    assert readme.read_text() == original                            # --quick: not written
    assert [c[0] for c in calls] == ['bench_core.py', 'bench_sweep.py', 'bench_estimator.py',
                                     'bench_planner.py', 'bench_identify.py',
                                     'bench_realtime.py', 'bench_fleet.py']
    assert calls[0][1] == ['--quick'] and calls[1][1] == ['--quick']
    assert calls[4][1] == ['--seeds', '10', '--eq26-seeds', '3']
    assert calls[5][1] == ['--duration', '5']
    assert calls[6][1] == ['--duration', '5', '--rods', '3', '--large-rods', '10']

    assert run_all.main(['--quick', '--write', '--page', str(readme)]) == 1
    new = readme.read_text()
    out = capsys.readouterr().out
    block = new[new.index(run_all.BEGIN) + len(run_all.BEGIN):new.index(run_all.END)]
    assert block.strip() in out
    assert '`.venv/bin/python bench/run_all.py --quick --write --page' in block
    assert 'rmw_test' in block and 'quick run' in block and '- run time: ' in block
    assert new[:new.index(run_all.BEGIN)] == original[:original.index(run_all.BEGIN)]
    assert new[new.index(run_all.END):] == original[original.index(run_all.END):]
