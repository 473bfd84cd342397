"""The trajectory that makes external-torque estimation most precise (thesis § 3.4, eq. 3.29).

The thesis states the problem and leaves its solution open (§ 6.2, item 5):
among the motions from q_s to q_f in T seconds within the joint limits, find
the one that minimises OBJ[q] (eq. 3.28, = EM[q] of eq. 3.32),

    OBJ[q] = ∫ w_t(t) Σ_j w_j ( Σ_k |Y_kj^q(q) Θ̂| B_Q̃k + Σ_p |Y_jp(q, q̇, q̈)| B_Θ̃p ) dt,

with |·| replaced by the smooth f(x) = (ε + x²)^½ of eq. 3.30 so that the
problem is differentiable. :func:`optimize_trajectory` solves it by direct
transcription instead of the Euler–Lagrange equation 3.31:

- **Parameterisation**: each joint is a clamped B-spline of degree 5
  (:class:`~sensorless.trajectories.SplineTrajectory`); the boundary
  conditions (positions, velocities, optionally accelerations) fix the first
  and last control points, the others are the variables
  (:mod:`sensorless.metric._transcription`).
- **Objective**: OBJ by the trapezoid rule on a collocation grid. B_Q̃ is
  *not* held at its value for the quintic: by the Table 3.1 method it is the
  largest estimation error of the online filter, whose lag grows with the
  jerk, and a planner blind to that makes trajectories whose own B_Q̃ is
  several times larger (EM of the PUMA task of ``benchmarks/plan_evidence.py``:
  3.1 -> 8.6 N m s). B_Q̃k is a variable s_k with |Q̂_k − Q_k| <= s_k at the
  peaks of the error, the error being exact for ``n_draws`` fixed noise draws
  (linear filter: :mod:`sensorless.metric._lag`). A given ``bq`` is held fixed.
- **Smooth |·|**: ε is lowered by a factor 100 per stage from 100 to
  ``epsilon`` (continuation), each stage starting from the last optimum.
- **Gradient**: exact in q̇ and q̈ (Y is linear in Q, eq. 3.12), a forward
  difference in q per sample (n_dof extra evaluations of the split regressor
  per sample, compiled with numba when installed), carried to the control
  points through the spline basis exactly (:mod:`sensorless.metric._objective`).
- **Constraints**: joint position, velocity and acceleration limits (linear
  in the control points) and rigid-body torque limits |M q̈ + C q̇ + g| <= τ_max
  (Jacobian from Pinocchio's RNEA derivatives) on the collocation grid; via
  points as linear equalities. After SLSQP the limits are checked on a grid
  10 times denser; points that exceed a limit join the constraint grid and
  SLSQP runs again from there (at most
  :data:`~sensorless.metric._optimal_solve.REFINEMENT_ROUNDS` rounds per stage).
- **Start**: the quintic through the same points
  (:class:`~sensorless.trajectories.QuinticViaPoints`), the project's default;
  ``n_starts > 1`` adds seeded random perturbations of it, and the best
  result is kept. The result is never worse (in EM) than a feasible start.

Examples
--------
>>> import sensorless as sl
>>> from sensorless.metric import optimize_trajectory
>>> robot = sl.robots.load("planar2")
>>> plan = optimize_trajectory(robot, [0.0, 0.0], [1.0, -0.5], 2.0, n_control=8, n_draws=2)
>>> bool(plan.metric <= plan.initial_metric)
True
"""

from __future__ import annotations

import weakref
from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.integrate import trapezoid
from threadpoolctl import threadpool_limits

