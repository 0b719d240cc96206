"""A linear thermal structure seen at one sensor (:class:`Machine`) and its exact responses.

dx/dt = A x + b_heat·power + b_room·room: the homogeneous part by the matrix exponential, the
forced part in closed form (constant power, a room ramp and a room sinusoid all have an exact
particular solution), so the truth a benchmark scores against carries no integration error.
How machines are drawn is :mod:`~mtident.testing.machines`, a run of one
:mod:`~mtident.testing.warmups`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from scipy.linalg import expm
from scipy.optimize import brentq

from mtident._typing import FloatArray
from mtident.exceptions import InputError

__all__ = [
    "EQUILIBRIUM_FRACTION",
    "ROOM_DRIFT_KEYS",
    "Machine",
    "crossing_time",
    "forced_response",
    "free_response",
    "modal_form",
    "room_temperature",
    "steady_state",
]

EQUILIBRIUM_FRACTION = 0.95
ROOM_DRIFT_KEYS = frozenset({"amplitude_C", "period_min", "phase_rad", "slope_C_per_h", "noise_C", "rounding_C"})


@dataclass(frozen=True)
class Machine:
    """A linear thermal structure seen at one sensor.

    dx/dt = A x + b_heat·power + b_room·room, y = sensor · x, with x absolute temperatures (°C) and
    time in minutes. A constant room R at zero power is an equilibrium: A @ 1 + b_room = 0.

    Attributes
    ----------
    kind : str
        ``"network"`` (lumped RC, 1-4 nodes) or ``"conduction"`` (1-D body).
    A : ndarray, shape (m, m)
        State matrix (1/min). With a sensor lag the last state is the lagged sensor.
    b_heat : ndarray, shape (m,)
        Heating rate of each state at unit power (K/min); non-negative.
    b_room : ndarray, shape (m,)
        Room coupling (1/min), so that A @ 1 + b_room = 0.
    sensor : ndarray, shape (m,)
        Output row; its entries sum to 1 (the room gain of the sensor is 1).
    time_constants_min : tuple of float
        −1/eig(A), sorted descending (the sensor lag included).
    description : str
        One line, e.g. ``"network 3 nodes (chain), tau 151/20/3.1 min, lag 0.8 min"``.
    sensor_lag_min : float
        Time constant of the sensor's first-order lag; 0 when it has none.
    structure : dict
        What was drawn (nodes, topology, structural time constants, heat and sensor positions,
        nominal rise), JSON-serialisable.
    """

    kind: str
    A: FloatArray
    b_heat: FloatArray
    b_room: FloatArray
    sensor: FloatArray
    time_constants_min: tuple[float, ...]
    description: str
    sensor_lag_min: float = 0.0
    structure: dict[str, Any] = field(default_factory=dict)

    @property
    def structural_time_constants_min(self) -> tuple[float, ...]:
        """The structure's time constants without the sensor lag, sorted descending.

        Returns
        -------
        tuple of float
            The time constants (min).
        """
        return tuple(self.structure.get("time_constants_min", self.time_constants_min))


def steady_state(machine: Machine, power: float, room: float) -> FloatArray:
    """The equilibrium state at a constant power and room: x∞ = −A⁻¹(b_heat·power + b_room·room).

    Parameters
    ----------
    machine : Machine
    power : float
        Heating power (1 = the machine's nominal rise).
    room : float
        The room's temperature (°C).

    Returns
    -------
    ndarray, shape (m,)
        Every state's temperature (°C).
    """
    return np.asarray(np.linalg.solve(-machine.A, machine.b_heat * power + machine.b_room * room), dtype=float)


def free_response(machine: Machine, h0: FloatArray, dt: float, n: int) -> FloatArray:
    """sensor · exp(A·k·dt) · h0 for k = 0..n−1, exact, in O(√n) matrix products.

    Rows r_i = sensor·Φ^i (i < B) and block states z_j = Φ^(jB)·h0, so y[jB + i] = r_i·z_j: no
    per-sample Python loop and no accumulation over thousands of steps.

    Parameters
    ----------
    machine : Machine
    h0 : ndarray, shape (m,)
        The state at k = 0, relative to the equilibrium (°C).
    dt : float
        The sampling interval (min).
    n : int
        The number of samples.

    Returns
    -------
    ndarray, shape (n,)
        The sensor's free response (°C).
    """
    block = max(1, math.isqrt(max(n - 1, 0)) + 1)
    blocks = -(-n // block)
    phi = expm(machine.A * dt)
    rows = np.empty((block, len(h0)))
    rows[0] = machine.sensor
    for i in range(1, block):
        rows[i] = rows[i - 1] @ phi
    # Φ^B by squaring: one matrix exponential per run (scipy's expm is the costly call)
    phi_block = np.linalg.matrix_power(phi, block)
    states = np.empty((blocks, len(h0)))
    states[0] = h0
    for j in range(1, blocks):
        states[j] = phi_block @ states[j - 1]
    return (states @ rows.T).reshape(-1)[:n]


def modal_form(machine: Machine, h0: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Rates λ_k (1/min, negative) and amplitudes a_k of sensor·exp(At)·h0 = Σ a_k·e^{λ_k t}.

    Parameters
    ----------
    machine : Machine
    h0 : ndarray, shape (m,)
        The state at t = 0, relative to the equilibrium (°C).

    Returns
    -------
    rates : ndarray, shape (m,)
        λ_k (1/min), in the order of ``np.linalg.eig``.
    amplitudes : ndarray, shape (m,)
        a_k (°C).
    """
    eigenvalues, vectors = np.linalg.eig(machine.A)
    if np.max(np.abs(eigenvalues.imag)) > 1e-9 * np.max(np.abs(eigenvalues.real)):
        raise ArithmeticError("complex modes: A is not a thermal structure")  # pragma: no cover
    weights = np.linalg.solve(vectors, h0)
    return eigenvalues.real, np.real((machine.sensor @ vectors) * weights)


def crossing_time(machine: Machine, h0: FloatArray, fraction: float) -> float:
    """First t with |sensor·(exp(At) − I)·h0| ≥ fraction·|sensor·h0| (h0 = x0 − x∞).

    A grid finds the first point past the level, widened until one is; brentq on the modal form
    (exact, A has real distinct eigenvalues) then gives the crossing to 1e-10 min.

    Parameters
    ----------
    machine : Machine
    h0 : ndarray, shape (m,)
        The state at t = 0 less the equilibrium, x0 − x∞ (°C).
    fraction : float
        The share of the total rise to reach (0.95 for t95).

    Returns
    -------
    float
        The crossing time (min).

    Raises
    ------
    InputError
        The sensor does not rise (sensor·h0 = 0).
    """
    total = float(machine.sensor @ h0)
    if total == 0.0:
        raise InputError("the sensor does not rise: no crossing time")
    rates, amplitudes = modal_form(machine, h0)
    level = fraction * abs(total)
    horizon = 4.0 * max(machine.time_constants_min)
    points = 4096

    def gap(t: float) -> float:
        return abs(float(amplitudes @ np.exp(rates * t)) - total) - level

    for _ in range(60):
        grid = np.linspace(0.0, horizon, points)
        y = np.exp(np.outer(grid, rates)) @ amplitudes
        past = np.flatnonzero(np.abs(y - total) >= level)
        if past.size:
            k = int(past[0])
            return float(brentq(gap, grid[k - 1], grid[k], xtol=1e-10, rtol=1e-13))
        horizon *= 2.0
    raise InputError("the sensor never reaches the level")  # pragma: no cover - stable A


def room_temperature(time_min: FloatArray, room_start_C: float, room_drift: Mapping[str, float] | None) -> FloatArray:
    """The true room temperature at the given times.

    room(t) = room_start + slope·t + amplitude·(sin(2πt/period + phase) − sin(phase)), so that
    room(0) = room_start.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
    room_start_C : float
    room_drift : mapping or None
        Keys ``amplitude_C``, ``period_min``, ``phase_rad`` (default 0), ``slope_C_per_h``
        (default 0); also ``noise_C`` and ``rounding_C`` of the room sensor (unused here).
        None: a steady room.

    Returns
    -------
    ndarray, shape (N,)

    Raises
    ------
    InputError
        ``room_drift`` with an unknown key, or a ``period_min`` that is not positive.
    """
    t = np.asarray(time_min, dtype=float)
    if room_drift is None:
        return np.full_like(t, room_start_C)
    amplitude, omega, phase, slope = _drift_terms(room_drift)
    answer: FloatArray = room_start_C + slope * t + amplitude * (np.sin(omega * t + phase) - np.sin(phase))
    return answer


def _drift_terms(room_drift: Mapping[str, float]) -> tuple[float, float, float, float]:
    unknown = set(room_drift) - ROOM_DRIFT_KEYS
    if unknown:
        raise InputError(f"room_drift: unknown keys {sorted(unknown)}")
    period = float(room_drift.get("period_min", math.inf))
    if not period > 0:
        raise InputError("room_drift: period_min must be positive")
    amplitude = float(room_drift.get("amplitude_C", 0.0))
    omega = 2.0 * math.pi / period
    return (
        amplitude,
        omega,
        float(room_drift.get("phase_rad", 0.0)),
        float(room_drift.get("slope_C_per_h", 0.0)) / 60.0,
    )


def forced_response(
    machine: Machine,
    t: FloatArray,
    power: float,
    room_start_C: float,
    room_drift: Mapping[str, float] | None,
) -> tuple[FloatArray, FloatArray]:
    """A particular solution x_p(t) of the run's inputs: sensor·x_p(t) at t, and x_p(0).

    Constant part: −A⁻¹(b_heat·P + b_room·R); a room ramp s·t: α·t + β with α = −A⁻¹b_room·s,
    β = A⁻¹α; a room sinusoid a·sin(ωt + φ): Im(z·e^{i(ωt+φ)}) with (iωI − A)z = b_room·a.

    Parameters
    ----------
    machine : Machine
    t : ndarray, shape (N,)
        Sample times (min).
    power : float
        Heating power (1 = the machine's nominal rise).
    room_start_C : float
        The room at t = 0 (°C).
    room_drift : mapping or None
        The room's drift (see :func:`room_temperature`); None: a steady room.

    Returns
    -------
    y : ndarray, shape (N,)
        sensor·x_p(t) (°C).
    x0 : ndarray, shape (m,)
        x_p(0) (°C).
    """
    A, b_room, s = machine.A, machine.b_room, machine.sensor
    if room_drift is None:
        x_const = steady_state(machine, power, room_start_C)
        return np.full(t.shape, float(s @ x_const)), x_const
    amplitude, omega, phase, slope = _drift_terms(room_drift)
    x_const = steady_state(machine, power, room_start_C - amplitude * math.sin(phase))
    alpha = np.linalg.solve(-A, b_room * slope)
    beta = np.linalg.solve(A, alpha)
    z = np.linalg.solve(1j * omega * np.eye(len(A)) - A, b_room * amplitude)
    y = float(s @ x_const) + float(s @ alpha) * t + float(s @ beta)
    y = y + np.imag(complex(s @ z) * np.exp(1j * (omega * t + phase)))
    x0 = x_const + beta + np.imag(z * np.exp(1j * phase))
    return y, x0
