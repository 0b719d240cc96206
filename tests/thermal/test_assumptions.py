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


def test_the_machine_model_is_said_only_where_the_answer_comes_with_it():
    """A new user's `identify --sensor column --reference`: one sensor, so no machine model, but its
    assumptions said "the machine model: every sensor fitted together"."""
    from mtident.thermal.assumptions import describe_assumptions
    from mtident.thermal.machine_model import MachineModel
    from mtident.thermal.robust import RobustSettings

    model = MachineModel(("A", "B"), (120.0, 20.0), (0.05, 0.05), ((-1.0, -0.5), (-0.8, -0.2)))
    modes = {name: SensorModes((120.0, 20.0), (0.05, 0.05)) for name in "AB"}
    reference = MachineReference("run.csv", "2026-11-25", 300.0, "not measured", modes, machine_model=model)
    with_model = describe_assumptions(RobustSettings(), None, reference, "A").reference
    alone = describe_assumptions(RobustSettings(), None, reference, "A", machine_used=False).reference
    assert with_model is not None and "; and the machine model: every sensor fitted together" in with_model
    assert alone is not None and "machine model" not in alone and with_model.startswith(alone)
