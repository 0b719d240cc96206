"""Where the heat enters: the monitor without a reference, on seeded machines, with the sensors
whose every mode rises stated as such (``--heat-enters-at``), against the same test without it.

Each case is a machine of :mod:`_machines` (as ``bench_machines.py`` draws them) and its test log.
A sensor's warm-up "has every mode rising" where, on the noiseless test from its start state to
its equilibrium at the room's first level, each of its modal amplitudes lifts it (a sensor at a
heat source's node of a conductance network, without a lag of its own, started cold or warm from
the same heat): the truth this benchmark reads off the machine, which an engineer would state
from where the sensor sits.

Three replays per case, none with a reference, the room sensor as the ambient input:

- ``stated``: those sensors stated, the test waiting for them alone;
- ``plain``: the same sensors waited for, nothing stated (what the tool does without the option);
- ``misused``: every sensor stated and waited for, rising or not (an engineer who states it
  wrongly): how often the readings contradict it, and how often a stop comes beyond the tolerance.

Recorded per replay: the stop, the waited sensors' worst T∞ error against the truth at the stop
(their equilibrium at the room's level), whether each 95 % interval covers it, and stop/t_settle
(the latest settle time of the waited sensors on the noiseless curve, where finite).

Seeds: development 36000-36199 may be looked at; held-out blocks of ``bench_machines.py``'s range
(37000-40999) are for evaluating a change once: 39700-39739 was spent on this option.

Run: python benchmarks/bench_heat_enters.py --cases 40 --first-seed 36000 --out heat.jsonl [--shard 1/2]
     python benchmarks/bench_heat_enters.py --report heat.jsonl
"""

from __future__ import annotations

import json
import math
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _common import run_seeds, seeded_run_parser  # noqa: E402
from _machines import TOLERANCE_C, Case, draw_case, simulate  # noqa: E402

from mtident.thermal.monitor import MonitorSettings, monitor_step, new_state  # noqa: E402
from mtident.thermal.robust_types import RobustSettings  # noqa: E402

FIRST_SEED = 36000
# a modal amplitude smaller than this share of the sensor's largest counts as none
NEGLIGIBLE_SHARE = 1e-4


def rising_sensors(case: Case) -> list[bool]:
    """Per sensor, whether every modal amplitude of its noiseless test lifts it toward its
    equilibrium at the room's first level (the heat part alone: the room held)."""
    plant = case.plant
    x_end = np.linalg.solve(
        -plant.A, plant.b_sources @ (case.test_power * case.test_split) + plant.b_room * case.room.start_C
    )
    values, vectors = np.linalg.eig(plant.A)
    weights = np.linalg.solve(vectors, case.x0 - x_end)
    amplitudes = np.real((plant.C @ vectors) * weights[None, :])  # (S, modes): y − y∞ = Σ a e^(λt)
    out = []
    for row in amplitudes:
        big = np.abs(row) > NEGLIGIBLE_SHARE * np.abs(row).max()
        out.append(bool(np.all(row[big] <= 0.0)))
    return out


