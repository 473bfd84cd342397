"""Input checks shared by the whole package.

Conventions checked here: arrays of joint quantities have shape ``(n_dof,)``
for one sample or ``(n_samples, n_dof)`` for a time series (time along
axis 0); values are finite; angles are radians; the sample period ``dt`` [s]
is positive and finite.
"""

from __future__ import annotations

import math
import operator
from typing import Any, Literal, TypeVar

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .exceptions import DimensionError, InputTypeError, InputValueError

FloatArray = NDArray[np.float64]

__all__ = [
    "FloatArray",
    "as_float_array",
    "as_joint_array",
    "as_sample",
    "check_dt",
    "check_duration",
    "check_finite",
    "check_increasing",
    "check_int",
    "check_range",
    "check_scalar",
    "check_type",
    "first_irregular_step",
    "joint_parameter",
    "per_joint",
]

T = TypeVar("T")

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
    return _number(dt, name, "a positive, finite number of seconds", "positive")


def check_duration(value: Any, name: str) -> float:
    """Return a duration [s] (a transient, a hold time) as a float after checking it is >= 0."""
    return _number(value, name, "a finite number of seconds >= 0", "nonnegative")


def _number(value: Any, name: str, wanted: str, sign: Sign) -> float:
    """``value`` as a finite float of the required sign; bools are refused."""
    try:
        number = math.nan if isinstance(value, (bool, np.bool_)) else float(value)
    except (TypeError, ValueError):
        number = math.nan
    if not np.isfinite(number) or not _sign_ok(np.array([number]), sign):
        raise InputValueError(f"{name} must be {wanted}; got {value!r}")
    return number


def check_type(value: Any, kind: type[T], name: str, hint: str = "") -> T:
    """Return ``value`` if it is a ``kind``; else :class:`InputTypeError` naming what came.

    ``hint`` follows the expected type in the message, e.g. where to get one.
    """
    if not isinstance(value, kind):
        article = "an" if kind.__name__[:1] in "AEIOU" else "a"
        raise InputTypeError(
            f"{name} must be {article} {kind.__name__}{hint}; got {type(value).__name__}"
        )
    return value


def check_state_joints(state_n_dof: int, n_dof: int, owner: str) -> None:
    """:class:`DimensionError` unless a state for ``state_n_dof`` joints fits ``owner``."""
    if state_n_dof != n_dof:
        raise DimensionError(f"state is for {state_n_dof} joints; {owner} has {n_dof}")


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
    return _number(value, name, f"a finite number{_SIGN_TEXT[sign]} [{unit}]", sign)


def check_range(value: Any, name: str, unit: str, sign: Sign = "any") -> tuple[float, float]:
    """Return ``value`` as a range (low, high) of finite floats [unit], low <= high.

    Each end is checked as :func:`check_scalar` checks it with ``sign``.
    """
    pair = tuple(value) if isinstance(value, tuple | list) else ()
    if len(pair) != 2:
        raise InputValueError(f"{name} must be a range (low, high) [{unit}]; got {value!r}")
    low, high = (check_scalar(v, name, unit, sign) for v in pair)
    if low > high:
        raise InputValueError(f"{name} must be a range (low, high) with low <= high; got {value!r}")
    return low, high


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


def per_joint(
    value: Any, n_dof: int, name: str, unit: str, sign: Sign = "any", *, allow_inf: bool = False
) -> FloatArray:
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
    allow_inf : bool
        Accept ``-inf``/``+inf`` (e.g. "no limit"); NaN is refused all the same.

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
    if allow_inf and np.isnan(arr).any():
        raise InputValueError(f"{name} must not contain NaN [{unit}]; got {value!r}")
    if not (allow_inf or np.isfinite(arr).all()) or not _sign_ok(arr, sign):
        finite = "" if allow_inf else "finite and"
        wanted = f"{finite}{_SIGN_TEXT[sign]}".strip() if sign != "any" else "finite"
        raise InputValueError(f"{name} must be {wanted} [{unit}]; got {value!r}")
    return arr


def joint_parameter(value: Any, name: str) -> FloatArray:
    """A finite scalar or non-empty array of shape ``(n_dof,)`` before ``n_dof`` is known.

    For models whose number of joints follows from their parameters (friction,
    sensors). Returns a new float array of ndim 0 or 1.
    """
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputValueError(
            f"{name} must be a number or an array of shape (n_dof,); got {value!r}"
        ) from None
    if arr.ndim > 1 or arr.size == 0:
        raise DimensionError(
            f"{name} must be a scalar or a non-empty array of shape (n_dof,); got shape {arr.shape}"
        )
    check_finite(np.atleast_1d(arr), name)
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


def first_irregular_step(t: FloatArray, period: float, rtol: float) -> int | None:
    """Index ``k`` of the first step ``t[k+1] - t[k]`` [s] that is not ``period`` within ``rtol``.

    None when every step is regular (or ``t`` has fewer than two samples).
    """
    step = np.diff(t)
    # Time stamps far from zero (e.g. Unix time) carry rounding of their own spacing; a
    # few ulps of the largest stamp are not jitter.
    tolerance = rtol * period + 4.0 * float(np.spacing(max(abs(t[0]), abs(t[-1]))))
    bad = np.flatnonzero(np.abs(step - period) > tolerance)
    return int(bad[0]) if bad.size else None


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
