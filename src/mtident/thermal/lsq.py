"""Batch least-squares fit of the temperature-rise model: the baseline a user would otherwise reach for."""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np
from scipy.special import ndtr, ndtri

from mtident._typing import FloatArray, IntArray
from mtident.thermal.model import rise_curve

# how often a true first-order curve is taken for a lagged one: 2.5σ on each of 3 leading samples
_LAG_FALSE_FLAG = 3 * 2 * float(ndtr(-2.5))
# λ's range (1/min): from a rise too slow to tell from a line in any window to one over within seconds
_RATE_BOUNDS = (1e-6, 10.0)
# points of the log-λ grid the profile is searched on before Brent's method refines it (a step of
# 7 % in λ: an exponential's profile has one minimum per basin much wider than that)
_RATE_GRID = 241

__all__ = [
    "LeastSquaresFit",
    "fit_rise",
    "rise_threshold",
    "flat_lead",
    "late_onset",
    "first_level",
    "first_order_onset",
    "cramer_rao_bound",
]


@dataclass(frozen=True, slots=True)
class LeastSquaresFit:
    """Estimates [T₀, λ, T∞] per sensor (S, 3), their covariance (S, 3, 3) and residual σ (S,).

    Attributes
    ----------
    params : ndarray, shape (S, 3)
        [T₀, λ, T∞] per sensor (°C, 1/min, °C), T₀ at ``time_min`` = 0.
    cov : ndarray, shape (S, 3, 3)
        Their covariance; 1e12 on the diagonal where the fit gave none (not identified).
    residual_sigma : ndarray, shape (S,)
        The residuals' standard deviation (°C), with N − 3 degrees of freedom.
    """

    params: FloatArray
    cov: FloatArray
    residual_sigma: FloatArray


def fit_rise(time_min: FloatArray, values: FloatArray, guess: FloatArray) -> LeastSquaresFit:
    """Fit T(t) = T∞ + (T₀ − T∞)e^(−λt) to each column of ``values`` by least squares.

    The fit is separable: for a given λ, T₀ and T∞ are a straight-line regression on 1 − e^(−λt),
    so the residual sum of squares is profiled over λ alone, searched on a log grid over the
    bounds and refined by Brent's method around the grid's best (no start to be trapped near, and
    no interpreter between the linear parameters). The covariance is the Gauss-Newton one at
    the optimum, scaled by the residual variance (as scipy's ``curve_fit`` with
    ``absolute_sigma=False``), so it needs no noise level from the user.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
    values : ndarray, shape (N, S)
        NaN samples are left out.
    guess : ndarray, shape (S, 3)
        [T₀, λ, T∞] kept by a sensor that cannot be fitted.

    Returns
    -------
    LeastSquaresFit
        A sensor with fewer than three valid samples keeps ``guess`` (its level where that is not
        finite), with 1e12 on its covariance's diagonal; so does any fit whose covariance is
        not finite (three samples, or a flat window).
    """
    params, covs, sigmas = [], [], []
    for s in range(values.shape[1]):
        ok = np.isfinite(values[:, s])
        t, y = time_min[ok], values[ok, s]
        start = np.asarray(guess[s], dtype=float).copy()
        level = float(np.mean(y)) if y.size else 0.0
        start[[0, 2]] = np.where(np.isfinite(start[[0, 2]]), start[[0, 2]], level)
        start[1] = np.clip(start[1], _RATE_BOUNDS[0], _RATE_BOUNDS[1]) if np.isfinite(start[1]) else 0.01
        p, c = _profiled_fit(t, y) if y.size >= 3 else (start, np.full((3, 3), np.inf))
        if not np.all(np.isfinite(c)):
            c = np.diag(np.full(3, 1e12))
        params.append(p)
        covs.append(c)
        resid = y - rise_curve(t, *p)
        sigmas.append(np.sqrt(np.sum(resid**2) / max(len(y) - 3, 1)))
    return LeastSquaresFit(np.array(params), np.array(covs), np.array(sigmas))


