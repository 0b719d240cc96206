"""What a sensor's readings say before any model is fitted: the display step a logger rounds
to, the noise level, and a first guess of the warm-up's start, rate and steady state.

These feed every method: the first-order filters' tuning
(:func:`~mtident.thermal.settings.tuning_from_data`), the flat-start search of
:mod:`~mtident.thermal.lsq` and the model-robust fit's noise (:mod:`~mtident.thermal.robust`).
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from mtident._typing import FloatArray

__all__ = [
    "DISPLAY_STEPS_C",
    "display_resolution",
    "noise_sigma",
    "on_display_steps",
    "quantisation_step",
    "quick_estimate",
    "reading_range",
    "rise_threshold_C",
    "sampling_interval_min",
    "coarse_room_step_C",
    "room_error_C",
    "warming_room_warning",
    "room_input",
    "room_noise_C",
    "spikes",
    "step_from_grid",
    "stuck_since",
    "without_stuck",
    "frozen_stretches",
    "frozen_words",
]

ROOM_TREND_MIN = 120.0
"""The room drives the machine model (every sensor fitted together) as its local trend
(:func:`room_trend`) over this window: there the room sensor's error is one error of every sensor at once."""
ROOM_WINDOWS_MIN = (120.0, 60.0, 30.0, 15.0)
"""The windows a sensor's own fit may take the room's trend over, longest first."""
CURVATURE_SHRINK = 2.0
"""A room trend's curvature is shrunk by this many times its variance over its square: at zero
curvature the trend keeps a seventh of the noise a parabola adds, and a curvature four times its
uncertainty a tenth of the squared error a line leaves (:func:`room_trend`)."""
CURVATURE_SPAN = 150.0
"""A log longer than this many trend windows (12.5 days of two-hour windows) keeps the straight line."""
ROOM_WINDOW_SLACK = 1.25
"""A window is short enough where the room's readings stray from its trend by no more than this
many times their own noise (RMS)."""

# Display steps a logger rounds to, coarsest first: decimal ones, and the binary ones of digital
# sensors (a DS18B20 reads in steps of 1/16 °C at 12 bits, 1/2 °C at 9 bits).
DISPLAY_STEPS_C = np.array(
    sorted({1.0, 0.5, 0.25, 0.125, 0.1, 0.0625, 0.05, 0.03125, 0.01, 0.005, 0.001}, reverse=True)
)


def on_display_steps(values: FloatArray) -> np.ndarray:
    """(..., S, len(DISPLAY_STEPS_C)): whether each reading is a whole multiple of each step (NaN: yes).

    Parameters
    ----------
    values : ndarray, shape (..., S)
        Readings (°C, NaN: missing).

    Returns
    -------
    ndarray of bool, shape (..., S, K)
        One entry per step of ``DISPLAY_STEPS_C`` (K steps, coarsest first).
    """
    multiples = np.asarray(values, dtype=float)[..., None] / DISPLAY_STEPS_C
    with np.errstate(invalid="ignore"):
        answer: np.ndarray = ~(np.abs(multiples - np.round(multiples)) >= 1e-6)
        return answer


def step_from_grid(on_grid: np.ndarray, spread: FloatArray) -> FloatArray:
    """Per sensor, the coarsest step every reading is a multiple of and the readings span at least
    twice (a flat ``20.0`` is not a 1 °C display); 0 where there is none.

    Parameters
    ----------
    on_grid : ndarray of bool, shape (S, K)
        Whether every reading of a sensor is a whole multiple of each step of ``DISPLAY_STEPS_C``.
    spread : ndarray, shape (S,)
        Each sensor's highest reading less its lowest (°C).

    Returns
    -------
    ndarray, shape (S,)
        The step (°C).
    """
    usable = on_grid & (np.asarray(spread, dtype=float)[:, None] >= 2.0 * DISPLAY_STEPS_C - 1e-9)
    return np.where(usable.any(axis=1), DISPLAY_STEPS_C[np.argmax(usable, axis=1)], 0.0)


def display_resolution(values: FloatArray) -> FloatArray:
    """The step each sensor's readings are rounded to (°C), 0 where none is seen: the coarsest of
    the usual display steps (0.1, 0.01, 1/16 °C, ...) that fits every valid reading
    (:func:`step_from_grid`).

    Parameters
    ----------
    values : ndarray, shape (N, S)

    Returns
    -------
    ndarray, shape (S,)
        The step (°C).
    """
    return step_from_grid(np.asarray(on_display_steps(values).all(axis=0)), np.nan_to_num(reading_range(values)))


