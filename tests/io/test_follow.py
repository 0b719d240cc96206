"""Tests of :mod:`mtident.io.follow`."""

from __future__ import annotations

import hashlib
import os
import re
from pathlib import Path

import numpy as np
import pytest
from conftest import first_order, logger_dialects, through_state_file
from helpers import UNITS_LOG, T, _local_clock_log, csv_text, mtident

from mtident.exceptions import InputError
from mtident.io import read_temperature_log
from mtident.io.follow import LogFollower


def test_stamps_whose_offset_changes_when_summer_time_ends_stay_in_order(write_csv):
    """02:50+02:00 is followed by 02:00+01:00, ten minutes later. pandas refused the mixed
    offsets with a ValueError that reached the user as a traceback."""
    from mtident.io.follow import LogFollower

    stamps = [
        "02:30:00+02:00",
        "02:40:00+02:00",
        "02:50:00+02:00",
        "02:00:00+01:00",
        "02:10:00+01:00",
        "02:20:00+01:00",
    ]
    path = write_csv("stamp,A\n" + "".join(f"2026-10-25T{s},{20 + k / 10}\n" for k, s in enumerate(stamps)))
    np.testing.assert_allclose(read_temperature_log(path).time_min, [0, 10, 20, 30, 40, 50])
    np.testing.assert_allclose(LogFollower(path).poll().time_min, [0, 10, 20, 30, 40, 50])


