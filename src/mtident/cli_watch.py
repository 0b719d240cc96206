"""``mtident thermal watch``: follow a warm-up log and say when the test can stop.

A renderer over :class:`~mtident.thermal.session.WatchSession`: the session follows the log,
feeds the monitor and keeps the state file; this module turns its events and answers into lines,
tables, a picture and the JSON answer.
"""

from __future__ import annotations

import math
import signal
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path
from typing import TYPE_CHECKING

import click
import numpy as np
from rich.table import Table

from mtident._json import finite_or_none
from mtident.cli import (
    F,
    FiniteFloatRange,
    OptionConsole,
    OutputPath,
    PicturePath,
    carried_interrupt,
    print_json,
    table_console,
    thermal,
    user_errors,
)
from mtident.cli_sources import Recorder, network_recorder
from mtident.cli_thermal import (
    _column_layout,
    _fmt,
    _say_room_candidates,
    asked_sensors,
    free_fast_option,
    load_reference_file,
    log_options,
    log_path,
    machine_option,
    max_time_constant_option,
    reference_option,
    stderr,
)
from mtident.exceptions import InputError
from mtident.io.logs import SAMPLES
from mtident.io.record import RecordingThread
from mtident.thermal.hindsight import Hindsight
from mtident.thermal.monitor import Event, MonitorSettings, assumptions, minutes
from mtident.thermal.robust import RobustSettings
from mtident.thermal.session import RecordTail, WatchSession, default_state_path

if TYPE_CHECKING:
    from mtident.web import LivePage, Served

# events said on stderr as they come (a status change while narrowing is shown in the table)
_SAID = ("note", "warning", "ready", "not ready", "stop")
# a watch that has seen no new row for this long says it is waiting, once (a finished log given
# without --replay otherwise waits in silence)
_WAITING_HINT_S = 60.0


def decision_options(func: F) -> F:
    """The options of the stop decision, shared by watch and report.

    Parameters
    ----------
    func : callable
        The command's callback.

    Returns
    -------
    callable
        ``func`` with --tolerance, --confidence, --max-time-constant, --reference, --machine,
        --free-fast-modes, --ambient, --room-wander and --wait-for.
    """
    options = [
        click.option(
            "--tolerance",
            "tolerance_C",
            type=FiniteFloatRange(min=0, min_open=True),
            default=0.2,
            show_default=True,
            help="A sensor may stop when every model the data allow puts T∞ within this of the estimate (°C).",
        ),
        click.option(
            "--confidence",
            "decision_level",
            type=FiniteFloatRange(min=0.5, max=0.999),
            default=0.99,
            show_default=True,
            help="Confidence level of the interval the decision uses.",
        ),
        max_time_constant_option,
        reference_option,
        machine_option,
        free_fast_option,
        click.option(
            "--ambient",
            "ambient_col",
            metavar="NAME",
            help=(
                "Room-temperature column: the room becomes an input of every mode's heat balance, so a drifting room "
                "does not "
                "fool the rule."
            ),
        ),
        click.option(
            "--room-wander",
            "room_wander",
            type=FiniteFloatRange(min=0.0),
            default=0.05,
            show_default=True,
            help=(
                "Without --ambient: how far the unmeasured room may wander in an hour (°C, 1σ of a random walk); 0 "
                "takes the "
                "room as steady."
            ),
        ),
        click.option(
            "--wait-for",
            "wait_for",
            multiple=True,
            metavar="NAME",
            help=(
                "A sensor the test waits for; repeat (default: every sensor watched). The others are checked and "
                "reported but do not hold the stop (a slow column sensor in a spindle test)."
            ),
        ),
    ]
    for option in reversed(options):
        func = option(func)
    return func


