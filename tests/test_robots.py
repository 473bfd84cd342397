"""Tests of :mod:`sensorless.robots` (the :class:`RobotModel` and the built-in robots).

Every check compares against something computed another way: the identities
of rigid-body dynamics, finite differences of M(q), of the potential energy
and of the forward kinematics, the textbook closed form of the two-link
planar arm, textbook sums over link Jacobians, an MDH table rewritten as a
URDF file by a writer in this file, and the numbers of the cited sources.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import sensorless as sl
from sensorless.exceptions import DimensionError, InputValueError, ModelError, UnknownNameError

N_STATES = 5
FD_STEP = 1e-6


@pytest.fixture(scope="module", params=sl.robots.available())
def robot(request: pytest.FixtureRequest) -> sl.RobotModel:
    return sl.robots.load(request.param)


@pytest.fixture(scope="module")
def planar() -> sl.RobotModel:
    return sl.robots.load("planar2")


def random_states(
    n_dof: int, seed: int, n: int = N_STATES
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """q uniform within ±2 rad, q̇ and q̈ standard normal."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(-2.0, 2.0, (n, n_dof))
    return q, rng.standard_normal((n, n_dof)), rng.standard_normal((n, n_dof))


def assert_close(actual: np.ndarray, desired: np.ndarray, rel: float = 1e-10) -> None:
    """Equal up to ``rel`` times the largest entry of ``desired`` (scale-free)."""
    scale = max(1.0, float(np.max(np.abs(desired))))
    np.testing.assert_allclose(actual, desired, rtol=0, atol=rel * scale)


def skew(w: np.ndarray) -> np.ndarray:
    return np.array([[0.0, -w[2], w[1]], [w[2], 0.0, -w[0]], [-w[1], w[0], 0.0]])


def vee(s: np.ndarray) -> np.ndarray:
    return np.array([s[2, 1] - s[1, 2], s[0, 2] - s[2, 0], s[1, 0] - s[0, 1]]) / 2


def com_and_inertia(robot: sl.RobotModel) -> list[tuple[float, np.ndarray, np.ndarray]]:
    """(mass, COM, inertia about the COM) of each link, from the standard parameters."""
    out = []
    for _, row in robot.standard_parameters().iterrows():
        m = row["m"]
        first = np.array([row["mX"], row["mY"], row["mZ"]])
        c = first / m if m > 0 else np.zeros(3)
        origin = np.array(
            [
                [row["XX"], row["XY"], row["XZ"]],
                [row["XY"], row["YY"], row["YZ"]],
                [row["XZ"], row["YZ"], row["ZZ"]],
            ]
        )
        # Parallel-axis theorem, from the link frame origin back to the COM.
        out.append((m, c, origin - m * (c @ c * np.eye(3) - np.outer(c, c))))
    return out


# --------------------------------------------------------------------------- identities
def test_mass_matrix_symmetric_positive_definite(robot: sl.RobotModel) -> None:
    q, _, _ = random_states(robot.n_dof, 0)
    for mass in robot.mass_matrix(q):
        np.testing.assert_array_equal(mass, mass.T)
        assert np.linalg.eigvalsh(mass).min() > 0


def test_mdot_minus_two_c_is_skew_symmetric(robot: sl.RobotModel) -> None:
    q, qd, _ = random_states(robot.n_dof, 1)
    for qk, qdk in zip(q, qd, strict=True):
        mass_dot = (
            robot.mass_matrix(qk + FD_STEP * qdk) - robot.mass_matrix(qk - FD_STEP * qdk)
        ) / (2 * FD_STEP)
        n = mass_dot - 2 * robot.coriolis_matrix(qk, qdk)
        np.testing.assert_allclose(n + n.T, 0.0, atol=1e-7 * max(1.0, np.abs(mass_dot).max()))


def test_coriolis_matrix_is_christoffel(robot: sl.RobotModel) -> None:
    """C_kj = Σ_i c_ijk q̇_i with c_ijk = ½(∂M_kj/∂q_i + ∂M_ki/∂q_j − ∂M_ij/∂q_k)."""
    q, qd, _ = random_states(robot.n_dof, 2, n=2)
    eye = np.eye(robot.n_dof)
    for qk, qdk in zip(q, qd, strict=True):
        # dm[i] = ∂M/∂q_i by central differences.
        dm = (robot.mass_matrix(qk + FD_STEP * eye) - robot.mass_matrix(qk - FD_STEP * eye)) / (
            2 * FD_STEP
        )
        christoffel = 0.5 * (
            np.einsum("ikj->ijk", dm) + np.einsum("jki->ijk", dm) - np.einsum("kij->ijk", dm)
        )
        expected = np.einsum("ijk,i->kj", christoffel, qdk)
        np.testing.assert_allclose(
            robot.coriolis_matrix(qk, qdk), expected, atol=1e-7 * max(1.0, np.abs(dm).max())
        )


def test_inverse_dynamics_is_m_qdd_plus_c_qd_plus_g(robot: sl.RobotModel) -> None:
    q, qd, qdd = random_states(robot.n_dof, 3)
    expected = (
        np.einsum("kij,kj->ki", robot.mass_matrix(q), qdd)
        + np.einsum("kij,kj->ki", robot.coriolis_matrix(q, qd), qd)
        + robot.gravity(q)
    )
    assert_close(robot.inverse_dynamics(q, qd, qdd), expected)


