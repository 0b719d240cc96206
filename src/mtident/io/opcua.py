"""Temperatures straight from an OPC UA server, recorded to a CSV log that the monitor follows.

The :class:`OpcUaRecorder` subscribes to each node's data changes (with the server's source time
stamps, every change the server samples queued, not only the last of a publishing interval; a
trigger on the time stamp too, so a reading that repeats the one before is recorded, not taken
for a missing one) and writes them at each fetch, in time order, one row per time stamp. A time
stamp stepped far ahead of the others once is left out, and said; readings stamped before the
log's last row (a clock gone back) are left out, and said. A subscription made again after
a dropped connection starts with each node's value of now, written only where it is newer than
the last written: nothing twice. A bad status code is a missing reading. The values a node took
while the watch was stopped or the server could not be reached are read from the server's history
(HistoryRead) where it keeps one for the node; where it does not, they are not recorded, and the
recorder says so.

Every row goes to a CSV log (``time_min`` from the first value, one column per node, named by its
display name), which the watch follows like any logger's file, so the test can be replayed from
it afterwards with the same decision. Needs the ``asyncua`` package (``pip install mtident[opcua]``).
"""

from __future__ import annotations

import datetime as dt
import json
import math
import os
import queue
from pathlib import Path
from typing import Any

from mtident.exceptions import InputError
from mtident.io.record import last_logged_time, quoted, save_position

__all__ = ["OpcUaRecorder"]

SIDECAR_SUFFIX = ".opcua.json"
# The subscription's publishing interval, and how many changes of one node the server keeps
# between two publications (a sampling faster than the publishing loses none).
PUBLISHING_MS = 200.0
QUEUE_SIZE = 1000
# The server's clock (Server.ServerStatus.CurrentTime), read at each fetch to see a dropped connection.
SERVER_TIME = "i=2258"
# A time stamp this far (min) beyond the readings before it, and this many of the log's last steps,
# waits for the next reading: the clock moved on (a gap) or stepped ahead once (that stamp left out).
CLOCK_STEP_MIN = 10.0
CLOCK_STEP_STEPS = 10.0
# How many request timeouts a call to the client may wait before it is given up.
SYNC_WAITS = 4


def _new_client(url: str, timeout_s: float) -> Any:  # noqa: ANN401 - asyncua's sync Client
    """A client whose event loop runs in a daemon thread: a connection that hangs never keeps the
    watch's process alive at its end, and no call waits longer than a few of its timeouts."""
    try:
        from asyncua.sync import Client, ThreadLoop
    except ImportError as exc:
        msg = "reading an OPC UA server needs the asyncua package: pip install 'mtident[opcua]'"
        raise InputError(msg) from exc
    loop = ThreadLoop(timeout=SYNC_WAITS * timeout_s)
    loop.daemon = True
    loop.start()
    return Client(url, timeout=timeout_s, tloop=loop)


