"""The drift adapter's per-sample recursion written out joint by joint, compiled by numba.

:class:`~sensorless.observers.adaptive.FrictionAdapter` runs this kernel for
``step`` and ``run`` when numba is installed (its numpy ``_advance`` is the
fallback and the reference the tests compare with, to rounding). The
arithmetic is that of ``FrictionAdapter._advance`` and ``_learn``, operation
for operation; the state arrays are updated in place, a sample whose inputs
or new values are not finite changes nothing. Units and shapes as in
:mod:`sensorless.observers.adaptive`.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._validation import FloatArray
from ._adaptive_state import _Work

__all__ = ["advance_block", "advance_rows", "compiled", "compiled_rows", "run", "temporaries_size"]


def temporaries_size(n: int, m: int) -> int:
    """Length of the flat ``scratch`` of :func:`advance_rows` for n joints and m columns."""
    return n * (6 + 3 * m + m * m) + 3 * m


def advance_block(
    r: FloatArray,
    qd: FloatArray,
    h: FloatArray,
    trusted: Any,
    state: tuple[FloatArray, ...],
    flags: Any,
    updates: Any,
    params: tuple[FloatArray, ...],
    scalars: FloatArray,
    out: FloatArray,
) -> None:
    """Run the adapter over rows of ``r`` [N m], ``qd`` [rad/s] and ``h`` [N m], in place.

    ``state`` = (θ, estimate, P, φ, ψ, δτ, F(δτ)); ``flags[0]`` is 1 once
    started; ``updates`` counts the learned samples per joint; ``params`` =
    (pole, weight, v_s, max_correction, norm weights, box, rate·dt);
    ``scalars`` = (λ, max_trace, columns).
    """
    n, m = r.shape[1], int(scalars[2])
    scratch = np.empty(temporaries_size(n, m))
    advance_rows(r, qd, h, trusted, state, flags, updates, params, scalars, out, scratch)


def advance_rows(
    r: FloatArray,
    qd: FloatArray,
    h: FloatArray,
    trusted: Any,
    state: tuple[FloatArray, ...],
    flags: Any,
    updates: Any,
    params: tuple[FloatArray, ...],
    scalars: FloatArray,
    out: FloatArray,
    scratch: FloatArray,
) -> None:
    """:func:`advance_block` with its temporaries in ``scratch`` (see :func:`temporaries_size`).

    A stream calls it once per sample on one row: with the temporaries in
    its own buffers it allocates nothing.
    """
    theta, estimate, cov, reg, freg, corr, fcorr = state
    pole, weight, v_s, max_corr, norm_w, box, step_bound = params
    lam, max_trace = scalars[0], scalars[1]
    m = int(scalars[2])
    n_samples, n = r.shape
    phi = scratch[: 3 * n].reshape((n, 3))
    at = 3 * n
    delta, filt, model_part = (
        scratch[at : at + n],
        scratch[at + n : at + 2 * n],
        scratch[at + 2 * n : at + 3 * n],
    )
    at += 3 * n
    psi = scratch[at : at + n * m].reshape((n, m))
    new_theta = scratch[at + n * m : at + 2 * n * m].reshape((n, m))
    new_est = scratch[at + 2 * n * m : at + 3 * n * m].reshape((n, m))
    at += 3 * n * m
    new_cov = scratch[at : at + n * m * m].reshape((n, m, m))
    at += n * m * m
    p_psi, gain, move = (
        scratch[at : at + m],
        scratch[at + m : at + 2 * m],
        scratch[at + 2 * m : at + 3 * m],
    )
    for j in range(n):
        model_part[j] = 0.0
    for k in range(n_samples):
        finite = True
        for j in range(n):
            if not (np.isfinite(r[k, j]) and np.isfinite(qd[k, j]) and np.isfinite(h[k, j])):
                finite = False
        if not finite:
            for j in range(n):
                out[k, j] = r[k, j] - fcorr[j]
            continue
        ok = True
        for j in range(n):
            phi[j, 0] = math.tanh(qd[k, j] / v_s[j])
            phi[j, 1] = qd[k, j]
            phi[j, 2] = 1.0
            s = phi[j, 0] * theta[j, 0] + phi[j, 1] * theta[j, 1] + phi[j, 2] * theta[j, 2]
            if s < -max_corr[j]:
                s = -max_corr[j]
            elif s > max_corr[j]:
                s = max_corr[j]
            delta[j] = s
            ok = ok and np.isfinite(phi[j, 0]) and np.isfinite(s)
        if flags[0] == 0:
            if ok:
                for j in range(n):
                    for c in range(3):
                        reg[j, c] = phi[j, c]
                    corr[j] = delta[j]
                flags[0] = 1
            for j in range(n):
                out[k, j] = r[k, j]
            continue
        any_trusted = False
        for j in range(n):
            for c in range(3):
                psi[j, c] = pole[j] * freg[j, c] + (weight[j] * 0.5) * (reg[j, c] + phi[j, c])
            if m == 4:
                psi[j, 3] = h[k, j]
                model_part[j] = theta[j, 3] * h[k, j]
            filt[j] = pole[j] * fcorr[j] + weight[j] * 0.5 * (corr[j] + delta[j])
            any_trusted = any_trusted or trusted[k, j]
        for j in range(n):
            if not (any_trusted and trusted[k, j]):
                for a in range(m):
                    new_theta[j, a] = theta[j, a]
                    new_est[j, a] = estimate[j, a]
                    for b in range(m):
                        new_cov[j, a, b] = cov[j, a, b]
                continue
            den = 0.0
            predicted = 0.0
            for a in range(m):
                acc = 0.0
                for b in range(m):
                    acc += cov[j, a, b] * psi[j, b]
                p_psi[a] = acc
            for a in range(m):
                den += psi[j, a] * p_psi[a]
                predicted += psi[j, a] * estimate[j, a]
            den += lam
            err = r[k, j] - predicted
            for a in range(m):
                gain[a] = p_psi[a] / den
                new_est[j, a] = estimate[j, a] + gain[a] * err
            for a in range(m):
                for b in range(m):
                    new_cov[j, a, b] = (cov[j, a, b] - gain[a] * p_psi[b]) / lam
            trace = 0.0
            for a in range(m):
                for b in range(a + 1, m):
                    sym = 0.5 * (new_cov[j, a, b] + new_cov[j, b, a])
                    new_cov[j, a, b] = sym
                    new_cov[j, b, a] = sym
                trace += new_cov[j, a, a]
            if trace > max_trace:
                cap = max_trace / trace
                for a in range(m):
                    for b in range(m):
                        new_cov[j, a, b] *= cap
            size = 0.0
            for a in range(m):
                target = new_est[j, a]
                if target < -box[j, a]:
                    target = -box[j, a]
                elif target > box[j, a]:
                    target = box[j, a]
                move[a] = target - theta[j, a]
                size += abs(move[a]) * norm_w[j, a]
            shrink = step_bound[j] / size if size > step_bound[j] else 1.0
            for a in range(m):
                new_theta[j, a] = theta[j, a] + move[a] * shrink
        for j in range(n):
            ok = ok and np.isfinite(filt[j])
            for a in range(m):
                ok = ok and np.isfinite(psi[j, a]) and np.isfinite(new_theta[j, a])
                ok = ok and np.isfinite(new_est[j, a])
                for b in range(m):
                    ok = ok and np.isfinite(new_cov[j, a, b])
        if not ok:
            for j in range(n):
                out[k, j] = r[k, j] - fcorr[j]
            continue
        for j in range(n):
            for c in range(3):
                reg[j, c] = phi[j, c]
            for a in range(m):
                freg[j, a] = psi[j, a]
                theta[j, a] = new_theta[j, a]
                estimate[j, a] = new_est[j, a]
                for b in range(m):
                    cov[j, a, b] = new_cov[j, a, b]
            corr[j] = delta[j]
            fcorr[j] = filt[j]
            if any_trusted and trusted[k, j]:
                updates[j] += 1
            out[k, j] = r[k, j] - filt[j] - model_part[j]


def run(
    work: _Work,
    inputs: tuple[FloatArray, FloatArray, FloatArray],
    trusted: Any,
    params: tuple[FloatArray, ...],
    scalars: FloatArray,
) -> FloatArray:
    """Rows of checked (r̂, q̇, h) through :data:`compiled`, updating ``work`` in place."""
    r_hat, qd, h = inputs
    out = np.empty(r_hat.shape)
    flags = np.array([int(work.started)], dtype=np.int64)
    state = (
        work.theta, work.estimate, work.covariance, work.regressor,
        work.filtered_regressor, work.correction, work.filtered_correction,
    )  # fmt: skip
    compiled(
        np.ascontiguousarray(r_hat, dtype=np.float64),
        np.ascontiguousarray(qd, dtype=np.float64),
        np.ascontiguousarray(h, dtype=np.float64),
        np.ascontiguousarray(trusted, dtype=np.bool_),
        state,
        flags,
        work.updates,
        params,
        scalars,
        out,
    )
    work.started = bool(flags[0])
    return out


compiled: Any
compiled_rows: Any
try:
    from numba import njit
except ImportError:  # FrictionAdapter._advance (numpy) is the fallback
    compiled = compiled_rows = None
else:
    # advance_block calls these by their global names: bound to the compiled
    # versions before advance_block is compiled, those calls stay in machine code.
    temporaries_size = njit(cache=True)(temporaries_size)
    advance_rows = compiled_rows = njit(cache=True)(advance_rows)
    compiled = njit(cache=True)(advance_block)
