"""Input checks shared by the whole package.

Conventions checked here: arrays of joint quantities have shape ``(n_dof,)``
for one sample or ``(n_samples, n_dof)`` for a time series (time along
axis 0); values are finite; angles are radians; the sample period ``dt`` [s]
is positive and finite.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .exceptions import DimensionError, InputValueError

FloatArray = NDArray[np.float64]

__all__ = ["FloatArray", "as_joint_array", "check_dt", "check_finite"]


def check_finite(x: FloatArray, name: str) -> None:
    """Raise :class:`InputValueError` naming the first non-finite entry of ``x``."""
    finite = np.isfinite(x)
    if not finite.all():
        bad = np.argwhere(~finite)[0]
        where = f"sample {bad[0]}, joint {bad[1]}" if bad.size == 2 else f"index {tuple(bad)}"
        raise InputValueError(f"{name} must be finite; found {x[tuple(bad)]} at {where}")


def as_joint_array(
    x: ArrayLike, n_dof: int, name: str, *, allow_nonfinite: bool = False
) -> tuple[FloatArray, bool]:
    """Convert ``x`` to a float array of shape ``(n_samples, n_dof)``.

    Parameters
    ----------
    x : array-like of shape (n_dof,) or (n_samples, n_dof)
        Joint quantity (time along axis 0).
    n_dof : int
        Expected number of joints.
    name : str
        Name used in error messages.
    allow_nonfinite : bool
        Skip the NaN/inf check (streaming paths that report a fault instead).

    Returns
    -------
    array : ndarray of shape (n_samples, n_dof)
        Two-dimensional float copy-free view where possible.
    single : bool
        True when ``x`` was one sample of shape ``(n_dof,)``; callers use it to
        return results of the same rank.
    """
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise DimensionError(
            f"{name} must be a numeric array of shape ({n_dof},) or (n_samples, {n_dof}); "
            f"could not convert it: {exc}"
        ) from None
    single = arr.ndim == 1
    if single:
        arr = arr[None, :]
    if arr.ndim != 2 or arr.shape[1] != n_dof:
        raise DimensionError(
            f"{name} must have shape ({n_dof},) or (n_samples, {n_dof}) for a robot with "
            f"{n_dof} joints; got shape {np.shape(x)}"
        )
    if not allow_nonfinite:
        check_finite(arr, name)
    return arr, single


def check_dt(dt: Any, name: str = "dt") -> float:
    """Return the sample period ``dt`` [s] as a float after checking it is positive and finite."""
    try:
        value = float(dt)
    except (TypeError, ValueError):
        raise InputValueError(f"{name} must be a positive number of seconds; got {dt!r}") from None
    if not np.isfinite(value) or value <= 0.0:
        raise InputValueError(f"{name} must be a positive, finite number of seconds; got {dt!r}")
    return value
