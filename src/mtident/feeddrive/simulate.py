"""Vibration response of the feed drive by classical RK4 (Nguyen-Quoc et al. §2.2, Eqs 10-14 corrected)."""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.feeddrive.model import Excitation, accelerations, exact_step, input_matrix, rk4_linear_step, system_matrix
from mtident.feeddrive.params import FeedDriveParameters, validate

__all__ = [
    "Response",
    "simulate",
    "run_responses",
    "write_response",
    "read_response",
    "RESPONSE_COLUMNS",
    "FORCE_COLUMNS",
    "substeps_for",
]

RESPONSE_COLUMNS = (
    "x_t_m",
    "x_b_m",
    "theta_b_rad",
    "theta_m_rad",
    "v_t_m_per_s",
    "v_b_m_per_s",
    "omega_b_rad_per_s",
    "omega_m_rad_per_s",
    "a_t_m_per_s2",
    "a_b_m_per_s2",
    "alpha_b_rad_per_s2",
    "alpha_m_rad_per_s2",
)
FORCE_COLUMNS = ("F_t_N", "F_b_N", "T_b_Nm", "T_m_Nm")


@dataclass(frozen=True, slots=True)
class Response:
    """Sampled response of the four coordinates.

    Attributes
    ----------
    time_s : ndarray, shape (N,)
    forces : ndarray, shape (N, 4)
        Generalized forces, held over each sample.
    values : ndarray, shape (N, 12)
        Displacements, velocities and accelerations (``RESPONSE_COLUMNS``), NaN where not measured.
    """

    time_s: FloatArray
    forces: FloatArray
    values: FloatArray

    @property
    def sample_rate_Hz(self) -> float:
        """1 / the sampling interval."""
        return 1.0 / float(self.time_s[1] - self.time_s[0])

    def __repr__(self) -> str:
        measured = [
            name for name, column in zip(RESPONSE_COLUMNS, self.values.T, strict=True) if np.isfinite(column).any()
        ]
        rate = f" at {self.sample_rate_Hz:g} Hz" if len(self.time_s) > 1 else ""
        return f"Response({len(self.time_s)} samples{rate}, {len(measured)} of 12 responses: {', '.join(measured)})"


def substeps_for(p: FeedDriveParameters, h: float, max_phase_step: float = 0.01) -> int:
    """RK4 sub-steps (a power of two) so that ω_max·h/substeps ≤ ``max_phase_step``.

    Parameters
    ----------
    p : FeedDriveParameters
        The drive; ω_max is the largest eigenvalue magnitude of its A (rad/s).
    h : float
        Sampling interval (s).
    max_phase_step : float, optional
        Largest phase advance of the fastest mode per sub-step (rad).

    Returns
    -------
    int
        The smallest power of two (1 or more) that meets the bound.
    """
    omega = np.abs(np.linalg.eigvals(system_matrix(p))).max()
    needed = max(1, int(np.ceil(omega * h / max_phase_step)))
    return 1 << (needed - 1).bit_length()


def run_responses(
    p: FeedDriveParameters, phi: FloatArray, gamma: FloatArray, start: FloatArray, forces: FloatArray
) -> FloatArray:
    """The 12 responses (N, 12) from state ``start`` under ``forces`` (N, 4), stepped by (phi, gamma).

    The input over [t_k, t_k+1) is forces[k]; row 0 is ``start``.

    Parameters
    ----------
    p : FeedDriveParameters
        The drive, for the accelerations.
    phi : ndarray, shape (8, 8)
        Φ, the state transition over one sample.
    gamma : ndarray, shape (8, 4)
        Γ, the effect of the held forces over one sample.
    start : ndarray, shape (8,)
        Initial state X = [x_t, x_b, θ_b, θ_m, ẋ_t, ẋ_b, θ̇_b, θ̇_m] (m, rad, m/s, rad/s).
    forces : ndarray, shape (N, 4)
        Generalized forces (N, N, N m, N m).

    Returns
    -------
    ndarray, shape (N, 12)
        The 8 states and the 4 accelerations at each sample, as ``RESPONSE_COLUMNS`` names them.
    """
    states = np.empty((len(forces), 8))
    states[0] = start
    drive = forces[:-1] @ gamma.T
    for k in range(len(forces) - 1):
        states[k + 1] = phi @ states[k] + drive[k]
    return np.hstack([states, accelerations(p, states, forces)])


