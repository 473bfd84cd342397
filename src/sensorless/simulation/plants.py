"""Simulated arms: rigid joints (eq. 5.1) and flexible joints (eq. 2.1 with the loop of eq. 2.2).

A plant holds constants only (the *true* robot, its friction, joint
elasticity); its state lives in a :class:`PlantState` passed in and returned.
:meth:`advance` integrates one control period with the command and the
external torque held constant (zero-order hold), using fixed-step
substeps: classical RK4 for rigid joints; for flexible joints a linearly
implicit step that treats the joint springs and the torque loop implicitly
(:mod:`sensorless.simulation._stiff`), or RK4 as the reference
(``integrator="rk4"``). Stiff friction (LuGre) is split off: its bristle
state is advanced with the exact solution of its own equation after each
substep, and held during the stages, where the friction is evaluated once
per stage. Friction that drifts with time
(:class:`~sensorless.friction.drift.DriftingFriction`) is evaluated at the
state's time ``t``, held over the period (it changes over minutes). Units SI,
radians; joint vectors have shape (n_dof,).

These ``advance`` methods are the reference; the same periods compiled with
numba are :class:`sensorless.simulation.compiled.CompiledPlant`, which the
simulator uses when it can (``simulate(..., backend="numpy")`` keeps these).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from functools import partial
from typing import Any

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike

from .._validation import FloatArray, check_dt
from ..exceptions import DimensionError, InputValueError, ModelError
from ..friction import FrictionModel, LuGre
from ..friction.drift import DriftingFriction
from ..robots.model import RobotModel
from ._stiff import SpringLoop

__all__ = [
    "FlexiblePlant",
    "Friction",
    "PlantState",
    "RigidPlant",
    "TorqueFeedback",
    "friction_torque",
]

Friction = FrictionModel | LuGre | DriftingFriction | None
_ROBOT_FRICTION: Any = "robot"
_INTEGRATORS = ("rosenbrock", "rk4")


@dataclass(frozen=True)
class PlantState:
    """State of a simulated arm at one instant.

    Attributes
    ----------
    q, qd : ndarray of shape (n_dof,)
        Link positions [rad] and velocities [rad/s].
    z : ndarray of shape (n_dof,) or None
        Bristle deflection of a LuGre joint (link-side) friction [rad].
    theta, thetad : ndarray of shape (n_dof,) or None
        Motor positions and velocities on the joint side [rad], [rad/s]
        (flexible joints only).
    z_motor : ndarray of shape (n_dof,) or None
        Bristle deflection of a LuGre motor-side friction [rad].
    t : float
        Time since the start of the run [s] (the clock of drifting friction).
    """

    q: FloatArray
    qd: FloatArray
    z: FloatArray | None = None
    theta: FloatArray | None = None
    thetad: FloatArray | None = None
    z_motor: FloatArray | None = None
    t: float = 0.0


def friction_torque(
    friction: Friction, qd: FloatArray, z: FloatArray | None, t: float = 0.0
) -> FloatArray:
    """Friction torque [N m] of a friction model at velocity ``qd``, time ``t`` [s]; no checks."""
    if friction is None:
        return np.zeros_like(qd)
    if isinstance(friction, DriftingFriction):
        return friction.evaluate_at(t, qd)
    if isinstance(friction, LuGre):
        assert z is not None  # state invariant: LuGre plants always carry z
        return friction.output(qd, z)
    return friction.evaluate(qd)


def _held_friction(
    friction: Friction, z: FloatArray | None, t: float
) -> Callable[[FloatArray], FloatArray] | None:
    """Friction torque [N m] as a function of velocity [rad/s], bristles and time held."""
    if friction is None:
        return None
    if isinstance(friction, DriftingFriction):
        return friction.at(t).evaluate
    if isinstance(friction, LuGre):
        assert z is not None  # state invariant: LuGre plants always carry z
        return friction.held(z)
    return friction.evaluate


def _advance_bristles(
    friction: Friction, z: FloatArray | None, qd_mid: FloatArray, h: float
) -> FloatArray | None:
    if isinstance(friction, LuGre):
        assert z is not None
        return friction.advance_state(qd_mid, h, z)
    return z


def _check_friction(friction: Friction, n_dof: int, label: str) -> None:
    if friction is not None and friction.n_dof != n_dof:
        raise DimensionError(f"{label} friction has {friction.n_dof} joints; the robot has {n_dof}")


def _joint_vector(value: ArrayLike, n_dof: int, name: str, *, positive: bool = False) -> FloatArray:
    arr = np.broadcast_to(np.asarray(value, dtype=float), (n_dof,)).copy()
    if not np.isfinite(arr).all() or (positive and (arr <= 0).any()) or (arr < 0).any():
        need = "> 0" if positive else ">= 0"
        raise InputValueError(f"{name} must be finite and {need} for every joint; got {arr}")
    return arr


def _friction_rates(friction: Friction, inertia: FloatArray) -> list[float]:
    """Stiffness-like rates [1/s] of a friction model acting on joint inertias [kg m²]."""
    if friction is None:
        return [0.0]
    if isinstance(friction, DriftingFriction):
        friction = friction.base  # warm-up only lowers friction: the cold joint is the stiffest
    if isinstance(friction, LuGre):
        damping = (friction.sigma1 + friction.sigma2) / inertia
        return [float(np.max(damping)), float(np.max(np.sqrt(friction.sigma0 / inertia)))]
    probe = np.array([[0.01], [0.02]]) * np.ones((1, friction.n_dof))
    torque = friction.evaluate(probe)
    return [float(np.max(np.abs(torque[1] - torque[0]) / 0.01 / inertia))]


def _substeps_for(rates: list[float], dt: float) -> int:
    # RK4 is stable up to |λh| ≈ 2.8; keep |λh| ≤ 1 for accuracy as well.
    fastest = max(rates)
    return max(1, math.ceil(dt * fastest))


def _rk4(derivative: Any, x: FloatArray, h: float) -> FloatArray:
    k1 = derivative(x)
    k2 = derivative(x + 0.5 * h * k1)
    k3 = derivative(x + 0.5 * h * k2)
    k4 = derivative(x + h * k3)
    return np.asarray(x + (h / 6.0) * (k1 + 2.0 * k2 + 2.0 * k3 + k4))


@dataclass(frozen=True, eq=False)
class RigidPlant:
    """Rigid-joint arm, M(q) q̈ + C(q, q̇) q̇ + g(q) = τ_m + τ_c − τ_fr (eq. 5.1).

    Parameters
    ----------
    robot : RobotModel
        The *true* robot; its armature is part of M(q).
    friction : FrictionModel, LuGre or None
        The true joint friction; by default ``robot.friction``.
    """

    robot: RobotModel
    friction: Friction = _ROBOT_FRICTION
    _data: pin.Data = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if isinstance(self.friction, str):
            object.__setattr__(self, "friction", self.robot.friction)
        _check_friction(self.friction, self.robot.n_dof, "joint")
        object.__setattr__(self, "_data", self.robot.pinocchio_model.createData())

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return self.robot.n_dof

    def initial_state(self, q0: ArrayLike, qd0: ArrayLike | None = None) -> PlantState:
        """Rest state (or given velocity) at ``q0`` [rad]."""
        q, qd = _initial(q0, qd0, self.n_dof)
        z = np.zeros(self.n_dof) if isinstance(self.friction, LuGre) else None
        return PlantState(q, qd, z)

    def substeps(self, dt: float, q: ArrayLike) -> int:
        """RK4 substeps per period ``dt`` [s] for stability with this robot's friction.

        The rates use each joint's own inertia M_jj(q) [kg m²] (joint coupling is
        neglected), taken at ``q`` [rad].
        """
        inertia = np.diag(self.robot.mass_matrix(q))
        return _substeps_for(_friction_rates(self.friction, inertia), check_dt(dt))

    def joint_friction(self, state: PlantState) -> FloatArray:
        """True friction torque τ_fr [N m] at ``state``."""
        return friction_torque(self.friction, state.qd, state.z, state.t)

    def elastic_torque(self, state: PlantState) -> None:
        """Rigid joints have no joint-torque sensor reading."""
        return None

    def advance(
        self, state: PlantState, tau_m: FloatArray, tau_c: FloatArray, dt: float, substeps: int
    ) -> PlantState:
        """Integrate one period ``dt`` [s] with τ_m and τ_c [N m] held."""
        model, data, friction = self.robot.pinocchio_model, self._data, self.friction
        if isinstance(friction, DriftingFriction):
            friction = friction.at(state.t)  # held over the period
        drive = tau_m + tau_c
        h = dt / substeps
        n = self.n_dof
        # Classical RK4 on x = (q, q̇) stacked, one array operation per stage
        # update: this is the simulator's hot loop.
        x = np.concatenate((state.q, state.qd))
        slope = np.empty((4, 2 * n))
        stage = np.empty(2 * n)
        z = state.z
        for _ in range(substeps):
            resist = _held_friction(friction, z, state.t)
            np.copyto(stage, x)
            for i, weight in enumerate((0.5 * h, 0.5 * h, h, 0.0)):
                qd = stage[n:]
                force = drive if resist is None else drive - resist(qd)
                slope[i, :n] = qd
                slope[i, n:] = pin.aba(model, data, stage[:n], qd, force)
                if weight:
                    np.multiply(slope[i], weight, out=stage)
                    stage += x
            x_new = x + (h / 6.0) * (slope[0] + 2.0 * (slope[1] + slope[2]) + slope[3])
            z = _advance_bristles(friction, z, 0.5 * (x[n:] + x_new[n:]), h)
            x = x_new
        return PlantState(x[:n], x[n:], z, t=state.t + dt)


@dataclass(frozen=True)
class TorqueFeedback:
    """Joint-torque feedback of the LWR (eq. 2.2, Albu-Schäffer et al. 2007).

    τ_m = B B_θ⁻¹ u + (I − B B_θ⁻¹) τ_J + (D − B B_θ⁻¹ D_s) K⁻¹ τ̇_J

    Parameters
    ----------
    motor_inertia : array-like of shape (n_dof,)
        Apparent motor inertia B_θ the loop imposes [kg m²], > 0.
    damping : array-like of shape (n_dof,)
        Apparent joint damping D_s [N m s/rad], >= 0.
    """

    motor_inertia: FloatArray
    damping: FloatArray


@dataclass(frozen=True, eq=False)
class FlexiblePlant:
    """Flexible-joint arm of eq. (2.1a–c).

    Link side: M(q) q̈ + C q̇ + g = τ_L − τ_frL + τ_c; motor side (joint-side
    coordinates): B θ̈ + τ_L = τ_m − τ_fr; τ_L = τ_J + D (θ̇ − q̇) with the
    elastic torque τ_J = K (θ − q) that a joint torque sensor reads.

    Parameters
    ----------
    robot : RobotModel
        True link-side robot; its armature is taken as the motor inertia B
        when ``motor_inertia`` is not given, and removed from the link side.
    stiffness : array-like of shape (n_dof,)
        Joint stiffness K [N m/rad], > 0.
    damping : array-like of shape (n_dof,)
        Joint damping D [N m s/rad], >= 0.
    motor_inertia : array-like of shape (n_dof,), optional
        Motor inertia B on the joint side [kg m²], > 0.
    motor_friction, link_friction : FrictionModel, LuGre or None
        Motor-side τ_fr (on θ̇) and link-side τ_frL (on q̇) friction.
    feedback : TorqueFeedback, optional
        Torque loop of eq. (2.2); the command u then replaces τ_m.
    integrator : {"rosenbrock", "rk4"}, default "rosenbrock"
        ``"rosenbrock"``: the springs and the torque loop implicit
        (:mod:`sensorless.simulation._stiff`), so the substeps resolve the
        joint oscillation only up to h ω ≤ π and faster modes are damped;
        ``"rk4"``: classical RK4 with |λ h| ≤ 1 for every rate, the reference.
    """

    robot: RobotModel
    stiffness: ArrayLike
    damping: ArrayLike
    motor_inertia: ArrayLike | None = None
    motor_friction: Friction = None
    link_friction: Friction = None
    feedback: TorqueFeedback | None = None
    integrator: str = "rosenbrock"
    _link_model: pin.Model = field(init=False, repr=False)
    _link_data: pin.Data = field(init=False, repr=False)
    _loop: SpringLoop = field(init=False, repr=False)

    def __post_init__(self) -> None:
        n = self.robot.n_dof
        inertia = self.robot.armature if self.motor_inertia is None else self.motor_inertia
        b = _joint_vector(inertia, n, "motor inertia B [kg m²]", positive=True)
        object.__setattr__(self, "motor_inertia", b)
        object.__setattr__(
            self, "stiffness", _joint_vector(self.stiffness, n, "stiffness K", positive=True)
        )
        object.__setattr__(self, "damping", _joint_vector(self.damping, n, "damping D"))
        _check_friction(self.motor_friction, n, "motor-side")
        _check_friction(self.link_friction, n, "link-side")
        if self.feedback is not None:
            fb = TorqueFeedback(
                _joint_vector(self.feedback.motor_inertia, n, "B_θ", positive=True),
                _joint_vector(self.feedback.damping, n, "D_s"),
            )
            object.__setattr__(self, "feedback", fb)
        if self.integrator not in _INTEGRATORS:
            raise InputValueError(
                f"integrator must be one of {list(_INTEGRATORS)}; got {self.integrator!r}"
            )
        link = self.robot.pinocchio_model.copy()
        link.armature = np.zeros(n)
        object.__setattr__(self, "_link_model", link)
        object.__setattr__(self, "_link_data", link.createData())
        k, d = np.asarray(self.stiffness), np.asarray(self.damping)
        feedback = self.feedback
        loop = (b, d) if feedback is None else (feedback.motor_inertia, feedback.damping)
        object.__setattr__(self, "_loop", SpringLoop(k, d, b, *loop))

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return self.robot.n_dof

    def initial_state(self, q0: ArrayLike, qd0: ArrayLike | None = None) -> PlantState:
        """Static equilibrium at ``q0`` [rad]: the springs carry gravity, θ = q + K⁻¹ g(q)."""
        q, qd = _initial(q0, qd0, self.n_dof)
        gravity = pin.computeGeneralizedGravity(self._link_model, self._link_data, q)
        theta = q + gravity / np.asarray(self.stiffness)
        lugre = [np.zeros(self.n_dof) if isinstance(f, LuGre) else None
                 for f in (self.link_friction, self.motor_friction)]  # fmt: skip
        return PlantState(q, qd, lugre[0], theta, qd.copy(), lugre[1])

    def substeps(self, dt: float, q: ArrayLike) -> int:
        """Substeps per period ``dt`` [s] for these stiff joints, taken at ``q`` [rad].

        RK4 keeps |λ h| ≤ 1 for the joint oscillation, the damping and the
        friction; the implicit step only for the friction (explicit in it),
        and h ω ≤ π for the joint oscillation ω [rad/s]: modes faster than
        the substep's Nyquist frequency are damped, not resolved.
        """
        link = self._link_model
        inertia = np.diag(pin.crba(link, self._link_data, np.asarray(q, float))).copy()
        b = np.asarray(self.motor_inertia)
        k = np.asarray(self.stiffness)
        d = np.asarray(self.damping)
        friction = [
            *_friction_rates(self.link_friction, inertia),
            *_friction_rates(self.motor_friction, b),
        ]
        if self.integrator == "rosenbrock":
            loop = np.asarray(self._loop.loop_inertia)
            oscillation = float(np.max(np.sqrt(k * (1.0 / loop + 1.0 / inertia))))
            return _substeps_for([oscillation / math.pi, *friction], check_dt(dt))
        rates = [
            float(np.max(np.sqrt(k * (1.0 / b + 1.0 / inertia)))),
            float(np.max(d * (1.0 / b + 1.0 / inertia))),
            *friction,
        ]
        if self.feedback is not None:
            rates.append(float(np.max(self.feedback.damping / self.feedback.motor_inertia)))
        return _substeps_for(rates, check_dt(dt))

    def joint_friction(self, state: PlantState) -> FloatArray:
        """Link-side friction τ_frL [N m] at ``state``."""
        return friction_torque(self.link_friction, state.qd, state.z, state.t)

    def elastic_torque(self, state: PlantState) -> FloatArray:
        """Elastic joint torque τ_J = K (θ − q) [N m] read by the torque sensors."""
        assert state.theta is not None
        return np.asarray(self.stiffness) * (state.theta - state.q)

    def advance(
        self, state: PlantState, tau_m: FloatArray, tau_c: FloatArray, dt: float, substeps: int
    ) -> PlantState:
        """Integrate one period ``dt`` [s].

        ``tau_m`` is the motor torque, or the command u when a feedback loop is set.
        """
        if state.theta is None or state.thetad is None:
            raise ModelError("a flexible plant needs a state with motor positions (theta)")
        if self.integrator == "rk4":
            return self._advance_rk4(state, tau_m, tau_c, dt, substeps)
        n = self.n_dof
        h = dt / substeps
        y = np.concatenate((state.q, state.qd, state.theta, state.thetad))
        z, z_motor, t = state.z, state.z_motor, state.t
        for _ in range(substeps):
            y_new = self._loop.advance(
                self._link_model,
                self._link_data,
                y,
                tau_m,
                tau_c,
                _held_friction(self.link_friction, z, t),
                _held_friction(self.motor_friction, z_motor, t),
                h,
            )
            z = _advance_bristles(self.link_friction, z, 0.5 * (y[n : 2 * n] + y_new[n : 2 * n]), h)
            z_motor = _advance_bristles(
                self.motor_friction, z_motor, 0.5 * (y[3 * n :] + y_new[3 * n :]), h
            )
            y = y_new
        return PlantState(y[:n], y[n : 2 * n], z, y[2 * n : 3 * n], y[3 * n :], z_motor, t + dt)

    def _advance_rk4(
        self, state: PlantState, tau_m: FloatArray, tau_c: FloatArray, dt: float, substeps: int
    ) -> PlantState:
        """The reference path: classical RK4 on the whole state (``integrator="rk4"``)."""
        assert state.theta is not None and state.thetad is not None
        model, data = self._link_model, self._link_data
        n = self.n_dof
        k, d, b = (np.asarray(v) for v in (self.stiffness, self.damping, self.motor_inertia))
        fb = self.feedback
        h = dt / substeps
        x = np.concatenate([state.q, state.qd, state.theta, state.thetad])
        z, z_motor, t = state.z, state.z_motor, state.t
        link_friction, motor_friction = self.link_friction, self.motor_friction

        def derivative(
            y: FloatArray, z: FloatArray | None, z_motor: FloatArray | None
        ) -> FloatArray:
            q, qd, theta, thetad = y[:n], y[n : 2 * n], y[2 * n : 3 * n], y[3 * n :]
            tau_j = k * (theta - q)
            tau_l = tau_j + d * (thetad - qd)
            motor = tau_m
            if fb is not None:
                ratio = b / fb.motor_inertia
                motor = (
                    ratio * tau_m + (1 - ratio) * tau_j + (d - ratio * fb.damping) * (thetad - qd)
                )
            link_tau = tau_l - friction_torque(link_friction, qd, z, t) + tau_c
            motor_acc = (motor - friction_torque(motor_friction, thetad, z_motor, t) - tau_l) / b
            return np.concatenate([qd, pin.aba(model, data, q, qd, link_tau), thetad, motor_acc])

        for _ in range(substeps):
            x_new = _rk4(partial(derivative, z=z, z_motor=z_motor), x, h)
            z = _advance_bristles(link_friction, z, 0.5 * (x[n : 2 * n] + x_new[n : 2 * n]), h)
            z_motor = _advance_bristles(
                motor_friction, z_motor, 0.5 * (x[3 * n :] + x_new[3 * n :]), h
            )
            x = x_new
        return PlantState(x[:n], x[n : 2 * n], z, x[2 * n : 3 * n], x[3 * n :], z_motor, t + dt)


def _initial(q0: ArrayLike, qd0: ArrayLike | None, n_dof: int) -> tuple[FloatArray, FloatArray]:
    q = np.asarray(q0, dtype=float).copy()
    qd = np.zeros(n_dof) if qd0 is None else np.asarray(qd0, dtype=float).copy()
    for name, arr in (("q0", q), ("qd0", qd)):
        if arr.shape != (n_dof,):
            raise DimensionError(f"{name} must have shape ({n_dof},); got {arr.shape}")
        if not np.isfinite(arr).all():
            raise InputValueError(f"{name} must be finite; got {arr}")
    return q, qd
