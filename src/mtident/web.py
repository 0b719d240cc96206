"""A live web page of a watched test: the per-sensor table and the curves, pushed to the browser
as the monitor decides (server-sent events), read-only.

The watch publishes each new answer to a :class:`LivePage`; a Starlette app serves the page, the
answer as JSON (``/state.json``), the curves as a picture (``/plot.png``) and a stream of
answers (``/events``). The curves are drawn on the server with the same figure as ``--plot``,
so the page needs no script library and works on a shop floor without internet.
"""

from __future__ import annotations

import asyncio
import json
import threading
import time
from collections.abc import AsyncIterator
from dataclasses import dataclass, field

import jinja2
import uvicorn
from starlette.applications import Starlette
from starlette.requests import Request
from starlette.responses import HTMLResponse, JSONResponse, Response, StreamingResponse
from starlette.routing import Route

from mtident.exceptions import InputError

__all__ = ["LivePage", "parse_address", "serve"]

# how often the event stream looks for a new answer (s)
_STREAM_POLL_S = 0.1


@dataclass
class LivePage:
    """The latest answer of a watch, shared between the watch's loop and the server's thread.

    Attributes
    ----------
    title : str
        The log watched.
    version : int
        Raised by each :meth:`publish` and :meth:`record`; the event stream sends an answer when it
        changes.
    """

    title: str
    version: int = 0
    _answer: dict[str, object] = field(default_factory=dict)
    _plot: bytes = b""
    _published_at: float = 0.0
    # the newest readings recorded (time in min, latest per sensor), shown over the answer's own
    _record: tuple[float, dict[str, float | None]] | None = None
    _lock: threading.Lock = field(default_factory=threading.Lock)

    def publish(self, answer: dict[str, object], plot_png: bytes | None = None) -> None:
        """Show a new answer (the monitor's JSON object), and new curves where given.

        Parameters
        ----------
        answer : dict of str to object
            The monitor's answer as a JSON-ready object; it replaces the one shown and raises :attr:`version`.
        plot_png : bytes or None, optional
            The curves as a PNG image; ``None`` keeps the picture published before.
        """
        with self._lock:
            self._answer = answer
            if plot_png is not None:
                self._plot = plot_png
            self.version += 1
            self._published_at = time.time()

    def record(self, time_min: float, latest_C: dict[str, float | None]) -> None:
        """Show the newest readings as soon as they are recorded, before the monitor has checked them.

        Parameters
        ----------
        time_min : float
            The newest row's time (min from the log's first row).
        latest_C : dict of str to float or None
            Each sensor's latest reading (°C; None: none yet).
        """
        with self._lock:
            self._record = (time_min, latest_C)
            self.version += 1
            self._published_at = time.time()

    def snapshot(self) -> tuple[int, dict[str, object], float]:
        """The version, the answer and when it was published (seconds since the epoch).

        The answer's ``latest_C`` and ``recorded_time_min`` are the newest readings recorded
        (:meth:`record`) where they are newer than those the answer was made from.
        """
        with self._lock:
            answer = self._answer
            checked = answer.get("recorded_time_min", answer.get("last_time_min"))
            if self._record is not None and (not isinstance(checked, float | int) or self._record[0] > checked):
                answer = {**answer, "recorded_time_min": self._record[0], "latest_C": self._record[1]}
            return self.version, answer, self._published_at

    def plot(self) -> bytes:
        with self._lock:
            return self._plot


_PAGE = jinja2.Environment(
    loader=jinja2.PackageLoader("mtident", "data"), autoescape=jinja2.select_autoescape(["html"])
).get_template("live.html.j2")


def app(page: LivePage) -> Starlette:
    """The Starlette app of the page (read-only: GET only).

    Parameters
    ----------
    page : LivePage
        The answer and picture the page serves; the monitor publishes to it.

    Returns
    -------
    Starlette
        The app: the page, its answer as JSON, its picture and a stream of answers.
    """

    async def index(request: Request) -> HTMLResponse:
        # the answer so far in the page itself: it reads without its script, which only updates it
        return HTMLResponse(_PAGE.render(title=page.title, answer=page.snapshot()[1]))

    async def state(request: Request) -> JSONResponse:
        version, answer, published = page.snapshot()
        return JSONResponse({"version": version, "published_at": published, "answer": answer})

    async def plot(request: Request) -> Response:
        data = page.plot()
        return Response(data, media_type="image/png") if data else Response(status_code=204)

    async def events(request: Request) -> StreamingResponse:
        async def stream() -> AsyncIterator[str]:
            seen = -1
            while not await request.is_disconnected():
                version, answer, published = page.snapshot()
                if version != seen:
                    seen = version
                    payload = {"version": version, "published_at": published, "answer": answer}
                    yield f"data: {json.dumps(payload, allow_nan=False)}\n\n"
                await asyncio.sleep(_STREAM_POLL_S)

        return StreamingResponse(stream(), media_type="text/event-stream", headers={"Cache-Control": "no-cache"})

    routes = [
        Route("/", index),
        Route("/state.json", state),
        Route("/plot.png", plot),
        Route("/events", events),
    ]
    return Starlette(routes=routes)


def parse_address(text: str) -> tuple[str, int]:
    """``HOST:PORT`` (or ``PORT`` alone, on the loopback interface), checked.

    Parameters
    ----------
    text : str

    Returns
    -------
    host : str
    port : int

    Raises
    ------
    InputError
        For anything but a host and a port from 0 to 65535.
    """
    host, sep, port = text.rpartition(":")
    host = host if sep else "127.0.0.1"
    try:
        number = int(port)
    except ValueError:
        number = -1
    if not host or not 0 <= number <= 65535:
        msg = f"{text!r}: expected HOST:PORT, such as 127.0.0.1:8050"
        raise InputError(msg)
    return host.strip("[]"), number


@dataclass
class Served:
    """A running server: where it listens, and how to stop it."""

    url: str
    server: uvicorn.Server
    thread: threading.Thread

    def stop(self) -> None:
        self.server.should_exit = True
        self.thread.join(timeout=5.0)


def serve(page: LivePage, host: str, port: int) -> Served:
    """Serve the page from a background thread; returns once it listens.

    Parameters
    ----------
    page : LivePage
    host : str
        The interface (the loopback interface unless told otherwise).
    port : int
        0: any free port.

    Returns
    -------
    Served
        With the URL it listens at.
    """
    config = uvicorn.Config(app(page), host=host, port=port, log_level="warning", lifespan="off")
    server = uvicorn.Server(config)
    thread = threading.Thread(target=server.run, name="mtident-page", daemon=True)
    thread.start()
    deadline = time.monotonic() + 10.0
    while not server.started:
        if not thread.is_alive() or time.monotonic() > deadline:
            msg = f"cannot serve the page at {host}:{port} (is the port in use?)"
            raise InputError(msg)
        time.sleep(0.02)
    bound = server.servers[0].sockets[0].getsockname()[1]
    shown = f"[{host}]" if ":" in host else host
    return Served(f"http://{shown}:{bound}/", server, thread)
