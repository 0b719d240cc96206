"""The feed drive's joint state/parameter filter in its own units (Nguyen-Quoc et al. §3.2): the
responses it measures, the states and responses scaled by their RMS and the parameters as
log(p/p_guess) (:class:`ScaledProblem`), its prior and noise (:func:`filter_noise`), the RK4
sub-steps of its transition (:func:`filter_substeps`), and its two loops: the generic engine's
(:func:`run_numpy`) and the compiled one (:func:`run_compiled`).
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass
from itertools import product

import numpy as np

from mtident._typing import FloatArray, IntArray
from mtident.exceptions import CovarianceError, InputError, NegativeWeightWarning
from mtident.feeddrive.model import input_matrix, parameter_basis, rk4_linear_step, system_matrices
from mtident.feeddrive.params import FeedDriveParameters
from mtident.feeddrive.simulate import RESPONSE_COLUMNS, Response, simulate, substeps_for
from mtident.ukf import FilterConfig, GaussianState, MerweScaledSigmaPoints, SigmaWeights, filter_step, initial_carry

__all__ = [
    "MEASUREMENT_SETS",
    "PRESENT",
    "PRIOR_SD_LOG",
    "FilterSetup",
    "ScaledProblem",
    "filter_noise",
    "filter_substeps",
    "measured_indices",
    "run_compiled",
    "run_numpy",
    "scaled_problem",
]

# Which responses are measured: all 12 (Nguyen-Quoc et al.), or what a machine usually has:
# table acceleration (accelerometer), motor angle and velocity (encoder).
MEASUREMENT_SETS = {
    "all": tuple(range(12)),
    "realistic": (
        RESPONSE_COLUMNS.index("a_t_m_per_s2"),
        RESPONSE_COLUMNS.index("theta_m_rad"),
        RESPONSE_COLUMNS.index("omega_m_rad_per_s"),
    ),
}
# The measurement set of the responses a file has (a machine's own log seldom has all 12).
PRESENT = "present"
# The default filter, in units of each state's RMS and of ln(p/p_guess): the prior on the states
# (they start near rest) and on the parameters (a guess within a factor e^±1 at 2σ), and the random
# walks that let the states absorb small model errors and the parameters drift slowly. The walk on
# the states also forgets the slow decay that carries the guideway and bearing damping (Bt, Bb): a
# hundred times smaller, it pins them from Nguyen-Quoc et al.'s impulse, but the filter then states intervals
# that miss the truth by several standard deviations under a sweep, a step or a multisine.
STATE_PRIOR_VAR = 1e-4
PRIOR_SD_LOG = 0.5
STATE_PROCESS_VAR = 1e-8
PARAMETER_PROCESS_VAR = 1e-12


def measured_indices(response: Response, measured: str | tuple[int, ...]) -> tuple[int, ...]:
    """The responses the filter uses, checked against those the record has."""
    if isinstance(measured, str) and measured not in (PRESENT, *MEASUREMENT_SETS):
        msg = f"measurement set {measured!r} is not one of: {', '.join((PRESENT, *MEASUREMENT_SETS))}"
        raise InputError(msg)
    in_file = tuple(i for i in range(len(RESPONSE_COLUMNS)) if not np.all(np.isnan(response.values[:, i])))
    indices = (
        in_file if measured == PRESENT else MEASUREMENT_SETS[measured] if isinstance(measured, str) else tuple(measured)
    )
    missing = [RESPONSE_COLUMNS[i] for i in indices if i not in in_file]
    if missing:
        msg = f"the response has no {missing[0]!r} column, which the measurement set {measured!r} needs"
        raise InputError(msg)
    constant = [i for i in indices if np.ptp(response.values[:, i]) == 0]
    if constant:
        name = RESPONSE_COLUMNS[constant[0]]
        msg = (
            f"the response column {name!r} is constant throughout ({response.values[0, constant[0]]:g}): "
            "a dead channel, or no excitation; check it, or choose a measurement set without it"
        )
        raise InputError(msg)
    return indices


def _response_scales(response: Response, guess: FeedDriveParameters, h: float) -> FloatArray:
    """The RMS of each measured response; for the others, of a simulation of the guess with the
    same input (only run when some response is not in the file)."""
    present = np.isfinite(response.values)
    counts = present.sum(axis=0)
    rms_data = np.sqrt(np.sum(np.where(present, response.values**2, 0.0), axis=0) / np.maximum(counts, 1))
    known = (counts > 0) & (rms_data > 0)
    rms_model = np.ones(12)
    if not known.all() and np.any(response.forces):
        model = simulate(guess, sample_rate_Hz=1.0 / h, duration_s=h * (len(response.time_s) - 1), method="exact")
        rms_model = np.sqrt(np.mean(model.values**2, axis=0))
    scale = np.where(known, rms_data, rms_model)
    return np.where(scale > 0, scale, 1.0)


def filter_substeps(guess: FeedDriveParameters, h: float, reach_log: float) -> int:
    """RK4 sub-steps per sample for the filter's transition.

    ω·h/m ≤ 0.15 at the guess keeps RK4's discretisation error below what the record says about
    the damping (half as many sub-steps bias the damping estimates past their 2σ), and
    ω·h/m ≤ 1 at every sigma point of the prior (each parameter e^±``reach_log`` times the guess)
    keeps RK4 stable (its limit on the imaginary axis is 2√2) wherever the sigma points put the modes.

    Parameters
    ----------
    guess : FeedDriveParameters
    h : float
        Sampling interval (s).
    reach_log : float
        How far the sigma points reach in log-parameter: spread × prior standard deviation.

    Returns
    -------
    int
        A power of two.
    """
    count = substeps_for(guess, h, max_phase_step=0.15)
    for j, sign in product(range(8), (-1.0, 1.0)):
        values = guess.identified()
        values[j] *= np.exp(sign * reach_log)
        count = max(count, substeps_for(guess.with_identified(values), h, max_phase_step=1.0))
    return count


@dataclass(frozen=True, slots=True)
class FilterSetup:
    """Sigma points, initial belief and noise covariances of the augmented filter."""

    sigma: MerweScaledSigmaPoints
    weights: SigmaWeights
    mean0: FloatArray
    cov0: FloatArray
    process_cov: FloatArray
    emission_cov: FloatArray
    prior_sd_log: float
    log_form: bool


def _filter_setup(
    preset: str, response: Response, idx: FloatArray, reference: FloatArray, scale: FloatArray, noise_fraction: float
) -> FilterSetup:
    """The default (scaled states, log-parameters, broad prior) or the paper's settings (Nguyen-Quoc et al.
    Eqs 40-44)."""
    n = 16
    if preset == "paper":
        sigma = MerweScaledSigmaPoints(0.5, 2.0, 3.0)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NegativeWeightWarning)
            weights = sigma.weights(n)
        state_var = np.nan_to_num(np.nanvar(response.values[:, :8], axis=0), nan=1e-12)
        cov0 = np.diag(np.concatenate([np.maximum(state_var, 1e-30), np.zeros(8)]))
        q = 1e-4 * np.eye(n)
        # P₀ of Eq. 44 is singular (zero variance on the parameters): the first time update adds Q.
        return FilterSetup(
            sigma, weights, np.concatenate([np.zeros(8), reference]), cov0 + q, q, 1e-9 * np.eye(len(idx)), 0.0, False
        )
    sigma = MerweScaledSigmaPoints(1.0, 2.0, 0.0)
    cov0, q, r = filter_noise(noise_fraction, len(idx))
    return FilterSetup(sigma, sigma.weights(n), np.zeros(n), cov0, q, r, PRIOR_SD_LOG, True)


def filter_noise(noise_fraction: float, measured: int) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The default filter's P₀, Q and R (scaled states and responses, log-parameters).

    Parameters
    ----------
    noise_fraction : float
        Measurement noise standard deviation as a fraction of each response's RMS.
    measured : int
        How many responses are measured.

    Returns
    -------
    (P₀ (16, 16), Q (16, 16), R (measured, measured))
    """
    cov0 = np.diag(np.concatenate([np.full(8, STATE_PRIOR_VAR), np.full(8, PRIOR_SD_LOG**2)]))
    q = np.diag(np.concatenate([np.full(8, STATE_PROCESS_VAR), np.full(8, PARAMETER_PROCESS_VAR)]))
    return cov0, q, np.diag(np.full(measured, noise_fraction**2))  # outputs are scaled by their RMS