from .._validation import (
    FloatArray,
    check_dt,
    check_int,
    check_scalar,
    check_type,
)
from ..exceptions import InputValueError, UnknownNameError
from ..filters import Butterworth, CausalEstimator
from ..robots.base_parameters import BaseParameters, base_parameters
from ..robots.model import RobotModel
from ..trajectories import QuinticViaPoints, SplineTrajectory, Trajectory
from ._checks import per_joint_nonnegative
from ._lag import LagModel
from ._objective import SmoothIntegrand, backend_of
from ._optimal_checks import (
    TimeWeight,
    boundary_of,
    limits_of,
    quintic_through,
    time_weight_on,
    via_of,
)
from ._optimal_result import PlannedTrajectory, load_plan
from ._optimal_solve import Run, Table31, solve
from ._transcription import DEGREE, Problem, basis, clamped_knots
from .bounds import check_bq, error_bound_terms, parameter_bounds

__all__ = ["PlannedTrajectory", "load_plan", "optimize_trajectory"]

#: Points of the limit check per interval of the collocation grid.
CHECK_DENSITY = 10
#: Collocation points per knot span by default.
_POINTS_PER_SPAN = 8
#: Points per knot span where the limits are imposed before refinement.
_CONSTRAINTS_PER_SPAN = 4
#: Largest ε of the continuation, and its number of stages (ε grows by 100 per stage).
_EPSILON_START = 1e2
_STAGES = 4
#: Most samples of EM and B_c(t) (every dt over the duration).
_MAX_SAMPLES = 2e6
#: Control points beyond a full turn cannot be a joint's positions [rad].
_MAX_RADIANS = 2.0 * np.pi
#: Standard deviation of the random starts, relative to the largest joint travel.
_START_SPREAD = 0.1

# The QR behind base_parameters dominates a short optimisation; models are immutable.
_BASES: weakref.WeakKeyDictionary[RobotModel, BaseParameters] = weakref.WeakKeyDictionary()


