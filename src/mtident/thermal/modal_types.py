"""The types of the model-robust fit: the family of models an interval covers, a sensor's
readings in bins, modes, the models that set an interval's ends, and the estimate."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from mtident._typing import FloatArray

__all__ = [
    "DEFAULT_MAX_TIME_CONSTANT_MIN",
    "Binned",
    "IntervalEnd",
    "Mode",
    "ModeFamily",
    "SteadyState",
    "bin_index",
    "bin_samples",
    "interval_half_width",
]

# The slowest thermal mode a machine tool is taken to have, unless told: a machine's
# structure (bed, column, the spindle head's casting) warms with time constants of one to
# five hours; ISO 230-3 warm-ups run 4-6 h for that reason. A mode slower than this is
# taken as absent; said in every answer.
DEFAULT_MAX_TIME_CONSTANT_MIN = 300.0
MAX_MODES = 4
# A bin spans about this fraction of the time since the log began: fast modes are resolved
# early, and a record of any length keeps a few hundred bins.
BIN_FRACTION = 0.02
BIN_ORIGIN_MIN = 1.0


@dataclass(frozen=True)
class ModeFamily:
    """The models an interval covers.

    Parameters
    ----------
    max_time_constant_min : float
        The largest time constant a mode may have (minutes).
    max_modes : int
        At most this many modes.
    reference_min : tuple of float, optional
        Time constants of a reference run of the same machine (minutes). Given, each mode's
        time constant is searched only within ``reference_box`` (relative half-widths) of the
        reference's, and no other mode is allowed.
    reference_box : tuple of float
        Relative half-width of each reference time constant's box (0.1: ±10 %).
    free_fast : int
        With a reference: up to this many more modes, free, faster than the reference's fastest
        box. A reference run pins a machine's slow modes; a fast one (a sensor's lag, a local
        transient, a mode the run could not resolve) left out would take a slow mode's place in
        the fit and pin T∞ falsely.
    every_mode_rises : bool
        Only models in which every mode rises toward T∞: the warm-up of a sensor where the heat
        enters, in a network of conductances (its response to the heat is a sum of decaying
        exponentials with positive weights), started cold or warm from the same heat, without a
        lag of its own. The engineer's to state; the readings can contradict it, not prove it.
    """

    max_time_constant_min: float = DEFAULT_MAX_TIME_CONSTANT_MIN
    max_modes: int = MAX_MODES
    reference_min: tuple[float, ...] | None = None
    reference_box: tuple[float, ...] = ()
    free_fast: int = 0
    every_mode_rises: bool = False

    def without_reference(self) -> ModeFamily:
        """The same family without the reference's boxes.

        Returns
        -------
        ModeFamily
            The same largest time constant, number of modes and sign of the modes, with no
            reference.
        """
        return ModeFamily(self.max_time_constant_min, self.max_modes, every_mode_rises=self.every_mode_rises)


@dataclass(frozen=True)
class Binned:
    """One sensor's readings in bins, the form every fit here works on.

    Parameters
    ----------
    time_min : ndarray, shape (B,)
        Mean time of each bin's readings (minutes since the log began).
    value_C : ndarray, shape (B,)
        Mean reading of each bin.
    count : ndarray, shape (B,)
        Readings in each bin (the bin's weight).
    room_C : ndarray, shape (B,), optional
        Mean room reading of each bin, where a room sensor is used.
    """

    time_min: FloatArray
    value_C: FloatArray
    count: FloatArray
    room_C: FloatArray | None = None

    def __len__(self) -> int:
        return len(self.time_min)

    def since(self, start_min: float) -> Binned:
        """The bins from ``start_min`` on.

        Parameters
        ----------
        start_min : float
            Minutes since the log began.

        Returns
        -------
        Binned
            The bins whose mean time is at or after ``start_min``.
        """
        keep = self.time_min >= start_min - 1e-9
        room = None if self.room_C is None else self.room_C[keep]
        return Binned(self.time_min[keep], self.value_C[keep], self.count[keep], room)


@dataclass(frozen=True)
class Mode:
    """One exponential mode: ``amplitude_C·e^(−t/time_constant_min)``.

    Attributes
    ----------
    time_constant_min : float
        The mode's time constant τ (min).
    amplitude_C : float
        Its value at the fit's origin (°C): the model is T∞ + Σ a·e^(−(t − origin)/τ).
    """

    time_constant_min: float
    amplitude_C: float


@dataclass(frozen=True)
class IntervalEnd:
    """The model that sets one end of an interval: its modes, with the amplitudes they take
    at that end.

    Attributes
    ----------
    steady_C : float
        T∞ of this model (°C): the interval's end it sets.
    modes : tuple of Mode
        Its modes, with the amplitudes they take at that end.
    """

    steady_C: float
    modes: tuple[Mode, ...]

    def slowest(self) -> Mode | None:
        """The slowest mode of this model (None for a model without a mode).

        Returns
        -------
        Mode or None
        """
        return max(self.modes, key=lambda m: (m.time_constant_min, abs(m.amplitude_C)), default=None)


def interval_half_width(steady_C: float, interval_C: tuple[float, float]) -> float:
    """The larger distance from T∞ to an end of its interval: the interval's half-width about T∞,
    which need not be its centre.

    Parameters
    ----------
    steady_C : float
        T∞ (°C).
    interval_C : (float, float)
        The interval's low and high ends (°C).

    Returns
    -------
    float
        The half-width (°C).
    """
    lo, hi = interval_C
    return max(steady_C - lo, hi - steady_C)


@dataclass(frozen=True)
class SteadyState:
    """The model-robust estimate of one sensor's steady state.

    Attributes
    ----------
    steady_C : float
        T∞ of the best-fitting model (at the room's last level, with a room sensor).
    interval_C : dict of float to (float, float)
        Per confidence level, the hull of T∞ over every model the data do not exclude.
    ends : dict of float to (IntervalEnd, IntervalEnd)
        Per level, the models that set the low and the high end.
    modes : tuple of Mode
        The best-fitting model's modes (with the number chosen by BIC).
    start_C : float
        The best model's value at the fit's first bin.
    origin_min : float
        Where the fit begins (a warm-up that begins after the log starts at its last flat bin).
    equilibrium_time_min : float
        When the best model stays within 5 % of its total rise from T∞ (from the log's start).
    noise_C : float
        The readings' noise as the fit sees it (per reading, with the residuals' correlation).
    correlation_factor : float
        How much the residuals' correlation widens the interval's variance (1: none).
    rss, dof : float
        Weighted residual sum of squares and degrees of freedom of the best fit with the most modes.
    n_bins : int
    room_level_C : float or None
        The room's last level, where a room sensor is used.
    family : ModeFamily
    determined : bool
        Enough data for an interval (False: the interval is infinite).
    fits : dict of int to float
        The best fit's residual sum of squares per number of modes.
    refined : dict of float to bool
        Per level, whether the hull was refined off the search grid (else it is the grid's,
        at most as wide as the true hull).
    room_gains : tuple of float
        With a room sensor, each mode's gain on the room (its lag of the room less the room).
    """

    steady_C: float
    interval_C: dict[float, tuple[float, float]]
    ends: dict[float, tuple[IntervalEnd, IntervalEnd]]
    modes: tuple[Mode, ...]
    start_C: float
    origin_min: float
    equilibrium_time_min: float
    noise_C: float
    correlation_factor: float
    rss: float
    dof: float
    n_bins: int
    room_level_C: float | None
    family: ModeFamily
    determined: bool = True
    fits: dict[int, float] = field(default_factory=dict)
    refined: dict[float, bool] = field(default_factory=dict)
    room_gains: tuple[float, ...] = ()

    def half_width(self, level: float) -> float:
        """:func:`interval_half_width` of the interval at ``level``, a confidence level of ``interval_C``
        (infinite where the interval is)."""
        return interval_half_width(self.steady_C, self.interval_C[level])

    def slowest_time_constant_min(self) -> float:
        """The best model's slowest time constant (NaN for a model without a mode).

        Returns
        -------
        float
            The time constant (min).
        """
        return max((m.time_constant_min for m in self.modes), default=float("nan"))


def bin_index(time_min: FloatArray, fraction: float = BIN_FRACTION, origin_min: float = BIN_ORIGIN_MIN) -> FloatArray:
    """The bin each time falls into (minutes since the log began): bins a fixed fraction of the
    elapsed time wide, so that the same reading always falls into the same bin, live or not.

    Parameters
    ----------
    time_min : ndarray
        Minutes since the log began (a negative time counts as 0).
    fraction : float, optional
        A bin's width as a fraction of its time plus ``origin_min``.
    origin_min : float, optional
        The time scale of the first bins (min): near t = 0 a bin is ``fraction * origin_min`` wide.

    Returns
    -------
    ndarray
        The bin numbers, as floats, in the shape of ``time_min``.

    Examples
    --------
    >>> bin_index(np.array([0.0, 0.5, 1.0, 100.0, 1000.0])).astype(int).tolist()
    [0, 20, 35, 233, 348]
    """
    since: FloatArray = np.maximum(np.asarray(time_min, dtype=float), 0.0)
    bins: FloatArray = np.floor(np.log1p(since / origin_min) / np.log1p(fraction))
    return bins


def bin_samples(time_min: FloatArray, values: FloatArray, room_C: FloatArray | None = None) -> Binned:
    """Bin one sensor's readings (missing ones left out) by :func:`bin_index`.

    Parameters
    ----------
    time_min : ndarray, shape (N,)
        Minutes since the log began.
    values : ndarray, shape (N,)
    room_C : ndarray, shape (N,), optional
        The room sensor's readings; a bin takes the readings where both are valid.

    Returns
    -------
    Binned
    """
    t = np.asarray(time_min, dtype=float)
    y = np.asarray(values, dtype=float)
    valid = np.isfinite(y) & np.isfinite(t)
    if room_C is not None:
        valid &= np.isfinite(room_C)
    _, which = np.unique(bin_index(t[valid]), return_inverse=True)
    count = np.bincount(which).astype(float)

    def mean(x: FloatArray) -> FloatArray:
        answer: FloatArray = np.bincount(which, weights=x) / count
        return answer

    room = None if room_C is None else mean(np.asarray(room_C, dtype=float)[valid])
    return Binned(mean(t[valid]), mean(y[valid]), count, room)
