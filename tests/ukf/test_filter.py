"""Tests of :mod:`mtident.ukf.filter`."""

from __future__ import annotations

import inspect

import numpy as np
import pytest
from filterpy.kalman import KalmanFilter, UnscentedKalmanFilter
from filterpy.kalman import MerweScaledSigmaPoints as FPPoints
from ukf_helpers import DT, THERMAL_P0, THERMAL_Q, THERMAL_R, THERMAL_X0, first, thermal_data, thermal_f

from mtident.exceptions import CovarianceError, DimensionError
from mtident.ukf import (
    AdaptiveLaw,
    FadingFactor,
    FilterConfig,
    GaussianState,
    MerweScaledSigmaPoints,
    filter_step,
    initial_carry,
    run_filter,
)

# filterpy 2.x redraws the sigma points from the predicted (x, P) at the end of
# predict() (seed 001 Eq. 8); filterpy 1.4.5 reuses the propagated ones (seed 000).
FILTERPY_REDRAWS = "self.sigmas_f = self.points_fn.sigma_points" in inspect.getsource(UnscentedKalmanFilter.predict)


def filterpy_run(ys, x0, P0, Q, R, fx, hx, alpha=1.0, beta=2.0, kappa=0.0):
    n = len(x0)
    pts = FPPoints(n, alpha=alpha, beta=beta, kappa=kappa)
    ukf = UnscentedKalmanFilter(
        dim_x=n, dim_z=ys.shape[1], dt=DT, fx=lambda x, dt: fx(x[None])[0], hx=lambda x: hx(x[None])[0], points=pts
    )
    ukf.x, ukf.P, ukf.Q, ukf.R = x0.copy(), P0.copy(), Q.copy(), R.copy()
    means, covs = [], []
    for y in ys:
        ukf.predict()
        ukf.update(y)
        means.append(ukf.x.copy())
        covs.append(ukf.P.copy())
    return np.array(means), np.array(covs)


@pytest.mark.parametrize("alpha,beta,kappa", [(1.0, 2.0, 0.0), (1.0, 2.0, 2.0)])
def test_standard_ukf_equals_filterpy_on_thermal_model(alpha, beta, kappa):
    ys = thermal_data()
    ref_m, ref_P = filterpy_run(ys, THERMAL_X0, THERMAL_P0, THERMAL_Q, THERMAL_R, thermal_f, first, alpha, beta, kappa)
    config = FilterConfig(sigma_points=MerweScaledSigmaPoints(alpha, beta, kappa), redraw=FILTERPY_REDRAWS)
    rec = run_filter(
        GaussianState(THERMAL_X0, THERMAL_P0), ys, lambda p, k: thermal_f(p), first, THERMAL_Q, THERMAL_R, config
    )
    np.testing.assert_allclose(rec.means, ref_m, rtol=1e-9)
    np.testing.assert_allclose(rec.covs, ref_P, rtol=1e-9, atol=1e-18)


def linear_model(seed: int = 1):
    rng = np.random.default_rng(seed)
    F = np.array([[1.0, 0.1, 0.0, 0.0], [0.0, 1.0, 0.0, 0.0], [0.0, 0.0, 0.9, 0.2], [0.0, 0.0, -0.2, 0.9]])
    H = np.array([[1.0, 0.0, 0.0, 0.0], [0.0, 0.0, 1.0, 0.5]])
    Q = 0.01 * np.eye(4)
    R = np.diag([0.1, 0.2])
    x = np.zeros(4)
    ys = []
    for _ in range(200):
        x = F @ x + rng.multivariate_normal(np.zeros(4), Q)
        ys.append(H @ x + rng.multivariate_normal(np.zeros(2), R))
    return F, H, Q, R, np.array(ys)


