"""Tests of :mod:`sensorless.identification.consistent`.

The retrieved parameters are checked against facts that do not come from the
retrieval: Pinocchio's RNEA of the true model (the base parameters fix the
dynamics, so a different but consistent model must give the same torques),
the pseudo-inertia test of :mod:`sensorless.simulation.model_error`, and the
zero pattern and base parameters of the thesis's KUKA LWR (Tables 2.4, 2.5, 2.7).
"""

from __future__ import annotations

import doctest
import functools
import math

import numpy as np
import pytest

import sensorless as sl
from sensorless.exceptions import DimensionError, InputTypeError, InputValueError
from sensorless.identification import consistent as consistent_module
from sensorless.identification._log_cholesky import Layout
from sensorless.identification.consistent import ConsistentFit, consistent_parameters
from sensorless.simulation.model_error import (
    is_physically_consistent,
    perturb,
    physically_consistent_links,
    pseudo_inertia,
)

MARGIN = 1e-6


def random_states(n_dof: int, seed: int, n: int = 6) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    return (
        rng.uniform(-2.0, 2.0, (n, n_dof)),
        rng.standard_normal((n, n_dof)),
        rng.standard_normal((n, n_dof)),
    )


def assert_same_dynamics(model: sl.RobotModel, reference: sl.RobotModel, seed: int = 0) -> None:
    """Pinocchio's RNEA of both models agrees at random states."""
    q, qd, qdd = random_states(model.n_dof, seed)
    expected = reference.inverse_dynamics(q, qd, qdd)
    scale = max(1.0, float(np.abs(expected).max()))
    np.testing.assert_allclose(
        model.inverse_dynamics(q, qd, qdd), expected, rtol=0, atol=1e-8 * scale
    )


# --------------------------------------------------------------------------- thesis LWR
L3, L5 = 0.4, 0.39
LWR_ALPHA_DEG = (0, 90, -90, -90, 90, 90, -90)  # Table 2.4
LWR_D = (0.0, 0.0, L3, 0.0, L5, 0.0, 0.0)
# Table 2.5: XY, XZ, mX zero on every link; no rotor inertia on the link side.
SYMMETRIC_ZERO = tuple(
    [f"{p}{i}" for i in range(1, 8) for p in ("XY", "XZ", "mX")] + [f"Ia{i}" for i in range(1, 8)]
)
# Table 2.5 link 1: only ZZ1 (the others have no effect with a vertical first axis).
LINK1_ZERO = tuple(f"{p}1" for p in ("XX", "YY", "YZ", "mY", "mZ", "m"))
# Table 2.7 "Final Estimation" [kg m, kg m²], by base-parameter name (θ1 ... θ25).
TABLE_2_7 = {
    "mY2R": 3.4968, "mY3R": 0.0, "mY4R": -1.343, "mY5R": 0.02398, "mY6R": 0.02628,
    "mY7": 0.0, "XX2R": 1.2634, "XX3R": 0.0, "XX4R": 0.42847, "XX5R": 0.0, "XX6R": 0.0,
    "XX7R": 0.0, "YZ2": 0.0, "YZ3": 0.0, "YZ4": 0.0, "YZ5": 4.241e-4, "YZ6": 0.0,
    "YZ7": 0.0, "ZZ1R": 0.0116, "ZZ2R": 1.2686, "ZZ3R": 0.0108, "ZZ4R": 0.4328,
    "ZZ5R": 6.33e-3, "ZZ6R": 4.421e-3, "ZZ7": 1.201e-4,
}  # fmt: skip


