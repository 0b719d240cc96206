"""Tests of :mod:`mtident.thermal.robust_identify`."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import PAPER_STEADY, first_order, make_log
from hypothesis import given, settings
from hypothesis import strategies as st

from mtident.exceptions import InputError
from mtident.io import read_temperature_log
from mtident.thermal import identify


def test_too_short_a_window_of_a_log_read_as_minutes_names_the_time_unit_too(write_csv):
    """A log in seconds read as minutes: 90 "min" held 5 readings, and the error said only to use a
    longer window."""

    text = "time,T1\n" + "".join(f"{s},{20 + 6 * (1 - np.exp(-s / 1800)):.2f}\n" for s in range(0, 28801, 20))
    with pytest.raises(InputError, match=r"use a longer `window_min`, or the time column's unit, `time_unit`"):
        identify(read_temperature_log(write_csv(text)), 90.0)
    minutes = "time,T1\n" + "".join(f"{m},{20 + m / 100:.2f}\n" for m in range(0, 120, 5))
    with pytest.raises(InputError, match=r"use a longer `window_min`\)$"):
        identify(read_temperature_log(write_csv(minutes)), 20.0)


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        ({"method": "lsq"}, "needs a UKF method with the data tuning"),
        ({"method": "ukf", "preset": "xia2014"}, "needs a UKF method with the data tuning"),
    ],
)
def test_room_input_refuses_what_models_a_steady_room(kwargs, message):
    t = np.arange(0.0, 61.0)
    with pytest.raises(InputError, match=message):
        identify(make_log(t, {"A": first_order(t)}), 30.0, ambient_C=np.full(len(t), 17.9), **kwargs)
    with pytest.raises(InputError, match="3 readings for 61 samples"):
        identify(make_log(t, {"A": first_order(t)}), 30.0, ambient_C=np.full(3, 17.9))


@pytest.mark.parametrize(("window", "within"), [(30.0, 0.4), (60.0, 0.1)])
def test_the_robust_estimate_of_a_first_order_curve_is_as_accurate_as_the_papers(window, within):
    """The point estimate is the best-fitting model's: on the papers' kind of curve as accurate as
    the first-order filters; it is the interval that widens where the data allow more."""
    t = np.arange(0.0, 241.0)
    errors = []
    for seed in range(6):
        y = np.round(first_order(t) + 0.02 * np.random.default_rng(seed).standard_normal(len(t)), 2)
        errors.append(identify(make_log(t, {"S": y}), window).steady_state_C[0] - PAPER_STEADY)
    assert np.sqrt(np.mean(np.square(errors))) < within


def test_identify_never_calls_a_risen_sensor_flat():
    """Sensors that rose 0.5-3.5 °C were called "no rise" and left out; the robust answer reports
    the rise and its interval whatever it is."""
    t = np.arange(0.0, 121.0)
    rng = np.random.default_rng(32)
    columns = {
        f"r{r}": 20.0 + r * (1 - np.exp(-t / 150.0)) + 0.02 * rng.standard_normal(len(t)) for r in (0.5, 1.5, 3.5)
    }
    result = identify(make_log(t, columns), 120.0)
    for i in range(3):
        summary = result.summary(i)
        assert not any("no rise" in w for w in summary["warnings"])  # type: ignore[union-attr]
        assert summary["model"]["rise_C"] > 0.25  # type: ignore[index]


@settings(max_examples=5, deadline=None)
@given(seed=st.integers(min_value=0, max_value=2**31 - 1), fraction=st.sampled_from([0.25, 0.5, 1.0]))
def test_robust_answers_over_generated_warm_ups_are_consistent(seed, fraction):
    """On any warm-up of the benchmark's population: the point estimate lies in its intervals, the
    99 % interval holds the 95 %, and the summary is plain JSON."""
    import json

    from mtident.testing.warmups import random_warmup
    from mtident.thermal.robust_identify import identify_robust

    warm = random_warmup(np.random.default_rng(seed))
    window = max(fraction * warm.t95_min, 10 * warm.interval_min)
    result = identify_robust(make_log(warm.time_min, {"S": warm.reading_C}), window, warm.room_C)
    estimate = result.details.estimates[0]
    assert estimate.fit is not None, estimate.status  # every warm-up of the population rises: a model is fitted
    (lo95, hi95), (lo99, hi99) = estimate.interval_C[0.95], estimate.interval_C[0.99]
    assert lo99 <= lo95 <= estimate.steady_C <= hi95 <= hi99
    json.dumps(result.summary(0), allow_nan=False)


def test_a_robust_answer_printed_in_a_notebook_says_why_it_is_not_trusted():
    """A newcomer's print(result) said "not trusted (see warnings)" and showed none."""
    from mtident.thermal.robust_identify import identify_robust

    t = np.arange(0.0, 60.0)
    y = 20.0 + 5.0 * (1.0 - np.exp(-t / 80.0)) + 0.01 * np.random.default_rng(0).standard_normal(t.size)
    text = repr(identify_robust(make_log(t, {"S": np.round(y, 2)}), 30.0))
    assert ", not trusted:\n    - S: T∞ not determined yet (95 % interval" in text, text
    assert "\n  assumes: a sum of up to four exponential modes" in text and "time constants up to 300 min" in text


