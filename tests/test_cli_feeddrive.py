"""Tests of :mod:`mtident.cli_feeddrive`."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from helpers import mtident

from mtident.feeddrive import (
    IDENTIFIED,
    Excitation,
    FeedDriveParameters,
    identify_feed_drive,
    load_parameters,
    parameter_template,
    simulate,
    write_response,
)
from mtident.feeddrive.params import UNITS


def test_cli_modes_simulate_identify(tmp_path):
    out = mtident("feeddrive", "modes", "--json")
    data = json.loads(out.stdout)
    np.testing.assert_allclose(data["natural_frequencies_Hz"], [103.94, 266.54, 1082.43, 1443.79], atol=0.01)
    assert data["positive_definite"] is True
    csv = tmp_path / "r.csv"
    out = mtident("feeddrive", "simulate", "--duration", "0.2", "--noise", "0.01", "--out", str(csv))
    assert out.returncode == 0, out.stderr
    header = csv.read_text().splitlines()[0].split(",")
    assert header[:6] == ["time_s", "F_t_N", "F_b_N", "T_b_Nm", "T_m_Nm", "x_t_m"]
    out = mtident("feeddrive", "identify", str(csv), "--json")
    assert out.returncode == 0, out.stderr
    data = json.loads(out.stdout)
    assert set(data["parameters"]) == set(IDENTIFIED) == set(data["parameters_std"])
    assert data["parameters_sd"] == data["parameters_std"]  # the name used before the contract's, kept as an alias
    assert set(data["correlation"]) >= {"x_t_m", "a_t_m_per_s2"}


def test_cli_identifies_from_the_responses_a_file_has(tmp_path):
    """A machine's own log has a few responses: the default "all" refused it ("no 'x_t_m' column");
    now the responses present are used. A file without any force column was read with zero
    excitation, silently; it is refused."""
    csv = tmp_path / "r.csv"
    assert mtident("feeddrive", "simulate", "--duration", "0.2", "--out", str(csv)).returncode == 0
    lines = [line.split(",") for line in csv.read_text().splitlines()]
    keep = [lines[0].index(c) for c in ("time_s", "F_t_N", "a_t_m_per_s2", "theta_m_rad", "omega_m_rad_per_s")]
    partial = tmp_path / "partial.csv"
    partial.write_text("".join(",".join(row[i] for i in keep) + "\n" for row in lines))
    out = mtident("feeddrive", "identify", str(partial), "--json")
    assert out.returncode == 0, out.stderr
    assert set(json.loads(out.stdout)["correlation"]) == {"a_t_m_per_s2", "theta_m_rad", "omega_m_rad_per_s"}
    every = mtident("feeddrive", "identify", str(partial), "--measured", "all")
    assert every.returncode == 2 and "no 'x_t_m' column, which the measurement set 'all' needs" in every.stderr
    unforced = tmp_path / "unforced.csv"
    unforced.write_text("".join(",".join(row[i] for i in keep[:1] + keep[2:]) + "\n" for row in lines))
    refused = mtident("feeddrive", "identify", str(unforced))
    assert (
        refused.returncode == 2
        and "no force column; the excitation must be measured" in refused.stderr
        and "Traceback" not in refused.stderr
    )


def test_cli_refuses_the_printed_beta(tmp_path):
    path = tmp_path / "printed.toml"
    path.write_text("beta = 2.55e-3\n")
    out = mtident("feeddrive", "modes", "--params", str(path), "--json")
    assert out.returncode == 2 and "K is indefinite" in out.stderr and "Traceback" not in out.stderr


def test_the_table_marks_an_estimate_whose_intervals_do_not_hold(tmp_path):
    """A newcomer's sweep was identified 'yes' for every stiffness and friction while the notes said
    the estimate does not reproduce the record: the table now says the intervals do not hold."""
    sine = simulate(
        FeedDriveParameters(),
        Excitation("sine", frequency_Hz=100.0),
        duration_s=0.3,
        noise_fraction=0.01,
        rng=np.random.default_rng(3),
    )
    path = write_response(sine, tmp_path / "sine.csv")
    out = mtident("feeddrive", "identify", str(path), "--no-refine")
    assert out.returncode == 0
    assert "does not reproduce the record: its ± 2σ do not hold" in out.stdout
    assert "doubtful" in out.stdout and " yes " not in out.stdout


def test_the_parameter_template_names_every_parameter_and_reads_back(tmp_path):
    text = parameter_template()
    for name, unit in UNITS.items():
        assert re.search(rf"^{name} = \S+  # {re.escape(unit)}: ", text, re.M), name
    path = tmp_path / "p.toml"
    path.write_text(text)
    assert load_parameters(path) == FeedDriveParameters()
    out = mtident("feeddrive", "params", "--template", "--out", str(tmp_path / "guess.toml"))
    assert out.returncode == 0 and (tmp_path / "guess.toml").read_text() == text
    shown = mtident("feeddrive", "params", "--json")
    assert json.loads(shown.stdout)["units"]["K1"] == "N/m"


def test_a_refinement_that_does_not_fit_the_record_is_not_kept(tmp_path):
    """Noise ten times the stated: no set fits within it, so the filter's estimate stands and the
    note says why; the CLI refines by default and shows the filter's column only where it did."""
    record = simulate(FeedDriveParameters(), duration_s=0.3, noise_fraction=0.01, rng=np.random.default_rng(3))
    result = identify_feed_drive(record, noise_fraction=0.001, refine=True)
    assert result.filter_parameters is None and result.summary()["refined"] is False
    assert any(note.startswith("the open-loop refinement does not fit the record") for note in result.notes)
    csv = tmp_path / "r.csv"
    write_response(record, csv)
    tables = [mtident("feeddrive", "identify", str(csv), *flag) for flag in ([], ["--no-refine"])]
    assert [t.returncode for t in tables] == [0, 0]
    headers = [t.stdout.splitlines()[2].replace("┃", " ").split() for t in tables]
    assert headers[0][:4] == ["parameter", "guess", "filter", "estimate"]
    assert headers[1][:3] == ["parameter", "guess", "estimate"]


