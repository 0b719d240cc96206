"""Learning a reference from one complete run: each sensor's modes with their boxes, the doubt
of a sensor the run did not pin down, a mode that may be two merged split against the machine's
modes, and the machine model of the sensors the run pins down together.

:func:`learn_reference` gives the :class:`~mtident.thermal.reference.MachineReference` that
:mod:`mtident.thermal.reference` writes, reads and fits to a later test's log.
"""

from __future__ import annotations

import datetime as dt
import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.special import chdtri

from mtident._typing import FloatArray
from mtident.io.columns import room_named
from mtident.io.logs import TemperatureLog
from mtident.thermal.machine_fit import fit_test
from mtident.thermal.machine_model import (
    MachineModel,
    MachineReadings,
    learn_machine_model,
    loose_slow,
    loose_slow_modes,
    machine_readings,
    missing_modes,
)
from mtident.thermal.modal_search import room_lag
from mtident.thermal.modes import SteadyState, bin_samples, log_time_constant_sd
from mtident.thermal.readings import coarse_room_step_C, coarse_room_warning, room_input, warming_room_warning
from mtident.thermal.reference import ROOM_MEASURED, MachineReference
from mtident.thermal.robust import DISAGREEMENT_LEVEL, MIN_REFERENCE_BOX, UNTRUSTING_CODES, estimate_sensor
from mtident.thermal.robust_types import DEFAULT_MAX_MODES, RobustSettings, SensorEstimate, SensorModes

__all__ = ["learn_reference"]

# A reference's box is three standard deviations of its log time constant either side (at least
# ±10 %, at most a factor of 100); a mode counts as pinned down within 0.15 (about ±15 %) at one.
BOX_SDS = 3.0
MAX_BOX_REACH = math.log(100.0)
MAX_MODE_SD = 0.15
# a mode, or a mode's box, within 2 % of the largest time constant searched is at that limit: the
# run cannot tell it from a slower one
AT_LIMIT_SHARE = 0.98
# a sensor's modal amplitudes in the machine model may add up to at most this many times its rise
# (a remote sensor's transfer response has amplitudes of both signs; far beyond, two slow modes
# cancel, and a test at another heat split extrapolates them wrongly: a stop 0.26 °C off)
MAX_CANCELLING = 10.0
# A reference run pins a sensor down when its own steady state is known within this (95 %): half
# the usual tolerance of a later test.
PINNED_HALF_WIDTH_C = 0.1
# A room whose course through a sensor's slowest mode leaves the room by this much (°C) has a lag
# that the fit's free room gains can take for a lower or higher steady state; a steadier room's
# course is its sensor's own error.
ROOM_LAG_SHOWN_C = 0.025
# The machine's modes, pooled over its sensors: pinned modes of several sensors this close (ratio)
# are one; a sensor's mode that holds none of them in its box, between two of them at most this
# ratio apart, may be those two merged (a sensor that shows each only a little fits one between).
_SAME_MODE_RATIO = 1.3
_PINNED_BOX = 0.3
_MERGE_SPAN = 4.0


