"""How each sensor's answer narrowed to the stop: the live monitor's checks as one table.

The monitor keeps every check in its state (:attr:`~mtident.thermal.monitor_types.MonitorState.timeline`),
so a resumed watch, a replay and a report see the same history. As a table it is one row per
check of a sensor, in the watch answer's names: when (``checked_at_min``), the sensor, its status,
T∞ and its 95 % and decision intervals. A spreadsheet or a notebook draws how the interval closed
in on T∞ from it; ``watch --timeline`` writes it as CSV.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from mtident.thermal.monitor_types import STATUSES, TIMELINE_COLUMNS, MonitorState

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["check_timeline", "write_timeline"]

_COLUMN = {name: i for i, name in enumerate(TIMELINE_COLUMNS)}


def check_timeline(state: MonitorState) -> pd.DataFrame:
    """Every check the monitor made so far, one row per sensor checked, in the order made.

    Parameters
    ----------
    state : MonitorState

    Returns
    -------
    pandas.DataFrame
        Columns ``checked_at_min``, ``sensor``, ``status``, ``steady_state_C``, ``ci95_low_C``,
        ``ci95_high_C``, ``decision_low_C``, ``decision_high_C`` (°C; NaN where a check had no
        interval). Empty for a state saved before the monitor kept its checks.

    Examples
    --------
    >>> from mtident.thermal.monitor import new_state
    >>> check_timeline(new_state(("T1",))).columns.tolist()[:3]
    ['checked_at_min', 'sensor', 'status']
    """
    import pandas as pd  # only for the table: a watch without --timeline starts without it

    rows = np.asarray(state.timeline, dtype=float).reshape(-1, len(TIMELINE_COLUMNS))

    def column(name: str) -> np.ndarray:
        values = rows[:, _COLUMN[name]]
        # an interval with no end is no number a spreadsheet reads: blank, as a check without one
        return np.where(np.isfinite(values), values, np.nan)

    return pd.DataFrame(
        {
            "checked_at_min": column("checked_min"),
            "sensor": [state.sensors[int(i)] for i in rows[:, _COLUMN["sensor"]]],
            "status": [STATUSES[int(i)] for i in rows[:, _COLUMN["status"]]],
            "steady_state_C": column("steady_C"),
            "ci95_low_C": column("low95_C"),
            "ci95_high_C": column("high95_C"),
            "decision_low_C": column("low_C"),
            "decision_high_C": column("high_C"),
        }
    )


def write_timeline(state: MonitorState, path: str | Path) -> Path:
    """Write :func:`check_timeline` as CSV (atomically: a spreadsheet open on it never sees half a file).

    Parameters
    ----------
    state : MonitorState
    path : str or Path

    Returns
    -------
    Path
        The file written.
    """
    target = Path(path)
    partial = target.with_name(target.name + ".part")
    check_timeline(state).to_csv(partial, index=False, float_format="%.4f")
    partial.replace(target)
    return target
