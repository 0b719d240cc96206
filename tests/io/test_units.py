"""Tests of :mod:`mtident.io.units`: the units of time and temperature stated by a units row, a
column's name or the options, and the columns they tell to be no temperature.
"""

from __future__ import annotations

import re

import numpy as np
import pytest
from helpers import UNITS_LOG

from mtident.exceptions import InputError
from mtident.io import read_temperature_log
from mtident.io.follow import LogFollower


def test_minutes_seconds_hours_and_timestamps(write_csv):
    log = read_temperature_log(write_csv("time_s,A,B\n0,20,21\n60,20.5,21.5\n120,21,22\n180,21.2,22\n240,21.4,22.1\n"))
    np.testing.assert_allclose(log.time_min, [0, 1, 2, 3, 4])
    assert log.sensors == ("A", "B")
    log = read_temperature_log(write_csv("t,A\n0,20\n0.5,20.5\n1,21\n1.5,21.2\n2,21.4\n"), time_unit="h")
    np.testing.assert_allclose(log.time_min, [0, 30, 60, 90, 120])
    stamps = "stamp,A\n" + "".join(f"2026-11-22T08:{m:02d}:00,{20 + m / 10}\n" for m in range(0, 10, 2))
    log = read_temperature_log(write_csv(stamps))
    np.testing.assert_allclose(log.time_min, [0, 2, 4, 6, 8])


def test_a_units_row_states_the_time_unit_and_the_temperature_scale(write_csv):
    """Many loggers write a units row under the header; it was refused ("'[s]' is neither a number
    nor a time stamp"). Its time unit is used, K and °F are converted to °C, and a channel that is
    no temperature is left out with a note (refused if asked for)."""
    log = read_temperature_log(write_csv(UNITS_LOG))
    assert log.sensors == ("T1", "T2", "T3")
    np.testing.assert_allclose(log.time_min, np.arange(12.0))
    np.testing.assert_allclose(
        log.temperature_C, np.repeat((20 + 0.1 * np.arange(12.0))[:, None], 3, axis=1), atol=1e-9
    )
    assert any("'T2': read in K" in n for n in log.notes) and any("'T3': read in °F" in n for n in log.notes)
    assert any("not temperatures by the units row: speed (rpm)" in n for n in log.notes)
    with pytest.raises(InputError, match=r"sensor 'speed' is in 'rpm' by the units row, not a temperature"):
        read_temperature_log(write_csv(UNITS_LOG), sensors=["speed"])
    # a bad cell's row number counts the units row
    with pytest.raises(InputError, match=r"sensor 'T1', row 5: 'x' is not a number"):
        read_temperature_log(write_csv(UNITS_LOG.replace("20,20", "x")))


def test_a_first_row_without_readings_is_no_units_row(write_csv):
    """A time stamp with every sensor empty has no unit in it: it stays a data row."""
    log = read_temperature_log(
        write_csv(
            "time,T1,T2\n2026-11-22T08:00:00,,\n"
            + "".join(f"2026-11-22T08:{m:02d}:00,{20 + m / 10:.1f},{21 + m / 10:.1f}\n" for m in range(1, 20))
        )
    )
    assert len(log.time_min) == 20 and np.isnan(log.temperature_C[0]).all()


def test_a_unit_at_the_end_of_a_column_name(write_csv):
    """'Time [s]' was read as minutes (only a _s suffix counted); 'T1 [°F]' as °C. A name whose
    brackets hold no unit ('T2 (spindle)') is a plain °C sensor."""
    text = "Time [s],T1 [°F],T2 (spindle)\n" + "".join(
        f"{60 * m},{68 + 0.18 * m:.2f},{20 + 0.1 * m:.1f}\n" for m in range(12)
    )
    log = read_temperature_log(write_csv(text))
    assert log.sensors == ("T1 [°F]", "T2 (spindle)")
    np.testing.assert_allclose(log.time_min, np.arange(12.0))
    np.testing.assert_allclose(
        log.temperature_C, np.repeat((20 + 0.1 * np.arange(12.0))[:, None], 2, axis=1), atol=1e-9
    )
    assert log.notes == ("sensor 'T1 [°F]': read in °F (its name), converted to °C",)


