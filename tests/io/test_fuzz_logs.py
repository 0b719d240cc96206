"""A fuzz run over the logger exports a user produces (issue 37's evidence): no traceback, and no
answer from a misread file.

A seeded generator writes one known warm-up (a few sensors rising to a known level, a room
sensor now and then) as logger programs export it: ``,`` ``;`` or tab between the cells, a decimal
point or comma, a units row or none, the time as minutes, seconds or hours (the unit said in the
name, in brackets, in words, in a units row, or not at all) or as time stamps in several formats
(a date and a clock in two columns, a time of day alone across midnight), UTF-8 with and without a
byte-order mark, cp1252 and UTF-16, °F and K with and without a stated unit, a half-written last
line, rows written twice, blank lines, a preamble, quoted names, a delimiter at each line's end,
CRLF. Each export is read as a user reads it: the library's ``read_temperature_log``, ``mtident
thermal inspect`` (table and ``--json``) and ``mtident thermal identify --json``. Whatever is read
must be the truth (minutes from the first reading, °C, within the rounding the export wrote), or
a note must say what is doubtful; what is not read must be refused in one line (exit 2), never a
traceback.
"""

from __future__ import annotations

import datetime as dt
import json
import math
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from click.testing import CliRunner

import mtident.cli_thermal as cli_thermal
from mtident.cli import main
from mtident.exceptions import InputError
from mtident.io.logs import OPEN_CIRCUIT_HIGH_C, OPEN_CIRCUIT_LOW_C, TemperatureLog, read_temperature_log

SEED = 37
EXPORTS = 160
# a sensor whose column does not rise (a room column taken for a machine sensor)
NO_RISE = "no warm-up to identify"
# identify's model-robust fit (the default method) takes about a second an export; the rest use lsq
ROBUST_EVERY = 40

_SENSOR_NAMES = (
    ("Spindle", "Spindel", "T_spindle", "Spindle bearing", "Spindellager vorne", "CH1", "T1"),
    ("Housing", "Gehäuse", "T_housing", "Spindle housing", "Spindelkasten", "CH2", "T2"),
    ("Motor", "Motor winding", "T_motor", "Motorflansch", "CH3", "T3"),
    ("Column top", "Ständer oben", "T_column", "Bett", "CH4", "T4", "Temp, Ständer"),
)
_ROOM_NAMES = ("Room", "Raum", "T_amb", "Ambient", "Hallentemperatur", "room air")
# how the temperature unit is written in a units row and in a name
_TEMPERATURE_UNIT_CELLS = {"C": ("°C", "degC", "[°C]", "C"), "F": ("°F", "degF", "[°F]", "F"), "K": ("K", "[K]")}
_TEMPERATURE_UNIT_IN_NAME = {
    "C": (" [°C]", " (°C)", " °C", "/°C"),
    "F": (" [°F]", " (°F)", " °F"),
    "K": (" [K]", " (K)"),
}
# a numeric time column's header, by how it states its unit; the units-row cell where one states it
_TIME_HEADERS = {
    "min": {
        "suffix": ("time_min", "t_min"),
        "brackets": ("Time [min]", "Zeit (min)"),
        "words": ("Time in minutes", "Minutes"),
        "none": ("Time", "t", "Zeit"),
    },
    "s": {
        "suffix": ("time_s", "t_s"),
        "brackets": ("Time [s]", "Zeit (s)", "Time (sec)"),
        "words": ("Seconds", "Elapsed seconds"),
        "none": ("Time", "t"),
    },
    "h": {"suffix": ("time_h",), "brackets": ("Time [h]", "Zeit (h)"), "words": ("Hours", "Elapsed hours"), "none": ()},
}
_TIME_UNIT_ROW_CELLS = {"min": ("min", "[min]", "minutes"), "s": ("s", "[s]", "sec"), "h": ("h", "[h]", "hours")}
_SECONDS_PER = {"min": 60.0, "s": 1.0, "h": 3600.0}
# time stamps: (format of the one column, or of the date and the clock in two), its header
_STAMPS = (
    ("%Y-%m-%dT%H:%M:%S", "Timestamp"),
    ("%Y-%m-%d %H:%M:%S", "Date/Time"),
    ("%Y-%m-%d %H:%M:%S.000", "Time"),
    ("%Y-%m-%dT%H:%M:%SZ", "time"),
    ("%Y-%m-%dT%H:%M:%S+01:00", "Zeitstempel"),
    ("%d.%m.%Y %H:%M:%S", "Datum/Uhrzeit"),
    ("%d.%m.%Y %H:%M", "Zeit"),
    ("%d.%m.%y %H:%M:%S", "Datum Zeit"),
    ("%m/%d/%Y %I:%M:%S %p", "Date Time"),
    ("%d/%m/%Y %H:%M:%S", "Date"),
    ("%d-%b-%Y %H:%M:%S", "DateTime"),
    ("%H:%M:%S", "Clock"),
    (("%d.%m.%Y", "%H:%M:%S"), ("Datum", "Uhrzeit")),
    (("%Y-%m-%d", "%H:%M:%S"), ("Date", "Time")),
)
_ENCODINGS = ("utf-8", "utf-8", "utf-8-sig", "cp1252", "cp1252", "utf-16", "utf-16-le")


