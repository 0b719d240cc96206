"""Tests of :mod:`mtident.report.plots`."""

from __future__ import annotations

import subprocess
import sys

import pytest


@pytest.mark.slow
def test_plots_leave_the_users_matplotlib_alone_and_return_a_figure_without_a_path():
    """Importing the plots used to switch matplotlib to Agg: a notebook's inline plots stopped showing."""
    code = (
        "import matplotlib; matplotlib.use('svg'); import mtident.report as r; "
        "from mtident.io import read_temperature_log; from mtident.io import sample_log_path; "
        "from mtident.thermal import identify; "
        "fig = r.plot_identification(identify(read_temperature_log(sample_log_path()).select(['T1', 'T2']), 30.0, "
        "'ukf')); "
        "print(matplotlib.get_backend(), type(fig).__name__, len(fig.axes))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300, check=False)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split() == ["svg", "Figure", "2"]


def test_the_timeline_picture_draws_each_sensors_reach_down_to_the_tolerance_and_the_stop():
    """How the intervals narrowed: one line per sensor through the checks that had an interval, at
    the reach of the decision's interval from T∞, the tolerance and the stop drawn, on a log scale."""
    import numpy as np
    from conftest import first_order
    from helpers import T, noisy, one_mode_reference

    from mtident.report.plots import plot_timeline
    from mtident.thermal.monitor import monitor_step, new_state
    from mtident.thermal.monitor_types import MonitorSettings
    from mtident.thermal.robust_types import RobustSettings

    settings = MonitorSettings(reference=one_mode_reference("A", "B"), robust=RobustSettings(free_fast_modes=0))
    values = np.c_[noisy(first_order(T[:101]), 3), noisy(first_order(T[:101], steady=25.0), 4)]
    state, _ = monitor_step(new_state(["A", "B"]), T[:101], values, None, settings)
    assert state.stopped
    (ax,) = plot_timeline(state, settings).axes
    lines = {line.get_label(): line for line in ax.get_lines()}
    assert ax.get_yscale() == "log" and {"A", "B", "tolerance 0.2 °C"} <= set(lines)
    assert f"stop at {state.stop_time_min:g} min" in lines
    for s, name in enumerate(("A", "B")):
        mine = state.timeline[state.timeline[:, 1] == s]
        reach = np.fmax(mine[:, 3] - mine[:, 6], mine[:, 7] - mine[:, 3])
        np.testing.assert_allclose(lines[name].get_ydata(), reach[np.isfinite(reach)])
        assert lines[name].get_ydata()[-1] <= 0.2
