"""Tests of :mod:`sensorless.simulation.model_error`.

The perturbed models are checked from their standard parameters with
computations written here: the parallel-axis theorem back to the centre of
mass, the principal moments by an eigen-decomposition, the pseudo-inertia
matrix as the second moment of point masses, and the dynamics (inverse
dynamics, M(q) ≻ 0) through the model's own RNEA and CRBA.
"""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

import sensorless as sl
from sensorless.exceptions import DimensionError, InputValueError, ModelError, SensorlessError
from sensorless.friction import Coulomb, CoulombViscous, LuGre, Sigmoid, Stribeck
from sensorless.simulation.model_error import (
    is_physically_consistent,
    perturb,
    perturb_friction,
    perturb_inertia,
    physically_consistent_links,
    pseudo_inertia,
)

RELATIVE = 0.15
SLACK = 1e-9  # relative round-off allowed at the edges of the band
SEEDS = range(8)


@pytest.fixture(scope="module", params=["puma560", "panda_gaz"])
def robot(request: pytest.FixtureRequest) -> sl.RobotModel:
    return sl.robots.load(request.param)


@pytest.fixture(scope="module")
def puma() -> sl.RobotModel:
    return sl.robots.load("puma560")


@pytest.fixture(scope="module")
def planar() -> sl.RobotModel:
    return sl.robots.load("planar2")


def random_states(n_dof: int, seed: int, n: int = 20) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(seed)
    q = rng.uniform(-2.0, 2.0, (n, n_dof))
    return q, rng.standard_normal((n, n_dof)), rng.standard_normal((n, n_dof))


def link_data(pi: np.ndarray) -> list[tuple[float, np.ndarray, np.ndarray, float]]:
    """(mass, COM, inertia about the COM, armature) of each link from standard parameters."""
    out = []
    for row in np.asarray(pi).reshape(-1, 11):
        xx, xy, xz, yy, yz, zz, mx, my, mz, m, ia = row
        c = np.array([mx, my, mz]) / m if m > 0 else np.zeros(3)
        origin = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        # Parallel-axis theorem, from the link frame origin back to the COM.
        out.append((m, c, origin - m * (c @ c * np.eye(3) - np.outer(c, c)), ia))
    return out


def pseudo_inertia_here(pi: np.ndarray) -> np.ndarray:
    """J = [[½tr(Ī)E − Ī, h], [hᵀ, m]] per link, written independently of the module."""
    out = []
    for row in np.asarray(pi).reshape(-1, 11):
        xx, xy, xz, yy, yz, zz, mx, my, mz, m, _ = row
        origin = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        h = np.array([mx, my, mz])
        upper = np.hstack([0.5 * np.trace(origin) * np.eye(3) - origin, h[:, None]])
        out.append(np.vstack([upper, np.append(h, m)]))
    return np.array(out)


def psd_links(pi: np.ndarray, tol: float = 1e-12) -> np.ndarray:
    eigenvalues = np.linalg.eigvalsh(pseudo_inertia_here(pi))
    return eigenvalues[:, 0] >= -tol * np.abs(eigenvalues).max(axis=1)


def assert_in_band(value: float, nominal: float, relative: float) -> None:
    low, high = sorted(((1 - relative) * nominal, (1 + relative) * nominal))
    margin = SLACK * abs(nominal) + 1e-15
    assert low - margin <= value <= high + margin, (value, nominal, relative)


def friction_values(model: object) -> dict[str, np.ndarray]:
    """Per-joint parameters of a friction model (its constructor's fields), by name."""
    assert dataclasses.is_dataclass(model)
    fields = dataclasses.fields(model)
    return {f.name: np.asarray(getattr(model, f.name)) for f in fields if f.init}


# --------------------------------------------------------------------------- reproducibility
def test_same_seed_same_model(robot: sl.RobotModel) -> None:
    first, second = perturb(robot, RELATIVE, seed=7), perturb(robot, RELATIVE, seed=7)
    np.testing.assert_array_equal(first.parameter_vector(), second.parameter_vector())
    for name, value in friction_values(first.friction).items():
        np.testing.assert_array_equal(value, getattr(second.friction, name))
    by_generator = perturb(robot, RELATIVE, seed=np.random.default_rng(7))
    np.testing.assert_array_equal(by_generator.parameter_vector(), first.parameter_vector())


