"""A small MTConnect agent for the tests: a real HTTP server on the loopback interface that
answers /probe, /current and /sample?from=&count= with MTConnectDevices and MTConnectStreams
documents in the standard's shapes (version 2.0), from a buffer of observations the test
publishes. It can be stopped and started again on the same port, restarted as a new instance, and
made to drop old observations from its buffer."""

from __future__ import annotations

import datetime as dt
import threading
import urllib.parse
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer

START = dt.datetime(2026, 11, 24, 8, 0, tzinfo=dt.UTC)

PROBE = """<?xml version="1.0" encoding="UTF-8"?>
<MTConnectDevices xmlns="urn:mtconnect.org:MTConnectDevices:2.0">
  <Header creationTime="2026-11-24T08:00:00Z" sender="test-agent" instanceId="{instance}" version="2.0.0.0"
          assetBufferSize="1024" assetCount="0" bufferSize="{size}"/>
  <Devices>
    <Device id="vmc1" name="VMC1" uuid="vmc1-uuid">
      <DataItems>
        <DataItem category="EVENT" id="avail" type="AVAILABILITY"/>
      </DataItems>
      <Components>
        <Rotary id="c1" name="C">
          <DataItems>
            <DataItem category="SAMPLE" id="spindle_temp" name="Spindle" type="TEMPERATURE" units="CELSIUS"/>
            <DataItem category="SAMPLE" id="bearing_temp" name="Bearing" type="TEMPERATURE" units="CELSIUS"/>
            <DataItem category="SAMPLE" id="c_speed" type="ROTARY_VELOCITY" units="REVOLUTION/MINUTE"/>
          </DataItems>
        </Rotary>
      </Components>
    </Device>
  </Devices>
</MTConnectDevices>
"""


@dataclass
class Agent:
    """The agent's buffer: (sequence, item id, minutes from START, text) observations."""

    instance: int = 1700000000
    size: int = 131072
    observations: list[tuple[int, str, float, str]] = field(default_factory=list)
    first_sequence: int = 1
    requests: list[str] = field(default_factory=list)

    def publish(self, minute: float, values: dict[str, str]) -> None:
        """Observations at one time (a value, or "UNAVAILABLE"), with the next sequence numbers."""
        for item, text in values.items():
            self.observations.append((self.next_sequence, item, minute, text))

    @property
    def next_sequence(self) -> int:
        return self.first_sequence + len(self.observations)

    def restart(self) -> None:
        """The agent started again: a new instance, an empty buffer, its sequence numbers from 1."""
        self.instance += 1
        self.observations = []
        self.first_sequence = 1

    def drop_oldest(self, count: int) -> None:
        """The buffer wraps: the oldest observations are gone."""
        self.observations = self.observations[count:]
        self.first_sequence += count

    def streams(self, chosen: list[tuple[int, str, float, str]], next_sequence: int) -> str:
        samples = "\n".join(
            f'          <Temperature dataItemId="{item}" timestamp="{_stamp(minute)}" sequence="{seq}"'
            f"{' name=' + chr(34) + NAMES[item] + chr(34) if item in NAMES else ''}>{text}</Temperature>"
            for seq, item, minute, text in chosen
        )
        last = self.next_sequence - 1
        return f"""<?xml version="1.0" encoding="UTF-8"?>
<MTConnectStreams xmlns="urn:mtconnect.org:MTConnectStreams:2.0">
  <Header creationTime="2026-11-24T08:00:00Z" sender="test-agent" instanceId="{self.instance}" version="2.0.0.0"
          bufferSize="{self.size}" nextSequence="{next_sequence}" firstSequence="{self.first_sequence}"
          lastSequence="{last}"/>
  <Streams>
    <DeviceStream name="VMC1" uuid="vmc1-uuid">
      <ComponentStream component="Rotary" name="C" componentId="c1">
        <Samples>
{samples}
        </Samples>
      </ComponentStream>
    </DeviceStream>
  </Streams>
</MTConnectStreams>
"""

    def answer(self, path: str, query: dict[str, list[str]]) -> tuple[int, str]:
        self.requests.append(path)
        parts = [p for p in path.split("/") if p]
        if parts and parts[0] == "VMC1":
            parts = parts[1:]
        if parts == ["probe"]:
            return 200, PROBE.format(instance=self.instance, size=self.size)
        if parts == ["current"]:
            latest: dict[str, tuple[int, str, float, str]] = {}
            for obs in self.observations:
                latest[obs[1]] = obs
            return 200, self.streams(sorted(latest.values()), self.next_sequence)
        if parts == ["sample"]:
            start = int(query.get("from", [str(self.first_sequence)])[0])
            count = int(query.get("count", ["100"])[0])
            if start < self.first_sequence:
                start = self.first_sequence
            if start > self.next_sequence:  # as a real agent answers (cppagent)
                return (
                    400,
                    '<MTConnectError xmlns="urn:mtconnect.org:MTConnectError:2.0"><Errors><Error errorCode="OUT_OF_RANGE">'
                    f"'from' must be less than or equal to {self.next_sequence}.</Error></Errors></MTConnectError>",
                )
            chosen = [o for o in self.observations if o[0] >= start][:count]
            return 200, self.streams(chosen, chosen[-1][0] + 1 if chosen else max(start, self.next_sequence))
        return (
            404,
            '<MTConnectError xmlns="urn:mtconnect.org:MTConnectError:2.0"><Errors><Error errorCode="UNSUPPORTED">unknown</Error></Errors></MTConnectError>',
        )


NAMES = {"spindle_temp": "Spindle", "bearing_temp": "Bearing"}


def _stamp(minute: float) -> str:
    return (START + dt.timedelta(minutes=minute)).strftime("%Y-%m-%dT%H:%M:%S.%fZ")


class Server:
    """The agent served on 127.0.0.1; stop() and start() keep the port."""

    def __init__(self, agent: Agent, port: int = 0) -> None:
        self.agent = agent
        self.port = port
        self._server: ThreadingHTTPServer | None = None

    def start(self) -> Server:
        agent = self.agent

        class Handler(BaseHTTPRequestHandler):
            def do_GET(self) -> None:  # noqa: N802 - the http.server interface
                parsed = urllib.parse.urlparse(self.path)
                status, body = agent.answer(parsed.path, urllib.parse.parse_qs(parsed.query))
                data = body.encode("utf-8")
                self.send_response(status)
                self.send_header("Content-Type", "text/xml")
                self.send_header("Content-Length", str(len(data)))
                self.end_headers()
                self.wfile.write(data)

            def log_message(self, *args: object) -> None:
                pass

        ThreadingHTTPServer.allow_reuse_address = True
        self._server = ThreadingHTTPServer(("127.0.0.1", self.port), Handler)
        self.port = self._server.server_address[1]
        threading.Thread(target=self._server.serve_forever, daemon=True).start()
        return self

    def stop(self) -> None:
        if self._server is not None:
            self._server.shutdown()
            self._server.server_close()
            self._server = None

    @property
    def url(self) -> str:
        return f"http://127.0.0.1:{self.port}"
