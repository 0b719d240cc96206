"""The UKF step and the filter loop, standard or square-root, with plug-in adaptation.

``filter_step`` is the online API: one measurement for every filter of a batch.
``run_filter`` loops over it and returns stacked arrays; ``forecast`` runs the
time update alone (prediction after the identification time).

Shapes: a batch of filters has leading axes ``...``; the state has n components,
the measurement m. Measurements that are NaN are treated as missing: that
filter keeps its prediction for the step.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mtident._typing import BoolArray, FloatArray
from mtident.exceptions import CovarianceError, DimensionError
from mtident.ukf.adaptation import AdaptiveLaw, FadingFactor, fading_value, residual_memory
from mtident.ukf.linalg import cholesky_downdate_or_mask, lower_factor_from_qr, safe_cholesky, solve_gain, symmetrize
from mtident.ukf.sigma_points import MerweScaledSigmaPoints, SigmaWeights
from mtident.ukf.transform import MeasurementMoments, ModelFunction, Prior, measurement_moments, propagate, sqrt_factor

__all__ = [
    "GaussianState",
    "FilterConfig",
    "FilterCarry",
    "StepInfo",
    "FilterRecord",
    "initial_carry",
    "filter_step",
    "run_filter",
    "transition_at",
    "forecast",
]

StepTransition = Callable[[FloatArray, int], FloatArray]


@dataclass(frozen=True, slots=True)
class GaussianState:
    """Mean (..., n) and covariance (..., n, n) of a batch of Gaussian beliefs.

    Attributes
    ----------
    mean : ndarray, shape (..., n)
        The means of the beliefs, in the state's units.
    cov : ndarray, shape (..., n, n)
        Their covariances (symmetric positive definite).
    """

    mean: FloatArray
    cov: FloatArray


@dataclass(frozen=True, slots=True)
class FilterConfig:
    """Which UKF: the standard one plus zero or more adaptations.

    Parameters
    ----------
    sigma_points : MerweScaledSigmaPoints
        The sigma-point scheme (α, β, κ).
    square_root : bool
        Carry the Cholesky factor instead of P (Yu et al. 2019 Eqs 2-13).
    redraw : bool
        Draw the measurement sigma points anew from the prior (Yu et al. 2019 Eq. 8)
        instead of reusing the propagated points (Xia et al. 2014, filterpy).
    fading : FadingFactor, optional
        Fading factor on the gain (Yu et al. 2019 Eqs 15-29).
    adaptive_law : AdaptiveLaw, optional
        Q/R adaptive law (Xia et al. 2014 §2.2). Scalar measurements only.
    name : str
        Named in error messages.
    """

    sigma_points: MerweScaledSigmaPoints = MerweScaledSigmaPoints()
    square_root: bool = False
    redraw: bool = False
    fading: FadingFactor | None = None
    adaptive_law: AdaptiveLaw | None = None
    name: str = "ukf"


@dataclass(frozen=True, slots=True)
class FilterCarry:
    """Everything a batch of filters carries from one step to the next.

    ``chol`` is the lower Cholesky factor of the posterior covariance in the
    square-root form; ``cov`` in the standard form (the other is None).

    Attributes
    ----------
    mean : ndarray, shape (..., n)
        Posterior mean x̂ₖ.
    cov : ndarray, shape (..., n, n) or None
        Posterior covariance Pₖ (standard form), else None.
    chol : ndarray, shape (..., n, n) or None
        Lower Cholesky factor of Pₖ (square-root form), else None.
    process_cov : ndarray, shape (..., n, n)
        Q for the next step, as the adaptive law has left it.
    emission_cov : ndarray, shape (..., m, m)
        R for the next step, as the adaptive law has left it.
    residual_memory : ndarray, shape (..., m, m)
        Vₖ of the fading factor (zeros without one).
    updates_seen : ndarray, shape (...)
        Measurement updates done so far (steps with a missing measurement do not count); 0 before
        the first, where V₀ = ε₀ε₀ᵀ.
    """

    mean: FloatArray
    cov: FloatArray | None
    chol: FloatArray | None
    process_cov: FloatArray
    emission_cov: FloatArray
    residual_memory: FloatArray
    updates_seen: FloatArray

    def covariance(self) -> FloatArray:
        """The posterior covariance, formed from the factor in the square-root form."""
        if self.cov is not None:
            return self.cov
        assert self.chol is not None
        return self.chol @ np.swapaxes(self.chol, -1, -2)


@dataclass(frozen=True, slots=True)
class StepInfo:
    """Diagnostics of one step, each with the batch shape in front.

    Attributes
    ----------
    innovation : ndarray, shape (..., m)
        εₖ = yₖ − ŷₖ⁻, NaN where the measurement was missing.
    innovation_cov : ndarray, shape (..., m, m)
        Py, the predicted measurement covariance with R.
    fading : ndarray, shape (...)
        αₖ, 1 without a fading factor.
    posterior_residual : ndarray, shape (..., m)
        γₖ = yₖ − h(x̂ₖ), NaN without an adaptive law or a measurement.
    adapted : ndarray of bool, shape (...)
        The adaptive law changed Q and R at this step.
    reached : ndarray of bool, shape (...)
        |γ| ≤ C after the adaptation (True where none was needed).
    """

    innovation: FloatArray  # (..., m), NaN where the measurement was missing
    innovation_cov: FloatArray  # (..., m, m)
    fading: FloatArray  # (...,) αₖ, 1 without fading
    posterior_residual: FloatArray  # (..., m) γₖ = yₖ − h(x̂ₖ), NaN without an adaptive law
    adapted: BoolArray  # (...,) the adaptive law changed Q and R
    reached: BoolArray  # (...,) |γ| ≤ C after the adaptation (True where nothing was needed)


@dataclass(frozen=True, slots=True)
class FilterRecord:
    """Stacked results of ``run_filter``; the first axis is the step.

    Attributes
    ----------
    means : ndarray, shape (T, ..., n)
        Posterior mean after each step's update.
    covs : ndarray, shape (T, ..., n, n)
        Posterior covariance after each step (formed from the factor in the square-root form).
    process_covs : ndarray, shape (T, ..., n, n)
        Q after each step.
    emission_covs : ndarray, shape (T, ..., m, m)
        R after each step.
    innovations : ndarray, shape (T, ..., m)
        εₖ, NaN where the measurement was missing.
    innovation_covs : ndarray, shape (T, ..., m, m)
        Py of each step.
    fading : ndarray, shape (T, ...)
        αₖ of each step (1 without a fading factor).
    adapted : ndarray of bool, shape (T, ...)
        Steps at which the adaptive law changed Q and R.
    final : FilterCarry
        The carry after the last step, to go on from.
    """

    means: FloatArray  # (T, ..., n)
    covs: FloatArray  # (T, ..., n, n)
    process_covs: FloatArray  # (T, ..., n, n)
    emission_covs: FloatArray  # (T, ..., m, m)
    innovations: FloatArray  # (T, ..., m)
    innovation_covs: FloatArray  # (T, ..., m, m)
    fading: FloatArray  # (T, ...)
    adapted: BoolArray  # (T, ...)
    final: FilterCarry


def initial_carry(
    initial: GaussianState, process_cov: FloatArray, emission_cov: FloatArray, config: FilterConfig
) -> FilterCarry:
    """Start a batch of filters; Q and R broadcast to the batch shape of ``initial``.

    Parameters
    ----------
    initial : GaussianState
        x̂₀ and P₀, shapes (..., n) and (..., n, n); P₀ broadcast to the mean's batch shape.
    process_cov : ndarray, shape (..., n, n)
        Q.
    emission_cov : ndarray, shape (..., m, m)
        R; its last axis gives m.
    config : FilterConfig
        With ``square_root`` the carry holds P₀'s Cholesky factor instead of P₀.

    Returns
    -------
    FilterCarry
        No update seen yet, and the fading factor's residual memory at zero.

    Raises
    ------
    DimensionError
        P₀ or Q not (..., n, n), or an adaptive law with m other than 1.
    CovarianceError
        In the square-root form, P₀ is not positive definite.
    """
    batch = initial.mean.shape[:-1]
    n = initial.mean.shape[-1]
    m = np.shape(emission_cov)[-1]
    if initial.cov.shape[-2:] != (n, n):
        msg = f"initial covariance: expected shape (..., {n}, {n}), found {initial.cov.shape}"
        raise DimensionError(msg)
    if np.shape(process_cov)[-2:] != (n, n):
        msg = f"process noise covariance Q: expected shape (..., {n}, {n}), found {np.shape(process_cov)}"
        raise DimensionError(msg)
    if config.adaptive_law is not None and m != 1:
        msg = f"the adaptive law (Xia 2014) is defined for a scalar measurement; found m = {m}"
        raise DimensionError(msg)
    cov = np.broadcast_to(np.asarray(initial.cov, dtype=float), (*batch, n, n)).copy()
    chol = safe_cholesky(cov, f"initial covariance P0 of filter {config.name!r}") if config.square_root else None
    return FilterCarry(
        mean=np.asarray(initial.mean, dtype=float).copy(),
        cov=None if config.square_root else symmetrize(cov),
        chol=chol,
        process_cov=np.broadcast_to(np.asarray(process_cov, dtype=float), (*batch, n, n)).copy(),
        emission_cov=np.broadcast_to(np.asarray(emission_cov, dtype=float), (*batch, m, m)).copy(),
        residual_memory=np.zeros((*batch, m, m)),
        updates_seen=np.zeros(batch),
    )


def _condition(
    prior: Prior,
    moments: MeasurementMoments,
    innovation: FloatArray,
    emission_cov: FloatArray,
    alpha: FloatArray,
    config: FilterConfig,
    weights: SigmaWeights,
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Posterior mean and covariance (or factor) for gain K = α Pxy Py⁻¹ (Eqs 18-20, Yu et al. 2019 Eqs 12-13).

    With a fading factor in the "covariance" form, α scales P⁻ (and so Pxy and
    the sigma-point part of Py) instead of the gain.
    """
    if config.fading is not None and config.fading.form == "covariance":
        prior, moments = _inflate(prior, moments, alpha)
        alpha = np.ones_like(alpha)
    coefficient = 2.0 * alpha - alpha**2  # P⁺ = P⁻ − (2α − α²) Pxy Py⁻¹ Pxyᵀ, see FadingFactor
    pxy = moments.cross_cov
    if config.square_root:
        assert prior.chol is not None
        emission_chol = safe_cholesky(emission_cov, "square root of the measurement noise R")
        sy = sqrt_factor(moments.deviations, emission_chol, weights, "update: rank-1 update of the innovation factor")
        # U = Pxy S_y⁻ᵀ, so U Uᵀ = Pxy Py⁻¹ Pxyᵀ and K = α U S_y⁻¹
        u = np.swapaxes(np.linalg.solve(sy, np.swapaxes(pxy, -1, -2)), -1, -2)
        whitened = np.linalg.solve(sy, innovation[..., None])[..., 0]
        mean = prior.mean + alpha[..., None] * np.einsum("...ij,...j->...i", u, whitened)
        chol = prior.chol
        sign = np.where(coefficient >= 0.0, -1.0, 1.0)
        scale = np.sqrt(np.abs(coefficient))[..., None]
        failed = np.zeros(chol.shape[:-2], dtype=bool)
        for j in range(u.shape[-1]):
            chol, bad = cholesky_downdate_or_mask(chol, scale * u[..., :, j], sign)
            failed |= bad
        if np.any(failed):
            chol = np.where(failed[..., None, None], _joseph_factor(prior, pxy, emission_chol, alpha, sy), chol)
        innovation_cov = sy @ np.swapaxes(sy, -1, -2)
        return mean, chol, innovation_cov
    innovation_cov = moments.cov_without_noise + emission_cov
    mean, gain = _gain_update(prior.mean, innovation_cov, pxy, innovation, alpha)
    cov = symmetrize(prior.cov - coefficient[..., None, None] * gain @ np.swapaxes(pxy, -1, -2))
    return mean, cov, innovation_cov


