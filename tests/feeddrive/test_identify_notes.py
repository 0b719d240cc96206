"""Tests of :mod:`mtident.feeddrive.identify_notes`."""

from __future__ import annotations

import pytest
from feeddrive_helpers import _sweep_note_of


@pytest.mark.parametrize("kind", ["sweep", "multisine"])
def test_a_swept_excitation_is_said_to_bias_damping(kind):
    """Sweeps and Schroeder multisines (a periodic chirp) gave biased damping in simulation: the
    identification says so, from the force alone."""
    said = _sweep_note_of(kind)
    assert len(said) == 1
    assert said[0].startswith("the excitation sweeps through its band (F_t_N from about ")
    assert "biased beyond their own intervals" in said[0]


@pytest.mark.parametrize("kind", ["prbs", "impulse", "step", "sine"])
def test_the_other_excitations_are_not_called_sweeps(kind):
    assert _sweep_note_of(kind) == []
