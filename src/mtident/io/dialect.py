"""How a data-acquisition program wrote its CSV: delimiter, decimal mark, preamble, encoding, time stamps.

Loggers differ. European ones write ``;`` between cells and a decimal comma
(``17,90``); many write a preamble (device, channel setup), as ``#`` lines or
as plain lines, before the header; Windows programs write cp1252, where ``°`` is
the single byte 0xB0 that UTF-8 refuses, or UTF-16 (Excel's "Unicode text"); a trailing delimiter leaves an empty last column; time
stamps come as ISO 8601, as ``22.11.2026 08:00:00`` (day first, as everywhere
dots separate the date; so ``22-11-2026`` and ``22-Nov-2026``), as ``11/22/2026 3:05:00 PM`` (month first, as US loggers
write it, unless the log shows day first), as the time of day alone, or as a date
and a time of day in two columns; many write a row of units
under the header (``min;°C;°C``, ``[s],[K]``), which states the time unit and the
temperature scale (:func:`celsius_conversion`). Both readers of a log (the
whole file, :func:`~mtident.io.logs.read_temperature_log`, and the live
follower, :class:`~mtident.io.follow.LogFollower`) take the dialect from the
file's head here, so they read a log the same way.
"""

from __future__ import annotations

import csv
import math
import re
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TYPE_CHECKING

from mtident.exceptions import InputError

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "CsvDialect",
    "sniff_dialect",
    "header_names",
    "check_unique_names",
    "read_csv",
    "stamp_format",
    "other_date_order",
    "after_midnight",
    "date_and_clock",
    "celsius_conversion",
    "temperature_columns",
    "is_humidity",
    "time_named",
    "number_without_unit",
    "carried_unit",
    "text_only_cells",
    "counter_before_time",
    "text_before_stamps",
    "millisecond_column",
    "HEAD_BYTES",
    "TIME_OF_DAY_FORMATS",
    "MINUTES_PER_DAY",
    "IMPLAUSIBLE_STEP_MIN",
]

