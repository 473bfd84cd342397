"""Tests of sensorless.identification.regression."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.linalg

import sensorless as sl
from sensorless.exceptions import DimensionError, InputValueError
from sensorless.identification.regression import (
    RegressionAccumulator,
    eliminate,
    identify_base_parameters,
    least_squares,
    relative_weight_significance,
    relative_weights,
)
from sensorless.robots.base_parameters import base_parameters


def _states(n_dof: int, n: int, seed: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return (
        rng.uniform(-np.pi, np.pi, (n, n_dof)),
        rng.uniform(-2, 2, (n, n_dof)),
        rng.uniform(-5, 5, (n, n_dof)),
    )


def _data(seed: int = 0, n: int = 500, p: int = 4) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    X = rng.standard_normal((n, p)) @ rng.standard_normal((p, p)) + 1.0
    y = X @ np.arange(1.0, p + 1) + 0.5 + rng.standard_normal(n)
    return X, y


def test_noise_free_recovery_planar2_no_friction() -> None:
    robot = sl.robots.load("planar2")
    q, qd, qdd = _states(2, 300, 1)
    tau = robot.inverse_dynamics(q, qd, qdd)
    bp, res = identify_base_parameters(robot, q, qd, qdd, tau, friction=None, segment=70)
    np.testing.assert_allclose(res.estimates, bp.values, atol=1e-6 * np.abs(bp.values).max())
    assert res.names == bp.names
    assert res.r_squared == pytest.approx(1.0)


def test_noise_free_recovery_puma_with_friction() -> None:
    robot = sl.robots.load("puma560")
    q, qd, qdd = _states(6, 400, 2)
    tau = robot.inverse_dynamics(q, qd, qdd) + robot.friction_torque(qd)
    bp, res = identify_base_parameters(robot, q, qd, qdd, tau, segment=150)
    truth = np.concatenate(
        [bp.values, robot.friction.c_pos, robot.friction.c_neg, robot.friction.fv]
    )
    np.testing.assert_allclose(res.estimates, truth, rtol=1e-6, atol=1e-6 * np.abs(truth).max())
    assert res.names[-1] == "fv6"
    assert res.to_pandas().shape == (truth.size, 5)


def test_confidence_interval_coverage() -> None:
    robot = sl.robots.load("planar2")
    bp = base_parameters(robot)
    q, qd, qdd = _states(2, 100, 3)
    X = bp.regressor(q, qd, qdd).reshape(-1, bp.count)
    clean = X @ bp.values
    rng = np.random.default_rng(4)
    inside = []
    for _ in range(100):
        res = least_squares(X, clean + 0.3 * rng.standard_normal(clean.size), bp.names)
        inside.append((res.ci_lower <= bp.values) & (bp.values <= res.ci_upper))
    coverage = np.mean(inside)
    assert 0.90 <= coverage <= 0.99


def test_statistics_match_direct_formulas() -> None:
    X, y = _data()
    res = least_squares(X, y)
    theta, *_ = np.linalg.lstsq(X, y, rcond=None)
    np.testing.assert_allclose(res.estimates, theta, rtol=1e-10)
    resid = y - X @ theta
    sigma2 = resid @ resid / (X.shape[0] - X.shape[1])
    se = np.sqrt(np.diag(np.linalg.inv(X.T @ X)) * sigma2)
    np.testing.assert_allclose(res.std_errors, se, rtol=1e-9)
    np.testing.assert_allclose(res.t_values, theta / se, rtol=1e-9)
    assert res.rss == pytest.approx(resid @ resid, rel=1e-9)
    assert res.condition_number == pytest.approx(np.linalg.cond(X), rel=1e-6)
    assert res.r_squared == pytest.approx(1 - resid @ resid / np.sum((y - y.mean()) ** 2))


def _johnson(X: np.ndarray, y: np.ndarray) -> np.ndarray:
    corr = np.corrcoef(np.column_stack([X, y]), rowvar=False)
    rxx, rxy = corr[:-1, :-1], corr[:-1, -1]
    lam = np.real(scipy.linalg.sqrtm(rxx))
    beta = np.linalg.solve(lam, rxy)
    return (lam**2) @ (beta**2)


def test_relative_weights_match_johnson_and_sum_to_r_squared() -> None:
    X, y = _data(5)
    raw, rescaled = relative_weights(X, y)
    np.testing.assert_allclose(raw, _johnson(X, y), rtol=1e-9)
    with_intercept = np.column_stack([np.ones(len(y)), X])
    theta, *_ = np.linalg.lstsq(with_intercept, y, rcond=None)
    resid = y - with_intercept @ theta
    r2 = 1 - resid @ resid / np.sum((y - y.mean()) ** 2)
    assert raw.sum() == pytest.approx(r2, rel=1e-9)
    assert rescaled.sum() == pytest.approx(100.0)


def test_pooled_equals_single() -> None:
    X, y = _data(6, n=1000)
    single = RegressionAccumulator(4).add(X, y)
    pooled = RegressionAccumulator(4)
    for part in np.array_split(np.arange(1000), 13):
        pooled.add(X[part], y[part])
    a, b = single.result(), pooled.result()
    np.testing.assert_allclose(b.estimates, a.estimates, rtol=1e-9)
    np.testing.assert_allclose(b.std_errors, a.std_errors, rtol=1e-9)
    assert b.r_squared == pytest.approx(a.r_squared, rel=1e-9)
    np.testing.assert_allclose(relative_weights(pooled)[0], relative_weights(single)[0], rtol=1e-9)


def test_eliminate_drops_noise_and_tiny_collinear_columns() -> None:
    rng = np.random.default_rng(7)
    n = 2000
    true = rng.standard_normal((n, 3))
    noise_col = rng.standard_normal(n)
    collinear = 0.05 * true[:, 0] + rng.standard_normal(n)  # weakly collinear with "a"
    X = np.column_stack([true, noise_col, collinear])
    y = true @ np.array([3.0, -2.0, 1.5]) + 1e-3 * collinear + 0.5 * rng.standard_normal(n)
    names = ["a", "b", "c", "noise", "tiny"]
    report = eliminate(X, y, names, t_threshold=10.0, weight_threshold=0.5)
    assert report.converged
    assert report.kept == ["a", "b", "c"]
    assert report.final_estimates[3:].tolist() == [0.0, 0.0]
    np.testing.assert_allclose(report.final_estimates[:3], [3.0, -2.0, 1.5], atol=0.05)
    table = report.to_pandas()
    assert ("Iteration 1", "relative_weight") in table.columns
    assert ("Final", "estimate") in table.columns
    assert not table[("Iteration 1", "kept")]["noise"]


def test_relative_weight_significance() -> None:
    rng = np.random.default_rng(8)
    X = rng.standard_normal((300, 2))
    y = 2.0 * X[:, 0] + rng.standard_normal(300)
    sig = relative_weight_significance(X, y, ["real", "noise"], n_boot=100)
    assert sig.significant.tolist() == [True, False]
    assert sig.to_pandas().shape == (2, 4)


def test_rank_deficient_data_names_dependent_columns() -> None:
    X, y = _data(9, p=3)
    X = np.column_stack([X, X[:, 0] + 2 * X[:, 1]])
    with pytest.raises(InputValueError, match=r"rank-deficient.*x1.*x2.*x4"):
        least_squares(X, y)


def test_zero_column_and_no_excitation() -> None:
    X, y = _data(10, p=2)
    with pytest.raises(InputValueError, match=r"columns \['x3'\] are zero"):
        least_squares(np.column_stack([X, np.zeros(len(y))]), y)
    with pytest.raises(InputValueError, match="standing still"):
        least_squares(np.zeros((50, 3)), np.ones(50))
    robot = sl.robots.load("planar2")
    still = np.zeros((50, 2))
    with pytest.raises(InputValueError, match=r"rank-deficient|standing still"):
        identify_base_parameters(robot, still, still, still, still)


def test_too_few_samples() -> None:
    X, y = _data(11, n=4, p=4)
    with pytest.raises(InputValueError, match="more samples than parameters"):
        least_squares(X, y)


def test_mismatched_joint_counts_and_options() -> None:
    robot = sl.robots.load("planar2")
    q, qd, qdd = _states(3, 20, 0)
    with pytest.raises(DimensionError, match="2 joints"):
        identify_base_parameters(robot, q, qd, qdd, q)
    q, qd, qdd = _states(2, 20, 0)
    with pytest.raises(DimensionError, match="same number of samples"):
        identify_base_parameters(robot, q, qd, qdd, q[:10])
    with pytest.raises(InputValueError, match="friction must be one of"):
        identify_base_parameters(robot, q, qd, qdd, q, friction="lugre")
    with pytest.raises(InputValueError, match="segment must be"):
        identify_base_parameters(robot, q, qd, qdd, q, segment=0)
    with pytest.raises(DimensionError, match="y must have shape"):
        least_squares(np.ones((5, 2)), np.ones(4))
    with pytest.raises(DimensionError, match="3 columns"):
        RegressionAccumulator(3).add(np.ones((5, 2)), np.ones(5))
