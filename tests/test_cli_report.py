"""Tests of :mod:`mtident.cli_report`."""

from __future__ import annotations

import html
import re

import numpy as np
from conftest import first_order
from helpers import T, csv_text, frozen_channel, mtident, noisy, one_mode_reference, workbook_of_runs

from mtident.thermal.reference import save_reference


def logged_test(tmp_path, steady_b: float = 29.0):  # noqa: ANN001, ANN201
    log = tmp_path / "run.csv"
    log.write_text(csv_text(T, {"A": noisy(first_order(T), 21), "B": noisy(first_order(T, steady=steady_b), 22)}))
    reference = tmp_path / "machine.toml"
    save_reference(one_mode_reference("A", "B"), reference)
    return log, reference


def test_the_html_report_says_the_decision_each_sensor_and_what_it_rests_on(tmp_path):
    log, reference = logged_test(tmp_path)
    out = tmp_path / "report.html"
    code, stdout, err = mtident(
        "thermal", "report", str(log), "--reference", str(reference), "--free-fast-modes", "0", "-o", str(out)
    )
    assert code == 0, err
    assert stdout.startswith(f"{out}: the test could stop at t = ")
    page = out.read_text(encoding="utf-8")
    stop = float(stdout.split("t = ")[1].split()[0])
    assert f"The test could stop at t = {stop:g} min" in page and 50 <= stop <= 80
    assert page.count("<td>A</td>") == 1 and page.count("<td>B</td>") == 1
    assert "every sensor that settled (2) is within the tolerance (0.2 °C)" in page
    assert "no mode faster than these (assumed)" in page and "time constants up to 300 min" in page
    assert 'src="data:image/png;base64,' in page and "Made with mtident" in page
    # T∞ of each sensor in its row, within the tolerance of the truth
    for truth in (26.7, 29.0):
        assert any(abs(float(cell) - truth) < 0.2 for cell in _cells(page, 2))


def _cells(page: str, column: int) -> list[str]:
    rows = page.split("<tr>")[2:]
    return [row.split("<td")[column + 1].split(">", 1)[1].split("<")[0] for row in rows]


def test_the_pdf_report_has_the_summary_and_the_curves(tmp_path):
    log, reference = logged_test(tmp_path)
    out = tmp_path / "report.pdf"
    code, _, err = mtident(
        "thermal", "report", str(log), "--reference", str(reference), "--free-fast-modes", "0", "-o", str(out)
    )
    assert code == 0, err
    data = out.read_bytes()
    assert data.startswith(b"%PDF") and data.count(b"/Type /Page\n") + data.count(b"/Type /Page ") >= 1


def test_a_test_that_cannot_stop_is_reported_with_the_reason(tmp_path):
    t = np.arange(0.0, 90.0)
    log = tmp_path / "short.csv"
    log.write_text(csv_text(t, {"S": noisy(first_order(t), 23)}))
    out = tmp_path / "short.html"
    code, stdout, err = mtident("thermal", "report", str(log), "-o", str(out))
    assert code == 0, err
    assert stdout.endswith("no stop within the log\n")
    page = out.read_text(encoding="utf-8")
    assert "No stop within the log (to 89 min)" in page and "<h2>Why not yet</h2>" in page and "still fits" in page


def test_a_recorded_log_says_where_it_was_recorded_from_and_its_state_file_is_left_alone(tmp_path):
    log, reference = logged_test(tmp_path)
    (tmp_path / "run.csv.opcua.json").write_text(
        '{"url": "opc.tcp://vmc1:4840", "nodes": ["ns=2;s=A", "ns=2;s=B"], "names": ["A", "B"], '
        '"origin": "2026-11-24T08:00:00+00:00", "last_stamp": {}}'
    )
    code, _, err = mtident(
        "thermal",
        "report",
        str(log),
        "--reference",
        str(reference),
        "--free-fast-modes",
        "0",
        "-o",
        str(tmp_path / "r.html"),
    )
    assert code == 0, err
    page = (tmp_path / "r.html").read_text(encoding="utf-8")
    assert "recorded from opc.tcp://vmc1:4840 (nodes ns=2;s=A, ns=2;s=B)</dd>" in page
    assert "(the recorder&#39;s first reading)</dd>" in page
    assert not (tmp_path / "run.csv.watch-state.npz").exists()


