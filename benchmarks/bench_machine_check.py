"""The cost of one check with the machine model (issue 36, "Speed"): on seeded machines of the
machine benchmark with 8-10 sensors, at a few times of the test, one joint fit of every sensor
(:func:`mtident.thermal.monitor.machine_fit`) against the per-sensor checks of the same readings
(:func:`mtident.thermal.monitor.sensor_estimate` for each sensor, with the reference), in one run.

The target: one check of a 10-sensor machine, machine model included, no slower than ten of the
per-sensor checks it replaced; the joint fit is added to them, so its share is what it costs.

Run: python benchmarks/bench_machine_check.py [--cases 6]
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machines import TOLERANCE_C, draw_case, simulate
from bench_machines import FIRST_SEED, learnt_reference

from mtident.thermal.monitor import MonitorSettings, Readings, machine_fit, sensor_estimate

TIMES_MIN = (30.0, 90.0, 240.0)


def _time(fn, repeat: int = 3) -> float:  # noqa: ANN001
    best = float("inf")
    for _ in range(repeat):
        started = time.perf_counter()
        fn()
        best = min(best, time.perf_counter() - started)
    return best


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--cases", type=int, default=6)
    args = parser.parse_args()
    rows = []
    seed = FIRST_SEED
    while len(rows) < args.cases * len(TIMES_MIN) and seed < FIRST_SEED + 100:
        case = draw_case(seed)
        seed += 1
        if len(case.plant.sensors) < 8:
            continue
        reference, _, _ = learnt_reference(case, case.seed)
        if reference is None or reference.machine_model is None:
            continue
        run = simulate(case, np.random.default_rng(case.seed + 20_000_000), "test")
        settings = MonitorSettings(tolerance_C=TOLERANCE_C, reference=reference, room_sensor="room")
        sensors = case.plant.sensors
        for at in TIMES_MIN:
            n = int(np.searchsorted(run.time_min, at, side="right"))
            readings = Readings(run.time_min[:n], run.reading_C[:n], run.room_reading_C[:n])
            with np.errstate(all="ignore"):
                joint = _time(lambda r=readings, n=sensors, k=settings: machine_fit(r, n, k))
                own = _time(
                    lambda r=readings, n=sensors, k=settings: [
                        sensor_estimate(r, s, name, k) for s, name in enumerate(n)
                    ],
                    1,
                )
            rows.append((case.seed, len(sensors), at, joint, own))
            print(
                f"seed {case.seed} ({len(sensors)} sensors) at {at:g} min: joint fit {joint * 1e3:.0f} ms, "
                f"{len(sensors)} per-sensor checks {own * 1e3:.0f} ms, check with the machine model / without "
                f"{(joint + own) / own:.2f}",
                flush=True,
            )
    ratios = [(j + o) / o for *_, j, o in rows]
    shares = [j / o for *_, j, o in rows]
    print(
        f"\n{len(rows)} checks: a check with the machine model takes a median {statistics.median(ratios):.2f}x "
        f"(max {max(ratios):.2f}x) of the per-sensor checks alone; the joint fit alone a median "
        f"{statistics.median(shares):.2f}x of them"
    )


if __name__ == "__main__":
    main()
