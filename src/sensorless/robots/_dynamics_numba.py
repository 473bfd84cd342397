"""Compiled (numba) forward dynamics and joint-space inertia on the recursion's constants.

Importing this module requires numba. The functions work on the ``consts``
array of :mod:`sensorless.robots._recursion_numba` (shape (n_dof, 28), built by
:attr:`sensorless.robots.recursion.MomentumTerms.kernel_constants`): a tree of
one-DoF revolute or prismatic joints, each in its canonical frame with the
joint axis along z, spatial vectors written (linear, angular) at the frame
origin. Two algorithms of Featherstone's *Rigid Body Dynamics Algorithms*
(2008):

- :func:`aba`, the articulated-body algorithm (ch. 7): q̈ from q, q̇ and τ,
  armature included in each joint's D_i = S_iᵀ U_i + I_a,i as Pinocchio's
  ``aba`` does; gravity enters as the base acceleration −a_g;
- :func:`crba`, the composite-rigid-body algorithm (ch. 6): M(q), armature on
  the diagonal.

Scratch arrays, allocated by :func:`scratch` and reused across calls:

``work`` : float64 array of shape (n_dof, 52)
    Per joint: the rotation E from the parent frame to the joint frame,
    row-major (0–8), the joint frame's origin in the parent frame [m] (9–11),
    the link velocity (12–17), the velocity-product acceleration c (18–23),
    the bias force pᴬ (24–29), U = Iᴬ S (30–35), D (36), u (37), the
    momentum I v (40–45), the bias force passed to the parent (46–51).
``inertia`` : float64 array of shape (n_dof + 2, 6, 6)
    The articulated (ABA) or composite (CRBA) inertia of each subtree; the
    last two are the 6 × 6 transform X and a product of the inertia transform.
``acc`` : float64 array of shape (n_dof + 1, 6)
    The spatial acceleration of each link; the last row is the base's, −a_g.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .._validation import FloatArray

__all__ = ["aba", "crba", "rnea", "scratch", "transforms"]


@njit(cache=True)
def scratch(n_dof: int) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Scratch of :func:`aba` and :func:`crba`: ``work``, ``inertia`` and ``acc``."""
    return np.zeros((n_dof, 52)), np.zeros((n_dof + 2, 6, 6)), np.zeros((n_dof + 1, 6))


@njit(cache=True)
def transforms(q: FloatArray, consts: FloatArray, work: FloatArray) -> None:
    """E (parent to joint frame) and the joint frame's origin r of every joint at q.

    With R, p the joint placement (consts 0–8, 9–11) and the joint motion
    about or along z: revolute E = (R R_z(q))ᵀ, r = p; prismatic E = Rᵀ,
    r = p + q R e_z.
    """
    for k in range(q.shape[0]):
        angle = q[k]
        if consts[k, 24] == 0.0:
            co, si = math.cos(angle), math.sin(angle)
            for i in range(3):
                a, b = consts[k, 3 * i], consts[k, 3 * i + 1]
                work[k, i] = co * a + si * b  # row 0 of E = column 0 of R R_z
                work[k, 3 + i] = co * b - si * a
                work[k, 6 + i] = consts[k, 3 * i + 2]
            work[k, 9], work[k, 10], work[k, 11] = consts[k, 9], consts[k, 10], consts[k, 11]
        else:
            for i in range(3):
                for j in range(3):
                    work[k, 3 * i + j] = consts[k, 3 * j + i]
            for i in range(3):
                work[k, 9 + i] = consts[k, 9 + i] + angle * consts[k, 3 * i + 2]


@njit(cache=True)
def _motion_in(work: FloatArray, k: int, src: FloatArray, dst: FloatArray) -> None:
    """dst = X_k src: a motion vector (ν, ω) of the parent frame in joint k's frame."""
    nx, ny, nz = src[0], src[1], src[2]
    wx, wy, wz = src[3], src[4], src[5]
    rx, ry, rz = work[k, 9], work[k, 10], work[k, 11]
    # ν + ω × r: the velocity of the joint frame's origin
    nx, ny, nz = nx + wy * rz - wz * ry, ny + wz * rx - wx * rz, nz + wx * ry - wy * rx
    for i in range(3):
        e0, e1, e2 = work[k, 3 * i], work[k, 3 * i + 1], work[k, 3 * i + 2]
        dst[i] = e0 * nx + e1 * ny + e2 * nz
        dst[3 + i] = e0 * wx + e1 * wy + e2 * wz


