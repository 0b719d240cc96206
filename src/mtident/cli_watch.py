"""``mtident thermal watch``: follow a warm-up log and say when the test can stop.

A renderer over :class:`~mtident.thermal.session.WatchSession`: the session follows the log,
feeds the monitor and keeps the state file; this module turns its events and answers into lines,
tables, a picture and the JSON answer.
"""

from __future__ import annotations

import math
import re
import signal
import sys
import threading
import time
from collections.abc import Callable, Generator, Iterator, Mapping
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Any

import click
import numpy as np

from mtident._json import finite_or_none
from mtident.cli import (
    F,
    FiniteFloatRange,
    OptionConsole,
    OutputPath,
    carried_interrupt,
    number_option,
    stderr,
    thermal,
    user_errors,
)
from mtident.cli_logs import (
    LogRequest,
    asked_sensors,
    load_reference_file,
    log_options,
    log_path,
    log_request,
    named_column,
    named_columns,
    say_room_candidates,
    unread_rooms_of,
)
from mtident.cli_options import (
    ambient_option,
    file_option,
    free_fast_option,
    heat_enters_option,
    machine_option,
    max_time_constant_option,
    plot_option,
    reference_option,
)
from mtident.cli_sources import Recorder, network_recorder
from mtident.cli_watch_answer import print_answer, status_table
from mtident.exceptions import InputError
from mtident.io.logs import SAMPLES
from mtident.io.record import RecordingThread
from mtident.thermal.monitor import Event, MonitorSettings, minutes, said_at
from mtident.thermal.robust import RobustSettings
from mtident.thermal.session import (
    Ended,
    FollowSettings,
    Polled,
    RecordTail,
    SourceNote,
    Waiting,
    WatchEvent,
    Watching,
    WatchSession,
    default_state_path,
)
from mtident.thermal.timeline import write_timeline

if TYPE_CHECKING:
    from mtident.web import LivePage, Served

# events said on stderr as they come (a status change while narrowing is shown in the table)
_SAID = ("note", "warning", "ready", "not ready", "stop")
# the --plot picture is drawn again this often at most (s), and at the stop
_PLOT_S = 5.0
# a replay without a live table (a pipe, a file, --json) says how far it has read this often (s)
_PIPE_PROGRESS_S = 15.0


