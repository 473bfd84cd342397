"""Numpy form of the bound terms: a :class:`~sensorless.metric._plan.BoundPlan` over blocks.

Every array keeps the samples on its last axis, so that gathering rows of
the vector table or of the products copies contiguous blocks. Notation:
:mod:`sensorless.metric._plan`.
"""

from __future__ import annotations

import numpy as np

from .._validation import FloatArray
from ..robots.regressors import q_length
from ._plan import BoundPlan, BoundWeights

__all__ = ["bound_terms_block"]


def bound_terms_block(
    plan: BoundPlan,
    weights: BoundWeights,
    q: FloatArray,
    qd: FloatArray,
    qdd: FloatArray,
    out: FloatArray,
) -> None:
    """The three terms of every sample of a block into ``out`` of shape (3, n_samples, n_dof).

    ``q``, ``qd``, ``qdd`` [rad, rad/s, rad/s²] have shape (n_samples, n_dof);
    the rows of ``out`` are the q-error, cross and parameter-error terms [N m].
    """
    n_samples, n = q.shape
    vectors = _vector_table(plan, q, qd, qdd)
    products = _phi(vectors[plan.product_x], vectors[plan.product_w])  # (product, 10, sample)
    entries = products[plan.entry_product[:, 0]] * plan.entry_sign[:, :1, None]
    for slot in (1, 2):
        used = np.flatnonzero(plan.entry_sign[:, slot])
        sign = plan.entry_sign[used, slot, None, None]
        entries[used] += products[plan.entry_product[used, slot]] * sign
    n_split = plan.n_split_entries
    split, param = entries[:n_split], entries[n_split:]
    body = plan.entry_body[:n_split]
    length = q_length(n)
    # Σ_b Y_k^q Θ̂ per (joint, term); Y_{M_i} has 1 in the armature column Ia_i at joint i.
    yth = np.zeros((n * length, n_samples))
    grouped = np.einsum("ecs,ec->es", split, weights.theta[body, :10])
    yth[plan.group_flat] = np.add.reduceat(grouped, plan.group_start, axis=0)
    diagonal = np.arange(n) * (length + 1)
    yth[diagonal] += weights.theta[:, 10, None]
    out[0] = (np.abs(yth.reshape(n, length, n_samples)).transpose(2, 0, 1)) @ weights.bq
    magnitude = np.einsum("ecs,ec->es", np.abs(split), weights.btheta[body, :10])
    magnitude *= weights.bq[plan.entry_term, None]
    cross = np.add.reduceat(magnitude, plan.joint_start, axis=0)
    out[1] = cross.T + weights.bq[:n] * weights.btheta[:, 10]
    body = plan.entry_body[n_split:]
    magnitude = np.einsum("ecs,ec->es", np.abs(param), weights.btheta[body, :10])
    param_error = np.add.reduceat(magnitude, plan.param_joint_start, axis=0)
    out[2] = param_error.T + np.abs(qdd) * weights.btheta[:, 10]


def _cross(a: FloatArray, b: FloatArray) -> FloatArray:
    """Cross product of (..., 3, n_samples) arrays along axis −2."""
    a0, a1, a2 = a[..., 0, :], a[..., 1, :], a[..., 2, :]
    b0, b1, b2 = b[..., 0, :], b[..., 1, :], b[..., 2, :]
    return np.stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0], axis=-2)


def _motion_cross(x: FloatArray, w: FloatArray) -> FloatArray:
    """x ×m w of (..., 6, n_samples) spatial motion vectors (linear, angular)."""
    xl, xa, wl, wa = x[..., :3, :], x[..., 3:, :], w[..., :3, :], w[..., 3:, :]
    return np.concatenate([_cross(xa, wl) + _cross(xl, wa), _cross(xa, wa)], axis=-2)


