"""Tests of :mod:`sensorless.identification.matrices` (thesis eq. 2.14–2.15).

Independent facts: the mass matrix and gravity torque of Pinocchio (CRBA and
RNEA), the textbook closed form of the planar two-link arm, the regression on
the full inverse-dynamics regressor, and the coverage of Student-t intervals.
"""

from __future__ import annotations

import numpy as np
import pytest

import sensorless as sl
from sensorless.exceptions import DimensionError, InputTypeError, InputValueError
from sensorless.identification.matrices import (
    contributing_terms,
    identify_from_matrices,
    matrix_regressors,
)
from sensorless.identification.regression import identify_base_parameters

GRAVITY = 9.81


def random_q(n_dof: int, n: int, seed: int) -> np.ndarray:
    return np.random.default_rng(seed).uniform(-np.pi, np.pi, (n, n_dof))


@pytest.fixture(scope="module")
def planar2() -> sl.RobotModel:
    return sl.robots.load("planar2")


@pytest.fixture(scope="module")
def planar2_base(planar2: sl.RobotModel) -> sl.BaseParameters:
    return sl.base_parameters(planar2)


def planar2_closed_form(q: np.ndarray, l1: float = 1.0) -> tuple[np.ndarray, np.ndarray]:
    """Y_M and Y_g of the planar arm in the base parameters ZZ1R, mX1R, mY1, ZZ2, mX2, mY2, Ia2.

    M11 = ZZ1R + ZZ2 + 2 l1 (mX2 c2 − mY2 s2), M12 = ZZ2 + l1 (mX2 c2 − mY2 s2),
    M22 = ZZ2 + Ia2; with gravity along −y,
    g1 = g0 (mX1R c1 − mY1 s1 + mX2 c12 − mY2 s12), g2 = g0 (mX2 c12 − mY2 s12).
    """
    c1, s1 = np.cos(q[:, 0]), np.sin(q[:, 0])
    c2, s2 = np.cos(q[:, 1]), np.sin(q[:, 1])
    c12, s12 = np.cos(q.sum(axis=1)), np.sin(q.sum(axis=1))
    zero, one = np.zeros_like(c1), np.ones_like(c1)
    # Columns: ZZ1R, mX1R, mY1, ZZ2, mX2, mY2, Ia2.
    m1 = [  # column 1 of M: rows (M11, M21)
        [one, zero, zero, one, 2 * l1 * c2, -2 * l1 * s2, zero],
        [zero, zero, zero, one, l1 * c2, -l1 * s2, zero],
    ]
    m2 = [  # column 2 of M: rows (M12, M22)
        [zero, zero, zero, one, l1 * c2, -l1 * s2, zero],
        [zero, zero, zero, one, zero, zero, one],
    ]
    g = [
        [zero, c1, -s1, zero, c12, -s12, zero],
        [zero, zero, zero, zero, c12, -s12, zero],
    ]
    y_m = np.stack([np.array(m1), np.array(m2)])  # (column, row, parameter, sample)
    y_g = GRAVITY * np.array(g)
    return np.moveaxis(y_m, -1, 0), np.moveaxis(y_g, -1, 0)


# ---------------------------------------------------------------------- regressors


def test_planar2_regressors_match_closed_form(planar2_base: sl.BaseParameters) -> None:
    assert planar2_base.names == ["ZZ1R", "mX1R", "mY1", "ZZ2", "mX2", "mY2", "Ia2"]
    q = random_q(2, 25, 0)
    y_m, y_g = matrix_regressors(planar2_base, q)
    want_m, want_g = planar2_closed_form(q)
    assert y_m.shape == (25, 2, 2, 7)
    assert y_g.shape == (25, 2, 7)
    np.testing.assert_allclose(y_m, want_m, rtol=0, atol=1e-12)
    np.testing.assert_allclose(y_g, want_g, rtol=0, atol=1e-12)


