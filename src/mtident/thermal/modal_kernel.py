"""The compiled hot loops of :mod:`mtident.thermal.modes` (numba): one sum-of-modes fit and its
slopes in log τ, the objectives a refinement minimises and a quasi-Newton search over them, the
grid's batched normal equations, and the choice of leading models of different basins.

:func:`fit_one` is the same arithmetic as ``modal_search._fit`` for one model: the design matrix (the
constant, each mode's e^(−u/τ), with a room each mode's lag of the room less the room), the
penalised normal equations solved in normalised form, and the exact variable-projection slopes
of the residual sum of squares, of T∞ and of its variance. Compiled whole, a refinement costs
the fits and not the interpreter between them.
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
from numba import njit

from mtident._typing import FloatArray

__all__ = [
    "APART_PENALTY",
    "EDGE_PENALTY",
    "END_OBJECTIVE",
    "RSS_OBJECTIVE",
    "end_values",
    "fit_one",
    "lag_rows",
    "leading_rows",
    "objective_and_gradient",
    "refine_log_tau",
    "solve_selected",
]

# the same ridge as modal_search._JITTER, and the room columns' forward-difference step
_JITTER = 1e-11
_DIFF_STEP = 1e-6

# the arrays :func:`fit_one` takes as its ``inputs`` (u, time_min, weight, target, room), and an
# objective as :func:`objective_and_gradient` takes it (kind, threshold, sign, gap, log_mode_ratio)
KernelInputs: TypeAlias = tuple[FloatArray, FloatArray, FloatArray, FloatArray, FloatArray]
KernelObjective: TypeAlias = tuple[float, float, float, float, float]


@njit(cache=True)
def lag_rows(room: FloatArray, time_min: FloatArray, tau: FloatArray) -> FloatArray:  # pragma: no cover - compiled
    """A first-order lag of each time constant in ``tau`` (k,) applied to ``room`` (B,) taken as
    piecewise linear between its times, from a machine at the room's first level: (k, B).

    Parameters
    ----------
    room : ndarray, shape (B,)
        The room's readings (°C).
    time_min : ndarray, shape (B,)
        Their times (min), increasing.
    tau : ndarray, shape (k,)
        Time constants (min).

    Returns
    -------
    ndarray, shape (k, B)
        Each lag's temperature (°C) at ``time_min``.
    """
    k, n = tau.shape[0], room.shape[0]
    out = np.empty((k, n))
    for j in range(k):
        x = room[0]
        out[j, 0] = x
        for i in range(1, n):
            dt = time_min[i] - time_min[i - 1]
            slope = (room[i] - room[i - 1]) / dt
            x = room[i] - slope * tau[j] + (x - room[i - 1] + slope * tau[j]) * np.exp(-dt / tau[j])
            out[j, i] = x
    return out


@njit(cache=True)
def fit_one(
    inputs: KernelInputs, log_tau: FloatArray, penalty: FloatArray
) -> tuple[float, FloatArray, float, FloatArray, FloatArray, FloatArray, FloatArray]:  # pragma: no cover - compiled
    """The penalised least-squares fit of one model and its slopes in log τ.

    Parameters
    ----------
    inputs : (u, time_min, weight, target, room)
        u : (B,) minutes since the modes began; time_min : (B,) the bins' times (for the room's lag);
        weight : (B,) readings per bin; target : (B,) the readings (less the room) less the centring;
        room : (B,) the room's readings, or an empty array without a room sensor
    log_tau : (k,); penalty : (p,) the priors' weights

    Returns
    -------
    rss, theta (p,), var_steady, direction (p,), d_rss (k,), d_steady (k,), d_var (k,)
    """
    u, time_min, weight, target, room = inputs
    k = log_tau.shape[0]
    n = u.shape[0]
    with_room = room.shape[0] > 0
    p = 1 + k + (k if with_room else 0)
    tau = np.exp(log_tau)
    X = np.empty((n, p))
    D = np.zeros((k, n))  # the slope of each τ-dependent column (mode j, and its room column)
    R = np.zeros((k, n))
    for i in range(n):
        X[i, 0] = 1.0
    for j in range(k):
        for i in range(n):
            e = np.exp(-u[i] / tau[j])
            X[i, 1 + j] = e
            D[j, i] = e * u[i] / tau[j]
    if with_room:
        lagged = lag_rows(room, time_min, tau)
        nudged = lag_rows(room, time_min, tau * np.exp(_DIFF_STEP))
        for j in range(k):
            for i in range(n):
                X[i, 1 + k + j] = lagged[j, i] - room[i]
                R[j, i] = (nudged[j, i] - lagged[j, i]) / _DIFF_STEP
    gram = np.zeros((p, p))
    rhs = np.zeros(p)
    for i in range(n):
        for a in range(p):
            xa = weight[i] * X[i, a]
            rhs[a] += xa * target[i]
            for b in range(a, p):
                gram[a, b] += xa * X[i, b]
    for a in range(p):
        gram[a, a] += penalty[a]
        for b in range(a):
            gram[a, b] = gram[b, a]
    scale = np.sqrt(np.maximum(np.diag(gram), 1e-300))
    normed = gram / np.outer(scale, scale) + _JITTER * np.eye(p)
    inverse = np.linalg.inv(normed) / np.outer(scale, scale)
    theta = inverse @ rhs
    resid = target - X @ theta
    rss = 0.0
    for i in range(n):
        rss += weight[i] * resid[i] * resid[i]
    for a in range(p):
        rss += penalty[a] * theta[a] * theta[a]
    g0 = inverse[:, 0].copy()
    d_rss = np.zeros(k)
    d_steady = np.zeros(k)
    d_var = np.zeros(k)
    for j in range(k):
        cols = (1 + j, 1 + k + j) if with_room else (1 + j, -1)
        # dG = DᵀWX + XᵀWD, dc = DᵀWy with D nonzero in the τ's own columns only
        d_gram = np.zeros((p, p))
        d_rhs = np.zeros(p)
        d_fit = np.zeros(n)  # D θ
        for c_index in range(2):
            c = cols[c_index]
            if c < 0:
                continue
            slope = D[j] if c_index == 0 else R[j]
            for i in range(n):
                ws = weight[i] * slope[i]
                d_rhs[c] += ws * target[i]
                d_fit[i] += slope[i] * theta[c]
                for b in range(p):
                    d_gram[c, b] += ws * X[i, b]
        d_gram = d_gram + d_gram.T
        d_theta = inverse @ (d_rhs - d_gram @ theta)
        total = 0.0
        for i in range(n):
            total += weight[i] * resid[i] * d_fit[i]
        d_rss[j] = -2.0 * total
        d_steady[j] = d_theta[0]
        d_var[j] = -(g0 @ (d_gram @ g0))
    return rss, theta, inverse[0, 0], g0, d_rss, d_steady, d_var


# the objectives :func:`refine_log_tau` minimises (see ``modal_search._RssObjective``/``_EndObjective``)
RSS_OBJECTIVE = 0
END_OBJECTIVE = 1
# beyond the threshold, a profile's end search is pushed back this many times more steeply than
# T∞'s own reach at the best fit: a search crossing the edge returns
EDGE_PENALTY = 1e3
# the weight of the penalty that keeps two modes' time constants apart
APART_PENALTY = 1e4
# L-BFGS-B's default stopping rules: a relative decrease below factr·eps, a projected gradient
# below pgtol
_FTOL = 1e7 * np.finfo(np.float64).eps
_PGTOL = 1e-5
_ARMIJO = 1e-4
_HALVINGS = 30
_PASSES = 4
_DOUBLINGS = 8


@njit(cache=True)
def objective_and_gradient(
    inputs: KernelInputs,
    log_tau: FloatArray,
    penalty: FloatArray,
    objective: KernelObjective,
) -> tuple[float, FloatArray]:  # pragma: no cover - compiled
    """One model's objective and its gradient in log τ, as ``modal_search._refine`` minimises it.

    Parameters
    ----------
    inputs : tuple
        The arrays :func:`fit_one` takes (u, time_min, weight, target, room).
    log_tau : ndarray, shape (k,)
    penalty : ndarray, shape (p,)
    objective : tuple
        (kind, threshold, sign, gap, log_mode_ratio): ``RSS_OBJECTIVE`` or ``END_OBJECTIVE`` with
        the end's threshold, direction and gap; with ``log_mode_ratio`` > 0 the penalty that keeps
        any two modes at least that far apart (log).

    Returns
    -------
    value : float
    gradient : ndarray, shape (k,)
        Not-a-number slopes as zero, infinite ones as the largest float (as ``numpy.nan_to_num``).
    """
    kind, threshold, sign, gap, log_mode_ratio = objective
    rss, theta, var, _, d_rss, d_steady, d_var = fit_one(inputs, log_tau, penalty)
    k = log_tau.shape[0]
    if kind == RSS_OBJECTIVE:
        value = rss
        gradient = d_rss.copy()
    else:
        slack = threshold - rss
        var = max(var, 1e-300)
        if slack >= 0:
            root = max(np.sqrt(slack * var), 1e-300)
            value = -sign * theta[0] - root
            gradient = -sign * d_steady - (-d_rss * var + slack * d_var) / (2.0 * root)
        else:
            reach = np.sqrt(var * gap)
            d_reach = d_var * gap / (2.0 * reach)
            value = -sign * theta[0] - EDGE_PENALTY * reach * slack / gap
            gradient = -sign * d_steady - EDGE_PENALTY * (d_reach * slack - reach * d_rss) / gap
    if log_mode_ratio > 0 and k > 1:
        order = np.argsort(log_tau)
        j = 0
        for n in range(1, k - 1):
            if log_tau[order[n + 1]] - log_tau[order[n]] < log_tau[order[j + 1]] - log_tau[order[j]]:
                j = n
        excess = log_mode_ratio - (log_tau[order[j + 1]] - log_tau[order[j]])
        if excess > 0:
            value += APART_PENALTY * excess * excess
            gradient[order[j + 1]] -= 2.0 * APART_PENALTY * excess
            gradient[order[j]] += 2.0 * APART_PENALTY * excess
    for j in range(k):
        if np.isnan(gradient[j]):
            gradient[j] = 0.0
        elif np.isinf(gradient[j]):
            gradient[j] = np.finfo(np.float64).max if gradient[j] > 0 else -np.finfo(np.float64).max
    return value, gradient


@njit(cache=True)
def refine_log_tau(
    inputs: KernelInputs,
    start: FloatArray,
    lower: FloatArray,
    upper: FloatArray,
    penalty: FloatArray,
    objective: KernelObjective,
    max_iterations: int,
    max_evaluations: int,
) -> FloatArray:  # pragma: no cover - compiled
    """The log time constants that minimise :func:`objective_and_gradient` within the bounds,
    from ``start``: a projected quasi-Newton search (BFGS on the free variables, a backtracking
    line search along the projected path) with L-BFGS-B's default stopping rules. Compiled whole,
    so that each step costs the fit and not the interpreter.

    Parameters
    ----------
    inputs, penalty, objective
        As :func:`objective_and_gradient`.
    start, lower, upper : ndarray, shape (k,)
        The first point and the bounds (log τ).
    max_iterations, max_evaluations : int

    Returns
    -------
    ndarray, shape (k,)
        The best point found.
    """
    x = np.minimum(np.maximum(start, lower), upper)
    f, g = objective_and_gradient(inputs, x, penalty, objective)
    evaluations = 1
    # a kink (the end objective's edge) spoils the curvature learnt before it: start afresh from
    # where a pass ended, while passes still gain
    for _ in range(_PASSES):
        before = f
        x, f, g, spent = _quasi_newton_pass(
            inputs, penalty, objective, (lower, upper), (x, f, g), max_iterations, max_evaluations - evaluations
        )
        evaluations += spent
        if evaluations >= max_evaluations or before - f <= _FTOL * max(abs(f), abs(before), 1.0):
            break
    return x


@njit(cache=True)
def _quasi_newton_pass(
    inputs: KernelInputs,
    penalty: FloatArray,
    objective: KernelObjective,
    bounds: tuple[FloatArray, FloatArray],
    point: tuple[FloatArray, float, FloatArray],
    max_iterations: int,
    max_evaluations: int,
) -> tuple[FloatArray, float, FloatArray, int]:  # pragma: no cover - compiled
    """One pass of :func:`refine_log_tau`'s search within ``bounds`` (lower, upper) from ``point``
    (x, its value f and gradient g), the curvature learnt afresh: the point it ends at, its value
    and gradient, and the evaluations it spent."""
    lower, upper = bounds
    x, f, g = point
    k = x.shape[0]
    evaluations = 0
    h = np.eye(k)
    for iteration in range(max_iterations):
        projected = x - np.minimum(np.maximum(x - g, lower), upper)
        if np.max(np.abs(projected)) <= _PGTOL:
            break
        active = ((x <= lower) & (g > 0)) | ((x >= upper) & (g < 0))
        direction = -(h @ g)
        for j in range(k):
            if active[j]:
                direction[j] = 0.0
        slope = np.dot(g, direction)
        if not slope < 0:
            h = np.eye(k)
            direction = -g.copy()
            for j in range(k):
                if active[j]:
                    direction[j] = 0.0
            slope = np.dot(g, direction)
            if not slope < 0:
                break
        if iteration == 0 or not np.all(np.isfinite(direction)):
            # the first step, with no curvature yet, moves at most one unit (a factor e in τ)
            size = np.sqrt(np.dot(direction, direction))
            if size > 1.0:
                direction = direction / size
        step = 1.0
        accepted = False
        for _ in range(_HALVINGS):
            trial = np.minimum(np.maximum(x + step * direction, lower), upper)
            f_trial, g_trial = objective_and_gradient(inputs, trial, penalty, objective)
            evaluations += 1
            if np.isfinite(f_trial) and f_trial <= f + _ARMIJO * np.dot(g, trial - x):
                accepted = True
                break
            if evaluations >= max_evaluations:
                break
            step *= 0.5
        if not accepted:
            break
        if step == 1.0:
            # a whole step taken at once: along a long ridge, go on while it keeps paying
            for _ in range(_DOUBLINGS):
                if evaluations >= max_evaluations:
                    break
                further = np.minimum(np.maximum(x + 2.0 * step * direction, lower), upper)
                if np.all(further == trial):
                    break
                f_further, g_further = objective_and_gradient(inputs, further, penalty, objective)
                evaluations += 1
                if not (np.isfinite(f_further) and f_further < f_trial):
                    break
                step, trial, f_trial, g_trial = 2.0 * step, further, f_further, g_further
        s = trial - x
        y = g_trial - g
        decrease = f - f_trial
        x, f, g = trial, f_trial, g_trial
        sy = np.dot(s, y)
        if sy > 1e-10 * np.sqrt(np.dot(s, s) * np.dot(y, y)):
            rho = 1.0 / sy
            v = np.eye(k) - rho * np.outer(s, y)
            h = v @ h @ v.T + rho * np.outer(s, s)
        if decrease <= _FTOL * max(abs(f), abs(f + decrease), 1.0) or evaluations >= max_evaluations:
            break
    return x, f, g, evaluations


@njit(cache=True)
def end_values(
    rss: FloatArray, var_steady: FloatArray, steady: FloatArray, threshold: float, sign: float, gap: float
) -> FloatArray:  # pragma: no cover - compiled
    """``modal_search._EndObjective`` over a batch of fits, row by row in one pass (the grid's
    batches are scanned for their leading models at every level and end, and the interpreter's
    temporaries cost more than the arithmetic).

    Parameters
    ----------
    rss, var_steady, steady : ndarray, shape (T,)
        The fits' residual sums of squares, T∞ variance factors and T∞.
    threshold, sign, gap : float
        As ``modal_search._EndObjective``.

    Returns
    -------
    ndarray, shape (T,)
    """
    values = np.empty(rss.shape[0])
    for row in range(rss.shape[0]):
        slack = threshold - rss[row]
        var = max(var_steady[row], 0.0)
        if slack >= 0:
            values[row] = -sign * steady[row] - np.sqrt(slack * var)
        else:
            values[row] = -sign * steady[row] - EDGE_PENALTY * np.sqrt(var * gap) * slack / gap
    return values


@njit(cache=True)
def leading_rows(
    values: FloatArray,
    order: np.ndarray,
    boundary: float,
    log_tau: FloatArray,
    modes: np.ndarray,
    count: int,
    apart_log: float,
) -> tuple[np.ndarray, bool]:  # pragma: no cover - compiled
    """The rows of the ``count`` lowest finite ``values``, lowest first, scanned in ``order`` (rows
    by value, ties by row); with ``apart_log`` > 0, each of a different basin: a row whose log
    time constants all lie within ``apart_log`` of a row already taken of as many modes is passed
    over.

    Parameters
    ----------
    values : ndarray, shape (T,)
    order : ndarray of int, shape (M,)
        The M lowest rows in order (M ≤ T).
    boundary : float
        The value of the rows left out of ``order`` that are tied with its last (infinite where
        ``order`` holds every row): the scan stops at it.
    log_tau : ndarray, shape (M, K)
        The log time constants of each row of ``order``, in its order, the first ``modes[i]``
        entries used.
    modes : ndarray of int, shape (M,)
    count : int
    apart_log : float

    Returns
    -------
    rows : ndarray of int
        The rows taken.
    exhausted : bool
        Whether the scan reached the end of ``order`` or ``boundary`` still short of ``count``: a
        longer ``order`` may take more.
    """
    taken = np.empty(min(count, order.shape[0]), dtype=np.int64)
    n_taken = 0
    for i in range(order.shape[0]):
        row = order[i]
        if n_taken >= count or not np.isfinite(values[row]):
            return order[taken[:n_taken]], False
        if values[row] >= boundary:
            return order[taken[:n_taken]], True
        same_basin = False
        if apart_log > 0:
            for t in range(n_taken):
                other = taken[t]
                if modes[other] != modes[i]:
                    continue
                close = True
                for j in range(modes[i]):
                    if abs(log_tau[i, j] - log_tau[other, j]) > apart_log:
                        close = False
                        break
                if close:
                    same_basin = True
                    break
        if not same_basin:
            taken[n_taken] = i
            n_taken += 1
    return order[taken[:n_taken]], n_taken < count


# numpy's error model: no zero-division check on every division (each divisor is a scale of at
# least 1e-150 or a pivot of a positive-definite matrix plus a ridge), the same numbers
@njit(cache=True, error_model="numpy")
def solve_selected(
    gram: FloatArray, rhs: FloatArray, columns: np.ndarray, yy: float, penalty: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray]:  # pragma: no cover - compiled
    """Penalised normal equations of many models that each use some columns of a shared Gram
    matrix, solved in normalised form (Gaussian elimination with partial pivoting).

    Parameters
    ----------
    gram : ndarray, shape (S, P, P)
        Per set, the weighted Gram matrix of every column.
    rhs : ndarray, shape (S, P)
        Per set, the columns' weighted products with the readings.
    columns : ndarray of int, shape (T, p)
        Each model's columns.
    yy : float
        The readings' weighted sum of squares.
    penalty : ndarray, shape (p,)
        The priors' weights on the model's parameters.

    Returns
    -------
    rss : ndarray, shape (S·T,)
    theta : ndarray, shape (S·T, p)
    first_column : ndarray, shape (S·T, p)
        G⁻¹e₀ per model (its first entry the variance factor of T∞).
    """
    sets, models, p = gram.shape[0], columns.shape[0], columns.shape[1]
    rss = np.empty(sets * models)
    theta = np.empty((sets * models, p))
    first_column = np.empty((sets * models, p))
    a = np.empty((p, p + 2))
    scale = np.empty(p)
    for s in range(sets):
        for t in range(models):
            row = s * models + t
            for i in range(p):
                scale[i] = np.sqrt(max(gram[s, columns[t, i], columns[t, i]] + penalty[i], 1e-300))
            for i in range(p):
                for j in range(p):
                    a[i, j] = gram[s, columns[t, i], columns[t, j]] / (scale[i] * scale[j])
                a[i, i] += penalty[i] / (scale[i] * scale[i]) + _JITTER
                a[i, p] = rhs[s, columns[t, i]] / scale[i]
                a[i, p + 1] = 0.0
            a[0, p + 1] = 1.0 / scale[0]
            for c in range(p):
                pivot = c
                for i in range(c + 1, p):
                    if abs(a[i, c]) > abs(a[pivot, c]):
                        pivot = i
                if pivot != c:
                    for j in range(c, p + 2):
                        a[c, j], a[pivot, j] = a[pivot, j], a[c, j]
                for i in range(c + 1, p):
                    factor = a[i, c] / a[c, c]
                    for j in range(c, p + 2):
                        a[i, j] -= factor * a[c, j]
            for c in range(p - 1, -1, -1):
                for r in (p, p + 1):
                    value = a[c, r]
                    for j in range(c + 1, p):
                        value -= a[c, j] * a[j, r]
                    a[c, r] = value / a[c, c]
            fitted = 0.0
            for i in range(p):
                theta[row, i] = a[i, p] / scale[i]
                first_column[row, i] = a[i, p + 1] / scale[i]
                fitted += rhs[s, columns[t, i]] * theta[row, i]
            rss[row] = yy - fitted
    return rss, theta, first_column
