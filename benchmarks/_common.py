"""Shared helpers for the benchmarks: timing, the filterpy reference loop, and the seeded runs'
command line (shards of seeds written one case a line)."""

from __future__ import annotations

import argparse
import json
import time
from collections.abc import Callable
from pathlib import Path

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


def seeded_run_parser(description: str, cases: int, first_seed: int, out: str) -> argparse.ArgumentParser:
    """The options every seeded benchmark takes: how many cases from which seed, the JSON-lines
    file, the shard, and --report."""
    parser = argparse.ArgumentParser(description=description)
    parser.add_argument("--cases", type=int, default=cases)
    parser.add_argument("--first-seed", type=int, default=first_seed)
    parser.add_argument("--out", type=Path, default=Path(out))
    parser.add_argument("--shard", default="1/1", help="K/N: run every N-th case from the K-th")
    parser.add_argument("--report", type=Path, nargs="+", help="summarise results files and stop")
    return parser


def shard_seeds(args: argparse.Namespace) -> list[int]:
    """This shard's seeds not yet in ``args.out`` (a long run resumes where it stopped)."""
    k, n = (int(v) for v in args.shard.split("/"))
    done = (
        {json.loads(line)["seed"] for line in args.out.read_text().splitlines() if line.strip()}
        if args.out.exists()
        else set()
    )
    return [
        s
        for s in range(args.first_seed, args.first_seed + args.cases)
        if (s - args.first_seed) % n == k - 1 and s not in done
    ]


def run_seeds(args: argparse.Namespace, run_one: Callable[[int], dict[str, object]]) -> None:
    """Each of this shard's seeds not yet in ``args.out`` run by ``run_one``, its row (with the
    case's seconds) appended to ``args.out`` as a JSON line as soon as it is done, so that a long
    run resumes where it stopped."""
    for seed in shard_seeds(args):
        started = time.perf_counter()
        row = run_one(seed)
        row["case_seconds"] = time.perf_counter() - started
        with args.out.open("a") as out:
            out.write(json.dumps(row, default=float) + "\n")
        print(f"seed {seed}: {row['case_seconds']:.1f} s", flush=True)
