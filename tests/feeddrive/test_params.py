"""Tests of :mod:`mtident.feeddrive.params`."""

from __future__ import annotations

import numpy as np
import pytest

from mtident.exceptions import InputError, UnstableModelError
from mtident.feeddrive import (
    FeedDriveParameters,
    load_parameters,
    modes,
    parameter_template,
    read_response,
    validate,
)
from mtident.feeddrive.params import mass_matrix, stiffness_matrix


def test_modes_reproduce_the_paper_with_the_corrected_beta():
    result = modes(FeedDriveParameters())
    # seed 004 prints 104.34, 266.54, 1082.4, 1443.8 Hz; the first differs (DESIGN.md errata)
    np.testing.assert_allclose(result.frequencies_Hz, [103.94, 266.54, 1082.43, 1443.79], atol=0.01)
    p = FeedDriveParameters()
    k, m = stiffness_matrix(p), mass_matrix(p)
    omega2 = (2 * np.pi * result.frequencies_Hz) ** 2
    for j in range(4):  # Eq. 3: (K − ω²M)φ = 0
        residual = (k - omega2[j] * m) @ result.shapes[:, j]
        assert np.linalg.norm(residual) < 1e-6 * np.linalg.norm(k @ result.shapes[:, j])
    np.testing.assert_allclose(result.shapes.T @ m @ result.shapes, np.eye(4), atol=1e-10)
    assert result.positive_definite and np.all(result.damping_ratios > 0)


def test_printed_beta_is_refused_with_the_indefinite_k_error():
    with pytest.raises(
        UnstableModelError,
        match=r"K3 < K4 \+ β²·K1 .*K is indefinite, the model is unstable \(β = 2.55e-3 is the value printed",
    ):
        validate(FeedDriveParameters(beta=2.55e-3))
    with pytest.raises(UnstableModelError, match="K2 = .* ≤ K1"):
        validate(FeedDriveParameters(K2=1e8))


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("Mt = -1", r"parameter Mt = -1.0: must be a positive number \(kg\)"),
        ("Bt = -0.5", r"parameter Bt = -0.5: damping must be zero or positive"),
        ("Kx = 3", r"unknown parameter 'Kx'"),
        ("K1 = 'stiff'", r"K1 = 'stiff' is not a number"),
        ("K1 = = 3", r"not valid TOML"),
        ("beta = 2.55e-3", r"K is indefinite"),
    ],
)
def test_parameter_files_are_validated(tmp_path, text, message):
    path = tmp_path / "p.toml"
    path.write_text(text + "\n")
    with pytest.raises((InputError, UnstableModelError), match=message):
        load_parameters(path)


def test_parameter_file_overrides_the_shipped_set(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text("K1 = 1.2e8\nBt = 2.0\n")
    p = load_parameters(path)
    assert p.K1 == 1.2e8 and p.Bt == 2.0 and p.Mt == 15.0
    with pytest.raises(InputError, match="no such parameter file"):
        load_parameters(tmp_path / "missing.toml")


def test_a_parameter_file_given_as_a_record_and_a_bad_value_name_the_file(tmp_path):
    """From a new user's trial: a TOML file given where the response CSV belongs gave pandas'
    tokenizer error, and a bad value's message did not say which file held it."""
    toml = tmp_path / "drive.toml"
    toml.write_text(parameter_template(FeedDriveParameters()))
    with pytest.raises(InputError, match=r"drive.toml: a TOML file \(name = value lines\), not a CSV file of readings"):
        read_response(toml)
    toml.write_text("K3 = -5.0\n")
    with pytest.raises(InputError, match=r"drive.toml: parameter K3 = -5.0: must be a positive number"):
        load_parameters(toml)
