"""Tests of :mod:`mtident.thermal.session`."""

from __future__ import annotations

import json
import math

import numpy as np
from conftest import PAPER_STEADY, first_order
from helpers import BATCHED_SETTINGS, T, csv_text, mtident, noisy, one_mode_reference

from mtident.persist import load_dataclass, save_dataclass
from mtident.thermal.monitor import MonitorSettings, MonitorState
from mtident.thermal.session import (
    Ended,
    FollowSettings,
    Polled,
    SavedWatch,
    Watching,
    WatchSession,
    default_state_path,
)


def test_watch_reads_a_log_in_fahrenheit_as_the_unit_option_says(tmp_path):
    """The decision of a °F log without units, with --unit F, is the one of the same log in °C; a
    state saved with the option is not resumed without it (its readings were converted)."""
    log = tmp_path / "run.csv"
    curve = noisy(first_order(T[:200]), 13)
    log.write_text(csv_text(T[:200], {"A": curve * 9 / 5 + 32}))
    state = tmp_path / "state.npz"
    code, out, err = mtident("thermal", "watch", str(log), "--replay", "--unit", "F", "--json", "--state", str(state))
    assert code == 0, err
    data = json.loads(out)
    assert abs(data["steady_state_C"] - PAPER_STEADY) < 0.5, data["steady_state_C"]
    assert "read in °F (--unit), converted to °C: A" in err
    settings = MonitorSettings()
    saved = WatchSession(log, settings, state_path=state, temperature_unit="F")
    assert saved.state is not None and any("resuming from" in n for n in saved.notes)
    again = WatchSession(log, settings, state_path=state)
    assert again.state is None and "other settings or sensors" in again.notes[0]
    _, values, _ = saved.whole_log()
    np.testing.assert_allclose(values[:, 0], np.round(curve * 9 / 5 + 32, 3) * 5 / 9 - 160 / 9, atol=1e-9)


def test_the_state_file_lives_beside_the_log_and_a_replay_starts_afresh(tmp_path):
    log = tmp_path / "run.csv"
    log.write_text(csv_text(T[:180], {"S": noisy(first_order(T[:180]), 9)}))
    options = MonitorSettings(reference=one_mode_reference("S"))
    assert default_state_path(log) == tmp_path / "run.csv.watch-state.npz"
    first = WatchSession(log, options)
    first.poll()
    assert first.state_path.is_file() and first.stopped
    again = WatchSession(log, options)
    assert again.state is not None and any("resuming from" in n for n in again.notes)
    fresh = WatchSession(log, options, resume=False)
    assert fresh.state is None and not fresh.notes
    other = WatchSession(log, MonitorSettings(tolerance_C=0.3, reference=one_mode_reference("S")))
    assert other.state is None and "other settings or sensors" in other.notes[0]


def test_a_different_log_copied_over_the_same_path_is_not_resumed(tmp_path):
    log = tmp_path / "run.csv"
    log.write_text(csv_text(T[:180], {"S": noisy(first_order(T[:180]), 10)}))
    options = BATCHED_SETTINGS  # stops by about 70 min
    session = WatchSession(log, options)
    session.poll()
    assert session.stopped
    # the next test's log, longer, copied over the old one (same path, same inode)
    with log.open("w") as out:
        out.write(csv_text(T, {"S": noisy(first_order(T, steady=30.0), 11)}))
    again = WatchSession(log, options)
    assert again.state is None and "another log at the same path" in again.notes[0]
    again.poll()
    assert again.stopped and abs(again.state.checks[0].steady_C - 30.0) < 0.2  # type: ignore[union-attr]


def test_an_unreadable_state_file_is_said_and_overwritten(tmp_path):
    log = tmp_path / "run.csv"
    log.write_text(csv_text(T[:60], {"S": noisy(first_order(T[:60]), 12)}))
    (tmp_path / "run.csv.watch-state.npz").write_text("not a state")
    session = WatchSession(log, MonitorSettings())
    assert "cannot be resumed" in session.notes[0]
    session.poll()
    assert isinstance(load_dataclass(session.state_path, SavedWatch), SavedWatch)


