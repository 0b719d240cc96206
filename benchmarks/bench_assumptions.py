"""What each of the monitor's assumptions costs: the same warm-ups replayed with a learnt reference
under the default settings and with one assumption said otherwise at a time.

The cases are :mod:`bench_safe_stops`'s (``random_warmup`` with a reference learnt from another
run of the same machine). Per case and variant: the stop, T∞'s error there against the truth, and
whether the 95 % interval covers it. ``--report`` prints, per variant, the stops, those beyond the
tolerance, the median stop over every case (a case that does not stop counts as never), the share
within 1.5·t95, and the median of the stop's ratio to the default's where both stop.

Run: python benchmarks/bench_assumptions.py --cases 120 --first-seed 17100 --out a.jsonl [--shard 1/2]
     python benchmarks/bench_assumptions.py --report a.jsonl
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from _common import seeded_run_parser, shard_seeds  # noqa: E402
from bench_safe_stops import TOLERANCE_C, _replay, learnt_reference, near_first_order  # noqa: E402

from mtident.testing.warmups import random_warmup  # noqa: E402
from mtident.thermal.robust import RobustSettings  # noqa: E402

VARIANTS: dict[str, dict[str, object]] = {
    "default": {},
    "one free fast mode (--free-fast-modes 1)": {"robust": RobustSettings(free_fast_modes=1)},
    "no free fast mode (--free-fast-modes 0)": {"robust": RobustSettings(free_fast_modes=0)},
    "a steady room (--room-wander 0)": {"robust": RobustSettings(room_wander_C_per_h=0.0)},
    "decided at 95 % (--confidence 0.95)": {"decision_level": 0.95},
    "one check within suffices": {"consecutive_checks": 1},
}


def run_case(seed: int) -> dict[str, object] | None:
    """One case under every variant; None where the reference run kept no usable sensor."""
    warm = random_warmup(np.random.default_rng(seed))
    reference = learnt_reference(seed, warm.machine)
    if reference is None or reference.sensors["S"].doubt is not None:
        return None
    near, _ = near_first_order(warm.machine, warm)
    case: dict[str, object] = {
        "seed": seed,
        "t95_min": warm.t95_min,
        "near_first_order": near,
        "room_sensor": warm.room_C is not None,
    }
    for name, said in VARIANTS.items():
        case[name] = _replay(warm, reference, **said)
    return case


def report(paths: list[Path]) -> str:
    """A Markdown table per group of cases."""
    cases = [json.loads(line) for path in paths for line in path.read_text().splitlines() if line.strip()]
    groups = (
        ("all", cases),
        ("near first order", [c for c in cases if c["near_first_order"]]),
        ("multi-mode", [c for c in cases if not c["near_first_order"]]),
        ("no room sensor", [c for c in cases if not c["room_sensor"]]),
    )
    lines = []
    for label, group in groups:
        if not group:
            continue
        lines += [
            f"\n{label} ({len(group)} cases)\n",
            "| assumption | stopped | beyond tolerance (worst °C) | 95 % covers at stop | median stop/t95 "
            "(no stop: never) | within 1.5·t95 | stop against the default's (both stop) |",
            "|---|---|---|---|---|---|---|",
        ]
        for name in VARIANTS:
            ratio = np.array([c[name]["stop_min"] / c["t95_min"] if c[name]["stopped"] else np.inf for c in group])
            stops = [c for c in group if c[name]["stopped"]]
            errors = np.array([abs(c[name]["error_C"]) for c in stops])
            covered = np.mean([c[name]["covered95"] for c in stops]) if stops else np.nan
            paired = [c[name]["stop_min"] / c["default"]["stop_min"] for c in stops if c["default"]["stopped"]]
            lines.append(
                f"| {name} | {len(stops)} | {int((errors > TOLERANCE_C).sum())} "
                f"({errors.max(initial=0.0):.3f}) | {covered * 100:.1f} % | {np.median(ratio):.2f} | "
                f"{np.mean(ratio <= 1.5) * 100:.0f} % | {np.median(paired) if paired else np.nan:.2f} |"
            )
    return "\n".join(lines)


def main() -> None:
    args = seeded_run_parser(__doc__.splitlines()[0], 120, 17100, "assumptions.jsonl").parse_args()
    if args.report:
        print(report(args.report))
        return
    for seed in shard_seeds(args):
        case = run_case(seed)
        if case is not None:
            with args.out.open("a") as out:
                out.write(json.dumps(case, default=float) + "\n")
        print(f"seed {seed}", flush=True)


if __name__ == "__main__":
    main()
