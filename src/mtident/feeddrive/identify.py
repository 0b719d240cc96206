"""Joint state/parameter estimation of the feed drive with a UKF (seed 004 §2.3, §3.2).

Augmented state (seed 004 Eq. 37): the 8 physical states and the 8 identified
parameters K1..K4, Bt, Bb, Qb, Qm. Differences from the paper (DESIGN.md errata):

* The transition integrates the same ODE as the simulator — classical RK4 with
  sub-steps, the input held over each sample — not Eq. 39's garbled Euler step.
* Physical states are scaled by the RMS of their responses and parameters are
  estimated as log(p/p_guess), so 1e8 N/m and 1e-3 N m s/rad live side by side
  in one well-conditioned covariance, with a small random walk on them.
* The parameters start from a wrong guess (default: the shipped set ±30 %) with a
  broad prior, not at the truth with zero variance (Eq. 44). The ``paper``
  preset reproduces Eq. 44 and the paper's α, β, κ, Q and R for comparison.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from mtident._typing import BoolArray, FloatArray
from mtident.exceptions import CovarianceError, InputError, NegativeWeightWarning
from mtident.feeddrive.model import exact_step, input_matrix, rk4_linear_step, system_matrix
from mtident.feeddrive.params import IDENTIFIED, FeedDriveParameters, validate
from mtident.feeddrive.simulate import FORCE_COLUMNS, RESPONSE_COLUMNS, Response, run_responses, simulate, substeps_for
from mtident.ukf import FilterConfig, GaussianState, MerweScaledSigmaPoints, filter_step, initial_carry

__all__ = ["FeedDriveIdentification", "identify_feed_drive", "MEASUREMENT_SETS", "PRESENT", "default_guess"]

# Which responses are measured: all 12 (seed 004), or what a machine usually has:
# table acceleration (accelerometer), motor angle and velocity (encoder).
MEASUREMENT_SETS = {
    "all": tuple(range(12)),
    "realistic": (RESPONSE_COLUMNS.index("a_t_m_per_s2"), RESPONSE_COLUMNS.index("theta_m_rad"), RESPONSE_COLUMNS.index("omega_m_rad_per_s")),
}
# The measurement set of the responses a file has (a machine's own log seldom has all 12).
PRESENT = "present"
# K1 low and K2 high keep the guess stable (K2 > K1).
GUESS_FACTORS = np.array([0.7, 1.3, 1.3, 0.7, 1.3, 0.7, 1.3, 0.7])


def default_guess(truth: FeedDriveParameters | None = None) -> FeedDriveParameters:
    """The shipped set with each identified parameter 30 % high or low (``GUESS_FACTORS``)."""
    base = truth or FeedDriveParameters()
    return base.with_identified(base.identified() * GUESS_FACTORS)


@dataclass(frozen=True)
class FeedDriveIdentification:
    """Result of the joint estimation.

    Attributes
    ----------
    parameters, parameters_sd : ndarray, shape (8,)
        Final estimates of ``IDENTIFIED`` and their standard deviations (SI).
    identifiable : ndarray of bool, shape (8,)
        The data shrank the parameter's prior standard deviation at least tenfold.
    history, history_sd : ndarray, shape (N, 8)
        Convergence of the parameter estimates.
    estimated : ndarray, shape (N, 12)
        Responses of the filtered states.
    correlation : dict
        Response name → correlation of estimated and measured response (Table 2).
    measured_columns : tuple of str
    guess : FeedDriveParameters
    """

    time_s: FloatArray
    parameters: FloatArray
    parameters_sd: FloatArray
    prior_sd_log: float
    identifiable: BoolArray
    history: FloatArray
    history_sd: FloatArray
    estimated: FloatArray
    correlation: dict[str, float]
    measured_columns: tuple[str, ...]
    guess: FeedDriveParameters
    preset: str
    notes: tuple[str, ...]

    def __repr__(self) -> str:
        rows = [
            f"  {name}: {value:.5g} ± {2 * sd:.2g} (2σ){'' if known else ', not identified'}"
            for name, value, sd, known in zip(IDENTIFIED, self.parameters, self.parameters_sd, self.identifiable, strict=True)
        ]
        return "\n".join([f"FeedDriveIdentification({self.preset}, {len(self.time_s)} samples, measured: {', '.join(self.measured_columns)})", *rows])

    def errors_percent(self, truth: FeedDriveParameters) -> dict[str, float]:
        """Table 3: 100·|estimate − truth|/truth per parameter."""
        true = truth.identified()
        return {name: float(100 * abs(v - t) / t) for name, v, t in zip(IDENTIFIED, self.parameters, true, strict=True)}

    def covers(self, truth: FeedDriveParameters) -> dict[str, bool]:
        """Whether ±2σ around each estimate contains the truth."""
        true = truth.identified()
        return {name: bool(abs(v - t) <= 2 * s) for name, v, s, t in zip(IDENTIFIED, self.parameters, self.parameters_sd, true, strict=True)}

    def summary(self, truth: FeedDriveParameters | None = None) -> dict[str, object]:
        """The contract's JSON object (DESIGN.md), plus extras."""
        out: dict[str, object] = {
            "parameters": {n: float(v) for n, v in zip(IDENTIFIED, self.parameters, strict=True)},
            "parameters_sd": {n: float(v) for n, v in zip(IDENTIFIED, self.parameters_sd, strict=True)},
            "identifiable": {n: bool(v) for n, v in zip(IDENTIFIED, self.identifiable, strict=True)},
            "correlation": self.correlation,
            "measured": list(self.measured_columns),
            "guess": {n: float(getattr(self.guess, n)) for n in IDENTIFIED},
            "preset": self.preset,
        }
        if truth is not None:
            out["error_percent"] = self.errors_percent(truth)
            out["within_2sd"] = self.covers(truth)
        return out


