"""The live monitor: when may a warm-up test stop?

The monitor is the engine's shape applied to a long-running test: a frozen
:class:`MonitorState` made of small sub-states (the readings, one :class:`SensorCheck` per
sensor, the decision), and one pure step,
``monitor_step(state, time_min, values, room_C, settings) -> (state, events)``, whose events
are records a terminal, a web page or a test renders or asserts on. Persistence is generated
from the dataclass fields (:mod:`mtident.persist`); resuming is loading a state.

The decision rests on the model-robust interval (:mod:`mtident.thermal.robust`): a sensor may
stop when every model the data cannot exclude (sums of up to four modes with time constants
up to the largest the machine may have, or within a reference run's boxes) puts T∞ within the
tolerance of the estimate, at the decision's level, at two checks in a row. The test may stop
when every sensor may. Checks come as the data come: every few per cent of the time since the
sensor's warm-up began, more seldom while the interval is far from the tolerance (re-fitting
every sample would change nothing but the cost). The expected stop is found by the same
readiness predicate run on the best model's continuation.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import TypedDict

import numpy as np

from mtident._json import fields_of
from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.thermal.machine_answer import combined_estimate, fit_readings, unmeasured_wander
from mtident.thermal.machine_model import MachineFit, MachineModel
from mtident.thermal.modes import Mode, model_curve
from mtident.thermal.monitor_answer import assumptions, failure_words, result, room_silent_words, silent_words
from mtident.thermal.monitor_types import (
    REPORT_LEVEL,
    STATUSES,
    TIMELINE_COLUMNS,
    Event,
    EventKind,
    MonitorSettings,
    MonitorState,
    Readings,
    SensorCheck,
    Status,
    last_valid,
    minutes,
    said_at,
    without_time,
)
from mtident.thermal.readings import frozen_words, sampling_interval_min, without_stuck
from mtident.thermal.reference import reference_for_log
from mtident.thermal.robust import estimate_sensor
from mtident.thermal.robust_types import SensorEstimate

__all__ = [
    "assumptions",
    "check_every_sensor",
    "expected_stop",
    "is_within",
    "monitor_step",
    "new_state",
    "result",
    "sensor_estimate",
]
# the types the monitor takes and gives (from monitor_types) are its names too: a caller imports the monitor alone
__all__ += [
    "Event",
    "EventKind",
    "MonitorSettings",
    "MonitorState",
    "Readings",
    "SensorCheck",
    "Status",
    "minutes",
    "said_at",
    "without_time",
]

# a check falls due this little before its time (min): 60 µs, far below any logging interval
_DUE_SLACK_MIN = 1e-6


# checks of a sensor far from the tolerance, or waiting for the others, come this many times
# ``check_spacing`` apart
_LONGEST_SHARE = 4.0


def new_state(sensors: tuple[str, ...] | list[str], with_room: bool = False) -> MonitorState:
    """A monitor before its first reading.

    Parameters
    ----------
    sensors : sequence of str
    with_room : bool
        Room readings will come with every row.

    Returns
    -------
    MonitorState

    Raises
    ------
    InputError
        No sensor names.
    """
    if isinstance(sensors, str):
        msg = f"sensors: expected a sequence of names, not one string (for one sensor: [{sensors!r}])"
        raise InputError(msg)
    names = tuple(sensors)
    if not names:
        msg = "sensors: expected at least one sensor name"
        raise InputError(msg)
    empty = Readings(np.empty(0), np.empty((0, len(names))), np.empty(0) if with_room else None)
    return MonitorState(names, empty, tuple(SensorCheck(name) for name in names))


def _validated(
    state: MonitorState, time_min: FloatArray, values: FloatArray, room_C: FloatArray | None
) -> tuple[FloatArray, FloatArray, FloatArray | None]:
    """The new readings as arrays of the right shapes, or an InputError naming what is wrong."""
    t = np.atleast_1d(np.asarray(time_min, dtype=float))
    y = np.asarray(values, dtype=float)
    y = y.reshape(len(t), -1) if y.ndim < 2 else y
    if y.shape != (len(t), len(state.sensors)):
        msg = (
            f"values: expected shape ({len(t)}, {len(state.sensors)}) for {len(t)} time(s) and the sensors "
            f"{', '.join(state.sensors)}; found {np.shape(values)}"
        )
        raise InputError(msg)
    if not np.all(np.isfinite(t)):
        msg = "time_min: expected finite minutes; found NaN or infinity"
        raise InputError(msg)
    previous = state.readings.latest_min
    if np.any(np.diff(t) <= 0) or (len(t) and math.isfinite(previous) and t[0] <= previous):
        msg = f"time_min: expected times increasing after t = {minutes(previous)}; found {t.tolist()[:5]}"
        raise InputError(msg)
    with_room = state.readings.room_C is not None
    if with_room != (room_C is not None):
        msg = "room_C: this monitor was started " + (
            "with a room sensor; give its readings"
            if with_room
            else "without a room sensor; give none, or start it with new_state(sensors, with_room=True)"
        )
        raise InputError(msg)
    room = None if room_C is None else np.atleast_1d(np.asarray(room_C, dtype=float))
    if room is not None and room.shape != t.shape:
        msg = f"room_C: expected {len(t)} readings, found {room.shape}"
        raise InputError(msg)
    return t, y, room


class _Cancelled(Exception):
    """A check given up half-way because the caller asked to stop (see ``cancel`` of :func:`monitor_step`)."""


def monitor_step(
    state: MonitorState,
    time_min: FloatArray,
    values: FloatArray,
    room_C: FloatArray | None,
    settings: MonitorSettings,
    cancel: Callable[[], bool] | None = None,
    checked: Callable[[MonitorState], None] | None = None,
) -> tuple[MonitorState, list[Event]]:
    """Take new readings, check each sensor when it falls due, and decide.

    The readings are taken up to each time a check falls due and the check is made there, so
    the answer does not depend on how the readings are batched: a replay fed all at once
    decides as the live test fed row by row.

    Parameters
    ----------
    state : MonitorState
    time_min : ndarray, shape (n,)
        Minutes since the log began, after every time seen so far.
    values : ndarray, shape (n, S)
        The sensors' readings (NaN: missing).
    room_C : ndarray, shape (n,), optional
        The room sensor's readings, for a monitor started with one.
    settings : MonitorSettings
    cancel : callable, optional
        Asked before each check and between its sensors; once it returns True the step ends there:
        the state returned has taken the readings up to its last whole check, as if only those had
        been given (its latest reading says how far it got), so a caller can save it and give the
        rest again later.
    checked : callable, optional
        Called with the state as soon as each check ends (its readings up to the check): a live
        page or table shows a check's answer then, not after the step's later checks.

    Returns
    -------
    MonitorState
    list of Event

    Raises
    ------
    InputError
        Readings of the wrong shape, or times not after those seen.
    """
    t, y, room = _validated(state, time_min, values, room_C)
    unknown = [name for name in settings.wait_for if name not in state.sensors]
    if unknown:
        msg = (
            f"the test cannot wait for {', '.join(map(repr, unknown))}: not among the sensors watched "
            f"({', '.join(state.sensors)})"
        )
        raise InputError(msg)
    settings.robust.unknown_heat_sensors(state.sensors)
    settings = _named_reference(settings, state.sensors, room is not None)
    events: list[Event] = []
    start = 0
    while start < len(t) and not state.stopped:
        if cancel is not None and cancel():
            break
        due = min(c.next_check_min for c in state.checks)
        end = start + int(np.searchsorted(t[start:], due, side="left")) + 1
        part = slice(start, min(end, len(t)))
        readings = state.readings.append(t[part], y[part], None if room is None else room[part])
        fed = replace(state, readings=readings)
        if readings.latest_min >= due:
            try:
                fed, said = _check_due(fed, settings, cancel)
            except _Cancelled:
                break  # the readings of this check are not taken: the state is as before them
            events.extend(said)
            fed = _with_warned(fed, said)
            if checked is not None:
                checked(fed)
        state = fed
        start = part.stop
    return state, events


def check_every_sensor(
    state: MonitorState, settings: MonitorSettings, cancel: Callable[[], bool] | None = None
) -> tuple[MonitorState, list[Event]]:
    """Check every sensor not yet checked at the latest reading: where a log ends (a replay, a
    timeout) before the test may stop, its answer stands on every reading, not on checks spaced
    out before it (a slow sensor's T∞ was last fitted 70 min before the log's end).

    Parameters
    ----------
    state : MonitorState
    settings : MonitorSettings
    cancel : callable, optional
        As :func:`monitor_step`: once it returns True the state is returned as it was.

    Returns
    -------
    MonitorState
    list of Event
        The checks' events, as :func:`monitor_step` gives them (a stop, where every sensor now may).
    """
    now = state.readings.latest_min
    if state.stopped or not len(state.readings.time_min) or all(c.checked_min >= now for c in state.checks):
        return state, []
    settings = _named_reference(settings, state.sensors, state.readings.room_C is not None)
    due = replace(state, checks=tuple(replace(c, next_check_min=min(c.next_check_min, now)) for c in state.checks))
    try:
        checked, events = _check_due(due, settings, cancel)
    except _Cancelled:
        return state, []
    return _with_warned(checked, events), events


def _named_reference(settings: MonitorSettings, sensors: tuple[str, ...], with_room: bool) -> MonitorSettings:
    """The settings with the reference as this log's sensors name it (one of another machine
    refused); the notes are the caller's to say, once."""
    if settings.reference is None:
        return settings
    reference, _ = reference_for_log(settings.reference, sensors, with_room)
    return replace(settings, reference=reference)