def _line_on_rise(time_min: FloatArray, values: FloatArray, log_rate: FloatArray) -> tuple[FloatArray, ...]:
    """For each log λ (G,): the regression of the values on u = 1 − e^(−λt): T₀ (the value at u = 0),
    T∞ − T₀ (the slope) and the residual sum of squares."""
    u = -np.expm1(-np.exp(log_rate)[:, None] * time_min[None, :])  # (G, N)
    du = u - u.mean(axis=1, keepdims=True)
    dy = values - values.mean()
    suu = np.einsum("gn,gn->g", du, du)
    suy = du @ dy
    slope = np.where(suu > 0, suy / np.where(suu > 0, suu, 1.0), 0.0)
    start = values.mean() - slope * u.mean(axis=1)
    rss = np.maximum(float(dy @ dy) - slope * suy, 0.0)
    return start, slope, rss


def _profiled_fit(time_min: FloatArray, values: FloatArray) -> tuple[FloatArray, FloatArray]:
    """[T₀, λ, T∞] at the least residual sum of squares over λ within the bounds, and their
    covariance (infinite where the Jacobian is rank-deficient beyond what a pseudo-inverse drops,
    or with no residual degree of freedom)."""
    from scipy.optimize import minimize_scalar  # here, not at the top: it costs ~0.3 s of start-up

    lower, upper = np.log(_RATE_BOUNDS)
    grid = np.linspace(lower, upper, _RATE_GRID)
    best = int(np.argmin(_line_on_rise(time_min, values, grid)[2]))
    bracket = (grid[max(best - 1, 0)], grid[min(best + 1, len(grid) - 1)])
    found = minimize_scalar(
        lambda phi: float(_line_on_rise(time_min, values, np.array([phi]))[2][0]),
        bounds=bracket,
        method="bounded",
        options={"xatol": 1e-10},
    )
    log_rate = float(found.x) if found.fun <= _line_on_rise(time_min, values, grid[[best]])[2][0] else grid[best]
    start, slope, rss = (float(a[0]) for a in _line_on_rise(time_min, values, np.array([log_rate])))
    rate = float(np.exp(log_rate))
    params = np.array([start, rate, start + slope])
    decay = np.exp(-rate * time_min)
    jac = np.column_stack([decay, slope * time_min * decay, 1.0 - decay])
    _, sv, vt = np.linalg.svd(jac, full_matrices=False)
    dof = len(values) - 3
    if dof <= 0 or sv[-1] <= np.finfo(float).eps * max(jac.shape) * sv[0]:
        # a direction the window does not determine (λ at a bound, where its column is another's):
        # not identified, rather than the zero variance a pseudo-inverse would give that direction
        return params, np.full((3, 3), np.inf)
    return params, (vt.T / sv**2) @ vt * rss / dof


def cramer_rao_bound(
    time_min: FloatArray, start_C: float, rate_per_min: float, steady_C: float, sigma_C: float
) -> FloatArray:
    """Cramér-Rao bound (covariance, 3×3) of [T₀, λ, T∞] for white noise σ at the sample times.

    Inverse of the Fisher information JᵀJ/σ², J the sensitivities of T(t).

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        Sample times (min), t = 0 at T₀.
    start_C, rate_per_min, steady_C : float
        The curve the sensitivities are taken on: T₀ (°C), λ (1/min) and T∞ (°C) of
        T(t) = T∞ + (T₀ − T∞)e^(−λt).
    sigma_C : float
        The noise's standard deviation (°C, per sample).

    Returns
    -------
    ndarray, shape (3, 3)
        The covariance bound of [T₀, λ, T∞].

    Raises
    ------
    numpy.linalg.LinAlgError
        The information is exactly singular, as where T₀ = T∞ (no rise). Fewer than three
        distinct times need not raise: the information is then singular only up to rounding and
        the bound returned is meaningless.
    """
    t = np.asarray(time_min, dtype=float)
    decay = np.exp(-rate_per_min * t)
    jac = np.column_stack([decay, -(start_C - steady_C) * t * decay, 1.0 - decay])
    return np.linalg.inv(jac.T @ jac / sigma_C**2)


