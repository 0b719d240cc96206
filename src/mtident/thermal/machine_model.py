"""One model of the machine: every sensor a sum of the same modes, each mode's amplitudes across
the sensors in the proportions a reference run showed.

Physics (issue 36). For a linear thermal structure ``dx/dt = A·x + B·u + b·room`` seen through
sensor rows ``C``, any constant heat input and any initial state give

    y_s(t) = T∞_s − Σ_k (C_s·v_k)·z_k·e^(−t/τ_k) + (room through the same modes),

with ``v_k`` the structure's mode shapes and ``z_k = w_kᵀ(x∞ − x0)`` one number per mode, the same
for every sensor. The heat split, the power and a partly warm start change only ``z``; the shape
``C_s·v_k`` is the machine's. A reference run that reached equilibrium measures it (its amplitudes
``g_sk``, with ``z = 1`` in the reference), and a later test has only one free amplitude per mode for
the whole machine instead of one per mode and sensor. Its slow mode, the one that keeps a test
open, is then pinned by every sensor together.

A sensor's own lag (a sleeve, a thermowell) adds a fast mode of its own: each sensor keeps
``FAST_TIME_CONSTANTS_MIN`` modes with free amplitudes. The room enters through the same modes with
static gain one. How the room reaches each sensor does not depend on the heat input: where the
reference run's room moved enough to show it, each sensor's gains on the room ``h_sk`` are learnt
from that run and a test's room is then a known input; elsewhere a test fits them as ``g_sk·η_k``,
``η`` shared, and counts a moving room's lag as uncertain.

The tie is held loosely, not exactly: each tied amplitude may leave ``g_sk·z_k`` by a prior of
``TIE_SLACK`` of itself (the reference's own error, a slightly non-linear machine), and a sensor
whose readings reject the tie (a likelihood-ratio test against its own free amplitudes) is left to
its own fit.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Any

import numpy as np
from scipy import optimize
from scipy.special import chdtri, ndtri

from mtident._threads import one_blas_thread
from mtident._typing import FloatArray
from mtident.thermal.lsq import flat_lead
from mtident.thermal.modal_search import correlation_factor, room_lag
from mtident.thermal.modal_types import Binned, Mode, bin_samples
from mtident.thermal.readings import ROOM_LEVEL_FLOOR_C, ROOM_TREND_MIN, display_resolution, noise_sigma, room_trend
from mtident.thermal.robust import MISFIT_FACTOR

FAST_TIME_CONSTANTS_MIN = (0.7, 2.5)
"""Each sensor's own fast modes (free amplitudes): a sensor's lag, the start's details."""
TIE_SLACK = 0.15
"""Prior sd of a tied amplitude's departure from ``g_sk·z_k``, relative to it."""
OWN_AMPLITUDE_SHARE = 0.1
"""Shared modes faster than this share of the slowest may be untied, each sensor's amplitude its
own, where sensors reject the tie of all (:func:`_own_amplitudes`)."""
TAU_BOX_MIN = 0.05
"""The smallest relative box searched around each of the reference's time constants."""
TAU_BOX_SDS = 3.0
TAU_DEPARTURE_SDS = 1.5 * TAU_BOX_SDS
"""A test whose fit moves a time constant this many prior sds (twice its box) from the reference's
does not follow the machine model (:func:`_departed`)."""
LOOSE_BOX = 0.3
"""A time constant whose box is wider than this is profiled, not linearised."""
ROOM_LAG_SHARE = 0.6
"""The share of the room's rate times the slowest time constant taken as the prior sd of each
sensor's own lag behind the room (:func:`_lag_variance`): what the readings cannot tell of it. A
machine lags a drifting room by the rate times each sensor's mean delay, ``C·(−A)⁻¹·1``, which
``benchmarks/study_room_lag.py`` finds between 0.30 and 2.47 of the slowest time constant over the
development machines' sensors (median 1.01): within 2.5 sd of one time constant at this share."""
ROOM_TRUNCATION_SHARE = 0.5
"""And at most this share of it for the model's truncation, within the whole (the lag's variance and
this no more than the square of the rate times the slowest time constant): a model of fewer modes
than the machine gets the room's path into it wrong, which shows only when the room moves. It is
no more than the readings ask: the shift of the level that fitting the lag would make
(:func:`_lag_variance`), where the room's course has shown the path (a daily cycle's readings fit
the model's path, and the whole share held such tests open until a turn of the cycle)."""
ROOM_RESPONSE_SHARE = 0.3
"""A learnt room response's own error (one sd): this share of the room's effect on the sensor, in
quadrature with the reference's standard error (the model is a truncation); of it a test counts
what its readings cannot tell and no more than they ask (:func:`_learnt_allowance`)."""
ROOM_RESPONSE_LAG_SHARE = 0.5
"""And this share of the lag's sd without a learnt response (:data:`ROOM_LAG_SHARE`): the drift's
lag, which a reference's daily cycle does not show; counted likewise."""
ROOM_STATIC_SD = 0.05
"""The prior sd of a sensor's static gain on the room (one) in its learnt room gains."""
ROOM_SHOWN_C = 0.05
"""A reference run shows the room's path into the machine only where its room, through the slowest
mode, moved by at least this (°C)."""
ROOM_RESPONSE_LEARNT = 0.2
"""A sensor's room response is kept from the reference run where its lag behind a ramp
(``Σ_k h_sk·τ_k``) is known within this share of the slowest time constant (one sd)."""
ROOM_PRIOR_SHARE = 0.3
ROOM_PRIOR_GAIN = 0.5
"""The room factors' prior sd: this share of their static-gain-one value, plus a room gain of this
at the sensor that shows the mode most."""
ROOM_PATH_DELAYS = (0.5, 1.0, 2.0)
"""The room may reach the sensors later than through a model's one mode: through a chain of bodies
whose modes the model does not hold (a chain of 175, 159 and 93 min learnt as one mode of 174, the
room at its far end). A test's fit is made again with the room delayed by these shares of the time
constant, and its interval holds each such fit: the readings cannot tell them apart where the one
mode's room factor takes up the heat's misfit."""
MODEL_ERROR_FACTOR = 1.8
"""The fit's standard error times this: the machine model is a truncation (fewer modes than the
machine, time constants learnt at another heat split), and its error shows in the extrapolation,
not in the residuals. Calibrated on the development machines (their 95 % intervals at the stop
covered 88 % without it)."""
PROFILE_POINTS = (-1.0, -0.5, 0.5, 1.0)
REJECT_P = 1e-3
CONTRADICTION_MIN_MIN = 10.0
"""Most sensors rejecting the tie say the test is not the reference's machine only over readings
of at least this (min) and half the slowest shared mode."""
MAX_MODES = 6
AT_LIMIT = 0.99
"""A shared mode at this share of the slowest searched or beyond is at the search's limit."""
MIN_LOG_SPACING = 0.2
"""Two shared modes closer than this (log ratio) are one: the pair would only cancel."""
_START_TAUS_MIN = (1.5, 4.0, 10.0, 25.0, 60.0, 150.0, 400.0)
MISSING_MODE_P = 1e-4
"""A sensor's run shows a mode the shared ones lack where one more mode explains it beyond this
chance (χ² on two degrees of freedom, searched over :data:`MISSING_MODE_GRID` time constants)."""
MISSING_MODE_C = 0.1
"""And carries at least this much of its rise (°C)."""
MISSING_MODE_GRID = 16
MISSING_MODE_SHARE = 0.1
"""The fastest mode searched for, as a share of the slowest shared one."""
# the machine model is kept only where the run pins each of its slow shared time constants (at
# least FAST_SHARE of the slowest) within MAX_MACHINE_BOX: a test fitted with time constants the
# run left loose extrapolates with the wrong ones, confidently (two slow modes 190 and 186 min,
# learnt as 239 ±172 % and 196 ±50 %, stopped a test 0.21 °C off at 162 min). A faster loose one
# (a close pair of modes well below the slowest, learnt as one) is profiled across its box by the
# test's fit instead: it has decayed long before the slowest mode that sets the stop
MAX_MACHINE_BOX = 0.5
FAST_SHARE = 0.3
"""Loose modes faster than this share of the slowest are profiled by a test's fit, not refused."""


