"""`mtident thermal report`: the write-up of a finished or stopped warm-up test."""

from __future__ import annotations

import numpy as np
from click.testing import CliRunner
from test_watch import T, csv_text, first_order, noisy, one_mode_reference

from mtident.cli import main
from mtident.report.test_report import reading_gaps
from mtident.thermal.reference import save_reference


def report(*args: str) -> tuple[int, str, str]:
    outcome = CliRunner().invoke(main, ["thermal", "report", *args], catch_exceptions=False)
    return outcome.exit_code, outcome.stdout, outcome.stderr


def logged_test(tmp_path, steady_b: float = 29.0):  # noqa: ANN001, ANN201
    log = tmp_path / "run.csv"
    log.write_text(csv_text(T, {"A": noisy(first_order(T), 21), "B": noisy(first_order(T, steady=steady_b), 22)}))
    reference = tmp_path / "machine.toml"
    save_reference(one_mode_reference("A", "B"), reference)
    return log, reference


def test_the_html_report_says_the_decision_each_sensor_and_what_it_rests_on(tmp_path):
    log, reference = logged_test(tmp_path)
    out = tmp_path / "report.html"
    code, stdout, err = report(str(log), "--reference", str(reference), "--free-fast-modes", "0", "-o", str(out))
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
    code, _, err = report(str(log), "--reference", str(reference), "--free-fast-modes", "0", "-o", str(out))
    assert code == 0, err
    data = out.read_bytes()
    assert data.startswith(b"%PDF") and data.count(b"/Type /Page\n") + data.count(b"/Type /Page ") >= 2


def test_a_test_that_cannot_stop_is_reported_with_the_reason(tmp_path):
    t = np.arange(0.0, 90.0)
    log = tmp_path / "short.csv"
    log.write_text(csv_text(t, {"S": noisy(first_order(t), 23)}))
    out = tmp_path / "short.html"
    code, stdout, err = report(str(log), "-o", str(out))
    assert code == 0, err
    assert stdout.endswith("no stop within the log\n")
    page = out.read_text(encoding="utf-8")
    assert "No stop within the log (to 89 min)" in page and "Why not yet:" in page and "still fits" in page


def test_stretches_without_readings_are_said(tmp_path):
    # a recorder stopped from minute 40 to 70: the report says so
    t = np.concatenate([np.arange(0.0, 41.0), np.arange(70.0, 120.0)])
    log = tmp_path / "gappy.csv"
    log.write_text(csv_text(t, {"S": noisy(first_order(t), 24)}))
    out = tmp_path / "gappy.html"
    code, _, err = report(str(log), "-o", str(out))
    assert code == 0, err
    assert "to t = 119 min; none from 40 min to 70 min</dd>" in out.read_text(encoding="utf-8")
    assert reading_gaps(np.arange(10.0)) == ()
    assert reading_gaps(np.array([0.0, 1.0, 2.0, 9.0, 10.0])) == ((2.0, 9.0),)


def test_a_recorded_log_says_where_it_was_recorded_from_and_its_state_file_is_left_alone(tmp_path):
    log, reference = logged_test(tmp_path)
    (tmp_path / "run.csv.opcua.json").write_text(
        '{"url": "opc.tcp://vmc1:4840", "nodes": ["ns=2;s=A", "ns=2;s=B"], "names": ["A", "B"], '
        '"origin": "2026-11-24T08:00:00+00:00", "last_stamp": {}}'
    )
    code, _, err = report(
        str(log), "--reference", str(reference), "--free-fast-modes", "0", "-o", str(tmp_path / "r.html")
    )
    assert code == 0, err
    assert "recorded from opc.tcp://vmc1:4840 (nodes ns=2;s=A, ns=2;s=B); t = 0 is 2026-11-24T08:00:00+00:00</dd>" in (
        tmp_path / "r.html"
    ).read_text(encoding="utf-8")
    assert not (tmp_path / "run.csv.watch-state.npz").exists()


def test_report_refuses_what_it_cannot_write_or_read(tmp_path):
    log, _ = logged_test(tmp_path)
    code, _, err = report(str(log), "-o", str(tmp_path / "report.docx"))
    assert code == 2 and "give a name ending in .html or .pdf" in err
    code, _, err = report(str(tmp_path / "none.csv"), "-o", str(tmp_path / "r.html"))
    assert code == 2 and "no such file" in err
    code, _, err = report(str(log), "-o", str(tmp_path / "missing" / "r.html"))
    assert code == 2 and "does not exist" in err
