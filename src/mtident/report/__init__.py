"""Plots (PNG) and terminal tables."""

from mtident.report.plots import plot_identification, plot_min_time

__all__ = ["plot_identification", "plot_min_time"]
