"""The synthetic warm-up generator: exactness, physical validity and the population's mix."""

from __future__ import annotations

import json
import math
from collections import Counter
from pathlib import Path

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from mtident.exceptions import InputError
from mtident.testing.warmups import (
    DURATION_LIMITS_MIN,
    INTERVALS_MIN,
    Machine,
    WarmUp,
    load_real_curves,
    modal_amplitudes,
    random_machine,
    random_warmup,
    reference_run,
    room_temperature,
    simulate,
)

REAL_DATA = Path(__file__).resolve().parents[2].parent / "shared" / "realdata"


def _machines(seed: int, count: int, **kw: object) -> list[Machine]:
    rng = np.random.default_rng(seed)
    return [random_machine(rng, **kw) for _ in range(count)]  # type: ignore[arg-type]


def _modal_curve(machine: Machine, run: WarmUp, t: np.ndarray) -> np.ndarray:
    taus, amplitudes = modal_amplitudes(machine, run)
    return run.steady_C[0] + np.exp(-np.outer(t, 1.0 / taus)) @ amplitudes


@pytest.fixture(scope="module")
def population() -> list[WarmUp]:
    rng = np.random.default_rng(20261123)
    return [random_warmup(rng) for _ in range(200)]


@pytest.mark.parametrize("kind", ["network", "conduction"])
def test_room_gain_is_one(kind: str) -> None:
    for machine in _machines(1, 15, kind=kind):
        ones = np.ones(len(machine.A))
        scale = np.abs(machine.A).max()  # a fine shaft's axial links are fast: relative
        np.testing.assert_allclose(machine.A @ ones + machine.b_room, 0.0, atol=1e-13 * scale)
        gain = machine.sensor @ np.linalg.solve(-machine.A, machine.b_room)
        assert gain == pytest.approx(1.0, abs=1e-10)
    rng = np.random.default_rng(2)
    run = random_warmup(rng, kind=kind, with_drift=True)
    room = room_temperature(run.time_min, run.settings["room_start_C"], run.settings["room_drift"])
    machine = run.machine
    heat = np.linalg.solve(-machine.A, machine.b_heat * run.power)
    formula = [machine.sensor @ (heat + np.linalg.solve(-machine.A, machine.b_room * r)) for r in room]
    np.testing.assert_allclose(run.steady_C, formula, atol=1e-9)
    np.testing.assert_allclose(run.steady_C - run.steady_C[0], room - room[0], atol=1e-9)
    assert run.room_C is not None and np.nanmax(np.abs(run.room_C - room)) < 0.3


def test_networks_are_physical() -> None:
    for machine in _machines(3, 60, kind="network"):
        st = machine.structure
        n = st["nodes"]
        capacity = np.array(st["capacities"])
        links = np.array(st["conductances"])
        convection = np.array(st["convection"])
        assert np.all(capacity > 0) and np.all(convection >= 0) and convection.sum() > 0
        assert np.all(links >= 0) and np.allclose(links, links.T)
        g = np.diag(links.sum(axis=1) + convection) - links
        np.testing.assert_allclose(-g / capacity[:, None], machine.A[:n, :n], rtol=1e-9, atol=1e-12)
        assert np.all(machine.b_heat >= 0)
        # every node's steady rise is positive, and heat anywhere warms every node
        assert np.all(np.linalg.solve(-machine.A, machine.b_heat) > 0)
        assert np.all(np.linalg.inv(g) >= 0)
        assert sum(machine.sensor) == 1.0


def test_time_constants_in_range() -> None:
    machines = _machines(4, 80)
    networks = [m for m in machines if m.kind == "network"]
    conductions = [m for m in machines if m.kind != "network"]
    lags = [m.sensor_lag_min for m in machines if m.sensor_lag_min]
    assert networks and conductions and lags  # the sample holds each kind, and sensors with a lag
    for machine in networks:
        structural = machine.structural_time_constants_min
        assert 2.0 <= min(structural) and max(structural) <= 300.0
        assert len(structural) == machine.structure["nodes"]
    for machine in conductions:
        structural = machine.structural_time_constants_min
        assert len(structural) >= 30 and 2.0 <= max(structural) <= 300.0
    assert all(0.2 <= lag <= 5.0 for lag in lags), lags
    for machine in machines:
        lag = (machine.sensor_lag_min,) if machine.sensor_lag_min else ()
        expected = sorted(machine.structural_time_constants_min + lag)
        np.testing.assert_allclose(sorted(machine.time_constants_min), expected, rtol=1e-9)
    for machine in _machines(5, 20, kind="network", min_time_constant_min=10.0, max_time_constant_min=50.0):
        assert 10.0 <= min(machine.structural_time_constants_min)
        assert max(machine.structural_time_constants_min) <= 50.0
    for machine in _machines(6, 10, kind="network", nodes=3, rise_C=5.0, sensor_lag_min=1.5):
        assert machine.sensor_lag_min == 1.5 and len(machine.A) == 4
        steady = machine.sensor @ np.linalg.solve(-machine.A, machine.b_heat)
        assert steady == pytest.approx(5.0)


