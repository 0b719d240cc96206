"""What the log readers say of a time column: its unit (stated, given or assumed), spreadsheet
serial dates, gaps between readings, and the hints that a column read as minutes is in seconds or
hours. Both readers of a log (:func:`~mtident.io.logs.read_temperature_log` and the live
:class:`~mtident.io.follow.LogFollower`) say them in these words.
"""

from __future__ import annotations

import datetime as dt
import math

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError

__all__ = [
    "TIME_UNITS",
    "UNLIKELY_MINUTES",
    "GAP_FACTOR",
    "GAP_MIN_MIN",
    "HOURS_HINT_SAMPLES",
    "SPARSE_HINT_STEP_MIN",
    "SPARSE_HINT_ROWS",
    "time_unit_factor",
    "unit_overridden_note",
    "time_unit_assumed",
    "names_a_date",
    "serial_date_note",
    "serial_date_hint",
    "read_as_minutes",
    "seconds_hint",
    "gap_note",
    "gap_said",
    "sparse_hint",
    "unit_hint",
    "hours_hint",
]

TIME_UNITS = {"ms": 1.0 / 60_000.0, "s": 1.0 / 60.0, "min": 1.0, "h": 60.0, "d": 1440.0}


def _suffix_unit(header: str) -> str | None:
    """The unit a time column's name ends in: Time_s, t_min, hours_h."""
    return next((unit for unit in TIME_UNITS if header.lower().endswith("_" + unit)), None)


def time_unit_factor(header: str, time_unit: str | None, stated: str | None = None) -> float:
    """Minutes per unit of a numeric time column: ``time_unit``, else the header's suffix (_s, _min,
    _h), else the unit ``stated`` by a units row or in the name's brackets (``Time [s]``), else minutes.

    Parameters
    ----------
    header : str
        The time column's name (a suffix such as ``_s`` or ``_min`` states its unit).
    time_unit : str or None
        The unit the user gave: "ms", "s", "min", "h" or "d"; None to take it from the log.
    stated : str or None, optional
        The unit the log states for the column (units row or brackets in the name), as a key of
        ``TIME_UNITS``; None where it states none.

    Returns
    -------
    float
        Minutes per unit of the column (1/60 for seconds, 60 for hours, 1440 for days).

    Raises
    ------
    InputError
        ``time_unit`` is not one of the units.
    """
    if time_unit is not None:
        if time_unit not in TIME_UNITS:
            msg = f"time unit {time_unit!r} is not one of: {', '.join(TIME_UNITS)}"
            raise InputError(msg)
        return TIME_UNITS[time_unit]
    suffix = _suffix_unit(header)
    if suffix is not None and stated is not None and TIME_UNITS[suffix] != TIME_UNITS[stated]:
        # "time_min" over a units row of "h": read as minutes, without a word, sixty times too fast
        msg = (
            f"time column {header!r}: its name says {suffix!r}, but the log states {stated!r} for it (under the "
            f"header or in brackets), and which is right cannot be told; give the unit (`time_unit='{stated}'` or "
            f"`time_unit='{suffix}'`), or mend the header"
        )
        raise InputError(msg)
    unit = suffix or stated
    return TIME_UNITS[unit] if unit is not None else 1.0


def unit_overridden_note(header: str, time_unit: str | None, stated: str | None) -> str | None:
    """What a reader says when the unit given (``time_unit``) differs from the one the log states
    for its time column (a suffix of its name, brackets or a units row): the option wins, and a
    slip in it rescales every time constant. None where they agree or either is missing.

    Parameters
    ----------
    header : str
        The time column's name.
    time_unit : str or None
        The unit the user gave.
    stated : str or None
        The unit a units row or brackets state, as a key of ``TIME_UNITS``.

    Returns
    -------
    str or None

    Examples
    --------
    >>> unit_overridden_note("time_s", "min", None) is not None, unit_overridden_note("time_s", "s", None)
    (True, None)
    """
    own = _suffix_unit(header) or stated
    if time_unit is None or own is None or TIME_UNITS.get(time_unit) == TIME_UNITS[own]:
        return None
    return (
        f"time column {header!r} states its unit as {own}, but `time_unit={time_unit!r}` reads it in {time_unit}: the "
        "option wins; leave it out if the column's own unit is right"
    )


# A warm-up is hours long: a time column read as minutes (no unit given anywhere) that runs past two
# days is more likely seconds.
UNLIKELY_MINUTES = 2 * 1440.0
# a step this many times the usual one, and this long (min), is a gap worth a note (:func:`gap_note`)
GAP_FACTOR = 10.0
GAP_MIN_MIN = 5.0
# readings enough to tell a log in hours read as minutes (:func:`hours_hint`)
HOURS_HINT_SAMPLES = 100
# a usual step this long (min), read as minutes for want of a unit, may be seconds (:func:`sparse_hint`)
SPARSE_HINT_STEP_MIN = 10.0
# the first readings whose usual step tells a column in seconds read as minutes
SPARSE_HINT_ROWS = 10


