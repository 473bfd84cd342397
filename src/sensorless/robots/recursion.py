"""The three vectors of a momentum observer by one O(n) recursion, without M or C.

A generalized-momentum observer (thesis eq. (4.4)) needs, per sample, only

- the generalized momentum p = M(q) q̇ [N m s],
- the vector C(q, q̇)ᵀ q̇ [N m] for any C with Ṁ = C + Cᵀ (Pinocchio's is one),
- the gravity torque g(q) [N m] (the torque that balances gravity, Pinocchio's sign),

so that ṗ = τ + Cᵀq̇ − g. :class:`MomentumTerms` computes the three in one
forward and one backward sweep over the joints, in numpy over a whole time
series or, when numba is installed, compiled (``pip install numba``).

>>> import numpy as np
>>> import sensorless as sl
>>> from sensorless.robots.recursion import MomentumTerms
>>> robot = sl.robots.load("planar2")
>>> terms = MomentumTerms.from_robot(robot, backend="numpy")
>>> q, qd = np.array([[0.3, -0.2]]), np.array([[0.5, 1.0]])
>>> p, c, g = terms.terms(q, qd)
>>> bool(np.allclose(p, robot.mass_matrix(q) @ qd[0]))
True
"""

from __future__ import annotations

from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from .._validation import FloatArray, as_joint_array, check_int
from ..exceptions import DimensionError, InputValueError, ModelError, UnknownNameError

if TYPE_CHECKING:
    from .model import RobotModel

_numba_kernels: ModuleType | None
try:
    from . import _recursion_numba as _numba_kernels
except ImportError:  # numba is an optional extra
    _numba_kernels = None

__all__ = ["BACKENDS", "MomentumTerms", "frame_with_z", "joint_axis", "numba_available"]

#: Backend names accepted by :class:`MomentumTerms`.
BACKENDS = ("auto", "numba", "numpy")

_REVOLUTE = ("JointModelRX", "JointModelRY", "JointModelRZ", "JointModelRevoluteUnaligned")
_PRISMATIC = ("JointModelPX", "JointModelPY", "JointModelPZ", "JointModelPrismaticUnaligned")


def numba_available() -> bool:
    """True when the compiled kernel can be used (numba is importable)."""
    return _numba_kernels is not None


def _skew(v: FloatArray) -> FloatArray:
    """Matrix [v]× with [v]× w = v × w."""
    return np.array([[0.0, -v[2], v[1]], [v[2], 0.0, -v[0]], [-v[1], v[0], 0.0]])


def frame_with_z(axis: FloatArray) -> FloatArray:
    """A rotation whose third column is the unit vector ``axis`` (the identity for +z).

    The kernels work in each joint's canonical frame, its placement frame turned
    by this rotation so that the joint's axis is z.
    """
    helper = np.eye(3)[int(np.argmin(np.abs(axis)))]
    first = helper - (helper @ axis) * axis
    first /= np.linalg.norm(first)
    return np.column_stack([first, np.cross(axis, first), axis])


def joint_axis(model: pin.Model, j: int) -> tuple[int, FloatArray]:
    """Kind (0 revolute, 1 prismatic) and unit axis of joint ``j``; ModelError otherwise."""
    joint = model.joints[j]
    kind_name = joint.shortname()
    if kind_name not in _REVOLUTE + _PRISMATIC:
        raise ModelError(
            f"joint {model.names[j]!r} is a {kind_name}; the momentum recursion handles "
            f"one-DoF revolute or prismatic joints: {list(_REVOLUTE + _PRISMATIC)}"
        )
    joint_data = joint.createData()
    joint.calc(joint_data, np.zeros(model.nq))
    subspace = np.asarray(joint_data.S, dtype=float).ravel()
    kind = 0 if kind_name in _REVOLUTE else 1
    axis = subspace[3:6] if kind == 0 else subspace[0:3]
    return kind, axis / np.linalg.norm(axis)


