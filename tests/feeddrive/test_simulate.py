"""Tests of :mod:`mtident.feeddrive.simulate`."""

from __future__ import annotations

import numpy as np
import pytest
from helpers import mtident

from mtident.exceptions import InputError
from mtident.feeddrive import (
    IDENTIFIED,
    Excitation,
    FeedDriveParameters,
    identify_feed_drive,
    modes,
    read_response,
    simulate,
    write_response,
)
from mtident.feeddrive.information import closest_consistent, response_moments


def test_rk4_equals_the_matrix_exponential_over_two_seconds():
    p = FeedDriveParameters()
    rk4 = simulate(p)
    exact = simulate(p, method="exact")
    scale = np.abs(exact.values).max(axis=0)
    np.testing.assert_array_less(np.abs(rk4.values - exact.values).max(axis=0) / scale, 1e-6)
    # the response to a 20 N, 0.1 ms impulse: the table moves by about 10 nm
    assert 1e-9 < np.abs(exact.values[:, 0]).max() < 1e-7


def test_response_csv_round_trip_and_errors(tmp_path):
    response = simulate(FeedDriveParameters(), duration_s=0.01, noise_fraction=0.01, rng=np.random.default_rng(1))
    path = write_response(response, tmp_path / "r.csv")
    back = read_response(path)
    np.testing.assert_allclose(back.values, response.values, rtol=1e-8)
    np.testing.assert_allclose(back.forces, response.forces)
    # as a European acquisition program writes it: a preamble, semicolons, decimal commas
    german = "# DAQ export\n" + path.read_text().replace(",", ";").replace(".", ",")
    (tmp_path / "de.csv").write_text(german)
    np.testing.assert_array_equal(read_response(tmp_path / "de.csv").values, back.values)
    (tmp_path / "bad.csv").write_text("t,x\n0,1\n")
    with pytest.raises(InputError, match="no time_s column"):
        read_response(tmp_path / "bad.csv")
    lines = path.read_text().splitlines()
    cells = lines[3].split(",")
    for cell, message in (("", r"row 4: empty or NaN"), ("oops", r"row 4: 'oops' is not a number")):
        cells[5] = cell
        (tmp_path / "bad.csv").write_text("\n".join([*lines[:3], ",".join(cells), *lines[4:]]) + "\n")
        with pytest.raises(InputError, match=f"column 'x_t_m', {message}"):
            read_response(tmp_path / "bad.csv")
    with pytest.raises(InputError, match="noise needs a seeded generator"):
        simulate(FeedDriveParameters(), noise_fraction=0.01)


def test_identification_from_all_twelve_responses():
    truth = FeedDriveParameters()
    response = simulate(truth, noise_fraction=0.01, rng=np.random.default_rng(42))
    result = identify_feed_drive(response)
    errors = result.errors_percent(truth)
    assert all(errors[k] < 0.02 for k in ("K1", "K2", "K3", "K4"))
    covered = result.covers(truth)
    assert all(covered.values()), covered
    # a parameter the data cannot pin down is reported, not given a confident wrong number
    assert [name for name, known in zip(IDENTIFIED, result.identifiable, strict=True) if not known] == ["Bt", "Bb"]
    # the friction the data do pin down is within 20 %
    assert errors["Qb"] < 20.0 and errors["Qm"] < 20.0, errors
    assert result.reproduces_record()
    assert all(r > 0.99 for r in result.correlation.values())


def test_identification_from_a_realistic_subset():
    truth = FeedDriveParameters()
    response = simulate(truth, noise_fraction=0.01, rng=np.random.default_rng(7))
    result = identify_feed_drive(response, measured="realistic")
    covered = result.covers(truth)
    assert sum(covered.values()) >= 7, covered
    assert result.measured_columns == ("a_t_m_per_s2", "theta_m_rad", "omega_m_rad_per_s")


