"""A linearly implicit step for flexible joints: the springs and the torque loop implicit.

The joint springs of a flexible arm (and the torque loop of eq. 2.2) make
modes of several thousand rad/s that an explicit step must resolve (RK4
needs about ten substeps per millisecond on the LWR). Here they are the
matrix ``J`` of a two-stage Rosenbrock W-method (ROS2, Verwer, Spee, Blom and
Hundsdorfer 1999)::

    (I − γ h J) k1 = f(y)
    (I − γ h J) k2 = f(y + h k1) − 2 k1
    y⁺ = y + (3/2) h k1 + (1/2) h k2,      γ = 1 − 1/√2

which is second order for any ``J`` and L-stable, so a stiff mode is damped
instead of blowing up, whatever the step. ``f`` is the full right-hand side
(link dynamics by ABA, friction, contacts), evaluated explicitly; ``J`` is
its linear spring-damper part with M(q) frozen at the start of the period::

    M q̈ = K (θ − q) + D (θ̇ − q̇) + …        B_m θ̈ = −K (θ − q) − D_m (θ̇ − q̇) + …

where B_m, D_m are the motor inertia and damping the motor side sees: B and
D without torque feedback, B_θ and D_s with it. The motor rows are
diagonal, so a solve with ``I − γ h J`` eliminates them and leaves one n × n
system ``W = M + diag(α_l B_m / β)``, inverted once per period.

State vector ``y = (q, q̇, θ, θ̇)`` of shape (4 n_dof,), SI units, radians.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import pinocchio as pin

from .._validation import FloatArray

__all__ = ["GAMMA", "SpringLoop"]

#: γ of ROS2: 1 − 1/√2 (the smaller of the two L-stable values: smaller error constant).
GAMMA = 1.0 - 1.0 / math.sqrt(2.0)

StageFriction = Callable[[FloatArray], FloatArray] | None


@dataclass(frozen=True, eq=False)
class SpringLoop:
    """Constants of the implicit spring-damper part of one flexible plant.

    Parameters
    ----------
    stiffness, damping : ndarray of shape (n_dof,)
        Joint stiffness K [N m/rad] and damping D [N m s/rad].
    motor_inertia : ndarray of shape (n_dof,)
        Motor inertia B [kg m²] (divides the motor friction).
    loop_inertia, loop_damping : ndarray of shape (n_dof,)
        B_m [kg m²] and D_m [N m s/rad] seen on the motor side (B, D
        without feedback; B_θ, D_s with it).
    """

    stiffness: FloatArray
    damping: FloatArray
    motor_inertia: FloatArray
    loop_inertia: FloatArray
    loop_damping: FloatArray

    def advance(
        self,
        model: pin.Model,
        data: pin.Data,
        y: FloatArray,
        command: FloatArray,
        tau_c: FloatArray,
        link_friction: StageFriction,
        motor_friction: StageFriction,
        h: float,
    ) -> FloatArray:
        """One ROS2 step of length ``h`` [s] from ``y``; returns y⁺.

        ``command`` is u (with feedback) or τ_m [N m], held; the friction
        callables give torque [N m] from velocity with any bristle state held.
        M(q) is taken at ``y``'s positions.
        """
        n = self.stiffness.shape[0]
        k, d, bm, dm = self.stiffness, self.damping, self.loop_inertia, self.loop_damping
        c = GAMMA * h
        ck = c * k
        alpha_l = c * (ck + d)
        alpha_m = c * (ck + dm)
        beta = bm + alpha_m
        coupling = alpha_l / beta
        mass = np.asarray(pin.crba(model, data, y[:n]))
        mass = np.triu(mass) + np.triu(mass, 1).T
        w_inv = np.linalg.inv(mass + np.diag(coupling * bm))
        inv_bm = 1.0 / bm
        inv_b = 1.0 / self.motor_inertia

        def derivative(x: FloatArray) -> tuple[FloatArray, FloatArray]:
            """f(x) with its link rows as M(q_0) q̈ (what the solve needs) and as q̈."""
            q, qd, theta, thetad = x[:n], x[n : 2 * n], x[2 * n : 3 * n], x[3 * n :]
            deflection_rate = thetad - qd
            spring = k * (theta - q)
            link = spring + d * deflection_rate + tau_c
            if link_friction is not None:
                link = link - link_friction(qd)
            motor = (command - spring - dm * deflection_rate) * inv_bm
            if motor_friction is not None:
                motor = motor - motor_friction(thetad) * inv_b
            acceleration = np.asarray(pin.aba(model, data, q, qd, link))
            return np.concatenate((qd, acceleration, thetad, motor)), acceleration

        def solve(r: FloatArray, link_force: FloatArray) -> FloatArray:
            """k with (I − γ h J) k = r; ``link_force`` is M(q_0) times r's q̈ rows."""
            rq, rtheta, rw = r[:n], r[2 * n : 3 * n], r[3 * n :]
            spring = ck * (rtheta - rq)
            motor = bm * rw - spring
            kv = w_inv @ (link_force + spring + coupling * motor)
            kw = (motor + alpha_m * kv) / beta
            return np.concatenate((rq + c * kv, kv, rtheta + c * kw, kw))

        f1, acc1 = derivative(y)
        k1 = solve(f1, mass @ acc1)
        f2, acc2 = derivative(y + h * k1)
        k2 = solve(f2 - 2.0 * k1, mass @ (acc2 - 2.0 * k1[n : 2 * n]))
        return np.asarray(y + (1.5 * h) * k1 + (0.5 * h) * k2)
