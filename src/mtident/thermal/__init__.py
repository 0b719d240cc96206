"""Thermal test acceleration: identify a warm-up from its first minutes (Xia et al. 2014; Yu et al. 2019)."""

from mtident.thermal.hindsight import Hindsight, check_decision
from mtident.thermal.identify import Identification, MethodDetails, identify, rmse
from mtident.thermal.min_time import MinTimeResult, minimal_identification_time
from mtident.thermal.model import equilibrium_time, rise_curve, rise_transition
from mtident.thermal.monitor import MonitorSettings, MonitorState, monitor_step, new_state
from mtident.thermal.reference import MachineReference, learn_reference, load_reference, save_reference
from mtident.thermal.robust import RobustSettings
from mtident.thermal.robust_identify import identify_robust
from mtident.thermal.session import WatchSession
from mtident.thermal.settings import DEFAULT_METHOD, METHODS, PRESETS, ThermalTuning, tuning_from_data

__all__ = [
    "DEFAULT_METHOD",
    "Hindsight",
    "Identification",
    "METHODS",
    "MachineReference",
    "MethodDetails",
    "MinTimeResult",
    "MonitorSettings",
    "MonitorState",
    "PRESETS",
    "RobustSettings",
    "ThermalTuning",
    "WatchSession",
    "check_decision",
    "equilibrium_time",
    "identify",
    "identify_robust",
    "learn_reference",
    "load_reference",
    "minimal_identification_time",
    "monitor_step",
    "new_state",
    "rise_curve",
    "rise_transition",
    "rmse",
    "save_reference",
    "tuning_from_data",
]