@dataclass
class Export:
    """One logger export of a known warm-up, and what reading it must give."""

    kind: list[str]
    data: bytes
    # the truth, as the export wrote it: minutes from the first reading, and each column in °C; one
    # row more than the export holds whole (the row it cut short, which a reader may keep only whole)
    time_min: np.ndarray
    celsius: np.ndarray  # (N + 1, S)
    steady_C: np.ndarray  # (S,) each column's true level (°C)
    # words a note must hold where the readings are not the truth (a unit the export does not state)
    doubt: str | None = None
    # the export is broken so that it cannot be read (decimal commas in a comma-separated file)
    refuse: bool = False
    # it may be refused: quoted decimal commas in a comma-separated file
    may_refuse: bool = False
    rows: int = 0  # rows the export holds whole

    def describe(self) -> str:
        return ", ".join(self.kind)


def _pick(rng: np.random.Generator, options: Sequence[Any]) -> Any:
    return options[int(rng.integers(len(options)))]


def _number(value: float, decimals: int, decimal: str) -> str:
    text = f"{value:.{decimals}f}"
    return text.replace(".", ",") if decimal == "," else text


def make_export(rng: np.random.Generator) -> Export:
    """A warm-up of 2-4 sensors (and a room sensor now and then) written as one logger program might."""
    kind: list[str] = []
    n_sensors = int(rng.integers(2, 5))
    names = [_pick(rng, _SENSOR_NAMES[k]) for k in range(n_sensors)]
    room = bool(rng.random() < 0.4)
    if room:
        names.append(_pick(rng, _ROOM_NAMES))
        kind.append("room column")
    step_s = float(_pick(rng, (10.0, 30.0, 60.0, 60.0, 120.0)))
    rows = int(rng.integers(30, 121))
    t_s = step_s * np.arange(rows + 1)  # the last row is written only cut short (a file still being written)
    room_C = 20.0 + rng.uniform(-2, 3) + 0.3 * np.sin(t_s / 3000.0)
    levels, columns = [], []
    for _ in range(n_sensors):
        start = room_C[0] + rng.uniform(-0.3, 0.5)
        steady = start + rng.uniform(3.0, 15.0)
        tau_s = rng.uniform(15.0, 60.0) * 60.0
        levels.append(steady)
        columns.append(steady + (start - steady) * np.exp(-t_s / tau_s))
    if room:
        levels.append(float(np.mean(room_C)))
        columns.append(room_C)
    true_C = np.column_stack(columns)

    # the temperature unit and how it is stated
    unit = _pick(rng, ("C",) * 6 + ("F", "F", "K"))
    stated_by = _pick(rng, ("row", "name", "none")) if unit != "C" else _pick(rng, ("row", "name", "none", "none"))
    kind.append(f"°{unit}" if unit != "K" else "K")
    kind.append(f"temperature unit by {stated_by}")
    scale, offset = {"C": (1.0, 0.0), "F": (1.8, 32.0), "K": (1.0, 273.15)}[unit]
    decimals = int(_pick(rng, (1, 2, 2, 3)))
    written = np.round(true_C * scale + offset, decimals)
    celsius = (written - offset) / scale
    if stated_by == "name":
        suffix = _pick(rng, _TEMPERATURE_UNIT_IN_NAME[unit])
        names = [name + suffix for name in names]
    doubt = "far outside any workshop's range" if unit != "C" and stated_by == "none" else None

    # separator and decimal mark
    delimiter, decimal = _pick(
        rng, ((",", "."), (",", "."), (";", "."), (";", ","), (";", ","), ("\t", "."), ("\t", ","), (",", ","))
    )
    refuse = may_refuse = False
    quote_numbers = False
    if delimiter == "," and decimal == ",":
        quote_numbers = bool(rng.random() < 0.5)
        refuse = not quote_numbers and decimals > 0
        may_refuse = quote_numbers and decimals == 3  # 22,415 might be twenty-two thousand
        kind.append("decimal commas in a comma-separated file" + (", quoted" if quote_numbers else ""))
    kind.append({",": "comma", ";": "semicolon", "\t": "tab"}[delimiter] + f", decimal {decimal!r}")

    # the time column(s)
    time_kind = _pick(rng, ("min", "min", "s", "h", "stamp", "stamp", "stamp"))
    units_row = stated_by == "row" or bool(rng.random() < 0.25)
    time_unit_cell = ""
    if time_kind == "stamp":
        fmt, header = _pick(rng, _STAMPS)
        if ":%S" not in str(fmt) and step_s % 60:
            fmt, header = "%d.%m.%Y %H:%M:%S", "Datum/Uhrzeit"
        start = dt.datetime(
            2026, int(rng.integers(1, 13)), int(rng.integers(1, 29)), int(rng.integers(0, 24)), int(rng.integers(0, 60))
        )
        if fmt == "%H:%M:%S":  # a time of day alone: across midnight now and then
            start = start.replace(hour=int(_pick(rng, (7, 13, 22, 23))))
        stamps = [start + dt.timedelta(seconds=float(s)) for s in t_s]
        if isinstance(fmt, tuple):
            time_headers = list(header)
            time_cells = [[s.strftime(fmt[0]), s.strftime(fmt[1])] for s in stamps]
            unit_cells = ["", ""]
        else:
            time_headers = [header]
            time_cells = [[s.strftime(fmt)] for s in stamps]
            unit_cells = [_pick(rng, ("", "", "hh:mm:ss", "-"))]
        time_min = t_s / 60.0
        kind.append(f"stamps {fmt}")
    else:
        how = _pick(
            rng, tuple(h for h in ("suffix", "brackets", "words", "none", "row") if h != "none" or time_kind != "h")
        )
        if how == "row" and not units_row:
            units_row = True
        if how == "row":
            header = _pick(rng, _TIME_HEADERS[time_kind]["none"] or ("Time",))
            time_unit_cell = _pick(rng, _TIME_UNIT_ROW_CELLS[time_kind])
        else:
            header = _pick(rng, _TIME_HEADERS[time_kind][how])
            time_unit_cell = _pick(rng, _TIME_UNIT_ROW_CELLS[time_kind]) if units_row else ""
        per_unit = _SECONDS_PER[time_kind]
        t_decimals = {"min": 2, "s": 0, "h": 5}[time_kind]
        offset_s = float(_pick(rng, (0.0, 0.0, 120.0)))  # a log may start at a later time
        values = np.round((t_s + offset_s) / per_unit, t_decimals)
        time_cells = [[_number(v, t_decimals, decimal) if t_decimals else f"{v:.0f}"] for v in values]
        time_headers = [header]
        unit_cells = [time_unit_cell]
        time_min = (values - values[0]) * per_unit / 60.0
        if time_kind == "s" and how == "none" and not units_row:
            doubt = doubt or "is read as minutes"
        kind.append(f"time in {time_kind} ({how}{', units row' if units_row else ''})")
    if units_row:
        kind.append("units row")
        unit_cells = unit_cells + [
            _pick(rng, _TEMPERATURE_UNIT_CELLS[unit]) if unit != "C" or rng.random() < 0.8 else "" for _ in names
        ]
        if stated_by != "row" and unit != "C":  # a units row states the unit whatever the name says
            unit_cells[len(time_headers) :] = [_pick(rng, _TEMPERATURE_UNIT_CELLS[unit]) for _ in names]
            doubt = None if doubt == "far outside any workshop's range" else doubt

    cells = [[*time_cells[i], *(_number(v, decimals, decimal) for v in written[i])] for i in range(rows + 1)]

    def line(row: list[str], numbers: bool = False) -> str:
        quoted = [
            f'"{c}"' if (delimiter in c and not (numbers and refuse)) or (numbers and quote_numbers) else c for c in row
        ]
        return delimiter.join(quoted)

    header_cells = [*time_headers, *names]
    quote_header = bool(rng.random() < 0.2)
    header_line = delimiter.join(f'"{c}"' for c in header_cells) if quote_header else line(header_cells)
    if quote_header:
        kind.append("quoted header")
    text_lines: list[str] = []
    if rng.random() < 0.15:
        text_lines += ["# exported by LogView 3.2", "# channels: " + " ".join(names)]
        kind.append("# preamble")
    if delimiter != "," and rng.random() < 0.1:
        text_lines.append(f"sep={delimiter}")
        kind.append("sep= line")
    text_lines.append(header_line)
    if units_row:
        text_lines.append(line(unit_cells))
    if rng.random() < 0.05:
        text_lines.append("")
        kind.append("a blank line under the header")
    data_lines = [line(c, numbers=True) for c in cells[:rows]]
    # rows written twice (a buffer flushed again) and blank lines between rows: the truth is unchanged
    if rng.random() < 0.25:
        twice = sorted(set(int(r) for r in rng.integers(1, rows - 1, size=int(rng.integers(1, 4)))))
        for r in reversed(twice):
            data_lines.insert(r + 1, data_lines[r])
        kind.append(f"{len(twice)} row(s) written twice")
    if rng.random() < 0.2:
        for _ in range(int(rng.integers(1, 4))):
            data_lines.insert(int(rng.integers(1, len(data_lines))), "")
        kind.append("blank lines")
    trailing = delimiter != "\t" and bool(rng.random() < 0.1)
    if trailing:
        data_lines = [d + delimiter if d else d for d in data_lines]
        kind.append("a delimiter at each row's end")
    text_lines += data_lines
    newline = _pick(rng, ("\n", "\n", "\r\n"))
    if newline == "\r\n":
        kind.append("CRLF")
    text = newline.join(text_lines) + newline
    ending = _pick(rng, ("whole", "whole", "whole", "cut", "cut", "no line end", "blank lines at the end"))
    if ending == "cut":  # a file still being written: the next row cut anywhere after its first character
        extra = line(cells[rows], numbers=True)
        text += extra[: int(rng.integers(1, len(extra)))]
        kind.append("a half-written last line")
    elif ending == "no line end":
        text = text.removesuffix(newline)
        kind.append("no line end after the last row")
    elif ending == "blank lines at the end":
        text += newline * 2
        kind.append("blank lines at the end")
    encoding = _pick(rng, _ENCODINGS)
    kind.append(encoding)
    data = text.encode(encoding)
    if ending == "cut" and encoding.startswith("utf-16") and rng.random() < 0.5:
        data = data[:-1]  # cut inside a character
        kind.append("cut inside a UTF-16 character")
    return Export(
        kind, data, time_min, celsius, np.array(levels), doubt=doubt, refuse=refuse, may_refuse=may_refuse, rows=rows
    )