def test_a_response_time_printed_with_few_digits_is_the_even_grid(tmp_path):
    """3 kHz printed to six decimals steps 0.000333 / 0.000334 s: refused before as uneven. Within
    1 % the even grid is taken; a missing sample (a step of two) is refused, naming its row."""
    response = simulate(FeedDriveParameters(), sample_rate_Hz=3000.0, duration_s=0.01)
    path = write_response(response, tmp_path / "r.csv")
    lines = path.read_text().splitlines()
    rounded = [lines[0]] + [",".join([f"{float(line.split(',')[0]):.6f}", *line.split(",")[1:]]) for line in lines[1:]]
    (tmp_path / "rounded.csv").write_text("\n".join(rounded) + "\n")
    back = read_response(tmp_path / "rounded.csv")
    np.testing.assert_allclose(np.diff(back.time_s), 1 / 3000.0, rtol=1e-9)
    np.testing.assert_array_equal(back.values, read_response(path).values)
    (tmp_path / "gap.csv").write_text("\n".join(lines[:6] + lines[7:]) + "\n")
    with pytest.raises(
        InputError,
        match=(
            r"evenly spaced \(within 1 %\).*row 7 comes 0.000666667 s after the one before, against a median step of "
            r"0.000333333 s"
        ),
    ):
        read_response(tmp_path / "gap.csv")


def test_sensitivities_equal_finite_differences():
    p = FeedDriveParameters()
    record = simulate(p, duration_s=0.02, method="exact")
    idx = (0, 5, 9, 11)
    moments = response_moments(p, record.forces, 1e-4, idx)
    columns = []
    for j in range(8):
        nudged = p.with_identified(p.identified() * np.exp(1e-6 * np.eye(8)[j]))
        shifted = simulate(nudged, duration_s=0.02, method="exact")
        columns.append((shifted.values[:, idx] - record.values[:, idx]) / 1e-6)
    gram = np.einsum("jnr,knr->rjk", np.array(columns), np.array(columns))
    scale = np.sqrt(np.einsum("rjj,rkk->rjk", gram, gram))
    # forward differences of step 1e-6 in ln p: agreement to ~1e-4 of each entry's scale
    np.testing.assert_array_less(np.abs(moments.gram - gram) / scale, 1e-3)
    np.testing.assert_allclose(moments.power, np.sum(record.values[:, idx] ** 2, axis=0), rtol=1e-9)


def test_the_consistency_fit_finds_a_set_one_sigma_off_whose_open_loop_response_has_drifted_in_phase():
    """An estimate one standard deviation off a lightly damped drive leaves a 2 s record by many
    times the noise open loop; the fit returns to the truth, with the distance the error had."""
    truth = FeedDriveParameters()
    record = simulate(truth, duration_s=2.0, method="exact")
    noise = 1e-3 * np.sqrt(np.mean(record.values**2, axis=0))
    data = record.values + noise * np.random.default_rng(4).standard_normal(record.values.shape)
    sd = np.array([2e-5, 2e-5, 1e-4, 1e-4, 0.05, 0.02, 0.01, 0.01])
    error = np.array([1.0, -1.0, 1.0, 1.0, -1.0, 1.0, -1.0, 1.0])
    estimate = truth.with_identified(truth.identified() * np.exp(error * sd))
    check = closest_consistent(estimate, np.diag(sd**2), record.forces, 1e-4, tuple(range(12)), data, noise)
    np.testing.assert_allclose(check.misfit, 1.0, atol=0.02)
    np.testing.assert_allclose(check.parameters_log_shift / sd, -error, atol=0.2)
    assert 5.0 < check.distance < 11.0  # 8 at the truth


def test_the_response_plot_is_readable_at_twenty_thousand_samples():
    from mtident.report.plots import plot_responses

    p = FeedDriveParameters()
    record = simulate(p, noise_fraction=0.01, rng=np.random.default_rng(1))
    figure = plot_responses(record, None, modes(p).frequencies_Hz)
    panels = figure.axes
    # 12 panels in time: 8 periods of the first mode (77 ms), sample by sample, not 20,001 samples each
    assert all(len(ax.lines[0].get_xdata()) == 769 for ax in panels[:12])
    # 4 spectra over the whole record, up to 1.5 × the highest mode, the four modes marked
    assert all(ax.get_xlim()[1] == pytest.approx(1.5 * 1443.79, rel=1e-3) and len(ax.lines) == 5 for ax in panels[12:])