def state_file(file: str, path: Path, given: str | None) -> Path:
    """The state file: the one given, else beside the log; for a shipped sample, in the current
    folder (not inside the installed package).

    Parameters
    ----------
    file : str
        FILE as given.
    path : Path
        The log.
    given : str or None
        The --state option.

    Returns
    -------
    Path
    """
    if given:
        return Path(given)
    return Path.cwd() / default_state_path(path).name if file in SAMPLES else default_state_path(path)


def monitor_settings(
    tolerance_C: float,
    decision_level: float,
    max_tau_min: float,
    reference_path: str | None,
    free_fast_modes: int,
    ambient_col: str | None,
    room_wander: float,
    wait_for: tuple[str, ...] = (),
    machine: str | None = None,
) -> MonitorSettings:
    """The decision's settings from the options of :func:`decision_options`.

    Parameters
    ----------
    tolerance_C : float
        --tolerance (°C).
    decision_level : float
        --confidence.
    max_tau_min : float
        --max-time-constant (min).
    reference_path : str or None
        --reference.
    free_fast_modes : int
        --free-fast-modes.
    ambient_col : str or None
        --ambient: the room sensor's column.
    room_wander : float
        --room-wander (°C in an hour).
    wait_for : tuple of str
        --wait-for (empty: every sensor).
    machine : str or None
        --machine: the machine the test is of.

    Returns
    -------
    MonitorSettings

    Raises
    ------
    InputError
        A reference file that cannot be read.
    """
    return MonitorSettings(
        tolerance_C=tolerance_C,
        decision_level=decision_level,
        robust=RobustSettings(
            max_time_constant_min=max_tau_min, room_wander_C_per_h=room_wander, free_fast_modes=free_fast_modes
        ),
        reference=load_reference_file(reference_path, machine),
        room_sensor=ambient_col,
        wait_for=tuple(wait_for),
    )