def lwr_robot(seed: int) -> sl.RobotModel:
    """Table 2.4 kinematics; random rigid links with XY = XZ = mX = 0 (Table 2.5)."""
    rng = np.random.default_rng(seed)
    table = [
        {"alpha": math.radians(alpha), "a": 0.0, "theta": 0.0, "d": d}
        for alpha, d in zip(LWR_ALPHA_DEG, LWR_D, strict=True)
    ]
    links = []
    for _ in range(7):
        # COM in the y-z plane, principal axes turned about x: XY = XZ = mX = 0.
        phi = rng.uniform(-np.pi, np.pi)
        c, s = math.cos(phi), math.sin(phi)
        rotation = np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])
        moments = rng.uniform(0.01, 0.1, 3)
        principal = moments.sum() - moments  # a rigid body: triangle inequality
        com = np.array([0.0, *rng.uniform(-0.1, 0.1, 2)])
        inertia = rotation @ np.diag(principal) @ rotation.T
        links.append(sl.LinkInertia(rng.uniform(1.0, 4.0), com, inertia))
    return sl.RobotModel.from_mdh(table, links, name="lwr_table_2_4")


@functools.cache
def grouping(kinematics: str, zero: tuple[str, ...] = ()) -> sl.BaseParameters:
    """Base parameters of a built-in robot or of the LWR (any seed: same kinematics).

    Cached: the grouping depends on the kinematics and the declared zeros only,
    and its QR is the slow part of these tests.
    """
    model = lwr_robot(0) if kinematics == "lwr" else sl.robots.load(kinematics)
    return sl.base_parameters(model, zero=zero)


def values_by_name(fit: ConsistentFit) -> dict[str, float]:
    names = fit.robot.parameter_names()
    return dict(zip(names, fit.parameters.to_numpy().ravel(), strict=True))


# --------------------------------------------------------------------------- retrieval
@pytest.mark.parametrize(("name", "seed"), [("planar2", 1), ("panda_gaz", 2), ("puma560", 3)])
def test_retrieves_another_consistent_model_with_the_same_dynamics(name: str, seed: int) -> None:
    """θ of A from a different prior B: consistent, θ reproduced, RNEA of A, yet not A.

    The PUMA 560 and its perturbation are not rigid bodies (link 1 is a lone
    moment): the prior is projected, and the base parameters are still met.
    """
    true = sl.robots.load(name)
    base = grouping(name)
    prior = perturb(true, relative=0.3, seed=seed)
    assert is_physically_consistent(prior) == (name != "puma560")
    fit = consistent_parameters(base, base.values_of(true), prior=prior)
    assert fit.success, fit.message
    assert is_physically_consistent(fit.robot)
    assert fit.relative_residual < 1e-8
    assert np.all(np.abs(fit.residual) <= 1e-8 * fit.scale)
    assert np.all(fit.min_eigenvalue >= (1 - 1e-2) * MARGIN)
    assert_same_dynamics(fit.robot, true, seed)
    difference = np.abs(fit.robot.parameter_vector() - true.parameter_vector())
    assert difference.max() > 1e-3  # another model: the standard parameters are not A's


def test_true_model_as_prior_is_kept() -> None:
    """With A as prior (the default: base.robot) and J ⪰ 2·margin, the fit is A itself."""
    true = lwr_robot(seed=17)
    assert np.linalg.eigvalsh(pseudo_inertia(true)).min() > 2 * MARGIN
    base = sl.base_parameters(true)  # base.robot is the default prior
    fit = consistent_parameters(base, base.values)
    assert fit.success, fit.message
    np.testing.assert_allclose(
        fit.robot.parameter_vector(), true.parameter_vector(), rtol=1e-11, atol=1e-12
    )


def test_prior_inside_the_margin_moves_little() -> None:
    """panda_gaz link 2 has a pseudo-inertia eigenvalue below 2·margin: clipped, then refit."""
    true = sl.robots.load("panda_gaz")
    assert np.linalg.eigvalsh(pseudo_inertia(true))[1, 0] < 2 * MARGIN
    base = grouping("panda_gaz")
    fit = consistent_parameters(base, base.values)
    assert fit.success, fit.message
    np.testing.assert_allclose(
        fit.robot.parameter_vector(), true.parameter_vector(), rtol=1e-4, atol=1e-4
    )


