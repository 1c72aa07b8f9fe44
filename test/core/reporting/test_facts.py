"""Stage verdicts that follow the measured values."""

import dataclasses

import pytest

from rotrod_core import RodParams, simulate
from rotrod_core.reporting.facts import EQ26, stage_facts


@pytest.fixture(scope='module')
def eq26_run():
    return simulate(RodParams(), EQ26, 40.0, dt=1e-3)


def test_stage_verdicts_follow_the_measurement(eq26_run):
    """The same criteria call a mirrored motion (v -> -v) wrong: the verdicts are measured."""
    facts = stage_facts(eq26_run)
    mirrored = dataclasses.replace(eq26_run, v=-eq26_run.v, dv=-eq26_run.dv)
    flipped = stage_facts(mirrored)
    by_claim = {f.claim: (f.verdict, g.verdict) for f, g in zip(facts, flipped)}
    direction = [k for k in by_claim if 'backwards' in k or 'moves forward' in k]
    assert len(direction) == 2
    for claim in direction:
        assert by_claim[claim] == ('agrees', 'differs'), claim
