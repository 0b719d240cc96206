"""A thermal identification's answer, whatever the method: each sensor's curve over the window
and on with its 95 % band, T∞ with its interval, the verdict, what the log itself measured, and
one sensor's answer (:class:`SensorAnswer`), whose fields are its JSON object.

:class:`Identification` is the one answer; what a method adds (the papers' filters' λ and
residual test, the model-robust fit's modes) is its ``details``, behind the small
:class:`MethodDetails` protocol. The methods that build it are
:func:`~mtident.thermal.first_order.identify_first_order` (the papers' filters, least squares)
and :func:`~mtident.thermal.robust_identify.identify_robust` (the modal fit); this module imports
neither.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Generic, Protocol, TypeVar

import numpy as np

from mtident._json import SensorAnswers, json_inline
from mtident._typing import BoolArray, FloatArray

if TYPE_CHECKING:
    import pandas as pd

    from mtident.thermal.robust_types import Assumptions

__all__ = ["Identification", "MethodAnswer", "MethodDetails", "SensorAnswer", "sensor_notes"]


class MethodAnswer(Protocol):
    """A method's own part of one sensor's answer: a frozen dataclass whose fields are its keys in
    the sensor's JSON object (its λ, time constant, ...), among them what the answer assumes."""

    @property
    def assumptions(self) -> Assumptions:
        """What the sensor's interval rests on."""
        ...


class MethodDetails(Protocol):
    """What one identification method adds to the common answer.

    A method's ``index`` is the sensor's position, in the log's order of sensors.
    """

    def answer(self, index: int) -> MethodAnswer:
        """The method's own part of one sensor's answer (its λ, time constant, assumptions ...).

        Returns
        -------
        MethodAnswer
            A frozen dataclass; its fields are the method's keys of the sensor's JSON object.
        """
        ...

    def describe(self) -> list[str]:
        """Lines that say what the answer assumes, for the identification's repr.

        Returns
        -------
        list of str
            Each line indented by two spaces.
        """
        ...

    def follows_room(self, index: int) -> bool:
        """Whether the sensor's prediction after L follows the room as logged (a room input).

        Returns
        -------
        bool
        """
        ...


DetailsT = TypeVar("DetailsT", bound=MethodDetails, covariant=True)


@dataclass(frozen=True, slots=True)
class SensorAnswer:
    """One sensor's answer, whatever the method: its fields are the sensor's JSON object (the
    documentation's JSON page), NaN written as null.

    Attributes
    ----------
    sensor, method, preset : str
    window_min : float
        Identification time L actually used.
    steady_state_C : float
        T∞ (NaN where not determined).
    steady_state_ci95_C : tuple of float
        T∞'s 95 % interval, low and high.
    start_C, total_rise_C : float
        The curve's start and its rise to T∞.
    equilibrium_time_min : float
        Predicted time to 95 % of the total rise.
    rmse_C : float
        Xia et al. 2014 Eq. 33 over all measured samples.
    model_ok : bool
        Whether the answer is trusted.
    warnings : tuple of str
    measured_final_C, measured_equilibrium_time_min : float
        From the log itself where it reached equilibrium, else NaN.
    measured_settled : bool or None
        Whether the log settled to its measured final level (None where it has none).
    method_answer : MethodAnswer
        The method's own keys, written into the same object.
    log : str
        The log the readings are from, as given (and the sheet of a workbook of several); "" where
        none was named (a DataFrame).
    """

    sensor: str
    method: str
    preset: str
    window_min: float
    steady_state_C: float
    steady_state_ci95_C: tuple[float, float]
    start_C: float
    total_rise_C: float
    equilibrium_time_min: float
    rmse_C: float
    model_ok: bool
    warnings: tuple[str, ...]
    measured_final_C: float
    measured_equilibrium_time_min: float
    measured_settled: bool | None
    method_answer: MethodAnswer = json_inline()
    log: str = ""


