"""Scaled sigma points (Xia et al. 2014, Eqs 5-13; van der Merwe 2004).

Convention: the matrix square root is the *lower* Cholesky factor ``L`` with
``P = L Lᵀ``; the sigma points are ``x ± columns of sqrt(n + λ)·L``. These are
the rows of the upper factor ``U = Lᵀ``, which is what Xia et al. 2014 calls "the ith
row of the matrix square root" and what filterpy's ``MerweScaledSigmaPoints``
uses, so both give the same points.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import NegativeWeightWarning

__all__ = ["SigmaWeights", "MerweScaledSigmaPoints", "sigma_points"]


@dataclass(frozen=True, slots=True)
class SigmaWeights:
    """Weights of a sigma-point set for a state of dimension ``n``.

    Attributes
    ----------
    mean : ndarray, shape (2n+1,)
        Weights W⁽ᵐ⁾ of Eqs 11 and 13.
    cov : ndarray, shape (2n+1,)
        Weights W⁽ᶜ⁾ of Eqs 12 and 13.
    spread : float
        ``sqrt(n + λ)``, the factor applied to the matrix square root.
    """

    mean: FloatArray
    cov: FloatArray
    spread: float

    @property
    def n_points(self) -> int:
        """Number of sigma points, 2n+1."""
        return int(self.mean.shape[0])


@dataclass(frozen=True, slots=True)
class MerweScaledSigmaPoints:
    """The scaled sigma-point scheme, λ = α²(n + κ) − n.

    Parameters
    ----------
    alpha : float
        Spread of the points around the mean (Xia et al. 2014: "a small positive value").
    beta : float
        Prior knowledge of the distribution; 2 is optimal for a Gaussian.
    kappa : float
        Secondary scaling parameter.

    Notes
    -----
    The default α = 1, β = 2, κ = 0 puts the points at ``x ± sqrt(n P)``, as
    Yu et al. 2019 Eq. 3 writes them, with W₀⁽ᵐ⁾ = 0 and W₀⁽ᶜ⁾ = 2. Nguyen-Quoc et al. use
    α = 1/2, β = 2, κ = 3 for n = 16, which gives W₀⁽ᵐ⁾ ≈ −2.37: a negative centre
    weight is allowed but warned about (:class:`NegativeWeightWarning`),
    because with a negative W₀⁽ᶜ⁾ the predicted covariance can lose positive
    definiteness.

    Examples
    --------
    >>> w = MerweScaledSigmaPoints().weights(3)
    >>> w.mean.round(4).tolist()
    [0.0, 0.1667, 0.1667, 0.1667, 0.1667, 0.1667, 0.1667]
    >>> float(w.cov[0])
    2.0
    """

    alpha: float = 1.0
    beta: float = 2.0
    kappa: float = 0.0

    def weights(self, n: int) -> SigmaWeights:
        """Weights for a state of dimension ``n`` (Eqs 11-13).

        Parameters
        ----------
        n : int
            Dimension of the state; ``n + λ`` must be positive.

        Returns
        -------
        SigmaWeights
            The 2n+1 weights W⁽ᵐ⁾ and W⁽ᶜ⁾, and the spread ``sqrt(n + λ)``.
        """
        lam = self.alpha**2 * (n + self.kappa) - n
        if n + lam <= 0:
            msg = f"sigma points: n + λ = {n + lam:.3g} must be positive (α={self.alpha}, κ={self.kappa}, n={n})"
            raise ValueError(msg)
        w_i = 0.5 / (n + lam)
        mean = np.full(2 * n + 1, w_i)
        cov = np.full(2 * n + 1, w_i)
        mean[0] = lam / (n + lam)
        cov[0] = mean[0] + 1.0 - self.alpha**2 + self.beta
        if mean[0] < 0 or cov[0] < 0:
            warnings.warn(
                f"sigma points (α={self.alpha}, β={self.beta}, κ={self.kappa}, n={n}): negative centre "
                f"weight W0m={mean[0]:.4g}, W0c={cov[0]:.4g}; the unscented transform is still unbiased "
                "but covariances may lose positive definiteness (the square-root filter then needs a "
                "Cholesky downdate)",
                NegativeWeightWarning,
                stacklevel=2,
            )
        return SigmaWeights(mean=mean, cov=cov, spread=float(np.sqrt(n + lam)))


def sigma_points(mean: FloatArray, chol: FloatArray, weights: SigmaWeights) -> FloatArray:
    """Sigma points around ``mean`` from the lower Cholesky factor ``chol``.

    Parameters
    ----------
    mean : ndarray, shape (..., n)
    chol : ndarray, shape (..., n, n)
        Lower factor with ``P = chol @ cholᵀ``.
    weights : SigmaWeights
        Supplies the spread ``sqrt(n + λ)``.

    Returns
    -------
    ndarray, shape (..., 2n+1, n)
        Point 0 is the mean, points 1..n add the columns, n+1..2n subtract them.
    """
    offsets = weights.spread * np.swapaxes(chol, -1, -2)  # rows = columns of chol
    centre = mean[..., None, :]
    return np.concatenate([centre, centre + offsets, centre - offsets], axis=-2)
