"""Helpers that tests of more than one module share."""

from __future__ import annotations

import urllib.error
import urllib.request
from pathlib import Path
from typing import NamedTuple

import numpy as np
from click.testing import CliRunner
from conftest import first_order, make_log
from scipy.integrate import solve_ivp
from scipy.linalg import expm

from mtident.cli import main
from mtident.io import read_temperature_log, sample_log_path
from mtident.testing.warmups import (
    Machine,
    WarmUp,
    modal_amplitudes,
    random_machine,
)
from mtident.thermal import RobustSettings
from mtident.thermal.monitor import MonitorSettings, MonitorState, monitor_step, new_state
from mtident.thermal.reference import MachineReference
from mtident.thermal.robust import SensorModes


def _local_clock_log(
    start: str, change_at: int, shift_h: int, rows: int = 240, step_s: int = 60, fmt: str = "%d.%m.%Y %H:%M:%S"
) -> str:
    """A 1-min warm-up log whose local clock (no offset written) is put back (shift_h = -1) or
    forward (+1) by an hour before row ``change_at``."""
    import datetime as dt

    first = dt.datetime.fromisoformat(start)
    clock = [
        first + dt.timedelta(seconds=step_s * k) + (dt.timedelta(hours=shift_h) if k >= change_at else dt.timedelta())
        for k in range(rows)
    ]
    return "time;T1\n" + "".join(
        f"{c.strftime(fmt)};{26.7 - 8.8 * np.exp(-0.016 * k * step_s / 60):.3f}\n".replace(
            ".", ",", 1 if fmt.startswith("%Y") else 0
        )
        for k, c in enumerate(clock)
    )


UNITS_LOG = "time;T1;T2;T3;speed\n[s];°C;K;°F;rpm\n" + "".join(
    f"{60 * m:g};{20 + 0.1 * m:.2f};{293.15 + 0.1 * m:.2f};{68 + 0.18 * m:.2f};{1000 + m:g}\n".replace(".", ",")
    for m in range(12)
)


def workbook_of_runs(path: Path, minutes: float = 60.0) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """An Excel workbook of four sheets at ``path``: a logger's "Details" (no table), two runs' tables,
    "Run 1" (sensor A, from 20 °C) and "Run 2" (sensor B, from 25 °C; and a room column "Umgebung"),
    and an empty "Spare". Returns the minutes and the readings of A and of B."""
    import pandas as pd

    t = np.arange(0.0, minutes + 1)
    a, b = 24.0 - 4.0 * np.exp(-t / 20.0), 31.0 - 6.0 * np.exp(-t / 25.0)
    with pd.ExcelWriter(path) as writer:
        pd.DataFrame([["Device", "UX120-006M"]]).to_excel(writer, sheet_name="Details", index=False, header=False)
        pd.DataFrame({"time_min": t, "A": a}).to_excel(writer, sheet_name="Run 1", index=False)
        pd.DataFrame({"time_min": t, "B": b, "Umgebung": 20.0}).to_excel(writer, sheet_name="Run 2", index=False)
        pd.DataFrame().to_excel(writer, sheet_name="Spare", index=False)
    return t, a, b


class Outcome(NamedTuple):
    """What a command run in-process ended with, named as :func:`subprocess.run` names it (and
    unpacked as ``code, out, err``)."""

    returncode: int
    stdout: str
    stderr: str


def mtident(*args: str) -> Outcome:
    """``mtident ARGS...`` in-process, the one way the tests run a command: exit code, stdout, stderr.

    An exception the command does not turn into an error message is raised, not hidden in an exit
    code of 1. A subprocess costs 1-2 s of start-up a call; what a process boundary is for is
    tested with real processes (marked ``slow``): `python -m mtident` (test_cli_thermal), the
    modules a command imports (test_cli), matplotlib's backend (report/test_plots), SIGKILL,
    SIGTERM and the live page of a watch (test_cli_watch, test_persist)."""
    result = CliRunner().invoke(main, list(args), catch_exceptions=False)
    return Outcome(result.exit_code, result.stdout, result.stderr)


T = np.arange(0.0, 401.0)


# the papers' curve, first order: τ = 62.5 min, 95 % of the rise at 187 min
PAPER_TAU = 62.5


PAPER_T95 = 187.2


def csv_text(t: np.ndarray, columns: dict[str, np.ndarray]) -> str:
    lines = ["time_min," + ",".join(columns)]
    for k, tk in enumerate(t):
        lines.append(f"{tk:g}," + ",".join("" if np.isnan(v[k]) else f"{v[k]:.3f}" for v in columns.values()))
    return "\n".join(lines) + "\n"