MIN_RISE_C = 0.1
"""The smallest change from a sensor's first level taken as its warm-up's start (°C), or 6σ."""


def rise_threshold(sigma: FloatArray, min_rise_C: float = MIN_RISE_C) -> FloatArray:
    """A change that is a rise, not noise: ``min_rise_C``, or 6σ if larger.

    Parameters
    ----------
    sigma : ndarray, shape (S,)
        Noise level per sensor (°C).
    min_rise_C : float, optional
        The smallest change taken as a rise (°C).

    Returns
    -------
    ndarray, shape (S,)
        The threshold per sensor (°C).
    """
    return np.maximum(min_rise_C, 6.0 * np.asarray(sigma))


def flat_lead(
    time_min: FloatArray,
    values: FloatArray,
    sigma: FloatArray,
    min_rise_C: float = MIN_RISE_C,
    min_flat_min: float = 10.0,
) -> IntArray:
    """Per sensor, the index of the last sample at the first level, where a late warm-up begins.

    The logger started before the spindle: the sensor stays at its first level
    (the median of its first three samples) within max(``min_rise_C``, 6σ) for
    ``min_flat_min`` minutes or more, then departs. 0 where it departs sooner
    (a warm-up from the first sample); ``len(time_min)`` where it never departs.
    A sensor behind a thermal lag also starts slowly (the sample's stay within
    0.12 °C of their first level for up to 6 min), but rises from the start: the
    default 10 min leaves those to :func:`first_order_onset`'s lag rule, which fits
    them better than a cut at the last flat sample (at L = 28 min a 5-min rule
    sent four of the sample's ten T∞ off by 15 to 40 °C).

    Parameters
    ----------
    time_min, values
        As for :func:`~mtident.thermal.measured.measured_and_settled`.
    sigma : ndarray, shape (S,)
        Noise level per sensor (°C).
    min_rise_C : float, optional
        The smallest departure from the first level taken as a rise (°C).
    min_flat_min : float, optional
        How long a sensor must stay at its first level to be a late warm-up (min).

    Returns
    -------
    ndarray of int, shape (S,)
    """
    t = np.asarray(time_min, dtype=float)
    y = np.asarray(values, dtype=float)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a column with no valid sample
        level = np.nanmedian(y[:3], axis=0)
    with np.errstate(invalid="ignore"):
        departed = np.abs(y - level) > rise_threshold(sigma, min_rise_C)
    first = np.argmax(departed, axis=0)
    # Flat for as long as it was seen flat: to its last flat reading and one sampling step on. Judged
    # by its first departed reading instead, a gap in the log counted as flat minutes (5 missing
    # minutes in the papers' first 10 made a warm-up from the first sample a late one).
    step = float(np.median(np.diff(t))) if len(t) > 1 else 0.0
    # a sensor already off its first three readings' median at its first reading rises from the
    # start: readings 10 min or more apart put that median on the rise
    late = (first > 0) & (t[np.maximum(first - 1, 0)] + step - t[0] >= min_flat_min)
    return np.where(~departed.any(axis=0), len(t), np.where(late, first - 1, 0))


def late_onset(time_min: FloatArray, values: FloatArray, sigma: FloatArray) -> IntArray:
    """Per sensor, the sample a late warm-up is fitted from: its last flat sample
    (:func:`flat_lead`), 0 for a warm-up from the log's start and for a sensor that
    never rises (it has no rise to fit from).

    Parameters
    ----------
    time_min, values, sigma
        As for :func:`flat_lead`.

    Returns
    -------
    ndarray of int, shape (S,)
    """
    last_flat = flat_lead(time_min, values, sigma)
    return np.where(last_flat < len(time_min), last_flat, 0)


def first_level(values: FloatArray) -> FloatArray:
    """Per sensor, the level a late warm-up holds before its rise: the median of the
    valid ones among its first three samples (NaN for a sensor with none).

    Parameters
    ----------
    values : ndarray, shape (N, S)
        Readings (°C, NaN: missing); only the first three rows are read.

    Returns
    -------
    ndarray, shape (S,)
        The level (°C).
    """
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a sensor without a valid first sample
        answer: FloatArray = np.nanmedian(np.asarray(values, dtype=float)[:3], axis=0)
        return answer


