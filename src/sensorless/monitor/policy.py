"""What the monitor accepts: the time base, physical limits, start-up and latching.

One :class:`StreamPolicy` is shared by the live stream and the batch path of
:class:`~sensorless.monitor.CollisionMonitor`, so that both call the same
sample a fault. Units SI and radians; time along axis 0.

Fault semantics (modelled on a robot controller's reflex and error states):

* A sample that is not finite, has the wrong shape, goes back in time,
  repeats a time stamp, comes less than ``early``·dt after the last accepted
  sample, or whose position, velocity or torque is outside the limits below
  is a **fault**: it is ignored and every state stays exactly as it was.
* A sample more than ``gap``·dt after the last accepted one is a fault too.
  If a later sample follows the last accepted one regularly, the odd time
  stamp was the fault and the stream goes on. If instead it follows regularly
  the last refused sample since then (the gap sample, or the end of a run of
  bad samples), the gap was real: the stream restarts at that sample
  (observer, threshold and detector from scratch). Two samples at a regular
  spacing after a gap are a resumed stream by definition.
* After a start or a restart the verdict is **settling** for ``settle``
  seconds: the observer runs, nothing is judged, and the threshold starts
  when the settling ends.
* A **collision** verdict latches: it stays until :meth:`reset` or, with
  ``release`` set, until every monitored residual has been inside its bounds
  for ``release`` seconds.
* Durations (``settle``, ``release``, and the detector's ``min_duration`` and
  ``hold``) are compared up to :data:`~sensorless.detection.TIME_TOLERANCE`
  (1 ns), so a whole number of sample periods equal to one of them counts as
  equal at every sample rate despite the rounding of time stamps.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from .._validation import FloatArray, check_scalar
from ..exceptions import InputValueError
from ..robots.model import RobotModel

__all__ = ["Limits", "StreamPolicy"]

BoolArray = NDArray[np.bool_]


@dataclass(frozen=True)
class StreamPolicy:
    """How the monitor judges time, physical limits and its own start.

    Parameters
    ----------
    early : float
        A sample less than ``early``·dt after the last accepted one is a
        fault [-] (repeated or jittered-together time stamps).
    gap : float
        A sample more than ``gap``·dt after the last accepted one is a fault
        and may start a restart [-].
    settle : float or None
        Settling time after a (re)start [s]; None: the observer's
        :meth:`~sensorless.monitor.ObserverSettings.settle_time`.
    release : float or None
        None: a collision latches until :meth:`CollisionMonitor.reset`; a
        number: the latch releases after that many seconds inside the bounds [s].
    position_margin : float
        Allowed overshoot of the robot's position limits [rad].
    velocity_factor, torque_factor : float
        Allowed multiple of the robot's velocity and effort limits [-]
        (estimated velocities are noisy; commanded torques overshoot).
    max_position, max_velocity, max_torque : float
        Plausibility caps where the robot declares no limit [rad], [rad/s], [N m].
    period_rtol : float
        Relative tolerance between a log's sample period and the tuned one [-].
    """

    early: float = 0.5
    gap: float = 1.5
    settle: float | None = None
    release: float | None = None
    position_margin: float = 0.1
    velocity_factor: float = 1.5
    torque_factor: float = 2.0
    max_position: float = 100.0
    max_velocity: float = 100.0
    max_torque: float = 1e5
    period_rtol: float = 1e-3

    def __post_init__(self) -> None:
        early = check_scalar(self.early, "early", "-", "positive")
        gap = check_scalar(self.gap, "gap", "-", "positive")
        if not early < 1.0 < gap:
            raise InputValueError(
                f"need early < 1 < gap (multiples of dt); got early={early}, gap={gap}"
            )
        if self.settle is not None:
            check_scalar(self.settle, "settle", "s", "nonnegative")
        if self.release is not None:
            check_scalar(self.release, "release", "s", "nonnegative")
        check_scalar(self.position_margin, "position_margin", "rad", "nonnegative")
        for name in ("velocity_factor", "torque_factor"):
            check_scalar(getattr(self, name), name, "-", "positive")
        check_scalar(self.max_position, "max_position", "rad", "positive")
        check_scalar(self.max_velocity, "max_velocity", "rad/s", "positive")
        check_scalar(self.max_torque, "max_torque", "N m", "positive")
        check_scalar(self.period_rtol, "period_rtol", "-", "positive")

    def limits(self, robot: RobotModel) -> Limits:
        """The per-joint limits this policy allows for ``robot``."""
        low, high = robot.position_limits
        low = np.where(np.isfinite(low), low - self.position_margin, -self.max_position)
        high = np.where(np.isfinite(high), high + self.position_margin, self.max_position)
        velocity = np.where(
            np.isfinite(robot.velocity_limits),
            self.velocity_factor * robot.velocity_limits,
            self.max_velocity,
        )
        torque = np.where(
            np.isfinite(robot.effort_limits),
            self.torque_factor * robot.effort_limits,
            self.max_torque,
        )
        return Limits((high + low) / 2.0, (high - low) / 2.0, velocity, torque)


@dataclass(frozen=True, eq=False)
class Limits:
    """Per-joint limits, each of shape (n_dof,).

    Attributes
    ----------
    centre, half_range : ndarray
        Middle and half width of the allowed positions [rad].
    velocity : ndarray
        Largest allowed speed [rad/s].
    torque : ndarray
        Largest allowed torque magnitude [N m].

    A comparison with NaN is false, so every check also rejects NaN and inf.
    """

    centre: FloatArray
    half_range: FloatArray
    velocity: FloatArray
    torque: FloatArray

    def position_ok(self, q: FloatArray) -> bool:
        """Whether one sample of positions [rad] is finite and inside the limits."""
        return bool((np.abs(q - self.centre) <= self.half_range).all())

    def velocity_ok(self, qd: FloatArray) -> bool:
        """Whether one sample of velocities [rad/s] is finite and inside the limits."""
        return bool((np.abs(qd) <= self.velocity).all())

    def torque_ok(self, tau: FloatArray) -> bool:
        """Whether one sample of torques [N m] is finite and inside the limits."""
        return bool((np.abs(tau) <= self.torque).all())

    def bad_rows(self, q: FloatArray, qd: FloatArray | None, *torques: FloatArray) -> BoolArray:
        """Rows a stream would call a fault, as a boolean mask of shape (n_samples,).

        ``q`` [rad], ``qd`` [rad/s] and the torques [N m] have shape (n_samples, n_dof).
        """
        ok = (np.abs(q - self.centre) <= self.half_range).all(axis=1)
        if qd is not None:
            ok &= (np.abs(qd) <= self.velocity).all(axis=1)
        for tau in torques:
            ok &= (np.abs(tau) <= self.torque).all(axis=1)
        return np.logical_not(ok)

    def describe(self, name: str, values: FloatArray) -> str:
        """Why one sample of ``name`` ("q", "qd" or a torque) is outside its limits."""
        if not np.isfinite(values).all():
            return f"{name} has a non-finite value: {values}"
        if name == "q":
            over = np.abs(values - self.centre) - self.half_range
            j = int(np.argmax(over))
            low, high = self.centre[j] - self.half_range[j], self.centre[j] + self.half_range[j]
            return (
                f"q of joint {j + 1} is {values[j]:.6g} rad, outside its limits "
                f"[{low:.4g}, {high:.4g}] rad (degrees instead of radians?)"
            )
        limit = self.velocity if name == "qd" else self.torque
        unit = "rad/s" if name == "qd" else "N m"
        j = int(np.argmax(np.abs(values) - limit))
        return f"{name} of joint {j + 1} is {values[j]:.6g} {unit}, beyond ±{limit[j]:.4g} {unit}"
