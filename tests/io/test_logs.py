"""Tests of :mod:`mtident.io.logs`."""

from __future__ import annotations

import datetime as dt
import json
import re
from pathlib import Path

import numpy as np
import pytest
from conftest import logger_dialects, through_state_file
from fuzz_logs_helpers import _run, exports
from helpers import UNITS_LOG, _local_clock_log, sample_log
from hypothesis import example, given, settings
from hypothesis import strategies as st

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


def _rows(m_max: int = 20) -> str:
    return "".join(f"{m};{22 + m / 7:.2f};{21 + m / 9:.2f}\n".replace(".", ",") for m in range(m_max))


@pytest.mark.parametrize("cut", ["20;24,86;23,2", "20;24,86;2", "20;24,86;23,", "20;24,86;"])
def test_a_last_line_cut_inside_its_last_reading_is_left_out_and_said(write_csv, cut):
    """A log still being written, cut inside its last reading: every cell is there, so the line
    was read whole, ``2`` as 2.00 °C (and a K log then lost its note that it reads as no workshop
    does), ``23,2`` as 23.20 where 23.22 was being written, an empty cell as a sensor's missing
    reading."""
    log = read_temperature_log(write_csv("time_min;Spindle;Housing\n" + _rows() + cut))
    assert len(log.time_min) == 20 and not np.isnan(log.temperature_C).any()
    assert any(note.startswith(f"left out the last line, {cut!r}: it has no line end") for note in log.notes), log.notes
    out = _run("thermal", "inspect", str(write_csv("time_min;Spindle;Housing\n" + _rows() + cut, "i.csv")), "--json")
    info = json.loads(out.stdout)
    assert info["time"]["samples"] == 20 and info["sensors"][1]["last_C"] == pytest.approx(21 + 19 / 9, abs=0.006)


def test_a_whole_last_line_without_a_line_end_is_read(write_csv):
    log = read_temperature_log(write_csv("time_min;Spindle;Housing\n" + _rows() + "20;24,86;23,22"))
    assert len(log.time_min) == 21 and log.temperature_C[-1, 1] == pytest.approx(23.22)
    assert not any("last line" in note for note in log.notes)


@pytest.mark.parametrize("encoding", ["utf-16", "utf-16-le"])
def test_a_utf16_log_cut_inside_a_character_is_read_without_its_cut_line(tmp_path, encoding):
    """Excel's "Unicode text" of a log still being written, cut between the two bytes of a
    character: pandas refused the whole file ("truncated data")."""
    text = "Zeit (s)\tSpindel [°C]\tGehäuse [°C]\n" + _rows().replace(";", "\t") + "20\t24,8"
    path = tmp_path / "live.txt"
    path.write_bytes(text.encode(encoding) + b"6")
    log = read_temperature_log(path)
    assert len(log.time_min) == 20 and log.time_min[-1] == pytest.approx(19 / 60)
    assert log.sensors == ("Spindel [°C]", "Gehäuse [°C]")
    assert any(note.startswith("left out the last line, '20\\t24,8'") for note in log.notes), log.notes


def test_quoted_decimal_commas_in_a_comma_separated_file_are_read(write_csv):
    """A spreadsheet in a decimal-comma locale saving CSV with commas quotes its numbers: each
    reading was "not a number" and the log refused; unquoted, it is refused, with the reason."""
    rows = "".join(f'"{m / 2:.1f}","{22 + m / 7:.2f}","{21 + m / 9:.2f}"\n'.replace(".", ",") for m in range(20))
    log = read_temperature_log(write_csv("Time [min],Spindle,Housing\n" + rows))
    np.testing.assert_allclose(log.time_min, np.arange(20) / 2)
    np.testing.assert_allclose(log.temperature_C[:, 1], np.round(21 + np.arange(20) / 9, 2))
    with pytest.raises(InputError, match="likely decimal commas in a comma-separated file"):
        read_temperature_log(write_csv("Time [min],Spindle,Housing\n" + rows.replace('"', ""), "plain.csv"))


@pytest.mark.parametrize(
    ("header", "thousands"), [("time_s,Spindle\n", '"1,500","22,41"\n'), ("time_s,Spindle\n", '"1,500","1,234.5"\n')]
)
def test_quoted_thousands_are_no_decimal_commas(write_csv, header, thousands):
    rows = "".join(f'"{60 * m}","{22 + m / 10:.1f}"\n' for m in range(6))
    text = header + rows.replace('"22,41"', "") + thousands
    try:
        log = read_temperature_log(write_csv(text))
    except InputError:
        return  # refused: no reading misread
    assert log.time_min[-1] == pytest.approx(25.0)  # 1,500 s, not 1.5


def test_a_quoted_last_line_cut_inside_a_reading_is_left_out(write_csv):
    """A cut that leaves a quote open ("22,4): pandas refused the whole file (EOF inside string)."""
    rows = "".join(f'"{m / 2:.1f}","{22 + m / 7:.2f}","{21 + m / 9:.2f}"\n'.replace(".", ",") for m in range(20))
    log = read_temperature_log(write_csv("Time [min],Spindle,Housing\n" + rows + '"10,0","24,86","23'))
    assert len(log.time_min) == 20 and any(note.startswith("left out the last line") for note in log.notes)


def test_minutes_seconds_hours_and_timestamps(write_csv):
    log = read_temperature_log(write_csv("time_s,A,B\n0,20,21\n60,20.5,21.5\n120,21,22\n180,21.2,22\n240,21.4,22.1\n"))
    np.testing.assert_allclose(log.time_min, [0, 1, 2, 3, 4])
    assert log.sensors == ("A", "B")
    log = read_temperature_log(write_csv("t,A\n0,20\n0.5,20.5\n1,21\n1.5,21.2\n2,21.4\n"), time_unit="h")
    np.testing.assert_allclose(log.time_min, [0, 30, 60, 90, 120])
    stamps = "stamp,A\n" + "".join(f"2026-11-22T08:{m:02d}:00,{20 + m / 10}\n" for m in range(0, 10, 2))
    log = read_temperature_log(write_csv(stamps))
    np.testing.assert_allclose(log.time_min, [0, 2, 4, 6, 8])


def test_time_column_by_name(write_csv):
    log = read_temperature_log(
        write_csv("A,minute,B\n20,0,30\n21,1,31\n22,2,32\n23,3,33\n24,4,34\n"), time_col="minute"
    )
    assert log.sensors == ("A", "B")
    np.testing.assert_allclose(log.temperature_C[:, 1], [30, 31, 32, 33, 34])


def test_isolated_bad_samples_are_skipped_with_a_note(write_csv):
    rows = "".join(f"{k},{20 + k * 0.1 if k not in (3, 7) else ('' if k == 3 else 850.0)}\n" for k in range(30))
    log = read_temperature_log(write_csv("time_min,A\n" + rows))
    assert np.isnan(log.temperature_C[3, 0]) and np.isnan(log.temperature_C[7, 0])
    assert log.notes == ("sensor 'A': skipped 1 empty/NaN and 1 open-circuit sample(s) (rows 5, 9)",)


@pytest.mark.parametrize(
    ("text", "kwargs", "message"),
    [
        ("time_min,A\n0,20\n1,abc\n2,21\n3,21\n4,21\n", {}, r"sensor 'A', row 3: 'abc' is not a number"),
        ("time_min,A\n0,20\n1,20\n1,21\n3,21\n4,21\n", {}, r"row 4: duplicate time"),
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
    ],
)
def test_bad_logs_are_refused_with_a_message_naming_the_problem(write_csv, text, kwargs, message):
    with pytest.raises(InputError, match=message):
        read_temperature_log(write_csv(text), **kwargs)


