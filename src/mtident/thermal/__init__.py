"""Thermal test acceleration: identify a warm-up from its first minutes (Xia et al. 2014; Yu et al. 2019)."""

from mtident.thermal.identify import Identification, identify, rmse
from mtident.thermal.min_time import MinTimeResult, minimal_identification_time
from mtident.thermal.model import equilibrium_time, rise_curve, rise_transition
from mtident.thermal.settings import DEFAULT_METHOD, METHODS, PRESETS, ThermalTuning, tuning_from_data

__all__ = [
    "DEFAULT_METHOD",
    "Identification",
    "METHODS",
    "MinTimeResult",
    "PRESETS",
    "ThermalTuning",
    "equilibrium_time",
    "identify",
    "minimal_identification_time",
    "rise_curve",
    "rise_transition",
    "rmse",
    "tuning_from_data",
]