def learn_reference(
    log: TemperatureLog, room_C: FloatArray | None = None, settings: RobustSettings | None = None
) -> tuple[MachineReference, list[str]]:
    """Each sensor's modes from a warm-up that ran to equilibrium.

    Parameters
    ----------
    log : TemperatureLog
    room_C : ndarray, shape (N,), optional
        A room sensor (an input of every mode).
    settings : RobustSettings, optional
        The largest time constant searched (default: 300 min).

    Returns
    -------
    MachineReference
    list of str
        Warnings: sensors left out (no fit), sensors not pinned down (a log that did not reach
        equilibrium), modes the run needs but cannot pin down (kept with wide boxes).
    """
    settings = settings or RobustSettings()
    sensors: dict[str, SensorModes] = {}
    loose: dict[str, tuple[int, int, str]] = {}
    reaching: dict[str, str] = {}
    warnings: list[str] = _room_candidates(log.sensors) if room_C is None else []
    room_step = 0.0 if room_C is None else coarse_room_step_C(log.time_min, room_C)
    for s, name in enumerate(log.sensors):
        learnt = _learn_sensor(name, log.time_min, log.temperature_C[:, s], room_C, room_step, settings)
        if isinstance(learnt, str):
            warnings.append(f"{name}: left out of the reference ({learnt})")
            continue
        estimate, centres, boxes, determined = learnt.estimate, learnt.centres, learnt.boxes, learnt.determined
        fit = _fit_of(estimate)
        ceiling = _ceiling_min(centres, boxes)
        doubt = _doubt(estimate, learnt.one_more, ceiling, learnt.room_reach, learnt.room_followed)
        sensors[name] = SensorModes(centres, boxes, tuple(m.amplitude_C for m in fit.modes), doubt)
        if doubt is None and len(fit.modes) > determined:
            loose[name] = (len(fit.modes), determined, _spans(centres, boxes, determined))
        if doubt is not None:
            way_on = _way_on(estimate, room_C is not None)
            warnings.append(f"{name}: {doubt}. Later tests will not use this sensor's modes: {way_on}")
        limit = settings.max_time_constant_min
        if max(m.time_constant_min for m in fit.modes) >= AT_LIMIT_SHARE * limit:
            reaching[name] = (
                f"{name}: a mode at the largest time constant searched ({limit:g} min): the "
                "machine may have a slower one (raise `max_time_constant_min`)"
            )
        elif ceiling >= AT_LIMIT_SHARE * limit:
            # a box that reaches the limit holds a mode the run cannot tell from one at it
            centre, box = max(zip(centres, boxes, strict=True), key=lambda cb: cb[0] * (1.0 + cb[1]))
            reaching[name] = (
                f"{name}: a mode of {centre:.3g} min ±{box:.0%}, which reaches the largest time constant searched "
                f"({limit:g} min): the run cannot tell it from one at that limit, and the machine may have a "
                "slower one (raise `max_time_constant_min`)"
            )
    warnings[len(warnings) : len(warnings)] = _loose_modes_words(loose)
    model, said, learnt_model = _learn_machine(log, room_C, settings)
    warnings.extend(_reaching_words(reaching, model, settings.max_time_constant_min))
    sensors, split = split_merged_modes(sensors, model)
    warnings.extend(split)
    warnings.extend(said)
    if model is None and learnt_model is not None:
        warnings.extend(_hidden_slow_words(learnt_model, sensors, log.time_min, settings.max_time_constant_min))
    if room_step > 0:
        warnings.append(coarse_room_warning(room_step, "learnt modes explain only what lies beyond it"))
    warming = None if room_C is None else warming_room_warning(room_C, None, log.time_min)
    warnings.extend([] if warming is None else [warming])
    room = ROOM_MEASURED if room_C is not None else "not measured"
    return MachineReference(
        log.source, dt.date.today().isoformat(), settings.max_time_constant_min, room, sensors, machine_model=model
    ), warnings


def _ceiling_min(centres: tuple[float, ...], boxes: tuple[float, ...]) -> float:
    """The slowest time constant these modes' boxes hold (min)."""
    return max(c * (1.0 + b) for c, b in zip(centres, boxes, strict=True))


def _reaching_words(reaching: dict[str, str], model: MachineModel | None, limit_min: float) -> list[str]:
    """The warnings of sensors whose own slowest mode, or its box, reaches the largest time constant
    searched; those the machine model holds, where it pins its slowest mode below that limit, in
    one line: the model's modes are what a test uses, and the machine has no slower mode that the
    run shows (a newcomer's clean run gave four such warnings, each advising a larger limit, for a
    machine whose slowest mode of 239 min the model pinned at 232)."""
    if model is None or _ceiling_min(model.time_constants_min, model.box) >= AT_LIMIT_SHARE * limit_min:
        return list(reaching.values())
    held = [name for name in reaching if name in model.sensors]
    slowest = int(np.argmax(model.time_constants_min))
    pinned = (
        f"{', '.join(held)}: {'its' if len(held) == 1 else 'their'} own fit leaves the slowest mode loose up to, or "
        f"at, the largest time constant searched ({limit_min:g} min), but the machine model pins it at "
        f"{model.time_constants_min[slowest]:.3g} min ±{model.box[slowest]:.0%}; a test uses the model (the sensor's "
        "own modes, their box held, only where a test falls back on them)"
    )
    return [words for name, words in reaching.items() if name not in held] + ([pinned] if held else [])


ROOM_MOVED_C = 0.15
"""A room sensor whose readings span more than this (°C) over a reference run moved during it
(more than one step of a room read in 0.1 °C steps)."""


def loose_mode_advice(room_C: FloatArray | None) -> str:
    """What to do where a reference run leaves the machine's slow modes loose, in words: where its
    room moved, the room's path into each slow mode traded against the mode's rise."""
    finite = np.asarray(room_C, float)[np.isfinite(room_C)] if room_C is not None else np.zeros(0)
    span = float(np.ptp(finite)) if len(finite) else 0.0
    if span > ROOM_MOVED_C:
        return (
            f"the room moved {span:.2f} °C during the run, and its path into the slow modes trades against their "
            "rise: learn from a run in a steady room that reaches equilibrium"
        )
    return "learn from a run that reaches equilibrium, in a room that drifts little"


