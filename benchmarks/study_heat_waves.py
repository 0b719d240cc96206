"""Does a warm-up's rate of rise, once falling, grow again? A study of one physics the model-robust
interval does not use yet (issue 36, "the intervals obey the physics").

Without a reference, the interval's far end is often a course that the readings cannot tell from
the best model: a slow mode still rising while faster modes fall back by about as much, so that
the readings stay flat now and rise again later. Its rate of rise is near zero now and grows
again: a second wave of heat. A warm-up at constant power from one heat source, seen where the
heat enters, never does that (its modal amplitudes are all of one sign); heat from a second
source that reaches the sensor late can. This study measures how often, and how far, on two
populations:

* the machine benchmark's development machines (:mod:`_machines`, the test's heat input and
  initial state, the room held steady): per sensor, the rise that comes after the rate has
  fallen, beyond a rate that never grows again ("extra", °C);
* adversarial chains of 3-20 nodes with two heat sources at the two ends, most of the heat at
  the far end (50-97 %), the sensor at or near the small source: "extra", and the largest ratio
  of a later rate to the lowest rate since the rate's peak ("regrowth").

Whether such a rule would narrow the interval is measured on the papers' kind of curve (first
order, 59 min, 8.85 °C, σ 0.01 °C, 1-min readings): the 99 % profile hull's high end over sums of
four modes on a grid of 16 time constants (1.5-300 min), without the rule, with "a later rate at
most K times an earlier one" (from 60 min on, to 2500 min) and a rate that never falls below 0,
each model's amplitudes and T∞ solved by SLSQP within the residual threshold; and over three
modes on a finer grid, free and with every mode rising (a sensor where the only heat enters).

Run: python benchmarks/study_heat_waves.py [--first-seed 36000 --cases 100] [--chains 300] [--papers-curve]
"""

from __future__ import annotations

import argparse
import itertools
import sys
from pathlib import Path

import numpy as np
from scipy.linalg import expm
from scipy.optimize import lsq_linear, minimize

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machines import draw_case, states  # noqa: E402


def waves(rate: np.ndarray, dt: float) -> tuple[float, float]:
    """The rise after the rate's peak beyond a rate that never grows again (°C), and the largest
    ratio of a later rate to the lowest since the peak (rates above 1e-5 °C/min)."""
    after = rate[int(np.argmax(rate)) :]
    lowest = np.minimum.accumulate(after)
    later = np.maximum.accumulate(after[::-1])[::-1]
    seen = lowest > 1e-5
    regrowth = float(np.max(later[seen] / lowest[seen])) if seen.any() else 1.0
    return float(np.sum(after - lowest) * dt), regrowth


def benchmark_machines(first: int, count: int) -> list[tuple[float, float]]:
    out = []
    for seed in range(first, first + count):
        case = draw_case(seed)
        plant = case.plant
        dt = 0.25
        n = int(min(6.0 * max(plant.time_constants_min) + 100.0, 3000.0) / dt) + 1
        curves = states(plant, case.test_power, case.test_split, case.room.steady_version(), case.x0, dt, n) @ plant.C.T
        out += [waves(np.gradient(curves[:, s], dt), dt) for s in range(curves.shape[1])]
    return out


def two_source_chains(count: int, rng: np.random.Generator) -> list[tuple[float, float]]:
    out = []
    for _ in range(count):
        n = int(rng.choice([3, 4, 5, 8, 12, 20]))
        capacity = np.exp(rng.uniform(np.log(0.3), np.log(30.0), n))
        links = np.exp(rng.uniform(np.log(0.02), np.log(3.0), n - 1))
        convection = np.exp(rng.uniform(np.log(0.002), np.log(0.5), n))
        laplacian = np.zeros((n, n))
        for i, g in enumerate(links):
            laplacian[[i, i + 1], [i, i + 1]] += g
            laplacian[[i, i + 1], [i + 1, i]] -= g
        A = -(laplacian + np.diag(convection)) / capacity[:, None]
        taus = -1.0 / np.linalg.eigvals(A).real
        if taus.max() > 300.0:
            continue
        far = rng.uniform(0.5, 0.97)
        heat = np.zeros(n)
        heat[0], heat[-1] = 1.0 - far, far
        b = heat / capacity
        dt = 0.25
        steps = int((5.0 * taus.max() + 50.0) / dt)
        phi = expm(A * dt)
        forced = np.linalg.solve(A, (phi - np.eye(n)) @ b)
        x, xs = np.zeros(n), np.empty((steps, n))
        for k in range(steps):
            xs[k] = x
            x = phi @ x + forced
        scale = 10.0 / np.linalg.solve(-A, b).max()  # the largest rise 10 °C
        out += [waves(np.gradient(xs[:, s] * scale, dt), dt) for s in range(min(n, 3))]
    return out


