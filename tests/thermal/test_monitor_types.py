"""Tests of :mod:`mtident.thermal.monitor_types`."""

from __future__ import annotations

import pytest

from mtident.exceptions import InputError
from mtident.thermal.monitor import MonitorSettings


def test_bad_settings_are_refused():
    with pytest.raises(InputError, match="tolerance_C: expected a positive number"):
        MonitorSettings(tolerance_C=float("nan"))
    with pytest.raises(InputError, match="decision_level: expected a probability"):
        MonitorSettings(decision_level=1.0)
