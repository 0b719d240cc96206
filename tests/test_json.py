"""The field-driven JSON encoder (mtident._json) that the answers and the state files share."""

from __future__ import annotations

import json
import math
from dataclasses import fields

import numpy as np

import mtident.thermal
from mtident._json import to_json_value, walk_fields
from mtident.thermal.monitor_types import SensorCheck
from mtident.thermal.robust_types import Assumptions, SensorModes


def test_a_result_is_encoded_from_its_fields_in_their_order():
    said = Assumptions(max_time_constant_min=300.0, room="not measured", reference=None)
    out = to_json_value(said)
    assert list(out) == [f.name for f in fields(Assumptions)]
    assert out == {"max_time_constant_min": 300.0, "room": "not measured", "reference": None, "model": said.model}


def test_a_check_before_its_first_fit_encodes_to_json_without_nan_or_infinity():
    check = SensorCheck("T1", modes=((12.0, -3.5),))
    out = to_json_value(check)
    json.dumps(out, allow_nan=False)  # JSON has no NaN: the encoder writes None
    assert out["checked_min"] is None and out["low95_C"] is None and out["high_C"] is None
    assert out["modes"] == [[12.0, -3.5]]
    assert out["status"] == "collecting"


def test_numpy_values_become_plain_numbers_and_lists():
    modes = SensorModes(time_constants_min=(np.float64(90.5),), box=(0.1,), amplitudes_C=(np.float64(-2.0),))
    out = to_json_value({"T1": modes, "curve": np.array([[1.0, np.nan], [np.inf, 2.0]])})
    assert out["curve"] == [[1.0, None], [None, 2.0]]
    assert type(out["T1"]["time_constants_min"][0]) is float
    assert json.loads(json.dumps(out))["T1"]["amplitudes_C"] == [-2.0]


def test_the_state_files_walk_keeps_non_string_keys_as_pairs():
    tree = walk_fields({0.95: (1.0, math.inf)}, lambda v: v, dict_as_pairs=True)
    assert tree == [[0.95, [1.0, math.inf]]]


def test_the_thermal_package_exports_the_default_path():
    for name in ("identify", "monitor_step", "new_state", "WatchSession", "Event", "SensorCheck", "Status"):
        assert name in mtident.thermal.__all__
        assert getattr(mtident.thermal, name) is not None


def test_an_optional_field_is_left_out_where_none_and_an_inline_one_is_written_into_its_parent():
    from dataclasses import dataclass

    import pytest

    from mtident._json import json_inline, json_optional

    @dataclass(frozen=True)
    class Part:
        lambda_per_min: float

    @dataclass(frozen=True)
    class Answer:
        sensor: str
        part: Part = json_inline()
        extra: dict[str, float] = json_inline()
        onset_min: float | None = json_optional()

    out = to_json_value(Answer("T1", Part(math.nan), {"steady_state_ci99_C": 30.5}))
    assert out == {"sensor": "T1", "lambda_per_min": None, "steady_state_ci99_C": 30.5}
    assert to_json_value(Answer("T1", Part(0.1), {}, 12.0))["onset_min"] == 12.0

    @dataclass(frozen=True)
    class Wrong:
        values: tuple[float, ...] = json_inline()

    with pytest.raises(TypeError, match="Wrong.values: an inline field walks to a dict, not list"):
        to_json_value(Wrong((1.0,)))


def test_an_identification_s_json_is_its_answer_s_fields():
    from mtident.io.logs import read_temperature_log, sample_log_path
    from mtident.thermal import identify

    log = read_temperature_log(sample_log_path("@sample"), sensors=["T1"])
    for method in ("lsq", "robust"):
        result = identify(log, 30.0, method)
        answer = result.answer(0)
        summary = result.summary(0)
        assert summary == to_json_value(answer) and summary["sensor"] == "T1"
        # the method's keys are written beside the common ones, not as an object of their own
        assert "method_answer" not in summary and "lambda_per_min" in summary
        assert answer.method_answer.assumptions.model == summary["assumptions"]["model"]
    assert "steady_state_ci99_C" in summary and "highest_interval" not in summary
