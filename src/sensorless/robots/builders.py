"""Pinocchio models of revolute arms from a DH table or a URDF file.

These functions build the ``pinocchio.Model`` that a
:class:`~sensorless.robots.model.RobotModel` wraps; they know nothing of
friction. Two DH conventions are read:

``"modified"`` (Craig, thesis Table 2.4)
    Frame *i* follows frame *i-1* by Rx(α_{i-1}) Tx(a_{i-1}) Rz(θ_i) Tz(d_i);
    the link frame of link *i* is frame *i*.
``"standard"`` (distal, Corke's toolbox)
    Frame *i* follows frame *i-1* by Rz(θ_i) Tz(d_i) Tx(a_i) Rx(α_i); joint *i*
    turns about z_{i-1}, and the inertial data of link *i* are given in frame *i*.

In both, θ_i = q_i + θ offset; angles are radians and lengths metres.
"""

from __future__ import annotations

import math
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Mapping, Sequence
from pathlib import Path
from typing import Any, Literal, TypedDict

import numpy as np
import pandas as pd
import pinocchio as pin
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_float_array
from ..exceptions import DimensionError, InputTypeError, InputValueError, ModelError
from .inertia import LinkInertia, MotorData

__all__ = [
    "Convention",
    "LinksLike",
    "MotorsLike",
    "TableOptions",
    "model_from_table",
    "model_from_urdf",
]

Convention = Literal["modified", "standard"]
#: Inertial data of each link: :class:`LinkInertia` or mappings ``mass, com, inertia``.
LinksLike = Sequence[LinkInertia | Mapping[str, Any]]
#: Motor data: :class:`MotorData`, a mapping ``rotor_inertia, gear_ratio``, or None.
MotorsLike = MotorData | Mapping[str, Any] | None


class TableOptions(TypedDict, total=False):
    """Keyword options of :func:`model_from_table` besides ``convention``."""

    gravity: ArrayLike
    name: str
    position_limits: tuple[ArrayLike, ArrayLike] | None
    velocity_limits: ArrayLike | None
    effort_limits: ArrayLike | None


_DH_FIELDS = ("alpha", "a", "theta", "d")
_GRIPPER_WORDS = ("finger", "gripper", "hand")


def model_from_table(
    table: Any,
    links: LinksLike,
    motors: MotorsLike,
    *,
    convention: Convention,
    gravity: ArrayLike = (0.0, 0.0, -9.81),
    name: str = "robot",
    position_limits: tuple[ArrayLike, ArrayLike] | None = None,
    velocity_limits: ArrayLike | None = None,
    effort_limits: ArrayLike | None = None,
) -> pin.Model:
    """Pinocchio model of a revolute arm from a DH table (conventions: module docstring).

    The arguments are those of :meth:`RobotModel.from_mdh
    <sensorless.robots.model.RobotModel.from_mdh>` but friction and description.
    """
    rows = _dh_rows(table, convention)
    n_dof = len(rows)
    inertias = _coerce_links(links, n_dof)
    model = pin.Model()
    model.name = name
    parent = 0
    previous_link = pin.SE3.Identity()
    for i, (row, link) in enumerate(zip(rows, inertias, strict=True), start=1):
        joint_frame, link_frame = _dh_frames(row, convention)
        placement = previous_link * joint_frame
        parent = model.addJoint(parent, pin.JointModelRZ(), placement, f"joint{i}")
        model.appendBodyToJoint(parent, link.to_pinocchio(), link_frame)
        previous_link = link_frame
    model.armature = _armature(motors, n_dof)
    grav = as_float_array(gravity, "gravity", "(3,)")
    if grav.shape != (3,) or not np.isfinite(grav).all():
        raise ModelError(f"gravity must be a finite 3-vector [m/s²]; got {gravity!r}")
    model.gravity = pin.Motion(grav, np.zeros(3))
    _set_limits(model, position_limits, velocity_limits, effort_limits)
    return model


def model_from_urdf(
    path: str | Path, joints: Sequence[str] | None, *, tip: str | None, armature: ArrayLike | None
) -> pin.Model:
    """Pinocchio model of the arm of a URDF file, named after its ``<robot>`` tag.

    The arguments are those of :meth:`RobotModel.from_urdf
    <sensorless.robots.model.RobotModel.from_urdf>`; None for ``joints`` keeps
    every movable joint that is not a gripper's, None for ``armature`` is zero.
    """
    path = Path(path)
    if not path.is_file():
        raise ModelError(f"URDF file not found: {path}")
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as exc:
        raise ModelError(f"cannot parse URDF {path}: {exc}") from None
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
        raise ModelError(f"joints {unknown} are not movable joints of {path}; options: {movable}")
    lock = [full.getJointId(j) for j in movable if j not in joints]
    model = pin.buildReducedModel(full, lock, pin.neutral(full)) if lock else full
    order = [model.names[j] for j in range(1, model.njoints)]
    if order != list(joints):
        raise ModelError(f"joints must be listed in chain order {order}; got {list(joints)}")
    n_dof = model.nv
    if armature is None:
        arm = np.zeros(n_dof)
    else:
        arm = as_float_array(armature, "armature", f"({n_dof},)")
    if arm.shape != (n_dof,):
        raise DimensionError(f"armature must have {n_dof} entries; got shape {arm.shape}")
    model.armature = arm
    model.name = str(root.get("name", path.stem))
    return model


