"""What the recorders of network sources (MTConnect, OPC UA) share: the CSV log they append to."""

from __future__ import annotations

import json
import math
import os
from collections.abc import Mapping
from pathlib import Path

__all__ = ["last_logged_time", "quoted", "save_position"]


def last_logged_time(log: Path) -> float:
    """The last row's time in the log (minus infinity for a log without rows).

    Parameters
    ----------
    log : Path
        The recorder's CSV log, whose first column is ``time_min``; only its last 4 KiB are read.

    Returns
    -------
    float
        The first cell of the last row that starts with a number (min from the first observation).
    """
    with log.open("rb") as handle:
        handle.seek(0, os.SEEK_END)
        handle.seek(max(0, handle.tell() - 4096))
        lines = [line for line in handle.read().decode("utf-8", "replace").splitlines() if line.strip()]
    for line in reversed(lines):
        try:
            return float(line.split(",", 1)[0])
        except ValueError:
            continue
    return -math.inf


def quoted(name: str) -> str:
    """A column name as a CSV header cell (quoted where it holds a comma, a quote or a line end).

    Parameters
    ----------
    name : str
        The column name, as the source calls the data item or node.

    Returns
    -------
    str
        ``name`` in double quotes with its quotes doubled, or ``name`` itself where it needs none.
    """
    return '"' + name.replace('"', '""') + '"' if any(c in name for c in ',"\n') else name


def save_position(sidecar: Path, position: Mapping[str, object]) -> None:
    """Write a recorder's sidecar atomically (a killed recorder leaves the old or the new one).

    Parameters
    ----------
    sidecar : Path
        The sidecar file, replaced by way of ``<sidecar>.partial`` in the same folder.
    position : dict
        What the recorder needs to go on after a restart (source, columns, origin, where it stopped);
        written as JSON, so its values must be JSON-serialisable.
    """
    partial = sidecar.with_name(sidecar.name + ".partial")
    partial.write_text(json.dumps(position), encoding="utf-8")
    os.replace(partial, sidecar)
