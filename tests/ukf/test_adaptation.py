"""Tests of :mod:`mtident.ukf.adaptation`."""

from __future__ import annotations

import numpy as np
import pytest
from ukf_helpers import THERMAL_P0, THERMAL_Q, THERMAL_R, THERMAL_X0, first, thermal_data, thermal_f

from mtident.ukf import (
    AdaptiveLaw,
    FadingFactor,
    FilterConfig,
    GaussianState,
    filter_step,
    initial_carry,
    normalisation_from_reference,
    run_filter,
)


def _one_step(y: float, law: AdaptiveLaw, x0=THERMAL_X0, fading=None, square_root=False):
    cfg = FilterConfig(adaptive_law=law, fading=fading, square_root=square_root)
    carry = initial_carry(GaussianState(x0, THERMAL_P0), THERMAL_Q, THERMAL_R, cfg)
    return carry, filter_step(carry, np.array([y]), thermal_f, first, cfg)


@pytest.mark.parametrize("square_root", [False, True])
@pytest.mark.parametrize("offset", [+0.3, -0.3])
def test_adaptive_law_cases_with_linear_measurement(offset, square_root):
    """γ has the sign of ψ here, so R must decrease; Q grows for γ < −C and shrinks for γ > C."""
    law = AdaptiveLaw(threshold=1e-4)
    prior_T = thermal_f(THERMAL_X0[None])[0, 0]
    carry, (new, info) = _one_step(prior_T + offset, law, square_root=square_root)
    assert info.adapted
    assert new.emission_cov[0, 0] < carry.emission_cov[0, 0]
    expected_q = 10.0 if offset < 0 else 0.1
    np.testing.assert_allclose(new.process_cov, expected_q * carry.process_cov)
    assert info.reached and abs(info.posterior_residual[0]) <= 1e-4
    # R moved by a whole number of steps of R/100 (not cumulative)
    j = (1 - new.emission_cov[0, 0] / carry.emission_cov[0, 0]) * 100
    np.testing.assert_allclose(j, np.round(j), atol=1e-9)


def test_adaptive_law_leaves_small_residuals_alone():
    law = AdaptiveLaw(threshold=10.0)
    carry, (new, info) = _one_step(18.0, law)
    assert not info.adapted
    np.testing.assert_array_equal(new.process_cov, carry.process_cov)
    np.testing.assert_array_equal(new.emission_cov, carry.emission_cov)


def test_adaptive_law_decrease_never_reaches_zero():
    up, down = AdaptiveLaw(max_search_steps=500).search_multipliers()
    assert down.min() > 0 and len(down) == 99 and len(up) == 500


def test_normalised_fading_factor():
    lam = normalisation_from_reference(np.array([20.0]))
    np.testing.assert_allclose(lam, [1.0])  # Eq. 29 with m = 1: the normalisation is the identity
    ys = thermal_data(6)
    runs = [
        run_filter(
            GaussianState(THERMAL_X0, THERMAL_P0),
            ys,
            lambda p, k: thermal_f(p),
            first,
            THERMAL_Q,
            THERMAL_R,
            FilterConfig(fading=f),
        )
        for f in (FadingFactor(), FadingFactor(normalisation=lam))
    ]
    np.testing.assert_allclose(runs[0].means, runs[1].means, rtol=1e-12)
    two = normalisation_from_reference(np.array([1.0, 100.0]))
    np.testing.assert_allclose(np.sum(two**2), 2.0)
