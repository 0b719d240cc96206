"""Temperature logs: CSV with one time column and one column per sensor.

The time column is the first one unless ``time_col`` names another. Its unit is
minutes unless ``time_unit`` says otherwise or the header ends in ``_s``,
``_min`` or ``_h``; ISO-8601 timestamps are read as such, and so are dotted
day-first ones (``22.11.2026 08:00:00``) and times of day. Temperatures are °C
unless a units row or a column's name says K or °F, or ``temperature_unit`` does
for the columns that state no unit.
The file may be comma-, semicolon- or tab-separated, with a decimal comma, a
``#`` preamble and cp1252 text (:mod:`mtident.io.dialect`).

A pandas DataFrame (a notebook's table, its time as a column or as the index)
is read the same way.

Everything that can be wrong with a user's file is reported as an
:class:`~mtident.exceptions.InputError` naming the file, the column and the row.
Isolated bad samples (an empty or NaN cell, an open-circuit reading) are
replaced by NaN — the filters treat NaN as a missing measurement — and listed in
``TemperatureLog.notes`` so the CLI can say so on stderr.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.io.columns import (
    check_unique_names,
    missing_column,
    room_named,
    temperature_columns,
    text_only_cells,
)
from mtident.io.dialect import CsvDialect, read_csv
from mtident.io.layout import LogLayout, time_columns
from mtident.io.parse import OPEN_CIRCUIT_HIGH_C, OPEN_CIRCUIT_LOW_C
from mtident.io.stamps import (
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
    read_as_minutes,
    seconds_hint,
    serial_date_hint,
    serial_date_note,
    sparse_hint,
    time_unit_assumed,
    time_unit_factor,
    unit_overridden_note,
)
from mtident.io.units import number_without_unit

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

# What loggers write in place of a reading for a broken thermocouple or an overrange (Graphtec
# "BURNOUT"); the live follower reads any text as a missing reading.
OPEN_CIRCUIT_TEXT = (
    "burnout",
    "burn out",
    "open",
    "ol",
    "over",
    "+over",
    "-over",
    "overrange",
    "under",
    "+++++",
    "-----",
)
# What loggers and spreadsheets write in place of a reading they do not have (a dropped sample,
# a channel between scans): missing, like an empty cell.
MISSING_TEXT = ("-", "--", "---", "n/a", "na", "#n/a", "#na", "null", "none", "nan")
# Above this share of bad samples a sensor is refused rather than bridged.
MAX_BAD_FRACTION = 0.1


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

_STAMP_EXAMPLES = "(ISO 8601, 22.11.2026 08:00:00, 11/22/2026 08:00:00 AM or 08:00:00)"


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


def _cell(value: object) -> str:
    """A cell as the user wrote it: 4, not np.float64(4.0); text quoted."""
    if isinstance(value, (int, float, np.number)) and not isinstance(value, bool):
        return f"{value:g}"
    return repr(str(value))


def _parse_time(
    column: pd.Series,
    header: str,
    time_unit: str | None,
    source: str,
    first_row: int = 2,
    stated_unit: str | None = None,
    sub_second_min: FloatArray | None = None,
) -> tuple[FloatArray, list[str]]:
    """Minutes from the first sample, and notes (a summer-time change read); ``first_row``
    numbers the rows in messages (2: a CSV file's first data line); ``sub_second_min``: a
    millisecond column's part of each time (minutes)."""
    import pandas as pd

    notes: list[str] = []

    def minutes_since_first(stamps: pd.Series) -> FloatArray:
        answer: FloatArray = (stamps - stamps.iloc[0]).dt.total_seconds().to_numpy(dtype=float) / 60.0
        return answer

    numeric = pd.to_numeric(column, errors="coerce")
    if pd.api.types.is_timedelta64_dtype(column) or pd.api.types.is_datetime64_any_dtype(column):
        # a DataFrame's elapsed-time or time-stamp index, already parsed
        values = minutes_since_first(column)
    elif numeric.notna().all():
        values = numeric.to_numpy(dtype=float) * time_unit_factor(header, time_unit, stated_unit)
        serial = (
            serial_date_hint(header, values[0], float(np.median(np.diff(values))))
            if len(values) > 1 and time_unit_assumed(header, time_unit, stated_unit)
            else None
        )
        if serial is not None and names_a_date(header):
            notes.append(serial_date_note(header, float(values[0])))
            values = values * MINUTES_PER_DAY
        elif serial is not None:
            msg = f"{source}: {serial}"
            raise InputError(msg)
    else:
        text = column.astype(str).str.strip()
        empty = column.isna().to_numpy() | (text == "").to_numpy()
        if empty.any():
            row = int(empty.argmax())
            msg = f"{source}: time column {header!r}, row {row + first_row} is empty"
            raise InputError(msg)
        fmt = stamp_format(str(text.iloc[0]))
        if time_unit is not None:
            notes.append(f"time column {header!r} holds time stamps: the unit {time_unit!r} given for it is not used")
        # as UTC: stamps with offsets that change (summer time ends during the test) stay in order
        stamps = (
            pd.to_datetime(text, format=fmt, errors="coerce", utc=True)
            if fmt is not None
            else pd.Series(pd.NaT, index=text.index)
        )
        swapped = other_date_order(fmt)
        if swapped is not None:  # a slashed date: day and month the other way round, if that reads better
            other = pd.to_datetime(text, format=swapped, errors="coerce", utc=True)
            if other.notna().all() and (
                stamps.isna().any() or _longest_step(other) < min(_longest_step(stamps), IMPLAUSIBLE_STEP_MIN)
            ):
                stamps = other
        elapsed = (
            [elapsed_minutes(str(cell)) for cell in text] if fmt in TIME_OF_DAY_FORMATS and stamps.isna().any() else []
        )
        if elapsed and None not in elapsed:
            # a clock that runs past 24:00:00 is elapsed time since the start of the test
            notes.append(f"time column {header!r} read as hours:minutes:seconds elapsed (it runs past 24:00:00)")
            values = np.array(elapsed, dtype=float)
        elif stamps.isna().any():
            row = int(stamps.isna().to_numpy().argmax())
            msg = (
                f"{source}: time column {header!r}, row {row + first_row}: {_cell(column.iloc[row])} is neither a "
                "number "
                f"nor a time stamp {'like the first one' if fmt is not None and row > 0 else _STAMP_EXAMPLES}"
            )
            raise InputError(msg)
        else:
            values = minutes_since_first(stamps)
            if fmt in TIME_OF_DAY_FORMATS:
                previous: float | None = None
                for k, t in enumerate(values):  # row by row, as the live follower reads them
                    values[k] = previous = after_midnight(previous, float(t))
            elif not has_utc_offset(str(text.iloc[0])) and len(values) > 2:
                values = _across_clock_changes(values, stamps.iloc[0].timestamp() / 60.0, column, first_row, notes)
    if sub_second_min is not None:
        values = values + sub_second_min
    steps = np.diff(values)
    if np.any(steps == 0):
        row = int(np.argmax(steps == 0)) + 1
        msg = f"{source}: time column {header!r}, row {row + first_row}: duplicate time {_cell(column.iloc[row])}"
        raise InputError(msg)
    if np.any(steps < 0):
        row = int(np.argmax(steps < 0)) + 1
        msg = (
            f"{source}: time column {header!r}, row {row + first_row}: time goes back ({_cell(column.iloc[row - 1])} "
            f"then {_cell(column.iloc[row])}); time must increase: sort the rows by time, or, after a logger's "
            "clock was reset, cut the log there and give the part you want"
        )
        raise InputError(msg)
    return values - values[0], notes


def _across_clock_changes(
    values: FloatArray, first_min: float, column: pd.Series, first_row: int, notes: list[str]
) -> FloatArray:
    """Minutes from the first local stamp (written without an offset) with the clock's summer-time
    changes taken out (:func:`~mtident.io.stamps.clock_change`); a note for each, naming the row
    and its cells. ``first_min``: the first stamp in minutes since 1970 as written."""
    steps = np.diff(values)
    shifted = values.copy()
    for k in np.flatnonzero((steps <= 0) | (steps > 59.0)) + 1:
        # the step before, as read (the follower knows no other when the row comes)
        interval = float(shifted[k - 1] - shifted[k - 2]) if k >= 2 else None
        shift = clock_change(first_min + values[k - 1], first_min + values[k], interval)
        if shift:
            shifted[k:] += shift
            notes.append(
                clock_change_note(shift, f"at row {k + first_row}", _cell(column.iloc[k - 1]), _cell(column.iloc[k]))
            )
    return shifted


def _rows_with_readings(frame: pd.DataFrame, header: str, sensors: list[str]) -> np.ndarray:
    """Rows to read: all but those without a reading in any sensor that come at the end of the
    log or repeat a neighbour's time (HOBO writes its events, "Host Connected", "End Of File", as
    rows of their own, at the time of the read-out, several at one time)."""
    import pandas as pd

    # a blank cell is text ("" or spaces) only in a column pandas did not read as numbers
    empty = np.ones(len(frame), dtype=bool)
    for name in sensors:
        column = frame[name]
        blank = (
            column.isna()
            if pd.api.types.is_numeric_dtype(column)
            else column.isna() | (column.astype(str).str.strip() == "")
        )
        empty &= blank.to_numpy()
    if empty.all():
        return np.ones(len(frame), dtype=bool)
    times = frame[header].astype(str).to_numpy()
    repeated = np.zeros(len(frame), dtype=bool)
    repeated[1:] |= times[1:] == times[:-1]
    repeated[:-1] |= times[:-1] == times[1:]
    trailing = np.flip(np.cumprod(np.flip(empty)).astype(bool))
    answer: np.ndarray = ~(empty & (repeated | trailing))
    return answer


def _longest_step(stamps: pd.Series) -> float:
    """The largest step between neighbouring valid stamps, back or forth (min)."""
    valid = stamps.dropna()
    minutes = valid.diff().dt.total_seconds().to_numpy()[1:] / 60.0
    return float(np.max(np.abs(minutes))) if len(minutes) else 0.0


def _text_only(column: pd.Series) -> bool:
    """Whether a column holds text and not one number (empty cells aside)."""
    import pandas as pd

    return not pd.api.types.is_numeric_dtype(column) and text_only_cells(column.dropna().astype(str).tolist())


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


def _sensor_readings(
    frame: pd.DataFrame,
    name: str,
    dialect: CsvDialect,
    conversion: FloatArray,
    source: str,
    first_row: int,
    notes: list[str],
) -> FloatArray:
    """A sensor's column in °C (by ``conversion``, the layout's (scale, offset): from its own unit,
    else the one given), NaN for an empty or open-circuit cell (said in ``notes``); an error naming
    the first cell that is no number, or a column mostly empty."""
    import pandas as pd

    raw = frame[name]
    scale, offset = float(conversion[0]), float(conversion[1])
    # One bad cell leaves a decimal-comma column as text: its good cells must still read as numbers
    # (the message named the first good cell, '20,00', instead of the bad one).
    cells = raw
    if dialect.units_in_cells and not pd.api.types.is_numeric_dtype(raw):  # "13.1 °C"
        cells = raw.astype(str).map(number_without_unit).where(raw.notna())
    if dialect.decimal == "," and not pd.api.types.is_numeric_dtype(cells):
        cells = cells.astype(str).str.replace(",", ".", regex=False).where(cells.notna())
    values: FloatArray = scale * pd.to_numeric(cells, errors="coerce").to_numpy(dtype=float) + offset
    text = raw.astype(str).str.strip().str.lower()
    marked_open = text.isin(OPEN_CIRCUIT_TEXT).to_numpy()
    marked_missing = text.isin([*MISSING_TEXT, ""]).to_numpy()
    non_numeric = np.isnan(values) & raw.notna().to_numpy() & ~marked_missing & ~marked_open
    if np.any(non_numeric):
        row = int(np.argmax(non_numeric))
        msg = f"{source}: sensor {name!r}, row {row + first_row}: {_cell(raw.iloc[row])} is not a number"
        raise InputError(msg)
    missing = np.isnan(values) & ~marked_open
    open_circuit = (values > OPEN_CIRCUIT_HIGH_C) | (values < OPEN_CIRCUIT_LOW_C) | marked_open
    bad = missing | open_circuit
    if np.mean(bad) > MAX_BAD_FRACTION:
        msg = (
            f"{source}: sensor {name!r}: {int(bad.sum())} of {len(values)} samples are empty, NaN or "
            f"open-circuit (outside {OPEN_CIRCUIT_LOW_C:g}..{OPEN_CIRCUIT_HIGH_C:g} °C); check the wiring "
            "or leave this sensor out with `sensors`"
        )
        raise InputError(msg)
    if np.any(bad):
        rows = ", ".join(str(int(r) + first_row) for r in np.flatnonzero(bad)[:5])
        kinds = []
        if missing.any():
            kinds.append(f"{int(missing.sum())} empty/NaN")
        if open_circuit.any():
            kinds.append(f"{int(open_circuit.sum())} open-circuit")
        notes.append(
            f"sensor {name!r}: skipped {' and '.join(kinds)} sample(s) (rows {rows}{', ...' if bad.sum() > 5 else ''})"
        )
        values = np.where(bad, np.nan, values)
    return values


def read_temperature_log(
    path: str | Path | pd.DataFrame,
    time_col: str | None = None,
    time_unit: str | None = None,
    min_samples: int = 5,
    sensors: list[str] | None = None,
    temperature_unit: str | None = None,
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

    Returns
    -------
    TemperatureLog

    Raises
    ------
    InputError
        Missing or unreadable file, no such column, no sensor column, non-numeric
        cells, time not increasing or duplicated, too few samples, too many bad
        samples in a sensor, a column's own unit that ``temperature_unit``
        contradicts.
    """
    read_notes: list[str] = []
    frame, dialect, source, first_row = _as_frame(path, read_notes)
    notes: list[str] = [renamed] if (renamed := dialect.renaming()) else []
    notes.extend(read_notes)
    names = [str(c) for c in frame.columns]
    first_cells = list(frame.iloc[0]) if len(frame) else []
    (at, clock_at, milliseconds_at), left_out, time_notes = time_columns(names, first_cells, dialect, time_col, source)
    notes.extend(time_notes)
    if len(frame) < min_samples:
        msg = f"{source}: {len(frame)} samples; at least {min_samples} are needed"
        raise InputError(msg)
    header, clock = names[at], None if clock_at is None else names[clock_at]
    sub_second = None if milliseconds_at is None else _sub_second_min(frame, names[milliseconds_at], source, first_row)
    available = [c for c in names if c not in left_out]
    missing_names = [n for n in sensors or [] if n not in available]
    if missing_names:
        msg = missing_column(source, missing_names[0], available)
        raise InputError(msg)
    if not sensors:
        available = _sensor_candidates(frame, available, notes)
    sensors, unit_notes = temperature_columns(
        list(sensors) if sensors else available, bool(sensors), dialect, source, temperature_unit
    )
    notes.extend(unit_notes)
    keep = _rows_with_readings(frame, header, sensors)
    if not keep.all():
        notes.append(
            f"left out {int((~keep).sum())} row(s) without a reading at the end or at a repeated time (a logger's "
            "events: coupler, host connected, end of file)"
        )
        frame = frame[keep]
        sub_second = None if sub_second is None else sub_second[keep]
    repeated = frame.duplicated().to_numpy()
    if repeated.any():
        # a logger that writes a row twice (a buffer flushed again): the copy adds nothing
        rows = ", ".join(str(int(r) + first_row) for r in frame.index[repeated][:5])
        notes.append(f"left out {int(repeated.sum())} row(s) repeating an earlier row exactly (rows {rows})")
        frame = frame[~repeated]
        sub_second = None if sub_second is None else sub_second[~repeated]
    layout = LogLayout(
        dialect,
        tuple(names),
        at,
        clock_at,
        milliseconds_at,
        tuple(sensors),
        tuple(names.index(name) for name in sensors),
        time_unit,
        temperature_unit,
    )
    time_min = _time_min(frame, layout, source, first_row, sub_second, notes)
    if (gap := gap_note(time_min)) is not None:
        notes.append(gap)
    conversions = layout.conversions()
    columns = [
        _sensor_readings(frame, name, dialect, conversions[k], source, first_row, notes)
        for k, name in enumerate(sensors)
    ]
    if (scale := scale_note(sensors, np.column_stack(columns), dialect, temperature_unit)) is not None:
        notes.append(scale)
    return TemperatureLog(
        time_min,
        tuple(sensors),
        np.column_stack(columns),
        tuple(notes),
        source,
        header if clock is None else f"{header} + {clock}",
    )


def scale_note(
    sensors: list[str], values: FloatArray, dialect: CsvDialect, temperature_unit: str | None = None
) -> str | None:
    """What a reader says when columns read as °C for want of a stated unit read far outside any
    workshop's range (``WORKSHOP_ROOM_C``): a column named as the room (:func:`room_named`), or
    every column above the range's top (at a warm-up's start the machine is near the room). A log in
    °F (a room at 69) or K was taken as °C without a word. None otherwise, and where the user
    stated the unit (``temperature_unit``).

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
    if temperature_unit is not None:
        return None
    assumed = [k for k, name in enumerate(sensors) if not dialect.unit_of(name).strip()]
    spans = {}
    for k in assumed:
        valid = values[:, k][np.isfinite(values[:, k])]
        if len(valid):
            spans[k] = (float(np.min(valid)), float(np.median(valid)), float(np.max(valid)))
    rooms = [k for k in spans if room_named(sensors[k]) and not low <= spans[k][1] <= high]
    if rooms:
        which = "; ".join(f"{sensors[k]!r} reads {spans[k][0]:g} to {spans[k][2]:g}" for k in rooms) + " as the room"
    elif spans and len(spans) == len(sensors) and all(span[0] > high for span in spans.values()):
        which = (
            f"every column reads above {high:g} °C (the lowest {min(span[0] for span in spans.values()):g}), "
            "none near the room"
        )
    else:
        return None
    return (
        f"readings taken as °C (the log states no unit), but {which}: far outside any workshop's range "
        f"({low:g} to {high:g} °C). If the log is in °F (or K), state the unit and it is converted: "
        "`temperature_unit='F'` (or `temperature_unit='K'`), a units row under the header (min;°F;°F) or the unit "
        "in the column names (Room [°F])"
    )


def _as_frame(path: str | Path | pd.DataFrame, notes: list[str]) -> tuple[pd.DataFrame, CsvDialect, str, int]:
    """The log as a table with stripped column names, its dialect, its name for the messages and
    the row number a message gives its first data row; what the file's reader left out goes to
    ``notes`` (a cut last line)."""
    import pandas as pd  # here, not at import: 0.4 s of start-up that `watch` does not need

    first_row = 1  # in messages, a CSV file's first data line is its row 2 (after the header)
    dialect = CsvDialect()
    if isinstance(path, pd.DataFrame):
        source, first_row = "DataFrame", 0
        # a time index (set_index, resample) is the time column too
        frame = path.reset_index() if path.index.name is not None else path.copy()
    else:
        if isinstance(path, str) and path in SAMPLES:
            path = sample_log_path(path)
        source = str(path)
        frame, dialect = read_csv(path, notes)
        first_row += dialect.head_lines
    frame.columns = [str(c).strip() for c in frame.columns]
    if isinstance(path, pd.DataFrame):  # a CSV file's header was checked by read_csv, before pandas renamed a repeat
        check_unique_names(list(frame.columns), source)
    if frame.shape[0] == 0 and not isinstance(path, pd.DataFrame):
        msg = f"{source}: no data rows, only a header or a logger's preamble (is the test still to start?)"
        raise InputError(msg)
    if frame.shape[1] < 2:
        msg = (
            f"{source}: need a time column and at least one sensor column, separated by ',', ';' or tabs; found "
            f"columns: {', '.join(frame.columns)}"
        )
        raise InputError(msg)
    return frame, dialect, source, first_row


def _sub_second_min(frame: pd.DataFrame, column: str, source: str, first_row: int) -> FloatArray:
    """A logger's millisecond column, in minutes; an error naming its first cell that is no number."""
    import pandas as pd

    values = pd.to_numeric(frame[column], errors="coerce").to_numpy(dtype=float)
    if np.isnan(values).any():
        row = int(np.isnan(values).argmax())
        msg = (
            f"{source}: millisecond column {column!r}, row {row + first_row}: "
            f"{_cell(frame[column].iloc[row])} is not a number"
        )
        raise InputError(msg)
    answer: FloatArray = values / 60_000.0
    return answer


def _sensor_candidates(frame: pd.DataFrame, available: list[str], notes: list[str]) -> list[str]:
    """The columns that may be sensors where none were asked for: a column of text alone (a
    logger's status or comment channel) or one that logged nothing (HOBO's "Coupler Detached") is
    left out, and said in ``notes``, unless every column is such."""
    text_only = [name for name in available if _text_only(frame[name])]
    if text_only and len(text_only) < len(available):
        notes.append(f"left out, no numbers in them: {', '.join(text_only)}")
        available = [name for name in available if name not in text_only]
    empty = [name for name in available if frame[name].isna().all()]
    if empty and len(empty) < len(available):
        notes.append(f"left out, no readings in them: {', '.join(empty)}")
        available = [name for name in available if name not in empty]
    return available


def _time_min(
    frame: pd.DataFrame,
    layout: LogLayout,
    source: str,
    first_row: int,
    sub_second: FloatArray | None,
    notes: list[str],
) -> FloatArray:
    """The log's times in minutes from its time column, or from a date column and the time of day
    in the next (the layout's clock column); what was assumed goes to ``notes``."""
    import pandas as pd

    header, time_unit = layout.time_name, layout.time_unit
    clock = None if layout.clock_column is None else layout.header[layout.clock_column]

    if clock is not None:
        stamps = frame[header].astype(str).str.strip() + " " + frame[clock].astype(str).str.strip()
        time_min, time_notes = _parse_time(
            stamps.where(frame[header].notna() & frame[clock].notna()),
            f"{header} + {clock}",
            time_unit,
            source,
            first_row,
            sub_second_min=sub_second,
        )
        notes.extend(time_notes)
        return time_min
    stated = layout.dialect.time_unit(header)
    time_min, time_notes = _parse_time(frame[header], header, time_unit, source, first_row, stated, sub_second)
    notes.extend(time_notes)
    if (overridden := unit_overridden_note(header, time_unit, stated)) is not None:
        notes.append(overridden)
    numeric = pd.api.types.is_numeric_dtype(frame[header]) and not pd.api.types.is_timedelta64_dtype(frame[header])
    if numeric and time_unit_assumed(header, time_unit, stated):
        span = float(time_min[-1] - time_min[0])
        if time_min[-1] > UNLIKELY_MINUTES:
            notes.append(seconds_hint(header, float(time_min[-1])))
        elif (hint := hours_hint(header, span, len(time_min)) or sparse_hint(header, time_min)) is not None:
            notes.append(hint)
    return time_min
