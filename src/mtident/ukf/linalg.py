"""Small linear-algebra kernels the filters share, all batched over leading axes."""

from __future__ import annotations

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import CovarianceError

__all__ = [
    "symmetrize",
    "safe_cholesky",
    "cholesky_update",
    "cholesky_downdate_or_mask",
    "weighted_outer",
    "first_bad_index",
    "solve_gain",
    "lower_factor_from_qr",
]


def solve_gain(innovation_cov: FloatArray, cross_cov: FloatArray) -> FloatArray:
    """Pxy Py⁻¹ for Py (..., m, m), Pxy (..., n, m), by a solve (a division when m = 1).

    Parameters
    ----------
    innovation_cov : ndarray, shape (..., m, m)
        Py, the covariance of the predicted measurement (symmetric positive definite).
    cross_cov : ndarray, shape (..., n, m)
        Pxy, the cross-covariance of state and measurement.

    Returns
    -------
    ndarray, shape (..., n, m)
        The Kalman gain K = Pxy Py⁻¹.
    """
    if innovation_cov.shape[-1] == 1:
        return cross_cov / innovation_cov[..., 0:1, :]
    return np.swapaxes(np.linalg.solve(innovation_cov, np.swapaxes(cross_cov, -1, -2)), -1, -2)


def symmetrize(matrix: FloatArray) -> FloatArray:
    """(A + Aᵀ)/2 over the last two axes.

    Parameters
    ----------
    matrix : ndarray, shape (..., n, n)
        A stack of square matrices (covariances that rounding made slightly asymmetric).

    Returns
    -------
    ndarray, shape (..., n, n)
        Their symmetric parts.
    """
    return 0.5 * (matrix + np.swapaxes(matrix, -1, -2))


def first_bad_index(matrix: FloatArray) -> tuple[tuple[int, ...] | None, float]:
    """Batch index and value of the most negative eigenvalue in a stack of symmetric matrices.

    Parameters
    ----------
    matrix : ndarray, shape (..., n, n)
        The stack (symmetrised before its eigenvalues are taken).

    Returns
    -------
    index : tuple of int or None
        Position in the leading axes of the matrix with the smallest eigenvalue; None for a single
        matrix (no leading axes).
    value : float
        That smallest eigenvalue (negative where the matrix is indefinite).
    """
    eig = np.linalg.eigvalsh(symmetrize(matrix))
    smallest = eig[..., 0]
    flat = int(np.argmin(smallest))
    index = np.unravel_index(flat, smallest.shape) if smallest.ndim else ()
    value = float(smallest.reshape(-1)[flat])
    return (tuple(int(i) for i in index) or None), value


def safe_cholesky(matrix: FloatArray, stage: str) -> FloatArray:
    """Lower Cholesky factor of a stack of covariances, or a :class:`CovarianceError`.

    The error names ``stage``, the batch index of the first offending matrix and
    its smallest eigenvalue (numpy alone says only "Matrix is not positive definite").

    Parameters
    ----------
    matrix : ndarray, shape (..., n, n)
        A stack of symmetric covariances.
    stage : str
        What the covariance is, for the error ("sigma points of the previous posterior").

    Returns
    -------
    ndarray, shape (..., n, n)
        Lower triangular L with L Lᵀ = ``matrix``, float64.

    Raises
    ------
    CovarianceError
        A matrix of the stack is not positive definite.
    """
    try:
        return np.asarray(np.linalg.cholesky(matrix), dtype=np.float64)
    except np.linalg.LinAlgError as exc:
        index, value = first_bad_index(matrix)
        raise CovarianceError(stage, index, value) from exc


def weighted_outer(weights: FloatArray, left: FloatArray, right: FloatArray) -> FloatArray:
    """Σᵢ wᵢ aᵢ bᵢᵀ for deviations ``left`` (..., S, n) and ``right`` (..., S, m).

    Parameters
    ----------
    weights : ndarray, shape (S,)
        One weight per sigma point, shared by the batch.
    left : ndarray, shape (..., S, n)
        Deviations aᵢ of the S sigma points from their mean.
    right : ndarray, shape (..., S, m)
        Deviations bᵢ (``left`` again for a covariance).

    Returns
    -------
    ndarray, shape (..., n, m)
        The weighted sum of outer products (a covariance or cross-covariance).
    """
    return np.swapaxes(left * weights[:, None], -1, -2) @ right