def test_report_refuses_what_it_cannot_write_or_read(tmp_path):
    log, _ = logged_test(tmp_path)
    code, _, err = mtident("thermal", "report", str(log), "-o", str(tmp_path / "report.docx"))
    assert code == 2 and "give a name ending in .html or .pdf" in err
    code, _, err = mtident("thermal", "report", str(tmp_path / "none.csv"), "-o", str(tmp_path / "r.html"))
    assert code == 2 and "no such file" in err
    code, _, err = mtident("thermal", "report", str(log), "-o", str(tmp_path / "missing" / "r.html"))
    assert code == 2 and "does not exist" in err


def dated_log(path, t, columns, start=None):  # noqa: ANN001, ANN201
    """A logger's export: dotted local time stamps, semicolons and decimal commas."""
    import datetime as dt

    start = start or dt.datetime(2026, 11, 26, 7, 0, 0)
    lines = ["Datum Zeit;" + ";".join(columns)]
    for k, tk in enumerate(t):
        stamp = (start + dt.timedelta(minutes=float(tk))).strftime("%d.%m.%Y %H:%M:%S")
        lines.append(stamp + ";" + ";".join(f"{v[k]:.2f}".replace(".", ",") for v in columns.values()))
    path.write_text("\n".join(lines) + "\n")
    return path


def named_reference(tmp_path, *names: str):  # noqa: ANN001, ANN201
    from dataclasses import replace

    reference = tmp_path / "vmc.toml"
    said = replace(
        one_mode_reference(*names),
        machine="VMC 1",
        serial="S-0042",
        program="spindle 3,500 r/min",
        run_date="2026-11-20",
    )
    save_reference(said, reference)
    return reference


def test_the_title_names_the_machine_and_program_and_t0_is_the_logs_start_in_local_time(tmp_path):
    # today: "Warm-up test: /full/path/run.csv", no machine, no program, no date, no start (the
    # title's words need an hour of log, not a whole warm-up)
    hour = T[:61]
    log = dated_log(
        tmp_path / "run.csv", hour, {"A": noisy(first_order(hour), 21), "B": noisy(first_order(hour, steady=29.0), 22)}
    )
    reference = named_reference(tmp_path, "A", "B")
    out = tmp_path / "report.html"
    code, _, err = mtident(
        "thermal", "report", str(log), "--reference", str(reference), "--free-fast-modes", "0", "-o", str(out)
    )
    assert code == 0, err
    page = out.read_text(encoding="utf-8")
    assert "<title>Warm-up test of VMC 1 (serial S-0042)</title>" in page
    assert "<h1>Warm-up test of VMC 1 (serial S-0042)</h1>" in page
    # the program on record is the reference run's: a test at another speed is not titled with it
    assert "spindle 3,500 r/min (this test&#39;s may differ)" in page
    assert "Test of 26 Nov 2026 · log run.csv" in page
    assert "<dt>t = 0</dt><dd>26 Nov 2026, 07:00 (the log&#39;s time stamps)</dd>" in page
    # --machine names the machine where no reference does; nothing known: the file name
    code, _, err = mtident("thermal", "report", str(log), "--machine", "VMC 2", "-o", str(tmp_path / "m.html"))
    assert code == 0, err
    assert "<h1>Warm-up test of VMC 2</h1>" in (tmp_path / "m.html").read_text(encoding="utf-8")
    numbered, _ = logged_test(tmp_path)
    code, _, err = mtident("thermal", "report", str(numbered), "-o", str(tmp_path / "n.html"))
    assert code == 0, err
    plain = (tmp_path / "n.html").read_text(encoding="utf-8")
    assert "<h1>Warm-up test: run.csv</h1>" in plain
    assert "<dt>t = 0</dt><dd>the log&#39;s first reading (the log has no time stamps)</dd>" in plain


