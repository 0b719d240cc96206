"""``mtident thermal ...``: identify a warm-up, find the minimal identification time."""

from __future__ import annotations

from importlib import resources
from pathlib import Path

import click
import numpy as np
from rich.console import Console
from rich.table import Table

from mtident.cli import print_json, thermal, user_errors
from mtident.exceptions import InputError
from mtident.io.logs import TIME_UNITS, TemperatureLog, read_temperature_log
from mtident.thermal import DEFAULT_METHOD, METHODS, PRESETS, identify, minimal_identification_time

SAMPLE = "@sample"
stderr = Console(stderr=True, soft_wrap=True)


def sample_log_path() -> Path:
    """The 10-sensor warm-up log shipped in the package (scripts/make_sample_warmup.py)."""
    return Path(str(resources.files("mtident") / "data" / "spindle_warmup.csv"))


def load_log(file: str, sensors: tuple[str, ...], time_col: str | None, time_unit: str | None) -> TemperatureLog:
    path = sample_log_path() if file == SAMPLE else Path(file)
    log = read_temperature_log(path, time_col=time_col, time_unit=time_unit)
    names = [name for entry in sensors for name in entry.split(",") if name]
    log = log.select(names or None)
    for note in log.notes:
        stderr.print(f"mtident: note: {note}", highlight=False)
    return log


def log_options(func):  # noqa: ANN001,ANN201 - click decorator stack
    func = click.option("--time-unit", type=click.Choice(list(TIME_UNITS)), help="Unit of a numeric time column (default: from its header suffix _s/_min/_h, else min).")(func)
    func = click.option("--time-col", metavar="NAME", help="Time column (default: the first column).")(func)
    func = click.option("--sensor", "sensors", multiple=True, metavar="NAME", help="Sensor column(s) to use; repeat or comma-separate (default: all).")(func)
    func = click.argument("file", metavar="FILE")(func)
    return func


def _fmt(value: object, digits: int = 2) -> str:
    if value is None:
        return "—"
    if isinstance(value, float):
        return f"{value:.{digits}f}"
    return str(value)


@thermal.command("identify")
@log_options
@click.option("--window", "window_min", type=click.FloatRange(min=0, min_open=True), default=30.0, show_default=True, help="Identification time L in minutes from the first sample.")
@click.option("--method", type=click.Choice(METHODS), default=DEFAULT_METHOD, show_default=True, help="ukf, aukf (Xia 2014), fukf, afukf (Yu 2019) or lsq (least squares).")
@click.option("--preset", type=click.Choice(PRESETS), default="data", show_default=True, help="Initial values and tuning: from the data, or a paper's exactly.")
@click.option("--horizon", "horizon_min", type=click.FloatRange(min=0, min_open=True), help="Predict to this time (min).")
@click.option("--pseudo-seed", type=int, help="Predict with seed 000's noisy pseudo-measurements (Eqs 21-22) from this seed.")
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False, writable=True), help="Draw measured and predicted curves to this PNG.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of a table.")
@user_errors
def identify_command(file: str, sensors: tuple[str, ...], time_col: str | None, time_unit: str | None, window_min: float, method: str, preset: str, horizon_min: float | None, pseudo_seed: int | None, plot_path: str | None, as_json: bool) -> None:
    """Identify the temperature rise from the first WINDOW minutes of FILE and predict the rest.

    FILE is a CSV log (time column, one column per sensor) or @sample for the
    10-sensor warm-up shipped with mtident.
    """
    log = load_log(file, sensors, time_col, time_unit)
    result = identify(log, window_min, method, preset, horizon_min, pseudo_seed)
    for note in result.notes[len(log.notes):]:
        stderr.print(f"mtident: warning: {note}", highlight=False)
    if plot_path:
        from mtident.report import plot_identification

        plot_identification(result, plot_path)
        stderr.print(f"mtident: plot written to {plot_path}", highlight=False)
    summaries = [result.summary(i) for i in range(len(result.sensors))]
    if as_json:
        print_json(summaries[0] if len(summaries) == 1 else {"sensors": summaries, "method": method, "window_min": result.window_min})
        return
    table = Table(title=f"{log.source}: identified from the first {result.window_min:g} min ({method}, preset {preset})")
    for column in ("sensor", "T∞ ± 95 % (°C)", "λ (1/min)", "t_eq (min)", "RMSE (°C)", "model", "measured T / t_eq"):
        table.add_column(column, justify="right" if column != "sensor" else "left", no_wrap=True)
    for d in summaries:
        lo, hi = d["steady_state_ci95_C"]
        half = None if lo is None or hi is None else (hi - lo) / 2
        measured = "—" if d["measured_final_C"] is None else f"{d['measured_final_C']:.2f} / {_fmt(d['measured_equilibrium_time_min'], 0)}"
        table.add_row(
            str(d["sensor"]), f"{_fmt(d['steady_state_C'])} ± {_fmt(half)}", _fmt(d["lambda_per_min"], 4),
            _fmt(d["equilibrium_time_min"], 0), _fmt(d["rmse_C"], 3),
            "fits" if d["model_fits"] else "[yellow]misfit[/]", measured,
        )
    Console(width=max(Console().width, 100)).print(table)


