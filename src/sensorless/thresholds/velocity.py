"""Velocity-based variable thresholds UT/LT of eq. (4.33)-(4.39), tuned by eq. (4.45).

The friction error of a robot depends on its velocity (eq. 4.23-4.24), and
the error of the rigid-body model is roughly proportional to h (eq. 4.25).
Removing both from the residual leaves r̂_c ≈ 0 (eq. 4.30), bounded by
L(q̇) < r̂_c < U(q̇) (eq. 4.32), hence for joint j (eq. 4.34-4.36)

    LT(t) = L(q̇) + γ h(t) + K_I/(s+K_I)·τ̂_fme(q̇)(t)
    UT(t) = U(q̇) + γ h(t) + K_I/(s+K_I)·τ̂_fme(q̇)(t).

τ̂_fme(q̇) is piecewise constant over velocity bins of width ``bin_width``
(the thesis quantised q̇ with 0.06 rad/s); bin ``k`` covers
``[k w, (k + 1) w)``. Zero velocity is a bin edge so that no bin mixes the
two directions of motion across the Coulomb friction jump.

Fit (eq. 4.45, section 4.5.2), per joint: least squares of r̂ on the columns
[h, K_I/(s+K_I)·1{q̇ ∈ bin b} for every visited bin b]; their coefficients
are γ and τ̂_fme(b). The indicators are filtered with the observer's
zero-order-hold recursion (:func:`~sensorless.thresholds.base.first_order`),
starting from their first value. With e = r̂ - γ h - K_I/(s+K_I)·τ̂_fme(q̇),
L(b) = min e and U(b) = max e over the fit samples in bin b, widened by
``margin``. The same fit serves r̂_s (eq. 4.37-4.39, 4.46): the sign of the
τ̂_sfe term is absorbed by the fitted τ̂_fme, which is then -τ̂_sfe.

Not implemented: combining the motor-torque and the torque-sensor problems
into one least squares through eq. (4.21); it needs both residuals of the
same run.

Velocities outside the fitted range
-----------------------------------
All joints share one grid of bins, from the slowest to the fastest velocity
of any joint in the fit runs. A bin of the grid that a joint never visited
takes the values of the nearest visited bin of that joint (ties: the bin of
lower velocity), and a velocity beyond the grid uses the first or last bin.
Where the velocity of a joint is outside the range of the bins it visited
during fit, its bounds are widened by ``extrapolation_margin`` [N m].

Examples
--------
>>> import numpy as np
>>> from sensorless.signals import ObserverSignals
>>> t = np.arange(2000) * 1e-3
>>> v = np.sin(2 * t)[:, None]
>>> z = np.zeros_like(v)
>>> run = ObserverSignals(t, 0.1 * np.tanh(5 * v), z, z, z, v, gain=20.0, robot="demo")
>>> th = VelocityThreshold(bin_width=0.1).fit(run)
>>> th.bin_edges_[[0, -1]]
array([-0.8,  1. ])
>>> lower, upper = th.bounds(run)
>>> bool(np.all((lower <= run.residual) & (run.residual <= upper)))
True
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from .._validation import FloatArray
from ..exceptions import DimensionError, InputValueError
from ..signals import ObserverSignals
from .base import (
    BoolArray,
    Threshold,
    ThresholdInputs,
    ThresholdState,
    first_order,
    regular_period,
    rounding_guard,
)

__all__ = ["MAX_BINS", "VelocityThreshold"]

MAX_BINS = 10_000
"""Largest number of velocity bins; more means a ``bin_width`` far too small for the data."""

IntArray = np.ndarray[Any, np.dtype[np.int64]]


def _bin_index(edges: FloatArray, velocity: FloatArray) -> IntArray:
    """Bin of every velocity; beyond the grid, the first or last bin."""
    index = np.searchsorted(edges, velocity, side="right") - 1
    return np.clip(index, 0, edges.shape[0] - 2).astype(np.int64)


def _as_float(value: Any) -> float:
    """``float(value)``, or NaN (rejected by the caller) when it is not a number."""
    try:
        return float(value)
    except (TypeError, ValueError):
        return math.nan


def _fill_nearest(values: FloatArray, valid: BoolArray) -> FloatArray:
    """Give every invalid entry of each column the value of the nearest valid one (ties: lower)."""
    filled = values.copy()
    positions = np.arange(values.shape[0])
    for j in range(values.shape[1]):
        source = np.flatnonzero(valid[:, j])
        nearest = source[np.argmin(np.abs(positions[:, None] - source[None, :]), axis=1)]
        filled[:, j] = values[nearest, j]
    return np.asarray(filled, dtype=np.float64)


class VelocityThreshold(Threshold):
    """Velocity-based bounds LT/UT of eq. (4.35)-(4.36), fitted by eq. (4.45).

    Parameters
    ----------
    bin_width : float
        Width of the velocity bins [rad/s] (0.06 in section 4.5.2).
    margin : float or array-like of shape (n_dof,)
        Subtracted from L and added to U [N m], >= 0.
    extrapolation_margin : float
        Extra widening [N m] where a joint's velocity is outside the bins it
        visited during fit, >= 0.
    joints : sequence of int, optional
        Monitored joints (1-based); None for all.
    transient : float
        Time skipped at the start of every fit run [s].

    Attributes
    ----------
    gamma_ : ndarray of shape (n_dof,)
        Coefficient γ of h [-].
    bin_edges_ : ndarray of shape (n_bins + 1,)
        Edges of the velocity bins [rad/s], shared by all joints.
    tau_fme_ : ndarray of shape (n_bins, n_dof)
        τ̂_fme per bin and joint [N m].
    lower_, upper_ : ndarray of shape (n_bins, n_dof)
        L and U per bin and joint [N m] (include ``margin``).
    counts_ : ndarray of shape (n_bins, n_dof)
        Number of fit samples per bin and joint; 0 marks a bin filled from
        the nearest visited one.
    """

    name = "velocity"
    _integer_attributes = ("counts_",)

    gamma_: FloatArray
    bin_edges_: FloatArray
    tau_fme_: FloatArray
    lower_: FloatArray
    upper_: FloatArray
    counts_: IntArray

    def __init__(
        self,
        bin_width: float = 0.06,
        margin: Any = 0.0,
        extrapolation_margin: float = 0.0,
        *,
        joints: Any = None,
        transient: float = 0.0,
    ) -> None:
        self.bin_width = bin_width
        self.margin = margin
        self.extrapolation_margin = extrapolation_margin
        self.joints = joints
        self.transient = transient

    def _attribute_names(self) -> tuple[str, ...]:
        return ("gamma_", "bin_edges_", "tau_fme_", "lower_", "upper_", "counts_")

    def _period(self, t: FloatArray, what: str) -> float:
        return regular_period(t, what)

    def _check_attributes(self) -> None:
        n_bins = self.bin_edges_.shape[0] - 1
        if self.bin_edges_.ndim != 1 or n_bins < 1 or np.any(np.diff(self.bin_edges_) <= 0):
            raise DimensionError(
                "bin_edges_ must be increasing, with at least 2 edges; got "
                f"{self.bin_edges_.tolist()}"
            )
        if self.gamma_.shape != (self.n_dof_,):
            raise DimensionError(
                f"gamma_ must have shape ({self.n_dof_},); got {self.gamma_.shape}"
            )
        for name in ("tau_fme_", "lower_", "upper_", "counts_"):
            shape = getattr(self, name).shape
            if shape != (n_bins, self.n_dof_):
                raise DimensionError(
                    f"{name} must have shape ({n_bins}, {self.n_dof_}); got {shape}"
                )

    def _check_hyper_parameters(self) -> tuple[float, float]:
        width = _as_float(self.bin_width)
        if not math.isfinite(width) or width <= 0:
            raise InputValueError(
                f"bin_width must be a positive, finite number [rad/s]; got {self.bin_width!r}"
            )
        extra = _as_float(self.extrapolation_margin)
        if not math.isfinite(extra) or extra < 0:
            raise InputValueError(
                "extrapolation_margin must be a finite number >= 0 [N m]; got "
                f"{self.extrapolation_margin!r}"
            )
        return width, extra

    def _grid(self, runs: list[ObserverSignals], width: float) -> FloatArray:
        slowest = min(float(run.velocity.min()) for run in runs)
        fastest = max(float(run.velocity.max()) for run in runs)
        first = math.floor(slowest / width)
        last = math.floor(fastest / width)
        if last - first + 1 > MAX_BINS:
            raise InputValueError(
                f"bin_width = {width} rad/s gives {last - first + 1} bins over the velocity range "
                f"[{slowest:.6g}, {fastest:.6g}] rad/s of the fit runs; at most {MAX_BINS} allowed"
            )
        return np.arange(first, last + 2, dtype=np.float64) * width

    def _fit(self, runs: list[ObserverSignals], keep: list[BoolArray], margin: FloatArray) -> None:
        width, _ = self._check_hyper_parameters()
        periods = [regular_period(run.t, f"fit run {i}") for i, run in enumerate(runs)]
        edges = self._grid(runs, width)
        n_bins, n_dof = edges.shape[0] - 1, runs[0].n_dof
        gain = runs[0].gain
        bins = [_bin_index(edges, run.velocity) for run in runs]
        gamma = np.empty(n_dof)
        tau = np.full((n_bins, n_dof), np.nan)
        for j in range(n_dof):
            gamma[j], visited, values = self._least_squares(runs, keep, bins, periods, gain, j)
            tau[visited, j] = values
        tau = _fill_nearest(tau, ~np.isnan(tau))

        errors, centres = [], []
        for run, index, dt in zip(runs, bins, periods, strict=True):
            centre, _ = self._centre(gamma, tau, index, run.model_torque, gain, dt, None)
            errors.append(run.residual - centre)
            centres.append(centre)
        kept = np.concatenate([i[k] for i, k in zip(bins, keep, strict=True)])
        error = np.concatenate([e[k] for e, k in zip(errors, keep, strict=True)])
        lower = np.full((n_bins, n_dof), np.inf)
        upper = np.full((n_bins, n_dof), -np.inf)
        counts = np.zeros((n_bins, n_dof), dtype=np.int64)
        for j in range(n_dof):
            np.minimum.at(lower[:, j], kept[:, j], error[:, j])
            np.maximum.at(upper[:, j], kept[:, j], error[:, j])
            np.add.at(counts[:, j], kept[:, j], 1)
        residual = np.concatenate([run.residual for run in runs])
        guard = rounding_guard(residual, np.concatenate(centres))
        self.gamma_ = gamma
        self.bin_edges_ = edges
        self.tau_fme_ = tau
        self.lower_ = _fill_nearest(lower, counts > 0) - margin - guard
        self.upper_ = _fill_nearest(upper, counts > 0) + margin + guard
        self.counts_ = counts

    @staticmethod
    def _least_squares(
        runs: list[ObserverSignals],
        keep: list[BoolArray],
        bins: list[IntArray],
        periods: list[float],
        gain: FloatArray,
        j: int,
    ) -> tuple[float, IntArray, FloatArray]:
        """γ_j and τ̂_fme of the bins joint j visited: least squares of eq. (4.45)."""
        visited = np.unique(np.concatenate([index[:, j] for index in bins]))
        rows, targets = [], []
        for run, index, dt, k in zip(runs, bins, periods, keep, strict=True):
            indicator = (index[:, j, None] == visited[None, :]).astype(np.float64)
            filtered, _ = first_order(indicator, gain[j], dt)
            rows.append(np.column_stack([run.model_torque[:, j], filtered])[k])
            targets.append(run.residual[k, j])
        solution = np.linalg.lstsq(np.concatenate(rows), np.concatenate(targets), rcond=None)[0]
        return float(solution[0]), visited, solution[1:]

    @staticmethod
    def _centre(
        gamma: FloatArray,
        tau: FloatArray,
        index: IntArray,
        model_torque: FloatArray,
        gain: FloatArray,
        dt: float,
        zi: FloatArray | None,
    ) -> tuple[FloatArray, FloatArray]:
        """γ h + K_I/(s+K_I)·τ̂_fme(q̇) and the filter state after the last sample."""
        friction, zf = first_order(tau[index, np.arange(tau.shape[1])], gain, dt, zi)
        return gamma * model_torque + friction, zf

    def _initial_zi(self, inputs: ThresholdInputs, dt: float) -> FloatArray:
        index = _bin_index(self.bin_edges_, inputs.velocity[0])
        return np.asarray(self.tau_fme_[index, np.arange(self.n_dof_)])

    def _run(
        self, state: ThresholdState, inputs: ThresholdInputs
    ) -> tuple[FloatArray, FloatArray, ThresholdState]:
        _, extra = self._check_hyper_parameters()
        index = _bin_index(self.bin_edges_, inputs.velocity)
        centre, zf = self._centre(
            self.gamma_, self.tau_fme_, index, inputs.model_torque, self.gain_, state.dt, state.zi
        )
        joints = np.arange(self.n_dof_)
        lower = self.lower_[index, joints] + centre
        upper = self.upper_[index, joints] + centre
        if extra > 0.0:
            visited = self.counts_ > 0
            first = np.argmax(visited, axis=0)
            last = visited.shape[0] - 1 - np.argmax(visited[::-1], axis=0)
            velocity = inputs.velocity
            outside = (velocity < self.bin_edges_[first]) | (velocity >= self.bin_edges_[last + 1])
            lower = lower - extra * outside
            upper = upper + extra * outside
        return lower, upper, ThresholdState(state.dt, zf)