def test_a_state_file_of_an_older_version_is_not_resumed_but_started_afresh(tmp_path):
    """Older versions kept the follower's position as JSON text of their own (a dict, its dialect a
    list of four, five or eight entries): such a state file is not read by branches of its own,
    it is said and started afresh, then written as the follower's frozen position."""
    import dataclasses

    log = tmp_path / "run.csv"
    log.write_text(csv_text(T[:60], {"S": noisy(first_order(T[:60]), 12)}))
    first = WatchSession(log, MonitorSettings())
    first.poll()
    saved = load_dataclass(first.state_path, SavedWatch)

    @dataclasses.dataclass(frozen=True)
    class OlderSavedWatch:
        log: str
        fingerprint: str
        fingerprint_bytes: int
        settings_key: str
        position: str
        monitor: MonitorState

    older = {"offset": 120, "dialect": [",", ".", 0, "utf-8-sig"], "origin": 0.0, "last_time": 59.0}
    fields = {f.name: getattr(saved, f.name) for f in dataclasses.fields(OlderSavedWatch)}
    save_dataclass(first.state_path, OlderSavedWatch(**{**fields, "position": json.dumps(older)}))
    session = WatchSession(log, MonitorSettings())
    assert session.state is None
    assert f"the state file {session.state_path} cannot be resumed" in session.notes[0]
    assert "FollowPosition" in session.notes[0] and session.notes[0].endswith("starting afresh")
    session.poll()
    assert load_dataclass(session.state_path, SavedWatch).position == session.follower.position()


def test_a_session_that_keeps_no_state_says_it_leaves_another_runs_state_file_alone(tmp_path):
    """The report replays a log with a watch's state file beside it: 'starting afresh (it will be
    overwritten)' was said, though the report writes no state."""
    log = tmp_path / "log.csv"
    log.write_text(csv_text(T[:40], {"S": noisy(first_order(T[:40]), 4)}))
    first = WatchSession(log, MonitorSettings(tolerance_C=0.3))
    first.poll()
    first.save()
    notes = WatchSession(log, MonitorSettings(tolerance_C=0.2), persist=False).notes
    assert any("the log is decided from its start (the file is left as it is)" in n for n in notes)
    assert not any("overwritten" in n for n in notes)
    said = WatchSession(log, MonitorSettings(tolerance_C=0.2)).notes
    assert any("starting afresh (it will be overwritten)" in n for n in said)


def test_a_sessions_run_yields_its_polls_and_ends_by_timeout_replay_or_cancel(tmp_path):
    """The loop the command renders lives in the library: the sensors said once, each poll, and
    why it ended (a cancel, as SIGTERM's flag, with the state file kept for a resume)."""
    log = tmp_path / "short.csv"
    log.write_text("time_min,S\n" + "".join(f"{a:g},{20 + a / 10:.2f}\n" for a in range(20)))

    def kinds(follow: FollowSettings, cancel=None) -> list[object]:  # noqa: ANN001
        session = WatchSession(log, MonitorSettings(), state_path=tmp_path / "s.npz", resume=False)
        return [e for e in session.run(follow, cancel=cancel) if not hasattr(e, "kind")]

    timed_out = kinds(FollowSettings(poll_s=0.05, timeout_s=0.2))
    assert timed_out[0] == Watching(("S",)) and timed_out[1] == Polled(20, False)
    assert all(e == Polled(0, False) for e in timed_out[2:-1]) and len(timed_out) > 3
    assert isinstance(timed_out[-1], Ended) and timed_out[-1].reason == "timeout"
    replayed = kinds(FollowSettings(replay=True))
    assert [type(e) for e in replayed] == [Watching, Polled, Ended] and replayed[-1].reason == "replayed"
    cancelled = kinds(FollowSettings(poll_s=0.05), cancel=lambda: True)
    assert cancelled[-1].reason == "cancelled" and (tmp_path / "s.npz").is_file()


