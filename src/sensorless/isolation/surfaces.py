"""Where a contact can be: the outer surface of each link, in its link frame.

A :class:`Surface` holds candidate contact points with their outward
normals, in the frame of the link it belongs to [m], and projects any point
onto itself (the isolator refines its best candidate on the surface). Two
kinds:

:class:`CapsuleSurface`
    A capsule (a cylinder with hemispherical ends) of radius R around a
    segment; :func:`capsule_surfaces` puts one around every link, from the
    origin of its joint to the origin of the next joint (the last link: to
    the farthest frame attached to it, else to twice its centre of mass).
:class:`MeshSurface`
    A closed triangle mesh; :func:`urdf_surfaces` reads the collision
    geometry of a URDF with Pinocchio (meshes, boxes, cylinders, spheres) and
    attaches it to the links of a :class:`~sensorless.robots.RobotModel`,
    capsules for the links that have none.

Links are numbered from 1 (the link moved by joint 1) to ``n_dof``; the link
frame is the frame of the joint that moves the link
(:meth:`RobotModel.link_pose <sensorless.robots.RobotModel.link_pose>`).
"""

from __future__ import annotations

import math
from abc import ABC, abstractmethod
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._validation import FloatArray, check_scalar, per_joint
from ..exceptions import InputTypeError, ModelError
from ..robots.model import RobotModel
from . import _triangles as tri

__all__ = [
    "CapsuleSurface",
    "MeshSurface",
    "Surface",
    "capsule_surfaces",
    "urdf_surfaces",
]

DEFAULT_RADIUS = 0.05
"""Capsule radius [m] when none is given: the order of a forearm of a light arm."""

DEFAULT_SPACING = 0.02
"""Distance between candidate points [m] when none is given."""


