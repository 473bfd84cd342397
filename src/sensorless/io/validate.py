"""Validation of a log table: the one routine that every way into a log goes through.

:func:`validate_table` checks a table against the layout of the
:mod:`sensorless.io` docstring; :func:`~sensorless.io.read_log`,
:meth:`~sensorless.io.Log.from_pandas` and the :class:`~sensorless.io.Log`
constructor all call it, and so should every importer of a foreign format.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, TypedDict

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from .._validation import FloatArray
from ..exceptions import DimensionError, InputValueError, LogFormatError
from .columns import (
    ANGLE_GROUPS,
    ANGLE_LIMIT,
    COLUMN_PATTERN,
    JOINT_GROUPS,
    KNOWN_COLUMNS,
    abbreviate,
    column_name,
    show_value,
)

__all__ = ["TableChecks", "as_float_column", "validate_table"]


class TableChecks(TypedDict, total=False):
    """Keyword options of :func:`validate_table` that readers pass through to it."""

    check_regular: bool
    rtol: float
    allow_missing: bool


def _check_n_dof(n_dof: Any) -> int | None:
    if n_dof is None:
        return None
    if isinstance(n_dof, bool) or not isinstance(n_dof, int | np.integer) or n_dof < 1:
        raise InputValueError(f"n_dof must be a positive integer or None; got {n_dof!r}")
    return int(n_dof)


def _check_rtol(rtol: Any) -> float:
    try:
        value = float(rtol)
    except (TypeError, ValueError):
        raise InputValueError(f"rtol must be a non-negative number; got {rtol!r}") from None
    if not math.isfinite(value) or value < 0.0:
        raise InputValueError(f"rtol must be a finite, non-negative number; got {rtol!r}")
    return value


def _parse_columns(names: list[Any], n_dof: int | None) -> tuple[int, list[str]]:
    """Check the column set; return the joint count and the present groups in table order."""
    joints: dict[str, set[int]] = {}
    unknown: list[Any] = []
    for name in names:
        match = COLUMN_PATTERN.fullmatch(name) if isinstance(name, str) else None
        if match is not None:
            joints.setdefault(match[1], set()).add(int(match[2]))
        elif name not in ("t", "collision_id"):
            unknown.append(name)
    if unknown:
        raise LogFormatError(
            f"unknown column(s) {abbreviate(unknown)}; known columns are {KNOWN_COLUMNS}"
        )
    if "t" not in names or "q" not in joints:
        expected_q = "'q_1'..'q_<n_dof>'" if n_dof is None else f"'q_1'..'q_{n_dof}'"
        present = (("'t'", "t" in names), (expected_q, "q" in joints))
        missing = [label for label, ok in present if not ok]
        raise LogFormatError(
            f"a log needs the time column 't' and the joint positions {expected_q}; "
            f"missing {', '.join(missing)}; found columns {abbreviate(names)}"
        )
    groups = [group for group in JOINT_GROUPS if group in joints]
    n_found = max(max(indices) for indices in joints.values())
    missing_columns = [
        column_name(group, joint)
        for group in groups
        for joint in range(1, n_found + 1)
        if joint not in joints[group]
    ]
    if missing_columns:
        counts = ", ".join(f"{group}: {len(joints[group])}" for group in groups)
        raise LogFormatError(
            f"joint groups have inconsistent joint counts ({counts}); every present group "
            f"needs columns <group>_1..<group>_{n_found}; missing column(s) "
            f"{abbreviate(missing_columns)}"
        )
    if n_dof is not None and n_dof != n_found:
        raise DimensionError(
            f"n_dof mismatch: robot has {n_dof} joints, log has {n_found} "
            f"(columns q_1..q_{n_found})"
        )
    return n_found, groups


def as_float_column(name: str, values: ArrayLike) -> FloatArray:
    """Convert one column to float64, naming the first row that is not a number.

    Parameters
    ----------
    name : str
        Column name, for error messages.
    values : array-like of shape (n_samples,)
        The column; numbers, or numbers written as text (from a CSV file).

    Returns
    -------
    ndarray of shape (n_samples,)
        float64; missing values (None, ``pd.NA``) become NaN.

    Raises
    ------
    LogFormatError
        The column is not one-dimensional or holds a value that is not a number.
    """
    arr = np.asarray(values)
    if arr.ndim != 1:
        raise LogFormatError(f"column {name!r} must be one-dimensional; got shape {arr.shape}")
    if arr.dtype.kind in "iuf":
        return arr.astype(np.float64, copy=False)
    if arr.dtype.kind not in "OUS":
        raise LogFormatError(f"column {name!r} must be numeric; it has dtype {arr.dtype}")
    # Object and text columns come from CSV files with a stray word in them, or from
    # nullable pandas dtypes; numbers written as text are fine, anything else is not.
    out = np.empty(arr.shape, dtype=np.float64)
    for row, value in enumerate(arr.tolist()):
        if value is None or value is pd.NA:
            out[row] = math.nan
            continue
        if isinstance(value, bool):
            number = None
        elif isinstance(value, int | float):
            number = float(value)
        else:
            try:
                number = float(value)
            except OverflowError:  # an integer beyond the float range: refused as not finite
                number = math.inf if value > 0 else -math.inf
            except (TypeError, ValueError):
                number = None
        if number is None:
            raise LogFormatError(
                f"column {name!r} must be numeric; row {row} holds the non-numeric value {value!r}"
            )
        out[row] = number
    return out


MAX_PERIOD = 0.5
"""Longest median sample period of a log [s]: longer is time in milliseconds (2 Hz at most)."""


def _check_time(t: FloatArray, check_regular: bool, rtol: float) -> None:
    step = np.diff(t)
    not_increasing = np.flatnonzero(step <= 0.0)
    if not_increasing.size:
        row = int(not_increasing[0]) + 1
        before, after = float(t[row - 1]), float(t[row])
        how = "repeats" if after == before else "goes backwards"
        raise LogFormatError(
            f"column 't' must be strictly increasing; it {how} at row {row}: "
            f"t = {after!r} s at row {row} after t = {before!r} s at row {row - 1}"
        )
    if not check_regular:
        return
    median = float(np.median(step))
    if median > MAX_PERIOD:
        raise LogFormatError(
            f"column 't' looks like milliseconds, but time must be seconds: the median step "
            f"is {median:.6g} s, longer than {MAX_PERIOD:g} s (a robot log is sampled at "
            "100 Hz-1 kHz); divide t by 1000, or import with the column-mapping importer and "
            "declare the time unit (`unit: ms` in its spec)"
        )
    # Time stamps far from zero (e.g. Unix time) carry rounding of their own spacing; a
    # few ulps of the largest stamp are not jitter.
    tolerance = rtol * median + 4.0 * float(np.spacing(max(abs(t[0]), abs(t[-1]))))
    irregular = np.flatnonzero(np.abs(step - median) > tolerance)
    if irregular.size:
        row = int(irregular[0]) + 1
        before, after = float(t[row - 1]), float(t[row])
        deviation = abs(step[row - 1] - median) / median
        raise LogFormatError(
            f"column 't' is not regularly sampled: the step from row {row - 1} to row {row} "
            f"(t = {before!r} -> {after!r} s) is {step[row - 1]:.9g} s, the median step "
            f"is {median:.9g} s; relative deviation {deviation:.3g} exceeds rtol = {rtol:g}. "
            "Resample explicitly with sensorless.io.resample(log, dt) on a log read with "
            "check_regular=False, or pass check_regular=False"
        )


def _check_collision_id(values: FloatArray) -> None:
    # Up to 2**53: a float holds every integer up to there, and int64 overflows not far beyond.
    bad = np.flatnonzero((values < 0.0) | (values > 2.0**53) | (values != np.round(values)))
    if bad.size:
        row = int(bad[0])
        raise LogFormatError(
            "column 'collision_id' must hold non-negative integers (0 = no collision) up to "
            "2**53; "
            f"row {row} holds {show_value(values[row])}"
        )


def _check_angles(name: str, values: FloatArray) -> None:
    too_large = np.flatnonzero(np.abs(values) > ANGLE_LIMIT)
    if too_large.size:
        row = int(too_large[0])
        raise LogFormatError(
            f"column {name!r} looks like degrees, but angles must be radians: row {row} "
            f"holds {show_value(values[row])}, beyond ±4π = ±{ANGLE_LIMIT:.6g} rad; convert "
            "with numpy.deg2rad"
        )


def validate_table(
    df: pd.DataFrame | Mapping[str, ArrayLike],
    n_dof: int | None = None,
    check_regular: bool = True,
    rtol: float = 1e-6,
    allow_missing: bool = False,
) -> int:
    """Check that a table is a valid log and return its number of joints.

    This is the one validation routine of the log format; the readers and the
    :class:`~sensorless.io.Log` constructor all call it.

    Parameters
    ----------
    df : DataFrame or mapping of column name to array-like of shape (n_samples,)
        The log table, columns named as in the :mod:`sensorless.io` docstring.
    n_dof : int, optional
        Number of joints of the robot the log is meant for; checked against the log.
    check_regular : bool
        Require a regular time base: every time step [s] within ``rtol``
        (relative) of the median step.
    rtol : float
        Relative tolerance of the regularity check.
    allow_missing : bool
        Accept NaN or inf in the joint groups as lost samples (``t`` and
        ``collision_id`` must still be finite).

    Returns
    -------
    n_dof : int
        Number of joints in the log.

    Raises
    ------
    LogFormatError
        Unknown, missing or duplicate columns; joint groups of different
        lengths; fewer than 2 samples; a non-numeric, NaN or infinite value;
        time not strictly increasing, or (with ``check_regular``, as files are
        read) with a median step beyond ``MAX_PERIOD`` (0.5 s: milliseconds) or
        irregular;
        angles beyond ±4π rad (degrees); a negative or fractional
        ``collision_id``. The message names the column and the first bad row.
    DimensionError
        ``n_dof`` differs from the joint count of the log.
    InputValueError
        ``n_dof`` or ``rtol`` is not a valid value.

    Examples
    --------
    >>> import pandas as pd
    >>> validate_table(pd.DataFrame({"t": [0.0, 0.1, 0.2], "q_1": [0.0, 0.1, 0.2]}))
    1
    >>> validate_table(pd.DataFrame({"t": [0.0, 0.1], "q_1": [0.0, 90.0]}))
    Traceback (most recent call last):
    ...
    sensorless.exceptions.LogFormatError: column 'q_1' looks like degrees, ...
    """
    expected = _check_n_dof(n_dof)
    tolerance = _check_rtol(rtol)
    if isinstance(df, pd.DataFrame):
        names: list[Any] = list(df.columns)
        duplicated = [name for name in names if names.count(name) > 1]
        if duplicated:
            raise LogFormatError(f"duplicate column(s) {abbreviate(sorted(set(duplicated)))}")
        columns: Mapping[Any, ArrayLike] = {name: df[name].to_numpy() for name in names}
    elif isinstance(df, Mapping):
        names = list(df)
        columns = df
    else:
        raise LogFormatError(
            f"a log table must be a pandas DataFrame or a mapping of columns; got {type(df)}"
        )
    n_found, groups = _parse_columns(names, expected)

    ordered = ["t"] + [column_name(g, j) for g in groups for j in range(1, n_found + 1)]
    if "collision_id" in names:
        ordered.append("collision_id")
    values = {name: as_float_column(name, columns[name]) for name in ordered}
    lengths = {len(column) for column in values.values()}
    if len(lengths) > 1:
        raise LogFormatError(f"all columns must have the same length; got lengths {lengths}")
    n_samples = lengths.pop()
    if n_samples < 2:
        raise LogFormatError(
            f"a log needs at least 2 samples to define its time base; got {n_samples}"
        )
    for name, column in values.items():
        if allow_missing and name not in ("t", "collision_id"):
            continue
        bad = np.flatnonzero(~np.isfinite(column))
        if bad.size:
            row = int(bad[0])
            raise LogFormatError(
                f"column {name!r} must be finite; row {row} holds {show_value(column[row])}"
            )
    if "collision_id" in values:
        _check_collision_id(values["collision_id"])
    _check_time(values["t"], check_regular, tolerance)
    for group in ANGLE_GROUPS:
        if group in groups:
            for joint in range(1, n_found + 1):
                name = column_name(group, joint)
                _check_angles(name, values[name])
    return n_found
