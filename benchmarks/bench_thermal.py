"""Thermal identification: accuracy (Monte Carlo against the Cramér-Rao bound), the papers'
presets on the sample log, and the speed of the minimal-identification-time search against
the same computation done with filterpy in a loop; with ``--checks``, the cost of one
model-robust check of one sensor against the length of its record, and of replays of the
sample's ten sensors.

Run: python benchmarks/bench_thermal.py [--quick] [--checks]
"""

from __future__ import annotations

import sys
import time
import warnings

import numpy as np
from _common import filterpy_ukf

from mtident.io import read_temperature_log, sample_log_path
from mtident.io.logs import TemperatureLog
from mtident.thermal import identify, minimal_identification_time
from mtident.thermal.lsq import cramer_rao_bound
from mtident.thermal.model import slope_transition
from mtident.thermal.settings import tuning_from_data
from mtident.ukf import AdaptiveLaw

START, STEADY, RATE, SIGMA, WINDOW = 17.9, 26.7, 0.016, 0.02, 28.0


def monte_carlo(runs: int) -> None:
    rng = np.random.default_rng(2014)
    t = np.arange(0.0, 400.0)
    curve = STEADY + (START - STEADY) * np.exp(-RATE * t)
    data = curve[:, None] + SIGMA * rng.standard_normal((len(t), runs))
    log = TemperatureLog(t, tuple(f"r{i}" for i in range(runs)), data, (), "mc")
    bound = np.sqrt(cramer_rao_bound(t[: int(WINDOW) + 1], START, RATE, STEADY, SIGMA)[2, 2])
    print(f"\nMonte Carlo: {runs} runs of {START} -> {STEADY} °C, λ = {RATE}/min, σ = {SIGMA} °C, L = {WINDOW:g} min")
    print(f"Cramér-Rao bound on T∞: {bound:.3f} °C")
    print(
        f"{'method':>16} {'bias °C':>9} {'spread °C':>10} {'spread/CRB':>11} {'mean sd':>8} {'coverage':>9} "
        f"{'misfit':>7} {'time s':>7}"
    )
    for preset, methods in (
        ("data", ("ukf", "aukf", "fukf", "afukf", "lsq")),
        ("xia2014", ("ukf", "aukf")),
        ("yu2019", ("fukf", "afukf")),
    ):
        for method in methods:
            start = time.perf_counter()
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                result = identify(log, WINDOW, method, preset)
            elapsed = time.perf_counter() - start
            error = result.steady_state_C - STEADY
            ok = np.isfinite(error)
            if not ok.any():
                print(f"{method + '/' + preset:>16}   all {len(error)} runs diverged  {elapsed:7.2f}")
                continue
            first_order = result.details  # the papers' filters: λ, the standard deviations and the residual test
            cover = np.mean(np.abs(error[ok]) <= first_order.quantile * first_order.steady_state_sd_C[ok])
            name = method if preset == "data" else f"{method}/{preset}"
            print(
                f"{name:>16} {np.mean(error[ok]):9.3f} {np.std(error[ok]):10.3f} {np.std(error[ok]) / bound:11.2f} "
                f"{np.mean(first_order.steady_state_sd_C[ok]):8.3f} {cover:9.2f} {np.mean(~first_order.fits):7.2f} "
                f"{elapsed:7.2f}" + ("" if ok.all() else f"  ({np.sum(~ok)} diverged)")
            )


def presets_on_sample() -> None:
    log = read_temperature_log(sample_log_path())
    print(
        f"\nSample log ({len(log.sensors)} sensors, {log.time_min[-1]:g} min), L = 28 min: T∞ (°C) against the "
        "measured final temperature"
    )
    rows = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for label, method, preset in (
            ("ukf (default)", "ukf", "data"),
            ("lsq", "lsq", "data"),
            ("aukf/xia2014", "aukf", "xia2014"),
            ("afukf/yu2019", "afukf", "yu2019"),
        ):
            rows[label] = identify(log, 28.0, method, preset)
    first = next(iter(rows.values()))
    print(f"{'sensor':>7} {'measured':>9} " + " ".join(f"{label:>15}" for label in rows))
    for s, name in enumerate(log.sensors):
        cells = []
        for result in rows.values():
            value = result.steady_state_C[s]
            half = result.details.quantile * result.details.steady_state_sd_C[s]
            cells.append(f"{value:7.2f}±{half:<7.2f}" if np.isfinite(value) else f"{'diverged':>15}")
        print(f"{name:>7} {first.measured_final_C[s]:9.2f} " + " ".join(cells))
    for label, result in rows.items():
        err = np.abs(result.steady_state_C - result.measured_final_C)
        if not np.isfinite(err).any():
            print(f"  {label:>15}: diverged on every sensor")
            continue
        print(
            f"  {label:>15}: median |T∞ − measured| = {np.nanmedian(err):.2f} °C, RMSE over 400 min median "
            f"{np.nanmedian(result.rmse_C):.3f} °C"
        )


