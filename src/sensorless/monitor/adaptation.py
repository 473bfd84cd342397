"""Drift adaptation of a live monitor: when it may learn, and how fast.

Friction and torque offsets drift as an arm warms up; a threshold tuned on
a cold arm then alarms on a warm one. With an :class:`Adaptation`, a
:class:`~sensorless.monitor.CollisionMonitor` corrects the momentum residual
by a :class:`~sensorless.observers.adaptive.FrictionAdapter` (recursive least
squares on the Coulomb/viscous/offset regressor, optionally with the relative
model error on the model torque, rate-limited and bounded)
placed between the observer and the threshold, and feeds it only with
samples its own detector holds collision-free:

* not while settling after a (re)start;
* not while a collision is latched;
* not within ``guard`` seconds after any monitored joint was outside its
  bounds (so the tail of a contact is not learned).

The samples just before an alarm, when a contact is building up but not yet
outside the bounds, cannot be known causally; the adapter's rate limit
bounds what they can teach: at most ``rate_limit`` N m/s of correction, so a
push ramped over 2 s moves the correction by at most 2·``rate_limit`` N m.

The learned parameters survive a restart after a gap (the filters start
again with the observer). Units SI and radians.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

from .._validation import check_scalar
from ..observers.adaptive import FrictionAdapter
from ..observers.momentum import MomentumObserver

__all__ = ["Adaptation"]


@dataclass(frozen=True)
class Adaptation:
    """How a monitor adapts its nominal friction and offsets to drift.

    Parameters
    ----------
    rate_limit : float or array-like of shape (n_dof,)
        Largest rate of change of the learned correction [N m/s], > 0. Keep it
        well below the torque rate of the slowest contact to detect.
    max_correction : float or array-like of shape (n_dof,)
        Bound on the learned correction [N m], > 0.
    forgetting_time : float
        Memory of the least squares [s], > 0: samples older than a few of it
        no longer count.
    guard : float
        No learning for this long after a monitored joint was outside its
        bounds [s], >= 0.
    smooth_velocity : float
        Velocity scale of the smooth sign tanh(q̇/v_s) of the Coulomb term [rad/s], > 0.
    max_velocity : float
        Velocity range over which ``rate_limit`` and ``max_correction`` hold [rad/s], > 0.
    max_model_torque : float or array-like of shape (n_dof,), optional
        Learn the relative model error on the observer's model torque h too
        (see :class:`~sensorless.observers.adaptive.FrictionAdapter`): the
        bound on |h| [N m] over which the rate limit and the bound hold. None
        (default): friction and offsets only.
    """

    rate_limit: Any = 0.05
    max_correction: Any = 5.0
    forgetting_time: float = 120.0
    guard: float = 2.0
    smooth_velocity: float = 0.02
    max_velocity: float = 2.0
    max_model_torque: Any = None

    def __post_init__(self) -> None:
        check_scalar(self.forgetting_time, "forgetting_time", "s")
        check_scalar(self.smooth_velocity, "smooth_velocity", "rad/s")
        check_scalar(self.max_velocity, "max_velocity", "rad/s")
        check_scalar(self.guard, "guard", "s", "nonnegative")

    def adapter(self, observer: MomentumObserver) -> FrictionAdapter:
        """The :class:`FrictionAdapter` for the residual of ``observer``."""
        return FrictionAdapter.from_observer(
            observer,
            rate_limit=self.rate_limit,
            max_correction=self.max_correction,
            forgetting_time=self.forgetting_time,
            smooth_velocity=self.smooth_velocity,
            max_velocity=self.max_velocity,
            max_model_torque=self.max_model_torque,
        )