def reading_range(values: FloatArray) -> FloatArray:
    """Per sensor, the highest valid reading less the lowest (NaN for a column without one).

    Parameters
    ----------
    values : ndarray, shape (N, S)
        Readings (°C, NaN: missing).

    Returns
    -------
    ndarray, shape (S,)
        The range (°C).
    """
    y = np.asarray(values, dtype=float)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a column without a valid reading
        answer: FloatArray = np.nanmax(y, axis=0) - np.nanmin(y, axis=0)
        return answer


def noise_sigma(values: FloatArray, time_min: FloatArray | None = None) -> FloatArray:
    """Measurement noise per sensor from fourth differences, robust to spikes (MAD).

    For white noise of standard deviation σ, Δ⁴y has standard deviation σ√70; a
    smooth warm-up curve contributes only D·(λΔt)⁴ to it (about 1e-6 °C for the
    papers' curves), so a noise-free curve gives σ ≈ 0 and is fitted exactly.

    With ``time_min``, five readings in a row that are not evenly spaced (a gap
    of rows, a missing reading) are combined with the weights of their fourth
    divided difference, normalised: the combination that cancels any cubic at
    those times, σ times a unit vector for white noise (Δ⁴y/√70 on an even grid).
    Taken as if even, a 5-min gap in the papers' first 12 min put the curve's own
    slope into σ (0.22 °C for 0.02), and the live monitor read the rise as flat.

    A rounded reading (a logger's 0.01 or 0.1 °C display) is never better than
    its rounding, q/√12 for a display step q (:func:`display_resolution`). The
    MAD alone does not see it: on a smooth curve most fourth differences of the
    rounded readings are exactly 0, the MAD was 0, and a filter told the noise
    was 1e-9 °C chased the rounding off course (a clean 0.1 °C log ended in a
    Cholesky failure, a 0.01 °C one never stopped the live monitor).

    Parameters
    ----------
    values : ndarray, shape (N, S)
    time_min : ndarray, shape (N,), optional
        The readings' times; without them the readings are taken as evenly spaced.

    Returns
    -------
    ndarray, shape (S,)
        The noise's standard deviation per reading (°C), at least the display step's q/√12; 0.05 °C
        for a sensor with fewer than seven valid readings.
    """
    out = []
    y_all = np.asarray(values, dtype=float)
    t_all = np.arange(len(y_all), dtype=float) if time_min is None else np.asarray(time_min, dtype=float)
    for column in y_all.T:
        finite = np.isfinite(column)
        d4 = _unit_fourth_differences(t_all[finite], column[finite])
        if d4.size < 3:
            out.append(0.05)
            continue
        sigma = np.median(np.abs(d4 - np.median(d4))) * 1.4826
        spacing = np.diff(t_all[finite])
        broken = not finite.all() or bool(np.ptp(spacing) > 1e-6 * max(float(np.median(spacing)), 1e-12))
        if broken and d4.size < _FEW_DIFFERENCES:
            # A handful of differences around missing readings can all be small by chance (4 gave
            # 0.003 °C for 0.02 in a monitor's first 10 min with readings missing, and its filter took
            # every later reading for a spike); the residuals of a cubic through the short window use
            # every reading, and the larger of the two is kept. (A complete short window keeps the
            # differences alone: a cubic cannot follow a late start's kink, 0.038 °C for 0.02.)
            sigma = max(sigma, _cubic_residual_sigma(t_all[finite], column[finite]))
        out.append(max(sigma, 1e-9))
    answer: FloatArray = np.maximum(np.array(out), display_resolution(values) / np.sqrt(12.0))
    return answer


# below this many fourth differences around missing readings, their MAD alone is no noise estimate to trust
_FEW_DIFFERENCES = 10


def _cubic_residual_sigma(t: FloatArray, y: FloatArray) -> float:
    """σ from the residuals of a least-squares cubic in time (len(y) − 4 degrees of freedom); a short
    window of a smooth warm-up bends less than a cubic can follow."""
    if len(y) < 6:
        return 0.0
    scaled = (t - t.mean()) / max(float(np.ptp(t)), 1e-9)
    residuals = y - np.polyval(np.polyfit(scaled, y, 3), scaled)
    return float(np.sqrt(np.sum(residuals**2) / (len(y) - 4)))


