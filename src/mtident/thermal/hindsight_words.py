"""The check against the rest of the log in words: why a sensor has no settled level, which stuck,
and when the readings settled against the stop (the time the rule saved). A terminal, a report
or a notebook says them alike."""

from __future__ import annotations

import numpy as np

from mtident.thermal.hindsight import Hindsight
from mtident.thermal.monitor_types import minutes

__all__ = ["no_level_words", "settle_timing", "stuck_sensors"]


def no_level_words(hindsight: Hindsight, late: list[str], with_room: bool, stuck_words: str) -> str:
    """Why no sensor has a settled level to check T∞ against: the log ends before the ``late`` ones
    settled, the others follow the room, or stuck (``stuck_words``)."""
    if late:
        who = "its sensors" if len(late) == len(hindsight.sensors) else ", ".join(late)
        return (
            f"The log ends before {who} settled (settled: moving less than {hindsight.tolerance_C / 2:g} °C over the "
            f"log's last quarter, with under {hindsight.tolerance_C / 4:g} °C still to come at the pace of its "
            "slowest mode, a move its readings' display step could hide counted in)"
            + ("; the others' readings keep following the room" if with_room else "")
            + (f"; {stuck_words}" if stuck_words else "")
        )
    if stuck_words and not with_room:
        return f"Every sensor's readings are {stuck_words}"
    if stuck_words:
        return "Every sensor's readings keep following the room to the log's end, or stuck: no settled level"
    return "Every sensor's readings keep following the room to the log's end: no settled level"


def stuck_sensors(hindsight: Hindsight, stuck: np.ndarray) -> list[tuple[str, float]]:
    """The sensors ``stuck`` marks and when each stuck."""
    return [
        (name, float(since))
        for name, since, flag in zip(hindsight.sensors, hindsight.stuck_since, stuck, strict=True)
        if flag
    ]


def _settle_unknown(hindsight: Hindsight) -> str:
    """Why t_settle is not known, in words: the log ends before the readings settled; or, with a
    room sensor, the readings levelled off but their rise above the room as each sensor follows it
    had not by the log's end (settle times are read off that rise: a daily room keeps the readings
    themselves moving)."""
    unknown = (
        "the log ends before the readings of every sensor the test waits for settled within the tolerance, "
        "so the time it saved is not known"
    )
    if hindsight.settle_time_min is None:
        return unknown
    waited = np.ones(len(hindsight.sensors), bool) if hindsight.waited is None else np.asarray(hindsight.waited, bool)
    late = waited & ~np.isfinite(np.asarray(hindsight.settle_time_min, dtype=float))
    failed = late & np.isfinite(hindsight.stuck_since)
    if failed.any():
        names = ", ".join(name for name, flag in zip(hindsight.sensors, failed, strict=True) if flag)
        return (
            f"{names} stuck before settling, so when the readings of every sensor the test waits for settled, and "
            "the time the stop saved, is not known"
        )
    levelled = late & np.isfinite(hindsight.settled_C)
    if not late.any() or levelled.sum() < late.sum() or hindsight.sensor_shift_C is None:
        return unknown
    names = ", ".join(name for name, flag in zip(hindsight.sensors, levelled, strict=True) if flag)
    return (
        f"the readings of {names} levelled off by the log's end, but their rise above the room, as each follows "
        "it, was still moving: when they settled within the tolerance, and so the time the stop saved, is not known"
    )


def settle_timing(hindsight: Hindsight) -> str:
    """When the readings settled within the tolerance (t_settle, of the sensors the test waits for),
    against the stop: the time the rule saved over simply waiting."""
    settle = hindsight.test_settle_time_min
    saved = hindsight.time_saved_min
    if saved is None or not np.isfinite(settle):
        return _settle_unknown(hindsight)
    when = (
        f"the readings of every sensor waited for stayed within ±{hindsight.tolerance_C:g} °C of where they settled "
        f"from t = {minutes(settle)}"
    )
    if saved > 0:
        return f"{when}: the stop saved {minutes(saved)} over waiting for that"
    return f"{when}, {minutes(-saved)} before the stop: the rule saved no time"
