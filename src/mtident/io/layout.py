"""A log's layout: what both readers fix from its head and keep for every row after it.

The dialect (:mod:`mtident.io.dialect`), the header, the time column (with a time of day in the
column after a date, and a millisecond column after the stamp), the sensors' columns, and the
units the time and the readings are converted from. The file reader
(:func:`~mtident.io.logs.read_temperature_log`) and the live follower
(:class:`~mtident.io.follow.LogFollower`) take the time columns here by the same rule
(:func:`time_columns`); the follower takes its sensors from the head alone
(:func:`layout_of_head`), the file reader by all the rows it has.
"""

from __future__ import annotations

import math
import re
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.io.columns import (
    check_header_names,
    choose_time_column,
    millisecond_column,
    missing_column,
    sensor_unit,
    temperature_columns,
    text_only_cells,
)
from mtident.io.dialect import CsvDialect
from mtident.io.stamps import date_and_clock
from mtident.io.time_notes import time_unit_assumed, time_unit_factor, unit_overridden_note
from mtident.io.units import celsius_conversion

__all__ = ["LogLayout", "time_columns", "layout_of_head", "refuse_grouped_time"]


@dataclass(frozen=True, slots=True)
class LogLayout:
    """How a log's rows are read, fixed from its head.

    Attributes
    ----------
    dialect : CsvDialect
        How the log is written (delimiter, decimal mark, preamble, encoding, units under the header).
    header : tuple of str
        The column names, in file order.
    time_column : int
        The time column's position.
    clock_column : int or None
        The column of the time of day where the time column holds the date alone.
    millisecond_column : int or None
        A column with the time stamps' milliseconds (Graphtec's "ms").
    sensors : tuple of str
        The sensors' columns, in the order read (a room sensor last where none were named).
    sensor_columns : tuple of int
        Their positions in the header.
    time_unit : str or None
        Unit of a numeric time column given by the user ("ms", "s", "min", "h", "d"); None: the log's own.
    temperature_unit : str or None
        Unit of the temperature columns that state none of their own ("C", "F" or "K"); None: °C.
    """

    dialect: CsvDialect
    header: tuple[str, ...]
    time_column: int
    clock_column: int | None
    millisecond_column: int | None
    sensors: tuple[str, ...]
    sensor_columns: tuple[int, ...]
    time_unit: str | None = None
    temperature_unit: str | None = None

    @property
    def time_name(self) -> str:
        """The time column's name.

        Returns
        -------
        str
        """
        return self.header[self.time_column]

    def conversions(self) -> FloatArray:
        """Each sensor's conversion to °C from the unit it is in (its own, else ``temperature_unit``).

        Returns
        -------
        ndarray, shape (S, 2)
            (scale, offset) per sensor: °C = scale * reading + offset.
        """
        pairs = [
            celsius_conversion(sensor_unit(name, self.dialect, self.temperature_unit)) or (1.0, 0.0)
            for name in self.sensors
        ]
        return np.array(pairs, dtype=float).reshape(-1, 2)

    def time_scale(self) -> tuple[float, bool]:
        """Minutes per unit of a numeric time column, and whether that unit is assumed (minutes for
        want of one stated or given: :func:`~mtident.io.time_notes.time_unit_assumed`).

        Returns
        -------
        minutes_per_unit : float
        assumed : bool
        """
        stated = self.dialect.time_unit(self.time_name)
        return (
            time_unit_factor(self.time_name, self.time_unit, stated),
            time_unit_assumed(self.time_name, self.time_unit, stated),
        )


_GROUPED = re.compile(r"^\s*[1-9]\d{0,2}(\.\d{3})+\s*$")
_COMMA_GROUPED = re.compile(r"^\s*[1-9]\d{0,2}(,\d{3})+\s*$")


