"""The papers' first-order filters (Xia et al. 2014, Yu et al. 2019) run over the identification window,
or least squares fitted to it, and their prediction after it: the course each sensor's first-order
answer (:mod:`mtident.thermal.first_order`) is made of. The room, where a room sensor is given, is
the filters' input (:func:`room_rates`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import CovarianceError, InputError
from mtident.io.logs import TemperatureLog
from mtident.thermal.lsq import fit_rise
from mtident.thermal.model import (
    heat_balance_path,
    observe_temperature,
    rise_curve,
    slope_transition,
    to_physical,
    transition_for,
)
from mtident.thermal.settings import ThermalTuning, filter_config
from mtident.ukf import (
    FilterCarry,
    FilterConfig,
    FilterRecord,
    GaussianState,
    filter_step,
    forecast,
    run_filter,
    transition_at,
)

__all__ = [
    "filter_window",
    "room_input",
    "room_rates",
]

# a papers' preset is their noise covariances, set for their sampling and rise
PRESET_HINT = (
    "the '{preset}' preset's noise covariances were set for the paper's readings, not these: preset 'data' "
    "takes them from the readings"
)


def _profile_rss(time_min: FloatArray, values: FloatArray, rates: FloatArray, with_drift: bool) -> FloatArray:
    """Residual sum of squares of a + b·e^(−λt) (+ c·t) for each λ in ``rates``, linear parameters solved out."""
    t = time_min - time_min[0]
    columns = [np.ones((len(rates), len(t))), np.exp(-rates[:, None] * t[None, :])]
    if with_drift:
        columns.append(np.broadcast_to(t / max(t[-1], 1e-9), (len(rates), len(t))))
    basis = np.stack(columns, axis=-1)  # (G, N, k)
    gram = np.swapaxes(basis, -1, -2) @ basis + 1e-12 * np.eye(basis.shape[-1])
    coef = np.linalg.solve(gram, (np.swapaxes(basis, -1, -2) @ values)[..., None])[..., 0]
    residual = values - (basis @ coef[..., None])[..., 0]
    answer: FloatArray = np.sum(residual**2, axis=-1)
    return answer


def best_rss(time_min: FloatArray, values: FloatArray, with_drift: bool) -> float:
    """Smallest RSS over λ by three rounds of a zooming log-spaced grid (no local-minimum trap)."""
    span = max(float(time_min[-1] - time_min[0]), 1e-9)
    lo, hi = np.log(0.01 / span), np.log(100.0 / span)
    best = np.inf
    for _ in range(3):
        grid = np.linspace(lo, hi, 41)
        rss = _profile_rss(time_min, values, np.exp(grid), with_drift)
        i = int(np.argmin(rss))
        best = min(best, float(rss[i]))
        step = grid[1] - grid[0]
        lo, hi = grid[i] - step, grid[i] + step
    return best


def filter_window(
    time_min: FloatArray,
    values: FloatArray,
    config: FilterConfig,
    tuning: ThermalTuning,
    room_rate: FloatArray | None = None,
) -> tuple[FilterRecord, FloatArray, FloatArray]:
    """Filter samples (N, S) of every sensor at once; the first is measured at t₀ itself (Δt = 0).

    ``room_rate`` (N,), °C/min over each step, makes the room the input of the
    heat balance (slope parametrisation only; see
    :func:`~mtident.thermal.model.slope_transition`). Returns the filter record
    and the per-step mean (N, S, 3) and covariance (N, S, 3, 3) of [T, λ, T∞]
    whatever the parametrisation.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        Sample times (min).
    values : ndarray, shape (N, S)
        Readings (°C, NaN: a missing measurement).
    config : FilterConfig
        The UKF variant (:func:`~mtident.thermal.settings.filter_config`).
    tuning : ThermalTuning
        Initial state and covariances, and the parametrisation.
    room_rate : ndarray, shape (N,), optional
        The room's rate over each step (°C/min). None: a steady room.

    Returns
    -------
    record : FilterRecord
        The filter's record, in the tuning's parametrisation.
    mean : ndarray, shape (N, S, 3)
        [T, λ, T∞] after each sample (°C, 1/min, °C).
    cov : ndarray, shape (N, S, 3, 3)
        Their covariance.
    """
    dts = np.diff(time_min, prepend=time_min[0])
    record = run_filter(
        GaussianState(tuning.initial_mean, tuning.initial_cov),
        values[..., None],
        _transition_with(dts, tuning.parametrisation, room_rate),
        observe_temperature,
        tuning.process_cov,
        tuning.emission_cov,
        config,
    )
    means, covs = to_physical(record.means, record.covs, tuning.parametrisation)
    return record, means, covs


def _transition_with(
    dts: FloatArray, parametrisation: str = "rate", room_rate: FloatArray | None = None
) -> Callable[[FloatArray, int], FloatArray]:  # a closure over the step intervals
    step = transition_for(parametrisation)
    if room_rate is not None:

        def with_room(points: FloatArray, k: int) -> FloatArray:
            return slope_transition(points, dts[k], room_rate[k])

        return with_room

    def transition(points: FloatArray, k: int) -> FloatArray:
        return step(points, dts[k])

    return transition


def _curve_with_room(time_min: FloatArray, values: FloatArray, room_rate: FloatArray, final: FloatArray) -> FloatArray:
    """The identified heat balance (final λ, final T∞ over the room) run over the window with the room as input.

    Started from each sensor's first valid sample; ``final`` (S, 3) is [T, λ, T∞] at the window's end.
    """
    rate, steady_end = final[:, 1], final[:, 2]
    dts = np.diff(time_min, prepend=time_min[0])
    room_change = np.cumsum(room_rate * dts)  # the room's level relative to t₀
    first = np.array([np.flatnonzero(np.isfinite(col))[0] for col in values.T])
    T = values[first, np.arange(values.shape[1])]
    # s = λ(T_room + ΔT∞ − T) at the first sample, with ΔT∞ = T∞ − T_room at the window's end
    slope = rate * (steady_end - room_change[-1] + room_change[first] - T)
    curve = heat_balance_path(np.stack([T, slope, rate], axis=-1), first, dts, room_rate)
    return np.where(np.arange(len(time_min))[:, None] >= first[None, :], curve, np.nan)


def room_input(log: TemperatureLog, ambient_C: FloatArray | None, method: str, preset: str) -> FloatArray | None:
    """The room's rate over each step of ``log`` from a room sensor, checked; None without one.

    Parameters
    ----------
    log : TemperatureLog
    ambient_C : ndarray, shape (N,) or None
        A room sensor's readings (°C) at the log's sample times; None without one.
    method : str
        The identification method.
    preset : str
        The tuning preset.

    Returns
    -------
    ndarray, shape (N,) or None
        The room's rate over each step (°C/min, :func:`room_rates`).

    Raises
    ------
    InputError
        A room sensor with the "lsq" method or a paper's preset, or with another number of readings
        than the log has samples.
    """
    if ambient_C is None:
        return None
    if method == "lsq" or preset != "data":
        msg = (
            "a room sensor (`ambient_C`) needs a UKF method with the data tuning: lsq and the papers' presets model a "
            "steady room"
        )
        raise InputError(msg)
    if len(ambient_C) != len(log.time_min):
        msg = f"the room sensor has {len(ambient_C)} readings for {len(log.time_min)} samples"
        raise InputError(msg)
    return room_rates(log.time_min, ambient_C)


def room_rates(time_min: FloatArray, room_C: FloatArray) -> FloatArray:
    """The room's rate (°C/min) over each step, from a room sensor; missing readings interpolated.

    The first step (Δt = 0) has rate 0. A room sensor with no valid reading
    gives rate 0 throughout (the room is taken as steady).

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        Sample times (min).
    room_C : ndarray, shape (N,)
        The room sensor's readings (°C, NaN: missing).

    Returns
    -------
    ndarray, shape (N,)
        The room's rate over the step to each sample (°C/min).
    """
    t = np.asarray(time_min, dtype=float)
    a = np.asarray(room_C, dtype=float)
    valid = np.isfinite(a)
    if not valid.any():
        return np.zeros(len(t))
    level = np.interp(t, t[valid], a[valid])
    dts = np.diff(t, prepend=t[0])
    answer: FloatArray = np.diff(level, prepend=level[0]) / np.where(dts > 0, dts, 1.0)
    return answer


@dataclass(frozen=True)
class FirstOrderCourse:
    """A first-order identification's course: the curve over the window and on, its variance,
    the parameters' history over the window and their final mean and covariance."""

    times: FloatArray
    mean_curve: FloatArray
    curve_var: FloatArray
    history: FloatArray
    history_sd: FloatArray
    final_mean: FloatArray
    final_cov: FloatArray
    window_fit: FloatArray
    idle: np.ndarray | None = None  # (S,) a filter's fading factor and adaptive law never acted
    idle_words: str = ""
    failed: tuple[tuple[int, str], ...] = ()  # sensors whose filter broke down, with the error's words