def test_the_open_loop_refinement_recovers_a_noiseless_drive_from_a_biased_start():
    """Output-error maximum likelihood from a start 30 % off in damping and 0.1 % in stiffness: a
    record with (almost) no noise is fitted to the truth, the initial state (rest) with it."""
    from mtident.feeddrive.refine import refine_open_loop

    truth = FeedDriveParameters()
    record = simulate(truth, Excitation("sweep", frequency_Hz=100.0), duration_s=0.5, method="exact")
    start = truth.with_identified(truth.identified() * np.array([1.001, 0.999, 1.001, 0.999, 1.3, 0.7, 1.3, 0.7]))
    noise = 1e-6 * np.sqrt(np.mean(record.values**2, axis=0))
    said: list[tuple[int, int]] = []
    fit = refine_open_loop(
        start, record.forces, 1e-4, tuple(range(12)), record.values, noise, progress=lambda k, n: said.append((k, n))
    )
    assert fit.converged
    assert [k for k, _ in said] == list(range(1, len(said) + 1)) and {n for _, n in said} == {100}
    assert 1 < len(said) <= fit.passes
    np.testing.assert_allclose(fit.parameters.identified(), truth.identified(), rtol=1e-6)
    np.testing.assert_allclose(fit.start, 0.0, atol=1e-9)
    np.testing.assert_array_less(fit.misfit, 0.01)


def test_a_refinement_that_has_not_settled_is_not_kept(monkeypatch):
    """On a held-out drive a fit stopped at its pass limit, 184 of its standard deviations off with
    a misfit of 1.46, was kept: an unsettled fit is now refused, the filter's estimate given."""
    from functools import partial

    import mtident.feeddrive.identify as identify_module
    from mtident.feeddrive.refine import refine_open_loop

    record = simulate(FeedDriveParameters(), Excitation("prbs"), 10_000.0, 0.3, 0.01, np.random.default_rng(4))
    monkeypatch.setattr(identify_module, "refine_open_loop", partial(refine_open_loop, max_passes=2))
    result = identify_feed_drive(record, refine=True)
    assert result.filter_parameters is None
    assert any(note.startswith("the open-loop refinement did not settle within 2 passes") for note in result.notes)


def test_a_record_whose_every_force_is_zero_is_refused_saying_so(tmp_path):
    """The only non-zero force column dropped: "the filter diverged ... the guess may be far from
    the drive", or an exit 0 with Bt -59 % and Bb +219 % "doubtful". Nothing excites the drive."""
    from dataclasses import replace

    response = simulate(FeedDriveParameters(), duration_s=0.02, noise_fraction=0.01, rng=np.random.default_rng(2))
    unforced = replace(response, forces=np.zeros_like(response.forces))
    with pytest.raises(
        InputError, match=r"every force column is zero \(F_t_N, F_b_N, T_b_Nm, T_m_Nm\): nothing excites the drive"
    ):
        identify_feed_drive(unforced)
    path = write_response(unforced, tmp_path / "unforced.csv")
    out = mtident("feeddrive", "identify", str(path))
    assert out.returncode == 2 and "every force column is zero" in out.stderr and "diverged" not in out.stderr