@njit(cache=True)
def _force_out(work: FloatArray, k: int, src: FloatArray, dst: FloatArray) -> None:
    """dst += X_kᵀ src: a force (f, n) of joint k's frame added in the parent frame."""
    fx = work[k, 0] * src[0] + work[k, 3] * src[1] + work[k, 6] * src[2]
    fy = work[k, 1] * src[0] + work[k, 4] * src[1] + work[k, 7] * src[2]
    fz = work[k, 2] * src[0] + work[k, 5] * src[1] + work[k, 8] * src[2]
    mx = work[k, 0] * src[3] + work[k, 3] * src[4] + work[k, 6] * src[5]
    my = work[k, 1] * src[3] + work[k, 4] * src[4] + work[k, 7] * src[5]
    mz = work[k, 2] * src[3] + work[k, 5] * src[4] + work[k, 8] * src[5]
    rx, ry, rz = work[k, 9], work[k, 10], work[k, 11]
    dst[0] += fx
    dst[1] += fy
    dst[2] += fz
    dst[3] += mx + ry * fz - rz * fy
    dst[4] += my + rz * fx - rx * fz
    dst[5] += mz + rx * fy - ry * fx


@njit(cache=True)
def _inertia_out(
    work: FloatArray,
    k: int,
    child: FloatArray,
    parent: FloatArray,
    x: FloatArray,
    product: FloatArray,
) -> None:
    """parent += X_kᵀ child X_k for a 6 × 6 inertia of joint k's frame (x, product: scratch)."""
    for i in range(3):
        for j in range(3):
            x[3 + i, j] = 0.0
    for i in range(3):
        for j in range(3):
            e = work[k, 3 * i + j]
            x[i, j] = e
            x[3 + i, 3 + j] = e
    rx, ry, rz = work[k, 9], work[k, 10], work[k, 11]
    for i in range(3):
        e0, e1, e2 = work[k, 3 * i], work[k, 3 * i + 1], work[k, 3 * i + 2]
        # −E [r]×, column by column
        x[i, 3] = -(e1 * rz - e2 * ry)
        x[i, 4] = -(e2 * rx - e0 * rz)
        x[i, 5] = -(e0 * ry - e1 * rx)
    for i in range(6):
        for j in range(6):
            total = 0.0
            for m in range(6):
                total += child[i, m] * x[m, j]
            product[i, j] = total
    for i in range(6):
        for j in range(6):
            total = 0.0
            for m in range(6):
                total += x[m, i] * product[m, j]
            parent[i, j] += total


@njit(cache=True)
def _link_inertia(consts: FloatArray, k: int, out: FloatArray) -> None:
    """The 6 × 6 spatial inertia of link k about its frame origin, (linear, angular) order."""
    mass, hx, hy, hz = consts[k, 12], consts[k, 13], consts[k, 14], consts[k, 15]
    for i in range(6):
        for j in range(6):
            out[i, j] = 0.0
    out[0, 0] = out[1, 1] = out[2, 2] = mass
    # [[m 1, −[h]×], [[h]×, I_o]]
    out[0, 4], out[0, 5], out[1, 5] = hz, -hy, hx
    out[1, 3], out[2, 3], out[2, 4] = -hz, hy, -hx
    out[3, 1], out[3, 2], out[4, 2] = -hz, hy, -hx
    out[4, 0], out[5, 0], out[5, 1] = hz, -hy, hx
    out[3, 3], out[3, 4], out[3, 5] = consts[k, 16], consts[k, 17], consts[k, 18]
    out[4, 3], out[4, 4], out[4, 5] = consts[k, 17], consts[k, 19], consts[k, 20]
    out[5, 3], out[5, 4], out[5, 5] = consts[k, 18], consts[k, 20], consts[k, 21]