# enough for a preamble, the header and a few rows
HEAD_BYTES = 65536
_DELIMITERS = (",", ";", "\t")
# Excel's first line "sep=;" states the delimiter
_SEP_DIRECTIVE = re.compile(r"^sep=(.)\r?$")
# a header whose first column, the row counter, is named "#" (HOBOware: #,"Date Time, GMT+01:00",...): no comment
_HASH_HEADER = re.compile(r'^\s*"?#"?\s*[,;\t]')
_DECIMAL_COMMA = re.compile(r"^\s*[+-]?\d+,\d+(?:[eE][+-]?\d+)?\s*$")
# A time of day alone passes midnight in an overnight test: a step back of more than 12 h is the next day.
# (Keysight BenchLink writes the milliseconds after a colon: 08:00:00:123)
TIME_OF_DAY_FORMATS = ("%H:%M:%S.%f", "%H:%M:%S", "%H:%M:%S:%f", "%H:%M", "%I:%M:%S %p", "%I:%M %p")
# Time stamps other than ISO 8601, tried in this order (pandas/strptime formats). A dotted date is
# day first wherever it is written. A slashed one is month first (US loggers, 11/22/2026 3:05:00 PM)
# unless the first stamp says day first (22/11/2026); where the first stamp cannot tell (01/02),
# the order whose steps are plausible at the first change of date is taken (:func:`other_date_order`).
_DOTTED = tuple(f"%d.%m.{year} {clock}" for year in ("%Y", "%y") for clock in TIME_OF_DAY_FORMATS)
# day first with dashes too (22-11-2026, and 22-Nov-2026 as spreadsheets and LabVIEW write it; a
# building-management export, 22-Nov-26 8:00:00 am)
_DASHED = tuple(f"%d-{month}-{year} {clock}" for month in ("%m", "%b") for year in ("%Y", "%y") for clock in TIME_OF_DAY_FORMATS)
_SLASHED = tuple(f"{date} {clock}" for date in ("%m/%d/%Y", "%m/%d/%y", "%d/%m/%Y", "%d/%m/%y", "%d/%b/%Y", "%d/%b/%y") for clock in TIME_OF_DAY_FORMATS)
# The time of day before the date (Hanwell: 08:00:00 22/Nov/2026), and a comma between a dotted
# date and the time inside one ';'-separated cell (a climate controller's "date,time" column).
_TIME_FIRST = tuple(f"{clock} {date}" for date in ("%d/%b/%Y", "%d/%b/%y", "%d-%b-%Y", "%d.%m.%Y", "%d.%m.%y", "%Y-%m-%d") for clock in TIME_OF_DAY_FORMATS)
_DOTTED_COMMA = tuple(f"%d.%m.{year},{clock}" for year in ("%Y", "%y") for clock in TIME_OF_DAY_FORMATS)
_STAMP_FORMATS = (*_DOTTED, *_DASHED, *_SLASHED, *_TIME_FIRST, *_DOTTED_COMMA, "%Y-%m-%d %I:%M:%S %p", "%Y-%m-%d %I:%M %p", *TIME_OF_DAY_FORMATS)
MINUTES_PER_DAY = 1440.0
# a step that long between two rows of a warm-up log is a date read in the wrong order
IMPLAUSIBLE_STEP_MIN = 20 * MINUTES_PER_DAY
# A unit at the end of a column's name (a unit this module knows): "Time [s]", "T1 (°C)", "Temp (°C)
# #9724974" (a serial number after it), "T/°C", and after a comma before the logger's details,
# "Temp, °F (LGR S/N: 10679014, SEN S/N: 10679014)" (HOBOware).
_UNITS_IN_NAME = (
    re.compile(r"[\[(]\s*([^\[\]()]+?)\s*[\])]\s*(?:#\s*\d+)?\s*$"),
    re.compile(r"\S/\s*([^/\[\]()]+?)\s*$"),
    re.compile(r",\s*([^,\[\]()]+?)\s*(?:\([^()]*\))?\s*$"),
)
# a date without a time: the first of two time-stamp columns
_DATE_FORMATS = ("%d.%m.%Y", "%d.%m.%y", "%d-%m-%Y", "%d-%b-%Y", "%d-%m-%y", "%d-%b-%y", "%Y-%m-%d", "%Y/%m/%d", "%m/%d/%Y", "%m/%d/%y", "%d/%m/%Y", "%d/%m/%y", "%d/%b/%Y")
# A units row's cells, brackets, spaces and degree signs taken away (º, and Â from a UTF-8 ° read
# as cp1252, too), lower case. The time units name the keys of logs.TIME_UNITS; a temperature unit
# gives (scale, offset) to °C.
_TIME_UNIT_NAMES = {"ms": "ms", "msec": "ms", "milliseconds": "ms", "s": "s", "sec": "s", "secs": "s", "second": "s", "seconds": "s", "min": "min", "mins": "min", "minute": "min", "minutes": "min", "h": "h", "hr": "h", "hrs": "h", "hour": "h", "hours": "h", "d": "d", "day": "d", "days": "d"}
_TEMPERATURE_UNITS = {
    # "ﾟC": Japanese loggers (Graphtec) write the half-width ﾟ of Shift-JIS for the degree sign
    **dict.fromkeys(("c", "degc", "celsius", "gradc", "degreesc", "degreec", "ﾟc"), (1.0, 0.0)),
    **dict.fromkeys(("k", "kelvin"), (1.0, -273.15)),
    **dict.fromkeys(("f", "degf", "fahrenheit", "degreesf", "degreef"), (5.0 / 9.0, -160.0 / 9.0)),
}
# Units of a logger's other channels, named at the end of a column's name ("Speed (rpm)", "RH/%"):
# such a column is no temperature. (A units row may name any unit; a name must name a known one.)
_OTHER_UNITS = frozenset(
    ("%", "%rh", "rh", "%rf", "v", "mv", "µv", "uv", "a", "ma", "rpm", "1/min", "u/min", "hz", "khz", "bar", "mbar", "pa", "kpa", "hpa", "mpa", "psi",
     "w", "kw", "lx", "lux", "lxh", "mm", "µm", "um", "nm", "n", "kn", "ppm", "g", "m/s2", "m/s^2", "mm/s", "l/min", "ohm", "Ω", "kΩ", "mw/cm2", "w/cm2h",
     "mg/l", "µs/cm", "us/cm", "ms/cm", "lum/ft²", "lum/ft2", "m/s", "mph", "kwh", "wh", "va")
)
# A column named as a humidity ("Humidity", "RH", "Feuchte", "湿度"; the name alone, without a unit)
_HUMIDITY_WORDS = ("humidity", "feuchte", "湿度")


