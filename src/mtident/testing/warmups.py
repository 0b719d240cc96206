"""Synthetic warm-ups for benchmarks and property tests, and the real curves beside the project.

The population is the one of the safe-stops benchmark and of the stopping-rule study
(``../shared/research/stop-rules.md``): linear thermal structures seen at one sensor,

* ``"network"``: a lumped RC network of 1-4 nodes, A = −C⁻¹G with G a weighted Laplacian of
  conductances plus convection to the room, every time constant drawn log-uniformly in
  2-300 min and the network built to have exactly those time constants;
* ``"conduction"``: a 1-D body (a shaft) of 30-60 finite volumes, conduction along it,
  convection along its surface, heat at one or two bearings, the sensor anywhere along it; its
  slowest time constant drawn in 2-300 min;

optionally seen through a first-order sensor lag (an extra state), started cold or partly warm,
in a steady or a drifting room (with a room sensor), sampled, noisy and rounded like a logger.

Every response is exact: the homogeneous part by the matrix exponential, the forced part in
closed form (constant power, a room ramp and a room sinusoid all have an exact particular
solution), so the truth a benchmark scores against carries no integration error. Randomness
comes only from the ``np.random.Generator`` passed in.
"""

from __future__ import annotations

import csv
import math
from collections.abc import Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

import numpy as np
from scipy.linalg import expm
from scipy.ndimage import median_filter
from scipy.optimize import brentq

from mtident._typing import FloatArray
from mtident.exceptions import InputError

__all__ = [
    "Machine",
    "WarmUp",
    "RealCurve",
    "random_machine",
    "simulate",
    "random_warmup",
    "reference_run",
    "modal_amplitudes",
    "room_temperature",
    "load_real_curves",
    "KINDS",
    "INTERVALS_MIN",
    "ROUNDINGS_C",
]

KINDS = ("network", "conduction")
KIND_WEIGHTS = (0.75, 0.25)
# Loggers seen on machine tools: 1 s, 10 s, 30 s, 1, 2 and 5 min.
INTERVALS_MIN = (1.0 / 60.0, 10.0 / 60.0, 0.5, 1.0, 2.0, 5.0)
# 0.32 °C is the TCLab's quantisation (10-bit ADC over a thermistor), the coarsest seen.
ROUNDINGS_C = (0.01, 0.02, 0.05, 0.1, 0.32)
ROUNDING_WEIGHTS = (0.5, 0.15, 0.15, 0.1, 0.1)
ROOM_ROUNDINGS_C = (0.01, 0.02, 0.05, 0.1)
ROOM_ROUNDING_WEIGHTS = (0.55, 0.2, 0.15, 0.1)
MIN_ROUNDING_STEPS = 20
DURATION_LIMITS_MIN = (60.0, 2000.0)
ONE_SECOND_MAX_DURATION_MIN = 300.0
REFERENCE_MAX_SAMPLES = 20_000
EQUILIBRIUM_FRACTION = 0.95
# A sensor whose steady rise is under this share of the hottest node's would need an absurd heat
# input to rise 2-30 °C: such a sensor position is drawn again.
MIN_SENSOR_SHARE = 0.1
# Time constants closer than this (relative) are drawn again: the lag state and an equal network
# mode would make A defective, and near it the modal amplitudes lose digits.
MIN_RELATIVE_GAP = 0.02
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


@dataclass(frozen=True)
class WarmUp:
    """One simulated warm-up test: what the logger wrote and the noiseless truth.

    Attributes
    ----------
    machine : Machine
    time_min : ndarray, shape (N,)
        Sample times from 0, evenly spaced by ``interval_min``.
    reading_C : ndarray, shape (N,)
        What the logger writes: noisy, rounded to ``rounding_C``, NaN where a row was dropped.
    clean_C : ndarray, shape (N,)
        Noiseless sensor temperature (room drift included).
    room_C : ndarray, shape (N,) or None
        Room sensor readings (noisy, rounded, NaN at the dropped rows) when the room drifts;
        None in a steady room.
    steady_C : ndarray, shape (N,)
        The truth: the sensor's equilibrium for the run's power with the room held at its level
        at each sample time (the room gain is 1, so it moves with the room one to one).
    start_C : float
        Noiseless sensor temperature at t = 0.
    t95_min : float
        First time the noiseless sensor of the steady-room version of the run reaches 95 % of
        its total rise, |clean − start| ≥ 0.95·|steady − start| (continuous time, exact).
    noise_C, rounding_C, interval_min : float
    settings : dict
        Everything drawn or given, JSON-serialisable (for a benchmark's table).
    power : float
        Heating power of the run (1 = the machine's nominal rise).
    initial_state_C : ndarray, shape (m,)
        The machine's state at t = 0 (absolute °C); with ``settings["room_start_C"]`` it fixes the
        modal amplitudes.
    """

    machine: Machine
    time_min: FloatArray
    reading_C: FloatArray
    clean_C: FloatArray
    room_C: FloatArray | None
    steady_C: FloatArray
    start_C: float
    t95_min: float
    noise_C: float
    rounding_C: float
    interval_min: float
    settings: dict[str, Any]
    power: float
    initial_state_C: FloatArray

    @property
    def rise_C(self) -> float:
        """Total rise of the run in its starting room: steady_C[0] − start_C.

        Returns
        -------
        float
            The rise (°C).
        """
        return float(self.steady_C[0] - self.start_C)

    @property
    def duration_min(self) -> float:
        """Time of the last sample.

        Returns
        -------
        float
            The time (min).
        """
        return float(self.time_min[-1])

    def __repr__(self) -> str:
        room = "drifting room" if self.room_C is not None else "steady room"
        return (
            f"WarmUp({self.machine.description}; {len(self.time_min)} samples every "
            f"{self.interval_min * 60:g} s, rise {self.rise_C:.2f} °C, t95 {self.t95_min:.1f} min, "
            f"σ {self.noise_C:.3g}, rounding {self.rounding_C:g} °C, {room})"
        )


