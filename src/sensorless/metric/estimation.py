"""Estimation metric EM[q] of a trajectory, eq. 3.24, 3.28 and 3.32, and the ranking of Table 3.2.

Notation and the role of the bounds: :mod:`sensorless.metric`; the bound
terms come from :mod:`sensorless.metric.bounds`.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from scipy.integrate import trapezoid

from .._validation import FloatArray, as_joint_array, check_dt, check_increasing, check_type
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..filters import Butterworth, CausalEstimator
from ..robots.base_parameters import BaseParameters, base_parameters
from ..robots.model import RobotModel
from ..trajectories import Trajectory
from ._checks import nonnegative, per_joint_nonnegative
from .bounds import (
    DEFAULT_CHUNK_SIZE,
    BoundTerms,
    check_bq,
    error_bound_terms,
    parameter_bounds,
    q_error_bounds,
)

__all__ = ["estimation_metric", "metric_terms", "rank_trajectories"]

TimeWeight = Callable[[FloatArray], ArrayLike] | ArrayLike


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
    robot, q, qd, qdd, bq, btheta, base, joint_weights, chunk_size
        As in :func:`metric_terms`: the nominal robot, the trajectory's joint
        positions [rad], velocities [rad/s] and accelerations [rad/s²], the
        bounds B_Q̃ and B_Θ̃, and the weights w_j >= 0 [-].
    t : array-like of shape (n_samples,)
        Time [s], strictly increasing (need not be regular).
    time_weight : callable or array-like of shape (n_samples,), optional
        w_t(t) >= 0 [-]: a function called with ``t`` or its values at ``t``;
        default 1.

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
    n_dof = check_type(robot, RobotModel, "robot").n_dof
    qs, _ = as_joint_array(q, n_dof, "q")
    qds, _ = as_joint_array(qd, n_dof, "qd")
    qdds, _ = as_joint_array(qdd, n_dof, "qdd")
    if not qs.shape == qds.shape == qdds.shape:
        raise DimensionError(
            f"q, qd and qdd must have the same shape (n_samples, {n_dof}); got {qs.shape}, "
            f"{qds.shape} and {qdds.shape}"
        )
    base = base_parameters(robot) if base is None else check_type(base, BaseParameters, "base")
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
        else per_joint_nonnegative(joint_weights, n_dof, "joint_weights", "-")
    )
    terms = error_bound_terms(
        robot, base.independent, theta, qs, qds, qdds, bounds_q, bounds_theta,
        chunk_size=chunk_size,
    )  # fmt: skip
    return terms, weights


def _check_time(t: FloatArray, n_samples: int) -> None:
    if t.shape != (n_samples,):
        raise DimensionError(f"t must have shape ({n_samples},) like q; got shape {t.shape}")
    check_increasing(t, "the trajectory")


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
    return nonnegative(weight, "time_weight")
