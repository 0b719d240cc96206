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
from collections.abc import Callable
from dataclasses import dataclass, field, replace
from typing import Literal

import numpy as np

from mtident._json import finite_or_none
from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.thermal.machine_model import MachineFit, combined_estimate, machine_fit_of_window, unmeasured_wander
from mtident.thermal.modes import Mode, model_curve
from mtident.thermal.reference import MachineReference, reference_notes
from mtident.thermal.robust import (
    Assumptions,
    RobustSettings,
    SensorEstimate,
    describe_assumptions,
    estimate_sensor,
    room_wander_half_width,
    sampling_interval_min,
)

__all__ = [
    "Event",
    "EventKind",
    "MonitorSettings",
    "MonitorState",
    "Readings",
    "SensorCheck",
    "Status",
    "assumptions",
    "expected_stop",
    "is_within",
    "minutes",
    "monitor_step",
    "new_state",
    "result",
    "sensor_estimate",
]

# a sensor's status at its latest check, as a table and the JSON show it
Status = Literal[
    "collecting",
    "no data",
    "no rise",
    "undetermined",
    "narrowing",
    "confirming",
    "may stop",
    "misfit",
    "off reference",
    "too coarse",
]
# what an event of the monitor (and of a watch session) says
EventKind = Literal["check", "ready", "not ready", "stop", "warning", "note"]

# a check falls due this little before its time (min): 60 µs, far below any logging interval
_DUE_SLACK_MIN = 1e-6
# checks of a sensor far from the tolerance, or waiting for the others, come this many times
# ``check_spacing`` apart
_LONGEST_SHARE = 4.0

# the interval's level for the report and for the decision
REPORT_LEVEL = 0.95


@dataclass(frozen=True)
class MonitorSettings:
    """How the monitor decides.

    Parameters
    ----------
    tolerance_C : float
        A sensor may stop when every model the data allow puts T∞ within this of the estimate.
    decision_level : float
        Confidence level of the interval the decision uses.
    consecutive_checks : int
        Checks in a row that must find the interval within the tolerance.
    check_spacing : float
        Checks come every this fraction of the time since the sensor's warm-up began (more
        seldom while the interval is far from the tolerance).
    robust : RobustSettings
        The largest time constant and the room's wander.
    reference : MachineReference, optional
        A reference run of the same machine.
    room_sensor : str, optional
        The room sensor's name, where one is used.
    wait_for : tuple of str
        The sensors whose T∞ the test waits for (empty: every sensor watched); the others are
        checked and reported but do not hold the stop (a slow column sensor in a spindle test).

    Raises
    ------
    InputError
        A tolerance, level, number of checks, check spacing, largest time constant or room wander
        outside its range.
    """

    tolerance_C: float = 0.2
    decision_level: float = 0.99
    consecutive_checks: int = 2
    check_spacing: float = 0.025
    robust: RobustSettings = field(default_factory=RobustSettings)
    reference: MachineReference | None = None
    room_sensor: str | None = None
    wait_for: tuple[str, ...] = ()

    def waits_for(self, sensor: str) -> bool:
        """Whether the test waits for ``sensor`` (every sensor, unless ``wait_for`` names some).

        Parameters
        ----------
        sensor : str

        Returns
        -------
        bool
        """
        return not self.wait_for or sensor in self.wait_for

    def __post_init__(self) -> None:
        checks = [
            (
                "tolerance_C",
                self.tolerance_C,
                math.isfinite(self.tolerance_C) and self.tolerance_C > 0,
                "a positive number of °C",
            ),
            ("decision_level", self.decision_level, 0.5 < self.decision_level < 1.0, "a probability between 0.5 and 1"),
            ("consecutive_checks", self.consecutive_checks, self.consecutive_checks >= 1, "at least 1"),
            ("check_spacing", self.check_spacing, 0 < self.check_spacing <= 1, "a fraction in (0, 1]"),
            (
                "max_time_constant_min",
                self.robust.max_time_constant_min,
                math.isfinite(self.robust.max_time_constant_min) and self.robust.max_time_constant_min > 0,
                "a positive number of minutes",
            ),
            (
                "room_wander_C_per_h",
                self.robust.room_wander_C_per_h,
                math.isfinite(self.robust.room_wander_C_per_h) and self.robust.room_wander_C_per_h >= 0,
                "0 or more °C in an hour",
            ),
        ]
        for name, value, ok, expected in checks:
            if not ok:
                msg = f"{name}: expected {expected}, found {value!r}"
                raise InputError(msg)

    @property
    def levels(self) -> tuple[float, ...]:
        """The levels the intervals are computed at: the report's (95 %) and the decision's.

        Returns
        -------
        tuple of float
        """
        return (REPORT_LEVEL, self.decision_level)


