"""Tests of :mod:`mtident.thermal.readings`."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from conftest import PAPER_RATE, PAPER_START, PAPER_STEADY, first_order, make_log

from mtident.thermal import identify
from mtident.thermal.lsq import cramer_rao_bound
from mtident.thermal.readings import display_resolution, noise_sigma, quick_estimate, room_error_C


def test_a_room_is_taken_over_the_longest_window_it_follows_within_its_noise():
    """A steady room flickering between two 0.05 °C steps is taken as its two-hour line (the
    flicker gone); one wandering ±0.1 °C within an hour and a half, read to 0.01 °C with 0.02 °C of
    noise, over a shorter window that follows the wander."""
    from mtident.thermal.readings import room_input, room_trend

    rng = np.random.default_rng(5)
    t = np.arange(0.0, 400.0, 0.5)
    flicker = np.round((17.435 + rng.normal(0.0, 0.0076, t.size)) * 20.0) / 20.0
    assert np.ptp(flicker) == pytest.approx(0.05) and np.ptp(room_input(t, flicker)[40:-40]) < 0.02
    wander = 18.0 + 0.1 * np.sin(2.0 * np.pi * t / 80.0)
    taken = room_input(t, np.round(wander + rng.normal(0.0, 0.02, t.size), 2))
    assert np.max(np.abs(taken - wander)[40:-40]) < 0.03
    assert np.max(np.abs(room_trend(t, wander, 120.0) - wander)[40:-40]) > 0.05  # the two-hour one would not


def test_a_daily_room_cycle_keeps_its_swing_in_the_two_hour_trend():
    """A straight line over two hours takes about 1 % off a daily cycle's swing (0.0034 °C of a
    ±0.3 °C cycle), which hundreds of readings make a significant slow error of every fit; the
    local parabola keeps it."""
    from mtident.thermal.readings import room_trend

    t = np.arange(0.0, 600.0, 0.5)
    cycle = 20.0 + 0.3 * np.sin(2.0 * np.pi * (t + 300.0) / 1440.0)
    assert np.max(np.abs(room_trend(t, cycle, 120.0) - cycle)) < 2e-4


def test_a_room_trend_bends_with_a_noisy_daily_cycle_but_hardly_with_a_steady_rooms_noise(monkeypatch):
    """Read at 0.01 °C with 0.01 °C of noise: in a daily cycle the trend's error is under 0.6 times
    the straight line's (its bias gone); in a steady room, where the line is right, the curvature's
    term adds little of the noise a full parabola would (the parabola's error is 1.6 times the
    line's)."""
    from mtident.thermal import readings

    rng = np.random.default_rng(3)
    t = np.arange(0.0, 600.0, 0.5)
    cycle = 20.0 + 0.3 * np.sin(2.0 * np.pi * (t + 300.0) / 1440.0)
    courses = {"daily": cycle, "steady": np.full(t.size, 20.0)}
    read = {kind: np.round(course + rng.normal(0.0, 0.01, t.size), 2) for kind, course in courses.items()}

    def error(kind: str, shrink: float) -> float:
        monkeypatch.setattr(readings, "CURVATURE_SHRINK", shrink)
        return float(np.sqrt(np.mean((readings.room_trend(t, read[kind], 120.0) - courses[kind]) ** 2)))

    line, parabola, trend = ({kind: error(kind, k) for kind in courses} for k in (1e12, 0.0, 2.0))
    assert trend["daily"] < 0.6 * line["daily"]
    assert parabola["steady"] > 1.4 * line["steady"] and trend["steady"] < 1.25 * line["steady"]
    # a log of 40 days (480 windows) keeps the line: the window's moments would be rounding there
    days = np.arange(0.0, 40 * 1440.0, 10.0)
    long_cycle = np.round(20.0 + 0.3 * np.sin(2.0 * np.pi * days / 1440.0) + rng.normal(0.0, 0.01, days.size), 2)
    monkeypatch.setattr(readings, "CURVATURE_SHRINK", 0.0)
    bent = readings.room_trend(days, long_cycle, 120.0)
    monkeypatch.setattr(readings, "CURVATURE_SHRINK", 1e12)
    np.testing.assert_allclose(bent, readings.room_trend(days, long_cycle, 120.0), atol=1e-9)


def test_a_room_trend_follows_a_drift_to_the_end_through_display_steps_and_gaps():
    from mtident.thermal.readings import room_trend

    t = np.arange(0.0, 300.0, 2.0)
    line = 20.0 + 0.003 * t
    np.testing.assert_allclose(room_trend(t, line, 120.0), line, atol=1e-9)  # a line is kept exactly
    steps = np.round((line + np.random.default_rng(1).normal(0.0, 0.01, t.size)) / 0.05) * 0.05
    steps[40:45] = np.nan
    trend = room_trend(t, steps, 120.0)
    assert np.isnan(trend[40:45]).all()
    # the steps' error (up to half a step) shrinks to a fifth, and the latest value has no lag
    assert np.nanmax(np.abs(steps - line)) > 0.02
    assert np.nanmax(np.abs(trend - line)) < 0.01 and abs(trend[-1] - line[-1]) < 0.005


def test_quick_estimate_and_noise_level():
    t = np.arange(0.0, 31.0)
    start, rate, steady = quick_estimate(t, first_order(t)[:, None])
    np.testing.assert_allclose([start[0], rate[0], steady[0]], [PAPER_START, PAPER_RATE, PAPER_STEADY], rtol=1e-9)
    rng = np.random.default_rng(0)
    noisy = first_order(np.arange(400.0))[:, None] + 0.02 * rng.standard_normal((400, 1))
    np.testing.assert_allclose(noise_sigma(noisy), [0.02], rtol=0.1)  # MAD of 396 fourth differences: ~5 % spread


@pytest.mark.parametrize("missing", [[1, 2, 3], [10, 11], [20, 21, 22], [25, 26]])
def test_quick_estimate_bridges_missing_readings(missing):
    """Left out of their third's mean, three missing readings of the noiseless papers' curve gave
    λ = 0.107/min and T∞ = 21.0 °C; the filter started there scattered by 0.66 °C instead of 0.49
    with 12.5 % dropouts (stop 17)."""
    t = np.arange(0.0, 29.0)
    y = first_order(t)
    y[missing] = np.nan
    start, rate, steady = quick_estimate(t, y[:, None])
    assert start[0] == PAPER_START
    assert rate[0] == pytest.approx(PAPER_RATE, rel=0.02) and steady[0] == pytest.approx(PAPER_STEADY, abs=0.1)


@pytest.mark.parametrize(("gap", "within"), [((3, 8), 0.15), ((12, 17), 0.3), ((20, 26), 0.3), ((0, 3), 0.01)])
def test_quick_estimate_takes_a_gap_or_a_late_first_reading_on_its_own_span(gap, within):
    """Rows missing (a logger's pause) made the thirds unequal: a 6-min gap in the noiseless papers'
    curve gave T∞ 20.9 °C; a sensor whose first readings are left out (a lag) tilted its first
    third (below: the sample's T9)."""
    t = np.arange(0.0, 29.0)
    y = first_order(t)
    if gap[0] == 0:  # the first readings left out, as identify leaves out a lagging start
        y[: gap[1]] = np.nan
        kept_t, kept_y = t, y
    else:
        keep = (t < gap[0]) | (t >= gap[1])
        kept_t, kept_y = t[keep], y[keep]
    _, rate, steady = quick_estimate(kept_t, kept_y[:, None])
    assert steady[0] == pytest.approx(PAPER_STEADY, abs=within) and rate[0] == pytest.approx(PAPER_RATE, rel=0.05)


def test_noise_level_across_gaps_and_missing_readings():
    """Fourth differences across a gap of rows, or across missing readings, took the curve's own
    slope for noise: σ 0.22 °C for 0.02 from the papers' first 12 min with minutes 4-8 missing;
    0.025 for 0.02 with 12.5 % of the readings missing. Taken by their fourth divided difference at
    the readings' times, they cancel the curve as on an even grid."""
    rng = np.random.default_rng(0)
    t = np.arange(400.0)
    y = first_order(t) + 0.02 * rng.standard_normal(len(t))
    even = noise_sigma(y[:, None])
    np.testing.assert_allclose(noise_sigma(y[:, None], t), even, rtol=1e-12)  # an even grid: Δ⁴y/√70 as before
    keep = np.ones(len(t), dtype=bool)
    for start in range(5, 400, 40):  # ten 6-min gaps in the steep first part and after
        keep[start : start + 6] = False
    np.testing.assert_allclose(noise_sigma(y[keep, None], t[keep]), [0.02], rtol=0.15)
    missing = y.copy()
    missing[rng.random(len(t)) < 0.125] = np.nan
    np.testing.assert_allclose(noise_sigma(missing[:, None]), [0.02], rtol=0.15)
    repeated = t.copy()
    repeated[101] = repeated[100]  # two readings at one time (a merged log) give no difference there
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        np.testing.assert_allclose(noise_sigma(y[:, None], repeated), [0.02], rtol=0.15)


@pytest.mark.parametrize(("step", "expected"), [(0.1, 0.1), (0.01, 0.01), (1 / 16, 0.0625), (0.5, 0.5), (None, 0.0)])
def test_display_resolution_is_the_step_the_readings_are_rounded_to(step, expected):
    t = np.arange(0.0, 31.0)
    curve = first_order(t)
    readings = curve if step is None else np.round(curve / step) * step
    assert display_resolution(readings[:, None]) == pytest.approx([expected])
    # a flat column shows no step (a constant 20.0 is not a 1 °C display); NaN cells are skipped
    assert display_resolution(np.array([[20.0], [20.0], [np.nan], [20.0]])) == pytest.approx([0.0])


@pytest.mark.parametrize("step", [0.1, 0.01, 1 / 16])
def test_a_clean_curve_logged_in_rounded_steps_is_identified_within_its_interval(step):
    """Rounding a smooth curve makes most fourth differences exactly 0: the noise used to come out
    as 1e-9 °C, and a 0.1 °C log ended in 'covariance not positive definite'."""
    t = np.arange(0.0, 401.0)
    readings = np.round(first_order(t) / step) * step
    sigma = noise_sigma(readings[:30, None])[0]
    assert step / np.sqrt(12.0) - 1e-12 <= sigma < step
    result = identify(make_log(t, {"S": readings}), 30.0, "ukf")
    assert abs(result.steady_state_C[0] - PAPER_STEADY) <= result.details.quantile * result.details.steady_state_sd_C[0]
    # as wide as noise of q/√12 allows (the Cramér-Rao bound of that noise), not a collapse or a blow-up
    bound = np.sqrt(cramer_rao_bound(t[:31], PAPER_START, PAPER_RATE, PAPER_STEADY, sigma)[2, 2])
    assert 0.5 * bound < result.details.steady_state_sd_C[0] < 2.0 * bound


def test_a_coarse_room_sensors_slow_error_is_its_steps_and_a_fine_ones_none():
    rng = np.random.default_rng(4)
    t = np.arange(0.0, 120.0)
    room = 21.12 + 0.2 * np.sin(2 * np.pi * t / 1440.0) + rng.normal(0.0, 0.01, t.size)
    assert room_error_C(t, np.round(room, 1)) == pytest.approx(0.1 / np.sqrt(12.0))
    assert room_error_C(t, np.round(room * 20.0) / 20.0) == pytest.approx(0.05 / np.sqrt(12.0))
    assert room_error_C(t, np.round(room, 2)) == 0.0
    assert room_error_C(t[:4], np.round(room[:4], 1)) == 0.0


def test_a_spike_beside_a_skipped_reading_is_a_spike_and_a_one_sided_end_is_not_judged():
    """An open circuit's 850 °C skipped (NaN), then 85.0 °C: the glitch's neighbour window held a
    missing reading, so it had no median and 85.0 was kept (T∞ interval to 48.6 °C, trusted). A
    window with most neighbours on both sides is judged; the last readings, with none after them, are not."""
    from mtident.thermal.readings import spikes

    y = 20.0 + 0.01 * np.arange(40.0)
    y[20], y[21] = np.nan, 85.0
    wild = spikes(y, 0.01, 0.0)
    assert wild[21] and wild.sum() == 1
    y[38] = 85.0  # one reading after it: a live log's end, judged when its neighbours come
    assert not spikes(y, 0.01, 0.0)[38]
    y[:] = 20.0 + 0.01 * np.arange(40.0)
    y[18:21] = np.nan  # three missing in a row before it: no neighbours that side
    y[21] = 85.0
    assert not spikes(y, 0.01, 0.0)[21]


def test_a_room_that_warms_like_a_machine_is_said_and_a_real_rooms_course_is_not():
    """A bearing's column named as the room (up 4.7 °C like a warm-up) gave time constants of 13
    to 424 min for a 120-min truth, without a word. A workshop's air on a daily cycle and drifting
    2.5 °C over a day is said nothing of; a spike is no level."""
    from mtident.thermal.readings import warming_room_warning

    t = np.arange(0.0, 600.0)
    bearing = 20.0 + 5.0 * (1.0 - np.exp(-t / 30.0))
    said = warming_room_warning(bearing, "room")
    assert said is not None and said.startswith(
        "the room sensor 'room' warmed 4.7 °C from its first level (20.32 to 25.00 °C)"
    )
    assert "`room_sensor`" in said
    # by when: a replay says it after the checks that read the same rows
    timed = warming_room_warning(bearing, "room", t)
    assert timed is not None and timed.startswith(
        "the room sensor 'room' warmed 4.7 °C from its first level (20.32 to 25.00 °C), up by more than 3 °C by "
        "t = 33 min,"
    )
    air = 20.0 + 0.5 * np.sin(2 * np.pi * t / 1440.0) + 2.5 * t / 1440.0
    spiked = air.copy()
    spiked[300] = 35.0
    assert warming_room_warning(air, "room") is None and warming_room_warning(spiked, "room") is None
    assert warming_room_warning(bearing[:8], "room") is None  # too few readings to tell


def test_a_stretch_that_froze_and_read_on_is_left_out_and_a_coarse_displays_repeats_are_not():
    """A logger channel repeated its last reading for 30 min and then read on: its repeats were
    fitted, and the sensor came out a misfit, T∞ 26.17 [25.91, 37.70] for a truth of 26.00. The
    stretch is found (from its second reading: the first is a real one) and left out; a settled
    sensor on a 0.1 °C display repeats its reading by the hour, which is no freeze; a channel stuck
    to the end is stuck_since's, not a stretch."""
    from mtident.thermal.readings import frozen_stretches, frozen_words, without_stuck

    t = np.arange(0.0, 200.0)
    rng = np.random.default_rng(3)
    y = np.round(20.0 + 6.0 * (1.0 - np.exp(-t / 40.0)) + rng.normal(0.0, 0.01, t.size), 3)
    y[80:111] = y[80]
    assert frozen_stretches(t, y) == [(81.0, 110.0)]
    values, since, frozen = without_stuck(t, y[:, None])
    assert frozen == [[(81.0, 110.0)]]
    assert np.isnan(since[0]) and np.isnan(values[81:111, 0]).all() and np.isfinite(values[[80, 111], 0]).all()
    assert frozen_words("T2", [(81.0, 110.0)]).startswith("T2: its readings froze at one value (t = 81 to 110 min)")
    coarse = np.round(20.0 + 6.0 * (1.0 - np.exp(-t / 20.0)) + rng.normal(0.0, 0.01, t.size), 1)
    assert frozen_stretches(t, coarse) == []
    # a 10-bit converter's 0.32 °C steps hold a slow rise for half an hour: 5 of 1,000 of the
    # benchmark's warm-ups were found frozen where the step was taken from the display's resolution
    from mtident.testing.warmups import random_warmup

    converter = random_warmup(np.random.default_rng(50079))
    assert converter.rounding_C == pytest.approx(0.32)
    assert frozen_stretches(converter.time_min, converter.reading_C) == []
    stuck = y.copy()
    stuck[150:] = stuck[150]
    assert frozen_stretches(t, stuck) == [(81.0, 110.0)]