def _with_warned(state: MonitorState, events: list[Event]) -> MonitorState:
    """The state with the check's warnings of a sensor kept (an answer says them per sensor)."""
    warned = tuple(
        (e.sensor, said_at(e.time_min, e.text)) for e in events if e.kind == "warning" and e.sensor is not None
    )
    return replace(state, warned=state.warned + warned) if warned else state


def _check_due(
    state: MonitorState, settings: MonitorSettings, cancel: Callable[[], bool] | None = None
) -> tuple[MonitorState, list[Event]]:
    """Check the sensors due at the latest reading, and decide (``_Cancelled`` where ``cancel``
    asks to stop between two sensors)."""
    readings = state.readings
    now = readings.latest_min
    events: list[Event] = []
    said = set(state.said)
    checks = list(state.checks)
    dropped = state.reference_dropped
    used = replace(settings, reference=None) if dropped else settings
    # a stuck sensor's repeats say nothing of its temperature: its fits leave them out
    values, since, frozen = without_stuck(readings.time_min, readings.values_C)
    fitted = readings if values is readings.values_C else replace(readings, values_C=values)
    last, silent, stuck = _last_readings(readings, since)
    events.extend(_frozen_events(frozen, state.sensors, said, now))
    # every sensor fitted together once a check; the sensors checked take their part of it
    machine = machine_fit(fitted, state.sensors, used)
    if machine is not None and machine.contradicted:
        # the machine model is the reference's strongest claim: where most sensors reject it, the
        # per-sensor modes of the same run are not this machine's either
        why = f"is refused: its machine model is rejected by {len(machine.rejected)} of the sensors it knows"
        events.append(_reference_dropped(settings, now, why, machine.rejected))
        dropped, used, machine = True, replace(settings, reference=None), None
        checks = [replace(c, passes=0, ready_since_min=math.nan) for c in checks]
    wander = unmeasured_wander(_model_of(used), readings.room_C is not None, replace(used.robust, levels=used.levels))
    checked_now: set[int] = set()

    def check_sensor(s: int, since: SensorCheck | None = None) -> None:
        """Check sensor ``s``; its status's change is said against ``since`` (default: its check so far)."""
        if cancel is not None and cancel():
            raise _Cancelled
        checked_now.add(s)
        estimate = combined_estimate(sensor_estimate(fitted, s, state.sensors[s], used), machine, s, wander)
        before, checks[s] = (
            checks[s],
            _checked(checks[s], estimate, now, readings, used, (last[s], silent[s], stuck[s])),
        )
        said_against = before if since is None else since
        events.extend(_check_events(said_against, checks[s], estimate, said, now, settings.decision_level))

    waited = [s for s, name in enumerate(state.sensors) if settings.waits_for(name)]
    for s, check in enumerate(checks):
        # a sensor that has just fallen silent (or stuck) is checked at once, not at its next spaced check
        # (a 60-row gap was said 28 min after the sensor's last reading, a 20-row one never)
        newly = (silent[s] and check.status != "silent") or (stuck[s] and check.status != "stuck")
        if now >= check.next_check_min or (newly and check.checked_min < now):
            check_sensor(s)
        if (silent[s] or stuck[s]) and checks[s].may_stop and f"failed after: {checks[s].sensor}" not in said:
            # its answer stands on its readings before, but a failed sensor is said, never passed over
            said.add(f"failed after: {checks[s].sensor}")
            events.append(Event("warning", now, _failed_after_words(checks[s], stuck[s], last[s]), checks[s].sensor))
    contradicting, known = ([], 0) if dropped else _contradicting(checks, settings)
    if contradicting:
        # the sensors that follow it are the exception: a reference of another machine fits a few by chance
        dropped, used = True, replace(settings, reference=None)
        machine, wander = None, {}
        why = f"is contradicted by {len(contradicting)} of the {known} sensors it knows"
        # the checks on the reference said statuses the checks without it replace: a sensor said "off
        # reference" at the drop was recorded as "narrowing" (a new user's terminal and timeline disagreed)
        events[:] = [e for e in events if e.kind not in _STATUS_KINDS]
        events.append(_reference_dropped(settings, now, why, contradicting))
        checks = [replace(c, passes=0, ready_since_min=math.nan) for c in checks]
        for s in range(len(checks)):
            check_sensor(s, since=state.checks[s])
    if all(checks[s].may_stop for s in waited):
        # a sensor that may stop waits for the others at a longer spacing: before the test stops,
        # each is checked again on every reading so far
        for s in waited:
            if checks[s].checked_min < now:
                check_sensor(s)
    # T∞ is at the room's latest level: a silent room sensor leaves it unknown, and holds the test
    room_since = readings.room_silent_since()
    room_silent = math.isfinite(room_since)
    if room_silent and "room silent" not in said:
        said.add("room silent")
        events.append(Event("warning", now, room_silent_words(room_since, settings)))
    stop = now if all(checks[s].may_stop for s in waited) and not room_silent else math.nan
    if math.isfinite(stop):
        which = "every sensor's T∞ is" if len(waited) == len(checks) else "every sensor waited for has its T∞"
        events.append(
            Event(
                "stop",
                now,
                f"{which} within ±{settings.tolerance_C:g} °C at {settings.decision_level * 100:g} %: the "
                f"test can stop at t = {minutes(now)}",
            )
        )
    timeline = np.concatenate([state.timeline, _timeline_rows(checks, sorted(checked_now), now)])
    return MonitorState(
        state.sensors, readings, tuple(checks), stop, tuple(sorted(said)), dropped, state.warned, timeline
    ), events


