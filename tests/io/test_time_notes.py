"""Tests of :mod:`mtident.io.time_notes`: what the readers say of a time column (its unit, serial
dates, gaps, the hints that minutes are seconds or hours).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
from conftest import through_state_file

from mtident.exceptions import InputError
from mtident.io import read_temperature_log


def test_a_time_column_in_seconds_read_as_minutes_gets_a_hint(write_csv, tmp_path):
    """A 2-h log in seconds under a plain 'Time' header read as 5 days of minutes; identify then
    said 'use a longer --window' and watch called the sensor 'no rise', with no word on the unit."""
    from mtident.io.follow import LogFollower

    text = "Time,T1\n" + "".join(f"{s},{20 + s / 7200:.4f}\n" for s in range(0, 7201, 10))
    log = read_temperature_log(write_csv(text))
    assert any(
        "time column 'Time' is read as minutes" in n and "7200 min (5.0 days)" in n and "give `time_unit='s'`" in n
        for n in log.notes
    )
    assert not any("read as minutes" in n for n in read_temperature_log(write_csv(text), time_unit="s").notes)
    assert not any(
        "read as minutes" in n for n in read_temperature_log(write_csv(text.replace("Time,", "Time_s,"))).notes
    )
    live = tmp_path / "live.csv"
    live.write_text(text)
    warnings = LogFollower(live).poll().warnings
    assert sum("read as minutes" in w for w in warnings) == 1


def test_a_time_column_in_seconds_with_a_sparse_step_gets_a_hint_before_two_days(write_csv, tmp_path):
    """A newcomer's later test in seconds (a reading every 30 s) under a plain 'time' header, cut at
    20 min as a live log would be: read as 1,200 minutes it looked settled, watch stopped 1.2-1.3 °C
    low, and the hint on seconds could come only after two days of 'minutes'."""
    from mtident.io.follow import LogFollower

    text = "time,T1\n" + "".join(f"{s},{20 + 6 * (1 - np.exp(-s / 1800)):.2f}\n" for s in range(0, 1201, 30))
    log = read_temperature_log(write_csv(text))
    assert any("a reading every 30 min: if it is in seconds, give `time_unit='s'`" in n for n in log.notes)
    assert not any("read as minutes" in n for n in read_temperature_log(write_csv(text), time_unit="s").notes)
    minutes = "time,T1\n" + "".join(f"{m},{20 + m / 100:.2f}\n" for m in range(0, 120, 2))
    assert not any("read as minutes" in n for n in read_temperature_log(write_csv(minutes)).notes)
    live = tmp_path / "live.csv"
    live.write_text(text)
    follower = LogFollower(live)
    assert sum("a reading every 30 min" in w for w in follower.poll().warnings) == 1
    with live.open("a") as more:
        more.write("".join(f"{s},26.00\n" for s in range(1230, 1500, 30)))
    assert not any("read as minutes" in w for w in follower.poll().warnings)


def test_a_time_unit_given_against_the_columns_own_is_said(write_csv, tmp_path):
    """`--time-unit min` on a column named 'time_s' read its seconds as minutes with no word, and
    watch stopped 1.2 °C low."""
    from mtident.io.follow import LogFollower

    text = "time_s,T1\n" + "".join(f"{s},{20 + s / 600:.2f}\n" for s in range(0, 600, 30))
    said = "time column 'time_s' states its unit as s, but `time_unit='min'` reads it in min"
    assert any(said in n for n in read_temperature_log(write_csv(text), time_unit="min").notes)
    assert not any("states its unit" in n for n in read_temperature_log(write_csv(text), time_unit="s").notes)
    assert not any("states its unit" in n for n in read_temperature_log(write_csv(text)).notes)
    live = tmp_path / "live.csv"
    live.write_text(text)
    assert sum(said in n for n in LogFollower(live, time_unit="min").poll().notes) == 1


def test_spreadsheet_serial_dates_are_named_not_read_as_minutes(write_csv):
    """A date cell saved as a number (46348.33333 is 22.11.2026 08:00): read as minutes, a 2-h
    test lasted 0.08 min and was identified as λ = 23/min, "fits". In a column named as dates it
    is read in days, with a note (both readers, also resumed); in any other it is refused with the
    unit to give; --time-unit d reads it, --time-unit min as minutes."""
    from mtident.io.follow import LogFollower

    rows = "".join(f"{46348.333333 + k / 1440:.8f},{26.7 - 8.8 * np.exp(-0.016 * k):.2f}\n" for k in range(60))
    path = write_csv("Time,T1\n" + rows)
    with pytest.raises(
        InputError,
        match=r"'Time' looks like spreadsheet serial dates \(days since 30.12.1899: 46348.33333 is 22.11.2026 08:00:00\), not minutes: give `time_unit='d'`",
    ):
        read_temperature_log(path)
    np.testing.assert_allclose(read_temperature_log(path, time_unit="d").time_min, np.arange(60.0), atol=1e-4)
    assert read_temperature_log(path, time_unit="min").time_min[-1] == pytest.approx(59 / 1440, abs=1e-6)
    dated = write_csv("Date,T1\n" + rows, "dated.csv")
    log = read_temperature_log(dated)
    np.testing.assert_allclose(log.time_min, np.arange(60.0), atol=1e-4)
    said = "time column 'Date' read as spreadsheet serial dates (days since 30.12.1899: 46348.33333 is 22.11.2026 08:00:00); give `time_unit='min'` if it is minutes"
    assert log.notes == (said,)
    live = write_csv("Date,T1\n" + "".join(rows.splitlines(True)[:30]), "live.csv")
    follower = LogFollower(live)
    first = follower.poll()
    assert first.notes == (said,)
    live.write_text("Date,T1\n" + rows)
    second = LogFollower.resume(live, through_state_file(follower.position()), None, None).poll()
    np.testing.assert_allclose(np.concatenate([first.time_min, second.time_min]), np.arange(60.0), atol=1e-4)


def test_a_time_column_in_hours_read_as_minutes_gets_a_hint(write_csv, tmp_path):
    """A 14-h log in hours under a plain 't' header read as 14 minutes at a reading every 0.5 s:
    identify gave a 3-min t_eq, trusted, and watch flipped between 'may stop' and 'undetermined',
    with no word on the unit."""
    from mtident.io.follow import LogFollower

    text = "t,T1\n" + "".join(f"{k / 120:.5f},{20 + 8 * (1 - np.exp(-k / 120)):.2f}\n" for k in range(1681))
    log = read_temperature_log(write_csv(text))
    assert any("runs only to 14 min with a reading every 0.5 s" in n and "time_unit='h'" in n for n in log.notes)
    assert not any("read as minutes" in n for n in read_temperature_log(write_csv(text), time_unit="h").notes)
    short = "t,T1\n" + "".join(f"{k / 120:.5f},{20 + k / 100:.2f}\n" for k in range(50))
    assert not any("read as minutes" in n for n in read_temperature_log(write_csv(short)).notes)
    live = tmp_path / "live.csv"
    live.write_text(text)
    follower = LogFollower(live)
    assert sum("time_unit='h'" in w for w in follower.poll().warnings) == 1


@pytest.mark.parametrize("header", ["time_min", "Time [min]"])
def test_decimal_clock_hours_under_a_name_that_states_minutes_get_a_hint(write_csv, tmp_path, header):
    """A trial's log held decimal clock hours (8.0 to 20.0, a reading a minute) in a column named
    ``time_min``: read as 12 minutes as its name states, with no word that it may be hours."""
    from mtident.io.follow import LogFollower

    rows = "".join(f"{8 + k / 60:.4f},{20 + 8 * (1 - np.exp(-k / 60)):.2f}\n" for k in range(721))
    text = f"{header},T1\n" + rows
    said = [n for n in read_temperature_log(write_csv(text)).notes if "time_unit='h'" in n]
    assert len(said) == 1 and said[0].startswith(f"time column {header!r} is read as minutes, as its name")
    assert "runs only to 12 min with a reading every 1 s" in said[0]
    assert not any("time_unit='h'" in n for n in read_temperature_log(write_csv(text), time_unit="min").notes)
    minutes = f"{header},T1\n" + "".join(f"{k},{20 + k / 100:.2f}\n" for k in range(721))
    assert not any("time_unit='h'" in n for n in read_temperature_log(write_csv(minutes)).notes)
    live = tmp_path / "live.csv"
    live.write_text(text)
    assert sum("time_unit='h'" in w for w in LogFollower(live).poll().warnings) == 1


def test_a_gap_in_the_readings_and_a_unit_given_for_time_stamps_are_said(write_csv, tmp_path):
    """A newcomer's log with 40 minutes missing: inspect still said 'a step of 30 s', and neither
    identify nor watch mentioned the gap; --time-unit s given for a stamp column was ignored silently."""
    from mtident.io.follow import LogFollower

    minutes = [m / 2 for m in range(240) if not 120 <= m < 200]
    text = "time_min,A\n" + "".join(f"{m:g},{20 + m / 100:.3f}\n" for m in minutes)
    path = write_csv(text)
    gap = "a gap of 40.5 min in the readings after t = 59.5 min (otherwise a reading every 30 s): the fit bridges it"
    assert gap in read_temperature_log(path).notes
    said = LogFollower(Path(path)).poll().notes
    assert any(n.startswith("a gap of 40.5 min in the readings after t = 59.5 min") for n in said)
    stamps = "time,A\n" + "".join(f"2026-11-25 08:{m:02d}:00,{20 + m / 100:.2f}\n" for m in range(30))
    notes = read_temperature_log(write_csv(stamps), time_unit="s").notes
    assert "time column 'time' holds time stamps: the unit 's' given for it is not used" in notes
    assert not any("gap" in n or "not used" in n for n in read_temperature_log(write_csv(stamps)).notes)
