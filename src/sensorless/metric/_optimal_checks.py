"""Input checks of :func:`~sensorless.metric.optimize_trajectory` and its starting quintic."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_float_array, check_finite, per_joint
from ..exceptions import DimensionError, InputValueError
from ..robots.model import RobotModel
from ..trajectories import QuinticViaPoints
from ._transcription import Boundary, Limits

__all__ = ["TimeWeight", "boundary_of", "limits_of", "quintic_through", "time_weight_on", "via_of"]

TimeWeight = Callable[[FloatArray], ArrayLike]


def _joint_vector(value: ArrayLike, n: int, name: str, unit: str) -> FloatArray:
    arr = as_float_array(value, name, f"({n},)")
    if arr.shape != (n,):
        raise DimensionError(
            f"{name} must have shape ({n},) [{unit}] for a robot with {n} joints; "
            f"got shape {arr.shape}"
        )
    check_finite(arr, name)
    return arr


def limits_of(
    robot: RobotModel,
    position_limits: tuple[ArrayLike, ArrayLike] | None,
    velocity_limits: float | ArrayLike | None,
    acceleration_limits: float | ArrayLike | None,
    torque_limits: float | ArrayLike | None,
) -> Limits:
    n = robot.n_dof
    if position_limits is None:
        lower, upper = robot.position_limits
    else:
        if len(position_limits) != 2:
            raise DimensionError(
                f"position_limits must be a pair (lower, upper) [rad]; got {position_limits!r}"
            )
        lower = per_joint(position_limits[0], n, "position_limits lower", "rad", allow_inf=True)
        upper = per_joint(position_limits[1], n, "position_limits upper", "rad", allow_inf=True)
    if (lower >= upper).any():
        j = int(np.argmax(lower >= upper))
        raise InputValueError(
            f"position limits need lower < upper; joint {j + 1} has {lower[j]:.6g} >= "
            f"{upper[j]:.6g} rad"
        )
    speed, torque = robot.velocity_limits, robot.effort_limits
    limits = []
    for value, default, name, unit in (
        (velocity_limits, speed, "velocity_limits", "rad/s"),
        (acceleration_limits, np.full(n, np.inf), "acceleration_limits", "rad/s²"),
        (torque_limits, torque, "torque_limits", "N m"),
    ):
        arr = default if value is None else per_joint(value, n, name, unit, allow_inf=True)
        if (arr <= 0).any():
            j = int(np.argmax(arr <= 0))
            raise InputValueError(f"{name} must be > 0 [{unit}]; joint {j + 1} has {arr[j]:.6g}")
        limits.append(np.asarray(arr, dtype=float))
    return Limits(np.asarray(lower, float), np.asarray(upper, float), *limits)


def _within(q: FloatArray, limits: Limits, name: str) -> None:
    outside = (q < limits.lower) | (q > limits.upper)
    if outside.any():
        j = int(np.argmax(outside))
        raise InputValueError(
            f"{name} must lie within the position limits; joint {j + 1} is at {q[j]:.6g} rad, "
            f"outside [{limits.lower[j]:.6g}, {limits.upper[j]:.6g}] rad"
        )


def boundary_of(
    n: int,
    q_start: ArrayLike,
    q_end: ArrayLike,
    qd_start: float | ArrayLike,
    qd_end: float | ArrayLike,
    qdd_start: float | ArrayLike | None,
    qdd_end: float | ArrayLike | None,
    limits: Limits,
    duration: float,
) -> Boundary:
    q_s = _joint_vector(q_start, n, "q_start", "rad")
    q_e = _joint_vector(q_end, n, "q_end", "rad")
    _within(q_s, limits, "q_start")
    _within(q_e, limits, "q_end")
    speeds = [
        per_joint(v, n, name, "rad/s") for v, name in ((qd_start, "qd_start"), (qd_end, "qd_end"))
    ]
    for value, name in zip(speeds, ("qd_start", "qd_end"), strict=True):
        if (np.abs(value) > limits.velocity).any():
            j = int(np.argmax(np.abs(value) > limits.velocity))
            raise InputValueError(
                f"{name} exceeds the velocity limit at joint {j + 1}: |{value[j]:.6g}| > "
                f"{limits.velocity[j]:.6g} rad/s"
            )
    travel = np.abs(q_e - q_s) / duration
    if (travel > limits.velocity).any():
        j = int(np.argmax(travel / limits.velocity))
        raise InputValueError(
            f"joint {j + 1} must travel {abs(q_e[j] - q_s[j]):.6g} rad in {duration:g} s, at "
            f"least {travel[j]:.6g} rad/s on average, above its velocity limit "
            f"{limits.velocity[j]:.6g} rad/s; give a longer duration"
        )
    accelerations = [
        None if v is None else per_joint(v, n, name, "rad/s²")
        for v, name in ((qdd_start, "qdd_start"), (qdd_end, "qdd_end"))
    ]
    return Boundary(q_s, q_e, speeds[0], speeds[1], accelerations[0], accelerations[1])


def via_of(
    n: int,
    via_times: ArrayLike | None,
    via_positions: ArrayLike | None,
    duration: float,
    limits: Limits,
) -> tuple[FloatArray, FloatArray] | None:
    if via_times is None and via_positions is None:
        return None
    if via_times is None or via_positions is None:
        raise InputValueError("via points need both via_times [s] and via_positions [rad]")
    times = as_float_array(via_times, "via_times", "(n_via,)")
    if times.ndim != 1 or times.size == 0:
        raise DimensionError(
            f"via_times must have shape (n_via,) with n_via >= 1; got {times.shape}"
        )
    check_finite(times, "via_times")
    positions = as_float_array(via_positions, "via_positions", f"({times.size}, {n})")
    if positions.shape != (times.size, n):
        raise DimensionError(
            f"via_positions must have shape (n_via, n_dof) = ({times.size}, {n}); got "
            f"{positions.shape}"
        )
    check_finite(positions, "via_positions")
    if times[0] <= 0.0 or times[-1] >= duration or (np.diff(times) <= 0).any():
        raise InputValueError(
            f"via_times must be strictly increasing inside (0, duration = {duration:g}) s; "
            f"got {times.tolist()}"
        )
    for k, row in enumerate(positions):
        _within(row, limits, f"via_positions[{k}]")
    return times, positions


def time_weight_on(time_weight: TimeWeight | None, t: FloatArray) -> FloatArray:
    if time_weight is None:
        return np.ones_like(t)
    if not callable(time_weight):
        raise InputValueError(
            f"time_weight must be a function of the time [s]; got {type(time_weight).__name__}"
        )
    weight = np.broadcast_to(np.asarray(time_weight(t), dtype=float), t.shape).copy()
    if not np.isfinite(weight).all() or (weight < 0).any():
        raise InputValueError("time_weight(t) must be finite and >= 0 at every time")
    return weight


def quintic_through(
    boundary: Boundary, via: tuple[FloatArray, FloatArray] | None, duration: float
) -> QuinticViaPoints:
    """The quintic through the same points: the project's default and the start."""
    times = np.array([0.0, duration])
    positions = np.vstack([boundary.q_start, boundary.q_end])
    velocities: FloatArray | None = np.vstack([boundary.qd_start, boundary.qd_end])
    zero = np.zeros_like(boundary.q_start)
    first = zero if boundary.qdd_start is None else boundary.qdd_start
    last = zero if boundary.qdd_end is None else boundary.qdd_end
    accelerations = np.vstack([first, last])
    if via is not None:
        times = np.concatenate([[0.0], via[0], [duration]])
        positions = np.vstack([boundary.q_start, via[1], boundary.q_end])
        velocities = None
        accelerations = np.zeros_like(positions)
        accelerations[0], accelerations[-1] = first, last
        heuristic = QuinticViaPoints(times, positions)
        velocities = np.array(heuristic.velocities)
        velocities[0], velocities[-1] = boundary.qd_start, boundary.qd_end
    return QuinticViaPoints(times, positions, velocities, accelerations)
