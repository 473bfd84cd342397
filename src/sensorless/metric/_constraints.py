"""Constraints of the transcribed problem for SLSQP, in the variables x = [vec(Z), s].

Every inequality is written c(x) >= 0 and scaled by its limit, so that its
rows are of order one: joint position, velocity and acceleration limits at
given times (linear in Z), rigid-body torque limits |M q̈ + C q̇ + g| <= τ_max
(Jacobian from Pinocchio's RNEA derivatives), the epigraph |e_k(t)| <= s_k of
the lag model (:mod:`sensorless.metric._lag`) at given samples, and via points
(linear equalities). Limits are tightened by the relative ``backoff`` so that
the solver's tolerance cannot cross the true ones.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pinocchio as pin

from .._validation import FloatArray
from ._plan import IntArray
from ._transcription import Problem

__all__ = ["constraints"]

Constraint = dict[str, Any]


def constraints(
    problem: Problem, times: FloatArray, lag_pairs: IntArray, backoff: float
) -> list[Constraint]:
    """All constraints: limits at ``times`` [s], the lag model at the (draw, sample, entry)
    triples ``lag_pairs`` of shape (m, 3), via points."""
    out = [_linear_limits(problem, times, backoff)]
    if np.isfinite(problem.limits.torque).any():
        out.append(_torque_limits(problem, times, backoff))
    if problem.lag is not None and lag_pairs.size:
        out.append(_lag(problem, lag_pairs))
    if problem.via is not None:
        out.append(_via(problem))
    return out


def _pad(problem: Problem, matrix: FloatArray) -> FloatArray:
    """Jacobian rows in Z extended by zero columns for s."""
    return np.hstack([matrix, np.zeros((matrix.shape[0], problem.n_s))])


def _linear_limits(problem: Problem, times: FloatArray, backoff: float) -> Constraint:
    lim, keep, n = problem.limits, 1.0 - backoff, problem.n_dof
    maps = problem.affine(times)
    bounded = np.isfinite(lim.upper - lim.lower)
    span, centre, zero = np.full(n, np.inf), np.zeros(n), np.zeros(n)
    span[bounded] = (lim.upper - lim.lower)[bounded]
    centre[bounded] = 0.5 * (lim.upper[bounded] + lim.lower[bounded])
    blocks: list[FloatArray] = []
    offsets: list[FloatArray] = []
    sizes = [
        (0.5 * span * keep, centre),
        (lim.velocity * keep, zero),
        (lim.acceleration * keep, zero),
    ]
    for (g, offset), (half, middle) in zip(maps, sizes, strict=True):
        finite = np.isfinite(half)
        if not finite.any():
            continue
        rows = np.tile(finite, g.shape[0])
        size = np.tile(np.where(finite, half, 1.0), g.shape[0])[rows]
        a = np.kron(g, np.eye(n))[rows] / size[:, None]
        b = (offset.ravel() - np.tile(middle, g.shape[0]))[rows] / size
        # |a x + b| <= 1 as 1 - (a x + b) >= 0 and 1 + (a x + b) >= 0.
        blocks += [-a, a]
        offsets += [1.0 - b, 1.0 + b]
    if not blocks:
        blocks, offsets = [np.zeros((1, problem.n_z))], [np.ones(1)]
    matrix, constant = _pad(problem, np.vstack(blocks)), np.concatenate(offsets)
    return {"type": "ineq", "fun": lambda x: matrix @ x + constant, "jac": lambda x: matrix}


def _torque_limits(problem: Problem, times: FloatArray, backoff: float) -> Constraint:
    maps = problem.affine(times)
    limit = problem.limits.torque * (1.0 - backoff)
    finite = np.isfinite(limit)
    n = problem.n_dof
    model = problem.robot.pinocchio_model
    data = model.createData()
    upper = np.triu(np.ones((n, n), dtype=bool))
    memo: dict[bytes, tuple[FloatArray, FloatArray]] = {}

    def torque(x: FloatArray) -> tuple[FloatArray, FloatArray]:
        key = x.tobytes()
        if key not in memo:
            memo.clear()
            q, qd, qdd = problem.states(x, maps)
            tau = np.empty_like(q)
            derivatives = np.empty((3, q.shape[0], n, n))
            for s in range(q.shape[0]):
                pin.computeRNEADerivatives(model, data, q[s], qd[s], qdd[s])
                tau[s] = pin.rnea(model, data, q[s], qd[s], qdd[s])
                derivatives[0, s], derivatives[1, s] = data.dtau_dq, data.dtau_dv
                derivatives[2, s] = data.M
            # Pinocchio fills the upper triangle of M = ∂τ/∂q̈.
            derivatives[2] = np.where(upper, derivatives[2], derivatives[2].swapaxes(1, 2))
            jac = np.zeros((q.shape[0], n, problem.n_free, n))
            for (g, _), d in zip(maps, derivatives, strict=True):
                jac += np.einsum("sf,sjm->sjfm", g, d)
            ratio = (tau / limit)[:, finite].ravel()
            ratio_jac = np.asarray(
                (jac / limit[None, :, None, None])[:, finite].reshape(ratio.size, -1), dtype=float
            )
            memo[key] = (ratio, _pad(problem, ratio_jac))
        return memo[key]

    return {
        "type": "ineq",
        "fun": lambda x: np.concatenate([1.0 - torque(x)[0], 1.0 + torque(x)[0]]),
        "jac": lambda x: np.vstack([-torque(x)[1], torque(x)[1]]),
    }


def _lag(problem: Problem, triples: IntArray) -> Constraint:
    """(s_k − |e_k(t)|) / scale_k >= 0 at every (draw, sample, entry k) of ``triples``."""
    lag = problem.lag
    assert lag is not None  # only called with the lag model
    draws, rows, entries = triples.T
    scale = problem.lag_scale[entries]
    n_z = problem.n_z
    select = np.zeros((entries.size, problem.n_s))
    select[np.arange(entries.size), entries] = 1.0 / scale

    def value(x: FloatArray) -> FloatArray:
        errors = lag.at(x[:n_z], draws, rows, entries) / scale
        s = x[n_z:][entries] / scale
        return np.concatenate([s - errors, s + errors])

    def jacobian(x: FloatArray) -> FloatArray:
        de = lag.gradient(x[:n_z], draws, rows, entries).reshape(entries.size, n_z)
        de = de / scale[:, None]
        return np.vstack([np.hstack([-de, select]), np.hstack([de, select])])

    return {"type": "ineq", "fun": value, "jac": jacobian}


def _via(problem: Problem) -> Constraint:
    assert problem.via is not None  # only called with via points
    times, positions = problem.via
    design, offset = problem.affine(times)[0]
    matrix = _pad(problem, np.asarray(np.kron(design, np.eye(problem.n_dof)), dtype=float))
    target = (positions - offset).ravel()
    return {"type": "eq", "fun": lambda x: matrix @ x - target, "jac": lambda x: matrix}
