"""Joint controllers computed from the *nominal* model.

The controller sees only what a real one sees: measured joint positions, the
desired trajectory and the nominal robot model (never the true one). Its
state (integral of the error, previous measured position) is explicit.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._validation import FloatArray, check_dt
from ..exceptions import DimensionError, InputValueError
from ..friction import FrictionModel, LuGre
from ..robots.model import RobotModel

__all__ = ["ComputedTorque", "ControllerState", "JointPID"]


def friction_torque(friction: FrictionModel | LuGre, qd: FloatArray) -> FloatArray:
    """Steady-state friction of a nominal model at velocity ``qd`` [rad/s] (no checks)."""
    if isinstance(friction, LuGre):
        return friction.steady_state(qd)
    return friction.evaluate(qd)


@dataclass(frozen=True)
class ControllerState:
    """Integral of the position error [rad s] and the previous measured position [rad]."""

    integral: FloatArray
    q_previous: FloatArray


@dataclass(frozen=True, eq=False)
class JointPID:
    """Decentralised joint PID (PD when ``ki`` is 0) with model-based compensation.

    u = kp e + ki ∫e dt + kd (q̇_d − q̇̂) + ĝ(q) + τ̂_fr(q̇_d), with e = q_d − q,
    q̇̂ the backward difference of the measured position, ĝ and τ̂_fr from the
    nominal model (friction compensation at the desired velocity, so that a
    discontinuous Coulomb model does not chatter on measurement noise), and
    u clipped to ± ``torque_limit``.

    Parameters
    ----------
    kp, ki, kd : array-like of shape (n_dof,)
        Gains [N m/rad], [N m/(rad s)], [N m s/rad], >= 0.
    model : RobotModel
        Nominal model for the compensation terms.
    gravity_compensation, friction_compensation : bool
        Add ĝ(q) and the nominal friction τ̂_fr(q̇_d).
    torque_limit : array-like of shape (n_dof,), optional
        Saturation [N m]; default: the model's effort limits.
    """

    kp: FloatArray
    ki: FloatArray
    kd: FloatArray
    model: RobotModel
    gravity_compensation: bool = True
    friction_compensation: bool = True
    torque_limit: FloatArray | None = None
    _data: object = field(init=False, repr=False)

    def __post_init__(self) -> None:
        n = self.model.n_dof
        for name in ("kp", "ki", "kd"):
            value = np.asarray(getattr(self, name), dtype=float)
            if value.ndim == 0:
                value = np.full(n, float(value))
            if value.shape != (n,):
                raise DimensionError(
                    f"{name} must have {n} entries (one per joint); got {value.shape}"
                )
            if not np.isfinite(value).all() or (value < 0).any():
                raise InputValueError(f"{name} must be finite and >= 0; got {value}")
            object.__setattr__(self, name, value)
        limit = self.model.effort_limits if self.torque_limit is None else self.torque_limit
        limit = np.broadcast_to(np.asarray(limit, dtype=float), (n,)).copy()
        if np.isnan(limit).any() or (limit <= 0).any():
            raise InputValueError(f"torque_limit must be > 0 N m for every joint; got {limit}")
        object.__setattr__(self, "torque_limit", limit)
        object.__setattr__(self, "_data", self.model.pinocchio_model.createData())

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return self.model.n_dof

    def initial_state(self, q0: ArrayLike) -> ControllerState:
        """Zero integral, previous position ``q0`` [rad]."""
        q = np.asarray(q0, dtype=float).copy()
        return ControllerState(np.zeros(self.n_dof), q)

    def step(
        self,
        state: ControllerState,
        q: FloatArray,
        q_desired: FloatArray,
        qd_desired: FloatArray,
        dt: float,
        qdd_desired: FloatArray | None = None,
    ) -> tuple[FloatArray, ControllerState]:
        """Command for one period.

        Parameters
        ----------
        state : ControllerState
        q : ndarray of shape (n_dof,)
            Measured joint positions [rad].
        q_desired, qd_desired : ndarray of shape (n_dof,)
            Desired positions [rad] and velocities [rad/s].
        dt : float
            Control period [s].
        qdd_desired : ndarray of shape (n_dof,), optional
            Desired accelerations [rad/s²] (used by :class:`ComputedTorque`).

        Returns
        -------
        u : ndarray of shape (n_dof,)
            Joint torque command [N m].
        state : ControllerState
        """
        return self._step_unchecked(state, q, q_desired, qd_desired, check_dt(dt), qdd_desired)

    def _step_unchecked(
        self,
        state: ControllerState,
        q: FloatArray,
        q_desired: FloatArray,
        qd_desired: FloatArray,
        period: float,
        qdd_desired: FloatArray | None = None,
    ) -> tuple[FloatArray, ControllerState]:
        """:meth:`step` with the period already checked (the simulator's inner loop)."""
        error = q_desired - q
        integral = state.integral + error * period
        velocity = (q - state.q_previous) / period
        feedback = self.kp * error + self.ki * integral + self.kd * (qd_desired - velocity)
        u = self._feedback_torque(q, velocity, feedback, qdd_desired)
        friction = self.model.friction
        if self.friction_compensation and friction is not None:
            u = u + friction_torque(friction, qd_desired)
        limit = np.asarray(self.torque_limit)
        return np.minimum(np.maximum(u, -limit), limit), ControllerState(integral, q.copy())

    def _feedback_torque(
        self, q: FloatArray, velocity: FloatArray, feedback: FloatArray, _: FloatArray | None
    ) -> FloatArray:
        if not self.gravity_compensation:
            return feedback
        return feedback + pin.computeGeneralizedGravity(self.model.pinocchio_model, self._data, q)


@dataclass(frozen=True, eq=False)
class ComputedTorque(JointPID):
    """Computed-torque control with the nominal model (inverse-dynamics feedback).

    u = M̂(q)(q̈_d + kp e + ki ∫e dt + kd (q̇_d − q̇̂)) + Ĉ(q, q̇̂) q̇̂ + ĝ(q) + τ̂_fr(q̇_d):
    the nominal inertia decouples the joints, so the gains are per-joint
    bandwidths (kp = ω² [1/s²], kd = 2ζω [1/s], ki [1/s³]) that stay stable at
    1 kHz even where a decentralised PD with the same bandwidth is not (the
    Panda's joints 1 and 3 are nearly coaxial when q₂ ≈ 0, and the light mode
    they form makes a stiff PD chatter). ``gravity_compensation`` has no
    effect: ĝ is part of the inverse dynamics.
    """

    def _feedback_torque(
        self, q: FloatArray, velocity: FloatArray, feedback: FloatArray, qdd: FloatArray | None
    ) -> FloatArray:
        model, data = self.model.pinocchio_model, self._data
        acceleration = feedback if qdd is None else qdd + feedback
        return np.asarray(pin.rnea(model, data, q, velocity, acceleration))