def test_different_seeds_differ(robot: sl.RobotModel) -> None:
    first, second = perturb(robot, RELATIVE, seed=1), perturb(robot, RELATIVE, seed=2)
    masses = robot.parameter_vector()[9::11]
    differ = first.parameter_vector()[9::11] != second.parameter_vector()[9::11]
    np.testing.assert_array_equal(differ, masses > 0)  # a zero mass stays zero
    for name, value in friction_values(first.friction).items():
        assert (value != getattr(second.friction, name)).all(), name


def test_one_generator_draws_inertia_then_friction(robot: sl.RobotModel) -> None:
    whole = perturb(robot, RELATIVE, seed=11)
    generator = np.random.default_rng(11)
    inertial = perturb_inertia(robot, RELATIVE, generator)
    friction = perturb_friction(robot.friction, RELATIVE, generator)
    np.testing.assert_array_equal(whole.parameter_vector(), inertial.parameter_vector())
    for name, value in friction_values(friction).items():
        np.testing.assert_array_equal(value, getattr(whole.friction, name))
    assert inertial.friction is robot.friction


# --------------------------------------------------------------------------- the band
@pytest.mark.parametrize("seed", SEEDS)
def test_parameters_stay_in_the_band(robot: sl.RobotModel, seed: int) -> None:
    nominal = link_data(robot.parameter_vector())
    perturbed = link_data(perturb(robot, RELATIVE, seed=seed).parameter_vector())
    for (m0, c0, i0, a0), (m1, c1, i1, a1) in zip(nominal, perturbed, strict=True):
        assert_in_band(m1, m0, RELATIVE)
        assert_in_band(a1, a0, RELATIVE)
        if m0 > 0:
            for k in range(3):
                assert_in_band(c1[k], c0[k], RELATIVE)
        # Order statistics keep the band; clipping keeps it for rigid true links.
        for p1, p0 in zip(np.linalg.eigvalsh(i1), np.linalg.eigvalsh(i0), strict=True):
            assert_in_band(p1, p0 if abs(p0) > 1e-12 else 0.0, RELATIVE)


def test_draws_fill_the_band(robot: sl.RobotModel) -> None:
    masses = robot.parameter_vector()[9::11]
    massive = masses > 0
    drawn = np.array([perturb(robot, RELATIVE, seed=s).parameter_vector()[9::11] for s in SEEDS])
    ratios = drawn[:, massive] / masses[massive]
    assert ratios.min() < 1 - 0.8 * RELATIVE and ratios.max() > 1 + 0.8 * RELATIVE


def test_zero_pattern_and_principal_axes_are_kept(robot: sl.RobotModel) -> None:
    nominal = robot.parameter_vector()
    perturbed = perturb(robot, RELATIVE, seed=3).parameter_vector()
    zero = np.abs(nominal) < 1e-12  # e.g. XY, XZ, mX of PUMA links 3-6
    np.testing.assert_allclose(perturbed[zero], 0.0, atol=1e-12)
    for (_, _, i0, _), (_, _, i1, _) in zip(link_data(nominal), link_data(perturbed), strict=True):
        _, axes = np.linalg.eigh(i0)
        rotated = axes.T @ i1 @ axes
        off_diagonal = rotated - np.diag(np.diag(rotated))
        assert np.abs(off_diagonal).max() <= 1e-9 * max(np.abs(i1).max(), 1e-300)


def test_round_off_does_not_tilt_a_symmetric_body() -> None:
    # A cylinder with moments (a, a, b) and an XY residue of 1e-14·a, as float
    # rotations leave it: the eigenvectors of the degenerate pair would turn by
    # 45°, and distinct factors on them would create a product of inertia ≈ 0.1·a.
    a = 1e-3
    inertia = np.diag([a, a, 2.5 * a])
    inertia[0, 1] = inertia[1, 0] = 1e-14 * a
    # 2.5·a > a + a: not a rigid body (no cylinder has it), which this test does not need.
    cylinder = sl.LinkInertia(1.0, (0.0, 0.0, 0.1), inertia, rigid_body=False)
    robot = sl.RobotModel.from_mdh([(0.0, 0.0, 0.0, 0.0)], [cylinder])
    for seed in SEEDS:
        xy = perturb_inertia(robot, RELATIVE, seed).parameter_vector()[1]
        assert abs(xy) <= 1e-12 * a


