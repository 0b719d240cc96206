"""Tests of :mod:`mtident.cli_watch`."""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np
import pandas as pd
import pytest
from conftest import first_order, wait_until
from helpers import (
    T,
    _get,
    _log,
    csv_text,
    mtident,
    noisy,
    one_mode_reference,
    spindle_and_column,
    three_mode_housing,
    workbook_of_runs,
)

from mtident.cli_watch_answer import _print_hindsight, _status_words
from mtident.persist import load_dataclass
from mtident.thermal.hindsight import Hindsight
from mtident.thermal.monitor import new_state
from mtident.thermal.reference import save_reference
from mtident.thermal.session import (
    SavedWatch,
    WatchSession,
)


def _printed_hindsight(hindsight: Hindsight, capsys: pytest.CaptureFixture[str]) -> str:
    """What the hindsight check prints, its whitespace folded."""
    _print_hindsight(hindsight)
    return " ".join(capsys.readouterr().out.split())


def test_a_replayed_workbooks_warnings_name_the_workbook(tmp_path):
    """A workbook is replayed as the CSV it holds, written to a temporary folder: its warnings named
    that copy (/tmp/mtident-znqtcjd6/wb2.csv), a file the user never made and cannot open."""
    import numpy as np
    import pandas as pd

    t = np.arange(0.0, 160.0)
    book = tmp_path / "warmup.xlsx"
    pd.DataFrame({"t": 60.0 * t, "Spindle": 26.7 - 8.8 * np.exp(-0.04 * t)}).to_excel(book, index=False)
    out = mtident("thermal", "watch", str(book), "--replay", "--state", str(tmp_path / "state.json"), "--json")
    said = f"{book}: time column 't' is read as minutes"
    assert said in out.stderr and "mtident-" not in out.stderr
    assert any(warning.startswith(said) for warning in json.loads(out.stdout)["log_warnings"])


def test_watch_replays_a_workbook(tmp_path):
    """A workbook is no live log, but --replay runs it as the CSV it holds (it was refused)."""
    import numpy as np
    import pandas as pd

    t = np.arange(0.0, 160.0)
    book = tmp_path / "warmup.xlsx"
    pd.DataFrame(
        {
            "Time": pd.date_range("2026-11-22 08:00", periods=len(t), freq="1min"),
            "Spindle (°C)": 26.7 - 8.8 * np.exp(-0.04 * t),
        }
    ).to_excel(book, index=False)
    out = mtident(
        "thermal",
        "watch",
        str(book),
        "--replay",
        "--room-wander",
        "0",
        "--state",
        str(tmp_path / "state.json"),
        "--json",
    )
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)
    assert result["decision"] == "stop" and abs(result["steady_state_C"] - 26.7) < 0.05
    # resumed, the workbook is copied again, to a new file: the same log, not "truncated or replaced"
    again = mtident(
        "thermal", "watch", str(book), "--replay", "--resume", "--room-wander", "0", "--state",
        str(tmp_path / "state.json"), "--json",
    )  # fmt: skip
    assert again.returncode == 0 and "replaced" not in again.stderr, again.stderr
    assert json.loads(again.stdout).get("log_warnings") == result.get("log_warnings")
    for extra in ((), ("--ambient", "Time")):  # with --ambient the header was read first, as garbage
        live = mtident("thermal", "watch", str(book), "--timeout", "1", "--state", str(tmp_path / "live.json"), *extra)
        assert (
            live.returncode == 2
            and "an Excel workbook is not written row by row" in live.stderr
            and "Traceback" not in live.stderr
        )


def test_a_replayed_workbook_of_several_sheets_says_the_sheet_it_read_and_replays_the_one_named(tmp_path):
    """watch --replay read a workbook's first sheet with a table without a word; --sheet picks
    another, and a live watch, which follows CSV text, refuses it."""
    book = tmp_path / "runs.xlsx"
    workbook_of_runs(book, minutes=120.0)
    out = mtident(
        "thermal", "watch", str(book), "--replay", "--room-wander", "0", "--state", str(tmp_path / "a.json"), "--json"
    )
    assert out.returncode == 0, out.stderr
    said = (
        f"{book}: read sheet 'Run 1' of 4 (the first that holds a table); not read: 'Details' (no table), 'Run 2' "
        "(a table too), 'Spare' (empty); --sheet NAME reads another (its name, or its number from 1)"
    )
    assert f"mtident: warning: {said}" in out.stderr
    result = json.loads(out.stdout)
    assert said in result["log_warnings"] and [d["sensor"] for d in result["sensors"]] == ["A"]
    out = mtident(
        "thermal",
        "watch",
        str(book),
        "--replay",
        "--sheet",
        "Run 2",
        "--sensor",
        "B",
        "--room-wander",
        "0",
        "--state",
        str(tmp_path / "b.json"),
        "--json",
    )
    assert out.returncode == 0, out.stderr
    result = json.loads(out.stdout)
    assert [d["sensor"] for d in result["sensors"]] == ["B"] and "read sheet" not in out.stderr
    assert not any("read sheet" in w for w in result.get("log_warnings") or [])
    # B settles at 31 °C, A at 24 °C: the stop's T∞ is the sheet's
    assert result["decision"] == "stop" and abs(result["steady_state_C"] - 31.0) < 0.2
    # the room column that --sensor left unread is pointed out, as identify does
    assert "'Umgebung' is named as a room sensor and not read (--sensor names the sensors read)" in out.stderr
    live = mtident(
        "thermal", "watch", str(book), "--sheet", "Run 2", "--timeout", "1", "--state", str(tmp_path / "c.json")
    )
    assert (
        live.returncode == 2
        and (
            "--sheet Run 2: a sheet of an Excel workbook is replayed (--replay); a live log is the CSV text a logger "
            "writes, which has no sheets"
        )
        in live.stderr
    )
    # without --state, each sheet keeps a state file of its own beside the workbook
    for sheet in ("Run 1", "Run 2"):
        out = mtident("thermal", "watch", str(book), "--replay", "--sheet", sheet, "--room-wander", "0")
        assert out.returncode == 0, out.stderr
    assert {p.name for p in tmp_path.glob("*.watch-state.npz")} == {
        "runs.xlsx.Run_1.watch-state.npz",
        "runs.xlsx.Run_2.watch-state.npz",
    }