@pytest.mark.parametrize("kind", ["network", "conduction"])
def test_modal_amplitudes_reproduce_clean(kind: str) -> None:
    rng = np.random.default_rng(7)
    for k in range(12):
        warm = (0.0, 0.0, 0.4, 0.3)[k % 4]
        profile = "heating" if k % 4 == 3 else "steady"
        machine = random_machine(rng, kind)
        run = simulate(
            machine,
            rng,
            interval_min=0.5,
            warm_start=warm,
            warm_profile=profile,
            warm_power=1.7 if profile == "heating" else None,
        )
        taus, amplitudes = modal_amplitudes(machine, run)
        assert np.all(np.diff(taus) <= 0)
        assert amplitudes.sum() == pytest.approx(run.start_C - run.steady_C[0], abs=1e-9)
        np.testing.assert_allclose(_modal_curve(machine, run, run.time_min), run.clean_C, atol=1e-9, rtol=0)
        # a cold start (warm = 0) begins at the room; a warm one that fraction of the way to the
        # steady state, which is not a scaled cold start: the previous heating moved the modes
        assert run.start_C - run.settings["room_start_C"] == pytest.approx(
            warm * (run.steady_C[0] - run.settings["room_start_C"]), rel=1e-9
        )


def test_steady_matches_long_simulation() -> None:
    rng = np.random.default_rng(8)
    for machine in _machines(9, 10):
        slow = max(machine.time_constants_min)
        run = simulate(
            machine,
            rng,
            power=1.3,
            duration_min=40 * slow,
            interval_min=slow / 4,
            noise_C=0.0,
            rounding_C=0.0,
            room_start_C=21.5,
        )
        assert run.clean_C[-1] == pytest.approx(run.steady_C[-1], abs=1e-9)
        assert run.steady_C[0] == pytest.approx(21.5 + 1.3 * machine.structure["rise_C"])
        np.testing.assert_array_equal(run.reading_C, run.clean_C)


def test_t95() -> None:
    rng = np.random.default_rng(10)
    for k in range(16):
        machine = random_machine(rng, ("network", "conduction")[k % 2])
        run = simulate(machine, rng, interval_min=0.25, warm_start=0.3 * (k % 3 == 0), duration_min=60.0)
        rise = run.steady_C[0] - run.start_C
        at = _modal_curve(machine, run, np.array([run.t95_min]))[0]
        assert abs(at - run.start_C) == pytest.approx(0.95 * abs(rise), abs=1e-9)
        before = np.linspace(0.0, run.t95_min, 4001)[:-1]
        assert np.all(np.abs(_modal_curve(machine, run, before) - run.start_C) < 0.95 * abs(rise))
        assert run.t95_min == run.settings["t95_min"]
    # first order: t95 = τ·ln 20
    rng = np.random.default_rng(11)
    machine = random_machine(rng, "network", nodes=1, sensor_lag_min=0.0)
    run = simulate(machine, rng)
    assert run.t95_min == pytest.approx(machine.time_constants_min[0] * math.log(20.0), rel=1e-9)
    assert run.duration_min == pytest.approx(np.clip(1.5 * run.t95_min, *DURATION_LIMITS_MIN), abs=run.interval_min)


@pytest.mark.parametrize("kind", ["network", "conduction"])
def test_drifting_room_matches_solve_ivp(kind: str) -> None:
    rng = np.random.default_rng(12)
    machine = random_machine(rng, kind, sensor_lag_min=0.7)
    drift = {"amplitude_C": 0.3, "period_min": 720.0, "phase_rad": 1.1, "slope_C_per_h": 0.05}
    run = simulate(
        machine,
        rng,
        duration_min=600.0,
        interval_min=5.0,
        room_drift=drift,
        room_start_C=19.0,
        warm_start=0.35,
        warm_profile="heating",
        warm_power=1.5,
    )

    def room(t: float) -> float:
        return float(room_temperature(np.array([t]), 19.0, drift)[0])

    solution = solve_ivp(
        lambda t, x: machine.A @ x + machine.b_heat * run.power + machine.b_room * room(t),
        (0.0, run.time_min[-1]),
        run.initial_state_C,
        t_eval=run.time_min,
        method="Radau",
        jac=lambda t, x: machine.A,
        rtol=1e-11,
        atol=1e-12,
    )
    np.testing.assert_allclose(machine.sensor @ solution.y, run.clean_C, atol=1e-7, rtol=0)
    assert run.room_C is not None and run.settings["room_drift"]["slope_C_per_h"] == 0.05


def test_seeds_reproducible() -> None:
    a, b = (random_warmup(np.random.default_rng(13), with_dropouts=True) for _ in range(2))
    np.testing.assert_array_equal(a.reading_C, b.reading_C)
    np.testing.assert_array_equal(a.machine.A, b.machine.A)
    assert a.settings == b.settings
    c = random_warmup(np.random.default_rng(14))
    assert c.settings != a.settings