def _unit_fourth_differences(t: FloatArray, y: FloatArray) -> FloatArray:
    """Each five readings in a row combined by their normalised fourth divided difference: zero for
    any cubic through them, σ times a unit vector for white noise (Δ⁴y/√70 on an even grid)."""
    if len(y) < 5:
        return np.empty(0)
    windows = np.lib.stride_tricks.sliding_window_view(np.arange(len(y)), 5)
    times, readings = t[windows], y[windows]
    apart = times[:, :, None] - times[:, None, :]
    apart[:, np.arange(5), np.arange(5)] = 1.0
    with np.errstate(divide="ignore", invalid="ignore"):  # two readings at one time: no difference there
        weights = 1.0 / np.prod(apart, axis=2)
        weights /= np.linalg.norm(weights, axis=1, keepdims=True)
        combined = np.sum(weights * readings, axis=1)
    answer: FloatArray = combined[np.isfinite(combined)]
    return answer


def quick_estimate(time_min: FloatArray, values: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """T₀, λ and T∞ per sensor from the means of three equal thirds of the window.

    For T = T∞ + D e^(−λt), segment means A₁, A₂, A₃ spaced τ apart satisfy
    (A₃ − A₂)/(A₂ − A₁) = e^(−λτ), independent of D. Where the ratio is not in
    (0, 1) (no curvature yet, or noise), λ falls back to 3/window — a curve
    still rising steeply at the end of the window. Each sensor is taken on a
    uniform grid over its own span from its first to its last valid reading
    (missing readings and gaps interpolated), so T₀ is its first valid reading.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        Sample times (min) of the window.
    values : ndarray, shape (N, S)
        Readings (°C, NaN: missing).

    Returns
    -------
    start_C, rate_per_min, steady_C : ndarray, shape (S,)
        T₀ (°C), λ (1/min) and T∞ (°C); T₀ and T∞ are NaN for a sensor without a valid reading.
    """
    t = np.asarray(time_min, dtype=float)
    y = np.asarray(values, dtype=float)
    # Each sensor on a uniform grid over its own valid span, its readings interpolated onto it: the
    # thirds' formula needs equally spaced thirds of equal weight. A missing reading left out of its
    # third's mean tilted the mean against the third's mean time (three of them on the noiseless
    # papers' curve gave λ = 0.107/min, T∞ = 21.0 °C), and a gap of rows made the thirds unequal
    # (a 6-min gap: T∞ 20.9 °C); a filter started from that guess inherited it.
    n, S = y.shape
    grid_t = np.tile(t[:, None], (1, S))
    grid_y = np.full((n, S), np.nan)
    start = np.full(S, np.nan)  # each sensor's first valid reading
    for s in range(S):
        valid = np.isfinite(y[:, s])
        if not valid.any():
            continue
        start[s] = y[valid, s][0]
        if valid.sum() >= 2:
            grid_t[:, s] = np.linspace(t[valid][0], t[valid][-1], n)
            grid_y[:, s] = np.interp(grid_t[:, s], t[valid], y[valid, s])
        else:
            grid_y[:, s] = start[s]
    size = n // 3
    thirds = [np.arange(n - 3 * size + j * size, n - 3 * size + (j + 1) * size) for j in range(3)]
    seg_t = np.stack([grid_t[i].mean(axis=0) for i in thirds])  # (3, S)
    seg_y = np.stack([grid_y[i].mean(axis=0) for i in thirds])
    tau = (seg_t[2] - seg_t[0]) / 2.0
    d1, d2 = seg_y[1] - seg_y[0], seg_y[2] - seg_y[1]
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = d2 / d1
    span = np.maximum(grid_t[-1] - grid_t[0], 1e-9)
    fallback = 3.0 / span
    ok = (ratio > 0.05) & (ratio < 0.98) & np.isfinite(ratio) & (tau > 0)
    rate = np.where(ok, -np.log(np.where(ok, ratio, 0.5)) / np.where(ok, tau, 1.0), fallback)
    # Segment means are A_j = T∞ + D·m_j with m_j the segment mean of e^(−λt).
    m = np.stack([np.exp(-rate[None, :] * (grid_t[i] - grid_t[0][None, :])).mean(axis=0) for i in thirds])
    with np.errstate(divide="ignore", invalid="ignore"):
        amplitude = (seg_y[2] - seg_y[0]) / (m[2] - m[0])
        steady = seg_y[0] - amplitude * m[0]
    steady = np.where(np.isfinite(steady), steady, seg_y[2])
    return start, rate, steady


def room_input(time_min: FloatArray, room_C: FloatArray) -> FloatArray:
    """The room as a sensor's fit takes it: its readings' local trend (:func:`room_trend`) over
    the longest of :data:`ROOM_WINDOWS_MIN` that the room follows within its own noise (RMS,
    display steps counted in). The room sensor's noise and display steps are one error that every
    sensor's fit shares; fed raw, a fit takes them for a slow mode (a reference run of a machine of
    3-minute modes, in a steady room read in 0.05 °C steps, learnt modes of 150 min), while a room
    that wanders within hours must be followed (a shipped sample's room, ±0.1 °C over two to three
    hours, was missed by 0.14 °C by a two-hour line).

    Parameters
    ----------
    time_min, room_C
        As for :func:`room_trend`.

    Returns
    -------
    ndarray, shape (N,)
    """
    t = np.asarray(time_min, dtype=float)
    room = np.asarray(room_C, dtype=float)
    valid = np.isfinite(room)
    if np.count_nonzero(valid) < 5:
        return room.copy()
    noise = room_noise_C(t, room)
    trend = room
    for window in ROOM_WINDOWS_MIN:
        trend = room_trend(t, room, window, noise)
        if np.sqrt(np.mean((room[valid] - trend[valid]) ** 2)) <= ROOM_WINDOW_SLACK * noise:
            break
    return trend


def room_noise_C(time_min: FloatArray, room_C: FloatArray) -> float:
    """A room sensor's error about its course (°C): its noise (:func:`noise_sigma`) and its display
    step's q/√12 together."""
    column = np.asarray(room_C, dtype=float)[:, None]
    step = float(display_resolution(column)[0])
    return math.hypot(float(noise_sigma(column, time_min)[0]), step / math.sqrt(12.0))


ROOM_LEVEL_FLOOR_C = 0.015
"""The least error (one sd, °C) of a sensor's T∞ at the room's level, where a room sensor sets that
level: the room sensor's and the readings' resolution, which no length of readings narrows (the
room's last level is a trend of readings in display steps, and the truth moves with the room's
true level). Every interval at the room's level carries it in quadrature, a machine model's and a
sensor's own fit's alike."""


COARSE_ROOM_STEP_C = 0.05
"""A room sensor read in steps this coarse or coarser hides the room's slow moves within a step."""


def coarse_room_step_C(time_min: FloatArray, room_C: FloatArray) -> float:
    """A coarse room sensor's display step (°C): the step its readings come in, where it is
    :data:`COARSE_ROOM_STEP_C` or coarser; else 0 (its slow error, :func:`room_error_C`, is the
    step's q/√12).

    A room read in 0.1 °C steps holds one value for an hour while the room moves a few
    hundredths, and as it crosses a step its readings jump: what a fit takes as the room
    (:func:`room_input`) is off by up to half a step, slowly, and every sensor's fit carries that
    error, which a mode the machine does not have can take up (reference runs of 2.5-minute
    machines in a room cycling ±0.12 °C, read in 0.1 °C steps, learnt modes of 30 to 150 min). A
    room read in finer steps is followed by its trend within its noise.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        Sample times (min); the step is read from the readings alone.
    room_C : ndarray, shape (N,)
        The room's readings (°C, NaN: missing).

    Returns
    -------
    float
    """
    room = np.asarray(room_C, dtype=float)
    if np.count_nonzero(np.isfinite(room)) < 5:
        return 0.0
    step = max(float(display_resolution(room[:, None])[0]), quantisation_step(room))
    return step if step >= COARSE_ROOM_STEP_C - 1e-9 else 0.0


def room_error_C(time_min: FloatArray, room_C: FloatArray) -> float:
    """The slow part of a coarse room sensor's error (°C): its display step's q/√12
    (:func:`coarse_room_step_C`); 0 for a fine one."""
    return coarse_room_step_C(time_min, room_C) / math.sqrt(12.0)


def coarse_room_warning(step_C: float, consequence: str) -> str:
    """What to say of a room read in steps of ``step_C`` (°C, from :func:`coarse_room_step_C`), and
    what that costs here (``consequence``)."""
    return (
        f"the room is read in steps of {step_C:.2g} °C: it moves within a step unseen, and its readings jump as it "
        f"crosses one, an error every sensor's fit shares ({consequence}). Log the room at 0.01 °C"
    )


ROOM_WARMING_C = 3.0
"""A room sensor whose readings rise more than this from their first level (°C) warms more than a
workshop's air does in a test: a sensor on the machine named as the room, most likely."""


def warming_room_warning(room_C: FloatArray, name: str | None, time_min: FloatArray | None = None) -> str | None:
    """What to say of a room sensor that warms like a machine's (up by more than
    :data:`ROOM_WARMING_C` from its first level): a bearing named as the room took every sensor's
    warm-up as the room's, and their time constants came out 13 to 424 min for a 120-min truth,
    without a word. None for a room that does not.

    Parameters
    ----------
    room_C : ndarray, shape (N,)
        The room's readings (°C, NaN: missing).
    name : str or None
        The room sensor's column, for the words.
    time_min : ndarray, shape (N,), optional
        The readings' times (min): the words say by when it had warmed that much (a replay says its
        warnings after the checks that read the same rows).

    Returns
    -------
    str or None
    """
    room = np.asarray(room_C, dtype=float)
    ok = np.isfinite(room)
    valid = room[ok]
    if len(valid) < 10:
        return None
    levels = _running_median(valid, 5)
    first, highest = float(np.median(valid[:5])), float(np.max(levels))
    if highest - first <= ROOM_WARMING_C:
        return None
    column = f"the room sensor {name!r}" if name else "the room sensor"
    when = ""
    if time_min is not None:
        # a level is its window's middle reading's; the figures are of the readings so far, the time
        # when they first rose beyond the limit
        beyond = int(np.argmax(levels > first + ROOM_WARMING_C)) + 2
        when = f", up by more than {ROOM_WARMING_C:g} °C by t = {float(np.asarray(time_min)[ok][beyond]):g} min"
    return (
        f"{column} warmed {highest - first:.1f} °C from its first level ({first:.2f} to {highest:.2f} °C){when}, "
        f"more than a workshop's air moves in a test ({ROOM_WARMING_C:g} °C): is it a sensor on the machine? The room "
        "is an input of every sensor's fit, so a machine sensor taken for it bends every answer; name the air's own "
        "column as the room (`room_sensor`)"
    )


def _running_median(values: FloatArray, width: int) -> FloatArray:
    """The median of each ``width`` readings in a row (a spike is no level)."""
    windows = np.lib.stride_tricks.sliding_window_view(values, width)
    running: FloatArray = np.median(windows, axis=1)
    return running


def _window_sums(time_min: FloatArray, valid: np.ndarray, window_min: float, *columns: FloatArray) -> list[FloatArray]:
    """Each column's sum over the valid readings within ``window_min / 2`` of each time."""
    lo = np.searchsorted(time_min, time_min - window_min / 2.0, side="left")
    hi = np.searchsorted(time_min, time_min + window_min / 2.0, side="right")
    out = []
    for column in columns:
        cumulative = np.concatenate([[0.0], np.cumsum(np.where(valid, column, 0.0))])
        out.append(cumulative[hi] - cumulative[lo])
    return out


def room_trend(time_min: FloatArray, room_C: FloatArray, window_min: float, noise_C: float | None = None) -> FloatArray:
    """A room sensor's readings as a local straight line over a window centred on each time
    (one-sided at the ends, where a straight line still follows a drift without lag), bent by the
    window's curvature as far as the readings show it beyond their noise: the room's course without
    the sensor's noise and display steps, which every sensor would otherwise share as one error.

    A straight line misses the room's curvature: over two hours of a daily cycle it takes about
    1 % off the cycle's swing, an error far below the room sensor's noise that every sensor's fit
    shares as a slow input error over hundreds of readings, and a test's fit explained it by a
    slower mode than its reference allowed (a sensor said "off reference" by the chance of the room
    sensor's noise). A parabola follows the curvature but carries more of the noise, which a steady
    room's fits pay for; so the curvature's term is shrunk towards the line by its own uncertainty
    (James-Stein, positive part, by ``CURVATURE_SHRINK`` of its variance): kept where the window
    shows it clearly, dropped where the readings show none.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        Sample times (min), increasing.
    room_C : ndarray, shape (N,)
        The room's readings (°C, NaN: missing).
    window_min : float
        The window's width (min).
    noise_C : float, optional
        The room sensor's error about its course (default: :func:`room_noise_C`).

    Returns
    -------
    ndarray, shape (N,)
        The local trend's value at each time (NaN where the reading itself is missing).
    """
    t = np.asarray(time_min, dtype=float)
    room = np.asarray(room_C, dtype=float)
    valid = np.isfinite(room)
    if not len(t):
        return room.copy()
    noise = room_noise_C(t, room) if noise_C is None else noise_C
    # times scaled to [0, 1]; the window's moments are still a (window/span)⁴ share of the log's
    # (CURVATURE_SPAN below)
    span = max(float(t[-1] - t[0]), 1e-9)
    u = (t - t[0]) / span
    n, s1, s2, s3, s4, sy, s1y, s2y = _window_sums(
        t, valid, window_min, np.ones_like(u), u, u**2, u**3, u**4, room, u * room, u * u * room
    )
    with np.errstate(invalid="ignore", divide="ignore"):
        # each window's sums about its own mean time: v = u − mean, so that 1 and v are orthogonal
        mean = s1 / n
        c2 = s2 - 2 * mean * s1 + mean**2 * n
        c3 = s3 - 3 * mean * s2 + 3 * mean**2 * s1 - mean**3 * n
        c4 = s4 - 4 * mean * s3 + 6 * mean**2 * s2 - 4 * mean**3 * s1 + mean**4 * n
        d1 = s1y - mean * sy
        d2 = s2y - 2 * mean * s1y + mean**2 * sy
        v = u - mean
        sloped = c2 > 1e-9 * np.maximum(s2, 1e-300)
        slope = np.where(sloped, d1 / c2, 0.0)
        line = sy / n + slope * v
        # the curvature's term: v² less its part along 1 and v, q(v) = v² − c2/n − (c3/c2)·v
        q_norm = np.where(sloped, c4 - c2**2 / n - c3**2 / c2, 0.0)
        # the window's fourth moment about its mean comes from the log's, which it is a (window/span)⁴
        # share of: beyond CURVATURE_SPAN windows, rounding would swamp it
        curved = (span <= CURVATURE_SPAN * window_min) & sloped & (n >= 3) & (q_norm > 1e-9 * np.maximum(c4, 1e-300))
        curvature = np.where(curved, (d2 - c2 / n * sy - c3 / c2 * d1) / q_norm, 0.0)
        variance = np.where(curved, noise**2 / q_norm, 0.0)
        kept = np.where(curved, np.maximum(0.0, 1.0 - CURVATURE_SHRINK * variance / curvature**2), 0.0)
        trend = line + np.where(curved, kept * curvature * (v * v - c2 / n - c3 / c2 * v), 0.0)
    return np.where(valid, trend, np.nan)


def sampling_interval_min(time_min: FloatArray) -> float:
    """The log's usual sampling interval (the median step; 1 min for fewer than two readings).

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        Sample times (min).

    Returns
    -------
    float
        The interval (min).
    """
    t = np.asarray(time_min, dtype=float)
    return float(np.median(np.diff(t))) if len(t) > 1 else 1.0


def rise_threshold_C(noise_C: float, rounding_C: float) -> float:
    """A move from the first level that is a rise, not noise: 6σ, or three rounding steps.

    Parameters
    ----------
    noise_C : float
        The readings' noise (°C, per reading).
    rounding_C : float
        The step the readings come in (°C; 0 where none).

    Returns
    -------
    float
        The threshold (°C).
    """
    return max(6.0 * noise_C, 3.0 * rounding_C, 1e-6)


def quantisation_step(values: FloatArray) -> float:
    """The step a converter's quantisation puts between readings (0 where none is seen): the
    smallest common change between successive readings, where nearly all changes are whole
    multiples of it (a 10-bit converter's 0.32 °C, off any decimal grid a display step would
    show). Where the readings have changed fewer than five times, the smallest change: as far as
    they tell, they may move in steps that large (a converter's two levels, 0.32 °C apart, read as
    a settled fast mode, would put T∞ on the upper level within ±0.16 °C).

    Parameters
    ----------
    values : ndarray, shape (N,)
        One sensor's readings (°C, NaN: missing).

    Returns
    -------
    float
        The step (°C).

    Examples
    --------
    >>> round(quantisation_step(22.84 + 0.3223 * np.array([0, 0, 1, 1, 2, 2, 2, 4, 5, 5, 6, 6])), 4)
    0.3223
    >>> quantisation_step(np.array([20.0, 20.013, 20.031, 20.04, 20.052, 20.071, 20.079, 20.102]))
    0.0
    >>> round(quantisation_step(np.array([18.56, 18.56, 18.56, 18.88, 18.88, 18.88])), 2)
    0.32
    """
    changes = np.abs(np.diff(np.asarray(values, dtype=float)))
    changes = changes[np.isfinite(changes) & (changes > 1e-9)]
    if len(changes) < 5:
        return float(changes.min()) if len(changes) else 0.0
    step = float(np.percentile(changes, 5))
    multiples = changes / step
    if np.mean(np.abs(multiples - np.round(multiples)) < 0.05) < 0.8:
        return 0.0
    return float(np.median(changes[np.round(multiples) == 1]))


def spikes(values: FloatArray, noise_C: float, rounding_C: float, half_window: int = 3) -> np.ndarray:
    """Which readings are spikes: further from the median of their neighbours (``half_window``
    each side, none missing) than 8σ and five rounding steps (a Hampel filter). A smooth
    rise, however steep, keeps its readings at the median of their neighbours; a glitch does not.
    The last ``half_window`` readings of a live log are judged when their neighbours come.

    Parameters
    ----------
    values : ndarray, shape (N,)
    noise_C, rounding_C : float
    half_window : int, optional
        Neighbours on each side of a reading.

    Returns
    -------
    ndarray of bool, shape (N,)
    """
    y = np.asarray(values, dtype=float)
    width = 2 * half_window + 1
    wild = np.zeros(len(y), dtype=bool)
    if len(y) < width:
        return wild
    # only readings with neighbours on both sides, most of them there: at a live log's end, or
    # where a rise begins, a one-sided median trails the curve; a reading skipped beside a glitch
    # (an open circuit's 850 °C, then 85.0) must not hide it
    windows = np.lib.stride_tricks.sliding_window_view(y, width)
    finite = np.isfinite(windows)
    median = np.median(windows, axis=1)  # NaN where any is missing
    gaps = ~finite.all(axis=1)
    both = gaps & (
        np.minimum(finite[:, :half_window].sum(axis=1), finite[:, half_window + 1 :].sum(axis=1))
        >= max(half_window - 1, 1)
    )
    if both.any():
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)
            median[both] = np.nanmedian(windows[both], axis=1)
    limit = max(8.0 * noise_C, 5.0 * rounding_C)
    with np.errstate(invalid="ignore"):
        wild[half_window : len(y) - half_window] = np.abs(y[half_window : len(y) - half_window] - median) > limit
    return wild


