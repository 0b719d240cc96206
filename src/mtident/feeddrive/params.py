"""Ball-screw feed drive parameters (Nguyen-Quoc et al., Table 1) and the matrices of Eq. 2.

Parameter files are TOML with Table 1's names in SI units::

    Mt = 15.0          # table mass, kg
    Mb = 2.56          # screw mass, kg
    Jm = 1.73e-5       # motor inertia, kg m²
    Jb = 1.4475e-4     # screw inertia, kg m²
    K1 = 1.374e8       # nut stiffness, N/m
    K2 = 1.874e8       # equivalent axial stiffness of the screw, N/m
    K3 = 1153.93       # equivalent torsional stiffness, N m/rad
    K4 = 717.0         # torsional stiffness screw-motor, N m/rad
    beta = 1.5915e-3   # lead/(2π), m/rad
    Bt = 1.0           # guideway damping, N s/m
    Bb = 1.0           # support-bearing axial damping, N s/m
    Qm = 0.002         # motor rotational damping, N m s/rad
    Qb = 0.002         # support-bearing rotational damping, N m s/rad

β is printed in Table 1 as 2.55e-3 "Nm/rad"; it is the lead/(2π) in m/rad, and
the printed value makes K indefinite (the documentation's Theory page). The default
uses β = 0.01/(2π), which reproduces the paper's frequencies.
"""

from __future__ import annotations

import math
import numbers
import tomllib
from dataclasses import asdict, dataclass, fields, replace
from pathlib import Path

import numpy as np

from mtident._typing import FloatArray
from mtident.exceptions import InputError, MtidentError, UnstableModelError

__all__ = [
    "FeedDriveParameters",
    "IDENTIFIED",
    "load_parameters",
    "mass_matrix",
    "damping_matrix",
    "stiffness_matrix",
    "validate",
    "PRINTED_BETA",
    "COORDINATES",
    "DESCRIPTIONS",
    "parameter_template",
]

PRINTED_BETA = 2.55e-3
COORDINATES = ("table", "screw", "screw_rotation", "motor_rotation")
# The parameters the UKF estimates (Nguyen-Quoc et al. Eq. 37, state x9..x16).
IDENTIFIED = ("K1", "K2", "K3", "K4", "Bt", "Bb", "Qb", "Qm")
UNITS = {
    "Mt": "kg",
    "Mb": "kg",
    "Jm": "kg m²",
    "Jb": "kg m²",
    "K1": "N/m",
    "K2": "N/m",
    "K3": "N m/rad",
    "K4": "N m/rad",
    "beta": "m/rad",
    "Bt": "N s/m",
    "Bb": "N s/m",
    "Qm": "N m s/rad",
    "Qb": "N m s/rad",
}
# What each parameter is (Nguyen-Quoc et al., Table 1).
DESCRIPTIONS = {
    "Mt": "mass of the working table",
    "Mb": "mass of the ball screw",
    "Jm": "moment of inertia of the motor",
    "Jb": "moment of inertia of the ball screw",
    "K1": "stiffness of the ball-screw nut",
    "K2": "equivalent axial stiffness of the screw",
    "K3": "equivalent torsional stiffness of the screw",
    "K4": "torsional stiffness between screw and motor",
    "beta": "lead / (2π): table travel per radian of the screw",
    "Bt": "viscous damping of the table's guideway",
    "Bb": "axial viscous damping of the screw's support bearing",
    "Qm": "rotational viscous damping of the motor",
    "Qb": "rotational viscous damping of the support bearing",
}


@dataclass(frozen=True, slots=True)
class FeedDriveParameters:
    """The 4-DOF lumped model of a ball-screw feed drive, SI units.

    Defaults: Nguyen-Quoc et al. Table 1 with the corrected β = 0.01/(2π) m/rad.

    Parameters
    ----------
    Mt : float
        Mass of the working table (kg).
    Mb : float
        Mass of the ball screw (kg).
    Jm : float
        Moment of inertia of the motor (kg m²).
    Jb : float
        Moment of inertia of the ball screw (kg m²).
    K1 : float
        Stiffness of the ball-screw nut (N/m).
    K2 : float
        Equivalent axial stiffness of the screw (N/m).
    K3 : float
        Equivalent torsional stiffness of the screw (N m/rad).
    K4 : float
        Torsional stiffness between screw and motor (N m/rad).
    beta : float
        Lead / (2π): table travel per radian of the screw (m/rad).
    Bt : float
        Viscous damping of the table's guideway (N s/m).
    Bb : float
        Axial viscous damping of the screw's support bearing (N s/m).
    Qm : float
        Rotational viscous damping of the motor (N m s/rad).
    Qb : float
        Rotational viscous damping of the support bearing (N m s/rad).
    """

    Mt: float = 15.0
    Mb: float = 2.56
    Jm: float = 1.73e-5
    Jb: float = 1.4475e-4
    K1: float = 1.374e8
    K2: float = 1.874e8
    K3: float = 1153.93
    K4: float = 717.0
    beta: float = 0.01 / (2.0 * math.pi)
    Bt: float = 1.0
    Bb: float = 1.0
    Qm: float = 0.002
    Qb: float = 0.002

    def identified(self) -> FloatArray:
        """The eight identified parameters in the order of ``IDENTIFIED``."""
        return np.array([getattr(self, name) for name in IDENTIFIED])

    def with_identified(self, values: FloatArray) -> FeedDriveParameters:
        """A copy with the eight identified parameters replaced.

        Parameters
        ----------
        values : ndarray, shape (8,)
            New values of K1..K4 (N/m, N/m, N m/rad, N m/rad), Bt, Bb (N s/m), Qb, Qm (N m s/rad), in the
            order of ``IDENTIFIED``.

        Returns
        -------
        FeedDriveParameters
            The same masses, inertias and β with those values (not checked).
        """
        return replace(self, **{name: float(v) for name, v in zip(IDENTIFIED, values, strict=True)})

    def as_dict(self) -> dict[str, float]:
        """Name → value."""
        return asdict(self)


