"""Thermal test acceleration: identify a warm-up from its first minutes (Xia et al. 2014; Yu et al. 2019).

The default path: :func:`identify` (the model-robust estimate, or a paper's filter) for a log so
far; :func:`monitor_step` over a :class:`MonitorState` for a test followed live, its
:class:`Event` records and each sensor's :class:`SensorCheck`; :class:`WatchSession` for a log
file followed, its state kept for resuming.
"""

from mtident.thermal.hindsight import Hindsight, check_decision
from mtident.thermal.identify import Identification, MethodDetails, identify, rmse
from mtident.thermal.min_time import MinTimeResult, minimal_identification_time
from mtident.thermal.model import equilibrium_time, rise_curve, rise_transition
from mtident.thermal.monitor import MonitorSettings, MonitorState, monitor_step, new_state
from mtident.thermal.monitor_types import Event, EventKind, SensorCheck, Status
from mtident.thermal.reference import MachineReference, load_reference, save_reference
from mtident.thermal.reference_learning import learn_reference
from mtident.thermal.robust import RobustSettings
from mtident.thermal.robust_identify import identify_robust
from mtident.thermal.session import WatchSession
from mtident.thermal.settings import DEFAULT_METHOD, METHODS, PRESETS, ThermalTuning, tuning_from_data

__all__ = [
    "DEFAULT_METHOD",
    "Event",
    "EventKind",
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
    "SensorCheck",
    "Status",
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