@dataclass(frozen=True, slots=True)
class CsvDialect:
    """How one log file is written.

    Attributes
    ----------
    delimiter : {",", ";", "\\t"}
    decimal : {".", ","}
    preamble_lines : int
        Lines before the header: ``#`` comments, blank lines, Excel's ``sep=;``, a
        logger's settings written before its table.
    encoding : {"utf-8-sig", "cp1252", "cp932", "utf-16-le", "utf-16-be"}
        UTF-8 (a byte-order mark is skipped), Windows' cp1252 where UTF-8 fails,
        Shift-JIS (cp932) where both fail, or UTF-16 (Excel's "Unicode text"),
        told by its byte-order mark.
    units : tuple of (str, str)
        Each column's unit as the log states it under the header: in a units row
        (``min;°C;°C``), in the readings' cells (``13.1 °C``), or as a humidity in a
        logger's description rows; empty if it states none.
    extra_rows : int
        Lines between the header and the first data row: a units row, a second
        row of names, a logger's description of each channel (serial number,
        type, property), an empty row or a section tag (``[#D]``).
    units_source : str
        Where ``units`` come from, for messages: "the units row", "its cells",
        "the rows under the header".
    units_in_cells : bool
        The readings carry their unit (``13.1 °C``, ``56.3 %RH``), taken off when read.
    """

    delimiter: str = ","
    decimal: str = "."
    preamble_lines: int = 0
    encoding: str = "utf-8-sig"
    # (column name, unit) from under the header; () if the log states none there
    units: tuple[tuple[str, str], ...] = ()
    extra_rows: int = 0
    units_source: str = "the units row"
    units_in_cells: bool = False

    def cells(self, line: str) -> list[str]:
        """The cells of one line (a header), stripped; quotes removed."""
        return [cell.strip() for cell in next(csv.reader([line], delimiter=self.delimiter), [])]

    def number(self, cell: str) -> float:
        """A cell as a float under this decimal mark (a unit after it taken off where the log
        writes one there); ValueError if it is none."""
        if self.units_in_cells:
            cell = number_without_unit(cell)
        return float(cell.replace(",", ".") if self.decimal == "," else cell)

    def decode(self, data: bytes) -> str:
        """Bytes of the log, read from a line's start, as text (a byte-order mark dropped)."""
        return data.decode(self.encoding, errors="replace").removeprefix("\ufeff")

    def complete_length(self, data: bytes) -> int:
        """How many bytes of ``data`` (read from a line's start) are complete lines."""
        newline = "\n".encode(self.encoding.removesuffix("-sig"))
        end = len(data)
        while (at := data.rfind(newline, 0, end)) >= 0:
            if at % len(newline) == 0:  # UTF-16: a newline's two bytes, not the halves of two characters
                return at + len(newline)
            end = at + len(newline) - 1
        return 0

    @property
    def head_lines(self) -> int:
        """Lines before the first data row: the preamble, the header and the rows under it."""
        return self.preamble_lines + 1 + self.extra_rows

    def unit_of(self, column: str) -> str:
        """The column's unit as the log states it under the header, else as its name ends
        ("Time [s]", "T1 (°F)": a unit this module knows only); "" without one."""
        stated = dict(self.units).get(column, "")
        if stated.strip():
            return stated
        if column == "X_Value":  # LabVIEW's measurement files (.lvm) give their x axis in seconds
            return "s"
        # "T (spindle)" names a place, not a unit; "Date/Time" no unit either
        for pattern in _UNITS_IN_NAME:
            named = pattern.search(column)
            if named is not None and _unit_key(named.group(1)) in (*_TIME_UNIT_NAMES, *_TEMPERATURE_UNITS, *_OTHER_UNITS):
                return named.group(1)
        return ""

    def time_unit(self, column: str) -> str | None:
        """"s", "min" or "h" if the units row or the column's name states its unit, else None."""
        return _TIME_UNIT_NAMES.get(_unit_key(self.unit_of(column)))


# a reading with its unit after it: "13.1 °C", "56.3 %RH" (Tinytag Explorer writes them so)
_NUMBER_THEN_UNIT = re.compile(r"^\s*([+-]?(?:\d+(?:[.,]\d*)?|[.,]\d+)(?:[eE][+-]?\d+)?)\s*(\S.*?)\s*$")


def carried_unit(cell: str) -> str | None:
    """The unit a reading carries after its number ("13.1 °C": "°C"), if it is one this module knows."""
    match = _NUMBER_THEN_UNIT.match(cell)
    return match.group(2) if match and _unit_key(match.group(2)) in (*_TEMPERATURE_UNITS, *_OTHER_UNITS) else None


def number_without_unit(cell: str) -> str:
    """A reading's number with a known unit after it taken off ("13.1 °C": "13.1"); other cells as they are."""
    match = _NUMBER_THEN_UNIT.match(cell)
    return match.group(1) if match and carried_unit(cell) else cell


def _unit_key(cell: str) -> str:
    return re.sub(r"[\s\[\]()°º.Â_]", "", cell).lower()


def text_only_cells(cells: list[str]) -> bool:
    """Whether a column's cells hold text and not one number (empty and NaN cells aside; a decimal
    comma counts as a number): a logger's status channel, no sensor. Both readers of a log use it."""
    written = [c.strip() for c in cells if c.strip() and c.strip().lower() != "nan"]
    return bool(written) and not any(_is_number(c) for c in written)


# A first column that counts the rows (Graphtec's "NO.", Keysight's "Scan", "Nr.", "Index"), before the time column.
_COUNTER_NAMES = {"no", "nr", "number", "index", "#", "n", "sample", "samples", "count", "lfdnr", "scan", "record"}
# A column after the time stamp that holds its milliseconds (Graphtec: "NO.,Time,ms,CH1,...").
_MILLISECOND_NAMES = {"ms", "msec", "millisecond", "milliseconds"}


