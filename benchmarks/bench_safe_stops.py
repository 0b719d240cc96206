"""Safe stops on many warm-ups: the monitor and identify on a seeded population nobody shaped.

Each case is a random warm-up of :func:`mtident.testing.warmups.random_warmup` (lumped networks
of 1-4 nodes and conduction bodies, time constants 2-300 min, sensor lags, partly warm starts,
drifting rooms with a room sensor, sampling 1 s-5 min, noise 0.005-0.05 °C, rounding
0.01-0.32 °C). Per case:

* the monitor replayed without a reference, and with a reference learnt from another run of the
  same machine (:func:`~mtident.testing.warmups.reference_run`, at another power): the stop,
  T∞'s error there against the truth (the equilibrium at the room's level at the stop), and
  whether the 95 % interval covers it;
* ``identify`` (model-robust, and the papers' first-order UKF) at fixed fractions of t95: the 95 %
  interval's coverage, its width, and ``model_ok``.

Cases are split into near-first-order (one mode ≥ 97 % of the rise) and multi-mode. Results go to
a JSON-lines file, one case a line, so a long run can be resumed and several can run at once
(``--shard K/N``); ``--report`` summarises a file.

The seeds used while the rules were tuned are 0-299 (the global search checked against brute
force, the misfit threshold). Seeds 1000-1008 and 2000-2417 were evaluation runs of earlier
rules; their failures were looked at (a conduction body's far sensor fitted with false
confidence; fast transients taking the place of a slow mode in a three-mode family) and the
rules changed, so they are no longer held out. The default seeds (3000 on) were never looked at
before this benchmark ran; 3000-3499, 4000-4299, 5000-5299, 6000-6499 and 8000-8199 have been
since (the commit messages of docs/results.md say which rules each measured).

Run: python benchmarks/bench_safe_stops.py --cases 500 --out results.jsonl [--shard 1/2]
     python benchmarks/bench_safe_stops.py --report results.jsonl
"""

from __future__ import annotations

import json
import sys
import time
import warnings
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from _common import run_seeds, seeded_run_parser  # noqa: E402

from mtident.io.logs import TemperatureLog  # noqa: E402
from mtident.testing.warmups import modal_amplitudes, random_warmup, reference_run  # noqa: E402
from mtident.thermal.identify import identify  # noqa: E402
from mtident.thermal.monitor import MonitorSettings, monitor_step, new_state  # noqa: E402
from mtident.thermal.reference import MachineReference  # noqa: E402
from mtident.thermal.reference_learning import learn_reference  # noqa: E402
from mtident.thermal.robust import RobustSettings  # noqa: E402
from mtident.thermal.robust_identify import identify_robust  # noqa: E402

TOLERANCE_C = 0.2
FRACTIONS = (0.25, 0.5)
NEAR_FIRST_ORDER_SHARE = 0.97
FIRST_SEED = 3000
# the monitor's replays: the results' key, and the reference column of the report
STATED = {
    "without_reference": "none",
    "with_reference": "learnt",
    "with_reference_steady_room": "learnt, steady room said",
    "with_reference_every_mode": "learnt, every mode and steady room said",
}


def _log(t: np.ndarray, y: np.ndarray, name: str) -> TemperatureLog:
    return TemperatureLog(t, ("S",), y[:, None], (), name)