@dataclass(frozen=True)
class MachineModel:
    """The machine's modes and their shapes across its sensors, learnt from one complete run.

    Attributes
    ----------
    sensors : tuple of str
    time_constants_min : tuple of float
        The shared modes' time constants (K), slowest first.
    box : tuple of float
        Each time constant's relative half-width searched in a test.
    gains_C : tuple of tuple of float
        ``gains_C[s][k]``: sensor s's amplitude of mode k in the reference run (°C; rise positive).
    room_gains : tuple of tuple of float, optional
        ``room_gains[s][k]``: sensor s's gain of mode k on the room, learnt from the reference run
        (a row of NaN: not learnt for that sensor; empty: for none).
    room_gain_cov : tuple, optional
        Per sensor, the covariance (K, K) of its room gains.
    """

    sensors: tuple[str, ...]
    time_constants_min: tuple[float, ...]
    box: tuple[float, ...]
    gains_C: tuple[tuple[float, ...], ...]
    room_gains: tuple[tuple[float, ...], ...] = ()
    room_gain_cov: tuple[tuple[tuple[float, ...], ...], ...] = ()

    def describe(self) -> str:
        """What a test fitted with the model assumes, in words."""
        taus = ", ".join(f"{t:.3g}" for t in self.time_constants_min)
        return (
            f"the machine model: every sensor fitted together, the amplitudes of its {len(self.time_constants_min)} "
            f"shared modes ({taus} min) in the reference run's proportions across the sensors (each within "
            f"{TIE_SLACK:.0%} of them), used where the readings do not reject it and its interval agrees with the "
            "sensor's own"
            + (
                f"; the room's path into {self.learnt_room_sensors()} learnt from the reference run"
                if self.room_gains
                else ""
            )
        )

    def learnt_room_sensors(self) -> str:
        """The sensors whose room response the model knows, in words."""
        known = [name for name, row in zip(self.sensors, self.room_gains, strict=True) if np.all(np.isfinite(row))]
        return "every sensor" if len(known) == len(self.sensors) else ", ".join(known)

    def of(self, sensors: list[str]) -> MachineModel:
        """The model of some of its sensors."""
        if not self.room_gains:
            return replace(self, sensors=tuple(sensors), gains_C=tuple(map(tuple, self.gains(sensors))))
        gains, cov = self.room_response(sensors)
        return replace(
            self,
            sensors=tuple(sensors),
            gains_C=tuple(map(tuple, self.gains(sensors))),
            room_gains=tuple(tuple(map(float, row)) for row in gains),
            room_gain_cov=tuple(tuple(tuple(map(float, r)) for r in c) for c in cov),
        )

    def room_response(self, sensors: tuple[str, ...] | list[str]) -> tuple[FloatArray, FloatArray]:
        """The room gains (S, K) of ``sensors`` and their covariances (S, K, K) (NaN where not
        learnt)."""
        k = len(self.time_constants_min)
        known = dict(zip(self.sensors, zip(self.room_gains, self.room_gain_cov, strict=True), strict=False))
        gains = np.full((len(sensors), k), math.nan)
        cov = np.full((len(sensors), k, k), math.nan)
        for s, name in enumerate(sensors):
            if name in known:
                gains[s], cov[s] = known[name]
        return gains, cov

    def gains(self, sensors: tuple[str, ...] | list[str]) -> FloatArray:
        """The gains (S, K) of ``sensors`` (a row of NaN for one the model does not know)."""
        known = {name: row for name, row in zip(self.sensors, self.gains_C, strict=True)}
        k = len(self.time_constants_min)
        return np.array([known.get(name, (math.nan,) * k) for name in sensors], dtype=float).reshape(len(sensors), k)


@dataclass(frozen=True)
class MachineFit:
    """A test's readings fitted with the machine model.

    Attributes
    ----------
    steady_C : ndarray (S,)
        Each sensor's T∞ at the room's latest level (NaN where the sensor is not in the fit).
    half_width_C : dict of float to ndarray (S,)
        The interval's half-width per level.
    used : ndarray of bool (S,)
        Sensors fitted with the tie (known to the model, with readings, not rejecting it).
    rejected : tuple of str
        Sensors whose readings reject the tie.
    amplitudes : ndarray (K,)
        The test's amplitude of each mode relative to the reference run (``z``).
    modes : tuple of tuple of Mode
        Per sensor, its course's modes (the shared ones, then its own fast ones; amplitudes as
        :func:`~mtident.thermal.modes.model_curve` takes them), empty where not fitted.
    room_gains : tuple of tuple of float
        Per sensor, each of its modes' gain on the room (empty without a room).
    origin_min : float
        Where the modes begin.
    contradicted : bool
        Most of the sensors fitted reject the tie or misfit the model (residuals correlated beyond
        ``MISFIT_FACTOR``; then none is used): the test does not follow the reference's machine
        (another machine's reference, or a changed machine).
    room_lag_C : ndarray (S,), optional
        The part of each sensor's interval that is its lag behind a moving room (one sd, °C: its
        own lag as the fit counts it with the truncation's share, or a learnt response's error;
        where the physics bounds it tighter, :func:`_path_bound`'s), 0 where none.
    """

    steady_C: FloatArray
    half_width_C: dict[float, FloatArray]
    used: np.ndarray
    rejected: tuple[str, ...]
    amplitudes: FloatArray
    modes: tuple[tuple[Mode, ...], ...] = ()
    room_gains: tuple[tuple[float, ...], ...] = ()
    origin_min: float = 0.0
    contradicted: bool = False
    room_lag_C: FloatArray | None = None


@dataclass(frozen=True)
class MachineReadings:
    """A log's readings as the machine model takes them, to learn it or to fit a test
    (:func:`machine_readings`).

    Attributes
    ----------
    sensors : tuple of str
        The columns' names (fitting a test: a sensor the model does not know is left out).
    time_min : ndarray, shape (N,)
    values : ndarray, shape (N, S)
        The readings (°C, NaN: missing).
    room_C : ndarray, shape (N,) or None
        The room sensor (an input of every mode, static gain one), as its trend over
        :data:`~mtident.thermal.readings.ROOM_TREND_MIN`.
    noise_C : ndarray, shape (S,)
        Each sensor's noise per reading.
    origin_min : float
        Where the warm-up begins.
    """

    sensors: tuple[str, ...]
    time_min: FloatArray
    values: FloatArray
    room_C: FloatArray | None
    noise_C: FloatArray
    origin_min: float

    @cached_property
    def binned(self) -> list[Binned | None]:
        """Each sensor's readings since the warm-up began, in bins (None for one of fewer than eight
        valid readings): binned once, for the model's learning, its checks and a test's fits."""
        after = self.time_min >= self.origin_min
        out: list[Binned | None] = []
        for s in range(self.values.shape[1]):
            y = self.values[after, s]
            if np.count_nonzero(np.isfinite(y)) < 8:
                out.append(None)
                continue
            room = None if self.room_C is None else self.room_C[after]
            out.append(bin_samples(self.time_min[after] - self.origin_min, y, room))
        return out


# ----------------------------------------------------------------------------------------------
# Columns shared by the reference's fit and the test's


def _exp_columns(u: FloatArray, taus: FloatArray) -> FloatArray:
    columns: FloatArray = np.exp(-u[:, None] / np.asarray(taus, dtype=float)[None, :])
    return columns


def _room_columns(binned: Binned, taus: FloatArray, delay_min: float = 0.0) -> FloatArray:
    """The room through each mode, less the room; with ``delay_min``, that much later first (a room
    that reaches the sensors through a chain of bodies: many stages in series act as a delay)."""
    assert binned.room_C is not None
    room = binned.room_C
    if delay_min > 0:
        room = np.interp(binned.time_min - delay_min, binned.time_min, room)
    return (room_lag(room, binned.time_min, np.asarray(taus, dtype=float)) - binned.room_C).T


def _target(binned: Binned) -> FloatArray:
    return binned.value_C - (binned.room_C if binned.room_C is not None else 0.0)


# ----------------------------------------------------------------------------------------------
# Learning the model from a complete run


def _free_design(binned: Binned, taus: FloatArray) -> FloatArray:
    """One sensor's columns with its own amplitudes: [level, fast modes, −each mode, room gains]."""
    u = binned.time_min
    cols = [np.ones((len(u), 1)), _exp_columns(u, np.array(FAST_TIME_CONSTANTS_MIN)), -_exp_columns(u, taus)]
    if binned.room_C is not None:
        cols.append(_room_columns(binned, taus))
    design: FloatArray = np.hstack(cols)
    return design


