"""``mtident thermal ...``: identify a warm-up, find the minimal identification time."""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import click
import numpy as np
from rich.table import Table

from mtident.cli import (
    FiniteFloatRange,
    OptionConsole,
    OutputPath,
    as_options,
    cell_text,
    column_layout,
    number_option,
    plain,
    print_json,
    prose_console,
    stderr,
    table_console,
    thermal,
    user_errors,
)
from mtident.cli_logs import (
    CommandRequest,
    LogRequest,
    asked_sensors,
    command_request,
    load_log_with_room,
    load_reference_file,
    log_options,
    log_path,
    named_columns,
    say_room_candidates,
    unread_rooms_of,
)
from mtident.cli_options import (
    ambient_option,
    free_fast_option,
    heat_enters_option,
    json_option,
    machine_option,
    max_time_constant_option,
    plot_option,
    preset_option,
    reference_option,
)
from mtident.exceptions import InputError
from mtident.io.logs import TemperatureLog
from mtident.thermal import DEFAULT_METHOD, METHODS, identify, minimal_identification_time
from mtident.thermal.assumptions import MACHINE_MARK
from mtident.thermal.identification import SensorAnswer
from mtident.thermal.measured import SETTLED_MOVE_C
from mtident.thermal.min_time import MinTimeAnswer, MinTimeResult
from mtident.thermal.modes import DEFAULT_MAX_TIME_CONSTANT_MIN
from mtident.thermal.robust_types import RobustSettings
from mtident.thermal.settings import IDENTIFY_METHODS, ROBUST_METHOD

if TYPE_CHECKING:
    from mtident.io.describe import LogDescription
    from mtident.thermal.reference import MachineReference


def _not_settled_note(slowest_min: float) -> str:
    """The table's "*": by which rule a sensor had not settled by the log's end, with an example of
    the second (a newcomer read a last quarter that moved 0.05 °C as against the first alone)."""
    half = SETTLED_MOVE_C / 2.0
    left = half / math.expm1(90.0 / slowest_min)
    return (
        f"* not settled by the log's end: its last quarter moved {SETTLED_MOVE_C:g} °C or more, or enough that a "
        f"mode as slow as {slowest_min:g} min would still bring more than {half:g} °C (at that pace a move of {half:g} "
        f"°C in 90 min leaves {left:.2f} °C to come). Its last level and 95 %-rise time may be short of where it "
        "settles."
    )


@thermal.command("identify")
@log_options
@click.option(
    "--window",
    "window_min",
    type=FiniteFloatRange(min=0, min_open=True),
    default=30.0,
    show_default=True,
    help="Identification time L in minutes from the first sample.",
)
@click.option(
    "--method",
    type=click.Choice(IDENTIFY_METHODS),
    default=DEFAULT_METHOD,
    show_default=True,
    help="robust: sums of up to four exponential modes (six where the readings use all four), with an interval "
    "over every model the data cannot exclude. "
    "The papers' first-order filters (their interval assumes a first-order machine): ukf, aukf (Xia 2014), fukf, "
    "afukf (Yu 2019), or lsq (least squares).",
)
@preset_option
@max_time_constant_option
@heat_enters_option
@reference_option
@machine_option
@free_fast_option
@number_option(
    "--room-wander",
    "room_wander",
    default=0.05,
    help="robust, without --ambient: how far the unmeasured room may wander in an hour (°C, 1σ of a random walk).",
    min=0.0,
)
@click.option(
    "--horizon", "horizon_min", type=FiniteFloatRange(min=0, min_open=True), help="Predict to this time (min)."
)
@click.option(
    "--pseudo-seed",
    type=int,
    help=(
        "First-order filters: predict with the noisy pseudo-measurements of Xia et al. (2014), Eqs 21-22, from this "
        "seed."
    ),
)
@ambient_option(
    "Room-temperature column: the room becomes an input of each sensor's heat balance; T∞ at the room's level at "
    "the window's end."
)
@plot_option("Draw measured and predicted curves to this picture (PNG; .svg or .pdf by the suffix).")
@click.option(
    "--curve",
    "curve_path",
    type=OutputPath(),
    help=(
        "Write the measured and predicted curves with their 95 % band to this CSV (a row per time; for a report or a "
        "spreadsheet)."
    ),
)
@json_option()
@user_errors
def identify_command(**options: Any) -> None:
    """Identify the temperature rise from the first WINDOW minutes of FILE and predict the rest.

    FILE is a CSV log (time column, one column per sensor), or @sample for the
    10-sensor warm-up shipped with mtident (@sample-room: the same with a room
    sensor column "room", for --ambient room).

    The table's RMSE is the predicted curve's against every reading of the
    log (Xia et al. 2014, Eq. 33): where the log runs past the window, it
    measures the prediction.

    \f

    Parameters
    ----------
    **options
        The options by click's names, each with its help above (:func:`identify_request`).

    Raises
    ------
    InputError
        Options that do not go together, or a log that cannot be read (said as a one-line error).
    """
    run_identify(identify_request(options))


