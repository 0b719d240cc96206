"""Figures like the papers': measured vs predicted warm-ups, RMSE vs identification time,
and (feed drive) responses and parameter convergence.

Each ``plot_*`` function writes a PNG to ``path``, or, without one, returns the
matplotlib Figure (a notebook shows it). The figures are built without pyplot,
so importing this module leaves the user's matplotlib backend and open figures
alone (it used to switch the backend to Agg, which stopped a notebook's own
inline plots from showing)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, overload

import numpy as np
from matplotlib.figure import Figure

if TYPE_CHECKING:
    from matplotlib.axes import Axes

    from mtident._typing import FloatArray
    from mtident.feeddrive.identification import FeedDriveIdentification
    from mtident.feeddrive.params import FeedDriveParameters
    from mtident.feeddrive.simulate import Response
    from mtident.thermal.identification import Identification, MethodDetails
    from mtident.thermal.min_time import MinTimeResult
    from mtident.thermal.monitor import MonitorSettings, MonitorState, Readings

__all__ = [
    "plot_identification",
    "plot_min_time",
    "plot_monitor",
    "plot_timeline",
    "draw_timeline",
    "plot_responses",
    "plot_feed_drive_identification",
    "grid",
    "draw_monitor_panel",
]


def picture_format(path: str | Path) -> str:
    """The format a picture is written in: its suffix (``png`` without one).

    Parameters
    ----------
    path : str or Path
        The picture's file name.

    Returns
    -------
    str
        The format, as matplotlib names it (``png``, ``svg``, ``pdf``, ...).

    Raises
    ------
    ValueError
        Naming the formats matplotlib writes, where it writes none such.
    """
    from matplotlib.backend_bases import FigureCanvasBase

    suffix = Path(path).suffix.lower().lstrip(".") or "png"
    formats = FigureCanvasBase.get_supported_filetypes()
    if suffix not in formats:
        msg = (
            f"'.{suffix}' is not a picture format matplotlib writes; use one of: "
            f"{', '.join('.' + f for f in sorted(formats))}"
        )
        raise ValueError(msg)
    return suffix


def _save(fig: Figure, path: str | Path | None, dpi: int = 110, top: float = 1.0) -> Path | Figure:
    """Lay out (the axes below ``top``, a fraction of the height, where a title goes above them);
    write atomically (a watcher may be reading the old picture), or return the figure without a path.

    The format follows the suffix (``fit.svg`` is an SVG; the temporary file's own suffix
    used to make every picture a PNG)."""
    fig.tight_layout(rect=(0.0, 0.0, 1.0, top))
    if path is None:
        return fig
    out = Path(path)
    fmt = picture_format(out)
    tmp = out.with_name(out.name + ".tmp")
    try:
        fig.savefig(tmp, dpi=dpi, format=fmt)
        tmp.replace(out)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
    return out


def grid(count: int, width: float = 4.2, height: float = 3.0) -> tuple[Figure, list[Axes]]:
    """A figure with ``count`` panels in up to 3 columns; returns (figure, list of axes).

    Parameters
    ----------
    count : int
        Panels wanted (1 or more); the grid's cells beyond them are hidden.
    width, height : float
        Size of one panel (inches).

    Returns
    -------
    figure : Figure
    axes : list of Axes
        The ``count`` visible panels, row by row.
    """
    cols = min(count, 3)
    rows = math.ceil(count / cols)
    fig = Figure(figsize=(width * cols, height * rows))
    axes = fig.subplots(rows, cols, squeeze=False)
    flat = list(axes.ravel())
    for ax in flat[count:]:
        ax.set_visible(False)
    return fig, flat[:count]


def plot_identification(result: Identification[MethodDetails], path: str | Path | None = None) -> Path | Figure:
    """Measured and predicted temperature per sensor, with the 95 % band, the
    identification time, T∞ and the predicted equilibrium time (Xia et al. 2014 Figs 6-8).

    Parameters
    ----------
    result : Identification
        One panel per sensor: the curve fitted up to ``result.window_min`` (min), predicted after it.
    path : str or Path, optional
        Where to write the picture, its format from the suffix (PNG without one); default:
        return the Figure instead.

    Returns
    -------
    Path or Figure
        ``path`` once written, or the Figure where no path is given.

    Raises
    ------
    ValueError
        ``path``'s suffix is not a picture format matplotlib writes.
    """
    fig, axes = grid(len(result.sensors))
    t = result.time_min
    for s, ax in enumerate(axes):
        measured = result.measured_C[:, s]
        ax.plot(t, measured, ".", ms=2.5, color="0.45", label="measured")
        mean = result.curve_C[:, s]
        low, high = result.band_low_C[:, s], result.band_high_C[:, s]
        inside = t <= result.window_min + 1e-9
        ax.plot(t[inside], mean[inside], color="tab:blue", lw=1.6, label="fitted")
        # with a room sensor the course after L follows the room as logged, and T∞ is at the room's
        # level at L: the two part where the room moved after it
        follows_room = result.details.follows_room(s)
        ax.plot(
            t[~inside],
            mean[~inside],
            color="tab:red",
            lw=1.6,
            label="predicted, with the room as logged" if follows_room else "predicted",
        )
        finite = np.isfinite(low) & np.isfinite(high) & (high - low < 100)
        ax.fill_between(t[finite], low[finite], high[finite], color="tab:red", alpha=0.18, lw=0, label="95 % band")
        ax.axvline(result.window_min, color="k", ls="--", lw=1, label=f"L = {result.window_min:g} min")
        steady = result.steady_state_C[s]
        if np.isfinite(steady):
            where = " (room as at L)" if follows_room else ""
            ax.axhline(steady, color="tab:green", ls=":", lw=1.2, label=f"T∞ = {steady:.2f} °C{where}")
        eq = result.equilibrium_time_min[s]
        if np.isfinite(eq) and eq < t[-1]:
            ax.axvline(eq, color="tab:green", ls="-.", lw=1, label=f"95 % at {eq:.0f} min")
        ax.set_title(f"{result.sensors[s]} ({result.method})", fontsize=10)
        ax.set_xlabel("time (min)")
        ax.set_ylabel("temperature (°C)")
        lo = np.nanmin(measured) - 0.5
        hi = max(np.nanmax(measured), np.nanmax(mean[np.isfinite(mean)]) if np.any(np.isfinite(mean)) else lo) + 0.5
        ax.set_ylim(lo, min(hi, np.nanmax(measured) + 10))
        ax.grid(alpha=0.3)
        if s == 0:
            ax.legend(fontsize=7, loc="lower right")
    return _save(fig, path, 110)


def plot_min_time(result: MinTimeResult, path: str | Path | None = None) -> Path | Figure:
    """RMSE against identification time for each sampling period (Xia et al. 2014 Figs 5 and 9).

    Parameters
    ----------
    result : MinTimeResult
        One panel per sensor: a curve per sampling period M (min), the chosen minimal
        identification time (min) marked.
    path : str or Path, optional
        Where to write the picture, as for :func:`plot_identification`.

    Returns
    -------
    Path or Figure
        As :func:`plot_identification` returns (and raises) for ``path``.
    """
    fig, axes = grid(len(result.sensors))
    for s, ax in enumerate(axes):
        for p, period in enumerate(result.periods_min):
            curve = result.rmse_C[p, :, s]
            ok = np.isfinite(curve)
            ax.plot(result.windows_min[ok], curve[ok], marker=".", ms=3, lw=1, label=f"M = {period:g} min")
        ax.axvline(
            result.min_identification_time_min[s],
            color="k",
            ls="--",
            lw=1,
            label=f"chosen {result.min_identification_time_min[s]:g} min",
        )
        ax.set_yscale("log")
        ax.set_title(f"{result.sensors[s]} ({result.method})", fontsize=10)
        ax.set_xlabel("identification time L (min)")
        ax.set_ylabel("RMSE (°C)")
        ax.grid(alpha=0.3, which="both")
        if s == 0:
            ax.legend(fontsize=7)
    return _save(fig, path, 110)


# Samples a panel draws at most: beyond, a line of a ringing response fills the panel solid.
_PANEL_POINTS = 2000
# The zoom shows this many periods of the lowest mode: enough to see the modes ring down.
_ZOOM_PERIODS = 8


def _zoom(time_s: FloatArray, lowest_Hz: float | None) -> slice:
    """The first samples of a record: ``_ZOOM_PERIODS`` periods of the lowest mode, or ``_PANEL_POINTS`` samples."""
    h = float(time_s[1] - time_s[0])
    count = int(_ZOOM_PERIODS / (lowest_Hz * h)) if lowest_Hz else _PANEL_POINTS
    return slice(0, max(10, min(len(time_s), count)))


def _spectrum(values: FloatArray, h: float) -> tuple[FloatArray, FloatArray]:
    """One-sided amplitude spectrum of a record (Hann window), for a log-scale panel."""
    window = np.hanning(len(values))
    amplitude = 2.0 * np.abs(np.fft.rfft((values - np.mean(values)) * window)) / window.sum()
    frequencies = np.asarray(np.fft.rfftfreq(len(values), h), dtype=np.float64)
    return frequencies, np.maximum(amplitude, 1e-300)


def _draw_spectra(
    axes: list[Axes],
    time_s: FloatArray,
    measured: FloatArray,
    model: FloatArray | None,
    modes_Hz: FloatArray | None,
) -> None:
    """Row of four spectra, one per coordinate: measured (and the model's where given), modes marked."""
    from mtident.feeddrive.params import COORDINATES
    from mtident.feeddrive.simulate import RESPONSE_COLUMNS

    h = float(time_s[1] - time_s[0])
    for c, ax in enumerate(axes):
        column = next((i + c for i in (8, 4, 0) if np.isfinite(measured[:, i + c]).all()), None)
        if column is None:
            ax.set_visible(False)
            continue
        f, amplitude = _spectrum(measured[:, column], h)
        ax.semilogy(f, amplitude, lw=0.6, color="0.45", label="measured")
        if model is not None:
            ax.semilogy(f, _spectrum(model[:, column], h)[1], lw=0.6, color="tab:blue", label="model, open loop")
        for fn in modes_Hz if modes_Hz is not None else ():
            ax.axvline(fn, color="k", ls=":", lw=0.8)
        if modes_Hz is not None:  # the band of the modes, not the noise up to the Nyquist frequency
            ax.set_xlim(0, min(f[-1], 1.5 * float(np.max(modes_Hz))))
        ax.set_ylim(amplitude.max() * 1e-6, amplitude.max() * 3)
        ax.set_title(f"spectrum of {RESPONSE_COLUMNS[column]} ({COORDINATES[c]})", fontsize=9)
        ax.set_xlabel("frequency (Hz)")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)


