"""A warm-up test written up for the customer: the machine and program, when the test began,
the verdict and, where the test could not stop, what holds it (a line per sensor), each
sensor's answer with its curve and band, the check against the rest of the log, the warnings,
what the answer assumes, the method and the software version.

:func:`build_report` runs the monitor over a finished or stopped log (resuming from the state
file ``watch`` left beside it, where it belongs to this log and these settings);
:func:`~mtident.report.report_render.write_html` writes one self-contained HTML page (the
figure embedded) and :func:`~mtident.report.report_render.write_pdf` an A4 PDF (the curves
laid out two to a row, on as few pages as they fill), both from the same :class:`WarmupReport`.
"""

from __future__ import annotations

import datetime as dt
import io
import json
import math
import re
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.axes import Axes
from matplotlib.figure import Figure

from mtident import __version__
from mtident.exceptions import InputError
from mtident.io.logs import log_name
from mtident.report.plots import plot_monitor, plot_timeline
from mtident.thermal.hindsight import Hindsight
from mtident.thermal.hindsight_words import no_level_words
from mtident.thermal.monitor import (
    Event,
    MonitorSettings,
    MonitorState,
    SensorCheck,
    assumptions,
    minutes,
    said_at,
    without_time,
)
from mtident.thermal.monitor_answer import WAYS_ON, SensorStatus, silent_words
from mtident.thermal.session import WatchSession

__all__ = [
    "SensorLine",
    "WarmupReport",
    "build_report",
    "log_start",
    "reading_gaps",
    "status_words",
]


@dataclass(frozen=True)
class SensorLine:
    """One sensor's row of the report (NaN where there is no value).

    Attributes
    ----------
    sensor : str
        The sensor column's name.
    latest_C : float
        The last valid reading the decision saw (°C): at the stop, or at the log's end.
    steady_C : float
        T∞, the estimated steady-state temperature (°C).
    ci95_C : tuple of float
        95 % interval of T∞ (°C), (low, high).
    slowest_time_constant_min : float
        Largest time constant of the fitted modes (min).
    equilibrium_time_min : float
        When the best model stays within 5 % of its total rise from T∞ (min from the log's start).
    status : str
        The monitor's status of the sensor ("may stop", "confirming", "narrowing", "no rise", ...).
    decision_interval_C : tuple of float
        The interval at the decision level that is compared with the tolerance (°C), (low, high).
    model_ok : bool
        The fit can be trusted: T∞ is determined and the residuals are not much more correlated than
        noise.
    settled_C : float
        Where the readings settled by the log's end (°C), NaN where they did not settle or the stop
        is not checked in hindsight.
    difference_C : float
        T∞ at the stop, moved with the room, less ``settled_C`` (°C).
    within_tolerance : bool or None
        ``difference_C`` is within the tolerance; None where nothing could be checked.
    settle_time_min : float
        When the readings came within the tolerance of where they settled, to stay (min), NaN where
        not known.
    settled_with_room : bool
        The readings keep following a moving room: ``settled_C`` is where their rise above the room,
        as the sensor follows it, settled, at the room's course at the log's end.
    """

    sensor: str
    latest_C: float
    steady_C: float
    ci95_C: tuple[float, float]
    slowest_time_constant_min: float
    equilibrium_time_min: float
    status: str
    decision_interval_C: tuple[float, float]
    model_ok: bool
    settled_C: float
    difference_C: float
    within_tolerance: bool | None
    settle_time_min: float = math.nan
    settled_with_room: bool = False

    @property
    def rate_per_min(self) -> float:
        """λ of the slowest mode, 1/τ (the papers' rate)."""
        return 1.0 / self.slowest_time_constant_min if self.slowest_time_constant_min > 0 else math.nan


