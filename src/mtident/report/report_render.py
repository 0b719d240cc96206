"""The warm-up report rendered for the customer: :func:`write_html` writes one self-contained
HTML page (the figure embedded) and :func:`write_pdf` an A4 PDF (the curves laid out two to a
row, on as few pages as they fill), both from the same
:class:`~mtident.report.test_report.WarmupReport` that
:func:`~mtident.report.test_report.build_report` gathers; the verdict, the setup and the table
in words as both show them, and the notes said under the table and the pictures.
"""

from __future__ import annotations

import base64
import io
import math
import textwrap
from pathlib import Path
from typing import Any

import jinja2
from matplotlib.axes import Axes
from matplotlib.backends.backend_pdf import PdfPages
from matplotlib.figure import Figure
from matplotlib.transforms import Bbox

from mtident.report.plots import draw_monitor_panel, draw_timeline
from mtident.report.test_report import WarmupReport, draw_rest_of_log, status_words
from mtident.thermal.monitor import minutes
from mtident.thermal.monitor_answer import WAYS_ON

__all__ = ["write_html", "write_pdf"]

# under the picture of the checks
TIMELINE_WORDS = (
    "At each check, how far T∞'s interval at the decision's level reached from T∞, per sensor (log scale): a "
    "sensor may stop once it stays within the tolerance (dashed) at two checks in a row. The watch's "
    "--timeline option writes the same checks as CSV."
)
# the warnings' heading: each said at its check, not the answer at the end
WARNINGS_NOTE = (
    "As said during the test, each at its time (t = …): a later check may have withdrawn it. The table above is "
    "the answer at the end."
)
# the table's terms, said under it
T_EQ_NOTE = (
    "t_eq: when the best model's curve comes within 5 % of its total rise from T∞ (min from t = 0). "
    "95 % interval: where T∞ lies, at 95 %, by every model the readings allow; the decision's interval, at its "
    "level, is the one held against the tolerance."
)
SETTLED_NOTE = (
    "settled: where the readings after the stop came to rest (room: readings that keep following the room, where "
    "their rise above it, as the sensor follows it, came to rest, at the room's level at the log's end); "
    "difference: T∞ at the stop (moved with the room) less that; settled by: when the readings came within the "
    "tolerance of it, to stay."
)


# ---- the pieces ----------------------------------------------------------------------------------


def saved_words(report: WarmupReport) -> str | None:
    """The readings' settle time and the time the stop saved, in words, where known.

    Parameters
    ----------
    report : WarmupReport

    Returns
    -------
    str or None
    """
    if not math.isfinite(report.settle_time_min):
        return None
    settled = f"The readings settled within the tolerance by t = {minutes(report.settle_time_min)}"
    saved = report.time_saved_min
    if not math.isfinite(saved):
        return settled + "."
    if saved >= 0:
        return f"{settled}: the stop at {minutes(report.stop_time_min)} saved {saved:.0f} min."
    return f"{settled}, {-saved:.0f} min before the stop at {minutes(report.stop_time_min)}."


def _verdict(report: WarmupReport) -> str:
    if report.decision == "stop":
        return (
            f"The test could stop at t = {minutes(report.stop_time_min)}: every sensor's T∞ known within "
            f"±{report.tolerance_C:g} °C at {report.decision_level * 100:g} %."
        )
    return (
        f"No stop within the log (to {minutes(report.log_end_min)}): not every sensor's T∞ is known within "
        f"±{report.tolerance_C:g} °C at {report.decision_level * 100:g} % yet."
    )


def _gaps(report: WarmupReport) -> str:
    if not report.gaps:
        return ""
    spans = ", ".join(f"{minutes(a)} to {minutes(b)}" for a, b in report.gaps)
    return f"; none from {spans}"


def _setup(report: WarmupReport) -> list[tuple[str, str]]:
    """The setup, (term, words) as the HTML's list and the PDF's lines show it."""
    rows = []
    if report.machine:
        rows.append(("Machine", report.machine + (f", serial {report.serial}" if report.serial else "")))
    if report.program:
        rows.append(("Reference run's program", f"{report.program} (this test's may differ)"))
    rows.append(("t = 0", report.start_words))
    log = report.source + ("" if report.recorded_from is None else f", recorded from {report.recorded_from}")
    rows += [
        ("Log", log),
        ("Sensors", ", ".join(line.sensor for line in report.lines)),
        (
            "Readings",
            f"{report.samples}, every {_fmt(report.sampling_interval_min)} min, to t = "
            f"{minutes(report.log_end_min)}{_gaps(report)}",
        ),
        ("Room", report.room),
        ("Decision", f"tolerance ±{report.tolerance_C:g} °C, confidence {report.decision_level * 100:.0f} %"),
    ]
    return rows


