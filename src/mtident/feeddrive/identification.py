"""A feed drive's identification: the estimated stiffness and damping with their intervals, how
the estimate converged, the responses it reproduces, and its JSON (:class:`FeedDriveIdentification`).
The filter that makes it is :mod:`~mtident.feeddrive.identify`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mtident._json import json_optional, to_json_value
from mtident._typing import BoolArray, FloatArray
from mtident.feeddrive.information import Consistency
from mtident.feeddrive.model import exact_step, input_matrix, system_matrix
from mtident.feeddrive.params import IDENTIFIED, FeedDriveParameters
from mtident.feeddrive.simulate import Response, run_responses

__all__ = ["DISTANCE_LIMIT", "IDENTIFIED_WITHIN", "MISFIT_LIMIT", "FeedDriveAnswer", "FeedDriveIdentification"]

# A parameter is identified when its ±2σ interval is within ±10 % (a tenth of the prior's 2σ, 100 %).
IDENTIFIED_WITHIN = 0.10
# The consistency check (closest_consistent) says the intervals do not hold when the set they allow
# leaves a response by more than this many times its assumed noise (RMS; 1 expected), or lies farther
# from the estimate than this squared Mahalanobis distance (χ² with 8 degrees of freedom: 99.9 % quantile).
MISFIT_LIMIT, DISTANCE_LIMIT = 1.5, 26.1


@dataclass(frozen=True, slots=True)
class FeedDriveAnswer:
    """A feed drive's identification as its JSON object says it; a key whose field is None is left out.

    Attributes
    ----------
    parameters, parameters_std : dict of str to float
        The estimates and their standard deviations (SI), by name.
    parameters_sd : dict of str to float
        ``parameters_std`` again, for scripts written before that name was used.
    identifiable : dict of str to bool
    correlation : dict of str to float
        Response name → correlation of estimated and measured response.
    measured : tuple of str
        The responses used.
    guess : dict of str to float
    preset : str
    reproduces_record : bool or None
        None where not checked.
    refined : bool
        ``parameters`` is the open-loop refinement of the filter's estimate.
    notes : tuple of str
    filter_parameters, filter_parameters_std : dict of str to float or None
        The filter's own estimate, where refined.
    open_loop_misfit : dict of str to float or None
        Per response, the open-loop misfit in units of its noise, where checked.
    error_percent : dict of str to float or None
        Against the truth, where given.
    within_2sd : dict of str to bool or None
        Whether the ±2σ interval covers the truth, where given.
    """

    parameters: dict[str, float]
    parameters_std: dict[str, float]
    parameters_sd: dict[str, float]
    identifiable: dict[str, bool]
    correlation: dict[str, float]
    measured: tuple[str, ...]
    guess: dict[str, float]
    preset: str
    reproduces_record: bool | None
    refined: bool
    notes: tuple[str, ...]
    filter_parameters: dict[str, float] | None = json_optional()
    filter_parameters_std: dict[str, float] | None = json_optional()
    open_loop_misfit: dict[str, float] | None = json_optional()
    error_percent: dict[str, float] | None = json_optional()
    within_2sd: dict[str, bool] | None = json_optional()


@dataclass(frozen=True)
class FeedDriveIdentification:
    """Result of the joint estimation.

    Attributes
    ----------
    parameters, parameters_std : ndarray, shape (8,)
        Final estimates of ``IDENTIFIED`` and their standard deviations (SI).
    identifiable : ndarray of bool, shape (8,)
        The record pins the parameter down: ±2σ within ±``IDENTIFIED_WITHIN``.
    history, history_std : ndarray, shape (N, 8)
        Convergence of the parameter estimates.
    estimated : ndarray, shape (N, 12)
        Responses of the filtered states.
    correlation : dict
        Response name → correlation of estimated and measured response (Table 2).
    measured_columns : tuple of str
    guess : FeedDriveParameters
    covariance_log : ndarray, shape (8, 8)
        Covariance of the log-parameters at the end of the record.
    consistency : Consistency or None
        The open-loop check of the estimate against the record (None if not run); for a refined
        estimate, the refinement's own fit of the record.
    filter_parameters, filter_parameters_std : ndarray, shape (8,) or None
        The filter's own estimate where ``parameters`` is its open-loop refinement (else None).
    """

    time_s: FloatArray
    parameters: FloatArray
    parameters_std: FloatArray
    prior_sd_log: float
    identifiable: BoolArray
    history: FloatArray
    history_std: FloatArray
    estimated: FloatArray
    correlation: dict[str, float]
    measured_columns: tuple[str, ...]
    guess: FeedDriveParameters
    preset: str
    notes: tuple[str, ...]
    covariance_log: FloatArray
    consistency: Consistency | None
    filter_parameters: FloatArray | None = None
    filter_parameters_std: FloatArray | None = None

    @property
    def parameters_sd(self) -> FloatArray:
        """Alias of ``parameters_std`` (its name before ``parameters_std`` was used)."""
        return self.parameters_std

    def __repr__(self) -> str:
        rows = [
            f"  {name}: {value:.5g} ± {2 * sd:.2g} (2σ){'' if known else ', not identified'}"
            for name, value, sd, known in zip(
                IDENTIFIED, self.parameters, self.parameters_std, self.identifiable, strict=True
            )
        ]
        return "\n".join(
            [
                f"FeedDriveIdentification({self.preset}, {len(self.time_s)} samples, "
                f"measured: {', '.join(self.measured_columns)})",
                *rows,
            ]
        )

    def errors_percent(self, truth: FeedDriveParameters) -> dict[str, float]:
        """Table 3: 100·|estimate − truth|/truth per parameter.

        Parameters
        ----------
        truth : FeedDriveParameters
            The true set (a simulated record's); its K1..K4, Bt, Bb, Qb, Qm are compared.

        Returns
        -------
        dict of str to float
            Name in ``IDENTIFIED`` → relative error of the estimate (%).
        """
        true = truth.identified()
        return {name: float(100 * abs(v - t) / t) for name, v, t in zip(IDENTIFIED, self.parameters, true, strict=True)}

    def covers(self, truth: FeedDriveParameters) -> dict[str, bool]:
        """Whether ±2σ around each estimate contains the truth.

        ``truth`` is the true set, as for :meth:`errors_percent`.

        Returns
        -------
        dict of str to bool
            Name in ``IDENTIFIED`` → the true value lies within ±2 ``parameters_std`` of the estimate.
        """
        true = truth.identified()
        return {
            name: bool(abs(v - t) <= 2 * s)
            for name, v, s, t in zip(IDENTIFIED, self.parameters, self.parameters_std, true, strict=True)
        }

    def reproduces_record(self) -> bool | None:
        """Whether the set the intervals allow reproduces the record open loop (None: not checked)."""
        if self.consistency is None:
            return None
        return bool(np.all(self.consistency.misfit <= MISFIT_LIMIT) and self.consistency.distance <= DISTANCE_LIMIT)

    def model_response(self, response: Response) -> FloatArray:
        """The 12 responses (N, 12) of the set the consistency check fitted, open loop under the record's forces.

        Parameters
        ----------
        response : Response
            The record: its forces (N, N, N m, N m) drive the model, its first two times (s) give the sampling
            interval.

        Returns
        -------
        ndarray, shape (N, 12)
            The 8 states and the 4 accelerations at each sample (``RESPONSE_COLUMNS``), from the start the check
            fitted (rest where it was not run).
        """
        shift = np.zeros(8) if self.consistency is None else self.consistency.parameters_log_shift
        start = np.zeros(8) if self.consistency is None else self.consistency.start
        fitted = self.guess.with_identified(self.parameters * np.exp(shift))
        phi, gamma = exact_step(
            system_matrix(fitted), input_matrix(fitted), float(response.time_s[1] - response.time_s[0])
        )
        return run_responses(fitted, phi, gamma, start, response.forces)

    def answer(self, truth: FeedDriveParameters | None = None) -> FeedDriveAnswer:
        """The answer, its fields the JSON object (parameters, parameters_std, correlation) plus extras.

        Parameters
        ----------
        truth : FeedDriveParameters, optional
            The true set (a simulated record's); given, the errors (:meth:`errors_percent`) and whether the
            intervals cover it (:meth:`covers`) are added.

        Returns
        -------
        FeedDriveAnswer
        """

        def named(values: FloatArray, names: tuple[str, ...] = IDENTIFIED) -> dict[str, float]:
            return {n: float(v) for n, v in zip(names, values, strict=True)}

        std = named(self.parameters_std)
        filtered, filtered_std = self.filter_parameters, self.filter_parameters_std
        return FeedDriveAnswer(
            parameters=named(self.parameters),
            parameters_std=std,
            parameters_sd=std,
            identifiable={n: bool(v) for n, v in zip(IDENTIFIED, self.identifiable, strict=True)},
            correlation=self.correlation,
            measured=tuple(self.measured_columns),
            guess={n: float(getattr(self.guess, n)) for n in IDENTIFIED},
            preset=self.preset,
            reproduces_record=self.reproduces_record(),
            refined=self.filter_parameters is not None,
            notes=tuple(self.notes),
            filter_parameters=None if filtered is None or filtered_std is None else named(filtered),
            filter_parameters_std=None if filtered is None or filtered_std is None else named(filtered_std),
            open_loop_misfit=None
            if self.consistency is None
            else named(self.consistency.misfit, tuple(self.measured_columns)),
            error_percent=None if truth is None else self.errors_percent(truth),
            within_2sd=None if truth is None else self.covers(truth),
        )

    def summary(self, truth: FeedDriveParameters | None = None) -> dict[str, object]:
        """The JSON object (parameters, parameters_std, correlation), plus extras: :meth:`answer`'s fields.

        ``parameters_sd`` repeats ``parameters_std`` for scripts written before that name was used.

        Parameters
        ----------
        truth : FeedDriveParameters, optional
            As for :meth:`answer`.

        Returns
        -------
        dict of str to object
            JSON-ready: the estimates and standard deviations (SI) by name, identifiability, correlations, the
            guess, notes, the filter's own estimate where refined, the open-loop misfit where checked, and with
            ``truth`` "error_percent" and "within_2sd".
        """
        tree: dict[str, object] = to_json_value(self.answer(truth))
        return tree