def exports(count: int = EXPORTS, seed: int = SEED) -> Iterator[Export]:
    rng = np.random.default_rng(seed)
    for _ in range(count):
        yield make_export(rng)


# ---------------------------------------------------------------------------------------------
# what a reading must give


def _misread(export: Export, time_min: np.ndarray, celsius: np.ndarray) -> str | None:
    """What is wrong with readings against the truth, or None: the rows the export holds whole (and
    the cut one only where it was read whole), each time and each reading as written."""
    n = len(time_min)
    if n not in (export.rows, export.rows + 1):
        return f"{n} rows read of {export.rows}"
    if celsius.shape != (n, export.celsius.shape[1]):
        return f"readings of shape {celsius.shape}, not {(n, export.celsius.shape[1])}"
    if not np.allclose(time_min, export.time_min[:n], rtol=0, atol=1e-6):
        k = int(np.argmax(~np.isclose(time_min, export.time_min[:n], rtol=0, atol=1e-6)))
        return f"time at row {k}: {time_min[k]:g} min, not {export.time_min[k]:g}"
    wrong = ~np.isclose(celsius, export.celsius[:n], rtol=0, atol=1e-6)
    if wrong.any():
        k, j = (int(i[0]) for i in np.nonzero(wrong))
        return f"column {j} at row {k}: {celsius[k, j]:.6g} °C, not {export.celsius[k, j]:.6g}"
    return None