@pytest.mark.parametrize("head", ["Time_ms,A\n", "Time [ms],A\n", "time,A\nms,°C\n"])
def test_a_time_column_in_milliseconds(write_csv, head):
    """Time_ms was read as minutes (a 10-min log as 417 days, with a hint that it might be seconds)."""
    rows = "".join(f"{60_000 * k},{20 + k / 10:.2f}\n" for k in range(10))
    np.testing.assert_allclose(read_temperature_log(write_csv(head + rows)).time_min, np.arange(10.0))


def test_hobo_exports_in_fahrenheit_with_event_rows_at_the_end(write_csv):
    """HOBOware's export: the header began with '#' and was skipped as a comment (the first data
    row became the header), the unit after a comma ('Temp, °F (LGR S/N: ...)') was not seen, so
    °F would have been read as °C, and the event rows of the read-out, several at one time and
    without a reading, were refused as duplicate times."""
    rows = "".join(
        f"{k + 1},11/22/26 {8 + k // 60:02d}:{k % 60:02d}:00 "
        f"AM,{68 + 0.18 * k:.3f},50.1,{'Logged' if k == 0 else ''},,\n"
        for k in range(8)
    )
    rows += "9,11/22/26 08:10:00 AM,,,,Logged,\n10,11/22/26 08:10:00 AM,,,,,Logged\n"
    text = (
        'Plot Title: 20827226,,,,,,\n#,"Date Time, GMT+01:00","Temp, °F (LGR S/N: 20827226, SEN S/N: 20827226)","RH, '
        '% (LGR S/N: 20827226)",Coupler Detached (LGR S/N: 20827226),Host Connected (LGR S/N: 20827226),End Of File '
        "(LGR S/N: 20827226)\n" + rows
    )
    log = read_temperature_log(write_csv(text))
    assert log.sensors == ("Temp, °F (LGR S/N: 20827226, SEN S/N: 20827226)",)
    np.testing.assert_allclose(log.temperature_C[:, 0], 20 + 0.1 * np.arange(8), atol=1e-9)
    np.testing.assert_allclose(log.time_min, np.arange(8.0))
    assert any("left out 2 row(s) without a reading" in n for n in log.notes)
    # the classic export: tabs, the unit in brackets with the serial number after it, empty event channels
    classic = "Date Time\tTemp (°F)  #9724974\tCoupler Detached\tEnd Of File\n" + "".join(
        f"11/22/26 08:{k:02d}:00\t{68 + 0.18 * k:.3f}\t\t\n" for k in range(8)
    )
    log = read_temperature_log(write_csv(classic))
    assert log.sensors == ("Temp (°F)  #9724974",)
    np.testing.assert_allclose(log.temperature_C[:, 0], 20 + 0.1 * np.arange(8), atol=1e-9)
    # a row without a reading inside the log stays (a dropout, bridged), and a time repeated with a reading is refused
    with pytest.raises(InputError, match="duplicate time"):
        read_temperature_log(write_csv(text.replace("8,11/22/26 08:07:00 AM", "8,11/22/26 08:06:00 AM")))


def test_a_time_column_named_by_its_unit_in_words(write_csv):
    """'Elapsed hours' or 'Seconds' was read as minutes: a 40-min test at 1 min lasted 0.67 min. A
    sensor named 'T min' is still a temperature."""
    for name, per_minute in (("Elapsed hours", 1 / 60), ("Seconds", 60.0), ("Time in minutes", 1.0)):
        log = read_temperature_log(
            write_csv(f"{name},T min\n" + "".join(f"{k * per_minute:.6f},{20 + k / 10:.1f}\n" for k in range(8)))
        )
        np.testing.assert_allclose(log.time_min, np.arange(8.0), atol=1e-3)
        assert log.sensors == ("T min",)


def test_a_machines_labels_are_no_units(write_csv):
    """'Bearing (RH)' (right-hand), '(A)', '(N)' label places on a machine: read as sensors, not
    left out as a humidity, an ampere or a newton."""
    log = read_temperature_log(
        write_csv(
            "time,Bearing (RH),Bearing (LH),Motor (A),Column (N),RH\n"
            + "".join(f"{k},{20 + k / 10:.1f},20,20,20,20\n" for k in range(8))
        )
    )
    assert log.sensors == ("Bearing (RH)", "Bearing (LH)", "Motor (A)", "Column (N)", "RH")


