"""What a sensor's model-robust interval rests on, in words: the largest time constant, the room
(measured, or its assumed wander), and a reference run's modes with the free modes a test may add
(:class:`~mtident.thermal.robust_types.Assumptions`, in every answer).
"""

from __future__ import annotations

import functools

from mtident.thermal.reference import MachineReference
from mtident.thermal.robust import free_fast
from mtident.thermal.robust_types import Assumptions, RobustSettings

__all__ = ["describe_assumptions"]


def describe_assumptions(
    settings: RobustSettings,
    room_sensor: str | None,
    reference: MachineReference | None,
    sensor: str,
    room_measured: bool = False,
    machine_used: bool = True,
) -> Assumptions:
    """What a sensor's interval rests on, in words.

    Parameters
    ----------
    settings : RobustSettings
        The largest time constant, the room's wander and the free fast modes allowed.
    room_sensor : str or None
        The room sensor's name; None without one.
    reference : MachineReference or None
        A reference run of the same machine.
    sensor : str
        The sensor whose reference modes are described.
    room_measured : bool
        Room readings were given (under ``room_sensor``'s name, or unnamed).
    machine_used : bool
        The sensor's answer comes with the reference's machine model (the words then say it);
        False where the answer is its own fit's (a sensor identified alone, or one the model left
        out).

    Returns
    -------
    Assumptions
    """
    if room_sensor is not None:
        room = f"measured by {room_sensor!r}, an input of every mode; T∞ at the room's last level"
    elif room_measured:
        room = "measured (the room readings given), an input of every mode; T∞ at the room's last level"
    elif settings.room_wander_C_per_h > 0:
        room = f"not measured; taken to wander as a random walk of {settings.room_wander_C_per_h:g} °C in an hour"
    else:
        room = "not measured; taken as steady"
    said = _said(settings)
    if reference is None or sensor not in reference.sensors:
        return said(settings.max_time_constant_min, room, None if reference is None else reference.describe(sensor))
    modes = reference.sensors[sensor]
    if modes.doubt is not None:
        return said(settings.max_time_constant_min, room, f"{reference.describe(sensor)}; not used: {modes.doubt}")
    extra = free_fast(modes, settings)
    if extra:
        faster = f"up to {extra} free mode{'s' if extra > 1 else ''} faster than the slowest of these" + (
            f" ({settings.max_modes} modes in all)" if extra < settings.free_fast_modes else ""
        )
    elif len(modes.time_constants_min) >= settings.max_modes:
        faster = f"no free mode besides these ({settings.max_modes} modes in all)"
    elif settings.free_fast_modes:
        faster = "no mode faster than these (assumed: the reference says it holds every mode)"
    else:
        faster = "no mode faster than these (assumed)"
    return said(
        settings.max_time_constant_min,
        room,
        f"{reference.describe(sensor)}; {faster}{_machine_words(reference, sensor) if machine_used else ''}",
    )


def _said(settings: RobustSettings) -> type[Assumptions] | functools.partial[Assumptions]:
    """Assumptions whose model words name the sensors the engineer said the heat enters at."""
    if not settings.heat_enters_at:
        return Assumptions
    names = ", ".join(settings.heat_enters_at)
    return functools.partial(
        Assumptions,
        model=f"{Assumptions.model}; where the heat enters ({names}, as stated), every mode of a warm-up fitted "
        "without a reference rises, unless its readings contradict it (said where they do)",
    )


MACHINE_MARK = "; and "
"""Where a sensor's reference words go on to the machine model's (``MachineModel.describe``), which
a listing of many sensors says once (:func:`mtident.cli_thermal.reference_lines`)."""


def _machine_words(reference: MachineReference, sensor: str) -> str:
    model = reference.machine_model
    return "" if model is None or sensor not in model.sensors else f"{MACHINE_MARK}{model.describe()}"
