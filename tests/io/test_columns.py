"""Tests of :mod:`mtident.io.columns`."""

from __future__ import annotations

import re

import numpy as np
import pytest

from mtident.exceptions import InputError
from mtident.io import read_temperature_log


@pytest.mark.parametrize(
    ("name", "room"),
    [
        ("room", True),
        ("T_room", True),
        ("Raumtemperatur", True),
        ("AmbientTemp", True),
        ("CH3 Ambient", True),
        ("T_amb", True),
        ("TAmb", True),
        ("Tamb", True),
        ("Air temp", True),
        ("AirTemp", True),
        ("Umgebung", True),
        ("Halle", True),
        ("Raum", True),
        ("ambient_T", True),
        ("Hall", True),
        ("room temp (C)", True),
        ("environment", True),
        ("Raumluft", True),
        ("Werkhalle", True),
        ("Werkstatt", True),
        ("Surroundings", True),
        ("T_surr", True),
        ("Tenv", True),
        ("T_Umg", True),
        # a room's word inside another word, and machine sensors
        ("Bauraum", False),  # the machine's work space
        ("Arbeitsraum", False),
        ("Chair", False),
        ("Shall", False),
        ("Envelope", False),
        ("T1", False),
        ("TC1 (Spindle)", False),
        ("Bearing front", False),
    ],
)
def test_a_column_named_as_the_room_is_told_from_machine_sensors(name, room):
    from mtident.io.columns import room_named

    assert room_named(name) is room


def test_a_room_column_left_unread_is_found_unless_its_name_says_it_is_no_temperature():
    """A room column that --sensor left out was passed over without a word; a room's humidity, a
    column in % named after the room is no room sensor."""
    from mtident.io.columns import unread_rooms

    header = ["Zeit", "T1", "T2", "Umgebung", "Room humidity", "Raumfeuchte", "Hall [%]", "T_amb [°F]"]
    assert unread_rooms(header, ["T1"]) == ["Umgebung", "T_amb [°F]"]
    assert unread_rooms(header, ("T1", "Umgebung", "T_amb [°F]")) == []


def test_time_column_by_name(write_csv):
    log = read_temperature_log(
        write_csv("A,minute,B\n20,0,30\n21,1,31\n22,2,32\n23,3,33\n24,4,34\n"), time_col="minute"
    )
    assert log.sensors == ("A", "B")
    np.testing.assert_allclose(log.temperature_C[:, 1], [30, 31, 32, 33, 34])


def test_a_text_column_is_no_sensor_unless_asked_for(write_csv):
    """A logger's status channel ('OK' in every row) stopped identify: "'OK' is not a number", and
    watch showed it as a sensor without data."""
    from mtident.io.follow import LogFollower

    text = "time,T1,Status\n" + "".join(f"{m},{20 + m / 10:.1f},OK\n" for m in range(10))
    log = read_temperature_log(write_csv(text))
    assert log.sensors == ("T1",) and log.notes == ("left out, no numbers in them: Status",)
    follower = LogFollower(write_csv(text, "live.csv"))
    rows = follower.poll()
    assert rows.notes == ("left out, no numbers in them: Status",) and not rows.warnings and follower.sensors == ["T1"]
    with pytest.raises(InputError, match=r"sensor 'Status', row 2: 'OK' is not a number"):
        read_temperature_log(write_csv(text), sensors=["T1", "Status"])
    # a sensor with one bad cell is still refused by name: it has numbers
    with pytest.raises(InputError, match=r"sensor 'T1', row 4: 'oops' is not a number"):
        read_temperature_log(write_csv(text.replace("2,20.2", "2,oops")))