@dataclass(frozen=True)
class Curves:
    """What the curves are drawn from: the monitor's state and settings, and the whole log.

    Attributes
    ----------
    state : MonitorState
    settings : MonitorSettings
    time_min : ndarray, shape (T,)
        The whole log's times (min), the readings after the stop among them.
    values_C : ndarray, shape (T, S)
        The whole log's readings (°C).
    """

    state: MonitorState
    settings: MonitorSettings
    time_min: np.ndarray
    values_C: np.ndarray


@dataclass(frozen=True)
class WarmupReport:
    """Everything a report shows, computed once and rendered as HTML or PDF.

    Attributes
    ----------
    source : str
        The log.
    machine, serial, program : str
        What the test is of, as far as known ("" where not): the machine from ``--machine`` or
        the reference run the decision used, its serial number and program from that reference.
    started : str or None
        t = 0 in local time, in words ("26 Nov 2026, 07:00"), None where nothing says when.
    started_from : str
        Where ``started`` comes from (the log's time stamps, the recorder's first reading), or
        why it is not known.
    test_date : str or None
        The test's day ("26 Nov 2026"), None where not known.
    room : str
        How the room entered the answer.
    samples, sampling_interval_min, log_end_min
        The log's readings: how many, how often, and the last one's time.
    gaps : tuple of (float, float)
        Stretches without readings longer than ``GAP_INTERVALS`` sampling intervals: (from, to), min.
    recorded_from : str or None
        Where a watch recorded the log from (an MTConnect agent's device, an OPC UA server's
        nodes), from the recorder's sidecar file; None for a logger's file.
    decision : str
        "stop" or "continue".
    tolerance_C, decision_level
        The decision's settings.
    stop_time_min : float
        The stop (NaN: no stop within the log).
    reason : str or None
        The monitor's own account of why the test could not stop (the command line's), where it could not.
    holding : tuple of str
        Why not yet, in plain words: one line per sensor that holds the test, what would settle it.
    ways_on : str or None
        What the user can do, where the test could not stop.
    lines : tuple of SensorLine
    warnings : tuple of str
    assumptions : str
    method : str
    hindsight : str or None
        The verdict of the check against the rest of the log, where the log runs on past the stop.
    settle_time_min : float
        When every waited-for sensor's readings had settled within the tolerance (NaN: not known).
    time_saved_min : float
        The settle time less the stop (NaN: not known).
    figure_png : bytes
        The curves (measured, the best model on, the T∞ intervals, the stop).
    version, created
        The software and when the report was made.
    curves : Curves or None
        What the PDF draws its curves from (as vectors, two to a row); None: it places ``figure_png``.
    timeline_png : bytes
        How each sensor's interval narrowed to the tolerance, check by check
        (:func:`~mtident.report.plots.plot_timeline`); empty where the state kept no checks.
    log_warnings, log_notes : tuple of str
        What reading the log said, as a watch says it: a unit taken for want of one, readings far
        outside a workshop's range, a reference of another machine (warnings); gaps, readings
        left out, units converted (notes).
    """

    source: str
    machine: str
    serial: str
    program: str
    started: str | None
    started_from: str
    test_date: str | None
    room: str
    samples: int
    sampling_interval_min: float
    log_end_min: float
    gaps: tuple[tuple[float, float], ...]
    recorded_from: str | None
    decision: str
    tolerance_C: float
    decision_level: float
    stop_time_min: float
    reason: str | None
    holding: tuple[str, ...]
    ways_on: str | None
    lines: tuple[SensorLine, ...]
    warnings: tuple[str, ...]
    assumptions: str
    method: str
    hindsight: str | None
    settle_time_min: float
    time_saved_min: float
    figure_png: bytes
    version: str
    created: str
    curves: Curves | None = field(default=None, repr=False, compare=False)
    timeline_png: bytes = field(default=b"", repr=False)
    log_warnings: tuple[str, ...] = ()
    log_notes: tuple[str, ...] = ()

    @property
    def title(self) -> str:
        """The report's title: the machine and its program, else the log's file name."""
        if not self.machine:
            return f"Warm-up test: {Path(self.source).name}"
        serial = f" (serial {self.serial})" if self.serial else ""
        # the program on record is the reference run's, not necessarily this test's: it is said in the setup
        return f"Warm-up test of {self.machine}{serial}"

    @property
    def subtitle(self) -> str:
        """The test's day and the log, under the title."""
        day = f"Test of {self.test_date} · " if self.test_date else ""
        return f"{day}log {Path(self.source).name}"

    @property
    def start_words(self) -> str:
        """What t = 0 is, in words."""
        if self.started is None:
            return f"the log's first reading ({self.started_from})"
        return f"{self.started} ({self.started_from})"

    def reworded(self, word: Callable[[str], str]) -> WarmupReport:
        """The report with each of its messages to the user (:data:`MESSAGE_FIELDS`) passed
        through ``word``: the command line says them with its options, not the library's
        parameters."""
        changed: dict[str, Any] = {name: _reworded(getattr(self, name), word) for name in MESSAGE_FIELDS}
        return replace(self, **changed)


