"""The disk cache of planned spin-ups (rotrod_core.command.plan_cache)."""

import json
import os

import numpy as np
import pytest

from rotrod_core import RodParams, plan_spin_up
from rotrod_core.command import plan_cache
from rotrod_core.command.profiles import SpinUpProfile

FIELDS = ('duration', 'peak_deflection', 'residual_amplitude', 'band_residual', 'robust',
          't_start')


@pytest.fixture
def cache(tmp_path, monkeypatch):
    folder = tmp_path / 'plans'
    monkeypatch.setenv(plan_cache.ENV, str(folder))
    return folder


def a_plan(duration=1.25):
    return SpinUpProfile(duration, [0.0, 0.0, 0.7 + 1e-16, 1.3, 2.0, 2.0],
                         peak_deflection=2.9e-3, residual_amplitude=1.1e-7,
                         band_residual=2.2e-7, robust=0.1, t_start=0.5)


def counted(result):
    calls = []

    def plan():
        calls.append(1)
        if isinstance(result, Exception):
            raise result
        return result
    return plan, calls


def same(a, b):
    assert np.array_equal(a.control_points, b.control_points)
    for name in FIELDS:
        assert getattr(a, name) == getattr(b, name), name


def test_a_request_is_planned_once_and_read_back_to_the_bit(cache):
    plan, calls = counted(a_plan())
    request = {'omega_target': 2.0, 'robust': 0.1}
    first = plan_cache.cached_plan(request, plan)
    again = plan_cache.cached_plan(dict(reversed(request.items())), plan)
    assert len(calls) == 1 and len(list(cache.glob('*.json'))) == 1
    same(first, again)
    assert first is not again
    plan_cache.cached_plan({'omega_target': 2.0, 'robust': 0.1 + 1e-16}, plan)
    plan_cache.cached_plan({'omega_target': 2.0, 'robust': 0.1, 'x': None}, plan)
    assert len(calls) == 3                   # any other request is planned


def test_no_plan_is_remembered_with_its_reason(cache):
    plan, calls = counted(ValueError('no spin-up from 0 to 9 rad/s found within 60 s'))
    for _ in range(2):
        with pytest.raises(ValueError, match='no spin-up from 0 to 9 rad/s'):
            plan_cache.cached_plan({'omega_target': 9.0}, plan)
    assert len(calls) == 1


def test_other_code_plans_anew(cache, monkeypatch):
    plan, calls = counted(a_plan())
    plan_cache.cached_plan({'omega_target': 2.0}, plan)
    monkeypatch.setattr(plan_cache, 'code_fingerprint', lambda: 'another version')
    plan_cache.cached_plan({'omega_target': 2.0}, plan)
    assert len(calls) == 2


@pytest.mark.parametrize('content', ['', '{"plan": ', '[1, 2]', '{"plan": {"duration": 1}}',
                                     '{"plan": {"duration": -1, "control_points": [], '
                                     '"peak_deflection": null, "residual_amplitude": null, '
                                     '"band_residual": null, "robust": 0, "t_start": 0}}',
                                     '{"error": 3}'])
def test_a_malformed_entry_is_planned_again_and_replaced(cache, content):
    plan, calls = counted(a_plan())
    request = {'omega_target': 2.0}
    cache.mkdir()
    path = cache / f'{plan_cache.key(request)}.json'
    path.write_text(content)
    same(plan_cache.cached_plan(request, plan), a_plan())
    assert len(calls) == 1
    assert 'plan' in json.loads(path.read_text())


def test_off_and_unwritable_caches_still_plan(tmp_path, monkeypatch):
    plan, calls = counted(a_plan())
    monkeypatch.setenv(plan_cache.ENV, 'off')
    assert plan_cache.directory() is None
    plan_cache.cached_plan({'omega_target': 2.0}, plan)
    plan_cache.cached_plan({'omega_target': 2.0}, plan)
    blocker = tmp_path / 'a file'
    blocker.write_text('')
    monkeypatch.setenv(plan_cache.ENV, str(blocker / 'plans'))
    same(plan_cache.cached_plan({'omega_target': 2.0}, plan), a_plan())
    assert len(calls) == 3


def test_the_default_place_follows_xdg(monkeypatch, tmp_path):
    monkeypatch.delenv(plan_cache.ENV)
    monkeypatch.setenv('XDG_CACHE_HOME', str(tmp_path))
    assert plan_cache.directory() == tmp_path / 'rotrod' / 'plans'


def test_the_oldest_entries_go_beyond_the_limit(cache, monkeypatch):
    monkeypatch.setattr(plan_cache, 'MAX_ENTRIES', 3)
    plan, _ = counted(a_plan())
    for k in range(5):
        plan_cache.cached_plan({'omega_target': float(k)}, plan)
        path = cache / f'{plan_cache.key({"omega_target": float(k)})}.json'
        os.utime(path, (k, k))               # written in this order, a second apart
    kept = {p.name for p in cache.glob('*.json')}
    assert kept == {f'{plan_cache.key({"omega_target": float(k)})}.json' for k in (2, 3, 4)}


def test_plan_spin_up_reads_back_the_plan_it_made(cache):
    """The planner's own result, stored and read: the same profile to the bit."""
    made = plan_spin_up(RodParams(), 2.0)
    assert len(list(cache.glob('*.json'))) == 1
    read = plan_spin_up(RodParams(), 2.0)
    same(made, read)
    assert made.band_residual <= 2.5e-7 and made.peak_deflection <= 3e-3
    assert len(list(cache.glob('*.json'))) == 1