def _filter_each_sensor(
    tw: FloatArray,
    yw: FloatArray,
    config: FilterConfig,
    tuning: ThermalTuning,
    preset: str,
    room_rate: FloatArray | None,
) -> tuple[FilterRecord, FloatArray, FloatArray, tuple[tuple[int, str], ...]]:
    """:func:`filter_window` over every sensor at once; where one sensor's covariance breaks down
    the others go on without it (its readings left out, its breakdown returned with the error's
    words): one sensor's failure stopped a whole log's identification. A single sensor's failure,
    or one the error does not place, is raised (with the preset's hint for the papers' presets)."""
    values = yw.copy()
    failed: list[tuple[int, str]] = []
    while True:
        try:
            record, history, history_cov = filter_window(
                tw, values, config, tuning, None if room_rate is None else room_rate[: len(tw)]
            )
            return record, history, history_cov, tuple(failed)
        except CovarianceError as exc:
            where = exc.batch_index[0] if exc.batch_index else None
            if where is None or yw.shape[1] - len(failed) <= 1 or any(s == where for s, _ in failed):
                if preset == "data":
                    raise
                raise exc.hinted(PRESET_HINT.format(preset=preset)) from None
            failed.append((int(where), str(exc)))
            values[:, where] = np.nan


def least_squares_course(
    t: FloatArray, tw: FloatArray, yw: FloatArray, tuning: ThermalTuning, window_min: float, horizon_min: float | None
) -> FirstOrderCourse:
    fit = fit_rise(tw, yw, tuning.initial_mean)
    params, cov = fit.params, fit.cov
    times = np.concatenate([tw, _future_times(t, len(tw), window_min, horizon_min, params[:, 1])])
    mean_curve = rise_curve(times[:, None], params[:, 0], params[:, 1], params[:, 2])
    jac = _rise_jacobian(times[:, None], params)
    n, sensors = len(tw), yw.shape[1]
    return FirstOrderCourse(
        times=times,
        mean_curve=mean_curve,
        curve_var=np.einsum("nsi,sij,nsj->ns", jac, cov, jac),
        history=np.broadcast_to(params, (n, sensors, 3)).copy(),
        history_sd=np.broadcast_to(np.sqrt(np.diagonal(cov, axis1=-2, axis2=-1)), (n, sensors, 3)).copy(),
        final_mean=params,
        final_cov=cov,
        window_fit=mean_curve[:n],
    )