def refuse_grouped_time(cell: str, decimal: str, name: str, source: str | Path, previous: str | None = None) -> None:
    """InputError for a time cell written with a thousands separator: a point under a decimal comma
    ("1.000" for 1000 s: read with its point as a decimal mark, 1000-13000 s was a log of 0.2 min),
    or a comma under a decimal point ("1,020", an English spreadsheet's export: the whole column was
    refused as "row 2: '0' is neither a number nor a time stamp"), or a comma under a decimal comma
    where it makes the time go back after ``previous`` ("960" then "1,020": 1.02 s).

    Parameters
    ----------
    cell : str
        A time cell as written.
    decimal : str
        The log's decimal mark.
    name : str
        The time column's name.
    source : str or Path
        The log, for the message.
    previous : str, optional
        The time cell before it, where the time went back at ``cell``.

    Raises
    ------
    InputError
        The cell groups thousands.
    """
    text = cell.strip()
    if decimal == "," and _GROUPED.match(cell):
        mark, marks = "point", "decimal commas"
    elif _COMMA_GROUPED.match(cell) and (
        decimal != "," or (previous is not None and _plain_float(previous) < float(text.replace(",", "")))
    ):
        mark = "comma"
        marks = "decimal points" if decimal != "," else f"decimal commas, yet it follows {previous!r}"
    else:
        return
    msg = (
        f"{source}: time column {name!r} holds {text!r} in a log written with {marks}: the {mark} groups thousands "
        f"there ({text} = {text.replace('.', '').replace(',', '')}), which mtident does not read; export the time "
        "without a thousands separator"
    )
    raise InputError(msg)


def _plain_float(cell: str) -> float:
    try:
        return float(cell.strip().replace(",", "."))
    except ValueError:
        return math.inf


def time_columns(
    header: list[str], first_row: Sequence[object], dialect: CsvDialect, time_col: str | None, source: str | Path
) -> tuple[tuple[int, int | None, int | None], list[str], list[str]]:
    """The time column, the time of day's column after a date, and a millisecond column, by the
    header and the first data row; which columns belong to the time (no sensors); and notes.

    Parameters
    ----------
    header : list of str
        The column names.
    first_row : sequence
        The first data row's cells (text; a table's cells may be numbers or stamps, which are
        then no date beside a time of day).
    dialect : CsvDialect
        How the log is written.
    time_col : str or None
        The time column's name, None to find it.
    source : str or Path
        The log, for the messages.

    Returns
    -------
    columns : (int, int or None, int or None)
        The positions of the time column, of the time of day, of the milliseconds.
    not_sensors : list of str
        The columns that belong to the time: a row counter before it, the time of day, the milliseconds.
    notes : list of str
        How the time column was found.

    Raises
    ------
    InputError
        No column ``time_col``.
    """
    time_name, counter, notes = choose_time_column(header, [str(v) for v in first_row], dialect, time_col)
    if time_name not in header:
        msg = f"{source}: no time column {time_name!r}; the columns are: {', '.join(header)}"
        raise InputError(msg)
    at = header.index(time_name)
    cell = first_row[at] if at < len(first_row) else None
    if isinstance(cell, str):
        refuse_grouped_time(cell, dialect.decimal, time_name, source)
    following = at + 1
    clock = None
    if following < min(len(header), len(first_row)):
        date, time_of_day = first_row[at], first_row[following]
        if isinstance(date, str) and isinstance(time_of_day, str) and date_and_clock(date, time_of_day):
            clock = following
    milliseconds = millisecond_column(header, following if clock is not None else at)
    not_sensors = [header[k] for k in (at, clock, milliseconds, 0 if counter else None) if k is not None]
    return (at, clock, milliseconds), not_sensors, notes