def _sensor_solve(binned: Binned, taus: FloatArray, noise: float) -> tuple[FloatArray, FloatArray]:
    """One sensor's free fit at shared ``taus``: its coefficients (:func:`_free_design`) and its
    weighted residuals."""
    X = _free_design(binned, taus)
    w = np.sqrt(binned.count) / noise
    coef = np.asarray(np.linalg.lstsq(X * w[:, None], _target(binned) * w, rcond=None)[0], dtype=float)
    resid: FloatArray = (_target(binned) - X @ coef) * w
    return coef, resid


def _residuals(log_taus: FloatArray, bins: list[Binned], noise: FloatArray) -> FloatArray:
    """Every sensor's weighted residuals, each with its own amplitudes at shared time constants."""
    taus = np.exp(log_taus)
    return np.concatenate([_sensor_solve(b, taus, n)[1] for b, n in zip(bins, noise, strict=True)])


def _total_chi2(log_taus: FloatArray, bins: list[Binned], noise: FloatArray) -> float:
    resid = _residuals(log_taus, bins, noise)
    return float(resid @ resid)


def _spaced_chi2(log_taus: FloatArray, bins: list[Binned], noise: FloatArray) -> float:
    """:func:`_total_chi2`, steeply penalised where two time constants come closer than
    ``MIN_LOG_SPACING``: the search stays among models whose modes are distinct, instead of
    ending on a cancelling pair."""
    chi2 = _total_chi2(log_taus, bins, noise)
    gaps = np.diff(np.sort(log_taus))
    return chi2 * (1.0 + 100.0 * float(np.sum(np.clip(MIN_LOG_SPACING - gaps, 0.0, None) ** 2)))


def _best_taus(
    bins: list[Binned], noise: FloatArray, starts: list[FloatArray], bounds: tuple[float, float]
) -> tuple[FloatArray, float]:
    lo, hi = math.log(bounds[0]), math.log(bounds[1])
    best: tuple[FloatArray, float] = (starts[0], math.inf)
    for start in starts:
        x0 = np.clip(np.log(start), lo + 1e-6, hi - 1e-6)
        res = optimize.minimize(_spaced_chi2, x0, args=(bins, noise), method="L-BFGS-B", bounds=[(lo, hi)] * len(x0))
        taus = np.sort(np.exp(res.x))[::-1]
        spaced = len(taus) < 2 or np.min(np.log(taus[:-1] / taus[1:])) >= 0.9 * MIN_LOG_SPACING
        if res.fun < best[1] and spaced:
            best = (taus, float(res.fun))
    return best


@one_blas_thread()  # thousands of tiny solves: BLAS threads would only wait on one another
def learn_machine_model(
    readings: MachineReadings, max_time_constant_min: float, more_than: MachineModel | None = None
) -> MachineModel | None:
    """Fit a complete run's sensors together with shared time constants.

    The number of shared modes grows while the drop in χ² beats the BIC's price of one more
    mode (a time constant and an amplitude and room gain per sensor).

    Parameters
    ----------
    readings : MachineReadings
        The run's readings.
    max_time_constant_min : float
        The slowest mode searched (at most half the run, which pins down nothing slower).
    more_than : MachineModel, optional
        A model of these readings that lacks a mode some sensor shows (:func:`missing_modes`):
        the answer has one shared mode more, searched from its time constants and the missing
        mode's, whatever the BIC says (its price is that of every sensor, the evidence one
        sensor's). None where it already has :data:`MAX_MODES`, or no sensor lacks a mode.

    Returns
    -------
    MachineModel or None
        None where fewer than two sensors have readings.
    """
    binned = readings.binned
    keep = [s for s, b in enumerate(binned) if b is not None]
    if len(keep) < 2:
        return None
    bins = [b for b in binned if b is not None]
    noise = np.maximum(readings.noise_C[keep], 1e-4)
    n_rows = sum(len(b) for b in bins)
    span = max(float(b.time_min[-1]) for b in bins)
    # a run pins down no mode much slower than itself: a longer one would only stand in for the room
    bounds = (1.0, min(max_time_constant_min, 0.5 * span))
    if more_than is not None:
        lacking = missing_modes(more_than, readings)
        known = np.array(more_than.time_constants_min)
        if not lacking or len(known) >= MAX_MODES:
            return None
        taus, found = _best_taus(bins, noise, [np.append(known, tau) for tau, _ in lacking.values()], bounds)
        if not math.isfinite(found):  # no search kept the modes apart
            return None
    else:
        taus, chi2 = _best_taus(bins, noise, [np.array([30.0])], bounds)
        per_mode_params = 1 + len(bins) * (2 if readings.room_C is not None else 1)
        for _ in range(1, MAX_MODES):
            starts = [np.append(taus, t) for t in _START_TAUS_MIN if np.all(np.abs(np.log(taus / t)) > 0.3)]
            more, more_chi2 = _best_taus(bins, noise, starts, bounds)
            if chi2 - more_chi2 <= per_mode_params * math.log(n_rows):
                break
            taus, chi2 = more, more_chi2
    k = len(taus)
    gains = np.full((len(readings.sensors), k), math.nan)
    for s, b, n in zip(keep, bins, noise, strict=True):
        coef, _ = _sensor_solve(b, taus, n)
        gains[s] = coef[1 + len(FAST_TIME_CONSTANTS_MIN) : 1 + len(FAST_TIME_CONSTANTS_MIN) + k]
    sd = _log_tau_sd(bins, noise, taus)
    # a mode at the slowest searched stands in for any slower one: the run does not bound it
    # (a 300-min run's 150-min mode, its box ±5 %, stopped a test of a 150-min machine 0.18 °C off)
    sd = np.where(taus >= AT_LIMIT * bounds[1], np.inf, sd)
    box = tuple(float(max(TAU_BOX_MIN, math.expm1(min(TAU_BOX_SDS * v, 1.0)))) for v in sd)
    model = MachineModel(
        readings.sensors,
        tuple(float(t) for t in taus),
        box,
        tuple(tuple(float(v) for v in row) for row in gains),
    )
    return model if readings.room_C is None else _with_room_response(model, keep, bins, noise)


def loose_slow_modes(model: MachineModel) -> list[str]:
    """The machine model's slow shared modes (at least :data:`FAST_SHARE` of the slowest) that the
    run pins down only within more than :data:`MAX_MACHINE_BOX`, in words ("239 min ±172%"): a
    model with any is not kept.

    Parameters
    ----------
    model : MachineModel

    Returns
    -------
    list of str
    """
    slowest = max(model.time_constants_min)
    return [
        f"{tau:.3g} min ±{box:.0%}"
        for tau, box in zip(model.time_constants_min, model.box, strict=True)
        if box > MAX_MACHINE_BOX and tau >= FAST_SHARE * slowest
    ]


def missing_modes(model: MachineModel, readings: MachineReadings) -> dict[str, tuple[float, float]]:
    """The sensors whose run shows a slow mode the shared ones lack: per sensor, the time constant
    (min, between the fastest shared mode, and at least :data:`MISSING_MODE_SHARE` of the slowest,
    and the slowest) and amplitude (°C) of the one mode more that explains its readings beyond chance
    (:data:`MISSING_MODE_P`, over the residuals' correlation factor) with at least
    :data:`MISSING_MODE_C` of its rise. A machine model of fewer modes than the machine (a chain's
    middle modes) fits such a sensor's run and extrapolates its test wrongly with confidence."""
    taus = np.array(model.time_constants_min)
    # a mode faster than every shared one (a sensor's own lag) is the test's free fast modes' to
    # take up; one between the shared modes changes how a test extrapolates. None is slower than the
    # machine's slowest, whose mode every sensor shares: one found there is a cancelling pair that
    # moves the slowest time constant a little for one sensor, a learning artefact (those left out
    # held their tests open to the end, where the machine model answered them well)
    slowest = float(taus.max())
    fastest = max(MISSING_MODE_SHARE * slowest, float(taus.min()) * math.exp(MIN_LOG_SPACING))
    grid = np.exp(np.linspace(math.log(fastest), math.log(slowest), MISSING_MODE_GRID))
    grid = grid[(grid < slowest) & np.all(np.abs(np.log(grid[:, None] / taus[None, :])) > MIN_LOG_SPACING, axis=1)]
    k = 1 + len(FAST_TIME_CONSTANTS_MIN) + len(taus)
    out: dict[str, tuple[float, float]] = {}
    for s, b in enumerate(readings.binned):
        name = readings.sensors[s]
        if b is None or name not in model.sensors:
            continue
        noise = max(float(readings.noise_C[s]), 1e-4)  # as learn_machine_model floors it
        _, resid = _sensor_solve(b, taus, noise)
        corr = correlation_factor(resid)
        tried = [(extra, *_sensor_solve(b, np.append(taus, extra), noise)) for extra in grid]
        drops = [(float(resid @ resid) - float(more @ more)) / corr for _, _, more in tried]
        best = int(np.argmax(drops)) if drops else -1
        if best >= 0 and drops[best] > chdtri(2, MISSING_MODE_P) and abs(tried[best][1][k]) >= MISSING_MODE_C:
            out[name] = (float(tried[best][0]), float(tried[best][1][k]))
    return out


