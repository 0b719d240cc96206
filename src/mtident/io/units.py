"""What a log's cells and names say about units: of time, of temperature, of other quantities.

A unit is stated in a units row under the header (``min;°C;°C``), at the end of
a column's name (``Time [s]``, ``T1 (°F)``, ``T/°C``, HOBOware's ``Temp, °F (LGR
S/N: ...)``), or in the readings' own cells (``13.1 °C``). Time units set the
time column's scale, temperature units the conversion to °C
(:func:`celsius_conversion`), and any other unit (%, rpm, V, lx) marks a channel
that is no temperature.
"""

from __future__ import annotations

import re

from mtident.exceptions import InputError

__all__ = [
    "TEMPERATURE_UNIT_OPTIONS",
    "stated_temperature_unit",
    "unit_key",
    "unit_in_name",
    "time_unit_name",
    "is_time_or_temperature_unit",
    "celsius_conversion",
    "carried_unit",
    "name_without_unit",
    "number_without_unit",
    "is_number",
    "is_humidity",
    "is_from_humidity",
]

# A units row's cells, brackets, spaces and degree signs taken away (º, and Â from a UTF-8 ° read
# as cp1252, too), lower case. The time units name the keys of logs.TIME_UNITS; a temperature unit
# gives (scale, offset) to °C.
_TIME_UNIT_NAMES = {
    "ms": "ms",
    "msec": "ms",
    "milliseconds": "ms",
    "s": "s",
    "sec": "s",
    "secs": "s",
    "second": "s",
    "seconds": "s",
    "min": "min",
    "mins": "min",
    "minute": "min",
    "minutes": "min",
    "h": "h",
    "hr": "h",
    "hrs": "h",
    "hour": "h",
    "hours": "h",
    "d": "d",
    "day": "d",
    "days": "d",
}
_TEMPERATURE_UNITS = {
    # "ﾟC": Japanese loggers (Graphtec) write the half-width ﾟ of Shift-JIS for the degree sign
    **dict.fromkeys(("c", "degc", "celsius", "gradc", "degreesc", "degreec", "ﾟc"), (1.0, 0.0)),
    **dict.fromkeys(("k", "kelvin"), (1.0, -273.15)),
    **dict.fromkeys(("f", "degf", "fahrenheit", "degreesf", "degreef"), (5.0 / 9.0, -160.0 / 9.0)),
}
# The units a user may state for a log's temperature columns without a unit of their own
# (``temperature_unit``, the command line's --unit), and how the notes and messages write them
TEMPERATURE_UNIT_OPTIONS = {"C": "°C", "F": "°F", "K": "K"}
_UNIT_WRITTEN = {(1.0, 0.0): "°C", (1.0, -273.15): "K", (5.0 / 9.0, -160.0 / 9.0): "°F"}
# Units of a logger's other channels, named at the end of a column's name ("Speed (rpm)", "RH/%"):
# such a column is no temperature. (A units row may name any unit; a name must name a known one.)
# Not the letters a machine's sensors are labelled with: "Bearing (A)", "(N)" for north, and "(RH)"
# for the right-hand side would have left a temperature out.
_OTHER_UNITS = frozenset(
    (
        "%",
        "%rh",
        "%rf",
        "v",
        "mv",
        "µv",
        "uv",
        "ma",
        "rpm",
        "1/min",
        "u/min",
        "hz",
        "khz",
        "bar",
        "mbar",
        "pa",
        "kpa",
        "hpa",
        "mpa",
        "psi",
        "kw",
        "lx",
        "lux",
        "lxh",
        "mm",
        "µm",
        "um",
        "nm",
        "kn",
        "ppm",
        "m/s2",
        "m/s^2",
        "mm/s",
        "l/min",
        "ohm",
        "Ω",
        "kΩ",
        "mw/cm2",
        "w/cm2h",
        "mg/l",
        "µs/cm",
        "us/cm",
        "ms/cm",
        "lum/ft²",
        "lum/ft2",
        "m/s",
        "mph",
        "kwh",
        "wh",
        "va",
    )
)
# A column named as a humidity ("Humidity", "RH", "Feuchte", "湿度"; the name alone, without a unit)
_HUMIDITY_WORDS = ("humidity", "feuchte", "湿度")
# Temperatures a logger computes from the air's humidity: in °C, but no temperature of the machine
# (Tinytag's and EasyLog's dew point channel beside their temperature and humidity).
_FROM_HUMIDITY_WORDS = (
    "dewpoint",
    "dewpt",
    "taupunkt",
    "pointderosée",
    "pointderosee",
    "puntoderocío",
    "puntoderocio",
    "露点",
    "wetbulb",
    "feuchtkugel",
    "heatindex",
    "hitzeindex",
)
# A unit at the end of a column's name (a unit this module knows): "Time [s]", "T1 (°C)", "Temp (°C)
# #9724974" (a serial number after it), "T/°C", and after a comma before the logger's details,
# "Temp, °F (LGR S/N: 10679014, SEN S/N: 10679014)" (HOBOware).
_UNITS_IN_NAME = (
    re.compile(r"[\[(]\s*([^\[\]()]+?)\s*[\])]\s*(?:#\s*\d+)?\s*$"),
    re.compile(r"\S/\s*([^/\[\]()]+?)\s*$"),
    re.compile(r",\s*([^,\[\]()]+?)\s*(?:\([^()]*\))?\s*$"),
    # a degree-marked unit after a space or an underscore, without brackets: "T1 °F", "T1 in °F",
    # "Temp degF", "T1_degC" (read as °C before: a °F log was 1.8 times too warm, silently)
    re.compile(r"[\s_]((?:°|º|deg\s*)[CFK])\s*$", re.IGNORECASE),
)
# a reading with its unit after it: "13.1 °C", "56.3 %RH" (Tinytag Explorer writes them so)
_NUMBER_THEN_UNIT = re.compile(r"^\s*([+-]?(?:\d+(?:[.,]\d*)?|[.,]\d+)(?:[eE][+-]?\d+)?)\s*(\S.*?)\s*$")


