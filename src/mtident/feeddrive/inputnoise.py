"""Noise on the measured forces: how much a record's force columns carry, and what it does to a fit.

An output-error fit (:mod:`mtident.feeddrive.refine`) drives the model with the measured forces as if
they were exact. A force sensor or a motor current is measured too: its noise drives the model where it
did not drive the drive, and the residual then holds that noise filtered through the drive, coloured,
strongest at the modes, exactly where the sensitivities to stiffness and damping are. The Fisher
information of white response noise then states intervals several times too narrow (a drive at 1 %
noise on every column: Bb 133 standard deviations off, by 1.6 %).

The noise is estimated from the force record itself, as white noise above what the excitation holds
(:func:`force_noise`), and carried to first order: the fit's error gains H⁻¹ M H⁻¹, M the covariance of
its gradient under the force noise (``fast.input_noise_moments``), and each response's residual gains the
variance of the force noise through the drive (:func:`response_noise_from_forces`).
"""

from __future__ import annotations

import numpy as np
from scipy import stats

from mtident._typing import FloatArray
from mtident.feeddrive.information import scaled_inverse, sensitivity_system
from mtident.feeddrive.params import FeedDriveParameters

__all__ = [
    "force_noise",
    "response_noise_from_forces",
    "input_noise_moments",
    "tolerated_force_noise",
    "FORCE_NOISE_QUANTILE",
]

# The noise of a force column is the smaller of two estimates, each exact for white noise alone and
# too high where the excitation adds to it: from the first differences (a held force, an impulse, a
# step or a binary sequence changes in few samples: this quantile of |Δu| is noise alone), and from the
# floor of its spectrum (a sine, a sweep or a multisine fills a band: this quantile of the averaged
# periodogram's bins lies outside it).
DIFFERENCE_QUANTILE = 0.25
FORCE_NOISE_QUANTILE = 0.1
_SEGMENTS = 16
_MIN_SEGMENT = 32


def force_noise(forces: FloatArray) -> FloatArray:
    """The standard deviation of white noise on each force column, estimated from the record.

    Parameters
    ----------
    forces : ndarray, shape (N, 4)
        The measured generalized forces.

    Returns
    -------
    ndarray, shape (4,)
        Zero for a column that is constant, or whose differences are mostly zero and whose spectrum
        has no floor (an exact impulse, step or binary sequence).

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> forces = np.zeros((20000, 4))
    >>> forces[100, 0] = 20.0
    >>> print(np.round(force_noise(forces), 4))
    [0. 0. 0. 0.]
    >>> print(np.round(force_noise(forces + 0.01 * rng.standard_normal(forces.shape)), 3))
    [0.01 0.01 0.01 0.01]
    """
    forces = np.asarray(forces, dtype=float)
    out = np.zeros(forces.shape[1])
    for q in range(forces.shape[1]):
        column = forces[:, q]
        if len(column) < 2 * _MIN_SEGMENT or np.ptp(column) == 0:
            continue
        # |Δu| of white noise σ is half-normal with scale σ√2
        steps = np.abs(np.diff(column))
        by_steps = float(np.quantile(steps, DIFFERENCE_QUANTILE)) / (
            np.sqrt(2.0) * float(stats.norm.ppf(0.5 + DIFFERENCE_QUANTILE / 2))
        )
        out[q] = min(by_steps, _spectral_floor(column))
    return out