def _gain_update(
    prior_mean: FloatArray, innovation_cov: FloatArray, cross_cov: FloatArray, innovation: FloatArray, alpha: FloatArray
) -> tuple[FloatArray, FloatArray]:
    """x⁺ = x⁻ + α K ν with K = Pxy Py⁻¹, batched over all leading axes; returns (x⁺, K)."""
    gain = solve_gain(innovation_cov, cross_cov)
    return prior_mean + alpha[..., None] * np.einsum("...ij,...j->...i", gain, innovation), gain


def _inflate(prior: Prior, moments: MeasurementMoments, alpha: FloatArray) -> tuple[Prior, MeasurementMoments]:
    """P⁻ ← α P⁻ for each filter: the fading factor of a strong-tracking filter."""
    a = alpha[..., None, None]
    root = np.sqrt(alpha)[..., None, None]
    inflated = Prior(prior.mean, a * prior.cov, None if prior.chol is None else root * prior.chol, prior.sigmas)
    return inflated, MeasurementMoments(
        moments.mean, root * moments.deviations, a * moments.cov_without_noise, a * moments.cross_cov
    )


def _joseph_factor(
    prior: Prior, pxy: FloatArray, emission_chol: FloatArray, alpha: FloatArray, sy: FloatArray
) -> FloatArray:
    """Fallback when the downdate fails: factor of the Joseph form (I−KH)P⁻(I−KH)ᵀ + KRKᵀ by QR.

    H = Pxyᵀ P⁻⁻¹ is the statistical linearisation of the measurement. A sum of
    two PSD terms, so it cannot turn indefinite, where the downdate P⁻ − UUᵀ of a
    nearly singular posterior can fail to rounding (very precise measurements).
    """
    assert prior.chol is not None
    n = prior.mean.shape[-1]
    h = np.swapaxes(np.linalg.pinv(prior.cov, hermitian=True) @ pxy, -1, -2)  # (..., m, n); P⁻ may be singular
    u_t = np.linalg.solve(sy, np.swapaxes(pxy, -1, -2))
    gain = alpha[..., None, None] * np.swapaxes(np.linalg.solve(np.swapaxes(sy, -1, -2), u_t), -1, -2)
    residual_map = np.eye(n) - gain @ h
    columns = np.concatenate([residual_map @ prior.chol, gain @ emission_chol], axis=-1)
    return lower_factor_from_qr(columns)


