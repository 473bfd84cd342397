"""Triangle meshes for contact surfaces: sampling, closest points, primitives.

Helpers of :mod:`sensorless.isolation.surfaces`; every array is in metres, in
the frame of the link the mesh belongs to. A mesh is ``vertices`` of shape
(n_vertices, 3) and ``triangles`` of shape (n_triangles, 3), the vertex
indices of each face counter-clockwise seen from outside (outward normals).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from .._validation import FloatArray

__all__ = [
    "box_mesh",
    "closest_points",
    "cylinder_mesh",
    "face_normals",
    "sample_faces",
    "signed_volume",
    "sphere_mesh",
]

IntArray = NDArray[np.int64]


def face_normals(vertices: FloatArray, triangles: IntArray) -> FloatArray:
    """Unit normals of the faces, (n_triangles, 3); a degenerate face gets (0, 0, 0)."""
    a, b, c = (vertices[triangles[:, i]] for i in range(3))
    cross = np.cross(b - a, c - a)
    norm = np.linalg.norm(cross, axis=1, keepdims=True)
    return np.divide(cross, norm, out=np.zeros_like(cross), where=norm > 0.0)


def signed_volume(vertices: FloatArray, triangles: IntArray) -> float:
    """Volume enclosed by a closed mesh [m³]; negative when its faces are wound inward."""
    a, b, c = (vertices[triangles[:, i]] for i in range(3))
    return float(np.einsum("ij,ij->i", a, np.cross(b, c)).sum() / 6.0)


def sample_faces(
    vertices: FloatArray, triangles: IntArray, spacing: float
) -> tuple[FloatArray, IntArray]:
    """Points on every face, about ``spacing`` [m] apart, and the face of each point.

    Each triangle gets a barycentric grid of m subdivisions per side, m the
    smallest number with longest edge / m <= ``spacing``; the grid points
    strictly inside the face, or its centroid when m is 1 or 2 and the grid
    has none, so that shared edges and vertices are not sampled twice.
    """
    points: list[FloatArray] = []
    faces: list[IntArray] = []
    for index, tri in enumerate(triangles):
        a, b, c = vertices[tri]
        longest = max(np.linalg.norm(b - a), np.linalg.norm(c - b), np.linalg.norm(a - c))
        m = max(1, math.ceil(longest / spacing))
        i, j = np.meshgrid(np.arange(1, m), np.arange(1, m), indexing="ij")
        inside = (i + j) < m
        u, v = i[inside] / m, j[inside] / m
        if u.size == 0:
            u, v = np.array([1.0 / 3.0]), np.array([1.0 / 3.0])
        grid = a + np.outer(u, b - a) + np.outer(v, c - a)
        points.append(grid)
        faces.append(np.full(grid.shape[0], index, dtype=np.int64))
    return np.concatenate(points), np.concatenate(faces)


def closest_points(
    points: FloatArray, vertices: FloatArray, triangles: IntArray
) -> tuple[FloatArray, IntArray]:
    """Closest point of the mesh to each of ``points`` (m, 3) and the face it lies on.

    The region test of Ericson, *Real-Time Collision Detection* (2005), §5.1.5,
    for every point against every face at once.
    """
    a, b, c = (vertices[triangles[:, i]][None] for i in range(3))
    p = points[:, None, :]
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = _dot(ab, ap), _dot(ac, ap)
    bp, cp = p - b, p - c
    d3, d4 = _dot(ab, bp), _dot(ac, bp)
    d5, d6 = _dot(ab, cp), _dot(ac, cp)
    va = d3 * d6 - d5 * d4
    vb = d5 * d2 - d1 * d6
    vc = d1 * d4 - d3 * d2
    denom = va + vb + vc
    safe = np.where(denom == 0.0, 1.0, denom)
    v = vb / safe
    w = vc / safe
    result = a + ab * v[..., None] + ac * w[..., None]  # inside the face
    # Edges, then vertices: later assignments take precedence, as in Ericson's order.
    edge_bc = (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0)
    t_bc = _ratio(d4 - d3, (d4 - d3) + (d5 - d6))
    result = np.where(edge_bc[..., None], b + (c - b) * t_bc[..., None], result)
    edge_ac = (vb <= 0) & (d2 >= 0) & (d6 <= 0)
    result = np.where(edge_ac[..., None], a + ac * _ratio(d2, d2 - d6)[..., None], result)
    edge_ab = (vc <= 0) & (d1 >= 0) & (d3 <= 0)
    result = np.where(edge_ab[..., None], a + ab * _ratio(d1, d1 - d3)[..., None], result)
    result = np.where(((d6 >= 0) & (d5 <= d6))[..., None], c, result)
    result = np.where(((d3 >= 0) & (d4 <= d3))[..., None], b, result)
    result = np.where(((d1 <= 0) & (d2 <= 0))[..., None], a, result)
    distance = np.linalg.norm(result - p, axis=2)
    face = np.argmin(distance, axis=1)
    return result[np.arange(points.shape[0]), face], face.astype(np.int64)


def _dot(x: FloatArray, y: FloatArray) -> FloatArray:
    return np.asarray(np.einsum("...i,...i->...", x, y))


def _ratio(num: FloatArray, den: FloatArray) -> FloatArray:
    return np.asarray(np.clip(num / np.where(den == 0.0, 1.0, den), 0.0, 1.0))


def box_mesh(half_sides: FloatArray) -> tuple[FloatArray, IntArray]:
    """A box centred at the origin with half side lengths ``half_sides`` [m]."""
    corners = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    vertices = corners * np.asarray(half_sides, dtype=float)
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    triangles = np.array([t for a, b, c, d in quads for t in ((a, b, c), (a, c, d))])
    return _outward(vertices, triangles)


def cylinder_mesh(
    radius: float, half_length: float, n_around: int = 24
) -> tuple[FloatArray, IntArray]:
    """A cylinder about the z axis, centred at the origin [m], as an ``n_around``-gon prism."""
    angle = 2.0 * np.pi * np.arange(n_around) / n_around
    ring = np.column_stack([radius * np.cos(angle), radius * np.sin(angle)])
    bottom = np.column_stack([ring, np.full(n_around, -half_length)])
    top = np.column_stack([ring, np.full(n_around, half_length)])
    vertices = np.vstack([bottom, top, [[0, 0, -half_length], [0, 0, half_length]]])
    k = np.arange(n_around)
    nxt = (k + 1) % n_around
    low, high = 2 * n_around, 2 * n_around + 1
    sides = np.concatenate(
        [
            np.column_stack([k, nxt, nxt + n_around]),
            np.column_stack([k, nxt + n_around, k + n_around]),
        ]
    )
    caps = np.concatenate(
        [
            np.column_stack([np.full(n_around, low), nxt, k]),
            np.column_stack([np.full(n_around, high), k + n_around, nxt + n_around]),
        ]
    )
    return _outward(vertices, np.concatenate([sides, caps]))


def sphere_mesh(radius: float, n_around: int = 24) -> tuple[FloatArray, IntArray]:
    """A sphere centred at the origin [m], as a latitude-longitude mesh."""
    n_lat = max(2, n_around // 2)
    polar = np.pi * np.arange(1, n_lat) / n_lat
    angle = 2.0 * np.pi * np.arange(n_around) / n_around
    rings = [
        radius
        * np.column_stack(
            [np.sin(p) * np.cos(angle), np.sin(p) * np.sin(angle), np.full(n_around, np.cos(p))]
        )
        for p in polar
    ]
    vertices = np.vstack([*rings, [[0, 0, radius], [0, 0, -radius]]])
    north, south = len(rings) * n_around, len(rings) * n_around + 1
    k = np.arange(n_around)
    nxt = (k + 1) % n_around
    faces = [np.column_stack([np.full(n_around, north), k, nxt])]
    for r in range(len(rings) - 1):
        top, bot = r * n_around, (r + 1) * n_around
        faces.append(np.column_stack([top + k, bot + k, bot + nxt]))
        faces.append(np.column_stack([top + k, bot + nxt, top + nxt]))
    last = (len(rings) - 1) * n_around
    faces.append(np.column_stack([np.full(n_around, south), last + nxt, last + k]))
    return _outward(vertices, np.concatenate(faces))


def _outward(vertices: FloatArray, triangles: NDArray[np.integer]) -> tuple[FloatArray, IntArray]:
    """The mesh with its faces wound so that their normals point outward."""
    tris = np.asarray(triangles, dtype=np.int64)
    if signed_volume(vertices, tris) < 0.0:
        tris = tris[:, ::-1].copy()
    return np.asarray(vertices, dtype=float), tris
