"""The monitor's decision against where a finished log settled.

A replay of a log that ran on past the stop (an old warm-up that ran to
equilibrium) can check the rule on the engineer's own machine: each sensor's
T∞ at the stop against the temperature the log settled to
(:func:`~mtident.thermal.identify.measured_equilibrium`: the median of its last
10 samples, where its last quarter rose by less than 5 % of the whole rise and
by less than half the tolerance, and where no more than a quarter of the tolerance is still to
come at the pace of the sensor's slowest mode at the stop).
With a room sensor the room may have moved between the stop and the log's end;
T∞ follows the room one to one, but a sensor follows a move of the room through
its modes, so a move in the last hours is only partly in the log's end: the move
added to each sensor's T∞ at the stop is from the room's level at the stop (which
T∞ holds) to the room lagged by each of the sensor's modes at the stop, weighted
by their shares of its rise, at the log's end (the room's own move where the
modes are not known). Taken whole, a room that falls slowly after the stop
makes a right stop look wrong by the part of the fall the sensor has not yet
followed.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mtident._json import to_json_value
from mtident._typing import FloatArray
from mtident.thermal.measured import measured_equilibrium
from mtident.thermal.modal_search import room_lag
from mtident.thermal.modal_types import DEFAULT_MAX_TIME_CONSTANT_MIN
from mtident.thermal.readings import without_stuck

__all__ = ["Hindsight", "HindsightAnswer", "HindsightSensor", "check_decision", "settle_times"]

# the room at the stop: the median of its readings this close to it (min)
_ROOM_AROUND_STOP_MIN = 5.0
# a reading's level for the settle time: the median of this many valid readings centred on it, so
# that one noisy reading does not count as the sensor leaving its level
_SETTLE_MEDIAN_READINGS = 5


@dataclass(frozen=True, slots=True)
class HindsightSensor:
    """One sensor's line of :class:`HindsightAnswer` (NaN written as null: not known).

    Attributes
    ----------
    sensor : str
    steady_state_C : float
        T∞ at the stop (°C).
    room_shift_C : float
        The room's move as the sensor follows it, added to T∞ (°C).
    settled_C, error_C : float
        Where the log settled, and T∞ (with the room's move) less that (°C).
    measured_equilibrium_time_min : float
        When the log reached 95 % of its total rise (min).
    within_tolerance : bool or None
        None where there is nothing to check.
    settle_time_min : float
        When its readings came within the tolerance of where they settled (min).
    waited_for : bool
        The test waits for it.
    stuck_since_min : float
        When its readings stuck at one value for good (min; NaN: they did not): the repeats say
        nothing of its temperature and are left out of the check.
    settled_with_room : bool
        Its readings keep following a moving room: ``settled_C`` is where its rise above the room,
        as it follows it, settled, at the room's course at the log's end.
    """

    sensor: str
    steady_state_C: float
    room_shift_C: float
    settled_C: float
    error_C: float
    measured_equilibrium_time_min: float
    within_tolerance: bool | None
    settle_time_min: float
    waited_for: bool
    stuck_since_min: float
    settled_with_room: bool = False


@dataclass(frozen=True, slots=True)
class HindsightAnswer:
    """The decision against the rest of the log, as its JSON object says it.

    Attributes
    ----------
    stop_time_min, log_end_min : float
        The stop and the log's last sample (min).
    room_shift_C : float
        The room's move from the stop to the log's end (°C).
    settle_time_min : float
        When every sensor waited for had settled within the tolerance (t_settle; NaN: not known).
    time_saved_min : float or None
        t_settle less the stop.
    sensors : tuple of HindsightSensor
    """

    stop_time_min: float
    log_end_min: float
    room_shift_C: float
    settle_time_min: float
    time_saved_min: float | None
    sensors: tuple[HindsightSensor, ...]


@dataclass(frozen=True, slots=True)
class Hindsight:
    """Per sensor: T∞ at the stop (NaN: left out of the decision), where the log settled (NaN: not at
    equilibrium by its end), and the difference.

    Attributes
    ----------
    sensors : tuple of str
        The sensors, in the log's order.
    stop_time_min : float
        The stop (min).
    log_end_min : float
        The time of the log's last sample (min).
    steady_state_C : ndarray, shape (S,)
        T∞ at the stop (°C), NaN for a sensor left out of the decision.
    settled_C : ndarray, shape (S,)
        Where the log settled (°C, :func:`~mtident.thermal.identify.measured_equilibrium`), NaN
        where it was not at equilibrium by its end, or its last quarter still moved by half the
        tolerance or more.
    measured_equilibrium_time_min : ndarray, shape (S,)
        When the log reached 95 % of its total rise (min), NaN where it did not settle.
    room_shift_C : float
        The room's move from the stop to the log's end (°C); 0 without a room sensor.
    tolerance_C : float
        The decision's tolerance (°C).
    sensor_shift_C : ndarray, shape (S,), optional
        The room's move as each sensor follows it by the log's end (°C), added to its T∞
        (default: the room's move for every sensor).
    settle_time_min : ndarray, shape (S,), optional
        When each sensor's readings came within the tolerance of where they settled, to stay
        (:func:`settle_times`; with a room sensor, of their equilibrium at the room's level at the
        time, as T∞ follows the room; NaN where the log did not settle); default: not known.
    waited : ndarray of bool, shape (S,), optional
        The sensors the test waits for (default: every one).
    stuck_since_min : ndarray, shape (S,), optional
        When each sensor's readings stuck at one value for good (min; NaN: they did not; default:
        none did). Its repeats are left out: a sensor that stuck before it settled has no level to
        check, and that is the sensor's failure, not the log's being short.
    settled_above_room : ndarray of bool, shape (S,), optional
        The sensors whose readings keep following a moving room: their ``settled_C`` is where
        their rise above the room, as they follow it through their modes at the stop, settled, at
        the room's course at the log's end (default: none).
    """

    sensors: tuple[str, ...]
    stop_time_min: float
    log_end_min: float
    steady_state_C: FloatArray
    settled_C: FloatArray
    measured_equilibrium_time_min: FloatArray
    room_shift_C: float
    tolerance_C: float
    sensor_shift_C: FloatArray | None = None
    settle_time_min: FloatArray | None = None
    waited: np.ndarray | None = None
    stuck_since_min: FloatArray | None = None
    settled_above_room: np.ndarray | None = None

    @property
    def test_settle_time_min(self) -> float:
        """When the readings of every sensor the test waits for had settled within the tolerance
        (t_settle): the latest of their settle times; NaN where one of them did not settle by the
        log's end, or the settle times are not known.

        Returns
        -------
        float
            The time (min).
        """
        if self.settle_time_min is None:
            return float("nan")
        waited = np.ones(len(self.sensors), dtype=bool) if self.waited is None else np.asarray(self.waited, bool)
        times = np.asarray(self.settle_time_min, dtype=float)[waited]
        return float(times.max()) if len(times) and np.all(np.isfinite(times)) else float("nan")

    @property
    def time_saved_min(self) -> float | None:
        """The time the stop saved against waiting until the readings settled (t_settle less the
        stop; negative where the stop came later); None where t_settle is not known.

        Returns
        -------
        float or None
        """
        settle = self.test_settle_time_min
        return settle - self.stop_time_min if np.isfinite(settle) else None

    @property
    def shift_C(self) -> FloatArray:
        """The room's move added to each sensor's T∞ (°C).

        Returns
        -------
        ndarray, shape (S,)
        """
        if self.sensor_shift_C is not None:
            return np.asarray(self.sensor_shift_C, dtype=float)
        return np.full(len(self.sensors), self.room_shift_C)

    def __repr__(self) -> str:
        # a notebook shows the verdict, not the arrays
        room = f", room moved {self.room_shift_C:+.2f} °C" if self.room_shift_C else ""
        lines = [
            f"Hindsight(stop at {self.stop_time_min:g} min, log to {self.log_end_min:g} min{room}, tolerance "
            f"{self.tolerance_C:g} °C)"
        ]
        for i, name in enumerate(self.sensors):
            if not self.checked[i]:
                since = self.stuck_since[i]
                why = (
                    "left out of the decision"
                    if not np.isfinite(self.steady_state_C[i])
                    else f"stuck from {since:g} min, before it settled: nothing to check"
                    if np.isfinite(since)
                    else "not settled by the log's end"
                )
                lines.append(f"  {name}: {why}")
                continue
            verdict = "within" if self.within[i] else "BEYOND the tolerance"
            lines.append(
                f"  {name}: T∞ {self.steady_state_C[i]:.2f} °C, settled at {self.settled_C[i]:.2f} °C: "
                f"{self.error_C[i]:+.3f} °C, {verdict}"
            )
        return "\n".join(lines)

    @property
    def settled_with_room(self) -> np.ndarray:
        """Whether each sensor's settled level is its rise above the room as it follows it (its
        readings keep following a moving room).

        Returns
        -------
        ndarray of bool, shape (S,)
        """
        if self.settled_above_room is None:
            return np.zeros(len(self.sensors), dtype=bool)
        return np.asarray(self.settled_above_room, dtype=bool)

    @property
    def following_room(self) -> np.ndarray:
        """Whether each sensor's readings keep following a moving room with no level to check: a
        settle time known (of its rise above the room), no settled level.

        Returns
        -------
        ndarray of bool, shape (S,)
        """
        if self.settle_time_min is None:
            return np.zeros(len(self.sensors), dtype=bool)
        following: np.ndarray = ~np.isfinite(self.settled_C) & np.isfinite(np.asarray(self.settle_time_min, float))
        return following

    @property
    def stuck_since(self) -> FloatArray:
        """When each sensor's readings stuck for good (min, NaN where they did not).

        Returns
        -------
        ndarray, shape (S,)
        """
        if self.stuck_since_min is None:
            return np.full(len(self.sensors), np.nan)
        return np.asarray(self.stuck_since_min, dtype=float)

    @property
    def error_C(self) -> FloatArray:
        """T∞ at the stop, moved with the room as the sensor follows it, minus where the log settled.

        Returns
        -------
        ndarray, shape (S,)
            The error (°C), NaN where T∞ or the settled temperature is NaN.
        """
        return self.steady_state_C + self.shift_C - self.settled_C

    @property
    def checked(self) -> np.ndarray:
        """The sensors with something to check: in the decision, and settled by the log's end.

        Returns
        -------
        ndarray of bool, shape (S,)
        """
        return np.isfinite(self.error_C)

    @property
    def within(self) -> np.ndarray:
        """Whether each sensor's T∞ was within the tolerance of where it settled (False where it did not settle).

        Returns
        -------
        ndarray of bool, shape (S,)
        """
        with np.errstate(invalid="ignore"):
            return np.abs(self.error_C) <= self.tolerance_C

    @property
    def not_settled(self) -> list[str]:
        """The sensors in the decision with no level to check by the log's end: their readings did not
        settle, nor their rise above the room as they follow it, and they did not stick.

        Returns
        -------
        list of str
        """
        # readings that keep following a moving room, their settle time known, have not failed to settle
        stuck = np.isfinite(self.stuck_since)
        return [
            name
            for name, decided, known, room, failed in zip(
                self.sensors, np.isfinite(self.steady_state_C), self.checked, self.following_room, stuck, strict=True
            )
            if decided and not known and not room and not failed
        ]

    def verdict_words(self) -> str:
        """Whether the sensors that settled did so within the tolerance of T∞ at the stop, in words
        (a clause, lower case; empty where none settled).

        Returns
        -------
        str
        """
        checked = self.checked
        if not checked.any():
            return ""
        beyond = [name for name, ok, known in zip(self.sensors, self.within, checked, strict=True) if known and not ok]
        if beyond:
            return (
                f"{len(beyond)} of {int(checked.sum())} sensors settled beyond the tolerance ({self.tolerance_C:g} °C) "
                f"of T∞ at the stop: {', '.join(beyond)}"
            )
        return (
            f"every sensor that settled ({int(checked.sum())}) is within the tolerance ({self.tolerance_C:g} °C) "
            "of T∞ at the stop"
        )

    def answer(self) -> HindsightAnswer:
        """The check as a record whose fields are its JSON object.

        Returns
        -------
        HindsightAnswer
            The stop, the log's end, the room's shift, when the readings settled, the time saved,
            and one entry per sensor.
        """
        shift = self.shift_C
        settle = (
            np.full(len(self.sensors), np.nan) if self.settle_time_min is None else np.asarray(self.settle_time_min)
        )
        waited = np.ones(len(self.sensors), dtype=bool) if self.waited is None else np.asarray(self.waited, bool)
        within, checked = self.within, self.checked
        return HindsightAnswer(
            stop_time_min=self.stop_time_min,
            log_end_min=self.log_end_min,
            room_shift_C=self.room_shift_C,
            settle_time_min=self.test_settle_time_min,
            time_saved_min=self.time_saved_min,
            sensors=tuple(
                HindsightSensor(
                    sensor=name,
                    steady_state_C=float(self.steady_state_C[i]),
                    room_shift_C=float(shift[i]),
                    settled_C=float(self.settled_C[i]),
                    error_C=float(self.error_C[i]),
                    measured_equilibrium_time_min=float(self.measured_equilibrium_time_min[i]),
                    within_tolerance=bool(within[i]) if checked[i] else None,
                    settle_time_min=float(settle[i]),
                    waited_for=bool(waited[i]),
                    stuck_since_min=float(self.stuck_since[i]),
                    settled_with_room=bool(self.settled_with_room[i]),
                )
                for i, name in enumerate(self.sensors)
            ),
        )

    def to_dict(self) -> dict[str, object]:
        """Plain JSON types (None where not known): :meth:`answer`'s fields.

        Returns
        -------
        dict
            The stop, the log's end, the room's shift and one entry per sensor: its T∞, the room's
            shift as it follows it, where it settled, the error, the measured equilibrium time and
            whether it was within the tolerance.
        """
        tree: dict[str, object] = to_json_value(self.answer())
        return tree


def check_decision(
    sensors: tuple[str, ...],
    steady_state_C: FloatArray,
    stop_time_min: float,
    time_min: FloatArray,
    values: FloatArray,
    tolerance_C: float,
    room_C: FloatArray | None = None,
    modes: Sequence[tuple[tuple[float, float], ...]] | None = None,
    max_time_constant_min: float = DEFAULT_MAX_TIME_CONSTANT_MIN,
    waited: np.ndarray | None = None,
    room_gains: Sequence[tuple[float, ...]] | None = None,
) -> Hindsight:
    """Compare T∞ at the stop (one per sensor, NaN for one left out) with where the whole log settled.

    Parameters
    ----------
    sensors : tuple of str
    steady_state_C : ndarray, shape (S,)
        T∞ at the stop (°C), NaN for a sensor left out of the decision.
    stop_time_min : float
        The stop (min).
    time_min : ndarray, shape (N,)
        The whole log's times (min), past the stop.
    values : ndarray, shape (N, S)
        The whole log's readings (°C, NaN: missing).
    tolerance_C : float
        The decision's tolerance (°C).
    room_C : ndarray, shape (N,), optional
        The room sensor's readings (°C): its move from the stop (the median within 5 min of it)
        to the log's end (the median of its last 10 valid readings) is added to T∞. No shift
        where it has fewer than 10 valid readings or none within 5 min of the stop.
    modes : sequence of tuples of (time constant, amplitude), optional
        Each sensor's modes at the stop: the room's move reaches it through them, by its gains on
        the room (``room_gains``) or else weighted by their shares of its rise (without them, or
        for a sensor with none, whole).
    max_time_constant_min : float
        The slowest mode allowed (min), for a sensor whose modes are not given. A sensor counts
        as settled where the rise still to come at the pace of its slowest mode (its late move m
        over Δ minutes leaves m / (e^(Δ/τ) − 1)) is at most a quarter of the tolerance.
    waited : ndarray of bool, shape (S,), optional
        The sensors the test waits for (default: all): t_settle is the latest of theirs.
    room_gains : sequence of tuples of float, optional
        Each sensor's gain on the room per mode at the stop (one per mode of ``modes``): the room's
        course through the sensor, for its move after the stop and its settle time.

    Returns
    -------
    Hindsight
    """
    # a stuck sensor's repeats are no temperature: a channel that failed after the stop at its
    # last value was taken as where the sensor settled, and the stop blamed for 1.16 °C
    values, stuck, _ = without_stuck(time_min, values)
    # a sensor still moving by half the tolerance, or with more than a quarter of it still to come
    # at the pace of its slowest mode, is not settled to the precision the check needs
    slowest_min = np.array(
        [
            min(max((tau for tau, _ in m), default=max_time_constant_min), max_time_constant_min)
            for m in (modes if modes is not None else [()] * len(sensors))
        ],
        dtype=float,
    )
    # settled to the check's precision: the tolerance's bounds, not a share of the rise (a column that
    # rose 0.6 °C, moving 0.07 °C with a daily room, was "not yet" settled, and the time saved unknown)
    settling = {"max_late_move_C": tolerance_C / 2.0, "max_remaining_C": tolerance_C / 4.0, "max_late_share": np.inf}
    settled, equilibrium = measured_equilibrium(time_min, values, slowest_mode_min=slowest_min, **settling)
    # each sensor's course of the room (the room itself for one without modes), where one is logged
    courses = None
    if room_C is not None and np.isfinite(room_C).sum() >= 10:
        gains = room_gains if room_gains is not None else [()] * len(sensors)
        per_sensor = modes if modes is not None else [()] * len(sensors)
        courses = np.column_stack(
            [_room_course(time_min, room_C, m, g) for m, g in zip(per_sensor, gains, strict=True)]
        )
    shift, followed, with_room = 0.0, None, None
    # where each settles above the room, as it follows it (readings that keep following a moving room)
    above = (
        None
        if courses is None
        else measured_equilibrium(time_min, values - courses, slowest_mode_min=slowest_min, **settling)[0]
    )
    if room_C is not None and courses is not None and above is not None:
        valid = np.isfinite(room_C)
        near = valid & (np.abs(time_min - stop_time_min) <= _ROOM_AROUND_STOP_MIN)
        if near.any():
            at_stop = float(np.median(room_C[near]))
            shift = float(np.median(room_C[valid][-10:])) - at_stop
            if modes is not None:
                course_end = np.median(courses[valid][-10:], axis=0)
                followed = course_end - at_stop
                # T∞ at the stop, moved as the sensor follows the room, against its rise above the room
                # as it follows it, at the log's end: a daily cycle keeps the readings themselves moving
                with_room = ~np.isfinite(settled) & np.isfinite(above)
                settled = np.where(with_room, above + course_end, settled)
    return Hindsight(
        sensors=tuple(sensors),
        stop_time_min=float(stop_time_min),
        log_end_min=float(time_min[-1]),
        steady_state_C=np.asarray(steady_state_C, dtype=float),
        settled_C=settled,
        measured_equilibrium_time_min=equilibrium,
        room_shift_C=shift,
        tolerance_C=float(tolerance_C),
        sensor_shift_C=followed,
        settle_time_min=_settle_times(time_min, values, courses, above, room_C, settled, tolerance_C),
        waited=None if waited is None else np.asarray(waited, dtype=bool),
        stuck_since_min=None if all(math.isnan(v) for v in stuck) else np.array(stuck, dtype=float),
        settled_above_room=with_room if with_room is not None and with_room.any() else None,
    )


def _settle_times(
    time_min: FloatArray,
    values: FloatArray,
    room_courses: FloatArray | None,
    settled_above: FloatArray | None,
    room_C: FloatArray | None,
    settled_C: FloatArray,
    tolerance_C: float,
) -> FloatArray:
    """The settle times of the readings: with a room sensor, when each sensor's readings stayed
    within the tolerance of its equilibrium at the room's level at the time, the benchmark's
    t_settle. Where each settles above the room is the level of its readings less the room as it
    follows it (``room_courses``, (N, S), :func:`_room_course`): T∞ follows the room one to one,
    and a room on a daily cycle keeps the readings themselves moving by more than the tolerance
    long after the sensor has settled above it. The readings are held against that level plus the
    room itself, not its course: a sensor that lags a moving room by more than the tolerance is
    not settled, however long ago its own warm-up was (less the course, a daily room's lag read
    as settled 150 min before the readings came within the tolerance of the truth). Where the
    readings never come that close by the log's end, the time their rise above the room as they
    follow it settled stands in (``settled_above``: where it settled)."""
    if room_courses is None or settled_above is None or room_C is None:
        return settle_times(time_min, values, settled_C, tolerance_C)
    above = values - room_courses
    room_now = _room_course(time_min, room_C, (), ())
    behind = settle_times(time_min, values - room_now[:, None], settled_above, tolerance_C)
    # a sensor that lags a daily room by more than the tolerance to the log's end: its rise above the
    # room as it follows it, as the benchmark's t_settle takes the same test in a steady room then
    return np.where(np.isfinite(behind), behind, settle_times(time_min, above, settled_above, tolerance_C))


def _room_course(
    time_min: FloatArray, room_C: FloatArray, modes: tuple[tuple[float, float], ...], gains: tuple[float, ...]
) -> FloatArray:
    """The room as a sensor of these modes follows it, at every time of the log: through each mode
    by the fit's gain on the room (:func:`~mtident.thermal.modes.course_with_room`), or without
    gains lagged by each mode weighted by its share of the rise; the room itself without modes.
    Less the room itself, a slow sensor's warm-up and its lag behind a daily cycle cancelled: a
    column still 0.77 °C below its course read as settled from 421 min of a 720-min log."""
    weights = np.abs(np.array([a for _, a in modes], dtype=float))
    valid = np.isfinite(room_C)
    if not len(modes) or not weights.sum() > 0:
        return np.interp(time_min, time_min[valid], room_C[valid])
    times, first = np.unique(time_min[valid], return_index=True)
    room = room_C[valid][first]
    lagged = room_lag(room, times, np.array([tau for tau, _ in modes], dtype=float))
    followed = (
        room + np.asarray(gains) @ (lagged - room) if len(gains) == len(modes) else weights @ lagged / weights.sum()
    )
    course: FloatArray = np.interp(time_min, times, followed)
    return course


def settle_times(time_min: FloatArray, values: FloatArray, settled_C: FloatArray, tolerance_C: float) -> FloatArray:
    """When each sensor's readings came within the tolerance of where they settled and stayed there.

    A reading's level is the median of the few valid readings centred on it, so that noise
    alone does not count as leaving; the settle time is the first reading after the last level
    beyond the tolerance (the first reading where none is).

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        The log's times (min).
    values : ndarray, shape (N, S)
        The readings (°C, NaN: missing).
    settled_C : ndarray, shape (S,)
        Where each sensor settled (°C, NaN: it did not).
    tolerance_C : float
        The tolerance (°C).

    Returns
    -------
    ndarray, shape (S,)
        The settle times (min), NaN where a sensor did not settle.
    """
    out = np.full(values.shape[1], np.nan)
    half = _SETTLE_MEDIAN_READINGS // 2
    for s in range(values.shape[1]):
        ok = np.isfinite(values[:, s])
        if not np.isfinite(settled_C[s]) or ok.sum() < _SETTLE_MEDIAN_READINGS:
            continue
        t, y = time_min[ok], values[ok, s]
        padded = np.pad(y, half, mode="edge")
        level = np.median(np.lib.stride_tricks.sliding_window_view(padded, 2 * half + 1), axis=1)
        beyond = np.flatnonzero(np.abs(level - settled_C[s]) > tolerance_C)
        if not len(beyond):
            out[s] = t[0]
        elif beyond[-1] + 1 < len(t):
            out[s] = t[beyond[-1] + 1]
    return out
