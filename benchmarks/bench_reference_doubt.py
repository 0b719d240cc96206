"""A candidate doubt for learnt references, replayed on warm-ups: doubt a reference sensor whose
run leaves its own steady state much wider with one mode more than it determines (a slow mode the
run was too short or too coarse to show), and decide that sensor without the reference.

Per case of :func:`mtident.testing.warmups.random_warmup`: the reference learnt from another run
of the same machine (as in ``bench_safe_stops.py``), the run's own 95 % half-width of T∞ with the
learnt mode count and with one more, and the monitor replayed with the reference (and, where the
excess is over 0.1 °C, without it). ``--report`` prints, per threshold, the reference stops kept,
lost and beyond the tolerance.

Run: python benchmarks/bench_reference_doubt.py --first-seed 6000 --cases 250 --out doubt.jsonl
     python benchmarks/bench_reference_doubt.py --report doubt.jsonl
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from bench_safe_stops import TOLERANCE_C, _log, _replay

from mtident.testing.warmups import random_warmup, reference_run
from mtident.thermal.reference_learning import learn_reference
from mtident.thermal.robust import RobustSettings, estimate_sensor

THRESHOLDS_C = (0.1, 0.2, 0.3, 0.5)


def _half_width(t: np.ndarray, y: np.ndarray, modes: int) -> float:
    """The 95 % half-width of T∞ of a run fitted with up to ``modes`` modes."""
    estimate = estimate_sensor("S", t, y, None, RobustSettings(max_modes=modes, more_modes_when_used=False))
    lo, hi = estimate.interval_C[0.95]
    return float((hi - lo) / 2)


def run_case(seed: int) -> dict[str, object]:
    warm = random_warmup(np.random.default_rng(seed))
    run = reference_run(warm.machine, np.random.default_rng(seed + 10_000_000))
    with np.errstate(all="ignore"):
        learnt, _ = learn_reference(_log(run.time_min, run.reading_C, "reference"))
    case: dict[str, object] = {"seed": seed, "t95_min": warm.t95_min, "usable": False}
    if not learnt.sensors or learnt.sensors["S"].doubt is not None:
        return case
    count = len(learnt.sensors["S"].time_constants_min)
    with np.errstate(all="ignore"):
        same = _half_width(run.time_min, run.reading_C, count)
        more = _half_width(run.time_min, run.reading_C, count + 1) if count < 4 else same
    excess = max(more - same, 0.0)
    case.update(usable=True, count=count, excess=excess, with_reference=_replay(warm, learnt))
    case["without_reference"] = _replay(warm, None) if excess > min(THRESHOLDS_C) else None
    return case


def report(paths: list[Path]) -> None:
    cases = [json.loads(line) for path in paths for line in path.read_text().splitlines()]
    usable = [c for c in cases if c["usable"]]
    stops = [c for c in usable if c["with_reference"]["stopped"]]
    wrong = sum(abs(c["with_reference"]["error_C"]) > TOLERANCE_C for c in stops)
    print(f"{len(cases)} cases, {len(usable)} usable references: {len(stops)} stops, {wrong} beyond the tolerance")
    for threshold in THRESHOLDS_C:
        kept, lost, beyond = 0, 0, 0
        for c in usable:
            decided = c["without_reference"] if c["excess"] > threshold else c["with_reference"]
            kept += decided["stopped"]
            lost += c["with_reference"]["stopped"] and not decided["stopped"]
            beyond += decided["stopped"] and abs(decided["error_C"]) > TOLERANCE_C
        doubted = sum(c["excess"] > threshold for c in usable)
        said = f"{doubted} doubted, {kept} stops ({lost} lost), {beyond} beyond the tolerance"
        print(f"doubt over {threshold:g} °C: {said}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=250)
    parser.add_argument("--first-seed", type=int, default=6000)
    parser.add_argument("--out", type=Path, default=Path("reference_doubt.jsonl"))
    parser.add_argument("--report", type=Path, nargs="+", help="summarise results files and stop")
    args = parser.parse_args()
    if args.report:
        report(args.report)
        return
    with args.out.open("a") as out:
        for seed in range(args.first_seed, args.first_seed + args.cases):
            start = time.perf_counter()
            case = run_case(seed)
            case["seconds"] = time.perf_counter() - start
            out.write(json.dumps(case) + "\n")
            out.flush()


if __name__ == "__main__":
    main()
