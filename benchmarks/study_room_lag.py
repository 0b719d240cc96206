"""How far behind a drifting room can a machine's sensor be, in its slowest time constants? A study
of the physics behind the machine model's prior on a sensor's lag behind a moving room
(``machine_fit.ROOM_LAG_SHARE``; issue 36, "the room's static gain is one").

A machine in a room that drifts at a constant rate settles behind it: each state lags the room by
the rate times its mean delay ``d = (−A)⁻¹·1`` (min; the first moment of its step response to the
room, which rises monotonically from 0 to 1), and a sensor by ``C·d``. A test's readings in a pure
drift cannot tell that lag from a lower or higher T∞; a reference run in a steady room does not
show it either. What the machine model can lean on is how the lag relates to the modes it knows:
this study measures ``C·d`` over the benchmark's machines (:mod:`_machines`: networks of 2-5
nodes and conduction bodies, sensors on nodes, between two and behind a lag), per sensor, as a
share of the machine's slowest time constant and of the sum of all its time constants.

Run: python benchmarks/study_room_lag.py [--first-seed 36000 --cases 200]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "src"))
sys.path.insert(0, str(Path(__file__).resolve().parent))

from _machines import draw_case  # noqa: E402

QUANTILES = (0.0, 0.01, 0.05, 0.25, 0.5, 0.75, 0.95, 0.99, 1.0)


def sensor_lags(seed: int) -> tuple[np.ndarray, np.ndarray]:
    """Each sensor's lag behind a unit ramp of the room (min) as a share of the machine's slowest
    time constant, and of the sum of its time constants (sensor lags included)."""
    plant = draw_case(seed).plant
    delay = plant.C @ np.linalg.solve(-plant.A, np.ones(len(plant.A)))
    taus = -1.0 / np.linalg.eigvals(plant.A).real
    return delay / taus.max(), delay / taus.sum()


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--first-seed", type=int, default=36000)
    parser.add_argument("--cases", type=int, default=200)
    args = parser.parse_args(argv)
    of_slowest, of_sum = (
        np.concatenate(v)
        for v in zip(*map(sensor_lags, range(args.first_seed, args.first_seed + args.cases)), strict=True)
    )
    print(
        f"{len(of_slowest)} sensors of {args.cases} machines",
        f"(seeds {args.first_seed}-{args.first_seed + args.cases - 1})",
    )
    print("quantiles:          " + " ".join(f"{q:>6.2f}" for q in QUANTILES))
    print("lag / slowest tau:  " + " ".join(f"{v:>6.2f}" for v in np.quantile(of_slowest, QUANTILES)))
    print("lag / sum of taus:  " + " ".join(f"{v:>6.2f}" for v in np.quantile(of_sum, QUANTILES)))
    for share in (0.6, 1.0):
        beyond = np.abs(of_slowest - 1.0) > 2.576 * share
        print(
            f"lags beyond the 99 % range of a prior centred at one slowest tau, sd {share:g} of it: {int(beyond.sum())}"
        )


if __name__ == "__main__":
    main()
