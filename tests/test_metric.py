"""Tests of :mod:`sensorless.metric` (thesis § 3.4, eq. 3.28/3.32, Tables 3.1–3.2).

The metric is checked against a brute-force evaluation written here with
plain loops over :meth:`RobotModel.regressor` and
:meth:`RobotModel.regressor_terms`, and by exact identities: zero bounds give
zero, the metric is linear in B_Θ̃, a time-reversed trajectory has the same
metric (Y depends on q̇ only through products q̇_i q̇_j), and on an arm without
gravity slowing a trajectory down by s divides the parameter part by s.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
import pinocchio as pin
import pytest

import sensorless as sl
from sensorless.exceptions import DimensionError, InputValueError, ModelError, UnknownNameError
from sensorless.filters import Butterworth, FiniteDifference, SavitzkyGolay
from sensorless.metric import (
    BoundTerms,
    error_bound_terms,
    estimation_metric,
    metric_terms,
    parameter_bounds,
    q_error_bounds,
    q_length,
    q_vector,
    rank_trajectories,
)
from sensorless.metric import bounds as bounds_module
from sensorless.robots.recursion import numba_available
from sensorless.trajectories import QuinticViaPoints

DT = 0.01
BACKENDS = ["numpy", "numba"] if numba_available() else ["numpy"]


@pytest.fixture(scope="module")
def planar() -> sl.RobotModel:
    return sl.robots.load("planar2")


@pytest.fixture(scope="module")
def horizontal() -> sl.RobotModel:
    """Two-link arm turning about the vertical axis: gravity does no work on it."""
    table = [
        {"alpha": 0.0, "a": 0.0, "theta": 0.0, "d": 0.0},
        {"alpha": 0.0, "a": 1.0, "theta": 0.0, "d": 0.0},
    ]
    links = [sl.LinkInertia(m, (0.5, 0.0, 0.0), np.diag([0.01, 0.1, 0.1]) * m) for m in (2.0, 1.0)]
    return sl.RobotModel.from_mdh(table, links, gravity=(0.0, 0.0, -9.81), name="horizontal")


@pytest.fixture(scope="module")
def puma() -> sl.RobotModel:
    return sl.robots.load("puma560")


@pytest.fixture(scope="module")
def puma_base(puma: sl.RobotModel) -> sl.BaseParameters:
    return sl.base_parameters(puma)


def via_points(n_dof: int, scale: float = 1.0) -> QuinticViaPoints:
    rng = np.random.default_rng(3)
    positions = rng.uniform(-1.0, 1.0, (4, n_dof))
    return QuinticViaPoints(scale * np.array([0.0, 1.0, 2.0, 3.0]), positions)


def sampled(trajectory: QuinticViaPoints, dt: float = DT) -> tuple[np.ndarray, ...]:
    return trajectory.sample(dt)


def brute_force(
    base: sl.BaseParameters,
    q: np.ndarray,
    qd: np.ndarray,
    qdd: np.ndarray,
    t: np.ndarray,
    bq: np.ndarray,
    relative: float,
    weights: np.ndarray,
    time_weight: np.ndarray,
) -> float:
    """Eq. 3.28 with explicit sums over time, joints, k and p (no vectorisation)."""
    robot = base.robot
    theta = base.values
    btheta = relative * np.abs(theta)
    columns = base.independent
    of = np.zeros(len(t))
    for i in range(len(t)):
        y_full = robot.regressor(q[i], qd[i], qdd[i])[:, columns]
        y_terms = robot.regressor_terms(q[i])[:, :, columns]
        for j in range(robot.n_dof):
            part_a = 0.0
            for k in range(y_terms.shape[0]):
                part_a += abs(float(y_terms[k, j] @ theta)) * bq[k]
            part_b = 0.0
            for p in range(theta.size):
                part_b += abs(y_full[j, p]) * btheta[p]
            of[i] += weights[j] * (part_a + part_b)
    total = 0.0
    for i in range(len(t) - 1):
        total += 0.5 * (t[i + 1] - t[i]) * (time_weight[i] * of[i] + time_weight[i + 1] * of[i + 1])
    return total


# ------------------------------------------------------------------------- Q vector


def test_q_vector_matches_the_robot_model(puma: sl.RobotModel) -> None:
    rng = np.random.default_rng(0)
    qd, qdd = rng.standard_normal((2, 5, 6))
    np.testing.assert_array_equal(q_vector(qd, qdd), puma.q_vector(qd, qdd))
    assert q_length(6) == 28 == q_vector(qd, qdd).shape[1]


def test_q_vector_rejects_mismatched_shapes() -> None:
    with pytest.raises(DimensionError, match="same shape"):
        q_vector(np.zeros((4, 2)), np.zeros((3, 2)))
    with pytest.raises(DimensionError, match=r"shape \(n_samples, n_dof\)"):
        q_vector(np.zeros(2), np.zeros(2))


# ------------------------------------------------------------------------- the metric


def test_metric_is_zero_without_error_bounds(planar: sl.RobotModel) -> None:
    t, q, qd, qdd = sampled(via_points(2))
    assert estimation_metric(planar, q, qd, qdd, t, np.zeros(6), 0.0) == 0.0
    assert not metric_terms(planar, q, qd, qdd, np.zeros(6), 0.0).any()


def test_metric_is_linear_in_parameter_bounds(planar: sl.RobotModel) -> None:
    t, q, qd, qdd = sampled(via_points(2))
    zero = np.zeros(6)
    em2 = estimation_metric(planar, q, qd, qdd, t, zero, 0.02)
    assert em2 > 0
    assert estimation_metric(planar, q, qd, qdd, t, zero, 0.06) == pytest.approx(3 * em2, 1e-12)
    rng = np.random.default_rng(1)
    n_base = sl.base_parameters(planar).count
    b1, b2 = rng.uniform(0, 0.1, (2, n_base))
    em_1 = estimation_metric(planar, q, qd, qdd, t, zero, b1)
    em_2 = estimation_metric(planar, q, qd, qdd, t, zero, b2)
    combined = estimation_metric(planar, q, qd, qdd, t, zero, 2.0 * b1 + 0.5 * b2)
    assert combined == pytest.approx(2.0 * em_1 + 0.5 * em_2, rel=1e-12)


def test_metric_equals_brute_force_evaluation(
    puma: sl.RobotModel, puma_base: sl.BaseParameters
) -> None:
    rng = np.random.default_rng(7)
    n = 6
    t = np.cumsum(rng.uniform(0.01, 0.02, n))
    q = rng.uniform(-1.5, 1.5, (n, 6))
    qd, qdd = rng.standard_normal((2, n, 6))
    bq = rng.uniform(0.0, 0.5, q_length(6))
    bq[-1] = 0.0
    weights = rng.uniform(0.5, 2.0, 6)
    time_weight = rng.uniform(0.5, 1.5, n)
    expected = brute_force(puma_base, q, qd, qdd, t, bq, 0.02, weights, time_weight)
    actual = estimation_metric(
        puma, q, qd, qdd, t, bq, 0.02, joint_weights=weights, time_weight=time_weight,
        chunk_size=4, base=puma_base,
    )  # fmt: skip
    assert actual == pytest.approx(expected, rel=1e-9)
    # a callable time weight gives the same as its values
    lookup = dict(zip(t.tolist(), time_weight.tolist(), strict=True))
    by_callable = estimation_metric(
        puma, q, qd, qdd, t, bq, 0.02, joint_weights=weights, base=puma_base,
        time_weight=lambda times: np.array([lookup[x] for x in times.tolist()]),
    )  # fmt: skip
    assert by_callable == pytest.approx(expected, rel=1e-9)


def test_chunked_terms_equal_whole(planar: sl.RobotModel) -> None:
    t, q, qd, qdd = sampled(via_points(2))
    bq = np.linspace(0.1, 0.6, 6)
    whole = metric_terms(planar, q, qd, qdd, bq, 0.02)
    chunked = metric_terms(planar, q, qd, qdd, bq, 0.02, chunk_size=7)
    np.testing.assert_allclose(chunked, whole, rtol=1e-14, atol=0)
    assert whole.shape == t.shape


def test_bound_terms_rebuild_the_regressor(
    puma: sl.RobotModel, puma_base: sl.BaseParameters
) -> None:
    """The parameter term uses Σ_k Y_k^q Q_k; compare with |Y| from regressor()."""
    rng = np.random.default_rng(2)
    q = rng.uniform(-1, 1, (3, 6))
    qd, qdd = rng.standard_normal((2, 3, 6))
    base = puma_base
    btheta = parameter_bounds(0.02, base.values)
    terms = error_bound_terms(puma, base.independent, base.values, q, qd, qdd, np.ones(28), btheta)
    assert isinstance(terms, BoundTerms)
    expected = np.abs(base.regressor(q, qd, qdd)) @ btheta
    np.testing.assert_allclose(terms.parameter_error, expected, rtol=1e-9)
    cross = np.einsum("tlnp,p->tn", np.abs(puma.regressor_terms(q)[..., base.independent]), btheta)
    np.testing.assert_allclose(terms.cross, cross, rtol=1e-12)


def test_time_reversed_trajectory_has_the_same_metric(planar: sl.RobotModel) -> None:
    t, q, qd, qdd = sampled(via_points(2))
    bq = np.array([0.3, 0.2, 1e-3, 2e-3, 1e-3, 0.0])
    forward = estimation_metric(planar, q, qd, qdd, t, bq, 0.02)
    backward = estimation_metric(planar, q[::-1], -qd[::-1], qdd[::-1], t, bq, 0.02)
    assert backward == pytest.approx(forward, rel=1e-12)


def test_slower_trajectory_without_gravity_scales_inversely(horizontal: sl.RobotModel) -> None:
    """Y = Σ Y_k Q_k with Q ∝ 1/s² and no gravity term; the time span grows by s."""
    s = 2.0
    zero = np.zeros(6)
    t, q, qd, qdd = sampled(via_points(2))
    t_s, q_s, qd_s, qdd_s = sampled(via_points(2, scale=s), dt=s * DT)
    np.testing.assert_allclose(q_s, q, atol=1e-12)
    fast = estimation_metric(horizontal, q, qd, qdd, t, zero, 0.02)
    slow = estimation_metric(horizontal, q_s, qd_s, qdd_s, t_s, zero, 0.02)
    assert slow == pytest.approx(fast / s, rel=1e-9)


def test_weights_scale_the_metric(planar: sl.RobotModel) -> None:
    t, q, qd, qdd = sampled(via_points(2))
    bq = np.array([0.3, 0.2, 1e-3, 2e-3, 1e-3, 0.0])
    em = estimation_metric(planar, q, qd, qdd, t, bq, 0.02)
    per_joint = [
        estimation_metric(planar, q, qd, qdd, t, bq, 0.02, joint_weights=w)
        for w in ([1.0, 0.0], [0.0, 1.0])
    ]
    assert sum(per_joint) == pytest.approx(em, rel=1e-12)
    assert estimation_metric(planar, q, qd, qdd, t, bq, 0.02, time_weight=3.0) == pytest.approx(
        3 * em, rel=1e-12
    )
    early = estimation_metric(
        planar, q, qd, qdd, t, bq, 0.02, time_weight=lambda times: (times < 1.5).astype(float)
    )
    assert 0 < early < em


# ------------------------------------------------------------------------- ranking


def test_rank_trajectories_slower_first_without_gravity(horizontal: sl.RobotModel) -> None:
    trajectories = {"fast": via_points(2), "slow": via_points(2, scale=2.0)}
    table = rank_trajectories(horizontal, trajectories, DT, bq=np.zeros(6))
    assert list(table.index) == ["slow", "fast"]
    assert table.index.name == "trajectory"
    assert table["rank"].tolist() == [1, 2]
    # on the common grid dt the trapezoid rule is not exact, so allow its error
    ratio = table.loc["fast", "metric"] / table.loc["slow", "metric"]
    assert ratio == pytest.approx(2.0, rel=1e-3)


def test_rank_trajectories_table(planar: sl.RobotModel) -> None:
    rng = np.random.default_rng(5)
    trajectories = {
        f"traj{i}": QuinticViaPoints([0.0, 1.0, 2.0], rng.uniform(-1, 1, (3, 2))) for i in range(3)
    }
    table = rank_trajectories(
        planar, trajectories, 1e-3, noise_std=1e-5, estimator=Butterworth(1e-3, 20.0)
    )
    assert isinstance(table, pd.DataFrame)
    assert set(table.index) == set(trajectories)
    assert table["metric"].is_monotonic_increasing
    assert table["rank"].tolist() == [1, 2, 3]
    np.testing.assert_allclose(
        table["metric"], table["q_error_part"] + table["parameter_part"], rtol=1e-12
    )
    assert (table["q_error_part"] > 0).all() and (table["max_bq_acceleration"] > 0).all()
    again = rank_trajectories(
        planar, trajectories, 1e-3, noise_std=1e-5, estimator=Butterworth(1e-3, 20.0)
    )
    pd.testing.assert_frame_equal(table, again)


def test_rank_trajectories_errors(planar: sl.RobotModel) -> None:
    with pytest.raises(InputValueError, match="trajectories is empty"):
        rank_trajectories(planar, {}, DT)
    with pytest.raises(DimensionError, match="has 6 joints; the robot has 2"):
        rank_trajectories(planar, {"a": via_points(6)}, DT, bq=np.zeros(6))
    with pytest.raises(TypeError, match="must be a Trajectory"):
        rank_trajectories(planar, {"a": "line"}, DT)  # type: ignore[dict-item]


# ------------------------------------------------------------------------- B_Q̃


def polynomial(n: int = 300, dt: float = DT) -> tuple[np.ndarray, ...]:
    t = np.arange(n)[:, None] * dt
    q = np.hstack([0.5 * t**2 - 0.2 * t, -(t**2) + 0.1])
    qd = np.hstack([t - 0.2, -2 * t])
    qdd = np.tile([1.0, -2.0], (n, 1))
    return q, qd, qdd


def test_q_error_bounds_noise_free_finite_difference_is_small() -> None:
    q, qd, qdd = polynomial()
    bounds = q_error_bounds(
        q, DT, FiniteDifference(DT), noise_std=0.0, reference=(qd, qdd), transient=2 * DT
    )
    assert bounds.shape == (6,)
    assert bounds[-1] == 0.0
    # backward differences of a quadratic: exact q̈ after two samples, and q̇(t - dt/2)
    shifted = q_vector(qd - 0.5 * DT * qdd, qdd) - q_vector(qd, qdd)
    np.testing.assert_allclose(bounds, np.abs(shifted[2:]).max(axis=0), atol=1e-9)
    np.testing.assert_allclose(bounds[:2], 0.0, atol=1e-9)
    # without skipping, the start at rest (q̇ = 0 while the true q̇ = -0.2) shows up
    raw = q_error_bounds(q, DT, FiniteDifference(DT), noise_std=0.0, reference=(qd, qdd))
    assert raw.max() > bounds.max()


def test_q_error_bounds_default_reference_matches_exact() -> None:
    q, qd, qdd = polynomial()
    est = Butterworth(DT, cutoff=5.0)
    exact = q_error_bounds(q, DT, est, noise_std=1e-4, reference=(qd, qdd), seed=4)
    numeric = q_error_bounds(q, DT, est, noise_std=1e-4, seed=4)
    np.testing.assert_allclose(numeric, exact, rtol=1e-6, atol=1e-9)


def test_q_error_bounds_grow_with_noise_and_are_seeded() -> None:
    # a ramp: once the start-up is over the Butterworth estimate is exact, so only
    # the noise, scaled by noise_std with the same seed, makes Q̂ wrong
    t = np.arange(1000)[:, None] * 1e-3
    q = np.hstack([0.3 * t, -0.5 * t])
    qd, qdd = np.tile([0.3, -0.5], (1000, 1)), np.zeros((1000, 2))
    est = Butterworth(1e-3, cutoff=20.0)
    kwargs = {"reference": (qd, qdd), "transient": 0.4}
    exact = q_error_bounds(q, 1e-3, est, noise_std=0.0, seed=1, **kwargs)
    low = q_error_bounds(q, 1e-3, est, noise_std=1e-6, seed=1, **kwargs)
    high = q_error_bounds(q, 1e-3, est, noise_std=1e-4, seed=1, **kwargs)
    assert exact.max() < 1e-4
    assert (high[:-1] > 10 * low[:-1]).all()
    np.testing.assert_allclose(high[:2], 100 * low[:2], rtol=0.05)  # q̈ error is linear in noise
    np.testing.assert_array_equal(
        q_error_bounds(q, 1e-3, est, noise_std=1e-4, seed=1, **kwargs), high
    )
    other = q_error_bounds(q, 1e-3, est, noise_std=1e-4, seed=2, **kwargs)
    assert not np.array_equal(other, high)
    per_joint = q_error_bounds(q, 1e-3, est, noise_std=[1e-4, 0.0], seed=1, **kwargs)
    assert per_joint[1] < high[1]


def test_q_error_bounds_errors() -> None:
    q, qd, qdd = polynomial(50)
    est = FiniteDifference(DT)
    with pytest.raises(InputValueError, match=r"designed for dt = 0\.01 s"):
        q_error_bounds(q, 0.02, est, noise_std=0.0)
    with pytest.raises(TypeError, match="causal estimator"):
        q_error_bounds(q, DT, SavitzkyGolay(DT, 5), noise_std=0.0)  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match="noise_std must be finite and >= 0"):
        q_error_bounds(q, DT, est, noise_std=-1.0)
    with pytest.raises(DimensionError, match=r"noise_std must be a scalar or have shape \(2,\)"):
        q_error_bounds(q, DT, est, noise_std=[0.0, 0.0, 0.0])
    with pytest.raises(InputValueError, match="0 <= transient < n_samples"):
        q_error_bounds(q, DT, est, noise_std=0.0, transient=1.0)
    with pytest.raises(DimensionError, match="must have the shape of q"):
        q_error_bounds(q, DT, est, noise_std=0.0, reference=(qd[:-1], qdd[:-1]))
    with pytest.raises(DimensionError, match="pair"):
        q_error_bounds(q, DT, est, noise_std=0.0, reference=(qd,))  # type: ignore[arg-type]
    with pytest.raises(DimensionError, match="at least 3 samples"):
        q_error_bounds(q[:2], DT, est, noise_std=0.0)
    with pytest.raises(InputValueError, match="positive"):
        q_error_bounds(q, -1.0, est, noise_std=0.0)


# --------------------------------------------------------------------- terms, fast and reference


def _reference_bound_terms(
    robot: sl.RobotModel,
    columns: np.ndarray,
    theta: np.ndarray,
    q: np.ndarray,
    qd: np.ndarray,
    qdd: np.ndarray,
    bq: np.ndarray,
    btheta: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The terms as computed before issue 14: products of the split regressor of l unit states."""
    n_samples, n_dof = q.shape
    terms = robot.regressor_terms(q)[..., columns]  # (c, l, n, p)
    q_error = np.abs(terms @ theta).transpose(0, 2, 1) @ bq
    cross = (np.abs(terms) @ btheta).transpose(0, 2, 1) @ bq
    flat = terms.reshape(n_samples, terms.shape[1], -1)
    regressor = (q_vector(qd, qdd)[:, None, :] @ flat).reshape(n_samples, n_dof, -1)
    return q_error, cross, np.abs(regressor) @ btheta


