"""The ``mtident`` command. Thin: parse, call the library, print a table or one JSON object.

A user's own mistake (bad file, bad column, bad option) ends with a one-line
error on stderr and exit code 2, never a traceback.
"""

from __future__ import annotations

import json
import math
import sys
from collections.abc import Callable
from functools import wraps
from typing import Any, TypeVar

import click

from mtident import __version__
from mtident.exceptions import MtidentError

F = TypeVar("F", bound=Callable[..., Any])


def print_json(payload: dict[str, Any]) -> None:
    """Exactly one JSON object on stdout."""
    click.echo(json.dumps(payload, indent=2, sort_keys=True, allow_nan=False))


class FiniteFloatRange(click.FloatRange):
    """click.FloatRange that also refuses nan and ±inf (a NaN tolerance would silently never stop)."""

    name = "finite float"

    def _describe_range(self) -> str:
        # click describes a range without bounds as "x<=None" in the help
        return "" if self.min is None and self.max is None else super()._describe_range()

    def convert(self, value: Any, param: click.Parameter | None, ctx: click.Context | None) -> Any:
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return number


def user_errors(func: F) -> F:
    """Turn MtidentError (and missing files) into a one-line error and exit code 2."""

    @wraps(func)
    def wrapper(*args: Any, **kwargs: Any) -> Any:
        try:
            return func(*args, **kwargs)
        except (MtidentError, OSError) as exc:
            click.echo(f"mtident: error: {exc}", err=True)
            sys.exit(2)

    return wrapper  # type: ignore[return-value]


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(__version__, prog_name="mtident")
def main() -> None:
    """Machine-tool identification with unscented Kalman filters."""


@main.group()
def thermal() -> None:
    """Thermal test acceleration: identify a warm-up from its first minutes."""


@main.group()
def feeddrive() -> None:
    """Ball-screw feed drive: 4-DOF model, modes, simulation, identification."""


from mtident import cli_feeddrive as _cli_feeddrive  # noqa: E402,F401  (registers the feed-drive commands)
from mtident import cli_thermal as _cli_thermal  # noqa: E402,F401  (registers the thermal commands)
