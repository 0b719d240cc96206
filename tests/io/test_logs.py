"""Tests of :mod:`mtident.io.logs`: the entry point (files, DataFrames, shipped logs), the selection
of sensors, a log built by hand, and what the reader says of readings no workshop has.
"""

from __future__ import annotations

import numpy as np
import pytest
from fuzz_logs_helpers import exports
from helpers import sample_log

from mtident.exceptions import InputError
from mtident.io import read_temperature_log, sample_log_path
from mtident.io.logs import TemperatureLog


def test_the_exports_cover_what_users_produce():
    """The generator writes every kind the issue names, more than once."""
    kinds = [k for export in exports() for k in export.kind]
    text = " | ".join(kinds)
    for kind in (
        "comma, decimal '.'",
        "semicolon, decimal ','",
        "tab, decimal ','",
        "decimal commas in a comma-separated file",
        "units row",
        "time in s",
        "time in h",
        "time in min",
        "stamps %H:%M:%S",
        "stamps ('%d.%m.%Y', '%H:%M:%S')",
        "utf-8-sig",
        "cp1252",
        "utf-16",
        "°F",
        "temperature unit by none",
        "a half-written last line",
        "cut inside a UTF-16 character",
        "written twice",
        "blank lines",
        "no line end after the last row",
        "quoted header",
        "room column",
    ):
        assert text.count(kind) >= 2, kind
    assert sum(e.doubt is not None for e in exports()) >= 5 and sum(e.refuse for e in exports()) >= 5