def replay(case: Case, run, stated: tuple[str, ...], waited: tuple[str, ...]) -> dict[str, object]:  # noqa: ANN001
    """The monitor over the test log without a reference."""
    sensors = list(case.plant.sensors)
    settings = MonitorSettings(
        tolerance_C=TOLERANCE_C,
        room_sensor="room",
        wait_for=waited,
        robust=RobustSettings(heat_enters_at=stated),
    )
    state = new_state(sensors, with_room=True)
    started = time.perf_counter()
    with np.errstate(all="ignore"):
        state, events = monitor_step(state, run.time_min, run.reading_C, run.room_reading_C, settings)
    seconds = time.perf_counter() - started
    at = state.stop_time_min if state.stopped else float(run.time_min[-1])
    k = min(int(np.searchsorted(run.time_min, at - 1e-9)), len(run.time_min) - 1)
    per = []
    for s, check in enumerate(state.checks):
        if check.sensor not in waited:
            continue
        truth = float(run.truth_C[k][s])
        error = check.steady_C - truth
        per.append(
            {
                "sensor": check.sensor,
                "status": check.status,
                "error_C": float(error) if math.isfinite(error) else None,
                "covered95": bool(check.low95_C <= truth <= check.high95_C),
                "contradicted": any("stated as where the heat enters" in w for w in check.warnings),
            }
        )
    settle = [case.sensor_settle_min[case.plant.sensors.index(p["sensor"])] for p in per]
    t_settle = max(settle) if settle and all(math.isfinite(v) for v in settle) else None
    errors = [abs(p["error_C"]) for p in per if p["error_C"] is not None]
    return {
        "seconds": seconds,
        "stopped": state.stopped,
        "stop_min": state.stop_time_min if state.stopped else None,
        "last_min": float(run.time_min[-1]),
        "t_settle_min": t_settle,
        "worst_error_C": max(errors) if errors else None,
        "beyond": bool(state.stopped and any(e > TOLERANCE_C for e in errors)),
        "sensors": per,
    }


def run_case(case: Case, seed: int) -> dict[str, object]:
    run = simulate(case, np.random.default_rng(seed + 20_000_000), "test")
    rising = rising_sensors(case)
    names = tuple(case.plant.sensors)
    heated = tuple(n for n, r in zip(names, rising, strict=True) if r)
    out: dict[str, object] = {
        "seed": seed,
        "description": case.plant.description,
        "room": case.room.describe(),
        "rising": list(rising),
        "sensor_where": list(case.plant.sensor_where),
        "sensor_lags_min": list(case.plant.sensor_lags_min),
    }
    if heated:
        out["stated"] = replay(case, run, heated, heated)
        out["plain"] = replay(case, run, (), heated)
    out["misused"] = replay(case, run, names, names)
    return out


def report(paths: list[Path]) -> dict[str, object]:
    rows = [json.loads(line) for p in paths for line in p.read_text().splitlines() if line.strip()]
    summary: dict[str, object] = {"cases": len(rows), "with a rising sensor": sum("stated" in r for r in rows)}
    for key in ("stated", "plain", "misused"):
        runs = [r[key] for r in rows if key in r]
        stops = [x for x in runs if x["stopped"]]
        ratios = sorted(x["stop_min"] / x["t_settle_min"] for x in stops if x["t_settle_min"])
        covered = [p["covered95"] for x in stops for p in x["sensors"]]
        summary[key] = {
            "replays": len(runs),
            "stopped": len(stops),
            "beyond": sum(x["beyond"] for x in stops),
            "worst_error_C": max((x["worst_error_C"] or 0.0 for x in stops), default=None),
            "covered95_at_stop": (sum(covered) / len(covered)) if covered else None,
            "covered95_at_stop_or_end": float(np.mean([p["covered95"] for x in runs for p in x["sensors"]]))
            if runs
            else None,
            "worst_error_at_stop_or_end_C": max((x["worst_error_C"] or 0.0 for x in runs), default=None),
            "median_stop_over_settle": float(np.median(ratios)) if ratios else None,
            "p90_stop_over_settle": float(np.percentile(ratios, 90)) if ratios else None,
            "contradicted_sensors": sum(p["contradicted"] for x in runs for p in x["sensors"]),
            "beyond_seeds": [r["seed"] for r in rows if key in r and r[key]["beyond"]],
        }
    return summary


def main() -> None:
    parser = seeded_run_parser(__doc__.splitlines()[0], 40, FIRST_SEED, "heat.jsonl")
    args = parser.parse_args()
    if args.report:
        print(json.dumps(report(args.report), indent=2))
        return
    run_seeds(args, lambda seed: run_case(draw_case(seed), seed))


if __name__ == "__main__":
    main()
