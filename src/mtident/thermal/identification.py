"""A first-order identification's answer (the papers' filters, or least squares): each sensor's
curve over the window and on, T∞ with its interval, the model check and the measured equilibrium,
and one sensor's summary for the JSON.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

from mtident._json import finite_or_none
from mtident._typing import BoolArray, FloatArray

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["FIRST_ORDER_ASSUMPTIONS", "Identification", "Z95", "sensor_notes"]

Z95 = 1.959963984540054


@dataclass(frozen=True)
class Identification:
    """The identified warm-up of every sensor of a log, arrays with a sensor axis S.

    Attributes
    ----------
    sensors : tuple of str
    method, preset : str
    window_min : float
        Identification time L actually used (time of the last sample ≤ L).
    n_window : int
        The number of samples in the window.
    time_min : ndarray, shape (N,)
        The log's sample times, then the forecast horizon beyond it.
    measured_C : ndarray, shape (N, S)
        The log's readings at ``time_min``, NaN past the log's end.
    curve_C, curve_sd_C : ndarray, shape (N, S)
        Estimated temperature (filtered up to L, predicted after) and its standard deviation.
    steady_state_C, steady_state_sd_C, rate_per_min, rate_sd_per_min, start_C : ndarray, shape (S,)
    equilibrium_time_min : ndarray, shape (S,)
        Predicted time to 95 % of the total rise, from the start of the log.
    rmse_C : ndarray, shape (S,)
        Xia et al. 2014 Eq. 33 over all measured samples.
    fit_chi2, fit_autocorr : ndarray, shape (S,)
        Residual test of the first-order model inside the window.
    fits : ndarray of bool, shape (S,)
        The residual test passed; where it failed the interval was widened.
    quantile : float
        Multiplier of the standard deviations for the 95 % intervals: Student's t
        with N − 3 degrees of freedom, because the noise level is estimated
        from the same N samples.
    history : ndarray, shape (L, S, 3)
        Filtered state at each sample up to L (convergence plots).
    history_sd : ndarray, shape (L, S, 3)
    measured_final_C, measured_equilibrium_time_min : ndarray, shape (S,)
        From the log itself where it reached equilibrium, else NaN.
    notes : tuple of str
    quantile : float
    measured_settled : ndarray of bool, shape (S,), optional
        Whether the log's last quarter moved less than ``SETTLED_MOVE_C``, with at most half that
        still to come at the pace of the largest time constant: only then is the measured final
        temperature where the sensor settles to the tolerance's precision.
    untrusted : ndarray of bool, shape (S,), optional
        An answer no physics allows, or fitted to a few minutes of rise (said in ``notes``):
        ``model_ok`` is then false.
    """

    sensors: tuple[str, ...]
    method: str
    preset: str
    window_min: float
    n_window: int
    time_min: FloatArray
    measured_C: FloatArray
    curve_C: FloatArray
    curve_sd_C: FloatArray
    steady_state_C: FloatArray
    steady_state_sd_C: FloatArray
    rate_per_min: FloatArray
    rate_sd_per_min: FloatArray
    start_C: FloatArray
    equilibrium_time_min: FloatArray
    rmse_C: FloatArray
    fit_chi2: FloatArray
    fit_autocorr: FloatArray
    fits: BoolArray
    history: FloatArray
    history_sd: FloatArray
    measured_final_C: FloatArray
    measured_equilibrium_time_min: FloatArray
    notes: tuple[str, ...]
    quantile: float = Z95
    measured_settled: np.ndarray | None = None
    untrusted: np.ndarray | None = None

    def __repr__(self) -> str:
        # a notebook shows the answer, not ~40 kB of arrays
        lines = [
            f"Identification({self.method}/{self.preset}, L = {self.window_min:g} min, {len(self.sensors)} sensor(s))"
        ]
        for i, name in enumerate(self.sensors):
            half = self.quantile * self.steady_state_sd_C[i]
            lines.append(
                f"  {name}: T∞ {self.steady_state_C[i]:.2f} ± {half:.2f} °C, λ {self.rate_per_min[i]:.4g}/min, "
                f"t_eq {self.equilibrium_time_min[i]:.0f} min, RMSE {self.rmse_C[i]:.3f} "
                f"°C{'' if self.fits[i] else ', model check failed'}"
            )
        return "\n".join(lines)

    def curve_frame(self) -> pd.DataFrame:
        """The measured and modelled curve of every sensor with its 95 % band, a row per time: for
        a report or a spreadsheet. ``part`` says whether the row is in the identification window
        (the filtered curve) or after it (the prediction); a time past the log's end has no
        measured value.

        Returns
        -------
        pandas.DataFrame
            Columns ``time_min``, ``part`` ("window" or "prediction") and per sensor ``NAME_measured_C``,
            ``NAME_model_C``, ``NAME_low95_C`` and ``NAME_high95_C`` (°C).
        """
        import pandas as pd

        half = self.quantile * self.curve_sd_C
        columns: dict[str, object] = {
            "time_min": self.time_min,
            "part": np.where(self.time_min <= self.window_min + 1e-9, "window", "prediction"),
        }
        for s, name in enumerate(self.sensors):
            columns[f"{name}_measured_C"] = self.measured_C[:, s]
            columns[f"{name}_model_C"] = self.curve_C[:, s]
            columns[f"{name}_low95_C"] = self.curve_C[:, s] - half[:, s]
            columns[f"{name}_high95_C"] = self.curve_C[:, s] + half[:, s]
        return pd.DataFrame(columns)

    def band_C(self) -> tuple[FloatArray, FloatArray]:
        """The curve's 95 % band, low and high, each (N, S).

        Returns
        -------
        low, high : ndarray, shape (N, S)
            The band's ends (°C).
        """
        half = self.quantile * self.curve_sd_C
        return self.curve_C - half, self.curve_C + half

    def steady_state_ci95(self) -> FloatArray:
        """(S, 2) 95 % interval of T∞.

        Returns
        -------
        ndarray, shape (S, 2)
            The low and high end of each sensor's interval (°C).
        """
        half = self.quantile * self.steady_state_sd_C
        return np.column_stack([self.steady_state_C - half, self.steady_state_C + half])

    def summary(self, index: int) -> dict[str, object]:
        """The JSON object of one sensor (the documentation's JSON page), plus extras.

        Parameters
        ----------
        index : int
            The sensor's position in ``sensors``.

        Returns
        -------
        dict
            JSON types: T∞ with its interval, λ, the time constant, the equilibrium time, the RMSE, the
            model check, the sensor's warnings and what the answer assumes; None where a value is not
            finite.
        """
        lo, hi = self.steady_state_ci95()[index]
        rate = float(self.rate_per_min[index])
        name = self.sensors[index]
        undetermined = not (np.isfinite(lo) and np.isfinite(hi))
        return {
            "sensor": name,
            "method": self.method,
            "preset": self.preset,
            "window_min": float(self.window_min),
            "steady_state_C": finite_or_none(self.steady_state_C[index]),
            "steady_state_ci95_C": [finite_or_none(lo), finite_or_none(hi)],
            "lambda_per_min": finite_or_none(rate),
            "lambda_sd_per_min": finite_or_none(self.rate_sd_per_min[index]),
            "time_constant_min": 1.0 / rate if rate > 0 else None,
            "start_C": finite_or_none(self.start_C[index]),
            "total_rise_C": finite_or_none(self.steady_state_C[index] - self.start_C[index]),
            "equilibrium_time_min": finite_or_none(self.equilibrium_time_min[index]),
            "rmse_C": finite_or_none(self.rmse_C[index]),
            "model_fits": bool(self.fits[index]),
            "model_ok": bool(self.fits[index])
            and not undetermined
            and not (self.untrusted is not None and self.untrusted[index]),
            "warnings": sensor_notes(self.notes, name),
            "assumptions": FIRST_ORDER_ASSUMPTIONS,
            "residual_chi2": finite_or_none(self.fit_chi2[index]),
            "measured_final_C": finite_or_none(self.measured_final_C[index]),
            "measured_equilibrium_time_min": finite_or_none(self.measured_equilibrium_time_min[index]),
            "measured_settled": None
            if self.measured_settled is None or not np.isfinite(self.measured_final_C[index])
            else bool(self.measured_settled[index]),
        }


FIRST_ORDER_ASSUMPTIONS: dict[str, object] = {
    "model": "first order (one exponential, the papers' model): the interval assumes a first-order machine; "
    "a slower mode not yet seen moves T∞ beyond it",
    "max_time_constant_min": None,
    "room": "the room at its level in the window (or the room sensor's course, where given)",
    "reference": None,
}


def sensor_notes(notes: tuple[str, ...], sensor: str) -> list[str]:
    """The notes that name ``sensor`` (as 'NAME' or NAME:), and those that name no sensor of a list.

    Parameters
    ----------
    notes : tuple of str
        A log's or an identification's notes.
    sensor : str
        The sensor's name.

    Returns
    -------
    list of str
        The notes that name ``sensor``, in their order.
    """
    return [n for n in notes if repr(sensor) in n or n.startswith(f"{sensor}:")]
