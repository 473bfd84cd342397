"""The :class:`Trajectory` base class and the input checks its families share.

A trajectory evaluates ``q`` [rad], ``qd`` [rad/s] and ``qdd`` [rad/s²] on
``0 <= t <= duration``; this module adds the scalar or array time argument,
the hold outside that interval and sampling on a regular grid.
"""

from __future__ import annotations

from abc import ABC, abstractmethod

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_float_array, check_dt, check_finite
from ..exceptions import DimensionError, InputValueError

__all__ = ["Evaluation", "Trajectory"]

#: Joint positions [rad], velocities [rad/s] and accelerations [rad/s²].
Evaluation = tuple[FloatArray, FloatArray, FloatArray]

#: Largest joint angle accepted as radians [rad]; a full turn plus round-off.
_MAX_RADIANS = 2.0 * np.pi + 1e-9


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


def _vector(x: ArrayLike, name: str, length: str, minimum: int, least: str) -> FloatArray:
    """Convert ``x`` to a finite float array of shape ``(length,)`` with ``minimum`` entries.

    Parameters
    ----------
    x : array-like of shape (length,)
        The values.
    name : str
        Name used in error messages.
    length : str
        Name of the length in error messages, e.g. ``"n_points"``.
    minimum : int
        Fewest entries accepted.
    least : str
        What ``minimum`` entries are, with the unit, e.g. ``"2 via points [s]"``.
    """
    arr = as_float_array(x, name, f"({length},)")
    if arr.ndim != 1 or arr.size < minimum:
        raise DimensionError(
            f"{name} must have shape ({length},) with at least {least}; got shape {arr.shape}"
        )
    check_finite(arr, name)
    return arr


def _with_shape(x: ArrayLike, name: str, shape: tuple[int, ...], expected: str) -> FloatArray:
    """Convert ``x`` to a finite float array of shape ``shape``.

    ``expected`` describes the shape in the error message, e.g.
    ``"the shape of a (n_harmonics, n_dof)"``.
    """
    arr = as_float_array(x, name, f"{shape}")
    if arr.shape != shape:
        raise DimensionError(f"{name} must have {expected} = {shape}; got shape {arr.shape}")
    check_finite(arr, name)
    return arr


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
        t_arr = as_float_array(t, "t", "() or (n_samples,)")
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
