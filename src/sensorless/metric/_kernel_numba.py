"""Compiled (numba) form of the bound terms: a :class:`~sensorless.metric._plan.BoundPlan`.

Importing this module requires numba; :func:`sensorless.metric.error_bound_terms`
falls back to :mod:`._kernel_numpy` when the import fails. The kernel runs the
plan one sample at a time with scalar arithmetic, in scratch arrays allocated
once per call (a one-sample call of the stream included):

``table`` (n_vectors, 6)
    The vector table of the sample (row 0 stays zero).
``products`` (n_products, 10)
    Φ(x, w) of every product of the plan.
``frames`` (n_dof, 15)
    Per joint: world rotation, row-major (0–8, the layout the rotation helpers of
    :mod:`sensorless.robots._recursion_numba` read), origin [m] (9–11), joint axis (12–14);
    ``work`` (2, 3, 3) holds two rotations while they are built.
``yth`` (n_dof, l)
    Σ_b Y_k^q Θ̂ per joint and term.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .._validation import FloatArray
from ..robots._recursion_numba import _cross, _rotate_t
from ._plan import IntArray

__all__ = ["bound_terms_batch"]


@njit(cache=True)
def _kinematics(
    q: FloatArray,
    parents: IntArray,
    revolute: IntArray,
    axes: FloatArray,
    rotations: FloatArray,
    translations: FloatArray,
    frames: FloatArray,
    work: FloatArray,
) -> None:
    """World rotation, origin and joint axis of every joint into ``frames``; ``work`` (2, 3, 3)."""
    frame, local = work[0], work[1]
    for k in range(q.shape[0]):
        parent = parents[k]
        for r in range(3):
            for c in range(3):
                if parent >= 0:
                    value = 0.0
                    for j in range(3):
                        value += frames[parent, 3 * r + j] * rotations[k, j, c]
                    frame[r, c] = value
                else:
                    frame[r, c] = rotations[k, r, c]
        for r in range(3):
            start = translations[k, r]
            if parent >= 0:
                start = frames[parent, 9 + r]
                for j in range(3):
                    start += frames[parent, 3 * r + j] * translations[k, j]
            direction = frame[r, 0] * axes[k, 0] + frame[r, 1] * axes[k, 1]
            frames[k, 12 + r] = direction + frame[r, 2] * axes[k, 2]
            frames[k, 9 + r] = start
        if revolute[k]:
            # R = frame · (I + sin q [a]× + (1 − cos q) [a]×²)
            ax, ay, az = axes[k, 0], axes[k, 1], axes[k, 2]
            sine, versine = math.sin(q[k]), 1.0 - math.cos(q[k])
            local[0, 0] = 1.0 - versine * (ay * ay + az * az)
            local[1, 1] = 1.0 - versine * (ax * ax + az * az)
            local[2, 2] = 1.0 - versine * (ax * ax + ay * ay)
            local[0, 1] = -sine * az + versine * ax * ay
            local[1, 0] = sine * az + versine * ax * ay
            local[0, 2] = sine * ay + versine * ax * az
            local[2, 0] = -sine * ay + versine * ax * az
            local[1, 2] = -sine * ax + versine * ay * az
            local[2, 1] = sine * ax + versine * ay * az
            for r in range(3):
                for c in range(3):
                    frames[k, 3 * r + c] = (
                        frame[r, 0] * local[0, c]
                        + frame[r, 1] * local[1, c]
                        + frame[r, 2] * local[2, c]
                    )
        else:
            for r in range(3):
                for c in range(3):
                    frames[k, 3 * r + c] = frame[r, c]
                frames[k, 9 + r] += frames[k, 12 + r] * q[k]


@njit(cache=True, inline="always")
def _motion_cross(table: FloatArray, out: int, left: int, right: int) -> None:
    """table[out] = table[left] ×m table[right] (spatial motion vectors, linear first)."""
    lx, ly, lz = table[left, 0], table[left, 1], table[left, 2]
    ax, ay, az = table[left, 3], table[left, 4], table[left, 5]
    rx, ry, rz = table[right, 0], table[right, 1], table[right, 2]
    bx, by, bz = table[right, 3], table[right, 4], table[right, 5]
    c1x, c1y, c1z = _cross(ax, ay, az, rx, ry, rz)
    c2x, c2y, c2z = _cross(lx, ly, lz, bx, by, bz)
    table[out, 0], table[out, 1], table[out, 2] = c1x + c2x, c1y + c2y, c1z + c2z
    table[out, 3], table[out, 4], table[out, 5] = _cross(ax, ay, az, bx, by, bz)


@njit(cache=True)
def _vector_table(
    q: FloatArray,
    qd: FloatArray,
    qdd: FloatArray,
    revolute: IntArray,
    gravity: FloatArray,
    jacobian: IntArray,
    gravity_row: IntArray,
    ancestors: IntArray,
    n_ancestors: IntArray,
    cross_rows: IntArray,
    pair_row: IntArray,
    motion_rows: IntArray,
    velocity_cross: IntArray,
    frames: FloatArray,
    table: FloatArray,
) -> None:
    """The vector table of one sample; ``motion_rows[b]`` are the rows of v_b and a_b."""
    n = q.shape[0]
    for b in range(n):
        for index in range(n_ancestors[b]):
            k = ancestors[b, index]
            row = jacobian[b, k]
            zx, zy, zz = frames[k, 12], frames[k, 13], frames[k, 14]
            if revolute[k]:
                dx, dy, dz = (
                    frames[b, 9] - frames[k, 9],
                    frames[b, 10] - frames[k, 10],
                    (frames[b, 11] - frames[k, 11]),
                )
                lx, ly, lz = _cross(zx, zy, zz, dx, dy, dz)
                table[row, 0], table[row, 1], table[row, 2] = _rotate_t(frames, b, lx, ly, lz)
                table[row, 3], table[row, 4], table[row, 5] = _rotate_t(frames, b, zx, zy, zz)
            else:
                table[row, 0], table[row, 1], table[row, 2] = _rotate_t(frames, b, zx, zy, zz)
                table[row, 3], table[row, 4], table[row, 5] = 0.0, 0.0, 0.0
        row = gravity_row[b]
        gx, gy, gz = _rotate_t(frames, b, -gravity[0], -gravity[1], -gravity[2])
        table[row, 0], table[row, 1], table[row, 2] = gx, gy, gz
        table[row, 3], table[row, 4], table[row, 5] = 0.0, 0.0, 0.0
    for index in range(cross_rows.shape[0]):
        _motion_cross(table, cross_rows[index, 0], cross_rows[index, 1], cross_rows[index, 2])
    for b in range(n):
        velocity, acceleration = motion_rows[b, 0], motion_rows[b, 1]
        for c in range(6):
            table[velocity, c] = 0.0
            table[acceleration, c] = table[gravity_row[b], c]
        for first in range(n_ancestors[b]):
            k = ancestors[b, first]
            row = jacobian[b, k]
            for c in range(6):
                table[velocity, c] += table[row, c] * qd[k]
                table[acceleration, c] += table[row, c] * qdd[k]
            for second in range(first + 1, n_ancestors[b]):
                j = ancestors[b, second]
                pair, speed = pair_row[b, k, j], qd[k] * qd[j]
                for c in range(6):
                    table[acceleration, c] += table[pair, c] * speed
    for index in range(velocity_cross.shape[0]):
        out, left, right = (
            velocity_cross[index, 0],
            velocity_cross[index, 1],
            velocity_cross[index, 2],
        )
        _motion_cross(table, out, left, right)


@njit(cache=True)
def _products(table: FloatArray, product_x: IntArray, product_w: IntArray, out: FloatArray) -> None:
    """Φ(x, w) of every product, thesis order (XX, XY, XZ, YY, YZ, ZZ, mX, mY, mZ, m)."""
    for p in range(product_x.shape[0]):
        x, w = product_x[p], product_w[p]
        xlx, xly, xlz = table[x, 0], table[x, 1], table[x, 2]
        xax, xay, xaz = table[x, 3], table[x, 4], table[x, 5]
        wlx, wly, wlz = table[w, 0], table[w, 1], table[w, 2]
        wax, way, waz = table[w, 3], table[w, 4], table[w, 5]
        out[p, 0] = xax * wax
        out[p, 1] = xax * way + xay * wax
        out[p, 2] = xax * waz + xaz * wax
        out[p, 3] = xay * way
        out[p, 4] = xay * waz + xaz * way
        out[p, 5] = xaz * waz
        c1x, c1y, c1z = _cross(xlx, xly, xlz, wax, way, waz)
        c2x, c2y, c2z = _cross(wlx, wly, wlz, xax, xay, xaz)
        out[p, 6], out[p, 7], out[p, 8] = c1x + c2x, c1y + c2y, c1z + c2z
        out[p, 9] = xlx * wlx + xly * wly + xlz * wlz


@njit(cache=True)
def _entries(
    products: FloatArray,
    entry_product: IntArray,
    entry_sign: FloatArray,
    entry_body: IntArray,
    entry_joint: IntArray,
    entry_term: IntArray,
    n_split: int,
    theta: FloatArray,
    btheta: FloatArray,
    bq: FloatArray,
    yth: FloatArray,
    out: FloatArray,
) -> None:
    """Sum the entries: Σ_b Y_k^q Θ̂ into ``yth``, the cross and parameter terms into ``out``."""
    y = np.empty(10)
    for e in range(entry_product.shape[0]):
        for c in range(10):
            y[c] = products[entry_product[e, 0], c] * entry_sign[e, 0]
        for slot in range(1, 3):
            sign = entry_sign[e, slot]
            if sign != 0.0:
                p = entry_product[e, slot]
                for c in range(10):
                    y[c] += products[p, c] * sign
        b, i = entry_body[e], entry_joint[e]
        magnitude = 0.0
        for c in range(10):
            magnitude += abs(y[c]) * btheta[b, c]
        if e < n_split:
            k = entry_term[e]
            value = 0.0
            for c in range(10):
                value += y[c] * theta[b, c]
            yth[i, k] += value
            out[1, i] += bq[k] * magnitude
        else:
            out[2, i] += magnitude


@njit(cache=True)
def bound_terms_batch(
    q: FloatArray,
    qd: FloatArray,
    qdd: FloatArray,
    joints: IntArray,
    axes: FloatArray,
    rotations: FloatArray,
    translations: FloatArray,
    gravity: FloatArray,
    jacobian: IntArray,
    gravity_row: IntArray,
    ancestors: IntArray,
    cross_rows: IntArray,
    pair_row: IntArray,
    velocity_cross: IntArray,
    product_x: IntArray,
    product_w: IntArray,
    entry_product: IntArray,
    entry_sign: FloatArray,
    entries: IntArray,
    n_vectors: int,
    n_split: int,
    theta: FloatArray,
    btheta: FloatArray,
    bq: FloatArray,
    out: FloatArray,
) -> None:
    """The three terms of every sample (axis 0 of q, qd, qdd) into ``out`` (3, n_samples, n_dof).

    ``joints`` (n_dof, 5) holds per joint its parent (−1: root), 1 if revolute,
    the number of its ancestors and the rows of v_b and a_b; ``entries``
    (n_entries, 3) the body, joint and term of each entry (term −1 past
    ``n_split``). The other arrays are those of the plan and weights.
    """
    n = q.shape[1]
    length = bq.shape[0]
    table = np.zeros((n_vectors, 6))
    products = np.empty((product_x.shape[0], 10))
    frames = np.empty((n, 15))
    work = np.empty((2, 3, 3))
    yth = np.empty((n, length))
    parents, revolute, n_ancestors = joints[:, 0], joints[:, 1], joints[:, 2]
    motion_rows = joints[:, 3:5]
    for s in range(q.shape[0]):
        _kinematics(q[s], parents, revolute, axes, rotations, translations, frames, work)
        _vector_table(
            q[s], qd[s], qdd[s], revolute, gravity, jacobian, gravity_row, ancestors,
            n_ancestors, cross_rows, pair_row, motion_rows, velocity_cross, frames, table,
        )  # fmt: skip
        _products(table, product_x, product_w, products)
        yth[:] = 0.0
        result = out[:, s]
        result[:] = 0.0
        _entries(
            products, entry_product, entry_sign, entries[:, 0], entries[:, 1], entries[:, 2],
            n_split, theta, btheta, bq, yth, result,
        )  # fmt: skip
        for i in range(n):
            # Y_{M_i} has 1 in the armature column Ia_i at joint i.
            yth[i, i] += theta[i, 10]
            total = 0.0
            for k in range(length):
                total += abs(yth[i, k]) * bq[k]
            result[0, i] = total
            result[1, i] += bq[i] * btheta[i, 10]
            result[2, i] += abs(qdd[s, i]) * btheta[i, 10]
