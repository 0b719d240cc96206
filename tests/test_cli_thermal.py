"""Tests of :mod:`mtident.cli_thermal`."""

from __future__ import annotations

import json
import math
import re
import subprocess
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any

import numpy as np
import pytest
from conftest import first_order, make_log
from fuzz_logs_helpers import EXPORTS, Export, exports
from helpers import Outcome, csv_text, frozen_channel, mtident, noisy, two_mode, workbook_of_runs

import mtident.cli_logs as cli_logs
import mtident.cli_thermal as cli_thermal
from mtident.exceptions import InputError
from mtident.io.logs import OPEN_CIRCUIT_HIGH_C, OPEN_CIRCUIT_LOW_C, TemperatureLog, read_temperature_log
from mtident.thermal.reference import MachineReference, save_reference
from mtident.thermal.robust import SensorModes

# a sensor whose column does not rise (a room column taken for a machine sensor)
NO_RISE = "no warm-up to identify"


# identify's model-robust fit (the default method) takes about a second an export; the rest use lsq
ROBUST_EVERY = 40


def _misread(export: Export, time_min: np.ndarray, celsius: np.ndarray) -> str | None:
    """What is wrong with readings against the truth, or None: the rows the export holds whole (and
    the cut one only where it was read whole), each time and each reading as written."""
    n = len(time_min)
    if n not in (export.rows, export.rows + 1):
        return f"{n} rows read of {export.rows}"
    if celsius.shape != (n, export.celsius.shape[1]):
        return f"readings of shape {celsius.shape}, not {(n, export.celsius.shape[1])}"
    if not np.allclose(time_min, export.time_min[:n], rtol=0, atol=1e-6):
        k = int(np.argmax(~np.isclose(time_min, export.time_min[:n], rtol=0, atol=1e-6)))
        return f"time at row {k}: {time_min[k]:g} min, not {export.time_min[k]:g}"
    wrong = ~np.isclose(celsius, export.celsius[:n], rtol=0, atol=1e-6)
    if wrong.any():
        k, j = (int(i[0]) for i in np.nonzero(wrong))
        return f"column {j} at row {k}: {celsius[k, j]:.6g} °C, not {export.celsius[k, j]:.6g}"
    return None


def _check_log(export: Export, log: TemperatureLog, where: str) -> list[str]:
    wrong = _misread(export, log.time_min, log.temperature_C)
    if wrong is None:
        return []
    if export.doubt is not None and any(export.doubt in note for note in log.notes):
        return []  # read as written, and said to be doubtful
    return [f"{where}: misread without a word ({wrong}); notes: {list(log.notes)}"]


def _check_refusal(out: Outcome, where: str) -> list[str]:
    """A command that gives no answer must say why in one line, with exit code 1 or 2."""
    said = [line for line in out.stderr.splitlines() if line.startswith("mtident: error:")]
    if out.returncode not in (1, 2) or len(said) != 1 or "Traceback" in out.stderr + out.stdout:
        return [f"{where}: exit {out.returncode} without a one-line error: {out.stderr[-400:]!r}"]
    return []


@contextmanager
def _logs_read() -> Iterator[list[TemperatureLog]]:
    """The logs the commands read, as their fits get them."""
    read: list[TemperatureLog] = []
    original = cli_logs.load_log

    def recording(*args: Any, **kwargs: Any) -> TemperatureLog:
        log = original(*args, **kwargs)
        read.append(log)
        return log

    cli_logs.load_log = recording
    try:
        yield read
    finally:
        cli_logs.load_log = original


def check_export(export: Export, path: Path, robust: bool = False) -> tuple[list[str], bool]:
    """The problems reading ``export`` (written at ``path``) shows, and whether it was read."""
    problems: list[str] = []
    try:
        log = read_temperature_log(path)
    except InputError as exc:
        log = None
        if not (export.refuse or export.may_refuse):
            problems.append(f"read_temperature_log refused a sane export: {exc}")
    else:
        if export.refuse:
            problems.append("read_temperature_log read an export it must refuse")
        problems += _check_log(export, log, "read_temperature_log")
    read = log is not None

    table = mtident("thermal", "inspect", str(path))
    out = mtident("thermal", "inspect", str(path), "--json")
    if out.returncode != table.returncode:
        problems.append(f"inspect: exit {table.returncode} for the table, {out.returncode} for --json")
    if out.returncode == 0:
        if not read:
            problems.append("inspect read what read_temperature_log refused")
        info = json.loads(out.stdout)
        n = info["time"]["samples"]
        notes = info["notes"]
        wrong = None if n in (export.rows, export.rows + 1) else f"{n} samples of {export.rows}"
        if wrong is None and not math.isclose(info["time"]["span_min"], export.time_min[n - 1], abs_tol=1e-6):
            wrong = f"a span of {info['time']['span_min']:g} min, not {export.time_min[n - 1]:g}"
        for j, sensor in enumerate(info["sensors"] if wrong is None else []):
            truth = export.celsius[:n, j]
            for key, value in (
                ("first_C", truth[0]),
                ("last_C", truth[-1]),
                ("min_C", truth.min()),
                ("max_C", truth.max()),
            ):
                if sensor[key] is None or not math.isclose(sensor[key], value, abs_tol=1e-6):
                    wrong = f"{sensor['sensor']!r} {key} {sensor[key]}, not {value:.6g}"
        if wrong is not None and not (export.doubt is not None and any(export.doubt in note for note in notes)):
            problems.append(f"inspect --json: misread without a word ({wrong}); notes: {notes}")
    else:
        problems += _check_refusal(out, "inspect --json") + _check_refusal(table, "inspect")
        if read:
            problems.append("inspect refused what read_temperature_log read")

    method = () if robust else ("--method", "lsq")
    with _logs_read() as logs:
        out = mtident("thermal", "identify", str(path), "--json", *method)
    if out.returncode == 0:
        problems += _check_log(export, logs[0], "identify")
        answer = json.loads(out.stdout)
        doubted = export.doubt is not None and export.doubt in out.stderr
        if _misread(export, logs[0].time_min, logs[0].temperature_C) is not None and not doubted:
            problems.append(f"identify: answered from a misread log without a warning: {out.stderr[-300:]!r}")
        for summary in answer.get("sensors", [answer]):
            level = float(export.steady_C[logs[0].sensors.index(summary["sensor"])])
            lo, hi = summary["steady_state_ci95_C"]
            if not summary["model_ok"] or doubted:
                continue
            if NO_RISE in " ".join(summary["warnings"]):
                continue  # a flat column's trusted nonsense: test_a_flat_columns_absurd_answer_is_not_trusted
            # an answer trusted from readings that are the truth must be one physics allows (whether its
            # interval covers the truth is the fits' matter: test_first_order, test_robust)
            if lo is None or hi is None or lo < OPEN_CIRCUIT_LOW_C or hi > OPEN_CIRCUIT_HIGH_C:
                problems.append(
                    f"identify: {summary['sensor']!r} trusted T∞ {summary['steady_state_C']:.2f} °C [{lo}, {hi}], "
                    f"the truth {level:.2f}"
                )
    else:
        problems += _check_refusal(out, "identify")
    return problems, read