@pytest.mark.parametrize("name", ["planar2", "puma560", "panda_gaz"])
def test_regressors_reproduce_mass_matrix_and_gravity(name: str) -> None:
    """M_i(q) = Y_{M_i}(q) θ column by column (2.15) and g(q) = Y_g(q) θ (2.14a)."""
    robot = sl.robots.load(name)
    base = sl.base_parameters(robot)
    q = random_q(robot.n_dof, 20, 1)
    y_m, y_g = matrix_regressors(base, q)
    mass = robot.mass_matrix(q)
    scale = np.abs(mass).max()
    for i in range(robot.n_dof):
        np.testing.assert_allclose(y_m[:, i] @ base.values, mass[:, :, i], atol=1e-12 * scale)
    gravity = robot.gravity(q)
    np.testing.assert_allclose(y_g @ base.values, gravity, atol=1e-12 * np.abs(gravity).max())


def test_single_configuration_drops_the_sample_axis(planar2_base: sl.BaseParameters) -> None:
    q = random_q(2, 3, 2)
    y_m, y_g = matrix_regressors(planar2_base, q)
    one_m, one_g = matrix_regressors(planar2_base, q[1])
    assert one_m.shape == (2, 2, 7) and one_g.shape == (2, 7)
    np.testing.assert_array_equal(one_m, y_m[1])
    np.testing.assert_array_equal(one_g, y_g[1])


# ---------------------------------------------------------------------- identification


@pytest.mark.parametrize("name", ["puma560", "panda_gaz"])
def test_noise_free_recovery(name: str) -> None:
    robot = sl.robots.load(name)
    q = random_q(robot.n_dof, 40, 3)
    base, result = identify_from_matrices(robot, q, robot.mass_matrix(q), robot.gravity(q))
    truth = base.values
    atol = 1e-6 * np.abs(truth).max()
    np.testing.assert_allclose(result.estimates, truth, rtol=1e-6, atol=atol)
    assert result.names == base.names
    assert result.r_squared == pytest.approx(1.0, abs=1e-12)
    # The same base parameters from the full inverse-dynamics regressor, eq. (2.12).
    rng = np.random.default_rng(4)
    qd, qdd = rng.standard_normal(q.shape), rng.standard_normal(q.shape)
    tau = robot.inverse_dynamics(q, qd, qdd)
    _, full = identify_base_parameters(robot, q, qd, qdd, tau, friction=None)
    np.testing.assert_allclose(result.estimates, full.estimates, rtol=1e-6, atol=atol)


def test_exact_data_t_statistics_separate_zero_parameters(planar2: sl.RobotModel) -> None:
    """Exact data: finite t; huge for acting parameters, O(1) for the zero ones (Table 2.7)."""
    q = random_q(2, 50, 5)
    base, result = identify_from_matrices(planar2, q, planar2.mass_matrix(q), planar2.gravity(q))
    zero = base.values == 0.0
    assert [name for name, z in zip(base.names, zero, strict=True) if z] == ["mY1", "mY2", "Ia2"]
    assert np.isfinite(result.t_values).all()
    assert (np.abs(result.t_values[~zero]) > 1e10).all()
    assert (np.abs(result.t_values[zero]) < 1e4).all()
    assert 0.0 < result.residual_std < 1e-12
    assert result.rss == pytest.approx(result.residual_std**2 * (result.n_samples - base.count))


