"""Identify, then predict: every sensor of a log from its first minutes, by the model-robust
fit (the default) or one of the papers' first-order filters (Xia et al. 2014 §2.1 end and §2.4;
Yu et al. 2019 §1.5).

:func:`identify` is the one way in; the methods live in
:mod:`~mtident.thermal.robust_identify` and :mod:`~mtident.thermal.first_order`, the answer of the
papers' filters in :mod:`~mtident.thermal.identification`, and what a log itself measures in
:mod:`~mtident.thermal.measured`. Their names are importable from here as before.
"""

from __future__ import annotations

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.io.logs import TemperatureLog, as_temperature_log
from mtident.thermal.first_order import (
    filter_window,
    first_order_suffices,
    identify_first_order,
    model_check,
    room_input,
    room_rates,
)
from mtident.thermal.identification import FIRST_ORDER_ASSUMPTIONS, Z95, Identification, sensor_notes
from mtident.thermal.measured import (
    MIN_WINDOW_SAMPLES,
    SETTLED_MOVE_C,
    measured_and_settled,
    measured_equilibrium,
    rmse,
    window_samples,
)
from mtident.thermal.robust_identify import RobustIdentification, identify_robust
from mtident.thermal.settings import DEFAULT_METHOD, IDENTIFY_METHODS, METHODS, ROBUST_METHOD

__all__ = [
    "FIRST_ORDER_ASSUMPTIONS",
    "Identification",
    "MIN_WINDOW_SAMPLES",
    "SETTLED_MOVE_C",
    "Z95",
    "filter_window",
    "first_order_suffices",
    "identify",
    "measured_and_settled",
    "measured_equilibrium",
    "model_check",
    "rmse",
    "room_input",
    "room_rates",
    "sensor_notes",
    "window_samples",
]


def identify(
    log: TemperatureLog,
    window_min: float,
    method: str = DEFAULT_METHOD,
    preset: str = "data",
    horizon_min: float | None = None,
    pseudo_measurement_seed: int | None = None,
    ambient_C: FloatArray | None = None,
) -> Identification | RobustIdentification:
    """Identify every sensor of ``log`` from its first ``window_min`` minutes, then predict.

    Parameters
    ----------
    log : TemperatureLog
    window_min : float
        Identification time L (minutes from the first sample).
    method : {"robust", "ukf", "aukf", "fukf", "afukf", "lsq"}
        "robust" (the model-robust estimate: sums of up to four modes, an interval over every
        model the data cannot exclude; :func:`~mtident.thermal.robust_identify.identify_robust`
        for its settings), or one of the papers' first-order filters, whose interval assumes a
        first-order machine.
    preset : {"data", "xia2014", "yu2019"}
        Initial values and tuning: from the data (default) or a paper's exactly.
    horizon_min : float, optional
        Predict to this time (default: the end of the log, or 4 time constants
        beyond the window if that is later).
    pseudo_measurement_seed : int, optional
        Predict as Xia et al. 2014 Eqs 21-22 do, feeding noisy pseudo-measurements to
        the filter after L, from a generator with this seed. Default: the
        deterministic forecast of the mean with its covariance.
    ambient_C : ndarray, shape (N,), optional
        A room sensor at the log's sample times. The room becomes an input of each
        sensor's heat balance (of every mode with the default ``"robust"`` method, of the
        first-order balance with a UKF method and the data tuning; lsq and the papers'
        presets refuse it), so a drifting room does not bend the identified curve; T∞ is
        then the steady state at the room's level at the end of the window, and the
        prediction holds the room there.

    Returns
    -------
    Identification or RobustIdentification
        The papers' filters' answer, or the model-robust one (the default method).

    Raises
    ------
    InputError
        Unknown method or preset, or too few samples in the window.
    """
    if method not in IDENTIFY_METHODS:
        msg = f"method {method!r} is not one of: {', '.join(IDENTIFY_METHODS)}"
        raise InputError(msg)
    log = as_temperature_log(log, "identify")
    if method == ROBUST_METHOD:
        if preset != "data":
            msg = (
                f"preset {preset!r} is a setting of the papers' first-order filters; with it choose one of: "
                f"{', '.join(METHODS)}"
            )
            raise InputError(msg)
        return identify_robust(log, window_min, ambient_C, horizon_min=horizon_min)
    return identify_first_order(log, window_min, method, preset, horizon_min, pseudo_measurement_seed, ambient_C)