@thermal.command("watch")
@log_options
@decision_options
@click.option(
    "--replay",
    is_flag=True,
    help="Run a finished log as if it arrived live, as fast as possible (afresh, unless --resume).",
)
@click.option("--resume", is_flag=True, help="With --replay: resume from the state file instead of starting afresh.")
@click.option(
    "--state",
    "state_path",
    type=click.Path(dir_okay=False),
    help="State file for resuming (default: beside the log, LOG.watch-state.npz).",
)
@click.option(
    "--poll",
    "poll_s",
    type=FiniteFloatRange(min=0.05),
    default=0.5,
    show_default=True,
    help="Seconds between looks at a growing log.",
)
@click.option(
    "--timeout", "timeout_s", type=FiniteFloatRange(min=0), help="Give up after this many seconds without a new row."
)
@click.option(
    "--plot",
    "plot_path",
    type=PicturePath(),
    help="Keep a picture (PNG; .svg or .pdf by the suffix) of measured and predicted curves up to date.",
)
@click.option(
    "--json",
    "as_json",
    is_flag=True,
    help="Print one JSON object when the decision is reached (or the log ends); its keys are in the docs' JSON page.",
)
@click.option("--device", metavar="NAME", help="MTConnect (FILE is the agent, http://host:5000): the device's name.")
@click.option(
    "--node",
    "nodes",
    multiple=True,
    metavar="NODEID",
    help="OPC UA (FILE is the server, opc.tcp://host:4840): a node to record, such as ns=2;s=Spindle.T1; repeat.",
)
@click.option(
    "--item",
    "items",
    multiple=True,
    metavar="ID=NAME",
    help="MTConnect: record this TEMPERATURE data item (id or name) as sensor NAME; repeat (default: every one).",
)
@click.option(
    "--record",
    "record_path",
    type=OutputPath(),
    help="MTConnect or OPC UA: the CSV log the readings are written to, to replay later (default: DEVICE.csv or "
    "HOST.csv here).",
)
@click.option(
    "--from-buffer-start",
    is_flag=True,
    help="MTConnect: begin with every reading the agent still holds (a test begun before the watch).",
)
@click.option(
    "--serve",
    "serve_address",
    metavar="HOST:PORT",
    help="Serve a live page of the table and the curves, read-only (127.0.0.1:8050; 0.0.0.0:8050 for the network).",
)
@user_errors
def watch_command(
    file: str,
    sensors: tuple[str, ...],
    time_col: str | None,
    time_unit: str | None,
    temperature_unit: str | None,
    tolerance_C: float,
    decision_level: float,
    max_tau_min: float,
    reference_path: str | None,
    machine: str | None,
    free_fast_modes: int,
    ambient_col: str | None,
    room_wander: float,
    wait_for: tuple[str, ...],
    replay: bool,
    resume: bool,
    state_path: str | None,
    poll_s: float,
    timeout_s: float | None,
    plot_path: str | None,
    as_json: bool,
    device: str | None,
    nodes: tuple[str, ...],
    items: tuple[str, ...],
    record_path: str | None,
    from_buffer_start: bool,
    serve_address: str | None,
) -> None:
    """Follow a warm-up log as it grows and say when the test can stop.

    Each sensor's readings so far are fitted with sums of up to four exponential modes (six where
    the readings use all four); a sensor may stop when every model the data cannot exclude
    (modes up to --max-time-constant, or near a reference run's) puts its steady-state
    temperature T∞ within the tolerance, at two checks in a row. The test may stop when every
    sensor may. Until then the answer says the interval, what sets its ends, and when the stop
    is expected. A killed monitor resumes
    from its state file.

    \f

    Parameters
    ----------
    file : str
        FILE: a log, a shipped log's @-name, an MTConnect agent's URL or an OPC UA server's.
    sensors : tuple of str
        --sensor (empty: all).
    time_col, time_unit : str or None
        --time-col and --time-unit.
    temperature_unit : str or None
        --unit: the unit of the temperature columns that state none.
    tolerance_C : float
        --tolerance (°C).
    decision_level : float
        --confidence.
    max_tau_min : float
        --max-time-constant (min).
    reference_path : str or None
        --reference.
    machine : str or None
        --machine: the machine the test is of.
    free_fast_modes : int
        --free-fast-modes.
    ambient_col : str or None
        --ambient: the room sensor's column.
    room_wander : float
        --room-wander (°C in an hour).
    wait_for : tuple of str
        --wait-for (empty: every sensor).
    replay, resume : bool
        --replay and --resume.
    state_path : str or None
        --state.
    poll_s : float
        --poll (s).
    timeout_s : float or None
        --timeout (s).
    plot_path : str or None
        --plot.
    as_json : bool
        --json.
    device : str or None
        --device (MTConnect).
    nodes : tuple of str
        --node (OPC UA).
    items : tuple of str
        --item (MTConnect).
    record_path : str or None
        --record.
    from_buffer_start : bool
        --from-buffer-start (MTConnect).
    serve_address : str or None
        --serve: HOST:PORT of the live page.

    Raises
    ------
    InputError
        --replay of a missing log, a log without data rows, or a source's options that do not fit
        FILE.
    """
    if resume and not replay:
        stderr.print(
            "mtident: note: --resume is the default for a live log; it matters only with --replay", highlight=False
        )
    recorder = network_recorder(file, device, nodes, items, record_path, from_buffer_start, replay)
    path = log_path(file) if recorder is None else recorder.log
    if replay and not path.is_file():
        msg = f"{path}: no such file"
        raise InputError(msg)
    settings = monitor_settings(
        tolerance_C,
        decision_level,
        max_tau_min,
        reference_path,
        free_fast_modes,
        ambient_col,
        room_wander,
        wait_for,
        machine,
    )
    followed = _workbook_as_replayed_csv(path) if replay else path
    session = WatchSession(
        followed,
        settings,
        sensors=asked_sensors(sensors, path) or None,
        time_col=time_col,
        time_unit=time_unit,
        temperature_unit=temperature_unit,
        state_path=state_file(str(path) if recorder else file, path, state_path),
        resume=resume or not replay,
    )
    for note in session.notes:
        stderr.print(f"mtident: {note}", highlight=False)
    if recorder is not None:
        stderr.print(f"mtident: recording {file} to {path}", highlight=False)
    elif not path.is_file():
        stderr.print(f"mtident: waiting for {path} to appear (the logger has not created it yet)", highlight=False)
    interrupted = _follow_served(
        session,
        path,
        replay,
        poll_s,
        timeout_s,
        plot_path,
        sys.stdout.isatty() and not as_json,
        serve_address,
        recorder,
    )
    if session.state is None:
        if interrupted:
            sys.exit(130)
        msg = (
            f"{path}: no data rows"
            if path.is_file()
            else f"{path}: no such file (not created within the --timeout of {timeout_s:g} s)"
        )
        raise InputError(msg)
    if plot_path:
        _plot(session, plot_path)
    # interrupted: the answer without the expected stops, whose forecasts take seconds
    _answer(
        session,
        path,
        replay,
        as_json,
        live=sys.stdout.isatty() and not as_json and not replay,
        forecast=not interrupted,
    )
    if interrupted:
        sys.exit(130)  # a shell's convention for SIGINT: the test was not decided here