def _with_room_response(model: MachineModel, keep: list[int], bins: list[Binned], noise: FloatArray) -> MachineModel:
    """The model with each sensor's gains on the room, where the run pins its lag behind the room
    down (:data:`ROOM_RESPONSE_LEARNT`): its own free fit's room coefficients and their covariance,
    scaled by the residuals' χ² per degree of freedom and correlation."""
    taus = np.array(model.time_constants_min)
    if not _room_moved(bins[0], float(taus.max())):
        return model
    k = len(taus)
    gains = np.full((len(model.sensors), k), math.nan)
    cov = np.full((len(model.sensors), k, k), math.nan)
    for s, b, n in zip(keep, bins, noise, strict=True):
        X = _free_design(b, taus)
        w = np.sqrt(b.count) / n
        # the room's static gain is one: Σ_k h_sk = 1, within what a sensor's own lag takes
        static = np.concatenate([np.zeros(X.shape[1] - k), np.ones(k)]) / ROOM_STATIC_SD
        coef, full = _least_squares(np.vstack([X * w[:, None], static]), np.append(_target(b) * w, 1 / ROOM_STATIC_SD))
        resid = (_target(b) - X @ coef) * w
        scale = max(1.0, float(resid @ resid) / max(1, len(resid) - X.shape[1])) * correlation_factor(resid)
        c = full[-k:, -k:] * scale
        if math.sqrt(max(float(taus @ c @ taus), 0.0)) <= ROOM_RESPONSE_LEARNT * taus.max():
            gains[s], cov[s] = coef[-k:], c
    if not np.any(np.isfinite(gains[:, 0])):
        return model
    return replace(
        model,
        room_gains=tuple(tuple(map(float, row)) for row in gains),
        room_gain_cov=tuple(tuple(tuple(map(float, r)) for r in c) for c in cov),
    )


def _room_moved(binned: Binned, slowest_min: float) -> bool:
    """Whether the run's room moved enough, over the slowest mode's time, to show how the room
    reaches the sensors (:data:`ROOM_SHOWN_C`). A steady room's sensor wobbles by its noise alone,
    which every slow path fits alike: the lag a fit reads from it is the model's, not the run's."""
    assert binned.room_C is not None
    course = room_lag(binned.room_C, binned.time_min, np.array([slowest_min]))[0]
    return float(np.ptp(course)) >= ROOM_SHOWN_C


def _log_tau_sd(bins: list[Binned], noise: FloatArray, taus: FloatArray) -> FloatArray:
    """Each log time constant's sd from the χ² surface's curvature (the Gauss-Newton Hessian)."""
    x = np.log(taus)
    h = 1e-3
    r0 = _residuals(x, bins, noise)
    J = np.empty((len(r0), len(x)))
    for j in range(len(x)):
        step = np.zeros_like(x)
        step[j] = h
        J[:, j] = (_residuals(x + step, bins, noise) - r0) / h
    scale = max(1.0, float(r0 @ r0) / max(1, len(r0) - len(x)))
    try:
        cov = np.linalg.inv(J.T @ J) * scale
    except np.linalg.LinAlgError:
        return np.full(len(x), math.inf)
    sd: FloatArray = np.sqrt(np.clip(np.diag(cov), 0, None))
    return sd


# ----------------------------------------------------------------------------------------------
# Fitting a test with the model


def fit_test(
    model: MachineModel, readings: MachineReadings, levels: tuple[float, ...], room_lag: bool = True
) -> MachineFit | None:
    """Each sensor's T∞ and interval from the test's readings so far, every sensor fitted together
    with the model's modes.

    Parameters
    ----------
    model : MachineModel
    readings : MachineReadings
        The test's readings so far.
    levels : tuple of float
        The intervals' confidence levels.
    room_lag : bool, optional
        Count a moving room's lag as uncertain (:func:`_room_lag_sd`): a test's readings. False
        for the reference run itself, whose modes and room gains are being learnt from it.

    Returns
    -------
    MachineFit or None
        None where fewer than two sensors can be fitted with the tie; ``contradicted`` where most
        of them reject it.

    Notes
    -----
    Where sensors reject the tie of every mode, the fit is made again with the fast modes untied
    (:func:`_own_amplitudes`), and kept where fewer reject that tie: a reference run pins a fast
    pair of modes' shapes poorly, and at another heat split the pair no longer cancels. Where they
    still reject it and the room's path was learnt, the fit is made again with the room's path
    fitted as without a learnt one (each sensor's lag then counted as uncertain), kept likewise: a
    path learnt from one room's cycle misfits a larger one where the room reaches a sensor faster
    than the model's modes (a new user's nose, reached in minutes, rejected it in a room cycling
    twice as far, and with two others refused the reference).
    """
    no_mode = np.zeros(len(model.time_constants_min), bool)
    best = _fit_tied(model, readings, levels, room_lag, no_mode)
    fast = _own_amplitudes(np.array(model.time_constants_min))
    others = [(model, fast)] if fast.any() else []
    if model.room_gains and readings.room_C is not None:
        fitted_room = replace(model, room_gains=(), room_gain_cov=())
        others += [(fitted_room, no_mode)] + ([(fitted_room, fast)] if fast.any() else [])
    for other, own in others:
        if best is not None and not best.rejected:
            break
        alternative = _fit_tied(other, readings, levels, room_lag, own)
        if (
            alternative is not None
            and not alternative.contradicted
            and (best is None or len(alternative.rejected) < len(best.rejected))
        ):
            best = alternative
    return best


