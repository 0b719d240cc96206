"""Temperatures from an OPC UA server: the recorder against a real asyncua server on the loopback
interface, stopped and started again mid-test; bad status codes as missing readings."""

from __future__ import annotations

import asyncio
import datetime as dt
import socket

import numpy as np
import pytest
from asyncua import ua  # noqa: E402
from asyncua.sync import Server, ThreadLoop  # noqa: E402
from conftest import wait_until
from helpers import mtident

from mtident.exceptions import InputError  # noqa: E402
from mtident.io.logs import read_temperature_log  # noqa: E402
from mtident.io.opcua import OpcUaRecorder  # noqa: E402

pytest.importorskip("asyncua", reason="the OPC UA source needs the asyncua package (mtident[opcua])")


START = dt.datetime(2026, 11, 24, 8, 0, tzinfo=dt.UTC)


NODES = ["ns=2;s=Spindle.T1", "ns=2;s=Spindle.T2"]


def _free_port() -> int:
    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        return int(probe.getsockname()[1])


class Machine:
    """An OPC UA server with two temperature nodes, started and stopped on one port; started again,
    its nodes hold their last values, as a controller's would."""

    def __init__(self, history: bool = True) -> None:
        self.history = history
        self.url = f"opc.tcp://127.0.0.1:{_free_port()}/mtident/"
        self.server: Server | None = None
        self.variables: list = []
        self.last: tuple[float, tuple[float, float]] | None = None

    def start(self) -> None:
        loop = ThreadLoop()
        loop.daemon = True  # a test that fails mid-way leaves no thread that keeps pytest alive
        loop.start()
        server = Server(tloop=loop)
        server.set_endpoint(self.url)
        idx = server.register_namespace("urn:mtident:test")
        assert idx == 2
        spindle = server.nodes.objects.add_object(idx, "Spindle")
        self.variables = [
            spindle.add_variable(node, name, 20.0) for node, name in zip(NODES, ("T1", "T2"), strict=True)
        ]
        server.start()
        self.server = server
        # the nodes hold the last values published (a fresh machine: the minute before the test), then
        # the server keeps their values (in memory, lost with it)
        last = self.last
        self.publish(*(last or (-1.0, (20.0, 20.0))))
        self.last = last
        if self.history:
            # kept without a period: the stamps are of a fixed past day, and asyncua's default of seven
            # days would drop them as too old once the calendar passes it
            nodes = [v.aio_obj for v in self.variables]
            server.tloop.post(server.aio_obj.historize_node_data_change(nodes, period=None))

    def stop(self) -> None:
        assert self.server is not None
        server, self.server = self.server, None
        # the server's clock task sleeps a second between ticks, and its stop waits for the tick
        iserver = server.aio_obj.iserver
        clock, iserver.time_task = iserver.time_task, None
        if clock is not None:
            server.tloop.loop.call_soon_threadsafe(clock.cancel)
        server.stop()
        server.tloop.post(_end_what_is_left(iserver))
        server.tloop.stop()

    def historized(self, minute: float, timeout_s: float = 10.0) -> None:
        """Wait until the server's history holds every node's value of ``minute`` (it takes each
        change at its own sampling, a moment after the write)."""
        stamp = START + dt.timedelta(minutes=minute)
        wait_until(
            lambda: all(v.read_raw_history(stamp, stamp + dt.timedelta(seconds=1), 0, False) for v in self.variables),
            f"the server's history taking minute {minute}",
            timeout_s,
        )

    def publish(self, minute: float, values: tuple[float, float], good: bool = True) -> None:
        self.last = (minute, values)
        stamp = START + dt.timedelta(minutes=minute)
        status = ua.StatusCode(ua.StatusCodes.Good if good else ua.StatusCodes.BadSensorFailure)
        for variable, value in zip(self.variables, values, strict=True):
            variable.write_value(
                ua.DataValue(
                    ua.Variant(value, ua.VariantType.Double), status, SourceTimestamp=stamp, ServerTimestamp=stamp
                )
            )