def _learn_machine(
    log: TemperatureLog, room_C: FloatArray | None, settings: RobustSettings
) -> tuple[MachineModel | None, list[str], MachineModel | None]:
    """The machine model of the run's sensors that it pins down together (each one's steady state
    within ``PINNED_HALF_WIDTH_C`` at 95 % with the model), None where fewer than two, or where
    the run does not pin down the slow modes they share; what the warnings say; and the model
    learnt, kept or not."""
    if len(log.sensors) < 2:
        return None, [], None
    readings = machine_readings(log.sensors, log.time_min, log.temperature_C, room_C)
    model = learn_machine_model(readings, settings.max_time_constant_min)
    if model is None:
        return None, [], None
    kept, said, missing = _judged(model, readings, log, room_C)
    # a sensor whose run shows a mode the shared ones lack: one shared mode more, where that keeps more
    # sensors (the BIC prices a mode for every sensor, where one sensor's readings ask for it)
    while missing:
        more = learn_machine_model(readings, settings.max_time_constant_min, more_than=model)
        if more is None:
            break
        more_kept, more_said, more_missing = _judged(more, readings, log, room_C)
        if more_kept is None or len(more_kept.sensors) <= (0 if kept is None else len(kept.sensors)):
            break
        model, kept, said, missing = more, more_kept, more_said, more_missing
    return kept, said, model


def _hidden_slow_words(
    model: MachineModel, sensors: dict[str, SensorModes], time_min: FloatArray, max_time_constant_min: float
) -> list[str]:
    """Where the machine model was not kept for a loose slow mode (not one at the slowest searched:
    half the run, or the largest time constant searched), the sensors whose own slowest mode, box
    and all, is faster than it, in words: each may have merged a slower mode that shows only a
    little in it with its own slowest (a new user's machine of 100 and 244 min, learnt as about
    105 ±10 % in five sensors; the machine model's shared fit left a mode of 156 min ±69 %), which
    a test then finds only when its readings contradict the reference."""
    span = float(time_min[-1] - time_min[0]) if len(time_min) else 0.0
    searched = AT_LIMIT_SHARE * min(0.5 * span, max_time_constant_min)
    slow = [(tau, box) for tau, box in loose_slow(model) if tau < searched]
    if not slow:
        return []
    tau, box = max(slow)
    below = {
        name: _ceiling_min(m.time_constants_min, m.box)
        for name, m in sensors.items()
        if m.doubt is None and m.time_constants_min
    }
    hiding = [name for name, ceiling in below.items() if ceiling < tau]
    if not hiding:
        return []
    low, high = (f"{f(below[n] for n in hiding):.3g}" for f in (min, max))
    return [
        f"{', '.join(hiding)}: the slowest mode learnt for each ({low if low == high else f'{low}-{high}'} min at "
        "most, box and all) is faster than the slow mode the sensors "
        f"share in their fit together ({tau:.3g} min ±{box:.0%}, which the run leaves loose): each may hold a slower "
        "mode merged with its own, which shows only a little in it. A later test drops the reference where its "
        "readings contradict it, but until then it may say such a sensor may stop on the wrong modes: learn from "
        "a longer run, in a steady room"
    ]


def _judged(
    model: MachineModel, readings: MachineReadings, log: TemperatureLog, room_C: FloatArray | None
) -> tuple[MachineModel | None, list[str], dict[str, tuple[float, float]]]:
    """The learnt model of the sensors it pins down together (None where fewer than two, or where
    the run leaves its slow modes loose or builds a sensor from cancelling modes), what the warnings
    say of it, and the sensors left out for a mode the shared ones lack."""
    if loose := loose_slow_modes(model):
        return (
            None,
            [
                f"the run does not pin down the slow modes its sensors share ({', '.join(loose)}): later tests use "
                f"each sensor's modes alone ({loose_mode_advice(room_C)})"
            ],
            {},
        )
    gains = np.array(model.gains_C)
    cancelling = np.abs(gains).sum(axis=1) / np.maximum(np.abs(gains.sum(axis=1)), 1e-9)
    if np.max(cancelling) > MAX_CANCELLING:
        worst = log.sensors[int(np.argmax(cancelling))]
        return (
            None,
            [
                f"the machine model would build {worst}'s rise from modes {np.max(cancelling):.0f} times larger "
                "that cancel: too fragile to extrapolate a test with; later tests use each sensor's modes alone"
            ],
            {},
        )
    itself = fit_test(model, readings, (0.95,), room_lag=False)
    pinned = (
        []
        if itself is None
        else [n for n, h in zip(log.sensors, itself.half_width_C[0.95], strict=True) if h <= PINNED_HALF_WIDTH_C]
    )
    missing = missing_modes(model, readings)
    shared = ", ".join(f"{tau:.3g}" for tau in model.time_constants_min)
    lacking = [
        f"the machine model leaves out {name}: its run shows a mode of about {tau:.3g} min ({amplitude:+.2f} °C) "
        f"that the shared modes ({shared} min) lack, so a test would extrapolate it wrongly"
        for name, (tau, amplitude) in missing.items()
        if name in pinned
    ]
    pinned = [name for name in pinned if name not in missing]
    if len(pinned) < 2:
        return (
            None,
            [
                *lacking,
                "the run does not pin down two or more sensors together: later tests use each sensor's modes alone",
            ],
            missing,
        )
    left = [name for name in log.sensors if name not in pinned and name not in missing]
    said = (
        [
            f"the machine model leaves out {', '.join(left)}: the run does not pin "
            + ("its steady state" if len(left) == 1 else "their steady states")
            + " down together with the others'"
        ]
        if left
        else []
    )
    return model.of(pinned), [*lacking, *said], missing


