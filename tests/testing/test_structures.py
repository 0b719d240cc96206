"""Tests of :mod:`mtident.testing.structures`."""

from __future__ import annotations

import numpy as np
from helpers import PAPER_TAU, one_mode_reference, replay


def test_a_drifting_room_measured_by_a_room_sensor_stops_within_the_tolerance():
    """The room is an input of every mode: a 0.3 °C air-conditioning cycle does not bias T∞."""
    from mtident.testing.warmups import Machine, simulate

    rate = 1.0 / PAPER_TAU
    machine = Machine(
        "network",
        np.array([[-rate]]),
        np.array([8.8 * rate]),
        np.array([rate]),
        np.array([1.0]),
        (PAPER_TAU,),
        "one node",
    )
    drift = {
        "amplitude_C": 0.3,
        "period_min": 240.0,
        "phase_rad": 0.5,
        "slope_C_per_h": 0.0,
        "noise_C": 0.02,
        "rounding_C": 0.01,
    }
    warm = simulate(machine, np.random.default_rng(8), duration_min=400.0, room_drift=drift, room_start_C=17.9)
    state = replay(
        {"S": warm.reading_C}, warm.time_min, warm.room_C, reference=one_mode_reference("S"), room_sensor="room"
    )
    assert state.stopped
    stop = int(np.searchsorted(warm.time_min, state.stop_time_min))
    assert abs(state.checks[0].steady_C - warm.steady_C[stop]) < 0.2
