"""Input checks shared by the whole package.

Conventions checked here: arrays of joint quantities have shape ``(n_dof,)``
for one sample or ``(n_samples, n_dof)`` for a time series (time along
axis 0); values are finite; angles are radians; the sample period ``dt`` [s]
is positive and finite.
"""

from __future__ import annotations

import operator
from typing import Any, Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .exceptions import DimensionError, InputValueError

FloatArray = NDArray[np.float64]

__all__ = [
    "FloatArray",
    "as_float_array",
    "as_joint_array",
    "as_sample",
    "check_dt",
    "check_finite",
    "check_increasing",
    "check_int",
    "check_scalar",
    "per_joint",
]

Sign = Literal["any", "nonnegative", "positive"]
_SIGN_TEXT = {"any": "", "nonnegative": " >= 0", "positive": " > 0"}


def check_finite(x: FloatArray, name: str) -> None:
    """Raise :class:`InputValueError` naming the first non-finite entry of ``x``."""
    finite = np.isfinite(x)
    if not finite.all():
        bad = np.argwhere(~finite)[0]
        index = tuple(int(i) for i in bad)
        where = f"sample {index[0]}, joint {index[1]}" if len(index) == 2 else f"index {index}"
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


def _sign_ok(values: FloatArray, sign: Sign) -> bool:
    if sign == "nonnegative":
        return bool((values >= 0.0).all())
    if sign == "positive":
        return bool((values > 0.0).all())
    return True


def as_float_array(x: Any, name: str, shape: str) -> FloatArray:
    """Convert ``x`` to a float array (a copy); :class:`DimensionError` naming ``shape`` if not."""
    try:
        return np.array(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise DimensionError(
            f"{name} must be a numeric array of shape {shape}; could not convert it: {exc}"
        ) from None


def check_scalar(value: Any, name: str, unit: str, sign: Sign = "positive") -> float:
    """Return ``value`` as a finite float [unit] with the required sign.

    Parameters
    ----------
    value : float
        The number to check.
    name, unit : str
        Used in the error message ("gain [1/s] must be ...").
    sign : {"positive", "nonnegative", "any"}
        Required sign.
    """
    wanted = f"a finite number{_SIGN_TEXT[sign]} [{unit}]"
    if isinstance(value, (bool, np.bool_)):
        raise InputValueError(f"{name} must be {wanted}; got {value!r}")
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InputValueError(f"{name} must be {wanted}; got {value!r}") from None
    if not np.isfinite(number) or not _sign_ok(np.array([number]), sign):
        raise InputValueError(f"{name} must be {wanted}; got {value!r}")
    return number


def check_int(value: Any, name: str, minimum: int, owner: str = "") -> int:
    """Return ``value`` as an int >= ``minimum``; bools and floats are refused."""
    index: int | None
    if isinstance(value, (bool, np.bool_)):
        index = None
    else:
        try:
            index = operator.index(value)
        except TypeError:
            index = None
    if index is None or index < minimum:
        prefix = f"{owner}: " if owner else ""
        raise InputValueError(f"{prefix}{name} must be an integer >= {minimum}; got {value!r}")
    return index


def per_joint(value: Any, n_dof: int, name: str, unit: str, sign: Sign = "any") -> FloatArray:
    """Broadcast a scalar or an array of shape ``(n_dof,)`` to a finite array of shape ``(n_dof,)``.

    Parameters
    ----------
    value : float or array-like of shape (n_dof,)
        One value for every joint, or one per joint [unit].
    n_dof : int
        Number of joints.
    name, unit : str
        Used in error messages.
    sign : {"any", "nonnegative", "positive"}
        Required sign of every entry.

    Returns
    -------
    ndarray of shape (n_dof,)
        A new float array.
    """
    wanted = f"a number or an array of shape ({n_dof},) [{unit}]"
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputValueError(f"{name} must be {wanted}; got {value!r}") from None
    if arr.ndim == 0:
        arr = np.full(n_dof, float(arr))
    if arr.shape != (n_dof,):
        raise DimensionError(
            f"{name} must be a scalar or have shape ({n_dof},) for {n_dof} joints; "
            f"got shape {arr.shape}"
        )
    if not np.isfinite(arr).all() or not _sign_ok(arr, sign):
        wanted = f"finite and{_SIGN_TEXT[sign]}" if sign != "any" else "finite"
        raise InputValueError(f"{name} must be {wanted} [{unit}]; got {value!r}")
    return arr


def check_increasing(t: FloatArray, what: str) -> None:
    """Raise :class:`InputValueError` unless ``t`` [s] is finite and strictly increasing."""
    check_finite(t, f"t of {what}")
    bad = np.flatnonzero(np.diff(t) <= 0.0)
    if bad.size:
        k = int(bad[0]) + 1
        raise InputValueError(
            f"t of {what} must be strictly increasing; t[{k}] = {t[k]!r} s follows "
            f"t[{k - 1}] = {t[k - 1]!r} s"
        )


def as_sample(x: Any, n_dof: int, name: str) -> tuple[FloatArray, str]:
    """One sample of shape ``(n_dof,)`` as a C-contiguous float array, for streams.

    Never raises on data: returns ``(array, "")``, or an empty array and the
    reason (not numeric, wrong shape). Finiteness and limits are the caller's.
    """
    try:
        arr = np.ascontiguousarray(x, dtype=np.float64)
    except (TypeError, ValueError, OverflowError):
        return _EMPTY, f"{name} must be numeric; got {x!r}"
    if arr.shape != (n_dof,):
        return _EMPTY, f"{name} must have shape ({n_dof},); got {arr.shape}"
    return arr, ""


_EMPTY = np.empty(0)
