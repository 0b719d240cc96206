"""Adaptation rules that plug into the UKF step.

* :class:`FadingFactor` — the fading factor of Yu et al. 2019 (Yu et al. 2019 Eqs 15-22),
  and with ``normalisation`` the residual-normalised factor of Eqs 23-29.
* :class:`AdaptiveLaw` — the Q/R adaptive law of Xia et al. 2014 (Xia et al. 2014 §2.2,
  Fig. 1; Yu et al. 2019 §1.3).

Both are frozen settings; the state they need (the residual memory Vₖ, the
current Q and R) travels in the filter carry, never inside these objects.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mtident._typing import FloatArray

__all__ = ["FadingFactor", "AdaptiveLaw", "residual_memory", "fading_value", "normalisation_from_reference"]


@dataclass(frozen=True, slots=True)
class FadingFactor:
    """Fading factor αₖ applied to the gain, Kₖ = αₖ Pxy Py⁻¹ (Yu et al. 2019 Eq. 12).

    Vₖ = (ξ Vₖ₋₁ + εₖεₖᵀ)/(1 + ξ) with V₀ = ε₀ε₀ᵀ (Eq. 22), Nₖ = Vₖ − ρRₖ and
    αₖ = max(1, tr Nₖ / tr(S_y S_yᵀ)) (Eqs 18, 21).

    Parameters
    ----------
    forgetting : float
        ξ, default 0.95 (Yu et al. 2019 §1.2).
    weakening : float
        ρ, default 3 (Yu et al. 2019 §1.2, after He et al. 2018).
    normalisation : ndarray, shape (m,), optional
        λ of Eqs 23-29: residuals are divided by it before Vₖ is formed. Build it
        with :func:`normalisation_from_reference`. For m = 1, Eq. 29 gives λ = 1
        and the normalised factor equals the plain one.
    max_factor : float
        Upper bound on αₖ (ours; the paper has none). Default 2: in the "gain"
        form, the largest α for which the update does not *increase* P. Beyond
        it the gain moves the estimate past the measurement by more than the
        prior error, the true error covariance grows by (α² − 2α)·Pxy Py⁻¹ Pxyᵀ,
        and combined with the adaptive law the filter diverges (seen on warm-up
        data started 1 °C off).
    form : {"gain", "covariance"}
        "gain" multiplies the gain by α as Yu et al. 2019 Eq. 12 writes it. "covariance"
        multiplies the predicted covariance P⁻ by α before the gain is formed, as
        strong-tracking filters do (Zhou & Frank 1996): the gain then grows
        towards, never past, the measurement and P stays positive definite for
        any α. The papers' presets use "gain"; mtident's data-driven tuning uses
        "covariance".

    Notes
    -----
    With λ we also scale R and S_y S_yᵀ by λ⁻¹(·)λ⁻¹ so that the ratio in Eq. 21
    compares like with like; for m = 1 this changes nothing.

    The covariance update with a faded gain uses the form valid for any gain,
    P⁺ = P⁻ − K Pxyᵀ − Pxy Kᵀ + K Py Kᵀ = P⁻ − (2α − α²) Pxy Py⁻¹ Pxyᵀ. Yu et al. 2019
    Eq. 13 (P⁺ = P⁻ − K Py Kᵀ) equals it only for α = 1 and makes P indefinite
    for large α.
    """

    forgetting: float = 0.95
    weakening: float = 3.0
    normalisation: FloatArray | None = None
    max_factor: float = 2.0
    form: str = "gain"


def normalisation_from_reference(reference_output: FloatArray) -> FloatArray:
    """λⱼ = y₀ⱼ √(m / Σ y₀ᵢ²) (Yu et al. 2019 Eq. 29) from prior knowledge of the outputs.

    Parameters
    ----------
    reference_output : ndarray, shape (..., m)
        y₀, typical magnitudes of the m outputs (in their own units; the sign is ignored, and not all
        may be zero).

    Returns
    -------
    ndarray, shape (..., m)
        λ, dimensionless ratios whose squares average to 1 over the outputs.

    Examples
    --------
    >>> normalisation_from_reference(np.array([3.0, 4.0])).round(4).tolist()
    [0.8485, 1.1314]
    """
    y0 = np.asarray(reference_output, dtype=float)
    normalisation: FloatArray = np.abs(y0) * np.sqrt(y0.shape[-1] / np.sum(y0**2, axis=-1, keepdims=True))
    return normalisation


def residual_memory(fading: FadingFactor, memory: FloatArray, first: FloatArray, innovation: FloatArray) -> FloatArray:
    """Vₖ of Eq. 22 (or V'ₖ of Eq. 25) for the new innovation εₖ, batched.

    Parameters
    ----------
    fading : FadingFactor
        Supplies ξ (``forgetting``) and λ (``normalisation``, which divides the innovation).
    memory : ndarray, shape (..., m, m)
        Vₖ₋₁ of each filter.
    first : ndarray of bool, shape (...)
        The filters at their first update, where V₀ = ε₀ε₀ᵀ replaces the memory.
    innovation : ndarray, shape (..., m)
        εₖ = yₖ − ŷₖ⁻, in the measurement's units.

    Returns
    -------
    ndarray, shape (..., m, m)
        Vₖ.
    """
    scaled = innovation if fading.normalisation is None else innovation / fading.normalisation
    outer = scaled[..., :, None] * scaled[..., None, :]
    xi = fading.forgetting
    updated: FloatArray = np.where(first[..., None, None], outer, (xi * memory + outer) / (1.0 + xi))
    return updated


def fading_value(
    fading: FadingFactor, memory: FloatArray, innovation_cov: FloatArray, emission_cov: FloatArray
) -> FloatArray:
    """αₖ = max(1, tr(Vₖ − ρR)/tr(Py)) (Eqs 18, 21), bounded by ``max_factor``, shape (...).

    Parameters
    ----------
    fading : FadingFactor
        Supplies ρ (``weakening``), λ (``normalisation``) and the bound ``max_factor``.
    memory : ndarray, shape (..., m, m)
        Vₖ from :func:`residual_memory`.
    innovation_cov : ndarray, shape (..., m, m)
        Py = S_y S_yᵀ, the predicted measurement covariance (R included).
    emission_cov : ndarray, shape (..., m, m)
        Rₖ, the measurement noise covariance.

    Returns
    -------
    ndarray, shape (...)
        αₖ, from 1 to ``max_factor``.
    """
    if fading.normalisation is not None:
        scale = fading.normalisation[..., :, None] * fading.normalisation[..., None, :]
        innovation_cov = innovation_cov / scale
        emission_cov = emission_cov / scale
    numerator = np.trace(memory - fading.weakening * emission_cov, axis1=-2, axis2=-1)
    denominator = np.trace(innovation_cov, axis1=-2, axis2=-1)
    factor: FloatArray = np.clip(numerator / denominator, 1.0, fading.max_factor)
    return factor


@dataclass(frozen=True, slots=True)
class AdaptiveLaw:
    """The adaptive law of Xia et al. 2014 for a scalar measurement.

    After the update, the a-posteriori residual γₖ = yₖ − h(x̂ₖ) is compared with
    the threshold C. Where |γₖ| > C, with ψₖ = yₖ − ŷₖ⁻ the a-priori residual:

    ======================  ===============  ==============
    case                    Q                R
    ======================  ===============  ==============
    γ < −C, ψ > 0           Q ← q_increase·Q  increase
    γ < −C, ψ < 0           Q ← q_increase·Q  decrease
    γ > +C, ψ > 0           Q ← q_decrease·Q  decrease
    γ > +C, ψ < 0           Q ← q_decrease·Q  increase
    ======================  ===============  ==============

    and the update is redone with the new Q and the first R in the search that
    brings |γ| ≤ C.

    Choices where the papers are ambiguous:

    * ``R_step = r_step_fraction · R`` is fixed at the start of each step's search
      (the R entering the step), and candidate j is ``R ± j·R_step`` (j = 1, 2, …),
      i.e. the step is *not* cumulative: after j tries R has moved by j·R_step.
    * The search is bounded: at most ``max_search_steps`` candidates, and a
      decrease stops before R would reach zero (so R stays ≥ R_step). If no
      candidate reaches |γ| ≤ C, the one with the smallest |γ| is taken and the
      step reports ``reached=False``.
    * All candidates are evaluated at once (vectorised), so the search costs one
      batched call of the measurement function.
    * For a measurement linear in the state with the propagated sigma points,
      γ = ψ·R/(Py⁰ + R) has the sign of ψ, so only the two "decrease R" cases occur.

    Parameters
    ----------
    threshold : float or ndarray, shape (...)
        C (Xia et al. 2014: 1e-4 °C; Yu et al. 2019 calls it H), one per filter if an array.
    q_increase, q_decrease : float
        coff > 1 and 0 < coff < 1 (Xia et al. 2014: 10 and 0.1).
    r_step_fraction : float
        R_step / R (Xia et al. 2014: 1/100).
    max_search_steps : int
        Bound on the R search.
    """

    threshold: float | FloatArray = 1e-4
    q_increase: float = 10.0
    q_decrease: float = 0.1
    r_step_fraction: float = 0.01
    max_search_steps: int = 100

    def search_multipliers(self) -> tuple[FloatArray, FloatArray]:
        """Factors R_j/R for the increasing and the decreasing search, each shape (J,)."""
        j = np.arange(1, self.max_search_steps + 1, dtype=float)
        up = 1.0 + j * self.r_step_fraction
        down = 1.0 - j * self.r_step_fraction
        return up, down[down > 0.0]