def test_coriolis_transpose_velocity(robot: sl.RobotModel) -> None:
    q, qd, _ = random_states(robot.n_dof, 4)
    expected = np.einsum("kji,kj->ki", robot.coriolis_matrix(q, qd), qd)
    assert_close(robot.coriolis_transpose_velocity(q, qd), expected)


def test_nonlinear_effects(robot: sl.RobotModel) -> None:
    q, qd, _ = random_states(robot.n_dof, 5)
    expected = np.einsum("kij,kj->ki", robot.coriolis_matrix(q, qd), qd) + robot.gravity(q)
    assert_close(robot.nonlinear_effects(q, qd), expected)


def test_gravity_is_gradient_of_potential_energy(robot: sl.RobotModel) -> None:
    """g = ∂P/∂q with P = −Σ m_i g₀·p_ci(q), the COMs placed by forward kinematics."""
    links = com_and_inertia(robot)
    g0 = robot.gravity_vector

    def potential(q: np.ndarray) -> np.ndarray:
        return -sum(
            m * robot.forward_kinematics(q, i, c) @ g0 for i, (m, c, _) in enumerate(links, 1)
        )

    q, _, _ = random_states(robot.n_dof, 6)
    eye = np.eye(robot.n_dof)
    for qk in q:
        gradient = (potential(qk + FD_STEP * eye) - potential(qk - FD_STEP * eye)) / (2 * FD_STEP)
        assert_close(robot.gravity(qk), gradient, rel=1e-7)


def test_mass_matrix_from_link_jacobians(robot: sl.RobotModel) -> None:
    """M = Σ m_i J_viᵀJ_vi + J_ωiᵀ R_i I_ci R_iᵀ J_ωi + diag(armature) (Spong eq. 7.48)."""
    links = com_and_inertia(robot)
    q, _, _ = random_states(robot.n_dof, 7)
    for qk in q:
        expected = np.diag(robot.armature)
        for i, (m, c, inertia) in enumerate(links, start=1):
            jac = robot.point_jacobian(qk, i, c)
            rot = robot.link_pose(qk, i)[:3, :3]
            expected = expected + m * jac[:3].T @ jac[:3]
            expected = expected + jac[3:].T @ rot @ inertia @ rot.T @ jac[3:]
        assert_close(robot.mass_matrix(qk), expected)


def test_regressor_times_parameters_is_inverse_dynamics(robot: sl.RobotModel) -> None:
    q, qd, qdd = random_states(robot.n_dof, 8)
    tau = robot.regressor(q, qd, qdd) @ robot.parameter_vector()
    assert_close(tau, robot.inverse_dynamics(q, qd, qdd))


def test_regressor_terms_sum_to_inverse_dynamics(robot: sl.RobotModel) -> None:
    n = robot.n_dof
    q, qd, qdd = random_states(n, 9, n=3)
    n_terms = (n * n + 3 * n + 2) // 2
    pi = robot.parameter_vector()
    labels = robot.regressor_term_labels()
    assert len(labels) == n_terms
    assert labels[0] == "M1" and labels[-1] == "g"
    for qk, qdk, qddk in zip(q, qd, qdd, strict=True):
        terms = robot.regressor_terms(qk)
        big_q = robot.q_vector(qdk, qddk)
        assert terms.shape == (n_terms, n, 11 * n)
        assert big_q.shape == (n_terms,)
        tau = np.einsum("kij,k,j->i", terms, big_q, pi)
        assert_close(tau, robot.inverse_dynamics(qk, qdk, qddk))


def test_regressor_terms_have_their_meaning(planar: sl.RobotModel) -> None:
    """Y_{M_j} π is column j of M and Y_g π is g (eq. 3.10)."""
    q = np.array([0.4, -1.1])
    terms = planar.regressor_terms(q) @ planar.parameter_vector()
    labels = planar.regressor_term_labels()
    assert labels == ["M1", "M2", "B12", "C1", "C2", "g"]
    assert_close(terms[:2].T, planar.mass_matrix(q))
    assert_close(terms[-1], planar.gravity(q))


BATCH_METHODS = {
    "mass_matrix": ("q",),
    "coriolis_matrix": ("q", "qd"),
    "coriolis_transpose_velocity": ("q", "qd"),
    "gravity": ("q",),
    "nonlinear_effects": ("q", "qd"),
    "inverse_dynamics": ("q", "qd", "qdd"),
    "regressor": ("q", "qd", "qdd"),
    "regressor_terms": ("q",),
    "q_vector": ("qd", "qdd"),
    "friction_torque": ("qd",),
}


@pytest.mark.parametrize("method", sorted(BATCH_METHODS))
def test_batch_equals_stacked_samples(robot: sl.RobotModel, method: str) -> None:
    q, qd, qdd = random_states(robot.n_dof, 10, n=3)
    arrays = {"q": q, "qd": qd, "qdd": qdd}
    args = [arrays[name] for name in BATCH_METHODS[method]]
    function = getattr(robot, method)
    batch = function(*args)
    stacked = np.stack([function(*sample) for sample in zip(*args, strict=True)])
    assert batch.shape == stacked.shape
    np.testing.assert_array_equal(batch, stacked)


