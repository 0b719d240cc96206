"""The first-order temperature-rise model (Xia et al. 2014 Eqs 29-32, Yu et al. 2019 Eq. 37).

T(t) = T∞ + (T₀ − T∞)·e^(−λt). As a state-space model with x = [T, λ, T∞]:
Tₖ = T∞ + (Tₖ₋₁ − T∞)·e^(−λΔtₖ), λ and T∞ constant, y = T. Any sampling
interval works, also uneven ones (Δtₖ per step).
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np

from mtident._typing import FloatArray, IntArray

__all__ = [
    "rise_transition",
    "slope_transition",
    "heat_balance_path",
    "transition_for",
    "to_physical",
    "observe_temperature",
    "rise_curve",
    "EQUILIBRIUM_FRACTION",
    "equilibrium_time",
    "PARAMETRISATIONS",
]

# "rate": x = [T, λ, T∞] as the papers; "slope": x = [T, s, λ] with s = dT/dt = λ(T∞ − T).
PARAMETRISATIONS = ("rate", "slope")

# The papers call the moment the rise reaches 95 % of its total the thermal equilibrium time.
EQUILIBRIUM_FRACTION = 0.95


def rise_transition(points: FloatArray, dt_min: FloatArray | float) -> FloatArray:
    """Propagate states (..., 3) = [T, λ, T∞] over ``dt_min`` minutes (broadcast to ...).

    Parameters
    ----------
    points : ndarray, shape (..., 3)
        States [T, λ, T∞] (°C, 1/min, °C).
    dt_min : float or ndarray
        The step (min), broadcast against ``points[..., 0]``.

    Returns
    -------
    ndarray, shape (..., 3)
        The states [T, λ, T∞] after the step.

    Examples
    --------
    >>> rise_transition(np.array([20.0, 0.1, 30.0]), 10.0).round(4).tolist()
    [26.3212, 0.1, 30.0]
    """
    T, lam, Tinf = points[..., 0], points[..., 1], points[..., 2]
    return np.stack([Tinf + (T - Tinf) * np.exp(-lam * dt_min), lam, Tinf], axis=-1)


def slope_transition(points: FloatArray, dt_min: FloatArray | float, room_rate: FloatArray | float = 0.0) -> FloatArray:
    """Propagate states (..., 3) = [T, s, λ] with s = dT/dt, over ``dt_min`` minutes.

    The same first-order curve as :func:`rise_transition`, written so that the
    measurement informs T and s almost linearly and only λ enters nonlinearly:
    Tₖ = Tₖ₋₁ + sₖ₋₁(1 − e^(−λΔt))/λ, sₖ = sₖ₋₁e^(−λΔt). With [T, λ, T∞] the
    short-window posterior is a curved ridge (only λ(T∞ − T) is known early),
    which a UKF's Gaussian approximation follows badly; with [T, s, λ] the UKF
    reaches the Cramér-Rao bound (benchmarks/bench_thermal.py).

    ``room_rate`` (°C/min over the step) makes the room the input of the same
    heat balance: dT/dt = λ(T_room + ΔT∞ − T), the papers' first-order model
    (one heat capacity, one conductance to the room) with a room that drifts.
    Then s relaxes towards the room's rate r instead of 0:
    sₖ = r + (sₖ₋₁ − r)e^(−λΔt), Tₖ = Tₖ₋₁ + rΔt + (sₖ₋₁ − r)(1 − e^(−λΔt))/λ,
    and T + s/λ stays the steady state at the room's current level.

    Parameters
    ----------
    points : ndarray, shape (..., 3)
        States [T, s, λ] (°C, °C/min, 1/min).
    dt_min : float or ndarray
        As for :func:`rise_transition`.
    room_rate : float or ndarray, optional
        The room's rate over the step (°C/min); 0 for a steady room.

    Returns
    -------
    ndarray, shape (..., 3)
        After the step, the states [T, s, λ].

    Examples
    --------
    >>> slope_transition(np.array([20.0, 1.0, 0.1]), 10.0).round(4).tolist()
    [26.3212, 0.3679, 0.1]
    """
    T, slope, lam = points[..., 0], points[..., 1], points[..., 2]
    # Sigma points of a wide belief can reach λ < 0, where e^(−λΔt) grows. A little is part of
    # the Gaussian approximation; a lot (a widened filter's λ = −10/min grew ×22,000 a step and
    # diverged to 1e28) is no heat balance: the growth is capped at e^0.5 per step.
    x = np.maximum(lam * dt_min, -0.5)
    small = np.abs(x) < 1e-9
    gain = dt_min * np.where(small, 1.0 - 0.5 * x, -np.expm1(-x) / np.where(small, 1.0, x))
    excess = slope - room_rate
    return np.stack([T + room_rate * dt_min + excess * gain, room_rate + excess * np.exp(-x), lam], axis=-1)


def heat_balance_path(state: FloatArray, start: IntArray, dt_min: FloatArray, room_rate: FloatArray) -> FloatArray:
    """Temperatures (N, ...) of states (..., 3) = [T, s, λ] run on with :func:`slope_transition`.

    Each state holds until its ``start`` index (broadcast to ``state.shape[:-1]``)
    and moves on from there, step k covering ``dt_min[k]`` with the room's rate
    ``room_rate[k]``: the heat balance with the measured room as its input.

    Parameters
    ----------
    state : ndarray, shape (..., 3)
        States [T, s, λ] (°C, °C/min, 1/min).
    start : ndarray of int
        The step each state holds until, broadcast to ``state.shape[:-1]``.
    dt_min : ndarray, shape (N,)
        Each step's length (min).
    room_rate : ndarray, shape (N,)
        The room's rate over each step (°C/min).

    Returns
    -------
    ndarray, shape (N, ...)
        T after each step (°C).
    """
    path = np.empty((len(dt_min), *state.shape[:-1]))
    for k in range(len(dt_min)):
        moved = slope_transition(state, dt_min[k], room_rate[k])
        state = np.where((k > start)[..., None], moved, state)
        path[k] = state[..., 0]
    return path


def transition_for(parametrisation: str) -> Callable[[FloatArray, FloatArray | float], FloatArray]:
    """The transition of a parametrisation ("rate" or "slope").

    Parameters
    ----------
    parametrisation : {"rate", "slope"}

    Returns
    -------
    callable
        :func:`rise_transition` for "rate", else :func:`slope_transition`.
    """
    return rise_transition if parametrisation == "rate" else slope_transition


def to_physical(mean: FloatArray, cov: FloatArray, parametrisation: str) -> tuple[FloatArray, FloatArray]:
    """Mean (..., 3) and covariance (..., 3, 3) of [T, λ, T∞] from either parametrisation.

    For "slope", T∞ = T + s/λ and the covariance is propagated to first order
    (J P Jᵀ).

    Parameters
    ----------
    mean : ndarray, shape (..., 3)
        The state's mean in ``parametrisation``.
    cov : ndarray, shape (..., 3, 3)
        Its covariance.
    parametrisation : {"rate", "slope"}
        "rate": [T, λ, T∞], returned as given; "slope": [T, s, λ].

    Returns
    -------
    mean : ndarray, shape (..., 3)
        [T, λ, T∞] (°C, 1/min, °C).
    cov : ndarray, shape (..., 3, 3)
    """
    if parametrisation == "rate":
        return mean, cov
    T, slope, lam = mean[..., 0], mean[..., 1], mean[..., 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        steady = T + slope / lam
        jac = np.zeros((*mean.shape[:-1], 3, 3))
        jac[..., 0, 0] = 1.0
        jac[..., 1, 2] = 1.0
        jac[..., 2, 0] = 1.0
        jac[..., 2, 1] = 1.0 / lam
        jac[..., 2, 2] = -slope / lam**2
    physical = np.stack([T, lam, steady], axis=-1)
    return physical, jac @ cov @ np.swapaxes(jac, -1, -2)


def observe_temperature(points: FloatArray) -> FloatArray:
    """y = T (Eq. 32): (..., 3) → (..., 1).

    Parameters
    ----------
    points : ndarray, shape (..., 3)
        States, T (°C) first.

    Returns
    -------
    ndarray, shape (..., 1)
    """
    return points[..., :1]


def rise_curve(time_min: FloatArray, start_C: FloatArray, rate_per_min: FloatArray, steady_C: FloatArray) -> FloatArray:
    """T(t) = T∞ + (T₀ − T∞)e^(−λt), broadcast.

    Parameters
    ----------
    time_min : ndarray
        Time since T₀ (min).
    start_C : ndarray
        T₀ (°C).
    rate_per_min : ndarray
        λ (1/min).
    steady_C : ndarray
        T∞ (°C).

    Returns
    -------
    ndarray
        T(t) (°C), in the inputs' broadcast shape.
    """
    return steady_C + (start_C - steady_C) * np.exp(-rate_per_min * time_min)


def equilibrium_time(rate_per_min: FloatArray) -> FloatArray:
    """Time to 95 % of the total rise of a first-order curve: ln(20)/λ.

    Parameters
    ----------
    rate_per_min : ndarray
        λ (1/min).

    Returns
    -------
    ndarray
        The time from the curve's start (min).
    """
    answer: FloatArray = np.log(1.0 / (1.0 - EQUILIBRIUM_FRACTION)) / rate_per_min
    return answer
