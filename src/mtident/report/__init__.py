"""Plots (PNG) and terminal tables."""

from mtident.report.plots import (
    plot_feed_drive_identification,
    plot_identification,
    plot_min_time,
    plot_monitor,
    plot_responses,
)

__all__ = ["plot_identification", "plot_min_time", "plot_monitor", "plot_responses", "plot_feed_drive_identification"]
