"""What each column of a log is: the time, a part of it, a sensor, or something to leave out.

A logger writes more than temperatures: a row counter before the time
(:func:`counter_before_time`), text columns before it (:func:`text_before_stamps`),
its milliseconds after it, more time columns (:func:`time_named`), its own
records (events, alarms, a serial number: :func:`event_named`), humidities and
other quantities (:func:`temperature_columns`). Both readers of a log decide
here, so that a live log and the finished file have the same sensors.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from pathlib import Path
from typing import Protocol

from mtident.exceptions import InputError
from mtident.io.stamps import DATE_FORMATS, parses_as, stamp_format
from mtident.io.units import (
    celsius_conversion,
    is_from_humidity,
    is_humidity,
    is_number,
    names_other_quantity,
    number_without_unit,
    stated_temperature_unit,
    unit_in_name,
    unit_key,
)

__all__ = [
    "column_named",
    "missing_column",
    "text_only_cells",
    "choose_time_column",
    "counter_before_time",
    "text_before_stamps",
    "millisecond_column",
    "time_named",
    "event_named",
    "temperature_columns",
    "sensor_unit",
    "check_header_names",
    "check_unique_names",
    "room_named",
    "unread_rooms",
]


class DialectView(Protocol):
    """What the column rules read of a log's dialect (:class:`mtident.io.dialect.CsvDialect`), which
    itself depends on these rules."""

    @property
    def units(self) -> tuple[tuple[str, str], ...]: ...

    @property
    def units_source(self) -> str: ...

    @property
    def from_humidity(self) -> tuple[str, ...]: ...

    def unit_of(self, column: str) -> str: ...


def text_only_cells(cells: list[str]) -> bool:
    """Whether a column's cells hold text and not one number (empty and NaN cells aside; a decimal
    comma counts as a number): a logger's status channel, no sensor. Both readers of a log use it.

    Parameters
    ----------
    cells : list of str
        The column's cells as written in the file (the first data rows, or the rows read so far).

    Returns
    -------
    bool
        True where at least one cell holds something other than NaN and none of them is a number (a
        number with its unit after it, "68.00 °F", counts: such a column among plain ones was left out).
    """
    written = [c.strip() for c in cells if c.strip() and c.strip().lower() != "nan"]
    return bool(written) and not any(is_number(number_without_unit(c)) for c in written)


# A first column that counts the rows (Graphtec's "NO.", Keysight's "Scan", "Nr.", "Index"), before the time column.
_COUNTER_NAMES = {"no", "nr", "number", "index", "#", "n", "sample", "samples", "count", "lfdnr", "scan", "record"}
# A column after the time stamp that holds its milliseconds (Graphtec: "NO.,Time,ms,CH1,...").
_MILLISECOND_NAMES = {"ms", "msec", "millisecond", "milliseconds"}


def counter_before_time(header: list[str], first_row: list[str], dialect: DialectView) -> bool:
    """Whether the first column counts rows and the second holds the time stamps (its first cell
    no plain number): a logger's sample counter, which read as minutes would be a wrong time. The
    counter is told by its name, or by its cell in the row under the header (Graphtec writes a
    Japanese header and "NO.,Time,ms,ﾟC" under it), or, whatever its name, as a whole number
    before a time stamp or a date (Tinytag leaves the name empty, Lascar's EasyLog puts the
    logger's name there, MadgeTech calls it "Reading #").

    Parameters
    ----------
    header : list of str
        The column names, in file order.
    first_row : list of str
        The cells of the first data row, as written.
    dialect : DialectView
        The log's dialect: its units row (Graphtec's row under the header), where the counter may be
        named instead of in the header.

    Returns
    -------
    bool
        True where the first column is a row counter and the second the time; False for fewer than
        three columns.
    """
    if len(header) < 3 or len(first_row) < 2:
        return False
    if (
        first_row[0].strip().isdigit()
        and not is_number(first_row[1])
        and first_row[1].strip()
        and (stamp_format(first_row[1]) or parses_as(first_row[1], DATE_FORMATS))
    ):
        return True
    if not {unit_key(header[0]), unit_key(dialect.unit_of(header[0]))} & _COUNTER_NAMES:
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
    a bad first time cell must not make a sensor the time).

    Parameters
    ----------
    first_row : list of str
        The cells of the first data row, as written; only the first four are looked at.

    Returns
    -------
    int
        The position (0 to 3) of the first column of time stamps, which is the number of text columns
        before it.
    """
    for k, cell in enumerate(first_row[:4]):
        text = cell.strip()
        if not text or is_number(text) or parses_as(text, DATE_FORMATS):  # a date: its time of day follows
            return 0
        if stamp_format(text) is not None:
            return k
    return 0


