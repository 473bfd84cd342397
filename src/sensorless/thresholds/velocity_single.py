"""The velocity-based bounds of one residual, LT/UT of eq. (4.35)-(4.36), fitted by eq. (4.45).

The model and the fit are described in :mod:`sensorless.thresholds.velocity`,
the bins in :mod:`sensorless.thresholds.velocity_bins`.
"""

from __future__ import annotations

import numpy as np

from .._validation import FloatArray
from ..signals import ObserverSignals
from .base import StreamBounds
from .fitting import BoolArray, stack
from .state import ThresholdInputs, ThresholdState
from .velocity_bins import BinTable, VelocityBinsThreshold, initial_friction

__all__ = ["VelocityThreshold"]


class VelocityThreshold(VelocityBinsThreshold):
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
    min_bin_time : float
        Fit data [s] a bin needs for its own L and U, >= 0; a sparser bin
        takes them over the nearest bins that together hold this much (see
        :mod:`sensorless.thresholds.velocity_bins`). 0: no pooling.
    joints, transient
        As for every family, see :class:`~sensorless.thresholds.base.Threshold`.

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
        Number of fit samples per bin and joint; 0 marks a bin the fit runs
        never visited (τ̂_fme from the nearest visited one).
    pooled_bins_ : ndarray of bool, shape (n_bins, n_dof)
        Bins whose L and U are pooled (less than ``min_bin_time`` of fit
        data); ``pooled_bins_.sum(axis=0)`` counts them per joint.
    """

    name = "velocity"
    _per_bin = ("tau_fme_", "lower_", "upper_", "counts_")

    tau_fme_: FloatArray
    lower_: FloatArray
    upper_: FloatArray

    def _attribute_names(self) -> tuple[str, ...]:
        return ("gamma_", "bin_edges_", *self._per_bin)

    def _table(self) -> BinTable:
        return BinTable(
            self.bin_edges_, self.gamma_, self.tau_fme_, self.lower_, self.upper_, self.counts_
        )

    def _fit(self, runs: list[ObserverSignals], keep: list[BoolArray], margin: FloatArray) -> None:
        grid = self._grid(runs, keep, "fit run")
        model_torque = stack(runs, keep, "model_torque")
        residual = stack(runs, keep, "residual")

        def solve(j: int, basis: FloatArray) -> tuple[float, FloatArray]:
            design = np.column_stack([model_torque[:, j], basis])
            solution = np.linalg.lstsq(design, residual[:, j], rcond=None)[0]
            return float(solution[0]), np.asarray(solution[1:, None], dtype=np.float64)

        gamma, (tau,) = grid.fit(runs[0].n_dof, 1, solve)
        self.gamma_ = gamma
        self.bin_edges_ = grid.edges
        self.tau_fme_ = tau
        self.lower_, self.upper_, self.counts_ = grid.bounds(
            runs, gamma, tau, margin, self._fit_least(runs)
        )

    def _initial_state_checked(
        self, inputs: ThresholdInputs, dt: float, kind: str | None = None
    ) -> ThresholdState:
        return ThresholdState(dt, initial_friction(self._table(), inputs.velocity))

    def _run(self, state: ThresholdState, inputs: ThresholdInputs) -> StreamBounds:
        lower, upper, zf = self._table_bounds(self._table(), state, inputs)
        return lower, upper, ThresholdState(state.dt, zf)
