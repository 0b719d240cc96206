"""A test's answer from the machine model: every sensor's readings fitted together with the
reference's model (:func:`fit_readings`), and each sensor's own model-robust estimate combined with
it (:func:`combined_estimate`) where the two agree, or widened to hold both where they do not.
"""

from __future__ import annotations

import math
from dataclasses import replace

from mtident._threads import one_blas_thread
from mtident._typing import FloatArray
from mtident.thermal.machine_fit import fit_test
from mtident.thermal.machine_model import MachineFit, MachineModel, machine_readings
from mtident.thermal.modal_types import IntervalEnd, Mode
from mtident.thermal.modes import equilibrium_time
from mtident.thermal.robust import RobustSettings, SensorEstimate, room_wander_half_width

__all__ = ["combined_estimate", "fit_readings", "unmeasured_wander"]

# a sensor's own answer with one of these warnings is not combined with the machine model's
_CONTRADICTED = {"misfit", "reference-disagrees"}


def fit_readings(
    model: MachineModel | None,
    sensors: tuple[str, ...] | list[str],
    time_min: FloatArray,
    values: FloatArray,
    room_C: FloatArray | None,
    levels: tuple[float, ...],
) -> MachineFit | None:
    """:func:`fit_test` on a log's readings so far (:func:`machine_readings`; None without a model)."""
    if model is None:
        return None
    readings = machine_readings(sensors, time_min, values, room_C)
    with one_blas_thread():
        return fit_test(model, readings, levels)


def unmeasured_wander(model: MachineModel | None, room_measured: bool, settings: RobustSettings) -> dict[float, float]:
    """Per level, how far the room's unmeasured wander moves T∞ through the machine model's
    slowest mode (nothing where the room is measured, or without a machine model)."""
    if room_measured or model is None:
        return {}
    slowest = max(model.time_constants_min)
    return {level: room_wander_half_width(slowest, level, settings) for level in settings.levels}


def combined_estimate(
    estimate: SensorEstimate, fit: MachineFit | None, s: int, wander: dict[float, float]
) -> SensorEstimate:
    """The sensor's answer with the machine model's where both agree: T∞ from the machine model,
    each interval the overlap of the two.

    The sensor's own interval must hold the machine model's T∞ at every level; else one of the
    two is wrong (the machine model does not fit the sensor, or the sensor's own modes miss a
    lag or a room path), and the sensor keeps its own T∞ with each interval the hull of the two,
    and says so. Its own T∞ need not lie in the machine model's interval: it is the less certain
    of the two. ``wander`` widens the machine model's half-widths by the room's unmeasured wander
    per level. Where the sensor's own fit puts T∞ above a measured room's level, the machine
    model's interval is held only above that level, where a heated machine settles
    (:func:`_disputed`).
    """
    if fit is None or estimate.fit is None or not fit.used[s] or _CONTRADICTED & set(estimate.warning_codes):
        return estimate
    steady = float(fit.steady_C[s])
    half = {level: float(fit.half_width_C[level][s]) + wander.get(level, 0.0) for level in estimate.interval_C}
    if not all(lo <= steady <= hi for lo, hi in estimate.interval_C.values()):
        return _disputed(estimate, steady, half)
    intervals: dict[float, tuple[float, float]] = {}
    for level, (lo, hi) in estimate.interval_C.items():
        intervals[level] = (max(lo, steady - half[level]), min(hi, steady + half[level]))
    # the machine model determines what the sensor's own curve left open
    kept = [i for i, code in enumerate(estimate.warning_codes) if code != "undetermined"]
    modes = fit.modes[s]
    start = estimate.fit.start_C
    return replace(
        estimate,
        fit=replace(
            estimate.fit,
            steady_C=steady,
            modes=modes,
            origin_min=fit.origin_min,
            room_gains=fit.room_gains[s] if estimate.fit.room_gains else (),
            equilibrium_time_min=equilibrium_time(modes, steady, start, fit.origin_min),
            ends={level: _ends(modes, steady, lo, hi) for level, (lo, hi) in intervals.items()},
            interval_C=intervals,
        ),
        interval_C=intervals,
        model_ok=True,
        warnings=tuple(estimate.warnings[i] for i in kept),
        warning_codes=tuple(estimate.warning_codes[i] for i in kept),
        machine_used=True,
        room_lag_C=0.0 if fit.room_lag_C is None else float(fit.room_lag_C[s]),
    )


def _disputed(estimate: SensorEstimate, steady: float, half: dict[float, float]) -> SensorEstimate:
    """The sensor's own answer where the machine model's T∞ lies outside its interval: each
    interval widened to hold the machine model's too (a PT100 behind its own lag, fitted alone in
    a room read in coarse steps, said "may stop" 0.22 °C off while the machine model held the
    truth), and said.

    Where the sensor's own fit puts T∞ above a measured room's level, only the part of the machine
    model's interval above that level is held: a heated machine settles above its room (every
    equilibrium is the room's level plus ``(−A)⁻¹`` times a heat input, both non-negative), and a
    new user's early check held a column sensor's test open for a T∞ 2 °C below the room. Where
    no part is above it, the sensor's interval is its own."""
    assert estimate.fit is not None  # combined_estimate's caller has a fit
    room = estimate.fit.room_level_C
    floor = room if room is not None and estimate.steady_C > room else -math.inf
    intervals = {}
    for level, (lo, hi) in estimate.interval_C.items():
        low, high = max(steady - half[level], floor), steady + half[level]
        intervals[level] = (min(lo, low), max(hi, high)) if high >= low else (lo, hi)
    below = f" (below the room, {room:.2f} °C, where a heated machine does not settle)" if steady < floor else ""
    if intervals == estimate.interval_C:
        held = "this sensor's answer is its own fit's"
    elif math.isfinite(floor) and steady - max(half.values()) < floor:
        held = "its interval holds both above the room"
    else:
        held = "its interval holds both"
    text = f"{estimate.sensor}: the machine model puts T∞ at {steady:.2f} °C{below}, outside this sensor's own "
    text += f"interval: {held}"
    own = estimate.fit
    ends = {level: _ends(own.modes, own.steady_C, lo, hi) for level, (lo, hi) in intervals.items()}
    return replace(
        estimate,
        fit=replace(own, interval_C=intervals, ends=ends),
        interval_C=intervals,
        warnings=(*estimate.warnings, text),
        warning_codes=(*estimate.warning_codes, "machine-disagrees"),
    )


def _ends(modes: tuple[Mode, ...], steady: float, low: float, high: float) -> tuple[IntervalEnd, IntervalEnd]:
    """The models at an interval's ends: the slowest mode takes up the difference in T∞, so that
    each end's course starts where the best one does."""
    k = max(range(len(modes)), key=lambda i: modes[i].time_constant_min)

    def moved(end: float) -> IntervalEnd:
        shifted = tuple(
            Mode(m.time_constant_min, m.amplitude_C - (end - steady)) if i == k else m for i, m in enumerate(modes)
        )
        return IntervalEnd(end, shifted)

    return moved(low), moved(high)