def test_watch_that_cannot_stop_says_why_and_the_ways_on(tmp_path):
    t = np.arange(0.0, 120.5, 0.5)
    log = tmp_path / "housing.csv"
    log.write_text(csv_text(t, {"housing": noisy(three_mode_housing(t), 15)}))
    code, out, err = mtident("thermal", "watch", str(log), "--replay")
    assert code == 0, err
    text = " ".join(out.split())
    # a replayed log is whole: its end is said, not a running test to keep on
    assert "Not yet: the log ends at t = 120 min, before the test may stop." in text and "still fits" in text
    assert "Ways on: continue the test, or give a reference run of this machine" in text
    assert (
        "Assumes: a sum of up to four exponential modes (six where the readings use all four), of a warm-up that "
        "does not overshoot: a rising sensor's T∞ not below its latest readings, less four times their noise and "
        "any fall of a logged room, time constants up to 300 min" in text
    )
    # the ends named in words are the interval's own (widened for the room's wander alike)
    code, out, err = mtident("thermal", "watch", str(log), "--replay", "--room-wander", "0.5")
    assert code == 0, err
    text = " ".join(out.split())
    said = re.search(
        r"interval (-?[\d.]+) to (-?[\d.]+) °C, reaching beyond .*?low end (-?[\d.]+) °C.*?high end (-?[\d.]+) °C",
        text,
    )
    assert said and said.group(1) == said.group(3) and said.group(2) == said.group(4), text


def test_watch_refuses_the_options_of_a_week_ago_by_name(tmp_path):
    log = tmp_path / "run.csv"
    log.write_text(csv_text(T[:20], {"S": noisy(first_order(T[:20]), 16)}))
    for old in ("--hold", "--bin"):
        code, _, err = mtident("thermal", "watch", str(log), "--replay", old, "12")
        assert code == 2 and f"No such option '{old}'" in err, err


def test_watch_refuses_a_missing_reference_and_a_bad_tolerance(tmp_path):
    log = tmp_path / "run.csv"
    log.write_text(csv_text(T[:20], {"S": noisy(first_order(T[:20]), 17)}))
    code, _, err = mtident("thermal", "watch", str(log), "--replay", "--reference", str(tmp_path / "none.toml"))
    assert code == 2 and "no such file (learn one with `mtident thermal learn" in err
    code, _, err = mtident("thermal", "watch", str(log), "--replay", "--tolerance", "nan")
    assert code == 2 and "--tolerance" in err
    code, _, err = mtident("thermal", "watch", str(log), "--replay", "--free-fast-modes", "3")
    assert code == 2 and "--free-fast-modes" in err and "0<=x<=2" in err


@pytest.mark.slow
def test_watch_killed_mid_run_resumes_to_the_same_decision(tmp_path):
    """SIGKILL while following a live log; the logger carries on; the same command resumes."""
    from mtident.thermal.reference import save_reference

    save_reference(one_mode_reference("A"), tmp_path / "machine.toml")
    full = tmp_path / "full.csv"
    full.write_text(csv_text(T[:101], {"A": noisy(first_order(T[:101]), 18)}))
    fast = ("--reference", str(tmp_path / "machine.toml"), "--free-fast-modes", "0")  # stops at about 70 min
    code, out, err = mtident("thermal", "watch", str(full), "--replay", "--json", *fast)
    assert code == 0, err
    reference = json.loads(out)
    assert reference["decision"] == "stop"
    reference.pop("hindsight", None)

    live = tmp_path / "live.csv"
    lines = full.read_text().splitlines(keepends=True)
    live.write_text("".join(lines[:20]))
    state = tmp_path / "live-state.npz"
    cmd = [
        sys.executable,
        "-m",
        "mtident",
        "thermal",
        "watch",
        str(live),
        "--json",
        "--state",
        str(state),
        "--poll",
        "0.05",
        "--timeout",
        "20",
        *fast,
    ]
    proc = subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        wait_until(state.is_file, "the watch's first state file", 60)
        with open(live, "a") as out_file:
            out_file.write("".join(lines[20:40]))
        # killed once it has saved some of the new rows (the state file is replaced whole)
        wait_until(
            lambda: load_dataclass(state, SavedWatch).monitor.readings.latest_min >= 20, "the new rows saved", 60
        )
    finally:
        proc.send_signal(signal.SIGKILL)
        proc.wait()
    saved = load_dataclass(state, SavedWatch)
    assert 10 <= saved.monitor.readings.latest_min < 40
    live.write_text("".join(lines))  # the logger carries on while the monitor is down
    out = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, timeout=120, check=False)
    assert out.returncode == 0, out.stderr
    assert "resuming from" in out.stderr
    assert json.loads(out.stdout) == reference