@pytest.mark.parametrize(
    ("text", "kwargs", "message"),
    [
        ("time_min,A\n0,20\n1,abc\n2,21\n3,21\n4,21\n", {}, r"sensor 'A', row 3: 'abc' is not a number"),
        (
            "time_min,A\n0,20\n1,20\n1,21\n3,21\n4,21\n",
            {},
            r"row 4: duplicate time 1, the time of row 3 too, with other readings; each reading needs its own time",
        ),
        ("time_min,A\n0,20\n2,20\n1,21\n3,21\n4,21\n", {}, r"row 4: time goes back"),
        ("time_min,A\n0,20\n1,20\n", {}, r"2 samples; at least 5 are needed"),
        ("time_min\n0\n1\n2\n3\n4\n", {}, r"need a time column and at least one sensor column"),
        (
            "time_min,A\n0,20\n1,20\n2,21\n3,21\n4,21\n",
            {"time_col": "clock"},
            r"no time column 'clock'; the columns are: time_min, A",
        ),
        (
            "time_min,A\n0,20\n1,20\n2,21\n3,21\n4,21\n",
            {"time_unit": "days"},
            r"time unit 'days' is not one of: ms, s, min, h, d",
        ),
        (
            "time_min,A\nyesterday,20\n1,20\n2,21\n3,21\n4,21\n",
            {},
            r"row 2: 'yesterday' is neither a number nor a time stamp \(ISO 8601, 22.11.2026 08:00:00, 11/22/2026 "
            r"08:00:00 AM or 08:00:00\)",
        ),
        (
            "stamp,A\n22.11.2026 08:00,20\n22.11.2026 08:01,20\n01/02/2026 08:02,21\n22.11.2026 08:03,21\n22.11.2026 "
            "08:04,21\n",
            {},
            r"row 4: '01/02/2026 08:02' is neither a number nor a time stamp like the first one",
        ),
        (
            "stamp,A\nFeb 1 2026 08:00,20\nFeb 1 2026 08:01,20\nFeb 1 2026 08:02,21\nFeb 1 2026 08:03,21\nFeb 1 2026 "
            "08:04,21\n",
            {},
            r"row 2: .* \(ISO 8601",
        ),
        ("time_min,A\n0,20\n1,\n2,\n3,500\n4,21\n", {}, r"sensor 'A': 3 of 5 samples are empty, NaN or open-circuit"),
        (
            "time_min,A,B,A\n0,20,20,20\n1,20,20,20\n2,21,21,21\n3,21,21,21\n4,21,21,21\n",
            {},
            r"the column name 'A' appears twice \(columns 2 and 4\); give each column its own name",
        ),
        (
            "time_min;A; A\n0;20;20\n1;20;20\n2;21;21\n3;21;21\n4;21;21\n",
            {},
            r"the column name 'A' appears twice \(columns 2 and 3\)",
        ),
        # a log exported without its header: its first readings were sensors named "20.003", its first row lost
        (
            "0,20.003,20.020\n1,20.1,20.2\n2,20.2,20.3\n3,20.3,20.4\n4,20.3,20.4\n",
            {},
            r"the header \(0, 20.003, 20.020\) holds readings, not column names: a log needs a header naming its "
            r"columns above the readings \(time_min,T1,T2,...\)",
        ),
        # thousands grouped with points under decimal commas: 1000-13000 s read as a log of 0.2 min
        (
            "Zeit [s];T1\n1.000;20,0\n1.060;20,2\n1.120;20,4\n1.180;20,5\n1.240;20,6\n",
            {},
            r"time column 'Zeit \[s\]' holds '1.000' in a log written with decimal commas: the point groups "
            r"thousands there \(1.000 = 1000\)",
        ),
        (
            "Zeit [s];T1\n900;20,0\n960;20,2\n1.020;20,4\n1.080;20,5\n1.140;20,6\n",
            {},
            r"holds '1.020' in a log written with decimal commas",
        ),
        # thousands grouped with commas (an English spreadsheet's export): the whole column was refused as
        # "row 2: '0' is neither a number nor a time stamp"; under semicolons and decimal commas, as "time goes back"
        (
            'time_s,T1\n"900",20.0\n"960",20.2\n"1,020",20.4\n"1,080",20.5\n"1,140",20.6\n',
            {},
            r"time column 'time_s' holds '1,020' in a log written with decimal points: the comma groups thousands "
            r"there \(1,020 = 1020\)",
        ),
        (
            "time_s;T1\n900;20,0\n960;20,2\n1,020;20,4\n1,080;20,5\n1,140;20,6\n",
            {},
            r"holds '1,020' in a log written with decimal commas, yet it follows '960': the comma groups thousands",
        ),
        (
            "22.11.2026 08:00:00;20,003;20,020\n22.11.2026 08:01:00;20,1;20,2\n22.11.2026 08:02:00;20,2;20,3\n",
            {},
            r"the header \(22.11.2026 08:00:00, 20,003, 20,020\) holds readings",
        ),
    ],
)
def test_bad_logs_are_refused_with_a_message_naming_the_problem(write_csv, text, kwargs, message):
    with pytest.raises(InputError, match=message):
        read_temperature_log(write_csv(text), **kwargs)


def test_missing_file_and_unknown_sensor(tmp_path, write_csv):
    with pytest.raises(InputError, match="no such file"):
        read_temperature_log(tmp_path / "nope.csv")
    log = read_temperature_log(write_csv("time_min,A\n0,20\n1,20\n2,21\n3,21\n4,21\n"))
    with pytest.raises(InputError, match="no sensor column 'B'; the log has: A"):
        log.select(["B"])
    assert log.select(["all"]) is log


def test_a_dead_sensor_that_is_not_asked_for_does_not_stop_the_others(write_csv):
    """The error for a dead sensor says "leave this sensor out with --sensor"; that used to fail
    the same way, because every column was checked before the selection."""
    path = write_csv(
        "time_min,dead,B,A\n" + "".join(f"{k},{'20' if k == 0 else ''},{30 + k},{20 + k}\n" for k in range(6))
    )
    with pytest.raises(InputError, match="sensor 'dead': 5 of 6 samples are empty"):
        read_temperature_log(path)
    # one that never gave a reading is left out of the default selection, with a note
    never = read_temperature_log(
        write_csv("time_min,dead,B,A\n" + "".join(f"{k},,{30 + k},{20 + k}\n" for k in range(6)))
    )
    assert never.sensors == ("B", "A") and "left out, no readings in them: dead" in never.notes
    log = read_temperature_log(path, sensors=["A", "B"])
    assert log.sensors == ("A", "B") and log.temperature_C[2].tolist() == [22.0, 32.0]
    with pytest.raises(InputError, match="no sensor column 'C'; the log has: dead, B, A"):
        read_temperature_log(path, sensors=["A", "C"])


