"""Exceptions raised by mtident.

Every error a user can cause derives from :class:`MtidentError`, so the CLI can
turn it into a one-line message instead of a traceback.
"""

from __future__ import annotations

__all__ = [
    "MtidentError",
    "DimensionError",
    "InputError",
    "CovarianceError",
    "DivergenceError",
    "UnstableModelError",
    "NegativeWeightWarning",
    "ModelFitWarning",
]


class MtidentError(Exception):
    """Base class of every error mtident raises on purpose."""


class DimensionError(MtidentError, ValueError):
    """An array has the wrong shape."""


class InputError(MtidentError, ValueError):
    """A file, column, option or value given by the user is unusable."""


class UnstableModelError(MtidentError, ValueError):
    """A physical parameter set gives an unstable (indefinite) model."""


class CovarianceError(MtidentError, ArithmeticError):
    """A covariance stopped being positive definite inside a filter.

    Carries where it happened so the message can say which filter, which step,
    which stage and how negative the smallest eigenvalue was.
    """

    def __init__(
        self,
        stage: str,
        batch_index: tuple[int, ...] | None,
        min_eigenvalue: float,
        step: int | None = None,
        filter_name: str | None = None,
        hint: str | None = None,
    ) -> None:
        self.stage = stage
        self.batch_index = batch_index
        self.min_eigenvalue = min_eigenvalue
        self.step = step
        self.filter_name = filter_name
        self.hint = hint
        super().__init__(self._message())

    def _message(self) -> str:
        where = []
        if self.filter_name:
            where.append(f"filter {self.filter_name!r}")
        if self.batch_index:
            where.append(f"batch index {self.batch_index}")
        if self.step is not None:
            where.append(f"step {self.step}")
        place = ", ".join(where) if where else "filter"
        return (
            f"{place}: covariance not positive definite at stage '{self.stage}' "
            f"(smallest eigenvalue {self.min_eigenvalue:.3e}); the noise covariances are "
            "probably too small for the scale of the state, or the model diverged"
        ) + (f"; {self.hint}" if self.hint else "")

    def at(self, step: int, filter_name: str | None) -> CovarianceError:
        """Return the same error, now naming the step and the filter.

        Parameters
        ----------
        step : int
            Index of the filter step (the measurement, from 0) at which the covariance failed.
        filter_name : str or None
            Name of the filter (its ``FilterConfig.name``), or None to name none.

        Returns
        -------
        CovarianceError
            A new error with the same stage, batch index and smallest eigenvalue, whose message names both.
        """
        return CovarianceError(self.stage, self.batch_index, self.min_eigenvalue, step, filter_name, self.hint)

    def hinted(self, hint: str) -> CovarianceError:
        """Return the same error with what the caller knows of the way on.

        Parameters
        ----------
        hint : str
            Appended to the message.

        Returns
        -------
        CovarianceError
        """
        return CovarianceError(self.stage, self.batch_index, self.min_eigenvalue, self.step, self.filter_name, hint)


class DivergenceError(MtidentError, ArithmeticError):
    """A filter's estimate stopped being finite, or its covariance positive definite, on data it accepted."""


class NegativeWeightWarning(UserWarning):
    """A sigma-point scheme has a negative centre weight."""


class ModelFitWarning(UserWarning):
    """The data do not fit the model well enough to trust a narrow interval."""