def filtered_course(
    t: FloatArray,
    tw: FloatArray,
    yw: FloatArray,
    method: str,
    preset: str,
    tuning: ThermalTuning,
    window_min: float,
    horizon_min: float | None,
    pseudo_measurement_seed: int | None,
    room_rate: FloatArray | None,
) -> FirstOrderCourse:
    n, sensors = len(tw), yw.shape[1]
    t_future = _future_times(t, n, window_min, horizon_min, tuning.initial_mean[:, 1])
    config = filter_config(method, tuning)
    record, history, history_cov, failed = _filter_each_sensor(tw, yw, config, tuning, preset, room_rate)
    for sensor, _ in failed:  # its filter broke down: no course and no estimate (said, with the error)
        history[:, sensor] = np.nan
        history_cov[:, sensor] = np.nan
    history_sd = np.sqrt(np.diagonal(history_cov, axis1=-2, axis2=-1))
    # A-posteriori variance factor: R came from a noise estimate (±20 % from ~30 samples); the
    # residual variance of the best first-order fit says how far off it was, and the covariance
    # is scaled by the ratio (as curve_fit does with absolute_sigma=False).
    variance_factor = np.ones(sensors)
    if preset == "data":
        for s in range(sensors):
            ok = np.isfinite(yw[:, s])
            fit_var = best_rss(tw[ok], yw[ok, s], with_drift=False) / max(int(ok.sum()) - 3, 1)
            variance_factor[s] = np.clip(fit_var / tuning.emission_cov[s, 0, 0], 0.25, 25.0)
    history_sd = history_sd * np.sqrt(variance_factor)[:, None]
    final_mean, final_cov = history[-1], history_cov[-1] * variance_factor[:, None, None]
    future_mean, future_var = _predict_after_window(
        record.final, final_mean, t_future, tw[-1], config, tuning, pseudo_measurement_seed
    )
    # the model curve through the final state, back over the window, for the residual test
    if room_rate is None:
        window_fit = rise_curve(tw[:, None] - tw[-1], final_mean[:, 0], final_mean[:, 1], final_mean[:, 2])
    else:
        window_fit = _curve_with_room(tw, yw, room_rate[:n], final_mean)
    return FirstOrderCourse(
        times=np.concatenate([tw, t_future]),
        mean_curve=np.concatenate([history[:, :, 0], future_mean]),
        curve_var=np.concatenate([history_sd[:, :, 0] ** 2, future_var * variance_factor]),
        history=history,
        history_sd=history_sd,
        final_mean=final_mean,
        final_cov=final_cov,
        window_fit=window_fit,
        failed=failed,
        idle=None if config.fading is None and config.adaptive_law is None else _idle(record),
        idle_words=" and ".join(
            words
            for words, used in (
                ("fading factor stayed 1", config.fading is not None),
                ("adaptive law changed nothing", config.adaptive_law is not None),
            )
            if used
        ),
    )