@pytest.mark.parametrize("method", ["link_pose", "forward_kinematics", "point_jacobian"])
def test_kinematics_batch_equals_stacked_samples(robot: sl.RobotModel, method: str) -> None:
    q, _, _ = random_states(robot.n_dof, 11, n=3)
    function = getattr(robot, method)
    batch = function(q, robot.n_dof)
    np.testing.assert_array_equal(batch, np.stack([function(qk, robot.n_dof) for qk in q]))


# --------------------------------------------------------------------------- planar2
def test_planar2_matches_spong_closed_form(planar: sl.RobotModel) -> None:
    """Spong, Hutchinson & Vidyasagar §7.4, two-link arm of uniform rods."""
    m1 = m2 = 1.0
    l1 = 1.0
    lc1 = lc2 = 0.5
    i1 = i2 = 1.0 / 12.0
    g = 9.81
    q, qd, qdd = random_states(2, 12)
    for (q1, q2), (qd1, qd2), qddk in zip(q, qd, qdd, strict=True):
        c2 = math.cos(q2)
        d11 = m1 * lc1**2 + m2 * (l1**2 + lc2**2 + 2 * l1 * lc2 * c2) + i1 + i2
        d12 = m2 * (lc2**2 + l1 * lc2 * c2) + i2
        d22 = m2 * lc2**2 + i2
        mass = np.array([[d11, d12], [d12, d22]])
        h = -m2 * l1 * lc2 * math.sin(q2)
        coriolis = np.array([[h * qd2, h * (qd1 + qd2)], [-h * qd1, 0.0]])
        gravity = np.array(
            [
                (m1 * lc1 + m2 * l1) * g * math.cos(q1) + m2 * lc2 * g * math.cos(q1 + q2),
                m2 * lc2 * g * math.cos(q1 + q2),
            ]
        )
        qk, qdk = np.array([q1, q2]), np.array([qd1, qd2])
        assert_close(planar.mass_matrix(qk), mass)
        assert_close(planar.coriolis_matrix(qk, qdk), coriolis)
        assert_close(planar.gravity(qk), gravity)
        assert_close(planar.inverse_dynamics(qk, qdk, qddk), mass @ qddk + coriolis @ qdk + gravity)


def test_planar2_options_change_the_closed_form() -> None:
    """load() forwards options: l = (0.5, 2), m = (3, 2), COM at 0.25 l."""
    robot = sl.robots.load("planar2", lengths=(0.5, 2.0), masses=(3.0, 2.0), com_ratio=0.25)
    l1, l2, m1, m2 = 0.5, 2.0, 3.0, 2.0
    lc1, lc2 = 0.25 * l1, 0.25 * l2
    q = np.array([0.3, 0.9])
    expected = np.array(
        [
            (m1 * lc1 + m2 * l1) * 9.81 * math.cos(q[0]) + m2 * lc2 * 9.81 * math.cos(q.sum()),
            m2 * lc2 * 9.81 * math.cos(q.sum()),
        ]
    )
    assert_close(robot.gravity(q), expected)
    assert_close(robot.mass_matrix(q)[1, 1], m2 * lc2**2 + m2 * l2**2 / 12)


# --------------------------------------------------------------------------- MDH vs URDF
# Craig modified DH of the Panda, Gaz et al. 2019 (Load_Franka_DH.m, parameters.md).
GAZ_ALPHA = [0.0, -np.pi / 2, np.pi / 2, np.pi / 2, -np.pi / 2, np.pi / 2, np.pi / 2]
GAZ_A = [0.0, 0.0, 0.0, 0.0825, -0.0825, 0.0, 0.088]
GAZ_D = [0.333, 0.0, 0.316, 0.0, 0.384, 0.0, 0.0]


def random_link(rng: np.random.Generator) -> sl.LinkInertia:
    """A physically valid rigid body: I_c = R diag(B+C, A+C, A+B) Rᵀ with A, B, C > 0."""
    second_moments = rng.uniform(0.01, 0.2, 3)
    principal = second_moments.sum() - second_moments
    rot = Rotation.random(random_state=rng).as_matrix()
    return sl.LinkInertia(
        rng.uniform(0.5, 5.0), rng.uniform(-0.1, 0.1, 3), rot @ np.diag(principal) @ rot.T
    )


def mdh_transform(alpha: float, a: float, theta: float, d: float) -> np.ndarray:
    """Rx(α) Tx(a) Rz(θ) Tz(d), written out (Craig, eq. 3.6)."""
    ca, sa, ct, st = math.cos(alpha), math.sin(alpha), math.cos(theta), math.sin(theta)
    return np.array(
        [
            [ct, -st, 0.0, a],
            [st * ca, ct * ca, -sa, -sa * d],
            [st * sa, ct * sa, ca, ca * d],
            [0.0, 0.0, 0.0, 1.0],
        ]
    )


URDF_INERTIA = {
    "ixx": (0, 0),
    "ixy": (0, 1),
    "ixz": (0, 2),
    "iyy": (1, 1),
    "iyz": (1, 2),
    "izz": (2, 2),
}