def test_expected_stops_end_when_asked_within_a_forecast(tmp_path):
    """A SIGTERM while the final answer is written: the forecasts (up to 12 s a sensor) stop at the
    next fit of the one under way."""
    log = tmp_path / "log.csv"
    log.write_text(
        csv_text(T[:161], {n: noisy(first_order(T[:161], steady=24.0 + k), 70 + k) for k, n in enumerate("AB")})
    )
    session = WatchSession(log, MonitorSettings(), persist=False)
    session.poll()
    asked = []
    assert session.expected_stops(cancel=lambda: asked.append(1) or True) is None and 1 <= len(asked) <= 2
    cancelled = session.result(cancel=lambda: True)["sensors"]
    assert all(s.get("expected_stop_time_min") is None for s in cancelled)  # type: ignore[union-attr]
    assert all(np.isfinite(v) for v in (session.expected_stops() or {"none": math.nan}).values())
    # once made, the same state's forecast is answered from, with nothing left to cancel
    answered = session.result(cancel=lambda: True)["sensors"]
    assert all(s.get("expected_stop_time_min") is not None for s in answered)  # type: ignore[union-attr]


def test_a_long_replay_shows_the_test_from_its_first_checks(tmp_path):
    """A replay showed nothing on its table or page until its first 250 rows were fed and checked."""
    from mtident.thermal.session import FIRST_FEED_ROWS, WatchSession

    t = np.arange(0.0, 400.0, 1.0)
    log = tmp_path / "long.csv"
    log.write_text("time_min,S\n" + "".join(f"{a:g},{30 - 10 * np.exp(-a / 60):.2f}\n" for a in t))
    session = WatchSession(log, MonitorSettings(), persist=False, resume=False)
    seen: list[float] = []
    session.poll(lambda s: seen.append(s.state.readings.latest_min))
    assert seen[0] <= FIRST_FEED_ROWS - 1 == 24.0  # the first check, at the latest the first part's end
    assert 24.0 in seen and 274.0 in seen  # and every 250 rows (until the test may stop), besides each check
    assert seen == sorted(seen)


def test_a_room_read_in_coarse_steps_is_said_once_and_a_fine_one_not(tmp_path):
    """A room column in 0.1 °C steps draws one warning, naming the step and the way on (log it at
    0.01 °C), after enough readings show the step; the same room in 0.01 °C steps draws none."""
    t = T[:120]
    room = 21.0 + 0.3 * np.sin(t / 40.0)
    curve = noisy(first_order(t), 5) + (room - 21.0)

    def warnings(step: float) -> list[str]:
        log = tmp_path / f"room{step:g}.csv"
        log.write_text(csv_text(t, {"A": curve, "R": np.round(room / step) * step}))
        session = WatchSession(log, MonitorSettings(room_sensor="R"), resume=False, persist=False)
        return [e.text for e in session.poll() + session.poll() if e.kind == "warning"]

    coarse = [w for w in warnings(0.1) if "steps of" in w]
    session = WatchSession(tmp_path / "room0.1.csv", MonitorSettings(room_sensor="R"), resume=False, persist=False)
    session.poll()
    # a JSON reader sees what the terminal said
    assert [w for w in session.result(with_forecast=False)["log_warnings"] if "steps of 0.1 °C" in w]
    assert len(coarse) == 1 and "R: the room is read in steps of 0.1 °C" in coarse[0] and "0.01 °C" in coarse[0]
    assert not [w for w in warnings(0.01) if "steps of" in w]


def test_readings_lost_are_among_the_json_answers_log_warnings(tmp_path):
    """An open circuit for a stretch: the terminal said "skipped 20 ... reading(s)" as a note, and
    the JSON answer's log_warnings, which the guide says holds readings lost or misread, had none."""
    t = T[:120]
    curve = noisy(first_order(t), 5)
    curve[60:80] = -200.0
    log = tmp_path / "open.csv"
    log.write_text(csv_text(t, {"A": curve}))
    session = WatchSession(log, MonitorSettings(), resume=False, persist=False)
    said = [e for e in session.poll() if "skipped 20" in e.text]
    assert len(said) == 1 and said[0].kind == "warning"
    lost = [w for w in session.result(with_forecast=False)["log_warnings"] if "skipped 20" in w]
    assert lost == [
        f"sensor 'A': skipped 20 empty, unreadable or open-circuit reading(s) (the first at t = {t[60]:g} min)"
    ]


