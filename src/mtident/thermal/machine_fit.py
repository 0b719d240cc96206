"""A test fitted with the machine model: every sensor together, each mode's amplitudes tied to the
reference run's proportions (:mod:`mtident.thermal.machine_model`), the room's path into the machine
learnt or fitted, and each sensor's T∞ with its interval.

The fit frees only what a test can change: one amplitude per mode for the whole machine (the power,
the heat split and a partly warm start), a slack of :data:`~mtident.thermal.machine_model.TIE_SLACK`
about each tied amplitude, the time constants within the reference's box, and the room's factors.
A sensor whose readings reject the tie is left to its own fit; where most do, the test does not
follow the model (``contradicted``). The intervals carry what the readings cannot tell: the model's
own error (:data:`MODEL_ERROR_FACTOR`), and a moving room's lag, bounded by the physics
(:func:`_path_bound`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace
from functools import cached_property
from typing import Any

import numpy as np
from scipy.special import chdtri, ndtri

from mtident._typing import FloatArray
from mtident.thermal.machine_model import (
    FAST_TIME_CONSTANTS_MIN,
    TAU_BOX_SDS,
    TIE_SLACK,
    MachineFit,
    MachineModel,
    MachineReadings,
    exp_columns,
    least_squares,
    rise_above_room,
    room_columns,
)
from mtident.thermal.modal_search import correlation_factor
from mtident.thermal.modal_types import Binned, Mode
from mtident.thermal.readings import ROOM_LEVEL_FLOOR_C
from mtident.thermal.robust import MISFIT_FACTOR

__all__ = ["fit_test"]

OWN_AMPLITUDE_SHARE = 0.1
"""Shared modes faster than this share of the slowest may be untied, each sensor's amplitude its
own, where sensors reject the tie of all (:func:`_own_amplitudes`)."""
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
        R = room_columns(b, taus)
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
        X[:, i_fast + s * F : i_fast + (s + 1) * F] = exp_columns(u, np.array(FAST_TIME_CONSTANTS_MIN))
        e = exp_columns(u, taus)
        X[:, i_z : i_z + K] = -gains[s][None, :] * e
        X[:, i_d + s * K : i_d + (s + 1) * K] = -e
        w = np.sqrt(b.count) / noise[s]
        if b.room_C is not None:
            room = room_columns(b, taus, room_delay_min)
            X[:, i_eta : i_eta + K] = room * gains[s][None, :]
            latest_path[s] = -room[-1] * gains[s]
            undelayed = room if room_delay_min == 0 else room_columns(b, taus)
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
        targets.append(rise_above_room(b) * w)
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
        coef, cov = least_squares(X, y)
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