def choose_time_column(
    header: list[str], first_row: list[str], dialect: DialectView, time_col: str | None
) -> tuple[str, bool, list[str]]:
    """The time column's name (``time_col`` where given), whether the first column is a row
    counter before it, and notes; both readers of a log take the time column here, by the header
    and the first data row's cells.

    Parameters
    ----------
    header, first_row, dialect
        As for :func:`counter_before_time`.
    time_col : str or None
        The time column the user named (no counter or text columns are looked for then), or None to
        find it: the second column after a row counter, the first column of time stamps after text
        columns, else the first column.

    Returns
    -------
    name : str
        The time column's name.
    counter : bool
        Whether the first column is a row counter, left out.
    notes : list of str
        What was left out and which column is the time, for the user.
    """
    counter = time_col is None and counter_before_time(header, first_row, dialect)
    text_before = 0 if time_col is not None or counter else text_before_stamps(first_row)
    named = None if time_col is not None or counter or text_before else _named_time_after_first(header, first_row)
    name = time_col or (named if named is not None else header[1 if counter else text_before])
    # pandas names an unnamed column "Unnamed: 0", the follower ""
    first = header[0] if header[0].strip() and not header[0].startswith("Unnamed: ") else "the unnamed first column"
    notes = [f"left out, a row counter: {first}; the time is {name!r}"] if counter else []
    if text_before:
        notes.append(f"the time is {name!r}, the first column of time stamps")
    if named is not None:
        notes.append(f"the time is {name!r}, the column named as the time; {first!r} before it is read as a sensor")
    return name, counter, notes


def _named_time_after_first(header: list[str], first_row: list[str]) -> str | None:
    """A column named as the time after a first column of numbers that is not (a log whose first
    column is the room: its readings were taken for the time, and refused as a "duplicate time
    19.997" with no word of the time column); None where the first column is the time's or none is."""
    if not header or time_named(header[0]) or not first_row or not is_number(first_row[0].strip()):
        return None
    return next((name for name in header[1:] if time_named(name)), None)


def millisecond_column(header: list[str], last_time_column: int) -> int | None:
    """The column after the time stamp (or its clock column) if it is named as its milliseconds.

    Parameters
    ----------
    header : list of str
        The column names, in file order.
    last_time_column : int
        Position (from 0) of the time column, or of the clock column where date and clock are two columns.

    Returns
    -------
    int or None
        The position of the next column where it is named "ms", "msec", "millisecond(s)", else None.
    """
    following = last_time_column + 1
    return following if following < len(header) and unit_key(header[following]) in _MILLISECOND_NAMES else None


def time_named(name: str) -> bool:
    """Whether a column's name says it holds a time (a second time column, as T&D writes its
    stamps' spreadsheet serial dates beside them, or a controller's time difference): no sensor.

    Parameters
    ----------
    name : str
        The column name as read (pandas' ".1" suffix of a repeated name is ignored).

    Returns
    -------
    bool
        True where the name, in lower case without spaces, brackets, points and underscores, begins with a
        word for time or date ("time", "Zeit", "Datum", "timestamp", "時間", ...).
    """
    key = unit_key(re.sub(r"\.\d+$", "", name))  # pandas' ".1" after a repeated name
    return key.startswith(_TIME_NAME_STARTS)


# what the names of time columns begin with
_TIME_NAME_STARTS = ("time", "date", "zeit", "datum", "uhrzeit", "timestamp", "日付", "時間", "時刻")
# A logger's records of itself: event channels (HOBOware writes "Logged" in them when the event
# happens, else nothing), its serial number (Lascar's EasyLog writes it in the first row alone),
# a comment column (LabVIEW's), alarm and status channels (Keysight BenchLink's "Alarm 101" holds
# 0 or 1: as a sensor it was flat, "no rise", or, once it switched, a 1-degree step taken for a warm-up).
_EVENT_NAME_STARTS = (
    "couplerdetached",
    "couplerattached",
    "hostconnected",
    "stopped",
    "endoffile",
    "buttonup",
    "buttondown",
    "badbattery",
    "goodbattery",
    "started",
    "serialnumber",
    "serialno",
    "comment",
    "alarm",
    "status",
    "flag",
    "event",
    "trigger",
    "logic",
    "pulse",
)


