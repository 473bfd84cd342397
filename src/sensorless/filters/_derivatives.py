"""The result of every estimator, and the shape check of its input."""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray
from ..exceptions import DimensionError

__all__ = ["Derivatives", "n_dof_of"]


class Derivatives(NamedTuple):
    """Position and its first two time derivatives.

    Attributes
    ----------
    position : ndarray of shape (n_samples, n_dof) or (n_dof,)
        Joint positions [rad]: the filtered position where the estimator
        filters it, otherwise the input.
    velocity : ndarray of shape (n_samples, n_dof) or (n_dof,)
        Estimated joint velocities [rad/s].
    acceleration : ndarray of shape (n_samples, n_dof) or (n_dof,)
        Estimated joint accelerations [rad/s²].
    """

    position: FloatArray
    velocity: FloatArray
    acceleration: FloatArray


def n_dof_of(x: ArrayLike, name: str, ndim: int) -> int:
    """Number of joints of ``x``, which must have ``ndim`` dimensions and n_dof >= 1."""
    shape = np.shape(x)
    expected = "(n_dof,)" if ndim == 1 else "(n_samples, n_dof)"
    if len(shape) != ndim or shape[-1] < 1:
        raise DimensionError(f"{name} must have shape {expected} with n_dof >= 1; got {shape}")
    return int(shape[-1])