def _fading(
    config: FilterConfig, memory: FloatArray, moments: MeasurementMoments, emission_cov: FloatArray
) -> FloatArray:
    if config.fading is None:
        return np.ones(memory.shape[:-2])
    return fading_value(config.fading, memory, moments.cov_without_noise + emission_cov, emission_cov)


def _with_process_cov(
    prior: Prior, old: FloatArray, new: FloatArray, config: FilterConfig, weights: SigmaWeights
) -> Prior:
    """The same prior with Q replaced (the sigma points do not change)."""
    cov = symmetrize(prior.cov + (new - old))
    chol = None
    if config.square_root:
        deviations = prior.sigmas - prior.mean[..., None, :]
        chol = sqrt_factor(
            deviations,
            safe_cholesky(new, "square root of the adapted Q"),
            weights,
            "predict: rank-1 update with the centre point",
        )
    return Prior(mean=prior.mean, cov=cov, chol=chol, sigmas=prior.sigmas)


def _search_emission_cov(
    law: AdaptiveLaw,
    config: FilterConfig,
    prior: Prior,
    moments: MeasurementMoments,
    innovation: FloatArray,
    y: FloatArray,
    measurement: ModelFunction,
    emission_cov: FloatArray,
    direction: FloatArray,
    memory: FloatArray,
) -> tuple[FloatArray, BoolArray]:
    """R for each filter from the bounded search of the adaptive law, all candidates at once."""
    up, down = law.search_multipliers()
    result = emission_cov.copy()
    reached = np.ones(direction.shape, dtype=bool)
    for sign, multipliers in ((1.0, up), (-1.0, down)):
        active = direction == sign
        if not np.any(active):
            continue
        candidates = emission_cov[..., None, :, :] * multipliers[:, None, None]  # (..., J, 1, 1)
        pyy = moments.cov_without_noise[..., None, :, :] + candidates
        pxy = moments.cross_cov[..., None, :, :]
        if config.fading is None:
            alpha = np.ones(pyy.shape[:-2])
        else:
            alpha = fading_value(config.fading, memory[..., None, :, :], pyy, candidates)
            if config.fading.form == "covariance":
                pyy = alpha[..., None, None] * moments.cov_without_noise[..., None, :, :] + candidates
                pxy = alpha[..., None, None] * pxy
                alpha = np.ones_like(alpha)
        # the candidates' posterior means, exactly as _condition's (dense) update computes them
        means, _ = _gain_update(prior.mean[..., None, :], pyy, pxy, innovation[..., None, :], alpha)
        gamma = np.abs(y[..., None, :] - measurement(means))[..., 0]  # (..., J)
        ok = gamma <= np.asarray(law.threshold)[..., None]
        chosen = np.where(ok.any(axis=-1), np.argmax(ok, axis=-1), np.argmin(gamma, axis=-1))
        picked = np.take_along_axis(candidates, chosen[..., None, None, None], axis=-3)[..., 0, :, :]
        result = np.where(active[..., None, None], picked, result)
        reached = np.where(active, ok.any(axis=-1), reached)
    return result, reached


