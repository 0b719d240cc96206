"""Live monitor evidence: replay warm-ups and report when the rule stops and how far off T∞ is then.

Cases: the shipped sample log (10 sensors), first-order curves like the papers'
(σ = 0.02 °C), the same with ambient drift, fast-plus-slow curves, and a log
with bad data (spike, dropout, gap, a sensor that never heats). Also the replay
time of the 10-sensor, 400-sample log.

Run: python benchmarks/bench_watch.py
"""

from __future__ import annotations

import time

import numpy as np

from mtident.cli_thermal import sample_log_path
from mtident.io import read_temperature_log
from mtident.thermal.monitor import Monitor, MonitorSettings

TOLERANCE = 0.2
T = np.arange(0.0, 401.0)


def equilibrium_of(curve: np.ndarray) -> float:
    """95 % of the rise from the start to the curve's value at 2,000 min."""
    start, final = curve[0], curve[-1]
    return float(T_LONG[np.argmax(curve >= start + 0.95 * (final - start))])


T_LONG = np.arange(0.0, 2001.0)


def run_case(name: str, clean_long: np.ndarray, noisy: np.ndarray, ambient=None, room_sensor=None) -> tuple[str, float | None, float, float]:  # noqa: ANN001
    """Replay one sensor; return (name, stop time, equilibrium time, |T∞ error| at stop).

    The truth is the curve's value at 2,000 min; with a drifting room (``ambient``
    given as a function of time), the warm-up's own steady state plus the room's
    offset at the stop time: the temperature the machine settles to if the room
    stays as it is then.
    """
    monitor = Monitor(("S",), MonitorSettings(tolerance_C=TOLERANCE))
    monitor.feed(T, noisy[:, None], room_sensor)
    result = monitor.result()
    truth = clean_long[-1]
    if ambient is not None and result["stop_time_min"] is not None:
        truth = clean_long[-1] - ambient(T_LONG[-1]) + ambient(result["stop_time_min"])
    error = abs(result["steady_state_C"] - truth) if result["steady_state_C"] is not None else float("nan")  # type: ignore[operator]
    return name, result["stop_time_min"], equilibrium_of(clean_long), error  # type: ignore[return-value]


def room(t: np.ndarray | float) -> np.ndarray | float:
    """Ambient offset: a 0.15 °C air-conditioning cycle of 4 h on a 0.1 °C slow rise."""
    return 0.15 * np.sin(2 * np.pi * np.asarray(t) / 240.0) + 0.1 * (1 - np.exp(-np.asarray(t) / 200.0))


def families(count: int) -> dict[str, list[tuple[str, float | None, float, float]]]:
    """``count`` seeded replays of each kind of warm-up."""
    out: dict[str, list[tuple[str, float | None, float, float]]] = {"first-order": [], "drift, no room sensor": [], "drift + --ambient": [], "fast+slow": []}
    first_order = 26.7 - 8.8 * np.exp(-0.016 * T_LONG)
    fast_slow = 17.9 + 4.0 * (1 - np.exp(-T_LONG / 8.0)) + 6.0 * (1 - np.exp(-T_LONG / 150.0))
    drifting = first_order + room(T_LONG)
    for seed in range(count):
        rng = np.random.default_rng(seed)
        out["first-order"].append(run_case(f"first-order #{seed}", first_order, first_order[:401] + 0.02 * rng.standard_normal(401)))
        noisy = drifting[:401] + 0.02 * rng.standard_normal(401)
        out["drift, no room sensor"].append(run_case(f"drift #{seed}", drifting, noisy, room))
        room_sensor = 17.9 + room(T) + 0.02 * rng.standard_normal(401)
        out["drift + --ambient"].append(run_case(f"drift+ambient #{seed}", drifting, noisy, room, room_sensor))
        out["fast+slow"].append(run_case(f"fast+slow #{seed}", fast_slow, fast_slow[:401] + 0.02 * rng.standard_normal(401)))
    return out


def main() -> None:
    count = 20
    print(f"Replays of {count} seeded warm-ups of each kind, σ = 0.02 °C, 1-min samples, tolerance {TOLERANCE} °C.")
    print("error = |T∞ at the stop − the curve's value at 2,000 min|; with a drifting room, the steady state under the room's offset at the stop.")
    print(f"{'kind':>22} {'stopped':>8} {'stop/t_eq median':>17} {'max':>6} {'max error °C':>13} {'error > tol':>12}")
    for kind, rows in families(count).items():
        fractions = np.array([stop / eq for _, stop, eq, _ in rows if stop is not None])
        errors = np.array([error for _, stop, _, error in rows if stop is not None])
        print(f"{kind:>22} {len(fractions):>5}/{len(rows):<2} {np.median(fractions):17.2f} {fractions.max():6.2f} {errors.max():13.3f} {int(np.sum(errors > TOLERANCE)):>12}")

    log = read_temperature_log(sample_log_path())
    start = time.perf_counter()
    monitor = Monitor(log.sensors, MonitorSettings(tolerance_C=TOLERANCE))
    monitor.feed(log.time_min, log.temperature_C)
    elapsed = time.perf_counter() - start
    result = monitor.result()
    print(f"\nSample log (10 sensors, 400 samples): replay {elapsed:.2f} s; stop at {result['stop_time_min']} min")
    print(f"{'sensor':>7} {'T∞ at stop':>11} {'±':>6} {'final at 400 min':>17} {'difference':>11}")
    for i, d in enumerate(result["sensors"]):  # type: ignore[arg-type]
        final = float(np.median(log.temperature_C[-10:, i]))
        lo, hi = d["steady_state_ci95_C"]
        print(f"{d['sensor']:>7} {d['steady_state_C']:11.2f} {(hi - lo) / 2:6.2f} {final:17.2f} {d['steady_state_C'] - final:11.2f}")

    rng = np.random.default_rng(7)
    curve = 26.7 - 8.8 * np.exp(-0.016 * T)
    bad = np.column_stack([curve + 0.02 * rng.standard_normal(401), np.full(401, 20.0) + 0.02 * rng.standard_normal(401)])
    bad[30, 0] = 35.0  # spike
    bad[40:43, 0] = np.nan  # dropout
    bad[44, 0] = np.nan  # an open circuit (the log reader turns > 400 °C into NaN)
    keep = np.ones(401, dtype=bool)
    keep[50:60] = False  # a 10-min gap
    monitor = Monitor(("heating", "cold"), MonitorSettings(tolerance_C=TOLERANCE))
    messages = monitor.feed(T[keep], bad[keep])
    result = monitor.result()
    print(f"\nBad data (spike at 30, dropout 40-42, open circuit at 44, gap 50-60, one sensor never heats): stop at {result['stop_time_min']} min")
    for d in result["sensors"]:  # type: ignore[union-attr]
        print(f"  {d['sensor']}: T∞ {d['steady_state_C']}, status {d['status']}")
    kinds = {"spike": "spike", "no valid reading": "dropout", "gap": "gap", "no longer fit": "model check"}
    for key, label in kinds.items():
        print(f"  {label}: {sum(key in m for m in messages)} message(s)")


if __name__ == "__main__":
    main()