def _replay(warm, reference, **said: object) -> dict[str, object]:  # noqa: ANN001
    """The monitor replayed on the case; ``said``: MonitorSettings fields besides the defaults."""
    room = warm.room_C
    settings = MonitorSettings(
        tolerance_C=TOLERANCE_C,
        reference=reference,
        room_sensor="room" if room is not None else None,
        **said,  # type: ignore[arg-type]
    )
    state = new_state(["S"], with_room=room is not None)
    started = time.perf_counter()
    state, _ = monitor_step(state, warm.time_min, warm.reading_C[:, None], room, settings)
    seconds = time.perf_counter() - started
    check = state.checks[0]
    out: dict[str, object] = {"seconds": seconds, "stopped": state.stopped, "last_min": float(warm.time_min[-1])}
    at = state.stop_time_min if state.stopped else float(warm.time_min[-1])
    truth = float(
        warm.steady_C[int(np.searchsorted(warm.time_min, at))] if at < warm.time_min[-1] else warm.steady_C[-1]
    )
    out.update(
        stop_min=state.stop_time_min if state.stopped else None,
        error_C=check.steady_C - truth,
        covered95=bool(check.low95_C <= truth <= check.high95_C),
        covered_decision=bool(check.low_C <= truth <= check.high_C),
        half_width_C=check.half_width_C,
        reference_used=check.reference_used,
        status=check.status,
    )
    return out


def _identify_at(warm, fraction: float, reference) -> dict[str, object]:  # noqa: ANN001
    window = fraction * warm.t95_min
    if np.searchsorted(warm.time_min, window) < 8:
        return {}
    log = _log(warm.time_min, warm.reading_C, "case")
    n = int(np.searchsorted(warm.time_min, window, side="right"))
    truth = float(warm.steady_C[n - 1])
    out: dict[str, object] = {}
    robust = identify_robust(
        log, window, warm.room_C, reference=reference, room_sensor="room" if warm.room_C is not None else None
    )
    lo, hi = robust.steady_state_ci95_C[0]
    out["robust"] = {
        "covered": bool(lo <= truth <= hi),
        "half_width_C": float((hi - lo) / 2),
        "error_C": float(robust.steady_state_C[0] - truth),
        "model_ok": bool(robust.model_ok[0]),
    }
    if reference is None:
        with warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            try:
                first = identify(log, window, "ukf", ambient_C=warm.room_C)
                flo, fhi = first.steady_state_ci95_C[0]
                out["first_order"] = {
                    "covered": bool(flo <= truth <= fhi),
                    "half_width_C": float((fhi - flo) / 2),
                    "error_C": float(first.steady_state_C[0] - truth),
                    "model_ok": bool(first.summary(0)["model_ok"]),
                }
            except Exception as exc:  # noqa: BLE001 - the peer's failure is a result too
                out["first_order"] = {"failed": str(exc)[:200]}
    return out


def learnt_reference(seed: int, machine) -> MachineReference | None:  # noqa: ANN001
    """The reference learnt from another complete run of the case's machine (at another power),
    None where it kept no sensor."""
    ref_run = reference_run(machine, np.random.default_rng(seed + 10_000_000))
    with np.errstate(all="ignore"):
        learnt, _ = learn_reference(_log(ref_run.time_min, ref_run.reading_C, "reference"))
    return learnt if learnt.sensors else None


def near_first_order(machine, warm) -> tuple[bool, float]:  # noqa: ANN001
    """Whether one mode holds at least ``NEAR_FIRST_ORDER_SHARE`` of the rise, and its share."""
    _, amplitudes = modal_amplitudes(machine, warm)
    share = float(np.max(np.abs(amplitudes)) / max(np.sum(np.abs(amplitudes)), 1e-12))
    return share >= NEAR_FIRST_ORDER_SHARE, share


