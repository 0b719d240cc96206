"""Options several commands share, built once (click decorators): a file to read, the file a
command writes, its picture, ``--json`` and the room sensor's column. Each command gives its own help
where what the option does differs between commands.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import click

from mtident.cli import F, FiniteFloatRange, OutputPath, PicturePath
from mtident.thermal import PRESETS
from mtident.thermal.modes import DEFAULT_MAX_TIME_CONSTANT_MIN
from mtident.thermal.robust_types import MAX_FREE_FAST

__all__ = ["ambient_option", "file_option", "json_option", "output_option", "plot_option"]


def file_option(*decls: str, help: str, **extra: Any) -> Callable[[F], F]:
    """An option that names a file to read (a path, not a folder).

    Parameters
    ----------
    *decls : str
        The option's names, as for ``click.option`` ("--state", "state_path").
    help : str
        The help text.
    **extra
        Further arguments of ``click.option`` (``metavar``).

    Returns
    -------
    callable
        The ``click.option`` decorator.
    """
    return click.option(*decls, type=click.Path(dir_okay=False), help=help, **extra)


def output_option(help: str) -> Callable[[F], F]:
    """The required ``-o``/``--output`` file a command writes (an :class:`OutputPath`); ``help``
    is its help text, and the value returned the ``click.option`` decorator, as for :func:`plot_option`."""
    return click.option("-o", "--output", "output_path", type=OutputPath(), required=True, help=help)


def plot_option(help: str) -> Callable[[F], F]:
    """The ``--plot`` picture a command draws (a :class:`PicturePath`).

    Parameters
    ----------
    help : str
        The help text: what the picture shows.

    Returns
    -------
    callable
        The ``click.option`` decorator.
    """
    return click.option("--plot", "plot_path", type=PicturePath(), help=help)


def json_option(instead_of: str = "a table") -> Callable[[F], F]:
    """The ``--json`` flag: one JSON object on stdout instead of what the command prints for a reader.

    Parameters
    ----------
    instead_of : str
        What the JSON object replaces, in the help ("a table").

    Returns
    -------
    callable
        The ``click.option`` decorator.
    """
    return click.option("--json", "as_json", is_flag=True, help=f"Print one JSON object instead of {instead_of}.")


def ambient_option(help: str) -> Callable[[F], F]:
    """The ``--ambient`` room-temperature column; ``help`` says what the room is to the command's fit,
    and the value returned is the ``click.option`` decorator, as for :func:`plot_option`."""
    return click.option("--ambient", "ambient_col", metavar="NAME", help=help)


# options several commands share (click decorators)
reference_option = file_option(
    "--reference",
    "reference_path",
    help="A reference run of this machine (from `mtident thermal learn`): each sensor's time constants are "
    "searched only near those it learnt, "
    "which lets a test stop far earlier; a test that does not follow them is said to and decided without them.",
)


machine_option = click.option(
    "--machine",
    "machine",
    metavar="NAME",
    help="The machine this test is of: a --reference learnt on another (learn --machine) is refused.",
)


free_fast_option = click.option(
    "--free-fast-modes",
    "free_fast_modes",
    type=click.IntRange(0, MAX_FREE_FAST),
    default=MAX_FREE_FAST,
    show_default=True,
    help="With --reference: how many free modes faster than the reference's slowest a test may add (a "
    "reference run can miss a mode; one more where the readings use them all). "
    "0 assumes the reference holds every mode of the machine: the earliest stops, resting on that assumption, "
    "which the answer states.",
)


preset_option = click.option(
    "--preset",
    type=click.Choice(PRESETS),
    default="data",
    show_default=True,
    help="First-order filters: initial values and tuning from the data, or a paper's exactly.",
)


max_time_constant_option = click.option(
    "--max-time-constant",
    "max_tau_min",
    type=FiniteFloatRange(min=1.0),
    default=DEFAULT_MAX_TIME_CONSTANT_MIN,
    show_default=True,
    help="The slowest thermal mode the machine may have (min). The interval covers every mode up to this that the "
    "data cannot exclude: "
    "a machine's bed or column warms with 1-5 h time constants.",
)


heat_enters_option = click.option(
    "--heat-enters-at",
    "heat_enters_at",
    multiple=True,
    metavar="NAME",
    help="A sensor that sits where the heat enters (on the spindle's bearing, the motor's housing), without a lag "
    "of its own; repeat. Fitted without a reference, its every mode rises: a slow mode not yet seen must already "
    "show in its rise, which bounds T∞ early. Yours to know: the answer states it, and readings that contradict "
    "it are fitted as any other sensor's, said so.",
)
