"""Forward kinematics and point Jacobians of a :class:`~sensorless.robots.RobotModel`.

The link frame is the frame of the joint that moves the link (for a modified
DH table, Craig's frame *i*); a link is named by its 1-based number or its
joint name (:meth:`RobotModel.link_id`). Positions are in metres, in the
base frame. Every function accepts one sample, ``q`` of shape ``(n_dof,)``,
or a time series of shape ``(n_samples, n_dof)``, and returns results of the
matching rank; the methods of the same names on :class:`RobotModel` call them.

Examples
--------
>>> import sensorless as sl
>>> robot = sl.robots.load("planar2")
>>> forward_kinematics(robot, [0.0, 0.0], 2, (1.0, 0.0, 0.0)).round(12).tolist()
[2.0, 0.0, 0.0]
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_float_array
from ..exceptions import DimensionError

if TYPE_CHECKING:
    from .model import RobotModel

__all__ = ["check_point", "forward_kinematics", "link_pose", "point_jacobian"]


def link_pose(robot: RobotModel, q: ArrayLike, link: int | str) -> FloatArray:
    """Homogeneous transform of a link frame in the base frame [m].

    Parameters
    ----------
    robot : RobotModel
        Robot whose link frames are meant.
    q : array-like of shape (n_dof,) or (n_samples, n_dof)
        Joint positions [rad].
    link : int or str
        Link number (1-based) or joint name.

    Returns
    -------
    ndarray of shape (4, 4) or (n_samples, 4, 4)
    """
    jid = robot.link_id(link)

    def pose(model: pin.Model, data: pin.Data, qk: FloatArray) -> FloatArray:
        pin.forwardKinematics(model, data, qk)
        return np.asarray(data.oMi[jid].homogeneous)

    # RobotModel's per-sample loop owns the scratch Pinocchio data (robots package internal).
    return robot._per_sample(pose, (4, 4), (q, "q"))


def forward_kinematics(
    robot: RobotModel, q: ArrayLike, link: int | str, point: ArrayLike = (0.0, 0.0, 0.0)
) -> FloatArray:
    """Position in the base frame [m] of a point fixed on a link.

    Parameters
    ----------
    robot, q, link
        As in :func:`link_pose`.
    point : array-like of shape (3,)
        Point in the link frame [m].

    Returns
    -------
    ndarray of shape (3,) or (n_samples, 3)
    """
    pose = link_pose(robot, q, link)
    p = check_point(point)
    return np.asarray(pose[..., :3, :3] @ p + pose[..., :3, 3])


def point_jacobian(
    robot: RobotModel, q: ArrayLike, link: int | str, point: ArrayLike = (0.0, 0.0, 0.0)
) -> FloatArray:
    """Geometric Jacobian of a point fixed on a link, in base-frame axes.

    Rows 0–2 map q̇ to the point's linear velocity [m/s], rows 3–5 to the
    link's angular velocity [rad/s]; so τ_c = Jᵀ [f; m] for a force f [N]
    and moment m [N m] applied at the point, in base axes (eq. 5.34).

    Parameters
    ----------
    robot, q, link, point
        As in :func:`forward_kinematics`: the robot, joint positions [rad],
        link number or joint name, and the point in the link frame [m].

    Returns
    -------
    ndarray of shape (6, n_dof) or (n_samples, 6, n_dof)
    """
    jid = robot.link_id(link)
    p = check_point(point)
    frame = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED

    def jacobian(model: pin.Model, data: pin.Data, qk: FloatArray) -> FloatArray:
        pin.computeJointJacobians(model, data, qk)
        jac = pin.getJointJacobian(model, data, jid, frame)  # at the joint origin
        linear, angular = jac[:3], jac[3:]
        arm = data.oMi[jid].rotation @ p
        return np.vstack([linear - np.cross(arm, angular.T).T, angular])

    return robot._per_sample(jacobian, (6, robot.n_dof), (q, "q"))


def check_point(point: ArrayLike) -> FloatArray:
    """Return ``point`` as a float array of shape (3,) [m] after checking it is finite."""
    p = as_float_array(point, "point", "(3,)")
    if p.shape != (3,) or not np.isfinite(p).all():
        raise DimensionError(
            f"point must be a finite 3-vector in the link frame [m]; got {point!r}"
        )
    return p