@dataclass(frozen=True)
class _MachineMode:
    """One of the machine's modes, pooled over the sensors that pin it down."""

    time_constant_min: float
    box: float
    sensors: frozenset[str]


def machine_modes(sensors: dict[str, SensorModes]) -> list[_MachineMode]:
    """The machine's modes: every trusted sensor's pinned modes (box at most ±30 %), those of
    several sensors within a ratio of 1.3 taken as one (its box holding every member's).

    Parameters
    ----------
    sensors : dict of str to SensorModes

    Returns
    -------
    list of _MachineMode
        Sorted by time constant.
    """
    pinned = sorted(
        (tau, box, name)
        for name, m in sensors.items()
        if m.doubt is None
        for tau, box in zip(m.time_constants_min, m.box, strict=True)
        if box <= _PINNED_BOX
    )
    groups: list[list[tuple[float, float, str]]] = []
    for member in pinned:
        if groups and member[0] / groups[-1][-1][0] < _SAME_MODE_RATIO:
            groups[-1].append(member)
        else:
            groups.append([member])
    out = []
    for group in groups:
        low = min(t * (1.0 - b) for t, b, _ in group)
        high = max(t * (1.0 + b) for t, b, _ in group)
        out.append(_MachineMode((low + high) / 2.0, (high - low) / (high + low), frozenset(n for _, _, n in group)))
    return out


_MODEL = "the machine model"


def _model_modes(model: MachineModel | None, sensors: dict[str, SensorModes]) -> list[_MachineMode]:
    """The machine model's modes it pins down (box at most ±30 %), each as a mode of the machine
    that every sensor of the model and the model itself witness."""
    if model is None:
        return []
    witnesses = frozenset(n for n in model.sensors if n in sensors) | {_MODEL}
    return [
        _MachineMode(tau, box, witnesses)
        for tau, box in zip(model.time_constants_min, model.box, strict=True)
        if box <= _PINNED_BOX
    ]


def _model_brackets(machine: list[_MachineMode], tau: float, box: float) -> bool:
    """Whether the machine model pins a mode below ``tau``'s box and one above it, at most
    ``_MERGE_SPAN`` apart, and none within it."""
    pinned = [mm.time_constant_min for mm in machine if _MODEL in mm.sensors]
    if any(_holds(tau, box, t) for t in pinned):
        return False
    below = [t for t in pinned if t < tau * (1.0 - box)]
    above = [t for t in pinned if t > tau * (1.0 + box)]
    return bool(below and above) and min(above) / max(below) <= _MERGE_SPAN


def _room_candidates(names: tuple[str, ...]) -> list[str]:
    """A warning on columns named as a room sensor, learnt as machine sensors for want of a room:
    a room that moves then misfits every mode (a notebook's nine misfit warnings named no cause)."""
    rooms = [name for name in names if room_named(name)]
    if not rooms or len(rooms) == len(names):
        return []
    return [
        f"{', '.join(repr(r) for r in rooms)} {'is' if len(rooms) == 1 else 'are'} named as a room sensor and "
        "learnt as a machine sensor: if it measures the room, give it as the room (`room_C`), and each sensor's "
        "fit takes the room's course as an input"
    ]


def split_merged_modes(
    sensors: dict[str, SensorModes], model: MachineModel | None = None
) -> tuple[dict[str, SensorModes], list[str]]:
    """Each sensor's modes against the machine's: a mode whose box holds none of the modes other
    sensors pin down, lying between two of them (at most a factor of four apart) that the sensor's
    other modes do not hold, may be the two merged (110 and 260 min learnt as one of 170 ±10 %,
    whose box excludes both): it is replaced by the two, with their boxes, and said. The machine
    model's modes pinned down (box at most ±30 %) count as the machine's too: the sensors fitted
    together pin a slow mode down that none of them does alone.

    Parameters
    ----------
    sensors : dict of str to SensorModes
    model : MachineModel, optional
        The run's machine model.

    Returns
    -------
    dict of str to SensorModes
        The sensors, a merged mode split where one was found.
    list of str
        One warning per split.
    """
    machine = sorted(
        machine_modes(sensors) + _model_modes(model, sensors), key=lambda mm: (mm.time_constant_min, mm.box)
    )
    out, warnings = dict(sensors), []
    for name, m in sensors.items():
        if m.doubt is not None:
            continue
        others = [mm for mm in machine if mm.sensors - {name}]
        # one merge at a time: a sensor may have merged a fast pair and a slow one
        for _ in range(DEFAULT_MAX_MODES):
            split = _split_once(name, out[name], others, machine)
            if split is None:
                break
            out[name], said = split
            warnings.append(said)
    return out, warnings