def test_the_first_run_says_it_compiles_the_filter_before_a_silent_minute(tmp_path, monkeypatch):
    """The first run after installing compiled the filter for 84 s without a word where stderr is
    no terminal (a spinner shows only on one)."""
    import mtident.feeddrive.fast as fast

    path = write_response(simulate(FeedDriveParameters(), duration_s=0.005), tmp_path / "r.csv")
    monkeypatch.setattr(fast, "compiled_cache_ready", lambda: False)
    out = mtident("feeddrive", "identify", str(path), "--no-refine")
    assert out.returncode == 0, out.stderr
    assert "compiling the filter first (once after installing: about a minute)" in out.stderr.splitlines()[0]
    monkeypatch.setattr(fast, "compiled_cache_ready", lambda: True)
    assert "compiling" not in mtident("feeddrive", "identify", str(path), "--no-refine").stderr
    monkeypatch.setattr(fast, "compiled_cache_ready", lambda: False)
    planned = mtident(
        "feeddrive", "plan", "--excitation", "impulse", "--durations", "0.25", "--fs", "10000", "--no-refine"
    )
    assert planned.returncode == 0, planned.stderr
    assert "predicting 2 tests: compiling the filter first" in planned.stderr.splitlines()[0]


def test_the_effect_of_force_noise_on_a_fit_is_the_gradients_sensitivity_to_each_force_sample():
    """M = Σₘ Aₘ diag(σ²) Aₘᵀ from the adjoint pass equals the one from perturbing each force sample of a
    short record in turn (the gradient of a fit whose residual is zero is linear in the forces)."""
    from mtident.feeddrive.fast import response_moments as run
    from mtident.feeddrive.information import sensitivity_system
    from mtident.feeddrive.inputnoise import input_noise_moments

    truth = FeedDriveParameters()
    idx = (0, 8, 11)
    record = simulate(truth, Excitation("prbs", 3, 0.1, frequency_end_Hz=2000.0), duration_s=0.006, method="exact")
    data = record.values[:, list(idx)]
    weight = np.array([1.0, 2.0, 0.5]) / np.mean(data**2, axis=0)
    input_sd = np.array([0.3, 0.0, 0.02, 0.05])
    spread = input_noise_moments(truth, record.forces, 1e-4, idx, np.isfinite(data), weight, input_sd)
    system = sensitivity_system(truth, 1e-4, idx)

    def gradient(forces: np.ndarray) -> np.ndarray:
        return run(system, np.zeros(8), forces, data, True)[1].T @ weight

    base, brute = gradient(record.forces), np.zeros((16, 16))
    for m in range(len(record.forces)):
        for q in np.flatnonzero(input_sd):
            moved = record.forces.copy()
            moved[m, q] += 1e-3
            a = (gradient(moved) - base) / 1e-3
            brute += input_sd[q] ** 2 * np.outer(a, a)
    np.testing.assert_allclose(spread, brute, rtol=1e-5, atol=1e-8 * np.max(np.abs(brute)))


def test_noise_needs_a_generator_and_a_share_of_zero_or_more():
    """``rng=0`` raised AttributeError ('int' object has no attribute 'standard_normal'), and a
    negative noise share was taken."""
    drive = FeedDriveParameters()
    with pytest.raises(InputError, match=r"needs a seeded generator \(rng=np.random.default_rng\(seed\)\), not int"):
        simulate(drive, duration_s=0.01, noise_fraction=0.01, rng=0)  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"noise_fraction must be 0 or more"):
        simulate(drive, duration_s=0.01, noise_fraction=-0.1, rng=np.random.default_rng(0))


def test_a_drive_that_is_no_parameter_set_is_refused_by_name():
    """``modes({"K1": 1})`` raised AttributeError ('dict' object has no attribute 'Mt'), and a
    stiffness given as text a TypeError from math."""
    with pytest.raises(InputError, match=r"a feed drive is given as FeedDriveParameters .*, not dict"):
        modes({"K1": 1.0})  # type: ignore[arg-type]
    with pytest.raises(InputError, match=r"parameter K1 = '1e8': must be a number \(N/m\)"):
        modes(FeedDriveParameters(K1="1e8"))  # type: ignore[arg-type]


def test_a_record_that_is_no_response_is_refused_by_name():
    """A DataFrame of the record raised AttributeError ('forces') from inside pandas."""
    import pandas as pd

    with pytest.raises(InputError, match=r"a feed drive's record is a Response .*, not DataFrame"):
        identify_feed_drive(pd.DataFrame({"time_s": [0.0, 0.001]}))  # type: ignore[arg-type]