@dataclass(frozen=True)
class RealCurve:
    """One heating channel of a measured record.

    Attributes
    ----------
    name : str
        ``"<file stem>:<column>"``.
    time_min : ndarray, shape (N,)
        Sample times from the record's start (as logged, not necessarily even).
    reading_C : ndarray, shape (N,)
    settled_C : float
        Median of the last 5 % of the readings when the record settled (the last quarter rose
        under 1 % of the total rise), else NaN: then the record shows no equilibrium to score
        against.
    t95_min : float
        First time a running median of the readings reaches start + 0.95·(settled − start),
        interpolated between samples; NaN when not settled or not reached.
    rounding_C : float
        The logger's quantisation, read off the spacing of the distinct readings.
    start_C : float
        Median of the first three readings.
    end_C : float
        Median of the last 5 % of the readings, settled or not.
    last_quarter_rise : float
        What the last quarter rose, as a fraction of the total rise.
    """

    name: str
    time_min: FloatArray
    reading_C: FloatArray
    settled_C: float
    t95_min: float
    rounding_C: float
    start_C: float
    end_C: float
    last_quarter_rise: float


# --------------------------------------------------------------------------------------------
# Linear-system helpers


def _steady_state(machine: Machine, power: float, room: float) -> FloatArray:
    return np.asarray(np.linalg.solve(-machine.A, machine.b_heat * power + machine.b_room * room), dtype=float)


def _free_response(machine: Machine, h0: FloatArray, dt: float, n: int) -> FloatArray:
    """sensor · exp(A·k·dt) · h0 for k = 0..n−1, exact, in O(√n) matrix products.

    Rows r_i = sensor·Φ^i (i < B) and block states z_j = Φ^(jB)·h0, so y[jB + i] = r_i·z_j: no
    per-sample Python loop and no accumulation over thousands of steps.
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


def _modes(machine: Machine, h0: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Rates λ_k (1/min, negative) and amplitudes a_k of sensor·exp(At)·h0 = Σ a_k·e^{λ_k t}."""
    eigenvalues, vectors = np.linalg.eig(machine.A)
    if np.max(np.abs(eigenvalues.imag)) > 1e-9 * np.max(np.abs(eigenvalues.real)):
        raise ArithmeticError("complex modes: A is not a thermal structure")  # pragma: no cover
    weights = np.linalg.solve(vectors, h0)
    return eigenvalues.real, np.real((machine.sensor @ vectors) * weights)


def _crossing_time(machine: Machine, h0: FloatArray, fraction: float) -> float:
    """First t with |sensor·(exp(At) − I)·h0| ≥ fraction·|sensor·h0| (h0 = x0 − x∞).

    A grid finds the first point past the level, widened until one is; brentq on the modal form
    (exact, A has real distinct eigenvalues) then gives the crossing to 1e-10 min.
    """
    total = float(machine.sensor @ h0)
    if total == 0.0:
        raise InputError("the sensor does not rise: no crossing time")
    rates, amplitudes = _modes(machine, h0)
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


def _forced_response(
    machine: Machine,
    t: FloatArray,
    power: float,
    room_start_C: float,
    room_drift: Mapping[str, float] | None,
) -> tuple[FloatArray, FloatArray]:
    """A particular solution x_p(t) of the run's inputs: sensor·x_p(t) at t, and x_p(0).

    Constant part: −A⁻¹(b_heat·P + b_room·R); a room ramp s·t: α·t + β with α = −A⁻¹b_room·s,
    β = A⁻¹α; a room sinusoid a·sin(ωt + φ): Im(z·e^{i(ωt+φ)}) with (iωI − A)z = b_room·a.
    """
    A, b_room, s = machine.A, machine.b_room, machine.sensor
    if room_drift is None:
        x_const = _steady_state(machine, power, room_start_C)
        return np.full(t.shape, float(s @ x_const)), x_const
    amplitude, omega, phase, slope = _drift_terms(room_drift)
    x_const = _steady_state(machine, power, room_start_C - amplitude * math.sin(phase))
    alpha = np.linalg.solve(-A, b_room * slope)
    beta = np.linalg.solve(A, alpha)
    z = np.linalg.solve(1j * omega * np.eye(len(A)) - A, b_room * amplitude)
    y = float(s @ x_const) + float(s @ alpha) * t + float(s @ beta)
    y = y + np.imag(complex(s @ z) * np.exp(1j * (omega * t + phase)))
    x0 = x_const + beta + np.imag(z * np.exp(1j * phase))
    return y, x0


# --------------------------------------------------------------------------------------------
# Machines


