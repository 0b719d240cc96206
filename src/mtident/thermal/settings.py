"""Identification methods, their tuning, the papers' presets and the data-driven default.

Methods (the names the CLI and the JSON use): ``ukf`` (normal UKF), ``aukf`` (adaptive law of
Xia 2014), ``fukf`` (fading UKF of Yu 2019 Eqs 15-22), ``afukf`` (modified
adaptive fading UKF of Yu 2019: square-root UKF + normalised fading factor +
adaptive law) and ``lsq`` (batch least squares, the baseline).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.thermal.readings import noise_sigma, quick_estimate
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
]

METHODS = ("ukf", "aukf", "fukf", "afukf", "lsq")
PRESETS = ("data", "xia2014", "yu2019")
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
        C of the adaptive law (H in Yu et al. 2019).
    redraw : bool
        Redraw measurement sigma points (Yu et al. 2019 Eq. 8; exact Kalman filter on
        linear models) or reuse the propagated ones (Xia et al. 2014).
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
    """The UKF variant a method name stands for.

    Parameters
    ----------
    method : {"ukf", "aukf", "fukf", "afukf"}
    tuning : ThermalTuning
        Its adaptive law's threshold, whether sigma points are redrawn, and its parametrisation
        ("slope" runs in square-root form).

    Returns
    -------
    FilterConfig

    Raises
    ------
    InputError
        ``method`` is not one of the filters.
    """
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

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        The window's sample times (min).
    values : ndarray, shape (N, S)
        The window's readings (°C, NaN: missing or left out).
    start_min : float, optional
        The time the initial state is for (min); default: the window's first time.

    Returns
    -------
    ThermalTuning
        In the "slope" parametrisation.
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

    ``xia2014`` (Xia et al. 2014 §3.1): x₀ = [10, 0.01, 30], P₀ = diag(0.5², 0.1², 0.1²),
    Q₀ = 0.001²·I, R₀ = 0.001², C = 1e-4, propagated sigma points.
    ``yu2019`` (Yu et al. 2019 §2.1): x₀ = [10, 0.01, 30], P₀ = diag(0.25, 0.01, 0.01),
    Q₀ = 1e-6·I, R₀ = 1e-6, H = 1e-4, redrawn sigma points (Eq. 8).

    Parameters
    ----------
    preset : {"xia2014", "yu2019"}
    n_sensors : int
        The number of sensors, each tuned alike.

    Returns
    -------
    ThermalTuning
        In the "rate" parametrisation.

    Raises
    ------
    InputError
        ``preset`` is not one of the papers'.
    """
    if preset not in ("xia2014", "yu2019"):
        msg = f"preset {preset!r} is not one of: {', '.join(PRESETS)}"
        raise InputError(msg)
    mean = np.tile([10.0, 0.01, 30.0], (n_sensors, 1))
    cov = np.tile(np.diag([0.25, 0.01, 0.01]), (n_sensors, 1, 1))
    q = np.tile(1e-6 * np.eye(3), (n_sensors, 1, 1))
    r = np.full((n_sensors, 1, 1), 1e-6)
    return ThermalTuning(mean, cov, q, r, threshold_C=1e-4, redraw=(preset == "yu2019"), parametrisation="rate")
