"""Joint-space reference trajectories: via points, random moves, Fourier, velocity sweeps.

Every trajectory is a :class:`Trajectory`: it has ``n_dof`` joints, lasts
``duration`` [s] from ``t = 0`` and gives the joint positions ``q`` [rad],
velocities ``qd`` [rad/s] and accelerations ``qdd`` [rad/s²] at any time with
:meth:`Trajectory.evaluate`, or on a regular grid with
:meth:`Trajectory.sample`. Time runs along axis 0.

Outside ``[0, duration]`` a trajectory holds still: before ``t = 0`` it stays
at ``q(0)`` and after ``t = duration`` at ``q(duration)``, both with zero
velocity and acceleration. A simulation that runs a little longer than its
reference therefore sees a robot commanded to stand still, not an
extrapolated polynomial.

Four families are provided.

:class:`QuinticViaPoints`
    The trajectories of the thesis (Tables 5.1 and 5.8): "a five-order
    polynomial passing through the given points", one quintic per joint and
    per segment between consecutive time-stamped via points, matching
    position, velocity and acceleration at both ends of the segment.
:class:`RandomPointToPoint`
    Seeded random rest-to-rest quintic moves between uniformly drawn targets,
    with the duration of each move long enough to respect a velocity limit.
    Useful to tune thresholds on "a few different trajectories" (section 5.3).
:class:`FourierSeries`
    The finite Fourier series of Swevers et al. (1997), the usual
    parametrisation of excitation trajectories for identification.
:class:`VelocitySweep`
    One joint at a time at constant velocities, the friction experiments of
    section 2.4.1.

Examples
--------
>>> import numpy as np
>>> from sensorless.trajectories import QuinticViaPoints
>>> traj = QuinticViaPoints.from_degrees([0.0, 1.0, 2.0], [[0.0], [90.0], [0.0]])
>>> q, qd, qdd = traj.evaluate(1.0)
>>> float(np.rad2deg(q[0])), float(qd[0])
(90.0, 0.0)
>>> t, q, qd, qdd = traj.sample(0.5)
>>> t
array([0. , 0.5, 1. , 1.5, 2. ])
>>> q.shape
(5, 1)
"""

from __future__ import annotations

import os
import re
from abc import ABC, abstractmethod
from collections.abc import Mapping
from typing import IO, Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from scipy.interpolate import BPoly

from ._validation import FloatArray, check_dt, check_finite
from .exceptions import DimensionError, InputTypeError, InputValueError, LogFormatError

__all__ = [
    "FourierSeries",
    "QuinticViaPoints",
    "RandomPointToPoint",
    "Trajectory",
    "VelocitySweep",
]

Evaluation = tuple[FloatArray, FloatArray, FloatArray]

#: Largest joint angle accepted as radians [rad]; a full turn plus round-off.
_MAX_RADIANS = 2.0 * np.pi + 1e-9
#: Peak velocity of a rest-to-rest quintic over a move of size 1 lasting 1 s.
_QUINTIC_PEAK_VELOCITY = 15.0 / 8.0
_TIME_COLUMN = re.compile(r"^\s*time\s*(\(s\)|\[s\])?\s*$", re.IGNORECASE)


