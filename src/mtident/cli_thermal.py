"""``mtident thermal ...``: identify a warm-up, find the minimal identification time."""

from __future__ import annotations

import math
import shlex
from pathlib import Path
from typing import Literal, TypedDict

import click
import numpy as np
from rich.console import Console
from rich.table import Table

from mtident.cli import FiniteFloatRange, OutputPath, PicturePath, print_json, thermal, user_errors
from mtident.exceptions import InputError
from mtident.io.columns import room_named
from mtident.io.logs import SAMPLES, TIME_UNITS, TemperatureLog, read_temperature_log, sample_log_path
from mtident.thermal import DEFAULT_METHOD, METHODS, PRESETS, identify, minimal_identification_time

stderr = Console(stderr=True, soft_wrap=True)


def log_path(file: str) -> Path:
    """FILE as given, or the shipped log it names (@sample, @sample-room)."""
    return sample_log_path(file) if file in SAMPLES else Path(file)


def asked_sensors(sensors: tuple[str, ...], path: Path) -> list[str]:
    """The --sensor names, repeated or comma-separated, each once; empty for all ("all" or none given).

    An entry that is a column of the log as it stands is one name, commas and
    all ("Temp, Spindel", as some loggers name their channels).
    """
    from mtident.io.dialect import header_names

    columns = set(header_names(path)) if sensors and path.is_file() else set()
    names = (name.strip() for entry in sensors for name in ([entry] if entry.strip() in columns else entry.split(",")))
    return list(dict.fromkeys(name for name in names if name and name != "all"))


def load_log(file: str, sensors: tuple[str, ...], time_col: str | None, time_unit: str | None) -> TemperatureLog:
    path = log_path(file)
    log = read_temperature_log(path, time_col=time_col, time_unit=time_unit, sensors=asked_sensors(sensors, path) or None)
    for note in log.notes:
        stderr.print(f"mtident: note: {note}", highlight=False)
    return log


def load_log_with_room(file: str, sensors: tuple[str, ...], time_col: str | None, time_unit: str | None, room_col: str | None) -> tuple[TemperatureLog, np.ndarray | None]:
    """The log's sensors, and the room column split off from them when one is named."""
    if room_col is None:
        log = load_log(file, sensors, time_col, time_unit)
        _say_room_candidates(log.sensors, "identified as a machine sensor")
        return log, None
    asked = asked_sensors(sensors, log_path(file))
    # only the asked-for columns and the room are read: a dead column elsewhere does not matter
    every = load_log(file, tuple(dict.fromkeys([*asked, room_col])) if asked else (), time_col, time_unit)
    room = every.select([room_col]).temperature_C[:, 0]
    names = [name for name in asked or list(every.sensors) if name != room_col]
    if not names:
        msg = f"{every.source}: no sensor column left besides the room column {room_col!r}"
        raise InputError(msg)
    return every.select(names), room


def _say_room_candidates(sensors: tuple[str, ...] | list[str], taken_as: str) -> None:
    """A note on columns named as a room sensor when no --ambient was given: the room is then an
    assumption (steady, or wandering by --room-wander), and a drifting one biases T∞."""
    rooms = [name for name in sensors if room_named(name)]
    if rooms and len(rooms) < len(sensors):
        stderr.print(
            f"mtident: note: {', '.join(repr(r) for r in rooms)} {'is' if len(rooms) == 1 else 'are'} named as a room sensor and {taken_as}; "
            f"if it measures the room, --ambient {shlex.quote(rooms[0])} makes it the input of each sensor's heat balance (a drifting room then stays out of T∞)",
            highlight=False,
        )


def log_options(func):  # noqa: ANN001,ANN201 - click decorator stack
    func = click.option("--time-unit", type=click.Choice(list(TIME_UNITS)), help="Unit of a numeric time column (default: from its name, Time_s or Time [s], or a units row; else min). d: days, as spreadsheet serial dates (46348.33 = 22.11.2026 08:00).")(func)
    func = click.option("--time-col", metavar="NAME", help="Time column (default: the first column).")(func)
    func = click.option("--sensor", "sensors", multiple=True, metavar="NAME", help="Sensor column(s) to use; repeat or comma-separate (default: all).")(func)
    func = click.argument("file", metavar="FILE")(func)
    return func


class _ColumnLayout(TypedDict, total=False):
    no_wrap: bool
    overflow: Literal["fold", "crop", "ellipsis", "ignore"]
    min_width: int
    max_width: int


