"""Inertial data of links and motors, and the order of the standard parameters.

Standard inertial parameters follow thesis Table 2.5: per link
``XX, XY, XZ, YY, YZ, ZZ`` (inertia tensor about the link frame origin,
[kg m²]), ``mX, mY, mZ`` (first moments [kg m]), ``m`` [kg], plus ``Ia``, the
joint-side armature Jm·G² [kg m²] of the motor driving the joint. Pinocchio
orders the same ten inertial numbers differently; :data:`PIN_TO_THESIS` maps
one order to the other.

Six numbers for one inertia tensor
----------------------------------
Tools list the six distinct entries of a symmetric inertia tensor in
different orders; :class:`LinkInertia` reads a 6-vector in the order named by
``order`` (:data:`INERTIA_ORDERS`):

``"urdf"`` (the default)
    xx, xy, xz, yy, yz, zz: the attributes of URDF's ``<inertia>``, ROS
    ``geometry_msgs/Inertia``, and thesis Table 2.5.
``"pinocchio"``
    xx, xy, yy, xz, yz, zz: the lower triangle row by row, as in Pinocchio's
    dynamic parameters ``[m, mx, my, mz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz]``
    (``Inertia.toDynamicParameters``).
``"rtb"``
    xx, yy, zz, xy, yz, xz: ``Link.I`` of Corke's Robotics Toolbox (MATLAB and
    Python).
``"mujoco"``
    xx, yy, zz, xy, xz, yz: MJCF ``fullinertia``.

What a link's inertia must be
-----------------------------
The tensor must be symmetric and positive *semi*-definite: a point mass (zero
tensor) and a thin rod (one zero moment) are the usual idealisations, and
Pinocchio takes them. Its principal moments must also satisfy the triangle
inequality I₁ + I₂ ≥ I₃, as those of every rigid body (a flat plate is the
equality); ``rigid_body=False`` waives this for published data that break it
(the PUMA 560 of Armstrong, Khatib & Burdick 1986, links 1 and 3). Each check
allows a relative round-off of :data:`INERTIA_RTOL`. Every refusal is a
:class:`~sensorless.exceptions.ModelError` that names the link.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import KW_ONLY, InitVar, dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_float_array
from ..exceptions import InputTypeError, ModelError, UnknownNameError

__all__ = [
    "INERTIA_ORDERS",
    "INERTIA_RTOL",
    "N_LINK_PARAMETERS",
    "PARAMETER_NAMES",
    "PIN_TO_THESIS",
    "LinkInertia",
    "MotorData",
    "check_inertia_tensor",
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

#: Orders of the six distinct entries of an inertia tensor, by name (module docstring).
INERTIA_ORDERS: dict[str, tuple[str, ...]] = {
    "urdf": ("xx", "xy", "xz", "yy", "yz", "zz"),
    "pinocchio": ("xx", "xy", "yy", "xz", "yz", "zz"),
    "rtb": ("xx", "yy", "zz", "xy", "yz", "xz"),
    "mujoco": ("xx", "yy", "zz", "xy", "xz", "yz"),
}
#: Relative tolerance of the symmetry, semi-definiteness and triangle checks, as a
#: fraction of the largest entry or principal moment: room for the round-off of
#: rotating a tensor, far below any rounding of published data.
INERTIA_RTOL = 1e-9
_ENTRY = {"xx": (0, 0), "yy": (1, 1), "zz": (2, 2), "xy": (0, 1), "xz": (0, 2), "yz": (1, 2)}


def _tensor_from_entries(values: FloatArray, order: str) -> FloatArray:
    """Symmetric 3x3 tensor from its six distinct entries listed in ``order``."""
    tensor = np.empty((3, 3))
    for entry, value in zip(INERTIA_ORDERS[order], values, strict=True):
        row, column = _ENTRY[entry]
        tensor[row, column] = tensor[column, row] = value
    return tensor


def _moments_text(moments: ArrayLike) -> str:
    return "(" + ", ".join(f"{m:.6g}" for m in np.asarray(moments, dtype=float)) + ")"


def check_inertia_tensor(inertia: FloatArray, where: str, *, rigid_body: bool = True) -> FloatArray:
    """The inertia tensor about a centre of mass, checked as the module docstring states.

    Parameters
    ----------
    inertia : ndarray of shape (3, 3)
        Finite inertia tensor [kg m²].
    where : str
        What it belongs to, first in every message (``"link 'link3'"``).
    rigid_body : bool, default True
        Also require the triangle inequality of the principal moments.

    Returns
    -------
    ndarray of shape (3, 3)
        The tensor made exactly symmetric, with diagonal entries inside the
        round-off tolerance below zero set to zero (Pinocchio refuses them).

    Raises
    ------
    ModelError
        Not symmetric, not positive semi-definite, or (``rigid_body``) principal
        moments that break the triangle inequality.
    """
    asymmetry = float(np.abs(inertia - inertia.T).max())
    if asymmetry > INERTIA_RTOL * float(np.abs(inertia).max()):
        raise ModelError(
            f"{where}: the inertia tensor is not symmetric (largest |I - Iᵀ| entry "
            f"{asymmetry:.6g}) [kg m²]; got {inertia.tolist()}"
        )
    tensor = 0.5 * (inertia + inertia.T)
    moments = np.linalg.eigvalsh(tensor)  # principal moments, ascending
    tolerance = INERTIA_RTOL * float(np.abs(moments).max())
    if moments[0] < -tolerance:
        raise ModelError(
            f"{where}: the inertia tensor is not positive semi-definite (principal moments "
            f"{_moments_text(moments)}) [kg m²]; no moment of inertia is negative"
        )
    if rigid_body and moments[0] + moments[1] < moments[2] - tolerance:
        raise ModelError(
            f"{where}: the principal moments {_moments_text(moments)} [kg m²] break the "
            f"triangle inequality {moments[0]:.6g} + {moments[1]:.6g} < {moments[2]:.6g}; no "
            "rigid body has them (a flat plate is the limit). Check the order of the six "
            "entries, or pass rigid_body=False for published data known to break it"
        )
    np.fill_diagonal(tensor, np.maximum(np.diag(tensor), 0.0))
    return tensor


@dataclass(frozen=True)
class LinkInertia:
    """Inertial parameters of one rigid link.

    Parameters
    ----------
    mass : float
        Link mass [kg], finite and non-negative.
    com : array-like of shape (3,)
        Centre of mass in the link frame [m].
    inertia : array-like of shape (3, 3) or (6,)
        Inertia tensor about the centre of mass, axes of the link frame
        [kg m²]: symmetric, positive semi-definite and, unless ``rigid_body``
        is False, with principal moments that satisfy the triangle inequality
        (module docstring). A 6-vector lists the distinct entries in ``order``.
    name : str, optional
        Link name, first in every error message (the builders name the links
        of a mapping ``link1, link2, ...``).
    rigid_body : bool, default True, keyword-only
        False accepts principal moments that break the triangle inequality
        (published data such as the PUMA 560's links 1 and 3); the tensor must
        still be symmetric and positive semi-definite.
    order : str, default "urdf", keyword-only
        Order of a 6-vector ``inertia``, one of :data:`INERTIA_ORDERS`:
        ``"urdf"`` (xx, xy, xz, yy, yz, zz), ``"pinocchio"`` (xx, xy, yy, xz,
        yz, zz), ``"rtb"`` (xx, yy, zz, xy, yz, xz; Robotics Toolbox) or
        ``"mujoco"`` (xx, yy, zz, xy, xz, yz).

    Raises
    ------
    ModelError
        A mass, centre of mass or tensor that no link has, naming the link.
    UnknownNameError
        An unknown ``order``.

    Examples
    --------
    >>> import numpy as np
    >>> from sensorless.robots import LinkInertia
    >>> rtb = LinkInertia(2.0, (0, 0, 0.1), [0.2, 0.3, 0.4, 0.01, 0.02, 0.03], order="rtb")
    >>> rtb.inertia[0]  # xx, xy, xz
    array([0.2 , 0.01, 0.03])
    >>> LinkInertia(1.0, (0, 0, 0), np.diag([0.1, 0.1, 0.5]), name="link3")  # doctest: +ELLIPSIS
    Traceback (most recent call last):
    ...
    sensorless.exceptions.ModelError: link 'link3': the principal moments (0.1, 0.1, 0.5) ...
    """

    mass: float
    com: ArrayLike
    inertia: ArrayLike
    name: str = ""
    _: KW_ONLY
    rigid_body: bool = True
    order: InitVar[str] = "urdf"

    def __post_init__(self, order: str) -> None:
        if not isinstance(self.name, str):
            raise InputTypeError(f"a link name must be a str; got {type(self.name).__name__}")
        where = self._where()
        if not isinstance(order, str) or order not in INERTIA_ORDERS:
            raise UnknownNameError(
                f"{where}: unknown order {order!r} of the six inertia entries; options: "
                + ", ".join(f"{k} {INERTIA_ORDERS[k]}" for k in INERTIA_ORDERS)
            )
        if not isinstance(self.rigid_body, (bool, np.bool_)):
            raise InputTypeError(
                f"{where}: rigid_body must be True or False; got {self.rigid_body!r}"
            )
        com = as_float_array(self.com, f"{where}: centre of mass", "(3,)")
        inertia = as_float_array(self.inertia, f"{where}: inertia", "(3, 3) or (6,)")
        if com.shape != (3,):
            raise ModelError(
                f"{where}: centre of mass must have 3 entries [m]; got shape {com.shape}"
            )
        if inertia.shape == (6,):
            inertia = _tensor_from_entries(inertia, order)
        if inertia.shape != (3, 3):
            raise ModelError(
                f"{where}: inertia must be a 3x3 tensor or 6 entries in the order {order!r} "
                f"{INERTIA_ORDERS[order]} [kg m²]; got shape {inertia.shape}"
            )
        mass = _mass(self.mass, where)
        if not (np.isfinite(com).all() and np.isfinite(inertia).all()):
            raise ModelError(
                f"{where}: centre of mass and inertia must be finite; got com {com.tolist()}, "
                f"inertia {inertia.tolist()}"
            )
        tensor = check_inertia_tensor(inertia, where, rigid_body=bool(self.rigid_body))
        object.__setattr__(self, "mass", mass)
        object.__setattr__(self, "com", com)
        object.__setattr__(self, "inertia", tensor)
        object.__setattr__(self, "rigid_body", bool(self.rigid_body))

    def _where(self) -> str:
        return f"link {self.name!r}" if self.name else "unnamed link"

    @classmethod
    def coerce(cls, value: LinkInertia | Mapping[str, Any], name: str = "") -> LinkInertia:
        """Accept a :class:`LinkInertia` or a mapping of its arguments.

        Parameters
        ----------
        value : LinkInertia or mapping
            A mapping needs the keys ``mass, com, inertia`` and may have
            ``name, rigid_body, order``; other keys are refused.
        name : str, optional
            Name of the link when the mapping has none.
        """
        if isinstance(value, LinkInertia):
            return value
        if not isinstance(value, Mapping):
            raise InputTypeError(
                f"link inertial data must be a LinkInertia or a mapping with keys mass, com, "
                f"inertia; got {type(value).__name__}"
            )
        where = f"link {value.get('name', name)!r}" if value.get("name", name) else "link"
        missing = [key for key in _REQUIRED if key not in value]
        if missing:
            raise ModelError(
                f"{where}: inertial data needs keys mass, com, inertia; "
                f"missing {missing} in {dict(value)}"
            )
        unknown = [key for key in value if key not in (*_REQUIRED, *_OPTIONAL)]
        if unknown:
            raise InputTypeError(
                f"{where}: unknown keys {unknown} in the inertial data; valid keys: "
                f"{[*_REQUIRED, *_OPTIONAL]}"
            )
        options = {key: value[key] for key in _OPTIONAL if key in value}
        options.setdefault("name", name)
        return cls(value["mass"], value["com"], value["inertia"], **options)

    def to_pinocchio(self) -> pin.Inertia:
        """Pinocchio spatial inertia of this link, expressed in the link frame."""
        try:
            return pin.Inertia(self.mass, np.asarray(self.com), np.asarray(self.inertia))
        except (RuntimeError, ValueError) as exc:  # only if the arrays were changed in place
            raise ModelError(f"{self._where()}: Pinocchio refuses its inertia: {exc}") from None


_REQUIRED = ("mass", "com", "inertia")
_OPTIONAL = ("name", "rigid_body", "order")


def _mass(value: Any, where: str) -> float:
    """A link mass [kg] as a finite float >= 0."""
    try:
        if isinstance(value, (bool, np.bool_)):
            raise TypeError
        mass = float(value)
    except (TypeError, ValueError):
        raise ModelError(f"{where}: mass must be a number [kg]; got {value!r}") from None
    if not np.isfinite(mass):
        raise ModelError(f"{where}: mass must be finite [kg]; got {value!r}")
    if mass < 0:
        raise ModelError(f"{where}: mass must be >= 0 kg; got {value!r}")
    return mass


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
    Identified parameters need not be those of a rigid body, so the only
    inertia refused is one Pinocchio refuses: a negative moment about the
    centre of mass (beyond :data:`INERTIA_RTOL` of the largest one).

    Parameters
    ----------
    values : ndarray of shape (10,)
        Inertia about the link origin [kg m²], first moments [kg m], mass [kg].
    link : int
        Link number (1-based), for the error message.

    Raises
    ------
    ModelError
        A negative mass, first moments without a mass, or a negative moment
        about the centre of mass, naming the link.
    """
    xx, xy, xz, yy, yz, zz, mx, my, mz, mass = values
    inertia_origin = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    first_moment = np.array([mx, my, mz])
    if mass < 0 or (mass == 0 and np.any(first_moment != 0)):
        raise ModelError(
            f"link {link}: mass must be >= 0 and a massless link has zero first moments; "
            f"got m = {mass}, (mX, mY, mZ) = {tuple(first_moment)}"
        )
    com = first_moment / mass if mass > 0 else np.zeros(3)
    inertia = inertia_origin - mass * (com @ com * np.eye(3) - np.outer(com, com))
    diagonal = np.diag(inertia).copy()
    if diagonal.min() < -INERTIA_RTOL * float(np.abs(diagonal).max()):
        raise ModelError(
            f"link {link}: the standard parameters give a negative moment about the centre "
            f"of mass (XX, YY, ZZ there = {_moments_text(diagonal)}) [kg m²]. The inertia "
            "about the link origin includes m·d² of every mass at distance d from it: a "
            "payload added to m and mX, mY, mZ must be added to XX, YY, ZZ too"
        )
    np.fill_diagonal(inertia, np.maximum(diagonal, 0.0))
    return pin.Inertia(float(mass), com, inertia)
