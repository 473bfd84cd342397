"""Optimised excitation trajectories for identification (Swevers et al. 1997).

The trajectory of joint j is a finite Fourier series (thesis §2.4.3, "Using
Optimal Trajectories"), the form of :class:`~sensorless.trajectories.FourierSeries`:

    q_j(t) = q_{j,0} + Σ_{k=1}^{N} a_{j,k}/(ω_f k) sin(ω_f k t) − b_{j,k}/(ω_f k) cos(ω_f k t)

with ω_f = 2π f. It is periodic with period 1/f, so the excitation can be
repeated and averaged, and q̇, q̈ are analytic. The decision variables are the
offsets q_{j,0} [rad] and the coefficients a_{j,k}, b_{j,k} [rad/s].

Criterion: the condition number of the base regressor W = [Y_b(q(t_i),
q̇(t_i), q̈(t_i))]_i stacked over ``n_samples`` instants of one period (its
logarithm is minimised; the minimiser is the same). A small condition number
keeps the least-squares estimate insensitive to noise in the torques. The
condition number is that of W as it stands, in the SI units of the
parameters, as in Swevers et al. and Gautier's work.

Constraints: joint position, velocity and (optionally) acceleration limits at
the same instants. All three are linear in the decision variables, so
``scipy.optimize.minimize(method="SLSQP")`` gets them as linear inequalities
with exact Jacobians; the gradient of the criterion is a forward difference
whose perturbed trajectories go through the regressor in one batch.

Limits between the instants: after the optimisation the trajectory is checked
on a grid ``10`` times denser. Scaling every a, b by s scales q − q_0, q̇ and
q̈ by exactly s, so where the dense grid finds an excess the coefficients are
shrunk by the smallest such factor (reported as
:attr:`ExcitationResult.amplitude_scale`): the returned trajectory respects
the limits on the dense grid by construction.

Optionally (``start_at_rest=True``) q̇(0) = Σ_k a_{j,k} = 0 and
q̈(0) = Σ_k ω_f k b_{j,k} = 0, two linear equalities per joint, so that a robot
at rest at q(0) can start the trajectory without a jump; without them the
trajectory must be entered by a separate transition.

References
----------
J. Swevers, C. Ganseman, D. B. Tükel, J. De Schutter, H. Van Brussel,
"Optimal robot excitation and identification", IEEE Trans. Robotics and
Automation 13(5), 1997.

The result object and its YAML file live in ``_excitation_result``; this
module is their public home.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
import scipy.optimize
from numpy.typing import ArrayLike

from .._validation import FloatArray, check_int, check_type, per_joint
from ..exceptions import DimensionError, InputValueError
from ..robots.base_parameters import BaseParameters, base_parameters
from ..robots.model import RobotModel
from ..trajectories import FourierSeries
from ._excitation_result import ExcitationResult, load_excitation

__all__ = ["ExcitationResult", "load_excitation", "optimize_excitation"]

#: Points of the limit check per point of the optimisation grid.
_CHECK_DENSITY = 10
#: Step of the forward-difference gradient in the scaled decision variables.
_GRADIENT_STEP = 1e-6
#: Relative margin kept by the final amplitude scaling, against round-off.
_SCALE_MARGIN = 1e-9
#: The random starts use this fraction of the largest amplitude within the limits.
_START_FILL = 0.8


# ---------------------------------------------------------------------- checks


def _joint_limits(
    value: ArrayLike, n_dof: int, name: str, unit: str, *, positive: bool = False
) -> FloatArray:
    """Limits of shape (n_dof,) [unit] from one number for all joints or one per joint.

    ``inf`` is accepted here (no limit); NaN is not.
    """
    arr = per_joint(value, n_dof, name, unit, allow_inf=True)
    if positive and (arr <= 0).any():
        j = int(np.argmax(arr <= 0))
        raise InputValueError(f"{name} must be positive [{unit}]; joint {j} has {arr[j]:.6g}")
    return arr


def _limits(
    robot: RobotModel,
    position_limits: tuple[ArrayLike, ArrayLike] | None,
    velocity_limits: ArrayLike | None,
    acceleration_limits: ArrayLike | None,
    margin: float,
) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
    n = robot.n_dof
    if not (np.isfinite(margin) and 0.0 <= margin < 0.5):
        raise InputValueError(f"limit_margin must lie in [0, 0.5); got {margin!r}")
    if position_limits is None:
        low, high = robot.position_limits
        source = f"the position limits of robot {robot.name!r}"
        if np.isfinite(low).all() and np.isfinite(high).all():
            span = high - low
            low, high = low + margin * span, high - margin * span
    else:
        if len(position_limits) != 2:
            raise DimensionError(
                f"position_limits must be a pair (lower, upper) [rad]; got {position_limits!r}"
            )
        low = _joint_limits(position_limits[0], n, "position_limits lower", "rad")
        high = _joint_limits(position_limits[1], n, "position_limits upper", "rad")
        source = "position_limits"
    if not (np.isfinite(low).all() and np.isfinite(high).all()):
        raise InputValueError(
            f"{source} must be finite; got lower {low}, upper {high}. Pass position_limits"
        )
    if (low >= high).any():
        j = int(np.argmax(low >= high))
        raise InputValueError(
            f"{source} need lower < upper; joint {j} has {low[j]:.6g} >= {high[j]:.6g} rad"
        )
    if velocity_limits is None:
        velocity = robot.velocity_limits * (1.0 - 2.0 * margin)
        if not np.isfinite(velocity).all():
            raise InputValueError(
                f"robot {robot.name!r} has no finite velocity limits ({robot.velocity_limits}); "
                "pass velocity_limits [rad/s]"
            )
    else:
        velocity = _joint_limits(velocity_limits, n, "velocity_limits", "rad/s", positive=True)
        if not np.isfinite(velocity).all():
            raise InputValueError(f"velocity_limits must be finite [rad/s]; got {velocity}")
    if acceleration_limits is None:
        acceleration = np.full(n, np.inf)
    else:
        acceleration = _joint_limits(
            acceleration_limits, n, "acceleration_limits", "rad/s²", positive=True
        )
    return low, high, velocity, acceleration


# ---------------------------------------------------------------------- problem


class _Problem:
    """The Fourier parametrisation on a time grid, in scaled decision variables.

    x = [q_0 / h, vec(a) / v, vec(b) / v] with h the half range of the position
    limits and v the velocity limits, so that every variable is of order 1;
    vec stacks harmonic-major (index k·n_dof + j). q, q̇, q̈ flattened
    sample-major are J x for constant matrices J: the map is linear.
    """

    def __init__(
        self,
        base: BaseParameters,
        n_harmonics: int,
        base_frequency: float,
        n_samples: int,
        limits: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
    ) -> None:
        self.base = base
        self.n_dof = base.robot.n_dof
        self.n_harmonics = n_harmonics
        self.base_frequency = base_frequency
        self.lower, self.upper, self.velocity, self.acceleration = limits
        self.half_range = 0.5 * (self.upper - self.lower)
        self.omega = 2.0 * np.pi * base_frequency * np.arange(1, n_harmonics + 1)
        t = np.arange(n_samples) / (n_samples * base_frequency)
        self.jq, self.jqd, self.jqdd = self.jacobians(t)

    def jacobians(self, t: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        """J_q, J_q̇, J_q̈ of shape (len(t)·n_dof, n_dof (1 + 2 n_harmonics))."""
        n, m = self.n_dof, t.size
        phase = np.outer(t, self.omega)
        sin, cos = np.sin(phase), np.cos(phase)
        v = np.diag(self.velocity)
        zero = np.zeros((m * n, n))
        jq = np.hstack(
            [
                np.kron(np.ones((m, 1)), np.diag(self.half_range)),
                np.kron(sin / self.omega, v),
                np.kron(-cos / self.omega, v),
            ]
        )
        jqd = np.hstack([zero, np.kron(cos, v), np.kron(sin, v)])
        jqdd = np.hstack([zero, np.kron(-sin * self.omega, v), np.kron(cos * self.omega, v)])
        return jq, jqd, jqdd

    def pack(self, q0: FloatArray, a: FloatArray, b: FloatArray) -> FloatArray:
        return np.concatenate(
            [q0 / self.half_range, (a / self.velocity).ravel(), (b / self.velocity).ravel()]
        )

    def unpack(self, x: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
        n, k = self.n_dof, self.n_harmonics
        q0 = x[:n] * self.half_range
        a = x[n : n + n * k].reshape(k, n) * self.velocity
        b = x[n + n * k :].reshape(k, n) * self.velocity
        return q0, a, b

    def series(self, x: FloatArray) -> FourierSeries:
        q0, a, b = self.unpack(x)
        return FourierSeries(self.base_frequency, a=a, b=b, q0=q0)

    def regressors(self, xs: FloatArray) -> FloatArray:
        """W for each column of ``xs`` (n_variables, n_points): (n_points, m·n_dof, count)."""
        n, n_points = self.n_dof, xs.shape[1]

        def states(j: FloatArray) -> FloatArray:
            # (m·n, n_points) -> (n_points·m, n): one trajectory after the other.
            return (j @ xs).T.reshape(-1, n)

        y = self.base.regressor(states(self.jq), states(self.jqd), states(self.jqdd))
        return np.asarray(y.reshape(n_points, -1, self.base.count))

    def log_condition(self, xs: FloatArray) -> FloatArray:
        """log cond(W) for each column of ``xs`` (shape (n_variables, n_points)).

        From the eigenvalues of WᵀW, which is small (count × count): far cheaper
        than batched SVDs of the tall W and accurate enough for the search
        (cond² stays well within double precision for any useful trajectory).
        """
        w = self.regressors(xs)
        eigenvalues = np.linalg.eigvalsh(np.swapaxes(w, 1, 2) @ w)
        smallest = np.maximum(eigenvalues[:, 0], np.finfo(float).tiny)
        return np.asarray(0.5 * (np.log(eigenvalues[:, -1]) - np.log(smallest)))

    def condition_number(self, x: FloatArray) -> float:
        """cond(W) of one trajectory, from the singular values of W."""
        singular = np.linalg.svd(self.regressors(x[:, None])[0], compute_uv=False)
        return float(singular[0] / singular[-1]) if singular[-1] > 0 else float("inf")

    def constraints(self, start_at_rest: bool) -> list[dict[str, Any]]:
        """Linear constraints of SLSQP: A x - c >= 0 (limits) and E x = 0 (rest at t = 0)."""
        blocks = [
            (self.jq, -np.tile(self.lower, self.jq.shape[0] // self.n_dof)),
            (-self.jq, np.tile(self.upper, self.jq.shape[0] // self.n_dof)),
        ]
        for jac, limit in ((self.jqd, self.velocity), (self.jqdd, self.acceleration)):
            finite = np.isfinite(np.tile(limit, jac.shape[0] // self.n_dof))
            bound = np.tile(limit, jac.shape[0] // self.n_dof)[finite]
            blocks += [(jac[finite], bound), (-jac[finite], bound)]
        matrix = np.vstack([block[0] for block in blocks])
        offset = np.concatenate([block[1] for block in blocks])
        out: list[dict[str, Any]] = [
            {
                "type": "ineq",
                "fun": lambda x: matrix @ x + offset,
                "jac": lambda x: matrix,
            }
        ]
        if start_at_rest:
            # Row block 0 of J_q̇ and J_q̈ is t = 0: q̇(0) = Σ a, q̈(0) = Σ ω_k b.
            rest = np.vstack([self.jqd[: self.n_dof], self.jqdd[: self.n_dof]])
            out.append({"type": "eq", "fun": lambda x: rest @ x, "jac": lambda x: rest})
        return out


class _Objective:
    """log cond(W) and its forward-difference gradient, sharing evaluations."""

    def __init__(self, problem: _Problem) -> None:
        self.problem = problem
        self.last_x: FloatArray | None = None
        self.last_value = 0.0

    def value(self, x: FloatArray) -> float:
        if self.last_x is None or not np.array_equal(x, self.last_x):
            self.last_value = float(self.problem.log_condition(x[:, None])[0])
            self.last_x = x.copy()
        return self.last_value

    def gradient(self, x: FloatArray) -> FloatArray:
        points = np.hstack([x[:, None], x[:, None] + _GRADIENT_STEP * np.eye(x.size)])
        values = self.problem.log_condition(points)
        self.last_x, self.last_value = x.copy(), float(values[0])
        return np.asarray((values[1:] - values[0]) / _GRADIENT_STEP)


def _amplitude_scale(
    q0: FloatArray,
    q: FloatArray,
    qd: FloatArray,
    qdd: FloatArray,
    limits: tuple[FloatArray, FloatArray, FloatArray, FloatArray],
) -> float:
    """Largest s >= 0 with q0 + s (q - q0), s q̇, s q̈ within the limits at every sample."""
    lower, upper, velocity, acceleration = limits
    swing = q - q0
    with np.errstate(divide="ignore", invalid="ignore"):
        room = np.where(
            swing > 0, (upper - q0) / swing, np.where(swing < 0, (lower - q0) / swing, np.inf)
        )
        ratios = [
            room.min(),
            (velocity / np.abs(qd)).min(),
            (acceleration / np.abs(qdd)).min(),
        ]
    return max(float(np.nanmin(ratios)), 0.0)


def _random_start(problem: _Problem, rng: np.random.Generator, start_at_rest: bool) -> FloatArray:
    n, k = problem.n_dof, problem.n_harmonics
    centre = 0.5 * (problem.lower + problem.upper)
    q0 = centre + 0.5 * problem.half_range * rng.uniform(-1.0, 1.0, n)
    # Coefficients falling off as 1/k: a smooth start, like a band-limited excitation.
    decay = 1.0 / np.arange(1, k + 1)[:, None]
    a = rng.standard_normal((k, n)) * decay
    b = rng.standard_normal((k, n)) * decay
    if start_at_rest:
        a -= a.mean(axis=0)
        weights = problem.omega[:, None]
        b -= weights * (weights * b).sum(axis=0) / (weights**2).sum()
    x = problem.pack(q0, a, b)
    q, qd, qdd = ((j @ x).reshape(-1, n) for j in (problem.jq, problem.jqd, problem.jqdd))
    limits = (problem.lower, problem.upper, problem.velocity, problem.acceleration)
    scale = _START_FILL * _amplitude_scale(q0, q, qd, qdd, limits)
    return problem.pack(q0, scale * a, scale * b)


def _fit_to_limits(
    problem: _Problem, x: FloatArray, n_check: int
) -> tuple[FourierSeries, float, tuple[FloatArray, ...]]:
    """Shrink the amplitudes of ``x`` until a dense grid respects the limits."""
    trajectory = problem.series(x)
    t = np.arange(n_check) / (n_check * problem.base_frequency)
    q, qd, qdd = trajectory.evaluate(t)
    limits = (problem.lower, problem.upper, problem.velocity, problem.acceleration)
    scale = min(1.0, _amplitude_scale(trajectory.q0, q, qd, qdd, limits))
    if scale < 1.0:
        # A hair inside, so that the round-off of s·q̇ cannot cross the limit.
        scale *= 1.0 - _SCALE_MARGIN
        trajectory = FourierSeries(
            problem.base_frequency, a=scale * trajectory.a, b=scale * trajectory.b, q0=trajectory.q0
        )
        q, qd, qdd = trajectory.evaluate(t)
    extremes = (
        q.min(axis=0),
        q.max(axis=0),
        np.abs(qd).max(axis=0),
        np.abs(qdd).max(axis=0),
    )
    return trajectory, scale, extremes


def optimize_excitation(
    robot: RobotModel,
    *,
    base: BaseParameters | None = None,
    zero: Sequence[str] = (),
    n_harmonics: int = 5,
    base_frequency: float = 0.1,
    n_samples: int | None = None,
    position_limits: tuple[ArrayLike, ArrayLike] | None = None,
    velocity_limits: ArrayLike | None = None,
    acceleration_limits: ArrayLike | None = None,
    limit_margin: float = 0.1,
    start_at_rest: bool = False,
    seed: int = 0,
    n_restarts: int = 3,
    max_iterations: int = 100,
) -> ExcitationResult:
    """Fourier excitation trajectory minimising cond(W) within joint limits.

    Parameters
    ----------
    robot : RobotModel
        Robot to excite; its limits are the defaults.
    base : BaseParameters, optional
        Base parameters whose regressor W is conditioned; by default
        ``base_parameters(robot, zero=zero)``.
    zero : sequence of str
        Standard parameters known to be zero; only without ``base``.
    n_harmonics : int
        Harmonics N per joint.
    base_frequency : float
        Fundamental frequency f [Hz]; the period 1/f [s] is the duration.
    n_samples : int, optional
        Instants of one period at which W is stacked and the limits imposed;
        default ``max(20 N, 2 count / n_dof + 1)``. At least 2N + 1, and
        ``n_samples · n_dof`` must exceed the number of base parameters.
    position_limits : (lower, upper), optional
        Joint position limits [rad], numbers or arrays of shape (n_dof,);
        default the robot's, shrunk by ``limit_margin`` of their span at each
        end.
    velocity_limits : float or array-like of shape (n_dof,), optional
        Joint speed limits [rad/s]; default the robot's times ``1 − 2 limit_margin``.
    acceleration_limits : float or array-like of shape (n_dof,), optional
        Joint acceleration limits [rad/s²]; default none (robot models carry none).
    limit_margin : float
        Fraction of the span of the robot's limits kept free at each end,
        0 <= limit_margin < 0.5; only for limits taken from the robot.
    start_at_rest : bool
        Impose q̇(0) = 0 and q̈(0) = 0 (needs ``n_harmonics >= 2``).
    seed : int
        Seed of the random starts (:func:`numpy.random.default_rng`); the same
        seed and arguments give identical coefficients on the same machine and
        BLAS threading (another thread count rounds sums differently, and the
        optimiser amplifies that into a slightly different optimum).
    n_restarts : int
        Random starts; the run with the lowest final cond(W) is kept.
    max_iterations : int
        SLSQP iterations per start.

    Returns
    -------
    ExcitationResult

    Raises
    ------
    InputTypeError
        If ``robot`` is not a RobotModel or ``base`` not a BaseParameters.
    DimensionError
        If a limit has the wrong shape or ``base`` belongs to a robot with
        another number of joints.
    InputValueError
        For a bad count, frequency, margin, seed, a non-positive or missing
        limit, or ``zero`` given together with ``base``.

    Examples
    --------
    >>> import sensorless as sl
    >>> robot = sl.robots.load("planar2")
    >>> res = optimize_excitation(robot, n_harmonics=2, position_limits=(-2.0, 2.0),
    ...                           velocity_limits=1.5, n_restarts=1, max_iterations=20)
    >>> bool(res.condition_number < res.initial_condition_number) and res.within_limits
    True
    """
    check_type(robot, RobotModel, "robot")
    if base is None:
        base = base_parameters(robot, zero=zero)
    else:
        check_type(base, BaseParameters, "base")
        if tuple(zero):
            raise InputValueError(
                f"zero={tuple(zero)!r} applies only without base; the given base already "
                f"fixes the zero parameters {base.zero!r}"
            )
        if base.robot.n_dof != robot.n_dof:
            raise DimensionError(
                f"base belongs to a robot with {base.robot.n_dof} joints; robot "
                f"{robot.name!r} has {robot.n_dof}"
            )
    n_harmonics = check_int(n_harmonics, "n_harmonics", 1)
    if start_at_rest and n_harmonics < 2:
        raise InputValueError(
            "start_at_rest needs n_harmonics >= 2: with one harmonic q̇(0) = q̈(0) = 0 "
            f"leaves no motion; got n_harmonics={n_harmonics}"
        )
    try:
        frequency = float(base_frequency)
    except (TypeError, ValueError):
        frequency = float("nan")
    if not (np.isfinite(frequency) and frequency > 0):
        raise InputValueError(
            f"base_frequency must be a positive number [Hz]; got {base_frequency!r}"
        )
    n = robot.n_dof
    if n_samples is None:
        n_samples = max(20 * n_harmonics, 2 * base.count // n + 1)
    n_samples = check_int(n_samples, "n_samples", 2 * n_harmonics + 1)
    if n_samples * n <= base.count:
        raise InputValueError(
            f"n_samples · n_dof must exceed the {base.count} base parameters; got "
            f"{n_samples} · {n} = {n_samples * n}"
        )
    seed = check_int(seed, "seed", 0)
    n_restarts = check_int(n_restarts, "n_restarts", 1)
    max_iterations = check_int(max_iterations, "max_iterations", 1)
    limits = _limits(robot, position_limits, velocity_limits, acceleration_limits, limit_margin)

    problem = _Problem(base, n_harmonics, frequency, n_samples, limits)
    constraints = problem.constraints(bool(start_at_rest))
    rng = np.random.default_rng(seed)
    starts, runs = [], []
    for _ in range(n_restarts):
        x0 = _random_start(problem, rng, bool(start_at_rest))
        starts.append((problem.condition_number(x0), x0))
        objective = _Objective(problem)
        run = scipy.optimize.minimize(
            objective.value,
            x0,
            jac=objective.gradient,
            method="SLSQP",
            constraints=constraints,
            options={"maxiter": max_iterations},
        )
        trajectory, scale, extremes = _fit_to_limits(problem, run.x, _CHECK_DENSITY * n_samples)
        condition = problem.condition_number(
            problem.pack(trajectory.q0, trajectory.a, trajectory.b)
        )
        runs.append((condition, trajectory, scale, extremes, run))
    initial_condition, initial_x = min(starts, key=lambda item: item[0])
    condition, trajectory, scale, extremes, run = min(runs, key=lambda item: item[0])
    low, high, velocity, acceleration = limits
    min_q, max_q, max_qd, max_qdd = extremes
    return ExcitationResult(
        trajectory=trajectory,
        initial_trajectory=problem.series(initial_x),
        condition_number=condition,
        initial_condition_number=initial_condition,
        robot=robot.name,
        joint_names=list(robot.joint_names),
        base_names=list(base.names),
        n_samples=n_samples,
        lower_limit=low,
        upper_limit=high,
        velocity_limit=velocity,
        acceleration_limit=acceleration,
        min_position=min_q,
        max_position=max_q,
        max_velocity=max_qd,
        max_acceleration=max_qdd,
        amplitude_scale=scale,
        success=bool(run.success),
        message=str(run.message),
        n_iterations=int(run.nit),
    )
