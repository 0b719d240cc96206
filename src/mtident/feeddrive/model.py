"""First-order form of the feed-drive model (Nguyen-Quoc et al. Eqs 5-9), inputs, and classical RK4.

State X = [x_t, x_b, θ_b, θ_m, ẋ_t, ẋ_b, θ̇_b, θ̇_m]; Ẋ = A X + [0; M⁻¹F(t)] with
A = [[0, I], [−M⁻¹K, −M⁻¹C]]. (Eq. 8 prints +M⁻¹K: a sign slip.)

RK4 is the classical scheme (Eqs 10-14 misprint ¼ in k3 and tᵢ in k4). Inputs are
held constant over each sample (zero-order hold, as a data-acquisition system
applies them), so "a 20 N force for one sample" is a rectangular impulse.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.feeddrive.params import FeedDriveParameters, damping_matrix, mass_matrix, stiffness_matrix

__all__ = [
    "Excitation",
    "system_matrix",
    "input_matrix",
    "rk4_linear_step",
    "exact_step",
    "EXCITATION_KINDS",
    "accelerations",
    "parameter_basis",
    "system_matrices",
    "prbs_bits",
    "multisine",
]

EXCITATION_KINDS = ("impulse", "step", "sine", "sweep", "prbs", "multisine")
# Feedback taps of maximal-length Fibonacci shift registers, by register length (Xilinx XAPP052, Table 3).
_LFSR_TAPS = {
    5: (5, 3),
    6: (6, 5),
    7: (7, 6),
    8: (8, 6, 5, 4),
    9: (9, 5),
    10: (10, 7),
    11: (11, 9),
    12: (12, 6, 4, 1),
    13: (13, 4, 3, 1),
    14: (14, 5, 3, 1),
    15: (15, 14),
    16: (16, 15, 13, 4),
    17: (17, 14),
    18: (18, 11),
    19: (19, 6, 2, 1),
    20: (20, 17),
}


def prbs_bits(count: int) -> FloatArray:
    """±1 from a maximal-length sequence whose period (2ⁿ − 1) is at least ``count`` (deterministic;
    beyond 2²⁰ − 1 bits the 20-bit sequence repeats).

    Parameters
    ----------
    count : int
        Number of bits.

    Returns
    -------
    ndarray, shape (count,)
        +1.0 and −1.0, from a Fibonacci shift register of 5 to 20 bits started at all ones.

    Examples
    --------
    >>> bits = prbs_bits(31)
    >>> len(bits), int(bits.sum())  # one period of a 5-bit sequence: 16 ones, 15 minus ones
    (31, 1)
    """
    length = min(max(5, int(np.ceil(np.log2(count + 1)))), max(_LFSR_TAPS))
    taps = _LFSR_TAPS[length]
    register = [1] * length
    out = np.empty(count)
    for k in range(count):
        out[k] = 1.0 if register[-1] else -1.0
        feedback = 0
        for tap in taps:
            feedback ^= register[tap - 1]
        register = [feedback, *register[:-1]]
    return out


def multisine(count: int, h: float, low_Hz: float, high_Hz: float) -> FloatArray:
    """Equal-amplitude sines on the record's frequency grid (1/(count·h)) from ``low_Hz`` to ``high_Hz``,
    Schroeder phases for a low crest factor, scaled to a peak of 1 (periodic over the record).

    Schroeder, IEEE Trans. Inf. Theory 16 (1970) 85: φₖ = −πk(k−1)/K.

    Parameters
    ----------
    count : int
        Number of samples in the record.
    h : float
        Sampling interval (s).
    low_Hz, high_Hz : float
        The band (Hz); lines outside 1/(count·h) … 1/(2h) are left out. A band with no line of the
        grid gets the line nearest its centre.

    Returns
    -------
    ndarray, shape (count,)
        The signal, largest absolute value 1.
    """
    bins = np.arange(count // 2 + 1)
    frequencies = bins / (count * h)
    lines = bins[(frequencies >= low_Hz) & (frequencies <= high_Hz) & (bins > 0)]
    if len(lines) == 0:  # a band narrower than the grid: the nearest line
        lines = np.array([max(1, min(count // 2, int(round(0.5 * (low_Hz + high_Hz) * count * h))))])
    k = np.arange(1, len(lines) + 1)
    spectrum = np.zeros(count // 2 + 1, dtype=complex)
    spectrum[lines] = np.exp(-1j * np.pi * k * (k - 1) / len(lines))
    signal = np.fft.irfft(spectrum, n=count)
    answer: FloatArray = signal / np.abs(signal).max()
    return answer


@dataclass(frozen=True, slots=True)
class Excitation:
    """A generalized force on one coordinate, as a function of time.

    Parameters
    ----------
    kind : {"impulse", "step", "sine", "sweep", "prbs", "multisine"}
        impulse: ``amplitude`` for the first sample only (Nguyen-Quoc et al. §3.1);
        step: ``amplitude`` from ``start_s`` on; sine: amplitude·sin(2πft);
        sweep: a linear chirp from ``frequency_Hz`` to ``frequency_end_Hz`` over the record;
        prbs: ±amplitude from a maximal-length binary sequence clocked at ``frequency_end_Hz``
        (its power is within 3 dB of flat up to 0.44 × the clock);
        multisine: sines from ``frequency_Hz`` to ``frequency_end_Hz`` on the record's frequency
        grid, Schroeder phases, peak ``amplitude``.
    coordinate : int
        0 table force (N), 1 screw axial force (N), 2 screw torque (N m), 3 motor torque T_m (N m).
    amplitude : float
    frequency_Hz, frequency_end_Hz, start_s : float
    """

    kind: str = "impulse"
    coordinate: int = 0
    amplitude: float = 20.0
    frequency_Hz: float = 100.0
    frequency_end_Hz: float = 2000.0
    start_s: float = 0.0

    def __post_init__(self) -> None:
        if self.kind not in EXCITATION_KINDS:
            msg = f"excitation {self.kind!r} is not one of: {', '.join(EXCITATION_KINDS)}"
            raise InputError(msg)
        if self.coordinate not in range(4):
            msg = (
                f"excitation coordinate {self.coordinate}: expected 0 (table), 1 (screw), 2 (screw rotation) or 3 "
                "(motor)"
            )
            raise InputError(msg)

    def forces(self, time_s: FloatArray) -> FloatArray:
        """Generalized forces (N, 4) held over each sample starting at ``time_s``.

        Parameters
        ----------
        time_s : ndarray, shape (N,)
            Start of each sample (s), increasing and evenly spaced (a multisine takes its interval from the
            first two).

        Returns
        -------
        ndarray, shape (N, 4)
            F (N, N, N m, N m): the excitation in the column of ``coordinate``, zero in the others.
        """
        t = np.asarray(time_s, dtype=float)
        value = np.zeros_like(t)
        if self.kind == "impulse":
            value[np.argmin(np.abs(t - self.start_s))] = self.amplitude
        elif self.kind == "step":
            value = np.where(t >= self.start_s, self.amplitude, 0.0)
        elif self.kind == "sine":
            value = self.amplitude * np.sin(2 * np.pi * self.frequency_Hz * t)
        elif self.kind == "sweep":
            span = max(float(t[-1] - t[0]), 1e-12)
            rate = (self.frequency_end_Hz - self.frequency_Hz) / span
            value = self.amplitude * np.sin(2 * np.pi * (self.frequency_Hz * t + 0.5 * rate * t**2))
        elif self.kind == "prbs":
            ticks = np.floor((t - t[0]) * self.frequency_end_Hz + 1e-9).astype(int)
            value = self.amplitude * prbs_bits(int(ticks[-1]) + 1)[ticks]
        else:
            h = float(t[1] - t[0]) if len(t) > 1 else 1.0
            value = self.amplitude * multisine(len(t), h, self.frequency_Hz, self.frequency_end_Hz)
        out = np.zeros((len(t), 4))
        out[:, self.coordinate] = value
        return out


def system_matrix(p: FeedDriveParameters) -> FloatArray:
    """A (8, 8) of Eq. 8.

    Parameters
    ----------
    p : FeedDriveParameters
        Masses, inertias, stiffnesses, dampings and β (SI units).

    Returns
    -------
    ndarray, shape (8, 8)
        A = [[0, I], [−M⁻¹K, −M⁻¹C]] for the state X = [x_t, x_b, θ_b, θ_m, ẋ_t, ẋ_b, θ̇_b, θ̇_m].
    """
    m_inv = np.diag(1.0 / np.diag(mass_matrix(p)))
    return np.block([[np.zeros((4, 4)), np.eye(4)], [-m_inv @ stiffness_matrix(p), -m_inv @ damping_matrix(p)]])


def parameter_basis(fixed: FeedDriveParameters) -> tuple[FloatArray, FloatArray]:
    """A is linear in the identified parameters: A(p) = A₀ + Σⱼ pⱼ Dⱼ. Returns (A₀, D (8, 8, 8)).

    ``fixed`` gives the masses, inertias and β; its identified parameters are not used.

    Parameters
    ----------
    fixed : FeedDriveParameters
        Supplies Mt, Mb (kg), Jb, Jm (kg m²) and β (m/rad).

    Returns
    -------
    a0 : ndarray, shape (8, 8)
        A₀ = [[0, I], [0, 0]], the part of A that no identified parameter multiplies.
    basis : ndarray, shape (8, 8, 8)
        Dⱼ (rows 5-8 nonzero), the part of A that the j-th of K1..K4, Bt, Bb, Qb, Qm multiplies.
    """
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


def system_matrices(params: FloatArray, basis: tuple[FloatArray, FloatArray]) -> FloatArray:
    """A (..., 8, 8) for identified parameters (..., 8) = K1..K4, Bt, Bb, Qb, Qm.

    Parameters
    ----------
    params : ndarray, shape (..., 8)
        Identified parameters K1..K4 (N/m, N/m, N m/rad, N m/rad), Bt, Bb (N s/m), Qb, Qm (N m s/rad),
        with any leading batch axes.
    basis : tuple of ndarray
        (A₀ (8, 8), D (8, 8, 8)) from :func:`parameter_basis`.

    Returns
    -------
    ndarray, shape (..., 8, 8)
        A = A₀ + Σⱼ pⱼ Dⱼ for each parameter vector.
    """
    a0, d = basis
    return a0 + (params @ d.reshape(8, 64)).reshape(*params.shape[:-1], 8, 8)


def input_matrix(p: FeedDriveParameters) -> FloatArray:
    """B (8, 4): Ẋ = A X + B F.

    Parameters
    ----------
    p : FeedDriveParameters
        Its masses and inertias are used (SI units).

    Returns
    -------
    ndarray, shape (8, 4)
        [0; M⁻¹]: the generalized forces F (N, N, N m, N m) reach the accelerations only.
    """
    return np.vstack([np.zeros((4, 4)), np.diag(1.0 / np.diag(mass_matrix(p)))])


def accelerations(p: FeedDriveParameters, states: FloatArray, forces: FloatArray) -> FloatArray:
    """Ẍ = M⁻¹(F − C ẋ − K x) for states (N, 8) and forces (N, 4).

    Parameters
    ----------
    p : FeedDriveParameters
        Masses, inertias, stiffnesses, dampings and β (SI units).
    states : ndarray, shape (N, 8)
        X = [x_t, x_b, θ_b, θ_m, ẋ_t, ẋ_b, θ̇_b, θ̇_m] (m, rad, m/s, rad/s).
    forces : ndarray, shape (N, 4)
        Generalized forces F (N, N, N m, N m).

    Returns
    -------
    ndarray, shape (N, 4)
        ẍ_t, ẍ_b (m/s²), θ̈_b, θ̈_m (rad/s²).
    """
    m_inv = 1.0 / np.diag(mass_matrix(p))
    return (forces - states[:, 4:] @ damping_matrix(p).T - states[:, :4] @ stiffness_matrix(p).T) * m_inv


def rk4_linear_step(a: FloatArray, b: FloatArray, h: float, substeps: int) -> tuple[FloatArray, FloatArray]:
    """(Φ, Γ) such that ``substeps`` classical RK4 steps of size h/substeps on Ẋ = AX + Bu,
    u held constant, give X⁺ = Φ X + Γ u — exactly, for any A (batched over leading axes).

    One RK4 step of a linear system is X⁺ = T X + S b with T = Σ₀⁴ (Ah)ʲ/j! and
    S = h Σ₀³ (Ah)ʲ/(j+1)!; ``substeps`` steps are composed by repeated squaring
    when it is a power of two, else step by step.

    Parameters
    ----------
    a : ndarray, shape (..., n, n)
        System matrices A.
    b : ndarray, shape (n, m) or (..., n, m)
        Input matrix B, shared by the batch or one per A.
    h : float
        Sampling interval (s): the input is held constant over it.
    substeps : int
        RK4 steps of size h/substeps per sample (1 or more).

    Returns
    -------
    phi : ndarray, shape (..., n, n)
        Φ, the state transition over one sample.
    gamma : ndarray, shape (..., n, m)
        Γ, the held input's effect over one sample.
    """
    n = a.shape[-1]
    eye = np.broadcast_to(np.eye(n), a.shape)
    dt = h / substeps
    ah = a * dt
    ah2 = ah @ ah
    ah3 = ah2 @ ah
    t = eye + ah + ah2 / 2.0 + ah3 / 6.0 + ah3 @ ah / 24.0
    s = dt * (eye + ah / 2.0 + ah2 / 6.0 + ah3 / 24.0) @ b
    phi, gamma = t, s
    if substeps & (substeps - 1) == 0:
        count = 1
        while count < substeps:
            gamma = phi @ gamma + gamma
            phi = phi @ phi
            count *= 2
    else:
        for _ in range(substeps - 1):
            gamma = t @ gamma + s
            phi = t @ phi
    return phi, gamma


def exact_step(a: FloatArray, b: FloatArray, h: float) -> tuple[FloatArray, FloatArray]:
    """Zero-order-hold discretisation by the matrix exponential: the reference for RK4.

    Parameters
    ----------
    a : ndarray, shape (n, n)
        System matrix A (one, not a batch).
    b : ndarray, shape (n, m)
        Input matrix B.
    h : float
        Sampling interval (s): the input is held constant over it.

    Returns
    -------
    phi : ndarray, shape (n, n)
        Φ = e^(Ah).
    gamma : ndarray, shape (n, m)
        Γ = ∫₀ʰ e^(As) ds B, so that X⁺ = Φ X + Γ u.
    """
    n, m = b.shape
    block = np.zeros((n + m, n + m))
    block[:n, :n] = a
    block[:n, n:] = b
    from scipy.linalg import expm  # here, not at the top: the thermal commands never need it

    e = expm(block * h)
    return e[:n, :n], e[:n, n:]
