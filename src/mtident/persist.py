"""Saving and loading frozen dataclasses, generated from their fields.

A state (the live monitor's, say) is a tree of frozen dataclasses, tuples, numbers, strings
and numpy arrays. It is written as one ``.npz`` file: every array a member of its own, the
rest a JSON tree that names them. Nothing is kept by hand per class, so a field added to a
dataclass is saved and loaded with no more code. A file written before a field with a default
was added loads with that default; a file written for other fields is refused with the names
of the fields that do not match.
"""

from __future__ import annotations

import dataclasses
import io
import json
import math
import os
import tempfile
import types
import typing
from pathlib import Path
from typing import Any, TypeVar

import numpy as np

from mtident._json import walk_fields

__all__ = ["save_dataclass", "load_dataclass", "StateFileError"]

T = TypeVar("T")
_FORMAT = "mtident-state-1"


class StateFileError(ValueError):
    """A state file that cannot be read back into the asked class."""


def _encode(value: Any, arrays: dict[str, np.ndarray]) -> Any:
    """The JSON tree of ``value`` (:func:`~mtident._json.walk_fields`), its arrays moved to ``arrays``."""

    def leaf(item: Any) -> Any:
        if isinstance(item, np.ndarray):
            key = f"a{len(arrays)}"
            arrays[key] = item
            return {"__array__": key}
        if isinstance(item, float) and not math.isfinite(item):
            return {"__float__": repr(item)}
        if isinstance(item, np.generic):
            return item.item()
        return item

    return walk_fields(value, leaf, dict_as_pairs=True)


def save_dataclass(path: str | Path, value: object) -> None:
    """Write a dataclass tree to ``path`` atomically (a killed process leaves the old file or the
    new one, never half of one).

    Parameters
    ----------
    path : str or Path
    value : a dataclass instance
    """
    arrays: dict[str, np.ndarray] = {}
    tree = _encode(value, arrays)
    buffer = io.BytesIO()
    arrays["__tree__"] = np.array(json.dumps({"format": _FORMAT, "tree": tree}))
    np.savez(buffer, **arrays)  # type: ignore[arg-type]
    target = Path(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    handle, tmp = tempfile.mkstemp(dir=target.parent, prefix=target.name, suffix=".tmp")
    try:
        with os.fdopen(handle, "wb") as out:
            out.write(buffer.getvalue())
            out.flush()
            os.fsync(out.fileno())
        os.replace(tmp, target)
    except BaseException:  # Ctrl-C or a full disk half-way: no stray temporary file
        Path(tmp).unlink(missing_ok=True)
        raise


def load_dataclass(path: str | Path, cls: type[T]) -> T:
    """Read a dataclass tree written by :func:`save_dataclass` back as ``cls``.

    Parameters
    ----------
    path : str or Path
    cls : type
        The dataclass the file holds.

    Returns
    -------
    cls instance

    Raises
    ------
    StateFileError
        The file is not a state file, or holds other fields than ``cls`` has.
    """
    try:
        with np.load(Path(path), allow_pickle=False) as data:
            header = json.loads(str(data["__tree__"]))
            arrays = {k: data[k] for k in data.files if k != "__tree__"}
    except (OSError, ValueError, KeyError) as exc:
        msg = f"{path}: not a state file mtident can read ({exc})"
        raise StateFileError(msg) from exc
    if header.get("format") != _FORMAT:
        msg = f"{path}: a state file of another format ({header.get('format')!r})"
        raise StateFileError(msg)
    return typing.cast(T, _decode(header["tree"], cls, arrays, cls.__name__))


def _decode(value: Any, hint: Any, arrays: dict[str, np.ndarray], where: str) -> Any:
    origin = typing.get_origin(hint)
    if origin in (typing.Union, types.UnionType):
        options = [a for a in typing.get_args(hint) if a is not type(None)]
        return None if value is None else _decode(value, options[0], arrays, where)
    if isinstance(value, dict) and "__array__" in value:
        return arrays[value["__array__"]]
    if isinstance(value, dict) and "__float__" in value:
        return float(value["__float__"])
    if isinstance(hint, type) and dataclasses.is_dataclass(hint):
        hints = typing.get_type_hints(hint)
        names = {f.name for f in dataclasses.fields(hint) if f.init}
        # a field added since the file was written, with a default, takes its default
        optional = {
            f.name
            for f in dataclasses.fields(hint)
            if f.init and (f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING)
        }
        if not isinstance(value, dict) or not names - optional <= set(value) <= names:
            found = sorted(value) if isinstance(value, dict) else type(value).__name__
            msg = f"{where}: the state file holds {found}, {hint.__name__} has {sorted(names)}"
            raise StateFileError(msg)
        return hint(**{k: _decode(v, hints[k], arrays, f"{where}.{k}") for k, v in value.items()})
    if origin is tuple:
        args = typing.get_args(hint)
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_decode(v, args[0], arrays, where) for v in value)
        return tuple(_decode(v, a, arrays, where) for v, a in zip(value, args, strict=True))
    if origin is dict:
        key_hint, value_hint = typing.get_args(hint)
        return {_decode(k, key_hint, arrays, where): _decode(v, value_hint, arrays, where) for k, v in value}
    if hint is float:
        return float(value)
    return value