def _split_once(
    name: str, m: SensorModes, others: list[_MachineMode], machine: list[_MachineMode]
) -> tuple[SensorModes, str] | None:
    """:func:`split_merged_modes` for the first of the sensor's modes that may be two merged: the
    sensor with it split (or its box widened to hold both), and what to say; None where none is."""
    modes = list(zip(m.time_constants_min, m.box, m.amplitudes_C or (math.nan,) * len(m.box), strict=True))
    for i, (tau, box, amplitude) in enumerate(modes):
        # where the sensors fitted together pin a mode on either side and none within, other
        # sensors that hold this one merged the same two (five sensors each learnt 105-111 min for a
        # machine's 74 and 129), and witness nothing
        bracketed = _model_brackets(machine, tau, box)
        pool = [mm for mm in others if _MODEL in mm.sensors] if bracketed else others
        held = [] if bracketed else [mm for mm in others if _holds(tau, box, mm.time_constant_min)]
        below = [mm for mm in pool if mm.time_constant_min < tau * (1.0 - box)]
        above = [mm for mm in pool if mm.time_constant_min > tau * (1.0 + box)]
        if held or not below or not above:
            continue
        low, high = below[-1], above[0]
        others_hold = [
            any(_holds(t, b, mm.time_constant_min) for j, (t, b, _) in enumerate(modes) if j != i) for mm in (low, high)
        ]
        if high.time_constant_min / low.time_constant_min > _MERGE_SPAN:
            continue
        if any(others_hold):
            if bracketed and not all(others_hold):
                return _displaced(name, m, modes, i, high if others_hold[0] else low)
            continue
        witnesses = low.sensors | high.sensors
        by = "the machine model pins down" if _MODEL in witnesses else "other sensors pin down"
        who = ", ".join(sorted(witnesses - {_MODEL}))
        of = f", {amplitude:+.2f} °C" if math.isfinite(amplitude) else ""
        said = (
            f"{name}: its mode of {tau:.3g} min (±{box:.0%}{of}) lies between the machine's modes of "
            f"{low.time_constant_min:.3g} and {high.time_constant_min:.3g} min that {by} ({who}), and its box "
            "holds neither: the run may have merged the two into one. Later tests search "
        )
        if len(modes) + 1 > DEFAULT_MAX_MODES:
            # no room for both: one mode searched over both keeps the test's interval honest
            lowest = min(low.time_constant_min * (1.0 - max(low.box, MIN_REFERENCE_BOX)), tau * (1.0 - box))
            highest = max(high.time_constant_min * (1.0 + max(high.box, MIN_REFERENCE_BOX)), tau * (1.0 + box))
            centre, wide = _spanning(lowest, highest)
            return _with_modes(m, [*modes[:i], (centre, wide, amplitude), *modes[i + 1 :]]), (
                f"{said}{centre:.3g} ±{wide:.0%} ({lowest:.3g}-{highest:.3g} min), holding both, for this sensor (it "
                f"has {len(modes)} modes already, the most a sensor's fit takes)"
            )
        # the run measured the two modes' amplitudes as one: neither is known on its own (halves, shown in
        # learn's table, read as measured)
        split = [(low.time_constant_min, low.box, math.nan), (high.time_constant_min, high.box, math.nan)]
        return _with_modes(m, modes[:i] + split + modes[i + 1 :]), (
            f"{said}both ({low.time_constant_min:.3g} ±{max(low.box, MIN_REFERENCE_BOX):.0%}, "
            f"{high.time_constant_min:.3g} ±{max(high.box, MIN_REFERENCE_BOX):.0%}) for this sensor"
        )
    return None


def _displaced(
    name: str, m: SensorModes, modes: list[tuple[float, float, float]], i: int, missed: _MachineMode
) -> tuple[SensorModes, str]:
    """The sensor with mode ``i`` searched over a range that holds the machine model's mode it
    lies beside and no other of its modes holds (``missed``): the run placed it between that mode
    and one the sensor has already (a motor kept 26.8, 105 and 170 ±10 % min where the machine
    model pinned 246, and a test found a slower mode fitting better beyond chance)."""
    tau, box, amplitude = modes[i]
    other_box = max(missed.box, MIN_REFERENCE_BOX)
    lowest = min(tau * (1.0 - box), missed.time_constant_min * (1.0 - other_box))
    highest = max(tau * (1.0 + box), missed.time_constant_min * (1.0 + other_box))
    centre, wide = _spanning(lowest, highest)
    said = (
        f"{name}: its mode of {tau:.3g} min (±{box:.0%}) lies beside the machine model's mode of "
        f"{missed.time_constant_min:.3g} min, which none of its modes holds: the run may have placed that mode "
        f"there. Later tests search {centre:.3g} ±{wide:.0%} ({lowest:.3g}-{highest:.3g} min) for this sensor"
    )
    return _with_modes(m, [*modes[:i], (centre, wide, amplitude), *modes[i + 1 :]]), said