def _follow_served(
    session: WatchSession,
    path: Path,
    replay: bool,
    poll_s: float,
    timeout_s: float | None,
    plot_path: str | None,
    live: bool,
    serve_address: str | None,
    recorder: Recorder | None,
) -> bool:
    """:func:`_follow` with its surroundings: the live page served where ``--serve`` asks for one,
    SIGTERM taken as an interrupt (on the main thread), and a network source recorded on its own
    thread; each undone when the following ends.

    Parameters
    ----------
    session : WatchSession
    path : Path
        The log followed.
    replay : bool
        Replay a finished log instead of following a growing one.
    poll_s, timeout_s : float
        How often to look for new rows, and how long to wait for the log to appear (s).
    plot_path : str or None
        Where to keep a plot up to date.
    live : bool
        Redraw the table in place (a terminal, not JSON).
    serve_address : str or None
        Where to serve the live page (None: no page).
    recorder : Recorder or None
        A network source that writes the log (None: a log file).

    Returns
    -------
    bool
        Whether the following was interrupted (Ctrl-C or SIGTERM).
    """
    page, served = _serve(serve_address, path)
    on_main = threading.current_thread() is threading.main_thread()
    _terminating.clear()
    previous = signal.signal(signal.SIGTERM, _terminate) if on_main else None
    # the source is recorded on its own thread: its rows reach the log while the fits run
    recording = None if recorder is None else RecordingThread(recorder, poll_s)
    try:
        return _follow(
            session,
            path,
            replay,
            poll_s,
            timeout_s,
            plot_path,
            live,
            None if recording is None else recording.fetch,
            page,
        )
    finally:
        if on_main:
            signal.signal(signal.SIGTERM, previous)
        if served is not None:
            served.stop()
        if recording is not None:
            recording.close()


def _follow(
    session: WatchSession,
    path: Path,
    replay: bool,
    poll_s: float,
    timeout_s: float | None,
    plot_path: str | None,
    live: bool,
    fetch: Callable[[], list[str]] | None = None,
    page: LivePage | None = None,
) -> bool:
    """Poll the log until the decision, the log's end (a replay) or a timeout; True if Ctrl-C
    ended it (the state file then holds the last rows fed). A live log's newest readings reach the
    page from a thread of their own, while this one runs the checks."""
    tail = None if page is None or replay else RecordTail(session, page.record, poll_s)
    try:
        return _follow_polls(session, path, replay, poll_s, timeout_s, plot_path, live, fetch, page)
    finally:
        if tail is not None:
            tail.close()


