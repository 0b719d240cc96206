"""One sensor's model-robust answer: where its warm-up begins, its noise, the modal fit and its
interval, and whether to trust it.

The interval of :func:`mtident.thermal.modes.fit_steady_state` covers every sum of modes the
data do not exclude. Here it gets what the readings alone cannot give: the room's unmeasured
wander (without a room sensor), a reference run's time constants (and a check that the test
agrees with them), and the verdict a script reads (``model_ok`` and the warnings). The answer's
types are in :mod:`~mtident.thermal.robust_types` and what it assumes, in words, in
:mod:`~mtident.thermal.assumptions`; the types and the readings' checks are importable from here
as before.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import replace
from typing import Literal

import numpy as np
from scipy.special import chdtri, ndtri

from mtident._typing import FloatArray
from mtident.thermal.lsq import MIN_RISE_C, flat_lead, rise_threshold
from mtident.thermal.measured import fall_from_highest, warm_up_floor_C
from mtident.thermal.modes import (
    Binned,
    ModeFamily,
    SteadyState,
    best_fit,
    bin_samples,
    fit_steady_state,
)
from mtident.thermal.readings import (
    ROOM_LEVEL_FLOOR_C,
    display_resolution,
    noise_sigma,
    quantisation_step,
    rise_threshold_C,
    room_input,
    sampling_interval_min,
    spikes,
)
from mtident.thermal.robust_types import (
    DEFAULT_MAX_MODES,
    MAX_FREE_FAST,
    Assumptions,
    RobustSettings,
    SensorEstimate,
    SensorModes,
    WarningCode,
)

__all__ = [
    "DEFAULT_MAX_MODES",
    "MAX_FREE_FAST",
    "Assumptions",
    "RobustSettings",
    "SensorEstimate",
    "SensorModes",
    "estimate_sensor",
    "free_fast",
    "rise_threshold_C",
    "room_wander_half_width",
    "sampling_interval_min",
    "quantisation_step",
    "spikes",
    "with_fragility",
]

# A reference's time constant is never taken as known better than ±10 %: the study of stopping
# rules found boxes of this size safe, and exact time constants not.
MIN_REFERENCE_BOX = 0.10


# Residuals this much more correlated than noise mean the model does not describe the data: a
# sensor far from the heat in a conduction body (many modes of alternating sign) fitted by three
# modes at a factor of 3 put T∞ 0.7 °C outside a 99 % interval of ±0.08 °C; correct fits rarely
# reach 2.5.
MISFIT_FACTOR = 2.5


# A test whose readings a fit with free time constants describes better than the reference's
# boxes at this level does not follow the reference.
DISAGREEMENT_LEVEL = 0.99


# a boxed time constant within this share of its box's end is held there by the box, not by the data
EDGE_SHARE = 0.005


# how much further than the largest time constant the test of a fit held at it lets a mode reach
SLOWER_REACH = 10.0


# the warnings that make an estimate untrusted (``model_ok`` false)
UNTRUSTING_CODES: frozenset[WarningCode] = frozenset(
    {"misfit", "undetermined", "modes-unresolved", "slower-than-allowed", "fragile", "below-floor"}
)


# With a tolerance to meet, the likelihood-ratio test and the wider families run only where the
# interval is within this many tolerances: beyond, each could only widen an interval that already
# fails the decision, and they cost most of a check (the reference's warning comes at the first
# check that could pass on it, before any stop).
DECISION_MARGIN = 1.0


# Where the readings use every mode of the family beyond chance, one more is allowed, up to this
# many (a fit of six modes costs about ten of four).
MAX_MODES_WHEN_SATURATED = 6


# With a reference, where the readings use every free mode beyond chance, one more is allowed, up
# to this many (each multiplies the reference grid by the free grid's size).
MAX_FREE_WHEN_SATURATED = 3


MIN_BINS = 8


# A regular likelihood's 99 % interval is 1.3 times as wide as its 95 % one. Far wider, the fit is
# nearly as good over a long valley of models between the two levels (slow modes the readings
# barely exclude), and whether the narrower interval covers rests on the χ² calibration alone.
FRAGILE_RATIO = 3.0


def estimate_sensor(
    sensor: str,
    time_min: FloatArray,
    values: FloatArray,
    room_C: FloatArray | None = None,
    settings: RobustSettings = RobustSettings(),
    reference: SensorModes | None = None,
    noise_C: float | None = None,
    refine_within: float | None = None,
    misfit_beyond_C: float = 0.0,
) -> SensorEstimate:
    """The model-robust T∞ of one sensor from all its readings so far.

    Parameters
    ----------
    sensor : str
        The sensor's name (for the messages).
    time_min : ndarray, shape (N,)
        Minutes since the log began.
    values : ndarray, shape (N,)
        Readings (NaN: missing).
    room_C : ndarray, shape (N,), optional
        A room sensor: the room becomes an input of every mode's heat balance.
    settings : RobustSettings
    reference : SensorModes, optional
        The sensor's modes from a reference run of the same machine.
    noise_C : float, optional
        The readings' noise, if known (default: from their fourth differences, at least their
        rounding's).
    refine_within : float, optional
        Refine the intervals off the search grid only where already within this (°C)
        (:func:`~mtident.thermal.modes.fit_steady_state`).
    misfit_beyond_C : float, optional
        Residuals correlated beyond :data:`MISFIT_FACTOR` are a misfit only where their part beyond
        the noise exceeds this (RMS, °C): a reference run learns with the room sensor's own error
        here (:func:`~mtident.thermal.readings.room_error_C`), which every fit's residuals show;
        a test keeps 0, and its answer is not trusted on any such misfit.

    Returns
    -------
    SensorEstimate
    """
    t = np.asarray(time_min, dtype=float)
    y = np.asarray(values, dtype=float)
    valid = np.isfinite(y) if room_C is None else np.isfinite(y) & np.isfinite(room_C)
    if not valid.any():
        return _without_fit(
            sensor,
            "no data",
            0.0,
            0.0,
            float(t[0]) if len(t) else 0.0,
            settings,
            "no valid reading yet"
            if not np.isfinite(y).any()
            else "no reading yet with a valid room reading beside it",
        )
    rounding = max(float(display_resolution(y[:, None])[0]), quantisation_step(y))
    noise = max(float(noise_sigma(y[:, None], t)[0]), rounding / np.sqrt(12.0)) if noise_C is None else noise_C
    notes = _Notes(sensor)
    wild = spikes(y, noise, rounding)
    if wild.any():
        y = np.where(wild, np.nan, y)
        notes.add("spikes", f"{int(wild.sum())} reading(s) left out as spikes (further from their neighbours than 8σ)")
    first = float(np.nanmedian(y[valid & ~wild][:3]))
    rise = float(np.nanmax(np.abs(y - first)))
    threshold = rise_threshold_C(noise, rounding)
    if int((valid & ~wild).sum()) < MIN_BINS:
        return _without_fit(
            sensor,
            "too few readings",
            rise,
            noise,
            float(t[0]),
            settings,
            f"{int((valid & ~wild).sum())} readings: too few for a model",
        )
    if rise < threshold:
        return _without_fit(
            sensor,
            "no rise",
            rise,
            noise,
            float(t[0]),
            settings,
            f"no rise above its noise yet ({rise:.3g} °C from its first level, noise {noise:.2g} °C"
            + (f", readings in steps of {rounding:.2g} °C" if rounding > 0 else "")
            + "): no warm-up to identify",
        )
    room_in = None if room_C is None else room_input(t, np.asarray(room_C, dtype=float))
    # against the room: a rise that a falling room hides is no flat start
    lead = int(flat_lead(t, _above_room(y, room_in)[:, None], np.array([noise]))[0])
    onset = lead if lead < len(t) else 0
    room = None if room_in is None else room_in[onset:]
    binned = bin_samples(t[onset:], y[onset:], room)
    if len(binned) < MIN_BINS:
        return _without_fit(
            sensor,
            "too few readings",
            rise,
            noise,
            float(t[onset]),
            settings,
            f"{len(binned)} reading{'' if len(binned) == 1 else 's'} since its warm-up began: too few for a model",
        )
    fit, reference_used, floor = _fit_above_floor(
        binned,
        (t[onset:], y[onset:], room),
        noise,
        rounding,
        sampling_interval_min(t),
        settings,
        reference,
        notes,
        refine_within,
        max(rise, threshold),
    )
    _say_a_fall(t[onset:], _above_room(y, room_in)[onset:], noise, rounding, room, notes)
    _say_a_jump(t, y, noise, rounding, notes)
    # the floor lifts the low end, never above T∞ itself (the fit's own interval stays around it)
    readings = {q: (min(max(lo, floor), fit.steady_C), hi) for q, (lo, hi) in fit.interval_C.items()}
    intervals = _nested(_with_room_error(fit, readings, room_C is not None, settings))
    misfit = fit.correlation_factor > MISFIT_FACTOR and (
        misfit_beyond_C <= 0.0 or _systematic_C(fit, binned, noise) > misfit_beyond_C
    )
    late = (float(t[onset]), float(rise_threshold(np.array([noise]))[0])) if onset else None
    ok = _verdict(fit, intervals, rise, threshold, late, misfit, notes, room is not None)
    return SensorEstimate(
        sensor,
        "estimated",
        fit,
        float(t[onset]),
        rise,
        noise,
        intervals,
        ok,
        *notes.said(),
        reference_used,
        int(wild.sum()),
        rounding,
        last_min=float(t[np.isfinite(y)][-1]),
    )


def _above_room(values: FloatArray, room: FloatArray | None) -> FloatArray:
    """The readings less the room's change since its first valid level (the readings themselves
    without a room)."""
    if room is None or not np.isfinite(room).any():
        return values
    above: FloatArray = values - (room - room[np.isfinite(room)][0])
    return above


def _fit_above_floor(
    binned: Binned,
    readings: tuple[FloatArray, FloatArray, FloatArray | None],
    noise: float,
    rounding: float,
    interval: float,
    settings: RobustSettings,
    reference: SensorModes | None,
    notes: _Notes,
    refine_within: float | None,
    rise: float,
) -> tuple[SteadyState, bool, float]:
    """The sensor's fit (:func:`_modal_fit`), whether it used the reference, and the floor a
    warm-up does not come down below (``-inf`` where the fit's T∞ lies below it: not trusted).
    A fit with the reference that puts T∞ below the floor is made again without it; a fit whose
    interval the floor brings near a decision, again without the search's shortcuts.
    ``readings``: the times, readings and room since the warm-up began; ``interval``: the log's
    sampling interval (min); ``rise``: the rise so far (an interval wider says nothing)."""

    def searched(modes: SensorModes | None) -> tuple[SteadyState, bool, float]:
        tried = _Notes(notes.sensor)
        fit, used = _modal_fit(binned, noise, interval, settings, modes, tried, refine_within)
        floor = overshoot_floor_C(fit, readings, noise, rounding)
        if _floor_brings_near(fit, floor, settings, refine_within):
            # the search's shortcuts judged the interval far from a decision before the floor lifted
            # its low end: a high end left unrefined, or a wider family left unsearched, would then
            # decide (a new user's bearing sensor in a drifting room said "may stop" 0.31 °C low,
            # its 99 % high end 28.63 °C where the full search finds 29.38)
            tried = _Notes(notes.sensor)
            fit, used = _modal_fit(binned, noise, interval, settings, modes, tried, None)
            floor = overshoot_floor_C(fit, readings, noise, rounding)
        notes.extend(tried)
        return fit, used, floor

    fit, reference_used, floor = searched(reference)
    if reference_used and _below_floor(fit, floor):
        # the reference's modes make this warm-up come down to its T∞: they are not this sensor's
        steady, already = _apart(fit.steady_C, floor)
        notes.add(
            "reference-disagrees",
            f"with the reference's modes its T∞ would be {steady} °C, below where it already is ({already} °C) by "
            f"more than the fit's own error, and a warm-up does not come down: {_why_off_reference(readings[2])}? "
            "This answer does not use it",
        )
        fit, reference_used, floor = searched(None)
    steady, already = _apart(fit.steady_C, floor)
    if _below_floor(fit, floor, rise) and _wider_than(fit, rise):
        notes.add(
            "below-floor",
            f"its best fit puts T∞ at {steady} °C, below where it already is ({already} °C), and a warm-up does not "
            "come down: too few readings yet to tell where it settles (a T∞ below its readings is the fit's, not the "
            "sensor's)",
        )
    elif _below_floor(fit, floor):
        notes.add(
            "below-floor",
            f"its best fit puts T∞ at {steady} °C, below where it already is ({already} °C) by more than the fit's "
            "own error, and a warm-up does not come down: the fit does not describe this sensor's warm-up (a heat "
            "input that changed, a sensor that cooled); its interval is the fit's own, not trusted",
        )
        floor = -np.inf
    return fit, reference_used, floor


# a logged room whose course moves more than this over the log (°C) is no still room: where the heat
# enters, every mode rising is assumed only in a still room
ROOM_STILL_C = 0.05

# a logged room that moved this much (°C) since the warm-up began may be why a test leaves its reference
_ROOM_MOVED_C = 0.1


def _why_off_reference(room_C: FloatArray | None) -> str:
    """What may have taken a sensor off its reference, likeliest first: a room that moved reaches a
    sensor through its modes, and a reference learnt in a steadier room did not see that path (in
    rooms drifting or on a daily cycle the right machine's reference was said to be perhaps another's)."""
    valid = np.empty(0) if room_C is None else room_C[np.isfinite(room_C)]
    moved = float(np.ptp(valid)) if len(valid) else 0.0
    machine = "has the machine changed, or is the reference another machine's"
    if moved < _ROOM_MOVED_C:
        return machine
    return (
        f"the room moved {moved:.2f} °C since this warm-up began, and its moves may reach this sensor by another path "
        f"than the reference run showed; or {machine}"
    )


def _floor_brings_near(fit: SteadyState, floor: float, settings: RobustSettings, refine_within: float | None) -> bool:
    """Whether the fit's interval was far from a decision (the search took its shortcuts,
    :func:`_near_decision`) but is near one with its low end lifted to ``floor``."""
    if refine_within is None or not fit.determined or _near_decision(fit, settings, refine_within):
        return False
    lo, hi = fit.interval_C[max(settings.levels)]
    floored = max(fit.steady_C - max(lo, floor), hi - fit.steady_C)
    return floored <= DECISION_MARGIN * refine_within


def _apart(low: float, high: float) -> tuple[str, str]:
    """Two temperatures (°C) to as many decimals (two to four) as it takes to tell them apart."""
    for decimals in (2, 3):
        if f"{low:.{decimals}f}" != f"{high:.{decimals}f}":
            return f"{low:.{decimals}f}", f"{high:.{decimals}f}"
    return f"{low:.4f}", f"{high:.4f}"


# a fall from the highest level said: beyond this many times the floor's margin, and this share of the rise
_FALL_MARGINS = 2.0
_FALL_SHARE = 0.1


def _say_a_fall(
    time_min: FloatArray,
    values: FloatArray,
    noise: float,
    rounding: float,
    room_C: FloatArray | None,
    notes: _Notes,
) -> None:
    """A warning where the readings (less the logged room's change) came down from their highest
    level by more than their noise and a tenth of their rise: the answer then fits a curve that no
    warm-up at constant heat makes, which a newcomer took for one (the interval alone said it). A
    logged room's range is allowed besides: the machine follows the room late, so its readings less
    the room's change move by up to that much without any change of heat."""
    fall = fall_from_highest(time_min, values)
    span = 0.0 if room_C is None or not np.isfinite(room_C).any() else float(np.nanmax(room_C) - np.nanmin(room_C))
    margin = 4.0 * noise + rounding
    if fall is None or fall.fall_C <= max(_FALL_MARGINS * margin, _FALL_SHARE * fall.rise_C) + span:
        return
    room = "" if room_C is not None else ", or the room cooled (log it: --ambient)"
    notes.add(
        "came-down",
        f"its readings came down {fall.fall_C:.2f} °C from their highest ({fall.highest_C:.2f} °C at t = "
        f"{fall.highest_min:.0f} min): a warm-up at constant heat does not; did the heat input fall (the spindle "
        f"stopped or slowed){room}? The answer fits these readings as they are, not a warm-up",
    )


# a step between two readings said as a jump: at least this (°C), this many times the other steps' 99th
# percentile, and beyond the noise; a warm-up's own first steps stay far within the second
_JUMP_C = 1.0
_JUMP_STEPS = 20.0
# the power-on reading of the common DS18B20 sensor: a sensor that lost power and came back reads it
_POWER_ON_C = 85.0


def _say_a_jump(time_min: FloatArray, values: FloatArray, noise: float, rounding: float, notes: _Notes) -> None:
    """A warning where the readings jump between two readings and stay at the new level (a sensor
    unplugged, replaced or rewired): a new user's sensor went from 23.9 to 85 °C in one step, and the
    answer said only that the fit was poor, with a T∞ of 76.5 °C."""
    ok = np.isfinite(values)
    t, y = time_min[ok], values[ok]
    if len(y) < 10:
        return
    steps = np.diff(y)
    k = int(np.argmax(np.abs(steps)))
    jump = float(steps[k])
    typical = float(np.quantile(np.abs(np.delete(steps, k)), 0.99))
    if abs(jump) < max(_JUMP_C, _JUMP_STEPS * typical, 30.0 * noise + 2.0 * rounding):
        return
    after = y[k + 1 : k + 6]
    if abs(float(np.median(after)) - y[k + 1]) > 0.1 * abs(jump):
        return  # a spike that came back, not a new level
    reset = f" ({_POWER_ON_C:g} °C is a DS18B20's power-on reading)" if abs(y[k + 1] - _POWER_ON_C) < 0.1 else ""
    notes.add(
        "jumped",
        f"its readings jumped {jump:+.2f} °C from t = {t[k]:g} to {t[k + 1]:g} min ({y[k]:.2f} to {y[k + 1]:.2f} °C) "
        f"and stayed there: a warm-up does not; was the sensor unplugged, replaced or rewired?{reset} The answer "
        "fits these readings as they are",
    )


def _modal_fit(
    binned: Binned,
    noise: float,
    interval: float,
    settings: RobustSettings,
    reference: SensorModes | None,
    notes: _Notes,
    refine_within: float | None,
) -> tuple[SteadyState, bool]:
    """The fit within the reference's boxes where the test follows them, else over every model up
    to the largest time constant; and whether the reference was used."""
    rising = notes.sensor in settings.heat_enters_at
    family = ModeFamily(settings.max_time_constant_min, settings.max_modes, every_mode_rises=rising)

    def fit_of(family: ModeFamily) -> SteadyState:
        return fit_steady_state(
            binned,
            noise_C=noise,
            interval_min=interval,
            family=family,
            levels=settings.levels,
            refine_within=refine_within,
        )

    if reference is not None and reference.doubt is not None:
        notes.add(
            "reference-doubtful",
            f"the reference run did not pin this sensor down ({reference.doubt}): the answer does not use it",
        )
        reference = None
    if reference is not None:
        boxes, asked = tuple(max(b, MIN_REFERENCE_BOX) for b in reference.box), free_fast(reference, settings)
        fit, unheld = _widened_while_used(
            fit_of,
            ModeFamily(
                settings.max_time_constant_min,
                len(reference.time_constants_min),
                tuple(reference.time_constants_min),
                boxes,
                free_fast=asked,
            ),
            settings,
            refine_within,
        )
        if fit.family.free_fast > asked and not unheld:
            notes.add(
                "modes-saturated",
                f"the readings use {_every_free(asked)} faster than the reference's beyond chance, so the interval "
                f"allows {fit.family.free_fast}",
            )
        # the free fit costs most of a check: where the boxed answer is far from any decision, the
        # cheap tests alone decide whether to use it
        far = fit.determined and not _near_decision(fit, settings, refine_within)
        why = (
            f"the readings use {_every_free(fit.family.free_fast)} faster than its modes beyond chance"
            if unheld
            else _disagreement(binned, noise, interval, fit, family, likelihood_ratio=not far)
        )
        if why is None:
            return fit, True
        missed = (
            "or did the reference run miss a mode (with no free mode allowed, a sensor lag or a small fast mode it "
            "did not keep is enough)?"
            if free_fast(reference, settings) == 0 and len(reference.time_constants_min) < settings.max_modes
            else "or did the reference run miss a mode?"
        )
        notes.add(
            "reference-disagrees",
            f"this test does not follow the reference's modes ({_taus(reference.time_constants_min)}; {why}): has the "
            f"machine changed, {missed} This answer does not use it",
        )
    moved = 0.0 if binned.room_C is None else float(np.ptp(binned.room_C))
    if rising and moved > ROOM_STILL_C:
        # a moving room's earlier moves reach the sensor through its modes with either sign, and
        # the room's columns assume a machine at the room's first level: the intervals missed
        rising, family = False, replace(family, every_mode_rises=False)
        notes.add(
            "heat-enters-room-moved",
            f"stated as where the heat enters, but the logged room moved {moved:.3f} °C over the log, more than "
            f"{ROOM_STILL_C:g} °C: its moves reach the sensor through modes of either sign, so every mode rising is "
            "not assumed",
        )
    fit, unheld = _widened_while_used(fit_of, family, settings, refine_within)
    if rising and not fit.family.every_mode_rises:
        notes.add(
            "heat-enters-contradicted",
            "stated as where the heat enters, its readings fit better beyond chance with a mode that does not rise (a "
            "lag of its own, a second path of the heat, a change of heat or a fall): it is fitted as any other sensor",
        )
    slower = (
        _slower_than_allowed(binned, noise, interval, fit) if _near_decision(fit, settings, refine_within) else None
    )
    if slower is not None:
        notes.add(
            "slower-than-allowed",
            f"its best fit holds a mode at the largest time constant allowed, {family.max_time_constant_min:g} "
            f"min, and a slower one fits better beyond chance ({slower}): the interval assumes no slower mode. If the "
            "machine may have one, raise --max-time-constant; if the log's times are not minutes, give their unit "
            "(--time-unit)",
        )
    if unheld:
        notes.add(
            "modes-unresolved",
            f"the readings use all {fit.family.max_modes} modes beyond chance: no sum of modes searched here holds "
            "them, and the interval may be too narrow",
        )
    if fit.family.max_modes > family.max_modes:
        notes.add(
            "modes-saturated",
            f"the readings use all {family.max_modes} modes beyond chance, so a sum of {family.max_modes} may not hold "
            f"them: the interval covers sums of up to {fit.family.max_modes} modes",
        )
    return fit, False


def _widened_while_used(
    fit_of: Callable[[ModeFamily], SteadyState],
    family: ModeFamily,
    settings: RobustSettings,
    refine_within: float | None,
) -> tuple[SteadyState, bool]:
    """The fit over ``family``, with one mode more (with a reference, one free mode more) while the
    readings use every mode it allows beyond chance, near a decision only; and whether they still
    do at the most searched (``MAX_MODES_WHEN_SATURATED`` modes, ``MAX_FREE_WHEN_SATURATED`` free
    ones). A reference family of no free modes (the reference said to hold every mode) stays so.

    A hull over a family that cannot hold the truth can exclude it: a conduction body's sensor near
    the heat (four modes spent on its first minutes' transient left its slow rise out), and one
    far from it with a reference (its lag and the body's second mode, both faster than the
    reference's, and two faster still: two free modes left the hull 0.22 °C off the truth)."""
    fit = fit_of(family)
    boxed = family.reference_min is not None
    while (
        settings.more_modes_when_used
        and (family.free_fast > 0 or not boxed)
        and _near_decision(fit, settings, refine_within)
        and _last_mode_needed(fit)
    ):
        if _mode_count(family) >= MAX_MODES_WHEN_SATURATED or family.free_fast >= MAX_FREE_WHEN_SATURATED:
            return fit, True
        family = (
            replace(family, free_fast=family.free_fast + 1)
            if boxed
            else replace(family, max_modes=family.max_modes + 1)
        )
        fit = fit_of(family)
    return fit, False


def _near_decision(fit: SteadyState, settings: RobustSettings, refine_within: float | None) -> bool:
    """Whether a fit's interval may be near a decision: always without a tolerance to meet, else
    where it is within ``DECISION_MARGIN`` tolerances (a wider family only widens it further)."""
    if refine_within is None:
        return True
    return fit.determined and fit.half_width(max(settings.levels)) <= DECISION_MARGIN * refine_within


def _last_mode_needed(fit: SteadyState) -> bool:
    """Whether the family's largest number of modes (with a reference, its boxes and free modes)
    fits better than one mode fewer beyond chance (χ² on 2 degrees of freedom at
    ``DISAGREEMENT_LEVEL``)."""
    most = _mode_count(fit.family)
    if not fit.determined or most not in fit.fits or most - 1 not in fit.fits:
        return False
    statistic = (fit.fits[most - 1] - fit.fits[most]) / fit.noise_C**2
    return statistic > float(chdtri(2, 1.0 - DISAGREEMENT_LEVEL))


def _mode_count(family: ModeFamily) -> int:
    """The most modes a family's model has (with a reference, its boxes and its free modes)."""
    return family.max_modes + (family.free_fast if family.reference_min is not None else 0)


def free_fast(reference: SensorModes, settings: RobustSettings) -> int:
    """How many free modes faster than a reference's a test may add (the total at most
    ``settings.max_modes``, and at most ``settings.free_fast_modes`` and the reference's own
    ``free_fast_modes``).

    Parameters
    ----------
    reference : SensorModes
        The sensor's modes from the reference run.
    settings : RobustSettings

    Returns
    -------
    int
    """
    said = settings.free_fast_modes if reference.free_fast_modes is None else reference.free_fast_modes
    return max(0, min(settings.free_fast_modes, said, settings.max_modes - len(reference.time_constants_min)))


def _disagreement(
    binned: Binned, noise: float, interval: float, boxed: SteadyState, family: ModeFamily, likelihood_ratio: bool = True
) -> str | None:
    """Why the readings do not follow the reference's boxed modes, or None where they do: residuals
    correlated like a misfit, or a fit with free time constants that is better beyond chance (a
    likelihood-ratio test at ``DISAGREEMENT_LEVEL``; a mode the reference run missed shows here
    long before the residuals look correlated)."""
    if boxed.correlation_factor > MISFIT_FACTOR:
        return f"residuals {boxed.correlation_factor:.1f}x as correlated as noise"
    if not boxed.determined:
        return None
    slowest = max(boxed.modes, key=lambda m: m.time_constant_min)
    ceiling = max(
        ref * (1.0 + box) for ref, box in zip(boxed.family.reference_min or (), boxed.family.reference_box, strict=True)
    )
    if slowest.time_constant_min >= ceiling * (1.0 - EDGE_SHARE):
        # at its box's end a poorly determined slow mode may simply drift there: the readings ask for
        # a slower one only where letting it be slower fits better beyond chance
        slower = _likelihood_ratio(binned, noise, interval, boxed, _slowest_box_opened(boxed.family), 1)
        if slower is not None:
            return (
                f"the slowest mode's time constant is held at its box's upper end, {ceiling:.3g} min, and a slower "
                f"one fits better beyond chance ({slower})"
            )
    if not likelihood_ratio:
        return None
    free = _likelihood_ratio(binned, noise, interval, boxed, family, None)
    return None if free is None else f"free time constants fit better beyond chance: {free}"


def _likelihood_ratio(
    binned: Binned, noise: float, interval: float, boxed: SteadyState, family: ModeFamily, extra: int | None
) -> str | None:
    """The χ² of the best fit of ``family`` against the boxed fit, where it exceeds its quantile at
    ``DISAGREEMENT_LEVEL`` (``extra`` degrees of freedom; default: the difference in parameters),
    in words; None where it does not."""
    rss, n_params, factor = best_fit(binned, noise_C=noise, interval_min=interval, family=family)
    dof = len(binned) - n_params
    extra = n_params - (1 + 2 * len(boxed.modes)) if extra is None else extra
    if dof < 2 or extra < 1:
        return None
    sigma2 = max(rss / dof, noise**2) * factor
    statistic = (boxed.rss - rss) / sigma2
    if statistic > float(chdtri(extra, 1.0 - DISAGREEMENT_LEVEL)):
        return f"χ² {statistic:.1f} on {extra} degree(s) of freedom"
    return None


def _slower_than_allowed(binned: Binned, noise: float, interval: float, fit: SteadyState) -> str | None:
    """Where the best fit holds its slowest mode at the largest time constant allowed, whether a
    family reaching ``SLOWER_REACH`` times further fits better beyond chance (the χ² in words), or
    None. The bound is the interval's stated assumption; readings that push against it, a slower
    mode than the machine was said to have or a log's seconds read as minutes, contradict it."""
    if not (fit.determined and fit.slowest_time_constant_min() >= fit.family.max_time_constant_min * (1 - EDGE_SHARE)):
        return None
    opened = replace(fit.family, max_time_constant_min=fit.family.max_time_constant_min * SLOWER_REACH)
    return _likelihood_ratio(binned, noise, interval, fit, opened, 1)


def _slowest_box_opened(family: ModeFamily) -> ModeFamily:
    """The reference family with its slowest box reaching up to the largest time constant."""
    taus, boxes = list(family.reference_min or ()), list(family.reference_box)
    k = int(np.argmax(taus))
    low, high = taus[k] * (1.0 - boxes[k]), max(family.max_time_constant_min, taus[k] * (1.0 + boxes[k]))
    taus[k], boxes[k] = (low + high) / 2.0, (high - low) / (high + low)
    return replace(family, reference_min=tuple(taus), reference_box=tuple(boxes))


def _every_free(count: int) -> str:
    return "the one free mode" if count == 1 else f"all {count} free modes"


def _taus(taus: tuple[float, ...]) -> str:
    return "τ " + ", ".join(f"{x:.3g}" for x in taus) + " min"


def _below_floor(fit: SteadyState, floor: float, rise: float | None = None) -> bool:
    """Whether the fit's T∞ lies below the floor by more than one of its standard errors (from
    its narrowest interval's upper half-width): the fit describes a warm-up that comes down. With
    the ``rise`` so far, a fit whose interval is wider than it lies below the floor by any amount:
    its error says nothing (a real 1-s log 4 min into its warm-up, at 53.1 °C, was given T∞ 31.3 °C
    with an interval of 31.3 to 258 °C, a curve that comes down by 22 °C, said only "not
    determined")."""
    if not np.isfinite(floor) or not fit.interval_C:
        return False
    if rise is not None and _wider_than(fit, rise):
        return bool(floor > fit.steady_C)
    level = min(fit.interval_C)
    se = (fit.interval_C[level][1] - fit.steady_C) / float(ndtri(0.5 + level / 2.0))
    return bool(floor > fit.steady_C + max(se, 0.0))


def _wider_than(fit: SteadyState, rise: float) -> bool:
    """Whether the fit's narrowest interval is wider than the ``rise`` so far (or unbounded)."""
    lo, hi = fit.interval_C[min(fit.interval_C)]
    return not np.isfinite(hi - lo) or hi - lo > rise


def overshoot_floor_C(
    fit: SteadyState, readings: tuple[FloatArray, FloatArray, FloatArray | None], noise_C: float, rounding_C: float
) -> float:
    """:func:`~mtident.thermal.measured.warm_up_floor_C` of a determined fit (−inf otherwise), of
    ``readings``: the times, readings and room since the warm-up began."""
    if not fit.determined:
        return -np.inf
    return warm_up_floor_C(fit.steady_C, *readings, noise_C, rounding_C)


def _with_room_error(
    fit: SteadyState, readings: dict[float, tuple[float, float]], room_measured: bool, settings: RobustSettings
) -> dict[float, tuple[float, float]]:
    """The intervals the readings give, widened by what the room adds that they cannot narrow: an
    unmeasured room's wander (its random walk over the last slowest-mode time constant, since the
    warm-up began, is not yet in the readings, and moves the steady state at the room's level with
    it), or a measured room's level error (:data:`~mtident.thermal.readings.ROOM_LEVEL_FLOOR_C`)."""
    if not fit.determined or not (room_measured or settings.room_wander_C_per_h > 0):
        return dict(readings)
    out = {}
    for q, (lo, hi) in readings.items():
        extra = (
            float(ndtri(0.5 + q / 2.0)) * ROOM_LEVEL_FLOOR_C
            if room_measured
            else room_wander_half_width(fit.slowest_time_constant_min(), q, settings)
        )
        # each end moves out by what the room adds to its distance from T∞ in quadrature (a low
        # end lifted above a T∞ that comes down, to where the sensor already is, by the room's part itself)
        below, above = max(fit.steady_C - lo, 0.0), max(hi - fit.steady_C, 0.0)
        out[q] = (lo - _widening(below, extra), hi + _widening(above, extra))
    return out


def _widening(distance: float, extra: float) -> float:
    """How far an interval end at ``distance`` from T∞ moves out with ``extra`` added in quadrature
    (an open end stays where it is)."""
    return float(np.hypot(distance, extra) - distance) if np.isfinite(distance) else 0.0


def room_wander_half_width(slowest_time_constant_min: float, level: float, settings: RobustSettings) -> float:
    """How far the unmeasured room's stated wander alone moves T∞ at ``level``: its random walk
    over the slowest mode's time constant (at most the largest allowed). The readings cannot
    narrow it: where it is wider than a tolerance, no longer test meets that tolerance.

    Parameters
    ----------
    slowest_time_constant_min : float
        The sensor's slowest mode (min).
    level : float
        The interval's level (0.95, 0.99).
    settings : RobustSettings
        The room's wander and the largest time constant.

    Returns
    -------
    float
        The half-width (°C) the wander alone adds in quadrature; 0 where no wander is assumed.
    """
    memory = min(slowest_time_constant_min, settings.max_time_constant_min)
    sd = settings.room_wander_C_per_h * np.sqrt(max(memory, 0.0) / 60.0)
    answer: float = float(ndtri(0.5 + level / 2.0)) * sd
    return answer


def _nested(intervals: dict[float, tuple[float, float]]) -> dict[float, tuple[float, float]]:
    """The intervals with each level's inside every higher level's: a higher level reaches at
    least as far as a lower level's finite end (each level's search is its own, and one that
    stopped short is widened, never the other narrowed), and a lower level's end the search left
    open (infinite) is bounded by the higher level's end."""
    out = dict(intervals)
    levels = sorted(intervals)
    for lower, higher in zip(levels, levels[1:], strict=False):
        (lo, hi), (outer_lo, outer_hi) = out[lower], out[higher]
        out[higher] = (
            min(outer_lo, lo) if np.isfinite(lo) else outer_lo,
            max(outer_hi, hi) if np.isfinite(hi) else outer_hi,
        )
    outer = (-np.inf, np.inf)
    for q in reversed(levels):
        lo, hi = out[q]
        out[q] = outer = (max(lo, outer[0]), min(hi, outer[1]))
    return dict(sorted(out.items()))


class _Notes:
    """A sensor's warnings as they are found, each with its code."""

    def __init__(self, sensor: str) -> None:
        self.sensor = sensor
        self.codes: list[WarningCode] = []
        self.texts: list[str] = []

    def add(self, code: WarningCode, text: str) -> None:
        self.codes.append(code)
        self.texts.append(f"{self.sensor}: {text}")

    def extend(self, other: _Notes) -> None:
        self.codes += other.codes
        self.texts += other.texts

    def said(self) -> tuple[tuple[str, ...], tuple[WarningCode, ...]]:
        return tuple(self.texts), tuple(self.codes)


def _systematic_C(fit: SteadyState, binned: Binned, noise: float) -> float:
    """The residuals' part beyond the readings' noise, per reading (RMS, °C)."""
    dof = float(binned.count.sum()) - (len(binned) - fit.dof)
    return math.sqrt(max(fit.rss / max(dof, 1.0) - noise**2, 0.0))


def _verdict(
    fit: SteadyState,
    intervals: dict[float, tuple[float, float]],
    rise: float,
    threshold: float,
    late_start: tuple[float, float] | None,
    misfit: bool,
    notes: _Notes,
    room_measured: bool = False,
) -> bool:
    """``model_ok`` of one fitted sensor; its warnings go to ``notes``. ``misfit``: residuals
    correlated beyond :data:`MISFIT_FACTOR` (and beyond what :func:`estimate_sensor`'s
    ``misfit_beyond_C`` allows); ``late_start``: where a late warm-up began (min) and how far from its
    first level the readings stayed till then (°C); ``room_measured``: those are the readings less
    the room's."""
    ok = fit.determined and not UNTRUSTING_CODES & set(notes.codes)
    if late_start is not None:
        flat = "flat against the room" if room_measured else "flat"
        onset_min, within = late_start
        notes.add(
            "late-start",
            f"{flat} until t = {round(onset_min, 1):g} min, within {within:.2g} °C of its first level (the larger of "
            f"{MIN_RISE_C:g} °C and six times its noise): the heat reached this sensor only then, as it reaches one "
            "far from the heat; the warm-up began after the log; or a partly warm sensor moved too slowly to show "
            "sooner. The modes are counted from there",
        )
    if misfit:
        ok = False
        notes.add(
            "misfit",
            f"the residuals are {fit.correlation_factor:.1f}x as correlated as noise: no sum of up to "
            f"{fit.family.max_modes} modes describes these readings well (the interval is widened by that factor's "
            "square root)",
        )
    level = min(intervals)
    lo, hi = intervals[level]
    # an interval as wide as the whole rise so far does not say where the sensor settles
    if not np.isfinite(hi - lo) or hi - lo > max(rise, threshold):
        ok = False
        interval = (
            f"{level * 100:g} % interval {lo:.2f} to {hi:.2f} °C, wider than the rise so far"
            if np.isfinite(hi - lo)
            else f"its {level * 100:g} % interval not yet bounded"
        )
        notes.add("undetermined", f"T∞ not determined yet ({interval})")
    return ok


def with_fragility(estimate: SensorEstimate) -> SensorEstimate:
    """The estimate, not trusted where its narrowest interval is fragile: the widest level's
    interval more than ``FRAGILE_RATIO`` times as wide. A report reads the narrowest interval; a
    decision made at the widest level rests on that level alone and needs no such verdict.

    Parameters
    ----------
    estimate : SensorEstimate

    Returns
    -------
    SensorEstimate
        ``estimate`` itself, or a copy with ``model_ok`` False and the warning added.
    """
    if estimate.fit is None or len(estimate.interval_C) < 2:
        return estimate
    level, widest = min(estimate.interval_C), max(estimate.interval_C)
    (lo, hi), (wide_lo, wide_hi) = estimate.interval_C[level], estimate.interval_C[widest]
    if not (np.isfinite(wide_hi - wide_lo) and wide_hi - wide_lo > FRAGILE_RATIO * (hi - lo)):
        return estimate
    text = (
        f"{estimate.sensor}: the {level * 100:g} % interval ({lo:.2f} to {hi:.2f} °C) is fragile: models fitting "
        f"nearly as well reach {wide_lo:.2f} to {wide_hi:.2f} °C at {widest * 100:g} %"
    )
    return replace(
        estimate,
        model_ok=False,
        warnings=(*estimate.warnings, text),
        warning_codes=(*estimate.warning_codes, "fragile"),
    )


def _without_fit(
    sensor: str,
    status: Literal["no data", "no rise", "too few readings"],
    rise: float,
    noise: float,
    onset: float,
    settings: RobustSettings,
    why: str,
) -> SensorEstimate:
    wide = {q: (-np.inf, np.inf) for q in settings.levels}
    return SensorEstimate(
        sensor, status, None, onset, rise, noise, wide, False, (f"{sensor}: {why}",), (_WITHOUT_FIT_CODES[status],)
    )


# the warning code of each status without a fit
_WITHOUT_FIT_CODES: dict[str, WarningCode] = {
    "no data": "no-data",
    "no rise": "no-rise",
    "too few readings": "too-few-readings",
}