def _column_layout(column: str) -> _ColumnLayout:
    """Numbers on one line; a long sensor name (a building-management point's, HOBOware's with
    its serial numbers) folded over several lines of 14 to 32 characters, so that it neither
    squeezes the numbers to "…" nor is squeezed to two letters in an 80-column terminal."""
    if column == "sensor":
        return {"overflow": "fold", "min_width": 14, "max_width": 32}
    if column == "status":  # words: wrapped at a space when the table is too wide
        return {"min_width": 9}
    return {"no_wrap": True}


def _fmt(value: object, digits: int = 2) -> str:
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "—"  # no estimate yet (still collecting, or no steady state)
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


@thermal.command("identify")
@log_options
@click.option("--window", "window_min", type=FiniteFloatRange(min=0, min_open=True), default=30.0, show_default=True, help="Identification time L in minutes from the first sample.")
@click.option("--method", type=click.Choice(METHODS), default=DEFAULT_METHOD, show_default=True, help="ukf, aukf (Xia 2014), fukf, afukf (Yu 2019) or lsq (least squares).")
@click.option("--preset", type=click.Choice(PRESETS), default="data", show_default=True, help="Initial values and tuning: from the data, or a paper's exactly.")
@click.option("--horizon", "horizon_min", type=FiniteFloatRange(min=0, min_open=True), help="Predict to this time (min).")
@click.option("--pseudo-seed", type=int, help="Predict with seed 000's noisy pseudo-measurements (Eqs 21-22) from this seed.")
@click.option("--ambient", "ambient_col", metavar="NAME", help="Room-temperature column: the room becomes the input of each sensor's heat balance; T∞ at the room's level at the window's end.")
@click.option("--plot", "plot_path", type=PicturePath(), help="Draw measured and predicted curves to this picture (PNG; .svg or .pdf by the suffix).")
@click.option("--curve", "curve_path", type=OutputPath(), help="Write the measured and predicted curves with their 95 % band to this CSV (a row per time; for a report or a spreadsheet).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of a table.")
@user_errors
def identify_command(file: str, sensors: tuple[str, ...], time_col: str | None, time_unit: str | None, window_min: float, method: str, preset: str, horizon_min: float | None, pseudo_seed: int | None, ambient_col: str | None, plot_path: str | None, curve_path: str | None, as_json: bool) -> None:
    """Identify the temperature rise from the first WINDOW minutes of FILE and predict the rest.

    FILE is a CSV log (time column, one column per sensor), or @sample for the
    10-sensor warm-up shipped with mtident (@sample-room: the same with a room
    sensor column "room", for --ambient room).
    """
    log, room = load_log_with_room(file, sensors, time_col, time_unit, ambient_col)
    result = identify(log, window_min, method, preset, horizon_min, pseudo_seed, room)
    for note in result.notes[len(log.notes):]:
        stderr.print(f"mtident: warning: {note}", highlight=False)
    if plot_path:
        from mtident.report import plot_identification

        plot_identification(result, plot_path)
        stderr.print(f"mtident: plot written to {plot_path}", highlight=False)
    if curve_path:
        result.curve_frame().to_csv(curve_path, index=False, float_format="%.6f")
        stderr.print(f"mtident: curves written to {curve_path} ({len(result.time_min)} rows to t = {result.time_min[-1]:g} min)", highlight=False)
    summaries = [result.summary(i) for i in range(len(result.sensors))]
    if as_json:
        print_json(summaries[0] if len(summaries) == 1 else {"sensors": summaries, "method": method, "window_min": result.window_min})
        return
    table = Table(title=f"{log.source}: identified from the first {result.window_min:g} min ({method}, preset {preset})")
    for column in ("sensor", "T∞ ± 95 % (°C)", "λ (1/min)", "t_eq (min)", "RMSE (°C)", "model", "measured T / t_eq"):
        table.add_column(column, justify="right" if column != "sensor" else "left", **_column_layout(column))
    for d in summaries:
        interval = d["steady_state_ci95_C"]
        assert isinstance(interval, list)
        lo, hi = interval
        half = None if lo is None or hi is None else (hi - lo) / 2
        measured = "—" if d["measured_final_C"] is None else f"{d['measured_final_C']:.2f} / {_fmt(d['measured_equilibrium_time_min'], 0)}"
        table.add_row(
            str(d["sensor"]), f"{_fmt(d['steady_state_C'])} ± {_fmt(half)}", _fmt(d["lambda_per_min"], 4),
            _fmt(d["equilibrium_time_min"], 0), _fmt(d["rmse_C"], 3),
            "fits" if d["model_fits"] else "[yellow]misfit[/]", measured,
        )
    Console(width=max(Console().width, 100)).print(table)


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


