"""Tests of :mod:`mtident.testing.real_curves`."""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from mtident.testing.warmups import (
    load_real_curves,
)

REAL_DATA = Path(__file__).resolve().parents[2].parent / "shared" / "realdata"


@pytest.mark.skipif(not REAL_DATA.is_dir(), reason="../shared/realdata not beside the repository")
def test_real_curves() -> None:
    curves = {curve.name: curve for curve in load_real_curves(REAL_DATA)}
    assert set(curves) == {
        "tclab_step50_run1:T1",
        "tclab_step50_run1:T2",
        "tclab_step50_run3_T1:T1",
    }
    for name in ("tclab_step50_run1:T1", "tclab_step50_run3_T1:T1"):
        curve = curves[name]
        assert curve.rounding_C == pytest.approx(0.32, abs=0.01)
        assert curve.time_min[-1] == pytest.approx(15.0, abs=0.1)
        assert 55.0 < curve.settled_C < 65.0 and curve.last_quarter_rise < 0.01
        assert 4.0 < curve.t95_min < 12.0
    lagged = curves["tclab_step50_run1:T2"]
    assert math.isnan(lagged.settled_C) and math.isnan(lagged.t95_min)
    assert lagged.end_C - lagged.start_C > 10.0
