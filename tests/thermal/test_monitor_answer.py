"""Tests of :mod:`mtident.thermal.monitor_answer`."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
from conftest import first_order
from helpers import PAPER_T95, T, noisy, one_mode_reference, replay, three_mode_housing

from mtident.thermal.monitor import MonitorSettings, new_state, result
from mtident.thermal.robust import RobustSettings


def test_a_reference_said_to_hold_every_mode_stops_as_early_as_the_papers_filters():
    """--free-fast-modes 0: no mode faster than the reference's, an assumption the answer states;
    the stop comes by about 0.4·t95 (66 and 75 min: 0.35 and 0.40 on these seeds), within the tolerance."""
    from mtident.thermal.monitor import assumptions

    settings = MonitorSettings(reference=one_mode_reference("S"), robust=RobustSettings(free_fast_modes=0))
    for seed in (1, 2):
        state = replay({"S": noisy(first_order(T), seed)}, reference=settings.reference, robust=settings.robust)
        check = state.checks[0]
        assert state.stopped and state.stop_time_min <= 0.41 * PAPER_T95, state.stop_time_min
        assert abs(check.steady_C - 26.7) < 0.2 and check.low_C <= 26.7 <= check.high_C
    assert "no mode faster than these (assumed)" in str(assumptions(settings, "S").reference)
    assert "up to 2 free modes faster than the slowest of these" in str(
        assumptions(MonitorSettings(reference=one_mode_reference("S")), "S").reference
    )


def test_a_reference_learnt_as_holding_every_mode_stops_as_early_as_the_option_says():
    """`learn --every-mode` puts the assumption in the reference: a test with the default
    --free-fast-modes stops as with --free-fast-modes 0 (by 0.41·t95 on these seeds), and says why."""
    from mtident.thermal.monitor import assumptions

    reference = one_mode_reference("S").holding_every_mode()
    for seed in (1, 2):
        state = replay({"S": noisy(first_order(T), seed)}, reference=reference)
        check = state.checks[0]
        assert state.stopped and state.stop_time_min <= 0.41 * PAPER_T95, state.stop_time_min
        assert abs(check.steady_C - 26.7) < 0.2 and check.low_C <= 26.7 <= check.high_C
    said = str(assumptions(MonitorSettings(reference=reference), "S").reference)
    assert "no mode faster than these (assumed: the reference says it holds every mode)" in said


def test_a_slow_mode_not_yet_seen_keeps_the_monitor_from_stopping_wrongly():
    t = np.arange(0.0, 241.0)  # every minute: interval 24.06-24.85 °C (every 30 s: 23.86-24.78), a quarter of the time
    state = replay({"housing": noisy(three_mode_housing(t), 4)}, t)
    check = state.checks[0]
    assert not state.stopped
    assert check.low_C <= 24.38 <= check.high_C  # the interval covers the truth
    out = result(state, MonitorSettings())
    assert out["stop_time_min"] is None and out["decision"] == "continue"
    reason = str(out["reason"])
    assert "housing: T∞" in reason and "still fits" in reason and "give a reference run of this machine" in reason
    # the end is a mode at the largest time constant searched: the way to say the machine has none
    assert "a mode of about 300 min" in check.ends
    assert "where a mode of about 300 min sets an end, and this machine has none that slow" in reason
    assert "`max_time_constant_min`" in reason


def test_the_largest_time_constant_is_offered_only_where_a_mode_at_it_sets_an_end():
    from mtident.thermal.robust_types import ends_at_the_largest

    assert ends_at_the_largest("low end 28.80 °C: a mode of about 300 min, rising 0.49 °C in all, still fits", 300.0)
    assert ends_at_the_largest("high end 29.1 °C: a mode of about 292 min, rising 3 °C in all, still fits", 300.0)
    assert not ends_at_the_largest("high end 29.1 °C: a mode of about 97 min, rising 3 °C in all, still fits", 300.0)
    assert not ends_at_the_largest("too few readings for a model", 300.0)


def test_fast_plus_slow_does_not_stop_with_a_wrong_answer():
    """A mode of 8 min and one of 150 min (T∞ 27.9 °C), 400 min every 3 min, no reference: the slow
    mode has not settled, so no stop, and the interval covers T∞ (27.67-28.20 °C). Its predecessor
    asserted only under `if stop is not None`: a monitor that never stopped passed, whatever it said."""
    t = np.arange(0.0, 401.0, 3.0)
    truth = 17.9 + 4.0 * (1 - np.exp(-t / 8.0)) + 6.0 * (1 - np.exp(-t / 150.0))
    state = replay({"S": noisy(truth, 200)}, t)
    check = state.checks[0]
    assert not state.stopped and result(state, MonitorSettings())["decision"] == "continue"
    assert check.low_C <= 27.9 <= check.high_C and check.high_C - check.low_C < 1.0


def _checked_state(steady: float, low: float, high: float, slowest: float, room_level: float = float("nan")):  # noqa: ANN202
    """A one-sensor state checked once: T∞, its decision interval, the best model's slowest mode."""
    state = new_state(["S"])
    check = replace(
        state.checks[0],
        status="narrowing",
        steady_C=steady,
        low_C=low,
        high_C=high,
        modes=((slowest, -6.0), (20.0, -2.0)),
        room_level_C=room_level,
    )
    return replace(state, checks=(check,))