def _spanning(lowest: float, highest: float) -> tuple[float, float]:
    """The time constant and relative box that span ``lowest`` to ``highest`` (min): a box about a
    mode's own time constant that reached both went below zero (±275 % about 30.8 min)."""
    return (lowest + highest) / 2.0, (highest - lowest) / (highest + lowest)


def _with_modes(m: SensorModes, modes: list[tuple[float, float, float]]) -> SensorModes:
    """The sensor with these modes (time constant, box, amplitude), in order of time constant, each
    box at least :data:`MIN_REFERENCE_BOX`."""
    modes = sorted(modes)
    return replace(
        m,
        time_constants_min=tuple(t for t, _, _ in modes),
        box=tuple(max(b, MIN_REFERENCE_BOX) for _, b, _ in modes),
        amplitudes_C=tuple(a for _, _, a in modes) if m.amplitudes_C else (),
    )


def _holds(tau: float, box: float, other: float) -> bool:
    return tau * (1.0 - box) <= other <= tau * (1.0 + box)


def _doubt(
    estimate: SensorEstimate,
    one_more: SensorEstimate,
    ceiling_min: float,
    room_reach: float,
    room_followed: tuple[float, float] | None = None,
) -> str | None:
    """Why a reference run did not pin a sensor down, or None: its modes misfit the run, its
    readings leave its own steady state wider than ``PINNED_HALF_WIDTH_C``, or its best fit with
    one mode more (``one_more``, chosen by BIC) has a mode slower than the learnt modes' boxes
    (``ceiling_min``) and moves the steady state further than that. A later test allows faster
    modes than the reference's, not slower ones: a sparse run that ended while a small slow mode
    was still rising was learnt as one fast mode (its noise, read off the rise, hid the slow
    mode from the test of modes needed), and a test that trusted it stopped 0.29 °C low. The
    slower mode must explain more than the room sensor's own error could (``room_reach``, °C²,
    as :func:`_modes_needed`). The
    readings' interval, without the unmeasured room's wander: the wander is the future room's,
    which a later test meets with its own readings, and with it every run whose slowest mode
    exceeds an hour was doubted, however complete. In a moving room the narrower of it and the
    interval with the room's course taken out (``room_followed``, :func:`_room_followed`): the
    fit's free room gains stand for any lag, which says nothing of whether the run settled."""
    fit = _fit_of(estimate)
    level = min(fit.interval_C)
    lo, hi = fit.interval_C[level]
    if room_followed is not None and room_followed[1] - room_followed[0] < hi - lo:
        lo, hi = room_followed
    if not estimate.model_ok:
        # the warnings that took the trust away, less the sensor's name each starts with
        why = [
            text.split(": ", 1)[-1]
            for text, code in zip(estimate.warnings, estimate.warning_codes, strict=True)
            if code in UNTRUSTING_CODES
        ]
        return "; ".join(why) or "its model is not trusted"
    if (hi - lo) / 2 > PINNED_HALF_WIDTH_C:
        return (
            f"with the modes learnt, the run pins its own steady state down only to {lo:.2f}-{hi:.2f} °C (95 %), "
            f"not to the ±{PINNED_HALF_WIDTH_C:g} °C a reference needs"
        )
    better = one_more.fit
    if better is None or len(better.modes) <= len(fit.modes):
        return None
    slowest = max(m.time_constant_min for m in better.modes)
    explains = fit.rss - better.rss > room_reach
    if slowest > ceiling_min and abs(better.steady_C - fit.steady_C) > PINNED_HALF_WIDTH_C and explains:
        return (
            f"a fit with one mode more, of about {slowest:.3g} min, slower than those learnt, describes the run better "
            f"(BIC) and puts its steady state at {better.steady_C:.2f} °C instead of {fit.steady_C:.2f} °C: the run "
            "may have ended before that mode settled"
        )
    return None


def _way_on(estimate: SensorEstimate, with_room: bool = True) -> str:
    """What to do about a doubted sensor: a run that misfits every model tried is no shorter or
    sparser run's fault; a run that does not pin the steady state down is. Without a room sensor, a
    room that moved a few hundredths reads as a misfit too (a new user's steady-room run learnt
    without its room column doubted five of six sensors, with it none)."""
    if "misfit" in estimate.warning_codes:
        room = (
            "; and where the room was logged, name its column as the room sensor (--ambient): a room that moves even "
            "a few hundredths of a degree, unknown to the fit, reads as a misfit"
            if not with_room
            else ""
        )
        return (
            "the run's readings follow no sum of the modes tried, so a longer run alone will not help. Check that the "
            "heat input stayed the same through the run and that the sensor reads the body itself (one behind a lag "
            "of its own, in a sleeve or a loose fit, adds a mode; one the air reaches reads the room's noise too)"
            + room
        )
    return (
        "learn from a run that reaches equilibrium, logged densely enough to show every mode, in a room that drifts "
        "little (a drift of the room through the whole run hides the steady state)"
    )


