"""Model-robust steady state: a warm-up as a sum of exponential modes.

A sensor on a machine heated by a constant power in a room is a linear system: its
temperature is T(t) = T∞ + Σₖ aₖ·e^(−t/τₖ), one term per thermal mode (heat
capacity) of the structure, with a lagged sensor or a distant part giving modes of
either sign. The papers' first-order model keeps one mode; a machine has several, and
a slow one not yet visible in the data moves T∞ far from what one mode predicts.

This module fits up to four modes (the family's number), their time constants at least a
factor ``MIN_MODE_RATIO`` apart, to all the data so far, by variable projection: for given time
constants the model is linear in T∞ and the amplitudes, so only the time constants are
searched, first on a log grid from the sampling interval to the largest time constant the
machine may have, then locally (:mod:`mtident.thermal.modal_search`; the types in
:mod:`mtident.thermal.modal_types`). The interval for T∞ is the profile-likelihood hull:
every model of the family, with every time constant up to ``max_time_constant_min``,
whose fit is within the chosen χ² quantile of the best, contributes the T∞ values it
allows. A slow mode that the data cannot yet exclude therefore widens the interval
until they can. With a reference run (:mod:`mtident.thermal.reference`) the time
constants are searched only within boxes around the reference's, which is what lets a
test stop early.

With a room sensor the room is an input of every mode's heat balance: the sensor less
the room follows T∞ − T_room + Σ aₖe^(−t/τₖ) + Σ gₖ(Fₖ[room] − room), where Fₖ is the
first-order lag of mode k (a steady room gives the sensor the room's level, whatever
the gains gₖ, which are free).

References
----------
Golub, G. and Pereyra, V. (2003). Separable nonlinear least squares: the variable
projection method and its applications. Inverse Problems 19(2), R1-R26.
"""

from __future__ import annotations

from dataclasses import replace
from typing import Any

import numpy as np
from scipy.special import chdtri, stdtrit

from mtident._threads import one_blas_thread
from mtident._typing import FloatArray
from mtident.thermal.modal_search import (
    Fits,
    Problem,
    best_per_count,
    choose_count,
    correlation_factor,
    design_columns,
    grid_candidates,
    grid_half_width,
    hull_end,
    interval_end,
    make_problem,
    modes_of,
    profile_bounds,
    refined_per_count,
    rising_best,
    room_lag,
    weighted_residuals,
)
from mtident.thermal.modal_types import (
    DEFAULT_MAX_TIME_CONSTANT_MIN,
    Binned,
    IntervalEnd,
    Mode,
    ModeFamily,
    SteadyState,
    bin_index,
    bin_samples,
)
from mtident.thermal.model import EQUILIBRIUM_FRACTION

__all__ = [
    "DEFAULT_MAX_TIME_CONSTANT_MIN",
    "Binned",
    "ModeFamily",
    "Mode",
    "IntervalEnd",
    "SteadyState",
    "bin_index",
    "best_fit",
    "bin_samples",
    "equilibrium_time",
    "fit_steady_state",
    "fitted_curve",
    "course_with_room",
    "model_curve",
]

# with a tolerance to meet, the grid's hull alone answers where it is this many times wider
_ROUGH_MARGIN = 2.0
# the level at which readings fitted better with a mode that does not rise contradict every mode
# rising (a likelihood-ratio test)
RISING_LEVEL = 0.99


# ---------------------------------------------------------------------------------------------
# The estimate


def fit_steady_state(
    binned: Binned,
    *,
    noise_C: float,
    interval_min: float,
    family: ModeFamily = ModeFamily(),
    levels: tuple[float, ...] = (0.95, 0.99),
    refine_within: float | None = None,
) -> SteadyState:
    """The model-robust T∞ of one sensor: the best-fitting sum of modes and the profile hull
    over every model of ``family`` the data do not exclude.

    Parameters
    ----------
    binned : Binned
        The sensor's readings from where its warm-up begins (:func:`bin_samples`); the modes
        are counted from the first bin.
    noise_C : float
        The readings' noise (°C, per reading), a floor under the residuals' own estimate.
    interval_min : float
        The sampling interval: modes much faster than it are not searched.
    family : ModeFamily
    levels : tuple of float
        Confidence levels of the intervals.
    refine_within : float, optional
        Refine a level's hull off the search grid only where the grid's own half-width is
        within this (°C): a monitor asking "within the tolerance?" needs no more where the
        grid already says no. Default: always refine.

    Returns
    -------
    SteadyState

    Examples
    --------
    >>> t = np.arange(0.0, 241.0)
    >>> warm = 26.7 - 8.8 * np.exp(-t / 62.5) + 0.02 * np.random.default_rng(0).standard_normal(t.size)
    >>> fit = fit_steady_state(bin_samples(t, warm), noise_C=0.02, interval_min=1.0)
    >>> round(fit.steady_C, 1), len(fit.modes)
    (26.7, 1)
    """
    with one_blas_thread():
        return _fit_steady_state(make_problem(binned, noise_C, interval_min, family), levels, refine_within)