def _follow_polls(
    session: WatchSession,
    path: Path,
    replay: bool,
    poll_s: float,
    timeout_s: float | None,
    plot_path: str | None,
    live: bool,
    fetch: Callable[[], list[str]] | None,
    page: LivePage | None,
) -> bool:
    """The polls of :func:`_follow`."""
    from rich.live import Live

    last_data = time.monotonic()
    last_plot = last_page = last_shown = 0.0
    said_room = said_waiting = False
    try:
        with Live(console=OptionConsole(), auto_refresh=False, transient=False) if live else _Nothing() as view:

            def redraw(s: WatchSession) -> None:
                nonlocal last_shown
                if live:
                    view.update(_status_table(s, path), refresh=True)
                if page is not None:
                    # each check's answer at once (a long poll's too: a replay, a resume's catch-up); the
                    # curves, which cost a picture, at most every _PAGE_PROGRESS_S
                    picture = time.monotonic() - last_shown > _PAGE_PROGRESS_S
                    _publish(page, s, last_page, forecast=False, picture=picture)
                    last_shown = time.monotonic() if picture else last_shown

            while True:
                if page is not None and page.version == 0 and session.state is not None:
                    _publish(page, session, last_page, forecast=False)  # a resumed state: at once
                for note in fetch() if fetch is not None else []:
                    stderr.print(f"mtident: {note}", highlight=False)
                events = session.poll(redraw if live or page is not None else None, _terminating.is_set)
                _say(events)
                if _terminating.is_set():  # at a safe point: the state file holds what the message says
                    return _say_interrupted(_Terminated(), session)
                if session.state is not None and not said_room and session.settings.room_sensor is None:
                    _say_room_candidates(session.sensors, "watched as a machine sensor")
                    said_room = True
                if session.last_rows:
                    last_data = time.monotonic()
                if page is not None and session.state is not None and (session.last_rows or session.stopped):
                    last_page = _publish(page, session, last_page)
                if plot_path and session.state is not None and (time.monotonic() - last_plot > 5.0 or session.stopped):
                    _plot(session, plot_path)
                    last_plot = time.monotonic()
                if session.stopped or replay:
                    return False
                if timeout_s is not None and time.monotonic() - last_data > timeout_s:
                    stderr.print(f"mtident: no new row for {timeout_s:g} s; stopping", highlight=False)
                    return False
                if not said_waiting and time.monotonic() - last_data > _WAITING_HINT_S:
                    stderr.print(
                        f"mtident: waiting for new rows: none for {_WAITING_HINT_S:g} s (a finished log is replayed "
                        "with --replay; Ctrl-C stops, and the same command resumes)",
                        highlight=False,
                    )
                    said_waiting = True
                time.sleep(poll_s)
                if _terminating.is_set():
                    return _say_interrupted(_Terminated(), session)
    except KeyboardInterrupt as stop:
        session.back_to_saved()  # a poll cut short fed rows the state file does not hold
        return _say_interrupted(stop, session)
    except SystemError as error:
        interrupt = carried_interrupt(error)
        if interrupt is None:
            raise
        session.back_to_saved()
        return _say_interrupted(interrupt, session)


def _say_interrupted(stop: KeyboardInterrupt, session: WatchSession) -> bool:
    """Where the watch was stopped, and what it kept; True (interrupted)."""
    how = "terminated (SIGTERM)" if isinstance(stop, _Terminated) else "interrupted (Ctrl-C)"
    where = (
        "before the first sample"
        if session.state is None or not len(session.state.readings.time_min)
        else f"at t = {minutes(session.state.readings.latest_min)}"
    )
    kept = (
        f"the state is in {session.state_path}; the same command resumes from there"
        if session.state_path.is_file()
        else "nothing was saved"
    )
    stderr.print(f"mtident: {how} {where}; {kept}", highlight=False)
    return True


class _Terminated(KeyboardInterrupt):
    """SIGTERM (a service manager stopping the watch), taken as Ctrl-C: the state kept, the record written."""