def run_case(seed: int, only: str | None = None, stated: bool = False) -> dict[str, object]:
    """One case; ``only`` ("without" or "with") replays the monitor without or with a learnt
    reference alone, and skips ``identify``; ``stated``: also with the reference under the
    assumptions a user may state (:data:`STATED`)."""
    rng = np.random.default_rng(seed)
    warm = random_warmup(rng)
    machine = warm.machine
    taus, _ = modal_amplitudes(machine, warm)
    near, share = near_first_order(machine, warm)
    reference = learnt_reference(seed, machine) if only != "without" else None
    case: dict[str, object] = {
        "seed": seed,
        "kind": machine.kind,
        "description": machine.description,
        "t95_min": warm.t95_min,
        "interval_min": warm.interval_min,
        "noise_C": warm.noise_C,
        "rounding_C": warm.rounding_C,
        "room_sensor": warm.room_C is not None,
        "near_first_order": near,
        "largest_mode_share": share,
        "reference_taus": None if reference is None else list(reference.sensors["S"].time_constants_min),
        "true_taus": [float(t) for t in taus[:4]],
    }
    case["without_reference"] = _replay(warm, None) if only != "with" else None
    case["with_reference"] = _replay(warm, reference) if reference is not None else None
    if stated and reference is not None:
        steady = RobustSettings(room_wander_C_per_h=0.0)
        # a steady room is true of every case without a room sensor; with one, the room is measured
        case["with_reference_steady_room"] = _replay(warm, reference, robust=steady) if warm.room_C is None else None
        case["with_reference_every_mode"] = _replay(warm, reference.holding_every_mode(), robust=steady)
    if only is not None:
        return case
    for fraction in FRACTIONS:
        case[f"identify_{fraction}"] = _identify_at(warm, fraction, None)
        if reference is not None:
            case[f"identify_ref_{fraction}"] = _identify_at(warm, fraction, reference)
    return case


def _summary(cases: list[dict], key: str) -> dict[str, object]:
    runs = [c for c in cases if c.get(key)]
    stops = [c for c in runs if c[key]["stopped"]]
    ratio = np.array([c[key]["stop_min"] / c["t95_min"] for c in stops])
    beyond = [c for c in stops if abs(c[key]["error_C"]) > TOLERANCE_C]
    return {
        "cases": len(runs),
        "stopped": len(stops),
        "beyond_tolerance": len(beyond),
        "worst_error_C": max((abs(c[key]["error_C"]) for c in stops), default=None),
        "beyond_seeds": [c["seed"] for c in beyond],
        "covered95_at_stop": float(np.mean([c[key]["covered95"] for c in stops])) if stops else None,
        "median_stop_over_t95": float(np.median(ratio)) if len(ratio) else None,
        "p90_stop_over_t95": float(np.percentile(ratio, 90)) if len(ratio) else None,
        "stopped_within_1.5_t95": float(
            np.mean([c[key]["stopped"] and c[key]["stop_min"] <= 1.5 * c["t95_min"] for c in runs])
        )
        if runs
        else None,
        "median_seconds": float(np.median([c[key]["seconds"] for c in runs])) if runs else None,
    }


def _identify_summary(cases: list[dict], key: str, method: str) -> dict[str, object]:
    rows = [c[key][method] for c in cases if c.get(key) and method in c[key] and "covered" in c[key][method]]
    if not rows:
        return {}
    trusted = [r for r in rows if r["model_ok"]]
    return {
        "cases": len(rows),
        "covered95": float(np.mean([r["covered"] for r in rows])),
        "median_half_width_C": float(np.median([r["half_width_C"] for r in rows])),
        "model_ok": len(trusted),
        "missed_with_model_ok": sum(not r["covered"] for r in trusted),
        "covered95_when_model_ok": float(np.mean([r["covered"] for r in trusted])) if trusted else None,
    }


def report(paths: list[Path]) -> dict[str, object]:
    cases = [json.loads(line) for path in paths for line in path.read_text().splitlines() if line.strip()]
    out: dict[str, object] = {
        "cases": len(cases),
        "seeds": [min(c["seed"] for c in cases), max(c["seed"] for c in cases)] if cases else None,
    }
    for group, chosen in (
        ("near first order", [c for c in cases if c["near_first_order"]]),
        ("multi-mode", [c for c in cases if not c["near_first_order"]]),
        ("reference of one mode", [c for c in cases if c["reference_taus"] and len(c["reference_taus"]) == 1]),
        ("no room sensor", [c for c in cases if not c["room_sensor"]]),
        ("all", cases),
    ):
        block: dict[str, object] = {"cases": len(chosen)}
        for key in STATED:
            block[key] = _summary(chosen, key)
        for fraction in FRACTIONS:
            block[f"identify at {fraction} t95, robust"] = _identify_summary(chosen, f"identify_{fraction}", "robust")
            block[f"identify at {fraction} t95, first-order UKF"] = _identify_summary(
                chosen, f"identify_{fraction}", "first_order"
            )
            block[f"identify at {fraction} t95, robust with reference"] = _identify_summary(
                chosen, f"identify_ref_{fraction}", "robust"
            )
        out[group] = block
    return out