def filterpy_min_time(log: TemperatureLog, windows: np.ndarray, periods: np.ndarray) -> np.ndarray:
    """The same search with filterpy: for every sensor and every L, filter to L with the adaptive
    law (wrapped around filterpy's UKF), predict to the longest period, take the RMSEs."""
    t, y = log.time_min, log.temperature_C
    n_total = log.window(periods[-1])
    first = log.window(windows[0])
    table = np.full((len(periods), len(windows), y.shape[1]), np.nan)
    for s in range(y.shape[1]):
        tuning = tuning_from_data(t[:first], y[:first, s : s + 1])
        for i, window in enumerate(windows):
            estimate = _filterpy_window(t, y[:, s], log.window(window), n_total, tuning)
            if estimate is None:
                continue
            for p, period in enumerate(periods):
                if window < period:
                    m = log.window(period)
                    table[p, i, s] = np.sqrt(np.sum((estimate[:m] - y[:m, s]) ** 2) / (m - 1))
    return table


def _filterpy_window(t: np.ndarray, y: np.ndarray, n: int, n_total: int, tuning) -> np.ndarray | None:  # noqa: ANN001
    """Filter to sample n with filterpy plus the adaptive law, then predict to n_total (None if it fails)."""
    law = AdaptiveLaw(threshold=float(tuning.threshold_C[0]))
    up, down = law.search_multipliers()
    ukf = filterpy_ukf(
        3,
        1,
        lambda x, dt: slope_transition(x, dt),
        lambda x: x[:1],
        tuning.initial_mean[0],
        tuning.initial_cov[0],
        tuning.process_cov[0],
        tuning.emission_cov[0],
    )
    estimate = np.empty(n_total)
    try:
        for k in range(n_total):
            ukf.predict(dt=0.0 if k == 0 else t[k] - t[k - 1])
            if k < n:
                x_prior, p_prior = ukf.x.copy(), ukf.P.copy()
                ukf.update(y[k : k + 1])
                gamma = y[k] - ukf.x[0]
                if abs(gamma) > law.threshold:
                    psi = y[k] - x_prior[0]
                    new_q = ukf.Q * (law.q_increase if gamma < 0 else law.q_decrease)
                    p_prior = p_prior + new_q - ukf.Q
                    ukf.Q = new_q
                    r0 = ukf.R.copy()
                    for m in up if -np.sign(gamma * psi) > 0 else down:
                        ukf.x, ukf.P = x_prior.copy(), p_prior.copy()
                        ukf.sigmas_f = ukf.points_fn.sigma_points(x_prior, p_prior)
                        ukf.update(y[k : k + 1], R=r0 * m)
                        if abs(y[k] - ukf.x[0]) <= law.threshold:
                            break
                    ukf.R = r0 * m
            estimate[k] = ukf.x[0]
    except (ValueError, np.linalg.LinAlgError):
        return None  # filterpy's Cholesky failed on this window
    return estimate


def speed() -> None:
    log = read_temperature_log(sample_log_path())
    windows = np.arange(5.0, 61.0)
    periods = np.array([65.0, 70.0, 75.0, 80.0])
    minimal_identification_time(log, "aukf", periods_min=list(periods), windows_min=list(windows))  # warm-up
    start = time.perf_counter()
    ours = minimal_identification_time(log, "aukf", periods_min=list(periods), windows_min=list(windows))
    t_ours = time.perf_counter() - start
    start = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        peer = filterpy_min_time(log, windows, periods)
    t_peer = time.perf_counter() - start
    agree = np.mean(
        ours.windows_min[np.nanargmin(np.where(np.isfinite(peer), peer, np.inf), axis=1)] == ours.best_per_period_min
    )
    print("\nMinimal-identification-time search, 10 sensors, L = 5..60 min, 4 sampling periods, aukf:")
    print(f"  mtident {t_ours:.3f} s   filterpy loop {t_peer:.1f} s   ratio filterpy/mtident = {t_peer / t_ours:.0f}x")
    print(
        f"  best L per (period, sensor) identical in {agree:.0%} of cases (filterpy: dense form; mtident: square-root)"
    )


