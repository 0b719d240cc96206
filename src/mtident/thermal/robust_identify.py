"""Identify every sensor of a log with the model-robust estimate: the default of ``identify``.

Its answer is an :class:`~mtident.thermal.identification.Identification` whose ``details`` are
:class:`RobustDetails`. Each sensor's readings up to the identification time are fitted with sums of up to four
exponential modes (:mod:`mtident.thermal.robust`); the answer is the best-fitting model's course
and T∞, with the interval over every model the data cannot exclude. The predicted curve's band
is the envelope of the best model and the two models that set the interval's ends.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from mtident._json import json_inline
from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.io.logs import TemperatureLog, as_temperature_log
from mtident.thermal.assumptions import describe_assumptions
from mtident.thermal.identification import Identification, sensor_notes
from mtident.thermal.machine_answer import combined_estimate, fit_readings, unmeasured_wander
from mtident.thermal.measured import measured_and_settled, minutes_given, rmse, window_samples
from mtident.thermal.modal_types import Mode
from mtident.thermal.modes import fitted_curve
from mtident.thermal.readings import warming_room_warning
from mtident.thermal.reference import MachineReference, reference_for_log
from mtident.thermal.robust import estimate_sensor, with_fragility
from mtident.thermal.robust_types import Assumptions, RobustSettings, SensorEstimate
from mtident.thermal.settings import ROBUST_METHOD

__all__ = ["ModelAnswer", "RobustAnswer", "RobustDetails", "identify_robust"]

REPORT_LEVEL = 0.95
# the prediction runs this many of the slowest mode's time constants past the window, at least
HORIZON_TIME_CONSTANTS = 4.0


@dataclass(frozen=True, slots=True)
class ModelAnswer:
    """The best model of one sensor, as its answer's ``model`` object says it.

    Attributes
    ----------
    status : str
        The estimate's status ("estimated", "no rise", ...).
    modes : tuple of Mode
        The best model's modes (none without a fit).
    onset_min, rise_C, noise_C : float
        Where the warm-up begins, how far it has risen, the readings' noise.
    interval_ends : str
        In words, the models that set the 95 % interval's ends.
    reference_used, machine_model_used : bool
        The reference's time constants, or its machine model, were used.
    spikes_left_out : int
        Readings left out as spikes.
    """

    status: str
    modes: tuple[Mode, ...]
    onset_min: float
    rise_C: float
    noise_C: float
    interval_ends: str
    reference_used: bool
    machine_model_used: bool
    spikes_left_out: int


@dataclass(frozen=True, slots=True)
class RobustAnswer:
    """The model-robust estimate's part of one sensor's answer (its keys in the sensor's JSON object).

    Attributes
    ----------
    lambda_per_min, time_constant_min : float
        The slowest mode's rate and time constant (NaN without a fit).
    model_fits : bool
        The data do not contradict the model.
    assumptions : Assumptions
        What the interval rests on.
    model : ModelAnswer
        The best model.
    highest_interval : dict of str to (float, float)
        T∞'s interval at the highest level computed, under its key ``steady_state_ciNN_C`` (NN the
        level in %; a key of the JSON object itself, its name set by the level).
    """

    lambda_per_min: float
    time_constant_min: float
    model_fits: bool
    assumptions: Assumptions
    model: ModelAnswer
    highest_interval: dict[str, tuple[float, float]] = json_inline()


@dataclass(frozen=True)
class RobustDetails:
    """What the model-robust estimate adds to an
    :class:`~mtident.thermal.identification.Identification`: each sensor's estimate and what its
    interval assumes.

    Attributes
    ----------
    estimates : tuple of SensorEstimate
        Each sensor's best model, its intervals at every level computed, and its verdict.
    assumptions : tuple of Assumptions
        What each sensor's interval rests on.
    """

    estimates: tuple[SensorEstimate, ...]
    assumptions: tuple[Assumptions, ...]

    def answer(self, index: int) -> RobustAnswer:
        """T∞'s interval at the highest level computed, the slowest time constant, the assumptions
        and the best model's modes (:meth:`~mtident.thermal.identification.MethodDetails.answer`)."""
        e = self.estimates[index]
        fit = e.fit
        slowest = np.nan if fit is None else fit.slowest_time_constant_min()
        highest = max(e.interval_C)
        lo, hi = e.interval_C[highest]
        return RobustAnswer(
            lambda_per_min=float(1.0 / slowest) if np.isfinite(slowest) else np.nan,
            time_constant_min=float(slowest),
            model_fits=bool(e.model_ok),
            assumptions=self.assumptions[index],
            model=ModelAnswer(
                status=e.status,
                modes=() if fit is None else fit.modes,
                onset_min=e.onset_min,
                rise_C=e.rise_C,
                noise_C=e.noise_C,
                interval_ends=e.what_sets_the_ends(REPORT_LEVEL),
                reference_used=e.reference_used,
                machine_model_used=e.machine_used,
                spikes_left_out=e.spikes,
            ),
            highest_interval={f"steady_state_ci{round(100 * highest)}_C": (float(lo), float(hi))},
        )

    def describe(self) -> list[str]:
        """What the intervals assume, and each sensor's reference.

        Returns
        -------
        list of str
        """
        said = self.assumptions[0] if self.assumptions else None
        if said is None:
            return []
        return [
            f"  assumes: {said.model}, time constants up to {said.max_time_constant_min:g} min; room {said.room}",
            *(
                f"  reference for {e.sensor}: {a.reference}"
                for e, a in zip(self.estimates, self.assumptions, strict=True)
                if a.reference is not None
            ),
        ]

    def follows_room(self, index: int) -> bool:
        """Whether the sensor's modes take the room as an input, a room sensor given
        (:meth:`~mtident.thermal.identification.MethodDetails.follows_room`)."""
        fit = self.estimates[index].fit
        return fit is not None and fit.room_level_C is not None