def _rot_x(angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[1.0, 0.0, 0.0], [0.0, c, -s], [0.0, s, c]])


def _rot_z(angle: float) -> FloatArray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


def _se3(rotation: FloatArray, translation: ArrayLike) -> pin.SE3:
    return pin.SE3(rotation, np.asarray(translation, dtype=float))


def _dh_frames(row: Mapping[str, float], convention: Convention) -> tuple[pin.SE3, pin.SE3]:
    """Joint frame relative to the previous link frame, and link frame relative to the joint.

    The joint frame is the one that turns by q_i about its z axis; the link
    frame carries the link's inertial data.
    """
    if convention == "modified":
        rotation = _rot_x(row["alpha"]) @ _rot_z(row["theta"])
        translation = np.array([row["a"], 0.0, 0.0]) + rotation @ np.array([0.0, 0.0, row["d"]])
        return _se3(rotation, translation), pin.SE3.Identity()
    joint_frame = _se3(_rot_z(row["theta"]), np.zeros(3))
    # Frame i relative to the moving joint frame: Tz(d) Tx(a) Rx(alpha).
    return joint_frame, _se3(_rot_x(row["alpha"]), [row["a"], 0.0, row["d"]])


def _dh_rows(table: Any, kind: str) -> list[dict[str, float]]:
    """Read a DH table (DataFrame, sequence of mappings or of 4-sequences) into dicts."""
    if isinstance(table, pd.DataFrame):
        rows: list[Any] = table.to_dict("records")
    elif isinstance(table, (str, bytes, Mapping)) or not isinstance(table, Iterable):
        raise InputTypeError(
            f"the {kind} DH table must be a DataFrame or a sequence of rows (mappings or "
            f"4-sequences), one per joint; got {type(table).__name__}"
        )
    else:
        rows = list(table)
    if not rows:
        raise ModelError(f"the {kind} DH table is empty; expected one row per joint")
    out = []
    for index, row in enumerate(rows, start=1):
        if isinstance(row, Mapping):
            missing = [key for key in _DH_FIELDS if key not in row or row[key] is None]
            if missing:
                raise ModelError(
                    f"{kind} DH row {index} is missing {missing}; every row needs "
                    f"{list(_DH_FIELDS)} (alpha, theta offset [rad]; a, d [m])"
                )
            values = {key: row[key] for key in _DH_FIELDS}
        else:
            seq = list(row)
            if len(seq) != 4:
                raise ModelError(
                    f"{kind} DH row {index} has {len(seq)} fields; expected 4 in the order "
                    f"{list(_DH_FIELDS)}"
                )
            values = dict(zip(_DH_FIELDS, seq, strict=True))
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
    return [LinkInertia.coerce(link, f"link{i}") for i, link in enumerate(links, start=1)]


def _armature(motors: MotorsLike, n_dof: int) -> FloatArray:
    if motors is None:
        return np.zeros(n_dof)
    if not isinstance(motors, MotorData):
        motors = MotorData(motors["rotor_inertia"], motors["gear_ratio"])
    if motors.armature.shape != (n_dof,):
        raise DimensionError(
            f"motor data must have {n_dof} entries (one per joint); got {motors.armature.shape[0]}"
        )
    return motors.armature


def _set_limits(
    model: pin.Model,
    position: tuple[ArrayLike, ArrayLike] | None,
    velocity: ArrayLike | None,
    effort: ArrayLike | None,
) -> None:
    """Set joint limits [rad], [rad/s], [N m], each a scalar or one per joint; None is unlimited."""
    n_dof = model.nv
    inf = np.full(n_dof, np.inf)
    lower, upper = (-inf, inf) if position is None else position
    model.lowerPositionLimit = np.broadcast_to(np.asarray(lower, float), (n_dof,)).copy()
    model.upperPositionLimit = np.broadcast_to(np.asarray(upper, float), (n_dof,)).copy()
    for attr, value in (("velocityLimit", velocity), ("effortLimit", effort)):
        arr = inf if value is None else np.broadcast_to(np.asarray(value, float), (n_dof,))
        setattr(model, attr, arr.copy())


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
