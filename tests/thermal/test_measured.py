"""Tests of :mod:`mtident.thermal.measured`."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import first_order, make_log
from scipy.signal import lfilter

from mtident.thermal import identify
from mtident.thermal.identify import measured_equilibrium, rmse
from mtident.thermal.measured import warm_up_floor_C


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


def _through_a_lag(room: np.ndarray, tau_min: float) -> np.ndarray:
    """The room as a sensor behind a first-order path of ``tau_min`` follows it (1-min steps)."""
    decay = np.exp(-1.0 / tau_min)
    return lfilter([1.0 - decay], [1.0, -decay], room - room[0]) + room[0]


def test_a_warm_up_that_came_down_with_a_falling_room_keeps_a_floor_below_its_equilibrium():
    """A daily room falling 0.4 °C late in a warm-up brings the readings down with it: the readings
    less the room's highest level until then still bound the heat's part, so the floor holds
    (it gave none, a low end 1.5 °C below the readings left standing) and stays below T∞; over
    random rooms, paths and warm-ups it is never above T∞."""
    t = np.arange(0.0, 400.0)
    room = 20.0 + 0.4 * np.sin(2.0 * np.pi * t / 1440.0 + 0.8)
    readings = 6.0 * (1.0 - np.exp(-t / 25.0)) + _through_a_lag(room, 40.0)
    assert readings[-1] < readings.max() - 0.1  # it came down
    truth = 6.0 + room[-1]
    floor = warm_up_floor_C(truth + 1.0, t, readings, room, 0.01, 0.0)
    assert truth - 0.2 < floor < truth
    rng = np.random.default_rng(3)
    for _ in range(100):
        room = 20.0 + rng.uniform(0.1, 0.6) * np.sin(2.0 * np.pi * t / 1440.0 + rng.uniform(0.0, 2.0 * np.pi))
        rise, tau = rng.uniform(2.0, 10.0), rng.uniform(10.0, 120.0)
        clean = rise * (1.0 - np.exp(-t / tau)) + _through_a_lag(room, rng.uniform(20.0, 300.0))
        noisy = np.round(clean + rng.normal(0.0, 0.01, t.size), 2)
        floor = warm_up_floor_C(rise + room[-1] + 1.0, t, noisy, room + rng.normal(0.0, 0.005, t.size), 0.01, 0.01)
        assert np.isfinite(floor) and floor < rise + room[-1]


def test_a_heat_part_that_fell_more_than_the_room_explains_sets_no_floor():
    """Readings that fell 0.5 °C while the room moved 0.1 °C: the heat input fell, and a warm-up's
    floor says nothing of where it settles now."""
    t = np.arange(0.0, 300.0)
    room = 20.0 + 0.1 * (t > 150.0)
    heat = np.where(t < 200.0, 6.0 * (1.0 - np.exp(-t / 25.0)), 6.0 - 0.5 * (1.0 - np.exp(-(t - 200.0) / 20.0)))
    assert warm_up_floor_C(25.0, t, heat + room, room, 0.01, 0.0) == -np.inf