@pytest.mark.parametrize("dialect", list(logger_dialects(np.arange(3.0), {"A": np.zeros(3)})))
def test_logs_as_loggers_write_them_read_like_the_plain_csv(tmp_path, dialect):
    """Semicolons with a decimal comma, tabs, a # preamble, a delimiter at the end of each line,
    cp1252 text, a byte-order mark, CRLF, dotted day-first stamps and times of day: each
    was refused before (or, for the trailing delimiter, read as a dead sensor "Unnamed: 3")."""
    t = np.arange(0.0, 40.0)
    columns = {"A": 26.7 - 8.8 * np.exp(-0.016 * t), "B": 25.0 - 7.0 * np.exp(-0.02 * t)}
    files = logger_dialects(t, columns)
    (tmp_path / "plain.csv").write_bytes(files["plain"])
    (tmp_path / "other.csv").write_bytes(files[dialect])
    plain, other = read_temperature_log(tmp_path / "plain.csv"), read_temperature_log(tmp_path / "other.csv")
    np.testing.assert_allclose(other.time_min, plain.time_min, atol=1e-9)
    np.testing.assert_array_equal(other.temperature_C, plain.temperature_C)
    assert [re.sub(r"\s*[(/ ,].*$", "", s) for s in other.sensors] == ["A", "B"]  # without a unit


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


def followed_in_pieces(live: Path, data: bytes, cuts: list[int]):  # noqa: ANN201 - (LogFollower, times)
    """A log written to ``live`` in pieces cut at ``cuts`` (bytes), the follower polling after each:
    the follower, and the times it read (no warning on the way)."""
    from mtident.io.follow import LogFollower

    live.write_bytes(b"")
    follower, times = LogFollower(live), []
    for a, b in zip([0, *sorted(set(cuts))], [*sorted(set(cuts)), len(data)], strict=True):
        with open(live, "ab") as out:
            out.write(data[a:b])
        polled = follower.poll()
        assert not polled.warnings
        times.extend(polled.time_min)
    return follower, times


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


def test_excel_sep_line_states_the_delimiter(write_csv):
    """Header names with commas in them: as many ',' as ';' in the header. Excel's "sep=;"
    decides, or else the data rows agree with both and the tie goes to ';'."""
    rows = "".join(f"{k};{20 + k / 10:.1f};{19 + k / 10:.1f}\n".replace(".", ",") for k in range(6))
    for directive in ("sep=;\n", ""):  # without it, the data rows settle the tie
        log = read_temperature_log(write_csv(directive + "Zeit;Temp, Spindel;Temp, Motor\n" + rows))
        assert log.sensors == ("Temp, Spindel", "Temp, Motor") and log.temperature_C[5].tolist() == [20.5, 19.5]
    # the same tie in a comma-separated header: its rows split into three cells only at ','
    log = read_temperature_log(
        write_csv("time,T1;front,T2;rear\n" + "".join(f"{k},{20 + k / 10:.1f},{19 + k / 10:.1f}\n" for k in range(6)))
    )
    assert log.sensors == ("T1;front", "T2;rear")


def test_row_numbers_in_messages_count_a_preamble(write_csv):
    log = read_temperature_log(
        write_csv(
            "# logger\n# setup\ntime_min;A\n" + "".join(f"{k};{'' if k == 3 else f'20,{k}'}\n" for k in range(30))
        )
    )
    assert log.notes == ("sensor 'A': skipped 1 empty/NaN sample(s) (rows 7)",)
    with pytest.raises(InputError, match="sensor 'A', row 5: 'x' is not a number"):
        read_temperature_log(write_csv("# logger\n# setup\ntime_min;A\n0;20\n1;x\n2;21\n3;21\n4;21\n"))


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


def test_binary_file_is_refused(write_csv, tmp_path):
    path = tmp_path / "bin.csv"
    path.write_bytes(b"\xff\xfe\x00\x01garbage")
    with pytest.raises(InputError, match="not a readable CSV file|need a time column"):
        read_temperature_log(path)


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


