"""The search behind the model-robust fit of :mod:`mtident.thermal.modes`: one sensor's
least-squares problem, the grid of time constants and its leading models, their refinement,
and the hull's ends.

For given time constants the model is linear in T∞ and the amplitudes (variable projection),
so only the time constants are searched: on a log grid from the sampling interval to the
largest time constant, then locally (the compiled loops of
:mod:`mtident.thermal.modal_kernel`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from functools import lru_cache
from itertools import chain, combinations

import numpy as np
from scipy.optimize import minimize

from mtident._typing import FloatArray, IntArray
from mtident.thermal.modal_kernel import (
    APART_PENALTY,
    END_OBJECTIVE,
    RSS_OBJECTIVE,
    end_values,
    lag_rows,
    leading_rows,
    objective_and_gradient,
    refine_log_tau,
    solve_selected,
)
from mtident.thermal.modal_types import Binned, IntervalEnd, Mode, ModeFamily

# Two modes closer than this are one to the fit: nearly alike columns with large amplitudes of
# opposite sign fit anything, and the hull then grows with the search grid's resolution.
MIN_MODE_RATIO = 1.5
_LOG_MODE_RATIO = float(np.log(MIN_MODE_RATIO))
# prior standard deviation of a room gain gₖ (the sum of the gains of a passive structure is 1)
ROOM_GAIN_SD = 2.0
# a tiny ridge on every normalised column, so that a degenerate set of modes (three slow ones
# on a short record) gives a huge interval instead of a singular matrix
_JITTER = 1e-11
# Each amplitude has a weak prior of this many times the readings' spread: three slow modes of
# ±1000 °C cancelling one another fit any short record and are no machine.
AMPLITUDE_SD_FACTOR = 4.0
_FASTEST_MIN = 0.05
_GRID_POINTS = 40
_MAX_GRID_RATIO = 1.25
_CANDIDATES = 3
# The hull's ends: the grid's leading models of this many basins, each moved by a lattice search,
# then the best few polished by L-BFGS-B (a thin ridge of slow modes with large amplitudes of
# opposite sign sets an end, and the grid's few leading models all lie in one basin; a model with
# a mode at the largest time constant can rank below three others after the lattice search and
# still reach furthest once polished)
_END_STARTS = 30
_POLISHED = 6
# Within a reference's boxes fewer basins, but not one: free fast modes between and below the
# boxes make several, and the hull's end often lies in another than the best fit's (the search
# compared with one from many more starts is in the documentation's measured results)
_END_STARTS_REFERENCE = 10
_POLISHED_REFERENCE = 6
# a refinement's iterations and evaluations: the few that wander along a ridge's edge end here
_MAXITER = 100
_MAXFUN = 300
_LATTICE_ROUNDS = 4
# the leading models are looked for among this many lowest first
_LEADING_SCAN = 2048
_MAX_CORRELATION_FACTOR = 25.0


# ---------------------------------------------------------------------------------------------
# One sensor's least-squares problem


@dataclass(frozen=True)
class Problem:
    """What every fit of one sensor shares: the bins, where the modes begin, the centring of the
    readings, the priors (as penalties in units of the noise) and the search's bounds."""

    binned: Binned
    origin: float
    centre: float
    sigma2: float  # the noise variance the penalties are counted in
    amplitude_sd: float
    tau_bounds: tuple[float, float]
    family: ModeFamily

    @property
    def rising_slack_C(self) -> float:
        """How far a mode may fall and still count as rising (°C): a logged room's range over the
        log. A room that moved before the log left the machine off its equilibrium with the
        room's first level, the start the room's columns assume, and that history decays through
        the modes with either sign."""
        room = self.binned.room_C
        return _RISING_SLACK_C + (0.0 if room is None else float(np.ptp(room)))

    @property
    def with_room(self) -> bool:
        return self.binned.room_C is not None

    def target(self) -> FloatArray:
        b = self.binned
        return (b.value_C if b.room_C is None else b.value_C - b.room_C) - self.centre

    def kernel_inputs(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]:
        """The arrays :func:`~mtident.thermal.modal_kernel.fit_one` takes (no room: an empty one)."""
        b = self.binned
        room = np.empty(0) if b.room_C is None else np.ascontiguousarray(b.room_C, dtype=float)
        return b.time_min - self.origin, b.time_min, b.count, self.target(), room

    def penalty(self, k: int) -> FloatArray:
        """Per column, the prior's weight: nothing on T∞, a weak bound on each amplitude and on
        each room gain.

        Parameters
        ----------
        k : int
            Number of modes of the models.

        Returns
        -------
        ndarray, shape (p,)
            The diagonal added to XᵀWX, one per design column (p = 1 + k, + k with a room): 0 for T∞,
            σ² over the amplitude's prior variance for each amplitude, σ² over the room gain's for each gain.
        """
        room = [self.sigma2 / ROOM_GAIN_SD**2] * k if self.with_room else []
        return np.array([0.0] + [self.sigma2 / self.amplitude_sd**2] * k + room)

    def starts(self) -> int:
        """How many of the grid's leading models each refinement starts from: a reference's small
        boxes hold one optimum, the whole range of time constants several."""
        return _CANDIDATES if self.family.reference_min is None else 1

    def end_starts(self) -> int:
        """How many models of different basins each end of the hull starts from: an end often lies
        on a thin ridge of slow modes with large amplitudes of opposite sign, which the grid's
        leading few models, all in one basin, miss."""
        return _END_STARTS if self.family.reference_min is None else _END_STARTS_REFERENCE

    def polished(self) -> int:
        """How many of the lattice search's best models each end polishes by L-BFGS-B."""
        return _POLISHED if self.family.reference_min is None else _POLISHED_REFERENCE

    def basin_log(self) -> float:
        """Models closer than this in every log time constant are taken as of one basin: two
        steps of the free grid, or half a step within a reference's boxes (a box of ±10 % spans
        less than two steps, so a wider basin left the starts no choice in them, and an end
        reached along one box's edge was missed)."""
        answer: float = (2.0 if self.family.reference_min is None else 0.5) * np.log(_MAX_GRID_RATIO)
        return answer

    def bounds(self, k: int) -> FloatArray:
        """The search's bounds on the time constants of a model of ``k`` modes.

        Parameters
        ----------
        k : int
            Number of modes of the model; with a reference, those beyond its boxes are free fast modes.

        Returns
        -------
        ndarray, shape (k, 2)
            Per mode, the lowest and highest time constant (min): the problem's range, or with a
            reference its boxes, then the free modes below the slowest box.
        """
        if self.family.reference_min is not None:
            return _reference_bounds(self.family, self.tau_bounds[0], k - len(self.family.reference_min))
        return np.tile(self.tau_bounds, (k, 1))