STUCK_MIN = 10.0
"""A stuck run spans at least this long (min), as a silent sensor's gap does."""
STUCK_READINGS = 20
"""A sensor whose latest readings (at least this many, over at least :data:`STUCK_MIN`) are one
and the same value, more alike than its noise leaves to chance (:data:`STUCK_CHANCE`), is stuck."""
STUCK_CHANCE = 1e-7
"""The chance below which that many readings in one display step are not noise."""
_NOISE_BEFORE = 20
_STUCK_NOISE_STEPS = 0.5
"""Below this much noise (in display steps, beyond the rounding's), a repeated reading is not judged."""


def stuck_since(time_min: FloatArray, values: FloatArray) -> float:
    """The time from which a column's valid readings have all been exactly its latest one, where
    its noise before them, and how often its readings before repeated themselves, make that many
    alike no chance (below :data:`STUCK_CHANCE`): a stuck
    sensor, a logger channel that repeats its last value. NaN where they can be chance (a display
    coarser than the noise repeats a settled reading for hours), or where the column never varied.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
    values : ndarray, shape (N,)
        The column's readings (°C, NaN: missing).

    Returns
    -------
    float
    """
    at = np.flatnonzero(np.isfinite(values))
    if len(at) < STUCK_READINGS + _NOISE_BEFORE or values[at[-1]] != values[at[-STUCK_READINGS]]:
        return math.nan
    y = values[at]
    differs = np.flatnonzero(y != y[-1])
    start = int(differs[-1]) + 1 if len(differs) else 0
    return float(time_min[at[start]]) if _no_chance(time_min[at], y, start, len(y)) else math.nan