@settings(max_examples=60, deadline=None)
# found by the search: a decimal comma with the unit in the cell ("20,00 °C" was not a number), a live
# UTF-16 log's first byte (taken for a binary file), a CRLF cut between CR and LF (the first row was
# taken as complete, the date and clock columns were not told apart, every row refused)
@example(
    delimiter=";",
    decimal_comma=True,
    preamble=[],
    encoding="utf-8",
    crlf=False,
    trailing=False,
    quoted=False,
    stamps="minutes",
    units="none",
    under="nothing",
    units_in_cells=True,
    counter="none",
    cuts=[],
)
@example(
    delimiter=",",
    decimal_comma=False,
    preamble=[],
    encoding="utf-16-be",
    crlf=False,
    trailing=False,
    quoted=False,
    stamps="minutes",
    units="none",
    under="nothing",
    units_in_cells=False,
    counter="none",
    cuts=[1],
)
@example(
    delimiter=",",
    decimal_comma=False,
    preamble=[],
    encoding="utf-16",
    crlf=True,
    trailing=True,
    quoted=False,
    stamps="date, clock",
    units="min",
    under="nothing",
    units_in_cells=True,
    counter="none",
    cuts=[144],
)
@given(
    delimiter=st.sampled_from([",", ";", "\t"]),
    decimal_comma=st.booleans(),
    preamble=st.lists(
        st.sampled_from(
            [
                "# logger",
                "",
                "#channels: 4",
                "   ",
                "sep=DELIMITER",
                "Logger: GL240",
                "Interval: 60 s",
                "Start,22.11.2026",
            ]
        ),
        max_size=3,
    ),
    encoding=st.sampled_from(["utf-8", "cp1252", "utf-16", "utf-16-le", "utf-16-be"]),
    crlf=st.booleans(),
    trailing=st.booleans(),
    quoted=st.booleans(),
    stamps=st.sampled_from(
        [
            "minutes",
            "iso",
            "dotted",
            "dashed",
            "month name",
            "time of day",
            "date, clock",
            "iso date, clock",
            "ymd date, clock",
            "us slashed",
            "day-first slashed",
        ]
    ),
    units=st.sampled_from(["none", "min", "s"]),
    under=st.sampled_from(
        ["nothing", "a second row of names", "rows describing the channels", "an empty row and a section tag"]
    ),
    units_in_cells=st.booleans(),
    counter=st.sampled_from(["none", "NO.", "", "Reading #"]),
    cuts=st.lists(st.integers(1, 2000), max_size=6),
)
def test_any_logger_dialect_reads_alike_whole_and_live(
    tmp_path_factory,
    delimiter,
    decimal_comma,
    preamble,
    encoding,
    crlf,
    trailing,
    quoted,
    stamps,
    units,
    under,
    units_in_cells,
    counter,
    cuts,
):
    """Every combination of delimiter, decimal mark, preamble (also a logger's settings without
    '#'), encoding (also UTF-16 with and without a byte-order mark), line end, trailing
    delimiter, quoted cells (as spreadsheets write them), time format (also a date and a time of day in two columns), a units row
    and other rows under the header (a second row of names, rows describing the channels, an empty row and
    a section tag), readings with their unit in the cell, a row counter before time stamps (named,
    unnamed or under any name), read whole and followed live in random pieces, gives the plain
    file's times and temperatures (a channel the description rows call a dew point left out)."""

    decimal_comma = decimal_comma and delimiter != ","
    t = np.arange(0.0, 25.0) * 1.5
    temperatures = np.column_stack([20.0 + 0.37 * t, 19.5 + 0.21 * t, 8.0 + 0.01 * t])
    start = dt.datetime(2026, 11, 22, 23, 50, 0)  # time-of-day stamps pass midnight

    def time_cells(minutes: float) -> list[str]:
        when = start + dt.timedelta(minutes=float(minutes))
        if stamps == "us slashed":
            return [when.strftime("%m/%d/%Y %I:%M:%S %p")]
        if stamps == "day-first slashed":  # 01/11 then 02/11 at midnight: read month first, a month's jump
            return [(when - dt.timedelta(days=21)).strftime("%d/%m/%Y %H:%M:%S")]
        if stamps == "minutes" and units == "s":
            return [f"{60 * minutes:g}"]
        if stamps.endswith("date, clock"):  # a stamp in two columns
            return [
                when.strftime({"iso": "%Y-%m-%d", "ymd": "%Y/%m/%d"}.get(stamps.split()[0], "%d.%m.%Y")),
                when.strftime("%H:%M:%S"),
            ]
        return [
            {
                "minutes": f"{minutes:g}",
                "iso": when.isoformat(),
                "dotted": when.strftime("%d.%m.%Y %H:%M:%S"),
                "dashed": when.strftime("%d-%m-%Y %H:%M:%S"),
                "month name": when.strftime("%d-%b-%Y %H:%M:%S"),
                "time of day": when.strftime("%H:%M:%S"),
            }[stamps]
        ]

    def number(value: float) -> str:
        text = f"{value:.2f}".replace(".", ",") if decimal_comma else f"{value:.2f}"
        return f"{text} °C" if units_in_cells else text

    end = "\r\n" if crlf else "\n"
    tail = delimiter if trailing else ""
    # a counter before numbers in minutes would be the time: only before time stamps
    counted = counter != "none" and stamps != "minutes"

    def row(cells: list[str], lead: str = "") -> str:
        return delimiter.join(f'"{c}"' if quoted else c for c in ([lead] if counted else []) + cells) + tail

    clock = ["clock"] if stamps.endswith("date, clock") else []
    no_time = ["", *["" for _ in clock]]
    described = {
        "nothing": [],
        "a second row of names": [row(["Date/Time", *clock, "ch1", "ch2", "ch3"])],  # T&D
        "rows describing the channels": [
            row([*no_time, "227659", "227659", "227659"]),
            row([*no_time, "Temperature", "Temperature", "Dew Point"]),
        ],  # Tinytag
        "an empty row and a section tag": [
            row([*no_time, "", "", ""]),
            "[#D]" + delimiter * (len(no_time) + 2 + counted),
        ],  # Rotronic
    }[under]
    lines = [
        *(line.replace("DELIMITER", delimiter) for line in preamble),
        row(["time", *clock, "A °C", "B", "C"], counter),
    ]
    units_row = (
        [row([units if stamps == "minutes" else "", *["" for _ in clock], "°C", "[°C]", "°C"])]
        if units != "none"
        else []
    )  # the time's unit only where the time is a number
    # rows that describe the channels come straight under the header; empty rows and tags after them
    lines += [*units_row, *described] if under == "an empty row and a section tag" else [*described, *units_row]
    lines += [
        row([*time_cells(m), *(number(v) for v in values)], str(k + 1))
        for k, (m, values) in enumerate(zip(t, temperatures, strict=True))
    ]
    data = (end.join(lines) + end).encode(encoding)
    folder = tmp_path_factory.mktemp("dialect")
    whole = folder / "whole.csv"
    whole.write_bytes(data)
    log = read_temperature_log(whole)
    dew_point = under == "rows describing the channels"
    assert log.sensors == (("A °C", "B") if dew_point else ("A °C", "B", "C"))
    np.testing.assert_allclose(log.time_min, t, atol=1e-9)
    np.testing.assert_array_equal(
        log.temperature_C, [[float(f"{v:.2f}") for v in row[: len(log.sensors)]] for row in temperatures]
    )
    follower, times = followed_in_pieces(folder / "live.csv", data, cuts)
    np.testing.assert_allclose(times, t, atol=1e-9)
    assert tuple(follower.sensors or ()) == log.sensors


def test_a_units_row_states_the_time_unit_and_the_temperature_scale(write_csv):
    """Many loggers write a units row under the header; it was refused ("'[s]' is neither a number
    nor a time stamp"). Its time unit is used, K and °F are converted to °C, and a channel that is
    no temperature is left out with a note (refused if asked for)."""
    log = read_temperature_log(write_csv(UNITS_LOG))
    assert log.sensors == ("T1", "T2", "T3")
    np.testing.assert_allclose(log.time_min, np.arange(12.0))
    np.testing.assert_allclose(
        log.temperature_C, np.repeat((20 + 0.1 * np.arange(12.0))[:, None], 3, axis=1), atol=1e-9
    )
    assert any("'T2': read in K" in n for n in log.notes) and any("'T3': read in °F" in n for n in log.notes)
    assert any("not temperatures by the units row: speed (rpm)" in n for n in log.notes)
    with pytest.raises(InputError, match=r"sensor 'speed' is in 'rpm' by the units row, not a temperature"):
        read_temperature_log(write_csv(UNITS_LOG), sensors=["speed"])
    # a bad cell's row number counts the units row
    with pytest.raises(InputError, match=r"sensor 'T1', row 5: 'x' is not a number"):
        read_temperature_log(write_csv(UNITS_LOG.replace("20,20", "x")))


def test_a_first_row_without_readings_is_no_units_row(write_csv):
    """A time stamp with every sensor empty has no unit in it: it stays a data row."""
    log = read_temperature_log(
        write_csv(
            "time,T1,T2\n2026-11-22T08:00:00,,\n"
            + "".join(f"2026-11-22T08:{m:02d}:00,{20 + m / 10:.1f},{21 + m / 10:.1f}\n" for m in range(1, 20))
        )
    )
    assert len(log.time_min) == 20 and np.isnan(log.temperature_C[0]).all()


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


def test_a_time_column_in_seconds_read_as_minutes_gets_a_hint(write_csv, tmp_path):
    """A 2-h log in seconds under a plain 'Time' header read as 5 days of minutes; identify then
    said 'use a longer --window' and watch called the sensor 'no rise', with no word on the unit."""
    from mtident.io.follow import LogFollower

    text = "Time,T1\n" + "".join(f"{s},{20 + s / 7200:.4f}\n" for s in range(0, 7201, 10))
    log = read_temperature_log(write_csv(text))
    assert any(
        "time column 'Time' is read as minutes" in n and "7200 min (5.0 days)" in n and "give `time_unit='s'`" in n
        for n in log.notes
    )
    assert not any("read as minutes" in n for n in read_temperature_log(write_csv(text), time_unit="s").notes)
    assert not any(
        "read as minutes" in n for n in read_temperature_log(write_csv(text.replace("Time,", "Time_s,"))).notes
    )
    live = tmp_path / "live.csv"
    live.write_text(text)
    warnings = LogFollower(live).poll().warnings
    assert sum("read as minutes" in w for w in warnings) == 1