def _float_list(text: str, option: str) -> list[float]:
    try:
        values = [float(v) for v in text.split(",") if v.strip()]
    except ValueError as exc:
        msg = f"{option}: expected comma-separated minutes such as 35,40,45,50; found {text!r}"
        raise InputError(msg) from exc
    if not values or any(v <= 0 for v in values):
        msg = f"{option}: expected positive minutes; found {text!r}"
        raise InputError(msg)
    return values


@thermal.command("min-time")
@log_options
@click.option("--sampling-periods", default="35,40,45,50", show_default=True, help="Sampling periods M (min), comma-separated.")
@click.option("--windows", default=None, help="Candidate identification times L as START:STOP[:STEP] minutes (default: every sample from 5 min to the longest period).")
@click.option("--method", type=click.Choice(METHODS), default="aukf", show_default=True)
@click.option("--preset", type=click.Choice(PRESETS), default="data", show_default=True)
@click.option("--plot", "plot_path", type=click.Path(dir_okay=False, writable=True), help="Draw RMSE against identification time to this PNG.")
@click.option("--json", "as_json", is_flag=True, help="Print one JSON object instead of a table.")
@user_errors
def min_time_command(file: str, sensors: tuple[str, ...], time_col: str | None, time_unit: str | None, sampling_periods: str, windows: str | None, method: str, preset: str, plot_path: str | None, as_json: bool) -> None:
    """Find the minimal identification time (seed 000 §2.4): RMSE against L for several sampling periods."""
    periods = _float_list(sampling_periods, "--sampling-periods")
    candidates = None
    if windows:
        parts = _float_list(windows.replace(":", ","), "--windows")
        if len(parts) not in (2, 3) or parts[1] <= parts[0]:
            msg = f"--windows: expected START:STOP[:STEP] with STOP > START; found {windows!r}"
            raise InputError(msg)
        step = parts[2] if len(parts) == 3 else 1.0
        candidates = list(np.arange(parts[0], parts[1] + step / 2, step))
    log = load_log(file, sensors, time_col, time_unit)
    with stderr.status("searching identification times…"):
        result = minimal_identification_time(log, method, preset, periods, candidates)
    if plot_path:
        from mtident.report import plot_min_time

        plot_min_time(result, plot_path)
        stderr.print(f"mtident: plot written to {plot_path}", highlight=False)
    summaries = [result.summary(i) for i in range(len(result.sensors))]
    if as_json:
        print_json(summaries[0] if len(summaries) == 1 else {"sensors": summaries, "method": method, "sampling_periods_min": periods})
        return
    table = Table(title=f"{log.source}: minimal identification time ({method}); choosing it took {result.measuring_time_min:g} min of measurement")
    table.add_column("sensor")
    table.add_column("minimal L (min)", justify="right")
    for p in result.periods_min:
        table.add_column(f"best L for M={p:g}", justify="right")
    table.add_column("periods agree", justify="center")
    for i, d in enumerate(summaries):
        table.add_row(str(d["sensor"]), _fmt(d["min_identification_time_min"], 0), *[f"{b:g}" for b in result.best_per_period_min[:, i]], "yes" if d["periods_agree"] else "[yellow]no[/]")
    Console(width=max(Console().width, 100)).print(table)
