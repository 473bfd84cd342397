"""External-torque estimation metric EM[q] of a trajectory (thesis § 3.4).

The acceleration-based estimate τ̂_c (eq. 3.16) is wrong by (eq. 3.19)

    τ̃_c = Σ_k Y_k^q(q) [Q̃_k Θ̂ + Q_k Θ̃] − τ̃_L + τ_d + τ̃_fr,

with Q = [q̈; q̇_i q̇_j (i < j); q̇_i²; 1] (eq. 3.11, :func:`q_vector`), Y_k^q
the split regressor of eq. 3.12 (:meth:`RobotModel.regressor_terms`), Q̃ the
error of the estimated Q̂ (eq. 3.18) and Θ̃ that of the parameters. With
bounds |Q̃_k| ≤ B_Q̃k (eq. 3.26) and |Θ̃_p| ≤ B_Θ̃p (eq. 3.27) the metric is
(eq. 3.28, 3.32)

    EM[q] = ∫ w_t(t) Σ_j w_j ( Σ_k |Y_kj^q(q) Θ̂| B_Q̃k + Σ_p |Y_jp(q, q̇, q̈)| B_Θ̃p ) dt,

the integrand without w_t being OF(t) (eq. 3.24). Smaller is better: the
same task planned along a trajectory with a smaller EM gives a more precise
τ̂_c and a lower model-based threshold (§ 3.5, :mod:`sensorless.thresholds.model_based`).

Θ are the *base* parameters (:func:`sensorless.base_parameters`): the
columns ``independent`` of the standard regressor, with the values of the
nominal robot. Y_kjp^q is the (j, p) entry of Y_k^q restricted to those
columns.

B_Q̃ comes from :func:`q_error_bounds`, the method of thesis Table 3.1: add
white noise to the trajectory, estimate q̇, q̈ with the causal filter used
online, and take the largest error of each entry of Q̂. B_Θ̃ is relative
(2 % of |Θ̂_p|, eq. 3.40) or given per parameter (e.g. regression confidence
intervals). :func:`rank_trajectories` does all of it for a set of
trajectories (Table 3.2).

Examples
--------
>>> import numpy as np
>>> import sensorless as sl
>>> from sensorless.metric import estimation_metric, q_vector
>>> robot = sl.robots.load("planar2")
>>> t = np.linspace(0.0, 1.0, 101)
>>> q = np.column_stack([np.sin(t), np.cos(t)])
>>> qd = np.column_stack([np.cos(t), -np.sin(t)])
>>> qdd = -q
>>> q_vector(qd[:1], qdd[:1]).shape                      # l = (n² + 3n + 2)/2
(1, 6)
>>> estimation_metric(robot, q, qd, qdd, t, bq=np.zeros(6), btheta=0.0)
0.0
>>> em = estimation_metric(robot, q, qd, qdd, t, bq=np.zeros(6), btheta=0.02)
>>> bool(np.isclose(estimation_metric(robot, q, qd, qdd, t, bq=np.zeros(6), btheta=0.04), 2 * em))
True
"""

from __future__ import annotations

import operator
from collections.abc import Callable, Mapping
from typing import Any, NamedTuple

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from scipy.integrate import trapezoid

from ._validation import FloatArray, as_joint_array, check_dt, check_finite
from .exceptions import DimensionError, InputTypeError, InputValueError
from .filters import Butterworth, CausalEstimator
from .robots.base_parameters import BaseParameters, base_parameters
from .robots.model import RobotModel
from .trajectories import Trajectory

__all__ = [
    "DEFAULT_CHUNK_SIZE",
    "BoundTerms",
    "check_bq",
    "error_bound_terms",
    "estimation_metric",
    "metric_terms",
    "parameter_bounds",
    "q_error_bounds",
    "q_length",
    "q_vector",
    "rank_trajectories",
]

#: Samples per batch of :meth:`RobotModel.regressor_terms`, whose result holds
#: l·n·11n floats per sample (about 30 kB for six joints): 2 000 samples ≈ 60 MB.
DEFAULT_CHUNK_SIZE = 2000

TimeWeight = Callable[[FloatArray], ArrayLike] | ArrayLike


