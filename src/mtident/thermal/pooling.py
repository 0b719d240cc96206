"""Pooling the references of several complete runs of one machine into one.

A machine's time constants belong to its structure, not to one run: every complete warm-up of
the same machine (a reference run, or a test that ran on until its sensors settled) measures
them again. Where two runs agree, their boxes pool as two independent measurements of the same
log time constant (each box is :data:`~mtident.thermal.reference_learning.BOX_SDS` standard
deviations either side); where they do not, the pooled box holds both, and the answer says so.
"""

from __future__ import annotations

import math
from dataclasses import replace

from mtident.thermal.machine_model import TAU_BOX_MIN, MachineModel
from mtident.thermal.reference import MachineReference
from mtident.thermal.robust import MIN_REFERENCE_BOX
from mtident.thermal.robust_types import SensorModes

__all__ = ["pool_references"]


def pool_references(first: MachineReference, later: MachineReference) -> tuple[MachineReference, list[str]]:
    """One reference from two of the same machine: each sensor's and the machine model's time
    constants pooled where the runs agree, a box holding both where they do not.

    Parameters
    ----------
    first : MachineReference
        The reference so far (its machine, serial, program and room are kept where ``later``
        does not say them).
    later : MachineReference
        Another complete run of the same machine.

    Returns
    -------
    MachineReference
    list of str
        What the pooling changed beyond narrowing: modes that disagree, mode counts that differ,
        sensors only one run knows, a machine model only one run has.
    """
    said: list[str] = []
    sensors: dict[str, SensorModes] = {}
    for name in (*first.sensors, *(n for n in later.sensors if n not in first.sensors)):
        a, b = first.sensors.get(name), later.sensors.get(name)
        if a is None or b is None:
            sensors[name] = next(m for m in (a, b) if m is not None)
            said.append(f"{name}: only one run has its modes; they are kept as that run learnt them")
            continue
        sensors[name], note = _pooled_sensor(name, a, b)
        said.extend(note)
    model, note = _pooled_model(first.machine_model, later.machine_model)
    said.extend(note)
    pooled = replace(
        first,
        source=f"{first.source} + {later.source}",
        learnt_on=max(first.learnt_on, later.learnt_on),
        max_time_constant_min=max(first.max_time_constant_min, later.max_time_constant_min),
        room=first.room if first.room == later.room else f"{first.room}; {later.room}",
        sensors=sensors,
        machine=first.machine or later.machine,
        serial=first.serial or later.serial,
        program=first.program if first.program == later.program else _both(first.program, later.program),
        run_date=first.run_date if first.run_date == later.run_date else _both(first.run_date, later.run_date),
        machine_model=model,
    )
    return pooled, said


def _both(first: str, later: str) -> str:
    return " + ".join(p for p in (first, later) if p)


def _pooled_sensor(name: str, a: SensorModes, b: SensorModes) -> tuple[SensorModes, list[str]]:
    """A sensor's modes from two runs: a doubtful run's left out; of two mode counts the larger
    kept (a run that shows fewer modes may have missed one); else each mode pooled."""
    if a.doubt is not None or b.doubt is not None:
        kept = b if a.doubt is not None and b.doubt is None else a
        both = a.doubt is not None and b.doubt is not None
        return kept, [] if both else [f"{name}: one run did not pin it down; the other's modes kept"]
    if len(a.time_constants_min) != len(b.time_constants_min):
        kept = a if len(a.time_constants_min) > len(b.time_constants_min) else b
        return kept, [
            f"{name}: the runs learnt {len(a.time_constants_min)} and {len(b.time_constants_min)} modes; the "
            f"{len(kept.time_constants_min)} kept (a run may miss a mode, not invent one beyond chance)"
        ]
    centres, boxes, apart = _pooled_boxes(a.time_constants_min, a.box, b.time_constants_min, b.box, MIN_REFERENCE_BOX)
    free = [m for m in (a.free_fast_modes, b.free_fast_modes) if m is not None]
    pooled = SensorModes(centres, boxes, a.amplitudes_C, None, min(free) if free else None)
    return pooled, [f"{name}: {text}" for text in apart]


