"""Machines, not single curves: the monitor on seeded multi-sensor machines (issue 36, "Evidence").

Each case is a random machine of :mod:`_machines` (lumped networks of 2-5 nodes and conduction
bodies, time constants 2-300 min; 3-10 sensors, on nodes or between two, some with a 0.5-3 min
lag; 1-3 heat sources with a heat split), its reference run (cold, at power 1 and a split changed
by up to ±30 % from the test's, logged until it settles, the room logged), and a test at another
power (0.6-0.9 or 1.1-1.5), starting cold or up to 30 % warm (the state of an earlier partial
warm-up), in a steady room, a daily cycle of ±0.1-0.6 °C or a linear drift, the room logged by a
room sensor; sampling 10 s-2 min, σ 0.005-0.05 °C per sensor, readings rounded to 0.01 °C.

Per case the monitor replays the test with the room sensor as the ambient input, without a
reference and with the reference learnt
(:func:`mtident.thermal.reference_learning.learn_reference`, with its room sensor) from the
reference run. Recorded: whether it stopped and when, stop/t_settle,
every sensor's T∞ error against the truth (its equilibrium at the room's level at the stop, the
room's static gain one) and whether the 95 % interval covers it, each sensor's status and what
sets its interval's ends, and for a test that did not stop the monitor's reason.

t_settle: the time after which every sensor stays within 0.2 °C of its truth on the noiseless
curve. Where a slow machine lags a daily room cycle or a drift by more than the tolerance for good
(t_settle infinite), the same test's in a steady room stands in (``settle_basis``).

Seeds: the development blocks 36000-36199 may be looked at. The held-out blocks (37000-40999) must
NOT be run while the monitor's rules are being changed, nor by whoever built this benchmark: each
is for the evaluation of a change, once. 36500-36799 and 37000-39789 are spent (every seed
evaluated a change, or was started to); the next evaluation starts at 39790.

Run: python benchmarks/bench_machines.py --cases 100 --out dev.jsonl [--shard 1/2]
     python benchmarks/bench_machines.py --report dev.jsonl [--markdown]
     python benchmarks/bench_machines.py --named [--out named.jsonl]
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
from _machines import (  # noqa: E402
    TOLERANCE_C,
    Case,
    Room,
    build_plant,
    draw_case,
    finish_case,
    simulate,
)

from mtident.io.logs import TemperatureLog  # noqa: E402
from mtident.testing.warmups import _network  # noqa: E402
from mtident.thermal.monitor import MonitorSettings, monitor_step, new_state, result  # noqa: E402
from mtident.thermal.reference import MachineReference  # noqa: E402
from mtident.thermal.reference_learning import learn_reference  # noqa: E402
from mtident.thermal.robust_types import ends_at_the_largest  # noqa: E402

FIRST_SEED = 36000
HELD_OUT = range(37000, 41000)
KEYS = ("without_reference", "with_reference")
MAX_TAU_MIN = 300.0  # RobustSettings' default largest time constant


def learnt_reference(case: Case, seed: int) -> tuple[MachineReference | None, list[str], float]:
    """The reference learnt from the case's reference run (with its room sensor)."""
    run = simulate(case, np.random.default_rng(seed + 10_000_000), "reference")
    log = TemperatureLog(run.time_min, case.plant.sensors, run.reading_C, (), "reference")
    started = time.perf_counter()
    with np.errstate(all="ignore"):
        learnt, warnings = learn_reference(log, run.room_reading_C)
    seconds = time.perf_counter() - started
    return (learnt if learnt.sensors else None), warnings, seconds