def _no_chance(time_min: FloatArray, y: FloatArray, start: int, stop: int, step_C: float = 0.0) -> bool:
    """Whether the valid readings ``y[start:stop]``, one and the same value, are too many and too
    long alike for the noise of the readings before them (:data:`STUCK_CHANCE`); ``step_C``: a
    step the readings come in that their display's resolution does not show (a converter's)."""
    alike = stop - start
    if start < _NOISE_BEFORE or alike < STUCK_READINGS or time_min[stop - 1] - time_min[start] < STUCK_MIN:
        return False
    before = slice(max(start - 10 * _NOISE_BEFORE, 0), start)
    sigma = float(noise_sigma(y[before, None], time_min[before])[0])
    step = max(float(display_resolution(y[:, None])[0]), step_C)
    # the noise beyond the rounding's own (q/√12): a smooth settled curve, rounded, repeats its
    # reading by the hundred, and the rounding's share of σ says nothing of how often
    beyond = math.sqrt(max(sigma**2 - step**2 / 12.0, 0.0))
    if beyond <= 0.0 or beyond < _STUCK_NOISE_STEPS * step:
        return False
    # the most readings of noise σ about a level can share is one step about it; and the readings
    # before, as often as they repeated themselves then
    in_one_step = math.erf(step / (2.0 * math.sqrt(2.0) * beyond))
    repeated = float(np.mean(np.diff(y[before]) == 0.0))
    return bool(max(in_one_step, repeated) ** (alike - 1) < STUCK_CHANCE)


