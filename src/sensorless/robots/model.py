"""Immutable robot models built on Pinocchio.

A :class:`RobotModel` holds the constants of a serial arm (kinematics,
inertial parameters, armature, optional friction) in a Pinocchio ``Model``;
the scratch ``Data`` Pinocchio needs is private to the instance. Every
dynamics method accepts one sample, arrays of shape ``(n_dof,)``, or a time
series, arrays of shape ``(n_samples, n_dof)`` with time along axis 0, and
returns results of the matching rank. Units are SI and radians.

Standard inertial parameters follow thesis Table 2.5: per link
``XX, XY, XZ, YY, YZ, ZZ`` (inertia tensor about the link frame origin,
[kg m²]), ``mX, mY, mZ`` (first moments [kg m]), ``m`` [kg], plus ``Ia``, the
joint-side armature Jm·G² [kg m²] of the motor driving the joint. The link
frame is the frame of the joint that moves the link (for a modified DH table
it is Craig's frame *i*).
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np
import pandas as pd
import pinocchio as pin
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_joint_array, check_finite
from ..exceptions import DimensionError, InputValueError, ModelError

if TYPE_CHECKING:
    from ..friction import FrictionModel

__all__ = [
    "PARAMETER_NAMES",
    "LinkInertia",
    "MotorData",
    "RobotModel",
]

#: Standard parameters of one link, in the order of thesis Table 2.5 plus the armature.
PARAMETER_NAMES: tuple[str, ...] = (
    "XX", "XY", "XZ", "YY", "YZ", "ZZ", "mX", "mY", "mZ", "m", "Ia",
)  # fmt: skip
N_LINK_PARAMETERS = len(PARAMETER_NAMES)
# Pinocchio's dynamic parameters are [m, mx, my, mz, Ixx, Ixy, Iyy, Ixz, Iyz, Izz];
# _PIN_TO_THESIS[k] is the index in Pinocchio's vector of PARAMETER_NAMES[k].
_PIN_TO_THESIS = np.array([4, 5, 7, 6, 8, 9, 1, 2, 3, 0])
_MDH_FIELDS = ("alpha", "a", "theta", "d")
_GRIPPER_WORDS = ("finger", "gripper", "hand")


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
        com = np.asarray(self.com, dtype=float)
        inertia = np.asarray(self.inertia, dtype=float)
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
        jm = np.atleast_1d(np.asarray(self.rotor_inertia, dtype=float))
        ratio = np.atleast_1d(np.asarray(self.gear_ratio, dtype=float))
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


def _rot_x(angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rot_z(angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _se3(rotation: FloatArray, translation: ArrayLike) -> pin.SE3:
    return pin.SE3(rotation, np.asarray(translation, dtype=float))


def _dh_rows(table: Any, kind: str) -> list[dict[str, float]]:
    """Read a DH table (DataFrame, sequence of mappings or of 4-sequences) into dicts."""
    if isinstance(table, pd.DataFrame):
        rows: list[Any] = table.to_dict("records")
    else:
        rows = list(table)
    if not rows:
        raise ModelError(f"the {kind} DH table is empty; expected one row per joint")
    out = []
    for index, row in enumerate(rows, start=1):
        if isinstance(row, Mapping):
            missing = [key for key in _MDH_FIELDS if key not in row or row[key] is None]
            if missing:
                raise ModelError(
                    f"{kind} DH row {index} is missing {missing}; every row needs "
                    f"{list(_MDH_FIELDS)} (alpha, theta offset [rad]; a, d [m])"
                )
            values = {key: row[key] for key in _MDH_FIELDS}
        else:
            seq = list(row)
            if len(seq) != 4:
                raise ModelError(
                    f"{kind} DH row {index} has {len(seq)} fields; expected 4 in the order "
                    f"{list(_MDH_FIELDS)}"
                )
            values = dict(zip(_MDH_FIELDS, seq, strict=True))
        try:
            parsed = {key: float(value) for key, value in values.items()}
        except (TypeError, ValueError):
            raise ModelError(f"{kind} DH row {index} has a non-numeric field: {values}") from None
        if not all(math.isfinite(v) for v in parsed.values()):
            raise ModelError(f"{kind} DH row {index} has a non-finite field: {parsed}")
        for key in ("alpha", "theta"):
            if abs(parsed[key]) > 2 * math.pi + 1e-9:
                raise InputValueError(
                    f"{kind} DH row {index}: {key} = {parsed[key]} is larger than 2π; angles "
                    "are radians (this looks like degrees: use numpy.deg2rad)"
                )
        out.append(parsed)
    return out


def _coerce_links(links: Sequence[Any], n_dof: int) -> list[LinkInertia]:
    if len(links) != n_dof:
        raise DimensionError(
            f"expected inertial data for {n_dof} links (one per DH row); got {len(links)}"
        )
    return [LinkInertia.coerce(link) for link in links]


def _armature(motors: MotorData | Mapping[str, Any] | None, n_dof: int) -> FloatArray:
    if motors is None:
        return np.zeros(n_dof)
    if not isinstance(motors, MotorData):
        motors = MotorData(motors["rotor_inertia"], motors["gear_ratio"])
    if motors.armature.shape != (n_dof,):
        raise DimensionError(
            f"motor data must have {n_dof} entries (one per joint); got {motors.armature.shape[0]}"
        )
    return motors.armature


@dataclass(frozen=True, eq=False)
class RobotModel:
    """Immutable model of a serial manipulator with revolute joints.

    Build it with :meth:`from_mdh`, :meth:`from_dh`, :meth:`from_urdf` or
    :meth:`from_pinocchio`; derive variants with :meth:`with_standard_parameters`.
    Not thread-safe: give each thread its own model (``copy.deepcopy``).

    Parameters
    ----------
    pinocchio_model : pinocchio.Model
        Rigid-body model; it is copied, and must have ``n_dof`` one-DoF joints
        (``nq == nv``). Do not mutate :attr:`pinocchio_model` afterwards.
    name : str
        Human-readable name.
    friction : FrictionModel or None
        Joint friction model (see :mod:`sensorless.friction`), or None.
    description : str
        Where the numbers come from.
    """

    pinocchio_model: pin.Model
    name: str = "robot"
    friction: FrictionModel | None = None
    description: str = ""
    _data: pin.Data = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        model = self.pinocchio_model.copy()
        if model.nq != model.nv or model.nv == 0:
            raise ModelError(
                "RobotModel needs a chain of one-DoF joints (nq == nv > 0); "
                f"got nq={model.nq}, nv={model.nv}"
            )
        object.__setattr__(self, "pinocchio_model", model)
        object.__setattr__(self, "_data", model.createData())
        friction_dof = getattr(self.friction, "n_dof", model.nv)
        if self.friction is not None and friction_dof != model.nv:
            raise DimensionError(
                f"friction model has {friction_dof} joints; the robot has {model.nv}"
            )

    # ------------------------------------------------------------------ builders
    @classmethod
    def from_mdh(
        cls,
        table: Any,
        links: Sequence[LinkInertia | Mapping[str, Any]],
        motors: MotorData | Mapping[str, Any] | None = None,
        *,
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        friction: FrictionModel | None = None,
        name: str = "robot",
        description: str = "",
        position_limits: tuple[ArrayLike, ArrayLike] | None = None,
        velocity_limits: ArrayLike | None = None,
        effort_limits: ArrayLike | None = None,
    ) -> RobotModel:
        """Build a revolute arm from a modified DH table (Craig convention).

        Frame *i* follows frame *i-1* by Rx(α_{i-1}) Tx(a_{i-1}) Rz(θ_i) Tz(d_i),
        θ_i = q_i + θ offset; the row of joint *i* holds (α_{i-1}, a_{i-1}, θ offset,
        d_i) as in thesis Table 2.4.

        Parameters
        ----------
        table : DataFrame, sequence of mappings or sequence of 4-sequences
            One row per joint with ``alpha`` [rad], ``a`` [m], ``theta`` offset [rad],
            ``d`` [m].
        links : sequence of LinkInertia or mappings
            Mass [kg], centre of mass [m] and inertia about the centre of mass
            [kg m²] of each link, in its link frame *i*.
        motors : MotorData or mapping, optional
            Rotor inertia [kg m²] and gear ratio per joint; armature = Jm·G².
        gravity : array-like of shape (3,)
            Gravity in the base frame [m/s²].
        friction : FrictionModel, optional
            Joint friction.
        position_limits, velocity_limits, effort_limits : optional
            Joint limits (lower, upper) [rad], [rad/s], [N m]; unlimited by default.
        """
        rows = _dh_rows(table, "modified")
        n_dof = len(rows)
        inertias = _coerce_links(links, n_dof)
        model = pin.Model()
        model.name = name
        parent = 0
        for i, (row, link) in enumerate(zip(rows, inertias, strict=True), start=1):
            rotation = _rot_x(row["alpha"]) @ _rot_z(row["theta"])
            translation = np.array([row["a"], 0.0, 0.0]) + rotation @ np.array([0, 0, row["d"]])
            placement = _se3(rotation, translation)
            parent = model.addJoint(parent, pin.JointModelRZ(), placement, f"joint{i}")
            model.appendBodyToJoint(parent, link.to_pinocchio(), pin.SE3.Identity())
        return cls._finish(
            model, _armature(motors, n_dof), gravity, friction, name, description,
            position_limits, velocity_limits, effort_limits,
        )  # fmt: skip

    @classmethod
    def from_dh(
        cls,
        table: Any,
        links: Sequence[LinkInertia | Mapping[str, Any]],
        motors: MotorData | Mapping[str, Any] | None = None,
        *,
        gravity: ArrayLike = (0.0, 0.0, -9.81),
        friction: FrictionModel | None = None,
        name: str = "robot",
        description: str = "",
        position_limits: tuple[ArrayLike, ArrayLike] | None = None,
        velocity_limits: ArrayLike | None = None,
        effort_limits: ArrayLike | None = None,
    ) -> RobotModel:
        """Build a revolute arm from a standard (distal) DH table.

        Frame *i* follows frame *i-1* by Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i); joint *i*
        turns about z_{i-1}. Inertial data of link *i* are given in frame *i*
        (as in Corke's toolbox). The model's link frame for the standard
        parameters is the joint frame z_{i-1} rotated by q_i.
        Parameters as in :meth:`from_mdh`.
        """
        rows = _dh_rows(table, "standard")
        n_dof = len(rows)
        inertias = _coerce_links(links, n_dof)
        model = pin.Model()
        model.name = name
        parent = 0
        previous_tail = pin.SE3.Identity()
        for i, (row, link) in enumerate(zip(rows, inertias, strict=True), start=1):
            placement = previous_tail * _se3(_rot_z(row["theta"]), np.zeros(3))
            parent = model.addJoint(parent, pin.JointModelRZ(), placement, f"joint{i}")
            # Frame i relative to the moving joint frame: Tz(d) Tx(a) Rx(alpha).
            tail = _se3(_rot_x(row["alpha"]), [row["a"], 0.0, row["d"]])
            model.appendBodyToJoint(parent, link.to_pinocchio(), tail)
            previous_tail = tail
        return cls._finish(
            model, _armature(motors, n_dof), gravity, friction, name, description,
            position_limits, velocity_limits, effort_limits,
        )  # fmt: skip

    @classmethod
    def from_urdf(
        cls,
        path: str | Path,
        joints: Sequence[str] | None = None,
        *,
        tip: str | None = None,
        friction: FrictionModel | None = None,
        armature: ArrayLike | None = None,
        name: str | None = None,
        description: str = "",
    ) -> RobotModel:
        """Build a model from a URDF file with Pinocchio's parser.

        Parameters
        ----------
        path : str or Path
            URDF file.
        joints : sequence of str, optional
            Names of the arm joints to keep, in order; every other movable joint
            is locked at zero (its links stay, rigidly attached). By default,
            every movable joint whose name does not mention a gripper
            (finger, gripper, hand).
        tip : str, optional
            Link name at which to cut the tree: links that are not ancestors of
            ``tip`` (a gripper, a hand, sensors) are removed, mass included.
        friction : FrictionModel, optional
            Joint friction (URDF ``<dynamics>`` tags are ignored).
        armature : array-like of shape (n_dof,), optional
            Joint-side rotor inertia Jm·G² [kg m²].
        """
        path = Path(path)
        if not path.is_file():
            raise ModelError(f"URDF file not found: {path}")
        try:
            tree = ET.parse(path)
        except ET.ParseError as exc:
            raise ModelError(f"cannot parse URDF {path}: {exc}") from None
        root = tree.getroot()
        if tip is not None:
            _prune_urdf(root, tip)
        try:
            full = pin.buildModelFromXML(ET.tostring(root, encoding="unicode"))
        except (RuntimeError, ValueError) as exc:
            raise ModelError(f"Pinocchio could not build a model from {path}: {exc}") from None
        movable = [full.names[j] for j in range(1, full.njoints) if full.joints[j].nv > 0]
        if joints is None:
            joints = [j for j in movable if not any(w in j.lower() for w in _GRIPPER_WORDS)]
        unknown = [j for j in joints if j not in movable]
        if unknown:
            raise ModelError(
                f"joints {unknown} are not movable joints of {path}; options: {movable}"
            )
        lock = [full.getJointId(j) for j in movable if j not in joints]
        model = pin.buildReducedModel(full, lock, pin.neutral(full)) if lock else full
        order = [model.names[j] for j in range(1, model.njoints)]
        if order != list(joints):
            raise ModelError(f"joints must be listed in chain order {order}; got {list(joints)}")
        n_dof = model.nv
        arm = np.zeros(n_dof) if armature is None else np.asarray(armature, dtype=float)
        if arm.shape != (n_dof,):
            raise DimensionError(f"armature must have {n_dof} entries; got shape {arm.shape}")
        model.armature = arm
        return cls(model, name or str(root.get("name", path.stem)), friction, description)

    @classmethod
    def from_pinocchio(
        cls, model: pin.Model, *, name: str | None = None, friction: FrictionModel | None = None
    ) -> RobotModel:
        """Wrap an existing Pinocchio model (copied); its ``armature`` is the joint armature."""
        return cls(model, name or model.name or "robot", friction)

    @classmethod
    def _finish(
        cls,
        model: pin.Model,
        armature: FloatArray,
        gravity: ArrayLike,
        friction: FrictionModel | None,
        name: str,
        description: str,
        position_limits: tuple[ArrayLike, ArrayLike] | None,
        velocity_limits: ArrayLike | None,
        effort_limits: ArrayLike | None,
    ) -> RobotModel:
        n_dof = model.nv
        model.armature = armature
        grav = np.asarray(gravity, dtype=float)
        if grav.shape != (3,) or not np.isfinite(grav).all():
            raise ModelError(f"gravity must be a finite 3-vector [m/s²]; got {gravity!r}")
        model.gravity = pin.Motion(grav, np.zeros(3))
        inf = np.full(n_dof, np.inf)
        lower, upper = (-inf, inf) if position_limits is None else position_limits
        model.lowerPositionLimit = np.broadcast_to(np.asarray(lower, float), (n_dof,)).copy()
        model.upperPositionLimit = np.broadcast_to(np.asarray(upper, float), (n_dof,)).copy()
        for attr, value in (("velocityLimit", velocity_limits), ("effortLimit", effort_limits)):
            arr = inf if value is None else np.broadcast_to(np.asarray(value, float), (n_dof,))
            setattr(model, attr, arr.copy())
        return cls(model, name, friction, description)

    # ------------------------------------------------------------------ properties
    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return int(self.pinocchio_model.nv)

    @property
    def joint_names(self) -> list[str]:
        """Joint names in model order."""
        return [self.pinocchio_model.names[j] for j in range(1, self.pinocchio_model.njoints)]

    @property
    def armature(self) -> FloatArray:
        """Joint-side armature Jm·G² [kg m²], shape (n_dof,)."""
        return np.array(self.pinocchio_model.armature, dtype=float)

    @property
    def position_limits(self) -> tuple[FloatArray, FloatArray]:
        """Lower and upper joint limits [rad]."""
        m = self.pinocchio_model
        return np.array(m.lowerPositionLimit), np.array(m.upperPositionLimit)

    @property
    def velocity_limits(self) -> FloatArray:
        """Joint speed limits [rad/s] (inf when unknown)."""
        return np.array(self.pinocchio_model.velocityLimit)

    @property
    def effort_limits(self) -> FloatArray:
        """Joint torque limits [N m] (inf when unknown)."""
        return np.array(self.pinocchio_model.effortLimit)

    @property
    def gravity_vector(self) -> FloatArray:
        """Gravity acceleration in the base frame [m/s²]."""
        return np.array(self.pinocchio_model.gravity.linear)

    def __repr__(self) -> str:
        return f"RobotModel(name={self.name!r}, n_dof={self.n_dof})"

    # ------------------------------------------------------------------ parameters
    def parameter_names(self) -> list[str]:
        """Names of the standard parameters, ``XX1 ... Ia1, XX2, ...`` (11 per link)."""
        return [f"{p}{i}" for i in range(1, self.n_dof + 1) for p in PARAMETER_NAMES]

    def parameter_vector(self) -> FloatArray:
        """Standard parameters π of shape (11·n_dof,), ordered as :meth:`parameter_names`."""
        model = self.pinocchio_model
        out = np.empty((self.n_dof, N_LINK_PARAMETERS))
        for i in range(self.n_dof):
            out[i, :10] = model.inertias[i + 1].toDynamicParameters()[_PIN_TO_THESIS]
        out[:, 10] = model.armature
        return out.ravel()

    def standard_parameters(self) -> pd.DataFrame:
        """Standard inertial parameters, one row per link (thesis Table 2.5 names).

        Returns
        -------
        DataFrame of shape (n_dof, 11)
            Columns ``XX, XY, XZ, YY, YZ, ZZ`` [kg m²] about the link frame origin,
            ``mX, mY, mZ`` [kg m], ``m`` [kg], ``Ia`` [kg m²]; index ``link1 ...``.
        """
        values = self.parameter_vector().reshape(self.n_dof, N_LINK_PARAMETERS)
        index = pd.Index([f"link{i}" for i in range(1, self.n_dof + 1)], name="link")
        return pd.DataFrame(values, index=index, columns=list(PARAMETER_NAMES))

    def with_standard_parameters(
        self, parameters: ArrayLike, *, friction: Any = "keep", name: str | None = None
    ) -> RobotModel:
        """Return a copy whose standard parameters are ``parameters``.

        Parameters
        ----------
        parameters : array-like of shape (11·n_dof,) or (n_dof, 11) or DataFrame
            Values in the order of :meth:`parameter_names`.
        friction : FrictionModel or None, optional
            New friction model; by default the current one is kept.
        """
        values = np.asarray(parameters, dtype=float).reshape(-1)
        expected = self.n_dof * N_LINK_PARAMETERS
        if values.shape != (expected,):
            raise DimensionError(
                f"expected {expected} standard parameters ({self.n_dof} links x 11); "
                f"got {np.size(parameters)}"
            )
        check_finite(values, "standard parameters")
        per_link = values.reshape(self.n_dof, N_LINK_PARAMETERS)
        model = self.pinocchio_model.copy()
        for i in range(self.n_dof):
            model.inertias[i + 1] = _inertia_from_parameters(per_link[i, :10], i + 1)
        model.armature = per_link[:, 10].copy()
        new_friction = self.friction if friction == "keep" else friction
        return RobotModel(model, name or self.name, new_friction, self.description)

    # ------------------------------------------------------------------ helpers
    def _states(self, *arrays: tuple[ArrayLike, str]) -> tuple[list[FloatArray], bool]:
        out, singles, lengths = [], set(), set()
        for value, label in arrays:
            arr, single = as_joint_array(value, self.n_dof, label)
            out.append(arr)
            singles.add(single)
            lengths.add(arr.shape[0])
        if len(lengths) > 1:
            raise DimensionError(
                f"{', '.join(label for _, label in arrays)} must have the same number of "
                f"samples; got {[a.shape[0] for a in out]}"
            )
        return out, singles == {True}

    def link_id(self, link: int | str) -> int:
        """Pinocchio joint id of ``link``: a 1-based link number or a joint name."""
        if isinstance(link, str):
            if link not in self.joint_names:
                raise ModelError(f"unknown joint {link!r}; options: {self.joint_names}")
            return int(self.pinocchio_model.getJointId(link))
        if isinstance(link, (int, np.integer)) and 1 <= int(link) <= self.n_dof:
            return int(link)
        raise ModelError(
            f"link must be a number from 1 to {self.n_dof} or a joint name; got {link!r}"
        )

    # ------------------------------------------------------------------ dynamics
    def mass_matrix(self, q: ArrayLike) -> FloatArray:
        """Joint-space inertia matrix M(q), armature included [kg m²].

        Parameters
        ----------
        q : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad].

        Returns
        -------
        ndarray of shape (n_dof, n_dof) or (n_samples, n_dof, n_dof)
        """
        (qs,), single = self._states((q, "q"))
        model, data = self.pinocchio_model, self._data
        out = np.empty((qs.shape[0], self.n_dof, self.n_dof))
        for k, qk in enumerate(qs):
            out[k] = pin.crba(model, data, qk)
        # CRBA fills the upper triangle; mirror it once for the whole batch.
        out = np.triu(out) + np.swapaxes(np.triu(out, 1), 1, 2)
        return out[0] if single else out

    def coriolis_matrix(self, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """Coriolis/centrifugal matrix C(q, q̇) with Ṁ − 2C skew-symmetric [kg m²/s].

        Parameters
        ----------
        q, qd : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad] and velocities [rad/s].

        Returns
        -------
        ndarray of shape (n_dof, n_dof) or (n_samples, n_dof, n_dof)
        """
        (qs, qds), single = self._states((q, "q"), (qd, "qd"))
        model, data = self.pinocchio_model, self._data
        out = np.empty((qs.shape[0], self.n_dof, self.n_dof))
        for k in range(qs.shape[0]):
            out[k] = pin.computeCoriolisMatrix(model, data, qs[k], qds[k])
        return out[0] if single else out

    def coriolis_transpose_velocity(self, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """C(q, q̇)ᵀ q̇ [N m], the term of the momentum observer (eq. 4.4).

        Parameters
        ----------
        q, qd : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad] and velocities [rad/s].

        Returns
        -------
        ndarray of shape (n_dof,) or (n_samples, n_dof)
        """
        (qs, qds), single = self._states((q, "q"), (qd, "qd"))
        model, data = self.pinocchio_model, self._data
        out = np.empty_like(qs)
        for k in range(qs.shape[0]):
            out[k] = pin.computeCoriolisMatrix(model, data, qs[k], qds[k]).T @ qds[k]
        return out[0] if single else out

    def gravity(self, q: ArrayLike) -> FloatArray:
        """Gravity torque g(q) [N m].

        Parameters
        ----------
        q : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad].

        Returns
        -------
        ndarray of shape (n_dof,) or (n_samples, n_dof)
        """
        (qs,), single = self._states((q, "q"))
        model, data = self.pinocchio_model, self._data
        out = np.empty_like(qs)
        for k in range(qs.shape[0]):
            out[k] = pin.computeGeneralizedGravity(model, data, qs[k])
        return out[0] if single else out

    def nonlinear_effects(self, q: ArrayLike, qd: ArrayLike) -> FloatArray:
        """C(q, q̇) q̇ + g(q) [N m]; shapes as in :meth:`coriolis_transpose_velocity`."""
        (qs, qds), single = self._states((q, "q"), (qd, "qd"))
        model, data = self.pinocchio_model, self._data
        out = np.empty_like(qs)
        for k in range(qs.shape[0]):
            out[k] = pin.nonLinearEffects(model, data, qs[k], qds[k])
        return out[0] if single else out

    def inverse_dynamics(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> FloatArray:
        """Rigid-body torque M(q) q̈ + C(q, q̇) q̇ + g(q) [N m] (RNEA), friction excluded.

        Parameters
        ----------
        q, qd, qdd : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad], velocities [rad/s], accelerations [rad/s²].

        Returns
        -------
        ndarray of shape (n_dof,) or (n_samples, n_dof)
        """
        (qs, qds, qdds), single = self._states((q, "q"), (qd, "qd"), (qdd, "qdd"))
        model, data = self.pinocchio_model, self._data
        out = np.empty_like(qs)
        for k in range(qs.shape[0]):
            out[k] = pin.rnea(model, data, qs[k], qds[k], qdds[k])
        return out[0] if single else out

    def friction_torque(self, qd: ArrayLike) -> FloatArray:
        """Steady-state friction torque of the attached friction model [N m].

        Zero when the model has no friction. Stateful models (LuGre) give their
        steady-state curve here; simulate them with their own ``step``.
        """
        (qds,), single = self._states((qd, "qd"))
        if self.friction is None:
            out = np.zeros_like(qds)
        elif hasattr(self.friction, "steady_state"):
            out = self.friction.steady_state(qds)
        else:
            out = self.friction.torque(qds)
        return out[0] if single else out

    # ------------------------------------------------------------------ regressors
    def regressor(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> FloatArray:
        """Regressor Y(q, q̇, q̈) of the standard parameters: Y π = inverse dynamics (eq. 2.11).

        Columns follow :meth:`parameter_names` (11 per link, armature last).

        Parameters
        ----------
        q, qd, qdd : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad], velocities [rad/s], accelerations [rad/s²].

        Returns
        -------
        ndarray of shape (n_dof, 11·n_dof) or (n_samples, n_dof, 11·n_dof)
        """
        (qs, qds, qdds), single = self._states((q, "q"), (qd, "qd"), (qdd, "qdd"))
        out = np.zeros((qs.shape[0], self.n_dof, self.n_dof * N_LINK_PARAMETERS))
        self._fill_regressor(qs, qds, qdds, out)
        return out[0] if single else out

    def _fill_regressor(
        self, qs: FloatArray, qds: FloatArray, qdds: FloatArray, out: FloatArray
    ) -> None:
        n = self.n_dof
        inertial = (np.arange(n)[:, None] * N_LINK_PARAMETERS + np.arange(10)).ravel()
        source = (np.arange(n)[:, None] * 10 + _PIN_TO_THESIS).ravel()
        rows = np.arange(n)
        model, data = self.pinocchio_model, self._data
        armature = rows * N_LINK_PARAMETERS + 10
        for k in range(qs.shape[0]):
            y10 = pin.computeJointTorqueRegressor(model, data, qs[k], qds[k], qdds[k])
            out[k][:, inertial] = y10[:, source]
            out[k][rows, armature] = qdds[k]

    def regressor_terms(self, q: ArrayLike) -> FloatArray:
        """Split regressor Y_k^q(q) of eq. 3.10–3.12: Y(q, q̇, q̈) = Σ_k Y_k^q(q) Q_k.

        The terms are ordered as :func:`q_vector`: Y_{M_i} (i = 1..n, columns of
        M), Y_{B_ij} (i < j, coefficients of q̇_i q̇_j), Y_{C_i} (coefficients of
        q̇_i²), Y_g. See :meth:`regressor_term_labels`.

        Parameters
        ----------
        q : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad].

        Returns
        -------
        ndarray of shape (l, n_dof, 11·n_dof) or (n_samples, l, n_dof, 11·n_dof)
            With l = (n² + 3n + 2)/2.
        """
        (qs,), single = self._states((q, "q"))
        n = self.n_dof
        upper_i, upper_j = np.triu_indices(n, 1)
        n_pairs = upper_i.size
        eye = np.eye(n)
        # Unit states that isolate each term: g, then q̈ = e_i, q̇ = e_i, q̇ = e_i + e_j.
        velocities = np.vstack([np.zeros((1 + n, n)), eye, eye[upper_i] + eye[upper_j]])
        accelerations = np.vstack([np.zeros((1, n)), eye, np.zeros((n + n_pairs, n))])
        n_states = velocities.shape[0]
        samples = np.zeros((n_states, n, n * N_LINK_PARAMETERS))
        out = np.empty((qs.shape[0], n_states, n, n * N_LINK_PARAMETERS))
        for k, qk in enumerate(qs):
            self._fill_regressor(np.tile(qk, (n_states, 1)), velocities, accelerations, samples)
            y_g = samples[0]
            y_m = samples[1 : n + 1] - y_g
            y_c = samples[n + 1 : 2 * n + 1] - y_g
            y_b = samples[2 * n + 1 :] - y_g - y_c[upper_i] - y_c[upper_j]
            out[k] = np.concatenate([y_m, y_b, y_c, y_g[None]])
        return out[0] if single else out

    def regressor_term_labels(self) -> list[str]:
        """Labels of :meth:`regressor_terms`: ``M1.., B12.., C1.., g``."""
        n = self.n_dof
        pairs = [f"B{i + 1}{j + 1}" for i in range(n) for j in range(i + 1, n)]
        return (
            [f"M{i}" for i in range(1, n + 1)] + pairs + [f"C{i}" for i in range(1, n + 1)] + ["g"]
        )

    def q_vector(self, qd: ArrayLike, qdd: ArrayLike) -> FloatArray:
        """The vector Q = [q̈; q̇_i q̇_j (i<j); q̇_i²; 1] of eq. 3.11.

        Parameters
        ----------
        qd, qdd : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint velocities [rad/s] and accelerations [rad/s²].

        Returns
        -------
        ndarray of shape (l,) or (n_samples, l), l = (n² + 3n + 2)/2
        """
        (qds, qdds), single = self._states((qd, "qd"), (qdd, "qdd"))
        upper_i, upper_j = np.triu_indices(self.n_dof, 1)
        out = np.hstack(
            [qdds, qds[:, upper_i] * qds[:, upper_j], qds**2, np.ones((qds.shape[0], 1))]
        )
        return out[0] if single else out

    # ------------------------------------------------------------------ kinematics
    def link_pose(self, q: ArrayLike, link: int | str) -> FloatArray:
        """Homogeneous transform of a link frame in the base frame [m].

        Parameters
        ----------
        q : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad].
        link : int or str
            Link number (1-based) or joint name.

        Returns
        -------
        ndarray of shape (4, 4) or (n_samples, 4, 4)
        """
        (qs,), single = self._states((q, "q"))
        jid = self.link_id(link)
        model, data = self.pinocchio_model, self._data
        out = np.empty((qs.shape[0], 4, 4))
        for k in range(qs.shape[0]):
            pin.forwardKinematics(model, data, qs[k])
            out[k] = data.oMi[jid].homogeneous
        return out[0] if single else out

    def forward_kinematics(
        self, q: ArrayLike, link: int | str, point: ArrayLike = (0.0, 0.0, 0.0)
    ) -> FloatArray:
        """Position in the base frame [m] of a point fixed on a link.

        Parameters
        ----------
        q : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad].
        link : int or str
            Link number (1-based) or joint name.
        point : array-like of shape (3,)
            Point in the link frame [m].

        Returns
        -------
        ndarray of shape (3,) or (n_samples, 3)
        """
        pose = self.link_pose(q, link)
        p = self._point(point)
        return np.asarray(pose[..., :3, :3] @ p + pose[..., :3, 3])

    def point_jacobian(
        self, q: ArrayLike, link: int | str, point: ArrayLike = (0.0, 0.0, 0.0)
    ) -> FloatArray:
        """Geometric Jacobian of a point fixed on a link, in base-frame axes.

        Rows 0–2 map q̇ to the point's linear velocity [m/s], rows 3–5 to the
        link's angular velocity [rad/s]; so τ_c = Jᵀ [f; m] for a force f [N]
        and moment m [N m] applied at the point, in base axes (eq. 5.34).

        Parameters
        ----------
        q : array-like of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad].
        link : int or str
            Link number (1-based) or joint name.
        point : array-like of shape (3,)
            Point in the link frame [m].

        Returns
        -------
        ndarray of shape (6, n_dof) or (n_samples, 6, n_dof)
        """
        (qs,), single = self._states((q, "q"))
        jid = self.link_id(link)
        p = self._point(point)
        model, data = self.pinocchio_model, self._data
        out = np.empty((qs.shape[0], 6, self.n_dof))
        frame = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED
        for k in range(qs.shape[0]):
            pin.computeJointJacobians(model, data, qs[k])
            jac = pin.getJointJacobian(model, data, jid, frame)  # at the joint origin
            lin, ang = jac[:3], jac[3:]
            arm = data.oMi[jid].rotation @ p
            out[k, :3] = lin - np.cross(arm, ang.T).T
            out[k, 3:] = ang
        return out[0] if single else out

    @staticmethod
    def _point(point: ArrayLike) -> FloatArray:
        p = np.asarray(point, dtype=float)
        if p.shape != (3,) or not np.isfinite(p).all():
            raise DimensionError(
                f"point must be a finite 3-vector in the link frame [m]; got {point!r}"
            )
        return p


def _inertia_from_parameters(values: FloatArray, link: int) -> pin.Inertia:
    """Spatial inertia from (XX, XY, XZ, YY, YZ, ZZ, mX, mY, mZ, m) about the link origin.

    Pinocchio's ``FromDynamicParameters`` divides by the mass; a massless link
    (PUMA link 1) keeps its rotational inertia here instead of turning into NaN.
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


def _prune_urdf(root: ET.Element, tip: str) -> None:
    """Remove from a URDF tree every link that is not ``tip`` or one of its ancestors."""
    links = {link.get("name") for link in root.findall("link")}
    if tip not in links:
        raise ModelError(f"tip link {tip!r} not in the URDF; options: {sorted(map(str, links))}")
    parent_of: dict[str, str] = {}
    for joint in root.findall("joint"):
        child, parent = joint.find("child"), joint.find("parent")
        if child is None or parent is None:
            raise ModelError(f"URDF joint {joint.get('name')!r} needs a parent and a child link")
        parent_of[str(child.get("link"))] = str(parent.get("link"))
    keep = {tip}
    node = tip
    while node in parent_of:
        node = parent_of[node]
        keep.add(node)
    for link in root.findall("link"):
        if link.get("name") not in keep:
            root.remove(link)
    for joint in root.findall("joint"):
        if str(joint.find("child").get("link")) not in keep:  # type: ignore[union-attr]
            root.remove(joint)