def _log_uniform(rng: np.random.Generator, low: float, high: float, size: int | None = None) -> Any:
    return np.exp(rng.uniform(math.log(low), math.log(high), size))


def _well_separated(values: FloatArray) -> bool:
    v = np.sort(np.asarray(values, dtype=float))
    return bool(np.all(np.diff(v) >= MIN_RELATIVE_GAP * v[1:])) if v.size > 1 else True


def _jacobi_with_spectrum(eigenvalues: FloatArray, weights: FloatArray) -> FloatArray:
    """The tridiagonal symmetric matrix with the given eigenvalues and off-diagonals < 0.

    Lanczos on diag(eigenvalues) from the start vector √weights gives the unique Jacobi matrix
    (positive off-diagonals) whose eigenvectors have first components √weights; flipping the sign
    of every other row and column keeps the spectrum and makes the off-diagonals negative, as
    conductances between neighbouring nodes need.
    """
    n = len(eigenvalues)
    q = np.zeros((n, n))
    q[:, 0] = np.sqrt(weights / weights.sum())
    diag = np.zeros(n)
    off = np.zeros(max(n - 1, 0))
    for j in range(n):
        w = eigenvalues * q[:, j]
        diag[j] = q[:, j] @ w
        for _ in range(2):  # full re-orthogonalisation, twice: n ≤ 4, exactness matters
            w = w - q[:, : j + 1] @ (q[:, : j + 1].T @ w)
        if j < n - 1:
            off[j] = np.linalg.norm(w)
            q[:, j + 1] = w / off[j]
    return np.diag(diag) - np.diag(off, 1) - np.diag(off, -1)


def _scrambled(rng: np.random.Generator, s: FloatArray, tries: int = 200) -> FloatArray | None:
    """An isospectral R·S·Rᵀ (R a random rotation) whose off-diagonals are all negative.

    Rejection sampling around the chain: the chain's zero entries become links of either sign,
    and a draw is kept only where every pair of nodes is linked by a positive conductance. Large
    rotations are tried first, so that the extra links are strong where the spectrum allows.
    """
    n = len(s)
    for size in np.geomspace(1.0, 0.01, tries):
        k = rng.normal(size=(n, n)) * size
        k = k - k.T
        rotation = np.linalg.solve(np.eye(n) - k, np.eye(n) + k)  # Cayley: orthogonal
        candidate = rotation @ s @ rotation.T
        candidate = 0.5 * (candidate + candidate.T)
        if np.all(candidate[~np.eye(n, dtype=bool)] < 0.0):
            return np.asarray(candidate, dtype=float)
    return None


