"""What the recorders of network sources (MTConnect, OPC UA) share: the CSV log they append to, and
a thread that records apart from the fits."""

from __future__ import annotations

import json
import math
import os
import queue
import threading
from collections.abc import Mapping
from pathlib import Path
from typing import Protocol

__all__ = ["RecordingThread", "last_logged_time", "quoted", "save_position"]


class _Source(Protocol):
    def fetch(self) -> list[str]: ...

    def close(self) -> None: ...


class RecordingThread:
    """A recorder fetched on its own thread, every ``period_s``: its rows reach the log while the
    watch's fits run, not only between them.

    Parameters
    ----------
    recorder : object
        An MTConnect or OPC UA recorder (``fetch() -> list[str]`` and ``close()``).
    period_s : float
        Seconds between two fetches.
    """

    def __init__(self, recorder: _Source, period_s: float) -> None:
        self.recorder = recorder
        self.period_s = period_s
        self._notes: queue.SimpleQueue[str] = queue.SimpleQueue()
        self._error: BaseException | None = None
        self._stop = threading.Event()
        self._first = threading.Event()
        self._thread = threading.Thread(target=self._run, name="mtident-recording", daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while True:
            try:
                notes = self.recorder.fetch()
            except BaseException as exc:  # noqa: BLE001 - raised again on the watch's thread by fetch()
                self._error = exc
                self._first.set()
                return
            for note in notes:
                self._notes.put(note)
            self._first.set()
            if self._stop.wait(self.period_s):
                return

    def fetch(self) -> list[str]:
        """What the recorder said since the last call (the first call waits for its first fetch).

        Returns
        -------
        list of str
            The recorder's notes (the source unreachable, back again, ...).

        Raises
        ------
        Exception
            What the recorder's fetch raised (a source that refuses the nodes or items asked for).
        """
        self._first.wait(timeout=60.0)
        notes = []
        while True:
            try:
                notes.append(self._notes.get_nowait())
            except queue.Empty:
                break
        if self._error is not None and not notes:
            error, self._error = self._error, None
            raise error
        return notes

    def close(self) -> None:
        """Stop fetching, and close the recorder (it writes what it holds)."""
        self._stop.set()
        self._thread.join(timeout=10.0)
        self.recorder.close()


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