def test_a_recorded_logs_start_is_its_first_reading_in_local_time_not_raw_utc(tmp_path):
    import os
    import time

    log, reference = logged_test(tmp_path)
    (tmp_path / "run.csv.opcua.json").write_text(
        '{"url": "opc.tcp://vmc1:4840", "nodes": ["ns=2;s=A"], "names": ["A"], '
        '"origin": "2026-11-24T08:00:00.123456+00:00", "last_stamp": {}}'
    )
    before = os.environ.get("TZ")
    os.environ["TZ"] = "Europe/Berlin"
    time.tzset()
    try:
        code, _, err = mtident(
            "thermal", "report", str(log), "--reference", str(reference), "-o", str(tmp_path / "r.html")
        )
    finally:
        if before is None:
            del os.environ["TZ"]
        else:
            os.environ["TZ"] = before
        time.tzset()
    assert code == 0, err
    page = (tmp_path / "r.html").read_text(encoding="utf-8")
    assert "<dt>t = 0</dt><dd>24 Nov 2026, 09:00 CET (the recorder&#39;s first reading)</dd>" in page
    assert "Test of 24 Nov 2026" in page and "123456" not in page and "+00:00" not in page


def test_why_not_yet_is_a_short_line_per_sensor_that_holds_the_test(tmp_path):
    # today: one paragraph of some 1,100 characters
    t = np.arange(0.0, 90.0)
    log = tmp_path / "short.csv"
    # a sensor's name is escaped on the page (today the template's .j2 name left autoescaping off)
    columns = {name: noisy(first_order(t, steady=26.7 + k), 30 + k) for k, name in enumerate(("A", "B", "C<&>"))}
    log.write_text(csv_text(t, columns))
    out = tmp_path / "short.html"
    code, _, err = mtident("thermal", "report", str(log), "-o", str(out))
    assert code == 0, err
    page = out.read_text(encoding="utf-8")
    items = page.split('<ul class="holding">')[1].split("</ul>")[0].split("<li>")[1:]
    assert [item.split(":")[0] for item in items] == ["A", "B", "C&lt;&amp;&gt;"]
    for item in items:
        text = item.split("</li>")[0]
        assert len(text) < 300, text
        assert "still possible" in text and "wider than ±0.2 °C" in text and "still fits the readings" in text
    # the ways on are watch's, said with the command line's options
    assert "<strong>Ways on:</strong> continue the test, or give a reference run of this machine" in page
    assert "(--max-time-constant)" in html.unescape(page)
    assert "Why not yet:</strong>" not in page


def test_the_table_keeps_what_the_customer_reads_and_the_hindsight_says_the_time_saved(tmp_path):
    log, reference = logged_test(tmp_path)
    out = tmp_path / "report.html"
    code, stdout, err = mtident(
        "thermal", "report", str(log), "--reference", str(reference), "--free-fast-modes", "0", "-o", str(out)
    )
    assert code == 0, err
    page = out.read_text(encoding="utf-8")
    header = page.split("<h2>Per sensor</h2>")[1].split("</tr>")[0]
    assert "λ" not in header and "decision interval" not in header and "slowest τ" not in header
    # the decision's own interval beside the 95 % one (a user missed it: the decision is at 99 %)
    for column in ("at the stop (°C)", "T∞ (°C)", "95 % interval (°C)", "99 % interval (°C)", "t_eq (min)", "status"):
        assert f"<th>{column}</th>" in header
    assert "<th>settled (°C)</th>" in header
    assert "<th>difference (°C)</th><th>settled by (min)</th>" in header
    assert page.count('<td class="text">ready: T∞ within the tolerance</td>') == 2
    assert "t_eq: when the best model" in page
    stop = float(stdout.split("t = ")[1].split()[0])
    said = re.search(
        r"The readings settled within the tolerance by t = (\d+) min: the stop at (\d+) min saved (\d+) min\.", page
    )
    assert said is not None, page
    settle, at, saved = (int(g) for g in said.groups())
    assert at == stop and saved == settle - stop > 0


