"""The filter's estimate refined open loop: the output-error (maximum-likelihood) fit of the record.

The joint filter settles each mode's damping while the excitation passes it, from a broad prior;
an excitation that passes each mode once (a sweep, a multisine with Schroeder's phases) leaves
those early, biased values in place. Fitting the whole record open loop from the filter's estimate
(the responses' noise-free simulation under the measured forces against the data, the initial
state free) uses every sample alike and is the maximum-likelihood estimate for white measurement
noise. Its covariance is the inverse Gauss-Newton Hessian: the Fisher information of the record.
Where the measured forces carry noise too, the fit errs more: the residual holds that noise through
the drive, coloured at the modes; the covariance then gains its first-order effect
(:mod:`mtident.feeddrive.inputnoise`), and the misfit is measured against both noises.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mtident._typing import FloatArray
from mtident.feeddrive.information import (
    Moments,
    gauss_newton_step,
    response_moments,
    scaled_inverse,
    stable_log_values,
)
from mtident.feeddrive.inputnoise import input_noise_moments, response_noise_from_forces
from mtident.feeddrive.params import FeedDriveParameters

__all__ = ["OpenLoopFit", "refine_open_loop"]

# Marquardt's damping (in units where every unknown's curvature is 1): where the search starts (a
# Gauss-Newton step at once runs along the weakly curved damping directions to e^-13 of Bt, where
# the data no longer see it), how it is raised after a step that raises the
# misfit and lowered after one that lowers it, and where the search gives up (no step lowers it).
_DAMPING_START = 1.0
_DAMPING_UP, _DAMPING_DOWN = 10.0, 0.3
_DAMPING_MAX = 1e8
# The largest change of a log-parameter in one step: the responses are nearly linear in a damping,
# not in its log, and a step to e^-13 of it (where the data no longer see it) stalls the search.
_MAX_LOG_STEP = 0.3
# Settled: the Gauss-Newton step from the point moves no unknown by more than this many of its
# standard deviations.
_SETTLED = 0.05


@dataclass(frozen=True, slots=True)
class OpenLoopFit:
    """The record fitted open loop.

    Attributes
    ----------
    parameters : FeedDriveParameters
        The fitted set.
    covariance_log : ndarray, shape (8, 8)
        Covariance of its log-parameters (the inverse Fisher information, widened by the misfit
        where the residuals exceed the assumed noise).
    misfit : ndarray, shape (R,)
        RMS residual of each measured response in units of its assumed noise (with what the forces'
        noise adds through the drive, where they carry any).
    start : ndarray, shape (8,)
        The fitted initial state.
    converged : bool
        The Gauss-Newton step from the point reached moves no unknown by more than ``_SETTLED`` of
        its standard deviation: the minimum. An unsettled fit is not an estimate.
    passes : int
        Passes over the record.
    input_noise : ndarray, shape (4,)
        The standard deviation of the noise on each force column the covariance carries (zero: exact).
    widened : ndarray, shape (8,)
        How many times the forces' noise widened each parameter's standard deviation (1: not at all).
    """

    parameters: FeedDriveParameters
    covariance_log: FloatArray
    misfit: FloatArray
    start: FloatArray
    converged: bool
    passes: int
    input_noise: FloatArray
    widened: FloatArray


def refine_open_loop(
    estimate: FeedDriveParameters,
    forces: FloatArray,
    h: float,
    idx: tuple[int, ...],
    data: FloatArray,
    noise: FloatArray,
    max_passes: int = 100,
    progress: Callable[[int, int], None] | None = None,
    input_noise: FloatArray | None = None,
) -> OpenLoopFit:
    """Fit the log-parameters and the initial state to the record open loop, from ``estimate``:
    minimise ‖(y − ŷ)/σ‖² by Levenberg-Marquardt.

    Parameters
    ----------
    estimate : FeedDriveParameters
        The start (the filter's estimate); masses, inertias and β are kept.
    forces : ndarray, shape (N, 4)
        Generalized forces, held over each sample.
    h : float
        Sampling interval (s).
    idx : tuple of int
        The measured responses (indices into ``RESPONSE_COLUMNS``).
    data : ndarray, shape (N, len(idx))
        The measured responses (NaN where missing).
    noise : ndarray, shape (len(idx),)
        Assumed noise standard deviation of each response.
    max_passes : int
        Passes over the record at most (one per step tried).
    progress : callable, optional
        ``progress(passes, max_passes)`` as each pass over the record begins (a long record takes
        seconds a pass).
    input_noise : ndarray, shape (4,), optional
        Standard deviation of white noise on each force column (``inputnoise.force_noise``), carried into
        the covariance and the misfit (default: the forces are exact).

    Returns
    -------
    OpenLoopFit
    """
    weight = 1.0 / np.asarray(noise, dtype=float) ** 2
    log_values, start = np.log(estimate.identified()), np.zeros(8)
    passes = 0

    def moments_at(values: FloatArray, initial: FloatArray) -> Moments:
        nonlocal passes
        passes += 1
        if progress is not None:
            progress(passes, max_passes)
        return response_moments(estimate.with_identified(np.exp(values)), forces, h, idx, data, initial)

    moments = moments_at(log_values, start)
    converged, damping = False, _DAMPING_START
    while not converged and passes < max_passes and damping < _DAMPING_MAX:
        step, _ = gauss_newton_step(moments, weight, damping=damping)
        step *= min(1.0, _MAX_LOG_STEP / max(float(np.max(np.abs(step[:8]))), 1e-300))
        values = log_values + step[:8]
        trial = moments_at(values, start + step[8:]) if stable_log_values(estimate, values) else None
        if trial is None or float(trial.residual @ weight) > float(moments.residual @ weight):
            damping *= _DAMPING_UP
            continue
        log_values, start, moments = values, start + step[8:], trial
        damping *= _DAMPING_DOWN
        # settled where the undamped (Gauss-Newton) step from here is negligible: a damped step is
        # small wherever the damping is large, also far from the minimum
        newton, hessian = gauss_newton_step(moments, weight)
        converged = bool(
            np.all(np.abs(newton) <= _SETTLED * np.sqrt(np.maximum(np.diag(scaled_inverse(hessian)), 0.0)))
        )
    _, hessian = gauss_newton_step(moments, weight)
    inverse = scaled_inverse(hessian)
    forced = np.zeros(len(weight))
    input_sd = np.zeros(4) if input_noise is None else np.asarray(input_noise, dtype=float)
    widened = np.ones(8)
    if np.any(input_sd > 0):
        fitted = estimate.with_identified(np.exp(log_values))
        spread = input_noise_moments(fitted, forces, h, idx, np.isfinite(data), weight, input_sd, start)
        alone = np.sqrt(np.maximum(np.diag(inverse)[:8], 1e-300))
        inverse = inverse + inverse @ spread @ inverse
        widened = np.sqrt(np.maximum(np.diag(inverse)[:8], 0.0)) / alone
        forced = response_noise_from_forces(fitted, h, idx, len(forces), input_sd)
    expected = 1.0 / weight + forced
    misfit = np.sqrt(moments.residual / expected / np.maximum(moments.count, 1.0))
    widening = max(1.0, float(np.max(misfit)) ** 2)
    covariance = widening * inverse[:8, :8]
    return OpenLoopFit(
        parameters=estimate.with_identified(np.exp(log_values)),
        covariance_log=covariance,
        misfit=misfit,
        start=start,
        converged=converged,
        passes=passes,
        input_noise=input_sd,
        widened=widened,
    )
