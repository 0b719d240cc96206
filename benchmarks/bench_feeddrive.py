"""Feed-drive identification: accuracy on simulated data and speed against filterpy.

Accuracy: 2 s at 10 kHz, 20 N impulse on the table, noise 1 % of each response's
RMS, guess 30 % off; all 12 responses and the realistic subset.
Speed: the 20,000-step identification (16 states, 12 responses) with mtident's
compiled loop and with filterpy's UnscentedKalmanFilter doing the same steps
(same RK4 sub-steps, same sigma points) in the same run. filterpy is timed on
the first 300 steps and scaled to 20,000 (it needs ~20 ms a step).

Run: python benchmarks/bench_feeddrive.py
"""

from __future__ import annotations

import time

import numpy as np
from _common import filterpy_ukf

from mtident.feeddrive import IDENTIFIED, FeedDriveParameters, default_guess, identify_feed_drive, simulate
from mtident.feeddrive.identify import _build_matrices, _parameter_basis
from mtident.feeddrive.simulate import substeps_for


def accuracy() -> None:
    truth = FeedDriveParameters()
    response = simulate(truth, noise_fraction=0.01, rng=np.random.default_rng(2024))
    for measured in ("all", "realistic"):
        result = identify_feed_drive(response, measured=measured)
        errors, covers = result.errors_percent(truth), result.covers(truth)
        print(f"\nmeasured: {measured} ({', '.join(result.measured_columns)})")
        print(f"{'param':>6} {'guess':>11} {'estimate':>11} {'2σ %':>8} {'error %':>9} {'±2σ covers':>11} {'identified':>11}")
        for i, name in enumerate(IDENTIFIED):
            print(f"{name:>6} {getattr(result.guess, name):11.5g} {result.parameters[i]:11.5g} {200 * result.parameters_sd[i] / result.parameters[i]:8.3g} {errors[name]:9.3g} {str(covers[name]):>11} {str(bool(result.identifiable[i])):>11}")
        print("correlation (Table 2): " + ", ".join(f"{k} {v:.5f}" for k, v in result.correlation.items()))


def speed() -> None:
    truth = FeedDriveParameters()
    response = simulate(truth, noise_fraction=0.01, rng=np.random.default_rng(1))
    identify_feed_drive(simulate(truth, duration_s=0.01))  # compile (cached on disk afterwards)
    start = time.perf_counter()
    identify_feed_drive(response)
    t_ours = time.perf_counter() - start

    guess = default_guess()
    h = 1e-4
    m = substeps_for(guess, h, max_phase_step=0.15)
    basis = _parameter_basis(guess)
    reference = guess.identified()
    m_inv = 1.0 / np.array([guess.Mt, guess.Mb, guess.Jb, guess.Jm])
    scale = np.sqrt(np.mean(response.values**2, axis=0))
    steps = 300

    def fx(z: np.ndarray, dt: float, drive: np.ndarray) -> np.ndarray:
        a = _build_matrices(reference * np.exp(z[8:]), basis)
        x = z[:8] * scale[:8]
        d = h / m
        f = lambda y: a @ y + np.concatenate([np.zeros(4), drive])  # noqa: E731
        for _ in range(m):
            k1 = f(x); k2 = f(x + d / 2 * k1); k3 = f(x + d / 2 * k2); k4 = f(x + d * k3)  # noqa: E702
            x = x + d / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
        return np.concatenate([x / scale[:8], z[8:]])

    def hx(z: np.ndarray, drive: np.ndarray) -> np.ndarray:
        a = _build_matrices(reference * np.exp(z[8:]), basis)
        x = z[:8] * scale[:8]
        return np.concatenate([x, a[4:] @ x + drive]) / scale

    ukf = filterpy_ukf(16, 12, fx, hx, np.zeros(16), np.diag([1e-4] * 8 + [0.25] * 8), np.diag([1e-8] * 8 + [1e-12] * 8), np.diag((0.01 * np.ones(12)) ** 2))
    drives = response.forces * m_inv
    start = time.perf_counter()
    for k in range(1, steps + 1):
        ukf.predict(drive=drives[k - 1])
        ukf.update(response.values[k] / scale, drive=drives[k])
    t_peer = (time.perf_counter() - start) * 20_000 / steps
    print(f"\n20,000-step identification (16 states, 12 responses, RK4 with {m} sub-steps):")
    print(f"  mtident {t_ours:.2f} s (real time: 2.00 s)   filterpy {t_peer:.0f} s (300 steps timed, scaled)   ratio filterpy/mtident = {t_peer / t_ours:.0f}x")


if __name__ == "__main__":
    accuracy()
    speed()
