"""B_Q̃ of eq. 3.26 as a function of the planned spline, by the method of thesis Table 3.1.

Table 3.1 takes B_Q̃k = max_t |Q̂_k − Q_k| with Q̂ from the online estimator
fed with noisy positions. The estimator is a linear filter that starts at
rest at q(0), so with one fixed noise draw (that of
:func:`~sensorless.metric.q_error_bounds`, same seed) its output is
F(q) + F(noise), and the errors are

    e_j  = q̂̈_j − q̈_j = (F_a q − q̈)_j + F_a(noise)_j                 (k = j),
    e_ij = q̂̇_i q̂̇_j − q̇_i q̇_j,  q̂̇ = F_v q + F_v(noise)       (products, squares),

affine (q̈) or quadratic (products) in the control points. A trajectory that
changes its acceleration quickly lags the filter more, so B_Q̃ cannot be held
at the value of the quintic while the trajectory changes: the planner would
buy a smaller ∫|Y| with a larger B_Q̃ that it does not see. :class:`Problem
<sensorless.metric._transcription.Problem>` makes B_Q̃k a variable s_k with
|e_k(t)| <= s_k at the samples where e_k peaks (an epigraph): at the optimum
s_k is the Table 3.1 value of the planned trajectory, for that noise draw.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .._validation import FloatArray
from ..filters import CausalEstimator
from ._plan import IntArray

__all__ = ["LagModel"]


@dataclass(frozen=True)
class LagModel:
    """Estimation errors on the sample grid, affine or quadratic in the variables.

    On the samples t_i = i dt: q̇ = D Z + d, q̂̇ = P Z + p_m, q̂̈ − q̈ = A Z + a_m,
    with Z the free control points (n_free, n_dof); maps (n_samples, n_free),
    offsets (n_samples, n_dof) and, with the filtered noise of draw m,
    (n_draws, n_samples, n_dof).
    """

    rate: FloatArray
    rate_offset: FloatArray
    estimate: FloatArray
    estimate_offset: FloatArray
    acceleration: FloatArray
    acceleration_offset: FloatArray

    @classmethod
    def build(
        cls,
        basis_values: tuple[FloatArray, FloatArray, FloatArray],
        free: FloatArray,
        shift: FloatArray,
        estimator: CausalEstimator,
        noise: FloatArray,
    ) -> LagModel:
        """From the basis (value, first and second derivative) on the sample grid.

        The estimator filters every basis function on its own (a linear filter
        of each column), so the estimates of any spline are the same
        combination of those of the basis functions; ``noise`` (n_draws,
        n_samples, n_dof) [rad] holds the position noise of each draw.
        """
        values, first, second = basis_values
        estimate, _ = estimator.filter(values)
        rates, accelerations = [], []
        for draw in noise:
            noisy, _ = estimator.filter(draw)
            rates.append(noisy.velocity)
            accelerations.append(noisy.acceleration)
        lag_acceleration = np.asarray(estimate.acceleration) - second
        return cls(
            rate=first @ free,
            rate_offset=first @ shift,
            estimate=np.asarray(estimate.velocity) @ free,
            estimate_offset=np.asarray(estimate.velocity) @ shift + np.array(rates),
            acceleration=lag_acceleration @ free,
            acceleration_offset=lag_acceleration @ shift + np.array(accelerations),
        )

    @property
    def n_draws(self) -> int:
        """Noise draws."""
        return int(self.estimate_offset.shape[0])

    def errors(self, z: FloatArray) -> FloatArray:
        """e_k of every draw and sample: shape (n_draws, n_samples, l − 1), Q's order (eq. 3.11)."""
        n = self.rate_offset.shape[1]
        zz = z.reshape(-1, n)
        acceleration = (self.acceleration @ zz)[None] + self.acceleration_offset
        rate = self.rate @ zz + self.rate_offset
        estimate = (self.estimate @ zz)[None] + self.estimate_offset
        first, second = _pairs(n)
        products = estimate[..., first] * estimate[..., second] - (rate[:, first] * rate[:, second])
        return np.asarray(np.concatenate([acceleration, products], axis=-1))

    def at(self, z: FloatArray, draws: IntArray, rows: IntArray, entries: IntArray) -> FloatArray:
        """e_k at the (draw, sample, entry) triples: shape (n_triples,)."""
        n = self.rate_offset.shape[1]
        zz = z.reshape(-1, n)
        out = np.empty(entries.size)
        acc = entries < n
        out[acc] = (
            np.einsum("tf,tf->t", self.acceleration[rows[acc]], zz[:, entries[acc]].T)
            + self.acceleration_offset[draws[acc], rows[acc], entries[acc]]
        )
        first, second = _pairs(n)
        i, j, r, d = first[entries[~acc] - n], second[entries[~acc] - n], rows[~acc], draws[~acc]
        est = self.estimate[r] @ zz + self.estimate_offset[d, r]
        rate = self.rate[r] @ zz + self.rate_offset[r]
        k = np.arange(r.size)
        out[~acc] = est[k, i] * est[k, j] - rate[k, i] * rate[k, j]
        return out

    def gradient(
        self, z: FloatArray, draws: IntArray, rows: IntArray, entries: IntArray
    ) -> FloatArray:
        """∂e_k/∂Z at the (draw, sample, entry) triples: shape (n_triples, n_free, n_dof)."""
        n = self.rate_offset.shape[1]
        zz = z.reshape(-1, n)
        out = np.zeros((entries.size, self.rate.shape[1], n))
        acc = np.flatnonzero(entries < n)
        out[acc, :, entries[acc]] = self.acceleration[rows[acc]]
        products = np.flatnonzero(entries >= n)
        first, second = _pairs(n)
        i, j = first[entries[products] - n], second[entries[products] - n]
        r, d = rows[products], draws[products]
        p_map, d_map = self.estimate[r], self.rate[r]
        est = p_map @ zz + self.estimate_offset[d, r]
        rate = d_map @ zz + self.rate_offset[r]
        k = np.arange(products.size)
        # e_ij = p_i p_j − r_i r_j: the derivative in joint i's variables, then in j's.
        out[products, :, i] += p_map * est[k, j, None] - d_map * rate[k, j, None]
        out[products, :, j] += p_map * est[k, i, None] - d_map * rate[k, i, None]
        return out


def _pairs(n: int) -> tuple[IntArray, IntArray]:
    """Joint pairs of Q (eq. 3.11) after q̈: i < j row-major, then the squares (i, i)."""
    first, second = np.triu_indices(n, 1)
    diagonal = np.arange(n)
    return np.concatenate([first, diagonal]), np.concatenate([second, diagonal])