@pytest.mark.parametrize(
    ("start", "change_at", "shift_h", "step_s", "said"),
    [
        (
            "2026-10-25 00:00:00",
            180,
            -1,
            60,
            "go back an hour at row 182 ('25.10.2026 02:59:00' then '25.10.2026 02:00:00'): read as the end of "
            "summer time",
        ),
        (
            "2026-11-01 01:40:00",
            120,
            -1,
            10,
            "go back an hour at row 122 ('01.11.2026 01:59:50' then '01.11.2026 01:00:00')",
        ),  # US, 10-s rows
        (
            "2026-03-29 00:00:00",
            120,
            1,
            60,
            "jump an hour at row 122 ('29.03.2026 01:59:00' then '29.03.2026 03:00:00'): read as the start of summer "
            "time",
        ),
    ],
)
def test_a_local_clock_changed_for_summer_time_is_read_across_the_change(
    write_csv, start, change_at, shift_h, step_s, said
):
    """Stamps without an offset go back an hour when summer time ends (the file was refused:
    "time goes back"; the follower refused the repeated hour row by row) and jump an hour when it
    begins (read as an hour's gap: the warm-up seemed to stand still for an hour). Both readers
    now read the true elapsed time, with a note, also followed in pieces across the change."""
    from mtident.io.follow import LogFollower

    path = write_csv(_local_clock_log(start, change_at, shift_h, step_s=step_s))
    log = read_temperature_log(path)
    np.testing.assert_allclose(log.time_min, np.arange(240) * step_s / 60, atol=1e-9)
    assert [n for n in log.notes if said in n] and len(log.notes) == 1
    text = path.read_bytes()
    live = path.with_name("live.csv")
    cut = text.index(b"\n", len(text) * change_at // 240 - 40) + 1  # a few rows before the change
    live.write_bytes(text[:cut])
    follower = LogFollower(live)
    first = follower.poll()
    live.write_bytes(text)
    resumed = LogFollower.resume(live, through_state_file(follower.position()), None, None)
    second = resumed.poll()
    np.testing.assert_allclose(np.concatenate([first.time_min, second.time_min]), log.time_min, atol=1e-9)
    assert not second.warnings and [n for n in second.notes if said.split(" at row")[0] in n and "after t = " in n]


def test_a_follower_restarted_after_a_summer_time_change_does_not_count_rows_twice(write_csv):
    """The logger restarts and writes its log again from the start: the rows before and after the
    change come again, and none is taken twice (the hour's shift is found again)."""
    from mtident.io.follow import LogFollower

    text = _local_clock_log("2026-10-25 00:00:00", 180, -1)
    path = write_csv(text)
    follower = LogFollower(path)
    first = follower.poll()
    path.unlink()
    path.write_text(text + "25.10.2026 03:00:00;26,500\n")  # replaced, one row more
    again = follower.poll()
    assert len(first.time_min) == 240 and again.time_min.tolist() == [240.0]


def test_an_elapsed_clock_past_24_hours_is_read_as_elapsed_time(write_csv):
    """A data-acquisition program's elapsed time as hh:mm:ss (a test of more than a day: 23:50:00,
    24:00:00, 26:10:00) was refused at 24:00:00 as "neither a number nor a time stamp"; both
    readers read it as minutes from the start, the file reader with a note."""
    from mtident.io.follow import LogFollower

    minutes = np.arange(0, 26 * 60 + 1, 10)
    text = "Time,Channel 1 (°C)\n" + "".join(f"{m // 60:02d}:{m % 60:02d}:00,{20 + m / 1000:.3f}\n" for m in minutes)
    log = read_temperature_log(write_csv(text))
    np.testing.assert_allclose(log.time_min, minutes)
    assert log.notes == ("time column 'Time' read as hours:minutes:seconds elapsed (it runs past 24:00:00)",)
    live = write_csv(text[: text.index("23:50:00")], "live.csv")
    follower = LogFollower(live)
    first = follower.poll()
    live.write_text(text)
    second = follower.poll()
    np.testing.assert_allclose(np.concatenate([first.time_min, second.time_min]), minutes)
    assert not second.warnings
    # a cell past 24:00:00 that is no clock is still refused
    with pytest.raises(InputError, match="row 5: '24:75:00' is neither a number nor a time stamp like the first one"):
        read_temperature_log(
            write_csv("Time,T1\n23:30:00,20\n23:40:00,20\n23:50:00,20\n24:75:00,20\n25:00:00,20\n25:10:00,20\n")
        )


@pytest.mark.parametrize(
    "cut", [5, len("time;T1;T2;T3;speed\n") + 3, len("time;T1;T2;T3;speed\n[s];°C;K;°F;rpm\n") + 4]
)
def test_a_live_log_reads_its_units_row_like_the_whole_file(tmp_path, cut):
    """Also when the units row is not yet written at the first look (a cut after the header)."""
    from mtident.io.follow import LogFollower

    data = UNITS_LOG.encode()
    cut = len(UNITS_LOG[:cut].encode())
    live = tmp_path / "live.csv"
    live.write_bytes(data[:cut])
    follower = LogFollower(live)
    first = follower.poll()
    live.write_bytes(data)
    second = follower.poll()
    times = np.concatenate([first.time_min, second.time_min])
    values = np.concatenate([first.temperature_C.reshape(-1, 3), second.temperature_C])
    np.testing.assert_allclose(times, np.arange(12.0))
    np.testing.assert_allclose(values, np.repeat((20 + 0.1 * np.arange(12.0))[:, None], 3, axis=1), atol=1e-9)
    assert follower.sensors == ["T1", "T2", "T3"]
    assert not first.warnings + second.warnings
    assert any("speed (rpm)" in n for n in first.notes + second.notes)


def test_a_live_decimal_comma_log_whose_header_comes_first_reads_its_numbers(tmp_path):
    """A logger writes its header at the start and a row a minute later; the follower took the
    dialect from the header alone (decimal point) and read every '20,5' as NaN."""
    from mtident.io.follow import LogFollower

    live = tmp_path / "live.csv"
    live.write_text("Zeit;Temp, Spindel;Temp, Motor\n")
    follower = LogFollower(live)
    assert len(follower.poll().time_min) == 0
    live.write_text("Zeit;Temp, Spindel;Temp, Motor\n0;20,5;19,5\n1;20,6;19,6\n")
    rows = follower.poll()
    np.testing.assert_array_equal(rows.temperature_C, [[20.5, 19.5], [20.6, 19.6]])
    assert follower.sensors == ["Temp, Spindel", "Temp, Motor"]


def test_a_follower_position_resumes_through_the_state_file_and_an_older_one_is_refused(tmp_path):
    """The position is a frozen value that the generic persistence saves (the dialect with its units
    row); the dicts and lists older versions saved (a dialect of four, five or eight entries) are
    refused with the way on, not read by branches of their own."""
    from mtident.io.dialect import CsvDialect
    from mtident.io.follow import FollowPosition, LogFollower

    live = tmp_path / "live.csv"
    live.write_text("time;T1\nmin;K\n0;293,5\n")
    follower = LogFollower(live)
    follower.poll()
    position = through_state_file(follower.position())
    assert isinstance(position, FollowPosition) and position == follower.position()
    assert position.layout is not None and position.layout.dialect == CsvDialect(
        ";", ",", 0, "utf-8-sig", (("time", "min"), ("T1", "K")), 1
    )
    with open(live, "a") as out:
        out.write("1;293,6\n")
    rows = LogFollower.resume(live, position, None, None).poll()
    np.testing.assert_allclose(rows.temperature_C, [[293.6 - 273.15]])
    older = {"offset": 20, "dialect": [";", ",", 0, "utf-8-sig", [["time", "min"], ["T1", "K"]]]}
    with pytest.raises(
        InputError, match=r"live.csv: the follower's position is a dict, as an older version .*start afresh"
    ):
        LogFollower.resume(live, older, None, None)  # type: ignore[arg-type]


def test_a_whole_log_in_seconds_read_at_once_is_told_by_its_step(tmp_path):
    """A replay reads the whole log in one poll: its span passed two days before the first rows'
    step was looked at, so the hint said it "runs to 2900 min (2.0 days)", which a newcomer took
    for a hint that came only after two days of readings."""
    from mtident.io.follow import LogFollower

    live = tmp_path / "whole.csv"
    live.write_text("time,T1\n" + "".join(f"{s},{20 + 6 * (1 - np.exp(-s / 1800)):.2f}\n" for s in range(0, 28801, 20)))
    hints = [w for w in LogFollower(live).poll().warnings if "read as minutes" in w]
    assert len(hints) == 1 and "a reading every 20 min: if it is in seconds" in hints[0]


@pytest.mark.parametrize(
    ("fmt", "start"),
    [
        ("%m/%d/%Y %I:%M:%S %p", "2026-11-22 23:50"),  # a US logger (HOBO): month first, AM/PM
        ("%d/%m/%Y %H:%M:%S", "2026-11-01 23:50"),  # day first, 01/11 -> 02/11 at midnight: not Jan 11 -> Feb 11
        ("%m/%d/%Y %H:%M:%S", "2026-01-11 23:50"),  # month first, the same dates the other way
        ("%d.%m.%y %H:%M", "2026-11-22 23:50"),  # two-digit year, no seconds
        ("%H:%M", "2026-11-22 23:50"),  # a clock without seconds passes midnight
    ],
)
def test_slashed_dates_am_pm_and_clocks_without_seconds(tmp_path, fmt, start):
    """Each was refused ("neither a number nor a time stamp"); a slashed date is read month first
    unless the first stamp or the first change of date says day first, whole and live alike."""
    import datetime as dt

    from mtident.io.follow import LogFollower

    first = dt.datetime.fromisoformat(start)
    minutes = np.arange(0.0, 30.0)
    text = "stamp,T1\n" + "".join(
        f"{(first + dt.timedelta(minutes=float(m))).strftime(fmt)},{20 + m / 10:.1f}\n" for m in minutes
    )
    path = tmp_path / "log.csv"
    path.write_text(text)
    np.testing.assert_allclose(read_temperature_log(path).time_min, minutes)
    live = tmp_path / "live.csv"
    follower = LogFollower(live)
    times: list[float] = []
    for cut in (60, 400, len(text)):  # the change of date comes in the last piece
        live.write_text(text[:cut])
        rows = follower.poll()
        assert not rows.warnings
        times.extend(rows.time_min)
    np.testing.assert_allclose(times, minutes)


def test_header_sensors_are_the_ones_the_first_poll_takes(write_csv):
    """watch --ambient resolved the sensors from the header with its own rules (a status column was
    kept as a sensor there, left out by the follower); it now asks the follower."""
    from mtident.io.follow import LogFollower

    path = write_csv("time,room,T1,Status\n" + "".join(f"{m},18.0,{20 + m / 10:.1f},OK\n" for m in range(10)))
    assert LogFollower(path, None, room="room").header_sensors() == ["T1", "room"]
    follower = LogFollower(path, None, room="room")
    follower.poll()
    assert follower.sensors == ["T1", "room"]
    assert LogFollower(write_csv("time,T1\n", "empty.csv"), None).header_sensors() is None


def test_alarm_and_status_channels_are_no_sensors(write_csv, tmp_path):
    """Keysight BenchLink writes each channel's alarm as 0 or 1 ('Alarm 101'): read as a sensor, flat,
    it was "no rise" in watch and an identification of nothing in identify. Left out by name in
    both readers; asked for with --sensor, it is read."""
    from mtident.io.follow import LogFollower

    text = "Scan,Time,101 (C),Alarm 101,Status\n" + "".join(
        f"{k + 1},11/22/2026 08:{k:02d}:00:000,{20 + k / 10:.1f},0,0\n" for k in range(8)
    )
    path = write_csv(text)
    log = read_temperature_log(path)
    assert log.sensors == ("101 (C)",) and "left out, the logger's own records: Alarm 101, Status" in log.notes
    rows = LogFollower(path).poll()
    assert rows.temperature_C.shape == (8, 1) and any("Alarm 101, Status" in n for n in rows.notes)
    assert read_temperature_log(path, sensors=["Alarm 101"]).sensors == ("Alarm 101",)


def test_a_live_log_is_read_from_its_first_rows_whatever_its_layout(write_csv):
    """The follower waited for 21 rows before it fixed the header of a log whose rows do not match
    it cell for cell (EasyLog's serial number in the first row alone) or begin with text (a
    receiver's name before the date): 21 minutes without an answer on a 1-min log."""
    from mtident.io.follow import LogFollower

    easylog = write_csv(
        "Spindle,Time,Celsius(°C),Serial Number\n1,22/11/2026 08:00:00,20.5,10543212\n2,22/11/2026 08:01:00,20.6\n",
        "easylog.csv",
    )
    rows = LogFollower(easylog).poll()
    np.testing.assert_array_equal(rows.temperature_C[:, 0], [20.5, 20.6])
    wireless = write_csv(
        'RECEIVER,TRANSMITTER,DATE,TEMPERATURE,HUMIDITY\n"Shop","Spindle","2026-11-22 08:00",20.5,55\n', "meaco.csv"
    )
    follower = LogFollower(wireless)
    assert follower.poll().temperature_C.tolist() == [[20.5]] and follower.sensors == ["TEMPERATURE"]


def test_a_degree_marked_unit_after_a_space_converts(write_csv):
    """'T1 °F' and 'T2_degF' (no brackets) were read as °C: a Fahrenheit log 1.8 times too warm, silently."""
    from mtident.io.follow import LogFollower

    path = write_csv(
        "time,T1 °F,T2_degF,T3 °C\n"
        + "".join(f"{k},{68 + 0.18 * k:.2f},{68 + 0.18 * k:.2f},{20 + k / 10:.1f}\n" for k in range(8))
    )
    log = read_temperature_log(path)
    np.testing.assert_allclose(log.temperature_C, np.repeat((20 + np.arange(8) / 10)[:, None], 3, axis=1), atol=1e-9)
    assert "sensor 'T1 °F': read in °F (its name), converted to °C" in log.notes
    np.testing.assert_allclose(LogFollower(path).poll().temperature_C, log.temperature_C, atol=1e-9)


def test_a_live_log_whose_lines_end_in_a_lone_cr(tmp_path):
    """The follower found no complete line in a log whose lines end in a lone CR (old Macs, some
    serial loggers): it waited for ever, where the file reader reads it."""
    from mtident.io.follow import LogFollower

    path = tmp_path / "cr.csv"
    data = ("time,A\r" + "".join(f"{k},{20 + k / 10:.1f}\r" for k in range(8))).encode()
    path.write_bytes(b"")
    follower = LogFollower(path)
    values = []
    for a, b in ((0, 9), (9, 20), (20, len(data))):
        with open(path, "ab") as out:
            out.write(data[a:b])
        values.extend(follower.poll().temperature_C.ravel())
    np.testing.assert_allclose(values, 20 + np.arange(8) / 10)


def test_a_loggers_placeholder_is_a_missing_reading_said_by_the_file_reader_and_the_follower(write_csv, tmp_path):
    """'---' in a cell (a common logger placeholder) stopped the run ("'---' is not a number"),
    and watch skipped empty and open-circuit readings without the note identify gives."""
    from mtident.io.follow import LogFollower

    rows = "".join(
        f"{k};{'---' if k == 5 else 'n/a' if k == 8 else f'{20 + k / 10:.2f}'.replace('.', ',')}\n" for k in range(30)
    )
    path = write_csv("time_min;A\n" + rows)
    log = read_temperature_log(path)
    assert log.notes == ("sensor 'A': skipped 2 empty/NaN sample(s) (rows 7, 10)",)
    assert np.isnan(log.temperature_C[[5, 8], 0]).all()
    said = LogFollower(Path(path)).poll().warnings
    assert "sensor 'A': skipped 2 empty, unreadable or open-circuit reading(s) (the first at t = 5 min)" in said


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
            follower = LogFollower.resume(path, through_state_file(follower.position()), None, None)
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
    # said once for the rows of a poll, not once a row (a duplicated block gave 21 lines)
    assert [w for w in rows.warnings if "go back" in w] == [
        f"{path}: refused 2 rows that repeat or go back (the first at t = 1 min after t = 1 min, the last at t = 0.5 min after t = 1 min)"
    ]


def test_follower_refuses_a_clock_that_restarted(tmp_path):
    """A logger restarted its clock at row 200: 200 rows were refused one warning each, and its row
    at its own 200 min (the 400th minute) was then taken as the first run's t = 200."""
    path = tmp_path / "log.csv"
    rows = [f"{t},{20 + t / 100:.2f}" for t in range(200)] + [f"{t},{22 + t / 100:.2f}" for t in range(201)]
    path.write_text("time_min,A\n" + "\n".join(rows) + "\n")
    with pytest.raises(InputError, match=r"the time went back from t = 199 min to 0 min \(a logger restarted"):
        LogFollower(path).poll()


def test_follower_refuses_a_header_that_changes_the_columns_and_passes_over_the_same_one(tmp_path):
    """A logger reconfigured mid-test wrote a new header with a column added before the room's: the
    follower read on by the first header's places, fed the room from the new column, and the test
    stopped without a word."""
    path = tmp_path / "log.csv"
    head = "time_min,A,room\n" + "".join(f"{t},{20 + t / 100:.2f},18.00\n" for t in range(60))
    path.write_text(head + "time_min,A,room\n60,20.60,18.00\n")
    rows = LogFollower(path).poll()
    np.testing.assert_allclose(rows.time_min, np.arange(61.0))
    path.write_text(head + "time_min,A,B,room\n60,20.60,25.00,18.00\n")
    with pytest.raises(
        InputError, match=r"a new header \(time_min, A, B, room\) where the log's is \(time_min, A, room\)"
    ):
        LogFollower(path).poll()


def test_follower_refuses_rows_wider_than_the_header(tmp_path):
    """Decimal commas in a comma-separated log: the file reader refused it, the follower read each
    row to the header's width and fed the second sensor the first one's decimals."""
    path = tmp_path / "log.csv"
    wide = "".join(f"{t},20,{t % 10},21,{t % 7}\n" for t in range(60, 70))
    path.write_text("time_min,A,B\n" + "".join(f"{t},20.{t % 10},21.{t % 7}\n" for t in range(60)) + wide)
    rows = LogFollower(path).poll()
    np.testing.assert_allclose(rows.time_min, np.arange(60.0))
    assert any(
        "refused 10 row(s) with more cells than the header's 3 (the first has 5) (decimal commas" in w
        for w in rows.warnings
    )


def test_follower_and_watch_refuse_two_columns_of_one_name(tmp_path):
    """Both columns were read from the first one: the second sensor showed the first one's curve."""
    path = tmp_path / "log.csv"
    path.write_text("time_min,T1,T1\n0,20,21\n1,20.1,21.2\n")
    with pytest.raises(InputError, match=r"log.csv: the column name 'T1' appears twice \(columns 2 and 3\)"):
        LogFollower(path).poll()
    code, _, err = mtident("thermal", "watch", str(path), "--replay")
    assert code == 2 and "Traceback" not in err
    assert "the column name 'T1' appears twice" in err


def test_follower_and_watch_refuse_a_log_without_a_header(tmp_path):
    """A logger's export without its header line: watch named the sensors "20.003" and "20.020"
    after the first readings, lost those, and said "20.003: may stop"."""
    path = tmp_path / "log.csv"
    path.write_text("".join(f"{t},{20 + t / 100:.3f},{20.02 + t / 90:.3f}\n" for t in range(30)))
    with pytest.raises(InputError, match=r"the header \(0, 20.000, 20.020\) holds readings, not column names"):
        LogFollower(path).poll()
    code, _, err = mtident("thermal", "watch", str(path), "--replay")
    assert code == 2 and "Traceback" not in err and "add one, or export the log with its header" in err


def test_follower_refuses_a_time_with_thousands_grouped_under_decimal_commas(tmp_path):
    """'960' then '1.020' (s): read as 1.02 s, the time went back, and a live log's rows after
    960 s would have been skipped as out of order, the grouping unsaid."""
    path = tmp_path / "log.csv"
    path.write_text("Zeit [s];T1\n900;20,0\n960;20,2\n1.020;20,4\n1.080;20,5\n")
    with pytest.raises(InputError, match=r"holds '1.020' in a log written with decimal commas: the point groups"):
        LogFollower(path).poll()


def test_follower_handles_a_replaced_log_without_double_counting(tmp_path):
    path = tmp_path / "log.csv"
    stamps = [f"2026-11-22T08:{m:02d}:00" for m in range(10)]
    path.write_text("stamp,A\n" + "".join(f"{s},{20 + i / 10}\n" for i, s in enumerate(stamps[:5])))
    follower = LogFollower(path)
    assert follower.poll().time_min.size == 5
    replacement = tmp_path / "new.csv"  # the logger restarts and rewrites the whole file, its readings anew
    replacement.write_text("stamp,A\n" + "".join(f"{s},{21 + i / 10}\n" for i, s in enumerate(stamps[:8])))
    os.replace(replacement, path)
    rows = follower.poll()
    np.testing.assert_allclose(rows.time_min, [5, 6, 7])
    assert any("truncated or replaced" in w for w in rows.warnings)


def test_follower_takes_its_log_written_anew_as_the_same_log(tmp_path):
    """A logger that writes a longer copy and renames it over the log (a new inode at every write),
    or a workbook's sheet copied again for a resumed replay: the same bytes before where the follower
    had read, so it reads on from there without a word (a resumed replay of an Excel workbook said "the
    log was truncated or replaced", and the report carried it)."""
    path = tmp_path / "log.csv"
    text = "time_min,A\n" + "".join(f"{m},{20 + m / 10:.2f}\n" for m in range(12))
    path.write_text(text[: text.index("5,")])
    follower = LogFollower(path)
    assert follower.poll().time_min.size == 5
    copy = tmp_path / "copy.csv"
    copy.write_text(text)
    os.replace(copy, path)
    rows = follower.poll()
    np.testing.assert_allclose(rows.time_min, np.arange(5.0, 12.0))
    assert not rows.warnings


def test_follower_never_writes_to_the_log(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text(csv_text(T[:50], {"A": first_order(T[:50])}))
    before = (hashlib.sha256(path.read_bytes()).hexdigest(), path.stat().st_mtime_ns)
    follower = LogFollower(path)
    follower.poll()
    follower.poll()
    assert (hashlib.sha256(path.read_bytes()).hexdigest(), path.stat().st_mtime_ns) == before


def test_follower_reads_a_log_without_units_in_the_unit_stated_room_too(tmp_path):
    """Issue 37: the live follower read a °F log that states no unit as °C, as the file reader did;
    ``temperature_unit`` converts every column, the room's too, and a resumed follower goes on so."""
    path = tmp_path / "log.csv"
    path.write_text("time_min,A,room\n0,68,68\n1,212,69.8\n")
    follower = LogFollower(path, room="room", temperature_unit="F")
    rows = follower.poll()
    np.testing.assert_allclose(rows.temperature_C, [[20.0, 20.0], [100.0, 21.0]])
    assert "read in °F (`temperature_unit`), converted to °C: A" in rows.notes
    with path.open("a") as out:
        out.write("2,203,71.6\n")
    resumed = LogFollower.resume(path, through_state_file(follower.position()), None, None, "F")
    np.testing.assert_allclose(resumed.poll().temperature_C, [[95.0, 22.0]])
    kelvin = tmp_path / "kelvin.csv"
    kelvin.write_text("time_min,A\n0,293.15\n1,373.15\n")
    np.testing.assert_allclose(LogFollower(kelvin, temperature_unit="K").poll().temperature_C, [[20.0], [100.0]])
    assert not any("workshop" in text for text in (*rows.notes, *rows.warnings))
    as_celsius = LogFollower(path).poll()
    np.testing.assert_allclose(as_celsius.temperature_C[:2], [[68.0, 68.0], [212.0, 69.8]])
    # said once, at the first rows, as the file reader says it
    assert sum("'room' reads 68 to 71.6 as the room: far outside" in text for text in as_celsius.warnings) == 1


def test_follower_says_a_log_in_celsius_read_in_a_stated_fahrenheit_reads_outside_any_workshop(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text("time_min,A,room\n0,20,20\n1,30,20.1\n")
    follower = LogFollower(path, room="room", temperature_unit="F")
    said = [warning for warning in follower.poll().warnings if "far outside any workshop's range" in warning]
    assert len(said) == 1 and "If the log is in °C already, leave the unit out" in said[0]
    with path.open("a") as out:
        out.write("2,35,20.2\n")
    assert not any("workshop" in warning for warning in follower.poll().warnings)
    # a first row without a room reading is not judged: the next rows are
    late = tmp_path / "late.csv"
    late.write_text("time_min,A,room\n0,20,\n")
    follower = LogFollower(late, room="room", temperature_unit="F")
    assert not any("workshop" in warning for warning in follower.poll().warnings)
    with late.open("a") as out:
        out.write("".join(f"{m},{20 + m},20\n" for m in range(1, 30)))
    assert sum("far outside any workshop's range" in warning for warning in follower.poll().warnings) == 1


@pytest.mark.parametrize("sensors", [None, ["A", "room [°C]"]])
def test_follower_refuses_a_column_whose_own_unit_the_stated_one_contradicts(tmp_path, sensors):
    path = tmp_path / "log.csv"
    path.write_text("time_min,A,room [°C]\n0,68,20\n1,212,21\n")
    with pytest.raises(InputError, match=r"sensor 'room \[°C\]' is in °C by its name, but `temperature_unit='F'`"):
        LogFollower(path, sensors, room="room [°C]", temperature_unit="F").poll()
    code, _, err = mtident("thermal", "watch", str(path), "--replay", "--unit", "F", "--state", str(tmp_path / "s.npz"))
    assert code == 2 and "Traceback" not in err
    assert "sensor 'room [°C]' is in °C by its name, but --unit F says the temperatures are in °F" in err


def test_a_row_cut_short_inside_the_log_is_left_out_and_said_by_the_file_reader_and_the_follower(tmp_path):
    """'150,27.829,2' between rows of five cells (a write cut short, T2's reading cut from 25.0..)
    was read as T2 = 2 °C and trusted, its missing cells said only as skipped readings. Both
    readers leave the row out and say why; a logger that leaves out its last (empty) column on
    every row keeps its rows."""
    from mtident.io import read_temperature_log
    from mtident.io.follow import LogFollower

    rows = [f"{t:g},{20 + 0.01 * t:.3f},{25 + 0.01 * t:.3f},{29 + 0.01 * t:.3f},20.0" for t in range(40)]
    rows[20] = "20,20.200,2"
    path = tmp_path / "cut.csv"
    path.write_text("time_min,T1,T2,T3,room\n" + "\n".join(rows) + "\n")
    log = read_temperature_log(path)
    assert 20.0 not in log.time_min and np.nanmin(log.temperature_C[:, 1]) > 24.9
    assert [n for n in log.notes if n.startswith("left out line 22, '20,20.200,2': it has 3 cells")]
    polled = LogFollower(path).poll()
    assert 20.0 not in polled.time_min and np.nanmin(polled.temperature_C[:, 1]) > 24.9
    assert [w for w in polled.warnings if "refused the row '20,20.200,2': it has 3 cells" in w]
    evented = tmp_path / "event.csv"
    evented.write_text("time_min,T1,event\n" + "\n".join(f"{t:g},{20 + 0.01 * t:.3f}" for t in range(40)) + "\n")
    assert len(read_temperature_log(evented).time_min) == 40 and len(LogFollower(evented).poll().time_min) == 40


def test_a_header_repeated_inside_the_log_is_left_out_and_said():
    """Two logs joined into one file: the header again on line 22 made the file reader take the
    time column for time stamps and fail at row 2 ("'0' is neither a number nor a time stamp"),
    naming neither the line nor the cause. It is left out and said; the follower refuses it."""
    import tempfile

    from mtident.io import read_temperature_log
    from mtident.io.follow import LogFollower

    rows = [f"{t:g},{20 + 0.01 * t:.3f},{25 + 0.01 * t:.3f}" for t in range(40)]
    rows.insert(20, "time_min,T1,T2")
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "joined.csv"
        path.write_text("time_min,T1,T2\n" + "\n".join(rows) + "\n")
        log = read_temperature_log(path)
        assert (
            len(log.time_min) == 40
            and "left out line(s) 22: the header again (logs joined into one file?)" in log.notes
        )
        assert len(LogFollower(path).poll().time_min) == 40


def test_follower_says_a_twelve_hour_clock_without_am_or_pm():
    """12:59:00 then 01:00:00: the time went back 12 hours, which the follower took for a logger
    whose clock restarted; it is a 12-hour clock written without AM or PM."""
    import tempfile
    from pathlib import Path

    stamps = [f"{12 + (m // 60) % 12 if m < 60 else (m // 60) % 12:02d}:{m % 60:02d}:00" for m in range(120)]
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "clock.csv"
        path.write_text("Time,A\n" + "".join(f"{s},{20 + k / 100:.2f}\n" for k, s in enumerate(stamps)))
        with pytest.raises(InputError, match=r"went back .* \(a 12-hour clock written without AM or PM\?\)"):
            LogFollower(path).poll()