def test_massless_link_stays_massless(puma: sl.RobotModel) -> None:
    link1 = perturb(puma, RELATIVE, seed=5).parameter_vector()[:11]
    np.testing.assert_array_equal(link1[6:10], 0.0)  # mX, mY, mZ, m
    assert_in_band(link1[5], puma.parameter_vector()[5], RELATIVE)  # ZZ1 about the joint axis
    np.testing.assert_allclose(link1[:5], 0.0, atol=1e-15)


# --------------------------------------------------------------------------- consistency
@pytest.mark.parametrize("seed", SEEDS)
def test_perturbed_links_are_rigid_bodies(robot: sl.RobotModel, seed: int) -> None:
    nominal_rigid = psd_links(robot.parameter_vector())
    perturbed = perturb(robot, RELATIVE, seed=seed)
    rigid = psd_links(perturbed.parameter_vector())
    assert rigid[nominal_rigid].all()
    np.testing.assert_array_equal(physically_consistent_links(perturbed), rigid)
    q, _, _ = random_states(robot.n_dof, seed)
    assert (np.linalg.eigvalsh(perturbed.mass_matrix(q)) > 0).all()


def test_puma_links_1_and_3_are_the_known_exceptions(puma: sl.RobotModel) -> None:
    expected = np.array([False, True, False, True, True, True])
    np.testing.assert_array_equal(psd_links(puma.parameter_vector()), expected)
    np.testing.assert_array_equal(physically_consistent_links(puma), expected)
    assert not is_physically_consistent(puma)
    for seed in SEEDS:
        assert not physically_consistent_links(perturb(puma, RELATIVE, seed=seed))[0]


def test_other_builtin_robots_are_consistent() -> None:
    for name in ("panda_gaz", "panda", "planar2"):
        robot = sl.robots.load(name)
        assert is_physically_consistent(robot), name
        assert is_physically_consistent(perturb(robot, RELATIVE, seed=4)), name


def test_slender_rods_are_clipped_to_the_triangle_boundary(planar: sl.RobotModel) -> None:
    # A uniform rod has moments (0, a, a): almost every draw breaks the triangle
    # inequality, and the largest moment must come back to the sum of the others.
    for seed in SEEDS:
        perturbed = link_data(perturb(planar, RELATIVE, seed=seed).parameter_vector())
        for (_, _, i0, _), (_, _, i1, _) in zip(
            link_data(planar.parameter_vector()), perturbed, strict=True
        ):
            moments = np.linalg.eigvalsh(i1)
            np.testing.assert_allclose(moments[0], 0.0, atol=1e-15)
            np.testing.assert_allclose(moments[2], moments[0] + moments[1], rtol=1e-12)
            assert_in_band(moments[2], np.linalg.eigvalsh(i0)[2], RELATIVE)


def test_thin_disc_stays_a_rigid_body() -> None:
    # Moments (a, a, 2a) sit on the boundary; a disc of mass 2 kg, radius 0.3 m.
    a = 2.0 * 0.3**2 / 4
    disc = sl.LinkInertia(2.0, (0.1, 0.0, 0.05), np.diag([a, a, 2 * a]))
    robot = sl.RobotModel.from_mdh([(0.0, 0.0, 0.0, 0.0)], [disc])
    for seed in range(20):
        perturbed = perturb_inertia(robot, 0.5, seed)
        ((_, c, inertia, _),) = link_data(perturbed.parameter_vector())
        moments = np.linalg.eigvalsh(inertia)
        assert moments[2] <= moments[0] + moments[1] + 1e-15
        for p1, p0 in zip(moments, (a, a, 2 * a), strict=True):
            assert_in_band(p1, p0, 0.5)
        assert c[1] == 0.0
        assert psd_links(perturbed.parameter_vector()).all()


# --------------------------------------------------------------------------- dynamics
def test_zero_error_gives_the_same_dynamics(robot: sl.RobotModel) -> None:
    same = perturb(robot, 0.0, seed=9)
    q, qd, qdd = random_states(robot.n_dof, 0)
    tau = robot.inverse_dynamics(q, qd, qdd)
    np.testing.assert_allclose(
        same.inverse_dynamics(q, qd, qdd), tau, rtol=0, atol=1e-12 * np.abs(tau).max()
    )
    np.testing.assert_allclose(
        same.parameter_vector(), robot.parameter_vector(), rtol=0, atol=1e-14
    )
    for name, value in friction_values(robot.friction).items():
        np.testing.assert_array_equal(getattr(same.friction, name), value)


