"""A warm-up test written up: the setup, each sensor's answer with its curve and band, the
decision and when it came, the check against the rest of the log, the warnings, what the
answer assumes, the method and the software version.

:func:`build_report` runs the monitor over a finished or stopped log (resuming from the state
file ``watch`` left beside it, where it belongs to this log and these settings);
:func:`write_html` writes one self-contained HTML page (the figure embedded) and
:func:`write_pdf` a PDF of two pages, both from the same :class:`WarmupReport`.
"""

from __future__ import annotations

import base64
import datetime as dt
import io
import json
import math
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import jinja2
import numpy as np
from matplotlib.backends.backend_pdf import PdfPages
from matplotlib.figure import Figure
from matplotlib.transforms import Bbox

from mtident import __version__
from mtident.exceptions import InputError
from mtident.report.plots import plot_monitor
from mtident.thermal.monitor import MonitorSettings, assumptions, minutes
from mtident.thermal.session import WatchSession

__all__ = ["SensorLine", "WarmupReport", "build_report", "reading_gaps", "write_html", "write_pdf"]


@dataclass(frozen=True)
class SensorLine:
    """One sensor's row of the report (NaN where there is no value).

    Attributes
    ----------
    sensor : str
        The sensor column's name.
    latest_C : float
        The last valid reading the decision saw (°C): at the stop, or at the log's end.
    steady_C : float
        T∞, the estimated steady-state temperature (°C).
    ci95_C : tuple of float
        95 % interval of T∞ (°C), (low, high).
    decision_interval_C : tuple of float
        The interval at the decision level that is compared with the tolerance (°C), (low, high).
    slowest_time_constant_min : float
        Largest time constant of the fitted modes (min).
    equilibrium_time_min : float
        When the best model stays within 5 % of its total rise from T∞ (min from the log's start).
    status : str
        The monitor's status of the sensor ("may stop", "confirming", "narrowing", "no rise", ...).
    model_ok : bool
        The fit can be trusted: T∞ is determined and the residuals are not much more correlated than
        noise.
    settled_C : float
        Where the readings settled by the log's end (°C), NaN where they did not settle or the stop
        is not checked in hindsight.
    difference_C : float
        T∞ at the stop, moved with the room, less ``settled_C`` (°C).
    within_tolerance : bool or None
        ``difference_C`` is within the tolerance; None where nothing could be checked.
    """

    sensor: str
    latest_C: float
    steady_C: float
    ci95_C: tuple[float, float]
    decision_interval_C: tuple[float, float]
    slowest_time_constant_min: float
    equilibrium_time_min: float
    status: str
    model_ok: bool
    settled_C: float
    difference_C: float
    within_tolerance: bool | None

    @property
    def rate_per_min(self) -> float:
        """λ of the slowest mode, 1/τ (the papers' rate)."""
        return 1.0 / self.slowest_time_constant_min if self.slowest_time_constant_min > 0 else math.nan


@dataclass(frozen=True)
class WarmupReport:
    """Everything a report shows, computed once and rendered as HTML or PDF.

    Attributes
    ----------
    source : str
        The log.
    room : str
        How the room entered the answer.
    samples, sampling_interval_min, log_end_min
        The log's readings: how many, how often, and the last one's time.
    gaps : tuple of (float, float)
        Stretches without readings longer than ``GAP_INTERVALS`` sampling intervals: (from, to), min.
    recorded_from : str or None
        Where a watch recorded the log from (an MTConnect agent's device, an OPC UA server's
        nodes) and its first reading's time, from the recorder's sidecar file; None for a logger's file.
    decision : str
        "stop" or "continue".
    stop_time_min : float
        The stop (NaN: no stop within the log).
    reason : str or None
        Why the test could not stop, where it could not.
    lines : tuple of SensorLine
    warnings : tuple of str
    assumptions : str
    method : str
    tolerance_C, decision_level
        The decision's settings.
    hindsight : str or None
        The verdict of the check against the rest of the log, where the log runs on past the stop.
    figure_png : bytes
        The curves (measured, the best model on, the T∞ intervals, the stop).
    version, created
        The software and when the report was made.
    """

    source: str
    room: str
    samples: int
    sampling_interval_min: float
    log_end_min: float
    gaps: tuple[tuple[float, float], ...]
    recorded_from: str | None
    decision: str
    stop_time_min: float
    reason: str | None
    lines: tuple[SensorLine, ...]
    warnings: tuple[str, ...]
    assumptions: str
    method: str
    tolerance_C: float
    decision_level: float
    hindsight: str | None
    figure_png: bytes
    version: str
    created: str


