"""A live warm-up test: a log followed as it grows, the monitor fed, its state kept for resuming.

:class:`WatchSession` is what a terminal, a notebook or a web page drives: it owns the
:class:`~mtident.io.follow.LogFollower`, the :class:`~mtident.thermal.monitor.MonitorState` and the
state file, and each :meth:`WatchSession.poll` returns the monitor's events to be shown;
:meth:`WatchSession.run` polls until the decision, the log's end or a timeout and yields what
happens as events, for a command, a page or a test to render. The
state file lives beside the log unless told otherwise; it records which log it belongs to (its
path and a fingerprint of its first bytes), so that a different log copied over the same path
starts afresh instead of resuming the old test's answer.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
import math
import os
import threading
import time
from collections.abc import Callable, Generator
from dataclasses import dataclass
from pathlib import Path
from typing import Literal

import numpy as np

from mtident._json import to_json_value
from mtident._typing import FloatArray
from mtident.exceptions import InputError, MtidentError
from mtident.io.follow import FollowPosition, LogFollower
from mtident.persist import StateFileError, load_dataclass, save_dataclass
from mtident.thermal.hindsight import Hindsight, check_decision
from mtident.thermal.monitor import (
    Event,
    MonitorSettings,
    MonitorState,
    check_every_sensor,
    expected_stop,
    minutes,
    monitor_step,
    new_state,
)
from mtident.thermal.monitor_answer import WatchAnswer, answer
from mtident.thermal.readings import coarse_room_step_C, coarse_room_warning, warming_room_warning
from mtident.thermal.reference import reference_for_log

__all__ = [
    "Ended",
    "FollowSettings",
    "Forecast",
    "Polled",
    "RecordTail",
    "SavedWatch",
    "SourceNote",
    "Waiting",
    "WatchEvent",
    "WatchSession",
    "Watching",
    "default_state_path",
    "log_fingerprint",
]

STATE_SUFFIX = ".watch-state.npz"
# the log's head that identifies it: its header and first rows
FINGERPRINT_BYTES = 4096
# rows fed to the monitor between two progress calls (a long replay's table moves on)
FEED_ROWS = 250
FIRST_FEED_ROWS = 25
# the room readings after which the room sensor's display step is judged
ROOM_STEP_READINGS = 30
# a watch that has seen no new row for this long says it is waiting, once (a finished log given
# without --replay otherwise waits in silence)
WAITING_HINT_S = 60.0


@dataclass(frozen=True, slots=True)
class FollowSettings:
    """How :meth:`WatchSession.run` follows the log.

    Attributes
    ----------
    replay : bool
        Feed what the log holds now, once, and end (a finished log replayed as if it arrived live).
    poll_s : float
        Seconds between two looks at a growing log.
    timeout_s : float or None
        End after this many seconds without a new row (None: wait until the decision).
    """

    replay: bool = False
    poll_s: float = 0.5
    timeout_s: float | None = None


@dataclass(frozen=True, slots=True)
class Watching:
    """The log's sensors are known (its header read, or a state resumed): said once.

    Attributes
    ----------
    sensors : tuple of str
        The sensors watched.
    """

    sensors: tuple[str, ...]


@dataclass(frozen=True, slots=True)
class Polled:
    """A poll ended, its rows recorded and fed to the monitor (its events yielded before this).

    Attributes
    ----------
    rows : int
        Rows the poll read (0: the log did not grow).
    stopped : bool
        Whether the test may now stop.
    """

    rows: int
    stopped: bool


@dataclass(frozen=True, slots=True)
class SourceNote:
    """What a network source's recorder says (a reconnection, a data item that appeared).

    Attributes
    ----------
    text : str
        The recorder's message, as the watch says it.
    """

    text: str


@dataclass(frozen=True, slots=True)
class Waiting:
    """No new row for ``idle_s`` seconds: said once, while the watch goes on waiting.

    Attributes
    ----------
    idle_s : float
        How long no new row came (s): ``WAITING_HINT_S``, when it is said.
    """

    idle_s: float


EndReason = Literal["stopped", "replayed", "timeout", "cancelled"]


@dataclass(frozen=True, slots=True)
class Ended:
    """The run ended: the test may stop, the replayed log was fed, no row came within the timeout,
    or the ``cancel`` asked (the state file then holds what a resume starts from).

    Attributes
    ----------
    reason : {"stopped", "replayed", "timeout", "cancelled"}
    idle_s : float
        Seconds since the last new row.
    """

    reason: EndReason
    idle_s: float


# what :meth:`WatchSession.run` yields: the monitor's events (checks, decisions, notes) and the run's own
WatchEvent = Event | Watching | Polled | SourceNote | Waiting | Ended


@dataclass(frozen=True)
class Forecast:
    """Each sensor's expected stop (:meth:`WatchSession.expected_stops`) and the state it was made
    of: its latest reading's time and its number of checks. Saved with the state, so that a
    resumed watch or a report of the same log answers from it instead of forecasting again (each
    sensor's forecast takes seconds).

    Attributes
    ----------
    latest_min : float
    checks : int
    stops : dict of str to float
    """

    latest_min: float
    checks: int
    stops: dict[str, float]

    def is_of(self, state: MonitorState) -> bool:
        """Whether this is the forecast of ``state``."""
        return self.latest_min == state.readings.latest_min and self.checks == len(state.timeline)


@dataclass(frozen=True)
class SavedWatch:
    """What the state file holds: which log and settings it belongs to, where the follower is,
    and the monitor's state.

    Attributes
    ----------
    log : str
        The log's absolute path.
    fingerprint : str
        The SHA-256 of the log's first bytes (:func:`log_fingerprint`).
    fingerprint_bytes : int
        How many bytes the fingerprint covers.
    settings_key : str
        The settings, the sensors and how the time column is read, as JSON text.
    position : FollowPosition
        The follower's position in the log.
    monitor : MonitorState
    log_warnings : tuple of str
        The warnings said so far of the log or the test as a whole (a coarse room sensor, the
        reference dropped): a resumed watch, and a report made from the state, say them too.
    forecast : Forecast or None
        The latest expected stops, where they were made.
    """

    log: str
    fingerprint: str
    fingerprint_bytes: int
    settings_key: str
    position: FollowPosition
    monitor: MonitorState
    log_warnings: tuple[str, ...] = ()
    forecast: Forecast | None = None


def default_state_path(log: Path) -> Path:
    """Beside the log (``LOG.watch-state.npz``), or in the current folder where the log's folder
    cannot be written (a logger's share mounted read-only).

    Parameters
    ----------
    log : Path
        The log (it need not exist yet).

    Returns
    -------
    Path
        The log's name with ``.watch-state.npz`` appended, in the log's folder, or in the
        current working folder (an absolute path) where the log's folder is not writable.
    """
    beside = log.with_name(log.name + STATE_SUFFIX)
    folder = log.parent if str(log.parent) else Path(".")
    return beside if os.access(folder, os.W_OK) else Path.cwd() / beside.name


def log_fingerprint(path: Path, length: int = FINGERPRINT_BYTES) -> tuple[str, int]:
    """The SHA-256 of the log's first ``length`` bytes (fewer if it is shorter), and how many.

    Parameters
    ----------
    path : Path
        The log.
    length : int
        Bytes to read from its start: its header and first rows.

    Returns
    -------
    digest : str
        The hexadecimal SHA-256 of the bytes read ("" where the file cannot be read).
    count : int
        How many bytes were read (0 where the file cannot be read).
    """
    try:
        with path.open("rb") as handle:
            head = handle.read(length)
    except OSError:
        return "", 0
    return hashlib.sha256(head).hexdigest(), len(head)


def _settings_key(
    settings: MonitorSettings,
    sensors: list[str] | None,
    time_col: str | None,
    time_unit: str | None,
    temperature_unit: str | None = None,
) -> str:
    """Everything that changes the answer, as text: a state saved with another key is not resumed."""
    fields = dataclasses.asdict(settings)
    if not settings.wait_for:
        del fields["wait_for"]  # waiting for every sensor, as before the option: such a state resumes
    if not settings.robust.heat_enters_at:
        del fields["robust"]["heat_enters_at"]  # as before the option: such a state resumes
    fields["reference"] = (
        None
        if settings.reference is None
        else {name: dataclasses.asdict(m) for name, m in settings.reference.sensors.items()}
    )
    options: dict[str, object] = {"settings": fields, "sensors": sensors, "time_col": time_col, "time_unit": time_unit}
    if temperature_unit is not None:  # the log's own units, as before the option: such a state resumes
        options["temperature_unit"] = temperature_unit
    return json.dumps(options, sort_keys=True, default=str)


class WatchSession:
    """A warm-up test followed live (or replayed) and decided by the monitor.

    Parameters
    ----------
    log : Path
        The CSV log a logger writes (it need not exist yet).
    settings : MonitorSettings
        The decision's settings; ``settings.room_sensor`` names the room's column, if any.
    sensors : list of str, optional
        The sensors to watch (default: every temperature column but the room's).
    time_col, time_unit : str, optional
        How to read the time column.
    temperature_unit : {"C", "F", "K"}, optional
        Unit of the temperature columns that state none of their own (default: °C).
    state_path : Path, optional
        The state file (default: beside the log, :func:`default_state_path`).
    persist : bool
        Write the state file after each poll (False: read it to start from, never write it, as a
        report of a log that a watch may still follow does).
    resume : bool
        Resume from the state file where it belongs to this log and these settings.
    shown_as : Path, optional
        The file the messages name, where ``log`` is a copy of it (an Excel workbook replayed as
        the CSV it holds; default: ``log``).
    sheet : str, optional
        The sheet of ``shown_as`` that ``log`` holds, where the workbook has several: titles name it.

    Attributes
    ----------
    notes : list of str
        What the session found on opening (a state resumed, or one not resumed and why).
    last_rows : int
        Rows read by the last poll.
    log_warnings : list of str
        The warnings said so far of the log or the test as a whole, each once (the answer's).
    cancelled : bool
        A poll ended early because its ``cancel`` asked (the state then holds the rows fed up to it).
    state : MonitorState or None
        The monitor's state; None before the log's header is read.
    state_path : Path
        The state file.
    """

    def __init__(
        self,
        log: Path,
        settings: MonitorSettings,
        *,
        sensors: list[str] | None = None,
        time_col: str | None = None,
        time_unit: str | None = None,
        temperature_unit: str | None = None,
        state_path: Path | None = None,
        resume: bool = True,
        persist: bool = True,
        shown_as: Path | None = None,
        sheet: str = "",
    ) -> None:
        self.path = Path(log)
        self.shown = Path(shown_as) if shown_as is not None else self.path
        self.sheet = sheet
        self.persist = persist
        self.settings = settings
        self.state_path = Path(state_path) if state_path is not None else default_state_path(self.path)
        self.notes: list[str] = []
        self.last_rows = 0
        self.cancelled = False
        self._room_step_said = self._room_warming_said = False
        self._forecast: Forecast | None = None
        self.log_warnings: list[str] = []
        room = settings.room_sensor
        self._asked = None if sensors is None else [*[n for n in sensors if n != room], *([room] if room else [])]
        self._key = _settings_key(settings, sensors, time_col, time_unit, temperature_unit)
        self._fingerprint: tuple[str, int] = ("", 0)
        self.state: MonitorState | None = None
        self._saved: MonitorState | None = None  # the state the state file holds (None: none written)
        self.follower = LogFollower(
            self.path,
            self._asked,
            time_col,
            time_unit,
            room=room,
            temperature_unit=temperature_unit,
            shown_as=shown_as,
        )
        if resume and self.state_path.is_file():
            self._resume(time_col, time_unit)

    # -- the state file --------------------------------------------------------------------

    def _resume(self, time_col: str | None, time_unit: str | None) -> None:
        try:
            saved = load_dataclass(self.state_path, SavedWatch)
        except StateFileError as exc:
            self.notes.append(
                f"the state file {self.state_path} cannot be resumed ({exc}); "
                + ("starting afresh" if self.persist else "the log is decided from its start")
            )
            return
        differs = []
        if saved.log != str(self.shown.resolve()):
            differs.append(f"another log ({saved.log})")
        elif log_fingerprint(self.path, saved.fingerprint_bytes)[0] != saved.fingerprint:
            differs.append("another log at the same path (its first lines differ)")
        if saved.settings_key != self._key:
            differs.append("other settings or sensors")
        if differs:
            afresh = (
                "starting afresh (it will be overwritten)"
                if self.persist
                else "the log is decided from its start (the file is left as it is)"
            )
            self.notes.append(f"the state file {self.state_path} was written for {' and '.join(differs)}; {afresh}")
            return
        self.follower = LogFollower.resume(
            self.path, saved.position, time_col, time_unit, self.follower.temperature_unit, shown_as=self.shown
        )
        self.state = self._saved = saved.monitor
        self.log_warnings = list(saved.log_warnings)
        self._forecast = saved.forecast
        self._fingerprint = (saved.fingerprint, saved.fingerprint_bytes)
        self.notes.append(f"resuming from {self.state_path} at t = {minutes(saved.monitor.readings.latest_min)}")

    def save(self, position_before: FollowPosition | None = None) -> None:
        """Write the state file (atomically: a killed process leaves the old or the new one).

        Parameters
        ----------
        position_before : FollowPosition, optional
            The follower's position to save (default: where it is now): a poll cut short saves the
            one of before it, with the state of the rows it fed.
        """
        if self.state is None:
            return
        if self._fingerprint[1] < FINGERPRINT_BYTES:
            # taken again while the log is short: a live log's head grows to its full length
            self._fingerprint = log_fingerprint(self.path)
        position = self.follower.position() if position_before is None else position_before
        save_dataclass(
            self.state_path,
            SavedWatch(
                str(self.shown.resolve()),
                *self._fingerprint,
                self._key,
                position,
                self.state,
                tuple(self.log_warnings),
                self._forecast,
            ),
        )
        self._saved = self.state

    def back_to_saved(self) -> None:
        """Take up again the state the state file holds (a poll interrupted mid-way, by Ctrl-C, fed
        rows it did not save): what is said and answered is then what a resume starts from."""
        if self.persist and self._saved is not None:
            self.state = self._saved

    # -- following ---------------------------------------------------------------------------

    @property
    def asked(self) -> list[str] | None:
        """The sensor columns asked for (the room sensor's last), None where every temperature column
        is read.

        Returns
        -------
        list of str or None
        """
        return None if self._asked is None else list(self._asked)

    @property
    def sensors(self) -> tuple[str, ...]:
        """The sensors watched (empty before the log's header is read).

        Returns
        -------
        tuple of str
        """
        return () if self.state is None else self.state.sensors

    @property
    def stopped(self) -> bool:
        """Whether the monitor has decided that the test may stop (False before the first reading).

        Returns
        -------
        bool
        """
        return self.state is not None and self.state.stopped

    def poll(
        self, progress: Callable[[WatchSession], None] | None = None, cancel: Callable[[], bool] | None = None
    ) -> list[Event]:
        """Read the rows added to the log since the last poll, feed them to the monitor and save.

        Parameters
        ----------
        progress : callable, optional
            Called with the session as soon as each of the monitor's checks ends and after every
            ``FEED_ROWS`` rows fed (to redraw a table or a page: a check's answer is shown then,
            not after the poll's later checks).
        cancel : callable, optional
            Asked between the monitor's checks (and their sensors): once it returns True the poll
            ends there, and the state file keeps the rows fed up to the last whole check, with the
            follower's position of before the poll (its rows up to that check are skipped when the
            same command resumes). :attr:`cancelled` then says so.

        Returns
        -------
        list of Event
            The follower's notes and warnings, then the monitor's events.

        Raises
        ------
        InputError
            The log has no sensor column besides the room sensor's, or the reference knows none of its sensors.
        """
        events = self._read(progress, cancel)
        self._keep_test_warnings(events)
        return events

    def _keep_test_warnings(self, events: list[Event]) -> None:
        """Keep the warnings said of the log or the test as a whole (a JSON reader, a report and a
        resumed watch see what the terminal said: they are saved with the state)."""
        for e in events:
            if e.kind == "warning" and e.sensor is None and e.text not in self.log_warnings:
                self.log_warnings.append(e.text)

    def _read(self, progress: Callable[[WatchSession], None] | None, cancel: Callable[[], bool] | None) -> list[Event]:
        """:meth:`poll`'s work: the follower's rows fed to the monitor, and what was said."""
        before = self.follower.position()
        rows = self.follower.poll()
        if self.state is not None and len(rows.time_min) and len(self.state.readings.time_min):
            # a poll cut short saved the follower's position of before it: its rows fed are skipped
            taken = rows.time_min > self.state.readings.latest_min
            if not taken.all():
                rows = dataclasses.replace(rows, time_min=rows.time_min[taken], temperature_C=rows.temperature_C[taken])
        self.last_rows = len(rows.time_min)
        events = [Event("note", np.nan, text) for text in rows.notes]
        events += [Event("warning", np.nan, text) for text in rows.warnings]
        created = False
        if self.state is None and self.follower.sensors:
            self.state, created = self._new_state(self.follower.sensors), True
        if self.state is not None and self.settings.reference is not None:
            # a resumed watch's settings are named again too: they are not saved with the state
            named, notes = reference_for_log(
                self.settings.reference, self.sensors, bool(self.settings.room_sensor), self.settings.room_sensor
            )
            self.settings = dataclasses.replace(self.settings, reference=named)
            if created:
                events.extend(Event("warning", np.nan, note) for note in notes)
        if self.state is None or not len(rows.time_min):
            return events
        values, room = (
            (rows.temperature_C[:, :-1], rows.temperature_C[:, -1])
            if self.settings.room_sensor
            else (rows.temperature_C, None)
        )
        # a first short part, so that a long replay's table and page show the test from its first checks
        bounds = [0, *range(FIRST_FEED_ROWS, len(rows.time_min), FEED_ROWS), len(rows.time_min)]

        def checked(state: MonitorState) -> None:
            self.state = state
            if progress is not None:
                progress(self)

        for start, stop in zip(bounds[:-1], bounds[1:], strict=True):
            part = slice(start, stop)
            self.state, said = monitor_step(
                self.state,
                rows.time_min[part],
                values[part],
                None if room is None else room[part],
                self.settings,
                cancel,
                checked,
            )
            events.extend(said)
            if cancel is not None and cancel():
                self.cancelled = True
                if self.persist:
                    self.save(before)
                # the rest of the rows are read again by the next poll (as by a resumed watch)
                time_col, time_unit = self.follower.time_col, self.follower.time_unit
                unit = self.follower.temperature_unit
                self.follower = LogFollower.resume(self.path, before, time_col, time_unit, unit, shown_as=self.shown)
                return events
            if progress is not None:
                progress(self)
        events.extend(self._coarse_room())
        events.extend(self._warming_room())
        self._keep_test_warnings(events)
        if self.persist:
            self.save()
        return events

    def catch_up(self, cancel: Callable[[], bool] | None = None) -> list[Event]:
        """Where the log ended before the test may stop, check every sensor on every reading
        (:func:`~mtident.thermal.monitor.check_every_sensor`) and save: the last answer is of the
        whole log, not of checks spaced out before its end.

        Parameters
        ----------
        cancel : callable, optional
            As :meth:`poll`: the checks are then left undone.

        Returns
        -------
        list of Event
        """
        if self.state is None or self.stopped:
            return []
        before = self.state
        self.state, events = check_every_sensor(self.state, self.settings, cancel)
        self._keep_test_warnings(events)  # the reference dropped at the log's end, say
        # the checks at the log's end are saved though they said nothing: a report or a resumed
        # watch of the same log then answers from them, not from the checks spaced out before
        if self.state is not before and self.persist:
            self.save()
        return events

    def _warming_room(self) -> list[Event]:
        """Once per session, a warning where the room sensor warms like a machine's sensor
        (:func:`~mtident.thermal.readings.warming_room_warning`), as soon as it has."""
        readings = None if self.state is None else self.state.readings
        if self._room_warming_said or readings is None or readings.room_C is None:
            return []
        text = warming_room_warning(readings.room_C, self.settings.room_sensor, readings.time_min)
        if text is None:
            return []
        self._room_warming_said = True
        return [Event("warning", np.nan, text)]

    def _coarse_room(self) -> list[Event]:
        """Once per session, a warning where the room sensor reads in coarse steps (as soon as its
        readings show the step)."""
        readings = None if self.state is None else self.state.readings
        if self._room_step_said or readings is None or readings.room_C is None:
            return []
        if np.count_nonzero(np.isfinite(readings.room_C)) < ROOM_STEP_READINGS:
            return []
        self._room_step_said = True
        step = coarse_room_step_C(readings.time_min, readings.room_C)
        if step <= 0:
            return []
        text = coarse_room_warning(step, "each T∞ carries up to half a step of it")
        return [Event("warning", np.nan, f"{self.settings.room_sensor}: {text}")]

    def run(
        self,
        follow: FollowSettings,
        progress: Callable[[WatchSession], None] | None = None,
        cancel: Callable[[], bool] | None = None,
        fetch: Callable[[], list[str]] | None = None,
    ) -> Generator[WatchEvent, None, None]:
        """Poll the log until the decision, the log's end (a replay), a timeout or ``cancel``,
        yielding what happens.

        Each poll yields the source's notes (:class:`SourceNote`), the follower's and the monitor's
        events (:class:`~mtident.thermal.monitor_types.Event`: checks, decisions, notes, warnings),
        :class:`Watching` once the sensors are known, then :class:`Polled`; the run ends with
        :class:`Ended`. An exception (Ctrl-C) takes up the saved state again before it goes on
        (:meth:`back_to_saved`), as does closing the run early.

        Parameters
        ----------
        follow : FollowSettings
            Replay or follow, how often to poll, and the timeout.
        progress : callable, optional
            Called with the session as each check ends, within a poll (:meth:`poll`).
        cancel : callable, optional
            Asked between checks and after each poll and wait: once it returns True the run ends
            there (a signal handler's flag; the state file keeps what a resume starts from).
        fetch : callable, optional
            Returns what a network source's recorder has to say since it was last asked.

        Yields
        ------
        Event, Watching, Polled, SourceNote, Waiting or Ended

        Raises
        ------
        InputError
            As :meth:`poll`.
        """
        cancelled = cancel if cancel is not None else (lambda: False)
        last_data = time.monotonic()
        said_watching = said_waiting = False
        try:
            while True:
                for note in fetch() if fetch is not None else []:
                    yield SourceNote(note)
                yield from self.poll(progress, cancel)
                if cancelled():  # at a safe point: the state file holds what the poll fed
                    yield Ended("cancelled", time.monotonic() - last_data)
                    return
                if not said_watching and self.state is not None:
                    said_watching = True
                    yield Watching(self.sensors)
                if self.last_rows:
                    last_data = time.monotonic()
                # idle as the poll found it: the time a caller takes over Polled (a page's
                # picture) is no time without data, and rows written meanwhile are read next
                idle_s = time.monotonic() - last_data
                if self.state is not None:
                    yield Polled(self.last_rows, self.stopped)
                if follow.replay and not self.stopped and (line := self.follower.unfinished_line()) is not None:
                    # a replayed log is whole: a last line without its end is a reading lost, said
                    text = (
                        f"{self.shown}: left out the last line, {line[:80]!r}: it has no line end (a log still being "
                        "written, or cut); the replay ends before it"
                    )
                    self.log_warnings.append(text)
                    latest = math.nan if self.state is None else self.state.readings.latest_min
                    yield Event("warning", latest, text)
                if self.stopped or follow.replay:
                    yield from self.catch_up(cancel)
                    yield Ended("stopped" if self.stopped else "replayed", idle_s)
                    return
                if follow.timeout_s is not None and idle_s > follow.timeout_s:
                    yield from self.catch_up(cancel)
                    yield Ended("timeout", idle_s)
                    return
                if not said_waiting and idle_s > WAITING_HINT_S:
                    said_waiting = True
                    yield Waiting(WAITING_HINT_S)
                time.sleep(follow.poll_s)
                if cancelled():
                    yield Ended("cancelled", time.monotonic() - last_data)
                    return
        except BaseException:
            # Ctrl-C mid-poll fed rows the state file does not hold (a KeyboardInterrupt, or the
            # SystemError of compiled code it landed in), or the run was closed early
            self.back_to_saved()
            raise

    def _new_state(self, columns: list[str]) -> MonitorState:
        room = self.settings.room_sensor
        watched = [name for name in columns if name != room]
        if not watched:
            msg = f"{self.shown}: no sensor column besides the room sensor {room!r}"
            raise InputError(msg)
        return new_state(watched, with_room=room is not None)

    def new_follower(self) -> LogFollower:
        """A follower of the same log, columns, time column and units, at the log's start (the
        session's own keeps its position for the state file).

        Returns
        -------
        LogFollower
        """
        follower = self.follower
        return LogFollower(
            self.path,
            self._asked,
            follower.time_col,
            follower.time_unit,
            room=self.settings.room_sensor,
            temperature_unit=follower.temperature_unit,
            shown_as=self.shown,
        )

    # -- answers -----------------------------------------------------------------------------

    @property
    def forecast_made(self) -> bool:
        """Whether the expected stops of the state as it is are made (saved with it, or made since)."""
        return self.state is not None and self._forecast is not None and self._forecast.is_of(self.state)

    def expected_stops(self, cancel: Callable[[], bool] | None = None) -> dict[str, float] | None:
        """Each sensor's expected stop on its best model's course (NaN: not foreseeable).

        Parameters
        ----------
        cancel : callable, optional
            Asked between two sensors' forecasts (each takes seconds): True stops the forecasts.

        Returns
        -------
        dict of str to float or None
            Per sensor, the expected stop (min); empty before the log's header is read; None
            where ``cancel`` stopped them.
        """
        state = self.state
        if state is None:
            return {}
        made = self._forecast
        if made is not None and made.is_of(state):
            return dict(made.stops)
        out = {}
        for s, name in enumerate(state.sensors):
            out[name] = expected_stop(state, self.settings, s, cancel=cancel)
            if cancel is not None and cancel():
                return None
        self._forecast = Forecast(state.readings.latest_min, len(state.timeline), out)
        if self.persist and self.state is state:
            self.save()
        return dict(out)

    def answer(self, with_forecast: bool = True, cancel: Callable[[], bool] | None = None) -> WatchAnswer:
        """The answer (:func:`~mtident.thermal.monitor_answer.answer`), its fields the JSON's keys.

        Parameters
        ----------
        with_forecast : bool, optional
            Add each sensor's expected stop while the test has not stopped (a forecast per sensor).
        cancel : callable, optional
            As :meth:`expected_stops`: the answer then has no expected stops.

        Returns
        -------
        WatchAnswer

        Raises
        ------
        InputError
            No data rows yet, or no log file.
        """
        if self.state is None:
            msg = f"{self.shown}: no data rows" if self.path.is_file() else f"{self.shown}: no such file"
            raise InputError(msg)
        expected = self.expected_stops(cancel) if with_forecast and not self.state.stopped else None
        said = answer(self.state, self.settings, expected)
        return dataclasses.replace(said, log_warnings=tuple(self.log_warnings)) if self.log_warnings else said

    def result(self, with_forecast: bool = True, cancel: Callable[[], bool] | None = None) -> dict[str, object]:
        """The JSON answer: :meth:`answer`'s fields.

        The parameters and what it raises are those of :meth:`answer`.

        Returns
        -------
        dict
        """
        tree: dict[str, object] = to_json_value(self.answer(with_forecast, cancel))
        return tree

    def hindsight(self, whole: tuple[FloatArray, FloatArray, FloatArray | None] | None = None) -> Hindsight | None:
        """The decision against where the log settled, for a log that runs on past the stop (read
        again whole, unless ``whole`` is :meth:`whole_log` already read); None before a decision
        or where the log ends at it.

        Parameters
        ----------
        whole : tuple of (ndarray, ndarray, ndarray or None), optional
            The whole log as :meth:`whole_log` returns it; default: read it again.

        Returns
        -------
        Hindsight or None
        """
        state = self.state
        if state is None or not state.stopped:
            return None
        time_min, values, room_C = self.whole_log() if whole is None else whole
        if not len(time_min) or time_min[-1] <= state.stop_time_min:
            return None
        steady = np.array([c.steady_C for c in state.checks])
        return check_decision(
            state.sensors,
            steady,
            state.stop_time_min,
            time_min,
            values,
            self.settings.tolerance_C,
            room_C,
            [c.modes for c in state.checks],
            self.settings.robust.max_time_constant_min,
            np.array([self.settings.waits_for(name) for name in state.sensors]),
            [c.room_gains for c in state.checks],
        )

    def whole_log(self) -> tuple[FloatArray, FloatArray, FloatArray | None]:
        """The watched sensors' readings (T, S) over the whole log, read again, and the room's
        (None without a room sensor); empty before the log's header is read.

        Returns
        -------
        time_min : ndarray, shape (T,)
            Sample times (min).
        values : ndarray, shape (T, S)
            The watched sensors' readings (°C, NaN: missing).
        room_C : ndarray, shape (T,) or None
            The room sensor's readings (°C).
        """
        return self.read_whole_log()[0]

    def read_whole_log(
        self,
    ) -> tuple[tuple[FloatArray, FloatArray, FloatArray | None], tuple[str, ...], tuple[str, ...]]:
        """:meth:`whole_log`, with the warnings and notes of reading it: a report made from a saved
        state has not read the log's first rows itself, and must still say a unit taken for want of
        one, a gap, readings left out.

        Returns
        -------
        tuple
            As :meth:`whole_log` returns it.
        warnings, notes : tuple of str
        """
        if self.state is None:
            return (np.empty(0), np.empty((0, 0)), None), (), ()
        room = self.settings.room_sensor
        columns = [*self.state.sensors, *([room] if room else [])]
        rows = LogFollower(
            self.path,
            columns,
            self.follower.time_col,
            self.follower.time_unit,
            room=room,
            temperature_unit=self.follower.temperature_unit,
            shown_as=self.shown,
        ).poll()
        if room:
            return (rows.time_min, rows.temperature_C[:, :-1], rows.temperature_C[:, -1]), rows.warnings, rows.notes
        return (rows.time_min, rows.temperature_C, None), rows.warnings, rows.notes


class RecordTail:
    """The log's newest readings, read on a thread of their own every ``period_s`` and handed to
    ``shown`` at once: the watch's thread reads the log only between its checks, whose fits take
    seconds (under load far more), and a page shows the record without waiting for them.

    It reads the log with a follower of its own (the session's keeps its position for the state
    file) and says nothing of what it reads: the session's follower says it.

    Parameters
    ----------
    session : WatchSession
        Whose log, sensors, time column and units are read.
    shown : callable
        Called on the tail's thread with the newest row's time (min from the log's first row) and
        each watched sensor's latest reading (°C; None: none yet), after each read that found rows.
    period_s : float
        Seconds between two reads.
    """

    def __init__(
        self, session: WatchSession, shown: Callable[[float, dict[str, float | None]], None], period_s: float
    ) -> None:
        self._follower = session.new_follower()
        self._room = session.settings.room_sensor
        self._shown = shown
        self._period_s = period_s
        self._latest: dict[str, float | None] = {}
        self._stop = threading.Event()
        self._thread = threading.Thread(target=self._run, name="mtident-record-tail", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop.is_set():
            try:
                self.read()
            except (MtidentError, OSError):
                return  # the session's follower meets the same and says it; the page then shows the monitor's
            self._stop.wait(self._period_s)

    def read(self) -> None:
        """Read the rows added since the last read, and show the newest (nothing where none were added)."""
        rows = self._follower.poll()
        if not len(rows.time_min):
            return
        columns = self._follower.sensors or []
        names = columns[:-1] if self._room else columns
        for s, name in enumerate(names):
            column = rows.temperature_C[:, s]
            finite = column[np.isfinite(column)]
            if len(finite):
                self._latest[name] = float(finite[-1])
            else:
                self._latest.setdefault(name, None)
        self._shown(float(rows.time_min[-1]), dict(self._latest))

    def close(self) -> None:
        """Stop reading."""
        self._stop.set()
        self._thread.join(timeout=5.0)