def filter_step(
    carry: FilterCarry,
    y: FloatArray,
    transition: ModelFunction,
    measurement: ModelFunction,
    config: FilterConfig,
    weights: SigmaWeights | None = None,
) -> tuple[FilterCarry, StepInfo]:
    """Advance a batch of filters by one measurement.

    Parameters
    ----------
    carry : FilterCarry
        The state after the previous step (from :func:`initial_carry`).
    y : ndarray, shape (..., m)
        Measurements; a NaN component marks that filter's measurement as missing.
    transition, measurement : callable
        Called once each on all sigma points, shape (..., 2n+1, n).
    config : FilterConfig
    weights : SigmaWeights, optional
        Precomputed ``config.sigma_points.weights(n)`` (saves time in loops).

    Returns
    -------
    FilterCarry, StepInfo

    Raises
    ------
    CovarianceError
        A covariance lost positive definiteness; the message names the stage.
    """
    w = weights if weights is not None else config.sigma_points.weights(carry.mean.shape[-1])
    if config.square_root:
        chol = carry.chol
    else:
        assert carry.cov is not None
        chol = safe_cholesky(carry.cov, "sigma points of the previous posterior")
    assert chol is not None
    prior = propagate(carry.mean, chol, transition, carry.process_cov, w, config.square_root)
    observed = np.all(np.isfinite(y), axis=-1)
    y_safe = np.where(observed[..., None], y, 0.0)
    moments = measurement_moments(prior, measurement, w, config.redraw)
    innovation = np.where(observed[..., None], y_safe - moments.mean, 0.0)

    first = carry.updates_seen == 0
    memory = carry.residual_memory
    if config.fading is not None:
        memory = residual_memory(config.fading, memory, first, innovation)
    process_cov, emission_cov = carry.process_cov, carry.emission_cov
    alpha = _fading(config, memory, moments, emission_cov)
    mean, spread, innovation_cov = _condition(prior, moments, innovation, emission_cov, alpha, config, w)

    adapted = np.zeros(observed.shape, dtype=bool)
    reached = np.ones(observed.shape, dtype=bool)
    law = config.adaptive_law
    gamma = np.full_like(innovation, np.nan)  # computed only where the adaptive law needs it
    if law is not None:
        gamma = y_safe - measurement(mean[..., None, :])[..., 0, :]
        g = gamma[..., 0]
        psi = innovation[..., 0]
        adapted = observed & (np.abs(g) > law.threshold)
        if np.any(adapted):
            q_scale = np.where(adapted, np.where(g < 0.0, law.q_increase, law.q_decrease), 1.0)
            direction = np.where(adapted, -np.sign(g * psi), 0.0)
            new_q = process_cov * q_scale[..., None, None]
            prior = _with_process_cov(prior, process_cov, new_q, config, w)
            if config.redraw:
                moments = measurement_moments(prior, measurement, w, config.redraw)
                innovation = np.where(observed[..., None], y_safe - moments.mean, 0.0)
            new_r, reached = _search_emission_cov(
                law, config, prior, moments, innovation, y_safe, measurement, emission_cov, direction, memory
            )
            process_cov, emission_cov = new_q, new_r
            alpha = _fading(config, memory, moments, emission_cov)
            mean, spread, innovation_cov = _condition(prior, moments, innovation, emission_cov, alpha, config, w)
            gamma = y_safe - measurement(mean[..., None, :])[..., 0, :]

    if config.square_root:
        new_chol, new_cov = spread, None
    else:
        new_chol, new_cov = None, spread
    if not np.all(observed):
        # A missing measurement leaves the prediction as the posterior.
        keep = observed[..., None, None]
        mean = np.where(observed[..., None], mean, prior.mean)
        new_chol = None if new_chol is None or prior.chol is None else np.where(keep, new_chol, prior.chol)
        new_cov = None if new_cov is None or prior.cov is None else np.where(keep, new_cov, prior.cov)
        memory = np.where(keep, memory, carry.residual_memory)
    new_carry = FilterCarry(
        mean=mean,
        cov=new_cov,
        chol=new_chol,
        process_cov=process_cov,
        emission_cov=emission_cov,
        residual_memory=memory,
        updates_seen=carry.updates_seen + observed,
    )
    info = StepInfo(
        innovation=np.where(observed[..., None], innovation, np.nan),
        innovation_cov=innovation_cov,
        fading=alpha,
        posterior_residual=np.where(observed[..., None], gamma, np.nan),
        adapted=adapted,
        reached=reached,
    )
    return new_carry, info