def test_a_notebook_dataframe_is_read_and_checked_like_a_file():
    """A DataFrame already in memory, with a time column or a time index (numbers, stamps or
    elapsed time); its errors count rows from 0, as the DataFrame does."""
    import pandas as pd

    t = np.arange(0.0, 6.0)
    frame = pd.DataFrame({"time_min": t, "A": 20 + t, "B": 30 + t})
    plain = read_temperature_log(frame, sensors=["B"])
    assert (
        plain.sensors == ("B",)
        and plain.source == "DataFrame"
        and plain.temperature_C[:, 0].tolist() == (30 + t).tolist()
    )
    by_index = [
        frame.set_index("time_min"),
        frame.drop(columns="time_min").set_index(
            pd.date_range("2026-11-22 08:00", periods=6, freq="1min", name="stamp")
        ),
        frame.drop(columns="time_min").set_index(pd.to_timedelta(t, unit="min").rename("elapsed")),
    ]
    for indexed in by_index:
        log = read_temperature_log(indexed)
        assert log.sensors == ("A", "B")
        np.testing.assert_allclose(log.time_min, t)
    bad = frame.astype({"A": object})
    bad.loc[3, "A"] = "x"
    with pytest.raises(InputError, match=r"DataFrame: sensor 'A', row 3: 'x' is not a number"):
        read_temperature_log(bad)
    back = frame.copy()
    back.loc[4, "time_min"] = 1.0
    # the cell as written (1), not np.float64(1.0); the same in a file's messages
    with pytest.raises(InputError, match=r"DataFrame: time column 'time_min', row 4: time goes back \(3 then 1\)"):
        read_temperature_log(back)


def test_a_room_column_splits_off_as_the_room_and_a_log_of_the_room_alone_is_refused():
    """The Python guide's way to pass a room sensor (a new user left it among the sensors, and
    every sensor of the reference learnt from that log was doubtful)."""
    log = read_temperature_log("@sample-room", sensors=["T1", "room", "T2"])
    sensors, room = log.split_room("room")
    assert sensors.sensors == ("T1", "T2")
    np.testing.assert_array_equal(room, log.temperature_C[:, 1])
    np.testing.assert_array_equal(sensors.temperature_C, log.temperature_C[:, [0, 2]])
    with pytest.raises(InputError, match="no sensor column 'Raum'"):
        log.split_room("Raum")
    with pytest.raises(InputError, match="no sensor column left besides the room column 'room'"):
        log.select(["room"]).split_room("room")


def test_the_shipped_logs_by_name():

    assert read_temperature_log("@sample").sensors == read_temperature_log(sample_log_path()).sensors
    assert "room" in read_temperature_log("@sample-room").sensors
    with pytest.raises(InputError, match="no shipped log '@smaple'; there are: @sample, @sample-room"):
        sample_log_path("@smaple")


