"""Machines of the benchmark population, drawn at random.

The population is the one of the safe-stops benchmark and of the stopping-rule study
(``../shared/research/stop-rules.md``): linear thermal structures seen at one sensor,

* ``"network"``: a lumped RC network of 1-4 nodes, A = −C⁻¹G with G a weighted Laplacian of
  conductances plus convection to the room, every time constant drawn log-uniformly in
  2-300 min and the network built to have exactly those time constants;
* ``"conduction"``: a 1-D body (a shaft) of 30-60 finite volumes, conduction along it,
  convection along its surface, heat at one or two bearings, the sensor anywhere along it; its
  slowest time constant drawn in 2-300 min;

optionally seen through a first-order sensor lag (an extra state). Randomness comes only from
the ``np.random.Generator`` passed in.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.testing.structures import Machine

__all__ = ["KINDS", "log_uniform", "random_machine"]

KINDS = ("network", "conduction")
KIND_WEIGHTS = (0.75, 0.25)
# A sensor whose steady rise is under this share of the hottest node's would need an absurd heat
# input to rise 2-30 °C: such a sensor position is drawn again.
MIN_SENSOR_SHARE = 0.1
# Time constants closer than this (relative) are drawn again: the lag state and an equal network
# mode would make A defective, and near it the modal amplitudes lose digits.
MIN_RELATIVE_GAP = 0.02


def log_uniform(rng: np.random.Generator, low: float, high: float, size: int | None = None) -> Any:
    """A draw (or ``size`` draws) log-uniform in [low, high].

    Parameters
    ----------
    rng : numpy.random.Generator
    low, high : float
        The range, positive.
    size : int, optional
        How many (default: one, a scalar).

    Returns
    -------
    float or ndarray
    """
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
    ratio = float(log_uniform(rng, 0.3, 100.0))
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
        rise_C = float(log_uniform(rng, 2.0, 30.0))
    if kind == "network":
        n = int(rng.integers(1, 5)) if nodes is None else int(nodes)
        if not 1 <= n <= 4:
            raise InputError("a network has 1-4 nodes")
        while True:
            taus = np.sort(log_uniform(rng, min_time_constant_min, max_time_constant_min, n))
            if _well_separated(taus):
                break
        A, capacity, convection, structure = _network(rng, n, taus[::-1])
        power = np.zeros(n)
        heated = rng.choice(n, size=int(rng.integers(1, n + 1)), replace=False)
        power[heated] = rng.uniform(0.2, 1.0, heated.size)
        structure["heated_nodes"] = sorted(int(k) for k in heated)
        positions = None
    else:
        tau_slow = float(log_uniform(rng, min_time_constant_min, max_time_constant_min))
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
                lag = float(log_uniform(rng, 0.2, 5.0))
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
