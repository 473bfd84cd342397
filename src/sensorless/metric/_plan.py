"""The terms of eq. 3.28 and 3.36 without building the split regressor.

:func:`sensorless.metric.error_bound_terms` needs, per sample, every entry of
the split regressor Y_k^q(q) restricted to the base parameters (the cross
term takes its absolute value entry by entry). Evaluating the standard
regressor at l unit states (:meth:`RobotModel.regressor_terms`) is simple
but costs l Pinocchio calls and l·n·11n floats per sample. Here the entries
come from the kinematics instead.

With J_i the column of joint i of the Jacobian of link b, expressed in the
frame of link b (spatial vectors written (linear, angular)), v_b and a_b the
spatial velocity and acceleration of link b (gravity as the acceleration
−g of the base), the 10 standard parameters π_b of link b enter the torque
of joint i (an ancestor of b, or b) through

    Y_{i,b} = Φ(J_i, a_b) + Φ(J_i ×m v_b, v_b),    Φ(x, w)·π_b = xᵀ I_b w,

where ×m is the motion cross product and Φ is bilinear and symmetric, with
x = (x_l, x_a), w = (w_l, w_a) and the parameters in the order of thesis
Table 2.5:

- XX … ZZ: the symmetrised products x_a,r w_a,s + x_a,s w_a,r (r ≠ s) and x_a,r w_a,r;
- mX, mY, mZ: x_l × w_a + w_l × x_a;
- m: x_l · w_l.

Since v_b = Σ_k J_k q̇_k and a_b = Σ_k J_k q̈_k + Σ_{k≺j} (J_k ×m J_j) q̇_k q̇_j − g
(k ≺ j: joint k is nearer the base), the split terms of eq. 3.12 are, with
T(i, k, j) = Φ(J_i ×m J_k, J_j):

- Y_{M_k} = Φ(J_i, J_k) (symmetric in i, k), Y_g = Φ(J_i, −g),
- Y_{C_k} = T(i, k, k), Y_{B_kj} = T(k, j, i) + T(i, k, j) + T(i, j, k),

and T(i, k, j) = −T(k, i, j). So a link moved by m joints needs
m(m+1)/2 + m + m²(m−1)/2 evaluations of Φ, not the 3m³/2 of a direct
expansion. The armature column Ia_i adds 1 to Y_{M_i} at joint i.

A :class:`BoundPlan` lists, once per robot, which spatial vectors a sample
needs (the vector table), which products Φ(x, w) of them, and how the
entries of Y_k^q (and of Y at the sample's own q̇, q̈) sum those products.
:mod:`._kernel_numpy` runs the plan over blocks of samples, :mod:`._kernel_numba`
compiled, one sample at a time (:func:`sensorless.metric.error_bound_terms` picks one).
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import NDArray

from .._validation import FloatArray
from ..exceptions import ModelError
from ..robots.inertia import N_LINK_PARAMETERS
from ..robots.model import RobotModel
from ..robots.regressors import q_length

__all__ = ["BoundPlan", "BoundWeights", "IntArray", "plan_for"]

IntArray = NDArray[np.intp]

_PLANS: weakref.WeakKeyDictionary[RobotModel, BoundPlan] = weakref.WeakKeyDictionary()


@dataclass(frozen=True)
class BoundPlan:
    """Constants of the bound computation for one robot (see the module docstring).

    Joints (parents first): ``parents`` (−1 for a root), ``revolute`` (else
    prismatic), unit ``axes`` in the joint frame, the joint placements in the
    parent frame and the ``gravity`` vector [m/s²].

    Vector table (per sample, shape (n_vectors, 6), spatial motion vectors
    (linear, angular)): row 0 is zero; ``jacobian[b, k]`` is the row of J_k in
    the frame of link b (0 when joint k does not move link b);
    ``gravity_row[b]`` that of −g; ``cross_rows`` lists (out, left, right) with
    out = left ×m right over Jacobian columns, ``pair_row[b, k, l]`` being the
    row of J_k ×m J_l for k ≺ l (0 otherwise); ``velocity_row[b]`` and
    ``acceleration_row[b]`` the rows of v_b and a_b; ``velocity_cross`` the
    rows (out, left, right) of J_i ×m v_b. ``ancestors[b, :n_ancestors[b]]``
    are the joints that move link b, root first.

    Products Φ(x, w) of rows ``product_x`` and ``product_w``. Entries: signed
    sums of up to three products (``entry_product``, ``entry_sign``), each
    with the link, joint and (for the first ``n_split_entries``, the entries
    of Y_k^q) term k of Q it belongs to, in ``entry_table`` (term −1 for the
    entries of Y at the sample's state). Entries are sorted by joint, then
    term: ``group_start`` starts the runs of equal (joint, term) and
    ``group_flat`` is joint·l + term of each run; ``joint_start`` starts the
    runs of each joint among split entries, ``param_joint_start`` among the
    others. ``joint_table`` packs, per joint, parent, revolute, number of
    ancestors and the rows of v_b, a_b for the compiled kernel.
    """

    n_dof: int
    parents: IntArray
    revolute: NDArray[np.bool_]
    axes: FloatArray
    placement_rotations: FloatArray
    placement_translations: FloatArray
    gravity: FloatArray
    n_vectors: int
    jacobian: IntArray
    gravity_row: IntArray
    ancestors: IntArray
    n_ancestors: IntArray
    cross_rows: IntArray
    pair_row: IntArray
    velocity_row: IntArray
    acceleration_row: IntArray
    velocity_cross: IntArray
    product_x: IntArray
    product_w: IntArray
    entry_product: IntArray
    entry_sign: FloatArray
    entry_table: IntArray
    n_split_entries: int
    joint_table: IntArray
    group_start: IntArray
    group_flat: IntArray
    joint_start: IntArray
    param_joint_start: IntArray

    @classmethod
    def from_model(cls, model: pin.Model) -> BoundPlan:
        """Read the kinematic tree of ``model`` and lay out the computation."""
        parents, revolute, axes, rotations, translations, gravity = _read_joints(model)
        layout = _Layout(parents)
        fields = layout.fields()
        fields["joint_table"] = np.column_stack(
            [parents, revolute, layout.n_ancestors, layout.velocity_row, layout.acceleration_row]
        ).astype(np.intp)
        return cls(
            len(parents), parents, revolute, axes, rotations, translations, gravity, **fields
        )

    @property
    def entry_body(self) -> IntArray:
        """Link of each entry."""
        return self.entry_table[:, 0]

    @property
    def entry_term(self) -> IntArray:
        """Term k of Q of each split entry."""
        return self.entry_table[: self.n_split_entries, 2]


@dataclass(frozen=True)
class BoundWeights:
    """Weights of one call: Θ̂ and B_Θ̃ per link and parameter, B_Q̃ per term.

    ``theta`` and ``btheta`` have shape (n_dof, 11), zero outside the base
    columns; ``bq`` shape (l,).
    """

    theta: FloatArray
    btheta: FloatArray
    bq: FloatArray

    @classmethod
    def from_base(
        cls, n_dof: int, columns: IntArray, theta: FloatArray, btheta: FloatArray, bq: FloatArray
    ) -> BoundWeights:
        """Spread base-parameter values over the standard columns ``columns``."""
        full_theta = np.zeros(n_dof * N_LINK_PARAMETERS)
        full_btheta = np.zeros(n_dof * N_LINK_PARAMETERS)
        full_theta[columns] = theta
        full_btheta[columns] = btheta
        shape = (n_dof, N_LINK_PARAMETERS)
        return cls(full_theta.reshape(shape), full_btheta.reshape(shape), np.asarray(bq))


def plan_for(robot: RobotModel) -> BoundPlan:
    """The :class:`BoundPlan` of ``robot``, built once per (immutable) model."""
    plan = _PLANS.get(robot)
    if plan is None:
        plan = _PLANS[robot] = BoundPlan.from_model(robot.pinocchio_model)
    return plan


# ---------------------------------------------------------------------------- layout


class _Layout:
    """Builds the index arrays of a :class:`BoundPlan` for a tree with these ``parents``."""

    def __init__(self, parents: IntArray) -> None:
        n = self.n = len(parents)
        self.length = q_length(n)
        self.chains: list[list[int]] = []
        for b in range(n):
            chain = [b]
            while parents[chain[-1]] >= 0:
                chain.append(int(parents[chain[-1]]))
            self.chains.append(chain[::-1])
        self.n_ancestors = np.array([len(chain) for chain in self.chains], dtype=np.intp)
        self.ancestors = np.zeros((n, n), dtype=np.intp)
        for b, chain in enumerate(self.chains):
            self.ancestors[b, : len(chain)] = chain
        self.rows = 1  # row 0: the zero vector
        self.jacobian = np.zeros((n, n), dtype=np.intp)
        for b, chain in enumerate(self.chains):
            self.jacobian[b, chain] = self._take(len(chain))
        self.gravity_row = self._take(n)
        self.pair_row = np.zeros((n, n, n), dtype=np.intp)
        crosses = []
        for b, chain in enumerate(self.chains):
            for index, k in enumerate(chain):
                for j in chain[index + 1 :]:
                    self.pair_row[b, k, j] = self._take(1)[0]
                    crosses.append(
                        (self.pair_row[b, k, j], self.jacobian[b, k], self.jacobian[b, j])
                    )
        self.cross_rows = np.array(crosses, dtype=np.intp).reshape(-1, 3)
        self.velocity_row, self.acceleration_row = self._take(n), self._take(n)
        self.velocity_cross_row = np.zeros((n, n), dtype=np.intp)
        velocity_cross = []
        for b, chain in enumerate(self.chains):
            for i in chain:
                self.velocity_cross_row[b, i] = self._take(1)[0]
                velocity_cross.append(
                    (self.velocity_cross_row[b, i], self.jacobian[b, i], self.velocity_row[b])
                )
        self.velocity_cross = np.array(velocity_cross, dtype=np.intp)
        self.products: dict[tuple[int, int], int] = {}

    def _take(self, count: int) -> IntArray:
        """The next ``count`` rows of the vector table."""
        rows = np.arange(self.rows, self.rows + count, dtype=np.intp)
        self.rows += count
        return rows

    def product(self, x: int, w: int) -> int:
        """Index of the product Φ(row x, row w) = Φ(row w, row x), added on first use."""
        return self.products.setdefault((min(x, w), max(x, w)), len(self.products))

    def triple(self, b: int, i: int, k: int, j: int) -> tuple[int, float]:
        """(product, sign) of T(i, k, j) = Φ(J_i ×m J_k, J_j) on link b; sign 0 if i = k."""
        if i == k:
            return 0, 0.0
        pair = self.pair_row[b, min(i, k), max(i, k)]
        return self.product(pair, self.jacobian[b, j]), 1.0 if i < k else -1.0

    def split_terms(self, b: int, i: int) -> list[tuple[int, list[tuple[int, float]]]]:
        """(term k, signed products) of the entries of Y_k^q at joint i from link b."""
        n, chain, row = self.n, self.chains[b], self.jacobian[b]
        terms = [(k, [(self.product(row[i], row[k]), 1.0)]) for k in chain]
        for index, k in enumerate(chain):
            for j in chain[index + 1 :]:
                # Y_{B_kj} = T(k, j, i) + T(i, k, j) + T(i, j, k), at q̇_k q̇_j in Q
                pair = n + k * n - k * (k + 1) // 2 + (j - k - 1)
                parts = [self.triple(b, k, j, i), self.triple(b, i, k, j), self.triple(b, i, j, k)]
                terms.append((pair, [part for part in parts if part[1] != 0.0]))
        squares = self.length - 1 - n
        terms.extend((squares + k, [self.triple(b, i, k, k)]) for k in chain if k != i)
        terms.append((self.length - 1, [(self.product(row[i], self.gravity_row[b]), 1.0)]))
        return terms

    def fields(self) -> dict[str, Any]:
        """The index arrays of :class:`BoundPlan` (all but the joint table)."""
        Entry = tuple[int, int, int, list[tuple[int, float]]]  # joint, term, link, products
        split: list[Entry] = []
        param: list[Entry] = []
        for i in range(self.n):
            for b, chain in enumerate(self.chains):
                if i in chain:
                    split.extend((i, term, b, parts) for term, parts in self.split_terms(b, i))
        split.sort(key=lambda entry: (entry[0], entry[1]))
        for i in range(self.n):
            for b, chain in enumerate(self.chains):
                if i in chain:
                    # Y_{i,b} = Φ(J_i, a_b) + Φ(J_i ×m v_b, v_b), with this sample's v_b, a_b.
                    first = self.product(self.jacobian[b, i], self.acceleration_row[b])
                    second = self.product(self.velocity_cross_row[b, i], self.velocity_row[b])
                    param.append((i, -1, b, [(first, 1.0), (second, 1.0)]))
        entries = split + param
        products = np.zeros((len(entries), 3), dtype=np.intp)
        signs = np.zeros((len(entries), 3))
        for e, (_, _, _, parts) in enumerate(entries):
            for slot, (index, sign) in enumerate(parts):
                products[e, slot], signs[e, slot] = index, sign
        table = np.array([entry[:3] for entry in entries], dtype=np.intp)[:, [2, 0, 1]]
        joint, term = table[:, 1], table[: len(split), 2]
        flat = joint[: len(split)] * self.length + term
        group_start = np.flatnonzero(np.r_[True, np.diff(flat) != 0])
        pairs = np.array(list(self.products), dtype=np.intp)
        return {
            "n_vectors": self.rows,
            "jacobian": self.jacobian,
            "gravity_row": self.gravity_row,
            "ancestors": self.ancestors,
            "n_ancestors": self.n_ancestors,
            "cross_rows": self.cross_rows,
            "pair_row": self.pair_row,
            "velocity_row": self.velocity_row,
            "acceleration_row": self.acceleration_row,
            "velocity_cross": self.velocity_cross,
            "product_x": pairs[:, 0].copy(),
            "product_w": pairs[:, 1].copy(),
            "entry_product": products,
            "entry_sign": signs,
            "entry_table": table,
            "n_split_entries": len(split),
            "group_start": group_start,
            "group_flat": flat[group_start],
            "joint_start": np.searchsorted(joint[: len(split)], np.arange(self.n)),
            "param_joint_start": np.searchsorted(joint[len(split) :], np.arange(self.n)),
        }


def _read_joints(
    model: pin.Model,
) -> tuple[IntArray, NDArray[np.bool_], FloatArray, FloatArray, FloatArray, FloatArray]:
    """Parents, kinds, unit axes, placements and gravity of a tree of one-DoF joints."""
    spin = np.asarray(model.gravity.angular, dtype=float)
    if np.any(spin != 0.0):
        raise ModelError(f"model.gravity must be a pure linear field; angular part {spin}")
    n = model.njoints - 1
    parents = np.array([int(model.parents[j]) - 1 for j in range(1, n + 1)], dtype=np.intp)
    revolute = np.zeros(n, dtype=bool)
    axes = np.zeros((n, 3))
    rotations = np.zeros((n, 3, 3))
    translations = np.zeros((n, 3))
    for k in range(n):
        joint = model.joints[k + 1]
        subspace = np.zeros(6)
        if joint.nv == 1:
            joint_data = joint.createData()
            joint.calc(joint_data, np.zeros(model.nq))
            subspace = np.asarray(joint_data.S, dtype=float).ravel()
        linear, angular = float(np.linalg.norm(subspace[:3])), float(np.linalg.norm(subspace[3:]))
        if joint.nv != 1 or (linear > 0) == (angular > 0):
            raise ModelError(
                f"joint {model.names[k + 1]!r} is a {joint.shortname()}; the bound terms "
                "handle one-DoF revolute or prismatic joints"
            )
        revolute[k] = angular > 0
        axes[k] = subspace[3:] / angular if angular > 0 else subspace[:3] / linear
        placement = model.jointPlacements[k + 1]
        rotations[k] = placement.rotation
        translations[k] = placement.translation
    gravity = np.array(model.gravity.linear, dtype=float)
    return parents, revolute, axes, rotations, translations, gravity