def optimize_trajectory(
    robot: RobotModel,
    q_start: ArrayLike,
    q_end: ArrayLike,
    duration: float,
    *,
    qd_start: float | ArrayLike = 0.0,
    qd_end: float | ArrayLike = 0.0,
    qdd_start: float | ArrayLike | None = 0.0,
    qdd_end: float | ArrayLike | None = 0.0,
    via_times: ArrayLike | None = None,
    via_positions: ArrayLike | None = None,
    position_limits: tuple[ArrayLike, ArrayLike] | None = None,
    velocity_limits: float | ArrayLike | None = None,
    acceleration_limits: float | ArrayLike | None = None,
    torque_limits: float | ArrayLike | None = None,
    joint_weights: ArrayLike | None = None,
    time_weight: TimeWeight | None = None,
    btheta: float | ArrayLike = 0.02,
    bq: ArrayLike | None = None,
    noise_std: float | ArrayLike = 1e-5,
    estimator: CausalEstimator | None = None,
    dt: float = 1e-3,
    epsilon: float = 1.0,
    n_control: int | None = None,
    n_grid: int | None = None,
    seed: int = 0,
    n_draws: int = 8,
    n_starts: int = 1,
    max_iterations: int = 200,
    tolerance: float = 1e-6,
    backend: str = "auto",
) -> PlannedTrajectory:
    """Trajectory from ``q_start`` to ``q_end`` in ``duration`` that minimises OBJ[q] (eq. 3.29).

    Parameters
    ----------
    robot : RobotModel
        Nominal robot: Θ̂ are its base parameters; its joint limits are the defaults.
    q_start, q_end : array-like of shape (n_dof,)
        Positions at t = 0 and t = ``duration`` [rad], within the position limits.
    duration : float
        T [s], > 0.
    qd_start, qd_end : float or array-like of shape (n_dof,)
        Velocities at both ends [rad/s]; default 0 (rest).
    qdd_start, qdd_end : float, array-like of shape (n_dof,) or None
        Accelerations at both ends [rad/s²]; default 0; None leaves them free.
    via_times : array-like of shape (n_via,), optional
        Times [s] of via points, strictly increasing inside (0, duration).
    via_positions : array-like of shape (n_via, n_dof), optional
        Positions [rad] the trajectory passes at ``via_times``.
    position_limits : (lower, upper), optional
        Position limits [rad], each a number or shape (n_dof,); default the robot's.
    velocity_limits, acceleration_limits, torque_limits : float or array-like, optional
        Limits on |q̇| [rad/s], |q̈| [rad/s²] and the rigid-body torque
        |M q̈ + C q̇ + g| [N m] (friction excluded); inf means none. Default the
        robot's velocity and effort limits and no acceleration limit.
    joint_weights : array-like of shape (n_dof,), optional
        w_j >= 0 [-]; default 1.
    time_weight : callable, optional
        w_t(t) >= 0 [-], called with an array of times [s]; default 1.
    btheta : float or array-like of shape (n_base,)
        B_Θ̃: relative (0.02, eq. 3.40) or per base parameter.
    bq : array-like of shape (l,), optional
        B_Q̃ held fixed. By default B_Q̃ is a function of the trajectory: the
        Table 3.1 method (:func:`q_error_bounds`) with ``noise_std``,
        ``estimator`` and ``dt``, the largest over ``n_draws`` noise draws
        seeded from ``seed``, modelled exactly in the problem
        (:mod:`sensorless.metric._lag`).
    noise_std : float or array-like of shape (n_dof,)
        Position noise [rad] for B_Q̃; default 1e-5 rad.
    estimator : CausalEstimator, optional
        Online estimator for B_Q̃; default a 5th-order Butterworth at 20 Hz.
    dt : float
        Sample period [s] of the estimator, of EM and of the bound B_c(t).
    epsilon : float
        ε > 0 of f(x) = (ε + x²)^½ (eq. 3.30), in the squared unit of each term;
        default 1. Smaller values follow |·| closer but take more iterations;
        the result's EM is always computed with |·|.
    n_control : int, optional
        Control points per joint, >= 7 plus the via points; default
        ``10 + 2 n_via``.
    n_grid : int, optional
        Collocation points (uniform, ends included), >= n_control; default
        12 per knot span plus one.
    seed : int
        Seed of B_Q̃'s noise draws (their seeds: ``numpy.random.SeedSequence(seed)
        .spawn(n_draws)``) and of the random starts.
    n_draws : int
        Noise draws behind B_Q̃ (more draws: a B_Q̃ that depends less on one
        draw, which the planner could otherwise fit).
    n_starts : int
        Starts: the quintic, then ``n_starts - 1`` seeded perturbations of it.
    max_iterations : int
        SLSQP iterations per round.
    tolerance : float
        SLSQP's ``ftol`` on OBJ divided by its value at the start.
    backend : {"auto", "numba", "numpy"}
        Compiled objective (numba, when installed) or numpy; same values.

    Returns
    -------
    PlannedTrajectory
        The trajectory, EM and B_c(t) along it and along the quintic.

    Raises
    ------
    DimensionError
        An array of the wrong shape.
    InputValueError
        A value that is not finite or out of range: a duration <= 0, a
        position outside the limits, a boundary velocity above the limit, via
        times outside (0, duration), too few control points.
    UnknownNameError
        An unknown backend.
    """
    check_type(robot, RobotModel, "robot")
    n = robot.n_dof
    total = check_scalar(duration, "duration", "s")
    limits = limits_of(robot, position_limits, velocity_limits, acceleration_limits, torque_limits)
    boundary = boundary_of(n, q_start, q_end, qd_start, qd_end, qdd_start, qdd_end, limits, total)
    via = via_of(n, via_times, via_positions, total, limits)
    n_via = 0 if via is None else via[0].size
    fixed = 4 + (boundary.qdd_start is not None) + (boundary.qdd_end is not None)
    controls = 10 + 2 * n_via if n_control is None else n_control
    controls = check_int(controls, "n_control", max(DEGREE + 2, fixed + n_via + 1))
    spans = controls - DEGREE
    grid_size = check_int(
        _POINTS_PER_SPAN * spans + 1 if n_grid is None else n_grid, "n_grid", controls
    )
    eps = check_scalar(epsilon, "epsilon", "unit of each term squared")
    period = check_dt(dt)
    n_samples = total / period + 1.0
    if not 3.0 <= n_samples <= _MAX_SAMPLES:
        raise InputValueError(
            f"duration / dt must give between 3 and {_MAX_SAMPLES:.0e} samples (EM and B_c are "
            f"sampled every dt); got duration = {total:g} s with dt = {period:g} s"
        )
    if backend not in ("auto", "numba", "numpy"):
        raise UnknownNameError(f"unknown backend {backend!r}; options: ['auto', 'numba', 'numpy']")
    starts_count = check_int(n_starts, "n_starts", 1)
    draws = check_int(n_draws, "n_draws", 1)
    iterations = check_int(max_iterations, "max_iterations", 1)
    ftol = check_scalar(tolerance, "tolerance", "-")
    weights = (
        np.ones(n)
        if joint_weights is None
        else per_joint_nonnegative(joint_weights, n, "joint_weights", "-")
    )

    initial = quintic_through(boundary, via, total)
    base = _BASES.get(robot)
    if base is None:
        base = _BASES[robot] = base_parameters(robot)
    theta = base.values_of(robot)
    btheta_abs = parameter_bounds(btheta, theta)
    est = Butterworth(period, cutoff=20.0, order=5) if estimator is None else estimator
    t, q, qd, qdd = initial.sample(period)
    table_31: Table31 | None = None
    if bq is None:
        table_31 = Table31(est, period, noise_std, seed, draws)
        bounds_q = table_31(q, qd, qdd)
    else:
        bounds_q = check_bq(bq, n)
    integrand = SmoothIntegrand(
        robot, base.independent, theta, btheta_abs, bounds_q, weights, eps, backend_of(backend)
    )
    grid = np.linspace(0.0, total, grid_size)
    problem = Problem(
        robot, clamped_knots(total, controls), boundary, limits, integrand, grid,
        time_weight_on(time_weight, grid), via, bounds_q,
    )  # fmt: skip
    dense = np.linspace(0.0, total, CHECK_DENSITY * (grid_size - 1) + 1)
    x0 = problem.start(initial.evaluate(dense)[0], dense)
    if table_31 is not None:
        values = (
            basis(problem.knots, t, 0),
            basis(problem.knots, t, 1),
            basis(problem.knots, t, 2),
        )
        lag = LagModel.build(values, problem.free, problem.shift, est, table_31.noise(q.shape))
        largest = np.abs(lag.errors(x0)).max(axis=(0, 1))
        problem.bq = np.zeros_like(bounds_q)
        # One scale per kind of entry (q̈, products of q̇), so that no row is ill-scaled.
        scale = np.full(largest.shape, max(float(largest[n:].max(initial=0.0)), 1e-9))
        scale[:n] = max(float(largest[:n].max()), 1e-9)
        problem.use_lag(lag, scale)
        x0 = problem.start(initial.evaluate(dense)[0], dense)
    schedule = [
        eps * 100.0**k for k in range(_STAGES - 1, 0, -1) if eps * 100.0**k <= _EPSILON_START
    ]
    schedule.append(eps)
    rng = np.random.default_rng(seed)
    travel = max(float(np.abs(boundary.q_end - boundary.q_start).max()), 0.1)
    starts = [x0]
    for _ in range(starts_count - 1):
        shaken = x0.copy()
        shaken[: problem.n_z] += rng.normal(0.0, _START_SPREAD * travel, problem.n_z)
        if problem.lag is not None:
            shaken[problem.n_z :] = problem.largest_lag(shaken)
        starts.append(shaken)
    first_times = np.linspace(0.0, total, _CONSTRAINTS_PER_SPAN * spans + 1)
    # SLSQP's subproblems are small: threaded BLAS only adds overhead (4x on 2 busy cores).
    with threadpool_limits(limits=1, user_api="blas"):
        runs = [
            solve(problem, start, dense, first_times, schedule, iterations, ftol)
            for start in starts
        ]
    best = min(runs, key=lambda run: (not run.feasible, run.objective))
    measure = _Measure(robot, base.independent, theta, btheta_abs, weights, time_weight, backend)
    return _result(problem, initial, best, x0, dense, measure, table_31, bounds_q, period)


