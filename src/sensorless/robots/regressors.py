"""Regressors of the standard parameters: Y of eq. 2.11 and its split, eq. 3.10–3.12.

The inverse dynamics is linear in the standard parameters π (eq. 2.11),
Y(q, q̇, q̈) π (:func:`regressor`), and Y splits into terms that depend on q only,

    Y(q, q̇, q̈) = Σ_k Y_k^q(q) Q_k,    Q = [q̈; q̇_i q̇_j (i < j); q̇_i²; 1],

with l = (n² + 3n + 2)/2 entries in Q (:func:`q_length`). The terms are
ordered as Q: Y_{M_i} (i = 1..n, columns of M), Y_{B_ij} (i < j,
coefficients of q̇_i q̇_j), Y_{C_i} (coefficients of q̇_i²), Y_g; their
labels are :func:`regressor_term_labels`. The methods of the same names on
:class:`RobotModel` call the functions of this module; :mod:`sensorless.metric`
uses them to bound the error of an acceleration-based torque estimate.

Examples
--------
>>> import numpy as np
>>> import sensorless as sl
>>> robot = sl.robots.load("planar2")
>>> q, qd, qdd = np.array([0.3, -0.2]), np.array([0.5, 1.0]), np.array([-1.0, 2.0])
>>> big_q = q_vector(qd[None], qdd[None])[0]                  # shape (l,) = (6,)
>>> total = np.tensordot(big_q, regressor_terms(robot, q), axes=1)
>>> bool(np.allclose(total, robot.regressor(q, qd, qdd)))
True
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_joint_array
from ..exceptions import DimensionError
from .inertia import N_LINK_PARAMETERS, standard_regressor

if TYPE_CHECKING:
    from .model import RobotModel

__all__ = ["q_length", "q_vector", "regressor", "regressor_term_labels", "regressor_terms"]


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
    shape = np.shape(qd)
    if len(shape) != 2 or shape[1] < 1:
        raise DimensionError(f"qd must have shape (n_samples, n_dof) with n_dof >= 1; got {shape}")
    qds, _ = as_joint_array(qd, shape[1], "qd")
    qdds, _ = as_joint_array(qdd, shape[1], "qdd")
    if qdds.shape != qds.shape:
        raise DimensionError(
            f"qd and qdd must have the same shape (n_samples, n_dof); got {qds.shape} "
            f"and {qdds.shape}"
        )
    upper_i, upper_j = np.triu_indices(qds.shape[1], 1)
    return np.hstack([qdds, qds[:, upper_i] * qds[:, upper_j], qds**2, np.ones((qds.shape[0], 1))])


def regressor(robot: RobotModel, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> FloatArray:
    """Regressor Y(q, q̇, q̈) of the standard parameters: Y π = inverse dynamics (eq. 2.11).

    Columns follow :meth:`RobotModel.parameter_names` (11 per link, armature last).

    Parameters
    ----------
    robot : RobotModel
        Robot whose standard parameters the columns multiply.
    q, qd, qdd : array-like of shape (n_dof,) or (n_samples, n_dof)
        Joint positions [rad], velocities [rad/s], accelerations [rad/s²].

    Returns
    -------
    ndarray of shape (n_dof, 11·n_dof) or (n_samples, n_dof, 11·n_dof)
    """
    shape = (robot.n_dof, robot.n_dof * N_LINK_PARAMETERS)
    states = (q, "q"), (qd, "qd"), (qdd, "qdd")
    # RobotModel's per-sample loop owns the scratch Pinocchio data (robots package internal).
    return robot._per_sample(standard_regressor, shape, *states)


def regressor_terms(robot: RobotModel, q: ArrayLike) -> FloatArray:
    """Split regressor Y_k^q(q) of eq. 3.10–3.12: Y(q, q̇, q̈) = Σ_k Y_k^q(q) Q_k.

    The terms are ordered as :func:`q_vector`; see :func:`regressor_term_labels`.
    Each term is the standard regressor at a unit state that isolates it:
    Y_g at rest, Y_{M_i} from q̈ = e_i, Y_{C_i} from q̇ = e_i, and Y_{B_ij}
    from q̇ = e_i + e_j minus the two squares.

    Parameters
    ----------
    robot : RobotModel
        Robot whose standard parameters the columns multiply.
    q : array-like of shape (n_dof,) or (n_samples, n_dof)
        Joint positions [rad].

    Returns
    -------
    ndarray of shape (l, n_dof, 11·n_dof) or (n_samples, l, n_dof, 11·n_dof)
        With l = (n² + 3n + 2)/2; the columns follow :meth:`RobotModel.parameter_names`.
    """
    n = robot.n_dof
    shape = (q_length(n), n, n * N_LINK_PARAMETERS)
    return robot._per_sample(_sample_terms, shape, (q, "q"))


def regressor_term_labels(n_dof: int) -> list[str]:
    """Labels of the terms of :func:`regressor_terms`: ``M1.., B12.., C1.., g``."""
    pairs = [f"B{i + 1}{j + 1}" for i in range(n_dof) for j in range(i + 1, n_dof)]
    masses = [f"M{i}" for i in range(1, n_dof + 1)]
    return masses + pairs + [f"C{i}" for i in range(1, n_dof + 1)] + ["g"]


def _sample_terms(model: pin.Model, data: pin.Data, q: FloatArray) -> FloatArray:
    """Split regressor of one sample, shape (l, n_dof, 11·n_dof), filled in place."""
    n = model.nv
    out = np.empty((q_length(n), n, n * N_LINK_PARAMETERS))
    zero, eye = np.zeros(n), np.eye(n)
    # Unit states that isolate each term: g at rest, then q̈ = e_i, q̇ = e_i, q̇ = e_i + e_j.
    y_g = out[-1]
    y_g[:] = standard_regressor(model, data, q, zero, zero)
    for i in range(n):
        out[i] = standard_regressor(model, data, q, zero, eye[i]) - y_g
    y_c = out[-1 - n : -1]
    for i in range(n):
        y_c[i] = standard_regressor(model, data, q, eye[i], zero) - y_g
    upper_i, upper_j = np.triu_indices(n, 1)
    for index, (first, second) in enumerate(zip(upper_i, upper_j, strict=True)):
        y_b = standard_regressor(model, data, q, eye[first] + eye[second], zero)
        out[n + index] = y_b - y_g - y_c[first] - y_c[second]
    return out
