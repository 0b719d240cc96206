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

import warnings
from collections.abc import Callable
from dataclasses import dataclass, replace
from itertools import product

import numpy as np

from mtident._typing import BoolArray, FloatArray, IntArray
from mtident.exceptions import CovarianceError, DivergenceError, InputError, NegativeWeightWarning
from mtident.feeddrive.information import Consistency, closest_consistent, response_moments, scaled_inverse
from mtident.feeddrive.inputnoise import force_noise, input_noise_moments, response_noise_from_forces
from mtident.feeddrive.model import (
    exact_step,
    input_matrix,
    parameter_basis,
    rk4_linear_step,
    system_matrices,
    system_matrix,
)
from mtident.feeddrive.modes import modes, sampling_problem
from mtident.feeddrive.params import IDENTIFIED, FeedDriveParameters, validate
from mtident.feeddrive.refine import refine_open_loop
from mtident.feeddrive.simulate import FORCE_COLUMNS, RESPONSE_COLUMNS, Response, run_responses, simulate, substeps_for
from mtident.ukf import FilterConfig, GaussianState, MerweScaledSigmaPoints, SigmaWeights, filter_step, initial_carry

__all__ = [
    "FeedDriveIdentification",
    "identify_feed_drive",
    "MEASUREMENT_SETS",
    "PRESENT",
    "default_guess",
    "IDENTIFIED_WITHIN",
    "filter_noise",
    "filter_substeps",
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
# K1 low and K2 high keep the guess stable (K2 > K1).
GUESS_FACTORS = np.array([0.7, 1.3, 1.3, 0.7, 1.3, 0.7, 1.3, 0.7])
# A parameter is identified when its ±2σ interval is within ±10 % (a tenth of the prior's 2σ, 100 %).
IDENTIFIED_WITHIN = 0.10
# The consistency check (closest_consistent) says the intervals do not hold when the set they allow
# leaves a response by more than this many times its assumed noise (RMS; 1 expected), or lies farther
# from the estimate than this squared Mahalanobis distance (χ² with 8 degrees of freedom: 99.9 % quantile).
MISFIT_LIMIT = 1.5
DISTANCE_LIMIT = 26.1
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


@dataclass(frozen=True)
class FeedDriveIdentification:
    """Result of the joint estimation.

    Attributes
    ----------
    parameters, parameters_std : ndarray, shape (8,)
        Final estimates of ``IDENTIFIED`` and their standard deviations (SI).
    identifiable : ndarray of bool, shape (8,)
        The record pins the parameter down: ±2σ within ±``IDENTIFIED_WITHIN``.
    history, history_std : ndarray, shape (N, 8)
        Convergence of the parameter estimates.
    estimated : ndarray, shape (N, 12)
        Responses of the filtered states.
    correlation : dict
        Response name → correlation of estimated and measured response (Table 2).
    measured_columns : tuple of str
    guess : FeedDriveParameters
    covariance_log : ndarray, shape (8, 8)
        Covariance of the log-parameters at the end of the record.
    consistency : Consistency or None
        The open-loop check of the estimate against the record (None if not run); for a refined
        estimate, the refinement's own fit of the record.
    filter_parameters, filter_parameters_std : ndarray, shape (8,) or None
        The filter's own estimate where ``parameters`` is its open-loop refinement (else None).
    """

    time_s: FloatArray
    parameters: FloatArray
    parameters_std: FloatArray
    prior_sd_log: float
    identifiable: BoolArray
    history: FloatArray
    history_std: FloatArray
    estimated: FloatArray
    correlation: dict[str, float]
    measured_columns: tuple[str, ...]
    guess: FeedDriveParameters
    preset: str
    notes: tuple[str, ...]
    covariance_log: FloatArray
    consistency: Consistency | None
    filter_parameters: FloatArray | None = None
    filter_parameters_std: FloatArray | None = None

    @property
    def parameters_sd(self) -> FloatArray:
        """Alias of ``parameters_std`` (its name before ``parameters_std`` was used)."""
        return self.parameters_std

    def __repr__(self) -> str:
        rows = [
            f"  {name}: {value:.5g} ± {2 * sd:.2g} (2σ){'' if known else ', not identified'}"
            for name, value, sd, known in zip(
                IDENTIFIED, self.parameters, self.parameters_std, self.identifiable, strict=True
            )
        ]
        return "\n".join(
            [
                f"FeedDriveIdentification({self.preset}, {len(self.time_s)} samples, "
                f"measured: {', '.join(self.measured_columns)})",
                *rows,
            ]
        )

    def errors_percent(self, truth: FeedDriveParameters) -> dict[str, float]:
        """Table 3: 100·|estimate − truth|/truth per parameter.

        Parameters
        ----------
        truth : FeedDriveParameters
            The true set (a simulated record's); its K1..K4, Bt, Bb, Qb, Qm are compared.

        Returns
        -------
        dict of str to float
            Name in ``IDENTIFIED`` → relative error of the estimate (%).
        """
        true = truth.identified()
        return {name: float(100 * abs(v - t) / t) for name, v, t in zip(IDENTIFIED, self.parameters, true, strict=True)}

    def covers(self, truth: FeedDriveParameters) -> dict[str, bool]:
        """Whether ±2σ around each estimate contains the truth.

        Parameters
        ----------
        truth : FeedDriveParameters
            The true set (a simulated record's); its K1..K4, Bt, Bb, Qb, Qm are compared.

        Returns
        -------
        dict of str to bool
            Name in ``IDENTIFIED`` → the true value lies within ±2 ``parameters_std`` of the estimate.
        """
        true = truth.identified()
        return {
            name: bool(abs(v - t) <= 2 * s)
            for name, v, s, t in zip(IDENTIFIED, self.parameters, self.parameters_std, true, strict=True)
        }

    def reproduces_record(self) -> bool | None:
        """Whether the set the intervals allow reproduces the record open loop (None: not checked)."""
        if self.consistency is None:
            return None
        return bool(np.all(self.consistency.misfit <= MISFIT_LIMIT) and self.consistency.distance <= DISTANCE_LIMIT)

    def model_response(self, response: Response) -> FloatArray:
        """The 12 responses (N, 12) of the set the consistency check fitted, open loop under the record's forces.

        Parameters
        ----------
        response : Response
            The record: its forces (N, N, N m, N m) drive the model, its first two times (s) give the sampling
            interval.

        Returns
        -------
        ndarray, shape (N, 12)
            The 8 states and the 4 accelerations at each sample (``RESPONSE_COLUMNS``), from the start the check
            fitted (rest where it was not run).
        """
        shift = np.zeros(8) if self.consistency is None else self.consistency.parameters_log_shift
        start = np.zeros(8) if self.consistency is None else self.consistency.start
        fitted = self.guess.with_identified(self.parameters * np.exp(shift))
        phi, gamma = exact_step(
            system_matrix(fitted), input_matrix(fitted), float(response.time_s[1] - response.time_s[0])
        )
        return run_responses(fitted, phi, gamma, start, response.forces)

    def summary(self, truth: FeedDriveParameters | None = None) -> dict[str, object]:
        """The JSON object (parameters, parameters_std, correlation), plus extras.

        ``parameters_sd`` repeats ``parameters_std`` for scripts written before that name was used.

        Parameters
        ----------
        truth : FeedDriveParameters, optional
            The true set (a simulated record's); given, the errors (:meth:`errors_percent`) and whether the
            intervals cover it (:meth:`covers`) are added.

        Returns
        -------
        dict of str to object
            JSON-ready: the estimates and standard deviations (SI) by name, identifiability, correlations, the
            guess, notes, the filter's own estimate where refined, the open-loop misfit where checked, and with
            ``truth`` "error_percent" and "within_2sd".
        """
        std = {n: float(v) for n, v in zip(IDENTIFIED, self.parameters_std, strict=True)}
        out: dict[str, object] = {
            "parameters": {n: float(v) for n, v in zip(IDENTIFIED, self.parameters, strict=True)},
            "parameters_std": std,
            "parameters_sd": dict(std),
            "identifiable": {n: bool(v) for n, v in zip(IDENTIFIED, self.identifiable, strict=True)},
            "correlation": self.correlation,
            "measured": list(self.measured_columns),
            "guess": {n: float(getattr(self.guess, n)) for n in IDENTIFIED},
            "preset": self.preset,
            "reproduces_record": self.reproduces_record(),
            "refined": self.filter_parameters is not None,
            "notes": list(self.notes),
        }
        if self.filter_parameters is not None and self.filter_parameters_std is not None:
            out["filter_parameters"] = {n: float(v) for n, v in zip(IDENTIFIED, self.filter_parameters, strict=True)}
            out["filter_parameters_std"] = {
                n: float(v) for n, v in zip(IDENTIFIED, self.filter_parameters_std, strict=True)
            }
        if self.consistency is not None:
            out["open_loop_misfit"] = {
                n: float(v) for n, v in zip(self.measured_columns, self.consistency.misfit, strict=True)
            }
        if truth is not None:
            out["error_percent"] = self.errors_percent(truth)
            out["within_2sd"] = self.covers(truth)
        return out


def _consistency_notes(check: Consistency, columns: tuple[str, ...]) -> list[str]:
    """A note if the set the estimate's intervals allow does not reproduce the record open loop.

    The filtered responses follow the data whatever the parameters (the states are corrected every
    sample: all correlations 0.99999 under a 100 Hz sine whose estimate was 17-45 % off, with
    intervals under 1 %). Run open loop from the start with the measured forces, a wrong estimate
    leaves the data, and no set its intervals allow brings it back.
    """
    worst = int(np.argmax(check.misfit))
    if check.misfit[worst] <= MISFIT_LIMIT and check.distance <= DISTANCE_LIMIT:
        return []
    found = (
        f"{columns[worst]} leaves the data by {check.misfit[worst]:.1f}× the assumed noise "
        f"(RMS; 1 expected, at most {MISFIT_LIMIT:g} accepted)"
        if check.misfit[worst] > MISFIT_LIMIT
        else f"only a set {np.sqrt(check.distance):.1f} standard deviations (Mahalanobis) "
        "from the estimate reproduces it "
        f"(at most {np.sqrt(DISTANCE_LIMIT):.1f} expected)"
    )
    return [
        "the estimate does not reproduce the record: of the parameter sets its intervals allow, "
        f"fitted open loop with the measured forces, "
        f"{found}. The filter may have settled on a wrong set (an excitation of one frequency near a mode does this), "
        "or the noise is larger than assumed: the intervals do not hold"
    ]


# A force this close to one sine (the share of its variance a sine at its strongest frequency explains)
# excites one frequency only.
_ONE_FREQUENCY_SHARE = 0.95
# A sweep, looked for in this many windows of the record: one narrow band at a time (the bins
# holding this share of a window's power lie within this fraction of its spectrum), moving from
# window to window.
_SWEEP_WINDOWS = 16
_SWEEP_MIN_WINDOW = 32
_SWEEP_POWER = 0.9
_SWEEP_BAND = 0.1


def _one_frequency_note(forces: FloatArray, h: float) -> list[str]:
    """A note where every force that acts is one sine: the record then shows the drive's response at
    that frequency alone (an amplitude and a phase per response), too little to tell eight stiffness
    and damping parameters apart; the filter may settle on a wrong set that fits it."""
    acting = [k for k in range(forces.shape[1]) if np.ptp(forces[:, k]) > 0]
    if not acting:
        return []
    t = np.arange(len(forces)) * h
    found = []
    for k in acting:
        f = forces[:, k] - forces[:, k].mean()
        spectrum = np.abs(np.fft.rfft(f))
        peak = int(np.argmax(spectrum[1:])) + 1
        # the strongest line, between two bins: the sine through it by least squares, at a few
        # frequencies around the bin (a sine between bins leaks into its neighbours)
        best, best_frequency = 0.0, 0.0
        for frequency in (peak + np.linspace(-0.5, 0.5, 11)) / (len(f) * h):
            basis = np.column_stack(
                [np.sin(2 * np.pi * frequency * t), np.cos(2 * np.pi * frequency * t), np.ones_like(t)]
            )
            fitted = basis @ np.linalg.lstsq(basis, f, rcond=None)[0]
            share = 1.0 - float(np.sum((f - fitted) ** 2) / np.sum(f**2))
            best, best_frequency = max((best, best_frequency), (share, frequency))
        if best < _ONE_FREQUENCY_SHARE:
            return []
        found.append(f"{FORCE_COLUMNS[k]} at {best_frequency:.3g} Hz")
    return [
        f"the excitation is one frequency ({', '.join(found)}): the record shows the drive's response at that "
        "frequency alone, "
        "too little to tell its stiffness and damping parameters apart; an impulse, a step or a binary sequence "
        "(PRBS) excites every mode, and a test plan (plan_tests) says which identifies all eight"
    ]


def _sweep_note(forces: FloatArray, h: float, refined: bool = False) -> list[str]:
    """A note where a force sweeps: one narrow band at a time (in short windows), moving through
    the record (a sweep, or a multisine with Schroeder's phases, a periodic chirp). In simulation
    at 1 % noise the filter's damping and friction estimates from such records were biased beyond
    their own intervals (it settles each mode's damping from its broad prior while the sweep
    passes the mode, which the sweep never revisits); binary sequences and impulses, and the
    open-loop refinement of any of them, were not. ``refined``: the note for a refined estimate."""
    found = []
    for k in range(forces.shape[1]):
        length = len(forces) // _SWEEP_WINDOWS
        if np.ptp(forces[:, k]) == 0 or length < _SWEEP_MIN_WINDOW:
            continue
        taper = np.hanning(length)
        spans, centres = [], []
        for w in range(_SWEEP_WINDOWS):
            part = forces[w * length : (w + 1) * length, k]
            power = np.abs(np.fft.rfft((part - part.mean()) * taper))[1:] ** 2
            if not np.sum(power) > 0:
                continue
            # the fewest bins that hold most of the window's power, and how far apart they lie
            strongest = np.argsort(power)[::-1]
            held = strongest[: int(np.searchsorted(np.cumsum(power[strongest]), _SWEEP_POWER * np.sum(power))) + 1]
            spans.append((int(held.max()) - int(held.min()) + 1) / len(power))
            centres.append((float(np.sum(power * np.arange(1, len(power) + 1)) / np.sum(power))) / (length * h))
        if (
            len(spans) >= _SWEEP_WINDOWS // 2
            and float(np.median(spans)) <= _SWEEP_BAND
            and max(centres) - min(centres) > 4.0 / (length * h)
        ):
            found.append(f"{FORCE_COLUMNS[k]} from about {min(centres):.3g} to {max(centres):.3g} Hz")
    if not found:
        return []
    swept = f"the excitation sweeps through its band ({', '.join(found)}: a sweep, or a Schroeder-phase multisine"
    if refined:
        return [
            f"{swept}): the filter's damping and friction estimates (filter_parameters) are biased on such records, "
            "the refined ones were not in simulation"
        ]
    return [
        f"{swept}, which is one): in simulation the filter's damping and friction estimates from such records were "
        "biased beyond their own intervals, where binary sequences (PRBS) and impulses were not; refine the estimate "
        "open loop (refine), which was unbiased on them, or treat Bt, Bb, Qb and Qm with care"
    ]


def _measured_indices(response: Response, measured: str | tuple[int, ...]) -> tuple[int, ...]:
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
class _FilterSetup:
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
) -> _FilterSetup:
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
        return _FilterSetup(
            sigma, weights, np.concatenate([np.zeros(8), reference]), cov0 + q, q, 1e-9 * np.eye(len(idx)), 0.0, False
        )
    sigma = MerweScaledSigmaPoints(1.0, 2.0, 0.0)
    cov0, q, r = filter_noise(noise_fraction, len(idx))
    return _FilterSetup(sigma, sigma.weights(n), np.zeros(n), cov0, q, r, PRIOR_SD_LOG, True)


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


