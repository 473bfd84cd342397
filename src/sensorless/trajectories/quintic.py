"""Piecewise quintic trajectories through time-stamped via points (thesis Tables 5.1, 5.8).

Between consecutive via points each joint follows the fifth-order polynomial
that matches position, velocity and acceleration at both ends; the via points
come from arrays, from degrees, or from a table such as those of the thesis.
"""

from __future__ import annotations

import os
import re
from typing import IO

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from scipy.interpolate import BPoly

from .._validation import FloatArray, as_float_array, check_finite
from ..exceptions import DimensionError, InputValueError, LogFormatError
from .base import Evaluation, Trajectory, _check_radians, _vector, _with_shape

__all__ = ["QuinticViaPoints"]

_TIME_COLUMN = re.compile(r"^\s*time\s*(\(s\)|\[s\])?\s*$", re.IGNORECASE)
#: The shape of via-point velocities and accelerations, for error messages.
_LIKE = "the shape of positions (n_points, n_dof)"


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
        positions_arr = as_float_array(positions, "positions", "(n_points, n_dof)")
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
            velocities_arr = _with_shape(velocities, "velocities", positions_arr.shape, _LIKE)
        if accelerations is None:
            accelerations_arr = np.zeros_like(positions_arr)
        else:
            accelerations_arr = _with_shape(
                accelerations, "accelerations", positions_arr.shape, _LIKE
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
        arr = _vector(times, "times", "n_points", 2, "2 via points [s]")
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
        positions = as_float_array(positions_deg, "positions_deg", "(n_points, n_dof)")
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
