"""A log's data lines into rows: one pure function, :func:`parse_lines`, over the log's layout
(:class:`~mtident.io.layout.LogLayout`) and how far its time column has been read
(:class:`TimeState`), for the live follower and the file reader alike.

The lines are split into cells and their readings read as numbers in one way
(:mod:`mtident.io.cells`). A live log's rows come in the order written and are read one by one,
as a logger writes them, so that lines read in pieces (a live log, polled) give the rows and
notes of the lines read at once:

* a row whose time cannot be read is refused with a warning;
* a row at or before the last time taken is refused with a warning (quietly after a restart,
  where the log is read again from its start);
* a summer-time change of a local clock between two rows is taken out, with a note;
* spreadsheet serial dates in a column named as dates are read in days, told at the second row;
* a slashed date read the wrong way round (month first for day first) is read again the other way
  where that steps on plausibly;
* a reading that is empty, no number or an open circuit's is NaN, with a note per sensor.

A whole log (:class:`WholeLog`, the file reader's) is read at once, by its columns, and what the
follower passes over with a warning is an error naming the row (:mod:`mtident.io.whole`).
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.io import stamps
from mtident.io.cells import OPEN_CIRCUIT_HIGH_C, OPEN_CIRCUIT_LOW_C, column, numbers, split_rows
from mtident.io.layout import LogLayout, refuse_grouped_time
from mtident.io.log_file import cut_short_words, rows_cut_short
from mtident.io.time_notes import gap_said, names_a_date, serial_date_hint, serial_date_note
from mtident.io.whole import MAX_BAD_FRACTION, read_whole

__all__ = ["TimeState", "ParsedRows", "WholeLog", "parse_lines", "OPEN_CIRCUIT_HIGH_C", "OPEN_CIRCUIT_LOW_C"]


@dataclass(frozen=True, slots=True)
class TimeState:
    """How far a log's time column has been read.

    Attributes
    ----------
    origin : float or None
        The first sample's time as read (min; from 1970 for time stamps), which is t = 0.
    last_time : float or None
        The last row's time (min from ``origin``).
    time_format : str or None
        pandas format of the time stamps, from the first one; None for a numeric time column.
    first_stamp : str or None
        The first time stamp as written (a slashed date may have to be read again day first).
    clock_shift : float
        Minutes added to the stamps since summer time ended (+60) or began (−60) during the log.
    last_step : float or None
        Minutes between the last two rows taken (a clock change is told against it).
    serial_days : bool
        The time column, named as dates, holds spreadsheet serial dates, read in days.
    last_stamp : str or None
        The last row's time cell(s) as written, for a note on a clock change.
    """

    origin: float | None = None
    last_time: float | None = None
    time_format: str | None = None
    first_stamp: str | None = None
    clock_shift: float = 0.0
    last_step: float | None = None
    serial_days: bool = False
    last_stamp: str | None = None


@dataclass(frozen=True, slots=True)
class ParsedRows:
    """The rows of some data lines.

    Attributes
    ----------
    time_min : ndarray, shape (n,)
        Times of the rows taken (min from the first sample ever read).
    temperature_C : ndarray, shape (n, S)
        Their readings (°C; NaN: empty, no number or an open circuit's), one column per sensor.
    notes : tuple of str
        What was found out (a clock change, serial dates, a gap, readings skipped).
    warnings : tuple of str
        Rows refused: an unreadable time, a time that repeats or goes back.
    """

    time_min: FloatArray
    temperature_C: FloatArray
    notes: tuple[str, ...] = ()
    warnings: tuple[str, ...] = ()


@dataclass(frozen=True, slots=True)
class WholeLog:
    """Lines that are a whole log, read at once (the file reader's): a time or a reading that
    cannot be read, and a time that repeats or goes back, is an error naming its row; rows without
    readings at the end or at a repeated time, and rows written twice, are left out with a note.

    Attributes
    ----------
    first_row : int
        The number messages give the first data line (a CSV file's line after its header and the rows
        under it; 0 for a table's first row). Blank lines are not counted.
    """

    first_row: int
    max_bad_fraction: float = MAX_BAD_FRACTION


def parse_lines(
    layout: LogLayout,
    state: TimeState,
    lines: list[str],
    source: str | Path,
    restarted: bool = False,
    whole: WholeLog | None = None,
) -> tuple[TimeState, ParsedRows]:
    """The rows of a log's data lines, and the time state after them.

    Parameters
    ----------
    layout : LogLayout
        How the log's rows are read.
    state : TimeState
        How far the time column was read before these lines (``TimeState()`` for the first).
    lines : list of str
        Complete data lines, as text, without their line breaks (blank ones are passed over).
    source : str or Path
        The log, for the messages.
    restarted : bool, optional
        The lines are the log read again from its start (a logger restarted): rows at or before
        the last time taken are passed over quietly, and summer-time changes found again.
    whole : WholeLog or None, optional
        The lines are a whole log, read from ``TimeState()``, its rows numbered in messages as this says.

    Returns
    -------
    state : TimeState
        How far the time column is read after them.
    rows : ParsedRows
        The rows taken, notes and warnings (none for a whole log).

    Raises
    ------
    InputError
        Spreadsheet serial dates in a column not named as dates (the unit to give is said); in a whole
        log, a time or a reading that cannot be read, a time that repeats or goes back, a sensor with
        too many bad readings.
    """
    if whole is not None:
        return _whole_log(layout, split_rows(lines, layout.dialect, len(layout.header)), str(source), whole)
    # the file reader leaves out a row cut short inside the log (read_lines); a follower, here
    short = set(rows_cut_short(lines, layout.dialect))
    warnings = [f"{source}: refused the row {cut_short_words(lines[k], layout.dialect)}" for k in sorted(short)]
    rows = split_rows((line for k, line in enumerate(lines) if k not in short), layout.dialect, len(layout.header))
    rows, said = _without_wide_rows(layout, _without_headers(layout, rows, source), source)
    state, parsed = _live_rows(layout, state, rows, source, restarted)
    warnings += said
    return state, replace(parsed, warnings=(*warnings, *parsed.warnings)) if warnings else parsed


def _without_headers(layout: LogLayout, rows: list[list[str]], source: str | Path) -> list[list[str]]:
    """The rows less a header written again (a logger restarted): the same names are passed over;
    other names are an error, for the rows after them would be read under the first header's names
    (a column added before the room's fed the room's readings from it, and the test stopped)."""
    names = [name.strip() for name in layout.header]
    time_name = names[layout.time_column]
    kept = []
    for row in rows:
        cells = [cell.strip() for cell in row]
        if len(cells) <= layout.time_column or cells[layout.time_column] != time_name:
            kept.append(row)
            continue
        written = [cell for cell in cells if cell]
        if written != [name for name in names if name and not name.startswith("Unnamed: ")]:
            msg = (
                f"{source}: a new header ({', '.join(written)}) where the log's is ({', '.join(names)}): the logger's "
                "columns changed, and the rows after it would be read under the first header's names. Watch the rows "
                "after it as a log of their own"
            )
            raise InputError(msg)
    return kept


def _without_wide_rows(
    layout: LogLayout, rows: list[list[str]], source: str | Path
) -> tuple[list[list[str]], list[str]]:
    """The rows less those with more cells than the header where the cells past it hold something
    (the file reader refuses the log: :func:`~mtident.io.log_file.read_lines`), and one warning for
    them: read to the header's width, a comma-separated row with decimal commas fed one sensor's
    integer parts as its readings and its decimals as the next sensor's."""
    width = len(layout.header)
    too_wide = [len(row) > width and any(cell.strip() for cell in row[width:]) for row in rows]
    if not any(too_wide):
        return rows, []
    wide = [row for row, refused in zip(rows, too_wide, strict=True) if refused]
    hint = " (decimal commas in a comma-separated log?)" if layout.dialect.delimiter == "," else ""
    said = (
        f"{source}: refused {len(wide)} row(s) with more cells than the header's {width} (the first has "
        f"{len(wide[0])}){hint}: their readings would land under the wrong names"
    )
    return [row for row, refused in zip(rows, too_wide, strict=True) if not refused], [said]


def _live_rows(
    layout: LogLayout, state: TimeState, rows: list[list[str]], source: str | Path, restarted: bool
) -> tuple[TimeState, ParsedRows]:
    """A live log's rows one by one, as a logger writes them (the rules of the module's docstring)."""
    notes: list[str] = []
    warnings: list[str] = []
    numeric_scale = layout.time_scale()
    times: list[float] = []
    taken: list[list[str]] = []
    if restarted:
        state = replace(state, clock_shift=0.0)
    # the previous row's time as the clock wrote it (minutes from the first row) and its cell: a
    # summer-time change is a step between two rows; a log read again from its start after a
    # restart finds its changes again
    previous_raw = None if restarted or state.last_time is None else state.last_time - state.clock_shift
    previous_cell = None if restarted else state.last_stamp
    back: list[tuple[float, float]] = []
    for line in rows:
        if all(not c.strip() for c in line):
            continue
        stamped = _row_time(layout, state, line, numeric_scale, source, notes)
        if stamped is None:
            warnings.append(f"{source}: refused a row with an unreadable time {line[:1]!r}")
            continue
        state, raw, cell = stamped
        if previous_raw is not None:
            state = _follow_clock_change(state, previous_raw, raw, previous_cell, cell, notes)
        t = raw + state.clock_shift
        if state.last_time is not None and t <= state.last_time:
            if not restarted:  # after a restart the old rows come again: expected, not an error
                _refuse_clock_restart(state, t, source)
                back.append((t, state.last_time))
            else:
                previous_raw, previous_cell = raw, cell
            continue
        if state.last_time is not None and state.last_step is not None:
            if (gap := gap_said(t - state.last_time, state.last_time, state.last_step)) is not None:
                notes.append(gap)
        state = replace(
            state, last_step=None if state.last_time is None else t - state.last_time, last_time=t, last_stamp=cell
        )
        previous_raw, previous_cell = raw, cell
        times.append(t)
        taken.append(line)
    if len(back) == 1:
        warnings.append(
            f"{source}: refused the row at t = {back[0][0]:g} min: it repeats or goes back from t = {back[0][1]:g} min"
        )
    elif back:
        warnings.append(
            f"{source}: refused {len(back)} rows that repeat or go back (the first at t = {back[0][0]:g} min after "
            f"t = {back[0][1]:g} min, the last at t = {back[-1][0]:g} min after t = {back[-1][1]:g} min)"
        )
    values = _readings(layout, taken)
    # readings lost are a warning: a JSON reader finds them among the watch's log_warnings
    warnings.extend(_skipped_notes(layout.sensors, np.array(times), values))
    return state, ParsedRows(np.array(times), values, tuple(notes), tuple(warnings))


RESTART_STEPS = 10
"""A time that goes back by more than this many sampling steps, and by more than half the log so far,
is a logger whose clock restarted, not a row out of order."""


def _refuse_clock_restart(state: TimeState, t: float, source: str | Path) -> None:
    """An error where a row's time goes back so far that the logger's clock restarted: the rows after
    it are another run's, at times the log cannot place (read on, a restarted row at its own time
    200 min was taken for the first run's, where it was the 400th minute)."""
    last, step = state.last_time, state.last_step
    if last is None or step is None or last - t <= max(RESTART_STEPS * step, 0.5 * last):
        return
    # a clock of 12 hours written without AM or PM goes back by 12 hours at 12:59 to 01:00
    twelve = abs(last - t - 720.0) <= 2.0 * step + 1.0
    why = "a 12-hour clock written without AM or PM?" if twelve else "a logger restarted with its clock?"
    way_on = (
        "log the time with AM/PM or on a 24-hour clock"
        if twelve
        else "the rows after it are another run's, at times this log cannot place. Watch them as a log of their own"
    )
    msg = f"{source}: the time went back from t = {last:g} min to {t:g} min ({why}): {way_on}"
    raise InputError(msg)


def _whole_log(layout: LogLayout, rows: list[list[str]], source: str, whole: WholeLog) -> tuple[TimeState, ParsedRows]:
    """A whole log's rows at once (:mod:`mtident.io.whole`), and the time state after them."""
    time, values, notes = read_whole(layout, rows, source, whole.first_row, whole.max_bad_fraction)
    steps = np.diff(time.time_min)
    state = TimeState(
        time.origin,
        float(time.time_min[-1]),
        time.time_format,
        time.first_stamp,
        time.clock_shift,
        float(steps[-1]) if len(steps) else None,
        time.serial_days,
        time.last_cell,
    )
    return state, ParsedRows(time.time_min, values, tuple(notes))


def _row_time(
    layout: LogLayout,
    state: TimeState,
    line: list[str],
    numeric_scale: tuple[float, bool],
    source: str | Path,
    notes: list[str],
) -> tuple[TimeState, float, str] | None:
    """A row's time as its clock wrote it (minutes), its time cell(s) and the state after it; None
    for a row whose time cannot be read."""
    try:
        cell = (
            line[layout.time_column].strip()
            if layout.clock_column is None
            else f"{line[layout.time_column].strip()} {line[layout.clock_column].strip()}"
        )
        state, t = _parse_time(layout, state, cell, numeric_scale, source, notes)
        if layout.millisecond_column is not None:
            t += layout.dialect.number(line[layout.millisecond_column]) / 60_000.0
    except InputError:  # a ValueError too, but about the whole log, not this row
        raise
    except (ValueError, IndexError):
        return None
    return state, t, cell


def _parse_time(
    layout: LogLayout,
    state: TimeState,
    text: str,
    numeric_scale: tuple[float, bool],
    source: str | Path,
    notes: list[str],
) -> tuple[TimeState, float]:
    """Minutes relative to the first sample, and the state after it; ValueError for an unreadable
    cell; what it finds out about the time column (serial dates read as days) goes to ``notes``."""
    try:
        raw = layout.dialect.number(text)
        refuse_grouped_time(text, layout.dialect.decimal, layout.time_name, source)
        scale, assumed = (stamps.MINUTES_PER_DAY, False) if state.serial_days else numeric_scale
        stamp = raw * scale
    except ValueError:
        if state.time_format is None:
            state = replace(state, time_format=stamps.stamp_format(text), first_stamp=text.strip())
        if state.time_format is None:
            raise
        state, stamp = _stamp_minutes(state, text.strip())
    else:
        # spreadsheet serial dates are told at the second row
        serial = None
        if state.origin is not None and state.last_time == 0.0 and assumed:
            serial = serial_date_hint(layout.time_name, state.origin, stamp - state.origin)
        if serial is not None and names_a_date(layout.time_name):
            # read in days from here on, the first row's too (it is t = 0 whatever its unit)
            assert state.origin is not None
            notes.append(serial_date_note(layout.time_name, state.origin))
            state = replace(state, serial_days=True, origin=state.origin * stamps.MINUTES_PER_DAY)
            stamp = raw * stamps.MINUTES_PER_DAY
        elif serial is not None:
            msg = f"{source}: {serial}"
            raise InputError(msg)
    if state.origin is None:
        state = replace(state, origin=stamp)
    assert state.origin is not None
    t = stamp - state.origin
    if state.time_format in stamps.TIME_OF_DAY_FORMATS:
        t = stamps.after_midnight(state.last_time, t)
    return state, t


def _stamp_minutes(state: TimeState, text: str) -> tuple[TimeState, float]:
    """A time stamp in minutes since 1970 in the log's format, and the state after it; ValueError
    if it is none.

    A slashed date read as the first stamp told that does not parse, or jumps by weeks, is read
    with day and month swapped where that steps on plausibly (01/12 then 02/12 just after
    midnight: a day, not a month); from then on the other order is used, and t = 0 is the first
    stamp read that way.
    """
    import pandas as pd  # only for time stamps

    def minutes(cell: str, fmt: str | None) -> float:
        return float(pd.to_datetime(cell, format=fmt, utc=True).timestamp() / 60.0)

    swapped = stamps.other_date_order(state.time_format)
    if swapped is None or state.first_stamp is None or state.origin is None or state.last_time is None:
        try:
            return state, minutes(text, state.time_format)
        except ValueError:
            elapsed = stamps.elapsed_minutes(text) if state.time_format in stamps.TIME_OF_DAY_FORMATS else None
            if elapsed is None:
                raise
            # a clock past 24:00:00 is elapsed time: on from the day a time of day is read on
            return state, stamps.CLOCK_DAY_ZERO_MIN + elapsed
    stamp: float | None
    try:
        stamp = minutes(text, state.time_format)
        if stamp - state.origin - state.last_time < stamps.IMPLAUSIBLE_STEP_MIN:
            return state, stamp
    except ValueError:
        stamp = None
    try:
        origin, turned = minutes(state.first_stamp, swapped), minutes(text, swapped)
    except ValueError:
        origin = turned = float("nan")
    if not 0.0 < turned - origin - state.last_time < stamps.IMPLAUSIBLE_STEP_MIN:
        if stamp is None:
            raise ValueError(text)
        return state, stamp
    return replace(state, time_format=swapped, origin=origin), turned


def _local_dated_stamps(state: TimeState) -> bool:
    """Whether the log's times are dated stamps of a local clock, written without their offset
    from UTC: the clock may change for summer time during the log."""
    return (
        state.time_format is not None
        and state.time_format not in stamps.TIME_OF_DAY_FORMATS
        and not stamps.has_utc_offset(state.first_stamp or "")
    )


def _follow_clock_change(
    state: TimeState, previous_raw: float, raw: float, previous_cell: str | None, cell: str, notes: list[str]
) -> TimeState:
    """A step between two rows of local date stamps that a summer-time change explains shifts
    the clock (said once, not again on a re-read)."""
    if 0.0 < raw - previous_raw <= 59.0 or not _local_dated_stamps(state):
        return state
    assert state.origin is not None
    shift = stamps.clock_change(state.origin + previous_raw, state.origin + raw, state.last_step)
    if not shift:
        return state
    state = replace(state, clock_shift=state.clock_shift + shift)
    if state.last_time is None or raw + state.clock_shift > state.last_time:
        notes.append(
            stamps.clock_change_note(
                shift,
                f"after t = {previous_raw + state.clock_shift - shift:g} min",
                repr(previous_cell or "the row before"),
                repr(cell),
            )
        )
    return state


def _readings(layout: LogLayout, rows: list[list[str]]) -> FloatArray:
    """The rows' temperatures in °C (NaN: empty, unreadable, or an open circuit's reading)."""
    values = np.empty((len(rows), len(layout.sensors)))
    for k, ((scale, offset), index) in enumerate(zip(layout.conversions(), layout.sensor_columns, strict=True)):
        celsius = scale * numbers(column(rows, index), layout.dialect) + offset
        values[:, k] = np.where((celsius >= OPEN_CIRCUIT_LOW_C) & (celsius <= OPEN_CIRCUIT_HIGH_C), celsius, np.nan)
    return values


def _skipped_notes(sensors: tuple[str, ...], time_min: FloatArray, values: FloatArray) -> list[str]:
    """A note per sensor with readings left out (empty, not a number, or an open circuit's)."""
    notes = []
    for name, readings in zip(sensors, values.T, strict=True):
        missing = np.flatnonzero(np.isnan(readings))
        if len(missing):
            notes.append(
                f"sensor {name!r}: skipped {len(missing)} empty, unreadable or open-circuit reading(s) (the first at "
                f"t = {time_min[missing[0]]:g} min)"
            )
    return notes