def tree_robot() -> sl.RobotModel:
    """A branching arm: revolute joints about x, y and a skew axis, two prismatic joints."""
    rng = np.random.default_rng(11)
    model = pin.Model()
    model.name = "tree"
    joints = [
        (0, pin.JointModelRX()),
        (1, pin.JointModelPY()),
        (1, pin.JointModelRevoluteUnaligned(*(np.array([1.0, 2.0, 2.0]) / 3.0))),
        (3, pin.JointModelPrismaticUnaligned(*(np.array([2.0, -1.0, 2.0]) / 3.0))),
        (3, pin.JointModelRY()),
    ]
    for index, (parent, joint) in enumerate(joints, start=1):
        rotation = pin.rpy.rpyToMatrix(*rng.uniform(-1.0, 1.0, 3))
        placement = pin.SE3(rotation, rng.uniform(-0.3, 0.3, 3))
        jid = model.addJoint(parent, joint, placement, f"joint{index}")
        spread = rng.standard_normal((3, 3))
        inertia = pin.Inertia(
            rng.uniform(0.5, 2.0), rng.uniform(-0.2, 0.2, 3), spread @ spread.T + 0.1 * np.eye(3)
        )
        model.appendBodyToJoint(jid, inertia, pin.SE3.Identity())
    model.armature = rng.uniform(0.01, 0.1, len(joints))
    return sl.RobotModel.from_pinocchio(model)