def test_a_time_column_in_seconds_with_a_sparse_step_gets_a_hint_before_two_days(write_csv, tmp_path):
    """A newcomer's later test in seconds (a reading every 30 s) under a plain 'time' header, cut at
    20 min as a live log would be: read as 1,200 minutes it looked settled, watch stopped 1.2-1.3 °C
    low, and the hint on seconds could come only after two days of 'minutes'."""
    from mtident.io.follow import LogFollower

    text = "time,T1\n" + "".join(f"{s},{20 + 6 * (1 - np.exp(-s / 1800)):.2f}\n" for s in range(0, 1201, 30))
    log = read_temperature_log(write_csv(text))
    assert any("a reading every 30 min: if it is in seconds, give `time_unit='s'`" in n for n in log.notes)
    assert not any("read as minutes" in n for n in read_temperature_log(write_csv(text), time_unit="s").notes)
    minutes = "time,T1\n" + "".join(f"{m},{20 + m / 100:.2f}\n" for m in range(0, 120, 2))
    assert not any("read as minutes" in n for n in read_temperature_log(write_csv(minutes)).notes)
    live = tmp_path / "live.csv"
    live.write_text(text)
    follower = LogFollower(live)
    assert sum("a reading every 30 min" in w for w in follower.poll().warnings) == 1
    with live.open("a") as more:
        more.write("".join(f"{s},26.00\n" for s in range(1230, 1500, 30)))
    assert not any("read as minutes" in w for w in follower.poll().warnings)


def test_a_time_unit_given_against_the_columns_own_is_said(write_csv, tmp_path):
    """`--time-unit min` on a column named 'time_s' read its seconds as minutes with no word, and
    watch stopped 1.2 °C low."""
    from mtident.io.follow import LogFollower

    text = "time_s,T1\n" + "".join(f"{s},{20 + s / 600:.2f}\n" for s in range(0, 600, 30))
    said = "time column 'time_s' states its unit as s, but `time_unit='min'` reads it in min"
    assert any(said in n for n in read_temperature_log(write_csv(text), time_unit="min").notes)
    assert not any("states its unit" in n for n in read_temperature_log(write_csv(text), time_unit="s").notes)
    assert not any("states its unit" in n for n in read_temperature_log(write_csv(text)).notes)
    live = tmp_path / "live.csv"
    live.write_text(text)
    assert sum(said in n for n in LogFollower(live, time_unit="min").poll().notes) == 1


def test_a_unit_at_the_end_of_a_column_name(write_csv):
    """'Time [s]' was read as minutes (only a _s suffix counted); 'T1 [°F]' as °C. A name whose
    brackets hold no unit ('T2 (spindle)') is a plain °C sensor."""
    text = "Time [s],T1 [°F],T2 (spindle)\n" + "".join(
        f"{60 * m},{68 + 0.18 * m:.2f},{20 + 0.1 * m:.1f}\n" for m in range(12)
    )
    log = read_temperature_log(write_csv(text))
    assert log.sensors == ("T1 [°F]", "T2 (spindle)")
    np.testing.assert_allclose(log.time_min, np.arange(12.0))
    np.testing.assert_allclose(
        log.temperature_C, np.repeat((20 + 0.1 * np.arange(12.0))[:, None], 2, axis=1), atol=1e-9
    )
    assert log.notes == ("sensor 'T1 [°F]': read in °F (its name), converted to °C",)


def test_a_text_column_is_no_sensor_unless_asked_for(write_csv):
    """A logger's status channel ('OK' in every row) stopped identify: "'OK' is not a number", and
    watch showed it as a sensor without data."""
    from mtident.io.follow import LogFollower

    text = "time,T1,Status\n" + "".join(f"{m},{20 + m / 10:.1f},OK\n" for m in range(10))
    log = read_temperature_log(write_csv(text))
    assert log.sensors == ("T1",) and log.notes == ("left out, no numbers in them: Status",)
    follower = LogFollower(write_csv(text, "live.csv"))
    rows = follower.poll()
    assert rows.notes == ("left out, no numbers in them: Status",) and not rows.warnings and follower.sensors == ["T1"]
    with pytest.raises(InputError, match=r"sensor 'Status', row 2: 'OK' is not a number"):
        read_temperature_log(write_csv(text), sensors=["T1", "Status"])
    # a sensor with one bad cell is still refused by name: it has numbers
    with pytest.raises(InputError, match=r"sensor 'T1', row 4: 'oops' is not a number"):
        read_temperature_log(write_csv(text.replace("2,20.2", "2,oops")))


def test_a_short_first_row_keeps_the_header(write_csv):
    """The header is looked for further down only where a later line heads a table; a first data
    row with a cell missing (a channel not ready) must not make the rows below a "header"."""
    rows = "".join(f"{k},{20 + k / 10:.2f},{19 + k / 10:.2f}\n" for k in range(1, 20))
    log = read_temperature_log(write_csv("time_min,A,B\n0,20.1\n" + rows))
    assert log.sensors == ("A", "B")
    np.testing.assert_allclose(log.time_min, np.arange(20.0))
    assert np.isnan(log.temperature_C[0, 1]) and log.temperature_C[1, 1] == 19.1


def test_settings_before_the_header_with_as_many_cells_are_no_header(write_csv):
    """'Interval,60,s' splits into as many cells as the table 'time_min,A,B', but no data row
    follows it: the header is the line after the blank one, which a data row follows."""
    rows = "".join(f"{k},{20 + k / 10:.2f},{19 + k / 10:.2f}\n" for k in range(10))
    log = read_temperature_log(write_csv("Logger: GL240\nInterval,60,s\nChannels,2,K\n\ntime_min,A,B\n" + rows))
    assert log.sensors == ("A", "B")
    np.testing.assert_allclose(log.temperature_C[:, 0], 20 + np.arange(10) / 10)


@pytest.mark.parametrize("fmt", ["%d-%m-%Y %H:%M:%S", "%d-%b-%Y %H:%M:%S"])
def test_dashed_day_first_stamps(write_csv, fmt):
    """22-11-2026 08:00:00 and 22-Nov-2026 08:00:00 (spreadsheets, LabVIEW) were refused as no time stamp."""

    start = dt.datetime(2026, 11, 30, 23, 58, 0)  # across the end of the month
    rows = "".join(f"{(start + dt.timedelta(minutes=k)).strftime(fmt)},{20 + k / 10:.2f}\n" for k in range(6))
    log = read_temperature_log(write_csv("stamp,A\n" + rows))
    np.testing.assert_allclose(log.time_min, np.arange(6.0))


def test_spreadsheet_serial_dates_are_named_not_read_as_minutes(write_csv):
    """A date cell saved as a number (46348.33333 is 22.11.2026 08:00): read as minutes, a 2-h
    test lasted 0.08 min and was identified as λ = 23/min, "fits". In a column named as dates it
    is read in days, with a note (both readers, also resumed); in any other it is refused with the
    unit to give; --time-unit d reads it, --time-unit min as minutes."""
    from mtident.io.follow import LogFollower

    rows = "".join(f"{46348.333333 + k / 1440:.8f},{26.7 - 8.8 * np.exp(-0.016 * k):.2f}\n" for k in range(60))
    path = write_csv("Time,T1\n" + rows)
    with pytest.raises(
        InputError,
        match=r"'Time' looks like spreadsheet serial dates \(days since 30.12.1899: 46348.33333 is 22.11.2026 08:00:00\), not minutes: give `time_unit='d'`",
    ):
        read_temperature_log(path)
    np.testing.assert_allclose(read_temperature_log(path, time_unit="d").time_min, np.arange(60.0), atol=1e-4)
    assert read_temperature_log(path, time_unit="min").time_min[-1] == pytest.approx(59 / 1440, abs=1e-6)
    dated = write_csv("Date,T1\n" + rows, "dated.csv")
    log = read_temperature_log(dated)
    np.testing.assert_allclose(log.time_min, np.arange(60.0), atol=1e-4)
    said = "time column 'Date' read as spreadsheet serial dates (days since 30.12.1899: 46348.33333 is 22.11.2026 08:00:00); give `time_unit='min'` if it is minutes"
    assert log.notes == (said,)
    live = write_csv("Date,T1\n" + "".join(rows.splitlines(True)[:30]), "live.csv")
    follower = LogFollower(live)
    first = follower.poll()
    assert first.notes == (said,)
    live.write_text("Date,T1\n" + rows)
    second = LogFollower.resume(live, through_state_file(follower.position()), None, None).poll()
    np.testing.assert_allclose(np.concatenate([first.time_min, second.time_min]), np.arange(60.0), atol=1e-4)