def identify_robust(
    log: TemperatureLog,
    window_min: float,
    room_C: FloatArray | None = None,
    settings: RobustSettings | None = None,
    reference: MachineReference | None = None,
    horizon_min: float | None = None,
    room_sensor: str | None = None,
    *,
    sensors: Sequence[str] | None = None,
) -> Identification[RobustDetails]:
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
    sensors : sequence of str, optional
        The sensors to identify (default: all). The log's others still pin the reference's machine
        model: one sensor fitted with a machine model alone has no other sensor to share its modes'
        proportions with, and its answer would not be the one it gets beside them.

    Returns
    -------
    Identification
        With :class:`RobustDetails`.

    Raises
    ------
    InputError
        A window with too few readings, or a reference that knows none of the log's sensors.
    """
    log = as_temperature_log(log, "identify")
    settings = settings or RobustSettings()
    settings.unknown_heat_sensors(log.sensors)
    window_min = minutes_given("window_min", window_min, "a positive number of minutes", strictly=True)
    n = window_samples(log, window_min)
    t, y = log.time_min, log.temperature_C
    if room_C is not None and len(room_C) != len(t):
        msg = f"the room sensor has {len(room_C)} readings for {len(t)} samples"
        raise InputError(msg)
    room_window = None if room_C is None else room_C[:n]
    warming = None if room_C is None else warming_room_warning(room_C, room_sensor, t)
    room_said = () if warming is None else (warming,)
    unfit: list[str] = []
    if reference is not None:
        reference, unfit = reference_for_log(reference, log.sensors, room_C is not None, room_sensor)
    model = None if reference is None else reference.machine_model
    machine = fit_readings(model, log.sensors, t[:n], y[:n], room_window, settings.levels)
    if machine is not None and machine.contradicted:
        assert reference is not None
        unfit.append(
            f"the reference ({reference.identity}): its machine model is rejected by {len(machine.rejected)} of the "
            f"sensors it knows ({', '.join(machine.rejected)}): the reference is not used for any sensor (another "
            "machine's reference, this machine changed since its run, or the test's times or temperatures in another "
            "unit than the reference run's; learn the reference again, or give the unit (`time_unit`, "
            "`temperature_unit`))"
        )
        reference, model, machine = None, None, None
    asked = log.select(list(sensors) if sensors is not None else None).sensors
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
        for s, name in ((log.sensors.index(name), name) for name in asked)
    )
    log = log.select(list(asked))
    y = log.temperature_C
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
    steady = np.array([e.steady_C for e in estimates])
    return Identification(
        sensors=log.sensors,
        method=ROBUST_METHOD,
        preset="data",
        window_min=float(t[n - 1]),
        n_window=n,
        time_min=times,
        measured_C=measured,
        curve_C=curve,
        band_low_C=low,
        band_high_C=high,
        steady_state_C=steady,
        steady_state_ci95_C=np.array(
            [e.interval_C.get(REPORT_LEVEL, (-np.inf, np.inf)) for e in estimates], dtype=float
        ).reshape(-1, 2),
        start_C=np.array([np.nan if e.fit is None else e.fit.start_C for e in estimates]),
        # when each best model stays within 5 % of its total rise from T∞
        equilibrium_time_min=np.array([np.nan if e.fit is None else e.fit.equilibrium_time_min for e in estimates]),
        rmse_C=rmse(curve[in_log], y[: int(in_log.sum())]),
        model_ok=np.array([e.model_ok for e in estimates], dtype=bool),
        # what the log's reading said of a sensor (readings skipped, a unit converted) is its answer's too
        warnings=tuple((*sensor_notes(log.notes, e.sensor), *e.warnings) for e in estimates),
        measured_final_C=final,
        measured_equilibrium_time_min=equilibrium,
        measured_settled=settled,
        notes=(*log.notes, *unfit, *room_said, *(w for e in estimates for w in e.warnings)),
        details=RobustDetails(
            estimates=estimates,
            assumptions=tuple(
                describe_assumptions(settings, room_sensor, reference, e.sensor, room_C is not None, e.machine_used)
                for e in estimates
            ),
        ),
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
    if e.steady_C >= fit.start_C:
        # the answer assumes a warm-up that rises and does not overshoot: no course it allows falls
        # or passes its T∞'s interval, so neither may the band (an end's model that rose to 27 °C
        # and fell back to a low end of 23.3 drew a band whose low edge fell 2.6 °C)
        low = np.minimum(np.fmax.accumulate(low), lo)
        high = np.minimum(np.fmin.accumulate(high[::-1])[::-1], hi)
    return curve, low, high