# ---- HTML ------------------------------------------------------------------------------------


def _fmt(value: float, digits: int = 2) -> str:
    return "—" if not math.isfinite(value) else f"{value:.{digits}f}"


def _interval(pair: tuple[float, float]) -> str:
    return f"{_fmt(pair[0])} to {_fmt(pair[1])}"


def _settled(report: WarmupReport) -> bool:
    """Whether the hindsight checked a sensor: the table's columns of where they settled."""
    return any(line.within_tolerance is not None for line in report.lines)


def _table(report: WarmupReport) -> tuple[list[str], list[list[str]]]:
    """The table for the customer: header and rows (the hindsight's columns where a sensor settled)."""
    reading = "at the stop (°C)" if report.decision == "stop" else "latest (°C)"
    # the decision's own interval beside the 95 % one: a reader checks the stop against it
    decision = f"{report.decision_level * 100:g} % interval (°C)"
    header = ["sensor", reading, "T∞ (°C)", "95 % interval (°C)", decision, "t_eq (min)", "status"]
    if _settled(report):
        header += ["settled (°C)", "difference (°C)", "settled by (min)"]
    rows = []
    for line in report.lines:
        row = [
            line.sensor,
            _fmt(line.latest_C),
            _fmt(line.steady_C),
            _interval(line.ci95_C),
            _interval(line.decision_interval_C),
            _fmt(line.equilibrium_time_min, 0),
            status_words(line),
        ]
        if _settled(report):
            settled = _fmt(line.settled_C) + (" (room)" if line.settled_with_room else "")
            row += [settled, _signed(line.difference_C), _fmt(line.settle_time_min, 0)]
        rows.append(row)
    return header, rows


def _signed(value: float) -> str:
    return "—" if not math.isfinite(value) else f"{value:+.2f}"


