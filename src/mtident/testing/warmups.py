"""Simulated warm-up runs of a machine, exact, then logged like a logger would: sampled, noisy
and rounded, started cold or partly warm, in a steady or a drifting room (with a room sensor).

The machines are :mod:`~mtident.testing.machines` (drawn) and
:mod:`~mtident.testing.structures` (their exact responses); the real curves beside the project
are :mod:`~mtident.testing.real_curves`. Every name of those this module has always offered is
importable from here too. Randomness comes only from the ``np.random.Generator`` passed in.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, replace
from typing import Any

import numpy as np
from scipy.linalg import expm

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.testing.machines import KINDS, log_uniform, random_machine
from mtident.testing.machines import _conduction as _conduction
from mtident.testing.machines import _network as _network
from mtident.testing.real_curves import RealCurve, load_real_curves
from mtident.testing.structures import (
    EQUILIBRIUM_FRACTION,
    Machine,
    crossing_time,
    forced_response,
    free_response,
    modal_form,
    room_temperature,
    steady_state,
)

__all__ = [
    "Machine",
    "WarmUp",
    "RealCurve",
    "random_machine",
    "simulate",
    "random_warmup",
    "reference_run",
    "modal_amplitudes",
    "room_temperature",
    "load_real_curves",
    "KINDS",
    "INTERVALS_MIN",
    "ROUNDINGS_C",
]

# Loggers seen on machine tools: 1 s, 10 s, 30 s, 1, 2 and 5 min.
INTERVALS_MIN = (1.0 / 60.0, 10.0 / 60.0, 0.5, 1.0, 2.0, 5.0)
# 0.32 °C is the TCLab's quantisation (10-bit ADC over a thermistor), the coarsest seen.
ROUNDINGS_C = (0.01, 0.02, 0.05, 0.1, 0.32)
ROUNDING_WEIGHTS = (0.5, 0.15, 0.15, 0.1, 0.1)
ROOM_ROUNDINGS_C = (0.01, 0.02, 0.05, 0.1)
ROOM_ROUNDING_WEIGHTS = (0.55, 0.2, 0.15, 0.1)
MIN_ROUNDING_STEPS = 20
DURATION_LIMITS_MIN = (60.0, 2000.0)
ONE_SECOND_MAX_DURATION_MIN = 300.0
REFERENCE_MAX_SAMPLES = 20_000


@dataclass(frozen=True)
class WarmUp:
    """One simulated warm-up test: what the logger wrote and the noiseless truth.

    Attributes
    ----------
    machine : Machine
    time_min : ndarray, shape (N,)
        Sample times from 0, evenly spaced by ``interval_min``.
    reading_C : ndarray, shape (N,)
        What the logger writes: noisy, rounded to ``rounding_C``, NaN where a row was dropped.
    clean_C : ndarray, shape (N,)
        Noiseless sensor temperature (room drift included).
    room_C : ndarray, shape (N,) or None
        Room sensor readings (noisy, rounded, NaN at the dropped rows) when the room drifts;
        None in a steady room.
    steady_C : ndarray, shape (N,)
        The truth: the sensor's equilibrium for the run's power with the room held at its level
        at each sample time (the room gain is 1, so it moves with the room one to one).
    start_C : float
        Noiseless sensor temperature at t = 0.
    t95_min : float
        First time the noiseless sensor of the steady-room version of the run reaches 95 % of
        its total rise, |clean − start| ≥ 0.95·|steady − start| (continuous time, exact).
    noise_C, rounding_C, interval_min : float
    settings : dict
        Everything drawn or given, JSON-serialisable (for a benchmark's table).
    power : float
        Heating power of the run (1 = the machine's nominal rise).
    initial_state_C : ndarray, shape (m,)
        The machine's state at t = 0 (absolute °C); with ``settings["room_start_C"]`` it fixes the
        modal amplitudes.
    """

    machine: Machine
    time_min: FloatArray
    reading_C: FloatArray
    clean_C: FloatArray
    room_C: FloatArray | None
    steady_C: FloatArray
    start_C: float
    t95_min: float
    noise_C: float
    rounding_C: float
    interval_min: float
    settings: dict[str, Any]
    power: float
    initial_state_C: FloatArray

    @property
    def rise_C(self) -> float:
        """Total rise of the run in its starting room: steady_C[0] − start_C.

        Returns
        -------
        float
            The rise (°C).
        """
        return float(self.steady_C[0] - self.start_C)

    @property
    def duration_min(self) -> float:
        """Time of the last sample.

        Returns
        -------
        float
            The time (min).
        """
        return float(self.time_min[-1])

    def __repr__(self) -> str:
        room = "drifting room" if self.room_C is not None else "steady room"
        return (
            f"WarmUp({self.machine.description}; {len(self.time_min)} samples every "
            f"{self.interval_min * 60:g} s, rise {self.rise_C:.2f} °C, t95 {self.t95_min:.1f} min, "
            f"σ {self.noise_C:.3g}, rounding {self.rounding_C:g} °C, {room})"
        )


def _initial_state(
    machine: Machine,
    power: float,
    room_start_C: float,
    warm_start: float,
    warm_profile: str,
    warm_power: float | None,
) -> tuple[FloatArray, float | None]:
    """The state at t = 0 and, for a previous heating, how long it lasted."""
    m = len(machine.A)
    cold = np.full(m, room_start_C)
    if not 0.0 <= warm_start < 1.0:
        raise InputError("warm_start is a fraction of the steady rise in [0, 1)")
    if warm_start == 0.0:
        return cold, None
    steady = steady_state(machine, power, room_start_C)
    if warm_profile == "steady":
        return cold + warm_start * (steady - cold), None
    if warm_profile != "heating":
        raise InputError("warm_profile is 'steady' or 'heating'")
    prior = power if warm_power is None else float(warm_power)
    if prior <= warm_start * power:
        raise InputError("the previous heating's power is too low to reach the warm start")
    prior_steady = steady_state(machine, prior, room_start_C)
    h0 = cold - prior_steady
    # the previous heating stops when the sensor has risen warm_start of this run's rise
    fraction = warm_start * power / prior
    t_pre = crossing_time(machine, h0, fraction)
    return prior_steady + expm(machine.A * t_pre) @ h0, t_pre


def _rounded(values: FloatArray, step: float) -> FloatArray:
    if step <= 0:
        return values
    # round() to 10 decimals drops the binary residue of k·step, as a logger's text would
    return np.round(np.round(values / step) * step, 10)


def simulate(
    machine: Machine,
    rng: np.random.Generator,
    *,
    power: float = 1.0,
    duration_min: float | None = None,
    interval_min: float = 1.0,
    noise_C: float = 0.02,
    rounding_C: float = 0.01,
    warm_start: float = 0.0,
    room_drift: Mapping[str, float] | None = None,
    room_start_C: float = 20.0,
    dropout: float = 0.0,
    warm_profile: str = "steady",
    warm_power: float | None = None,
) -> WarmUp:
    """One warm-up of ``machine`` at constant power, exact, then logged.

    Parameters
    ----------
    machine : Machine
    rng : numpy.random.Generator
        For the noise and the dropouts only.
    power : float
        Heating power (1 = the machine's nominal rise).
    duration_min : float or None
        Length of the record; None: 1.5·t95 clipped to 60-2000 min.
    interval_min : float
        Sampling interval.
    noise_C, rounding_C : float
        Gaussian noise σ of the sensor and the logger's rounding step (0: none).
    warm_start : float
        0: a cold start (everything at the room). f in (0, 1): the sensor starts at f of its
        steady rise, on the path given by ``warm_profile``.
    room_drift : mapping or None
        A drifting room (see :func:`room_temperature`), logged by a room sensor with its own
        ``noise_C`` (default 0.01) and ``rounding_C`` (default 0.01) from the mapping.
        None: the room stays at ``room_start_C`` and ``room_C`` is None.
    room_start_C : float
    dropout : float
        Fraction of rows (never the first) logged as NaN, independently at random.
    warm_profile : {"steady", "heating"}
        "steady": every state at f of its own steady rise (the steady profile scaled);
        "heating": the state after a previous heating from cold, at ``warm_power``, stopped when
        the sensor reached f of this run's rise (other modal amplitudes than "steady").
    warm_power : float or None
        Power of the previous heating (None: ``power``); must exceed f·power.

    Returns
    -------
    WarmUp

    Raises
    ------
    InputError
        A non-positive ``interval_min`` or ``duration_min``, a negative ``noise_C`` or
        ``rounding_C``, a ``dropout`` outside [0, 1), a ``warm_start`` outside [0, 1), an unknown
        ``warm_profile``, a ``warm_power`` too low to reach the warm start, or a bad ``room_drift``.
    """
    if not (interval_min > 0 and noise_C >= 0 and rounding_C >= 0 and 0 <= dropout < 1):
        raise InputError("need interval_min > 0, noise_C ≥ 0, rounding_C ≥ 0, 0 ≤ dropout < 1")
    x0, t_pre = _initial_state(machine, power, room_start_C, warm_start, warm_profile, warm_power)
    steady0 = steady_state(machine, power, room_start_C)
    t95 = crossing_time(machine, x0 - steady0, EQUILIBRIUM_FRACTION)
    if duration_min is None:
        duration_min = float(np.clip(1.5 * t95, *DURATION_LIMITS_MIN))
    if not duration_min > 0:
        raise InputError("duration_min must be positive")
    n = int(math.floor(duration_min / interval_min + 1e-9)) + 1
    t: FloatArray = np.arange(n, dtype=float) * interval_min
    forced, xp0 = forced_response(machine, t, power, room_start_C, room_drift)
    clean = forced + free_response(machine, x0 - xp0, interval_min, n)
    room = room_temperature(t, room_start_C, room_drift)
    heat_gain = float(machine.sensor @ np.linalg.solve(-machine.A, machine.b_heat))
    room_gain = float(machine.sensor @ np.linalg.solve(-machine.A, machine.b_room))
    steady = heat_gain * power + room_gain * room
    reading = _rounded(clean + noise_C * rng.standard_normal(n), rounding_C)
    room_C = None
    drift_settings = None
    if room_drift is not None:
        room_noise = float(room_drift.get("noise_C", 0.01))
        room_rounding = float(room_drift.get("rounding_C", 0.01))
        room_C = _rounded(room + room_noise * rng.standard_normal(n), room_rounding)
        drift_settings = {k: float(v) for k, v in room_drift.items()}
        drift_settings.setdefault("noise_C", room_noise)
        drift_settings.setdefault("rounding_C", room_rounding)
    if dropout > 0:
        lost = rng.random(n) < dropout
        lost[0] = False
        reading[lost] = np.nan
        if room_C is not None:
            room_C[lost] = np.nan
    start = float(clean[0])
    settings: dict[str, Any] = {
        "kind": machine.kind,
        "description": machine.description,
        "time_constants_min": list(machine.time_constants_min),
        "structural_time_constants_min": list(machine.structural_time_constants_min),
        "sensor_lag_min": machine.sensor_lag_min,
        "power": float(power),
        "duration_min": float(t[-1]),
        "interval_min": float(interval_min),
        "samples": n,
        "noise_C": float(noise_C),
        "rounding_C": float(rounding_C),
        "warm_start": float(warm_start),
        "warm_profile": warm_profile if warm_start > 0 else None,
        "warm_power": None
        if warm_start == 0 or warm_profile == "steady"
        else float(power if warm_power is None else warm_power),
        "warm_heating_min": t_pre,
        "room_start_C": float(room_start_C),
        "room_drift": drift_settings,
        "dropout": float(dropout),
        "start_C": start,
        "steady_start_C": float(steady[0]),
        "rise_C": float(steady[0]) - start,
        "t95_min": t95,
    }
    return WarmUp(
        machine=machine,
        time_min=t,
        reading_C=reading,
        clean_C=clean,
        room_C=room_C,
        steady_C=steady,
        start_C=start,
        t95_min=t95,
        noise_C=float(noise_C),
        rounding_C=float(rounding_C),
        interval_min=float(interval_min),
        settings=settings,
        power=float(power),
        initial_state_C=x0,
    )


def _draw_rounding(rng: np.random.Generator, rise: float) -> float:
    """A rounding of the population that leaves at least 20 steps in the rise."""
    if rise < MIN_ROUNDING_STEPS * ROUNDINGS_C[0]:
        raise InputError(f"a rise of {rise:.3g} °C is under 20 steps of any rounding")
    while True:
        step = float(rng.choice(ROUNDINGS_C, p=ROUNDING_WEIGHTS))
        if abs(rise) >= MIN_ROUNDING_STEPS * step:
            return step


def _draw_interval(rng: np.random.Generator, duration: float, max_samples: int | None) -> float:
    """A sampling interval of the population; 1 s only for records of at most 300 min."""
    while True:
        interval = float(rng.choice(INTERVALS_MIN))
        if interval == INTERVALS_MIN[0] and duration > ONE_SECOND_MAX_DURATION_MIN:
            continue
        if max_samples is not None and duration / interval > max_samples:
            continue
        return interval


def random_warmup(
    rng: np.random.Generator,
    *,
    kind: str | None = None,
    with_drift: bool | None = None,
    with_dropouts: bool = False,
) -> WarmUp:
    """Draw a machine and a warm-up of it from the benchmark population.

    Machine as :func:`random_machine` (75 % network, 25 % conduction; lag with probability 0.4;
    the run's own rise log-uniform in 2-30 °C). Warm start with probability 0.2: a fraction
    0.1-0.6 of the steady rise, on the steady profile or after a previous heating (half each;
    its power 0.5-2× this run's). Room drift with probability 0.3: amplitude 0.05-0.3 °C, period
    12-24 h, random phase, half of them with a ramp of ±0.005-0.05 °C/h; a room sensor with σ
    log-uniform 0.005-0.05 °C and rounding 0.01-0.1 °C. Room at the start 17-25 °C. Duration 1.5·t95
    clipped to 60-2000 min; sampling 1 s (only up to 300 min), 10 s, 30 s, 1, 2 or 5 min; noise
    σ log-uniform 0.005-0.05 °C; rounding 0.01 (50 %), 0.02, 0.05 (15 % each), 0.1, 0.32 °C
    (10 % each), drawn again while the rise is under 20 steps.

    Parameters
    ----------
    rng : numpy.random.Generator
    kind : {"network", "conduction"} or None
        None draws it.
    with_drift : bool or None
        None draws it (probability 0.3); True/False forces a drifting/steady room.
    with_dropouts : bool
        Lose a fraction log-uniform in 0.1-5 % of the rows (NaN readings).

    Returns
    -------
    WarmUp
        ``settings`` holds every draw (the machine's structure under ``"machine"``).
    """
    power = 1.0
    warm_start, warm_profile, warm_power = 0.0, "steady", None
    if rng.random() < 0.2:
        warm_start = float(rng.uniform(0.1, 0.6))
        if rng.random() < 0.5:
            warm_profile = "heating"
            warm_power = float(rng.uniform(max(0.5, warm_start / 0.8), 2.0))
    # the run itself rises 2-30 °C: a warm machine's full rise is larger by 1/(1 − f)
    rise_C = float(log_uniform(rng, 2.0, 30.0)) / (1.0 - warm_start)
    machine = random_machine(rng, kind, rise_C=rise_C)
    room_start = float(rng.uniform(17.0, 25.0))
    x0, _ = _initial_state(machine, power, room_start, warm_start, warm_profile, warm_power)
    steady0 = steady_state(machine, power, room_start)
    t95 = crossing_time(machine, x0 - steady0, EQUILIBRIUM_FRACTION)
    duration = float(np.clip(1.5 * t95, *DURATION_LIMITS_MIN))
    interval = _draw_interval(rng, duration, None)
    noise = float(log_uniform(rng, 0.005, 0.05))
    rise = float(machine.sensor @ (steady0 - x0))
    rounding = _draw_rounding(rng, rise)
    drift: dict[str, float] | None = None
    if rng.random() < 0.3 if with_drift is None else with_drift:
        drift = {
            "amplitude_C": float(rng.uniform(0.05, 0.3)),
            "period_min": float(rng.uniform(12.0, 24.0) * 60.0),
            "phase_rad": float(rng.uniform(0.0, 2.0 * math.pi)),
            "slope_C_per_h": 0.0,
            "noise_C": float(log_uniform(rng, 0.005, 0.05)),
            "rounding_C": float(rng.choice(ROOM_ROUNDINGS_C, p=ROOM_ROUNDING_WEIGHTS)),
        }
        if rng.random() < 0.5:
            drift["slope_C_per_h"] = float(rng.choice((-1.0, 1.0)) * rng.uniform(0.005, 0.05))
    dropout = float(log_uniform(rng, 0.001, 0.05)) if with_dropouts else 0.0
    run = simulate(
        machine,
        rng,
        power=power,
        duration_min=duration,
        interval_min=interval,
        noise_C=noise,
        rounding_C=rounding,
        warm_start=warm_start,
        room_drift=drift,
        room_start_C=room_start,
        dropout=dropout,
        warm_profile=warm_profile,
        warm_power=warm_power,
    )
    return replace(run, settings={**run.settings, "machine": machine.structure})


def reference_run(machine: Machine, rng: np.random.Generator, **kw: Any) -> WarmUp:
    """A long cold-start run of the same machine, for learning its modes.

    Defaults (each overridden by a keyword of :func:`simulate`): power drawn in 0.6-1.4 (times
    ``base_power``, default 1); a cold start in a steady room; duration 3·t95 (a shorter
    ``duration_min`` given is raised to 3·t95); interval, noise and rounding drawn as in
    :func:`random_warmup`, the interval so that the record has at most 20 000 samples.

    Parameters
    ----------
    machine : Machine
    rng : numpy.random.Generator
    **kw
        Keywords of :func:`simulate`, and ``base_power``.

    Returns
    -------
    WarmUp
        ``settings["reference"]`` is True.

    Raises
    ------
    InputError
        A non-zero ``warm_start`` (a reference run starts cold), or what :func:`simulate` refuses.
    """
    base = float(kw.pop("base_power", 1.0))
    power = float(kw.pop("power", rng.uniform(0.6, 1.4) * base))
    if kw.get("warm_start", 0.0):
        raise InputError("a reference run starts cold")
    room_start = float(kw.pop("room_start_C", 20.0))
    x0 = np.full(len(machine.A), room_start)
    steady0 = steady_state(machine, power, room_start)
    t95 = crossing_time(machine, x0 - steady0, EQUILIBRIUM_FRACTION)
    duration = max(float(kw.pop("duration_min", 0.0) or 0.0), 3.0 * t95)
    if "interval_min" not in kw:
        kw["interval_min"] = _draw_interval(rng, duration, REFERENCE_MAX_SAMPLES)
    # whole intervals up to at least 3·t95: the last sample is not before it
    duration = math.ceil(duration / kw["interval_min"] - 1e-9) * kw["interval_min"]
    if "noise_C" not in kw:
        kw["noise_C"] = float(log_uniform(rng, 0.005, 0.05))
    if "rounding_C" not in kw:
        kw["rounding_C"] = _draw_rounding(rng, float(machine.sensor @ (steady0 - x0)))
    run = simulate(machine, rng, power=power, duration_min=duration, room_start_C=room_start, **kw)
    return replace(run, settings={**run.settings, "reference": True})


def modal_amplitudes(machine: Machine, warmup: WarmUp) -> tuple[FloatArray, FloatArray]:
    """The run's sensor response as T∞ + Σ a_k·exp(−t/τ_k), in a steady room.

    Exact from the eigendecomposition A = V·Λ·V⁻¹: a_k = (sensor·V)_k·(V⁻¹(x0 − x∞))_k, with x0
    the run's initial state and x∞ its equilibrium at the starting room. T∞ = warmup.steady_C[0];
    for a drifting room this is the steady-room version of the run (the modes are the same).

    Parameters
    ----------
    machine : Machine
    warmup : WarmUp

    Returns
    -------
    taus : ndarray, shape (m,)
        Time constants (min), descending (one per state, the lag included).
    amplitudes : ndarray, shape (m,)
        a_k (°C); they sum to start_C − T∞.
    """
    room = float(warmup.settings["room_start_C"])
    h0 = warmup.initial_state_C - steady_state(machine, warmup.power, room)
    rates, amplitudes = modal_form(machine, h0)
    taus = -1.0 / rates
    order = np.argsort(-taus)
    return taus[order], amplitudes[order]
