"""Shared fixtures: synthetic warm-up logs."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from mtident.io.logs import TemperatureLog

# The papers' curve (seed 000 §3.1): 17.9 → 26.7 °C, λ = 0.016 /min, 1 min sampling.
PAPER_START, PAPER_STEADY, PAPER_RATE = 17.9, 26.7, 0.016


def first_order(t: np.ndarray, start: float = PAPER_START, steady: float = PAPER_STEADY, rate: float = PAPER_RATE) -> np.ndarray:
    return steady + (start - steady) * np.exp(-rate * t)


def make_log(t: np.ndarray, columns: dict[str, np.ndarray]) -> TemperatureLog:
    return TemperatureLog(t, tuple(columns), np.column_stack(list(columns.values())), (), "test")


@pytest.fixture
def write_csv(tmp_path: Path):
    def _write(text: str, name: str = "log.csv") -> Path:
        path = tmp_path / name
        path.write_text(text)
        return path

    return _write