def design_columns(problem: Problem, tau: FloatArray) -> FloatArray:
    """Design matrices of a batch of models: the constant, each mode's e^(−t/τ), then with a room
    each mode's lag of the room less the room.

    Parameters
    ----------
    problem : Problem
    tau : ndarray, shape (T, k)
        Time constants of T models of k modes (min).

    Returns
    -------
    ndarray, shape (T, B, p)
        Per model, one row per bin and p = 1 + k (+ k with a room) columns.
    """
    b = problem.binned
    u = b.time_min - problem.origin
    cols = [np.ones(tau.shape[:1] + u.shape)]
    cols.extend(np.exp(-u / tau[:, k, None]) for k in range(tau.shape[1]))
    if b.room_C is not None:
        cols.extend(room_lag(b.room_C, b.time_min, tau[:, k]) - b.room_C for k in range(tau.shape[1]))
    return np.stack(cols, axis=-1)


def room_lag(room: FloatArray, time_min: FloatArray, tau: FloatArray) -> FloatArray:
    """A first-order lag of each time constant applied to a room taken as piecewise linear between
    the bins, from a machine at the room's first level (compiled: the lags of every model a
    search tries cost most of a check with a room sensor where the interpreter runs the loop).

    Parameters
    ----------
    room : ndarray, shape (B,)
        The room at each bin.
    time_min : ndarray, shape (B,)
        The bins' times (min).
    tau : ndarray, shape (T,)
        The time constants (min).

    Returns
    -------
    ndarray, shape (T, B)
    """
    return lag_rows(
        np.ascontiguousarray(room, dtype=float),
        np.ascontiguousarray(time_min, dtype=float),
        np.ascontiguousarray(tau, dtype=float).reshape(-1),
    )


@dataclass(frozen=True)
class Fits:
    """Penalised least-squares fits of a batch of T models with k modes each."""

    tau: FloatArray  # (T, k) time constants
    rss: FloatArray  # (T,) weighted residuals' sum of squares plus the priors' penalty
    steady: FloatArray  # (T,) T∞ (less the problem's centring)
    var_steady: FloatArray  # (T,) [(XᵀWX + P)⁻¹]₀₀
    direction: FloatArray  # (T, p) (XᵀWX + P)⁻¹e₀: how the parameters follow T∞ along the profile
    theta: FloatArray  # (T, p)

    def take(self, i: int) -> Fits:
        """The i-th model alone.

        Parameters
        ----------
        i : int
            Index of the model in the batch (0 to T − 1).

        Returns
        -------
        Fits
            A batch of that one model (T = 1).
        """
        s = slice(i, i + 1)
        return Fits(self.tau[s], self.rss[s], self.steady[s], self.var_steady[s], self.direction[s], self.theta[s])

    @property
    def n_params(self) -> int:
        answer: int = self.theta.shape[1] + self.tau.shape[1]
        return answer


