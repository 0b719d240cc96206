"""Tests of :mod:`mtident.thermal.robust_types`."""

from __future__ import annotations

import math
from dataclasses import replace

import pytest

from mtident.thermal.reference import MachineReference
from mtident.thermal.robust import SensorModes


def test_pooled_modes_narrow_where_runs_agree_and_hold_both_where_they_do_not():
    from mtident.thermal.pooling import pool_references
    from mtident.thermal.robust_types import SensorModes

    def reference(sensors: dict[str, SensorModes]) -> MachineReference:
        return MachineReference("run.csv", "2026-11-29", 300.0, "not measured", sensors)

    first = reference(
        {
            "agree": SensorModes((40.0,), (0.3,)),
            "apart": SensorModes((40.0,), (0.1,)),
            "fewer": SensorModes((40.0,), (0.1,)),
            "doubted": SensorModes((40.0,), (0.1,), doubt="not pinned down"),
            "first only": SensorModes((5.0,), (0.1,)),
        }
    )
    later = reference(
        {
            "agree": SensorModes((41.0,), (0.3,)),
            "apart": SensorModes((80.0,), (0.1,)),
            "fewer": SensorModes((4.0, 42.0), (0.2, 0.1)),
            "doubted": SensorModes((60.0,), (0.2,)),
        }
    )
    pooled, said = pool_references(first, later)
    (tau,), (box,) = pooled.sensors["agree"].time_constants_min, pooled.sensors["agree"].box
    assert 39.0 < tau < 41.0 and box == pytest.approx(math.tanh(math.atanh(0.3) / math.sqrt(2.0)), rel=0.05)
    (tau,), (box,) = pooled.sensors["apart"].time_constants_min, pooled.sensors["apart"].box
    assert tau * (1 - box) <= 36.0 + 1e-9 and tau * (1 + box) >= 88.0 - 1e-9
    assert pooled.sensors["fewer"] == later.sensors["fewer"] and pooled.sensors["doubted"] == later.sensors["doubted"]
    assert pooled.sensors["first only"] == first.sensors["first only"] and pooled.source == "run.csv + run.csv"
    assert any(s.startswith("apart: its mode of 40 min ±10% in one run is 80 min ±10%") for s in said), said
    assert any(s.startswith("fewer: the runs learnt 1 and 2 modes; the 2 kept") for s in said), said
    # each run's date is kept (the later's alone lost the first's)
    dated = pool_references(replace(first, run_date="2026-01-10"), replace(later, run_date="2026-01-11"))[0]
    assert dated.run_date == "2026-01-10 + 2026-01-11"
    same = pool_references(replace(first, run_date="2026-01-10"), replace(later, run_date="2026-01-10"))[0]
    assert same.run_date == "2026-01-10"
    # a box wider than its mode (a run in a cycling room: 2.78 min ±106 %) pooled: `learn --update`
    # ended in a math domain error; the pooled box leans on the other run's, its lower end positive
    loose = pool_references(
        reference({"fast": SensorModes((2.78,), (1.06,))}), reference({"fast": SensorModes((3.2,), (0.2,))})
    )
    (tau,), (box,) = loose[0].sensors["fast"].time_constants_min, loose[0].sensors["fast"].box
    assert box < 1.0 and 2.0 < tau * (1 - box) < 3.2 < tau * (1 + box) < 2.78 * 2.06


def test_the_ends_say_what_is_left_of_their_slowest_mode_and_of_the_others():
    """A first-order warm-up (59 min, 8.85 °C) read for 120 min: the high end is a slow mode that
    still rises, the low end one that falls; each is said as what is left of it after the last
    reading, and the faster modes going the other way by how far they go, so that the two add up
    to the end's distance from where the model stands now."""
    import math
    import re

    import numpy as np

    from mtident.thermal.robust import estimate_sensor

    t = np.arange(0.0, 121.0)
    y = 20.0 + 8.85 * (1.0 - np.exp(-t / 59.0)) + np.random.default_rng(5).normal(0.0, 0.01, t.size)
    estimate = estimate_sensor("T1", t, y)
    assert estimate.fit is not None and estimate.last_min == 120.0
    text = estimate.what_sets_the_ends(0.99)
    elapsed = 120.0 - estimate.fit.origin_min
    for end, phrase in zip(estimate.fit.ends[0.99], text.split("; "), strict=True):
        slowest = end.slowest()
        assert slowest is not None
        own = -slowest.amplitude_C * math.exp(-elapsed / slowest.time_constant_min)
        course = "rise" if own > 0 else "fall"
        said = re.search(rf"still fits, with ([0-9.]+) °C of {course} still to come after t = 120 min", phrase)
        assert said is not None, phrase
        assert float(said.group(1)) == pytest.approx(abs(own), abs=0.006)
        left = sum(-m.amplitude_C * math.exp(-elapsed / m.time_constant_min) for m in end.modes)
        others = re.search(r"faster modes (rising|falling) ([0-9.]+) °C meanwhile", phrase)
        if others is not None:
            sign = 1.0 if others.group(1) == "rising" else -1.0
            assert own + sign * float(others.group(2)) == pytest.approx(left, abs=0.012)
        else:
            assert left == pytest.approx(own, abs=0.012) or own * (left - own) > 0
    assert text.startswith("low end") and "; high end" in text and "of rise" in text.split("; ")[1]


