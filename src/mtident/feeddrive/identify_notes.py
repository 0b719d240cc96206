"""What a feed-drive identification says of its record and of its estimate, in words: an
excitation of one frequency or a sweep, parameters the record leaves wide, noise on the measured
forces, and an estimate that does not reproduce the record open loop.
"""

from __future__ import annotations

import numpy as np

from mtident._typing import FloatArray
from mtident.feeddrive.identification import DISTANCE_LIMIT, IDENTIFIED_WITHIN, MISFIT_LIMIT
from mtident.feeddrive.information import Consistency
from mtident.feeddrive.params import IDENTIFIED
from mtident.feeddrive.simulate import FORCE_COLUMNS

__all__ = [
    "NOTED_WIDENING",
    "WIDENED_BY_FORCES",
    "consistency_notes",
    "force_noise_notes",
    "one_frequency_note",
    "parameter_notes",
    "refined_notes",
    "sweep_note",
]


def consistency_notes(check: Consistency, columns: tuple[str, ...]) -> list[str]:
    """A note if the set the estimate's intervals allow does not reproduce the record open loop.

    The filtered responses follow the data whatever the parameters (the states are corrected every
    sample: all correlations 0.99999 under a 100 Hz sine whose estimate was 17-45 % off, with
    intervals under 1 %). Run open loop from the start with the measured forces, a wrong estimate
    leaves the data, and no set its intervals allow brings it back.
    """
    worst = int(np.argmax(check.misfit))
    if check.misfit[worst] <= MISFIT_LIMIT and check.distance <= DISTANCE_LIMIT:
        return []
    found = (
        f"{columns[worst]} leaves the data by {check.misfit[worst]:.1f}× the assumed noise "
        f"(RMS; 1 expected, at most {MISFIT_LIMIT:g} accepted)"
        if check.misfit[worst] > MISFIT_LIMIT
        else f"only a set {np.sqrt(check.distance):.1f} standard deviations (Mahalanobis) "
        "from the estimate reproduces it "
        f"(at most {np.sqrt(DISTANCE_LIMIT):.1f} expected)"
    )
    return [
        "the estimate does not reproduce the record: of the parameter sets its intervals allow, "
        f"fitted open loop with the measured forces, "
        f"{found}. The filter may have settled on a wrong set (an excitation of one frequency near a mode does this), "
        "or the noise is larger than assumed: the intervals do not hold"
    ]


# A force this close to one sine (the share of its variance a sine at its strongest frequency explains)
# excites one frequency only.
_ONE_FREQUENCY_SHARE = 0.95
# A sweep, looked for in this many windows of the record: one narrow band at a time (the bins
# holding this share of a window's power lie within this fraction of its spectrum), moving from
# window to window.
_SWEEP_WINDOWS = 16
_SWEEP_MIN_WINDOW = 32
_SWEEP_POWER = 0.9
_SWEEP_BAND = 0.1


def one_frequency_note(forces: FloatArray, h: float) -> list[str]:
    """A note where every force that acts is one sine: the record then shows the drive's response at
    that frequency alone (an amplitude and a phase per response), too little to tell eight stiffness
    and damping parameters apart; the filter may settle on a wrong set that fits it."""
    acting = [k for k in range(forces.shape[1]) if np.ptp(forces[:, k]) > 0]
    if not acting:
        return []
    t = np.arange(len(forces)) * h
    found = []
    for k in acting:
        f = forces[:, k] - forces[:, k].mean()
        spectrum = np.abs(np.fft.rfft(f))
        peak = int(np.argmax(spectrum[1:])) + 1
        # the strongest line, between two bins: the sine through it by least squares, at a few
        # frequencies around the bin (a sine between bins leaks into its neighbours)
        best, best_frequency = 0.0, 0.0
        for frequency in (peak + np.linspace(-0.5, 0.5, 11)) / (len(f) * h):
            basis = np.column_stack(
                [np.sin(2 * np.pi * frequency * t), np.cos(2 * np.pi * frequency * t), np.ones_like(t)]
            )
            fitted = basis @ np.linalg.lstsq(basis, f, rcond=None)[0]
            share = 1.0 - float(np.sum((f - fitted) ** 2) / np.sum(f**2))
            best, best_frequency = max((best, best_frequency), (share, frequency))
        if best < _ONE_FREQUENCY_SHARE:
            return []
        found.append(f"{FORCE_COLUMNS[k]} at {best_frequency:.3g} Hz")
    return [
        f"the excitation is one frequency ({', '.join(found)}): the record shows the drive's response at that "
        "frequency alone, "
        "too little to tell its stiffness and damping parameters apart; an impulse, a step or a binary sequence "
        "(PRBS) excites every mode, and a test plan (plan_tests) says which identifies all eight"
    ]