def carried_unit(cell: str) -> str | None:
    """The unit a reading carries after its number ("13.1 °C": "°C"), if it is one this module knows.

    Parameters
    ----------
    cell : str
        A cell as written in the log.

    Returns
    -------
    str or None
        The unit after the number, as written, where it is a temperature unit or another unit this module
        knows (%RH, V, rpm, ...); None for a plain number, text, or an unknown unit.
    """
    match = _NUMBER_THEN_UNIT.match(cell)
    return match.group(2) if match and unit_key(match.group(2)) in (*_TEMPERATURE_UNITS, *_OTHER_UNITS) else None


def number_without_unit(cell: str) -> str:
    """A reading's number with a known unit after it taken off ("13.1 °C": "13.1"); other cells as they are.

    ``cell`` is a cell as written in the log (as for :func:`carried_unit`).

    Returns
    -------
    str
        The number's text (a decimal comma kept), or ``cell`` unchanged.
    """
    match = _NUMBER_THEN_UNIT.match(cell)
    return match.group(1) if match and carried_unit(cell) else cell


def unit_key(cell: str) -> str:
    """A unit or name as compared here: brackets, spaces, points and degree signs taken away, lower case.

    Parameters
    ----------
    cell : str
        A unit or a column name as written ("[°C]", "Time (s)", "T_amb").

    Returns
    -------
    str
        ``cell`` without whitespace, brackets, parentheses, points, underscores, degree signs (° and º)
        and "Â" (a UTF-8 ° read as cp1252), in lower case ("[°C]": "c").
    """
    return re.sub(r"[\s\[\]()°º.Â_]", "", cell).lower()


def is_number(cell: str) -> bool:
    """Whether a cell is a number (a decimal comma counts).

    ``cell`` is a cell as written in the log (as for :func:`carried_unit`).

    Returns
    -------
    bool
        True where ``float`` reads it with a decimal comma taken as a point ("nan" and "inf" count too).
    """
    try:
        float(cell.replace(",", "."))
    except ValueError:
        return False
    return True


def celsius_conversion(unit: str) -> tuple[float, float] | None:
    """(scale, offset) taking a reading in ``unit`` to °C (°C = scale·reading + offset): (1, 0) for
    °C and for no unit, (1, −273.15) for K, (5/9, −160/9) for °F; None for a unit that is no
    temperature (V, %, rpm).

    Parameters
    ----------
    unit : str
        The unit as written ("°F", "[K]", "degC", "" for none).

    Returns
    -------
    tuple of float or None
        (scale, offset), or None.
    """
    if not unit.strip():
        return 1.0, 0.0
    return _TEMPERATURE_UNITS.get(unit_key(unit))


def stated_temperature_unit(unit: str | None) -> str | None:
    """The temperature unit a user states for a log's columns without a unit of their own, as the
    notes write it ("F": "°F"); None where none is stated.

    Parameters
    ----------
    unit : str or None
        "C", "F" or "K" (a unit as a log writes it, "°F" or "Kelvin", is taken too); None: the log's own
        units, °C where it states none.

    Returns
    -------
    str or None
        "°C", "°F" or "K"; None for None.

    Raises
    ------
    InputError
        ``unit`` is no unit of temperature.
    """
    if unit is None:
        return None
    conversion = _TEMPERATURE_UNITS.get(unit_key(unit)) if unit.strip() else None
    if conversion is None:
        msg = f"temperature unit {unit!r} is not one of: {', '.join(TEMPERATURE_UNIT_OPTIONS)}"
        raise InputError(msg)
    return _UNIT_WRITTEN[conversion]