def test_fifteen_percent_gives_a_plausible_torque_error(robot: sl.RobotModel) -> None:
    q, qd, qdd = random_states(robot.n_dof, 1, n=50)
    tau = robot.inverse_dynamics(q, qd, qdd)
    for seed in SEEDS:
        error = perturb(robot, RELATIVE, seed=seed).inverse_dynamics(q, qd, qdd) - tau
        ratio = np.linalg.norm(error) / np.linalg.norm(tau)
        assert 0.0 < ratio < 0.5, ratio


def test_kinematics_limits_and_name_are_kept(robot: sl.RobotModel) -> None:
    perturbed = perturb(robot, RELATIVE, seed=2)
    named = perturb(robot, RELATIVE, seed=2, name="nominal")
    assert perturbed.name == robot.name and named.name == "nominal"
    assert perturbed.description == robot.description
    q, _, _ = random_states(robot.n_dof, 2, n=3)
    np.testing.assert_array_equal(
        perturbed.link_pose(q, robot.n_dof), robot.link_pose(q, robot.n_dof)
    )
    np.testing.assert_array_equal(perturbed.position_limits, robot.position_limits)
    np.testing.assert_array_equal(perturbed.gravity_vector, robot.gravity_vector)


# --------------------------------------------------------------------------- friction
FRICTIONS = [
    sl.robots.load("puma560").friction,
    sl.robots.load("panda_gaz").friction,
    LuGre.canudas1995(3),
    Coulomb(c_pos=[0.25, 0.0], c_neg=[-0.26, -0.1]),
    Stribeck(fc=[1.0, 2.0], fs=1.5, vs=0.01, fv=0.3, delta=1.0),
]


@pytest.mark.parametrize("friction", FRICTIONS, ids=lambda f: type(f).__name__)
def test_perturbed_friction_keeps_class_signs_and_band(friction: object) -> None:
    for seed in SEEDS:
        perturbed = perturb_friction(friction, RELATIVE, np.random.default_rng(seed))
        assert type(perturbed) is type(friction)
        for name, value in friction_values(friction).items():
            new = np.asarray(getattr(perturbed, name))
            assert new.shape == value.shape
            np.testing.assert_array_equal(np.sign(new), np.sign(value))
            for v1, v0 in zip(new, value, strict=True):
                assert_in_band(v1, v0, RELATIVE)
    if isinstance(friction, Coulomb | CoulombViscous):
        assert (perturbed.c_neg <= 0).all() and (perturbed.c_pos >= 0).all()


def test_sigmoid_offsets_keep_both_signs() -> None:
    friction = sl.robots.load("panda_gaz").friction
    assert isinstance(friction, Sigmoid)
    perturbed = perturb_friction(friction, RELATIVE, 0)
    np.testing.assert_array_equal(np.sign(perturbed.phi3), np.sign(friction.phi3))
    assert (perturbed.phi3 < 0).any() and (perturbed.phi3 > 0).any()


def test_no_friction_stays_none(planar: sl.RobotModel) -> None:
    assert perturb_friction(None, RELATIVE, 0) is None
    assert perturb(planar, RELATIVE, seed=0).friction is None


def test_separate_friction_band(puma: sl.RobotModel) -> None:
    fixed = perturb(puma, RELATIVE, seed=3, friction_relative=0.0)
    np.testing.assert_array_equal(fixed.friction.c_pos, puma.friction.c_pos)
    assert not np.array_equal(fixed.parameter_vector(), puma.parameter_vector())
    wide = perturb(puma, 0.0, seed=3, friction_relative=0.5).friction
    ratio = wide.fv / puma.friction.fv
    assert ((ratio >= 0.5) & (ratio <= 1.5)).all() and np.abs(ratio - 1).max() > RELATIVE


def test_friction_that_is_not_a_dataclass() -> None:
    class Custom:
        fv = np.array([0.5])

    with pytest.raises(ModelError, match=r"dataclass of per-joint parameters.*got Custom"):
        perturb_friction(Custom(), RELATIVE, 0)  # type: ignore[type-var]


