"""The thermal commands' log: the file, the sensors and columns asked for, the room sensor, the
reference file, the options that name them, and reading the log with what was asked."""

from __future__ import annotations

import shlex
from collections.abc import Mapping
from dataclasses import dataclass, fields, replace
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeVar

import click
import numpy as np

from mtident.cli import (
    F,
    stderr,
)
from mtident.exceptions import InputError
from mtident.io.columns import column_named, room_named, unread_rooms
from mtident.io.logs import SAMPLES, TemperatureLog, read_temperature_log, sample_log_path
from mtident.io.time_notes import TIME_UNITS
from mtident.io.units import TEMPERATURE_UNIT_OPTIONS

if TYPE_CHECKING:
    from mtident.thermal.reference import MachineReference


def log_path(file: str) -> Path:
    """FILE as given, or the shipped log it names (@sample, @sample-room).

    Parameters
    ----------
    file : str
        The FILE argument: a path, or a shipped log's @-name.

    Returns
    -------
    Path
    """
    return sample_log_path(file) if file in SAMPLES else Path(file)


def asked_sensors(sensors: tuple[str, ...], path: Path, sheet: str | None = None) -> list[str]:
    """The --sensor names, repeated or comma-separated, each once; empty for all ("all" or none given).

    An entry that is a column of the log as it stands is one name, commas and
    all ("Temp, Spindel", as some loggers name their channels).

    Parameters
    ----------
    sensors : tuple of str
        The --sensor values as given.
    path : Path
        The log: a --sensor value that names one of its columns is one name, commas and all.
    sheet : str or None, optional
        --sheet: the sheet of a workbook whose columns those are.

    Returns
    -------
    list of str
        The names in the order given.
    """
    from mtident.io.log_file import header_names

    header = header_names(path, sheet) if sensors and path.is_file() else []
    columns = set(header)
    names = (name.strip() for entry in sensors for name in ([entry] if entry.strip() in columns else entry.split(",")))
    return list(dict.fromkeys(column_named(name, header) for name in names if name and name != "all"))


def named_column(name: str | None, file: str, sheet: str | None, option: str) -> str | None:
    """The column of FILE that a --ambient or --wait-for name means (:func:`~mtident.io.columns.column_named`:
    "Room" for ``Room [°C]``), said on stderr where it is not the name as given; the name itself where
    FILE is no file yet (a live log still to come, a network source).

    Parameters
    ----------
    name : str or None
        The name given; None: the option was not given.
    file : str
        FILE as given.
    sheet : str or None
        --sheet.
    option : str
        The option, for the note ("--ambient").

    Returns
    -------
    str or None
    """
    from mtident.io.log_file import header_names

    path = log_path(file)
    if name is None or not path.is_file():
        return name
    try:
        column = column_named(name, header_names(path, sheet))
    except InputError:  # the reader says what is wrong with the log
        return name
    if column != name:
        stderr.print(f"mtident: note: {option} {name!r} is the column {column!r}", highlight=False)
    return column


@dataclass(frozen=True, slots=True)
class LogRequest:
    """FILE and how its columns are read (:func:`log_options`).

    Attributes
    ----------
    file : str
        FILE as given: a log, a shipped log's @-name, an MTConnect agent's URL or an OPC UA server's.
    sensors : tuple of str
        --sensor (empty: all).
    time_col, time_unit, temperature_unit : str or None
        --time-col, --time-unit and --unit.
    sheet : str or None
        --sheet: an Excel workbook's sheet, by name or number from 1 (None: its first with a table).
    """

    file: str
    sensors: tuple[str, ...]
    time_col: str | None
    time_unit: str | None
    temperature_unit: str | None
    sheet: str | None = None


def log_request(options: Mapping[str, Any]) -> LogRequest:
    """The options of :func:`log_options`, read from a command's (a mapping by click's names), as one
    :class:`LogRequest`."""
    return LogRequest(
        options["file"],
        options["sensors"],
        options["time_col"],
        options["time_unit"],
        options["temperature_unit"],
        options["sheet"],
    )


@dataclass(frozen=True, slots=True)
class CommandRequest:
    """What a command that reads a log with a room column was asked: the fields its request shares.

    Attributes
    ----------
    log : LogRequest
        FILE and how its columns are read.
    room_col : str or None
        --ambient: the room sensor's column.
    """

    log: LogRequest
    room_col: str | None