def _idle(record: FilterRecord) -> np.ndarray:
    """Per sensor, whether the fading factor stayed one and the adaptive law changed nothing at
    every step of the window: the filter's answer is then the normal UKF's."""
    idle: np.ndarray = np.all(record.fading == 1.0, axis=0) & ~np.any(record.adapted, axis=0)
    return idle


def _future_times(
    t: FloatArray, n_window: int, window_min: float, horizon_min: float | None, rate: FloatArray
) -> FloatArray:
    """Sample times after the window: the log's own, then uniform steps to the horizon."""
    logged = t[n_window:]
    step = float(np.median(np.diff(t))) if len(t) > 1 else 1.0
    if horizon_min is None:
        finite = rate[np.isfinite(rate) & (rate > 0)]
        reach = 4.0 / float(np.min(finite)) if finite.size else 0.0
        horizon_min = max(float(t[-1]), min(window_min + reach, 20 * max(float(t[-1]), window_min)))
    if horizon_min <= t[-1]:
        return logged[logged <= horizon_min + 1e-9]
    extra = np.arange(t[-1] + step, horizon_min + 0.5 * step, step)
    return np.concatenate([logged, extra])


def _rise_jacobian(time_min: FloatArray, params: FloatArray) -> FloatArray:
    """∂T(t)/∂[T₀, λ, T∞], shape (N, S, 3)."""
    T0, lam, Tinf = params[:, 0], params[:, 1], params[:, 2]
    decay = np.exp(-lam * time_min)
    return np.stack([decay, -(T0 - Tinf) * time_min * decay, 1.0 - decay], axis=-1)


def _predict_after_window(
    carry: FilterCarry,  # of the last window step
    physical_mean: FloatArray,
    t_future: FloatArray,
    t_last: float,
    config: FilterConfig,
    tuning: ThermalTuning,
    seed: int | None,
) -> tuple[FloatArray, FloatArray]:
    """Temperature mean and variance (F, S) after the window, with Q and R as adapted last.

    The mean is the model curve through the state at L; its variance comes from
    the UKF's time updates (Q included). The UT mean itself is not used: with
    the broad posterior of a short window its sigma points include negative
    decay rates, which pull the mean away from every plausible curve.
    """
    S = physical_mean.shape[0]
    if len(t_future) == 0:
        return np.empty((0, S)), np.empty((0, S))
    dts = np.diff(t_future, prepend=t_last)
    transition = _transition_with(dts, tuning.parametrisation)
    normal = replace(config, adaptive_law=None, square_root=False)
    if seed is None:
        mean = rise_curve((t_future - t_last)[:, None], physical_mean[:, 0], physical_mean[:, 1], physical_mean[:, 2])
        belief = GaussianState(carry.mean, carry.covariance())
        try:
            variance = forecast(belief, transition, carry.process_cov, len(dts), normal).cov[:, :, 0, 0]
        except CovarianceError:
            if S == 1:
                raise
            # one sensor's state past any forecast: each sensor's own, no number where it breaks down
            variance = np.full((len(dts), S), np.nan)
            for one in range(S):
                alone = GaussianState(belief.mean[one : one + 1], belief.cov[one : one + 1])
                try:
                    own = forecast(alone, transition, carry.process_cov[one : one + 1], len(dts), normal)
                except CovarianceError:
                    mean[:, one] = np.nan
                    continue
                variance[:, one] = own.cov[:, 0, 0, 0]
        return mean, variance
    # Xia et al. 2014 Eqs 21-22: sₖ = f(x̂ₖ₋₁) + q·randn, yₖ = h(sₖ) + r·randn, then a normal UKF update.
    rng = np.random.default_rng(seed)
    q_sd = np.sqrt(np.diagonal(carry.process_cov, axis1=-2, axis2=-1))
    r_sd = np.sqrt(carry.emission_cov[..., 0, 0])
    state = replace(carry, cov=carry.covariance(), chol=None)
    weights = normal.sigma_points.weights(3)
    means, variances = [], []
    for k in range(len(dts)):
        s = transition(state.mean, k) + q_sd * rng.standard_normal(state.mean.shape)
        pseudo = s[:, :1] + (r_sd * rng.standard_normal(r_sd.shape))[:, None]
        state, _ = filter_step(state, pseudo, transition_at(transition, k), observe_temperature, normal, weights)
        means.append(state.mean[:, 0])
        variances.append(state.covariance()[:, 0, 0])
    return np.array(means), np.array(variances)