def _spectral_floor(column: FloatArray) -> float:
    """The white-noise standard deviation of a column from a low quantile of its averaged periodogram
    (``_SEGMENTS`` Hann-windowed segments): each bin of white noise σ averages to σ², spread as χ² with
    2·segments degrees of freedom."""
    length = max(_MIN_SEGMENT, len(column) // _SEGMENTS)
    count = len(column) // length
    parts = column[: count * length].reshape(count, length)
    taper = np.hanning(length)
    parts = (parts - parts.mean(axis=1, keepdims=True)) * taper
    power = np.mean(np.abs(np.fft.rfft(parts, axis=1)[:, 1:-1]) ** 2, axis=0) / np.sum(taper**2)
    if len(power) == 0:
        return float("inf")
    quantile = float(stats.chi2.ppf(FORCE_NOISE_QUANTILE, 2 * count)) / (2 * count)
    return float(np.sqrt(np.quantile(power, FORCE_NOISE_QUANTILE) / quantile))


def response_noise_from_forces(
    p: FeedDriveParameters, h: float, idx: tuple[int, ...], samples: int, input_sd: FloatArray
) -> FloatArray:
    """The variance (mean over the record) each measured response gains from white noise ``input_sd`` on the
    forces, through the drive ``p``.

    Parameters
    ----------
    p, h, idx
        The drive, the sampling interval (s) and the measured responses, as for
        :func:`~mtident.feeddrive.information.sensitivity_system`.
    samples : int
        Samples in the record.
    input_sd : ndarray, shape (4,)
        Standard deviation of the noise on each force column.

    Returns
    -------
    ndarray, shape (len(idx),)
    """
    from mtident.feeddrive.fast import input_response_energy

    variance = np.asarray(input_sd, dtype=float) ** 2
    if not np.any(variance > 0):
        return np.zeros(len(idx))
    (phi, gamma, _, _), (c_row, e_row, _) = sensitivity_system(p, h, idx)
    energy = input_response_energy(
        np.ascontiguousarray(phi), np.ascontiguousarray(gamma), np.ascontiguousarray(c_row), e_row, int(samples)
    )
    return np.asarray(energy @ variance, dtype=float)


def input_noise_moments(
    p: FeedDriveParameters,
    forces: FloatArray,
    h: float,
    idx: tuple[int, ...],
    measured: FloatArray,
    weight: FloatArray,
    input_sd: FloatArray,
    start: FloatArray | None = None,
) -> FloatArray:
    """M (16, 16): the covariance of a fit's gradient (log-parameters, then the initial state) under white
    noise ``input_sd`` on the forces; the fit with Hessian H errs by H⁻¹ M H⁻¹ more.

    Parameters
    ----------
    p : FeedDriveParameters
        The fitted set.
    forces : ndarray, shape (N, 4)
    h : float
        Sampling interval (s).
    idx : tuple of int
        The measured responses (indices into ``RESPONSE_COLUMNS``).
    measured : ndarray of bool, shape (N, len(idx))
        Where each response has data.
    weight : ndarray, shape (len(idx),)
        1/σ² of each response, as the fit weighs it.
    input_sd : ndarray, shape (4,)
        Standard deviation of the noise on each force column.
    start : ndarray, shape (8,), optional
        The fitted initial state (default: rest).

    Returns
    -------
    ndarray, shape (16, 16)
    """
    from mtident.feeddrive.fast import input_noise_moments as run

    variance = np.asarray(input_sd, dtype=float) ** 2
    if not np.any(variance > 0):
        return np.zeros((16, 16))
    initial = np.zeros(8) if start is None else np.asarray(start, dtype=float)
    return np.asarray(
        run(
            sensitivity_system(p, h, idx),
            initial,
            np.asarray(forces, dtype=float),
            np.asarray(measured, dtype=float),
            np.asarray(weight, dtype=float),
            variance,
            True,
        ),
        dtype=float,
    )


def tolerated_force_noise(
    p: FeedDriveParameters,
    forces: FloatArray,
    h: float,
    idx: tuple[int, ...],
    noise_fraction: float,
    target: float,
) -> float | None:
    """The most white noise on the forces, as a fraction of each acting force column's RMS, under which the
    parameters a record identifies from rest (refined open loop: ±2σ within ``target``) all stay identified.

    The refined estimate's variance grows with the forces' noise f as v₀ + f² v₁ (to first order: v₀ the
    inverse Fisher information of the responses' noise, v₁ the forces' noise through it at f = 1), so each
    identified parameter holds up to f = √((target²/4 − v₀)/v₁).

    Parameters
    ----------
    p : FeedDriveParameters
    forces : ndarray, shape (N, 4)
        The test's exact forces.
    h : float
        Sampling interval (s).
    idx : tuple of int
        The measured responses (indices into ``RESPONSE_COLUMNS``).
    noise_fraction : float
        The responses' noise, a fraction of each one's RMS.
    target : float
        Half-width of the ±2σ interval, relative, that counts as identified.

    Returns
    -------
    float or None
        None where the test identifies none of the eight even with exact forces; inf where the forces'
        noise moves none of those it identifies.
    """
    from mtident.feeddrive.fast import response_moments as run

    forces = np.asarray(forces, dtype=float)
    no_data = np.full((len(forces), len(idx)), np.nan)
    gram, _, _, power = run(sensitivity_system(p, h, idx), np.zeros(8), forces, no_data, True)
    variance = noise_fraction**2 * power / len(forces)
    weight = 1.0 / np.where(variance > 0, variance, np.inf)
    inverse = scaled_inverse(np.einsum("rij,r->ij", gram, weight))
    alone = np.diag(inverse)[:8]
    identified = 2.0 * np.sqrt(np.maximum(alone, 0.0)) <= target
    if not identified.any():
        return None
    rms = np.sqrt(np.mean(forces**2, axis=0))
    spread = input_noise_moments(p, forces, h, idx, np.ones((len(forces), len(idx))), weight, rms)
    added = np.diag(inverse @ spread @ inverse)[:8]
    room = target**2 / 4.0 - alone
    with np.errstate(divide="ignore"):
        limits = np.where(added > 0, np.sqrt(np.maximum(room, 0.0) / added), np.inf)
    return float(np.min(limits[identified]))
