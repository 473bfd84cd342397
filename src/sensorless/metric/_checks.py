"""Checks shared by the bound terms and the metric: finite, non-negative values."""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, per_joint
from ..exceptions import InputValueError

__all__ = ["nonnegative", "per_joint_nonnegative"]


def per_joint_nonnegative(x: ArrayLike, n_dof: int, name: str, unit: str) -> FloatArray:
    """``x`` as an array of shape (n_dof,) [unit], every entry finite and >= 0.

    A scalar applies to every joint (:func:`sensorless._validation.per_joint`).
    """
    return nonnegative(per_joint(x, n_dof, name, unit), name, unit)


def nonnegative(value: FloatArray, name: str, unit: str = "") -> FloatArray:
    """A copy of ``value`` after checking that every entry is finite and >= 0."""
    if not np.isfinite(value).all() or (value < 0).any():
        in_unit = f" [{unit}]" if unit else ""
        raise InputValueError(f"{name} must be finite and >= 0{in_unit}; got {value}")
    return value.copy()