def transition_at(transition: StepTransition, k: int) -> Callable[[FloatArray], FloatArray]:
    """The transition of step ``k`` as a function of the sigma points alone.

    Parameters
    ----------
    transition : callable
        ``transition(points, k)``, sigma points (..., 2n+1, n) from step k−1 to step k.
    k : int
        The step.

    Returns
    -------
    callable
        ``step(points)`` = ``transition(points, k)``: the form :func:`filter_step` calls.
    """

    def step(points: FloatArray) -> FloatArray:
        return transition(points, k)

    return step


def run_filter(
    initial: GaussianState,
    emissions: FloatArray,
    transition: StepTransition,
    measurement: ModelFunction,
    process_cov: FloatArray,
    emission_cov: FloatArray,
    config: FilterConfig = FilterConfig(),
    progress: Callable[[int], None] | None = None,
) -> FilterRecord:
    """Filter a sequence of measurements for a batch of filters.

    Parameters
    ----------
    initial : GaussianState
        x̂₀ and P₀, shapes (..., n) and (..., n, n).
    emissions : ndarray, shape (T, ..., m)
        yₖ for k = 1..T (NaN = missing).
    transition : callable
        ``transition(points, k)`` propagates sigma points (..., 2n+1, n) from step
        k−1 to step k (k counts from 0 for the first measurement).
    measurement : callable
        ``measurement(points)`` maps (..., S, n) to (..., S, m).
    process_cov, emission_cov : ndarray
        Q (..., n, n) and R (..., m, m), broadcast to the batch.
    config : FilterConfig
    progress : callable, optional
        Called with the step index after each step.

    Returns
    -------
    FilterRecord

    Raises
    ------
    CovarianceError
        Names the filter, the step, the batch index and the smallest eigenvalue.

    Examples
    --------
    A random walk seen directly. With redrawn measurement points the UKF is the
    Kalman filter (gain 2/3); Xia et al. 2014's propagated points leave Q out of the
    innovation covariance (gain 1/2), which only matters where Q is not small.

    >>> x0 = GaussianState(np.zeros(1), np.eye(1))
    >>> walk, seen = (lambda p, k: p), (lambda p: p)
    >>> rec = run_filter(x0, np.array([[1.0]]), walk, seen, np.eye(1), np.eye(1), FilterConfig(redraw=True))
    >>> rec.means[0].round(6).tolist(), rec.covs[0].round(6).tolist()
    ([0.666667], [[0.666667]])
    >>> run_filter(x0, np.array([[1.0]]), walk, seen, np.eye(1), np.eye(1)).means[0].tolist()
    [0.5]
    """
    emissions = np.asarray(emissions, dtype=float)
    carry = initial_carry(initial, process_cov, emission_cov, config)
    weights = config.sigma_points.weights(carry.mean.shape[-1])
    steps = emissions.shape[0]
    shape = carry.mean.shape
    n, m = shape[-1], emissions.shape[-1]
    means = np.empty((steps, *shape))
    covs = np.empty((steps, *shape, n))
    qs = np.empty((steps, *shape, n))
    rs = np.empty((steps, *shape[:-1], m, m))
    innovations = np.empty((steps, *shape[:-1], m))
    innovation_covs = np.empty((steps, *shape[:-1], m, m))
    fading = np.empty((steps, *shape[:-1]))
    adapted = np.empty((steps, *shape[:-1]), dtype=bool)
    for k in range(steps):
        try:
            carry, info = filter_step(carry, emissions[k], transition_at(transition, k), measurement, config, weights)
        except CovarianceError as exc:
            raise exc.at(k, config.name) from exc
        means[k] = carry.mean
        covs[k] = carry.covariance()
        qs[k] = carry.process_cov
        rs[k] = carry.emission_cov
        innovations[k] = info.innovation
        innovation_covs[k] = info.innovation_cov
        fading[k] = info.fading
        adapted[k] = info.adapted
        if progress is not None:
            progress(k)
    return FilterRecord(means, covs, qs, rs, innovations, innovation_covs, fading, adapted, carry)