_STATUS_KINDS = ("ready", "not ready", "check")
"""The kinds of event that say a sensor's status changed."""


def _timeline_rows(checks: Sequence[SensorCheck], checked: Sequence[int], now: float) -> FloatArray:
    """The rows of :attr:`MonitorState.timeline` of the sensors ``checked`` at ``now``: a sensor
    checked twice (a reference dropped between) once, as it ended."""
    return np.array(
        [
            (now, s, STATUSES.index(c.status), c.steady_C, c.low95_C, c.high95_C, c.low_C, c.high_C)
            for s in checked
            for c in (checks[s],)
        ],
        dtype=float,
    ).reshape(-1, len(TIMELINE_COLUMNS))


def _frozen_events(
    frozen: list[list[tuple[float, float]]], sensors: tuple[str, ...], said: set[str], now: float
) -> list[Event]:
    """A warning per sensor for each stretch of its readings that froze and moved on again
    (``frozen``, per sensor), once (``said`` keeps them): its fits leave the repeats out."""
    events = []
    for name, stretches in zip(sensors, frozen, strict=True):
        new = [(first, last) for first, last in stretches if f"frozen: {name}: {first:g}" not in said]
        if new:
            said.update(f"frozen: {name}: {first:g}" for first, _ in new)
            events.append(Event("warning", now, frozen_words(name, new), name))
    return events


