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