# --------------------------------------------------------------------------- pseudo-inertia
def test_pseudo_inertia_is_the_second_moment_of_point_masses() -> None:
    rng = np.random.default_rng(0)
    masses, points = rng.uniform(0.1, 2.0, 5), rng.uniform(-0.5, 0.5, (5, 3))
    origin = np.zeros((3, 3))
    expected = np.zeros((4, 4))
    for m, p in zip(masses, points, strict=True):
        origin += m * (p @ p * np.eye(3) - np.outer(p, p))
        expected += m * np.outer(np.append(p, 1.0), np.append(p, 1.0))  # ∫ [p; 1][p; 1]ᵀ dm
    upper = origin[np.triu_indices(3)]  # XX, XY, XZ, YY, YZ, ZZ
    row = np.concatenate([upper, masses @ points, [masses.sum(), 0.0]])
    np.testing.assert_allclose(pseudo_inertia(row)[0], expected, rtol=1e-12)
    np.testing.assert_allclose(pseudo_inertia([row, row]), [expected, expected], rtol=1e-12)


def test_pseudo_inertia_of_a_model(robot: sl.RobotModel) -> None:
    np.testing.assert_allclose(
        pseudo_inertia(robot), pseudo_inertia_here(robot.parameter_vector()), rtol=1e-14
    )
    assert pseudo_inertia(robot).shape == (robot.n_dof, 4, 4)
    np.testing.assert_array_equal(
        pseudo_inertia(robot.standard_parameters()), pseudo_inertia(robot)
    )


def test_consistency_rejects_what_is_not_a_body(planar: sl.RobotModel) -> None:
    pi = planar.parameter_vector().reshape(2, 11)
    assert is_physically_consistent(pi)
    negative_mass = pi.copy()
    negative_mass[1, 6:10] *= -1  # m < 0 with the COM kept
    negative_mass[1, :6] -= 2 * 1.0 * 0.25 * np.array([0, 0, 0, 1, 0, 1])
    np.testing.assert_array_equal(physically_consistent_links(negative_mass), [True, False])
    negative_armature = pi.copy()
    negative_armature[0, 10] = -0.1
    np.testing.assert_array_equal(physically_consistent_links(negative_armature), [False, True])
    massless = np.zeros((1, 11))
    assert is_physically_consistent(massless)
    massless[0, 5] = 0.2  # only ZZ: no body has it
    assert not is_physically_consistent(massless)
    massless[0, [0, 3]] = 0.1  # a massless ring: the limit of bodies
    assert is_physically_consistent(massless)


# --------------------------------------------------------------------------- validation
BAD_RELATIVE = [
    (-0.1, "in \\[0, 1\\).*got -0.1"),
    (1.0, "in \\[0, 1\\).*zero or negative masses.*got 1.0"),
    (15, "in \\[0, 1\\).*got 15"),
    (float("nan"), "finite fraction.*got nan"),
    (float("inf"), "finite fraction.*got inf"),
    (True, "real number.*got True"),
    ("0.15", "real number.*got '0.15'"),
]


@pytest.mark.parametrize(("value", "match"), BAD_RELATIVE)
def test_invalid_relative(puma: sl.RobotModel, value: object, match: str) -> None:
    with pytest.raises(InputValueError, match="relative must be.*" + match):
        perturb(puma, value)  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match="relative must be.*" + match):
        perturb_inertia(puma, value, 0)  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match="relative must be.*" + match):
        perturb_friction(puma.friction, value, 0)  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match="friction_relative must be.*" + match):
        perturb(puma, 0.1, friction_relative=value)  # type: ignore[arg-type]


def test_invalid_parameters_and_tolerance(puma: sl.RobotModel) -> None:
    with pytest.raises(
        DimensionError, match=r"shape \(11·n_dof,\) or \(n_dof, 11\); got shape \(10,\)"
    ):
        pseudo_inertia(np.zeros(10))
    with pytest.raises(DimensionError, match=r"got shape \(2, 22\)"):
        pseudo_inertia(np.zeros((2, 22)))
    with pytest.raises(InputValueError, match="standard parameters must be finite"):
        is_physically_consistent(np.full(11, np.nan))
    with pytest.raises(
        InputValueError, match=r"tol must be a relative tolerance in \[0, 1\); got -1"
    ):
        is_physically_consistent(puma, tol=-1)


def test_errors_share_the_root_and_builtin_bases(puma: sl.RobotModel) -> None:
    with pytest.raises(SensorlessError):
        perturb(puma, 2.0)
    with pytest.raises(ValueError, match="relative"):
        perturb(puma, -1.0)