def test_armature_from_a_prior_without_one() -> None:
    """Ia2 is a base parameter of planar2: a prior with Ia = 0 must let it grow."""
    plain = sl.robots.load("planar2")
    values = plain.parameter_vector()
    values[21] = 0.05  # Ia2 [kg m²]
    true = plain.with_standard_parameters(values)
    base = grouping("planar2")
    fit = consistent_parameters(base, base.values_of(true), prior=plain)
    assert fit.success, fit.message
    assert fit.parameters.loc["link2", "Ia"] == pytest.approx(0.05, rel=1e-9)
    assert_same_dynamics(fit.robot, true)


def test_prior_as_array_equals_prior_as_model() -> None:
    true = sl.robots.load("planar2")
    base = grouping("planar2")
    prior = perturb(true, relative=0.2, seed=4)
    from_model = consistent_parameters(base, base.values, prior=prior)
    table = prior.standard_parameters().to_numpy()
    from_table = consistent_parameters(base, base.values, prior=table)
    from_vector = consistent_parameters(base, base.values, prior=table.ravel())
    expected = from_model.parameters.to_numpy()
    np.testing.assert_array_equal(from_table.parameters.to_numpy(), expected)
    np.testing.assert_array_equal(from_vector.parameters.to_numpy(), expected)


def test_zero_prior_weight() -> None:
    """Without a prior term the start (the prior) still selects the solution found."""
    true = sl.robots.load("planar2")
    base = grouping("planar2")
    fit = consistent_parameters(
        base, base.values, prior=perturb(true, relative=0.3, seed=5), prior_weight=0.0
    )
    assert fit.success, fit.message
    assert is_physically_consistent(fit.robot)
    assert_same_dynamics(fit.robot, true)


# --------------------------------------------------------------------------- declared zeros
def test_table_2_5_zeros_are_exact() -> None:
    """XY = XZ = mX = 0 on every link (blocks of the factor) and no armature."""
    true = lwr_robot(seed=7)
    base = grouping("lwr", SYMMETRIC_ZERO)
    fit = consistent_parameters(base, base.values_of(true), prior=perturb(true, 0.3, seed=8))
    assert fit.success, fit.message
    assert is_physically_consistent(fit.robot)
    values = values_by_name(fit)
    robot_values = dict(zip(fit.robot.parameter_names(), fit.robot.parameter_vector(), strict=True))
    for name in SYMMETRIC_ZERO:
        assert values[name] == 0.0, name
        assert abs(robot_values[name]) <= 1e-9, name
    assert_same_dynamics(fit.robot, true)


def test_zero_that_needs_the_penalty() -> None:
    """XY alone does not split J into blocks: imposed by a residual, then set to 0."""
    true = sl.robots.load("planar2")  # rods along x: XY = 0 in the true model
    zero = ("XY1", "XY2")
    base = grouping("planar2", zero)
    fit = consistent_parameters(base, base.values_of(true), prior=perturb(true, 0.3, seed=9))
    assert fit.success, fit.message
    assert (fit.parameters["XY"] == 0.0).all()
    assert np.abs(fit.robot.standard_parameters()["XY"]).max() <= 1e-9
    assert physically_consistent_links(fit.robot).all()
    assert_same_dynamics(fit.robot, true)


def test_link_with_a_lone_moment_becomes_empty() -> None:
    """Table 2.5 link 1 (only ZZ1) is a rigid body only if ZZ1 = 0: J1 = 0, ZZ1 goes to YY2."""
    true = lwr_robot(seed=11)
    base = grouping("lwr", SYMMETRIC_ZERO + LINK1_ZERO)
    assert base.count == 25
    fit = consistent_parameters(base, base.values_of(true), prior=perturb(true, 0.3, seed=12))
    assert fit.success, fit.message
    assert is_physically_consistent(fit.robot)
    assert (fit.parameters.loc["link1"] == 0.0).all()
    assert fit.min_eigenvalue[0] == 0.0
    assert np.all(fit.min_eigenvalue[1:] >= (1 - 1e-2) * MARGIN)
    assert_same_dynamics(fit.robot, true)


