"""Live thermal-test monitor: recursive identification of every sensor and the stopping rule.

Each new sample advances every sensor's filter by one step (constant work per
sample: no refit from the start). The stopping rule, per sensor:

1. the 95 % interval of T∞ is well within ``tolerance``: half-width ≤
   ``interval_fraction`` × tolerance (default 0.6: stopping at the first moment
   an interval fits selects a lucky moment, so a margin is kept),
2. the T∞ estimate has stayed within ±tolerance/2 of its current value for the
   last ``hold_min`` minutes (or a tenth of the test so far, if longer), and its
   trend over that time, carried on towards the predicted equilibrium (at least
   one and at most ``creep_holds`` hold periods ahead, default 3), moves it by
   less than tolerance/2 (a slow mode or ambient drift shows as a T∞ estimate
   that keeps creeping),
3. the model check passes: over the last ``check_samples`` samples the
   normalised innovations νₖ/√Sₖ have mean ≈ 0 and mean square ≈ 1. A
   fast-plus-slow warm-up whose slow part the first-order model has not yet
   seen gives innovations of one sign; the monitor then widens the filter's
   parameter covariance (a discrete fading step) so that it learns the new
   trend, and the T∞ history starts again. With a room sensor, the sensor is
   then identified afresh from the ``restart_delay_min`` (30) minutes after
   its last failed check (:meth:`Monitor._restart`): a filter that also learnt
   from the fast part stays biased towards it. Without one, a failed check may
   be the room's unmeasured drift, which a fresh filter on 30 min would follow
   too closely; the widened filter keeps its memory;
4. at least ``min_samples`` samples and ``min_duration_min`` minutes of test
   (default 30, the papers' identification time): a fast transient that settles
   in minutes can hide a slow mode that only shows later,
5. the estimate is consistent with the monitor's own earlier answers: over the
   last ``consistency_window_min`` minutes, T∞ has not moved from any earlier
   estimate by more than ``consistency_factor`` × that estimate's 95 %
   half-width (and more than tolerance/2, which rule 2 covers). For a
   first-order warm-up a later, better estimate lies inside the earlier
   intervals. A room that drifts (a 4-h air-conditioning cycle) tilts the
   slope the filter sees, so its T∞ wanders by the drift rate / λ, several
   times its interval; where the wander turns round it holds still long enough
   to pass rule 2 at its largest error. This rule catches that; a room sensor
   (``ambient``) takes the drift into account (``room_coupling``: "lagged",
   the room is the input of the sensor's first-order heat balance, for a
   sensor in the machine's structure; "direct", the sensor follows the room at
   once, for one in the air stream: its rise over the room is followed).

A sensor flat at the start (the logger started before the spindle, or a sensor
behind a thermal lag) is started when it rises, on the ``init_min`` minutes
from its last flat sample, like the first start; a filter thrown far off
course (a rate below −0.1 per sample) is identified again from the next
``restart_delay_min`` minutes.

Without a room sensor the room is an unknown input that may wander: a random
walk of ``room_wander_C_per_h`` (1σ in one hour, default 0.05 °C) in the heat
balance (:meth:`Monitor._unmeasured_room_noise`). The filter then does not take a
slope bent by the room for the warm-up's own, and the T∞ band allows for where
the room may have gone. Set it to 0 for a room known to be steady (the papers'
setting: earlier stops), higher for an unconditioned workshop.

The test may stop when every sensor may, except sensors that show no rise
(they are reported and left out of the decision).

Before the decision, :meth:`Monitor.expected_stop_times` says when each sensor
is expected to stop if its warm-up keeps its present first-order course (each
filter run on, on a copy, with its own predicted readings), and
:meth:`Monitor.expected_stop_time` when the whole test is.

Bad samples: a spike (|ν|/√S > ``spike_sigma``) is rejected and the step redone
without it; NaN, empty and open-circuit cells are treated as missing (the
filter bridges them); a gap in time is bridged by the model and reported; a
sensor without a valid reading in the start window (dead, or plugged in later)
waits for its readings like a sensor that has not begun to rise, and is "no
data", left out of the decision, if none come.
Repeated messages of one kind for one sensor (a dead sensor, a slow mode) are
said at most once per ``quiet_min`` minutes.

A log faster than ``bin_min`` (default 10 s: a 1-Hz log) is fed in bins of
about that length, their mean time and readings (:meth:`Monitor._take_bin`): a
display's rounding stays the same for many samples at 1 Hz, and a filter told
they were independent grew sure of the wrong answer (a 0.1 °C display at 1 Hz
never stopped); the bins also cut the work per sample. The noise is never
taken below the rounding of the raw readings' display step
(:func:`~mtident.thermal.settings.display_resolution`).

The whole state is a JSON-serialisable dict (:meth:`Monitor.to_dict`), so a
monitor killed at any moment (also in the middle of a bin) resumes with the
same result.
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field, fields, replace
from typing import Any

import numpy as np
from scipy.special import fdtri, stdtrit

from mtident._typing import FloatArray
from mtident.exceptions import CovarianceError, InputError
from mtident.thermal.lsq import flat_lead, rise_threshold
from mtident.thermal.model import equilibrium_time, observe_temperature, slope_transition, to_physical
from mtident.thermal.settings import DISPLAY_STEPS_C, ThermalTuning, filter_config, noise_sigma, on_display_steps, step_from_grid, tuning_from_data
from mtident.ukf import FilterCarry, FilterConfig, GaussianState, SigmaWeights, StepInfo, filter_step, initial_carry

__all__ = ["MonitorSettings", "Monitor", "SensorStatus", "ROOM_COUPLINGS", "minutes"]

# How a sensor feels the room (with a room sensor): "lagged", through the machine's own heat
# balance (a sensor in the structure); "direct", at once (a sensor in the air stream, on a thin cover).
ROOM_COUPLINGS = ("lagged", "direct")
# statuses of sensors left out of the decision: they give no warm-up to wait for
_LEFT_OUT = ("no rise", "no data")
# fourth differences of the noise before its estimate is called settled, in the model-check message
_MATURE_NOISE_ESTIMATE = 30
# minutes of innovations before a failed trend check is no longer put down to the filter's own start
_SETTLING_MIN = 30.0
# a wild reading after this many spikes within about this many minutes (their count fading with
# that time) is more noise than estimated, not a spike
_SPIKES_FOR_NOISE = 3
_SPIKE_MEMORY_MIN = 20.0
# ... unless they are this far off: no noise a logger's readings grow into (a loose contact's were 6-12σ)
_NOISE_SIGMA_MAX = 25.0
# Neighbouring fourth differences of white noise overlap (correlations -0.8, 0.4, -0.11, 0.014): a
# mean of k of their squares varies like a mean of k / 2.63 independent ones.
_D4_OVERLAP = 1.0 + 2.0 * (0.8**2 + 0.4**2 + (8 / 70) ** 2 + (1 / 70) ** 2)
# The forecast of the stop runs each filter on for at most this long, in at most this many steps.
_FORECAST_HORIZON_MIN = 600.0
_FORECAST_STEPS = 300
# the room sensor's name in the message log (sensor names are the log's column names)
_ROOM = "(room sensor)"
# what a missing reading can be, in the messages
_MISSING = "empty, NaN, not a number or open circuit"


@dataclass(frozen=True, slots=True)
class MonitorSettings:
    """Tuning of the stopping rule (defaults for a 1-min PT100 log)."""

    tolerance_C: float = 0.2
    interval_fraction: float = 0.6
    hold_min: float = 12.0
    init_min: float = 10.0
    min_samples: int = 15
    check_samples: int = 20
    spike_sigma: float = 6.0
    min_rise_C: float = 0.1
    gap_factor: float = 5.0
    hold_fraction: float = 0.1
    min_duration_min: float = 30.0
    consistency_window_min: float = 60.0
    consistency_factor: float = 1.0
    room_coupling: str = "lagged"
    quiet_min: float = 60.0
    creep_holds: float = 3.0
    room_wander_C_per_h: float = 0.05
    late_rise_min: float = 5.0
    restart_delay_min: float = 30.0
    bin_min: float = 1.0 / 6.0

    def __post_init__(self) -> None:
        if not (np.isfinite(self.bin_min) and self.bin_min >= 0):
            raise ValueError(f"bin_min must be a finite number of minutes ≥ 0, not {self.bin_min!r}")
        if self.room_coupling not in ROOM_COUPLINGS:
            raise ValueError(f"room_coupling must be one of {ROOM_COUPLINGS}, not {self.room_coupling!r}")
        if not (np.isfinite(self.room_wander_C_per_h) and self.room_wander_C_per_h >= 0):
            raise ValueError(f"room_wander_C_per_h must be a finite number ≥ 0 (°C in one hour, 1σ), not {self.room_wander_C_per_h!r}")


@dataclass(frozen=True, slots=True)
class SensorStatus:
    """What the monitor says about one sensor now."""

    sensor: str
    latest_C: float
    steady_state_C: float
    half_width_C: float
    equilibrium_time_min: float
    may_stop: bool
    status: str

    @property
    def left_out(self) -> bool:
        """Whether the sensor gives no warm-up to wait for ("no rise", "no data"): left out of the decision."""
        return self.status in _LEFT_OUT


def minutes(value: float) -> str:
    """A time for the engineer, to a tenth of a minute (a 1-Hz log's bins end at times like 62.5917)."""
    return f"{value:.1f}".removesuffix(".0")


def transition_with_room(dt_min: float, room_rate: float):  # noqa: ANN201 - a transition for filter_step
    """The heat balance's step over ``dt_min`` with the room's rate over it."""
    return lambda points: slope_transition(points, dt_min, room_rate)


def _normalised_innovation(info: StepInfo) -> FloatArray:
    """ν/√S per sensor (NaN where the sample was missing)."""
    return info.innovation[:, 0] / np.sqrt(info.innovation_cov[:, 0, 0])


def _count_innovations(observed: FloatArray, nis_sum: FloatArray, z: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Valid samples per sensor, and the sum of z² after the first three (the consistency factor's)."""
    ok = np.isfinite(z)
    observed = observed + ok
    return observed, nis_sum + np.where(ok & (observed > 3), z**2, 0.0)


def _bin_wants_more(span: float, interval: float, bin_min: float) -> bool:
    """Whether a bin whose rows span ``span`` minutes, ``interval`` apart, is nearer ``bin_min`` with one more row.

    Each row stands for about one interval, so the bin covers span + interval now
    and span + 2·interval with another row.
    """
    return span + 1.5 * interval < bin_min * (1.0 - 1e-9)


def _number_or_none(value: float) -> float | None:
    """A number for JSON: None where there is none (NaN, infinite)."""
    return float(value) if np.isfinite(value) else None


def _test_expected(status: list[SensorStatus], times: FloatArray) -> float | None:
    """The test's expected stop: the latest of the sensors in the decision, None if one is not foreseeable."""
    needed = [float(t) for t, st in zip(times, status, strict=True) if not st.left_out]
    return max(needed) if needed and all(np.isfinite(needed)) else None


def _floats(value: Any) -> FloatArray:
    return np.array(value, dtype=float)


def _optional_floats(value: Any) -> FloatArray | None:
    return None if value is None else np.array(value, dtype=float)


def _tolist(value: object) -> object:
    return value.tolist() if isinstance(value, np.ndarray) else value


def _no_rows() -> FloatArray:
    return np.empty((0, 0))


def _rows(value: Any) -> FloatArray:
    """Saved rows (a list of lists) as a 2-D array; the width of an empty one is set by the monitor."""
    rows = np.array(value, dtype=float)
    return rows if rows.ndim == 2 else _no_rows()


def _append_row(rows: FloatArray, row: FloatArray | list[float]) -> FloatArray:
    return np.concatenate([rows, np.asarray(row, dtype=float)[None, :]])


def _since(rows: FloatArray, start: float) -> FloatArray:
    """The rows (time in the first column, increasing) from ``start`` on."""
    return rows[int(np.searchsorted(rows[:, 0], start, side="left")) :]


@dataclass
class Monitor:
    """Recursive warm-up monitor for S sensors. Feed it samples with :meth:`feed`."""

    sensors: tuple[str, ...]
    settings: MonitorSettings = MonitorSettings()
    buffer_t: list[float] = field(default_factory=list)
    buffer_y: list[list[float]] = field(default_factory=list)
    tuning: ThermalTuning | None = None
    carry: FilterCarry | None = None
    last_t: float | None = None
    median_dt: float | None = None
    observed: FloatArray | None = None
    # The histories are arrays (rows appended, the oldest dropped): a list of lists turned into
    # an array every sample cost a third of the step at 1-Hz sampling.
    z_history: FloatArray = field(default_factory=_no_rows)  # the last check_samples ν/√S per sensor
    steady_history: FloatArray = field(default_factory=_no_rows)  # rows: [t, T∞ per sensor] over the hold
    nis_sum: FloatArray | None = None
    min_T: FloatArray | None = None
    max_T: FloatArray | None = None
    samples: int = 0
    recent_y: FloatArray = field(default_factory=_no_rows)  # last 5 raw samples, for the noise estimate
    rejected_run: FloatArray | None = None
    recent_spikes: FloatArray | None = None  # spikes rejected lately, fading over ``_SPIKE_MEMORY_MIN``
    room_measured: bool = False  # fed with ``ambient``: the room is an input, not an unknown that wanders
    ambient_level: float | None = None  # the room's last valid reading, with ``ambient``
    ambient_time: float | None = None
    buffer_room_rate: list[float] = field(default_factory=list)
    # per sensor, the time of the last failed model check while a re-identification waits for data (NaN: none)
    restart_from: list[float] | None = None
    waiting_rise: list[bool] | None = None  # per sensor: flat since the start, its filter waits for the rise
    unread: list[bool] | None = None  # per sensor: no valid reading yet (disconnected, or dead from the start)
    recent_rows: FloatArray = field(default_factory=_no_rows)  # [t, room rate, y per sensor] over the last restart_delay_min
    # derived from the tuning once per process (not saved): the step needs them every sample
    _config: FilterConfig | None = field(default=None, repr=False, compare=False)
    _weights: SigmaWeights | None = field(default=None, repr=False, compare=False)
    # the last forecast of the stop and what it was made at (samples, time, horizon): result(),
    # the table and the picture ask for it several times between two samples
    _forecast: tuple[tuple[int, float | None, float], FloatArray] | None = field(default=None, repr=False, compare=False)
    d4_sum: FloatArray | None = None
    d4_count: FloatArray | None = None
    # The raw readings, per sensor: for each display step whether every one was a whole multiple of
    # it, and the lowest and highest: the noise is never taken below the display's rounding.
    on_grid: np.ndarray | None = None
    raw_low: FloatArray | None = None
    raw_high: FloatArray | None = None
    # the raw rows of the bin being gathered (a log faster than bin_min): [t, room, y per sensor]
    pending: FloatArray = field(default_factory=_no_rows)
    # the last raw row's time: a closed bin's mean time lies before it, and neither the next row's
    # interval nor the check that times move on may be measured from the mean
    last_row_t: float | None = None
    # rows [t, rise T∞ per sensor, its 95 % half-width per sensor], about one per minute of the window
    checkpoints: FloatArray = field(default_factory=_no_rows)
    wandering: list[bool] | None = None
    last_said: dict[str, float] = field(default_factory=dict)  # "kind:sensor" -> time of the last such message
    stop_time: float | None = None
    decision: list[dict[str, object]] | None = None
    notes: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        if isinstance(self.sensors, str):  # Monitor("T1"): one sensor, not one per letter
            self.sensors = (self.sensors,)
        self.sensors = tuple(self.sensors)
        if not self.sensors:
            raise InputError("Monitor needs at least one sensor name, e.g. Monitor(('T1', 'T2'))")
        S = len(self.sensors)
        for name, width in (("z_history", S), ("steady_history", 1 + S), ("recent_y", S), ("recent_rows", 2 + S), ("checkpoints", 2 + 2 * S), ("pending", 2 + S)):
            if len(getattr(self, name)) == 0:
                setattr(self, name, np.empty((0, width)))
        if self.on_grid is None or self.raw_low is None or self.raw_high is None:
            self.on_grid = np.ones((S, len(DISPLAY_STEPS_C)), dtype=bool)
            self.raw_low, self.raw_high = np.full(S, np.inf), np.full(S, -np.inf)

    def __repr__(self) -> str:
        # the whole state is for to_dict; a notebook wants the answer so far
        if self.carry is None:
            return f"Monitor({len(self.sensors)} sensor(s), collecting the first {self.settings.init_min:g} min)"
        if self.stop_time is not None:
            decision = f"stop at t = {minutes(self.stop_time)} min"
        else:
            expected = self.expected_stop_time()
            decision = "continue" + ("" if expected is None else f", expected stop at t ≈ {minutes(round(expected))} min")
        lines = [f"Monitor({len(self.sensors)} sensor(s), t = {minutes(self.latest_time or 0.0)} min, decision: {decision})"]
        for st in self.status():
            lines.append(f"  {st.sensor}: T∞ {st.steady_state_C:.2f} ± {st.half_width_C:.2f} °C, t_eq {st.equilibrium_time_min:.0f} min, {st.status}")
        return "\n".join(lines)

    @property
    def latest_time(self) -> float | None:
        """The time of the last sample fed (min), also while the start window or a bin is collected."""
        if self.last_row_t is not None:
            return self.last_row_t
        if len(self.pending):  # a state file written before last_row_t was kept
            return float(self.pending[-1, 0])
        return self.last_t if self.last_t is not None else (self.buffer_t[-1] if self.buffer_t else None)

    # ---- recursion --------------------------------------------------------------------
    def feed(self, times: FloatArray, values: FloatArray, ambient: FloatArray | None = None) -> list[str]:
        """Process new samples (times in min, values (n, S)); returns warnings for the engineer.

        With ``ambient`` (n,), a reference sensor in the room, the room becomes the
        input of each sensor's first-order heat balance, dT/dt = λ(T_room + ΔT∞ − T)
        (:func:`~mtident.thermal.model.slope_transition`): the papers' model, one
        heat capacity coupled to the room, which stays first order when the room
        drifts. T∞ is then the steady state the machine reaches if the room stays
        as it is now. Subtracting the room reading from the sensor instead would
        assume the sensor follows the room air without lag; a machine's mass
        follows it with its own time constant.

        Once the decision is reached the monitor's answer is final and later
        samples are not used, so a replay of a whole log and a live run that stops
        at the decision end in the same state.
        """
        times, rows, room = self._checked(times, values, ambient)
        messages: list[str] = []
        self.room_measured = self.room_measured or ambient is not None
        for raw_t, raw_y, raw_a in zip(times, rows, room, strict=True):
            if self.stop_time is not None:
                break
            previous = self.latest_time
            self._note_reading(raw_y)
            self.pending = _append_row(self.pending, [raw_t, raw_a, *raw_y])
            self.last_row_t = float(raw_t)
            # A log faster than bin_min (1 Hz) is fed as bins of about bin_min, their mean time and
            # readings: a display's rounding stays the same for many samples, and the filter, told
            # they were independent, stopped late or never (0.1 °C at 1 Hz). A slower log is fed
            # sample by sample, as before. The bin closes when one more row would take it further
            # from bin_min than it is (10 rows at 1 Hz): a 10-s logger whose rows come 9.5 s apart
            # is fed row by row, not in 20-s pairs.
            if previous is not None and _bin_wants_more(raw_t - self.pending[0, 0], raw_t - previous, self.settings.bin_min):
                continue
            t, y, a = self._take_bin()
            rate = 0.0
            if np.isfinite(a):
                # the room's mean rate since its last valid reading (a missing one: the room held still)
                if self.ambient_level is not None and self.ambient_time is not None and t > self.ambient_time:
                    rate = (float(a) - self.ambient_level) / (float(t) - self.ambient_time)
                self.ambient_level, self.ambient_time = float(a), float(t)
            elif ambient is not None and self._may_say("dropout", _ROOM, float(t)):
                if self.ambient_level is not None:
                    held = "its last reading is used"
                elif self.settings.room_coupling == "direct":
                    held = "the sensors' rise over the room waits for its first reading"
                else:
                    held = "the room is taken as steady until its first reading"
                messages.append(f"room sensor: no valid reading at t = {minutes(t)} min ({_MISSING}); {held}{self._quiet_note()}")
            if ambient is not None and self.settings.room_coupling == "direct":
                # The raw reading, not a smoothed one: its noise stays white, so the fourth-
                # difference noise estimate (and with it the interval) accounts for it.
                y = y - (self.ambient_level if self.ambient_level is not None else np.nan)
                rate = 0.0
            messages.extend(self._one(float(t), y.copy(), rate))
        self.notes.extend(messages)
        return messages

    def _note_reading(self, y: FloatArray) -> None:
        assert self.on_grid is not None and self.raw_low is not None and self.raw_high is not None
        self.on_grid &= on_display_steps(y)
        self.raw_low, self.raw_high = np.fmin(self.raw_low, y), np.fmax(self.raw_high, y)

    def _display_step(self) -> FloatArray:
        """Per sensor, the step the raw readings are rounded to (°C; 0: none seen)."""
        assert self.on_grid is not None and self.raw_low is not None and self.raw_high is not None
        return step_from_grid(self.on_grid, self.raw_high - self.raw_low)

    def _take_bin(self) -> tuple[float, FloatArray, float]:
        """The gathered bin as one sample: its mean time, readings and room (NaN where none was valid)."""
        rows, self.pending = self.pending, self.pending[:0]
        if len(rows) == 1:
            return float(rows[0, 0]), rows[0, 2:].copy(), float(rows[0, 1])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", RuntimeWarning)  # a sensor without a valid reading in the bin
            means = np.nanmean(rows, axis=0)
        return float(means[0]), means[2:], float(means[1])

    def _checked(self, times: FloatArray, values: FloatArray, ambient: FloatArray | None) -> tuple[FloatArray, FloatArray, FloatArray]:
        """The samples as (n,), (n, S) and (n,) float arrays, or an :class:`InputError` naming what is wrong.

        A missing reading is NaN in ``values`` or ``ambient``; times must be known
        and move on (a log follower refuses repeated and backward rows before this).
        """
        S = len(self.sensors)
        try:
            t = np.atleast_1d(np.asarray(times, dtype=float))
            y = np.asarray(values, dtype=float)
            room = np.full(len(t), np.nan) if ambient is None else np.atleast_1d(np.asarray(ambient, dtype=float))
        except (TypeError, ValueError) as exc:
            raise InputError(f"Monitor.feed: times, values and ambient must be numbers ({exc})") from None
        if np.ndim(times) == 0 and y.ndim <= 1:
            y = y.reshape(1, -1)  # one row as it arrives: a time and a reading per sensor
        elif y.ndim == 1 and S == 1:
            y = y[:, None]  # one sensor's readings as a plain column
        if t.ndim != 1 or y.shape != (len(t), S) or room.shape != (len(t),):
            shapes = f"times {t.shape}, values {y.shape}" + ("" if ambient is None else f", ambient {room.shape}")
            raise InputError(f"Monitor.feed: expected times (n,), values (n, {S}) for the sensors {', '.join(self.sensors)}" + ("" if ambient is None else " and ambient (n,)") + f"; got {shapes}")
        if not np.all(np.isfinite(t)):
            raise InputError(f"Monitor.feed: time {int(np.argmin(np.isfinite(t)))} of this batch is not a finite number of minutes")
        previous = np.concatenate([[-np.inf if self.latest_time is None else self.latest_time], t[:-1]])
        back = np.flatnonzero(t <= previous)
        if len(back):
            k = int(back[0])
            raise InputError(f"Monitor.feed: time {k} of this batch ({t[k]:g} min) does not come after the one before it ({previous[k]:g} min); times must increase")
        return t, y, room

    def _one(self, t: float, y: FloatArray, room_rate: float) -> list[str]:
        messages: list[str] = []
        self.samples += 1
        if self.carry is None:
            self.buffer_t.append(t)
            self.buffer_y.append([float(v) for v in y])
            self.buffer_room_rate.append(room_rate)
            ready = t - self.buffer_t[0] >= self.settings.init_min and len(self.buffer_t) >= 8
            if ready:
                messages.extend(self._start())
            return messages
        return self._step(t, y, room_rate)

    def _start(self) -> list[str]:
        t = np.array(self.buffer_t)
        y = np.array(self.buffer_y)
        # A sensor without one valid reading yet gets a flat placeholder; it waits for its rise,
        # and its filter is moved to its first reading when one comes (:meth:`_step`).
        unread = ~np.isfinite(y).any(axis=0)
        # A missing reading stays missing: tuning_from_data takes the rest as they are. Filled with
        # the column's mean, a missing first reading made the start look flat and high, and the
        # filter began off course (λ = 0.24/min, T∞ 19.2 °C on the papers' curve at 10 min): 22 of
        # 200 first-order replays with 12.5 % dropouts went to λ < 0 (stop 17).
        filled = np.where(unread[None, :], 0.0, y)
        self.unread = [bool(u) for u in unread]
        self.tuning = tuning_from_data(t, filled)
        config, _ = self._filter()
        self.carry = initial_carry(GaussianState(self.tuning.initial_mean, self.tuning.initial_cov), self.tuning.process_cov, self.tuning.emission_cov, config)
        S = len(self.sensors)
        self.observed = np.zeros(S)
        self.nis_sum = np.zeros(S)
        self.min_T = self.tuning.initial_mean[:, 0].copy()
        self.max_T = self.tuning.initial_mean[:, 0].copy()
        self.median_dt = float(np.median(np.diff(t))) if len(t) > 1 else 1.0
        self.last_t = None
        self.d4_sum = np.zeros(S)
        self.d4_count = np.zeros(S)
        self.recent_y = self.recent_y[:0]
        self.rejected_run = np.zeros(S)
        self.recent_spikes = np.zeros(S)
        messages = []
        # A sensor that has not begun to rise (the logger started before the spindle) gives no
        # first-order curve to start from: its filter is started again once it rises.
        # One that rose only after a few flat minutes is started again from the start of its rise.
        last_flat = np.where(unread, len(t), flat_lead(t, y, noise_sigma(filled, t), self.settings.min_rise_C, self.settings.late_rise_min))
        late = last_flat > 0
        never = last_flat >= len(t)
        self.restart_from = [float(t[0]) if nv else float(t[k]) if lt else float("nan") for k, lt, nv in zip(last_flat, late, never, strict=True)]
        self.waiting_rise = [bool(lt) for lt in late]
        for s in np.flatnonzero(late):
            if unread[s]:
                self._may_say("dropout", self.sensors[s], float(t[-1]))  # said here; the next reminder in quiet_min
                messages.append(f"sensor {self.sensors[s]!r}: no valid reading in the first {t[-1] - t[0]:g} min ({_MISSING}); waiting for its readings")
            elif never[s]:
                messages.append(f"sensor {self.sensors[s]!r}: no rise in the first {t[-1] - t[0]:g} min; waiting for its warm-up to begin")
            else:
                messages.append(f"sensor {self.sensors[s]!r}: flat until t = {minutes(t[last_flat[s] + 1])} min; identifying it from the start of its rise")
        for tt, yy, rate in zip(t, y, self.buffer_room_rate, strict=True):
            messages.extend(self._step(float(tt), yy.copy(), rate))
        self.buffer_t, self.buffer_y, self.buffer_room_rate = [], [], []
        return messages

    def _step(self, t: float, y: FloatArray, room_rate: float = 0.0) -> list[str]:
        assert self.carry is not None and self.tuning is not None and self.observed is not None
        assert self.rejected_run is not None and self.min_T is not None and self.max_T is not None and self.nis_sum is not None
        messages: list[str] = []
        config, weights = self._filter()
        dt = 0.0 if self.last_t is None else t - self.last_t
        if self.median_dt and dt > self.settings.gap_factor * self.median_dt:
            messages.append(f"gap in the log: {dt:g} min without samples before t = {minutes(t)} min; bridged by the model")
        step = transition_with_room(dt, room_rate)
        self._first_readings(y)
        self.carry = replace(self.carry, process_cov=self._process_cov(self.carry.mean[:, 2], dt))
        new, info = filter_step(self.carry, y[:, None], step, observe_temperature, config, weights)
        z = _normalised_innovation(info)
        # a sensor waiting for its rise has no model yet to call a sample wild against
        modelled = ~np.array(self.waiting_rise) if self.waiting_rise is not None else np.ones(len(y), dtype=bool)
        wild = np.isfinite(z) & (np.abs(z) > self.settings.spike_sigma) & (self.observed >= self.settings.check_samples) & modelled
        # A spike is one wild sample. Wild samples in a row are not spikes but a change the
        # model missed: accept them and widen the filter (else it would freeze on old data).
        spikes = wild & (self.rejected_run == 0)
        broken = wild & (self.rejected_run > 0)
        # Spikes are rare. Many in a short while are more noise than estimated (a loose contact, a
        # drive's interference): rejected one by one, every other reading was thrown away for good
        # and the noise estimate, which leaves out wild differences, never learnt it.
        recent = (self.recent_spikes if self.recent_spikes is not None else np.zeros(len(y))) * np.exp(-dt / _SPIKE_MEMORY_MIN)
        # (a reading far beyond any noise, a +15 °C glitch, stays a spike however many came before)
        noisier = spikes & (recent >= _SPIKES_FOR_NOISE - 1) & (np.abs(z) < _NOISE_SIGMA_MAX)
        spikes &= ~noisier
        self.recent_spikes = recent + spikes
        if np.any(noisier):
            for s in np.flatnonzero(noisier):
                messages.append(f"sensor {self.sensors[s]!r}: one more wild reading at t = {minutes(t)} min after {_SPIKES_FOR_NOISE} spikes in the last {_SPIKE_MEMORY_MIN:g} min or so: more noise than estimated, not spikes; taking them in and estimating the noise again")
            self._relearn_noise(noisier)
            self.recent_spikes = np.where(noisier, 0.0, self.recent_spikes)
            new, info = filter_step(self.carry, y[:, None], step, observe_temperature, config, weights)
            z = _normalised_innovation(info)
        self.rejected_run = np.where(wild & ~noisier, self.rejected_run + 1, 0.0)
        if np.any(broken):
            for s in np.flatnonzero(broken):
                messages.append(f"sensor {self.sensors[s]!r}: a second wild sample in a row at t = {minutes(t)} min; not a spike: the warm-up changed course, widening its parameter uncertainty")
            self._widen(broken)
            new, info = filter_step(self.carry, y[:, None], step, observe_temperature, config, weights)
            z = _normalised_innovation(info)
        if np.any(spikes):
            for s in np.flatnonzero(spikes):
                messages.append(f"sensor {self.sensors[s]!r}: rejected a spike at t = {minutes(t)} min ({y[s]:.2f} °C, {abs(z[s]):.0f}σ from the prediction)")
            y[spikes] = np.nan
            new, info = filter_step(self.carry, y[:, None], step, observe_temperature, config, weights)
            z = _normalised_innovation(info)
        for s in np.flatnonzero(~np.isfinite(y) & ~spikes):
            if self._may_say("dropout", self.sensors[s], t):
                if self.unread is not None and self.unread[s]:
                    messages.append(f"sensor {self.sensors[s]!r}: still no valid reading at t = {minutes(t)} min; waiting for its readings{self._quiet_note()}")
                else:
                    messages.append(f"sensor {self.sensors[s]!r}: no valid reading at t = {minutes(t)} min ({_MISSING}); bridged{self._quiet_note()}")
        self.carry = new
        self.last_t = t
        self.recent_rows = _since(_append_row(self.recent_rows, [t, room_rate, *y]), t - self.settings.restart_delay_min)
        self._update_noise(y)
        ok = np.isfinite(z)
        self.observed, self.nis_sum = _count_innovations(self.observed, self.nis_sum, z)
        self.z_history = _append_row(self.z_history, z)[-self.settings.check_samples :]
        physical, cov = to_physical(self.carry.mean, self.carry.covariance(), "slope")
        temperature = physical[:, 0]
        self.min_T = np.minimum(self.min_T, temperature)
        self.max_T = np.maximum(self.max_T, temperature)
        # A sensor without a valid sample this step cannot be said to hold still: NaN in its history.
        history = _append_row(self.steady_history, [t, *np.where(ok, physical[:, 2], np.nan)])
        # the oldest rows go while the next one is still at or beyond the hold's start (two stay)
        beyond = int(np.searchsorted(history[1:, 0], t - self._hold(t), side="right"))
        self.steady_history = history[min(beyond, max(len(history) - 2, 0)) :]
        one_sided, too_large = self._misfit_tests()
        misfit_now = one_sided | too_large
        misfit = misfit_now & modelled
        if np.any(misfit):
            measured_room = self.room_measured
            what = f"identifying it again from the next {self.settings.restart_delay_min:g} min" if measured_room else "widening its parameter uncertainty to follow the new trend"
            assert self.d4_count is not None
            for s in np.flatnonzero(misfit):
                if not self._may_say("misfit", self.sensors[s], t):
                    continue
                if not one_sided[s] and self.d4_count[s] < _MATURE_NOISE_ESTIMATE:
                    # Large residuals of both signs, with a noise level estimated from few samples:
                    # 10 of 100 first-order replays failed the check this way in their first hour
                    # (and 11 of 100 fast + slow ones first did). 5 readings per fourth difference.
                    why = f"are larger than the noise estimated so far from {int(self.d4_count[s]) + 4} readings (more noise than those showed, or a slower mode)"
                elif one_sided[s]:
                    # A filter started on the first minutes still settles for a while: 8 of the 11
                    # first-order replays (of 100) that failed this way did so before 30 min, none
                    # of them once started on 20 min of data (stop 17).
                    age = max(float(self.observed[s]) - 1.0, 0.0) * (self.median_dt or 1.0)
                    young = f", or its filter, {minutes(age)} min old, still settling" if age < _SETTLING_MIN else ""
                    why = f"no longer fit the first-order model: a trend it misses (a slower mode{young}?)"
                else:
                    why = "no longer fit the first-order model (a slower mode?)"
                messages.append(f"sensor {self.sensors[s]!r}: residuals at t = {minutes(t)} min {why}; {what}{self._quiet_note()}")
            self._widen(misfit)
        was_waiting = np.array(self.waiting_rise) if self.waiting_rise is not None else np.zeros(len(self.sensors), dtype=bool)
        due = self._schedule_restarts(t, misfit & self.room_measured)
        if np.any(due):
            self._restart(due, first_start=due & was_waiting)
        # unchanged since they were computed above unless a filter was widened or started again
        status = self.status(None if np.any(misfit) or np.any(due) else (physical, cov, misfit_now))
        messages.extend(self._note_wandering(status))
        self._record_checkpoint(t, status)
        if self.stop_time is None and all(st.may_stop for st in status) and not all(st.status in _LEFT_OUT for st in status):
            self.stop_time = t
            self.decision = [self._summary(st) for st in status]
            messages.append(f"the test can stop at t = {minutes(t)} min")
        return messages

    def _first_readings(self, y: FloatArray) -> None:
        """A sensor read for the first time: its flat placeholder filter moves to the reading.

        It is still waiting for its rise (flat since the start, as far as the
        monitor knows), so it is started afresh once it rises.
        """
        if self.unread is None or not any(self.unread):
            return
        assert self.carry is not None and self.min_T is not None and self.max_T is not None
        first = np.array(self.unread) & np.isfinite(y)
        if not np.any(first):
            return
        mean = self.carry.mean.copy()
        mean[first, 0] = y[first]
        self.carry = replace(self.carry, mean=mean)
        self.min_T = np.where(first, y, self.min_T)
        self.max_T = np.where(first, y, self.max_T)
        self.unread = [bool(u and not f) for u, f in zip(self.unread, first, strict=True)]

    def _record_checkpoint(self, t: float, status: list[SensorStatus]) -> None:
        """Keep each T∞ (over the room, with ``ambient``) and its half-width, about 60 times per window."""
        window = self.settings.consistency_window_min
        if len(self.checkpoints) and t - self.checkpoints[-1, 0] < window / 60.0:
            return
        # Estimates before the minimum duration, or with intervals wider than twice the tolerance,
        # are too far from Gaussian (T∞ = T + s/λ is a ratio) to hold later ones to.
        mature = t >= self.settings.min_duration_min
        usable = [mature and st.status not in ("no steady state yet", *_LEFT_OUT) and st.half_width_C <= 2 * self.settings.tolerance_C for st in status]
        steady = [st.steady_state_C if use else float("nan") for st, use in zip(status, usable, strict=True)]
        self.checkpoints = _since(_append_row(self.checkpoints, [t, self.ambient_level or 0.0, *steady, *[st.half_width_C for st in status]]), t - window)

    def _outside(self, steady: FloatArray) -> np.ndarray:
        """(checkpoints, S): where T∞ now lies outside an earlier estimate's allowance.

        With a room sensor the comparison is of T∞ over the room: T∞ itself
        follows the room, as it should.
        """
        S = len(self.sensors)
        rows = self.checkpoints
        room, then, halves = rows[:, 1], rows[:, 2 : 2 + S], rows[:, 2 + S :]
        # a shift within ±tolerance/2 is left to the hold rule: it does not change the answer
        allowed = np.maximum(self.settings.consistency_factor * halves, self.settings.tolerance_C / 2)
        with np.errstate(invalid="ignore"):
            outside = np.abs((steady - (self.ambient_level or 0.0))[None, :] - (then - room[:, None])) > allowed
        return outside & np.isfinite(then) & np.isfinite(halves)

    def _note_wandering(self, status: list[SensorStatus]) -> list[str]:
        """A message when a sensor's T∞ starts wandering outside its earlier intervals."""
        now = [st.status == "wandering" for st in status]
        before = self.wandering or [False] * len(status)
        self.wandering = now
        started = [s for s in range(len(status)) if now[s] and not before[s]]
        if not started:
            return []
        outside = self._outside(np.array([st.steady_state_C for st in status]))
        hint = "" if self.ambient_level is not None else "; a room sensor (--ambient) takes the room's drift into account"
        messages = []
        for s in started:
            if not self._may_say("wandering", self.sensors[s], float(self.last_t or 0.0)):
                continue
            k = int(np.argmax(outside[:, s]))
            then, half, when = self.checkpoints[k, 2 + s], self.checkpoints[k, 2 + len(status) + s], self.checkpoints[k, 0]
            messages.append(
                f"sensor {status[s].sensor!r}: T∞ = {status[s].steady_state_C:.2f} °C has left the interval {then:.2f} ± {half:.2f} °C of t = {minutes(when)} min "
                f"(by more than {self.settings.consistency_factor:g}× its half-width): not a first-order warm-up here, a slow mode or a drifting room{hint}; waiting for it to settle"
            )
        return messages

    def _may_say(self, kind: str, who: str, t: float) -> bool:
        """Whether to repeat a message of this kind for this sensor (or the room): at most once per
        ``quiet_min`` (a dead sensor or a slow mode would otherwise repeat it every sample)."""
        key = f"{kind}:{who}"
        last = self.last_said.get(key)
        if last is not None and t - last < self.settings.quiet_min:
            return False
        self.last_said[key] = t
        return True

    def _quiet_note(self) -> str:
        return f" (not repeated within {self.settings.quiet_min:g} min)"

    def _filter(self) -> tuple[FilterConfig, SigmaWeights]:
        """The UKF variant and its sigma weights for the tuning (computed once)."""
        if self._config is None or self._weights is None:
            assert self.tuning is not None
            self._config = filter_config("ukf", self.tuning)
            self._weights = self._config.sigma_points.weights(3)
        return self._config, self._weights

    def _update_noise(self, y: FloatArray) -> None:
        """Running noise variance from fourth differences (σ² = E[Δ⁴y²]/70), spikes excluded; sets R.

        The 10-minute start window gives only a handful of differences, so R is
        re-estimated with every sample (constant work) instead of trusted.
        """
        assert self.d4_sum is not None and self.d4_count is not None and self.carry is not None
        self.recent_y = _append_row(self.recent_y, y)[-5:]
        if len(self.recent_y) < 5:
            return
        r = self.recent_y
        d4 = r[0] - 4 * r[1] + 6 * r[2] - 4 * r[3] + r[4]
        current = np.where(self.d4_count > 0, self.d4_sum / np.maximum(self.d4_count, 1), np.inf)
        use = np.isfinite(d4) & ((self.d4_count < 10) | (d4**2 <= 36.0 * current))
        self.d4_sum = self.d4_sum + np.where(use, d4**2, 0.0)
        self.d4_count = self.d4_count + use
        ready = self.d4_count >= 5
        if np.any(ready):
            # Rounded readings (a 1/16 °C sensor) give fourth differences mostly 0 and now and then
            # a whole step, which the outlier guard above leaves out: the running mean alone fell to
            # a tenth of the rounding's q²/12 and every later sample looked like a spike.
            rounding = self._display_step() ** 2 / 12.0
            variance = np.where(ready, np.maximum(self.d4_sum / np.maximum(self.d4_count, 1) / 70.0, np.maximum(rounding, 1e-12)), self.carry.emission_cov[:, 0, 0])
            self.carry = replace(self.carry, emission_cov=variance[:, None, None])

    def _relearn_noise(self, mask: np.ndarray) -> None:
        """Estimate the noise of the ``mask`` sensors afresh from their next readings (their wild ones
        included), starting from four times the present variance (twice the σ). Their residuals'
        statistics start again too: measured against the old noise they were large, and the
        consistency factor they left kept the T∞ interval wide to the log's end."""
        assert self.d4_sum is not None and self.d4_count is not None and self.carry is not None
        assert self.observed is not None and self.nis_sum is not None
        self.d4_sum = np.where(mask, 0.0, self.d4_sum)
        self.d4_count = np.where(mask, 0.0, self.d4_count)
        self.observed = np.where(mask, 0.0, self.observed)
        self.nis_sum = np.where(mask, 0.0, self.nis_sum)
        self.z_history[:, mask] = np.nan
        variance = np.where(mask, 4.0 * self.carry.emission_cov[:, 0, 0], self.carry.emission_cov[:, 0, 0])
        self.carry = replace(self.carry, emission_cov=variance[:, None, None])

    def _hold(self, t: float) -> float:
        """How long T∞ must hold still: ``hold_min``, or ``hold_fraction`` of the test so far if
        longer (late in a test a slow mode shows only over a longer stretch)."""
        return max(self.settings.hold_min, self.settings.hold_fraction * t)

    def _misfit(self) -> np.ndarray:
        one_sided, too_large = self._misfit_tests()
        return one_sided | too_large

    def _misfit_tests(self) -> tuple[np.ndarray, np.ndarray]:
        """The model check over the last ``check_samples`` normalised innovations, per sensor:
        their mean is off zero (a trend the model misses), or their mean square is off one."""
        z = self.z_history
        if len(z) < self.settings.check_samples:
            none = np.zeros(len(self.sensors), dtype=bool)
            return none, none
        count = np.sum(np.isfinite(z), axis=0)
        enough = count >= self.settings.check_samples // 2
        safe = np.where(enough, count, 1)
        mean = np.where(enough, np.nansum(z, axis=0) / safe, 0.0)
        mean_square = np.where(enough, np.nansum(z**2, axis=0) / safe, 0.0)
        # Early on R comes from a few fourth differences and is itself uncertain: the mean square
        # of z is then F-distributed, not χ². Its 99.9 % quantile keeps a young noise estimate from
        # being taken for a misfit, whose widening then sent some drifting-room runs to a wrong stop
        # (100 seeds: first-order runs with a false alarm 17 -> 13; beyond the tolerance, room felt
        # at once 2 -> 0, lagged room 2 -> 1; fast + slow in a drifting room stopped 84 -> 82).
        assert self.d4_count is not None
        too_large = mean_square > 3.0 + 4.0 * np.sqrt(2.0 / safe)
        if np.any(too_large):  # the F quantile only where it can matter (it cost a tenth of a 1-Hz step)
            noise_dof = np.maximum(self.d4_count / _D4_OVERLAP, 1.0)
            too_large &= mean_square > fdtri(safe, noise_dof, 0.999)
        return enough & (np.abs(mean) * np.sqrt(safe) > 4.5), enough & too_large

    def _schedule_restarts(self, t: float, misfit: np.ndarray) -> np.ndarray:
        """Which sensors to identify afresh now, from their samples since ``restart_from``.

        A sensor is identified again ``restart_delay_min`` after the last reason:
        a failed model check (with a room sensor), a rate λ far outside the
        physical range (a filter thrown off course), or the start of its
        rise (a sensor flat at the start waits, its window moving on, until it
        has risen by more than the noise).
        """
        assert self.carry is not None
        S = len(self.sensors)
        restart_from = np.array(self.restart_from if self.restart_from is not None else [float("nan")] * S)
        waiting = np.array(self.waiting_rise if self.waiting_rise is not None else [False] * S)
        restart_from[misfit] = t
        # λ < 0 for a while is part of the Gaussian approximation early on; growth by a tenth
        # a step is no warm-up (a filter widened after a change of course went to λ = −10/min)
        thrown_off = ~(self.carry.mean[:, 2] * (self.median_dt or 1.0) > -0.1) & ~np.isfinite(restart_from)
        restart_from[thrown_off] = t
        if np.any(waiting):
            # Still flat over the last 5 min: the rise has not begun, and the window for the new
            # start begins at the latest flat sample. Once it rises the window stays put.
            rows = self.recent_rows
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", RuntimeWarning)  # no valid sample in the last 5 min
                values = np.where(rows[:, 0][:, None] >= t - 5.0, rows[:, 2:], np.nan)
                span = np.nanmax(values, axis=0) - np.nanmin(values, axis=0)
            still_flat = waiting & ~(span >= rise_threshold(np.sqrt(self.carry.emission_cov[:, 0, 0]), self.settings.min_rise_C))
            restart_from[still_flat] = t - 1.0
        # a sensor that begins to rise is started like the first one, after ``init_min`` of its rise
        delay = np.where(waiting, self.settings.init_min, self.settings.restart_delay_min)
        with np.errstate(invalid="ignore"):
            due = ~np.isnan(restart_from) & (t - restart_from >= delay)
        waiting &= ~due
        self.restart_from = [float(v) for v in restart_from]
        self.waiting_rise = [bool(v) for v in waiting]
        return due

    def _process_cov(self, rate: FloatArray, dt: float, sensors: np.ndarray | slice = slice(None)) -> FloatArray:
        """Q for one step: the tuning's, plus the room's unmeasured wander as a random input of the heat balance.

        s = λ(T_room + ΔT∞ − T), so a room that moves by δ moves s by λδ (and T∞
        by δ). A random walk of the room with ``room_wander_C_per_h`` (1σ) per
        hour adds λ²σ²Δt/60 to the variance of s each step: the filter no longer
        takes a slope bent by the room for the warm-up's own, and the T∞ interval
        carries where the room may have gone since the data last told.
        """
        assert self.tuning is not None
        q = self.tuning.process_cov[sensors].copy()  # ``rate`` is of these sensors
        if not self.room_measured:
            q[:, 1, 1] += np.maximum(rate, 0.0) ** 2 * self.settings.room_wander_C_per_h**2 * dt / 60.0
        return q

    def _restart(self, due: np.ndarray, first_start: np.ndarray) -> None:
        """Identify the ``due`` sensors again from their samples since ``restart_from``.

        The reasons are in :meth:`_schedule_restarts`; the first one found in use:
        once the fast part of a fast-plus-slow warm-up has died away, the data
        since then are first order again, but a filter that also learnt from the
        fast part stays biased towards it (widening its covariance forgets only
        part of it: T∞ came out at about twice its interval's half-width). A fresh
        filter on the samples since the last failed check (at least
        ``restart_delay_min`` of them; the check is widened-and-watched meanwhile)
        sees only the new trend. Done once per slow mode, not per sample.
        """
        assert self.carry is not None and self.carry.chol is not None and self.restart_from is not None
        rows = self.recent_rows
        rows = rows[rows[:, 0] >= np.nanmin(np.where(due, self.restart_from, np.nan))]
        t, rates, y = rows[:, 0], rows[:, 1], rows[:, 2:].copy()
        y[(t[:, None] < np.array(self.restart_from)[None, :]) | ~due[None, :]] = np.nan
        leading = np.cumsum(np.isfinite(y), axis=0) == 0
        ready = due & ~leading[-1]  # a sensor without a valid sample since then keeps its widened filter
        mean, cov = self.carry.mean.copy(), self.carry.covariance().copy()
        if np.any(ready):
            # missing readings stay missing (see _start); a missing lead is carried back by tuning_from_data
            tuning = tuning_from_data(t, y[:, ready])
            mean[ready], cov[ready] = tuning.initial_mean, tuning.initial_cov
        config, weights = self._filter()
        fresh = initial_carry(GaussianState(mean, cov), self.carry.process_cov, self.carry.emission_cov, config)
        # the restarted sensors' consistency statistics start again with their new data
        assert self.observed is not None and self.nis_sum is not None
        observed, nis_sum = np.zeros(len(due)), np.zeros(len(due))
        for k in range(len(t)):
            dt = 0.0 if k == 0 else float(t[k] - t[k - 1])
            fresh = replace(fresh, process_cov=self._process_cov(fresh.mean[:, 2], dt))
            fresh, info = filter_step(fresh, y[k][:, None], transition_with_room(dt, float(rates[k])), observe_temperature, config, weights)
            observed, nis_sum = _count_innovations(observed, nis_sum, _normalised_innovation(info))
        # A sensor that only now began to rise starts its statistics and its earlier answers afresh:
        # the filter before had nothing to fit. After a failed model check they are kept: the
        # earlier answers and misfits are evidence that the model is in doubt.
        fresh_statistics = ready & first_start
        self.observed = np.where(fresh_statistics, observed, self.observed)
        self.nis_sum = np.where(fresh_statistics, nis_sum, self.nis_sum)
        self.checkpoints[:, 2 : 2 + len(due)][:, fresh_statistics] = np.nan
        assert fresh.chol is not None
        self.carry = replace(
            self.carry,
            mean=np.where(ready[:, None], fresh.mean, self.carry.mean),
            chol=np.where(ready[:, None, None], fresh.chol, self.carry.chol),
        )
        self.restart_from = [float("nan") if d else r for d, r in zip(due, self.restart_from, strict=True)]
        self.z_history[:, ready] = np.nan
        self.steady_history = self.steady_history[-1:]

    def _widen(self, mask: np.ndarray) -> None:
        assert self.carry is not None and self.carry.chol is not None
        factor = np.where(mask, 2.0, 1.0)[:, None, None]
        self.carry = replace(self.carry, chol=self.carry.chol * factor)
        self.z_history[:, mask] = np.nan
        self.steady_history = self.steady_history[-1:]

    # ---- the decision -------------------------------------------------------------------
    def status(self, _current: tuple[FloatArray, FloatArray, np.ndarray] | None = None) -> list[SensorStatus]:
        """Per-sensor estimate and whether it may stop now."""
        out = []
        if self.carry is None:
            return [SensorStatus(name, float(self.buffer_y[-1][i]) if self.buffer_y else float("nan"), float("nan"), float("nan"), float("nan"), False, "collecting") for i, name in enumerate(self.sensors)]
        physical, cov, misfit = _current if _current is not None else (*to_physical(self.carry.mean, self.carry.covariance(), "slope"), self._misfit())
        assert self.observed is not None and self.nis_sum is not None and self.min_T is not None and self.max_T is not None
        factor = np.maximum(1.0, self.nis_sum / np.maximum(self.observed - 3, 1))
        history = self.steady_history
        # with a directly coupled room the filters follow the rise over the room
        offset = (self.ambient_level or 0.0) if self.settings.room_coupling == "direct" else 0.0
        quantiles = stdtrit(np.maximum(self.observed - 3, 1), 0.975)
        halves = quantiles * np.sqrt(np.maximum(cov[:, 2, 2], 0.0) * factor)
        wandering: np.ndarray = np.asarray(self._outside(physical[:, 2] + offset).any(axis=0))
        rates = physical[:, 1]
        with np.errstate(divide="ignore", invalid="ignore"):
            equilibrium = np.where(rates > 0, equilibrium_time(rates), np.nan)
        stable = self._holds_still(history, physical[:, 2], equilibrium)
        for s, name in enumerate(self.sensors):
            n = int(self.observed[s])
            half = float(halves[s])
            steady = float(physical[s, 2])
            rate = float(rates[s])
            eq = float(equilibrium[s])
            rise = float(self.max_T[s] - self.min_T[s])
            long_enough = self.samples * (self.median_dt or 1.0) >= self.settings.init_min + self.settings.hold_min
            waiting = self.waiting_rise is not None and self.waiting_rise[s]
            # waiting and flat over the last 5 min (its window start moved up to now): no rise yet
            still_flat = waiting and self.restart_from is not None and self.last_t is not None and self.restart_from[s] >= self.last_t - 1.0
            unread = self.unread is not None and self.unread[s]
            if unread:
                state, may = ("no data", True) if long_enough else ("collecting", False)
            elif long_enough and (rise < self.settings.min_rise_C or still_flat):
                state, may = "no rise", True
            elif waiting:
                state, may = "collecting", False
            elif misfit[s] or (self.restart_from is not None and np.isfinite(self.restart_from[s])):
                state, may = "model check", False
            elif not np.isfinite(steady) or rate <= 0:
                state, may = "no steady state yet", False
            elif n < self.settings.min_samples or history[-1, 0] < self.settings.min_duration_min:
                state, may = "collecting", False
            elif half > self.settings.interval_fraction * self.settings.tolerance_C:
                state, may = "narrowing", False
            elif wandering[s]:
                state, may = "wandering", False
            elif not stable[s]:
                state, may = "settling", False
            else:
                state, may = "may stop", True
            if unread:  # its filter holds a placeholder, not an estimate
                out.append(SensorStatus(name, float("nan"), float("nan"), float("nan"), float("nan"), may, state))
                continue
            out.append(SensorStatus(name, float(physical[s, 0]) + offset, steady + offset, half, eq, may, state))
        return out

    def _holds_still(self, history: FloatArray, steady: FloatArray, equilibrium: FloatArray) -> np.ndarray:
        """Rule 2 for every sensor: T∞ within ±tolerance/2 over the hold, and no creep.

        ``history`` rows are [t, T∞ per sensor] (NaN: no valid sample); the creep
        is the least-squares slope of T∞ over the hold, carried on towards the
        predicted equilibrium, at least one and at most three holds ahead.
        """
        times, columns = history[:, 0], history[:, 1:]
        valid = np.isfinite(columns)
        count = valid.sum(axis=0)
        hold = self._hold(float(times[-1]))
        half_band = self.settings.tolerance_C / 2
        with np.errstate(invalid="ignore"):
            inside = np.all(~valid | (np.abs(columns - steady[None, :]) <= half_band), axis=0)
        stable = (times[-1] - times[0] >= hold - 1e-9) & (count >= 0.8 * len(times)) & inside
        weights = valid.astype(float)
        n = np.maximum(count, 1)
        values = np.where(valid, columns, 0.0)
        centred = (times[:, None] - (weights * times[:, None]).sum(axis=0) / n) * weights
        spread = (centred**2).sum(axis=0)
        trend = np.where(spread > 0, (centred * (values - values.sum(axis=0) / n)).sum(axis=0) / np.where(spread > 0, spread, 1.0), 0.0)
        remaining = np.where(np.isfinite(equilibrium), np.clip(equilibrium - times[-1], hold, self.settings.creep_holds * hold), np.inf)
        with np.errstate(invalid="ignore"):
            no_creep = np.abs(trend) * remaining <= half_band
        return stable & ((count <= 2) | no_creep)

    # ---- the forecast -------------------------------------------------------------------
    def expected_stop_times(self, horizon_min: float = _FORECAST_HORIZON_MIN) -> FloatArray:
        """Per sensor, when the rule expects it may stop if its warm-up keeps its present course.

        Each filter is run on from now on its own predicted readings. A UKF's
        covariance update does not depend on the reading, only on where the
        filter is, so its T∞ interval narrows as real readings on that course
        would narrow it (with the room's wander and the noise as estimated so
        far). The expected time is the first at which the interval fits
        (rule 1), no earlier than the hold (rule 2, from the last T∞ outside the
        hold's band, or the start of the hold after a restart) and the minimum
        duration allow (and, for a sensor to be identified again, its restart).
        It assumes the first-order course holds: a slow mode not
        yet seen, a drifting room or a failed model check move the real stop
        later (``benchmarks/bench_watch.py`` measures how far).

        Returns the time in minutes: the current time for a sensor that may stop
        now, NaN for one left out of the decision ("no rise", "no data"), one
        without a course yet (collecting, no steady state yet), or one whose
        interval does not fit within ``horizon_min`` from now.
        """
        key = (self.samples, self.last_t, horizon_min)
        if self._forecast is not None and self._forecast[0] == key:
            return self._forecast[1].copy()
        expected = self._expected_stop_times(horizon_min)
        self._forecast = (key, expected.copy())
        return expected

    def _expected_stop_times(self, horizon_min: float) -> FloatArray:
        S = len(self.sensors)
        expected = np.full(S, np.nan)
        if self.stop_time is not None:  # decided: the sensors in the decision stopped then
            return np.where([st.left_out for st in self.status()], np.nan, self.stop_time)
        if self.carry is None or self.last_t is None:
            return expected
        assert self.observed is not None and self.nis_sum is not None
        status = self.status()
        now = self.last_t
        physical = to_physical(self.carry.mean, self.carry.covariance(), "slope")[0]
        waiting = np.array(self.waiting_rise if self.waiting_rise is not None else [False] * S) | np.array(self.unread if self.unread is not None else [False] * S)
        with np.errstate(invalid="ignore"):
            course = (physical[:, 1] > 0) & np.isfinite(physical[:, 2]) & ~waiting & ~np.array([st.left_out for st in status])
        may = np.array([st.may_stop and not st.left_out for st in status])
        expected[may] = now
        todo = course & ~may
        if not np.any(todo):
            return expected
        half_band = self.settings.tolerance_C / 2
        # rule 2: the hold runs from the last T∞ outside the band around the current one (or from
        # the start of the history, if that is younger than a hold: after a restart or a widening)
        history = self.steady_history
        steady_now = physical[:, 2]  # as the history holds it (over the room with a direct coupling)
        with np.errstate(invalid="ignore"):
            outside = np.abs(history[:, 1:] - steady_now[None, :]) > half_band
        last_outside = history[::-1, 0][np.argmax(outside[::-1], axis=0)]
        held = now - history[0, 0] >= self._hold(now) - 1e-9
        anchor = np.where(outside.any(axis=0), last_outside, -np.inf if held else history[0, 0])
        # a sensor to be identified again (a failed model check with a room sensor) starts its hold then
        if self.restart_from is not None:
            anchor = np.fmax(anchor, np.array(self.restart_from) + self.settings.restart_delay_min)
        # Coarse steps keep the forecast cheap: m samples in one step carry their mean, whose noise
        # variance is R/m, and the room's wander grows with the time, not with the steps.
        dt_data = self.median_dt or 1.0
        step = max(dt_data, horizon_min / _FORECAST_STEPS)
        per_step = step / dt_data
        config, weights = self._filter()
        # Only the sensors on a course run on: one far off course (thrown off, to be identified
        # again) overflowed in the batch, and a failure of its factor stopped the others' forecast.
        which = np.flatnonzero(todo)
        parts = {f.name: value[which] for f in fields(self.carry) if (value := getattr(self.carry, f.name)) is not None}
        carry = replace(self.carry, **{**parts, "emission_cov": parts["emission_cov"] / per_step})
        threshold = self.settings.interval_fraction * self.settings.tolerance_C
        observed, nis_sum, anchor = self.observed[which], self.nis_sum[which], anchor[which]
        found = np.full(len(which), np.nan)
        t = now
        # a course that runs off over the horizon (NaN or inf) is only not foreseeable: ready stays False
        with np.errstate(over="ignore", invalid="ignore"):
            while np.any(np.isnan(found)) and t < now + horizon_min:
                t += step
                predicted = slope_transition(carry.mean, step)[:, :1]
                carry = replace(carry, process_cov=self._process_cov(carry.mean[:, 2], step, which))
                try:
                    carry, _ = filter_step(carry, predicted, transition_with_room(step, 0.0), observe_temperature, config, weights)
                except CovarianceError:  # a filter far off course: its stop is not foreseeable
                    break
                # readings on the course fit it: each adds 1 to the sum of normalised innovations squared
                observed, nis_sum = observed + per_step, nis_sum + per_step
                factor = np.maximum(1.0, nis_sum / np.maximum(observed - 3, 1))
                _, cov = to_physical(carry.mean, carry.covariance(), "slope")
                half = stdtrit(np.maximum(observed - 3, 1), 0.975) * np.sqrt(np.maximum(cov[:, 2, 2], 0.0) * factor)
                ready = (half <= threshold) & (t - anchor >= self._hold(t) - 1e-9) & (t >= self.settings.min_duration_min) & (observed >= self.settings.min_samples)
                found[ready & np.isnan(found)] = t
        expected[which] = found
        return expected

    def decided_steady_states(self) -> FloatArray:
        """T∞ per sensor at the decision (NaN for a sensor left out of it); all NaN before the decision."""
        decided = {d["sensor"]: d for d in self.decision or []}
        return np.array(
            [
                np.nan if name not in decided or decided[name]["status"] in _LEFT_OUT or decided[name]["steady_state_C"] is None else float(decided[name]["steady_state_C"])  # type: ignore[arg-type]
                for name in self.sensors
            ]
        )

    def expected_stop_time(self, times: FloatArray | None = None) -> float | None:
        """When the rule expects the test may stop (every sensor in the decision), if the warm-ups keep
        their present courses; None where one sensor's is not foreseeable. ``times``: the sensors'
        from :meth:`expected_stop_times`, if already at hand."""
        if self.stop_time is not None:
            return self.stop_time
        return _test_expected(self.status(), self.expected_stop_times() if times is None else times)

    def _summary(self, st: SensorStatus) -> dict[str, object]:
        num = _number_or_none
        return {
            "sensor": st.sensor,
            "steady_state_C": num(st.steady_state_C),
            "steady_state_ci95_C": [num(st.steady_state_C - st.half_width_C), num(st.steady_state_C + st.half_width_C)],
            "equilibrium_time_min": num(st.equilibrium_time_min),
            "status": st.status,
        }

    def result(self) -> dict[str, object]:
        """The contract's JSON object: the decision if reached, else the current estimates."""
        if self.decision is not None:
            sensors, expected = self.decision, self.stop_time
        else:
            status = self.status()
            times = self.expected_stop_times()
            sensors = [{**self._summary(st), "expected_stop_time_min": _number_or_none(t)} for st, t in zip(status, times, strict=True)]
            expected = _test_expected(status, times)
        payload: dict[str, object] = {"stop_time_min": self.stop_time, "decision": "stop" if self.stop_time is not None else "continue", "last_time_min": self.latest_time}
        eq = [d["equilibrium_time_min"] for d in sensors if d["equilibrium_time_min"] is not None and d["status"] not in _LEFT_OUT]
        if self.stop_time is not None and eq:
            payload["time_saved_min"] = max(float(e) for e in eq) - self.stop_time  # type: ignore[arg-type]
        if len(sensors) == 1:
            payload.update({k: v for k, v in sensors[0].items() if k != "sensor"})
            payload["sensor"] = sensors[0]["sensor"]
        else:
            # The contract's single-sensor keys describe the slowest sensor: the one whose
            # equilibrium the test waits for.
            ranked = [d for d in sensors if d["equilibrium_time_min"] is not None and d["status"] not in _LEFT_OUT] or sensors
            slowest = max(ranked, key=lambda d: d["equilibrium_time_min"] or 0.0)  # type: ignore[arg-type,return-value]
            payload.update({k: v for k, v in slowest.items() if k != "status"})
            payload["sensors"] = sensors
        payload["expected_stop_time_min"] = expected
        return payload

    # ---- persistence --------------------------------------------------------------------
    def to_dict(self) -> dict[str, object]:
        """Everything needed to resume, as plain JSON types (floats round-trip exactly)."""
        carry = None
        if self.carry is not None:
            carry = {k: _tolist(getattr(self.carry, k)) for k in ("mean", "cov", "chol", "process_cov", "emission_cov", "residual_memory", "updates_seen")}
        tuning = None
        if self.tuning is not None:
            tuning = {k: _tolist(getattr(self.tuning, k)) for k in ("initial_mean", "initial_cov", "process_cov", "emission_cov", "threshold_C", "redraw", "parametrisation")}
        return {
            "sensors": list(self.sensors),
            "settings": {k: getattr(self.settings, k) for k in MonitorSettings.__slots__},
            "buffer_t": self.buffer_t,
            "buffer_y": self.buffer_y,
            "tuning": tuning,
            "carry": carry,
            "last_t": self.last_t,
            "median_dt": self.median_dt,
            "observed": _tolist(self.observed),
            "z_history": _tolist(self.z_history),
            "steady_history": _tolist(self.steady_history),
            "nis_sum": _tolist(self.nis_sum),
            "min_T": _tolist(self.min_T),
            "max_T": _tolist(self.max_T),
            "samples": self.samples,
            "recent_y": _tolist(self.recent_y),
            "rejected_run": _tolist(self.rejected_run),
            "recent_spikes": _tolist(self.recent_spikes),
            "room_measured": self.room_measured,
            "ambient_level": self.ambient_level,
            "ambient_time": self.ambient_time,
            "buffer_room_rate": self.buffer_room_rate,
            "d4_sum": _tolist(self.d4_sum),
            "d4_count": _tolist(self.d4_count),
            "on_grid": _tolist(self.on_grid),
            "raw_low": _tolist(self.raw_low),
            "raw_high": _tolist(self.raw_high),
            "pending": _tolist(self.pending),
            "last_row_t": self.last_row_t,
            "checkpoints": _tolist(self.checkpoints),
            "wandering": self.wandering,
            "restart_from": self.restart_from,
            "waiting_rise": self.waiting_rise,
            "unread": self.unread,
            "recent_rows": _tolist(self.recent_rows),
            "last_said": self.last_said,
            "stop_time": self.stop_time,
            "decision": self.decision,
        }

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Monitor:
        """Rebuild a monitor saved with :meth:`to_dict`."""
        tuning = None
        if data["tuning"] is not None:
            t = data["tuning"]
            tuning = ThermalTuning(_floats(t["initial_mean"]), _floats(t["initial_cov"]), _floats(t["process_cov"]), _floats(t["emission_cov"]), _floats(t["threshold_C"]), bool(t["redraw"]), str(t["parametrisation"]))
        carry = None
        if data["carry"] is not None:
            c = data["carry"]
            carry = FilterCarry(_floats(c["mean"]), _optional_floats(c["cov"]), _optional_floats(c["chol"]), _floats(c["process_cov"]), _floats(c["emission_cov"]), _floats(c["residual_memory"]), _floats(c["updates_seen"]))
        return cls(
            sensors=tuple(data["sensors"]),
            settings=MonitorSettings(**data["settings"]),
            buffer_t=list(data["buffer_t"]),
            buffer_y=[list(r) for r in data["buffer_y"]],
            tuning=tuning,
            carry=carry,
            last_t=data["last_t"],
            median_dt=data["median_dt"],
            observed=_optional_floats(data["observed"]),
            z_history=_rows(data["z_history"]),
            steady_history=_rows(data["steady_history"]),
            nis_sum=_optional_floats(data["nis_sum"]),
            min_T=_optional_floats(data["min_T"]),
            max_T=_optional_floats(data["max_T"]),
            samples=int(data["samples"]),
            recent_y=_rows(data["recent_y"]),
            rejected_run=_optional_floats(data["rejected_run"]),
            recent_spikes=_optional_floats(data.get("recent_spikes")),
            room_measured=bool(data.get("room_measured", data["ambient_level"] is not None)),
            ambient_level=data["ambient_level"],
            ambient_time=data.get("ambient_time"),
            buffer_room_rate=list(data.get("buffer_room_rate", [0.0] * len(data["buffer_t"]))),
            d4_sum=_optional_floats(data["d4_sum"]),
            d4_count=_optional_floats(data["d4_count"]),
            on_grid=None if data.get("on_grid") is None else np.array(data["on_grid"], dtype=bool),
            raw_low=_optional_floats(data.get("raw_low")),
            raw_high=_optional_floats(data.get("raw_high")),
            pending=_rows(data.get("pending", [])),
            last_row_t=data.get("last_row_t"),
            checkpoints=_rows(data.get("checkpoints", [])),
            wandering=data.get("wandering"),
            restart_from=data.get("restart_from"),
            waiting_rise=data.get("waiting_rise"),
            unread=data.get("unread"),
            recent_rows=_rows(data.get("recent_rows", [])),
            last_said=dict(data.get("last_said", {})),
            stop_time=data["stop_time"],
            decision=data["decision"],
        )