def event_named(name: str) -> bool:
    """Whether a column's name says it records the logger itself (HOBO's "Host Connected", a serial
    number): no sensor.

    Parameters
    ----------
    name : str
        The column name as read.

    Returns
    -------
    bool
        True where the name, in lower case without spaces, brackets, points and underscores, begins with
        an event, alarm, status, comment or serial-number word ("Host Connected", "Alarm 101", "Serial
        Number", ...).
    """
    return unit_key(name).startswith(_EVENT_NAME_STARTS)


# Names of a room sensor: inside a name ("T_room", "Raumtemperatur", "AmbientTemp") and as a word
# of its own (camelCase split), where a shorter one would hide in other words ("Chair", "Shall");
# "raum" alone is no part: "Bauraum" and "Arbeitsraum" are the machine's work space.
_ROOM_NAME_PARTS = (
    "room",
    "ambient",
    "ambiant",
    "umgebung",
    "raumtemp",
    "raumluft",
    "hallentemp",
    "hallenluft",
    "werkhalle",
    "lufttemp",
    "environment",
    "surrounding",
    "室温",
    "周囲",
)
_ROOM_NAME_WORDS = frozenset(
    {"amb", "tamb", "air", "env", "tenv", "raum", "halle", "hall", "luft", "umg", "tumg", "surr", "werkstatt"}
)


def room_named(name: str) -> bool:
    """Whether a column's name says it measures the room ("room", "T_amb", "Umgebung", "Air temp"):
    a candidate for ``--ambient``, which a user who did not give it is told of.

    Parameters
    ----------
    name : str
        As for :func:`event_named`.

    Returns
    -------
    bool
        True where the name contains a word for the room ("room", "ambient", "Umgebung", "室温", ...)
        or has a short one as a word of its own ("amb", "air", "env", "Raum", "Halle", ...).
    """
    lower = name.lower()
    if any(part in lower for part in _ROOM_NAME_PARTS):
        return True
    split = re.sub(r"([a-z])([A-Z])|([A-Z])([A-Z][a-z])", r"\1\3 \2\4", name)  # "AirTemp", "TAmb"
    words = re.findall(r"[a-z]+", split.lower())
    return any(word in _ROOM_NAME_WORDS for word in words)


def unread_rooms(header: list[str], read: list[str] | tuple[str, ...]) -> list[str]:
    """The columns of a log named as a room sensor (:func:`room_named`) that were not read, where the
    sensors read were named (``--sensor``): without ``--ambient`` such a room was passed over without
    a word, and a drifting room biases T∞.

    Parameters
    ----------
    header : list of str
        The log's column names.
    read : list of str or tuple of str
        The columns read as sensors.

    Returns
    -------
    list of str
        Those columns, in file order, but for one whose name says it is no temperature (a time, the
        logger's own record, a humidity or a value computed from it, a unit such as "%").
    """
    return [
        name
        for name in header
        if name not in read
        and room_named(name)
        and not (time_named(name) or event_named(name) or is_humidity(name) or is_from_humidity(name))
        and celsius_conversion(unit_in_name(name)) is not None
    ]


def sensor_unit(name: str, dialect: DialectView, temperature_unit: str | None = None) -> str:
    """The unit a sensor column's readings are in, as written: its own (a units row, its cells, its
    name), else the unit ``temperature_unit`` states for the columns without one, else "" (°C).
    Both readers of a log convert by it (:func:`~mtident.io.units.celsius_conversion`);
    :func:`temperature_columns` refuses a column whose own unit ``temperature_unit`` contradicts.

    Parameters
    ----------
    name : str
        The sensor column's name.
    dialect : DialectView
        The log's dialect: the units it states.
    temperature_unit : str or None, optional
        The unit the user states ("C", "F" or "K"); None: the log's own, °C where it states none.

    Returns
    -------
    str
        The column's own unit as written ("[°F]", "K"), "°C", "°F" or "K" by ``temperature_unit``, or "".

    Raises
    ------
    InputError
        ``temperature_unit`` is no unit of temperature.
    """
    own = dialect.unit_of(name)
    stated = stated_temperature_unit(temperature_unit)
    return own if own.strip() or stated is None else stated