@dataclass(frozen=True)
class _Learnt:
    """One sensor's learning: the estimate with the modes kept, their boxes' centres and relative
    half-widths, how many the run pins down, the fit with one mode more (for the doubt) and what
    the room sensor's own error could explain (°C², :func:`_modes_needed`)."""

    estimate: SensorEstimate
    centres: tuple[float, ...]
    boxes: tuple[float, ...]
    determined: int
    one_more: SensorEstimate
    room_reach: float
    room_followed: tuple[float, float] | None = None


def _room_followed(
    name: str, time_min: FloatArray, values: FloatArray, room_in: FloatArray, fit: SteadyState, settings: RobustSettings
) -> tuple[float, float] | None:
    """The steady state's interval (at the fit's smallest level) with the room's course taken out
    as the fit's slowest mode follows it (a body's room gains sum to one, its step response from
    the room starting at zero): where the fit's free room gains stand for any lag, this says whether
    the heat's own course settled. None where it cannot be fitted."""
    if not fit.modes or not np.all(np.isfinite(room_in)):
        return None
    slowest = np.array([max(m.time_constant_min for m in fit.modes)])
    course = room_lag(room_in, time_min, slowest)[0]
    if np.max(np.abs(course - room_in)) < ROOM_LAG_SHOWN_C:
        return None  # a room this steady leaves the lag nothing to hide
    estimate = estimate_sensor(name, time_min, values - (course - course[0]), None, settings)
    if estimate.fit is None:
        return None
    return estimate.fit.interval_C[min(estimate.fit.interval_C)]


def _learn_sensor(
    name: str,
    time_min: FloatArray,
    values: FloatArray,
    room_C: FloatArray | None,
    room_step: float,
    settings: RobustSettings,
) -> _Learnt | str:
    """The sensor's modes, their boxes' centres and widths, how many of them the run pins down,
    and the fit with one mode more; where no model fits, why (a room's column given as a sensor
    does not rise). The modes:
    the most whose time constants the run determines (each within ±``MAX_MODE_SD`` at one
    standard deviation), or more where the run needs more beyond chance (up to the family's
    most, four: a sensor's lag and three modes, fitted with three, bent all three time constants
    and left the slowest unpinned). A mode the run needs but cannot pin down stays, with the wide
    box its uncertainty gives: left out, it would tell a later test that no mode lies beyond the
    others' boxes, which the run itself contradicts (a slow mode of a fifth of a degree, learnt
    away, stopped a test 0.4 °C low). ``room_step``: a coarse room sensor's display step (0 for a
    fine one, :func:`~mtident.thermal.readings.coarse_room_step_C`)."""
    room_in = None if room_C is None else room_input(time_min, room_C)
    # the room sensor's slow error shows in every fit's residuals: no misfit, and no mode needed
    room_error = 0.0 if room_in is None else _slow_room_error(room_in, room_step)

    def family(count: int) -> RobustSettings:
        return replace(settings, max_modes=count, more_modes_when_used=False)

    def fitted(count: int) -> SensorEstimate:
        return estimate_sensor(name, time_min, values, room_C, family(count), misfit_beyond_C=room_error)

    tried: dict[int, SensorEstimate] = {}
    estimates: dict[int, SensorEstimate] = {}
    sds: dict[int, FloatArray] = {}
    why = "no model fits its readings"
    for count in range(1, settings.max_modes + 1):
        estimate = tried[count] = fitted(count)
        fit = estimate.fit
        if fit is None and estimate.warnings:
            why = estimate.warnings[0].removeprefix(f"{name}: ")
        if fit is None or len(fit.modes) < count:
            break
        first = int(np.searchsorted(time_min, fit.origin_min))
        binned = bin_samples(time_min[first:], values[first:], None if room_in is None else room_in[first:])
        estimates[count], sds[count] = estimate, np.asarray(log_time_constant_sd(binned, fit), dtype=float)
    if not estimates:
        return why
    determined = max((c for c in estimates if np.max(sds[c]) <= MAX_MODE_SD), default=1)
    most = _fit_of(estimates[max(estimates)])
    room_reach = (
        0.0 if room_C is None else _room_reach(time_min, values, room_C, most.origin_min, room_error, room_step)
    )
    count = max(determined, _modes_needed(most, room_reach))
    taus = [m.time_constant_min for m in _fit_of(estimates[count]).modes]
    centres, boxes = zip(
        *(_box(tau, float(sd), settings.max_time_constant_min) for tau, sd in zip(taus, sds[count], strict=True)),
        strict=True,
    )
    one_more = tried[count + 1] if count + 1 in tried else fitted(count + 1)
    followed = None
    if room_in is not None:
        followed = _room_followed(name, time_min, values, room_in, _fit_of(estimates[count]), family(count))
    return _Learnt(estimates[count], centres, boxes, determined, one_more, room_reach, followed)