# a stretch without readings longer than this many sampling intervals is said in the report
GAP_INTERVALS = 5.0
METHOD = (
    "Each sensor's readings from the start of its warm-up are fitted with sums of up to four exponential modes "
    "(six where the readings use all four; variable projection, a global search over the time constants). "
    "The interval of the steady-state "
    "temperature T∞ covers every such model the readings cannot exclude, up to the largest time constant "
    "assumed. A sensor may stop when its interval at the decision's confidence lies within the tolerance of its "
    "T∞ at two checks in a row; the test may stop when every sensor may."
)


def build_report(session: WatchSession, progress: Callable[[WatchSession], None] | None = None) -> WarmupReport:
    """Run the session's monitor over the whole log and gather the report.

    Parameters
    ----------
    session : WatchSession
        The log and the decision's settings (resumed from its state file where it can be).
    progress : callable, optional
        Called with the session as readings are fed (for a progress display).

    Returns
    -------
    WarmupReport
    """
    while True:
        session.poll(progress)
        if session.last_rows == 0:
            break
    state = session.state
    if state is None:
        msg = f"{session.path}: no data rows to report on"
        raise InputError(msg)
    settings = session.settings
    outcome = session.result(with_forecast=False)
    whole = session.whole_log()
    hindsight = session.hindsight(whole)
    time_min, values, _ = whole
    lines = tuple(
        _line(summary, state.readings.values_C[:, s], hindsight, s) for s, summary in enumerate(_sensors(outcome))
    )
    said = assumptions(settings, state.sensors[0], state.readings.room_C is not None)
    assumed = f"{said.model}, time constants up to {said.max_time_constant_min:g} min; room {said.room}"
    for sensor in state.sensors:
        reference = assumptions(settings, sensor).reference
        if reference:
            assumed += f"; reference for {sensor}: {reference}"
    figure = plot_monitor(state, settings)
    assert isinstance(figure, Figure)
    if state.stopped:
        _draw_rest_of_log(figure, time_min, values, state.stop_time_min)
    return WarmupReport(
        source=str(session.path),
        room=said.room,
        samples=len(time_min),
        sampling_interval_min=float(np.median(np.diff(time_min))) if len(time_min) > 1 else math.nan,
        log_end_min=float(time_min[-1]) if len(time_min) else math.nan,
        gaps=reading_gaps(time_min),
        recorded_from=_recorded_from(session.path),
        decision=str(outcome["decision"]),
        stop_time_min=state.stop_time_min if state.stopped else math.nan,
        reason=outcome["reason"] if isinstance(outcome["reason"], str) else None,
        lines=lines,
        warnings=tuple(dict.fromkeys(w for summary in _sensors(outcome) for w in summary["warnings"])),
        assumptions=assumed,
        method=METHOD,
        tolerance_C=settings.tolerance_C,
        decision_level=settings.decision_level,
        hindsight=None if hindsight is None else _hindsight_verdict(lines, hindsight.log_end_min, settings),
        figure_png=_png(figure),
        version=__version__,
        created=dt.datetime.now().astimezone().isoformat(timespec="minutes"),
    )


def _draw_rest_of_log(figure: Figure, time_min: np.ndarray, values: np.ndarray, stop_min: float) -> None:
    """The readings after the stop, which the decision did not see, on each sensor's axes."""
    after = time_min > stop_min
    if not after.any():
        return
    for s, ax in enumerate(figure.axes[: values.shape[1]]):
        ax.plot(time_min[after], values[after, s], ".", ms=2.0, color="tab:blue", alpha=0.5, label="after the stop")
        if s == 0:
            ax.legend(fontsize=7, loc="lower right")


def _sensors(outcome: dict[str, Any]) -> list[dict[str, Any]]:
    return list(outcome["sensors"])


def _number(value: object) -> float:
    return float(value) if isinstance(value, int | float) else math.nan


def _line(summary: dict[str, Any], readings: np.ndarray, hindsight: Any, s: int) -> SensorLine:  # noqa: ANN401
    ci95, decision = summary["steady_state_ci95_C"], summary["decision_interval_C"]
    slowest = max((m["time_constant_min"] for m in summary["modes"]), default=math.nan)
    valid = readings[np.isfinite(readings)]
    settled = difference = math.nan
    within: bool | None = None
    if hindsight is not None and bool(hindsight.checked[s]):
        settled = float(hindsight.settled_C[s])
        difference = float(hindsight.error_C[s])
        within = bool(hindsight.within[s])
    return SensorLine(
        sensor=summary["sensor"],
        latest_C=float(valid[-1]) if len(valid) else math.nan,
        steady_C=_number(summary["steady_state_C"]),
        ci95_C=(_number(ci95[0]), _number(ci95[1])),
        decision_interval_C=(_number(decision[0]), _number(decision[1])),
        slowest_time_constant_min=float(slowest),
        equilibrium_time_min=_number(summary["equilibrium_time_min"]),
        status=summary["status"],
        model_ok=bool(summary["model_ok"]),
        settled_C=settled,
        difference_C=difference,
        within_tolerance=within,
    )


