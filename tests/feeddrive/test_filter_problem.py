"""Tests of :mod:`mtident.feeddrive.filter_problem`."""

from __future__ import annotations

from mtident.feeddrive import (
    default_guess,
)
from mtident.feeddrive.identify import filter_substeps
from mtident.feeddrive.synthetic import HEAVY_DRIVE


def test_filter_substeps_follow_the_highest_mode_and_the_sampling_interval():
    guess = default_guess()
    # 10 kHz: ω·h/m ≤ 0.15 at the guess's 1580 Hz mode gives 8; the sigma points need fewer
    assert filter_substeps(guess, 1e-4, 2.0) == 8
    assert filter_substeps(guess, 2e-5, 2.0) == 2  # 50 kHz
    assert filter_substeps(HEAVY_DRIVE, 1e-3, 2.0) == 8  # 1 kHz on the heavy drive