@pytest.mark.parametrize("head", ["Time_ms,A\n", "Time [ms],A\n", "time,A\nms,°C\n"])
def test_a_time_column_in_milliseconds(write_csv, head):
    """Time_ms was read as minutes (a 10-min log as 417 days, with a hint that it might be seconds)."""
    rows = "".join(f"{60_000 * k},{20 + k / 10:.2f}\n" for k in range(10))
    np.testing.assert_allclose(read_temperature_log(write_csv(head + rows)).time_min, np.arange(10.0))


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


def test_a_burnout_marker_is_an_open_circuit_sample(write_csv):
    """Graphtec writes BURNOUT for a broken thermocouple's reading: it stopped the file reader
    ("'BURNOUT' is not a number") where the live follower bridged it."""
    rows = "".join(f"{k},{'BURNOUT' if k in (7, 9) else f'{20 + k / 10:.2f}'}\n" for k in range(30))
    log = read_temperature_log(write_csv("time_min,A\n" + rows))
    assert log.notes == ("sensor 'A': skipped 2 open-circuit sample(s) (rows 9, 11)",)
    assert np.isnan(log.temperature_C[[7, 9], 0]).all() and log.temperature_C[8, 0] == 20.8


def test_real_logger_exports_name_their_channels_and_leave_out_the_rest(write_csv):
    """Layouts of real exports (public test files of a logger-graphing project), each refused
    before: Tinytag's unnamed counter, numbered channels, description rows and units in the cells
    ("'S/N' is neither a number nor a time stamp"); T&D's unnamed stamp column with serial dates
    beside it ("row 2 is empty"). The humidity and light channels are left out, and named; so is
    the dew point (in °C, read as a sensor before), by the Property row or by its name (EasyLog)."""
    tinytag = (
        ",Time,1,2,3\nS/N,,227659,227659,227659\nType,,Tinytag Ultra H°C/%RH,Tinytag Ultra H°C/%RH,csv "
        "file\nDescription,,Spindle,Spindle,Spindle\nProperty,,Temperature,Humidity,Dew Point\n"
    )
    tinytag += "".join(
        f"{k + 1},2026-11-22 08:{k:02d}:00,{20 + k / 10:.1f} °C,{56 + k / 100:.1f} %RH,{8 + k / 10:.1f} °C\n"
        for k in range(8)
    )
    log = read_temperature_log(write_csv(tinytag))
    assert log.sensors == ("1",)
    assert (
        "left out, computed from the humidity (a dew point, wet-bulb temperature or heat index; `sensors` reads one "
        "all the same): 3" in log.notes
    )
    assert read_temperature_log(write_csv(tinytag), sensors=["3"]).temperature_C[0, 0] == 8.0
    np.testing.assert_allclose(log.temperature_C[:, 0], 20 + np.arange(8) / 10)
    np.testing.assert_allclose(log.time_min, np.arange(8.0))
    assert "left out, a row counter: the unnamed first column; the time is 'Time'" in log.notes
    from mtident.io.follow import LogFollower

    followed = LogFollower(write_csv(tinytag, "live.csv"))
    assert followed.poll().notes[
        0
    ] == "left out, a row counter: the unnamed first column; the time is 'Time'" and followed.sensors == ["1"]
    assert "left out, not temperatures by its cells: 2 (%RH)" in log.notes
    # the older export writes no units in the cells: the Property row names the humidity
    plain = re.sub(r" (°C|%RH)", "", tinytag)
    assert read_temperature_log(write_csv(plain)).sensors == ("1",)
    easylog = "Comedor,Time,Celsius(°C),Humidity(%rh),Dew Point(°C),Serial Number\n"
    easylog += "".join(
        f"{k + 1},2026-11-22 08:{k:02d}:00,{20 + k / 10:.1f},{56 + k / 100:.1f},{8 + k / 10:.1f}{',10543212' if k == 0 else ''}\n"
        for k in range(8)
    )
    log = read_temperature_log(write_csv(easylog))
    assert log.sensors == ("Celsius(°C)",) and any(
        n.endswith("heat index; `sensors` reads one all the same): Dew Point(°C)") for n in log.notes
    )
    tandd = ",Date/Time,No.1,No.2,No.3,No.4,\n,Date/Time,ch1,ch2,ch3,ch4,\n,,lx,mW/cm2,°C,%,\n"
    tandd += "".join(
        f"2026-11-22 08:{k:02d}:00,{46348.333333 + k / 1440:.5f},6.27,0,{20 + k / 10:.1f},51,\n" for k in range(8)
    )
    log = read_temperature_log(write_csv(tandd))
    assert log.sensors == ("No.3",)
    assert (
        "left out, named as times: Date/Time" in log.notes
        and "left out, not temperatures by the units row: No.1 (lx), No.2 (mW/cm2), No.4 (%)" in log.notes
    )
    meaco = "RECEIVER,TRANSMITTER,DATE,TEMPERATURE,HUMIDITY\n" + "".join(
        f'"Shop","Spindle","2026-11-22 08:{k:02d}",{20 + k / 10:.2f},55.1\n' for k in range(8)
    )
    log = read_temperature_log(write_csv(meaco))
    assert log.sensors == ("TEMPERATURE",) and "the time is 'DATE', the first column of time stamps" in log.notes
    with pytest.raises(InputError, match="sensor 'HUMIDITY' is a humidity by its name, not a temperature"):
        read_temperature_log(write_csv(meaco), sensors=["HUMIDITY"])
    # a bad first data row is still refused, not taken for a row that describes the channels
    with pytest.raises(InputError, match="row 2: 'yesterday' is neither a number nor a time stamp"):
        read_temperature_log(write_csv("time,A\nyesterday,20\n" + "".join(f"{k},20\n" for k in range(1, 6))))