def random_states(n_dof: int, n_samples: int = 40) -> tuple[np.ndarray, ...]:
    rng = np.random.default_rng(5)
    q, qd, qdd = rng.uniform(-3.0, 3.0, (3, n_samples, n_dof))
    bq = rng.uniform(0.0, 1.0, q_length(n_dof))
    bq[-1] = 0.0
    return q, qd, qdd, bq


@pytest.mark.parametrize("backend", BACKENDS)
@pytest.mark.parametrize("name", ["puma560", "panda"])
def test_bound_terms_equal_the_split_regressor(name: str, backend: str) -> None:
    """Kinematic terms = products of RobotModel.regressor_terms (l Pinocchio calls per sample)."""
    robot = sl.robots.load(name)
    base = sl.base_parameters(robot)
    q, qd, qdd, bq = random_states(robot.n_dof)
    btheta = parameter_bounds(0.02, base.values)
    args = (robot, base.independent, base.values, q, qd, qdd, bq, btheta)
    terms = error_bound_terms(*args, backend=backend, chunk_size=16)
    for actual, expected in zip(terms, _reference_bound_terms(*args), strict=True):
        assert np.all(expected > 0)
        np.testing.assert_allclose(actual, expected, rtol=1e-10, atol=0)


@pytest.mark.parametrize("backend", BACKENDS)
def test_bound_terms_of_a_tree_with_prismatic_joints(backend: str) -> None:
    """Every standard column, revolute and prismatic joints on any axis, two branches."""
    robot = tree_robot()
    columns = np.arange(robot.n_dof * 11)
    btheta = np.random.default_rng(2).uniform(0.0, 0.1, columns.size)
    q, qd, qdd, bq = random_states(robot.n_dof)
    args = (robot, columns, robot.parameter_vector(), q, qd, qdd, bq, btheta)
    terms = error_bound_terms(*args, backend=backend, chunk_size=16)
    for actual, expected in zip(terms, _reference_bound_terms(*args), strict=True):
        np.testing.assert_allclose(actual, expected, rtol=1e-10, atol=0)


