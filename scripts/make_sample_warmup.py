"""Generate the sample warm-up log shipped in the package (src/mtident/data/spindle_warmup.csv).

A lumped thermal network of a vertical machining centre's spindle, with the
sensor positions of Yu et al. 2019, Table 1:

    T1..T5  front bearing end-cap surface (five spots around the cap)
    T6, T9  spindle sleeve
    T7      end of the spindle cylinder
    T8      spindle motor
    T10     lower end of the spindle

Physics (C dT/dt = −G T + h (T_amb − T) + P): seven nodes — front bearing,
rear bearing, motor, sleeve, cylinder end, nose (lower end), head casting —
with heat capacities C (J/K), conductances G between neighbours (W/K),
convection h to an ambient that starts at 17.9 °C (seed 000) and drifts by a
few tenths of a degree over the test, and heat inputs P (W) switched on at
t = 0 (spindle at 5,000 r/min). Surface sensors see their node through a small
thermal resistance (a first-order lag under a minute). Readings get PT100-like
white noise (σ = 0.02 °C) and are rounded to 0.01 °C.

Deterministic: the noise comes from ``np.random.default_rng(2019)``. A second
file, spindle_warmup_room.csv (``@sample-room``), is the same log with a room
sensor column ``room`` (for ``--ambient room``).

Run: python scripts/make_sample_warmup.py
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy.integrate import solve_ivp

NODES = ("front_bearing", "rear_bearing", "motor", "sleeve", "cylinder_end", "nose", "casting")
CAPACITY_J_PER_K = np.array([9.0e3, 7.0e3, 2.2e4, 1.4e4, 1.0e4, 6.0e3, 6.0e4])
HEAT_W = np.array([22.0, 12.0, 40.0, 14.0, 9.0, 7.0, 0.0])
CONVECTION_W_PER_K = np.array([1.6, 1.2, 4.2, 2.6, 1.6, 1.2, 12.0])
LINKS_W_PER_K = {
    ("front_bearing", "sleeve"): 2.5,
    ("front_bearing", "nose"): 1.5,
    ("rear_bearing", "sleeve"): 1.8,
    ("rear_bearing", "cylinder_end"): 1.2,
    ("motor", "cylinder_end"): 2.0,
    ("motor", "rear_bearing"): 1.0,
    ("sleeve", "casting"): 0.8,
    ("cylinder_end", "casting"): 0.4,
    ("nose", "sleeve"): 1.2,
}
# sensor -> (node, lag time constant in minutes, fraction of the node's rise seen on the surface)
SENSORS = {
    "T1": ("front_bearing", 0.5, 0.97),
    "T2": ("front_bearing", 0.8, 0.93),
    "T3": ("front_bearing", 0.6, 0.95),
    "T4": ("front_bearing", 1.0, 0.90),
    "T5": ("front_bearing", 0.9, 0.88),
    "T6": ("sleeve", 0.5, 1.00),
    "T7": ("cylinder_end", 0.6, 0.96),
    "T8": ("motor", 0.4, 1.00),
    "T9": ("sleeve", 0.8, 0.94),
    "T10": ("nose", 0.6, 0.97),
}
# Weak links keep each part close to a first-order warm-up (as the papers' curves are: seed
# 000 predicts T∞ within 0.1 °C from 28 min), with a small slow tail from the neighbours.
# At 0.25 (the first version of this file) the tails were not small: a first-order fit of
# 90 min missed T∞ by 0.3-1 °C, a network no first-order method can call early
# (benchmarks/bench_watch.py keeps it as a stress case).
LINK_SCALE = 0.05
START_C = 17.9
NOISE_C = 0.02
RESOLUTION_C = 0.01
DURATION_MIN = 400
SEED = 2019


def ambient_C(t_min: np.ndarray | float) -> np.ndarray | float:
    """Room temperature: 17.9 °C, a slow rise of 0.3 °C over the test and a 0.1 °C wobble."""
    return (
        START_C + 0.3 * (1.0 - np.exp(-np.asarray(t_min) / 200.0)) + 0.1 * np.sin(2 * np.pi * np.asarray(t_min) / 150.0)
    )


def conductance_matrix(link_scale: float = LINK_SCALE) -> np.ndarray:
    n = len(NODES)
    G = np.zeros((n, n))
    for (a, b), g in LINKS_W_PER_K.items():
        g *= link_scale
        i, j = NODES.index(a), NODES.index(b)
        G[i, i] += g
        G[j, j] += g
        G[i, j] -= g
        G[j, i] -= g
    return G + np.diag(CONVECTION_W_PER_K)


def simulate(times_min: np.ndarray, link_scale: float = LINK_SCALE, heat_scale: float = 1.0) -> dict[str, np.ndarray]:
    """Noise-free sensor temperatures at ``times_min``."""
    G = conductance_matrix(link_scale)
    n_nodes, n_sensors = len(NODES), len(SENSORS)
    lags = np.array([SENSORS[s][1] for s in SENSORS])
    seen = np.array([SENSORS[s][2] for s in SENSORS])
    which = np.array([NODES.index(SENSORS[s][0]) for s in SENSORS])

    def rhs(t_min: float, state: np.ndarray) -> np.ndarray:
        nodes, surfaces = state[:n_nodes], state[n_nodes:]
        amb = ambient_C(t_min)
        d_nodes = (heat_scale * HEAT_W - G @ nodes + CONVECTION_W_PER_K * amb) / CAPACITY_J_PER_K * 60.0
        target = amb + seen * (nodes[which] - amb)
        d_surfaces = (target - surfaces) / lags
        return np.concatenate([d_nodes, d_surfaces])

    start = np.full(n_nodes + n_sensors, START_C)
    sol = solve_ivp(rhs, (0.0, float(times_min[-1])), start, t_eval=times_min, method="LSODA", rtol=1e-9, atol=1e-9)
    return {name: sol.y[n_nodes + i] for i, name in enumerate(SENSORS)}


def main() -> None:
    rng = np.random.default_rng(SEED)
    times = np.arange(0.0, DURATION_MIN + 1.0)
    clean = simulate(times)
    lines = ["time_min," + ",".join(SENSORS)]
    noisy = {
        name: np.round((values + NOISE_C * rng.standard_normal(len(values))) / RESOLUTION_C) * RESOLUTION_C
        for name, values in clean.items()
    }
    for k, t in enumerate(times):
        lines.append(f"{t:g}," + ",".join(f"{noisy[name][k]:.2f}" for name in SENSORS))
    data = Path(__file__).resolve().parents[1] / "src" / "mtident" / "data"
    out = data / "spindle_warmup.csv"
    out.write_text("\n".join(lines) + "\n")
    finals = ", ".join(f"{name} {clean[name][-1]:.2f}" for name in SENSORS)
    print(f"wrote {out} ({len(times)} samples); final temperatures: {finals}")
    # The same test with a room sensor beside the machine (its noise drawn after the others', so the
    # ten sensor columns are the same numbers as above): the @sample-room log, for --ambient.
    room = np.round((ambient_C(times) + NOISE_C * rng.standard_normal(len(times))) / RESOLUTION_C) * RESOLUTION_C
    with_room = [lines[0] + ",room"] + [f"{line},{value:.2f}" for line, value in zip(lines[1:], room, strict=True)]
    out = data / "spindle_warmup_room.csv"
    out.write_text("\n".join(with_room) + "\n")
    print(f"wrote {out} (the same log with a room column)")
    write_reference(data / "spindle_machine.toml")


# the reference run: an earlier test of the same machine at a lower speed, run to equilibrium
REFERENCE_HEAT_SCALE = 0.7
REFERENCE_DURATION_MIN = 720
REFERENCE_SEED = 2018


def write_reference(out: Path) -> None:
    """The machine's modes learnt from an earlier, complete warm-up at 70 % of the heat (the
    ``@sample-machine`` reference), with its room sensor as an input."""
    from mtident.io.logs import TemperatureLog
    from mtident.thermal.reference import save_reference
    from mtident.thermal.reference_learning import learn_reference

    rng = np.random.default_rng(REFERENCE_SEED)
    times = np.arange(0.0, REFERENCE_DURATION_MIN + 1.0)
    clean = simulate(times, heat_scale=REFERENCE_HEAT_SCALE)
    values = np.column_stack(
        [
            np.round((clean[name] + NOISE_C * rng.standard_normal(len(times))) / RESOLUTION_C) * RESOLUTION_C
            for name in SENSORS
        ]
    )
    room = np.round((ambient_C(times) + NOISE_C * rng.standard_normal(len(times))) / RESOLUTION_C) * RESOLUTION_C
    log = TemperatureLog(times, tuple(SENSORS), values, (), "earlier warm-up at 3,500 r/min (720 min)")
    reference, warnings = learn_reference(log, room)
    save_reference(reference, out)
    print(f"wrote {out} (modes of {len(reference.sensors)} sensors){'; ' + '; '.join(warnings) if warnings else ''}")


if __name__ == "__main__":
    main()