def is_humidity(name: str) -> bool:
    """Whether a column's name (or a description row's cell) names a humidity, not a temperature.

    Parameters
    ----------
    name : str
        The column name or cell as written.

    Returns
    -------
    bool
        True for "%RH", "RH%" or a name containing "humidity", "Feuchte" or "湿度" ("RH" alone is not one:
        it may be a right-hand sensor).
    """
    key = unit_key(name)
    return key in ("%rh", "rh%") or any(word in key for word in _HUMIDITY_WORDS)  # not "RH": a right-hand sensor


def is_from_humidity(name: str) -> bool:
    """Whether a column's name (or a description row's cell) names a temperature computed from the
    air's humidity (a dew point, a wet-bulb temperature, a heat index), not one of the machine.

    ``name`` is the column name or cell as written (as for :func:`is_humidity`).

    Returns
    -------
    bool
        True where the name, without spaces, hyphens, brackets, points and underscores and in lower case,
        contains "dewpoint", "Taupunkt", "point de rosée", "露点", "wet bulb", "heat index" or the like.
    """
    key = re.sub(r"[-\s\[\]()°º._]", "", name).lower()
    return any(word in key for word in _FROM_HUMIDITY_WORDS)


# Words that name a logger's other channels without a unit in brackets ("P_kW", "Drehzahl",
# "Spindle speed"): such a column is no temperature, unless its name also says it is one
# ("Speed-side bearing temp"). Whole words only: "load" and "current" name bearings and readings too.
_OTHER_QUANTITY_WORDS = frozenset(
    (
        "drehzahl",
        "leistung",
        "power",
        "speed",
        "rpm",
        "torque",
        "drehmoment",
        "strom",
        "voltage",
        "spannung",
        "pressure",
        "druck",
        "vorschub",
        "feedrate",
        "kw",
    )
)
_TEMPERATURE_WORDS = ("temp", "thermo", "pt100", "pt1000", "°c", "degc", "celsius")


def names_other_quantity(name: str) -> bool:
    """Whether a column's name says it is a logger's other channel, not a temperature: a word such as
    "Drehzahl", "power", "speed" or "kW" in it ("P_kW", "Spindle speed"), and no word that says it is a
    temperature ("temp", "Pt100", "°C").

    Parameters
    ----------
    name : str
        The column name as written.

    Returns
    -------
    bool
    """
    lower = name.lower()
    words = set(re.split(r"[^a-zäöüß0-9]+", lower))
    return bool(words & _OTHER_QUANTITY_WORDS) and not any(word in lower for word in _TEMPERATURE_WORDS)


def unit_in_name(column: str) -> str:
    """The unit at the end of a column's name, as written ("Time [s]": "s"), if it is one this
    module knows; "" without one ("T (spindle)" names a place, not a unit; "Date/Time" no unit either).

    Parameters
    ----------
    column : str
        The column name as written.

    Returns
    -------
    str
        The unit (a time or temperature unit, or another known one such as "%" or "rpm") in brackets at
        the end of the name, after a slash, after a comma, or degree-marked after a space or underscore
        ("T1 °F"); "" where there is none.
    """
    for pattern in _UNITS_IN_NAME:
        named = pattern.search(column)
        if named is not None and unit_key(named.group(1)) in (*_TIME_UNIT_NAMES, *_TEMPERATURE_UNITS, *_OTHER_UNITS):
            return named.group(1)
    return ""


def name_without_unit(column: str) -> str:
    """A column's name less the unit at its end (:func:`unit_in_name`): "T5 [°F]", "T5/°F" and
    "T5 °F" all name sensor "T5"; a name without a unit is returned as it is.

    Parameters
    ----------
    column : str

    Returns
    -------
    str
    """
    for pattern in _UNITS_IN_NAME:
        named = pattern.search(column)
        if named is not None and unit_key(named.group(1)) in (*_TIME_UNIT_NAMES, *_TEMPERATURE_UNITS, *_OTHER_UNITS):
            return column[: named.start(1)].rstrip(" \t[(/,_") or column
    return column


def time_unit_name(unit: str) -> str | None:
    """ "ms", "s", "min", "h" or "d" for a unit of time as written ("[sec]", "Minutes"), else None.

    Parameters
    ----------
    unit : str
        A unit as written, brackets and case as they come.

    Returns
    -------
    str or None
        The key of the unit in ``logs.TIME_UNITS``, or None where it is no unit of time.
    """
    return _TIME_UNIT_NAMES.get(unit_key(unit))


def is_time_or_temperature_unit(cell: str) -> bool:
    """Whether a cell names a unit of time or of temperature (a units row has one at least).

    Parameters
    ----------
    cell : str
        A cell as written, of a row that may be a units row.

    Returns
    -------
    bool
        True where the cell is a unit of time ("s", "min", "[h]", ...) or of temperature ("°C", "K", "°F", ...).
    """
    return unit_key(cell) in _TIME_UNIT_NAMES or unit_key(cell) in _TEMPERATURE_UNITS
