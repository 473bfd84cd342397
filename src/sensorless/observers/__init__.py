"""Collision observers: the generalized-momentum residual and the acceleration-based estimate.

Two observers turn joint positions, velocities and torques into a residual
that is zero without contact and follows the external joint torque τ_c
during a contact:

:class:`MomentumObserver`
    The generalized-momentum residual r̂ of eq. (4.4) with motor torques, or
    r̂_s of eq. (4.9) with joint-torque-sensor torques. It needs no
    acceleration: with an exact model, r̂ = K_I/(s+K_I)·τ_c (eq. 3.6).
    Alongside r̂ it produces the model torque h(t) of eq. (4.26)/(5.30), the
    filtered friction K_I/(s+K_I)·τ̂_fr of eq. (5.29) and the filtered sign
    K_I/(s+K_I)·sign(q̇) used by the thresholds of eq. (5.39).
:class:`AccelerationObserver`
    The estimate τ̂_c of eq. (3.8)/(3.16) from velocities and accelerations
    estimated by a causal filter of :mod:`sensorless.filters`.
:func:`observe`
    Either observer over a :class:`~sensorless.io.Log`.

Dynamics and signs (friction convention of :mod:`sensorless.friction`)::

    M(q) q̈ + C(q, q̇) q̇ + g(q) = τ + τ_c − τ_fr                   eq. (4.1)

with τ the motor torque τ_m (``torque="motor"``) or, for the link side of a
flexible-joint arm, the joint-torque-sensor reading τ_J (``torque="joint"``).

Streaming and batch share one implementation, as :func:`scipy.signal.lfilter`
with ``zi``/``zf``: ``initial_state`` gives a state, ``step`` processes one
sample and ``run`` a whole array; both return the state after the last
sample, so a record cut into chunks gives the same signals as in one go.
Units are SI and radians; time series have shape ``(n_samples, n_dof)``
with time along axis 0, and one sample has shape ``(n_dof,)``.

Examples
--------
A push τ_c on joint 1 of an arm held at rest: r̂ follows K_I/(s+K_I)·τ_c,
1 − e^(−K_I t) of the push after t = 0.1 s.

>>> import numpy as np
>>> from sensorless import robots
>>> from sensorless.observers import MomentumObserver
>>> robot = robots.load("planar2")
>>> t = np.arange(101) * 1e-3
>>> q = qd = np.zeros((t.size, 2))                           # at rest
>>> tau_c = np.array([1.0, 0.0])
>>> tau = np.tile(robot.gravity(q[0]) - tau_c, (t.size, 1))  # the motors hold against it
>>> signals, _ = MomentumObserver(robot, 1e-3, gain=20.0, friction=None).run(t, q, qd, tau)
>>> signals.residual[-1].round(3).tolist()
[0.865, 0.0]
"""

from __future__ import annotations

from ._common import OBSERVER_KINDS, TORQUE_KINDS, VELOCITY_SOURCES, ObserverSample
from .acceleration import AccelerationObserver
from .adaptive import AdapterState, FrictionAdapter
from .momentum import MomentumObserver, ObserverState
from .observe import default_estimator, observe

__all__ = [
    "OBSERVER_KINDS",
    "TORQUE_KINDS",
    "VELOCITY_SOURCES",
    "AccelerationObserver",
    "AdapterState",
    "FrictionAdapter",
    "MomentumObserver",
    "ObserverSample",
    "ObserverState",
    "default_estimator",
    "observe",
]
