"""The installed ``mtident`` command: contract JSON keys, tables, plots, one-line errors."""

from __future__ import annotations

import json
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


def test_readme_quick_start_and_ci_agree():
    readme = (ROOT / "README.md").read_text()
    block = re.search(r"## Quick start\s+```bash\n(.*?)```", readme, re.S)
    assert block is not None
    lines = [line for line in block.group(1).splitlines() if line.strip()]
    assert len(lines) == 2
    ci = (ROOT / ".ci" / "run").read_text()
    assert lines[1] in ci


@pytest.fixture(scope="session")
def loaded_modules(tmp_path_factory: pytest.TempPathFactory) -> dict[str, bool]:
    """One fresh process (an interpreter's start-up costs 1-2 s) runs `thermal watch --replay` of a
    numeric log, then `thermal identify` of the sample with the default method, and says after each
    which modules it had loaded."""
    folder = tmp_path_factory.mktemp("imports")
    (folder / "log.csv").write_text(
        "time_min,T1\n" + "".join(f"{m},{26.7 - 8.8 * 2.718281828 ** (-m / 62.5):.2f}\n" for m in range(60))
    )
    code = (
        "import json, sys; from mtident.cli import main; "
        "main(['thermal', 'watch', 'log.csv', '--replay', '--json'], standalone_mode=False); "
        "watch = {'pandas': 'pandas' in sys.modules}; "
        "main(['thermal', 'identify', '@sample', '--sensor', 'T1', '--json'], standalone_mode=False); "
        "print(json.dumps({'watch': watch, 'identify': {m: m in sys.modules for m in ('mtident.cli_feeddrive', "
        "'scipy.stats', 'mtident.cli_thermal')}}))"
    )
    result = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, cwd=folder, timeout=300
    )
    return json.loads(result.stdout.strip().splitlines()[-1])


@pytest.mark.slow
@pytest.mark.xdist_group("one fresh process")
def test_a_thermal_command_loads_neither_the_feed_drive_code_nor_scipy_stats(loaded_modules):
    """Start-up: commands load on first use (`mtident --version` took 0.60-0.78 s with every
    command imported, 0.08-0.10 s without), and identify's F quantile comes from
    scipy.special (importing scipy.stats for it cost 0.5 s of each `thermal identify`).
    Here after a watch and an identify in one process."""
    assert loaded_modules["identify"] == {
        "mtident.cli_feeddrive": False,
        "scipy.stats": False,
        "mtident.cli_thermal": True,
    }


@pytest.mark.slow
@pytest.mark.xdist_group("one fresh process")
def test_watch_of_a_numeric_log_does_not_load_pandas(loaded_modules):
    """pandas costs 0.5 s of start-up; a check for two-column time stamps loaded it for every log
    (watch's replay of the sample: 1.9 s against 1.0 s). The watch is the process's first command."""
    assert loaded_modules["watch"] == {"pandas": False}


def test_a_ctrl_c_inside_nested_compiled_code_is_a_ctrl_c():
    """A Ctrl-C during a fit reached Python as a SystemError of numba's unpickler, chained to
    another of the compiled solver, chained to the KeyboardInterrupt: only one link was looked at,
    and the user got a traceback and exit code 1 instead of "interrupted" and 130."""
    from mtident.cli import carried_interrupt

    stop = KeyboardInterrupt()
    inner = SystemError("<function _numba_unpickle> returned a result with an exception set")
    inner.__cause__ = stop
    outer = SystemError("CPUDispatcher(solve_selected) returned a result with an exception set")
    outer.__cause__ = inner
    assert carried_interrupt(outer) is stop and carried_interrupt(inner) is stop
    other = SystemError("a fault of its own")
    other.__context__ = ValueError("no Ctrl-C here")
    assert carried_interrupt(other) is None and carried_interrupt(SystemError("alone")) is None
