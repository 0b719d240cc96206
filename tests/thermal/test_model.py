"""Tests of :mod:`mtident.thermal.model`."""

from __future__ import annotations

import numpy as np
import pytest

from mtident.thermal.model import rise_transition, slope_transition, to_physical


def test_slope_transition_caps_the_growth_of_a_negative_rate():
    # λΔt ≥ −0.5 is left as it is (the Gaussian approximation's small excursions) ...
    state = np.array([20.0, 1.0, -0.2])
    np.testing.assert_allclose(
        slope_transition(state, 1.0), [20.0 + (np.exp(0.2) - 1) / 0.2, np.exp(0.2), -0.2], rtol=1e-13
    )
    # ... beyond, a sigma point of a widened filter (λ = −10/min) grows by e^0.5 a step, not e^10
    far = slope_transition(np.array([20.0, 1.0, -10.0]), 1.0)
    np.testing.assert_allclose(far, [20.0 + (np.exp(0.5) - 1) / 0.5, np.exp(0.5), -10.0], rtol=1e-13)


def test_slope_transition_with_a_drifting_room_solves_the_heat_balance():
    """dT/dt = λ(T_room(t) + ΔT∞ − T) with the room rising linearly over the step, against an ODE solver."""
    from scipy.integrate import solve_ivp

    lam, rise, room0, rate, dt = 0.016, 8.8, 17.9, 0.004, 7.0
    T0 = 21.0
    solution = solve_ivp(lambda t, T: lam * (room0 + rate * t + rise - T), (0.0, dt), [T0], rtol=1e-12, atol=1e-12)
    T_end = solution.y[0, -1]
    slope_end = lam * (room0 + rate * dt + rise - T_end)
    state = np.array([T0, lam * (room0 + rise - T0), lam])
    moved = slope_transition(state, dt, rate)
    np.testing.assert_allclose(moved[:2], [T_end, slope_end], rtol=1e-9)
    # T + s/λ is the steady state at the room's new level
    assert moved[0] + moved[1] / lam == pytest.approx(room0 + rate * dt + rise, rel=1e-12)


def test_slope_parametrisation_is_the_same_curve():
    rate_state = np.array([20.0, 0.02, 30.0])
    slope_state = np.array([20.0, 0.02 * 10.0, 0.02])
    for dt in (0.5, 1.0, 7.0):
        np.testing.assert_allclose(slope_transition(slope_state, dt)[0], rise_transition(rate_state, dt)[0], rtol=1e-13)
    physical, cov = to_physical(slope_state, np.diag([1e-4, 1e-6, 1e-8]), "slope")
    np.testing.assert_allclose(physical, rate_state)
    np.testing.assert_allclose(cov, cov.T)
