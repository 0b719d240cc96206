"""Following a CSV log that a data-acquisition program is still writing.

The follower never writes to the log. It remembers the byte offset of the last
complete line it read, the file's identity (device, inode) and how far the time
column was read, so that:

* new rows are picked up on the next poll;
* a partly written last line (no newline yet) waits for its end;
* a truncated or replaced file (the logger restarted) is read again from its
  start, and rows at or before the last accepted time are skipped, so nothing is
  counted twice;
* a row that repeats a time stamp or goes back in time is refused with a warning.

The follower owns the I/O alone: the log's layout is fixed from its head as the
file reader fixes it (:mod:`mtident.io.layout`), and its lines become rows in
:func:`~mtident.io.parse.parse_lines`, so a live log and the finished file read
the same.

Where it is is a small frozen value (:class:`FollowPosition`, from
:meth:`LogFollower.position`) that the monitor keeps in its state file
(:mod:`mtident.persist`) to resume exactly where it was.
"""

from __future__ import annotations

import csv
import os
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.io.dialect import HEAD_BYTES, CsvDialect, binary_kind, sniff_dialect
from mtident.io.layout import LogLayout, layout_of_head
from mtident.io.log_file import refuse_split_name
from mtident.io.logs import another_unit_error, scale_note
from mtident.io.parse import TimeState, parse_lines
from mtident.io.time_notes import SPARSE_HINT_ROWS, hours_hint, unit_hint

__all__ = ["FollowPosition", "LogFollower", "Rows"]


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


TAIL_BYTES = 64
"""How many of the last bytes read a follower keeps, to know its log written anew from another."""


