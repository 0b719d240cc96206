"""Tests of :mod:`mtident.io.stamps`: time stamps as loggers write them, read into minutes."""

from __future__ import annotations

import datetime as dt

import numpy as np
import pytest
from helpers import _local_clock_log, followed_in_pieces
from hypothesis import given, settings
from hypothesis import strategies as st

from mtident.exceptions import InputError
from mtident.io import read_temperature_log


def test_a_time_of_day_passes_midnight_in_an_overnight_test(write_csv, tmp_path):
    """Before, 23:59 then 00:00 was refused as time going back."""
    from mtident.io.follow import LogFollower

    text = "clock,A\n" + "".join(
        f"{h:02d}:{m:02d}:00,{20 + k / 10}\n"
        for k, (h, m) in enumerate([(23, 57), (23, 58), (23, 59), (0, 0), (0, 1), (0, 3)])
    )
    np.testing.assert_allclose(read_temperature_log(write_csv(text)).time_min, [0, 1, 2, 3, 4, 6])
    np.testing.assert_allclose(LogFollower(write_csv(text)).poll().time_min, [0, 1, 2, 3, 4, 6])
    with pytest.raises(InputError, match="row 4: time goes back"):
        read_temperature_log(write_csv("clock,A\n08:00:00,20\n08:01:00,20\n07:59:00,21\n08:03:00,21\n08:04:00,21\n"))
    with pytest.raises(InputError, match="no header line, only # comments"):
        read_temperature_log(write_csv("# logger\n\n# nothing yet\n"))


@settings(max_examples=40, deadline=None)
@given(
    day=st.sampled_from(["2026-10-25", "2026-11-01", "2026-03-29", "2026-03-08", "2026-04-05", "2026-09-27"]),
    start_min=st.integers(0, 170),
    step_s=st.sampled_from([1, 10, 60, 300]),
    back=st.booleans(),
    fmt=st.sampled_from(["%d.%m.%Y %H:%M:%S", "%Y-%m-%dT%H:%M:%S", "%m/%d/%Y %I:%M:%S %p"]),
    cuts=st.lists(st.floats(0.0, 1.0), max_size=3),
)
def test_any_summer_time_change_reads_alike_whole_and_live(tmp_path_factory, day, start_min, step_s, back, fmt, cuts):
    """A local clock put back or forward an hour at 02:00 or 03:00 (as Europe, North America and
    Australia do) under any sampling interval and stamp format: the file reader and the follower,
    fed in random pieces, both read the true elapsed time."""

    change = dt.datetime.fromisoformat(day) + dt.timedelta(hours=3 if back and day.startswith("2026-10") else 2)
    if step_s < 60:  # 1-s and 10-s rows: 5 min with the change 1-4 min from the start (the follower
        rows = 300 // step_s  # parses a stamp a row: two hours of 1-s rows from midnight cost 2-4 s an example)
        first = change - dt.timedelta(minutes=1 + start_min % 4)
    else:  # four hours from midnight + start_min: the change in them, or (started after it) not
        rows = int(14400 / step_s) + 1
        first = dt.datetime.fromisoformat(day) + dt.timedelta(minutes=start_min)
    real = [first + dt.timedelta(seconds=step_s * k) for k in range(rows)]
    clock = [
        r - dt.timedelta(hours=1)
        if back and r >= change
        else r + dt.timedelta(hours=1)
        if not back and r >= change
        else r
        for r in real
    ]
    text = "time,T1\n" + "".join(f"{c.strftime(fmt)},{20 + k / rows:.4f}\n" for k, c in enumerate(clock))
    folder = tmp_path_factory.mktemp("summer")
    whole = folder / "whole.csv"
    whole.write_text(text)
    expected = np.arange(rows) * step_s / 60.0
    np.testing.assert_allclose(read_temperature_log(whole).time_min, expected, atol=1e-6)
    data = text.encode()
    _, times = followed_in_pieces(folder / "live.csv", data, [int(c * len(data)) for c in cuts])
    np.testing.assert_allclose(times, expected, atol=1e-6)


