"""Seeded random rest-to-rest quintic moves between uniformly drawn targets.

Useful to tune thresholds on "a few different trajectories" (thesis section
5.3): the same seed and parameters give the same trajectory.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_float_array, check_dt, per_joint
from ..exceptions import DimensionError, InputValueError
from .base import Evaluation, Trajectory, _check_radians
from .quintic import QuinticViaPoints

__all__ = ["RandomPointToPoint"]

#: Peak velocity of a rest-to-rest quintic over a move of size 1 lasting 1 s.
_QUINTIC_PEAK_VELOCITY = 15.0 / 8.0


def _interval(pair: tuple[float, float], name: str, *, allow_zero: bool) -> tuple[float, float]:
    """Check a ``(min, max)`` pair of durations [s]."""
    arr = as_float_array(pair, name, "(2,)")
    if arr.shape != (2,):
        raise DimensionError(f"{name} must be a pair (min, max) [s]; got shape {arr.shape}")
    low, high = float(arr[0]), float(arr[1])
    bound_ok = low >= 0.0 if allow_zero else low > 0.0
    if not (np.isfinite(low) and np.isfinite(high) and bound_ok and low <= high):
        sign = ">= 0" if allow_zero else "> 0"
        raise InputValueError(
            f"{name} must be a pair (min, max) [s] of finite times with min {sign} and "
            f"min <= max; got {tuple(pair)!r}"
        )
    return low, high


class RandomPointToPoint(Trajectory):
    """Seeded random rest-to-rest quintic moves between uniformly drawn targets.

    Starting from ``start`` (or a random point), targets are drawn uniformly
    in ``[lower, upper]`` per joint. Each move is a rest-to-rest quintic (zero
    velocity and acceleration at both ends) whose duration ``T`` [s] is a
    random time drawn from ``segment_time``, lengthened where needed so that
    the peak velocity of every joint, ``15/8 · |Δq_j| / T``, does not exceed
    ``max_velocity[j]``. After each move the robot rests for a random time
    drawn from ``rest``. The first move that would end after ``duration`` is
    replaced by a rest at the current target, so the trajectory ends at rest
    exactly at ``duration``.

    Parameters
    ----------
    n_dof : int
        Number of joints.
    duration : float
        Duration of the trajectory [s].
    lower, upper : float or array-like of shape (n_dof,)
        Joint limits for the targets [rad], ``lower <= upper``.
    max_velocity : float or array-like of shape (n_dof,)
        Joint velocity limits [rad/s], positive.
    seed : int, default 0
        Seed of :func:`numpy.random.default_rng`; the same seed and parameters
        give identical trajectories.
    segment_time : (float, float), default (0.5, 2.0)
        Range ``(min, max)`` of the random minimum move duration [s], ``min > 0``.
    rest : (float, float), default (0.0, 0.0)
        Range ``(min, max)`` of the random rest after each move [s], ``min >= 0``.
    start : array-like of shape (n_dof,), optional
        Initial joint positions [rad]; drawn uniformly in ``[lower, upper]``
        by default. It may lie outside the limits (the robot's current
        position, say); the targets never do.

    Attributes
    ----------
    via_points : QuinticViaPoints
        The underlying via points (targets with zero velocity and acceleration).

    Examples
    --------
    >>> traj = RandomPointToPoint(2, 10.0, -1.0, 1.0, max_velocity=0.5, seed=3)
    >>> t, q, qd, qdd = traj.sample(0.01)
    >>> bool(abs(qd).max() <= 0.5)
    True
    """

    def __init__(
        self,
        n_dof: int,
        duration: float,
        lower: ArrayLike,
        upper: ArrayLike,
        max_velocity: ArrayLike,
        seed: int = 0,
        segment_time: tuple[float, float] = (0.5, 2.0),
        rest: tuple[float, float] = (0.0, 0.0),
        start: ArrayLike | None = None,
    ) -> None:
        if isinstance(n_dof, bool) or not isinstance(n_dof, (int, np.integer)) or n_dof < 1:
            raise InputValueError(f"n_dof must be a positive integer; got {n_dof!r}")
        if isinstance(seed, bool) or not isinstance(seed, (int, np.integer)) or seed < 0:
            raise InputValueError(f"seed must be a non-negative integer; got {seed!r}")
        n_dof = int(n_dof)
        total = check_dt(duration, "duration")
        lower_arr = per_joint(lower, n_dof, "lower", "rad")
        upper_arr = per_joint(upper, n_dof, "upper", "rad")
        _check_radians(lower_arr, "lower")
        _check_radians(upper_arr, "upper")
        if (lower_arr > upper_arr).any():
            j = int(np.argmax(lower_arr > upper_arr))
            raise InputValueError(
                f"lower must not exceed upper; joint {j} has lower = {lower_arr[j]:.6g} rad > "
                f"upper = {upper_arr[j]:.6g} rad"
            )
        vmax = per_joint(max_velocity, n_dof, "max_velocity", "rad/s")
        if (vmax <= 0.0).any():
            j = int(np.argmax(vmax <= 0.0))
            raise InputValueError(
                f"max_velocity must be positive [rad/s]; joint {j} has {vmax[j]:.6g}"
            )
        self.segment_time = _interval(segment_time, "segment_time", allow_zero=False)
        self.rest = _interval(rest, "rest", allow_zero=True)
        rng = np.random.default_rng(int(seed))
        if start is None:
            start_arr = rng.uniform(lower_arr, upper_arr)
        else:
            start_arr = per_joint(start, n_dof, "start", "rad")
            _check_radians(start_arr, "start")
        self.seed = int(seed)
        self.lower = lower_arr
        self.upper = upper_arr
        self.max_velocity = vmax
        for arr in (lower_arr, upper_arr, vmax):
            arr.setflags(write=False)
        times, positions = self._draw_moves(rng, start_arr, total)
        self.via_points = QuinticViaPoints(
            times, positions, np.zeros_like(positions), np.zeros_like(positions)
        )

    def _draw_moves(
        self, rng: np.random.Generator, start: FloatArray, total: float
    ) -> tuple[FloatArray, FloatArray]:
        times, positions = [0.0], [start]
        t, q = 0.0, start
        while True:
            target = rng.uniform(self.lower, self.upper)
            fastest = float(np.max(_QUINTIC_PEAK_VELOCITY * np.abs(target - q) / self.max_velocity))
            move = max(rng.uniform(*self.segment_time), fastest)
            pause = rng.uniform(*self.rest)
            if t + move >= total:
                break
            t, q = t + move, target
            times.append(t)
            positions.append(q)
            if t + pause >= total:
                break
            if pause > 0.0:
                t += pause
                times.append(t)
                positions.append(q)
        if t < total:
            times.append(total)
            positions.append(q)
        return np.array(times), np.array(positions)

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return self.via_points.n_dof

    @property
    def duration(self) -> float:
        """Duration of the trajectory [s]."""
        return self.via_points.duration

    def _evaluate_inside(self, t: FloatArray) -> Evaluation:
        return self.via_points._evaluate_inside(t)
