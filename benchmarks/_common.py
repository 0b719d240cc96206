"""Shared helpers for the benchmarks: timing and the filterpy reference loop."""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np


def best_time(func: Callable[[], object], repeat: int = 3) -> float:
    """Best wall time of ``repeat`` runs, in seconds."""
    best = np.inf
    for _ in range(repeat):
        start = time.perf_counter()
        func()
        best = min(best, time.perf_counter() - start)
    return float(best)


def filterpy_ukf(dim_x: int, dim_z: int, fx, hx, x0, P0, Q, R, alpha=1.0, beta=2.0, kappa=0.0):
    """A filterpy UnscentedKalmanFilter set up like ours (MerweScaledSigmaPoints)."""
    from filterpy.kalman import MerweScaledSigmaPoints, UnscentedKalmanFilter

    ukf = UnscentedKalmanFilter(
        dim_x=dim_x, dim_z=dim_z, dt=1.0, fx=fx, hx=hx, points=MerweScaledSigmaPoints(dim_x, alpha, beta, kappa)
    )
    ukf.x, ukf.P, ukf.Q, ukf.R = np.array(x0, float), np.array(P0, float), np.array(Q, float), np.array(R, float)
    return ukf