# ---------------------------------------------------------------------- solve


class _Measure:
    """EM (eq. 3.32, |·|, trapezoid rule) and the model part of B_c(t) (eq. 3.36) of samples."""

    def __init__(
        self,
        robot: RobotModel,
        columns: Any,
        theta: FloatArray,
        btheta: FloatArray,
        weights: FloatArray,
        time_weight: TimeWeight | None,
        backend: str,
    ) -> None:
        self.robot, self.columns, self.theta, self.btheta = robot, columns, theta, btheta
        self.weights, self.time_weight, self.backend = weights, time_weight, backend_of(backend)

    def __call__(
        self, t: FloatArray, q: FloatArray, qd: FloatArray, qdd: FloatArray, bq: FloatArray
    ) -> tuple[float, FloatArray]:
        terms = error_bound_terms(
            self.robot, self.columns, self.theta, q, qd, qdd, bq, self.btheta,
            backend=self.backend,
        )  # fmt: skip
        integrand = (terms.q_error + terms.parameter_error) @ self.weights
        metric = float(trapezoid(time_weight_on(self.time_weight, t) * integrand, t))
        return metric, terms.q_error + terms.cross + terms.parameter_error


def _result(
    problem: Problem,
    initial: QuinticViaPoints,
    run: Run,
    x0: FloatArray,
    dense: FloatArray,
    measure: _Measure,
    table_31: Table31 | None,
    bq: FloatArray,
    period: float,
) -> PlannedTrajectory:
    robot = problem.robot

    def evaluate(trajectory: Trajectory) -> tuple[float, FloatArray, FloatArray, FloatArray]:
        t, q, qd, qdd = trajectory.sample(period)
        bounds = bq if table_31 is None else table_31(q, qd, qdd)
        return (*measure(t, q, qd, qdd, bounds), bounds, t)

    initial_metric, initial_bound, initial_bq, t = evaluate(initial)
    start = SplineTrajectory(problem.knots, problem.control_points(x0), DEGREE)
    start_metric, start_bound, start_bq, _ = evaluate(start)
    message, x = run.info["message"], run.x
    points = problem.control_points(x)
    if not np.isfinite(points).all() or np.abs(points).max() > _MAX_RADIANS:
        # SLSQP left the range of any joint (an infeasible or badly posed task): no result.
        x, run.violation = x0, np.inf
        message += "; SLSQP diverged and the start is returned"
    trajectory = SplineTrajectory(problem.knots, problem.control_points(x), DEGREE)
    metric, bound, planned_bq, _ = evaluate(trajectory)
    start_violation = float(problem.limits.violation(robot, *start.evaluate(dense)).max())
    if metric > start_metric and start_violation <= 0.0:
        # The solution's EM with its own B_Q̃ is above its feasible start's: keep the start.
        x, trajectory, metric, bound, planned_bq = x0, start, start_metric, start_bound, start_bq
        message += "; the start had the lower EM and is returned"
    violation = float(problem.limits.violation(robot, *trajectory.evaluate(dense)).max())
    if violation > 0.0:
        message += f"; a limit is exceeded by {violation:.3g} of it on the check grid"
    return PlannedTrajectory(
        trajectory=trajectory,
        initial=initial,
        metric=metric,
        initial_metric=initial_metric,
        t=t,
        bound=bound,
        initial_bound=initial_bound,
        bq=planned_bq,
        initial_bq=initial_bq,
        dt=period,
        robot=robot.name,
        joint_names=list(robot.joint_names),
        objective=problem.raw_objective(x),
        initial_objective=problem.raw_objective(x0),
        epsilon=problem.integrand.epsilon,
        max_violation=violation,
        success=bool(run.info["success"]) and violation <= 0.0,
        message=message,
        n_iterations=int(run.info["iterations"]),
        n_values=problem.n_value,
        n_gradients=problem.n_gradient,
    )
