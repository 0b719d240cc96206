"""Feed drives and records for benchmarks and tests: random drives the project never saw, a heavy
one, and noise on a record's measured forces.

Masses, inertias, lead, stiffnesses and damping are drawn log-uniformly around Nguyen-Quoc et al.'s Table 1
over the ranges of machine-tool feed drives (a 5-200 kg table, a 5-32 mm lead); the stiffnesses
are drawn so that K is positive definite (K2 > K1, K3 > K4 + β²K1, see :func:`~.params.validate`).
Randomness comes only from the ``np.random.Generator`` passed in (or the seed).
"""

from __future__ import annotations

import math

import numpy as np

from mtident.exceptions import MtidentError
from mtident.feeddrive.params import FeedDriveParameters, validate
from mtident.feeddrive.simulate import Response

__all__ = ["random_drive", "random_guess", "with_force_noise", "HEAVY_DRIVE", "LEADS_M"]

# Ball-screw leads on the market, m.
LEADS_M = (0.005, 0.01, 0.016, 0.02, 0.025, 0.032)

# A heavy, soft drive (a 400 kg table on a 20 mm lead): every mode below 110 Hz.
HEAVY_DRIVE = FeedDriveParameters(
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


def with_force_noise(record: Response, fraction: float, seed: int) -> Response:
    """``record`` with white noise of ``fraction`` of each force column's RMS on its forces (a force sensor
    or a motor current is measured too).

    Parameters
    ----------
    record : Response
    fraction : float
        The noise's standard deviation, a fraction of each force column's RMS.
    seed : int
        Seed of the noise.

    Returns
    -------
    Response
        The same times and responses, the forces with noise.
    """
    rms = np.sqrt(np.mean(record.forces**2, axis=0))
    noise = fraction * rms * np.random.default_rng(seed).standard_normal(record.forces.shape)
    return Response(record.time_s, record.forces + noise, record.values)