def test_ctrl_c_inside_compiled_code_is_an_interruption_not_a_traceback(tmp_path, monkeypatch):
    """Ctrl-C that lands while a compiled kernel runs reaches Python as that call's SystemError,
    the KeyboardInterrupt chained to it: a newcomer's Ctrl-C 8 s into a replay printed numba's
    traceback and exit code 1. Any other SystemError is still raised."""
    log = tmp_path / "live.csv"
    log.write_text(csv_text(T[:30], {"A": noisy(first_order(T[:30]), 19)}))
    polls = []

    def poll(session, redraw=None, cancel=None):  # noqa: ANN001, ANN202
        polls.append(session)
        if len(polls) == 1:
            return original(session, redraw, cancel)
        raise SystemError("<numba function> returned a result with an exception set") from KeyboardInterrupt()

    original = WatchSession.poll
    monkeypatch.setattr(WatchSession, "poll", poll)
    code, out, err = mtident("thermal", "watch", str(log), "--json", "--poll", "0.05", "--timeout", "5")
    assert code == 130 and "interrupted (Ctrl-C) at t = 29 min" in err
    assert json.loads(out)["last_time_min"] == 29.0

    def broken(session, redraw=None, cancel=None):  # noqa: ANN001, ANN202
        raise SystemError("a fault of our own")

    monkeypatch.setattr(WatchSession, "poll", broken)
    with pytest.raises(SystemError, match="a fault of our own"):
        mtident("thermal", "watch", str(log), "--replay")


def test_a_replay_interrupted_says_that_resuming_it_takes_resume(tmp_path, monkeypatch):
    """Ctrl-C in a replay said "the same command resumes from there"; the same command started
    afresh and overwrote the state. A replay resumes with --resume, and says so."""
    log = tmp_path / "done.csv"
    log.write_text(csv_text(T[:30], {"A": noisy(first_order(T[:30]), 19)}))
    original = WatchSession.poll

    def poll(session, redraw=None, cancel=None):  # noqa: ANN001, ANN202
        original(session, redraw, cancel)
        raise KeyboardInterrupt

    monkeypatch.setattr(WatchSession, "poll", poll)
    code, out, err = mtident("thermal", "watch", str(log), "--replay")
    assert code == 130 and "interrupted (Ctrl-C) at t = 29 min" in err
    assert "the same command with --resume resumes from there" in err
    # the replay's log does not end where it was interrupted
    assert "where the replay was interrupted (--resume continues it)" in out and "the log ends at" not in out