@pytest.mark.parametrize("zero", [SYMMETRIC_ZERO, SYMMETRIC_ZERO + LINK1_ZERO])
def test_thesis_table_2_7(zero: tuple[str, ...]) -> None:
    """The 25 published LWR base parameters (1.2e-4 ... 3.5) from a random prior.

    Independent check: the base regressor of Table 2.6 times θ (Y_b θ) equals
    Pinocchio's RNEA of the retrieved model.
    """
    prior = lwr_robot(seed=13)
    base = grouping("lwr", zero)
    assert sorted(base.names) == sorted(TABLE_2_7)
    theta = np.array([TABLE_2_7[name] for name in base.names])
    fit = consistent_parameters(base, theta, prior=prior)
    assert fit.success, fit.message
    assert is_physically_consistent(fit.robot)
    assert np.all(np.abs(fit.residual) <= 1e-8 * np.maximum(np.abs(theta), 3.5e-6))
    q, qd, qdd = random_states(7, 14)
    np.testing.assert_allclose(
        fit.robot.inverse_dynamics(q, qd, qdd),
        base.regressor(q, qd, qdd) @ theta,
        rtol=0,
        atol=1e-9 * 3.5 * 9.81,
    )
    values = values_by_name(fit)
    assert all(values[name] == 0.0 for name in zero)


# --------------------------------------------------------------------------- infeasible
def test_infeasible_target_is_reported() -> None:
    """Negative ZZ1R = ZZ1 + Ia1 + l1² m2 and ZZ2 need a negative inertia or mass."""
    base = grouping("planar2")
    theta = base.values.copy()
    for name in ("ZZ1R", "ZZ2"):
        theta[base.names.index(name)] *= -1.0
    fit = consistent_parameters(base, theta, max_evaluations=300)
    assert not fit.success
    assert fit.n_evaluations <= 300
    assert is_physically_consistent(fit.robot)  # the output is still a set of rigid bodies
    assert "could not reproduce" in fit.message
    worst = fit.message.split("worst: ")[1]
    assert worst.index("ZZ2") < worst.index("mX1R") and "ZZ1R" in worst
    table = fit.to_pandas()
    assert table.loc["ZZ2", "reproduced"] > 0 > table.loc["ZZ2", "target"]
    assert abs(table.loc["ZZ2", "scaled_residual"]) > 0.5


# --------------------------------------------------------------------------- result object
def test_result_table_and_residuals() -> None:
    true = sl.robots.load("planar2")
    base = grouping("planar2")
    fit = consistent_parameters(base, base.values, prior=perturb(true, 0.3, seed=15))
    table = fit.to_pandas()
    assert list(table.index) == base.names
    assert table.index.name == "base parameter"
    assert list(table.columns) == ["target", "reproduced", "residual", "scaled_residual"]
    np.testing.assert_array_equal(table["residual"], fit.reproduced - fit.target)
    np.testing.assert_array_equal(fit.reproduced, base.values_of(fit.parameters.to_numpy().ravel()))
    assert fit.relative_residual == pytest.approx(
        np.linalg.norm(fit.residual) / np.linalg.norm(fit.target), rel=1e-12, abs=1e-300
    )
    reference = fit.robot.standard_parameters()
    assert list(fit.parameters.columns) == list(reference.columns)
    assert list(fit.parameters.index) == list(reference.index)
    np.testing.assert_allclose(fit.parameters, reference, rtol=0, atol=1e-12)
    np.testing.assert_allclose(
        fit.min_eigenvalue,
        np.linalg.eigvalsh(pseudo_inertia(fit.robot))[:, 0],
        rtol=0,
        atol=1e-12,
    )
    with pytest.raises(AttributeError):
        fit.success = False  # type: ignore[misc]


def test_jacobian_matches_finite_differences() -> None:
    """dπ/dx of the factor parameterisation, with blocks and dead coordinates."""
    zero = {"XY2", "XZ2", "mX2", "XX3", "Ia1", "XY4"}
    layout = Layout.build(4, zero, MARGIN)
    x = np.random.default_rng(16).standard_normal(layout.n_variables) * 0.5
    step = 1e-6
    numeric = np.stack(
        [
            (layout.parameters(x + step * e) - layout.parameters(x - step * e)) / (2 * step)
            for e in np.eye(layout.n_variables)
        ],
        axis=1,
    )
    np.testing.assert_allclose(layout.jacobian(x), numeric, rtol=0, atol=1e-7)
    per_link = layout.parameters(x).reshape(4, 11)
    assert physically_consistent_links(per_link).all()
    # Link 3 has XX3 = 0: J keeps only x and the homogeneous coordinate (a rod along x).
    assert per_link[2, 0] == 0.0 and per_link[2, 7] == 0.0 and per_link[2, 8] == 0.0
    assert layout.penalised == (3 * 11 + 1,)  # XY4 needs the penalty