def time_unit_assumed(header: str, time_unit: str | None, stated: str | None) -> bool:
    """Whether :func:`time_unit_factor` falls back to minutes: no --time-unit, header suffix or units row.

    Parameters
    ----------
    header : str
        The time column's name.
    time_unit : str or None
        The unit the user gave, or None.
    stated : str or None
        The unit the log states for the column, or None.

    Returns
    -------
    bool
        True where neither ``time_unit``, a suffix of ``header`` nor ``stated`` gives a unit.
    """
    return time_unit is None and stated is None and _suffix_unit(header) is None


def names_a_date(header: str) -> bool:
    """Whether a time column's name says it holds dates (``Date``, ``Date/Time``, ``Datum``):
    spreadsheet serial dates in it are read as days, not refused.

    Parameters
    ----------
    header : str
        The time column's name.

    Returns
    -------
    bool
        True where the name contains "date", "Datum", "fecha", "日付" or "日時" (any case).
    """
    key = header.lower()
    return any(word in key for word in ("date", "datum", "fecha", "日付", "日時"))


def _serial_date(first: float) -> str:
    """A spreadsheet serial date (days since 30.12.1899) and the date it is, for a message."""
    when = dt.datetime(1899, 12, 30) + dt.timedelta(seconds=round(first * 86_400.0))
    return f"days since 30.12.1899: {first:.5f} is {when:%d.%m.%Y %H:%M:%S}"


def serial_date_note(header: str, first: float) -> str:
    """What a reader says when it reads a time column's spreadsheet serial dates as days.

    Parameters
    ----------
    header : str
        The time column's name.
    first : float
        The column's first value (days since 30.12.1899), shown with the date and time it is.

    Returns
    -------
    str
        The note, suggesting ``time_unit='min'`` where the column is minutes after all.
    """
    return (
        f"time column {header!r} read as spreadsheet serial dates ({_serial_date(first)}); give `time_unit='min'` if "
        "it "
        "is minutes"
    )


def serial_date_hint(header: str, first: float, step: float) -> str | None:
    """A message if a time column read as minutes holds spreadsheet serial dates (days since
    30.12.1899: 46348.33 is 22.11.2026 08:00, as a spreadsheet saves a date cell formatted as a
    number): read as minutes, a 2-h test lasted 0.08 min and was identified as nonsense.

    Parameters
    ----------
    header : str
        The time column's name.
    first : float
        The column's first value, as read.
    step : float
        The spacing of its values (the median step, or a later value less the first), in the same unit.

    Returns
    -------
    str or None
        The message, suggesting ``time_unit='d'``, where ``first`` is a fractional number from 20000
        to 80000 (the years 1954 to 2119) and ``step`` is positive and at most 0.05 (72 min as days);
        else None.
    """
    if not (
        20_000.0 <= first <= 80_000.0 and 0.0 < step <= 0.05 and first != math.floor(first)
    ):  # 1954-2119, steps under 72 min
        return None
    return (
        f"time column {header!r} looks like spreadsheet serial dates ({_serial_date(first)}), not minutes: give "
        "`time_unit='d'` (or `time_unit='min'` if it is minutes)"
    )


def read_as_minutes(header: str) -> str:
    """The words that open every hint on a time column read as minutes for want of a unit."""
    return f"time column {header!r} is read as minutes (no unit in its name, a units row or `time_unit`)"


def seconds_hint(header: str, span_min: float) -> str:
    """What a reader says when a time column read as minutes, for want of a stated unit, runs past two
    days (``UNLIKELY_MINUTES``): a warm-up is hours long, so the column is more likely seconds.

    Parameters
    ----------
    header : str
        The time column's name.
    span_min : float
        The last time read (min), which the message gives in minutes and in days.

    Returns
    -------
    str
        The note, suggesting ``time_unit='s'``.
    """
    return (
        f"{read_as_minutes(header)} and runs to {span_min:g} min ({span_min / 1440:.1f} days): if it is in "
        "seconds, give `time_unit='s'`"
    )


def gap_note(time_min: FloatArray) -> str | None:
    """What a reader says of the longest gap between readings against their usual (median) step
    (:func:`gap_said`); None where it is no gap.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        Sample times (min), increasing.

    Returns
    -------
    str or None

    Examples
    --------
    >>> gap_note(np.r_[np.arange(0.0, 60.0, 0.5), np.arange(100.0, 200.0, 0.5)])
    'a gap of 40.5 min in the readings after t = 59.5 min (otherwise a reading every 30 s): the fit bridges it'
    """
    steps = np.diff(np.asarray(time_min, dtype=float))
    if len(steps) < 3:
        return None
    k = int(np.argmax(steps))
    return gap_said(float(steps[k]), float(time_min[k]), float(np.median(steps)))