@dataclass(frozen=True, slots=True)
class IdentifyRequest(CommandRequest):
    """What ``thermal identify`` was asked, grouped (:func:`identify_request`).

    Attributes
    ----------
    log, room_col
        As in :class:`CommandRequest`.
    window_min : float
        --window: the identification time L (min).
    method, preset : str
        --method and --preset (first-order filters only).
    robust : RobustSettings
        --max-time-constant, --room-wander and --free-fast-modes.
    reference_path : str or None
        --reference.
    machine : str or None
        --machine: the machine the test is of.
    horizon_min : float or None
        --horizon (min).
    pseudo_seed : int or None
        --pseudo-seed (first-order filters only).
    plot_path, curve_path : str or None
        --plot and --curve: the picture and the CSV to write.
    as_json : bool
        --json.
    """

    window_min: float
    method: str
    preset: str
    robust: RobustSettings
    reference_path: str | None
    machine: str | None
    horizon_min: float | None
    pseudo_seed: int | None
    plot_path: str | None
    curve_path: str | None
    as_json: bool


def identify_request(options: Mapping[str, Any]) -> IdentifyRequest:
    """The options of ``thermal identify`` (a mapping by click's names, their help the command's ``--help``),
    grouped into settings: an :class:`IdentifyRequest`.
    """
    return command_request(
        IdentifyRequest,
        options,
        robust=RobustSettings(
            max_time_constant_min=options["max_tau_min"],
            room_wander_C_per_h=options["room_wander"],
            free_fast_modes=options["free_fast_modes"],
            heat_enters_at=named_columns(options, "heat_enters_at", "--heat-enters-at"),
        ),
    )


@dataclass(frozen=True, slots=True)
class IdentifiedSensors:
    """The JSON answer of ``thermal identify`` for more than one sensor.

    Attributes
    ----------
    sensors : tuple of SensorAnswer
    method : str
    window_min : float
        The identification time L used.
    log : str
        The log read (and the sheet of a workbook of several).
    """

    sensors: tuple[SensorAnswer, ...]
    method: str
    window_min: float
    log: str


def run_identify(request: IdentifyRequest) -> None:
    """Identify the log an :class:`IdentifyRequest` names, write its picture and curves, and print
    its answer as a table or JSON.

    Parameters
    ----------
    request : IdentifyRequest

    Raises
    ------
    InputError
        As :func:`identify_command`.
    """
    log, room = load_log_with_room(request.log, request.room_col)
    reference = load_reference_file(request.reference_path, request.machine)
    asked = list(log.sensors)
    log, room = _with_machine_sensors(request, log, room, reference)
    with stderr.status(f"fitting {len(asked)} sensor(s)…"):
        result = identify(
            log,
            request.window_min,
            request.method,
            request.preset,
            request.horizon_min,
            request.pseudo_seed,
            room,
            settings=request.robust,
            reference=reference,
            room_sensor=request.room_col,
            sensors=asked,
        )
    if request.method != ROBUST_METHOD:
        stderr.print(
            "mtident: note: the papers' first-order model: the interval assumes a first-order machine (a slower mode "
            "not yet seen moves T∞ beyond it); --method robust covers up to four modes",
            highlight=False,
        )
    if request.window_min > result.window_min and result.n_window == len(log.time_min):
        stderr.print(
            f"mtident: note: the log ends at t = {result.window_min:g} min, before --window {request.window_min:g}: "
            "identified from all of it",
            highlight=False,
        )
    for note in result.notes[len(log.notes) :]:
        stderr.print(f"mtident: warning: {note}", highlight=False)
    if request.plot_path:
        from mtident.report import plot_identification

        plot_identification(result, request.plot_path)
        stderr.print(f"mtident: plot written to {request.plot_path}", highlight=False)
    if request.curve_path:
        result.curve_frame().to_csv(request.curve_path, index=False, float_format="%.6f")
        stderr.print(
            f"mtident: curves written to {request.curve_path} ({len(result.time_min)} rows to t = "
            f"{result.time_min[-1]:g} min)",
            highlight=False,
        )
    answers = tuple(replace(result.answer(i), log=log.source) for i in range(len(result.sensors)))
    if request.as_json:
        several = IdentifiedSensors(answers, request.method, result.window_min, log.source)
        print_json(answers[0] if len(answers) == 1 else several)
        return
    _identify_table(log.source, request, result.window_min, answers)


