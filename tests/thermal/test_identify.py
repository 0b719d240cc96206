"""Tests of :mod:`mtident.thermal.identify`."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import first_order, make_log

from mtident.exceptions import InputError
from mtident.io import read_temperature_log, sample_log_path
from mtident.thermal import RobustSettings, identify, load_reference, minimal_identification_time


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda log: identify(log, 3.0, "ukf"), r"only 4 samples in the first 3 min"),
        (
            lambda log: identify(log, 30.0, "kalman"),
            r"method 'kalman' is not one of: robust, ukf, aukf, fukf, afukf, lsq",
        ),
        (
            lambda log: identify(log, 30.0, "ukf", preset="smith"),
            r"preset 'smith' is not one of: data, xia2014, yu2019",
        ),
        (
            lambda log: identify(log, 30.0, preset="xia2014"),
            r"`preset` is a setting of the papers' first-order filters: give `method` ukf, aukf, fukf, afukf or lsq",
        ),
        (
            lambda log: identify(log, 30.0, pseudo_measurement_seed=7),
            r"`pseudo_measurement_seed` is a setting of the papers' first-order filters",
        ),
        (
            lambda log: identify(log, 30.0, "ukf", reference=load_reference(sample_log_path("@sample-machine"))),
            r"`reference` needs the model-robust method",
        ),
        (
            lambda log: identify(log, 30.0, "lsq", settings=RobustSettings(max_time_constant_min=200.0)),
            r"the largest time constant, the room's wander and the free fast modes \(`max_time_constant_min`",
        ),
        (
            lambda log: minimal_identification_time(log, periods_min=[35, 400]),
            r"covers 59 min; the longest sampling period is 400 min",
        ),
        (lambda log: minimal_identification_time(log, "x"), r"method 'x' is not one of"),
    ],
)
def test_errors_name_the_problem(call, message):
    t = np.arange(0.0, 60.0)
    with pytest.raises(InputError, match=message):
        call(make_log(t, {"S": first_order(t)}))


def test_identify_and_min_time_take_a_dataframe_and_refuse_what_they_cannot_use():
    """A notebook's DataFrame is read like a CSV file (it raised AttributeError before); other
    types and impossible windows are named."""
    import pandas as pd

    t = np.arange(0.0, 120.0)
    rng = np.random.default_rng(8)
    frame = pd.DataFrame({"time_min": t, "A": 26.7 - 8.8 * np.exp(-0.016 * t) + 0.02 * rng.standard_normal(len(t))})
    from_frame = identify(frame, window_min=60, method="ukf").summary(0)
    assert from_frame == identify(read_temperature_log(frame), window_min=60, method="ukf").summary(0)
    low, high = from_frame["steady_state_ci95_C"]
    assert low < 26.7 < high and high - low < 0.5
    assert (
        minimal_identification_time(frame).min_identification_time_min.tolist()
        == minimal_identification_time(read_temperature_log(frame)).min_identification_time_min.tolist()
    )
    with pytest.raises(
        InputError,
        match=(
            r"identify takes a TemperatureLog \(read_temperature_log\(path or DataFrame\)\) or a pandas DataFrame, "
            r"not ndarray"
        ),
    ):
        identify(frame.to_numpy(), window_min=30, method="ukf")  # type: ignore[arg-type]
    for window in (-5.0, 0.0, float("nan")):
        with pytest.raises(InputError, match="window_min must be a positive number of minutes"):
            identify(frame, window_min=window, method="ukf")
    with pytest.raises(InputError, match=r"periods_min must be positive numbers of minutes, not \[0\]"):
        minimal_identification_time(frame, periods_min=[0])
    with pytest.raises(InputError, match=r"windows_min must be positive numbers of minutes, not \[\]"):
        minimal_identification_time(frame, windows_min=[])
    with pytest.raises(InputError, match=r"windows_min must be positive numbers of minutes, not 'x'"):
        minimal_identification_time(frame, windows_min="x")  # type: ignore[arg-type]
    # an L at or beyond the longest period broadcast a curve into too short an array (a traceback)
    with pytest.raises(InputError, match=r"shorter than the longest sampling period \(35 min\).*: 2 \(40-60 min\)"):
        minimal_identification_time(frame, periods_min=[35.0], windows_min=[20.0, 40.0, 60.0])
    # one number, or an array, is taken as the list it stands for
    assert list(minimal_identification_time(frame, "lsq", periods_min=35).periods_min) == [35.0]


def test_identify_leaves_out_a_stuck_channels_readings_and_says_so():
    """A failed channel read 0.00 °C from 150 min on: identify took it as where the sensor settled
    (measured final 0.00, settled, RMSE 23 °C) without a word."""
    rng = np.random.default_rng(2)
    t = np.arange(0.0, 300.0, 1.0)
    y = np.round(20.0 + 10.0 * (1.0 - np.exp(-t / 40.0)) + rng.normal(0.0, 0.02, t.size), 2)
    y[150:] = 0.0
    result = identify(make_log(t, {"S": y}), 60.0)
    said = [n for n in result.notes if "every reading from t = 150 min to the log's end is the same value" in n]
    assert len(said) == 1 and "'S'" in said[0] and said[0] in result.warnings[0]
    assert result.rmse_C[0] < 0.2 and not (result.measured_final_C[0] == 0.0)


def test_a_notebooks_wrong_arguments_are_refused_by_name():
    """A new user's notebook: a string window raised a numpy TypeError, a negative largest time
    constant an OverflowError deep in the search, a negative horizon an IndexError, a list of rows a
    pathlib TypeError, and one sensor's name was split into its letters."""
    from mtident.io import read_temperature_log
    from mtident.thermal import RobustSettings

    log = read_temperature_log("@sample", sensors="T1")
    assert log.sensors == ("T1",)
    with pytest.raises(InputError, match=r"window_min must be a positive number of minutes, not 'x'"):
        identify(log, window_min="x")  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"horizon_min must be a number of minutes, 0 or more, not -10"):
        identify(log, window_min=60, horizon_min=-10)
    with pytest.raises(InputError, match=r"`max_time_constant_min` must be a finite number of minutes, 1 or more"):
        RobustSettings(max_time_constant_min=-1.0)
    with pytest.raises(InputError, match=r"`room_wander_C_per_h` must be a finite number of °C in an hour, 0 or more"):
        RobustSettings(room_wander_C_per_h=-1.0)
    with pytest.raises(InputError, match=r"`levels` must be confidence levels between 0 and 1"):
        RobustSettings(levels=(95.0,))
    with pytest.raises(InputError, match=r"a file's path or a pandas DataFrame .*, not list"):
        read_temperature_log([[0.0, 20.0], [1.0, 21.0]])  # type: ignore[arg-type]