def gap_said(step_min: float, after_min: float, usual_min: float) -> str | None:
    """What a reader says of a step between readings that is ``GAP_FACTOR`` times the usual one and
    at least ``GAP_MIN_MIN`` minutes (a logger paused, a cable pulled): the fit bridges it, and the
    user should know it did. None for a shorter step.

    Parameters
    ----------
    step_min : float
        The step (min).
    after_min : float
        The time of the reading before it (min).
    usual_min : float
        The usual step between readings (min).

    Returns
    -------
    str or None
    """
    if step_min < max(GAP_FACTOR * usual_min, GAP_MIN_MIN):
        return None
    every = f"{60.0 * usual_min:.3g} s" if usual_min < 1.0 else f"{usual_min:.3g} min"
    return (
        f"a gap of {step_min:.3g} min in the readings after t = {after_min:g} min (otherwise a reading every "
        f"{every}): the fit bridges it"
    )


def sparse_hint(header: str, times_min: FloatArray) -> str | None:
    """What a reader says when a time column read as minutes, for want of a stated unit, has
    readings a usual ``SPARSE_HINT_STEP_MIN`` or more apart: a warm-up logged every half hour is
    rare, one logged every 30 s common, and seconds read as minutes stretch the warm-up sixty-fold,
    so that its first minutes look settled. None otherwise (fewer than three readings too).

    Parameters
    ----------
    header : str
        The time column's name.
    times_min : ndarray
        The times read so far (min).

    Returns
    -------
    str or None
        The note, suggesting ``time_unit='s'``.

    Examples
    --------
    >>> sparse_hint("t", np.array([0.0, 30.0, 60.0])) is not None, sparse_hint("t", np.array([0.0, 1.0, 2.0]))
    (True, None)
    """
    if len(times_min) < 3:
        return None
    step = float(np.median(np.diff(times_min)))
    if step < SPARSE_HINT_STEP_MIN:
        return None
    return (
        f"{read_as_minutes(header)}, a reading every {step:g} min: if it is in seconds, give `time_unit='s'` "
        "(read as minutes, a warm-up in seconds looks "
        "sixty times slower, and settled long before it is)"
    )


def unit_hint(header: str, first_times_min: FloatArray, last_min: float, samples: int) -> str | None:
    """The one thing a log follower says of a numeric time column read as minutes for want of a
    stated unit, or None: its first ``SPARSE_HINT_ROWS`` readings a usual ten minutes or more
    apart (:func:`sparse_hint`), else a span past two days (:func:`seconds_hint`), else a dense
    hour (:func:`hours_hint`). The step comes first: live, it tells at once, where the span tells
    only after two days of readings.

    Parameters
    ----------
    header : str
        The time column's name.
    first_times_min : ndarray
        The first ``SPARSE_HINT_ROWS`` times read (min; fewer while fewer were read).
    last_min : float
        The last time read (min from the first reading): the span.
    samples : int
        How many readings that span holds.

    Returns
    -------
    str or None

    Examples
    --------
    >>> unit_hint("t", np.array([0.0, 20.0, 40.0]), 2900.0, 146).split(", a reading every")[1][:7]
    ' 20 min'
    """
    if (hint := sparse_hint(header, np.asarray(first_times_min, dtype=float)[:SPARSE_HINT_ROWS])) is not None:
        return hint
    if last_min > UNLIKELY_MINUTES:
        return seconds_hint(header, last_min)
    return hours_hint(header, last_min, samples)


def hours_hint(header: str, span_min: float, samples: int, named_minutes: bool = False) -> str | None:
    """What a reader says when a time column read as minutes holds at least ``HOURS_HINT_SAMPLES``
    readings over at most an hour, a second or less apart: a warm-up logged so densely for so short
    a time is more likely a column in hours. None otherwise.

    Parameters
    ----------
    header : str
        The time column's name.
    span_min : float
        The last time read (min).
    samples : int
        How many readings that span holds.
    named_minutes : bool, optional
        The log states minutes (``time_min``, ``Time [min]``): decimal clock hours written under such
        a name are read as minutes as stated, and the hint says the name may be wrong. False: no unit
        is stated, and minutes were assumed.

    Returns
    -------
    str or None
        The note, suggesting ``time_unit='h'``.

    Examples
    --------
    >>> hours_hint("t", 14.0, 1681) is not None, hours_hint("t", 14.0, 15) is None
    (True, True)
    >>> hours_hint("Time", 6.68, 401) is not None  # a minute written in hours as 0.0167
    True
    """
    # a minute written in hours to four places (0.0167) is a step of 1.002 s: a second, as written
    if samples < HOURS_HINT_SAMPLES or span_min > 60.0 or span_min / (samples - 1) > 1.05 / 60.0:
        return None
    opening = (
        f"time column {header!r} is read as minutes, as its name or units row states,"
        if named_minutes
        else read_as_minutes(header)
    )
    return (
        f"{opening} and runs only to {span_min:g} min with a reading every "
        f"{60.0 * span_min / (samples - 1):.2g} s: if it is in hours, give "
        "`time_unit='h'`"
    )