def test_hobo_exports_in_fahrenheit_with_event_rows_at_the_end(write_csv):
    """HOBOware's export: the header began with '#' and was skipped as a comment (the first data
    row became the header), the unit after a comma ('Temp, °F (LGR S/N: ...)') was not seen, so
    °F would have been read as °C, and the event rows of the read-out, several at one time and
    without a reading, were refused as duplicate times."""
    rows = "".join(
        f"{k + 1},11/22/26 {8 + k // 60:02d}:{k % 60:02d}:00 "
        f"AM,{68 + 0.18 * k:.3f},50.1,{'Logged' if k == 0 else ''},,\n"
        for k in range(8)
    )
    rows += "9,11/22/26 08:10:00 AM,,,,Logged,\n10,11/22/26 08:10:00 AM,,,,,Logged\n"
    text = (
        'Plot Title: 20827226,,,,,,\n#,"Date Time, GMT+01:00","Temp, °F (LGR S/N: 20827226, SEN S/N: 20827226)","RH, '
        '% (LGR S/N: 20827226)",Coupler Detached (LGR S/N: 20827226),Host Connected (LGR S/N: 20827226),End Of File '
        "(LGR S/N: 20827226)\n" + rows
    )
    log = read_temperature_log(write_csv(text))
    assert log.sensors == ("Temp, °F (LGR S/N: 20827226, SEN S/N: 20827226)",)
    np.testing.assert_allclose(log.temperature_C[:, 0], 20 + 0.1 * np.arange(8), atol=1e-9)
    np.testing.assert_allclose(log.time_min, np.arange(8.0))
    assert any("left out 2 row(s) without a reading" in n for n in log.notes)
    # the classic export: tabs, the unit in brackets with the serial number after it, empty event channels
    classic = "Date Time\tTemp (°F)  #9724974\tCoupler Detached\tEnd Of File\n" + "".join(
        f"11/22/26 08:{k:02d}:00\t{68 + 0.18 * k:.3f}\t\t\n" for k in range(8)
    )
    log = read_temperature_log(write_csv(classic))
    assert log.sensors == ("Temp (°F)  #9724974",)
    np.testing.assert_allclose(log.temperature_C[:, 0], 20 + 0.1 * np.arange(8), atol=1e-9)
    # a row without a reading inside the log stays (a dropout, bridged), and a time repeated with a reading is refused
    with pytest.raises(InputError, match="duplicate time"):
        read_temperature_log(write_csv(text.replace("8,11/22/26 08:07:00 AM", "8,11/22/26 08:06:00 AM")))


def test_an_excel_workbook_reads_like_the_csv_it_holds(tmp_path):
    """Loggers' software exports .xlsx as readily as CSV; a workbook ended in a traceback
    (the csv module's "new-line character seen in unquoted field")."""

    import pandas as pd

    from mtident.io.follow import LogFollower

    t = np.arange(12.0)
    values = 20 + t / 10
    stamps = [dt.datetime(2026, 11, 22, 8, 0) + dt.timedelta(minutes=float(m)) for m in t]
    book = tmp_path / "log.xlsx"
    with pd.ExcelWriter(book) as writer:  # a sheet of details before the data's sheet is passed over
        pd.DataFrame([["Device", "UX120-006M"], ["Serial", "20827226"]]).to_excel(
            writer, sheet_name="Details", index=False, header=False
        )
        pd.DataFrame([["Logger", "HOBO UX120"]]).to_excel(writer, sheet_name="Data", index=False, header=False)
        pd.DataFrame({"Date Time": stamps, "Temp, °F (LGR S/N: 1)": values * 9 / 5 + 32, "RH, %": 50.0}).to_excel(
            writer, sheet_name="Data", index=False, startrow=2
        )
    log = read_temperature_log(book)
    assert log.sensors == ("Temp, °F (LGR S/N: 1)",)
    np.testing.assert_allclose(log.time_min, t, atol=1e-9)
    np.testing.assert_allclose(log.temperature_C[:, 0], values, atol=1e-9)
    with pytest.raises(InputError, match="an Excel workbook is not written row by row"):
        LogFollower(book).poll()
    (tmp_path / "old.xls").write_bytes(b"\xd0\xcf\x11\xe0" + bytes(600))
    with pytest.raises(InputError, match=r"an Excel 97-2003 workbook \(.xls\); save it as .xlsx or as CSV"):
        read_temperature_log(tmp_path / "old.xls")
    (tmp_path / "broken.xlsx").write_bytes(b"PK\x03\x04" + b"x" * 100)
    with pytest.raises(InputError, match="not a readable Excel workbook"):
        read_temperature_log(tmp_path / "broken.xlsx")


def test_other_files_and_line_ends(write_csv, tmp_path):
    """A lone CR at the end of each line (old Macs, some serial loggers) ended in a traceback;
    a binary file is refused by both readers; a settings line with as many cells as a two-column
    table, above a blank line, is no header."""
    from mtident.io.follow import LogFollower

    rows = "".join(f"{k},{20 + k / 10:.1f}\n" for k in range(8))
    cr = tmp_path / "cr.csv"
    cr.write_bytes(("time,A\n" + rows).replace("\n", "\r").encode())
    np.testing.assert_allclose(read_temperature_log(cr).temperature_C[:, 0], 20 + np.arange(8) / 10)
    binary = tmp_path / "data.csv"
    binary.write_bytes(b"time,A\n0,20\x00\x01\x02\n" + bytes(range(256)))
    with pytest.raises(InputError, match="not a text file"):
        read_temperature_log(binary)
    with pytest.raises(InputError, match="not a text file"):
        LogFollower(binary).poll()
    log = read_temperature_log(write_csv("Model,GL240\n\ntime,A\n" + rows))
    assert log.sensors == ("A",) and len(log.time_min) == 8


def test_a_log_of_nothing_but_left_out_columns_says_what_it_left_out(write_csv):
    """With every column left out, the message listed nothing: 'no temperature column: its name gives '."""
    with pytest.raises(
        InputError,
        match=r"no temperature column; left out: Status \(the logger's own record\); by its name: RH/% \(%\) \(`sensors=\[NAME\]`",
    ):
        read_temperature_log(write_csv("time,Status,RH/%\n" + "".join(f"{k},1,50\n" for k in range(6))))


def test_a_time_column_named_by_its_unit_in_words(write_csv):
    """'Elapsed hours' or 'Seconds' was read as minutes: a 40-min test at 1 min lasted 0.67 min. A
    sensor named 'T min' is still a temperature."""
    for name, per_minute in (("Elapsed hours", 1 / 60), ("Seconds", 60.0), ("Time in minutes", 1.0)):
        log = read_temperature_log(
            write_csv(f"{name},T min\n" + "".join(f"{k * per_minute:.6f},{20 + k / 10:.1f}\n" for k in range(8)))
        )
        np.testing.assert_allclose(log.time_min, np.arange(8.0), atol=1e-3)
        assert log.sensors == ("T min",)


def test_a_machines_labels_are_no_units(write_csv):
    """'Bearing (RH)' (right-hand), '(A)', '(N)' label places on a machine: read as sensors, not
    left out as a humidity, an ampere or a newton."""
    log = read_temperature_log(
        write_csv(
            "time,Bearing (RH),Bearing (LH),Motor (A),Column (N),RH\n"
            + "".join(f"{k},{20 + k / 10:.1f},20,20,20,20\n" for k in range(8))
        )
    )
    assert log.sensors == ("Bearing (RH)", "Bearing (LH)", "Motor (A)", "Column (N)", "RH")


def test_channels_named_under_a_numbering_header(write_csv):
    """T&D numbers its channels in the header (No.1, No.2) and writes the names a user gave them
    in the row under it; they were read as 'No.2' and 'No.3'. Both readers take the names, say so,
    and a state file resumes with them."""
    from mtident.io.follow import LogFollower

    text = ",Date/Time,No.1,No.2,No.3,\n,Date/Time,ch1,Spindle,Motor,\n,,lx,°C,°C,\n" + "".join(
        f"2026-11-22 08:{k:02d}:00,{46348.333333 + k / 1440:.5f},6.27,{20 + k / 10:.1f},{21 + k / 10:.1f},\n"
        for k in range(8)
    )
    path = write_csv(text)
    log = read_temperature_log(path)
    assert log.sensors == ("Spindle", "Motor")
    assert "channels named by the row under the header: No.2 is 'Spindle', No.3 is 'Motor'" in log.notes
    follower = LogFollower(path)
    rows = follower.poll()
    assert follower.sensors == ["Spindle", "Motor"] and any("No.2 is 'Spindle'" in n for n in rows.notes)
    np.testing.assert_array_equal(rows.temperature_C, log.temperature_C)
    resumed = LogFollower.resume(path, through_state_file(follower.position()), None, None)
    assert resumed.dialect == follower.dialect
    assert read_temperature_log(path, sensors=["Motor"]).sensors == ("Motor",)
    # a row of default names ("ch1") renames nothing; a row that would repeat a name is no row of names
    assert read_temperature_log(write_csv(text.replace("Spindle,Motor", "ch2,ch3"))).sensors == ("No.2", "No.3")
    assert read_temperature_log(write_csv(text.replace("Spindle,Motor", "Spindle,Spindle"))).sensors == ("No.2", "No.3")


