"""The UKF engine: sigma points, standard and square-root UKF, adaptation rules.

Knows nothing of temperatures or ball screws. Every function is batched over
leading axes, so many independent filters advance in one call.
"""

from mtident.ukf.adaptation import AdaptiveLaw, FadingFactor, normalisation_from_reference
from mtident.ukf.filter import (
    FilterCarry,
    FilterConfig,
    FilterRecord,
    GaussianState,
    StepInfo,
    filter_step,
    forecast,
    initial_carry,
    run_filter,
    transition_at,
)
from mtident.ukf.linalg import cholesky_update, safe_cholesky
from mtident.ukf.sigma_points import MerweScaledSigmaPoints, SigmaWeights, sigma_points

__all__ = [
    "AdaptiveLaw",
    "FadingFactor",
    "FilterCarry",
    "FilterConfig",
    "FilterRecord",
    "GaussianState",
    "MerweScaledSigmaPoints",
    "SigmaWeights",
    "StepInfo",
    "cholesky_update",
    "filter_step",
    "forecast",
    "initial_carry",
    "normalisation_from_reference",
    "run_filter",
    "safe_cholesky",
    "sigma_points",
    "transition_at",
]