def _parameter_basis(fixed: FeedDriveParameters) -> tuple[FloatArray, FloatArray]:
    """A is linear in the identified parameters: A(p) = A₀ + Σⱼ pⱼ Dⱼ. Returns (A₀, D (8, 8, 8))."""
    a0 = np.zeros((8, 8))
    a0[:4, 4:] = np.eye(4)
    basis = np.zeros((8, 8, 8))
    for j, unit in enumerate(np.eye(8)):
        basis[j, 4:, :] = _system_rows(unit, fixed)  # the part of A that parameter j multiplies
    return a0, basis


def _system_rows(params: FloatArray, fixed: FeedDriveParameters) -> FloatArray:
    """Rows 5-8 of A, [−M⁻¹K | −M⁻¹C], for one vector of identified parameters K1..K4, Bt, Bb, Qb, Qm."""
    k1, k2, k3, k4, bt, bb, qb, qm = params
    beta = fixed.beta
    stiffness = np.array(
        [[k1, -k1, -beta * k1, 0.0], [-k1, k2, beta * k1, 0.0], [-beta * k1, beta * k1, k3, -k4], [0.0, 0.0, -k4, k4]]
    )
    m_inv = 1.0 / np.array([fixed.Mt, fixed.Mb, fixed.Jb, fixed.Jm])
    return np.hstack([-m_inv[:, None] * stiffness, -np.diag(m_inv * np.array([bt, bb, qb, qm]))])


def _build_matrices(params: FloatArray, basis: tuple[FloatArray, FloatArray]) -> FloatArray:
    """A (..., 8, 8) for identified parameters (..., 8) = K1..K4, Bt, Bb, Qb, Qm."""
    a0, d = basis
    return a0 + (params @ d.reshape(8, 64)).reshape(*params.shape[:-1], 8, 8)


# An estimate run open loop must stay within this many times the assumed noise (RMS) of each response.
_OPEN_LOOP_LIMIT = 3.0