def one_mode_reference(*names: str, tau: float = PAPER_TAU) -> MachineReference:
    return MachineReference(
        "reference.csv", "2026-11-24", 300.0, "not measured", {n: SensorModes((tau,), (0.1,)) for n in names}
    )


def noisy(curve: np.ndarray, seed: int, sigma: float = 0.02) -> np.ndarray:
    return np.round(curve + sigma * np.random.default_rng(seed).standard_normal(len(curve)), 2)


def replay(
    columns: dict[str, np.ndarray], t: np.ndarray = T, room: np.ndarray | None = None, **options: object
) -> MonitorState:
    settings = MonitorSettings(**options)  # type: ignore[arg-type]
    state = new_state(tuple(columns), with_room=room is not None)
    state, _ = monitor_step(state, t, np.column_stack(list(columns.values())), room, settings)
    return state


def three_mode_housing(t: np.ndarray) -> np.ndarray:
    """A housing sensor of a three-node network (5, 40 and 200 min): a first-order fit of its first
    hour misses T∞ by degrees."""
    return 24.38 - 1.2 * np.exp(-t / 5.0) - 2.3 * np.exp(-t / 40.0) - 2.98 * np.exp(-t / 200.0)


# a reference said to hold every mode: the stop comes at 70 min, and each monitor run costs a second
BATCHED_SETTINGS = MonitorSettings(reference=one_mode_reference("S"), robust=RobustSettings(free_fast_modes=0))


def _get(url: str) -> bytes:
    with urllib.request.urlopen(url, timeout=10) as answer:
        return bytes(answer.read())


def _log(rows: int, names: tuple[str, ...] = ("A", "B", "C")) -> str:
    t = np.arange(0.0, float(rows))
    return csv_text(t, {n: noisy(first_order(t, steady=24.0 + k), 70 + k) for k, n in enumerate(names)})


def _machines(seed: int, count: int, **kw: object) -> list[Machine]:
    rng = np.random.default_rng(seed)
    return [random_machine(rng, **kw) for _ in range(count)]  # type: ignore[arg-type]


def _modal_curve(machine: Machine, run: WarmUp, t: np.ndarray) -> np.ndarray:
    taus, amplitudes = modal_amplitudes(machine, run)
    return run.steady_C[0] + np.exp(-np.outer(t, 1.0 / taus)) @ amplitudes


ROOM_C = 20.0


# a three-node chain (spindle nose, bearing housing, column), time constants of 9, 48 and 268 min
_CONDUCTANCE = np.array([[-0.09, 0.06, 0.0], [0.02, -0.035, 0.012], [0.0, 0.004, -0.0065]])


_HEAT = np.array([[0.5, 0.0], [0.0, 0.12], [0.0, 0.0]])


# sensors: the three nodes and one between the last two
_SENSOR_ROWS = np.array([[1.0, 0, 0], [0, 1.0, 0], [0, 0, 1.0], [0, 0.5, 0.5]])


SENSORS = ("nose", "housing", "column", "between")


def _run(
    split: tuple[float, float], power: float, x0_rise: np.ndarray, minutes: float, dt: float = 0.5
) -> tuple[np.ndarray, np.ndarray]:
    """Exact readings of the sensors (°C) from a start ``x0_rise`` above the room."""
    A = _CONDUCTANCE
    u = _HEAT @ (power * np.asarray(split))
    steady = np.linalg.solve(-A, u)
    t = np.arange(0.0, minutes + dt / 2, dt)
    step = expm(A * dt)
    x = np.empty((len(t), 3))
    x[0] = x0_rise - steady
    for k in range(1, len(t)):
        x[k] = step @ x[k - 1]
    return t, (x + steady) @ _SENSOR_ROWS.T + ROOM_C


def _truth(split: tuple[float, float], power: float) -> np.ndarray:
    return _SENSOR_ROWS @ np.linalg.solve(-_CONDUCTANCE, _HEAT @ (power * np.asarray(split))) + ROOM_C


def _noisy_chain(split, power, x0_rise, minutes, seed, dt=1.0):
    t, y = _run(split, power, x0_rise, minutes, dt)
    return t, np.round(y + np.random.default_rng(seed).normal(0.0, 0.01, y.shape), 2)


# the chain coupled to the room by each node's conductance (A·1 + b = 0: the room's static gain one)
_ROOM_COUPLING = -_CONDUCTANCE @ np.ones(3)


