"""Modes of the feed drive: |K − ω²M| = 0 (Nguyen-Quoc et al. Eq. 3)."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mtident._typing import FloatArray
from mtident.feeddrive.params import (
    COORDINATES,
    FeedDriveParameters,
    damping_matrix,
    mass_matrix,
    stiffness_matrix,
    validate,
)

__all__ = ["Modes", "ModesAnswer", "modes", "sampling_problem"]


@dataclass(frozen=True, slots=True)
class ModesAnswer:
    """The modes as the JSON of ``mtident feeddrive modes`` says them.

    Attributes
    ----------
    natural_frequencies_Hz : tuple of float
        Lowest first.
    positive_definite : bool
    damping_ratios : tuple of float
    mode_shapes : dict of str to tuple of float
        Per coordinate, its component in each mode.
    """

    natural_frequencies_Hz: tuple[float, ...]
    positive_definite: bool
    damping_ratios: tuple[float, ...]
    mode_shapes: dict[str, tuple[float, ...]]


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

    def answer(self) -> ModesAnswer:
        """The modes as their JSON says them: the shapes by coordinate.

        Returns
        -------
        ModesAnswer
        """
        return ModesAnswer(
            natural_frequencies_Hz=tuple(float(f) for f in self.frequencies_Hz),
            positive_definite=self.positive_definite,
            damping_ratios=tuple(float(z) for z in self.damping_ratios),
            mode_shapes={
                name: tuple(float(v) for v in row) for name, row in zip(COORDINATES, self.shapes, strict=True)
            },
        )


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


# Samples per period of the highest mode the filter needs. Nguyen-Quoc et al. (§3.1) samples at 5-20 times
# the highest natural frequency. Below that the sigma points, which spread the stiffnesses over the
# prior's range, put the highest mode near or past the Nyquist frequency; the filter then settles
# with intervals that miss the truth by tens of standard deviations, or diverges.
SAMPLES_PER_PERIOD = 5.0


def sampling_problem(p: FeedDriveParameters, sample_rate_Hz: float, name: str = "the parameters") -> str | None:
    """Why a record sampled at ``sample_rate_Hz`` cannot be identified with modes like those of ``p``, or None.

    Parameters
    ----------
    p : FeedDriveParameters
        The parameters whose modes the filter must follow (the guess).
    sample_rate_Hz : float
    name : str
        What ``p`` is, in the message ("the guess").

    Returns
    -------
    str or None
        One line naming the highest mode, the rate it needs and the modes the rate does follow.

    Examples
    --------
    >>> print(sampling_problem(FeedDriveParameters(), 10_000.0))
    None
    >>> sampling_problem(FeedDriveParameters(), 1_000.0).split(":")[0]
    'sampling at 1000 Hz cannot follow mode 4 of the parameters (1444 Hz)'
    """
    frequencies = modes(p).frequencies_Hz
    needed = SAMPLES_PER_PERIOD * frequencies[-1]
    if sample_rate_Hz >= needed:
        return None
    followed = int(np.sum(SAMPLES_PER_PERIOD * frequencies <= sample_rate_Hz))
    which = f"modes 1-{followed} only" if followed > 1 else "mode 1 only" if followed == 1 else "none of the four modes"
    return (
        f"sampling at {sample_rate_Hz:g} Hz cannot follow mode 4 of {name} ({frequencies[-1]:.0f} Hz): "
        f"the filter needs {SAMPLES_PER_PERIOD:g} samples per period of the highest mode, a rate of at least "
        f"{needed:.0f} Hz; at {sample_rate_Hz:g} Hz it follows {which}, and all four act in every response"
    )
