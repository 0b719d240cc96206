"""Tests of :mod:`mtident.ukf.sigma_points`."""

from __future__ import annotations

import numpy as np
import pytest

from mtident.exceptions import NegativeWeightWarning
from mtident.ukf import (
    MerweScaledSigmaPoints,
    sigma_points,
)


def test_sigma_points_reproduce_mean_and_covariance():
    rng = np.random.default_rng(0)
    A = rng.standard_normal((4, 4))
    P = A @ A.T + np.eye(4)
    x = rng.standard_normal(4)
    scheme = MerweScaledSigmaPoints(1.0, 2.0, 1.0)
    w = scheme.weights(4)
    pts = sigma_points(x, np.linalg.cholesky(P), w)
    assert pts.shape == (9, 4)
    mean = w.mean @ pts
    np.testing.assert_allclose(mean, x, rtol=1e-12)
    dev = pts - mean
    np.testing.assert_allclose(np.einsum("s,si,sj->ij", w.cov, dev, dev), P, rtol=1e-12)


def test_seed_004_sigma_settings_warn_negative_centre_weight():
    with pytest.warns(NegativeWeightWarning, match="negative centre weight W0m=-2.368"):
        w = MerweScaledSigmaPoints(0.5, 2.0, 3.0).weights(16)
    np.testing.assert_allclose(w.mean.sum(), 1.0, rtol=1e-12)
    assert w.mean[0] < 0 < w.cov[0]


def test_invalid_sigma_scaling_is_refused():
    with pytest.raises(ValueError, match="n \\+ λ"):
        MerweScaledSigmaPoints(alpha=0.0).weights(3)