def first_order_onset(time_min: FloatArray, values: FloatArray, lead_fraction: float = 0.1) -> IntArray:
    """Per sensor, the index of the first sample a first-order curve describes.

    A first-order rise is steepest at its start. A sensor behind a thermal lag
    (its own mass, the glue, the heat's way from the bearing to the surface)
    starts flat instead, and its first samples lie below any first-order curve
    through the rest; fitted from t₀, that S-shaped start pulls T∞ up (the
    sample log: +0.3 to +0.6 °C from 60 min, outside the 95 % intervals). The
    leading samples (within the first ``lead_fraction`` of the window, at least
    3) that the best first-order fit misses by more than 2.5σ (σ from
    :func:`~mtident.thermal.readings.noise_sigma`), and the samples right after
    them missed by more than σ/2 on the same side (the lag's tail), are left
    out, and the fit repeated once without them. 0 for a sensor that fits from
    its first sample. Leaving out a few samples of a true first-order curve by
    mistake costs little (no bias, slightly wider intervals); keeping a flat
    start costs a bias, so the thresholds are low.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        The window's sample times (min).
    values : ndarray, shape (N, S)
        The window's readings (°C, NaN: missing).
    lead_fraction : float, optional
        The share of the window whose leading samples may be left out.

    Returns
    -------
    ndarray of int, shape (S,)
        The index of the first sample to fit from; all 0 for a window too short to judge.

    Examples
    --------
    >>> t = np.arange(0.0, 61.0)
    >>> lagged = 20 + 10 * (1 - (94 * np.exp(-t / 94) - np.exp(-t)) / 93)  # a 1-min sensor lag
    >>> plain = 20 + 10 * (1 - np.exp(-t / 94))
    >>> noise = 0.02 * np.random.default_rng(0).standard_normal((61, 2))
    >>> first_order_onset(t, np.column_stack([lagged, plain]) + noise).tolist()
    [4, 0]
    """
    from mtident.thermal.readings import noise_sigma, quick_estimate

    t = np.asarray(time_min, dtype=float)
    y = np.asarray(values, dtype=float)
    onsets = np.zeros(y.shape[1], dtype=int)
    lead = max(3, int(lead_fraction * len(t)))
    if len(t) < lead + 6:
        return onsets
    sigma = np.maximum(noise_sigma(y, t), 1e-6)
    # a warm-up that begins after the log: its flat minutes go first; each sensor's leading samples
    # count from its own onset (another sensor's late start is no reason to cut this one)
    onsets = late_onset(t, y, sigma)
    leads = np.minimum(lead + onsets, len(t) // 2)
    # 2.5σ over the 3 leading samples of a 1-min log: one false flag in 27 curves. A 1-Hz log has
    # 180 leading samples, and 2.5σ flagged nearly every true first-order curve as lagged; the
    # threshold keeps that rate whatever the number of samples.
    threshold = max(2.5, float(-ndtri(_LAG_FALSE_FLAG / 2.0 / lead)))
    for _ in range(2):
        used = y.copy()
        for s in np.flatnonzero(onsets).tolist():
            used[: onsets[s], s] = np.nan
        start, rate, steady = quick_estimate(t, used)
        fit = fit_rise(t, used, np.column_stack([start, rate, steady]))
        curve = rise_curve(t[:, None], fit.params[:, 0], fit.params[:, 1], fit.params[:, 2])
        z = (y - curve) / sigma
        for s in range(y.shape[1]):
            flagged = np.flatnonzero(np.abs(z[: leads[s], s]) > threshold)
            if not flagged.size:
                continue
            # the lag's decay goes on past the last flagged sample: take the run of same-sign misses beyond σ/2
            end = int(flagged[-1]) + 1
            sign = np.sign(z[flagged[-1], s])
            while end < leads[s] and sign * z[end, s] > 0.5:
                end += 1
            onsets[s] = max(onsets[s], end)
    return onsets
