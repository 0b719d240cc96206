"""Live monitor evidence: replay warm-ups and report when the rule stops and how far off T∞ is then.

Cases: first-order curves like the papers' (σ = 0.02 °C), fast-plus-slow
curves, a drifting room (with and without a room sensor, felt by the machine
through its heat balance or at once), rooms that wander as the monitor assumes,
and the shipped sample log (10 sensors) with the replay's time. Every kind is
replayed without a reference and with one (the true time constants, ±10 %: a
reference run that learnt them).

Without a room sensor the monitor allows for an unmeasured room wandering by
0.05 °C in an hour (1σ, the default ``--room-wander``); the rows marked
"wander 0" take the room as steady, for comparison.

Run: python benchmarks/bench_watch.py [SEEDS]   (5 seeded replays per kind unless given)
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "scripts"))

import make_sample_warmup  # noqa: E402 - the sample's generator, for its true steady states

from mtident.io import read_temperature_log, sample_log_path  # noqa: E402
from mtident.io.logs import TemperatureLog  # noqa: E402
from mtident.thermal.monitor import MonitorSettings, monitor_step, new_state  # noqa: E402
from mtident.thermal.reference import MachineReference  # noqa: E402
from mtident.thermal.reference_learning import learn_reference  # noqa: E402
from mtident.thermal.robust import RobustSettings, SensorModes  # noqa: E402

TOLERANCE = 0.2
T = np.arange(0.0, 401.0)
T_1HZ = np.arange(0.0, 240.0, 1.0 / 60.0)


def equilibrium_of(curve: np.ndarray) -> float:
    """95 % of the rise from the start to the curve's value at 2,000 min."""
    start, final = curve[0], curve[-1]
    return float(T_LONG[np.argmax(curve >= start + 0.95 * (final - start))])


T_LONG = np.arange(0.0, 2001.0)


def run_case(
    name: str,
    clean_long: np.ndarray,
    noisy: np.ndarray,
    ambient=None,
    room_sensor=None,
    steady: float = 26.7,
    wander: float = 0.05,
    times: np.ndarray = T,
    taus: tuple[float, ...] | None = None,
) -> tuple[str, float | None, float, float]:  # noqa: ANN001
    """Replay one sensor; return (name, stop time, equilibrium time, |T∞ error| at stop).

    The truth is the curve's value at 2,000 min; with a drifting room (``ambient``
    given as a function of time), the steady state under the room's level at the
    stop, 17.9 °C + 8.8 °C + the room's offset: the temperature the machine
    settles to if the room stays as it is then. ``taus``: a reference of these
    time constants (±10 %).
    """
    reference = (
        None
        if taus is None
        else MachineReference("known", "", 300.0, "", {"S": SensorModes(taus, tuple(0.1 for _ in taus))})
    )
    settings = MonitorSettings(
        tolerance_C=TOLERANCE,
        robust=RobustSettings(room_wander_C_per_h=wander),
        reference=reference,
        room_sensor=None if room_sensor is None else "room",
    )
    state, _ = monitor_step(
        new_state(["S"], with_room=room_sensor is not None), times, noisy[:, None], room_sensor, settings
    )
    stop = state.stop_time_min if state.stopped else None
    truth = clean_long[-1]
    if ambient is not None and stop is not None:
        truth = steady + ambient(stop)
    error = abs(state.checks[0].steady_C - truth) if stop is not None else float("nan")
    return name, stop, equilibrium_of(clean_long), error


def room(t: np.ndarray | float) -> np.ndarray | float:
    """Ambient offset: a 0.15 °C air-conditioning cycle of 4 h on a 0.1 °C slow rise."""
    return 0.15 * np.sin(2 * np.pi * np.asarray(t) / 240.0) + 0.1 * (1 - np.exp(-np.asarray(t) / 200.0))


def machine_in_drifting_room(rate_per_min: float = 0.016, rise_C: float = 8.8) -> np.ndarray:
    """The papers' first-order heat balance with the room as its input, on ``T_LONG``.

    dT/dt = λ(T_room(t) + ΔT∞ − T): one heat capacity coupled to the room, so the
    machine follows the room's drift through its own time constant.
    """

    def rhs(t: float, T: np.ndarray) -> np.ndarray:
        return rate_per_min * (17.9 + room(t) + rise_C - T)

    solution = solve_ivp(rhs, (0.0, T_LONG[-1]), [17.9], t_eval=T_LONG, rtol=1e-10, atol=1e-10, max_step=1.0)
    return solution.y[0]


