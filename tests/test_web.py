"""The live page of `watch --serve`: served by a real server on the loopback interface, read with
HTTP and with a headless browser where one is installed."""

from __future__ import annotations

import contextlib
import itertools
import json
import re
import shutil
import socket
import subprocess
import threading
import time
import urllib.error
import urllib.request
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest
from conftest import first_order, wait_until
from helpers import T, _get, _log, noisy, one_mode_reference

from mtident.exceptions import InputError
from mtident.thermal.monitor import MonitorSettings, monitor_step, new_state, result
from mtident.thermal.robust import RobustSettings
from mtident.web import LivePage, parse_address, serve

ARTIFACTS = Path(__file__).resolve().parents[1] / "test-artifacts"


def _answer() -> dict[str, object]:
    settings = MonitorSettings(reference=one_mode_reference("S"), robust=RobustSettings(free_fast_modes=0))
    state, _ = monitor_step(new_state(["S"]), T[:100], noisy(first_order(T[:100]), 41)[:, None], None, settings)
    assert state.stopped
    return {**result(state, settings), "latest_C": {"S": 23.9}}


@pytest.fixture
def served_page():  # noqa: ANN201
    page = LivePage("run.csv")
    served = serve(page, "127.0.0.1", 0)
    yield page, served
    served.stop()


@pytest.mark.slow
def test_the_page_serves_the_answer_the_curves_and_a_stream_of_answers(served_page):
    page, served = served_page
    assert served.url.startswith("http://127.0.0.1:")
    html = _get(served.url).decode()
    assert "<title>mtident watch: run.csv</title>" in html and 'new EventSource("events")' in html
    answer = _answer()
    page.publish(answer, b"\x89PNG fake")
    state = json.loads(_get(served.url + "state.json"))
    assert state["version"] == 1 and state["answer"]["decision"] == "stop"
    assert _get(served.url + "plot.png") == b"\x89PNG fake"
    # the stream sends each new answer: the latency from publish to receipt over 20 answers
    latencies = []
    with urllib.request.urlopen(served.url + "events", timeout=10) as stream:
        assert json.loads(stream.readline().decode().removeprefix("data: "))["version"] == 1
        stream.readline()
        for _ in range(20):
            sent = time.monotonic()
            page.publish(answer)
            line = stream.readline().decode()
            stream.readline()
            latencies.append(time.monotonic() - sent)
            assert json.loads(line.removeprefix("data: "))["version"] == page.version
    assert float(np.median(latencies)) < 0.5


@pytest.mark.slow
def test_the_page_is_read_only(served_page):
    _, served = served_page
    request = urllib.request.Request(served.url + "state.json", data=b"{}", method="POST")
    with pytest.raises(urllib.error.HTTPError, match="405"):
        urllib.request.urlopen(request, timeout=10)


@pytest.mark.parametrize(
    ("text", "expected"),
    [("127.0.0.1:8050", ("127.0.0.1", 8050)), ("8050", ("127.0.0.1", 8050)), ("[::1]:0", ("::1", 0))],
)
def test_addresses_are_read_and_bad_ones_refused(text, expected):
    assert parse_address(text) == expected
    for bad in ("host:port", "127.0.0.1:70000", ":8050"):
        with pytest.raises(InputError, match="expected HOST:PORT"):
            parse_address(bad)


BROWSER = shutil.which("chromium") or shutil.which("chromium-browser") or shutil.which("google-chrome")


@pytest.mark.slow
@pytest.mark.skipif(BROWSER is None, reason="no headless Chromium here (Debian's package `chromium`)")
def test_a_browser_shows_the_decision(served_page):
    page, served = served_page
    page.publish(_answer(), _png())
    common = [BROWSER, "--headless", "--no-sandbox", "--disable-gpu"]
    run = _browser([*common, "--dump-dom", served.url])
    if run.returncode != 0 or "<html" not in run.stdout:
        pytest.skip(f"Chromium here does not run headless: {run.stderr.strip().splitlines()[-1:]}")
    assert re.search(r'<p id="decision" class="stop">The test can stop \(at t = \d+ min\)\.</p>', run.stdout)
    assert '<td class="text">S</td><td>23.90</td>' in run.stdout and '<td class="text">may stop</td>' in run.stdout
    ARTIFACTS.mkdir(exist_ok=True)
    shot = ARTIFACTS / "live-page.png"
    _browser([*common, "--timeout=4000", "--window-size=1200,900", f"--screenshot={shot}", served.url])
    assert shot.stat().st_size > 10_000