def test_a_log_built_by_hand_is_checked_like_one_read_from_a_file():
    """A notebook user's TemperatureLog(...) skipped every check: times that went back gave T∞
    24.17 °C for 26.62 with no word, and a transposed array, a 1-D one, plain lists or a NaN time
    failed deep inside with IndexError, TypeError or ValueError."""

    t = np.arange(0.0, 100.0)
    y = 20.0 + 6.0 * (1.0 - np.exp(-t / 40.0))
    log = TemperatureLog(list(t), ["T1"], [[v] for v in y])
    assert isinstance(log.time_min, np.ndarray) and log.temperature_C.shape == (100, 1) and log.sensors == ("T1",)
    back = t.copy()
    back[50] = 40.0
    with pytest.raises(InputError, match=r"time_min must increase strictly; t\[50\] = 40 min follows t\[49\] = 49 min"):
        TemperatureLog(back, ("T1",), y[:, None])
    with pytest.raises(InputError, match=r"shape \(N, S\) = \(100, 1\) .* not \(1, 100\) \(transposed\?\)"):
        TemperatureLog(t, ("T1",), y[None, :])
    with pytest.raises(InputError, match=r"not \(100,\)"):
        TemperatureLog(t, ("T1",), y)
    nan_time = t.copy()
    nan_time[3] = np.nan
    with pytest.raises(InputError, match="non-finite time at row 3"):
        TemperatureLog(nan_time, ("T1",), y[:, None])
    with pytest.raises(InputError, match=r"not one string \(for one: \('T1',\)\)"):
        TemperatureLog(t, "T1", y[:, None])  # type: ignore[arg-type]
    with pytest.raises(InputError, match="must be numbers"):
        TemperatureLog(t, ("T1",), [["hot"]] * 100)


def test_a_room_far_outside_a_workshops_range_read_as_celsius_is_said(write_csv):
    """A log in °F without a unit row: a room at 69 "°C" and a machine at 70-92 were taken as °C
    without a word (with a °F units row they convert, rightly)."""
    rows = "".join(f"{m},{70 + 22 * (1 - np.exp(-m / 40)):.2f},{69 + m / 100:.2f}\n" for m in range(0, 60, 2))
    log = read_temperature_log(write_csv("time_min,spindle,room\n" + rows))
    said = [note for note in log.notes if "far outside any workshop's range" in note]
    assert said and "'room' reads 69 to 69.58" in said[0] and "°F" in said[0] and "units row" in said[0], log.notes
    converted = read_temperature_log(write_csv("time_min,spindle,room\nmin,°F,°F\n" + rows, "stated.csv"))
    assert not any("workshop" in note for note in converted.notes)
    # a log in °C converted from a stated °F: the converted range is said to four digits, not to six
    celsius = "".join(f"{m},{20 + 5 * (1 - np.exp(-m / 40)):.2f},{20 + m / 100:.2f}\n" for m in range(0, 60, 2))
    misread = read_temperature_log(write_csv("time_min,spindle,room\n" + celsius, "c.csv"), temperature_unit="F")
    said = [note for note in misread.notes if "far outside any workshop's range" in note]
    assert said and "'room' reads -6.667 to -6.344 as the room" in said[0], misread.notes


def test_every_column_far_above_a_workshops_range_read_as_celsius_is_said(write_csv):
    rows = "".join(
        f"{m},{70 + 22 * (1 - np.exp(-m / 40)):.2f},{69 + 9 * (1 - np.exp(-m / 60)):.2f}\n" for m in range(0, 60, 2)
    )
    log = read_temperature_log(write_csv("time_min,spindle,housing\n" + rows))
    assert any("every column reads above 40 °C" in note and "°F" in note for note in log.notes), log.notes
    warm = "".join(
        f"{m},{22 + 10 * (1 - np.exp(-m / 40)):.2f},{21 + 4 * (1 - np.exp(-m / 60)):.2f}\n" for m in range(0, 60, 2)
    )
    assert not any(
        "workshop" in note
        for note in read_temperature_log(write_csv("time_min,spindle,housing\n" + warm, "c.csv")).notes
    )


def test_sample_log_is_ten_sensors_four_hundred_minutes():
    log = sample_log()
    assert log.sensors == tuple(f"T{i}" for i in range(1, 11))
    np.testing.assert_allclose(log.time_min, np.arange(401.0))
    np.testing.assert_allclose(log.temperature_C[0], 17.9, atol=0.1)
    # 0.01 °C resolution
    np.testing.assert_allclose(log.temperature_C * 100, np.round(log.temperature_C * 100), atol=1e-6)