def noisy_planar2(
    robot: sl.RobotModel, q: np.ndarray, sigma: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """M and g with Gaussian noise of std sigma on every used entry; M kept symmetric."""
    noise = sigma * rng.standard_normal((q.shape[0], 2, 2))
    noise = np.triu(noise) + np.swapaxes(np.triu(noise, 1), 1, 2)
    gravity = robot.gravity(q) + sigma * rng.standard_normal(q.shape)
    return robot.mass_matrix(q) + noise, gravity


def test_confidence_interval_coverage(
    planar2: sl.RobotModel, planar2_base: sl.BaseParameters
) -> None:
    """95 % intervals hold the true values in 95 % of 200 seeded trials."""
    rng = np.random.default_rng(6)
    truth = planar2_base.values
    inside = []
    for _ in range(200):
        q = rng.uniform(-np.pi, np.pi, (12, 2))
        mass, gravity = noisy_planar2(planar2, q, 0.05, rng)
        _, result = identify_from_matrices(planar2_base, q, mass, gravity)
        inside.append((result.ci_lower <= truth) & (truth <= result.ci_upper))
    # 1400 indicator values; binomial sd sqrt(0.95·0.05/1400) ≈ 0.006, and the
    # 7 intervals of one trial are correlated: allow ±0.025 (about 4 sd).
    coverage = float(np.mean(inside))
    assert 0.925 <= coverage <= 0.975


def test_pooled_segments_equal_one_segment(
    planar2: sl.RobotModel, planar2_base: sl.BaseParameters
) -> None:
    rng = np.random.default_rng(7)
    q = rng.uniform(-np.pi, np.pi, (103, 2))
    mass, gravity = noisy_planar2(planar2, q, 0.01, rng)
    _, whole = identify_from_matrices(planar2_base, q, mass, gravity, segment=10_000)
    _, pooled = identify_from_matrices(planar2_base, q, mass, gravity, segment=7)
    for field in ("estimates", "std_errors", "t_values", "ci_lower", "ci_upper", "covariance"):
        got, want = getattr(pooled, field), getattr(whole, field)
        np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9 * np.abs(want).max())
    assert pooled.rss == pytest.approx(whole.rss, rel=1e-9)
    assert pooled.n_samples == whole.n_samples == 103 * (2 + 3)
    # Exact data: the estimates agree too.
    exact = planar2.mass_matrix(q), planar2.gravity(q)
    _, whole = identify_from_matrices(planar2_base, q, *exact, segment=10_000)
    _, pooled = identify_from_matrices(planar2_base, q, *exact, segment=7)
    np.testing.assert_allclose(pooled.estimates, whole.estimates, rtol=0, atol=1e-9)


def test_order_of_use_does_not_matter(
    planar2: sl.RobotModel, planar2_base: sl.BaseParameters
) -> None:
    q = random_q(2, 30, 8)
    data = planar2.mass_matrix(q), planar2.gravity(q)
    _, forward = identify_from_matrices(planar2_base, q, *data, use=("M", "g"))
    _, backward = identify_from_matrices(planar2_base, q, *data, use=["g", "M"])
    np.testing.assert_allclose(forward.estimates, backward.estimates, atol=1e-12)


@pytest.mark.parametrize(
    ("use", "missing"), [("g", r"\['ZZ1R', 'ZZ2', 'Ia2'\]"), ("M", r"\['mX1R', 'mY1'\]")]
)
def test_one_term_alone_misses_the_other_terms_parameters(
    planar2: sl.RobotModel, planar2_base: sl.BaseParameters, use: str, missing: str
) -> None:
    """g alone does not see inertias, M alone not the first moments of link 1."""
    q = random_q(2, 30, 9)
    with pytest.raises(InputValueError, match=f"rank-deficient.*{missing}"):
        identify_from_matrices(planar2_base, q, planar2.mass_matrix(q), planar2.gravity(q), use=use)


def test_zero_parameters_are_passed_on(planar2: sl.RobotModel) -> None:
    q = random_q(2, 30, 10)
    base, result = identify_from_matrices(
        planar2, q, planar2.mass_matrix(q), planar2.gravity(q), zero=["mY1", "mY2"]
    )
    assert base.zero == ("mY1", "mY2")
    assert "mY1" not in result.names and len(result.names) == 5


# ---------------------------------------------------------------------- contributing terms


