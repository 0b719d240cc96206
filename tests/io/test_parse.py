"""Tests of :mod:`mtident.io.parse`."""

from __future__ import annotations

import numpy as np

from mtident.io import read_temperature_log


def test_the_file_reader_reads_its_lines_with_the_followers_function(write_csv):
    """One log reader: the rows of a whole log are parse_lines' over the layout, read as a whole log."""
    from mtident.io.layout import layout_of_head
    from mtident.io.log_file import read_lines
    from mtident.io.parse import TimeState, WholeLog, parse_lines

    rows = "".join(
        f"{k};{20 + k / 10:.2f};{'' if k == 7 else f'{21 + k / 10:.2f}'}\n".replace(".", ",") for k in range(20)
    )
    path = write_csv("# logger\ntime_min;A;B\n" + rows)
    log = read_temperature_log(path)
    lines, dialect = read_lines(path)
    layout, _ = layout_of_head(lines[0], [dialect.cells(line) for line in lines[1:]], dialect, path)
    state, whole = parse_lines(layout, TimeState(), lines[1:], str(path), whole=WholeLog(3))
    _, live = parse_lines(layout, TimeState(), lines[1:], str(path))
    np.testing.assert_array_equal(whole.time_min, log.time_min)
    np.testing.assert_array_equal(whole.temperature_C, log.temperature_C)
    np.testing.assert_array_equal(live.temperature_C, log.temperature_C)
    assert whole.notes == log.notes == ("sensor 'B': skipped 1 empty/NaN sample(s) (rows 10)",)
    assert state.last_time == live.time_min[-1] == 19.0 and whole.warnings == ()
