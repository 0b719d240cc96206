"""The unscented transform through the transition and the measurement models.

Dense form (Xia et al. 2014 Eqs 8-17, as filterpy) and square-root form (Yu et al. 2019
Eqs 7 and 10; van der Merwe & Wan 2001): the weighted deviations are
triangularised by QR together with √Q (or √R) and the centre point is added by a
rank-1 Cholesky update or downdate, with the sign of W₀⁽ᶜ⁾.

Model functions are called **once on all sigma points** of all filters: a
transition receives an array of shape (..., 2n+1, n) and returns the same shape.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mtident._typing import FloatArray
from mtident.ukf.linalg import cholesky_update, lower_factor_from_qr, safe_cholesky, symmetrize, weighted_outer
from mtident.ukf.sigma_points import SigmaWeights, sigma_points

__all__ = [
    "ModelFunction",
    "Prior",
    "MeasurementMoments",
    "propagate",
    "measurement_moments",
    "sqrt_factor",
]

ModelFunction = Callable[[FloatArray], FloatArray]


@dataclass(frozen=True, slots=True)
class Prior:
    """The a-priori (predicted) state of a batch of filters.

    Attributes
    ----------
    mean : ndarray, shape (..., n)
    cov : ndarray, shape (..., n, n)
        Predicted covariance including Q (dense form) — also kept in the
        square-root form because the adaptive law's search needs it.
    chol : ndarray, shape (..., n, n) or None
        Lower factor of ``cov`` from the QR/cholupdate (square-root form only).
    sigmas : ndarray, shape (..., 2n+1, n)
        The propagated sigma points f(Xᵢ).
    """

    mean: FloatArray
    cov: FloatArray
    chol: FloatArray | None
    sigmas: FloatArray


@dataclass(frozen=True, slots=True)
class MeasurementMoments:
    """Predicted measurement statistics without R (Eqs 14-17).

    Attributes
    ----------
    mean : ndarray, shape (..., m)
        ŷ⁻, the weighted mean of the measured sigma points.
    deviations : ndarray, shape (..., 2n+1, m)
        The measured sigma points less ``mean``.
    cov_without_noise : ndarray, shape (..., m, m)
        Σ Wᶜᵢ (ŷᵢ − ŷ⁻)(ŷᵢ − ŷ⁻)ᵀ; R is added to it to make Py.
    cross_cov : ndarray, shape (..., n, m)
        Pxy, the cross-covariance of the sigma points and their measurements.
    """

    mean: FloatArray  # (..., m)
    deviations: FloatArray  # (..., 2n+1, m)
    cov_without_noise: FloatArray  # (..., m, m)
    cross_cov: FloatArray  # (..., n, m)


def sqrt_factor(deviations: FloatArray, noise_chol: FloatArray, weights: SigmaWeights, stage: str) -> FloatArray:
    """Lower factor of Σ Wᶜᵢ dᵢdᵢᵀ + N from QR of [√Wᶜ₁ d₁..₂ₙ, √N] and a rank-1 update with d₀.

    Parameters
    ----------
    deviations : ndarray, shape (..., 2n+1, k)
        Sigma-point deviations from their weighted mean.
    noise_chol : ndarray, shape (..., k, k)
        Lower factor of the additive noise covariance N.
    weights : SigmaWeights
    stage : str
        Named in the error if the rank-1 downdate fails.
    """
    stacked = np.concatenate(
        [np.sqrt(weights.cov[1]) * deviations[..., 1:, :], np.swapaxes(noise_chol, -1, -2)], axis=-2
    )
    lower = lower_factor_from_qr(np.swapaxes(stacked, -1, -2))
    w0 = float(weights.cov[0])
    return cholesky_update(lower, np.sqrt(abs(w0)) * deviations[..., 0, :], np.sign(w0) or 1.0, stage)


def propagate(
    mean: FloatArray,
    chol: FloatArray,
    transition: ModelFunction,
    process_cov: FloatArray,
    weights: SigmaWeights,
    square_root: bool,
) -> Prior:
    """Time update: sigma points of N(mean, chol cholᵀ) through the transition (Eqs 5-10).

    Parameters
    ----------
    mean : ndarray, shape (..., n)
        Posterior mean of each filter.
    chol : ndarray, shape (..., n, n)
        Lower Cholesky factor of its posterior covariance.
    transition : callable
        f, called once on all sigma points, shape (..., 2n+1, n) in and out.
    process_cov : ndarray, shape (..., n, n)
        Q, added to the propagated covariance.
    weights : SigmaWeights
        Sigma-point spread and weights.
    square_root : bool
        Also form the lower factor of the predicted covariance by QR and a rank-1 update (square-root
        form).

    Returns
    -------
    Prior
        Predicted mean, covariance, its lower factor (square-root form only) and the propagated
        sigma points.

    Raises
    ------
    CovarianceError
        In the square-root form, Q is not positive definite or the rank-1 downdate with the centre
        point fails.
    """
    points = sigma_points(mean, chol, weights)
    propagated = transition(points)
    prior_mean = weights.mean @ propagated
    deviations = propagated - prior_mean[..., None, :]
    cov = symmetrize(weighted_outer(weights.cov, deviations, deviations) + process_cov)
    prior_chol = None
    if square_root:
        process_chol = safe_cholesky(process_cov, "square root of the process noise Q")
        prior_chol = sqrt_factor(deviations, process_chol, weights, "predict: rank-1 update with the centre point")
    return Prior(mean=prior_mean, cov=cov, chol=prior_chol, sigmas=propagated)


def measurement_moments(
    prior: Prior, measurement: ModelFunction, weights: SigmaWeights, redraw: bool
) -> MeasurementMoments:
    """Measurement update moments (Eqs 14-17).

    With ``redraw=False`` the measurement sigma points are the propagated points
    (Xia et al. 2014, filterpy). With ``redraw=True`` they are drawn anew from the
    predicted mean and covariance (Yu et al. 2019 Eq. 8), which lets Q reach the gain.

    Parameters
    ----------
    prior : Prior
        The predicted state of each filter, from :func:`propagate`.
    measurement : callable
        h, called once on all sigma points: (..., 2n+1, n) in, (..., 2n+1, m) out.
    weights : SigmaWeights
        Sigma-point spread and weights.
    redraw : bool
        Draw new sigma points from the prior's mean and covariance instead of reusing the propagated ones.

    Returns
    -------
    MeasurementMoments
        The predicted measurement's mean, deviations, covariance without R, and the cross-covariance.

    Raises
    ------
    CovarianceError
        With ``redraw`` in the dense form, the predicted covariance is not positive definite.
    """
    if redraw:
        chol = prior.chol if prior.chol is not None else safe_cholesky(prior.cov, "redraw sigma points from the prior")
        points = sigma_points(prior.mean, chol, weights)
    else:
        points = prior.sigmas
    outputs = measurement(points)
    mean = weights.mean @ outputs
    dy = outputs - mean[..., None, :]
    dx = points - prior.mean[..., None, :]
    return MeasurementMoments(
        mean=mean,
        deviations=dy,
        cov_without_noise=weighted_outer(weights.cov, dy, dy),
        cross_cov=weighted_outer(weights.cov, dx, dy),
    )
