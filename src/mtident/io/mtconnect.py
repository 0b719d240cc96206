"""Temperatures straight from an MTConnect agent, recorded to a CSV log that the monitor follows.

An MTConnect agent publishes a machine's data items over HTTP: ``/probe`` describes the device
(its TEMPERATURE data items), ``/current`` the latest value of each, and ``/sample?from=N`` every
observation from sequence number N on, with the agent's buffer range in the header. The
:class:`MTConnectRecorder` asks for the samples from the next sequence it has not seen, so that
nothing is read twice or skipped across reconnects; a sequence that dropped out of the agent's
buffer, or an agent restarted with a new instance (its sequence numbers begin again), is said; a
new instance's buffer is read from its start.
``UNAVAILABLE`` is a missing reading.

Every observation is written to a CSV log (``time_min`` from the first observation, one column
per sensor, a row per time stamp), which the watch follows like any logger's file: the test can
be replayed and checked afterwards from that file, and gives the same decision.
"""

from __future__ import annotations

import datetime as dt
import json
import math
import os
import urllib.error
import urllib.parse
import urllib.request
import xml.etree.ElementTree as ET
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

from mtident.exceptions import InputError
from mtident.io.record import last_logged_time, quoted, save_position

__all__ = ["DataItem", "MTConnectRecorder", "Observation", "StreamHeader", "parse_probe", "parse_streams"]

# observations asked for at once (an agent's default buffer holds 131,072)
SAMPLE_COUNT = 1000
SIDECAR_SUFFIX = ".mtconnect.json"
_CELSIUS = {"CELSIUS", "CEL", "°C"}


@dataclass(frozen=True)
class DataItem:
    """A TEMPERATURE sample of the device's model.

    Attributes
    ----------
    id : str
        The data item's id, which its observations name.
    name : str or None
        Its name in the device's model, where it has one.
    units : str or None
        Its ``units`` (else ``nativeUnits``) as the agent states them ("CELSIUS"), or None.
    """

    id: str
    name: str | None
    units: str | None


@dataclass(frozen=True)
class Observation:
    """One value of a data item (NaN: UNAVAILABLE).

    Attributes
    ----------
    item : str
        The id of the data item it belongs to.
    time : datetime.datetime
        The agent's time stamp, timezone-aware (UTC where the stamp gives no offset).
    value : float
        The reading in the data item's units; NaN where the agent says UNAVAILABLE or the text is no number.
    sequence : int
        The agent's sequence number of the observation.
    """

    item: str
    time: dt.datetime
    value: float
    sequence: int


@dataclass(frozen=True)
class StreamHeader:
    """The agent's instance and the range of sequence numbers its buffer holds.

    Attributes
    ----------
    instance_id : str
        The agent's instance: a new one (after the agent restarted) numbers its sequence anew.
    first_sequence : int
        The oldest sequence number still in the agent's buffer.
    next_sequence : int
        The sequence number the next observation will get.
    """

    instance_id: str
    first_sequence: int
    next_sequence: int


def _local(tag: str) -> str:
    return tag.rsplit("}", 1)[-1]


def _parse(document: bytes, what: str) -> ET.Element:
    try:
        root = ET.fromstring(document)
    except ET.ParseError as exc:
        msg = f"the agent's {what} is no XML document ({exc})"
        raise InputError(msg) from exc
    if _local(root.tag) == "MTConnectError":
        errors = "; ".join(
            f"{e.get('errorCode', '?')}: {(e.text or '').strip()}" for e in root.iter() if _local(e.tag) == "Error"
        )
        msg = f"the agent refused the {what}: {errors or 'no reason given'}"
        raise InputError(msg)
    return root