def test_a_column_named_with_another_case_or_a_slip_is_pointed_to(write_csv):
    path = write_csv("time_min,Spindle,room\n" + "".join(f"{k},{20 + k / 10:.2f},19.9\n" for k in range(8)))
    with pytest.raises(
        InputError, match=r"no sensor column 'Room' \(did you mean 'room'\?\); the log has: Spindle, room"
    ):
        read_temperature_log(path, sensors=["Room"])
    with pytest.raises(InputError, match=r"no sensor column 'Spindel' \(did you mean 'Spindle'\?\)"):
        read_temperature_log(path, sensors=["Spindel"])
    with pytest.raises(InputError, match=r"no sensor column 'T9'; the log has"):
        read_temperature_log(path, sensors=["T9"])


def test_a_time_column_in_hours_read_as_minutes_gets_a_hint(write_csv, tmp_path):
    """A 14-h log in hours under a plain 't' header read as 14 minutes at a reading every 0.5 s:
    identify gave a 3-min t_eq, trusted, and watch flipped between 'may stop' and 'undetermined',
    with no word on the unit."""
    from mtident.io.follow import LogFollower

    text = "t,T1\n" + "".join(f"{k / 120:.5f},{20 + 8 * (1 - np.exp(-k / 120)):.2f}\n" for k in range(1681))
    log = read_temperature_log(write_csv(text))
    assert any("runs only to 14 min with a reading every 0.5 s" in n and "time_unit='h'" in n for n in log.notes)
    assert not any("read as minutes" in n for n in read_temperature_log(write_csv(text), time_unit="h").notes)
    short = "t,T1\n" + "".join(f"{k / 120:.5f},{20 + k / 100:.2f}\n" for k in range(50))
    assert not any("read as minutes" in n for n in read_temperature_log(write_csv(short)).notes)
    live = tmp_path / "live.csv"
    live.write_text(text)
    follower = LogFollower(live)
    assert sum("time_unit='h'" in w for w in follower.poll().warnings) == 1


def test_a_folder_given_as_a_log_is_said_to_be_a_folder(tmp_path):
    with pytest.raises(InputError, match=r": a folder, not a log file$"):
        read_temperature_log(tmp_path)


def test_a_gap_in_the_readings_and_a_unit_given_for_time_stamps_are_said(write_csv, tmp_path):
    """A newcomer's log with 40 minutes missing: inspect still said 'a step of 30 s', and neither
    identify nor watch mentioned the gap; --time-unit s given for a stamp column was ignored silently."""
    from mtident.io.follow import LogFollower

    minutes = [m / 2 for m in range(240) if not 120 <= m < 200]
    text = "time_min,A\n" + "".join(f"{m:g},{20 + m / 100:.3f}\n" for m in minutes)
    path = write_csv(text)
    gap = "a gap of 40.5 min in the readings after t = 59.5 min (otherwise a reading every 30 s): the fit bridges it"
    assert gap in read_temperature_log(path).notes
    said = LogFollower(Path(path)).poll().notes
    assert any(n.startswith("a gap of 40.5 min in the readings after t = 59.5 min") for n in said)
    stamps = "time,A\n" + "".join(f"2026-11-25 08:{m:02d}:00,{20 + m / 100:.2f}\n" for m in range(30))
    notes = read_temperature_log(write_csv(stamps), time_unit="s").notes
    assert "time column 'time' holds time stamps: the unit 's' given for it is not used" in notes
    assert not any("gap" in n or "not used" in n for n in read_temperature_log(write_csv(stamps)).notes)


def test_a_row_written_twice_is_left_out_and_said(write_csv):
    """A logger flushing its buffer again wrote a row twice; the run ended with 'duplicate time'.
    The same time with other readings is still refused."""
    rows = "".join(f"{k},{20 + k / 10:.2f}\n" for k in range(20))
    log = read_temperature_log(write_csv("time_min,A\n" + rows.replace("5,20.50\n", "5,20.50\n5,20.50\n")))
    assert len(log.time_min) == 20 and "left out 1 row(s) repeating an earlier row exactly (rows 8)" in log.notes
    with pytest.raises(InputError, match="duplicate time"):
        read_temperature_log(write_csv("time_min,A\n" + rows.replace("5,20.50\n", "5,20.50\n5,20.60\n")))


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


def test_decimal_commas_in_a_comma_separated_export_are_refused_with_the_reason(write_csv):
    """A classic broken export: a decimal comma in a comma-separated file splits each reading in
    two. It was read with one sensor as the integer parts and the next as the decimal parts (a
    ParserWarning leaked out), and identified as T∞ -4,895 to 7,209 °C."""
    rows = "".join(f"26.11.2026 07:{m:02d}:00,22,{70 + m},21,{60 + m}\n" for m in range(0, 20, 2))
    path = write_csv("Zeit,Bearing,Housing\n" + rows)
    with pytest.raises(
        InputError,
        match=r"log\.csv: line 2 has 5 cells where the header has 3 \(Zeit, Bearing, Housing\): "
        r"'26\.11\.2026 07:00:00,22,70,21,60'; .*likely decimal commas in a comma-separated file: '22,70' is one "
        r"reading split in two\); export it with ';'",
    ):
        read_temperature_log(path)


def test_a_row_longer_than_the_header_after_the_first_is_refused_with_the_reason(write_csv):
    rows = "".join(f"{m},{20 + m / 10:.1f}\n" for m in range(8)) + "8,21.3,5\n"
    with pytest.raises(InputError, match=r"line 10 has 3 cells where the header has 2 \(time_min, A\)"):
        read_temperature_log(write_csv("time_min,A\n" + rows))


def test_empty_cells_beyond_the_header_are_no_reading_and_read_as_before(write_csv):
    rows = "".join(f"{m},{20 + m / 10:.1f},,\n" for m in range(8))
    log = read_temperature_log(write_csv("time_min,A\n" + rows))
    np.testing.assert_allclose(log.temperature_C[:, 0], 20 + np.arange(8) / 10)


def test_a_half_written_last_line_is_left_out_and_said(write_csv):
    """A log still being written ends in a cut line without its line end; inspect and identify
    read it as a reading (2.00 °C, trusted); watch leaves it out, and so must the file reader."""
    rows = "".join(
        f"26.11.2026 {7 + m // 60:02d}:{m % 60:02d}:00;{22 + m / 10:.2f};{21 + m / 20:.2f}\n" for m in range(0, 40, 2)
    )
    path = write_csv(
        "Zeit;Lager;Gehäuse\n" + rows.replace(".", ",").replace(",11,2026", ".11.2026") + "26.11.2026 07:40:00;29,3"
    )
    log = read_temperature_log(path)
    assert len(log.time_min) == 20
    assert not np.isnan(log.temperature_C).any()
    assert any(
        "left out the last line, '26.11.2026 07:40:00;29,3': it has no line end and 2 of the 3 cells" in note
        for note in log.notes
    ), log.notes


