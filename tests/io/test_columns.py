"""Tests of :mod:`mtident.io.columns`."""

from __future__ import annotations

import pytest


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
        # a room's word inside another word, and machine sensors
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