def _failed_after_words(check: SensorCheck, stuck: bool, since_min: float) -> str:
    """What to say of a sensor that may stop and then fell silent or stuck."""
    return (
        f"{check.sensor}: {failure_words(stuck, since_min)}; it may stop on its readings before (T∞ "
        f"{check.steady_C:.2f} °C), which the decision keeps: check the sensor before the next test"
    )


def _reference_dropped(settings: MonitorSettings, now: float, why: str, sensors: Sequence[str]) -> Event:
    """The warning that the reference is used for no sensor from now on, and why."""
    assert settings.reference is not None
    # a room that moves and is not logged takes every sensor off a reference learnt with the room as
    # an input: the likeliest cause where the test names no room sensor
    unlogged = settings.room_sensor is None and settings.reference.room_measured
    room = (
        "a room that moved and that this test does not log (the reference was learnt with a room sensor: name "
        "the test's room column as the room sensor, `room_sensor`), "
        if unlogged
        else ""
    )
    return Event(
        "warning",
        now,
        f"the reference ({settings.reference.identity}) {why} ({', '.join(sensors)}): it is not used for any "
        f"sensor from now on ({room}another machine's reference, this machine changed since its run, or the test's "
        "times or temperatures in another unit than the reference run's; learn the reference again, or give the "
        "unit (`time_unit`, `temperature_unit`))",
    )


