"""The ``mtident`` command. Thin: parse, call the library, print a table or one JSON object.

A user's own mistake (bad file, bad column, bad option) ends with a one-line
error on stderr and exit code 2, never a traceback.
"""

from __future__ import annotations

import importlib
import json
import math
import re
import sys
from collections.abc import Callable
from functools import wraps
from typing import TYPE_CHECKING, Any, Literal, TypedDict, TypeVar

import click
from rich.console import Console
from rich.errors import StyleSyntaxError
from rich.markup import escape
from rich.style import Style

from mtident import __version__
from mtident.exceptions import MtidentError

F = TypeVar("F", bound=Callable[..., Any])

if TYPE_CHECKING:  # click's parameter types are generic in its annotations, a plain class in click 8.1
    _PathParamType = click.ParamType[str]
else:
    _PathParamType = click.ParamType


# The library's messages name its parameters in backticks (`time_unit='s'`); the command line says
# the option instead (--time-unit s).
_OPTION_OF = {
    "time_unit": "--time-unit",
    "temperature_unit": "--unit",
    "time_col": "--time-col",
    "sensors": "--sensor",
    "sheet": "--sheet",
    "window_min": "--window",
    "max_time_constant_min": "--max-time-constant",
    "ambient_C": "--ambient",
    "room_C": "--ambient",
    "room_sensor": "--ambient",
    "method": "--method",
    "preset": "--preset",
    "pseudo_measurement_seed": "--pseudo-seed",
    "reference": "--reference",
    "room_wander_C_per_h": "--room-wander",
    "free_fast_modes": "--free-fast-modes",
    "wait_for": "--wait-for",
    "heat_enters_at": "--heat-enters-at",
}
_PARAMETER = re.compile(r"`(\w+)(?:=(?:'([^']*)'|\[([^\]]*)\]))?`")


def as_options(text: str) -> str:
    """A library message as the command line says it: each parameter named in backticks, with
    its value, becomes the option (``time_unit='s'`` -> ``--time-unit s``).

    Parameters
    ----------
    text : str
        A message from the library. Each parameter it names in backticks, alone or with a quoted
        value or a bracketed list, is replaced where the command line has an option for it
        (``time_unit``, ``temperature_unit``, ``time_col``, ``sensors``, ``sheet``, ``window_min``,
        ``max_time_constant_min``, ``ambient_C``, ``room_sensor``, ``method``, ``preset``, ``pseudo_measurement_seed``,
        ``reference``, ``room_wander_C_per_h``, ``free_fast_modes``); other words in backticks are kept as they
        are.

    Returns
    -------
    str
        The message with those parameters said as options (``--time-unit s``, ``--sensor a, b``).
    """

    def option(match: re.Match[str]) -> str:
        flag = _OPTION_OF.get(match[1])
        if flag is None:
            return match[0]
        value = match[2] if match[2] is not None else match[3]
        return f"{flag} {value}" if value else flag

    return _PARAMETER.sub(option, text)