class MomentumTerms:
    """p = M(q)q̇, C(q, q̇)ᵀq̇ and g(q) of a tree of one-DoF joints, O(n) per sample.

    The geometry, inertias, armature and gravity are read once from the
    Pinocchio model into plain arrays; Pinocchio itself is called only by
    :meth:`terms_one` without numba. Not thread-safe (the one-sample path
    reuses scratch buffers): give each thread its own instance.

    Parameters
    ----------
    model : pinocchio.Model
        Fixed-base tree whose joints are revolute (``JointModelRX/RY/RZ``,
        ``JointModelRevoluteUnaligned``) or prismatic (``JointModelPX/PY/PZ``,
        ``JointModelPrismaticUnaligned``); fixed joints of a URDF are already
        merged into the links by Pinocchio's parser. ``model.armature`` [kg m²]
        (rotor inertia for prismatic joints [kg]) enters p; ``model.gravity``
        [m/s²] enters g.
    backend : {"auto", "numba", "numpy"}
        Compiled kernel or numpy. ``"auto"`` takes numba when importable.
    chunk_size : int
        Samples per block of the numpy batch path; its scratch memory is about
        320·n_dof·chunk_size bytes (9 MB at 7 dof and the default). The default
        was the fastest measured at 7 dof; from 8192 on, OpenBLAS spreads the
        small matrix products over threads for no gain.

    Notes
    -----
    Every joint k gets a canonical frame whose z axis is its joint axis, so
    that its motion subspace is S_k = (0, e_z) (revolute) or (e_z, 0)
    (prismatic), spatial vectors written (linear, angular) at the frame origin.
    With v_k the spatial velocity of link k and I_i the spatial inertia of
    link i, each in its own frame:

    - forward sweep: v_k = ᵏX_λ v_λ(k) + S_k q̇_k, and the gravity vector a_g in
      frame k;
    - backward sweep: H_k = I_k v_k + Σ_children ᵏX*_c H_c, the momentum of the
      subtree carried by joint k, and G_k = I_k (a_g, 0) + Σ_children ᵏX*_c G_c,
      its gravity wrench.

    Then p_k = S_kᵀ H_k + I_a,k q̇_k and g_k = −S_kᵀ G_k. With T the kinetic
    energy, Lagrange's equations give C q̇ = Ṁ q̇ − ∂T/∂q, hence
    Cᵀq̇ = Ṁq̇ − Cq̇ = ∂T/∂q for every C with Ṁ = C + Cᵀ. In a fixed frame,
    ∂v_i/∂q_k = S_k ×m (v_i − v_λ(k)) and ∂I_i/∂q_k = S_k ×* I_i − I_i (S_k ×m)
    for i in the subtree of k, so ∂T/∂q_k = (v_λ(k) ×m S_k)ᵀ H_k
    = (v_k ×m S_k)ᵀ H_k (as S_k ×m S_k = 0). In the canonical frame, with
    v_k = (ν, ω) and H_k = (f, n), this is e_z·(f × ν + n × ω) for a revolute
    joint and e_z·(f × ω) for a prismatic one. The armature does not depend on
    q and adds nothing to Cᵀq̇.
    """

    def __init__(self, model: pin.Model, *, backend: str = "auto", chunk_size: int = 4096) -> None:
        if backend not in BACKENDS:
            raise UnknownNameError(f"unknown backend {backend!r}; options: {list(BACKENDS)}")
        if backend == "numba" and _numba_kernels is None:
            raise InputValueError(
                "backend 'numba' needs numba (pip install numba); use 'auto' or 'numpy'"
            )
        self._kernels = _numba_kernels if backend != "numpy" else None
        self.chunk_size = check_int(chunk_size, "chunk_size", 1, "MomentumTerms")
        self._read_model(model)
        self._build_block_matrices()
        self._scratch = np.zeros((self.n_dof, 23))
        self._pinocchio = _PinocchioOneSample(model)

    @classmethod
    def from_robot(
        cls, robot: RobotModel, *, backend: str = "auto", chunk_size: int = 4096
    ) -> MomentumTerms:
        """Build from a :class:`~sensorless.robots.RobotModel` (its ``pinocchio_model``).

        ``backend`` and ``chunk_size`` are those of :class:`MomentumTerms`.
        """
        return cls(robot.pinocchio_model, backend=backend, chunk_size=chunk_size)

    # ------------------------------------------------------------------ model
    def _read_model(self, model: pin.Model) -> None:
        angular = np.asarray(model.gravity.angular, dtype=float)
        if np.any(angular != 0.0):
            raise ModelError(f"model.gravity must be a pure linear field; angular part {angular}")
        n_dof = model.njoints - 1
        if n_dof == 0:
            raise ModelError("the model has no joint; the momentum recursion needs at least one")
        gravity = np.array(model.gravity.linear, dtype=float)
        consts = np.zeros((n_dof, 28))
        frames = []
        for k in range(n_dof):
            kind, axis = joint_axis(model, k + 1)
            frames.append(frame_with_z(axis))
            parent = int(model.parents[k + 1]) - 1
            consts[k, 23:25] = parent, kind
            if parent < 0:
                consts[k, 25:28] = gravity
            parent_frame = frames[parent] if parent >= 0 else np.eye(3)
            placement = model.jointPlacements[k + 1]
            consts[k, 0:9] = (parent_frame.T @ placement.rotation @ frames[k]).ravel()
            consts[k, 9:12] = parent_frame.T @ placement.translation
            inertia = model.inertias[k + 1]
            mass = float(inertia.mass)
            com = frames[k].T @ inertia.lever
            about_com = frames[k].T @ inertia.inertia @ frames[k]
            about_origin = about_com + mass * (com @ com * np.eye(3) - np.outer(com, com))
            consts[k, 12] = mass
            consts[k, 13:16] = mass * com
            consts[k, 16:22] = about_origin[np.triu_indices(3)]
            consts[k, 22] = model.armature[model.joints[k + 1].idx_v]
        self.n_dof = n_dof
        self._consts = consts
        self._parents = [int(parent) for parent in consts[:, 23]]
        self._revolute = consts[:, 24] == 0.0

    def _build_block_matrices(self) -> None:
        """Constant matrices of the numpy path, acting on stacked per-joint vectors.

        Velocity state (9 rows): ν, ω, a_g. Wrench state (12 rows): f, n of the
        momentum, f, n of the gravity wrench.
        """
        n_dof = self.n_dof
        self._forward = np.zeros((n_dof, 9, 9))
        self._own = np.zeros((n_dof, 12, 9))
        self._upward = np.zeros((n_dof, 12, 12))
        self._root_state = np.zeros((n_dof, 9))
        for k in range(n_dof):
            rot = self._consts[k, 0:9].reshape(3, 3)
            pos = self._consts[k, 9:12]
            for b in range(3):
                self._forward[k, 3 * b : 3 * b + 3, 3 * b : 3 * b + 3] = rot.T
            self._forward[k, 0:3, 3:6] = -rot.T @ _skew(pos)
            self._root_state[k, 6:9] = rot.T @ self._consts[k, 25:28]
            mass, first = self._consts[k, 12], _skew(self._consts[k, 13:16])
            about_origin = np.zeros((3, 3))
            about_origin[np.triu_indices(3)] = self._consts[k, 16:22]
            about_origin = about_origin + np.triu(about_origin, 1).T
            self._own[k, 0:3, 0:3] = mass * np.eye(3)
            self._own[k, 0:3, 3:6] = -first
            self._own[k, 3:6, 0:3] = first
            self._own[k, 3:6, 3:6] = about_origin
            self._own[k, 6:9, 6:9] = mass * np.eye(3)
            self._own[k, 9:12, 6:9] = first
            for b in range(4):
                self._upward[k, 3 * b : 3 * b + 3, 3 * b : 3 * b + 3] = rot
            for b in (0, 6):
                self._upward[k, b + 3 : b + 6, b : b + 3] = _skew(pos) @ rot

    @property
    def kernel_constants(self) -> FloatArray:
        """Read-only constants of the compiled kernel, shape (n_dof, 28).

        The layout is that of :mod:`sensorless.robots._recursion_numba`, whose
        ``terms_at`` other compiled code can call with this array.
        """
        view = self._consts.view()
        view.flags.writeable = False
        return view

    @property
    def backend(self) -> str:
        """``"numba"`` or ``"numpy"``: the path this instance runs."""
        return "numpy" if self._kernels is None else "numba"

    # ------------------------------------------------------------------ batch
    def terms(self, q: ArrayLike, qd: ArrayLike) -> tuple[FloatArray, FloatArray, FloatArray]:
        """p = M(q)q̇, C(q, q̇)ᵀq̇ and g(q) over a time series.

        Parameters
        ----------
        q : array-like of shape (n_samples, n_dof) or (n_dof,)
            Joint positions [rad] (prismatic joints [m]), time along axis 0.
        qd : array-like of the same shape
            Joint velocities [rad/s] (prismatic joints [m/s]).

        Returns
        -------
        p : ndarray of the shape of q
            Generalized momentum M(q)q̇, armature included [N m s].
        coriolis_t_qd : ndarray of the shape of q
            C(q, q̇)ᵀq̇ [N m].
        gravity : ndarray of the shape of q
            Gravity torque g(q) [N m], the torque that balances gravity.
        """
        qs, single = as_joint_array(q, self.n_dof, "q")
        qds, _ = as_joint_array(qd, self.n_dof, "qd")
        if qds.shape != qs.shape:
            raise DimensionError(
                f"q and qd must have the same shape; got {qs.shape} and {qds.shape}"
            )
        p, coriolis_t_qd, gravity = self.terms_checked(qs, qds)
        if single:
            return p[0], coriolis_t_qd[0], gravity[0]
        return p, coriolis_t_qd, gravity

    def terms_checked(self, qs: FloatArray, qds: FloatArray) -> FloatArray:
        """:meth:`terms` for trusted arrays of shape (n_samples, n_dof): rows p, Cᵀq̇, g.

        ``qs`` and ``qds`` are finite float64 arrays of one shape (the caller
        checked them); returns an array of shape (3, n_samples, n_dof).
        """
        outputs = np.empty((3, *qs.shape))
        if self._kernels is not None:
            self._kernels.terms_batch(
                np.ascontiguousarray(qs), np.ascontiguousarray(qds), self._consts, outputs
            )
        else:
            for start in range(0, qs.shape[0], self.chunk_size):
                stop = start + self.chunk_size
                block = self._chunk_numpy(
                    np.ascontiguousarray(qs[start:stop].T), np.ascontiguousarray(qds[start:stop].T)
                )
                outputs[:, start:stop] = block.transpose(0, 2, 1)
        return outputs

    def _chunk_numpy(self, q: FloatArray, qd: FloatArray) -> FloatArray:
        """The recursion on arrays of shape (n_dof, n) (joints along axis 0): (3, n_dof, n)."""
        cos, sin = np.cos(q), np.sin(q)
        vel = self._forward_numpy(q, qd, cos, sin)
        n_dof, n = q.shape
        wrench = np.zeros((n_dof, 12, n))
        out = np.empty((3, n_dof, n))
        for k in range(n_dof - 1, -1, -1):
            v, w = vel[k], wrench[k]
            w += self._own[k] @ v
            if self._revolute[k]:
                out[0, k] = w[5]
                out[1, k] = w[0] * v[1] - w[1] * v[0] + w[3] * v[4] - w[4] * v[3]
                out[2, k] = -w[11]
            else:
                out[0, k] = w[2]
                out[1, k] = w[0] * v[4] - w[1] * v[3]
                out[2, k] = -w[8]
            parent = self._parents[k]
            if parent < 0:
                continue
            if self._revolute[k]:
                _rotate_rows(w, cos[k], sin[k])
            else:
                for b in (0, 6):
                    w[b + 3] -= q[k] * w[b + 1]
                    w[b + 4] += q[k] * w[b]
            wrench[parent] += self._upward[k] @ w
        out[0] += self._consts[:, 22:23] * qd
        return out

    def _forward_numpy(
        self, q: FloatArray, qd: FloatArray, cos: FloatArray, sin: FloatArray
    ) -> FloatArray:
        """Velocity ν, ω and gravity vector of every link in its frame: (n_dof, 9, n)."""
        vel = np.empty((q.shape[0], 9, q.shape[1]))
        for k, parent in enumerate(self._parents):
            if parent < 0:
                vel[k] = self._root_state[k][:, None]
            else:
                np.matmul(self._forward[k], vel[parent], out=vel[k])
            v = vel[k]
            if self._revolute[k]:
                _rotate_rows(v, cos[k], -sin[k])
                v[5] += qd[k]
            else:
                v[0] += q[k] * v[4]
                v[1] -= q[k] * v[3]
                v[2] += qd[k]
        return vel

    # ------------------------------------------------------------------ one sample
    def terms_one(self, q: FloatArray, qd: FloatArray, out: FloatArray | None = None) -> FloatArray:
        """p, Cᵀq̇ and g of one sample, for streaming (no input checks).

        Parameters
        ----------
        q, qd : ndarray of shape (n_dof,)
            Joint positions [rad] and velocities [rad/s]; trusted to be float64,
            C-contiguous and finite.
        out : ndarray of shape (3, n_dof), optional
            Where to write the result (float64, C-contiguous).

        Returns
        -------
        ndarray of shape (3, n_dof)
            Rows p [N m s], Cᵀq̇ [N m] and g [N m]: ``p, c, g = terms.terms_one(q, qd)``.

        Notes
        -----
        Without numba, one sample is cheaper through Pinocchio's compiled
        algorithms than through a recursion of small numpy operations: p is
        ``rnea(q, 0, q̇)`` without gravity, Cᵀq̇ uses ``computeCoriolisMatrix``
        and g ``computeGeneralizedGravity``.
        """
        if out is None:
            out = np.empty((3, self.n_dof))
        if self._kernels is None:
            return self._pinocchio(q, qd, out)
        self._kernels.terms_one(q, qd, self._consts, self._scratch, out)
        return out