def replay(case: Case, run, reference: MachineReference | None) -> dict[str, object]:  # noqa: ANN001
    """The monitor over the whole test log, the room sensor as its ambient input."""
    sensors = list(case.plant.sensors)
    settings = MonitorSettings(tolerance_C=TOLERANCE_C, reference=reference, room_sensor="room")
    state = new_state(sensors, with_room=True)
    started = time.perf_counter()
    with np.errstate(all="ignore"):
        state, _ = monitor_step(state, run.time_min, run.reading_C, run.room_reading_C, settings)
        answer = result(state, settings)
    seconds = time.perf_counter() - started
    stopped = state.stopped
    at = state.stop_time_min if stopped else float(run.time_min[-1])
    k = min(int(np.searchsorted(run.time_min, at - 1e-9)), len(run.time_min) - 1)
    truth = run.truth_C[k]
    per = []
    for s, check in enumerate(state.checks):
        err = check.steady_C - truth[s]
        per.append(
            {
                "sensor": check.sensor,
                "status": check.status,
                "settle_min": case.sensor_settle_min[s],
                "ready_since_min": check.ready_since_min if math.isfinite(check.ready_since_min) else None,
                "steady_C": check.steady_C if math.isfinite(check.steady_C) else None,
                "truth_C": float(truth[s]),
                "error_C": float(err) if math.isfinite(err) else None,
                "low95_C": check.low95_C if math.isfinite(check.low95_C) else None,
                "high95_C": check.high95_C if math.isfinite(check.high95_C) else None,
                "covered95": bool(check.low95_C <= truth[s] <= check.high95_C),
                "half_width_C": check.half_width_C if math.isfinite(check.half_width_C) else None,
                "taus": [round(tau, 2) for tau, _ in check.modes],
                "amplitudes": [round(a, 3) for _, a in check.modes],
                "model_ok": check.model_ok,
                "reference_used": check.reference_used,
                "machine_used": check.machine_used,
                "ends": check.ends[:300],
                "warnings": [w[:200] for w in check.warnings],
            }
        )
    errors = [abs(p["error_C"]) for p in per if p["error_C"] is not None]
    return {
        "seconds": seconds,
        "stopped": stopped,
        "stop_min": state.stop_time_min if stopped else None,
        "last_min": float(run.time_min[-1]),
        "worst_error_C": max(errors) if errors else None,
        "beyond": stopped and any(e > TOLERANCE_C for e in errors),
        "sensors_beyond": sum(e > TOLERANCE_C for e in errors) if stopped else None,
        "covered95": [p["covered95"] for p in per],
        "reason": None if stopped else str(answer.get("reason"))[:1500],
        "holding": [p["sensor"] for p in per if p["status"] != "may stop"],
        "sensors": per,
    }


def describe(case: Case) -> dict[str, object]:
    plant = case.plant
    return {
        "seed": case.seed,
        **case.family,
        "description": plant.description,
        "sensor_where": list(plant.sensor_where),
        "sensor_lags_min": list(plant.sensor_lags_min),
        "time_constants_min": [round(t, 3) for t in plant.time_constants_min[:6]],
        "room_desc": case.room.describe(),
        "ref_room": case.ref_room.describe(),
        "test_power": case.test_power,
        "test_split": case.test_split.tolist(),
        "ref_split": case.ref_split.tolist(),
        "warm_fraction": case.warm_fraction,
        "interval_min": case.interval_min,
        "noise_C": case.noise_C.tolist(),
        "t_settle_min": case.t_settle_min if math.isfinite(case.t_settle_min) else None,
        "t_settle_steady_min": case.t_settle_steady_min,
        "t_settle_used_min": case.t_settle_min if math.isfinite(case.t_settle_min) else case.t_settle_steady_min,
        "settle_basis": "as run" if math.isfinite(case.t_settle_min) else "steady-room version",
        "test_min": case.test_min,
        "ref_min": case.ref_min,
        "ref_interval_min": case.ref_interval_min,
    }


def run_case(case: Case, seed: int, without: bool = True, learn: bool = True) -> dict[str, object]:
    out = describe(case)
    run = simulate(case, np.random.default_rng(seed + 20_000_000), "test")
    out["log_reaches_settle"] = bool(run.time_min[-1] >= out["t_settle_used_min"])
    reference, warnings, learn_s = learnt_reference(case, seed) if learn else (None, [], 0.0)
    out["learn_seconds"] = learn_s
    out["reference_warnings"] = [w[:300] for w in warnings]
    out["reference_taus"] = (
        None
        if reference is None
        else {name: [round(t, 2) for t in m.time_constants_min] for name, m in reference.sensors.items()}
    )
    out["reference_doubts"] = (
        None if reference is None else [name for name, m in reference.sensors.items() if m.doubt is not None]
    )
    out["without_reference"] = replay(case, run, None) if without else None
    out["with_reference"] = replay(case, run, reference) if reference is not None else None
    return out


# ----------------------------------------------------------------------------------------------
# Named cases


def papers_curve() -> Case:
    """One sensor, first order τ 59 min, 8.85 °C rise, σ 0.01, 1-min sampling, 400 min, a steady
    logged room (its reference is drawn but not asked for)."""
    A = np.array([[-1.0 / 59.0]])
    capacity = np.array([1.0])
    convection = np.array([1.0 / 59.0])
    patterns = np.array([[8.85 / 59.0]])
    plant = build_plant(
        "network", A, capacity, convection, patterns, [np.array([1.0])], [0.0], ["node 0"], "first order"
    )
    room = Room("steady", 20.0, noise_C=0.005, rounding_C=0.01)
    return finish_case(
        -1,
        plant,
        1.0,
        np.array([1.0]),
        1.0,
        np.array([1.0]),
        0.0,
        room,
        room,
        1.0,
        np.array([0.01]),
        np.array([0.01]),
        test_min=400.0,
    )