@njit(cache=True)
def aba(
    q: FloatArray,
    qd: FloatArray,
    tau: FloatArray,
    consts: FloatArray,
    work: FloatArray,
    inertia: FloatArray,
    acc: FloatArray,
    out: FloatArray,
) -> None:
    """q̈ = M(q)⁻¹ (τ − C(q, q̇) q̇ − g(q)) into ``out`` (n_dof,), by the articulated-body algorithm.

    ``q``, ``qd`` [rad, rad/s] and ``tau`` [N m] of shape (n_dof,);
    ``work``, ``inertia``, ``acc`` from :func:`scratch`.
    """
    n_dof = q.shape[0]
    transforms(q, consts, work)
    for k in range(n_dof):
        parent = int(consts[k, 23])
        v = work[k, 12:18]
        if parent < 0:
            for i in range(6):
                v[i] = 0.0
        else:
            _motion_in(work, k, work[parent, 12:18], v)
        rate = qd[k]
        nx, ny, nz, wx, wy, wz = v[0], v[1], v[2], v[3], v[4], v[5]
        c = work[k, 18:24]
        if consts[k, 24] == 0.0:
            v[5] += rate
            c[0], c[1], c[2] = ny * rate, -nx * rate, 0.0
            c[3], c[4], c[5] = wy * rate, -wx * rate, 0.0
        else:
            v[2] += rate
            c[0], c[1], c[2] = wy * rate, -wx * rate, 0.0
            c[3], c[4], c[5] = 0.0, 0.0, 0.0
        ia = inertia[k]
        _link_inertia(consts, k, ia)
        # pᴬ = v ×* (I v)
        h = work[k, 40:46]
        for i in range(6):
            total = 0.0
            for j in range(6):
                total += ia[i, j] * v[j]
            h[i] = total
        nx, ny, nz, wx, wy, wz = v[0], v[1], v[2], v[3], v[4], v[5]
        p = work[k, 24:30]
        p[0] = wy * h[2] - wz * h[1]
        p[1] = wz * h[0] - wx * h[2]
        p[2] = wx * h[1] - wy * h[0]
        p[3] = wy * h[5] - wz * h[4] + ny * h[2] - nz * h[1]
        p[4] = wz * h[3] - wx * h[5] + nz * h[0] - nx * h[2]
        p[5] = wx * h[4] - wy * h[3] + nx * h[1] - ny * h[0]
    for k in range(n_dof - 1, -1, -1):
        ia = inertia[k]
        s = 5 if consts[k, 24] == 0.0 else 2
        u_vec = work[k, 30:36]
        for i in range(6):
            u_vec[i] = ia[i, s]
        d = u_vec[s] + consts[k, 22]
        u = tau[k] - work[k, 24 + s]
        work[k, 36], work[k, 37] = d, u
        parent = int(consts[k, 23])
        if parent < 0:
            continue
        for i in range(6):
            for j in range(6):
                ia[i, j] -= u_vec[i] * u_vec[j] / d
        pa = work[k, 46:52]
        ratio = u / d
        for i in range(6):
            total = work[k, 24 + i] + u_vec[i] * ratio
            for j in range(6):
                total += ia[i, j] * work[k, 18 + j]
            pa[i] = total
        _force_out(work, k, pa, work[parent, 24:30])
        _inertia_out(work, k, ia, inertia[parent], inertia[n_dof], inertia[n_dof + 1])
    base = acc[n_dof]
    for k in range(n_dof):
        parent = int(consts[k, 23])
        a = acc[k]
        if parent < 0:
            for i in range(3):
                base[i] = -consts[k, 25 + i]
                base[3 + i] = 0.0
            _motion_in(work, k, base, a)
        else:
            _motion_in(work, k, acc[parent], a)
        for i in range(6):
            a[i] += work[k, 18 + i]
        s = 5 if consts[k, 24] == 0.0 else 2
        total = work[k, 37]
        for i in range(6):
            total -= work[k, 30 + i] * a[i]
        qdd = total / work[k, 36]
        a[s] += qdd
        out[k] = qdd