def _with_machine_sensors(
    request: IdentifyRequest,
    log: TemperatureLog,
    room: np.ndarray | None,
    reference: MachineReference | None,
) -> tuple[TemperatureLog, np.ndarray | None]:
    """The log with the reference's machine-model sensors that --sensor left out, where the log has
    them: they pin the shared modes of the sensors asked for (one sensor alone has none to share
    them with, and its answer would not be the one it gets beside them). The log as read where
    there are none, or where they cannot be read (said)."""
    model = None if reference is None else reference.machine_model
    if model is None or request.method != ROBUST_METHOD:
        return log, room
    header = _header_or_none(request.log)
    companions = [name for name in model.sensors if name not in log.sensors and name in header]
    if not companions:
        return log, room
    wider = replace(request.log, sensors=(*log.sensors, *companions))
    try:
        fuller, fuller_room = load_log_with_room(wider, request.room_col, say_rooms=False)
    except InputError as error:
        stderr.print(
            f"mtident: note: the machine model's other sensors ({', '.join(companions)}) could not be read, so it "
            f"pins the sensors asked for on their readings alone: {error}",
            highlight=False,
        )
        return log, room
    stderr.print(
        f"mtident: note: the machine model also fits {', '.join(companions)} (not asked for, not reported): they pin "
        "the shared modes",
        highlight=False,
    )
    return fuller, fuller_room


def _header_or_none(request: LogRequest) -> list[str]:
    """The log file's column names; none for a source that is no file (a server) or cannot be read."""
    from mtident.io.log_file import header_names

    path = log_path(request.file)
    if not path.is_file():
        return []
    try:
        return header_names(path, request.sheet)
    except InputError:
        return []


def _identify_table(
    source: str, request: IdentifyRequest, window_min: float, answers: tuple[SensorAnswer, ...]
) -> None:
    robust = request.method == ROBUST_METHOD
    how = "model-robust: up to four modes" if robust else f"{request.method}, preset {request.preset}: first order"
    table = Table(title=f"{source}: identified from the first {window_min:g} min ({how})")
    for column in ("sensor", "T∞ (°C)", "95 % interval", "t_eq (min)", "RMSE (°C)", "trusted", "measured T / t_eq"):
        table.add_column(column, justify="right" if column != "sensor" else "left", **column_layout(column))
    for a in answers:
        lo, hi = a.steady_state_ci95_C
        measured = (
            "—"
            if not math.isfinite(a.measured_final_C)
            else f"{a.measured_final_C:.2f} / {cell_text(a.measured_equilibrium_time_min, 0)}"
            + (" *" if a.measured_settled is False else "")
        )
        table.add_row(
            plain(a.sensor),
            cell_text(a.steady_state_C),
            f"{cell_text(lo)} to {cell_text(hi)}",
            cell_text(a.equilibrium_time_min, 0),
            cell_text(a.rmse_C, 3),
            "yes" if a.model_ok else "[yellow]no[/]",
            measured,
        )
    table_console().print(table)
    console = prose_console()
    assumed = answers[0].method_answer.assumptions
    if any(a.measured_settled is False for a in answers):
        slowest = assumed.max_time_constant_min if robust else DEFAULT_MAX_TIME_CONSTANT_MIN
        console.print(_not_settled_note(slowest), highlight=False)
    if not robust:
        console.print(f"Assumes: {assumed.model}.", highlight=False)
        return
    console.print(
        f"Assumes: {assumed.model}, time constants up to {assumed.max_time_constant_min:g} min; room {assumed.room}.",
        highlight=False,
    )
    said = [(a.sensor, a.method_answer.assumptions.reference) for a in answers]
    for line in reference_lines([(name, text) for name, text in said if text]):
        console.print(line, highlight=False)


