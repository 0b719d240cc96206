"""Temperatures from an MTConnect agent: the recorder against a real HTTP agent on the loopback
interface (tests/mtconnect_agent.py), stopped and restarted mid-test, restarted as a new instance,
with its buffer wrapping; and `watch URL` deciding as the replay of what it recorded does."""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import first_order, wait_until
from helpers import mtident, noisy, one_mode_reference
from mtconnect_agent import Agent, Server

from mtident.exceptions import InputError
from mtident.io.logs import read_temperature_log
from mtident.io.mtconnect import MTConnectRecorder, parse_probe, parse_streams
from mtident.thermal.reference import save_reference

MINUTES = np.arange(0.0, 400.0)


SPINDLE = noisy(first_order(MINUTES), 31)


BEARING = noisy(first_order(MINUTES, steady=29.0), 32)


def publish(agent: Agent, minutes: range) -> None:
    for k in minutes:
        agent.publish(float(MINUTES[k]), {"spindle_temp": f"{SPINDLE[k]:.2f}", "bearing_temp": f"{BEARING[k]:.2f}"})


@pytest.fixture
def agent_server():  # noqa: ANN201
    agent = Agent()
    server = Server(agent).start()
    yield agent, server
    server.stop()


def test_probe_and_streams_are_read_as_the_standard_writes_them():
    agent = Agent()
    publish(agent, range(3))
    agent.publish(3.0, {"spindle_temp": "UNAVAILABLE", "bearing_temp": "21.0"})
    items = parse_probe(agent.answer("/VMC1/probe", {})[1].encode())
    assert [(i.id, i.name, i.units) for i in items] == [
        ("spindle_temp", "Spindle", "CELSIUS"),
        ("bearing_temp", "Bearing", "CELSIUS"),
    ]
    header, observations = parse_streams(agent.answer("/VMC1/sample", {"from": ["1"], "count": ["100"]})[1].encode())
    assert (header.first_sequence, header.next_sequence) == (1, 9) and len(observations) == 8
    assert np.isnan(observations[6].value) and observations[7].value == 21.0
    assert observations[2].time.isoformat() == "2026-11-24T08:01:00+00:00"
    with pytest.raises(InputError, match="no device 'VMC9' at the agent; it has: VMC1"):
        parse_probe(agent.answer("/probe", {})[1].encode(), "VMC9")
    with pytest.raises(InputError, match="the agent refused the sample: UNSUPPORTED: unknown"):
        parse_streams(agent.answer("/nowhere", {})[1].encode())


@pytest.mark.slow
def test_a_stopped_and_restarted_agent_loses_and_doubles_no_sample(agent_server, tmp_path):
    agent, server = agent_server
    log = tmp_path / "vmc1.csv"
    recorder = MTConnectRecorder(server.url, log, device="VMC1")
    assert recorder.fetch() == []  # started with the test: nothing yet
    publish(agent, range(0, 50))
    assert recorder.fetch() == []
    publish(agent, range(50, 120))
    recorder.fetch()
    server.stop()
    publish(agent, range(120, 200))  # the agent keeps its buffer; only the connection is gone
    notes = recorder.fetch()
    assert len(notes) == 1 and "does not answer" in notes[0]
    assert recorder.fetch() == []  # said once per outage
    server.start()
    assert recorder.fetch() == [f"the agent at {server.url} answers again"]
    # a recorder killed and started again goes on from its sidecar
    publish(agent, range(200, 400))
    again = MTConnectRecorder(server.url, log, device="VMC1")
    while agent.next_sequence > (again.next_sequence or 0):
        again.fetch()
    recorded = read_temperature_log(log)
    np.testing.assert_allclose(recorded.time_min, MINUTES[:])  # every minute once: none lost, none doubled
    np.testing.assert_allclose(recorded.temperature_C[:, 0], SPINDLE, atol=1e-9)
    np.testing.assert_allclose(recorded.temperature_C[:, 1], BEARING, atol=1e-9)
    assert recorded.sensors == ("Spindle", "Bearing")
    with pytest.raises(InputError, match="was recorded from .* device VMC1; to record another agent or device"):
        MTConnectRecorder(server.url, log, device="VMC2")


@pytest.mark.slow
def test_an_answer_cut_at_the_count_is_not_written_in_part(agent_server, tmp_path, monkeypatch):
    import mtident.io.mtconnect as mtconnect

    agent, server = agent_server
    monkeypatch.setattr(mtconnect, "SAMPLE_COUNT", 7)  # cuts a time stamp's pair in two
    recorder = MTConnectRecorder(server.url, tmp_path / "cut.csv", device="VMC1", from_buffer_start=True)
    publish(agent, range(0, 30))
    for _ in range(20):
        recorder.fetch()
    recorded = read_temperature_log(tmp_path / "cut.csv")
    np.testing.assert_allclose(recorded.time_min, MINUTES[:30])
    assert np.isfinite(recorded.temperature_C).all()


@pytest.mark.slow
def test_a_new_agent_instance_and_a_wrapped_buffer_are_said(agent_server, tmp_path):
    agent, server = agent_server
    recorder = MTConnectRecorder(server.url, tmp_path / "vmc1.csv", device="VMC1")
    publish(agent, range(0, 10))
    recorder.fetch()
    publish(agent, range(10, 30))
    agent.drop_oldest(40)  # 20 observations never read fell out of the buffer
    notes = recorder.fetch()
    assert notes == ["20 observation(s) dropped out of the agent's buffer before they were read"]
    agent.instance += 1
    publish(agent, range(30, 35))
    assert "the agent was restarted (a new instance)" in recorder.fetch()[0]


