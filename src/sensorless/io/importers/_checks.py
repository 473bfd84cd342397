"""The check of every value an importer reads: finite, an angle within ±4π rad, a label.

:func:`checked_column` turns one column of a format (numbers or text, as the
reader parsed it) into float64 and refuses what no log may hold, naming the
file, the column and the row (:mod:`._pipeline` then regularises the checked
recording). Units SI and radians.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, Literal

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from ..._validation import FloatArray
from ...exceptions import LogFormatError
from ..columns import ANGLE_LIMIT, show_value

__all__ = ["ColumnKind", "checked_column"]

ColumnKind = Literal["time", "angle", "value", "label"]


def _problem(source: Path, column: str, row: int, text: str) -> LogFormatError:
    return LogFormatError(f"{source}: {column}, row {row}: {text}")


def _as_float_one_by_one(
    values: NDArray[Any], source: Path, column: str, first_row: int
) -> FloatArray:
    """As :func:`_as_float`, value by value: an integer beyond the float range is named."""
    numbers = np.empty(values.shape, dtype=np.float64)
    for row, value in enumerate(values.tolist()):
        try:
            numbers[row] = float(value)
        except OverflowError:
            raise _problem(
                source, column, first_row + row, f"holds {value!r}, beyond the range of a float"
            ) from None
        except (TypeError, ValueError):
            numbers[row] = math.nan
    return numbers


def _as_float(values: NDArray[Any], source: Path, column: str, first_row: int) -> FloatArray:
    if values.dtype.kind in "iuf":
        return values.astype(np.float64, copy=False)
    if values.dtype.kind == "b":
        raise _problem(source, column, first_row, "holds booleans, not numbers")
    try:
        numbers = pd.to_numeric(pd.Series(values), errors="coerce").to_numpy(dtype=np.float64)
    except OverflowError:
        numbers = _as_float_one_by_one(values, source, column, first_row)
    missing = pd.isna(pd.Series(values)).to_numpy()
    bad = np.flatnonzero(np.isnan(numbers) & ~missing)
    if bad.size:
        row = int(bad[0])
        raise _problem(
            source, column, first_row + row, f"holds {values[row]!r}, which is not a number"
        )
    return numbers


_NOT_FINITE = (
    "holds {value} (an empty field or a non-finite number); every value must be a finite number"
)
_NOT_AN_ANGLE = (
    "holds the angle {value} rad, beyond ±4π rad; is the column in degrees? Declare its unit "
    "as 'deg'"
)
_NOT_A_LABEL = "holds {value}; labels must be non-negative integers up to 2**53 (0 = no collision)"
# Beyond it a float no longer holds every integer, and int64 overflows soon after.
_MAX_LABEL = 2.0**53


def _not_finite(values: FloatArray) -> NDArray[np.bool_]:
    return ~np.isfinite(values)


def _beyond_angle_limit(values: FloatArray) -> NDArray[np.bool_]:
    return np.abs(values) > ANGLE_LIMIT


def _not_a_label(values: FloatArray) -> NDArray[np.bool_]:
    return (values < 0.0) | (values > _MAX_LABEL) | (values != np.round(values))


def checked_column(
    values: ArrayLike, *, source: Path, column: str, first_row: int, kind: ColumnKind
) -> FloatArray:
    """Convert one column of a chunk to float64 and check its values.

    Parameters
    ----------
    values : array-like of shape (n_rows,)
        The values as read (numbers, or text from a CSV file).
    source : Path
        File name, for error messages.
    column : str
        The column as error messages name it, e.g. ``"column 'dq3'"`` or
        ``"column 14"``.
    first_row : int
        Row number of ``values[0]`` in the file (data rows counted from 0).
    kind : {"time", "angle", "value", "label"}
        ``"angle"``: also within ±4π rad (after unit conversion);
        ``"label"``: also non-negative integers.

    Returns
    -------
    ndarray of shape (n_rows,)
        float64.

    Raises
    ------
    LogFormatError
        A value is not a number, not finite, an angle beyond ±4π rad or a
        label that is not a non-negative integer; the message names the
        file, the column and the row.
    """
    numbers = _as_float(np.asarray(values), source, column, first_row)
    tests = [(_not_finite, _NOT_FINITE)]
    if kind == "angle":
        tests.append((_beyond_angle_limit, _NOT_AN_ANGLE))
    elif kind == "label":
        tests.append((_not_a_label, _NOT_A_LABEL))
    for test, text in tests:
        bad = np.flatnonzero(test(numbers))
        if bad.size:
            row = int(bad[0])
            value = show_value(numbers[row])
            raise _problem(source, column, first_row + row, text.format(value=value))
    return numbers