def q_length(n_dof: int) -> int:
    """Length l = (n² + 3n + 2)/2 of the vector Q of eq. 3.11 for ``n_dof`` joints."""
    return (n_dof * n_dof + 3 * n_dof + 2) // 2


def q_vector(qd: ArrayLike, qdd: ArrayLike) -> FloatArray:
    """The vector Q = [q̈; q̇_i q̇_j (i < j); q̇_i²; 1] of eq. 3.11, without a robot.

    Same order as :meth:`RobotModel.q_vector` and :meth:`RobotModel.regressor_terms`.

    Parameters
    ----------
    qd : array-like of shape (n_samples, n_dof)
        Joint velocities [rad/s].
    qdd : array-like of shape (n_samples, n_dof)
        Joint accelerations [rad/s²].

    Returns
    -------
    ndarray of shape (n_samples, l), l = (n² + 3n + 2)/2

    Examples
    --------
    >>> q_vector([[1.0, 2.0]], [[3.0, 4.0]]).tolist()
    [[3.0, 4.0, 2.0, 1.0, 4.0, 1.0]]
    """
    qds = _series(qd, "qd")
    qdds, _ = as_joint_array(qdd, qds.shape[1], "qdd")
    if qdds.shape != qds.shape:
        raise DimensionError(
            f"qd and qdd must have the same shape (n_samples, n_dof); got {qds.shape} "
            f"and {qdds.shape}"
        )
    upper_i, upper_j = np.triu_indices(qds.shape[1], 1)
    return np.hstack([qdds, qds[:, upper_i] * qds[:, upper_j], qds**2, np.ones((qds.shape[0], 1))])


def q_error_bounds(
    q: ArrayLike,
    dt: float,
    estimator: CausalEstimator,
    *,
    noise_std: float | ArrayLike,
    seed: int | np.random.Generator | None = 0,
    reference: tuple[ArrayLike, ArrayLike] | None = None,
    transient: float = 0.0,
) -> FloatArray:
    """Bounds B_Q̃ of eq. 3.26 by the method of thesis Table 3.1.

    White Gaussian noise of standard deviation ``noise_std`` is added to the
    positions, the causal ``estimator`` turns them into q̂̇ and q̂̈, and
    B_Q̃k = max_t |Q̂_k(t) − Q_k(t)| (eq. 3.18); the last entry (the constant
    1) is 0. The estimator's delay is part of the error on purpose: the
    online estimate τ̂_c suffers it too.

    Parameters
    ----------
    q : array-like of shape (n_samples, n_dof)
        Noise-free joint positions of the trajectory on a regular grid [rad].
    dt : float
        Sample period [s].
    estimator : CausalEstimator
        The velocity/acceleration estimator used online (e.g. a 5th-order
        :class:`~sensorless.filters.Butterworth`, as in the thesis). Its
        ``dt`` must equal ``dt``. It starts at rest at ``q[0]``.
    noise_std : float or array-like of shape (n_dof,)
        Standard deviation of the position noise [rad], >= 0.
    seed : int, numpy Generator or None
        Seed of the noise.
    reference : (qd, qdd), optional
        True joint velocities [rad/s] and accelerations [rad/s²], each of
        shape (n_samples, n_dof), e.g. from :meth:`Trajectory.sample`. By
        default second-order central differences of the noise-free ``q``
        (:func:`numpy.gradient`), accurate for a smooth ``q`` sampled finely.
    transient : float
        Time [s] skipped at the start, where the estimator's start-up
        transient would dominate (useful when the trajectory does not start
        at rest); ``0 <= transient < n_samples · dt``.

    Returns
    -------
    ndarray of shape (l,)
        B_Q̃ in the units of Q: [rad/s²] for q̈, [rad²/s²] for the products.

    Examples
    --------
    >>> import numpy as np
    >>> from sensorless.filters import FiniteDifference
    >>> t = np.arange(200)[:, None] * 0.01
    >>> q = np.hstack([0.5 * t**2, -t**2])
    >>> b = q_error_bounds(q, 0.01, FiniteDifference(0.01), noise_std=0.0,
    ...                    reference=(np.hstack([t, -2 * t]), np.tile([1.0, -2.0], (200, 1))),
    ...                    transient=0.02)
    >>> bool(b.max() < 0.1), float(b[-1])
    (True, 0.0)
    """
    dt = check_dt(dt)
    positions = _series(q, "q")
    n_samples, n_dof = positions.shape
    if not isinstance(estimator, CausalEstimator):
        raise InputTypeError(
            "estimator must be a causal estimator of sensorless.filters (FiniteDifference, "
            f"DirtyDerivative, Butterworth); got {type(estimator).__name__}"
        )
    if not np.isclose(estimator.dt, dt, rtol=1e-9, atol=0.0):
        raise InputValueError(
            f"the estimator was designed for dt = {estimator.dt:g} s but the trajectory is "
            f"sampled with dt = {dt:g} s; design it with the same sample period"
        )
    std = _per_joint_nonnegative(noise_std, n_dof, "noise_std", "rad")
    skip = _transient_samples(transient, dt, n_samples)
    if reference is None:
        if n_samples < 3:
            raise DimensionError(f"q needs at least 3 samples to differentiate it; got {n_samples}")
        qd_true = np.gradient(positions, dt, axis=0, edge_order=2)
        qdd_true = np.gradient(qd_true, dt, axis=0, edge_order=2)
    else:
        if len(reference) != 2:
            raise DimensionError(
                f"reference must be a pair (qd, qdd) of true derivatives; got {len(reference)} "
                "arrays"
            )
        qd_true, _ = as_joint_array(reference[0], n_dof, "reference qd")
        qdd_true, _ = as_joint_array(reference[1], n_dof, "reference qdd")
        if qd_true.shape != positions.shape or qdd_true.shape != positions.shape:
            raise DimensionError(
                f"reference qd and qdd must have the shape of q, {positions.shape}; got "
                f"{qd_true.shape} and {qdd_true.shape}"
            )
    rng = np.random.default_rng(seed)
    noisy = positions + rng.standard_normal(positions.shape) * std
    estimate, _ = estimator.filter(noisy)
    error = q_vector(estimate.velocity, estimate.acceleration) - q_vector(qd_true, qdd_true)
    bounds = np.abs(error[skip:]).max(axis=0)
    bounds[-1] = 0.0
    return np.asarray(bounds)