def test_watch_waits_for_a_log_the_logger_has_not_created_yet(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    code, _, err = mtident("thermal", "watch", "later.csv", "--poll", "0.05", "--timeout", "0.3")
    assert code == 2
    assert (
        "waiting for later.csv to appear" in err
        and "later.csv: no such file (not created within the --timeout of 0.3 s)" in err
    )


def test_watch_says_it_is_waiting_for_rows_of_a_log_that_does_not_grow(tmp_path, monkeypatch):
    """A newcomer gave a finished log without --replay, and the watch waited in silence."""
    t = np.arange(0.0, 20.0)
    log = tmp_path / "done.csv"
    log.write_text("time_min,S\n" + "".join(f"{a:g},{20 + a / 10:.2f}\n" for a in t))
    monkeypatch.setattr("mtident.thermal.session.WAITING_HINT_S", 0.1)
    code, _, err = mtident(
        "thermal", "watch", str(log), "--poll", "0.05", "--timeout", "0.5", "--state", str(tmp_path / "s")
    )
    said = " ".join(err.split())
    assert code == 0 and "waiting for new rows: none for 0.1 s (a finished log is replayed with --replay" in said
    assert said.count("waiting for new rows") == 1
    assert "no new row for 0.5 s; the watch ends here, before the test may stop" in said


def test_exit_code_says_a_watch_that_ended_before_the_test_may_stop(tmp_path):
    """A script ran `watch --timeout 600 && next-step`: the watch gave up on a stalled logger and
    exited 0, and the next step ran on an undecided test. With --exit-code it exits 3 there (a
    timeout, or a replay that ends undecided), and 0 where the test may stop."""
    t = np.arange(0.0, 20.0)
    log = tmp_path / "stalled.csv"
    log.write_text("time_min,S\n" + "".join(f"{a:g},{20 + a / 10:.2f}\n" for a in t))
    state = str(tmp_path / "s")
    code, _, err = mtident("thermal", "watch", str(log), "--poll", "0.05", "--timeout", "0.3", "--state", state)
    assert code == 0, err
    code, _, err = mtident(
        "thermal", "watch", str(log), "--poll", "0.05", "--timeout", "0.3", "--state", state, "--exit-code"
    )
    assert code == 3 and "before the test may stop" in err
    code, _, _ = mtident("thermal", "watch", str(log), "--replay", "--state", state, "--exit-code")
    assert code == 3
    t = np.arange(0.0, 400.0)
    log.write_text(csv_text(t, {"S": noisy(30.0 - 10.0 * np.exp(-t / 20.0), 3)}))
    code, out, err = mtident("thermal", "watch", str(log), "--replay", "--state", state, "--exit-code")
    assert code == 0 and "may stop" in out, err


def test_the_hindsight_table_adds_the_rooms_move_to_the_column_it_compares(capsys):
    hindsight = Hindsight(
        ("T1",),
        233.0,
        400.0,
        np.array([30.50]),
        np.array([30.40]),
        np.array([258.0]),
        0.05,
        0.2,
        settle_time_min=np.array([251.0]),
    )
    text = _printed_hindsight(hindsight, capsys)
    assert (
        "the room moved +0.05 °C from the stop to the end, but each sensor follows the room late, through its modes, "
        "and still follows its moves before the stop: +0.05 °C added to T∞ at the stop, to where the room, as the "
        "sensor follows it, stands at the log's end" in text
    )
    assert "T∞ at stop, room followed (°C)" in text
    # 30.50 + 0.05 shown beside 30.40: the difference of the two columns, 0.15
    assert re.search(r"│ T1 +│ +30\.55 │ +30\.40 │ +0\.15 │ +251 │", text), text
    assert "stayed within ±0.2 °C of where they settled from t = 251 min: the stop saved 18 min" in text


def test_the_hindsight_table_says_a_sensors_late_following_of_the_room_though_the_room_is_back(capsys):
    """A newcomer's room swung and was back at its level by the log's end: the room's move was 0.00,
    so the column was called "T∞ at stop" while it showed T∞ plus each sensor's late following of
    the room (48.93 beside a T∞ of 48.95)."""
    hindsight = Hindsight(
        ("T1",), 435.0, 480.0, np.array([48.95]), np.array([np.nan]), np.array([np.nan]), 0.0, 0.2, np.array([-0.02])
    )
    text = _printed_hindsight(hindsight, capsys)
    assert "T∞ at stop, room followed (°C)" in text and "-0.02 °C added to T∞ at the stop" in text
    assert re.search(r"│ T1 +│ +48\.93 │", text), text


def test_the_hindsight_check_says_why_t_settle_is_unknown_where_the_readings_levelled_in_a_moving_room(capsys):
    """A newcomer's daily room: every sensor's readings levelled off (a settled level, within the
    tolerance of T∞), but their rise above the room had not, so no settle time; the check said
    "every sensor that settled (2)" and then "the log ends before the readings ... settled"."""
    nan = np.nan
    hindsight = Hindsight(
        ("S1", "S2"),
        470.0,
        600.0,
        np.array([26.69, 24.01]),
        np.array([26.69, 23.99]),
        np.array([211.0, 261.5]),
        0.063,
        0.2,
        sensor_shift_C=np.array([0.059, 0.064]),
        settle_time_min=np.array([nan, nan]),
    )
    text = _printed_hindsight(hindsight, capsys)
    assert "the log ends before" not in text
    assert (
        "the readings of S1, S2 levelled off by the log's end, but their rise above the room, as each follows it, "
        "was still moving: when they settled within the tolerance, and so the time the stop saved, is not known"
    ) in text


def test_the_hindsight_check_does_not_say_no_time_was_saved_when_a_sensor_did_not_settle(capsys):
    """A newcomer's three sensors: the one that settled reached 95 % at 183 min, the test stopped
    at 270 and the others had not settled by the log's end; the check said "the rule saved no
    time", though their 95 % times lay beyond the log."""
    nan = np.nan
    hindsight = Hindsight(
        ("front", "rear"), 270.0, 480.0, np.array([32.5, 27.4]), np.array([nan, 27.38]), np.array([nan, 183.0]), 0, 0.2
    )
    text = _printed_hindsight(hindsight, capsys)
    assert "saved no time" not in text
    assert (
        "the log ends before the readings of every sensor the test waits for settled within the tolerance, "
        "so the time it saved is not known" in text
    )
    assert "not settled by the log's end: front" in text
    settled = Hindsight(
        ("rear",),
        270.0,
        480.0,
        np.array([27.4]),
        np.array([27.38]),
        np.array([183.0]),
        0,
        0.2,
        settle_time_min=np.array([240.0]),
    )
    assert "from t = 240 min, 30 min before the stop: the rule saved no time" in _printed_hindsight(settled, capsys)


def test_watch_says_when_no_expected_stop_was_found(tmp_path):
    """A newcomer's unfinished run showed 'Expected stop: t ≈ … min' once and, on another log,
    nothing at all: where no stop is found on the best models' courses, it now says so, naming the
    sensor that has none (another newcomer saw per-sensor expected stops in the JSON beside "none
    found")."""
    t = np.arange(0.0, 30.0, 0.5)
    log = tmp_path / "early.csv"
    log.write_text(csv_text(t, {"S": noisy(20.0 + 8.0 * (1.0 - np.exp(-t / 60.0)), 5)}))
    code, out, err = mtident("thermal", "watch", str(log), "--replay", "--state", str(tmp_path / "s.npz"))
    assert code == 0 and "Not yet" in out
    # and where it left its state (a newcomer found the file beside the log unannounced)
    assert f"the state is in {tmp_path / 's.npz'}; --resume continues from there" in " ".join(err.split()), err
    text = " ".join(out.split())
    assert "Expected stop: none found; S (undetermined) has none on the best model's course" in text, text
    assert "Expected stop: t ≈" not in out


def test_the_other_sensors_expected_stops_read_as_one_or_a_range():
    """A newcomer's trial read 'the others' come at t ≈ 913 min to 913 min' of one sensor."""
    from mtident.cli_watch_answer import _others_stops

    assert _others_stops([], 500.0) == ""
    assert _others_stops([913], 500.0) == "; the other's comes at t ≈ 913 min"
    assert _others_stops([913, 913], 500.0) == "; the others' come at t ≈ 913 min"
    assert _others_stops([800, 913], 500.0) == "; the others' come at t ≈ 800 min to 913 min"


def test_the_other_sensors_that_may_stop_already_are_not_said_to_come():
    """A new user read "the others' come at t ≈ 861 min to 1190 min" at 900 min: a sensor that may
    stop has its expected stop at the time it became ready, which is past."""
    from mtident.cli_watch_answer import _others_stops

    assert (
        _others_stops([861, 1190], 900.0)
        == "; the other's comes at t ≈ 1190 min; one other may stop already (since t ≈ 861 min)"
    )
    assert _others_stops([700, 861], 900.0) == "; 2 others may stop already (since t ≈ 700 min)"


@pytest.mark.slow
def test_sigterm_during_a_fit_ends_cleanly_at_the_next_check_and_saves_what_it_says(tmp_path):
    """A service manager's SIGTERM while the fits run (a long poll): no traceback from inside the
    compiled code, an end within a few seconds, and the state file holds the time the message
    says; the same command then resumes to the decision of a run never stopped."""
    names = ("A", "B", "C", "D")
    full = csv_text(T[:301], {n: noisy(first_order(T[:301], steady=24.0 + k), 60 + k) for k, n in enumerate(names)})
    lines = full.splitlines(keepends=True)
    log = tmp_path / "live.csv"
    log.write_text("".join(lines[:31]))
    state = tmp_path / "live-state.npz"
    cmd = [sys.executable, "-m", "mtident", "thermal", "watch", str(log), "--json", "--state", str(state)]
    stderr = tmp_path / "stderr.txt"
    with open(stderr, "w") as said_file:  # a file, not a pipe: read while the watch runs and after
        proc = subprocess.Popen(
            [*cmd, "--poll", "0.05", "--serve", "127.0.0.1:0"],
            stdout=subprocess.PIPE,
            stderr=said_file,
            text=True,
            cwd=tmp_path,
        )
    try:
        # the live page shows each check's answer as it ends: it says when the fits of the new rows run
        page = wait_until(
            lambda: re.search(r"the live page is at (http://\S+/)", stderr.read_text()), "the page's address", 120
        ).group(1)
        wait_until(state.is_file, "the watch's first state file", timeout_s=120)
        with open(log, "a") as out_file:
            out_file.write("".join(lines[31:]))  # 270 rows at once: a poll of many checks
        wait_until(
            lambda: json.loads(_get(page + "state.json"))["answer"].get("last_time_min", 0.0) > 29.0,
            "a check of the new rows ended (the poll's next fits run)",
            120,
        )
        proc.send_signal(signal.SIGTERM)
        sent = time.monotonic()
        out, _ = proc.communicate(timeout=60)
        took = time.monotonic() - sent
    finally:
        proc.kill()
    err = stderr.read_text()
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "SystemError" not in err
    assert took < 5.0, took
    said = re.search(r"terminated \(SIGTERM\) at t = (\d+) min; the state is in", err)
    assert said is not None, err
    saved = load_dataclass(state, SavedWatch).monitor.readings.latest_min
    assert f"{saved:.0f}" == said.group(1) and 30 <= saved <= 300  # mid-fit, or after the last row on a fast machine
    assert json.loads(out)["last_time_min"] == saved
    resumed = subprocess.run(
        [*cmd, "--poll", "0.05", "--timeout", "1"],
        capture_output=True,
        text=True,
        timeout=300,
        cwd=tmp_path,
        check=False,
    )
    assert resumed.returncode == 0, resumed.stderr
    assert "resuming from" in resumed.stderr and "refused the row" not in resumed.stderr
    whole = tmp_path / "whole.csv"
    whole.write_text(full)
    code, out, _ = mtident("thermal", "watch", str(whole), "--replay", "--json")
    assert code == 0
    assert json.loads(resumed.stdout)["sensors"] == json.loads(out)["sensors"]


def test_a_sigterm_while_the_answer_is_written_is_noted_not_fatal():
    """A SIGTERM after the following ended, while the final answer's forecasts ran, killed the
    process outright: exit -15, no word (the state file held every reading)."""

    from mtident.cli_watch import _sigterm_deferred

    before = signal.getsignal(signal.SIGTERM)
    with _sigterm_deferred() as terminated:
        os.kill(os.getpid(), signal.SIGTERM)
        wait_until(terminated.is_set, "the deferred SIGTERM", timeout_s=5.0, poll_s=0.01)
    assert terminated.is_set()
    assert signal.getsignal(signal.SIGTERM) == before


@pytest.mark.slow
def test_watch_serve_says_where_the_page_is(tmp_path):
    log = tmp_path / "run.csv"
    log.write_text(csv_text(T[:30], {"S": noisy(first_order(T[:30]), 42)}))
    out = mtident("thermal", "watch", str(log), "--replay", "--serve", "127.0.0.1:0")
    assert out.returncode == 0, out.stderr
    assert "the live page is at http://127.0.0.1:" in out.stderr
    bad = mtident("thermal", "watch", str(log), "--replay", "--serve", "nowhere")
    assert bad.returncode == 2 and "expected HOST:PORT" in bad.stderr


def _watch_serving(args: list[str], cwd: Path) -> tuple[subprocess.Popen[str], str]:
    """`watch ... --serve 127.0.0.1:0` in a subprocess, and the page's URL once it says it."""
    import sys

    proc = subprocess.Popen(
        [sys.executable, "-m", "mtident", "thermal", "watch", *args, "--serve", "127.0.0.1:0", "--json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=cwd,
    )
    assert proc.stderr is not None
    for line in proc.stderr:
        if (found := re.search(r"the live page is at (http://\S+/)", line)) is not None:
            return proc, found.group(1)
    proc.kill()
    pytest.fail(f"the watch never served its page: {proc.communicate()}")


def _first_answer(proc: subprocess.Popen[str], url: str, within_s: float) -> dict:
    """The page's first answer, asked for while the watch runs, within ``within_s``."""

    def answer() -> dict | None:
        if proc.poll() is not None:
            pytest.fail("the watch ended before its page showed an answer")
        shown = json.loads(_get(url + "state.json"))["answer"]
        return dict(shown) if "decision" in shown else None  # not the newest readings alone, shown first live

    return wait_until(answer, "an answer on the page", within_s, 0.1)


@pytest.mark.slow
def test_the_page_answers_at_once_after_a_resume_and_during_a_replay(tmp_path):
    """A watch resumed with a long log to catch up on showed `{"version":0,"answer":{}}` until its
    first poll ended (80 s); a replay never showed an answer at all."""
    lines = _log(601).splitlines(keepends=True)
    log = tmp_path / "live.csv"
    log.write_text("".join(lines[:31]))
    first = mtident("thermal", "watch", str(log), "--timeout", "0.2")
    assert first.returncode == 0 and (tmp_path / "live.csv.watch-state.npz").is_file()
    with open(log, "a") as out:
        out.write("".join(lines[31:]))  # the logger went on while the watch was stopped
    proc, url = _watch_serving([str(log), "--poll", "0.05"], tmp_path)
    try:
        answer = _first_answer(proc, url, 20.0)  # the resumed state's answer, before the catch-up's fits (80 s before)
        assert answer["last_time_min"] == 29.0
    finally:
        proc.terminate()
        proc.communicate(timeout=60)
    whole = tmp_path / "whole.csv"
    whole.write_text("".join(lines))
    proc, url = _watch_serving([str(whole), "--replay"], tmp_path)
    try:
        answer = _first_answer(proc, url, 60.0)
        assert proc.poll() is None and 0 <= float(answer["last_time_min"]) < 600  # shown while the replay runs
    finally:
        proc.terminate()
        proc.communicate(timeout=60)


def test_watch_says_the_time_saved_against_the_settled_readings_not_a_predicted_equilibrium(
    tmp_path, spindle_reference
):
    t = np.arange(0.0, 480.0, 1.0)
    values = spindle_and_column(t)
    log = tmp_path / "test.csv"
    rows = "\n".join(f"{a:g},{b:.2f},{c:.2f}" for a, (b, c) in zip(t, values, strict=True))
    log.write_text("time_min,S,column\n" + rows + "\n")
    save_reference(spindle_reference, tmp_path / "machine.toml")
    out = mtident(
        "thermal", "watch", str(log), "--replay", "--json", "--reference", str(tmp_path / "machine.toml"),
        "--wait-for", "S", "--state", str(tmp_path / "state.npz"),
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    answer = json.loads(out.stdout)
    assert answer["decision"] == "stop"
    settle = answer["hindsight"]["settle_time_min"]
    # the spindle sensor (8 and 60 min, 10 °C, −4 °C slow) is within 0.2 °C of 30 from about 60·ln 20 = 180 min
    assert 170.0 <= settle <= 190.0
    assert answer["settle_time_min"] == settle
    assert answer["time_saved_min"] == pytest.approx(settle - answer["stop_time_min"])
    text = mtident(
        "thermal", "watch", str(log), "--replay", "--reference", str(tmp_path / "machine.toml"), "--wait-for", "S",
        "--state", str(tmp_path / "state2.npz"),
    ).stdout  # fmt: skip
    assert answer["time_saved_min"] > 0
    assert f"{answer['time_saved_min']:.0f} min before the readings settled within the tolerance" in " ".join(
        text.split()
    )


def test_the_hindsight_check_says_a_sensor_stuck_before_it_settled_is_stuck_not_unsettled(capsys):
    """A long log whose slow sensor stuck at 400 min, before its readings had settled: the check
    said "not settled by the log's end" and that the log ended before the readings settled, as if
    the log were too short; the sensor had failed."""
    nan = np.nan
    hindsight = Hindsight(
        ("spindle", "column"),
        300.0,
        1200.0,
        np.array([32.5, 27.4]),
        np.array([32.49, nan]),
        np.array([200.0, nan]),
        0,
        0.2,
        settle_time_min=np.array([250.0, nan]),
        stuck_since_min=np.array([nan, 400.0]),
    )
    text = _printed_hindsight(hindsight, capsys)
    assert "not settled by the log's end" not in text and "the log ends before" not in text
    assert "stuck from 400 min" in text
    assert (
        "stuck at one value before they settled (their repeats say nothing of the temperature): column from t = "
        in text
    )
    assert "column stuck before settling, so when the readings of every sensor the test waits for settled" in text
    alone = Hindsight(
        ("column",),
        300.0,
        1200.0,
        np.array([27.4]),
        np.array([nan]),
        np.array([nan]),
        0,
        0.2,
        settle_time_min=np.array([nan]),
        stuck_since_min=np.array([400.0]),
    )
    text = _printed_hindsight(alone, capsys)
    assert "The log ends before" not in text and "Every sensor's readings are stuck at one value" in text


def test_the_hindsight_table_says_why_a_sensor_has_a_settle_time_but_no_settled_level(capsys):
    """A newcomer's daily room: the readings kept following the room (no settled level: "—") while
    their rise above the room settled at 297.5 min, shown beside it without a word."""
    nan = np.nan
    hindsight = Hindsight(
        ("T0", "T1"),
        73.5,
        600.0,
        np.array([31.2, 28.4]),
        np.array([nan, 28.41]),
        np.array([nan, 250.0]),
        0.0,
        0.2,
        settle_time_min=np.array([297.5, nan]),
    )
    text = _printed_hindsight(hindsight, capsys)
    assert re.search(r"│ T0 +│ +31\.20 │ with the room │ +— │ +298 │", text), text
    assert re.search(r"│ T1 +│ +28\.40 │ +28\.41 │ +-0\.01 │ +— │", text), text
    assert "with the room: the readings keep following the room; from the time shown they stayed within" in text


def test_a_column_named_as_the_room_is_pointed_out_before_the_checks_say_anything(tmp_path):
    """A new user left --ambient out: the note naming the option came last of 29 lines, after every
    check's warning (a replay's first poll holds them all); it comes first now."""
    t = np.arange(0.0, 121.0)
    rng = np.random.default_rng(3)
    room = 20.0 + 0.3 * np.sin(2.0 * np.pi * t / 1440.0)
    spindle = room + 8.0 * (1.0 - np.exp(-t / 30.0)) + 0.01 * rng.standard_normal(t.size)
    rows = [f"{a:g},{b:.3f},{c:.3f}" for a, b, c in zip(t, spindle, room, strict=True)]
    path = tmp_path / "room.csv"
    path.write_text("time_min,spindle,room\n" + "\n".join(rows) + "\n")
    out = mtident("thermal", "watch", str(path), "--replay", "--json")
    assert out.returncode == 0, out.stderr
    said = [line for line in out.stderr.splitlines() if line.startswith("mtident:")]
    assert said and "'room' is named as a room sensor and watched as a machine sensor" in said[0], said[:3]
    assert sum("named as a room sensor" in line for line in said) == 1


def test_a_first_ctrl_c_ends_the_watch_at_its_next_safe_point_and_a_second_at_once():
    """A Ctrl-C while the watch caught up on a long log threw into the fit and saved nothing
    ("interrupted at t = 197 min; nothing was saved"), where SIGTERM ended it at the next safe
    point with the state saved. The first Ctrl-C now does what SIGTERM does, said as a Ctrl-C; a
    second one stops at once."""
    from mtident import cli_watch

    cli_watch._terminating.clear()
    cli_watch._interrupting.clear()
    try:
        cli_watch._interrupt(2, None)
        assert cli_watch._terminating.is_set() and cli_watch._interrupting.is_set()
        with pytest.raises(KeyboardInterrupt):
            cli_watch._interrupt(2, None)
    finally:
        cli_watch._terminating.clear()
        cli_watch._interrupting.clear()


def test_the_hindsight_check_does_not_say_the_log_ended_early_where_the_readings_follow_the_room(capsys):
    """A new user's 1,500-min log (six times the slowest mode) in a daily room: every sensor's
    readings kept following the room, their rise above it settled by 370 min; the check said "the
    log ends before its sensors settled"."""
    nan = np.nan
    hindsight = Hindsight(
        ("S1", "S2"),
        689.0,
        1500.0,
        np.array([26.55, 24.02]),
        np.array([nan, nan]),
        np.array([nan, nan]),
        0.1,
        0.2,
        settle_time_min=np.array([339.0, 370.0]),
    )
    text = _printed_hindsight(hindsight, capsys)
    assert "The log ends before" not in text
    assert (
        "Every sensor's readings keep following the room to the log's end: no settled level: nothing to check" in text
    )
    hindsight = replace(hindsight, settle_time_min=np.array([339.0, nan]))
    text = _printed_hindsight(hindsight, capsys)
    assert "The log ends before S2 settled" in text and "the others' readings keep following the room" in text


def test_watch_that_refused_every_row_is_an_error_not_an_answer(tmp_path):
    """A comma-separated log with decimal commas: every row was refused, and watch answered
    "continue the test" with exit 0, having read nothing."""
    log = tmp_path / "comma.csv"
    log.write_text("time_min,A,B\n" + "".join(f"{t},20,{t % 10},21,{t % 7}\n" for t in range(60)))
    code, out, err = mtident("thermal", "watch", str(log), "--replay", "--state", str(tmp_path / "s"))
    assert code == 2 and out == ""
    assert "refused 60 row(s) with more cells than the header's 3" in err
    assert "comma.csv: no data rows read (where rows were refused, the warnings above say why)" in " ".join(err.split())


def test_a_failed_sensors_status_says_since_when():
    """A stuck sensor's row showed its repeated value as "latest" and the log's end as "checked",
    as if it read on: its status says since when its readings say nothing."""
    check = new_state(["T1"]).checks[0]
    assert _status_words(replace(check, status="stuck", last_reading_min=149.0)) == "stuck from 149 min"
    assert _status_words(replace(check, status="silent", last_reading_min=380.0)) == "silent from 380 min"
    assert _status_words(replace(check, status="narrowing", last_reading_min=380.0)) == "narrowing"


def test_a_replay_into_a_pipe_says_how_far_it_has_read(tmp_path, monkeypatch):
    """Into a pipe or a file there is no live table: a replay whose checks took half a minute said
    nothing until its first sensor might stop. It now says how far it has read, at most every
    ``_PIPE_PROGRESS_S`` (here every check)."""
    import mtident.cli_watch as cli_watch

    monkeypatch.setattr(cli_watch, "_PIPE_PROGRESS_S", 0.0)
    t = np.arange(0.0, 160.0)
    log = tmp_path / "w.csv"
    log.write_text(csv_text(t, {"S": noisy(26.7 - 8.8 * np.exp(-t / 25.0), 1)}))
    code, _, err = mtident(
        "thermal", "watch", str(log), "--replay", "--room-wander", "0", "--state", str(tmp_path / "s")
    )
    assert code == 0, err
    said = re.findall(r"mtident: replayed to t = (\d+) min; (\d) of 1 sensor may stop", err)
    assert len(said) >= 2 and [int(t) for t, _ in said] == sorted(int(t) for t, _ in said)


def test_a_replays_plot_draws_the_readings_after_the_stop_apart(monkeypatch, tmp_path):
    """A newcomer's replayed test stopped at 465 min of a 600-min log, and its picture ended at
    the stop: the readings after it, which show how the answer held, are drawn apart."""
    from types import SimpleNamespace

    import mtident.report.plots as plots
    from mtident.cli_watch import _plot
    from mtident.thermal.monitor import MonitorSettings, monitor_step

    t = np.arange(0.0, 400.0, 1.0)
    y = noisy(20.0 + 5.0 * (1.0 - np.exp(-t / 20.0)), 7)[:, None]
    settings = MonitorSettings()
    state, _ = monitor_step(new_state(["S"]), t, y, None, settings)
    assert state.stopped and state.stop_time_min < t[-1] - 10.0  # readings after the stop to draw
    drawn = {}
    monkeypatch.setattr(plots, "plot_monitor", lambda *args, after=None: drawn.update(after=after))
    _plot(SimpleNamespace(state=state, settings=settings, whole_log=lambda: (t, y, None)), str(tmp_path / "w.png"))
    after_t, after_y = drawn["after"]
    assert after_t[0] > state.stop_time_min and after_t[-1] == t[-1] and after_y.shape == (len(after_t), 1)
    monkeypatch.undo()  # the real one draws them, labelled
    figure = plots.plot_monitor(state, settings, after=(after_t, after_y))
    assert any(line.get_label() == "after the stop" for line in figure.axes[0].get_lines())


def test_a_replay_that_stops_reads_the_whole_log_again_once_for_its_picture_and_hindsight(monkeypatch, tmp_path):
    """The picture's readings after the stop and the hindsight table came from two reads of the
    whole log; both take the one read."""
    import mtident.report.plots as plots
    from mtident.thermal.session import WatchSession

    reads = []
    whole_log = WatchSession.whole_log
    monkeypatch.setattr(WatchSession, "whole_log", lambda self: reads.append(1) or whole_log(self))
    drawn = {}
    monkeypatch.setattr(plots, "plot_monitor", lambda *args, after=None: drawn.update(after=after))
    t = np.arange(0.0, 400.0)
    log = tmp_path / "w.csv"
    log.write_text(csv_text(t, {"S": noisy(20.0 + 5.0 * (1.0 - np.exp(-t / 20.0)), 7)}))
    code, out, err = mtident(
        "thermal", "watch", str(log), "--replay", "--room-wander", "0", "--state", str(tmp_path / "s"),
        "--plot", str(tmp_path / "w.png"),
    )  # fmt: skip
    assert code == 0, err
    assert "can stop" in out and "Against the rest of the log" in out
    assert len(reads) == 1 and drawn["after"][0][-1] == t[-1]


def test_an_expected_stop_with_a_logged_room_says_it_holds_the_room_still(tmp_path):
    """A new user's test in a drifting room said 'Expected stop: … t ≈ 1035 min' while the drift
    went on and the room's allowance held every sensor open: the forecast holds a logged room at
    its latest level, and now says so."""
    t = np.arange(0.0, 60.0, 0.5)
    room = 20.0 + 0.05 / 60.0 * t
    log = tmp_path / "drift.csv"
    curve = room + 6.0 * (1.0 - np.exp(-t / 15.0))
    log.write_text(csv_text(t, {"S": noisy(curve, 3, sigma=0.01), "room": np.round(room, 2)}))
    code, out, err = mtident(
        "thermal", "watch", str(log), "--ambient", "room", "--replay", "--state", str(tmp_path / "s.npz")
    )
    assert code == 0, err
    text = " ".join(out.split())
    assert "Not yet" in text and "Expected stop: t ≈" in text, text
    said = "the room held at its latest level (a slower mode that still fits, or a room that keeps moving, moves"
    assert f"on the best model's course, {said} it later)" in text, text


def test_the_timeline_csv_holds_every_check_and_a_resumed_replay_writes_the_same(tmp_path):
    """An engineer wanted to see how the answer narrowed to the stop, check by check, in a
    spreadsheet: --timeline writes one row per sensor checked, its last row the answer's own
    numbers. The checks live in the state file: a replay resumed half-way keeps those made before."""
    save_reference(one_mode_reference("A", "B"), tmp_path / "machine.toml")
    columns = {"A": noisy(first_order(T[:101]), 18), "B": noisy(first_order(T[:101], steady=25.0), 19)}
    full = tmp_path / "full.csv"
    full.write_text(csv_text(T[:101], columns))
    fast = ("--reference", str(tmp_path / "machine.toml"), "--free-fast-modes", "0")
    whole = tmp_path / "whole.csv"
    code, out, err = mtident("thermal", "watch", str(full), "--replay", "--json", "--timeline", str(whole), *fast)
    assert code == 0, err
    answer = json.loads(out)
    assert answer["decision"] == "stop"
    table = pd.read_csv(whole)
    assert list(table.columns) == [
        "checked_at_min",
        "sensor",
        "status",
        "steady_state_C",
        "ci95_low_C",
        "ci95_high_C",
        "decision_low_C",
        "decision_high_C",
    ]
    assert set(table["sensor"]) == {"A", "B"} and np.all(np.diff(table["checked_at_min"]) >= 0)
    for sensor in answer["sensors"]:
        last = table[table["sensor"] == sensor["sensor"]].iloc[-1]
        assert last["checked_at_min"] == pytest.approx(sensor["checked_at_min"])
        assert last["status"] == sensor["status"] == "may stop"
        assert last["steady_state_C"] == pytest.approx(sensor["steady_state_C"], abs=1e-4)
        assert [last["decision_low_C"], last["decision_high_C"]] == pytest.approx(
            sensor["decision_interval_C"], abs=1e-4
        )
    # the early checks have no interval: blank cells, not "inf"
    assert "inf" not in whole.read_text()

    part = tmp_path / "part.csv"
    lines = full.read_text().splitlines(keepends=True)
    part.write_text("".join(lines[:40]))
    state, resumed = str(tmp_path / "state.npz"), tmp_path / "resumed.csv"
    code, _, err = mtident(
        "thermal", "watch", str(part), "--replay", "--state", state, "--timeline", str(resumed), *fast
    )
    assert code == 0, err
    before = pd.read_csv(resumed)
    part.write_text("".join(lines))
    code, _, err = mtident(
        "thermal", "watch", str(part), "--replay", "--resume", "--state", state, "--timeline", str(resumed), *fast
    )
    assert code == 0, err
    again = pd.read_csv(resumed)
    # the checks before the resume are kept, none twice, and the run goes on to the stop
    pd.testing.assert_frame_equal(again.iloc[: len(before)], before)
    assert len(again) > len(before) and not again.duplicated(["checked_at_min", "sensor"]).any()
    assert list(again.groupby("sensor")["status"].last()) == ["may stop", "may stop"]
