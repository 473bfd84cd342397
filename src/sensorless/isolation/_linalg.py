"""Small dense linear algebra of the isolator: eq. (1) of :mod:`.estimate` per link and point.

Arrays are in SI units; a "stack" has the candidates along axis 0. The
matrices are at most 7×5, so closed forms and normal equations beat
LAPACK's per-call overhead; the SVD takes over where they are singular.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validation import FloatArray

__all__ = ["RCOND", "Link", "force_bound", "least_squares", "lsq", "pushes", "skew", "tangents"]

RCOND = 1e-10
"""Relative singular value below which a force direction counts as unseen."""


def skew(v: FloatArray) -> FloatArray:
    """[v]ₓ of vectors of shape (..., 3): shape (..., 3, 3), [v]ₓ u = v × u."""
    out = np.zeros((*v.shape[:-1], 3, 3))
    out[..., 0, 1], out[..., 0, 2] = -v[..., 2], v[..., 1]
    out[..., 1, 0], out[..., 1, 2] = v[..., 2], -v[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -v[..., 1], v[..., 0]
    return out


@dataclass(frozen=True)
class Link:
    """Link k's frame (rotation, origin [m]) and its joint's Jacobian rows, transposed (k, 3)."""

    rotation: FloatArray
    origin: FloatArray
    lin: FloatArray
    ang: FloatArray

    def solve(
        self, c: FloatArray, w: FloatArray, yk: FloatArray
    ) -> tuple[FloatArray, FloatArray, float]:
        """B = W J_cᵀ (k, 3), F̂ [N] and the squared misfit for the point ``c`` (link frame) [m]."""
        b = w[:, None] * (self.lin + self.ang @ skew(self.rotation @ c))
        force = lsq(b, yk)
        misfit = b @ force - yk
        return b, force, float(misfit @ misfit)

    def jacobian(
        self, b: FloatArray, force: FloatArray, normal: FloatArray, w: FloatArray
    ) -> FloatArray:
        """Jacobian (k, 5) of W τ(c, F) in F and the two tangent coordinates of c at ``normal``.

        ∂τ/∂c = −J_angᵀ [F]ₓ R (link-frame increments of c), from eq. (1).
        """
        along = -(w[:, None] * (self.ang @ skew(force) @ self.rotation)) @ tangents(normal).T
        return np.hstack([b, along])


def least_squares(b: FloatArray, y: FloatArray) -> FloatArray:
    """argmin ‖B_p F − y‖ for a stack B of shape (P, k, 3): F of shape (P, 3).

    Normal equations (BᵀB) F = Bᵀy with 3 joints or more; with fewer, the
    minimum-norm force F = Bᵀ (BBᵀ)⁻¹ y (no component in the directions the
    joints do not see). Both systems are at most 3×3 and solved in closed
    form (the adjugate), all candidates at once; the pseudo-inverse takes
    the matrices where the system is singular (a candidate on a joint axis,
    a singular pose).
    """
    k = b.shape[1]
    if k >= 3:
        columns = [b[:, :, i] for i in range(3)]
        rhs = np.stack([c @ y for c in columns], axis=1)
        solved, regular = _solve_symmetric(columns, rhs)
    else:
        rows = [b[:, j, :] for j in range(k)]
        rhs = np.broadcast_to(y, (b.shape[0], k))
        coef, regular = _solve_symmetric(rows, rhs)
        solved = np.einsum("pki,pk->pi", b, coef)
    if not regular.all():
        solved[~regular] = np.einsum("pij,j->pi", np.linalg.pinv(b[~regular], rcond=RCOND), y)
    return solved


def lsq(a: FloatArray, y: FloatArray) -> FloatArray:
    """Least-squares (minimum-norm if underdetermined) solution of a x = y, one small matrix.

    The normal equations of the smaller side (a few µs); the SVD when they are singular.
    """
    try:
        if a.shape[0] >= a.shape[1]:
            return np.asarray(np.linalg.solve(a.T @ a, a.T @ y))
        return np.asarray(a.T @ np.linalg.solve(a @ a.T, y))
    except np.linalg.LinAlgError:
        return np.asarray(np.linalg.lstsq(a, y, rcond=RCOND)[0])


def _solve_symmetric(vectors: list[FloatArray], rhs: FloatArray) -> tuple[FloatArray, np.ndarray]:
    """Solve G x = rhs, G_ij = vectors[i]·vectors[j] (m = 1, 2 or 3 vectors of shape (P, d)).

    Returns x of shape (P, m) and where G is regular (det > 1e-12 (tr G/m)^m).
    """
    m = len(vectors)
    g = [[np.einsum("pi,pi->p", vectors[i], vectors[j]) for j in range(m)] for i in range(m)]
    if m == 1:
        det = g[0][0]
        adj = [[np.ones_like(det)]]
    elif m == 2:
        det = g[0][0] * g[1][1] - g[0][1] ** 2
        adj = [[g[1][1], -g[0][1]], [-g[0][1], g[0][0]]]
    else:
        a, b, c, d, e, f = g[0][0], g[0][1], g[0][2], g[1][1], g[1][2], g[2][2]
        co = [
            d * f - e * e,
            c * e - b * f,
            b * e - c * d,
            a * f - c * c,
            b * c - a * e,
            a * d - b * b,
        ]
        det = a * co[0] + b * co[1] + c * co[2]
        adj = [[co[0], co[1], co[2]], [co[1], co[3], co[4]], [co[2], co[4], co[5]]]
    scale = sum(g[i][i] for i in range(m)) / m
    regular = det > 1e-12 * scale**m
    safe = np.where(regular, det, 1.0)
    x = np.stack([sum(adj[i][j] * rhs[:, j] for j in range(m)) / safe for i in range(m)], axis=1)
    return x, regular


def pushes(force: FloatArray, normal: FloatArray) -> bool:
    """F·n <= 0 up to rounding: the force points into the surface."""
    return bool(force @ normal <= 1e-9 * np.linalg.norm(force))


def force_bound(b: FloatArray, weight: FloatArray, half: FloatArray) -> tuple[FloatArray, int]:
    """Worst-case error of F̂ = pinv(B) W r̂ per component [N], and rank of B (k, 3).

    |ΔF_i| <= Σ_j |pinv(B)_ij| w_j δ_j for errors within ±δ_j; a joint with
    weight 0 (an infinite band) does not enter F̂ and adds nothing.
    """
    singular = np.linalg.svd(b, compute_uv=False)
    rank = int(np.sum(singular > RCOND * singular[0])) if singular.size and singular[0] > 0 else 0
    if rank < 3:
        return np.full(3, np.inf), rank
    scaled = np.where(weight > 0.0, weight * np.where(np.isfinite(half), half, 0.0), 0.0)
    return np.abs(np.linalg.pinv(b, rcond=RCOND)) @ scaled, rank


def tangents(normal: FloatArray) -> FloatArray:
    """Two unit vectors spanning the plane normal to ``normal`` (rows of a (2, 3) array)."""
    x, y, z = normal
    # Cross with the axis least aligned with the normal, written out (np.cross is slow here).
    if abs(x) <= abs(y) and abs(x) <= abs(z):
        first = np.array([0.0, z, -y])
    elif abs(y) <= abs(z):
        first = np.array([-z, 0.0, x])
    else:
        first = np.array([y, -x, 0.0])
    first /= np.sqrt(first @ first)
    a, b, c = first
    return np.array([first, [y * c - z * b, z * a - x * c, x * b - y * a]])