class BoundTerms(NamedTuple):
    """The three trajectory-dependent terms of the error bound (eq. 3.28, 3.36).

    Each has shape (n_samples, n_dof) [N m].

    Attributes
    ----------
    q_error : ndarray
        Σ_k |Y_kj^q(q) Θ̂| B_Q̃k, objective A of eq. 3.22 (error of Q̂).
    cross : ndarray
        Σ_p Σ_k |Y_kjp^q(q)| B_Q̃k B_Θ̃p, the product term of eq. 3.36.
    parameter_error : ndarray
        Σ_p |Y_jp(q, q̇, q̈)| B_Θ̃p, objective B of eq. 3.22 (error of Θ̂),
        with the q̇, q̈ given (true ones for the metric, estimated ones for
        the threshold).
    """

    q_error: FloatArray
    cross: FloatArray
    parameter_error: FloatArray


def parameter_bounds(btheta: float | ArrayLike, theta: FloatArray) -> FloatArray:
    """B_Θ̃ from a relative bound (eq. 3.40) or a bound per base parameter.

    Parameters
    ----------
    btheta : float or array-like of shape (n_base,)
        A float r >= 0 gives B_Θ̃ = r·|Θ̂| (0.02 in the thesis); an array is
        the bound of each base parameter in its own unit, >= 0.
    theta : ndarray of shape (n_base,)
        Base-parameter values Θ̂.

    Returns
    -------
    ndarray of shape (n_base,)
    """
    value = np.asarray(btheta, dtype=float)
    if value.ndim == 0:
        if not np.isfinite(value) or value < 0:
            raise InputValueError(
                f"btheta as a relative bound must be a finite number >= 0 (0.02 = 2 %); "
                f"got {btheta!r}"
            )
        return np.asarray(float(value) * np.abs(theta))
    if value.shape != theta.shape:
        raise DimensionError(
            f"btheta must be a relative bound (float) or one bound per base parameter, shape "
            f"{theta.shape}; got shape {value.shape}"
        )
    if not np.isfinite(value).all() or (value < 0).any():
        raise InputValueError(f"btheta must be finite and >= 0; got {value}")
    return value.copy()