@dataclass(frozen=True)
class Readings:
    """Every reading so far: times (N,), the sensors' readings (N, S) and the room's (N,).

    Attributes
    ----------
    time_min : ndarray, shape (N,)
        Minutes since the log began, increasing.
    values_C : ndarray, shape (N, S)
        The sensors' readings (°C, NaN: missing).
    room_C : ndarray, shape (N,), optional
        The room sensor's readings (°C); None without a room sensor.
    """

    time_min: FloatArray
    values_C: FloatArray
    room_C: FloatArray | None = None

    def append(self, time_min: FloatArray, values_C: FloatArray, room_C: FloatArray | None) -> Readings:
        """These readings with more after them.

        Parameters
        ----------
        time_min : ndarray, shape (n,)
            The new times (min), after the last one.
        values_C : ndarray, shape (n, S)
            The sensors' new readings (°C, NaN: missing).
        room_C : ndarray, shape (n,) or None
            The room's new readings (°C); None without a room sensor.

        Returns
        -------
        Readings
        """
        room = None if self.room_C is None or room_C is None else np.concatenate([self.room_C, room_C])
        return Readings(np.concatenate([self.time_min, time_min]), np.concatenate([self.values_C, values_C]), room)

    @property
    def latest_min(self) -> float:
        """The time of the last reading (NaN before the first).

        Returns
        -------
        float
            The time (min).
        """
        return float(self.time_min[-1]) if len(self.time_min) else math.nan


@dataclass(frozen=True)
class SensorCheck:
    """One sensor's latest check, in plain numbers (what a table or a page shows).

    ``passes`` counts the checks in a row that found the interval within the tolerance;
    ``status`` is one of "collecting", "no data", "no rise", "undetermined", "narrowing",
    "confirming", "may stop", "misfit", "off reference", "too coarse" (readings in steps no finer than the
    tolerance).

    Attributes
    ----------
    sensor : str
    status : Status
    checked_min : float
        When it was last checked (min), NaN before its first check.
    next_check_min : float
        When its next check falls due (min).
    passes : int
    ready_since_min : float
        The check from which it may stop (min), NaN while it may not.
    steady_C : float
        T∞ (°C), NaN without a fit.
    low95_C, high95_C : float
        T∞'s 95 % interval (°C), infinite without one.
    low_C, high_C : float
        T∞'s interval at the decision's level (°C), infinite without one.
    equilibrium_time_min : float
        When the best model stays within 5 % of its total rise from T∞ (min, from the log's start),
        NaN without a fit.
    origin_min : float
        Where its warm-up begins (min).
    modes : tuple of (float, float)
        The best model's modes: time constant (min) and amplitude (°C).
    noise_C : float
        The readings' noise (°C, per reading).
    rise_C : float
        How far it has moved from its first level (°C).
    model_ok : bool
        The data do not contradict the model, and T∞ is determined.
    reference_used : bool
        The reference run's time constants were used.
    machine_used : bool
        T∞ and its intervals come with the machine model's (every sensor fitted together).
    warnings : tuple of str
    ends : str
        In words, what sets the interval's ends (or why its readings are too coarse).
    room_level_C : float
        The room's last level (°C), NaN without a room sensor.
    room_gains : tuple of float
        The best model's gain on the room per mode (with a room sensor; its course as logged).
    """

    sensor: str
    status: Status = "collecting"
    checked_min: float = math.nan
    next_check_min: float = 0.0
    passes: int = 0
    ready_since_min: float = math.nan
    steady_C: float = math.nan
    low95_C: float = -math.inf
    high95_C: float = math.inf
    low_C: float = -math.inf
    high_C: float = math.inf
    equilibrium_time_min: float = math.nan
    origin_min: float = 0.0
    modes: tuple[tuple[float, float], ...] = ()
    noise_C: float = math.nan
    rise_C: float = 0.0
    model_ok: bool = False
    reference_used: bool = False
    machine_used: bool = False
    warnings: tuple[str, ...] = ()
    ends: str = ""
    room_level_C: float = math.nan
    room_gains: tuple[float, ...] = ()

    @property
    def half_width_C(self) -> float:
        """The larger distance from T∞ to an end of the decision's interval.

        Returns
        -------
        float
            The half-width (°C), infinite without T∞.
        """
        return (
            max(self.steady_C - self.low_C, self.high_C - self.steady_C) if math.isfinite(self.steady_C) else math.inf
        )

    @property
    def may_stop(self) -> bool:
        """Whether this sensor may stop (its status is "may stop").

        Returns
        -------
        bool
        """
        return self.status == "may stop"


