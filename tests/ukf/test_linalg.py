"""Tests of :mod:`mtident.ukf.linalg`."""

from __future__ import annotations

import numpy as np
import pytest

from mtident.exceptions import CovarianceError
from mtident.ukf import (
    cholesky_update,
)


def test_cholesky_update_and_downdate():
    rng = np.random.default_rng(4)
    A = rng.standard_normal((3, 3))
    P = A @ A.T + 3 * np.eye(3)
    v = rng.standard_normal(3)
    L = np.linalg.cholesky(P)
    up = cholesky_update(L, v, 1.0, "t")
    np.testing.assert_allclose(up @ up.T, P + np.outer(v, v), rtol=1e-12)
    down = cholesky_update(up, v, -1.0, "t")
    np.testing.assert_allclose(down @ down.T, P, rtol=1e-10)
    with pytest.raises(CovarianceError, match="stage 'too big'.*smallest eigenvalue -"):
        cholesky_update(L, 10 * v, -1.0, "too big")