def check_bq(bq: ArrayLike, n_dof: int) -> FloatArray:
    """Check B_Q̃: finite, >= 0, shape (l,) with l = (n² + 3n + 2)/2."""
    value = np.asarray(bq, dtype=float)
    length = q_length(n_dof)
    if value.shape != (length,):
        raise DimensionError(
            f"bq must have shape ({length},) for {n_dof} joints (one bound per entry of Q, "
            f"eq. 3.11); got shape {value.shape}"
        )
    if not np.isfinite(value).all() or (value < 0).any():
        raise InputValueError(f"bq must be finite and >= 0; got {value}")
    return value.copy()


def error_bound_terms(
    robot: RobotModel,
    columns: ArrayLike,
    theta: ArrayLike,
    q: FloatArray,
    qd: FloatArray,
    qdd: FloatArray,
    bq: FloatArray,
    btheta: FloatArray,
    *,
    chunk_size: int = DEFAULT_CHUNK_SIZE,
) -> BoundTerms:
    """Per-sample, per-joint terms of eq. 3.28 and 3.36, in batches of samples.

    Y(q, q̇, q̈) is rebuilt as Σ_k Y_k^q(q) Q_k from the split regressor, which
    costs nothing more than the split itself. Inputs are not checked here
    (the public functions of this module and the thresholds check them).

    Parameters
    ----------
    robot : RobotModel
        Robot with the kinematics of the nominal model (only its regressor is used).
    columns : array-like of int of shape (n_base,)
        Base-parameter columns of the standard regressor
        (:attr:`BaseParameters.independent`).
    theta : array-like of shape (n_base,)
        Base-parameter values Θ̂ (:meth:`BaseParameters.values_of` the nominal robot).
    q, qd, qdd : ndarray of shape (n_samples, n_dof)
        Joint positions [rad], velocities [rad/s], accelerations [rad/s²].
    bq : ndarray of shape (l,)
        B_Q̃ (eq. 3.26), checked by :func:`check_bq`.
    btheta : ndarray of shape (n_base,)
        Absolute B_Θ̃ (eq. 3.27), e.g. from :func:`parameter_bounds`.
    chunk_size : int
        Samples per call of :meth:`RobotModel.regressor_terms` (bounds memory).

    Returns
    -------
    BoundTerms
    """
    chunk = _positive_int(chunk_size, "chunk_size")
    index = np.asarray(columns, dtype=np.intp)
    values = np.asarray(theta, dtype=float)
    n_samples, n_dof = q.shape
    parts = [np.zeros((n_samples, n_dof)) for _ in range(3)]
    q_all = q_vector(qd, qdd)
    for start in range(0, n_samples, chunk):
        stop = min(start + chunk, n_samples)
        terms = robot.regressor_terms(q[start:stop])[..., index]  # (c, l, n, p)
        c, n_terms = terms.shape[:2]
        # Matrix products rather than multi-operand einsums: BLAS does the work.
        parts[0][start:stop] = np.abs(terms @ values).transpose(0, 2, 1) @ bq
        parts[1][start:stop] = (np.abs(terms) @ btheta).transpose(0, 2, 1) @ bq
        flat = terms.reshape(c, n_terms, -1)
        regressor = (q_all[start:stop, None, :] @ flat).reshape(c, n_dof, -1)
        parts[2][start:stop] = np.abs(regressor) @ btheta
    return BoundTerms(*parts)