async def _end_what_is_left(iserver) -> None:  # noqa: ANN001 - asyncua's InternalServer
    """End what a stopped server leaves running on its event loop: the session of a client that was
    connected (it outlives the connection, for the client to come back), with its subscriptions'
    publishing loops and its timeout watchdog. Left pending on a loop that is stopped, each is
    "Task was destroyed but it is pending!" at the interpreter's exit."""
    for session in list(iserver._external_sessions.values()):
        await session.close_session(True)
    left = [task for task in asyncio.all_tasks() if task is not asyncio.current_task()]
    for task in left:
        task.cancel()
    await asyncio.gather(*left, return_exceptions=True)


def settle(recorder: OpcUaRecorder, rows: int, timeout_s: float = 10.0) -> list[str]:
    """Fetch until the log holds ``rows`` data rows (the subscription delivers its changes at its
    publishing interval); what the recorder said on the way."""
    said: list[str] = []

    def written() -> list[int] | None:
        said.extend(recorder.fetch())
        count = recorder.log.read_text().count("\n") - 1 if recorder.log.is_file() else 0
        return [count] if count >= rows else None

    assert wait_until(written, f"{rows} rows in {recorder.log.name}", timeout_s) == [rows]
    return said


def change(minute: float, value: float) -> ua.DataValue:
    """A node's good value of the test's ``minute``, stamped by its source."""
    stamp = START + dt.timedelta(minutes=minute)
    return ua.DataValue(ua.Variant(value, ua.VariantType.Double), SourceTimestamp=stamp)


def _offline_recorder(tmp_path) -> OpcUaRecorder:  # noqa: ANN001
    """A recorder of the two nodes that is given its changes by hand, never connected."""
    recorder = OpcUaRecorder("opc.tcp://127.0.0.1:1/", tmp_path / "opc.csv", NODES)
    recorder.names = ["T1", "T2"]
    return recorder


@pytest.fixture
def machine():  # noqa: ANN201
    m = Machine()
    m.start()
    yield m
    if m.server is not None:
        m.stop()


@pytest.fixture(scope="session")
def running_machine():  # noqa: ANN201
    """One server for the tests that neither stop it nor read its history (a start takes seconds);
    each publishes the values it records before it connects."""
    m = Machine()
    m.start()
    yield m
    m.stop()


@pytest.mark.slow
def test_a_stopped_and_restarted_server_writes_each_value_once(machine, tmp_path):
    log = tmp_path / "opc.csv"
    recorder = OpcUaRecorder(machine.url, log, NODES)
    published = []
    machine.publish(0.0, (20.0, 21.0))
    published.append(0)
    assert settle(recorder, 1) == []
    for k in range(1, 10):  # faster than the publishing interval: every change is kept
        machine.publish(float(k), (20 + k / 10, 21 + k / 10))
        published.append(k)
    assert settle(recorder, 10) == []
    assert settle(recorder, 10) == []  # nothing written twice
    machine.stop()
    notes = recorder.fetch()
    assert len(notes) == 1 and "does not answer" in notes[0]
    assert recorder.fetch() == []
    machine.start()  # subscribed again, the nodes' values of now (minute 9) are not written again
    said = settle(recorder, 10)  # a server started again has no history of its outage: nothing to read
    assert said == [
        f"the OPC UA server at {machine.url} answers again: 0 reading(s) it published while it could not be reached "
        "read from its history"
    ]
    for k in range(10, 15):
        machine.publish(float(k), (20 + k / 10, 21 + k / 10))
        published.append(k)
        assert settle(recorder, k + 1) == []
    recorder.close()
    again = OpcUaRecorder(machine.url, log, NODES)  # a watch started again goes on from its sidecar
    machine.publish(15.0, (21.5, 22.5))
    published.append(15)
    machine.historized(15.0)
    assert settle(again, 16) == [
        f"recording {machine.url} again: 1 reading(s) it published while the watch was stopped read from its history"
    ]
    machine.publish(16.0, (21.6, 22.6))  # received, not yet fetched: written when the watch closes
    published.append(16)
    wait_until(lambda: again._changes._queue.qsize() >= 2, "both nodes' changes of minute 16 received")
    again.close()
    recorded = read_temperature_log(log)
    np.testing.assert_allclose(recorded.time_min, published)
    np.testing.assert_allclose(recorded.temperature_C[:, 0], [20 + k / 10 for k in published])
    assert recorded.sensors == ("T1", "T2")


