"""Time stamps as loggers write them, read into minutes.

ISO 8601; ``22.11.2026 08:00:00`` (day first, as everywhere dots separate the
date; so ``22-11-2026``, ``22-Nov-2026`` and ``22-Nov-26 8:00:00 am``);
``11/22/2026 3:05:00 PM`` (month first, as US loggers write it, unless the log
shows day first: :func:`other_date_order`); the time of day before the date
(``08:00:00 22/Nov/2026``); the time of day alone (:func:`after_midnight`); a
date and a time of day in two columns (:func:`date_and_clock`). The format is
taken from the first stamp (:func:`stamp_format`) and kept for the log.
"""

from __future__ import annotations

import datetime as dt
import math
import re

__all__ = [
    "stamp_format",
    "other_date_order",
    "after_midnight",
    "date_and_clock",
    "parses_as",
    "TIME_OF_DAY_FORMATS",
    "DATE_FORMATS",
    "MINUTES_PER_DAY",
    "IMPLAUSIBLE_STEP_MIN",
    "clock_change",
    "elapsed_minutes",
    "CLOCK_DAY_ZERO_MIN",
    "clock_change_note",
    "has_utc_offset",
]

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
_DASHED = tuple(
    f"%d-{month}-{year} {clock}" for month in ("%m", "%b") for year in ("%Y", "%y") for clock in TIME_OF_DAY_FORMATS
)
_SLASHED = tuple(
    f"{date} {clock}"
    for date in ("%m/%d/%Y", "%m/%d/%y", "%d/%m/%Y", "%d/%m/%y", "%d/%b/%Y", "%d/%b/%y")
    for clock in TIME_OF_DAY_FORMATS
)
# The time of day before the date (Hanwell: 08:00:00 22/Nov/2026), and a comma between a dotted
# date and the time inside one ';'-separated cell (a climate controller's "date,time" column).
_TIME_FIRST = tuple(
    f"{clock} {date}"
    for date in ("%d/%b/%Y", "%d/%b/%y", "%d-%b-%Y", "%d.%m.%Y", "%d.%m.%y", "%Y-%m-%d")
    for clock in TIME_OF_DAY_FORMATS
)
_DOTTED_COMMA = tuple(f"%d.%m.{year},{clock}" for year in ("%Y", "%y") for clock in TIME_OF_DAY_FORMATS)
_STAMP_FORMATS = (
    *_DOTTED,
    *_DASHED,
    *_SLASHED,
    *_TIME_FIRST,
    *_DOTTED_COMMA,
    "%Y-%m-%d %I:%M:%S %p",
    "%Y-%m-%d %I:%M %p",
    *TIME_OF_DAY_FORMATS,
)
MINUTES_PER_DAY = 1440.0
# a step that long between two rows of a warm-up log is a date read in the wrong order
IMPLAUSIBLE_STEP_MIN = 20 * MINUTES_PER_DAY
# a date without a time: the first of two time-stamp columns
DATE_FORMATS = (
    "%d.%m.%Y",
    "%d.%m.%y",
    "%d-%m-%Y",
    "%d-%b-%Y",
    "%d-%m-%y",
    "%d-%b-%y",
    "%Y-%m-%d",
    "%Y/%m/%d",
    "%m/%d/%Y",
    "%m/%d/%y",
    "%d/%m/%Y",
    "%d/%m/%y",
    "%d/%b/%Y",
)


def date_and_clock(date_cell: str, clock_cell: str) -> bool:
    """Whether two cells are a date alone and a time of day: a logger that writes its time stamp
    in two columns (``Datum;Uhrzeit``, ``Date\tTime``), read as one stamp, date first.

    Parameters
    ----------
    date_cell : str
        The first cell, which must hold a date alone ("22.11.2026", "2026-11-22", "11/22/2026").
    clock_cell : str
        The next cell, which must hold a time of day alone ("08:00:00", "8:00 AM").

    Returns
    -------
    bool
        True where the first reads in one of ``DATE_FORMATS`` and the second in one of
        ``TIME_OF_DAY_FORMATS``.
    """
    if ":" not in clock_cell or not any(mark in date_cell for mark in "./-"):
        return False  # not worth importing pandas (0.5 s that a numeric live log does not need)
    return parses_as(date_cell, DATE_FORMATS) and parses_as(clock_cell, TIME_OF_DAY_FORMATS)


