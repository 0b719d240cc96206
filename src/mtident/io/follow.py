"""Following a CSV log that a data-acquisition program is still writing.

The follower never writes to the log. It remembers the byte offset of the last
complete line it read, the file's identity (device, inode) and the last time
stamp it accepted, so that:

* new rows are picked up on the next poll;
* a partly written last line (no newline yet) waits for its end;
* a truncated or replaced file (the logger restarted) is read again from its
  start, and rows at or before the last accepted time are skipped, so nothing is
  counted twice;
* a row that repeats a time stamp or goes back in time is refused with a warning.

The file's dialect (delimiter, decimal mark, preamble, encoding, time-stamp
format) is taken from its head as :func:`~mtident.io.logs.read_temperature_log`
takes it (:mod:`mtident.io.dialect`), so a live log and the finished file read
the same.

The position is a small dict (:meth:`LogFollower.position`) that the monitor
keeps in its state file to resume exactly where it was.
"""

from __future__ import annotations

import csv
import io
import os
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.io.columns import (
    check_unique_names,
    choose_time_column,
    millisecond_column,
    missing_column,
    sensor_unit,
    temperature_columns,
    text_only_cells,
)
from mtident.io.dialect import HEAD_BYTES, CsvDialect, binary_kind, sniff_dialect
from mtident.io.logs import (
    OPEN_CIRCUIT_HIGH_C,
    OPEN_CIRCUIT_LOW_C,
    SPARSE_HINT_ROWS,
    gap_said,
    names_a_date,
    serial_date_hint,
    serial_date_note,
    time_unit_assumed,
    time_unit_factor,
    unit_hint,
    unit_overridden_note,
)
from mtident.io.stamps import (
    CLOCK_DAY_ZERO_MIN,
    IMPLAUSIBLE_STEP_MIN,
    MINUTES_PER_DAY,
    TIME_OF_DAY_FORMATS,
    after_midnight,
    clock_change,
    clock_change_note,
    date_and_clock,
    elapsed_minutes,
    has_utc_offset,
    other_date_order,
    stamp_format,
)
from mtident.io.units import celsius_conversion

__all__ = ["LogFollower", "Rows"]


@dataclass(frozen=True)
class Rows:
    """New samples: times (minutes from the first sample ever read), temperatures (n, S), warnings,
    and notes (how the header was read: units converted, columns left out).

    Attributes
    ----------
    time_min : ndarray, shape (n,)
        Times of the new rows (min from the first sample ever read).
    temperature_C : ndarray, shape (n, S)
        Their readings (°C, converted from K or °F), one column per sensor in the follower's order.
    warnings : tuple of str
        What went wrong while reading (a truncated or replaced log, rows refused for an unreadable
        time or one that goes back, a time column that may be seconds).
    notes : tuple of str
        How the header and the time column were read.
    """

    time_min: FloatArray
    temperature_C: FloatArray
    warnings: tuple[str, ...] = ()
    notes: tuple[str, ...] = ()


def _dialect_to_save(dialect: CsvDialect) -> dict[str, object]:
    """The dialect for the state file, by its fields' names (JSON: its tuples as lists)."""
    return {
        name: [list(v) if isinstance(v, tuple) else v for v in value] if isinstance(value, tuple) else value
        for name, value in asdict(dialect).items()
    }


def _saved_dialect(saved: dict[str, Any] | list[Any]) -> CsvDialect:
    """The dialect as a state file keeps it: by its fields' names, or, in state files of
    earlier versions, as a list of its first fields. One written before units rows were read
    has four entries; one written before the rows under the header were counted, five (a units
    row, if any); one written before the channels' names under the header were read, eight."""
    if isinstance(saved, dict):  # its lists are the dialect's tuples (units: of pairs)
        fields: dict[str, Any] = {
            name: tuple(tuple(v) if isinstance(v, list) else v for v in value) if isinstance(value, list) else value
            for name, value in saved.items()
        }
        return CsvDialect(**fields)
    units = tuple((str(n), str(u)) for n, u in (saved[4] if len(saved) > 4 else []))
    if len(saved) > 5:  # (the channels' names from the row under the header since the 9th and 10th)
        names = (tuple(str(n) for n in saved[8]), tuple(str(n) for n in saved[9])) if len(saved) > 9 else ((), ())
        return CsvDialect(
            str(saved[0]),
            str(saved[1]),
            int(saved[2]),
            str(saved[3]),
            units,
            int(saved[5]),
            str(saved[6]),
            bool(saved[7]),
            *names,
        )
    return CsvDialect(str(saved[0]), str(saved[1]), int(saved[2]), str(saved[3]), units, int(bool(units)))


