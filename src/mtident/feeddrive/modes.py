"""Modes of the feed drive: |K − ω²M| = 0 (seed 004 Eq. 3)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mtident._typing import FloatArray
from mtident.feeddrive.params import FeedDriveParameters, damping_matrix, mass_matrix, stiffness_matrix, validate

__all__ = ["Modes", "modes"]


@dataclass(frozen=True, slots=True)
class Modes:
    """Undamped modes, lowest first.

    Attributes
    ----------
    frequencies_Hz : ndarray, shape (4,)
    shapes : ndarray, shape (4, 4)
        Column j is mode j, mass-normalised (ΦᵀMΦ = I) and scaled so its
        largest component is positive.
    damping_ratios : ndarray, shape (4,)
        ζⱼ = (ΦᵀCΦ)ⱼⱼ / (2ωⱼ) (the modal damping, neglecting off-diagonal coupling).
    positive_definite : bool
    """

    frequencies_Hz: FloatArray
    shapes: FloatArray
    damping_ratios: FloatArray
    positive_definite: bool


def modes(p: FeedDriveParameters) -> Modes:
    """Natural frequencies, mode shapes and damping ratios of a validated parameter set.

    Examples
    --------
    >>> modes(FeedDriveParameters()).frequencies_Hz.round(2).tolist()
    [103.94, 266.54, 1082.43, 1443.79]
    """
    validate(p)
    m, k = mass_matrix(p), stiffness_matrix(p)
    from scipy.linalg import eigh  # here, not at the top: the thermal commands never need it

    eigenvalues, shapes = eigh(k, m)
    omega = np.sqrt(eigenvalues)
    signs = np.sign(shapes[np.argmax(np.abs(shapes), axis=0), np.arange(4)])
    shapes = shapes * signs
    modal_damping = np.diag(shapes.T @ damping_matrix(p) @ shapes)
    return Modes(omega / (2.0 * np.pi), shapes, modal_damping / (2.0 * omega), bool(np.all(eigenvalues > 0)))