def lower_factor_from_qr(columns: FloatArray) -> FloatArray:
    """Lower L with L Lᵀ = A Aᵀ for A (..., n, k), k ≥ n, by QR of Aᵀ (positive diagonal).

    Parameters
    ----------
    columns : ndarray, shape (..., n, k)
        A, k ≥ n: weighted sigma-point deviations and square-root noise columns side by side.

    Returns
    -------
    ndarray, shape (..., n, n)
        Lower triangular L with a non-negative diagonal (the transposed R factor of Aᵀ, with the
        signs of its rows fixed).
    """
    upper = np.linalg.qr(np.swapaxes(columns, -1, -2), mode="r")
    signs = np.sign(np.diagonal(upper, axis1=-2, axis2=-1))
    signs = np.where(signs == 0.0, 1.0, signs)
    return np.swapaxes(upper * signs[..., :, None], -1, -2)


def cholesky_downdate_or_mask(
    chol: FloatArray, vector: FloatArray, sign: float | FloatArray
) -> tuple[FloatArray, FloatArray]:
    """Like :func:`cholesky_update`, but returns ``(L, failed)`` instead of raising.

    ``failed`` (shape ...) marks the filters whose downdate would have made the
    matrix indefinite; their factor is meaningless and must be replaced.

    Parameters
    ----------
    chol : ndarray, shape (..., n, n)
        Lower Cholesky factor L (not changed).
    vector : ndarray, shape (..., n)
        v.
    sign : float or ndarray, shape (...)
        +1 for an update, −1 for a downdate (per filter if an array).

    Returns
    -------
    L : ndarray, shape (..., n, n)
        The factor of L Lᵀ + sign · v vᵀ where it exists.
    failed : ndarray of bool, shape (...)
        The filters whose result is indefinite (or not finite).
    """
    L = np.array(chol, dtype=float, copy=True)
    x = np.array(vector, dtype=float, copy=True)
    sign = np.broadcast_to(np.asarray(sign, dtype=float), L.shape[:-2])
    failed = np.zeros(L.shape[:-2], dtype=bool)
    n = L.shape[-1]
    for k in range(n):
        diag = L[..., k, k]
        r2 = diag**2 + sign * x[..., k] ** 2
        bad = ~(r2 > 0.0)
        failed = failed | bad
        r = np.sqrt(np.where(bad, 1.0, r2))
        diag = np.where(bad, 1.0, diag)
        c = r / diag
        s = x[..., k] / diag
        L[..., k, k] = r
        if k + 1 < n:
            column = (L[..., k + 1 :, k] + (sign * s)[..., None] * x[..., k + 1 :]) / c[..., None]
            x[..., k + 1 :] = c[..., None] * x[..., k + 1 :] - s[..., None] * column
            L[..., k + 1 :, k] = column
    return L, failed


def cholesky_update(chol: FloatArray, vector: FloatArray, sign: float | FloatArray, stage: str) -> FloatArray:
    """Rank-1 update (sign > 0) or downdate (sign < 0) of a lower Cholesky factor.

    Returns ``L'`` with ``L' L'ᵀ = L Lᵀ + sign · v vᵀ``, batched over leading axes.
    A downdate that would make the matrix indefinite raises :class:`CovarianceError`
    rather than producing NaN (MATLAB's ``cholupdate(R, x, '-')`` fails the same way).

    Parameters
    ----------
    chol : ndarray, shape (..., n, n)
    vector : ndarray, shape (..., n)
    sign : float or ndarray, shape (...)
        +1 for an update, -1 for a downdate (per filter if an array).
    stage : str
        Named in the error if the downdate fails.
    """
    result, failed = cholesky_downdate_or_mask(chol, vector, sign)
    if np.any(failed):
        index = tuple(int(i) for i in np.argwhere(np.atleast_1d(failed))[0]) if failed.ndim else None
        v = np.asarray(vector, dtype=float)
        sign_b = np.broadcast_to(np.asarray(sign, dtype=float), failed.shape)
        target = chol @ np.swapaxes(chol, -1, -2) + sign_b[..., None, None] * v[..., :, None] * v[..., None, :]
        _, value = first_bad_index(target)
        raise CovarianceError(stage, index, value)
    return result