def _contradicting(checks: list[SensorCheck], settings: MonitorSettings) -> tuple[list[str], int]:
    """The sensors that contradict the reference, where they are most of the two or more checked
    sensors it has trusted modes for (each then answered without it), else none; and how many it
    has trusted modes for."""
    reference = settings.reference
    if reference is None:
        return [], 0
    known = [
        c
        for c in checks
        if math.isfinite(c.steady_C) and (modes := reference.modes(c.sensor)) is not None and modes.doubt is None
    ]
    off = [c.sensor for c in known if not c.reference_used]
    return (off if len(known) >= 2 and 2 * len(off) > len(known) else []), len(known)


def machine_fit(readings: Readings, sensors: tuple[str, ...], settings: MonitorSettings) -> MachineFit | None:
    """Every sensor's readings so far fitted together with the reference's machine model (None
    without one).

    Parameters
    ----------
    readings : Readings
    sensors : tuple of str
        The columns' names.
    settings : MonitorSettings

    Returns
    -------
    MachineFit or None
    """
    return fit_readings(
        _model_of(settings), sensors, readings.time_min, readings.values_C, readings.room_C, settings.levels
    )


def _model_of(settings: MonitorSettings) -> MachineModel | None:
    return None if settings.reference is None else settings.reference.machine_model


def sensor_estimate(
    readings: Readings, s: int, sensor: str, settings: MonitorSettings, noise_C: float | None = None
) -> SensorEstimate:
    """The model-robust estimate of sensor ``s`` from every reading so far (its intervals refined
    where they may be within the tolerance; elsewhere the search grid's, already too wide).

    Parameters
    ----------
    readings : Readings
        Times (N,) in min, the sensors' readings (N, S) in °C and the room's (N,) where measured.
    s : int
        The sensor's column in ``readings.values_C``.
    sensor : str
        Its name: picks its modes from ``settings.reference``, and names it in the messages.
    settings : MonitorSettings
        The intervals come at the report's level (95 %) and ``settings.decision_level``.
    noise_C : float, optional
        The readings' noise (°C, per reading), if known (default: estimated from the readings).

    Returns
    -------
    SensorEstimate
    """
    reference = None if settings.reference is None else settings.reference.modes(sensor)
    robust = replace(settings.robust, levels=settings.levels)
    return estimate_sensor(
        sensor,
        readings.time_min,
        readings.values_C[:, s],
        readings.room_C,
        robust,
        reference,
        noise_C,
        refine_within=settings.tolerance_C,
    )