def sweep_note(forces: FloatArray, h: float, refined: bool = False) -> list[str]:
    """A note where a force sweeps: one narrow band at a time (in short windows), moving through
    the record (a sweep, or a multisine with Schroeder's phases, a periodic chirp). In simulation
    at 1 % noise the filter's damping and friction estimates from such records were biased beyond
    their own intervals (it settles each mode's damping from its broad prior while the sweep
    passes the mode, which the sweep never revisits); binary sequences and impulses, and the
    open-loop refinement of any of them, were not. ``refined``: the note for a refined estimate."""
    found = []
    for k in range(forces.shape[1]):
        length = len(forces) // _SWEEP_WINDOWS
        if np.ptp(forces[:, k]) == 0 or length < _SWEEP_MIN_WINDOW:
            continue
        taper = np.hanning(length)
        spans, centres = [], []
        for w in range(_SWEEP_WINDOWS):
            part = forces[w * length : (w + 1) * length, k]
            power = np.abs(np.fft.rfft((part - part.mean()) * taper))[1:] ** 2
            if not np.sum(power) > 0:
                continue
            # the fewest bins that hold most of the window's power, and how far apart they lie
            strongest = np.argsort(power)[::-1]
            held = strongest[: int(np.searchsorted(np.cumsum(power[strongest]), _SWEEP_POWER * np.sum(power))) + 1]
            spans.append((int(held.max()) - int(held.min()) + 1) / len(power))
            centres.append((float(np.sum(power * np.arange(1, len(power) + 1)) / np.sum(power))) / (length * h))
        if (
            len(spans) >= _SWEEP_WINDOWS // 2
            and float(np.median(spans)) <= _SWEEP_BAND
            and max(centres) - min(centres) > 4.0 / (length * h)
        ):
            found.append(f"{FORCE_COLUMNS[k]} from about {min(centres):.3g} to {max(centres):.3g} Hz")
    if not found:
        return []
    swept = f"the excitation sweeps through its band ({', '.join(found)}: a sweep, or a Schroeder-phase multisine"
    if refined:
        return [
            f"{swept}): the filter's damping and friction estimates (filter_parameters) are biased on such records, "
            "the refined ones were not in simulation"
        ]
    return [
        f"{swept}, which is one): in simulation the filter's damping and friction estimates from such records were "
        "biased beyond their own intervals, where binary sequences (PRBS) and impulses were not; refine the estimate "
        "open loop (refine), which was unbiased on them, or treat Bt, Bb, Qb and Qm with care"
    ]


def parameter_notes(final_sd_log: FloatArray, prior_sd_log: float | None) -> list[str]:
    """A note for each parameter the record leaves beyond ±``IDENTIFIED_WITHIN`` (2σ): against the
    filter's prior where it has one (``prior_sd_log``), else (a refined estimate) as it is."""
    said = []
    for name, sd in zip(IDENTIFIED, final_sd_log, strict=True):
        if 2 * sd <= IDENTIFIED_WITHIN:
            continue
        if prior_sd_log is None:
            said.append(
                f"{name}: not identified (±{200 * sd:.3g} % at 2σ, beyond ±{100 * IDENTIFIED_WITHIN:g} %); a test plan "
                "says which test, if any, would identify it"
            )
        else:
            said.append(
                f"{name}: the data barely inform it (standard deviation {100 * sd:.0f} % after the record, prior "
                f"{100 * prior_sd_log:.0f} %); treat its estimate as the guess, not a measurement; a test plan says "
                "which test, if any, would identify it"
            )
    return said


# A parameter whose interval the forces' noise widens more than this many times is said: the record
# would pin it far closer with a cleaner force signal, and its interval rests on the noise estimated
# from the force record.
WIDENED_BY_FORCES = 2.0
# The forces' noise is said where it widens some interval by this much at least.
NOTED_WIDENING = 1.05


def force_noise_notes(input_noise: FloatArray, forces: FloatArray, widened: FloatArray) -> list[str]:
    """What the noise on the measured forces did to the estimate's intervals (nothing where it widened none
    by ``NOTED_WIDENING``), and the parameters it widened beyond ``WIDENED_BY_FORCES``."""
    if float(np.max(widened)) < NOTED_WIDENING:
        return []  # none, or too little to move an interval (an exact sine's spectral floor, 1e-6 of its RMS)
    rms = np.sqrt(np.mean(forces**2, axis=0))
    acting = [q for q in range(len(input_noise)) if input_noise[q] > 0]
    levels = ", ".join(
        f"{FORCE_COLUMNS[q]} {input_noise[q]:.3g}"
        + (f" ({100 * input_noise[q] / rms[q]:.2g} % of its RMS)" if rms[q] > 0 else "")
        for q in acting
    )
    said = [
        f"the measured forces carry noise ({levels}, estimated from the force record as white noise): it drives "
        "the model where it did not drive the drive, and the intervals carry its effect (up to "
        f"{float(np.max(widened)):.2g}× wider than from the responses' noise alone)"
    ]
    flagged = [name for name, factor in zip(IDENTIFIED, widened, strict=True) if factor > WIDENED_BY_FORCES]
    if flagged:
        said.append(
            f"{', '.join(flagged)}: limited by the force signal's noise (its interval {WIDENED_BY_FORCES:g}× or more "
            "wider than the responses' noise alone gives, and resting on the force noise estimated from the record); "
            "a cleaner force signal (filtered, averaged over repeats, a better sensor) pins it closer"
        )
    return said


def refined_notes(notes: list[str], forces: FloatArray, h: float) -> list[str]:
    """The notes of the record that still hold for its refined estimate (a sweep's, reworded)."""
    swept = sweep_note(forces, h, refined=True)
    return [swept[0] if swept and note.startswith("the excitation sweeps") else note for note in notes]