def write_urdf(path: Path, table: list[dict[str, float]], links: list[sl.LinkInertia]) -> Path:
    """A URDF of revolute z joints whose origins are the MDH transforms."""

    def numbers(values: np.ndarray) -> str:
        return " ".join(repr(float(v)) for v in values)

    parts = ['<robot name="mdh_as_urdf">', '<link name="base"/>']
    parent = "base"
    for i, (row, link) in enumerate(zip(table, links, strict=True), start=1):
        transform = mdh_transform(row["alpha"], row["a"], row["theta"], row["d"])
        rpy = Rotation.from_matrix(transform[:3, :3]).as_euler("xyz")  # R = Rz(y) Ry(p) Rx(r)
        inertia = " ".join(
            f'{key}="{float(link.inertia[ij])!r}"' for key, ij in URDF_INERTIA.items()
        )
        parts += [
            f'<joint name="joint{i}" type="revolute">',
            f'<parent link="{parent}"/><child link="link{i}"/>',
            f'<origin xyz="{numbers(transform[:3, 3])}" rpy="{numbers(rpy)}"/>',
            '<axis xyz="0 0 1"/>',
            '<limit lower="-10" upper="10" effort="100" velocity="10"/>',
            "</joint>",
            f'<link name="link{i}"><inertial>',
            f'<origin xyz="{numbers(link.com)}" rpy="0 0 0"/>',
            f'<mass value="{float(link.mass)!r}"/>',
            f"<inertia {inertia}/>",
            "</inertial></link>",
        ]
        parent = f"link{i}"
    parts.append("</robot>")
    path.write_text("\n".join(parts))
    return path


def gaz_table() -> list[dict[str, float]]:
    return [
        {"alpha": al, "a": a, "theta": 0.0, "d": d}
        for al, a, d in zip(GAZ_ALPHA, GAZ_A, GAZ_D, strict=True)
    ]


def random_table(rng: np.random.Generator) -> list[dict[str, float]]:
    """Five joints with every MDH field non-zero, θ offsets included."""
    return [
        {
            "alpha": rng.uniform(-np.pi, np.pi),
            "a": rng.uniform(-0.3, 0.3),
            "theta": rng.uniform(-np.pi, np.pi),
            "d": rng.uniform(-0.3, 0.3),
        }
        for _ in range(5)
    ]


@pytest.mark.parametrize("which", ["gaz_table", "random_table"])
def test_mdh_and_urdf_give_the_same_dynamics(tmp_path: Path, which: str) -> None:
    rng = np.random.default_rng(20)
    table = gaz_table() if which == "gaz_table" else random_table(rng)
    links = [random_link(rng) for _ in table]
    from_mdh = sl.RobotModel.from_mdh(table, links)
    from_urdf = sl.RobotModel.from_urdf(write_urdf(tmp_path / "robot.urdf", table, links))
    assert from_urdf.n_dof == len(table)
    q, qd, qdd = random_states(len(table), 21)
    assert_close(from_urdf.mass_matrix(q), from_mdh.mass_matrix(q))
    assert_close(from_urdf.gravity(q), from_mdh.gravity(q))
    assert_close(from_urdf.inverse_dynamics(q, qd, qdd), from_mdh.inverse_dynamics(q, qd, qdd))
    assert_close(from_urdf.regressor(q, qd, qdd), from_mdh.regressor(q, qd, qdd))
    assert_close(from_urdf.parameter_vector(), from_mdh.parameter_vector())


def test_mdh_link_poses_are_the_product_of_craig_transforms() -> None:
    rng = np.random.default_rng(22)
    table = random_table(rng)
    robot = sl.RobotModel.from_mdh(table, [random_link(rng) for _ in table])
    q, _, _ = random_states(len(table), 23, n=2)
    for qk in q:
        pose = np.eye(4)
        for i, (row, qi) in enumerate(zip(table, qk, strict=True), start=1):
            pose = pose @ mdh_transform(row["alpha"], row["a"], row["theta"] + qi, row["d"])
            assert_close(robot.link_pose(qk, i), pose, rel=1e-12)


def test_puma560_standard_dh_chain() -> None:
    """Frame 6 = Π Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i) with the table of parameters.md.

    The model's link frame *i* is the joint frame z_{i-1} turned by q_i, so the
    distal DH frame 6 is link frame 6 followed by Tz(d6) Tx(a6) Rx(α6).
    """

    def dh(theta: float, d: float, a: float, alpha: float) -> np.ndarray:
        ct, st, ca, sa = math.cos(theta), math.sin(theta), math.cos(alpha), math.sin(alpha)
        return np.array(
            [
                [ct, -st * ca, st * sa, a * ct],
                [st, ct * ca, -ct * sa, a * st],
                [0, sa, ca, d],
                [0, 0, 0, 1],
            ]
        )

    d = [0.672, 0.0, 0.15005, 0.4318, 0.0, 0.0]
    a = [0.0, 0.4318, 0.0203, 0.0, 0.0, 0.0]
    alpha = [np.pi / 2, 0.0, -np.pi / 2, np.pi / 2, -np.pi / 2, 0.0]
    robot = sl.robots.load("puma560")
    q, _, _ = random_states(6, 24, n=3)
    for qk in q:
        expected = np.eye(4)
        for qi, di, ai, al in zip(qk, d, a, alpha, strict=True):
            expected = expected @ dh(qi, di, ai, al)
        assert_close(robot.link_pose(qk, 6) @ dh(0.0, d[5], a[5], alpha[5]), expected, rel=1e-12)


