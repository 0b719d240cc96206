"""Which sensors a test waits for, and the time a stop saves against when the readings settle."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import make_log
from test_cli import mtident
from test_reference import two_mode

from mtident.exceptions import InputError
from mtident.thermal.hindsight import check_decision, settle_times
from mtident.thermal.monitor import MonitorSettings, monitor_step, new_state, result
from mtident.thermal.reference import MachineReference, learn_reference, save_reference


@pytest.fixture(scope="module")
def spindle_reference() -> MachineReference:
    t = np.arange(0.0, 480.0, 1.0)
    y = two_mode(t) + np.random.default_rng(1).normal(0.0, 0.01, t.size)
    reference, _ = learn_reference(make_log(t, {"S": np.round(y, 2)}))
    return reference


def spindle_and_column(t: np.ndarray) -> np.ndarray:
    """A spindle sensor the reference knows (8 and 60 min) and a column sensor of 250 min it does not."""
    rng = np.random.default_rng(5)
    spindle = two_mode(t, -4.0) + rng.normal(0.0, 0.01, t.size)
    column = 20.0 + 8.0 * (1.0 - np.exp(-t / 250.0)) + rng.normal(0.0, 0.01, t.size)
    return np.round(np.column_stack([spindle, column]), 2)


def test_a_sensor_the_test_does_not_wait_for_does_not_hold_the_stop(spindle_reference):
    t = np.arange(0.0, 240.0, 1.0)
    values = spindle_and_column(t)
    every = MonitorSettings(reference=spindle_reference)
    state, _ = monitor_step(new_state(["S", "column"]), t, values, None, every)
    assert not state.stopped
    assert result(state, every)["waited_for"] == ["S", "column"]

    spindle_only = MonitorSettings(reference=spindle_reference, wait_for=("S",))
    state, events = monitor_step(new_state(["S", "column"]), t, values, None, spindle_only)
    assert state.stopped and state.stop_time_min < 200.0
    # the spindle sensor's T∞ is 30 °C; the column's is still open and is reported, not waited for
    assert abs(state.checks[0].steady_C - 30.0) <= 0.2
    assert not state.checks[1].may_stop
    answer = result(state, spindle_only)
    assert answer["sensor"] == "S" and answer["waited_for"] == ["S"]
    assert [s["waited_for"] for s in answer["sensors"]] == [True, False]
    assert "every sensor waited for has its T∞ within ±0.2 °C" in events[-1].text


def test_waiting_for_a_sensor_not_watched_is_refused_by_name(spindle_reference):
    t = np.arange(0.0, 10.0, 1.0)
    settings = MonitorSettings(reference=spindle_reference, wait_for=("spindle",))
    with pytest.raises(InputError, match=r"cannot wait for 'spindle': not among the sensors watched \(S, column\)"):
        monitor_step(new_state(["S", "column"]), t, spindle_and_column(t), None, settings)


def test_the_settle_time_is_when_the_readings_stay_within_the_tolerance():
    # 30 − 10·e^(−t/20) is within 0.2 °C of 30 from t = 20·ln 50 = 78.2 min on
    t = np.arange(0.0, 300.0, 1.0)
    y = 30.0 - 10.0 * np.exp(-t / 20.0)
    noisy = y + np.where(np.arange(t.size) == 150, 0.5, 0.0)  # one spike is no leaving
    times = settle_times(t, np.column_stack([y, noisy, y]), np.array([30.0, 30.0, np.nan]), 0.2)
    assert times[0] == 79.0 and times[1] == 79.0 and np.isnan(times[2])


def test_the_time_saved_is_against_the_latest_settle_time_of_the_sensors_waited_for():
    t = np.arange(0.0, 600.0, 1.0)
    fast = 30.0 - 10.0 * np.exp(-t / 20.0)  # settles at 79 min
    slow = 28.0 - 8.0 * np.exp(-t / 60.0)  # within 0.2 °C from 60·ln 40 = 221.3 min
    values = np.column_stack([fast, slow])
    both = check_decision(("fast", "slow"), np.array([30.0, 28.0]), 150.0, t, values, 0.2)
    assert both.test_settle_time_min == 222.0 and both.time_saved_min == 72.0
    fast_only = check_decision(
        ("fast", "slow"), np.array([30.0, 28.0]), 150.0, t, values, 0.2, waited=np.array([True, False])
    )
    assert fast_only.time_saved_min == 79.0 - 150.0
    answer = fast_only.to_dict()
    assert answer["settle_time_min"] == 79.0 and answer["time_saved_min"] == -71.0
    assert [s["waited_for"] for s in answer["sensors"]] == [True, False]


def test_watch_says_the_time_saved_against_the_settled_readings_not_a_predicted_equilibrium(
    tmp_path, spindle_reference
):
    t = np.arange(0.0, 480.0, 1.0)
    values = spindle_and_column(t)
    log = tmp_path / "test.csv"
    rows = "\n".join(f"{a:g},{b:.2f},{c:.2f}" for a, (b, c) in zip(t, values, strict=True))
    log.write_text("time_min,S,column\n" + rows + "\n")
    save_reference(spindle_reference, tmp_path / "machine.toml")
    out = mtident(
        "thermal", "watch", str(log), "--replay", "--json", "--reference", str(tmp_path / "machine.toml"),
        "--wait-for", "S", "--state", str(tmp_path / "state.npz"),
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    answer = json.loads(out.stdout)
    assert answer["decision"] == "stop"
    settle = answer["hindsight"]["settle_time_min"]
    # the spindle sensor (8 and 60 min, 10 °C, −4 °C slow) is within 0.2 °C of 30 from about 60·ln 20 = 180 min
    assert 170.0 <= settle <= 190.0
    assert answer["settle_time_min"] == settle
    assert answer["time_saved_min"] == pytest.approx(settle - answer["stop_time_min"])
    text = mtident(
        "thermal", "watch", str(log), "--replay", "--reference", str(tmp_path / "machine.toml"), "--wait-for", "S",
        "--state", str(tmp_path / "state2.npz"),
    ).stdout  # fmt: skip
    assert answer["time_saved_min"] > 0
    assert f"{answer['time_saved_min']:.0f} min before the readings settled within the tolerance" in " ".join(
        text.split()
    )


def test_a_reference_names_its_machine_and_a_test_of_another_is_refused(tmp_path, spindle_reference):
    t = np.arange(0.0, 480.0, 1.0)
    y = two_mode(t) + np.random.default_rng(1).normal(0.0, 0.01, t.size)
    run = tmp_path / "run.csv"
    run.write_text("time_min,S\n" + "\n".join(f"{a:g},{b:.2f}" for a, b in zip(t, y, strict=True)) + "\n")
    out = mtident(
        "thermal", "learn", str(run), "-o", str(tmp_path / "vmc.toml"), "--machine", "VMC-1", "--serial", "4711",
        "--program", "8000 rpm", "--run-date", "2026-11-20", "--json",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    learnt = json.loads(out.stdout)
    assert (learnt["machine"], learnt["serial"], learnt["program"], learnt["run_date"]) == (
        "VMC-1", "4711", "8000 rpm", "2026-11-20",
    )  # fmt: skip
    from mtident.thermal.reference import load_reference

    reference = load_reference(tmp_path / "vmc.toml")
    assert reference.identity == f"machine VMC-1, serial 4711, program 8000 rpm, run on 2026-11-20 ({run})"
    assert reference.describe("S").startswith("machine VMC-1, serial 4711, program 8000 rpm, run on 2026-11-20: ")
    test = tmp_path / "test.csv"
    test.write_text("time_min,S\n" + "\n".join(f"{a:g},{b:.2f}" for a, b in zip(t[:60], y[:60], strict=True)) + "\n")
    same = mtident("thermal", "identify", str(test), "--reference", str(tmp_path / "vmc.toml"), "--machine", "VMC-1")
    assert same.returncode == 0, same.stderr
    other = mtident("thermal", "identify", str(test), "--reference", str(tmp_path / "vmc.toml"), "--machine", "HMC-2")
    assert other.returncode != 0
    assert "the reference is of machine 'VMC-1'" in other.stderr and "'HMC-2'" in other.stderr
    save_reference(spindle_reference, tmp_path / "unnamed.toml")
    unnamed = mtident(
        "thermal", "watch", str(test), "--replay", "--reference", str(tmp_path / "unnamed.toml"), "--machine",
        "VMC-1", "--state", str(tmp_path / "s.npz"),
    )  # fmt: skip
    assert unnamed.returncode != 0 and "does not say which machine it is of" in unnamed.stderr


def test_a_reference_most_sensors_contradict_is_used_for_none():
    """Another machine's reference (every time constant ×0.45 of this one's): three of four sensors
    contradict it, and the fourth, which follows it by chance, is answered without it too."""
    from mtident.thermal.robust import SensorModes

    modes = SensorModes((8.0, 60.0), (0.1, 0.1), (-4.0, -6.0), None)
    reference = MachineReference("small.csv", "2026-11-20", 300.0, "not measured", {n: modes for n in "ABCD"})
    t = np.arange(0.0, 120.0, 0.5)
    rng = np.random.default_rng(3)

    def sensor(fast: float, slow: float) -> np.ndarray:
        y = 30.0 - 4.0 * np.exp(-t / slow) - 6.0 * np.exp(-t / fast)
        return np.round(y + rng.normal(0.0, 0.01, t.size), 2)

    values = np.column_stack([sensor(8.0 / 0.45, 60.0 / 0.45)] * 3 + [sensor(8.0, 60.0)])
    settings = MonitorSettings(reference=reference)
    state, events = monitor_step(new_state(list("ABCD")), t, values, None, settings)
    assert state.reference_dropped
    said = [e.text for e in events if "contradicted by" in e.text]
    assert len(said) == 1 and "contradicted by 3 of the 4 sensors it knows (A, B, C)" in said[0]
    assert not any(c.reference_used for c in state.checks)
    answer = result(state, settings)
    assert answer["reference_dropped"] is True
    assert all(s["assumptions"]["reference"] is None for s in answer["sensors"])


def test_learn_splits_a_mode_that_merges_two_of_the_machines_modes():
    """A new user's machine: 110 and 260 min, learnt at one sensor as one mode of 170 min ±10 % (a box
    holding neither), while other sensors pin both down. The sensor keeps both, and it is said."""
    from mtident.thermal.reference import machine_modes, split_merged_modes
    from mtident.thermal.robust import SensorModes

    sensors = {
        "bearing": SensorModes((35.0, 110.0, 260.0), (0.1, 0.1, 0.1), (-1.0, -2.0, -3.0)),
        "sleeve": SensorModes((170.0,), (0.1,), (-5.0,)),
        "housing": SensorModes((2.0, 108.0, 255.0), (0.5, 0.1, 0.1), (1.0, -2.0, -3.0)),
    }
    taus = [round(m.time_constant_min) for m in machine_modes(sensors)]
    assert taus == [35, 109, 170, 258]  # the lag of ±50 % is no machine mode
    split, warnings = split_merged_modes(sensors)
    sleeve = split["sleeve"]
    assert sleeve.time_constants_min == pytest.approx((109.1, 257.75))
    # each box holds every sensor's time constant of the mode
    assert (
        sleeve.time_constants_min[0] * (1 - sleeve.box[0]) <= 99.0
        and sleeve.time_constants_min[1] * (1 + sleeve.box[1]) >= 286.0
    )
    assert sleeve.amplitudes_C == (-2.5, -2.5)
    assert split["bearing"] == sensors["bearing"] and split["housing"] == sensors["housing"]
    assert (
        len(warnings) == 1
        and "sleeve: its mode of 170 min (±10%) lies between the machine's modes of 109" in (warnings[0])
    )
    # a mode whose box holds a machine mode, or one alone with no machine mode either side, stays
    alone = {"a": SensorModes((170.0,), (0.1,)), "b": SensorModes((160.0,), (0.1,))}
    assert split_merged_modes(alone) == (alone, [])


def test_learn_splits_a_merged_mode_where_only_the_machine_model_pins_the_two_down():
    """A new user's trial: no sensor pinned the 113- and 280-min modes down alone (each sensor's
    slowest box wide), the machine model did (±10 %, ±13 %); the PT100 kept one mode of 189 min
    ±10 %, holding neither, without a word. The machine model's modes count as the machine's."""
    from mtident.thermal.machine_model import MachineModel
    from mtident.thermal.reference import split_merged_modes
    from mtident.thermal.robust import SensorModes

    sensors = {
        "bearing": SensorModes((3.5, 35.0, 200.0), (0.1, 0.1, 0.6), (-1.0, -2.0, -3.0)),
        "pt100": SensorModes((1.5, 189.0), (0.2, 0.1), (1.0, -5.0)),
    }
    model = MachineModel(("bearing", "pt100"), (280.0, 113.0, 34.7), (0.13, 0.10, 0.05), ((-1.0,) * 3, (-1.0,) * 3))
    split, warnings = split_merged_modes(sensors, model)
    assert split["pt100"].time_constants_min == pytest.approx((1.5, 113.0, 280.0))
    assert split["bearing"] == sensors["bearing"]
    assert len(warnings) == 1 and warnings[0].startswith(
        "pt100: its mode of 189 min (±10%) lies between the machine's modes of 113 and 280 min that the machine "
        "model pins down (bearing, pt100), and its box holds neither"
    )
    assert split_merged_modes(sensors) == (sensors, [])  # the sensors alone pin neither down


def test_a_rise_a_falling_room_hides_is_no_flat_start():
    """A new user's trial: a column rising 0.4 °C over five hours while the room fell as much read
    flat, and with the room given its fit began at 314 min ("flat until"), the first five hours
    left out. Against the room it rises from the start (and departs by 0.1 °C within 40 min)."""
    from mtident.thermal.robust import estimate_sensor

    t = np.arange(0.0, 600.0)
    room = 20.0 - 0.45 * (1.0 - np.exp(-np.minimum(t, 300.0) / 150.0))
    column = room + 0.5 * (1.0 - np.exp(-t / 150.0))
    rng = np.random.default_rng(4)
    readings = np.round(column + rng.normal(0.0, 0.01, t.size), 2)
    assert np.ptp(readings[:300]) < 0.15  # flat to the eye for five hours
    estimate = estimate_sensor("column", t, readings, np.round(room + rng.normal(0.0, 0.01, t.size), 2))
    assert estimate.onset_min < 40.0, estimate.warnings  # where 0.1 °C above the room is first seen


def test_the_floor_a_warm_up_sets_holds_only_for_a_rising_sensor_and_follows_a_room_that_fell():
    from mtident.thermal.robust import RobustSettings, estimate_sensor, overshoot_floor_C

    t = np.arange(0.0, 120.0, 1.0)
    rng = np.random.default_rng(8)
    rising = 30.0 - 10.0 * np.exp(-t / 40.0) + rng.normal(0.0, 0.01, t.size)
    estimate = estimate_sensor("S", t, rising, settings=RobustSettings(room_wander_C_per_h=0.0), noise_C=0.01)
    assert estimate.fit is not None
    latest = float(np.median(rising[-5:]))
    floor = overshoot_floor_C(estimate.fit, t, rising, None, 0.01, 0.0)
    assert floor == pytest.approx(latest - 0.04)
    assert estimate.interval_C[0.99][0] >= floor
    # a room that stood 0.3 °C above its latest level lowers the floor by that much
    room = 20.0 + 0.3 * (t < 60.0)
    assert overshoot_floor_C(estimate.fit, t, rising, room, 0.01, 0.0) == pytest.approx(latest - 0.34)
    # a sensor that cooled from a peak (an earlier heating at more power) sets none
    cooled = np.where(t < 60.0, rising, rising[59] - 0.02 * (t - 59.0))
    assert overshoot_floor_C(estimate.fit, t, cooled, None, 0.01, 0.0) == -np.inf


def test_with_a_room_sensor_the_settle_time_is_of_the_readings_above_the_room():
    """A new user's machine in a room on a daily cycle of ±0.3 °C: the readings kept moving with
    the room long after they had settled above it, and `time_saved_min` was null in every run."""
    t = np.arange(0.0, 600.0, 1.0)
    room = 20.0 + 0.4 * np.sin(2.0 * np.pi * t / 1440.0)
    sensor = room + 10.0 - 10.0 * np.exp(-t / 20.0)  # within 0.2 °C of room + 10 from 20·ln 50 = 78.2 min
    values = sensor[:, None]
    without = check_decision(("S",), np.array([30.0]), 150.0, t, values, 0.2)
    assert without.time_saved_min is None
    with_room = check_decision(("S",), np.array([30.0]), 150.0, t, values, 0.2, room_C=room)
    assert with_room.test_settle_time_min == 79.0 and with_room.time_saved_min == 79.0 - 150.0


def test_a_long_replay_shows_the_test_from_its_first_checks(tmp_path):
    """A replay showed nothing on its table or page until its first 250 rows were fed and checked."""
    from mtident.thermal.session import FIRST_FEED_ROWS, WatchSession

    t = np.arange(0.0, 400.0, 1.0)
    log = tmp_path / "long.csv"
    log.write_text("time_min,S\n" + "".join(f"{a:g},{30 - 10 * np.exp(-a / 60):.2f}\n" for a in t))
    session = WatchSession(log, MonitorSettings(), persist=False, resume=False)
    seen: list[float] = []
    session.poll(lambda s: seen.append(s.state.readings.latest_min))
    assert seen[0] <= FIRST_FEED_ROWS - 1 == 24.0  # the first check, at the latest the first part's end
    assert 24.0 in seen and 274.0 in seen  # and every 250 rows (until the test may stop), besides each check
    assert seen == sorted(seen)
