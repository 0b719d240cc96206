"""The synthetic warm-up generator: exactness, physical validity and the population's mix."""

from __future__ import annotations

import json
from collections import Counter

import numpy as np
import pytest
from helpers import _machines, _modal_curve

from mtident.exceptions import InputError
from mtident.testing.warmups import (
    DURATION_LIMITS_MIN,
    INTERVALS_MIN,
    WarmUp,
    modal_amplitudes,
    random_machine,
    random_warmup,
    reference_run,
    room_temperature,
    simulate,
)


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