def is_within(estimate: SensorEstimate, settings: MonitorSettings) -> bool:
    """The readiness predicate, shared by the decision and the forecast: a trusted model whose
    interval at the decision's level lies within the tolerance of T∞.

    Parameters
    ----------
    estimate : SensorEstimate
        From :func:`sensor_estimate`.
    settings : MonitorSettings
        ``tolerance_C`` (°C) and ``decision_level``.

    Returns
    -------
    bool
        True where the estimate has a fit, its model is not contradicted by the data
        (``model_ok``), its readings resolve the tolerance (their display step is finer), and
        both ends of its interval at the decision's level lie within ``tolerance_C`` of T∞. One
        check only: a sensor may stop after ``consecutive_checks`` in a row.
    """
    return (
        estimate.fit is not None
        and estimate.model_ok
        and resolves_tolerance(estimate, settings)
        and estimate.half_width(settings.decision_level) <= settings.tolerance_C
    )


def resolves_tolerance(estimate: SensorEstimate, settings: MonitorSettings) -> bool:
    """Whether the readings come in steps finer than the tolerance. Rounding to a step as coarse
    as the tolerance, with too little noise to dither it, can bias T∞ by half a step wherever the
    curve flattens within one step, and no interval from the readings shows it.

    Parameters
    ----------
    estimate : SensorEstimate
    settings : MonitorSettings

    Returns
    -------
    bool
    """
    return estimate.display_step_C < settings.tolerance_C


class _EstimateKeys(TypedDict):
    """What a check repeats of its estimate, under the same names."""

    noise_C: float
    rise_C: float
    model_ok: bool
    reference_used: bool
    machine_used: bool
    warnings: tuple[str, ...]
    room_lag_C: float


def _checked(
    check: SensorCheck,
    estimate: SensorEstimate,
    now: float,
    readings: Readings,
    settings: MonitorSettings,
    latest: tuple[float, bool, bool],
) -> SensorCheck:
    """The sensor's check after ``estimate``: its numbers, its run of passes, when to look again.
    ``latest``: the time of its latest valid (for a stuck sensor: first repeated) reading and
    whether it is silent or stuck (:func:`_last_readings`). A check gains a pass only with a new
    reading of the sensor since its last check; a silent or stuck sensor says so in its status."""
    last, silent, stuck = latest
    within = is_within(estimate, settings)
    # a pass needs a reading since the last check: the same readings checked again are no new evidence
    fresh = not math.isfinite(check.checked_min) or last > check.checked_min
    passes = (check.passes + int(fresh)) if within else 0
    ready = passes >= settings.consecutive_checks
    fit = estimate.fit
    status = _status(estimate, within, ready) if resolves_tolerance(estimate, settings) else "too coarse"
    if (silent or stuck) and not ready and estimate.fit is not None:
        status = "silent" if silent else "stuck"
    lo95, hi95 = estimate.interval_C.get(REPORT_LEVEL, (-math.inf, math.inf))
    lo, hi = estimate.interval_C.get(settings.decision_level, (-math.inf, math.inf))
    return SensorCheck(
        sensor=check.sensor,
        status=status,
        checked_min=now,
        next_check_min=_next_check(now, estimate, passes, readings, settings),
        passes=passes,
        ready_since_min=(check.ready_since_min if check.may_stop else now) if ready else math.nan,
        steady_C=estimate.steady_C,
        low95_C=lo95,
        high95_C=hi95,
        low_C=lo,
        high_C=hi,
        equilibrium_time_min=math.nan if fit is None else fit.equilibrium_time_min,
        # where its modes begin: its own warm-up's start, or the machine's where the machine model answers
        origin_min=estimate.onset_min if fit is None else fit.origin_min,
        modes=() if fit is None else tuple((m.time_constant_min, m.amplitude_C) for m in fit.modes),
        **fields_of(estimate, _EstimateKeys),
        ends=estimate.what_sets_the_ends(settings.decision_level)
        if resolves_tolerance(estimate, settings)
        else f"its readings come in steps of {estimate.display_step_C:.3g} °C, no finer than the tolerance",
        room_level_C=math.nan if fit is None or fit.room_level_C is None else fit.room_level_C,
        room_gains=() if fit is None else fit.room_gains,
        last_reading_min=last,
    )