def mass_matrix(p: FeedDriveParameters) -> FloatArray:
    """[M] of Eq. 2 for coordinates (x_t, x_b, θ_b, θ_m).

    Parameters
    ----------
    p : FeedDriveParameters
        Its masses Mt, Mb (kg) and inertias Jb, Jm (kg m²) are used.

    Returns
    -------
    ndarray, shape (4, 4)
        diag(Mt, Mb, Jb, Jm).
    """
    return np.diag([p.Mt, p.Mb, p.Jb, p.Jm])


def damping_matrix(p: FeedDriveParameters) -> FloatArray:
    """[C] of Eq. 2.

    Parameters
    ----------
    p : FeedDriveParameters
        Its dampings Bt, Bb (N s/m) and Qb, Qm (N m s/rad) are used.

    Returns
    -------
    ndarray, shape (4, 4)
        diag(Bt, Bb, Qb, Qm) for the coordinates (x_t, x_b, θ_b, θ_m).
    """
    return np.diag([p.Bt, p.Bb, p.Qb, p.Qm])


def stiffness_matrix(p: FeedDriveParameters) -> FloatArray:
    """[K] of Eq. 2.

    Parameters
    ----------
    p : FeedDriveParameters
        Its stiffnesses K1, K2 (N/m), K3, K4 (N m/rad) and β (m/rad) are used.

    Returns
    -------
    ndarray, shape (4, 4)
        The symmetric stiffness matrix for the coordinates (x_t, x_b, θ_b, θ_m): the nut K1 couples
        table, screw and screw rotation (through β), K4 couples the screw and the motor rotations.
    """
    b, k1 = p.beta, p.K1
    return np.array(
        [
            [k1, -k1, -b * k1, 0.0],
            [-k1, p.K2, b * k1, 0.0],
            [-b * k1, b * k1, p.K3, -p.K4],
            [0.0, 0.0, -p.K4, p.K4],
        ]
    )


def validate(p: FeedDriveParameters) -> FeedDriveParameters:
    """Refuse a parameter set that is not a physical, stable model.

    Masses, inertias, stiffnesses and β must be positive, damping non-negative,
    and K symmetric positive definite. Eliminating x_t shows K is positive
    definite exactly when K2 > K1 and K3 − β²K1 > K4, so the error names which
    of these fails.

    Parameters
    ----------
    p : FeedDriveParameters
        The set to check.

    Returns
    -------
    FeedDriveParameters
        ``p`` itself, unchanged, when it passes.

    Raises
    ------
    InputError
        A value of the wrong sign, or not finite.
    UnstableModelError
        K is not positive definite (the model would be unstable).
    """
    if not isinstance(p, FeedDriveParameters):
        msg = (
            f"a feed drive is given as FeedDriveParameters (FeedDriveParameters(K1=..., ...) or "
            f"load_parameters(path)), not {type(p).__name__}"
        )
        raise InputError(msg)
    for name in ("Mt", "Mb", "Jm", "Jb", "K1", "K2", "K3", "K4", "beta"):
        value = getattr(p, name)
        if not isinstance(value, numbers.Real) or isinstance(value, bool):
            msg = f"parameter {name} = {value!r}: must be a number ({UNITS[name]})"
            raise InputError(msg)
        if not (math.isfinite(value) and float(value) > 0):
            msg = f"parameter {name} = {value!r}: must be a positive number ({UNITS[name]})"
            raise InputError(msg)
    for name in ("Bt", "Bb", "Qm", "Qb"):
        value = getattr(p, name)
        if not isinstance(value, numbers.Real) or isinstance(value, bool):
            msg = f"parameter {name} = {value!r}: must be a number ({UNITS[name]})"
            raise InputError(msg)
        if not (math.isfinite(value) and float(value) >= 0):
            msg = f"parameter {name} = {value!r}: damping must be zero or positive ({UNITS[name]})"
            raise InputError(msg)
    if p.K2 <= p.K1:
        msg = f"K2 = {p.K2:.6g} ≤ K1 = {p.K1:.6g}: K is not positive definite, the model is unstable"
        raise UnstableModelError(msg)
    coupling = p.beta**2 * p.K1
    if p.K3 - coupling <= p.K4:
        hint = ""
        if abs(p.beta - PRINTED_BETA) < 1e-9:
            hint = (
                " (β = 2.55e-3 is the value printed in Nguyen-Quoc et al.'s Table 1; β = lead/(2π) = 0.01/(2π) "
                "≈ 1.5915e-3 "
                "m/rad reproduces the paper's frequencies)"
            )
        msg = (
            f"K3 < K4 + β²·K1 ({p.K3:.6g} < {p.K4:.6g} + {coupling:.6g} N m/rad): K is indefinite, "
            f"the model is unstable{hint}"
        )
        raise UnstableModelError(msg)
    return p