def _open_loop_check(estimate: FeedDriveParameters, response: Response, states: FloatArray, idx: FloatArray, noise: FloatArray) -> list[str]:
    """A note if the final parameters, run open loop with the measured forces, do not reproduce the record.

    The filtered responses follow the data whatever the parameters (the states are
    corrected every sample: all correlations 0.99999 under a 100 Hz sine whose
    estimate was 17-45 % off, with intervals under 1 %). Run from the filtered state
    a tenth into the record, a wrong estimate leaves the data by many times the noise.
    """
    start = len(response.time_s) // 10
    try:
        phi, gamma = exact_step(system_matrix(estimate), input_matrix(estimate), float(response.time_s[1] - response.time_s[0]))
    except (InputError, np.linalg.LinAlgError):
        return []  # a non-physical estimate: the filter's own notes and intervals speak for it
    replay = run_responses(estimate, phi, gamma, states[start], response.forces[start:])[:, idx]
    with np.errstate(invalid="ignore", over="ignore"):
        misfit = np.sqrt(np.nanmean(((replay - response.values[start:, idx]) / noise) ** 2, axis=0))
    worst = int(np.nanargmax(np.where(np.isfinite(misfit), misfit, np.inf))) if np.any(~(misfit <= _OPEN_LOOP_LIMIT)) else -1
    if worst < 0:
        return []
    name = RESPONSE_COLUMNS[int(idx[worst])]
    return [
        f"the estimate does not reproduce the record: run open loop with the measured forces from t = {response.time_s[start]:g} s, {name} leaves the data by "
        f"{misfit[worst]:.1f}× the assumed noise (RMS; at most {_OPEN_LOOP_LIMIT:g} expected). The filter may have settled on a wrong set (an excitation of one "
        "frequency near a mode does this), or the noise is larger than --noise says: the intervals do not hold"
    ]


# A force this close to one sine (the share of its variance a sine at its strongest frequency explains)
# excites one frequency only.
_ONE_FREQUENCY_SHARE = 0.95


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
            basis = np.column_stack([np.sin(2 * np.pi * frequency * t), np.cos(2 * np.pi * frequency * t), np.ones_like(t)])
            fitted = basis @ np.linalg.lstsq(basis, f, rcond=None)[0]
            share = 1.0 - float(np.sum((f - fitted) ** 2) / np.sum(f**2))
            best, best_frequency = max((best, best_frequency), (share, frequency))
        if best < _ONE_FREQUENCY_SHARE:
            return []
        found.append(f"{FORCE_COLUMNS[k]} at {best_frequency:.3g} Hz")
    return [
        f"the excitation is one frequency ({', '.join(found)}): the record shows the drive's response at that frequency alone, "
        "too little to tell its stiffness and damping parameters apart; an impulse, a step or a sweep excites every mode"
    ]