def reference_lines(said: list[tuple[str, str]]) -> list[str]:
    """What each sensor's answer takes from the reference, as lines under "Assumes": the run said
    once where every sensor's is the same run, sensors that take the same modes on one line, the
    machine model's words once below them.

    Parameters
    ----------
    said : list of (str, str)
        Per sensor, its name and what its answer takes from the reference (the run, ": ", then
        its modes).

    Returns
    -------
    list of str
    """
    parts = [(name, *text.partition(": ")[::2]) for name, text in said]
    runs = {run for _, run, _ in parts}
    if len(parts) < 2 or len(runs) > 1 or not all(modes for _, _, modes in parts):
        return [f"  reference for {name}: {text}" for name, text in said]
    # the machine model's words, the same for every sensor it holds, said once below them
    mark = MACHINE_MARK + "the machine model: "
    model_words = {modes.partition(mark)[2] for _, _, modes in parts if mark in modes}
    shared = model_words.pop() if len(model_words) == 1 else ""
    names_by_modes: dict[str, list[str]] = {}
    held: list[str] = []
    for name, _, modes in parts:
        if shared and modes.endswith(mark + shared):
            modes, held = modes[: -len(mark + shared)] + " (and the machine model)", [*held, name]
        names_by_modes.setdefault(modes, []).append(name)
    lines = [f"  reference: {runs.pop()}"]
    lines += [f"    {', '.join(names)}: {modes}" for modes, names in names_by_modes.items()]
    every = "every sensor above" if len(held) == len(parts) else ", ".join(held)
    return lines + ([f"    and the machine model, for {every}: {shared}"] if shared else [])