def parameter_template(p: FeedDriveParameters | None = None) -> str:
    """A commented TOML parameter file: every name with its unit, meaning and value (default: the shipped set).

    :func:`load_parameters` reads it back to the same set.

    Parameters
    ----------
    p : FeedDriveParameters, optional

    Returns
    -------
    str

    Examples
    --------
    >>> print(parameter_template().splitlines()[5])
    Mt = 15.0  # kg: mass of the working table
    """
    p = p or FeedDriveParameters()
    shipped = FeedDriveParameters()
    lines = [
        "# Ball-screw feed drive parameters, SI units (names of Nguyen-Quoc et al., Table 1).",
        "# Values: "
        + ("the shipped set (Nguyen-Quoc et al.'s Table 1, β corrected)." if p == shipped else "as given."),
        "# Delete a line to keep the shipped value. mtident identifies K1-K4, Bt, Bb, Qb and Qm;",
        "# Mt, Mb, Jm, Jb and beta are taken as known.",
        "",
    ]
    for f in fields(FeedDriveParameters):
        value = float(getattr(p, f.name))
        short = f"{value:.6g}"
        text = short if float(short) == value else repr(value)  # short where it reads back exactly
        if f.name == "beta":
            lines.append(
                f"# Table 1 prints β = {PRINTED_BETA:g} 'Nm/rad', which makes K indefinite; "
                "0.01/(2π) reproduces its frequencies"
            )
        number = text if any(c in text for c in ".en") else text + ".0"  # a TOML float, not an integer
        lines.append(f"{f.name} = {number}  # {UNITS[f.name]}: {DESCRIPTIONS[f.name]}")
    return "\n".join(lines) + "\n"


def load_parameters(path: str | Path | None, base: FeedDriveParameters | None = None) -> FeedDriveParameters:
    """Read a TOML parameter file over ``base`` (default: the shipped set) and validate it.

    Parameters
    ----------
    path : str or Path or None
        The TOML file: Table 1's names (``Mt``, ``K1``, ``beta``, ...) with numbers in SI units; a
        name it leaves out keeps its value in ``base``. None reads no file and validates ``base`` alone.
    base : FeedDriveParameters, optional
        The values the file is read over (default: the shipped set).

    Returns
    -------
    FeedDriveParameters
        The validated set.

    Raises
    ------
    InputError
        Missing file, bad TOML, unknown name, non-numeric value.
    UnstableModelError
        The set gives an indefinite K.
    """
    params = base or FeedDriveParameters()
    if path is None:
        return validate(params)
    file = Path(path)
    if not file.is_file():
        msg = f"{path}: no such parameter file"
        raise InputError(msg)
    try:
        data = tomllib.loads(file.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as exc:
        msg = f"{path}: not valid TOML ({exc})"
        raise InputError(msg) from exc
    known = {f.name for f in fields(FeedDriveParameters)}
    unknown = sorted(set(data) - known)
    if unknown:
        msg = f"{path}: unknown parameter {unknown[0]!r}; the names are: {', '.join(sorted(known))}"
        raise InputError(msg)
    values = {}
    for name, value in data.items():
        if isinstance(value, bool) or not isinstance(value, int | float):
            msg = f"{path}: parameter {name} = {value!r} is not a number"
            raise InputError(msg)
        values[name] = float(value)
    try:
        return validate(replace(params, **values))
    except MtidentError as exc:  # the same kind, said with the file it came from
        raise type(exc)(f"{path}: {exc}") from exc