@pytest.mark.parametrize("part", range(8))
def test_logger_exports_are_read_right_or_refused_in_one_line(tmp_path, part):
    """Each eighth of the exports (the parts run on the suite's workers): read by the library, by
    inspect and by identify, the readings are the truth or a note says what is doubtful; what is
    not read is refused in one line; the exports that can be read are read."""
    problems, read, checked = [], 0, 0
    for k, export in enumerate(exports()):
        if k % 8 != part:
            continue
        path = tmp_path / f"export{k}.csv"
        path.write_bytes(export.data)
        try:
            found, was_read = check_export(export, path, robust=k % ROBUST_EVERY == part)
        except Exception as exc:  # a traceback: the export that raised it, and the exception
            raise AssertionError(f"export {k} ({export.describe()}) raised {type(exc).__name__}: {exc}") from exc
        problems += [f"export {k} ({export.describe()}): {p}" for p in found]
        read += was_read
        checked += 1
    assert not problems, "\n".join(problems)
    assert checked == EXPORTS // 8 and read >= 0.75 * checked, (read, checked)


def test_a_flat_columns_absurd_answer_is_not_trusted(write_csv):
    # a room column in 0.1 °C steps: 19.8 °C for 17 min, then 19.9 (fuzz export 80)
    rows = "".join(
        f"{m},{20 + 8 * (1 - np.exp(-m / 40)):.2f},{19.8 + 0.1 * (m >= 17) + 0.1 * (m >= 37):.1f}\n" for m in range(60)
    )
    out = mtident("thermal", "identify", str(write_csv("time_min,Spindle,Room\n" + rows)), "--json", "--method", "lsq")
    room = json.loads(out.stdout)["sensors"][1]
    lo, hi = room["steady_state_ci95_C"]
    assert not room["model_ok"] or (lo is not None and hi is not None and -60 <= lo and hi <= 400), room


@pytest.mark.slow
def test_python_dash_m_mtident_runs_end_to_end():
    """Smoke test of the entry point in a process of its own: one JSON object on stdout, exit 0.
    (The other tests call the command in-process; test_cli_watch runs `python -m mtident thermal
    watch` in processes it kills and resumes.)"""
    out = subprocess.run(
        [
            sys.executable,
            "-m",
            "mtident",
            "thermal",
            "identify",
            "@sample",
            "--sensor",
            "T1",
            "--method",
            "ukf",
            "--json",
        ],
        capture_output=True,
        text=True,
        timeout=300,
        check=False,
    )
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["sensor"] == "T1" and "Traceback" not in out.stderr


def test_help_lists_the_command_groups():
    out = mtident("--help")
    assert out.returncode == 0
    assert re.search(r"^\s+feeddrive\s", out.stdout, re.M) and re.search(r"^\s+thermal\s", out.stdout, re.M)
    assert "identify" in mtident("thermal", "--help").stdout


def test_thermal_identify_json_has_the_contract_keys(tmp_path):
    png = tmp_path / "fit.png"
    out = mtident("thermal", "identify", "@sample", "--sensor", "T3", "--window", "30", "--json", "--plot", str(png))
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert set(data) >= {
        "sensor",
        "method",
        "window_min",
        "steady_state_C",
        "steady_state_ci95_C",
        "lambda_per_min",
        "time_constant_min",
        "equilibrium_time_min",
        "rmse_C",
    }
    assert set(data) >= {"model_ok", "warnings", "assumptions", "model"}
    assert data["sensor"] == "T3" and data["method"] == "robust" and data["window_min"] == 30.0
    # 30 min of a warm-up whose slowest mode is 90 min do not exclude one of 300 min: said, not hidden
    assert data["model_ok"] is False and any("not determined yet" in w for w in data["warnings"])
    assert data["assumptions"]["max_time_constant_min"] == 300.0 and data["assumptions"]["reference"] is None
    lo, hi = data["steady_state_ci95_C"]
    assert lo < data["steady_state_C"] < hi
    assert lo <= data["measured_final_C"] <= hi  # the sample log ran to equilibrium
    assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_thermal_identify_all_sensors_json_and_table():
    out = mtident("thermal", "identify", "@sample", "--method", "lsq", "--json")
    data = json.loads(out.stdout)
    assert [d["sensor"] for d in data["sensors"]] == [f"T{i}" for i in range(1, 11)]
    table = mtident("thermal", "identify", "@sample", "--sensor", "T1,T8")
    assert table.returncode == 0 and "T8" in table.stdout and "T∞" in table.stdout
    # a name given twice is one sensor; a space after a comma is no part of the name
    spaced = mtident(
        "thermal", "identify", "@sample", "--method", "lsq", "--json", "--sensor", "T8, T1", "--sensor", "T8"
    )
    assert [d["sensor"] for d in json.loads(spaced.stdout)["sensors"]] == ["T8", "T1"]


def test_a_sensor_whose_name_holds_a_comma_can_be_asked_for(tmp_path):
    """'Temp, Spindel' (a logger's channel name) was split into 'Temp' and 'Spindel': no such column."""
    t = np.arange(0.0, 61.0)
    rows = "".join(f"{m:g};{26.7 - 8.8 * np.exp(-0.016 * m):.3f};{20 + 0.01 * m:.2f}\n".replace(".", ",") for m in t)
    log = tmp_path / "komma.csv"
    log.write_text("Zeit;Temp, Spindel;Temp, Motor\n" + rows)
    out = mtident(
        "thermal", "identify", str(log), "--sensor", "Temp, Spindel", "--method", "ukf", "--json"
    )  # the name, not the method, is tested
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["sensor"] == "Temp, Spindel"


def test_thermal_min_time_json_has_the_contract_keys(tmp_path):
    png = tmp_path / "rmse.png"
    out = mtident("thermal", "min-time", "@sample", "--sensor", "T1", "--json", "--plot", str(png))
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert set(data) >= {"min_identification_time_min", "sampling_periods_min", "rmse_C"}
    assert data["sampling_periods_min"] == [35.0, 40.0, 45.0, 50.0]
    assert set(data["rmse_C"]) == {"35", "40", "45", "50"}
    assert all(len(pair) == 2 for rows in data["rmse_C"].values() for pair in rows)
    assert data["measuring_time_needed_min"] == 50.0
    assert png.stat().st_size > 1000