_ENVIRONMENT = jinja2.Environment(
    loader=jinja2.PackageLoader("mtident", "data"),
    autoescape=jinja2.select_autoescape(["html", "html.j2"]),  # a sensor's name may hold < or &
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
    header, rows = _table(report)
    page = _ENVIRONMENT.get_template("report.html.j2").render(
        r=report,
        verdict=_verdict(report),
        saved=saved_words(report),
        setup=_setup(report),
        header=header,
        rows=list(zip(rows, [line.within_tolerance is False for line in report.lines], strict=True)),
        notes=[T_EQ_NOTE] + ([SETTLED_NOTE] if _settled(report) else []),
        figure=base64.b64encode(report.figure_png).decode("ascii"),
        timeline=base64.b64encode(report.timeline_png).decode("ascii"),
        timeline_words=TIMELINE_WORDS,
        warnings_note=WARNINGS_NOTE,
    )
    out = Path(path)
    out.write_text(page, encoding="utf-8")
    return out


# ---- PDF -------------------------------------------------------------------------------------

_A4_INCHES = (8.27, 11.69)
_LEFT, _RIGHT, _TOP, _BOTTOM = 0.07, 0.93, 0.955, 0.055
# the curves: two panels to a row, each row this high (a fraction of the page)
_PANELS_PER_ROW = 2
_ROW_HEIGHT = 0.22  # four rows to a page


class _Pages:
    """A4 pages filled from the top: text, the table and rows of curves flow on to a new page
    where the one in hand is full."""

    def __init__(self) -> None:
        self.figures: list[Figure] = []
        self.y = 0.0
        self.new_page()

    @property
    def page(self) -> Figure:
        return self.figures[-1]

    def new_page(self) -> None:
        self.figures.append(Figure(figsize=_A4_INCHES))
        self.y = _TOP

    def room(self, height: float) -> None:
        """Start a new page unless ``height`` fits on this one."""
        if self.y - height < _BOTTOM:
            self.new_page()

    def text(
        self, text: str, size: float = 8.0, indent: float = 0.0, keep: float = 0.0, whole: bool = False, **style: Any
    ) -> None:  # noqa: ANN401
        """Wrapped to the page's width; ``keep``: room wanted below the first line (a heading's
        text); ``whole``: the lines not split over two pages."""
        step = size * 1.5 / 72.0 / _A4_INCHES[1]
        width = int((_RIGHT - _LEFT - indent) * _A4_INCHES[0] * 72.0 / (size * 0.55))
        wrapped = textwrap.wrap(text, width) or [""]
        if whole:
            self.room(step * len(wrapped))
        for k, line in enumerate(wrapped):
            self.room(step + (keep if k == 0 else 0.0))
            self.y -= step
            self.page.text(_LEFT + indent, self.y, line, fontsize=size, **style)

    def bullet(self, text: str, size: float = 8.0) -> None:
        step = size * 1.5 / 72.0 / _A4_INCHES[1]
        self.room(step)
        self.page.text(_LEFT + 0.01, self.y - step, "•", fontsize=size)
        self.text(text, size, indent=0.03)

    def heading(self, text: str, keep: float = 0.06) -> None:
        self.space(0.012)
        self.text(text, 10.0, keep=keep, weight="bold")
        self.space(0.004)

    def space(self, height: float) -> None:
        self.y -= height

    def table(self, header: list[str], rows: list[list[str]], widths: list[float]) -> None:
        height = 0.022 * (len(rows) + 1)
        self.room(height)
        ax = self.page.add_axes((_LEFT - 0.02, self.y - height, _RIGHT - _LEFT + 0.04, height))
        ax.axis("off")
        table = ax.table(
            cellText=rows, colLabels=header, colWidths=widths, bbox=Bbox.from_bounds(0, 0, 1, 1), cellLoc="center"
        )
        table.auto_set_font_size(False)
        table.set_fontsize(7.0)
        for (row, _), cell in table.get_celld().items():
            cell.set_linewidth(0.4)
            if row == 0:
                cell.set_facecolor("#eeeeee")
        self.y -= height

    def wide_panel(self) -> Axes:
        """Axes the page's width and one row of curves high."""
        self.room(_ROW_HEIGHT)
        bottom = self.y - _ROW_HEIGHT + 0.045
        ax = self.page.add_axes((_LEFT + 0.04, bottom, _RIGHT - _LEFT - 0.04, _ROW_HEIGHT - 0.075))
        self.y -= _ROW_HEIGHT
        return ax

    def panels(self, count: int) -> list[Axes]:
        """Axes for ``count`` curves, two to a row, on this page and on as many more as they need."""
        axes: list[Axes] = []
        width = (_RIGHT - _LEFT - 0.08) / _PANELS_PER_ROW
        for start in range(0, count, _PANELS_PER_ROW):
            self.room(_ROW_HEIGHT)
            for k in range(min(_PANELS_PER_ROW, count - start)):
                left = _LEFT + 0.04 + k * (width + 0.08)
                axes.append(self.page.add_axes((left, self.y - _ROW_HEIGHT + 0.045, width, _ROW_HEIGHT - 0.075)))
            self.y -= _ROW_HEIGHT
        return axes


def write_pdf(report: WarmupReport, path: str | Path) -> Path:
    """Write the report as an A4 PDF: the verdict, the setup, why not yet, the table, the
    curves two to a row (drawn as vectors from ``report.curves``, else the report's picture),
    then the warnings, the assumptions and the method; returns the path.

    Parameters
    ----------
    report : WarmupReport
        From :func:`build_report`.
    path : str or Path
        The PDF to write, replaced if it exists.

    Returns
    -------
    Path
        ``path``.
    """
    pages = summary_pages(report)
    out = Path(path)
    with PdfPages(out, metadata={"Title": report.title, "Creator": f"mtident {report.version}"}) as pdf:
        for page in pages:
            pdf.savefig(page)
    return out


def summary_pages(report: WarmupReport) -> list[Figure]:
    """The report's pages as A4 figures: the curves drawn from ``report.curves``, two to a row;
    without them the report's picture is placed, as large as the page's width allows.

    Parameters
    ----------
    report : WarmupReport

    Returns
    -------
    list of Figure
    """
    pages = _Pages()
    pages.text(report.title, 15.0, weight="bold")
    pages.space(0.004)
    pages.text(report.subtitle, 9.0, color="0.35")
    pages.space(0.01)
    colour = "tab:green" if report.decision == "stop" else "tab:orange"
    pages.text(_verdict(report), 11.0, color=colour, weight="bold")
    if (saved := saved_words(report)) is not None:
        pages.text(saved, 9.0)
    if report.hindsight:
        pages.text(report.hindsight, 8.5)
    if report.log_warnings:
        pages.heading("Read with warnings", keep=0.03)
        for line in report.log_warnings:
            pages.bullet(line, 8.0)
    if report.holding:
        pages.heading("Why not yet", keep=0.03)
        for line in report.holding:
            pages.bullet(line, 8.0)
        if report.ways_on:
            pages.text(f"{WAYS_ON}{report.ways_on}.", 8.0, weight="bold")
    pages.heading("Setup", keep=0.03)
    for term, words in _setup(report):
        pages.text(f"{term}: {words}", 8.0)
    pages.heading("Per sensor", keep=0.022 * (len(report.lines) + 1))
    header, rows = _table(report)
    widths = [1.3, 0.9, 0.8, 1.5, 1.5, 0.7, 2.8] + ([0.9, 1.0, 0.9] if _settled(report) else [])
    if _settled(report):
        header = [h.replace(" (", "\n(") for h in header]
    pages.table(header, rows, widths)
    pages.space(0.006)
    for note in [T_EQ_NOTE] + ([SETTLED_NOTE] if _settled(report) else []):
        pages.text(note, 6.5, whole=True, color="0.35")
    pages.heading("Curves", keep=_ROW_HEIGHT)
    pages.text(
        "Measured readings, the best model's course, T∞'s 95 % interval (shaded) and the decision's (dashed), "
        "the stop, and the readings after it, which the decision did not see.",
        7.5,
        keep=_ROW_HEIGHT,
    )
    _curves(pages, report)
    if report.curves is not None and len(report.curves.state.timeline):
        pages.heading("How the intervals narrowed", keep=_ROW_HEIGHT)
        pages.text(TIMELINE_WORDS, 7.5, keep=_ROW_HEIGHT)
        ax = pages.wide_panel()
        draw_timeline(ax, report.curves.state, report.curves.settings)
        ax.xaxis.label.set_fontsize(7.5)
        ax.yaxis.label.set_fontsize(7.5)
        ax.tick_params(labelsize=7)
    if report.warnings:
        pages.heading("Warnings", keep=0.03)
        pages.text(WARNINGS_NOTE, 7.5)
        for warning in report.warnings:
            pages.bullet(warning, 7.5)
    if report.log_notes:
        pages.heading("How the log was read", keep=0.03)
        for line in report.log_notes:
            pages.bullet(line, 7.5)
    pages.heading("What the answer assumes", keep=0.03)
    pages.text(report.assumptions, 7.5)
    pages.heading("Method", keep=0.03)
    pages.text(report.method, 7.5)
    count = len(pages.figures)
    for k, page in enumerate(pages.figures, 1):
        page.text(
            _LEFT,
            0.025,
            f"{report.title} · mtident {report.version} · made {report.created} · page {k} of {count}",
            fontsize=6.5,
            color="0.4",
        )
    return pages.figures


def _curves(pages: _Pages, report: WarmupReport) -> None:
    curves = report.curves
    if curves is None:
        import matplotlib.image as mpimg

        picture = mpimg.imread(io.BytesIO(report.figure_png), format="png")
        width = _RIGHT - _LEFT
        height = min(width * _A4_INCHES[0] * picture.shape[0] / picture.shape[1] / _A4_INCHES[1], _TOP - _BOTTOM)
        pages.room(height)
        ax = pages.page.add_axes((_LEFT, pages.y - height, width, height))
        ax.imshow(picture)
        ax.axis("off")
        pages.y -= height
        return
    state = curves.state
    axes = pages.panels(len(state.sensors))
    for s, ax in enumerate(axes):
        draw_monitor_panel(ax, state, curves.settings, s)
        ax.title.set_fontsize(8.5)
        ax.xaxis.label.set_fontsize(7.5)
        ax.yaxis.label.set_fontsize(7.5)
        ax.tick_params(labelsize=7)
        if state.stopped and s < curves.values_C.shape[1]:
            draw_rest_of_log(ax, curves.time_min, curves.values_C[:, s], state.stop_time_min, legend=False)
        if s == 0:
            ax.legend(fontsize=6, loc="lower right")