@pytest.mark.slow
@pytest.mark.xdist_group("one OPC UA server")
def test_a_bad_status_is_a_missing_reading(running_machine, tmp_path):
    recorder = OpcUaRecorder(running_machine.url, tmp_path / "bad.csv", NODES)
    running_machine.publish(0.0, (20.0, 21.0))
    settle(recorder, 1)
    running_machine.publish(1.0, (99.0, 99.0), good=False)
    settle(recorder, 2)
    recorder.close()
    lines = (tmp_path / "bad.csv").read_text().splitlines()
    assert lines == ["time_min,T1,T2", "0.000000,20,21", "1.000000,,"]


@pytest.mark.slow
@pytest.mark.parametrize(
    ("history", "said", "minutes"),
    [
        (True, "5 reading(s) it published while the watch was stopped read from its history", [0, 1, 2, 3, 4, 5]),
        # without a history, only the value of now
        (
            False,
            "the values it published while the watch was stopped are not recorded (it keeps no history of the nodes)",
            [0, 5],
        ),
    ],
)
def test_values_published_while_the_watch_was_stopped_come_from_the_servers_history(tmp_path, history, said, minutes):
    machine = Machine(history)
    machine.start()
    try:
        log = tmp_path / "opc.csv"
        recorder = OpcUaRecorder(machine.url, log, NODES)
        machine.publish(0.0, (20.0, 21.0))
        settle(recorder, 1)
        recorder.close()  # the watch stopped
        for k in range(1, 6):
            machine.publish(float(k), (20 + k / 10, 21 + k / 10))
        if history:
            machine.historized(5.0)
        again = OpcUaRecorder(machine.url, log, NODES)
        notes = settle(again, len(minutes))
        again.close()
    finally:
        machine.stop()
    assert notes == [f"recording {machine.url} again: {said}"]
    assert [line.split(",")[0] for line in log.read_text().splitlines()[1:]] == [f"{m:.6f}" for m in minutes]


def test_changes_are_written_in_time_order_whatever_the_order_received(tmp_path):
    # a value of a later time received first (history and subscription interleave) does not hide
    # the earlier ones
    recorder = _offline_recorder(tmp_path)
    recorder._write([(0, change(5.0, 25.0)), (0, change(0.0, 20.0)), (1, change(0.0, 30.0)), (0, change(2.0, 22.0))])
    lines = (tmp_path / "opc.csv").read_text().splitlines()
    assert lines == ["time_min,T1,T2", "0.000000,20,30", "2.000000,22,"]  # minute 5 waits for T2
    recorder._write([], final=True)
    lines = (tmp_path / "opc.csv").read_text().splitlines()
    assert lines[-1] == "5.000000,25,"


def test_a_row_waits_for_every_nodes_value_of_its_time(tmp_path):
    # each node's change arrives on its own (from the history of one, the subscription of the
    # other): the newest row is written once both are in, not without the later one
    recorder = _offline_recorder(tmp_path)
    recorder._write([(0, change(0.0, 20.0)), (1, change(0.0, 30.0)), (1, change(1.0, 31.0))])
    assert (tmp_path / "opc.csv").read_text().splitlines() == ["time_min,T1,T2", "0.000000,20,30"]
    recorder._write([(0, change(1.0, 21.0))])
    assert (tmp_path / "opc.csv").read_text().splitlines()[-1] == "1.000000,21,31"
    recorder._write([(1, change(2.0, 32.0)), (0, change(3.0, 23.0))])  # a newer time: minute 2 has all it will get
    assert (tmp_path / "opc.csv").read_text().splitlines()[-1] == "2.000000,,32"