RequestT = TypeVar("RequestT", bound=CommandRequest)


def command_request(request_type: type[RequestT], options: Mapping[str, Any], **settings: Any) -> RequestT:
    """A command's options, by click's names, grouped into its request: ``log`` and ``room_col``
    from :func:`log_request` and --ambient, the fields ``settings`` gives, every other field from
    the option of its name.

    Parameters
    ----------
    request_type : type
        The command's request, a :class:`CommandRequest`.
    options : mapping
        The command's options (their help is the command's ``--help``).
    **settings
        The fields not one option of the same name: settings grouped or read from options.

    Returns
    -------
    RequestT
    """
    room = named_column(options["ambient_col"], options["file"], options["sheet"], "--ambient")
    given = {"log": log_request(options), "room_col": room, **settings}
    return request_type(
        **{
            field.name: given[field.name] if field.name in given else options[field.name]
            for field in fields(request_type)
        }
    )


def load_log(request: LogRequest) -> TemperatureLog:
    """The log FILE names, read as the options say; its notes said on stderr.

    Parameters
    ----------
    request : LogRequest
        FILE, --sensor (empty: all), --time-col, --time-unit, --unit and --sheet.

    Returns
    -------
    TemperatureLog
        As :func:`~mtident.io.logs.read_temperature_log` reads it.

    Raises
    ------
    InputError
        A log that cannot be read as asked.
    """
    path = log_path(request.file)
    log = read_temperature_log(
        path,
        time_col=request.time_col,
        time_unit=request.time_unit,
        sensors=asked_sensors(request.sensors, path, request.sheet) or None,
        temperature_unit=request.temperature_unit,
        sheet=request.sheet,
    )
    for note in log.notes:
        stderr.print(f"mtident: note: {note}", highlight=False)
    return log


def load_log_with_room(
    request: LogRequest, room_col: str | None, say_rooms: bool = True
) -> tuple[TemperatureLog, np.ndarray | None]:
    """The log's sensors, and the room column split off from them when one is named; without one,
    a note on columns named as a room sensor (``say_rooms``: where the command does not say it).

    Parameters
    ----------
    request : LogRequest
        FILE and how its columns are read; the room's column is read in the unit --unit says too.
    room_col : str or None
        The --ambient option: the room sensor's column; None without one.
    say_rooms : bool, optional
        Say columns named as a room sensor, read as sensors, where none is given (a room column that
        --sensor left unread is said regardless).

    Returns
    -------
    log : TemperatureLog
        The sensors, without the room column.
    room : ndarray, shape (N,) or None
        The room column's readings (°C).

    Raises
    ------
    InputError
        A log that cannot be read as asked, or no sensor column besides the room column.
    """
    if room_col is None:
        log = load_log(request)
        # a room column --sensor left unread is said here whatever the command says of the sensors
        named = any(name.strip() not in ("", "all") for entry in request.sensors for name in entry.split(","))
        unread = unread_rooms_of(log_path(request.file), log.sensors, request.sheet) if named else []
        say_room_candidates(log.sensors if say_rooms else (), "identified as a machine sensor", unread=unread)
        return log, None
    asked = asked_sensors(request.sensors, log_path(request.file), request.sheet)
    # only the asked-for columns and the room are read: a dead column elsewhere does not matter
    every = load_log(replace(request, sensors=tuple(dict.fromkeys([*asked, room_col])) if asked else ()))
    log, room = every.split_room(room_col)
    return log.select([name for name in asked if name != room_col] or None), room


def unread_rooms_of(path: Path, read: tuple[str, ...] | list[str], sheet: str | None = None) -> list[str]:
    """The columns of the log at ``path`` named as a room sensor and not among ``read``, the sensors
    --sensor named (:func:`~mtident.io.columns.unread_rooms`); none where its header cannot be read.

    Parameters
    ----------
    path : Path
        The log (a workbook's sheet by ``sheet``).
    read : tuple of str or list of str
        The sensor columns read.
    sheet : str or None, optional
        --sheet.

    Returns
    -------
    list of str
    """
    from mtident.io.log_file import header_names

    if not path.is_file():
        return []
    try:
        header = header_names(path, sheet)
    except InputError:  # the reader has said what is wrong with the log
        return []
    return unread_rooms(header, read)


