"""Tests of :mod:`sensorless.robots.base_parameters`.

The counts are the published ones (Gautier & Khalil 1990 for the PUMA 560,
Gaz et al. 2019 for the Panda), the groupings are those of thesis Table 2.6
for the KUKA LWR table of Table 2.4, written out by hand below, and the
regrouped model is checked against the full one through inverse dynamics.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import sensorless as sl
from sensorless.exceptions import InputValueError, UnknownNameError

N_STATES = 5


@pytest.fixture(scope="module", params=sl.robots.available())
def robot(request: pytest.FixtureRequest) -> sl.RobotModel:
    return sl.robots.load(request.param)


def random_states(
    n_dof: int, seed: int, n: int = N_STATES
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """q uniform within ±2 rad, q̇ and q̈ standard normal."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(-2.0, 2.0, (n, n_dof))
    return q, rng.standard_normal((n, n_dof)), rng.standard_normal((n, n_dof))


def assert_close(actual: np.ndarray, desired: np.ndarray, rel: float = 1e-9) -> None:
    scale = max(1.0, float(np.max(np.abs(desired))))
    np.testing.assert_allclose(actual, desired, rtol=0, atol=rel * scale)


def armature_names(n_dof: int) -> list[str]:
    return [f"Ia{i}" for i in range(1, n_dof + 1)]


# --------------------------------------------------------------------------- every robot
def test_base_regressor_reproduces_inverse_dynamics(robot: sl.RobotModel) -> None:
    bp = sl.base_parameters(robot)
    q, qd, qdd = random_states(robot.n_dof, 0)
    tau = bp.regressor(q, qd, qdd) @ bp.values
    assert bp.regressor(q, qd, qdd).shape == (N_STATES, robot.n_dof, bp.count)
    assert_close(tau, robot.inverse_dynamics(q, qd, qdd))


def test_base_values_of_any_parameter_vector(robot: sl.RobotModel) -> None:
    """The grouping depends on the kinematics only: Y π = Y_b θ(π) for any π."""
    bp = sl.base_parameters(robot)
    rng = np.random.default_rng(1)
    pi = rng.standard_normal(robot.n_dof * 11)
    q, qd, qdd = random_states(robot.n_dof, 2)
    np.testing.assert_allclose(bp.values_of(pi), bp.combinations.to_numpy() @ pi)
    assert_close(bp.regressor(q, qd, qdd) @ bp.values_of(pi), robot.regressor(q, qd, qdd) @ pi)
    np.testing.assert_array_equal(bp.values, bp.values_of(robot.parameter_vector()))


@pytest.mark.parametrize(
    ("analysed", "other", "options", "same_values"),
    [
        ("planar2", "planar2", {"masses": (2.0, 3.0), "com_ratio": 0.3}, False),
        # Their standard parameters differ only in link-1 terms of no dynamic effect.
        ("panda", "panda_gaz", {}, True),
    ],
)
def test_base_values_of_another_model(
    analysed: str, other: str, options: dict, same_values: bool
) -> None:
    """Base values of a model with the same kinematics give that model's dynamics."""
    bp = sl.base_parameters(sl.robots.load(analysed))
    model = sl.robots.load(other, **options)
    q, qd, qdd = random_states(model.n_dof, 3)
    assert_close(bp.regressor(q, qd, qdd) @ bp.values_of(model), model.inverse_dynamics(q, qd, qdd))
    assert np.allclose(bp.values_of(model), bp.values, rtol=0, atol=1e-12) == same_values


def test_combinations_table_shape_and_names(robot: sl.RobotModel) -> None:
    bp = sl.base_parameters(robot)
    names = robot.parameter_names()
    assert list(bp.combinations.columns) == names
    assert list(bp.combinations.index) == bp.names
    assert bp.count == len(bp.names) == bp.independent.size
    # Each base parameter is built on its own standard parameter with coefficient 1.
    combos = bp.combinations.to_numpy()
    np.testing.assert_array_equal(combos[np.arange(bp.count), bp.independent], 1.0)
    np.testing.assert_array_equal(combos[:, bp.independent], np.eye(bp.count))
    for name, k in zip(bp.names, bp.independent, strict=True):
        assert name.removesuffix("R") == names[k]
        assert name.endswith("R") == (np.count_nonzero(combos[list(bp.names).index(name)]) > 1)
    table = bp.to_pandas()
    assert list(table.columns) == ["formula", "value"]
    np.testing.assert_allclose(table["value"], bp.values)


