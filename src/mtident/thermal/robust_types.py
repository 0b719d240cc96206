"""What the model-robust answer is made of: its settings (:class:`RobustSettings`), a reference
run's modes of one sensor (:class:`SensorModes`), what an interval assumes (:class:`Assumptions`)
and one sensor's answer (:class:`SensorEstimate`). The fit that makes them is
:mod:`~mtident.thermal.robust`.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Literal

from mtident.exceptions import InputError
from mtident.thermal.modal_types import MAX_MODES, IntervalEnd, Mode, interval_half_width
from mtident.thermal.modes import DEFAULT_MAX_TIME_CONSTANT_MIN, SteadyState

__all__ = [
    "DEFAULT_MAX_MODES",
    "MAX_FREE_FAST",
    "Assumptions",
    "EstimateStatus",
    "RobustSettings",
    "SensorEstimate",
    "SensorModes",
    "WarningCode",
]

# how far a sensor's answer got, as the JSON's model.status says it
EstimateStatus = Literal["estimated", "no data", "no rise", "too few readings"]

# what a sensor's warning is about, one word each: to say each once, and to decide on it
WarningCode = Literal[
    "late-start",
    "spikes",
    "misfit",
    "undetermined",
    "fragile",
    "modes-saturated",
    "modes-unresolved",
    "slower-than-allowed",
    "reference-disagrees",
    "reference-doubtful",
    "machine-disagrees",
    "below-floor",
    "came-down",
    "jumped",
    "heat-enters-contradicted",
    "heat-enters-room-moved",
    "too-few-readings",
    "no-data",
    "no-rise",
]

# With a reference, up to this many free modes faster than its slowest (the cost of a check grows
# with each).
MAX_FREE_FAST = 2


# the modes searched without widening, and the most a reference run keeps: the mode family's
DEFAULT_MAX_MODES = MAX_MODES


@dataclass(frozen=True)
class RobustSettings:
    """What the model-robust answer assumes and how sure it must be.

    Parameters
    ----------
    max_time_constant_min : float
        The slowest mode the machine may have (minutes).
    room_wander_C_per_h : float
        Without a room sensor: how far the unmeasured room may wander, as a random walk of this
        many °C in an hour (0: a room known to be steady).
    levels : tuple of float
        Confidence levels of the intervals computed (the report's and the decision's).
    max_modes : int
        At most this many modes.
    more_modes_when_used : bool
        Where the readings use all ``max_modes`` beyond chance, cover more, up to
        ``MAX_MODES_WHEN_SATURATED``; with a reference, one free mode more where they use every
        free mode, up to ``MAX_FREE_WHEN_SATURATED`` (False: exactly the family asked for, as a
        reference run's fit of a given number of modes wants).
    free_fast_modes : int
        With a reference: at most this many free modes faster than its slowest box (below or
        between its other boxes), which a reference run can miss (0 assumes the reference holds
        every mode of the machine: the earliest stops, and an assumption every answer then states).
    heat_enters_at : tuple of str
        The sensors that sit where the heat enters, as the engineer states: fitted without a
        reference, their models have every mode rising (``ModeFamily.every_mode_rises``), which
        bounds a slow mode not yet seen by the rise it would already show. Readings that
        contradict it are fitted as any other sensor's, and the answer says so.
    """

    max_time_constant_min: float = DEFAULT_MAX_TIME_CONSTANT_MIN
    room_wander_C_per_h: float = 0.05
    levels: tuple[float, ...] = (0.95, 0.99)
    max_modes: int = DEFAULT_MAX_MODES
    free_fast_modes: int = MAX_FREE_FAST
    more_modes_when_used: bool = True
    heat_enters_at: tuple[str, ...] = ()

    def unknown_heat_sensors(self, sensors: tuple[str, ...] | list[str]) -> None:
        """Refuse ``heat_enters_at`` names that are not among ``sensors``.

        Parameters
        ----------
        sensors : tuple or list of str
            The sensors of the log.

        Raises
        ------
        InputError
            A name that is not one of them.
        """
        unknown = [name for name in self.heat_enters_at if name not in sensors]
        if unknown:
            msg = (
                f"the heat cannot be said to enter at {', '.join(map(repr, unknown))}: not among the log's sensors "
                f"({', '.join(sensors)})"
            )
            raise InputError(msg)

    def __post_init__(self) -> None:
        # a notebook builds these directly: a negative time constant overflowed deep in the search
        checks = (
            ("max_time_constant_min", self.max_time_constant_min, "a finite number of minutes, 1 or more", 1.0),
            ("room_wander_C_per_h", self.room_wander_C_per_h, "a finite number of °C in an hour, 0 or more", 0.0),
            ("max_modes", self.max_modes, "a whole number, 1 or more", 1.0),
            ("free_fast_modes", self.free_fast_modes, "a whole number, 0 or more", 0.0),
        )
        for name, value, right, least in checks:
            try:
                ok = math.isfinite(float(value)) and float(value) >= least
            except (TypeError, ValueError):
                ok = False
            if not ok:
                msg = f"RobustSettings: `{name}` must be {right}, not {value!r}"
                raise InputError(msg)
        if not self.levels or not all(0.0 < float(q) < 1.0 for q in self.levels):
            msg = f"RobustSettings: `levels` must be confidence levels between 0 and 1, not {self.levels!r}"
            raise InputError(msg)


ROOMS_PART_LOGGED = " (the room's part: the path its moves take into the sensor, and its level's error)"
ROOMS_PART_UNLOGGED = " (the room's part: its unlogged wander)"
"""What "more from the room" in an interval end's words means, said once after a sensor's ends."""

WIDE_BOX = 0.5
"""A box this wide (relative half-width) or wider is said as its range, not as a centre ± a share."""


@dataclass(frozen=True)
class SensorModes:
    """A sensor's modes learnt from a reference run.

    Parameters
    ----------
    time_constants_min : tuple of float
        The modes' time constants (min): the centres of the boxes a later test searches.
    box : tuple of float
        Relative half-width of each time constant's uncertainty (0.1: ±10 %).
    amplitudes_C : tuple of float
        The amplitudes in the reference run (for information; a new test's are free).
    doubt : str or None
        Why the reference run did not pin this sensor down (its steady state left uncertain, or its
        modes a misfit), or None. A doubtful sensor's modes are not used by later tests: a run
        that did not reach its equilibrium, or that a few modes do not describe, can miss the very
        mode that sets a later test's steady state.
    free_fast_modes : int or None
        The most free modes faster than these a later test allows for this sensor (0: the
        reference is said to hold every mode, as of a machine known to be first order); None:
        the test's own setting. A test's smaller setting wins.
    """

    time_constants_min: tuple[float, ...]
    box: tuple[float, ...]
    amplitudes_C: tuple[float, ...] = ()
    doubt: str | None = None
    free_fast_modes: int | None = None

    def box_words(self, unit: str = "") -> str:
        """The time constants with their boxes, in words: ``6.03 ±10%``, and a wide box as the range
        it is (``3-300``), whose middle is no measurement; a box as wide as its mode or wider as how
        far it reaches (``up to 5.73``: a time constant is never below zero).

        Parameters
        ----------
        unit : str, optional
            Put after each number (" min").

        Returns
        -------
        str
        """

        def words(t: float, b: float) -> str:
            if b >= 1.0:
                return f"up to {t * (1 + b):.3g}{unit}"
            return f"{t * (1 - b):.3g}-{t * (1 + b):.3g}{unit}" if b >= WIDE_BOX else f"{t:.3g}{unit} ±{b:.0%}"

        return ", ".join(words(t, b) for t, b in zip(self.time_constants_min, self.box, strict=True))


@dataclass(frozen=True)
class Assumptions:
    """What an interval rests on, said with every answer.

    Attributes
    ----------
    max_time_constant_min : float
        The largest time constant searched (min).
    room : str
        How the room enters the answer, in words.
    reference : str or None
        The reference run's modes and how they are used, in words; None without a reference.
    model : str
        The models the interval covers, in words.
    """

    max_time_constant_min: float
    room: str
    reference: str | None = None
    model: str = (
        "a sum of up to four exponential modes (six where the readings use all four), of a warm-up that does not "
        "overshoot: a rising sensor's T∞ not below its latest readings, less four times their noise and any fall "
        "of a logged room"
    )


@dataclass(frozen=True)
class SensorEstimate:
    """One sensor's model-robust answer.

    Attributes
    ----------
    sensor : str
    status : EstimateStatus
        "estimated", "no data", "no rise" (within its noise of its first level) or "too few readings".
    fit : SteadyState or None
    onset_min : float
        Where its warm-up begins (after a flat start, the last flat reading).
    rise_C : float
        How far it has moved from its first level.
    noise_C : float
        The readings' noise (per reading).
    interval_C : dict of float to (float, float)
        T∞'s interval per level, the room's unmeasured wander or a logged room's level error included.
    model_ok : bool
        False where the data contradict the model or T∞ is not determined.
    warnings : tuple of str
    warning_codes : tuple of WarningCode
        What each warning is about, one word each (``WarningCode``: "late-start", "spikes",
        "misfit", "undetermined", "fragile", ...): to say each once.
    reference_used : bool
        The reference's time constants were used (the test agrees with them).
    spikes : int
        Readings left out as spikes.
    display_step_C : float
        The step the readings come in (a display's rounding or a converter's; 0 where none).
    machine_used : bool
        T∞ and the intervals come with the machine model's (every sensor fitted together with the
        reference run's modes and their proportions across the sensors).
    room_lag_C : float
        With the machine model, how far its lag behind a moving room may move T∞ (one sd, °C; part
        of the intervals), 0 where the room stands still or is not logged.
    last_min : float
        The time of the last reading fitted (min; NaN where none was).
    """

    sensor: str
    status: EstimateStatus
    fit: SteadyState | None
    onset_min: float
    rise_C: float
    noise_C: float
    interval_C: dict[float, tuple[float, float]]
    model_ok: bool
    warnings: tuple[str, ...]
    warning_codes: tuple[WarningCode, ...] = ()
    reference_used: bool = False
    spikes: int = 0
    display_step_C: float = 0.0
    machine_used: bool = False
    room_lag_C: float = 0.0
    last_min: float = float("nan")

    @property
    def steady_C(self) -> float:
        """T∞ of the best-fitting model (NaN without a fit).

        Returns
        -------
        float
            T∞ (°C).
        """
        return float("nan") if self.fit is None else self.fit.steady_C

    def half_width(self, level: float) -> float:
        """:meth:`SteadyState.half_width <mtident.thermal.modal_types.SteadyState.half_width>` of this
        estimate's own interval at ``level`` (the room's unmeasured wander included); inf without a fit."""
        if self.fit is None:
            return float("inf")
        return interval_half_width(self.steady_C, self.interval_C[level])

    def what_sets_the_ends(self, level: float) -> str:
        """In words, the models that set the interval's ends: "a mode of about 280 min still fits,
        with 0.45 °C of rise still to come after t = 120 min".

        A slow mode at an end is said by what is left of it after the last reading, and faster modes
        that go the other way meanwhile by how far they go: its whole course from the warm-up's
        start can be several times the rise so far, or a fall, which read as nonsense beside a
        sensor that rose.

        Parameters
        ----------
        level : float
            A confidence level of ``interval_C``.

        Returns
        -------
        str
            One phrase per end whose model has a mode; "too few readings for a model" without a fit at
            ``level``.
        """
        if self.fit is None or level not in self.fit.ends:
            return "too few readings for a model"
        words = []
        # each end as the interval states it (widened for the room's wander where it is not
        # measured), so that the sentence and the interval beside it agree
        ends = zip(self.fit.ends[level], ("low", "high"), self.interval_C[level], strict=True)
        elapsed = max(self.last_min - self.fit.origin_min, 0.0) if math.isfinite(self.last_min) else 0.0
        after = f" after t = {self.last_min:.0f} min" if math.isfinite(self.last_min) else ""
        best_left = sum(_left(m, elapsed) for m in self.fit.modes)
        for end, label, value in ends:
            slowest = end.slowest()
            if label == "low" and value > end.steady_C + 1e-9:
                # the warm-up's floor lifted this end above every model's that goes lower
                words.append(
                    f"low end {value:.2f} °C: where the sensor already is, less its noise (a warm-up does not fall)"
                )
                continue
            if slowest is None:
                continue
            own = _left(slowest, elapsed)
            others = sum(_left(m, elapsed) for m in end.modes) - own
            course = "rise" if own > 0 else "fall"
            meanwhile = (
                f" (faster modes {'falling' if others < 0 else 'rising'} {abs(others):.2f} °C meanwhile)"
                if own * others < 0 and abs(others) >= 0.01
                else ""
            )
            words.append(
                f"{label} end {value:.2f} °C: a mode of about {slowest.time_constant_min:.0f} min still fits, "
                f"with {abs(own):.2f} °C of {course} still to come{after}{meanwhile}"
                + self._rooms_share(value, end, own + others - best_left)
            )
        said = "; ".join(words)
        # what the room's part is, once for both ends (a test's reason said it eight times over)
        if "more from the room" not in said:
            return said
        return said + (ROOMS_PART_LOGGED if self.fit.room_level_C is not None else ROOMS_PART_UNLOGGED)

    def _rooms_share(self, value: float, end: IntervalEnd, modes_beyond: float) -> str:
        """Words for the part of an end's distance from T∞ that its modes' course does not make: the
        room's (what it is, :meth:`what_sets_the_ends` says once). A logged room's: the path its moves
        take into the sensor, and its level's error
        (both models fit the readings, so they stand alike now; what is left of the distance is
        where they put the room). An unlogged room's: its wander, by which the end was widened."""
        assert self.fit is not None
        logged = self.fit.room_level_C is not None
        share = value - self.fit.steady_C - modes_beyond if logged else value - end.steady_C
        if abs(share) < 0.01 or share * (value - self.fit.steady_C) <= 0:
            return ""
        return f", and {abs(share):.2f} °C more from the room"


def _left(mode: Mode, elapsed_min: float) -> float:
    """What is left of a mode after ``elapsed_min``, counted as a rise (T = T∞ + a·e^(−t/τ))."""
    return -mode.amplitude_C * math.exp(-elapsed_min / mode.time_constant_min)


_END_MODE = re.compile(r"a mode of about (\d+(?:\.\d+)?) min")


def ends_at_the_largest(ends: str, max_time_constant_min: float) -> bool:
    """Whether an interval's ends, in the words of :meth:`SensorEstimate.what_sets_the_ends`, are
    set by a mode at the largest time constant searched: a slow mode the readings cannot yet
    exclude, which only a reference run or a smaller stated largest time constant removes.

    Parameters
    ----------
    ends : str
    max_time_constant_min : float

    Returns
    -------
    bool
    """
    return any(float(tau) >= 0.97 * max_time_constant_min for tau in _END_MODE.findall(ends))