def _hindsight_verdict(lines: tuple[SensorLine, ...], log_end_min: float, settings: MonitorSettings) -> str:
    checked = [line for line in lines if line.within_tolerance is not None]
    if not checked:
        return f"The log runs on to {minutes(log_end_min)}, but no sensor settled by its end: nothing to check."
    beyond = [line.sensor for line in checked if not line.within_tolerance]
    if beyond:
        return (
            f"Against the rest of the log (to {minutes(log_end_min)}): {', '.join(beyond)} settled beyond the "
            f"tolerance ({settings.tolerance_C:g} °C) of T∞ at the stop."
        )
    return (
        f"Against the rest of the log (to {minutes(log_end_min)}): every sensor that settled ({len(checked)}) "
        f"is within the tolerance ({settings.tolerance_C:g} °C) of T∞ at the stop."
    )


def _png(figure: Figure) -> bytes:
    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=110, bbox_inches="tight")
    return buffer.getvalue()


# ---- HTML ------------------------------------------------------------------------------------


def _fmt(value: float, digits: int = 2) -> str:
    return "—" if not math.isfinite(value) else f"{value:.{digits}f}"


def _interval(pair: tuple[float, float]) -> str:
    return f"{_fmt(pair[0])} to {_fmt(pair[1])}"


_ENVIRONMENT = jinja2.Environment(
    loader=jinja2.PackageLoader("mtident", "data"),
    autoescape=jinja2.select_autoescape(["html"]),
    undefined=jinja2.StrictUndefined,
)
_ENVIRONMENT.filters.update(fmt=_fmt, interval=_interval, minutes=minutes)


def write_html(report: WarmupReport, path: str | Path) -> Path:
    """Write the report as one self-contained HTML page (the figure embedded); returns the path.

    Parameters
    ----------
    report : WarmupReport
        From :func:`build_report`; its figure is embedded as a base64 PNG.
    path : str or Path
        The page to write (UTF-8), replaced if it exists.

    Returns
    -------
    Path
        ``path``.
    """
    page = _ENVIRONMENT.get_template("report.html.j2").render(
        r=report, figure=base64.b64encode(report.figure_png).decode("ascii"), isfinite=math.isfinite
    )
    out = Path(path)
    out.write_text(page, encoding="utf-8")
    return out


# ---- PDF -------------------------------------------------------------------------------------

_A4_INCHES = (8.27, 11.69)


def write_pdf(report: WarmupReport, path: str | Path) -> Path:
    """Write the report as a PDF (A4: the summary and table, then the curves); returns the path.

    Parameters
    ----------
    report : WarmupReport
        From :func:`build_report`.
    path : str or Path
        The PDF to write (two A4 pages), replaced if it exists.

    Returns
    -------
    Path
        ``path``.
    """
    out = Path(path)
    with PdfPages(out, metadata={"Title": f"Warm-up test: {Path(report.source).name}", "Creator": "mtident"}) as pdf:
        pdf.savefig(summary_page(report))
        pdf.savefig(_figure_page(report))
    return out


