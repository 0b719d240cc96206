"""Helpers that tests of more than one module share."""

from __future__ import annotations

import math

import numpy as np

from mtident.feeddrive import (
    Excitation,
    FeedDriveParameters,
    Response,
)

# A heavy, soft drive (a 400 kg table on a 20 mm lead): every mode below 110 Hz.
HEAVY = FeedDriveParameters(
    Mt=400.0,
    Mb=40.0,
    Jm=4e-3,
    Jb=6e-3,
    K1=1.0e7,
    K2=1.5e7,
    K3=700.0,
    K4=250.0,
    beta=0.02 / (2 * math.pi),
    Bt=20.0,
    Bb=20.0,
    Qm=0.05,
    Qb=0.05,
)


def _sweep_note_of(kind: str) -> list[str]:
    """What the identification says of an excitation's force, 0.3 s of it at 10 kHz."""
    from mtident.feeddrive.identify_notes import sweep_note

    h = 1e-4
    return sweep_note(Excitation(kind).forces(np.arange(0.0, 0.3, h)), h)


def _noisy_forces(record: Response, fraction: float, seed: int) -> Response:
    """``record`` with white noise of ``fraction`` of each force column's RMS on its forces (a force sensor
    or a motor current is measured too)."""
    rms = np.sqrt(np.mean(record.forces**2, axis=0))
    noise = fraction * rms * np.random.default_rng(seed).standard_normal(record.forces.shape)
    return Response(record.time_s, record.forces + noise, record.values)