def test_a_workbooks_report_names_the_workbook_its_sheet_and_a_room_column(tmp_path):
    """A workbook is reported from the CSV its sheet holds, written to a temporary folder: the report
    named that copy (/tmp/mtident-.../runs.csv) as the log; which sheet of several was read went
    unsaid, and so did a column named as the room, reported as a machine sensor."""
    book = tmp_path / "runs.xlsx"
    workbook_of_runs(book, minutes=120.0)
    out = tmp_path / "report.html"
    code, _, err = mtident("thermal", "report", str(book), "--room-wander", "0", "-o", str(out))
    assert code == 0, err
    assert f"mtident: warning: {book}: read sheet 'Run 1' of 4 (the first that holds a table)" in err
    code, _, err = mtident("thermal", "report", str(book), "--sheet", "Run 2", "--room-wander", "0", "-o", str(out))
    assert code == 0, err
    page = out.read_text(encoding="utf-8")
    assert str(book) in page and "runs.xlsx, sheet &#39;Run 2&#39;" in page and "mtident-" not in page
    assert "read sheet" not in err
    assert (
        "mtident: note: 'Umgebung' is named as a room sensor and reported as a machine sensor; if it measures the "
        "room, --ambient Umgebung makes it the input of each sensor's heat balance"
    ) in err


def test_the_report_answers_as_a_replayed_watch_does_from_every_sensor_checked_at_the_logs_end(tmp_path):
    """A new user's report of a log that did not stop gave other T∞ and intervals than watch of the
    same log (front_brg 24.72 [24.69, 25.01] against 24.71 [24.64, 24.95] °C): watch checks every
    sensor on every reading where the log ends, the report answered from checks spaced out before
    the end, and watch's state file did not keep its last checks."""
    import json

    t = np.arange(0.0, 151.0)
    log = tmp_path / "long.csv"
    log.write_text(
        csv_text(
            t,
            {"A": noisy(first_order(t, rate=1 / 80.0), 31), "B": noisy(first_order(t, steady=29.0, rate=1 / 45.0), 32)},
        )
    )
    code, out, err = mtident("thermal", "watch", str(log), "--replay", "--json", "--state", str(tmp_path / "w.npz"))
    assert code == 0, err
    watched = {s["sensor"]: s for s in json.loads(out)["sensors"]}
    assert watched["A"]["steady_state_ci95_C"][1] - watched["A"]["steady_state_ci95_C"][0] > 0.4  # no stop
    for state in ("fresh.npz", "w.npz"):  # a report of its own, and one that starts from watch's state
        page = tmp_path / f"{state}.html"
        code, _, err = mtident("thermal", "report", str(log), "--state", str(tmp_path / state), "-o", str(page))
        assert code == 0, err
        text = page.read_text(encoding="utf-8")
        for name, cells in zip(_cells(text, 0), zip(_cells(text, 2), _cells(text, 3), strict=True), strict=True):
            low, high = watched[name]["steady_state_ci95_C"]
            assert cells == (f"{watched[name]['steady_state_C']:.2f}", f"{low:.2f} to {high:.2f}"), (state, name)


def test_the_report_says_what_reading_the_log_said_though_a_watch_read_its_first_rows(tmp_path):
    """A log in °F with no unit stated was reported with T∞ 82.40 "°C" and no word of the unit, the
    gap or the readings left out: the watch says them while it reads, and the report (which resumes
    from the watch's state) dropped them. It says them on stderr and in the page, from its own read
    of the whole log; and it draws how the intervals narrowed, check by check."""
    t = np.arange(0.0, 120.0)
    keep = (t < 60) | (t >= 75)
    fahrenheit = {name: first_order(t[keep], steady=s) * 9 / 5 + 32 for name, s in (("A", 26.7), ("B", 29.0))}
    fahrenheit["room"] = np.full(keep.sum(), 68.0)
    log = tmp_path / "f.csv"
    log.write_text(csv_text(t[keep], fahrenheit))
    code, _, err = mtident("thermal", "watch", str(log), "--replay", "--ambient", "room")
    assert code == 0 and "far outside any workshop's range" in err
    out = tmp_path / "f.html"
    code, _, err = mtident("thermal", "report", str(log), "--ambient", "room", "-o", str(out))
    assert code == 0 and "resuming from" in err
    assert "warning: readings taken as °C (the log states no unit)" in err and "--unit F" in err
    assert "note: a gap of 16 min in the readings after t = 59 min" in err
    page = html.unescape(" ".join(out.read_text(encoding="utf-8").split()))
    assert "<h2>Read with warnings</h2>" in page and "far outside any workshop's range" in page
    assert "--unit F" in page and "temperature_unit" not in page
    assert "<h2>How the log was read</h2>" in page and "a gap of 16 min" in page
    assert "<h2>How the intervals narrowed</h2>" in page and page.count('src="data:image/png;base64,') == 2