@thermal.command("min-time")
@log_options
@click.option("--sampling-periods", default="35,40,45,50", show_default=True, help="Sampling periods M (min), comma-separated.")
@click.option("--windows", default=None, help="Candidate identification times L as START:STOP[:STEP] minutes (default: every sample from 5 min to the longest period).")
@click.option("--method", type=click.Choice(METHODS), default="aukf", show_default=True)
@click.option("--preset", type=click.Choice(PRESETS), default="data", show_default=True)
@click.option("--ambient", "ambient_col", metavar="NAME", help="Room-temperature column: the input of each sensor's heat balance, before and after L.")
@click.option("--plot", "plot_path", type=PicturePath(), help="Draw RMSE against identification time to this picture (PNG; .svg or .pdf by the suffix).")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of a table.")
@user_errors
def min_time_command(file: str, sensors: tuple[str, ...], time_col: str | None, time_unit: str | None, sampling_periods: str, windows: str | None, method: str, preset: str, ambient_col: str | None, plot_path: str | None, as_json: bool) -> None:
    """Find the minimal identification time (seed 000 §2.4): RMSE against L for several sampling periods."""
    periods = _float_list(sampling_periods, "--sampling-periods")
    candidates = None
    if windows:
        parts = _float_list(windows.replace(":", ","), "--windows")
        if len(parts) not in (2, 3) or parts[1] <= parts[0]:
            msg = f"--windows: expected START:STOP[:STEP] with STOP > START; found {windows!r}"
            raise InputError(msg)
        step = parts[2] if len(parts) == 3 else 1.0
        candidates = list(np.arange(parts[0], parts[1] + step / 2, step))
    log, room = load_log_with_room(file, sensors, time_col, time_unit, ambient_col)
    with stderr.status("searching identification times…"):
        result = minimal_identification_time(log, method, preset, periods, candidates, room)
    for name, begins in zip(result.sensors, result.rise_begins_min if result.rise_begins_min is not None else [], strict=False):
        if np.isfinite(begins):
            stderr.print(f"mtident: sensor {name!r} stays at its first level until t = {begins:g} min (the warm-up began after the log); fitted from there, L still counts from the log's start", highlight=False)
    if plot_path:
        from mtident.report import plot_min_time

        plot_min_time(result, plot_path)
        stderr.print(f"mtident: plot written to {plot_path}", highlight=False)
    summaries = [result.summary(i) for i in range(len(result.sensors))]
    if as_json:
        print_json(summaries[0] if len(summaries) == 1 else {"sensors": summaries, "method": method, "sampling_periods_min": periods})
        return
    table = Table(title=f"{log.source}: minimal identification time ({method}); choosing it took {result.measuring_time_min:g} min of measurement")
    table.add_column("sensor")
    table.add_column("minimal L (min)", justify="right")
    for p in result.periods_min:
        table.add_column(f"best L for M={p:g}", justify="right")
    table.add_column("periods agree", justify="center")
    for i, d in enumerate(summaries):
        # to 0.1 min: a 1-Hz log has a candidate L every second (39.9667 min)
        minimal = d["min_identification_time_min"]
        best = [f"{round(float(b), 1):g}" for b in result.best_per_period_min[:, i]]
        table.add_row(str(d["sensor"]), f"{round(minimal, 1):g}" if isinstance(minimal, float) else "—", *best, "yes" if d["periods_agree"] else "[yellow]no[/]")
    Console(width=max(Console().width, 100)).print(table)