def least_squares_speed() -> None:
    """The first-order least-squares fit against scipy's curve_fit (from the same starting guess)
    on every window of 8 to 60 readings of the sample's ten sensors: time, and which fits better."""
    from scipy.optimize import curve_fit

    from mtident.thermal.lsq import fit_rise
    from mtident.thermal.model import rise_curve
    from mtident.thermal.readings import quick_estimate

    log = read_temperature_log(sample_log_path())
    windows = [(log.time_min[:n], log.temperature_C[:n]) for n in range(8, 61)]
    guesses = [np.column_stack(quick_estimate(t, y)) for t, y in windows]
    start = time.perf_counter()
    ours = [fit_rise(t, y, g).params for (t, y), g in zip(windows, guesses, strict=True)]
    t_ours = time.perf_counter() - start
    start = time.perf_counter()
    peer = []
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        for (t, y), g in zip(windows, guesses, strict=True):
            row = []
            for s in range(y.shape[1]):
                p0 = [g[s, 0], float(np.clip(g[s, 1], 1e-5, 9.0)), g[s, 2]]
                bounds = ([-np.inf, 1e-6, -np.inf], [np.inf, 10.0, np.inf])
                row.append(curve_fit(rise_curve, t, y[:, s], p0=p0, bounds=bounds, max_nfev=2000)[0])
            peer.append(np.array(row))
    t_peer = time.perf_counter() - start
    better = worse = 0
    for (t, y), a, b in zip(windows, ours, peer, strict=True):
        rss_ours = np.sum((y - rise_curve(t[:, None], a[:, 0], a[:, 1], a[:, 2])) ** 2, axis=0)
        rss_peer = np.sum((y - rise_curve(t[:, None], b[:, 0], b[:, 1], b[:, 2])) ** 2, axis=0)
        better += int(np.sum(rss_ours < rss_peer * (1 - 1e-6)))
        worse += int(np.sum(rss_ours > rss_peer * (1 + 1e-6)))
    fits = sum(y.shape[1] for _, y in windows)
    print(f"\nFirst-order least squares, {fits} fits (10 sensors, windows of 8-60 readings of the sample):")
    print(
        f"  mtident {t_ours:.3f} s   scipy curve_fit {t_peer:.2f} s   ratio curve_fit/mtident = {t_peer / t_ours:.0f}x"
    )
    print(f"  residual sum of squares smaller than curve_fit's in {better}, larger in {worse}")


def robust_checks() -> None:
    """One check of one sensor (all its readings so far), a housing-like warm-up of two modes over
    two hours, at 100-800 readings: no reference, a two-mode reference (two free faster modes),
    and the same reference said to hold every mode; then replays of the sample's ten sensors."""
    from mtident.thermal.monitor import MonitorSettings, monitor_step, new_state
    from mtident.thermal.reference import MachineReference
    from mtident.thermal.robust import RobustSettings, SensorModes, estimate_sensor

    rng = np.random.default_rng(1)
    reference = SensorModes((60.0, 8.0), (0.1, 0.1))
    print("\nOne model-robust check of one sensor (median of 3; seconds; 'monitor': as the monitor checks, ±0.2 °C):")
    print(
        f"{'readings':>9} {'no reference':>13} {'reference':>10} {'ref, free 0':>12} {'monitor, none':>14} "
        f"{'monitor, ref':>13}"
    )
    for n in (100, 200, 400, 800):
        t = np.linspace(0.0, 120.0, n)
        y = np.round(28.0 - 6.0 * np.exp(-t / 60.0) - 2.0 * np.exp(-t / 8.0) + rng.normal(0.0, 0.02, n), 2)
        cells = []
        said_complete = {"reference": reference, "settings": RobustSettings(free_fast_modes=0)}
        monitor: dict[str, object] = {"refine_within": 0.2}
        for kw in ({}, {"reference": reference}, said_complete, monitor, {**monitor, "reference": reference}):
            times = []
            for _ in range(3):
                start = time.perf_counter()
                estimate_sensor("S", t, y, **kw)
                times.append(time.perf_counter() - start)
            cells.append(float(np.median(times)))
        print(f"{n:>9} {cells[0]:>13.3f} {cells[1]:>10.3f} {cells[2]:>12.3f} {cells[3]:>14.3f} {cells[4]:>13.3f}")
    log = read_temperature_log(sample_log_path())
    known = MachineReference("known", "", 300.0, "", {s: SensorModes((62.5,), (0.1,)) for s in log.sensors})
    choices = (("no reference", MonitorSettings()), ("one-mode reference", MonitorSettings(reference=known)))
    for label, settings in choices:
        state = new_state(list(log.sensors))
        start = time.perf_counter()
        state, _ = monitor_step(state, log.time_min, log.temperature_C, None, settings)
        print(
            f"replay of the sample, {len(log.sensors)} sensors x {len(log.time_min)} readings, {label}: "
            f"{time.perf_counter() - start:.1f} s (stopped: {state.stopped}, at {state.stop_time_min} min)"
        )
    _quick_start_replay()


def _quick_start_replay() -> None:
    """The README's quick start: the sample with its room sensor and the shipped reference."""
    from mtident.thermal.monitor import MonitorSettings, monitor_step, new_state
    from mtident.thermal.reference import load_reference

    log = read_temperature_log(sample_log_path("@sample-room"))
    room = log.sensors.index("room")
    machine = [s for s in range(len(log.sensors)) if s != room]
    settings = MonitorSettings(reference=load_reference(sample_log_path("@sample-machine")), room_sensor="room")
    state = new_state([log.sensors[s] for s in machine], with_room=True)
    start = time.perf_counter()
    state, _ = monitor_step(state, log.time_min, log.temperature_C[:, machine], log.temperature_C[:, room], settings)
    print(
        f"replay of the quick start (@sample-room, --ambient room, @sample-machine), {len(machine)} sensors x "
        f"{len(log.time_min)} readings: {time.perf_counter() - start:.1f} s (stopped at {state.stop_time_min} min)"
    )


def main() -> None:
    if "--checks" in sys.argv:
        robust_checks()
        return
    quick = "--quick" in sys.argv
    monte_carlo(50 if quick else 200)
    presets_on_sample()
    speed()
    least_squares_speed()


if __name__ == "__main__":
    main()
