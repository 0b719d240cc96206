"""The compiled loops of the model-robust fit: the objectives' slopes, the quasi-Newton search,
the grid's normal equations and the choice of leading models, each against a plain reference."""

from __future__ import annotations

import numpy as np
import pytest

import mtident.thermal.modal_search as search_module
from mtident.thermal.modal_kernel import (
    END_OBJECTIVE,
    RSS_OBJECTIVE,
    leading_rows,
    objective_and_gradient,
    refine_log_tau,
    solve_selected,
)

LOG_MODE_RATIO = float(np.log(1.5))


def _inputs(with_room: bool, noise: float = 0.0, seed: int = 0):  # noqa: ANN202
    """Kernel inputs of a two-mode warm-up (τ 40 and 6 min), binned one reading a bin."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 90.0, 120)
    room = 20.0 + 0.01 * t + 0.3 * np.sin(t / 15.0)
    y = 30.0 - 7.0 * np.exp(-t / 40.0) - 3.0 * np.exp(-t / 6.0) + rng.normal(0.0, noise, t.size)
    target = (y - room if with_room else y) - 25.0
    return (t.copy(), t.copy(), np.ones_like(t), target, room if with_room else np.empty(0))


def _penalty(k: int, with_room: bool) -> np.ndarray:
    return np.array([0.0] + [1e-6] * k + ([1e-6] * k if with_room else []))


@pytest.mark.parametrize("with_room", [False, True])
@pytest.mark.parametrize(
    "objective",
    [
        (float(RSS_OBJECTIVE), 0.0, 0.0, 1.0, LOG_MODE_RATIO),
        (float(END_OBJECTIVE), 50.0, 1.0, 2.0, LOG_MODE_RATIO),  # inside the threshold
        (float(END_OBJECTIVE), 1e-3, -1.0, 2.0, 0.0),  # beyond it
    ],
)
def test_the_objectives_slopes_are_their_derivatives(with_room, objective):
    inputs = _inputs(with_room, noise=0.05)
    penalty = _penalty(2, with_room)
    # two modes closer than the ratio kept apart, so that the penalty's slope is tested too
    for log_tau in (np.log([35.0, 8.0]), np.log([12.0, 10.0])):
        _, gradient = objective_and_gradient(inputs, log_tau, penalty, objective)
        step = 1e-6
        numeric = [
            (
                objective_and_gradient(inputs, log_tau + step * e, penalty, objective)[0]
                - objective_and_gradient(inputs, log_tau - step * e, penalty, objective)[0]
            )
            / (2 * step)
            for e in np.eye(2)
        ]
        np.testing.assert_allclose(gradient, numeric, rtol=2e-4, atol=1e-6 * max(1.0, np.abs(numeric).max()))


def test_the_search_recovers_a_noiseless_curves_time_constants_and_keeps_to_its_bounds():
    inputs = _inputs(with_room=False)
    penalty = _penalty(2, False)
    objective = (float(RSS_OBJECTIVE), 0.0, 0.0, 1.0, LOG_MODE_RATIO)
    lower, upper = np.log([1.0, 1.0]), np.log([300.0, 300.0])
    found = refine_log_tau(inputs, np.log([60.0, 3.0]), lower, upper, penalty, objective, 100, 300)
    np.testing.assert_allclose(np.sort(np.exp(found)), [6.0, 40.0], rtol=1e-4)
    # a box that excludes the truth: the search ends on its edge, never beyond
    boxed = refine_log_tau(
        inputs, np.log([25.0, 9.0]), np.log([20.0, 8.0]), np.log([30.0, 10.0]), penalty, objective, 100, 300
    )
    assert np.all(boxed >= np.log([20.0, 8.0]) - 1e-12) and np.all(boxed <= np.log([30.0, 10.0]) + 1e-12)
    assert np.exp(boxed[0]) == pytest.approx(30.0) and np.exp(boxed[1]) == pytest.approx(8.0)


def test_the_grids_normal_equations_match_a_direct_solve():
    rng = np.random.default_rng(3)
    sets, columns_all, n = 3, 6, 50
    X = rng.normal(size=(sets, n, columns_all))
    y = rng.normal(size=n)
    gram, rhs, yy = np.swapaxes(X, 1, 2) @ X, np.swapaxes(X, 1, 2) @ y, float(y @ y)
    chosen = np.array([[0, 1, 4], [0, 2, 3], [0, 5, 1]])
    penalty = np.array([0.0, 0.5, 0.5])
    rss, theta, first = solve_selected(gram, rhs, chosen, yy, penalty)
    for s in range(sets):
        for t, cols in enumerate(chosen):
            g = gram[s][np.ix_(cols, cols)] + np.diag(penalty)
            direct = np.linalg.solve(g, rhs[s, cols])
            row = s * len(chosen) + t
            np.testing.assert_allclose(theta[row], direct, rtol=1e-8)
            np.testing.assert_allclose(first[row], np.linalg.inv(g)[:, 0], rtol=1e-8)
            resid = y - X[s][:, cols] @ direct
            assert rss[row] == pytest.approx(resid @ resid + direct @ np.diag(penalty) @ direct, rel=1e-8)


def _leading_reference(values, log_tau, modes, count, apart):  # noqa: ANN001, ANN202
    """The rule in plain Python: take the lowest, pass over its basin, again."""
    values = values.copy()
    taken = []
    while len(taken) < count and np.isfinite(values.min()):
        row = int(np.argmin(values))
        taken.append(row)
        values[row] = np.inf
        if apart > 0:
            k = modes[row]
            same = (modes == k) & np.all(np.abs(log_tau[:, :k] - log_tau[row, :k]) <= apart, axis=1)
            values[same] = np.inf
    return taken


@pytest.mark.parametrize("seed", range(5))
def test_the_leading_models_of_different_basins_are_those_of_the_plain_rule(seed, monkeypatch):
    rng = np.random.default_rng(seed)
    rows = 400
    modes = rng.integers(1, 4, rows)
    log_tau = np.where(np.arange(3) < modes[:, None], rng.uniform(0.0, 5.0, (rows, 3)), 0.0)
    values = rng.normal(size=rows)
    values[rng.random(rows) < 0.1] = np.inf
    values[:20] = values[20:40]  # ties go to the earlier row
    values[40:60] = values[60]
    for count, apart in ((5, 0.0), (30, 0.5), (400, 0.2)):
        expected = _leading_reference(values, log_tau, modes, count, apart)
        order = np.argsort(values, kind="stable")
        got, exhausted = leading_rows(values, order, np.inf, log_tau[order], modes[order], count, apart)
        assert list(got) == expected and not exhausted  # every row scanned, or the infinite ones reached
        # scanned from the lowest few rows, more where those run out (ties at the cut included)
        for scan in (1, 7, 64):
            monkeypatch.setattr(search_module, "_LEADING_SCAN", scan)
            scanned = search_module._leading_rows(values, lambda rows: (log_tau[rows], modes[rows]), count, apart)
            assert list(scanned) == expected
