"""Joint state/parameter estimation of the feed drive with a UKF (Nguyen-Quoc et al. §2.3, §3.2).

Augmented state (Nguyen-Quoc et al. Eq. 37): the 8 physical states and the 8 identified
parameters K1..K4, Bt, Bb, Qb, Qm. Differences from the paper (the documentation's Theory page):

* The transition integrates the same ODE as the simulator — classical RK4 with
  sub-steps, the input held over each sample — not Eq. 39's garbled Euler step.
  The sub-steps follow from the highest mode and the sampling interval, at the
  guess and at the sigma points; a record sampled too slowly for the guess's
  highest mode is refused before the work (:func:`~mtident.feeddrive.modes.sampling_problem`).
* Physical states are scaled by the RMS of their responses and parameters are
  estimated as log(p/p_guess), so 1e8 N/m and 1e-3 N m s/rad live side by side
  in one well-conditioned covariance, with a small random walk on them.
* The parameters start from a wrong guess (default: the shipped set ±30 %) with a
  broad prior, not at the truth with zero variance (Eq. 44). The ``paper``
  preset reproduces Eq. 44 and the paper's α, β, κ, Q and R for comparison.
* The estimate is checked against the record open loop: the filtered responses
  follow the data whatever the parameters, so the set its intervals allow must
  reproduce the record from its start with the measured forces alone
  (:func:`~mtident.feeddrive.information.closest_consistent`).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import replace

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import DivergenceError, InputError
from mtident.feeddrive.filter_problem import (
    MEASUREMENT_SETS,
    PRESENT,
    PRIOR_SD_LOG,
    ScaledProblem,
    filter_noise,
    filter_substeps,
    measured_indices,
    run_compiled,
    run_numpy,
    scaled_problem,
)
from mtident.feeddrive.identification import IDENTIFIED_WITHIN, MISFIT_LIMIT, FeedDriveIdentification
from mtident.feeddrive.identify_notes import (
    consistency_notes,
    force_noise_notes,
    one_frequency_note,
    parameter_notes,
    refined_notes,
    sweep_note,
)
from mtident.feeddrive.information import Consistency, closest_consistent, response_moments, scaled_inverse
from mtident.feeddrive.inputnoise import force_noise, input_noise_moments, response_noise_from_forces
from mtident.feeddrive.model import system_matrices
from mtident.feeddrive.modes import modes, sampling_problem
from mtident.feeddrive.params import IDENTIFIED, FeedDriveParameters, validate
from mtident.feeddrive.refine import refine_open_loop
from mtident.feeddrive.simulate import FORCE_COLUMNS, RESPONSE_COLUMNS, Response
from mtident.ukf import FilterConfig

__all__ = [
    "FeedDriveIdentification",
    "identify_feed_drive",
    "MEASUREMENT_SETS",
    "PRESENT",
    "PRIOR_SD_LOG",
    "default_guess",
    "IDENTIFIED_WITHIN",
    "filter_noise",
    "filter_substeps",
]

# K1 low and K2 high keep the guess stable (K2 > K1).
GUESS_FACTORS = np.array([0.7, 1.3, 1.3, 0.7, 1.3, 0.7, 1.3, 0.7])


def default_guess(truth: FeedDriveParameters | None = None) -> FeedDriveParameters:
    """The shipped set with each identified parameter 30 % high or low (``GUESS_FACTORS``).

    Parameters
    ----------
    truth : FeedDriveParameters, optional
        The set to start from (default: the shipped set).

    Returns
    -------
    FeedDriveParameters
        ``truth`` with K1..K4, Bt, Bb, Qb, Qm multiplied by 0.7, 1.3, 1.3, 0.7, 1.3, 0.7, 1.3, 0.7;
        the masses, inertias and β are kept.
    """
    base = truth or FeedDriveParameters()
    return base.with_identified(base.identified() * GUESS_FACTORS)


def identify_feed_drive(
    response: Response,
    guess: FeedDriveParameters | None = None,
    measured: str | tuple[int, ...] = "all",
    noise_fraction: float = 0.01,
    preset: str = "default",
    substeps: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    engine: str = "compiled",
    check: bool = True,
    refine: bool = False,
    refine_progress: Callable[[int, int], None] | None = None,
) -> FeedDriveIdentification:
    """Estimate states, stiffness and damping from a measured response.

    Parameters
    ----------
    response : Response
        Sampled forces and responses (NaN columns are not measured).
    guess : FeedDriveParameters
        Starting point; masses, inertias and β are taken as known. Default:
        :func:`default_guess` (±30 % off the shipped set).
    measured : {"all", "realistic", "present"} or tuple of int
        Which of the 12 responses the filter uses (must be present in ``response``).
    noise_fraction : float
        Measurement noise standard deviation as a fraction of each response's RMS.
    preset : {"default", "paper"}
        ``paper``: Nguyen-Quoc et al.'s α = 1/2, β = 2, κ = 3, Q = 1e-4·I, R = 1e-9·I and
        P₀ of Eq. 44 (zero variance on the parameters), in unscaled SI units.
    substeps : int, optional
        RK4 sub-steps per sample in the transition (default: :func:`filter_substeps`).
    progress : callable, optional
        ``progress(step, total)`` every 500 steps (numpy engine only).
    engine : {"compiled", "numpy"}
        The numba-compiled loop (:mod:`mtident.feeddrive.fast`) or the generic
        :mod:`mtident.ukf` engine; both compute the same filter.
    check : bool
        Check the estimate against the record open loop (``consistency``; a few passes over the
        record; not run for the paper preset).
    refine : bool
        Refine the filter's estimate by fitting the whole record open loop (output-error maximum
        likelihood, :mod:`mtident.feeddrive.refine`): unbiased where the filter is not (sweeps and
        multisines) and as precise as the record allows. Kept only where it fits the record within
        the noise; the filter's estimate stays in ``filter_parameters``. Not for the paper preset.
        Noise on the measured forces, estimated from their record (:mod:`mtident.feeddrive.inputnoise`),
        is carried into the refined intervals, the misfit and the open-loop check, and widens the filter's
        intervals by as much as it widens the fit's at its estimate; the notes say so.
    refine_progress : callable, optional
        ``refine_progress(passes, max_passes)`` as each of the refinement's passes over the record begins.

    Returns
    -------
    FeedDriveIdentification

    Raises
    ------
    InputError
        An unknown option, a response the measurement set needs but the record lacks, a dead
        channel, every force zero, or a sampling rate too low for the guess's highest mode.
    DivergenceError
        The filter's numbers stopped being finite on a record it accepted.
    """
    if not isinstance(response, Response):  # a DataFrame raised AttributeError deep in pandas
        msg = (
            f"a feed drive's record is a Response (read_response(path), or simulate(...)), not "
            f"{type(response).__name__}"
        )
        raise InputError(msg)
    guess = validate(guess or default_guess())
    if not np.any(response.forces):
        # the filter then follows noise about rest: it diverged, or kept a guess far from the drive
        msg = (
            f"every force column is zero ({', '.join(FORCE_COLUMNS)}): nothing excites the drive, so its record "
            "holds nothing to identify; give the measured force or torque that drove it (a force column a file "
            "lacks is taken as zero)"
        )
        raise InputError(msg)
    indices = measured_indices(response, measured)
    for option, value, allowed in (("preset", preset, ("default", "paper")), ("engine", engine, ("compiled", "numpy"))):
        if value not in allowed:
            msg = f"{option} {value!r} is not one of: {', '.join(allowed)}"
            raise InputError(msg)
    h = float(response.time_s[1] - response.time_s[0])
    problem = sampling_problem(guess, 1.0 / h, "the guess")
    if problem:
        msg = (
            f"{problem}; sample faster (the filter follows the guess's modes: where they are far above the "
            "drive's, check the guess)"
        )
        raise InputError(msg)
    scaled = scaled_problem(response, guess, indices, preset, noise_fraction, substeps, h)
    notes = one_frequency_note(response.forces, h) or sweep_note(response.forces, h)
    if preset == "paper":
        notes.append(
            "paper preset: α = 1/2, β = 2, κ = 3 give a negative centre weight W0m = -2.368 (Nguyen-Quoc et al. Eq. 41)"
        )
    ys = response.values[:, scaled.idx] / scaled.out_scale
    if engine == "compiled":
        means, variances, final_cov, failed = run_compiled(scaled, ys, response.forces)
    else:
        config = FilterConfig(sigma_points=scaled.setup.sigma, name=f"feed drive ({preset})")
        means, variances, final_cov, failed = run_numpy(
            scaled.setup,
            ys,
            scaled.transition_at(response.forces),
            scaled.measurement_at(response.forces),
            config,
            progress,
        )
    if failed >= 0:
        raise _divergence(failed, float(response.time_s[failed]), guess, noise_fraction)
    result = _identification(scaled, response, (means, variances, final_cov), notes, preset)
    if not scaled.setup.log_form:  # the paper preset keeps its guess (zero prior variance): nothing to refine or check
        return result
    result = _force_widened(result, scaled, response, noise_fraction, notes)
    if refine:
        refined, said = _refined(result, scaled, response, noise_fraction, notes, refine_progress)
        if refined is not None:
            return refined
        result = replace(result, notes=(*result.notes, said))
    return _checked(result, scaled, response, noise_fraction) if check else result


def _divergence(step: int, time_s: float, guess: FeedDriveParameters, noise_fraction: float) -> DivergenceError:
    """The error for a filter that diverged on a record it accepted."""
    frequencies = ", ".join(f"{f:.0f}" for f in modes(guess).frequencies_Hz)
    return DivergenceError(
        f"the filter diverged at sample {step} (t = {time_s:g} s): a parameter set within its prior gave a model whose "
        f"response is no longer finite. The guess (modes {frequencies} Hz) may be far from the drive, or the noise far "
        f"from the assumed {noise_fraction:g} of each response's RMS"
    )


def _identification(
    scaled: ScaledProblem,
    response: Response,
    run: tuple[FloatArray, FloatArray, FloatArray],
    notes: list[str],
    preset: str,
) -> FeedDriveIdentification:
    """The result from the filter's run: parameters and their intervals, and the estimated responses."""
    means, variances, final_cov = run
    setup, idx = scaled.setup, scaled.idx
    param_hist = scaled.to_params(means)
    var_z = variances[:, 8:]
    hist_sd = param_hist * np.sqrt(var_z) if setup.log_form else np.sqrt(var_z)
    states = means[:, :8] * scaled.state_scale
    accelerations = np.einsum("nij,nj->ni", system_matrices(param_hist, scaled.basis)[:, 4:, :], states)
    estimated = np.hstack([states, accelerations + scaled.m_inv * response.forces])
    correlation = {}
    for i in idx:
        ok = np.isfinite(response.values[:, i])
        correlation[RESPONSE_COLUMNS[i]] = float(np.corrcoef(estimated[ok, i], response.values[ok, i])[0, 1])
    final_sd_log = np.sqrt(var_z[-1])
    covariance_log = (
        final_cov[8:, 8:] if setup.log_form else final_cov[8:, 8:] / np.outer(param_hist[-1], param_hist[-1])
    )
    said = parameter_notes(final_sd_log, setup.prior_sd_log) if setup.log_form else []
    return FeedDriveIdentification(
        time_s=response.time_s,
        parameters=param_hist[-1],
        parameters_std=hist_sd[-1],
        prior_sd_log=setup.prior_sd_log,
        identifiable=2 * final_sd_log <= IDENTIFIED_WITHIN if setup.log_form else np.zeros(8, dtype=bool),
        history=param_hist,
        history_std=hist_sd,
        estimated=estimated,
        correlation=correlation,
        measured_columns=tuple(RESPONSE_COLUMNS[i] for i in idx),
        guess=scaled.guess,
        preset=preset,
        notes=(*notes, *said),
        covariance_log=covariance_log,
        consistency=None,
    )