# a spindle from 20 °C to 100 °C (212 °F, 373.15 K) with a room at 20 °C, in °C; the tests write it in °F or
# K without a unit
_STATED_C = np.column_stack([20 + 80 * np.arange(12.0) / 11, np.full(12, 20.0)])


def _without_units(to_unit, units_row: str = "") -> str:
    rows = "".join(f"{m},{to_unit(spindle):.4f},{to_unit(room):.4f}\n" for m, (spindle, room) in enumerate(_STATED_C))
    return "time_min,spindle,room\n" + units_row + rows


@pytest.mark.parametrize(
    ("unit", "to_unit", "written"),
    [("F", lambda c: c * 9 / 5 + 32, "°F"), ("K", lambda c: c + 273.15, "K"), ("C", lambda c: c, "°C")],
)
def test_temperature_unit_states_the_unit_of_columns_that_state_none(write_csv, unit, to_unit, written):
    """Issue 37: a log in °F or K without a units row or a unit in its names was read as °C, with at
    most a note on a room far outside a workshop's range; ``temperature_unit`` states its unit, and
    every temperature column converts, the room's too (212 °F and 373.15 K are 100 °C)."""
    path = write_csv(_without_units(to_unit))
    assert path.read_text().splitlines()[-1] == f"11,{to_unit(100.0):.4f},{to_unit(20.0):.4f}"  # 212 °F, 373.15 K
    log = read_temperature_log(path, temperature_unit=unit)
    assert log.sensors == ("spindle", "room")
    np.testing.assert_allclose(log.temperature_C, _STATED_C, atol=1e-4)
    assert log.temperature_C[-1, 0] == pytest.approx(100.0)
    converted = [n for n in log.notes if "`temperature_unit`" in n]
    if unit == "C":
        assert not converted
    else:
        assert converted == [f"read in {written} (`temperature_unit`), converted to °C: spindle, room"]
    assert not any("workshop" in note for note in log.notes)  # the unit was stated: nothing is assumed
    if unit != "C":  # without the option the numbers are read as °C, as they are written
        plain = read_temperature_log(path)
        np.testing.assert_allclose(plain.temperature_C, to_unit(_STATED_C), atol=1e-4)


def test_the_note_on_a_room_read_as_celsius_names_the_unit_option(write_csv):
    log = read_temperature_log(write_csv(_without_units(lambda c: c * 9 / 5 + 32)))
    said = [note for note in log.notes if "far outside any workshop's range" in note]
    assert said and "`temperature_unit='F'`" in said[0], log.notes


@pytest.mark.parametrize(
    ("to_unit", "said"), [(lambda c: c * 1.8 + 32, "(in °F: 20.0 °C)"), (lambda c: c + 273.15, "(in K: 20.0 °C)")]
)
def test_one_column_in_another_unit_among_celsius_ones_is_refused(write_csv, to_unit, said):
    """A user's log with one sensor in °F among °C ones, no unit stated anywhere: T2 was read as
    starting at 68 °C and a stop with its T∞ of 77 °C trusted, the unit said only in a note. Such a
    log is refused, the message naming the column, what it would read converted, and both fixes;
    with every column stated to be in °C it is read."""
    rows = "".join(f"{m},{20 + 0.3 * m:.2f},{to_unit(20 + 0.2 * m):.2f},20.0\n" for m in range(30))
    path = write_csv("time_min,T1,T2,room\n" + rows)
    with pytest.raises(InputError, match="where the other columns start near 20.0 °C") as refused:
        read_temperature_log(path)
    assert "'T2' starts at" in str(refused.value) and said in str(refused.value)
    unit = said[4:6].strip(":")
    assert f"the unit in its name (T2 [{unit}])" in str(refused.value) and "`temperature_unit='C'`" in str(
        refused.value
    )
    stated = read_temperature_log(path, temperature_unit="C")
    assert stated.temperature_C[0, 1] == pytest.approx(to_unit(20.0), abs=0.01)
    # the same log followed as it grows is refused alike
    with pytest.raises(InputError, match="'T2' starts at"):
        LogFollower(path).poll()
    # a part already hot in °C (45 °C, which in °F would be 7.2 °C): read, nothing said
    plain = "".join(f"{m},{20 + 0.3 * m:.2f},{45 + 0.2 * m:.2f},20.0\n" for m in range(30))
    assert not [
        n
        for n in read_temperature_log(write_csv("time_min,T1,T2,room\n" + plain, name="hot.csv")).notes
        if "other columns start" in n
    ]