def _pooled_model(a: MachineModel | None, b: MachineModel | None) -> tuple[MachineModel | None, list[str]]:
    """The machine model from two runs: pooled where both have one of the same sensors and modes
    (the shapes and the room's path of the first), else the first's (or the only one)."""
    if a is None or b is None:
        only = a if a is not None else b
        return only, ([] if only is None else ["the machine model is one run's: the other has none"])
    if a.sensors != b.sensors or len(a.time_constants_min) != len(b.time_constants_min):
        return a, ["the runs' machine models differ in their sensors or modes: the first's is kept"]
    centres, boxes, apart = _pooled_boxes(a.time_constants_min, a.box, b.time_constants_min, b.box, TAU_BOX_MIN)
    said = [f"machine model: {text}" for text in apart]
    if b.room_gains and not a.room_gains:
        # a run in a moving room pooled into one in a steady room: its path is not kept without a word
        said.append(
            f"machine model: the later run learnt the room's path into {b.learnt_room_sensors()}, which the "
            "reference so far has not (its room was steady or not logged); the pooled reference keeps the first's "
            "shapes and so no room path: learn from the run in the moving room first, then pool the other into it"
        )
    return replace(a, time_constants_min=centres, box=boxes), said


def _pooled_boxes(
    taus_a: tuple[float, ...],
    box_a: tuple[float, ...],
    taus_b: tuple[float, ...],
    box_b: tuple[float, ...],
    floor: float,
) -> tuple[tuple[float, ...], tuple[float, ...], list[str]]:
    """Each mode's centre and box from two runs' (modes paired in order of their time constants;
    a pooled box at least ``floor``), and what was said of those that disagree."""
    order_a = sorted(range(len(taus_a)), key=lambda k: taus_a[k])
    order_b = sorted(range(len(taus_b)), key=lambda k: taus_b[k])
    centres = list(taus_a)
    boxes = list(box_a)
    said = []
    for ka, kb in zip(order_a, order_b, strict=True):
        (ca, ra), (cb, rb) = _log_box(taus_a[ka], box_a[ka]), _log_box(taus_b[kb], box_b[kb])
        if abs(ca - cb) <= math.hypot(ra, rb):
            weight_a, weight_b = 1.0 / ra**2, 1.0 / rb**2
            centre = (weight_a * ca + weight_b * cb) / (weight_a + weight_b)
            reach = max(1.0 / math.sqrt(weight_a + weight_b), math.atanh(floor))
        else:
            low, high = min(ca - ra, cb - rb), max(ca + ra, cb + rb)
            centre, reach = (low + high) / 2.0, (high - low) / 2.0
            said.append(
                f"its mode of {taus_a[ka]:.3g} min ±{box_a[ka]:.0%} in one run is {taus_b[kb]:.3g} min "
                f"±{box_b[kb]:.0%} in the other; the box holds both"
            )
        centres[ka], boxes[ka] = _linear_box(centre, reach)
    return tuple(centres), tuple(boxes), said


# a box as wide as its mode or wider (a mode its run could not pin down: 2.78 min ±106 %) reaches
# down to this share of its centre: its log range has an end, and the pooled box leans on the other run
_LOWEST_SHARE = 1e-3


def _log_box(centre: float, box: float) -> tuple[float, float]:
    """A box (centre, relative half-width) as the middle and half-width of its log range."""
    low, high = centre * max(1.0 - box, _LOWEST_SHARE), centre * (1.0 + box)
    return 0.5 * math.log(low * high), 0.5 * math.log(high / low)


def _linear_box(log_centre: float, reach: float) -> tuple[float, float]:
    """A log range's middle and half-width as a box (centre, relative half-width)."""
    low, high = math.exp(log_centre - reach), math.exp(log_centre + reach)
    return (low + high) / 2.0, (high - low) / (high + low)
