"""The whirl fit on known motions, and verdicts that follow the measured values."""

import dataclasses
import math

import numpy as np
import pytest

from rotrod_core import RodParams, simulate
from rotrod_core.estimation.whirl import fit_whirls
from rotrod_core.reporting.facts import EQ26, stage_facts


def test_fit_recovers_a_centre_and_two_whirls():
    t = np.arange(0.0, 20.0, 0.01)
    c, a, b = 1e-3 + 2e-4j, 3e-6 * np.exp(0.3j), 1e-6 * np.exp(-1.1j)
    wf, wb = 7.3, 11.9
    z = c + a * np.exp(1j * wf * t) + b * np.exp(-1j * wb * t)
    fit = fit_whirls(t, z.real, z.imag)
    assert fit.forward_omega == pytest.approx(wf, rel=1e-10)
    assert fit.backward_omega == pytest.approx(wb, rel=1e-10)
    assert abs(fit.centre - c) < 1e-15 and abs(fit.forward - a) < 1e-15
    assert abs(fit.backward - b) < 1e-15 and fit.relative_residual < 1e-9
    assert fit.precession_rate == pytest.approx((wf - wb) / 2, rel=1e-9)
    assert fit.forward_frequency == pytest.approx(wf / (2 * math.pi), rel=1e-10)


def test_fit_semi_axes_are_the_ellipse_of_the_samples():
    t = np.arange(0.0, 10.0, 1e-3)
    a, b, w = 2e-6 * np.exp(0.4j), 0.5e-6 * np.exp(2.0j), 5.0
    z = a * np.exp(1j * w * t) + b * np.exp(-1j * w * t)
    fit = fit_whirls(t, z.real, z.imag)
    r = np.abs(z - fit.centre)
    assert fit.semi_major == pytest.approx(r.max(), rel=1e-6)
    assert fit.semi_minor == pytest.approx(r.min(), rel=1e-6)
    assert fit.semi_minor == pytest.approx(1.5e-6, rel=1e-9)
    assert abs(fit.precession_rate) < 1e-9


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