def test_count_is_the_rank_of_the_observation_matrix(robot: sl.RobotModel) -> None:
    """Independent of the library's QR: the rank of stacked regressors by SVD."""
    q, qd, qdd = random_states(robot.n_dof, 3, n=60)
    stacked = robot.regressor(q, qd, qdd).reshape(-1, robot.n_dof * 11)
    singular = np.linalg.svd(stacked, compute_uv=False)
    rank = int((singular > 1e-9 * singular[0]).sum())
    assert sl.base_parameters(robot).count == rank


# --------------------------------------------------------------------------- published counts
def test_puma560_counts() -> None:
    puma = sl.robots.load("puma560")
    without_rotors = sl.base_parameters(puma, zero=armature_names(6))
    # Gautier & Khalil 1990: 36 base parameters out of the 60 standard ones.
    assert without_rotors.count == 36
    with_rotors = sl.base_parameters(puma)
    # Ia1 and Ia2 act on q̈1, q̈2 only, exactly as ZZ1 and ZZ2 (axis 2 ⊥ axis 1), so
    # they are regrouped; Ia3..Ia6 add four: 36 + 4.
    assert with_rotors.count == 40
    zz1r = with_rotors.combinations.loc["ZZ1R"]
    assert zz1r["Ia1"] == pytest.approx(1.0)
    for bp in (without_rotors, with_rotors):
        kept, dropped = bp.singular_gap
        assert dropped == 0.0 or kept / dropped > 1e6


def test_panda_count_without_armature() -> None:
    """Gaz et al. 2019: 43 base parameters for the 7-DoF Panda."""
    for name in ("panda", "panda_gaz"):
        bp = sl.base_parameters(sl.robots.load(name), zero=armature_names(7))
        assert bp.count == 43
        kept, dropped = bp.singular_gap
        assert kept / dropped > 1e6


def test_planar2_closed_form_grouping() -> None:
    """Two-link planar arm: ZZ1R = ZZ1 + Ia1 + l1² m2 and mX1R = mX1 + l1 m2."""
    robot = sl.robots.load("planar2", lengths=(0.5, 1.0))
    bp = sl.base_parameters(robot)
    assert bp.count == 7
    assert bp.formula("ZZ1R") == "ZZ1 + Ia1 + 0.25 m2"
    assert bp.formula("mX1R") == "mX1 + 0.5 m2"
    assert bp.formula("ZZ2") == "ZZ2"
    # The values: ZZ1 = m l²/3 of a rod about its end, mX1 = m l/2.
    values = dict(zip(bp.names, bp.values, strict=True))
    assert values["ZZ1R"] == pytest.approx(0.25 / 3 + 0.25)
    assert values["mX1R"] == pytest.approx(0.25 + 0.5)


def test_formula_signs_and_digits() -> None:
    """Table 2.6 θ3 = mY4 − mZ5 − l5(m5 + m6 + m7), printed with its signs."""
    bp = sl.base_parameters(lwr_robot(), zero=TABLE_2_5_ZERO)
    assert bp.formula("mY4R") == "mY4 - mZ5 - 0.39 m5 - 0.39 m6 - 0.39 m7"
    assert bp.formula("mY4R", digits=1) == "mY4 - mZ5 - 0.4 m5 - 0.4 m6 - 0.4 m7"
    with pytest.raises(UnknownNameError, match=r"unknown base parameter 'θ1'; options: \['ZZ1R'"):
        bp.formula("θ1")