def forecast(
    state: GaussianState,
    transition: StepTransition,
    process_cov: FloatArray,
    steps: int,
    config: FilterConfig = FilterConfig(),
) -> GaussianState:
    """Time updates alone from ``state``: the deterministic prediction with its covariance.

    Returns a GaussianState with a leading step axis (steps, ..., n). Step k
    calls ``transition(points, k)``.

    Parameters
    ----------
    state : GaussianState
        Where to start: mean (..., n) and covariance (..., n, n), e.g. the filter's last posterior.
    transition : callable
        ``transition(points, k)`` propagates sigma points (..., 2n+1, n) by one step; k counts
        from 0 for the first step after ``state``.
    process_cov : ndarray, shape (..., n, n)
        Q, added at every step.
    steps : int
        How many steps to predict.
    config : FilterConfig
        Its sigma points and name; the standard form is used whatever ``square_root`` says.

    Returns
    -------
    GaussianState
        Means (steps, ..., n) and covariances (steps, ..., n, n); index 0 is one step after ``state``.

    Raises
    ------
    CovarianceError
        A covariance lost positive definiteness; names the step and the filter.
    """
    weights = config.sigma_points.weights(state.mean.shape[-1])
    mean, cov = np.asarray(state.mean, dtype=float), np.asarray(state.cov, dtype=float)
    means = np.empty((steps, *mean.shape))
    covs = np.empty((steps, *cov.shape))
    for k in range(steps):
        try:
            chol = safe_cholesky(cov, "forecast: sigma points")
        except CovarianceError as exc:
            raise exc.at(k, config.name) from exc
        prior = propagate(mean, chol, transition_at(transition, k), process_cov, weights, False)
        mean, cov = prior.mean, prior.cov
        means[k], covs[k] = mean, cov
    return GaussianState(means, covs)
