"""The feed-drive UKF loop compiled with numba (the hot loop of ``identify_feed_drive``), and the
loops over a record of :mod:`mtident.feeddrive.information` (sensitivities for the open-loop check,
the filter's covariance recursion for the test plan).

It runs exactly the standard UKF of :mod:`mtident.ukf` (Xia et al. 2014 Eqs 5-20:
propagated sigma points, additive Q and R, P⁺ = P⁻ − K Py Kᵀ) on the augmented
feed-drive state, with the transition integrated by classical RK4 sub-steps.
The generic engine spends ~0.5 ms a step in numpy call overhead for a 16-state,
12-output filter; compiled, a step costs tens of microseconds, which makes a
2 s record at 10 kHz faster than real time. ``tests/feeddrive/test_simulate.py`` checks
that both give the same numbers.
"""

from __future__ import annotations

from typing import TypeAlias

import numpy as np
from numba import njit

from mtident._typing import FloatArray

__all__ = [
    "run_feed_drive_ukf",
    "response_moments",
    "covariance_recursion",
    "input_noise_moments",
    "input_response_energy",
    "compiled_cache_ready",
]

# (Φ (8, 8), Γ (8, 4), Φₛ (8, 8, 8), Γₛ (8, 8, 4)): the exact one-sample step of the state and of its
# sensitivities; (c (R, 8), e (R, 4), cₛ (R, 8, 8)): the output rows of R responses
Step: TypeAlias = tuple[FloatArray, FloatArray, FloatArray, FloatArray]
Rows: TypeAlias = tuple[FloatArray, FloatArray, FloatArray]


@njit(cache=True, fastmath=False)
def _derivative(a: FloatArray, x: FloatArray, drive: FloatArray, out: FloatArray) -> None:
    for r in range(4):
        out[r] = x[4 + r]
    for r in range(4, 8):
        acc = drive[r - 4]
        for c in range(8):
            acc += a[r, c] * x[c]
        out[r] = acc


@njit(cache=True, fastmath=False)
def _rk4(a: FloatArray, y: FloatArray, drive: FloatArray, h: float, substeps: int, work: FloatArray) -> None:
    """Classical RK4 in place on y (8,), ``substeps`` steps of h/substeps; work is (5, 8) scratch."""
    d = h / substeps
    k1, k2, k3, k4, tmp = work[0], work[1], work[2], work[3], work[4]
    for _ in range(substeps):
        _derivative(a, y, drive, k1)
        for i in range(8):
            tmp[i] = y[i] + 0.5 * d * k1[i]
        _derivative(a, tmp, drive, k2)
        for i in range(8):
            tmp[i] = y[i] + 0.5 * d * k2[i]
        _derivative(a, tmp, drive, k3)
        for i in range(8):
            tmp[i] = y[i] + d * k3[i]
        _derivative(a, tmp, drive, k4)
        for i in range(8):
            y[i] += d / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i])


@njit(cache=True, fastmath=False)
def _system(
    z: FloatArray, a0: FloatArray, basis: FloatArray, reference: FloatArray, log_form: bool, a: FloatArray
) -> None:
    """A(p) into ``a`` for the parameters in z[8:] (log form: p = reference·e^z)."""
    a[:] = a0
    for j in range(8):
        p = reference[j] * np.exp(z[8 + j]) if log_form else z[8 + j]
        for r in range(4, 8):
            for c in range(8):
                a[r, c] += p * basis[j, r, c]


