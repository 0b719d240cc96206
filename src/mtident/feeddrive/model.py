"""First-order form of the feed-drive model (seed 004 Eqs 5-9), inputs, and classical RK4.

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

__all__ = ["Excitation", "system_matrix", "input_matrix", "rk4_linear_step", "exact_step", "EXCITATION_KINDS", "accelerations"]

EXCITATION_KINDS = ("impulse", "step", "sine", "sweep")


@dataclass(frozen=True, slots=True)
class Excitation:
    """A generalized force on one coordinate, as a function of time.

    Parameters
    ----------
    kind : {"impulse", "step", "sine", "sweep"}
        impulse: ``amplitude`` for the first sample only (seed 004 §3.1);
        step: ``amplitude`` from ``start_s`` on; sine: amplitude·sin(2πft);
        sweep: a linear chirp from ``frequency_Hz`` to ``frequency_end_Hz`` over the record.
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
            msg = f"excitation coordinate {self.coordinate}: expected 0 (table), 1 (screw), 2 (screw rotation) or 3 (motor)"
            raise InputError(msg)

    def forces(self, time_s: FloatArray) -> FloatArray:
        """Generalized forces (N, 4) held over each sample starting at ``time_s``."""
        t = np.asarray(time_s, dtype=float)
        value = np.zeros_like(t)
        if self.kind == "impulse":
            value[np.argmin(np.abs(t - self.start_s))] = self.amplitude
        elif self.kind == "step":
            value = np.where(t >= self.start_s, self.amplitude, 0.0)
        elif self.kind == "sine":
            value = self.amplitude * np.sin(2 * np.pi * self.frequency_Hz * t)
        else:
            span = max(float(t[-1] - t[0]), 1e-12)
            rate = (self.frequency_end_Hz - self.frequency_Hz) / span
            value = self.amplitude * np.sin(2 * np.pi * (self.frequency_Hz * t + 0.5 * rate * t**2))
        out = np.zeros((len(t), 4))
        out[:, self.coordinate] = value
        return out


def system_matrix(p: FeedDriveParameters) -> FloatArray:
    """A (8, 8) of Eq. 8."""
    m_inv = np.diag(1.0 / np.diag(mass_matrix(p)))
    return np.block([[np.zeros((4, 4)), np.eye(4)], [-m_inv @ stiffness_matrix(p), -m_inv @ damping_matrix(p)]])


def input_matrix(p: FeedDriveParameters) -> FloatArray:
    """B (8, 4): Ẋ = A X + B F."""
    return np.vstack([np.zeros((4, 4)), np.diag(1.0 / np.diag(mass_matrix(p)))])


def accelerations(p: FeedDriveParameters, states: FloatArray, forces: FloatArray) -> FloatArray:
    """Ẍ = M⁻¹(F − C ẋ − K x) for states (N, 8) and forces (N, 4)."""
    m_inv = 1.0 / np.diag(mass_matrix(p))
    return (forces - states[:, 4:] @ damping_matrix(p).T - states[:, :4] @ stiffness_matrix(p).T) * m_inv


def rk4_linear_step(a: FloatArray, b: FloatArray, h: float, substeps: int) -> tuple[FloatArray, FloatArray]:
    """(Φ, Γ) such that ``substeps`` classical RK4 steps of size h/substeps on Ẋ = AX + Bu,
    u held constant, give X⁺ = Φ X + Γ u — exactly, for any A (batched over leading axes).

    One RK4 step of a linear system is X⁺ = T X + S b with T = Σ₀⁴ (Ah)ʲ/j! and
    S = h Σ₀³ (Ah)ʲ/(j+1)!; ``substeps`` steps are composed by repeated squaring
    when it is a power of two, else step by step.
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
    """Zero-order-hold discretisation by the matrix exponential: the reference for RK4."""
    n, m = b.shape
    block = np.zeros((n + m, n + m))
    block[:n, :n] = a
    block[:n, n:] = b
    from scipy.linalg import expm  # here, not at the top: the thermal commands never need it

    e = expm(block * h)
    return e[:n, :n], e[:n, n:]