@dataclass(frozen=True)
class MonitorState:
    """Everything the monitor knows: the readings, each sensor's latest check, the decision, and
    the warnings already said (each said once per sensor).

    Attributes
    ----------
    sensors : tuple of str
    readings : Readings
    checks : tuple of SensorCheck
        One per sensor, in the order of ``sensors``.
    stop_time_min : float
        When the test may stop (min), NaN until then.
    said : tuple of str
        The warnings already said, one entry per sensor and kind of warning.
    reference_dropped : bool
        Whether the reference was dropped for every sensor, most of those it knows having
        contradicted it (another machine's, or this one changed).
    """

    sensors: tuple[str, ...]
    readings: Readings
    checks: tuple[SensorCheck, ...]
    stop_time_min: float = math.nan
    said: tuple[str, ...] = ()
    reference_dropped: bool = False

    @property
    def stopped(self) -> bool:
        """Whether the test may stop (``stop_time_min`` is set).

        Returns
        -------
        bool
        """
        return math.isfinite(self.stop_time_min)

    def __repr__(self) -> str:
        # a notebook shows the decision, not the readings' arrays
        decision = f"stop at t = {minutes(self.stop_time_min)}" if self.stopped else "continue"
        statuses = ", ".join(f"{c.sensor} {c.status}" for c in self.checks)
        return (
            f"MonitorState({len(self.sensors)} sensor(s), t = {minutes(self.readings.latest_min)}, decision: "
            f"{decision}; {statuses})"
        )


@dataclass(frozen=True)
class Event:
    """Something the monitor has to say: ``kind`` is "check", "ready", "not ready", "stop",
    "warning" or "note".

    Attributes
    ----------
    kind : EventKind
    time_min : float
        When it was said (min, on the log's clock).
    text : str
        What to say.
    sensor : str or None
        The sensor it is about; None for the whole test.
    """

    kind: EventKind
    time_min: float
    text: str
    sensor: str | None = None