def _width(value: float) -> str:
    """A median half-width, or a dash where most intervals were infinite (no median to give)."""
    return f"{value:.3g}" if np.isfinite(value) else "—"


def markdown(summary: dict[str, object]) -> str:
    """The report as Markdown tables: the monitor's stops, then identify's intervals."""
    lines = [
        f"{summary['cases']} warm-ups, seeds {summary['seeds'][0]}-{summary['seeds'][1]}, tolerance {TOLERANCE_C} °C.",
        "",
    ]  # type: ignore[index]
    lines += [
        "| cases | reference | stopped | beyond tolerance (worst °C) | 95 % covers at stop | stop/t95 median (p90) | "
        "stopped within 1.5·t95 |",
        "|---|---|---|---|---|---|---|",
    ]
    for group in ("near first order", "multi-mode", "reference of one mode", "no room sensor", "all"):
        block = summary[group]
        assert isinstance(block, dict)
        for key, label in STATED.items():
            r = block[key]
            if not r["cases"]:
                continue
            worst = "—" if r["worst_error_C"] is None else f"{r['worst_error_C']:.3f}"
            median = (
                "—"
                if r["median_stop_over_t95"] is None
                else f"{r['median_stop_over_t95']:.2f} ({r['p90_stop_over_t95']:.2f})"
            )
            covered = "—" if r["covered95_at_stop"] is None else f"{100 * r['covered95_at_stop']:.1f} %"
            within = "—" if r["stopped_within_1.5_t95"] is None else f"{100 * r['stopped_within_1.5_t95']:.0f} %"
            lines.append(
                f"| {group} ({r['cases']}) | {label} | {r['stopped']} | {r['beyond_tolerance']} ({worst}) | {covered} "
                f"| {median} | {within} |"
            )
    lines += [
        "",
        "| cases | identify at | method | 95 % covers | median half-width °C | model_ok | misses with model_ok |",
        "|---|---|---|---|---|---|---|",
    ]
    for group in ("near first order", "multi-mode", "all"):
        block = summary[group]
        assert isinstance(block, dict)
        for fraction in FRACTIONS:
            for method in ("robust", "first-order UKF", "robust with reference"):
                r = block[f"identify at {fraction} t95, {method}"]
                if r:
                    lines.append(
                        f"| {group} | {fraction}·t95 | {method} | {100 * r['covered95']:.1f} % ({r['cases']}) | "
                        f"{_width(r['median_half_width_C'])} | {r['model_ok']} | {r['missed_with_model_ok']} |"
                    )
    return "\n".join(lines)


def main() -> None:
    parser = seeded_run_parser(__doc__.splitlines()[0], 500, FIRST_SEED, "safe_stops.jsonl")
    parser.add_argument("--markdown", action="store_true", help="with --report: Markdown tables instead of JSON")
    parser.add_argument(
        "--without-reference-only", action="store_true", help="replay the monitor without a reference alone"
    )
    parser.add_argument(
        "--with-reference-only", action="store_true", help="replay the monitor with a learnt reference alone"
    )
    parser.add_argument(
        "--stated-assumptions",
        action="store_true",
        help="also replay with the reference and a steady room said (where the case has no room sensor), and with "
        "the reference said to hold every mode as well",
    )
    args = parser.parse_args()
    if args.report:
        summary = report(args.report)
        print(markdown(summary) if args.markdown else json.dumps(summary, indent=2))
        return
    only = "without" if args.without_reference_only else "with" if args.with_reference_only else None
    run_seeds(args, lambda seed: run_case(seed, only, args.stated_assumptions))


if __name__ == "__main__":
    main()