#: The report's fields that are messages to the user, worded by the caller (:meth:`WarmupReport.reworded`)
MESSAGE_FIELDS = ("log_warnings", "log_notes", "warnings", "holding", "ways_on", "reason")


def _reworded(value: str | tuple[str, ...] | None, word: Callable[[str], str]) -> str | tuple[str, ...] | None:
    if value is None or isinstance(value, str):
        return value if value is None else word(value)
    return tuple(map(word, value))


# a stretch without readings longer than this many sampling intervals is said in the report
GAP_INTERVALS = 5.0
METHOD = (
    "Each sensor's readings from the start of its warm-up are fitted with sums of up to four exponential modes "
    "(six where the readings use all four; variable projection, a global search over the time constants). "
    "The interval of the steady-state "
    "temperature T∞ covers every such model the readings cannot exclude, up to the largest time constant "
    "assumed. A sensor may stop when its interval at the decision's confidence lies within the tolerance of its "
    "T∞ at two checks in a row; the test may stop when every sensor may."
)

# the monitor's statuses in words for the customer
_STATUS_WORDS = {
    "may stop": "ready: T∞ within the tolerance",
    "confirming": "within the tolerance, confirming",
    "narrowing": "still warming",
    "undetermined": "too early to tell",
    "collecting": "collecting readings",
    "no data": "no readings",
    "no rise": "no rise yet",
    "misfit": "readings do not follow the model",
    "off reference": "does not follow the reference run",
    "too coarse": "readings too coarse for the tolerance",
    "silent": "no new readings (a failed sensor or channel?)",
    "stuck": "the same reading over and over (a stuck sensor or channel?)",
}


def status_words(line: SensorLine) -> str:
    """A sensor's status for the customer (the monitor's word where there is none other), with a
    doubtful fit said.

    Parameters
    ----------
    line : SensorLine

    Returns
    -------
    str
    """
    words = _STATUS_WORDS.get(line.status, line.status)
    if not line.model_ok and line.status not in ("no data", "no rise", "misfit", "collecting"):
        words += "; fit doubtful"
    return words