def metric_terms(
    robot: RobotModel,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    bq: ArrayLike,
    btheta: float | ArrayLike,
    *,
    base: BaseParameters | None = None,
    joint_weights: ArrayLike | None = None,
    chunk_size: int = DEFAULT_CHUNK_SIZE,
) -> FloatArray:
    """The integrand OF(t) of eq. 3.24 with the bounds of eq. 3.26–3.27 (as in eq. 3.28).

    OF(t) = Σ_j w_j ( Σ_k |Y_kj^q(q) Θ̂| B_Q̃k + Σ_p |Y_jp(q, q̇, q̈)| B_Θ̃p ).

    Parameters
    ----------
    robot : RobotModel
        Nominal robot; Θ̂ are its base-parameter values.
    q, qd, qdd : array-like of shape (n_samples, n_dof)
        Joint positions [rad], velocities [rad/s] and accelerations [rad/s²]
        of the trajectory (the true, planned ones).
    bq : array-like of shape (l,)
        B_Q̃ (eq. 3.26), e.g. from :func:`q_error_bounds`.
    btheta : float or array-like of shape (n_base,)
        B_Θ̃: relative (0.02 → 2 % of |Θ̂|, eq. 3.40) or per base parameter.
    base : BaseParameters, optional
        Base parameters to use; by default ``base_parameters(robot)``.
    joint_weights : array-like of shape (n_dof,), optional
        w_j >= 0 [-]; default 1 for every joint.
    chunk_size : int
        Samples per batch (bounds memory).

    Returns
    -------
    ndarray of shape (n_samples,)
        OF(t) [N m].
    """
    terms, weights = _terms(robot, q, qd, qdd, bq, btheta, base, joint_weights, chunk_size)
    return np.asarray((terms.q_error + terms.parameter_error) @ weights)


def estimation_metric(
    robot: RobotModel,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    t: ArrayLike,
    bq: ArrayLike,
    btheta: float | ArrayLike,
    *,
    base: BaseParameters | None = None,
    joint_weights: ArrayLike | None = None,
    time_weight: TimeWeight | None = None,
    chunk_size: int = DEFAULT_CHUNK_SIZE,
) -> float:
    """Estimation metric EM[q] of eq. 3.32 (= OBJ[q] of eq. 3.28), by the trapezoid rule.

    Parameters
    ----------
    robot : RobotModel
        Nominal robot; Θ̂ are its base-parameter values.
    q, qd, qdd : array-like of shape (n_samples, n_dof)
        Joint positions [rad], velocities [rad/s] and accelerations [rad/s²].
    t : array-like of shape (n_samples,)
        Time [s], strictly increasing (need not be regular).
    bq : array-like of shape (l,)
        B_Q̃ (eq. 3.26), e.g. from :func:`q_error_bounds`.
    btheta : float or array-like of shape (n_base,)
        B_Θ̃: relative (0.02 → 2 % of |Θ̂|, eq. 3.40) or per base parameter.
    base : BaseParameters, optional
        Base parameters; by default ``base_parameters(robot)``.
    joint_weights : array-like of shape (n_dof,), optional
        w_j >= 0 [-]; default 1.
    time_weight : callable or array-like of shape (n_samples,), optional
        w_t(t) >= 0 [-]: a function called with ``t`` or its values at ``t``;
        default 1.
    chunk_size : int
        Samples per batch (bounds memory).

    Returns
    -------
    float
        EM [N m s].
    """
    times = np.asarray(t, dtype=float)
    integrand = metric_terms(
        robot, q, qd, qdd, bq, btheta, base=base, joint_weights=joint_weights,
        chunk_size=chunk_size,
    )  # fmt: skip
    _check_time(times, integrand.shape[0])
    weight = _time_weight(time_weight, times)
    return float(trapezoid(weight * integrand, times))