def test_identify_writes_its_curves_for_a_spreadsheet(tmp_path, monkeypatch):
    import pandas as pd

    from mtident.io import read_temperature_log, sample_log_path
    from mtident.thermal import identify

    monkeypatch.chdir(tmp_path)
    out = mtident(
        "thermal", "identify", "@sample", "--sensor", "T1,T9", "--window", "30", "--method", "ukf", "--curve", "c.csv"
    )
    assert out.returncode == 0, out.stderr
    assert "curves written to c.csv (401 rows to t = 400 min)" in out.stderr
    table = pd.read_csv(tmp_path / "c.csv")
    assert list(table.columns) == [
        "time_min",
        "part",
        *[f"{s}_{what}_C" for s in ("T1", "T9") for what in ("measured", "model", "low95", "high95")],
    ]
    assert (table["part"] == "window").sum() == 31 and (table["part"] == "prediction").sum() == 370
    result = identify(read_temperature_log(sample_log_path()).select(["T1", "T9"]), 30.0, "ukf")
    np.testing.assert_allclose(table["T9_model_C"], result.curve_C[:, 1], atol=1e-6)
    np.testing.assert_allclose(
        table["T1_high95_C"] - table["T1_model_C"], result.details.quantile * result.details.curve_sd_C[:, 0], atol=2e-6
    )
    np.testing.assert_allclose(table["T1_measured_C"], result.measured_C[:, 0], atol=1e-6)


@pytest.mark.parametrize(
    ("name", "magic"), [("fit.svg", b"<?xml"), ("fit.pdf", b"%PDF"), ("fit.PNG", b"\x89PNG"), ("fit", b"\x89PNG")]
)
def test_the_plot_suffix_chooses_the_picture_format(tmp_path, monkeypatch, name, magic):
    """'fit.svg' used to be written as a PNG (the temporary file's suffix chose the format)."""
    monkeypatch.chdir(tmp_path)
    out = mtident(
        "thermal", "identify", "@sample", "--sensor", "T1", "--method", "ukf", "--plot", name
    )  # the picture, not the method, is tested
    assert out.returncode == 0, out.stderr
    assert (tmp_path / name).read_bytes().startswith(magic)
    assert sorted(p.name for p in tmp_path.iterdir()) == [name]  # no temporary file left beside it


def test_bad_csv_cell_is_reported(tmp_path):
    path = tmp_path / "bad.csv"
    path.write_text("time_min,A\n0,20\n1,20.1\n2,oops\n3,20.3\n4,20.4\n5,20.5\n6,20.6\n")
    out = mtident("thermal", "identify", str(path))
    assert out.returncode == 2 and "sensor 'A', row 4: 'oops' is not a number" in out.stderr


def test_a_dead_column_can_be_left_out_as_the_error_says(tmp_path):
    """The advice "leave this sensor out with --sensor" did not work: every column was checked first."""
    import numpy as np

    t = np.arange(0.0, 61.0)
    path = tmp_path / "dead.csv"
    # a few readings, then none: refused, with the advice
    path.write_text(
        "time_min,dead,A,room\n"
        + "".join(f"{tk:g},{'20.0' if tk < 3 else ''},{26.7 - 8.8 * np.exp(-0.016 * tk):.3f},17.9\n" for tk in t)
    )
    out = mtident(
        "thermal", "identify", str(path), "--window", "30", "--method", "ukf"
    )  # the columns, not the method, are tested
    assert out.returncode == 2 and "leave this sensor out with --sensor" in out.stderr
    # never a reading (an unplugged channel, an event channel that logged nothing): left out with a note
    path.write_text(
        "time_min,dead,A,room\n" + "".join(f"{tk:g},,{26.7 - 8.8 * np.exp(-0.016 * tk):.3f},17.9\n" for tk in t)
    )
    out = mtident("thermal", "identify", str(path), "--window", "30", "--method", "ukf", "--json")
    assert out.returncode == 0 and "left out, no readings in them: dead" in out.stderr
    assert [d["sensor"] for d in json.loads(out.stdout)["sensors"]] == ["A", "room"]
    for extra in ((), ("--ambient", "room")):
        out = mtident(
            "thermal", "identify", str(path), "--sensor", "A", "--window", "30", "--method", "ukf", "--json", *extra
        )
        assert out.returncode == 0, out.stderr
        assert json.loads(out.stdout)["sensor"] == "A"