def frozen_stretches(time_min: FloatArray, values: FloatArray) -> list[tuple[float, float]]:
    """The stretches inside a column's readings that froze at one value and moved on again (a
    logger channel that repeated its last reading for half an hour): as many readings alike as
    :func:`stuck_since` takes for no chance, followed by readings that differ. Each as (the time of
    its second reading, the time of its last): its first reading is a real one.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
    values : ndarray, shape (N,)
        The column's readings (°C, NaN: missing).

    Returns
    -------
    list of (float, float)
    """
    at = np.flatnonzero(np.isfinite(values))
    if len(at) < STUCK_READINGS + _NOISE_BEFORE:
        return []
    t, y = time_min[at], values[at]
    # runs of equal neighbours; the last run, reaching the end, is stuck_since's
    edges = np.flatnonzero(np.diff(y) != 0.0) + 1
    starts, stops = np.r_[0, edges], np.r_[edges, len(y)]
    long = [(int(a), int(b)) for a, b in zip(starts[:-1], stops[:-1], strict=True) if b - a >= STUCK_READINGS]
    if not long:
        return []
    # a 10-bit converter's 0.32 °C steps hold a slowly rising reading for half an hour: no freeze
    step = quantisation_step(y)
    return [(float(t[a + 1]), float(t[b - 1])) for a, b in long if _no_chance(t, y, a, b, step)]