def machining_centre() -> Case:
    """A vertical machining centre: a 4-node network (4, 35, 110, 260 min), a PT100 in a sleeve
    (1.5 min lag), six sensors and a room sensor; reference at 8000 rpm (power 1.0), test at
    6000 rpm (power 0.7, split changed), 15 % warm, daily room ±0.4 °C logged, 480 min."""
    rng = np.random.default_rng(8000)
    A, capacity, convection, _ = _network(rng, 4, np.array([260.0, 110.0, 35.0, 4.0]))
    per_node = np.linalg.solve(-A, np.eye(4) / capacity[:, None])
    # two sources: the spindle bearings (node of largest rise from node 0) and the motor
    patterns = np.zeros((4, 2))
    patterns[0, 0] = 1.0
    patterns[2, 1] = 1.0
    ref_split = np.array([0.65, 0.35])
    rise = (per_node @ patterns) @ ref_split
    patterns *= 12.0 / rise.max()
    rows = [np.eye(4)[i] for i in range(4)]
    rows += [np.array([0.0, 0.6, 0.4, 0.0]), np.eye(4)[0]]
    lags = [0.0, 0.0, 0.0, 0.0, 0.0, 1.5]
    where = ["node 0", "node 1", "node 2", "node 3", "0.6·node 1 + 0.4·node 2", "node 0 (PT100 sleeve)"]
    plant = build_plant("network", A, capacity, convection, patterns, rows, lags, where, "VMC 4 nodes 260/110/35/4")
    room = Room("daily", 21.0, amplitude_C=0.4, phase_rad=1.0, noise_C=0.01, rounding_C=0.01)
    ref_room = Room("steady", 21.0, noise_C=0.01, rounding_C=0.01)
    test_split = np.array([0.55, 0.45])
    noise = np.array([0.01, 0.015, 0.01, 0.02, 0.01, 0.01])
    return finish_case(
        -2, plant, 1.0, ref_split, 0.7, test_split, 0.15, room, ref_room, 0.5, noise, noise, test_min=480.0
    )


def run_named() -> list[dict[str, object]]:
    out = []
    for name, case, with_ref in (
        ("papers' curve", papers_curve(), False),
        ("machining centre", machining_centre(), True),
    ):
        started = time.perf_counter()
        run = simulate(case, np.random.default_rng(1), "test")
        row = describe(case)
        row["name"] = name
        row["without_reference"] = replay(case, run, None)
        if with_ref:
            reference, warnings, _ = learnt_reference(case, 1)
            row["reference_taus"] = (
                None if reference is None else {n: list(m.time_constants_min) for n, m in reference.sensors.items()}
            )
            row["reference_boxes"] = (
                None if reference is None else {n: list(m.box) for n, m in reference.sensors.items()}
            )
            row["reference_warnings"] = warnings
            row["with_reference"] = replay(case, run, reference) if reference is not None else None
        row["case_seconds"] = time.perf_counter() - started
        out.append(row)
    return out


# ----------------------------------------------------------------------------------------------
# Report


def _block(cases: list[dict], key: str) -> dict[str, object]:
    runs = [c for c in cases if c.get(key)]
    reach = [c for c in runs if c["log_reaches_settle"]]
    stops = [c for c in runs if c[key]["stopped"]]
    ratio = np.array([c[key]["stop_min"] / max(c["t_settle_used_min"], 1e-9) for c in stops])
    covered = [v for c in stops for v in c[key]["covered95"]]
    return {
        "cases": len(runs),
        "stopped": len(stops),
        "share_stopped_reaching_settle": float(np.mean([c[key]["stopped"] for c in reach])) if reach else None,
        "reaching_settle": len(reach),
        "beyond": sum(bool(c[key]["beyond"]) for c in stops),
        "beyond_seeds": [c["seed"] for c in stops if c[key]["beyond"]],
        "worst_error_C": max((c[key]["worst_error_C"] or 0 for c in stops), default=None),
        "covered95_at_stop": float(np.mean(covered)) if covered else None,
        "median_stop_over_settle": float(np.median(ratio)) if len(ratio) else None,
        "p90_stop_over_settle": float(np.percentile(ratio, 90)) if len(ratio) else None,
        "median_seconds": float(np.median([c[key]["seconds"] for c in runs])) if runs else None,
        "machine_model_used_share": float(
            np.mean([bool(p.get("machine_used")) for c in runs for p in c[key]["sensors"]])
        )
        if runs
        else None,
    }


def holding(cases: list[dict], key: str) -> dict[str, int]:
    """Why the tests that did not stop did not: each waiting sensor by what sets its interval's
    ends (a mode at the largest time constant searched, or a faster one), and whether the
    reference run left it doubtful (its modes then unused)."""
    out: dict[str, int] = {}
    for c in cases:
        r = c.get(key)
        if not r or r["stopped"]:
            continue
        for p in r["sensors"]:
            if p["status"] == "may stop":
                continue
            end = "slowest-searched mode still fits" if ends_at_the_largest(p["ends"], MAX_TAU_MIN) else "faster mode"
            doubtful = key == "with_reference" and p["sensor"] in (c.get("reference_doubts") or [])
            label = f"{p['status']}, {end}" + (", reference doubtful" if doubtful else "")
            out[label] = out.get(label, 0) + 1
    return dict(sorted(out.items(), key=lambda kv: -kv[1]))