@thermal.command("inspect")
@log_options
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of the summary.")
@user_errors
def inspect_command(file: str, sensors: tuple[str, ...], time_col: str | None, time_unit: str | None, as_json: bool) -> None:
    """Show how FILE is read: its format, the header line, the time column and step, each
    sensor's unit and readings, and every column left out with the reason.

    For a logger's own export, before trusting what identify or watch make of it.
    """
    from mtident.io.describe import describe_log

    path = log_path(file)
    info = describe_log(path, time_col, time_unit, asked_sensors(sensors, path) or None)
    if as_json:
        print_json(info)
        return
    fmt, time = info["format"], info["time"]
    assert isinstance(fmt, dict) and isinstance(time, dict)
    console = Console(soft_wrap=True)  # a line per fact, as a terminal or a file shows it
    rows_under = fmt["rows_under_header"]
    text = "" if str(fmt["kind"]).startswith("Excel") else f", {fmt['encoding']}, {fmt['delimiter']}-separated, decimal {fmt['decimal']!r}"
    console.print(
        f"[bold]{file}[/]: {fmt['kind']}{text}; header on line {fmt['header_line']}" + (f", {rows_under} row(s) under it before the data" if rows_under else "") + f"; units from {fmt['units_from']}",
        highlight=False,
    )
    step = time["step_min"]
    console.print(
        f"time: {time['column']!r}, read as {time['read_as']} (first cell {time['first_cell']!r}); "
        + ("1 sample so far" if step is None else f"{time['samples']} samples over {_fmt(time['span_min'], 1)} min, a step of " + (f"{step * 60:g} s" if step < 1 else f"{_fmt(step, 2)} min")),
        highlight=False,
    )
    table = Table()
    for column in ("sensor", "unit", "missing", "first °C", "last °C", "min °C", "max °C"):
        table.add_column(column, justify="left" if column in ("sensor", "unit") else "right", **_column_layout(column))
    sensor_rows = info["sensors"]
    assert isinstance(sensor_rows, list)
    for d in sensor_rows:
        table.add_row(d["sensor"], d["unit"], str(d["missing"]), _fmt(d["first_C"]), _fmt(d["last_C"]), _fmt(d["min_C"]), _fmt(d["max_C"]))
    console.print(table)
    notes = info["notes"]
    assert isinstance(notes, list)
    for note in notes:
        console.print(f"note: {note}", highlight=False)


def _save_state(path: Path, text: str) -> None:
    """Write the monitor's state atomically: a killed monitor leaves the old or the new file, never half of one."""
    import os
    import tempfile

    path.parent.mkdir(parents=True, exist_ok=True)
    handle, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
    try:
        with os.fdopen(handle, "w") as out:
            out.write(text)
            out.flush()
            os.fsync(out.fileno())
        os.replace(tmp, path)
    except BaseException:  # Ctrl-C or a full disk half-way: no stray temporary file beside the log
        Path(tmp).unlink(missing_ok=True)
        raise


def _when(monitor) -> str:  # noqa: ANN001 - thermal.monitor.Monitor
    """Where the monitor is in the log, for messages and the table's title."""
    from mtident.thermal.monitor import minutes

    return "before the first sample" if monitor.latest_time is None else f"at t = {minutes(monitor.latest_time)} min"


def _status_table(monitor, log: Path, live: bool = False) -> Table:  # noqa: ANN001 - thermal.monitor.Monitor
    """Per sensor: the latest reading, T∞ with its band, t_eq, when it is expected to stop, and its status.

    ``live``: the caption says when the whole test is expected to stop, on the warm-ups'
    present courses (:meth:`~mtident.thermal.monitor.Monitor.expected_stop_times`).
    """
    status = monitor.status()
    expected = monitor.expected_stop_times()
    caption = _expected_stop(monitor, expected) if live and monitor.stop_time is None else None
    table = Table(title=f"{log.name}: {_when(monitor)}", caption=caption)
    for column in ("sensor", "latest (°C)", "T∞ ± 95 % (°C)", "t_eq (min)", "stop ≈ (min)", "status"):
        table.add_column(column, justify="left" if column in ("sensor", "status") else "right", **_column_layout(column))
    for st, when in zip(status, expected, strict=True):
        colour = "green" if st.may_stop else "yellow"
        stop = "now" if st.may_stop and st.status == "may stop" else _fmt(when, 0)
        table.add_row(st.sensor, _fmt(st.latest_C), f"{_fmt(st.steady_state_C)} ± {_fmt(st.half_width_C)}", _fmt(st.equilibrium_time_min, 0), stop, f"[{colour}]{st.status}[/]")
    return table


def _expected_stop(monitor, times: np.ndarray | None = None) -> str | None:  # noqa: ANN001 - thermal.monitor.Monitor
    """When the test is expected to stop, for the engineer (None before the filters start);
    ``times``: the sensors' expected stops, if already at hand."""
    from mtident.thermal.monitor import minutes

    if monitor.carry is None or monitor.latest_time is None:
        return None
    times = monitor.expected_stop_times() if times is None else times
    whole = monitor.expected_stop_time(times)
    if whole is None:
        open_ = [st.sensor for st, t in zip(monitor.status(), times, strict=True) if not math.isfinite(t) and not st.left_out]
        return f"expected stop: not foreseeable yet ({', '.join(open_)}: no first-order course yet, or an interval that does not narrow enough on it)"
    # the forecast follows the present first-order courses: a slower mode or a drifting room only
    # delays the rule (bench_watch: at 45 min, first order within a median 4 min, fast + slow 245 min early)
    later = "a slower mode" if monitor.room_measured else "a slower mode or a drifting room"  # a measured room is in the model
    return (
        f"expected stop: t ≈ {minutes(round(whole))} min, in {minutes(round(whole - monitor.latest_time))} min, at the earliest: "
        f"on the present first-order courses ({later} moves it later)"
    )