@dataclass(frozen=True, slots=True)
class FollowPosition:
    """Where a follower is in its log: everything needed to resume (the state file keeps it).

    Attributes
    ----------
    offset : int
        Bytes of the file read so far (the next poll reads from there).
    identity : tuple of int or None
        (device, inode) of the file when it was last read: another file under the same name, or a
        shorter one, is read again from the start, but for one whose bytes before ``offset`` end as
        ``tail`` does (the same log written anew: a logger that replaces its file with a longer copy,
        or a workbook's sheet copied again for a resumed replay).
    tail : str
        The last bytes read (up to :data:`TAIL_BYTES`, as hexadecimal; "" before any, and in a state
        file from before it was kept).
    layout : LogLayout or None
        How the rows are read, once the header line and a data row were read.
    time : TimeState
        How far the time column was read.
    sensors : tuple of str or None
        The sensors asked for (None: every temperature column), for a follower resumed before the
        header was read.
    room : str or None
        The room sensor's column, read last where no sensors are named.
    """

    offset: int = 0
    identity: tuple[int, int] | None = None
    tail: str = ""
    layout: LogLayout | None = None
    time: TimeState = TimeState()
    sensors: tuple[str, ...] | None = None
    room: str | None = None


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
    room : str or None
        A room sensor's column: where no sensors are named, it is taken with the others and read last
        (named sensors are read as given, the room among them where the caller puts it).
    temperature_unit : str or None
        Unit of the temperature columns that state none of their own ("C", "F" or "K"); None: °C. A
        column whose own unit is another temperature unit is refused.
    shown_as : Path or None
        The file the messages name, where ``path`` is a copy of it (an Excel workbook replayed as
        the CSV it holds); None: ``path``.
    """

    path: Path
    sensors: list[str] | None = None
    time_col: str | None = None
    time_unit: str | None = None
    room: str | None = None
    temperature_unit: str | None = None
    shown_as: Path | None = None
    _at: FollowPosition = field(default_factory=FollowPosition, repr=False)
    # for the one hint on a time column's unit (not saved: a resumed follower may hint again)
    _rows_taken: int = field(default=0, repr=False, compare=False)
    _unit_said: bool = field(default=False, repr=False, compare=False)
    _scale_said: bool = field(default=False, repr=False, compare=False)
    _first_times: list[float] = field(default_factory=list, repr=False, compare=False)

    @property
    def source(self) -> Path:
        """The file the messages name."""
        return self.shown_as or self.path

    @property
    def dialect(self) -> CsvDialect | None:
        """How the log is written, once its header and a data row were read (else None).

        Returns
        -------
        CsvDialect or None
        """
        return None if self._at.layout is None else self._at.layout.dialect

    @property
    def layout(self) -> LogLayout | None:
        """How the rows are read, once the header and a data row were read (else None).

        Returns
        -------
        LogLayout or None
        """
        return self._at.layout

    def unfinished_line(self) -> str | None:
        """The text after the log's last line end, where there is any besides blanks: a line the
        follower waits for (its end not yet written); None where there is none, or no layout yet.

        Returns
        -------
        str or None
        """
        if self._at.layout is None:
            return None
        try:
            with open(self.path, "rb") as handle:
                handle.seek(self._at.offset)
                rest = handle.read()
        except OSError:
            return None
        text = self._at.layout.dialect.decode(rest).strip()
        return text or None

    def position(self) -> FollowPosition:
        """Everything needed to resume (for the state file: :func:`~mtident.persist.save_dataclass`).

        Returns
        -------
        FollowPosition
        """
        sensors = None if self.sensors is None else tuple(self.sensors)
        return replace(self._at, sensors=sensors, room=self.room)

    @classmethod
    def resume(
        cls,
        path: Path,
        position: FollowPosition,
        time_col: str | None,
        time_unit: str | None,
        temperature_unit: str | None = None,
        shown_as: Path | None = None,
    ) -> LogFollower:
        """A follower that continues from a saved position.

        Parameters
        ----------
        path : Path
            The log being written.
        position : FollowPosition
            What :meth:`position` returned (as :func:`~mtident.persist.load_dataclass` reads it back).
        time_col : str or None
            The time column's name, None to find it.
        time_unit : str or None
            Unit of a numeric time column ("ms", "s", "min", "h", "d"), None to take it from the log.
        temperature_unit : str or None, optional
            Unit of the temperature columns that state none of their own ("C", "F" or "K"); None: °C.
        shown_as : Path or None, optional
            The file the messages name (:class:`LogFollower`).

        Returns
        -------
        LogFollower
            A follower that reads on from the saved byte offset, with the saved layout and time.

        Raises
        ------
        InputError
            ``position`` is no :class:`FollowPosition` (one an older version saved, a dict or a list).
        """
        if not isinstance(position, FollowPosition):
            msg = (
                f"{shown_as or path}: the follower's position is a {type(position).__name__}, as an older version "
                "of mtident saved it, which this one does not read: start afresh (delete the state file, or run "
                "without resuming)"
            )
            raise InputError(msg)
        layout = position.layout
        if layout is not None:
            layout = replace(layout, time_unit=time_unit, temperature_unit=temperature_unit)
        sensors = None if position.sensors is None else list(position.sensors)
        follower = cls(path, sensors, time_col, time_unit, position.room, temperature_unit, shown_as)
        follower._at = replace(position, layout=layout)
        return follower

    def poll(self) -> Rows:
        """Read the complete lines added since the last poll.

        Returns
        -------
        Rows
            The rows of those lines, with the notes and warnings of reading them.
        """
        warnings: list[str] = []
        notes: list[str] = []
        new = self._new_lines(warnings, notes)
        if new is None or self._at.layout is None:
            return Rows(np.empty(0), np.empty((0, len(self.sensors or []))), tuple(warnings))
        lines, restarted = new
        layout = self._at.layout
        time, rows = parse_lines(layout, self._at.time, lines, self.source, restarted)
        self._at = replace(self._at, time=time)
        warnings.extend(rows.warnings)
        self._hint_unit(list(rows.time_min), warnings)
        if not self._scale_said and len(rows.time_min):
            # as the file reader says it: readings far outside any workshop's range in the unit taken,
            # judged once every column has a reading
            odd = another_unit_error(
                list(layout.sensors), rows.temperature_C, layout.dialect, self.source, self.temperature_unit
            )
            if odd is not None:
                raise InputError(odd)
            said = scale_note(list(layout.sensors), rows.temperature_C, layout.dialect, self.temperature_unit)
            self._scale_said = said is not None or bool(np.all(np.isfinite(rows.temperature_C).any(axis=0)))
            # readings that may be misread: a warning, which the watch's answer carries (log_warnings)
            warnings.extend([] if said is None else [said])
        return Rows(rows.time_min, rows.temperature_C, tuple(warnings), (*notes, *rows.notes))

    def header_sensors(self) -> list[str] | None:
        """The sensor columns (the room last) as the first poll will take them, from the log's head
        alone; None while it has no complete data row. For a caller that must know them before
        reading (a resumed monitor compares them with its state file's).

        Returns
        -------
        list of str or None
        """
        with open(self.path, "rb") as handle:
            head = handle.read(HEAD_BYTES)
        if binary_kind(head) is not None:
            return None  # no text: the first poll says so
        try:
            dialect = sniff_dialect(head, wait_for_row=True)
        except csv.Error:
            return None
        if dialect is None:
            return None
        complete = dialect.decode(head[: dialect.complete_length(head)])
        header_line, lines = _split_head(complete.splitlines(), dialect)
        return None if header_line is None else list(self._layout(header_line, lines, dialect)[0].sensors)

    def _hint_unit(self, times: list[float], warnings: list[str]) -> None:
        """Once (one hint on the unit in all), where a numeric time column read as minutes for want of a
        unit looks like seconds or hours (:func:`~mtident.io.time_notes.unit_hint`)."""
        layout = self._at.layout
        if not times or self._unit_said or layout is None or self._at.time.time_format is not None:
            return
        per_unit, assumed = layout.time_scale()
        named_minutes = not assumed and layout.time_unit is None and per_unit == 1.0
        if self._at.time.serial_days or not (assumed or named_minutes):
            return
        self._rows_taken += len(times)
        # times count from the first sample's: the last is the span
        self._first_times = (self._first_times + times)[:SPARSE_HINT_ROWS]
        hint = (
            hours_hint(layout.time_name, times[-1], self._rows_taken, named_minutes=True)
            if named_minutes
            else unit_hint(layout.time_name, np.array(self._first_times), times[-1], self._rows_taken)
        )
        if hint is not None:
            warnings.append(f"{self.source}: {hint}")
            self._unit_said = True

    def _new_lines(self, warnings: list[str], notes: list[str]) -> tuple[list[str], bool] | None:
        """The complete data lines written since the last poll, and whether the log was truncated or
        replaced (read again from its start); None while there are none (or no log yet). The first
        lines read fix the layout (their notes go to ``notes``)."""
        try:
            stat = os.stat(self.path)
        except FileNotFoundError:
            return None
        identity = (stat.st_dev, stat.st_ino)
        at = self._at
        restarted = at.identity is not None and (
            stat.st_size < at.offset or (identity != at.identity and not self._same_log(at))
        )
        if restarted:
            warnings.append(
                f"{self.source}: the log was truncated or replaced (logger restarted?); reading it again from the "
                "start, skipping rows already counted"
            )
            at = replace(at, offset=0, tail="")
        self._at = at = replace(at, identity=identity)
        with open(self.path, "rb") as handle:
            dialect = self.dialect if at.layout is not None else self._sniff(handle.read(HEAD_BYTES))
            if dialect is None:  # no complete data row yet
                return None
            handle.seek(at.offset)
            chunk = handle.read()
        end = dialect.complete_length(chunk)
        if end == 0:
            return None
        lines = dialect.decode(chunk[:end]).splitlines()
        if at.offset == 0:
            header_line, lines = _split_head(lines, dialect)
            if header_line is None:
                return None
            if at.layout is None:
                layout, said = self._layout(header_line, lines, dialect)
                self.sensors = list(layout.sensors)
                at = replace(at, layout=layout)
                notes.extend(said)
        tail = (bytes.fromhex(at.tail) + chunk[:end])[-TAIL_BYTES:]
        self._at = replace(at, offset=at.offset + end, tail=tail.hex())
        return lines, restarted

    def _same_log(self, at: FollowPosition) -> bool:
        """Whether the file now under the log's name is the log read so far written anew: its bytes
        before ``at.offset`` end as the ones read last did."""
        if not at.tail or at.offset < len(at.tail) // 2:
            return False
        with open(self.path, "rb") as handle:
            handle.seek(at.offset - len(at.tail) // 2)
            return handle.read(len(at.tail) // 2).hex() == at.tail

    def _layout(self, header_line: str, lines: list[str], dialect: CsvDialect) -> tuple[LogLayout, list[str]]:
        """The layout by the header line and the data lines written so far, and its notes."""
        rows_so_far = [
            cells for cells in csv.reader(lines, delimiter=dialect.delimiter) if any(c.strip() for c in cells)
        ]
        refuse_split_name(header_line, max(map(len, rows_so_far), default=0), dialect.delimiter, self.source)
        return layout_of_head(
            header_line,
            rows_so_far,
            dialect,
            self.source,
            time_col=self.time_col,
            sensors=self.sensors,
            room=self.room,
            time_unit=self.time_unit,
            temperature_unit=self.temperature_unit,
        )

    def _sniff(self, head: bytes) -> CsvDialect | None:
        """The log's dialect from its first bytes (None until a data row is complete)."""
        kind = binary_kind(head)
        if kind in ("xlsx", "xls"):
            msg = (
                f"{self.source}: an Excel workbook is not written row by row; watch follows the CSV a logger "
                "writes (identify and min-time read the workbook, and a replay replays it)"
            )
            raise InputError(msg)
        if kind is not None:
            msg = f"{self.source}: not a text file; watch follows the CSV text a logger writes"
            raise InputError(msg)
        try:
            return sniff_dialect(head, wait_for_row=True)
        except csv.Error as exc:
            msg = f"{self.source}: not a readable CSV file ({exc})"
            raise InputError(msg) from exc


def _split_head(lines: list[str], dialect: CsvDialect) -> tuple[str | None, list[str]]:
    """The header line among a log's first lines, and the data lines after it (preamble, header and
    units row taken off); None and no lines where they end before the header."""
    lines = lines[dialect.preamble_lines :]
    if not lines:
        return None, []
    return lines[0], lines[1 + dialect.extra_rows :]