# --------------------------------------------------------------------------- thesis Tables 2.4-2.6
L3, L5 = 0.4, 0.39
TABLE_2_4_ALPHA_DEG = [0, 90, -90, -90, 90, 90, -90]
TABLE_2_4_D = [0.0, 0.0, L3, 0.0, L5, 0.0, 0.0]
# Table 2.5: link 1 has only ZZ1; links 2-7 have no XY, XZ, mX; no rotor inertias.
TABLE_2_5_ZERO = (
    [f"{p}1" for p in ("XX", "XY", "XZ", "YY", "YZ", "mX", "mY", "mZ", "m")]
    + [f"{p}{i}" for i in range(2, 8) for p in ("XY", "XZ", "mX")]
    + armature_names(7)
)


def lwr_robot() -> sl.RobotModel:
    """Table 2.4 with random inertias that respect the zero pattern of Table 2.5."""
    rng = np.random.default_rng(7)
    table = [
        {"alpha": math.radians(al), "a": 0.0, "theta": 0.0, "d": d}
        for al, d in zip(TABLE_2_4_ALPHA_DEG, TABLE_2_4_D, strict=True)
    ]
    # Link 1: a massless rotor, one moment about its axis (no rigid body has only one).
    links = [
        sl.LinkInertia(
            0.0, np.zeros(3), np.diag([0.0, 0.0, rng.uniform(0.1, 1.0)]), rigid_body=False
        )
    ]
    for _ in range(6):
        # COM in the y-z plane and principal axes turned about x only: XY = XZ = mX = 0.
        phi = rng.uniform(-np.pi, np.pi)
        rot = np.array(
            [
                [1.0, 0.0, 0.0],
                [0.0, math.cos(phi), -math.sin(phi)],
                [0.0, math.sin(phi), math.cos(phi)],
            ]
        )
        moments = rng.uniform(0.01, 0.1, 3)
        principal = moments.sum() - moments
        com = np.array([0.0, *rng.uniform(-0.1, 0.1, 2)])
        links.append(sl.LinkInertia(rng.uniform(1.0, 4.0), com, rot @ np.diag(principal) @ rot.T))
    return sl.RobotModel.from_mdh(table, links, name="kuka_lwr_table_2_4")


def table_2_6() -> dict[str, dict[str, float]]:
    """θ1..θ25 of thesis Table 2.6, as coefficients of the standard parameters."""
    m3_7 = {f"m{i}": L3 for i in range(3, 8)}
    m5_7 = {f"m{i}": L5 for i in range(5, 8)}
    m3_7_sq = {f"m{i}": L3**2 for i in range(3, 8)}
    m5_7_sq = {f"m{i}": L5**2 for i in range(5, 8)}
    neg_m5_7 = {k: -v for k, v in m5_7.items()}
    return {
        "θ1": {"mY2": 1, "mZ3": 1, **m3_7},
        "θ2": {"mY3": 1, "mZ4": 1},
        "θ3": {"mY4": 1, "mZ5": -1, **neg_m5_7},
        "θ4": {"mY5": 1, "mZ6": -1},
        "θ5": {"mY6": 1, "mZ7": 1},
        "θ6": {"mY7": 1},
        "θ7": {**m3_7_sq, "mZ3": 2 * L3, "XX2": 1, "YY2": -1, "YY3": 1},
        "θ8": {"XX3": 1, "YY3": -1, "YY4": 1},
        "θ9": {**m5_7_sq, "mZ5": 2 * L5, "XX4": 1, "YY4": -1, "YY5": 1},
        "θ10": {"XX5": 1, "YY5": -1, "YY6": 1},
        "θ11": {"XX6": 1, "YY6": -1, "YY7": 1},
        "θ12": {"XX7": 1, "YY7": -1},
        "θ13": {"YZ2": 1},
        "θ14": {"YZ3": 1},
        "θ15": {"YZ4": 1},
        "θ16": {"YZ5": 1},
        "θ17": {"YZ6": 1},
        "θ18": {"YZ7": 1},
        "θ19": {"YY2": 1, "ZZ1": 1},
        "θ20": {**m3_7_sq, "mZ3": 2 * L3, "YY3": 1, "ZZ2": 1},
        "θ21": {"YY4": 1, "ZZ3": 1},
        "θ22": {**m5_7_sq, "mZ5": 2 * L5, "YY5": 1, "ZZ4": 1},
        "θ23": {"YY6": 1, "ZZ5": 1},
        "θ24": {"YY7": 1, "ZZ6": 1},
        "θ25": {"ZZ7": 1},
    }