def test_bound_terms_backends_and_chunks_agree(
    puma: sl.RobotModel, puma_base: sl.BaseParameters
) -> None:
    q, qd, qdd, bq = random_states(6, n_samples=50)
    columns, theta = puma_base.independent, puma_base.values
    btheta = parameter_bounds(0.02, theta)
    whole = error_bound_terms(puma, columns, theta, q, qd, qdd, bq, btheta, backend="numpy")
    for backend, chunk in [("numpy", 7), ("auto", 7), (BACKENDS[-1], 1)]:
        terms = error_bound_terms(
            puma, columns, theta, q, qd, qdd, bq, btheta, backend=backend, chunk_size=chunk
        )
        np.testing.assert_allclose(np.array(terms), np.array(whole), rtol=1e-13, atol=0)
    for backend in BACKENDS:
        empty = error_bound_terms(
            puma, columns, theta, q[:0], qd[:0], qdd[:0], bq, btheta, backend=backend
        )
        assert all(term.shape == (0, 6) for term in empty)


def test_bound_terms_errors(
    puma: sl.RobotModel, puma_base: sl.BaseParameters, monkeypatch: pytest.MonkeyPatch
) -> None:
    q, qd, qdd, bq = random_states(6, n_samples=3)
    btheta = parameter_bounds(0.02, puma_base.values)
    args = (puma, puma_base.independent, puma_base.values, q, qd, qdd, bq, btheta)
    with pytest.raises(UnknownNameError, match=r"unknown backend 'gpu'; options: \['auto'"):
        error_bound_terms(*args, backend="gpu")
    with pytest.raises(InputValueError, match="chunk_size must be an integer >= 1"):
        error_bound_terms(*args, chunk_size=0)
    expected = error_bound_terms(*args, backend="numpy")
    monkeypatch.setattr(bounds_module, "_numba_kernel", None)
    with pytest.raises(InputValueError, match="backend 'numba' needs numba"):
        error_bound_terms(*args, backend="numba")
    np.testing.assert_array_equal(np.array(error_bound_terms(*args)), np.array(expected))