@njit(cache=True, fastmath=False)
def run_feed_drive_ukf(
    mean0: FloatArray,
    cov0: FloatArray,
    process_cov: FloatArray,
    emission_cov: FloatArray,
    emissions: FloatArray,
    drives: FloatArray,
    weights_mean: FloatArray,
    weights_cov: FloatArray,
    spread: float,
    state_scale: FloatArray,
    output_scale: FloatArray,
    measured: np.ndarray,
    a0: FloatArray,
    basis: FloatArray,
    reference: FloatArray,
    h: float,
    substeps: int,
    log_form: bool,
) -> tuple[FloatArray, FloatArray, FloatArray, int, float]:
    """Filter ``emissions`` (N, m); returns (means (N, 16), variances (N, 16), final covariance,
    failed step or −1, smallest eigenvalue there: NaN where a number stopped being finite).

    ``drives`` (N, 4) is M⁻¹F at each sample (held over the interval that starts there).

    Parameters
    ----------
    mean0 : ndarray, shape (16,)
        Initial mean of the augmented state: the 8 states divided by ``state_scale``, then the 8
        identified parameters K1..K4, Bt, Bb, Qb, Qm (their logs relative to ``reference`` when
        ``log_form``, else in SI units).
    cov0 : ndarray, shape (16, 16)
        Initial covariance, in the same scaled units.
    process_cov : ndarray, shape (16, 16)
        Process noise covariance Q, added at every time update.
    emission_cov : ndarray, shape (m, m)
        Measurement noise covariance R of the scaled responses.
    emissions : ndarray, shape (N, m)
        Measured responses divided by ``output_scale``; row 0 is not used (the filter starts there).
    drives : ndarray, shape (N, 4)
        M⁻¹F: the generalized forces divided by the masses and inertias (m/s², rad/s²).
    weights_mean, weights_cov : ndarray, shape (33,)
        Sigma-point weights for the mean and the covariance (2·16 + 1 points).
    spread : float
        The sigma points lie at the mean ± ``spread`` times the columns of the lower Cholesky factor
        of the covariance (√(n + λ)).
    state_scale : ndarray, shape (8,)
        Physical state = scaled state × ``state_scale`` (ones for no scaling).
    output_scale : ndarray, shape (m,)
        Divisor of each measured response (ones for no scaling).
    measured : ndarray of int, shape (m,)
        The measured responses: indices into the 12 responses (the 8 states, then the 4
        accelerations), as ``RESPONSE_COLUMNS`` orders them.
    a0 : ndarray, shape (8, 8)
        The part of A that does not depend on the identified parameters (``model.parameter_basis``).
    basis : ndarray, shape (8, 8, 8)
        Dⱼ, the part of A that parameter j multiplies (``model.parameter_basis``).
    reference : ndarray, shape (8,)
        Parameters (SI) the log form is relative to: p = reference·e^z.
    h : float
        Sampling interval (s).
    substeps : int
        RK4 sub-steps per sample.
    log_form : bool
        The parameter states are log-parameters (else the parameters themselves).

    Returns
    -------
    means : ndarray, shape (N, 16)
        Filtered means (rows after a failed step are not filled).
    variances : ndarray, shape (N, 16)
        Diagonals of the filtered covariances.
    cov : ndarray, shape (16, 16)
        The final covariance, or the one at the failed step.
    failed : int
        The step at which the filter stopped (no Cholesky factor, or a non-finite number), −1 if none.
    smallest_eigenvalue : float
        Smallest eigenvalue of the covariance the Cholesky factor failed on; NaN where a number
        stopped being finite; 0.0 when the filter ran through.
    """
    n = mean0.shape[0]
    count = emissions.shape[0]
    m = measured.shape[0]
    s = 2 * n + 1
    means = np.empty((count, n))
    variances = np.empty((count, n))
    mean = mean0.copy()
    cov = cov0.copy()
    means[0] = mean
    for i in range(n):
        variances[0, i] = cov[i, i]
    sig = np.empty((s, n))
    prop = np.empty((s, n))
    outs = np.empty((s, m))
    full = np.empty(12)
    a = np.empty((8, 8))
    xn = np.empty(8)
    work = np.empty((5, 8))
    for k in range(1, count):
        # Sigma points: columns of the lower Cholesky factor.
        try:
            chol = np.linalg.cholesky(cov)
        except Exception:  # noqa: BLE001 - numba raises a generic error; report the step
            return means, variances, cov, k, np.linalg.eigvalsh(0.5 * (cov + cov.T))[0]
        for i in range(n):
            sig[0, i] = mean[i]
        for c in range(n):
            for i in range(n):
                sig[1 + c, i] = mean[i] + spread * chol[i, c]
                sig[1 + n + c, i] = mean[i] - spread * chol[i, c]
        # Time update through RK4, and the measurement of each propagated point.
        for p in range(s):
            _system(sig[p], a0, basis, reference, log_form, a)
            for i in range(8):
                xn[i] = sig[p, i] * state_scale[i]
            _rk4(a, xn, drives[k - 1], h, substeps, work)
            for i in range(8):
                prop[p, i] = xn[i] / state_scale[i]
            for i in range(8, n):
                prop[p, i] = sig[p, i]
            for i in range(8):
                full[i] = xn[i]
            for r in range(4):
                acc = drives[k, r]
                for c in range(8):
                    acc += a[4 + r, c] * xn[c]
                full[8 + r] = acc
            for j in range(m):
                outs[p, j] = full[measured[j]] / output_scale[j]
        prior = weights_mean @ prop
        dx = prop - prior
        prior_cov = (dx.T * weights_cov) @ dx + process_cov
        y_mean = weights_mean @ outs
        dy = outs - y_mean
        pyy = (dy.T * weights_cov) @ dy + emission_cov
        pxy = (dx.T * weights_cov) @ dy
        if not (np.all(np.isfinite(pyy)) and np.all(np.isfinite(pxy))):
            return means, variances, cov, k, np.nan
        gain = np.linalg.solve(pyy, pxy.T).T
        mean = prior + gain @ (emissions[k] - y_mean)
        cov = prior_cov - gain @ pyy @ gain.T
        cov = 0.5 * (cov + cov.T)
        if not (np.all(np.isfinite(cov)) and np.all(np.isfinite(mean))):
            # a sigma point's model blew up (unstable or unresolved): stop here, not at a NaN later
            return means, variances, cov, k, np.nan
        means[k] = mean
        for i in range(n):
            variances[k, i] = cov[i, i]
    return means, variances, cov, -1, 0.0


