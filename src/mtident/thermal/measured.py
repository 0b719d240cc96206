"""What a log itself shows, beside any model: how many samples a window holds, the RMSE of a
curve against every reading (Xia et al. 2014, Eq. 33), and the measured final temperature and
95 %-rise time of a log that ran to equilibrium, and whether it settled. Both identifications
(the papers' filters and the model-robust fit) measure their answers with these.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.io.logs import TemperatureLog, unit_doubted
from mtident.thermal.modal_types import DEFAULT_MAX_TIME_CONSTANT_MIN
from mtident.thermal.model import EQUILIBRIUM_FRACTION
from mtident.thermal.readings import display_resolution

__all__ = [
    "MIN_WINDOW_SAMPLES",
    "SETTLED_MOVE_C",
    "measured_and_settled",
    "measured_equilibrium",
    "rmse",
    "window_samples",
]

MIN_WINDOW_SAMPLES = 6


def rmse(estimate: FloatArray, measured: FloatArray) -> FloatArray:
    """Xia et al. 2014 Eq. 33: sqrt(Σ(Tₑ − Tₒ)²/(M − 1)) over the finite samples, per column.

    Parameters
    ----------
    estimate : ndarray, shape (N, S)
        The identified or predicted temperatures (°C).
    measured : ndarray, shape (N, S)
        The measured temperatures (°C, NaN: missing).

    Returns
    -------
    ndarray, shape (S,)
        The RMSE (°C) over the samples where both are finite; NaN where there is none (a sensor
        with no curve: an RMSE of 0 read as a perfect fit).
    """
    diff = estimate - measured
    ok = np.isfinite(diff)
    count = ok.sum(axis=0)
    sums = np.where(ok, diff**2, 0.0).sum(axis=0)
    return np.where(count > 0, np.sqrt(sums / np.maximum(count - 1, 1)), np.nan)


# a log counts as settled to the tolerance's precision where its last quarter moved less than this
# (°C), half the default tolerance
SETTLED_MOVE_C = 0.1


def measured_and_settled(
    time_min: FloatArray, values: FloatArray, slowest_mode_min: float
) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """The papers' measured final temperature and 95 %-rise time (:func:`measured_equilibrium`
    with its 5 % rule alone), and whether each sensor settled to the tolerance's precision: its last
    quarter moved less than ``SETTLED_MOVE_C``, with at most half that still to come at the pace of
    ``slowest_mode_min``.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
    values : ndarray, shape (N, S)
    slowest_mode_min : float
        The slowest mode the rise still to come is bounded with (min).

    Returns
    -------
    final_C, equilibrium_time_min : ndarray, shape (S,)
    settled : ndarray of bool, shape (S,)
    """
    final, equilibrium = measured_equilibrium(time_min, values)
    settled = np.isfinite(
        measured_equilibrium(time_min, values, SETTLED_MOVE_C, SETTLED_MOVE_C / 2.0, slowest_mode_min)[0]
    )
    return final, equilibrium, settled


def measured_equilibrium(
    time_min: FloatArray,
    values: FloatArray,
    max_late_move_C: float = math.inf,
    max_remaining_C: float = math.inf,
    slowest_mode_min: float | FloatArray = DEFAULT_MAX_TIME_CONSTANT_MIN,
    max_late_share: float = 0.05,
) -> tuple[FloatArray, FloatArray]:
    """Final temperature and 95 %-rise time read off a log that ran to equilibrium.

    The final temperature is the median of the last 10 samples; the log counts as
    having reached equilibrium when its last quarter rose by less than ``max_late_share`` (5 %) of
    the total rise and less than ``max_late_move_C`` (the mean of its last sixteenth against that of
    the sixteenth a quarter before its end), and when the rise still to come that this late move
    allows is at most ``max_remaining_C``. Otherwise NaN. A log still moving
    within those bounds gives a final temperature, and a 95 %-rise time, short of
    where it settles: the papers' "measured" values, read off the end of a test.

    The rise still to come is bounded by a mode as slow as ``slowest_mode_min``: a move m
    over Δ minutes of such a mode leaves m / (e^(Δ/τ) − 1) to come. A small late move is not
    settled by itself: a 180-min mode moves 0.09 °C in 68 min with 0.2 °C still to come.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        Sample times (min).
    values : ndarray, shape (N, S)
        Readings (°C, NaN: missing).
    max_late_move_C : float
        The most the last quarter may move (°C).
    max_remaining_C : float
        The most the rise still to come may be (°C).
    slowest_mode_min : float or ndarray, shape (S,)
        The slowest mode the rise still to come is bounded with (min), one for every sensor or
        each its own.
    max_late_share : float
        The most the last quarter may move, as a share of the total rise (inf: only the bounds in
        °C hold, as for a check against a tolerance, where a sensor that rose 0.6 °C moving 0.07 °C
        with a daily room is settled to the check's precision).

    Returns
    -------
    final_C : ndarray, shape (S,)
        The final temperature (°C), NaN where the log did not reach equilibrium or a sensor has
        fewer than 40 valid readings.
    equilibrium_time_min : ndarray, shape (S,)
        The time (min, on ``time_min``) at which the smoothed readings first reach 95 % of the
        rise, NaN where the final temperature is NaN.
    """
    finals, times = [], []
    n = len(time_min)
    slowest = np.broadcast_to(np.asarray(slowest_mode_min, dtype=float), (values.shape[1],))
    for col, tau in zip(values.T, slowest, strict=True):
        ok = np.isfinite(col)
        t, y = time_min[ok], col[ok]
        if len(y) < 40:
            finals.append(np.nan)
            times.append(np.nan)
            continue
        start = float(np.median(y[:3]))
        final = float(np.median(y[-10:]))
        quarter = max(n // 4, 5)
        # means over a quarter of the quarter, not medians of five: readings in display steps
        # (0.1 °C) and a little noise put five-reading medians a whole step apart on a settled log
        span = max(quarter // 4, 5)
        late_rise = float(np.mean(y[-span:]) - np.mean(y[-quarter : -quarter + span]))
        apart = float(np.mean(t[-span:]) - np.mean(t[-quarter : -quarter + span]))
        # the move less two of its standard errors: noise alone does not make a settled log move
        noise = 2.0 * math.sqrt(float(np.var(y[-span:]) + np.var(y[-quarter : -quarter + span])) / span)
        # readings in display steps with too little noise to dither them can hide a move of up to a
        # step: a log in 0.1 °C steps still 0.1 °C short of its level read as settled
        step = float(display_resolution(y[:, None])[0])
        hidden = step if math.sqrt(float(np.var(y[-span:]))) < step / 2.0 else 0.0
        pace = float(tau) if math.isfinite(tau) and tau > 0 else DEFAULT_MAX_TIME_CONSTANT_MIN
        to_come = (max(abs(late_rise) - noise, 0.0) + hidden) / max(math.expm1(apart / pace), 1e-12)
        rise = final - start
        if rise == 0 or abs(late_rise) > min(max_late_share * abs(rise), max_late_move_C) or to_come > max_remaining_C:
            finals.append(np.nan)
            times.append(np.nan)
            continue
        smooth = np.convolve(y, np.ones(5) / 5, mode="same")
        target = start + EQUILIBRIUM_FRACTION * rise
        crossed = (smooth >= target) if rise > 0 else (smooth <= target)
        crossed[:2] = False
        crossed[-2:] = crossed[-2:] | True
        times.append(float(t[int(np.argmax(crossed))]))
        finals.append(final)
    return np.array(finals), np.array(times)


def window_samples(log: TemperatureLog, window_min: float) -> int:
    """How many samples the first ``window_min`` minutes hold, at least ``MIN_WINDOW_SAMPLES``.

    Parameters
    ----------
    log : TemperatureLog
    window_min : float
        The identification window (min).

    Returns
    -------
    int

    Raises
    ------
    InputError
        Fewer samples than an identification needs.
    """
    n = log.window(window_min)
    if n < MIN_WINDOW_SAMPLES:
        unit = ", or the time column's unit, `time_unit`: its times were read as minutes" if unit_doubted(log) else ""
        msg = (
            f"{log.source}: only {n} samples in the first {window_min:g} min; the identification needs at least "
            f"{MIN_WINDOW_SAMPLES} (use a longer `window_min`{unit})"
        )
        raise InputError(msg)
    return n


# the floor a warm-up that does not overshoot sets on T∞: the median of this many latest readings,
# less this many times the noise (and the display step)
_LATEST_READINGS = 5


_FLOOR_NOISES = 4.0


def _levels(values: FloatArray) -> FloatArray:
    """The readings' levels: medians of each run of ``_LATEST_READINGS`` valid readings."""
    levels: FloatArray = np.median(np.lib.stride_tricks.sliding_window_view(values, _LATEST_READINGS), axis=1)
    return levels


def warm_up_floor_C(
    steady_C: float,
    time_min: FloatArray,
    values: FloatArray,
    room_C: FloatArray | None,
    noise_C: float,
    rounding_C: float,
) -> float:
    """The lowest T∞ a warm-up that does not overshoot allows: its latest level less the noise and,
    with a room sensor, the highest it stood above the room's highest level until then, at the
    room's latest level (a passive structure follows a room that fell only late, with a static gain
    of one).

    With constant heat, every temperature of a structure started at rest, or partly warm and
    still below its equilibrium, stays at or below its equilibrium (for a conductance network
    e^(At) is elementwise non-negative; for a continuous body, the maximum principle): a model
    whose T∞ lies below where the sensor already is describes a curve that came down from above,
    which such a warm-up cannot make. A room's part in a reading is a weighted mean of the room's
    levels until then (its impulse response is non-negative and integrates to one), so never above
    the room's highest level so far: the reading less that bounds the heat's part from below, at
    every time, and T∞ is the heat's final part at the room's latest level. Where the sensor does
    not rise to its fit's T∞, or its heat's part fell for certain (its latest reading less the
    room's lowest level lies below that bound at an earlier time by more than the noise: it cooled,
    an earlier heating at more power, a heat input that fell), nothing is assumed: −inf. Without a
    room sensor, the latest level alone (an unmeasured room may have stood higher earlier).

    Parameters
    ----------
    steady_C : float
        The fit's T∞.
    time_min : ndarray, shape (N,)
        The times since the warm-up began (min).
    values : ndarray, shape (N,)
        The readings since then (°C, NaN: missing).
    room_C : ndarray, shape (N,), optional
        The room's (smoothed) readings beside them.
    noise_C, rounding_C : float
        The readings' noise and display step (°C).

    Returns
    -------
    float
        The floor (°C), −inf where none holds.
    """
    ok = np.isfinite(values) if room_C is None else np.isfinite(values) & np.isfinite(room_C)
    if ok.sum() < 2 * _LATEST_READINGS or not np.isfinite(steady_C):
        return -np.inf
    # levels as medians of a few readings, so that one noisy reading neither sets nor breaks the floor
    levels = _levels(values[ok])
    latest, first = float(levels[-1]), float(levels[0])
    margin = _FLOOR_NOISES * noise_C + rounding_C
    if not (steady_C > first and latest > first + margin):
        return -np.inf
    if room_C is None:
        # an unmeasured room may have stood higher earlier: the latest level alone
        return latest - margin if latest >= float(levels.max()) - margin else -np.inf
    room = room_C[ok]
    # the room's highest and lowest levels until the last reading of each level's window
    highest = np.maximum.accumulate(room)[_LATEST_READINGS - 1 :]
    lowest = float(np.min(room))
    heat_at_least = levels - highest
    if latest - lowest < float(np.max(heat_at_least)) - margin:
        return -np.inf
    return float(np.max(heat_at_least)) + float(room[-1]) - margin


@dataclass(frozen=True)
class Fall:
    """How far a sensor's readings came down from their highest level.

    Attributes
    ----------
    fall_C : float
        The highest level less the latest (°C; levels are medians of a few readings, 0 where the
        readings never came down).
    highest_C : float
        The highest level (°C).
    highest_min : float
        When it was read (min).
    rise_C : float
        The highest level less the first (°C).
    """

    fall_C: float
    highest_C: float
    highest_min: float
    rise_C: float


def fall_from_highest(time_min: FloatArray, values: FloatArray) -> Fall | None:
    """How far ``values`` came down from their highest level: a warm-up at constant heat in a
    steady room never does (:func:`warm_up_floor_C`), so a fall says that the heat input fell
    (a spindle stopped or slowed) or the room cooled. None for fewer than twice
    ``_LATEST_READINGS`` valid readings.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
    values : ndarray, shape (N,)
        The readings (°C, NaN: missing), less the room's change where a room sensor is logged.

    Returns
    -------
    Fall or None
    """
    ok = np.isfinite(values)
    if ok.sum() < 2 * _LATEST_READINGS:
        return None
    levels = _levels(values[ok])
    top = int(np.argmax(levels))
    window = slice(top, top + _LATEST_READINGS)
    at = time_min[ok][window][int(np.argmax(values[ok][window]))]
    return Fall(float(levels[top] - levels[-1]), float(levels[top]), float(at), float(levels[top] - levels[0]))


def minutes_given(name: str, value: object, right: str, strictly: bool) -> float:
    """``value`` as a float; InputError naming ``name`` and what is ``right`` where it is no finite
    number above 0 (or at least 0 where not ``strictly``): a string or a negative horizon raised
    deep inside numpy."""
    try:
        minutes = float(value)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        minutes = math.nan
    if not (math.isfinite(minutes) and (minutes > 0 if strictly else minutes >= 0)):
        msg = f"{name} must be {right}, not {value!r}"
        raise InputError(msg)
    return minutes
