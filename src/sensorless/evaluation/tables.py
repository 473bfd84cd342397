"""Tables of several methods side by side (thesis Tables 4.3, 5.4, 5.7 and 5.9)."""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_float_array, check_finite
from ..exceptions import DimensionError, InputValueError
from .scoring import Evaluation, check_evaluations

__all__ = ["comparison_table", "efficiency_table", "summary_table"]


def comparison_table(
    evaluations: Mapping[str, Evaluation], *, missed: str = "missed", masked: str = "masked"
) -> pd.DataFrame:
    """Per-collision delays of several methods side by side (Tables 4.3, 5.4, 5.9).

    Parameters
    ----------
    evaluations : mapping of str to Evaluation
        Evaluations of the methods on the same log, by method name.
    missed : str
        Entry for a collision a method does not detect (the thesis writes
        "Does not Detect").
    masked : str
        Entry for a collision masked by an alarm that was already on when it
        started (see :mod:`sensorless.evaluation`).

    Returns
    -------
    DataFrame
        Indexed by collision id (``"collision"``); two-level columns:
        ``("window", "start")``, ``("window", "end")`` [s] and
        ``("window", "peak_force")`` [N], then for each method
        ``(name, "start_delay")`` and ``(name, "end_delay")`` [s], holding a
        delay, ``missed`` or ``masked``.

    Raises
    ------
    InputValueError
        The mapping is empty, a method is named ``"window"``, or the
        evaluations were made on different collision windows.
    TypeError
        ``evaluations`` is not a mapping of :class:`Evaluation`.
    """
    items = check_evaluations(evaluations)
    if "window" in evaluations:
        raise InputValueError(
            "a method may not be named 'window' in comparison_table; that column group "
            "holds the ground-truth windows"
        )
    reference_name, reference = items[0]
    windows = reference.per_collision[["start", "end", "peak_force"]]
    for name, evaluation in items[1:]:
        other = evaluation.per_collision[["start", "end"]]
        if list(other.index) != list(windows.index) or not np.allclose(
            other.to_numpy(dtype=float), windows[["start", "end"]].to_numpy(dtype=float)
        ):
            raise InputValueError(
                f"evaluations must be made on the same collision windows; {name!r} has "
                f"windows {list(other.index)} and {reference_name!r} has {list(windows.index)} "
                "(ids or times differ)"
            )
    columns: dict[tuple[str, str], Any] = {
        ("window", key): windows[key].to_numpy(dtype=float)
        for key in ("start", "end", "peak_force")
    }
    for name, evaluation in items:
        table = evaluation.per_collision
        for key in ("start_delay", "end_delay"):
            columns[(name, key)] = [
                float(value) if hit else masked if hidden else missed
                for value, hit, hidden in zip(
                    table[key], table["detected"], table["masked"], strict=True
                )
            ]
    result = pd.DataFrame(columns, index=pd.Index(windows.index, name="collision"))
    result.columns = pd.MultiIndex.from_tuples(list(columns), names=["method", "quantity"])
    return result


def summary_table(evaluations: Mapping[str, Evaluation]) -> pd.DataFrame:
    """One row per method: detected/total, false alarms, rate per hour, delays.

    Parameters
    ----------
    evaluations : mapping of str to Evaluation
        Evaluations by method name (the names index the table).

    Returns
    -------
    DataFrame
        Indexed by method name (``"method"``), with the columns of
        :meth:`Evaluation.summary` except ``method``.

    Raises
    ------
    InputValueError
        The mapping is empty.
    TypeError
        ``evaluations`` is not a mapping of :class:`Evaluation`.
    """
    items = check_evaluations(evaluations)
    rows = []
    for _, evaluation in items:
        row = evaluation.summary()
        del row["method"]
        rows.append(row)
    return pd.DataFrame(rows, index=pd.Index([name for name, _ in items], name="method"))


def _joint_vector(values: ArrayLike, name: str) -> FloatArray:
    arr = as_float_array(values, name, "(n_dof,)")
    if arr.ndim != 1 or arr.size == 0:
        raise DimensionError(f"{name} must have shape (n_dof,) with n_dof >= 1; got {arr.shape}")
    check_finite(arr, name)
    return arr


def efficiency_table(
    alpha: ArrayLike,
    beta: ArrayLike,
    *,
    extra: Mapping[str, ArrayLike] | None = None,
) -> pd.DataFrame:
    """Effectiveness eff = α/β of a time-variant threshold per joint (Table 5.7).

    Smaller values mean that the time-variant threshold b_2H/b_2L (eq. 5.33,
    5.39), whose constant part is α, is tighter than the constant threshold
    β = max|r̂| of eq. (5.32).

    Parameters
    ----------
    alpha : array-like of shape (n_dof,)
        Constant part α of the time-variant threshold [N m].
    beta : array-like of shape (n_dof,)
        Constant threshold β [N m], positive.
    extra : mapping of str to array-like of shape (n_dof,), optional
        Further rows shown between α and β, e.g. ``{"gamma": ..., "C": ...}``.

    Returns
    -------
    DataFrame
        Rows ``alpha``, the ``extra`` rows, ``beta``, ``eff``; columns the
        1-based joint numbers (``"joint"``).

    Raises
    ------
    DimensionError
        An input is not one-dimensional or the lengths differ.
    InputValueError
        A value is not finite, ``beta`` is not positive, or an ``extra`` row
        is named ``alpha``, ``beta`` or ``eff``.

    Examples
    --------
    >>> table = efficiency_table([2.0137, 1.8727, 2.3715], [2.5662, 2.4758, 2.8413])
    >>> table.loc["eff"].round(4).tolist()  # Table 5.7, KUKA-LWR
    [0.7847, 0.7564, 0.8347]
    """
    a = _joint_vector(alpha, "alpha")
    reserved = {"alpha", "beta", "eff"} & {str(name) for name in (extra or {})}
    if reserved:
        raise InputValueError(
            f"extra rows may not be named 'alpha', 'beta' or 'eff'; got {sorted(reserved)}"
        )
    rows: dict[str, FloatArray] = {"alpha": a}
    labelled = [(str(name), f"extra[{name!r}]", values) for name, values in (extra or {}).items()]
    for row, label, values in [*labelled, ("beta", "beta", beta)]:
        vector = _joint_vector(values, label)
        if vector.shape != a.shape:
            raise DimensionError(
                f"{label} must have the shape of alpha, ({a.size},); got {vector.shape}"
            )
        rows[row] = vector
    b = rows["beta"]
    if not (b > 0.0).all():
        raise InputValueError(f"beta must be positive to form eff = alpha/beta; got {b.tolist()}")
    rows["eff"] = a / b
    return pd.DataFrame.from_dict(
        rows, orient="index", columns=pd.RangeIndex(1, a.size + 1, name="joint")
    )