def temperature_columns(
    names: list[str],
    asked: bool,
    dialect: DialectView,
    source: str | Path,
    temperature_unit: str | None = None,
) -> tuple[list[str], list[str]]:
    """The sensor columns to read, and notes, by their units (a units row, or a unit in the name).

    A column whose unit is no temperature (a logger's speed or voltage channel),
    or that is named as a humidity, is left out of the default selection with a
    note, and refused when ``asked`` for by name; one in K or °F is converted,
    with a note. A column without a unit of its own is in ``temperature_unit``
    (°C without it); one whose own unit is another temperature unit than
    ``temperature_unit`` is refused: which of the two is right cannot be told.

    Parameters
    ----------
    names : list of str
        The candidate sensor columns: all but the time columns, or the ones the user asked for.
    asked : bool
        ``names`` are the sensors the user named: none is left out for its name (a time, an event, a
        value computed from the humidity), and a humidity or a column in another unit is an error.
    dialect : DialectView
        The log's dialect: each column's unit (from a units row or the name) and the columns computed
        from the humidity.
    source : str or Path
        The log, named in the notes and messages.
    temperature_unit : str or None, optional
        The unit of the temperature columns without a unit of their own: "C", "F" or "K" (the command
        line's --unit); None: °C.

    Returns
    -------
    sensors : list of str
        The temperature columns (°C, K or °F), in the order of ``names``.
    notes : list of str
        What was left out or converted, and why.

    Raises
    ------
    InputError
        A column asked for is a humidity or in a unit that is no temperature, no column is left,
        ``temperature_unit`` is no unit of temperature, or a column's own unit contradicts it.
    """
    stated = stated_temperature_unit(temperature_unit)
    kept, notes, other, times, events, computed, by_option, quantities = [], [], [], [], [], [], [], []
    for name in names:
        if not asked and time_named(name):
            times.append(name)
            continue
        if not asked and event_named(name):
            events.append(name)
            continue
        if not asked and (is_from_humidity(name) or name in dialect.from_humidity):
            computed.append(name)
            continue
        by = dialect.units_source if dict(dialect.units).get(name, "").strip() else "its name"
        written = dialect.unit_of(name)
        unit = written.strip().strip("[]()").strip()  # as written, without brackets
        if not unit and not asked and names_other_quantity(name):
            quantities.append(name)
            continue
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
            other.append(name if unit_in_name(name) else f"{name} ({unit})")  # "Speed (rpm)", not "(rpm) (rpm)"
            continue
        if stated is not None and unit and conversion != celsius_conversion(stated):
            msg = (
                f"{source}: sensor {name!r} is in {unit} by {by}, but `temperature_unit={temperature_unit!r}` says "
                f"the temperatures are in {stated}; leave the option out to read each column in its own unit, or "
                f"correct {by}"
            )
            raise InputError(msg)
        if not unit and stated is not None:
            conversion = celsius_conversion(stated)
            if conversion != (1.0, 0.0):
                by_option.append(name)
        elif conversion != (1.0, 0.0):
            notes.append(f"sensor {name!r}: read in {unit} ({by}), converted to °C")
        kept.append(name)
    if by_option:
        notes.append(f"read in {stated} (`temperature_unit`), converted to °C: {', '.join(by_option)}")
    by = dialect.units_source if dialect.units else "its name"
    if times:
        notes.append(f"left out, named as times: {', '.join(times)}")
    if events:
        notes.append(f"left out, the logger's own records: {', '.join(events)}")
    if computed:
        notes.append(
            "left out, computed from the humidity (a dew point, wet-bulb temperature or heat index; `sensors` reads "
            f"one all the same): {', '.join(computed)}"
        )
    if other:
        notes.append(f"left out, not temperatures by {by}: {', '.join(other)}")
    if quantities:
        notes.append(
            "left out, named as another quantity (a power, a speed, a torque, a pressure; `sensors` reads one all "
            f"the same): {', '.join(quantities)}"
        )
    if not kept:
        left_out = [
            *(f"{n} (named as a time)" for n in times),
            *(f"{n} (named as another quantity)" for n in quantities),
            *(f"{n} (the logger's own record)" for n in events),
            *(f"{n} (computed from the humidity)" for n in computed),
        ]
        if other:
            left_out.append(f"by {by}: {', '.join(other)}")
        msg = (
            f"{source}: no temperature column; left out: {'; '.join(left_out)} (`sensors=[NAME]` reads a column all "
            "the "
            "same, if it is a temperature)"
        )
        raise InputError(msg)
    return kept, notes