def _check_log(export: Export, log: TemperatureLog, where: str) -> list[str]:
    wrong = _misread(export, log.time_min, log.temperature_C)
    if wrong is None:
        return []
    if export.doubt is not None and any(export.doubt in note for note in log.notes):
        return []  # read as written, and said to be doubtful
    return [f"{where}: misread without a word ({wrong}); notes: {list(log.notes)}"]


@dataclass(frozen=True)
class Outcome:
    code: int
    stdout: str
    stderr: str


def _run(*args: str) -> Outcome:
    result = CliRunner().invoke(main, list(args), catch_exceptions=False)
    return Outcome(result.exit_code, result.stdout, result.stderr)


def _check_refusal(out: Outcome, where: str) -> list[str]:
    """A command that gives no answer must say why in one line, with exit code 1 or 2."""
    said = [line for line in out.stderr.splitlines() if line.startswith("mtident: error:")]
    if out.code not in (1, 2) or len(said) != 1 or "Traceback" in out.stderr + out.stdout:
        return [f"{where}: exit {out.code} without a one-line error: {out.stderr[-400:]!r}"]
    return []


@contextmanager
def _logs_read() -> Iterator[list[TemperatureLog]]:
    """The logs the commands read, as their fits get them."""
    read: list[TemperatureLog] = []
    original = cli_thermal.load_log

    def recording(*args: Any, **kwargs: Any) -> TemperatureLog:
        log = original(*args, **kwargs)
        read.append(log)
        return log

    cli_thermal.load_log = recording
    try:
        yield read
    finally:
        cli_thermal.load_log = original