def test_every_command_help_describes_its_options_without_placeholders():
    """click described an unbounded number range as "x<=None"."""
    import click

    from mtident.cli import main

    def paths(group: click.Group, prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
        out = []
        context = click.Context(group)
        for name in group.list_commands(context):  # loads a lazy group's commands, as the shell does
            command = group.get_command(context, name)
            out.append((*prefix, name))
            if isinstance(command, click.Group):
                out.extend(paths(command, (*prefix, name)))
        return out

    commands = paths(main)
    assert ("feeddrive", "simulate") in commands and ("thermal", "watch") in commands
    for path in commands:
        result = mtident(*path, "--help")
        assert result.returncode == 0 and "None" not in result.stdout + result.stderr, (path, result)


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["thermal", "identify", "missing.csv"], "missing.csv: no such file"),
        (["thermal", "identify", "@sample", "--sensor", "T99"], "no sensor column 'T99'"),
        (["thermal", "identify", "@sample", "--window", "2"], "samples in the first 2 min"),
        # the refusals are identify()'s, said as options
        (
            ["thermal", "identify", "@sample", "--preset", "xia2014"],
            "--preset is a setting of the papers' first-order filters: give --method ukf, aukf, fukf, afukf or lsq",
        ),
        (
            ["thermal", "identify", "@sample", "--method", "ukf", "--reference", "@sample-machine"],
            "--reference needs the model-robust method (--method robust)",
        ),
        (
            ["thermal", "identify", "@sample", "--method", "lsq", "--max-time-constant", "200"],
            "(--max-time-constant, --room-wander, --free-fast-modes) are settings of the model-robust method "
            "(--method robust)",
        ),
        (
            ["thermal", "min-time", "@sample", "--sampling-periods", "35,abc"],
            "--sampling-periods: expected comma-separated minutes",
        ),
        (["thermal", "min-time", "@sample", "--sampling-periods", "35,500"], "the longest sampling period is 500 min"),
        (["thermal", "min-time", "@sample", "--windows", "30:10"], "--windows: expected START:STOP"),
        (
            ["feeddrive", "simulate", "--duration", "1e-9", "--out", "x.csv"],
            "gives 1 sample(s); identification needs at least 10",
        ),
        (
            ["feeddrive", "simulate", "--excitation", "sine", "--frequency", "6000", "--out", "x.csv"],
            "the sine reaches 6000 Hz, above half the sampling rate (5000 Hz)",
        ),
        (
            ["feeddrive", "simulate", "--excitation", "sweep", "--fs", "1000", "--out", "x.csv"],
            "the sweep reaches 2000 Hz, above half the sampling rate (500 Hz)",
        ),
    ],
)
def test_user_errors_are_one_line_without_traceback(args, message):
    out = mtident(*args)
    assert out.returncode == 2
    assert message in out.stderr
    assert "Traceback" not in out.stderr
    assert len([line for line in out.stderr.splitlines() if line.startswith("mtident: error")]) == 1


@pytest.mark.parametrize(
    ("plot", "message"),
    [
        ("no-such-folder/fit.png", "the folder 'no-such-folder' of 'no-such-folder/fit.png' does not exist"),
        ("fit.txt", "'.txt' is not a picture format matplotlib writes; use one of:"),
        (".", "'.' is a folder; give a file name such as 'plot.png'"),
    ],
)
@pytest.mark.parametrize(
    "command",
    [
        ["thermal", "identify", "@sample"],
        ["thermal", "watch", "@sample", "--replay"],
        ["feeddrive", "simulate", "--duration", "0.01", "--out", "r.csv"],
    ],
)
def test_a_bad_plot_path_is_refused_before_the_work(tmp_path, monkeypatch, command, plot, message):
    """A mistyped folder used to end the whole run in an errno message about a temporary file."""
    monkeypatch.chdir(tmp_path)
    out = mtident(*command, "--plot", plot)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert message in out.stderr
    assert not list(tmp_path.iterdir())  # nothing was computed or written


@pytest.mark.parametrize(
    ("path", "message"),
    [
        ("no-such-folder/out.csv", "the folder 'no-such-folder' of 'no-such-folder/out.csv' does not exist"),
        (".", "'.' is a folder; give a file name such as 'out.csv'"),
    ],
)
@pytest.mark.parametrize(
    "command", [["thermal", "identify", "@sample", "--curve"], ["feeddrive", "simulate", "--duration", "0.01", "--out"]]
)
def test_a_bad_output_path_is_refused_before_the_work(tmp_path, monkeypatch, command, path, message):
    """The simulation's --out used to be checked only when written, after the work (pandas' "Cannot
    save file into a non-existent directory")."""
    monkeypatch.chdir(tmp_path)
    out = mtident(*command, path)
    assert out.returncode == 2 and "Traceback" not in out.stderr
    assert message in out.stderr
    assert not list(tmp_path.iterdir())
