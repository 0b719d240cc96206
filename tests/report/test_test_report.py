"""Tests of :mod:`mtident.report.report`."""

from __future__ import annotations

import numpy as np
from conftest import first_order
from helpers import csv_text, mtident, noisy

from mtident.report.test_report import reading_gaps


def test_stretches_without_readings_are_said(tmp_path):
    # a recorder stopped from minute 40 to 70: the report says so
    t = np.concatenate([np.arange(0.0, 41.0), np.arange(70.0, 120.0)])
    log = tmp_path / "gappy.csv"
    log.write_text(csv_text(t, {"S": noisy(first_order(t), 24)}))
    out = tmp_path / "gappy.html"
    code, _, err = mtident("thermal", "report", str(log), "-o", str(out))
    assert code == 0, err
    assert "to t = 119 min; none from 40 min to 70 min</dd>" in out.read_text(encoding="utf-8")
    assert reading_gaps(np.arange(10.0)) == ()
    assert reading_gaps(np.array([0.0, 1.0, 2.0, 9.0, 10.0])) == ((2.0, 9.0),)


def test_log_start_reads_every_kind_of_time_stamp():
    import datetime as dt
    from types import SimpleNamespace

    from mtident.report.test_report import log_start

    def follower(origin, fmt, first="", serial=False):  # noqa: ANN001, ANN202
        return SimpleNamespace(origin=origin, time_format=fmt, first_stamp=first, serial_days=serial)

    epoch = dt.datetime(2026, 11, 26, 7, 0, 30) - dt.datetime(1970, 1, 1)
    minutes_1970 = epoch.total_seconds() / 60.0
    assert log_start(follower(minutes_1970, "%d.%m.%Y %H:%M:%S")) == dt.datetime(2026, 11, 26, 7, 0, 30)
    aware = log_start(follower(minutes_1970, "ISO8601", "2026-11-26T08:00:30+01:00"))
    assert isinstance(aware, dt.datetime) and aware.tzinfo is not None
    assert aware == dt.datetime(2026, 11, 26, 7, 0, 30, tzinfo=dt.UTC)
    assert log_start(follower(-36816060.0, "%H:%M:%S")) == dt.time(7, 0)
    assert log_start(follower(46350.25 * 1440.0, None, serial=True)) == dt.datetime(2026, 11, 24, 6, 0)
    assert log_start(follower(0.0, None)) is None and log_start(follower(None, None)) is None


def test_the_pdf_uses_its_pages_the_curves_two_to_a_row(tmp_path):
    # today: page 2 holds one small picture of the three panels in a row, on an otherwise empty page
    from mtident.report.report_render import summary_pages
    from mtident.report.test_report import build_report
    from mtident.thermal.monitor import MonitorSettings
    from mtident.thermal.session import WatchSession

    t = np.arange(0.0, 90.0)
    log = tmp_path / "three.csv"
    log.write_text(csv_text(t, {name: noisy(first_order(t), 40 + k) for k, name in enumerate("ABC")}))
    built = build_report(WatchSession(log, MonitorSettings(), persist=False))
    pages = summary_pages(built)
    panels = [[ax for ax in page.axes if ax.get_xlabel() == "time (min)"] for page in pages]
    assert len(pages) == 2 and [len(p) for p in panels] == [2, 1]
    for ax in panels[0]:  # a panel is about half the page wide and a fifth of it high
        box = ax.get_position()
        assert 0.35 < box.width < 0.5 and 0.13 < box.height < 0.25
    # the second page holds the third panel, then the assumptions and the method
    texts = [text.get_text() for text in pages[1].texts]
    assert "Method" in texts and any("page 2 of 2" in text for text in texts)
    out = tmp_path / "three.pdf"
    from mtident.report.report_render import write_pdf

    write_pdf(built, out)
    data = out.read_bytes()
    assert data.count(b"/Type /Page\n") + data.count(b"/Type /Page ") == 2


def test_a_silent_sensor_is_said_so_in_the_report_with_the_way_on():
    from mtident.report.test_report import _holding_line
    from mtident.thermal.monitor import MonitorSettings, SensorCheck

    check = SensorCheck("T3", status="silent", steady_C=30.26, low_C=29.87, high_C=30.77, last_reading_min=149.0)
    line = _holding_line(check, MonitorSettings(), float("nan"))
    assert line.startswith("T3: no reading since t = 149 min while the others read on")
    assert line.endswith("leave it out of the sensors the test waits for (--wait-for).")


