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

:func:`error_bound_terms` evaluates these terms per sample from the
kinematics of the arm (the entries of Y_k^q and Y come from the link
Jacobians, without the l regressor calls of :meth:`RobotModel.regressor_terms`),
compiled with numba when it is installed (``pip install sensorless[fast]``).

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

:func:`optimize_trajectory` solves the problem of eq. 3.29 that the thesis
leaves open: the trajectory between two poses that minimises EM[q], with B_Q̃
of each candidate by the same Table 3.1 method (:mod:`sensorless.metric.optimal`).

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

from .bounds import (
    DEFAULT_CHUNK_SIZE,
    BoundTerms,
    check_bq,
    error_bound_terms,
    parameter_bounds,
    q_error_bounds,
    q_length,
    q_vector,
)
from .estimation import estimation_metric, metric_terms, rank_trajectories
from .optimal import PlannedTrajectory, load_plan, optimize_trajectory

__all__ = [
    "DEFAULT_CHUNK_SIZE",
    "BoundTerms",
    "PlannedTrajectory",
    "check_bq",
    "error_bound_terms",
    "estimation_metric",
    "load_plan",
    "metric_terms",
    "optimize_trajectory",
    "parameter_bounds",
    "q_error_bounds",
    "q_length",
    "q_vector",
    "rank_trajectories",
]