def test_a_sensor_only_the_assumed_room_wander_keeps_from_stopping_is_told_to_log_the_room():
    """A new user's machine (slowest mode 158 min) with no room column never stopped in 15 h, told
    to continue the test: the wander of 0.05 °C in an hour over 158 min alone is ±0.20 °C at 99 %."""
    settings = MonitorSettings()
    # its readings alone pin T∞ to ±0.05 °C; the wander over 199 min adds ±0.23 °C in quadrature
    bound = result(_checked_state(28.0, 27.76, 28.24, 199.0), settings)
    assert bound["room_bound_sensors"] == ["S"]
    reason = str(bound["reason"])
    assert "the readings alone pin T∞ within ±0.05 °C" in reason and "moves T∞ ±0.23 °C at 99 %" in reason
    assert "no longer test narrows that" in reason and "continue the test" not in reason
    assert "Ways on: for S, state a smaller room wander" in reason and "log the room beside the sensors" in reason
    # still far from the tolerance: more readings may still find a faster slowest mode
    early = result(_checked_state(28.0, 25.0, 31.0, 199.0), settings)
    assert early["room_bound_sensors"] == [] and "continue the test" in str(early["reason"])
    assert "for S, also state a smaller room wander" in str(early["reason"])
    # a slowest mode of 100 min: the wander alone (±0.17 °C) is within the tolerance
    fast = result(_checked_state(28.0, 27.76, 28.24, 100.0), settings)
    assert fast["room_bound_sensors"] == [] and "wander" not in str(fast["reason"])
    # a measured room, or a room said to be steady, has no wander
    measured = result(_checked_state(28.0, 27.76, 28.24, 199.0, room_level=22.0), settings)
    steady = result(
        _checked_state(28.0, 27.76, 28.24, 199.0), replace(settings, robust=RobustSettings(room_wander_C_per_h=0.0))
    )
    assert measured["room_bound_sensors"] == steady["room_bound_sensors"] == []


def test_readings_in_steps_as_coarse_as_the_tolerance_never_stop_within_it():
    """A 10-bit converter's 0.32 °C steps and hardly any noise: rounding can bias T∞ by half a
    step where the curve flattens within one, which no interval shows (a held-out warm-up stopped
    0.25 °C off), so a tolerance of 0.2 °C is refused, and one of 0.4 °C is not."""
    y = np.round(first_order(T) / 0.32) * 0.32
    fast = RobustSettings(free_fast_modes=0)
    # 150 min: past the 91 min where the 0.4-°C tolerance stops, and 0.8·t95
    state = replay({"S": y[:151]}, T[:151], reference=one_mode_reference("S"), robust=fast)
    assert not state.stopped and state.checks[0].status == "too coarse"
    reason = str(result(state, MonitorSettings(reference=one_mode_reference("S"), robust=fast))["reason"])
    assert "its readings come in steps of 0.32 °C, no finer than the tolerance" in reason
    assert replay({"S": y}, reference=one_mode_reference("S"), robust=fast, tolerance_C=0.4).stopped


def test_a_warning_said_again_with_other_figures_is_listed_once_as_of_now():
    """A new user's column: "flat against the room until t = 56.5 min, within 0.15 °C" said at 81
    min, and at 600 min its latest check said "within 0.13 °C": the answer listed both. An earlier
    warning the latest check no longer has at all is kept, with its time."""
    from mtident.thermal.monitor_answer import _said_of
    from mtident.thermal.monitor_types import SensorCheck

    now = "column: flat against the room until t = 56.5 min, within 0.13 °C of its first level"
    check = SensorCheck("column", warnings=(now,))
    warned = (
        ("column", "t = 81 min: column: flat against the room until t = 56.5 min, within 0.15 °C of its first level"),
        ("column", "t = 230 min: column: the reference is not followed"),
        ("other", "t = 90 min: other: something else"),
    )
    assert _said_of(check, warned) == (now, "t = 230 min: column: the reference is not followed")
