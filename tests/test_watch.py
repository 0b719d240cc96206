"""Live monitor: the log follower, the stopping rule, bad data, resuming after a kill."""

from __future__ import annotations

import hashlib
import json
import os
import pty
import re
import signal
import subprocess
import sys
import time
import warnings
from pathlib import Path

import numpy as np
import pytest
from conftest import first_order, logger_dialects, make_log
from hypothesis import example, given, settings
from hypothesis import strategies as st

from mtident.exceptions import InputError
from mtident.io.follow import LogFollower
from mtident.thermal.monitor import Monitor, MonitorSettings

T = np.arange(0.0, 401.0)


def csv_text(t: np.ndarray, columns: dict[str, np.ndarray]) -> str:
    lines = ["time_min," + ",".join(columns)]
    for k, tk in enumerate(t):
        lines.append(f"{tk:g}," + ",".join("" if np.isnan(v[k]) else f"{v[k]:.3f}" for v in columns.values()))
    return "\n".join(lines) + "\n"


# ---- follower ------------------------------------------------------------------------------

def test_follower_reads_new_rows_and_waits_for_a_partial_line(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text("time_min,A,B\n0,20.0,21.0\n1,20.1,21.1\n")
    follower = LogFollower(path)
    rows = follower.poll()
    np.testing.assert_allclose(rows.time_min, [0, 1])
    assert follower.sensors == ["A", "B"]
    with open(path, "a") as out:
        out.write("2,20.2,21.2\n3,20.")  # the logger is mid-line
    rows = follower.poll()
    np.testing.assert_allclose(rows.time_min, [2])
    with open(path, "a") as out:
        out.write("3,21.3\n")
    rows = follower.poll()
    np.testing.assert_allclose(rows.temperature_C, [[20.3, 21.3]])
    assert follower.poll().time_min.size == 0


def test_follower_waits_for_a_data_row_below_a_loggers_settings(tmp_path):
    """A logger writes its settings (no '#') and the header before its first row: the follower
    must not take the first settings line for the header meanwhile (it keeps the dialect)."""
    path = tmp_path / "live.csv"
    path.write_text("Logger: GL240\nInterval,60,s\n\ntime_min;A;B\n[min];[°C];[°C]\n")
    follower = LogFollower(path)
    rows = follower.poll()
    assert len(rows.time_min) == 0 and follower.dialect is None
    with path.open("a") as out:
        out.write("0;20,0;19,0\n1;20,1;19,1\n")
    rows = follower.poll()
    np.testing.assert_array_equal(rows.temperature_C, [[20.0, 19.0], [20.1, 19.1]])
    assert follower.sensors == ["A", "B"] and not rows.warnings


@pytest.mark.parametrize("dialect", list(logger_dialects(np.arange(3.0), {"A": np.zeros(3)}))[1:])
def test_follower_reads_logs_as_loggers_write_them_like_the_file_reader(tmp_path, dialect):
    """Written in pieces cut anywhere (in the preamble, mid-header, mid-line), and resumed
    from its saved position halfway, the follower reads each dialect as the whole-file reader
    does: the same times and temperatures as the plain CSV."""
    from mtident.io import read_temperature_log

    t = np.arange(0.0, 30.0)
    columns = {"A": first_order(t), "B": first_order(t, 18.0, 25.0, 0.02)}
    data = logger_dialects(t, columns)[dialect]
    (tmp_path / "plain.csv").write_bytes(logger_dialects(t, columns)["plain"])
    expected = read_temperature_log(tmp_path / "plain.csv")
    path = tmp_path / "live.csv"
    path.write_bytes(b"")
    follower = LogFollower(path)
    times, values = [], []
    cuts = sorted({0, 7, 40, 41, 95, 96, len(data) // 2, len(data) // 2 + 1, len(data) - 3, len(data)})
    for a, b in zip(cuts[:-1], cuts[1:], strict=True):
        with open(path, "ab") as out:
            out.write(data[a:b])
        if a == len(data) // 2:  # killed here and started again from the state file's position
            follower = LogFollower.resume(path, json.loads(json.dumps(follower.position())), None, None)
        rows = follower.poll()
        assert not rows.warnings
        times.extend(rows.time_min)
        values.extend(rows.temperature_C)
    np.testing.assert_allclose(times, expected.time_min, atol=1e-9)
    np.testing.assert_array_equal(np.array(values), expected.temperature_C)
    assert [re.sub(r"\s*[(/ ,].*$", "", s) for s in follower.sensors or []] == ["A", "B"]  # without a unit


def test_follower_refuses_repeated_and_backward_times(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text("time_min,A\n0,20\n1,20.1\n1,20.2\n0.5,20.3\n2,20.4\n")
    rows = LogFollower(path).poll()
    np.testing.assert_allclose(rows.time_min, [0, 1, 2])
    assert sum("repeats or goes back" in w for w in rows.warnings) == 2


def test_follower_and_watch_refuse_two_columns_of_one_name(tmp_path):
    """Both columns were read from the first one: the second sensor showed the first one's curve."""
    path = tmp_path / "log.csv"
    path.write_text("time_min,T1,T1\n0,20,21\n1,20.1,21.2\n")
    with pytest.raises(InputError, match=r"log.csv: the column name 'T1' appears twice \(columns 2 and 3\)"):
        LogFollower(path).poll()
    out = mtident("thermal", "watch", "log.csv", "--replay", cwd=tmp_path)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert "the column name 'T1' appears twice" in out.stderr


def test_follower_handles_a_replaced_log_without_double_counting(tmp_path):
    path = tmp_path / "log.csv"
    stamps = [f"2026-11-22T08:{m:02d}:00" for m in range(10)]
    path.write_text("stamp,A\n" + "".join(f"{s},{20 + i / 10}\n" for i, s in enumerate(stamps[:5])))
    follower = LogFollower(path)
    assert follower.poll().time_min.size == 5
    replacement = tmp_path / "new.csv"  # the logger restarts and rewrites the whole file
    replacement.write_text("stamp,A\n" + "".join(f"{s},{20 + i / 10}\n" for i, s in enumerate(stamps[:8])))
    os.replace(replacement, path)
    rows = follower.poll()
    np.testing.assert_allclose(rows.time_min, [5, 6, 7])
    assert any("truncated or replaced" in w for w in rows.warnings)


def test_follower_never_writes_to_the_log(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text(csv_text(T[:50], {"A": first_order(T[:50])}))
    before = (hashlib.sha256(path.read_bytes()).hexdigest(), path.stat().st_mtime_ns)
    follower = LogFollower(path)
    follower.poll()
    follower.poll()
    assert (hashlib.sha256(path.read_bytes()).hexdigest(), path.stat().st_mtime_ns) == before


# ---- stopping rule -------------------------------------------------------------------------

def replay(columns: dict[str, np.ndarray], t: np.ndarray = T, **settings: float) -> Monitor:
    monitor = Monitor(tuple(columns), MonitorSettings(**settings))
    monitor.feed(t, np.column_stack(list(columns.values())))
    return monitor


def test_first_order_stops_well_before_half_the_equilibrium_time():
    """The issue's claim is about the typical run (bench_watch: median 0.45 t_eq, the latest of 100
    at 0.68): over 12 seeds the median stop is before half t_eq, none after 0.75 t_eq, and every
    answer is within the tolerance."""
    equilibrium = np.log(20) / 0.016
    stops = []
    for seed in range(12):
        y = first_order(T) + 0.02 * np.random.default_rng(seed).standard_normal(len(T))
        result = replay({"S": y}).result()
        assert result["stop_time_min"] is not None
        assert abs(result["steady_state_C"] - 26.7) <= 0.2
        assert result["time_saved_min"] > 0
        stops.append(result["stop_time_min"] / equilibrium)
    assert np.median(stops) < 0.5 and max(stops) < 0.75


def test_the_expected_stop_on_a_first_order_warm_up_comes_true():
    """Forecast at 45 min from each filter run on with its own predicted readings, against the
    stop the rule then makes (bench_watch: over 100 seeds the median error is about 0 and half
    are within 4 min). Over 10 seeds: median within 6 min, each forecast finite."""
    errors = []
    for seed in range(10):
        y = first_order(T) + 0.02 * np.random.default_rng(seed).standard_normal(len(T))
        early = replay({"S": y[:46]}, T[:46])
        expected = early.expected_stop_time()
        assert expected is not None and expected > 45.0
        assert early.result()["expected_stop_time_min"] == expected
        errors.append(expected - replay({"S": y}).result()["stop_time_min"])
    assert abs(np.median(errors)) <= 6.0, errors


def test_the_forecast_changes_nothing_in_the_monitor():
    """It runs copies of the filters on: feeding on after it gives the same state as without it."""
    y = first_order(T) + 0.02 * np.random.default_rng(5).standard_normal(len(T))
    asked, plain = Monitor(("S",)), Monitor(("S",))
    for part in (slice(0, 40), slice(40, 70), slice(70, 401)):
        asked.feed(T[part], y[part, None])
        asked.expected_stop_times()
        plain.feed(T[part], y[part, None])
    assert json.dumps(asked.to_dict()) == json.dumps(plain.to_dict())


def test_a_filter_far_off_course_leaves_the_others_forecast_alone():
    """Found by a hypothesis hunt: a sensor's filter thrown off course (λ < 0, its factor at 1e21)
    ran on in the forecast with the others and overflowed (numpy's warning); run on alone, the
    sensors on a course are foreseen as before."""
    from dataclasses import replace

    rng = np.random.default_rng(1)
    # b warms slowly: its forecast runs on for hours, and a's state with it (it grew by e^(−λ·step) a step)
    columns = np.column_stack([first_order(T), first_order(T, steady=30.0, rate=0.006)]) + 0.02 * rng.standard_normal((len(T), 2))
    monitor = Monitor(("a", "b"))
    monitor.feed(T[:41], columns[:41])
    clean = monitor.expected_stop_times()
    assert np.isfinite(clean).all()
    broken = Monitor.from_dict(monitor.to_dict())
    assert broken.carry is not None and broken.carry.chol is not None
    mean = broken.carry.mean.copy()
    mean[0, 2] = np.nan  # where an overflow ends; before, numpy's eigenvalue solver gave up on the batch
    broken.carry = replace(broken.carry, mean=mean)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        expected = broken.expected_stop_times()
    assert np.isnan(expected[0]) and expected[1] == clean[1]


def test_the_expected_stop_before_a_course_after_the_decision_and_for_a_cold_sensor():
    rng = np.random.default_rng(8)
    heating, cold = first_order(T) + 0.02 * rng.standard_normal(len(T)), 20.0 + 0.02 * rng.standard_normal(len(T))
    start = replay({"S": heating[:5]}, T[:5])
    assert start.expected_stop_time() is None and start.result()["expected_stop_time_min"] is None
    # a sensor that never heats is left out of the decision, and of the expected stop
    monitor = replay({"heating": heating[:60], "cold": cold[:60]}, T[:60])
    times = monitor.expected_stop_times()
    assert np.isnan(times[1]) and times[0] > 59 and monitor.expected_stop_time() == times[0]
    assert [d["expected_stop_time_min"] for d in monitor.result()["sensors"]] == [times[0], None]
    done = replay({"heating": heating, "cold": cold})
    assert done.stop_time is not None and done.expected_stop_time() == done.stop_time == done.result()["expected_stop_time_min"]
    assert done.expected_stop_times()[0] == done.stop_time and np.isnan(done.expected_stop_times()[1])  # the cold sensor is left out


@pytest.mark.parametrize("seed", range(3))
def test_fast_plus_slow_does_not_stop_early_with_a_wrong_answer(seed):
    truth = 17.9 + 4.0 * (1 - np.exp(-T / 8.0)) + 6.0 * (1 - np.exp(-T / 150.0))
    final = 17.9 + 10.0
    monitor = replay({"S": truth + 0.02 * np.random.default_rng(200 + seed).standard_normal(len(T))})
    result = monitor.result()
    if result["stop_time_min"] is not None:
        assert abs(result["steady_state_C"] - final) <= 0.2, result


@pytest.mark.parametrize(("step", "noise"), [(0.01, 0.0), (1 / 16, 0.0), (1 / 16, 0.005), (0.1, 0.0)])
def test_readings_rounded_to_a_display_step_stop_with_the_right_answer(step, noise):
    """A clean 0.01 °C log never stopped (its filter, told the noise was 1e-9 °C, ran off to T∞ = −44 °C),
    and a 1/16 °C sensor called every other sample a spike: the noise is never taken below q/√12."""
    rng = np.random.default_rng(4)
    t = np.arange(0.0, 401.0)
    readings = np.round((first_order(t) + noise * rng.standard_normal(len(t))) / step) * step
    monitor = Monitor(("S",), MonitorSettings(tolerance_C=0.2))
    messages = monitor.feed(t, readings[:, None])
    result = monitor.result()
    assert result["stop_time_min"] is not None and result["stop_time_min"] < 0.7 * 187
    assert abs(result["steady_state_C"] - 26.7) < 0.2
    assert not [m for m in messages if "spike" in m or "wild" in m]


@pytest.mark.parametrize("seed", [6, 36])
def test_a_missing_first_reading_does_not_throw_the_filter_off_course(seed):
    """A first-order log with 12.5 % dropouts, its first reading among them. The start's tuning
    filled it with the column's mean: the start looked flat and high, the filter began at λ =
    0.24/min and T∞ 19.2 °C (seed 6), went to λ < 0, and never stopped within 200 min; seed 36
    said a misfit. Over 200 seeds 11 never stopped, none now (stop 17)."""
    t = np.arange(0.0, 200.0)
    rng = np.random.default_rng(seed)
    y = first_order(t) + 0.02 * rng.standard_normal(len(t))
    y[rng.random(len(t)) < 0.125] = np.nan
    assert np.isnan(y[0])
    monitor = Monitor(("a",))
    messages = monitor.feed(t[:11], y[:11, None])
    assert monitor.carry is not None and 0.0 < monitor.carry.mean[0, 2] < 0.1  # λ started on a warm-up's course
    messages += monitor.feed(t[11:], y[11:, None])
    result = monitor.result()
    assert result["stop_time_min"] is not None and abs(result["steady_state_C"] - 26.7) <= 0.2  # type: ignore[operator]
    assert not [m for m in messages if "spike" in m or "wild" in m or "fit the first-order model" in m or "left the interval" in m]


@pytest.mark.parametrize(("seed", "stop"), [(47, 97.0), (58, 81.0)])
def test_the_start_noise_around_missing_readings_is_not_taken_from_a_lucky_few(seed, stop):
    """bench_watch's 12.5 %-dropout replays 47 and 58: the first 10 min left 4 and 3 fourth
    differences between missing readings, their MAD gave σ = 0.003 and 0.002 °C for 0.02, and the
    filter took the next readings for spikes and changed course (47 stopped at 287 min, 58 at 363).
    The residuals of a short cubic through every reading keep σ near the truth."""
    y = first_order(T) + 0.02 * np.random.default_rng(seed).standard_normal((3, len(T)))[0]
    y[np.random.default_rng(30_000 + seed).random(len(T)) < 0.125] = np.nan
    monitor = replay({"S": y})
    assert not [m for m in monitor.notes if "spike" in m or "wild" in m]
    result = monitor.result()
    assert result["stop_time_min"] == stop and abs(result["steady_state_C"] - 26.7) <= 0.2  # type: ignore[operator]


def test_many_spikes_in_a_while_are_taken_as_more_noise():
    """A loose contact adds ±0.05 °C to every reading from 18 min on (the noise was 0.01 °C). Every
    other reading was more than 6σ off, never two in a row: each was rejected as a spike, the running
    noise estimate left the wild differences out and never learnt the new noise, and half the log
    was thrown away to its end. On stop 16's code, seeds 0 and 1 rejected 174 and 189 spikes and
    never stopped. A wild reading after three spikes within about 20 min is now more noise: taken
    in, the noise and the residuals' statistics estimated again; both stop within the tolerance (139
    and 132 min). Glitches far beyond any noise stay spikes however many come (below)."""
    for seed, relearnt in ((0, 57), (1, None)):
        y = first_order(T) + 0.01 * np.random.default_rng(seed).standard_normal(len(T)) + np.where(T >= 18, 0.05 * (-1.0) ** np.arange(len(T)), 0.0)
        monitor = replay({"S": y})
        assert len([m for m in monitor.notes if "rejected a spike" in m]) == 3
        said = [m for m in monitor.notes if "more noise than estimated, not spikes" in m]
        assert len(said) == 1
        if relearnt is not None:
            assert f"one more wild reading at t = {relearnt} min after 3 spikes in the last 20 min or so" in said[0]
        result = monitor.result()
        assert result["stop_time_min"] is not None and abs(result["steady_state_C"] - 26.7) <= 0.2  # type: ignore[operator]
    # a resumed monitor carries the spikes it rejected lately
    again = Monitor(("S",))
    again.feed(T[:54], y[:54, None])
    resumed = Monitor.from_dict(json.loads(json.dumps(again.to_dict())))
    resumed.feed(T[54:], y[54:, None])
    assert resumed.result() == result


def test_glitches_far_beyond_any_noise_stay_spikes_however_many():
    """Four +15 °C glitches 2 min apart: without the 25σ bound the fourth was taken in as noise and
    the monitor never stopped within 400 min; all four are rejected and it stops at 89 min."""
    y = first_order(T) + 0.02 * np.random.default_rng(3).standard_normal(len(T))
    y[[40, 42, 44, 46]] += 15.0
    monitor = replay({"S": y})
    assert len([m for m in monitor.notes if "rejected a spike" in m]) == 4
    assert not [m for m in monitor.notes if "more noise than estimated" in m]
    result = monitor.result()
    assert result["stop_time_min"] == 89.0 and abs(result["steady_state_C"] - 26.7) <= 0.2  # type: ignore[operator]


def test_the_model_check_message_says_which_test_failed():
    """Early large residuals of both signs may be more noise than the few samples so far showed
    (here a loose contact adds ±0.05 °C from 18 min on); residuals of one sign are a trend the
    model misses, or a filter started on the first minutes still settling. (A young noise estimate
    alone no longer raises it: the limit is the F quantile.)"""
    y = first_order(T) + 0.01 * np.random.default_rng(0).standard_normal(len(T)) + np.where(T >= 18, 0.05 * (-1.0) ** np.arange(len(T)), 0.0)
    messages = replay({"S": y}).notes
    assert any("residuals at t = 27 min are larger than the noise estimated so far from 20 readings" in m for m in messages)
    assert not any("a trend it misses" in m for m in messages)
    truth = 17.9 + 4.0 * (1 - np.exp(-T / 8.0)) + 6.0 * (1 - np.exp(-T / 150.0))
    messages = replay({"S": truth + 0.02 * np.random.default_rng(202).standard_normal(len(T))}).notes
    assert any("residuals at t = 28 min no longer fit the first-order model: a trend it misses (a slower mode, or its filter, 28 min old, still settling?)" in m for m in messages)
    # on first-order curves (bench_watch's noise): a young filter's trend is put down to either cause,
    # an older one's to a slower mode alone
    for seed, said in ((10, "t = 24 min no longer fit the first-order model: a trend it misses (a slower mode, or its filter, 24 min old, still settling?)"), (29, "t = 42 min no longer fit the first-order model: a trend it misses (a slower mode?)")):
        y = first_order(T) + 0.02 * np.random.default_rng(seed).standard_normal((3, len(T)))[0]
        assert any(said in m for m in replay({"S": y}).notes), seed


def test_bad_data_is_rejected_bridged_or_reported_without_harming_other_sensors():
    rng = np.random.default_rng(7)
    heating = first_order(T) + 0.02 * rng.standard_normal(len(T))
    cold = 20.0 + 0.02 * rng.standard_normal(len(T))
    clean = replay({"heating": heating.copy(), "cold": cold.copy()}, T)
    heating[30] = 35.0  # spike
    heating[40:43] = np.nan  # dropout
    keep = np.ones(len(T), dtype=bool)
    keep[45:55] = False  # gap
    monitor = Monitor(("heating", "cold"))
    messages = monitor.feed(T[keep], np.column_stack([heating, cold])[keep])
    assert any("rejected a spike at t = 30 min" in m for m in messages)
    # said once, not once per missing sample (a dead sensor would flood the terminal)
    dropouts = [m for m in messages if "no valid reading" in m]
    assert len(dropouts) == 1 and "t = 40 min" in dropouts[0] and "not repeated within 60 min" in dropouts[0]
    assert any("gap in the log" in m for m in messages)
    result = monitor.result()
    statuses = {d["sensor"]: d["status"] for d in result["sensors"]}
    assert statuses["cold"] == "no rise"
    assert result["stop_time_min"] is not None
    heating_estimate = next(d for d in result["sensors"] if d["sensor"] == "heating")["steady_state_C"]
    assert abs(heating_estimate - 26.7) <= 0.2
    # the bad samples of one sensor leave the other sensor's filter untouched
    cold_clean = clean.carry.mean[1]
    np.testing.assert_allclose(monitor.carry.mean[1][0], cold_clean[0], atol=0.05)


def test_a_run_of_wild_samples_is_a_change_not_spikes():
    y = first_order(T) + 0.02 * np.random.default_rng(3).standard_normal(len(T))
    y[40:] += 1.0  # the machine's load changed: a step the model did not expect
    monitor = Monitor(("S",))
    messages = monitor.feed(T, y[:, None])
    assert sum("rejected a spike" in m for m in messages) <= 2  # the first of a run, and one while re-learning
    assert any("not a spike" in m for m in messages)
    result = monitor.result()
    assert result["stop_time_min"] > 60 and abs(result["steady_state_C"] - 27.7) <= 0.2


@pytest.mark.parametrize("delay", [15.0, 40.0])
def test_a_warm_up_that_begins_after_the_log_is_identified_from_its_rise(delay):
    """The logger started before the spindle. The first version crashed (LinAlgError) after 15
    flat minutes: started on a flat window, its filter had λ ≈ 4/min and s ≈ 0, and after
    widening λ went to −10/min and grew to 1e28."""
    rng = np.random.default_rng(0)
    y = first_order(np.clip(T - delay, 0.0, None)) + 0.02 * rng.standard_normal(len(T))
    cold = 20.0 + 0.02 * rng.standard_normal(len(T))  # a sensor that never heats, alongside
    columns = np.column_stack([y, cold])
    monitor = Monitor(("S", "cold"))
    messages = monitor.feed(T, columns)
    assert sum("no rise in the first 10 min; waiting for its warm-up to begin" in m for m in messages) == 2
    result = monitor.result()
    stop = result["stop_time_min"]
    # measured (seed 0): 114 and 126 min, 0.01 and 0.03 °C off
    assert stop is not None and stop - delay < 0.6 * np.log(20) / 0.016
    s, c = result["sensors"]
    assert abs(s["steady_state_C"] - 26.7) <= 0.1 and c["status"] == "no rise"
    # killed while it waits for the rise, or just after its new start: the same decision
    for cut in (12, int(delay) + 5, int(delay) + 12):
        first = Monitor(("S", "cold"))
        first.feed(T[:cut], columns[:cut])
        resumed = Monitor.from_dict(json.loads(json.dumps(first.to_dict())))
        resumed.feed(T[cut:], columns[cut:])
        assert resumed.result() == result


@pytest.mark.parametrize("connected_at", [None, 20, 60])
def test_a_sensor_without_readings_at_the_start_waits_for_them(connected_at):
    """A sensor with no valid reading in the start window (dead, or plugged in later) crashed the
    monitor with an IndexError. Now it waits: never read, it is "no data" and left out of the
    decision; read later (a warm-up already under way), it is identified from its readings."""
    rng = np.random.default_rng(2)
    good = first_order(T) + 0.02 * rng.standard_normal(len(T))
    late = first_order(T, steady=30.0) + 0.02 * rng.standard_normal(len(T))
    late[: len(T) if connected_at is None else connected_at] = np.nan
    columns = np.column_stack([good, late])
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        monitor = Monitor(("good", "late"))
        messages = monitor.feed(T, columns)
    assert any("'late': no valid reading in the first 10 min" in m and "waiting for its readings" in m for m in messages)
    assert not any("'late': no valid reading at t =" in m for m in messages)  # not "bridged": there is nothing to bridge
    result = monitor.result()
    good_alone = replay({"good": good}).result()
    late_summary = result["sensors"][1]
    if connected_at is None:
        assert late_summary["status"] == "no data" and late_summary["steady_state_C"] is None
        assert result["stop_time_min"] == good_alone["stop_time_min"]
    else:
        assert result["stop_time_min"] is not None and result["stop_time_min"] > connected_at
        assert abs(late_summary["steady_state_C"] - 30.0) <= 0.2
    # killed while it waits for its readings, or just after: the same decision
    for cut in (12, (connected_at or 30) + 5):
        first = Monitor(("good", "late"))
        first.feed(T[:cut], columns[:cut])
        resumed = Monitor.from_dict(json.loads(json.dumps(first.to_dict())))
        resumed.feed(T[cut:], columns[cut:])
        assert resumed.result() == result


def test_a_sensor_flat_for_a_few_minutes_is_started_at_its_rise():
    y = first_order(np.clip(T - 5.0, 0.0, None)) + 0.02 * np.random.default_rng(1).standard_normal(len(T))
    monitor = Monitor(("S",))
    messages = monitor.feed(T, y[:, None])
    assert any("flat until t = 6 min; identifying it from the start of its rise" in m for m in messages)
    result = monitor.result()
    assert result["stop_time_min"] is not None and abs(result["steady_state_C"] - 26.7) <= 0.2


def test_state_round_trip_gives_the_same_decision():
    rng = np.random.default_rng(11)
    data = np.column_stack([first_order(T) + 0.02 * rng.standard_normal(len(T)), first_order(T, steady=30.0) + 0.02 * rng.standard_normal(len(T))])
    whole = Monitor(("A", "B"))
    whole.feed(T, data)
    for cut in (5, 60, 90):
        first = Monitor(("A", "B"))
        first.feed(T[:cut], data[:cut])
        resumed = Monitor.from_dict(json.loads(json.dumps(first.to_dict())))
        resumed.feed(T[cut:], data[cut:])
        assert resumed.result() == whole.result()


# ---- the command ---------------------------------------------------------------------------

def mtident(*args: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run([sys.executable, "-m", "mtident", *args], capture_output=True, text=True, timeout=300, check=False, cwd=cwd)


def test_watch_replay_json_contract(tmp_path):
    out = mtident("thermal", "watch", "@sample", "--replay", "--json", "--plot", str(tmp_path / "w.png"), cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert set(data) >= {"stop_time_min", "steady_state_C", "steady_state_ci95_C", "equilibrium_time_min", "sensors"}
    assert data["stop_time_min"] is not None and (tmp_path / "w.png").stat().st_size > 1000
    assert (tmp_path / "spindle_warmup.watch-state.json").is_file()
    assert "no room sensor; the room is taken to wander by about 0.05 °C in an hour" in out.stderr  # the assumption is said
    # the sample runs on to 400 min, past the stop: the decision is checked against where it settled
    hindsight = data["hindsight"]
    assert hindsight["stop_time_min"] == data["stop_time_min"] and hindsight["log_end_min"] == 400.0 and hindsight["room_shift_C"] == 0.0
    assert [d["sensor"] for d in hindsight["sensors"]] == [f"T{i}" for i in range(1, 11)]
    for d, decided in zip(hindsight["sensors"], data["sensors"], strict=True):
        assert d["steady_state_C"] == decided["steady_state_C"] and d["within_tolerance"] is True
        assert d["error_C"] == pytest.approx(d["steady_state_C"] - d["settled_C"], abs=1e-12)
    # measured: T∞ at the stop 0.02-0.10 °C above the last 10 readings' median
    assert max(abs(d["error_C"]) for d in hindsight["sensors"]) < 0.12
    assert "the log runs on to t = 400 min: checking the decision against where it settled" in out.stderr


def test_a_replay_checks_its_decision_against_the_rest_of_the_log(tmp_path):
    """The table and the verdict; a log that ends at the stop has nothing to check, and a log still
    rising at its end is said to end before its sensor settled."""
    from mtident.thermal.hindsight import check_decision

    t = np.arange(0.0, 401.0)
    y = first_order(t) + 0.02 * np.random.default_rng(4).standard_normal(len(t))
    out = mtident("thermal", "watch", "@sample", "--replay", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "Against the rest of the log (to t = 400 min)" in out.stdout
    assert "Every sensor that settled (10) is within the tolerance (0.2 °C) of T∞ at the stop; the log reached 95 % of its rise by t = 294 min, 11 min before the stop: the rule saved no time on this log." in " ".join(out.stdout.split())
    # a log that ends at the decision
    monitor = Monitor(("S",))
    monitor.feed(t[:40], y[:40, None])
    assert np.isnan(monitor.decided_steady_states()).all()  # no decision yet
    monitor.feed(t[40:], y[40:, None])
    assert monitor.stop_time is not None
    assert monitor.decided_steady_states().tolist() == [monitor.result()["steady_state_C"]]
    stop = int(monitor.stop_time)
    (tmp_path / "short.csv").write_text(csv_text(t[: stop + 1], {"S": y[: stop + 1]}))
    out = mtident("thermal", "watch", "short.csv", "--replay", "--json", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["stop_time_min"] == stop and "hindsight" not in json.loads(out.stdout)
    # a log that runs on past the stop but ends still rising (the curve's last quarter rises by 10 %)
    rising = 17.9 + 8.8 * t / 400.0
    check = check_decision(("S",), np.array([30.0]), 100.0, t, rising[:, None], 0.2)
    assert np.isnan(check.settled_C[0]) and not check.within[0] and check.to_dict()["sensors"][0]["within_tolerance"] is None
    (tmp_path / "long.csv").write_text(csv_text(t, {"S": np.where(t <= stop, y, y[stop] + 0.05 * (t - stop))}))
    out = mtident("thermal", "watch", "long.csv", "--replay", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "The log ends before its sensors settled: nothing to check the decision against." in out.stdout


def test_the_room_move_after_the_stop_is_added_to_t_inf():
    from mtident.thermal.hindsight import check_decision

    t = np.arange(0.0, 401.0)
    room = np.where(t < 200.0, 17.9, 18.0)  # 0.1 °C up after the stop, for good
    settled = 26.8 + np.zeros_like(t)  # the machine followed it
    values = np.column_stack([first_order(t) + np.where(t < 200.0, 0.0, 0.1 * (1 - np.exp(-0.016 * (t - 200.0)))), settled])
    check = check_decision(("A", "B"), np.array([26.7, np.nan]), 150.0, t, values, 0.2, room)
    assert check.room_shift_C == pytest.approx(0.1)
    # the machine's last 10 readings: 26.7 + 0.1 room − the warm-up and the room move still to come
    expected_A = float(np.median(values[-10:, 0]))
    np.testing.assert_allclose(check.error_C, [26.7 + 0.1 - expected_A, np.nan])
    assert abs(check.error_C[0]) < 0.05 and check.within.tolist() == [True, False]  # a sensor left out is no check
    assert [d["within_tolerance"] for d in check.to_dict()["sensors"]] == [True, None]  # type: ignore[index]
    assert repr(check).splitlines() == [
        "Hindsight(stop at 150 min, log to 400 min, room moved +0.10 °C, tolerance 0.2 °C)",
        f"  A: T∞ 26.70 °C, settled at {expected_A:.2f} °C: {check.error_C[0]:+.3f} °C, within",
        "  B: left out of the decision",
    ]


def test_watch_killed_mid_run_resumes_to_the_same_decision(tmp_path):
    rng = np.random.default_rng(21)
    columns = {"A": first_order(T) + 0.02 * rng.standard_normal(len(T)), "B": first_order(T, steady=29.0, rate=0.02) + 0.02 * rng.standard_normal(len(T))}
    full = tmp_path / "full.csv"
    full.write_text(csv_text(T, columns))
    reference = json.loads(mtident("thermal", "watch", str(full), "--replay", "--json", "--state", str(tmp_path / "ref.json"), cwd=tmp_path).stdout)
    assert reference.pop("hindsight")["log_end_min"] == 400.0  # a replay that runs on past the stop checks it; a live run ends there

    live = tmp_path / "live.csv"
    lines = full.read_text().splitlines(keepends=True)
    live.write_text("".join(lines[:40]))
    state = tmp_path / "live-state.json"
    cmd = [sys.executable, "-m", "mtident", "thermal", "watch", str(live), "--json", "--state", str(state), "--poll", "0.05", "--timeout", "20"]
    proc = subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    deadline = time.monotonic() + 60
    written = 40
    while time.monotonic() < deadline:  # feed rows while it runs, then kill it mid-stream
        if state.is_file():
            with open(live, "a") as out:
                out.write("".join(lines[written : written + 5]))
            written += 5
            if written >= 70:
                break
        time.sleep(0.05)
    time.sleep(0.3)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    saved = json.loads(state.read_text())
    assert 30 <= saved["monitor"]["last_t"] < 70
    live.write_text("".join(lines))  # the logger carries on while the monitor is down
    out = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, timeout=120, check=False)
    assert out.returncode == 0, out.stderr
    assert "resuming from" in out.stderr
    assert json.loads(out.stdout) == reference


def room(t: np.ndarray) -> np.ndarray:
    """A room drifting 0.15 °C on a 4-h air-conditioning cycle and rising 0.1 °C."""
    return 0.15 * np.sin(2 * np.pi * t / 240.0) + 0.1 * (1 - np.exp(-t / 200.0))


def machine_in_room(t: np.ndarray, rate: float = 0.016, rise: float = 8.8) -> np.ndarray:
    """The first-order heat balance with the drifting room as input: dT/dt = λ(T_room + ΔT∞ − T)."""
    from scipy.integrate import solve_ivp

    solution = solve_ivp(lambda tt, T: rate * (17.9 + room(tt) + rise - T), (t[0], t[-1]), [17.9], t_eval=t, rtol=1e-10, atol=1e-10, max_step=1.0)
    return solution.y[0]


def noisy_in_room(curve: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """A sensor's curve and the room sensor's reading, each with 0.02 °C of noise."""
    rng = np.random.default_rng(seed)
    return curve + 0.02 * rng.standard_normal(len(T)), 17.9 + room(T) + 0.02 * rng.standard_normal(len(T))


@pytest.mark.parametrize("seed", [100, 101])
def test_ambient_reference_follows_a_drifting_room(seed):
    sensor, ambient = noisy_in_room(machine_in_room(T), seed)
    monitor = Monitor(("S",))
    monitor.feed(T, sensor[:, None], ambient)
    result = monitor.result()
    stop = result["stop_time_min"]
    assert stop is not None and stop < np.log(20) / 0.016
    # the steady state the machine reaches if the room stays as it is at the stop
    assert abs(result["steady_state_C"] - (26.7 + room(np.array(stop)))) <= 0.2
    resumed = Monitor.from_dict(json.loads(json.dumps(monitor.to_dict())))
    assert resumed.ambient_level == monitor.ambient_level and resumed.ambient_time == monitor.ambient_time


@pytest.mark.parametrize("seed", [100, 101])
def test_directly_coupled_sensor_follows_its_rise_over_the_room(seed):
    sensor, ambient = noisy_in_room(first_order(T) + room(T), seed)
    monitor = Monitor(("S",), MonitorSettings(room_coupling="direct"))
    monitor.feed(T, sensor[:, None], ambient)
    result = monitor.result()
    stop = result["stop_time_min"]
    assert stop is not None
    assert abs(result["steady_state_C"] - (26.7 + room(np.array(stop)))) <= 0.2


def fast_slow_in_room(t: np.ndarray) -> np.ndarray:
    """A fast part (4 °C, τ 8 min) on a slow part (6 °C, τ 150 min) that feels the drifting room."""
    from scipy.integrate import solve_ivp

    def rhs(tt: float, T: np.ndarray) -> np.ndarray:
        return np.array([(4.0 - T[0]) / 8.0, (17.9 + room(tt) + 6.0 - T[1]) / 150.0])

    solution = solve_ivp(rhs, (t[0], t[-1]), [0.0, 17.9], t_eval=t, rtol=1e-10, atol=1e-10, max_step=1.0)
    return solution.y[0] + solution.y[1]


@pytest.mark.parametrize("seed", [300, 303])
def test_fast_plus_slow_in_a_measured_room_is_identified_again_from_the_slow_part(seed):
    sensor, ambient = noisy_in_room(fast_slow_in_room(T), seed)
    monitor = Monitor(("S",))
    messages = monitor.feed(T, sensor[:, None], ambient)
    assert any("identifying it again from the next 30 min" in m for m in messages)
    result = monitor.result()
    stop = result["stop_time_min"]
    assert stop is not None and stop > 150  # not before the slow part is known
    assert abs(result["steady_state_C"] - (27.9 + room(np.array(stop)))) <= 0.15
    # killed while a re-identification waits for its data, or right after it: the same decision
    for cut in (40, 50, 60):
        first = Monitor(("S",))
        first.feed(T[:cut], sensor[:cut, None], ambient[:cut])
        resumed = Monitor.from_dict(json.loads(json.dumps(first.to_dict())))
        resumed.feed(T[cut:], sensor[cut:, None], ambient[cut:])
        assert resumed.result() == result
        # while a re-identification waits, the sensor is not expected to stop before it and a hold
        pending = first.restart_from[0]
        if np.isfinite(pending):
            assert first.expected_stop_times()[0] >= pending + 30 + 12


@pytest.mark.parametrize("coupling", ["lagged", "direct"])
def test_state_round_trip_with_a_room_sensor_gives_the_same_decision(coupling):
    sensor, ambient = noisy_in_room(machine_in_room(T), 12)
    ambient[25] = np.nan  # a missing room reading: the room held still
    settings = MonitorSettings(room_coupling=coupling)
    whole = Monitor(("S",), settings)
    whole.feed(T, sensor[:, None], ambient)
    for cut in (5, 26, 70):
        first = Monitor(("S",), settings)
        first.feed(T[:cut], sensor[:cut, None], ambient[:cut])
        resumed = Monitor.from_dict(json.loads(json.dumps(first.to_dict())))
        resumed.feed(T[cut:], sensor[cut:, None], ambient[cut:])
        assert resumed.result() == whole.result()


@pytest.mark.parametrize("coupling", ["lagged", "direct"])
def test_missing_room_readings_are_said_once_an_hour_and_bridged(coupling):
    """A dead room sensor used to pass unnoticed (lagged), or turned every sensor into "no data"
    with messages that blamed the sensors (direct)."""
    y, room_C = noisy_in_room(machine_in_room(T), 100)
    dead_until = 30
    room_C[:dead_until] = np.nan
    room_C[200] = np.nan
    monitor = Monitor(("S",), MonitorSettings(room_coupling=coupling))
    messages = monitor.feed(T, y[:, None], room_C)
    said = [m for m in messages if m.startswith("room sensor: no valid reading")]
    first = "the sensors' rise over the room waits for its first reading" if coupling == "direct" else "the room is taken as steady until its first reading"
    assert said[0].startswith("room sensor: no valid reading at t = 0 min") and first in said[0]
    assert len(said) == 1 + (monitor.last_t is not None and monitor.last_t >= 200)  # t = 0, and t = 200 if the test ran that far
    # lagged: the sensor's own readings are all there; direct: its rise over the room is not, until the room reads
    assert any("'S': no valid reading" in m for m in messages) == (coupling == "direct")
    assert monitor.result()["stop_time_min"] is not None


@pytest.mark.parametrize("seed", [2, 10])
def test_an_unmeasured_drifting_room_is_allowed_for(seed):
    """No room sensor: the default room wander keeps the answer within the tolerance where a
    steady-room filter (room_wander 0) is fooled by the room's cycle (bench_watch's noise for
    these seeds; measured: 0.016 and 0.065 °C off, 0.318 and 0.377 °C with room_wander 0. The
    seeds were 3 and 14 until the model check allowed for a young noise estimate: with
    room_wander 0 those two no longer stop within 400 min)."""
    noise = 0.02 * np.random.default_rng(seed).standard_normal((3, len(T)))[1]
    sensor = fast_slow_in_room(T) + noise
    wandering = Monitor(("S",))
    wandering.feed(T, sensor[:, None])
    steady = Monitor(("S",), MonitorSettings(room_wander_C_per_h=0.0))
    steady.feed(T, sensor[:, None])
    errors = []
    for monitor in (wandering, steady):
        result = monitor.result()
        stop = result["stop_time_min"]
        errors.append(float("nan") if stop is None else abs(result["steady_state_C"] - (27.9 + room(np.array(stop)))))
    assert not errors[0] > 0.2, errors
    assert errors[1] > 0.2, errors  # the case is a real one: without the allowance it stops too far off


def test_a_room_wandering_as_assumed_is_allowed_for_in_the_stop_interval():
    """The room the monitor assumes without a room sensor, a random walk of 0.05 °C in an hour:
    the error at the stop against the steady state under the room's level then, in units of the
    95 % half-width, has the RMS of a calibrated interval (0.51: error/(1.96σ)) where a
    steady-room filter's interval is too narrow (40 seeds, measured 0.50 and 0.71; on 100, 0.54
    and 0.76, coverage 93 % and 79 %), and no error is beyond the tolerance (largest 0.161 °C on 100)."""
    from scipy.signal import lfilter

    decay = np.exp(-0.016)
    normalised: dict[float, list[float]] = {0.05: [], 0.0: []}
    for seed in range(40):
        rng = np.random.default_rng(20_000 + seed)
        room_C = np.concatenate([[0.0], np.cumsum(0.05 * np.sqrt(1.0 / 60.0) * rng.standard_normal(len(T) - 1))])
        # the heat balance dT/dt = λ(T_room + ΔT∞ − T), exact for a room held over each minute
        rise, _ = lfilter([0.0, 1.0 - decay], [1.0, -decay], 8.8 + room_C, zi=[0.0])
        y = 17.9 + rise + 0.02 * rng.standard_normal(len(T))
        for wander, errors in normalised.items():
            monitor = Monitor(("S",), MonitorSettings(room_wander_C_per_h=wander))
            monitor.feed(T, y[:, None])
            result = monitor.result()
            stop = result["stop_time_min"]
            assert stop is not None
            error = result["steady_state_C"] - (26.7 + room_C[int(stop)])  # type: ignore[operator]
            low, high = result["steady_state_ci95_C"]  # type: ignore[misc]
            errors.append(error / ((high - low) / 2))
            if wander:
                assert abs(error) <= 0.2
    rms = {wander: float(np.sqrt(np.mean(np.square(errors)))) for wander, errors in normalised.items()}
    assert rms[0.05] <= 0.6, rms
    assert rms[0.0] >= 0.65, rms  # without the allowance the interval is too narrow for this room


def test_room_wander_is_the_random_input_of_the_heat_balance():
    rng = np.random.default_rng(5)
    y = first_order(T) + 0.02 * rng.standard_normal(len(T))
    monitor = Monitor(("S",), MonitorSettings(room_wander_C_per_h=0.1))
    monitor.feed(T[:59], y[:59, None])
    assert monitor.carry is not None and monitor.tuning is not None
    rate = monitor.carry.mean[0, 2]
    monitor.feed(T[59:60], y[59:60, None])
    # the step (1 min) added λ²σ²Δt/60 to the variance of s, nothing else
    added = monitor.carry.process_cov - monitor.tuning.process_cov
    np.testing.assert_allclose(added[0, 1, 1], rate**2 * 0.1**2 / 60.0, rtol=1e-6)
    added[0, 1, 1] = 0.0
    assert np.all(added == 0.0)
    # with a room sensor the room is an input, not an unknown
    measured = Monitor(("S",), MonitorSettings(room_wander_C_per_h=0.1))
    measured.feed(T[:60], y[:60, None], np.full(60, 17.9))
    assert measured.carry is not None and measured.tuning is not None
    np.testing.assert_array_equal(measured.carry.process_cov, measured.tuning.process_cov)


@pytest.mark.parametrize("value", [-0.1, float("nan"), float("inf")])
def test_a_bad_room_wander_is_refused(value):
    with pytest.raises(ValueError, match="room_wander_C_per_h"):
        MonitorSettings(room_wander_C_per_h=value)


@pytest.mark.parametrize("value", [-0.1, float("nan"), float("inf")])
def test_a_bad_bin_is_refused(value):
    with pytest.raises(ValueError, match="bin_min"):
        MonitorSettings(bin_min=value)


def one_hertz_warm_up(seed: int, step: float, noise: float, minutes: float = 150.0) -> tuple[np.ndarray, np.ndarray]:
    t = np.arange(0.0, minutes, 1.0 / 60.0)
    rng = np.random.default_rng(seed)
    return t, np.round((first_order(t) + noise * rng.standard_normal(len(t))) / step) * step


@pytest.mark.parametrize("noise", [0.005, 0.02])
def test_a_one_hertz_log_through_a_coarse_display_stops_with_the_right_answer(noise):
    """At 1 Hz a 0.1 °C display keeps its rounding for a minute at a time; fed sample by sample as
    if independent, the monitor never stopped (σ = 0.005 °C) or stopped at 290 min (0.02 °C)."""
    t, readings = one_hertz_warm_up(1, 0.1, noise)
    monitor = Monitor(("S",))
    messages = monitor.feed(t, readings[:, None])
    result = monitor.result()
    assert result["stop_time_min"] is not None and result["stop_time_min"] < 0.5 * 187
    assert abs(result["steady_state_C"] - 26.7) < 0.1
    assert len(messages) == 1  # only the decision


def test_a_one_hertz_log_resumes_mid_bin_to_the_same_decision():
    t, readings = one_hertz_warm_up(2, 0.01, 0.02, minutes=80.0)
    whole = Monitor(("S",))
    whole.feed(t, readings[:, None])
    pieces = Monitor(("S",))
    for start, stop in ((0, 7), (7, 1203), (1203, 1204), (1204, 3333), (3333, len(t))):
        pieces = Monitor.from_dict(json.loads(json.dumps(pieces.to_dict())))
        pieces.feed(t[start:stop], readings[start:stop, None])
    assert pieces.result() == whole.result() and whole.result()["stop_time_min"] is not None
    # a row as it arrives gives the same as a batch, and the time it reports is the latest row's
    rows = Monitor(("S",))
    for k in range(2000):
        rows.feed(t[k], [readings[k]])
    batch = Monitor(("S",))
    batch.feed(t[:2000], readings[:2000])
    assert rows.result() == batch.result() and rows.latest_time == pytest.approx(t[1999])


def test_watch_refuses_a_non_finite_tolerance(tmp_path):
    out = mtident("thermal", "watch", "@sample", "--replay", "--tolerance", "nan", cwd=tmp_path)
    assert out.returncode == 2 and "not a finite number" in out.stderr and "Traceback" not in out.stderr


def test_unknown_room_coupling_is_refused():
    with pytest.raises(ValueError, match="room_coupling"):
        MonitorSettings(room_coupling="sideways")


@pytest.mark.parametrize("seed", [101, 103])
def test_a_wandering_estimate_blocks_the_stop(seed):
    """Without a room sensor, a room cycle tilts the slope the filter sees, so T∞ wanders far outside
    its own earlier intervals; the old rule stopped where the wander turned round, 0.25 °C off."""
    rng = np.random.default_rng(seed)
    rng.standard_normal(len(T))  # the same draws as benchmarks/bench_watch.py's second case
    y = first_order(T) + room(T) + 0.02 * rng.standard_normal(len(T))
    monitor = Monitor(("S",))
    messages = monitor.feed(T, y[:, None])
    assert any("has left the interval" in m and "--ambient" in m for m in messages)
    result = monitor.result()
    if result["stop_time_min"] is not None:
        assert abs(result["steady_state_C"] - (26.7 + room(np.array(result["stop_time_min"])))) <= 0.2


@pytest.mark.parametrize("seed", range(100, 104))
def test_first_order_estimates_stay_inside_their_earlier_intervals(seed):
    y = first_order(T) + 0.02 * np.random.default_rng(seed).standard_normal(len(T))
    monitor = Monitor(("S",), MonitorSettings(tolerance_C=0.05))  # never stops: the whole log is checked
    messages = monitor.feed(T, y[:, None])
    assert not any("has left the interval" in m for m in messages)


def test_watch_ambient_option(tmp_path):
    rng = np.random.default_rng(5)
    path = tmp_path / "room.csv"
    path.write_text(csv_text(T, {"spindle": first_order(T) + room(T) + 0.02 * rng.standard_normal(len(T)), "room": 17.9 + room(T) + 0.02 * rng.standard_normal(len(T))}))
    out = mtident("thermal", "watch", str(path), "--ambient", "room", "--replay", "--json", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["sensor"] == "spindle" and data["stop_time_min"] is not None
    assert "--room-coupling lagged" in out.stderr and "give --room-coupling direct" in out.stderr  # the assumed coupling is said
    assert "no room sensor" not in out.stderr
    out = mtident("thermal", "watch", str(path), "--ambient", "room", "--room-coupling", "direct", "--replay", "--json", "--state", str(tmp_path / "d.json"), cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["stop_time_min"] is not None
    assert "give --room-coupling direct" not in out.stderr


def test_watch_ambient_finds_the_sensors_in_a_logger_dialect(tmp_path):
    """With --ambient and no --sensor the sensors are the header's other columns. The header
    was split at commas after a plain readline: a cp1252 log raised UnicodeDecodeError (a
    traceback), and a ';' log had no sensors."""
    rng = np.random.default_rng(5)
    spindle, air = first_order(T) + room(T) + 0.02 * rng.standard_normal(len(T)), 17.9 + room(T) + 0.02 * rng.standard_normal(len(T))
    lines = ["# Messung 3", "Zeit;Spindel °C;Raum"] + [f"{t:g};{a:.3f};{b:.3f}".replace(".", ",") for t, a, b in zip(T, spindle, air, strict=True)]
    path = tmp_path / "room_de.csv"
    path.write_bytes(("\n".join(lines) + "\n").encode("cp1252"))
    plain = tmp_path / "room.csv"
    plain.write_text(csv_text(T, {"Spindel °C": np.round(spindle, 3), "Raum": np.round(air, 3)}))
    out = mtident("thermal", "watch", str(path), "--ambient", "Raum", "--replay", "--json", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    expected = mtident("thermal", "watch", str(plain), "--ambient", "Raum", "--replay", "--json", cwd=tmp_path)
    assert json.loads(out.stdout) == json.loads(expected.stdout) and json.loads(out.stdout)["sensor"] == "Spindel °C"


def test_room_coupling_needs_a_room_sensor(tmp_path):
    out = mtident("thermal", "watch", "@sample", "--room-coupling", "direct", "--replay", cwd=tmp_path)
    assert out.returncode != 0 and "--room-coupling needs --ambient" in out.stderr and "Traceback" not in out.stderr


def test_live_table_shows_every_sensor_with_its_band_and_status():
    from rich.console import Console

    from mtident.cli_thermal import _status_table

    rng = np.random.default_rng(4)
    monitor = Monitor(("spindle", "motor"))
    monitor.feed(T[:50], np.column_stack([first_order(T[:50]), first_order(T[:50], steady=30.0)]) + 0.02 * rng.standard_normal((50, 2)))
    console = Console(record=True, width=120)
    console.print(_status_table(monitor, Path("logs/log.csv")))
    text = console.export_text()
    assert "log.csv: at t = 49 min" in text and "T∞ ± 95 % (°C)" in text
    for status in monitor.status():
        assert status.sensor in text and status.status in text and f"{status.steady_state_C:.2f}" in text
    for when in monitor.expected_stop_times():  # each sensor's expected stop, in its own column
        assert f"{when:.0f}" in text
    console = Console(record=True, width=120)
    console.print(_status_table(monitor, Path("logs/log.csv"), live=True))  # the live view adds the test's
    assert f"expected stop: t ≈ {round(monitor.expected_stop_time())} min, in {round(monitor.expected_stop_time()) - 49} min" in " ".join(console.export_text().split())


def test_the_live_picture_marks_each_sensors_expected_stop():
    from mtident.report import plot_monitor

    rng = np.random.default_rng(4)
    monitor = Monitor(("spindle", "motor"))
    y = np.column_stack([first_order(T[:50]), first_order(T[:50], steady=30.0)]) + 0.02 * rng.standard_normal((50, 2))
    monitor.feed(T[:50], y)
    figure = plot_monitor(make_log(T[:50], {"spindle": y[:, 0], "motor": y[:, 1]}), monitor)
    for ax, when in zip(figure.axes, monitor.expected_stop_times(), strict=True):
        lines = [line for line in ax.get_lines() if line.get_label() == "expected stop"]
        assert len(lines) == 1 and lines[0].get_xdata()[0] == when


def in_a_terminal(args: list[str], cwd: Path) -> tuple[int, str]:
    """Run mtident with a terminal on stdout (rich draws its live table); its exit code and the screen, without colours."""
    main, secondary = pty.openpty()
    proc = subprocess.Popen([sys.executable, "-m", "mtident", *args], stdout=secondary, stderr=subprocess.DEVNULL, cwd=cwd)
    os.close(secondary)
    chunks = []
    while True:  # read while it writes: a full terminal buffer would stall it
        try:
            chunk = os.read(main, 65536)
        except OSError:  # the terminal closed: the command has exited
            break
        if not chunk:
            break
        chunks.append(chunk)
    os.close(main)
    code = proc.wait(timeout=300)
    return code, re.sub(r"\x1b\[[0-9;?]*[A-Za-z]", "", b"".join(chunks).decode("utf-8", "replace"))


def test_watch_in_a_terminal_draws_the_live_table(tmp_path):
    """With a terminal on stdout the command draws the rich table in place (and does not crash)."""
    code, screen = in_a_terminal(["thermal", "watch", "@sample", "--replay", "--state", str(tmp_path / "s.json")], tmp_path)
    assert code == 0
    assert "T∞ ± 95 %" in screen and "T10" in screen and "The test can stop at t = 305 min" in screen


def test_watch_in_a_terminal_rings_the_bell_at_a_live_decision(tmp_path):
    """At the machine the decision is heard as well as seen (not in a replay)."""
    from mtident.io import sample_log_path

    log = tmp_path / "warmup.csv"
    log.write_bytes(sample_log_path().read_bytes())
    code, screen = in_a_terminal(["thermal", "watch", str(log), "--timeout", "1"], tmp_path)
    assert code == 0 and "The test can stop at t = 305 min" in screen and "\a" in screen
    code, screen = in_a_terminal(["thermal", "watch", str(log), "--replay", "--state", "r.json"], tmp_path)
    assert code == 0 and "The test can stop" in screen and "\a" not in screen


def test_watch_in_a_terminal_at_the_start_of_a_test(tmp_path):
    """Started on a log shorter than the start window (the usual case at the machine), the table
    shows the sensors collecting; this was a TypeError in the live view and the final table."""
    rng = np.random.default_rng(3)
    log = tmp_path / "start.csv"
    log.write_text(csv_text(T[:5], {"A": first_order(T[:5]) + 0.02 * rng.standard_normal(5)}))
    code, screen = in_a_terminal(["thermal", "watch", str(log), "--replay"], tmp_path)
    assert code == 0
    assert "start.csv: at t = 4 min" in screen and "collecting" in screen and "nan" not in screen
    assert "Not yet: keep the test running." in screen


def test_watch_of_a_test_under_way_says_when_it_expects_to_stop(tmp_path):
    """The log so far (60 min) does not decide; the table gives each sensor's expected stop and
    the last line the test's, with the assumption it rests on; --json gives the same time."""
    rng = np.random.default_rng(2)
    log = tmp_path / "under_way.csv"
    log.write_text(csv_text(T[:61], {"A": first_order(T[:61]) + 0.02 * rng.standard_normal(61), "B": first_order(T[:61], steady=30.0) + 0.02 * rng.standard_normal(61)}))
    out = mtident("thermal", "watch", str(log), "--replay", "--json", "--state", "a.json", cwd=tmp_path)
    data = json.loads(out.stdout)
    assert data["decision"] == "continue" and data["expected_stop_time_min"] > 60
    assert data["expected_stop_time_min"] == max(d["expected_stop_time_min"] for d in data["sensors"])
    out = mtident("thermal", "watch", str(log), "--replay", "--state", "b.json", cwd=tmp_path)
    assert "stop ≈ (min)" in out.stdout
    expected = round(data["expected_stop_time_min"])
    assert f"Expected stop: t ≈ {expected} min, in {expected - 60} min, at the earliest: on the present first-order courses (a slower mode or a drifting room moves it later)" in " ".join(out.stdout.split())
    # with a room sensor the room is in the model: only a slower mode can move it
    room = tmp_path / "with_room.csv"
    room.write_text(csv_text(T[:61], {"A": first_order(T[:61]) + 0.02 * rng.standard_normal(61), "room": 17.9 + 0.02 * rng.standard_normal(61)}))
    out = mtident("thermal", "watch", str(room), "--ambient", "room", "--replay", "--state", "c.json", cwd=tmp_path)
    assert "on the present first-order courses (a slower mode moves it later)" in " ".join(out.stdout.split())


def test_watch_run_again_after_its_decision_gives_the_same_answer(tmp_path):
    """The state file holds the decision: the same command again resumes and prints it (it raised in
    the table before, the saved covariance factor's missing dense form read back as NaN)."""
    first = mtident("thermal", "watch", "@sample", "--replay", "--json", cwd=tmp_path)
    again = mtident("thermal", "watch", "@sample", "--replay", "--json", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert "resuming from" in again.stderr and "at t = 305 min" in again.stderr
    assert json.loads(again.stdout) == json.loads(first.stdout)
    table = mtident("thermal", "watch", "@sample", "--replay", cwd=tmp_path)
    assert table.returncode == 0, table.stderr
    assert "The test can stop at t = 305 min" in table.stdout
    other = mtident("thermal", "watch", "@sample", "--replay", "--json", "--tolerance", "0.3", cwd=tmp_path)
    assert "resuming" not in other.stderr
    assert "was written for other settings (--tolerance, --hold, --room-coupling, --room-wander, --bin, --time-col or --time-unit); starting afresh" in other.stderr


def test_watch_interrupted_says_where_it_was_and_keeps_its_state(tmp_path):
    """Ctrl-C while following a log: no traceback, the last saved answer, where it stopped, exit 130."""
    rng = np.random.default_rng(4)
    log = tmp_path / "live.csv"
    log.write_text(csv_text(T[:60], {"A": first_order(T[:60]) + 0.02 * rng.standard_normal(60)}))
    state = tmp_path / "live-state.json"
    proc = subprocess.Popen(
        [sys.executable, "-m", "mtident", "thermal", "watch", str(log), "--json", "--state", str(state), "--poll", "0.05"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
    )
    deadline = time.monotonic() + 120
    while not state.is_file() and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.3)  # now it waits for new rows
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    assert "interrupted (Ctrl-C) at t = 59 min" in err and "the same command resumes from there" in err
    result = json.loads(out)
    assert result["decision"] == "continue" and result["last_time_min"] == 59.0
    assert result["steady_state_C"] == pytest.approx(26.7, abs=0.5)
    assert json.loads(state.read_text())["monitor"]["last_t"] == 59.0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["live-state.json", "live.csv"]  # no stray temporary file


def test_the_sample_with_its_room_sensor(tmp_path):
    from mtident.cli_thermal import sample_log_path
    from mtident.io import read_temperature_log

    plain, with_room = read_temperature_log(sample_log_path()), read_temperature_log(sample_log_path("@sample-room"))
    assert with_room.sensors == (*plain.sensors, "room")
    np.testing.assert_array_equal(with_room.select(list(plain.sensors)).temperature_C, plain.temperature_C)
    out = mtident("thermal", "watch", "@sample-room", "--ambient", "room", "--replay", "--json", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    # measured: 197 min with the room sensor, 305 min without; every T∞ within 0.07 °C of the network's steady state
    assert data["stop_time_min"] is not None and data["stop_time_min"] < 250
    assert [d["sensor"] for d in data["sensors"]] == list(plain.sensors)
    assert "named as a room sensor" not in out.stderr
    # checked against the rest of the log, T∞ moved with the room (measured: −0.10 °C after the stop)
    hindsight = data["hindsight"]
    assert hindsight["room_shift_C"] == pytest.approx(-0.10, abs=0.02)
    assert all(d["within_tolerance"] for d in hindsight["sensors"])
    out = mtident("thermal", "watch", "@sample-room", "--replay", "--json", cwd=tmp_path)
    assert out.returncode == 0, out.stderr
    assert "'room' is named as a room sensor and watched as a machine sensor; if it measures the room, --ambient room makes it" in out.stderr
    assert {"sensor": "room", "status": "no rise"}.items() <= json.loads(out.stdout)["sensors"][-1].items()


# ---- damaged logs: any mix of the bad data above ----------------------------------------------

STATUSES = {"collecting", "narrowing", "settling", "wandering", "model check", "may stop", "no rise", "no data", "no steady state yet"}


@settings(max_examples=12, deadline=None)
@given(
    seed=st.integers(0, 2**16),
    dropout_fraction=st.floats(0.0, 0.2),
    dead_until=st.sampled_from([0, 8, 25, 400]),
    late_start=st.sampled_from([0.0, 12.0]),
    gap=st.tuples(st.integers(20, 150), st.integers(0, 25)),
    spikes=st.integers(0, 3),
    with_room=st.booleans(),
    cut=st.integers(5, 150),
)
# found by a hunt: sensor c dead for 8 min, then a 24-min gap 30 min after a restart was scheduled
@example(seed=1666, dropout_fraction=0.1875, dead_until=8, late_start=0.0, gap=(37, 24), spikes=0, with_room=False, cut=5)
def test_a_damaged_log_never_crashes_warns_or_loses_the_decision(seed, dropout_fraction, dead_until, late_start, gap, spikes, with_room, cut):
    """Dropouts, a sensor dead for a while (or for good), a late warm-up, a gap, spikes, with or
    without a room sensor: the monitor raises nothing, warns nothing, reports known statuses, and
    a monitor killed at ``cut`` and resumed ends where an uninterrupted one does."""
    t = np.arange(0.0, 200.0)
    rng = np.random.default_rng(seed)
    columns = np.column_stack([first_order(t), first_order(np.clip(t - late_start, 0.0, None), steady=30.0), first_order(t, steady=24.0)])
    columns = columns + 0.02 * rng.standard_normal(columns.shape)
    columns[rng.random(columns.shape) < dropout_fraction] = np.nan
    columns[:dead_until, 2] = np.nan
    columns[rng.integers(15, len(t), spikes), rng.integers(0, 3, spikes)] += 15.0
    keep = np.ones(len(t), dtype=bool)
    keep[gap[0] : gap[0] + gap[1]] = False
    t, columns = t[keep], columns[keep]
    room_C = 17.9 + 0.02 * rng.standard_normal(len(t)) if with_room else None
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        whole = Monitor(("a", "b", "c"))
        whole.feed(t, columns, room_C)
        result = whole.result()
        cut = min(cut, len(t) - 1)
        first = Monitor(("a", "b", "c"))
        first.feed(t[:cut], columns[:cut], None if room_C is None else room_C[:cut])
        expected = first.expected_stop_times()  # the forecast on a damaged log: no error, no warning
        json.dumps(first.result())
        resumed = Monitor.from_dict(json.loads(json.dumps(first.to_dict())))
        resumed.feed(t[cut:], columns[cut:], None if room_C is None else room_C[cut:])
        if whole.stop_time is not None:  # the decision against the whole damaged log, as a replay checks it
            from mtident.thermal.hindsight import check_decision

            check = check_decision(whole.sensors, whole.decided_steady_states(), whole.stop_time, t, columns, 0.2, room_C)
            json.dumps(check.to_dict())
    assert resumed.result() == result
    assert {d["status"] for d in result["sensors"]} <= STATUSES
    if first.stop_time is None and first.last_t is not None:
        assert np.all(np.isnan(expected) | (expected >= first.last_t))
    json.dumps(result)


def test_watch_waits_for_a_log_the_logger_has_not_created_yet(tmp_path):
    """Started before the logger: it says it waits, picks the log up when it appears, and says
    why if it never does."""
    never = mtident("thermal", "watch", "later.csv", "--poll", "0.05", "--timeout", "0.5", cwd=tmp_path)
    assert never.returncode == 2
    assert "waiting for later.csv to appear" in never.stderr and "later.csv: no such file (not created within the --timeout of 0.5 s)" in never.stderr

    rng = np.random.default_rng(5)
    proc = subprocess.Popen(
        [sys.executable, "-m", "mtident", "thermal", "watch", "later.csv", "--json", "--poll", "0.05", "--timeout", "30"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
    )
    time.sleep(1.0)
    (tmp_path / "later.csv").write_text(csv_text(T, {"A": first_order(T) + 0.02 * rng.standard_normal(len(T))}))
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    assert json.loads(out)["decision"] == "stop"


def test_watch_with_a_room_sensor_waits_for_a_log_not_created_yet_and_resumes(tmp_path):
    """With --ambient and no --sensor, a log that appeared after the start ended in "Monitor needs at
    least one sensor name" (the sensors were taken from a header not yet written)."""
    rng = np.random.default_rng(6)
    columns = {"A": first_order(T) + room(T) + 0.02 * rng.standard_normal(len(T)), "room": 17.9 + room(T) + 0.02 * rng.standard_normal(len(T))}
    text = csv_text(T, columns)
    lines = text.splitlines(keepends=True)
    proc = subprocess.Popen(
        [sys.executable, "-m", "mtident", "thermal", "watch", "later.csv", "--ambient", "room", "--json", "--poll", "0.05", "--timeout", "3"],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, cwd=tmp_path,
    )
    time.sleep(1.0)
    (tmp_path / "later.csv").write_text("".join(lines[:41]))  # the header and 40 min
    out, err = proc.communicate(timeout=120)
    assert proc.returncode == 0, err
    first = json.loads(out)
    assert first["sensor"] == "A" and first["last_time_min"] == 39.0
    (tmp_path / "later.csv").write_text(text)
    again = mtident("thermal", "watch", "later.csv", "--ambient", "room", "--json", "--replay", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert "resuming from" in again.stderr and "starting afresh" not in again.stderr
    whole = mtident("thermal", "watch", "later.csv", "--ambient", "room", "--json", "--replay", "--state", "other.json", cwd=tmp_path)
    assert json.loads(again.stdout) == json.loads(whole.stdout)
    (tmp_path / "room_only.csv").write_text(csv_text(T, {"room": columns["room"]}))
    alone = mtident("thermal", "watch", "room_only.csv", "--ambient", "room", "--replay", cwd=tmp_path)
    assert alone.returncode == 2 and "room_only.csv: no sensor column besides the room sensor 'room'" in alone.stderr


@pytest.mark.parametrize(
    ("sensors", "times", "values", "ambient", "message"),
    [
        (("A", "B"), T[:20], np.zeros((20, 1)), None, "expected times (n,), values (n, 2) for the sensors A, B; got times (20,), values (20, 1)"),
        (("A",), T[:10], np.zeros((20, 1)), None, "got times (10,), values (20, 1)"),
        (("A",), T[:20], np.zeros((20, 1)), np.zeros(5), "and ambient (n,); got times (20,), values (20, 1), ambient (5,)"),
        (("A",), T[20::-1], np.zeros((21, 1)), None, "time 1 of this batch (19 min) does not come after the one before it (20 min); times must increase"),
        (("A",), np.r_[T[:5], T[4:10]], np.zeros((11, 1)), None, "time 5 of this batch (4 min) does not come after the one before it (4 min)"),
        (("A",), np.r_[T[:5], np.nan], np.zeros((6, 1)), None, "time 5 of this batch is not a finite number of minutes"),
        (("A",), T[:3], [["x"], ["y"], ["z"]], None, "must be numbers (could not convert string to float: 'x')"),
    ],
)
def test_monitor_feed_names_what_is_wrong_with_its_samples(sensors, times, values, ambient, message):
    monitor = Monitor(sensors)
    with pytest.raises(InputError, match=re.escape(message)):
        monitor.feed(times, values, ambient)
    assert monitor.samples == 0  # nothing of a refused batch was used


def test_monitor_feed_refuses_times_before_those_it_has_seen_and_takes_one_sensor_as_a_column():

    rng = np.random.default_rng(6)
    y = first_order(T) + 0.02 * rng.standard_normal(len(T))
    column, flat = Monitor(("A",)), Monitor("A")  # a single name is one sensor
    column.feed(T[:20], y[:20, None])
    flat.feed(T[:20], y[:20])
    assert flat.sensors == ("A",) and json.dumps(flat.to_dict()) == json.dumps(column.to_dict())
    with pytest.raises(InputError, match=re.escape("time 0 of this batch (15 min) does not come after the one before it (19 min)")):
        column.feed(T[15:30], y[15:30, None])
    with pytest.raises(InputError, match="Monitor needs at least one sensor name"):
        Monitor(())
    by_row = Monitor(("A",))  # row by row as they arrive: a time and the readings
    for k in range(20):
        by_row.feed(float(T[k]), [y[k]])
    assert json.dumps(by_row.to_dict()) == json.dumps(column.to_dict())


@pytest.mark.parametrize(("interval_s", "rows_per_bin"), [(1.0, 10), (0.5, 20), (5.0, 2), (6.0, 2), (7.0, 1), (9.5, 1), (10.0, 1), (60.0, 1)])
def test_rows_are_gathered_into_bins_nearest_ten_seconds(interval_s, rows_per_bin):
    """A fast log is fed in bins of the row count nearest 10 s; a 10-s logger whose clock runs a
    little fast (rows 9.5 s apart) was fed in pairs, 19 s a sample."""
    t = np.arange(0.0, 1800.0, interval_s) / 60.0
    monitor = Monitor(("S",), MonitorSettings(tolerance_C=1e-3))  # never stops: every row is fed
    monitor.feed(t, first_order(t)[:, None] + 0.02 * np.random.default_rng(1).standard_normal((len(t), 1)))
    # the first row is fed alone (no interval to judge by yet), then bins of rows_per_bin
    assert monitor.samples == 1 + (len(t) - 1) // rows_per_bin
    assert len(monitor.pending) == (len(t) - 1) % rows_per_bin


def test_a_jittery_ten_second_log_is_fed_row_by_row():
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(9.0, 11.0, 360)) / 60.0
    monitor = Monitor(("S",), MonitorSettings(tolerance_C=1e-3))
    monitor.feed(t, first_order(t)[:, None] + 0.02 * rng.standard_normal((len(t), 1)))
    assert monitor.samples == len(t) and len(monitor.pending) == 0


def test_a_row_back_in_time_is_refused_also_after_a_closed_bin():
    """A closed bin's mean time lies before its last row: a row between them was taken as new."""
    t = np.arange(0.0, 31.0) / 60.0  # the first row alone, then three bins of 10
    monitor = Monitor(("S",))
    monitor.feed(t, first_order(t)[:, None])
    assert len(monitor.pending) == 0 and monitor.latest_time == pytest.approx(t[-1])
    with pytest.raises(InputError, match="does not come after"):
        monitor.feed(t[-1] - 2.0 / 60.0, [first_order(t[-1])])


def test_a_log_with_a_units_row_and_a_speed_channel(tmp_path):
    """identify and watch read a units row (time in s, a room sensor in K) and leave out a channel
    that is no temperature; before, the units row was refused as a bad time."""
    t = np.arange(0.0, 121.0)
    rng = np.random.default_rng(4)
    spindle = 26.7 - 8.8 * np.exp(-0.016 * t) + 0.02 * rng.standard_normal(len(t))
    rows = "".join(f"{60 * m:g},{s:.3f},{291.05 + 0.02 * rng.standard_normal():.3f},{3000 + m:g}\n" for m, s in zip(t, spindle, strict=True))
    log = tmp_path / "units.csv"
    log.write_text("time,spindle,room,speed\n[s],[°C],[K],[rpm]\n" + rows)
    identify = mtident("thermal", "identify", str(log), "--window", "30", "--json", cwd=tmp_path)
    assert identify.returncode == 0, identify.stderr
    assert [s["sensor"] for s in json.loads(identify.stdout)["sensors"]] == ["spindle", "room"]
    assert "speed (rpm)" in identify.stderr
    watch = mtident("thermal", "watch", str(log), "--replay", "--ambient", "room", "--json", cwd=tmp_path)
    assert watch.returncode == 0, watch.stderr
    result = json.loads(watch.stdout)
    assert result["sensor"] == "spindle" and abs(result["steady_state_C"] - 26.7) < 0.3
    refused = mtident("thermal", "identify", str(log), "--sensor", "speed", cwd=tmp_path)
    assert refused.returncode == 2 and "not a temperature" in refused.stderr and "Traceback" not in refused.stderr


def test_a_row_counter_and_a_millisecond_column_are_read_as_the_file_reader_reads_them(tmp_path):
    """Graphtec writes 'NO.,Time,ms,CH1,...': the counter was taken for the time (in minutes: a
    500-ms log read 60x too slow per row), and the millisecond column for a sensor. The time is
    the stamp plus its milliseconds (two rows per second), the same live and whole."""
    import datetime as dt

    from mtident.io import read_temperature_log

    start = dt.datetime(2026, 11, 22, 8, 0, 0)
    rows = [f"{k + 1},{start + dt.timedelta(seconds=k // 2):%Y/%m/%d %H:%M:%S},{500 * (k % 2)},{20 + 0.01 * k:+.2f}" for k in range(40)]
    path = tmp_path / "gl240.csv"
    path.write_text("Model,GL240\n\nNO.,Time,ms,CH1\n" + "\n".join(rows) + "\n")
    whole = read_temperature_log(path)
    assert whole.sensors == ("CH1",) and whole.notes == ("left out, a row counter: NO.; the time is 'Time'",)
    np.testing.assert_allclose(whole.time_min * 60, 0.5 * np.arange(40), atol=1e-9)
    follower = LogFollower(path)
    rows_read = follower.poll()
    assert rows_read.notes == whole.notes and not rows_read.warnings
    np.testing.assert_allclose(rows_read.time_min, whole.time_min, atol=1e-6)
    np.testing.assert_array_equal(rows_read.temperature_C, whole.temperature_C)


def test_watch_bin_option_sets_the_bin_length(tmp_path):
    """--bin SECONDS gives the library's bin_min (the 10-s bin had no option); a state file
    written with another bin starts afresh, and one written with the default resumes."""
    t = np.arange(0.0, 90.0 * 60.0, 2.0) / 60.0  # 0.5 Hz for 90 min
    y = first_order(t) + 0.02 * np.random.default_rng(4).standard_normal(len(t))
    log = tmp_path / "fast.csv"
    log.write_text("time_min,S\n" + "".join(f"{a:.6f},{b:.3f}\n" for a, b in zip(t, y, strict=True)))
    results = {}
    for bin_s in (0.0, 30.0):
        out = mtident("thermal", "watch", str(log), "--replay", "--json", "--bin", f"{bin_s:g}", cwd=tmp_path)
        assert out.returncode == 0, out.stderr
        monitor = Monitor(("S",), MonitorSettings(bin_min=bin_s / 60.0))
        monitor.feed(np.round(t, 6), np.round(y, 3)[:, None])
        results[bin_s] = json.loads(out.stdout)
        assert results[bin_s]["steady_state_C"] == pytest.approx(monitor.result()["steady_state_C"], abs=1e-9)
    assert results[0.0]["steady_state_C"] != results[30.0]["steady_state_C"]
    again = mtident("thermal", "watch", str(log), "--replay", "--json", cwd=tmp_path)
    assert "starting afresh" in again.stderr and "--bin" in again.stderr
    default = mtident("thermal", "watch", str(log), "--replay", "--json", "--bin", "10", cwd=tmp_path)
    assert "resuming from" in default.stderr


def test_watch_names_spreadsheet_serial_dates_and_restarts_in_days(tmp_path):
    """The follower tells serial dates at the second row (it read them as 0.0007-min steps and
    stayed 'collecting'); a state saved after the first row is not resumed with another
    --time-unit, whose origin would be in other units. (A column named as dates is read in days:
    test_io; this one is named as a time.)"""
    log = tmp_path / "serial.csv"
    log.write_text("Time,T1\n46348.33333300,17.90\n")
    state = tmp_path / "s.json"
    first = mtident("thermal", "watch", str(log), "--timeout", "0", "--state", str(state), cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    log.write_text("Time,T1\n" + "".join(f"{46348.333333 + k / 1440:.8f},{26.7 - 8.8 * np.exp(-0.016 * k):.2f}\n" for k in range(120)))
    refused = mtident("thermal", "watch", str(log), "--replay", "--state", str(state), cwd=tmp_path)
    assert refused.returncode == 2 and "looks like spreadsheet serial dates" in refused.stderr and "Traceback" not in refused.stderr
    days = mtident("thermal", "watch", str(log), "--replay", "--json", "--time-unit", "d", "--state", str(state), cwd=tmp_path)
    assert days.returncode == 0, days.stderr
    assert "starting afresh" in days.stderr
    result = json.loads(days.stdout)
    assert 30 <= result["stop_time_min"] <= 119 and result["steady_state_C"] == pytest.approx(26.7, abs=0.2)


def test_a_comment_with_as_many_cells_as_the_header_does_not_delay_a_live_log():
    """The header after '#' lines is read at the first data row, also where a comment splits into
    as many cells as the header ('# channels: A, B' above 'time,A')."""
    from mtident.io.dialect import sniff_dialect

    dialect = sniff_dialect(b"# channels: A, B\ntime,A\n0,20\n", wait_for_row=True)
    assert dialect is not None and dialect.preamble_lines == 1
    assert sniff_dialect(b"Model,GL240\nTitle,x\n\nNO.,Time,ms,A\n", wait_for_row=True) is None  # no data row yet
    dialect = sniff_dialect(b"Model,GL240\nTitle,x\n\nNO.,Time,ms,A\n1,2026/11/22 08:00:00,0,20\n", wait_for_row=True)
    assert dialect is not None and dialect.preamble_lines == 3