@pytest.mark.slow
def test_a_restarted_agent_loses_no_reading_of_its_new_buffer(agent_server, tmp_path):
    # started again, the agent numbers its sequence from 1 and asking from where the recorder stopped is
    # out of its range: every reading in its new buffer is recorded, the first one too
    agent, server = agent_server
    log = tmp_path / "vmc1.csv"
    recorder = MTConnectRecorder(server.url, log, device="VMC1")
    assert recorder.fetch() == []
    publish(agent, range(0, 50))
    recorder.fetch()
    agent.restart()
    publish(agent, range(50, 53))
    notes = recorder.fetch()
    assert len(notes) == 1 and "the agent was restarted (a new instance)" in notes[0], notes
    publish(agent, range(53, 60))
    assert recorder.fetch() == []
    recorded = read_temperature_log(log)
    np.testing.assert_allclose(recorded.time_min, MINUTES[:60])  # none lost, none doubled
    np.testing.assert_allclose(recorded.temperature_C[:, 0], SPINDLE[:60], atol=1e-9)


@pytest.mark.slow
def test_unavailable_is_a_missing_reading_and_unknown_items_are_refused(agent_server, tmp_path):
    agent, server = agent_server
    publish(agent, range(0, 3))
    agent.publish(3.0, {"spindle_temp": "UNAVAILABLE", "bearing_temp": "21.0"})
    items = {"Spindle": "S", "bearing_temp": "B"}
    recorder = MTConnectRecorder(server.url, tmp_path / "u.csv", device="VMC1", items=items, from_buffer_start=True)
    recorder.fetch()
    recorder.fetch()
    lines = (tmp_path / "u.csv").read_text().splitlines()
    assert lines[0] == "time_min,S,B" and lines[-1] == "3.000000,,21"
    wrong = MTConnectRecorder(server.url, tmp_path / "w.csv", device="VMC1", items={"Coolant": "C"})
    with pytest.raises(
        InputError, match=r"no TEMPERATURE sample Coolant at the agent; it has: spindle_temp \(Spindle\)"
    ):
        wrong.fetch()


@pytest.mark.slow
def test_watch_follows_an_agent_and_decides_as_the_replay_of_its_record(agent_server, tmp_path):
    agent, server = agent_server
    publish(agent, range(0, 400))
    reference = tmp_path / "machine.toml"
    save_reference(one_mode_reference("Spindle", "Bearing"), reference)
    record = tmp_path / "vmc1.csv"
    common = ["--reference", str(reference), "--free-fast-modes", "0", "--json"]
    live = mtident(
        "thermal", "watch", server.url, "--device", "VMC1", "--from-buffer-start", "--record", str(record),
        "--poll", "0.05", "--timeout", "5", *common,
    )  # fmt: skip
    assert live.returncode == 0, live.stderr
    decided = json.loads(live.stdout)
    assert decided["decision"] == "stop" and 50 <= decided["stop_time_min"] <= 80
    replayed = mtident("thermal", "watch", str(record), "--replay", *common)
    again = json.loads(replayed.stdout)
    assert again["stop_time_min"] == decided["stop_time_min"]
    assert [s["steady_state_C"] for s in again["sensors"]] == [s["steady_state_C"] for s in decided["sensors"]]
    refused = mtident("thermal", "watch", server.url, "--replay")
    assert refused.returncode == 2 and "--replay replays a log file" in refused.stderr
    other_device = mtident("thermal", "watch", server.url, "--device", "VMC2", "--record", str(record))
    assert other_device.returncode == 2
    assert "was recorded from" in other_device.stderr and "record to another log (--record FILE)" in other_device.stderr


@pytest.mark.slow
def test_recording_goes_on_while_the_fits_run(agent_server, tmp_path, monkeypatch):
    """Under load the fits held the recording up to 100 s (one thread for both): the agent is asked
    for its samples while a poll's fits run, not only between polls."""
    from mtident.thermal.session import WatchSession

    agent, server = agent_server
    publish(agent, range(0, 10))
    asked_during = []
    original = WatchSession.poll

    def slow(session, redraw=None, cancel=None):  # noqa: ANN001, ANN202
        # fits that last until the agent has been asked five times more (one thread for both: never)
        before = len(agent.requests)
        wait_until(lambda: len(agent.requests) - before >= 5, "the agent asked while the fits run", 30.0, 0.01)
        asked_during.append(len(agent.requests) - before)
        return original(session, redraw, cancel)

    monkeypatch.setattr(WatchSession, "poll", slow)
    record = tmp_path / "vmc1.csv"
    args = ["thermal", "watch", server.url, "--device", "VMC1", "--from-buffer-start", "--record", str(record)]
    out = mtident(*args, "--poll", "0.05", "--timeout", "2.5", "--json")
    assert out.returncode == 0, out.stderr
    assert len(asked_during) >= 2 and min(asked_during) >= 5, asked_during
    np.testing.assert_allclose(read_temperature_log(record).time_min, MINUTES[:10])
