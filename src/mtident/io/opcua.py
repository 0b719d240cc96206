"""Temperatures straight from an OPC UA server, recorded to a CSV log that the monitor follows.

The :class:`OpcUaRecorder` reads each node's value with its source time stamp at every poll
and writes a value once, at the first poll that sees its time stamp: a value read again is not
written twice, and a dropped connection is reopened at the next poll. A bad status code is a
missing reading. Values a node takes and leaves again between two polls, or while the server
cannot be reached, are not seen: poll faster than the server samples (the watch's ``--poll``).

Every row goes to a CSV log (``time_min`` from the first value, one column per node, named by
its display name), which the watch follows like any logger's file, so the test can be replayed
from it afterwards with the same decision. Needs the ``asyncua`` package
(``pip install mtident[opcua]``).
"""

from __future__ import annotations

import datetime as dt
import json
import math
import os
from pathlib import Path
from typing import Any

from mtident.exceptions import InputError
from mtident.io.record import last_logged_time, quoted, save_position

__all__ = ["OpcUaRecorder"]

SIDECAR_SUFFIX = ".opcua.json"


def _client_class() -> Any:  # noqa: ANN401 - asyncua's sync Client, imported when needed
    try:
        from asyncua.sync import Client
    except ImportError as exc:
        msg = "reading an OPC UA server needs the asyncua package: pip install 'mtident[opcua]'"
        raise InputError(msg) from exc
    return Client


def _close(client: Any) -> None:  # noqa: ANN401
    """Disconnect, and stop the client's event-loop thread even where the connection is gone."""
    try:
        client.disconnect()
    except Exception:  # noqa: BLE001 - a connection already gone; disconnect stops the loop all the same
        pass


class OpcUaRecorder:
    """Records OPC UA nodes' temperatures to a CSV log, from where it left off.

    Parameters
    ----------
    url : str
        The server, ``opc.tcp://host:4840``.
    log : Path
        The CSV log written (and followed by the watch); its sidecar ``LOG.opcua.json`` keeps each
        node's last time stamp, so a restarted recorder writes no value twice.
    nodes : list of str
        Node ids (``ns=2;s=Spindle.T1``), each a sensor named by its display name.
    timeout_s : float
        Seconds to wait for the server.
    """

    def __init__(self, url: str, log: Path, nodes: list[str], timeout_s: float = 5.0) -> None:
        if not nodes:
            msg = f"{url}: name the nodes to record (node ids such as ns=2;s=Spindle.T1)"
            raise InputError(msg)
        self.url = url
        self.log = Path(log)
        self.nodes = list(nodes)
        self.timeout_s = timeout_s
        self._client: Any = None
        self._unreachable = False
        self._sidecar = self.log.with_name(self.log.name + SIDECAR_SUFFIX)
        self.names: list[str] = []
        self.origin: dt.datetime | None = None
        self.last_stamp: dict[str, str] = {}
        if self._sidecar.is_file():
            saved = json.loads(self._sidecar.read_text(encoding="utf-8"))
            self.names = list(saved["names"])
            self.origin = None if saved["origin"] is None else dt.datetime.fromisoformat(saved["origin"])
            self.last_stamp = dict(saved["last_stamp"])
        self.last_time_min = last_logged_time(self.log) if self.log.is_file() else -math.inf

    def _save(self) -> None:
        saved = {
            "url": self.url,
            "nodes": self.nodes,
            "names": self.names,
            "origin": None if self.origin is None else self.origin.isoformat(),
            "last_stamp": self.last_stamp,
        }
        save_position(self._sidecar, saved)

    def _connect(self) -> Any:  # noqa: ANN401
        client = _client_class()(self.url, timeout=self.timeout_s)
        try:
            client.connect()
        except Exception:
            _close(client)  # its event loop's thread would keep the process alive
            raise
        if not self.names:
            try:
                self.names = [client.get_node(node).read_display_name().Text or node for node in self.nodes]
            except Exception as exc:
                _close(client)
                msg = f"{self.url}: cannot read the nodes {', '.join(self.nodes)} ({exc})"
                raise InputError(msg) from exc
        return client

    def close(self) -> None:
        """Close the connection (the next fetch opens it again)."""
        if self._client is not None:
            _close(self._client)
            self._client = None

    def fetch(self) -> list[str]:
        """Read every node once and append the values not written yet.

        Returns
        -------
        list of str
            What the user should hear of: the server unreachable (once per outage) or back again.
        """
        notes: list[str] = []
        try:
            if self._client is None:
                self._client = self._connect()
            values = [self._client.get_node(node).read_data_value(raise_on_bad_status=False) for node in self.nodes]
        except InputError:
            raise
        except Exception as exc:  # noqa: BLE001 - asyncua raises many kinds for a lost server
            self.close()
            if not self._unreachable:
                notes.append(f"the OPC UA server at {self.url} does not answer ({type(exc).__name__}); trying again")
            self._unreachable = True
            return notes
        if self._unreachable:
            notes.append(f"the OPC UA server at {self.url} answers again")
            self._unreachable = False
        self._append(values)
        self._save()
        return notes

    def _append(self, values: list[Any]) -> None:
        row: dict[int, float] = {}
        stamps: list[dt.datetime] = []
        for i, (node, value) in enumerate(zip(self.nodes, values, strict=True)):
            stamp = value.SourceTimestamp or value.ServerTimestamp
            if stamp is None:
                continue
            stamp = stamp if stamp.tzinfo else stamp.replace(tzinfo=dt.UTC)
            if self.last_stamp.get(node) == stamp.isoformat():
                continue  # read before
            self.last_stamp[node] = stamp.isoformat()
            good = value.StatusCode is None or value.StatusCode.is_good()
            number = value.Value.Value if value.Value is not None else None
            row[i] = float(number) if good and isinstance(number, int | float) else math.nan
            stamps.append(stamp)
        if not row:
            return
        if self.origin is None:
            self.origin = min(stamps)
        t = (max(stamps) - self.origin).total_seconds() / 60.0
        if t <= self.last_time_min:
            return  # a server clock that went back: the log's times must increase
        new = not self.log.is_file() or self.log.stat().st_size == 0
        with self.log.open("a", encoding="utf-8", newline="") as out:
            if new:
                out.write("time_min," + ",".join(quoted(name) for name in self.names) + "\n")
            cells = ("" if i not in row or math.isnan(row[i]) else f"{row[i]:g}" for i in range(len(self.nodes)))
            out.write(f"{t:.6f}," + ",".join(cells) + "\n")
            out.flush()
            os.fsync(out.fileno())
        self.last_time_min = t