def _run_numpy(
    setup: _FilterSetup,
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


def _divergence(step: int, time_s: float, guess: FeedDriveParameters, noise_fraction: float) -> DivergenceError:
    """The error for a filter that diverged on a record it accepted."""
    frequencies = ", ".join(f"{f:.0f}" for f in modes(guess).frequencies_Hz)
    return DivergenceError(
        f"the filter diverged at sample {step} (t = {time_s:g} s): a parameter set within its prior gave a model whose "
        f"response is no longer finite. The guess (modes {frequencies} Hz) may be far from the drive, or the noise far "
        f"from the assumed {noise_fraction:g} of each response's RMS"
    )


def _parameter_notes(final_sd_log: FloatArray, prior_sd_log: float | None) -> list[str]:
    """A note for each parameter the record leaves beyond ±``IDENTIFIED_WITHIN`` (2σ): against the
    filter's prior where it has one (``prior_sd_log``), else (a refined estimate) as it is."""
    said = []
    for name, sd in zip(IDENTIFIED, final_sd_log, strict=True):
        if 2 * sd <= IDENTIFIED_WITHIN:
            continue
        if prior_sd_log is None:
            said.append(
                f"{name}: not identified (±{200 * sd:.2g} % at 2σ, beyond ±{100 * IDENTIFIED_WITHIN:g} %); a test plan "
                "says which test, if any, would identify it"
            )
        else:
            said.append(
                f"{name}: the data barely inform it (standard deviation {100 * sd:.0f} % after the record, prior "
                f"{100 * prior_sd_log:.0f} %); treat its estimate as the guess, not a measurement; a test plan says "
                "which test, if any, would identify it"
            )
    return said


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
    guess = validate(guess or default_guess())
    if not np.any(response.forces):
        # the filter then follows noise about rest: it diverged, or kept a guess far from the drive
        msg = (
            f"every force column is zero ({', '.join(FORCE_COLUMNS)}): nothing excites the drive, so its record "
            "holds nothing to identify; give the measured force or torque that drove it (a force column a file "
            "lacks is taken as zero)"
        )
        raise InputError(msg)
    indices = _measured_indices(response, measured)
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
    scaled = _scaled_problem(response, guess, indices, preset, noise_fraction, substeps, h)
    notes = _one_frequency_note(response.forces, h) or _sweep_note(response.forces, h)
    if preset == "paper":
        notes.append(
            "paper preset: α = 1/2, β = 2, κ = 3 give a negative centre weight W0m = -2.368 (Nguyen-Quoc et al. Eq. 41)"
        )
    ys = response.values[:, scaled.idx] / scaled.out_scale
    if engine == "compiled":
        means, variances, final_cov, failed = _run_compiled(scaled, ys, response.forces)
    else:
        config = FilterConfig(sigma_points=scaled.setup.sigma, name=f"feed drive ({preset})")
        means, variances, final_cov, failed = _run_numpy(
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


@dataclass(frozen=True)
class _ScaledProblem:
    """The filter's problem in its own units: the states and responses divided by their scales,
    the parameters (in log form) relative to the guess's."""

    guess: FeedDriveParameters
    setup: _FilterSetup
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


def _scaled_problem(
    response: Response,
    guess: FeedDriveParameters,
    indices: tuple[int, ...],
    preset: str,
    noise_fraction: float,
    substeps: int | None,
    h: float,
) -> _ScaledProblem:
    idx = np.array(indices)
    scale = _response_scales(response, guess, h)
    reference = guess.identified()
    setup = _filter_setup(preset, response, idx, reference, scale, noise_fraction)
    return _ScaledProblem(
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


def _run_compiled(
    scaled: _ScaledProblem, ys: FloatArray, forces: FloatArray
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


def _identification(
    scaled: _ScaledProblem,
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
    said = _parameter_notes(final_sd_log, setup.prior_sd_log) if setup.log_form else []
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
    scaled: _ScaledProblem,
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
    said = _force_noise_notes(input_sd, response.forces, widened)
    if not said:
        return result
    covariance_log = result.covariance_log * np.outer(widened, widened)
    sd_log = np.sqrt(np.diag(covariance_log))
    return replace(
        result,
        parameters_std=result.parameters * sd_log,
        identifiable=2 * sd_log <= IDENTIFIED_WITHIN,
        covariance_log=covariance_log,
        notes=(*notes, *_parameter_notes(sd_log, result.prior_sd_log), *said),
    )


def _checked(
    result: FeedDriveIdentification, scaled: _ScaledProblem, response: Response, noise_fraction: float
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
    notes = (*result.notes, *_consistency_notes(consistency, result.measured_columns))
    return replace(result, consistency=consistency, notes=notes)


def _refined(
    filtered: FeedDriveIdentification,
    scaled: _ScaledProblem,
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
    forced = _force_noise_notes(fit.input_noise, response.forces, fit.widened)
    refined = replace(
        filtered,
        parameters=values,
        parameters_std=values * sd_log,
        identifiable=2 * sd_log <= IDENTIFIED_WITHIN,
        covariance_log=fit.covariance_log,
        consistency=check,
        notes=(
            *_refined_notes(notes, response.forces, scaled.h),
            *_parameter_notes(sd_log, None),
            *forced,
            said,
        ),
        filter_parameters=filtered.parameters,
        filter_parameters_std=filtered.parameters_std,
    )
    return refined, said


# A parameter whose interval the forces' noise widens more than this many times is said: the record
# would pin it far closer with a cleaner force signal, and its interval rests on the noise estimated
# from the force record.
WIDENED_BY_FORCES = 2.0
# The forces' noise is said where it widens some interval by this much at least.
NOTED_WIDENING = 1.05


def _force_noise_notes(input_noise: FloatArray, forces: FloatArray, widened: FloatArray) -> list[str]:
    """What the noise on the measured forces did to the estimate's intervals (nothing where it widened none
    by ``NOTED_WIDENING``), and the parameters it widened beyond ``WIDENED_BY_FORCES``."""
    if float(np.max(widened)) < NOTED_WIDENING:
        return []  # none, or too little to move an interval (an exact sine's spectral floor, 1e-6 of its RMS)
    rms = np.sqrt(np.mean(forces**2, axis=0))
    acting = [q for q in range(len(input_noise)) if input_noise[q] > 0]
    levels = ", ".join(
        f"{FORCE_COLUMNS[q]} {input_noise[q]:.3g}"
        + (f" ({100 * input_noise[q] / rms[q]:.2g} % of its RMS)" if rms[q] > 0 else "")
        for q in acting
    )
    said = [
        f"the measured forces carry noise ({levels}, estimated from the force record as white noise): it drives "
        "the model where it did not drive the drive, and the intervals carry its effect (up to "
        f"{float(np.max(widened)):.2g}× wider than from the responses' noise alone)"
    ]
    flagged = [name for name, factor in zip(IDENTIFIED, widened, strict=True) if factor > WIDENED_BY_FORCES]
    if flagged:
        said.append(
            f"{', '.join(flagged)}: limited by the force signal's noise (its interval {WIDENED_BY_FORCES:g}× or more "
            "wider than the responses' noise alone gives, and resting on the force noise estimated from the record); "
            "a cleaner force signal (filtered, averaged over repeats, a better sensor) pins it closer"
        )
    return said


def _refined_notes(notes: list[str], forces: FloatArray, h: float) -> list[str]:
    """The notes of the record that still hold for its refined estimate (a sweep's, reworded)."""
    swept = _sweep_note(forces, h, refined=True)
    return [swept[0] if swept and note.startswith("the excitation sweeps") else note for note in notes]