def test_thermal_identify_with_a_room_column(tmp_path):
    import numpy as np

    t = np.arange(0.0, 121.0)
    rng = np.random.default_rng(2)
    room = 17.9 + 0.1 * np.sin(2 * np.pi * t / 240.0)
    rows = ["time_min,spindle,room"] + [
        f"{tk:g},{26.7 - 8.8 * np.exp(-0.016 * tk) + 0.02 * rng.standard_normal():.3f},{rk + 0.02 * rng.standard_normal():.3f}"
        for tk, rk in zip(t, room, strict=True)
    ]
    path = tmp_path / "room.csv"
    path.write_text("\n".join(rows) + "\n")
    out = mtident("thermal", "identify", str(path), "--ambient", "room", "--window", "60", "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert data["sensor"] == "spindle"  # the room column is the input, not a sensor
    assert "named as a room sensor" not in out.stderr
    # without --ambient the column named as the room is a sensor, and the user is told of the option
    out = mtident(
        "thermal", "identify", str(path), "--window", "60", "--method", "ukf", "--json"
    )  # the columns, not the method, are tested
    assert out.returncode == 0, out.stderr
    assert [d["sensor"] for d in json.loads(out.stdout)["sensors"]] == ["spindle", "room"]
    assert (
        "'room' is named as a room sensor and identified as a machine sensor; if it measures the room, --ambient room "
        "makes it" in out.stderr
    )
    out = mtident("thermal", "identify", str(path), "--ambient", "hall", "--window", "60")
    assert out.returncode == 2 and "no sensor column 'hall'" in out.stderr and "Traceback" not in out.stderr
    out = mtident("thermal", "identify", str(path), "--ambient", "room", "--method", "lsq")
    assert out.returncode == 2 and "needs a UKF method" in out.stderr
    out = mtident("thermal", "min-time", str(path), "--ambient", "room", "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["min_identification_time_min"] > 0


def test_a_column_named_without_its_unit_is_the_column(tmp_path):
    """A trial's `--ambient Room` was refused for a log whose column is ``Room [°C]`` ("did you mean
    'Room [°C]'?"): a name that is one column's without its unit means that column, and is said so.
    One that fits two columns, or none, is still refused."""
    t = np.arange(0.0, 120.0)
    spindle = 20.0 + 6.0 * (1.0 - np.exp(-t / 25.0))
    path = tmp_path / "log.csv"
    path.write_text(csv_text(t, {"Spindle [°C]": spindle, "Room [°C]": np.full(t.size, 20.0)}))
    out = mtident("thermal", "identify", str(path), "--ambient", "room", "--sensor", "spindle", "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["sensor"] == "Spindle [°C]"
    assert "mtident: note: --ambient 'room' is the column 'Room [°C]'" in out.stderr
    out = mtident("thermal", "watch", str(path), "--replay", "--ambient", "Room", "--wait-for", "Spindle", "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["waited_for"] == ["Spindle [°C]"]
    twice = tmp_path / "twice.csv"
    twice.write_text(csv_text(t, {"T [°C]": spindle, "T [K]": spindle + 273.15, "room": np.full(t.size, 20.0)}))
    out = mtident("thermal", "identify", str(twice), "--sensor", "T", "--ambient", "room")
    assert out.returncode == 2 and "no sensor column 'T'" in out.stderr


def test_a_room_column_that_sensor_leaves_unread_is_pointed_out(tmp_path):
    """--sensor naming the machine's sensors left a room column unread without a word (the note on a
    room column came only where it was read as a sensor): the room was an assumption unawares."""
    t = np.arange(0.0, 61.0)
    path = tmp_path / "hall.csv"
    path.write_text(
        "time_min,spindle,room temp (C)\n"
        + "".join(f"{tk:g},{26.7 - 8.8 * np.exp(-0.016 * tk):.3f},20.0\n" for tk in t)
    )
    said = (
        "mtident: note: 'room temp (C)' is named as a room sensor and not read (--sensor names the sensors read); if "
        "it measures the room, --ambient 'room temp (C)'{commands} makes it the input of each sensor's heat balance"
    )
    for command, commands in (
        (("identify", "--method", "lsq"), ""),
        (("min-time",), ""),
        (("inspect",), " (with identify, watch, learn or report)"),  # inspect takes no --ambient
    ):
        out = mtident("thermal", command[0], str(path), "--sensor", "spindle", *command[1:])
        assert out.returncode == 0, out.stderr
        assert said.format(commands=commands) in out.stderr, (command, out.stderr)
    # named as the room, or read as a sensor (the note of before), it is not said to be unread
    for extra in (("--ambient", "room temp (C)", "--method", "ukf"), ("--method", "lsq")):
        out = mtident("thermal", "identify", str(path), "--window", "40", *extra)
        assert out.returncode == 0, out.stderr
        assert "not read (--sensor" not in out.stderr


@pytest.mark.parametrize(
    "command",
    [
        ("identify",),
        ("min-time", "--sensor", "A"),
        ("inspect",),
        ("learn", "-o", "{tmp}/m.toml"),
        ("report", "-o", "{tmp}/r.html"),
        ("watch", "--replay", "--state", "{tmp}/s.json"),
    ],
)
def test_every_command_that_reads_a_log_takes_the_sheet_of_a_workbook(tmp_path, command):
    """Each command that reads a temperature log takes --sheet; a sheet the workbook lacks is an
    error naming the sheets it has."""
    book = tmp_path / "runs.xlsx"
    workbook_of_runs(book)
    args = [arg.format(tmp=tmp_path) for arg in command]
    out = mtident("thermal", args[0], str(book), *args[1:], "--sheet", "Run 3")
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert (
        f"mtident: error: {book}: no sheet 'Run 3'; the workbook's sheets: 1 'Details', 2 'Run 1', 3 'Run 2', "
        "4 'Spare' (--sheet NAME takes a sheet's name or its number, from 1)"
    ) in out.stderr


def test_identify_reads_the_sheet_named_and_says_which_it_read_where_none_is(tmp_path):
    """A workbook's first sheet with a table was read without a word, whatever sheet held the test."""
    book = tmp_path / "runs.xlsx"
    workbook_of_runs(book)
    out = mtident("thermal", "identify", str(book), "--window", "40", "--method", "lsq", "--json")
    assert out.returncode == 0, out.stderr
    answer = json.loads(out.stdout)
    assert answer["sensor"] == "A" and answer["log"] == f"{book}, sheet 'Run 1'"
    assert (
        f"mtident: note: {book}: read sheet 'Run 1' of 4 (the first that holds a table); not read: 'Details' "
        "(no table), 'Run 2' (a table too), 'Spare' (empty); --sheet NAME reads another (its name, or its number "
        "from 1)"
    ) in out.stderr
    for sheet in ("Run 2", "3"):
        out = mtident("thermal", "identify", str(book), "--sheet", sheet, "--window", "40", "--method", "lsq", "--json")
        assert out.returncode == 0, out.stderr
        answers = {d["sensor"]: d for d in json.loads(out.stdout)["sensors"]}
        assert json.loads(out.stdout)["log"] == f"{book}, sheet 'Run 2'"
        assert list(answers) == ["B", "Umgebung"]
        # a sheet named by number is said by name: pandas counts from 0, the option from 1
        said = "read sheet 'Run 2', number 3 of 4 (counted from 1)"
        assert (said in out.stderr) == (sheet == "3") and "not read:" not in out.stderr
        # B rises from 25 to 31 °C (τ = 25 min, no noise): its T∞ is the sheet's, not A's 24 °C
        assert abs(answers["B"]["steady_state_C"] - 31.0) < 0.05
        assert "'Umgebung' is named as a room sensor and identified as a machine sensor" in out.stderr
    # the log's name in titles, messages and a reference's source names the sheet of a workbook of several
    assert read_temperature_log(book, sheet="3").source == f"{book}, sheet 'Run 2'"
    out = mtident("thermal", "identify", str(book), "--sheet", "Run 2", "--sensor", "A")
    assert out.returncode == 2 and f"mtident: error: {book}, sheet 'Run 2': no sensor column 'A'" in out.stderr
    out = mtident("thermal", "inspect", str(book), "--sheet", "Run 2", "--json")
    assert out.returncode == 0, out.stderr
    info = json.loads(out.stdout)
    assert info["format"]["kind"] == "Excel workbook (the sheet --sheet names: 'Run 2')"
    assert [d["sensor"] for d in info["sensors"]] == ["B", "Umgebung"]
    csv = tmp_path / "runs.csv"
    csv.write_text("time_min,T1\n" + "".join(f"{m},{20 + m / 10}\n" for m in range(12)))
    out = mtident("thermal", "identify", str(csv), "--sheet", "2")
    assert (
        out.returncode == 2
        and (f"{csv}: --sheet 2 names a sheet of an Excel workbook, but this log is CSV text; leave it out")
        in out.stderr
    )


def test_min_time_table_gives_l_to_a_tenth_of_a_minute_for_a_fast_log(tmp_path):
    """A log sampled every 20 s has a candidate L every 20 s; the table printed 39.3333."""
    import numpy as np

    t = np.arange(0.0, 60.0 * 60 + 1, 20.0)
    y = 26.7 - 8.8 * np.exp(-0.016 * t / 60.0) + 0.02 * np.random.default_rng(0).standard_normal(len(t))
    path = tmp_path / "fast.csv"
    path.write_text("time_s,T1\n" + "".join(f"{a:g},{b:.3f}\n" for a, b in zip(t, y, strict=True)))
    out = mtident("thermal", "min-time", str(path))
    assert out.returncode == 0, out.stderr
    row = next(line for line in out.stdout.splitlines() if "T1" in line)
    cells = [c.strip() for c in row.strip("│ ").split("│")][1:-1]
    assert len(cells) == 5 and all(re.fullmatch(r"\d+(\.\d)?", c) for c in cells), row


def test_inspect_shows_how_a_logger_export_is_read(tmp_path):
    """`thermal inspect`: the header line, the rows under it, how the time is read, each sensor's
    unit and readings, and every column left out with the reason, as a summary or one JSON object."""
    path = tmp_path / "tinytag.csv"
    rows = "".join(
        f"{k + 1},2026-11-22 08:{k:02d}:00,{68 + 0.18 * k:.2f} °F,{56 + k / 100:.1f} %RH\n" for k in range(8)
    )
    path.write_text(
        ",Time,1,2\nS/N,,227659,227659\nType,,Tinytag,Tinytag\nDescription,,Spindle,Spindle\nProperty,,Temperature,Humidity\n"
        + rows,
        encoding="cp1252",
    )
    out = mtident("thermal", "inspect", str(path), "--json")
    assert out.returncode == 0, out.stderr
    info = json.loads(out.stdout)
    assert info["format"] == {
        "kind": "CSV text", "encoding": "cp1252", "delimiter": "comma", "decimal": ".", "lines_before_header": 0, "header_line": 1,
        "rows_under_header": 4, "units_from": "its cells", "units_in_cells": True,
    }  # fmt: skip
    assert info["time"] == {
        "column": "Time",
        "first_cell": "2026-11-22 08:00:00",
        "read_as": "time stamps",
        "samples": 8,
        "span_min": 7.0,
        "step_min": 1.0,
    }
    [sensor] = info["sensors"]
    assert sensor["sensor"] == "1" and sensor["unit"] == "°F" and sensor["missing"] == 0
    assert sensor["first_C"] == pytest.approx(20.0) and sensor["max_C"] == pytest.approx(20.7)
    assert (
        "left out, a row counter: the unnamed first column; the time is 'Time'" in info["notes"]
        and "left out, not temperatures by its cells: 2 (%RH)" in info["notes"]
    )
    text = mtident("thermal", "inspect", str(path)).stdout
    assert (
        "header on line 1, 4 row(s) under it before the data" in text
        and "read as time stamps" in text
        and "note: left out, a row counter" in text
    )
    seconds = tmp_path / "seconds.csv"
    seconds.write_text("t,A\n" + "".join(f"{60 * k},{20 + k / 10:.1f}\n" for k in range(8)))
    assert (
        json.loads(mtident("thermal", "inspect", str(seconds), "--time-unit", "s", "--json").stdout)["time"]["read_as"]
        == "numbers in s (--time-unit)"
    )
    assert "assumed" in json.loads(mtident("thermal", "inspect", str(seconds), "--json").stdout)["time"]["read_as"]
    begun = tmp_path / "begun.csv"  # a log just begun: no five samples needed to look at it
    begun.write_text("time,A\n0,20.5\n")
    assert json.loads(mtident("thermal", "inspect", str(begun), "--json").stdout)["time"]["samples"] == 1
    missing = mtident("thermal", "inspect", str(tmp_path / "nope.csv"))
    assert missing.returncode == 2 and "no such file" in missing.stderr and "Traceback" not in missing.stderr
    # a column named as a room sensor is pointed out, as identify and watch do
    room = mtident("thermal", "inspect", "@sample-room").stderr
    assert "'room' is named as a room sensor and read as a sensor column" in " ".join(room.split())


def test_the_command_line_says_options_where_the_library_names_its_parameters(tmp_path):
    """The library's messages name its parameters (`time_unit='d'`); the command says the option
    instead, in an error, a note and the JSON alike."""
    from mtident.cli import as_options

    assert as_options("give `time_unit='s'`; `sensors=[NAME]` reads it; a longer `window_min`") == (
        "give --time-unit s; --sensor NAME reads it; a longer --window"
    )
    assert as_options("`other` and `time_unit`") == "`other` and --time-unit"
    serial = tmp_path / "serial.csv"
    serial.write_text("Time,T1\n" + "".join(f"{46348.333333 + k / 1440:.8f},{20 + k / 100:.2f}\n" for k in range(60)))
    out = mtident("thermal", "identify", str(serial), "--method", "lsq")
    assert out.returncode == 2 and "not minutes: give --time-unit d (or --time-unit min if it is minutes)" in out.stderr
    seconds = tmp_path / "seconds.csv"
    seconds.write_text("Time,T1\n" + "".join(f"{s},{20 + s / 7200:.4f}\n" for s in range(0, 7201, 60)))
    info = json.loads(mtident("thermal", "inspect", str(seconds), "--json").stdout)
    assert any("if it is in seconds, give --time-unit s" in note for note in info["notes"])


def test_a_window_beyond_the_log_says_that_the_whole_log_was_used(tmp_path):
    t = np.arange(0.0, 61.0)
    log = tmp_path / "short.csv"
    log.write_text("time_min,T1\n" + "".join(f"{a:g},{20 + 6 * (1 - np.exp(-a / 30)):.3f}\n" for a in t))
    out = mtident("thermal", "identify", str(log), "--window", "90", "--method", "lsq")
    assert out.returncode == 0, out.stderr
    assert "the log ends at t = 60 min, before --window 90: identified from all of it" in " ".join(out.stderr.split())
    within = mtident("thermal", "identify", str(log), "--window", "45", "--method", "lsq")
    assert "the log ends" not in within.stderr


def test_identify_marks_a_measured_level_the_log_had_not_settled_to(tmp_path):
    """A new user's log, still rising 0.2 °C in its last hour, showed its last level as the
    "measured" T∞ beside the prediction, 0.21 °C short of where it settled."""
    t = np.arange(0.0, 241.0)
    for tau, settled in ((60.0, False), (20.0, True)):
        y = 30.0 - 8.0 * np.exp(-t / tau) + np.random.default_rng(7).normal(0.0, 0.01, t.size)
        log = tmp_path / f"tau{tau:g}.csv"
        log.write_text("time_min,S\n" + "".join(f"{a:g},{b:.2f}\n" for a, b in zip(t, y, strict=True)))
        data = json.loads(mtident("thermal", "identify", str(log), "--window", "60", "--json").stdout)
        assert data["measured_final_C"] is not None and data["measured_settled"] is settled
        table = mtident("thermal", "identify", str(log), "--window", "60").stdout
        assert ("* not settled by the log's end" in table) is not settled
        if not settled:  # both rules said, the second with an example at the largest time constant's pace
            said = " ".join(table.split())
            assert "its last quarter moved 0.1 °C or more, or enough that a mode as slow as 300 min would" in said
            assert "(at that pace a move of 0.05 °C in 90 min leaves 0.14 °C to come)" in said


def test_ctrl_c_inside_compiled_code_aborts_like_ctrl_c_and_other_system_errors_pass(monkeypatch):
    """A Ctrl-C that reaches Python from compiled code is the interrupted call's SystemError: it
    aborts as Ctrl-C does, without numba's traceback."""

    def interrupted(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        raise SystemError("<numba function> returned a result with an exception set") from KeyboardInterrupt()

    monkeypatch.setattr(cli_thermal, "identify", interrupted)
    out = mtident("thermal", "identify", "@sample", "--sensor", "T1", "--method", "ukf")
    assert out.returncode == 1 and "Aborted!" in out.stderr and "Traceback" not in out.stderr

    def broken(*args, **kwargs):  # noqa: ANN002, ANN003, ANN202
        raise SystemError("a fault of our own")

    monkeypatch.setattr(cli_thermal, "identify", broken)
    with pytest.raises(SystemError, match="a fault of our own"):
        mtident("thermal", "identify", "@sample", "--sensor", "T1", "--method", "ukf")


def _warm_up(path: Path, to_unit, units_row: str = "") -> Path:
    """A warm-up from 20 °C to 100 °C (τ = 30 min) over 3 h, written in another unit without one."""
    t = np.arange(0.0, 181.0)
    celsius = 20 + 80 * (1 - np.exp(-t / 30))
    path.write_text(
        "time_min,spindle\n" + units_row + "".join(f"{a:g},{to_unit(b):.4f}\n" for a, b in zip(t, celsius, strict=True))
    )
    return path


def test_the_unit_option_reads_a_log_without_units_in_fahrenheit_or_kelvin(tmp_path):
    """Issue 37: a log in °F or K that states no unit was read as °C; --unit states it, for every
    command that reads a log (212 °F and 373.15 K are 100 °C)."""
    fahrenheit = tmp_path / "f.csv"
    fahrenheit.write_text("time_min,spindle,room\n" + "".join(f"{m},{68 + 18 * m},{68 + m / 10:g}\n" for m in range(9)))
    info = json.loads(mtident("thermal", "inspect", str(fahrenheit), "--unit", "F", "--json").stdout)
    spindle, room = info["sensors"]
    assert spindle["last_C"] == pytest.approx(100.0) and spindle["first_C"] == pytest.approx(20.0)
    assert room["first_C"] == pytest.approx(20.0) and spindle["unit"] == room["unit"] == "°F (--unit)"
    assert "read in °F (--unit), converted to °C: spindle, room" in info["notes"]
    assert json.loads(mtident("thermal", "inspect", str(fahrenheit), "--json").stdout)["sensors"][0]["last_C"] == 212
    kelvin = _warm_up(tmp_path / "k.csv", lambda c: c + 273.15)
    out = mtident("thermal", "identify", str(kelvin), "--unit", "K", "--method", "lsq", "--json")
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)
    assert result["start_C"] == pytest.approx(20.0, abs=0.01) and result["steady_state_C"] == pytest.approx(
        100, abs=0.01
    )
    assert "read in K (--unit), converted to °C: spindle" in out.stderr
    for command in ("identify", "learn", "min-time", "inspect", "watch", "report"):
        assert re.search(r"--unit \[C\|F\|K\]", mtident("thermal", command, "--help").stdout), command


def test_the_unit_option_refuses_a_column_whose_own_unit_it_contradicts(tmp_path):
    stated = _warm_up(tmp_path / "stated.csv", lambda c: c, "min,°C\n")
    out = mtident("thermal", "identify", str(stated), "--unit", "F", "--method", "lsq")
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert [line for line in out.stderr.splitlines() if line.startswith("mtident: error")] == [
        f"mtident: error: {stated}: sensor 'spindle' is in °C by the units row, but --unit F says the temperatures "
        "are in °F; leave the option out to read each column in its own unit, or correct the units row"
    ]
    assert mtident("thermal", "identify", str(stated), "--unit", "C", "--method", "lsq").returncode == 0


def test_the_note_on_a_room_read_as_celsius_says_the_unit_option(tmp_path):
    path = tmp_path / "f.csv"
    path.write_text("time_min,spindle,room\n" + "".join(f"{m},{70 + m},{69 + m / 100:.2f}\n" for m in range(30)))
    notes = json.loads(mtident("thermal", "inspect", str(path), "--json").stdout)["notes"]
    assert any("far outside any workshop's range" in n and "--unit F (or --unit K)" in n for n in notes), notes


def test_the_papers_filters_interval_stays_where_a_warm_up_allows():
    """identify --method afukf at 30 min: T9's 95 % interval reached 15.68 °C, under the room
    (18.04 °C) and 3.7 °C under where T9 already was (19.35 °C), trusted."""
    import json

    out = mtident(
        "thermal", "identify", "@sample-room", "--window", "30", "--method", "afukf", "--ambient", "room", "--json"
    )
    assert out.returncode == 0
    sensors = {s["sensor"]: s for s in json.loads(out.stdout)["sensors"]}
    low, high = sensors["T9"]["steady_state_ci95_C"]
    assert 19.0 < low <= sensors["T9"]["steady_state_C"] <= high
    assert "not below its latest readings" in sensors["T9"]["assumptions"]["model"]


def test_identify_min_time_and_learn_turn_their_options_into_one_frozen_request(tmp_path):
    import dataclasses

    from mtident.cli_learn import learn_command, learn_request
    from mtident.cli_thermal import identify_command, identify_request, min_time_command, min_time_request

    args = ["@sample", "--sensor", "T1", "--room-wander", "0.1", "--max-time-constant", "200", "--json"]
    request = identify_request(identify_command.make_context("identify", args).params)
    assert request.log.file == "@sample" and request.log.sensors == ("T1",) and request.as_json
    assert (request.robust.room_wander_C_per_h, request.robust.max_time_constant_min) == (0.1, 200.0)
    with pytest.raises(dataclasses.FrozenInstanceError):
        request.method = "lsq"  # type: ignore[misc]
    timed = min_time_request(min_time_command.make_context("min-time", ["@sample", "--windows", "10:20:5"]).params)
    assert timed.windows_min == (10.0, 15.0, 20.0) and timed.periods_min == (35.0, 40.0, 45.0, 50.0)
    out = str(tmp_path / "m.toml")
    learnt = learn_request(learn_command.make_context("learn", ["@sample", "-o", out, "--machine", "M1"]).params)
    assert (learnt.output_path, learnt.machine, learnt.serial) == (out, "M1", "")


def test_a_sensor_the_reference_does_not_know_is_said_in_identify_and_watch(tmp_path):
    """A logger's export named the column 'Spindle T1' where the reference run had 'T1': the answer
    went on without the reference, said only in its assumptions. Where the reference knows none
    of the log's sensors, it is refused (a newcomer gave another machine's reference and got only
    a warning)."""
    from mtident.thermal.monitor import MonitorSettings, monitor_step, new_state
    from mtident.thermal.robust_identify import identify_robust
    from mtident.thermal.session import WatchSession

    t = np.arange(0.0, 61.0)
    y = np.round(two_mode(t) + np.random.default_rng(3).normal(0.0, 0.01, t.size), 2)
    modes = {"T1": SensorModes((60.0,), (0.1,)), "T2": SensorModes((60.0,), (0.1,))}
    reference = MachineReference("run.csv", "2026-11-25", 300.0, "not measured", modes)
    said = "the reference (run.csv) has no modes for 'Spindle T1': it is answered without it (the reference knows 'T1'"
    result = identify_robust(make_log(t, {"Spindle T1": y, "T2": y}), 60.0, reference=reference)
    assert any(note.startswith(said) for note in result.notes)
    assert not any(
        "no modes" in note for note in identify_robust(make_log(t, {"T1": y}), 60.0, reference=reference).notes
    )
    log = tmp_path / "log.csv"
    log.write_text("time_min,Spindle T1,T2\n" + "".join(f"{a:g},{b:.2f},{b:.2f}\n" for a, b in zip(t, y, strict=True)))
    events = WatchSession(log, MonitorSettings(reference=reference), persist=False).poll()
    assert [e.kind for e in events if e.text.startswith(said)] == ["warning"]
    refused = (
        "the reference (learnt from run.csv) has modes for none of this log's sensors ('Spindle T1'); it knows 'T1', "
        "'T2'"
    )
    with pytest.raises(InputError, match=re.escape(refused)):
        identify_robust(make_log(t, {"Spindle T1": y}), 60.0, reference=reference)
    alone = tmp_path / "alone.csv"
    alone.write_text("time_min,Spindle T1\n" + "".join(f"{a:g},{b:.2f}\n" for a, b in zip(t, y, strict=True)))
    with pytest.raises(InputError, match=re.escape(refused)):
        WatchSession(alone, MonitorSettings(reference=reference), persist=False).poll()
    with pytest.raises(InputError, match=re.escape(refused)):
        monitor_step(new_state(["Spindle T1"]), t, y[:, None], None, MonitorSettings(reference=reference))
    save_reference(reference, tmp_path / "machine.toml")
    out = mtident("thermal", "identify", str(alone), "--window", "60", "--reference", str(tmp_path / "machine.toml"))
    assert out.returncode == 2 and "has modes for none of this log's sensors" in out.stderr


def test_identify_says_each_sensors_reference(tmp_path):
    """The table's assumptions gave the first sensor's reference as if it were every sensor's."""
    t = np.arange(0.0, 61.0)
    rng = np.random.default_rng(4)
    columns = {name: np.round(two_mode(t) + rng.normal(0.0, 0.01, t.size), 2) for name in ("A", "B")}
    log = tmp_path / "log.csv"
    log.write_text(
        "time_min,A,B\n" + "".join(f"{a:g},{b:.2f},{c:.2f}\n" for a, b, c in zip(t, *columns.values(), strict=True))
    )
    modes = {"A": SensorModes((60.0,), (0.1,)), "B": SensorModes((45.0, 6.0), (0.1, 0.1))}
    save_reference(MachineReference("run.csv", "2026-11-25", 300.0, "not measured", modes), tmp_path / "m.toml")
    out = mtident("thermal", "identify", str(log), "--window", "60", "--reference", str(tmp_path / "m.toml"))
    assert out.returncode == 0, out.stderr
    text = " ".join(out.stdout.split())
    # the run said once, each sensor's modes on a line of their own (a new user read ten long lines)
    assert "reference: run.csv (learnt 2026-11-25) A: τ 60 min ±10%" in text
    assert "B: τ 45 min ±10%, 6 min ±10%" in text and "reference for" not in text


def test_sensors_that_take_the_same_modes_from_one_run_share_a_line():
    from mtident.cli_thermal import reference_lines

    said = [("T1", "run (2026-11-24): τ 88 min ±10%"), ("T2", "run (2026-11-24): τ 88 min ±10%")]
    assert reference_lines([*said, ("T3", "run (2026-11-24): τ 95 min ±10%")]) == [
        "  reference: run (2026-11-24)",
        "    T1, T2: τ 88 min ±10%",
        "    T3: τ 95 min ±10%",
    ]
    # the machine model's words once (a newcomer read one 60-word sentence six times)
    model = "; and the machine model: every sensor fitted together, its 3 shared modes"
    held = [(name, text + model) for name, text in said] + [("T3", "run (2026-11-24): τ 95 min ±10%")]
    assert reference_lines(held) == [
        "  reference: run (2026-11-24)",
        "    T1, T2: τ 88 min ±10% (and the machine model)",
        "    T3: τ 95 min ±10%",
        "    and the machine model, for T1, T2: every sensor fitted together, its 3 shared modes",
    ]
    assert reference_lines(held[:2])[-1].startswith("    and the machine model, for every sensor above: every")
    other_run = [*said, ("T3", "run.csv: no modes for this sensor")]
    assert reference_lines(other_run) == [f"  reference for {name}: {text}" for name, text in other_run]


def test_inspect_says_that_watch_reads_a_log_it_refuses_for_a_bad_row(tmp_path):
    """`inspect`, the check before trusting watch with a log, refused a cell that is no reading
    (an 'ERR' then, a marker now) without saying that watch reads the same log (skipping the
    reading): a user took it for unreadable."""
    path = tmp_path / "err.csv"
    path.write_text("time_min,T1\n" + "".join(f"{m},{20 + m / 10:.2f}\n" if m != 5 else "5,CH1?\n" for m in range(20)))
    out = mtident("thermal", "inspect", str(path))
    assert out.returncode == 2
    assert "row 7: 'CH1?' is not a number (identify, learn and report refuse the log too; watch" in out.stderr
    missing = mtident("thermal", "inspect", str(tmp_path / "none.csv"))
    assert missing.returncode == 2 and "reads on" not in missing.stderr


def test_identify_and_watch_say_a_room_column_that_warms_like_a_machine_sensor(tmp_path):
    """--ambient named a sensor on the machine: every sensor's warm-up was read as the room's."""
    t = np.arange(0.0, 200.0)
    columns = {name: noisy(first_order(t, steady=s), k) for k, (name, s) in enumerate((("A", 26.7), ("B", 24.0)))}
    columns["room"] = noisy(20.0 + 5.0 * (1.0 - np.exp(-t / 30.0)), 9)
    log = tmp_path / "log.csv"
    log.write_text(csv_text(t, columns))
    code, _, err = mtident("thermal", "identify", str(log), "--window", "120", "--ambient", "room")
    assert (
        code == 0
        and "warning: the room sensor 'room' warmed 4." in err
        and "up by more than 3 °C by t = " in err
        and "--ambient" in err
    )
    code, _, err = mtident("thermal", "watch", str(log), "--replay", "--ambient", "room")
    assert code == 0 and err.count("the room sensor 'room' warmed") == 1


def test_a_sensor_whose_channel_froze_for_half_an_hour_is_said_and_fitted_without_the_repeats(tmp_path):
    """A new user's T2 froze from 80 to 110 min: identify called it a misfit, T∞ 26.17 [25.91,
    37.70] for a truth of 26.00. The repeats are left out with a warning, once in a watch."""
    t = np.arange(0.0, 200.0)
    rng = np.random.default_rng(3)
    columns = frozen_channel(t, rng)
    log = tmp_path / "log.csv"
    log.write_text(csv_text(t, columns))
    code, out, err = mtident("thermal", "identify", str(log), "--window", "200", "--json")
    assert code == 0 and "warning: sensor 'T2': its readings froze at one value (t = 81 to 110 min)" in err
    t2 = next(s for s in json.loads(out)["sensors"] if s["sensor"] == "T2")
    assert t2["model_ok"] and abs(t2["steady_state_C"] - 26.0) < 0.05
    code, _, err = mtident("thermal", "watch", str(log), "--replay")
    assert code == 0 and err.count("T2: its readings froze at one value (t = 81 to 110 min)") == 1


def test_identify_of_one_sensor_fits_the_machine_model_with_the_others(tmp_path):
    """`--sensor` picks what is reported; the reference's machine model still fits the log's other
    sensors it knows, says so, and gives the sensor the answer it gets beside them."""
    from helpers import SENSORS, _noisy_chain

    from mtident.thermal.reference_learning import learn_reference

    t, y = _noisy_chain((0.6, 0.4), 1.0, np.zeros(3), 1500.0, seed=6)
    reference, _ = learn_reference(TemperatureLog(t, SENSORS, y, (), "ref.csv"))
    save_reference(reference, tmp_path / "m.toml")
    t, y = _noisy_chain((0.5, 0.5), 0.8, np.zeros(3), 400.0, seed=7)
    (tmp_path / "test.csv").write_text(csv_text(t, dict(zip(SENSORS, y.T, strict=True))))
    args = (
        "thermal",
        "identify",
        str(tmp_path / "test.csv"),
        "--window",
        "60",
        "--reference",
        str(tmp_path / "m.toml"),
    )
    every = json.loads(mtident(*args, "--json").stdout)["sensors"]
    alone = mtident(*args, "--sensor", SENSORS[1], "--json")
    assert alone.returncode == 0, alone.stderr
    assert f"the machine model also fits {SENSORS[0]}, {SENSORS[2]}, {SENSORS[3]} (not asked for" in alone.stderr
    answer = json.loads(alone.stdout)
    assert answer["sensor"] == SENSORS[1]
    # the same fit, the log's columns in another order
    assert answer["steady_state_C"] == pytest.approx(every[1]["steady_state_C"], abs=1e-6)
    assert answer["steady_state_ci95_C"] == pytest.approx(every[1]["steady_state_ci95_C"], abs=1e-6)


def test_heat_enters_at_a_sensor_closes_the_papers_curve_without_a_reference(write_csv):
    """The papers' kind of curve (τ 59 min, 10 °C, σ 0.01 °C) identified at its t95 without a
    reference: stated as where the heat enters, its 95 % interval is within the tolerance of the
    truth (30 °C) and the answer says what it assumed; a name the log does not have is refused."""
    rng = np.random.default_rng(5)
    rows = "".join(
        f"{m},{20 + 10 * (1 - np.exp(-m / 59)) + 0.01 * rng.standard_normal():.2f},20.00\n" for m in range(181)
    )
    path = str(write_csv("time_min,Spindle [°C],Room [°C]\n" + rows))
    out = mtident("thermal", "identify", path, "--window", "180", "--ambient", "Room", "--heat-enters-at", "Spindle")
    assert out.returncode == 0, out.stderr
    assert "where the heat enters (Spindle [°C], as stated), every mode of a warm-up fitted" in out.stdout
    answer = json.loads(
        mtident(
            "thermal", "identify", path, "--window", "180", "--ambient", "Room", "--heat-enters-at", "Spindle", "--json"
        ).stdout
    )
    lo, hi = answer["steady_state_ci95_C"]
    assert "where the heat enters (Spindle [°C], as stated)" in answer["assumptions"]["model"]
    assert lo <= 30.0 <= hi and hi - lo < 0.2
    refused = mtident("thermal", "identify", path, "--ambient", "Room", "--heat-enters-at", "bearing")
    assert refused.returncode != 0
    assert "the heat cannot be said to enter at 'bearing': not among the log's sensors (Spindle [°C])" in refused.stderr


def test_names_with_brackets_are_printed_as_written(tmp_path):
    """A new user's columns "Zeit [h]", "T1 [degC]" and "spindle [front]": inspect printed "Zeit ", "T1"
    and "spindle" (rich took the brackets for markup), and a user who copied the name shown got "no
    sensor column 'spindle'"; "Spindle speed (rpm)" was said as "Spindle speed (rpm) (rpm)"."""
    log = tmp_path / "br.csv"
    rows = "".join(f"{m / 10:g},{20 + m / 10:.2f},{20 + m / 8:.2f},8000\n" for m in range(8))
    log.write_text("Zeit [h],T1 [degC],spindle [front],Spindle speed (rpm)\n" + rows)
    code, out, err = mtident("thermal", "inspect", str(log))
    assert code == 0 and "'Zeit [h]'" in out + err and "T1 [degC]" in out, out + err
    assert "spindle" in out and "[front]" in out and "Spindle speed (rpm) (rpm)" not in out + err