def identify_feed_drive(
    response: Response,
    guess: FeedDriveParameters | None = None,
    measured: str | tuple[int, ...] = "all",
    noise_fraction: float = 0.01,
    preset: str = "default",
    substeps: int | None = None,
    progress: Callable[[int, int], None] | None = None,
    engine: str = "compiled",
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
        ``paper``: seed 004's α = 1/2, β = 2, κ = 3, Q = 1e-4·I, R = 1e-9·I and
        P₀ of Eq. 44 (zero variance on the parameters), in unscaled SI units.
    substeps : int, optional
        RK4 sub-steps per sample in the transition (default: ω_max·h ≤ 0.15, 8 at 10 kHz;
        with 4 the discretisation error biases the damping estimates past their 2σ).
    progress : callable, optional
        ``progress(step, total)`` every 500 steps (numpy engine only).
    engine : {"compiled", "numpy"}
        The numba-compiled loop (:mod:`mtident.feeddrive.fast`) or the generic
        :mod:`mtident.ukf` engine; both compute the same filter.
    """
    guess = validate(guess or default_guess())
    if isinstance(measured, str) and measured not in (PRESENT, *MEASUREMENT_SETS):
        msg = f"measurement set {measured!r} is not one of: {', '.join((PRESENT, *MEASUREMENT_SETS))}"
        raise InputError(msg)
    in_file = tuple(i for i in range(len(RESPONSE_COLUMNS)) if not np.all(np.isnan(response.values[:, i])))
    indices = in_file if measured == PRESENT else MEASUREMENT_SETS[measured] if isinstance(measured, str) else tuple(measured)
    missing = [RESPONSE_COLUMNS[i] for i in indices if i not in in_file]
    if missing:
        msg = f"the response has no {missing[0]!r} column, which the measurement set {measured!r} needs"
        raise InputError(msg)
    constant = [RESPONSE_COLUMNS[i] for i in indices if np.ptp(response.values[:, i]) == 0]
    if constant:
        msg = (
            f"the response column {constant[0]!r} is constant throughout ({response.values[0, RESPONSE_COLUMNS.index(constant[0])]:g}): "
            "a dead channel, or no excitation; check it, or choose a measurement set without it"
        )
        raise InputError(msg)
    if preset not in ("default", "paper"):
        msg = f"preset {preset!r} is not one of: default, paper"
        raise InputError(msg)
    h = float(response.time_s[1] - response.time_s[0])
    m = substeps or substeps_for(guess, h, max_phase_step=0.15)
    idx = np.array(indices)
    ys = response.values[:, idx]
    forces = response.forces
    b_matrix = input_matrix(guess)
    basis = _parameter_basis(guess)
    m_inv = 1.0 / np.array([guess.Mt, guess.Mb, guess.Jb, guess.Jm])
    reference = guess.identified()
    notes = _one_frequency_note(forces, h)

    # Scales: the RMS of each measured response; for the others, of a simulation of the
    # guess with the same input (only run when some response is not in the file).
    present = np.isfinite(response.values)
    counts = present.sum(axis=0)
    rms_data = np.sqrt(np.sum(np.where(present, response.values**2, 0.0), axis=0) / np.maximum(counts, 1))
    known = (counts > 0) & (rms_data > 0)
    rms_model = np.ones(12)
    if not known.all() and np.any(forces):
        model = simulate(guess, sample_rate_Hz=1.0 / h, duration_s=h * (len(response.time_s) - 1), method="exact")
        rms_model = np.sqrt(np.mean(model.values**2, axis=0))
    scale = np.where(known, rms_data, rms_model)
    scale = np.where(scale > 0, scale, 1.0)
    if preset == "paper":
        state_scale = np.ones(8)
        out_scale = np.ones(len(idx))
    else:
        state_scale = scale[:8]
        out_scale = scale[idx]

    log_form = preset != "paper"

    def to_params(z: FloatArray) -> FloatArray:
        return reference * np.exp(z[..., 8:]) if log_form else z[..., 8:]

    def transition_at(k: int) -> Callable[[FloatArray], FloatArray]:
        u = forces[k - 1]

        def transition(points: FloatArray) -> FloatArray:
            params = to_params(points)
            phi, gamma = rk4_linear_step(_build_matrices(params, basis), b_matrix, h, m)
            x = points[..., :8] * state_scale
            x_next = (phi @ x[..., None])[..., 0] + gamma @ u
            return np.concatenate([x_next / state_scale, points[..., 8:]], axis=-1)

        return transition

    def measurement_at(k: int) -> Callable[[FloatArray], FloatArray]:
        f = forces[k]

        def measure(points: FloatArray) -> FloatArray:
            x = points[..., :8] * state_scale
            a = _build_matrices(to_params(points), basis)
            acc = (a[..., 4:, :] @ x[..., None])[..., 0] + m_inv * f
            full = np.concatenate([x, acc], axis=-1)
            return full[..., idx] / out_scale

        return measure

    n = 16
    if preset == "paper":
        sigma = MerweScaledSigmaPoints(0.5, 2.0, 3.0)
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", NegativeWeightWarning)
            weights = sigma.weights(n)
        notes.append("paper preset: α = 1/2, β = 2, κ = 3 give a negative centre weight W0m = -2.368 (seed 004 Eq. 41)")
        mean0 = np.concatenate([np.zeros(8), reference])
        state_var = np.nan_to_num(np.nanvar(response.values[:, :8], axis=0), nan=1e-12)
        cov0 = np.diag(np.concatenate([np.maximum(state_var, 1e-30), np.zeros(8)]))
        q = 1e-4 * np.eye(n)
        r = 1e-9 * np.eye(len(idx))
        prior_sd_log = 0.0
    else:
        sigma = MerweScaledSigmaPoints(1.0, 2.0, 0.0)
        weights = sigma.weights(n)
        prior_sd_log = 0.5
        mean0 = np.zeros(n)
        cov0 = np.diag(np.concatenate([np.full(8, 1e-4), np.full(8, prior_sd_log**2)]))
        q = np.diag(np.concatenate([np.full(8, 1e-8), np.full(8, 1e-12)]))
        r = np.diag((noise_fraction * scale[idx] / out_scale) ** 2)
    config = FilterConfig(sigma_points=sigma, name=f"feed drive ({preset})")
    # P₀ of Eq. 44 is singular (zero variance on the parameters): the first time update adds Q.
    cov_start = cov0 if preset != "paper" else cov0 + q
    carry = initial_carry(GaussianState(mean0, cov_start), q, r, config)
    steps = len(response.time_s)
    if engine == "compiled":
        from mtident.feeddrive.fast import run_feed_drive_ukf

        a0, d = basis
        means, variances, _, failed, eigenvalue = run_feed_drive_ukf(
            mean0, cov_start, q, r, ys / out_scale, forces * m_inv, weights.mean, weights.cov, weights.spread,
            state_scale, out_scale, idx.astype(np.int64), a0, d, reference, h, m, log_form,
        )
        if failed >= 0:
            raise CovarianceError("sigma points of the previous posterior", None, float(eigenvalue), int(failed), config.name)
    elif engine == "numpy":
        carry = initial_carry(GaussianState(mean0, cov_start), q, r, config)
        means = np.empty((steps, n))
        variances = np.empty((steps, n))
        means[0], variances[0] = carry.mean, np.diag(carry.covariance())
        for k in range(1, steps):
            try:
                carry, _ = filter_step(carry, ys[k] / out_scale, transition_at(k), measurement_at(k), config, weights)
            except CovarianceError as exc:
                raise exc.at(k, config.name) from exc
            means[k], variances[k] = carry.mean, np.diag(carry.covariance())
            if progress is not None and k % 500 == 0:
                progress(k, steps)
    else:
        msg = f"engine {engine!r} is not one of: compiled, numpy"
        raise InputError(msg)

    param_hist = to_params(means)
    var_z = variances[:, 8:]
    hist_sd = param_hist * np.sqrt(var_z) if log_form else np.sqrt(var_z)
    states = means[:, :8] * state_scale
    acc = np.einsum("nij,nj->ni", _build_matrices(param_hist, basis)[:, 4:, :], states) + m_inv * forces
    estimated = np.hstack([states, acc])
    correlation = {}
    for i in idx:
        a_, b_ = estimated[:, i], response.values[:, i]
        ok = np.isfinite(b_)
        correlation[RESPONSE_COLUMNS[i]] = float(np.corrcoef(a_[ok], b_[ok])[0, 1])
    final_sd_log = np.sqrt(var_z[-1])
    identifiable = final_sd_log < 0.1 * prior_sd_log if log_form else np.zeros(8, dtype=bool)
    for name, ok_, sd in zip(IDENTIFIED, identifiable, final_sd_log, strict=True):
        if log_form and not ok_:
            notes.append(f"{name}: the data barely inform it (standard deviation {100 * sd:.0f} % after the record, prior {100 * prior_sd_log:.0f} %); treat its estimate as the guess, not a measurement")
    notes.extend(_open_loop_check(guess.with_identified(param_hist[-1]), response, states, idx, noise_fraction * scale[idx]))
    return FeedDriveIdentification(
        time_s=response.time_s,
        parameters=param_hist[-1],
        parameters_sd=hist_sd[-1],
        prior_sd_log=prior_sd_log,
        identifiable=identifiable,
        history=param_hist,
        history_sd=hist_sd,
        estimated=estimated,
        correlation=correlation,
        measured_columns=tuple(RESPONSE_COLUMNS[i] for i in idx),
        guess=guess,
        preset=preset,
        notes=tuple(notes),
    )