def test_standard_ukf_equals_filterpy_on_linear_4_state_model():
    F, H, Q, R, ys = linear_model()
    fx = lambda p: p @ F.T  # noqa: E731
    hx = lambda p: p @ H.T  # noqa: E731
    x0, P0 = np.ones(4), np.eye(4)
    ref_m, ref_P = filterpy_run(ys, x0, P0, Q, R, fx, hx)
    rec = run_filter(GaussianState(x0, P0), ys, lambda p, k: fx(p), hx, Q, R, FilterConfig(redraw=FILTERPY_REDRAWS))
    np.testing.assert_allclose(rec.means, ref_m, rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(rec.covs, ref_P, rtol=1e-9, atol=1e-12)


def test_ukf_equals_exact_kalman_filter_on_linear_gaussian_model():
    F, H, Q, R, ys = linear_model(2)
    kf = KalmanFilter(dim_x=4, dim_z=2)
    kf.F, kf.H, kf.Q, kf.R, kf.x, kf.P = F, H, Q, R, np.ones(4), np.eye(4)
    ref = []
    for y in ys:
        kf.predict()
        kf.update(y)
        ref.append((kf.x.copy(), kf.P.copy()))
    # Redrawn measurement points carry Q into Py and Pxy, as the Kalman filter does.
    cfg = FilterConfig(redraw=True)
    rec = run_filter(GaussianState(np.ones(4), np.eye(4)), ys, lambda p, k: p @ F.T, lambda p: p @ H.T, Q, R, cfg)
    np.testing.assert_allclose(rec.means, np.array([r[0] for r in ref]), rtol=1e-9, atol=1e-12)
    np.testing.assert_allclose(rec.covs, np.array([r[1] for r in ref]), rtol=1e-9, atol=1e-12)
    # Seed 000's propagated points leave Q out of Py: not the Kalman filter unless Q = 0.
    seed000 = run_filter(GaussianState(np.ones(4), np.eye(4)), ys, lambda p, k: p @ F.T, lambda p: p @ H.T, Q, R)
    assert np.abs(seed000.means - rec.means).max() > 1e-3


def test_square_root_ukf_equals_standard_ukf():
    ys = thermal_data(3)
    run = lambda cfg: run_filter(  # noqa: E731
        GaussianState(THERMAL_X0, THERMAL_P0), ys, lambda p, k: thermal_f(p), first, THERMAL_Q, THERMAL_R, cfg
    )
    dense = run(FilterConfig())
    sqrt = run(FilterConfig(square_root=True))
    np.testing.assert_allclose(sqrt.means, dense.means, rtol=1e-8)
    np.testing.assert_allclose(sqrt.covs, dense.covs, rtol=1e-8, atol=1e-16)


def test_square_root_stays_positive_definite_where_standard_fails():
    """Grewal & Andrews' ill-conditioned example: two nearly dependent, very precise measurements.

    P − K S Kᵀ loses positive definiteness to rounding in the standard form; the
    square-root form (downdate, or its Joseph-form fallback) keeps a valid factor.
    """
    d = 1e-6
    H = np.array([[1.0, 1.0], [1.0, 1.0 + d]])
    run = lambda sr: run_filter(  # noqa: E731
        GaussianState(np.zeros(2), np.eye(2)),
        np.zeros((5, 2)),
        lambda p, k: p,
        lambda p: p @ H.T,
        1e-30 * np.eye(2),
        d**2 * np.eye(2),
        FilterConfig(square_root=sr, redraw=True, name="std" if not sr else "sr"),
    )
    with pytest.raises(
        CovarianceError,
        match=r"filter 'std', step 1: .*stage 'sigma points of the previous posterior'.*smallest eigenvalue",
    ):
        run(False)
    rec = run(True)
    assert np.all(np.isfinite(rec.covs))
    assert np.linalg.eigvalsh(rec.covs).min() > 0
    np.testing.assert_allclose(rec.covs, np.swapaxes(rec.covs, -1, -2))


@pytest.mark.parametrize("d", [1e-6, 1e-8])
def test_square_root_survives_nearly_singular_posterior(d):
    """A precise measurement of x1 + x2 with very different prior scales: the downdate
    cancels to rounding and the Joseph-form fallback takes over instead of NaN."""
    F = np.array([[1.0, 0.1], [0.0, 1.0]])
    H = np.array([[1.0, 1.0]])
    rec = run_filter(
        GaussianState(np.zeros(2), np.diag([1e4, 1e-4])),
        np.zeros((50, 1)),
        lambda p, k: p @ F.T,
        lambda p: p @ H.T,
        np.diag([1e-12, 1e-12]),
        np.array([[d**2]]),
        FilterConfig(square_root=True, redraw=True),
    )
    assert np.all(np.isfinite(rec.covs)) and np.linalg.eigvalsh(rec.covs).min() > 0


def test_batch_equals_one_at_a_time():
    # 150 steps, not 400: every sensor's fading factor and adaptive law act in the first 100 (1-100
    # times each), and the runs cost 40 % of the time
    ys = np.stack([thermal_data(s, steps=150) for s in range(5)], axis=1)  # (T, 5, 1)
    x0 = np.stack([THERMAL_X0 + [0.1 * s, 0.0, 0.5 * s] for s in range(5)])
    for cfg in (
        FilterConfig(),
        FilterConfig(square_root=True, fading=FadingFactor(), adaptive_law=AdaptiveLaw(threshold=1e-3)),
    ):
        batch = run_filter(
            GaussianState(x0, THERMAL_P0), ys, lambda p, k: thermal_f(p), first, THERMAL_Q, THERMAL_R, cfg
        )
        for s in range(5):
            single = run_filter(
                GaussianState(x0[s], THERMAL_P0), ys[:, s], lambda p, k: thermal_f(p), first, THERMAL_Q, THERMAL_R, cfg
            )
            np.testing.assert_allclose(batch.means[:, s], single.means, rtol=1e-12)
            np.testing.assert_allclose(batch.covs[:, s], single.covs, rtol=1e-12, atol=1e-20)
            np.testing.assert_allclose(batch.emission_covs[:, s], single.emission_covs, rtol=1e-12)
            np.testing.assert_array_equal(batch.adapted[:, s], single.adapted)


def test_covariances_stay_symmetric_positive_definite():
    rec = run_filter(
        GaussianState(THERMAL_X0, THERMAL_P0), thermal_data(7), lambda p, k: thermal_f(p), first, THERMAL_Q, THERMAL_R
    )
    np.testing.assert_array_equal(rec.covs, np.swapaxes(rec.covs, -1, -2))
    assert np.linalg.eigvalsh(rec.covs).min() > 0


def test_missing_measurement_keeps_prediction():
    ys = thermal_data(1, steps=5)
    ys[2] = np.nan
    rec = run_filter(GaussianState(THERMAL_X0, THERMAL_P0), ys, lambda p, k: thermal_f(p), first, THERMAL_Q, THERMAL_R)
    assert np.all(np.isfinite(rec.means))
    assert rec.covs[2, 0, 0] > rec.covs[1, 0, 0]  # no update: uncertainty grows


def test_dimension_errors_name_the_input():
    with pytest.raises(DimensionError, match=r"process noise covariance Q: expected shape \(\.\.\., 3, 3\)"):
        initial_carry(GaussianState(THERMAL_X0, THERMAL_P0), np.eye(2), THERMAL_R, FilterConfig())
    with pytest.raises(DimensionError, match="initial covariance"):
        initial_carry(GaussianState(THERMAL_X0, np.eye(2)), THERMAL_Q, THERMAL_R, FilterConfig())
    with pytest.raises(DimensionError, match="scalar measurement"):
        initial_carry(
            GaussianState(THERMAL_X0, THERMAL_P0), THERMAL_Q, np.eye(2), FilterConfig(adaptive_law=AdaptiveLaw())
        )


def test_non_positive_definite_initial_covariance_is_named():
    with pytest.raises(CovarianceError, match="batch index \\(1,\\).*initial covariance P0 of filter 'afukf'"):
        initial_carry(
            GaussianState(np.zeros((2, 3)), np.stack([np.eye(3), -np.eye(3)])),
            THERMAL_Q,
            THERMAL_R,
            FilterConfig(square_root=True, name="afukf"),
        )


def test_adaptive_law_increases_r_when_measurement_is_nonlinear():
    """h(x) = −T flips the sign relation of γ and ψ: the cases that increase R occur."""
    law = AdaptiveLaw(threshold=1e-6, max_search_steps=5)
    cfg = FilterConfig(adaptive_law=law)
    neg = lambda p: -p[..., :1] + 1e-3 * p[..., :1] ** 2  # noqa: E731
    carry = initial_carry(GaussianState(THERMAL_X0, THERMAL_P0), THERMAL_Q, np.array([[0.3**2]]), cfg)
    prior_y = neg(thermal_f(THERMAL_X0[None]))[0, 0]
    new, info = filter_step(carry, np.array([prior_y + 0.2]), thermal_f, neg, cfg)
    assert info.adapted
    # the bounded search ends even though |γ| ≤ C is not reachable here
    ratio = new.emission_cov[0, 0] / carry.emission_cov[0, 0]
    assert 0.94 < ratio < 1.06 and ratio != 1.0
    assert not info.reached


def test_fading_factor_is_one_when_residuals_match_and_grows_after_a_jump():
    rng = np.random.default_rng(5)
    F = np.array([[1.0]])
    Q, R = np.array([[1e-4]]), np.array([[0.01]])
    x, ys = 0.0, []
    for k in range(300):
        x += rng.normal(0, 1e-2) + (5.0 if k == 200 else 0.0)
        ys.append([x + rng.normal(0, 0.1)])
    cfg = FilterConfig(fading=FadingFactor())
    rec = run_filter(GaussianState(np.zeros(1), np.eye(1)), np.array(ys), lambda p, k: p @ F.T, lambda p: p, Q, R, cfg)
    assert np.mean(rec.fading[50:200] == 1.0) > 0.95
    assert rec.fading[200] == 2.0  # the bound: tr(V − ρR)/tr(Py) is far above it after a 5σ·50 jump
    unbounded = run_filter(
        GaussianState(np.zeros(1), np.eye(1)),
        np.array(ys[:201]),
        lambda p, k: p @ F.T,
        lambda p: p,
        Q,
        R,
        FilterConfig(fading=FadingFactor(max_factor=np.inf)),
    )
    assert unbounded.fading[200] > 10.0
    plain = run_filter(GaussianState(np.zeros(1), np.eye(1)), np.array(ys), lambda p, k: p @ F.T, lambda p: p, Q, R)
    # after the jump the faded filter is back on the data sooner
    assert abs(rec.means[203, 0] - ys[203][0]) < abs(plain.means[203, 0] - ys[203][0])
    assert np.linalg.eigvalsh(rec.covs).min() > 0


def test_fading_factor_with_sqrt_equals_dense():
    ys = thermal_data(2)
    ys[100:] += 0.5
    run = lambda sr: run_filter(  # noqa: E731
        GaussianState(THERMAL_X0, THERMAL_P0),
        ys,
        lambda p, k: thermal_f(p),
        first,
        THERMAL_Q,
        THERMAL_R,
        FilterConfig(square_root=sr, fading=FadingFactor()),
    )
    dense, sqrt = run(False), run(True)
    assert dense.fading.max() > 1.0
    np.testing.assert_allclose(sqrt.means, dense.means, rtol=1e-7)
    np.testing.assert_allclose(sqrt.covs, dense.covs, rtol=1e-6, atol=1e-14)
