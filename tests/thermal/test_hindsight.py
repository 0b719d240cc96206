"""Tests of :mod:`mtident.thermal.hindsight`."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import noisy

from mtident.thermal.hindsight import check_decision, settle_times


def test_the_hindsight_moves_t_inf_with_the_room_as_the_sensor_follows_it():
    """A room falling 0.4 °C over the five hours after a stop: a sensor of one 60-min mode follows
    it 0.08 °C behind, so the room's whole move would call a stop at the exact T∞ 0.08 °C off."""
    from mtident.thermal.hindsight import check_decision
    from mtident.thermal.modal_search import room_lag

    t = np.arange(0.0, 601.0)
    room = np.where(t < 300.0, 20.0, 20.0 - 0.4 * (t - 300.0) / 300.0)
    sensor = room_lag(room, t, np.array([60.0]))[0] + 8.0 * (1.0 - np.exp(-t / 60.0))
    values = sensor[:, None]
    # a tolerance of 0.5 °C: a sensor still following the room by 0.2 °C in the log's last quarter
    # is not settled to the precision of 0.2
    followed = check_decision(("S",), np.array([28.0]), 300.0, t, values, 0.5, room, [((60.0, -8.0),)])
    whole = check_decision(("S",), np.array([28.0]), 300.0, t, values, 0.5, room, None, 60.0)
    assert np.isnan(check_decision(("S",), np.array([28.0]), 300.0, t, values, 0.2, room).error_C[0])
    assert abs(followed.error_C[0]) < 0.005 and whole.error_C[0] < -0.07
    assert followed.room_shift_C == whole.room_shift_C and abs(whole.room_shift_C + 0.4) < 0.01
    assert followed.to_dict()["sensors"][0]["room_shift_C"] == pytest.approx(-0.4 + 0.08, abs=0.01)
    # a room that rose before the stop and stayed: T∞ at the stop already holds its level, which the
    # sensor, 0.08 °C behind at the stop, reaches by the log's end
    room = np.where(t < 300.0, 20.0 + 0.4 * t / 300.0, 20.4)
    sensor = room_lag(room, t, np.array([60.0]))[0] + 8.0 * (1.0 - np.exp(-t / 60.0))
    caught_up = check_decision(("S",), np.array([28.4]), 300.0, t, sensor[:, None], 0.2, room, [((60.0, -8.0),)])
    assert abs(caught_up.error_C[0]) < 0.005


def test_a_log_still_rising_at_the_pace_of_a_slow_mode_is_not_called_settled():
    """A newcomer's spindle (modes of 6, 45 and 180 min) logged for 6 h: its last quarter moved
    0.09 °C, under half the tolerance, but 0.2 °C was still to come, and a right stop (0.03 °C
    off the truth) was called 0.25 °C beyond the tolerance. At the pace of its 180-min mode it is
    not settled; the same log run on to 15 h is, and the stop is within the tolerance."""
    from mtident.thermal.hindsight import check_decision

    modes = ((6.0, -5.6), (45.0, -3.7), (180.0, -1.0))
    for end, settled in ((360.0, False), (900.0, True)):
        t = np.arange(0.0, end + 1.0, 1.0 / 3.0)
        truth = 30.5 + sum(a * np.exp(-t / tau) for tau, a in modes)
        values = noisy(truth, 23)[:, None]
        check = check_decision(("spindle",), np.array([30.53]), 274.0, t, values, 0.2, None, [modes])
        assert np.isfinite(check.settled_C[0]) == settled
        assert not settled or abs(check.error_C[0]) < 0.1
        # without the stop's modes, the largest time constant allowed (300 min) sets the pace
        assert np.isnan(check_decision(("spindle",), np.array([30.53]), 274.0, t, values, 0.2).settled_C[0]) or (
            end == 900.0
        )


def test_a_sensor_stuck_after_the_stop_is_not_taken_as_settled_at_its_stuck_value():
    """A new user's motor sensor stuck at 400 min, after the test had stopped right (T∞ within
    0.05 °C): the check against the rest of the log took its repeated value as where it settled
    and called the stop 1.16 °C beyond the tolerance. Its readings before the repeats settle where
    T∞ said."""
    t = np.arange(0.0, 900.0)
    values = noisy(30.0 - 8.0 * np.exp(-t / 40.0), 5)
    values[t >= 400.0] = 28.84  # 1.16 °C below where it settles, for good
    check = check_decision(("motor",), np.array([30.02]), 300.0, t, values[:, None], 0.2, None, [((40.0, -8.0),)])
    assert abs(check.settled_C[0] - 30.0) < 0.05 and abs(check.error_C[0]) < 0.1


