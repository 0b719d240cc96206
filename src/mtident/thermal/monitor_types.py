"""What the live monitor is made of: its settings (:class:`MonitorSettings`), the readings so far,
one :class:`SensorCheck` per sensor, the frozen :class:`MonitorState` they make up, and the
:class:`Event` records a step gives; a sensor's status and an event's kind as literals. The step
itself is :mod:`~mtident.thermal.monitor`, the answer in JSON :mod:`~mtident.thermal.monitor_answer`.

Persistence is generated from these dataclasses' fields (:mod:`mtident.persist`), which is why
every name their fields are annotated with is imported at run time here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Literal, get_args

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.thermal.readings import sampling_interval_min
from mtident.thermal.reference import MachineReference
from mtident.thermal.robust_types import RobustSettings

SILENT_READINGS = 10
"""A sensor without a valid reading for this many sampling intervals while the log goes on is
silent (a failed sensor, a lost channel)."""
SILENT_MIN = 10.0
"""And for at least this long (min): a logger that skips a reading or two is not a failure."""


def last_valid(time_min: FloatArray, valid: np.ndarray, latest_min: float) -> tuple[float, bool]:
    """The time of a column's latest valid reading (NaN before the first), and whether it is silent:
    none for :data:`SILENT_READINGS` sampling intervals (its own, where it is logged more sparsely
    than the log), at least :data:`SILENT_MIN`, up to ``latest_min`` (the others' latest reading).

    Parameters
    ----------
    time_min : ndarray, shape (N,)
    valid : ndarray of bool, shape (N,)
        Which of the column's readings are valid.
    latest_min : float

    Returns
    -------
    float
    bool
    """
    at = np.flatnonzero(valid)
    if not len(at):
        return math.nan, False
    # its own step: a sensor logged every fifth row is not silent in between
    own = sampling_interval_min(time_min[at[-50:]]) if len(at) > 2 else 0.0
    last = float(time_min[at[-1]])
    return last, latest_min - last >= max(SILENT_MIN, SILENT_READINGS * max(own, sampling_interval_min(time_min)))


__all__ = [
    "REPORT_LEVEL",
    "Event",
    "EventKind",
    "MonitorSettings",
    "MonitorState",
    "Readings",
    "STATUSES",
    "SensorCheck",
    "Status",
    "TIMELINE_COLUMNS",
    "minutes",
    "said_at",
    "without_time",
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
    "silent",
    "stuck",
]
STATUSES: tuple[str, ...] = get_args(Status)
"""The statuses in order: a check's status in :attr:`MonitorState.timeline` is its index here."""

TIMELINE_COLUMNS = ("checked_min", "sensor", "status", "steady_C", "low95_C", "high95_C", "low_C", "high_C")
"""The columns of :attr:`MonitorState.timeline`, one row per check of a sensor: when, the sensor (its
index in ``sensors``), its status (its index in :data:`STATUSES`), T∞ and its intervals at 95 % and at
the decision's level (°C, infinite without one)."""


def _no_checks() -> FloatArray:
    return np.empty((0, len(TIMELINE_COLUMNS)))


# what an event of the monitor (and of a watch session) says
EventKind = Literal["check", "ready", "not ready", "stop", "warning", "note"]


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


@dataclass(frozen=True, eq=False)
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

    # arrays compare elementwise: a state saved and loaded again equals the one saved
    __hash__ = None  # type: ignore[assignment]

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Readings):
            return NotImplemented
        if (self.room_C is None) != (other.room_C is None):
            return False
        pairs = [(self.time_min, other.time_min), (self.values_C, other.values_C)]
        if self.room_C is not None and other.room_C is not None:
            pairs.append((self.room_C, other.room_C))
        return all(a.shape == b.shape and np.array_equal(a, b, equal_nan=True) for a, b in pairs)

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

    def room_silent_since(self) -> float:
        """The time of the room sensor's latest valid reading where it has been silent since (no
        valid reading for :data:`SILENT_READINGS` sampling intervals, at least :data:`SILENT_MIN`,
        while the sensors read on); NaN where it reads, or without a room sensor.

        Returns
        -------
        float
            The time (min).
        """
        sensors = np.flatnonzero(np.isfinite(self.values_C).any(axis=1))
        if self.room_C is None or not len(sensors):
            return math.nan
        last, silent = last_valid(self.time_min, np.isfinite(self.room_C), float(self.time_min[sensors[-1]]))
        return last if silent else math.nan


@dataclass(frozen=True)
class SensorCheck:
    """One sensor's latest check, in plain numbers (what a table or a page shows).

    ``passes`` counts the checks in a row that found the interval within the tolerance;
    ``status`` is one of "collecting", "no data", "no rise", "undetermined", "narrowing",
    "confirming", "may stop", "misfit", "off reference", "too coarse" (readings in steps no finer than the
    tolerance), "silent" (no reading for a while, the others reading on: a failed sensor or a lost
    channel; its answer rests on its readings up to then), "stuck" (the same reading over and over
    where its noise makes that no chance: its answer rests on its readings before).

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
        Where its best model's modes begin (min): its warm-up's start, or the machine's (the
        earliest sensor's) where the machine model answers.
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
    last_reading_min : float
        The time of its latest valid reading (min), NaN before the first.
    room_lag_C : float
        How far the machine model's lag behind a moving room may move T∞ (one sd, °C; part of
        the intervals), 0 where none.
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
    last_reading_min: float = math.nan
    room_lag_C: float = 0.0

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
    warned : tuple of (str, str)
        Each warning said of a sensor so far, as (sensor, text): its answer lists them, where its
        latest check may no longer have them.
    timeline : ndarray, shape (M, len(TIMELINE_COLUMNS))
        Every check so far, one row per sensor checked (:data:`TIMELINE_COLUMNS`): how T∞ and its
        interval narrowed to the stop (:func:`~mtident.thermal.timeline.check_timeline`).
    """

    sensors: tuple[str, ...]
    readings: Readings
    checks: tuple[SensorCheck, ...]
    stop_time_min: float = math.nan
    said: tuple[str, ...] = ()
    reference_dropped: bool = False
    warned: tuple[tuple[str, str], ...] = ()
    timeline: FloatArray = field(default_factory=_no_checks)

    # the timeline's array compares elementwise, as the readings' do
    __hash__ = None  # type: ignore[assignment]

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, MonitorState):
            return NotImplemented
        mine, theirs = np.asarray(self.timeline), np.asarray(other.timeline)
        return (
            (self.sensors, self.readings, self.checks, self.said, self.reference_dropped, self.warned)
            == (other.sensors, other.readings, other.checks, other.said, other.reference_dropped, other.warned)
            and (self.stop_time_min == other.stop_time_min or (self.stopped, other.stopped) == (False, False))
            and mine.shape == theirs.shape
            and np.array_equal(mine, theirs, equal_nan=True)
        )

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


def said_at(time_min: float, text: str) -> str:
    """A message as said at a time of the test: ``"t = 230 min: text"``."""
    return f"t = {minutes(time_min)}: {text}"


def without_time(said: str) -> str:
    """A message said at a time (:func:`said_at`) without its time; any other as it is."""
    return said.split(": ", 1)[1] if said.startswith("t = ") else said