@pytest.mark.slow
@pytest.mark.xdist_group("one OPC UA server")
def test_a_record_of_other_nodes_is_not_resumed(running_machine, tmp_path):
    log = tmp_path / "opc.csv"
    recorder = OpcUaRecorder(running_machine.url, log, NODES)
    running_machine.publish(0.0, (20.0, 21.0))
    settle(recorder, 1)
    recorder.close()
    assert OpcUaRecorder(running_machine.url, log, NODES[::-1]).nodes == NODES  # the same nodes: the log's order
    with pytest.raises(InputError, match="was recorded from .* nodes ns=2;s=Spindle.T1, ns=2;s=Spindle.T2; to record"):
        OpcUaRecorder(running_machine.url, log, NODES[:1])


@pytest.mark.slow
@pytest.mark.xdist_group("one OPC UA server")
def test_unknown_nodes_and_no_nodes_are_refused(running_machine, tmp_path):
    with pytest.raises(InputError, match="name the nodes to record"):
        OpcUaRecorder(running_machine.url, tmp_path / "x.csv", [])
    with pytest.raises(InputError, match="cannot read the nodes ns=2;s=Nowhere"):
        OpcUaRecorder(running_machine.url, tmp_path / "y.csv", ["ns=2;s=Nowhere"]).fetch()


@pytest.mark.slow
@pytest.mark.xdist_group("one OPC UA server")
def test_watch_follows_a_server_and_refuses_its_options_for_a_file(running_machine, tmp_path):
    import json

    for k in range(5):
        running_machine.publish(float(k), (20 + k / 10, 21 + k / 10))
    record = tmp_path / "opc.csv"
    args = ["thermal", "watch", running_machine.url, "--node", NODES[0], "--node", NODES[1], "--record", str(record)]
    out = mtident(*args, "--poll", "0.05", "--timeout", "1", "--json")
    assert out.returncode == 0, out.stderr
    assert f"recording {running_machine.url} to {record}" in out.stderr
    assert json.loads(out.stdout)["decision"] == "continue"
    # a subscription starts with the values of now: the server's last, at minute 4
    assert record.read_text().splitlines() == ["time_min,T1,T2", "0.000000,20.4,21.4"]
    wrong = mtident("thermal", "watch", str(record), "--node", NODES[0])
    assert wrong.returncode == 2 and "--node: not for a log file" in wrong.stderr


@pytest.mark.slow
def test_a_repeated_value_is_a_reading_not_a_missing_one(machine, tmp_path):
    # a sensor in 0.1 °C steps near equilibrium: most readings repeat the one before; each is a
    # reading the server published (a new source time stamp), written once, not an empty cell, across
    # a restart of the server too
    log = tmp_path / "opc.csv"
    recorder = OpcUaRecorder(machine.url, log, NODES)
    room = [20.0, 20.0, 20.0, 20.1, 20.1, 20.1, 20.1, 20.0, 20.0, 20.0, 20.0, 20.0]
    machine.publish(0.0, (room[0], 30.0))
    settle(recorder, 1)
    for k in range(1, len(room)):
        if k == 8:  # the server killed and started again: its nodes hold their last values
            machine.stop()
            recorder.fetch()
            machine.start()
        machine.publish(float(k), (room[k], 30.0 if k < 6 else 30.5))  # both repeat, then one
        settle(recorder, k + 1)
    machine.publish(float(len(room)), (99.0, 99.0), good=False)  # an open circuit is still a missing reading
    settle(recorder, len(room) + 1)
    recorder.close()
    lines = log.read_text().splitlines()
    assert len(lines) == len(room) + 2 and lines[-1] == f"{len(room)}.000000,,"  # none lost, none doubled
    recorded = read_temperature_log(log)  # (a row without a reading is not a sample)
    np.testing.assert_allclose(recorded.time_min, range(len(room)))
    np.testing.assert_allclose(recorded.temperature_C[:, 0], room)
    np.testing.assert_allclose(recorded.temperature_C[:, 1], [30.0] * 6 + [30.5] * 6)


