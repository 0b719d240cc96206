"""Which test identifies the feed drive: the expected standard deviation of every parameter, from the
Fisher information of the model at a guess, for candidate excitations, and the cheapest test that
identifies all eight.

An impulse on the table rings the modes down in a few hundred milliseconds: it pins the stiffnesses
to a few parts per million but leaves the table's and the screw's axial damping (Bt, Bb) barely
informed, because a lightly damped mode shows its damping only over many periods of motion.
A broadband excitation held through the record (a sweep, a binary sequence, a multisine) keeps every
mode moving, and the information about its damping grows with the record.

The prediction is the Cramér-Rao bound of the filter's own model: the Fisher information of the
log-parameters for white noise of the stated fraction of each response's RMS (as the filter
assumes), plus the filter's prior on them (:mod:`mtident.feeddrive.information`). A single sine is
listed but never recommended: its information is local, and the filter can settle on a wrong set
that fits one frequency (a 100 Hz sine near the first mode did, 17-45 % off with intervals under 1 %).
Sweeps and multisines are listed but not recommended either: on simulated records at 1 % noise the
identification's damping estimates from them came out biased beyond their own intervals, while
those from impulses and binary sequences stayed within them.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from mtident._json import to_json_value
from mtident._typing import BoolArray, FloatArray
from mtident.exceptions import InputError
from mtident.feeddrive.filter_problem import MEASUREMENT_SETS, filter_noise
from mtident.feeddrive.identification import IDENTIFIED_WITHIN
from mtident.feeddrive.information import SensitivitySystem, filter_covariance, fisher_covariance, sensitivity_system
from mtident.feeddrive.inputnoise import tolerated_force_noise
from mtident.feeddrive.model import Excitation
from mtident.feeddrive.modes import modes, sampling_problem
from mtident.feeddrive.params import COORDINATES, IDENTIFIED, FeedDriveParameters, validate
from mtident.feeddrive.simulate import RESPONSE_COLUMNS

__all__ = [
    "CandidateTest",
    "PlanPrediction",
    "ExcitationPlan",
    "PlanAnswer",
    "PlanRow",
    "candidate_tests",
    "predict_test",
    "plan_tests",
    "PLAN_KINDS",
]

# The kinds a plan tries, simplest first (the order breaks ties in cost).
PLAN_KINDS = ("impulse", "step", "sweep", "prbs", "multisine", "sine")
# Excitations held through the record: their information grows with its length.
BROADBAND = ("sweep", "prbs", "multisine")
# Listed with their predictions, never recommended: where the identification's estimates on
# simulated records of the excitation did not stay within their own intervals.
NOT_RECOMMENDED = {
    "sine": "one frequency: its information is local, and the filter can settle on a wrong set that fits it",
    "sweep": (
        "biased in simulation: on simulated records at 1 % noise the identification's damping estimates came "
        "out biased beyond their intervals (Bt by -10 to -75 %)"
    ),
    "multisine": (
        "biased in simulation: on simulated records at 1 % noise the identification's damping and friction "
        "estimates came out biased beyond their intervals (up to 9 standard deviations)"
    ),
}
# A lengthened test's duration: from its candidate's, for the widest interval times this over the target.
LENGTHEN_MARGIN = 1.1
# The longest test a plan proposes (10 kHz for two minutes: 1.2 million samples to identify), and
# how many lengthenings it predicts on the way.
MAX_LENGTHENED_S = 120.0
LENGTHEN_TRIES = 3
_FORCE_NAMES = {0: "table force", 1: "screw axial force", 2: "screw torque", 3: "motor torque"}


@dataclass(frozen=True, slots=True)
class CandidateTest:
    """One test: an excitation, how long, how fast it is sampled and what is measured.

    Attributes
    ----------
    excitation : Excitation
    duration_s, sample_rate_Hz : float
    measured : tuple of int
        Indices into ``RESPONSE_COLUMNS``.
    """

    excitation: Excitation
    duration_s: float
    sample_rate_Hz: float
    measured: tuple[int, ...]

    @property
    def label(self) -> str:
        """E.g. ``sweep 52-2166 Hz, motor torque, 0.5 s at 10000 Hz``."""
        e = self.excitation
        detail = {
            "sine": f" {e.frequency_Hz:.0f} Hz",
            "sweep": f" {e.frequency_Hz:.0f}-{e.frequency_end_Hz:.0f} Hz",
            "multisine": f" {e.frequency_Hz:.0f}-{e.frequency_end_Hz:.0f} Hz",
            "prbs": f" clock {e.frequency_end_Hz:.0f} Hz",
        }.get(e.kind, "")
        return f"{e.kind}{detail}, {_FORCE_NAMES[e.coordinate]}, {self.duration_s:g} s at {self.sample_rate_Hz:g} Hz"


@dataclass(frozen=True, slots=True)
class PlanPrediction:
    """What a test is expected to tell.

    Attributes
    ----------
    candidate : CandidateTest
    stated_std_log : ndarray, shape (8,)
        The standard deviation of ln(parameter) the identification will state after the test
        (≈ relative standard deviation; what its intervals and its "identified" rest on).
    expected_std_log : ndarray, shape (8,)
        The scatter of ln(estimate) over repeated tests, where the model fits the drive and the
        noise is as stated (the stated one is larger: the filter's random walk on the states).
    identified : ndarray of bool, shape (8,)
        Stated ±2σ within the plan's target: the identification will call it identified.
    reason : str or None
        Why the test is not recommended whatever its numbers (sampling too slow, one frequency).
    force_noise_tolerated : float or None
        For the plan's recommended (else closest) test of a refined estimate: the most white noise on the
        measured forces, a fraction of their RMS, under which what it identifies stays identified
        (``inputnoise.tolerated_force_noise``; inf: any). None where not predicted.
    """

    candidate: CandidateTest
    stated_std_log: FloatArray
    expected_std_log: FloatArray
    identified: BoolArray
    reason: str | None
    force_noise_tolerated: float | None = None

    @property
    def identifies_all(self) -> bool:
        """All eight within the target, and nothing against the test."""
        return bool(self.identified.all()) and self.reason is None

    def answer(self) -> PlanRow:
        """The prediction as the plan's JSON says it.

        Returns
        -------
        PlanRow
        """
        test = self.candidate
        return PlanRow(
            test=test.label,
            kind=test.excitation.kind,
            on=COORDINATES[test.excitation.coordinate],
            duration_s=test.duration_s,
            sample_rate_Hz=test.sample_rate_Hz,
            frequency_Hz=test.excitation.frequency_Hz,
            frequency_end_Hz=test.excitation.frequency_end_Hz,
            measured=tuple(RESPONSE_COLUMNS[i] for i in test.measured),
            stated_std_relative={n: float(s) for n, s in zip(IDENTIFIED, self.stated_std_log, strict=True)},
            expected_std_relative={n: float(s) for n, s in zip(IDENTIFIED, self.expected_std_log, strict=True)},
            identified={n: bool(k) for n, k in zip(IDENTIFIED, self.identified, strict=True)},
            reason=self.reason,
            force_noise_tolerated=self.force_noise_tolerated,
        )


@dataclass(frozen=True, slots=True)
class ExcitationPlan:
    """Predictions for every candidate, and the cheapest that identifies all eight (None if none does).

    Attributes
    ----------
    guess : FeedDriveParameters
    target : float
        Half-width of the ±2σ interval, relative, that counts as identified.
    noise_fraction : float
    predictions : tuple of PlanPrediction
        In the order of cost: shortest, then slowest sampling, then simplest excitation.
    recommended : PlanPrediction or None
        The cheapest that identifies all eight (None if none does).
    closest : PlanPrediction or None
        The one whose widest interval, relative to the target, is narrowest (the cheapest of
        equals); the recommended one where there is one. None only if every test is ruled out.
    lengthened : PlanPrediction or None
        Where no candidate identified all eight: the most informative broadband one run longer
        (also the last of ``predictions``, and the recommended one where it identifies all).
    refine : bool
        The predictions are of the estimate refined open loop (else of the filter's own).
    """

    guess: FeedDriveParameters
    target: float
    noise_fraction: float
    predictions: tuple[PlanPrediction, ...]
    recommended: PlanPrediction | None
    closest: PlanPrediction | None
    lengthened: PlanPrediction | None = None
    refine: bool = False

    def answer(self) -> PlanAnswer:
        """The plan as a record whose fields are its JSON object.

        Returns
        -------
        PlanAnswer
        """
        return PlanAnswer(
            predicts="refined" if self.refine else "filter",
            target_2sd_relative=self.target,
            noise_fraction=self.noise_fraction,
            recommended=None if self.recommended is None else self.recommended.answer(),
            lengthened=None if self.lengthened is None else self.lengthened.answer(),
            closest=None if self.closest is None else self.closest.answer(),
            candidates=tuple(p.answer() for p in self.predictions),
        )

    def summary(self) -> dict[str, object]:
        """A JSON-ready dict: every candidate's expected standard deviations (relative) and the
        recommendation (:meth:`answer`'s fields).

        Returns
        -------
        dict
        """
        tree: dict[str, object] = to_json_value(self.answer())
        return tree


@dataclass(frozen=True, slots=True)
class PlanRow:
    """One candidate test's prediction, as the plan's JSON says it.

    Attributes
    ----------
    test : str
        The test's label.
    kind, on : str
        The excitation and the coordinate it acts on.
    duration_s, sample_rate_Hz, frequency_Hz, frequency_end_Hz : float
    measured : tuple of str
        The responses measured.
    stated_std_relative, expected_std_relative : dict of str to float
        Per parameter, the standard deviations of ln(parameter) stated after the test and expected over repeats.
    identified : dict of str to bool
    reason : str or None
        Why the test is not recommended whatever its numbers.
    force_noise_tolerated : float or None
        The most white noise on the measured forces under which what it identifies stays identified.
    """

    test: str
    kind: str
    on: str
    duration_s: float
    sample_rate_Hz: float
    frequency_Hz: float
    frequency_end_Hz: float
    measured: tuple[str, ...]
    stated_std_relative: dict[str, float]
    expected_std_relative: dict[str, float]
    identified: dict[str, bool]
    reason: str | None
    force_noise_tolerated: float | None


@dataclass(frozen=True, slots=True)
class PlanAnswer:
    """A test plan as its JSON object says it.

    Attributes
    ----------
    predicts : str
        "refined" or "filter": whose estimate the predictions are of.
    target_2sd_relative, noise_fraction : float
    recommended, lengthened, closest : PlanRow or None
        As :class:`ExcitationPlan` names them.
    candidates : tuple of PlanRow
        Every candidate, in the order of cost.
    """

    predicts: str
    target_2sd_relative: float
    noise_fraction: float
    recommended: PlanRow | None
    lengthened: PlanRow | None
    closest: PlanRow | None
    candidates: tuple[PlanRow, ...]


def _measured(measured: str | tuple[int, ...]) -> tuple[int, ...]:
    if isinstance(measured, str):
        if measured not in MEASUREMENT_SETS:
            msg = f"measurement set {measured!r} is not one of: {', '.join(MEASUREMENT_SETS)}"
            raise InputError(msg)
        return MEASUREMENT_SETS[measured]
    bad = [i for i in measured if i not in range(len(RESPONSE_COLUMNS))]
    if bad or not measured:
        msg = f"measured responses {list(measured)}: expected indices 0-11 of {', '.join(RESPONSE_COLUMNS)}"
        raise InputError(msg)
    return tuple(measured)


def candidate_tests(
    guess: FeedDriveParameters,
    kinds: tuple[str, ...] = PLAN_KINDS,
    coordinates: tuple[int, ...] = (0, 3),
    durations_s: tuple[float, ...] = (0.25, 0.5, 1.0, 2.0),
    sample_rates_Hz: tuple[float, ...] = (10_000.0,),
    measured: str | tuple[int, ...] = "all",
) -> list[CandidateTest]:
    """Candidate tests around the guess's modes.

    The sine is at the first mode; the sweep and the multisine span half the first mode to 1.5 × the
    highest (at most 0.4 × the sampling rate); the binary sequence is clocked at 3 × the highest mode
    (at most half the sampling rate), which keeps its power within 3 dB up to 1.3 × that mode.

    Parameters
    ----------
    guess : FeedDriveParameters
    kinds : tuple of str
        Out of ``PLAN_KINDS``.
    coordinates : tuple of int
        Where the force acts: 0 table force, 3 motor torque (1, 2: screw force, screw torque).
    durations_s, sample_rates_Hz : tuple of float
    measured : {"all", "realistic"} or tuple of int

    Returns
    -------
    list of CandidateTest
    """
    frequencies = modes(validate(guess)).frequencies_Hz
    unknown = [k for k in kinds if k not in PLAN_KINDS]
    if unknown:
        msg = f"excitation {unknown[0]!r} is not one of: {', '.join(PLAN_KINDS)}"
        raise InputError(msg)
    if any(not (d > 0) for d in durations_s) or any(not (f > 0) for f in sample_rates_Hz):
        msg = f"durations {list(durations_s)} s and sampling rates {list(sample_rates_Hz)} Hz must be positive"
        raise InputError(msg)
    indices = _measured(measured)
    out = []
    for rate, duration, kind, coordinate in (
        (r, d, k, c) for r in sorted(sample_rates_Hz) for d in sorted(durations_s) for k in kinds for c in coordinates
    ):
        low, high = 0.5 * frequencies[0], min(1.5 * frequencies[-1], 0.4 * rate)
        frequency, end = {
            "sine": (frequencies[0], frequencies[0]),
            "prbs": (0.0, min(3.0 * frequencies[-1], 0.5 * rate)),
        }.get(kind, (low, high))
        out.append(CandidateTest(Excitation(kind, coordinate, 1.0, frequency, end), duration, rate, indices))
    return out


def predict_test(
    guess: FeedDriveParameters,
    candidate: CandidateTest,
    noise_fraction: float = 0.01,
    target: float = IDENTIFIED_WITHIN,
    system: SensitivitySystem | None = None,
    refine: bool = False,
) -> PlanPrediction:
    """The expected standard deviations after ``candidate``, for the identification started at ``guess``.

    Parameters
    ----------
    guess : FeedDriveParameters
    candidate : CandidateTest
    noise_fraction : float
        Measurement noise standard deviation as a fraction of each response's RMS.
    target : float
        Half-width of the ±2σ interval, relative, that counts as identified.
    system : SensitivitySystem, optional
        The guess's sensitivity system at the candidate's sampling and responses (shared among candidates).
    refine : bool
        Predict the estimate refined open loop (the inverse Fisher information of the record, which
        it states; as ``identify_feed_drive(refine=True)`` gives it, the CLI's default), else the
        filter's own (its prior and process noise included; the default, as for ``identify_feed_drive``).

    Returns
    -------
    PlanPrediction
    """
    h = 1.0 / candidate.sample_rate_Hz
    count = int(round(candidate.duration_s * candidate.sample_rate_Hz)) + 1
    forces = candidate.excitation.forces(np.arange(count, dtype=np.float64) * h)
    if refine:
        stated = scatter = fisher_covariance(guess, forces, h, candidate.measured, noise_fraction, system)
    else:
        noise = filter_noise(noise_fraction, len(candidate.measured))
        stated, scatter = filter_covariance(guess, forces, h, candidate.measured, noise, system)
    stated_std = np.sqrt(np.maximum(np.diag(stated), 0.0))
    reason = sampling_problem(guess, candidate.sample_rate_Hz, "the guess")
    if reason is None and (not refine or candidate.excitation.kind == "sine"):
        reason = NOT_RECOMMENDED.get(candidate.excitation.kind)
    expected_std = np.sqrt(np.maximum(np.diag(scatter), 0.0))
    return PlanPrediction(candidate, stated_std, expected_std, 2 * stated_std <= target, reason)


def plan_tests(
    guess: FeedDriveParameters,
    candidates: list[CandidateTest] | None = None,
    noise_fraction: float = 0.01,
    target: float = IDENTIFIED_WITHIN,
    lengthen: bool = True,
    refine: bool = False,
) -> ExcitationPlan:
    """Predict every candidate and recommend the cheapest that identifies all eight parameters.

    Cost is the test's duration, then its sampling rate, then the excitation's simplicity
    (the order of ``PLAN_KINDS``), table force before motor torque.

    Parameters
    ----------
    guess : FeedDriveParameters
        Where the information is evaluated: the best knowledge of the drive (an earlier estimate).
    candidates : list of CandidateTest, optional
        Default: :func:`candidate_tests` of the guess.
    noise_fraction : float
        Measurement noise standard deviation as a fraction of each response's RMS.
    target : float
        Half-width of the ±2σ interval, relative, that counts as identified (default ±10 %).
    lengthen : bool
        Where no candidate identifies all eight, predict the most informative broadband one
        (sweep, binary sequence, multisine) run as long as it needs, up to ``MAX_LENGTHENED_S``
        (:attr:`ExcitationPlan.lengthened`):
        held through the record, its information grows with the duration, so a longer run of it
        is the cheapest way on (its prediction is computed, not extrapolated).
    refine : bool
        Predict the estimate refined open loop (as ``identify_feed_drive(refine=True)`` and the
        CLI's ``identify`` give it; the CLI's ``plan`` default), else the filter's own; sweeps and
        multisines are recommended only for a refined estimate (the filter's damping from them was
        biased in simulation).

    Returns
    -------
    ExcitationPlan

    Examples
    --------
    For the filter alone, Nguyen-Quoc et al.'s impulse at 1 % noise leaves the guideway damping Bt barely
    known; with sensors a hundred times finer, 2 s of it identify all eight:

    >>> tests = candidate_tests(FeedDriveParameters(), kinds=("impulse",), coordinates=(0,), durations_s=(0.5, 2.0))
    >>> plan = plan_tests(FeedDriveParameters(), tests)
    >>> [round(200 * p.stated_std_log[IDENTIFIED.index("Bt")]) for p in plan.predictions]  # Bt's ±2σ, %
    [72, 46]
    >>> print(plan.recommended)
    None
    >>> plan_tests(FeedDriveParameters(), tests, noise_fraction=1e-4).recommended.candidate.label
    'impulse, table force, 2 s at 10000 Hz'

    Refined open loop, the record's information is all kept: half a second of it is enough.

    >>> plan_tests(FeedDriveParameters(), tests, refine=True).recommended.candidate.label
    'impulse, table force, 0.5 s at 10000 Hz'
    """
    guess = validate(guess)
    if not (0 < target < 10 and noise_fraction > 0):
        msg = (
            f"target {target:g} and noise fraction {noise_fraction:g}: "
            "expected 0 < target < 10 (relative) and a positive noise"
        )
        raise InputError(msg)
    chosen = candidate_tests(guess) if candidates is None else list(candidates)

    def cost(c: CandidateTest) -> tuple[float, float, int, int]:
        return (c.duration_s, c.sample_rate_Hz, PLAN_KINDS.index(c.excitation.kind), c.excitation.coordinate)

    systems: dict[tuple[float, tuple[int, ...]], SensitivitySystem] = {}
    for c in chosen:  # one per sampling rate and measured set, shared by the excitations
        key = (c.sample_rate_Hz, c.measured)
        systems.setdefault(key, sensitivity_system(guess, 1.0 / c.sample_rate_Hz, c.measured))
    predictions = tuple(
        predict_test(guess, c, noise_fraction, target, systems[(c.sample_rate_Hz, c.measured)], refine)
        for c in sorted(chosen, key=cost)
    )
    recommended = next((p for p in predictions if p.identifies_all), None)
    longer = None
    if recommended is None and lengthen:
        longer = _lengthened(guess, predictions, noise_fraction, target, systems, refine)
        if longer is not None:
            predictions, recommended = (*predictions, longer), longer if longer.identifies_all else None
    allowed = [p for p in predictions if p.reason is None]
    # min keeps the first of equals: the cheapest
    closest = recommended or (min(allowed, key=lambda p: float(np.max(p.stated_std_log))) if allowed else None)
    if refine and closest is not None:
        tolerant = _with_tolerance(guess, closest, noise_fraction, target)
        predictions = tuple(tolerant if p is closest else p for p in predictions)
        recommended = tolerant if recommended is closest else recommended
        longer = tolerant if longer is closest else longer
        closest = tolerant
    return ExcitationPlan(guess, target, noise_fraction, predictions, recommended, closest, longer, refine)


def _with_tolerance(
    guess: FeedDriveParameters, prediction: PlanPrediction, noise_fraction: float, target: float
) -> PlanPrediction:
    """``prediction`` with the noise on the measured forces its test tolerates (a refined estimate's)."""
    c = prediction.candidate
    h = 1.0 / c.sample_rate_Hz
    forces = c.excitation.forces(np.arange(int(round(c.duration_s * c.sample_rate_Hz)) + 1, dtype=np.float64) * h)
    tolerated = tolerated_force_noise(guess, forces, h, c.measured, noise_fraction, target)
    return replace(prediction, force_noise_tolerated=tolerated)


def _lengthened(
    guess: FeedDriveParameters,
    predictions: tuple[PlanPrediction, ...],
    noise_fraction: float,
    target: float,
    systems: dict[tuple[float, tuple[int, ...]], SensitivitySystem],
    refine: bool,
) -> PlanPrediction | None:
    """The most informative broadband candidate run long enough to identify all eight, predicted at
    that duration. The information of an excitation held through the record grows about linearly
    with it, so the next duration is the last one's times the square of its widest interval over
    the target, with a margin, rounded up to 1, 1.5, 2, 3, 5 or 7.5 times a power of ten; each
    is predicted in full (a short record's information grows otherwise), at most
    ``LENGTHEN_TRIES`` times and up to ``MAX_LENGTHENED_S``. The longest predicted, whether or not
    it identifies all eight; None where there is no broadband candidate."""
    broadband = [p for p in predictions if p.reason is None and p.candidate.excitation.kind in BROADBAND]
    if not broadband:
        return None
    last = min(broadband, key=lambda p: float(np.max(2 * p.stated_std_log / target)) / np.sqrt(p.candidate.duration_s))
    longest = None
    for _ in range(LENGTHEN_TRIES):
        ratio = float(np.max(2 * last.stated_std_log / target))
        c = last.candidate
        duration = min(_round_up(c.duration_s * (LENGTHEN_MARGIN * ratio) ** 2), MAX_LENGTHENED_S)
        if duration <= c.duration_s:
            break
        longer = CandidateTest(c.excitation, duration, c.sample_rate_Hz, c.measured)
        system = systems[(c.sample_rate_Hz, c.measured)]
        last = longest = predict_test(guess, longer, noise_fraction, target, system, refine)
        if last.identifies_all:
            break
    return longest


def _round_up(seconds: float) -> float:
    """The next of 1, 1.5, 2, 3, 5, 7.5, 10, 15, ... at or above ``seconds``."""
    power = 10.0 ** np.floor(np.log10(seconds))
    return float(next(m * power for m in (1, 1.5, 2, 3, 5, 7.5, 10) if m * power >= seconds * (1 - 1e-9)))