def decision_options(func: F) -> F:
    """The options of the stop decision, shared by watch and report: ``func``, the command's callback, with
    --tolerance, --confidence, --max-time-constant, --heat-enters-at, --reference, --machine, --free-fast-modes,
    --ambient, --room-wander and --wait-for (added as :func:`~mtident.cli_logs.log_options` adds a log's)."""
    options = [
        number_option(
            "--tolerance",
            "tolerance_C",
            default=0.2,
            help="A sensor may stop when every model the data allow puts T∞ within this of the estimate (°C).",
            min=0,
            min_open=True,
        ),
        number_option(
            "--confidence",
            "decision_level",
            default=0.99,
            help="Confidence level of the interval the decision uses.",
            min=0.5,
            max=0.999,
        ),
        max_time_constant_option,
        heat_enters_option,
        reference_option,
        machine_option,
        free_fast_option,
        ambient_option(
            "Room-temperature column: the room becomes an input of every mode's heat balance, so a drifting room "
            "does not fool the rule."
        ),
        number_option(
            "--room-wander",
            "room_wander",
            default=0.05,
            help="Without --ambient: how far the unmeasured room may wander in an hour (°C, 1σ of a random walk); 0 "
            "takes the room as steady.",
            min=0.0,
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


def state_file(file: str, path: Path, given: str | None, sheet: str | None = None) -> Path:
    """The state file: the one given, else beside the log (a workbook's sheet named: one of its
    own, ``LOG.SHEET.watch-state.npz``); for a shipped sample, in the current folder (not inside
    the installed package).

    Parameters
    ----------
    file : str
        FILE as given.
    path : Path
        The log.
    given : str or None
        The --state option.
    sheet : str or None, optional
        The --sheet option.

    Returns
    -------
    Path
    """
    if given:
        return Path(given)
    if sheet is not None:
        # each sheet of a workbook is a log of its own: one state file would be taken over by the other
        named = re.sub(r"[^\w.-]+", "_", sheet.strip())
        path = path.with_name(f"{path.name}.{named}")
    return Path.cwd() / default_state_path(path).name if file in SAMPLES else default_state_path(path)


def monitor_settings(options: Mapping[str, Any]) -> MonitorSettings:
    """The decision's settings, a :class:`MonitorSettings`, from the options of :func:`decision_options`
    read from the command's (a mapping by click's names).

    Raises
    ------
    InputError
        A reference file that cannot be read.
    """
    return MonitorSettings(
        tolerance_C=options["tolerance_C"],
        decision_level=options["decision_level"],
        robust=RobustSettings(
            max_time_constant_min=options["max_tau_min"],
            room_wander_C_per_h=options["room_wander"],
            free_fast_modes=options["free_fast_modes"],
            heat_enters_at=named_columns(options, "heat_enters_at", "--heat-enters-at"),
        ),
        reference=load_reference_file(options["reference_path"], options["machine"]),
        room_sensor=named_column(options["ambient_col"], options["file"], options["sheet"], "--ambient"),
        wait_for=named_columns(options, "wait_for", "--wait-for"),
    )


@dataclass(frozen=True, slots=True)
class SourceRequest:
    """A network source's options (:func:`~mtident.cli_sources.network_recorder`).

    Attributes
    ----------
    device : str or None
    nodes, items : tuple of str
    record_path : str or None
    from_buffer_start : bool
    """

    device: str | None
    nodes: tuple[str, ...]
    items: tuple[str, ...]
    record_path: str | None
    from_buffer_start: bool


@dataclass(frozen=True, slots=True)
class WatchRequest:
    """What ``thermal watch`` was asked, grouped (:func:`watch_request`).

    Attributes
    ----------
    log : LogRequest
    source : SourceRequest
    decision : MonitorSettings
    follow : FollowSettings
    resume : bool
        --resume.
    state_path : str or None
        --state.
    plot_path : str or None
        --plot.
    as_json : bool
        --json.
    serve_address : str or None
        --serve.
    exit_code : bool
        --exit-code.
    timeline_path : str or None
        --timeline.
    """

    log: LogRequest
    source: SourceRequest
    decision: MonitorSettings
    follow: FollowSettings
    resume: bool
    state_path: str | None
    plot_path: str | None
    as_json: bool
    serve_address: str | None
    exit_code: bool = False
    timeline_path: str | None = None


def watch_request(options: Mapping[str, Any]) -> WatchRequest:
    """The options of ``thermal watch`` (a mapping by click's names, their help the command's ``--help``),
    grouped into settings: a :class:`WatchRequest`.

    Raises
    ------
    InputError
        A reference file that cannot be read.
    """
    return WatchRequest(
        log=log_request(options),
        source=SourceRequest(
            options["device"], options["nodes"], options["items"], options["record_path"], options["from_buffer_start"]
        ),
        decision=monitor_settings(options),
        follow=FollowSettings(options["replay"], options["poll_s"], options["timeout_s"]),
        resume=options["resume"],
        state_path=options["state_path"],
        plot_path=options["plot_path"],
        as_json=options["as_json"],
        serve_address=options["serve_address"],
        exit_code=options["exit_code"],
        timeline_path=options["timeline_path"],
    )


UNDECIDED_EXIT = 3
"""``--exit-code``: the watch ended (the log ended, ``--timeout``) before the test may stop."""


@thermal.command("watch")
@log_options
@decision_options
@click.option(
    "--replay",
    is_flag=True,
    help="Run a finished log as if it arrived live, as fast as possible (afresh, unless --resume).",
)
@click.option("--resume", is_flag=True, help="With --replay: resume from the state file instead of starting afresh.")
@file_option("--state", "state_path", help="State file for resuming (default: beside the log, LOG.watch-state.npz).")
@number_option("--poll", "poll_s", default=0.5, help="Seconds between looks at a growing log.", min=0.05)
@click.option(
    "--timeout", "timeout_s", type=FiniteFloatRange(min=0), help="Give up after this many seconds without a new row."
)
@click.option(
    "--exit-code",
    "exit_code",
    is_flag=True,
    help=f"Exit with status {UNDECIDED_EXIT} where the watch ends (the log ended, --timeout) before the test may stop, "
    "so that `watch ... --exit-code && next-step` goes on only after a stop.",
)
@plot_option("Keep a picture (PNG; .svg or .pdf by the suffix) of measured and predicted curves up to date.")
@click.option(
    "--timeline",
    "timeline_path",
    type=OutputPath(),
    help="Keep a CSV of every check up to date: one row per sensor checked, with its status, T∞ and its 95 % and "
    "decision intervals (how the answer narrowed to the stop).",
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
def watch_command(**options: Any) -> None:
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
    **options
        The options by click's names, each with its help above (:func:`watch_request`).

    Raises
    ------
    InputError
        --replay of a missing log, a log without data rows, or a source's options that do not fit
        FILE.
    """
    watch(watch_request(options))


def watch(request: WatchRequest) -> None:
    """Run the watch a :class:`WatchRequest` asks for and render it.

    Parameters
    ----------
    request : WatchRequest

    Raises
    ------
    InputError
        As :func:`watch_command`.
    """
    file, follow = request.log.file, request.follow
    if request.resume and not follow.replay:
        stderr.print(
            "mtident: note: --resume is the default for a live log; it matters only with --replay", highlight=False
        )
    source = request.source
    recorder = network_recorder(
        file, source.device, source.nodes, source.items, source.record_path, source.from_buffer_start, follow.replay
    )
    path = log_path(file) if recorder is None else recorder.log
    if follow.replay and not path.is_file():
        msg = f"{path}: no such file"
        raise InputError(msg)
    sheet = request.log.sheet
    if sheet is not None and not follow.replay:
        msg = (
            f"--sheet {sheet}: a sheet of an Excel workbook is replayed (--replay); a live log is the CSV text a "
            "logger writes, which has no sheets"
        )
        raise InputError(msg)
    read, sheet_read, sheet_notes = workbook_as_replayed_csv(path, sheet) if follow.replay else (path, "", [])
    session = WatchSession(
        read,
        request.decision,
        sensors=asked_sensors(request.log.sensors, path, sheet) or None,
        time_col=request.log.time_col,
        time_unit=request.log.time_unit,
        temperature_unit=request.log.temperature_unit,
        state_path=state_file(str(path) if recorder else file, path, request.state_path, sheet),
        resume=request.resume or not follow.replay,
        shown_as=path,
        sheet=sheet_read,
    )
    for note in session.notes:
        stderr.print(f"mtident: {note}", highlight=False)
    for said in session.log_warnings:  # a resumed watch's, from its state file: its answer refers to them
        stderr.print(f"mtident: warning: (said before) {said}", highlight=False)
    for note in sheet_notes:  # the sheet a workbook's readings came from: the JSON answer carries it too
        if note not in session.log_warnings:  # a resumed watch has it from its state file, and said it above
            stderr.print(f"mtident: warning: {note}", highlight=False)
            session.log_warnings.append(note)
    if recorder is not None:
        stderr.print(f"mtident: recording {file} to {path}", highlight=False)
    elif not path.is_file():
        stderr.print(f"mtident: waiting for {path} to appear (the logger has not created it yet)", highlight=False)
    live = sys.stdout.isatty() and not request.as_json
    interrupted = _follow_served(session, path, request, live, recorder)
    if session.state is None or not len(session.state.readings.time_min):
        if interrupted:
            sys.exit(130)
        msg = (
            f"{path}: no data rows"
            + (" read (where rows were refused, the warnings above say why)" if session.state is not None else "")
            if path.is_file()
            else f"{path}: no such file (not created within the --timeout of {follow.timeout_s:g} s)"
        )
        raise InputError(msg)
    # a SIGTERM while the answer is written ends the command once it is written, with a word
    with _sigterm_deferred() as terminated:
        # the picture's readings after the stop and the replay's hindsight come from one read of the log
        whole = session.whole_log() if session.state.stopped and (request.plot_path or follow.replay) else None
        if request.plot_path:
            _plot(session, request.plot_path, whole)
        if request.timeline_path:
            write_timeline(session.state, request.timeline_path)
        # interrupted: the answer without the expected stops, whose forecasts take seconds
        print_answer(
            session,
            path,
            follow.replay,
            request.as_json,
            live=live and not follow.replay,
            forecast=not interrupted,
            cancel=terminated.is_set,
            whole=whole,
            interrupted=interrupted,
        )
    if terminated.is_set() and not interrupted:
        stderr.print(
            "mtident: terminated (SIGTERM) while the answer was written: it was written without the sensors' "
            f"expected stops, and the state is in {session.state_path}",
            highlight=False,
        )
    if interrupted or terminated.is_set():
        sys.exit(130)  # a shell's convention for SIGINT: the test was not decided here
    if session.state_path.is_file():
        resumes = "--resume continues from there" if follow.replay else "the same command resumes from there"
        stderr.print(f"mtident: the state is in {session.state_path}; {resumes} (--state: elsewhere)", highlight=False)
    if request.exit_code and not session.stopped:
        sys.exit(UNDECIDED_EXIT)


@contextmanager
def _sigterm_deferred() -> Iterator[threading.Event]:
    """SIGTERM noted, not acted on, within the block (on the main thread): the event is set if
    one came."""
    terminated = threading.Event()
    if threading.current_thread() is not threading.main_thread():
        yield terminated
        return
    previous = signal.signal(signal.SIGTERM, lambda signum, frame: terminated.set())
    try:
        yield terminated
    finally:
        signal.signal(signal.SIGTERM, previous)


def _follow_served(
    session: WatchSession, path: Path, request: WatchRequest, live: bool, recorder: Recorder | None
) -> bool:
    """:func:`_follow` with its surroundings: the live page served where ``--serve`` asks for one,
    SIGTERM taken as an interrupt (on the main thread), and a network source recorded on its own
    thread; each undone when the following ends.

    Parameters
    ----------
    session : WatchSession
    path : Path
        The log followed.
    request : WatchRequest
    live : bool
        Redraw the table in place (a terminal, not JSON).
    recorder : Recorder or None
        A network source that writes the log (None: a log file).

    Returns
    -------
    bool
        Whether the following was interrupted (Ctrl-C or SIGTERM).
    """
    page, served = _serve(request.serve_address, path)
    on_main = threading.current_thread() is threading.main_thread()
    _terminating.clear()
    _interrupting.clear()
    previous = signal.signal(signal.SIGTERM, _terminate) if on_main else None
    # a first Ctrl-C ends the watch at its next safe point, as SIGTERM does, so that what was read
    # is saved (one while it caught up on a long log saved nothing); a second one at once
    previous_int = signal.signal(signal.SIGINT, _interrupt) if on_main else None
    # the source is recorded on its own thread: its rows reach the log while the fits run
    recording = None if recorder is None else RecordingThread(recorder, request.follow.poll_s)
    try:
        fetch = None if recording is None else recording.fetch
        return _follow(session, path, request.follow, (request.plot_path, request.timeline_path), live, fetch, page)
    finally:
        if on_main:
            signal.signal(signal.SIGTERM, previous)
            signal.signal(signal.SIGINT, previous_int)
        if served is not None:
            served.stop()
        if recording is not None:
            recording.close()


def _follow(
    session: WatchSession,
    path: Path,
    follow: FollowSettings,
    kept: tuple[str | None, str | None],
    live: bool,
    fetch: Callable[[], list[str]] | None = None,
    page: LivePage | None = None,
) -> bool:
    """Render :meth:`WatchSession.run` until it ends; True if Ctrl-C or SIGTERM ended it (the
    state file then holds the last rows fed). A live log's newest readings reach the page from a
    thread of their own, while this one runs the checks. ``kept``: the --plot picture and the
    --timeline CSV kept up to date (None: not asked for)."""
    from rich.live import Live

    tail = None if page is None or follow.replay else RecordTail(session, page.record, follow.poll_s)
    run = None
    try:
        with Live(console=OptionConsole(), auto_refresh=False, transient=False) if live else _Nothing() as view:
            shown = _Shown(path, follow.timeout_s, kept, view if live else None, page, follow.replay)
            if page is not None and session.state is not None:
                shown.publish(session, forecast=False)  # a resumed state: at once
            run = session.run(follow, shown.progress, _terminating.is_set, fetch)
            for event in run:
                if isinstance(event, Ended) and event.reason == "cancelled":
                    return _say_interrupted(
                        KeyboardInterrupt() if _interrupting.is_set() else _Terminated(), session, follow.replay
                    )
                shown.show(session, event)
            return False
    except KeyboardInterrupt as stop:
        _close(run)  # a poll cut short fed rows the state file does not hold: the run takes up the saved state
        return _say_interrupted(stop, session, follow.replay)
    except SystemError as error:
        interrupt = carried_interrupt(error)
        if interrupt is None:
            raise
        _close(run)
        return _say_interrupted(interrupt, session, follow.replay)
    finally:
        if tail is not None:
            tail.close()


def _close(run: Generator[WatchEvent, None, None] | None) -> None:
    if run is not None:
        run.close()


class _Shown:
    """What a run shows as it goes: the table redrawn in place, the live page, the picture and the
    lines on stderr; the page's curves and the picture drawn at most so often, each costing a figure.

    Parameters
    ----------
    path : Path
        The log followed.
    timeout_s : float or None
        --timeout (s).
    kept : tuple of (str or None, str or None)
        --plot and --timeline.
    view : rich.live.Live or None
        Where the table is redrawn (None: not a terminal, or JSON).
    page : LivePage or None
        --serve's page.
    replay : bool
        --replay: without a table to redraw, a line says how far the replay has read every
        ``_PIPE_PROGRESS_S`` (a slow sensor's checks can take minutes without an event to say).
    """

    def __init__(
        self,
        path: Path,
        timeout_s: float | None,
        kept: tuple[str | None, str | None],
        view: Any,
        page: LivePage | None,
        replay: bool = False,
    ) -> None:
        self.path = path
        self.timeout_s = math.nan if timeout_s is None else timeout_s
        self.plot_path, self.timeline_path = kept
        self.view = view
        self.page = page
        self.replay = replay
        self.last_forecast = self.last_picture = self.last_plot = 0.0
        self.last_line = time.monotonic()
        self.rooms_said = False
        self.replay_said = False

    def say_rooms(self, session: WatchSession) -> None:
        """Once the sensors are known and before the checks' warnings (a replay's first poll holds
        them all): a column named as the room, watched as a machine sensor."""
        if not self.rooms_said and session.sensors:
            self.rooms_said = True
            if session.settings.room_sensor is None:
                # the followed file: a workbook's sheet is followed as the CSV it holds
                unread = unread_rooms_of(session.path, session.sensors) if session.asked is not None else []
                say_room_candidates(session.sensors, "watched as a machine sensor", unread=unread)

    def publish(self, session: WatchSession, forecast: bool = True, picture: bool = True) -> None:
        assert self.page is not None
        self.last_forecast = _publish(self.page, session, self.last_forecast, forecast, picture)

    def progress(self, session: WatchSession) -> None:
        """A check ended within a poll: the table and the page show its answer at once; the
        curves, which cost a picture, at most every ``_PAGE_PROGRESS_S``."""
        self.say_rooms(session)
        if self.view is not None:
            self.view.update(status_table(session, self.path), refresh=True)
        elif self.replay and session.state is not None and time.monotonic() - self.last_line > _PIPE_PROGRESS_S:
            self.last_line = time.monotonic()
            ready, count = sum(check.may_stop for check in session.state.checks), len(session.state.checks)
            # the checks' own lines come when the replay's read of the log ends, after these
            later = "" if self.replay_said else " (what each check said follows once the log is read)"
            self.replay_said = True
            stderr.print(
                f"mtident: replayed to t = {minutes(session.state.readings.latest_min)}; {ready} of {count} "
                f"sensor{'' if count == 1 else 's'} may stop{later}",
                highlight=False,
            )
        if self.page is not None:
            picture = time.monotonic() - self.last_picture > _PAGE_PROGRESS_S
            _publish(self.page, session, self.last_forecast, forecast=False, picture=picture)
            self.last_picture = time.monotonic() if picture else self.last_picture

    def show(self, session: WatchSession, event: WatchEvent) -> None:
        """Render one of the run's events."""
        if isinstance(event, Event):
            _say([event])
        elif isinstance(event, SourceNote):
            stderr.print(f"mtident: {event.text}", highlight=False)
        elif isinstance(event, Watching):
            self.say_rooms(session)
            if self.page is not None and self.page.version == 0:
                self.publish(session, forecast=False)
        elif isinstance(event, Polled):
            if self.page is not None and (event.rows or event.stopped):
                self.publish(session)
            # a replay's stop is drawn once the answer is written, from the log's one read after it
            drawn_after = self.replay and event.stopped
            if self.plot_path and not drawn_after and (time.monotonic() - self.last_plot > _PLOT_S or event.stopped):
                _plot(session, self.plot_path)
                self.last_plot = time.monotonic()
            if self.timeline_path and session.state is not None and event.rows:
                write_timeline(session.state, self.timeline_path)
        elif isinstance(event, Waiting):
            stderr.print(
                f"mtident: waiting for new rows: none for {event.idle_s:g} s (a finished log is replayed "
                "with --replay; Ctrl-C stops, and the same command resumes)",
                highlight=False,
            )
        elif event.reason == "timeout":
            stderr.print(
                f"mtident: no new row for {self.timeout_s:g} s; the watch ends here, before the test may stop",
                highlight=False,
            )


def _say_interrupted(stop: KeyboardInterrupt, session: WatchSession, replay: bool = False) -> bool:
    """Where the watch was stopped, and what it kept; True (interrupted). A replay resumes with
    --resume: the same command starts afresh, and overwrote the state it was told to resume from."""
    how = "terminated (SIGTERM)" if isinstance(stop, _Terminated) else "interrupted (Ctrl-C)"
    where = (
        "before the first sample"
        if session.state is None or not len(session.state.readings.time_min)
        else f"at t = {minutes(session.state.readings.latest_min)}"
    )
    kept = (
        f"the state is in {session.state_path}; "
        + ("the same command with --resume resumes from there" if replay else "the same command resumes from there")
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


# set by a first Ctrl-C: the watch ends as for SIGTERM, said as a Ctrl-C
_interrupting = threading.Event()


def _interrupt(signum: int, frame: object) -> None:  # noqa: ARG001
    if _interrupting.is_set() or _terminating.is_set():
        raise KeyboardInterrupt
    _interrupting.set()
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
        plot_monitor(state, session.settings).savefig(buffer, format="png", dpi=90)
        page.publish(shown, buffer.getvalue())
    return time.monotonic() if forecast else last_forecast


def _say(events: list[Event]) -> None:
    for event in events:
        if event.kind in _SAID:
            prefix = "warning: " if event.kind == "warning" else "note: " if event.kind == "note" else ""
            said = said_at(event.time_min, event.text) if math.isfinite(event.time_min) else event.text
            stderr.print(f"mtident: {prefix}{said}", highlight=False)


def _plot(
    session: WatchSession, plot_path: str, whole: tuple[np.ndarray, np.ndarray, np.ndarray | None] | None = None
) -> None:
    """The monitor's picture; ``whole``: the log already read again whole, else read here once stopped."""
    from mtident.report.plots import plot_monitor

    state = session.state
    assert state is not None
    after = None
    if state.stopped:
        # a replayed log runs on past the stop: the readings after it show how the answer held
        time_min, values, _ = session.whole_log() if whole is None else whole
        later = time_min > state.stop_time_min
        after = (time_min[later], values[later]) if later.any() else None
    plot_monitor(state, session.settings, plot_path, after=after)


class _Nothing:
    """A stand-in for rich.live.Live when there is no terminal to draw in."""

    def __enter__(self) -> _Nothing:
        return self

    def __exit__(self, *args: object) -> None:
        return None

    def update(self, *args: object, **kwargs: object) -> None:
        return None


def workbook_as_replayed_csv(path: Path, sheet: str | None = None) -> tuple[Path, str, list[str]]:
    """``path``, or for an Excel workbook the CSV its sheet holds (``sheet``, --sheet, else its first
    with a table), written to a temporary folder to be replayed
    (:func:`~mtident.io.log_file.workbook_as_csv`); the sheet read, where the workbook has several
    (else ""); and the reader's notes: which sheet of several was read. InputError for a sheet the
    workbook lacks, or one named for a CSV log."""
    import atexit
    import shutil
    import tempfile

    from mtident.io.dialect import binary_kind
    from mtident.io.log_file import no_sheets, workbook_as_csv

    with path.open("rb") as handle:
        if binary_kind(handle.read(8)) not in ("xlsx", "xls"):
            if sheet is not None:
                raise InputError(no_sheets(path, sheet))
            return path, "", []
    notes: list[str] = []
    name, data = workbook_as_csv(path, path, sheet, notes)
    folder = Path(tempfile.mkdtemp(prefix="mtident-"))
    atexit.register(shutil.rmtree, folder, ignore_errors=True)
    copy = folder / f"{path.stem}.csv"
    copy.write_bytes(data)
    return copy, name, notes