def test_panda_urdf_and_panda_gaz_share_kinematics_and_dynamics() -> None:
    urdf, gaz = sl.robots.load("panda"), sl.robots.load("panda_gaz")
    q, _, _ = random_states(7, 25)
    for link in range(1, 8):
        assert_close(urdf.link_pose(q, link), gaz.link_pose(q, link), rel=1e-12)
    assert_close(urdf.forward_kinematics(q, 7), gaz.forward_kinematics(q, 7), rel=1e-12)
    # The two inertial sets differ only in link 1's COM height (and the link-1 inertia
    # terms that follow from it). Link 1 turns about the vertical base z axis, so a
    # shift of its COM along that axis changes neither its ZZ1 about the axis nor its
    # potential energy: M(q) and g(q) must agree.
    differing = {
        name
        for name, x, y in zip(
            urdf.parameter_names(), urdf.parameter_vector(), gaz.parameter_vector(), strict=True
        )
        if not math.isclose(x, y, rel_tol=1e-9, abs_tol=1e-12)
    }
    assert differing <= {"XX1", "XZ1", "YY1", "YZ1", "mZ1"}
    assert_close(urdf.mass_matrix(q), gaz.mass_matrix(q), rel=1e-9)
    assert_close(urdf.gravity(q), gaz.gravity(q), rel=1e-9)


# --------------------------------------------------------------------------- Jacobians
def test_point_jacobian_matches_finite_differences(robot: sl.RobotModel) -> None:
    point = np.array([0.05, -0.1, 0.2])
    q, _, _ = random_states(robot.n_dof, 30, n=2)
    eye = np.eye(robot.n_dof)
    for qk in q:
        plus, minus = qk + FD_STEP * eye, qk - FD_STEP * eye
        for link in range(1, robot.n_dof + 1):
            jac = robot.point_jacobian(qk, link, point)
            linear = (
                robot.forward_kinematics(plus, link, point)
                - robot.forward_kinematics(minus, link, point)
            ) / (2 * FD_STEP)
            np.testing.assert_allclose(jac[:3], linear.T, atol=1e-8)
            rot = robot.link_pose(qk, link)[:3, :3]
            rot_diff = (robot.link_pose(plus, link) - robot.link_pose(minus, link))[:, :3, :3]
            # R(q + h e_j) R(q)ᵀ ≈ I + h [ω_j]×
            angular = np.array([vee(d @ rot.T) for d in rot_diff / (2 * FD_STEP)])
            np.testing.assert_allclose(jac[3:], angular.T, atol=1e-8)
            np.testing.assert_allclose(jac[3:, link:], 0.0, atol=1e-15)


def test_point_jacobian_gives_contact_torque(planar: sl.RobotModel) -> None:
    """A vertical force f at the tip of planar2 gives τ = Jᵀf = f (l1 cos q1 + l2 cos q12, ...)."""
    q = np.array([0.7, -0.4])
    f = 3.0
    jac = planar.point_jacobian(q, 2, (1.0, 0.0, 0.0))
    tau = jac.T @ np.array([0.0, f, 0.0, 0.0, 0.0, 0.0])
    expected = f * np.array([math.cos(q[0]) + math.cos(q.sum()), math.cos(q.sum())])
    assert_close(tau, expected)


def test_forward_kinematics_accepts_joint_names(planar: sl.RobotModel) -> None:
    q = np.array([0.2, 0.5])
    tip = planar.forward_kinematics(q, "joint2", (1.0, 0.0, 0.0))
    expected = [math.cos(0.2) + math.cos(0.7), math.sin(0.2) + math.sin(0.7), 0.0]
    assert_close(tip, np.array(expected))
    assert_close(planar.link_pose(q, "joint2"), planar.link_pose(q, 2))


# --------------------------------------------------------------------------- friction
# PUMA 560 motor-side B and Tc, gear ratios G (parameters.md, Corke & Armstrong-Hélouvry).
PUMA_GEAR = [-62.6111, 107.815, -53.7063, 76.0364, 71.923, 76.686]
PUMA_B = [1.48e-3, 0.817e-3, 1.38e-3, 71.2e-6, 82.6e-6, 36.7e-6]
PUMA_TC_POS = [0.395, 0.126, 0.132, 11.2e-3, 9.26e-3, 3.96e-3]
PUMA_TC_NEG = [-0.435, -0.071, -0.105, -16.9e-3, -14.5e-3, -10.5e-3]
PUMA_JM = [200e-6] * 3 + [33e-6] * 3


def test_puma560_friction_is_referred_to_the_joint_side() -> None:
    robot = sl.robots.load("puma560")
    tau = robot.friction_torque(np.ones(6))
    assert tau[0] == pytest.approx(0.395 * 62.6111 + 1.48e-3 * 62.6111**2, rel=1e-12)
    expected_pos = [
        tc * abs(g) + b * g**2 for tc, g, b in zip(PUMA_TC_POS, PUMA_GEAR, PUMA_B, strict=True)
    ]
    expected_neg = [
        tc * abs(g) - b * g**2 for tc, g, b in zip(PUMA_TC_NEG, PUMA_GEAR, PUMA_B, strict=True)
    ]
    np.testing.assert_allclose(tau, expected_pos, rtol=1e-12)
    np.testing.assert_allclose(robot.friction_torque(-np.ones(6)), expected_neg, rtol=1e-12)