def _said_as_options(value: Any) -> Any:
    if isinstance(value, str):
        return as_options(value)
    if isinstance(value, dict):
        return {k: _said_as_options(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_said_as_options(v) for v in value]
    return value


class OptionConsole(Console):
    """A rich Console that says the library's parameters as the command line's options.

    It takes the keyword arguments of ``rich.console.Console``.
    """

    def print(self, *objects: Any, **kwargs: Any) -> None:
        """Print as a rich Console does, each string with the library's parameters said as options.

        Parameters
        ----------
        *objects
            What to print; a string goes through :func:`as_options` first.
        **kwargs
            Passed on to ``rich.console.Console.print``.
        """
        markup = kwargs.get("markup", self._markup) is not False
        said = (as_options(o) if isinstance(o, str) else o for o in objects)
        super().print(*(_unknown_tags_kept(o) if markup and isinstance(o, str) else o for o in said), **kwargs)


_TAG = re.compile(r"(?<!\\)\[([^\[\]]*)\]")


def _unknown_tags_kept(text: str) -> str:
    """``text`` with every bracketed part that is no rich style escaped, so that it is printed as
    written: a user's column "Zeit [h]" or "spindle [front]" was printed as "Zeit " and "spindle"
    (rich took "[h]" for markup), while the messages' own "[bold green]" and "[/]" style them."""

    def kept(match: re.Match[str]) -> str:
        tag = match.group(1)
        if tag.startswith("/"):
            return match.group(0)
        try:
            Style.parse(tag)
        except StyleSyntaxError:
            return "\\" + match.group(0)
        return match.group(0)

    return _TAG.sub(kept, text)


def plain(text: str) -> str:
    """A user's text (a sensor's or a column's name) for a rich table's cell, printed as written
    ("spindle [front]", not "spindle")."""
    return escape(text)


def table_console(min_width: int = 100) -> OptionConsole:
    """A console for a table: as wide as the terminal and at least ``min_width``; writing to a
    file or a pipe, 200 columns (rich takes 80 there, and cut a table's last columns off).

    Parameters
    ----------
    min_width : int
        The narrowest the table is laid out (a narrower terminal wraps its lines).

    Returns
    -------
    OptionConsole
    """
    probe = OptionConsole()
    return OptionConsole(width=max(probe.width, min_width, 0 if probe.is_terminal else 200))


def prose_console() -> OptionConsole:
    """A console for the sentences around a table: wrapped at the terminal's own width (a table's
    console is laid out at least 100 wide, and its sentences ran past an 80-column terminal's
    edge); writing to a file or a pipe, a line per sentence, unwrapped, as a reader's editor or
    ``grep`` takes it.

    Returns
    -------
    OptionConsole
    """
    return OptionConsole(soft_wrap=not OptionConsole().is_terminal)


def print_json(payload: object) -> None:
    """Exactly one JSON object on stdout (the library's parameters said as options).

    Parameters
    ----------
    payload : dataclass or dict
        The answer: a record, written from its fields (:func:`~mtident._json.to_json_value`: NaN and
        infinity as null), or a dict of JSON types. Every string in it, nested ones too, has the
        library's parameters replaced by :func:`as_options`. It is written indented by 2, keys sorted.
    """
    from mtident._json import to_json_value

    tree = _said_as_options(to_json_value(payload))
    click.echo(json.dumps(tree, indent=2, sort_keys=True, allow_nan=False))


class FiniteFloatRange(click.FloatRange):
    """click.FloatRange that also refuses nan and ±inf (a NaN tolerance would silently never stop).

    It takes the arguments of ``click.FloatRange``: ``min``, ``max``, ``min_open``, ``max_open``
    and ``clamp``.
    """

    name = "finite float"

    def _describe_range(self) -> str:
        # click describes a range without bounds as "x<=None" in the help
        return "" if self.min is None and self.max is None else super()._describe_range()

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        """The option's number, checked against the range and for being finite.

        Parameters
        ----------
        value : object
            The option's value as given.
        param : click.Parameter or None
            The option, for the message.
        ctx : click.Context or None

        Returns
        -------
        float

        Raises
        ------
        click.BadParameter
            Not a number, outside the range, NaN or infinite.
        """
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return number


def number_option(*decls: str, default: float, help: str, **bounds: Any) -> Callable[[F], F]:
    """A finite-number option with its default shown in the help.

    Parameters
    ----------
    *decls : str
        The option's names, as for ``click.option`` ("--noise", "noise_fraction").
    default : float
        The value without the option.
    help : str
        The help text.
    **bounds
        The range: the arguments of :class:`FiniteFloatRange` (none: any finite number).

    Returns
    -------
    callable
        The ``click.option`` decorator.
    """
    return click.option(*decls, type=FiniteFloatRange(**bounds), default=default, show_default=True, help=help)


class OutputPath(_PathParamType):
    """A file to write: its folder exists and is writable, and it is no folder (checked before
    the work, so that a mistyped folder does not end a long run in an error).

    Attributes
    ----------
    name : str
        The type's name in the help.
    example : str
        A file name, for the message where a folder is given.
    """

    name = "file"
    example = "out.csv"  # a file name in the message for a folder given

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> str:
        """The file to write, checked before the work begins.

        Parameters
        ----------
        value : object
            The option's value as given (a path).
        param : click.Parameter or None
            The option, for the message.
        ctx : click.Context or None

        Returns
        -------
        str
            The path.

        Raises
        ------
        click.BadParameter
            A folder, or a file whose folder does not exist or is not writable.
        """
        import os
        from pathlib import Path

        path = Path(value)
        folder = path.parent
        if path.is_dir():
            self.fail(f"{value!r} is a folder; give a file name such as {str(path / self.example)!r}", param, ctx)
        if not folder.is_dir():
            self.fail(f"the folder {str(folder)!r} of {value!r} does not exist", param, ctx)
        if not os.access(folder, os.W_OK):
            self.fail(f"the folder {str(folder)!r} of {value!r} is not writable", param, ctx)
        return str(path)


class PicturePath(OutputPath):
    """A --plot file: an :class:`OutputPath` whose suffix is a format matplotlib writes (a mistyped
    folder used to end a long replay in an errno message about a temporary file, and 'fit.svg'
    was written as a PNG).

    Its attributes ``name`` and ``example`` are those of :class:`OutputPath`.
    """

    name = "picture"
    example = "plot.png"

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        """The picture file to write, checked as an :class:`OutputPath` and for its suffix.

        The parameters and the value returned are those of :meth:`OutputPath.convert`.

        Raises
        ------
        click.BadParameter
            What :class:`OutputPath` refuses, or a suffix of a format matplotlib does not write.
        """
        from pathlib import Path

        from mtident.report.plots import picture_format

        path = super().convert(value, param, ctx)
        try:
            picture_format(Path(path))
        except ValueError as exc:
            self.fail(str(exc), param, ctx)
        return path


def user_errors(func: F) -> F:
    """Turn MtidentError (and missing files) into a one-line error and exit code 2.

    Parameters
    ----------
    func : callable
        A click command's callback.

    Returns
    -------
    callable
        ``func`` wrapped: an ``MtidentError`` or ``OSError`` it raises is printed as
        ``mtident: error: <message>`` on stderr (parameters said as options) and the process exits
        with code 2; a Ctrl-C that reached compiled code (a SystemError carrying the
        KeyboardInterrupt) is a Ctrl-C again; any other exception passes through.
    """

    @wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except (MtidentError, OSError) as exc:
            click.echo(f"mtident: error: {as_options(str(exc))}", err=True)
            sys.exit(2)
        except SystemError as exc:
            if carried_interrupt(exc) is not None:
                raise KeyboardInterrupt from None
            raise

    return wrapper  # type: ignore[return-value]


def carried_interrupt(error: SystemError) -> KeyboardInterrupt | None:
    """The Ctrl-C a ``SystemError`` carries: one that lands while compiled code runs reaches
    Python as the interrupted call's SystemError, the KeyboardInterrupt chained to it.

    Parameters
    ----------
    error : SystemError

    Returns
    -------
    KeyboardInterrupt or None
        None where the error carries no Ctrl-C (a fault of its own).
    """
    # compiled code inside compiled code chains one SystemError to another before the Ctrl-C
    cause: BaseException | None = error
    seen: set[int] = set()
    while cause is not None and id(cause) not in seen:
        seen.add(id(cause))
        if isinstance(cause, KeyboardInterrupt):
            return cause
        if not isinstance(cause, SystemError):
            return None
        cause = cause.__cause__ or cause.__context__
    return None


class LazyGroup(click.Group):
    """A command group whose commands live in modules imported when first needed.

    ``mtident thermal ...`` then does not load the feed-drive code (nor ``--version`` either).
    The group names every module that registers a command on it: here, in one place.

    Parameters
    ----------
    *args, **kwargs
        Passed on to ``click.Group``.
    commands_modules : tuple of str
        Dotted names of the modules whose import registers the group's commands on it
        (``("mtident.cli_thermal", "mtident.cli_watch")``), imported in this order.
    """

    def __init__(self, *args: Any, commands_modules: tuple[str, ...], **kwargs: Any) -> None:
        super().__init__(*args, **kwargs)
        self.commands_modules = commands_modules

    def _register(self) -> None:
        for module in self.commands_modules:
            importlib.import_module(module)  # registers its commands on this group

    def list_commands(self, ctx: click.Context) -> list[str]:
        """The group's command names, its module imported first.

        Parameters
        ----------
        ctx : click.Context

        Returns
        -------
        list of str
        """
        self._register()
        return super().list_commands(ctx)

    def get_command(self, ctx: click.Context, cmd_name: str) -> click.Command | None:
        """The command named ``cmd_name``, its module imported first.

        Parameters
        ----------
        ctx : click.Context
        cmd_name : str

        Returns
        -------
        click.Command or None
            None where the group has no such command.
        """
        self._register()
        return super().get_command(ctx, cmd_name)


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="mtident")
def main() -> None:
    """When a machine tool's warm-up test can stop, and a ball-screw feed drive's stiffness and damping."""