def _fit_tied(
    model: MachineModel, readings: MachineReadings, levels: tuple[float, ...], room_lag: bool, own: np.ndarray
) -> MachineFit | None:
    """:func:`fit_test` with the modes ``own`` says untied (each sensor's amplitude its own)."""
    sensors, t, room_C, origin_min = readings.sensors, readings.time_min, readings.room_C, readings.origin_min
    gains = model.gains(sensors)
    noise = np.maximum(readings.noise_C, 1e-4)
    fitted = {s: b for s, b in enumerate(readings.binned) if b is not None and np.all(np.isfinite(gains[s]))}
    taus, tau_sd = _centres(model)
    # early on, a test's fast start (a mode faster than the reference run could show) misfits the
    # model too: only readings over half the slowest mode say it is another machine
    long_enough = t[-1] - origin_min >= max(CONTRADICTION_MIN_MIN, 0.5 * max(model.time_constants_min))
    lag_sd = _room_lag_sd(t, room_C, max(model.time_constants_min)) if room_lag else 0.0
    known = _known_room(model, sensors, fitted, taus, lag_sd if room_lag else None)
    fitted.update({s: k.binned for s, k in known.items()})
    # a sensor whose room response the model knows has the room taken out and its course's error
    # added; the others fit the room through the modes, each with a lag of its own
    lag_share = ROOM_LAG_SHARE if room_lag else 0.0
    rejected: list[int] = []
    # the worst sensor first, one at a time: a sensor far off pulls the shared amplitudes, and
    # the others' misfit then is its doing; where most sensors reject the tie, it does not hold
    while True:
        used = [s for s in fitted if s not in rejected]
        if 2 * len(rejected) > len(fitted):
            if not long_enough:
                return None
            return _contradicted(len(sensors), tuple(sensors[s] for s in rejected), levels, origin_min)
        if len(used) < 2:
            return None
        bins = [fitted[s] for s in used]
        known_lag = {j: (known[s].lag_column, known[s].course) for j, s in enumerate(used) if s in known}
        passes = _tied_solve(bins, gains[used], noise[used], taus, tau_sd, own, lag_share, known_lag)
        if passes is None:
            return None
        at_model, solved = passes
        excess = _excess(bins, gains[used], noise[used], taus, at_model, own)
        worst = int(np.argmax(excess))
        if excess[worst] <= chdtri(max(int((~own).sum()), 1), REJECT_P):
            break
        rejected.append(used[worst])
    solved, steady, half, bounded = _profiled(
        bins, gains[used], noise[used], model, solved, levels, own, lag_share, known_lag, lag_sd if room_lag else None
    )
    if _departed(solved.taus, taus, tau_sd):
        return None
    # the tie holds (the shapes), but the time constants do not: a machine of other time constants
    misfit = [sensors[s] for s, corr in zip(used, solved.corr, strict=True) if corr > MISFIT_FACTOR]
    if long_enough and 2 * (len(rejected) + len(misfit)) > len(fitted):
        return _contradicted(len(sensors), (*(sensors[s] for s in rejected), *misfit), levels, origin_min)
    # without room_lag (the reference run itself) both are zero; the truncation's share is what
    # the room's lag (its readings' part and this) leaves of the whole allowance, and no more than
    # the readings ask the path to move the level by
    whole = np.sqrt(np.clip(np.minimum((ROOM_TRUNCATION_SHARE * lag_sd) ** 2, lag_sd**2 - solved.lag_var), 0, None))
    lag = np.array(
        [
            _learnt_allowance(known[s], lag_sd, solved, j) if s in known else min(whole[j], abs(solved.lag_shift[j]))
            for j, s in enumerate(used)
        ]
    )
    stated = {level: np.hypot(h, ndtri(0.5 + level / 2.0) * lag) for level, h in half.items()}
    # the physics bounds the whole of the room's path, the truncation's share with it
    half = {level: np.minimum(h, bounded[level]) for level, h in stated.items()}
    path_sd = np.hypot(lag, np.sqrt(solved.lag_var + solved.room_factor_var))
    if room_lag:
        widest = max(levels)
        off, sd = _path_lag_bound(solved, lag_sd)
        path_sd = np.where(
            bounded[widest] < stated[widest], np.minimum(path_sd, sd + off / ndtri(0.5 + widest / 2.0)), path_sd
        )
    room_gains = [
        known[s].room_gains if s in known else row for s, row in zip(used, _room_gains_of(solved), strict=True)
    ]
    latest_room = 0.0 if room_C is None else float(np.asarray(room_C)[np.isfinite(room_C)][-1])
    placed = _Placed(len(sensors), used)
    return MachineFit(
        placed.values(steady + latest_room, math.nan),
        {level: placed.values(h, math.inf) for level, h in half.items()},
        placed.values(np.ones(len(used), bool), False),
        tuple(sensors[s] for s in rejected),
        solved.z,
        placed.rows(_modes_of(solved), ()),
        placed.rows(room_gains, ()) if room_C is not None else (),
        origin_min,
        room_lag_C=placed.values(path_sd, 0.0),
    )


def _departed(fitted: FloatArray, taus: FloatArray, tau_sd: FloatArray) -> bool:
    """Whether a (linearised) time constant was fitted beyond :data:`TAU_DEPARTURE_SDS` of its prior:
    the test's readings pull it out of the reference's box, so the reference's modes are not this
    test's (a machine's 149 and 210 min learnt as one of 235 ±10 %: a test at another heat split
    fitted it at 316 min, 9 sd away, and stopped 0.24 °C off). The linearisation does not hold that
    far either."""
    held = tau_sd > 1e-5
    return bool(np.any(np.abs(np.log(fitted[held] / taus[held])) > TAU_DEPARTURE_SDS * tau_sd[held]))


def _learnt_allowance(known: _KnownRoom, lag_sd: float, solved: _Solved, j: int) -> float:
    """How far a learnt room path may put sensor ``j``'s level off (one sd, °C), besides the lag's
    variance the fit counts: the reference's standard error, and of the course's scale error and a
    drift's lag each what the readings cannot tell (the variance one more column would add) and
    of the rest of its allowance no more than they ask (the shift that column would make). A daily
    cycle's readings show the path and leave little of either; a drift's cannot, and leave both."""
    lag_whole = math.sqrt(max((ROOM_RESPONSE_LAG_SHARE * lag_sd) ** 2 - solved.lag_var[j], 0.0))
    scale_whole = math.sqrt(max(known.share_sd**2 - solved.response_var[j], 0.0))
    return math.hypot(
        known.late_sd,
        math.sqrt(solved.response_var[j]),
        min(scale_whole, abs(solved.response_shift[j])),
        min(lag_whole, abs(solved.lag_shift[j])),
    )


@dataclass(frozen=True)
class _KnownRoom:
    """A sensor whose room response the model knows: its readings with the room's course through
    that response taken out; how far that course may be off (one sd, °C, the most over the later
    half of the readings; none in the reference run itself) by the reference's standard error
    (``late_sd``) and by :data:`ROOM_RESPONSE_SHARE` of itself (``share_sd``); its room gains per
    mode (its fast modes none); the
    room's course through the slowest mode less the room (the column a lag of its own on a drift
    would take) and the course itself (the column of an error in its scale)."""

    binned: Binned
    late_sd: float
    share_sd: float
    room_gains: tuple[float, ...]
    lag_column: FloatArray
    course: FloatArray


def _known_room(
    model: MachineModel,
    sensors: tuple[str, ...] | list[str],
    fitted: dict[int, Binned],
    taus: FloatArray,
    lag_sd: float | None,
) -> dict[int, _KnownRoom]:
    """The sensors whose room response the model knows well enough here.

    The course may be off by the reference's standard error and :data:`ROOM_RESPONSE_SHARE` of
    itself (the most over the later half of the readings), and by a lag of its own of up to
    :data:`ROOM_RESPONSE_LAG_SHARE` of ``lag_sd``, the lag counted without a learnt response: a
    reference run's room shows the response at its own frequencies (a daily cycle), and a drift's
    lag is the response at none, which a machine whose room reaches a sensor through a chain of
    bodies sets beyond the slowest time constant (how much of each a test counts:
    :func:`_learnt_allowance`). A sensor whose course could be less certain than ``lag_sd`` is left to
    the fitted room factors; ``lag_sd`` None: the reference run itself, every learnt response
    used."""
    if not model.room_gains:
        return {}
    gains, cov = model.room_response(sensors)
    slowest = int(np.argmax(taus))
    out: dict[int, _KnownRoom] = {}
    for s, b in fitted.items():
        if b.room_C is None or not np.all(np.isfinite(gains[s])):
            continue
        R = _room_columns(b, taus)
        course = R @ gains[s]
        se = np.sqrt(np.clip(np.einsum("bk,kl,bl->b", R, cov[s], R), 0, None))
        sd = np.hypot(se, ROOM_RESPONSE_SHARE * course)
        later = b.time_min >= 0.5 * b.time_min[-1]
        late = float(np.max(sd[later]))
        if lag_sd is None or math.hypot(late, ROOM_RESPONSE_LAG_SHARE * lag_sd) < lag_sd:
            row = (*map(float, gains[s]), *(0.0,) * len(FAST_TIME_CONSTANTS_MIN))
            out[s] = _KnownRoom(
                replace(b, value_C=b.value_C - b.room_C - course, room_C=None),
                0.0 if lag_sd is None else float(np.max(se[later])),
                0.0 if lag_sd is None else ROOM_RESPONSE_SHARE * float(np.max(np.abs(course[later]))),
                row,
                R[:, slowest],
                course,
            )
    return out


def _contradicted(count: int, rejected: tuple[str, ...], levels: tuple[float, ...], origin_min: float) -> MachineFit:
    """The answer where most sensors reject the tie: no sensor fitted with it."""
    return MachineFit(
        np.full(count, math.nan),
        {level: np.full(count, math.inf) for level in levels},
        np.zeros(count, bool),
        rejected,
        np.zeros(0),
        origin_min=origin_min,
        contradicted=True,
    )


@dataclass(frozen=True)
class _Placed:
    """The fitted sensors' places among all the sensors."""

    count: int
    used: list[int]

    def values(self, fitted: np.ndarray, missing: object) -> np.ndarray:
        out = np.full(self.count, missing, dtype=np.asarray(fitted).dtype)
        out[self.used] = fitted
        return out

    def rows(self, fitted: list[tuple[Any, ...]], missing: tuple[Any, ...]) -> tuple[tuple[Any, ...], ...]:
        out = [missing] * self.count
        for j, s in enumerate(self.used):
            out[s] = fitted[j]
        return tuple(out)