def test_panda_gaz_friction_vanishes_at_rest() -> None:
    robot = sl.robots.load("panda_gaz")
    np.testing.assert_allclose(robot.friction_torque(np.zeros(7)), 0.0, atol=1e-15)
    assert (np.sign(robot.friction_torque(np.full(7, 0.5))) == 1).all()


def test_robot_without_friction_gives_zero(planar: sl.RobotModel) -> None:
    assert planar.friction is None
    np.testing.assert_array_equal(planar.friction_torque([[1.0, -2.0]] * 3), np.zeros((3, 2)))


# --------------------------------------------------------------------------- parameters
def test_standard_parameter_table(planar: sl.RobotModel) -> None:
    table = planar.standard_parameters()
    assert list(table.columns) == ["XX", "XY", "XZ", "YY", "YZ", "ZZ", "mX", "mY", "mZ", "m", "Ia"]
    assert list(table.index) == ["link1", "link2"]
    link2 = table.loc["link2"]
    assert link2["m"] == pytest.approx(1.0)
    assert link2["mX"] == pytest.approx(0.5)
    # Rod about its COM m l²/12, moved to the joint by the parallel-axis theorem.
    assert link2["ZZ"] == pytest.approx(1 / 12 + 0.25)
    assert link2["YY"] == pytest.approx(1 / 12 + 0.25)
    for name in ("XX", "XY", "XZ", "YZ", "mY", "mZ", "Ia"):
        assert link2[name] == pytest.approx(0.0, abs=1e-15)
    assert planar.parameter_names()[:11] == [f"{p}1" for p in table.columns]
    np.testing.assert_array_equal(planar.parameter_vector(), table.to_numpy().ravel())


def test_puma560_armature_is_rotor_inertia_times_gear_ratio_squared() -> None:
    robot = sl.robots.load("puma560")
    expected = [jm * g**2 for jm, g in zip(PUMA_JM, PUMA_GEAR, strict=True)]
    np.testing.assert_allclose(robot.standard_parameters()["Ia"], expected, rtol=1e-12)
    assert expected[0] == pytest.approx(0.784, abs=5e-4)  # quoted in parameters.md


def test_with_standard_parameters_round_trip_and_linearity(robot: sl.RobotModel) -> None:
    q, qd, qdd = random_states(robot.n_dof, 40)
    copy = robot.with_standard_parameters(robot.parameter_vector())
    assert copy.friction is robot.friction
    assert_close(copy.parameter_vector(), robot.parameter_vector(), rel=1e-12)
    tau = robot.inverse_dynamics(q, qd, qdd)
    assert_close(copy.inverse_dynamics(q, qd, qdd), tau)
    assert_close(copy.mass_matrix(q), robot.mass_matrix(q))
    doubled = robot.with_standard_parameters(2 * robot.parameter_vector())
    assert_close(doubled.inverse_dynamics(q, qd, qdd), 2 * tau)
    table = robot.with_standard_parameters(robot.standard_parameters())
    assert_close(table.inverse_dynamics(q, qd, qdd), tau)
    assert robot.with_standard_parameters(robot.parameter_vector(), friction=None).friction is None


def test_with_standard_parameters_accepts_a_massless_link(planar: sl.RobotModel) -> None:
    """A link of zero mass with a rotor inertia about its axis is a valid rigid body."""
    pi = planar.parameter_vector().reshape(2, 11).copy()
    pi[1] = 0.0
    pi[1, 5] = 0.2  # ZZ2: a massless disc, an idealisation the standard parameters allow
    changed = planar.with_standard_parameters(pi)
    np.testing.assert_allclose(changed.parameter_vector(), pi.ravel(), atol=1e-15)
    pi[1, 7] = 0.1  # a first moment without mass is no rigid body
    with pytest.raises(ModelError, match="massless link has zero first moments"):
        planar.with_standard_parameters(pi)


def test_with_standard_parameters_changes_armature_only(planar: sl.RobotModel) -> None:
    pi = planar.parameter_vector().reshape(2, 11).copy()
    pi[:, 10] = [0.3, 0.7]
    changed = planar.with_standard_parameters(pi)
    q = np.array([0.1, 0.2])
    assert_close(changed.mass_matrix(q) - planar.mass_matrix(q), np.diag([0.3, 0.7]))
    assert_close(changed.armature, np.array([0.3, 0.7]))


def test_models_are_immutable(planar: sl.RobotModel) -> None:
    with pytest.raises(dataclasses.FrozenInstanceError):
        planar.name = "other"  # type: ignore[misc]


# --------------------------------------------------------------------------- registry
def test_available_and_load() -> None:
    expected = ["lwr4", "panda", "panda_gaz", "planar2", "puma560", "ur10", "ur5"]
    assert sl.robots.available() == expected
    dofs = {"panda": 7, "panda_gaz": 7, "planar2": 2, "puma560": 6, "ur10": 6, "ur5": 6}
    for name, n_dof in dofs.items():
        robot = sl.robots.load(name)
        assert robot.n_dof == n_dof
        assert robot.name == name


def test_unknown_robot_lists_the_available_ones() -> None:
    with pytest.raises(UnknownNameError, match=r"'ur3'.*panda.*panda_gaz.*puma560.*ur10.*ur5"):
        sl.robots.load("ur3")
    with pytest.raises(KeyError):
        sl.robots.load("ur3")


