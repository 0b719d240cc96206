"""Tests of :mod:`mtident.thermal.measured`."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import first_order, make_log

from mtident.thermal import identify
from mtident.thermal.identify import measured_equilibrium, rmse


def test_a_log_settled_in_display_steps_counts_as_settled_and_one_still_rising_does_not():
    """A new user's sensor in 0.1 °C steps, within 0.05 °C of where it settled for the last quarter
    of its log, was called 'not settled by the log's end': medians of five readings, a quarter
    apart, sat a whole step apart on 2 of these 20 noise draws."""
    t = np.arange(0.0, 901.0)
    draws = [np.random.default_rng(seed).normal(0.0, 0.03, t.size) for seed in range(20)]
    settled = np.column_stack([np.round(23.84 - 2.0 * np.exp(-t / 150.0) + noise, 1) for noise in draws])
    final, _ = measured_equilibrium(t, settled, max_late_move_C=0.1)
    assert np.all(np.abs(final - 23.84) < 0.1)  # within a step of the truth, none NaN
    rising = np.round(23.84 - 2.0 * np.exp(-t / 400.0) + draws[0], 1)  # 0.2 °C in its last quarter
    assert np.isnan(measured_equilibrium(t, rising[:, None], max_late_move_C=0.1)[0][0])


def test_a_move_hidden_by_the_display_step_is_not_settled():
    """A newcomer's column in 0.1 °C steps with little noise, 0.08 °C short of its level at the end
    of an 8-h log (a slow mode of 300 min): both ends of its last quarter read 23.8, so the check
    against the rest of the log called it settled at 23.80, 0.1 °C short. One that has settled
    (its slowest mode 40 min) still counts, and so does the first with noise that dithers its steps
    (its median, like any log still moving within the bounds, a little short)."""
    t = np.arange(0.0, 481.0)
    curve = 23.9 - 3.0 * np.exp(-t / 40.0) - 0.4 * np.exp(-t / 300.0)
    quiet = np.round(curve + np.random.default_rng(3).normal(0.0, 0.01, t.size), 1)
    assert np.isnan(measured_equilibrium(t, quiet[:, None], 0.1, 0.05, 300.0)[0][0])
    settled = np.round(23.9 - 3.0 * np.exp(-t / 40.0) + np.random.default_rng(3).normal(0.0, 0.01, t.size), 1)
    assert measured_equilibrium(t, settled[:, None], 0.1, 0.05, 40.0)[0][0] == pytest.approx(23.9)
    dithered = np.round(curve + np.random.default_rng(3).normal(0.0, 0.08, t.size), 1)
    assert measured_equilibrium(t, dithered[:, None], 0.1, 0.05, 40.0)[0][0] == pytest.approx(23.85, abs=0.06)


def test_a_sensor_with_no_curve_has_no_rmse_not_a_perfect_one():
    """identify showed an RMSE of 0.000 beside a sensor with no rise (no curve): read as a perfect fit."""
    measured = np.array([[20.0, 20.0], [20.1, 21.0], [20.0, 22.0]])
    curve = np.array([[np.nan, 20.0], [np.nan, 21.1], [np.nan, 21.9]])
    got = rmse(curve, measured)
    assert np.isnan(got[0]) and got[1] == pytest.approx(np.sqrt(0.02 / 2))
    t = np.arange(0.0, 61.0)
    flat = 20.0 + 0.02 * np.random.default_rng(0).standard_normal(len(t))
    result = identify(make_log(t, {"flat": flat, "heating": first_order(t)}), 30.0)
    assert np.isnan(result.rmse_C[0]) and result.summary(0)["rmse_C"] is None