def _last_readings(readings: Readings, stuck_since: list[float]) -> tuple[list[float], list[bool], list[bool]]:
    """Per sensor, :func:`~mtident.thermal.monitor_types.last_valid` up to the latest reading of
    any sensor (where every sensor stops, the logger has, and nothing is said of one), and whether
    it is stuck (``stuck_since`` not NaN, :func:`~mtident.thermal.readings.without_stuck`; that time
    then stands for its latest reading: repeats are no new readings)."""
    finite = np.isfinite(readings.values_C)
    anyone = np.flatnonzero(finite.any(axis=1))
    latest = float(readings.time_min[anyone[-1]]) if len(anyone) else math.nan
    pairs = [last_valid(readings.time_min, column, latest) for column in finite.T]
    last = [at if math.isnan(s) else s for (at, _), s in zip(pairs, stuck_since, strict=True)]
    return last, [silent for _, silent in pairs], [not math.isnan(s) for s in stuck_since]


def _status(estimate: SensorEstimate, within: bool, ready: bool) -> Status:
    if estimate.fit is None:
        return (
            "no data" if estimate.status == "no data" else "no rise" if estimate.status == "no rise" else "collecting"
        )
    if ready:
        return "may stop"
    if within:
        return "confirming"
    if "reference-disagrees" in estimate.warning_codes:
        return "off reference"
    if "misfit" in estimate.warning_codes:
        return "misfit"
    return "undetermined" if "undetermined" in estimate.warning_codes else "narrowing"


def _next_check(
    now: float, estimate: SensorEstimate, passes: int, readings: Readings, settings: MonitorSettings
) -> float:
    """When to check the sensor again: after the next reading while it confirms a first pass; else
    after a share of the time since its warm-up began, which grows with how far its interval is
    from the tolerance (a sensor that may stop, waiting for the others, at the longest share: the
    test stops only after a check of every sensor on every reading so far).
    A reading within ``_DUE_SLACK_MIN`` before that counts as at it: the next reading lies one
    step on, and the same log's times read from a file and followed live differ in their last
    bits, which decided whether that reading was due."""
    step = sampling_interval_min(readings.time_min)
    if estimate.fit is None or 0 < passes < settings.consecutive_checks:
        wait = step
    elif passes:
        wait = max(step, settings.check_spacing * _LONGEST_SHARE * (now - estimate.onset_min))
    else:
        ratio = estimate.half_width(settings.decision_level) / settings.tolerance_C
        factor = 1.0 if ratio <= 1.5 else 2.0 if ratio <= 5.0 else _LONGEST_SHARE
        wait = max(step, settings.check_spacing * factor * (now - estimate.onset_min))
    return now + wait - _DUE_SLACK_MIN


def _check_events(
    before: SensorCheck, after: SensorCheck, estimate: SensorEstimate, said: set[str], now: float, level: float
) -> list[Event]:
    """What a check has to say: a status that changed, and each kind of warning once."""
    events = []
    for code, text in zip(estimate.warning_codes, estimate.warnings, strict=True):
        key = f"{after.sensor}:{code}"
        if key not in said and code not in ("undetermined", "too-few-readings", "no-rise"):
            said.add(key)
            events.append(Event("warning", now, text, after.sensor))
    if after.status in ("silent", "stuck") and before.status != after.status:
        events.append(Event("warning", now, silent_words(after), after.sensor))
    elif after.status != before.status:
        kind: EventKind = "ready" if after.may_stop else "not ready" if before.may_stop else "check"
        bounded = math.isfinite(after.low_C) and math.isfinite(after.high_C)
        text = (
            f"{after.sensor}: {after.status}, T∞ {after.steady_C:.2f} °C, "
            + (
                f"{level * 100:g} % interval {after.low_C:.2f} to {after.high_C:.2f} °C"
                if bounded
                else "interval not yet bounded"
            )
            if math.isfinite(after.steady_C)
            else f"{after.sensor}: {after.status}"
        )
        events.append(Event(kind, now, text, after.sensor))
    return events