def simulate(
    p: FeedDriveParameters,
    excitation: Excitation | None = None,
    sample_rate_Hz: float = 10_000.0,
    duration_s: float = 2.0,
    noise_fraction: float = 0.0,
    rng: np.random.Generator | None = None,
    method: str = "rk4",
    substeps: int | None = None,
) -> Response:
    """Simulate the response to ``excitation`` from rest.

    Parameters
    ----------
    p : FeedDriveParameters
    excitation : Excitation
        Default: 20 N on the table for one sample (Nguyen-Quoc et al. §3.1).
    sample_rate_Hz, duration_s : float
        Default 10 kHz for 2 s, as in Nguyen-Quoc et al.
    noise_fraction : float
        White measurement noise with standard deviation ``noise_fraction`` × the
        RMS of each response (needs ``rng``).
    rng : numpy.random.Generator
        Source of the noise.
    method : {"rk4", "exact"}
        Classical RK4 (with ``substeps`` steps per sample, default enough that
        ω_max·h ≤ 0.01) or the matrix-exponential solution (the reference).

    Returns
    -------
    Response
    """
    validate(p)
    if sample_rate_Hz <= 0 or duration_s <= 0:
        msg = f"sample rate {sample_rate_Hz} Hz and duration {duration_s} s must be positive"
        raise InputError(msg)
    if not (math.isfinite(noise_fraction) and noise_fraction >= 0):
        msg = f"noise_fraction must be 0 or more (a share of each response's RMS), not {noise_fraction!r}"
        raise InputError(msg)
    if noise_fraction > 0 and not isinstance(rng, np.random.Generator):
        msg = "measurement noise needs a seeded generator (rng=np.random.default_rng(seed))" + (
            "" if rng is None else f", not {type(rng).__name__}"
        )
        raise InputError(msg)
    excitation = excitation or Excitation()
    h = 1.0 / sample_rate_Hz
    count = int(round(duration_s * sample_rate_Hz)) + 1
    time = np.arange(count, dtype=np.float64) * h
    forces = excitation.forces(time)
    a, b = system_matrix(p), input_matrix(p)
    if method == "rk4":
        phi, gamma = rk4_linear_step(a, b, h, substeps or substeps_for(p, h))
    elif method == "exact":
        phi, gamma = exact_step(a, b, h)
    else:
        msg = f"method {method!r}: expected 'rk4' or 'exact'"
        raise InputError(msg)
    values = run_responses(p, phi, gamma, np.zeros(8), forces)
    if noise_fraction > 0:
        assert rng is not None
        rms = np.sqrt(np.mean(values**2, axis=0))
        values = values + noise_fraction * rms * rng.standard_normal(values.shape)
    return Response(time, forces, np.asarray(values, dtype=np.float64))


def write_response(response: Response, path: str | Path) -> Path:
    """CSV with time_s, the four generalized forces and the twelve responses, units in the headers.

    Parameters
    ----------
    response : Response
        The record to write (NaN where a response was not measured is written as an empty cell).
    path : str or Path
        The CSV file, overwritten.

    Returns
    -------
    Path
        ``path``.
    """
    import pandas as pd

    frame = pd.DataFrame(
        np.hstack([response.time_s[:, None], response.forces, response.values]),
        columns=["time_s", *FORCE_COLUMNS, *RESPONSE_COLUMNS],
    )
    out = Path(path)
    frame.to_csv(out, index=False, float_format="%.9e")
    return out


def read_response(path: str | Path) -> Response:
    """Read a response CSV: time_s, optional force columns (default zero), any of the response columns.

    Parameters
    ----------
    path : str or Path
        The CSV file: ``time_s`` in s, evenly spaced; force columns ``FORCE_COLUMNS`` (N, N m), at
        least one; response columns named as ``RESPONSE_COLUMNS`` (SI units), at least one. Other
        columns are ignored.

    Returns
    -------
    Response
        Times put on the exact even grid from the first to the last, missing forces zero, missing
        responses NaN.

    Raises
    ------
    InputError
        Missing file, no time_s column, no known response column, uneven sampling, non-numeric cells.
    """
    import pandas as pd

    from mtident.io.log_file import read_csv

    frame, dialect = read_csv(path)
    first_row = 1 + dialect.head_lines  # the row number of the first data line in messages
    if "time_s" not in frame.columns:
        msg = f"{path}: no time_s column; the columns are: {', '.join(map(str, frame.columns))}"
        raise InputError(msg)
    measured = [c for c in RESPONSE_COLUMNS if c in frame.columns]
    if not measured:
        msg = f"{path}: no response column; expected some of: {', '.join(RESPONSE_COLUMNS)}"
        raise InputError(msg)
    if not any(c in frame.columns for c in FORCE_COLUMNS):
        # an excitation taken as zero leaves nothing to identify: the result would be the guess
        msg = (
            f"{path}: no force column; the excitation must be measured in one at least of: {', '.join(FORCE_COLUMNS)} "
            "(the others are taken as zero)"
        )
        raise InputError(msg)
    numeric = frame.apply(pd.to_numeric, errors="coerce")
    for column in ["time_s", *measured, *[c for c in FORCE_COLUMNS if c in frame.columns]]:
        bad = numeric[column].isna()
        if bad.any():
            row = int(np.argmax(bad.to_numpy()))
            raw = frame[column].iloc[row]
            what = "empty or NaN" if pd.isna(raw) else f"{str(raw)!r} is not a number"
            msg = f"{path}: column {column!r}, row {row + first_row}: {what}; every cell must be a number"
            raise InputError(msg)
    time = numeric["time_s"].to_numpy(dtype=float)
    steps = np.diff(time)
    # A time column printed with few digits (3 kHz as 0.000333, 0.000334) steps unevenly by its
    # rounding: within 1 % it is the even grid the acquisition ran on. Beyond, samples are missing
    # or the clock jittered, and a fixed-step model would be fitted to the wrong times.
    if len(time) < 10 or np.any(steps <= 0) or np.ptp(steps) > 0.01 * steps.mean():
        msg = f"{path}: time_s must be evenly spaced (within 1 %) and increasing, with at least 10 samples"
        if len(time) >= 10 and np.all(steps > 0):
            k = int(np.argmax(np.abs(steps - np.median(steps))))
            msg += (
                f"; row {k + first_row + 1} comes {steps[k]:.6g} s after the one before, against a median step of "
                f"{np.median(steps):.6g} s"
            )
        raise InputError(msg)
    time = time[0] + np.arange(len(time)) * (time[-1] - time[0]) / (len(time) - 1)
    forces = np.column_stack(
        [numeric[c].to_numpy(dtype=float) if c in frame.columns else np.zeros(len(time)) for c in FORCE_COLUMNS]
    )
    values = np.full((len(time), 12), np.nan)
    for i, column in enumerate(RESPONSE_COLUMNS):
        if column in frame.columns:
            values[:, i] = numeric[column].to_numpy(dtype=float)
    return Response(time, forces, np.asarray(values, dtype=np.float64))