class _PinocchioOneSample:
    """p, Cᵀq̇ and g of one sample through Pinocchio (the path without numba)."""

    def __init__(self, model: pin.Model) -> None:
        self.model = model.copy()
        self.data = self.model.createData()
        self.weightless = model.copy()
        self.weightless.gravity = pin.Motion.Zero()
        self.weightless_data = self.weightless.createData()
        self.zero = np.zeros(model.nv)

    def __call__(self, q: FloatArray, qd: FloatArray, out: FloatArray) -> FloatArray:
        # Without gravity, rnea(q, 0, q̇) = M(q) q̇, armature included.
        out[0] = pin.rnea(self.weightless, self.weightless_data, q, self.zero, qd)
        out[1] = qd @ pin.computeCoriolisMatrix(self.model, self.data, q, qd)
        out[2] = pin.computeGeneralizedGravity(self.model, self.data, q)
        return out


def _rotate_rows(rows: NDArray[np.float64], cos: FloatArray, sin: FloatArray) -> None:
    """Rotate, in place, every 3-vector stacked in ``rows`` about z by the angle (cos, sin)."""
    stacked = rows.reshape(-1, 3, rows.shape[-1])
    x, y = stacked[:, 0], stacked[:, 1]
    x_sin = x * sin
    x *= cos
    x -= y * sin
    y *= cos
    y += x_sin
