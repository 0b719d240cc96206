"""The papers' first-order identification (Xia et al. 2014 §2.1 end and §2.4; Yu et al. 2019
§1.5): filter the measurements up to the identification time L with a UKF (or fit them by least
squares), then predict to the end of the record (or a horizon). All sensors of a log are filtered
as one batch. Its answer is an :class:`~mtident.thermal.identification.Identification` whose
``details`` are :class:`FirstOrderDetails`; the filters themselves, and their prediction after the
window, are in :mod:`mtident.thermal.first_order_filter`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.special import fdtri, stdtrit

from mtident._typing import BoolArray, FloatArray
from mtident.io.logs import OPEN_CIRCUIT_HIGH_C, OPEN_CIRCUIT_LOW_C, TemperatureLog
from mtident.thermal.first_order_filter import (
    PRESET_HINT,
    FirstOrderCourse,
    best_rss,
    filtered_course,
    least_squares_course,
    room_input,
)
from mtident.thermal.identification import Identification, sensor_notes
from mtident.thermal.lsq import first_level, first_order_onset, late_onset, rise_threshold
from mtident.thermal.measured import measured_and_settled, minutes_given, rmse, warm_up_floor_C, window_samples
from mtident.thermal.modal_types import DEFAULT_MAX_TIME_CONSTANT_MIN
from mtident.thermal.model import equilibrium_time
from mtident.thermal.readings import display_resolution, noise_sigma, reading_range, sampling_interval_min
from mtident.thermal.robust_types import Assumptions
from mtident.thermal.settings import preset_tuning, tuning_from_data

__all__ = [
    "FIRST_ORDER_ASSUMPTIONS",
    "FirstOrderAnswer",
    "FirstOrderDetails",
    "Z95",
    "first_order_suffices",
    "identify_first_order",
    "model_check",
]

Z95 = 1.959963984540054

# no largest time constant: the one mode's is fitted, unbounded (infinite, written as null)
FIRST_ORDER_ASSUMPTIONS = Assumptions(
    max_time_constant_min=math.inf,
    room="the room at its level in the window (or the room sensor's course, where given)",
    reference=None,
    model="first order (one exponential, the papers' model): the interval assumes a first-order machine; "
    "a slower mode not yet seen moves T∞ beyond it; of a warm-up that does not overshoot: a rising sensor's T∞ "
    "not below its latest readings, less four times their noise and any fall of a logged room",
)

# A first-order fit to fewer minutes of rise than this is not trusted: a thermal time constant is
# tens of minutes, and a few minutes of its rise are nearly straight (:func:`_untrusted`).
MIN_RISE_SEEN_MIN = 5.0


# A T∞ interval wider than this many times the rise seen so far, plus the margin (°C), states
# nothing physics allows of a machine part's warm-up (:func:`_untrusted`).
MAX_HALF_PER_RISE, MAX_HALF_MARGIN_C = 5.0, 5.0


@dataclass(frozen=True, slots=True)
class FirstOrderAnswer:
    """The first-order filters' part of one sensor's answer (its keys in the sensor's JSON object).

    Attributes
    ----------
    lambda_per_min, lambda_sd_per_min : float
        λ and its standard deviation.
    time_constant_min : float or None
        1/λ, None where λ is not positive.
    model_fits : bool
        The residual test passed.
    assumptions : Assumptions
        :data:`FIRST_ORDER_ASSUMPTIONS`.
    residual_chi2 : float
        The residual test's statistic.
    """

    lambda_per_min: float
    lambda_sd_per_min: float
    time_constant_min: float | None
    model_fits: bool
    assumptions: Assumptions
    residual_chi2: float


@dataclass(frozen=True)
class FirstOrderDetails:
    """What the papers' first-order filters (or least squares) add to an
    :class:`~mtident.thermal.identification.Identification`, arrays with a sensor axis S.

    Attributes
    ----------
    curve_sd_C : ndarray, shape (N, S)
        The curve's standard deviation (filtered up to L, predicted after).
    steady_state_sd_C, rate_per_min, rate_sd_per_min : ndarray, shape (S,)
        T∞'s standard deviation, and λ with its own.
    fit_chi2, fit_autocorr : ndarray, shape (S,)
        Residual test of the first-order model inside the window.
    fits : ndarray of bool, shape (S,)
        The residual test passed; where it failed the interval was widened.
    history : ndarray, shape (L, S, 3)
        Filtered state at each sample up to L (convergence plots).
    history_sd : ndarray, shape (L, S, 3)
    quantile : float
        Multiplier of the standard deviations for the 95 % intervals: Student's t
        with N − 3 degrees of freedom, because the noise level is estimated
        from the same N samples.
    untrusted : ndarray of bool, shape (S,)
        An answer no physics allows, or fitted to a few minutes of rise (said in the notes):
        ``model_ok`` is then false.
    """

    curve_sd_C: FloatArray
    steady_state_sd_C: FloatArray
    rate_per_min: FloatArray
    rate_sd_per_min: FloatArray
    fit_chi2: FloatArray
    fit_autocorr: FloatArray
    fits: BoolArray
    history: FloatArray
    history_sd: FloatArray
    quantile: float
    untrusted: BoolArray

    def answer(self, index: int) -> FirstOrderAnswer:
        """λ with its standard deviation, the time constant, the residual test and what the answer assumes
        (:meth:`~mtident.thermal.identification.MethodDetails.answer`)."""
        rate = float(self.rate_per_min[index])
        return FirstOrderAnswer(
            lambda_per_min=rate,
            lambda_sd_per_min=float(self.rate_sd_per_min[index]),
            time_constant_min=1.0 / rate if rate > 0 else None,
            model_fits=bool(self.fits[index]),
            assumptions=FIRST_ORDER_ASSUMPTIONS,
            residual_chi2=float(self.fit_chi2[index]),
        )

    def describe(self) -> list[str]:
        """The first-order assumption, in a line.

        Returns
        -------
        list of str
        """
        return ["  assumes: first order (one exponential): a slower mode not yet seen moves T∞ beyond the interval"]

    def follows_room(self, index: int) -> bool:
        """False: the first-order prediction holds the room at its level at L
        (:meth:`~mtident.thermal.identification.MethodDetails.follows_room`)."""
        return False


def first_order_suffices(time_min: FloatArray, values: FloatArray, level: float = 0.999) -> bool:
    """Nested F-test: does a + b·e^(−λt) + c·t fit no better than a + b·e^(−λt)?

    False when the ramp term is significant at ``level`` — the signature of a
    slow mode (or drift) that a first-order model would average away. Needs no
    noise level.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        Sample times (min).
    values : ndarray, shape (N,)
        One sensor's readings (°C), all finite.
    level : float, optional
        The test's confidence level.

    Returns
    -------
    bool
        True where the ramp term is not significant at ``level``.
    """
    rss_null = best_rss(time_min, values, with_drift=False)
    rss_alt = best_rss(time_min, values, with_drift=True)
    floor = len(values) * (1e-4) ** 2  # residuals of a noise-free curve are rounding error
    f_stat = (rss_null - rss_alt) / max(rss_alt, floor) * (len(values) - 4)
    return bool(
        f_stat < fdtri(1, len(values) - 4, level)
    )  # the F(1, N − 4) quantile; scipy.stats costs 0.5 s to import


RUNAWAY_CHI2 = 1000.0
"""A residual χ²/dof beyond this is no misfit of the model but a filter whose final estimate does
not describe the readings it was given (a paper's preset on another log: χ²/dof 1e82 with the
residuals' lag-1 autocorrelation 0.03; a fading filter chasing the noise of 30 readings: 1,765)."""


def model_check(
    time_min: FloatArray, values: FloatArray, residuals: FloatArray, sigma: FloatArray
) -> tuple[FloatArray, FloatArray, BoolArray]:
    """Residual tests of the first-order model inside the window.

    1. A nested-model F-test: does a + b·e^(−λt) + c·t fit significantly better
       than a + b·e^(−λt)? A fast-plus-slow warm-up, whose slow part looks like a
       ramp in a short window, does (F above the 99.9 % point). The test needs no
       noise level.
    2. A gross misfit: χ²/dof of the filter's residuals against the noise level
       (at least 0.1 mK, below which residuals are rounding error) above
       4 + 4·sqrt(2/dof) together with a lag-1 autocorrelation above 3/sqrt(N).

    Parameters
    ----------
    time_min : ndarray, shape (N,)
    values : ndarray, shape (N, S)
        The window's measurements (NaN allowed).
    residuals : ndarray, shape (N, S)
        Data minus the identified curve inside the window.
    sigma : ndarray, shape (S,)
        Noise level from :func:`~mtident.thermal.readings.noise_sigma`.

    Returns
    -------
    chi2, autocorrelation, fits : ndarray, shape (S,)
    """
    chi2, corr, fits = [], [], []
    for s in range(residuals.shape[1]):
        ok = np.isfinite(residuals[:, s]) & np.isfinite(values[:, s])
        r = residuals[ok, s]
        if not len(r):  # a filter that diverged leaves no residual: no fit, and no warning of numpy's
            chi2.append(math.nan)
            corr.append(math.nan)
            fits.append(False)
            continue
        dof = max(len(r) - 3, 1)
        c2 = float(np.sum((r / max(sigma[s], 1e-4)) ** 2) / dof)
        centred = r - r.mean()
        denom = float(np.sum(centred**2))
        ac = float(np.sum(centred[1:] * centred[:-1]) / denom) if denom > 0 else 0.0
        # χ² alone only for a gross misfit: the noise level is itself an estimate (±20 %); beyond
        # RUNAWAY_CHI2 no misjudged noise explains it, whatever the residuals' autocorrelation
        passes = c2 < RUNAWAY_CHI2 and (c2 < 4.0 + 4.0 * np.sqrt(2.0 / dof) or ac < 3.0 / np.sqrt(len(r)))
        if passes and len(r) >= 8:
            passes = first_order_suffices(time_min[ok], values[ok, s])
        chi2.append(c2)
        corr.append(ac)
        fits.append(passes)
    return np.array(chi2), np.array(corr), np.array(fits)


def identify_first_order(
    log: TemperatureLog,
    window_min: float,
    method: str,
    preset: str,
    horizon_min: float | None = None,
    pseudo_measurement_seed: int | None = None,
    ambient_C: FloatArray | None = None,
) -> Identification[FirstOrderDetails]:
    """Identify every sensor of ``log`` with one of the papers' first-order filters, or least
    squares, from its first ``window_min`` minutes, then predict (:func:`~mtident.thermal.identify.identify`
    with a method other than "robust").

    Parameters
    ----------
    log : TemperatureLog
    window_min : float
        Identification time L (minutes from the first sample).
    method : {"ukf", "aukf", "fukf", "afukf", "lsq"}
    preset : {"data", "xia2014", "yu2019"}
        Initial values and tuning: from the data or a paper's exactly.
    horizon_min : float, optional
        Predict to this time (default: the end of the log, or 4 time constants beyond the
        window if that is later).
    pseudo_measurement_seed : int, optional
        Predict as Xia et al. 2014 Eqs 21-22 do, from a generator with this seed.
    ambient_C : ndarray, shape (N,), optional
        A room sensor at the log's sample times (a UKF method with the data tuning only).

    Returns
    -------
    Identification
        With :class:`FirstOrderDetails`.

    Raises
    ------
    InputError
        A window that is not a positive number of minutes or holds too few samples, or a room
        sensor the method or preset cannot take.
    """
    window_min = minutes_given("window_min", window_min, "a positive number of minutes", strictly=True)
    room_rate = room_input(log, ambient_C, method, preset)
    # A diverging filter (the papers' presets can) is reported in the notes, not as numpy warnings.
    with np.errstate(over="ignore", invalid="ignore", divide="ignore"):
        return _identify(log, window_min, method, preset, horizon_min, pseudo_measurement_seed, room_rate, ambient_C)


@dataclass(frozen=True)
class _WarmupStart:
    """Where each sensor's warm-up begins in the window: a warm-up that began after the log
    (``late``, flat at ``level`` until ``begins``), and the window's readings with a flat start
    left out (NaN) where the data tuning fits from the end of it."""

    window_readings: FloatArray
    late: np.ndarray
    begins: FloatArray
    level: FloatArray

    @classmethod
    def of(cls, log: TemperatureLog, n_window: int, preset: str, notes: list[str]) -> _WarmupStart:
        tw, yw = log.time_min[:n_window], log.temperature_C[:n_window]
        sensors = yw.shape[1]
        if preset != "data":
            # the papers' presets fit from the first sample, as the papers do
            return cls(yw, np.zeros(sensors, dtype=bool), np.full(sensors, tw[0]), first_level(yw))
        onset = late_onset(tw, yw, noise_sigma(yw, tw))
        late = onset > 0
        # the data tuning leaves out a flat start (a sensor lag, or a warm-up that began later),
        # which a first-order model cannot follow
        onsets = first_order_onset(tw, yw)
        trimmed = yw.copy()
        for is_late in (True, False):
            which = [i for i in np.flatnonzero(onsets).tolist() if late[i] == is_late]
            for i in which:
                trimmed[: onsets[i], i] = np.nan
            why = (
                "stay at their first level (the warm-up began after the log)"
                if is_late
                else (
                    "rise slower than a first-order curve starts (a sensor lag, heat still on its way, or now and "
                    "then the noise of a few readings: leaving them out costs a little width, keeping a slow start "
                    "a bias)"
                )
            )
            if len(which) == 1:
                i = which[0]
                notes.append(
                    f"sensor {log.sensors[i]!r}: the first {tw[onsets[i]] - tw[0]:g} min {why}; the model is fitted "
                    f"from t = {tw[onsets[i]]:g} min"
                )
            elif which:  # one note for all: the sample's five lagging sensors made five lines
                lead = ", ".join(f"{log.sensors[i]!r} ({tw[onsets[i]] - tw[0]:g} min)" for i in which)
                notes.append(f"sensors {lead}: the first minutes {why}; each model is fitted from the end of them")
        return cls(trimmed, late, tw[onset], first_level(yw))


def _verdicts(
    log: TemperatureLog,
    tw: FloatArray,
    method: str,
    preset: str,
    course: FirstOrderCourse,
    chi2: FloatArray,
    autocorr: FloatArray,
    fits: np.ndarray,
    notes: list[str],
) -> tuple[FloatArray, FloatArray]:
    """The final mean (T∞ NaN where there is no approach to a steady state, or the filter
    diverged) and T∞'s standard deviation, widened where the first-order model does not fit the
    window; said in ``notes``."""
    diverged = ~np.isfinite(course.final_mean).all(axis=1) | ~np.isfinite(course.final_cov).all(axis=(1, 2))
    with np.errstate(invalid="ignore"):
        ran_away = ~diverged & (chi2 >= RUNAWAY_CHI2)
    for s in np.flatnonzero(ran_away).tolist():
        notes.append(
            f"sensor {log.sensors[s]!r}: the {method} filter's final estimate does not describe the window's "
            f"readings (its curve back over the window: residual χ²/dof {chi2[s]:.3g}): its answer says nothing of "
            "the model or of T∞" + ("; " + PRESET_HINT.format(preset=preset) if preset != "data" else "")
        )
    for s in np.flatnonzero(~fits & ~diverged & ~ran_away).tolist():
        notes.append(
            f"sensor {log.sensors[s]!r}: the first-order model does not fit the window (residual χ²/dof "
            f"{chi2[s]:.2f}, lag-1 autocorrelation {autocorr[s]:.2f}); the T∞ interval was widened by "
            f"{max(np.sqrt(chi2[s]), 2.0):.1f}x, and a longer window or a two-term model may be needed"
        )
    steady_sd = np.sqrt(course.final_cov[:, 2, 2]) * np.where(fits, 1.0, np.maximum(np.sqrt(chi2), 2.0))
    final_mean = course.final_mean.copy()
    rate_now = final_mean[:, 1]
    no_steady = ~(np.isfinite(rate_now) & (rate_now > 0) & np.isfinite(final_mean[:, 2]) & np.isfinite(steady_sd))
    if course.idle is not None:
        for s in np.flatnonzero(course.idle & ~diverged).tolist():
            notes.append(
                f"sensor {log.sensors[s]!r}: the {method} filter's {course.idle_words} in the window: its answer "
                "is the normal UKF's"
            )
        if method == "aukf":
            for s in np.flatnonzero(~course.idle & ~diverged & ~no_steady).tolist():
                notes.append(
                    f"sensor {log.sensors[s]!r}: the aukf filter's adaptive law (Xia 2014) re-estimated Q and R from "
                    "the window's residuals, and its covariance, which the interval is made of, then understates its "
                    "error even on a first-order warm-up (the docs' measured results): the normal UKF's interval "
                    "(--method ukf) holds the truth far more often"
                )
    for s in np.flatnonzero(diverged).tolist():
        notes.append(
            f"sensor {log.sensors[s]!r}: the {method} filter diverged (its estimate is no number by t = {tw[-1]:g} "
            "min): no T∞"
            + ("; " + PRESET_HINT.format(preset=preset) if preset != "data" else ", and its readings may be no warm-up")
        )
    for s in np.flatnonzero(no_steady & ~diverged).tolist():
        notes.append(
            f"sensor {log.sensors[s]!r}: no approach to a steady state in the first {tw[-1]:g} min "
            f"(λ = {rate_now[s]:.3g}/min with the {method} filter); T∞ is not identifiable from this window — "
            "use a longer `window_min`"
        )
    final_mean[no_steady, 2] = np.nan
    return final_mean, np.where(no_steady, np.nan, steady_sd)


def _say_undetermined(
    log: TemperatureLog, tw: FloatArray, half: FloatArray, rise: FloatArray, no_rise: np.ndarray, notes: list[str]
) -> None:
    """An interval wider than the whole rise so far: the window's course is still nearly
    straight and does not tell where it bends."""
    with np.errstate(invalid="ignore"):
        undetermined = ~no_rise & (half > rise)
    if not np.any(undetermined):
        return
    names = ", ".join(
        f"{log.sensors[s]!r} (± {half[s]:.2g} °C, rose {rise[s]:.2g} °C)" for s in np.flatnonzero(undetermined).tolist()
    )
    notes.append(
        f"T∞ is barely determined by the first {tw[-1]:g} min for {names}: the 95 % interval is wider than the rise "
        "seen so far (the course is still nearly straight); a longer `window_min` narrows it (thermal watch says when "
        "it is narrow enough)"
    )


def _identify(
    log: TemperatureLog,
    window_min: float,
    method: str,
    preset: str,
    horizon_min: float | None,
    pseudo_measurement_seed: int | None,
    room_rate: FloatArray | None = None,
    ambient_C: FloatArray | None = None,
) -> Identification[FirstOrderDetails]:
    n_window = window_samples(log, window_min)
    t = log.time_min
    y = log.temperature_C
    tw = t[:n_window]
    notes: list[str] = list(log.notes)
    start = _WarmupStart.of(log, n_window, preset, notes)
    yw = start.window_readings
    tuning = tuning_from_data(tw, yw) if preset == "data" else preset_tuning(preset, y.shape[1])
    # the data tuning has the noise level already (its R); the papers' R is a setting, not the noise
    sigma = np.sqrt(tuning.emission_cov[:, 0, 0]) if preset == "data" else noise_sigma(yw, tw)
    if method == "lsq":
        course = least_squares_course(t, tw, yw, tuning, window_min, horizon_min)
    else:
        course = filtered_course(
            t, tw, yw, method, preset, tuning, window_min, horizon_min, pseudo_measurement_seed, room_rate
        )
    chi2, autocorr, fits = model_check(tw, yw, yw - course.window_fit, sigma)
    for sensor, error in course.failed:
        notes.append(f"sensor {log.sensors[sensor]!r}: {error}; the other sensors are answered without it")
    final_mean, steady_sd = _verdicts(log, tw, method, preset, course, chi2, autocorr, fits, notes)
    mean_curve, curve_var, times = course.mean_curve, course.curve_var, course.times
    if np.any(start.late):
        # before its warm-up began the sensor stayed at its first level; the equilibrium time
        # counts from the log's start, as the measured one does
        before = start.late[None, :] & (times[:, None] < start.begins[None, :])
        mean_curve = np.where(before, start.level[None, :], mean_curve)
        curve_var = np.where(before, sigma[None, :] ** 2, curve_var)
    steady = final_mean[:, 2]
    rate = final_mean[:, 1]
    eq_time, rise, no_rise = _equilibrium_times(log.sensors, tw, yw, rate, start, sigma, notes)
    quantile = float(stdtrit(max(n_window - 3, 1), 0.975))
    _say_undetermined(log, tw, quantile * steady_sd, rise, no_rise, notes)
    untrusted = _untrusted(log, tw, start.begins, steady, quantile * steady_sd, rise, no_rise, notes)
    untrusted |= _faster_than_readings(log.sensors, tw, rate, method, notes)
    n_log = len(t)
    measured_part = np.full((len(times), y.shape[1]), np.nan)
    measured_part[: min(n_log, len(times))] = y[: min(n_log, len(times))]
    in_log = times <= t[-1] + 1e-9
    # without a steady state there is no prediction to measure: a course that runs away
    # (no approach, λ < 0) has an RMSE of 1e39 °C, which says nothing the warning does not
    errors = np.where(np.isfinite(steady), rmse(mean_curve[in_log], y[: int(in_log.sum())]), np.nan)
    final_measured, eq_measured, settled = measured_and_settled(t, y, DEFAULT_MAX_TIME_CONSTANT_MIN)
    quantile_half = quantile * steady_sd
    floor = _warm_up_floors(
        tw, yw, None if ambient_C is None else np.asarray(ambient_C, float)[:n_window], steady, sigma
    )
    # a warm-up does not come down: the low end no lower than where the sensor already is (never above T∞)
    ci95 = np.column_stack([np.minimum(np.maximum(steady - quantile_half, floor), steady), steady + quantile_half])
    curve_sd = np.sqrt(np.maximum(curve_var, 0.0))
    band_half = quantile * curve_sd
    notes_said = tuple(notes)
    return Identification(
        sensors=log.sensors,
        method=method,
        preset=preset,
        window_min=float(tw[-1]),
        n_window=n_window,
        time_min=times,
        measured_C=measured_part,
        curve_C=mean_curve,
        band_low_C=mean_curve - band_half,
        band_high_C=mean_curve + band_half,
        steady_state_C=steady,
        steady_state_ci95_C=ci95,
        start_C=mean_curve[0],
        equilibrium_time_min=eq_time,
        rmse_C=errors,
        # a residual test passed, T∞ determined, an answer physics allows, and a warm-up to answer for
        # (a flat column's T∞ was trusted beside its own "no warm-up to identify")
        model_ok=fits & np.isfinite(ci95).all(axis=1) & ~untrusted & ~no_rise,
        warnings=tuple(tuple(sensor_notes(notes_said, name)) for name in log.sensors),
        measured_final_C=final_measured,
        measured_equilibrium_time_min=eq_measured,
        measured_settled=settled,
        notes=notes_said,
        details=FirstOrderDetails(
            curve_sd_C=curve_sd,
            steady_state_sd_C=steady_sd,
            rate_per_min=rate,
            rate_sd_per_min=np.sqrt(course.final_cov[:, 1, 1]),
            fit_chi2=chi2,
            fit_autocorr=autocorr,
            fits=fits,
            history=course.history,
            history_sd=course.history_sd,
            quantile=quantile,
            untrusted=untrusted,
        ),
    )


def _equilibrium_times(
    sensors: tuple[str, ...],
    tw: FloatArray,
    yw: FloatArray,
    rate: FloatArray,
    start: _WarmupStart,
    sigma: FloatArray,
    notes: list[str],
) -> tuple[FloatArray, FloatArray, np.ndarray]:
    """Each sensor's equilibrium time (from the log's start), its rise in the window, and which
    sensors do not rise (each said in ``notes``; no equilibrium time)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        eq_time = np.where(rate > 0, equilibrium_time(rate), np.nan) + np.where(start.late, start.begins - tw[0], 0.0)
    # A sensor that does not rise in the window (never heated, or not connected) is at its level;
    # a λ fitted to its noise would give it an "equilibrium time" it never had.
    rise = reading_range(yw)
    no_rise = rise < rise_threshold(sigma)
    for s in np.flatnonzero(no_rise).tolist():
        notes.append(
            f"sensor {sensors[s]!r}: no rise in the first {tw[-1]:g} min ({rise[s]:.2f} °C from lowest to "
            "highest): no warm-up to identify; it has no equilibrium time"
        )
    return np.where(no_rise, np.nan, eq_time), rise, no_rise


def _warm_up_floors(
    tw: FloatArray, yw: FloatArray, room_C: FloatArray | None, steady: FloatArray, sigma: FloatArray
) -> FloatArray:
    """Per sensor, the lowest T∞ its warm-up allows (:func:`~mtident.thermal.measured.warm_up_floor_C`),
    −inf where none holds."""
    rounding = display_resolution(yw)
    return np.array(
        [
            warm_up_floor_C(float(steady[s]), tw, yw[:, s], room_C, float(sigma[s]), float(rounding[s]))
            for s in range(yw.shape[1])
        ]
    )


def _faster_than_readings(
    sensors: tuple[str, ...], tw: FloatArray, rate: FloatArray, method: str, notes: list[str]
) -> np.ndarray:
    """Which sensors' rate λ makes a time constant shorter than the readings' interval, each said
    in ``notes``: no mode the readings can show. On a real 1-s log with 0.32 °C steps the fading
    filters ran λ up to 1e74/min, took the latest reading as T∞ with an interval of zero width, and
    called it trusted, below where the sensor went on to read."""
    interval = sampling_interval_min(tw)
    with np.errstate(invalid="ignore", over="ignore"):
        fast = np.isfinite(rate) & (rate * interval > 1.0)
    for s in np.flatnonzero(fast).tolist():
        notes.append(
            f"sensor {sensors[s]!r}: not trusted: the {method} filter's rate λ = {rate[s]:.3g}/min is a time constant "
            f"of {1.0 / rate[s]:.2g} min, shorter than the readings' interval ({interval:.3g} min): no mode the "
            "readings can show; the filter has taken its latest readings as T∞, and its interval says nothing"
        )
    return np.asarray(fast, dtype=bool)


def _untrusted(
    log: TemperatureLog,
    tw: FloatArray,
    begins: FloatArray,
    steady: FloatArray,
    half: FloatArray,
    rise: FloatArray,
    no_rise: np.ndarray,
    notes: list[str],
) -> np.ndarray:
    """Which sensors' answers no physics allows, or that rest on too little rise, each said in
    ``notes``: a fit to fewer than ``MIN_RISE_SEEN_MIN`` minutes of rise (a warm-up that began just
    before the window's end: the filters then gave T∞ of millions of °C), or an interval reaching
    outside the temperatures a machine part can have, or wider than ``MAX_HALF_PER_RISE`` times the
    rise so far plus ``MAX_HALF_MARGIN_C``."""
    seen = tw[-1] - begins
    with np.errstate(invalid="ignore"):
        short = ~no_rise & (seen < MIN_RISE_SEEN_MIN)
        # a column that does not rise is no warm-up, but an absurd answer for it is no more to be trusted
        wide = (
            ~short
            & np.isfinite(half)
            & (
                (steady - half < OPEN_CIRCUIT_LOW_C)
                | (steady + half > OPEN_CIRCUIT_HIGH_C)
                | (half > MAX_HALF_PER_RISE * rise + MAX_HALF_MARGIN_C)
            )
        )
    for s in np.flatnonzero(short).tolist():
        notes.append(
            f"sensor {log.sensors[s]!r}: not trusted: its warm-up began {seen[s]:g} min before the window's end "
            f"(at t = {begins[s]:g} min); a first-order fit to {seen[s]:g} min of rise cannot tell where it bends "
            f"(at least {MIN_RISE_SEEN_MIN:g} min are needed): use a longer `window_min`"
        )
    for s in np.flatnonzero(wide).tolist():
        notes.append(
            f"sensor {log.sensors[s]!r}: not trusted: the 95 % interval of T∞, {steady[s]:.4g} ± {half[s]:.3g} °C "
            f"before a warm-up's floor lifts its low end, is wider than physics allows (for a rise of "
            f"{rise[s]:.2g} °C so far; a machine part stays within {OPEN_CIRCUIT_LOW_C:g} to {OPEN_CIRCUIT_HIGH_C:g} "
            "°C): the window's course does not determine it; use a longer `window_min`"
        )
    return np.asarray(short | wide, dtype=bool)