# set by SIGTERM; the watch ends at its next safe point (between two checks or two sensors' fits, or
# after a poll), not by an exception thrown into whatever runs (a compiled fit, a plot)
_terminating = threading.Event()


def _terminate(signum: int, frame: object) -> None:  # noqa: ARG001
    _terminating.set()


def _serve(address: str | None, path: Path) -> tuple[LivePage | None, Served | None]:
    """The live page and its server, where --serve asks for one."""
    if address is None:
        return None, None
    from mtident.web import LivePage, parse_address, serve

    page = LivePage(path.name)
    served = serve(page, *parse_address(address))
    stderr.print(f"mtident: the live page is at {served.url} (read-only)", highlight=False)
    return page, served


# the expected stops cost a forecast per sensor: asked for on the page this seldom (s)
_PAGE_FORECAST_S = 10.0
# a long poll's progress is shown on the page this often at most (s): each costs a picture
_PAGE_PROGRESS_S = 2.0


def _publish(
    page: LivePage, session: WatchSession, last_forecast: float, forecast: bool = True, picture: bool = True
) -> float:
    """Show the session's answer on the live page (with the expected stops, where ``forecast`` and
    the last were made long enough ago), and its curves where ``picture``; returns when the forecast
    was made."""
    import io

    from mtident.report.plots import plot_monitor

    state = session.state
    assert state is not None
    forecast = forecast and not state.stopped and time.monotonic() - last_forecast > _PAGE_FORECAST_S
    answer = session.result(with_forecast=forecast)
    latest = {}
    for s, name in enumerate(state.sensors):
        valid = state.readings.values_C[:, s][np.isfinite(state.readings.values_C[:, s])]
        latest[name] = float(valid[-1]) if len(valid) else None
    shown = {**answer, "latest_C": latest, "recorded_time_min": finite_or_none(state.readings.latest_min)}
    page.publish(shown)  # the answer at once; its curves once drawn
    if picture:
        buffer = io.BytesIO()
        plot_monitor(state, session.settings).savefig(buffer, format="png", dpi=90)  # type: ignore[union-attr]
        page.publish(shown, buffer.getvalue())
    return time.monotonic() if forecast else last_forecast


def _say(events: list[Event]) -> None:
    for event in events:
        if event.kind in _SAID:
            prefix = "warning: " if event.kind == "warning" else "note: " if event.kind == "note" else ""
            when = f"t = {minutes(event.time_min)}: " if math.isfinite(event.time_min) else ""
            stderr.print(f"mtident: {prefix}{when}{event.text}", highlight=False)


