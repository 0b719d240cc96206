"""Model-robust steady state: a warm-up as a sum of exponential modes.

A sensor on a machine heated by a constant power in a room is a linear system: its
temperature is T(t) = T∞ + Σₖ aₖ·e^(−t/τₖ), one term per thermal mode (heat
capacity) of the structure, with a lagged sensor or a distant part giving modes of
either sign. The papers' first-order model keeps one mode; a machine has several, and
a slow one not yet visible in the data moves T∞ far from what one mode predicts.

This module fits up to four modes, their time constants at least a factor
``MIN_MODE_RATIO`` apart, to all the data so far, by variable projection: for given time constants the
model is linear in T∞ and the amplitudes, so only the time constants are searched,
first on a log grid from the sampling interval to the largest time constant the
machine may have, then locally. The interval for T∞ is the profile-likelihood hull:
every model of the family, with every time constant up to ``max_time_constant_min``,
whose fit is within the chosen χ² quantile of the best, contributes the T∞ values it
allows. A slow mode that the data cannot yet exclude therefore widens the interval
until they can. With a reference run (:mod:`mtident.thermal.reference`) the time
constants are searched only within boxes around the reference's, which is what lets a
test stop early.

With a room sensor the room is an input of every mode's heat balance: the sensor less
the room follows T∞ − T_room + Σ aₖe^(−t/τₖ) + Σ gₖ(Fₖ[room] − room), where Fₖ is the
first-order lag of mode k (a steady room gives the sensor the room's level, whatever
the gains gₖ, which are free).

References
----------
Golub, G. and Pereyra, V. (2003). Separable nonlinear least squares: the variable
projection method and its applications. Inverse Problems 19(2), R1-R26.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from functools import cached_property, lru_cache
from itertools import combinations
from typing import Any

import numpy as np
from scipy.optimize import minimize
from scipy.special import stdtrit

from mtident._typing import FloatArray, IntArray
from mtident.thermal.modal_kernel import (
    APART_PENALTY,
    EDGE_PENALTY,
    END_OBJECTIVE,
    RSS_OBJECTIVE,
    leading_rows,
    objective_and_gradient,
    refine_log_tau,
    solve_selected,
)
from mtident.thermal.model import EQUILIBRIUM_FRACTION

__all__ = [
    "DEFAULT_MAX_TIME_CONSTANT_MIN",
    "Binned",
    "ModeFamily",
    "Mode",
    "IntervalEnd",
    "SteadyState",
    "bin_index",
    "best_fit",
    "bin_samples",
    "equilibrium_time",
    "fit_steady_state",
    "fitted_curve",
    "model_curve",
]

# The slowest thermal mode a machine tool is taken to have, unless told: a machine's
# structure (bed, column, the spindle head's casting) warms with time constants of one to
# five hours; ISO 230-3 warm-ups run 4-6 h for that reason. A mode slower than this is
# taken as absent; said in every answer.
DEFAULT_MAX_TIME_CONSTANT_MIN = 300.0
MAX_MODES = 4
# A bin spans about this fraction of the time since the log began: fast modes are resolved
# early, and a record of any length keeps a few hundred bins.
BIN_FRACTION = 0.02
BIN_ORIGIN_MIN = 1.0
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
# opposite sign sets an end, and the grid's few leading models all lie in one basin)
_END_STARTS = 30
_POLISHED = 3
# a refinement's iterations and evaluations: the few that wander along a ridge's edge end here
_MAXITER = 100
_MAXFUN = 300
_LATTICE_ROUNDS = 4
# the leading models are looked for among this many lowest first
_LEADING_SCAN = 2048
# with a tolerance to meet, the grid's hull alone answers where it is this many times wider
_ROUGH_MARGIN = 2.0
_MAX_CORRELATION_FACTOR = 25.0


@dataclass(frozen=True)
class ModeFamily:
    """The models an interval covers.

    Parameters
    ----------
    max_time_constant_min : float
        The largest time constant a mode may have (minutes).
    max_modes : int
        At most this many modes.
    reference_min : tuple of float, optional
        Time constants of a reference run of the same machine (minutes). Given, each mode's
        time constant is searched only within ``reference_box`` (relative half-widths) of the
        reference's, and no other mode is allowed.
    reference_box : tuple of float
        Relative half-width of each reference time constant's box (0.1: ±10 %).
    free_fast : int
        With a reference: up to this many more modes, free, faster than the reference's fastest
        box. A reference run pins a machine's slow modes; a fast one (a sensor's lag, a local
        transient, a mode the run could not resolve) left out would take a slow mode's place in
        the fit and pin T∞ falsely.
    """

    max_time_constant_min: float = DEFAULT_MAX_TIME_CONSTANT_MIN
    max_modes: int = MAX_MODES
    reference_min: tuple[float, ...] | None = None
    reference_box: tuple[float, ...] = ()
    free_fast: int = 0

    def without_reference(self) -> ModeFamily:
        """The same family without the reference's boxes.

        Returns
        -------
        ModeFamily
            The same largest time constant and number of modes, with no reference.
        """
        return ModeFamily(self.max_time_constant_min, self.max_modes)


@dataclass(frozen=True)
class Binned:
    """One sensor's readings in bins, the form every fit here works on.

    Parameters
    ----------
    time_min : ndarray, shape (B,)
        Mean time of each bin's readings (minutes since the log began).
    value_C : ndarray, shape (B,)
        Mean reading of each bin.
    count : ndarray, shape (B,)
        Readings in each bin (the bin's weight).
    room_C : ndarray, shape (B,), optional
        Mean room reading of each bin, where a room sensor is used.
    """

    time_min: FloatArray
    value_C: FloatArray
    count: FloatArray
    room_C: FloatArray | None = None

    def __len__(self) -> int:
        return len(self.time_min)

    def since(self, start_min: float) -> Binned:
        """The bins from ``start_min`` on.

        Parameters
        ----------
        start_min : float
            Minutes since the log began.

        Returns
        -------
        Binned
            The bins whose mean time is at or after ``start_min``.
        """
        keep = self.time_min >= start_min - 1e-9
        room = None if self.room_C is None else self.room_C[keep]
        return Binned(self.time_min[keep], self.value_C[keep], self.count[keep], room)


@dataclass(frozen=True)
class Mode:
    """One exponential mode: ``amplitude_C·e^(−t/time_constant_min)``.

    Attributes
    ----------
    time_constant_min : float
        The mode's time constant τ (min).
    amplitude_C : float
        Its value at the fit's origin (°C): the model is T∞ + Σ a·e^(−(t − origin)/τ).
    """

    time_constant_min: float
    amplitude_C: float


@dataclass(frozen=True)
class IntervalEnd:
    """The model that sets one end of an interval: its modes, with the amplitudes they take
    at that end.

    Attributes
    ----------
    steady_C : float
        T∞ of this model (°C): the interval's end it sets.
    modes : tuple of Mode
        Its modes, with the amplitudes they take at that end.
    """

    steady_C: float
    modes: tuple[Mode, ...]

    def slowest(self) -> Mode | None:
        """The slowest mode of this model (None for a model without a mode).

        Returns
        -------
        Mode or None
        """
        return max(self.modes, key=lambda m: (m.time_constant_min, abs(m.amplitude_C)), default=None)


@dataclass(frozen=True)
class SteadyState:
    """The model-robust estimate of one sensor's steady state.

    Attributes
    ----------
    steady_C : float
        T∞ of the best-fitting model (at the room's last level, with a room sensor).
    interval_C : dict of float to (float, float)
        Per confidence level, the hull of T∞ over every model the data do not exclude.
    ends : dict of float to (IntervalEnd, IntervalEnd)
        Per level, the models that set the low and the high end.
    modes : tuple of Mode
        The best-fitting model's modes (with the number chosen by BIC).
    start_C : float
        The best model's value at the fit's first bin.
    origin_min : float
        Where the fit begins (a warm-up that begins after the log starts at its last flat bin).
    equilibrium_time_min : float
        When the best model stays within 5 % of its total rise from T∞ (from the log's start).
    noise_C : float
        The readings' noise as the fit sees it (per reading, with the residuals' correlation).
    correlation_factor : float
        How much the residuals' correlation widens the interval's variance (1: none).
    rss, dof : float
        Weighted residual sum of squares and degrees of freedom of the best fit with the most modes.
    n_bins : int
    room_level_C : float or None
        The room's last level, where a room sensor is used.
    family : ModeFamily
    determined : bool
        Enough data for an interval (False: the interval is infinite).
    fits : dict of int to float
        The best fit's residual sum of squares per number of modes.
    refined : dict of float to bool
        Per level, whether the hull was refined off the search grid (else it is the grid's,
        at most as wide as the true hull).
    room_gains : tuple of float
        With a room sensor, each mode's gain on the room (its lag of the room less the room).
    """

    steady_C: float
    interval_C: dict[float, tuple[float, float]]
    ends: dict[float, tuple[IntervalEnd, IntervalEnd]]
    modes: tuple[Mode, ...]
    start_C: float
    origin_min: float
    equilibrium_time_min: float
    noise_C: float
    correlation_factor: float
    rss: float
    dof: float
    n_bins: int
    room_level_C: float | None
    family: ModeFamily
    determined: bool = True
    fits: dict[int, float] = field(default_factory=dict)
    refined: dict[float, bool] = field(default_factory=dict)
    room_gains: tuple[float, ...] = ()

    def half_width(self, level: float) -> float:
        """The larger distance from T∞ to an end of the interval at ``level``.

        Parameters
        ----------
        level : float
            A confidence level of ``interval_C``.

        Returns
        -------
        float
            The half-width (°C); infinite where the interval is.
        """
        lo, hi = self.interval_C[level]
        return max(self.steady_C - lo, hi - self.steady_C)

    def slowest_time_constant_min(self) -> float:
        """The best model's slowest time constant (NaN for a model without a mode).

        Returns
        -------
        float
            The time constant (min).
        """
        return max((m.time_constant_min for m in self.modes), default=float("nan"))


def bin_index(time_min: FloatArray, fraction: float = BIN_FRACTION, origin_min: float = BIN_ORIGIN_MIN) -> FloatArray:
    """The bin each time falls into (minutes since the log began): bins a fixed fraction of the
    elapsed time wide, so that the same reading always falls into the same bin, live or not.

    Parameters
    ----------
    time_min : ndarray
        Minutes since the log began (a negative time counts as 0).
    fraction : float, optional
        A bin's width as a fraction of its time plus ``origin_min``.
    origin_min : float, optional
        The time scale of the first bins (min): near t = 0 a bin is ``fraction * origin_min`` wide.

    Returns
    -------
    ndarray
        The bin numbers, as floats, in the shape of ``time_min``.

    Examples
    --------
    >>> bin_index(np.array([0.0, 0.5, 1.0, 100.0, 1000.0])).astype(int).tolist()
    [0, 20, 35, 233, 348]
    """
    return np.floor(np.log1p(np.maximum(np.asarray(time_min, dtype=float), 0.0) / origin_min) / np.log1p(fraction))


def bin_samples(time_min: FloatArray, values: FloatArray, room_C: FloatArray | None = None) -> Binned:
    """Bin one sensor's readings (missing ones left out) by :func:`bin_index`.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        Minutes since the log began.
    values : ndarray, shape (N,)
    room_C : ndarray, shape (N,), optional
        The room sensor's readings; a bin takes the readings where both are valid.

    Returns
    -------
    Binned
    """
    t = np.asarray(time_min, dtype=float)
    y = np.asarray(values, dtype=float)
    valid = np.isfinite(y) & np.isfinite(t)
    if room_C is not None:
        valid &= np.isfinite(room_C)
    _, which = np.unique(bin_index(t[valid]), return_inverse=True)
    count = np.bincount(which).astype(float)

    def mean(x: FloatArray) -> FloatArray:
        return np.bincount(which, weights=x) / count

    room = None if room_C is None else mean(np.asarray(room_C, dtype=float)[valid])
    return Binned(mean(t[valid]), mean(y[valid]), count, room)


# ---------------------------------------------------------------------------------------------
# One sensor's least-squares problem


@dataclass(frozen=True)
class _Problem:
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
        each room gain."""
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
        return _END_STARTS if self.family.reference_min is None else 1

    def polished(self) -> int:
        """How many of the lattice search's best models each end polishes by L-BFGS-B."""
        return _POLISHED if self.family.reference_min is None else 1

    def basin_log(self) -> float:
        """Models closer than this in every log time constant are taken as of one basin."""
        return 2.0 * np.log(_MAX_GRID_RATIO)

    def bounds(self, k: int) -> FloatArray:
        if self.family.reference_min is not None:
            return _reference_bounds(self.family, self.tau_bounds[0], k - len(self.family.reference_min))
        return np.tile(self.tau_bounds, (k, 1))


def _columns(problem: _Problem, tau: FloatArray) -> FloatArray:
    """Design matrices (T, B, p) of a batch of models (T, k): the constant, each mode's
    e^(−t/τ), then with a room each mode's lag of the room less the room."""
    b = problem.binned
    u = b.time_min - problem.origin
    cols = [np.ones(tau.shape[:1] + u.shape)]
    cols.extend(np.exp(-u / tau[:, k, None]) for k in range(tau.shape[1]))
    if b.room_C is not None:
        room = np.broadcast_to(b.room_C, cols[0].shape)
        cols.extend(_lag(room, b.time_min, tau[:, k]) - b.room_C for k in range(tau.shape[1]))
    return np.stack(cols, axis=-1)


def _lag(rows: FloatArray, time_min: FloatArray, tau: FloatArray) -> FloatArray:
    """A first-order lag of time constant ``tau[t]`` applied to each row of ``rows`` (T, B): a
    room taken as piecewise linear between the bins, from a machine at the room's first level."""
    out = np.empty(rows.shape)
    x = np.array(rows[:, 0], dtype=float)
    out[:, 0] = x
    for i in range(1, rows.shape[1]):
        dt = time_min[i] - time_min[i - 1]
        slope = (rows[:, i] - rows[:, i - 1]) / dt
        x = rows[:, i] - slope * tau + (x - rows[:, i - 1] + slope * tau) * np.exp(-dt / tau)
        out[:, i] = x
    return out


@dataclass(frozen=True)
class _Fits:
    """Penalised least-squares fits of a batch of T models with k modes each."""

    tau: FloatArray  # (T, k) time constants
    rss: FloatArray  # (T,) weighted residuals' sum of squares plus the priors' penalty
    steady: FloatArray  # (T,) T∞ (less the problem's centring)
    var_steady: FloatArray  # (T,) [(XᵀWX + P)⁻¹]₀₀
    direction: FloatArray  # (T, p) (XᵀWX + P)⁻¹e₀: how the parameters follow T∞ along the profile
    theta: FloatArray  # (T, p)

    @cached_property
    def log_tau(self) -> FloatArray:
        """log τ (T, k), computed once: the leading models are chosen from it many times."""
        return np.log(self.tau)

    def take(self, i: int) -> _Fits:
        """The i-th model alone."""
        s = slice(i, i + 1)
        return _Fits(self.tau[s], self.rss[s], self.steady[s], self.var_steady[s], self.direction[s], self.theta[s])

    @property
    def n_params(self) -> int:
        return self.theta.shape[1] + self.tau.shape[1]


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


def _fit(problem: _Problem, tau: FloatArray) -> _Fits:
    """Fits of a batch of models (T, k) from their design matrices, the residuals summed
    directly (the normal equations lose digits where modes are nearly alike)."""
    X = _columns(problem, tau)
    w = problem.binned.count
    y = problem.target()
    penalty = problem.penalty(tau.shape[1])
    Xw = X * w[:, None]
    gram = np.swapaxes(Xw, 1, 2) @ X
    rhs = np.swapaxes(Xw, 1, 2) @ y
    _, theta, var0, direction = _solve(gram, rhs, float(np.sum(w * y * y)), penalty)
    resid = y - (X @ theta[:, :, None])[..., 0]
    rss = (resid**2) @ w + (theta**2) @ penalty
    return _Fits(tau, rss, theta[:, 0], var0, direction, theta)


# ---------------------------------------------------------------------------------------------
# The global search: every set of grid time constants at once, from one Gram matrix


@lru_cache(maxsize=64)
def _grid_tuples(m: int, k: int, apart: int) -> IntArray:
    """Indices (T, k) of k grid time constants, increasing, at least ``apart`` steps apart."""
    combos = [c for c in combinations(range(m), k) if all(b - a >= apart for a, b in zip(c, c[1:], strict=False))]
    return np.array(combos, dtype=int).reshape(-1, k)


def _grid_taus(problem: _Problem) -> FloatArray:
    lo, hi = problem.tau_bounds
    n = max(_GRID_POINTS, int(np.ceil(np.log(hi / lo) / np.log(_MAX_GRID_RATIO))) + 1)
    return np.geomspace(lo, hi, n)


def _gram_fits(problem: _Problem, tau: FloatArray, index_sets: list[IntArray]) -> list[_Fits]:
    """Fits of models whose time constants are taken from sets of candidates: ``tau`` (S, m) holds
    S sets of m time constants, each of ``index_sets`` a batch (T, k) of indices into a set; the
    fits come per batch (S·T models, set by set), all from one Gram matrix per set of every column
    any of its models uses."""
    sets, m = tau.shape
    b = problem.binned
    u = b.time_min - problem.origin
    basis = [np.ones((sets, len(b), 1)), np.exp(-u[None, :, None] / tau[:, None, :])]
    if b.room_C is not None:
        lags = _lag(np.broadcast_to(b.room_C, (sets * m, len(b))), b.time_min, tau.reshape(-1)) - b.room_C
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
        out.append(_Fits(tau[:, idx].reshape(-1, idx.shape[1]), rss, theta[:, 0], direction[:, 0], direction, theta))
    return out


def _grid_fits(problem: _Problem) -> list[_Fits]:
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


def _reference_grid_fits(problem: _Problem, points: int = 7) -> list[_Fits]:
    """Every model on grids over the reference's boxes, one batch per number of free modes, fitted
    from one Gram matrix: ``points`` time constants across each box, and the free modes on a
    log grid below the slowest box."""
    family, fast_lo = problem.family, problem.tau_bounds[0]
    bounds = _reference_bounds(family, fast_lo, 0)
    axes = [np.geomspace(lo, hi, points) for lo, hi in bounds]
    boxed = np.array(np.meshgrid(*[np.arange(points) + points * n for n in range(len(axes))], indexing="ij"))
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
        combos = combos + points * len(axes)
        index_sets.append(
            np.concatenate([np.repeat(boxed, len(combos), axis=0), np.tile(combos, (len(boxed), 1))], axis=1)
        )
    return _gram_fits(problem, np.concatenate([*axes, fast])[None, :], index_sets)


def _candidates(problem: _Problem) -> list[_Fits]:
    """Every model of the family's search grid, fitted."""
    if problem.family.reference_min is not None:
        return _reference_grid_fits(problem)
    return _grid_fits(problem)


# ---------------------------------------------------------------------------------------------
# Local refinement: quasi-Newton in log τ from the grid's leading models

Objective = Callable[[_Fits], FloatArray]


class _RssObjective:
    """The fit's residual sum of squares (with the priors' penalty)."""

    def __call__(self, fits: _Fits) -> FloatArray:
        return fits.rss

    def compiled(self, log_mode_ratio: float) -> tuple[float, float, float, float, float]:
        """The objective as :func:`~mtident.thermal.modal_kernel.refine_log_tau` takes it."""
        return (float(RSS_OBJECTIVE), 0.0, 0.0, 1.0, log_mode_ratio)


class _EndObjective:
    """Minimised by the model that reaches furthest in T∞ towards ``sign`` within ``threshold``;
    beyond it, rising with the excess (``gap``: the threshold over the best fit), so that a
    search crossing the edge is led back."""

    def __init__(self, threshold: float, sign: float, gap: float) -> None:
        self.threshold, self.sign, self.gap = threshold, sign, gap

    def __call__(self, fits: _Fits) -> FloatArray:
        slack = self.threshold - fits.rss
        var = np.maximum(fits.var_steady, 0.0)
        reach = np.sqrt(var * self.gap)
        inside = -self.sign * fits.steady - np.sqrt(np.maximum(slack, 0.0) * var)
        return np.where(slack >= 0, inside, -self.sign * fits.steady - EDGE_PENALTY * reach * slack / self.gap)

    def compiled(self, log_mode_ratio: float) -> tuple[float, float, float, float, float]:
        """The objective as :func:`~mtident.thermal.modal_kernel.refine_log_tau` takes it."""
        return (float(END_OBJECTIVE), self.threshold, self.sign, self.gap, log_mode_ratio)


def _refine(problem: _Problem, fits: _Fits, i: int, objective: _RssObjective | _EndObjective) -> _Fits:
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


def _best_per_count(problem: _Problem, candidates: list[_Fits]) -> dict[int, _Fits]:
    """Per number of modes, the best-fitting model, refined off the grid."""
    best: dict[int, _Fits] = {}
    for k in sorted({f.tau.shape[1] for f in candidates}):
        same = [f for f in candidates if f.tau.shape[1] == k]
        for fits, i in _leading(same, _RssObjective(), problem.starts()):
            refined = _refine(problem, fits, i, _RssObjective())
            if k not in best or refined.rss[0] < best[k].rss[0]:
                best[k] = refined
    return best


def _leading(
    candidates: list[_Fits], objective: Objective, count: int, apart_log: float = 0.0
) -> list[tuple[_Fits, int]]:
    """The ``count`` models with the lowest finite ``objective`` among all the batches; with
    ``apart_log``, each of a different basin: a model whose log time constants all lie within
    ``apart_log`` of a model already taken (of as many modes) is passed over."""
    if not candidates:
        return []
    values = np.concatenate(
        [np.where(np.isfinite(v := np.asarray(objective(fits), dtype=float)), v, np.inf) for fits in candidates]
    )
    widest = max(fits.tau.shape[1] for fits in candidates)
    log_tau = np.concatenate([np.pad(fits.log_tau, ((0, 0), (0, widest - fits.tau.shape[1]))) for fits in candidates])
    modes = np.concatenate([np.full(len(fits.tau), fits.tau.shape[1]) for fits in candidates])
    starts = np.cumsum([0] + [len(fits.tau) for fits in candidates])
    rows = _leading_rows(values, log_tau, modes, count, apart_log)
    batches = np.searchsorted(starts, rows, side="right") - 1
    return [(candidates[b], int(r - starts[b])) for b, r in zip(batches, rows, strict=True)]


def _leading_rows(values: FloatArray, log_tau: FloatArray, modes: IntArray, count: int, apart_log: float) -> IntArray:
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
        rows, exhausted = leading_rows(values, order, boundary, log_tau, modes, count, apart_log)
        if not exhausted or scanned == len(values):
            return rows
        scanned = min(len(values), 4 * scanned)


# ---------------------------------------------------------------------------------------------
# The profile hull


def _profile_bounds(fits: _Fits, threshold: float) -> tuple[FloatArray, FloatArray]:
    """Per model, the lowest and highest T∞ with a fit within ``threshold`` (NaN where the
    model's best fit is not)."""
    slack = threshold - fits.rss
    half = np.sqrt(np.where(slack >= 0, slack, np.nan) * np.maximum(fits.var_steady, 0.0))
    return fits.steady - half, fits.steady + half


def _grid_half_width(candidates: list[_Fits], threshold: float, steady: float) -> float:
    """The hull's half-width over the models searched so far (the grid's and the best fits):
    never wider than the refined hull's."""
    ends = [_profile_bounds(f, threshold) for f in candidates]
    lo = min((float(np.nanmin(lo, initial=np.inf)) for lo, _ in ends), default=steady)
    hi = max((float(np.nanmax(hi, initial=-np.inf)) for _, hi in ends), default=steady)
    return max(steady - lo, hi - steady)


def _hull_end(
    problem: _Problem,
    candidates: list[_Fits],
    threshold: float,
    sign: float,
    gap: float,
    fallback: _Fits,
    refine: bool = True,
    seeds: list[_Fits] | None = None,
) -> _Fits:
    """The model that sets one end of the hull (``fallback``, the best fit, if none stays within
    the threshold): the grid's leading models of different basins, each improved by a local
    search on a shrinking lattice around it (all at once), then the best few refined by
    L-BFGS-B; unrefined, the grid's leading model; with ``seeds``, those models alone refined."""
    objective = _EndObjective(threshold, sign, gap)
    if not refine:
        leading = _leading(candidates, objective, 1)
        return fallback if not leading else leading[0][0].take(leading[0][1])
    if seeds is not None:
        polish = [(f, 0) for f in seeds]
    else:
        starts = _leading(candidates, objective, problem.end_starts(), problem.basin_log())
        improved = [
            _lattice_search(problem, [f.take(i) for f, i in starts if f.tau.shape[1] == k], objective)
            for k in {f.tau.shape[1] for f, _ in starts}
        ]
        polish = _leading(improved, objective, problem.polished(), problem.basin_log())
    best, best_value = None, np.inf
    for fits, i in polish:
        refined = _refine(problem, fits, i, objective)
        if refined.rss[0] > threshold:
            continue
        value = float(objective(refined)[0])
        if value < best_value:
            best, best_value = refined, value
    return fallback if best is None else best


def _lattice_search(
    problem: _Problem, starts: list[_Fits], objective: _EndObjective, rounds: int = _LATTICE_ROUNDS
) -> _Fits:
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


def _end(fits: _Fits, threshold: float, sign: float, shift: float) -> IntervalEnd:
    """The model at its furthest T∞ towards ``sign``, with the amplitudes it takes there."""
    slack = max(threshold - float(fits.rss[0]), 0.0)
    theta = fits.theta[0] + sign * np.sqrt(slack / max(float(fits.var_steady[0]), 1e-300)) * fits.direction[0]
    return IntervalEnd(float(theta[0]) + shift, _modes_of(fits, theta))


def _correlation_factor(resid: FloatArray) -> float:
    """The residuals' long-run variance over their variance (Bartlett window of the usual
    Newey-West width): how much their correlation (a misfit, a wandering room, rounding held
    for many readings) widens the variance of anything that varies slowly. At least 1."""
    n = len(resid)
    r = resid - resid.mean()
    var = float(np.dot(r, r))
    if n < 8 or var <= 0:
        return 1.0
    lags = max(1, int(np.ceil(4.0 * (n / 100.0) ** (2.0 / 9.0))))
    acf = np.array([np.dot(r[:-lag], r[lag:]) / var for lag in range(1, lags + 1)])
    weights = 1.0 - np.arange(1, lags + 1) / (lags + 1.0)
    return float(np.clip(1.0 + 2.0 * np.sum(weights * acf), 1.0, _MAX_CORRELATION_FACTOR))


def _choose(best_per_count: dict[int, _Fits], n: int) -> _Fits:
    """The point estimate's model: the number of modes by BIC."""

    def bic(f: _Fits) -> float:
        return n * np.log(max(float(f.rss[0]), 1e-300) / n) + f.n_params * np.log(n)

    return min(best_per_count.values(), key=bic)


def _modes_of(fits: _Fits, theta: FloatArray | None = None) -> tuple[Mode, ...]:
    th = fits.theta[0] if theta is None else theta
    return tuple(Mode(float(tau), float(a)) for tau, a in zip(fits.tau[0], th[1 : 1 + fits.tau.shape[1]], strict=True))


def _weighted_residuals(problem: _Problem, fits: _Fits) -> FloatArray:
    X = _columns(problem, fits.tau)[0]
    return (problem.target() - X @ fits.theta[0]) * np.sqrt(problem.binned.count)


# ---------------------------------------------------------------------------------------------
# The estimate


def fit_steady_state(
    binned: Binned,
    *,
    noise_C: float,
    interval_min: float,
    family: ModeFamily = ModeFamily(),
    levels: tuple[float, ...] = (0.95, 0.99),
    refine_within: float | None = None,
) -> SteadyState:
    """The model-robust T∞ of one sensor: the best-fitting sum of modes and the profile hull
    over every model of ``family`` the data do not exclude.

    Parameters
    ----------
    binned : Binned
        The sensor's readings from where its warm-up begins (:func:`bin_samples`); the modes
        are counted from the first bin.
    noise_C : float
        The readings' noise (°C, per reading), a floor under the residuals' own estimate.
    interval_min : float
        The sampling interval: modes much faster than it are not searched.
    family : ModeFamily
    levels : tuple of float
        Confidence levels of the intervals.
    refine_within : float, optional
        Refine a level's hull off the search grid only where the grid's own half-width is
        within this (°C): a monitor asking "within the tolerance?" needs no more where the
        grid already says no. Default: always refine.

    Returns
    -------
    SteadyState

    Examples
    --------
    >>> t = np.arange(0.0, 241.0)
    >>> warm = 26.7 - 8.8 * np.exp(-t / 62.5) + 0.02 * np.random.default_rng(0).standard_normal(t.size)
    >>> fit = fit_steady_state(bin_samples(t, warm), noise_C=0.02, interval_min=1.0)
    >>> round(fit.steady_C, 1), len(fit.modes)
    (26.7, 1)
    """
    problem = _problem(binned, noise_C, interval_min, family)
    candidates = _candidates(problem)
    if refine_within is not None:
        # the grid alone, where its hull is far wider than asked: no refinement (most of the
        # cost) would bring it within, so the answer to "is it within?" is already no
        rough = _steady_state(problem, candidates, _grid_best(candidates), levels, refine=False)
        if not rough.determined or rough.half_width(max(levels)) > _ROUGH_MARGIN * refine_within:
            return rough
    return _steady_state(problem, candidates, _best_per_count(problem, candidates), levels, refine_within)


def _grid_best(candidates: list[_Fits]) -> dict[int, _Fits]:
    """Per number of modes, the best-fitting model of the grid."""
    return {f.tau.shape[1]: f.take(int(np.argmin(f.rss))) for f in candidates if len(f.rss)}


def _steady_state(
    problem: _Problem,
    candidates: list[_Fits],
    best: dict[int, _Fits],
    levels: tuple[float, ...],
    refine_within: float | None = None,
    refine: bool = True,
) -> SteadyState:
    """The estimate from the best fits per number of modes, and its hull over ``candidates``
    (refined off the grid where ``refine`` and, with ``refine_within``, where the grid's hull is
    within that)."""
    binned, family = problem.binned, problem.family
    full = min(best.values(), key=lambda f: float(f.rss[0]))
    chosen = _choose(best, len(binned))
    candidates = [*candidates, *best.values()]
    shift = problem.centre + (0.0 if binned.room_C is None else float(binned.room_C[-1]))
    modes = _modes_of(chosen)
    # the fit is of the readings less the room: the start is at the room's first level
    start = float(_columns(problem, chosen.tau)[0, 0] @ chosen.theta[0]) + problem.centre
    if binned.room_C is not None:
        start += float(binned.room_C[0])
    steady = float(chosen.steady[0]) + shift
    dof = float(len(binned) - full.n_params)
    common: dict[str, Any] = dict(
        steady_C=steady,
        modes=modes,
        room_gains=tuple(float(g) for g in chosen.theta[0, 1 + chosen.tau.shape[1] :])
        if binned.room_C is not None
        else (),
        start_C=start,
        origin_min=problem.origin,
        rss=float(full.rss[0]),
        dof=dof,
        n_bins=len(binned),
        room_level_C=None if binned.room_C is None else float(binned.room_C[-1]),
        family=family,
        fits={k: float(f.rss[0]) for k, f in best.items()},
    )
    if dof < 2:
        wide = (-np.inf, np.inf)
        return SteadyState(
            interval_C={q: wide for q in levels},
            ends={},
            equilibrium_time_min=float("nan"),
            noise_C=float(np.sqrt(problem.sigma2)),
            correlation_factor=1.0,
            determined=False,
            **common,
        )
    factor = _correlation_factor(_weighted_residuals(problem, full))
    sigma2 = max(float(full.rss[0]) / dof, problem.sigma2) * factor
    intervals: dict[float, tuple[float, float]] = {}
    ends: dict[float, tuple[IntervalEnd, IntervalEnd]] = {}
    refined: dict[float, bool] = {}
    widest_refined: bool | None = None
    ends_models: tuple[_Fits, _Fits] = (full, full)
    for q in sorted(levels, reverse=True):
        threshold = float(full.rss[0]) + sigma2 * float(stdtrit(dof, 0.5 + q / 2.0)) ** 2
        gap = threshold - float(full.rss[0])
        # the grid's hull is within the true one: where the widest level's is already wider than
        # asked, the refinement (most of the cost) cannot change the answer to "is it within?",
        # and the narrower levels are refined only along with the widest
        refine_level = refine
        if refine and refine_within is not None:
            if widest_refined is None:
                widest_refined = _grid_half_width(candidates, threshold, float(chosen.steady[0])) <= refine_within
            refine_level = widest_refined
        # with a tolerance the widest level's hull misses, a narrower level is polished from the
        # wider level's end models alone (the same ridges set both): a report's interval while the
        # decision waits; searched in full once the decision may be near
        near = (
            refine_within is None
            or not intervals
            or max(steady - intervals[max(intervals)][0], intervals[max(intervals)][1] - steady) <= refine_within
        )
        seeds = None if near else list(ends_models)
        low = _hull_end(problem, candidates, threshold, -1.0, gap, full, refine_level, seeds)
        high = _hull_end(problem, candidates, threshold, +1.0, gap, full, refine_level, seeds)
        ends_models = (low, high)
        lo = min(float(_profile_bounds(low, threshold)[0][0]) + shift, steady)
        hi = max(float(_profile_bounds(high, threshold)[1][0]) + shift, steady)
        intervals[q] = (lo, hi)
        ends[q] = (_end(low, threshold, -1.0, shift), _end(high, threshold, +1.0, shift))
        refined[q] = refine_level
    t_eq = equilibrium_time(modes, steady, start, problem.origin)
    intervals = {q: intervals[q] for q in levels}
    return SteadyState(
        interval_C=intervals,
        ends=ends,
        equilibrium_time_min=t_eq,
        noise_C=float(np.sqrt(sigma2)),
        correlation_factor=factor,
        refined=refined,
        **common,
    )


def best_fit(
    binned: Binned, *, noise_C: float, interval_min: float, family: ModeFamily = ModeFamily()
) -> tuple[float, int, float]:
    """The best fit of ``family`` alone, without an interval: its residual sum of squares, its
    number of parameters, and how much its residuals' correlation widens a variance (a
    reference's boxed fit is compared with it).

    Parameters
    ----------
    binned : Binned
    noise_C, interval_min : float
    family : ModeFamily

    Returns
    -------
    rss : float
    n_params : int
    correlation_factor : float
    """
    problem = _problem(binned, noise_C, interval_min, family)
    best = min(_best_per_count(problem, _candidates(problem)).values(), key=lambda f: float(f.rss[0]))
    return float(best.rss[0]), best.n_params, _correlation_factor(_weighted_residuals(problem, best))


def _problem(binned: Binned, noise_C: float, interval_min: float, family: ModeFamily) -> _Problem:
    y = binned.value_C if binned.room_C is None else binned.value_C - binned.room_C
    spread = max(float(np.ptp(binned.value_C)), 10.0 * noise_C)
    lo = max(0.5 * interval_min, _FASTEST_MIN)
    return _Problem(
        binned=binned,
        origin=float(binned.time_min[0]),
        centre=float(np.average(y, weights=binned.count)),
        sigma2=max(noise_C, 1e-6) ** 2,
        amplitude_sd=AMPLITUDE_SD_FACTOR * spread,
        tau_bounds=(min(lo, family.max_time_constant_min), family.max_time_constant_min),
        family=family,
    )


def model_curve(modes: tuple[Mode, ...], steady_C: float, origin_min: float, time_min: FloatArray) -> FloatArray:
    """The curve of a sum of modes (no room term) at ``time_min`` (from the log's start); before
    ``origin_min`` it holds its value there.

    Parameters
    ----------
    modes : tuple of Mode
    steady_C : float
    origin_min : float
    time_min : ndarray

    Returns
    -------
    ndarray, the shape of ``time_min``
    """
    u = np.maximum(np.asarray(time_min, dtype=float) - origin_min, 0.0)
    out = np.full(u.shape, float(steady_C))
    for m in modes:
        out = out + m.amplitude_C * np.exp(-u / m.time_constant_min)
    return out


def fitted_curve(
    fit: SteadyState,
    time_min: FloatArray,
    room_C: FloatArray | None = None,
    modes: tuple[Mode, ...] | None = None,
    steady_C: float | None = None,
) -> FloatArray:
    """The fitted model's course at ``time_min`` (from the log's start), with the room's own
    course where the fit had a room sensor (``room_C`` at those times; held at its last level
    where missing); ``modes`` and ``steady_C`` replace the best model's (an interval's end).

    Parameters
    ----------
    fit : SteadyState
    time_min : ndarray, shape (N,)
    room_C : ndarray, shape (N,), optional
    modes : tuple of Mode, optional
    steady_C : float, optional

    Returns
    -------
    ndarray, shape (N,)
    """
    t = np.asarray(time_min, dtype=float)
    modes = fit.modes if modes is None else modes
    steady = fit.steady_C if steady_C is None else steady_C
    if fit.room_level_C is None or room_C is None:
        return model_curve(modes, steady, fit.origin_min, t)
    room = np.asarray(room_C, dtype=float)
    valid = np.isfinite(room)
    room = np.interp(t, t[valid], room[valid]) if valid.any() else np.full(t.shape, fit.room_level_C)
    curve = model_curve(modes, steady - fit.room_level_C, fit.origin_min, t) + room
    after = t >= fit.origin_min
    if fit.room_gains and after.sum() > 1:
        taus = np.array([m.time_constant_min for m in fit.modes])
        lagged = _lag(np.broadcast_to(room[after], (len(taus), int(after.sum()))), t[after], taus)
        curve[after] += np.asarray(fit.room_gains) @ (lagged - room[after])
    return curve


def equilibrium_time(modes: tuple[Mode, ...], steady_C: float, start_C: float, origin_min: float) -> float:
    """When a sum of modes last leaves the band of 5 % of its total rise around T∞ (minutes
    from the log's start; the papers' thermal-equilibrium time for any number of modes).

    Parameters
    ----------
    modes : tuple of Mode
    steady_C, start_C : float
    origin_min : float

    Returns
    -------
    float
    """
    if not modes:
        return origin_min
    slowest = max(m.time_constant_min for m in modes)
    u = np.concatenate([[0.0], np.geomspace(1e-3, 40.0 * slowest, 4000)])
    curve = model_curve(modes, steady_C, 0.0, u)
    outside = np.flatnonzero(np.abs(curve - steady_C) > (1.0 - EQUILIBRIUM_FRACTION) * abs(steady_C - start_C))
    return origin_min + (float(u[min(outside[-1] + 1, len(u) - 1)]) if outside.size else 0.0)


def log_time_constant_sd(binned: Binned, fit: SteadyState) -> tuple[float, ...]:
    """The standard deviation of the log of each of the best model's time constants (its relative
    uncertainty), from the Gauss-Newton curvature of the fit at the noise the fit saw.

    Parameters
    ----------
    binned : Binned
        The readings the fit was made from.
    fit : SteadyState

    Returns
    -------
    tuple of float, one per mode of ``fit.modes``
    """
    if not fit.modes:
        return ()
    problem = _problem(binned, fit.noise_C, 1.0, fit.family)
    tau = np.array([[m.time_constant_min for m in fit.modes]])
    amplitude = np.array([m.amplitude_C for m in fit.modes])
    X = _columns(problem, tau)[0]
    u = (binned.time_min - problem.origin)[:, None]
    slopes = amplitude * (u / tau) * np.exp(-u / tau)  # ∂model/∂log τ
    J = np.concatenate([X, slopes], axis=1)
    info = (J * binned.count[:, None]).T @ J + np.diag(
        np.concatenate([problem.penalty(len(fit.modes)), np.zeros(len(fit.modes))])
    )
    cov = fit.noise_C**2 * np.linalg.pinv(info)
    return tuple(float(np.sqrt(max(v, 0.0))) for v in np.diagonal(cov)[-len(fit.modes) :])