def _as_float_array(x: ArrayLike, name: str, shape: str) -> FloatArray:
    try:
        return np.array(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise DimensionError(
            f"{name} must be a numeric array of shape {shape}; could not convert it: {exc}"
        ) from None


def _per_joint(x: ArrayLike, n_dof: int, name: str) -> FloatArray:
    """Broadcast a scalar or an array of shape ``(n_dof,)`` to shape ``(n_dof,)``."""
    arr = _as_float_array(x, name, f"() or ({n_dof},)")
    if arr.ndim == 0:
        arr = np.full(n_dof, float(arr))
    if arr.shape != (n_dof,):
        raise DimensionError(
            f"{name} must be a scalar or have shape ({n_dof},) for {n_dof} joints; "
            f"got shape {arr.shape}"
        )
    check_finite(arr, name)
    return arr


def _check_radians(angles: FloatArray, name: str) -> None:
    """Reject angles that cannot be radians of a revolute joint (|q| > 2π)."""
    too_large = np.abs(angles) > _MAX_RADIANS
    if too_large.any():
        index = tuple(int(i) for i in np.argwhere(too_large)[0])
        raise InputValueError(
            f"{name} must be in radians with |angle| <= 2π ≈ 6.2832; got "
            f"{angles[index]:.6g} at index {index}, which looks like degrees. Convert with "
            "np.deg2rad, or use QuinticViaPoints.from_degrees / from_table(..., degrees=True)"
        )


def _positive_scalar(x: float, name: str, unit: str) -> float:
    try:
        value = float(x)
    except (TypeError, ValueError):
        raise InputValueError(f"{name} must be a positive number [{unit}]; got {x!r}") from None
    if not np.isfinite(value) or value <= 0.0:
        raise InputValueError(f"{name} must be a positive, finite number [{unit}]; got {x!r}")
    return value


def _interval(pair: tuple[float, float], name: str, *, allow_zero: bool) -> tuple[float, float]:
    """Check a ``(min, max)`` pair of durations [s]."""
    arr = _as_float_array(pair, name, "(2,)")
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


def _heuristic_velocities(times: FloatArray, positions: FloatArray) -> FloatArray:
    """Via-point velocities [rad/s] by the heuristic of Craig (2005, §7.3) and Corke.

    Zero at the first and last point. At an interior point, the average of
    the slopes of the two adjacent segments when both have the same sign,
    zero when they differ in sign or one of them is zero (the joint turns
    back or dwells there).
    """
    slopes = np.diff(positions, axis=0) / np.diff(times)[:, None]
    before, after = slopes[:-1], slopes[1:]
    same_sign = np.sign(before) * np.sign(after) > 0.0
    velocities = np.zeros_like(positions)
    velocities[1:-1] = np.where(same_sign, 0.5 * (before + after), 0.0)
    return velocities


class Trajectory(ABC):
    """Joint-space reference trajectory ``q(t)`` on ``0 <= t <= duration``.

    Subclasses implement :attr:`n_dof`, :attr:`duration` and
    :meth:`_evaluate_inside`; this class handles input checks, the scalar or
    array time argument and the hold outside ``[0, duration]``.
    """

    @property
    @abstractmethod
    def n_dof(self) -> int:
        """Number of joints."""

    @property
    @abstractmethod
    def duration(self) -> float:
        """Duration of the trajectory [s]; it starts at ``t = 0``."""

    @abstractmethod
    def _evaluate_inside(self, t: FloatArray) -> Evaluation:
        """Return ``q, qd, qdd`` of shape ``(n, n_dof)`` for ``t`` of shape ``(n,)`` in range."""

    def evaluate(self, t: ArrayLike) -> Evaluation:
        """Joint positions, velocities and accelerations at time(s) ``t``.

        Parameters
        ----------
        t : float or array-like of shape (n_samples,)
            Time(s) [s]. Outside ``[0, duration]`` the trajectory holds
            ``q(0)`` (before) or ``q(duration)`` (after) with zero velocity
            and acceleration.

        Returns
        -------
        q : ndarray of shape (n_dof,) or (n_samples, n_dof)
            Joint positions [rad].
        qd : ndarray of shape (n_dof,) or (n_samples, n_dof)
            Joint velocities [rad/s].
        qdd : ndarray of shape (n_dof,) or (n_samples, n_dof)
            Joint accelerations [rad/s²].
            Each has shape ``(n_dof,)`` when ``t`` is a scalar.

        Raises
        ------
        DimensionError
            If ``t`` is not a scalar or a one-dimensional array.
        InputValueError
            If ``t`` contains NaN or inf.
        """
        t_arr = _as_float_array(t, "t", "() or (n_samples,)")
        if t_arr.ndim > 1:
            raise DimensionError(
                f"t must be a scalar or have shape (n_samples,) [s]; got shape {t_arr.shape}"
            )
        scalar = t_arr.ndim == 0
        times = np.atleast_1d(t_arr)
        check_finite(times, "t")
        q, qd, qdd = self._evaluate_inside(np.clip(times, 0.0, self.duration))
        outside = (times < 0.0) | (times > self.duration)
        qd[outside] = 0.0
        qdd[outside] = 0.0
        if scalar:
            return q[0], qd[0], qdd[0]
        return q, qd, qdd

    def sample(self, dt: float) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Sample the trajectory on the regular grid ``0, dt, 2 dt, ... <= duration``.

        Parameters
        ----------
        dt : float
            Sample period [s], positive and finite.

        Returns
        -------
        t : ndarray of shape (n_samples,)
            Sample times [s]; the last one is at most ``duration`` (a grid
            point within round-off of ``duration`` is placed on it).
        q : ndarray of shape (n_samples, n_dof)
            Joint positions [rad].
        qd : ndarray of shape (n_samples, n_dof)
            Joint velocities [rad/s].
        qdd : ndarray of shape (n_samples, n_dof)
            Joint accelerations [rad/s²].
        """
        dt = check_dt(dt)
        n_samples = int(np.floor(self.duration / dt + 1e-9)) + 1
        t = dt * np.arange(n_samples, dtype=np.float64)
        t[-1] = min(t[-1], self.duration)
        q, qd, qdd = self.evaluate(t)
        return t, q, qd, qdd

    def __repr__(self) -> str:
        return f"{type(self).__name__}(n_dof={self.n_dof}, duration={self.duration:g})"


class QuinticViaPoints(Trajectory):
    """Piecewise quintic through time-stamped via points (thesis Tables 5.1, 5.8).

    Between consecutive via points each joint follows the unique fifth-order
    polynomial that matches the position, velocity and acceleration at both
    ends of the segment, so ``q``, ``qd`` and ``qdd`` are continuous.

    Parameters
    ----------
    times : array-like of shape (n_points,)
        Via-point times [s]: finite, strictly increasing, starting at 0.
    positions : array-like of shape (n_points, n_dof)
        Via-point joint positions [rad]; ``|q| <= 2π`` (larger values are
        taken for degrees and rejected).
    velocities : array-like of shape (n_points, n_dof), optional
        Via-point joint velocities [rad/s]. By default zero at the first and
        last point and, at an interior point, the average of the slopes
        ``Δq/Δt`` of the two adjacent segments when they have the same sign
        and zero otherwise (the heuristic of Craig, *Introduction to
        Robotics*, §7.3, also used by Corke's ``mstraj``).
    accelerations : array-like of shape (n_points, n_dof), optional
        Via-point joint accelerations [rad/s²]; zero by default.

    Raises
    ------
    DimensionError
        If an array has the wrong shape or fewer than two via points are given.
    InputValueError
        If a value is NaN or inf, the times do not start at 0 or are not
        strictly increasing, or a position looks like degrees.

    See Also
    --------
    scipy.interpolate.BPoly.from_derivatives : the piecewise polynomial used.

    Examples
    --------
    >>> import numpy as np
    >>> traj = QuinticViaPoints([0.0, 2.0], [[0.0, 0.0], [1.0, -1.0]])
    >>> q, qd, qdd = traj.evaluate([0.0, 1.0, 2.0])
    >>> q
    array([[ 0. ,  0. ],
           [ 0.5, -0.5],
           [ 1. , -1. ]])
    >>> float(qd[1, 0])  # peak velocity 15/8 · Δq / T
    0.9375
    """

    def __init__(
        self,
        times: ArrayLike,
        positions: ArrayLike,
        velocities: ArrayLike | None = None,
        accelerations: ArrayLike | None = None,
    ) -> None:
        times_arr = self._check_times(times)
        n_points = times_arr.size
        positions_arr = _as_float_array(positions, "positions", "(n_points, n_dof)")
        if positions_arr.ndim != 2 or positions_arr.shape[0] != n_points:
            raise DimensionError(
                f"positions must have shape (n_points, n_dof) = ({n_points}, n_dof) for "
                f"{n_points} via-point times; got shape {positions_arr.shape}"
            )
        if positions_arr.shape[1] == 0:
            raise DimensionError("positions must have at least one joint column; got 0")
        check_finite(positions_arr, "positions")
        _check_radians(positions_arr, "positions")
        if velocities is None:
            velocities_arr = _heuristic_velocities(times_arr, positions_arr)
        else:
            velocities_arr = self._check_points(velocities, positions_arr.shape, "velocities")
        if accelerations is None:
            accelerations_arr = np.zeros_like(positions_arr)
        else:
            accelerations_arr = self._check_points(
                accelerations, positions_arr.shape, "accelerations"
            )
        self._times = times_arr
        self._positions = positions_arr
        self._velocities = velocities_arr
        self._accelerations = accelerations_arr
        for arr in (times_arr, positions_arr, velocities_arr, accelerations_arr):
            arr.setflags(write=False)
        # Derivatives at each point stacked as (n_points, 3, n_dof): BPoly then
        # builds one quintic per segment and joint.
        conditions = np.stack([positions_arr, velocities_arr, accelerations_arr], axis=1)
        self._q = BPoly.from_derivatives(times_arr, conditions)
        self._qd = self._q.derivative(1)
        self._qdd = self._q.derivative(2)

    @staticmethod
    def _check_times(times: ArrayLike) -> FloatArray:
        arr = _as_float_array(times, "times", "(n_points,)")
        if arr.ndim != 1 or arr.size < 2:
            raise DimensionError(
                f"times must have shape (n_points,) with at least 2 via points [s]; "
                f"got shape {arr.shape}"
            )
        check_finite(arr, "times")
        if arr[0] != 0.0:
            raise InputValueError(f"times must start at 0 s; got times[0] = {arr[0]:g} s")
        steps = np.diff(arr)
        if (steps <= 0.0).any():
            k = int(np.argmax(steps <= 0.0))
            raise InputValueError(
                f"times must be strictly increasing [s]; got times[{k}] = {arr[k]:g} followed "
                f"by times[{k + 1}] = {arr[k + 1]:g}"
            )
        return arr

    @staticmethod
    def _check_points(x: ArrayLike, shape: tuple[int, ...], name: str) -> FloatArray:
        arr = _as_float_array(x, name, f"{shape}")
        if arr.shape != shape:
            raise DimensionError(
                f"{name} must have the shape of positions (n_points, n_dof) = {shape}; "
                f"got shape {arr.shape}"
            )
        check_finite(arr, name)
        return arr

    @classmethod
    def from_degrees(cls, times: ArrayLike, positions_deg: ArrayLike) -> QuinticViaPoints:
        """Build from via-point positions in degrees, with the default velocities.

        Parameters
        ----------
        times : array-like of shape (n_points,)
            Via-point times [s].
        positions_deg : array-like of shape (n_points, n_dof)
            Via-point joint positions [deg], converted to radians.
        """
        positions = _as_float_array(positions_deg, "positions_deg", "(n_points, n_dof)")
        return cls(times, np.deg2rad(positions))

    @classmethod
    def from_table(
        cls,
        table: pd.DataFrame | str | os.PathLike[str] | IO[str],
        degrees: bool = True,
        repeat: int = 1,
    ) -> QuinticViaPoints:
        """Build from a table of via points such as thesis Tables 5.1 and 5.8.

        Parameters
        ----------
        table : DataFrame, path or text stream
            The via points. The first column is the time [s], named ``time``
            (``time(s)`` and ``time [s]`` are accepted too); every other
            column is one joint, in joint order. A path or stream is read as
            delimited text (comma, semicolon or tab separated).
        degrees : bool, default True
            Whether the joint columns are in degrees, as in the thesis tables.
            With ``degrees=False`` they are radians, and any ``|angle| > 2π``
            is rejected as probably being degrees.
        repeat : int, default 1
            Number of periods played back to back; the duration is
            ``repeat`` times that of the table. The last via point must equal
            the first. Each period is an exact copy of the first: the default
            velocities of one period are computed once (zero at its ends) and
            repeated, so the trajectory is periodic and passes through the
            start point at rest, with ``q``, ``qd``, ``qdd`` continuous there.

        Returns
        -------
        QuinticViaPoints
            The trajectory with default via-point velocities and zero
            accelerations.

        Raises
        ------
        LogFormatError
            If the first column is not ``time``, there is no joint column or
            a value is not numeric.
        InputValueError
            If ``repeat`` is not a positive integer, the last via point differs
            from the first with ``repeat > 1``, or for the checks of the
            constructor.

        Examples
        --------
        >>> import io
        >>> text = "time,q1\\n0,0\\n1,90\\n2,0\\n"
        >>> traj = QuinticViaPoints.from_table(io.StringIO(text), repeat=3)
        >>> traj.duration
        6.0
        """
        if isinstance(repeat, bool) or not isinstance(repeat, (int, np.integer)) or repeat < 1:
            raise InputValueError(f"repeat must be a positive integer; got {repeat!r}")
        frame = table if isinstance(table, pd.DataFrame) else cls._read_table(table)
        times, positions = cls._split_table(frame)
        if degrees:
            positions = np.deg2rad(positions)
        else:
            _check_radians(positions, "positions (degrees=False)")
        if repeat == 1:
            return cls(times, positions)
        check_finite(positions, "positions")
        mismatch = np.abs(positions[-1] - positions[0])
        if (mismatch > 1e-9).any():
            joint = int(np.argmax(mismatch))
            raise InputValueError(
                f"repeat={repeat} needs the last via point equal to the first for a seamless "
                f"repeat; joint {joint} starts at {positions[0, joint]:.6g} rad and ends at "
                f"{positions[-1, joint]:.6g} rad"
            )
        times = cls._check_times(times)
        velocities = _heuristic_velocities(times, positions)
        period = times[-1]
        all_times = np.concatenate([times] + [times[1:] + k * period for k in range(1, repeat)])
        tail = [slice(1, None)] * (repeat - 1)
        all_positions = np.concatenate([positions] + [positions[s] for s in tail])
        all_velocities = np.concatenate([velocities] + [velocities[s] for s in tail])
        return cls(all_times, all_positions, all_velocities)

    @staticmethod
    def _read_table(source: str | os.PathLike[str] | IO[str]) -> pd.DataFrame:
        try:
            return pd.read_csv(source, sep=r"\s*[,;\t]\s*", engine="python")
        except (pd.errors.ParserError, pd.errors.EmptyDataError, UnicodeDecodeError) as exc:
            raise LogFormatError(f"could not read the via-point table {source!r}: {exc}") from None

    @staticmethod
    def _split_table(frame: pd.DataFrame) -> tuple[FloatArray, FloatArray]:
        columns = [str(c) for c in frame.columns]
        if not columns or not _TIME_COLUMN.match(columns[0]):
            raise LogFormatError(
                "the first column of a via-point table must be 'time' [s] followed by one "
                f"column per joint; got columns {columns}"
            )
        if len(columns) < 2:
            raise LogFormatError(
                f"a via-point table needs at least one joint column after 'time'; got {columns}"
            )
        try:
            values = frame.to_numpy(dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise LogFormatError(
                f"every entry of a via-point table must be numeric; columns {columns}: {exc}"
            ) from None
        return values[:, 0], values[:, 1:]

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return int(self._positions.shape[1])

    @property
    def duration(self) -> float:
        """Time of the last via point [s]."""
        return float(self._times[-1])

    @property
    def times(self) -> FloatArray:
        """Via-point times [s], shape (n_points,); read-only."""
        return self._times

    @property
    def positions(self) -> FloatArray:
        """Via-point joint positions [rad], shape (n_points, n_dof); read-only."""
        return self._positions

    @property
    def velocities(self) -> FloatArray:
        """Via-point joint velocities [rad/s], shape (n_points, n_dof); read-only."""
        return self._velocities

    @property
    def accelerations(self) -> FloatArray:
        """Via-point joint accelerations [rad/s²], shape (n_points, n_dof); read-only."""
        return self._accelerations

    def _evaluate_inside(self, t: FloatArray) -> Evaluation:
        return (
            np.asarray(self._q(t), dtype=np.float64),
            np.asarray(self._qd(t), dtype=np.float64),
            np.asarray(self._qdd(t), dtype=np.float64),
        )


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
        total = _positive_scalar(duration, "duration", "s")
        lower_arr = _per_joint(lower, n_dof, "lower")
        upper_arr = _per_joint(upper, n_dof, "upper")
        _check_radians(lower_arr, "lower")
        _check_radians(upper_arr, "upper")
        if (lower_arr > upper_arr).any():
            j = int(np.argmax(lower_arr > upper_arr))
            raise InputValueError(
                f"lower must not exceed upper; joint {j} has lower = {lower_arr[j]:.6g} rad > "
                f"upper = {upper_arr[j]:.6g} rad"
            )
        vmax = _per_joint(max_velocity, n_dof, "max_velocity")
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
            start_arr = _per_joint(start, n_dof, "start")
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


class FourierSeries(Trajectory):
    """Finite Fourier series excitation trajectory of Swevers et al. (1997).

    .. math::

        q_j(t) = q_{0,j} + \\sum_{l=1}^{N} \\frac{a_{lj}}{\\omega_f l} \\sin(\\omega_f l t)
                 - \\frac{b_{lj}}{\\omega_f l} \\cos(\\omega_f l t),
        \\qquad \\omega_f = 2 \\pi f,

    with analytic velocity and acceleration. The motion is periodic with
    period ``1 / base_frequency``. Note that ``q(0) = q0 - Σ_l b_l / (ω_f l)``.

    Parameters
    ----------
    base_frequency : float
        Fundamental frequency ``f`` [Hz], positive.
    a, b : array-like of shape (n_harmonics, n_dof)
        Sine and cosine coefficients [rad/s]; row ``l - 1`` is harmonic ``l``.
    q0 : array-like of shape (n_dof,)
        Offset of the joint positions [rad].
    duration : float, optional
        Duration [s]; one period ``1 / base_frequency`` by default.

    References
    ----------
    J. Swevers, C. Ganseman, D. B. Tükel, J. De Schutter, H. Van Brussel,
    "Optimal robot excitation and identification", IEEE Trans. Robotics and
    Automation 13(5), 1997.

    Examples
    --------
    >>> traj = FourierSeries(0.5, a=[[1.0]], b=[[0.0]], q0=[0.0])
    >>> q, qd, qdd = traj.evaluate(0.0)
    >>> float(qd[0])
    1.0
    """

    def __init__(
        self,
        base_frequency: float,
        a: ArrayLike,
        b: ArrayLike,
        q0: ArrayLike,
        duration: float | None = None,
    ) -> None:
        self.base_frequency = _positive_scalar(base_frequency, "base_frequency", "Hz")
        a_arr = _as_float_array(a, "a", "(n_harmonics, n_dof)")
        if a_arr.ndim != 2 or 0 in a_arr.shape:
            raise DimensionError(
                f"a must have shape (n_harmonics, n_dof) with at least one harmonic and joint; "
                f"got shape {a_arr.shape}"
            )
        b_arr = _as_float_array(b, "b", "(n_harmonics, n_dof)")
        if b_arr.shape != a_arr.shape:
            raise DimensionError(
                f"b must have the shape of a (n_harmonics, n_dof) = {a_arr.shape}; "
                f"got shape {b_arr.shape}"
            )
        q0_arr = _as_float_array(q0, "q0", f"({a_arr.shape[1]},)")
        if q0_arr.shape != (a_arr.shape[1],):
            raise DimensionError(
                f"q0 must have shape (n_dof,) = ({a_arr.shape[1]},) to match a; "
                f"got shape {q0_arr.shape}"
            )
        for arr, name in ((a_arr, "a"), (b_arr, "b"), (q0_arr, "q0")):
            check_finite(arr, name)
            arr.setflags(write=False)
        self.a = a_arr
        self.b = b_arr
        self.q0 = q0_arr
        period = 1.0 / self.base_frequency
        self._duration = period if duration is None else _positive_scalar(duration, "duration", "s")

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return int(self.a.shape[1])

    @property
    def duration(self) -> float:
        """Duration of the trajectory [s]."""
        return self._duration

    @property
    def n_harmonics(self) -> int:
        """Number of harmonics ``N``."""
        return int(self.a.shape[0])

    def to_dict(self) -> dict[str, Any]:
        """The series as plain Python values, SI units, for a YAML or JSON file.

        Returns
        -------
        dict
            ``{"type": "fourier", "base_frequency": f [Hz], "duration": T [s],
            "offset": q0 [rad] (n_dof list), "a": [rad/s] and "b": [rad/s]
            (n_harmonics lists of n_dof)}``; :meth:`from_dict` rebuilds the
            identical series (floats are written with all their digits).

        Examples
        --------
        >>> FourierSeries(0.5, a=[[1.0]], b=[[0.0]], q0=[0.2]).to_dict()["offset"]
        [0.2]
        """
        return {
            "type": "fourier",
            "base_frequency": float(self.base_frequency),
            "duration": float(self.duration),
            "offset": [float(v) for v in self.q0],
            "a": [[float(v) for v in row] for row in self.a],
            "b": [[float(v) for v in row] for row in self.b],
        }

    @classmethod
    def from_dict(cls, spec: Mapping[str, Any]) -> FourierSeries:
        """Build from a specification such as :meth:`to_dict` writes.

        Parameters
        ----------
        spec : mapping
            Keys ``base_frequency`` [Hz], ``offset`` [rad] of length n_dof,
            ``a`` and ``b`` [rad/s] of shape (n_harmonics, n_dof); optional
            ``duration`` [s] (one period by default) and ``type``, which must
            be ``"fourier"`` when present.

        Returns
        -------
        FourierSeries

        Raises
        ------
        InputTypeError
            If ``spec`` is not a mapping or has keys other than those above.
        InputValueError
            If a required key is missing or ``type`` is not ``"fourier"``, or
            for the checks of the constructor.

        Examples
        --------
        >>> spec = {"type": "fourier", "base_frequency": 0.5, "offset": [0.0],
        ...         "a": [[1.0]], "b": [[0.0]]}
        >>> FourierSeries.from_dict(spec).duration
        2.0
        """
        required = ("base_frequency", "offset", "a", "b")
        optional = ("type", "duration")
        if not isinstance(spec, Mapping):
            raise InputTypeError(
                f"a Fourier trajectory specification must be a mapping with keys "
                f"{list(required)}; got {type(spec).__name__}"
            )
        unknown = sorted(str(key) for key in spec if key not in required + optional)
        if unknown:
            raise InputTypeError(
                f"unknown keys {unknown} in a Fourier trajectory specification; valid keys: "
                f"{list(required + optional)}"
            )
        missing = [key for key in required if key not in spec]
        if missing:
            raise InputValueError(
                f"a Fourier trajectory specification needs keys {list(required)}; missing {missing}"
            )
        kind = spec.get("type", "fourier")
        if kind != "fourier":
            raise InputValueError(
                f"type must be 'fourier' for a FourierSeries specification; got {kind!r}"
            )
        return cls(
            spec["base_frequency"], spec["a"], spec["b"], spec["offset"], spec.get("duration")
        )

    def _evaluate_inside(self, t: FloatArray) -> Evaluation:
        omega = 2.0 * np.pi * self.base_frequency * np.arange(1, self.n_harmonics + 1)
        phase = np.outer(t, omega)
        sin, cos = np.sin(phase), np.cos(phase)
        q = self.q0 + sin @ (self.a / omega[:, None]) - cos @ (self.b / omega[:, None])
        qd = cos @ self.a + sin @ self.b
        qdd = -sin @ (self.a * omega[:, None]) + cos @ (self.b * omega[:, None])
        return q, qd, qdd


def _ramp_shape(tau: FloatArray) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Cosine ramp ``s(τ) = (1 - cos πτ) / 2`` on ``0 <= τ <= 1``: its integral, value, slope.

    ``s`` goes from 0 to 1 with zero slope at both ends, so a velocity
    ``v0 + (v1 - v0) s`` joins two plateaus with a continuous acceleration.
    """
    integral = 0.5 * tau - np.sin(np.pi * tau) / (2.0 * np.pi)
    value = 0.5 * (1.0 - np.cos(np.pi * tau))
    slope = 0.5 * np.pi * np.sin(np.pi * tau)
    return integral, value, slope


def _limit(x: ArrayLike, n_dof: int, name: str) -> FloatArray:
    """One side of joint limits [rad], scalar or (n_dof,); ±inf (no stop) allowed, NaN not."""
    arr = _as_float_array(x, f"position_limits {name}", f"() or ({n_dof},)")
    if arr.ndim == 0:
        arr = np.full(n_dof, float(arr))
    if arr.shape != (n_dof,):
        raise DimensionError(
            f"position_limits {name} must be a scalar or have shape ({n_dof},) [rad]; "
            f"got shape {arr.shape}"
        )
    if np.isnan(arr).any():
        raise InputValueError(f"position_limits {name} must not contain NaN; got {arr.tolist()}")
    return arr


class VelocitySweep(Trajectory):
    """Constant-velocity friction experiment: one joint at a time (thesis §2.4.1-2.4.2).

    Each joint of ``joints`` in turn visits every velocity of
    ``velocities`` as a plateau of ``hold`` seconds while the other joints
    rest at ``home``. Consecutive plateaus are joined by cosine velocity
    ramps of ``ramp`` seconds, ``qd = v0 + (v1 - v0) (1 - cos πτ) / 2`` with
    ``τ`` from 0 to 1, so the acceleration is continuous, zero on the
    plateaus and at most ``π |v1 - v0| / (2 ramp)`` [rad/s²].

    The velocities must come in pairs ``+v, -v``: each joint visits the
    speeds in increasing order, ``+v`` then ``-v`` for each, so every pair
    goes out and comes back by the same distance ``v · hold``, and the ramp
    displacements cancel over the sequence; the joint ends its sweep at rest
    at ``home``. The excursion of a pair is one-sided, of about
    ``v (hold + ramp)``; it is put on the side of ``home`` with more room in
    ``position_limits`` (the sign order becomes ``-v, +v`` when there is more
    room below). The exact travel is checked at construction.

    Parameters
    ----------
    home : array-like of shape (n_dof,)
        Rest pose [rad]; every joint starts and ends its sweep there.
    joints : int or sequence of int, optional
        Joints to sweep, numbered from 1, in the order given; all joints by
        default.
    velocities : array-like of shape (n_velocities,), optional
        Plateau velocities [rad/s], nonzero, in pairs ``+v, -v`` (matched
        to 1e-9 rad/s; the negative ones are then taken as the exact mirror
        of the positive ones); duplicates are dropped. By default the thesis's
        :func:`sensorless.identification.friction.sweep_velocities`.
    hold : float, default 1.0
        Duration of each plateau [s].
    ramp : float, default 0.5
        Duration of each velocity ramp between plateaus [s].
    position_limits : (lower, upper), optional
        Joint limits [rad], each a float or an array of shape (n_dof,),
        e.g. ``robot.position_limits``. ``home`` must lie inside them and
        the sweep must stay inside them. No travel check by default.

    Raises
    ------
    DimensionError
        If an array has the wrong shape.
    InputValueError
        If ``joints`` is not a list of distinct joint numbers in
        ``1..n_dof``, a velocity is zero or lacks its opposite, ``hold`` or
        ``ramp`` is not positive, ``home`` is outside ``position_limits``, or
        a joint would leave ``position_limits`` during its sweep.

    Examples
    --------
    >>> sweep = VelocitySweep([0.0, 0.5], joints=[2], velocities=[-0.2, 0.2], hold=2.0)
    >>> sweep.schedule()
       joint  velocity  start  end
    0      2       0.2    0.5  2.5
    1      2      -0.2    3.0  5.0
    >>> q, qd, qdd = sweep.evaluate(1.5)
    >>> float(qd[1]), float(qdd[1]), float(q[0])
    (0.2, 0.0, 0.0)
    >>> float(sweep.evaluate(sweep.duration)[0][1])  # back home
    0.5
    """

    def __init__(
        self,
        home: ArrayLike,
        joints: int | ArrayLike | None = None,
        velocities: ArrayLike | None = None,
        *,
        hold: float = 1.0,
        ramp: float = 0.5,
        position_limits: tuple[ArrayLike, ArrayLike] | None = None,
    ) -> None:
        home_arr = _as_float_array(home, "home", "(n_dof,)")
        if home_arr.ndim != 1 or home_arr.size == 0:
            raise DimensionError(
                f"home must have shape (n_dof,) with at least one joint [rad]; "
                f"got shape {home_arr.shape}"
            )
        check_finite(home_arr, "home")
        _check_radians(home_arr, "home")
        n_dof = home_arr.size
        if velocities is None:
            # Imported here: the identification package imports this module.
            from .identification.friction import sweep_velocities

            velocities = sweep_velocities()
        self.home = home_arr
        self.joints = self._check_joints(joints, n_dof)
        self.velocities = self._check_velocities(velocities)
        self.hold = _positive_scalar(hold, "hold", "s")
        self.ramp = _positive_scalar(ramp, "ramp", "s")
        self.position_limits = self._check_limits(position_limits, home_arr)
        for arr in (self.home, self.velocities, *self.position_limits):
            arr.setflags(write=False)
        self._build_segments()
        self._check_travel()

    @staticmethod
    def _check_joints(joints: int | ArrayLike | None, n_dof: int) -> tuple[int, ...]:
        if joints is None:
            return tuple(range(1, n_dof + 1))
        values = np.atleast_1d(np.asarray(joints))
        valid = values.ndim == 1 and values.size > 0 and values.dtype.kind in "iu"
        if not valid or np.any((values < 1) | (values > n_dof)):
            raise InputValueError(
                f"joints must be joint numbers from 1 to n_dof = {n_dof}; got {joints!r}"
            )
        if np.unique(values).size != values.size:
            raise InputValueError(f"joints must be distinct; got {values.tolist()}")
        return tuple(int(j) for j in values)

    @staticmethod
    def _check_velocities(velocities: ArrayLike) -> FloatArray:
        arr = _as_float_array(velocities, "velocities", "(n_velocities,)")
        if arr.ndim != 1 or arr.size == 0:
            raise DimensionError(
                f"velocities must have shape (n_velocities,) with at least one pair +v, -v "
                f"[rad/s]; got shape {arr.shape}"
            )
        check_finite(arr, "velocities")
        if (arr == 0.0).any():
            raise InputValueError(
                f"velocities must be nonzero [rad/s] (a zero velocity is a rest, not a friction "
                f"measurement); got 0 at index {int(np.argmax(arr == 0.0))}"
            )
        positive, negative = np.unique(arr[arr > 0.0]), np.unique(-arr[arr < 0.0])
        matched = np.abs(positive[:, None] - negative[None, :]) <= 1e-9
        unpaired = [*positive[~matched.any(axis=1)], *(-negative[~matched.any(axis=0)])]
        if unpaired:
            raise InputValueError(
                "velocities must come in pairs +v, -v so that each joint returns home; "
                f"got no opposite for {sorted(float(v) for v in unpaired)} rad/s"
            )
        return np.concatenate([-positive[::-1], positive])

    @staticmethod
    def _check_limits(
        limits: tuple[ArrayLike, ArrayLike] | None, home: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        n_dof = home.size
        if limits is None:
            return np.full(n_dof, -np.inf), np.full(n_dof, np.inf)
        if len(limits) != 2:
            raise DimensionError(
                f"position_limits must be a pair (lower, upper) [rad]; got {len(limits)} items"
            )
        lower = _limit(limits[0], n_dof, "lower")
        upper = _limit(limits[1], n_dof, "upper")
        if (lower >= upper).any():
            j = int(np.argmax(lower >= upper))
            raise InputValueError(
                f"position_limits must have lower < upper [rad]; joint {j + 1} has "
                f"[{lower[j]:.6g}, {upper[j]:.6g}]"
            )
        outside = (home < lower) | (home > upper)
        if outside.any():
            j = int(np.argmax(outside))
            raise InputValueError(
                f"home must lie inside position_limits; joint {j + 1} has home = "
                f"{home[j]:.6g} rad, limits [{lower[j]:.6g}, {upper[j]:.6g}] rad"
            )
        return lower, upper

    def _build_segments(self) -> None:
        """Segments ``(start, duration, joint index, v0, v1, q0)``: plateaus and ramps."""
        lower, upper = self.position_limits
        speeds = self.velocities[self.velocities > 0.0]
        rows: list[tuple[float, float, int, float, float, float]] = []
        t = 0.0
        for joint in self.joints:
            j = joint - 1
            # The excursion of each pair goes to the side of home with more room.
            first = 1.0 if upper[j] - self.home[j] >= self.home[j] - lower[j] else -1.0
            plateaus = np.ravel(np.column_stack([first * speeds, -first * speeds])).tolist()
            q = float(self.home[j])
            segments = [(0.0, plateaus[0], self.ramp)]
            for v, following in zip(plateaus, [*plateaus[1:], 0.0], strict=True):
                segments += [(v, v, self.hold), (v, following, self.ramp)]
            for v0, v1, length in segments:
                rows.append((t, length, j, v0, v1, q))
                t += length
                q += 0.5 * length * (v0 + v1)
        table = np.array(rows)
        self._start = table[:, 0]
        self._length = table[:, 1]
        self._joint = table[:, 2].astype(np.intp)
        self._v0, self._v1, self._q0 = table[:, 3], table[:, 4], table[:, 5]
        self._duration = t

    def _segment_extremes(self) -> tuple[FloatArray, FloatArray]:
        """Lowest and highest position [rad] of each segment (exact)."""
        end = self._q0 + 0.5 * self._length * (self._v0 + self._v1)
        low, high = np.minimum(self._q0, end), np.maximum(self._q0, end)
        reverses = self._v0 * self._v1 < 0.0
        # Where a ramp reverses, the position turns at s(τ) = v0 / (v0 - v1).
        s = np.where(reverses, self._v0 / np.where(reverses, self._v0 - self._v1, 1.0), 0.0)
        tau = np.arccos(1.0 - 2.0 * s) / np.pi
        integral = _ramp_shape(tau)[0]
        turn = self._q0 + self._length * (self._v0 * tau + (self._v1 - self._v0) * integral)
        low = np.where(reverses, np.minimum(low, turn), low)
        high = np.where(reverses, np.maximum(high, turn), high)
        return low, high

    def _check_travel(self) -> None:
        lower, upper = self.position_limits
        low, high = self._segment_extremes()
        for joint in self.joints:
            mine = self._joint == joint - 1
            q_min, q_max = float(low[mine].min()), float(high[mine].max())
            j = joint - 1
            if q_min < lower[j] or q_max > upper[j]:
                fastest = float(self.velocities[-1])
                raise InputValueError(
                    f"joint {joint} would travel over [{q_min:.4g}, {q_max:.4g}] rad during "
                    f"its sweep, outside position_limits [{lower[j]:.4g}, {upper[j]:.4g}] rad "
                    f"(home {self.home[j]:.4g} rad); a plateau at {fastest:g} rad/s alone "
                    f"covers {fastest * self.hold:.4g} rad: shorten hold ({self.hold:g} s) or "
                    f"ramp ({self.ramp:g} s), or drop the fastest velocities"
                )

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return int(self.home.size)

    @property
    def duration(self) -> float:
        """Duration of the whole sweep [s]."""
        return self._duration

    def schedule(self) -> pd.DataFrame:
        """The constant-velocity plateaus in time order.

        Returns
        -------
        schedule : DataFrame
            One row per plateau with columns ``joint`` (numbered from 1),
            ``velocity`` [rad/s], ``start`` and ``end`` [s].
        """
        plateau = self._v0 == self._v1
        return pd.DataFrame(
            {
                "joint": self._joint[plateau] + 1,
                "velocity": self._v0[plateau],
                "start": self._start[plateau],
                "end": self._start[plateau] + self._length[plateau],
            }
        )

    def to_dict(self) -> dict[str, Any]:
        """The sweep as plain Python values, SI units, for a YAML or JSON file.

        Returns
        -------
        dict
            ``{"type": "velocity_sweep", "home": [rad], "joints": [...],
            "velocities": [rad/s], "hold": [s], "ramp": [s]}``; the position
            limits are not included (a scenario takes them from its robot).
            :meth:`from_dict` rebuilds the same sweep.
        """
        return {
            "type": "velocity_sweep",
            "home": [float(v) for v in self.home],
            "joints": list(self.joints),
            "velocities": [float(v) for v in self.velocities],
            "hold": float(self.hold),
            "ramp": float(self.ramp),
        }

    @classmethod
    def from_dict(
        cls,
        spec: Mapping[str, Any],
        position_limits: tuple[ArrayLike, ArrayLike] | None = None,
    ) -> VelocitySweep:
        """Build from a specification such as :meth:`to_dict` writes or a scenario holds.

        Parameters
        ----------
        spec : mapping
            Key ``home`` [rad] (required); optional ``type`` (must be
            ``"velocity_sweep"``), ``joints``, ``hold`` [s], ``ramp`` [s],
            and either ``velocities`` [rad/s] or the sweep tuples ``fast``
            and/or ``slow`` ``[low, high, step]`` [rad/s] of
            :func:`~sensorless.identification.friction.sweep_velocities`
            (``slow: null`` keeps the fast sweep alone).
        position_limits : (lower, upper), optional
            Joint limits [rad] checked at construction.

        Returns
        -------
        VelocitySweep

        Raises
        ------
        InputTypeError
            If ``spec`` is not a mapping or has unknown keys.
        InputValueError
            If ``home`` is missing, ``type`` is wrong, ``velocities`` is
            given together with ``fast``/``slow``, or for the checks of the
            constructor.

        Examples
        --------
        >>> spec = {"home": [0.0], "fast": [-1.0, 1.0, 0.5], "slow": None, "hold": 0.5}
        >>> VelocitySweep.from_dict(spec).velocities
        array([-1. , -0.5,  0.5,  1. ])
        """
        keys = ("type", "home", "joints", "velocities", "fast", "slow", "hold", "ramp")
        if not isinstance(spec, Mapping):
            raise InputTypeError(
                f"a velocity sweep specification must be a mapping with keys {list(keys)}; "
                f"got {type(spec).__name__}"
            )
        unknown = sorted(str(key) for key in spec if key not in keys)
        if unknown:
            raise InputTypeError(
                f"unknown keys {unknown} in a velocity sweep specification; valid keys: "
                f"{list(keys)}"
            )
        if "home" not in spec:
            raise InputValueError("a velocity sweep specification needs the key 'home' [rad]")
        kind = spec.get("type", "velocity_sweep")
        if kind != "velocity_sweep":
            raise InputValueError(
                f"type must be 'velocity_sweep' for a VelocitySweep specification; got {kind!r}"
            )
        velocities = spec.get("velocities")
        if "fast" in spec or "slow" in spec:
            if velocities is not None:
                raise InputValueError(
                    "give either 'velocities' or the sweep tuples 'fast'/'slow', not both"
                )
            from .identification.friction import sweep_velocities

            fast = tuple(spec.get("fast", (-2.0, 2.0, 0.16)))
            slow = spec.get("slow", (-0.11, 0.11, 0.01))
            velocities = sweep_velocities(fast, fast if slow is None else tuple(slow))
        return cls(
            spec["home"],
            spec.get("joints"),
            velocities,
            hold=spec.get("hold", 1.0),
            ramp=spec.get("ramp", 0.5),
            position_limits=position_limits,
        )

    def _evaluate_inside(self, t: FloatArray) -> Evaluation:
        index = np.clip(np.searchsorted(self._start, t, side="right") - 1, 0, None)
        length = self._length[index]
        tau = np.clip((t - self._start[index]) / length, 0.0, 1.0)
        v0, dv = self._v0[index], self._v1[index] - self._v0[index]
        integral, value, slope = _ramp_shape(tau)
        rows = np.arange(t.size)
        columns = self._joint[index]
        q = np.tile(self.home, (t.size, 1))
        qd = np.zeros_like(q)
        qdd = np.zeros_like(q)
        q[rows, columns] = self._q0[index] + length * (v0 * tau + dv * integral)
        qd[rows, columns] = v0 + dv * value
        qdd[rows, columns] = dv * slope / length
        return q, qd, qdd
