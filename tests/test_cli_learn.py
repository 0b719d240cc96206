"""Tests of :mod:`mtident.cli_learn`."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest
from helpers import mtident, two_mode

from mtident.exceptions import InputError
from mtident.thermal.reference import load_reference, save_reference


def test_learn_command_writes_the_reference_and_says_its_doubts(tmp_path):
    t = np.arange(0.0, 41.0, 5.0)
    y = np.round(two_mode(t) + np.random.default_rng(3).normal(0.0, 0.02, t.size), 2)
    log = tmp_path / "short.csv"
    log.write_text("time_min,S\n" + "".join(f"{a:g},{b:.2f}\n" for a, b in zip(t, y, strict=True)))
    out = mtident("thermal", "learn", str(log), "-o", str(tmp_path / "m.toml"), "--json")
    # every sensor doubtful: the file is written, to be read, but a script must not go on with it
    assert out.returncode == 1, out.stderr
    assert (tmp_path / "m.toml").is_file()
    result = json.loads(out.stdout)
    assert result["sensors"]["S"]["doubt"]
    assert "Later tests will not use this sensor's modes" in out.stderr
    assert "none of its sensors will be used by later tests (each is doubtful: S)" in out.stderr
    assert mtident("thermal", "learn", str(log), "-o", str(tmp_path / "m.toml")).returncode == 1


def test_learn_every_mode_writes_it_and_a_bad_value_is_refused(tmp_path):
    t = np.arange(0.0, 480.0, 2.0)
    y = np.round(26.7 - 8.8 * np.exp(-t / 62.5) + np.random.default_rng(4).normal(0.0, 0.02, t.size), 2)
    log = tmp_path / "full.csv"
    log.write_text("time_min,S\n" + "".join(f"{a:g},{b:.2f}\n" for a, b in zip(t, y, strict=True)))
    out = mtident("thermal", "learn", str(log), "-o", str(tmp_path / "m.toml"), "--every-mode", "--json")
    assert out.returncode == 0, out.stderr
    assert json.loads(out.stdout)["sensors"]["S"]["free_fast_modes"] == 0
    assert "\nfree_fast_modes = 0\n" in (tmp_path / "m.toml").read_text()
    assert load_reference(tmp_path / "m.toml").sensors["S"].free_fast_modes == 0
    shown = mtident("thermal", "learn", str(log), "-o", str(tmp_path / "m.toml"), "--every-mode")
    assert "no faster mode (--every-mode)" in " ".join(shown.stdout.split())
    plain = mtident("thermal", "learn", str(log), "-o", str(tmp_path / "p.toml"))
    assert plain.returncode == 0 and "\nfree_fast_modes = " not in (tmp_path / "p.toml").read_text()
    assert "--every-mode" not in plain.stdout
    assert load_reference(tmp_path / "p.toml").sensors["S"].free_fast_modes is None
    bad = (tmp_path / "m.toml").read_text().replace("\nfree_fast_modes = 0", "\nfree_fast_modes = 5")
    (tmp_path / "bad.toml").write_text(bad)
    with pytest.raises(InputError, match="if given, free_fast_modes = 0 to 2; found"):
        load_reference(tmp_path / "bad.toml")


def _warm_up_csv(path: Path, seed: int) -> Path:
    """Two sensors of one machine (modes of 12 and 150 min), 500 min logged once a minute, noisy
    enough (0.1 °C) that one run leaves the fast mode's box wider than the least a box may be."""
    rng = np.random.default_rng(seed)
    t = np.arange(0.0, 501.0)
    rise = {"A": (2.0, 6.0), "B": (-0.5, 4.0)}
    lines = ["time_min,A,B"]
    columns = {
        name: 20.0 + fast * (1 - np.exp(-t / 12.0)) + slow * (1 - np.exp(-t / 150.0)) + rng.normal(0, 0.1, t.size)
        for name, (fast, slow) in rise.items()
    }
    lines += [f"{v:g},{a:.2f},{b:.2f}" for v, a, b in zip(t, columns["A"], columns["B"], strict=True)]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_a_second_complete_run_pools_into_the_reference_and_narrows_its_boxes(tmp_path):
    first, second = _warm_up_csv(tmp_path / "run1.csv", 1), _warm_up_csv(tmp_path / "run2.csv", 2)
    assert (
        mtident("thermal", "learn", str(first), "-o", str(tmp_path / "one.toml"), "--machine", "VMC1").returncode == 0
    )
    out = mtident(
        "thermal", "learn", str(second), "--update", str(tmp_path / "one.toml"), "-o", str(tmp_path / "two.toml"),
        "--machine", "VMC1", "--json",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    one, two = load_reference(tmp_path / "one.toml"), load_reference(tmp_path / "two.toml")
    assert two.source == f"{first} + {second}" and json.loads(out.stdout)["source"] == two.source
    boxes = [(one.sensors[n].box, two.sensors[n].box) for n in ("A", "B")]
    assert one.machine_model is not None and two.machine_model is not None
    boxes.append((one.machine_model.box, two.machine_model.box))
    assert all(b <= a + 1e-12 for before, after in boxes for a, b in zip(before, after, strict=True)), boxes
    assert two.sensors["A"].box[0] < one.sensors["A"].box[0] - 0.02  # the fast mode's, from 0.165
    assert two.machine_model.box[1] < one.machine_model.box[1] - 0.05  # the model's fast mode, from 0.28
    assert all(130.0 < max(m.time_constants_min) < 170.0 for m in two.sensors.values())
    refused = mtident("thermal", "learn", str(second), "--update", str(tmp_path / "one.toml"), "-o",
                      str(tmp_path / "x.toml"), "--machine", "VMC2")  # fmt: skip
    assert refused.returncode == 2 and "is of machine 'VMC1', and this run of 'VMC2'" in refused.stderr
    assert not (tmp_path / "x.toml").exists()


def test_a_reference_names_its_machine_and_a_test_of_another_is_refused(tmp_path, spindle_reference):
    t = np.arange(0.0, 480.0, 1.0)
    y = two_mode(t) + np.random.default_rng(1).normal(0.0, 0.01, t.size)
    run = tmp_path / "run.csv"
    run.write_text("time_min,S\n" + "\n".join(f"{a:g},{b:.2f}" for a, b in zip(t, y, strict=True)) + "\n")
    out = mtident(
        "thermal", "learn", str(run), "-o", str(tmp_path / "vmc.toml"), "--machine", "VMC-1", "--serial", "4711",
        "--program", "8000 rpm", "--run-date", "2026-11-20", "--json",
    )  # fmt: skip
    assert out.returncode == 0, out.stderr
    learnt = json.loads(out.stdout)
    assert (learnt["machine"], learnt["serial"], learnt["program"], learnt["run_date"]) == (
        "VMC-1", "4711", "8000 rpm", "2026-11-20",
    )  # fmt: skip
    from mtident.thermal.reference import load_reference

    reference = load_reference(tmp_path / "vmc.toml")
    assert reference.identity == f"machine VMC-1, serial 4711, program 8000 rpm, run on 2026-11-20 ({run})"
    assert reference.describe("S").startswith("machine VMC-1, serial 4711, program 8000 rpm, run on 2026-11-20: ")
    test = tmp_path / "test.csv"
    test.write_text("time_min,S\n" + "\n".join(f"{a:g},{b:.2f}" for a, b in zip(t[:60], y[:60], strict=True)) + "\n")
    same = mtident("thermal", "identify", str(test), "--reference", str(tmp_path / "vmc.toml"), "--machine", "VMC-1")
    assert same.returncode == 0, same.stderr
    other = mtident("thermal", "identify", str(test), "--reference", str(tmp_path / "vmc.toml"), "--machine", "HMC-2")
    assert other.returncode != 0
    assert "the reference is of machine 'VMC-1'" in other.stderr and "'HMC-2'" in other.stderr
    save_reference(spindle_reference, tmp_path / "unnamed.toml")
    unnamed = mtident(
        "thermal", "watch", str(test), "--replay", "--reference", str(tmp_path / "unnamed.toml"), "--machine",
        "VMC-1", "--state", str(tmp_path / "s.npz"),
    )  # fmt: skip
    assert unnamed.returncode != 0 and "does not say which machine it is of" in unnamed.stderr


def test_learn_reads_back_the_file_it_wrote_and_says_a_fault_of_its_own(tmp_path, monkeypatch):
    """learn wrote a reference (a box of 2.75) that watch then refused, after learn's exit 0: the
    file is read back before learn ends, and one that does not read back is said as mtident's own
    fault, exit 1."""
    import mtident.thermal.reference as reference_module

    t = np.arange(0.0, 401.0, 2.0)
    y = np.round(two_mode(t) + np.random.default_rng(3).normal(0.0, 0.02, t.size), 2)
    log = tmp_path / "run.csv"
    log.write_text("time_min,S\n" + "".join(f"{a:g},{b:.2f}\n" for a, b in zip(t, y, strict=True)))
    assert mtident("thermal", "learn", str(log), "-o", str(tmp_path / "m.toml")).returncode == 0

    def broken(reference, path):  # noqa: ANN001, ANN202
        Path(path).write_text("[sensors.S]\ntime_constants_min = [8.0]\nbox = [2.75]\n")

    monkeypatch.setattr(reference_module, "save_reference", broken)
    out = mtident("thermal", "learn", str(log), "-o", str(tmp_path / "m.toml"))
    assert out.returncode == 1
    said = " ".join(out.stderr.split())
    assert "does not read back, a fault of mtident's (please report it, with the log)" in said and "2.75" in said