def plot_responses(
    response: Response,
    path: str | Path | None = None,
    modes_Hz: FloatArray | None = None,
) -> Path | Figure:
    """Displacements, velocities and accelerations of the four coordinates (Nguyen-Quoc et al. Figs 2-4), readable
    at any length: the first periods of the lowest mode sample by sample, and the spectrum of the
    whole record per coordinate with the natural frequencies ``modes_Hz`` (Hz) marked where given.

    Parameters
    ----------
    response : Response
        The record: times (N,) in s and the 12 responses (N, 12). A spectrum shows a coordinate's
        acceleration, else its velocity, else its displacement: the first with no NaN.
    path : str or Path, optional
        Where to write the picture, as for :func:`plot_identification`.
    modes_Hz : array_like, shape (4,), optional
        Natural frequencies (Hz): the zoom spans a few periods of the lowest and the spectra
        the band up to 1.5 × the highest. Without them the zoom is the first samples.

    Returns
    -------
    Path or Figure
        As :func:`plot_identification` returns (and raises) for ``path``.
    """
    from mtident.feeddrive.simulate import RESPONSE_COLUMNS

    zoom = _zoom(response.time_s, None if modes_Hz is None else float(np.min(modes_Hz)))
    fig = Figure(figsize=(16, 10.5))
    axes = fig.subplots(4, 4)
    t = response.time_s[zoom]
    for i, ax in enumerate(axes[:3].ravel()):
        ax.plot(t * 1e3, response.values[zoom, i], lw=0.7)
        ax.set_title(RESPONSE_COLUMNS[i], fontsize=9)
        ax.grid(alpha=0.3)
    for ax in axes[2]:
        ax.set_xlabel("time (ms)")
    _draw_spectra(axes[3], response.time_s, response.values, None, modes_Hz)
    span = response.time_s[-1] - response.time_s[0]
    fig.suptitle(f"first {1e3 * (t[-1] - t[0]):.3g} ms of {span:.3g} s; spectra over the whole record", fontsize=10)
    return _save(fig, path, 100)