@pytest.mark.slow
@pytest.mark.skipif(BROWSER is None, reason="no headless Chromium here (Debian's package `chromium`)")
def test_a_browser_shows_the_decision_change_as_it_comes(served_page):
    """The page's own script at work: opened before any answer, it shows the stop once one is
    published (server-sent events), read from the browser over its DevTools protocol."""
    page, served = served_page
    answer, png = _answer(), _png()
    with _devtools(served.url) as evaluate:
        decision = 'document.getElementById("decision").textContent'
        assert evaluate(decision) == "Waiting for the first readings…"
        page.publish(answer, png)

        def stop_shown() -> str | None:
            shown = str(evaluate(decision))
            return shown if "can stop" in shown else None

        shown = wait_until(stop_shown, "the page showing the stop", 10, 0.01)
        assert re.fullmatch(r"The test can stop \(at t = \d+ min\)\.", shown)
        assert evaluate('document.querySelector("#sensors td").textContent') == "S"


@contextlib.contextmanager
def _devtools(url: str):  # noqa: ANN202
    """A headless Chromium showing ``url``; yields a function that evaluates a JavaScript expression
    in the page (skips where Chromium does not start or answer)."""
    from websockets.sync.client import connect

    with socket.socket() as probe:
        probe.bind(("127.0.0.1", 0))
        port = int(probe.getsockname()[1])
    command = [BROWSER, "--headless", "--no-sandbox", "--disable-gpu", f"--remote-debugging-port={port}", "about:blank"]
    browser = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        target = _page_target(port)
        with connect(target, max_size=None) as socket_:
            calls = itertools.count(1)

            def call(method: str, **params: object) -> dict:
                n = next(calls)
                socket_.send(json.dumps({"id": n, "method": method, "params": params}))
                while (message := json.loads(socket_.recv(timeout=10))).get("id") != n:
                    pass
                return dict(message["result"])

            def evaluate(expression: str) -> object:
                return call("Runtime.evaluate", expression=expression)["result"].get("value")

            call("Page.navigate", url=url)
            wait_until(
                lambda: evaluate("location.href") == url and evaluate("document.readyState") == "complete",
                f"Chromium loading {url}",
                30,
            )
            yield evaluate
    finally:
        browser.terminate()
        browser.wait(10)


def _page_target(port: int) -> str:
    deadline = time.monotonic() + 60
    while time.monotonic() < deadline:
        try:
            targets = json.loads(_get(f"http://127.0.0.1:{port}/json/list"))
        except OSError:
            targets = []
        pages = [t["webSocketDebuggerUrl"] for t in targets if t.get("type") == "page"]
        if pages:
            return str(pages[0])
        time.sleep(0.2)
    pytest.skip("Chromium here did not open its DevTools port within 60 s")


def _browser(command: list[str]) -> subprocess.CompletedProcess[str]:
    try:
        return subprocess.run(command, capture_output=True, text=True, timeout=120, check=False)
    except subprocess.TimeoutExpired:
        pytest.skip("Chromium here did not answer within 120 s")


def _png() -> bytes:
    import io

    from mtident.report.plots import plot_monitor

    settings = MonitorSettings(reference=one_mode_reference("S"), robust=RobustSettings(free_fast_modes=0))
    state, _ = monitor_step(new_state(["S"]), T[:100], noisy(first_order(T[:100]), 41)[:, None], None, settings)
    buffer = io.BytesIO()
    plot_monitor(state, settings).savefig(buffer, format="png")  # type: ignore[union-attr]
    return buffer.getvalue()


class _HeldCheck:
    """The monitor's checks, one of them held until released: a check whose fits take long.

    ``hold(now)`` chooses the check to hold by its time (min); :attr:`held` is set once it waits.
    """

    def __init__(self, monkeypatch: pytest.MonkeyPatch, hold: Callable[[float, list[float]], bool]) -> None:
        from mtident.thermal import monitor

        self.done: list[float] = []  # the times of the checks that ended
        self.held = threading.Event()
        self.release = threading.Event()
        checked = monitor._check_due

        def check_due(state, settings, cancel=None):  # noqa: ANN001, ANN202
            if not self.release.is_set() and hold(state.readings.latest_min, self.done):
                self.held.set()
                self.release.wait()  # however long the test takes: the test releases it, whatever happens
            out = checked(state, settings, cancel)
            self.done.append(out[0].readings.latest_min)
            return out

        monkeypatch.setattr(monitor, "_check_due", check_due)


