"""Inertial data of links and motors, and the order of the standard parameters.

Standard inertial parameters follow thesis Table 2.5: per link
``XX, XY, XZ, YY, YZ, ZZ`` (inertia tensor about the link frame origin,
[kg m²]), ``mX, mY, mZ`` (first moments [kg m]), ``m`` [kg], plus ``Ia``, the
joint-side armature Jm·G² [kg m²] of the motor driving the joint. Pinocchio
orders the same ten inertial numbers differently; :data:`PIN_TO_THESIS` maps
one order to the other.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_float_array
from ..exceptions import ModelError

__all__ = [
    "N_LINK_PARAMETERS",
    "PARAMETER_NAMES",
    "PIN_TO_THESIS",
    "LinkInertia",
    "MotorData",
    "inertia_from_parameters",
    "parameters_from_inertia",
    "standard_regressor",
]

#: Standard parameters of one link, in the order of thesis Table 2.5 plus the armature.
PARAMETER_NAMES: tuple[str, ...] = (
    "XX", "XY", "XZ", "YY", "YZ", "ZZ", "mX", "mY", "mZ", "m", "Ia",
)  # fmt: skip
N_LINK_PARAMETERS = len(PARAMETER_NAMES)
#: Pinocchio's dynamic parameters are [m, mx, my, mz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz];
#: ``PIN_TO_THESIS[k]`` is the index in Pinocchio's vector of ``PARAMETER_NAMES[k]``.
PIN_TO_THESIS = np.array([4, 5, 7, 6, 8, 9, 1, 2, 3, 0])


@dataclass(frozen=True)
class LinkInertia:
    """Inertial parameters of one rigid link.

    Parameters
    ----------
    mass : float
        Link mass [kg], non-negative.
    com : array-like of shape (3,)
        Centre of mass in the link frame [m].
    inertia : array-like of shape (3, 3) or (6,)
        Inertia tensor about the centre of mass, axes of the link frame
        [kg m²]; a 6-vector is read as (xx, xy, xz, yy, yz, zz).
    """

    mass: float
    com: ArrayLike
    inertia: ArrayLike

    def __post_init__(self) -> None:
        com = as_float_array(self.com, "centre of mass", "(3,)")
        inertia = as_float_array(self.inertia, "inertia", "(3, 3) or (6,)")
        if inertia.shape == (6,):
            xx, xy, xz, yy, yz, zz = inertia
            inertia = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
        if com.shape != (3,):
            raise ModelError(f"centre of mass must have 3 entries [m]; got shape {com.shape}")
        if inertia.shape != (3, 3):
            raise ModelError(
                "inertia must be a 3x3 tensor or (xx, xy, xz, yy, yz, zz) [kg m²]; "
                f"got shape {inertia.shape}"
            )
        if not (np.isfinite(self.mass) and np.isfinite(com).all() and np.isfinite(inertia).all()):
            raise ModelError("link mass, centre of mass and inertia must be finite")
        if self.mass < 0:
            raise ModelError(f"link mass must be >= 0 kg; got {self.mass}")
        object.__setattr__(self, "mass", float(self.mass))
        object.__setattr__(self, "com", com)
        object.__setattr__(self, "inertia", 0.5 * (inertia + inertia.T))

    @classmethod
    def coerce(cls, value: LinkInertia | Mapping[str, Any]) -> LinkInertia:
        """Accept a :class:`LinkInertia` or a mapping with keys ``mass, com, inertia``."""
        if isinstance(value, LinkInertia):
            return value
        missing = [key for key in ("mass", "com", "inertia") if key not in value]
        if missing:
            raise ModelError(
                "link inertial data needs keys mass, com, inertia; "
                f"missing {missing} in {dict(value)}"
            )
        return cls(value["mass"], value["com"], value["inertia"])

    def to_pinocchio(self) -> pin.Inertia:
        """Pinocchio spatial inertia of this link, expressed in the link frame."""
        return pin.Inertia(self.mass, np.asarray(self.com), np.asarray(self.inertia))


@dataclass(frozen=True)
class MotorData:
    """Per-joint motor data giving the joint-side armature Jm·G².

    Parameters
    ----------
    rotor_inertia : array-like of shape (n_dof,)
        Rotor inertia Jm on the motor side [kg m²].
    gear_ratio : array-like of shape (n_dof,)
        Gear ratio G (motor angle / joint angle) [-]; its sign is irrelevant here.
    """

    rotor_inertia: ArrayLike
    gear_ratio: ArrayLike

    def __post_init__(self) -> None:
        jm = np.atleast_1d(as_float_array(self.rotor_inertia, "rotor_inertia", "(n_dof,)"))
        ratio = np.atleast_1d(as_float_array(self.gear_ratio, "gear_ratio", "(n_dof,)"))
        if jm.shape != ratio.shape or jm.ndim != 1:
            raise ModelError(
                "rotor_inertia and gear_ratio must be 1-D arrays of the same length; "
                f"got shapes {jm.shape} and {ratio.shape}"
            )
        if (jm < 0).any() or not np.isfinite(jm).all() or not np.isfinite(ratio).all():
            raise ModelError(f"rotor inertias must be finite and >= 0 kg m²; got {jm}")
        object.__setattr__(self, "rotor_inertia", jm)
        object.__setattr__(self, "gear_ratio", ratio)

    @property
    def armature(self) -> FloatArray:
        """Joint-side armature Jm·G² [kg m²], shape (n_dof,)."""
        return np.asarray(self.rotor_inertia) * np.asarray(self.gear_ratio) ** 2


def parameters_from_inertia(inertia: pin.Inertia) -> FloatArray:
    """(XX, XY, XZ, YY, YZ, ZZ, mX, mY, mZ, m) of a spatial inertia, about the link origin."""
    return np.asarray(inertia.toDynamicParameters()[PIN_TO_THESIS], dtype=float)


def standard_regressor(
    model: pin.Model, data: pin.Data, q: FloatArray, qd: FloatArray, qdd: FloatArray
) -> FloatArray:
    """Regressor Y(q, q̇, q̈) of one sample, columns in :data:`PARAMETER_NAMES` order per link.

    Pinocchio's joint-torque regressor, its ten columns per link reordered
    to thesis Table 2.5, plus the armature column Ia (torque Ia_i q̈_i on joint i).

    Parameters
    ----------
    model, data : pinocchio.Model, pinocchio.Data
        Robot model and its scratch data.
    q, qd, qdd : ndarray of shape (n_dof,)
        Joint positions [rad], velocities [rad/s], accelerations [rad/s²].

    Returns
    -------
    ndarray of shape (n_dof, 11·n_dof)
    """
    n = model.nv
    y10 = pin.computeJointTorqueRegressor(model, data, q, qd, qdd).reshape(n, n, 10)
    out = np.empty((n, n, N_LINK_PARAMETERS))
    out[:, :, :10] = y10[:, :, PIN_TO_THESIS]
    out[:, :, 10] = np.diag(qdd)
    return out.reshape(n, n * N_LINK_PARAMETERS)


def inertia_from_parameters(values: FloatArray, link: int) -> pin.Inertia:
    """Spatial inertia from (XX, XY, XZ, YY, YZ, ZZ, mX, mY, mZ, m) about the link origin.

    Pinocchio's ``FromDynamicParameters`` divides by the mass; a massless link
    (PUMA link 1) keeps its rotational inertia here instead of turning into NaN.

    Parameters
    ----------
    values : ndarray of shape (10,)
        Inertia about the link origin [kg m²], first moments [kg m], mass [kg].
    link : int
        Link number (1-based), for the error message.
    """
    xx, xy, xz, yy, yz, zz, mx, my, mz, mass = values
    inertia_origin = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    first_moment = np.array([mx, my, mz])
    if mass > 0:
        com = first_moment / mass
        shift = mass * (com @ com * np.eye(3) - np.outer(com, com))
        return pin.Inertia(mass, com, inertia_origin - shift)
    if mass < 0 or np.any(first_moment != 0):
        raise ModelError(
            f"link {link}: mass must be >= 0 and a massless link has zero first moments; "
            f"got m = {mass}, (mX, mY, mZ) = {tuple(first_moment)}"
        )
    return pin.Inertia(0.0, np.zeros(3), inertia_origin)
