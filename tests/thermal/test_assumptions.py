"""Tests of :mod:`mtident.thermal.assumptions`."""

from __future__ import annotations

from mtident.thermal.reference import MachineReference
from mtident.thermal.robust import SensorModes


def test_the_assumptions_say_how_many_free_modes_a_reference_leaves_room_for():
    """Two free modes by default, but never more than four modes in all: a reference of three
    modes leaves room for one, and the assumptions say why it is not two."""
    from mtident.thermal.assumptions import describe_assumptions
    from mtident.thermal.robust import RobustSettings

    reference = MachineReference(
        "run.csv",
        "2026-11-25",
        300.0,
        "not measured",
        {"A": SensorModes((60.0,), (0.1,)), "B": SensorModes((60.0, 12.0, 2.0), (0.1, 0.1, 0.3))},
    )
    one, three = (describe_assumptions(RobustSettings(), None, reference, s).reference for s in "AB")
    assert one is not None and one.endswith("; up to 2 free modes faster than the slowest of these")
    assert three is not None and three.endswith("; up to 1 free mode faster than the slowest of these (4 modes in all)")
    said = describe_assumptions(RobustSettings(free_fast_modes=1), None, reference, "B").reference
    assert said is not None and said.endswith("; up to 1 free mode faster than the slowest of these")