# --------------------------------------------------------------------------- errors
ROW = {"alpha": 0.0, "a": 0.0, "theta": 0.0, "d": 0.0}
LINK = {"mass": 1.0, "com": (0.0, 0.0, 0.0), "inertia": np.eye(3)}


@pytest.mark.parametrize(
    ("call", "error", "match"),
    [
        (lambda r: r.mass_matrix(np.zeros(3)), DimensionError, r"q must have shape \(2,\)"),
        (lambda r: r.gravity(np.zeros((4, 3))), DimensionError, r"\(n_samples, 2\).*\(4, 3\)"),
        (lambda r: r.gravity(np.zeros((2, 2, 2))), DimensionError, r"got shape \(2, 2, 2\)"),
        (lambda r: r.gravity(["a", "b"]), DimensionError, "numeric array"),
        (lambda r: r.gravity([0.0, np.nan]), InputValueError, "q must be finite.*nan"),
        (lambda r: r.gravity([[0.0, 0.0], [np.inf, 0]]), InputValueError, "sample 1, joint 0"),
        (
            lambda r: r.coriolis_matrix(np.zeros((3, 2)), np.zeros((4, 2))),
            DimensionError,
            r"q, qd must have the same number of samples; got \[3, 4\]",
        ),
        (
            lambda r: r.inverse_dynamics(np.zeros(2), np.zeros(2), np.zeros((2, 2))),
            DimensionError,
            "same number of samples",
        ),
        (lambda r: r.point_jacobian(np.zeros(2), 0), ModelError, "number from 1 to 2"),
        (
            lambda r: r.point_jacobian(np.zeros(2), 3),
            ModelError,
            "from 1 to 2 or a joint name; got 3",
        ),
        (lambda r: r.link_pose(np.zeros(2), "elbow"), ModelError, "unknown joint 'elbow'"),
        (lambda r: r.forward_kinematics(np.zeros(2), 1, (1, 2)), DimensionError, "3-vector"),
        (
            lambda r: r.with_standard_parameters(np.zeros(21)),
            DimensionError,
            r"expected 22 standard parameters \(2 links x 11\); got 21",
        ),
        (
            lambda r: r.with_standard_parameters(np.full(22, np.nan)),
            InputValueError,
            "standard parameters must be finite",
        ),
    ],
    ids=[
        "q-length",
        "q-columns",
        "q-rank-3",
        "q-not-numeric",
        "q-nan",
        "q-inf",
        "q-qd-samples",
        "qdd-samples",
        "link-0",
        "link-too-large",
        "unknown-joint-name",
        "point-length",
        "parameter-count",
        "parameter-nan",
    ],
)
def test_bad_state_input(planar: sl.RobotModel, call, error, match) -> None:
    with pytest.raises(error, match=match):
        call(planar)


def test_errors_share_the_root_and_builtin_bases(planar: sl.RobotModel) -> None:
    with pytest.raises(sl.SensorlessError):
        planar.gravity(np.zeros(5))
    with pytest.raises(ValueError, match="shape"):
        planar.gravity(np.zeros(5))


@pytest.mark.parametrize(
    ("table", "links", "error", "match"),
    [
        ([{"alpha": 0.0, "a": 0.0, "theta": 0.0}], [LINK], ModelError, r"row 1 is missing \['d'\]"),
        ([{**ROW, "a": None}], [LINK], ModelError, r"missing \['a'\]"),
        ([(0.0, 0.0, 0.0)], [LINK], ModelError, "row 1 has 3 fields; expected 4"),
        ([{**ROW, "d": "far"}], [LINK], ModelError, "non-numeric"),
        ([{**ROW, "a": np.inf}], [LINK], ModelError, "non-finite"),
        ([{**ROW, "alpha": 90.0}], [LINK], InputValueError, "alpha = 90.0.*degrees"),
        ([{**ROW, "theta": -180.0}], [LINK], InputValueError, "theta.*radians.*deg2rad"),
        ([], [], ModelError, "table is empty"),
        ([ROW, ROW], [LINK], DimensionError, "inertial data for 2 links.*got 1"),
        ([ROW], [{"mass": 1.0, "com": (0, 0, 0)}], ModelError, r"missing \['inertia'\]"),
        ([ROW], [{**LINK, "mass": -1.0}], ModelError, "mass must be >= 0 kg; got -1.0"),
        ([ROW], [{**LINK, "com": (0, 0)}], ModelError, r"3 entries \[m\]; got shape \(2,\)"),
        ([ROW], [{**LINK, "inertia": np.eye(2)}], ModelError, r"3x3 tensor.*got shape \(2, 2\)"),
        ([ROW], [{**LINK, "mass": np.nan}], ModelError, "must be finite"),
    ],
)
def test_bad_mdh_description(table, links, error, match) -> None:
    with pytest.raises(error, match=match):
        sl.RobotModel.from_mdh(table, links)


def test_degrees_in_a_standard_dh_table() -> None:
    with pytest.raises(InputValueError, match="degrees"):
        sl.RobotModel.from_dh([{**ROW, "alpha": 90.0}], [LINK])


