"""One sum-of-modes fit and its slopes in log τ, compiled with numba (the hot loop of the
refinement in :mod:`mtident.thermal.modes`, called some thousand times per estimate).

The same arithmetic as ``modes._fit`` and ``modes._fit_with_slopes`` for one model: the
design matrix (the constant, each mode's e^(−u/τ), with a room each mode's lag of the room
less the room), the penalised normal equations solved in normalised form, and the exact
variable-projection slopes of the residual sum of squares, of T∞ and of its variance.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from mtident._typing import FloatArray

__all__ = ["fit_one", "lag_rows"]

# the same ridge as modes._JITTER, and the room columns' forward-difference step
_JITTER = 1e-11
_DIFF_STEP = 1e-6


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
    u: FloatArray,
    time_min: FloatArray,
    weight: FloatArray,
    target: FloatArray,
    room: FloatArray,
    log_tau: FloatArray,
    penalty: FloatArray,
):  # noqa: ANN201  # pragma: no cover - compiled
    """The penalised least-squares fit of one model and its slopes in log τ.

    Parameters
    ----------
    u : (B,) minutes since the modes began; time_min : (B,) the bins' times (for the room's lag)
    weight : (B,) readings per bin; target : (B,) the readings (less the room) less the centring
    room : (B,) the room's readings, or an empty array without a room sensor
    log_tau : (k,); penalty : (p,) the priors' weights

    Returns
    -------
    rss, theta (p,), var_steady, direction (p,), d_rss (k,), d_steady (k,), d_var (k,)
    """
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
