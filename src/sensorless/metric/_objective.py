"""The smooth integrand L(t, q, q̇, q̈) of eq. 3.30 per sample, with its gradient.

With f(x) = (ε + x²)^½ in place of |x| (eq. 3.30), per sample

    L = Σ_j w_j ( Σ_k f(Y_kj^q(q) Θ̂) B_Q̃k + Σ_p f(Y_jp(q, q̇, q̈)) B_Θ̃p ),

the integrand of OBJ[q] (eq. 3.28) without w_t. Y(q, q̇, q̈) = Σ_k Y_k^q(q) Q_k
(eq. 3.12) is built from the split entries, so ∂L/∂Q_k = Σ_j w_j Σ_p
f′(Y_jp) Y_kjp^q B_Θ̃p exactly, and ∂L/∂q̇, ∂L/∂q̈ follow from Q = [q̈;
q̇_i q̇_j; q̇_i²; 1] (eq. 3.11). ∂L/∂q is a forward difference per joint; the
q-dependent entries are recomputed at the n_dof shifted positions of every
sample in one batch. A parameter p is one column of the standard regressor
among the base columns (B_Θ̃ is 0 elsewhere), as in :mod:`sensorless.metric.bounds`.

:class:`SmoothIntegrand` runs the compiled kernel (:mod:`._objective_numba`)
when numba is installed, else the numpy form below (same values).
"""

from __future__ import annotations

from types import ModuleType

import numpy as np

from .._validation import FloatArray
from ..robots.model import RobotModel
from ..robots.regressors import q_length, q_vector
from ._kernel_numpy import _phi, _vector_table
from ._plan import BoundWeights, IntArray, plan_for

_numba_objective: ModuleType | None
try:
    from . import _objective_numba as _numba_objective
except ImportError:  # numba is an optional extra
    _numba_objective = None

__all__ = ["SmoothIntegrand", "backend_of"]

#: Step [rad] of the forward difference in q.
POSITION_STEP = 1e-7
#: Samples per block of the numpy form.
_BLOCK = 64