def _close(client: Any) -> None:  # noqa: ANN401
    """Disconnect, and stop the client's event-loop thread even where the connection is gone."""
    try:
        client.disconnect()
    except Exception:  # noqa: BLE001 - a connection already gone; the loop is stopped all the same
        pass
    finally:
        client.tloop.stop()


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
        self._changes = _Changes()
        self._notes: list[str] = []  # what _connect and _write found, said by the next fetch
        self._repeats_said = False
        self._pending: dict[dt.datetime, dict[int, float]] = {}
        self._step: dt.datetime | None = None  # a time stamp far beyond the others, waiting (see _held_step)
        self._step_from = dt.datetime.min.replace(tzinfo=dt.UTC)  # the reading before it
        self._row_step = 0.0  # min between the log's last two rows (a sparse source's steps are no clock step)
        self._index: dict[str, int] = {}
        self._sidecar = self.log.with_name(self.log.name + SIDECAR_SUFFIX)
        self.names: list[str] = []
        self.origin: dt.datetime | None = None
        self.last_stamp: dict[str, str] = {}
        self._resumed = self._sidecar.is_file()
        if self._resumed:
            saved = json.loads(self._sidecar.read_text(encoding="utf-8"))
            if saved.get("url") == url and sorted(saved.get("nodes", [])) == sorted(self.nodes):
                self.nodes = list(saved["nodes"])  # the log's columns keep their order
            else:
                msg = (
                    f"{self.log} was recorded from {saved.get('url')} nodes {', '.join(saved.get('nodes', []))}; to "
                    "record other nodes or another server, record to another log"
                )
                raise InputError(msg)
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
        client = _new_client(self.url, self.timeout_s)
        try:
            client.connect()
        except Exception:
            _close(client)  # its event loop's thread would keep the process alive
            raise
        try:
            nodes = [client.get_node(node) for node in self.nodes]
            if not self.names:
                self.names = [
                    node.read_display_name().Text or node_id for node, node_id in zip(nodes, self.nodes, strict=True)
                ]
            self._index = {node.nodeid.to_string(): i for i, node in enumerate(nodes)}
            self._changes.lost = False
            subscription = client.create_subscription(PUBLISHING_MS, self._changes)
            self._subscribe(subscription, nodes)
        except Exception as exc:
            _close(client)
            msg = f"{self.url}: cannot read the nodes {', '.join(self.nodes)} ({exc})"
            raise InputError(msg) from exc
        return client

    def _subscribe(self, subscription: Any, nodes: list[Any]) -> None:  # noqa: ANN401 - asyncua's
        """Subscribe to each node's values with a trigger on the time stamp as well as the value and
        status: a reading that repeats the one before (a sensor in 0.1 °C steps near equilibrium) is
        a reading, which the default trigger (status and value) would not report. Nodes whose server
        refuses the filter are subscribed with the default one, and that is said."""
        from asyncua import ua
        from asyncua.ua.attribute_ids import AttributeIds

        requests = []
        for handle, node in enumerate(nodes, start=1):
            parameters = ua.MonitoringParameters(
                ClientHandle=handle,
                SamplingInterval=0.0,
                QueueSize=QUEUE_SIZE,
                DiscardOldest=True,
                Filter=ua.DataChangeFilter(Trigger=ua.DataChangeTrigger.StatusValueTimestamp),
            )
            requests.append(
                ua.MonitoredItemCreateRequest(
                    ItemToMonitor=ua.ReadValueId(NodeId=node.nodeid, AttributeId=AttributeIds.Value),
                    MonitoringMode=ua.MonitoringMode.Reporting,
                    RequestedParameters=parameters,
                )
            )
        results = subscription.create_monitored_items(requests)
        refused = [node for node, result in zip(nodes, results, strict=True) if isinstance(result, ua.StatusCode)]
        if refused:
            for result in subscription.subscribe_data_change(refused, queuesize=QUEUE_SIZE):
                if isinstance(result, ua.StatusCode):
                    result.check()
            if not self._repeats_said:
                names = [self.names[nodes.index(node)] for node in refused]
                self._notes.append(
                    f"the OPC UA server at {self.url} refuses a trigger on the time stamp for {', '.join(names)}: a "
                    "reading that repeats the one before is not reported, and its row has an empty cell there"
                )
                self._repeats_said = True

    def close(self) -> None:
        """Write the changes received so far, and close the connection (the next fetch opens it again)."""
        self._write(self._changes.drain(self._index), final=True)
        if self._client is not None:
            _close(self._client)
            self._client = None

    def fetch(self) -> list[str]:
        """Write the data changes received since the last fetch; open the connection where it is
        closed, and close it where the server no longer answers.

        Returns
        -------
        list of str
            What the user should hear of: the server unreachable (once per outage) or back again.
        """
        notes: list[str] = []
        backlog: list[tuple[int, Any]] | None = []
        try:
            if self._client is None:
                self._client = self._connect()
                backlog = self._history()
            self._client.get_node(SERVER_TIME).read_value()  # a dropped connection shows here
            if self._changes.lost:
                raise ConnectionError("the subscription's status changed")
        except InputError:
            raise
        except Exception as exc:  # noqa: BLE001 - asyncua raises many kinds for a lost server
            self.close()
            if not self._unreachable:
                notes.append(f"the OPC UA server at {self.url} does not answer ({type(exc).__name__}); trying again")
            self._unreachable = True
            return notes
        if self._unreachable or self._resumed:
            again = (
                f"the OPC UA server at {self.url} answers again" if self._unreachable else f"recording {self.url} again"
            )
            meanwhile = "while it could not be reached" if self._unreachable else "while the watch was stopped"
            notes.append(
                f"{again}: the values it published {meanwhile} are not recorded (it keeps no history of the nodes)"
                if backlog is None
                else f"{again}: {_readings(backlog)} reading(s) it published {meanwhile} read from its history"
            )
            self._unreachable = self._resumed = False
        self._write((backlog or []) + self._changes.drain(self._index))
        notes += self._notes
        self._notes = []
        return notes

    def _history(self) -> list[tuple[int, Any]] | None:
        """The values each node took since the last one written, from the server's history (a
        watch stopped, a connection lost); None where the server keeps no history of the nodes."""
        from asyncua import ua
        from asyncua.ua.attribute_ids import AttributeIds

        backlog: list[tuple[int, Any]] = []
        now = dt.datetime.now(dt.UTC) + dt.timedelta(days=1)
        for i, node_id in enumerate(self.nodes):
            last = self.last_stamp.get(node_id)
            if last is None:
                continue
            node = self._client.get_node(node_id)
            start = dt.datetime.fromisoformat(last) + dt.timedelta(microseconds=1)
            try:
                access = node.read_attribute(AttributeIds.AccessLevel).Value.Value
                if not int(access) & ua.AccessLevel.HistoryRead.mask:
                    return None
                values = node.read_raw_history(start, now, 0, False)
            except Exception:  # noqa: BLE001 - BadHistoryOperationUnsupported and its kind
                return None
            backlog.extend((i, value) for value in values)
        return backlog

    def _write(self, changes: list[tuple[int, Any]], *, final: bool = False) -> None:
        """Append the rows not written yet, one per source time stamp, in time order.

        A server sends each node's change on its own, so the newest time stamp's row waits until
        every node has a value for it, a newer time stamp arrives, or the recorder closes
        (``final``): a row written early would lose the values of that time arriving later.

        A time stamp more than ``CLOCK_STEP_MIN`` beyond the readings before it waits too, until
        the next reading tells whether the clock moved on (a newer one: a gap, written) or stepped
        ahead once (one back in line: that stamp is the outlier, left out and said, and recording
        goes on). A reading stamped before the log's last row is left out (the log's times must
        increase), and said.
        """
        # in time order, whatever the order received (history and subscription interleave)
        stamped = sorted(
            ((stamp, i, value) for i, value in changes if (stamp := _stamp(value)) is not None),
            key=lambda c: (c[0], c[1]),
        )
        behind: dict[int, int] = {}
        arrived: list[dt.datetime] = []
        for stamp, i, value in stamped:
            last = self.last_stamp.get(self.nodes[i])
            if last is not None and stamp == dt.datetime.fromisoformat(last):
                continue  # written before: a subscription made again starts with the value of now
            if self.origin is not None and (stamp - self.origin).total_seconds() / 60.0 <= self.last_time_min:
                behind[i] = behind.get(i, 0) + 1  # the server's clock went back
                continue
            good = value.StatusCode is None or value.StatusCode.is_good()
            number = value.Value.Value if value.Value is not None else None
            self._pending.setdefault(stamp, {})[i] = (
                float(number) if good and isinstance(number, int | float) else math.nan
            )
            arrived.append(stamp)
        if behind:
            self._notes.append(
                f"{sum(behind.values())} reading(s) of {', '.join(self.names[i] for i in sorted(behind))} stamped "
                f"before the log's last row ({_utc(self._last_row())}) left out, as the log's times must increase: the "
                "OPC UA server's clock went back, or they came late"
            )
        held = self._held_step(arrived)
        newest = max(self._pending, default=None)
        ready = sorted(
            stamp
            for stamp, row in self._pending.items()
            if (held is None or stamp < held) and (final or stamp != newest or len(row) == len(self.nodes))
        )
        if ready:
            self._append({stamp: self._pending.pop(stamp) for stamp in ready})

    def _last_row(self) -> dt.datetime | None:
        """The time stamp of the log's last row (None before the first)."""
        if self.origin is None or not math.isfinite(self.last_time_min):
            return None
        return self.origin + dt.timedelta(minutes=self.last_time_min)

    def _held_step(self, arrived: list[dt.datetime]) -> dt.datetime | None:
        """The first time stamp pending that lies more than ``CLOCK_STEP_MIN`` (and
        ``CLOCK_STEP_STEPS`` of the log's last steps) beyond the readings before it, whose rows wait
        (None: none waits). One followed by a newer reading is a clock that moved on: it waits no
        more. One followed, in a later fetch, by readings back in line (more than that before it) is
        a stamp stepped ahead once: its rows are left out, and said."""
        step = dt.timedelta(minutes=max(CLOCK_STEP_MIN, CLOCK_STEP_STEPS * self._row_step))
        if self._step is not None:
            if any(stamp > self._step for stamp in arrived):
                self._step = None  # the clock moved on: a gap in the log, which the watch says
                return None
            elif any(stamp < self._step - step for stamp in arrived):
                outliers = {stamp: self._pending.pop(stamp) for stamp in sorted(self._pending) if stamp >= self._step}
                names = sorted({self.names[i] for row in outliers.values() for i in row})
                ahead = f"{(self._step - self._step_from).total_seconds() / 60.0:.0f} min ahead"
                self._notes.append(
                    f"the OPC UA server's clock stepped: {', '.join(names)}'s reading stamped {_utc(self._step)}, "
                    f"{ahead} of the readings before and after it; that reading is left out (its time is not "
                    "known) and recording goes on"
                )
                self._step = None
            else:
                return self._step
        previous = self._last_row()
        for stamp in sorted(self._pending):
            if previous is not None and stamp - previous > step:
                self._step, self._step_from = stamp, previous
                return stamp
            previous = stamp
        return None

    def _append(self, rows: dict[dt.datetime, dict[int, float]]) -> None:
        """Write ``rows`` (in time order) to the log, and each node's last time stamp to the sidecar."""
        if self.origin is None:
            self.origin = min(rows)
        new = not self.log.is_file() or self.log.stat().st_size == 0
        with self.log.open("a", encoding="utf-8", newline="") as out:
            if new:
                out.write("time_min," + ",".join(quoted(name) for name in self.names) + "\n")
            for stamp, row in rows.items():
                for i in row:
                    self.last_stamp[self.nodes[i]] = stamp.isoformat()
                t = (stamp - self.origin).total_seconds() / 60.0
                if t <= self.last_time_min:
                    continue  # not reached: _write leaves out what is stamped before the log's last row
                cells = ("" if i not in row or math.isnan(row[i]) else f"{row[i]:g}" for i in range(len(self.nodes)))
                out.write(f"{t:.6f}," + ",".join(cells) + "\n")
                if math.isfinite(self.last_time_min):
                    self._row_step = t - self.last_time_min
                self.last_time_min = t
            out.flush()
            os.fsync(out.fileno())
        self._save()