@pytest.mark.parametrize(
    ("joint", "gravity", "message"),
    [
        (pin.JointModelHZ(0.1), np.zeros(3), "is a JointModelHZ; the bound terms handle one-DoF"),
        (pin.JointModelTranslation(), np.zeros(3), "is a JointModelTranslation"),
        (pin.JointModelRZ(), np.ones(3), "must be a pure linear field"),
    ],
)
def test_bound_terms_need_revolute_or_prismatic_joints(
    joint: pin.JointModel, gravity: np.ndarray, message: str
) -> None:
    model = pin.Model()
    jid = model.addJoint(0, joint, pin.SE3.Identity(), "joint")
    model.appendBodyToJoint(jid, pin.Inertia(1.0, np.zeros(3), np.eye(3)), pin.SE3.Identity())
    model.gravity = pin.Motion(np.array([0.0, 0.0, -9.81]), gravity)
    robot = sl.RobotModel.from_pinocchio(model)
    n = robot.n_dof
    zero = np.zeros((1, n))
    with pytest.raises(ModelError, match=message):
        error_bound_terms(robot, [0], [1.0], zero, zero, zero, np.zeros(q_length(n)), np.ones(1))


# ------------------------------------------------------------------------- validation


def test_metric_input_errors(planar: sl.RobotModel, puma_base: sl.BaseParameters) -> None:
    t, q, qd, qdd = sampled(via_points(2))
    zero = np.zeros(6)
    with pytest.raises(DimensionError, match=r"bq must have shape \(6,\)"):
        estimation_metric(planar, q, qd, qdd, t, np.zeros(5), 0.0)
    with pytest.raises(InputValueError, match="bq must be finite and >= 0"):
        estimation_metric(planar, q, qd, qdd, t, -np.ones(6), 0.0)
    with pytest.raises(InputValueError, match="relative bound must be a finite number >= 0"):
        estimation_metric(planar, q, qd, qdd, t, zero, -0.1)
    with pytest.raises(DimensionError, match="one bound per base parameter"):
        estimation_metric(planar, q, qd, qdd, t, zero, np.ones(3))
    with pytest.raises(InputValueError, match="joint_weights must be finite and >= 0"):
        estimation_metric(planar, q, qd, qdd, t, zero, 0.0, joint_weights=[1.0, -1.0])
    with pytest.raises(DimensionError, match="time_weight must give one weight per sample"):
        estimation_metric(planar, q, qd, qdd, t, zero, 0.0, time_weight=np.ones(3))
    with pytest.raises(InputValueError, match="time_weight must be finite and >= 0"):
        estimation_metric(planar, q, qd, qdd, t, zero, 0.0, time_weight=-1.0)
    with pytest.raises(InputValueError, match="strictly increasing"):
        estimation_metric(planar, q, qd, qdd, t[::-1], zero, 0.0)
    with pytest.raises(DimensionError, match="t must have shape"):
        estimation_metric(planar, q, qd, qdd, t[:-1], zero, 0.0)
    with pytest.raises(DimensionError, match="same shape"):
        estimation_metric(planar, q, qd[:-1], qdd, t, zero, 0.0)
    with pytest.raises(DimensionError, match="for a robot with 2 joints"):
        estimation_metric(planar, np.zeros((3, 6)), qd, qdd, t, zero, 0.0)
    with pytest.raises(DimensionError, match="base parameters are for 6 joints"):
        estimation_metric(planar, q, qd, qdd, t, zero, 0.0, base=puma_base)
    with pytest.raises(TypeError, match="robot must be a RobotModel"):
        estimation_metric("planar2", q, qd, qdd, t, zero, 0.0)  # type: ignore[arg-type]
    with pytest.raises(InputValueError, match="chunk_size must be an integer >= 1"):
        estimation_metric(planar, q, qd, qdd, t, zero, 0.0, chunk_size=0)
