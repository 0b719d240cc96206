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
from dataclasses import dataclass, replace
from functools import cached_property

import numpy as np
from scipy import optimize
from scipy.special import chdtri

from mtident._threads import one_blas_thread
from mtident._typing import FloatArray
from mtident.thermal.lsq import flat_lead
from mtident.thermal.modal_search import correlation_factor, room_lag
from mtident.thermal.modal_types import Binned, Mode, bin_samples
from mtident.thermal.readings import ROOM_TREND_MIN, display_resolution, noise_sigma, room_trend

FAST_TIME_CONSTANTS_MIN = (0.7, 2.5)
"""Each sensor's own fast modes (free amplitudes): a sensor's lag, the start's details."""
TIE_SLACK = 0.15
"""Prior sd of a tied amplitude's departure from ``g_sk·z_k``, relative to it."""
TAU_BOX_MIN = 0.05
"""The smallest relative box searched around each of the reference's time constants."""
TAU_BOX_SDS = 3.0
ROOM_STATIC_SD = 0.05
"""The prior sd of a sensor's static gain on the room (one) in its learnt room gains."""
ROOM_SHOWN_C = 0.05
"""A reference run shows the room's path into the machine only where its room, through the slowest
mode, moved by at least this (°C)."""
ROOM_RESPONSE_LEARNT = 0.2
"""A sensor's room response is kept from the reference run where its lag behind a ramp
(``Σ_k h_sk·τ_k``) is known within this share of the slowest time constant (one sd)."""
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
        where the physics bounds it tighter, :func:`~mtident.thermal.machine_fit._path_bound`'s), 0 where none.
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


def exp_columns(u: FloatArray, taus: FloatArray) -> FloatArray:
    columns: FloatArray = np.exp(-u[:, None] / np.asarray(taus, dtype=float)[None, :])
    return columns


def room_columns(binned: Binned, taus: FloatArray, delay_min: float = 0.0) -> FloatArray:
    """The room through each mode, less the room; with ``delay_min``, that much later first (a room
    that reaches the sensors through a chain of bodies: many stages in series act as a delay)."""
    assert binned.room_C is not None
    room = binned.room_C
    if delay_min > 0:
        room = np.interp(binned.time_min - delay_min, binned.time_min, room)
    return (room_lag(room, binned.time_min, np.asarray(taus, dtype=float)) - binned.room_C).T


def rise_above_room(binned: Binned) -> FloatArray:
    return binned.value_C - (binned.room_C if binned.room_C is not None else 0.0)


# ----------------------------------------------------------------------------------------------
# Learning the model from a complete run


def _free_design(binned: Binned, taus: FloatArray) -> FloatArray:
    """One sensor's columns with its own amplitudes: [level, fast modes, −each mode, room gains]."""
    u = binned.time_min
    cols = [np.ones((len(u), 1)), exp_columns(u, np.array(FAST_TIME_CONSTANTS_MIN)), -exp_columns(u, taus)]
    if binned.room_C is not None:
        cols.append(room_columns(binned, taus))
    design: FloatArray = np.hstack(cols)
    return design


def _sensor_solve(binned: Binned, taus: FloatArray, noise: float) -> tuple[FloatArray, FloatArray]:
    """One sensor's free fit at shared ``taus``: its coefficients (:func:`_free_design`) and its
    weighted residuals."""
    X = _free_design(binned, taus)
    w = np.sqrt(binned.count) / noise
    coef = np.asarray(np.linalg.lstsq(X * w[:, None], rise_above_room(binned) * w, rcond=None)[0], dtype=float)
    resid: FloatArray = (rise_above_room(binned) - X @ coef) * w
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


def loose_slow(model: MachineModel) -> list[tuple[float, float]]:
    """The machine model's slow shared modes (at least :data:`FAST_SHARE` of the slowest) that the
    run pins down only within more than :data:`MAX_MACHINE_BOX`, as (time constant, box): a model
    with any is not kept.

    Parameters
    ----------
    model : MachineModel

    Returns
    -------
    list of (float, float)
    """
    slowest = max(model.time_constants_min)
    return [
        (tau, box)
        for tau, box in zip(model.time_constants_min, model.box, strict=True)
        if box > MAX_MACHINE_BOX and tau >= FAST_SHARE * slowest
    ]


def loose_slow_modes(model: MachineModel) -> list[str]:
    """:func:`loose_slow` in words ("239 min ±172%").

    Parameters
    ----------
    model : MachineModel

    Returns
    -------
    list of str
    """
    return [f"{tau:.3g} min ±{box:.0%}" for tau, box in loose_slow(model)]


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
        coef, full = least_squares(
            np.vstack([X * w[:, None], static]), np.append(rise_above_room(b) * w, 1 / ROOM_STATIC_SD)
        )
        resid = (rise_above_room(b) - X @ coef) * w
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


def least_squares(X: FloatArray, y: FloatArray) -> tuple[FloatArray, FloatArray]:
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