def families(cases: list[dict]) -> list[tuple[str, list[dict]]]:
    out = [("all", cases)]
    for field, values in (
        ("kind", ("network", "conduction")),
        ("room", ("steady", "daily", "drift")),
        ("start", ("cold", "warm")),
    ):
        out += [(f"{field}={v}", [c for c in cases if c[field] == v]) for v in values]
    return out


def report(paths: list[Path]) -> dict[str, object]:
    cases = [json.loads(line) for path in paths for line in path.read_text().splitlines() if line.strip()]
    cases = [c for c in cases if c.get("seed", 0) >= 0]
    out: dict[str, object] = {
        "cases": len(cases),
        "seeds": [min(c["seed"] for c in cases), max(c["seed"] for c in cases)] if cases else None,
        "median_case_seconds": float(np.median([c["case_seconds"] for c in cases])) if cases else None,
    }
    for name, chosen in families(cases):
        out[name] = {"cases": len(chosen), **{key: _block(chosen, key) for key in KEYS}}
    out["holding sensors of tests not stopped"] = {key: holding(cases, key) for key in KEYS}
    return out


def markdown(summary: dict[str, object]) -> str:
    lines = [
        f"{summary['cases']} machines, seeds {summary['seeds']}, tolerance {TOLERANCE_C} °C, "
        f"median {summary['median_case_seconds']:.0f} s a case.",
        "",
        "| family | reference | stopped (share of logs reaching t_settle) | beyond tolerance (worst °C) | "
        "95 % covers at stop | stop/t_settle median (p90) |",
        "|---|---|---|---|---|---|",
    ]
    for name, block in summary.items():
        if not isinstance(block, dict) or name.startswith("holding"):
            continue
        for key in KEYS:
            r = block[key]
            if not r["cases"]:
                continue
            share = (
                "—"
                if r["share_stopped_reaching_settle"] is None
                else f"{100 * r['share_stopped_reaching_settle']:.0f} %"
            )
            worst = "—" if r["worst_error_C"] is None else f"{r['worst_error_C']:.3f}"
            cov = "—" if r["covered95_at_stop"] is None else f"{100 * r['covered95_at_stop']:.1f} %"
            med = (
                "—"
                if r["median_stop_over_settle"] is None
                else f"{r['median_stop_over_settle']:.2f} ({r['p90_stop_over_settle']:.2f})"
            )
            lines.append(
                f"| {name} ({r['cases']}) | {'learnt' if key == 'with_reference' else 'none'} | "
                f"{r['stopped']} ({share} of {r['reaching_settle']}) | {r['beyond']} ({worst}) | {cov} | {med} |"
            )
    lines += ["", "Sensors that held the tests that did not stop (status, what sets the interval's ends):"]
    for key, counts in summary["holding sensors of tests not stopped"].items():  # type: ignore[union-attr]
        lines.append(f"- {key}: " + "; ".join(f"{v} {k}" for k, v in counts.items()))
    return "\n".join(lines)


def main() -> None:
    parser = seeded_run_parser(__doc__.splitlines()[0], 100, FIRST_SEED, "machines.jsonl")
    parser.add_argument("--markdown", action="store_true", help="with --report: Markdown tables instead of JSON")
    parser.add_argument("--named", action="store_true", help="run the two named cases and stop")
    parser.add_argument(
        "--with-reference-only",
        action="store_true",
        help="replay each test with its reference only (the path a change to the reference's use affects)",
    )
    parser.add_argument(
        "--without-reference-only",
        action="store_true",
        help="replay each test without a reference only, learning none (the path a change to the fit alone affects)",
    )
    args = parser.parse_args()
    if args.report:
        summary = report(args.report)
        print(markdown(summary) if args.markdown else json.dumps(summary, indent=2))
        return
    if args.named:
        for row in run_named():
            with args.out.open("a") as out:
                out.write(json.dumps(row, default=float) + "\n")
            print(json.dumps(row, default=float)[:3000], flush=True)
        return

    def run_one(seed: int) -> dict[str, object]:
        if seed in HELD_OUT:
            print(f"seed {seed} is in the held-out block 37000-40999: run only to evaluate a change, once", flush=True)
        case = draw_case(seed)
        return run_case(case, seed, not args.with_reference_only, not args.without_reference_only)

    run_seeds(args, run_one)


if __name__ == "__main__":
    main()