def _fit_steady_state(problem: Problem, levels: tuple[float, ...], refine_within: float | None) -> SteadyState:
    candidates = grid_candidates(problem)
    if refine_within is not None:
        # the grid alone, where its hull is far wider than asked: no refinement (most of the
        # cost) would bring it within, so the answer to "is it within?" is already no
        grid_best = _grid_best(candidates)
        # the point estimate off the grid all the same (a few local fits): the grid's coarse best of
        # one mode made BIC choose three that overshoot, T∞ 0.2 °C below a rising sensor's readings
        point = choose_count(refined_per_count(problem, grid_best), len(problem.binned))
        rough = _steady_state(problem, candidates, grid_best, levels, refine=False, point=point)
        if not rough.determined or rough.half_width(max(levels)) > _ROUGH_MARGIN * refine_within:
            return rough
    return _steady_state(problem, candidates, best_per_count(problem, candidates), levels, refine_within)


def _grid_best(candidates: list[Fits]) -> dict[int, Fits]:
    """Per number of modes, the best-fitting model of the grid."""
    return {f.tau.shape[1]: f.take(int(np.argmin(f.rss))) for f in candidates if len(f.rss)}


def _steady_state(
    problem: Problem,
    candidates: list[Fits],
    best: dict[int, Fits],
    levels: tuple[float, ...],
    refine_within: float | None = None,
    refine: bool = True,
    point: Fits | None = None,
) -> SteadyState:
    """The estimate from the best fits per number of modes, and its hull over ``candidates``
    (refined off the grid where ``refine`` and, with ``refine_within``, where the grid's hull is
    within that); ``point``: the estimate's model, where not the one BIC chooses among ``best``."""
    binned, family = problem.binned, problem.family
    full = min(best.values(), key=lambda f: float(f.rss[0]))
    chosen = choose_count(best, len(binned)) if point is None else point
    candidates = [*candidates, *best.values()]
    if family.every_mode_rises and point is not None:
        candidates.append(point)  # the grid's shortcut's own refined model, which may be the rising one
    # the grid's coarse best fits can differ by more than chance where the refined ones would not:
    # only a refined search judges whether the readings contradict every mode rising
    rising = _rising_fit(problem, candidates, full, judge=refine) if family.every_mode_rises else None
    if rising is not None:
        chosen = rising
    elif family.every_mode_rises:
        # the readings contradict every mode rising: the answer is the free family's, and says so
        family = replace(family, every_mode_rises=False)
        problem = replace(problem, family=family)
    base = full if rising is None else rising
    shift = problem.centre + (0.0 if binned.room_C is None else float(binned.room_C[-1]))
    modes = modes_of(chosen)
    # the fit is of the readings less the room: the start is at the room's first level
    start = float(design_columns(problem, chosen.tau)[0, 0] @ chosen.theta[0]) + problem.centre
    if binned.room_C is not None:
        start += float(binned.room_C[0])
    steady = float(chosen.steady[0]) + shift
    dof = float(len(binned) - full.n_params)
    common: dict[str, Any] = dict(
        steady_C=steady,
        modes=modes,
        room_gains=tuple(float(g) for g in chosen.theta[0, 1 + chosen.tau.shape[1] :])
        if binned.room_C is not None
        else (),
        start_C=start,
        origin_min=problem.origin,
        rss=float(full.rss[0]),
        dof=dof,
        n_bins=len(binned),
        room_level_C=None if binned.room_C is None else float(binned.room_C[-1]),
        family=family,
        fits={k: float(f.rss[0]) for k, f in best.items()},
    )
    if dof < 2:
        wide = (-np.inf, np.inf)
        return SteadyState(
            interval_C={q: wide for q in levels},
            ends={},
            equilibrium_time_min=float("nan"),
            noise_C=float(np.sqrt(problem.sigma2)),
            correlation_factor=1.0,
            determined=False,
            **common,
        )
    factor, sigma2 = _residual_variance(problem, full)
    intervals: dict[float, tuple[float, float]] = {}
    ends: dict[float, tuple[IntervalEnd, IntervalEnd]] = {}
    refined: dict[float, bool] = {}
    widest_refined: bool | None = None
    ends_models: tuple[Fits, Fits] = (full, full)
    for q in sorted(levels, reverse=True):
        threshold = float(base.rss[0]) + sigma2 * float(stdtrit(dof, 0.5 + q / 2.0)) ** 2
        gap = threshold - float(base.rss[0])
        # the grid's hull is within the true one: where the widest level's is already wider than
        # asked, the refinement (most of the cost) cannot change the answer to "is it within?",
        # and the narrower levels are refined only along with the widest
        refine_level = refine
        if refine and refine_within is not None:
            if widest_refined is None:
                widest_refined = (
                    grid_half_width(
                        candidates, threshold, float(chosen.steady[0]), rising is not None, problem.rising_slack_C
                    )
                    <= refine_within
                )
            refine_level = widest_refined
        # a narrower level's end is polished from the wider level's end model too (the same ridges
        # set both, and a reference family's one start can miss their basin); with a tolerance the
        # widest level's hull misses, from that model alone: a report's interval while the decision
        # waits, searched in full once the decision may be near
        near = (
            refine_within is None
            or not intervals
            or max(steady - intervals[max(intervals)][0], intervals[max(intervals)][1] - steady) <= refine_within
        )
        seeds = [ends_models[0]] if intervals else None
        low = hull_end(problem, candidates, threshold, -1.0, gap, base, refine_level, seeds, not near)
        seeds = [ends_models[1]] if intervals else None
        high = hull_end(problem, candidates, threshold, +1.0, gap, base, refine_level, seeds, not near)
        ends_models = (low, high)
        low_end, high_end = (low, threshold), (high, threshold)
        if float(chosen.rss[0]) > threshold:
            low_end, high_end = _with_own_class(problem, candidates, chosen, gap, refine_level, low_end, high_end)
        lo = min(float(profile_bounds(*low_end)[0][0]) + shift, steady)
        hi = max(float(profile_bounds(*high_end)[1][0]) + shift, steady)
        intervals[q] = (lo, hi)
        ends[q] = (interval_end(*low_end, -1.0, shift), interval_end(*high_end, +1.0, shift))
        refined[q] = refine_level
    t_eq = equilibrium_time(modes, steady, start, problem.origin)
    intervals = {q: intervals[q] for q in levels}
    return SteadyState(
        interval_C=intervals,
        ends=ends,
        equilibrium_time_min=t_eq,
        noise_C=float(np.sqrt(sigma2)),
        correlation_factor=factor,
        refined=refined,
        **common,
    )