def test_a_sensor_stuck_before_it_settled_is_said_stuck_in_the_check():
    """A slow sensor (a 180-min mode) stuck at 300 min of a 15-h log: its repeats are left out,
    so it has no settled level, and the check says it stuck rather than that it did not settle."""
    t = np.arange(0.0, 900.0)
    values = noisy(30.0 - 8.0 * np.exp(-t / 180.0), 7)
    values[t >= 300.0] = values[t == 300.0][0]
    check = check_decision(("column",), np.array([30.0]), 250.0, t, values[:, None], 0.2, None, [((180.0, -8.0),)])
    assert np.isnan(check.settled_C[0]) and check.stuck_since[0] == 300.0
    assert "column: stuck from 300 min, before it settled: nothing to check" in repr(check)
    assert check.to_dict()["sensors"][0]["stuck_since_min"] == 300.0
    fine = check_decision(
        ("column",), np.array([30.0]), 250.0, t, noisy(30.0 - 8.0 * np.exp(-t / 180.0), 7)[:, None], 0.2
    )
    assert fine.to_dict()["sensors"][0]["stuck_since_min"] is None and np.isnan(fine.stuck_since[0])


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


def test_a_slow_sensor_still_rising_behind_a_daily_room_is_not_called_settled():
    """A new user's column (a 235-min mode) in a room on a daily cycle of ±0.4 °C, its log ending at
    720 min: less the room itself, its rise and its lag behind the room cancelled, and the hindsight
    said it had settled (here from 334 min, 0.72 °C below its course), that the rule 'saved no
    time', beside 'the log ends before its sensors settled'. Less the room as the sensor follows it
    (through its mode), it is still rising at the log's end: the time saved is not known."""
    from mtident.thermal.modal_search import room_lag

    t = np.arange(0.0, 721.0)
    room = 20.0 + 0.4 * np.sin(2.0 * np.pi * (t - 720.0) / 1440.0)
    sensor = room_lag(room, t, np.array([235.0]))[0] + 3.0 * (1.0 - np.exp(-t / 235.0))
    said = check_decision(("S",), np.array([23.0]), 444.0, t, sensor[:, None], 0.2, room, [((235.0, -3.0),)])
    assert np.isnan(said.settle_time_min[0]) and said.time_saved_min is None
    # the same sensor in a steady room, logged to 1200 min, settles where its rise does: within
    # 0.2 °C of its last readings (3 - 3·e^(-1200/235) above the room) from 616 min
    t = np.arange(0.0, 1201.0)
    flat = 20.0 + 3.0 * (1.0 - np.exp(-t / 235.0))
    settled = check_decision(
        ("S",), np.array([23.0]), 444.0, t, flat[:, None], 0.2, np.full(1201, 20.0), [((235.0, -3.0),)]
    )
    expected = 235.0 * np.log(3.0 / (0.2 + 3.0 * np.exp(-1200.0 / 235.0)))
    assert settled.settle_time_min[0] == pytest.approx(expected, abs=1.0)


def test_the_room_reaches_a_sensor_as_its_fit_says_through_its_room_gains():
    """A sensor whose rise is mostly a 20-min mode but which follows a daily room through a
    200-min one: weighted by the shares of the rise, the room's course misses its lag by up to
    0.3 °C and no settle time was found in 1500 min; through the fit's gains on the room, the
    readings above the room settle where the rise does."""
    from mtident.thermal.modal_search import room_lag

    t = np.arange(0.0, 1501.0)
    room = 20.0 + 0.4 * np.sin(2.0 * np.pi * t / 1440.0)
    sensor = (
        room_lag(room, t, np.array([200.0]))[0] + 8.0 * (1.0 - np.exp(-t / 20.0)) + 0.5 * (1.0 - np.exp(-t / 200.0))
    )
    modes = [((20.0, -8.0), (200.0, -0.5))]
    shares = check_decision(("S",), np.array([28.5]), 300.0, t, sensor[:, None], 0.2, room, modes)
    gains = check_decision(
        ("S",), np.array([28.5]), 300.0, t, sensor[:, None], 0.2, room, modes, room_gains=[(0.0, 1.0)]
    )
    assert np.isnan(shares.settle_time_min[0])
    # within 0.2 °C of the settled 0.5 °C of the slow mode from 200·ln(0.5/0.2) = 183 min
    assert gains.settle_time_min[0] == pytest.approx(200.0 * np.log(0.5 / 0.2), abs=3.0)