def expected_stop(
    state: MonitorState,
    settings: MonitorSettings,
    s: int,
    horizon_min: float | None = None,
    cancel: Callable[[], bool] | None = None,
) -> float:
    """When sensor ``s`` is expected to pass the readiness predicate, if its best model's course
    goes on (its continuation taken as readings at the log's sampling interval, with the noise
    it has now); NaN where not within ``horizon_min`` (default: 5 largest time constants).

    The forecast assumes the best model: a slower mode that the data cannot yet exclude, the very
    thing that keeps the interval wide, would move the stop later.

    Parameters
    ----------
    state : MonitorState
    settings : MonitorSettings
    s : int
        The sensor's index in ``state.sensors``.
    horizon_min : float, optional
        The latest time (min, on the log's clock) to look at; default: the latest reading plus
        5 × ``settings.robust.max_time_constant_min``.
    cancel : callable, optional
        Asked before each fit of the forecast (a second or more each): True ends it, NaN.

    Returns
    -------
    float
        The expected stop (min): the first of a set of candidate times, spaced geometrically
        (a factor 1.15) in the time since the warm-up began, at which the predicate holds. A
        sensor that may stop already gives the time it became ready. NaN where its status is
        not "narrowing" or "confirming" (no course to go on), or no candidate up to the horizon
        (39 at most) passes.
    """
    check = state.checks[s]
    if check.may_stop:
        return check.ready_since_min
    if not check.modes or not math.isfinite(check.steady_C) or check.status not in ("narrowing", "confirming"):
        return math.nan  # no course to go on: too few readings, T∞ undetermined, or a misfit
    readings = state.readings
    now = readings.latest_min
    step = sampling_interval_min(readings.time_min)
    horizon = now + 5.0 * settings.robust.max_time_constant_min if horizon_min is None else horizon_min
    modes = _as_modes(check.modes)
    steady = check.steady_C - (0.0 if math.isnan(check.room_level_C) else check.room_level_C)
    times = _candidate_times(now, horizon, check.origin_min)

    def ready_at(when: float) -> bool:
        if cancel is not None and cancel():
            raise _Cancelled
        future = np.arange(now + step, when + step / 2, step)
        if not len(future):
            return False
        continued = model_curve(modes, steady, check.origin_min, future)
        room = None if readings.room_C is None else np.full(len(future), readings.room_C[-1])
        if room is not None:
            continued = continued + room
        values = np.full((len(future), readings.values_C.shape[1]), np.nan)
        values[:, s] = continued
        extended = readings.append(future, values, room)
        return is_within(sensor_estimate(extended, s, check.sensor, settings, check.noise_C), settings)

    # the interval only narrows as the model's course goes on: the first ready time by bisection
    try:
        if not times or not ready_at(times[-1]):
            return math.nan
        low, high = -1, len(times) - 1
        while high - low > 1:
            middle = (low + high) // 2
            low, high = (low, middle) if ready_at(times[middle]) else (middle, high)
    except _Cancelled:
        return math.nan
    return float(times[high])


def _as_modes(pairs: tuple[tuple[float, float], ...]) -> tuple[Mode, ...]:
    return tuple(Mode(tau, amplitude) for tau, amplitude in pairs)


def _candidate_times(now: float, horizon: float, origin: float) -> list[float]:
    """Times to try the forecast at: geometric in the time since the warm-up began."""
    elapsed = max(now - origin, 1.0)
    out = []
    k = 1
    while origin + elapsed * 1.15**k <= horizon and k < 40:
        out.append(origin + elapsed * 1.15**k)
        k += 1
    return out
