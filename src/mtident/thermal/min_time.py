"""Minimal identification time (Xia et al. 2014 §2.4 and Fig. 2; Yu et al. 2019 §1.5 steps 1-5).

For every candidate identification time L and every sampling period M, identify
with the data up to L, predict to M, and take the RMSE (Eq. 33) against the
measurements up to M. The minimal identification time is the L at which the RMSE
is smallest for all sampling periods. Choosing it needs the measurements up to
the longest sampling period, so that is the measuring time the test really took:
both are reported.

One filter run per sensor serves every L (the state at L is the filtered state
after L's last sample), and the predictions from all L of all sensors advance
as one batch.

A warm-up that began after the log (flat at its first level for 10 min or
more, :func:`~mtident.thermal.lsq.flat_lead`; data tuning only) is identified
from its last flat sample, as ``identify`` does: its curve is held at the first
level before that, L still counts from the log's start, and an L that has fewer
than ``MIN_WINDOW_SAMPLES`` samples of the rise is no candidate for that sensor.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from mtident._json import SensorAnswers, json_optional
from mtident._typing import FloatArray, IntArray
from mtident.exceptions import InputError
from mtident.io.logs import TemperatureLog, as_temperature_log
from mtident.thermal.first_order import FIRST_ORDER_ASSUMPTIONS
from mtident.thermal.first_order_filter import filter_window, room_input
from mtident.thermal.lsq import first_level, fit_rise, late_onset, rise_threshold
from mtident.thermal.measured import MIN_WINDOW_SAMPLES, rmse
from mtident.thermal.model import heat_balance_path, rise_curve
from mtident.thermal.readings import noise_sigma, reading_range
from mtident.thermal.robust_types import Assumptions
from mtident.thermal.settings import METHODS, ThermalTuning, filter_config, preset_tuning, tuning_from_data

__all__ = ["MinTimeAnswer", "MinTimeResult", "minimal_identification_time"]

# an RMSE beyond this (°C) is a filter that left the data, not a prediction error
_EXPLODED_C = 100.0


@dataclass(frozen=True, slots=True)
class MinTimeAnswer:
    """One sensor's minimal identification time: its fields are the sensor's JSON object.

    Attributes
    ----------
    sensor, method : str
    min_identification_time_min : float
        The minimal L (NaN where none).
    sampling_periods_min : tuple of float
        The sampling periods M.
    rmse_C : dict of str to tuple of (float, float)
        Per period (its minutes as ``f"{M:g}"``), the RMSE curve as (L, RMSE) pairs.
    best_per_period_min : dict of str to float
        Per period, its own best L.
    periods_agree : bool
        Every period picks the same L.
    measuring_time_needed_min : float
        The longest sampling period.
    model_ok : bool
        False where the RMSE falls to the end of every period (the criterion says nothing).
    warnings : tuple of str
    assumptions : Assumptions
    rise_begins_min : float or None
        Where a warm-up that began after the log rises; left out of the JSON where it rose from the start.
    """

    sensor: str
    method: str
    min_identification_time_min: float
    sampling_periods_min: tuple[float, ...]
    rmse_C: dict[str, tuple[tuple[float, float], ...]]
    best_per_period_min: dict[str, float]
    periods_agree: bool
    measuring_time_needed_min: float
    model_ok: bool
    warnings: tuple[str, ...]
    assumptions: Assumptions
    rise_begins_min: float | None = json_optional()


@dataclass(frozen=True)
class MinTimeResult(SensorAnswers):
    """RMSE against identification time for several sampling periods, per sensor.

    A method's ``index`` is the sensor's position in ``sensors``.

    Attributes
    ----------
    sensors : tuple of str
    method : str
        The filter or "lsq".
    windows_min : ndarray, shape (W,)
        Candidate identification times L.
    periods_min : ndarray, shape (P,)
        Sampling periods M.
    rmse_C : ndarray, shape (P, W, S)
        NaN where L ≥ M.
    best_per_period_min : ndarray, shape (P, S)
        argmin over L for each period.
    min_identification_time_min : ndarray, shape (S,)
    agreement : ndarray of bool, shape (S,)
        All periods pick the same L (the paper's criterion); where they do not,
        the L with the smallest summed relative RMSE is reported.
    measuring_time_min : float
        The longest sampling period: the test had to run this long to choose.
    rise_begins_min : ndarray, shape (S,), optional
        Where a warm-up that began after the log starts its rise (min), NaN for one that rose
        from the log's start (data tuning only).
    no_rise : ndarray of bool, shape (S,), optional
        Sensors whose readings over the longest period do not rise above their noise: no warm-up,
        so no identification time to choose (default: none).
    """

    sensors: tuple[str, ...]
    method: str
    windows_min: FloatArray
    periods_min: FloatArray
    rmse_C: FloatArray
    best_per_period_min: FloatArray
    min_identification_time_min: FloatArray
    agreement: FloatArray
    measuring_time_min: float
    rise_begins_min: FloatArray | None = None
    no_rise: np.ndarray | None = None

    def __repr__(self) -> str:
        chosen = ", ".join(
            f"{name} {value:g}" for name, value in zip(self.sensors, self.min_identification_time_min, strict=True)
        )
        periods = "/".join(f"{p:g}" for p in self.periods_min)
        return (
            f"MinTimeResult({self.method}: minimal L (min) {chosen}; sampling periods {periods} min, measured for "
            f"{self.measuring_time_min:g} min)"
        )

    def warnings(self, index: int) -> list[str]:
        """What the criterion's answer for one sensor does not say: a best L at the end of every
        sampling period (more data simply fit better), RMSEs that explode, periods that disagree.

        Returns
        -------
        list of str
            Empty where there is nothing to say.
        """
        name = self.sensors[index]
        if self.no_rise is not None and self.no_rise[index]:
            # a flat column's L was chosen from noise, and trusted
            return [f"{name}: no rise above its noise within the longest sampling period: no warm-up to time"]
        said = []
        step = float(np.median(np.diff(self.windows_min))) if len(self.windows_min) > 1 else 1.0
        last = [float(self.windows_min[self.windows_min < p].max(initial=-np.inf)) for p in self.periods_min]
        at_end = [
            np.isfinite(b) and b >= end - 1.5 * step
            for b, end in zip(self.best_per_period_min[:, index], last, strict=True)
        ]
        if all(at_end):
            said.append(
                f"{name}: the RMSE falls to the end of every sampling period (best L = the longest window each "
                "allows): "
                "the criterion only says that more data fit better, not that a shorter test suffices"
            )
        curves = self.rmse_C[:, :, index]
        rise = max(float(np.nanmax(curves, initial=0.0)), 0.0)
        exploded = np.isfinite(curves) & (curves > _EXPLODED_C)
        if exploded.any() or not np.isfinite(rise):
            windows = self.windows_min[np.any(exploded, axis=0)]
            said.append(
                f"{name}: the RMSE explodes (largest {np.nanmax(curves[exploded]):.3g} °C) from L = {windows.min():g} "
                f"to {windows.max():g} min: "
                f"the {self.method} filter left the data's course from those windows; they are no candidates"
            )
        if not self.agreement[index]:
            said.append(
                f"{name}: the sampling periods pick different L; the one with the smallest summed relative RMSE is "
                "given"
            )
        return said

    def answer(self, index: int) -> MinTimeAnswer:
        """One sensor's answer, with its verdict and what it assumes.

        Returns
        -------
        MinTimeAnswer
        """
        curves = {
            f"{period:g}": tuple(
                (float(w), float(self.rmse_C[p, i, index]))
                for i, w in enumerate(self.windows_min)
                if np.isfinite(self.rmse_C[p, i, index])
            )
            for p, period in enumerate(self.periods_min)
        }
        warnings = tuple(self.warnings(index))
        begins = np.nan if self.rise_begins_min is None else float(self.rise_begins_min[index])
        return MinTimeAnswer(
            sensor=self.sensors[index],
            method=self.method,
            min_identification_time_min=float(self.min_identification_time_min[index]),
            sampling_periods_min=tuple(float(p) for p in self.periods_min),
            rmse_C=curves,
            best_per_period_min={
                f"{p:g}": float(b) for p, b in zip(self.periods_min, self.best_per_period_min[:, index], strict=True)
            },
            periods_agree=bool(self.agreement[index]),
            measuring_time_needed_min=float(self.measuring_time_min),
            model_ok=not any(": the RMSE falls to the end" in w for w in warnings)
            and not (self.no_rise is not None and bool(self.no_rise[index])),
            warnings=warnings,
            assumptions=FIRST_ORDER_ASSUMPTIONS,
            rise_begins_min=begins if np.isfinite(begins) else None,
        )


def minimal_identification_time(
    log: TemperatureLog,
    method: str = "aukf",
    preset: str = "data",
    periods_min: list[float] | None = None,
    windows_min: list[float] | None = None,
    ambient_C: FloatArray | None = None,
) -> MinTimeResult:
    """RMSE-versus-identification-time curves and the minimal identification time.

    Parameters
    ----------
    log : TemperatureLog
    method : str
        One of ``METHODS``.
    preset : {"data", "xia2014", "yu2019"}
        For "data", each filter is initialised from the first samples of the
        shortest window, so every L starts from the same prior.
    periods_min : list of float
        Sampling periods M (default 35, 40, 45, 50 as Xia et al. 2014).
    windows_min : list of float
        Candidate L (default every sample time from 5 min to the longest period).
    ambient_C : ndarray, shape (N,), optional
        A room sensor: the room is the input of the heat balance, in the filter
        up to L and in the prediction after it (the measured room is a known
        input, so the RMSE judges the model, not the room). UKF methods with the
        data tuning only.

    Returns
    -------
    MinTimeResult

    Raises
    ------
    InputError
        The log is shorter than the longest sampling period, or no candidate L fits.
    """
    if method not in METHODS:
        msg = f"method {method!r} is not one of: {', '.join(METHODS)}"
        raise InputError(msg)
    log = as_temperature_log(log, "minimal_identification_time")
    periods = _minutes("periods_min", periods_min)
    windows = _minutes("windows_min", windows_min)
    longest = max(periods) if periods else 50.0
    if windows is not None and max(windows) >= longest:
        beyond = [w for w in windows if w >= longest]
        said = f"{beyond[0]:g} min" if len(beyond) == 1 else f"{len(beyond)} ({min(beyond):g}-{max(beyond):g} min)"
        msg = (
            f"identification times (--windows, `windows_min`) must be shorter than the longest sampling period "
            f"({longest:g} min), whose RMSE judges each: {said} are not"
        )
        raise InputError(msg)
    room_rate = room_input(log, ambient_C, method, preset)
    # A diverging filter (the papers' presets can) shows as an infinite RMSE, not as numpy warnings.
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return _search(log, method, preset, periods, windows, room_rate)


def _minutes(name: str, values: object) -> list[float] | None:
    """``values`` (one number or several) as a list of minutes; InputError naming ``name`` where
    they are not all positive finite numbers."""
    if values is None:
        return None
    try:
        minutes = [float(v) for v in np.atleast_1d(np.asarray(values, dtype=float))]
    except (TypeError, ValueError):
        minutes = []
    if not minutes or not all(math.isfinite(v) and v > 0 for v in minutes):
        msg = f"{name} must be positive numbers of minutes, not {values!r}"
        raise InputError(msg)
    return minutes


def _search(
    log: TemperatureLog,
    method: str,
    preset: str,
    periods_min: list[float] | None,
    windows_min: list[float] | None,
    room_rate: FloatArray | None = None,
) -> MinTimeResult:
    periods = np.array(sorted(periods_min or [35.0, 40.0, 45.0, 50.0]), dtype=float)
    t, y = log.time_min, log.temperature_C
    if t[-1] + 1e-9 < periods[-1]:
        msg = f"{log.source}: the log covers {t[-1]:g} min; the longest sampling period is {periods[-1]:g} min"
        raise InputError(msg)
    if windows_min is None:
        candidates = t[(t >= 5.0 - 1e-9) & (t < periods[-1])]
    else:
        candidates = np.array(sorted(windows_min), dtype=float)
    counts = np.array([log.window(w) for w in candidates])
    keep = counts >= MIN_WINDOW_SAMPLES
    candidates, counts = candidates[keep], counts[keep]
    if candidates.size == 0:
        msg = f"{log.source}: no identification time has the {MIN_WINDOW_SAMPLES} samples it needs"
        raise InputError(msg)
    n_total = log.window(periods[-1])
    n_max = int(counts.max())
    S = y.shape[1]
    W = len(candidates)
    onsets = np.zeros(S, dtype=int)
    if preset == "data":
        onsets = late_onset(t[:n_total], y[:n_total], noise_sigma(y[:n_total], t[:n_total]))
    fitted = y.copy()
    for s in np.flatnonzero(onsets):
        fitted[: onsets[s], s] = np.nan
    # (W, S): an L with too few samples of a late sensor's rise is no candidate for it
    usable = counts[:, None] - onsets[None, :] >= MIN_WINDOW_SAMPLES

    # Estimated curves (W, n_total, S): filtered up to L, predicted after.
    curves = np.full((W, n_total, S), np.nan)
    if method == "lsq":
        guess = _prior(t, y, fitted, int(counts[0]), onsets).initial_mean
        for i, n in enumerate(counts):
            if not usable[i].any():
                continue
            params = fit_rise(t[:n], fitted[:n][:, usable[i]], guess[usable[i]]).params
            curves[i][:, usable[i]] = rise_curve(t[:n_total, None], params[:, 0], params[:, 1], params[:, 2])
    else:
        tuning = _prior(t, y, fitted, int(counts[0]), onsets) if preset == "data" else preset_tuning(preset, S)
        _, physical, _ = filter_window(
            t[:n_max],
            fitted[:n_max],
            filter_config(method, tuning),
            tuning,
            None if room_rate is None else room_rate[:n_max],
        )
        last = counts - 1
        at_window = physical[last]  # (W, S, 3): [T, λ, T∞] after each L's last sample
        if room_rate is None:
            # The prediction from L is the model curve through the state at L, for all L at once.
            elapsed = t[None, :n_total, None] - t[last][:, None, None]  # (W, n_total, 1)
            predicted = rise_curve(
                elapsed, at_window[:, None, :, 0], at_window[:, None, :, 1], at_window[:, None, :, 2]
            )
        else:
            predicted = _predict_with_room(t[:n_total], room_rate[:n_total], at_window, last)
        filtered = physical[:, :, 0]  # (n_max, S)
        for i, n in enumerate(counts):
            curves[i, :n] = filtered[:n]
            curves[i, n:] = predicted[i, n:]
        curves = np.where(np.isfinite(curves), curves, np.inf)  # a diverged filter has no minimum there
    level = first_level(y)
    for s in np.flatnonzero(onsets):
        curves[:, : onsets[s], s] = level[s]

    table = np.full((len(periods), W, S), np.nan)
    for p, period in enumerate(periods):
        n_period = log.window(period)
        for i, window in enumerate(candidates):
            if window < period:
                # an unusable L has no curve for that sensor: NaN, not rmse's 0 over no samples
                table[p, i] = np.where(usable[i], rmse(curves[i, :n_period], y[:n_period]), np.nan)
    safe = np.where(np.isfinite(table), table, np.inf)
    best_index = np.argmin(safe, axis=1)  # (P, S)
    best = candidates[best_index]
    agreement = np.all(best_index == best_index[:1], axis=0)
    relative = safe / np.min(safe, axis=1, keepdims=True)
    overall = candidates[np.argmin(np.sum(np.where(np.isfinite(relative), relative, 1e9), axis=0), axis=0)]
    chosen = np.where(agreement, best[0], overall)
    begins = np.where(onsets > 0, t[onsets], np.nan)
    return MinTimeResult(
        log.sensors,
        method,
        candidates,
        periods,
        table,
        best,
        chosen,
        agreement,
        float(periods[-1]),
        begins,
        _no_rise(t[:n_total], y[:n_total]),
    )


def _no_rise(time_min: FloatArray, values: FloatArray) -> np.ndarray:
    """Per sensor, whether its readings do not rise: identify's first-order rule (their range
    below :func:`~mtident.thermal.lsq.rise_threshold` of their noise)."""
    no_rise: np.ndarray = reading_range(values) < rise_threshold(noise_sigma(values, time_min))
    return no_rise


def _prior(
    time_min: FloatArray, values: FloatArray, fitted: FloatArray, n_first: int, onsets: IntArray
) -> ThermalTuning:
    """The data tuning from each sensor's first ``n_first`` samples of its rise (``fitted``: NaN before its onset)."""
    tuning = tuning_from_data(time_min[:n_first], values[:n_first])
    for s in np.flatnonzero(onsets):
        onset = int(onsets[s])
        # the late sensor's own window from its onset, carried back to the log's start
        own = tuning_from_data(
            time_min[onset : onset + n_first], fitted[onset : onset + n_first, [s]], start_min=float(time_min[0])
        )
        fields = {
            name: getattr(tuning, name).copy()
            for name in ("initial_mean", "initial_cov", "process_cov", "emission_cov", "threshold_C")
        }
        for name, array in fields.items():
            array[s] = getattr(own, name)[0]
        tuning = replace(tuning, **fields)
    return tuning


def _predict_with_room(
    time_min: FloatArray, room_rate: FloatArray, at_window: FloatArray, last: IntArray
) -> FloatArray:
    """(W, N, S): the heat balance run on from each L's state with the measured room as input."""
    T, rate, steady = at_window[..., 0], at_window[..., 1], at_window[..., 2]
    state = np.stack([T, rate * (steady - T), rate], axis=-1)  # [T, s, λ] at each L
    path = heat_balance_path(state, last[:, None], np.diff(time_min, prepend=time_min[0]), room_rate)
    return np.moveaxis(path, 0, 1)
