"""The network sources ``mtident thermal watch`` can follow: an MTConnect agent (http:// or
https://) or an OPC UA server (opc.tcp://), each recorded to the CSV log the watch reads.
"""

from __future__ import annotations

import contextlib
import urllib.parse
from collections.abc import Iterator
from pathlib import Path
from typing import Protocol

from mtident.exceptions import InputError
from mtident.io.mtconnect import MTConnectRecorder

__all__ = ["Recorder", "network_recorder"]


class Recorder(Protocol):
    """A network source recorded to the CSV log the watch follows.

    Attributes
    ----------
    log : Path
        The CSV log the readings are written to.
    """

    log: Path

    def fetch(self) -> list[str]:
        """Write the readings received since the last fetch to the log.

        Returns
        -------
        list of str
            What the user should hear of (the source unreachable, or back again).
        """
        ...

    def close(self) -> None:
        """Write what is left to the log, and close the connection."""
        ...


def network_recorder(
    file: str,
    device: str | None,
    nodes: tuple[str, ...],
    items: tuple[str, ...],
    record_path: str | None,
    from_buffer_start: bool,
    replay: bool,
) -> Recorder | None:
    """The recorder of an MTConnect agent (http:// or https://) or an OPC UA server (opc.tcp://)
    where FILE is one, else None; a source's options refused for a file.

    Parameters
    ----------
    file : str
        FILE: a log, an MTConnect agent's URL (http:// or https://) or an OPC UA server's
        (opc.tcp://).
    device : str or None
        --device: the MTConnect device's name.
    nodes : tuple of str
        --node: the OPC UA nodes to record.
    items : tuple of str
        --item: MTConnect data items as ID=NAME.
    record_path : str or None
        --record: the CSV to write (default: DEVICE.csv or HOST.csv in the current folder).
    from_buffer_start : bool
        --from-buffer-start.
    replay : bool
        --replay.

    Returns
    -------
    Recorder or None
        None for a log file.

    Raises
    ------
    InputError
        An option of one kind of source given for another or for a file, --replay with a source,
        or an --item that is not ID=NAME.
    """
    is_agent, is_server = file.startswith(("http://", "https://")), file.startswith("opc.tcp://")
    given = {
        "--device": device,
        "--item": items,
        "--from-buffer-start": from_buffer_start,
        "--node": nodes,
        "--record": record_path,
    }
    wrong = [
        name
        for name, value in given.items()
        if value and not (is_agent and name != "--node" or is_server and name in ("--node", "--record"))
    ]
    if wrong:
        msg = (
            f"{', '.join(wrong)}: not for "
            f"{'an OPC UA server' if is_server else 'an MTConnect agent' if is_agent else 'a log file'} "
            "(--device, --item and --from-buffer-start are for an MTConnect agent, http://host:5000; --node for an OPC "
            "UA server, opc.tcp://host:4840; --record for either)"
        )
        raise InputError(msg)
    if not (is_agent or is_server):
        return None
    if replay:
        msg = (
            f"{file}: --replay replays a log file; the readings are recorded (--record) and can be replayed from there"
        )
        raise InputError(msg)
    host = urllib.parse.urlparse(file).hostname or "source"
    log = Path(record_path) if record_path else Path.cwd() / f"{device or host}.csv"
    if is_server:
        import logging

        from mtident.io.opcua import OpcUaRecorder

        # the recorder says when the server does not answer; asyncua's own tracebacks of it are noise here
        logging.getLogger("asyncua").setLevel(logging.CRITICAL)
        with _record_hint():
            return OpcUaRecorder(file, log, list(nodes))
    mapping = {}
    for item in items:
        key, sep, name = item.partition("=")
        if not sep or not key.strip() or not name.strip():
            msg = f"--item {item!r}: expected ID=NAME (a data item's id or name, and the sensor's name)"
            raise InputError(msg)
        mapping[key.strip()] = name.strip()
    with _record_hint():
        return MTConnectRecorder(file, log, device, mapping or None, from_buffer_start=from_buffer_start)


@contextlib.contextmanager
def _record_hint() -> Iterator[None]:
    """A recorder's refusal to resume a log with the option that names another."""
    try:
        yield
    except InputError as error:
        raise InputError(f"{error} (--record FILE)") from None