def _following(session, log: Path, page: LivePage, replay: bool) -> threading.Thread:  # noqa: ANN001
    """The watch's following of ``log`` on a thread of its own: a replay ends at the log's end; a live
    log is followed without a timeout (one counts the time the page's picture takes, seconds under
    load) until the test sets ``cli_watch._terminating``, as a SIGTERM does."""
    from mtident.cli_watch import _follow
    from mtident.thermal.session import FollowSettings

    thread = threading.Thread(
        target=_follow,
        args=(session, log, FollowSettings(replay, 0.05, None), (None, None), False, None, page),
        daemon=True,
    )
    thread.start()
    return thread


def test_a_checks_answer_is_on_the_page_while_the_next_checks_fits_run(tmp_path, monkeypatch):
    """The page was published only after every 250 rows fed (at most every 2 s): a replay's page
    lagged its checks by the fits of the checks after them (the sample log: 3.5 s at the median, 9 s
    at most)."""
    from mtident.thermal.monitor import MonitorSettings
    from mtident.thermal.session import WatchSession

    log = tmp_path / "whole.csv"
    log.write_text(_log(121))  # within the second part fed (rows 25 to 275): its checks all publish before its end
    # the second check past the replay's first 25 rows (fed alone) is held: the first is in the same part
    held = _HeldCheck(monkeypatch, lambda now, done: now > 25 and sum(t > 25 for t in done) == 1)
    page = LivePage(log.name)
    session = WatchSession(log, MonitorSettings(), state_path=tmp_path / "state.npz", resume=False)
    thread = _following(session, log, page, replay=True)
    try:
        assert held.held.wait(timeout=180.0), "no check past the first 25 rows"
        first = held.done[-1]
        shown = wait_until(
            lambda: page.snapshot()[1].get("last_time_min") == first, "the ended check's answer on the page"
        )
        assert shown and page.snapshot()[1]["recorded_time_min"] == first
    finally:
        held.release.set()
        thread.join(timeout=120.0)
    assert not thread.is_alive() and page.snapshot()[1]["last_time_min"] == 120.0


def test_a_live_logs_new_rows_are_on_the_page_while_a_check_runs(tmp_path, monkeypatch):
    """The watch read the log only between its checks: rows written during a check's fits reached
    the page after them (the sample log written a row every 50 ms: 4.6 s at the median)."""
    from mtident import cli_watch
    from mtident.thermal.monitor import MonitorSettings
    from mtident.thermal.session import WatchSession

    lines = _log(61).splitlines(keepends=True)
    log = tmp_path / "live.csv"
    log.write_text("".join(lines[:31]))
    held = _HeldCheck(monkeypatch, lambda now, done: True)  # the first check
    page = LivePage(log.name)
    session = WatchSession(log, MonitorSettings(), state_path=tmp_path / "state.npz")
    stop = threading.Event()
    monkeypatch.setattr(cli_watch, "_terminating", stop)  # the following's end, when the test has seen it all
    thread = _following(session, log, page, replay=False)
    try:
        try:
            assert held.held.wait(timeout=180.0), "no check"
            with open(log, "a") as out:
                out.write("".join(lines[31:]))  # the logger writes on while the check's fits run
            wait_until(lambda: page.snapshot()[1].get("recorded_time_min") == 60.0, "the new rows on the page")
            latest = page.snapshot()[1]["latest_C"]
            assert latest == dict(zip(("A", "B", "C"), map(float, lines[-1].split(",")[1:]), strict=True))
            assert not held.done  # still within the check
        finally:
            held.release.set()
        # the rows written during the check are checked once it ends (a following that ended was the flaw)
        wait_until(
            lambda: page.snapshot()[1].get("last_time_min") == 60.0 or not thread.is_alive(),
            "the rows written during the check checked",
            120,
        )
        assert page.snapshot()[1]["last_time_min"] == 60.0
    finally:
        stop.set()
        thread.join(timeout=120.0)
    assert not thread.is_alive()


def test_the_page_shows_readings_newer_than_its_answer_and_never_older():
    page = LivePage("run.csv")
    page.record(3.0, {"S": 20.5})  # before any answer: the readings alone
    assert page.snapshot()[1] == {"recorded_time_min": 3.0, "latest_C": {"S": 20.5}}
    answer = {"last_time_min": 10.0, "recorded_time_min": 10.0, "latest_C": {"S": 21.0}, "decision": "continue"}
    page.publish(answer)
    assert page.snapshot()[1] == answer  # the readings of t = 3 are older than the answer's
    page.record(12.0, {"S": 21.2})
    version, shown, _ = page.snapshot()
    assert version == 3 and shown == {**answer, "recorded_time_min": 12.0, "latest_C": {"S": 21.2}}
