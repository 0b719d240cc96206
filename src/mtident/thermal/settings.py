"""Identification methods, their tuning, the papers' presets and the data-driven default.

Methods (DESIGN.md contract): ``ukf`` (normal UKF), ``aukf`` (adaptive law of
Xia 2014), ``fukf`` (fading UKF of Yu 2019 Eqs 15-22), ``afukf`` (modified
adaptive fading UKF of Yu 2019: square-root UKF + normalised fading factor +
adaptive law) and ``lsq`` (batch least squares, the baseline).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, replace

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.ukf import AdaptiveLaw, FadingFactor, FilterConfig, MerweScaledSigmaPoints

__all__ = [
    "METHODS",
    "PRESETS",
    "DEFAULT_METHOD",
    "IDENTIFY_METHODS",
    "ROBUST_METHOD",
    "ThermalTuning",
    "filter_config",
    "tuning_from_data",
    "preset_tuning",
    "noise_sigma",
    "display_resolution",
    "reading_range",
    "on_display_steps",
    "step_from_grid",
    "DISPLAY_STEPS_C",
    "quick_estimate",
]

METHODS = ("ukf", "aukf", "fukf", "afukf", "lsq")
PRESETS = ("data", "xia2014", "yu2019")
# Chosen by the Monte Carlo study in benchmarks/bench_thermal.py (closest to the
# Cramér-Rao bound with calibrated intervals); see README.
# the model-robust estimate (sums of up to four modes); the others are the papers' first-order filters
ROBUST_METHOD = "robust"
IDENTIFY_METHODS = (ROBUST_METHOD, *METHODS)
DEFAULT_METHOD = ROBUST_METHOD


@dataclass(frozen=True, slots=True)
class ThermalTuning:
    """Initial state and noise of the temperature-rise filters, per sensor.

    Arrays have a leading sensor axis S.

    Attributes
    ----------
    initial_mean : ndarray, shape (S, 3)
        x̂₀ = [T₀ (°C), λ₀ (1/min), T∞,₀ (°C)].
    initial_cov : ndarray, shape (S, 3, 3)
        P₀.
    process_cov : ndarray, shape (S, 3, 3)
        Q₀.
    emission_cov : ndarray, shape (S, 1, 1)
        R₀ (°C²).
    threshold_C : float or ndarray, shape (S,)
        C of the adaptive law (H in seed 001).
    redraw : bool
        Redraw measurement sigma points (seed 001 Eq. 8; exact Kalman filter on
        linear models) or reuse the propagated ones (seed 000).
    parametrisation : {"rate", "slope"}
        State [T, λ, T∞] as the papers, or [T, s, λ] (see
        :func:`~mtident.thermal.model.slope_transition`).
    """

    initial_mean: FloatArray
    initial_cov: FloatArray
    process_cov: FloatArray
    emission_cov: FloatArray
    threshold_C: float | FloatArray = 1e-4
    redraw: bool = True
    parametrisation: str = "rate"


def filter_config(method: str, tuning: ThermalTuning) -> FilterConfig:
    """The UKF variant a method name stands for."""
    law = AdaptiveLaw(threshold=tuning.threshold_C, q_increase=10.0, q_decrease=0.1, r_step_fraction=0.01)
    # The data-driven tuning lets R be as small as the data's noise (1e-9 °C on a noise-free
    # curve), where P⁻ − K Py Kᵀ cancels to rounding: it runs in square-root form.
    square_root = tuning.parametrisation == "slope"
    base = FilterConfig(
        sigma_points=MerweScaledSigmaPoints(1.0, 2.0, 0.0), redraw=tuning.redraw, square_root=square_root, name=method
    )
    if method == "ukf":
        return base
    if method == "aukf":
        return replace(base, adaptive_law=law)
    # The papers' fading factor scales the gain (Eq. 12); the data-driven tuning scales P⁻
    # instead (strong tracking), which cannot overshoot (see FadingFactor).
    fading = FadingFactor() if not square_root else FadingFactor(form="covariance", max_factor=2.0)
    if method == "fukf":
        return replace(base, fading=fading)
    if method == "afukf":
        # Eq. 29 with one measured output gives λ = 1 (see FadingFactor).
        return replace(base, square_root=True, fading=replace(fading, normalisation=np.ones(1)), adaptive_law=law)
    msg = f"method {method!r} is not a filter; choose one of: {', '.join(METHODS)}"
    raise InputError(msg)


# Display steps a logger rounds to, coarsest first: decimal ones, and the binary ones of digital
# sensors (a DS18B20 reads in steps of 1/16 °C at 12 bits, 1/2 °C at 9 bits).
DISPLAY_STEPS_C = np.array(
    sorted({1.0, 0.5, 0.25, 0.125, 0.1, 0.0625, 0.05, 0.03125, 0.01, 0.005, 0.001}, reverse=True)
)


def on_display_steps(values: FloatArray) -> np.ndarray:
    """(..., S, len(DISPLAY_STEPS_C)): whether each reading is a whole multiple of each step (NaN: yes)."""
    multiples = np.asarray(values, dtype=float)[..., None] / DISPLAY_STEPS_C
    with np.errstate(invalid="ignore"):
        return ~(np.abs(multiples - np.round(multiples)) >= 1e-6)


def step_from_grid(on_grid: np.ndarray, spread: FloatArray) -> FloatArray:
    """Per sensor, the coarsest step every reading is a multiple of and the readings span at least
    twice (a flat ``20.0`` is not a 1 °C display); 0 where there is none."""
    usable = on_grid & (np.asarray(spread, dtype=float)[:, None] >= 2.0 * DISPLAY_STEPS_C - 1e-9)
    return np.where(usable.any(axis=1), DISPLAY_STEPS_C[np.argmax(usable, axis=1)], 0.0)


def display_resolution(values: FloatArray) -> FloatArray:
    """The step each sensor's readings are rounded to (°C), 0 where none is seen: the coarsest of
    the usual display steps (0.1, 0.01, 1/16 °C, ...) that fits every valid reading
    (:func:`step_from_grid`).

    Parameters
    ----------
    values : ndarray, shape (N, S)
    """
    return step_from_grid(np.asarray(on_display_steps(values).all(axis=0)), np.nan_to_num(reading_range(values)))


def reading_range(values: FloatArray) -> FloatArray:
    """Per sensor, the highest valid reading less the lowest (NaN for a column without one)."""
    y = np.asarray(values, dtype=float)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a column without a valid reading
        return np.nanmax(y, axis=0) - np.nanmin(y, axis=0)


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
    return np.maximum(np.array(out), display_resolution(values) / np.sqrt(12.0))


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
    return combined[np.isfinite(combined)]


def quick_estimate(time_min: FloatArray, values: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """T₀, λ and T∞ per sensor from the means of three equal thirds of the window.

    For T = T∞ + D e^(−λt), segment means A₁, A₂, A₃ spaced τ apart satisfy
    (A₃ − A₂)/(A₂ − A₁) = e^(−λτ), independent of D. Where the ratio is not in
    (0, 1) (no curvature yet, or noise), λ falls back to 3/window — a curve
    still rising steeply at the end of the window. Each sensor is taken on a
    uniform grid over its own span from its first to its last valid reading
    (missing readings and gaps interpolated), so T₀ is its first valid reading.

    Returns
    -------
    start_C, rate_per_min, steady_C : ndarray, shape (S,)
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