def test_contributing_terms_planar2_closed_form(planar2_base: sl.BaseParameters) -> None:
    q = random_q(2, 30, 11)
    table = contributing_terms(planar2_base, q)
    want_m, want_g = planar2_closed_form(q)
    expected = np.column_stack(
        [np.abs(want_g).max(axis=(0, 1)) > 0]
        + [np.abs(want_m[:, i]).max(axis=(0, 1)) > 0 for i in range(2)]
    )
    assert list(table.columns) == ["Y_g", "Y_M1", "Y_M2"]
    assert list(table.index) == planar2_base.names
    assert table.dtypes.eq(bool).all()
    np.testing.assert_array_equal(table.to_numpy(), expected)
    # Spelled out: first moments of link 1 act through gravity only, inertias never do.
    assert table.loc["mX1R"].tolist() == [True, False, False]
    assert table.loc["mY1"].tolist() == [True, False, False]
    assert table.loc["ZZ1R"].tolist() == [False, True, False]
    assert table.loc["Ia2"].tolist() == [False, False, True]
    assert table.loc["mX2"].tolist() == [True, True, True]


def test_contributing_terms_puma() -> None:
    robot = sl.robots.load("puma560")
    base = sl.base_parameters(robot)
    q = random_q(6, 40, 12)
    table = contributing_terms(base, q, segment=7)
    # Like θ1 of Table 2.7: first moments of link 2 that act through gravity only
    # (their inertial effects are regrouped into XX2R, ZZ2R...), and ZZ1R, the
    # inertia about the vertical first axis, in the first column of M only.
    assert table.loc["mX2R"].tolist() == [True] + [False] * 6
    assert table.loc["mY2"].tolist() == [True] + [False] * 6
    assert table.loc["ZZ1R"].tolist() == [False, True] + [False] * 5
    # Armatures act on their own column of M only.
    for j in range(3, 7):
        assert table.loc[f"Ia{j}"].tolist() == [False] + [i == j for i in range(1, 7)]
    # Consistent with the regressors: a False term has a (numerically) zero column.
    y_m, y_g = matrix_regressors(base, q)
    peaks = np.vstack([np.abs(y_g).max(axis=(0, 1)), np.abs(y_m).max(axis=(0, 2))])
    assert (peaks.T[~table.to_numpy()] < 1e-12).all()


# ---------------------------------------------------------------------- validation


def valid_inputs(robot: sl.RobotModel, n: int = 10) -> dict[str, np.ndarray]:
    q = random_q(robot.n_dof, n, 13)
    return {"q": q, "mass_matrix": robot.mass_matrix(q), "gravity": robot.gravity(q)}


def _with(data: dict[str, np.ndarray], name: str, index: tuple[int, ...], value: float):
    arr = data[name].copy()
    arr[index] = value
    return {**data, name: arr}


@pytest.mark.parametrize(
    ("change", "error", "match"),
    [
        (lambda d: {**d, "q": d["q"][:, :1]}, DimensionError, r"q must have shape \(2,\)"),
        (
            lambda d: {**d, "mass_matrix": d["mass_matrix"][:5]},
            DimensionError,
            r"mass_matrix must have shape .*\(10, 2, 2\).*got shape \(5, 2, 2\)",
        ),
        (
            lambda d: {**d, "mass_matrix": d["mass_matrix"][:, :1]},
            DimensionError,
            r"mass_matrix must have shape",
        ),
        (
            lambda d: {**d, "gravity": d["gravity"][:4]},
            DimensionError,
            r"gravity must have as many samples as q \(10\); got shape \(4, 2\)",
        ),
        (
            lambda d: {**d, "gravity": d["gravity"][:, :1]},
            DimensionError,
            r"gravity must have shape \(2,\)",
        ),
        (lambda d: _with(d, "q", (3, 1), np.nan), InputValueError, "q must be finite"),
        (
            lambda d: _with(d, "mass_matrix", (2, 0, 0), np.inf),
            InputValueError,
            "mass_matrix must be finite",
        ),
        (lambda d: _with(d, "gravity", (1, 1), np.nan), InputValueError, "gravity must be finite"),
        (
            lambda d: _with(d, "mass_matrix", (4, 0, 1), 5.0),
            InputValueError,
            r"symmetric.*sample 4 has M\[(0, 1|1, 0)\]",
        ),
        (
            lambda d: {key: value[:1] for key, value in d.items()},
            InputValueError,
            r"too few samples.*at least 2 configurations of 5 equations.*got 1",
        ),
        (
            lambda d: {key: np.repeat(value[:1], 10, axis=0) for key, value in d.items()},
            InputValueError,
            r"rank-deficient data: rank \d < 7",
        ),
        (lambda d: {**d, "mass_matrix": None}, InputValueError, "mass_matrix is None but use"),
        (lambda d: {**d, "gravity": None}, InputValueError, "gravity is None but use"),
    ],
)
def test_identify_rejects_bad_data(planar2_base, change, error, match) -> None:
    data = change(valid_inputs(planar2_base.robot))
    with pytest.raises(error, match=match):
        identify_from_matrices(planar2_base, data["q"], data["mass_matrix"], data["gravity"])