def minutes(value: float) -> str:
    """Minutes as a person reads them: whole where whole, else to 0.1 (or to the second below
    a minute).

    Parameters
    ----------
    value : float
        A time (min).

    Returns
    -------
    str
        With its unit: "12 min", "12.3 min", below a minute "30 s"; "—" for NaN or infinity.

    Examples
    --------
    >>> minutes(12.0), minutes(12.34), minutes(0.5), minutes(float("nan"))
    ('12 min', '12.3 min', '30 s', '—')
    """
    if not math.isfinite(value):
        return "—"
    if abs(value - round(value)) < 1e-6:
        return f"{round(value):d} min"
    return f"{value:.1f} min" if abs(value) >= 1 else f"{value * 60:.0f} s"


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
    if settings.reference is not None:
        reference_notes(settings.reference, state.sensors, room is not None)  # refuses one of another machine
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
        state = fed
        start = part.stop
    return state, events


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
    machine: dict[int, MachineFit | None] = {}

    def check_sensor(s: int) -> None:
        if cancel is not None and cancel():
            raise _Cancelled
        if id(used.reference) not in machine:
            machine[id(used.reference)] = machine_fit(readings, state.sensors, used)
        estimate = combined_estimate(
            sensor_estimate(readings, s, state.sensors[s], used),
            machine[id(used.reference)],
            s,
            unmeasured_wander(used.reference, readings.room_C is not None, replace(used.robust, levels=used.levels)),
        )
        before, checks[s] = checks[s], _checked(checks[s], estimate, now, readings, used)
        events.extend(_check_events(before, checks[s], estimate, said, now, settings.decision_level))

    waited = [s for s, name in enumerate(state.sensors) if settings.waits_for(name)]
    for s, check in enumerate(checks):
        if now >= check.next_check_min:
            check_sensor(s)
    contradicting, known = ([], 0) if dropped else _contradicting(checks, settings)
    if contradicting:
        # the sensors that follow it are the exception: a reference of another machine fits a few by chance
        dropped, used = True, replace(settings, reference=None)
        assert settings.reference is not None
        events.append(
            Event(
                "warning",
                now,
                f"the reference ({settings.reference.identity}) is contradicted by {len(contradicting)} of the "
                f"{known} sensors it knows ({', '.join(contradicting)}): it is not used for "
                "any sensor from now on (another machine's reference, or this machine changed since its run; learn "
                "the reference again)",
            )
        )
        checks = [replace(c, passes=0, ready_since_min=math.nan) for c in checks]
        for s in range(len(checks)):
            check_sensor(s)
    if all(checks[s].may_stop for s in waited):
        # a sensor that may stop waits for the others at a longer spacing: before the test stops,
        # each is checked again on every reading so far
        for s in waited:
            if checks[s].checked_min < now:
                check_sensor(s)
    stop = now if all(checks[s].may_stop for s in waited) else math.nan
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
    return MonitorState(state.sensors, readings, tuple(checks), stop, tuple(sorted(said)), dropped), events


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
    robust = replace(settings.robust, levels=settings.levels)
    return machine_fit_of_window(
        settings.reference, sensors, readings.time_min, readings.values_C, readings.room_C, robust
    )


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


def _checked(
    check: SensorCheck, estimate: SensorEstimate, now: float, readings: Readings, settings: MonitorSettings
) -> SensorCheck:
    """The sensor's check after ``estimate``: its numbers, its run of passes, when to look again."""
    within = is_within(estimate, settings)
    passes = check.passes + 1 if within else 0
    ready = passes >= settings.consecutive_checks
    fit = estimate.fit
    status = _status(estimate, within, ready) if resolves_tolerance(estimate, settings) else "too coarse"
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
        origin_min=estimate.onset_min,
        modes=() if fit is None else tuple((m.time_constant_min, m.amplitude_C) for m in fit.modes),
        noise_C=estimate.noise_C,
        rise_C=estimate.rise_C,
        model_ok=estimate.model_ok,
        reference_used=estimate.reference_used,
        machine_used=estimate.machine_used,
        warnings=estimate.warnings,
        ends=estimate.what_sets_the_ends(settings.decision_level)
        if resolves_tolerance(estimate, settings)
        else f"its readings come in steps of {estimate.display_step_C:.3g} °C, no finer than the tolerance",
        room_level_C=math.nan if fit is None or fit.room_level_C is None else fit.room_level_C,
        room_gains=() if fit is None else fit.room_gains,
    )


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
    if after.status != before.status:
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


def expected_stop(state: MonitorState, settings: MonitorSettings, s: int, horizon_min: float | None = None) -> float:
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
    if not times or not ready_at(times[-1]):
        return math.nan
    low, high = -1, len(times) - 1
    while high - low > 1:
        middle = (low + high) // 2
        low, high = (low, middle) if ready_at(times[middle]) else (middle, high)
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


def assumptions(settings: MonitorSettings, sensor: str, room_measured: bool = False) -> Assumptions:
    """What a sensor's interval rests on, as the answer says it.

    Parameters
    ----------
    settings : MonitorSettings
        The largest time constant, the room's wander or sensor, and the reference run.
    sensor : str
        The sensor whose reference modes, if any, are described.
    room_measured : bool
        The monitor is given the room's readings (named or not by ``settings.room_sensor``).

    Returns
    -------
    Assumptions
        The model, the largest time constant (min), how the room entered, and the reference.
    """
    return describe_assumptions(settings.robust, settings.room_sensor, settings.reference, sensor, room_measured)


