"""Answers as JSON values, generated from their fields.

One walk over a tree of frozen dataclasses, tuples, dicts, numbers, strings and numpy arrays
(:func:`walk_fields`) serves both the JSON answers (:func:`to_json_value`) and the state files
(:mod:`mtident.persist`): a field added to a result is in its JSON with no more code.
"""

from __future__ import annotations

import dataclasses
import enum
import math
from collections.abc import Callable, Mapping
from typing import Any, TypeVar, cast

import numpy as np

__all__ = [
    "SensorAnswers",
    "fields_of",
    "finite_or_none",
    "json_inline",
    "json_optional",
    "to_json_value",
    "walk_fields",
]

# a TypedDict: the keys :func:`fields_of` takes, with their types
_Keys = TypeVar("_Keys", bound=Mapping[str, object])

# field metadata that :func:`walk_fields` reads: a field written only where it is not None, and a
# field whose own fields (or items) are written into its parent's object
_OPTIONAL = "mtident_json_optional"
_INLINE = "mtident_json_inline"


def json_optional() -> Any:
    """A dataclass field, None by default, that :func:`walk_fields` leaves out where it is None
    (a key an answer has only in some cases).

    Returns
    -------
    dataclasses.Field
        For a field's default: ``note: str | None = json_optional()``.

    Examples
    --------
    :func:`json_inline`'s example has such a field, ``onset_min``.
    """
    return dataclasses.field(default=None, metadata={_OPTIONAL: True})


def json_inline() -> Any:
    """A dataclass field (a dataclass or a dict with string keys) whose fields or items
    :func:`walk_fields` writes into the object of the dataclass that holds it, not as an object of
    its own (the keys a method adds to an answer's common ones).

    Returns
    -------
    dataclasses.Field
        For a field's default: ``method: FirstOrderAnswer = json_inline()``; the field has no default.

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> @dataclass(frozen=True)
    ... class Answer:
    ...     sensor: str
    ...     extra: dict[str, float] = json_inline()
    ...     onset_min: float | None = json_optional()
    >>> to_json_value(Answer("T1", {"steady_state_ci99_C": 30.5}))
    {'sensor': 'T1', 'steady_state_ci99_C': 30.5}
    >>> to_json_value(Answer("T1", {}, 12.0))
    {'sensor': 'T1', 'onset_min': 12.0}
    """
    return dataclasses.field(metadata={_INLINE: True})


def finite_or_none(value: float) -> float | None:
    """A float for JSON, or None where it is not finite (JSON has no NaN or infinity).

    Parameters
    ----------
    value : float
        Any number (a numpy scalar too); it is converted with ``float``.

    Returns
    -------
    float or None
        ``value`` as a plain float, or None where it is NaN or ±infinity.

    Examples
    --------
    >>> finite_or_none(1.5), finite_or_none(float("nan")), finite_or_none(float("inf"))
    (1.5, None, None)
    """
    value = float(value)
    return value if math.isfinite(value) else None


def fields_of(source: object, keys: type[_Keys]) -> _Keys:
    """The attributes of ``source`` that the TypedDict ``keys`` names, as that TypedDict: for an
    answer that repeats keys of what it is made from under the same names.

    The result is typed: mypy checks each key and its type where it is used (unpacked into a
    record's constructor, or held in a field), which a plain dict of names would not. That
    ``source`` has each key is checked as it is read (an AttributeError names the one it lacks).

    Parameters
    ----------
    source : object
        The object the keys are taken from (a dataclass).
    keys : type
        A TypedDict: the names to take, in its order, and their types.

    Returns
    -------
    dict
        A ``keys``.

    Examples
    --------
    >>> from types import SimpleNamespace
    >>> from typing import TypedDict
    >>> class Rise(TypedDict):
    ...     sensor: str
    ...     rise_C: float
    >>> fields_of(SimpleNamespace(sensor="T1", rise_C=2.5, noise_C=0.01), Rise)
    {'sensor': 'T1', 'rise_C': 2.5}
    """
    return cast(_Keys, {name: getattr(source, name) for name in keys.__annotations__})