def build_report(
    session: WatchSession,
    progress: Callable[[WatchSession], None] | None = None,
    machine: str | None = None,
) -> WarmupReport:
    """Run the session's monitor over the whole log and gather the report.

    Parameters
    ----------
    session : WatchSession
        The log and the decision's settings (resumed from its state file where it can be).
    progress : callable, optional
        Called with the session as readings are fed (for a progress display).
    machine : str, optional
        The machine the test is of (``--machine``); default: the reference run's, where the
        decision used one.

    Returns
    -------
    WarmupReport
    """
    said: list[Event] = []
    while True:
        said += session.poll(progress)
        if session.last_rows == 0:
            break
    # as a replayed watch answers: where the log ends before a stop, from every sensor checked on
    # every reading (not from checks spaced out before the end, which watch and report then differed by)
    said += session.catch_up()
    state = session.state
    if state is None:
        msg = f"{session.shown}: no data rows to report on"
        raise InputError(msg)
    settings = session.settings
    outcome = session.answer(with_forecast=False)
    # read whole again: what reading it says is the report's too, though a watch's state held its first rows
    whole, read_warnings, read_notes = session.read_whole_log()
    hindsight = session.hindsight(whole)
    time_min, values, _ = whole
    lines = tuple(
        _line(sensor, state.readings.values_C[:, s], hindsight, s) for s, sensor in enumerate(outcome.sensors)
    )
    of_log = [e for e in said if e.sensor is None]
    log_warnings = (*session.log_warnings, *read_warnings, *(e.text for e in of_log if e.kind == "warning"))
    log_notes = (*read_notes, *(e.text for e in of_log if e.kind == "note"))
    # a dropped reference: the answers rest on none, and what they assume says so, as watch's do
    resting_on = replace(settings, reference=None) if state.reference_dropped else settings
    said_assumed = assumptions(resting_on, state.sensors[0], state.readings.room_C is not None)
    assumed = (
        f"{said_assumed.model}, time constants up to {said_assumed.max_time_constant_min:g} min; "
        f"room {said_assumed.room}"
    )
    references: dict[str, list[str]] = {}
    for sensor in state.sensors:
        reference = assumptions(resting_on, sensor).reference
        if reference:
            references.setdefault(reference, []).append(sensor)
    for reference, named in references.items():
        whom = "every sensor" if len(named) == len(state.sensors) > 1 else ", ".join(named)
        assumed += f"; reference for {whom}: {reference}"
    if state.reference_dropped and settings.reference is not None:
        assumed += "; reference: not used (the test contradicted it; see the warnings)"
    # the reference names the machine where the decision rested on it (one most sensors contradicted may be another's)
    used = settings.reference if settings.reference is not None and not state.reference_dropped else None
    sidecar_words, recorder_start = _recorder(session.path)
    start = log_start(session.follower.position().time)
    started_from = "the log's time stamps"
    if start is None and recorder_start is not None:
        start, started_from = recorder_start, "the recorder's first reading"
    elif start is None:
        started_from = "the log has no time stamps"
    figure = plot_monitor(state, settings)
    if state.stopped:
        for s, ax in enumerate(figure.axes[: values.shape[1]]):
            draw_rest_of_log(ax, time_min, values[:, s], state.stop_time_min, legend=s == 0)
    stopped = state.stopped
    holding, ways = (
        ((), None) if stopped else _holding(state, settings, session.expected_stops() or {}, outcome.reason_lines)
    )
    settle = math.nan if hindsight is None else hindsight.test_settle_time_min
    saved = None if hindsight is None else hindsight.time_saved_min
    return WarmupReport(
        source=log_name(session.shown, session.sheet),
        machine=machine or (used.machine if used is not None else ""),
        serial=used.serial if used is not None and (not machine or machine == used.machine) else "",
        program=used.program if used is not None and (not machine or machine == used.machine) else "",
        started=None if start is None else _when(start),
        started_from=started_from,
        test_date=None if start is None or isinstance(start, dt.time) else _day(start),
        room=said_assumed.room,
        samples=len(time_min),
        sampling_interval_min=float(np.median(np.diff(time_min))) if len(time_min) > 1 else math.nan,
        log_end_min=float(time_min[-1]) if len(time_min) else math.nan,
        gaps=reading_gaps(time_min),
        recorded_from=sidecar_words,
        decision=outcome.decision,
        tolerance_C=settings.tolerance_C,
        decision_level=settings.decision_level,
        stop_time_min=state.stop_time_min if stopped else math.nan,
        reason=outcome.reason,
        holding=holding,
        ways_on=ways,
        lines=lines,
        warnings=_in_time_order(state, outcome.sensors),
        assumptions=assumed,
        method=METHOD,
        hindsight=None if hindsight is None else _hindsight_verdict(hindsight),
        settle_time_min=settle,
        time_saved_min=math.nan if saved is None else float(saved),
        figure_png=_png(figure),
        version=__version__,
        created=_when(dt.datetime.now().astimezone().replace(second=0, microsecond=0)),
        curves=Curves(state, settings, time_min, values),
        timeline_png=_png(plot_timeline(state, settings)) if len(state.timeline) else b"",
        log_warnings=tuple(dict.fromkeys(log_warnings)),
        log_notes=tuple(dict.fromkeys(log_notes)),
    )