def counter_before_time(header: list[str], first_row: list[str], dialect: CsvDialect) -> bool:
    """Whether the first column counts rows and the second holds the time stamps (its first cell
    no plain number): a logger's sample counter, which read as minutes would be a wrong time. The
    counter is told by its name, or by its cell in the row under the header (Graphtec writes a
    Japanese header and "NO.,Time,ms,ﾟC" under it), or, whatever its name, as a whole number
    before a time stamp or a date (Tinytag leaves the name empty, Lascar's EasyLog puts the
    logger's name there, MadgeTech calls it "Reading #")."""
    if len(header) < 3 or len(first_row) < 2:
        return False
    if first_row[0].strip().isdigit() and not _is_number(first_row[1]) and first_row[1].strip() and (stamp_format(first_row[1]) or _parses(first_row[1], _DATE_FORMATS)):
        return True
    if not {_unit_key(header[0]), _unit_key(dialect.unit_of(header[0]))} & _COUNTER_NAMES:
        return False
    try:
        float(first_row[1].replace(",", "."))
    except ValueError:
        return bool(first_row[1].strip())
    return False


def text_before_stamps(first_row: list[str]) -> int:
    """How many columns of text come before the first column of time stamps (a wireless logger's
    receiver and transmitter names before its DATE), by the first data row; 0 where the first
    column holds the time, or where the first time stamp is not clear (a number is no stamp here:
    a bad first time cell must not make a sensor the time)."""
    for k, cell in enumerate(first_row[:4]):
        text = cell.strip()
        if not text or _is_number(text) or _parses(text, _DATE_FORMATS):  # a date: its time of day follows
            return 0
        if stamp_format(text) is not None:
            return k
    return 0


def _is_number(cell: str) -> bool:
    try:
        float(cell.replace(",", "."))
    except ValueError:
        return False
    return True


def millisecond_column(header: list[str], last_time_column: int) -> int | None:
    """The column after the time stamp (or its clock column) if it is named as its milliseconds."""
    following = last_time_column + 1
    return following if following < len(header) and _unit_key(header[following]) in _MILLISECOND_NAMES else None


def celsius_conversion(unit: str) -> tuple[float, float] | None:
    """(scale, offset) taking a reading in ``unit`` to °C (°C = scale·reading + offset): (1, 0) for
    °C and for no unit, (1, −273.15) for K, (5/9, −160/9) for °F; None for a unit that is no
    temperature (V, %, rpm)."""
    if not unit.strip():
        return 1.0, 0.0
    return _TEMPERATURE_UNITS.get(_unit_key(unit))


def time_named(name: str) -> bool:
    """Whether a column's name says it holds a time (a second time column, as T&D writes its
    stamps' spreadsheet serial dates beside them, or a controller's time difference): no sensor."""
    key = _unit_key(re.sub(r"\.\d+$", "", name))  # pandas' ".1" after a repeated name
    return key.startswith(_TIME_NAME_STARTS)


# what the names of time columns begin with
_TIME_NAME_STARTS = ("time", "date", "zeit", "datum", "uhrzeit", "timestamp", "日付", "時間", "時刻")
# A logger's records of itself: event channels (HOBOware writes "Logged" in them when the event
# happens, else nothing), its serial number (Lascar's EasyLog writes it in the first row alone),
# a comment column (LabVIEW's), alarm and status channels (Keysight BenchLink's "Alarm 101" holds
# 0 or 1: as a sensor it was flat, "no rise", and held the test's decision up).
_EVENT_NAME_STARTS = (
    "couplerdetached", "couplerattached", "hostconnected", "stopped", "endoffile", "buttonup", "buttondown", "badbattery", "goodbattery", "started",
    "serialnumber", "serialno", "comment", "alarm", "status", "flag", "event", "trigger", "logic", "pulse",
)


def event_named(name: str) -> bool:
    """Whether a column's name says it records the logger itself (HOBO's "Host Connected", a serial number): no sensor."""
    return _unit_key(name).startswith(_EVENT_NAME_STARTS)


def is_humidity(name: str) -> bool:
    """Whether a column's name (or a description row's cell) names a humidity, not a temperature."""
    key = _unit_key(name)
    return key in ("rh", "%rh", "rh%") or any(word in key for word in _HUMIDITY_WORDS)