def test_unused_term_may_be_none(planar2: sl.RobotModel) -> None:
    """The None check only concerns the terms in use (g alone is rank-deficient here)."""
    data = valid_inputs(planar2)
    with pytest.raises(InputValueError, match="rank-deficient"):
        identify_from_matrices(planar2, data["q"], None, data["gravity"], use="g")


@pytest.mark.parametrize(
    ("options", "error", "match"),
    [
        ({"use": "x"}, InputValueError, r"use must be .*\['M', 'g'\]; got \('x',\)"),
        ({"use": ()}, InputValueError, "use must be a non-empty"),
        ({"use": ("g", "g")}, InputValueError, "without repeats"),
        ({"segment": 0}, InputValueError, "segment must be a positive integer"),
        ({"segment": 2.5}, InputValueError, "segment must be a positive integer"),
        ({"level": 1.0}, InputValueError, r"level must lie in \(0, 1\)"),
        ({"symmetry_tolerance": -1.0}, InputValueError, "symmetry_tolerance must be"),
        ({"zero": ["mY1"]}, InputValueError, "applies only when a RobotModel is given"),
    ],
)
def test_identify_rejects_bad_options(planar2_base, options, error, match) -> None:
    data = valid_inputs(planar2_base.robot)
    with pytest.raises(error, match=match):
        identify_from_matrices(
            planar2_base, data["q"], data["mass_matrix"], data["gravity"], **options
        )


def test_identify_rejects_a_non_robot(planar2: sl.RobotModel) -> None:
    data = valid_inputs(planar2)
    with pytest.raises(InputTypeError, match="RobotModel or a BaseParameters; got str"):
        identify_from_matrices("planar2", data["q"], data["mass_matrix"], data["gravity"])  # type: ignore[arg-type]


def test_symmetry_tolerance_accepts_round_off(planar2: sl.RobotModel) -> None:
    data = valid_inputs(planar2, 20)
    mass = data["mass_matrix"].astype(np.float32).astype(float)
    mass[:, 0, 1] *= 1 + 1e-7
    _, result = identify_from_matrices(planar2, data["q"], mass, data["gravity"])
    assert result.estimates.shape == (7,)


@pytest.mark.parametrize(
    ("call", "error", "match"),
    [
        (lambda b: matrix_regressors("base", [0.0, 0.0]), InputTypeError, "BaseParameters"),
        (lambda b: matrix_regressors(b, [0.0, 0.0, 0.0]), DimensionError, r"q must have shape"),
        (lambda b: contributing_terms(b, [[0.0, np.nan]]), InputValueError, "q must be finite"),
        (
            lambda b: contributing_terms(b, [[0.0, 0.0]], tolerance=1.0),
            InputValueError,
            r"tolerance must lie in \[0, 1\)",
        ),
        (
            lambda b: contributing_terms(b, [[0.0, 0.0]], segment=-1),
            InputValueError,
            "segment must be a positive integer",
        ),
    ],
)
def test_regressor_functions_reject_bad_input(planar2_base, call, error, match) -> None:
    with pytest.raises(error, match=match):
        call(planar2_base)