def _answer(session: WatchSession, path: Path, replay: bool, as_json: bool, live: bool, forecast: bool = True) -> None:
    """The decision: the JSON object, or the table, the verdict and what it rests on (with the
    expected stops where ``forecast``)."""
    outcome = session.result(with_forecast=forecast)
    hindsight = session.hindsight() if replay else None
    if hindsight is not None:
        outcome["time_saved_min"] = hindsight.time_saved_min
        outcome["settle_time_min"] = finite_or_none(hindsight.test_settle_time_min)
        stderr.print(
            f"mtident: the log runs on to t = {minutes(hindsight.log_end_min)}: comparing the decision with how "
            "it went on",
            highlight=False,
        )
    if as_json:
        print_json(outcome if hindsight is None else {**outcome, "hindsight": hindsight.to_dict()})
        return
    console = table_console()
    console.print(_status_table(session, path))
    state = session.state
    assert state is not None
    said = assumptions(session.settings, state.sensors[0], state.readings.room_C is not None)
    console.print(
        f"Assumes: {said.model}, time constants up to {said.max_time_constant_min:g} min; room {said.room}",
        highlight=False,
    )
    if session.settings.reference is not None:
        # each sensor has its own modes in the reference, or none, or doubtful ones
        for name in state.sensors:
            console.print(f"  reference for {name}: {assumptions(session.settings, name).reference}", highlight=False)
    if state.stopped:
        saved = outcome.get("time_saved_min")
        gain = (
            f"; {minutes(saved)} before the readings settled within the tolerance"
            if isinstance(saved, float) and saved > 0
            else ""
        )
        console.print(f"[bold green]The test can stop at t = {minutes(state.stop_time_min)}{gain}.[/]")
        if live:
            console.bell()  # the engineer may be at the other end of the machine
        if hindsight is not None:
            _print_hindsight(hindsight)
        return
    bound = outcome.get("room_bound_sensors")
    if isinstance(bound, list) and bound:
        console.print(
            f"[bold yellow]Not yet, and a longer test does not bring {', '.join(map(str, bound))} within the "
            "tolerance.[/]"
        )
        console.print(str(outcome["reason"]), highlight=False)
        console.print(
            "(--ambient COLUMN names the room sensor's column; --room-wander states the room's wander in °C an hour)"
        )
    else:
        console.print("[bold yellow]Not yet: keep the test running.[/]")
        console.print(str(outcome["reason"]), highlight=False)
    expected = outcome.get("expected_stop_time_min")
    if isinstance(expected, float):
        console.print(
            f"Expected stop: t ≈ {minutes(round(expected))} on the best model's course (a slower mode that still "
            "fits moves it later).",
            highlight=False,
        )
    elif "expected_stop_time_min" in outcome and outcome.get("decision") != "stop":
        console.print(
            "Expected stop: none found on the best models' courses (a sensor whose interval does not come within the "
            "tolerance there, or whose status gives no course to go on: no fit yet, off its reference, a misfit).",
            highlight=False,
        )


def _status_table(session: WatchSession, path: Path) -> Table:
    """Per sensor: the latest reading (°C), when it was last checked (min: a sensor is checked when
    it falls due, not at every reading), T∞ with its 95 % interval and the decision's, t_eq,
    status."""
    state = session.state
    where = "before the first sample" if state is None else f"at t = {minutes(state.readings.latest_min)}"
    table = Table(title=f"{path.name}: {where} (temperatures in °C, times in min)")
    level = f"{session.settings.decision_level * 100:g} %"
    columns = ("sensor", "latest", "checked", "T∞", "95 % interval", f"{level} interval", "t_eq")
    for column in (*columns, "status"):
        table.add_column(
            column, justify="left" if column in ("sensor", "status") else "right", **_column_layout(column)
        )
    if state is None:
        return table
    values = state.readings.values_C
    for s, check in enumerate(state.checks):
        readings = values[:, s]
        finite = readings[np.isfinite(readings)]
        latest = float(finite[-1]) if finite.size else math.nan
        colour = (
            "green"
            if check.may_stop
            else "yellow"
            if check.status in ("confirming", "narrowing")
            else "red"
            if check.status == "misfit"
            else "white"
        )
        table.add_row(
            check.sensor,
            _fmt(latest),
            _fmt(check.checked_min, 0),
            _fmt(check.steady_C),
            f"{_fmt(check.low95_C)} to {_fmt(check.high95_C)}",
            f"{_fmt(check.low_C)} to {_fmt(check.high_C)}",
            _fmt(check.equilibrium_time_min, 0),
            f"[{colour}]{check.status}[/]",
        )
    return table


def _plot(session: WatchSession, plot_path: str) -> None:
    from mtident.report.plots import plot_monitor

    assert session.state is not None
    plot_monitor(session.state, session.settings, plot_path)


def _span(values: np.ndarray) -> str:
    """``+0.06 to +0.07``, or one value where they round alike."""
    low, high = f"{float(values.min()):+.2f}", f"{float(values.max()):+.2f}"
    return low if low == high else f"{low} to {high}"


