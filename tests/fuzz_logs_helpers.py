"""Helpers that tests of more than one module share."""

from __future__ import annotations

import datetime as dt
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

SEED = 37


EXPORTS = 160


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
