"""State of :class:`~sensorless.observers.adaptive.FrictionAdapter` and its input checks.

Units and shapes as in :mod:`sensorless.observers.adaptive`.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .._validation import FloatArray, check_scalar
from ..exceptions import DimensionError, InputTypeError, InputValueError

__all__ = ["AdapterState"]

BoolArray = NDArray[np.bool_]


@dataclass(frozen=True, eq=False, slots=True)
class AdapterState:
    """State of a :class:`~sensorless.observers.adaptive.FrictionAdapter` after a sample.

    Get it from :meth:`FrictionAdapter.initial_state`, :meth:`FrictionAdapter.step`
    or :meth:`FrictionAdapter.run`.

    Attributes
    ----------
    theta : ndarray of shape (n_dof, columns)
        Applied parameters per joint: θ_c [N m], θ_v [N m s/rad], θ_0 [N m]
        (and θ_h [-], the relative model error, with the model-torque term);
        they follow ``estimate`` at the rate limit, inside the box.
    estimate : ndarray of shape (n_dof, columns)
        RLS estimate of θ, unconstrained (same units).
    covariance : ndarray of shape (n_dof, columns, columns)
        RLS covariance P per joint (units of θ squared per N m²).
    regressor : ndarray of shape (n_dof, 3)
        φ of the last sample: tanh(q̇/v_s) [-], q̇ [rad/s], 1 [-].
    filtered_regressor : ndarray of shape (n_dof, columns)
        ψ = F(φ) at the last sample (and h [N m], the model torque).
    correction : ndarray of shape (n_dof,)
        Correction δτ applied at the last sample [N m].
    filtered_correction : ndarray of shape (n_dof,)
        F(δτ) at the last sample [N m]: what was subtracted from r̂.
    started : bool
        False before the first sample.
    updates : ndarray of shape (n_dof,)
        Number of samples each joint has learned from [-].
    """

    theta: FloatArray
    estimate: FloatArray
    covariance: FloatArray
    regressor: FloatArray
    filtered_regressor: FloatArray
    correction: FloatArray
    filtered_correction: FloatArray
    started: bool
    updates: NDArray[np.int64]

    @property
    def n_dof(self) -> int:
        """Number of joints the state is for."""
        return int(self.theta.shape[0])


class _Work:
    """Mutable copy of a state that the per-sample kernel updates in place."""

    def __init__(self, state: AdapterState) -> None:
        self.theta = state.theta.copy()
        self.estimate = state.estimate.copy()
        self.covariance = state.covariance.copy()
        self.regressor = state.regressor.copy()
        self.filtered_regressor = state.filtered_regressor.copy()
        self.correction = state.correction.copy()
        self.filtered_correction = state.filtered_correction.copy()
        self.started = state.started
        self.updates = state.updates.copy()

    @staticmethod
    def fresh(
        theta: FloatArray,
        estimate: FloatArray,
        covariance: FloatArray,
        updates: NDArray[np.int64] | None = None,
    ) -> AdapterState:
        """The state before the first sample: filters at zero, θ, estimate and P given."""
        n = theta.shape[0]
        work = _Work.__new__(_Work)
        work.theta, work.estimate, work.covariance = (
            theta.copy(),
            estimate.copy(),
            covariance.copy(),
        )
        work.regressor, work.filtered_regressor = np.zeros((n, 3)), np.zeros(theta.shape)
        work.correction, work.filtered_correction = np.zeros(n), np.zeros(n)
        work.started = False
        work.updates = np.zeros(n, dtype=np.int64) if updates is None else updates.copy()
        return work.freeze()

    def freeze(self) -> AdapterState:
        arrays = (
            self.theta, self.estimate, self.covariance, self.regressor, self.filtered_regressor,
            self.correction, self.filtered_correction,
        )  # fmt: skip
        for arr in arrays:
            arr.setflags(write=False)
        self.updates.setflags(write=False)
        return AdapterState(*arrays, self.started, self.updates)


def _positive_or_inf(value: Any, name: str, unit: str) -> float:
    if isinstance(value, (int, float, np.floating)) and value == np.inf:
        return float("inf")
    return check_scalar(value, name, unit)


def _array(value: ArrayLike, shape: tuple[int, ...], name: str) -> FloatArray:
    try:
        arr = np.array(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputValueError(
            f"{name} must be a numeric array of shape {shape}; got {value!r}"
        ) from None
    if arr.shape != shape:
        raise DimensionError(f"{name} must have shape {shape}; got {arr.shape}")
    if not np.isfinite(arr).all():
        raise InputValueError(f"{name} must be finite; got {value!r}")
    return arr


def _trusted(value: ArrayLike, shape: tuple[int, ...]) -> BoolArray:
    """The trusted mask broadcast to ``shape``: per sample or per sample and joint."""
    arr = np.asarray(value)
    if arr.dtype != np.bool_:
        raise InputTypeError(f"trusted must be booleans; got dtype {arr.dtype}")
    if len(shape) == 2 and arr.ndim == 1:
        arr = arr[:, None]
    try:
        return np.broadcast_to(arr, shape)
    except ValueError:
        raise DimensionError(
            f"trusted must have shape {shape[:-1] or '()'} or {shape}; got {np.shape(value)}"
        ) from None