def _print_hindsight(hindsight: Hindsight) -> None:
    """The table of the decision against the rest of the log, and what it comes to."""
    shift = hindsight.room_shift_C
    added = hindsight.shift_C[np.isfinite(hindsight.shift_C)]
    # a room level again at the end can still have moved the sensors, which follow it late
    moved = bool(len(added) and np.any(added != 0.0))
    room = (
        f"; the room moved {shift:+.2f} °C from the stop to the end; each sensor follows its course through "
        f"its modes, {_span(added)} °C added to T∞ at the stop"
        if moved
        else ""
    )
    table = Table(title=f"Against the rest of the log (to t = {minutes(hindsight.log_end_min)}){room}")
    # with the room's move added in the column itself, the difference is the next two columns'
    stop_column = "T∞ at stop + room (°C)" if moved else "T∞ at stop (°C)"
    for column in ("sensor", stop_column, "settled (°C)", "difference (°C)", "settled by (min)"):
        table.add_column(column, justify="right" if column != "sensor" else "left", **_column_layout(column))
    settled = hindsight.checked
    for i, name in enumerate(hindsight.sensors):
        error = hindsight.error_C[i]
        shown = _fmt(float(error)) if settled[i] else "—"
        if settled[i] and not hindsight.within[i]:
            shown = f"[yellow]{shown}[/]"
        table.add_row(
            name,
            _fmt(float(hindsight.steady_state_C[i] + hindsight.shift_C[i])),
            _fmt(float(hindsight.settled_C[i])),
            shown,
            _fmt(float(hindsight.settle_time_min[i]), 0) if hindsight.settle_time_min is not None else "—",
        )
    table_console().print(table)
    timing = _settle_timing(hindsight)
    if not settled.any():
        OptionConsole().print(
            f"The log ends before its sensors settled (settled: moving less than {hindsight.tolerance_C / 2:g} °C "
            f"over the log's last quarter, with under {hindsight.tolerance_C / 4:g} °C still to come at the pace of "
            "its slowest mode, a move its readings' display step could hide counted in): nothing to check the "
            "decision against" + (f"; {timing}." if timing else "."),
            highlight=False,
        )
        return
    beyond = [
        name for name, ok, known in zip(hindsight.sensors, hindsight.within, settled, strict=True) if known and not ok
    ]
    unsettled = [
        name
        for name, known, decided in zip(hindsight.sensors, settled, np.isfinite(hindsight.steady_state_C), strict=True)
        if decided and not known
    ]
    verdict = (
        f"{len(beyond)} of {int(settled.sum())} sensors settled beyond the tolerance ({hindsight.tolerance_C:g} °C) "
        f"of T∞ at the stop: {', '.join(beyond)}"
        if beyond
        else (
            f"every sensor that settled ({int(settled.sum())}) is within the tolerance ({hindsight.tolerance_C:g} °C) "
            "of T∞ at the stop"
        )
    )
    not_settled = f"; not settled by the log's end: {', '.join(unsettled)}" if unsettled else ""
    OptionConsole().print(
        f"{verdict[0].upper()}{verdict[1:]}" + (f"; {timing}" if timing else "") + f"{not_settled}.", highlight=False
    )


def _settle_timing(hindsight: Hindsight) -> str:
    """When the readings settled within the tolerance (t_settle, of the sensors the test waits for),
    against the stop: the time the rule saved over simply waiting."""
    settle = hindsight.test_settle_time_min
    saved = hindsight.time_saved_min
    if saved is None or not np.isfinite(settle):
        return "when every sensor waited for settled within the tolerance is later than the log can tell"
    when = (
        f"the readings of every sensor waited for stayed within ±{hindsight.tolerance_C:g} °C of where they settled "
        f"from t = {minutes(settle)}"
    )
    if saved > 0:
        return f"{when}: the stop saved {minutes(saved)} over waiting for that"
    return f"{when}, {minutes(-saved)} before the stop: the rule saved no time"


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