def _run_in_room(split, power, x0_rise, minutes, room, seed, dt=1.0):
    """Noisy readings (σ 0.01 °C, to 0.01 °C) of the chain warming in a room ``room(t)`` (°C), the
    room logged to 0.01 °C; x0_rise above the room's first level."""
    t = np.arange(0.0, minutes + dt / 2, dt)
    r = room(t)
    n = len(_CONDUCTANCE)
    # exact for a room that moves linearly between the readings
    M = np.zeros((n + 2, n + 2))
    M[:n, :n] = _CONDUCTANCE
    M[:n, n] = _HEAT @ (power * np.asarray(split))
    M[:n, n + 1] = _ROOM_COUPLING
    x = np.empty((len(t), n))
    x[0] = x0_rise + r[0]
    for k in range(1, len(t)):
        M[:n, n] = _HEAT @ (power * np.asarray(split)) + _ROOM_COUPLING * r[k - 1]
        M[:n, n + 1] = _ROOM_COUPLING * (r[k] - r[k - 1]) / dt
        step = expm(M * dt)
        x[k] = step[:n, :n] @ x[k - 1] + step[:n, n] + step[:n, n + 1] * dt
    y = x @ _SENSOR_ROWS.T
    rng = np.random.default_rng(seed)
    return t, np.round(y + rng.normal(0.0, 0.01, y.shape), 2), np.round(r, 2)


def _daily(amplitude, phase=0.0):
    return lambda t: ROOM_C + amplitude * np.sin(2.0 * np.pi * t / 1440.0 + phase)


def two_mode(t: np.ndarray, slow_amplitude: float = -6.0) -> np.ndarray:
    """A housing sensor: a fast mode of 8 min and a slow one of 60 min, from 20 °C."""
    return 20.0 + 10.0 + slow_amplitude * np.exp(-t / 60.0) - (10.0 + slow_amplitude) * np.exp(-t / 8.0)


def sample_log():

    return read_temperature_log(sample_log_path())


def _machine_in_drifting_room(t: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """dT/dt = λ(T_room + 8.8 − T) with λ = 0.016 and a room on a 0.15 °C 4-h cycle plus a 0.1 °C rise."""

    def room(tt):  # noqa: ANN001, ANN202
        return 17.9 + 0.15 * np.sin(2 * np.pi * np.asarray(tt) / 240.0) + 0.1 * (1 - np.exp(-np.asarray(tt) / 200.0))

    solution = solve_ivp(
        lambda tt, T: 0.016 * (room(tt) + 8.8 - T),
        (t[0], t[-1]),
        [17.9],
        t_eval=t,
        rtol=1e-10,
        atol=1e-10,
        max_step=1.0,
    )
    return solution.y[0], room(t)


def _noisy_logs_in_drifting_room(t: np.ndarray, count: int, seed: int):  # noqa: ANN202
    """``count`` noisy sensors of the machine in the drifting room, the room sensor and the true room."""
    curve, room = _machine_in_drifting_room(t)
    rng = np.random.default_rng(seed)
    log = make_log(t, {f"r{i}": curve + 0.02 * rng.standard_normal(len(t)) for i in range(count)})
    return log, room + 0.02 * rng.standard_normal(len(t)), room


def spindle_and_column(t: np.ndarray) -> np.ndarray:
    """A spindle sensor the reference knows (8 and 60 min) and a column sensor of 250 min it does not."""
    rng = np.random.default_rng(5)
    spindle = two_mode(t, -4.0) + rng.normal(0.0, 0.01, t.size)
    column = 20.0 + 8.0 * (1.0 - np.exp(-t / 250.0)) + rng.normal(0.0, 0.01, t.size)
    return np.round(np.column_stack([spindle, column]), 2)


def followed_in_pieces(live: Path, data: bytes, cuts: list[int]):  # noqa: ANN201 - (LogFollower, times)
    """A log written to ``live`` in pieces cut at ``cuts`` (bytes), the follower polling after each:
    the follower, and the times it read (no warning on the way)."""
    from mtident.io.follow import LogFollower

    live.write_bytes(b"")
    follower, times = LogFollower(live), []
    for a, b in zip([0, *sorted(set(cuts))], [*sorted(set(cuts)), len(data)], strict=True):
        with open(live, "ab") as out:
            out.write(data[a:b])
        polled = follower.poll()
        assert not polled.warnings
        times.extend(polled.time_min)
    return follower, times


def frozen_channel(t: np.ndarray, rng: np.random.Generator) -> dict[str, np.ndarray]:
    """T1 and T2 warming by 8 and 6 °C (τ 40 min, σ 0.01 °C, read to 0.001 °C), T2's channel frozen
    at its reading at index 80 through index 110 (a logger that repeated it, then read on)."""
    columns = {
        name: np.round(20.0 + rise * (1.0 - np.exp(-t / 40.0)) + rng.normal(0.0, 0.01, t.size), 3)
        for name, rise in (("T1", 8.0), ("T2", 6.0))
    }
    columns["T2"][80:111] = columns["T2"][80]
    return columns