def machine_in_wandering_room(
    rng: np.random.Generator, sigma_C_per_h: float, rate_per_min: float = 0.016, rise_C: float = 8.8
):  # noqa: ANN201
    """The papers' heat balance in a room that is a random walk of ``sigma_C_per_h`` (1σ in an hour).

    The room the monitor assumes without a room sensor (``--room-wander``);
    returns the machine's curve on ``T_LONG`` and the room's offset as a
    function of time. Exact for a room held over each minute.
    """
    room_C = np.concatenate(
        [[0.0], np.cumsum(sigma_C_per_h * np.sqrt(1.0 / 60.0) * rng.standard_normal(len(T_LONG) - 1))]
    )
    decay = np.exp(-rate_per_min)
    curve = np.empty(len(T_LONG))
    curve[0] = 17.9
    for k in range(1, len(T_LONG)):
        curve[k] = decay * curve[k - 1] + (1 - decay) * (17.9 + rise_C + room_C[k - 1])
    return curve, lambda t: room_C[int(round(float(t)))]


def fast_slow_in_drifting_room() -> np.ndarray:
    """A fast part (4 °C, τ 8 min) on a slow part (6 °C, τ 150 min) that feels the room, on ``T_LONG``."""

    def rhs(t: float, T: np.ndarray) -> np.ndarray:
        fast, slow = T
        return np.array([(4.0 - fast) / 8.0, (17.9 + room(t) + 6.0 - slow) / 150.0])

    solution = solve_ivp(rhs, (0.0, T_LONG[-1]), [0.0, 17.9], t_eval=T_LONG, rtol=1e-10, atol=1e-10, max_step=1.0)
    return solution.y[0] + solution.y[1]


KINDS = {
    "first-order": (62.5,),
    "first-order, --room-wander 0": (62.5,),
    "first-order, begins 15 min late": (62.5,),
    "first-order, 0.1 °C display": (62.5,),
    "first-order, 1 Hz, 0.1 °C display": (62.5,),
    "first-order, 12.5 % dropouts": (62.5,),
    "fast+slow": (150.0, 8.0),
    "fast+slow, drift, --ambient": (150.0, 8.0),
    "fast+slow, drift, no sensor": (150.0, 8.0),
    "drift, no room sensor": (62.5,),
    "drift + --ambient": (62.5,),
    "drift at once, no sensor": (62.5,),
    "drift at once, --ambient": (62.5,),
    "room wanders 0.05/h, no sensor": (62.5,),
    "room wanders 0.1/h, no sensor": (62.5,),
    "room wanders 0.1/h, --room-wander 0.1": (62.5,),
}


def families(count: int, with_reference: bool) -> dict[str, list[tuple[str, float | None, float, float]]]:
    """``count`` seeded replays of each kind of warm-up, without or with a reference.

    "drift": the room cycles 0.15 °C every 4 h on a 0.1 °C rise and the machine
    follows it through its heat balance (:func:`machine_in_drifting_room`);
    "drift at once": a sensor that follows the room air without lag (the room's
    cycle added to the curve); "room wanders": the room is the random walk the
    monitor assumes without a room sensor (:func:`machine_in_wandering_room`), at
    the default's pace, at twice it, and at twice it with ``--room-wander`` saying so.
    """
    out: dict[str, list[tuple[str, float | None, float, float]]] = {kind: [] for kind in KINDS}

    def case(kind: str, *args, **kwargs) -> None:  # noqa: ANN002, ANN003
        out[kind].append(run_case(kind, *args, taus=KINDS[kind] if with_reference else None, **kwargs))

    first_order = 26.7 - 8.8 * np.exp(-0.016 * T_LONG)
    fast_slow = 17.9 + 4.0 * (1 - np.exp(-T_LONG / 8.0)) + 6.0 * (1 - np.exp(-T_LONG / 150.0))
    lagged = machine_in_drifting_room()
    fast_slow_drifting = fast_slow_in_drifting_room()
    at_once = first_order + room(T_LONG)
    for seed in range(count):
        rng = np.random.default_rng(seed)
        noise = 0.02 * rng.standard_normal((3, 401))
        room_sensor = 17.9 + room(T) + 0.02 * rng.standard_normal(401)
        case("first-order", first_order, first_order[:401] + noise[0])
        case("first-order, --room-wander 0", first_order, first_order[:401] + noise[0], wander=0.0)
        late = first_order[
            np.clip(np.arange(len(T_LONG)) - 15, 0, None)
        ]  # the logger started 15 min before the spindle
        case("first-order, begins 15 min late", late, late[:401] + noise[0])
        case("first-order, 0.1 °C display", first_order, np.round((first_order[:401] + noise[0]) / 0.1) * 0.1)
        fast = np.round((26.7 - 8.8 * np.exp(-0.016 * T_1HZ) + 0.02 * rng.standard_normal(len(T_1HZ))) / 0.1) * 0.1
        case("first-order, 1 Hz, 0.1 °C display", first_order, fast, times=T_1HZ)
        dropped = first_order[:401] + noise[0]
        dropped[np.random.default_rng(30_000 + seed).random(401) < 0.125] = np.nan  # empty cells, open circuits
        case("first-order, 12.5 % dropouts", first_order, dropped)
        case("fast+slow", fast_slow, fast_slow[:401] + noise[1])
        noisy = fast_slow_drifting[:401] + noise[1]
        case("fast+slow, drift, --ambient", fast_slow_drifting, noisy, room, room_sensor, steady=27.9)
        case("fast+slow, drift, no sensor", fast_slow_drifting, noisy, room, steady=27.9)
        for drifting, label in ((lagged, "drift"), (at_once, "drift at once")):
            noisy = drifting[:401] + noise[2]
            case("drift, no room sensor" if label == "drift" else f"{label}, no sensor", drifting, noisy, room)
            case("drift + --ambient" if label == "drift" else f"{label}, --ambient", drifting, noisy, room, room_sensor)
        for sigma, wander, kind in (
            (0.05, 0.05, "room wanders 0.05/h, no sensor"),
            (0.1, 0.05, "room wanders 0.1/h, no sensor"),
            (0.1, 0.1, "room wanders 0.1/h, --room-wander 0.1"),
        ):
            walk_rng = np.random.default_rng(10_000 + seed)
            wandering, room_at = machine_in_wandering_room(walk_rng, sigma)
            case(kind, wandering, wandering[:401] + 0.02 * walk_rng.standard_normal(401), room_at, wander=wander)
    return out


