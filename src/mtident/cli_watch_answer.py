"""How ``mtident thermal watch`` writes its answer on a terminal: the status table, the verdict,
why not yet and when a stop is expected, and a replay's comparison with the rest of its log.

The answer itself comes from :meth:`~mtident.thermal.session.WatchSession.answer`; this module only
words it (``--json`` prints the same answer as an object).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path

import numpy as np
from rich.table import Table

from mtident.cli import OptionConsole, cell_text, column_layout, plain, print_json, prose_console, stderr, table_console
from mtident.cli_thermal import reference_lines
from mtident.io.logs import log_name
from mtident.thermal.hindsight import Hindsight
from mtident.thermal.hindsight_words import no_level_words, settle_timing, stuck_sensors
from mtident.thermal.monitor import assumptions, minutes
from mtident.thermal.monitor_answer import WatchAnswer
from mtident.thermal.monitor_types import SensorCheck
from mtident.thermal.session import WatchSession

__all__ = ["print_answer", "status_table"]


def print_answer(
    session: WatchSession,
    path: Path,
    replay: bool,
    as_json: bool,
    live: bool,
    forecast: bool = True,
    cancel: Callable[[], bool] | None = None,
    whole: tuple[np.ndarray, np.ndarray, np.ndarray | None] | None = None,
    interrupted: bool = False,
) -> None:
    """The decision: the JSON object, or the table, the verdict and what it rests on (with the
    expected stops where ``forecast``, unless ``cancel`` stops them); ``whole``: the log already
    read again whole (:meth:`WatchSession.whole_log`), for the replay's hindsight; ``interrupted``:
    Ctrl-C ended the watch (a replay's log does not end there)."""
    state = session.state
    if forecast and state is not None and not state.stopped and not session.forecast_made:
        # seconds a sensor, a minute or more for a machine: said, or the terminal falls silent
        stderr.print(
            f"mtident: forecasting each sensor's expected stop ({len(state.sensors)} sensors, seconds each)",
            highlight=False,
        )
    outcome = session.answer(with_forecast=forecast, cancel=cancel)
    # the comparison with the rest of a replayed log fits again: not after a SIGTERM, nor of a replay
    # interrupted before its log's end
    hindsight = (
        session.hindsight(whole) if replay and not interrupted and not (cancel is not None and cancel()) else None
    )
    if hindsight is not None:
        outcome = replace(
            outcome,
            time_saved_min=hindsight.time_saved_min,
            settle_time_min=hindsight.test_settle_time_min,
            hindsight=hindsight.answer(),
        )
        stderr.print(
            f"mtident: the log runs on to t = {minutes(hindsight.log_end_min)}: comparing the decision with how "
            "it went on",
            highlight=False,
        )
    if as_json:
        print_json(outcome)
        return
    table_console().print(status_table(session, path))
    console = prose_console()
    _print_assumed(console, session)
    state = session.state
    assert state is not None
    if state.stopped:
        saved = outcome.time_saved_min
        gain = (
            f"; {minutes(saved)} before the readings settled within the tolerance"
            if saved is not None and saved > 0
            else ""
        )
        console.print(f"[bold green]The test can stop at t = {minutes(state.stop_time_min)}{gain}.[/]")
        if live:
            console.bell()  # the engineer may be at the other end of the machine
        if hindsight is not None:
            _print_hindsight(hindsight)
        return
    _print_not_yet(console, outcome, state.readings.latest_min, replay, interrupted)
    _print_expected(console, outcome, state.readings.latest_min, state.readings.room_C is not None)


def _print_assumed(console: OptionConsole, session: WatchSession) -> None:
    """What the answer assumes: the model, the slowest time constant, the room, and each sensor's
    reference (or that the test contradicted it)."""
    state = session.state
    assert state is not None
    said = assumptions(session.settings, state.sensors[0], state.readings.room_C is not None)
    console.print(
        f"Assumes: {said.model}, time constants up to {said.max_time_constant_min:g} min; room {said.room}",
        highlight=False,
    )
    if session.settings.reference is not None and state.reference_dropped:
        console.print("  reference: not used (the test contradicted it; see the warning above)", highlight=False)
    elif session.settings.reference is not None:
        # each sensor has its own modes in the reference, or none, or doubtful ones
        taken = [(name, assumptions(session.settings, name).reference or "") for name in state.sensors]
        for line in reference_lines(taken):
            console.print(line, highlight=False)


def _print_not_yet(console: OptionConsole, outcome: WatchAnswer, now: float, replay: bool, interrupted: bool) -> None:
    """Why the test may not stop yet (at ``now``, min), and how a longer test or a replay stands."""
    bound = outcome.room_bound_sensors
    if bound:
        console.print(
            f"[bold yellow]Not yet, and a longer test does not bring {', '.join(bound)} within the tolerance.[/]"
        )
        _print_reason(console, outcome.reason_lines or ())
        console.print(
            "(--ambient COLUMN names the room sensor's column; --room-wander states the room's wander in °C an hour)"
        )
        return
    if replay and interrupted:
        console.print(
            f"[bold yellow]Not yet at t = {minutes(now)}, where the replay was interrupted (--resume continues it).[/]"
        )
    elif replay:
        # a replayed log is whole: there is no running test to keep on
        console.print(f"[bold yellow]Not yet: the log ends at t = {minutes(now)}, before the test may stop.[/]")
    else:
        console.print("[bold yellow]Not yet: keep the test running.[/]")
    _print_reason(console, outcome.reason_lines or ())


def _print_expected(console: OptionConsole, outcome: WatchAnswer, now: float, room: bool) -> None:
    """When the test is expected to stop on the best model's course (``room``: a room sensor is
    logged), or which sensors waited for have no expected stop."""
    expected = outcome.expected_stop_time_min
    if expected is not None and math.isfinite(expected):
        # the forecast holds a logged room at its latest level: a room that keeps drifting keeps its
        # lag's allowance, which no course of the machine narrows
        console.print(
            f"Expected stop: t ≈ {minutes(round(expected))} on the best model's course"
            + (", the room held at its latest level" if room else "")
            + " (a slower mode that still fits"
            + (", or a room that keeps moving," if room else "")
            + " moves it later).",
            highlight=False,
        )
    elif expected is not None and outcome.decision != "stop":
        waited = [s for s in outcome.sensors if s.waited_for]
        stops = {s.sensor: s.expected_stop_time_min or math.nan for s in waited}
        status = {s.sensor: s.status for s in waited}
        none = [f"{name} ({status[name]})" for name, stop in stops.items() if not math.isfinite(stop)]
        found = sorted(round(stop) for stop in stops.values() if math.isfinite(stop))
        who = f"{', '.join(none)} {'has' if len(none) == 1 else 'have'}" if none else "a sensor waited for has"
        console.print(
            f"Expected stop: none found; {who} none on the best model's course (the interval does not come "
            f"within the tolerance there, or the status gives no course to go on){_others_stops(found, now)}.",
            highlight=False,
        )


def _others_stops(found: list[int], now: float) -> str:
    """Where the other sensors waited for expect their stops (``found``: sorted minutes): those to
    come, and those that may stop already (their expected stop is the time they became ready)."""
    come = [t for t in found if t > now]
    ready = [t for t in found if t <= now]
    words = ""
    if len(come) == 1:
        words += f"; the other's comes at t ≈ {minutes(come[0])}"
    elif come:
        span = minutes(come[0]) if come[0] == come[-1] else f"{minutes(come[0])} to {minutes(come[-1])}"
        words += f"; the others' come at t ≈ {span}"
    if ready:
        who = "one other" if len(ready) == 1 else f"{len(ready)} others"
        words += f"; {who} may stop already (since t ≈ {minutes(ready[0])})"
    return words


def status_table(session: WatchSession, path: Path) -> Table:
    """Per sensor: the latest reading (°C), when it was last checked (min: a sensor is checked when
    it falls due, not at every reading), T∞ with its 95 % interval and the decision's, t_eq,
    status."""
    state = session.state
    where = "before the first sample" if state is None else f"at t = {minutes(state.readings.latest_min)}"
    table = Table(title=f"{log_name(path.name, session.sheet)}: {where} (temperatures in °C, times in min)")
    level = f"{session.settings.decision_level * 100:g} %"
    columns = ("sensor", "latest", "checked", "T∞", "95 % interval", f"{level} interval", "t_eq")
    for column in (*columns, "status"):
        table.add_column(column, justify="left" if column in ("sensor", "status") else "right", **column_layout(column))
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
            if check.status in ("misfit", "silent")
            else "white"
        )
        table.add_row(
            plain(check.sensor),
            cell_text(latest),
            cell_text(check.checked_min, 0),
            cell_text(check.steady_C),
            f"{cell_text(check.low95_C)} to {cell_text(check.high95_C)}",
            f"{cell_text(check.low_C)} to {cell_text(check.high_C)}",
            cell_text(check.equilibrium_time_min, 0),
            f"[{colour}]{_status_words(check)}[/]",
        )
    return table


