"""Batch least-squares fit of the temperature-rise model: the baseline a user would otherwise reach for."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mtident._typing import FloatArray
from mtident.thermal.model import rise_curve

__all__ = ["LeastSquaresFit", "fit_rise", "cramer_rao_bound"]


@dataclass(frozen=True, slots=True)
class LeastSquaresFit:
    """Estimates [T₀, λ, T∞] per sensor (S, 3), their covariance (S, 3, 3) and residual σ (S,)."""

    params: FloatArray
    cov: FloatArray
    residual_sigma: FloatArray


def fit_rise(time_min: FloatArray, values: FloatArray, guess: FloatArray) -> LeastSquaresFit:
    """Fit T(t) = T∞ + (T₀ − T∞)e^(−λt) to each column of ``values`` with scipy's curve_fit.

    The covariance is curve_fit's, scaled by the residual variance
    (``absolute_sigma=False``), so it needs no noise level from the user.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
    values : ndarray, shape (N, S)
        NaN samples are left out.
    guess : ndarray, shape (S, 3)
        Starting point [T₀, λ, T∞].
    """
    from scipy.optimize import curve_fit  # here, not at the top: it costs ~0.3 s of start-up

    params, covs, sigmas = [], [], []
    for s in range(values.shape[1]):
        ok = np.isfinite(values[:, s])
        t, y = time_min[ok], values[ok, s]
        try:
            p, c = curve_fit(rise_curve, t, y, p0=guess[s], bounds=([-np.inf, 1e-6, -np.inf], [np.inf, 10.0, np.inf]), max_nfev=2000)
        except RuntimeError:
            p, c = np.asarray(guess[s], dtype=float), np.full((3, 3), np.inf)
        if not np.all(np.isfinite(c)):
            c = np.diag(np.full(3, 1e12))
        params.append(p)
        covs.append(c)
        resid = y - rise_curve(t, *p)
        sigmas.append(np.sqrt(np.sum(resid**2) / max(len(y) - 3, 1)))
    return LeastSquaresFit(np.array(params), np.array(covs), np.array(sigmas))


def cramer_rao_bound(time_min: FloatArray, start_C: float, rate_per_min: float, steady_C: float, sigma_C: float) -> FloatArray:
    """Cramér-Rao bound (covariance, 3×3) of [T₀, λ, T∞] for white noise σ at the sample times.

    Inverse of the Fisher information JᵀJ/σ², J the sensitivities of T(t).
    """
    t = np.asarray(time_min, dtype=float)
    decay = np.exp(-rate_per_min * t)
    jac = np.column_stack([decay, -(start_C - steady_C) * t * decay, 1.0 - decay])
    return np.linalg.inv(jac.T @ jac / sigma_C**2)