def walk_fields(value: Any, leaf: Callable[[Any], Any], *, dict_as_pairs: bool = False) -> Any:
    """A tree of plain containers: a dataclass as a dict of its fields (in their order), a tuple
    or list as a list, a dict as a dict (or as ``[key, value]`` pairs), every other value through
    ``leaf``. A field made with :func:`json_optional` is left out where it is None; one made with
    :func:`json_inline` has its own fields or items written in its place.

    Parameters
    ----------
    value : object
        A dataclass instance, a container of them, or a leaf.
    leaf : callable
        Turns a value that is none of the above (a number, a string, an array, None) into its
        encoded form.
    dict_as_pairs : bool, optional
        Write a dict as a list of ``[key, value]`` pairs, for keys that are not strings (a state
        file's intervals keyed by level); keys are walked as values then.

    Returns
    -------
    object
        The walked tree.

    Raises
    ------
    TypeError
        A :func:`json_inline` field whose value does not walk to a dict.

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> @dataclass(frozen=True)
    ... class Mode:
    ...     time_constant_min: float
    ...     amplitude_C: float
    >>> walk_fields((Mode(12.0, -3.5),), str)
    [{'time_constant_min': '12.0', 'amplitude_C': '-3.5'}]
    """
    if dataclasses.is_dataclass(value) and not isinstance(value, type):
        tree: dict[str, Any] = {}
        for f in dataclasses.fields(value):
            item = getattr(value, f.name)
            if item is None and f.metadata.get(_OPTIONAL):
                continue
            walked = walk_fields(item, leaf, dict_as_pairs=dict_as_pairs)
            if not f.metadata.get(_INLINE):
                tree[f.name] = walked
            elif isinstance(walked, dict):
                tree.update(walked)
            else:
                msg = f"{type(value).__name__}.{f.name}: an inline field walks to a dict, not {type(walked).__name__}"
                raise TypeError(msg)
        return tree
    if isinstance(value, tuple | list):
        return [walk_fields(v, leaf, dict_as_pairs=dict_as_pairs) for v in value]
    if isinstance(value, dict):
        if dict_as_pairs:
            return [
                [walk_fields(k, leaf, dict_as_pairs=True), walk_fields(v, leaf, dict_as_pairs=True)]
                for k, v in value.items()
            ]
        return {k: walk_fields(v, leaf) for k, v in value.items()}
    return leaf(value)


def to_json_value(value: Any) -> Any:
    """The JSON value of a result, from its fields: a dataclass as an object of its fields, tuples
    and arrays as lists, an enumeration as its value, and None where a number is not finite (JSON
    has no NaN or infinity).

    Parameters
    ----------
    value : object
        A dataclass instance (frozen, with JSON-able fields), a container of them, or a leaf.

    Returns
    -------
    object
        dicts, lists, strings, plain numbers, booleans and None, for ``json.dumps``.

    Examples
    --------
    >>> from dataclasses import dataclass
    >>> import numpy as np
    >>> @dataclass(frozen=True)
    ... class Answer:
    ...     sensor: str
    ...     steady_state_C: float
    ...     interval_C: tuple[float, float]
    ...     times_min: np.ndarray
    >>> to_json_value(Answer("T1", np.float64(24.5), (24.1, float("inf")), np.array([1.0, np.nan])))
    {'sensor': 'T1', 'steady_state_C': 24.5, 'interval_C': [24.1, None], 'times_min': [1.0, None]}
    """
    return walk_fields(value, _json_leaf)


class SensorAnswers:
    """A result of every sensor of a log whose JSON, sensor by sensor, is its answer record's fields."""

    def answer(self, index: int) -> Any:
        """The answer record, a frozen dataclass, of the sensor at ``index`` (each result has its own)."""
        raise NotImplementedError

    def summary(self, index: int) -> dict[str, object]:
        """The JSON object of one sensor (the documentation's JSON page): :meth:`answer`'s fields.

        Parameters
        ----------
        index : int
            Which sensor, as for :meth:`answer`.

        Returns
        -------
        dict
            JSON types; None where a value is not finite.
        """
        summary: dict[str, object] = to_json_value(self.answer(index))
        return summary


def _json_leaf(value: Any) -> Any:
    if isinstance(value, np.ndarray):
        return walk_fields(value.tolist(), _json_leaf)
    if isinstance(value, enum.Enum):
        return value.value
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, float) and not math.isfinite(value):
        return None
    return value