@thermal.command("watch")
@log_options
@click.option("--tolerance", "tolerance_C", type=FiniteFloatRange(min=0, min_open=True), default=0.2, show_default=True, help="Stop when the T∞ 95 % half-width is within this (°C).")
@click.option("--hold", "hold_min", type=FiniteFloatRange(min=0), default=12.0, show_default=True, help="Minutes the T∞ estimate must stay within ±tolerance/2 without creeping.")
@click.option("--ambient", "ambient_col", metavar="NAME", help="Room-temperature column: the room becomes the input of each sensor's heat balance (robust to a drifting room).")
@click.option("--room-coupling", type=click.Choice(["lagged", "direct"]), help="With --ambient: how the sensors feel the room. lagged (default): through the machine's own time constant (a sensor in the structure); direct: at once (a sensor in the air stream or on a thin cover).")
@click.option("--room-wander", "room_wander", type=FiniteFloatRange(min=0.0), default=0.05, show_default=True, help="Without --ambient: how far the unmeasured room may wander in one hour (°C, 1σ of a random walk). It enters each sensor's heat balance as a random input, so the T∞ band allows for it; 0 takes the room as steady.")
@click.option(
    "--bin",
    "bin_s",
    type=FiniteFloatRange(min=0),
    default=10.0,
    show_default=True,
    help="Rows of a faster log are fed in bins of about this many seconds (their mean time and readings): a display's rounding holds for many rows at 1 Hz and is no independent noise. 0 feeds every row.",
)
@click.option("--replay", is_flag=True, help="Run a finished log as if it arrived live, as fast as possible.")
@click.option("--state", "state_path", type=click.Path(dir_okay=False), help="State file for resuming (default: <log name>.watch-state.json in the current directory).")
@click.option("--poll", "poll_s", type=FiniteFloatRange(min=0.05), default=0.5, show_default=True, help="Seconds between looks at a growing log.")
@click.option("--timeout", "timeout_s", type=FiniteFloatRange(min=0), help="Give up after this many seconds without a new row.")
@click.option("--plot", "plot_path", type=PicturePath(), help="Keep a picture (PNG; .svg or .pdf by the suffix) of measured and predicted curves up to date.")
@click.option("--json", "as_json", is_flag=True, help="Print the contract's JSON object when the decision is reached (or the log ends).")
@user_errors
def watch_command(file: str, sensors: tuple[str, ...], time_col: str | None, time_unit: str | None, tolerance_C: float, hold_min: float, ambient_col: str | None, room_coupling: str | None, room_wander: float, bin_s: float, replay: bool, state_path: str | None, poll_s: float, timeout_s: float | None, plot_path: str | None, as_json: bool) -> None:
    """Follow a warm-up log as it grows and say when the test can stop.

    Every new row updates each sensor's filter (rows faster than one in 10 s, as
    10-s bins: --bin); a sensor may stop when its T∞ interval is within the tolerance,
    the estimate has held still, and its residuals fit the model. Until then the
    table says when each sensor, and the test, is expected to stop at the earliest
    (on its present first-order course). The state file lets a killed monitor resume.
    """
    import json
    import sys
    import time

    from rich.live import Live

    from mtident.io.follow import LogFollower
    from mtident.thermal.monitor import Monitor, MonitorSettings, minutes

    path = log_path(file)
    if not path.is_file() and replay:
        msg = f"{path}: no such file"
        raise InputError(msg)
    # A workbook is not written row by row, so it is no live log; replayed, it is followed as the
    # CSV it holds (the state file is still the workbook's).
    followed = _workbook_as_replayed_csv(path) if replay else path
    names = asked_sensors(sensors, path) or None
    if room_coupling is not None and ambient_col is None:
        msg = "--room-coupling needs --ambient ROOM_COLUMN: it says how the sensors feel that room sensor"
        raise InputError(msg)
    if ambient_col is not None and room_coupling is None:
        # The data cannot tell the coupling within the first hours (bench_watch: a sensor that
        # follows the room at once, taken as lagged, stopped up to 0.41 °C off), so say which is assumed.
        stderr.print(
            f"mtident: note: the sensors are taken to feel the room {ambient_col!r} through their own heat balance (--room-coupling lagged, "
            "for sensors in the machine's structure); give --room-coupling direct for sensors in the air stream or on a thin cover",
            highlight=False,
        )
    if ambient_col is None and room_wander > 0:
        # Without a room sensor the room is an assumption (bench_watch: a room cycling by 0.15 °C,
        # five times the default wander, stopped 1 of 100 replays just beyond a 0.2 °C tolerance).
        stderr.print(
            f"mtident: note: no room sensor; the room is taken to wander by about {room_wander:g} °C in an hour (--room-wander). "
            "A room that drifts more (an air-conditioning cycle) can bias T∞ by a tenth of a degree or more: give --ambient ROOM_COLUMN if the log has one",
            highlight=False,
        )
    room_coupling = room_coupling or "lagged"
    if ambient_col is not None:
        # read the room column with the sensors; it is split off again below
        if names is None and path.is_file():
            # the sensors as the follower will take them (a resumed run compares them with its state)
            names = LogFollower(followed, None, time_col, time_unit, room=ambient_col).header_sensors()
        # a log not created yet: the follower reads every sensor and the room last once its header comes
        if names is not None:
            names = [n for n in names if n != ambient_col] + [ambient_col]
    state_file = Path(state_path) if state_path else Path.cwd() / f"{path.stem}.watch-state.json"
    settings = MonitorSettings(tolerance_C=tolerance_C, hold_min=hold_min, room_coupling=room_coupling, room_wander_C_per_h=room_wander, bin_min=bin_s / 60.0)
    # As state files have held them; the later ones only where given, so that older files resume.
    # The follower's saved origin is in the time unit it was read in: another unit needs a fresh start.
    settings_key = [tolerance_C, hold_min, room_coupling, room_wander, *([bin_s] if bin_s != 10.0 else []), *([f"time: {time_col} in {time_unit}"] if time_col or time_unit else [])]
    follower: LogFollower | None = None
    monitor: Monitor | None = None
    saved_text: str | None = None  # the last state written or resumed from: what a Ctrl-C falls back to
    if state_file.is_file():
        try:
            text = state_file.read_text()
            saved = json.loads(text)
            differs = [
                what
                for what, now, then in (
                    ("another log", str(path.resolve()), saved.get("log")),
                    ("other settings (--tolerance, --hold, --room-coupling, --room-wander, --bin, --time-col or --time-unit)", settings_key, saved.get("settings")),
                    ("other sensors", names, saved.get("requested")),
                )
                if now != then
            ]
            if not differs:
                follower = LogFollower.resume(followed, saved["position"], time_col, time_unit)
                monitor = Monitor.from_dict(saved["monitor"])
                saved_text = text
                stderr.print(f"mtident: resuming from {state_file} {_when(monitor)}", highlight=False)
            else:
                stderr.print(f"mtident: note: the state file {state_file} was written for {' and '.join(differs)}; starting afresh (it will be overwritten)", highlight=False)
        except (ValueError, KeyError, TypeError) as exc:
            stderr.print(f"mtident: warning: ignoring the unreadable state file {state_file} ({exc}); starting afresh", highlight=False)
    if follower is None:
        follower = LogFollower(followed, names, time_col, time_unit, room=ambient_col)
    if not path.is_file():
        stderr.print(f"mtident: waiting for {path} to appear (the logger has not created it yet)", highlight=False)

    def save() -> None:
        nonlocal saved_text
        assert follower is not None and monitor is not None
        # the sensors as resolved from the header (also for a log that was not there at the start):
        # a resumed run compares them with its own
        requested = names if names is not None or ambient_col is None else follower.sensors
        text = json.dumps({"log": str(path.resolve()), "settings": settings_key, "requested": requested, "position": follower.position(), "monitor": monitor.to_dict()})
        _save_state(state_file, text)
        saved_text = text

    live_view = sys.stdout.isatty() and not as_json
    last_data = time.monotonic()
    last_plot = 0.0
    interrupted = False
    try:
        with Live(console=Console(), auto_refresh=False, transient=False) if live_view else _Nothing() as live:
            while True:
                rows = follower.poll()
                for note in rows.notes:
                    stderr.print(f"mtident: note: {note}", highlight=False)
                for warning in rows.warnings:
                    stderr.print(f"mtident: warning: {warning}", highlight=False)
                if monitor is None and follower.sensors:
                    monitored = follower.sensors[:-1] if ambient_col else follower.sensors
                    if not monitored:
                        msg = f"{path}: no sensor column besides the room sensor {ambient_col!r}"
                        raise InputError(msg)
                    monitor = Monitor(tuple(monitored), settings)
                    if ambient_col is None:
                        _say_room_candidates(monitored, "watched as a machine sensor")
                if len(rows.time_min) and monitor is not None:
                    last_data = time.monotonic()
                    values, room = _split_room(rows.temperature_C, ambient_col)
                    # in pieces, so that the table moves on through a long replay (300 min at 1 Hz: 42 s)
                    for start in range(0, len(rows.time_min), _FEED_ROWS):
                        part = slice(start, start + _FEED_ROWS)
                        for message in monitor.feed(rows.time_min[part], values[part], None if room is None else room[part]):
                            stderr.print(f"mtident: {message}", highlight=False)
                        if live_view:
                            live.update(_status_table(monitor, path, live=True), refresh=True)
                    # saved with the follower's position, which is at the end of these rows
                    save()
                    if plot_path and (time.monotonic() - last_plot > 5.0 or monitor.stop_time is not None):
                        _plot_watch(path, monitor, plot_path, time_col, time_unit)
                        last_plot = time.monotonic()
                if monitor is not None and monitor.stop_time is not None:
                    break
                if replay:
                    break
                if timeout_s is not None and time.monotonic() - last_data > timeout_s:
                    stderr.print(f"mtident: no new row for {timeout_s:g} s; stopping", highlight=False)
                    break
                time.sleep(poll_s)
    except KeyboardInterrupt:
        # The monitor may have been stopped half-way through a sample: fall back to the state last
        # written, which the same command resumes from.
        interrupted = True
        monitor = Monitor.from_dict(json.loads(saved_text)["monitor"]) if saved_text is not None else None
        where = _when(monitor) if monitor is not None else "before the first sample"
        kept = f"the state is in {state_file}; the same command resumes from there" if saved_text is not None else "nothing was saved"
        stderr.print(f"mtident: interrupted (Ctrl-C) {where}; {kept}", highlight=False)
        if monitor is None:
            sys.exit(130)
    if monitor is None:
        msg = f"{path}: no data rows" if path.is_file() else f"{path}: no such file (not created within the --timeout of {timeout_s:g} s)"
        raise InputError(msg)
    if plot_path:
        problem = _plot_watch(path, monitor, plot_path, time_col, time_unit)
        if problem:
            stderr.print(f"mtident: warning: no plot drawn: {problem}", highlight=False)
    result = monitor.result()
    hindsight = _hindsight(followed, monitor, time_col, time_unit, ambient_col) if replay and monitor.stop_time is not None else None
    if as_json:
        print_json(result if hindsight is None else {**result, "hindsight": hindsight.to_dict()})
    else:
        Console(width=max(Console().width, 100)).print(_status_table(monitor, path))
        if result["stop_time_min"] is not None:
            gain = f"; {result['time_saved_min']:.0f} min before the predicted equilibrium" if result.get("time_saved_min") is not None else ""
            Console().print(f"[bold green]The test can stop at t = {minutes(monitor.stop_time or 0.0)} min{gain}.[/]")
            if live_view and not replay:
                Console().bell()  # the engineer may be at the other end of the machine
            if hindsight is not None:
                _print_hindsight(hindsight)
        else:
            Console().print("[bold yellow]Not yet: keep the test running.[/]")
            forecast = _expected_stop(monitor)
            if forecast:
                Console().print(forecast[0].upper() + forecast[1:] + ".")
    if interrupted:
        sys.exit(130)  # a shell's convention for SIGINT: the test was not decided here