def test_a_time_stamp_stepped_ahead_once_is_said_and_the_record_goes_on(tmp_path):
    # a new variable's first value stamped hours ahead (the wall clock), then in line again: that one
    # stamp is the outlier, said, and the readings after it are recorded, not dropped as older
    recorder = _offline_recorder(tmp_path)
    recorder._write([(0, change(0.0, 20.0)), (1, change(0.0, 30.0))])
    recorder._write([(0, change(1.0, 21.0)), (1, change(1.0, 31.0))])
    recorder._write([(0, change(2.0, 22.0)), (1, change(614.0, 32.0))])
    for k in range(3, 6):
        recorder._write([(0, change(float(k), 20.0 + k)), (1, change(float(k), 30.0 + k))])
    recorder._write([], final=True)
    lines = (tmp_path / "opc.csv").read_text().splitlines()
    assert [line.split(",")[0] for line in lines[1:]] == [f"{k}.000000" for k in range(6)]
    assert lines[3] == "2.000000,22," and lines[-1] == "5.000000,25,35"
    said = recorder._notes
    assert len(said) == 1 and "T2's reading stamped 2026-11-24 18:14:00 UTC, 612 min ahead" in said[0], said
    assert "left out" in said[0] and "recording goes on" in said[0]


def test_a_clock_that_moved_on_is_a_gap_and_readings_behind_the_log_are_said(tmp_path):
    recorder = _offline_recorder(tmp_path)
    recorder._write([(0, change(0.0, 20.0)), (1, change(0.0, 30.0))])
    recorder._write([(0, change(700.0, 21.0)), (1, change(700.0, 31.0))])  # a jump: held until it goes on
    assert len((tmp_path / "opc.csv").read_text().splitlines()) == 2
    recorder._write([(0, change(701.0, 22.0)), (1, change(701.0, 32.0))])
    recorder._write([(0, change(3.0, 23.0))])  # behind the log: left out, and said
    recorder._write([], final=True)
    lines = (tmp_path / "opc.csv").read_text().splitlines()
    assert [line.split(",")[0] for line in lines[1:]] == ["0.000000", "700.000000", "701.000000"]
    assert recorder._notes == [
        "1 reading(s) of T1 stamped before the log's last row (2026-11-24 19:41:00 UTC) left out, as the log's "
        "times must increase: the OPC UA server's clock went back, or they came late"
    ]


@pytest.mark.slow
def test_a_server_whose_clock_steps_ahead_once_is_said_and_recorded_on(machine, tmp_path):
    # a real server: one node's value stamped 612 min ahead once (a new variable's first value with the
    # wall clock), then in line again; every other reading recorded, none doubled, the step said
    log = tmp_path / "opc.csv"
    recorder = OpcUaRecorder(machine.url, log, NODES)
    said = []
    for k in range(3):
        machine.publish(float(k), (20 + k / 10, 21 + k / 10))
        said += settle(recorder, k + 1)
    machine.variables[1].write_value(
        ua.DataValue(ua.Variant(29.9, ua.VariantType.Double), SourceTimestamp=START + dt.timedelta(minutes=614))
    )
    wait_until(lambda: not recorder._changes._queue.empty(), "the value stamped ahead received")
    said += recorder.fetch()
    for k in range(3, 8):
        machine.publish(float(k), (20 + k / 10, 21 + k / 10))
        said += settle(recorder, k + 1)
    recorder.close()
    recorded = read_temperature_log(log)
    np.testing.assert_allclose(recorded.time_min, range(8))
    np.testing.assert_allclose(recorded.temperature_C[:, 1], [21 + k / 10 for k in range(8)])
    assert len(said) == 1 and "clock stepped: T2's reading stamped 2026-11-24 18:14:00 UTC, 612 min ahead" in said[0]


def test_a_sparse_source_is_no_clock_step(tmp_path):
    # readings 15 min apart are written as they come, not each held for the next (only the first
    # step, before the log has one to go by, waits for the next reading)
    recorder = _offline_recorder(tmp_path)
    for k in range(5):
        recorder._write([(0, change(15.0 * k, 20.0 + k)), (1, change(15.0 * k, 30.0 + k))])
        assert len((tmp_path / "opc.csv").read_text().splitlines()) == (2 if k == 1 else k + 2)
    assert recorder._notes == []
