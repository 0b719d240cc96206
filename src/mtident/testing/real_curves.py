"""Real warm-up curves beside the project (``../shared/realdata``): each heating channel of a
measured record, with where it settled and its 95 % time read off the readings.
"""

from __future__ import annotations

import csv
import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.ndimage import median_filter

from mtident._typing import FloatArray
from mtident.exceptions import InputError
from mtident.testing.structures import EQUILIBRIUM_FRACTION

__all__ = ["RealCurve", "load_real_curves"]


@dataclass(frozen=True)
class RealCurve:
    """One heating channel of a measured record.

    Attributes
    ----------
    name : str
        ``"<file stem>:<column>"``.
    time_min : ndarray, shape (N,)
        Sample times from the record's start (as logged, not necessarily even).
    reading_C : ndarray, shape (N,)
    settled_C : float
        Median of the last 5 % of the readings when the record settled (the last quarter rose
        under 1 % of the total rise), else NaN: then the record shows no equilibrium to score
        against.
    t95_min : float
        First time a running median of the readings reaches start + 0.95·(settled − start),
        interpolated between samples; NaN when not settled or not reached.
    rounding_C : float
        The logger's quantisation, read off the spacing of the distinct readings.
    start_C : float
        Median of the first three readings.
    end_C : float
        Median of the last 5 % of the readings, settled or not.
    last_quarter_rise : float
        What the last quarter rose, as a fraction of the total rise.
    """

    name: str
    time_min: FloatArray
    reading_C: FloatArray
    settled_C: float
    t95_min: float
    rounding_C: float
    start_C: float
    end_C: float
    last_quarter_rise: float


def _time_column(names: list[str]) -> tuple[str, float]:
    """The time column and its factor to minutes (seconds unless the name says minutes)."""
    for name in names:
        low = name.lower()
        if low.startswith("time") or low in ("t", "t_s", "t_min"):
            return name, (1.0 if low.endswith("min") else 1.0 / 60.0)
    raise InputError(f"no time column among {names}")


def _real_curve(name: str, t: FloatArray, y: FloatArray) -> RealCurve | None:
    keep = np.isfinite(t) & np.isfinite(y)
    t, y = t[keep] - t[keep][0], y[keep]
    n = len(y)
    if n < 40:
        return None
    distinct = np.unique(y)
    steps = np.diff(distinct)
    rounding = float(np.round(np.median(steps), 4)) if steps.size else 0.0
    start = float(np.median(y[:3]))
    tail = max(3, n // 20)
    end = float(np.median(y[-tail:]))
    rise = end - start
    if rise < max(1.0, 10.0 * rounding):  # not a heat-up (flat, or cooling)
        return None
    mark = int(0.75 * n)
    quarter = float(np.median(y[max(0, mark - tail // 2) : mark + tail // 2 + 1]))
    last_quarter = (end - quarter) / rise
    settled = end if last_quarter < 0.01 else math.nan
    t95 = math.nan
    if math.isfinite(settled):
        smooth = median_filter(y, size=max(5, (n // 100) | 1), mode="nearest")
        level = start + EQUILIBRIUM_FRACTION * (settled - start)
        past = np.flatnonzero(smooth >= level)
        if past.size and past[0] > 0:
            k = int(past[0])
            t95 = float(t[k - 1] + (level - smooth[k - 1]) / (smooth[k] - smooth[k - 1]) * (t[k] - t[k - 1]))
    return RealCurve(name, t, y, settled, t95, rounding, start, end, last_quarter)


def load_real_curves(folder: Path) -> list[RealCurve]:
    """Every heating channel of every CSV in ``folder`` (the project's ``../shared/realdata``).

    Temperature channels are the columns named T1, T2, … (TCLab); time is the column whose name
    starts with "Time", in seconds unless it ends in "min". A channel is kept when it rises by
    more than max(1 °C, 10 rounding steps) from its first three readings to its last 5 %.

    Parameters
    ----------
    folder : Path

    Returns
    -------
    list of RealCurve
        Sorted by file name, then column.

    Raises
    ------
    InputError
        A CSV without a time column.
    """
    curves = []
    for path in sorted(Path(folder).glob("*.csv")):
        with path.open(newline="") as handle:
            rows = list(csv.reader(handle))
        header, body = rows[0], [r for r in rows[1:] if r]
        time_name, factor = _time_column(header)
        data = np.array([[float(v) if v.strip() else math.nan for v in r] for r in body])
        t = data[:, header.index(time_name)] * factor
        for j, name in enumerate(header):
            if len(name) > 1 and name[0] in "Tt" and name[1:].isdigit():
                curve = _real_curve(f"{path.stem}:{name}", t, data[:, j])
                if curve is not None:
                    curves.append(curve)
    return curves
