"""Random feed drives for benchmarks and property tests: drives the project never saw.

Masses, inertias, lead, stiffnesses and damping are drawn log-uniformly around Nguyen-Quoc et al.'s Table 1
over the ranges of machine-tool feed drives (a 5-200 kg table, a 5-32 mm lead); the stiffnesses
are drawn so that K is positive definite (K2 > K1, K3 > K4 + β²K1, see :func:`~.params.validate`).
Randomness comes only from the ``np.random.Generator`` passed in.
"""

from __future__ import annotations

import math

import numpy as np

from mtident.exceptions import MtidentError
from mtident.feeddrive.params import FeedDriveParameters, validate

__all__ = ["random_drive", "random_guess", "LEADS_M"]

# Ball-screw leads on the market, m.
LEADS_M = (0.005, 0.01, 0.016, 0.02, 0.025, 0.032)


def _log_uniform(rng: np.random.Generator, low: float, high: float) -> float:
    return float(np.exp(rng.uniform(np.log(low), np.log(high))))


def random_drive(rng: np.random.Generator) -> FeedDriveParameters:
    """A random, stable feed drive.

    Parameters
    ----------
    rng : numpy.random.Generator

    Returns
    -------
    FeedDriveParameters

    Examples
    --------
    >>> from mtident.feeddrive.modes import modes
    >>> bool(modes(random_drive(np.random.default_rng(0))).positive_definite)
    True
    """
    beta = float(rng.choice(LEADS_M)) / (2 * math.pi)
    k1 = _log_uniform(rng, 5e7, 5e8)
    k4 = _log_uniform(rng, 200.0, 3000.0)
    return validate(
        FeedDriveParameters(
            Mt=_log_uniform(rng, 5.0, 200.0),
            Mb=_log_uniform(rng, 1.0, 8.0),
            Jm=_log_uniform(rng, 5e-6, 5e-4),
            Jb=_log_uniform(rng, 3e-5, 1e-3),
            K1=k1,
            K2=k1 * rng.uniform(1.1, 3.0),
            K3=(k4 + beta**2 * k1) * rng.uniform(1.1, 2.0),
            K4=k4,
            beta=beta,
            Bt=_log_uniform(rng, 0.5, 20.0),
            Bb=_log_uniform(rng, 0.5, 20.0),
            Qm=_log_uniform(rng, 5e-4, 1e-2),
            Qb=_log_uniform(rng, 5e-4, 1e-2),
        )
    )


def random_guess(truth: FeedDriveParameters, rng: np.random.Generator, off: float = 0.3) -> FeedDriveParameters:
    """``truth`` with each identified parameter ``off`` high or low at random, redrawn until stable.

    Parameters
    ----------
    truth : FeedDriveParameters
    rng : numpy.random.Generator
    off : float
        Relative error of each identified parameter.

    Returns
    -------
    FeedDriveParameters
    """
    while True:
        factors = 1.0 + off * rng.choice([-1.0, 1.0], size=8)
        try:
            return validate(truth.with_identified(truth.identified() * factors))
        except MtidentError:
            continue
