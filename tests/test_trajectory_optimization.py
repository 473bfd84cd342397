"""Tests of :func:`sensorless.metric.optimize_trajectory` (thesis § 3.4) and its spline.

Independent checks: a one-joint problem whose optimum is derived in closed
form from the Euler–Lagrange equation 3.31; the limits, boundary conditions
and via points re-checked on a grid ten times denser than the collocation
grid with :meth:`RobotModel.inverse_dynamics`; EM recomputed by
:func:`sensorless.metric.estimation_metric` (a second code path) for the
quintic and the result; the per-sample gradient against central differences
of the value and the compiled kernel against its numpy form; the spline
against central differences of itself.
"""

from __future__ import annotations

import numpy as np
import pytest
from scipy.optimize import brentq

import sensorless as sl
from sensorless.exceptions import DimensionError, InputTypeError, InputValueError, UnknownNameError
from sensorless.filters import Butterworth
from sensorless.metric import (
    estimation_metric,
    load_plan,
    optimize_trajectory,
    parameter_bounds,
    q_error_bounds,
)
from sensorless.metric._lag import LagModel
from sensorless.metric._objective import SmoothIntegrand
from sensorless.metric._transcription import basis, clamped_knots
from sensorless.robots.model import LinkInertia
from sensorless.simulation.controllers import ComputedTorque
from sensorless.simulation.plants import RigidPlant
from sensorless.simulation.simulator import simulate
from sensorless.trajectories import QuinticViaPoints, SplineTrajectory, Trajectory

Q_START, Q_END, DURATION = np.array([0.0, 0.0]), np.array([1.0, -0.5]), 2.0


@pytest.fixture(scope="module")
def planar() -> sl.RobotModel:
    return sl.robots.load("planar2")


def turntable() -> sl.RobotModel:
    """One revolute joint about the vertical: gravity does no work, Y = q̈ for ZZ1R."""
    link = LinkInertia(2.0, (-0.25, 0.0, 0.0), np.diag([0.01, 0.05, 0.05]))
    table = [{"d": 0.0, "a": 0.5, "alpha": 0.0, "theta": 0.0}]
    return sl.RobotModel.from_dh(table, [link], name="turntable", position_limits=([-3.0], [3.0]))


@pytest.fixture(scope="module")
def limited(planar: sl.RobotModel) -> dict[str, object]:
    """Limits that bind: the quintic's own peak torque at joint 1, tight speeds and range."""
    quintic = QuinticViaPoints([0.0, DURATION], [Q_START, Q_END])
    tau = planar.inverse_dynamics(*quintic.evaluate(np.linspace(0.0, DURATION, 2001)))
    return {
        "position_limits": ([-0.1, -0.6], [1.05, 0.05]),
        "velocity_limits": [0.8, 0.6],
        "acceleration_limits": [2.5, 2.0],
        "torque_limits": np.abs(tau).max(axis=0) * [1.0, 1.2],
    }


@pytest.fixture(scope="module")
def plan(planar: sl.RobotModel) -> sl.metric.PlannedTrajectory:
    return optimize_trajectory(planar, Q_START, Q_END, DURATION)


