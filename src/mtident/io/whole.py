"""A whole log's rows read at once, as the file reader reads them (:func:`~mtident.io.parse.parse_lines`
with a :class:`~mtident.io.parse.WholeLog`).

Where the follower reads rows one by one and passes over what it cannot read with a warning, a
whole log is read column by column, and what cannot be read is an error naming the row:

* rows without a reading at the end of the log or at a repeated time (a logger's events) are left
  out, and so are rows that repeat an earlier row exactly, with a note;
* the time column is numbers (in the unit stated, given or assumed; spreadsheet serial dates in a
  column named as dates), or time stamps in the format of the first one, a slashed date read the
  other way round where that reads better, a clock past 24:00:00 as elapsed time, a time of day
  across midnight, a local clock across its summer-time changes; a time that is empty, unreadable,
  repeated or going back is an error;
* a reading that is empty or a placeholder, or an open circuit's, is NaN, with a note per sensor
  naming its rows; a reading that is no number is an error, and so is a sensor with more than
  ``MAX_BAD_FRACTION`` of its readings bad.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import TYPE_CHECKING

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.io.cells import OPEN_CIRCUIT_HIGH_C, OPEN_CIRCUIT_LOW_C, column, empty_cells, numbers, plain_numbers
from mtident.io.layout import LogLayout, refuse_grouped_time
from mtident.io.log_file import header_again_words
from mtident.io.stamps import (
    CLOCK_DAY_ZERO_MIN,
    IMPLAUSIBLE_STEP_MIN,
    MINUTES_PER_DAY,
    TIME_OF_DAY_FORMATS,
    after_midnight,
    clock_change,
    clock_change_note,
    elapsed_minutes,
    has_utc_offset,
    other_date_order,
    stamp_format,
)
from mtident.io.time_notes import (
    UNLIKELY_MINUTES,
    gap_note,
    hours_hint,
    names_a_date,
    seconds_hint,
    serial_date_hint,
    serial_date_note,
    sparse_hint,
    time_unit_assumed,
    time_unit_factor,
    unit_overridden_note,
)
from mtident.io.units import carried_unit, celsius_conversion

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "WholeTime",
    "read_whole",
    "OPEN_CIRCUIT_TEXT",
    "MISSING_TEXT",
    "MAX_BAD_FRACTION",
]

# What loggers write in place of a reading for a broken thermocouple or an overrange (Graphtec
# "BURNOUT"); the live follower reads any text as a missing reading.
OPEN_CIRCUIT_TEXT = frozenset(
    (
        *("burnout", "burn out", "open", "ol", "+ol", "-ol", "o.l.", "o.l", "ovl", "over", "+over", "-over"),
        *("overrange", "overflow", "under", "underrange", "err", "error", "+++++", "-----"),
    )
)
# What loggers and spreadsheets write in place of a reading they do not have (a dropped sample,
# a channel between scans): missing, like an empty cell.
MISSING_TEXT = frozenset(
    (
        *("", "-", "--", "---", "----", "n/a", "na", "#n/a", "#na", "null", "none", "nan"),
        # a spreadsheet's formula errors, where an export's cell had no reading to compute from
        *("#value!", "#div/0!", "#ref!", "#num!", "#name?", "#null!"),
    )
)
# Above this share of bad samples a sensor is refused rather than bridged.
MAX_BAD_FRACTION = 0.1
# readings a sensor must have given before it fell silent for good, for its silence to the log's end
# to count as a failure after the fact rather than a column that never worked
MIN_READINGS_BEFORE_FAILURE = 10

_STAMP_EXAMPLES = "(ISO 8601, 22.11.2026 08:00:00, 11/22/2026 08:00:00 AM or 08:00:00)"


@dataclass(frozen=True, slots=True)
class WholeTime:
    """A whole log's times, and how its time column was read.

    Attributes
    ----------
    time_min : ndarray, shape (N,)
        Minutes from the first row, strictly increasing.
    origin : float
        The first row's time as read (min; from 1970 for time stamps).
    time_format : str or None
        The time stamps' format; None for numbers and for elapsed time.
    first_stamp : str or None
        The first time stamp as written.
    clock_shift : float
        Minutes added to the last rows' stamps for summer-time changes.
    serial_days : bool
        The time column holds spreadsheet serial dates, read in days.
    last_cell : str or None
        The last row's time cell(s) as written.
    """

    time_min: FloatArray
    origin: float
    time_format: str | None = None
    first_stamp: str | None = None
    clock_shift: float = 0.0
    serial_days: bool = False
    last_cell: str | None = None


@dataclass(frozen=True, slots=True)
class _Column:
    """A column's cells as written (the time's: a date and a time of day joined), which are empty,
    each as a number where the column is one of numbers written with the log's decimal mark (None
    otherwise), and its name in messages."""

    cells: list[str]
    empty: np.ndarray
    numbers: FloatArray | None
    name: str

    def quoted(self, row: int) -> str:
        """A cell as the user wrote it: 4, not 4.0; text quoted; "nan" for an empty one."""
        if self.empty[row]:
            return "nan"
        return repr(self.cells[row]) if self.numbers is None else f"{self.numbers[row]:g}"

    def keys(self) -> list[object]:
        """The cells as compared: numbers by value, text as written, "nan" where empty."""
        if self.numbers is None:
            return ["nan" if e else c for c, e in zip(self.cells, self.empty, strict=True)]
        return ["nan" if e else v for v, e in zip(self.numbers.tolist(), self.empty, strict=True)]

    def taken(self, keep: np.ndarray) -> _Column:
        """The column of the rows kept."""
        numbers = None if self.numbers is None else self.numbers[keep]
        cells = [cell for cell, kept in zip(self.cells, keep, strict=True) if kept]
        return _Column(cells, self.empty[keep], numbers, self.name)


def read_whole(
    layout: LogLayout, rows: list[list[str]], source: str, first_row: int, max_bad_fraction: float = MAX_BAD_FRACTION
) -> tuple[WholeTime, FloatArray, list[str]]:
    """A whole log's times, readings and notes, from its rows.

    Parameters
    ----------
    layout : LogLayout
        How the rows are read.
    rows : list of list of str
        The data rows' cells (:func:`~mtident.io.cells.split_rows`), at least one.
    source : str
        The log, for the messages.
    first_row : int
        The number messages give the first row.
    max_bad_fraction : float, optional
        The largest share of a sensor's readings that may be bad (:data:`MAX_BAD_FRACTION`).

    Returns
    -------
    time : WholeTime
        The rows' times (those left out aside), and how the time column was read.
    temperature_C : ndarray, shape (N, S)
        Their readings (°C; NaN: empty, a placeholder or an open circuit's).
    notes : list of str
        Rows left out, how the time was read, a gap, readings skipped.

    Raises
    ------
    InputError
        A time that is empty, neither a number nor a time stamp like the first, repeated or going
        back, or a reading that is no number, named with its row; a sensor with more than
        ``max_bad_fraction`` of its readings bad, or more than :data:`MAX_BAD_FRACTION` only in the
        temperature unit stated; spreadsheet serial dates in a column not named as dates.
    """
    number = np.arange(len(rows)) + first_row
    notes: list[str] = []
    sub_second = _sub_second_min(layout, rows, number, source)
    time = _time_column(layout, rows)
    keep = _rows_kept(layout, rows, time, number, notes)
    if not keep.all():
        rows = [row for row, kept in zip(rows, keep, strict=True) if kept]
        number, time = number[keep], time.taken(keep)
        sub_second = None if sub_second is None else sub_second[keep]
    read = _times(layout, time, number, source, sub_second, notes)
    if (gap := gap_note(read.time_min)) is not None:
        notes.append(gap)
    return read, _readings(layout, rows, number, source, notes, max_bad_fraction), notes


def _rows_kept(
    layout: LogLayout, rows: list[list[str]], time: _Column, number: np.ndarray, notes: list[str]
) -> np.ndarray:
    """Which rows to read: all but those without a reading in any sensor that come at the end of
    the log or repeat a neighbour's time (HOBO writes its events, "Host Connected", "End Of File", as
    rows of their own, at the time of the read-out, several at one time), and those that repeat an
    earlier row exactly (a logger that writes a row twice, a buffer flushed again); said in ``notes``."""
    keep = _with_readings(layout, rows, time)
    if not keep.all():
        notes.append(
            f"left out {int((~keep).sum())} row(s) without a reading at the end or at a repeated time (a logger's "
            "events: coupler, host connected, end of file)"
        )
    kept = np.flatnonzero(keep)
    times = time.keys()
    repeated = _repeated_rows(layout, [rows[k] for k in kept], [times[k] for k in kept])
    if repeated.any():
        rows_repeated = ", ".join(str(int(r)) for r in number[kept][repeated][:5])
        notes.append(f"left out {int(repeated.sum())} row(s) repeating an earlier row exactly (rows {rows_repeated})")
        keep[kept[repeated]] = False
    return keep


def _with_readings(layout: LogLayout, rows: list[list[str]], time: _Column) -> np.ndarray:
    """Rows with a reading, or else neither at the end of the log nor at a time a neighbour repeats."""
    empty = np.ones(len(rows), dtype=bool)
    for index in layout.sensor_columns:
        at = np.flatnonzero(empty)  # only rows without a reading so far: a clean log looks at one column
        empty[at] = empty_cells([rows[k][index] for k in at])
    if empty.all() or not empty.any():
        return np.ones(len(rows), dtype=bool)
    # a date and a time of day in two columns: the date's column tells a repeated time here
    times = time.keys() if layout.clock_column is None else _cell_keys(column(rows, layout.time_column), layout)
    repeated = np.zeros(len(rows), dtype=bool)
    same = np.array([a == b for a, b in zip(times[1:], times[:-1], strict=True)], dtype=bool)
    repeated[1:] |= same
    repeated[:-1] |= same
    trailing = np.flip(np.cumprod(np.flip(empty)).astype(bool))
    answer: np.ndarray = ~(empty & (repeated | trailing))
    return answer


def _repeated_rows(layout: LogLayout, rows: list[list[str]], times: list[object]) -> np.ndarray:
    """Rows equal to an earlier one in every column (cells compared as a table reads them: numbers
    by value, text as written); ``times``: their time cells as compared."""
    repeated = np.zeros(len(rows), dtype=bool)
    if len(set(times)) == len(times):  # no time twice: no row twice (the common case, at once)
        return repeated
    columns = (_cell_keys(column(rows, k), layout) for k in range(len(layout.header)))
    seen: set[tuple[object, ...]] = set()
    for k, key in enumerate(zip(*columns, strict=True)):
        repeated[k] = key in seen
        seen.add(key)
    return repeated


def _cell_keys(cells: list[str], layout: LogLayout) -> list[object]:
    """A column's cells as compared: numbers by value in a column of numbers, else as written; an
    empty cell as "nan"."""
    empty = empty_cells(cells)
    return _Column(cells, empty, _as_numbers(cells, empty, layout.dialect.decimal), "").keys()


def _as_numbers(cells: list[str], empty: np.ndarray, mark: str) -> FloatArray | None:
    """Each cell as a number (NaN where empty), where every other cell is one written with ``mark``
    as the decimal mark (a table's column of numbers); None otherwise."""
    written = [c for c, e in zip(cells, empty, strict=True) if not e] if empty.any() else cells
    if not plain_numbers(written, mark):
        return None
    values = np.full(len(cells), np.nan)
    values[~empty] = np.fromiter((float(c.replace(",", ".")) for c in written), float, len(written))
    return values


def _sub_second_min(layout: LogLayout, rows: list[list[str]], number: np.ndarray, source: str) -> FloatArray | None:
    """A logger's millisecond column (the layout's), in minutes; None without one; an error naming
    the first cell that is no number."""
    if layout.millisecond_column is None:
        return None
    cells = column(rows, layout.millisecond_column)
    values = numbers(cells, layout.dialect)
    if np.isnan(values).any():
        row = int(np.isnan(values).argmax())
        empty = empty_cells(cells[row : row + 1])[0]
        msg = (
            f"{source}: millisecond column {layout.header[layout.millisecond_column]!r}, row {number[row]}: "
            f"{'nan' if empty else repr(cells[row])} is not a number"
        )
        raise InputError(msg)
    answer: FloatArray = values / 60_000.0
    return answer


def _times(
    layout: LogLayout,
    time: _Column,
    number: np.ndarray,
    source: str,
    sub_second: FloatArray | None,
    notes: list[str],
) -> WholeTime:
    """The rows' times in minutes from the first, from the layout's time column, or from its date
    column and the time of day in the next; what was assumed or found goes to ``notes``."""
    stated = None if layout.clock_column is not None else layout.dialect.time_unit(time.name)
    plain = None if layout.clock_column is not None else _plain_time(time)
    for cell in time.cells if layout.clock_column is None else ():
        refuse_grouped_time(cell, layout.dialect.decimal, time.name, source)
    if plain is not None:
        read = _numeric_time(plain, time.name, layout.time_unit, stated, source, notes)
    else:
        read = _stamped_time(time, layout.time_unit, number, source, notes)
    values = read.time_min if sub_second is None else read.time_min + sub_second
    _check_increasing(values, time, number, source)
    time_min: FloatArray = values - values[0]
    if layout.clock_column is None:
        _unit_notes(layout, time, time_min, stated, notes)
    return replace(read, time_min=time_min, last_cell=time.cells[-1].strip())


def _time_column(layout: LogLayout, rows: list[list[str]]) -> _Column:
    cells = column(rows, layout.time_column)
    empty = empty_cells(cells)
    if layout.clock_column is None:
        return _Column(cells, empty, _as_numbers(cells, empty, layout.dialect.decimal), layout.time_name)
    clock = column(rows, layout.clock_column)
    empty |= empty_cells(clock)
    cells = [f"{date.strip()} {time.strip()}" for date, time in zip(cells, clock, strict=True)]
    return _Column(cells, empty, None, f"{layout.time_name} + {layout.header[layout.clock_column]}")


def _plain_time(time: _Column) -> FloatArray | None:
    """The time column's numbers where every cell is one: written with the log's decimal mark, or
    all with a point (a decimal-comma log's, or a column whose rows of text were left out)."""
    if time.empty.any():
        return None
    if time.numbers is not None:
        return time.numbers
    if not plain_numbers(time.cells, "."):
        return None
    return np.fromiter(map(float, time.cells), float, len(time.cells))


def _numeric_time(
    plain: FloatArray, name: str, time_unit: str | None, stated: str | None, source: str, notes: list[str]
) -> WholeTime:
    """A column of numbers in minutes as read (its ``time_min`` not yet from the first row), in its
    unit; spreadsheet serial dates in days."""
    values: FloatArray = plain * time_unit_factor(name, time_unit, stated)
    serial = (
        serial_date_hint(name, values[0], float(np.median(np.diff(values))))
        if len(values) > 1 and time_unit_assumed(name, time_unit, stated)
        else None
    )
    if serial is not None and not names_a_date(name):
        msg = f"{source}: {serial}"
        raise InputError(msg)
    if serial is not None:
        notes.append(serial_date_note(name, float(values[0])))
        values = values * MINUTES_PER_DAY
    return WholeTime(values, float(values[0]), serial_days=serial is not None)


def _stamped_time(time: _Column, time_unit: str | None, number: np.ndarray, source: str, notes: list[str]) -> WholeTime:
    """A column of time stamps (or of elapsed time written as a clock past 24:00:00) in minutes from
    the first row, across midnight and summer-time changes (its ``time_min``)."""
    import pandas as pd  # only for time stamps

    if time.empty.any():
        row = int(time.empty.argmax())
        msg = f"{source}: time column {time.name!r}, row {number[row]} is empty"
        raise InputError(msg)
    _refuse_stray_time_cell(time, number, source)
    text = pd.Series([cell.strip() for cell in time.cells], dtype=object)
    fmt = stamp_format(str(text.iloc[0]))
    if time_unit is not None:
        notes.append(f"time column {time.name!r} holds time stamps: the unit {time_unit!r} given for it is not used")
    stamps, fmt = _stamps(text, fmt)
    elapsed = (
        [elapsed_minutes(str(cell)) for cell in text] if fmt in TIME_OF_DAY_FORMATS and stamps.isna().any() else []
    )
    if elapsed and None not in elapsed:
        # a clock that runs past 24:00:00 is elapsed time since the start of the test
        notes.append(f"time column {time.name!r} read as hours:minutes:seconds elapsed (it runs past 24:00:00)")
        minutes = np.array(elapsed, dtype=float)
        return WholeTime(minutes, CLOCK_DAY_ZERO_MIN + float(minutes[0]))
    if stamps.isna().any():
        row = int(stamps.isna().to_numpy().argmax())
        msg = (
            f"{source}: time column {time.name!r}, row {number[row]}: {time.quoted(row)} is neither a number nor a "
            f"time stamp {'like the first one' if fmt is not None and row > 0 else _STAMP_EXAMPLES}"
        )
        raise InputError(msg)
    first = float(stamps.iloc[0].timestamp() / 60.0)
    values: FloatArray = (stamps - stamps.iloc[0]).dt.total_seconds().to_numpy(dtype=float) / 60.0
    shifted = values
    if fmt in TIME_OF_DAY_FORMATS:
        previous: float | None = None
        for k, t in enumerate(values):  # row by row, as the live follower reads them
            values[k] = previous = after_midnight(previous, float(t))
    elif not has_utc_offset(str(text.iloc[0])) and len(values) > 2:
        shifted = _across_clock_changes(values, first, time, number, notes)
    return WholeTime(shifted, first, fmt, str(text.iloc[0]), float(shifted[-1] - values[-1]))


def _refuse_stray_time_cell(time: _Column, number: np.ndarray, source: str) -> None:
    """An error naming the first cell that is no number in a time column of numbers (nine in ten at
    least, the first among them): the column was taken for time stamps, and the error named its
    first row ('0' is neither a number nor a time stamp) where a summary row or a header written
    again lay hundreds of rows on."""
    numeric = np.array([plain_numbers([cell], ".") for cell in time.cells])
    if not len(numeric) or not numeric[0] or numeric.mean() < 0.9:
        return
    row = int(np.argmin(numeric))
    if time.cells[row].strip() == time.name.strip():
        # the same header again is left out before this (read_lines): this one names other columns
        raise InputError(header_again_words(source, f"row {number[row]}"))
    msg = (
        f"{source}: time column {time.name!r}, row {number[row]}: {time.quoted(row)} is not a number, where the "
        "column's other cells are (a summary row?): leave that row out"
    )
    raise InputError(msg)


def _stamps(text: pd.Series, fmt: str | None) -> tuple[pd.Series, str | None]:
    """The cells as time stamps (UTC) in the first one's format, NaT where one is not; a slashed date
    the other way round (day and month swapped) where that reads every cell and steps less far."""
    import pandas as pd

    # as UTC: stamps with offsets that change (summer time ends during the test) stay in order
    stamps = (
        pd.to_datetime(text, format=fmt, errors="coerce", utc=True)
        if fmt is not None
        else pd.Series(pd.NaT, index=text.index)
    )
    swapped = other_date_order(fmt)
    if swapped is not None:
        other = pd.to_datetime(text, format=swapped, errors="coerce", utc=True)
        if other.notna().all() and (
            stamps.isna().any() or _longest_step(other) < min(_longest_step(stamps), IMPLAUSIBLE_STEP_MIN)
        ):
            return other, swapped
    return stamps, fmt


def _longest_step(stamps: pd.Series) -> float:
    """The largest step between neighbouring valid stamps, back or forth (min)."""
    valid = stamps.dropna()
    minutes = valid.diff().dt.total_seconds().to_numpy()[1:] / 60.0
    return float(np.max(np.abs(minutes))) if len(minutes) else 0.0


def _across_clock_changes(
    values: FloatArray, first_min: float, time: _Column, number: np.ndarray, notes: list[str]
) -> FloatArray:
    """Minutes from the first local stamp (written without an offset) with the clock's summer-time
    changes taken out (:func:`~mtident.io.stamps.clock_change`); a note for each, naming the row
    and its cells. ``first_min``: the first stamp in minutes since 1970 as written."""
    steps = np.diff(values)
    shifted = values.copy()
    for k in (np.flatnonzero((steps <= 0) | (steps > 59.0)) + 1).tolist():
        # the step before, as read (the follower knows no other when the row comes)
        interval = float(shifted[k - 1] - shifted[k - 2]) if k >= 2 else None
        shift = clock_change(first_min + values[k - 1], first_min + values[k], interval)
        if shift:
            shifted[k:] += shift
            notes.append(clock_change_note(shift, f"at row {number[k]}", time.quoted(k - 1), time.quoted(k)))
    return shifted


def _check_increasing(values: FloatArray, time: _Column, number: np.ndarray, source: str) -> None:
    steps = np.diff(values)
    if np.any(steps == 0):
        row = int(np.argmax(steps == 0)) + 1
        repeats = int(np.count_nonzero(steps == 0))
        more = f" ({repeats} rows repeat the time before them)" if repeats > 1 else ""
        msg = (
            f"{source}: time column {time.name!r}, row {number[row]}: duplicate time {time.quoted(row)}, the time "
            f"of row {number[row - 1]} too, with other readings{more}; each reading needs its own time: give a time "
            "column that resolves the logging (seconds where it logs several rows a minute), or remove the row that "
            "is wrong (`watch` keeps the first of such rows and says so)"
        )
        raise InputError(msg)
    if np.any(steps < 0):
        row = int(np.argmax(steps < 0)) + 1
        refuse_grouped_time(time.cells[row], ",", time.name, source, previous=time.cells[row - 1])
        msg = (
            f"{source}: time column {time.name!r}, row {number[row]}: time goes back ({time.quoted(row - 1)} "
            f"then {time.quoted(row)}); time must increase: sort the rows by time, or, after a logger's "
            "clock was reset, cut the log there and give the part you want"
        )
        raise InputError(msg)


def _unit_notes(layout: LogLayout, time: _Column, time_min: FloatArray, stated: str | None, notes: list[str]) -> None:
    """A time unit given against the column's own, and where a column of numbers read as minutes
    for want of a unit looks like seconds or hours."""
    if (overridden := unit_overridden_note(time.name, layout.time_unit, stated)) is not None:
        notes.append(overridden)
    if time.numbers is not None and time_unit_assumed(time.name, layout.time_unit, stated):
        span = float(time_min[-1] - time_min[0])
        if time_min[-1] > UNLIKELY_MINUTES:
            notes.append(seconds_hint(time.name, float(time_min[-1])))
        elif (hint := hours_hint(time.name, span, len(time_min)) or sparse_hint(time.name, time_min)) is not None:
            notes.append(hint)
    elif time.numbers is not None and layout.time_unit is None and time_unit_factor(time.name, None, stated) == 1.0:
        # decimal clock hours under a name that states minutes: read as stated, and said
        span = float(time_min[-1] - time_min[0])
        if (hint := hours_hint(time.name, span, len(time_min), named_minutes=True)) is not None:
            notes.append(hint)


def _readings(
    layout: LogLayout,
    rows: list[list[str]],
    number: np.ndarray,
    source: str,
    notes: list[str],
    max_bad_fraction: float,
) -> FloatArray:
    """The sensors' readings in °C, NaN for an empty, placeholder or open-circuit cell (said in
    ``notes``, with the rows)."""
    conversions = layout.conversions()
    columns = [
        _sensor_readings(name, column(rows, index), layout, conversions[k], number, source, notes, max_bad_fraction)
        for k, (name, index) in enumerate(zip(layout.sensors, layout.sensor_columns, strict=True))
    ]
    return np.column_stack(columns) if columns else np.empty((len(rows), 0))


def _sensor_readings(
    name: str,
    cells: list[str],
    layout: LogLayout,
    conversion: FloatArray,
    number: np.ndarray,
    source: str,
    notes: list[str],
    max_bad_fraction: float,
) -> FloatArray:
    """A sensor's column in °C (by ``conversion``, (scale, offset)), NaN for an empty, placeholder
    or open-circuit cell (said in ``notes``); an error naming the first cell that is no number, or
    a column mostly bad."""
    scale, offset = float(conversion[0]), float(conversion[1])
    if layout.dialect.units_in_cells:
        _refuse_other_units(name, cells, (scale, offset), number, source)
    written = numbers(cells, layout.dialect)
    values: FloatArray = scale * written + offset
    marked_open = np.zeros(len(cells), dtype=bool)
    if np.isnan(values).any():  # what the cells that are no number hold
        at = np.flatnonzero(np.isnan(values))
        said = [cells[k].strip().lower() for k in at]
        marked_open[at] = [text in OPEN_CIRCUIT_TEXT for text in said]
        missing_said = empty_cells([cells[k] for k in at]) | [text in MISSING_TEXT for text in said]
        no_number = ~marked_open[at] & ~missing_said
        if no_number.any():
            row = int(at[np.argmax(no_number)])
            msg = f"{source}: sensor {name!r}, row {number[row]}: {cells[row]!r} is not a number"
            raise InputError(msg)
    missing = np.isnan(values) & ~marked_open
    open_circuit = (values > OPEN_CIRCUIT_HIGH_C) | (values < OPEN_CIRCUIT_LOW_C) | marked_open
    bad = missing | open_circuit
    # a sensor that failed and stayed silent to the log's end is judged on the readings it gave: the
    # stretch it was alive for may be all that a window of the log needs (its silence is said)
    given = np.flatnonzero(~bad)
    alive = bad[: given[-1] + 1] if len(given) >= MIN_READINGS_BEFORE_FAILURE else bad
    if np.mean(alive) > MAX_BAD_FRACTION:
        as_written = (written >= OPEN_CIRCUIT_LOW_C) & (written <= OPEN_CIRCUIT_HIGH_C)
        # a log in °C read as K is -253 °C: the unit the user stated, not the wiring
        stated = layout.temperature_unit is not None and not layout.dialect.unit_of(name).strip()
        converted = stated and (scale, offset) != (1.0, 0.0) and np.mean(~as_written | missing) <= MAX_BAD_FRACTION
        if not converted and np.mean(alive) <= max_bad_fraction:
            return _said_bad(name, values, bad, missing, open_circuit, number, notes)
        msg = (
            f"{source}: sensor {name!r}: {int(bad.sum())} of {len(values)} samples are empty, NaN or "
            f"open-circuit (outside {OPEN_CIRCUIT_LOW_C:g}..{OPEN_CIRCUIT_HIGH_C:g} °C); "
            + (
                "they were converted to °C from the unit stated, and as written they lie within that range: if the "
                "log is in °C, leave the unit out (`temperature_unit`)"
                if converted
                else "check the wiring or leave this sensor out with `sensors`"
            )
        )
        raise InputError(msg)
    return _said_bad(name, values, bad, missing, open_circuit, number, notes)


def _refuse_other_units(
    name: str, cells: list[str], conversion: tuple[float, float], number: np.ndarray, source: str
) -> None:
    """InputError for a reading that carries a temperature unit other than its column's ("23.1 °F" among
    "°C" cells: read as 23.1 °C, without a word)."""
    for row, cell in enumerate(cells):
        unit = carried_unit(cell)
        if unit is None or (own := celsius_conversion(unit)) is None:
            continue
        if own != conversion:
            msg = (
                f"{source}: sensor {name!r}, row {number[row]}: {cell.strip()!r} carries another unit than the "
                "column's other readings; a column must be in one unit (export it again, or give the column in that "
                "unit alone)"
            )
            raise InputError(msg)


def _said_bad(
    name: str,
    values: FloatArray,
    bad: np.ndarray,
    missing: np.ndarray,
    open_circuit: np.ndarray,
    number: np.ndarray,
    notes: list[str],
) -> FloatArray:
    """The column with its bad readings NaN, and a note naming them."""
    if np.any(bad):
        runs = _row_runs(number[bad])
        rows = ", ".join(runs[:5]) + (", ..." if len(runs) > 5 else "")
        kinds = []
        if missing.any():
            kinds.append(f"{int(missing.sum())} empty/NaN")
        if open_circuit.any():
            kinds.append(f"{int(open_circuit.sum())} open-circuit")
        given = np.flatnonzero(~bad)
        if len(given) and given[-1] < len(bad) - 2:
            # bad to the log's end: a sensor that failed, not a few lost readings (a note of skipped
            # samples alone was read past, beside a learnt reference that rested on the readings before)
            notes.append(
                f"sensor {name!r} failed at row {int(number[given[-1] + 1])} and gave no reading to the log's end "
                f"(skipped {' and '.join(kinds)} sample(s), rows {rows}): what it is answered from, and learnt "
                "from, ends there"
            )
        else:
            notes.append(f"sensor {name!r}: skipped {' and '.join(kinds)} sample(s) (rows {rows})")
        values = np.where(bad, np.nan, values)
    return values


def _row_runs(rows: np.ndarray) -> list[str]:
    """Row numbers as runs of consecutive rows: "202-281" for a stretch of 80 lost readings, which
    as a list of its first five rows read as five."""
    if not len(rows):
        return []
    breaks = np.flatnonzero(np.diff(rows) != 1) + 1
    return [f"{int(run[0])}" if len(run) == 1 else f"{int(run[0])}-{int(run[-1])}" for run in np.split(rows, breaks)]