def layout_of_head(
    header_line: str,
    rows: list[list[str]],
    dialect: CsvDialect,
    source: str | Path,
    *,
    time_col: str | None = None,
    sensors: list[str] | None = None,
    room: str | None = None,
    time_unit: str | None = None,
    temperature_unit: str | None = None,
) -> tuple[LogLayout, list[str]]:
    """The layout of a log from its header line and its first data rows, as the live follower
    takes it: the sensors asked for, or every temperature column but those of text alone so far
    (a status channel), the room sensor last.

    Parameters
    ----------
    header_line : str
        The header line, as text.
    rows : list of list of str
        The data rows' cells written so far (the first tells how the time is written).
    dialect : CsvDialect
        How the log is written.
    source : str or Path
        The log, for the messages.
    time_col : str or None, optional
        The time column's name, None to find it.
    sensors : list of str or None, optional
        The sensor columns to read, in that order; None or ["all"]: every temperature column.
    room : str or None, optional
        A room sensor's column, read last where no sensors are named.
    time_unit, temperature_unit : str or None, optional
        The units given for a numeric time column and for the temperatures that state none.

    Returns
    -------
    layout : LogLayout
    notes : list of str
        How the header was read (columns renamed or left out, units converted, a time unit given
        against the column's own).

    Raises
    ------
    InputError
        Fewer than two columns, a name twice, no such time or sensor column, no sensor besides the
        room's, a column's own unit that ``temperature_unit`` contradicts.
    """
    header = dialect.header(header_line)
    if len(header) < 2:
        msg = (
            f"{source}: need a time column and at least one sensor column, separated by ',', ';' or tabs; "
            f"found: {', '.join(header)}"
        )
        raise InputError(msg)
    check_header_names(header, dialect.number, source)
    first = rows[0] if rows else []
    (at, clock, milliseconds), not_sensors, notes = time_columns(header, first, dialect, time_col, source)
    names = [h for h in header if h not in (*not_sensors, "")]  # "": a delimiter at the end of the line
    chosen, sensor_notes = _choose_sensors(header, names, rows, dialect, source, sensors, room, temperature_unit)
    layout = LogLayout(
        dialect,
        tuple(header),
        at,
        clock,
        milliseconds,
        tuple(chosen),
        tuple(header.index(s) for s in chosen),
        time_unit,
        temperature_unit,
    )
    renamed = dialect.renaming()
    said = [*([renamed] if renamed else []), *notes, *sensor_notes]
    if clock is None and at < len(first) and _is_number(dialect, first[at]):
        # a numeric time column read in another unit than its own: said once, at the head
        overridden = unit_overridden_note(layout.time_name, time_unit, dialect.time_unit(layout.time_name))
        said += [overridden] if overridden is not None else []
    return layout, said


def _is_number(dialect: CsvDialect, cell: str) -> bool:
    try:
        dialect.number(cell)
    except ValueError:
        return False
    return True


def _choose_sensors(
    header: list[str],
    names: list[str],
    rows: list[list[str]],
    dialect: CsvDialect,
    source: str | Path,
    sensors: list[str] | None,
    room: str | None,
    temperature_unit: str | None,
) -> tuple[list[str], list[str]]:
    """The sensor columns to read, the room sensor last, and notes: those asked for, or every
    column of ``names`` but text-only and non-temperature ones (left out with a note)."""
    asked = bool(sensors) and sensors != ["all"]
    chosen = sensors if asked and sensors is not None else names
    notes = []
    if not asked:
        text_only = [
            n
            for n in chosen
            if n != room and text_only_cells([row[header.index(n)] for row in rows if header.index(n) < len(row)])
        ]
        if text_only and len(text_only) < len([n for n in chosen if n != room]):
            notes.append(f"left out, no numbers in them: {', '.join(text_only)}")
            chosen = [n for n in chosen if n not in text_only]
    room_last = None if asked else room  # read after the sensors
    if room_last is not None:
        chosen = [n for n in chosen if n != room_last] + [room_last]
    missing = [s for s in chosen if s not in header]
    if missing:
        msg = missing_column(source, missing[0], names)
        raise InputError(msg)
    if room_last is not None and len(chosen) == 1:
        msg = f"{source}: no sensor column besides the room sensor {room_last!r}"
        raise InputError(msg)
    if room_last is not None:  # the room sensor, named, must be a temperature
        taken, unit_notes = temperature_columns(chosen[:-1], False, dialect, source, temperature_unit)
        room_column = temperature_columns(chosen[-1:], True, dialect, source, temperature_unit)[0]
        chosen = [*taken, *room_column]
    else:
        chosen, unit_notes = temperature_columns(list(chosen), asked, dialect, source, temperature_unit)
    return list(chosen), [*notes, *unit_notes]