def papers_curve_high_end(t_now: float, regrowth: float | None, sigma: float = 0.01) -> float:
    """The 99 % hull's high end (°C) of the papers' kind of curve read to ``t_now``, over sums of
    four modes on a grid, with the rate of rise at most ``regrowth`` times any earlier rate from
    60 min on (None: no such rule)."""
    t = np.arange(0.0, t_now + 1.0)
    y = 20.0 + 8.85 * (1.0 - np.exp(-t / 59.0)) + np.random.default_rng(1).normal(0.0, sigma, t.size)
    fits = []
    for combo in itertools.combinations(np.geomspace(1.5, 300.0, 16), 4):
        X = np.column_stack([np.ones_like(t)] + [np.exp(-t / tau) for tau in combo])
        inverse = np.linalg.inv(X.T @ X)
        beta = inverse @ X.T @ y
        fits.append((combo, X, beta, float(np.sum((y - X @ beta) ** 2)), inverse[0, 0]))
    threshold = min(f[3] for f in fits) + 6.63 * sigma**2  # chi-squared, one degree of freedom, 99 %
    ends = sorted(
        ((b[0] + np.sqrt(max(threshold - rss, 0.0) * v), c, X, b) for c, X, b, rss, v in fits if rss <= threshold),
        key=lambda e: -e[0],
    )
    if regrowth is None:
        return float(ends[0][0])
    grid = np.concatenate([np.linspace(60.0, t_now, 12), np.geomspace(t_now + 5.0, 2500.0, 30)])
    i, j = np.triu_indices(len(grid), 1)
    best = -np.inf
    for unconstrained, combo, X, beta in ends[:60]:
        if unconstrained <= best:
            break
        rate = np.column_stack([np.zeros_like(grid)] + [-np.exp(-grid / tau) / tau for tau in combo])
        grows = regrowth * rate[i] - rate[j]
        constraints = [
            {"type": "ineq", "fun": lambda b, X=X: (threshold - np.sum((y - X @ b) ** 2)) / sigma**2},
            {"type": "ineq", "fun": lambda b, G=grows: 1e3 * G @ b, "jac": lambda b, G=grows: 1e3 * G},
            {"type": "ineq", "fun": lambda b, R=rate: 1e3 * R @ b, "jac": lambda b, R=rate: 1e3 * R},
        ]
        b = minimize(lambda b: -b[0], beta, constraints=constraints, method="SLSQP", options={"maxiter": 500}).x
        feasible = (
            np.sum((y - X @ b) ** 2) <= threshold + 1e-9 and (grows @ b >= -1e-8).all() and (rate @ b >= -1e-8).all()
        )
        if feasible:
            best = max(best, float(b[0]))
    return best


def rising_modes_high_end(t_now: float, sigma: float = 0.01) -> tuple[float, float]:
    """The 99 % hull's high end (°C) of the papers' kind of curve read to ``t_now``, over sums of
    three modes on a grid of 40 time constants (1.5-300 min): free, and with every mode rising (a
    sensor where the only heat enters: its modal amplitudes all of one sign)."""
    t = np.arange(0.0, t_now + 1.0)
    y = 20.0 + 8.85 * (1.0 - np.exp(-t / 59.0)) + np.random.default_rng(1).normal(0.0, sigma, t.size)
    free, rising = [], []
    for combo in itertools.combinations(np.geomspace(1.5, 300.0, 40), 3):
        X = np.column_stack([np.ones_like(t)] + [np.exp(-t / tau) for tau in combo])
        inverse = np.linalg.inv(X.T @ X)
        beta = inverse @ X.T @ y
        free.append((X, beta, float(np.sum((y - X @ beta) ** 2)), inverse[0, 0]))
        bounded = lsq_linear(X, y, bounds=([-np.inf] * 4, [np.inf] + [0.0] * 3)).x
        rising.append((X, bounded, float(np.sum((y - X @ bounded) ** 2))))
    threshold = min(f[2] for f in free) + 6.63 * sigma**2
    free_end = max(b[0] + np.sqrt(max(threshold - rss, 0.0) * v) for _, b, rss, v in free if rss <= threshold)
    best = -np.inf
    for X, b, _ in sorted((r for r in rising if r[2] <= threshold), key=lambda r: -r[1][0])[:150]:
        within = {"type": "ineq", "fun": lambda v, X=X: (threshold - np.sum((y - X @ v) ** 2)) / sigma**2}
        v = minimize(
            lambda v: -v[0], b, constraints=[within], bounds=[(None, None)] + [(None, 0.0)] * 3, method="SLSQP"
        ).x
        if np.sum((y - X @ v) ** 2) <= threshold + 1e-9 and (v[1:] <= 1e-9).all():
            best = max(best, float(v[0]))
    return float(free_end), best


def summary(name: str, rows: list[tuple[float, float]]) -> None:
    extra = np.array([r[0] for r in rows])
    regrowth = np.array([r[1] for r in rows])
    print(f"{name}: {len(rows)} sensors")
    print(
        "  extra rise after the rate fell, °C: "
        + ", ".join(f"> {x:g}: {int((extra > x).sum())}" for x in (0.005, 0.05, 0.2))
    )
    print(
        "  regrowth of the rate: "
        + ", ".join(f"> {x:g}: {int((regrowth > x).sum())}" for x in (1.01, 1.5, 2.0, 3.0))
        + f"; largest {regrowth.max():.2f}"
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--first-seed", type=int, default=36000, help="development machines only (36000-36099)")
    parser.add_argument("--cases", type=int, default=100)
    parser.add_argument("--chains", type=int, default=300)
    parser.add_argument("--papers-curve", action="store_true", help="the 99 %% high end with and without the rule")
    args = parser.parse_args()
    if args.papers_curve:
        for t_now in (200.0, 265.0, 300.0):
            ends = {k: papers_curve_high_end(t_now, k) for k in (None, 3.0, 1.0)}
            print(f"t = {t_now:g} min (truth 28.85): " + ", ".join(f"rule {k}: {v:.2f}" for k, v in ends.items()))
        for t_now in (120.0, 150.0, 200.0, 265.0):
            free, rising = rising_modes_high_end(t_now)
            print(f"t = {t_now:g} min, three modes: free {free:.2f}, every mode rising {rising:.2f} (truth 28.85)")
        return
    summary(
        f"benchmark machines {args.first_seed}-{args.first_seed + args.cases - 1}",
        benchmark_machines(args.first_seed, args.cases),
    )
    summary("two-source chains", two_source_chains(args.chains, np.random.default_rng(1)))


if __name__ == "__main__":
    main()