def _stamp(value: Any) -> dt.datetime | None:  # noqa: ANN401 - asyncua's DataValue
    """A value's source time stamp (else the server's), as an aware UTC time."""
    stamp = value.SourceTimestamp or value.ServerTimestamp
    if stamp is None:
        return None
    answer: dt.datetime | None = stamp if stamp.tzinfo else stamp.replace(tzinfo=dt.UTC)
    return answer


def _utc(stamp: dt.datetime | None) -> str:
    return "none" if stamp is None else f"{stamp.astimezone(dt.UTC):%Y-%m-%d %H:%M:%S} UTC"


def _readings(changes: list[tuple[int, Any]]) -> int:
    """How many rows ``changes`` make: their distinct source time stamps."""
    return len({value.SourceTimestamp or value.ServerTimestamp for _, value in changes})


class _Changes:
    """The subscription's handler: asyncua calls it from its own thread with each data change,
    which waits in a queue for the recorder's next fetch."""

    def __init__(self) -> None:
        self._queue: queue.SimpleQueue[tuple[str, Any]] = queue.SimpleQueue()
        self.lost = False

    def status_change_notification(self, status: Any) -> None:  # noqa: ANN401, ARG002
        self.lost = True  # the server ends or times out the subscription: subscribe again

    def datachange_notification(self, node: Any, val: Any, data: Any) -> None:  # noqa: ANN401, ARG002
        self._queue.put((node.nodeid.to_string(), data.monitored_item.Value))

    def drain(self, index: dict[str, int]) -> list[tuple[int, Any]]:
        """Every change received so far, as (the node's place in the recorder's list, DataValue)."""
        out: list[tuple[int, Any]] = []
        while True:
            try:
                node, value = self._queue.get_nowait()
            except queue.Empty:
                return out
            if node in index:
                out.append((index[node], value))
