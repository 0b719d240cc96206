"""How mtident reads a log file: its dialect, its time, its sensors, and what it left out.

A test engineer's log rarely looks like a plain CSV of minutes and sensors; before trusting
an identification from it, one wants to see how it was read (``mtident thermal
inspect``): which line was taken for the header, what the time column is and
how long a step is, each sensor's unit and readings, and every column left out
with the reason.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mtident.io.dialect import CsvDialect, binary_kind
from mtident.io.log_file import read_lines
from mtident.io.logs import read_temperature_log
from mtident.io.time_notes import TIME_UNITS, time_unit_assumed, time_unit_factor
from mtident.io.units import is_number, stated_temperature_unit
from mtident.io.whole import MAX_BAD_FRACTION

__all__ = ["LogDescription", "LogFormat", "SensorColumn", "TimeColumn", "describe_log"]

_DELIMITER_NAMES = {",": "comma", ";": "semicolon", "\t": "tab"}


@dataclass(frozen=True, slots=True)
class LogFormat:
    """What the file is and where its table begins.

    Attributes
    ----------
    kind : str
        "CSV text" or an Excel workbook.
    encoding, delimiter, decimal : str
        The text's encoding, the delimiter's name and the decimal mark.
    lines_before_header, header_line, rows_under_header : int
        The lines before the header, the header's line number, and the rows between it and the data.
    units_from : str
        Whence the units: a units row, or the column names; "no units in the log (°C assumed)"
        where neither states one (the unit stated instead of °C).
    units_in_cells : bool
        The cells carry their unit.
    """

    kind: str
    encoding: str
    delimiter: str
    decimal: str
    lines_before_header: int
    header_line: int
    rows_under_header: int
    units_from: str
    units_in_cells: bool


@dataclass(frozen=True, slots=True)
class TimeColumn:
    """How the time column is read.

    Attributes
    ----------
    column : str
    first_cell : str or None
        The first cell as written.
    read_as : str
        As time stamps, or as numbers in a unit and whence the unit.
    samples : int
    span_min : float
    step_min : float or None
        The median step (min); None for a single sample.
    """

    column: str
    first_cell: str | None
    read_as: str
    samples: int
    span_min: float
    step_min: float | None


@dataclass(frozen=True, slots=True)
class SensorColumn:
    """One sensor column as read.

    Attributes
    ----------
    sensor : str
    unit : str
        Its unit as the log states it, or as ``temperature_unit`` does where it states none.
    samples, missing : int
        Valid and missing samples.
    first_C, last_C, min_C, max_C : float or None
        Its first, last, lowest and highest valid reading (°C); None without one.
    """

    sensor: str
    unit: str
    samples: int
    missing: int
    first_C: float | None
    last_C: float | None
    min_C: float | None
    max_C: float | None


@dataclass(frozen=True, slots=True)
class LogDescription:
    """How a log is read: its fields are the JSON of ``mtident thermal inspect --json``.

    Attributes
    ----------
    file : str
    format : LogFormat
    time : TimeColumn
    sensors : tuple of SensorColumn
    notes : tuple of str
        Columns left out, conversions, rows skipped.
    """

    file: str
    format: LogFormat
    time: TimeColumn
    sensors: tuple[SensorColumn, ...]
    notes: tuple[str, ...]


def describe_log(
    path: str | Path,
    time_col: str | None = None,
    time_unit: str | None = None,
    sensors: list[str] | None = None,
    temperature_unit: str | None = None,
    sheet: str | int | None = None,
) -> LogDescription:
    """How the log at ``path`` is read (its JSON: ``to_json_value`` of the answer).

    Fields: ``file``; ``format`` (what the file is, its encoding, delimiter, decimal
    mark, the lines before the header, the header line's number, the rows between
    the header and the data); ``time`` (its column, the first cell as written, how it
    is read: stamps, or numbers in a unit and whence the unit; the samples, the span
    and the median step in minutes); ``sensors`` (per sensor: its unit as the log
    states it, or as ``temperature_unit`` does where it states none, valid and
    missing samples, first, last, lowest and highest reading in °C); ``notes``
    (columns left out, conversions, rows skipped).

    Parameters
    ----------
    path : str or Path
        The log file (CSV text or an Excel workbook).
    time_col : str, optional
        Name of the time column (default: the first column).
    time_unit : {"ms", "s", "min", "h", "d"}, optional
        Unit of a numeric time column (default: the header's suffix or a units row, else minutes).
    sensors : list of str, optional
        The sensor columns to describe, in this order (default: all).
    temperature_unit : {"C", "F", "K"}, optional
        Unit of the temperature columns that state none of their own (default: °C).
    sheet : str or int, optional
        An Excel workbook's sheet, by name or number from 1 (default: its first sheet with a table).

    Returns
    -------
    LogDescription
        The fields above; a value that cannot be known (a sensor without a valid reading, the
        step of a single sample) is None. A log of a single sample is described too.

    Raises
    ------
    InputError
        As the readers do (:func:`~mtident.io.logs.read_temperature_log`): a missing or
        unreadable file, no such column, a time column that does not increase.
    """
    file = Path(path)
    lines, dialect = read_lines(file, sheet=sheet)
    # a log just begun is worth a look too: no five samples needed here; nor one whose sensor failed
    log = read_temperature_log(
        file,
        time_col=time_col,
        time_unit=time_unit,
        sensors=sensors,
        min_samples=1,
        temperature_unit=temperature_unit,
        max_bad_fraction=1.0,
        sheet=sheet,
    )
    stated = stated_temperature_unit(temperature_unit)
    with file.open("rb") as handle:
        kind = binary_kind(handle.read(8))
    steps = np.diff(log.time_min)
    time_name = log.time_column.split(" + ")[0]
    first_cell = _first_cell(lines, dialect, time_name)
    per_sensor: list[SensorColumn] = []
    for k, name in enumerate(log.sensors):
        values = log.temperature_C[:, k]
        valid = values[np.isfinite(values)]
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            low, high = (float(np.min(valid)), float(np.max(valid))) if len(valid) else (None, None)
        per_sensor.append(
            SensorColumn(
                sensor=name,
                unit=dialect.unit_of(name).strip()
                or ("°C (assumed)" if stated is None else f"{stated} (`temperature_unit`)"),
                samples=int(len(valid)),
                missing=int(len(values) - len(valid)),
                first_C=float(valid[0]) if len(valid) else None,
                last_C=float(valid[-1]) if len(valid) else None,
                min_C=low,
                max_C=high,
            )
        )
    return LogDescription(
        file=str(path),
        format=_format(dialect, kind, any(dialect.unit_of(c.sensor).strip() for c in per_sensor), stated, sheet),
        time=TimeColumn(
            column=log.time_column,
            first_cell=None if first_cell is None else str(first_cell),
            read_as=_time_read_as(time_name, first_cell, time_unit, dialect),
            samples=int(len(log.time_min)),
            span_min=float(log.time_min[-1] - log.time_min[0]),
            step_min=float(np.median(steps)) if len(steps) else None,
        ),
        sensors=tuple(per_sensor),
        notes=(*log.notes, *_mostly_bad(per_sensor)),
    )


def _mostly_bad(columns: list[SensorColumn]) -> list[str]:
    """A note per sensor with more than :data:`~mtident.io.whole.MAX_BAD_FRACTION` of its samples
    bad: the commands that read a whole log refuse it, ``watch`` follows it."""
    return [
        f"sensor {c.sensor!r}: {c.missing} of {c.samples + c.missing} samples are empty, NaN or open-circuit, more "
        f"than {MAX_BAD_FRACTION:.0%}: identify, learn and report refuse it (check the wiring, or leave it out with "
        "--sensor); watch follows it, and says when it has stopped reading"
        for c in columns
        if c.missing > MAX_BAD_FRACTION * (c.samples + c.missing)
    ]


def _first_cell(lines: list[str], dialect: CsvDialect, name: str) -> str | None:
    """The first data line's cell in column ``name``, as written (None where the file has no such
    column or no data line)."""
    written = dialect.cells(lines[0])
    header = [
        dialect.names[k] if k < len(dialect.names) and dialect.names[k] != dialect.written_names[k] else cell.strip()
        for k, cell in enumerate(written)
    ]
    data = next((line for line in lines[1 + dialect.extra_rows :] if line.strip()), None)
    if name not in header or data is None:
        return None
    cells = dialect.cells(data)
    k = header.index(name)
    return cells[k].strip() if k < len(cells) else None


def _time_read_as(name: str, first_cell: object, time_unit: str | None, dialect: CsvDialect) -> str:
    """How the time column's cells are read: as time stamps, or as numbers in a unit, and whence the unit."""
    if first_cell is None or not is_number(str(first_cell)):
        return "time stamps"
    stated = dialect.time_unit(name)
    factor = time_unit_factor(name, time_unit, stated)
    unit = next(unit for unit, minutes in TIME_UNITS.items() if minutes == factor)
    if time_unit is not None:
        return f"numbers in {unit} (`time_unit`)"
    return (
        f"numbers in {unit} (assumed: no unit in its name, a units row or `time_unit`)"
        if time_unit_assumed(name, time_unit, stated)
        else f"numbers in {unit} (as the log states)"
    )


def _format(
    dialect: CsvDialect, kind: str | None, names_state_units: bool, stated: str | None, sheet: str | int | None
) -> LogFormat:
    """The log's format; its units from a units row, the column names, or nowhere (then °C, or
    the unit stated, is assumed)."""
    nowhere = "no units in the log (°C assumed)" if stated is None else f"no units in the log ({stated}, as stated)"
    which = "its first sheet with a table" if sheet is None else f"the sheet `sheet` names: {str(sheet)!r}"
    return LogFormat(
        kind=f"Excel workbook ({which})" if kind in ("xlsx", "xls") else "CSV text",
        encoding=dialect.encoding.removesuffix("-sig"),
        delimiter=_DELIMITER_NAMES.get(dialect.delimiter, dialect.delimiter),
        decimal=dialect.decimal,
        lines_before_header=dialect.preamble_lines,
        header_line=dialect.preamble_lines + 1,
        rows_under_header=dialect.extra_rows,
        units_from=dialect.units_source if dialect.units else "the column names" if names_state_units else nowhere,
        units_in_cells=dialect.units_in_cells,
    )
