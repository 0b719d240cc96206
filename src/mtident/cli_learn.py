"""``mtident thermal learn``: a reference run's modes learnt and written for later tests."""

from __future__ import annotations

import dataclasses
import math
import sys
from collections.abc import Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, TypedDict

import click
import numpy as np
from rich.table import Table

from mtident._json import fields_of, json_inline
from mtident.cli import column_layout, plain, print_json, stderr, table_console, thermal, user_errors
from mtident.cli_logs import CommandRequest, command_request, load_log_with_room, log_options
from mtident.cli_options import ambient_option, file_option, json_option, max_time_constant_option, output_option
from mtident.exceptions import InputError
from mtident.thermal.robust_types import RobustSettings, SensorModes

if TYPE_CHECKING:
    from mtident.thermal.reference import MachineReference


@thermal.command("learn")
@log_options
@ambient_option("Room-temperature column: an input of every mode's heat balance while learning.")
@max_time_constant_option
@output_option("The reference file to write (TOML), for --reference in identify and watch.")
@click.option(
    "--every-mode",
    "every_mode",
    is_flag=True,
    help="Say that the modes learnt are every mode of the machine (one learnt, a machine known to be first "
    "order): later tests then allow no free mode faster than them (--free-fast-modes 0 for these sensors), "
    "stop earliest, and state the assumption. Where the run merged or missed a mode, such stops can be wrong "
    "(docs: limits).",
)
@click.option(
    "--machine", metavar="NAME", default="", help="The machine the run is of (a test's --machine is held to it)."
)
@click.option("--serial", metavar="TEXT", default="", help="The machine's serial number.")
@click.option("--program", metavar="TEXT", default="", help="The program or spindle speed the run ran (8000 rpm).")
@click.option("--run-date", "run_date", metavar="DATE", default="", help="The day the run ran (2026-11-20).")
@file_option(
    "--update",
    "update_path",
    metavar="REFERENCE",
    help="A reference learnt before from another complete run of the same machine (a reference run, or a "
    "test that ran until its sensors settled): FILE's modes are pooled into it, narrower where the runs agree, "
    "holding both where they do not. -o may name the same file.",
)
@json_option()
@user_errors
def learn_command(**options: Any) -> None:
    """Learn each sensor's thermal modes from FILE, a warm-up that ran to equilibrium.

    The time constants belong to the machine's structure, not to the load: a later test of the
    same machine, with --reference, searches them only near these (never as exact), and may
    stop far earlier. A later test that does not follow them is said to (a changed machine).

    \f

    Parameters
    ----------
    **options
        The options by click's names, each with its help above (:func:`learn_request`).

    Raises
    ------
    InputError
        A log that cannot be read, or no sensor whose modes could be learnt.
    """
    run_learn(learn_request(options))


@dataclass(frozen=True, slots=True)
class LearnRequest(CommandRequest):
    """What ``thermal learn`` was asked, grouped (:func:`learn_request`).

    Attributes
    ----------
    log, room_col
        As in :class:`CommandRequest`.
    robust : RobustSettings
        --max-time-constant.
    output_path : str
        -o: the reference file to write.
    every_mode : bool
        --every-mode: later tests allow no free mode faster than the modes learnt.
    machine, serial, program, run_date : str
        --machine, --serial, --program and --run-date: what the run was of, written in the file.
    update_path : str or None
        --update: the reference to pool this run's modes into.
    as_json : bool
        --json.
    """

    robust: RobustSettings
    output_path: str
    every_mode: bool
    machine: str
    serial: str
    program: str
    run_date: str
    update_path: str | None
    as_json: bool


def learn_request(options: Mapping[str, Any]) -> LearnRequest:
    """The options of ``thermal learn`` (a mapping by click's names, their help the command's ``--help``),
    grouped into settings: a :class:`LearnRequest`.
    """
    return command_request(LearnRequest, options, robust=RobustSettings(max_time_constant_min=options["max_tau_min"]))


@dataclass(frozen=True, slots=True)
class MachineModelAnswer:
    """A reference's machine model as the JSON of ``thermal learn`` says it.

    Attributes
    ----------
    time_constants_min, box : tuple of float
        The shared modes' time constants (min) and their relative half-widths searched.
    gains_C : dict of str to tuple of float
        Per sensor, its amplitude of each mode (°C).
    room_lag_min : dict of str to float
        Per sensor whose path from the room was learnt, its lag behind the room (min).
    """

    time_constants_min: tuple[float, ...]
    box: tuple[float, ...]
    gains_C: dict[str, tuple[float, ...]]
    room_lag_min: dict[str, float]


class LearntRun(TypedDict):
    """The reference's own fields that the answer of ``thermal learn`` repeats under their names.

    Attributes
    ----------
    source, machine, serial, program, run_date : str
        The run's log and what it was of.
    max_time_constant_min : float
    room : str
        How the room entered.
    sensors : dict of str to SensorModes
        Each sensor's modes learnt.
    """

    source: str
    machine: str
    serial: str
    program: str
    run_date: str
    max_time_constant_min: float
    room: str
    sensors: dict[str, SensorModes]


@dataclass(frozen=True, slots=True)
class LearnAnswer:
    """The JSON answer of ``thermal learn``: the reference written, its fields.

    Attributes
    ----------
    reference : str
        The file written.
    run : LearntRun
        The reference's own fields, written as keys of the answer.
    machine_model : MachineModelAnswer or None
    warnings : tuple of str
    """

    reference: str
    run: LearntRun = json_inline()
    # mypy takes json_inline() for a default, so the fields after it have one too
    machine_model: MachineModelAnswer | None = None
    warnings: tuple[str, ...] = ()