def _phi(x: FloatArray, w: FloatArray) -> FloatArray:
    """Φ(x, w) of (..., 6, n_samples) arrays: the 10 coefficients of xᵀ I w, thesis order."""
    xl, xa, wl, wa = x[..., :3, :], x[..., 3:, :], w[..., :3, :], w[..., 3:, :]
    first_moment = _cross(xl, wa) + _cross(wl, xa)
    a0, a1, a2 = xa[..., 0, :], xa[..., 1, :], xa[..., 2, :]
    b0, b1, b2 = wa[..., 0, :], wa[..., 1, :], wa[..., 2, :]
    mass = xl[..., 0, :] * wl[..., 0, :] + xl[..., 1, :] * wl[..., 1, :]
    mass += xl[..., 2, :] * wl[..., 2, :]
    inertia = [a0 * b0, a0 * b1 + a1 * b0, a0 * b2 + a2 * b0, a1 * b1, a1 * b2 + a2 * b1, a2 * b2]
    return np.concatenate([np.stack(inertia, axis=-2), first_moment, mass[..., None, :]], axis=-2)


def _rotation(axis: FloatArray, angle: FloatArray) -> FloatArray:
    """Rotations about the unit ``axis`` by ``angle`` [rad], shape (n_samples, 3, 3)."""
    skew = np.array([[0.0, -axis[2], axis[1]], [axis[2], 0.0, -axis[0]], [-axis[1], axis[0], 0.0]])
    sine, versine = np.sin(angle)[:, None, None], (1.0 - np.cos(angle))[:, None, None]
    return np.eye(3) + sine * skew + versine * (skew @ skew)


def _kinematics(plan: BoundPlan, q: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """World rotation (n, s, 3, 3), origin (n, s, 3) and joint axis (n, s, 3) of every joint."""
    n_samples, n = q.shape
    rotation = np.empty((n, n_samples, 3, 3))
    origin = np.empty((n, n_samples, 3))
    axis = np.empty((n, n_samples, 3))
    for k in range(n):
        parent = plan.parents[k]
        if parent >= 0:
            frame = rotation[parent] @ plan.placement_rotations[k]
            start = origin[parent] + rotation[parent] @ plan.placement_translations[k]
        else:
            frame = np.broadcast_to(plan.placement_rotations[k], (n_samples, 3, 3))
            start = np.broadcast_to(plan.placement_translations[k], (n_samples, 3))
        axis[k] = frame @ plan.axes[k]
        if plan.revolute[k]:
            rotation[k] = frame @ _rotation(plan.axes[k], q[:, k])
            origin[k] = start
        else:
            rotation[k] = frame
            origin[k] = start + axis[k] * q[:, k, None]
    return rotation, origin, axis


def _vector_table(plan: BoundPlan, q: FloatArray, qd: FloatArray, qdd: FloatArray) -> FloatArray:
    """The vector table of every sample, shape (n_vectors, 6, n_samples)."""
    n_samples, n = q.shape
    rotation, origin, axis = _kinematics(plan, q)
    table = np.zeros((plan.n_vectors, 6, n_samples))
    for b in range(n):
        chain = plan.ancestors[b, : plan.n_ancestors[b]]
        rows = plan.jacobian[b, chain]
        # Rᵀ v for every sample: (s, 3, 3)ᵀ applied to (k, s, 3) → (k, 3, s)
        to_body = rotation[b].transpose(0, 2, 1)
        direction = np.einsum("sji,ksj->kis", rotation[b], axis[chain])
        lever = np.cross(axis[chain], origin[b] - origin[chain])
        revolute = plan.revolute[chain]
        table[rows[revolute], :3] = np.einsum("sji,ksj->kis", rotation[b], lever[revolute])
        table[rows[revolute], 3:] = direction[revolute]
        table[rows[~revolute], :3] = direction[~revolute]
        table[plan.gravity_row[b], :3] = (to_body @ -plan.gravity).T
    out, left, right = plan.cross_rows.T
    table[out] = _motion_cross(table[left], table[right])
    for b in range(n):
        chain = plan.ancestors[b, : plan.n_ancestors[b]]
        columns = table[plan.jacobian[b, chain]]
        table[plan.velocity_row[b]] = np.einsum("kcs,sk->cs", columns, qd[:, chain])
        pairs = plan.pair_row[b][np.ix_(chain, chain)]
        upper = np.nonzero(pairs)
        products = qd[:, chain[upper[0]]] * qd[:, chain[upper[1]]]
        table[plan.acceleration_row[b]] = (
            np.einsum("kcs,sk->cs", columns, qdd[:, chain])
            + np.einsum("pcs,sp->cs", table[pairs[upper]], products)
            + table[plan.gravity_row[b]]
        )
    out, left, right = plan.velocity_cross.T
    table[out] = _motion_cross(table[left], table[right])
    return table