def _modes_of(solved: _Solved) -> list[tuple[Any, ...]]:
    """Each fitted sensor's modes: the shared ones, then its own fast ones."""
    fast = np.array(FAST_TIME_CONSTANTS_MIN)
    return [
        tuple(Mode(float(t), -float(a)) for t, a in zip(solved.taus, shared, strict=True))
        + tuple(Mode(float(t), float(f)) for t, f in zip(fast, own, strict=True))
        for shared, own in zip(solved.amplitudes, solved.fast, strict=True)
    ]


def _room_gains_of(solved: _Solved) -> list[tuple[Any, ...]]:
    """Each fitted sensor's room gain per mode (its own fast modes none)."""
    return [(*map(float, row), *(0.0,) * len(FAST_TIME_CONSTANTS_MIN)) for row in solved.room_gains]


@dataclass(frozen=True)
class _Solved:
    """A joint fit: its coefficients and their covariance, the modes' amplitudes ``z``, and per
    sensor the χ² of its readings (with its slack's prior), its rows and its residuals' correlation
    factor."""

    coef: FloatArray
    cov: FloatArray
    z: FloatArray
    chi2_per_sensor: FloatArray
    rows_per_sensor: np.ndarray
    corr: FloatArray
    taus: FloatArray
    amplitudes: FloatArray
    fast: FloatArray
    room_gains: FloatArray
    lag_var: FloatArray
    lag_shift: FloatArray
    response_var: FloatArray
    response_shift: FloatArray
    room_factors: slice
    """The room factors' columns of ``coef`` and ``cov`` (none without a room)."""
    path_lag: FloatArray
    """Per sensor, how far behind the room's latest level the fit's path into the machine puts it
    (°C; 0 without a room)."""
    slowest_lag: FloatArray
    """Per sensor, how far behind it the room through the slowest mode alone is (°C): the middle of
    the lags a machine's physics allows (:func:`_path_bound`)."""

    @cached_property
    def room_factor_var(self) -> FloatArray:
        """Per sensor, the part of its level's variance that the room factors carry: what is left
        of their prior where the readings cannot tell the room's path (a drift's: its course through
        a mode is that mode's shape and a level), ``C_lη·C_ηη⁻¹·C_ηl``."""
        count, factors = len(self.chi2_per_sensor), self.room_factors
        if factors.start == factors.stop:
            return np.zeros(count)
        across = self.cov[:count, factors]
        carried = np.einsum("sk,sk->s", across, np.linalg.solve(self.cov[factors, factors], across.T).T)
        out: FloatArray = np.clip(carried, 0.0, np.diag(self.cov)[:count])
        return out


def _tied_solve(
    bins: list[Binned],
    gains: FloatArray,
    noise: FloatArray,
    taus: FloatArray,
    tau_sd: FloatArray,
    own: np.ndarray,
    lag_share: float,
    known_lag: dict[int, tuple[FloatArray, FloatArray]],
    room_delay_min: float = 0.0,
) -> tuple[_Solved, _Solved] | None:
    """The joint penalised least squares, in two passes: the first at ``taus`` (which the test of
    the tie uses: there the time constants cannot bend to one sensor); the second with each
    slack's prior scaled by the first's ``z`` and each log time constant a parameter too,
    linearised about the first's amplitudes, its prior sd ``tau_sd``, and each sensor's own lag on
    the room (``lag_share``) counted in its level; the room's path delayed by ``room_delay_min``
    (:func:`_room_columns`)."""
    first = _penalised(bins, gains, noise, taus, np.ones(len(taus)), None, own, room_delay_min=room_delay_min)
    if first is None:
        return None
    scale = np.maximum(np.abs(first.z), 0.05)
    second = _penalised(
        bins,
        gains,
        noise,
        taus,
        scale,
        (first.amplitudes, tau_sd),
        own,
        lag_share=lag_share,
        known_lag=known_lag,
        room_delay_min=room_delay_min,
    )
    return None if second is None else (first, second)


def _profiled(
    bins: list[Binned],
    gains: FloatArray,
    noise: FloatArray,
    model: MachineModel,
    best: _Solved,
    levels: tuple[float, ...],
    own: np.ndarray,
    lag_share: float,
    known_lag: dict[int, tuple[FloatArray, FloatArray]],
    lag_sd: float | None,
) -> tuple[_Solved, FloatArray, dict[float, FloatArray], dict[float, FloatArray]]:
    """The fit and its intervals with each loose time constant (a box wider than ``LOOSE_BOX``,
    too wide to linearise) profiled: held in turn at points across its box, the interval the hull
    of those of every point whose χ² is within the decision's threshold of the best. The room's
    path is profiled too (:data:`ROOM_PATH_DELAYS`), in the hull but never the point: the model's
    modes are the path the answer states. The intervals twice: as the fit states them
    (:func:`_interval`), and with the room's path bounded by the physics (:func:`_path_bound`;
    ``lag_sd`` None: not bounded, the reference run itself)."""
    taus, tau_sd = _centres(model)
    loose = [k for k, box in enumerate(model.box) if box > LOOSE_BOX]
    candidates = [best]
    for k in loose:
        for f in PROFILE_POINTS:
            moved = taus.copy()
            moved[k] *= (1.0 + model.box[k]) ** f
            solved = _tied_solve(bins, gains, noise, moved, tau_sd, own, lag_share, known_lag)
            if solved is not None:
                candidates.append(solved[1])
    stated = len(candidates)
    # a model of one mode has no freedom in the room's path (its room factor scales that mode's);
    # with more, the factors mix the modes into a later path or an earlier one
    if len(taus) == 1 and any(b.room_C is not None for b in bins):
        for share in ROOM_PATH_DELAYS:
            solved = _tied_solve(bins, gains, noise, taus, tau_sd, own, lag_share, known_lag, share * float(taus.max()))
            if solved is not None:
                candidates.append(solved[1])
    chi2 = np.array([c.chi2_per_sensor.sum() / max(float(np.max(c.corr)), 1.0) for c in candidates])
    point = candidates[int(np.argmin(chi2[:stated]))]
    steady = point.coef[: len(bins)]
    best = chi2[:stated].min()
    within = {
        lv: [c for i, c in enumerate(candidates) if i >= stated or chi2[i] - best <= chdtri(1, 1.0 - lv)]
        for lv in levels
    }
    stated_half = _hull(steady, within, lambda c: _interval(bins, c, levels)[1])
    if lag_sd is None:
        return point, steady, stated_half, {lv: np.full(len(bins), np.inf) for lv in levels}
    return point, steady, stated_half, _hull(steady, within, lambda c: _path_bound(bins, c, levels, lag_sd))


def _hull(
    steady: FloatArray, within: dict[float, list[_Solved]], width: Callable[[_Solved], dict[float, FloatArray]]
) -> dict[float, FloatArray]:
    """Per level, the half-width about ``steady`` that holds the interval (``width``) of every fit
    within that level's threshold."""
    out = {}
    widths: dict[int, dict[float, FloatArray]] = {}
    for lv, fits in within.items():
        low, high = steady.copy(), steady.copy()
        for c in fits:
            if id(c) not in widths:
                widths[id(c)] = width(c)
            centre, half = c.coef[: len(steady)], widths[id(c)][lv]
            low, high = np.minimum(low, centre - half), np.maximum(high, centre + half)
        out[lv] = np.maximum(steady - low, high - steady)
    return out


def _centres(model: MachineModel) -> tuple[FloatArray, FloatArray]:
    """The model's time constants and each log time constant's prior sd for the linearised fit
    (a loose one held: it is profiled instead)."""
    box = np.array(model.box)
    sd = np.where(box > LOOSE_BOX, 1e-6, np.log1p(box) / TAU_BOX_SDS)
    return np.array(model.time_constants_min), sd