# ---- when the test began -----------------------------------------------------------------------


def log_start(follower: Any) -> dt.datetime | dt.time | None:  # noqa: ANN401 - a TimeState
    """t = 0 by the log's own time stamps: a local clock's time as written (naive), an instant in
    the computer's local zone where the stamps carry their offset from UTC, the time of day alone
    where the log gives no date; None for a log timed in numbers from its start.

    Parameters
    ----------
    follower : TimeState
        How far the follower read the log's time column (its time origin and the stamps' format:
        :class:`~mtident.io.parse.TimeState`).

    Returns
    -------
    datetime, time or None
    """
    from mtident.io.stamps import TIME_OF_DAY_FORMATS, has_utc_offset

    origin = getattr(follower, "origin", None)
    if origin is None or not math.isfinite(origin):
        return None
    if getattr(follower, "serial_days", False):  # spreadsheet serial dates, read in minutes
        return _rounded(dt.datetime(1899, 12, 30) + dt.timedelta(minutes=origin))
    fmt = getattr(follower, "time_format", None)
    if fmt is None:
        return None
    when = dt.datetime(1970, 1, 1, tzinfo=dt.UTC) + dt.timedelta(minutes=origin)
    if fmt in TIME_OF_DAY_FORMATS:
        return _rounded(when.replace(tzinfo=None)).time()
    if has_utc_offset(getattr(follower, "first_stamp", None) or ""):
        return _rounded(when).astimezone()
    return _rounded(when.replace(tzinfo=None))


def _rounded(when: dt.datetime) -> dt.datetime:
    """To the second (minutes since 1970 in a float carry a few microseconds of rounding)."""
    return (when + dt.timedelta(microseconds=500_000)).replace(microsecond=0)


def _day(when: dt.datetime) -> str:
    return f"{when.day} {when:%b %Y}"


def _when(when: dt.datetime | dt.time) -> str:
    """A time in words: "26 Nov 2026, 07:00" (seconds where not zero, the zone where known)."""
    clock = f"{when:%H:%M}" + (f":{when:%S}" if when.second else "")
    if isinstance(when, dt.time):
        return f"{clock} (the log gives the time of day alone)"
    zone = f" {when.tzname()}" if when.tzinfo is not None and when.tzname() else ""
    return f"{_day(when)}, {clock}{zone}"