def test_a_replay_says_a_last_line_without_its_end(tmp_path):
    """A finished log whose last line has no line end: the replay left it out without a word
    (299 rows, where inspect read 300); it is said, and carried in the JSON answer."""
    t = T[:60]
    log = tmp_path / "cut.csv"
    log.write_text(csv_text(t, {"A": noisy(first_order(t), 5)}).rstrip("\n"))
    session = WatchSession(log, MonitorSettings(), resume=False, persist=False)
    said = [e.text for e in session.run(FollowSettings(replay=True)) if getattr(e, "kind", None) == "warning"]
    assert [w for w in said if "left out the last line" in w and "it has no line end" in w]
    assert [w for w in session.result(with_forecast=False)["log_warnings"] if "left out the last line" in w]
    whole = tmp_path / "whole.csv"
    whole.write_text(csv_text(t, {"A": noisy(first_order(t), 5)}))
    session = WatchSession(whole, MonitorSettings(), resume=False, persist=False)
    assert not [e for e in session.run(FollowSettings(replay=True)) if "last line" in getattr(e, "text", "")]


def test_a_replay_that_ends_before_the_stop_answers_on_every_reading(tmp_path):
    """Checks come spaced out (a sensor far from the tolerance every few tens of minutes): a log
    that ended before the test could stop gave the last answer of a check made before its end, a
    slow sensor's T∞ fitted on readings up to an hour short of it. Where the log ends, every sensor
    is checked on all of it."""
    t = np.arange(0.0, 241.0)
    log = tmp_path / "run.csv"
    log.write_text(
        csv_text(
            t, {"slow": noisy(30.0 - 10.0 * np.exp(-t / 150.0), 4), "fast": noisy(28.0 - 8.0 * np.exp(-t / 20.0), 5)}
        )
    )
    session = WatchSession(log, MonitorSettings(), persist=False)
    spaced = WatchSession(log, MonitorSettings(), persist=False)
    spaced.poll()
    assert spaced.state is not None and min(c.checked_min for c in spaced.state.checks) < 240.0
    ended = [e for e in session.run(FollowSettings(replay=True)) if isinstance(e, Ended)]
    assert ended[-1].reason == "replayed" and not session.stopped
    assert session.state is not None and all(c.checked_min == 240.0 for c in session.state.checks)


def test_a_forecast_is_saved_with_its_state_and_answered_from_by_a_resumed_session(tmp_path, monkeypatch):
    """A report made after a watch of the same log forecast every sensor's stop again (85 s of a
    new user's 88 s); the forecast is saved with the state it was made of and answered from while
    that state stands, and made again once a reading is fed."""
    import mtident.thermal.session as session_module

    log = tmp_path / "run.csv"
    log.write_text(
        csv_text(T[:90], {"A": noisy(first_order(T[:90]), 31), "B": noisy(first_order(T[:90], steady=29.0), 32)})
    )
    first = WatchSession(log, MonitorSettings())
    first.poll()
    made = first.expected_stops()
    assert made is not None and set(made) == {"A", "B"}
    assert load_dataclass(first.state_path, SavedWatch).forecast is not None

    def forecast_again(*_: object, **__: object) -> float:
        raise AssertionError("forecast made again for the state it was saved with")

    monkeypatch.setattr(session_module, "expected_stop", forecast_again)
    resumed = WatchSession(log, MonitorSettings())
    assert resumed.state is not None
    np.testing.assert_equal(resumed.expected_stops(), made)
    with log.open("a") as f:
        f.write("90,35.000,34.000\n")
    resumed.poll()
    monkeypatch.setattr(session_module, "expected_stop", lambda *_, **__: 123.0)
    assert resumed.expected_stops() == {"A": 123.0, "B": 123.0}