def say_room_candidates(
    sensors: tuple[str, ...] | list[str], taken_as: str, commands: str = "", unread: list[str] | None = None
) -> None:
    """A note on columns named as a room sensor when no --ambient was given: the room is then an
    assumption (steady, or wandering by --room-wander), and a drifting one biases T∞. ``commands``
    names the commands that take --ambient where the caller is not one of them; ``unread`` are such
    columns that --sensor left unread (:func:`unread_rooms_of`)."""
    rooms = [name for name in sensors if room_named(name)]
    if rooms and len(rooms) < len(sensors):
        _say_rooms(rooms, taken_as, commands)
    if unread:
        _say_rooms(unread, "not read (--sensor names the sensors read)", commands)


def _say_rooms(rooms: list[str], taken_as: str, commands: str) -> None:
    stderr.print(
        f"mtident: note: {', '.join(repr(r) for r in rooms)} {'is' if len(rooms) == 1 else 'are'} named as a room "
        f"sensor and {taken_as}; "
        f"if it measures the room, --ambient {shlex.quote(rooms[0])}{commands} makes it the input of each "
        "sensor's heat balance (a drifting room then stays out of T∞)",
        highlight=False,
    )


def log_options(func: F) -> F:
    """Add a log's argument and options to a command: FILE, --sensor, --time-col, --time-unit, --unit and --sheet.

    Parameters
    ----------
    func : callable
        The command's callback.

    Returns
    -------
    callable
        ``func`` with the argument and the options.
    """
    func = click.option(
        "--sheet",
        metavar="NAME|N",
        help=(
            "Excel workbook: the sheet to read, by name or number (from 1). Default: the first sheet that holds a "
            "table; a workbook with other sheets gets a note naming the sheet read and the others."
        ),
    )(func)
    func = click.option(
        "--unit",
        "temperature_unit",
        type=click.Choice(list(TEMPERATURE_UNIT_OPTIONS), case_sensitive=False),
        metavar=f"[{'|'.join(TEMPERATURE_UNIT_OPTIONS)}]",
        help=(
            "Unit of the temperature columns that state none (no units row, no unit in the name): C, F or K, "
            "converted to °C (default: °C). A column whose own unit differs is refused."
        ),
    )(func)
    func = click.option(
        "--time-unit",
        type=click.Choice(list(TIME_UNITS)),
        help=(
            "Unit of a numeric time column (default: from its name, Time_s or Time [s], or a units row; else min). d: "
            "days, as spreadsheet serial dates (46348.33 = 22.11.2026 08:00)."
        ),
    )(func)
    func = click.option("--time-col", metavar="NAME", help="Time column (default: the first column).")(func)
    func = click.option(
        "--sensor",
        "sensors",
        multiple=True,
        metavar="NAME",
        help="Sensor column(s) to use; repeat or comma-separate (default: all).",
    )(func)
    func = click.argument("file", metavar="FILE")(func)
    return func


def load_reference_file(reference_path: str | None, machine: str | None = None) -> MachineReference | None:
    """The reference run named by --reference, read (None where none is given).

    Parameters
    ----------
    reference_path : str or None
        The --reference option: a file, or a shipped reference's @-name.
    machine : str or None
        The --machine option: the machine the test says it is of.

    Returns
    -------
    MachineReference or None

    Raises
    ------
    InputError
        No such file, a file that is no reference, or a reference of another machine than --machine.
    """
    if reference_path is None:
        return None
    from mtident.thermal.reference import load_reference

    if reference_path in SAMPLES:
        return load_reference(sample_log_path(reference_path)).for_machine(machine)
    if not Path(reference_path).is_file():
        msg = (
            f"--reference {reference_path}: no such file (learn one with `mtident thermal learn FULL_LOG -o "
            f"{Path(reference_path).name}`)"
        )
        raise InputError(msg)
    return load_reference(reference_path).for_machine(machine)


def named_columns(options: Mapping[str, Any], key: str, option: str) -> tuple[str, ...]:
    """The log's columns that a repeated option (--wait-for, --heat-enters-at) names, each as
    :func:`named_column` reads it (a name without its unit matches); ``key``: its click name."""
    return tuple(str(named_column(name, options["file"], options["sheet"], option)) for name in options[key])
