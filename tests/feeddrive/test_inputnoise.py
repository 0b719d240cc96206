"""Tests of :mod:`mtident.feeddrive.inputnoise`."""

from __future__ import annotations

import numpy as np
import pytest

from mtident.feeddrive import (
    Excitation,
    FeedDriveParameters,
    simulate,
)
from mtident.feeddrive.synthetic import with_force_noise


@pytest.mark.parametrize("kind", ["impulse", "step", "prbs", "sine", "sweep", "multisine"])
def test_the_force_noise_is_estimated_from_the_force_record_and_is_none_for_exact_forces(kind: str) -> None:
    """White noise on a force column is found from its differences or its spectrum's floor, whatever the
    excitation (within 25 %, a binary sequence's above rather than below); exact forces have none (under
    a thousandth of their RMS), so a record with exact forces is fitted as before."""
    from mtident.feeddrive.inputnoise import force_noise

    record = simulate(FeedDriveParameters(), Excitation(kind, frequency_Hz=100.0), duration_s=1.0)
    rms = float(np.sqrt(np.mean(record.forces[:, 0] ** 2)))
    exact = force_noise(record.forces)
    assert exact[0] < 1e-3 * rms and np.all(exact[1:] == 0)
    if kind in ("impulse", "step", "prbs"):
        assert exact[0] == 0.0
    noisy = force_noise(with_force_noise(record, 0.01, 5).forces)
    assert 0.75 * 0.01 * rms < noisy[0] < 1.25 * 0.01 * rms
    assert np.all(noisy[1:] == 0)  # a force column of zeros carries no noise at 1 % of its RMS
