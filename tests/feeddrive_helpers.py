"""Helpers that tests of more than one module share."""

from __future__ import annotations

import numpy as np

from mtident.feeddrive import Excitation


def _sweep_note_of(kind: str) -> list[str]:
    """What the identification says of an excitation's force, 0.3 s of it at 10 kHz."""
    from mtident.feeddrive.identify_notes import sweep_note

    h = 1e-4
    return sweep_note(Excitation(kind).forces(np.arange(0.0, 0.3, h)), h)