def test_the_prediction_band_of_a_warm_up_never_falls_nor_leaves_the_interval():
    """30 min of the papers' kind of curve (59 min, 8.85 °C, σ 0.01 °C): the model at the 95 %
    interval's low end rose to 27 °C and fell back to 23.3 °C, and the band's low edge fell with
    it, against the answer's own assumption of a warm-up that does not overshoot. Now the band's
    edges only rise, the low edge up to the interval's low end, the high one within its high end."""
    t = np.arange(0.0, 31.0)
    y = 20.0 + 8.85 * (1.0 - np.exp(-t / 59.0)) + np.random.default_rng(1).normal(0.0, 0.01, len(t))
    result = identify(make_log(t, {"T1": np.round(y, 3)}), window_min=30, horizon_min=300)
    low, high = result.band_low_C[:, 0], result.band_high_C[:, 0]
    lo, hi = result.steady_state_ci95_C[0]
    assert np.all(np.diff(low) >= 0) and np.all(np.diff(high) >= 0)
    assert low.max() <= lo + 1e-12 and high.max() <= hi + 1e-12
    assert np.all(low <= result.curve_C[:, 0]) and np.all(result.curve_C[:, 0] <= high)


def test_readings_the_log_lost_are_among_the_sensors_warnings(write_csv):
    """identify's JSON gave no word of 20 open-circuit readings skipped in the sensor's column (the
    terminal's note only): each sensor's answer now carries what the log's reading said of it."""
    t = np.arange(0.0, 201.0)
    a = first_order(t)
    a[120:140] = -200.0
    rows = "\n".join(f"{ti:g},{ai:.3f},{bi:.3f}" for ti, ai, bi in zip(t, a, first_order(t), strict=True))
    log = read_temperature_log(write_csv("time_min,A,B\n" + rows + "\n"))
    result = identify(log, window_min=100)
    assert [w for w in result.warnings[0] if "skipped 20 open-circuit" in w]
    assert not [w for w in result.warnings[1] if "skipped" in w]


@pytest.mark.parametrize(
    ("interval", "said"),
    [
        ((-np.inf, np.inf), "S: T∞ not determined yet (its 95 % interval not yet bounded)"),
        ((20.0, 31.5), "S: T∞ not determined yet (95 % interval 20.00 to 31.50 °C, wider than the rise so far)"),
    ],
)
def test_an_interval_the_fits_do_not_bound_is_said_in_words(interval, said):
    """A seconds column read as minutes gave "95 % interval -inf to inf °C" in a warning."""
    from types import SimpleNamespace

    from mtident.thermal.robust import _Notes, _verdict

    notes = _Notes("S")
    fit = SimpleNamespace(determined=True)
    assert not _verdict(fit, {0.95: interval}, 8.0, 0.1, None, False, notes)  # type: ignore[arg-type]
    assert notes.texts == [said]