def _force_widened(
    result: FeedDriveIdentification,
    scaled: ScaledProblem,
    response: Response,
    noise_fraction: float,
    notes: list[str],
) -> FeedDriveIdentification:
    """The filter's result with its intervals widened for the noise on the measured forces (estimated from
    their record; unchanged where they carry none). The filter takes the forces as exact, as the
    open-loop fit does: each parameter's interval is widened by the factor the forces' noise widens the
    fit's at the filter's estimate (its Fisher information, to first order), and the note says so."""
    input_sd = force_noise(response.forces)
    if not np.any(input_sd > 0):
        return result
    estimate = result.guess.with_identified(result.parameters)
    idx = tuple(int(i) for i in scaled.idx)
    data = response.values[:, scaled.idx]
    weight = 1.0 / (noise_fraction * scaled.scale[scaled.idx]) ** 2
    moments = response_moments(estimate, response.forces, scaled.h, idx, data)
    inverse = scaled_inverse(np.einsum("rij,r->ij", moments.gram, weight))
    spread = input_noise_moments(estimate, response.forces, scaled.h, idx, np.isfinite(data), weight, input_sd)
    alone = np.maximum(np.diag(inverse)[:8], 1e-300)
    widened = np.sqrt(np.maximum(np.diag(inverse + inverse @ spread @ inverse)[:8], 0.0) / alone)
    said = force_noise_notes(input_sd, response.forces, widened)
    if not said:
        return result
    covariance_log = result.covariance_log * np.outer(widened, widened)
    sd_log = np.sqrt(np.diag(covariance_log))
    return replace(
        result,
        parameters_std=result.parameters * sd_log,
        identifiable=2 * sd_log <= IDENTIFIED_WITHIN,
        covariance_log=covariance_log,
        notes=(*notes, *parameter_notes(sd_log, result.prior_sd_log), *said),
    )


