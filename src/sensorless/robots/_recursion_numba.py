"""Compiled (numba) form of the momentum recursion of :mod:`sensorless.robots.recursion`.

Importing this module requires numba; :mod:`~sensorless.robots.recursion` falls
back to its numpy form when the import fails. The kernel works on one sample
with scalar arithmetic, in the canonical frames and with the packed constants
described there:

``joints`` : int64 array of shape (n_dof, 2)
    Parent joint (−1 for a root) and kind (0 revolute about z, 1 prismatic along z).
``consts`` : float64 array of shape (n_dof, 23)
    Per joint: rotation of the joint-placement frame in the parent frame,
    row-major (0–8); its origin [m] (9–11); link mass [kg] (12); first moment
    m·c [kg m] (13–15); rotational inertia about the frame origin [kg m²],
    xx, xy, xz, yy, yz, zz (16–21); armature [kg m²] (22).
``scratch`` : float64 array of shape (n_dof, 23)
    Per joint: velocity ν, ω and gravity vector in the joint frame (0–8); the
    momentum and gravity wrenches of the subtree, first as the children pass
    them up, then with the link's own (9–20); cos and sin of a revolute angle (21–22).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit  # type: ignore[import-untyped]

from .._validation import FloatArray

__all__ = ["terms_batch", "terms_one"]

IntArray = np.ndarray


@njit(cache=True, inline="always")  # type: ignore[misc]
def _cross(
    ax: float, ay: float, az: float, bx: float, by: float, bz: float
) -> tuple[float, float, float]:
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@njit(cache=True, inline="always")  # type: ignore[misc]
def _rotate_t(
    consts: FloatArray, k: int, x: float, y: float, z: float
) -> tuple[float, float, float]:
    """Rᵀ·(x, y, z) for the placement rotation R of joint k (row-major in consts[k, 0:9])."""
    return (
        consts[k, 0] * x + consts[k, 3] * y + consts[k, 6] * z,
        consts[k, 1] * x + consts[k, 4] * y + consts[k, 7] * z,
        consts[k, 2] * x + consts[k, 5] * y + consts[k, 8] * z,
    )


@njit(cache=True, inline="always")  # type: ignore[misc]
def _rotate(
    consts: FloatArray, k: int, x: float, y: float, z: float
) -> tuple[float, float, float]:
    """R·(x, y, z) for the placement rotation R of joint k (row-major in consts[k, 0:9])."""
    return (
        consts[k, 0] * x + consts[k, 1] * y + consts[k, 2] * z,
        consts[k, 3] * x + consts[k, 4] * y + consts[k, 5] * z,
        consts[k, 6] * x + consts[k, 7] * y + consts[k, 8] * z,
    )


@njit(cache=True, inline="always")  # type: ignore[misc]
def _forward(
    k: int,
    q: FloatArray,
    qd: FloatArray,
    joints: IntArray,
    consts: FloatArray,
    gravity: FloatArray,
    scratch: FloatArray,
) -> None:
    """Velocity and gravity of joint k in its frame, from its parent's; clear its wrenches."""
    parent = joints[k, 0]
    if parent < 0:
        nx = ny = nz = wx = wy = wz = 0.0
        gx, gy, gz = gravity[0], gravity[1], gravity[2]
    else:
        nx, ny, nz = scratch[parent, 0], scratch[parent, 1], scratch[parent, 2]
        wx, wy, wz = scratch[parent, 3], scratch[parent, 4], scratch[parent, 5]
        gx, gy, gz = scratch[parent, 6], scratch[parent, 7], scratch[parent, 8]
    tx, ty, tz = _cross(wx, wy, wz, consts[k, 9], consts[k, 10], consts[k, 11])
    nx, ny, nz = _rotate_t(consts, k, nx + tx, ny + ty, nz + tz)
    wx, wy, wz = _rotate_t(consts, k, wx, wy, wz)
    gx, gy, gz = _rotate_t(consts, k, gx, gy, gz)
    angle = q[k]
    if joints[k, 1] == 0:
        co, si = math.cos(angle), math.sin(angle)
        scratch[k, 21] = co
        scratch[k, 22] = si
        nx, ny = co * nx + si * ny, co * ny - si * nx
        wx, wy = co * wx + si * wy, co * wy - si * wx
        gx, gy = co * gx + si * gy, co * gy - si * gx
        wz += qd[k]
    else:
        nx, ny = nx + angle * wy, ny - angle * wx
        nz += qd[k]
    scratch[k, 0], scratch[k, 1], scratch[k, 2] = nx, ny, nz
    scratch[k, 3], scratch[k, 4], scratch[k, 5] = wx, wy, wz
    scratch[k, 6], scratch[k, 7], scratch[k, 8] = gx, gy, gz
    for i in range(9, 21):
        scratch[k, i] = 0.0