@pytest.fixture(scope="module")
def lwr() -> tuple[sl.RobotModel, sl.BaseParameters]:
    robot = lwr_robot()
    return robot, sl.base_parameters(robot, zero=TABLE_2_5_ZERO)


def test_lwr_inertias_follow_table_2_5(lwr: tuple[sl.RobotModel, sl.BaseParameters]) -> None:
    robot, _ = lwr
    values = dict(zip(robot.parameter_names(), robot.parameter_vector(), strict=True))
    for name in TABLE_2_5_ZERO:
        assert values[name] == pytest.approx(0.0, abs=1e-15), name


def test_lwr_has_25_base_parameters(lwr: tuple[sl.RobotModel, sl.BaseParameters]) -> None:
    robot, bp = lwr
    assert bp.count == 25
    assert bp.zero == tuple(TABLE_2_5_ZERO)
    kept, dropped = bp.singular_gap
    assert dropped == 0.0 or kept / dropped > 1e6
    q, qd, qdd = random_states(7, 8)
    assert_close(bp.regressor(q, qd, qdd) @ bp.values, robot.inverse_dynamics(q, qd, qdd))


@pytest.mark.parametrize("theta", list(table_2_6()))
def test_lwr_reproduces_table_2_6(lwr: tuple[sl.RobotModel, sl.BaseParameters], theta: str) -> None:
    robot, bp = lwr
    names = robot.parameter_names()
    expected = np.zeros(len(names))
    for name, coefficient in table_2_6()[theta].items():
        expected[names.index(name)] = coefficient
    rows = bp.combinations.to_numpy()
    cosine = np.abs(rows @ expected) / (np.linalg.norm(rows, axis=1) * np.linalg.norm(expected))
    assert cosine.max() > 1 - 1e-9, (theta, bp.names[int(cosine.argmax())], cosine.max())


def test_lwr_table_2_6_rows_are_distinct(lwr: tuple[sl.RobotModel, sl.BaseParameters]) -> None:
    """The 25 θ of Table 2.6 match 25 different rows: the grouping is the same basis."""
    robot, bp = lwr
    names = robot.parameter_names()
    rows = bp.combinations.to_numpy()
    rows = rows / np.linalg.norm(rows, axis=1, keepdims=True)
    matched = set()
    for formula in table_2_6().values():
        expected = np.zeros(len(names))
        for name, coefficient in formula.items():
            expected[names.index(name)] = coefficient
        matched.add(int(np.abs(rows @ expected).argmax()))
    assert len(matched) == 25


# --------------------------------------------------------------------------- options and errors
def test_result_does_not_depend_on_seed_or_sample_count() -> None:
    puma = sl.robots.load("puma560")
    reference = sl.base_parameters(puma)
    other = sl.base_parameters(puma, n_samples=30, seed=5)
    assert other.names == reference.names
    np.testing.assert_allclose(other.combinations, reference.combinations, atol=1e-8)


def test_unknown_zero_parameter() -> None:
    planar = sl.robots.load("planar2")
    with pytest.raises(
        UnknownNameError, match=r"unknown standard parameters \['ZZ9', 'zz1'\].*link number 1..2"
    ):
        sl.base_parameters(planar, zero=["ZZ1", "ZZ9", "zz1"])
    with pytest.raises(KeyError):
        sl.base_parameters(planar, zero=["ZZ9"])


def test_bad_sample_count() -> None:
    with pytest.raises(InputValueError, match="n_samples must be an integer >= 11; got 0"):
        sl.base_parameters(sl.robots.load("planar2"), n_samples=0)