def run_learn(request: LearnRequest) -> None:
    """Learn the reference a :class:`LearnRequest` asks for, write it, and print it as a table or JSON.

    Parameters
    ----------
    request : LearnRequest

    Raises
    ------
    InputError
        As :func:`learn_command`.
    """
    from mtident.thermal.pooling import pool_references
    from mtident.thermal.reference import load_reference, save_reference
    from mtident.thermal.reference_learning import learn_reference

    earlier = None if request.update_path is None else _earlier_reference(request.update_path, request.machine)
    # learn_reference says a column named as a room sensor itself
    log, room = load_log_with_room(request.log, request.room_col, say_rooms=False)
    with stderr.status(f"learning the modes of {len(log.sensors)} sensor(s)…"):
        reference, warnings = learn_reference(log, room, request.robust)
    reference = dataclasses.replace(
        reference, machine=request.machine, serial=request.serial, program=request.program, run_date=request.run_date
    )
    if earlier is not None:
        reference, pooled = pool_references(earlier, reference)
        warnings += [f"pooled with {request.update_path}: {text}" for text in pooled]
    if request.every_mode:
        reference = reference.holding_every_mode()
    for warning in warnings:
        stderr.print(f"mtident: warning: {warning}", highlight=False)
    if not reference.sensors:
        msg = f"{log.source}: no sensor's modes could be learnt; nothing written"
        raise InputError(msg)
    output_path = request.output_path
    save_reference(reference, output_path)
    try:
        # a file learn writes that identify and watch then refuse would be found a test too late
        load_reference(output_path)
    except InputError as exc:
        stderr.print(
            f"mtident: error: the reference written to {output_path} does not read back, a fault of mtident's "
            f"(please report it, with the log): {exc}",
            highlight=False,
        )
        raise SystemExit(1) from None
    doubtful = [name for name, m in reference.sensors.items() if m.doubt is not None]
    unused = (
        f"; none of its sensors will be used by later tests (each is doubtful: {', '.join(doubtful)})"
        if len(doubtful) == len(reference.sensors)
        else f"; later tests will not use {', '.join(doubtful)} (doubtful)"
        if doubtful
        else ""
    )
    stderr.print(f"mtident: reference written to {output_path}{unused}", highlight=False)
    if request.as_json:
        print_json(
            LearnAnswer(
                reference=str(output_path),
                run=fields_of(reference, LearntRun),
                machine_model=_machine_model_answer(reference),
                warnings=tuple(warnings),
            )
        )
    else:
        _learn_table(reference)
    _exit_if_none_used(reference)


def _earlier_reference(path: str, machine: str) -> MachineReference:
    """The reference --update names, refused where it is another machine's than --machine says."""
    from mtident.thermal.reference import load_reference

    earlier = load_reference(path)
    if earlier.machine and machine and earlier.machine != machine:
        msg = (
            f"--update {path} is of machine {earlier.machine!r}, and this run of {machine!r}: "
            "a reference pools runs of one machine (give the same --machine, or learn a new reference with -o)"
        )
        raise InputError(msg)
    return earlier


def _learn_table(reference: MachineReference) -> None:
    table = Table(title=f"{reference.identity}: modes learnt (time constants with their box)")
    for column in ("sensor", "time constants (min)", "amplitudes (°C)", "used by later tests"):
        table.add_column(column, justify="left" if column == "sensor" else "right", **column_layout(column))
    for name, m in reference.sensors.items():
        taus = m.box_words()
        used = "no" if m.doubt else "yes, no faster mode (--every-mode)" if m.free_fast_modes == 0 else "yes"
        # a mode split in two (a merge of two of the machine's) has no amplitude of its own: "—"
        amplitudes = ", ".join(f"{a:+.2f}" if math.isfinite(a) else "—" for a in m.amplitudes_C)
        table.add_row(plain(name), taus, amplitudes, used)
    table_console().print(table)
    model = reference.machine_model
    if model is not None:
        taus = SensorModes(model.time_constants_min, model.box).box_words()
        stderr.print(
            f"mtident: machine model: {len(model.time_constants_min)} modes shared by {len(model.sensors)} sensors "
            f"({taus} min); later tests fit every sensor together, each mode's amplitudes in this run's proportions"
            + (
                f"; the room's path into {model.learnt_room_sensors()} learnt: a later test's moving room is a known "
                "input"
                if model.room_gains
                else ""
            ),
            highlight=False,
        )


def _machine_model_answer(reference: MachineReference) -> MachineModelAnswer | None:
    model = reference.machine_model
    if model is None:
        return None
    return MachineModelAnswer(
        time_constants_min=model.time_constants_min,
        box=model.box,
        gains_C=dict(zip(model.sensors, model.gains_C, strict=True)),
        room_lag_min={
            name: float(np.dot(row, model.time_constants_min))
            for name, row in zip(model.sensors, model.room_gains or [(math.nan,)] * len(model.sensors), strict=True)
            if all(map(math.isfinite, row))
        },
    )


def _exit_if_none_used(reference: MachineReference) -> None:
    """Status 1 where every sensor is doubtful: a script must not go on to use a reference that
    teaches nothing (the file is written, to be read)."""
    if all(m.doubt is not None for m in reference.sensors.values()):
        sys.exit(1)