def temperature_columns(names: list[str], asked: bool, dialect: CsvDialect, source: str | Path) -> tuple[list[str], list[str]]:
    """The sensor columns to read, and notes, by their units (a units row, or a unit in the name).

    A column whose unit is no temperature (a logger's speed or voltage channel),
    or that is named as a humidity, is left out of the default selection with a
    note, and refused when ``asked`` for by name; one in K or °F is converted,
    with a note.
    """
    kept, notes, other, times, events = [], [], [], [], []
    for name in names:
        if not asked and time_named(name):
            times.append(name)
            continue
        if not asked and event_named(name):
            events.append(name)
            continue
        by = dialect.units_source if dict(dialect.units).get(name, "").strip() else "its name"
        written = dialect.unit_of(name)
        unit = written.strip().strip("[]()").strip()  # as written, without brackets
        if not unit and is_humidity(name):
            if asked:
                msg = f"{source}: sensor {name!r} is a humidity by its name, not a temperature (°C, K or °F)"
                raise InputError(msg)
            other.append(f"{name} (humidity)")
            continue
        conversion = celsius_conversion(written)
        if conversion is None:
            if asked:
                msg = f"{source}: sensor {name!r} is in {unit!r} by {by}, not a temperature (°C, K or °F)"
                raise InputError(msg)
            other.append(f"{name} ({unit})")
            continue
        if conversion != (1.0, 0.0):
            notes.append(f"sensor {name!r}: read in {unit} ({by}), converted to °C")
        kept.append(name)
    by = dialect.units_source if dialect.units else "its name"
    if times:
        notes.append(f"left out, named as times: {', '.join(times)}")
    if events:
        notes.append(f"left out, the logger's own records: {', '.join(events)}")
    if other:
        notes.append(f"left out, not temperatures by {by}: {', '.join(other)}")
    if not kept:
        msg = f"{source}: no temperature column: {by} gives {', '.join(other)}"
        raise InputError(msg)
    return kept, notes


def sniff_dialect(head: bytes, wait_for_row: bool = False, whole: bool = False) -> CsvDialect | None:
    """The dialect of a log from its first bytes; None while its header line is incomplete
    (with ``wait_for_row``, a live log's: until its first data row is complete). ``whole``: the
    head is the whole file, its last line complete without a newline.

    The delimiter is the one an Excel ``sep=`` line states, else the candidate
    that splits the header line into the most cells and the data rows into as
    many (a header has no decimal commas, so ``;`` against ``,`` is clear there,
    where csv.Sniffer, looking at data rows, would take the decimal comma for the
    delimiter). A decimal comma is assumed when the delimiter is not a comma and a
    data cell reads like ``17,90`` or ``1,5e-05``. The header is the first line
    that is no comment, or, where the lines after it do not continue its table,
    the line that heads the table below (:func:`_table_start`).
    """
    text, encoding = _decoded_head(head)
    lines = text.split("\n")
    complete = lines if whole else lines[:-1]  # the last piece has no newline yet
    preamble, stated = 0, None
    while preamble < len(complete):
        line = complete[preamble]
        directive = _SEP_DIRECTIVE.match(line)
        if directive and directive.group(1) in _DELIMITERS:
            stated = directive.group(1)
        elif line.strip() and (not line.lstrip().startswith("#") or _HASH_HEADER.match(line)):
            break
        preamble += 1
    table_start = _table_start(complete, preamble, stated, wait_for_row)
    if table_start is None:  # a live log's settings written, its table not yet
        return None
    preamble = table_start
    if preamble + wait_for_row >= len(complete):
        return None
    header = complete[preamble]
    delimiter = stated or _delimiter(header, complete[preamble + 1 : preamble + 21])
    decimal = "."
    if delimiter != ",":
        rows = csv.reader(complete[preamble + 1 : preamble + 21], delimiter=delimiter)  # "17,90" quoted, as spreadsheets write it
        if any(_DECIMAL_COMMA.match(cell) for row in rows for cell in row):
            decimal = ","
    dialect = _stated_units(CsvDialect(delimiter, decimal, preamble, encoding), complete)
    if wait_for_row and preamble + 1 + dialect.extra_rows >= len(complete):
        # A live log's header comes before its rows; the delimiter (a tie in the header) and the
        # decimal mark are told by a data row: sniffed from the header alone, a decimal-comma log
        # read every reading as NaN.
        return None
    return dialect


def _stated_units(dialect: CsvDialect, lines: list[str]) -> CsvDialect:
    """The dialect with the rows between its header and its first data row, and the units they
    state: a units row's, a humidity named in a description row ("Property: Humidity"), or the
    units the first data row's readings carry (``13.1 °C``)."""
    k = dialect.preamble_lines
    extra = _extra_rows(lines, k, dialect.delimiter) or 0
    header = dialect.cells(lines[k])
    units: dict[str, str] = {}
    source = "the units row"
    for line in lines[k + 1 : k + 1 + extra]:
        cells = dialect.cells(line)
        if not units and _is_units_row(cells, dialect):
            units, source = {name: unit for name, unit in zip(header, cells, strict=False) if unit}, "the units row"
        elif not units:
            named = {name: "%RH" for name, cell in zip(header, cells, strict=False) if is_humidity(cell)}
            units, source = named, "the rows under the header"
    in_cells = False
    if k + 1 + extra < len(lines):
        carried = {name: unit for name, cell in zip(header, dialect.cells(lines[k + 1 + extra]), strict=False) if (unit := carried_unit(cell))}
        in_cells = bool(carried)
        if carried:  # the readings' own units say most
            units, source = {**units, **carried}, "its cells"
    return replace(dialect, units=tuple(units.items()), extra_rows=extra, units_source=source, units_in_cells=in_cells)