def _device(root: ET.Element, device: str | None, kind: str) -> ET.Element:
    devices = [e for e in root.iter() if _local(e.tag) == kind]
    if device is not None:
        devices = [e for e in devices if device in (e.get("name"), e.get("uuid"), e.get("id"))]
    if not devices:
        names = [e.get("name") or e.get("uuid") for e in root.iter() if _local(e.tag) == kind]
        msg = (
            f"no device {device!r} at the agent; it has: {', '.join(n for n in names if n) or 'none'}"
            if device
            else "the agent describes no device"
        )
        raise InputError(msg)
    if len(devices) > 1:
        msg = f"the agent has {len(devices)} devices; name one ({', '.join(str(e.get('name')) for e in devices)})"
        raise InputError(msg)
    return devices[0]


def parse_probe(document: bytes, device: str | None = None) -> list[DataItem]:
    """The device's TEMPERATURE samples, from an ``MTConnectDevices`` document.

    Parameters
    ----------
    document : bytes
        The agent's answer to ``/probe``.
    device : str, optional
        The device's name, uuid or id (needed where the agent has several).

    Returns
    -------
    list of DataItem
        In the document's order.

    Raises
    ------
    InputError
        Where the document is no MTConnectDevices document or names no such device.
    """
    found = _device(_parse(document, "probe"), device, "Device")
    return [
        DataItem(e.get("id", ""), e.get("name"), e.get("units") or e.get("nativeUnits"))
        for e in found.iter()
        if _local(e.tag) == "DataItem" and e.get("type") == "TEMPERATURE" and e.get("category") == "SAMPLE"
    ]


def parse_streams(document: bytes, device: str | None = None) -> tuple[StreamHeader, list[Observation]]:
    """The header and the TEMPERATURE observations of an ``MTConnectStreams`` document.

    Parameters
    ----------
    document : bytes
        The agent's answer to ``/current`` or ``/sample``.
    device : str, optional
        The device's name or uuid.

    Returns
    -------
    header : StreamHeader
    observations : list of Observation
        In the order of their sequence numbers.
    """
    root = _parse(document, "sample")
    header = next((e for e in root.iter() if _local(e.tag) == "Header"), None)
    if header is None:
        msg = "the agent's answer has no Header"
        raise InputError(msg)
    head = StreamHeader(
        header.get("instanceId", ""), int(header.get("firstSequence", "0")), int(header.get("nextSequence", "0"))
    )
    streams = [e for e in root.iter() if _local(e.tag) == "DeviceStream"]
    if device is not None:
        streams = [e for e in streams if device in (e.get("name"), e.get("uuid"))]
    out = []
    for stream in streams:
        for e in stream.iter():
            if _local(e.tag) != "Temperature" or e.get("dataItemId") is None:
                continue
            text = (e.text or "").strip()
            try:
                value = float(text)
            except ValueError:
                value = math.nan  # UNAVAILABLE
            out.append(
                Observation(
                    e.get("dataItemId", ""), _timestamp(e.get("timestamp", "")), value, int(e.get("sequence", "0"))
                )
            )
    return head, sorted(out, key=lambda o: o.sequence)


def _timestamp(text: str) -> dt.datetime:
    stamp = dt.datetime.fromisoformat(text.replace("Z", "+00:00"))
    return stamp if stamp.tzinfo else stamp.replace(tzinfo=dt.UTC)


def _http_get(url: str, timeout_s: float) -> bytes:
    with urllib.request.urlopen(url, timeout=timeout_s) as answer:  # noqa: S310 - the user's agent URL
        return bytes(answer.read())