def test_inspect_describes_a_sensor_that_failed_and_says_who_refuses_it(write_csv):
    """identify, learn and report refuse a sensor with more than a tenth of its samples bad; inspect,
    which is how a user finds out, describes the log and says so."""
    from mtident.io.describe import describe_log

    path = write_csv("time_min,A,B\n" + "".join(f"{k},{20 + k},{-200 if k >= 3 else 21}\n" for k in range(8)))
    with pytest.raises(InputError, match="sensor 'B': 5 of 8 samples are empty, NaN or open-circuit"):
        read_temperature_log(path)
    info = describe_log(path)
    assert [(s.sensor, s.samples, s.missing) for s in info.sensors] == [("A", 8, 0), ("B", 3, 5)]
    assert any(
        note.startswith("sensor 'B': 5 of 8 samples are empty, NaN or open-circuit, more than 10%: identify, learn")
        for note in info.notes
    )
    assert not any("'A'" in note for note in info.notes)


def test_inspect_says_where_no_column_states_a_unit(write_csv):
    """A newcomer read 'units from the column names' above a table of '°C (assumed)'."""
    from mtident.io.describe import describe_log

    bare = write_csv("time_min,A,B\n" + "".join(f"{k},{20 + k},{21 + k}\n" for k in range(6)))
    assert describe_log(bare).format.units_from == "no units in the log (°C assumed)"
    assert describe_log(bare, temperature_unit="F").format.units_from == "no units in the log (°F, as stated)"
    named = write_csv("time_min,A [°C],B [°C]\n" + "".join(f"{k},{20 + k},{21 + k}\n" for k in range(6)))
    assert describe_log(named).format.units_from == "the column names"


def test_a_stray_row_in_a_numeric_time_column_is_named_where_it_is(tmp_path):
    """A summary row at the end, or a header written again with other columns at row 202, was
    reported as "row 2: '0' is neither a number nor a time stamp"."""
    body = "".join(f"{t},{20 + t / 100:.2f},{21 + t / 100:.2f}\n" for t in range(200))
    path = tmp_path / "summary.csv"
    path.write_text("time_min,A,B\n" + body + "Max,22.00,23.00\n")
    with pytest.raises(InputError, match=r"row 202: 'Max' is not a number, where the column's other cells are"):
        read_temperature_log(path)
    path.write_text("time_min,A,B\n" + body + "time_min,B,A\n200,23.00,22.00\n")
    with pytest.raises(InputError, match=r"row 202 is a header written again with other columns"):
        read_temperature_log(path)


def test_a_header_written_again_with_more_columns_is_named_as_one(tmp_path):
    """A logger reconfigured mid-test wrote a header with a column more: the reader said only that
    line 62 had more cells than the header, and that watch skips such a row, where watch refuses it."""
    body = "".join(f"{t},{20 + t / 100:.2f},{21 + t / 100:.2f}\n" for t in range(60))
    path = tmp_path / "added.csv"
    path.write_text("time_min,A,B\n" + body + "time_min,A,C,B\n60,20.60,25.00,21.60\n")
    with pytest.raises(InputError, match=r"line 62 is a header written again with more columns .* \(watch refuses"):
        read_temperature_log(path)


def test_a_time_column_named_as_such_is_the_time_though_another_column_comes_first(write_csv):
    """room,time_min,T1: the room's readings were taken for the time and the log refused as a
    "duplicate time 19.997", with no word of the time column. Both readers take the column named
    as the time, and say that the first is read as a sensor."""
    from mtident.io.follow import LogFollower

    text = "room,time_min,T1\n" + "".join(f"{20 + (k % 2) / 100:.2f},{k},{20 + k / 10:.1f}\n" for k in range(12))
    path = write_csv(text)
    log = read_temperature_log(path)
    np.testing.assert_allclose(log.time_min, np.arange(12.0))
    assert log.sensors == ("room", "T1") and log.temperature_C[3, 1] == pytest.approx(20.3)
    assert any("the time is 'time_min', the column named as the time; 'room' before it" in n for n in log.notes)
    rows = LogFollower(path).poll()
    np.testing.assert_allclose(rows.time_min, np.arange(12.0))