def test_a_log_in_celsius_read_in_a_stated_unit_is_said_to_read_outside_any_workshop(write_csv):
    """A new user's log in °C read with --unit F: the room at -6.7 °C and a bearing's T∞ at 0.03 °C
    were answered and trusted without a word; the note asks whether the log is in °C already. Read
    as K, the same log is refused (-253 °C is an open circuit), the error naming the unit, not the
    wiring."""
    log = read_temperature_log(write_csv(_without_units(lambda c: c)), temperature_unit="F")
    assert log.temperature_C[0, 1] == pytest.approx(-6.67, abs=0.01)
    said = [note for note in log.notes if "far outside any workshop's range" in note]
    assert len(said) == 1 and "converted from °F as stated (`temperature_unit='F'`)" in said[0], log.notes
    assert "'room' reads" in said[0] and "If the log is in °C already, leave the unit out" in said[0]
    with pytest.raises(InputError, match=r"converted to °C from the unit stated, and as written they lie within"):
        read_temperature_log(write_csv(_without_units(lambda c: c), name="again.csv"), temperature_unit="K")


def test_a_log_without_a_room_read_in_a_stated_unit_below_any_workshop_is_said_so(write_csv):
    path = write_csv("time_min,spindle,column\n" + "".join(f"{m},{20 + m},{20 + m / 2}\n" for m in range(12)))
    log = read_temperature_log(path, temperature_unit="F")
    said = [note for note in log.notes if "far outside any workshop's range" in note]
    assert len(said) == 1 and "every column reads below 5 °C (the highest -0.556)" in said[0], log.notes


@pytest.mark.parametrize(
    ("header", "units_row", "unit", "message"),
    [
        ("time_min,spindle,room", "min,°C,\n", "F", "sensor 'spindle' is in °C by the units row"),
        ("time_min,spindle [K],room", "", "F", "sensor 'spindle [K]' is in K by its name"),
        ("time_min,spindle,room (°F)", "", "K", "sensor 'room (°F)' is in °F by its name"),
        ("time_min,spindle,room", "min,K,°F\n", "C", "sensor 'spindle' is in K by the units row"),
    ],
)
def test_a_columns_own_unit_that_temperature_unit_contradicts_is_refused(write_csv, header, units_row, unit, message):
    """Which of the two is right cannot be told: the column is refused, named with its unit and the option."""
    rows = "".join(f"{m},{300 + m},{70 + m / 10}\n" for m in range(8))
    path = write_csv(header + "\n" + units_row + rows)
    with pytest.raises(InputError, match=re.escape(message) + f".*`temperature_unit='{unit}'`"):
        read_temperature_log(path, temperature_unit=unit)
    read_temperature_log(path)  # read in its own units without the option


def test_temperature_unit_leaves_a_columns_own_unit_that_agrees_and_other_quantities_alone(write_csv):
    """A column in °F by its name is read in °F with ``temperature_unit='F'``; one in rpm by the units
    row is no temperature whatever the option says; a humidity named as one is left out."""
    rows = "".join(f"{m},{212 - m},{32 + m},{1000 + m},{50 + m}\n" for m in range(8))
    log = read_temperature_log(
        write_csv("time_min,T1 [°F],T2,speed,Humidity\nmin,,,rpm,\n" + rows), temperature_unit="F"
    )
    assert log.sensors == ("T1 [°F]", "T2")
    np.testing.assert_allclose(log.temperature_C[:, 0], (212 - np.arange(8.0) - 32) * 5 / 9)
    np.testing.assert_allclose(log.temperature_C[:, 1], np.arange(8.0) * 5 / 9)
    with pytest.raises(InputError, match=r"temperature unit 'X' is not one of: C, F, K"):
        read_temperature_log(write_csv("time_min,T1\n" + rows.replace(",", ";")), temperature_unit="X")


@pytest.mark.parametrize(("unit", "said"), [("c", None), ("°C", None), ("celsius", None), ("°F", "°F"), ("F", "°F")])
def test_a_stated_unit_is_read_as_the_reader_reads_it_in_the_note(write_csv, unit, said):
    """A reviewer's finding: 'c', '°C' and 'celsius' were told to leave the unit out, '°F' was '°°F'."""
    log = read_temperature_log(write_csv(_without_units(lambda c: c)), temperature_unit=unit)
    notes = [note for note in log.notes if "far outside any workshop's range" in note]
    if said is None:
        assert not notes, notes
    else:
        assert len(notes) == 1 and f"converted from {said} as stated" in notes[0] and "°°" not in notes[0]