def test_the_reports_warnings_carry_their_times_in_the_order_said(tmp_path):
    """The report listed the latest check's warnings first, without their times ("column: flat
    against the room ..."), and the earlier ones, with theirs, after them: as the watch said them."""
    t = np.arange(0.0, 200.0)
    rng = np.random.default_rng(3)
    columns = frozen_channel(t, rng)
    late = np.clip(t - 35.0, 0.0, None)
    columns["T3"] = np.round(20.0 + 5.0 * (1.0 - np.exp(-late / 40.0)) + rng.normal(0.0, 0.01, t.size), 3)
    columns["room"] = np.round(20.0 + rng.normal(0.0, 0.01, t.size), 3)
    log = tmp_path / "log.csv"
    log.write_text(csv_text(t, columns))
    out = tmp_path / "r.html"
    code, _, err = mtident("thermal", "report", str(log), "--ambient", "room", "-o", str(out))
    assert code == 0, err
    page = html.unescape(out.read_text(encoding="utf-8"))
    said = re.findall(r"<li>(.*?)</li>", page.split("<h2>Warnings</h2>", 1)[1].split("</ul>", 1)[0], re.S)
    assert said and all(w.startswith("t = ") for w in said), said
    times = [float(w.split("t = ", 1)[1].split(" ", 1)[0]) for w in said]
    assert times == sorted(times) and any("T2: its readings froze at one value" in w for w in said)
    assert any("T3: flat against the room until" in w for w in said), said


def test_a_dropped_reference_is_said_by_the_report_and_a_resumed_watch_and_assumed_by_neither(tmp_path):
    """A new user's trial: the reference was dropped at the log's end (most sensors contradicting
    it), which watch said on stderr only; a resumed watch's JSON then lost it, and the report listed
    every sensor's reference among what the answer assumes. Another machine's reference here (every
    time constant x0.45 of this one's)."""
    import json

    from mtident.thermal.reference import MachineReference
    from mtident.thermal.robust_types import SensorModes

    modes = SensorModes((8.0, 60.0), (0.1, 0.1), (-4.0, -6.0), None)
    reference = tmp_path / "small.toml"
    save_reference(
        MachineReference("small.csv", "2026-11-20", 300.0, "not measured", {n: modes for n in "ABCD"}), reference
    )
    t = np.arange(0.0, 120.0, 0.5)
    rng = np.random.default_rng(3)

    def sensor(fast: float, slow: float) -> np.ndarray:
        return 30.0 - 4.0 * np.exp(-t / slow) - 6.0 * np.exp(-t / fast) + rng.normal(0.0, 0.01, t.size)

    log = tmp_path / "test.csv"
    columns = [sensor(8.0 / 0.45, 60.0 / 0.45)] * 3 + [sensor(8.0, 60.0)]
    log.write_text(csv_text(t, dict(zip("ABCD", columns, strict=True))))
    code, out, err = mtident("thermal", "watch", str(log), "--replay", "--reference", str(reference), "--json")
    assert code == 0, err
    dropped = [w for w in json.loads(out)["log_warnings"] if "contradicted by 3 of the 4" in w]
    assert len(dropped) == 1 and dropped[0] in err
    assert "forecasting each sensor's expected stop (4 sensors" in err  # the minute it may take is said
    code, out, err = mtident(
        "thermal", "watch", str(log), "--replay", "--resume", "--reference", str(reference), "--json"
    )
    assert code == 0 and "resuming from" in err, err
    assert json.loads(out)["log_warnings"] == [dropped[0]]
    assert f"mtident: warning: (said before) {dropped[0]}" in " ".join(err.split())
    assert "forecasting" not in err  # saved with the state
    page_path = tmp_path / "test.html"
    code, _, err = mtident("thermal", "report", str(log), "--reference", str(reference), "-o", str(page_path))
    assert code == 0 and "resuming from" in err, err
    page = html.unescape(page_path.read_text(encoding="utf-8"))
    assert "contradicted by 3 of the 4 sensors it knows (A, B, C)" in page
    assumed = page[page.index("What the answer assumes") :][:2000]
    assert "reference for" not in assumed and "small.csv" not in assumed
    assert "reference: not used (the test contradicted it; see the warnings)" in assumed