def parses_as(cell: str, formats: tuple[str, ...]) -> bool:
    """Whether a cell reads in one of the (pandas/strptime) formats.

    Parameters
    ----------
    cell : str
        The cell as written (surrounding spaces are ignored).
    formats : tuple of str
        strptime formats, such as ``DATE_FORMATS`` or ``TIME_OF_DAY_FORMATS``.

    Returns
    -------
    bool
        True where ``pandas.to_datetime`` reads the cell in one of them.
    """
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
    of a log use it, row by row.

    Parameters
    ----------
    previous_min : float or None
        The time of the row before (min), as already moved on; None for the first row.
    t_min : float
        This row's time of day (min from the first row's), as read.

    Returns
    -------
    float
        ``t_min`` plus as many whole days (1440 min) as make it no more than 12 h before
        ``previous_min``; ``t_min`` itself for the first row.
    """
    if previous_min is None:
        return t_min
    return t_min + MINUTES_PER_DAY * max(math.ceil((previous_min - t_min - MINUTES_PER_DAY / 2) / MINUTES_PER_DAY), 0)


def other_date_order(fmt: str | None) -> str | None:
    """The same format with day and month swapped, for a slashed date; None for any other.

    Parameters
    ----------
    fmt : str or None
        A strptime format, as :func:`stamp_format` gives it.

    Returns
    -------
    str or None
        ``%d/%m/...`` for ``%m/%d/...`` and the reverse, the rest of the format kept.
    """
    if fmt is not None and fmt.startswith(("%m/%d/", "%d/%m/")):
        return ("%d/%m/" if fmt.startswith("%m/%d/") else "%m/%d/") + fmt[6:]
    return None


def stamp_format(cell: str) -> str | None:
    """The pandas format of a time-stamp cell: "ISO8601", one of the dotted day-first or
    time-of-day formats, or None if it is no time stamp.

    Parameters
    ----------
    cell : str
        A cell of the time column, as written.

    Returns
    -------
    str or None
        The first format (ISO 8601 first, then the others in order) in which pandas reads the cell.
    """
    import pandas as pd

    text = cell.strip()
    for fmt in ("ISO8601", *_STAMP_FORMATS):
        try:
            pd.to_datetime(text, format=fmt, utc=True)
        except (ValueError, TypeError):
            continue
        return fmt
    return None


# Summer time begins and ends on a Sunday between 01:00 and 04:00 of the local clock, in these
# months: Europe March and October, North America March and November, Australia and New Zealand
# April, September and October.
_CLOCK_CHANGE_MONTHS = (3, 4, 9, 10, 11)
_EPOCH = dt.datetime(1970, 1, 1)
_UTC_OFFSET = re.compile(r"(Z|[+-]\d\d:?\d\d)$")


def has_utc_offset(stamp: str) -> bool:
    """Whether a time stamp carries its offset from UTC (``2026-10-25T02:30:00+01:00``, ``...Z``):
    such stamps stay in order when summer time ends, and no clock change is looked for.

    Parameters
    ----------
    stamp : str
        A time stamp as written.

    Returns
    -------
    bool
        True where it ends in "Z" or a ±hh:mm (or ±hhmm) offset.
    """
    return bool(_UTC_OFFSET.search(stamp.strip()))


def clock_change(before_min: float, after_min: float, interval_min: float | None) -> float:
    """Minutes the local clock was put back between two stamps written without an offset:
    +60 where summer time ended (02:59 then 02:00), −60 where it began (01:59 then 03:00), else 0.

    The stamps are minutes since 1970 as the clock wrote them. Told by the step: an hour back
    or forward more than the log's steps make it (corrected, it moves on by at most two
    ``interval_min``, the step before; None between a log's first two rows, where only the
    hour and the day tell), from a stamp between 01:00 and 04:00 of the clock to another, on a
    Sunday of a month in which summer time begins or ends somewhere. A step back cannot be a
    real pause; a step forward could be one of an hour to the minute at that hour of that
    Sunday, which the readers' notes name.

    Parameters
    ----------
    before_min, after_min : float
        The two stamps, in minutes since 1970-01-01 00:00 of the logger's clock.
    interval_min : float or None
        The log's step before these two (min), or None at its first two rows.

    Returns
    -------
    float
        The shift to add to the stamps from ``after_min`` on (min): +60, −60 or 0.
    """
    step = after_min - before_min
    shift = 60.0 if step < 0 else -60.0
    if not 0.0 < step + shift <= (60.0 if interval_min is None else 2.0 * interval_min + 1e-9):
        return 0.0
    before, after = (_EPOCH + dt.timedelta(minutes=m) for m in (before_min, after_min))
    on_a_change_day = after.weekday() == 6 and after.month in _CLOCK_CHANGE_MONTHS and after.date() == before.date()
    return shift if on_a_change_day and 1 <= before.hour < 4 and 1 <= after.hour < 4 else 0.0


def clock_change_note(shift: float, where: str, before: str, after: str) -> str:
    """What a reader did at a clock change (:func:`clock_change`), for the engineer.

    Parameters
    ----------
    shift : float
        The shift :func:`clock_change` gave (min): positive where summer time ended, negative where it began.
    where : str
        Where in the log it happened ("at row 412", "after t = 95 min").
    before, after : str
        The two stamps as the log writes them.

    Returns
    -------
    str
        The note.
    """
    if shift > 0:
        return (
            f"the time stamps go back an hour {where} ({before} then {after}): read as the end of summer time; the "
            "rows from there on are taken an hour later"
        )
    return (
        f"the time stamps jump an hour {where} ({before} then {after}): read as the start of summer time; the rows "
        "from there on are taken an hour earlier "
        "(if the logger's clock does not change for summer time, the log paused for an hour here)"
    )


# Elapsed time written as a clock that runs past 24:00:00 ("26:15:00"): hours, minutes, seconds.
_ELAPSED = re.compile(r"(\d+):([0-5]\d):([0-5]\d(?:\.\d+)?)")
# the day a time of day alone is read on (strptime's 1 January 1900), in minutes since 1970
CLOCK_DAY_ZERO_MIN = (dt.datetime(1900, 1, 1) - _EPOCH).total_seconds() / 60.0


def elapsed_minutes(cell: str) -> float | None:
    """An elapsed time written as hours:minutes:seconds, in minutes (``26:15:30`` is 1575.5), or
    None: a log's time column that looks like a time of day but runs past 24:00:00 (a test of
    more than a day, timed from its start).

    Parameters
    ----------
    cell : str
        A cell of the time column, as written ("26:15:30", "1:05:00.5").

    Returns
    -------
    float or None
        The elapsed time (min), or None where the cell is not hours:minutes:seconds with minutes and
        seconds below 60.
    """
    matched = _ELAPSED.fullmatch(cell.strip())
    if matched is None:
        return None
    hours, mins, secs = matched.groups()
    return 60.0 * int(hours) + int(mins) + float(secs) / 60.0