def test_a_column_whose_own_unit_puts_it_out_of_range_is_not_blamed_on_a_stated_unit(write_csv):
    path = write_csv("time_min,spindle [K],column [K]\n" + "".join(f"{m},{20 + m},{20 + m / 2}\n" for m in range(12)))
    with pytest.raises(InputError, match="check the wiring") as refused:
        read_temperature_log(path)
    assert "leave the unit out" not in str(refused.value)


def test_columns_named_as_another_quantity_are_left_out_with_a_note(write_csv):
    """A new user's log with a power and a speed channel beside the temperatures ("P_kW",
    "Drehzahl", "Spindle speed"): each was read as a °C sensor, held the stop for good ("no rise")
    or refused the whole log (8000 "°C"). They are left out by their names, said in a note; a name
    that also says it is a temperature is kept, and a column asked for by name is read."""
    header = "time_min,T1,P_kW,Drehzahl,Spindle speed,Speed side bearing temp,Bearing load side\n"
    rows = "".join(f"{m},{20 + 0.1 * m:.2f},3.5,8000,8000,{20 + 0.05 * m:.2f},{20 + 0.02 * m:.2f}\n" for m in range(30))
    path = write_csv(header + rows)
    log = read_temperature_log(path)
    assert log.sensors == ("T1", "Speed side bearing temp", "Bearing load side")
    said = [n for n in log.notes if n.startswith("left out, named as another quantity")]
    assert said and said[0].endswith(": P_kW, Drehzahl, Spindle speed"), log.notes
    assert read_temperature_log(path, sensors=["P_kW"]).sensors == ("P_kW",)


def test_readings_that_carry_their_unit_are_read_by_it_column_by_column(write_csv):
    """A new user's log with one column whose cells carry "°F" beside plain °C columns: the column was
    left out as having "no numbers in them"; it is read, converted. A reading carrying another unit than
    its column's ("23.1 °F" among "°C" cells, read as 23.1 °C without a word) is refused by its row."""
    rows = "".join(f"{m},{20 + 0.1 * m:.2f},{(20 + 0.1 * m) * 1.8 + 32:.2f} °F\n" for m in range(30))
    log = read_temperature_log(write_csv("time_min,T1,T3\n" + rows))
    assert log.sensors == ("T1", "T3")
    np.testing.assert_allclose(log.temperature_C[:, 1], log.temperature_C[:, 0], atol=0.01)
    mixed = "".join(f"{m},{20 + 0.1 * m:.2f} °C\n" if m != 7 else f"{m},23.1 °F\n" for m in range(30))
    with pytest.raises(InputError, match=r"sensor 'T1', row 9: '23.1 °F' carries another unit than the column's"):
        read_temperature_log(write_csv("time_min,T1\n" + mixed, name="mixed.csv"))


def test_units_the_log_states_against_each_other_or_its_readings_are_refused(write_csv):
    """A time column named 'time_min' over a units row of 'h' was read as minutes without a word,
    and a units row of °F over a column in °C put it at −6.6 °C beside 20 °C ones: each is refused,
    saying what disagrees and how to mend it; the time unit given settles the first."""
    rows = "".join(
        f"{m / 10:g};{20 + m / 10:.2f};{20 + m / 20:.2f};{20 + m / 15:.2f}\n".replace(".", ",") for m in range(8)
    )
    times = write_csv("time_min;T1;T2;T3\nh;°C;°C;°C\n" + rows, name="times.csv")
    with pytest.raises(InputError, match=r"time column 'time_min': its name says 'min', but the log states 'h'"):
        read_temperature_log(times)
    assert read_temperature_log(times, time_unit="h").time_min[1] == pytest.approx(6.0)
    wrong = write_csv("time_min;T1;T2;T3\nmin;°C;°C;°F\n" + rows, name="wrong.csv")
    with pytest.raises(InputError, match=r"'T3' is in °F by the units row, which starts it at -6.7 °C, where the"):
        read_temperature_log(wrong)