def check_export(export: Export, path: Path, robust: bool = False) -> tuple[list[str], bool]:
    """The problems reading ``export`` (written at ``path``) shows, and whether it was read."""
    problems: list[str] = []
    try:
        log = read_temperature_log(path)
    except InputError as exc:
        log = None
        if not (export.refuse or export.may_refuse):
            problems.append(f"read_temperature_log refused a sane export: {exc}")
    else:
        if export.refuse:
            problems.append("read_temperature_log read an export it must refuse")
        problems += _check_log(export, log, "read_temperature_log")
    read = log is not None

    table = _run("thermal", "inspect", str(path))
    out = _run("thermal", "inspect", str(path), "--json")
    if out.code != table.code:
        problems.append(f"inspect: exit {table.code} for the table, {out.code} for --json")
    if out.code == 0:
        if not read:
            problems.append("inspect read what read_temperature_log refused")
        info = json.loads(out.stdout)
        n = info["time"]["samples"]
        notes = info["notes"]
        wrong = None if n in (export.rows, export.rows + 1) else f"{n} samples of {export.rows}"
        if wrong is None and not math.isclose(info["time"]["span_min"], export.time_min[n - 1], abs_tol=1e-6):
            wrong = f"a span of {info['time']['span_min']:g} min, not {export.time_min[n - 1]:g}"
        for j, sensor in enumerate(info["sensors"] if wrong is None else []):
            truth = export.celsius[:n, j]
            for key, value in (
                ("first_C", truth[0]),
                ("last_C", truth[-1]),
                ("min_C", truth.min()),
                ("max_C", truth.max()),
            ):
                if sensor[key] is None or not math.isclose(sensor[key], value, abs_tol=1e-6):
                    wrong = f"{sensor['sensor']!r} {key} {sensor[key]}, not {value:.6g}"
        if wrong is not None and not (export.doubt is not None and any(export.doubt in note for note in notes)):
            problems.append(f"inspect --json: misread without a word ({wrong}); notes: {notes}")
    else:
        problems += _check_refusal(out, "inspect --json") + _check_refusal(table, "inspect")
        if read:
            problems.append("inspect refused what read_temperature_log read")

    method = () if robust else ("--method", "lsq")
    with _logs_read() as logs:
        out = _run("thermal", "identify", str(path), "--json", *method)
    if out.code == 0:
        problems += _check_log(export, logs[0], "identify")
        answer = json.loads(out.stdout)
        doubted = export.doubt is not None and export.doubt in out.stderr
        if _misread(export, logs[0].time_min, logs[0].temperature_C) is not None and not doubted:
            problems.append(f"identify: answered from a misread log without a warning: {out.stderr[-300:]!r}")
        for summary in answer.get("sensors", [answer]):
            level = float(export.steady_C[logs[0].sensors.index(summary["sensor"])])
            lo, hi = summary["steady_state_ci95_C"]
            if not summary["model_ok"] or doubted:
                continue
            if NO_RISE in " ".join(summary["warnings"]):
                continue  # a flat column's trusted nonsense: test_a_flat_columns_absurd_answer_is_not_trusted
            # an answer trusted from readings that are the truth must be one physics allows (whether its
            # interval covers the truth is the fits' matter: test_thermal, test_robust)
            if lo is None or hi is None or lo < OPEN_CIRCUIT_LOW_C or hi > OPEN_CIRCUIT_HIGH_C:
                problems.append(
                    f"identify: {summary['sensor']!r} trusted T∞ {summary['steady_state_C']:.2f} °C [{lo}, {hi}], "
                    f"the truth {level:.2f}"
                )
    else:
        problems += _check_refusal(out, "identify")
    return problems, read