def _residual_variance(problem: Problem, full: Fits) -> tuple[float, float]:
    """How much the residuals' correlation widens a variance, and the variance of a reading the
    intervals and tests count with: the best fit's residual variance, at least the noise's, so
    widened."""
    dof = max(len(problem.binned) - full.n_params, 1)
    factor = correlation_factor(weighted_residuals(problem, full))
    return factor, max(float(full.rss[0]) / dof, problem.sigma2) * factor


def _rising_fit(problem: Problem, candidates: list[Fits], full: Fits, judge: bool = True) -> Fits | None:
    """The best fit whose modes all rise (:func:`~mtident.thermal.modal_search.rising_best`),
    where it fits no worse than the best free fit within chance (a likelihood-ratio test at
    :data:`RISING_LEVEL`, of as many degrees of freedom as the free fit has parameters more, at
    least one; not ``judge``: any); None where the readings contradict every mode rising (a
    sensor's own lag, a second heat path, a fall)."""
    rising = rising_best(candidates, problem.rising_slack_C)
    if rising is None or not judge:
        return rising
    statistic = (float(rising.rss[0]) - float(full.rss[0])) / _residual_variance(problem, full)[1]
    extra = max(full.n_params - rising.n_params, 1)
    return rising if statistic <= float(chdtri(extra, 1.0 - RISING_LEVEL)) else None


