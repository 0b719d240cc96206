"""Tests of :mod:`mtident.persist`."""

from __future__ import annotations

import json
import signal
import subprocess
import sys

import numpy as np
import pytest
from conftest import first_order, wait_until
from helpers import T, csv_text, noisy

from mtident.persist import load_dataclass, save_dataclass
from mtident.thermal.session import (
    SavedWatch,
)


@pytest.mark.slow
@pytest.mark.parametrize(
    "stop, said", [(signal.SIGINT, "interrupted (Ctrl-C)"), (signal.SIGTERM, "terminated (SIGTERM)")]
)
def test_watch_interrupted_says_where_it_was_and_keeps_its_state(tmp_path, stop, said):
    """Ctrl-C (or a service manager's SIGTERM) while following a log: no traceback, where it
    stopped, exit 130. The child gets the default SIGINT handler whatever its parent ignores
    (nohup, a background job), and is killed in any case."""
    log = tmp_path / "live.csv"
    log.write_text(csv_text(T[:30], {"A": noisy(first_order(T[:30]), 19)}))
    state = tmp_path / "live-state.npz"
    proc = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import signal, sys; signal.signal(signal.SIGINT, signal.default_int_handler); from mtident.cli import "
            "main; sys.argv = ['mtident', *sys.argv[1:]]; main()",
            "thermal",
            "watch",
            str(log),
            "--json",
            "--state",
            str(state),
            "--poll",
            "0.05",
        ],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        cwd=tmp_path,
    )
    try:
        # stopped once it has saved every row (t = 29 min) and waits for new ones
        wait_until(
            lambda: state.is_file() and load_dataclass(state, SavedWatch).monitor.readings.latest_min == 29,
            "the whole log saved",
            120,
        )
        proc.send_signal(stop)
        out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == 130, err
    assert "Traceback" not in err
    assert f"{said} at t = 29 min" in err and "the same command resumes from there" in err
    assert json.loads(out)["decision"] == "continue" and json.loads(out)["last_time_min"] == 29.0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["live-state.npz", "live.csv"]  # no stray temporary file


def test_a_state_file_from_before_a_field_with_a_default_was_added_loads_with_it(tmp_path):
    """A check that gained a field (the room gains its picture needs) still resumes a state file
    written without it; a file that lacks a field with no default, or holds one the class does not
    have, is refused by name."""
    from dataclasses import dataclass, field

    from mtident.persist import StateFileError

    @dataclass(frozen=True)
    class Before:
        sensor: str
        steady_C: float

    @dataclass(frozen=True)
    class After:
        sensor: str
        steady_C: float
        room_gains: tuple[float, ...] = ()

    @dataclass(frozen=True)
    class Needs:
        sensor: str
        steady_C: float
        rise_C: float

    @dataclass(frozen=True)
    class Kept:
        sensor: str
        steady_C: float
        timeline: np.ndarray = field(default_factory=lambda: np.empty((0, 3)))

    save_dataclass(tmp_path / "before.npz", Before("T1", 26.7))
    assert load_dataclass(tmp_path / "before.npz", After) == After("T1", 26.7, ())
    # an array field added since (the monitor's checks) loads empty
    assert load_dataclass(tmp_path / "before.npz", Kept).timeline.shape == (0, 3)
    with pytest.raises(StateFileError, match="rise_C"):
        load_dataclass(tmp_path / "before.npz", Needs)
    save_dataclass(tmp_path / "after.npz", After("T1", 26.7, (0.5,)))
    with pytest.raises(StateFileError, match="room_gains"):
        load_dataclass(tmp_path / "after.npz", Before)


def test_monitor_states_compare_without_raising_their_readings_by_value():
    """Two monitor states compare (== raised on their readings' arrays): the readings of a state
    read back from its file equal the ones saved, NaN equal to NaN; a state with one reading more
    differs. A check's NaN fields follow float's rule (NaN differs from itself)."""
    from conftest import through_state_file

    from mtident.thermal.monitor import monitor_step, new_state
    from mtident.thermal.monitor_types import MonitorSettings

    values = np.c_[first_order(T[:40]), first_order(T[:40])]
    values[5, 1] = np.nan
    state, _ = monitor_step(new_state(["A", "B"], with_room=True), T[:40], values, np.full(40, 20.0), MonitorSettings())
    loaded = through_state_file(state)
    assert loaded.readings is not state.readings and loaded.readings == state.readings
    assert state == state and np.array_equal(loaded.timeline, state.timeline, equal_nan=True)
    assert len(state.timeline) > 0
    later, _ = monitor_step(loaded, T[40:41], values[-1:], np.array([20.0]), MonitorSettings())
    assert later != state and later.readings != state.readings