# rows fed between two redraws of the live table
_FEED_ROWS = 250


def _split_room(readings: np.ndarray, ambient_col: str | None) -> tuple[np.ndarray, np.ndarray | None]:
    """The sensors' readings and the room's: the follower reads the room sensor last."""
    return (readings[:, :-1], readings[:, -1]) if ambient_col else (readings, None)


def _hindsight(followed: Path, monitor, time_col: str | None, time_unit: str | None, ambient_col: str | None):  # noqa: ANN001,ANN202
    """The decision against where the whole log settled, for a replayed log that runs on past the stop
    (None if it ends there). Read again whole by the replay's own reader: a resumed replay polled
    only the rows after its saved position, and the settled level is judged against the start."""
    from mtident.io.follow import LogFollower
    from mtident.thermal.hindsight import check_decision
    from mtident.thermal.monitor import minutes

    rows = LogFollower(followed, [*monitor.sensors, *([ambient_col] if ambient_col else [])], time_col, time_unit, room=ambient_col).poll()
    if not len(rows.time_min) or rows.time_min[-1] <= monitor.stop_time:
        return None
    values, room = _split_room(rows.temperature_C, ambient_col)
    stderr.print(f"mtident: the log runs on to t = {minutes(rows.time_min[-1])} min: checking the decision against where it settled", highlight=False)
    return check_decision(monitor.sensors, monitor.decided_steady_states(), monitor.stop_time, rows.time_min, values, monitor.settings.tolerance_C, room)