@njit(cache=True, inline="always")  # type: ignore[misc]
def _pass_wrench(
    k: int, base: int, angle: float, joints: IntArray, consts: FloatArray, scratch: FloatArray
) -> None:
    """Add the wrench scratch[k, base:base + 6] (f, n in frame k) into the parent's."""
    parent = joints[k, 0]
    fx, fy, fz = scratch[k, base], scratch[k, base + 1], scratch[k, base + 2]
    mx, my, mz = scratch[k, base + 3], scratch[k, base + 4], scratch[k, base + 5]
    if joints[k, 1] == 0:
        co, si = scratch[k, 21], scratch[k, 22]
        fx, fy = co * fx - si * fy, si * fx + co * fy
        mx, my = co * mx - si * my, si * mx + co * my
    else:
        mx, my = mx - angle * fy, my + angle * fx
    fx, fy, fz = _rotate(consts, k, fx, fy, fz)
    mx, my, mz = _rotate(consts, k, mx, my, mz)
    tx, ty, tz = _cross(consts[k, 9], consts[k, 10], consts[k, 11], fx, fy, fz)
    scratch[parent, base] += fx
    scratch[parent, base + 1] += fy
    scratch[parent, base + 2] += fz
    scratch[parent, base + 3] += mx + tx
    scratch[parent, base + 4] += my + ty
    scratch[parent, base + 5] += mz + tz


@njit(cache=True, inline="always")  # type: ignore[misc]
def _backward(
    k: int,
    qd: FloatArray,
    joints: IntArray,
    consts: FloatArray,
    scratch: FloatArray,
    out: FloatArray,
) -> None:
    """Subtree wrenches of joint k (in place of its accumulators) and its three outputs."""
    s = scratch
    nx, ny, nz = s[k, 0], s[k, 1], s[k, 2]
    wx, wy, wz = s[k, 3], s[k, 4], s[k, 5]
    gx, gy, gz = s[k, 6], s[k, 7], s[k, 8]
    mass, hx, hy, hz = consts[k, 12], consts[k, 13], consts[k, 14], consts[k, 15]
    ixx, ixy, ixz = consts[k, 16], consts[k, 17], consts[k, 18]
    iyy, iyz, izz = consts[k, 19], consts[k, 20], consts[k, 21]
    ax, ay, az = _cross(wx, wy, wz, hx, hy, hz)
    s[k, 9] += mass * nx + ax
    s[k, 10] += mass * ny + ay
    s[k, 11] += mass * nz + az
    ax, ay, az = _cross(hx, hy, hz, nx, ny, nz)
    s[k, 12] += ax + ixx * wx + ixy * wy + ixz * wz
    s[k, 13] += ay + ixy * wx + iyy * wy + iyz * wz
    s[k, 14] += az + ixz * wx + iyz * wy + izz * wz
    ax, ay, az = _cross(hx, hy, hz, gx, gy, gz)
    s[k, 15] += mass * gx
    s[k, 16] += mass * gy
    s[k, 17] += mass * gz
    s[k, 18] += ax
    s[k, 19] += ay
    s[k, 20] += az
    if joints[k, 1] == 0:
        out[0, k] = s[k, 14] + consts[k, 22] * qd[k]
        out[1, k] = s[k, 9] * ny - s[k, 10] * nx + s[k, 12] * wy - s[k, 13] * wx
        out[2, k] = -s[k, 20]
    else:
        out[0, k] = s[k, 11] + consts[k, 22] * qd[k]
        out[1, k] = s[k, 9] * wy - s[k, 10] * wx
        out[2, k] = -s[k, 17]


@njit(cache=True)  # type: ignore[misc]
def terms_one(
    q: FloatArray,
    qd: FloatArray,
    joints: IntArray,
    consts: FloatArray,
    gravity: FloatArray,
    scratch: FloatArray,
    out: FloatArray,
) -> None:
    """p, Cᵀq̇ and g of one sample into the rows of ``out`` (shape (3, n_dof))."""
    n_dof = q.shape[0]
    for k in range(n_dof):
        _forward(k, q, qd, joints, consts, gravity, scratch)
    for k in range(n_dof - 1, -1, -1):
        _backward(k, qd, joints, consts, scratch, out)
        if joints[k, 0] >= 0:
            _pass_wrench(k, 9, q[k], joints, consts, scratch)
            _pass_wrench(k, 15, q[k], joints, consts, scratch)


@njit(cache=True)  # type: ignore[misc]
def terms_batch(
    q: FloatArray,
    qd: FloatArray,
    joints: IntArray,
    consts: FloatArray,
    gravity: FloatArray,
    out_p: FloatArray,
    out_c: FloatArray,
    out_g: FloatArray,
) -> None:
    """:func:`terms_one` over the samples (axis 0) of q, qd, into three (n_samples, n_dof) arrays."""
    n_dof = q.shape[1]
    scratch = np.empty((n_dof, 23))
    out = np.empty((3, n_dof))
    for i in range(q.shape[0]):
        terms_one(q[i], qd[i], joints, consts, gravity, scratch, out)
        out_p[i] = out[0]
        out_c[i] = out[1]
        out_g[i] = out[2]
