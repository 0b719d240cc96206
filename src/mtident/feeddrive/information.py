"""How much a record says about the feed drive's parameters: sensitivities, Fisher information and
the consistency of an estimate with the record it came from.

The responses are linear in the state, and the sensitivity of the state to the log of parameter j,
sⱼ = ∂X/∂zⱼ with zⱼ = ln pⱼ, obeys ṡⱼ = A sⱼ + (∂A/∂zⱼ) X (differentiate Ẋ = A X + B u). The state,
its eight sensitivities and, where asked, its sensitivities to the initial state form one linear
system, discretised exactly for inputs held over each sample (as the simulator applies them). One
pass over the record accumulates, per response, the Gram matrix of its sensitivities: the Fisher
information for white Gaussian noise (Ljung, System Identification, 2nd ed., §9.2).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TypeAlias

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import MtidentError
from mtident.feeddrive.model import exact_step, parameter_basis, system_matrices
from mtident.feeddrive.params import FeedDriveParameters, validate

__all__ = [
    "Moments",
    "Consistency",
    "SensitivitySystem",
    "sensitivity_system",
    "response_moments",
    "filter_covariance",
    "fisher_covariance",
    "scaled_inverse",
    "closest_consistent",
    "gauss_newton_step",
    "stable_log_values",
]


@dataclass(frozen=True, slots=True)
class Moments:
    """Sums over a record, per measured response r.

    Attributes
    ----------
    gram : ndarray, shape (R, P, P)
        Σₖ gₖ gₖᵀ, g the response's sensitivities: to the 8 log-parameters, then (where asked)
        to the 8 initial states.
    cross : ndarray, shape (R, P)
        Σₖ gₖ (yₖ − ŷₖ) against the data (zero without data).
    residual : ndarray, shape (R,)
        Σₖ (yₖ − ŷₖ)² (zero without data).
    power : ndarray, shape (R,)
        Σₖ ŷₖ², the model response's energy.
    count : ndarray, shape (R,)
        Samples summed (the measured ones where there are data).
    """

    gram: FloatArray
    cross: FloatArray
    residual: FloatArray
    power: FloatArray
    count: FloatArray


SensitivitySystem: TypeAlias = tuple[
    tuple[FloatArray, FloatArray, FloatArray, FloatArray], tuple[FloatArray, FloatArray, FloatArray]
]


def sensitivity_system(p: FeedDriveParameters, h: float, idx: tuple[int, ...]) -> SensitivitySystem:
    """The exact step of the state and its sensitivities, and the output rows (see ``fast.response_moments``).

    Parameters
    ----------
    p : FeedDriveParameters
    h : float
        Sampling interval (s).
    idx : tuple of int
        The responses (indices into ``RESPONSE_COLUMNS``).

    Returns
    -------
    ((Φ, Γ, Φₛ, Γₛ), (c, e, cₛ))
    """
    basis = parameter_basis(p)
    values = p.identified()
    a = system_matrices(values, basis)
    derivatives = values[:, None, None] * basis[1]  # ∂A/∂zⱼ = pⱼ ∂A/∂pⱼ
    m_inv = 1.0 / np.array([p.Mt, p.Mb, p.Jb, p.Jm])
    b = np.vstack([np.zeros((4, 4)), np.diag(m_inv)])
    phi, gamma = exact_step(a, b, h)
    phi_s = np.empty((8, 8, 8))
    gamma_s = np.empty((8, 8, 4))
    for j in range(8):  # d/dt [X; sⱼ] = [[A, 0], [∂A/∂zⱼ, A]] [X; sⱼ] + [B; 0] u
        big_a = np.block([[a, np.zeros((8, 8))], [derivatives[j], a]])
        big_phi, big_gamma = exact_step(big_a, np.vstack([b, np.zeros((8, 4))]), h)
        phi_s[j], gamma_s[j] = big_phi[8:, :8], big_gamma[8:]
    c_row = np.zeros((len(idx), 8))
    e_row = np.zeros((len(idx), 4))
    c_s = np.zeros((len(idx), 8, 8))
    for row, r in enumerate(idx):
        if r < 8:
            c_row[row, r] = 1.0
        else:  # an acceleration: row 4 + q of A X + M⁻¹ u
            q = r - 8
            c_row[row], e_row[row, q], c_s[row] = a[4 + q], m_inv[q], derivatives[:, 4 + q, :]
    return (phi, gamma, phi_s, gamma_s), (c_row, e_row, c_s)


def response_moments(
    p: FeedDriveParameters,
    forces: FloatArray,
    h: float,
    idx: tuple[int, ...],
    data: FloatArray | None = None,
    start: FloatArray | None = None,
) -> Moments:
    """Sensitivity and residual moments of the responses ``idx`` over a record.

    Parameters
    ----------
    p : FeedDriveParameters
        The parameters the sensitivities are taken at.
    forces : ndarray, shape (N, 4)
        Generalized forces, held over each sample.
    h : float
        Sampling interval (s).
    idx : tuple of int
        The responses (indices into ``RESPONSE_COLUMNS``).
    data : ndarray, shape (N, len(idx)), optional
        Measured responses (NaN where missing): adds the residual moments and the sensitivities
        to the initial state (which is then fitted too).
    start : ndarray, shape (8,), optional
        Initial state (default: rest).

    Returns
    -------
    Moments
    """
    from mtident.feeddrive.fast import response_moments as run

    system = sensitivity_system(p, h, idx)
    initial = np.zeros(8) if start is None else np.asarray(start, dtype=float)
    observed = np.full((len(forces), len(idx)), np.nan) if data is None else np.asarray(data, dtype=float)
    gram, cross, residual, power = run(system, initial, np.asarray(forces, dtype=float), observed, data is not None)
    count = (
        np.isfinite(observed).sum(axis=0).astype(float) if data is not None else np.full(len(idx), float(len(forces)))
    )
    return Moments(gram, cross, residual, power, count)


def filter_covariance(
    p: FeedDriveParameters,
    forces: FloatArray,
    h: float,
    idx: tuple[int, ...],
    noise: tuple[FloatArray, FloatArray, FloatArray],
    system: SensitivitySystem | None = None,
) -> tuple[FloatArray, FloatArray]:
    """What the filter is expected to end with on a record of the responses ``idx`` of a drive with
    parameters ``p`` under ``forces``, from rest: the covariance (8, 8) of the log-parameters it
    states, and the covariance of its estimates over draws of the measurement noise.

    Both come from the Kalman covariance recursion of the filter's own model linearised along the
    noise-free response (``fast.covariance_recursion``). The stated one is the inverse Fisher
    information of the log-parameters with the filter's prior and process noise; the scatter is
    smaller where the record has no process noise to absorb (a simulation, a model that fits): the
    filter's random walk on the states forgets old samples, which the data did not require.

    Parameters
    ----------
    p : FeedDriveParameters
    forces : ndarray, shape (N, 4)
    h : float
        Sampling interval (s).
    idx : tuple of int
        The measured responses (indices into ``RESPONSE_COLUMNS``).
    noise : (P₀ (16, 16), Q (16, 16), R (len(idx), len(idx)))
        The filter's prior, process and measurement noise covariances in its scaled units.
    system : SensitivitySystem, optional
        :func:`sensitivity_system` of the same ``p``, ``h`` and ``idx``, to share among records.

    Returns
    -------
    stated, scatter : ndarray, shape (8, 8)
    """
    from mtident.feeddrive.fast import covariance_recursion
    from mtident.feeddrive.simulate import run_responses

    step, rows = system or sensitivity_system(p, h, idx)
    forces = np.asarray(forces, dtype=float)
    values = run_responses(p, step[0], step[1], np.zeros(8), forces)
    rms = np.sqrt(np.mean(values**2, axis=0))
    scale = np.where(rms > 0, rms, 1.0)
    stated, scatter = covariance_recursion(step, forces, rows, scale[:8], scale[list(idx)], noise)
    return stated[8:, 8:], scatter[8:, 8:]


def fisher_covariance(
    p: FeedDriveParameters,
    forces: FloatArray,
    h: float,
    idx: tuple[int, ...],
    noise_fraction: float,
    system: SensitivitySystem | None = None,
) -> FloatArray:
    """The inverse Fisher information of the log-parameters for a record of the responses ``idx``
    of a drive with parameters ``p`` under ``forces``, from rest, with white noise of
    ``noise_fraction`` of each response's RMS, the initial state unknown: the covariance an
    efficient estimate of the record alone has, and the one the open-loop refinement states
    (:mod:`mtident.feeddrive.refine`).

    Parameters
    ----------
    p, forces, h, idx, system
        As for :func:`filter_covariance`.
    noise_fraction : float
        Measurement noise standard deviation as a fraction of each response's RMS.

    Returns
    -------
    ndarray, shape (8, 8)
    """
    from mtident.feeddrive.fast import response_moments as run

    forces = np.asarray(forces, dtype=float)
    no_data = np.full((len(forces), len(idx)), np.nan)
    # the initial state is fitted with the parameters, as the refinement does: an impulse's record
    # starts in its ring-down, and a free start takes some of the information
    gram, _, _, power = run(system or sensitivity_system(p, h, idx), np.zeros(8), forces, no_data, True)
    variance = noise_fraction**2 * power / len(forces)
    information = np.einsum("rij,r->ij", gram, 1.0 / np.where(variance > 0, variance, np.inf))
    return scaled_inverse(information)[:8, :8]


def scaled_inverse(matrix: FloatArray) -> FloatArray:
    """The (pseudo-)inverse of an information matrix whose diagonal spans many decades (stiffness
    and damping move the responses by amounts 1e10 apart), taken where every diagonal element is 1.

    Parameters
    ----------
    matrix : ndarray, shape (P, P)
        Symmetric, positive semi-definite.

    Returns
    -------
    ndarray, shape (P, P)
    """
    unit = _unit_scale(matrix)
    return np.asarray(np.linalg.pinv(matrix * np.outer(unit, unit), rcond=1e-12) * np.outer(unit, unit), dtype=float)


def _unit_scale(matrix: FloatArray) -> FloatArray:
    """The scale of each unknown that makes its curvature (the matrix's diagonal) 1: stiffness and
    damping move the responses by amounts 1e10 apart, and a least-squares or pseudo-inverse
    cut-off in the raw units drops the damping directions."""
    return np.asarray(1.0 / np.sqrt(np.maximum(np.diag(matrix), 1e-300)), dtype=float)


@dataclass(frozen=True, slots=True)
class Consistency:
    """The parameter set closest to an estimate that its intervals allow, fitted to the record open loop.

    Attributes
    ----------
    misfit : ndarray, shape (R,)
        RMS residual of each measured response in units of its assumed noise (≈ 1 when the
        estimate, its intervals and the noise hold).
    distance : float
        Squared Mahalanobis distance of that set from the estimate (χ² with 8 degrees of
        freedom when the intervals hold).
    parameters_log_shift : ndarray, shape (8,)
        ln(set / estimate) of the identified parameters.
    start : ndarray, shape (8,)
        The fitted initial state.
    """

    misfit: FloatArray
    distance: float
    parameters_log_shift: FloatArray
    start: FloatArray


def closest_consistent(
    estimate: FeedDriveParameters,
    covariance_log: FloatArray,
    forces: FloatArray,
    h: float,
    idx: tuple[int, ...],
    data: FloatArray,
    noise: FloatArray,
    max_passes: int = 8,
) -> Consistency:
    """Fit the record open loop from its start, the initial state free and the log-parameters held to
    the estimate by its covariance: minimise ‖(y − ŷ)/σ‖² + dᵀΣ⁻¹d by Gauss-Newton.

    The open-loop response of a lightly damped drive drifts in phase by many radians over a record
    for a parameter error of one standard deviation, so one linearisation at the estimate does not
    reach the set the intervals allow; a few Gauss-Newton passes do.

    Parameters
    ----------
    estimate : FeedDriveParameters
    covariance_log : ndarray, shape (8, 8)
        Covariance of the estimate's log-parameters.
    forces : ndarray, shape (N, 4)
    h : float
        Sampling interval (s).
    idx : tuple of int
        The measured responses (indices into ``RESPONSE_COLUMNS``).
    data : ndarray, shape (N, len(idx))
    noise : ndarray, shape (len(idx),)
        Assumed noise standard deviation of each response.
    max_passes : int
        Passes over the record at most (each one linearisation).

    Returns
    -------
    Consistency
    """
    weight = 1.0 / np.asarray(noise, dtype=float) ** 2
    # a direction of zero variance (the paper preset) is held, not freed, by a floor on the variance
    prior: FloatArray = np.linalg.inv(covariance_log + 1e-12 * np.eye(8)).astype(float)
    reference = np.log(estimate.identified())
    shift, start = np.zeros(8), np.zeros(8)
    tolerance = 0.1 * np.sqrt(np.diag(covariance_log) + 1e-12)
    for _ in range(max_passes):
        moments = response_moments(estimate.with_identified(np.exp(reference + shift)), forces, h, idx, data, start)
        step, _ = gauss_newton_step(moments, weight, prior, shift)
        if not stable_log_values(estimate, reference + shift + step[:8]):
            step = np.zeros_like(step)  # stay at the last stable set: its misfit is the one reported
        left = moments.residual - 2.0 * moments.cross @ step + np.einsum("i,rij,j->r", step, moments.gram, step)
        shift, start = shift + step[:8], start + step[8:]
        if np.all(np.abs(step[:8]) <= tolerance):
            break
    misfit = np.sqrt(np.maximum(left, 0.0) * weight / np.maximum(moments.count, 1.0))
    return Consistency(misfit, float(shift @ prior @ shift), shift, start)


def gauss_newton_step(
    moments: Moments,
    weight: FloatArray,
    prior: FloatArray | None = None,
    shift: FloatArray | None = None,
    damping: float = 0.0,
) -> tuple[FloatArray, FloatArray]:
    """The Gauss-Newton step of the log-parameters and the initial state from ``moments``, and the
    Hessian it solves.

    Parameters
    ----------
    moments : Moments
        Of the record at the current point, with data (P unknowns: the 8 log-parameters, then the
        initial state's 8).
    weight : ndarray, shape (R,)
        1/σ² of each response.
    prior : ndarray, shape (8, 8), optional
        Inverse covariance holding the log-parameters to where ``shift`` is measured from.
    shift : ndarray, shape (8,), optional
        The log-parameters' distance from the prior's centre.
    damping : float
        Marquardt's damping λ: the step solves (H + λ diag H) δ = g (0: Gauss-Newton's).

    Returns
    -------
    step : ndarray, shape (P,)
        Zero where the moments are not finite.
    hessian : ndarray, shape (P, P)
    """
    hessian = np.einsum("rij,r->ij", moments.gram, weight)
    gradient = moments.cross.T @ weight
    if prior is not None and shift is not None:
        hessian[:8, :8] += prior
        gradient[:8] -= prior @ shift
    unit = _unit_scale(hessian)
    step = np.zeros(len(gradient))
    if np.all(np.isfinite(hessian)) and np.all(np.isfinite(gradient)):
        scaled = hessian * np.outer(unit, unit) + damping * np.eye(len(unit))
        step = unit * np.linalg.lstsq(scaled, gradient * unit, rcond=1e-12)[0]
    return step, hessian


def stable_log_values(estimate: FeedDriveParameters, log_values: FloatArray) -> bool:
    """Whether the identified parameters e^``log_values`` give a finite, stable model.

    Parameters
    ----------
    estimate : FeedDriveParameters
        Its masses, inertias and β are kept.
    log_values : ndarray, shape (8,)
        ln K1..K4, Bt, Bb, Qb, Qm.

    Returns
    -------
    bool
    """
    if not np.all(np.abs(log_values) < 700):  # beyond, e^z is not a float
        return False
    values = np.exp(log_values)
    try:
        validate(estimate.with_identified(values))
    except MtidentError:
        return False
    return True