def _recorder(log: Path) -> tuple[str | None, dt.datetime | None]:
    """The source a watch recorded ``log`` from, in words, and its first reading's time in the
    computer's local zone, from its recorder's sidecar ((None, None) where there is none, or it
    cannot be read)."""
    from mtident.io import mtconnect, opcua

    for suffix, what in ((opcua.SIDECAR_SUFFIX, "nodes"), (mtconnect.SIDECAR_SUFFIX, "device")):
        sidecar = log.with_name(log.name + suffix)
        if not sidecar.is_file():
            continue
        try:
            saved = json.loads(sidecar.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None, None
        named = ", ".join(saved.get("nodes", [])) if what == "nodes" else str(saved.get("device") or "all devices")
        start = None
        try:
            start = _rounded(dt.datetime.fromisoformat(str(saved["origin"]))).astimezone()
        except (KeyError, TypeError, ValueError):
            pass
        return f"{saved.get('url')} ({what} {named})", start
    return None, None


# ---- why not yet ---------------------------------------------------------------------------------


def _holding(
    state: MonitorState, settings: MonitorSettings, expected: dict[str, float], reason: tuple[str, ...] | None
) -> tuple[tuple[str, ...], str]:
    """Why the test could not stop, a line per sensor that holds it, and the ways on: watch's
    (the last of its ``reason`` lines), so that the page and the terminal offer the same."""
    waiting = [c for c in state.checks if settings.waits_for(c.sensor) and not c.may_stop]
    if not waiting:
        return ("Every sensor is within the tolerance; the stop is confirmed at the next check.",), "continue the test"
    lines = [_holding_line(c, settings, expected.get(c.sensor, math.nan)) for c in waiting]
    last = reason[-1] if reason else ""
    ways = last.removeprefix(WAYS_ON).removesuffix(".") if last.startswith(WAYS_ON) else "continue the test"
    return tuple(lines), ways


def _holding_line(c: SensorCheck, settings: MonitorSettings, expected_min: float) -> str:
    tolerance = f"±{settings.tolerance_C:g} °C"
    level = f"{settings.decision_level * 100:g} %"
    if c.status in ("silent", "stuck"):
        return silent_words(c, "--wait-for") + "."
    if c.status == "no rise":
        return (
            f"{c.sensor}: has not risen above its noise yet. If the test does not heat it, leave it out (--sensor); "
            "if it reads the room, name it as the room sensor (--ambient)."
        )
    if not math.isfinite(c.steady_C):
        return f"{c.sensor}: {_STATUS_WORDS.get(c.status, c.status)}, no T∞ yet. Continue the test."
    if c.status == "too coarse":
        return (
            f"{c.sensor}: its readings step by more than the tolerance ({tolerance}), which can bias T∞ by half a "
            "step. Give a tolerance above the step."
        )
    if not c.model_ok and c.half_width_C <= settings.tolerance_C:
        return (
            f"{c.sensor}: T∞ {c.steady_C:.2f} °C is within {tolerance}, but its readings do not follow the model "
            "well (see the warnings). Continue the test."
        )
    span = (
        f"anywhere from {c.low_C:.2f} to {c.high_C:.2f} °C is still possible ({level})"
        if math.isfinite(c.low_C) and math.isfinite(c.high_C)
        else f"its range at {level} is not yet bounded"
    )
    slow = [float(m) for m in re.findall(r"about (\d+(?:\.\d+)?) min", c.ends)]
    cause = f": a slower warming (time constant about {max(slow):.0f} min) still fits the readings" if slow else ""
    # the expected stop: when T∞ would be known within the tolerance, not when the readings settle,
    # which may be long before (a new user's sensors were within 0.2 °C from 345 min; expected 793)
    known = (
        f" On its present course its T∞ would be known within {tolerance} by about t = {expected_min:.0f} min."
        if math.isfinite(expected_min)
        else " No stop is found on its best model's course (its interval does not come within the tolerance there)."
    )
    return f"{c.sensor}: T∞ {c.steady_C:.2f} °C, but {span}, wider than {tolerance}{cause}.{known}"


# ---- the pieces ----------------------------------------------------------------------------------


def draw_rest_of_log(ax: Axes, time_min: np.ndarray, values: np.ndarray, stop_min: float, legend: bool) -> None:
    """The readings after the stop, which the decision did not see."""
    after = time_min > stop_min
    if not after.any():
        return
    # beneath the model's course, which they are there to be compared with
    ax.plot(time_min[after], values[after], ".", ms=2.0, color="tab:blue", alpha=0.5, label="after the stop", zorder=1)
    shown = values[after][np.isfinite(values[after])]
    if len(shown):
        # the panel's scale was set by the readings up to the stop: the rest of the log must show too
        low, high = ax.get_ylim()
        margin = 0.05 * (high - low)
        ax.set_ylim(min(low, float(shown.min()) - margin), max(high, float(shown.max()) + margin))
    if legend:
        ax.legend(fontsize=7, loc="lower right")


def _finite(value: float) -> float:
    """NaN for a value that is not finite (an interval not yet bounded is shown as none)."""
    return value if math.isfinite(value) else math.nan


def _line(sensor: SensorStatus, readings: np.ndarray, hindsight: Hindsight | None, s: int) -> SensorLine:
    slowest = max((m.time_constant_min for m in sensor.modes), default=math.nan)
    valid = readings[np.isfinite(readings)]
    settled = difference = settle = math.nan
    within: bool | None = None
    with_room = hindsight is not None and bool(hindsight.checked[s] and hindsight.settled_with_room[s])
    if hindsight is not None and bool(hindsight.checked[s]):
        settled = float(hindsight.settled_C[s])
        difference = float(hindsight.error_C[s])
        within = bool(hindsight.within[s])
        if hindsight.settle_time_min is not None:
            settle = float(hindsight.settle_time_min[s])
    return SensorLine(
        sensor=sensor.sensor,
        latest_C=float(valid[-1]) if len(valid) else math.nan,
        steady_C=_finite(sensor.steady_state_C),
        ci95_C=(_finite(sensor.steady_state_ci95_C[0]), _finite(sensor.steady_state_ci95_C[1])),
        slowest_time_constant_min=float(slowest),
        equilibrium_time_min=_finite(sensor.equilibrium_time_min),
        status=sensor.status,
        decision_interval_C=(_finite(sensor.decision_interval_C[0]), _finite(sensor.decision_interval_C[1])),
        model_ok=sensor.model_ok,
        settled_C=settled,
        difference_C=difference,
        within_tolerance=within,
        settle_time_min=settle,
        settled_with_room=with_room,
    )


def _hindsight_verdict(hindsight: Hindsight) -> str:
    log_end_min = hindsight.log_end_min
    # a sensor that stuck before it settled has no level to check: said as its failure
    stuck = [
        f"{name} from {minutes(float(since))}"
        for name, since, known in zip(hindsight.sensors, hindsight.stuck_since, hindsight.checked, strict=True)
        if np.isfinite(since) and not known
    ]
    failed = f" Stuck at one value before settling (nothing to check): {', '.join(stuck)}." if stuck else ""
    verdict = hindsight.verdict_words()
    if not verdict:
        # as watch says it: which sensors the log ends before, by what rule, and which follow the room
        why = no_level_words(hindsight, hindsight.not_settled, bool(hindsight.following_room.any()), "")
        return f"The log runs on to {minutes(log_end_min)}. {why}: nothing to check T∞ against.{failed}"
    unsettled = hindsight.not_settled
    late = f"; not settled by the log's end: {', '.join(unsettled)}" if unsettled else ""
    return f"Against the rest of the log (to {minutes(log_end_min)}): {verdict}{late}.{failed}"


def _in_time_order(state: MonitorState, sensors: tuple[SensorStatus, ...]) -> tuple[str, ...]:
    """The sensors' warnings as the watch said them, each with its time, in the order said; then
    those of the latest checks not said so, with their checks' times (the report listed the
    latest check's first, without their times, and the earlier ones after them)."""
    said = [text for _, text in state.warned]
    bare = set(map(without_time, said))
    rest = sorted(
        (sensor.checked_at_min, w)
        for sensor in sensors
        for w in sensor.warnings
        if w not in bare and without_time(w) == w
    )
    return tuple(dict.fromkeys([*said, *(said_at(at, w) for at, w in rest)]))


def _png(figure: Figure) -> bytes:
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=110, bbox_inches="tight")
    return buffer.getvalue()


def reading_gaps(time_min: np.ndarray) -> tuple[tuple[float, float], ...]:
    """Stretches of the log without readings longer than ``GAP_INTERVALS`` times its usual
    sampling interval (a logger or a recorder stopped, a server away): (from, to) in minutes.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        The readings' times (min).

    Returns
    -------
    tuple of (float, float)
    """
    if len(time_min) < 3:
        return ()
    steps = np.diff(time_min)
    long = np.flatnonzero(steps > GAP_INTERVALS * float(np.median(steps)))
    return tuple((float(time_min[k]), float(time_min[k + 1])) for k in long)
