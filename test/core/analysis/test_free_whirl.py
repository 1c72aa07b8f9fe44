"""The free whirl measured from samples: two whirls about a static position (Eq. 28)."""

import math

import numpy as np
import pytest
from reference import W0

from rotrod_core import RodParams
from rotrod_core.analysis.free_whirl import free_whirl


def samples(w, a, b, centre, t):
    """z = centre + a exp(i (w0 - w) t) + b exp(-i (w0 + w) t): docs/model.md's whirls."""
    z = centre + a * np.exp(1j * (W0 - w) * t) + b * np.exp(-1j * (W0 + w) * t)
    return t, z.real, z.imag


@pytest.mark.parametrize('w', [0.0, 1.0, 2.0])
def test_the_amplitudes_of_two_whirls_about_any_centre(w):
    t = 5.0 + np.arange(400) * 0.01                  # 4 s at 100 Hz, from any time
    a, b = 3e-7 * np.exp(0.4j), 1e-7 * np.exp(-2.0j)
    whirl, misfit = free_whirl(*samples(w, a, b, 2.79e-3 + 1e-6j, t), RodParams(), w)
    assert whirl == pytest.approx(abs(a) + abs(b), rel=1e-9)
    assert misfit < 1e-15


def test_noise_shows_in_the_misfit_not_in_the_whirl():
    rng = np.random.default_rng(3)
    t = np.arange(400) * 0.01
    tt, u, v = samples(2.0, 2e-7, 0.0, 2.79e-3, t)
    noise = 1e-8
    whirl, misfit = free_whirl(tt, u + noise * rng.standard_normal(400),
                               v + noise * rng.standard_normal(400), RodParams(), 2.0)
    assert whirl == pytest.approx(2e-7, abs=5 * noise / math.sqrt(400) * 3)
    assert misfit == pytest.approx(noise * math.sqrt(2), rel=0.2)


def test_too_few_or_bad_samples_are_refused():
    with pytest.raises(ValueError, match='>= 8 samples'):
        free_whirl([0.0, 0.1], [0.0, 0.0], [0.0, 0.0], RodParams(), 1.0)
    with pytest.raises(ValueError, match='finite'):
        free_whirl(np.arange(10.0), [math.nan] * 10, np.zeros(10), RodParams(), 1.0)
