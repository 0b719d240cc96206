"""Identify, then predict: every sensor of a log from its first minutes, by the model-robust
fit (the default) or one of the papers' first-order filters (Xia et al. 2014 §2.1 end and §2.4;
Yu et al. 2019 §1.5).

:func:`identify` is the one way in, and the one place that picks the method and refuses the
settings a method has no use for. Every method answers with one type,
:class:`~mtident.thermal.identification.Identification`; the methods live in
:mod:`~mtident.thermal.robust_identify` and :mod:`~mtident.thermal.first_order`, and what a log
itself measures in :mod:`~mtident.thermal.measured`. Their names are importable from here as before.
"""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.io.logs import TemperatureLog, as_temperature_log
from mtident.thermal.first_order import (
    FIRST_ORDER_ASSUMPTIONS,
    Z95,
    first_order_suffices,
    identify_first_order,
    model_check,
)
from mtident.thermal.first_order_filter import filter_window, room_input, room_rates
from mtident.thermal.identification import Identification, MethodDetails, sensor_notes
from mtident.thermal.measured import (
    MIN_WINDOW_SAMPLES,
    SETTLED_MOVE_C,
    measured_and_settled,
    measured_equilibrium,
    minutes_given,
    rmse,
    window_samples,
)
from mtident.thermal.readings import frozen_words, without_stuck
from mtident.thermal.robust_identify import identify_robust
from mtident.thermal.robust_types import RobustSettings
from mtident.thermal.settings import DEFAULT_METHOD, IDENTIFY_METHODS, METHODS, ROBUST_METHOD

if TYPE_CHECKING:
    from collections.abc import Sequence

    from mtident.thermal.reference import MachineReference

__all__ = [
    "FIRST_ORDER_ASSUMPTIONS",
    "Identification",
    "MIN_WINDOW_SAMPLES",
    "MethodDetails",
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


def without_stuck_readings(log: TemperatureLog) -> TemperatureLog:
    """The log with each sensor's stuck readings at its end (:func:`~mtident.thermal.readings.stuck_since`),
    and those of a stretch that froze and moved on (:func:`~mtident.thermal.readings.frozen_stretches`),
    left out, and a note naming them: a failed channel's 0.00 °C from 150 min on was read as where
    the sensor settled (its measured final temperature 0.00, "settled", its RMSE 23 °C).

    Parameters
    ----------
    log : TemperatureLog

    Returns
    -------
    TemperatureLog
    """
    values, since, frozen = without_stuck(log.time_min, log.temperature_C)
    notes = [
        f"sensor {name!r}: every reading from t = {start:g} min to the log's end is the same value, which its "
        "noise makes no chance (a stuck sensor or a failed channel?): they are left out"
        for name, start in zip(log.sensors, since, strict=True)
        if not math.isnan(start)
    ]
    # a channel that froze for a while and read on: its repeats made the sensor a misfit, untrusted
    notes += [
        frozen_words(f"sensor {name!r}", stretches)
        for name, stretches in zip(log.sensors, frozen, strict=True)
        if stretches
    ]
    return replace(log, temperature_C=values, notes=(*log.notes, *notes)) if notes else log


def identify(
    log: TemperatureLog,
    window_min: float,
    method: str = DEFAULT_METHOD,
    preset: str = "data",
    horizon_min: float | None = None,
    pseudo_measurement_seed: int | None = None,
    ambient_C: FloatArray | None = None,
    *,
    settings: RobustSettings | None = None,
    reference: MachineReference | None = None,
    room_sensor: str | None = None,
    sensors: Sequence[str] | None = None,
) -> Identification[MethodDetails]:
    """Identify every sensor of ``log`` from its first ``window_min`` minutes, then predict.

    Parameters
    ----------
    log : TemperatureLog
    window_min : float
        Identification time L (minutes from the first sample).
    method : {"robust", "ukf", "aukf", "fukf", "afukf", "lsq"}
        "robust" (the model-robust estimate: sums of up to four modes, an interval over every
        model the data cannot exclude; :func:`~mtident.thermal.robust_identify.identify_robust`),
        or one of the papers' first-order filters, whose interval assumes a first-order machine
        (:func:`~mtident.thermal.first_order.identify_first_order`).
    preset : {"data", "xia2014", "yu2019"}
        First-order filters: initial values and tuning from the data (default) or a paper's exactly.
    horizon_min : float, optional
        Predict to this time (default: the end of the log, or 4 time constants
        beyond the window if that is later).
    pseudo_measurement_seed : int, optional
        First-order filters: predict as Xia et al. 2014 Eqs 21-22 do, feeding noisy
        pseudo-measurements to the filter after L, from a generator with this seed. Default: the
        deterministic forecast of the mean with its covariance.
    ambient_C : ndarray, shape (N,), optional
        A room sensor at the log's sample times. The room becomes an input of each
        sensor's heat balance (of every mode with the default ``"robust"`` method, of the
        first-order balance with a UKF method and the data tuning; lsq and the papers'
        presets refuse it), so a drifting room does not bend the identified curve; T∞ is
        then the steady state at the room's level at the end of the window, and the
        prediction holds the room there.
    settings : RobustSettings, optional
        The model-robust estimate's largest time constant, the room's wander and its modes
        (default: ``RobustSettings()``). The first-order filters refuse any other.
    reference : MachineReference, optional
        The model-robust estimate: a reference run of the same machine.
    room_sensor : str, optional
        The model-robust estimate: the room sensor's name, for the assumptions.
    sensors : sequence of str, optional
        The sensors to identify (default: every sensor of ``log``). With a reference, the log's
        other sensors still pin its machine model (:func:`~mtident.thermal.robust_identify.identify_robust`).

    Returns
    -------
    Identification
        One type for every method; its ``details`` are the method's own part
        (:class:`~mtident.thermal.robust_identify.RobustDetails` for "robust",
        :class:`~mtident.thermal.first_order.FirstOrderDetails` for the papers' filters).

    Raises
    ------
    InputError
        Unknown method or preset, a setting the method has no use for, or too few samples in the
        window.
    """
    if method not in IDENTIFY_METHODS:
        msg = f"method {method!r} is not one of: {', '.join(IDENTIFY_METHODS)}"
        raise InputError(msg)
    if horizon_min is not None:
        horizon_min = minutes_given("horizon_min", horizon_min, "a number of minutes, 0 or more", strictly=False)
    log = without_stuck_readings(as_temperature_log(log, "identify"))
    if method == ROBUST_METHOD:
        if preset != "data" or pseudo_measurement_seed is not None:
            setting = "`preset`" if preset != "data" else "`pseudo_measurement_seed`"
            msg = (
                f"{setting} is a setting of the papers' first-order filters: give `method` {', '.join(METHODS[:-1])} "
                f"or {METHODS[-1]} with it"
            )
            raise InputError(msg)
        return identify_robust(
            log, window_min, ambient_C, settings, reference, horizon_min, room_sensor, sensors=sensors
        )
    if reference is not None:
        msg = (
            "`reference` needs the model-robust method (`method='robust'`): the first-order filters have one mode "
            "and no reference to use"
        )
        raise InputError(msg)
    if settings is not None and settings != RobustSettings():
        msg = (
            "the largest time constant, the room's wander and the free fast modes (`max_time_constant_min`, "
            "`room_wander_C_per_h`, `free_fast_modes`) are settings of the model-robust method (`method='robust'`): "
            "the first-order filters take theirs from `preset`"
        )
        raise InputError(msg)
    log = log.select(list(sensors) if sensors is not None else None)
    return identify_first_order(log, window_min, method, preset, horizon_min, pseudo_measurement_seed, ambient_C)
