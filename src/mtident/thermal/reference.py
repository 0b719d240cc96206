"""Reference runs: learn a machine's thermal modes once, from a warm-up that ran to equilibrium.

A machine's time constants belong to its structure (masses, conductances, the coolant), not to
the load: a later test at another speed, from another start, has other amplitudes but the same
time constants. :func:`~mtident.thermal.reference_learning.learn_reference` identifies each
sensor's modes with their uncertainty from one complete run; a later ``identify`` or ``watch``
searches the time constants only within those boxes (never as exact), which is what lets a test
stop early and safely.

This module holds the reference itself (:class:`MachineReference`), its file
(:func:`save_reference`, :func:`load_reference`) and its use for a log
(:func:`reference_for_log`); :mod:`mtident.thermal.reference_learning` learns it from a run.
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Callable
from dataclasses import dataclass, replace
from pathlib import Path

from mtident.exceptions import InputError
from mtident.io.units import name_without_unit
from mtident.thermal.machine_model import MAX_MODES as MACHINE_MAX_MODES
from mtident.thermal.machine_model import MachineModel
from mtident.thermal.robust import MIN_REFERENCE_BOX
from mtident.thermal.robust_types import DEFAULT_MAX_MODES, MAX_FREE_FAST, SensorModes

__all__ = [
    "MachineReference",
    "load_reference",
    "reference_for_log",
    "save_reference",
]

# how a reference learnt with a room sensor says so in its file
ROOM_MEASURED = "a room sensor, an input of every mode"
_HEADER = """# mtident reference run: each sensor's thermal modes, learnt from a warm-up that ran to
# equilibrium. `mtident thermal identify|watch LOG --reference THIS_FILE` searches each sensor's
# time constants only within ±box of these (relative), with free amplitudes, and says so when a
# new test does not follow them (a changed machine). A sensor with a `doubt` is not used: the run
# did not pin it down (delete the line only if you know the run reached equilibrium). A sensor
# with `free_fast_modes = 0` (`learn --every-mode`) is said to have no mode faster than these:
# later tests stop earliest, and state that assumption.
"""


@dataclass(frozen=True)
class MachineReference:
    """A machine's modes per sensor, learnt from one complete warm-up.

    Parameters
    ----------
    source : str
        The log it was learnt from.
    learnt_on : str
        ISO date.
    max_time_constant_min : float
        The largest time constant searched when learning.
    room : str
        How the room was taken when learning.
    sensors : dict of str to SensorModes
        Each sensor's modes, by its name.
    machine, serial, program, run_date : str
        What the run was of, as ``learn`` was told ("" where not said): the machine, its serial
        number, the program or speed it ran, and the day it ran.
    machine_model : MachineModel, optional
        Every sensor together: the modes they share and each mode's amplitudes across them
        (None for a reference of one sensor, or one written before the machine model).
    """

    source: str
    learnt_on: str
    max_time_constant_min: float
    room: str
    sensors: dict[str, SensorModes]
    machine: str = ""
    serial: str = ""
    program: str = ""
    run_date: str = ""
    machine_model: MachineModel | None = None

    @property
    def identity(self) -> str:
        """What the reference is of, in words: machine, serial, program and the run's day, as far
        as ``learn`` was told them, else the log it was learnt from.

        Returns
        -------
        str
        """
        said = self._said()
        return f"{said} ({self.source})" if said else self.source

    def _said(self) -> str:
        parts = [
            f"machine {self.machine}" if self.machine else "",
            f"serial {self.serial}" if self.serial else "",
            f"program {self.program}" if self.program else "",
            f"run on {self.run_date}" if self.run_date else "",
        ]
        return ", ".join(p for p in parts if p)

    def for_machine(self, machine: str | None) -> MachineReference:
        """The reference, checked against the machine a test says it is of.

        Parameters
        ----------
        machine : str or None
            The test's machine (None: not said).

        Returns
        -------
        MachineReference
            Itself.

        Raises
        ------
        InputError
            The reference names another machine, or a machine is said and the reference names none.
        """
        if machine is None or machine == self.machine:
            return self
        if not self.machine:
            msg = (
                f"the reference ({self.source}) does not say which machine it is of, and this test says {machine!r}: "
                f"learn it again with --machine {machine}, or leave out --machine"
            )
        else:
            msg = (
                f"the reference is of machine {self.machine!r} ({self.identity}), and this test says it is of "
                f"{machine!r}: a reference teaches only the machine it was learnt on; give that machine's reference"
            )
        raise InputError(msg)

    @property
    def room_measured(self) -> bool:
        """Whether the reference run was learnt with a room sensor (the room an input of every mode)."""
        return self.room == ROOM_MEASURED

    def modes(self, sensor: str) -> SensorModes | None:
        """The modes of ``sensor`` (None if the reference does not know it).

        Parameters
        ----------
        sensor : str
            The sensor's name.

        Returns
        -------
        SensorModes or None
        """
        return self.sensors.get(sensor)

    def named_as(self, sensors: tuple[str, ...] | list[str]) -> MachineReference:
        """The reference with its sensors named as a log names them, where a name differs only by a
        unit at its end (:func:`~mtident.io.units.name_without_unit`): a test logged with
        "T5 [°F]" is the reference run's "T5" (it was answered without its modes, and never
        stopped). A name the log has as it is, or that matches none or two, stays.

        Parameters
        ----------
        sensors : sequence of str
            The log's sensors.

        Returns
        -------
        MachineReference
        """
        known = {name_without_unit(name): name for name in self.sensors}
        renamed = {}
        for name in sensors:
            base = name_without_unit(name)
            ours = known.get(base)
            if name in self.sensors or ours is None or ours in sensors or ours in renamed:
                continue
            if sum(name_without_unit(other) == base for other in sensors) == 1:
                renamed[ours] = name
        if not renamed:
            return self
        model = self.machine_model
        if model is not None:
            model = replace(model, sensors=tuple(renamed.get(name, name) for name in model.sensors))
        return replace(
            self, sensors={renamed.get(name, name): m for name, m in self.sensors.items()}, machine_model=model
        )

    def describe(self, sensor: str) -> str:
        """One line for the answer's assumptions.

        Parameters
        ----------
        sensor : str
            As for :meth:`modes`.

        Returns
        -------
        str
            The log it was learnt from, the date and the sensor's time constants with their boxes, or
            that it has no modes for the sensor.
        """
        modes = self.sensors.get(sensor)
        if modes is None:
            return f"{self.source}: no modes for this sensor"
        parts = modes.box_words(" min")
        if modes.doubt is not None:
            parts += " (doubtful)"
        said = self._said()
        return f"{said + ': ' if said else ''}{self.source} (learnt {self.learnt_on}): τ {parts}"

    def holding_every_mode(self) -> MachineReference:
        """The same reference, said to hold every mode of the machine: later tests allow no free
        mode faster than each sensor's (an assumption they state).

        Returns
        -------
        MachineReference
        """
        sensors = {name: replace(m, free_fast_modes=0) for name, m in self.sensors.items()}
        return replace(self, sensors=sensors)


def reference_for_log(
    reference: MachineReference, sensors: tuple[str, ...], with_room: bool, room_sensor: str | None = None
) -> tuple[MachineReference, list[str]]:
    """The reference with its sensors named as the log names them (:meth:`MachineReference.named_as`),
    and what a test should be told of how it fits, or an error where it fits none of
    the log's sensors (another machine's, or columns renamed since: a test answered without it all
    through is not what was asked for). The notes: sensors of its log the reference has no modes
    for (a column renamed since the reference run is answered without its modes, and only its
    assumptions would say so), and a reference learnt with a room sensor used by a test without
    one (its modes are the machine's either way, but the answer then rests on the room's stated
    wander, and a room that drifts may take it off the reference).

    Parameters
    ----------
    reference : MachineReference
    sensors : tuple of str
        The log's sensors.
    with_room : bool
        Whether this test has a room sensor.
    room_sensor : str, optional
        Its name: a reference that learnt that column as a machine sensor did not take the room as
        an input.

    Returns
    -------
    MachineReference
        The reference as the log names its sensors.
    list of str
        The notes, none where the reference fits.

    Raises
    ------
    InputError
        The reference has modes for none of the log's sensors.
    """
    reference = reference.named_as(sensors)
    notes = []
    missing = [name for name in sensors if name not in reference.sensors]
    if sensors and len(missing) == len(sensors):
        msg = (
            f"the reference (learnt from {reference.source}) has modes for none of this log's sensors "
            f"({', '.join(repr(n) for n in sensors)}); it knows {', '.join(repr(n) for n in reference.sensors)}. "
            "Give the reference learnt from this machine, or rename the log's columns to the reference run's"
        )
        raise InputError(msg)
    if missing:
        notes.append(
            f"the reference ({reference.source}) has no modes for {', '.join(repr(n) for n in missing)}: "
            f"{'they are' if len(missing) > 1 else 'it is'} answered without it (the reference knows "
            f"{', '.join(repr(n) for n in reference.sensors)}; a renamed column keeps its modes only under its old "
            "name)"
        )
    if not with_room and reference.room_measured:
        notes.append(
            f"the reference ({reference.source}) was learnt with a room sensor, and this test has none: its answer "
            "assumes the room's stated wander; the room's column, where it was logged, keeps a drifting room out"
        )
    if room_sensor is not None and room_sensor in reference.sensors:
        notes.append(
            f"the reference ({reference.source}) learnt {room_sensor!r}, this test's room sensor, as a machine sensor, "
            "and the others without the room as an input: learn it again with that column given as the room sensor"
        )
    return reference, notes


def save_reference(reference: MachineReference, path: str | Path) -> None:
    """Write a reference as a commented TOML file.

    Parameters
    ----------
    reference : MachineReference
    path : str or Path
    """
    import tomli_w

    said = {
        key: value
        for key, value in (
            ("machine", reference.machine),
            ("serial", reference.serial),
            ("program", reference.program),
            ("run_date", reference.run_date),
        )
        if value
    }
    doc = {
        **said,
        "source": reference.source,
        "learnt_on": reference.learnt_on,
        "max_time_constant_min": reference.max_time_constant_min,
        "room": reference.room,
        "sensors": {
            name: {
                "time_constants_min": list(m.time_constants_min),
                "box": list(m.box),
                "amplitudes_C": list(m.amplitudes_C),
                **({"doubt": m.doubt} if m.doubt is not None else {}),
                **({"free_fast_modes": m.free_fast_modes} if m.free_fast_modes is not None else {}),
            }
            for name, m in reference.sensors.items()
        },
    }
    model = reference.machine_model
    if model is not None:
        table: dict[str, object] = {
            "time_constants_min": list(model.time_constants_min),
            "box": list(model.box),
            "gains_C": {
                name: list(row)
                for name, row in zip(model.sensors, model.gains_C, strict=True)
                if all(map(math.isfinite, row))
            },
        }
        learnt = zip(model.sensors, model.room_gains, model.room_gain_cov, strict=True) if model.room_gains else ()
        room = {
            name: {"gains": list(row), "covariance": [list(r) for r in cov]}
            for name, row, cov in learnt
            if all(map(math.isfinite, row))
        }
        doc["machine_model"] = table | ({"room_response": room} if room else {})
    Path(path).write_text(_HEADER + tomli_w.dumps(doc), encoding="utf-8")


def load_reference(path: str | Path) -> MachineReference:
    """Read a reference written by :func:`save_reference` (or by hand).

    Parameters
    ----------
    path : str or Path

    Returns
    -------
    MachineReference

    Raises
    ------
    InputError
        Not a readable TOML file, or a sensor without positive time constants and boxes.
    """
    p = Path(path)
    try:
        doc = tomllib.loads(p.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        if p.is_dir():
            msg = f"{p}: a folder, not a reference file"
        elif not p.exists():
            msg = f"{p}: no such file"
        else:
            msg = f"{p}: not a reference file mtident can read (a TOML file written by `learn`; this one: {exc})"
        raise InputError(msg) from exc
    table = doc.get("sensors")
    if not isinstance(table, dict) or not table:
        msg = f"{p}: no [sensors.NAME] tables; learn one with `mtident thermal learn FULL_LOG -o {p.name}`"
        raise InputError(msg)
    sensors = {str(name): _sensor_modes(p, str(name), entry) for name, entry in table.items()}
    return MachineReference(
        str(doc.get("source", p.name)),
        str(doc.get("learnt_on", "")),
        float(doc.get("max_time_constant_min", math.nan)),
        str(doc.get("room", "")),
        sensors,
        machine=str(doc.get("machine", "")),
        serial=str(doc.get("serial", "")),
        program=str(doc.get("program", "")),
        run_date=str(doc.get("run_date", "")),
        machine_model=_machine_model(p, doc.get("machine_model")),
    )


def _machine_model(path: Path, entry: object) -> MachineModel | None:
    """The ``[machine_model]`` table (None where the file has none)."""
    if entry is None:
        return None
    taus = entry.get("time_constants_min") if isinstance(entry, dict) else None
    box = entry.get("box") if isinstance(entry, dict) else None
    gains = entry.get("gains_C") if isinstance(entry, dict) else None
    k = len(taus) if isinstance(taus, list) else -1

    def numbers(values: object, count: int) -> bool:
        return (
            isinstance(values, list)
            and len(values) == count
            and all(isinstance(v, int | float) and not isinstance(v, bool) and math.isfinite(v) for v in values)
        )

    ok = (
        0 < k <= MACHINE_MAX_MODES
        and numbers(taus, k)
        and numbers(box, k)
        and isinstance(gains, dict)
        and len(gains) >= 2
    )
    ok = ok and all(v > 0 for v in taus) and all(0 < v < 10 for v in box)  # type: ignore[union-attr]
    ok = ok and all(numbers(row, k) for row in gains.values())  # type: ignore[union-attr]
    if not ok:
        msg = (
            f"{path}: [machine_model]: expected time_constants_min = [1 to {MACHINE_MAX_MODES} positive minutes], "
            "box = [as many positive fractions] and gains_C with a list of as many numbers for two or more sensors; "
            f"found {entry!r} (learn the reference again, or delete the table to use each sensor's modes alone)"
        )
        raise InputError(msg)
    assert isinstance(entry, dict) and isinstance(taus, list) and isinstance(box, list) and isinstance(gains, dict)
    model = MachineModel(
        tuple(str(name) for name in gains),
        tuple(float(v) for v in taus),
        tuple(float(v) for v in box),
        tuple(tuple(float(v) for v in row) for row in gains.values()),
    )
    return _room_response(path, model, entry.get("room_response"), numbers)


def _room_response(
    path: Path, model: MachineModel, entry: object, numbers: Callable[[object, int], bool]
) -> MachineModel:
    """The model with the ``[machine_model.room_response.NAME]`` tables' room gains (none where the
    file has none)."""
    if entry is None:
        return model
    k = len(model.time_constants_min)
    ok = isinstance(entry, dict) and bool(entry) and set(entry) <= set(model.sensors)
    for table in entry.values() if isinstance(entry, dict) else ():
        ok = ok and isinstance(table, dict) and numbers(table.get("gains"), k)
        cov = table.get("covariance") if isinstance(table, dict) else None
        ok = ok and isinstance(cov, list) and len(cov) == k and all(numbers(row, k) for row in cov)
    if not ok:
        msg = (
            f"{path}: [machine_model.room_response]: expected, per sensor of the model, gains = [{k} numbers] and "
            f"covariance = [{k} lists of {k} numbers]; found {entry!r} (learn the reference again, or delete the "
            "table to fit the room in each test)"
        )
        raise InputError(msg)
    assert isinstance(entry, dict)
    nan_row = (math.nan,) * k
    return replace(
        model,
        room_gains=tuple(
            tuple(map(float, entry[name]["gains"])) if name in entry else nan_row for name in model.sensors
        ),
        room_gain_cov=tuple(
            tuple(tuple(map(float, row)) for row in entry[name]["covariance"]) if name in entry else (nan_row,) * k
            for name in model.sensors
        ),
    )


def _sensor_modes(path: Path, name: str, entry: object) -> SensorModes:
    taus = entry.get("time_constants_min") if isinstance(entry, dict) else None
    boxes = (
        entry.get("box", [MIN_REFERENCE_BOX] * len(taus))
        if isinstance(entry, dict) and isinstance(taus, list)
        else None
    )
    ok = isinstance(taus, list) and isinstance(boxes, list) and len(boxes) == len(taus)
    ok = ok and 0 < len(taus) <= DEFAULT_MAX_MODES  # type: ignore[arg-type]
    numbers = [*taus, *boxes] if ok else []  # type: ignore[misc]
    ok = ok and all(isinstance(v, int | float) and math.isfinite(v) and v > 0 for v in numbers)
    free = entry.get("free_fast_modes") if isinstance(entry, dict) else None
    ok = ok and (free is None or (isinstance(free, int) and not isinstance(free, bool) and 0 <= free <= MAX_FREE_FAST))
    if ok and not all(v < 1 for v in boxes):  # type: ignore[union-attr]
        msg = (
            f"{path}: sensor {name!r}: box = {boxes!r}: each box is a half-width relative to its time constant, "
            "below 1 (a box of 1 or more reaches below zero minutes). An earlier version of `learn` could write one "
            "where it widened a mode to hold two: learn the reference run again, or set that box below 1"
        )
        raise InputError(msg)
    if not ok:
        msg = (
            f"{path}: sensor {name!r}: expected time_constants_min = [1 to {DEFAULT_MAX_MODES} positive minutes], "
            f"box = [as many fractions between 0 and 1] and, if given, free_fast_modes = 0 to {MAX_FREE_FAST}; "
            f"found {entry!r}"
        )
        raise InputError(msg)
    assert isinstance(taus, list) and isinstance(boxes, list) and isinstance(entry, dict)
    return SensorModes(
        tuple(float(v) for v in taus),
        tuple(float(v) for v in boxes),
        tuple(float(v) for v in entry.get("amplitudes_C", [])),
        str(entry["doubt"]) if entry.get("doubt") else None,
        free,
    )