class Surface(ABC):
    """Candidate contact points of one link and the projection onto its surface.

    Attributes
    ----------
    points : ndarray of shape (n_points, 3)
        Candidate points in the link frame [m].
    normals : ndarray of shape (n_points, 3)
        Outward unit normals at the candidates, in the link frame.
    spacing : float
        Distance between neighbouring candidates [m].
    """

    points: FloatArray
    normals: FloatArray
    spacing: float

    @abstractmethod
    def project(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Closest surface points to ``x`` (m, 3) [m] and their outward unit normals."""


@dataclass(frozen=True, eq=False)
class CapsuleSurface(Surface):
    """A capsule: the points at distance ``radius`` from the segment ``start``–``end``.

    Parameters
    ----------
    start, end : array-like of shape (3,)
        Ends of the axis in the link frame [m]; equal ends give a sphere.
    radius : float
        Radius [m], > 0.
    spacing : float
        Distance between candidate points [m], > 0.
    """

    start: FloatArray
    end: FloatArray
    radius: float
    spacing: float = DEFAULT_SPACING
    points: FloatArray = field(init=False, repr=False)
    normals: FloatArray = field(init=False, repr=False)
    _axes: tuple[FloatArray, FloatArray, FloatArray, float] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        for name in ("start", "end"):
            value = np.array(getattr(self, name), dtype=float)
            if value.shape != (3,) or not np.isfinite(value).all():
                raise ModelError(f"capsule {name} must be a finite 3-vector [m]; got {value!r}")
            object.__setattr__(self, name, value)
        radius = check_scalar(self.radius, "capsule radius", "m")
        spacing = check_scalar(self.spacing, "spacing", "m")
        object.__setattr__(self, "radius", radius)
        object.__setattr__(self, "spacing", spacing)
        axis, e1, e2, length = _capsule_frame(self.start, self.end)
        object.__setattr__(self, "_axes", (axis, e1, e2, length))
        n_around = max(8, math.ceil(2.0 * np.pi * radius / spacing))
        angle = 2.0 * np.pi * np.arange(n_around) / n_around
        ring = np.outer(np.cos(angle), e1) + np.outer(np.sin(angle), e2)  # unit radial
        along = np.linspace(0.0, length, max(1, math.ceil(length / spacing)) + 1)
        normals = [np.tile(ring, (along.size, 1))]
        centres = [np.repeat(self.start + np.outer(along, axis), n_around, axis=0)]
        n_polar = max(2, math.ceil(0.5 * np.pi * radius / spacing))
        for sign, centre in ((-1.0, self.start), (1.0, self.end)):
            for polar in np.linspace(0.0, 0.5 * np.pi, n_polar + 1)[1:-1]:
                count = max(4, math.ceil(n_around * np.cos(polar)))
                phi = 2.0 * np.pi * np.arange(count) / count
                radial = np.outer(np.cos(phi), e1) + np.outer(np.sin(phi), e2)
                normals.append(np.cos(polar) * radial + sign * np.sin(polar) * axis)
                centres.append(np.tile(centre, (count, 1)))
            normals.append((sign * axis)[None])
            centres.append(centre[None])
        unit = np.concatenate(normals)
        object.__setattr__(self, "normals", unit)
        object.__setattr__(self, "points", np.concatenate(centres) + radius * unit)

    def project(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Closest points on the capsule to ``x`` (m, 3) [m] and the outward normals there."""
        axis, e1, _, length = self._axes
        s = np.clip((x - self.start) @ axis, 0.0, length)
        foot = self.start + np.outer(s, axis)
        radial = x - foot
        norm = np.linalg.norm(radial, axis=1, keepdims=True)
        # A point on the axis has no closest surface point of its own: any radial direction.
        unit = np.where(norm > 1e-15, radial / np.where(norm > 1e-15, norm, 1.0), e1)
        return foot + self.radius * unit, unit


@dataclass(frozen=True, eq=False)
class MeshSurface(Surface):
    """A closed triangle mesh in a link frame.

    Parameters
    ----------
    vertices : array-like of shape (n_vertices, 3)
        Vertices in the link frame [m].
    triangles : array-like of int, shape (n_triangles, 3)
        Vertex indices of each face; the winding is made outward (by the sign
        of the enclosed volume) on construction.
    spacing : float
        Distance between candidate points on the faces [m], > 0.
    """

    vertices: FloatArray
    triangles: Any
    spacing: float = DEFAULT_SPACING
    points: FloatArray = field(init=False, repr=False)
    normals: FloatArray = field(init=False, repr=False)
    _face_normals: FloatArray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        vertices = np.array(self.vertices, dtype=float)
        triangles = np.array(self.triangles, dtype=np.int64)
        if vertices.ndim != 2 or vertices.shape[1] != 3 or not np.isfinite(vertices).all():
            raise ModelError(
                f"mesh vertices must be finite, of shape (n_vertices, 3) [m]; got {vertices.shape}"
            )
        if (
            triangles.ndim != 2
            or triangles.shape[1] != 3
            or triangles.shape[0] == 0
            or triangles.min() < 0
            or triangles.max() >= vertices.shape[0]
        ):
            raise ModelError(
                "mesh triangles must be indices into the vertices, of shape (n_triangles, 3); "
                f"got shape {triangles.shape}"
            )
        vertices, triangles = tri._outward(vertices, triangles)
        spacing = check_scalar(self.spacing, "spacing", "m")
        object.__setattr__(self, "vertices", vertices)
        object.__setattr__(self, "triangles", triangles)
        object.__setattr__(self, "spacing", spacing)
        normals = tri.face_normals(vertices, triangles)
        points, faces = tri.sample_faces(vertices, triangles, spacing)
        keep = np.linalg.norm(normals[faces], axis=1) > 0.0  # degenerate faces have no normal
        object.__setattr__(self, "_face_normals", normals)
        object.__setattr__(self, "points", points[keep])
        object.__setattr__(self, "normals", normals[faces[keep]])

    def project(self, x: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Closest points on the mesh to ``x`` (m, 3) [m] and the normals of their faces."""
        closest, face = tri.closest_points(x, self.vertices, self.triangles)
        return closest, self._face_normals[face]


def _capsule_frame(
    start: FloatArray, end: FloatArray
) -> tuple[FloatArray, FloatArray, FloatArray, float]:
    """Unit axis (z for a sphere), two unit vectors normal to it, and the length [m]."""
    delta = end - start
    length = float(np.linalg.norm(delta))
    axis = delta / length if length > 0.0 else np.array([0.0, 0.0, 1.0])
    helper = np.eye(3)[int(np.argmin(np.abs(axis)))]
    e1 = np.cross(axis, helper)
    e1 /= np.linalg.norm(e1)
    return axis, e1, np.cross(axis, e1), length


def capsule_surfaces(
    robot: RobotModel,
    radius: float | ArrayLike = DEFAULT_RADIUS,
    spacing: float = DEFAULT_SPACING,
) -> dict[int, Surface]:
    """A capsule around every link of ``robot``.

    Link k's axis runs from the origin of joint k to the origin of joint k+1
    (both fixed in link k's frame); the last link's from its joint's origin
    to the farthest frame attached to it (a flange, a tool frame) or, in a
    model without such frames, to twice its centre of mass. Coinciding ends
    give a sphere.

    Parameters
    ----------
    robot : RobotModel
        The arm.
    radius : float or array-like of shape (n_dof,)
        Capsule radius [m], one for all links or one per link, > 0.
    spacing : float
        Distance between candidate points [m], > 0.

    Returns
    -------
    dict of int to Surface
        One capsule per link number 1..n_dof.
    """
    if not isinstance(robot, RobotModel):
        raise InputTypeError(f"robot must be a RobotModel; got {type(robot).__name__}")
    model = robot.pinocchio_model
    n = robot.n_dof
    radii = per_joint(radius, n, "radius", "m", "positive")
    surfaces: dict[int, Surface] = {}
    for link in range(1, n + 1):
        if link < n:
            end = np.array(model.jointPlacements[link + 1].translation)
        else:
            end = _tip(model, link)
        surfaces[link] = CapsuleSurface(np.zeros(3), end, float(radii[link - 1]), spacing)
    return surfaces


def _tip(model: pin.Model, joint: int) -> FloatArray:
    """End of the last link's capsule axis in its joint frame [m]."""
    attached = [
        np.array(frame.placement.translation)
        for frame in model.frames
        if frame.parentJoint == joint
    ]
    if attached:
        return max(attached, key=lambda p: float(np.linalg.norm(p)))
    return 2.0 * np.array(model.inertias[joint].lever)


def urdf_surfaces(
    robot: RobotModel,
    path: str | Path,
    *,
    package_dirs: Sequence[str | Path] | None = None,
    radius: float | ArrayLike = DEFAULT_RADIUS,
    spacing: float = DEFAULT_SPACING,
) -> dict[int, Surface]:
    """Collision geometry of a URDF on the links of ``robot``; capsules where it has none.

    Pinocchio reads the ``<collision>`` elements of ``path`` (meshes need
    Pinocchio built with coal/hpp-fcl, as the PyPI wheel is). Each geometry is
    attached to the link of ``robot`` whose joint carries the URDF link it
    belongs to, by frame name, so a model cut at a tip or with locked joints
    (:meth:`RobotModel.from_urdf`) gets the geometry of the links it kept;
    geometry on the base or on links it dropped is left out. Boxes,
    cylinders and spheres become triangle meshes.

    Parameters
    ----------
    robot : RobotModel
        A model built from the same URDF.
    path : str or Path
        The URDF file.
    package_dirs : sequence of str or Path, optional
        Where ``package://`` mesh paths are looked up; by default every
        folder above the URDF's.
    radius, spacing
        As in :func:`capsule_surfaces` (radius: links without geometry only).

    Returns
    -------
    dict of int to Surface
        One surface per link number 1..n_dof.

    Raises
    ------
    ModelError
        The file cannot be read, or none of its geometry belongs to a link of ``robot``.
    """
    surfaces = capsule_surfaces(robot, radius, spacing)
    file = Path(path)
    dirs = [str(d) for d in (file.resolve().parents if package_dirs is None else package_dirs)]
    try:
        full = pin.buildModelFromUrdf(str(file))
        geometry = pin.buildGeomFromUrdf(full, str(file), pin.COLLISION, package_dirs=dirs)
    except (RuntimeError, ValueError, OSError) as exc:
        raise ModelError(
            f"Pinocchio could not read the collision geometry of {file}: {exc}"
        ) from None
    meshes: dict[int, list[tuple[FloatArray, Any]]] = {}
    model = robot.pinocchio_model
    for obj in geometry.geometryObjects:
        frame = full.frames[obj.parentFrame]
        if not model.existFrame(frame.name):
            continue
        kept = model.frames[model.getFrameId(frame.name)]
        if kept.parentJoint == 0:
            continue
        placement = kept.placement * frame.placement.inverse() * obj.placement
        vertices, triangles = _mesh_of(obj.geometry, obj.name)
        moved = vertices @ np.array(placement.rotation).T + np.array(placement.translation)
        meshes.setdefault(int(kept.parentJoint), []).append((moved, triangles))
    if not meshes:
        raise ModelError(
            f"none of the collision geometry of {file} is on a link of {robot.name!r} "
            f"(links by frame name: {robot.joint_names})"
        )
    for link, parts in meshes.items():
        offsets = np.cumsum([0] + [v.shape[0] for v, _ in parts[:-1]])
        vertices = np.concatenate([v for v, _ in parts])
        triangles = np.concatenate([t + o for (_, t), o in zip(parts, offsets, strict=True)])
        surfaces[link] = MeshSurface(vertices, triangles, spacing)
    return surfaces


def _mesh_of(geometry: Any, name: str) -> tuple[FloatArray, Any]:
    """Vertices [m] and outward-wound triangles of a coal/hpp-fcl collision geometry."""
    kind = type(geometry).__name__
    if hasattr(geometry, "num_tris") and hasattr(geometry, "tri_indices"):
        vertices = np.array(geometry.vertices(), dtype=float)
        triangles = np.array(
            [[geometry.tri_indices(i)[j] for j in range(3)] for i in range(geometry.num_tris)],
            dtype=np.int64,
        )
        return tri._outward(vertices, triangles)
    if kind == "Box":
        return tri.box_mesh(np.array(geometry.halfSide, dtype=float))
    if kind == "Cylinder":
        return tri.cylinder_mesh(float(geometry.radius), float(geometry.halfLength))
    if kind == "Sphere":
        return tri.sphere_mesh(float(geometry.radius))
    raise ModelError(
        f"collision geometry {name!r} is a {kind}; supported: meshes, Box, Cylinder, Sphere"
    )
