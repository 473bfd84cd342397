"""A contact: a force applied at a point fixed on one link, eq. (5.34).

A :class:`Contact` combines a :class:`~sensorless.simulation.force_profiles.ForceProfile`
(magnitude over time [N]) with a unit direction in the base frame and a
point in a link frame [m], and maps the force to joint torques through the
point Jacobian of :meth:`sensorless.robots.RobotModel.point_jacobian`,

    τ_c(t) = J_c(q)ᵀ [f(t) d; 0]                                 eq. (5.34)

with ``d`` the unit direction and no applied moment. Links are numbered from
1 (the link moved by joint 1) to ``n_dof``.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_joint_array, check_int
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..robots.model import RobotModel
from .force_profiles import ForceProfile, _times

__all__ = ["Contact", "joint_torque_sum"]


def _vector3(value: ArrayLike, name: str) -> FloatArray:
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise DimensionError(f"{name} must be a 3-vector; got {value!r}") from None
    if arr.shape != (3,):
        raise DimensionError(f"{name} must be a 3-vector; got shape {arr.shape}")
    if not np.isfinite(arr).all():
        raise InputValueError(f"{name} must be finite; got {arr}")
    return arr


@dataclass(frozen=True, eq=False)
class Contact:
    """A force applied at a point fixed on one link, eq. (5.34).

    Parameters
    ----------
    id : int
        Label of the contact in logs and evaluations, ``>= 1`` (0 means
        "no contact").
    link : int
        Link number, 1-based (link ``k`` is moved by joint ``k``).
    point : array-like of shape (3,)
        Point of application in the link frame [m].
    direction : array-like of shape (3,)
        Direction of the force in the base frame; normalised to a unit
        vector on construction (the zero vector is an error).
    profile : ForceProfile
        Force magnitude over time [N].
    """

    id: int
    link: int
    point: FloatArray
    direction: FloatArray
    profile: ForceProfile

    def __post_init__(self) -> None:
        object.__setattr__(self, "id", check_int(self.id, "contact id", 1))
        object.__setattr__(self, "link", check_int(self.link, f"contact {self.id}: link", 1))
        point = _vector3(self.point, f"contact {self.id}: point [m]")
        direction = _vector3(self.direction, f"contact {self.id}: direction")
        norm = float(np.linalg.norm(direction))
        if norm == 0.0:
            raise InputValueError(
                f"contact {self.id}: direction must be a non-zero vector in the base frame; "
                f"got {direction}"
            )
        direction = direction / norm
        point.setflags(write=False)
        direction.setflags(write=False)
        object.__setattr__(self, "point", point)
        object.__setattr__(self, "direction", direction)
        if not isinstance(self.profile, ForceProfile):
            raise InputTypeError(
                f"contact {self.id}: profile must be a ForceProfile (HalfSine, Push, "
                f"Recorded); got {type(self.profile).__name__}"
            )

    def __eq__(self, other: object) -> bool:
        if not isinstance(other, Contact):
            return NotImplemented
        return (
            self.id == other.id
            and self.link == other.link
            and np.array_equal(self.point, other.point)
            and np.array_equal(self.direction, other.direction)
            and self.profile == other.profile
        )

    __hash__ = None  # type: ignore[assignment]

    @property
    def start(self) -> float:
        """First instant of the contact window [s]."""
        return self.profile.start

    @property
    def end(self) -> float:
        """Last instant of the contact window [s]."""
        return self.profile.end

    def force(self, t: ArrayLike) -> FloatArray:
        """Force vector in the base frame [N] at time(s) ``t`` [s].

        Returns
        -------
        ndarray of shape (3,) or (n_samples, 3)
        """
        magnitude = np.asarray(self.profile(np.asarray(t, dtype=np.float64)))
        return np.asarray(magnitude[..., None] * self.direction)

    def wrench(self, t: ArrayLike) -> FloatArray:
        """Wrench ``[f; m]`` in base axes at the contact point, ``m = 0`` [N, N m].

        Returns
        -------
        ndarray of shape (6,) or (n_samples, 6)
        """
        f = self.force(t)
        return np.concatenate([f, np.zeros_like(f)], axis=-1)

    def check(self, robot: RobotModel) -> None:
        """Raise :class:`InputValueError` if the link is not one of ``robot``'s links."""
        if self.link > robot.n_dof:
            raise InputValueError(
                f"contact {self.id}: link {self.link} does not exist on {robot.name!r}; "
                f"valid links are 1..{robot.n_dof}"
            )

    def joint_torque(self, robot: RobotModel, q: ArrayLike, t: ArrayLike) -> FloatArray:
        """Joint torques caused by the contact, τ_c = J_c(q)ᵀ [f; 0], eq. (5.34).

        The Jacobian is only evaluated at samples where the force is non-zero.

        Parameters
        ----------
        robot : RobotModel
            The robot the contact acts on.
        q : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad].
        t : float or array-like of shape (n_samples,)
            Time(s) [s]; a scalar applies to every sample.

        Returns
        -------
        tau_c : ndarray of the shape of ``q``
            External joint torques [N m].
        """
        return joint_torque_sum((self,), robot, q, t)

    def _torque(self, robot: RobotModel, q: FloatArray, t: FloatArray) -> FloatArray:
        """τ_c of this contact at checked samples ``q`` (n_samples, n_dof) [rad], ``t`` [s]."""
        forces = self.force(t)
        tau = np.zeros_like(q)
        rows = np.flatnonzero(np.any(forces != 0.0, axis=1))
        if rows.size:
            jac = robot.point_jacobian(q[rows], self.link, self.point)
            tau[rows] = np.einsum("kij,ki->kj", jac[:, :3, :], forces[rows])
        return tau

    def summary(self) -> dict[str, Any]:
        """Plain description for log metadata (JSON/YAML friendly).

        Keys: ``id``, ``link``, ``point`` [m], ``direction`` (unit, base
        frame), ``start`` [s], ``end`` [s], ``peak`` [N], ``profile`` (class
        name), ``kind`` (ground-truth label, "intended" or "collision").
        """
        return {
            "id": self.id,
            "link": self.link,
            "point": [float(x) for x in self.point],
            "direction": [float(x) for x in self.direction],
            "start": self.start,
            "end": self.end,
            "peak": self.profile.peak,
            "profile": type(self.profile).__name__,
            "kind": self.profile.kind,
        }


def joint_torque_sum(
    contacts: Iterable[Contact], robot: RobotModel, q: ArrayLike, t: ArrayLike
) -> FloatArray:
    """Sum of the joint torques of ``contacts`` [N m], eq. (5.34).

    The one implementation behind :meth:`Contact.joint_torque` and
    :meth:`ContactSet.joint_torque <sensorless.simulation.contact_set.ContactSet.joint_torque>`,
    with their arguments; every contact is checked against ``robot`` before
    ``q`` and ``t``.
    """
    chosen = list(contacts)
    for contact in chosen:
        contact.check(robot)
    qs, single = as_joint_array(q, robot.n_dof, "q")
    times = _times(t)
    if times.ndim == 0:
        times = np.full(qs.shape[0], float(times))
    elif times.shape != (qs.shape[0],):
        raise DimensionError(
            f"t must be a scalar or have shape ({qs.shape[0]},) to match q; got shape {times.shape}"
        )
    tau = np.zeros_like(qs)
    for contact in chosen:
        tau += contact._torque(robot, qs, times)
    return tau[0] if single else tau