def test_a_last_line_without_a_line_end_but_complete_is_read(write_csv):
    rows = "".join(f"{m},{20 + m / 10:.1f},{21 + m / 10:.1f}\n" for m in range(8))
    log = read_temperature_log(write_csv("time_min,A,B\n" + rows + "8,21.3,22.4"))
    assert len(log.time_min) == 9 and not any("last line" in note for note in log.notes)


def test_a_room_far_outside_a_workshops_range_read_as_celsius_is_said(write_csv):
    """A log in °F without a unit row: a room at 69 "°C" and a machine at 70-92 were taken as °C
    without a word (with a °F units row they convert, rightly)."""
    rows = "".join(f"{m},{70 + 22 * (1 - np.exp(-m / 40)):.2f},{69 + m / 100:.2f}\n" for m in range(0, 60, 2))
    log = read_temperature_log(write_csv("time_min,spindle,room\n" + rows))
    said = [note for note in log.notes if "far outside any workshop's range" in note]
    assert said and "'room' reads 69 to 69.58" in said[0] and "°F" in said[0] and "units row" in said[0], log.notes
    converted = read_temperature_log(write_csv("time_min,spindle,room\nmin,°F,°F\n" + rows, "stated.csv"))
    assert not any("workshop" in note for note in converted.notes)


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


# a spindle from 20 °C to 100 °C (212 °F, 373.15 K) with a room at 20 °C, in °C; the tests write it in °F or
# K without a unit
_STATED_C = np.column_stack([20 + 80 * np.arange(12.0) / 11, np.full(12, 20.0)])


def _without_units(to_unit, units_row: str = "") -> str:
    rows = "".join(f"{m},{to_unit(spindle):.4f},{to_unit(room):.4f}\n" for m, (spindle, room) in enumerate(_STATED_C))
    return "time_min,spindle,room\n" + units_row + rows


@pytest.mark.parametrize(
    ("unit", "to_unit", "written"),
    [("F", lambda c: c * 9 / 5 + 32, "°F"), ("K", lambda c: c + 273.15, "K"), ("C", lambda c: c, "°C")],
)
def test_temperature_unit_states_the_unit_of_columns_that_state_none(write_csv, unit, to_unit, written):
    """Issue 37: a log in °F or K without a units row or a unit in its names was read as °C, with at
    most a note on a room far outside a workshop's range; ``temperature_unit`` states its unit, and
    every temperature column converts, the room's too (212 °F and 373.15 K are 100 °C)."""
    path = write_csv(_without_units(to_unit))
    assert path.read_text().splitlines()[-1] == f"11,{to_unit(100.0):.4f},{to_unit(20.0):.4f}"  # 212 °F, 373.15 K
    log = read_temperature_log(path, temperature_unit=unit)
    assert log.sensors == ("spindle", "room")
    np.testing.assert_allclose(log.temperature_C, _STATED_C, atol=1e-4)
    assert log.temperature_C[-1, 0] == pytest.approx(100.0)
    converted = [n for n in log.notes if "`temperature_unit`" in n]
    if unit == "C":
        assert not converted
    else:
        assert converted == [f"read in {written} (`temperature_unit`), converted to °C: spindle, room"]
    assert not any("workshop" in note for note in log.notes)  # the unit was stated: nothing is assumed
    if unit != "C":  # without the option the numbers are read as °C, as they are written
        plain = read_temperature_log(path)
        np.testing.assert_allclose(plain.temperature_C, to_unit(_STATED_C), atol=1e-4)


def test_the_note_on_a_room_read_as_celsius_names_the_unit_option(write_csv):
    log = read_temperature_log(write_csv(_without_units(lambda c: c * 9 / 5 + 32)))
    said = [note for note in log.notes if "far outside any workshop's range" in note]
    assert said and "`temperature_unit='F'`" in said[0], log.notes


@pytest.mark.parametrize(
    ("header", "units_row", "unit", "message"),
    [
        ("time_min,spindle,room", "min,°C,\n", "F", "sensor 'spindle' is in °C by the units row"),
        ("time_min,spindle [K],room", "", "F", "sensor 'spindle [K]' is in K by its name"),
        ("time_min,spindle,room (°F)", "", "K", "sensor 'room (°F)' is in °F by its name"),
        ("time_min,spindle,room", "min,K,°F\n", "C", "sensor 'spindle' is in K by the units row"),
    ],
)
def test_a_columns_own_unit_that_temperature_unit_contradicts_is_refused(write_csv, header, units_row, unit, message):
    """Which of the two is right cannot be told: the column is refused, named with its unit and the option."""
    rows = "".join(f"{m},{300 + m},{70 + m / 10}\n" for m in range(8))
    path = write_csv(header + "\n" + units_row + rows)
    with pytest.raises(InputError, match=re.escape(message) + f".*`temperature_unit='{unit}'`"):
        read_temperature_log(path, temperature_unit=unit)
    read_temperature_log(path)  # read in its own units without the option


def test_temperature_unit_leaves_a_columns_own_unit_that_agrees_and_other_quantities_alone(write_csv):
    """A column in °F by its name is read in °F with ``temperature_unit='F'``; one in rpm by the units
    row is no temperature whatever the option says; a humidity named as one is left out."""
    rows = "".join(f"{m},{212 - m},{32 + m},{1000 + m},{50 + m}\n" for m in range(8))
    log = read_temperature_log(
        write_csv("time_min,T1 [°F],T2,speed,Humidity\nmin,,,rpm,\n" + rows), temperature_unit="F"
    )
    assert log.sensors == ("T1 [°F]", "T2")
    np.testing.assert_allclose(log.temperature_C[:, 0], (212 - np.arange(8.0) - 32) * 5 / 9)
    np.testing.assert_allclose(log.temperature_C[:, 1], np.arange(8.0) * 5 / 9)
    with pytest.raises(InputError, match=r"temperature unit 'X' is not one of: C, F, K"):
        read_temperature_log(write_csv("time_min,T1\n" + rows.replace(",", ";")), temperature_unit="X")


def test_rows_after_a_row_left_out_are_named_by_their_own_line(write_csv):
    """A message names the row as the file numbers it: a repeated row left out before it made the
    reader name the row above."""
    rows = "".join(f"{k},{20 + k / 10:.2f},{21 + k / 10:.2f}\n" for k in range(20))
    twice = rows.replace("3,20.30,21.30\n", "3,20.30,21.30\n3,20.30,21.30\n")
    log = read_temperature_log(write_csv("time_min,A,B\n" + twice.replace("8,20.80,", "8,,")))
    # line 1 the header, k at line k + 2, one more after the row written twice
    assert log.notes[-1] == "sensor 'A': skipped 1 empty/NaN sample(s) (rows 11)", log.notes
    with pytest.raises(InputError, match=r"sensor 'A', row 11: 'x' is not a number"):
        read_temperature_log(write_csv("time_min,A,B\n" + twice.replace("8,20.80,", "8,x,"), "bad.csv"))


@pytest.mark.parametrize("text", ["", "  \n\n"])
def test_an_empty_file_is_said_to_be_empty(write_csv, text):
    with pytest.raises(InputError, match=r"log\.csv: an empty file; a log is CSV text, a header line"):
        read_temperature_log(write_csv(text))


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


def test_sample_log_is_ten_sensors_four_hundred_minutes():
    log = sample_log()
    assert log.sensors == tuple(f"T{i}" for i in range(1, 11))
    np.testing.assert_allclose(log.time_min, np.arange(401.0))
    np.testing.assert_allclose(log.temperature_C[0], 17.9, atol=0.1)
    # 0.01 °C resolution
    np.testing.assert_allclose(log.temperature_C * 100, np.round(log.temperature_C * 100), atol=1e-6)
