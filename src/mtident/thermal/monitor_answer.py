"""The live monitor's answer: the record whose fields are the JSON a watch prints and saves
(:func:`answer`: the decision, the sensor the test waits for, and per sensor its answer, verdict
and assumptions), and why a test cannot stop yet, with the ways on, in words.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, replace

from scipy.special import ndtri

from mtident._json import json_optional, to_json_value
from mtident.thermal.assumptions import describe_assumptions
from mtident.thermal.hindsight import HindsightAnswer
from mtident.thermal.modal_types import Mode
from mtident.thermal.monitor_types import MonitorSettings, MonitorState, Readings, SensorCheck, without_time
from mtident.thermal.robust import room_wander_half_width
from mtident.thermal.robust_types import ROOMS_PART_LOGGED, ROOMS_PART_UNLOGGED, Assumptions, ends_at_the_largest

__all__ = [
    "SensorStatus",
    "WatchAnswer",
    "answer",
    "assumptions",
    "failure_words",
    "reason_lines",
    "reason_text",
    "result",
    "silent_words",
]


def assumptions(
    settings: MonitorSettings, sensor: str, room_measured: bool = False, machine_used: bool = True
) -> Assumptions:
    """What a sensor's interval rests on, as the answer says it.

    Parameters
    ----------
    settings : MonitorSettings
        The largest time constant, the room's wander or sensor, and the reference run.
    sensor : str
        The sensor whose reference modes, if any, are described.
    room_measured : bool
        The monitor is given the room's readings (named or not by ``settings.room_sensor``).
    machine_used : bool
        The sensor's answer comes with the machine model (default: what the reference holds).

    Returns
    -------
    Assumptions
        The model, the largest time constant (min), how the room entered, and the reference.
    """
    return describe_assumptions(
        settings.robust, settings.room_sensor, settings.reference, sensor, room_measured, machine_used
    )


@dataclass(frozen=True, slots=True)
class SensorStatus:
    """One sensor's line of the watch's answer (NaN written as null: not known).

    Attributes
    ----------
    sensor : str
    waited_for : bool
        The test waits for it.
    status : str
        Its check's status ("collecting", "narrowing", "may stop", ...).
    may_stop : bool
    checked_at_min : float
        When it was last checked (min).
    steady_state_C : float
        T∞ (°C).
    steady_state_ci95_C, decision_interval_C : tuple of float
        T∞'s 95 % interval and the decision's, low and high (°C).
    equilibrium_time_min : float
        Predicted time to 95 % of the total rise (min).
    modes : tuple of Mode
        The best model's modes.
    model_ok : bool
    warnings : tuple of str
    interval_ends : str
        In words, what sets the interval's ends.
    assumptions : Assumptions
    reference_used, machine_model_used : bool
    expected_stop_time_min : float
        Its expected stop (min; NaN where not foreseen or not asked for).
    """

    sensor: str
    waited_for: bool
    status: str
    may_stop: bool
    checked_at_min: float
    steady_state_C: float
    steady_state_ci95_C: tuple[float, float]
    decision_interval_C: tuple[float, float]
    equilibrium_time_min: float
    modes: tuple[Mode, ...]
    model_ok: bool
    warnings: tuple[str, ...]
    interval_ends: str
    assumptions: Assumptions
    reference_used: bool
    machine_model_used: bool
    expected_stop_time_min: float


@dataclass(frozen=True, slots=True)
class WatchAnswer:
    """The watch's answer: its fields are its JSON object (the documentation's JSON page).

    The first keys are those of one sensor's answer, of the sensor the test waits for: the
    slowest to equilibrium once stopped, the widest interval before.

    Attributes
    ----------
    sensor : str
    steady_state_C : float
    steady_state_ci95_C : tuple of float
    equilibrium_time_min : float
    model_ok : bool
    warnings : tuple of str
    assumptions : Assumptions
        That sensor's answer.
    stop_time_min : float or None
        The stop; None before it.
    decision : str
        "stop" or "continue".
    reason : str or None
        Why the test cannot stop yet, and the ways on.
    room_bound_sensors : tuple of str
        The sensors only the room's assumed wander keeps from the tolerance.
    waited_for : tuple of str
    reference_dropped : bool
    last_time_min : float
        The latest reading's time (min).
    tolerance_C, decision_level : float
    sensors : tuple of SensorStatus
    time_saved_min, settle_time_min : float or None
        Known only in hindsight (a replay of a log that runs on past the stop).
    expected_stop_time_min : float or None
        The test's expected stop (NaN: none found); None where not asked for, and then left out.
    hindsight : HindsightAnswer or None
        The decision against the rest of a replayed log; left out where None.
    log_warnings : tuple of str or None
        What this session said of the log and the test as a whole as it read them (readings lost
        or misread, a coarse room sensor, the reference's fit to the log), each once; left out
        where none was said.
    reason_lines : tuple of str or None
        ``reason`` a line at a time (:func:`reason_lines`): the room sensor's and each holding
        sensor's, then the ways on; left out where the test may stop.
    """

    sensor: str
    steady_state_C: float
    steady_state_ci95_C: tuple[float, float]
    equilibrium_time_min: float
    model_ok: bool
    warnings: tuple[str, ...]
    assumptions: Assumptions
    stop_time_min: float | None
    decision: str
    reason: str | None
    room_bound_sensors: tuple[str, ...]
    waited_for: tuple[str, ...]
    reference_dropped: bool
    last_time_min: float
    tolerance_C: float
    decision_level: float
    sensors: tuple[SensorStatus, ...]
    time_saved_min: float | None = None
    settle_time_min: float | None = None
    expected_stop_time_min: float | None = json_optional()
    hindsight: HindsightAnswer | None = json_optional()
    log_warnings: tuple[str, ...] | None = json_optional()
    reason_lines: tuple[str, ...] | None = json_optional()


def answer(state: MonitorState, settings: MonitorSettings, expected: dict[str, float] | None = None) -> WatchAnswer:
    """The answer: the decision, the single-sensor keys of the sensor the test
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
    WatchAnswer
    """
    if state.reference_dropped:
        settings = replace(settings, reference=None)  # the answers rest on no reference: their assumptions say so
    measured = state.readings.room_C is not None
    sensors = tuple(
        replace(
            _sensor_status(c, settings, math.nan if expected is None else expected.get(c.sensor, math.nan), measured),
            warnings=_said_of(c, state.warned),
        )
        for c in state.checks
    )
    stopped = state.stopped
    waited = [c for c in state.checks if settings.waits_for(c.sensor)]
    if stopped:
        key = max(waited, key=lambda c: c.equilibrium_time_min if math.isfinite(c.equilibrium_time_min) else -math.inf)
    else:
        key = max(waited, key=lambda c: c.half_width_C)
    lead = sensors[state.checks.index(key)]
    holding = [c for c in waited if not c.may_stop]
    lines = None if stopped else reason_lines(holding, settings, state.readings, state.reference_dropped)
    stops = None if expected is None else [expected.get(c.sensor, math.nan) for c in waited]
    return WatchAnswer(
        stop_time_min=state.stop_time_min if stopped else None,
        decision="stop" if stopped else "continue",
        reason=None if lines is None else reason_text(lines),
        reason_lines=lines,
        # the single-sensor keys: those of the sensor the test waits for
        sensor=lead.sensor,
        steady_state_C=lead.steady_state_C,
        steady_state_ci95_C=lead.steady_state_ci95_C,
        equilibrium_time_min=lead.equilibrium_time_min,
        model_ok=lead.model_ok,
        warnings=lead.warnings,
        assumptions=lead.assumptions,
        room_bound_sensors=() if stopped else tuple(c.sensor for c in waited if _room_bound(c, settings)),
        waited_for=tuple(c.sensor for c in waited),
        reference_dropped=state.reference_dropped,
        last_time_min=state.readings.latest_min,
        tolerance_C=settings.tolerance_C,
        decision_level=settings.decision_level,
        sensors=sensors,
        # the time saved is known only in hindsight, against when the readings settled (the session's
        # hindsight sets it); a predicted 95 %-rise time lies far beyond where they settle within the tolerance
        time_saved_min=None,
        settle_time_min=None,
        expected_stop_time_min=None if stops is None else max(stops) if all(map(math.isfinite, stops)) else math.nan,
    )


def result(
    state: MonitorState, settings: MonitorSettings, expected: dict[str, float] | None = None
) -> dict[str, object]:
    """The JSON answer: :func:`answer`'s fields.

    Parameters
    ----------
    state : MonitorState
    settings : MonitorSettings
    expected : dict of str to float, optional
        Each sensor's expected stop, where the caller has it.

    Returns
    -------
    dict
    """
    tree: dict[str, object] = to_json_value(answer(state, settings, expected))
    return tree


def room_silent_words(since_min: float, settings: MonitorSettings) -> str:
    """What a silent room sensor means, and the way on.

    Parameters
    ----------
    since_min : float
        Its latest valid reading (min, :meth:`Readings.room_silent_since`).
    settings : MonitorSettings

    Returns
    -------
    str
    """
    name = settings.room_sensor or "the room sensor"
    return (
        f"{name} (the room): no reading since t = {since_min:.0f} min while the sensors read on "
        "(a failed sensor or a lost channel?): T∞ is at the room's level, unknown since, so the test is held until "
        "it reads again; if it has failed, watch again without it and say how far the room may wander "
        "(`room_wander_C_per_h`)"
    )


def silent_words(check: SensorCheck, option: str = "`wait_for` the others") -> str:
    """What a silent (or stuck) sensor's status means, and the way on.

    Parameters
    ----------
    check : SensorCheck
    option : str, optional
        How to leave it out, as the reader says it (a report: the command line's option).

    Returns
    -------
    str
    """
    what = failure_words(check.status == "stuck", check.last_reading_min)
    if check.status == "stuck":
        return (
            f"{check.sensor}: {what}: those readings say nothing of its temperature, and it holds the test until it "
            f"reads again; if it has failed, leave it out of the sensors the test waits for ({option})"
        )
    return (
        f"{check.sensor}: {what}: its answer rests on its readings up to then, and it holds the test until it "
        f"reads again; if it has failed, leave it out of the sensors the test waits for ({option})"
    )


def failure_words(stuck: bool, since_min: float) -> str:
    """How a sensor failed, and since when: stuck (the same value over and over) or silent."""
    if stuck:
        return (
            f"every reading since t = {since_min:.0f} min is the same value, which its noise makes no chance (a "
            "stuck sensor, or a logger channel that repeats its last value?)"
        )
    return f"no reading since t = {since_min:.0f} min while the others read on (a failed sensor or a lost channel?)"


def reason_text(lines: tuple[str, ...]) -> str:
    """:func:`reason_lines` as one text, the JSON's ``reason``: what holds each sensor, then the ways on.

    Parameters
    ----------
    lines : tuple of str

    Returns
    -------
    str
    """
    if len(lines) == 1:
        return lines[0]
    return "; ".join(lines[:-1]) + ". " + lines[-1]


def reason_lines(
    waiting: list[SensorCheck], settings: MonitorSettings, readings: Readings, dropped: bool = False
) -> tuple[str, ...]:
    """Why the test cannot stop yet, a line for the room sensor and for each sensor that holds it,
    and the last line the ways on ("Ways on: ..."); one line where nothing holds it but the
    confirming check or a silent room sensor. What "more from the room" means is said at the
    first sensor only (a machine's reason said it at each of its eight sensors).

    Parameters
    ----------
    waiting : list of SensorCheck
        The sensors the test waits for that may not stop yet.
    settings : MonitorSettings
    readings : Readings
    dropped : bool, optional
        The reference was dropped (the test contradicted it).

    Returns
    -------
    tuple of str
    """
    since = readings.room_silent_since()
    silent_room = [room_silent_words(since, settings)] if math.isfinite(since) else []
    if not waiting:
        return (silent_room[0] if silent_room else "every sensor may stop; confirming at the next check",)
    parts = silent_room
    for c in waiting:
        if c.status in ("silent", "stuck"):
            parts.append(silent_words(c))
        elif c.status == "no rise":
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
        elif c.half_width_C <= settings.tolerance_C:
            # within the tolerance at its latest check, the second in a row still to come
            parts.append(
                f"{c.sensor}: T∞ {c.steady_C:.2f} °C, {settings.decision_level * 100:g} % interval {c.low_C:.2f} to "
                f"{c.high_C:.2f} °C, within ±{settings.tolerance_C:g} °C of T∞ at its latest check; confirming at its "
                "next"
            )
        else:
            bounds = (
                f"interval {c.low_C:.2f} to {c.high_C:.2f} °C"
                if math.isfinite(c.low_C) and math.isfinite(c.high_C)
                else "interval not yet bounded"
            )
            parts.append(
                f"{c.sensor}: T∞ {c.steady_C:.2f} °C, {settings.decision_level * 100:g} % {bounds}, reaching beyond "
                f"±{settings.tolerance_C:g} °C of T∞ ({c.ends})"
                + _room_bound_clause(c, settings)
                + _room_lag_clause(c, settings)
            )
    learn = (
        ", or learn the reference again from a complete run of this machine as it is now (mtident thermal learn)"
        if dropped
        else ", or give a reference run of this machine (mtident thermal learn)"
    )
    failed = [c.sensor for c in waiting if c.status in ("silent", "stuck")]
    # a failed sensor's interval does not narrow with time, a room, or a reference: it is to be mended or left out
    waiting = [c for c in waiting if c.sensor not in failed]
    mend = (
        f"check {', '.join(failed)} (its readings say nothing of its temperature now), or leave "
        f"{'it' if len(failed) == 1 else 'them'} out of the sensors the test waits for (`wait_for` the others)"
    )
    if not waiting:
        return (*_rooms_part_once(parts), f"{WAYS_ON}{mend}.")
    ways = "continue the test" + ("" if settings.reference is not None else learn)
    largest = settings.robust.max_time_constant_min
    if settings.reference is None and any(ends_at_the_largest(c.ends, largest) for c in waiting):
        ways += (
            f"; where a mode of about {largest:g} min sets an end, and this machine has none that slow, say the "
            "slowest it has (`max_time_constant_min`): the answer then assumes it"
        )
        if not settings.robust.heat_enters_at:
            ways += (
                "; or, for a sensor that sits where the heat enters, without a lag of its own, in a still room, say so "
                "(`heat_enters_at`): a slow mode must then already show in its rise"
            )
    room = (
        "state a smaller room wander if the room is steadier than assumed (0 for a steady room), or log the room "
        "beside the sensors and name it as the room sensor (the fit then follows the room instead of assuming it; "
        "without a reference run, a slow mode may still keep the interval open)"
    )
    if any(_room_lag_clause(c, settings) for c in waiting):
        ways += (
            "; a machine follows a drifting or cycling room behind it by the room's rate times a lag that the "
            "reference run did not pin down, and that allowance shrinks as the room moves less"
        )
    bound = [c.sensor for c in waiting if _room_bound(c, settings)]
    slow = [c.sensor for c in waiting if _room_wander_C(c, settings) > 0 and c.sensor not in bound]
    if bound:
        others = len(bound) < len(waiting)
        ways = f"for {', '.join(bound)}, {room}" + (f"; for the others, {ways}" if others else "")
    elif slow:
        ways += f"; for {', '.join(slow)}, also {room}"
    if failed:
        ways += f"; {mend}"
    return (*_rooms_part_once(parts), f"{WAYS_ON}{ways}.")


WAYS_ON = "Ways on: "
"""How the last of :func:`reason_lines` begins: the ways on follow it (a report takes them from there)."""


def _rooms_part_once(parts: list[str]) -> list[str]:
    """The parts with what the room's part of an interval's end is said at its first only."""
    out, said = [], set()
    for part in parts:
        for words in (ROOMS_PART_LOGGED, ROOMS_PART_UNLOGGED):
            if words in part:
                part = part.replace(words, "") if words in said else part
                said.add(words)
        out.append(part)
    return out


def _room_lag_clause(check: SensorCheck, settings: MonitorSettings) -> str:
    """Where the machine model's allowance for its lag behind a moving room alone takes half the
    tolerance or more, that it does: the room then keeps the machine model from pinning T∞ down,
    however well the readings fit (the interval shown can be narrower: the sensor's own)."""
    lag = ndtri(0.5 + settings.decision_level / 2.0) * check.room_lag_C
    if lag < 0.5 * settings.tolerance_C:
        return ""
    return f"; the machine model's interval carries ±{lag:.2f} °C for the room's move alone"


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


def _said_of(check: SensorCheck, warned: tuple[tuple[str, str], ...]) -> tuple[str, ...]:
    """A sensor's warnings: its latest check's, then each said of it earlier that the latest check
    no longer has, with when it was said (as stderr said it): a warning its latest answer no longer
    bears (the reference not followed at 230 min, followed again since) reads as of its time."""
    # an earlier warning the latest check says again with other figures (flat "within 0.15 °C" at
    # 81 min, "within 0.13 °C" at 600) is said once, as of now
    current = {_figures_out(text) for text in check.warnings}
    earlier = [
        text for name, text in warned if name == check.sensor and _figures_out(without_time(text)) not in current
    ]
    return tuple(dict.fromkeys([*check.warnings, *earlier]))


def _figures_out(text: str) -> str:
    """A message's words without its figures."""
    return re.sub(r"[-+]?\d+(?:\.\d+)?", "#", text)


def _room_bound(check: SensorCheck, settings: MonitorSettings) -> bool:
    """Whether only the unmeasured room's assumed wander keeps the sensor from the tolerance: its
    readings alone pin T∞ within it, the wander alone does not. No longer test helps."""
    wander = _room_wander_C(check, settings)
    return wander > 0 and _readings_half_width(check, wander) <= settings.tolerance_C


def _sensor_status(c: SensorCheck, settings: MonitorSettings, expected: float, room_measured: bool) -> SensorStatus:
    return SensorStatus(
        sensor=c.sensor,
        waited_for=settings.waits_for(c.sensor),
        status=c.status,
        may_stop=c.may_stop,
        checked_at_min=c.checked_min,
        steady_state_C=c.steady_C,
        steady_state_ci95_C=(c.low95_C, c.high95_C),
        decision_interval_C=(c.low_C, c.high_C),
        equilibrium_time_min=c.equilibrium_time_min,
        modes=tuple(Mode(tau, a) for tau, a in c.modes),
        model_ok=c.model_ok,
        warnings=c.warnings,
        interval_ends=c.ends,
        assumptions=assumptions(settings, c.sensor, room_measured, c.machine_used),
        reference_used=c.reference_used,
        machine_model_used=c.machine_used,
        expected_stop_time_min=expected,
    )