@njit(cache=True, fastmath=False)
def response_moments(
    system: tuple[Step, Rows], start: FloatArray, forces: FloatArray, data: FloatArray, with_start: bool
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Run the state X, its sensitivities sⱼ to the log-parameters and (``with_start``) fᵢ to the
    initial state over the record, and accumulate per response r the moments of its sensitivities
    and of its residual against ``data`` (N, R), NaN where not measured.

    ``system`` = (step, rows), step = (Φ (8, 8), Γ (8, 4), Φₛ (8, 8, 8), Γₛ (8, 8, 4)): X⁺ = Φ X + Γ u and
    sⱼ⁺ = Φₛⱼ X + Φ sⱼ + Γₛⱼ u (the exact step of the augmented system is block triangular);
    rows = (c (R, 8), e (R, 4), cₛ (R, 8, 8)): ŷ = c X + e u, ∂ŷ/∂zⱼ = c sⱼ + cₛⱼ X, ∂ŷ/∂X₀ᵢ = c fᵢ.
    Returns (G (R, P, P) = Σ g gᵀ, b (R, P) = Σ g (y − ŷ), c (R,) = Σ (y − ŷ)², s (R,) = Σ ŷ²),
    P = 8 or 16, the residual sums over the measured samples only.

    Parameters
    ----------
    system : (step, rows)
        step = (Φ (8, 8), Γ (8, 4), Φₛ (8, 8, 8), Γₛ (8, 8, 4)), the exact one-sample step of the state and
        of its sensitivities; rows = (c (R, 8), e (R, 4), cₛ (R, 8, 8)), the output rows of the R responses
        (``information.sensitivity_system``).
    start : ndarray, shape (8,)
        Initial state X₀ (SI units).
    forces : ndarray, shape (N, 4)
        Generalized forces u (N, N, N m, N m), held over each sample.
    data : ndarray, shape (N, R)
        Measured responses (SI units), NaN where not measured.
    with_start : bool
        Also take the sensitivities to the initial state (P = 16 instead of 8).

    Returns
    -------
    G : ndarray, shape (R, P, P)
        Σ g gᵀ over all samples, g the sensitivity of the response.
    b : ndarray, shape (R, P)
        Σ g (y − ŷ) over the measured samples.
    c : ndarray, shape (R,)
        Σ (y − ŷ)² over the measured samples.
    s : ndarray, shape (R,)
        Σ ŷ² over all samples.
    """
    step, (c_row, e_row, c_s) = system
    r_count = data.shape[1]
    p = 16 if with_start else 8
    big_g = np.zeros((r_count, p, p))
    big_b = np.zeros((r_count, p))
    big_c = np.zeros(r_count)
    big_s = np.zeros(r_count)
    x = start.copy()
    sens = np.zeros((8, 8))
    free = np.eye(8)
    g = np.empty(p)
    for k in range(forces.shape[0]):
        u = forces[k]
        for r in range(r_count):
            model = 0.0
            for i in range(8):
                model += c_row[r, i] * x[i]
            for i in range(4):
                model += e_row[r, i] * u[i]
            _sensitivities(x, sens, free, c_row, c_s, r, g)
            big_s[r] += model * model
            for a in range(p):
                for b in range(a, p):
                    big_g[r, a, b] += g[a] * g[b]
            y = data[k, r]
            if y == y:  # measured (not NaN)
                res = y - model
                big_c[r] += res * res
                for a in range(p):
                    big_b[r, a] += g[a] * res
        _advance(step, u, x, sens, free, with_start)
    for r in range(r_count):
        for a in range(p):
            for b in range(a):
                big_g[r, a, b] = big_g[r, b, a]
    return big_g, big_b, big_c, big_s


@njit(cache=True, fastmath=False)
def covariance_recursion(
    step: Step,
    forces: FloatArray,
    rows: Rows,
    state_scale: FloatArray,
    output_scale: FloatArray,
    noise: tuple[FloatArray, FloatArray, FloatArray],
) -> tuple[FloatArray, FloatArray]:
    """The Kalman covariance recursion of the augmented filter (8 scaled states, 8 log-parameters)
    linearised along the noise-free response from rest. Returns the final covariances (16, 16):

    * the filter's own, P: for a model linear in its unknowns, the inverse of the Fisher information
      with the filter's process noise and prior (Sarkka 2013, §4.3, §12.1), which the UKF, a
      second-order method, follows to the order of its linearisation;
    * the scatter its estimate actually has over draws of the measurement noise when the record
      has no process noise: the error ε⁺ = (I − KH)(F ε) + K v of a filter run with gains K
      designed for noise the data lack (Gelb, Applied Optimal Estimation, 1974, §7.2).

    ``step`` and ``rows`` as in :func:`response_moments`; ``noise`` = (P₀ (16, 16), Q (16, 16),
    R (m, m)) in the filter's scaled units.

    Parameters
    ----------
    step : tuple of ndarray
        (Φ (8, 8), Γ (8, 4), Φₛ (8, 8, 8), Γₛ (8, 8, 4)), as in :func:`response_moments`.
    forces : ndarray, shape (N, 4)
        Generalized forces (N, N, N m, N m), held over each sample.
    rows : tuple of ndarray
        (c (m, 8), e (m, 4), cₛ (m, 8, 8)), as in :func:`response_moments` (e is not used).
    state_scale : ndarray, shape (8,)
        Scale of each state in the filter (physical = scaled × scale).
    output_scale : ndarray, shape (m,)
        Scale of each measured response.
    noise : tuple of ndarray
        (P₀ (16, 16), Q (16, 16), R (m, m)): the filter's prior, process and measurement noise
        covariances in its scaled units.

    Returns
    -------
    cov : ndarray, shape (16, 16)
        P, the filter's own final covariance.
    scatter : ndarray, shape (16, 16)
        The covariance of its estimation error over draws of the measurement noise alone.
    """
    phi, gamma, phi_s, gamma_s = step
    c_row, _, c_s = rows
    cov0, process_cov, emission_cov = noise
    m = c_row.shape[0]
    cov = cov0.copy()
    scatter = np.zeros((16, 16))
    x = np.zeros(8)
    x_next = np.empty(8)
    trans = np.eye(16)
    meas = np.zeros((m, 16))
    for i in range(8):
        for j in range(8):
            trans[i, j] = phi[i, j] * state_scale[j] / state_scale[i]
    for r in range(m):
        for i in range(8):
            meas[r, i] = c_row[r, i] * state_scale[i] / output_scale[r]
    for k in range(1, forces.shape[0]):
        u = forces[k - 1]
        # ∂X⁺/∂zⱼ over one sample, from the state at its start: the j-th sensitivity system's step
        for j in range(8):
            for i in range(8):
                acc = 0.0
                for c in range(8):
                    acc += phi_s[j, i, c] * x[c]
                for c in range(4):
                    acc += gamma_s[j, i, c] * u[c]
                trans[i, 8 + j] = acc / state_scale[i]
        for i in range(8):
            x_next[i] = _state_step(phi, gamma, x, u, i)
        x[:] = x_next
        prior = trans @ cov @ trans.T + process_cov
        for r in range(m):
            for j in range(8):
                acc = 0.0
                for c in range(8):
                    acc += c_s[r, j, c] * x[c]
                meas[r, 8 + j] = acc / output_scale[r]
        cross = prior @ meas.T
        innovation = meas @ cross + emission_cov
        gain = np.linalg.solve(innovation, cross.T).T
        cov = prior - gain @ innovation @ gain.T
        cov = 0.5 * (cov + cov.T)
        closed = (np.eye(16) - gain @ meas) @ trans
        scatter = closed @ scatter @ closed.T + gain @ emission_cov @ gain.T
        scatter = 0.5 * (scatter + scatter.T)
    return cov, scatter


@njit(cache=True, fastmath=False)
def _sensitivities(
    x: FloatArray,
    sens: FloatArray,
    free: FloatArray,
    c_row: FloatArray,
    c_s: FloatArray,
    r: int,
    g: FloatArray,
) -> None:
    """g (P,) = ∂ŷᵣ/∂(log-parameters, initial state) at one sample (P = 8 or 16, by g's length)."""
    for j in range(8):
        acc = 0.0
        for i in range(8):
            acc += c_row[r, i] * sens[j, i] + c_s[r, j, i] * x[i]
        g[j] = acc
    if g.shape[0] > 8:
        for j in range(8):
            acc = 0.0
            for i in range(8):
                acc += c_row[r, i] * free[j, i]
            g[8 + j] = acc


@njit(cache=True, fastmath=False)
def _state_step(phi: FloatArray, gamma: FloatArray, x: FloatArray, u: FloatArray, i: int) -> float:
    """Row i of the state's exact one-sample step: (Φ X + Γ u)ᵢ."""
    acc = 0.0
    for c in range(8):
        acc += phi[i, c] * x[c]
    for c in range(4):
        acc += gamma[i, c] * u[c]
    return acc


@njit(cache=True, fastmath=False)
def _advance(
    step: Step,
    u: FloatArray,
    x: FloatArray,
    sens: FloatArray,
    free: FloatArray,
    with_start: bool,
) -> None:
    """One sample of the state, its sensitivities to the log-parameters and (``with_start``) to the initial state."""
    phi, gamma, phi_s, gamma_s = step
    x_next = np.empty(8)
    sens_next = np.empty((8, 8))
    free_next = np.empty((8, 8))
    for i in range(8):
        x_next[i] = _state_step(phi, gamma, x, u, i)
        for j in range(8):
            acc = 0.0
            for c in range(8):
                acc += phi_s[j, i, c] * x[c] + phi[i, c] * sens[j, c]
            for c in range(4):
                acc += gamma_s[j, i, c] * u[c]
            sens_next[j, i] = acc
            if with_start:
                acc = 0.0
                for c in range(8):
                    acc += phi[i, c] * free[j, c]
                free_next[j, i] = acc
    x[:] = x_next
    sens[:] = sens_next
    if with_start:
        free[:] = free_next


@njit(cache=True, fastmath=False)
def _through_adjoint(
    adjoint: FloatArray, matrix: FloatArray, row: FloatArray, output_rows: FloatArray, out: FloatArray
) -> None:
    """out (P, Q) = λ M + Σᵣ wᵣ gᵣ oᵣ: the adjoint λ (P, 8) through M (8, Q) (Γ or Φ), plus one sample's
    weighted gradients ``row`` (R, P) through the output rows o (R, Q) (e or c)."""
    for a in range(out.shape[0]):
        for q in range(out.shape[1]):
            acc = 0.0
            for i in range(8):
                acc += adjoint[a, i] * matrix[i, q]
            for r in range(row.shape[0]):
                acc += row[r, a] * output_rows[r, q]
            out[a, q] = acc


@njit(cache=True, fastmath=False)
def input_noise_moments(
    system: tuple[Step, Rows],
    start: FloatArray,
    forces: FloatArray,
    measured: FloatArray,
    weight: FloatArray,
    input_var: FloatArray,
    with_start: bool,
) -> FloatArray:
    """How white noise on the measured forces moves a least-squares fit of the record: M (P, P) =
    Σₘ Aₘ diag(``input_var``) Aₘᵀ, Aₘ = ∂(Σₖ Σᵣ wᵣ gₖᵣ (yₖᵣ − ŷₖᵣ))/∂uₘ the gradient's sensitivity to
    the force held over sample m. A fit whose Hessian is H then errs by H⁻¹ M H⁻¹ more (to first order)
    than it does from the responses' noise alone.

    The force uₘ moves every later response through the model, ŷₖ = c Φᵏ⁻ᵐ⁻¹ Γ uₘ (k > m) and e uₘ (k = m),
    so Aₘ = λₘ Γ + Σᵣ wᵣ gₘᵣ eᵣ with the adjoint λₘ = λₘ₊₁ Φ + Σᵣ wᵣ gₘ₊₁,ᵣ cᵣ run backwards from the
    record's end. The sensitivities gₖ are recomputed backwards segment by segment from states kept at
    the segments' starts (about √N of them): memory O(√N), two passes forward.

    Parameters
    ----------
    system, start, forces
        The step (Φ, Γ, Φₛ, Γₛ) and the output rows (c, e, cₛ), the initial state X₀ and the forces u, as
        in :func:`response_moments`.
    measured : ndarray, shape (N, R)
        1 where the response is measured (its residual is fitted), else 0.
    weight : ndarray, shape (R,)
        1/σ² of each response, as the fit weighs it.
    input_var : ndarray, shape (4,)
        Variance of the white noise on each force column.
    with_start : bool
        The initial state is fitted too (P = 16, else 8).

    Returns
    -------
    ndarray, shape (P, P)
        M.
    """
    step, (c_row, e_row, c_s) = system
    phi, gamma, _, _ = step
    r_count = c_row.shape[0]
    n = forces.shape[0]
    p = 16 if with_start else 8
    length = max(1, int(np.sqrt(n)) + 1)
    segments = (n + length - 1) // length
    keep_x = np.empty((segments, 8))
    keep_sens = np.empty((segments, 8, 8))
    keep_free = np.empty((segments, 8, 8))
    x = start.copy()
    sens = np.zeros((8, 8))
    free = np.eye(8)
    for k in range(n):
        if k % length == 0:
            keep_x[k // length] = x
            keep_sens[k // length] = sens
            keep_free[k // length] = free
        _advance(step, forces[k], x, sens, free, with_start)
    big_m = np.zeros((p, p))
    adjoint = np.zeros((p, 8))
    adjoint_next = np.empty((p, 8))
    grads = np.zeros((length, r_count, p))
    g = np.empty(p)
    a_m = np.empty((p, 4))
    for s in range(segments - 1, -1, -1):
        first = s * length
        last = min(n, first + length)
        x[:] = keep_x[s]
        sens[:] = keep_sens[s]
        free[:] = keep_free[s]
        for k in range(first, last):
            for r in range(r_count):
                _sensitivities(x, sens, free, c_row, c_s, r, g)
                for a in range(p):
                    grads[k - first, r, a] = g[a] * weight[r] * measured[k, r]
            _advance(step, forces[k], x, sens, free, with_start)
        for m in range(last - 1, first - 1, -1):
            row = grads[m - first]
            _through_adjoint(adjoint, gamma, row, e_row, a_m)
            for a in range(p):
                for b in range(a, p):
                    acc = 0.0
                    for q in range(4):
                        acc += a_m[a, q] * input_var[q] * a_m[b, q]
                    big_m[a, b] += acc
            # λ for the sample before: λₘ₋₁ = λₘ Φ + Σᵣ wᵣ gₘᵣ cᵣ
            _through_adjoint(adjoint, phi, row, c_row, adjoint_next)
            adjoint[:] = adjoint_next
    for a in range(p):
        for b in range(a):
            big_m[a, b] = big_m[b, a]
    return big_m


@njit(cache=True, fastmath=False)
def input_response_energy(
    phi: FloatArray, gamma: FloatArray, c_row: FloatArray, e_row: FloatArray, n: int
) -> FloatArray:
    """Σⱼ (1 − j/n) hᵣ,q(j)² per response r and force q: the mean over a record of n samples of the variance
    each response gains from unit white noise on force q (h the impulse response: e at j = 0, c Φʲ⁻¹ Γ after).

    Parameters
    ----------
    phi, gamma : ndarray
        Φ (8, 8) and Γ (8, 4), the exact one-sample step.
    c_row, e_row : ndarray
        c (R, 8) and e (R, 4), the output rows.
    n : int
        Samples in the record.

    Returns
    -------
    ndarray, shape (R, 4)
    """
    r_count = c_row.shape[0]
    out = np.zeros((r_count, 4))
    for r in range(r_count):
        for q in range(4):
            out[r, q] = e_row[r, q] * e_row[r, q]
    power = gamma.copy()  # Φʲ⁻¹ Γ
    for j in range(1, n):
        share = 1.0 - j / n
        for r in range(r_count):
            for q in range(4):
                acc = 0.0
                for i in range(8):
                    acc += c_row[r, i] * power[i, q]
                out[r, q] += share * acc * acc
        power = phi @ power
    return out


def compiled_cache_ready() -> bool:
    """Whether numba's cache on disk holds the compiled loops (a run then loads them in about a
    second); False where it does not, or where it cannot be told: the first run after installing
    compiles them, about a minute that a caller should say before it begins.

    Returns
    -------
    bool
        True where each loop's cache index file exists (numba checks the source's time stamp
        when it loads it: an index from an older source compiles again, which this does not see).
    """
    import os

    # the loops every identification runs; the others (force noise, information) only some, and
    # waiting for their caches said "compiling" before every run that never builds them
    loops: tuple[object, ...] = (run_feed_drive_ukf, response_moments)
    # numba's cache is internal: another version may keep it otherwise, and then this says False
    files = [getattr(getattr(loop, "_cache", None), "_cache_file", None) for loop in loops]
    paths = [getattr(file, "_index_path", None) for file in files]
    return all(isinstance(path, str) and os.path.exists(path) for path in paths)