def test_one_joint_optimum_matches_the_closed_form() -> None:
    """The optimum of eq. 3.29 for one joint, derived from eq. 3.31.

    For one revolute joint about the vertical, g(q) = 0, C = 0 and the only
    base parameter is the inertia about the axis, with Y = q̈. With B_Q̃ = 0,

        OBJ[q] = β ∫ f(q̈) dt,  f(x) = (ε + x²)^½ (eq. 3.30),  β = B_Θ̃ = 0.02 Θ̂.

    L depends on q̈ only, so eq. 3.31 reads d²/dt² ∂L/∂q̈ = 0: ∂L/∂q̈ =
    β q̈ / (ε + q̈²)^½ is affine in t. Write q̈/(ε + q̈²)^½ = u(t) = a + b t with
    |u| < 1, i.e. q̈ = √ε u / √(1 − u²). The ends fix q and q̇ = 0 (q̈ is
    free), four conditions for the fourth-order equation. q̇(T) − q̇(0) =
    ∫ q̈ dt = [−√ε √(1 − u²) / b] from u(0) to u(T) = 0 gives u(T) = −u(0),
    so u = κ (1 − 2t/T) with κ = u(0) ∈ (0, 1) for q_f > q_s. Integrating
    twice, with G(u) = (u √(1 − u²) + arcsin u) / 2 (a primitive of √(1 − u²)),

        q̇(t) = √ε T/(2κ) (√(1 − u²) − √(1 − κ²)),
        q(t) = q_s + √ε T/(2κ) [ T/(2κ) (G(κ) − G(u)) − t √(1 − κ²) ],

    and q(T) = q_f gives Δq = √ε T²/(4κ²) (arcsin κ − κ √(1 − κ²)), an
    increasing function of κ, solved for κ by bisection. The optimum is
    OBJ* = β √ε ∫ dt/√(1 − u²) = β √ε T arcsin(κ)/κ. (L is convex in q̈ and
    q̈ is linear in the control points, so the discrete problem is convex.)
    """
    robot = turntable()
    eps, total, q_f = 1.0, 2.0, 0.5

    def travel(kappa: float) -> float:
        return (
            np.sqrt(eps)
            * total**2
            / (4 * kappa**2)
            * (np.arcsin(kappa) - kappa * np.sqrt(1 - kappa**2))
        )

    kappa = brentq(lambda k: travel(k) - q_f, 1e-6, 1.0 - 1e-12)

    def primitive(u: np.ndarray) -> np.ndarray:
        return (u * np.sqrt(1 - u**2) + np.arcsin(u)) / 2

    def exact(t: np.ndarray) -> np.ndarray:
        u = kappa * (1 - 2 * t / total)
        scale = np.sqrt(eps) * total / (2 * kappa)
        return scale * (
            total / (2 * kappa) * (primitive(kappa) - primitive(u)) - t * np.sqrt(1 - kappa**2)
        )

    theta = sl.base_parameters(robot).values_of(robot)
    optimum = 0.02 * abs(theta[0]) * np.sqrt(eps) * total * np.arcsin(kappa) / kappa
    result = optimize_trajectory(
        robot, [0.0], [q_f], total, qdd_start=None, qdd_end=None, bq=np.zeros(3), epsilon=eps,
        n_control=14, n_grid=401,
    )  # fmt: skip
    t = np.linspace(0.0, total, 201)
    assert np.abs(result.trajectory.evaluate(t)[0][:, 0] - exact(t)).max() < 2e-5
    assert result.objective == pytest.approx(optimum, rel=1e-5)
    assert result.initial_objective > 1.02 * optimum  # the quintic is measurably worse


def table_31(trajectory: Trajectory, dt: float, seed: int, n_draws: int) -> np.ndarray:
    """B_Q̃ by Table 3.1, the largest over the draws seeded by SeedSequence(seed).spawn(n_draws)."""
    _, q, qd, qdd = trajectory.sample(dt)
    estimator = Butterworth(dt, cutoff=20.0, order=5)
    seeds = [int(c.generate_state(1)[0]) for c in np.random.SeedSequence(seed).spawn(n_draws)]
    bounds = [
        q_error_bounds(q, dt, estimator, noise_std=1e-5, seed=s, reference=(qd, qdd)) for s in seeds
    ]
    return np.max(bounds, axis=0)


def test_result_beats_the_quintic_and_em_is_recomputed(
    planar: sl.RobotModel, plan: sl.metric.PlannedTrajectory
) -> None:
    """EM of both trajectories again, each with its own B_Q̃ by Table 3.1 (8 draws of seed 0)."""
    assert plan.success, plan.message
    assert plan.metric < plan.initial_metric
    for trajectory, metric, bq in (
        (plan.initial, plan.initial_metric, plan.initial_bq),
        (plan.trajectory, plan.metric, plan.bq),
    ):
        bounds = table_31(trajectory, plan.dt, seed=0, n_draws=8)
        np.testing.assert_allclose(bq, bounds, rtol=1e-12)
        t, q, qd, qdd = trajectory.sample(plan.dt)
        assert metric == pytest.approx(estimation_metric(planar, q, qd, qdd, t, bounds, 0.02))
    assert plan.bound.shape == plan.initial_bound.shape == (plan.t.size, 2)
    # Both ends as asked: the quintic's positions, rest.
    for time, position in ((0.0, Q_START), (DURATION, Q_END)):
        q, qd, qdd = plan.trajectory.evaluate(time)
        np.testing.assert_allclose(q, position, atol=1e-12)
        np.testing.assert_allclose(np.hstack([qd, qdd]), 0.0, atol=1e-9)


