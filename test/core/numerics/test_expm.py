"""expm_batch against scipy's expm."""

import numpy as np

from rotrod_core.numerics.expm import expm_batch


def test_expm_batch_matches_scipy():
    from scipy.linalg import expm
    A = np.random.default_rng(3).normal(size=(40, 5, 5)) * np.array([0.01, 0.5, 3.0, 20.0]
                                                                    ).repeat(10)[:, None, None]
    ref = np.array([expm(a) for a in A])
    rel = np.max(np.abs(expm_batch(A) - ref), axis=(1, 2)) / np.max(np.abs(ref), axis=(1, 2))
    assert np.all(rel < 1e-11)