def _with_own_class(
    problem: Problem,
    candidates: list[Fits],
    chosen: Fits,
    gap: float,
    refine: bool,
    low_end: tuple[Fits, float],
    high_end: tuple[Fits, float],
) -> tuple[tuple[Fits, float], tuple[Fits, float]]:
    """Each end widened by the estimate's own number of modes profiled around it, where the fit
    with the most modes excludes the estimate at this level (BIC keeps fewer modes than the
    likelihood ratio allows: the extra modes follow structure in the residuals, such as rounding
    held over many readings, that is not noise). The estimate's own uncertainty then belongs to
    the interval as much as the models near the most-mode fit; each end is a model with the
    threshold its side of the hull was searched under."""
    k = chosen.tau.shape[1]
    same = [f for f in candidates if f.tau.shape[1] == k]
    own = float(chosen.rss[0]) + gap
    own_low = hull_end(problem, same, own, -1.0, gap, chosen, refine)
    own_high = hull_end(problem, same, own, +1.0, gap, chosen, refine)
    if profile_bounds(own_low, own)[0][0] < profile_bounds(*low_end)[0][0]:
        low_end = (own_low, own)
    if profile_bounds(own_high, own)[1][0] > profile_bounds(*high_end)[1][0]:
        high_end = (own_high, own)
    return low_end, high_end


def best_fit(
    binned: Binned, *, noise_C: float, interval_min: float, family: ModeFamily = ModeFamily()
) -> tuple[float, int, float]:
    """The best fit of ``family`` alone, without an interval: its residual sum of squares, its
    number of parameters, and how much its residuals' correlation widens a variance (a
    reference's boxed fit is compared with it).

    Parameters
    ----------
    binned : Binned
    noise_C, interval_min : float
    family : ModeFamily

    Returns
    -------
    rss : float
    n_params : int
    correlation_factor : float
    """
    problem = make_problem(binned, noise_C, interval_min, family)
    with one_blas_thread():
        best = min(best_per_count(problem, grid_candidates(problem)).values(), key=lambda f: float(f.rss[0]))
    return float(best.rss[0]), best.n_params, correlation_factor(weighted_residuals(problem, best))


def model_curve(modes: tuple[Mode, ...], steady_C: float, origin_min: float, time_min: FloatArray) -> FloatArray:
    """The curve of a sum of modes (no room term) at ``time_min`` (from the log's start); before
    ``origin_min`` it holds its value there.

    Parameters
    ----------
    modes : tuple of Mode
    steady_C : float
    origin_min : float
    time_min : ndarray

    Returns
    -------
    ndarray, the shape of ``time_min``
    """
    u = np.maximum(np.asarray(time_min, dtype=float) - origin_min, 0.0)
    out = np.full(u.shape, float(steady_C))
    for m in modes:
        out = out + m.amplitude_C * np.exp(-u / m.time_constant_min)
    return out


def fitted_curve(
    fit: SteadyState,
    time_min: FloatArray,
    room_C: FloatArray | None = None,
    modes: tuple[Mode, ...] | None = None,
    steady_C: float | None = None,
) -> FloatArray:
    """The fitted model's course at ``time_min`` (from the log's start), with the room's own
    course where the fit had a room sensor (``room_C`` at those times; held at its last level
    where missing); ``modes`` and ``steady_C`` replace the best model's (an interval's end).

    Parameters
    ----------
    fit : SteadyState
    time_min : ndarray, shape (N,)
    room_C : ndarray, shape (N,), optional
    modes : tuple of Mode, optional
    steady_C : float, optional

    Returns
    -------
    ndarray, shape (N,)
    """
    return course_with_room(
        fit.modes if modes is None else modes,
        fit.steady_C if steady_C is None else steady_C,
        fit.origin_min,
        time_min,
        room_C,
        fit.room_level_C,
        fit.room_gains,
        tuple(m.time_constant_min for m in fit.modes),
    )