def without_stuck(
    time_min: FloatArray, values: FloatArray
) -> tuple[FloatArray, list[float], list[list[tuple[float, float]]]]:
    """The readings with each column's stuck repeats (:func:`stuck_since` on) and the repeats of
    its frozen stretches (:func:`frozen_stretches`) missing: they say nothing of its temperature (a
    failed channel's 0.00 °C was fitted as where it settled).

    Parameters
    ----------
    time_min : ndarray, shape (N,)
    values : ndarray, shape (N, S)
        The readings (°C, NaN: missing).

    Returns
    -------
    values : ndarray, shape (N, S)
        The readings, the stuck repeats NaN (the same array where none is stuck).
    since : list of float
        Per column, when its repeats began (NaN: not stuck).
    frozen : list of list of (float, float)
        Per column, its frozen stretches (for the words, :func:`frozen_words`).
    """
    columns = np.asarray(values).T
    since = [stuck_since(time_min, column) for column in columns]
    frozen = [frozen_stretches(time_min, column) for column in columns]
    if all(math.isnan(s) for s in since) and not any(frozen):
        return values, since, frozen
    out = np.array(values, dtype=float)
    for s, start in enumerate(since):
        if not math.isnan(start):
            out[time_min >= start, s] = np.nan
        for first, last in frozen[s]:
            out[(time_min >= first) & (time_min <= last), s] = np.nan
    return out, since, frozen


def frozen_words(name: str, stretches: list[tuple[float, float]]) -> str:
    """What to say of a sensor's frozen stretches (:func:`frozen_stretches`), left out of its fit."""
    spans = ", ".join(f"t = {first:g} to {last:g} min" for first, last in stretches)
    return (
        f"{name}: its readings froze at one value ({spans}), more alike than its noise leaves to chance (a logger "
        "channel that repeated its last reading?): those repeats are left out"
    )
