"""Reading and validating sensor logs."""

from mtident.io.logs import (
    OPEN_CIRCUIT_HIGH_C,
    OPEN_CIRCUIT_LOW_C,
    TemperatureLog,
    read_temperature_log,
    sample_log_path,
)

__all__ = ["OPEN_CIRCUIT_HIGH_C", "OPEN_CIRCUIT_LOW_C", "TemperatureLog", "read_temperature_log", "sample_log_path"]