@njit(cache=True)
def crba(
    q: FloatArray, consts: FloatArray, work: FloatArray, inertia: FloatArray, out: FloatArray
) -> None:
    """M(q) [kg m²] into ``out`` (n_dof, n_dof), both triangles, armature on the diagonal.

    ``work`` and ``inertia`` from :func:`scratch`.
    """
    n_dof = q.shape[0]
    transforms(q, consts, work)
    for k in range(n_dof):
        _link_inertia(consts, k, inertia[k])
        for j in range(n_dof):
            out[k, j] = 0.0  # joints on different branches are not coupled
    force = work[0, 40:46]
    moved = work[0, 46:52]
    for k in range(n_dof - 1, -1, -1):
        ic = inertia[k]
        s = 5 if consts[k, 24] == 0.0 else 2
        for i in range(6):
            force[i] = ic[i, s]
        out[k, k] = force[s] + consts[k, 22]
        j = k
        parent = int(consts[j, 23])
        while parent >= 0:
            for i in range(6):
                moved[i] = 0.0
            _force_out(work, j, force, moved)
            for i in range(6):
                force[i] = moved[i]
            j = parent
            s_j = 5 if consts[j, 24] == 0.0 else 2
            out[k, j] = out[j, k] = force[s_j]
            parent = int(consts[j, 23])
        parent = int(consts[k, 23])
        if parent >= 0:
            _inertia_out(work, k, ic, inertia[parent], inertia[n_dof], inertia[n_dof + 1])


@njit(cache=True)
def rnea(
    q: FloatArray,
    qd: FloatArray,
    qdd: FloatArray,
    consts: FloatArray,
    work: FloatArray,
    inertia: FloatArray,
    acc: FloatArray,
    out: FloatArray,
) -> None:
    """τ = M(q) q̈ + C(q, q̇) q̇ + g(q) into ``out`` (n_dof,), by the recursive Newton-Euler algorithm.

    ``q``, ``qd``, ``qdd`` [rad, rad/s, rad/s²] of shape (n_dof,); the
    armature adds I_a q̈ as in Pinocchio's ``rnea``; scratch from :func:`scratch`.
    """
    n_dof = q.shape[0]
    transforms(q, consts, work)
    base = acc[n_dof]
    for k in range(n_dof):
        parent = int(consts[k, 23])
        v, a = work[k, 12:18], acc[k]
        if parent < 0:
            for i in range(3):
                base[i] = -consts[k, 25 + i]
                base[3 + i] = 0.0
            for i in range(6):
                v[i] = 0.0
            _motion_in(work, k, base, a)
        else:
            _motion_in(work, k, work[parent, 12:18], v)
            _motion_in(work, k, acc[parent], a)
        rate = qd[k]
        nx, ny, wx, wy = v[0], v[1], v[3], v[4]
        # a = X a_λ + S q̈ + v × S q̇
        if consts[k, 24] == 0.0:
            a[0] += ny * rate
            a[1] -= nx * rate
            a[3] += wy * rate
            a[4] -= wx * rate
            a[5] += qdd[k]
            v[5] += rate
        else:
            a[0] += wy * rate
            a[1] -= wx * rate
            a[2] += qdd[k]
            v[2] += rate
        ia = inertia[k]
        _link_inertia(consts, k, ia)
        h = work[k, 40:46]
        f = work[k, 24:30]
        for i in range(6):
            total = 0.0
            momentum = 0.0
            for j in range(6):
                total += ia[i, j] * a[j]
                momentum += ia[i, j] * v[j]
            f[i] = total
            h[i] = momentum
        # f = I a + v ×* (I v)
        nx, ny, nz, wx, wy, wz = v[0], v[1], v[2], v[3], v[4], v[5]
        f[0] += wy * h[2] - wz * h[1]
        f[1] += wz * h[0] - wx * h[2]
        f[2] += wx * h[1] - wy * h[0]
        f[3] += wy * h[5] - wz * h[4] + ny * h[2] - nz * h[1]
        f[4] += wz * h[3] - wx * h[5] + nz * h[0] - nx * h[2]
        f[5] += wx * h[4] - wy * h[3] + nx * h[1] - ny * h[0]
    for k in range(n_dof - 1, -1, -1):
        s = 5 if consts[k, 24] == 0.0 else 2
        out[k] = work[k, 24 + s] + consts[k, 22] * qdd[k]
        parent = int(consts[k, 23])
        if parent >= 0:
            _force_out(work, k, work[k, 24:30], work[parent, 24:30])
