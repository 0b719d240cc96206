"""UKF engine against filterpy, same work, one process.

(a) one 3-state temperature-rise filter, 400 steps;
(b) 1,000 independent 3-state filters, 400 steps each (filterpy in a loop).

Run: python benchmarks/bench_ukf.py
"""

from __future__ import annotations

import numpy as np
from _common import best_time, filterpy_ukf

from mtident.ukf import FilterConfig, GaussianState, run_filter

STEPS = 400
X0 = np.array([17.9, 0.01, 30.0])
P0 = np.diag([0.25, 1e-4, 16.0])
Q = np.diag([1e-6, 1e-10, 1e-8])
R = np.array([[4e-4]])


def f(points: np.ndarray) -> np.ndarray:
    T, lam, Tinf = points[..., 0], points[..., 1], points[..., 2]
    return np.stack([Tinf + (T - Tinf) * np.exp(-lam), lam, Tinf], axis=-1)


def h(points: np.ndarray) -> np.ndarray:
    return points[..., :1]


def data(batch: int) -> np.ndarray:
    rng = np.random.default_rng(0)
    t = np.arange(1, STEPS + 1, dtype=float)
    curve = 26.7 - 8.8 * np.exp(-0.016 * t)
    return curve[:, None, None] + 0.02 * rng.standard_normal((STEPS, batch, 1))


def ours(ys: np.ndarray) -> np.ndarray:
    batch = ys.shape[1]
    rec = run_filter(
        GaussianState(np.tile(X0, (batch, 1)), P0), ys, lambda p, k: f(p), h, Q, R, FilterConfig(redraw=True)
    )
    return rec.means[-1]


def peer(ys: np.ndarray) -> np.ndarray:
    out = []
    for b in range(ys.shape[1]):
        ukf = filterpy_ukf(3, 1, lambda x, dt: f(x), lambda x: x[:1], X0, P0, Q, R)
        for y in ys[:, b]:
            ukf.predict()
            ukf.update(y)
        out.append(ukf.x.copy())
    return np.array(out)


def main() -> None:
    single = data(1)
    np.testing.assert_allclose(ours(single), peer(single), rtol=1e-9)
    t_ours = best_time(lambda: ours(single), 5)
    t_peer = best_time(lambda: peer(single), 5)
    print(
        f"(a) 1 filter x {STEPS} steps:      mtident {t_ours * 1e3:8.1f} ms   filterpy {t_peer * 1e3:8.1f} ms   ratio "
        f"filterpy/mtident = {t_peer / t_ours:6.1f}x"
    )
    many = data(1000)
    t_ours = best_time(lambda: ours(many), 3)
    t_peer = best_time(lambda: peer(many[:, :50]), 1) * 1000 / 50
    print(
        f"(b) 1000 filters x {STEPS} steps:  mtident {t_ours * 1e3:8.1f} ms   filterpy {t_peer * 1e3:8.1f} ms (50 "
        f"filters timed, x20)   ratio = {t_peer / t_ours:6.1f}x"
    )


if __name__ == "__main__":
    main()