def test_in_a_drifting_room_the_ends_say_the_floor_and_the_rooms_share():
    """A first-order sensor (40 min, 6 °C) in a room drifting 0.1 °C/h, logged, read for 360 min
    without a reference: the low end is the warm-up's floor, not a model that still falls; the high
    end's distance from T∞ is its modes' course and the room's share, which add up to it (a new
    user read "0.01 °C of rise still to come" beside an end 0.2 °C away)."""
    import math
    import re

    import numpy as np

    from mtident.thermal.robust import estimate_sensor

    rng = np.random.default_rng(3)
    t = np.arange(0.0, 360.0)
    room = 20.0 + 0.1 * t / 60.0
    sensor = np.full(t.size, 20.0)
    decay = math.exp(-1.0 / 40.0)
    for i in range(1, t.size):
        sensor[i] = sensor[i - 1] * decay + (1.0 - decay) * (room[i - 1] + 6.0)
    y = np.round(sensor + rng.normal(0.0, 0.01, t.size), 2)
    estimate = estimate_sensor("S", t, y, np.round(room + rng.normal(0.0, 0.01, t.size), 2))
    assert estimate.fit is not None
    low, high = estimate.interval_C[0.99]
    low_words, high_words = estimate.what_sets_the_ends(0.99).split("; ")
    assert low_words == f"low end {low:.2f} °C: where the sensor already is, less its noise (a warm-up does not fall)"
    assert low > estimate.fit.ends[0.99][0].steady_C
    said = re.search(
        r"with ([0-9.]+) °C of (rise|fall) still to come after t = 359 min"
        r"(?: \(faster modes (rising|falling) ([0-9.]+) °C meanwhile\))?, and ([0-9.]+) °C more from the room",
        high_words,
    )
    assert said is not None, high_words
    own = float(said.group(1)) * (1.0 if said.group(2) == "rise" else -1.0)
    others = 0.0 if said.group(3) is None else float(said.group(4)) * (1.0 if said.group(3) == "rising" else -1.0)
    elapsed = estimate.last_min - estimate.fit.origin_min
    best_left = sum(-m.amplitude_C * math.exp(-elapsed / m.time_constant_min) for m in estimate.fit.modes)
    assert own + others - best_left + float(said.group(5)) == pytest.approx(high - estimate.steady_C, abs=0.02)
    assert float(said.group(5)) > 0.1


def test_a_wide_box_is_said_as_its_range_not_as_a_measurement():
    """learn showed a mode it could not pin down as "152 ±98 %": the middle of 3-300 min, which reads
    as a measurement."""
    from mtident.thermal.robust_types import SensorModes

    modes = SensorModes((6.02, 151.5, 136.0), (0.10, 0.98, 0.26))
    assert modes.box_words() == "6.02 ±10%, 3.03-300, 136 ±26%"
    assert modes.box_words(" min") == "6.02 min ±10%, 3.03-300 min, 136 min ±26%"
    # a box as wide as its mode or wider: a machine model's "2.78 ±106%" (a time constant is never below zero)
    assert SensorModes((2.78,), (1.06,)).box_words() == "up to 5.73"


def test_pooling_says_that_a_later_runs_room_path_is_not_kept():
    """A run in a daily-cycling room pooled into a steady-room reference: its learnt room path was
    left out without a word."""
    from mtident.thermal.machine_model import MachineModel
    from mtident.thermal.pooling import pool_references

    steady = MachineModel(("A", "B"), (100.0, 20.0), (0.1, 0.1), ((1.0, 0.5), (0.8, 0.2)))
    cycling = replace(
        steady,
        room_gains=((0.6, 0.4), (0.7, 0.3)),
        room_gain_cov=(((0.01, 0.0), (0.0, 0.01)), ((0.01, 0.0), (0.0, 0.01))),
    )
    modes = {"A": SensorModes((100.0, 20.0), (0.1, 0.1)), "B": SensorModes((100.0, 20.0), (0.1, 0.1))}

    def run(model: MachineModel) -> MachineReference:
        return MachineReference("run.csv", "2026-11-29", 300.0, "measured", modes, machine_model=model)

    pooled, said = pool_references(run(steady), run(cycling))
    assert pooled.machine_model is not None and not pooled.machine_model.room_gains
    assert any("the later run learnt the room's path into every sensor" in s for s in said), said
    assert not any("room's path" in s for s in pool_references(run(cycling), run(steady))[1])