def test_real_logger_exports_name_their_channels_and_leave_out_the_rest(write_csv):
    """Layouts of real exports (public test files of a logger-graphing project), each refused
    before: Tinytag's unnamed counter, numbered channels, description rows and units in the cells
    ("'S/N' is neither a number nor a time stamp"); T&D's unnamed stamp column with serial dates
    beside it ("row 2 is empty"). The humidity and light channels are left out, and named; so is
    the dew point (in °C, read as a sensor before), by the Property row or by its name (EasyLog)."""
    tinytag = (
        ",Time,1,2,3\nS/N,,227659,227659,227659\nType,,Tinytag Ultra H°C/%RH,Tinytag Ultra H°C/%RH,csv "
        "file\nDescription,,Spindle,Spindle,Spindle\nProperty,,Temperature,Humidity,Dew Point\n"
    )
    tinytag += "".join(
        f"{k + 1},2026-11-22 08:{k:02d}:00,{20 + k / 10:.1f} °C,{56 + k / 100:.1f} %RH,{8 + k / 10:.1f} °C\n"
        for k in range(8)
    )
    log = read_temperature_log(write_csv(tinytag))
    assert log.sensors == ("1",)
    assert (
        "left out, computed from the humidity (a dew point, wet-bulb temperature or heat index; `sensors` reads one "
        "all the same): 3" in log.notes
    )
    assert read_temperature_log(write_csv(tinytag), sensors=["3"]).temperature_C[0, 0] == 8.0
    np.testing.assert_allclose(log.temperature_C[:, 0], 20 + np.arange(8) / 10)
    np.testing.assert_allclose(log.time_min, np.arange(8.0))
    assert "left out, a row counter: the unnamed first column; the time is 'Time'" in log.notes
    from mtident.io.follow import LogFollower

    followed = LogFollower(write_csv(tinytag, "live.csv"))
    assert followed.poll().notes[
        0
    ] == "left out, a row counter: the unnamed first column; the time is 'Time'" and followed.sensors == ["1"]
    assert "left out, not temperatures by its cells: 2 (%RH)" in log.notes
    # the older export writes no units in the cells: the Property row names the humidity
    plain = re.sub(r" (°C|%RH)", "", tinytag)
    assert read_temperature_log(write_csv(plain)).sensors == ("1",)
    easylog = "Comedor,Time,Celsius(°C),Humidity(%rh),Dew Point(°C),Serial Number\n"
    easylog += "".join(
        f"{k + 1},2026-11-22 08:{k:02d}:00,{20 + k / 10:.1f},{56 + k / 100:.1f},{8 + k / 10:.1f}{',10543212' if k == 0 else ''}\n"
        for k in range(8)
    )
    log = read_temperature_log(write_csv(easylog))
    assert log.sensors == ("Celsius(°C)",) and any(
        n.endswith("heat index; `sensors` reads one all the same): Dew Point(°C)") for n in log.notes
    )
    tandd = ",Date/Time,No.1,No.2,No.3,No.4,\n,Date/Time,ch1,ch2,ch3,ch4,\n,,lx,mW/cm2,°C,%,\n"
    tandd += "".join(
        f"2026-11-22 08:{k:02d}:00,{46348.333333 + k / 1440:.5f},6.27,0,{20 + k / 10:.1f},51,\n" for k in range(8)
    )
    log = read_temperature_log(write_csv(tandd))
    assert log.sensors == ("No.3",)
    assert (
        "left out, named as times: Date/Time" in log.notes
        and "left out, not temperatures by the units row: No.1 (lx), No.2 (mW/cm2), No.4 (%)" in log.notes
    )
    meaco = "RECEIVER,TRANSMITTER,DATE,TEMPERATURE,HUMIDITY\n" + "".join(
        f'"Shop","Spindle","2026-11-22 08:{k:02d}",{20 + k / 10:.2f},55.1\n' for k in range(8)
    )
    log = read_temperature_log(write_csv(meaco))
    assert log.sensors == ("TEMPERATURE",) and "the time is 'DATE', the first column of time stamps" in log.notes
    with pytest.raises(InputError, match="sensor 'HUMIDITY' is a humidity by its name, not a temperature"):
        read_temperature_log(write_csv(meaco), sensors=["HUMIDITY"])
    # a bad first data row is still refused, not taken for a row that describes the channels
    with pytest.raises(InputError, match="row 2: 'yesterday' is neither a number nor a time stamp"):
        read_temperature_log(write_csv("time,A\nyesterday,20\n" + "".join(f"{k},20\n" for k in range(1, 6))))


def test_a_log_of_nothing_but_left_out_columns_says_what_it_left_out(write_csv):
    """With every column left out, the message listed nothing: 'no temperature column: its name gives '."""
    with pytest.raises(
        InputError,
        match=r"no temperature column; left out: Status \(the logger.s own record\); by its name: RH/% \(`sensors=\[NAME\]`",
    ):
        read_temperature_log(write_csv("time,Status,RH/%\n" + "".join(f"{k},1,50\n" for k in range(6))))


def test_a_column_named_with_another_case_or_a_slip_is_pointed_to(write_csv):
    path = write_csv("time_min,Spindle,room\n" + "".join(f"{k},{20 + k / 10:.2f},19.9\n" for k in range(8)))
    with pytest.raises(
        InputError, match=r"no sensor column 'Room' \(did you mean 'room'\?\); the log has: Spindle, room"
    ):
        read_temperature_log(path, sensors=["Room"])
    with pytest.raises(InputError, match=r"no sensor column 'Spindel' \(did you mean 'Spindle'\?\)"):
        read_temperature_log(path, sensors=["Spindel"])
    with pytest.raises(InputError, match=r"no sensor column 'T9'; the log has"):
        read_temperature_log(path, sensors=["T9"])