def _solve(
    gram: FloatArray, rhs: FloatArray, yy: float, penalty: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Batched penalised normal equations, solved in normalised form: rss, θ, [G⁻¹]₀₀, G⁻¹e₀."""
    gram = gram + np.diag(penalty)
    scale = np.sqrt(np.maximum(np.diagonal(gram, axis1=-2, axis2=-1), 1e-300))
    outer = scale[..., :, None] * scale[..., None, :]
    # only θ and G⁻¹'s first column are needed: one solve with two right-hand sides
    first = np.zeros(rhs.shape)
    first[..., 0] = 1.0 / scale[..., 0]
    solved = (
        np.linalg.solve(gram / outer + _JITTER * np.eye(gram.shape[-1]), np.stack([rhs / scale, first], axis=-1))
        / scale[..., :, None]
    )
    theta, column = solved[..., 0], solved[..., 1]
    rss = yy - np.sum(rhs * theta, axis=-1)
    return rss, theta, column[..., 0], column


def _fit(problem: Problem, tau: FloatArray) -> Fits:
    """Fits of a batch of models (T, k) from their design matrices, the residuals summed
    directly (the normal equations lose digits where modes are nearly alike)."""
    X = design_columns(problem, tau)
    w = problem.binned.count
    y = problem.target()
    penalty = problem.penalty(tau.shape[1])
    Xw = X * w[:, None]
    gram = np.swapaxes(Xw, 1, 2) @ X
    rhs = np.swapaxes(Xw, 1, 2) @ y
    _, theta, var0, direction = _solve(gram, rhs, float(np.sum(w * y * y)), penalty)
    resid = y - (X @ theta[:, :, None])[..., 0]
    rss = (resid**2) @ w + (theta**2) @ penalty
    return Fits(tau, rss, theta[:, 0], var0, direction, theta)


# ---------------------------------------------------------------------------------------------
# The global search: every set of grid time constants at once, from one Gram matrix


@lru_cache(maxsize=64)
def _grid_tuples(m: int, k: int, apart: int) -> IntArray:
    """Indices (T, k) of k grid time constants, increasing, at least ``apart`` steps apart, in
    lexicographic order: the combinations of a grid shorter by the steps the gaps take up, each
    index moved on by the gaps before it (filtering every combination costs a second of a check
    on a fine grid)."""
    gaps = (k - 1) * (max(apart, 1) - 1)
    if m - gaps < k:
        return np.empty((0, k), dtype=int)
    flat = np.fromiter(chain.from_iterable(combinations(range(m - gaps), k)), dtype=int)
    return flat.reshape(-1, k) + np.arange(k) * (max(apart, 1) - 1)


def _grid_taus(problem: Problem) -> FloatArray:
    lo, hi = problem.tau_bounds
    n = max(_GRID_POINTS, int(np.ceil(np.log(hi / lo) / np.log(_MAX_GRID_RATIO))) + 1)
    return np.geomspace(lo, hi, n)


def _gram_fits(problem: Problem, tau: FloatArray, index_sets: list[IntArray]) -> list[Fits]:
    """Fits of models whose time constants are taken from sets of candidates: ``tau`` (S, m) holds
    S sets of m time constants, each of ``index_sets`` a batch (T, k) of indices into a set; the
    fits come per batch (S·T models, set by set), all from one Gram matrix per set of every column
    any of its models uses."""
    sets, m = tau.shape
    b = problem.binned
    u = b.time_min - problem.origin
    basis = [np.ones((sets, len(b), 1)), np.exp(-u[None, :, None] / tau[:, None, :])]
    if b.room_C is not None:
        lags = room_lag(b.room_C, b.time_min, tau.reshape(-1)) - b.room_C
        basis.append(np.swapaxes(lags.reshape(sets, m, len(b)), 1, 2))
    X = np.concatenate(basis, axis=2)
    w, y = b.count, problem.target()
    Xw = X * w[None, :, None]
    gram, rhs, yy = np.swapaxes(Xw, 1, 2) @ X, np.swapaxes(Xw, 1, 2) @ y, float(np.sum(w * y * y))
    out = []
    for idx in index_sets:
        room = [1 + m + idx] if b.room_C is not None else []
        sel = np.concatenate([np.zeros((len(idx), 1), dtype=int), 1 + idx, *room], axis=1)
        rss, theta, direction = solve_selected(gram, rhs, sel, yy, problem.penalty(idx.shape[1]))
        out.append(Fits(tau[:, idx].reshape(-1, idx.shape[1]), rss, theta[:, 0], direction[:, 0], direction, theta))
    return out


def _grid_fits(problem: Problem) -> list[Fits]:
    """Every model with time constants on the search grid."""
    tau = _grid_taus(problem)
    apart = int(np.ceil(np.log(MIN_MODE_RATIO) / np.log(tau[1] / tau[0]) - 1e-9))
    return _gram_fits(
        problem, tau[None, :], [_grid_tuples(len(tau), k, apart) for k in range(1, problem.family.max_modes + 1)]
    )


def _reference_bounds(family: ModeFamily, fast_lo: float, extra: int) -> FloatArray:
    """Bounds (k, 2) of a reference family's time constants: the boxes, then ``extra`` free
    modes from ``fast_lo`` to the slowest box's lower end (a reference run can miss a mode faster
    than its slowest, between its others as well as below them)."""
    ref = np.asarray(family.reference_min, dtype=float)
    box = np.asarray(family.reference_box, dtype=float)
    bounds = np.column_stack([ref * (1 - box), ref * (1 + box)])
    ceiling = _free_ceiling(family)
    fast = np.tile([min(fast_lo, ceiling), ceiling], (extra, 1))
    return np.concatenate([bounds, fast]) if extra else bounds


def _free_ceiling(family: ModeFamily) -> float:
    """The slowest a reference family's free mode may be: the slowest box's lower end."""
    k = int(np.argmax(np.asarray(family.reference_min)))
    return float(family.reference_min[k] * (1 - family.reference_box[k]))  # type: ignore[index]


def _reference_grid_fits(problem: Problem, points: int = 7) -> list[Fits]:
    """Every model on grids over the reference's boxes, one batch per number of free modes, fitted
    from one Gram matrix: ``points`` time constants across each box (more across a box wider
    than the free grid's steps), and the free modes on a log grid below the slowest box."""
    family, fast_lo = problem.family, problem.tau_bounds[0]
    bounds = _reference_bounds(family, fast_lo, 0)
    # a wide box (a mode its run could not pin down) as finely as the free grid
    axes = [
        np.geomspace(lo, hi, max(points, int(np.ceil(np.log(hi / lo) / np.log(_MAX_GRID_RATIO))) + 1))
        for lo, hi in bounds
    ]
    sizes = [len(axis) for axis in axes]
    offsets = np.cumsum([0, *sizes])
    boxed = np.array(np.meshgrid(*[np.arange(size) + offsets[n] for n, size in enumerate(sizes)], indexing="ij"))
    boxed = boxed.reshape(len(axes), -1).T
    ceiling = _free_ceiling(family)
    fast = (
        np.geomspace(fast_lo, ceiling, max(2, int(np.ceil(np.log(ceiling / fast_lo) / np.log(_MAX_GRID_RATIO))) + 1))
        if ceiling > fast_lo
        else np.empty(0)
    )
    apart = max(1, int(np.ceil(np.log(MIN_MODE_RATIO) / np.log(_MAX_GRID_RATIO))))
    index_sets = [boxed]
    for extra in range(1, family.free_fast + 1):
        combos = _grid_tuples(len(fast), extra, apart)
        if not len(combos):
            break
        combos = combos + offsets[-1]
        index_sets.append(
            np.concatenate([np.repeat(boxed, len(combos), axis=0), np.tile(combos, (len(boxed), 1))], axis=1)
        )
    return _gram_fits(problem, np.concatenate([*axes, fast])[None, :], index_sets)


def grid_candidates(problem: Problem) -> list[Fits]:
    """Every model of the family's search grid, fitted.

    Parameters
    ----------
    problem : Problem

    Returns
    -------
    list of Fits
        One batch per number of modes (or per reference grid).
    """
    if problem.family.reference_min is not None:
        return _reference_grid_fits(problem)
    return _grid_fits(problem)


# ---------------------------------------------------------------------------------------------
# Local refinement: quasi-Newton in log τ from the grid's leading models

Objective = Callable[[Fits], FloatArray]


class _RssObjective:
    """The fit's residual sum of squares (with the priors' penalty)."""

    def __call__(self, fits: Fits) -> FloatArray:
        return fits.rss

    def compiled(self, log_mode_ratio: float) -> tuple[float, float, float, float, float]:
        """The objective as :func:`~mtident.thermal.modal_kernel.refine_log_tau` takes it."""
        return (float(RSS_OBJECTIVE), 0.0, 0.0, 1.0, log_mode_ratio)


class _EndObjective:
    """Minimised by the model that reaches furthest in T∞ towards ``sign`` within ``threshold``;
    beyond it, rising with the excess (``gap``: the threshold over the best fit), so that a
    search crossing the edge is led back. ``rising``: a model whose end has a mode that falls by
    more than ``slack`` (°C) is no model (infinite)."""

    def __init__(self, threshold: float, sign: float, gap: float, rising: bool = False, slack: float = 0.0) -> None:
        self.threshold, self.sign, self.gap, self.rising, self.slack = threshold, sign, gap, rising, slack

    def __call__(self, fits: Fits) -> FloatArray:
        values = end_values(fits.rss, fits.var_steady, fits.steady, self.threshold, self.sign, self.gap)
        if self.rising:
            values = np.where(rising_at_end(fits, self.threshold, self.sign, self.slack), values, np.inf)
        return values

    def compiled(self, log_mode_ratio: float) -> tuple[float, float, float, float, float]:
        """The objective as :func:`~mtident.thermal.modal_kernel.refine_log_tau` takes it."""
        return (float(END_OBJECTIVE), self.threshold, self.sign, self.gap, log_mode_ratio)


def _refine(problem: Problem, fits: Fits, i: int, objective: _RssObjective | _EndObjective) -> Fits:
    """Improve the i-th model's time constants in log τ within the family's bounds, minimising
    ``objective`` (finite everywhere) with its exact gradient; the best model found, alone. A
    profile's end lies on a thin ridge of the time constants where the data pin them down, which
    a search on a grid or along the axes misses.

    The best fit is searched by a compiled quasi-Newton method, with no interpreter between its
    steps; an end of the hull by L-BFGS-B over the compiled objective, because its line search
    follows the end objective's kinked ridge further than the compiled search does (the
    comparison is in the documentation's measured results, Speed)."""
    k = fits.tau.shape[1]
    bounds = np.log(problem.bounds(k))
    apart = (problem.family.reference_min is None or problem.family.free_fast > 0) and k > 1
    start = np.clip(np.log(fits.tau[i]), bounds[:, 0], bounds[:, 1])
    inputs, penalty = problem.kernel_inputs(), problem.penalty(k)
    compiled = objective.compiled(_LOG_MODE_RATIO if apart else 0.0)
    if isinstance(objective, _RssObjective):
        lower, upper = np.ascontiguousarray(bounds[:, 0]), np.ascontiguousarray(bounds[:, 1])
        found = refine_log_tau(inputs, start, lower, upper, penalty, compiled, _MAXITER, _MAXFUN)
    else:
        found = minimize(
            lambda phi: objective_and_gradient(inputs, phi, penalty, compiled),
            start,
            jac=True,
            method="L-BFGS-B",
            bounds=bounds,
            options={"maxiter": _MAXITER, "maxfun": _MAXFUN},
        ).x
    best = _fit(problem, np.exp(np.vstack([start, found])))
    values = objective(best) + (np.array([_apart_penalty(row) for row in np.log(best.tau)]) if apart else 0.0)
    return best.take(int(np.argmin(values)))


def _apart_penalty(log_tau: FloatArray) -> float:
    return float(APART_PENALTY * _closeness(log_tau[None, :])[0] ** 2)


def _closeness(log_tau: FloatArray) -> FloatArray:
    """How far (log) each row's closest two modes are inside ``MIN_MODE_RATIO`` of each other."""
    gaps = np.diff(np.sort(log_tau, axis=1), axis=1)
    return (
        np.maximum(np.log(MIN_MODE_RATIO) - gaps.min(axis=1, initial=np.inf), 0.0)
        if gaps.size
        else np.zeros(len(log_tau))
    )


def best_per_count(problem: Problem, candidates: list[Fits]) -> dict[int, Fits]:
    """Per number of modes, the best-fitting model, refined off the grid from the leading models
    of ``candidates``.

    Parameters
    ----------
    problem : Problem
    candidates : list of Fits
        The grid's models (:func:`grid_candidates`).

    Returns
    -------
    dict of int to Fits
        One model per number of modes.
    """
    best: dict[int, Fits] = {}
    for k in sorted({f.tau.shape[1] for f in candidates}):
        same = [f for f in candidates if f.tau.shape[1] == k]
        for fits, i in _leading(same, _RssObjective(), problem.starts()):
            refined = _refine(problem, fits, i, _RssObjective())
            if k not in best or refined.rss[0] < best[k].rss[0]:
                best[k] = refined
    return best


def refined_per_count(problem: Problem, per_count: dict[int, Fits]) -> dict[int, Fits]:
    """Each model of ``per_count`` (one per number of modes, its first) refined off the grid: a
    grid's best of few modes fits far worse than the same number of modes off the grid (the
    papers' first-order curve: one mode's grid best left 14 times the residuals of its refined
    fit), and the number of modes chosen by BIC among grid bests then takes a model of more modes
    that the readings do not need.

    Parameters
    ----------
    problem : Problem
    per_count : dict of int to Fits

    Returns
    -------
    dict of int to Fits
    """
    out = {}
    for k, fits in per_count.items():
        refined = _refine(problem, fits, 0, _RssObjective())
        out[k] = refined if float(refined.rss[0]) <= float(fits.rss[0]) else fits
    return out


def _leading(
    candidates: list[Fits], objective: Objective, count: int, apart_log: float = 0.0
) -> list[tuple[Fits, int]]:
    """The ``count`` models with the lowest finite ``objective`` among all the batches; with
    ``apart_log``, each of a different basin: a model whose log time constants all lie within
    ``apart_log`` of a model already taken (of as many modes) is passed over."""
    if not candidates:
        return []
    values = np.concatenate(
        [np.where(np.isfinite(v := np.asarray(objective(fits), dtype=float)), v, np.inf) for fits in candidates]
    )
    starts = np.cumsum([0] + [len(fits.tau) for fits in candidates])
    rows = _leading_rows(values, lambda order: _log_tau_of(candidates, starts, order), count, apart_log)
    batches = np.searchsorted(starts, rows, side="right") - 1
    return [(candidates[b], int(r - starts[b])) for b, r in zip(batches, rows, strict=True)]


def _log_tau_of(candidates: list[Fits], starts: IntArray, rows: IntArray) -> tuple[FloatArray, IntArray]:
    """The log time constants (padded with zeros to the widest batch's) and the number of modes
    of the given rows of the batches laid end to end: only the rows a scan reaches, because a
    grid's logarithms cost more than the scan."""
    batches = np.searchsorted(starts, rows, side="right") - 1
    log_tau = np.zeros((len(rows), max(fits.tau.shape[1] for fits in candidates)))
    modes = np.empty(len(rows), dtype=np.int64)
    for b in np.unique(batches):
        here = batches == b
        k = candidates[b].tau.shape[1]
        log_tau[here, :k] = np.log(candidates[b].tau[rows[here] - starts[b]])
        modes[here] = k
    return log_tau, modes


def _leading_rows(
    values: FloatArray,
    log_tau_of: Callable[[IntArray], tuple[FloatArray, IntArray]],
    count: int,
    apart_log: float,
) -> IntArray:
    """:func:`~mtident.thermal.modal_kernel.leading_rows` over the lowest rows only, more where
    those run out (sorting every row of a large grid would cost more than the scan)."""
    scanned = min(len(values), _LEADING_SCAN)
    while True:
        boundary = np.inf
        if scanned < len(values):
            lowest = np.argpartition(values, scanned - 1)[:scanned]
            order = lowest[np.lexsort((lowest, values[lowest]))]
            # rows tied with the last one taken in may have been left out before it
            boundary = float(values[order[-1]])
        else:
            order = np.argsort(values, kind="stable")
        log_tau, modes = log_tau_of(order)
        rows, exhausted = leading_rows(values, order, boundary, log_tau, modes, count, apart_log)
        if not exhausted or scanned == len(values):
            return rows
        scanned = min(len(values), 4 * scanned)


# ---------------------------------------------------------------------------------------------
# The profile hull


def profile_bounds(fits: Fits, threshold: float) -> tuple[FloatArray, FloatArray]:
    """Per model, the lowest and highest T∞ whose fit, the time constants held, stays within
    ``threshold``.

    Parameters
    ----------
    fits : Fits
    threshold : float
        The largest residual sum of squares allowed.

    Returns
    -------
    (ndarray, ndarray)
        The lowest and highest T∞ per model (centred; NaN where the model's best fit is above
        ``threshold``).
    """
    slack = threshold - fits.rss
    half = np.sqrt(np.where(slack >= 0, slack, np.nan) * np.maximum(fits.var_steady, 0.0))
    return fits.steady - half, fits.steady + half


# an amplitude this close to zero (°C) counts as rising: a mode a model holds at zero
_RISING_SLACK_C = 1e-9


def rising_at_end(fits: Fits, threshold: float, sign: float, slack: float = _RISING_SLACK_C) -> np.ndarray:
    """Per model, whether every mode rises (its amplitude, of e^(−t/τ), at most zero) at the end
    of its profile towards ``sign`` within ``threshold``. The furthest T∞ of models whose modes
    all rise is exactly the furthest such end over a family that holds each model's sub-models
    (with some amplitudes held at zero), as the grid's counts of modes do: where the constraint
    binds, the best model drops the modes it holds at zero.

    Parameters
    ----------
    fits : Fits
    threshold : float
        The largest residual sum of squares allowed.
    sign : float
        −1 for the low end, +1 for the high end.
    slack : float
        How far a mode may fall and still count (°C, :attr:`Problem.rising_slack_C`).

    Returns
    -------
    ndarray of bool, shape (T,)
    """
    k = fits.tau.shape[1]
    spare = np.maximum(threshold - fits.rss, 0.0)
    step = sign * np.sqrt(spare / np.maximum(fits.var_steady, 1e-300))
    amplitudes = fits.theta[:, 1 : 1 + k] + step[:, None] * fits.direction[:, 1 : 1 + k]
    rising: np.ndarray = np.all(amplitudes <= slack, axis=1)
    return rising


def rising_best(candidates: list[Fits], slack: float = _RISING_SLACK_C) -> Fits | None:
    """The best-fitting model whose modes all rise at its best fit (the least-squares fit with
    every amplitude at most zero, over a family that holds each model's sub-models), or None.

    Parameters
    ----------
    candidates : list of Fits
    slack : float
        How far a mode may fall and still count (°C).

    Returns
    -------
    Fits or None
    """
    best: Fits | None = None
    for fits in candidates:
        k = fits.tau.shape[1]
        rss = np.where(np.all(fits.theta[:, 1 : 1 + k] <= slack, axis=1), fits.rss, np.inf)
        if not len(rss) or not np.isfinite(rss).any():
            continue
        i = int(np.argmin(rss))
        if best is None or rss[i] < best.rss[0]:
            best = fits.take(i)
    return best


def grid_half_width(
    candidates: list[Fits], threshold: float, steady: float, rising: bool = False, slack: float = _RISING_SLACK_C
) -> float:
    """The hull's half-width over the models searched so far (the grid's and the best fits):
    never wider than the refined hull's.

    Parameters
    ----------
    candidates : list of Fits
    threshold : float
        The largest residual sum of squares allowed.
    steady : float
        The best model's T∞ (centred).
    rising : bool
        Only the ends whose modes all rise (:func:`rising_at_end`), within ``slack`` (°C).
    slack : float

    Returns
    -------
    float
        The larger distance from ``steady`` to an end (°C).
    """
    ends = [profile_bounds(f, threshold) for f in candidates]
    if rising:
        ends = [
            (
                np.where(rising_at_end(f, threshold, -1.0, slack), lo, np.nan),
                np.where(rising_at_end(f, threshold, 1.0, slack), hi, np.nan),
            )
            for f, (lo, hi) in zip(candidates, ends, strict=True)
        ]
    lo = min((float(np.nanmin(lo, initial=np.inf)) for lo, _ in ends), default=steady)
    hi = max((float(np.nanmax(hi, initial=-np.inf)) for _, hi in ends), default=steady)
    return max(steady - lo, hi - steady)


def hull_end(
    problem: Problem,
    candidates: list[Fits],
    threshold: float,
    sign: float,
    gap: float,
    fallback: Fits,
    refine: bool = True,
    seeds: list[Fits] | None = None,
    seeds_only: bool = False,
) -> Fits:
    """The model that sets one end of the hull: the grid's leading models of different basins,
    each improved by a local search on a shrinking lattice around it (all at once), then the
    best few refined by L-BFGS-B.

    Parameters
    ----------
    problem : Problem
    candidates : list of Fits
        The models searched so far.
    threshold : float
        The largest residual sum of squares allowed.
    sign : float
        −1 for the low end, +1 for the high end.
    gap : float
        ``threshold`` less the best fit's residual sum of squares.
    fallback : Fits
        The best fit, returned where no model found reaches further.
    refine : bool
        False: the furthest model of ``candidates`` as it is.
    seeds : list of Fits, optional
        Models refined besides the search's (the ends of a wider level's hull: the same ridges
        set both, and the search's few starts can miss the basin they lie in).
    seeds_only : bool
        Refine ``seeds`` alone, without a search of ``candidates``.

    Returns
    -------
    Fits
        One model.
    """
    objective = _EndObjective(threshold, sign, gap, problem.family.every_mode_rises, problem.rising_slack_C)
    # the furthest any model searched so far reaches within the threshold (the best fit's own
    # profile at least): a local search from there can wander just beyond the threshold and be
    # discarded, so the end found is never short of it
    best = _furthest_within([*candidates, fallback], objective, threshold)
    if not refine:
        return best
    polish = [(f, 0) for f in seeds or []]
    if not seeds_only:
        starts = _leading(candidates, objective, problem.end_starts(), problem.basin_log())
        improved = [
            _lattice_search(problem, [f.take(i) for f, i in starts if f.tau.shape[1] == k], objective)
            for k in {f.tau.shape[1] for f, _ in starts}
        ]
        polish += _leading(improved, objective, problem.polished(), problem.basin_log())
    best_value = float(objective(best)[0])
    for fits, i in polish:
        refined = _refine(problem, fits, i, objective)
        if refined.rss[0] > threshold or not np.isfinite(objective(refined)[0]):
            continue
        value = float(objective(refined)[0])
        if value < best_value:
            best, best_value = refined, value
    return best


def _furthest_within(candidates: list[Fits], objective: _EndObjective, threshold: float) -> Fits:
    """The model of ``candidates`` (the last one within ``threshold``) that reaches furthest
    towards the objective's end among those within ``threshold``."""
    best, best_value = candidates[-1].take(0), np.inf
    for fits in candidates:
        if not len(fits.rss):
            continue
        values = np.where(fits.rss <= threshold, objective(fits), np.inf)
        i = int(np.argmin(values))
        if values[i] < best_value:
            best, best_value = fits.take(i), float(values[i])
    return best


def _lattice_search(
    problem: Problem, starts: list[Fits], objective: _EndObjective, rounds: int = _LATTICE_ROUNDS
) -> Fits:
    """Each start (k modes each) moved to the best of the 3ᵏ points of a lattice around it in
    log τ, the lattice halved each round: a search with no gradient that crosses a thin ridge
    diagonally. Every start's lattice is fitted at once, from a Gram matrix of its 3k distinct
    time constants (the moved starts are fitted afresh from their residuals)."""
    k = starts[0].tau.shape[1]
    bounds = np.log(problem.bounds(k))
    phi = np.log(np.concatenate([f.tau for f in starts]))
    choice = np.array(np.meshgrid(*[[0, 1, 2]] * k, indexing="ij")).reshape(k, -1).T
    columns = choice + 3 * np.arange(k)  # (3ᵏ, k): which of the 3k time constants each point takes
    step = np.log(_MAX_GRID_RATIO)
    apart = (problem.family.reference_min is None or problem.family.free_fast > 0) and k > 1
    for _ in range(rounds):
        axes = np.clip(
            phi[:, :, None] + step * np.array([-1.0, 0.0, 1.0]), bounds[:, 0, None], bounds[:, 1, None]
        )  # (S, k, 3)
        (fits,) = _gram_fits(problem, np.exp(axes.reshape(len(phi), 3 * k)), [columns])
        values = objective(fits)
        if apart:
            values = values + APART_PENALTY * _closeness(np.log(fits.tau)) ** 2
        best = np.argmin(values.reshape(len(phi), -1), axis=1)
        phi = np.log(fits.tau.reshape(len(phi), -1, k)[np.arange(len(phi)), best])
        step /= 2.0
    return _fit(problem, np.exp(phi))


def interval_end(fits: Fits, threshold: float, sign: float, shift: float) -> IntervalEnd:
    """The model at its furthest T∞ towards ``sign``, with the amplitudes it takes there.

    Parameters
    ----------
    fits : Fits
        One model (:func:`hull_end`).
    threshold : float
        The largest residual sum of squares allowed.
    sign : float
        −1 for the low end, +1 for the high end.
    shift : float
        Added to T∞: the centring, and the room's last level.

    Returns
    -------
    IntervalEnd
    """
    slack = max(threshold - float(fits.rss[0]), 0.0)
    theta = fits.theta[0] + sign * np.sqrt(slack / max(float(fits.var_steady[0]), 1e-300)) * fits.direction[0]
    return IntervalEnd(float(theta[0]) + shift, modes_of(fits, theta))


def correlation_factor(resid: FloatArray) -> float:
    """The residuals' long-run variance over their variance (Bartlett window of the usual
    Newey-West width): how much their correlation (a misfit, a wandering room, rounding held
    for many readings) widens the variance of anything that varies slowly.

    Parameters
    ----------
    resid : ndarray, shape (B,)
        Weighted residuals, in time order.

    Returns
    -------
    float
        At least 1, at most ``_MAX_CORRELATION_FACTOR``.
    """
    n = len(resid)
    r = resid - resid.mean()
    var = float(np.dot(r, r))
    if n < 8 or var <= 0:
        return 1.0
    lags = max(1, int(np.ceil(4.0 * (n / 100.0) ** (2.0 / 9.0))))
    acf = np.array([np.dot(r[:-lag], r[lag:]) / var for lag in range(1, lags + 1)])
    weights = 1.0 - np.arange(1, lags + 1) / (lags + 1.0)
    return float(np.clip(1.0 + 2.0 * np.sum(weights * acf), 1.0, _MAX_CORRELATION_FACTOR))


def choose_count(best_per_count: dict[int, Fits], n: int) -> Fits:
    """The point estimate's model: the number of modes by BIC.

    Parameters
    ----------
    best_per_count : dict of int to Fits
        The best model per number of modes (:func:`best_per_count`).
    n : int
        The number of bins.

    Returns
    -------
    Fits
    """

    def bic(f: Fits) -> float:
        answer: float = n * np.log(max(float(f.rss[0]), 1e-300) / n) + f.n_params * np.log(n)
        return answer

    return min(best_per_count.values(), key=bic)


def modes_of(fits: Fits, theta: FloatArray | None = None) -> tuple[Mode, ...]:
    """The first model's modes.

    Parameters
    ----------
    fits : Fits
    theta : ndarray, optional
        Its coefficients (default: its best fit's): T∞, the amplitudes, the room gains.

    Returns
    -------
    tuple of Mode
    """
    th = fits.theta[0] if theta is None else theta
    return tuple(Mode(float(tau), float(a)) for tau, a in zip(fits.tau[0], th[1 : 1 + fits.tau.shape[1]], strict=True))


def weighted_residuals(problem: Problem, fits: Fits) -> FloatArray:
    """The first model's residuals per bin, each weighted by the square root of its count.

    Parameters
    ----------
    problem : Problem
    fits : Fits

    Returns
    -------
    ndarray, shape (B,)
    """
    X = design_columns(problem, fits.tau)[0]
    answer: FloatArray = (problem.target() - X @ fits.theta[0]) * np.sqrt(problem.binned.count)
    return answer


def make_problem(binned: Binned, noise_C: float, interval_min: float, family: ModeFamily) -> Problem:
    """One sensor's problem: where its modes begin, the centring, the priors and the bounds.

    Parameters
    ----------
    binned : Binned
    noise_C : float
        The readings' noise (°C per reading).
    interval_min : float
        The sampling interval: modes much faster are not searched.
    family : ModeFamily

    Returns
    -------
    Problem
    """
    y = binned.value_C if binned.room_C is None else binned.value_C - binned.room_C
    spread = max(float(np.ptp(binned.value_C)), 10.0 * noise_C)
    lo = max(0.5 * interval_min, _FASTEST_MIN)
    return Problem(
        binned=binned,
        origin=float(binned.time_min[0]),
        centre=float(np.average(y, weights=binned.count)),
        sigma2=max(noise_C, 1e-6) ** 2,
        amplitude_sd=AMPLITUDE_SD_FACTOR * spread,
        tau_bounds=(min(lo, family.max_time_constant_min), family.max_time_constant_min),
        family=family,
    )