def test_an_hour_back_that_is_no_summer_time_change_is_still_refused(write_csv):
    """At noon, on a Saturday, or in July the clock is not changed for summer time, and an hour
    back that is no change of the clock (a half-hour step back) is refused as before."""
    for start, change_at, shift in (
        ("2026-10-25 10:00:00", 120, -1),
        ("2026-10-24 00:00:00", 180, -1),
        ("2026-07-26 00:00:00", 180, -1),
    ):
        with pytest.raises(InputError, match="time goes back"):
            read_temperature_log(write_csv(_local_clock_log(start, change_at, shift)))
    with pytest.raises(InputError, match="time goes back"):
        read_temperature_log(
            write_csv(
                _local_clock_log("2026-10-25 02:00:00", 30, 0).replace("25.10.2026 02:31:00", "25.10.2026 02:01:30")
            )
        )
    # a jump forward at noon stays a gap of an hour, and is said as one
    log = read_temperature_log(write_csv(_local_clock_log("2026-03-29 10:00:00", 120, 1)))
    assert log.time_min[120] - log.time_min[119] == 61
    assert log.notes == (
        "a gap of 61 min in the readings after t = 119 min (otherwise a reading every 1 min): the fit bridges it",
    )


def test_a_date_and_a_time_of_day_in_two_columns_are_one_stamp(write_csv):
    """Datum;Uhrzeit as European loggers write them: refused before ("'01.03.2026' is neither a
    number nor a time stamp"); the clock column is no sensor."""
    text = "Datum;Uhrzeit;T1\n" + "".join(
        f"01.03.2026;23:{50 + m // 2}:{30 * (m % 2):02d};{20 + m / 10:.1f}\n" for m in range(10)
    )
    text += "02.03.2026;00:00:00;21.0\n02.03.2026;00:01:00;21.1\n"  # past midnight: the date tells
    log = read_temperature_log(write_csv(text))
    assert log.sensors == ("T1",)
    np.testing.assert_allclose(log.time_min, [*np.arange(10) * 0.5, 10.0, 11.0])
    with pytest.raises(InputError, match=r"time column 'Datum \+ Uhrzeit', row 4 is empty"):
        read_temperature_log(write_csv(text.replace("01.03.2026;23:51:00", "01.03.2026;")))


@pytest.mark.parametrize("fmt", ["%d-%m-%Y %H:%M:%S", "%d-%b-%Y %H:%M:%S"])
def test_dashed_day_first_stamps(write_csv, fmt):
    """22-11-2026 08:00:00 and 22-Nov-2026 08:00:00 (spreadsheets, LabVIEW) were refused as no time stamp."""

    start = dt.datetime(2026, 11, 30, 23, 58, 0)  # across the end of the month
    rows = "".join(f"{(start + dt.timedelta(minutes=k)).strftime(fmt)},{20 + k / 10:.2f}\n" for k in range(6))
    log = read_temperature_log(write_csv("stamp,A\n" + rows))
    np.testing.assert_allclose(log.time_min, np.arange(6.0))


def test_a_scan_counter_and_milliseconds_after_a_colon(write_csv):
    """Keysight BenchLink's 'Scan,Time,101 (C)' with 11/22/2026 08:00:10:500: the scan counter was
    read as the time in minutes (a 10-s scan as 1 min, silently) and the stamp was text."""

    start = dt.datetime(2026, 11, 22, 8, 0, 0)
    rows = "".join(
        f"{k + 1},{start + dt.timedelta(seconds=10 * k):%m/%d/%Y %H:%M:%S}:{500 * (k % 2):03d},{20 + k / 100:.3f}\n"
        for k in range(30)
    )
    log = read_temperature_log(write_csv("Scan,Time,101 (C)\n" + rows))
    assert log.sensors == ("101 (C)",) and log.notes == ("left out, a row counter: Scan; the time is 'Time'",)
    np.testing.assert_allclose(log.time_min * 60, 10 * np.arange(30) + 0.5 * (np.arange(30) % 2), atol=1e-6)


def test_a_dataframe_of_local_stamps_is_read_across_a_summer_time_change_like_its_csv(write_csv):
    import pandas as pd

    stamps = ["2026-10-25 01:30:00", "2026-10-25 02:00:00", "2026-10-25 02:30:00", "2026-10-25 02:00:00"]
    stamps += ["2026-10-25 02:30:00", "2026-10-25 03:00:00"]
    frame = pd.DataFrame({"A": 20 + np.arange(6.0)}, index=pd.Index(pd.to_datetime(stamps), name="t"))
    log = read_temperature_log(frame)
    text = read_temperature_log(write_csv("t,A\n" + "".join(f"{s},{20 + k}\n" for k, s in enumerate(stamps))))
    np.testing.assert_array_equal(log.time_min, [0, 30, 60, 90, 120, 150])
    np.testing.assert_array_equal(log.time_min, text.time_min)
    assert "read as the end of summer time" in log.notes[0] and "at row 3" in log.notes[0]