def rank_trajectories(
    robot: RobotModel,
    trajectories: Mapping[str, Trajectory],
    dt: float,
    *,
    noise_std: float | ArrayLike = 1e-5,
    estimator: CausalEstimator | None = None,
    btheta: float | ArrayLike = 0.02,
    bq: ArrayLike | None = None,
    seed: int = 0,
    transient: float = 0.0,
    base: BaseParameters | None = None,
    joint_weights: ArrayLike | None = None,
    time_weight: Callable[[FloatArray], ArrayLike] | None = None,
    chunk_size: int = DEFAULT_CHUNK_SIZE,
) -> pd.DataFrame:
    """Rank trajectories for the same task by EM (thesis Table 3.2), best first.

    Each trajectory is sampled every ``dt``; its B_Q̃ comes from
    :func:`q_error_bounds` (Table 3.1) with the same noise seed for all,
    unless ``bq`` is given.

    Parameters
    ----------
    robot : RobotModel
        Nominal robot.
    trajectories : mapping of str to Trajectory
        The candidates, by name.
    dt : float
        Sample period [s] of the estimator and of the integration.
    noise_std : float or array-like of shape (n_dof,)
        Position noise [rad] for B_Q̃; default 1e-5 rad (a fine encoder).
    estimator : CausalEstimator, optional
        Online velocity/acceleration estimator; default a 5th-order
        Butterworth at 20 Hz (as in the thesis; needs dt < 25 ms).
    btheta : float or array-like of shape (n_base,)
        B_Θ̃: relative (default 0.02, eq. 3.40) or per base parameter.
    bq : array-like of shape (l,), optional
        Fixed B_Q̃ for all trajectories instead of the Table 3.1 method.
    seed : int
        Noise seed.
    transient : float
        Start-up time [s] ignored by :func:`q_error_bounds`.
    base : BaseParameters, optional
        Base parameters; by default ``base_parameters(robot)``.
    joint_weights : array-like of shape (n_dof,), optional
        w_j >= 0; default 1.
    time_weight : callable, optional
        w_t(t) >= 0, called with each trajectory's sample times [s].
    chunk_size : int
        Samples per batch (bounds memory).

    Returns
    -------
    DataFrame
        Index ``trajectory``; columns ``rank`` (1 = best), ``metric`` (EM
        [N m s]), ``q_error_part`` and ``parameter_part`` (the integrals of
        objectives A and B of eq. 3.22, summing to ``metric``), ``duration``
        [s] and ``max_bq_acceleration`` (largest B_Q̃ of q̈ [rad/s²]);
        sorted by ``metric``.
    """
    dt = check_dt(dt)
    if not trajectories:
        raise InputValueError("trajectories is empty; give at least one named Trajectory")
    base = base_parameters(robot) if base is None else base
    est = Butterworth(dt, cutoff=20.0, order=5) if estimator is None else estimator
    rows: dict[str, dict[str, float]] = {}
    for name, trajectory in trajectories.items():
        if not isinstance(trajectory, Trajectory):
            raise InputTypeError(
                f"trajectories[{name!r}] must be a Trajectory; got {type(trajectory).__name__}"
            )
        if trajectory.n_dof != robot.n_dof:
            raise DimensionError(
                f"trajectory {name!r} has {trajectory.n_dof} joints; the robot has {robot.n_dof}"
            )
        t, q, qd, qdd = trajectory.sample(dt)
        if bq is None:
            bounds = q_error_bounds(
                q, dt, est, noise_std=noise_std, seed=seed, reference=(qd, qdd),
                transient=transient,
            )  # fmt: skip
        else:
            bounds = check_bq(bq, robot.n_dof)
        terms, weights = _terms(robot, q, qd, qdd, bounds, btheta, base, joint_weights, chunk_size)
        weight = _time_weight(time_weight, t)
        part_a = float(trapezoid(weight * (terms.q_error @ weights), t))
        part_b = float(trapezoid(weight * (terms.parameter_error @ weights), t))
        rows[name] = {
            "metric": part_a + part_b,
            "q_error_part": part_a,
            "parameter_part": part_b,
            "duration": trajectory.duration,
            "max_bq_acceleration": float(np.max(np.asarray(bounds)[: robot.n_dof])),
        }
    table = pd.DataFrame.from_dict(rows, orient="index").sort_values("metric", kind="stable")
    table.index.name = "trajectory"
    table.insert(0, "rank", np.arange(1, len(table) + 1))
    return table


# ---------------------------------------------------------------------------- helpers


