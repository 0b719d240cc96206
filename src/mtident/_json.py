"""Numbers for JSON answers."""

from __future__ import annotations

import math

__all__ = ["finite_or_none"]


def finite_or_none(value: float) -> float | None:
    """A float for JSON, or None where it is not finite (JSON has no NaN or infinity).

    Parameters
    ----------
    value : float
        Any number (a numpy scalar too); it is converted with ``float``.

    Returns
    -------
    float or None
        ``value`` as a plain float, or None where it is NaN or ±infinity.

    Examples
    --------
    >>> finite_or_none(1.5), finite_or_none(float("nan")), finite_or_none(float("inf"))
    (1.5, None, None)
    """
    value = float(value)
    return value if math.isfinite(value) else None