def _float_list(text: str, option: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError as exc:
        msg = f"{option}: expected comma-separated minutes such as 35,40,45,50; found {text!r}"
        raise InputError(msg) from exc
    if not values or any(v <= 0 for v in values):
        msg = f"{option}: expected positive minutes; found {text!r}"
        raise InputError(msg)
    return values


@thermal.command("min-time", short_help="Find the minimal identification time (Xia et al. 2014).")
@log_options
@click.option(
    "--sampling-periods", default="35,40,45,50", show_default=True, help="Sampling periods M (min), comma-separated."
)
@click.option(
    "--windows",
    default=None,
    help=(
        "Candidate identification times L as START:STOP[:STEP] minutes (default: every sample from 5 min to the "
        "longest period)."
    ),
)
@click.option(
    "--method",
    type=click.Choice(METHODS),
    default="aukf",
    show_default=True,
    help="The first-order filter (or least squares, lsq) fitted in every window, as in Xia et al. 2014 and "
    "Yu et al. 2019.",
)
@preset_option
@ambient_option("Room-temperature column: the input of each sensor's heat balance, before and after L.")
@plot_option("Draw RMSE against identification time to this picture (PNG; .svg or .pdf by the suffix).")
@json_option()
@user_errors
def min_time_command(**options: Any) -> None:
    """Find the minimal identification time (Xia et al. 2014 §2.4): RMSE against L for several sampling periods.

    \f

    Parameters
    ----------
    **options
        The options by click's names, each with its help above (:func:`min_time_request`).

    Raises
    ------
    InputError
        --sampling-periods or --windows not as asked, or a log that cannot be read.
    """
    run_min_time(min_time_request(options))


@dataclass(frozen=True, slots=True)
class MinTimeRequest(CommandRequest):
    """What ``thermal min-time`` was asked, grouped (:func:`min_time_request`).

    Attributes
    ----------
    log, room_col
        As in :class:`CommandRequest`.
    periods_min : tuple of float
        --sampling-periods (min).
    windows_min : tuple of float or None
        --windows: the candidate identification times L (min); None: the default.
    method, preset : str
        --method and --preset.
    plot_path : str or None
        --plot.
    as_json : bool
        --json.
    """

    periods_min: tuple[float, ...]
    windows_min: tuple[float, ...] | None
    method: str
    preset: str
    plot_path: str | None
    as_json: bool


def min_time_request(options: Mapping[str, Any]) -> MinTimeRequest:
    """The options of ``thermal min-time`` (a mapping by click's names, their help the command's ``--help``),
    read and grouped into settings: a :class:`MinTimeRequest`.

    Raises
    ------
    InputError
        --sampling-periods or --windows not as asked.
    """
    periods = _float_list(options["sampling_periods"], "--sampling-periods")
    windows = options["windows"]
    candidates = None
    if windows:
        parts = _float_list(windows.replace(":", ","), "--windows")
        if len(parts) not in (2, 3) or parts[1] <= parts[0]:
            msg = f"--windows: expected START:STOP[:STEP] with STOP > START; found {windows!r}"
            raise InputError(msg)
        step = parts[2] if len(parts) == 3 else 1.0
        candidates = tuple(np.arange(parts[0], parts[1] + step / 2, step))
    return command_request(MinTimeRequest, options, periods_min=tuple(periods), windows_min=candidates)


@dataclass(frozen=True, slots=True)
class MinTimeSensors:
    """The JSON answer of ``thermal min-time`` for more than one sensor.

    Attributes
    ----------
    sensors : tuple of MinTimeAnswer
    method : str
    sampling_periods_min : tuple of float
    """

    sensors: tuple[MinTimeAnswer, ...]
    method: str
    sampling_periods_min: tuple[float, ...]


def run_min_time(request: MinTimeRequest) -> None:
    """Search the minimal identification time a :class:`MinTimeRequest` asks for, draw it, and
    print the answer as a table or JSON.

    Parameters
    ----------
    request : MinTimeRequest

    Raises
    ------
    InputError
        A log that cannot be read, or too short for the sampling periods.
    """
    log, room = load_log_with_room(request.log, request.room_col)
    windows = None if request.windows_min is None else list(request.windows_min)
    with stderr.status("searching identification times…"):
        result = minimal_identification_time(
            log, request.method, request.preset, list(request.periods_min), windows, room
        )
    for name, begins in zip(
        result.sensors, result.rise_begins_min if result.rise_begins_min is not None else [], strict=False
    ):
        if np.isfinite(begins):
            stderr.print(
                f"mtident: sensor {name!r} stays at its first level until t = {begins:g} min (the warm-up began "
                "after the log); fitted from there, L still counts from the log's start",
                highlight=False,
            )
    if request.plot_path:
        from mtident.report import plot_min_time

        plot_min_time(result, request.plot_path)
        stderr.print(f"mtident: plot written to {request.plot_path}", highlight=False)
    answers = tuple(result.answer(i) for i in range(len(result.sensors)))
    for answer in answers:
        for warning in answer.warnings:
            stderr.print(f"mtident: warning: {warning}", highlight=False)
    if request.as_json:
        print_json(answers[0] if len(answers) == 1 else MinTimeSensors(answers, request.method, request.periods_min))
        return
    _min_time_table(log.source, request.method, result, answers)


def _min_time_table(source: str, method: str, result: MinTimeResult, answers: tuple[MinTimeAnswer, ...]) -> None:
    table = Table(
        title=(
            f"{source}: minimal identification time ({method}); choosing it took {result.measuring_time_min:g} "
            "min of measurement"
        )
    )
    table.add_column("sensor")
    table.add_column("minimal L (min)", justify="right")
    for p in result.periods_min:
        table.add_column(f"best L for M={p:g}", justify="right")
    table.add_column("periods agree", justify="center")
    for i, answer in enumerate(answers):
        # to 0.1 min: a 1-Hz log has a candidate L every second (39.9667 min)
        minimal = answer.min_identification_time_min
        best = [f"{round(float(b), 1):g}" for b in result.best_per_period_min[:, i]]
        table.add_row(
            plain(answer.sensor),
            f"{round(minimal, 1):g}" if math.isfinite(minimal) else "—",
            *best,
            "yes" if answer.periods_agree else "[yellow]no[/]",
        )
    table.caption = (
        "minimal L: the window whose relative RMSE, summed over the sampling periods M, is smallest (the papers' "
        "criterion); where the periods disagree it can differ from every period's own best"
    )
    table_console().print(table)


@thermal.command("inspect")
@log_options
@json_option("the summary")
@user_errors
def inspect_command(
    file: str,
    sensors: tuple[str, ...],
    time_col: str | None,
    time_unit: str | None,
    temperature_unit: str | None,
    sheet: str | None,
    as_json: bool,
) -> None:
    """Show how FILE is read: its format, the header line, the time column and step, each
    sensor's unit and readings, and every column left out with the reason.

    For a logger's own export, before trusting what identify or watch make of it.

    \f

    Parameters
    ----------
    file : str
        FILE: a log, or a shipped log's @-name.
    sensors : tuple of str
        --sensor (empty: all).
    time_col, time_unit : str or None
        --time-col and --time-unit.
    temperature_unit : str or None
        --unit: the unit of the temperature columns that state none.
    sheet : str or None
        --sheet: an Excel workbook's sheet.
    as_json : bool
        --json.
    """
    from mtident.io.describe import describe_log

    path = log_path(file)
    asked = asked_sensors(sensors, path, sheet)
    try:
        info = describe_log(path, time_col, time_unit, asked or None, temperature_unit, sheet)
    except InputError as exc:
        if (" row " not in str(exc) and " line " not in str(exc)) or "watch refuses it too" in str(exc):
            raise
        # a row refused here is refused by identify, learn and report too, but not by watch: say
        # so, where a user checks a log before trusting watch with it
        watch = (
            "watch skips a row that goes back a few steps with a warning, and refuses a log whose clock restarted"
            if "time goes back" in str(exc)
            else "watch, which follows a log as a logger writes it, skips such a row or reading with a warning and "
            "reads on"
        )
        msg = f"{exc} (identify, learn and report refuse the log too; {watch})"
        raise InputError(msg) from exc
    if as_json:
        print_json(info)
        return
    _inspect_table(file, info, unread_rooms_of(path, asked, sheet) if asked else [])


def _inspect_table(file: str, info: LogDescription, unread: list[str] | None = None) -> None:
    fmt, time = info.format, info.time
    console = OptionConsole(soft_wrap=True)  # a line per fact, as a terminal or a file shows it
    rows_under = fmt.rows_under_header
    text = (
        "" if fmt.kind.startswith("Excel") else f", {fmt.encoding}, {fmt.delimiter}-separated, decimal {fmt.decimal!r}"
    )
    console.print(
        f"[bold]{file}[/]: {fmt.kind}{text}; header on line {fmt.header_line}"
        + (f", {rows_under} row(s) under it before the data" if rows_under else "")
        + ("; " if fmt.units_from.startswith("no units") else "; units from ")
        + fmt.units_from,
        highlight=False,
    )
    step = time.step_min
    console.print(
        f"time: {time.column!r}, read as {time.read_as} (first cell {time.first_cell!r}); "
        + (
            "1 sample so far"
            if step is None
            else f"{time.samples} samples over {cell_text(time.span_min, 1)} min, a step of "
            + (f"{step * 60:g} s" if step < 1 else f"{cell_text(step, 2)} min")
        ),
        highlight=False,
    )
    table = Table()
    for column in ("sensor", "unit", "missing", "first °C", "last °C", "min °C", "max °C"):
        table.add_column(column, justify="left" if column in ("sensor", "unit") else "right", **column_layout(column))
    for d in info.sensors:
        table.add_row(
            plain(d.sensor),
            plain(as_options(d.unit)),
            str(d.missing),
            cell_text(d.first_C),
            cell_text(d.last_C),
            cell_text(d.min_C),
            cell_text(d.max_C),
        )
    console.print(table)
    for note in info.notes:
        console.print(f"note: {note}", highlight=False)
    say_room_candidates(
        [d.sensor for d in info.sensors],
        "read as a sensor column",
        " (with identify, watch, learn or report)",
        unread=unread,
    )