@dataclass(frozen=True)
class Identification(SensorAnswers, Generic[DetailsT]):
    """The identified warm-up of every sensor of a log, arrays with a sensor axis S.

    Attributes
    ----------
    sensors : tuple of str
    method, preset : str
        The method that identified it and its tuning ("robust" always with "data").
    window_min : float
        Identification time L actually used (time of the last sample ≤ L).
    n_window : int
        The number of samples in the window.
    time_min : ndarray, shape (N,)
        The log's sample times, then the forecast horizon beyond it.
    measured_C : ndarray, shape (N, S)
        The log's readings at ``time_min``, NaN past the log's end.
    curve_C : ndarray, shape (N, S)
        Estimated temperature: fitted up to L, predicted after.
    band_low_C, band_high_C : ndarray, shape (N, S)
        The curve's 95 % band.
    steady_state_C : ndarray, shape (S,)
        T∞ (NaN where a sensor has no fit).
    steady_state_ci95_C : ndarray, shape (S, 2)
        T∞'s 95 % interval, low and high (infinite where not determined).
    start_C : ndarray, shape (S,)
        The curve's start.
    equilibrium_time_min : ndarray, shape (S,)
        Predicted time to 95 % of the total rise, from the start of the log.
    rmse_C : ndarray, shape (S,)
        Xia et al. 2014 Eq. 33 over all measured samples.
    model_ok : ndarray of bool, shape (S,)
        Whether each sensor's answer is trusted: a fit the data do not contradict, with T∞ determined.
    warnings : tuple of tuple of str
        Each sensor's warnings.
    measured_final_C, measured_equilibrium_time_min : ndarray, shape (S,)
        From the log itself where it reached equilibrium, else NaN.
    measured_settled : ndarray of bool, shape (S,)
        Whether the log's last quarter moved less than ``SETTLED_MOVE_C``, with at most half that
        still to come at the pace of the largest time constant: only then is the measured final
        temperature where the sensor settles to the tolerance's precision.
    notes : tuple of str
        The log's notes and the identification's.
    details : MethodDetails
        What the method adds: :class:`~mtident.thermal.first_order.FirstOrderDetails` or
        :class:`~mtident.thermal.robust_identify.RobustDetails`.
    """

    sensors: tuple[str, ...]
    method: str
    preset: str
    window_min: float
    n_window: int
    time_min: FloatArray
    measured_C: FloatArray
    curve_C: FloatArray
    band_low_C: FloatArray
    band_high_C: FloatArray
    steady_state_C: FloatArray
    steady_state_ci95_C: FloatArray
    start_C: FloatArray
    equilibrium_time_min: FloatArray
    rmse_C: FloatArray
    model_ok: BoolArray
    warnings: tuple[tuple[str, ...], ...]
    measured_final_C: FloatArray
    measured_equilibrium_time_min: FloatArray
    measured_settled: BoolArray
    notes: tuple[str, ...]
    details: DetailsT

    def __repr__(self) -> str:
        # a notebook shows the answer, not ~40 kB of arrays, and why a sensor is not trusted
        lines = [
            f"Identification({self.method}/{self.preset}, L = {self.window_min:g} min, {len(self.sensors)} sensor(s))"
        ]
        for s, name in enumerate(self.sensors):
            lo, hi = self.steady_state_ci95_C[s]
            verdict = "" if self.model_ok[s] else ", not trusted:"
            interval = f"95 % interval {lo:.2f} to {hi:.2f} °C" if np.isfinite(hi - lo) else "no 95 % interval"
            lines.append(
                f"  {name}: T∞ {self.steady_state_C[s]:.2f} °C, {interval}, "
                f"t_eq {self.equilibrium_time_min[s]:.0f} min, RMSE {self.rmse_C[s]:.3f} °C{verdict}"
            )
            lines += [] if self.model_ok[s] else [f"    - {warning}" for warning in self.warnings[s]]
        lines += self.details.describe()
        said = {w for sensor in self.warnings for w in sensor}
        lines += [f"  note: {note}" for note in self.notes if note not in said]
        return "\n".join(lines)

    def curve_frame(self) -> pd.DataFrame:
        """The measured and modelled curve of every sensor with its 95 % band, a row per time: for
        a report or a spreadsheet. ``part`` says whether the row is in the identification window
        (the fitted curve) or after it (the prediction); a time past the log's end has no
        measured value.

        Returns
        -------
        pandas.DataFrame
            Columns ``time_min``, ``part`` ("window" or "prediction") and per sensor ``NAME_measured_C``,
            ``NAME_model_C``, ``NAME_low95_C`` and ``NAME_high95_C`` (°C).
        """
        import pandas as pd

        columns: dict[str, object] = {
            "time_min": self.time_min,
            "part": np.where(self.time_min <= self.window_min + 1e-9, "window", "prediction"),
        }
        for s, name in enumerate(self.sensors):
            columns[f"{name}_measured_C"] = self.measured_C[:, s]
            columns[f"{name}_model_C"] = self.curve_C[:, s]
            columns[f"{name}_low95_C"] = self.band_low_C[:, s]
            columns[f"{name}_high95_C"] = self.band_high_C[:, s]
        return pd.DataFrame(columns)

    def answer(self, index: int) -> SensorAnswer:
        """One sensor's answer, its fields the sensor's JSON object.

        Parameters
        ----------
        index : int
            The sensor's position in ``sensors``.

        Returns
        -------
        SensorAnswer
            T∞ with its interval, the equilibrium time, the RMSE, ``model_ok``, the sensor's
            warnings, what the log measured, and the method's own part (its λ and time constant,
            what the answer assumes, ...).
        """
        lo, hi = self.steady_state_ci95_C[index]
        measured = float(self.measured_final_C[index])
        return SensorAnswer(
            sensor=self.sensors[index],
            method=self.method,
            preset=self.preset,
            window_min=float(self.window_min),
            steady_state_C=float(self.steady_state_C[index]),
            steady_state_ci95_C=(float(lo), float(hi)),
            start_C=float(self.start_C[index]),
            total_rise_C=float(self.steady_state_C[index] - self.start_C[index]),
            equilibrium_time_min=float(self.equilibrium_time_min[index]),
            rmse_C=float(self.rmse_C[index]),
            model_ok=bool(self.model_ok[index]),
            warnings=tuple(self.warnings[index]),
            measured_final_C=measured,
            measured_equilibrium_time_min=float(self.measured_equilibrium_time_min[index]),
            measured_settled=bool(self.measured_settled[index]) if np.isfinite(measured) else None,
            method_answer=self.details.answer(index),
        )


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