def course_with_room(
    modes: tuple[Mode, ...],
    steady_C: float,
    origin_min: float,
    time_min: FloatArray,
    room_C: FloatArray | None = None,
    room_level_C: float | None = None,
    room_gains: tuple[float, ...] = (),
    gain_time_constants_min: tuple[float, ...] = (),
) -> FloatArray:
    """A sum of modes' course at ``time_min``, following the room as logged where the fit had a
    room sensor: T∞ (``steady_C``) is at the room's level ``room_level_C``, the course moves with
    ``room_C`` (NaN: missing, interpolated; held at its last level after it), and each mode's
    gain on the room acts through that mode's lag.

    Parameters
    ----------
    modes : tuple of Mode
    steady_C : float
        T∞ at ``room_level_C`` (°C).
    origin_min : float
        Where the modes begin (min).
    time_min : ndarray, shape (N,)
    room_C : ndarray, shape (N,), optional
        The room at ``time_min``; None: no room sensor (a course about T∞ alone).
    room_level_C : float, optional
        The room's level T∞ is given at.
    room_gains : tuple of float
        Each mode's gain on the room (:attr:`SteadyState.room_gains`).
    gain_time_constants_min : tuple of float
        The time constants the gains act through (the best model's).

    Returns
    -------
    ndarray, shape (N,)
    """
    t = np.asarray(time_min, dtype=float)
    if room_level_C is None or room_C is None:
        return model_curve(modes, steady_C, origin_min, t)
    room = np.asarray(room_C, dtype=float)
    valid = np.isfinite(room)
    room = np.interp(t, t[valid], room[valid]) if valid.any() else np.full(t.shape, room_level_C)
    curve: FloatArray = model_curve(modes, steady_C - room_level_C, origin_min, t) + room
    after = t >= origin_min
    if room_gains and after.sum() > 1:
        lagged = room_lag(room[after], t[after], np.asarray(gain_time_constants_min))
        curve[after] += np.asarray(room_gains) @ (lagged - room[after])
    return curve


def equilibrium_time(modes: tuple[Mode, ...], steady_C: float, start_C: float, origin_min: float) -> float:
    """When a sum of modes last leaves the band of 5 % of its total rise around T∞ (minutes
    from the log's start; the papers' thermal-equilibrium time for any number of modes).

    Parameters
    ----------
    modes : tuple of Mode
    steady_C, start_C : float
    origin_min : float

    Returns
    -------
    float
    """
    if not modes:
        return origin_min
    slowest = max(m.time_constant_min for m in modes)
    u = np.concatenate([[0.0], np.geomspace(1e-3, 40.0 * slowest, 4000)])
    curve = model_curve(modes, steady_C, 0.0, u)
    outside = np.flatnonzero(np.abs(curve - steady_C) > (1.0 - EQUILIBRIUM_FRACTION) * abs(steady_C - start_C))
    return origin_min + (float(u[min(outside[-1] + 1, len(u) - 1)]) if outside.size else 0.0)


def log_time_constant_sd(binned: Binned, fit: SteadyState) -> tuple[float, ...]:
    """The standard deviation of the log of each of the best model's time constants (its relative
    uncertainty), from the Gauss-Newton curvature of the fit at the noise the fit saw.

    Parameters
    ----------
    binned : Binned
        The readings the fit was made from.
    fit : SteadyState

    Returns
    -------
    tuple of float, one per mode of ``fit.modes``
    """
    if not fit.modes:
        return ()
    problem = make_problem(binned, fit.noise_C, 1.0, fit.family)
    tau = np.array([[m.time_constant_min for m in fit.modes]])
    amplitude = np.array([m.amplitude_C for m in fit.modes])
    X = design_columns(problem, tau)[0]
    u = (binned.time_min - problem.origin)[:, None]
    slopes = amplitude * (u / tau) * np.exp(-u / tau)  # ∂model/∂log τ
    J = np.concatenate([X, slopes], axis=1)
    info = (J * binned.count[:, None]).T @ J + np.diag(
        np.concatenate([problem.penalty(len(fit.modes)), np.zeros(len(fit.modes))])
    )
    cov = fit.noise_C**2 * np.linalg.pinv(info)
    return tuple(float(np.sqrt(max(v, 0.0))) for v in np.diagonal(cov)[-len(fit.modes) :])