# ---------------------------------------------------------------------------------------------
# the fuzz run


@pytest.mark.parametrize("part", range(8))
def test_logger_exports_are_read_right_or_refused_in_one_line(tmp_path, part):
    """Each eighth of the exports (the parts run on the suite's workers): read by the library, by
    inspect and by identify, the readings are the truth or a note says what is doubtful; what is
    not read is refused in one line; the exports that can be read are read."""
    problems, read, checked = [], 0, 0
    for k, export in enumerate(exports()):
        if k % 8 != part:
            continue
        path = tmp_path / f"export{k}.csv"
        path.write_bytes(export.data)
        try:
            found, was_read = check_export(export, path, robust=k % ROBUST_EVERY == part)
        except Exception as exc:  # a traceback: the export that raised it, and the exception
            raise AssertionError(f"export {k} ({export.describe()}) raised {type(exc).__name__}: {exc}") from exc
        problems += [f"export {k} ({export.describe()}): {p}" for p in found]
        read += was_read
        checked += 1
    assert not problems, "\n".join(problems)
    assert checked == EXPORTS // 8 and read >= 0.75 * checked, (read, checked)


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


# ---------------------------------------------------------------------------------------------
# what the fuzz found


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


def test_a_flat_columns_absurd_answer_is_not_trusted(write_csv):
    # a room column in 0.1 °C steps: 19.8 °C for 17 min, then 19.9 (fuzz export 80)
    rows = "".join(
        f"{m},{20 + 8 * (1 - np.exp(-m / 40)):.2f},{19.8 + 0.1 * (m >= 17) + 0.1 * (m >= 37):.1f}\n" for m in range(60)
    )
    out = _run("thermal", "identify", str(write_csv("time_min,Spindle,Room\n" + rows)), "--json", "--method", "lsq")
    room = json.loads(out.stdout)["sensors"][1]
    lo, hi = room["steady_state_ci95_C"]
    assert not room["model_ok"] or (lo is not None and hi is not None and -60 <= lo and hi <= 400), room


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
