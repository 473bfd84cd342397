"""Forward dynamics q̈ and the joint-space inertia M(q), compiled with numba when installed.

:class:`ForwardDynamics` reads the model's constants once, as
:class:`~sensorless.robots.recursion.MomentumTerms` does, and runs the
articulated-body, composite-rigid-body and recursive Newton-Euler algorithms
of :mod:`sensorless.robots._dynamics_numba` on them; without numba (or with
``backend="numpy"``) it calls Pinocchio's ``aba``, ``crba`` and ``rnea``, the reference.

>>> import numpy as np
>>> import sensorless as sl
>>> from sensorless.robots.forward_dynamics import ForwardDynamics
>>> robot = sl.robots.load("planar2")
>>> dynamics = ForwardDynamics.from_robot(robot)
>>> q, qd, tau = np.array([0.3, -0.2]), np.array([0.5, 1.0]), np.array([1.0, 0.5])
>>> qdd = dynamics.acceleration(q, qd, tau)
>>> bool(np.allclose(robot.mass_matrix(q) @ qdd, tau - robot.nonlinear_effects(q, qd)))
True
"""

from __future__ import annotations

from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_joint_array
from ..exceptions import DimensionError, InputValueError, UnknownNameError
from .recursion import BACKENDS, MomentumTerms

if TYPE_CHECKING:
    from .model import RobotModel

_kernels: ModuleType | None
try:
    from . import _dynamics_numba as _kernels
except ImportError:  # numba is an optional extra
    _kernels = None

__all__ = ["ForwardDynamics"]


class ForwardDynamics:
    """q̈ = M(q)⁻¹(τ − C(q, q̇)q̇ − g(q)) and M(q) of a tree of one-DoF joints.

    Parameters
    ----------
    model : pinocchio.Model
        Fixed-base tree of revolute or prismatic joints (those
        :class:`~sensorless.robots.recursion.MomentumTerms` accepts);
        ``model.armature`` [kg m²] enters M, ``model.gravity`` [m/s²] the bias.
    backend : {"auto", "numba", "numpy"}
        Compiled kernels or Pinocchio. ``"auto"`` takes numba when importable.

    Notes
    -----
    Not thread-safe (scratch buffers are reused): give each thread its own instance.
    """

    def __init__(self, model: pin.Model, *, backend: str = "auto") -> None:
        if backend not in BACKENDS:
            raise UnknownNameError(f"unknown backend {backend!r}; options: {list(BACKENDS)}")
        if backend == "numba" and _kernels is None:
            raise InputValueError(
                "backend 'numba' needs numba (pip install numba); use 'auto' or 'numpy'"
            )
        self._kernels = _kernels if backend != "numpy" else None
        self._model = model.copy()
        self._data = self._model.createData()
        # The recursion's reader checks the joint kinds and lays out the constants.
        terms = MomentumTerms(model, backend="numpy")
        self.n_dof = terms.n_dof
        self._consts = np.ascontiguousarray(terms.kernel_constants)
        self._scratch = None if self._kernels is None else self._kernels.scratch(self.n_dof)

    @classmethod
    def from_robot(cls, robot: RobotModel, *, backend: str = "auto") -> ForwardDynamics:
        """Build from a :class:`~sensorless.robots.RobotModel` (its ``pinocchio_model``)."""
        return cls(robot.pinocchio_model, backend=backend)

    @property
    def backend(self) -> str:
        """``"numba"`` or ``"numpy"``: the path this instance runs."""
        return "numpy" if self._kernels is None else "numba"

    @property
    def kernel_constants(self) -> FloatArray:
        """Read-only constants of the compiled kernels, shape (n_dof, 28) (the recursion's)."""
        view = self._consts.view()
        view.flags.writeable = False
        return view

    def _sample(self, value: ArrayLike, name: str) -> FloatArray:
        arr, single = as_joint_array(value, self.n_dof, name)
        if not single:
            raise DimensionError(
                f"{name} must be one sample of shape ({self.n_dof},); got shape {np.shape(value)}"
            )
        return np.ascontiguousarray(arr[0])

    def acceleration(self, q: ArrayLike, qd: ArrayLike, tau: ArrayLike) -> FloatArray:
        """Joint accelerations q̈ [rad/s²] at one state.

        Parameters
        ----------
        q, qd : array-like of shape (n_dof,)
            Joint positions [rad] and velocities [rad/s].
        tau : array-like of shape (n_dof,)
            Joint torques [N m].

        Returns
        -------
        ndarray of shape (n_dof,)
        """
        qs, qds, taus = (self._sample(v, name) for v, name in ((q, "q"), (qd, "qd"), (tau, "tau")))
        if self._kernels is None or self._scratch is None:
            return np.asarray(pin.aba(self._model, self._data, qs, qds, taus)).copy()
        out = np.empty(self.n_dof)
        self._kernels.aba(qs, qds, taus, self._consts, *self._scratch, out)
        return out

    def inverse_dynamics(self, q: ArrayLike, qd: ArrayLike, qdd: ArrayLike) -> FloatArray:
        """Joint torques τ = M(q)q̈ + C(q, q̇)q̇ + g(q) [N m] at one state (Newton-Euler).

        Parameters
        ----------
        q, qd, qdd : array-like of shape (n_dof,)
            Joint positions [rad], velocities [rad/s] and accelerations [rad/s²].

        Returns
        -------
        ndarray of shape (n_dof,)
        """
        qs, qds, qdds = (self._sample(v, name) for v, name in ((q, "q"), (qd, "qd"), (qdd, "qdd")))
        if self._kernels is None or self._scratch is None:
            return np.asarray(pin.rnea(self._model, self._data, qs, qds, qdds)).copy()
        out = np.empty(self.n_dof)
        self._kernels.rnea(qs, qds, qdds, self._consts, *self._scratch, out)
        return out

    def mass_matrix(self, q: ArrayLike) -> FloatArray:
        """Joint-space inertia M(q) [kg m²], armature included, shape (n_dof, n_dof).

        Parameters
        ----------
        q : array-like of shape (n_dof,)
            Joint positions [rad].
        """
        qs = self._sample(q, "q")
        if self._kernels is None or self._scratch is None:
            mass = np.asarray(pin.crba(self._model, self._data, qs))
            return np.triu(mass) + np.triu(mass, 1).T
        out = np.empty((self.n_dof, self.n_dof))
        self._kernels.crba(qs, self._consts, self._scratch[0], self._scratch[1], out)
        return out
