"""Identify every sensor of a log with the model-robust estimate: the default of ``identify``.

Each sensor's readings up to the identification time are fitted with sums of up to four
exponential modes (:mod:`mtident.thermal.robust`); the answer is the best-fitting model's course
and T∞, with the interval over every model the data cannot exclude. The predicted curve's band
is the envelope of the best model and the two models that set the interval's ends.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mtident._json import finite_or_none
from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.io.logs import TemperatureLog, as_temperature_log
from mtident.thermal.assumptions import describe_assumptions
from mtident.thermal.machine_model import combined_estimate, fit_readings, unmeasured_wander
from mtident.thermal.measured import measured_and_settled, rmse, window_samples
from mtident.thermal.modes import fitted_curve
from mtident.thermal.reference import MachineReference, reference_notes
from mtident.thermal.robust import estimate_sensor, with_fragility
from mtident.thermal.robust_types import Assumptions, RobustSettings, SensorEstimate

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["RobustIdentification", "identify_robust"]

REPORT_LEVEL = 0.95
# the prediction runs this many of the slowest mode's time constants past the window, at least
HORIZON_TIME_CONSTANTS = 4.0


@dataclass(frozen=True)
class RobustIdentification:
    """The model-robust identification of every sensor of a log (arrays with a sensor axis S).

    Attributes
    ----------
    sensors : tuple of str
    window_min : float
        Identification time actually used (the last reading at or before the asked one).
    n_window : int
        The number of readings in the window.
    time_min : ndarray, shape (N,)
        The log's times, then the prediction's beyond it.
    measured_C, curve_C, band_low_C, band_high_C : ndarray, shape (N, S)
        Readings (NaN past the log), the best model's course, and the 95 % band: the envelope
        of the best model and the models that set the ends of T∞'s interval.
    estimates : tuple of SensorEstimate
    assumptions : tuple of Assumptions
    rmse_C : ndarray, shape (S,)
        Xia et al. 2014 Eq. 33 of the best model over every measured reading.
    measured_final_C, measured_equilibrium_time_min : ndarray, shape (S,)
        From the log itself where it reached equilibrium, else NaN.
    notes : tuple of str
    method, preset : str
        Always "robust" and "data" (the names :class:`~mtident.thermal.identify.Identification` also has).
    measured_settled : ndarray of bool, shape (S,)
        Whether the log's last quarter moved less than ``SETTLED_MOVE_C``, with at most half that
        still to come at the pace of a mode as slow as the largest time constant allowed: where
        not, the measured values (the papers' 5 % rule) may be short of where the sensor settles.
    """

    sensors: tuple[str, ...]
    window_min: float
    n_window: int
    time_min: FloatArray
    measured_C: FloatArray
    curve_C: FloatArray
    band_low_C: FloatArray
    band_high_C: FloatArray
    estimates: tuple[SensorEstimate, ...]
    assumptions: tuple[Assumptions, ...]
    rmse_C: FloatArray
    measured_final_C: FloatArray
    measured_equilibrium_time_min: FloatArray
    notes: tuple[str, ...]
    method: str = "robust"
    preset: str = "data"
    measured_settled: np.ndarray | None = None

    @property
    def steady_state_C(self) -> FloatArray:
        """T∞ of each sensor's best-fitting model (NaN without a fit).

        Returns
        -------
        ndarray, shape (S,)
            T∞ (°C).
        """
        return np.array([e.steady_C for e in self.estimates])

    @property
    def equilibrium_time_min(self) -> FloatArray:
        """When each sensor's best model stays within 5 % of its total rise from T∞ (NaN without a fit).

        Returns
        -------
        ndarray, shape (S,)
            The time (min, from the log's start).
        """
        return np.array([np.nan if e.fit is None else e.fit.equilibrium_time_min for e in self.estimates])

    @property
    def model_ok(self) -> np.ndarray:
        """Whether each sensor's answer is trusted: a fit the data do not contradict, with T∞ determined.

        Returns
        -------
        ndarray of bool, shape (S,)
        """
        return np.array([e.model_ok for e in self.estimates])

    def steady_state_ci95(self) -> FloatArray:
        """(S, 2) 95 % interval of T∞ over every model the data cannot exclude.

        Returns
        -------
        ndarray, shape (S, 2)
            The low and high end of each sensor's interval (°C), infinite without a fit.
        """
        return np.array([e.interval_C.get(REPORT_LEVEL, (-np.inf, np.inf)) for e in self.estimates], dtype=float)

    def band_C(self) -> tuple[FloatArray, FloatArray]:
        """The curve's 95 % band, low and high, each (N, S).

        Returns
        -------
        low, high : ndarray, shape (N, S)
            The band's ends (°C).
        """
        return self.band_low_C, self.band_high_C

    def __repr__(self) -> str:
        lines = [f"RobustIdentification(L = {self.window_min:g} min, {len(self.sensors)} sensor(s))"]
        for e, (lo, hi) in zip(self.estimates, self.steady_state_ci95(), strict=True):
            verdict = "" if e.model_ok else ", not trusted:"
            lines.append(f"  {e.sensor}: T∞ {e.steady_C:.2f} °C, 95 % interval {lo:.2f} to {hi:.2f} °C{verdict}")
            # a notebook shows why, not only that
            lines += [f"    - {warning}" for warning in e.warnings] if not e.model_ok else []
        said = self.assumptions[0] if self.assumptions else None
        if said is not None:
            lines.append(
                f"  assumes: {said.model}, time constants up to {said.max_time_constant_min:g} min; room {said.room}"
            )
            lines += [
                f"  reference for {name}: {a.reference}"
                for name, a in zip(self.sensors, self.assumptions, strict=True)
                if a.reference is not None
            ]
        lines += [f"  note: {note}" for note in self.notes]
        return "\n".join(lines)

    def curve_frame(self) -> pd.DataFrame:
        """The measured and modelled curve of every sensor with its 95 % band, a row per time.

        Returns
        -------
        pandas.DataFrame
            Columns ``time_min``, ``part`` ("window" or "prediction") and per sensor ``NAME_measured_C``,
            ``NAME_model_C``, ``NAME_low95_C`` and ``NAME_high95_C`` (°C).
        """
        import pandas as pd

        columns: dict[str, object] = {
            "time_min": self.time_min,
            "part": np.where(self.time_min <= self.window_min + 1e-9, "window", "prediction"),
        }
        for s, name in enumerate(self.sensors):
            columns[f"{name}_measured_C"] = self.measured_C[:, s]
            columns[f"{name}_model_C"] = self.curve_C[:, s]
            columns[f"{name}_low95_C"] = self.band_low_C[:, s]
            columns[f"{name}_high95_C"] = self.band_high_C[:, s]
        return pd.DataFrame(columns)

    def summary(self, index: int) -> dict[str, object]:
        """The JSON object for one sensor, with its verdict and assumptions.

        Parameters
        ----------
        index : int
            The sensor's position in ``sensors``.

        Returns
        -------
        dict
            JSON types: T∞ with its 95 % interval and its interval at the highest level computed, the
            slowest time constant, the equilibrium time, the RMSE, ``model_ok``, the warnings, the
            assumptions and the best model's modes; None where a value is not finite.
        """
        e = self.estimates[index]
        fit = e.fit
        lo, hi = self.steady_state_ci95()[index]
        slowest = np.nan if fit is None else fit.slowest_time_constant_min()
        lo99, hi99 = e.interval_C.get(max(e.interval_C), (-np.inf, np.inf))
        return {
            "sensor": e.sensor,
            "method": self.method,
            "preset": self.preset,
            "window_min": float(self.window_min),
            "steady_state_C": finite_or_none(e.steady_C),
            "steady_state_ci95_C": [finite_or_none(lo), finite_or_none(hi)],
            f"steady_state_ci{round(100 * max(e.interval_C))}_C": [finite_or_none(lo99), finite_or_none(hi99)],
            "lambda_per_min": finite_or_none(1.0 / slowest) if np.isfinite(slowest) else None,
            "time_constant_min": finite_or_none(slowest),
            "start_C": None if fit is None else finite_or_none(fit.start_C),
            "total_rise_C": None if fit is None else finite_or_none(e.steady_C - fit.start_C),
            "equilibrium_time_min": finite_or_none(self.equilibrium_time_min[index]),
            "rmse_C": finite_or_none(self.rmse_C[index]),
            "model_ok": bool(e.model_ok),
            "model_fits": bool(e.model_ok),
            "warnings": list(e.warnings),
            "assumptions": self.assumptions[index].to_dict(),
            "model": _model_dict(e),
            "measured_final_C": finite_or_none(self.measured_final_C[index]),
            "measured_equilibrium_time_min": finite_or_none(self.measured_equilibrium_time_min[index]),
            "measured_settled": None
            if self.measured_settled is None or not np.isfinite(self.measured_final_C[index])
            else bool(self.measured_settled[index]),
        }


def _model_dict(e: SensorEstimate) -> dict[str, object]:
    fit = e.fit
    return {
        "status": e.status,
        "modes": []
        if fit is None
        else [{"time_constant_min": m.time_constant_min, "amplitude_C": m.amplitude_C} for m in fit.modes],
        "onset_min": finite_or_none(e.onset_min),
        "rise_C": finite_or_none(e.rise_C),
        "noise_C": finite_or_none(e.noise_C),
        "interval_ends": e.what_sets_the_ends(REPORT_LEVEL),
        "reference_used": e.reference_used,
        "machine_model_used": e.machine_used,
        "spikes_left_out": e.spikes,
    }


def identify_robust(
    log: TemperatureLog,
    window_min: float,
    room_C: FloatArray | None = None,
    settings: RobustSettings | None = None,
    reference: MachineReference | None = None,
    horizon_min: float | None = None,
    room_sensor: str | None = None,
) -> RobustIdentification:
    """Identify every sensor of ``log`` from its first ``window_min`` minutes with the
    model-robust estimate, and predict its course.

    Parameters
    ----------
    log : TemperatureLog
    window_min : float
        Identification time (minutes from the first reading).
    room_C : ndarray, shape (N,), optional
        A room sensor at the log's times: an input of every mode's heat balance.
    settings : RobustSettings, optional
        The largest time constant and the room's wander (default: 300 min, 0.05 °C in an hour).
    reference : MachineReference, optional
        A reference run of the same machine.
    horizon_min : float, optional
        Predict to this time (default: the log's end, or further to show the approach).
    room_sensor : str, optional
        The room sensor's name, for the assumptions.

    Returns
    -------
    RobustIdentification

    Raises
    ------
    InputError
        A window with too few readings, or a reference that knows none of the log's sensors.
    """
    log = as_temperature_log(log, "identify")
    settings = settings or RobustSettings()
    if not (np.isfinite(window_min) and window_min > 0):
        msg = f"window_min must be a positive number of minutes, not {window_min!r}"
        raise InputError(msg)
    n = window_samples(log, window_min)
    t, y = log.time_min, log.temperature_C
    if room_C is not None and len(room_C) != len(t):
        msg = f"the room sensor has {len(room_C)} readings for {len(t)} samples"
        raise InputError(msg)
    room_window = None if room_C is None else room_C[:n]
    unfit = [] if reference is None else reference_notes(reference, log.sensors, room_C is not None, room_sensor)
    model = None if reference is None else reference.machine_model
    machine = fit_readings(model, log.sensors, t[:n], y[:n], room_window, settings.levels)
    estimates = tuple(
        combined_estimate(
            with_fragility(
                estimate_sensor(
                    name, t[:n], y[:n, s], room_window, settings, None if reference is None else reference.modes(name)
                )
            ),
            machine,
            s,
            unmeasured_wander(model, room_C is not None, settings),
        )
        for s, name in enumerate(log.sensors)
    )
    times = _prediction_times(t, n, estimates, horizon_min)
    room_all = None if room_C is None else np.concatenate([room_C, np.full(len(times) - len(t), np.nan)])[: len(times)]
    curve, low, high = (np.full((len(times), len(estimates)), np.nan) for _ in range(3))
    for s, e in enumerate(estimates):
        if e.fit is not None:
            curve[:, s], low[:, s], high[:, s] = _course(e, times, room_all)
    measured = np.full((len(times), len(log.sensors)), np.nan)
    measured[: min(len(t), len(times))] = y[: len(times)]
    in_log = times <= t[-1] + 1e-9
    # the window's fit may not know the log's slowest mode: the largest allowed sets the pace
    final, equilibrium, settled = measured_and_settled(t, y, settings.max_time_constant_min)
    return RobustIdentification(
        sensors=log.sensors,
        window_min=float(t[n - 1]),
        n_window=n,
        time_min=times,
        measured_C=measured,
        curve_C=curve,
        band_low_C=low,
        band_high_C=high,
        estimates=estimates,
        assumptions=tuple(
            describe_assumptions(settings, room_sensor, reference, name, room_C is not None) for name in log.sensors
        ),
        rmse_C=rmse(curve[in_log], y[: int(in_log.sum())]),
        measured_final_C=final,
        measured_equilibrium_time_min=equilibrium,
        measured_settled=settled,
        notes=(*log.notes, *unfit, *(w for e in estimates for w in e.warnings)),
    )


def _prediction_times(
    t: FloatArray, n: int, estimates: tuple[SensorEstimate, ...], horizon_min: float | None
) -> FloatArray:
    """The log's times, then steps of its sampling interval to the horizon."""
    slowest = [e.fit.slowest_time_constant_min() for e in estimates if e.fit is not None and e.fit.modes]
    default = t[n - 1] + HORIZON_TIME_CONSTANTS * max(slowest, default=0.0)
    horizon = max(t[-1], default) if horizon_min is None else horizon_min
    if horizon <= t[-1]:
        return t[t <= horizon + 1e-9] if horizon_min is not None else t
    step = max(float(np.median(np.diff(t))) if len(t) > 1 else 1.0, (horizon - t[-1]) / 2000.0)
    return np.concatenate([t, np.arange(t[-1] + step, horizon + step / 2, step)])


def _course(
    e: SensorEstimate, times: FloatArray, room_C: FloatArray | None
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The best model's course and the band of the models at the 95 % interval's ends."""
    fit = e.fit
    assert fit is not None
    curve = fitted_curve(fit, times, room_C)
    if REPORT_LEVEL not in fit.ends:
        return curve, np.full(times.shape, -np.inf), np.full(times.shape, np.inf)
    best_modal = fitted_curve(fit, times)
    ends = [
        curve + fitted_curve(fit, times, modes=end.modes, steady_C=end.steady_C) - best_modal
        for end in fit.ends[REPORT_LEVEL]
    ]
    # the room's unmeasured wander widens T∞'s interval beyond the ends' models: the band reaches it
    lo, hi = e.interval_C[REPORT_LEVEL]
    grow = np.clip((times - fit.origin_min) / max(times[-1] - fit.origin_min, 1e-9), 0.0, 1.0)
    low = np.minimum.reduce([curve, *ends]) + grow * min(lo - fit.ends[REPORT_LEVEL][0].steady_C, 0.0)
    high = np.maximum.reduce([curve, *ends]) + grow * max(hi - fit.ends[REPORT_LEVEL][1].steady_C, 0.0)
    return curve, low, high
