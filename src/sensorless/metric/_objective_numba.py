"""Compiled (numba) smooth integrand L of eq. 3.30 and its gradient, one sample at a time.

Importing this module requires numba; :mod:`._objective` falls back to its
numpy form when the import fails. Notation: :mod:`sensorless.metric._plan`
and :mod:`._objective`. Per sample the kernel evaluates the split entries
Y_k^q(q) (the kinematics, vector table and products of
:mod:`._kernel_numba`, restricted to the products the split entries use)
at q and at q + h e_j for every joint j, so the gradient in q is a forward
difference; the gradient in q̇ and q̈ is exact (Y is linear in Q).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .._validation import FloatArray
from ._kernel_numba import _kinematics, _products, _vector_table
from ._plan import IntArray

__all__ = ["objective_batch"]


@njit(cache=True)
def _split_entries(
    q: FloatArray,
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
    no_cross: IntArray,
    product_x: IntArray,
    product_w: IntArray,
    entry_product: IntArray,
    entry_sign: FloatArray,
    zeros: FloatArray,
    frames: FloatArray,
    work: FloatArray,
    table: FloatArray,
    products: FloatArray,
    y: FloatArray,
) -> None:
    """The 10 coefficients of every split entry Y_kjp^q(q) at ``q`` into ``y``."""
    parents, revolute, n_ancestors = joints[:, 0], joints[:, 1], joints[:, 2]
    _kinematics(q, parents, revolute, axes, rotations, translations, frames, work)
    _vector_table(
        q, zeros, zeros, revolute, gravity, jacobian, gravity_row, ancestors, n_ancestors,
        cross_rows, pair_row, joints[:, 3:5], no_cross, frames, table,
    )  # fmt: skip
    _products(table, product_x, product_w, products)
    for e in range(entry_product.shape[0]):
        for c in range(10):
            y[e, c] = products[entry_product[e, 0], c] * entry_sign[e, 0]
        for slot in range(1, 3):
            sign = entry_sign[e, slot]
            if sign != 0.0:
                p = entry_product[e, slot]
                for c in range(10):
                    y[e, c] += products[p, c] * sign


@njit(cache=True)
def _value(
    y: FloatArray,
    big_q: FloatArray,
    qdd: FloatArray,
    entries: IntArray,
    moves: IntArray,
    theta: FloatArray,
    btheta: FloatArray,
    bq: FloatArray,
    weights: FloatArray,
    epsilon: float,
    yth: FloatArray,
    ysum: FloatArray,
    part: FloatArray,
) -> float:
    """L of one sample; leaves Σ_b Y_k^q Θ̂ in ``yth``, Y_{j,(b,c)} in ``ysum`` and
    Σ_j w_j f(Y_kj^q Θ̂) (= ∂L/∂B_Q̃k) in ``part``."""
    n, length = yth.shape
    yth[:] = 0.0
    ysum[:] = 0.0
    part[:] = 0.0
    for e in range(entries.shape[0]):
        b, i, k = entries[e, 0], entries[e, 1], entries[e, 2]
        value = 0.0
        for c in range(10):
            value += y[e, c] * theta[b, c]
            ysum[i, b, c] += y[e, c] * big_q[k]
        yth[i, k] += value
    total = 0.0
    for i in range(n):
        yth[i, i] += theta[i, 10]
        joint = 0.0
        for k in range(length):
            magnitude = math.sqrt(epsilon + yth[i, k] ** 2)
            joint += magnitude * bq[k]
            part[k] += weights[i] * magnitude
        for b in range(n):
            if moves[i, b]:
                for c in range(10):
                    joint += math.sqrt(epsilon + ysum[i, b, c] ** 2) * btheta[b, c]
        joint += math.sqrt(epsilon + qdd[i] ** 2) * btheta[i, 10]
        total += weights[i] * joint
    return total


@njit(cache=True)
def _rate_gradient(
    y: FloatArray,
    ysum: FloatArray,
    qd: FloatArray,
    qdd: FloatArray,
    entries: IntArray,
    btheta: FloatArray,
    weights: FloatArray,
    epsilon: float,
    grad_q: FloatArray,
    out: FloatArray,
) -> None:
    """∂L/∂q̇ into ``out[1]`` and ∂L/∂q̈ into ``out[2]`` from the entries of one sample."""
    n = qd.shape[0]
    length = grad_q.shape[0]
    grad_q[:] = 0.0
    for e in range(entries.shape[0]):
        b, i, k = entries[e, 0], entries[e, 1], entries[e, 2]
        total = 0.0
        for c in range(10):
            x = ysum[i, b, c]
            total += x / math.sqrt(epsilon + x * x) * btheta[b, c] * y[e, c]
        grad_q[k] += weights[i] * total
    squares = length - 1 - n
    for m in range(n):
        x = qdd[m]
        out[2, m] = grad_q[m] + weights[m] * x / math.sqrt(epsilon + x * x) * btheta[m, 10]
        rate = 2.0 * qd[m] * grad_q[squares + m]
        for j in range(n):
            if j != m:
                low, high = min(m, j), max(m, j)
                pair = n + low * n - low * (low + 1) // 2 + (high - low - 1)
                rate += grad_q[pair] * qd[j]
        out[1, m] = rate


@njit(cache=True)
def objective_batch(
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
    product_x: IntArray,
    product_w: IntArray,
    entry_product: IntArray,
    entry_sign: FloatArray,
    entries: IntArray,
    moves: IntArray,
    n_vectors: int,
    theta: FloatArray,
    btheta: FloatArray,
    bq: FloatArray,
    weights: FloatArray,
    epsilon: float,
    step: float,
    with_gradient: bool,
    value: FloatArray,
    gradient: FloatArray,
    parts: FloatArray,
) -> None:
    """L of every sample into ``value`` (n_samples,), its gradient into ``gradient``.

    ``parts`` (n_samples, l) receives ∂L/∂B_Q̃k = Σ_j w_j f(Y_kj^q(q) Θ̂).
    Without ``with_gradient`` only ``value`` is written. ``gradient`` has
    shape (n_samples, 3, n_dof): ∂L/∂q (forward difference of step ``step``
    [rad]), ∂L/∂q̇, ∂L/∂q̈. ``entries`` (n_split, 3) holds
    the body, joint and term of each split entry; ``moves[i, b]`` is 1 when
    joint i moves link b.
    """
    n = q.shape[1]
    length = bq.shape[0]
    squares = length - 1 - n
    table = np.zeros((n_vectors, 6))
    products = np.empty((product_x.shape[0], 10))
    frames = np.empty((n, 15))
    work = np.empty((2, 3, 3))
    y = np.empty((entries.shape[0], 10))
    yth = np.empty((n, length))
    ysum = np.empty((n, n, 10))
    big_q = np.empty(length)
    part = np.empty(length)
    grad_q = np.empty(length)
    zeros = np.zeros(n)
    point = np.empty(n)
    no_cross = np.zeros((0, 3), dtype=np.intp)
    for s in range(q.shape[0]):
        pair = n
        for i in range(n):
            big_q[i] = qdd[s, i]
            big_q[squares + i] = qd[s, i] * qd[s, i]
            for j in range(i + 1, n):
                big_q[pair] = qd[s, i] * qd[s, j]
                pair += 1
        big_q[length - 1] = 1.0
        for p in range(n + 1 if with_gradient else 1):
            for i in range(n):
                point[i] = q[s, i]
            if p > 0:
                point[p - 1] += step
            _split_entries(
                point, joints, axes, rotations, translations, gravity, jacobian, gravity_row,
                ancestors, cross_rows, pair_row, no_cross, product_x, product_w, entry_product,
                entry_sign, zeros, frames, work, table, products, y,
            )  # fmt: skip
            total = _value(
                y, big_q, qdd[s], entries, moves, theta, btheta, bq, weights, epsilon, yth, ysum,
                part,
            )  # fmt: skip
            if p == 0:
                value[s] = total
                parts[s] = part
                if not with_gradient:
                    continue
                _rate_gradient(
                    y, ysum, qd[s], qdd[s], entries, btheta, weights, epsilon, grad_q, gradient[s]
                )
            else:
                gradient[s, 0, p - 1] = (total - value[s]) / step