def _print_hindsight(hindsight) -> None:  # noqa: ANN001
    """The table of the decision against the rest of the log, and what it comes to."""
    from mtident.thermal.monitor import minutes

    room = f"; the room moved {hindsight.room_shift_C:+.2f} °C after the stop, added to T∞" if hindsight.room_shift_C else ""
    table = Table(title=f"Against the rest of the log (to t = {minutes(hindsight.log_end_min)} min){room}")
    for column in ("sensor", "T∞ at stop (°C)", "settled (°C)", "difference (°C)", "95 % rise at (min)"):
        table.add_column(column, justify="right" if column != "sensor" else "left", **_column_layout(column))
    settled = hindsight.checked
    for i, name in enumerate(hindsight.sensors):
        error = hindsight.error_C[i]
        shown = _fmt(float(error)) if settled[i] else "—"
        if settled[i] and not hindsight.within[i]:
            shown = f"[yellow]{shown}[/]"
        table.add_row(name, _fmt(float(hindsight.steady_state_C[i])), _fmt(float(hindsight.settled_C[i])), shown, _fmt(float(hindsight.measured_equilibrium_time_min[i]), 0))
    Console(width=max(Console().width, 100)).print(table)
    if not settled.any():
        Console().print("The log ends before its sensors settled: nothing to check the decision against.")
        return
    beyond = [name for name, ok, known in zip(hindsight.sensors, hindsight.within, settled, strict=True) if known and not ok]
    unsettled = [name for name, known, decided in zip(hindsight.sensors, settled, np.isfinite(hindsight.steady_state_C), strict=True) if decided and not known]
    verdict = (
        f"{len(beyond)} of {int(settled.sum())} sensors settled beyond the tolerance ({hindsight.tolerance_C:g} °C) of T∞ at the stop: {', '.join(beyond)}"
        if beyond
        else f"every sensor that settled ({int(settled.sum())}) is within the tolerance ({hindsight.tolerance_C:g} °C) of T∞ at the stop"
    )
    reached = float(np.nanmax(hindsight.measured_equilibrium_time_min[settled]))
    saved = reached - hindsight.stop_time_min
    timing = f"the log reached 95 % of its rise by t = {minutes(reached)} min, " + (f"{minutes(saved)} min after the stop" if saved > 0 else f"{minutes(-saved)} min before the stop: the rule saved no time on this log")
    not_settled = f"; not settled by the log's end: {', '.join(unsettled)}" if unsettled else ""
    Console().print(f"{verdict[0].upper()}{verdict[1:]}; {timing}{not_settled}.", highlight=False)