@dataclass
class LogFollower:
    """Tail a CSV temperature log (a time column, one column per sensor).

    Parameters
    ----------
    path : Path
        The log being written.
    sensors : list of str or None
        The sensor columns to read, in that order; None (or ``["all"]``) to take every temperature
        column, which the header then sets.
    time_col : str or None
        The time column's name, None to find it.
    time_unit : str or None
        Unit of a numeric time column ("ms", "s", "min", "h", "d"), None to take it from the log.
    offset : int
        Bytes of the file read so far (the next poll reads from there).
    identity : tuple of int or None
        (device, inode) of the file when it was last read: another file under the same name, or a
        shorter one, is read again from the start.
    header : list of str or None
        The column names, once the header line was read.
    origin : float or None
        The first sample's time (min; from 1970 for time stamps), which is t = 0.
    last_time : float or None
        The last row's time (min from ``origin``).
    columns : list of int
        Positions of the time column and of the sensors' columns, in that order.
    dialect : CsvDialect or None
        How the log is written, from its head once the header line is complete.
    time_format : str or None
        pandas format of the time stamps, from the first one; None for a numeric time column.
    clock_column : int or None
        The column of the time of day where the time column holds the date alone.
    millisecond_column : int or None
        A column with the time stamps' milliseconds (Graphtec's "ms").
    room : str or None
        A room sensor's column: where no sensors are named, it is taken with the others and read last
        (named sensors are read as given, the room among them where the caller puts it).
    first_stamp : str or None
        The first time stamp as written (a slashed date may have to be read again day first).
    clock_shift : float
        Minutes added to the stamps since summer time ended (+60) or began (−60) during the log.
    last_step : float or None
        Minutes between the last two rows taken (a clock change is told against it).
    serial_days : bool
        The time column, named as dates, holds spreadsheet serial dates, read in days.
    temperature_unit : str or None
        Unit of the temperature columns that state none of their own ("C", "F" or "K"); None: °C. A
        column whose own unit is another temperature unit is refused.
    """

    path: Path
    sensors: list[str] | None = None
    time_col: str | None = None
    time_unit: str | None = None
    offset: int = 0
    identity: tuple[int, int] | None = None
    header: list[str] | None = None
    origin: float | None = None  # raw time (or epoch seconds) of the first sample, defines t = 0
    last_time: float | None = None  # minutes
    columns: list[int] = field(default_factory=list)
    dialect: CsvDialect | None = None  # from the file's head, once its header line is complete
    time_format: str | None = None  # pandas format of the time stamps, from the first one
    clock_column: int | None = None  # the time of day's column where the date is in the time column
    millisecond_column: int | None = None  # a column with the time stamps' milliseconds (Graphtec's "ms")
    room: str | None = None  # a room sensor's column, read last, after all the sensors (none named)
    first_stamp: str | None = None  # the first time stamp as written: a slashed date may be read again the other way
    # minutes added to the local stamps since summer time ended (+60) or began (−60) during the log
    clock_shift: float = 0.0
    last_step: float | None = None  # minutes between the last two rows taken (a clock change is told by it)
    serial_days: bool = False  # a column named as dates holds spreadsheet serial dates: read in days
    temperature_unit: str | None = None  # the unit of the temperature columns that state none (an option, not saved)
    # derived once from the header and the options, not saved: (minutes per unit, unit assumed) of a
    # numeric time column (looked up on every row, it cost an eighth of a 28,800-row replay)
    _time_scale: tuple[float, bool] | None = field(default=None, repr=False, compare=False)
    _last_stamp: str | None = field(default=None, repr=False, compare=False)  # the last row's time cell, for a note
    _rows_taken: int = field(default=0, repr=False, compare=False)  # for the hint of a column in hours
    _unit_said: bool = field(default=False, repr=False, compare=False)
    _first_times: list[float] = field(default_factory=list, repr=False, compare=False)  # for a column in seconds

    def position(self) -> dict[str, object]:
        """Everything needed to resume (for the state file)."""
        return {
            "offset": self.offset,
            "identity": list(self.identity) if self.identity else None,
            "header": self.header,
            "origin": self.origin,
            "last_time": self.last_time,
            "columns": self.columns,
            "sensors": self.sensors,
            "dialect": None if self.dialect is None else _dialect_to_save(self.dialect),
            "time_format": self.time_format,
            "clock_column": self.clock_column,
            "millisecond_column": self.millisecond_column,
            "room": self.room,
            "first_stamp": self.first_stamp,
            "clock_shift": self.clock_shift,
            "last_step": self.last_step,
            "serial_days": self.serial_days,
        }

    @classmethod
    def resume(
        cls,
        path: Path,
        position: dict[str, Any],
        time_col: str | None,
        time_unit: str | None,
        temperature_unit: str | None = None,
    ) -> LogFollower:
        """A follower that continues from a saved position.

        Parameters
        ----------
        path : Path
            The log being written.
        position : dict of str to Any
            What :meth:`position` returned, as the state file keeps it (JSON: tuples as lists); "offset" is
            needed, a dialect absent (older state files) is taken from the log's head again.
        time_col : str or None
            The time column's name, None to find it.
        time_unit : str or None
            Unit of a numeric time column ("ms", "s", "min", "h", "d"), None to take it from the log.
        temperature_unit : str or None, optional
            Unit of the temperature columns that state none of their own ("C", "F" or "K"); None: °C.

        Returns
        -------
        LogFollower
            A follower that reads on from the saved byte offset, with the saved header, time origin, last
            time and dialect.
        """
        identity = position.get("identity")
        dialect = position.get("dialect")  # absent in older state files: taken from the head again
        return cls(
            path=path,
            sensors=position.get("sensors"),
            time_col=time_col,
            time_unit=time_unit,
            offset=int(position["offset"]),
            identity=tuple(identity) if identity else None,
            header=position.get("header"),
            origin=position.get("origin"),
            last_time=position.get("last_time"),
            columns=list(position.get("columns") or []),
            dialect=None if dialect is None else _saved_dialect(dialect),
            time_format=position.get("time_format"),
            clock_column=position.get("clock_column"),
            millisecond_column=position.get("millisecond_column"),
            room=position.get("room"),
            first_stamp=position.get("first_stamp"),
            clock_shift=float(position.get("clock_shift", 0.0)),
            last_step=position.get("last_step"),
            serial_days=bool(position.get("serial_days", False)),
            temperature_unit=temperature_unit,
        )

    def _set_header(self, line: str, rows: list[list[str]]) -> list[str]:
        """Take the header line: the time column and the sensors' columns; returns notes (units,
        columns left out).

        ``rows`` (the data rows' cells written so far, one at least) tell how the
        time is written (:meth:`_take_time_columns`) and which columns hold text
        alone (a status channel: no sensor, as the file reader has it).
        """
        assert self.dialect is not None
        header = self.dialect.header(line)
        if len(header) < 2:
            msg = (
                f"{self.path}: need a time column and at least one sensor column, separated by ',', ';' or tabs; "
                f"found: {', '.join(header)}"
            )
            raise InputError(msg)
        check_unique_names(header, self.path)
        time_name, no_sensors, notes = self._take_time_columns(header, rows[0] if rows else [])
        names = [h for h in header if h not in (*no_sensors, "")]  # "": a delimiter at the end of the line
        chosen, sensor_notes = self._choose_sensors(header, names, rows)
        self.header = header
        self.sensors = chosen
        self.columns = [header.index(time_name)] + [header.index(s) for s in chosen]
        renamed = self.dialect.renaming()
        return [*([renamed] if renamed else []), *notes, *sensor_notes]

    def _take_time_columns(self, header: list[str], first_row: list[str]) -> tuple[str, list[str], list[str]]:
        """The time column's name, the columns that belong to the time (no sensors: a row counter
        before it, a time of day after a date, milliseconds after the stamp), and notes; sets
        ``clock_column`` and ``millisecond_column``."""
        assert self.dialect is not None
        time_name, counter, notes = choose_time_column(header, first_row, self.dialect, self.time_col)
        if time_name not in header:
            msg = f"{self.path}: no time column {time_name!r}; the columns are: {', '.join(header)}"
            raise InputError(msg)
        following = header.index(time_name) + 1
        if following < min(len(header), len(first_row)) and date_and_clock(
            first_row[header.index(time_name)], first_row[following]
        ):
            self.clock_column = following
        clock_name = header[self.clock_column] if self.clock_column is not None else None
        self.millisecond_column = millisecond_column(header, header.index(clock_name or time_name))
        milliseconds = header[self.millisecond_column] if self.millisecond_column is not None else None
        return (
            time_name,
            [n for n in (time_name, clock_name, milliseconds, header[0] if counter else None) if n is not None],
            notes,
        )

    def _choose_sensors(
        self, header: list[str], names: list[str], rows: list[list[str]]
    ) -> tuple[list[str], list[str]]:
        """The sensor columns to read, the room sensor last, and notes: those asked for, or every
        column of ``names`` but text-only and non-temperature ones (left out with a note)."""
        assert self.dialect is not None
        asked = bool(self.sensors) and self.sensors != ["all"]
        chosen = self.sensors if asked and self.sensors is not None else names
        notes = []
        if not asked:
            text_only = [
                n
                for n in chosen
                if n != self.room
                and text_only_cells([row[header.index(n)] for row in rows if header.index(n) < len(row)])
            ]
            if text_only and len(text_only) < len([n for n in chosen if n != self.room]):
                notes.append(f"left out, no numbers in them: {', '.join(text_only)}")
                chosen = [n for n in chosen if n not in text_only]
        room_last = None if asked else self.room  # read after the sensors
        if room_last is not None:
            chosen = [n for n in chosen if n != room_last] + [room_last]
        missing = [s for s in chosen if s not in header]
        if missing:
            msg = missing_column(self.path, missing[0], names)
            raise InputError(msg)
        if room_last is not None and len(chosen) == 1:
            msg = f"{self.path}: no sensor column besides the room sensor {room_last!r}"
            raise InputError(msg)
        if room_last is not None:  # the room sensor, named, must be a temperature
            sensors, unit_notes = temperature_columns(
                chosen[:-1], False, self.dialect, self.path, self.temperature_unit
            )
            room = temperature_columns(chosen[-1:], True, self.dialect, self.path, self.temperature_unit)[0]
            chosen = [*sensors, *room]
        else:
            chosen, unit_notes = temperature_columns(
                list(chosen), asked, self.dialect, self.path, self.temperature_unit
            )
        return list(chosen), [*notes, *unit_notes]

    def _data_lines(self, lines: list[str], notes: list[str]) -> list[str]:
        """The data lines among the log's first lines (preamble, header and units row taken off);
        the header is taken on the first call, its notes added to ``notes``."""
        assert self.dialect is not None
        lines = lines[self.dialect.preamble_lines :]
        if not lines:
            return []
        header_line, lines = lines[0], lines[1 + self.dialect.extra_rows :]
        if self.header is None:
            rows_so_far = [
                cells for cells in csv.reader(lines, delimiter=self.dialect.delimiter) if any(c.strip() for c in cells)
            ]
            notes.extend(self._set_header(header_line, rows_so_far))
        return lines

    def header_sensors(self) -> list[str] | None:
        """The sensor columns (the room last) as the first poll will take them, from the log's head
        alone; None while it has no complete data row. For a caller that must know them before
        reading (a resumed monitor compares them with its state file's)."""
        with open(self.path, "rb") as handle:
            head = handle.read(HEAD_BYTES)
        if binary_kind(head) is not None:
            return None  # no text: the first poll says so
        try:
            probe = replace(self, dialect=sniff_dialect(head, wait_for_row=True), header=None)
        except csv.Error:
            return None
        if probe.dialect is None:
            return None
        complete = probe.dialect.decode(head[: probe.dialect.complete_length(head)])
        probe._data_lines(complete.splitlines(), [])
        return probe.sensors

    def _parse_time(self, text: str, notes: list[str]) -> float:
        """Minutes relative to the first sample; raises ValueError for an unreadable cell; what it
        finds out about the time column (serial dates read as days) goes to ``notes``."""
        assert self.header is not None and self.dialect is not None
        try:
            raw = self.dialect.number(text)
            time_name = self.header[self.columns[0]]
            if self._time_scale is None:
                stated = self.dialect.time_unit(time_name)
                if (overridden := unit_overridden_note(time_name, self.time_unit, stated)) is not None:
                    notes.append(overridden)
                self._time_scale = (
                    (MINUTES_PER_DAY, False)
                    if self.serial_days
                    else (
                        time_unit_factor(time_name, self.time_unit, stated),
                        time_unit_assumed(time_name, self.time_unit, stated),
                    )
                )
            scale, assumed = self._time_scale
            stamp = raw * scale
        except ValueError:
            if self.time_format is None:
                self.time_format = stamp_format(text)
                self.first_stamp = text.strip()
            if self.time_format is None:
                raise
            stamp = self._stamp_minutes(text.strip())
        else:
            # spreadsheet serial dates are told at the second row
            serial = None
            if self.origin is not None and self.last_time == 0.0 and assumed:
                serial = serial_date_hint(time_name, self.origin, stamp - self.origin)
            if serial is not None and names_a_date(time_name):
                # read in days from here on, the first row's too (it is t = 0 whatever its unit)
                assert self.origin is not None
                notes.append(serial_date_note(time_name, self.origin))
                self.serial_days, self._time_scale = True, (MINUTES_PER_DAY, False)
                self.origin, stamp = self.origin * MINUTES_PER_DAY, raw * MINUTES_PER_DAY
            elif serial is not None:
                msg = f"{self.path}: {serial}"
                raise InputError(msg)
        if self.origin is None:
            self.origin = stamp
        t = stamp - self.origin
        if self.time_format in TIME_OF_DAY_FORMATS:
            t = after_midnight(self.last_time, t)
        return t

    def _local_dated_stamps(self) -> bool:
        """Whether the log's times are dated stamps of a local clock, written without their offset
        from UTC: the clock may change for summer time during the log."""
        return (
            self.time_format is not None
            and self.time_format not in TIME_OF_DAY_FORMATS
            and not has_utc_offset(self.first_stamp or "")
        )

    def _stamp_minutes(self, text: str) -> float:
        """A time stamp in minutes since 1970 in the log's format; ValueError if it is none.

        A slashed date read as the first stamp told that does not parse, or jumps by
        weeks, is read with day and month swapped where that steps on plausibly
        (01/12 then 02/12 just after midnight: a day, not a month); from then on the
        other order is used, and t = 0 is the first stamp read that way.
        """
        import pandas as pd  # only for time stamps

        def minutes(cell: str, fmt: str | None) -> float:
            return float(pd.to_datetime(cell, format=fmt, utc=True).timestamp() / 60.0)

        swapped = other_date_order(self.time_format)
        if swapped is None or self.first_stamp is None or self.origin is None or self.last_time is None:
            try:
                return minutes(text, self.time_format)
            except ValueError:
                elapsed = elapsed_minutes(text) if self.time_format in TIME_OF_DAY_FORMATS else None
                if elapsed is None:
                    raise
                # a clock past 24:00:00 is elapsed time: on from the day a time of day is read on
                return CLOCK_DAY_ZERO_MIN + elapsed
        try:
            stamp = minutes(text, self.time_format)
            if stamp - self.origin - self.last_time < IMPLAUSIBLE_STEP_MIN:
                return stamp
        except ValueError:
            stamp = None
        try:
            origin, turned = minutes(self.first_stamp, swapped), minutes(text, swapped)
        except ValueError:
            origin = turned = float("nan")
        if not 0.0 < turned - origin - self.last_time < IMPLAUSIBLE_STEP_MIN:
            if stamp is None:
                raise ValueError(text)
            return stamp
        self.time_format, self.origin = swapped, origin
        return turned

    def poll(self) -> Rows:
        """Read the complete lines added since the last poll."""
        warnings: list[str] = []
        notes: list[str] = []
        new = self._new_lines(warnings, notes)
        if new is None:
            return Rows(np.empty(0), np.empty((0, len(self.sensors or []))), tuple(warnings))
        lines, restarted = new
        assert self.header is not None and self.dialect is not None
        conversions = np.array(
            [
                celsius_conversion(sensor_unit(self.header[i], self.dialect, self.temperature_unit)) or (1.0, 0.0)
                for i in self.columns[1:]
            ]
        ).reshape(-1, 2)
        times: list[float] = []
        rows: list[list[float]] = []
        # the previous row's time as the clock wrote it (minutes from the first row) and its cell: a
        # summer-time change is a step between two rows; a log read again from its start after a
        # restart finds its changes again
        if restarted:
            self.clock_shift = 0.0
        previous_raw = None if restarted or self.last_time is None else self.last_time - self.clock_shift
        previous_cell = None if restarted else self._last_stamp
        for line in csv.reader(io.StringIO("\n".join(lines)), delimiter=self.dialect.delimiter):
            if not line or all(not c.strip() for c in line):
                continue
            stamped = self._row_time(line, notes, warnings)
            if stamped is None:
                continue
            raw, cell = stamped
            if previous_raw is not None:
                self._follow_clock_change(previous_raw, raw, previous_cell, cell, notes)
            t = raw + self.clock_shift
            if self.last_time is not None and t <= self.last_time:
                if not restarted:  # after a restart the old rows come again: expected, not an error
                    warnings.append(
                        f"{self.path}: refused the row at t = {t:g} min: it repeats or goes back from t = "
                        f"{self.last_time:g} min"
                    )
                else:
                    previous_raw, previous_cell = raw, cell
                continue
            if self.last_time is not None and self.last_step is not None:
                if (gap := gap_said(t - self.last_time, self.last_time, self.last_step)) is not None:
                    notes.append(gap)
            self.last_step = None if self.last_time is None else t - self.last_time
            self.last_time = t
            self._last_stamp = previous_cell = cell
            previous_raw = raw
            times.append(t)
            rows.append(self._row_values(line, conversions))
        values = np.array(rows).reshape(len(rows), len(self.sensors or []))
        notes.extend(_skipped_notes(self.sensors or [], np.array(times), values))
        self._hint_unit(times, warnings)
        return Rows(np.array(times), values, tuple(warnings), tuple(notes))

    def _hint_unit(self, times: list[float], warnings: list[str]) -> None:
        """Once (one hint on the unit in all), where a numeric time column read as minutes for want of a
        unit looks like seconds or hours (:func:`~mtident.io.logs.unit_hint`)."""
        if not times or self._unit_said or self._time_scale is None or not self._time_scale[1]:
            return
        self._rows_taken += len(times)
        assert self.header is not None
        # times count from the first sample's: the last is the span
        self._first_times = (self._first_times + times)[:SPARSE_HINT_ROWS]
        hint = unit_hint(self.header[self.columns[0]], np.array(self._first_times), times[-1], self._rows_taken)
        if hint is not None:
            warnings.append(f"{self.path}: {hint}")
            self._unit_said = True

    def _new_lines(self, warnings: list[str], notes: list[str]) -> tuple[list[str], bool] | None:
        """The complete data lines written since the last poll, and whether the log was truncated or
        replaced (read again from its start); None while there are none (or no log yet)."""
        try:
            stat = os.stat(self.path)
        except FileNotFoundError:
            return None
        identity = (stat.st_dev, stat.st_ino)
        restarted = self.identity is not None and (identity != self.identity or stat.st_size < self.offset)
        if restarted:
            warnings.append(
                f"{self.path}: the log was truncated or replaced (logger restarted?); reading it again from the "
                "start, skipping rows already counted"
            )
            self.offset = 0
        self.identity = identity
        with open(self.path, "rb") as handle:
            if self.dialect is None:
                self.dialect = self._sniff(handle.read(HEAD_BYTES))
                if self.dialect is None:  # no complete data row yet
                    return None
            handle.seek(self.offset)
            chunk = handle.read()
        end = self.dialect.complete_length(chunk)
        if end == 0:
            return None
        start_offset = self.offset
        self.offset += end
        lines = self.dialect.decode(chunk[:end]).splitlines()
        return (self._data_lines(lines, notes) if start_offset == 0 else lines), restarted

    def _sniff(self, head: bytes) -> CsvDialect | None:
        """The log's dialect from its first bytes (None until a data row is complete)."""
        kind = binary_kind(head)
        if kind in ("xlsx", "xls"):
            msg = (
                f"{self.path}: an Excel workbook is not written row by row; watch follows the CSV a logger "
                "writes (identify and min-time read the workbook, and a replay replays it)"
            )
            raise InputError(msg)
        if kind is not None:
            msg = f"{self.path}: not a text file; watch follows the CSV text a logger writes"
            raise InputError(msg)
        try:
            return sniff_dialect(head, wait_for_row=True)
        except csv.Error as exc:
            msg = f"{self.path}: not a readable CSV file ({exc})"
            raise InputError(msg) from exc

    def _row_time(self, line: list[str], notes: list[str], warnings: list[str]) -> tuple[float, str] | None:
        """A row's time as its clock wrote it (minutes) and its time cell(s); None, with a warning,
        for a row whose time cannot be read."""
        assert self.dialect is not None
        try:
            cell = (
                line[self.columns[0]].strip()
                if self.clock_column is None
                else f"{line[self.columns[0]].strip()} {line[self.clock_column].strip()}"
            )
            t = self._parse_time(cell, notes)
            if self.millisecond_column is not None:
                t += self.dialect.number(line[self.millisecond_column]) / 60_000.0
        except InputError:  # a ValueError too, but about the whole log, not this row
            raise
        except (ValueError, IndexError):
            warnings.append(f"{self.path}: refused a row with an unreadable time {line[:1]!r}")
            return None
        return t, cell

    def _follow_clock_change(
        self, previous_raw: float, raw: float, previous_cell: str | None, cell: str, notes: list[str]
    ) -> None:
        """A step between two rows of local date stamps that a summer-time change explains shifts
        the clock (said once, not again on a re-read)."""
        if 0.0 < raw - previous_raw <= 59.0 or not self._local_dated_stamps():
            return
        assert self.origin is not None
        shift = clock_change(self.origin + previous_raw, self.origin + raw, self.last_step)
        if not shift:
            return
        self.clock_shift += shift
        if self.last_time is None or raw + self.clock_shift > self.last_time:
            notes.append(
                clock_change_note(
                    shift,
                    f"after t = {previous_raw + self.clock_shift - shift:g} min",
                    repr(previous_cell or "the row before"),
                    repr(cell),
                )
            )

    def _row_values(self, line: list[str], conversions: FloatArray) -> list[float]:
        """A row's temperatures in °C (NaN: empty, unreadable, or an open circuit's reading)."""
        assert self.dialect is not None
        values: list[float] = []
        for (scale, offset), index in zip(conversions, self.columns[1:], strict=True):
            try:
                value = scale * self.dialect.number(line[index]) + offset
            except (ValueError, IndexError):
                value = np.nan
            values.append(value if OPEN_CIRCUIT_LOW_C <= value <= OPEN_CIRCUIT_HIGH_C else np.nan)
        return values


def _skipped_notes(sensors: list[str], time_min: FloatArray, values: FloatArray) -> list[str]:
    """A note per sensor with readings left out (empty, not a number, or an open circuit's)."""
    notes = []
    for name, column in zip(sensors, values.T, strict=True):
        missing = np.flatnonzero(np.isnan(column))
        if len(missing):
            notes.append(
                f"sensor {name!r}: skipped {len(missing)} empty, unreadable or open-circuit reading(s) (the first at "
                f"t = {time_min[missing[0]]:g} min)"
            )
    return notes