def _slow_room_error(room_in: FloatArray, room_step: float) -> float:
    """A coarse room sensor's slow error over the run (RMS, °C): its step's q/√12, or less where
    the room's trend (``room_in``, :func:`~mtident.thermal.readings.room_input`) moved less than
    a step (a steady room's readings are off by one constant, which no mode takes up)."""
    if room_step <= 0.0:
        return 0.0
    return min(room_step, float(np.nanmax(room_in) - np.nanmin(room_in))) / math.sqrt(12.0)


def _room_reach(
    time_min: FloatArray, values: FloatArray, room_C: FloatArray, origin_min: float, room_error: float, step: float
) -> float:
    """The most a coarse room sensor's slow error (``room_error``, RMS) could give one mode to
    explain over the readings fitted (a residual sum of squares, °C²): all of it where the room
    crosses at most two of its steps, less as it crosses more (the error then changes sign with
    each step, faster than a mode follows)."""
    fitted = (time_min >= origin_min) & np.isfinite(values) & np.isfinite(room_C)
    if room_error <= 0.0 or not fitted.any():
        return 0.0
    crossed = float(np.ptp(room_C[fitted]))
    return float(np.count_nonzero(fitted)) * room_error**2 * min(1.0, 2.0 * step / max(crossed, 1e-12))


def _loose_modes_words(loose: dict[str, tuple[int, int, str]]) -> list[str]:
    """The warning for sensors whose run needs more modes beyond chance than it pins down (per
    sensor: the modes needed, those pinned down, the loose ones' boxes): one line for all of them,
    where one per sensor made a clean run of six sensors read as six alarms."""
    if not loose:
        return []
    later = "so later tests stop later than with a run that shows every mode"
    if len(loose) == 1:
        ((name, (needed, determined, spans)),) = loose.items()
        kept = (
            "the other is kept with the wide box the run leaves it"
            if needed - determined == 1
            else "the others are kept with the wide boxes the run leaves them"
        )
        needs = f"the run needs {needed} modes beyond chance but pins down only {determined}"
        return [f"{name}: {needs}; {kept} ({spans}), {later}"]
    each = ", ".join(f"{name} ({pinned} of {needed}: {spans})" for name, (needed, pinned, spans) in loose.items())
    return [
        f"the run needs more modes beyond chance than it pins down for {len(loose)} sensors; the others are kept "
        f"with the wide boxes the run leaves them, {later}: {each}"
    ]


def _spans(centres: tuple[float, ...], boxes: tuple[float, ...], skip: int) -> str:
    """The widest boxes, as ranges of minutes, slowest first."""
    widest = sorted(range(len(boxes)), key=lambda k: boxes[k])[skip:]
    order = sorted(widest, key=lambda k: -centres[k])
    return ", ".join(f"{centres[k] * (1 - boxes[k]):.3g}-{centres[k] * (1 + boxes[k]):.3g} min" for k in order)


def _modes_needed(fit: SteadyState, room_reach: float = 0.0) -> int:
    """The most modes that fit the run better than one mode fewer beyond chance (χ² on 2 degrees
    of freedom at ``DISAGREEMENT_LEVEL``, on the noise of the fit with the most modes: a fit with
    too few has correlated residuals, and its noise hides what the next mode explains) and beyond
    ``room_reach`` (°C², a residual sum of squares): all that the room sensor's own error
    (:func:`~mtident.thermal.readings.room_error_C`) could give a mode to explain."""
    quantile = float(chdtri(2, 1.0 - DISAGREEMENT_LEVEL))
    gains = {k: (fit.fits[k - 1] - fit.fits[k] - room_reach) / fit.noise_C**2 for k in fit.fits if k - 1 in fit.fits}
    return max((k for k, gain in gains.items() if gain > quantile), default=1)


def _fit_of(estimate: SensorEstimate) -> SteadyState:
    assert estimate.fit is not None
    return estimate.fit


def _box(tau: float, log_sd: float, max_time_constant_min: float) -> tuple[float, float]:
    """A time constant's box, as its centre and half-width (relative): ``BOX_SDS`` standard
    deviations of log τ either side (at least ±``MIN_REFERENCE_BOX``, at most up to the largest
    time constant searched), symmetric in log τ, since a poorly determined time constant is
    uncertain by a factor, not by a number of minutes."""
    reach = min(BOX_SDS * log_sd, MAX_BOX_REACH) if np.isfinite(log_sd) else MAX_BOX_REACH
    if reach <= MIN_REFERENCE_BOX:
        return tau, MIN_REFERENCE_BOX
    low, high = tau * math.exp(-reach), max(min(tau * math.exp(reach), max_time_constant_min), tau)
    return (low + high) / 2.0, (high - low) / (high + low)