def _status_words(check: SensorCheck) -> str:
    """The status, and for a sensor that failed since when: its "latest" reading is a stuck
    sensor's repeat, or a silent one's last, not where the sensor is now."""
    if check.status in ("stuck", "silent") and math.isfinite(check.last_reading_min):
        return f"{check.status} from {minutes(check.last_reading_min)}"
    return check.status


def _span(values: np.ndarray) -> str:
    """``+0.06 to +0.07``, or one value where they round alike."""
    low, high = f"{float(values.min()):+.2f}", f"{float(values.max()):+.2f}"
    return low if low == high else f"{low} to {high}"


def _print_reason(console: OptionConsole, lines: tuple[str, ...]) -> None:
    """Why the test cannot stop yet, a line for each sensor that holds it (a machine's eight sensors
    read as one paragraph of 3,000 characters), then the ways on."""
    for line in lines:
        indent = "" if line.startswith("Ways on:") or len(lines) == 1 else "  "
        console.print(f"{indent}{line}", highlight=False)


def _print_hindsight(hindsight: Hindsight) -> None:
    """The table of the decision against the rest of the log, and what it comes to."""
    shift = hindsight.room_shift_C
    added = hindsight.shift_C[np.isfinite(hindsight.shift_C)]
    # a room level again at the end can still have moved the sensors, which follow it late
    moved = bool(len(added) and np.any(np.abs(added) >= 0.005))  # as the sentence shows it, two decimals
    room = (
        f"; the room moved {shift:+.2f} °C from the stop to the end, but each sensor follows the room late, "
        f"through its modes, and still follows its moves before the stop: {_span(added)} °C added to T∞ at the "
        "stop, to where the room, as the sensor follows it, stands at the log's end"
        if moved
        else ""
    )
    prose_console().print(
        f"Against the rest of the log (to t = {minutes(hindsight.log_end_min)}){room}:", highlight=False
    )
    table = Table()
    # with the room's move added in the column itself, the difference is the next two columns'
    stop_column = "T∞ at stop, room followed (°C)" if moved else "T∞ at stop (°C)"
    for column in ("sensor", stop_column, "settled (°C)", "difference (°C)", "settled by (min)"):
        table.add_column(column, justify="right" if column != "sensor" else "left", **column_layout(column))
    settled = hindsight.checked
    settle_times = (
        np.full(len(hindsight.sensors), math.nan)
        if hindsight.settle_time_min is None
        else np.asarray(hindsight.settle_time_min, dtype=float)
    )
    # the settle time is read off the readings less the room, which settle where the readings
    # themselves keep following a moving room: checked against their rise above the room as they
    # follow it where the sensor's modes at the stop give that course, else no level to check
    followed = hindsight.settled_with_room
    with_room = hindsight.following_room
    # a sensor that stuck before it settled has no level: its failure, not the log's length
    stuck = ~settled & np.isfinite(hindsight.stuck_since) & ~with_room
    for i, name in enumerate(hindsight.sensors):
        error = hindsight.error_C[i]
        shown = cell_text(float(error)) if settled[i] else "—"
        if settled[i] and not hindsight.within[i]:
            shown = f"[yellow]{shown}[/]"
        level = float(hindsight.settled_C[i])
        cell = (
            f"{cell_text(level)} (room)"
            if followed[i]
            else cell_text(level)
            if math.isfinite(level)
            else "with the room"
            if with_room[i]
            else f"stuck from {hindsight.stuck_since[i]:.0f} min"
            if stuck[i]
            else "not yet"
        )
        table.add_row(
            plain(name),
            cell_text(float(hindsight.steady_state_C[i] + hindsight.shift_C[i])),
            cell,
            shown,
            cell_text(float(settle_times[i]), 0),
        )
    table_console().print(table)
    if followed.any():
        prose_console().print(
            "(room): the readings keep following the room; where their rise above the room, as they follow it "
            "through the sensor's modes at the stop, settled, at the room's course at the log's end.",
            highlight=False,
        )
    if with_room.any():
        prose_console().print(
            "with the room: the readings keep following the room; from the time shown they stayed within the "
            "tolerance of their equilibrium at the room's level (or, where they lag the room by more than that to "
            "the log's end, their rise above the room as they follow it did): no settled level to check T∞ against.",
            highlight=False,
        )
    timing = settle_timing(hindsight)
    stuck_words = (
        "stuck at one value before they settled (their repeats say nothing of the temperature): "
        + ", ".join(f"{name} from t = {minutes(float(since))}" for name, since in stuck_sensors(hindsight, stuck))
        if stuck.any()
        else ""
    )
    if not settled.any():
        # readings that keep following a moving room have not failed to settle: the log can be long
        why = no_level_words(hindsight, hindsight.not_settled, bool(with_room.any()), stuck_words)
        prose_console().print(
            f"{why}: nothing to check the decision against" + (f"; {timing}." if timing else "."), highlight=False
        )
        return
    unsettled = hindsight.not_settled
    verdict = hindsight.verdict_words()
    not_settled = f"; not settled by the log's end: {', '.join(unsettled)}" if unsettled else ""
    failed = f"; {stuck_words}" if stuck_words else ""
    prose_console().print(
        f"{verdict[0].upper()}{verdict[1:]}" + (f"; {timing}" if timing else "") + f"{not_settled}{failed}.",
        highlight=False,
    )