def run_numpy(
    setup: FilterSetup,
    ys: FloatArray,
    transition_at: Callable[[int], Callable[[FloatArray], FloatArray]],
    measurement_at: Callable[[int], Callable[[FloatArray], FloatArray]],
    config: FilterConfig,
    progress: Callable[[int, int], None] | None,
) -> tuple[FloatArray, FloatArray, FloatArray, int]:
    """The generic engine's loop: (means, variances, final covariance, failed step or −1)."""
    carry = initial_carry(GaussianState(setup.mean0, setup.cov0), setup.process_cov, setup.emission_cov, config)
    steps, n = len(ys), len(setup.mean0)
    means, variances = np.empty((steps, n)), np.empty((steps, n))
    means[0], variances[0] = carry.mean, np.diag(carry.covariance())
    for k in range(1, steps):
        try:
            with np.errstate(over="ignore", invalid="ignore"):
                carry, _ = filter_step(carry, ys[k], transition_at(k), measurement_at(k), config, setup.weights)
        except CovarianceError:
            return means, variances, carry.covariance(), k
        means[k], variances[k] = carry.mean, np.diag(carry.covariance())
        if not (np.all(np.isfinite(means[k])) and np.all(np.isfinite(variances[k]))):
            return means, variances, carry.covariance(), k
        if progress is not None and k % 500 == 0:
            progress(k, steps)
    return means, variances, carry.covariance(), -1


