"""The papers' first-order filters on first-order warm-ups, the one model they are right for: how
often each method's 95 % interval of T∞ holds the truth when half of t95 has been read, and how
wide it is. Each case: τ 20-120 min, a rise of 5-15 °C, σ 0.005-0.05 °C, one reading a minute
rounded to 0.01 °C; ``identify`` with the data's tuning.

Run: python benchmarks/bench_filter_intervals.py [--cases 120] [--seed 7]
"""

from __future__ import annotations

import argparse
import sys
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from mtident.io.logs import TemperatureLog  # noqa: E402
from mtident.thermal import identify  # noqa: E402

METHODS = ("ukf", "aukf", "fukf", "afukf", "lsq")


def _case(rng: np.random.Generator) -> tuple[TemperatureLog, float, float]:
    """A first-order warm-up logged to 2·t95, its t95 and its T∞."""
    tau, rise, sigma = rng.uniform(20.0, 120.0), rng.uniform(5.0, 15.0), rng.uniform(0.005, 0.05)
    start = 20.0 + rng.uniform(-2.0, 2.0)
    t95 = 3.0 * tau
    t = np.arange(0.0, 2.0 * t95, 1.0)
    y = np.round(start + rise * (1.0 - np.exp(-t / tau)) + rng.normal(0.0, sigma, t.size), 2)
    return TemperatureLog(t, ("S",), y[:, None], (), "first-order.csv"), t95, start + rise


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--cases", type=int, default=120)
    parser.add_argument("--seed", type=int, default=7)
    args = parser.parse_args()
    rng = np.random.default_rng(args.seed)
    covered = {m: 0 for m in METHODS}
    trusted_missed = {m: 0 for m in METHODS}
    widths: dict[str, list[float]] = {m: [] for m in METHODS}
    for _ in range(args.cases):
        log, t95, truth = _case(rng)
        for method in METHODS:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                answer = identify(log, 0.5 * t95, method=method)
            low, high = answer.steady_state_ci95_C[0]
            holds = bool(low <= truth <= high)
            covered[method] += holds
            trusted_missed[method] += bool(answer.model_ok[0]) and not holds
            widths[method].append((high - low) / 2.0)
    print(f"{args.cases} first-order warm-ups (seed {args.seed}), identified at half of t95\n")
    print("| method | 95 % holds the truth | median half-width (°C) | trusted answers that missed |")
    print("|---|---|---|---|")
    for method in METHODS:
        share = 100.0 * covered[method] / args.cases
        print(
            f"| {method} | {covered[method]} ({share:.1f} %) | {np.nanmedian(widths[method]):.3f} | "
            f"{trusted_missed[method]} |"
        )


if __name__ == "__main__":
    main()