class _Nothing:
    """A stand-in for rich.live.Live when there is no terminal to draw in."""

    def __enter__(self) -> _Nothing:
        return self

    def __exit__(self, *args: object) -> None:
        return None

    def update(self, *args: object, **kwargs: object) -> None:
        return None


def _workbook_as_replayed_csv(path: Path) -> Path:
    """``path``, or for an Excel workbook the CSV it holds, written to a temporary folder to be
    replayed (:func:`~mtident.io.dialect.workbook_as_csv`)."""
    import atexit
    import shutil
    import tempfile

    from mtident.io.dialect import binary_kind, workbook_as_csv

    with path.open("rb") as handle:
        if binary_kind(handle.read(8)) not in ("xlsx", "xls"):
            return path
    folder = Path(tempfile.mkdtemp(prefix="mtident-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    copy = folder / f"{path.stem}.csv"
    copy.write_bytes(workbook_as_csv(path, path))
    return copy


def _plot_watch(path: Path, monitor, plot_path: str, time_col: str | None, time_unit: str | None) -> str | None:  # noqa: ANN001
    """Redraw the measured log and the monitor's current prediction; why not, if it could not be read.

    While the logger writes, a failed read is usually its last line half written,
    and the next redraw catches up; the caller says the reason only for the last one.
    """
    from mtident.report.plots import plot_monitor

    try:
        log = read_temperature_log(path, time_col=time_col, time_unit=time_unit, sensors=list(monitor.sensors))
    except (InputError, OSError) as exc:
        return str(exc)
    plot_monitor(log, monitor, plot_path)
    return None