class SmoothIntegrand:
    """L of eq. 3.30 and its gradient for one robot, weights and bounds.

    Parameters
    ----------
    robot : RobotModel
        Nominal robot.
    columns, theta, btheta : ndarray of shape (n_base,)
        Base columns, Θ̂ and absolute B_Θ̃.
    bq : ndarray of shape (l,)
        B_Q̃.
    joint_weights : ndarray of shape (n_dof,)
        w_j >= 0.
    epsilon : float
        ε > 0 of f(x) = (ε + x²)^½ [in the squared units of each term].
    backend : {"numba", "numpy"}
        Compiled kernel (needs numba) or numpy.
    """

    def __init__(
        self,
        robot: RobotModel,
        columns: IntArray,
        theta: FloatArray,
        btheta: FloatArray,
        bq: FloatArray,
        joint_weights: FloatArray,
        epsilon: float,
        backend: str,
    ) -> None:
        plan = plan_for(robot)
        self.plan = plan
        self.weights = BoundWeights.from_base(robot.n_dof, columns, theta, btheta, bq)
        self.joint_weights = np.ascontiguousarray(joint_weights, dtype=float)
        self.epsilon = float(epsilon)
        self.compiled = backend == "numba" and _numba_objective is not None
        n_split = plan.n_split_entries
        self.entry_product = np.ascontiguousarray(plan.entry_product[:n_split])
        self.entry_sign = np.ascontiguousarray(plan.entry_sign[:n_split])
        self.entries = np.ascontiguousarray(plan.entry_table[:n_split])
        used = int(self.entry_product.max()) + 1
        self.product_x = np.ascontiguousarray(plan.product_x[:used])
        self.product_w = np.ascontiguousarray(plan.product_w[:used])
        n = robot.n_dof
        self.moves = np.zeros((n, n), dtype=np.intp)
        for b in range(n):
            self.moves[plan.ancestors[b, : plan.n_ancestors[b]], b] = 1

    def __call__(
        self,
        q: FloatArray,
        qd: FloatArray,
        qdd: FloatArray,
        with_gradient: bool = True,
        bq: FloatArray | None = None,
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """L, its gradient and its derivatives in B_Q̃ at every sample.

        Parameters
        ----------
        q, qd, qdd : ndarray of shape (n_samples, n_dof)
            Joint positions [rad], velocities [rad/s] and accelerations [rad/s²].
        with_gradient : bool
            Compute the gradient (else it is left uninitialised).
        bq : ndarray of shape (l,), optional
            B_Q̃ for this call; default the one given at construction.

        Returns
        -------
        value : ndarray of shape (n_samples,)
            L [N m].
        gradient : ndarray of shape (n_samples, 3, n_dof)
            ∂L/∂q, ∂L/∂q̇, ∂L/∂q̈.
        parts : ndarray of shape (n_samples, l)
            ∂L/∂B_Q̃k = Σ_j w_j f(Y_kj^q(q) Θ̂).
        """
        q, qd, qdd = (np.ascontiguousarray(x, dtype=float) for x in (q, qd, qdd))
        bounds = self.weights.bq if bq is None else np.ascontiguousarray(bq, dtype=float)
        value = np.empty(q.shape[0])
        gradient = np.empty((q.shape[0], 3, q.shape[1]))
        parts = np.empty((q.shape[0], bounds.size))
        if self.compiled and _numba_objective is not None:
            plan, w = self.plan, self.weights
            _numba_objective.objective_batch(
                q, qd, qdd, plan.joint_table, plan.axes, plan.placement_rotations,
                plan.placement_translations, plan.gravity, plan.jacobian, plan.gravity_row,
                plan.ancestors, plan.cross_rows, plan.pair_row, self.product_x, self.product_w,
                self.entry_product, self.entry_sign, self.entries, self.moves, plan.n_vectors,
                w.theta, w.btheta, bounds, self.joint_weights, self.epsilon, POSITION_STEP,
                with_gradient, value, gradient, parts,
            )  # fmt: skip
            return value, gradient, parts
        for start in range(0, q.shape[0], _BLOCK):
            rows = slice(start, start + _BLOCK)
            value[rows], gradient[rows], parts[rows] = self._block(
                q[rows], qd[rows], qdd[rows], with_gradient, bounds
            )
        return value, gradient, parts

    # ------------------------------------------------------------------ numpy form

    def _split(self, q: FloatArray) -> FloatArray:
        """Split entries Y_kjp^q of every sample, shape (n_split, 10, n_samples)."""
        zeros = np.zeros_like(q)
        vectors = _vector_table(self.plan, q, zeros, zeros)
        products = _phi(vectors[self.product_x], vectors[self.product_w])
        split = products[self.entry_product[:, 0]] * self.entry_sign[:, :1, None]
        for slot in (1, 2):
            used = np.flatnonzero(self.entry_sign[:, slot])
            sign = self.entry_sign[used, slot, None, None]
            split[used] += products[self.entry_product[used, slot]] * sign
        return np.asarray(split)

    def _values(
        self, split: FloatArray, big_q: FloatArray, qdd: FloatArray, bq: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """L per sample, Y_{j,(b,c)} of shape (n_dof·n_dof, 10, n_samples) and the parts."""
        plan, w, eps = self.plan, self.weights, self.epsilon
        n, n_samples = qdd.shape[1], qdd.shape[0]
        length = q_length(n)
        body, joint, term = self.entries.T
        grouped = np.einsum("ecs,ec->es", split, w.theta[body, :10])
        yth = np.zeros((n * length, n_samples))
        yth[plan.group_flat] = np.add.reduceat(grouped, plan.group_start, axis=0)
        yth[np.arange(n) * (length + 1)] += w.theta[:, 10, None]
        magnitude = np.sqrt(eps + yth.reshape(n, length, n_samples) ** 2)
        part_a = magnitude.transpose(0, 2, 1) @ bq
        parts = np.einsum("j,jks->sk", self.joint_weights, magnitude)
        ysum = np.zeros((n * n, 10, n_samples))
        np.add.at(ysum, joint * n + body, split * big_q[term][:, None, :])
        scaled = np.sqrt(eps + ysum**2) * (w.btheta[np.tile(np.arange(n), n), :10])[:, :, None]
        part_b = (scaled.sum(axis=1).reshape(n, n, n_samples) * self.moves[:, :, None]).sum(axis=1)
        part_b += (np.sqrt(eps + qdd**2) * w.btheta[:, 10]).T
        return np.asarray(self.joint_weights @ (part_a + part_b)), ysum, parts

    def _block(
        self, q: FloatArray, qd: FloatArray, qdd: FloatArray, with_gradient: bool, bq: FloatArray
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        n_samples, n = q.shape
        big_q = q_vector(qd, qdd).T
        gradient = np.empty((n_samples, 3, n))
        if not with_gradient:
            value, _, parts = self._values(self._split(q), big_q, qdd, bq)
            return value, gradient, parts
        shifted = np.concatenate([q] + [q + POSITION_STEP * np.eye(n)[j] for j in range(n)])
        split = self._split(shifted)
        values = np.empty((n + 1, n_samples))
        value, ysum, parts = self._values(split[:, :, :n_samples], big_q, qdd, bq)
        values[0] = value
        for p in range(1, n + 1):
            rows = slice(p * n_samples, (p + 1) * n_samples)
            values[p] = self._values(split[:, :, rows], big_q, qdd, bq)[0]
        gradient[:, 0] = ((values[1:] - values[0]) / POSITION_STEP).T
        gradient[:, 1:] = self._rate_gradient(split[:, :, :n_samples], ysum, qd, qdd)
        return value, gradient, parts

    def _rate_gradient(
        self, split: FloatArray, ysum: FloatArray, qd: FloatArray, qdd: FloatArray
    ) -> FloatArray:
        """(∂L/∂q̇, ∂L/∂q̈) of shape (n_samples, 2, n_dof)."""
        w, eps = self.weights, self.epsilon
        n_samples, n = qd.shape
        length = q_length(n)
        body, joint, term = self.entries.T
        sums = ysum[joint * n + body]
        slope = sums / np.sqrt(eps + sums**2) * w.btheta[body, :10, None]
        per_entry = (slope * split).sum(axis=1) * self.joint_weights[joint, None]
        grad_q = np.zeros((length, n_samples))
        np.add.at(grad_q, term, per_entry)
        out = np.empty((n_samples, 2, n))
        out[:, 1] = (
            grad_q[:n].T + self.joint_weights * qdd / np.sqrt(eps + qdd**2) * w.btheta[:, 10]
        )
        upper_i, upper_j = np.triu_indices(n, 1)
        rate = 2.0 * qd * grad_q[length - 1 - n : length - 1].T
        pairs = grad_q[n : n + upper_i.size].T
        np.add.at(rate.T, upper_i, (pairs * qd[:, upper_j]).T)
        np.add.at(rate.T, upper_j, (pairs * qd[:, upper_i]).T)
        out[:, 0] = rate
        return out


def backend_of(name: str) -> str:
    """``"numba"`` when ``name`` is auto or numba and numba is importable, else ``"numpy"``."""
    return "numba" if name != "numpy" and _numba_objective is not None else "numpy"
