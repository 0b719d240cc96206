"""Tests of :mod:`mtident.feeddrive.model`."""

from __future__ import annotations

import numpy as np
import pytest

from mtident.exceptions import InputError
from mtident.feeddrive import (
    Excitation,
    FeedDriveParameters,
)
from mtident.feeddrive.model import prbs_bits, rk4_linear_step, system_matrix


def test_rk4_error_scales_as_h_to_the_fourth():
    a = system_matrix(FeedDriveParameters())
    b = np.zeros((8, 4))
    exact = rk4_linear_step(a, b, 1e-4, 1024)[0]
    errors = [np.abs(rk4_linear_step(a, b, 1e-4, m)[0] - exact).max() for m in (16, 32)]
    # local error O(h⁵) per step, global O(h⁴) over a fixed interval: halving h divides it by ~16-32
    assert 14 < errors[0] / errors[1] < 40


def test_rk4_step_matrix_equals_explicit_rk4():
    a = system_matrix(FeedDriveParameters())
    b = np.vstack([np.zeros((4, 4)), np.eye(4)])
    rng = np.random.default_rng(0)
    x, u, h = rng.standard_normal(8) * 1e-6, rng.standard_normal(4), 1e-4
    phi, gamma = rk4_linear_step(a, b, h, 3)
    y = x.copy()
    d = h / 3
    for _ in range(3):
        f = lambda z: a @ z + b @ u  # noqa: E731
        k1 = f(y)
        k2 = f(y + d / 2 * k1)
        k3 = f(y + d / 2 * k2)
        k4 = f(y + d * k3)  # noqa: E702
        y = y + d / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    np.testing.assert_allclose(phi @ x + gamma @ u, y, rtol=1e-12, atol=1e-20)


@pytest.mark.parametrize("kind", ["impulse", "step", "sine", "sweep", "prbs", "multisine"])
def test_excitations(kind):
    forces = Excitation(kind, 3, 2.0).forces(np.arange(0, 0.01, 1e-4))
    assert forces.shape == (100, 4) and np.all(forces[:, :3] == 0) and np.abs(forces[:, 3]).max() <= 2.0
    with pytest.raises(InputError, match="coordinate 7"):
        Excitation(kind, 7)


def test_binary_sequences_are_maximal_length():
    for length in (31, 63, 127, 1023):
        bits = prbs_bits(length)
        assert int(bits.sum()) == 1  # one period: 2ⁿ⁻¹ ones and 2ⁿ⁻¹ − 1 minus ones
        # the autocorrelation of a maximal-length sequence is −1 off zero lag
        circular = np.array([bits @ np.roll(bits, k) for k in range(1, length)])
        np.testing.assert_array_equal(circular, -1.0)