def _with_lag(
    A: FloatArray, b_heat: FloatArray, b_room: FloatArray, sensor: FloatArray, lag_min: float
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    """Append the lagged sensor state: dy/dt = (sensor·x − y)/lag."""
    m = len(A)
    a = np.zeros((m + 1, m + 1))
    a[:m, :m] = A
    a[m, :m] = sensor / lag_min
    a[m, m] = -1.0 / lag_min
    out = np.zeros(m + 1)
    out[m] = 1.0
    return a, np.append(b_heat, 0.0), np.append(b_room, 0.0), out


def _format_taus(taus: tuple[float, ...] | list[float]) -> str:
    return "/".join(f"{t:.3g}" for t in taus)


def _network(
    rng: np.random.Generator, nodes: int, taus: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, dict[str, Any]]:
    """A = −C⁻¹G with eigenvalues −1/taus; also the convection rates and the structure."""
    rates = 1.0 / taus
    s = _jacobi_with_spectrum(rates, rng.dirichlet(np.ones(nodes)))
    topology = "chain" if nodes > 2 else ("pair" if nodes == 2 else "single")
    if nodes >= 3 and rng.random() < 0.5:
        scrambled = _scrambled(rng, s)
        if scrambled is not None:
            s, topology = scrambled, "meshed"
    order = rng.permutation(nodes)
    s = s[np.ix_(order, order)]
    # Convection on a random non-empty set of nodes: u ≥ 0, and v = S⁻¹u > 0 (S is an irreducible
    # M-matrix) gives C = diag(v²), G = diag(v)·S·diag(v) with G·1 = v∘u ≥ 0: a physical network.
    u = np.zeros(nodes)
    convecting = rng.choice(nodes, size=int(rng.integers(1, nodes + 1)), replace=False)
    u[convecting] = rng.uniform(0.2, 1.0, convecting.size)
    v = np.linalg.solve(s, u)
    if not np.all(v > 0):  # pragma: no cover - an irreducible M-matrix has a positive inverse
        raise ArithmeticError("network construction lost positivity")
    capacity = np.asarray(v**2, dtype=float)
    conductance = -(v[:, None] * s * v[None, :])
    np.fill_diagonal(conductance, 0.0)
    convection = v * u
    A = -(s * v[None, :]) / v[:, None]
    scale = capacity.max()
    structure = {
        "nodes": nodes,
        "topology": topology,
        "capacities": (capacity / scale).tolist(),
        "conductances": (conductance / scale).tolist(),
        "convection": (convection / scale).tolist(),
    }
    return np.asarray(A, dtype=float), capacity, convection, structure


def _conduction(rng: np.random.Generator, tau_slow: float) -> tuple[FloatArray, FloatArray, FloatArray, dict[str, Any]]:
    """A shaft of unit length in N finite volumes; its slowest time constant is tau_slow."""
    n = int(rng.integers(30, 61))
    z = (np.arange(n) + 0.5) / n
    # ratio = π²D/β: how much faster the first axial mode decays than the uniform one; small
    # ratios keep the heat near the bearing (a diffusive, delayed far end), large ones make the
    # shaft nearly isothermal.
    ratio = float(_log_uniform(rng, 0.3, 100.0))
    convection = np.full(n, 1.0 / n)
    housed = None
    if rng.random() < 0.5:  # a stretch inside a housing convects less
        lo, hi = np.sort(rng.uniform(0.0, 1.0, 2))
        factor = float(rng.uniform(0.1, 1.0))
        convection[(z >= lo) & (z <= hi)] *= factor
        housed = [float(lo), float(hi), factor]
    ends = rng.uniform(0.0, 0.1, 2)  # end faces as an equivalent length of surface
    convection[0] += ends[0]
    convection[-1] += ends[1]
    link = ratio / math.pi**2 * n
    g = np.diag(convection)
    i = np.arange(n - 1)
    g[i, i] += link
    g[i + 1, i + 1] += link
    g[i, i + 1] -= link
    g[i + 1, i] -= link
    capacity = np.full(n, 1.0 / n)
    slowest = float(np.linalg.eigvalsh(g / capacity[0]).min())
    capacity = capacity * tau_slow * slowest  # scales every rate: the slowest becomes 1/tau_slow
    A = -g / capacity[:, None]
    structure = {
        "nodes": n,
        "axial_ratio": ratio,
        "housed_stretch": housed,
        "end_losses": ends.tolist(),
    }
    return A, capacity, convection, structure


def _bearing_heat(rng: np.random.Generator, n: int) -> tuple[FloatArray, list[list[float]]]:
    z = (np.arange(n) + 0.5) / n
    width = 1.5 / n
    bearings = [[float(rng.uniform(0.05, 0.95)), 1.0]]
    if rng.random() < 0.5:
        bearings.append([float(rng.uniform(0.05, 0.95)), float(rng.uniform(0.2, 1.0))])
    heat = np.zeros(n)
    for where, share in bearings:
        heat += share * np.exp(-0.5 * ((z - where) / width) ** 2)
    return heat, bearings


def random_machine(
    rng: np.random.Generator,
    kind: str | None = None,
    max_time_constant_min: float = 300.0,
    min_time_constant_min: float = 2.0,
    *,
    nodes: int | None = None,
    rise_C: float | None = None,
    sensor_lag_min: float | None = None,
) -> Machine:
    """Draw a machine of the benchmark population.

    Parameters
    ----------
    rng : numpy.random.Generator
    kind : {"network", "conduction"} or None
        None draws it: network 75 %, conduction 25 %.
    max_time_constant_min, min_time_constant_min : float
        Range of the structural time constants (network: all of them, log-uniform, at least 2 %
        apart; conduction: the slowest, log-uniform).
    nodes : int or None
        Nodes of a network (1-4 drawn uniformly when None); ignored for conduction (30-60).
    rise_C : float or None
        The sensor's steady rise above the room at unit power; None draws it log-uniformly in
        2-30 °C.
    sensor_lag_min : float or None
        None: with probability 0.4 a first-order sensor lag log-uniform in 0.2-5 min (drawn
        again while within 2 % of a structural time constant); 0: none; > 0: that lag.

    Returns
    -------
    Machine

    Raises
    ------
    InputError
        An unknown ``kind``, time constant limits not in 0 < min < max, a network's ``nodes``
        outside 1-4, or a negative ``sensor_lag_min`` or one within 2 % of a structural time
        constant.
    """
    if kind is None:
        kind = str(rng.choice(KINDS, p=KIND_WEIGHTS))
    if kind not in KINDS:
        raise InputError(f"kind must be one of {KINDS}, not {kind!r}")
    if not 0 < min_time_constant_min < max_time_constant_min:
        raise InputError("need 0 < min_time_constant_min < max_time_constant_min")
    if rise_C is None:
        rise_C = float(_log_uniform(rng, 2.0, 30.0))
    if kind == "network":
        n = int(rng.integers(1, 5)) if nodes is None else int(nodes)
        if not 1 <= n <= 4:
            raise InputError("a network has 1-4 nodes")
        while True:
            taus = np.sort(_log_uniform(rng, min_time_constant_min, max_time_constant_min, n))
            if _well_separated(taus):
                break
        A, capacity, convection, structure = _network(rng, n, taus[::-1])
        power = np.zeros(n)
        heated = rng.choice(n, size=int(rng.integers(1, n + 1)), replace=False)
        power[heated] = rng.uniform(0.2, 1.0, heated.size)
        structure["heated_nodes"] = sorted(int(k) for k in heated)
        positions = None
    else:
        tau_slow = float(_log_uniform(rng, min_time_constant_min, max_time_constant_min))
        A, capacity, convection, structure = _conduction(rng, tau_slow)
        n = len(A)
        power, bearings = _bearing_heat(rng, n)
        structure["bearings"] = bearings
        positions = (np.arange(n) + 0.5) / n
    b_heat = power / capacity
    b_room = convection / capacity
    node_rise = np.linalg.solve(-A, b_heat)
    candidates = np.flatnonzero(node_rise >= MIN_SENSOR_SHARE * node_rise.max())
    sensor_node = int(rng.choice(candidates))
    sensor = np.zeros(n)
    sensor[sensor_node] = 1.0
    b_heat = b_heat * (rise_C / node_rise[sensor_node])
    structural = tuple(sorted((-1.0 / np.linalg.eigvals(A).real).tolist(), reverse=True))
    structure.update(
        kind=kind,
        sensor_node=sensor_node,
        rise_C=rise_C,
        time_constants_min=list(structural),
    )
    if positions is not None:
        structure["sensor_position"] = float(positions[sensor_node])
    if sensor_lag_min is None:
        lag = 0.0
        if rng.random() < 0.4:
            while True:
                lag = float(_log_uniform(rng, 0.2, 5.0))
                if np.min(np.abs(np.asarray(structural) - lag)) >= MIN_RELATIVE_GAP * lag:
                    break
    else:
        lag = float(sensor_lag_min)
        if lag < 0:
            raise InputError("sensor_lag_min must be ≥ 0")
        if lag > 0 and np.min(np.abs(np.asarray(structural) - lag)) < MIN_RELATIVE_GAP * lag:
            raise InputError("a sensor lag within 2 % of a structural time constant")
    if lag > 0:
        A, b_heat, b_room, sensor = _with_lag(A, b_heat, b_room, sensor, lag)
    structure["sensor_lag_min"] = lag
    all_taus = tuple(sorted((-1.0 / np.linalg.eigvals(A).real).tolist(), reverse=True))
    if kind == "network":
        description = f"network {n} nodes ({structure['topology']}), tau {_format_taus(structural)} min"
    else:
        description = (
            f"conduction {n} nodes, tau {_format_taus(structural[:3])}… min, bearing at "
            f"{structure['bearings'][0][0]:.2f} L, sensor at {structure['sensor_position']:.2f} L"
        )
    if lag > 0:
        description += f", lag {lag:.2g} min"
    return Machine(kind, A, b_heat, b_room, sensor, all_taus, description, lag, structure)


# --------------------------------------------------------------------------------------------
# Runs


def _initial_state(
    machine: Machine,
    power: float,
    room_start_C: float,
    warm_start: float,
    warm_profile: str,
    warm_power: float | None,
) -> tuple[FloatArray, float | None]:
    """The state at t = 0 and, for a previous heating, how long it lasted."""
    m = len(machine.A)
    cold = np.full(m, room_start_C)
    if not 0.0 <= warm_start < 1.0:
        raise InputError("warm_start is a fraction of the steady rise in [0, 1)")
    if warm_start == 0.0:
        return cold, None
    steady = _steady_state(machine, power, room_start_C)
    if warm_profile == "steady":
        return cold + warm_start * (steady - cold), None
    if warm_profile != "heating":
        raise InputError("warm_profile is 'steady' or 'heating'")
    prior = power if warm_power is None else float(warm_power)
    if prior <= warm_start * power:
        raise InputError("the previous heating's power is too low to reach the warm start")
    prior_steady = _steady_state(machine, prior, room_start_C)
    h0 = cold - prior_steady
    # the previous heating stops when the sensor has risen warm_start of this run's rise
    fraction = warm_start * power / prior
    t_pre = _crossing_time(machine, h0, fraction)
    return prior_steady + expm(machine.A * t_pre) @ h0, t_pre


def _rounded(values: FloatArray, step: float) -> FloatArray:
    if step <= 0:
        return values
    # round() to 10 decimals drops the binary residue of k·step, as a logger's text would
    return np.round(np.round(values / step) * step, 10)


def simulate(
    machine: Machine,
    rng: np.random.Generator,
    *,
    power: float = 1.0,
    duration_min: float | None = None,
    interval_min: float = 1.0,
    noise_C: float = 0.02,
    rounding_C: float = 0.01,
    warm_start: float = 0.0,
    room_drift: Mapping[str, float] | None = None,
    room_start_C: float = 20.0,
    dropout: float = 0.0,
    warm_profile: str = "steady",
    warm_power: float | None = None,
) -> WarmUp:
    """One warm-up of ``machine`` at constant power, exact, then logged.

    Parameters
    ----------
    machine : Machine
    rng : numpy.random.Generator
        For the noise and the dropouts only.
    power : float
        Heating power (1 = the machine's nominal rise).
    duration_min : float or None
        Length of the record; None: 1.5·t95 clipped to 60-2000 min.
    interval_min : float
        Sampling interval.
    noise_C, rounding_C : float
        Gaussian noise σ of the sensor and the logger's rounding step (0: none).
    warm_start : float
        0: a cold start (everything at the room). f in (0, 1): the sensor starts at f of its
        steady rise, on the path given by ``warm_profile``.
    room_drift : mapping or None
        A drifting room (see :func:`room_temperature`), logged by a room sensor with its own
        ``noise_C`` (default 0.01) and ``rounding_C`` (default 0.01) from the mapping.
        None: the room stays at ``room_start_C`` and ``room_C`` is None.
    room_start_C : float
    dropout : float
        Fraction of rows (never the first) logged as NaN, independently at random.
    warm_profile : {"steady", "heating"}
        "steady": every state at f of its own steady rise (the steady profile scaled);
        "heating": the state after a previous heating from cold, at ``warm_power``, stopped when
        the sensor reached f of this run's rise (other modal amplitudes than "steady").
    warm_power : float or None
        Power of the previous heating (None: ``power``); must exceed f·power.

    Returns
    -------
    WarmUp

    Raises
    ------
    InputError
        A non-positive ``interval_min`` or ``duration_min``, a negative ``noise_C`` or
        ``rounding_C``, a ``dropout`` outside [0, 1), a ``warm_start`` outside [0, 1), an unknown
        ``warm_profile``, a ``warm_power`` too low to reach the warm start, or a bad ``room_drift``.
    """
    if not (interval_min > 0 and noise_C >= 0 and rounding_C >= 0 and 0 <= dropout < 1):
        raise InputError("need interval_min > 0, noise_C ≥ 0, rounding_C ≥ 0, 0 ≤ dropout < 1")
    x0, t_pre = _initial_state(machine, power, room_start_C, warm_start, warm_profile, warm_power)
    steady0 = _steady_state(machine, power, room_start_C)
    t95 = _crossing_time(machine, x0 - steady0, EQUILIBRIUM_FRACTION)
    if duration_min is None:
        duration_min = float(np.clip(1.5 * t95, *DURATION_LIMITS_MIN))
    if not duration_min > 0:
        raise InputError("duration_min must be positive")
    n = int(math.floor(duration_min / interval_min + 1e-9)) + 1
    t: FloatArray = np.arange(n, dtype=float) * interval_min
    forced, xp0 = _forced_response(machine, t, power, room_start_C, room_drift)
    clean = forced + _free_response(machine, x0 - xp0, interval_min, n)
    room = room_temperature(t, room_start_C, room_drift)
    heat_gain = float(machine.sensor @ np.linalg.solve(-machine.A, machine.b_heat))
    room_gain = float(machine.sensor @ np.linalg.solve(-machine.A, machine.b_room))
    steady = heat_gain * power + room_gain * room
    reading = _rounded(clean + noise_C * rng.standard_normal(n), rounding_C)
    room_C = None
    drift_settings = None
    if room_drift is not None:
        room_noise = float(room_drift.get("noise_C", 0.01))
        room_rounding = float(room_drift.get("rounding_C", 0.01))
        room_C = _rounded(room + room_noise * rng.standard_normal(n), room_rounding)
        drift_settings = {k: float(v) for k, v in room_drift.items()}
        drift_settings.setdefault("noise_C", room_noise)
        drift_settings.setdefault("rounding_C", room_rounding)
    if dropout > 0:
        lost = rng.random(n) < dropout
        lost[0] = False
        reading[lost] = np.nan
        if room_C is not None:
            room_C[lost] = np.nan
    start = float(clean[0])
    settings: dict[str, Any] = {
        "kind": machine.kind,
        "description": machine.description,
        "time_constants_min": list(machine.time_constants_min),
        "structural_time_constants_min": list(machine.structural_time_constants_min),
        "sensor_lag_min": machine.sensor_lag_min,
        "power": float(power),
        "duration_min": float(t[-1]),
        "interval_min": float(interval_min),
        "samples": n,
        "noise_C": float(noise_C),
        "rounding_C": float(rounding_C),
        "warm_start": float(warm_start),
        "warm_profile": warm_profile if warm_start > 0 else None,
        "warm_power": None
        if warm_start == 0 or warm_profile == "steady"
        else float(power if warm_power is None else warm_power),
        "warm_heating_min": t_pre,
        "room_start_C": float(room_start_C),
        "room_drift": drift_settings,
        "dropout": float(dropout),
        "start_C": start,
        "steady_start_C": float(steady[0]),
        "rise_C": float(steady[0]) - start,
        "t95_min": t95,
    }
    return WarmUp(
        machine=machine,
        time_min=t,
        reading_C=reading,
        clean_C=clean,
        room_C=room_C,
        steady_C=steady,
        start_C=start,
        t95_min=t95,
        noise_C=float(noise_C),
        rounding_C=float(rounding_C),
        interval_min=float(interval_min),
        settings=settings,
        power=float(power),
        initial_state_C=x0,
    )


def _draw_rounding(rng: np.random.Generator, rise: float) -> float:
    """A rounding of the population that leaves at least 20 steps in the rise."""
    if rise < MIN_ROUNDING_STEPS * ROUNDINGS_C[0]:
        raise InputError(f"a rise of {rise:.3g} °C is under 20 steps of any rounding")
    while True:
        step = float(rng.choice(ROUNDINGS_C, p=ROUNDING_WEIGHTS))
        if abs(rise) >= MIN_ROUNDING_STEPS * step:
            return step


def _draw_interval(rng: np.random.Generator, duration: float, max_samples: int | None) -> float:
    """A sampling interval of the population; 1 s only for records of at most 300 min."""
    while True:
        interval = float(rng.choice(INTERVALS_MIN))
        if interval == INTERVALS_MIN[0] and duration > ONE_SECOND_MAX_DURATION_MIN:
            continue
        if max_samples is not None and duration / interval > max_samples:
            continue
        return interval


def random_warmup(
    rng: np.random.Generator,
    *,
    kind: str | None = None,
    with_drift: bool | None = None,
    with_dropouts: bool = False,
) -> WarmUp:
    """Draw a machine and a warm-up of it from the benchmark population.

    Machine as :func:`random_machine` (75 % network, 25 % conduction; lag with probability 0.4;
    the run's own rise log-uniform in 2-30 °C). Warm start with probability 0.2: a fraction
    0.1-0.6 of the steady rise, on the steady profile or after a previous heating (half each;
    its power 0.5-2× this run's). Room drift with probability 0.3: amplitude 0.05-0.3 °C, period
    12-24 h, random phase, half of them with a ramp of ±0.005-0.05 °C/h; a room sensor with σ
    log-uniform 0.005-0.05 °C and rounding 0.01-0.1 °C. Room at the start 17-25 °C. Duration 1.5·t95
    clipped to 60-2000 min; sampling 1 s (only up to 300 min), 10 s, 30 s, 1, 2 or 5 min; noise
    σ log-uniform 0.005-0.05 °C; rounding 0.01 (50 %), 0.02, 0.05 (15 % each), 0.1, 0.32 °C
    (10 % each), drawn again while the rise is under 20 steps.

    Parameters
    ----------
    rng : numpy.random.Generator
    kind : {"network", "conduction"} or None
        None draws it.
    with_drift : bool or None
        None draws it (probability 0.3); True/False forces a drifting/steady room.
    with_dropouts : bool
        Lose a fraction log-uniform in 0.1-5 % of the rows (NaN readings).

    Returns
    -------
    WarmUp
        ``settings`` holds every draw (the machine's structure under ``"machine"``).
    """
    power = 1.0
    warm_start, warm_profile, warm_power = 0.0, "steady", None
    if rng.random() < 0.2:
        warm_start = float(rng.uniform(0.1, 0.6))
        if rng.random() < 0.5:
            warm_profile = "heating"
            warm_power = float(rng.uniform(max(0.5, warm_start / 0.8), 2.0))
    # the run itself rises 2-30 °C: a warm machine's full rise is larger by 1/(1 − f)
    rise_C = float(_log_uniform(rng, 2.0, 30.0)) / (1.0 - warm_start)
    machine = random_machine(rng, kind, rise_C=rise_C)
    room_start = float(rng.uniform(17.0, 25.0))
    x0, _ = _initial_state(machine, power, room_start, warm_start, warm_profile, warm_power)
    steady0 = _steady_state(machine, power, room_start)
    t95 = _crossing_time(machine, x0 - steady0, EQUILIBRIUM_FRACTION)
    duration = float(np.clip(1.5 * t95, *DURATION_LIMITS_MIN))
    interval = _draw_interval(rng, duration, None)
    noise = float(_log_uniform(rng, 0.005, 0.05))
    rise = float(machine.sensor @ (steady0 - x0))
    rounding = _draw_rounding(rng, rise)
    drift: dict[str, float] | None = None
    if rng.random() < 0.3 if with_drift is None else with_drift:
        drift = {
            "amplitude_C": float(rng.uniform(0.05, 0.3)),
            "period_min": float(rng.uniform(12.0, 24.0) * 60.0),
            "phase_rad": float(rng.uniform(0.0, 2.0 * math.pi)),
            "slope_C_per_h": 0.0,
            "noise_C": float(_log_uniform(rng, 0.005, 0.05)),
            "rounding_C": float(rng.choice(ROOM_ROUNDINGS_C, p=ROOM_ROUNDING_WEIGHTS)),
        }
        if rng.random() < 0.5:
            drift["slope_C_per_h"] = float(rng.choice((-1.0, 1.0)) * rng.uniform(0.005, 0.05))
    dropout = float(_log_uniform(rng, 0.001, 0.05)) if with_dropouts else 0.0
    run = simulate(
        machine,
        rng,
        power=power,
        duration_min=duration,
        interval_min=interval,
        noise_C=noise,
        rounding_C=rounding,
        warm_start=warm_start,
        room_drift=drift,
        room_start_C=room_start,
        dropout=dropout,
        warm_profile=warm_profile,
        warm_power=warm_power,
    )
    return replace(run, settings={**run.settings, "machine": machine.structure})


def reference_run(machine: Machine, rng: np.random.Generator, **kw: Any) -> WarmUp:
    """A long cold-start run of the same machine, for learning its modes.

    Defaults (each overridden by a keyword of :func:`simulate`): power drawn in 0.6-1.4 (times
    ``base_power``, default 1); a cold start in a steady room; duration 3·t95 (a shorter
    ``duration_min`` given is raised to 3·t95); interval, noise and rounding drawn as in
    :func:`random_warmup`, the interval so that the record has at most 20 000 samples.

    Parameters
    ----------
    machine : Machine
    rng : numpy.random.Generator
    **kw
        Keywords of :func:`simulate`, and ``base_power``.

    Returns
    -------
    WarmUp
        ``settings["reference"]`` is True.

    Raises
    ------
    InputError
        A non-zero ``warm_start`` (a reference run starts cold), or what :func:`simulate` refuses.
    """
    base = float(kw.pop("base_power", 1.0))
    power = float(kw.pop("power", rng.uniform(0.6, 1.4) * base))
    if kw.get("warm_start", 0.0):
        raise InputError("a reference run starts cold")
    room_start = float(kw.pop("room_start_C", 20.0))
    x0 = np.full(len(machine.A), room_start)
    steady0 = _steady_state(machine, power, room_start)
    t95 = _crossing_time(machine, x0 - steady0, EQUILIBRIUM_FRACTION)
    duration = max(float(kw.pop("duration_min", 0.0) or 0.0), 3.0 * t95)
    if "interval_min" not in kw:
        kw["interval_min"] = _draw_interval(rng, duration, REFERENCE_MAX_SAMPLES)
    # whole intervals up to at least 3·t95: the last sample is not before it
    duration = math.ceil(duration / kw["interval_min"] - 1e-9) * kw["interval_min"]
    if "noise_C" not in kw:
        kw["noise_C"] = float(_log_uniform(rng, 0.005, 0.05))
    if "rounding_C" not in kw:
        kw["rounding_C"] = _draw_rounding(rng, float(machine.sensor @ (steady0 - x0)))
    run = simulate(machine, rng, power=power, duration_min=duration, room_start_C=room_start, **kw)
    return replace(run, settings={**run.settings, "reference": True})


def modal_amplitudes(machine: Machine, warmup: WarmUp) -> tuple[FloatArray, FloatArray]:
    """The run's sensor response as T∞ + Σ a_k·exp(−t/τ_k), in a steady room.

    Exact from the eigendecomposition A = V·Λ·V⁻¹: a_k = (sensor·V)_k·(V⁻¹(x0 − x∞))_k, with x0
    the run's initial state and x∞ its equilibrium at the starting room. T∞ = warmup.steady_C[0];
    for a drifting room this is the steady-room version of the run (the modes are the same).

    Parameters
    ----------
    machine : Machine
    warmup : WarmUp

    Returns
    -------
    taus : ndarray, shape (m,)
        Time constants (min), descending (one per state, the lag included).
    amplitudes : ndarray, shape (m,)
        a_k (°C); they sum to start_C − T∞.
    """
    room = float(warmup.settings["room_start_C"])
    h0 = warmup.initial_state_C - _steady_state(machine, warmup.power, room)
    rates, amplitudes = _modes(machine, h0)
    taus = -1.0 / rates
    order = np.argsort(-taus)
    return taus[order], amplitudes[order]


# --------------------------------------------------------------------------------------------
# Real curves


def _time_column(names: list[str]) -> tuple[str, float]:
    """The time column and its factor to minutes (seconds unless the name says minutes)."""
    for name in names:
        low = name.lower()
        if low.startswith("time") or low in ("t", "t_s", "t_min"):
            return name, (1.0 if low.endswith("min") else 1.0 / 60.0)
    raise InputError(f"no time column among {names}")


def _real_curve(name: str, t: FloatArray, y: FloatArray) -> RealCurve | None:
    keep = np.isfinite(t) & np.isfinite(y)
    t, y = t[keep] - t[keep][0], y[keep]
    n = len(y)
    if n < 40:
        return None
    distinct = np.unique(y)
    steps = np.diff(distinct)
    rounding = float(np.round(np.median(steps), 4)) if steps.size else 0.0
    start = float(np.median(y[:3]))
    tail = max(3, n // 20)
    end = float(np.median(y[-tail:]))
    rise = end - start
    if rise < max(1.0, 10.0 * rounding):  # not a heat-up (flat, or cooling)
        return None
    mark = int(0.75 * n)
    quarter = float(np.median(y[max(0, mark - tail // 2) : mark + tail // 2 + 1]))
    last_quarter = (end - quarter) / rise
    settled = end if last_quarter < 0.01 else math.nan
    t95 = math.nan
    if math.isfinite(settled):
        smooth = median_filter(y, size=max(5, (n // 100) | 1), mode="nearest")
        level = start + EQUILIBRIUM_FRACTION * (settled - start)
        past = np.flatnonzero(smooth >= level)
        if past.size and past[0] > 0:
            k = int(past[0])
            t95 = float(t[k - 1] + (level - smooth[k - 1]) / (smooth[k] - smooth[k - 1]) * (t[k] - t[k - 1]))
    return RealCurve(name, t, y, settled, t95, rounding, start, end, last_quarter)


def load_real_curves(folder: Path) -> list[RealCurve]:
    """Every heating channel of every CSV in ``folder`` (the project's ``../shared/realdata``).

    Temperature channels are the columns named T1, T2, … (TCLab); time is the column whose name
    starts with "Time", in seconds unless it ends in "min". A channel is kept when it rises by
    more than max(1 °C, 10 rounding steps) from its first three readings to its last 5 %.

    Parameters
    ----------
    folder : Path

    Returns
    -------
    list of RealCurve
        Sorted by file name, then column.

    Raises
    ------
    InputError
        A CSV without a time column.
    """
    curves = []
    for path in sorted(Path(folder).glob("*.csv")):
        with path.open(newline="") as handle:
            rows = list(csv.reader(handle))
        header, body = rows[0], [r for r in rows[1:] if r]
        time_name, factor = _time_column(header)
        data = np.array([[float(v) if v.strip() else math.nan for v in r] for r in body])
        t = data[:, header.index(time_name)] * factor
        for j, name in enumerate(header):
            if len(name) > 1 and name[0] in "Tt" and name[1:].isdigit():
                curve = _real_curve(f"{path.stem}:{name}", t, data[:, j])
                if curve is not None:
                    curves.append(curve)
    return curves