def _penalised(
    bins: list[Binned],
    gains: FloatArray,
    noise: FloatArray,
    taus: FloatArray,
    z_scale: FloatArray,
    linearised: tuple[FloatArray, FloatArray] | None,
    own: np.ndarray,
    untied: int | None = None,
    lag_share: float = 0.0,
    known_lag: dict[int, tuple[FloatArray, FloatArray]] | None = None,
    room_delay_min: float = 0.0,
) -> _Solved | None:
    """Columns: per sensor its level and fast modes; per mode its amplitude ``z_k``; per sensor
    and mode a slack; per mode the room's factor ``η_k`` (with a room); with ``linearised``
    (the amplitudes (S, K) and each log time constant's prior sd), per mode its log time
    constant's change. Sensor ``untied`` (if given) has no prior on its slack: its amplitudes are
    its own; so has every sensor on the modes ``own`` marks (:func:`_own_amplitudes`). With
    ``lag_share``, each sensor's level carries its own lag on the room too (:func:`_lag_variance`);
    one whose room response is known (its lag's column and course in ``known_lag``) a lag beyond
    that response, at :data:`ROOM_RESPONSE_LAG_SHARE` of the share, and an error in the course's
    scale, at :data:`ROOM_RESPONSE_SHARE`."""
    S, K = gains.shape
    F = len(FAST_TIME_CONSTANTS_MIN)
    with_room = any(b.room_C is not None for b in bins)
    i_fast, i_z = S, S + S * F
    i_d = i_z + K
    i_eta = i_d + S * K
    i_tau = i_eta + (K if with_room else 0)
    n_col = i_tau + (K if linearised is not None else 0)
    blocks, targets = [], []
    lag_columns: dict[int, tuple[FloatArray, float]] = {}
    response_columns: dict[int, tuple[FloatArray, float]] = {}
    latest_path = np.zeros((S, K))
    known_path = np.zeros(S)
    slowest_lag = np.zeros(S)
    for s, b in enumerate(bins):
        u = b.time_min
        X = np.zeros((len(u), n_col))
        X[:, s] = 1.0
        X[:, i_fast + s * F : i_fast + (s + 1) * F] = _exp_columns(u, np.array(FAST_TIME_CONSTANTS_MIN))
        e = _exp_columns(u, taus)
        X[:, i_z : i_z + K] = -gains[s][None, :] * e
        X[:, i_d + s * K : i_d + (s + 1) * K] = -e
        w = np.sqrt(b.count) / noise[s]
        if b.room_C is not None:
            room = _room_columns(b, taus, room_delay_min)
            X[:, i_eta : i_eta + K] = room * gains[s][None, :]
            latest_path[s] = -room[-1] * gains[s]
            undelayed = room if room_delay_min == 0 else _room_columns(b, taus)
            slowest_lag[s] = -float(undelayed[-1, int(np.argmax(taus))])
            if lag_share > 0:
                lag_columns[s] = (room[:, int(np.argmax(taus))] * w, lag_share)
        elif lag_share > 0 and known_lag and s in known_lag:
            lag_columns[s] = (known_lag[s][0] * w, ROOM_RESPONSE_LAG_SHARE * lag_share)
            response_columns[s] = (known_lag[s][1] * w, ROOM_RESPONSE_SHARE)
            known_path[s] = -float(known_lag[s][1][-1])
            slowest_lag[s] = -float(known_lag[s][0][-1])
        if linearised is not None:
            # d/d(log τ) of −a·e^(−u/τ); the room's lags move less and are left at the model's τ
            X[:, i_tau : i_tau + K] = -linearised[0][s][None, :] * e * (u[:, None] / taus[None, :])
        blocks.append(X * w[:, None])
        targets.append(_target(b) * w)
    slack_sd = TIE_SLACK * np.maximum(np.abs(gains) * z_scale[None, :], 1e-3)
    prior_cols = [i_d + s * K + k for s in range(S) for k in range(K) if s != untied and not own[k]]
    prior_sd = [slack_sd[s, k] for s in range(S) for k in range(K) if s != untied and not own[k]]
    prior_mean = [0.0] * len(prior_cols)
    # an untied mode's slacks are its amplitudes; its z, left with nothing to set it, is held at one
    prior_cols += [i_z + k for k in range(K) if own[k]]
    prior_sd += [1.0] * int(own.sum())
    prior_mean += [1.0] * int(own.sum())
    if with_room:
        mean, sd = _room_prior(gains)
        prior_cols += list(range(i_eta, i_eta + K))
        prior_sd += list(sd)
        prior_mean += list(mean)
    if linearised is not None:
        prior_cols += list(range(i_tau, i_tau + K))
        prior_sd += list(linearised[1])
        prior_mean += [0.0] * K
    P = np.zeros((len(prior_cols), n_col))
    P[np.arange(len(prior_cols)), prior_cols] = 1.0 / np.array(prior_sd)
    X = np.vstack([*blocks, P])
    y = np.concatenate([*targets, np.array(prior_mean) / np.array(prior_sd)])
    try:
        coef, cov = _least_squares(X, y)
    except np.linalg.LinAlgError:
        return None
    slack_chi2 = (((coef[i_d : i_d + S * K].reshape(S, K) / slack_sd) ** 2) * ~own[None, :]).sum(axis=1)
    if untied is not None:
        slack_chi2[untied] = 0.0
    chi2 = np.empty(S)
    corr = np.empty(S)
    for s, (block, target) in enumerate(zip(blocks, targets, strict=True)):
        r = target - block @ coef
        chi2[s] = float(r @ r) + slack_chi2[s]
        corr[s] = correlation_factor(r)
    z = coef[i_z : i_z + K]
    moved = taus * np.exp(coef[i_tau : i_tau + K]) if linearised is not None else taus
    eta = coef[i_eta : i_eta + K] if with_room else np.zeros(K)
    return _Solved(
        coef,
        cov,
        z,
        chi2,
        np.array([len(b) for b in bins]),
        corr,
        moved,
        gains * z[None, :] + coef[i_d : i_d + S * K].reshape(S, K),
        coef[i_fast : i_fast + S * F].reshape(S, F),
        gains * eta[None, :],
        *_lag_variance(blocks, targets, coef, lag_columns, cov, S),
        *_lag_variance(blocks, targets, coef, response_columns, cov, S),
        slice(i_eta, i_tau),
        known_path + latest_path @ eta,
        slowest_lag,
    )


def _lag_variance(
    blocks: list[FloatArray],
    targets: list[FloatArray],
    coef: FloatArray,
    columns: dict[int, tuple[FloatArray, float]],
    cov: FloatArray,
    count: int,
) -> tuple[FloatArray, FloatArray]:
    """Per sensor, the variance its level would gain from one more column of its own (weighted as
    its block), such as the room's course through the slowest mode less the room, with its
    coefficient's prior sd ``share`` (a lag behind a ramp of ``share`` times the rate times the
    slowest time constant), and the shift of the level that column's fit would make. A drift's lag
    cannot be told from a lower T∞ and adds its whole prior; a daily cycle's shows in the readings
    and adds less. The
    level itself stays where the fit puts it: the column's own estimate takes up misfit that is not
    the room's. One update of rank one per sensor: ``v = C·Xᵀc``, ``d = cᵀc + 1/share² − cᵀX·v``;
    the level's variance grows by ``v_s²/d``, and it would move by ``−v_s·cᵀr/d`` (``r``: the
    sensor's weighted residuals)."""
    out = np.zeros(count)
    shift = np.zeros(count)
    for s, (column, share) in columns.items():
        b = blocks[s].T @ column
        v = cov @ b
        d = float(column @ column) + share**-2 - float(b @ v)
        with np.errstate(over="ignore"):  # a column the others nearly make leaves the level unbounded: inf
            out[s] = v[s] ** 2 / max(d, 1e-300)
            shift[s] = -v[s] * float(column @ (targets[s] - blocks[s] @ coef)) / max(d, 1e-300)
    return out, shift


def _room_lag_sd(time_min: FloatArray, room_C: FloatArray | None, slowest_min: float) -> float:
    """How far a moving room's lag may be off (one sd, °C): the room's rate over the last
    ``slowest_min`` (or the last hour, the faster) times ``slowest_min``. A machine follows a
    drifting or cycling room behind it by the rate times an effective time constant that depends
    on the room's path into the machine, which a model of fewer modes than the machine gets wrong
    (a pair of slow modes of 143 and 159 min, learnt as one of 147, put a 0.17 °C/h drift's lag at
    half its size, and T∞ 0.4 °C low)."""
    if room_C is None:
        return 0.0
    t = np.asarray(time_min, float)
    room = np.asarray(room_C, float)
    rates = []
    for span in (slowest_min, 60.0):
        recent = (t >= t[-1] - span) & np.isfinite(room)
        if np.count_nonzero(recent) >= 3 and np.ptp(t[recent]) > 0:
            rates.append(abs(float(np.polyfit(t[recent], room[recent], 1)[0])))
    return ROOM_LAG_SHARE * max(rates, default=0.0) * slowest_min