class MTConnectRecorder:
    """Records an agent's temperatures to a CSV log, from where it left off.

    Parameters
    ----------
    url : str
        The agent, ``http://host:5000``.
    log : Path
        The CSV log written (and followed by the watch); its sidecar ``LOG.mtconnect.json`` keeps
        the agent's instance and the next sequence number, so a restarted recorder goes on where
        it stopped.
    device : str, optional
        The device's name or uuid (needed where the agent has several).
    items : dict of str to str, optional
        Data item id (or name) to sensor name; default every TEMPERATURE sample of the device,
        named by its name (else its id).
    timeout_s : float
        Seconds to wait for the agent's answer.
    from_buffer_start : bool
        Begin with every observation the agent's buffer still holds (a test begun before the
        recorder); by default with the agent's current values, then everything after them.
    get : callable, optional
        ``get(url, timeout_s) -> bytes``; by default an HTTP GET.
    """

    def __init__(
        self,
        url: str,
        log: Path,
        device: str | None = None,
        items: dict[str, str] | None = None,
        timeout_s: float = 5.0,
        from_buffer_start: bool = False,
        get: Callable[[str, float], bytes] | None = None,
    ) -> None:
        self.url = url.rstrip("/")
        self.log = Path(log)
        self.device = device
        self.timeout_s = timeout_s
        self.from_buffer_start = from_buffer_start
        self._get = get or _http_get
        self._asked = items
        self._sidecar = self.log.with_name(self.log.name + SIDECAR_SUFFIX)
        self.columns: dict[str, str] = {}
        self.instance_id: str | None = None
        self.next_sequence: int | None = None
        self.origin: dt.datetime | None = None
        self.last_time_min = -math.inf
        self._unreachable = False
        if self._sidecar.is_file():
            self._load()

    # -- what is kept between runs ------------------------------------------------------------

    def _load(self) -> None:
        saved = json.loads(self._sidecar.read_text(encoding="utf-8"))
        if saved.get("url") != self.url or saved.get("device") != self.device:
            msg = (
                f"{self.log} was recorded from {saved.get('url')} device {saved.get('device')}; to record another "
                "agent or device, record to another log"
            )
            raise InputError(msg)
        self.columns = dict(saved["columns"])
        self.instance_id = saved["instance_id"]
        self.next_sequence = saved["next_sequence"]
        self.origin = None if saved["origin"] is None else dt.datetime.fromisoformat(saved["origin"])
        # the log, not the sidecar, says what was written: a recorder killed between the two
        # writes would otherwise write those rows again
        self.last_time_min = last_logged_time(self.log) if self.log.is_file() else -math.inf

    def _save(self) -> None:
        saved = {
            "url": self.url,
            "device": self.device,
            "columns": self.columns,
            "instance_id": self.instance_id,
            "next_sequence": self.next_sequence,
            "origin": None if self.origin is None else self.origin.isoformat(),
        }
        save_position(self._sidecar, saved)

    # -- the agent ----------------------------------------------------------------------------

    def _ask(self, path: str, **query: object) -> bytes:
        device = f"/{urllib.parse.quote(self.device)}" if self.device else ""
        url = f"{self.url}{device}/{path}" + (f"?{urllib.parse.urlencode(query)}" if query else "")
        return self._get(url, self.timeout_s)

    def _choose_columns(self) -> None:
        items = parse_probe(self._ask("probe"), self.device)
        if self._asked is not None:
            by_key = {key: item for item in items for key in (item.id, item.name) if key}
            missing = [key for key in self._asked if key not in by_key]
            if missing:
                have = ", ".join(f"{i.id} ({i.name})" if i.name else i.id for i in items) or "none"
                msg = f"no TEMPERATURE sample {', '.join(missing)} at the agent; it has: {have}"
                raise InputError(msg)
            self.columns = {by_key[key].id: name for key, name in self._asked.items()}
        else:
            self.columns = {item.id: item.name or item.id for item in items}
        if not self.columns:
            msg = "the agent's device has no TEMPERATURE sample to record"
            raise InputError(msg)
        not_celsius = [
            self.columns[i.id] for i in items if i.id in self.columns and i.units and i.units.upper() not in _CELSIUS
        ]
        if not_celsius:
            msg = f"{', '.join(not_celsius)}: not in degrees Celsius at the agent"
            raise InputError(msg)

    def close(self) -> None:
        """Nothing to close: each request is its own connection."""

    def fetch(self) -> list[str]:
        """Ask the agent for the observations since the last, and append them to the log.

        Returns
        -------
        list of str
            What happened that the user should hear of: the agent unreachable (once per outage),
            back again, restarted, or samples lost from its buffer.
        """
        notes: list[str] = []
        try:
            if not self.columns:
                self._choose_columns()
            if self.next_sequence is None:
                first = self._ask("sample", count=SAMPLE_COUNT) if self.from_buffer_start else self._ask("current")
                header, observations = parse_streams(first, self.device)
                self.instance_id = header.instance_id
            else:
                header, observations = self._samples_after()
                restarted = header.instance_id != self.instance_id
                notes += self._continuity(header)
                if restarted:  # a new instance: its buffer from its start, the first reading it took too
                    header, observations = parse_streams(
                        self._ask("sample", **{"from": header.first_sequence, "count": SAMPLE_COUNT}), self.device
                    )
        except (urllib.error.URLError, ConnectionError, TimeoutError, OSError) as exc:
            if not self._unreachable:
                notes.append(f"the agent at {self.url} does not answer ({exc}); trying again")
            self._unreachable = True
            return notes
        if self._unreachable:
            notes.append(f"the agent at {self.url} answers again")
            self._unreachable = False
        next_sequence = header.next_sequence
        if len(observations) >= SAMPLE_COUNT:
            # the answer was cut at the count: the last time stamp's observations may go on in the
            # next, so they are asked for again rather than written in part
            last = max(o.time for o in observations)
            next_sequence = min(o.sequence for o in observations if o.time == last)
            observations = [o for o in observations if o.time != last]
        self._append(observations)
        self.next_sequence = next_sequence
        self._save()
        return notes

    def _samples_after(self) -> tuple[StreamHeader, list[Observation]]:
        """The observations from the next sequence number on; where the agent refuses the request
        (a restarted agent numbers its sequence anew, and the number asked for is out of its range),
        the header of its current values, whose new instance :meth:`_continuity` then finds."""
        try:
            return parse_streams(
                self._ask("sample", **{"from": self.next_sequence, "count": SAMPLE_COUNT}), self.device
            )
        except (urllib.error.HTTPError, InputError) as refused:
            try:
                header, _ = parse_streams(self._ask("current"), self.device)
            except (InputError, urllib.error.HTTPError):
                raise refused from None
            if header.instance_id == self.instance_id:
                raise
            return header, []

    def _continuity(self, header: StreamHeader) -> list[str]:
        assert self.next_sequence is not None
        if header.instance_id != self.instance_id:
            self.instance_id = header.instance_id
            return ["the agent was restarted (a new instance): readings while it was down are not in the log"]
        if header.first_sequence > self.next_sequence:
            lost = header.first_sequence - self.next_sequence
            return [f"{lost} observation(s) dropped out of the agent's buffer before they were read"]
        return []

    def _append(self, observations: list[Observation]) -> None:
        wanted = [o for o in observations if o.item in self.columns]
        if not wanted:
            return
        if self.origin is None:
            self.origin = min(o.time for o in wanted)
        order = list(self.columns)
        rows: dict[float, dict[str, float]] = {}
        for o in wanted:
            t = (o.time - self.origin).total_seconds() / 60.0
            if t > self.last_time_min:  # written before a restart, or a repeat of /current's values
                rows.setdefault(t, {})[o.item] = o.value
        if not rows:
            return
        new = not self.log.is_file() or self.log.stat().st_size == 0
        with self.log.open("a", encoding="utf-8", newline="") as out:
            if new:
                out.write("time_min," + ",".join(quoted(self.columns[i]) for i in order) + "\n")
            for t in sorted(rows):
                cells = ("" if math.isnan(v) else f"{v:g}" for v in (rows[t].get(i, math.nan) for i in order))
                out.write(f"{t:.6f}," + ",".join(cells) + "\n")
            out.flush()
            os.fsync(out.fileno())
        self.last_time_min = max(rows)