def test_lag_model_reproduces_the_table_31_errors() -> None:
    """The planner's B_Q̃ model against filtering the noisy samples (q_error_bounds)."""
    dt, duration, n_control = 1e-3, 1.5, 9
    rng = np.random.default_rng(8)
    knots = clamped_knots(duration, n_control)
    points = rng.uniform(-1.0, 1.0, (n_control, 2))
    spline = SplineTrajectory(knots, points)
    t, q, qd, qdd = spline.sample(dt)
    estimator = Butterworth(dt, cutoff=20.0, order=5)
    noise = np.array([np.random.default_rng(s).standard_normal(q.shape) * 1e-5 for s in (3, 4)])
    values = tuple(basis(knots, t, order) for order in range(3))
    lag = LagModel.build(values, np.eye(n_control), np.zeros((n_control, 2)), estimator, noise)
    errors = lag.errors(points.ravel())
    for draw, seed in enumerate((3, 4)):
        expected = q_error_bounds(q, dt, estimator, noise_std=1e-5, seed=seed, reference=(qd, qdd))
        np.testing.assert_allclose(np.abs(errors[draw]).max(axis=0), expected[:-1], rtol=1e-9)
    draws, rows, entries = np.array([0, 1, 1]), np.array([10, 700, 1400]), np.array([0, 2, 4])
    z, step = points.ravel(), 1e-6
    gradient = lag.gradient(z, draws, rows, entries).reshape(3, -1)
    for index in range(z.size):
        shift = np.zeros(z.size)
        shift[index] = step
        central = lag.at(z + shift, draws, rows, entries) - lag.at(z - shift, draws, rows, entries)
        np.testing.assert_allclose(gradient[:, index], central / (2 * step), rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(lag.at(z, draws, rows, entries), errors[draws, rows, entries])


def test_six_joint_arm_within_its_limits_beats_the_quintic() -> None:
    robot = sl.robots.load("puma560")
    lower, upper = robot.position_limits
    start, end = lower + 0.3 * (upper - lower), lower + 0.6 * (upper - lower)
    result = optimize_trajectory(robot, start, end, 2.0, n_control=8)
    assert result.success, result.message
    assert result.metric < result.initial_metric
    assert result.bound.mean() < result.initial_bound.mean()
    t = np.linspace(0.0, 2.0, 801)
    q = result.trajectory.evaluate(t)[0]
    assert (q >= lower).all() and (q <= upper).all()


@pytest.mark.parametrize("via", [False, True])
def test_limits_hold_on_a_grid_ten_times_denser(
    planar: sl.RobotModel, limited: dict[str, object], via: bool
) -> None:
    extra = {"via_times": [1.0], "via_positions": [[0.4, -0.1]]} if via else {}
    n_grid = 81
    result = optimize_trajectory(
        planar, Q_START, Q_END, DURATION, n_grid=n_grid, **limited, **extra
    )  # type: ignore[arg-type]
    assert result.success, result.message
    t = np.linspace(0.0, DURATION, 10 * (n_grid - 1) + 1)
    q, qd, qdd = result.trajectory.evaluate(t)
    lower, upper = (np.asarray(x) for x in limited["position_limits"])  # type: ignore[attr-defined]
    assert (q >= lower).all() and (q <= upper).all()
    assert (np.abs(qd) <= limited["velocity_limits"]).all()
    assert (np.abs(qdd) <= limited["acceleration_limits"]).all()
    assert (np.abs(planar.inverse_dynamics(q, qd, qdd)) <= limited["torque_limits"]).all()
    if via:
        np.testing.assert_allclose(result.trajectory.evaluate(1.0)[0], [0.4, -0.1], atol=1e-9)


def test_same_seed_and_start_give_the_same_result(planar: sl.RobotModel) -> None:
    runs = [
        optimize_trajectory(planar, Q_START, Q_END, DURATION, seed=3, n_starts=2, n_control=8)
        for _ in range(2)
    ]
    np.testing.assert_array_equal(
        runs[0].trajectory.control_points, runs[1].trajectory.control_points
    )
    np.testing.assert_array_equal(runs[0].bq, runs[1].bq)
    assert runs[0].metric == runs[1].metric
    other = optimize_trajectory(planar, Q_START, Q_END, DURATION, seed=4, n_starts=2, n_control=8)
    assert not np.array_equal(other.bq, runs[0].bq)  # the seed reaches B_Q̃'s noise


def test_gradient_matches_differences_and_backends_agree(planar: sl.RobotModel) -> None:
    pytest.importorskip("numba")
    robot = sl.robots.load("puma560")
    n = robot.n_dof
    base = sl.base_parameters(robot)
    theta = base.values_of(robot)
    rng = np.random.default_rng(5)
    bq = rng.uniform(0.0, 1e-2, (n * n + 3 * n + 2) // 2)
    weights = rng.uniform(0.5, 2.0, n)
    q, qd, qdd = rng.uniform(-1.0, 1.0, (3, 6, n))
    args = (robot, base.independent, theta, parameter_bounds(0.02, theta), bq, weights, 1e-2)
    compiled, plain = SmoothIntegrand(*args, "numba"), SmoothIntegrand(*args, "numpy")
    value, gradient, parts = compiled(q, qd, qdd)
    value_np, gradient_np, parts_np = plain(q, qd, qdd)
    np.testing.assert_allclose(parts, parts_np, rtol=1e-12)
    # L is affine in B_Q̃ with slope parts: a second value at another B_Q̃.
    other = compiled(q, qd, qdd, False, 2.0 * bq)[0]
    np.testing.assert_allclose(other - value, parts @ bq, rtol=1e-9)
    np.testing.assert_allclose(value, value_np, rtol=1e-12)
    # ∂L/∂q is a forward difference: its round-off (~1e-16 L / 1e-7) differs between the two.
    np.testing.assert_allclose(gradient, gradient_np, rtol=1e-6, atol=1e-7)
    step, states = 1e-6, (q, qd, qdd)
    for which in range(3):
        for j in range(n):
            up = [x.copy() for x in states]
            down = [x.copy() for x in states]
            up[which][:, j] += step
            down[which][:, j] -= step
            central = (compiled(*up, False)[0] - compiled(*down, False)[0]) / (2 * step)
            np.testing.assert_allclose(gradient[:, which, j], central, rtol=1e-4, atol=1e-6)


def test_plan_file_round_trip(plan: sl.metric.PlannedTrajectory, tmp_path) -> None:
    path = plan.to_yaml(tmp_path / "plan.yaml")
    again = load_plan(path)
    t = np.linspace(0.0, DURATION, 57)
    for a, b in zip(again.evaluate(t), plan.trajectory.evaluate(t), strict=True):
        np.testing.assert_array_equal(a, b)
    bare = tmp_path / "bare.yaml"
    bare.write_text(
        "type: bspline\nknots: [0, 0, 1, 1]\ncontrol_points: [[0.0], [1.0]]\ndegree: 1\n"
    )
    assert load_plan(bare).evaluate(0.5)[0][0] == pytest.approx(0.5)
    broken = tmp_path / "broken.yaml"
    broken.write_text("- just\n- a list\n")
    with pytest.raises(InputValueError, match="holds no trajectory specification"):
        load_plan(broken)


def test_the_simulator_follows_a_planned_trajectory(
    planar: sl.RobotModel, plan: sl.metric.PlannedTrajectory
) -> None:
    controller = ComputedTorque(kp=400.0, kd=40.0, ki=0.0, model=planar)
    run = simulate(RigidPlant(planar), controller, plan.trajectory, 0.5, dt=1e-3, seed=1)
    np.testing.assert_allclose(run.desired, plan.trajectory.evaluate(run.log.t)[0])
    assert np.abs(run.log.q - run.desired).max() < 1e-3


def test_spline_derivatives_and_specification() -> None:
    rng = np.random.default_rng(2)
    knots = np.r_[np.zeros(6), 0.7, 1.1, 2.0, np.full(6, 3.0)]
    spline = SplineTrajectory(knots, rng.uniform(-1.0, 1.0, (9, 2)))
    t, h = np.linspace(0.1, 2.9, 15), 1e-5
    _, qd, qdd = spline.evaluate(t)
    np.testing.assert_allclose(
        qd, (spline.evaluate(t + h)[0] - spline.evaluate(t - h)[0]) / (2 * h), atol=1e-7
    )
    np.testing.assert_allclose(
        qdd, (spline.evaluate(t + h)[1] - spline.evaluate(t - h)[1]) / (2 * h), atol=1e-6
    )
    assert SplineTrajectory.from_dict(spline.to_dict()).to_dict() == spline.to_dict()
    held = spline.evaluate(3.5)
    np.testing.assert_array_equal(held[0], spline.control_points[-1])
    np.testing.assert_array_equal(held[1], 0.0)


@pytest.mark.parametrize(
    ("spec", "error", "match"),
    [
        ([1, 2], InputTypeError, "must be a mapping"),
        (
            {"knots": [0, 0, 1, 1], "control_points": [[0], [1]], "order": 1},
            InputTypeError,
            "unknown keys",
        ),
        ({"knots": [0, 0, 1, 1]}, InputValueError, "missing"),
        (
            {"type": "fourier", "knots": [0, 0, 1, 1], "control_points": [[0], [1]]},
            InputValueError,
            "bspline",
        ),
        (
            {"knots": [0, 0, 1, 1], "control_points": [[0], [1]], "degree": 0},
            InputValueError,
            "degree",
        ),
        ({"knots": [0, 0, 1], "control_points": [[0], [1]], "degree": 1}, DimensionError, "knots"),
        (
            {"knots": [0, 0.5, 1, 1], "control_points": [[0], [1]], "degree": 1},
            InputValueError,
            "clamped",
        ),
        (
            {"knots": [0, 0, 1, 1], "control_points": [[0], [90]], "degree": 1},
            InputValueError,
            "degrees",
        ),
        (
            {"knots": [0, 0, 1, 1], "control_points": [[0], [np.nan]], "degree": 1},
            InputValueError,
            "finite",
        ),
    ],
)
def test_spline_specification_errors(spec: object, error: type, match: str) -> None:
    with pytest.raises(error, match=match):
        SplineTrajectory.from_dict(spec)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("change", "error", "match"),
    [
        ({"q_start": [0.0, 0.0, 0.0]}, DimensionError, r"q_start must have shape \(2,\)"),
        ({"q_end": [1.0, np.nan]}, InputValueError, "q_end must be finite"),
        ({"duration": 0.0}, InputValueError, "duration must be a finite number > 0"),
        ({"duration": -1.0}, InputValueError, "duration must be a finite number > 0"),
        ({"duration": np.inf}, InputValueError, "duration must be a finite number > 0"),
        (
            {"q_start": [2.0, 0.0]},
            InputValueError,
            "q_start must lie within the position limits; joint 1",
        ),
        (
            {"qd_start": [0.0, 9.0]},
            InputValueError,
            "qd_start exceeds the velocity limit at joint 2",
        ),
        ({"qd_end": [0.0, 0.0, 0.0]}, DimensionError, "qd_end must be a scalar or have shape"),
        (
            {"via_times": [2.5], "via_positions": [[0.5, 0.0]]},
            InputValueError,
            "inside \\(0, duration",
        ),
        ({"via_times": [1.0]}, InputValueError, "need both via_times"),
        (
            {"via_times": [1.0], "via_positions": [[0.5]]},
            DimensionError,
            "via_positions must have shape",
        ),
        (
            {"via_times": [1.0], "via_positions": [[0.5, -1.5]]},
            InputValueError,
            r"via_positions\[0\] must lie",
        ),
        ({"velocity_limits": [1.0, -1.0]}, InputValueError, "velocity_limits must be > 0"),
        ({"position_limits": ([0.0, 0.0], [0.0, 1.0])}, InputValueError, "lower < upper; joint 1"),
        ({"n_control": 6}, InputValueError, "n_control must be an integer >= 7"),
        ({"n_grid": 3}, InputValueError, "n_grid must be an integer >= 10"),
        ({"epsilon": 0.0}, InputValueError, "epsilon must be a finite number > 0"),
        ({"joint_weights": [1.0, -1.0]}, InputValueError, "joint_weights must be finite and >= 0"),
        ({"time_weight": 2.0}, InputValueError, "time_weight must be a function"),
        ({"time_weight": lambda t: -t}, InputValueError, "time_weight"),
        ({"dt": 5.0}, InputValueError, "between 3 and"),
        ({"backend": "fortran"}, UnknownNameError, "unknown backend"),
        ({"robot": "planar2"}, InputTypeError, "robot must be a RobotModel"),
    ],
)
def test_bad_inputs_raise_clear_errors(
    planar: sl.RobotModel, change: dict[str, object], error: type, match: str
) -> None:
    arguments: dict[str, object] = {
        "robot": planar,
        "q_start": Q_START,
        "q_end": Q_END,
        "duration": DURATION,
        "position_limits": ([-1.0, -1.0], [1.5, 1.0]),
        "velocity_limits": 2.0,
    }
    arguments.update(change)
    with pytest.raises(error, match=match):
        optimize_trajectory(**arguments)  # type: ignore[arg-type]