def _decoded_head(head: bytes) -> tuple[str, str]:
    """The head as text, and its encoding: UTF-16 by its byte-order mark (Excel's "Unicode
    text", Windows programs) or by a zero byte in every other place, else UTF-8, else cp1252
    (Windows in Europe and America), else Shift-JIS (cp932: Japanese loggers; it uses bytes that
    cp1252 leaves undefined), else cp1252 with the undefined bytes replaced."""
    utf16 = _utf16(head)
    if utf16 is not None:
        return head[: len(head) // 2 * 2].decode(utf16, errors="replace").removeprefix("\ufeff"), utf16
    for encoding in ("utf-8-sig", "cp1252", "cp932"):
        try:
            return head.decode(encoding), encoding
        except UnicodeDecodeError as exc:
            # a multi-byte character cut off at the end of the head is not a decoding failure
            if exc.start >= len(head) - 3 and _decodes(head[: exc.start], encoding):
                return head[: exc.start].decode(encoding), encoding
    return head.decode("cp1252", errors="replace"), "cp1252"


def _utf16(head: bytes) -> str | None:
    if head.startswith(b"\xff\xfe"):
        return "utf-16-le"
    if head.startswith(b"\xfe\xff"):
        return "utf-16-be"
    sample = head[:200]
    if len(sample) >= 8 and sample.count(0) * 2 >= len(sample) - 1:  # ASCII text in UTF-16 without a mark
        return "utf-16-le" if not any(sample[1::2]) else "utf-16-be" if not any(sample[0::2]) else None
    return None


def _table_start(lines: list[str], first: int, stated: str | None, wait_for_row: bool) -> int | None:
    """The header's line among the complete ``lines``: ``first`` (the first line that is no
    comment), unless the lines after it do not continue its table and a later line heads one: a
    logger's settings ("Model,GL240", "Interval: 60 s") before the header, without ``#``.

    ``first`` heads a table when the lines after it (up to 20) have as many cells. A later line
    heads one when, besides, it begins a block (after a blank line, or a line with another number
    of cells), begins like no data row, and the first row after it (or after a units row) begins
    like a data row, with its time: a bad first data row is not taken for a header. Where no line
    does, ``first`` (a log whose rows do not match its header in number: a delimiter at the end of
    each row). A live log (``wait_for_row``) needs a data row below ``first`` too, and waits for
    more lines (None) while none is found.
    """
    if first >= len(lines):
        return first
    delimiter = _table_delimiter(lines, first, stated)
    if delimiter is not None and (not wait_for_row or _data_row_below(lines, first, delimiter)):
        return first
    for k in range(first + 1, len(lines)):
        if _blank_like(lines[k]) or _data_like(lines[k]):
            continue
        delimiter = _table_delimiter(lines, k, stated)
        # a line inside a table (a bad first row below its header) heads none
        if delimiter is None:
            continue
        above = next(csv.reader([lines[k - 1]], delimiter=delimiter), [])
        # (a title padded with delimiters, "Plot Title: 20827226,,,,", is no row of a table)
        inside = sum(bool(c.strip()) for c in above) >= 2 and len(above) == len(next(csv.reader([lines[k]], delimiter=delimiter)))
        if not inside and _data_row_below(lines, k, delimiter):
            return k
    written = [line for line in lines[first:] if not _blank_like(line)]
    if wait_for_row and len(written) <= _TABLE_LOOKAHEAD + 1:
        return None
    return first


# rows after a header that must match it in number of cells
_TABLE_LOOKAHEAD = 20
# rows between a header and its first data row: a units row, a second row of names, a logger's
# description of its channels (Tinytag: S/N, Type, Description, Property), empty rows, section tags
_MAX_EXTRA_ROWS = 6
# a date or a time of day somewhere in a cell
_STAMP_LIKE = re.compile(r"\d{1,4}[./-]\d{1,2}[./-]\d{1,4}|\d{1,2}:\d{2}")


def _following(lines: list[str], k: int) -> list[str]:
    return [line for line in lines[k + 1 : k + 1 + _TABLE_LOOKAHEAD] if not _blank_like(line)]


def _blank_like(line: str) -> bool:
    """A line that belongs to no table: empty, empty cells alone (",,,"), or a section tag
    alone ("[#D],,,", "[Data]", as Rotronic writes its file's parts)."""
    core = line.strip().strip(",;\t").strip()
    if not core.strip('",;\t '):
        return True
    if core.startswith("***") and core.endswith("***"):  # LabVIEW's ***End_of_Header***
        return True
    return core.startswith("[") and "]" in core and not any(d in core for d in _DELIMITERS)


def _table_delimiter(lines: list[str], k: int, stated: str | None) -> str | None:
    """A delimiter that splits line ``k`` into two written cells or more and the lines after it into as many."""
    following = _following(lines, k)
    for delimiter in (stated,) if stated else _DELIMITERS:
        cells = next(csv.reader([lines[k]], delimiter=delimiter), [])
        if sum(bool(c.strip()) for c in cells) >= 2 and following and all(_continues(row, cells) for row in csv.reader(following, delimiter=delimiter)):
            return delimiter
    return None


def _continues(row: list[str], header: list[str]) -> bool:
    """Whether a row has as many cells as the ``header``, or one more that is empty (a delimiter
    at the end of each data row but not of the header, as a climate controller writes it), or one
    fewer where the header ends in LabVIEW's "Comment" column, which its rows leave out."""
    count = len(header)
    return len(row) == count or (len(row) == count + 1 and not row[-1].strip()) or (len(row) == count - 1 and header[-1].strip() == "Comment")


def _data_row_below(lines: list[str], k: int, delimiter: str) -> bool:
    """Whether a data row follows line ``k``, directly or after rows that describe its columns."""
    return _extra_rows(lines, k, delimiter) is not None


def _extra_rows(lines: list[str], k: int, delimiter: str) -> int | None:
    """How many lines come between the header at line ``k`` and its first data row (a units
    row, rows that describe the columns, empty rows, section tags); None if no data row follows
    within ``_MAX_EXTRA_ROWS`` of them. Rows that describe the columns come straight under the
    header: after an empty row, a row of names heads a table of its own (a logger's settings
    line "Interval,60,s" above a blank line and the real header is no header)."""
    blank_seen = False
    for j, line in enumerate(lines[k + 1 : k + 2 + _MAX_EXTRA_ROWS]):
        cells = [c.strip() for c in next(csv.reader([line], delimiter=delimiter), [])]
        if _data_row(cells):
            return j
        blank_seen = blank_seen or _blank_like(line)
        if not (_blank_like(line) or (_describes(cells) and not blank_seen)):
            return None
    return None


def _data_row(cells: list[str]) -> bool:
    """Cells that begin like a data row: with a number or a date, or with text before a time
    stamp (a wireless logger's receiver and transmitter names before the date)."""
    if cells and _data_like(cells[0]):
        return True
    return len(cells) >= 3 and bool(cells[0]) and any(_STAMP_LIKE.search(c) for c in cells[1:4])


def _describes(cells: list[str]) -> bool:
    """A row under the header that describes the columns and holds no readings: no number in
    it (units, names, types), or its first or second cell empty where a data row has its time
    (Tinytag's "S/N,,227659"): a row whose time is text ("yesterday,20") is a bad data row."""
    return not any(_is_number(c) for c in cells if c) or not all(cells[:2])


def _data_like(line: str) -> bool:
    """A line that begins like a data row: with a number or a date (a digit, a sign or a point)."""
    text = line.strip().lstrip('"')
    return text[:1].isdigit() or (text[:1] in "+-." and text[1:2].isdigit())


def _is_units_row(cells: list[str], dialect: CsvDialect) -> bool:
    """No cell is a number and one at least is a unit this module knows: a units row, not a data
    row (a data row's time stamp with every sensor empty has no unit in it)."""

    def number(cell: str) -> bool:
        try:
            dialect.number(cell)
        except ValueError:
            return False
        return True

    known = [c for c in cells if _unit_key(c) in _TIME_UNIT_NAMES or _unit_key(c) in _TEMPERATURE_UNITS]
    return bool(known) and not any(number(c) for c in cells if c)


def _delimiter(header: str, rows: list[str]) -> str:
    """The candidate that splits the header most often and the data rows into as many cells
    (a tie in the header, "Zeit;Temp, Spindel;Temp, Motor", is settled by the rows)."""
    cells = {d: next(csv.reader([header], delimiter=d)) for d in _DELIMITERS}
    counts = {d: len(cells[d]) for d in _DELIMITERS}
    # on a full tie ';' and tab come first: decimal commas in the rows can match commas in the names
    ranked = sorted((d for d in (";", "\t", ",") if counts[d] > 1), key=lambda d: -counts[d])
    for d in ranked:
        if all(_continues(row, cells[d]) for row in csv.reader([r for r in rows if not _blank_like(r)], delimiter=d)):
            return d
    return ranked[0] if ranked else ","


def header_names(file: Path) -> list[str]:
    """The column names of a log, read from its head only (a live log may be large); [] while
    its header line is incomplete."""
    with file.open("rb") as handle:
        head = handle.read(HEAD_BYTES)
    dialect = sniff_dialect(head)
    if dialect is None:
        return []
    return [name for name in dialect.cells(_header_line(head, dialect)) if name]


def _header_line(head: bytes, dialect: CsvDialect) -> str:
    return dialect.decode(head).split("\n")[dialect.preamble_lines]


def check_unique_names(header: list[str], source: str | Path) -> None:
    """InputError if two columns share a name: which one a sensor name meant could not be told
    (pandas would call the second 'T1.1', a reader by name would read the first twice)."""
    seen: dict[str, int] = {}
    for position, name in enumerate(header, start=1):
        if name and name in seen and not time_named(name):  # a repeated time column's name: no sensor is meant
            msg = f"{source}: the column name {name!r} appears twice (columns {seen[name]} and {position}); give each column its own name"
            raise InputError(msg)
        seen[name] = position


def read_csv(path: str | Path) -> tuple[pd.DataFrame, CsvDialect]:
    """A whole CSV file as a DataFrame, read in its own dialect; InputError, naming ``path`` as
    given, if it is missing or no CSV.

    An empty column without a name (a delimiter at the end of every line) is dropped.
    """
    import pandas as pd

    file = Path(path)
    if not file.is_file():
        msg = f"{path}: no such file"
        raise InputError(msg)
    with file.open("rb") as handle:
        head = handle.read(HEAD_BYTES)
    # the whole file fits in the head: its last line is complete even without a newline
    whole = len(head) < HEAD_BYTES
    dialect = sniff_dialect(head, whole=whole)
    if dialect is None and whole and head.strip():
        msg = f"{path}: no header line, only # comments and blank lines"
        raise InputError(msg)
    dialect = dialect or CsvDialect()
    if head.strip():
        check_unique_names(dialect.cells(_header_line(head, dialect)), path)
    try:
        frame = pd.read_csv(
            file,
            sep=dialect.delimiter,
            decimal=dialect.decimal,
            # the preamble, and a units row under the header
            skiprows=[*range(dialect.preamble_lines), *range(dialect.preamble_lines + 1, dialect.head_lines)],
            encoding=dialect.encoding,
            skipinitialspace=True,
            # a delimiter at the end of the data rows alone: the first column stays the time, not an index
            index_col=False,
        )
    except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
        msg = f"{path}: not a readable CSV file ({str(exc).splitlines()[0]})"
        raise InputError(msg) from exc
    frame.columns = [str(c).removeprefix("\ufeff") for c in frame.columns]  # UTF-16's byte-order mark
    unnamed = [c for c in frame.columns if str(c).startswith("Unnamed: ") and frame[c].isna().all()]
    return frame.drop(columns=unnamed), dialect


def _decodes(data: bytes, encoding: str = "utf-8-sig") -> bool:
    try:
        data.decode(encoding)
    except UnicodeDecodeError:
        return False
    return True


def date_and_clock(date_cell: str, clock_cell: str) -> bool:
    """Whether two cells are a date alone and a time of day: a logger that writes its time stamp
    in two columns (``Datum;Uhrzeit``, ``Date\tTime``), read as one stamp, date first."""
    if ":" not in clock_cell or not any(mark in date_cell for mark in "./-"):
        return False  # not worth importing pandas (0.5 s that a numeric live log does not need)
    return _parses(date_cell, _DATE_FORMATS) and _parses(clock_cell, TIME_OF_DAY_FORMATS)


def _parses(cell: str, formats: tuple[str, ...]) -> bool:
    import pandas as pd

    for fmt in formats:
        try:
            pd.to_datetime(cell.strip(), format=fmt)
        except (ValueError, TypeError):
            continue
        return True
    return False


def after_midnight(previous_min: float | None, t_min: float) -> float:
    """A time of day (minutes from the first one) on the day of the row before, or a later one: an
    overnight test passes midnight, and a step back of more than 12 h is the next day. Both readers
    of a log use it, row by row."""
    if previous_min is None:
        return t_min
    return t_min + MINUTES_PER_DAY * max(math.ceil((previous_min - t_min - MINUTES_PER_DAY / 2) / MINUTES_PER_DAY), 0)


def other_date_order(fmt: str | None) -> str | None:
    """The same format with day and month swapped, for a slashed date; None for any other."""
    if fmt is not None and fmt.startswith(("%m/%d/", "%d/%m/")):
        return ("%d/%m/" if fmt.startswith("%m/%d/") else "%m/%d/") + fmt[6:]
    return None


def stamp_format(cell: str) -> str | None:
    """The pandas format of a time-stamp cell: "ISO8601", one of the dotted day-first or
    time-of-day formats, or None if it is no time stamp."""
    import pandas as pd

    text = cell.strip()
    for fmt in ("ISO8601", *_STAMP_FORMATS):
        try:
            pd.to_datetime(text, format=fmt, utc=True)
        except (ValueError, TypeError):
            continue
        return fmt
    return None