def plot_feed_drive_identification(
    result: FeedDriveIdentification,
    response: Response,
    path: str | Path | None = None,
    truth: FeedDriveParameters | None = None,
) -> Path | Figure:
    """Measured, filtered and open-loop model responses over the first periods (Nguyen-Quoc et al. Figs 5-7), the
    spectra of measured vs model responses, and parameter convergence with ±2σ (Figs 8-9).

    The filtered responses follow the data whatever the parameters; the open-loop model (the set the
    consistency check fitted, run with the measured forces alone) shows whether the parameters do.

    Parameters
    ----------
    result : FeedDriveIdentification
        The estimate, its history with ±2σ per identified parameter, and the filtered responses.
    response : Response
        The record identified from: its forces drive the open-loop model, and its measured
        columns (``result.measured_columns``) are drawn.
    path : str or Path, optional
        Where to write the picture, as for :func:`plot_identification`.
    truth : FeedDriveParameters, optional
        The true parameters (a synthetic record): drawn as a line on each convergence panel.

    Returns
    -------
    Path or Figure
        As :func:`plot_identification` returns (and raises) for ``path``.
    """
    from mtident.feeddrive.modes import modes
    from mtident.feeddrive.params import IDENTIFIED
    from mtident.feeddrive.simulate import RESPONSE_COLUMNS

    estimate = result.guess.with_identified(result.parameters)
    frequencies = modes(estimate).frequencies_Hz
    model = result.model_response(response)
    zoom = _zoom(result.time_s, float(frequencies[0]))
    fig = Figure(figsize=(16, 19))
    axes = fig.subplots(6, 4)
    t = result.time_s[zoom] * 1e3
    for i, ax in enumerate(axes[:3].ravel()):
        if RESPONSE_COLUMNS[i] not in result.measured_columns:
            ax.set_title(f"{RESPONSE_COLUMNS[i]} (not measured)", fontsize=9)
        else:
            ax.plot(t, response.values[zoom, i], lw=0.5, color="0.6", label="measured")
            ax.set_title(RESPONSE_COLUMNS[i], fontsize=9)
        ax.plot(t, result.estimated[zoom, i], lw=0.6, color="tab:red", label="UKF (filtered)")
        ax.plot(t, model[zoom, i], lw=0.6, ls="--", color="tab:blue", label="model, open loop")
        ax.grid(alpha=0.3)
    for ax in axes[2]:
        ax.set_xlabel("time (ms)")
    axes[0, 0].legend(fontsize=7)
    measured = np.where(np.isin(np.array(RESPONSE_COLUMNS), result.measured_columns), response.values, np.nan)
    _draw_spectra(axes[3], result.time_s, measured, model, frequencies)
    stride = max(1, len(result.time_s) // _PANEL_POINTS)
    th = result.time_s[::stride]
    refined = result.filter_parameters is not None
    for j, ax in enumerate(axes[4:].ravel()):
        mean, sd = result.history[::stride, j], result.history_std[::stride, j]
        ax.plot(th, mean, color="tab:blue", lw=1, label="filter ±2σ")
        ax.fill_between(th, mean - 2 * sd, mean + 2 * sd, color="tab:blue", alpha=0.2, lw=0)
        value, half = result.parameters[j], 2 * result.parameters_std[j]
        if refined:  # the answer given: the whole record fitted, drawn over it
            ax.axhline(value, color="tab:red", lw=1, label="refined ±2σ")
            ax.axhspan(value - half, value + half, color="tab:red", alpha=0.2, lw=0)
        if truth is not None:
            ax.axhline(getattr(truth, IDENTIFIED[j]), color="k", ls="--", lw=1, label="true")
        settled = slice(len(th) // 20, None)  # the start, from the guess, would flatten the rest
        low = min(np.min((mean - 2 * sd)[settled]), value - half)
        high = max(np.max((mean + 2 * sd)[settled]), value + half)
        if np.isfinite(low) and np.isfinite(high) and high > low:
            ax.set_ylim(low - 0.2 * (high - low), high + 0.2 * (high - low))
        ax.ticklabel_format(axis="y", useOffset=False)  # an offset label overlaps the title
        ax.set_title(f"{IDENTIFIED[j]} ({'identified' if result.identifiable[j] else 'not identified'})", fontsize=9)
        ax.set_xlabel("time (s)")
        ax.grid(alpha=0.3)
    axes[4, 0].legend(fontsize=7)
    fig.suptitle(
        f"Responses over the first {t[-1]:.0f} ms of {result.time_s[-1]:.3g} s (rows 1-3), their spectra (row 4), "
        "the parameters over the record (rows 5-6)",
        fontsize=11,
    )
    return _save(fig, path, 90, top=0.985)


def _room_on(readings: Readings, times: np.ndarray) -> np.ndarray:
    """The room's readings at ``times``: interpolated, held at the ends (NaN where none is valid)."""
    room = np.asarray(readings.room_C, dtype=float)
    valid = np.isfinite(room)
    if not valid.any():
        return np.full(times.shape, np.nan)
    room_on: np.ndarray = np.interp(times, readings.time_min[valid], room[valid])
    return room_on


@overload
def plot_monitor(
    state: MonitorState,
    settings: MonitorSettings,
    path: None = None,
    expected: dict[str, float] | None = None,
    after: tuple[FloatArray, FloatArray] | None = None,
) -> Figure: ...


@overload
def plot_monitor(
    state: MonitorState,
    settings: MonitorSettings,
    path: str | Path,
    expected: dict[str, float] | None = None,
    after: tuple[FloatArray, FloatArray] | None = None,
) -> Path: ...


def plot_monitor(
    state: MonitorState,
    settings: MonitorSettings,
    path: str | Path | None = None,
    expected: dict[str, float] | None = None,
    after: tuple[FloatArray, FloatArray] | None = None,
) -> Path | Figure:
    """Each sensor's readings so far, its best model's course on from there, the T∞ intervals
    (95 % and the decision's), and the stop or the expected stop.

    Parameters
    ----------
    state : MonitorState
        The readings (min, °C) and each sensor's latest check; one panel per sensor.
    settings : MonitorSettings
        The settings ``state`` was decided with; the intervals drawn are the ones its checks hold.
    path : str or Path, optional
        Where to write the picture, as for :func:`plot_identification`.
    expected : dict of str to float, optional
        Sensor name → expected stop (min), drawn where finite and the test has not stopped
        (:meth:`~mtident.thermal.session.WatchSession.expected_stops`).
    after : (ndarray (T,), ndarray (T, S)), optional
        A replayed log's readings after the stop (min, °C), drawn apart from those the decision saw.

    Returns
    -------
    Path or Figure
        As :func:`plot_identification` returns (and raises) for ``path``.
    """
    fig, axes = grid(len(state.sensors))
    for s, ax in enumerate(axes):
        draw_monitor_panel(ax, state, settings, s, expected)
        if after is not None and len(after[0]):
            ax.plot(after[0], after[1][:, s], ".", ms=2.5, color="tab:blue", alpha=0.4, label="after the stop")
        if s == 0:
            ax.legend(fontsize=7, loc="lower right")
    return _save(fig, path, 100)


def draw_monitor_panel(
    ax: Axes, state: MonitorState, settings: MonitorSettings, s: int, expected: dict[str, float] | None = None
) -> None:
    """One sensor's panel of :func:`plot_monitor` on ``ax`` (a report lays the panels out on its pages).

    Parameters
    ----------
    ax : Axes
        Where to draw.
    state : MonitorState
        The readings (min, °C) and each sensor's latest check.
    settings : MonitorSettings
        The settings ``state`` was decided with.
    s : int
        The sensor's index in ``state.sensors``.
    expected : dict of str to float, optional
        Sensor name → expected stop (min), drawn where finite and the test has not stopped.
    """
    from mtident.thermal.modes import Mode, course_with_room
    from mtident.thermal.monitor import minutes

    readings = state.readings
    now = readings.latest_min
    check = state.checks[s]
    ax.plot(readings.time_min, readings.values_C[:, s], ".", ms=2.5, color="0.45", label="measured")
    if check.modes and np.isfinite(check.steady_C):
        slowest = max(tau for tau, _ in check.modes)
        future = np.linspace(check.origin_min, now + max(3.0 * slowest, 0.5 * now, 30.0), 300)
        # with a room sensor the model follows the room as logged (held at its last level on)
        logged = readings.room_C is not None and not np.isnan(check.room_level_C)
        curve = course_with_room(
            tuple(Mode(t, a) for t, a in check.modes),
            check.steady_C,
            check.origin_min,
            future,
            _room_on(readings, future) if logged else None,
            check.room_level_C if logged else None,
            check.room_gains,
            tuple(t for t, _ in check.modes),
        )
        label = "best model, with the room as logged" if logged else "best model"
        ax.plot(future, curve, color="tab:red", lw=1.5, label=label, zorder=3)
    if np.isfinite(check.low95_C) and np.isfinite(check.high95_C):
        ax.axhspan(check.low95_C, check.high95_C, color="tab:green", alpha=0.2, lw=0, label="T∞ 95 %")
    if np.isfinite(check.low_C) and np.isfinite(check.high_C):
        for k, edge in enumerate((check.low_C, check.high_C)):
            ax.axhline(edge, color="tab:green", lw=0.8, ls="--", label=None if k else "T∞, decision's level")
    if state.stopped:
        ax.axvline(state.stop_time_min, color="k", ls="--", lw=1, label=f"stop at {minutes(state.stop_time_min)}")
    elif expected and np.isfinite(expected.get(check.sensor, np.nan)):
        ax.axvline(expected[check.sensor], color="0.4", ls=":", lw=1, label="expected stop")
    ax.set_title(f"{check.sensor}: {check.status}", fontsize=10)
    ax.set_xlabel("time (min)")
    ax.set_ylabel("temperature (°C)")
    ax.grid(alpha=0.3)
    measured = readings.values_C[:, s]
    if np.isfinite(measured).any():
        # the interval shown where it is of the rise's size; a far wider one would flatten the curve
        low, high = float(np.nanmin(measured)), float(np.nanmax(measured))
        span = max(high - low, 0.5)
        # the 95 % band and the decision's level both show, where they are of the rise's size
        edges = [v for v in (check.low95_C, check.high95_C, check.low_C, check.high_C) if np.isfinite(v)]
        low = max(min([low, *edges]), low - span)
        high = min(max([high, *edges]), high + span)
        ax.set_ylim(low - 0.05 * span, high + 0.05 * span)


@overload
def plot_timeline(state: MonitorState, settings: MonitorSettings, path: None = None) -> Figure: ...


@overload
def plot_timeline(state: MonitorState, settings: MonitorSettings, path: str | Path) -> Path: ...


def plot_timeline(state: MonitorState, settings: MonitorSettings, path: str | Path | None = None) -> Path | Figure:
    """How each sensor's interval narrowed to the tolerance: :func:`draw_timeline` as a picture.

    Parameters
    ----------
    state : MonitorState
        Its checks so far (:attr:`~mtident.thermal.monitor_types.MonitorState.timeline`).
    settings : MonitorSettings
        The settings ``state`` was decided with (the tolerance drawn).
    path : str or Path, optional
        Where to write the picture, as for :func:`plot_identification`.

    Returns
    -------
    Path or Figure
        As :func:`plot_identification` returns (and raises) for ``path``.
    """
    fig = Figure(figsize=(8.0, 3.6))
    draw_timeline(fig.subplots(), state, settings)
    return _save(fig, path, 100)


def draw_timeline(ax: Axes, state: MonitorState, settings: MonitorSettings) -> None:
    """At each check, how far the decision's interval reaches from T∞ (its larger half-width), per
    sensor, on a log scale down to the tolerance a sensor must come within; the stop.

    Parameters
    ----------
    ax : Axes
        Where to draw.
    state : MonitorState
    settings : MonitorSettings
    """
    from mtident.thermal.monitor import minutes
    from mtident.thermal.timeline import check_timeline

    table = check_timeline(state)
    steady = table["steady_state_C"]
    reach = np.fmax(steady - table["decision_low_C"], table["decision_high_C"] - steady)
    for name in state.sensors:
        mine = (table["sensor"] == name).to_numpy() & np.isfinite(reach.to_numpy())
        ax.plot(table["checked_at_min"][mine], reach[mine], ".-", ms=3, lw=1, label=name)
    ax.axhline(settings.tolerance_C, color="k", lw=1, ls="--", label=f"tolerance {settings.tolerance_C:g} °C")
    if state.stopped:
        ax.axvline(state.stop_time_min, color="k", lw=1, ls=":", label=f"stop at {minutes(state.stop_time_min)}")
    ax.set_yscale("log")
    ax.set_xlabel("time of the check (min)")
    ax.set_ylabel(f"T∞ interval's reach at {settings.decision_level * 100:g} % (°C)")
    ax.grid(alpha=0.3, which="both")
    ax.legend(fontsize=6, ncol=max(1, math.ceil((len(state.sensors) + 2) / 8)), loc="upper right")