@pytest.mark.parametrize(
    ("options", "error", "match"),
    [
        ({"gravity": (0.0, -9.81)}, ModelError, "gravity must be a finite 3-vector"),
        (
            {"motors": sl.MotorData([1e-4], [50.0])},
            DimensionError,
            r"motor data must have 2 entries \(one per joint\); got 1",
        ),
        (
            {"motors": {"rotor_inertia": [1e-4, -1e-4], "gear_ratio": [50.0, 50.0]}},
            ModelError,
            "rotor inertias must be finite and >= 0",
        ),
        (
            {"motors": {"rotor_inertia": [1e-4, 1e-4], "gear_ratio": [50.0]}},
            ModelError,
            "same length",
        ),
        (
            {"friction": sl.friction.Viscous(fv=[1.0, 1.0, 1.0])},
            DimensionError,
            "friction model has 3 joints; the robot has 2",
        ),
    ],
)
def test_bad_mdh_options(options, error, match) -> None:
    with pytest.raises(error, match=match):
        sl.RobotModel.from_mdh([ROW, {**ROW, "a": 1.0}], [LINK, LINK], **options)


def test_motor_data_gives_armature() -> None:
    robot = sl.RobotModel.from_mdh(
        [ROW, {**ROW, "a": 1.0}],
        [LINK, LINK],
        {"rotor_inertia": [1e-4, 2e-4], "gear_ratio": [-50, 100]},
    )
    np.testing.assert_allclose(robot.armature, [0.25, 2.0])
    np.testing.assert_allclose(robot.standard_parameters()["Ia"], [0.25, 2.0])


@pytest.fixture(scope="module")
def small_urdf(tmp_path_factory: pytest.TempPathFactory) -> Path:
    rng = np.random.default_rng(50)
    table = random_table(rng)[:3]
    path = tmp_path_factory.mktemp("urdf") / "three.urdf"
    return write_urdf(path, table, [random_link(rng) for _ in table])


@pytest.mark.parametrize(
    ("options", "error", "match"),
    [
        ({"joints": ["joint1", "joint9"]}, ModelError, r"\['joint9'\] are not movable joints"),
        ({"joints": ["joint2", "joint1"]}, ModelError, "chain order"),
        ({"tip": "tool"}, ModelError, "tip link 'tool' not in the URDF"),
        (
            {"armature": [0.1, 0.2]},
            DimensionError,
            r"armature must have 3 entries; got shape \(2,\)",
        ),
    ],
)
def test_bad_urdf_options(small_urdf: Path, options, error, match) -> None:
    with pytest.raises(error, match=match):
        sl.RobotModel.from_urdf(small_urdf, **options)


def test_urdf_joint_subset_and_tip(small_urdf: Path) -> None:
    """Locking joint 3 at zero or cutting at link 2 leaves a two-joint arm."""
    full = sl.RobotModel.from_urdf(small_urdf)
    locked = sl.RobotModel.from_urdf(small_urdf, ["joint1", "joint2"])
    cut = sl.RobotModel.from_urdf(small_urdf, tip="link2")
    assert full.n_dof == 3 and locked.n_dof == 2 and cut.n_dof == 2
    q = np.array([0.3, -0.8])
    # With joint 3 locked at 0 the arm is the full one at q3 = 0.
    assert_close(locked.gravity(q), full.gravity(np.append(q, 0.0))[:2])
    # Cutting at link 2 removes link 3's mass.
    assert cut.standard_parameters()["m"].sum() < full.standard_parameters()["m"].sum()


def test_missing_or_broken_urdf(tmp_path: Path) -> None:
    with pytest.raises(ModelError, match=r"URDF file not found: .*nowhere\.urdf"):
        sl.RobotModel.from_urdf(tmp_path / "nowhere.urdf")
    broken = tmp_path / "broken.urdf"
    broken.write_text("<robot name='x'><link name='a'>")
    with pytest.raises(ModelError, match="cannot parse URDF"):
        sl.RobotModel.from_urdf(broken)


def test_puma560_matches_the_robotics_toolbox_published_output() -> None:
    """Corke's Robotics Toolbox for MATLAB, ``mdl_puma560``, at q = (1, 2, 3, 4, 5, 6) rad.

    ``p560.gravload(q)`` and ``p560.inertia(q)`` as printed (4 decimals) in the
    toolbox's documentation examples: an independent implementation of the same
    parameter set (armature included).
    """
    robot = sl.robots.load("puma560")
    q = np.arange(1.0, 7.0)
    gravload = [0.0000, -7.9683, 8.4581, -0.0197, 0.0027, 0.0]
    inertia = [
        [2.6152, -0.6550, -0.0363, 0.0001, 0.0010, 0.0000],
        [-0.6550, 4.3038, 0.2953, -0.0008, -0.0017, 0.0000],
        [-0.0363, 0.2953, 0.9366, -0.0009, -0.0006, 0.0000],
        [0.0001, -0.0008, -0.0009, 0.1926, 0.0000, 0.0000],
        [0.0010, -0.0017, -0.0006, 0.0000, 0.1713, 0.0000],
        [0.0000, 0.0000, 0.0000, 0.0000, 0.0000, 0.1941],
    ]
    np.testing.assert_allclose(robot.gravity(q), gravload, atol=5e-5)
    np.testing.assert_allclose(robot.mass_matrix(q), inertia, atol=5e-5)