def test_population(population: list[WarmUp]) -> None:
    kinds: Counter[str] = Counter()
    intervals: Counter[float] = Counter()
    drift = lag = warm = 0
    for run in population:
        json.dumps(run.settings)
        assert np.all(np.isfinite(run.clean_C)) and np.all(np.isfinite(run.steady_C))
        assert np.all(np.isfinite(run.reading_C))
        assert np.all(np.diff(run.time_min) > 0) and run.time_min[0] == 0.0
        assert abs(run.rise_C) >= 20 * run.rounding_C
        assert 2.0 - 1e-9 <= abs(run.rise_C) <= 30.0 + 1e-9
        assert DURATION_LIMITS_MIN[0] - run.interval_min < run.duration_min
        assert run.duration_min <= DURATION_LIMITS_MIN[1]
        steps = run.reading_C / run.rounding_C
        np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)
        assert np.std(run.reading_C - run.clean_C) < run.noise_C + run.rounding_C
        assert (run.room_C is None) == (run.settings["room_drift"] is None)
        kinds[run.machine.kind] += 1
        intervals[run.interval_min] += 1
        drift += run.room_C is not None
        lag += run.machine.sensor_lag_min > 0
        warm += run.settings["warm_start"] > 0
    n = len(population)
    assert abs(kinds["network"] / n - 0.75) < 0.08
    assert abs(drift / n - 0.3) < 0.08
    assert abs(lag / n - 0.4) < 0.08
    assert abs(warm / n - 0.2) < 0.07
    assert set(intervals) == set(INTERVALS_MIN)
    assert all(intervals[i] / n > 0.1 for i in INTERVALS_MIN[1:])
    # the finest readings are the shortest runs
    assert max(run.duration_min for run in population if run.interval_min == INTERVALS_MIN[0]) <= 300.0


def test_dropouts() -> None:
    rng = np.random.default_rng(15)
    machine = random_machine(rng, "network")
    run = simulate(
        machine,
        rng,
        duration_min=500.0,
        interval_min=0.5,
        dropout=0.1,
        room_drift={"amplitude_C": 0.1, "period_min": 900.0},
    )
    lost = np.isnan(run.reading_C)
    assert not lost[0] and 0.07 < lost.mean() < 0.13
    assert run.room_C is not None
    np.testing.assert_array_equal(np.isnan(run.room_C), lost)
    assert np.all(np.isfinite(run.clean_C))


def test_reference_run() -> None:
    rng = np.random.default_rng(16)
    for _ in range(10):
        run = random_warmup(rng)
        reference = reference_run(run.machine, rng)
        assert reference.machine is run.machine and reference.settings["reference"]
        assert 0.6 <= reference.power <= 1.4
        assert reference.duration_min >= 3.0 * reference.t95_min
        assert reference.settings["warm_start"] == 0.0 and reference.room_C is None
        assert len(reference.time_min) <= 20_001
        assert abs(reference.rise_C) >= 20 * reference.rounding_C
    same = reference_run(
        run.machine,
        rng,
        power=1.2,
        interval_min=run.interval_min,
        noise_C=run.noise_C,
        rounding_C=run.rounding_C,
    )
    assert same.power == 1.2 and same.interval_min == run.interval_min
    assert same.noise_C == run.noise_C and same.rounding_C == run.rounding_C


def test_bad_inputs() -> None:
    rng = np.random.default_rng(17)
    machine = random_machine(rng, "network")
    with pytest.raises(InputError):
        random_machine(rng, "rotor")
    with pytest.raises(InputError):
        simulate(machine, rng, warm_start=1.2)
    with pytest.raises(InputError):
        simulate(machine, rng, warm_start=0.5, warm_profile="heating", warm_power=0.4)
    with pytest.raises(InputError):
        simulate(machine, rng, room_drift={"amplitude": 0.1})


@pytest.mark.skipif(not REAL_DATA.is_dir(), reason="../shared/realdata not beside the repository")
def test_real_curves() -> None:
    curves = {curve.name: curve for curve in load_real_curves(REAL_DATA)}
    assert set(curves) == {
        "tclab_step50_run1:T1",
        "tclab_step50_run1:T2",
        "tclab_step50_run3_T1:T1",
    }
    for name in ("tclab_step50_run1:T1", "tclab_step50_run3_T1:T1"):
        curve = curves[name]
        assert curve.rounding_C == pytest.approx(0.32, abs=0.01)
        assert curve.time_min[-1] == pytest.approx(15.0, abs=0.1)
        assert 55.0 < curve.settled_C < 65.0 and curve.last_quarter_rise < 0.01
        assert 4.0 < curve.t95_min < 12.0
    lagged = curves["tclab_step50_run1:T2"]
    assert math.isnan(lagged.settled_C) and math.isnan(lagged.t95_min)
    assert lagged.end_C - lagged.start_C > 10.0