def _room_prior(gains: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The prior of each mode's room factor ``η``: centred on the room's static gain of one at every
    sensor (``Σ_k g_sk·η_k = 1``, in least squares), not on a machine the room does not reach. A
    room that drifts or cycles keeps a machine behind it by about its rate times the time
    constants; the readings alone cannot tell that lag from a lower T∞ (both shift every level),
    and a prior at zero read a lag of 0.2-0.4 °C as a lower T∞, confidently."""
    mean = np.asarray(np.linalg.lstsq(gains, np.ones(len(gains)), rcond=None)[0], dtype=float)
    scale = np.maximum(np.max(np.abs(gains), axis=0), 1e-3)
    sd: FloatArray = ROOM_PRIOR_SHARE * np.abs(mean) + ROOM_PRIOR_GAIN / scale
    return mean, sd


def _own_amplitudes(taus: FloatArray) -> np.ndarray:
    """The shared modes a test may untie where sensors reject the tie of all: those faster
    than :data:`OWN_AMPLITUDE_SHARE` of the slowest. A reference run pins a fast pair of modes'
    shapes poorly (a column's 16- and 10-min amplitudes learnt as -0.41 and +0.33 °C against a true
    0.01-0.03), and at another heat split the pair no longer cancels: a new user's test of the same
    machine had most sensors reject the tie, and the reference was dropped. A fast mode's amplitude
    is the test's own readings' to say, long before the slow ones that set T∞."""
    own: np.ndarray = np.asarray(taus) < OWN_AMPLITUDE_SHARE * float(np.max(taus))
    return own


def _least_squares(X: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
    """The minimum-norm solution and the full covariance (X'X)⁻¹, from the normal equations with
    the columns scaled (the design has many rows and few columns). Not a pseudo-inverse: a
    direction the readings do not determine (two slow modes that cancel over the readings so far)
    must leave every coefficient on it with a huge variance, where a pseudo-inverse drops it and
    reports the coefficients as known."""
    scale = np.linalg.norm(X, axis=0)
    scale[scale == 0] = 1.0
    Xs = X / scale
    eigenvalues, vectors = np.linalg.eigh(Xs.T @ Xs)
    floor = max(float(eigenvalues.max()), 1e-300) * 1e-28
    kept = eigenvalues > floor * 1e4
    projected = vectors.T @ (Xs.T @ y)
    coef = (vectors @ np.where(kept, projected / np.maximum(eigenvalues, floor), 0.0)) / scale
    cov = (vectors / np.maximum(eigenvalues, floor)) @ vectors.T / np.outer(scale, scale)
    return coef, cov


def _excess(
    bins: list[Binned], gains: FloatArray, noise: FloatArray, taus: FloatArray, tied: _Solved, own: np.ndarray
) -> FloatArray:
    """Per sensor, how far its readings reject the tie: the whole fit's χ² (slack priors included)
    less the same with that sensor's amplitudes its own, over its residuals' correlation factor
    (χ² with K degrees of freedom where the tie holds). The whole fit's, not the sensor's: a
    sensor far off pulls the shared amplitudes, and the misfit shows in the others."""
    total = float(tied.chi2_per_sensor.sum())
    out = np.zeros(len(bins))
    for s in range(len(bins)):
        free = _penalised(bins, gains, noise, taus, np.maximum(np.abs(tied.z), 0.05), None, own, untied=s)
        if free is not None:
            out[s] = (total - float(free.chi2_per_sensor.sum())) / tied.corr[s]
    return out


def _level_sds(bins: list[Binned], solved: _Solved) -> tuple[FloatArray, FloatArray]:
    """Each sensor's level's sd in two parts: the heat's and the room's path's.

    Each is the covariance's, scaled by the sensor's χ² per degree of freedom where above one and
    by its residuals' correlation factor. The heat's part, set by the readings, is widened for the
    model's own error (:data:`MODEL_ERROR_FACTOR`) and kept above the room's level error
    (:data:`~mtident.thermal.readings.ROOM_LEVEL_FLOOR_C`). The path's part is the room factors'
    (:attr:`_Solved.room_factor_var`), widened likewise in a model of several modes, whose factors
    are the only freedom the path has and off as its heat is, and not in a model of one, whose hull
    holds later paths too (:data:`ROOM_PATH_DELAYS`); and the room's lag, a prior's, not the
    readings'."""
    S = len(bins)
    dof_scale = np.maximum(1.0, solved.chi2_per_sensor / np.maximum(solved.rows_per_sensor - 3, 1)) * solved.corr
    factors = solved.room_factor_var
    readings = np.clip(np.diag(solved.cov)[:S] - factors, 0, None) * dof_scale
    heat = np.hypot(MODEL_ERROR_FACTOR * np.sqrt(readings), ROOM_LEVEL_FLOOR_C)
    widened = 1.0 if len(solved.taus) == 1 else MODEL_ERROR_FACTOR**2
    return heat, np.sqrt(factors * dof_scale * widened + solved.lag_var)


def _interval(
    bins: list[Binned], solved: _Solved, levels: tuple[float, ...]
) -> tuple[FloatArray, dict[float, FloatArray]]:
    """Each sensor's level and its half-width per level (:func:`_level_sds`)."""
    heat, path = _level_sds(bins, solved)
    se = np.hypot(heat, path)
    return solved.coef[: len(bins)], {lv: ndtri(0.5 + lv / 2.0) * se for lv in levels}


def _path_bound(
    bins: list[Binned], solved: _Solved, levels: tuple[float, ...], lag_sd: float
) -> dict[float, FloatArray]:
    """Each sensor's half-width per level with the room's path bounded by the physics instead of by
    the fit's room factors and lags: a machine lags a drifting room by the rate times each sensor's
    mean delay ``C·(−A)⁻¹·1``, about one slowest time constant (``benchmarks/study_room_lag.py``),
    with an sd of :data:`ROOM_LAG_SHARE` of it. Where the readings cannot tell the path (a drift),
    the fit's room factors keep their whole prior and the lag's column its own besides, twice the
    same unknown; this holds the lag the physics allows, wherever the fit put the path (its
    distance from the slowest mode's lag is added whole), and no more. ``lag_sd``: the room's
    rate times the slowest time constant, times the share (:func:`_room_lag_sd`)."""
    heat, _ = _level_sds(bins, solved)
    off, sd = _path_lag_bound(solved, lag_sd)
    return {lv: np.hypot(ndtri(0.5 + lv / 2.0) * heat, off + ndtri(0.5 + lv / 2.0) * sd) for lv in levels}


def _path_lag_bound(solved: _Solved, lag_sd: float) -> tuple[FloatArray, FloatArray]:
    """Per sensor, how far the fit's lag behind the room is from the slowest mode's (°C), and the
    sd the physics allows about the latter (:func:`_path_bound`): ``lag_sd``, or the share of the
    slowest mode's lag where larger (a room that moved before the rate's span)."""
    return np.abs(solved.path_lag - solved.slowest_lag), np.maximum(lag_sd, ROOM_LAG_SHARE * np.abs(solved.slowest_lag))


# ----------------------------------------------------------------------------------------------
# From a log's readings, and into a sensor's answer


def noise_and_origin(time_min: FloatArray, values: FloatArray) -> tuple[FloatArray, float]:
    """Each sensor's noise per reading (at least its display step's q/√12) and where the warm-up
    begins: the earliest sensor's departure from its first level (the heat switches on once for
    the whole machine; a remote sensor departs later only through its modes)."""
    t = np.asarray(time_min, float)
    y = np.asarray(values, float)
    rounding = display_resolution(y)
    noise = np.maximum(noise_sigma(y, t), rounding / math.sqrt(12.0))
    lead = flat_lead(t, y, noise)
    first = int(np.min(lead)) if len(lead) else 0
    return noise, float(t[first]) if first < len(t) else float(t[0])


def machine_readings(
    sensors: tuple[str, ...] | list[str], time_min: FloatArray, values: FloatArray, room_C: FloatArray | None
) -> MachineReadings:
    """A log's readings for the machine model: their noise and origin estimated, the room smoothed
    as every per-sensor fit smooths it."""
    t = np.asarray(time_min, float)
    noise, origin = noise_and_origin(t, values)
    room = None if room_C is None else room_trend(t, np.asarray(room_C, float), ROOM_TREND_MIN)
    return MachineReadings(tuple(sensors), t, np.asarray(values, float), room, noise, origin)