@dataclass(frozen=True)
class ScaledProblem:
    """The filter's problem in its own units: the states and responses divided by their scales,
    the parameters (in log form) relative to the guess's."""

    guess: FeedDriveParameters
    setup: FilterSetup
    idx: IntArray
    scale: FloatArray  # every response's scale (the noise is a fraction of it)
    state_scale: FloatArray
    out_scale: FloatArray
    reference: FloatArray
    basis: tuple[FloatArray, FloatArray]
    m_inv: FloatArray
    h: float
    substeps: int

    def to_params(self, z: FloatArray) -> FloatArray:
        """The parameters (8,) of filter states (..., 16)."""
        return self.reference * np.exp(z[..., 8:]) if self.setup.log_form else z[..., 8:]

    def transition_at(self, forces: FloatArray) -> Callable[[int], Callable[[FloatArray], FloatArray]]:
        """The transition into sample k of sigma points (..., 16), for the generic engine."""

        def at(k: int) -> Callable[[FloatArray], FloatArray]:
            u = forces[k - 1]

            def transition(points: FloatArray) -> FloatArray:
                a = system_matrices(self.to_params(points), self.basis)
                phi, gamma = rk4_linear_step(a, input_matrix(self.guess), self.h, self.substeps)
                x = points[..., :8] * self.state_scale
                x_next = (phi @ x[..., None])[..., 0] + gamma @ u
                return np.concatenate([x_next / self.state_scale, points[..., 8:]], axis=-1)

            return transition

        return at

    def measurement_at(self, forces: FloatArray) -> Callable[[int], Callable[[FloatArray], FloatArray]]:
        """The measured responses at sample k of sigma points (..., 16), for the generic engine."""

        def at(k: int) -> Callable[[FloatArray], FloatArray]:
            f = forces[k]

            def measure(points: FloatArray) -> FloatArray:
                x = points[..., :8] * self.state_scale
                a = system_matrices(self.to_params(points), self.basis)
                acc = (a[..., 4:, :] @ x[..., None])[..., 0] + self.m_inv * f
                return np.concatenate([x, acc], axis=-1)[..., self.idx] / self.out_scale

            return measure

        return at


def scaled_problem(
    response: Response,
    guess: FeedDriveParameters,
    indices: tuple[int, ...],
    preset: str,
    noise_fraction: float,
    substeps: int | None,
    h: float,
) -> ScaledProblem:
    idx = np.array(indices)
    scale = _response_scales(response, guess, h)
    reference = guess.identified()
    setup = _filter_setup(preset, response, idx, reference, scale, noise_fraction)
    return ScaledProblem(
        guess=guess,
        setup=setup,
        idx=idx,
        scale=scale,
        state_scale=scale[:8] if setup.log_form else np.ones(8),
        out_scale=scale[idx] if setup.log_form else np.ones(len(idx)),
        reference=reference,
        basis=parameter_basis(guess),
        m_inv=1.0 / np.array([guess.Mt, guess.Mb, guess.Jb, guess.Jm]),
        h=h,
        substeps=substeps or filter_substeps(guess, h, setup.weights.spread * setup.prior_sd_log),
    )


def run_compiled(
    scaled: ScaledProblem, ys: FloatArray, forces: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, int]:
    """The numba-compiled loop: (means, variances, final covariance, failed step or −1)."""
    from mtident.feeddrive.fast import run_feed_drive_ukf

    setup = scaled.setup
    a0, d = scaled.basis
    means, variances, final_cov, failed, _ = run_feed_drive_ukf(
        setup.mean0,
        setup.cov0,
        setup.process_cov,
        setup.emission_cov,
        ys,
        forces * scaled.m_inv,
        setup.weights.mean,
        setup.weights.cov,
        setup.weights.spread,
        scaled.state_scale,
        scaled.out_scale,
        scaled.idx.astype(np.int64),
        a0,
        d,
        scaled.reference,
        scaled.h,
        scaled.substeps,
        setup.log_form,
    )
    return means, variances, final_cov, failed
