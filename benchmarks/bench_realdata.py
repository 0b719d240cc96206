"""The real heat-up curves beside the project (``../shared/realdata``): identify at a quarter and at
half of each record's 95 %-rise time, and the monitor replayed, without a reference and with one
learnt from the other run of the same board (TCLab heater 1, runs 1 and 3).

Truth: where the record settled (its last 5 %, :class:`~mtident.testing.warmups.RealCurve`); a
record that did not settle is scored by its last readings, which are below T∞, so an interval
above them is not counted as a miss.

Run: python benchmarks/bench_realdata.py [FOLDER]
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))

from mtident.io.logs import TemperatureLog  # noqa: E402
from mtident.testing.warmups import load_real_curves  # noqa: E402
from mtident.thermal.identify import identify  # noqa: E402
from mtident.thermal.monitor import MonitorSettings, monitor_step, new_state  # noqa: E402
from mtident.thermal.reference_learning import learn_reference  # noqa: E402
from mtident.thermal.robust_identify import identify_robust  # noqa: E402

TOLERANCE_C = 0.2


def _log(curve) -> TemperatureLog:  # noqa: ANN001
    return TemperatureLog(curve.time_min, ("S",), curve.reading_C[:, None], (), curve.name)


def main() -> None:
    folder = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(__file__).resolve().parents[2] / "shared" / "realdata"
    curves = load_real_curves(folder)
    truth_of = {c.name: c.settled_C if np.isfinite(c.settled_C) else c.end_C for c in curves}
    references = {}
    heaters = [c for c in curves if c.name.endswith(":T1")]
    for c in heaters:
        learnt, _ = learn_reference(_log(c))
        references[c.name] = learnt
    print(
        f"{'curve':>28} {'t95':>5} {'at':>5} {'robust T∞ [95 %]':>26} {'ok':>3} {'covers':>6} "
        f"{'first-order T∞ [95 %]':>26} {'covers':>6}"
    )
    for c in curves:
        truth = truth_of[c.name]
        for fraction in (0.25, 0.5):
            window = fraction * c.t95_min
            if not np.isfinite(window) or np.searchsorted(c.time_min, window) < 8:
                continue
            robust = identify_robust(_log(c), window)
            lo, hi = robust.steady_state_ci95_C[0]
            first = identify(_log(c), window, "ukf")
            flo, fhi = first.steady_state_ci95_C[0]
            print(
                f"{c.name:>28} {c.t95_min:5.1f} {window:5.1f} {robust.steady_state_C[0]:8.2f} [{lo:7.2f}, {hi:7.2f}] "
                f"{'yes' if robust.model_ok[0] else 'no':>3} {str(lo <= truth <= hi):>6} "
                f"{first.steady_state_C[0]:8.2f} [{flo:7.2f}, {fhi:7.2f}] {str(flo <= truth <= fhi):>6}"
            )
    print(f"\nMonitor (tolerance {TOLERANCE_C} °C at 99 %), against where each record settled:")
    for c in curves:
        others = [r for name, r in references.items() if name != c.name and c.name.endswith(":T1")]
        for label, reference in (("no reference", None), ("reference: the other run", others[0] if others else None)):
            if label != "no reference" and reference is None:
                continue
            reference = (
                None
                if reference is None
                else type(reference)(
                    reference.source,
                    reference.learnt_on,
                    reference.max_time_constant_min,
                    reference.room,
                    {"S": reference.sensors["S"]},
                )
            )
            state, _ = monitor_step(
                new_state(["S"]),
                c.time_min,
                c.reading_C[:, None],
                None,
                MonitorSettings(tolerance_C=TOLERANCE_C, reference=reference),
            )
            check = state.checks[0]
            stop = (
                f"stop at {state.stop_time_min:5.1f} min ({state.stop_time_min / c.t95_min:.2f} t95), error "
                f"{check.steady_C - truth_of[c.name]:+.2f} °C"
                if state.stopped
                else f"no stop ({check.status}; 99 % interval {check.low_C:.2f} to {check.high_C:.2f})"
            )
            print(f"{c.name:>28} {label:>26}: {stop}")


if __name__ == "__main__":
    main()
