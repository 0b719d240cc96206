"""Helpers that tests of more than one module share."""

from __future__ import annotations

import numpy as np

DT = 1.0


def thermal_f(points: np.ndarray) -> np.ndarray:
    """Seed 000 Eq. 31 on sigma points (..., S, 3)."""
    T, lam, Tinf = points[..., 0], points[..., 1], points[..., 2]
    return np.stack([Tinf + (T - Tinf) * np.exp(-lam * DT), lam, Tinf], axis=-1)


def first(points: np.ndarray) -> np.ndarray:
    return points[..., :1]


def thermal_data(seed: int = 0, steps: int = 400, sigma: float = 0.02) -> np.ndarray:
    rng = np.random.default_rng(seed)
    t = np.arange(1, steps + 1) * DT
    return (26.7 - 8.8 * np.exp(-0.016 * t) + sigma * rng.standard_normal(steps))[:, None]


THERMAL_X0 = np.array([17.9, 0.01, 30.0])


THERMAL_P0 = np.diag([0.5**2, 0.01**2, 4.0**2])


THERMAL_Q = np.diag([1e-6, 1e-10, 1e-8])


THERMAL_R = np.array([[0.02**2]])
