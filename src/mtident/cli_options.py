"""Options several commands share, built once (click decorators): a file to read, the file a
command writes, its picture, ``--json`` and the room sensor's column. Each command gives its own help
where what the option does differs between commands.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import click

from mtident.cli import F, OutputPath, PicturePath

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
