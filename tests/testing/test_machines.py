"""Tests of :mod:`mtident.testing.machines`."""

from __future__ import annotations

import math

import numpy as np
import pytest
from helpers import _machines, _modal_curve
from scipy.integrate import solve_ivp

from mtident.testing.warmups import (
    DURATION_LIMITS_MIN,
    random_machine,
    room_temperature,
    simulate,
)


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
