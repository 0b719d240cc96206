"""Tests of :mod:`mtident.io.dialect` and :mod:`mtident.io.log_file`: delimiters, decimal marks,
preambles, encodings, line ends, the header and the rows under it, and a last line cut by a logger
still writing.
"""

from __future__ import annotations

import datetime as dt
import json
import re

import numpy as np
import pytest
from conftest import logger_dialects, through_state_file
from helpers import followed_in_pieces, mtident, workbook_of_runs
from hypothesis import example, given, settings
from hypothesis import strategies as st

from mtident.exceptions import InputError
from mtident.io import read_temperature_log


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
    out = mtident("thermal", "inspect", str(write_csv("time_min;Spindle;Housing\n" + _rows() + cut, "i.csv")), "--json")
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


def test_binary_file_is_refused(write_csv, tmp_path):
    path = tmp_path / "bin.csv"
    path.write_bytes(b"\xff\xfe\x00\x01garbage")
    with pytest.raises(InputError, match="not a readable CSV file|need a time column"):
        read_temperature_log(path)


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


def test_a_workbook_of_several_sheets_says_the_sheet_it_read_and_reads_the_one_named(tmp_path):
    """A workbook's first sheet with a table was read without a word: a user whose readings were
    on its second sheet got the first's answer. The sheet read, the others and how to pick one are
    said; a sheet is named by name (case aside) or number from 1."""
    from mtident.io.log_file import header_names

    book = tmp_path / "runs.xlsx"
    _, _, b = workbook_of_runs(book)
    log = read_temperature_log(book)
    assert log.sensors == ("A",)
    assert log.notes == (
        f"{book}: read sheet 'Run 1' of 4 (the first that holds a table); not read: 'Details' (no table), "
        "'Run 2' (a table too), 'Spare' (empty); `sheet='NAME'` reads another (its name, or its number from 1)",
    )
    for sheet in ("Run 2", "run 2", " Run 2 "):
        log = read_temperature_log(book, sheet=sheet)
        assert log.sensors == ("B", "Umgebung") and log.notes == (), sheet
    # a number counts from 1, where pandas counts from 0: the sheet read is said by name
    for sheet in (3, "3"):
        log = read_temperature_log(book, sheet=sheet)
        assert log.sensors == ("B", "Umgebung") and log.notes == (
            f"{book}: read sheet 'Run 2', number 3 of 4 (counted from 1)",
        )
        np.testing.assert_allclose(log.temperature_C[:, 0], b, atol=1e-9)
    assert header_names(book, "Run 2") == ["time_min", "B", "Umgebung"] and header_names(book) == ["time_min", "A"]
    # a logger's details sheet named is refused for what it is, not as a log too short
    for sheet in ("Details", 1):
        with pytest.raises(InputError, match=r"sheet 'Details' holds no table of readings .*: 'Run 1', 'Run 2'$"):
            read_temperature_log(book, sheet=sheet)
    listed = re.escape("the workbook's sheets: 1 'Details', 2 'Run 1', 3 'Run 2', 4 'Spare' (`sheet='NAME'`")
    with pytest.raises(InputError, match=rf"runs.xlsx: no sheet 'Run 3'; {listed}"):
        read_temperature_log(book, sheet="Run 3")
    for number in (5, "0"):
        with pytest.raises(InputError, match=rf"no sheet number {number} \(counted from 1\); {listed}"):
            read_temperature_log(book, sheet=number)


def test_a_sheet_named_where_there_are_no_sheets_is_refused(write_csv, tmp_path):
    """An option that changes nothing is not passed over: a CSV log or a DataFrame has no sheets."""
    import pandas as pd

    path = write_csv("time_min,T1\n" + "".join(f"{m},{20 + m / 10}\n" for m in range(6)))
    with pytest.raises(
        InputError, match=r"log.csv: `sheet='2'` names a sheet of an Excel workbook, but this log is CSV"
    ):
        read_temperature_log(path, sheet=2)
    with pytest.raises(InputError, match="a DataFrame has none"):
        read_temperature_log(pd.DataFrame({"time_min": range(6), "T1": 20.0}), sheet="Data")


def test_a_workbook_whose_other_sheets_are_empty_reads_its_table_without_a_note(tmp_path):
    """Excel's new workbooks held three sheets, two of them empty: nothing to choose, nothing said."""
    import pandas as pd

    book = tmp_path / "one.xlsx"
    with pd.ExcelWriter(book) as writer:
        pd.DataFrame({"time_min": range(6), "T1": 20.0}).to_excel(writer, sheet_name="Sheet1", index=False)
        for name in ("Sheet2", "Sheet3"):
            pd.DataFrame().to_excel(writer, sheet_name=name, index=False)
    log = read_temperature_log(book)
    assert log.sensors == ("T1",) and log.notes == ()


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


def test_a_folder_given_as_a_log_is_said_to_be_a_folder(tmp_path):
    with pytest.raises(InputError, match=r": a folder, not a log file$"):
        read_temperature_log(tmp_path)


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


def test_a_name_split_by_the_delimiter_is_refused_by_every_reader(write_csv):
    """An unquoted name with the delimiter in it split the header in two: the room's readings were
    read under the name's second half ('channel 3)') and the room itself as a column with none."""
    from mtident.io.follow import LogFollower

    rows = "".join(f"{m},{20 + m / 100:.2f},20.0\n" for m in range(60))
    path = write_csv("time_min,Bearing (PT100, channel 3),room\n" + rows)
    said = (
        r"log\.csv: the header has 4 names and its data rows no more than 3 cells: the name "
        r"'Bearing \(PT100, channel 3\)' holds the delimiter ',', .* in double quotes"
    )
    with pytest.raises(InputError, match=said):
        read_temperature_log(path)
    with pytest.raises(InputError, match=said):
        LogFollower(path).poll()
    # quoted, it is one name; a last column no row fills (an event column) is left out with a note
    quoted = read_temperature_log(write_csv('time_min,"Bearing (PT100, channel 3)",room\n' + rows))
    assert quoted.sensors == ("Bearing (PT100, channel 3)", "room")
    events = read_temperature_log(write_csv("time_min,Bearing (PT100),room,event\n" + rows))
    assert events.sensors == ("Bearing (PT100)", "room") and "left out, no readings in them: event" in events.notes


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


@pytest.mark.parametrize("text", ["", "  \n\n"])
def test_an_empty_file_is_said_to_be_empty(write_csv, text):
    with pytest.raises(InputError, match=r"log\.csv: an empty file; a log is CSV text, a header line"):
        read_temperature_log(write_csv(text))