_STAMP_LIKE = re.compile(r"^\s*\d{1,4}([-./:]\d{1,4})+([ T]\d{1,2}(:\d{1,2})+)?\s*$")


def check_header_names(header: list[str], number: Callable[[str], float], source: str | Path) -> None:
    """InputError where the header holds readings, not names (a log written without its header
    line: its first readings became column names, "20.003" a sensor, and the first row was lost),
    or two columns share a name (:func:`check_unique_names`).

    Parameters
    ----------
    header : list of str
        The column names, in file order.
    number : callable
        The log's number reader (its decimal mark): raises ValueError for a cell that is none.
    source : str or Path
        The log, named in the message.

    Raises
    ------
    InputError
        Every name a number but perhaps the first, itself a number or a time stamp.
    """

    def is_number(cell: str) -> bool:
        try:
            number(cell)
        except ValueError:
            return False
        return True

    named = [cell for cell in header if cell.strip()]
    if len(named) >= 2 and all(map(is_number, named[1:])) and (is_number(named[0]) or _STAMP_LIKE.match(named[0])):
        shown = ", ".join(named[:4]) + (", ..." if len(named) > 4 else "")
        msg = (
            f"{source}: the header ({shown}) holds readings, not column names: a log needs a header naming its "
            "columns above the readings (time_min,T1,T2,...); add one, or export the log with its header"
        )
        raise InputError(msg)
    check_unique_names(header, source)


def check_unique_names(header: list[str], source: str | Path) -> None:
    """InputError if two columns share a name: which one a sensor name meant could not be told
    (pandas would call the second 'T1.1', a reader by name would read the first twice).

    Parameters
    ----------
    header : list of str
        The column names, in file order; empty names and repeated time columns are let pass.
    source : str or Path
        The log, named in the message.

    Raises
    ------
    InputError
        Two columns share a name; the message gives both positions (from 1).
    """
    seen: dict[str, int] = {}
    for position, name in enumerate(header, start=1):
        if name and name in seen and not time_named(name):  # a repeated time column's name: no sensor is meant
            msg = (
                f"{source}: the column name {name!r} appears twice (columns {seen[name]} and {position}); give each "
                "column its own name"
            )
            raise InputError(msg)
        seen[name] = position


def _without_unit(name: str) -> str:
    """A column's name as compared by :func:`column_named`: its unit ("[°C]", "/K") left off."""
    unit = unit_in_name(name)
    return unit_key(name[: name.rfind(unit)] if unit else name)


def column_named(name: str, header: list[str] | tuple[str, ...]) -> str:
    """The column a user's name means: itself where the log has it, else the one column whose name
    is it with a unit ("Room" for ``Room [°C]``, "t1" for ``T1 / K``), else the name as given (the
    reader then says that the log has no such column, and which it has).

    Parameters
    ----------
    name : str
        A column's name as the user gave it (--sensor, --ambient, --wait-for).
    header : list of str or tuple of str
        The log's column names.

    Returns
    -------
    str

    Examples
    --------
    >>> column_named("Room", ["Time [min]", "T1 [°C]", "Room [°C]"]), column_named("T", ["T1 [°C]", "T2 [°C]"])
    ('Room [°C]', 'T')
    """
    if name in header:
        return name
    bare = _without_unit(name)
    matches = [column for column in header if _without_unit(column) == bare]
    return matches[0] if len(matches) == 1 else name


def missing_column(source: object, name: str, available: list[str] | tuple[str, ...]) -> str:
    """The message for a column the log does not have: the columns it has, and the nearest one
    where the name differs only a little (a capital letter, a typing slip).

    Parameters
    ----------
    source : object
        The log (a path, or a live source's description), named first in the message.
    name : str
        The sensor column that was asked for.
    available : list of str or tuple of str
        The log's sensor columns.

    Returns
    -------
    str
        The message, ending in the columns the log has.
    """
    import difflib

    near = [c for c in available if c.lower() == name.lower()] or difflib.get_close_matches(name, available, n=1)
    hint = f" (did you mean {near[0]!r}?)" if near else ""
    return f"{source}: no sensor column {name!r}{hint}; the log has: {', '.join(available)}"
