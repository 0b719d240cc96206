"""Temperature logs: CSV with one time column and one column per sensor.

The time column is the first one unless ``time_col`` names another. Its unit is
minutes unless ``time_unit`` says otherwise or the header ends in ``_s``,
``_min`` or ``_h``; ISO-8601 timestamps are read as such, and so are dotted
day-first ones (``22.11.2026 08:00:00``) and times of day. Temperatures are °C
unless a units row or a column's name says K or °F, or ``temperature_unit`` does
for the columns that state no unit.
The file may be comma-, semicolon- or tab-separated, with a decimal comma, a
``#`` preamble and cp1252 text (:mod:`mtident.io.dialect`), or an Excel
workbook, read as the CSV it holds.

Its layout is fixed as the live follower fixes it (:class:`~mtident.io.layout.LogLayout`),
and its lines become rows through the follower's entry point
(:func:`~mtident.io.parse.parse_lines`), read as a whole log: what the follower
passes over with a warning is an error here. The whole log's time column is read
as one column (:mod:`mtident.io.whole`), the follower's row by row; the two share
the layout, the cells (:mod:`mtident.io.cells`) and the time stamps' rules
(:mod:`mtident.io.stamps`), not one loop.

A pandas DataFrame (a notebook's table, its time as a column or as the index)
is read the same way, as the CSV text it would be written as.

Everything that can be wrong with a user's file is reported as an
:class:`~mtident.exceptions.InputError` naming the file, the column and the row.
Isolated bad samples (an empty or NaN cell, an open-circuit reading) are
replaced by NaN — the filters treat NaN as a missing measurement — and listed in
``TemperatureLog.notes`` so the CLI can say so on stderr.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.io.cells import OPEN_CIRCUIT_HIGH_C, OPEN_CIRCUIT_LOW_C, empty_cell, iter_rows
from mtident.io.columns import check_unique_names, missing_column, room_named, temperature_columns
from mtident.io.dialect import CsvDialect
from mtident.io.layout import LogLayout, time_columns
from mtident.io.log_file import read_lines
from mtident.io.parse import TimeState, WholeLog, parse_lines
from mtident.io.time_notes import read_as_minutes
from mtident.io.units import celsius_conversion, is_number, number_without_unit, stated_temperature_unit
from mtident.io.whole import MAX_BAD_FRACTION

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "TemperatureLog",
    "read_temperature_log",
    "sample_log_path",
    "as_temperature_log",
    "SAMPLES",
    "unit_doubted",
    "OPEN_CIRCUIT_HIGH_C",
    "OPEN_CIRCUIT_LOW_C",
    "scale_note",
    "WORKSHOP_ROOM_C",
]


@dataclass(frozen=True)
class TemperatureLog:
    """A validated warm-up log.

    Attributes
    ----------
    time_min : ndarray, shape (N,)
        Minutes since the first sample, strictly increasing.
    sensors : tuple of str
        Sensor (column) names.
    temperature_C : ndarray, shape (N, S)
        Temperatures, NaN where a sample was rejected.
    notes : tuple of str
        What was skipped and why (for stderr).
    source : str
        Where the log came from.
    time_column : str
        The column the time was read from ("Date + Time" for a date and a time of day
        in two columns); "" where not known.
    """

    time_min: FloatArray
    sensors: tuple[str, ...]
    temperature_C: FloatArray
    notes: tuple[str, ...] = field(default=())
    source: str = ""
    time_column: str = ""

    def __post_init__(self) -> None:
        # a log built by hand reaches the fits without the readers' checks: times that go back gave
        # a wrong T∞ with no word, a transposed array an IndexError deep inside
        if isinstance(self.sensors, str):
            msg = f"TemperatureLog: sensors must be a sequence of names, not one string (for one: ({self.sensors!r},))"
            raise InputError(msg)
        try:
            time_min = np.asarray(self.time_min, dtype=float)
            values = np.asarray(self.temperature_C, dtype=float)
        except (TypeError, ValueError) as exc:
            msg = f"TemperatureLog: time_min and temperature_C must be numbers ({exc})"
            raise InputError(msg) from None
        names = tuple(self.sensors)
        if time_min.ndim != 1:
            msg = f"TemperatureLog: time_min must be one-dimensional (N,), not of shape {time_min.shape}"
            raise InputError(msg)
        if values.shape != (len(time_min), len(names)):
            msg = (
                f"TemperatureLog: temperature_C must have shape (N, S) = ({len(time_min)}, {len(names)}) for "
                f"{len(time_min)} times and the sensors {', '.join(names) or '(none)'}, not {values.shape}"
                + (" (transposed?)" if values.shape == (len(names), len(time_min)) else "")
            )
            raise InputError(msg)
        if not np.isfinite(time_min).all():
            msg = f"TemperatureLog: time_min holds a non-finite time at row {int(np.argmax(~np.isfinite(time_min)))}"
            raise InputError(msg)
        if len(time_min) > 1 and (back := np.flatnonzero(np.diff(time_min) <= 0)).size:
            k = int(back[0]) + 1
            msg = (
                f"TemperatureLog: time_min must increase strictly; t[{k}] = {time_min[k]:g} min follows t[{k - 1}] = "
                f"{time_min[k - 1]:g} min"
            )
            raise InputError(msg)
        object.__setattr__(self, "time_min", time_min)
        object.__setattr__(self, "temperature_C", values)
        object.__setattr__(self, "sensors", names)

    def __repr__(self) -> str:
        names = ", ".join(self.sensors if len(self.sensors) <= 6 else [*self.sensors[:5], "...", self.sensors[-1]])
        span = f"{self.time_min[0]:g}-{self.time_min[-1]:g} min" if len(self.time_min) else "no samples"
        return (
            f"TemperatureLog({self.source!r}: {len(self.sensors)} sensor(s) ({names}), {len(self.time_min)} samples "
            f"over {span}, {len(self.notes)} note(s))"
        )

    def select(self, names: list[str] | None) -> TemperatureLog:
        """The same log restricted to ``names`` (all sensors if None or ["all"]).

        Parameters
        ----------
        names : list of str or None
            Sensor columns to keep, in the order wanted; None, [] or ["all"] keeps every sensor. A name
            that is no sensor column raises InputError.

        Returns
        -------
        TemperatureLog
            The same times, notes and source, with those sensors' columns alone, in the order of ``names``.
        """
        if not names or names == ["all"]:
            return self
        missing = [n for n in names if n not in self.sensors]
        if missing:
            msg = missing_column(self.source, missing[0], self.sensors)
            raise InputError(msg)
        idx = [self.sensors.index(n) for n in names]
        return TemperatureLog(
            self.time_min, tuple(names), self.temperature_C[:, idx], self.notes, self.source, self.time_column
        )

    def split_room(self, room: str) -> tuple[TemperatureLog, FloatArray]:
        """The sensors without the room sensor's column, and that column's readings: the room is
        an input of every sensor's modes, not a sensor (``identify_robust``, ``learn_reference``
        and ``monitor_step`` take it apart).

        Parameters
        ----------
        room : str
            The room sensor's column.

        Returns
        -------
        sensors : TemperatureLog
            The log without the room column.
        room_C : ndarray, shape (N,)
            The room's readings (°C, NaN where missing).

        Raises
        ------
        InputError
            No such column, or no sensor column besides it.
        """
        room_C = self.select([room]).temperature_C[:, 0]
        names = [name for name in self.sensors if name != room]
        if not names:
            msg = f"{self.source}: no sensor column left besides the room column {room!r}"
            raise InputError(msg)
        return self.select(names), room_C

    def window(self, minutes: float) -> int:
        """Number of samples with time ≤ ``minutes``.

        Parameters
        ----------
        minutes : float
            End of the window (min since the first sample).

        Returns
        -------
        int
            How many of the first samples lie within it: ``time_min[:n]`` is the window.
        """
        return int(np.searchsorted(self.time_min, minutes + 1e-9, side="right"))


# The logs shipped in the package (scripts/make_sample_warmup.py), by the names the CLI and
# read_temperature_log take: the 10-sensor warm-up, and the same with a room sensor column "room".
SAMPLES = {
    "@sample": "spindle_warmup.csv",
    "@sample-room": "spindle_warmup_room.csv",
    "@sample-machine": "spindle_machine.toml",
}


def sample_log_path(name: str = "@sample") -> Path:
    """A file shipped in the package, by its @-name: the logs @sample and @sample-room, and
    @sample-machine, the reference run of the sample's machine.

    Parameters
    ----------
    name : str, optional
        "@sample" (a spindle warm-up log), "@sample-room" (the same with a room sensor) or
        "@sample-machine" (its reference run, TOML).

    Returns
    -------
    Path
        The file inside the installed package.

    Raises
    ------
    InputError
        ``name`` is none of these.
    """
    from importlib import resources

    if name not in SAMPLES:
        msg = f"no shipped log {name!r}; there are: {', '.join(SAMPLES)}"
        raise InputError(msg)
    return Path(str(resources.files("mtident") / "data" / SAMPLES[name]))


# A workshop's air (°C), heated or not: a room read far outside it is more likely in °F or K
WORKSHOP_ROOM_C = (5.0, 40.0)


def unit_doubted(log: TemperatureLog) -> bool:
    """Whether the reader of ``log`` said its time column, read as minutes for want of a unit, may
    be in another unit (:mod:`mtident.io.time_notes`: ``seconds_hint``, ``sparse_hint``, ``hours_hint``).

    Parameters
    ----------
    log : TemperatureLog

    Returns
    -------
    bool
    """
    said = read_as_minutes(log.time_column)
    return any(note.startswith(said) for note in log.notes)


def read_temperature_log(
    path: str | Path | pd.DataFrame,
    time_col: str | None = None,
    time_unit: str | None = None,
    min_samples: int = 5,
    sensors: list[str] | None = None,
    temperature_unit: str | None = None,
    max_bad_fraction: float = MAX_BAD_FRACTION,
    sheet: str | int | None = None,
) -> TemperatureLog:
    """Read and validate a CSV temperature log.

    Parameters
    ----------
    path : str, Path or pandas.DataFrame
        The CSV file, or a table already in memory (a notebook's DataFrame),
        with the same columns; it is checked the same way. "@sample" and
        "@sample-room" name the logs shipped in the package.
    time_col : str, optional
        Name of the time column (default: the first column).
    time_unit : {"s", "min", "h"}, optional
        Unit of a numeric time column (default: from the header suffix, else minutes).
    min_samples : int
        Fewest samples accepted.
    sensors : list of str, optional
        The sensor columns to read and validate, in this order (default: all).
        A dead sensor that is not asked for does not stop the others.
    temperature_unit : {"C", "F", "K"}, optional
        Unit of the temperature columns that state none of their own (no units
        row, no unit in the name); default: °C. A column whose own unit is
        another temperature unit is refused.
    max_bad_fraction : float
        The largest share of a sensor's samples that may be bad (empty, NaN, open circuit): a
        sensor with more is refused (1 to describe a log whatever its sensors read).
    sheet : str or int, optional
        An Excel workbook's sheet to read: its name, or its number from 1 (default: the first sheet
        that holds a table; where the workbook has others, a note says which was read and which not).

    Returns
    -------
    TemperatureLog

    Raises
    ------
    InputError
        Missing or unreadable file, no such column, no sensor column, non-numeric
        cells, time not increasing or duplicated, too few samples, too many bad
        samples in a sensor, a column's own unit that ``temperature_unit``
        contradicts, a workbook without the sheet ``sheet`` (the message names its sheets), or
        ``sheet`` given for a log that is no workbook.
    """
    if isinstance(sensors, str):  # one name, not its letters ("no sensor column 'T'")
        sensors = [sensors]
    if not (isinstance(min_samples, int) and min_samples >= 1):
        msg = f"min_samples must be a whole number, 1 or more, not {min_samples!r}"
        raise InputError(msg)
    if not (isinstance(max_bad_fraction, (int, float)) and 0.0 <= max_bad_fraction <= 1.0):
        msg = f"max_bad_fraction must be a share between 0 and 1, not {max_bad_fraction!r}"
        raise InputError(msg)
    read_notes: list[str] = []
    table = _as_table(path, read_notes, sheet)
    notes: list[str] = [renamed] if (renamed := table.dialect.renaming()) else []
    notes.extend(read_notes)
    layout = _layout(table, time_col, time_unit, min_samples, sensors, temperature_unit, notes)
    whole = WholeLog(table.first_row, max_bad_fraction)
    _, rows = parse_lines(layout, TimeState(), table.lines, table.source, whole=whole)
    notes.extend(rows.notes)
    if odd := another_unit_error(
        list(layout.sensors), rows.temperature_C, table.dialect, table.source, temperature_unit
    ):
        raise InputError(odd)
    scale = scale_note(list(layout.sensors), rows.temperature_C, table.dialect, temperature_unit)
    clock = "" if layout.clock_column is None else f" + {layout.header[layout.clock_column]}"
    return TemperatureLog(
        rows.time_min,
        layout.sensors,
        rows.temperature_C,
        (*notes, *([] if scale is None else [scale])),
        table.source,
        layout.time_name + clock,
    )


def _layout(
    table: _LogTable,
    time_col: str | None,
    time_unit: str | None,
    min_samples: int,
    sensors: list[str] | None,
    temperature_unit: str | None,
    notes: list[str],
) -> LogLayout:
    """The layout of a whole log: its time columns by its first row, the sensors asked for, or
    every temperature column but those without a number or a reading in all the rows; how the
    columns were taken goes to ``notes``."""
    dialect, source = table.dialect, table.source
    names = [table.header[k] for k in table.columns]
    first = next(iter_rows(table.lines, dialect, len(table.header)), None)
    first_cells = [] if first is None else [first[k].strip() for k in table.columns]
    (at, clock_at, milliseconds_at), left_out, time_notes = time_columns(names, first_cells, dialect, time_col, source)
    notes.extend(time_notes)
    if len(table.lines) < max(min_samples, 1):
        msg = f"{source}: {len(table.lines)} samples; at least {max(min_samples, 1)} are needed"
        raise InputError(msg)
    available = [c for c in names if c not in left_out]
    missing_names = [n for n in sensors or [] if n not in available]
    if missing_names:
        msg = missing_column(source, missing_names[0], available)
        raise InputError(msg)
    if not sensors:
        available = _sensor_candidates(table, available, notes)
    chosen, unit_notes = temperature_columns(
        list(sensors) if sensors else available, bool(sensors), dialect, source, temperature_unit
    )
    notes.extend(unit_notes)
    return LogLayout(
        dialect,
        table.header,
        table.columns[at],
        None if clock_at is None else table.columns[clock_at],
        None if milliseconds_at is None else table.columns[milliseconds_at],
        tuple(chosen),
        tuple(table.header.index(name) for name in chosen),
        time_unit,
        temperature_unit,
    )


_START_AGREES_C = 5.0
"""A column converted from °F or K that starts within this of the others' start (°C) is likely in
that unit."""


def another_unit_error(
    sensors: list[str], values: FloatArray, dialect: CsvDialect, source: str | Path, temperature_unit: str | None = None
) -> str | None:
    """Why a log cannot be read as it is, where a column read as °C for want of a stated unit starts
    far above any workshop's range while the others start in it, and converted from °F (or K) would
    start with them: a log with one sensor in °F (T3 starting at 68) was read as °C, and a stop with its
    T∞ of 71.6 °C trusted, the column's unit said only in a note. None where the user stated a unit
    (``temperature_unit``: every column without one of its own is in it) or no column reads so.

    Parameters
    ----------
    sensors : list of str
        The sensor columns' names.
    values : ndarray, shape (N, S)
        Their readings as read (°C where a unit was stated, else the numbers as written; NaN: missing).
    dialect : CsvDialect
        The log's dialect, which says which columns state their unit.
    source : str or Path
        The log, named in the message.
    temperature_unit : str or None, optional
        The unit the user stated for the columns without one.

    Returns
    -------
    str or None
        The message of the error to raise.
    """
    low, high = WORKSHOP_ROOM_C
    assumed = (
        []
        if stated_temperature_unit(temperature_unit) is not None
        else [k for k, name in enumerate(sensors) if not dialect.unit_of(name).strip()]
    )
    first = np.array([_first_valid(values[:, k]) for k in range(values.shape[1])])
    usual = [k for k in range(len(sensors)) if low <= first[k] <= high]
    if not usual:
        return None
    start = float(np.median(first[usual]))
    odd, named = [], ""
    for k in assumed:
        for unit, celsius in (("°F", (first[k] - 32.0) / 1.8), ("K", first[k] - 273.15)):
            if first[k] > high and abs(celsius - start) <= _START_AGREES_C:
                odd.append(f"{sensors[k]!r} starts at {first[k]:g} (in {unit}: {celsius:.1f} °C)")
                named = named or f"{sensors[k]} [{unit}]"
    if not odd:
        return _own_unit_error(sensors, values, dialect, source, first, start)
    return (
        f"{source}: the log states no unit, so its readings would be taken as °C, but {'; '.join(odd)}, where the "
        f"other columns start near {start:.1f} °C. State the column's unit, and it is converted: a units row under "
        f"the header or the unit in its name ({named}); or, if every column is in °C, say so "
        "(`temperature_unit='C'`)"
    )


def _own_unit_error(
    sensors: list[str], values: FloatArray, dialect: CsvDialect, source: str | Path, first: FloatArray, start: float
) -> str | None:
    """Why a log cannot be read as it is, where a column converted from the unit the log states for it
    starts far below any workshop's range, and as written would start with the others (near
    ``start``, °C): a units row of °F over a column in °C put a sensor at −6.7 °C beside 20 °C ones,
    without a word."""
    low, _ = WORKSHOP_ROOM_C
    odd = []
    for k, name in enumerate(sensors):
        unit = dialect.unit_of(name).strip()
        conversion = celsius_conversion(unit) if unit else None
        if conversion is None or conversion == (1.0, 0.0) or not first[k] < low:
            continue
        written = (first[k] - conversion[1]) / conversion[0]
        if abs(written - start) <= _START_AGREES_C:
            odd.append(f"{name!r} is in {unit} by {dialect.units_source}, which starts it at {first[k]:.1f} °C")
    if not odd:
        return None
    return (
        f"{source}: {'; '.join(odd)}, where the other columns start near {start:.1f} °C, as it does read as "
        "written: if it is in °C, mend its unit in the log"
    )


def _first_valid(column: FloatArray) -> float:
    valid = column[np.isfinite(column)]
    return float(valid[0]) if len(valid) else math.nan


def scale_note(
    sensors: list[str], values: FloatArray, dialect: CsvDialect, temperature_unit: str | None = None
) -> str | None:
    """What a reader says when columns read as °C for want of a stated unit read far outside any
    workshop's range (``WORKSHOP_ROOM_C``): a column named as the room (:func:`room_named`), or
    every column above the range's top (at a warm-up's start the machine is near the room). A log in
    °F (a room at 69) or K was taken as °C without a word. Where the user stated °F or K
    (``temperature_unit``) and the converted readings read so far outside (a room at −6.7 °C, every
    column below the range's bottom), the note asks whether the log was in °C already: a log in °C
    read as °F had its room at −6.7 °C and a bearing's T∞ at 0.03 °C trusted. None otherwise.

    Parameters
    ----------
    sensors : list of str
        The sensor columns' names.
    values : ndarray, shape (N, S)
        Their readings as read (°C where a unit was stated, else the numbers as written; NaN: missing).
    dialect : CsvDialect
        The log's dialect, which says which columns state their unit.
    temperature_unit : str or None, optional
        The unit the user stated for the columns without one: none of them is then assumed.

    Returns
    -------
    str or None
    """
    low, high = WORKSHOP_ROOM_C
    stated = stated_temperature_unit(temperature_unit)
    if stated == "°C":
        return None
    assumed = [k for k, name in enumerate(sensors) if not dialect.unit_of(name).strip()]
    spans = {}
    for k in assumed:
        valid = values[:, k][np.isfinite(values[:, k])]
        if len(valid):
            spans[k] = (float(np.min(valid)), float(np.median(valid)), float(np.max(valid)))
    rooms = [k for k in spans if room_named(sensors[k]) and not low <= spans[k][1] <= high]
    every = spans and len(spans) == len(sensors)
    if rooms:
        which = (
            "; ".join(f"{sensors[k]!r} reads {spans[k][0]:.4g} to {spans[k][2]:.4g}" for k in rooms) + " as the room"
        )
    elif every and stated is None and all(span[0] > high for span in spans.values()):
        which = (
            f"every column reads above {high:g} °C (the lowest {min(span[0] for span in spans.values()):.4g}), "
            "none near the room"
        )
    elif every and stated is not None and all(span[2] < low for span in spans.values()):
        which = f"every column reads below {low:g} °C (the highest {max(span[2] for span in spans.values()):.3g})"
    else:
        return None
    if stated is not None:
        return (
            f"readings converted from {stated} as stated (`temperature_unit='{temperature_unit}'`), "
            f"but {which}: far outside any workshop's range ({low:g} to {high:g} °C). If the log is in °C already, "
            "leave the unit out"
        )
    return (
        f"readings taken as °C (the log states no unit), but {which}: far outside any workshop's range "
        f"({low:g} to {high:g} °C). If the log is in °F (or K), state the unit and it is converted: "
        "`temperature_unit='F'` (or `temperature_unit='K'`), a units row under the header (min;°F;°F) or the unit "
        "in the column names (Room [°F])"
    )


@dataclass(frozen=True, slots=True)
class _LogTable:
    """A log as lines of text, as the file reader takes it.

    Attributes
    ----------
    dialect : CsvDialect
        How the lines are written.
    header : tuple of str
        The columns' names, in order ("Unnamed: 3" for one without a name).
    columns : tuple of int
        The columns read, by position: all but those without a name and without a cell (a
        delimiter at the end of every line).
    lines : list of str
        The data lines, blank ones left out.
    source : str
        The log's name in messages.
    first_row : int
        The number messages give the first data line.
    """

    dialect: CsvDialect
    header: tuple[str, ...]
    columns: tuple[int, ...]
    lines: list[str]
    source: str
    first_row: int


def _as_table(path: str | Path | pd.DataFrame, notes: list[str], sheet: str | int | None = None) -> _LogTable:
    """The log as lines with its column names; what the file's reader left out goes to ``notes``
    (a cut last line, a workbook's sheets not read)."""
    import sys

    pandas = sys.modules.get("pandas")  # a DataFrame can come only where pandas was imported
    if pandas is not None and isinstance(path, pandas.DataFrame):
        if sheet is not None:
            msg = f"`sheet='{sheet}'` names a sheet of an Excel workbook; a DataFrame has none: leave it out"
            raise InputError(msg)
        table = _frame_table(path)
    else:
        if not isinstance(path, (str, Path)):
            msg = (
                f"a log is read from a file's path or a pandas DataFrame (time column first, a column per sensor), "
                f"not {type(path).__name__}"
            )
            raise InputError(msg)
        if isinstance(path, str) and path in SAMPLES:
            path = sample_log_path(path)
        table = _file_table(path, notes, sheet)
    if len(table.columns) < 2:
        msg = (
            f"{table.source}: need a time column and at least one sensor column, separated by ',', ';' or tabs; found "
            f"columns: {', '.join(table.header[k] for k in table.columns)}"
        )
        raise InputError(msg)
    return table


def log_name(path: str | Path, sheet: str = "") -> str:
    """A log's name in messages and titles: the file as given, and the sheet of a workbook of several.

    Parameters
    ----------
    path : str or Path
    sheet : str, optional
        The sheet read ("" for CSV text, or a workbook of one sheet).

    Returns
    -------
    str
        ``"log.xlsx, sheet 'Run 2'"``, or the path alone.
    """
    return f"{path}, sheet {sheet!r}" if sheet else str(path)


def _file_table(path: str | Path, notes: list[str], sheet: str | int | None = None) -> _LogTable:
    """A CSV file (or an Excel workbook's sheet, as the CSV it holds) as a table."""
    lines, dialect = read_lines(path, notes, sheet)
    if not lines:
        msg = (
            f"{path}: an empty file; a log is CSV text, a header line (a time column and a column per sensor) and "
            "a line per reading"
        )
        raise InputError(msg)
    written = dialect.cells(lines[0])
    distinct = _distinct([name or f"Unnamed: {k}" for k, name in enumerate(written)])
    # a second row of names names the channels where it names them otherwise
    renamed = {k: name for k, name in enumerate(dialect.names) if name != dialect.written_names[k]}
    header = tuple(renamed.get(k, name) for k, name in enumerate(distinct))
    data = [line for line in lines[1 + dialect.extra_rows :] if line.strip()]
    if not data:
        msg = f"{path}: no data rows, only a header or a logger's preamble (is the test still to start?)"
        raise InputError(msg)
    unnamed = [k for k, name in enumerate(header) if name.startswith("Unnamed: ")]
    written_in = _columns_written(data, dialect, len(header), unnamed)
    columns = tuple(k for k in range(len(header)) if k not in unnamed or k in written_in)
    return _LogTable(dialect, header, columns, data, log_name(path, dialect.sheet), 1 + dialect.head_lines)


def _distinct(names: list[str]) -> list[str]:
    """Names made distinct as a table's reader makes them: a repeated one (a second time column,
    "Date/Time") is "Date/Time.1"."""
    counts: dict[str, int] = {}
    distinct = []
    for name in names:
        count = counts.get(name, 0)
        while count:
            counts[name] = count + 1
            name = f"{name}.{count}"
            count = counts.get(name, 0)
        distinct.append(name)
        counts[name] = count + 1
    return distinct


def _columns_written(lines: list[str], dialect: CsvDialect, width: int, columns: list[int]) -> set[int]:
    """Which of ``columns`` hold a cell that is not empty, read until each does."""
    written: set[int] = set()
    if not columns:
        return written
    for row in iter_rows(lines, dialect, width):
        written.update(k for k in columns if not empty_cell(row[k]))
        if len(written) == len(columns):
            break
    return written


def _frame_table(frame: pd.DataFrame) -> _LogTable:
    """A notebook's DataFrame as the lines a CSV file of it would hold: numbers as Python writes them
    (read back exactly), time stamps in ISO 8601, an elapsed time as a stamp from 1970-01-01; a time
    index (set_index, resample) is the time column too."""
    table = frame.reset_index() if frame.index.name is not None else frame
    header = tuple(str(c).strip() for c in table.columns)
    check_unique_names(list(header), "DataFrame")
    out = io.StringIO()
    writer = csv.writer(out, quoting=csv.QUOTE_ALL, lineterminator="\n")
    writer.writerows(zip(*(_written(table[c]) for c in table.columns), strict=True))
    lines = out.getvalue().split("\n")[:-1]
    return _LogTable(CsvDialect(), header, tuple(range(len(header))), lines, "DataFrame", 0)


def _written(values: pd.Series) -> list[str]:
    """A DataFrame's column as a CSV file would hold it ("" where missing)."""
    import pandas as pd

    if pd.api.types.is_timedelta64_dtype(values):
        values = pd.Timestamp(0) + values
    if pd.api.types.is_datetime64_any_dtype(values):
        return ["" if pd.isna(v) else v.isoformat() for v in values]
    return ["" if pd.isna(v) else repr(float(v)) if isinstance(v, float) else str(v) for v in values.tolist()]


def _sensor_candidates(table: _LogTable, available: list[str], notes: list[str]) -> list[str]:
    """The columns that may be sensors where none were asked for: a column of text alone (a
    logger's status or comment channel) or one that logged nothing (HOBO's "Coupler Detached") is
    left out, and said in ``notes``, unless every column is such."""
    valued, numbers, texts = _column_contents(table, [table.header.index(name) for name in available])
    text_only = [name for name in available if table.header.index(name) in texts - numbers]
    if text_only and len(text_only) < len(available):
        notes.append(f"left out, no numbers in them: {', '.join(text_only)}")
        available = [name for name in available if name not in text_only]
    empty = [name for name in available if table.header.index(name) not in valued]
    if empty and len(empty) < len(available):
        notes.append(f"left out, no readings in them: {', '.join(empty)}")
        available = [name for name in available if name not in empty]
    return available


def _column_contents(table: _LogTable, columns: list[int]) -> tuple[set[int], set[int], set[int]]:
    """Which of ``columns`` hold a cell that is not empty, which a number, and which something other
    than "nan", read until each holds a number (:func:`~mtident.io.columns.text_only_cells`)."""
    valued: set[int] = set()
    numbers: set[int] = set()
    texts: set[int] = set()
    for row in iter_rows(table.lines, table.dialect, len(table.header)):
        for k in columns:
            if k in numbers and k in valued or empty_cell(row[k]):
                continue
            valued.add(k)
            text = row[k].strip()
            if text.lower() != "nan":
                texts.add(k)
                if is_number(number_without_unit(text)):  # "68.00 °F" too
                    numbers.add(k)
        if len(numbers & valued) == len(columns):
            break
    return valued, numbers, texts


def as_temperature_log(log: object, caller: str) -> TemperatureLog:
    """``log`` as a :class:`TemperatureLog`: a DataFrame is read (and checked) like a CSV file.

    Parameters
    ----------
    log : TemperatureLog or pandas.DataFrame
        The readings.
    caller : str
        The function the log was given to, for the message.

    Returns
    -------
    TemperatureLog
        ``log`` itself, or the DataFrame read.

    Raises
    ------
    InputError
        Anything else, saying what ``caller`` takes.
    """
    if isinstance(log, TemperatureLog):
        return log
    import pandas as pd

    if isinstance(log, pd.DataFrame):
        return read_temperature_log(log)
    msg = (
        f"{caller} takes a TemperatureLog (read_temperature_log(path or DataFrame)) or a pandas DataFrame, not "
        f"{type(log).__name__}"
    )
    raise InputError(msg)