def _checked(
    result: FeedDriveIdentification, scaled: ScaledProblem, response: Response, noise_fraction: float
) -> FeedDriveIdentification:
    """``result`` with the open-loop check of its estimate against the record, and its note. Noise on the
    measured forces (estimated from their record) drives the model where it did not drive the drive: the
    residual a correct estimate leaves is then that noise through the drive as well as the responses' own."""
    estimate = result.guess.with_identified(result.parameters)
    idx = tuple(int(i) for i in scaled.idx)
    noise = noise_fraction * scaled.scale[scaled.idx]
    input_sd = force_noise(response.forces)
    if np.any(input_sd > 0):
        noise = np.sqrt(noise**2 + response_noise_from_forces(estimate, scaled.h, idx, len(response.forces), input_sd))
    consistency = closest_consistent(
        estimate,
        result.covariance_log,
        response.forces,
        scaled.h,
        idx,
        response.values[:, scaled.idx],
        noise,
    )
    notes = (*result.notes, *consistency_notes(consistency, result.measured_columns))
    return replace(result, consistency=consistency, notes=notes)


def _refined(
    filtered: FeedDriveIdentification,
    scaled: ScaledProblem,
    response: Response,
    noise_fraction: float,
    notes: list[str],
    progress: Callable[[int, int], None] | None,
) -> tuple[FeedDriveIdentification | None, str]:
    """The filter's result with its estimate refined open loop, and what to say of it; None where
    the refinement did not settle or does not fit the record within the noise (the filter's
    estimate then stands)."""
    idx = tuple(int(i) for i in scaled.idx)
    fit = refine_open_loop(
        filtered.guess.with_identified(filtered.parameters),
        response.forces,
        scaled.h,
        idx,
        response.values[:, scaled.idx],
        noise_fraction * scaled.scale[scaled.idx],
        progress=progress,
        input_noise=force_noise(response.forces),
    )
    worst = float(np.max(fit.misfit))
    if not fit.converged:
        return None, (
            f"the open-loop refinement did not settle within {fit.passes} passes over the record (misfit up to "
            f"{worst:.2f}× the assumed noise): the filter's estimate is given"
        )
    if worst > MISFIT_LIMIT:
        column = filtered.measured_columns[int(np.argmax(fit.misfit))]
        return None, (
            f"the open-loop refinement does not fit the record ({column} "
            f"leaves it by {worst:.1f}× the assumed noise, at most {MISFIT_LIMIT:g} accepted): the filter's estimate "
            "is given"
        )
    sd_log = np.sqrt(np.diag(fit.covariance_log))
    values = fit.parameters.identified()
    moved = np.abs(np.log(values / filtered.parameters)) / sd_log
    said = (
        f"refined open loop (the whole record fitted from the filter's estimate, {fit.passes} passes): the "
        "filter's estimate was up to "
        f"{moved.max():.1f} of the refined standard deviations away ({IDENTIFIED[int(np.argmax(moved))]})"
    )
    check = Consistency(fit.misfit, 0.0, np.zeros(8), fit.start)
    forced = force_noise_notes(fit.input_noise, response.forces, fit.widened)
    refined = replace(
        filtered,
        parameters=values,
        parameters_std=values * sd_log,
        identifiable=2 * sd_log <= IDENTIFIED_WITHIN,
        covariance_log=fit.covariance_log,
        consistency=check,
        notes=(
            *refined_notes(notes, response.forces, scaled.h),
            *parameter_notes(sd_log, None),
            *forced,
            said,
        ),
        filter_parameters=filtered.parameters,
        filter_parameters_std=filtered.parameters_std,
    )
    return refined, said