def result(
    state: MonitorState, settings: MonitorSettings, expected: dict[str, float] | None = None
) -> dict[str, object]:
    """The JSON answer: the decision, the single-sensor keys of the sensor the test
    waits for (the slowest to equilibrium once stopped, the widest interval before), and per
    sensor its answer, verdict and assumptions; ``expected``: each sensor's expected stop, where
    the caller has it.

    Parameters
    ----------
    state : MonitorState
    settings : MonitorSettings
    expected : dict of str to float, optional

    Returns
    -------
    dict
    """
    if state.reference_dropped:
        settings = replace(settings, reference=None)  # the answers rest on no reference: their assumptions say so
    measured = state.readings.room_C is not None
    sensors = [
        _sensor_summary(c, settings, None if expected is None else expected.get(c.sensor), measured)
        for c in state.checks
    ]
    stopped = state.stopped
    waited = [c for c in state.checks if settings.waits_for(c.sensor)]
    if stopped:
        key = max(waited, key=lambda c: c.equilibrium_time_min if math.isfinite(c.equilibrium_time_min) else -math.inf)
    else:
        key = max(waited, key=lambda c: c.half_width_C)
    lead = sensors[state.checks.index(key)]
    out: dict[str, object] = {
        k: lead[k]
        for k in (
            "sensor",
            "steady_state_C",
            "steady_state_ci95_C",
            "equilibrium_time_min",
            "model_ok",
            "warnings",
            "assumptions",
        )
    }
    out.update(
        stop_time_min=state.stop_time_min if stopped else None,
        decision="stop" if stopped else "continue",
        reason=None if stopped else _reason([c for c in waited if not c.may_stop], settings),
        room_bound_sensors=[] if stopped else [c.sensor for c in waited if _room_bound(c, settings)],
        waited_for=[c.sensor for c in waited],
        reference_dropped=state.reference_dropped,
        last_time_min=finite_or_none(state.readings.latest_min),
        tolerance_C=settings.tolerance_C,
        decision_level=settings.decision_level,
        sensors=sensors,
    )
    # the time saved is known only in hindsight, against when the readings settled (the session's
    # hindsight sets it); a predicted 95 %-rise time lies far beyond where they settle within the tolerance
    out["time_saved_min"] = None
    out["settle_time_min"] = None
    if expected is not None:
        values = [expected.get(c.sensor, math.nan) for c in waited]
        out["expected_stop_time_min"] = max(values) if all(math.isfinite(v) for v in values) else None
    return out


def _reason(waiting: list[SensorCheck], settings: MonitorSettings) -> str:
    """Why the test cannot stop yet, and the two ways on."""
    if not waiting:
        return "every sensor may stop; confirming at the next check"
    parts = []
    for c in waiting:
        if c.status == "no rise":
            parts.append(
                f"{c.sensor}: no rise above its noise yet, which keeps the test from stopping (if the test does not "
                "heat it, leave it out of the sensors watched; if it is the room's, name it as the room sensor)"
            )
        elif not math.isfinite(c.steady_C):
            parts.append(f"{c.sensor}: {c.status}")
        elif c.status == "too coarse":
            parts.append(
                f"{c.sensor}: T∞ {c.steady_C:.2f} °C, but {c.ends} (±{settings.tolerance_C:g} °C): rounding can bias "
                "T∞ "
                "by half a step, which no interval shows; give a tolerance above the step"
            )
        elif not c.model_ok and c.half_width_C <= settings.tolerance_C:
            parts.append(
                f"{c.sensor}: T∞ {c.steady_C:.2f} °C, {settings.decision_level * 100:g} % interval {c.low_C:.2f} to "
                f"{c.high_C:.2f} °C, within ±{settings.tolerance_C:g} °C of T∞, but its model is not trusted (its "
                "warnings say why)"
            )
        else:
            bounds = (
                f"interval {c.low_C:.2f} to {c.high_C:.2f} °C"
                if math.isfinite(c.low_C) and math.isfinite(c.high_C)
                else "interval not yet bounded"
            )
            parts.append(
                f"{c.sensor}: T∞ {c.steady_C:.2f} °C, {settings.decision_level * 100:g} % {bounds}, reaching beyond "
                f"±{settings.tolerance_C:g} °C of T∞ ({c.ends})" + _room_bound_clause(c, settings)
            )
    learn = ", or give a reference run of this machine (mtident thermal learn)"
    ways = "continue the test" + ("" if settings.reference is not None else learn)
    room = (
        "state a smaller room wander if the room is steadier than assumed (0 for a steady room), or log the room "
        "beside the sensors and name it as the room sensor (the fit then follows the room instead of assuming it; "
        "without a reference run, a slow mode may still keep the interval open)"
    )
    bound = [c.sensor for c in waiting if _room_bound(c, settings)]
    slow = [c.sensor for c in waiting if _room_wander_C(c, settings) > 0 and c.sensor not in bound]
    if bound:
        others = len(bound) < len(waiting)
        ways = f"for {', '.join(bound)}, {room}" + (f"; for the others, {ways}" if others else "")
    elif slow:
        ways += f"; for {', '.join(slow)}, also {room}"
    return "; ".join(parts) + f". Ways on: {ways}."