def _terms(
    robot: RobotModel,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    bq: ArrayLike,
    btheta: float | ArrayLike,
    base: BaseParameters | None,
    joint_weights: ArrayLike | None,
    chunk_size: int,
) -> tuple[BoundTerms, FloatArray]:
    """Validate the inputs of the metric and compute its terms."""
    if not isinstance(robot, RobotModel):
        raise InputTypeError(f"robot must be a RobotModel; got {type(robot).__name__}")
    n_dof = robot.n_dof
    qs, _ = as_joint_array(q, n_dof, "q")
    qds, _ = as_joint_array(qd, n_dof, "qd")
    qdds, _ = as_joint_array(qdd, n_dof, "qdd")
    if not qs.shape == qds.shape == qdds.shape:
        raise DimensionError(
            f"q, qd and qdd must have the same shape (n_samples, {n_dof}); got {qs.shape}, "
            f"{qds.shape} and {qdds.shape}"
        )
    base = base_parameters(robot) if base is None else base
    if not isinstance(base, BaseParameters):
        raise InputTypeError(f"base must be a BaseParameters; got {type(base).__name__}")
    if base.robot.n_dof != n_dof:
        raise DimensionError(
            f"base parameters are for {base.robot.n_dof} joints; the robot has {n_dof}"
        )
    theta = base.values_of(robot)
    bounds_q = check_bq(bq, n_dof)
    bounds_theta = parameter_bounds(btheta, theta)
    weights = (
        np.ones(n_dof)
        if joint_weights is None
        else _per_joint_nonnegative(joint_weights, n_dof, "joint_weights", "-")
    )
    terms = error_bound_terms(
        robot, base.independent, theta, qs, qds, qdds, bounds_q, bounds_theta,
        chunk_size=chunk_size,
    )  # fmt: skip
    return terms, weights


def _series(x: ArrayLike, name: str) -> FloatArray:
    arr = np.asarray(x, dtype=float)
    if arr.ndim != 2 or arr.shape[1] < 1:
        raise DimensionError(
            f"{name} must have shape (n_samples, n_dof) with n_dof >= 1; got {arr.shape}"
        )
    check_finite(arr, name)
    return arr


def _per_joint_nonnegative(x: ArrayLike, n_dof: int, name: str, unit: str) -> FloatArray:
    value = np.asarray(x, dtype=float)
    if value.ndim == 0:
        value = np.full(n_dof, float(value))
    if value.shape != (n_dof,):
        raise DimensionError(
            f"{name} must be a scalar or have shape ({n_dof},) for {n_dof} joints; "
            f"got shape {value.shape}"
        )
    if not np.isfinite(value).all() or (value < 0).any():
        raise InputValueError(f"{name} must be finite and >= 0 [{unit}]; got {value}")
    return value


def _transient_samples(transient: float, dt: float, n_samples: int) -> int:
    try:
        value = float(transient)
    except (TypeError, ValueError):
        raise InputValueError(f"transient must be a time >= 0 [s]; got {transient!r}") from None
    skip = int(np.ceil(value / dt - 1e-9)) if np.isfinite(value) else n_samples
    if value < 0 or skip >= n_samples:
        raise InputValueError(
            f"transient must be a time [s] with 0 <= transient < n_samples·dt = "
            f"{n_samples * dt:g} s; got {transient!r}"
        )
    return skip


def _check_time(t: FloatArray, n_samples: int) -> None:
    if t.shape != (n_samples,):
        raise DimensionError(f"t must have shape ({n_samples},) like q; got shape {t.shape}")
    check_finite(t, "t")
    if n_samples > 1 and not (np.diff(t) > 0).all():
        raise InputValueError("t must be strictly increasing [s]")


def _time_weight(time_weight: Any, t: FloatArray) -> FloatArray:
    if time_weight is None:
        return np.ones_like(t)
    weight = np.asarray(time_weight(t) if callable(time_weight) else time_weight, dtype=float)
    if weight.ndim == 0:
        weight = np.full(t.shape, float(weight))
    if weight.shape != t.shape:
        raise DimensionError(
            f"time_weight must give one weight per sample, shape {t.shape}; got shape "
            f"{weight.shape}"
        )
    if not np.isfinite(weight).all() or (weight < 0).any():
        raise InputValueError("time_weight must be finite and >= 0 at every sample")
    return np.asarray(weight)


def _positive_int(value: Any, name: str) -> int:
    try:
        index = operator.index(value)
    except TypeError:
        index = 0
    if isinstance(value, bool) or index < 1:
        raise InputValueError(f"{name} must be an integer >= 1; got {value!r}")
    return index
