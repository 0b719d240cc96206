"""Tests of :mod:`mtident.thermal.modal_search`."""

from __future__ import annotations

import numpy as np

import mtident.thermal.modal_search as search_module


def test_the_room_lag_is_the_exact_lag_of_a_room_that_ramps_at_uneven_steps():
    """A room rising at s °C/min from a machine at its first level lags by s·τ·(1 − e^(−t/τ)), whatever
    the steps between the bins; each time constant its own row."""
    t = np.cumsum(np.r_[0.0, np.random.default_rng(3).uniform(0.1, 4.0, 80)])
    room = 19.0 + 0.02 * t
    tau = np.array([0.5, 7.0, 250.0])
    lagged = search_module.room_lag(room, t, tau)
    exact = room[None, :] - 0.02 * tau[:, None] * (1.0 - np.exp(-t[None, :] / tau[:, None]))
    np.testing.assert_allclose(lagged, exact, rtol=0, atol=1e-12)