def _room_bound_clause(check: SensorCheck, settings: MonitorSettings) -> str:
    wander = _room_wander_C(check, settings)
    if wander == 0:
        return ""
    assumed = (
        f"the room's unmeasured wander alone, as assumed ({settings.robust.room_wander_C_per_h:g} °C in an hour over "
        f"its slowest mode's {max(tau for tau, _ in check.modes):.0f} min), moves T∞ ±{wander:.2f} °C at "
        f"{settings.decision_level * 100:g} %"
    )
    if _room_bound(check, settings):
        alone = _readings_half_width(check, wander)
        return f"; the readings alone pin T∞ within ±{alone:.2f} °C, but {assumed}: no longer test narrows that"
    return f"; where its slowest mode stays as slow, {assumed}, more than the tolerance"


def _room_wander_C(check: SensorCheck, settings: MonitorSettings) -> float:
    """The half-width the unmeasured room's assumed wander alone gives the sensor's T∞ at the
    decision's level (on its best model's slowest mode), where that alone is wider than the
    tolerance; else 0."""
    if not check.modes or not math.isfinite(check.steady_C) or math.isfinite(check.room_level_C):
        return 0.0
    slowest = max(tau for tau, _ in check.modes)
    wander = room_wander_half_width(slowest, settings.decision_level, settings.robust)
    return wander if wander > settings.tolerance_C else 0.0


def _readings_half_width(check: SensorCheck, wander: float) -> float:
    """The decision interval's half-width less the room's wander (added in quadrature)."""
    return math.sqrt(max(check.half_width_C**2 - wander**2, 0.0))


def _room_bound(check: SensorCheck, settings: MonitorSettings) -> bool:
    """Whether only the unmeasured room's assumed wander keeps the sensor from the tolerance: its
    readings alone pin T∞ within it, the wander alone does not. No longer test helps."""
    wander = _room_wander_C(check, settings)
    return wander > 0 and _readings_half_width(check, wander) <= settings.tolerance_C


def _sensor_summary(
    c: SensorCheck, settings: MonitorSettings, expected: float | None, room_measured: bool
) -> dict[str, object]:
    return {
        "sensor": c.sensor,
        "waited_for": settings.waits_for(c.sensor),
        "status": c.status,
        "may_stop": c.may_stop,
        "checked_at_min": finite_or_none(c.checked_min),
        "steady_state_C": finite_or_none(c.steady_C),
        "steady_state_ci95_C": [finite_or_none(c.low95_C), finite_or_none(c.high95_C)],
        "decision_interval_C": [finite_or_none(c.low_C), finite_or_none(c.high_C)],
        "equilibrium_time_min": finite_or_none(c.equilibrium_time_min),
        "modes": [{"time_constant_min": tau, "amplitude_C": a} for tau, a in c.modes],
        "model_ok": c.model_ok,
        "warnings": list(c.warnings),
        "interval_ends": c.ends,
        "assumptions": assumptions(settings, c.sensor, room_measured).to_dict(),
        "reference_used": c.reference_used,
        "machine_model_used": c.machine_used,
        "expected_stop_time_min": None if expected is None else finite_or_none(expected),
    }