def test_a_sensor_lagging_a_moving_room_settles_when_its_readings_reach_the_equilibrium_at_the_rooms_level():
    """A trial's daily room: the settle time was that of the readings less the room as each sensor
    follows it, 236.5 min, when the readings were still 0.28-0.38 °C below their equilibrium at the
    room's level (they came within 0.2 °C at 382 min), so a right stop at 349 min was said to save
    no time. A sensor whose own warm-up (8 °C, 20 min) ends by 74 min lags a room rising 0.5 °C an
    hour to 200 min by a 60-min mode: 0.5 °C behind, within 0.2 °C from 200 + 60·ln(2.5) = 255 min."""
    from mtident.thermal.modal_search import room_lag

    t = np.arange(0.0, 601.0)
    room = 20.0 + np.minimum(t, 200.0) * 0.5 / 60.0
    sensor = room_lag(room, t, np.array([60.0]))[0] + 8.0 * (1.0 - np.exp(-t / 20.0))
    modes = [((20.0, -8.0), (60.0, 0.0))]
    hindsight = check_decision(
        ("S",), np.array([29.67]), 150.0, t, sensor[:, None], 0.2, room, modes, room_gains=[(0.0, 1.0)]
    )
    assert hindsight.settle_time_min[0] == pytest.approx(200.0 + 60.0 * np.log(2.5), abs=3.0)
    assert hindsight.time_saved_min == pytest.approx(255.0 - 150.0, abs=3.0)


def test_a_sensor_that_keeps_following_a_daily_room_is_checked_against_its_rise_above_the_room():
    """A trial's daily room (±0.3 °C): every sensor's readings kept following the room to the log's
    end, so the check said "no settled level to check T∞ against" beside a right stop. A sensor of
    8 °C over a 40-min mode following the room through a 120-min mode: its rise above the room as it
    follows it settles at 8 °C, so T∞ at the stop (8 °C above the room then) checks within 0.01 °C,
    and a T∞ 0.3 °C high is called beyond the tolerance."""
    from mtident.thermal.modal_search import room_lag

    t = np.arange(0.0, 901.0)
    room = 20.0 + 0.3 * np.sin(2.0 * np.pi * (t - 900.0) / 1440.0)  # rising fastest at the log's end
    sensor = room_lag(room, t, np.array([120.0]))[0] + 8.0 * (1.0 - np.exp(-t / 40.0))
    modes = [((40.0, -8.0), (120.0, 0.0))]
    right, wrong = (
        check_decision(("S",), np.array([level]), 300.0, t, sensor[:, None], 0.2, room, modes, room_gains=[(0.0, 1.0)])
        for level in (room[300] + 8.0, room[300] + 8.3)
    )
    steady = check_decision(("S",), np.array([28.0]), 300.0, t, sensor[:, None], 0.2)
    assert np.isnan(steady.settled_C[0])  # the readings themselves keep moving with the room
    assert right.settled_with_room[0] and abs(right.error_C[0]) < 0.01 and right.within[0]
    assert wrong.error_C[0] == pytest.approx(0.3, abs=0.01) and not wrong.within[0]
    assert right.to_dict()["sensors"][0]["settled_with_room"] is True
    # without the sensor's modes at the stop there is no course to take out: nothing to check
    assert not check_decision(("S",), np.array([28.0]), 300.0, t, sensor[:, None], 0.2, room).checked[0]


def test_a_sensor_of_a_small_rise_following_a_daily_room_is_settled_to_the_checks_precision():
    """A new user's column rose 0.6 °C above a room cycling ±0.3 °C a day; its readings moved
    0.07 °C over the log's last quarter with the room, more than 5 % of its rise, so the check said
    it had "not yet" settled and the time saved was not known, though it stayed within 0.05 °C of
    its equilibrium for the last 100 min. The check's precision is the tolerance's."""
    from mtident.thermal.measured import measured_equilibrium
    from mtident.thermal.modal_search import room_lag

    t = np.arange(0.0, 901.0)
    room = 20.0 + 0.3 * np.sin(2.0 * np.pi * (t - 900.0) / 1440.0)
    column = room_lag(room, t, np.array([200.0]))[0] + 0.6 * (1.0 - np.exp(-t / 50.0))
    assert np.isnan(measured_equilibrium(t, column[:, None], 0.1, 0.05, 200.0)[0][0])  # 5 % of its rise
    modes = [((50.0, -0.6), (150.0, 0.0))]  # its course through a slow mode a little off
    check = check_decision(
        ("column",), np.array([room[300] + 0.6]), 300.0, t, column[:, None], 0.2, room, modes, room_gains=[(0.0, 1.0)]
    )
    assert check.checked[0] and check.within[0] and abs(check.error_C[0]) < 0.02
    assert check.time_saved_min is not None and not check.not_settled