def test_a_panel_shows_the_rest_of_the_log_its_band_and_decision_level_beneath_nothing():
    """A user's report: the readings after the stop rose above the panel (its scale set by the
    readings up to the stop), the decision's upper level was cut off, and the points after the stop
    hid the model's course they are there to be compared with."""
    import matplotlib

    matplotlib.use("Agg")
    from matplotlib.figure import Figure

    from mtident.report.plots import draw_monitor_panel
    from mtident.report.test_report import draw_rest_of_log
    from mtident.thermal.monitor import MonitorSettings, monitor_step, new_state
    from mtident.thermal.robust_types import RobustSettings

    t = np.arange(0.0, 600.0, 1.0)
    y = 20.0 + 2.0 * (1.0 - np.exp(-t / 60.0)) + np.random.default_rng(2).normal(0.0, 0.02, t.size)
    settings = MonitorSettings(tolerance_C=0.5, robust=RobustSettings(max_time_constant_min=100.0))
    state, _ = monitor_step(new_state(["S3"]), t[:200], y[:200, None], None, settings)
    assert state.checks[0].high_C - state.checks[0].low_C < 2.0  # of the rise's size: drawn
    ax = Figure().add_subplot()
    draw_monitor_panel(ax, state, settings, 0)
    check = state.checks[0]
    low, high = ax.get_ylim()
    assert low <= check.low_C and check.high_C <= high
    draw_rest_of_log(ax, t, y, 199.0, legend=False)
    low, high = ax.get_ylim()
    assert low <= y.min() and y.max() <= high
    model = [line for line in ax.get_lines() if line.get_label().startswith("best model")]
    after = [line for line in ax.get_lines() if line.get_label() == "after the stop"]
    assert model and after and model[0].get_zorder() > after[0].get_zorder()


def test_a_log_that_runs_on_unsettled_is_said_as_watch_says_it_with_the_rule():
    """A new user's report said "no sensor settled by its end" where watch gave the rule (moving
    less than half the tolerance over the last quarter, a quarter of it still to come at the pace
    of the slowest mode): the user's own settle time, within the tolerance, came earlier."""
    from mtident.report.test_report import _hindsight_verdict
    from mtident.thermal.hindsight import check_decision

    t = np.arange(0.0, 361.0)
    rising = 20.0 + 5.0 * (1.0 - np.exp(-t / 180.0))
    hindsight = check_decision(("S",), np.array([25.0]), 200.0, t, rising[:, None], 0.2, None, [((180.0, -5.0),)])
    words = _hindsight_verdict(hindsight)
    assert words.startswith("The log runs on to 360 min. The log ends before its sensors settled (settled: moving ")
    assert "less than 0.1 °C over the log's last quarter, with under 0.05 °C still to come" in words
    assert words.endswith(": nothing to check T∞ against.")


def test_every_message_of_the_report_is_reworded_and_nothing_else():
    import dataclasses

    from mtident.report.test_report import MESSAGE_FIELDS, WarmupReport

    names = {f.name: f for f in dataclasses.fields(WarmupReport)}
    assert set(MESSAGE_FIELDS) <= set(names)
    blank = {name: ("x" if f.type == "str" else ()) for name, f in names.items()}
    report = WarmupReport(**{**blank, "reason": "give `reference`", "warnings": ("a `sensors`",), "ways_on": None})
    worded = report.reworded(str.upper)
    assert worded.reason == "GIVE `REFERENCE`" and worded.warnings == ("A `SENSORS`",) and worded.ways_on is None
    assert worded.source == "x" and worded.assumptions == "x"


def test_a_message_said_at_a_time_reads_back_without_it():
    from mtident.thermal.monitor import said_at, without_time

    said = said_at(230.0, "the reference: not followed")
    assert said == "t = 230 min: the reference: not followed"
    assert without_time(said) == "the reference: not followed"
    assert without_time("the reference: not followed") == "the reference: not followed"


def test_a_holding_line_says_when_t_inf_would_be_known_not_when_the_readings_settle():
    """A new user's six sensors were within 0.2 °C of their equilibrium from 345 min; the report
    said each "settles by about t = 793 min", its expected stop: when T∞ would be known."""
    from mtident.report.test_report import _holding_line
    from mtident.thermal.monitor import MonitorSettings, SensorCheck

    check = SensorCheck("S", status="narrowing", steady_C=33.37, low_C=33.04, high_C=33.61)
    line = _holding_line(check, MonitorSettings(), 793.5)
    assert line.endswith("On its present course its T∞ would be known within ±0.2 °C by about t = 794 min.")
    none = _holding_line(check, MonitorSettings(), float("nan"))
    assert "settles" not in line and "t = " not in none
    assert none.endswith(
        "No stop is found on its best model's course (its interval does not come within the tolerance there)."
    )
