"""Tests of :mod:`mtident.io.whole`: a whole log's readings left out, skipped and refused, each named
by its row."""

from __future__ import annotations

import numpy as np
import pytest

from mtident.exceptions import InputError
from mtident.io import read_temperature_log


def test_isolated_bad_samples_are_skipped_with_a_note(write_csv):
    rows = "".join(f"{k},{20 + k * 0.1 if k not in (3, 7) else ('' if k == 3 else 850.0)}\n" for k in range(30))
    log = read_temperature_log(write_csv("time_min,A\n" + rows))
    assert np.isnan(log.temperature_C[3, 0]) and np.isnan(log.temperature_C[7, 0])
    assert log.notes == ("sensor 'A': skipped 1 empty/NaN and 1 open-circuit sample(s) (rows 5, 9)",)


def test_a_stretch_of_lost_readings_is_said_as_one_run_of_rows(write_csv):
    """A sensor blank for 40 readings was said as its first five rows, "rows 42, 43, 44, 45, 46,
    ...", which reads as five lost readings."""
    rows = "".join(f"{k},{'' if 40 <= k < 80 or k == 90 else 20 + k * 0.01}\n" for k in range(500))
    log = read_temperature_log(write_csv("time_min,A\n" + rows))
    assert log.notes == ("sensor 'A': skipped 41 empty/NaN sample(s) (rows 42-81, 92)",)


def test_a_burnout_marker_is_an_open_circuit_sample(write_csv):
    """Graphtec writes BURNOUT for a broken thermocouple's reading: it stopped the file reader
    ("'BURNOUT' is not a number") where the live follower bridged it."""
    rows = "".join(f"{k},{'BURNOUT' if k in (7, 9) else f'{20 + k / 10:.2f}'}\n" for k in range(30))
    log = read_temperature_log(write_csv("time_min,A\n" + rows))
    assert log.notes == ("sensor 'A': skipped 2 open-circuit sample(s) (rows 9, 11)",)
    assert np.isnan(log.temperature_C[[7, 9], 0]).all() and log.temperature_C[8, 0] == 20.8


@pytest.mark.parametrize(
    ("marker", "kind"),
    [
        ("OVL", "open-circuit"),
        ("-OL", "open-circuit"),
        ("O.L.", "open-circuit"),
        ("Err", "open-circuit"),
        ("#VALUE!", "empty/NaN"),
        ("----", "empty/NaN"),
    ],
)
def test_more_loggers_markers_are_bad_samples_not_a_refused_log(write_csv, marker, kind):
    """A new user's loggers wrote OVL, -OL, O.L., Err, #VALUE! and ---- in place of readings: watch
    skipped them, inspect and identify refused the whole log ("'OVL' is not a number")."""
    rows = "".join(f"{k},{marker if k in (7, 9) else f'{20 + k / 10:.2f}'}\n" for k in range(30))
    log = read_temperature_log(write_csv("time_min,A\n" + rows))
    assert log.notes == (f"sensor 'A': skipped 2 {kind} sample(s) (rows 9, 11)",)


def test_a_row_written_twice_is_left_out_and_said(write_csv):
    """A logger flushing its buffer again wrote a row twice; the run ended with 'duplicate time'.
    The same time with other readings is still refused."""
    rows = "".join(f"{k},{20 + k / 10:.2f}\n" for k in range(20))
    log = read_temperature_log(write_csv("time_min,A\n" + rows.replace("5,20.50\n", "5,20.50\n5,20.50\n")))
    assert len(log.time_min) == 20 and "left out 1 row(s) repeating an earlier row exactly (rows 8)" in log.notes
    with pytest.raises(InputError, match="duplicate time"):
        read_temperature_log(write_csv("time_min,A\n" + rows.replace("5,20.50\n", "5,20.50\n5,20.60\n")))


def test_rows_after_a_row_left_out_are_named_by_their_own_line(write_csv):
    """A message names the row as the file numbers it: a repeated row left out before it made the
    reader name the row above."""
    rows = "".join(f"{k},{20 + k / 10:.2f},{21 + k / 10:.2f}\n" for k in range(20))
    twice = rows.replace("3,20.30,21.30\n", "3,20.30,21.30\n3,20.30,21.30\n")
    log = read_temperature_log(write_csv("time_min,A,B\n" + twice.replace("8,20.80,", "8,,")))
    # line 1 the header, k at line k + 2, one more after the row written twice
    assert log.notes[-1] == "sensor 'A': skipped 1 empty/NaN sample(s) (rows 11)", log.notes
    with pytest.raises(InputError, match=r"sensor 'A', row 11: 'x' is not a number"):
        read_temperature_log(write_csv("time_min,A,B\n" + twice.replace("8,20.80,", "8,x,"), "bad.csv"))


def test_a_reading_limit_that_means_nothing_is_refused(write_csv):
    """``min_samples=-1`` and ``max_bad_fraction=2`` were taken without a word."""
    path = write_csv("time_min,A\n" + "".join(f"{k},{20 + k * 0.1}\n" for k in range(10)))
    with pytest.raises(InputError, match=r"min_samples must be a whole number, 1 or more, not -1"):
        read_temperature_log(path, min_samples=-1)
    with pytest.raises(InputError, match=r"max_bad_fraction must be a share between 0 and 1, not 2"):
        read_temperature_log(path, max_bad_fraction=2)


def test_a_sensor_that_failed_for_good_is_read_up_to_its_last_reading(write_csv):
    """A sensor silent from t = 350 min to the end of a 600-min log was refused as "249 of 600
    samples are empty", though `identify --window 300` needs none of them. Gaps within its readings
    still count against it."""
    rows = "".join(f"{k},{20 + k / 100:.2f},{'' if k > 350 else f'{21 + k / 100:.2f}'}\n" for k in range(600))
    log = read_temperature_log(write_csv("time_min,A,B\n" + rows))
    assert np.isnan(log.temperature_C[351:, 1]).all() and np.isfinite(log.temperature_C[:351]).all()
    # said as a failure, not as a few readings lost: a reference learnt from it rests on the readings before
    assert log.notes == (
        "sensor 'B' failed at row 353 and gave no reading to the log's end (skipped 249 empty/NaN sample(s), rows "
        "353-601): what it is answered from, and learnt from, ends there",
    )
    holes = "".join(f"{k},{20 + k / 100:.2f},{'' if k % 5 == 0 else f'{21 + k / 100:.2f}'}\n" for k in range(600))
    with pytest.raises(InputError, match="sensor 'B': 120 of 601 samples are empty"):
        read_temperature_log(write_csv("time_min,A,B\n" + holes + "600,26.00,27.00\n"))