# every command of a group is registered by importing the modules named here
@main.group(
    cls=LazyGroup,
    commands_modules=(
        "mtident.cli_thermal",
        "mtident.cli_learn",
        "mtident.cli_watch",
        "mtident.cli_report",
    ),
)
def thermal() -> None:
    """Thermal test acceleration: identify a warm-up from its first minutes."""


@main.group(cls=LazyGroup, commands_modules=("mtident.cli_feeddrive",))
def feeddrive() -> None:
    """Ball-screw feed drive: 4-DOF model, modes, simulation, identification."""


stderr = OptionConsole(stderr=True, soft_wrap=True)


class ColumnLayout(TypedDict, total=False):
    no_wrap: bool
    overflow: Literal["fold", "crop", "ellipsis", "ignore"]
    min_width: int
    max_width: int


def column_layout(column: str) -> ColumnLayout:
    """Numbers on one line; a long sensor name (a building-management point's, HOBOware's with
    its serial numbers) folded over several lines of 14 to 32 characters, so that it neither
    squeezes the numbers to "…" nor is squeezed to two letters in an 80-column terminal."""
    if column == "sensor":
        return {"overflow": "fold", "min_width": 14, "max_width": 32}
    if column == "status":  # words: wrapped at a space when the table is too wide
        return {"min_width": 9}
    if column.endswith("interval"):  # "low to high": wrapped after "to" in a narrow terminal
        return {"min_width": 8}
    return {"no_wrap": True}


def cell_text(value: object, digits: int = 2) -> str:
    """A number for a table's cell, ``digits`` after the point; "—" where there is none."""
    if value is None or (isinstance(value, float) and not math.isfinite(value)):
        return "—"  # no estimate yet (still collecting, or no steady state)
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)