def summary_page(report: WarmupReport) -> Figure:
    """The report's first page as a figure: the verdict, the setup, the table, the assumptions.

    Parameters
    ----------
    report : WarmupReport
        The test's answer, as the report gives it.

    Returns
    -------
    Figure
        An A4 page.
    """
    fig = Figure(figsize=_A4_INCHES)
    y = 0.95
    fig.text(0.07, y, f"Warm-up test: {Path(report.source).name}", fontsize=16, weight="bold")
    y -= 0.035
    colour = "tab:green" if report.decision == "stop" else "tab:orange"
    fig.text(0.07, y, _verdict(report), fontsize=11, color=colour, weight="bold")
    y -= 0.03
    for text in _wrap(_setup(report), 110):
        fig.text(0.07, y, text, fontsize=8.5)
        y -= 0.018
    y -= 0.01
    rows_height = 0.021 * (len(report.lines) + 1)
    table_ax = fig.add_axes((0.05, y - rows_height, 0.9, rows_height))
    table_ax.axis("off")
    header = ["sensor", "T∞ (°C)", "95 % interval", "t_eq (min)", "λ (1/min)", "status", "settled (°C)", "diff. (°C)"]
    rows = [
        [
            line.sensor,
            _fmt(line.steady_C),
            _interval(line.ci95_C),
            _fmt(line.equilibrium_time_min, 0),
            _fmt(line.rate_per_min, 4),
            line.status,
            _fmt(line.settled_C),
            _fmt(line.difference_C),
        ]
        for line in report.lines
    ]
    table = table_ax.table(cellText=rows, colLabels=header, bbox=Bbox.from_bounds(0.0, 0.0, 1.0, 1.0), cellLoc="center")
    table.auto_set_font_size(False)
    table.set_fontsize(7.5)
    y -= rows_height + 0.035
    blocks = [("Assumes", report.assumptions), ("Method", report.method)]
    if report.hindsight:
        blocks.insert(0, ("Check", report.hindsight))
    if report.reason:
        blocks.insert(0, ("Why not yet", report.reason))
    if report.warnings:
        blocks.append(("Warnings", " • ".join(report.warnings)))
    for title, text in blocks:
        fig.text(0.07, y, title, fontsize=9, weight="bold")
        y -= 0.018
        for wrapped in _wrap(text, 135):
            fig.text(0.07, y, wrapped, fontsize=7.5)
            y -= 0.015
            if y < 0.05:
                break
        y -= 0.01
    fig.text(0.07, 0.025, f"mtident {report.version} · {report.created}", fontsize=7, color="0.4")
    return fig


def _figure_page(report: WarmupReport) -> Figure:
    import matplotlib.image as mpimg

    fig = Figure(figsize=_A4_INCHES)
    ax = fig.add_axes((0.03, 0.03, 0.94, 0.92))
    ax.imshow(mpimg.imread(io.BytesIO(report.figure_png), format="png"))
    ax.axis("off")
    fig.text(
        0.05, 0.965, "Measured and predicted curves, T∞ intervals (95 % shaded, the decision's dashed)", fontsize=10
    )
    return fig


def _verdict(report: WarmupReport) -> str:
    if report.decision == "stop":
        return (
            f"The test could stop at t = {minutes(report.stop_time_min)} (tolerance ±{report.tolerance_C:g} °C at "
            f"{report.decision_level * 100:g} %)."
        )
    return (
        f"No stop within the log (to {minutes(report.log_end_min)}): tolerance ±{report.tolerance_C:g} °C at "
        f"{report.decision_level * 100:g} %."
    )


def reading_gaps(time_min: np.ndarray) -> tuple[tuple[float, float], ...]:
    """Stretches of the log without readings longer than ``GAP_INTERVALS`` times its usual
    sampling interval (a logger or a recorder stopped, a server away): (from, to) in minutes.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        The readings' times (min).

    Returns
    -------
    tuple of (float, float)
    """
    if len(time_min) < 3:
        return ()
    steps = np.diff(time_min)
    long = np.flatnonzero(steps > GAP_INTERVALS * float(np.median(steps)))
    return tuple((float(time_min[k]), float(time_min[k + 1])) for k in long)


def _recorded_from(log: Path) -> str | None:
    """The source a watch recorded ``log`` from, in words, from its recorder's sidecar (None where
    there is none, or it cannot be read)."""
    from mtident.io import mtconnect, opcua

    for suffix, what in ((opcua.SIDECAR_SUFFIX, "nodes"), (mtconnect.SIDECAR_SUFFIX, "device")):
        sidecar = log.with_name(log.name + suffix)
        if not sidecar.is_file():
            continue
        try:
            saved = json.loads(sidecar.read_text(encoding="utf-8"))
        except (OSError, ValueError):
            return None
        named = ", ".join(saved.get("nodes", [])) if what == "nodes" else str(saved.get("device") or "all devices")
        start = f"; t = 0 is {saved['origin']}" if saved.get("origin") else ""
        return f"{saved.get('url')} ({what} {named}){start}"
    return None


def _gaps(report: WarmupReport) -> str:
    if not report.gaps:
        return ""
    spans = ", ".join(f"{minutes(a)} to {minutes(b)}" for a, b in report.gaps)
    return f" No readings from {spans}."


def _setup(report: WarmupReport) -> str:
    return (
        f"Log: {report.source}"
        f"{'' if report.recorded_from is None else f', recorded from {report.recorded_from}'}. "
        f"{len(report.lines)} sensor(s), {report.samples} readings every "
        f"{_fmt(report.sampling_interval_min)} min to t = {minutes(report.log_end_min)}.{_gaps(report)} "
        f"Room {report.room}."
    )


def _wrap(text: str, width: int) -> list[str]:
    import textwrap

    return textwrap.wrap(text, width) or [""]