def test_module_doctest() -> None:
    result = doctest.testmod(consistent_module)
    assert result.attempted > 0 and result.failed == 0


# --------------------------------------------------------------------------- validation
@pytest.fixture(scope="module")
def planar_base() -> sl.BaseParameters:
    return grouping("planar2")


def test_theta_of_wrong_length(planar_base: sl.BaseParameters) -> None:
    with pytest.raises(
        DimensionError,
        match=r"theta must have shape \(7,\), one value per base parameter \['ZZ1R', 'mX1R'.*"
        r"got shape \(6,\)",
    ):
        consistent_parameters(planar_base, planar_base.values[:6])
    with pytest.raises(DimensionError, match=r"theta must be 7 numbers.*could not convert"):
        consistent_parameters(planar_base, ["a"] * 7)


@pytest.mark.parametrize("bad", [np.nan, np.inf])
def test_theta_not_finite(planar_base: sl.BaseParameters, bad: float) -> None:
    theta = planar_base.values.copy()
    theta[3] = bad
    with pytest.raises(
        InputValueError, match=rf"theta must be finite; found {bad} at index 3 \(ZZ2\), 1 non"
    ):
        consistent_parameters(planar_base, theta)


def test_prior_of_another_robot(planar_base: sl.BaseParameters) -> None:
    with pytest.raises(
        DimensionError, match=r"prior must be a model with 2 joints .* 'puma560' with 6 joints"
    ):
        consistent_parameters(planar_base, planar_base.values, prior=sl.robots.load("puma560"))
    with pytest.raises(
        DimensionError,
        match=r"prior standard parameters must have shape \(22,\) or \(2, 11\) .* "
        r"got shape \(33,\)",
    ):
        consistent_parameters(planar_base, planar_base.values, prior=np.zeros(33))
    with pytest.raises(
        InputValueError, match=r"prior standard parameters must be finite; .* index 0 \(XX1\), 22"
    ):
        consistent_parameters(planar_base, planar_base.values, prior=np.full(22, np.nan))


@pytest.mark.parametrize(
    ("keyword", "value", "message"),
    [
        ("prior_weight", -1.0, r"prior_weight must be finite and >= 0 .*got -1.0"),
        ("prior_weight", np.nan, r"prior_weight must be finite and >= 0 .*got nan"),
        ("prior_weight", "big", r"prior_weight must be a real number >= 0 .*got 'big'"),
        ("margin", -1e-6, r"margin must be finite and >= 0 .*got -1e-06"),
        ("tolerance", 0.0, r"tolerance must be finite and > 0 .*got 0.0"),
        ("max_evaluations", 0, r"max_evaluations must be a positive integer; got 0"),
        ("max_evaluations", 10.5, r"max_evaluations must be a positive integer; got 10.5"),
    ],
)
def test_bad_settings(
    planar_base: sl.BaseParameters, keyword: str, value: object, message: str
) -> None:
    with pytest.raises(InputValueError, match=message):
        consistent_parameters(planar_base, planar_base.values, **{keyword: value})  # type: ignore[arg-type]


def test_bad_base_and_unknown_keyword(planar_base: sl.BaseParameters) -> None:
    with pytest.raises(InputTypeError, match=r"base must be BaseParameters .* got RobotModel"):
        consistent_parameters(sl.robots.load("planar2"), planar_base.values)  # type: ignore[arg-type]
    with pytest.raises(TypeError, match="weight"):
        consistent_parameters(planar_base, planar_base.values, weight=1.0)  # type: ignore[call-arg]