def tuning_from_data(time_min: FloatArray, values: FloatArray, start_min: float | None = None) -> ThermalTuning:
    """The default: initial values and noise taken from the window itself.

    The initial state is for ``start_min`` (default the window's first time),
    carried back along the first-order curve from each sensor's first valid
    sample (a flat start left out, a warm-up that began after the log).

    State [T, s, λ] (the "slope" parametrisation). T₀ from the first samples,
    λ and T∞ from :func:`quick_estimate` (s₀ = λ₀(T∞,₀ − T₀)), R from
    :func:`noise_sigma`. P₀ is broad — s and λ with 100 % standard deviation —
    so that the data, not the guess, decide. Q is tiny: the model is taken as
    right and the filter is a recursive Bayesian estimator of s and λ, whose
    intervals the Monte Carlo study shows to be calibrated; the adaptive filters
    adapt Q and R from there, with the adaptive law's threshold C = 2σ.
    """
    start, rate, steady = quick_estimate(time_min, values)
    sigma = noise_sigma(values, time_min)
    # A sensor whose first samples are left out (NaN: a flat start, see thermal.lsq.first_order_onset)
    # starts at t₀ on its first-order curve carried back from its first sample.
    first = np.array([time_min[np.flatnonzero(np.isfinite(col))[0]] for col in np.asarray(values, dtype=float).T])
    carried = steady + (start - steady) * np.exp(rate * (first - (time_min[0] if start_min is None else start_min)))
    carried = np.where(np.isfinite(carried), carried, start)
    carry_sd = 0.5 * np.abs(carried - start)
    start = carried
    slope = rate * (steady - start)
    S = len(start)
    mean = np.column_stack([start, slope, rate])
    cov = np.zeros((S, 3, 3))
    cov[:, 0, 0] = (2.0 * sigma) ** 2 + carry_sd**2
    cov[:, 1, 1] = np.maximum(np.abs(slope), 10.0 * sigma / max(float(np.ptp(time_min)), 1.0)) ** 2
    cov[:, 2, 2] = rate**2
    q = np.zeros((S, 3, 3))
    q[:, 0, 0] = (1e-3 * sigma) ** 2
    q[:, 1, 1] = (1e-7 * np.abs(slope) + 1e-12) ** 2
    q[:, 2, 2] = (1e-7 * rate) ** 2
    # C = 2σ: the law reacts to residuals the noise does not explain. The papers'
    # C = 1e-4 °C, far below the noise of a PT100, makes the filter chase every
    # noisy sample (R collapses; 57 of 200 Monte Carlo runs diverged).
    return ThermalTuning(
        mean, cov, q, (sigma**2)[:, None, None], threshold_C=2.0 * sigma, redraw=True, parametrisation="slope"
    )


def preset_tuning(preset: str, n_sensors: int) -> ThermalTuning:
    """The papers' settings, exactly.

    ``xia2014`` (seed 000 §3.1): x₀ = [10, 0.01, 30], P₀ = diag(0.5², 0.1², 0.1²),
    Q₀ = 0.001²·I, R₀ = 0.001², C = 1e-4, propagated sigma points.
    ``yu2019`` (seed 001 §2.1): x₀ = [10, 0.01, 30], P₀ = diag(0.25, 0.01, 0.01),
    Q₀ = 1e-6·I, R₀ = 1e-6, H = 1e-4, redrawn sigma points (Eq. 8).
    """
    if preset not in ("xia2014", "yu2019"):
        msg = f"preset {preset!r} is not one of: {', '.join(PRESETS)}"
        raise InputError(msg)
    mean = np.tile([10.0, 0.01, 30.0], (n_sensors, 1))
    cov = np.tile(np.diag([0.25, 0.01, 0.01]), (n_sensors, 1, 1))
    q = np.tile(1e-6 * np.eye(3), (n_sensors, 1, 1))
    r = np.full((n_sensors, 1, 1), 1e-6)
    return ThermalTuning(mean, cov, q, r, threshold_C=1e-4, redraw=(preset == "yu2019"), parametrisation="rate")
