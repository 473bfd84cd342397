"""The end link's regressor, filtered as the momentum observer filters: r̂ ≈ Ψ π_L.

A payload the nominal model lacks changes the true inertial parameters of
the end link by π_L (10 standard parameters about the end-link origin, the
order of :data:`sensorless.robots.PARAMETER_NAMES` without ``Ia``). The
momentum observer (:class:`~sensorless.observers.MomentumObserver`) computes
r̂ = h − K_I/(s+K_I)·τ + K_I/(s+K_I)·τ̂_fr from the nominal model; the true
torque holds the payload's part, so in free motion

    r̂ = −K_I/(s+K_I)·Y_L(q, q̇, q̈) π_L = Ψ π_L,

with Y_L the ten columns of the end link in the joint-torque regressor. The
observer never forms q̈: it takes the momentum p = M q̇ by its increment and
w = Cᵀq̇ − g by the trapezoid rule. Ψ is built the same way, from the
columns P and W of p and w (each linear in π_L), with the same discretisation:

    u_k = −[(P_k − P_k−1)/dt − (W_k−1 + W_k)/2],    Ψ_k = a Ψ_k−1 + (1 − a) u_k,

a = exp(−K_I dt) per joint. So Ψ needs only (q, q̂̇), the inputs of the
observer, and r̂ − Ψ π_L holds no discretisation error of the payload's part.

P and W of one sample come from :class:`~sensorless.robots.recursion.MomentumTerms`
on ten copies of the nominal model with every link massless except the end
link, which is a 1-kg point mass at one of ten points that span the ten
parameters (0, ±e_x, ±e_y, ±e_z, e_x+e_y, e_x+e_z, e_y+e_z, in metres): the
terms are linear in the end link's parameters, so the columns are the ten
outputs times the inverse of the points' parameter matrix.

Two starts: the observer's own (``held=False``: its first sample has r̂ = 0,
so Ψ_0 = 0, exact for :func:`~sensorless.observers.observe` and
``MomentumObserver.run`` from their default state) and the held start of the
threshold filters (``held=True``: the first sample's input held since
forever, Ψ_0 = W_0).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import pinocchio as pin
from scipy import signal

from .._validation import FloatArray, check_type
from ..robots.inertia import parameters_from_inertia
from ..robots.model import RobotModel
from ..robots.recursion import MomentumTerms

__all__ = [
    "N_PAYLOAD_PARAMETERS",
    "PAYLOAD_PARAMETER_NAMES",
    "PayloadRegressor",
    "RegressorState",
    "filter_coefficients",
]

#: Standard parameters of a payload about the end-link origin (``PARAMETER_NAMES`` without Ia).
PAYLOAD_PARAMETER_NAMES = ("XX", "XY", "XZ", "YY", "YZ", "ZZ", "mX", "mY", "mZ", "m")
N_PAYLOAD_PARAMETERS = len(PAYLOAD_PARAMETER_NAMES)
MASS, FIRST_MOMENTS = 9, slice(6, 9)

_BASIS_POINTS = np.array(
    [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [-1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [0.0, -1.0, 0.0],
        [0.0, 0.0, 1.0],
        [0.0, 0.0, -1.0],
        [1.0, 1.0, 0.0],
        [1.0, 0.0, 1.0],
        [0.0, 1.0, 1.0],
    ]
)


def filter_coefficients(gain: FloatArray, dt: float) -> tuple[FloatArray, FloatArray]:
    """Pole a = exp(−K_I dt) and weight 1 − a of K_I/(s+K_I), as the observer computes them."""
    return np.exp(-gain * dt), -np.expm1(-gain * dt)


@dataclass(frozen=True, eq=False)
class RegressorState:
    """State of the filtered regressor after a sample; immutable.

    Attributes
    ----------
    momentum : ndarray of shape (n_dof, 10)
        Columns P of p = M q̇ at the last sample [N m s per unit parameter].
    coriolis_gravity : ndarray of shape (n_dof, 10)
        Columns W of Cᵀq̇ − g at the last sample.
    filtered : ndarray of shape (n_dof, 10)
        Ψ at the last sample.
    fresh : bool
        True before the first sample of an observer's start: that sample's
        input is zero, as the observer's first residual.
    """

    momentum: FloatArray
    coriolis_gravity: FloatArray
    filtered: FloatArray
    fresh: bool = False


class PayloadRegressor:
    """Columns Ψ of the payload's part of the momentum residual, r̂ ≈ Ψ π_L (module docstring).

    Parameters
    ----------
    robot : RobotModel
        The nominal model the observer uses; the payload is on its last link.
    backend : {"auto", "numba", "numpy"}
        Backend of :class:`~sensorless.robots.recursion.MomentumTerms`.
    """

    def __init__(self, robot: RobotModel, *, backend: str = "auto") -> None:
        check_type(robot, RobotModel, "robot", " (the nominal model the observer uses)")
        self.robot = robot
        self.n_dof = robot.n_dof
        empty = robot.pinocchio_model.copy()
        for j in range(1, self.n_dof + 1):
            empty.inertias[j] = pin.Inertia.Zero()
        empty.armature = np.zeros(self.n_dof)
        self._terms = []
        basis = np.empty((N_PAYLOAD_PARAMETERS, len(_BASIS_POINTS)))
        for k, point in enumerate(_BASIS_POINTS):
            model = empty.copy()
            model.inertias[self.n_dof] = pin.Inertia(1.0, point, np.zeros((3, 3)))
            basis[:, k] = parameters_from_inertia(model.inertias[self.n_dof])
            self._terms.append(MomentumTerms(model, backend=backend))
        # outputs = columns @ basis, so columns = outputs @ basis⁻¹
        self._to_columns = np.linalg.inv(basis)
        self._data = robot.pinocchio_model.createData()

    def columns(self, q: FloatArray, qd: FloatArray) -> tuple[FloatArray, FloatArray]:
        """P and W of checked arrays of shape (n_samples, n_dof), each (n_samples, n_dof, 10).

        ``P π_L`` is the payload's generalized momentum [N m s] and ``W π_L`` its
        Cᵀq̇ − g [N m], for positions ``q`` [rad] and velocities ``qd`` [rad/s].
        """
        outputs = np.stack([terms.terms_checked(q, qd) for terms in self._terms], axis=-1)
        momentum = outputs[0] @ self._to_columns
        coriolis_gravity = (outputs[1] - outputs[2]) @ self._to_columns
        return momentum, coriolis_gravity

    def mass_columns(self, q: FloatArray) -> FloatArray:
        """Columns of the payload's mass matrix M_L(q), shape (n_samples, n_dof, n_dof, 10).

        ``out[k, j, i] @ π_L`` is M_L(q_k)[j, i] [kg m²] for checked positions
        (n_samples, n_dof). With (v_i, ω_i) the end link's Jacobian column of
        joint i in its own frame, M_L[j, i] = J_jᵀ I(π_L) J_i =
        m v_j·v_i + (mX, mY, mZ)·(v_i × ω_j + v_j × ω_i) + ω_jᵀ Ī ω_i.
        """
        model = self.robot.pinocchio_model
        jacobians = np.empty((q.shape[0], 6, self.n_dof))
        for k, sample in enumerate(q):
            jacobians[k] = pin.computeJointJacobian(model, self._data, sample, self.n_dof)
        v, w = jacobians[:, :3], jacobians[:, 3:]
        out = np.empty((q.shape[0], self.n_dof, self.n_dof, N_PAYLOAD_PARAMETERS))
        for column, (a, b) in enumerate(((0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2))):
            both = np.einsum("kj,ki->kji", w[:, a], w[:, b])
            out[..., column] = both if a == b else both + np.einsum("kj,ki->kji", w[:, b], w[:, a])
        cross = np.cross(v[:, :, None, :], w[:, :, :, None], axis=1)  # v_i × ω_j at [k, :, j, i]
        out[..., FIRST_MOMENTS] = np.moveaxis(cross + np.swapaxes(cross, 2, 3), 1, -1)
        out[..., MASS] = np.einsum("kaj,kai->kji", v, v)
        return out

    def initial_state(self, q0: FloatArray, qd0: FloatArray, *, held: bool) -> RegressorState:
        """State before the first sample of checked (1, n_dof) arrays (module docstring)."""
        momentum, coriolis_gravity = (x[0] for x in self.columns(q0, qd0))
        filtered = coriolis_gravity.copy() if held else np.zeros_like(coriolis_gravity)
        return RegressorState(momentum, coriolis_gravity, filtered, fresh=not held)

    def filter(
        self,
        state: RegressorState,
        q: FloatArray,
        qd: FloatArray,
        gain: FloatArray,
        dt: float,
    ) -> tuple[FloatArray, RegressorState]:
        """Ψ over checked samples (n_samples, n_dof) and the state after them.

        ``gain`` is the observer gain K_I per joint [1/s], shape (n_dof,);
        ``dt`` [s] the sample period. Chunks give the values of the whole run.
        """
        momentum, coriolis_gravity = self.columns(q, qd)
        previous_p = np.concatenate([state.momentum[None], momentum[:-1]])
        previous_w = np.concatenate([state.coriolis_gravity[None], coriolis_gravity[:-1]])
        inputs = 0.5 * (previous_w + coriolis_gravity) - (momentum - previous_p) / dt
        if state.fresh:
            inputs[0] = 0.0
        pole, weight = filter_coefficients(gain, dt)
        if q.shape[0] == 1:  # the stream: the arithmetic of lfilter for one sample
            out = weight[:, None] * inputs + (pole[:, None] * state.filtered)[None]
        else:
            out = np.empty_like(inputs)
            for j in range(self.n_dof):
                zi = (pole[j] * state.filtered[j])[None, :]
                out[:, j], _ = signal.lfilter(
                    [weight[j]], [1.0, -pole[j]], inputs[:, j], axis=0, zi=zi
                )
        new_state = RegressorState(momentum[-1].copy(), coriolis_gravity[-1].copy(), out[-1].copy())
        return out, new_state