def sample_table(with_reference: bool) -> None:
    """The shipped sample (10 sensors, 400 samples): the replay's time, the stop, each sensor's error
    against the generating network's steady state. The reference is learnt from a second run of the
    same network (other noise), as an engineer would learn it from last week's test."""
    log = read_temperature_log(sample_log_path())
    reference = None
    if with_reference:
        clean = make_sample_warmup.simulate(log.time_min)
        rng = np.random.default_rng(99)
        second = np.column_stack(
            [np.round(clean[name] + 0.02 * rng.standard_normal(len(log.time_min)), 2) for name in log.sensors]
        )
        reference, _ = learn_reference(TemperatureLog(log.time_min, log.sensors, second, (), "second run"))
    settings = MonitorSettings(tolerance_C=TOLERANCE, reference=reference)
    start = time.perf_counter()
    state, _ = monitor_step(new_state(log.sensors), log.time_min, log.temperature_C, None, settings)
    elapsed = time.perf_counter() - start
    final = {name: float(np.median(log.temperature_C[-10:, s])) for s, name in enumerate(log.sensors)}
    label = "with a reference from a second run" if with_reference else "without a reference"
    print(
        f"\nSample log, {label}: replay {elapsed:.1f} s; stop at {state.stop_time_min if state.stopped else 'none'} min"
    )
    for check in state.checks:
        print(
            f"  {check.sensor:>4}: T∞ {check.steady_C:.2f} °C [{check.low_C:.2f}, {check.high_C:.2f}], log's last 10 "
            f"readings {final[check.sensor]:.2f} °C, {check.status}"
        )


def main() -> None:
    count = int(sys.argv[1]) if len(sys.argv) > 1 else 5
    print(f"Replays of {count} seeded warm-ups of each kind, σ = 0.02 °C, 1-min samples, tolerance {TOLERANCE} °C.")
    print(
        "error = |T∞ at the stop − the curve's value at 2,000 min|; with a drifting room, the steady state under the "
        "room's offset at the stop."
    )
    for with_reference in (False, True):
        print(
            "\n"
            + (
                "With a reference (the true time constants ±10 %)"
                if with_reference
                else "Without a reference (modes up to 300 min)"
            )
        )
        print(
            f"{'kind':>38} {'stopped':>8} {'stop/t_eq median':>17} {'max':>6} {'max error °C':>13} {'error > tol':>12}"
        )
        for kind, rows in families(count, with_reference).items():
            fractions = np.array([stop / eq for _, stop, eq, _ in rows if stop is not None])
            errors = np.array([error for _, stop, _, error in rows if stop is not None])
            if len(fractions) == 0:
                print(f"{kind:>38} {0:>5}/{len(rows):<2} {'-':>17} {'-':>6} {'-':>13} {0:>12}")
                continue
            print(
                f"{kind:>38} {len(fractions):>5}/{len(rows):<2} {np.median(fractions):17.2f} {fractions.max():6.2f} "
                f"{errors.max():13.3f} {int(np.sum(errors > TOLERANCE)):>12}"
            )
    for with_reference in (False, True):
        sample_table(with_reference)


if __name__ == "__main__":
    main()
