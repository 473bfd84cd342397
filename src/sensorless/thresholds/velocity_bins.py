"""Velocity bins: the per-bin tables behind both velocity-based thresholds (eq. 4.32-4.39).

All joints share one grid of bins of width ``bin_width`` [rad/s], from the
slowest to the fastest velocity of any joint in the fit runs; bin ``k``
covers ``[k w, (k + 1) w)``, so zero velocity is a bin edge. A bin of the
grid that a joint never visited takes the values of the nearest visited bin
of that joint (ties: the bin of lower velocity), and a velocity beyond the
grid uses the first or last bin. Where the velocity of a joint is outside
the range of the bins it visited during fit, its bounds are widened by
``extrapolation_margin`` [N m].

:class:`BinTable` is what LT/UT of one residual need; :func:`table_bounds`
applies it to checked inputs. :class:`VelocityBinsThreshold` is the part of
:class:`~sensorless.thresholds.velocity.VelocityThreshold` and
:class:`~sensorless.thresholds.velocity.CombinedVelocityThreshold` that is the
same: hyper-parameters, the bin grid and the per-joint fit over it.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, ClassVar, NamedTuple

import numpy as np

from .._validation import FloatArray, check_scalar
from ..exceptions import DimensionError, InputValueError
from ..signals import ObserverSignals
from .base import Threshold
from .checks import regular_period
from .filtering import first_order
from .fitting import BoolArray, rounding_guard
from .state import IntArray, ThresholdInputs, ThresholdState

__all__ = [
    "MAX_BINS",
    "BinGrid",
    "BinTable",
    "VelocityBinsThreshold",
    "initial_friction",
    "table_bounds",
]

MAX_BINS = 10_000
"""Largest number of velocity bins; more means a ``bin_width`` far too small for the data."""

Solver = Callable[[int, FloatArray], tuple[float, FloatArray]]
"""``solve(j, basis)`` of :meth:`BinGrid.fit`: γ_j and the offsets of the visited bins."""


class BinTable(NamedTuple):
    """What LT/UT of one residual need (eq. 4.35-4.36, or 4.38-4.39 with tau = -τ̂_sfe).

    Edges [rad/s] of shape (n_bins + 1,), γ [-] of shape (n_dof,), and per bin
    and joint (n_bins, n_dof): τ [N m], L and U [N m], fit samples.
    """

    edges: FloatArray
    gamma: FloatArray
    tau: FloatArray
    lower: FloatArray
    upper: FloatArray
    counts: IntArray


def bin_index(edges: FloatArray, velocity: FloatArray) -> IntArray:
    """Bin of every velocity [rad/s]; beyond the grid, the first or last bin."""
    index = np.searchsorted(edges, velocity, side="right") - 1
    return np.clip(index, 0, edges.shape[0] - 2).astype(np.int64)


def fill_nearest(values: FloatArray, valid: BoolArray) -> FloatArray:
    """Give every invalid entry of each column the value of the nearest valid one (ties: lower)."""
    filled = values.copy()
    positions = np.arange(values.shape[0])
    for j in range(values.shape[1]):
        source = np.flatnonzero(valid[:, j])
        nearest = source[np.argmin(np.abs(positions[:, None] - source[None, :]), axis=1)]
        filled[:, j] = values[nearest, j]
    return np.asarray(filled, dtype=np.float64)


def check_widths(bin_width: Any, extrapolation_margin: Any) -> tuple[float, float]:
    """``bin_width`` [rad/s] and ``extrapolation_margin`` [N m] as checked floats."""
    try:
        width = float(bin_width)
    except (TypeError, ValueError):
        width = math.nan
    if not math.isfinite(width) or width <= 0:
        raise InputValueError(
            f"bin_width must be a positive, finite number [rad/s]; got {bin_width!r}"
        )
    return width, check_scalar(extrapolation_margin, "extrapolation_margin", "N m", "nonnegative")


def check_table(edges: FloatArray, gamma: FloatArray, n_dof: int, per_bin: dict[str, Any]) -> None:
    """Shapes of fitted attributes read from a file."""
    n_bins = edges.shape[0] - 1
    if edges.ndim != 1 or n_bins < 1 or np.any(np.diff(edges) <= 0):
        raise DimensionError(
            f"bin_edges_ must be increasing, with at least 2 edges; got {edges.tolist()}"
        )
    if gamma.shape != (n_dof,):
        raise DimensionError(f"gamma_ must have shape ({n_dof},); got {gamma.shape}")
    for name, value in per_bin.items():
        if value.shape != (n_bins, n_dof):
            raise DimensionError(f"{name} must have shape ({n_bins}, {n_dof}); got {value.shape}")


class BinGrid(NamedTuple):
    """The bins of checked fit runs: edges [rad/s], bin of every sample, periods [s]."""

    edges: FloatArray
    bins: list[IntArray]
    periods: list[float]
    keep: list[BoolArray]
    gain: FloatArray

    @classmethod
    def of_runs(
        cls, runs: list[ObserverSignals], keep: list[BoolArray], width: float, what: str
    ) -> BinGrid:
        """Bins of width ``width`` [rad/s] covering all joints of ``runs``; ``what`` names a run."""
        periods = [regular_period(run.t, f"{what} {i}") for i, run in enumerate(runs)]
        slowest = min(float(run.velocity.min()) for run in runs)
        fastest = max(float(run.velocity.max()) for run in runs)
        first = math.floor(slowest / width)
        last = math.floor(fastest / width)
        if last - first + 1 > MAX_BINS:
            raise InputValueError(
                f"bin_width = {width} rad/s gives {last - first + 1} bins over the velocity "
                f"range [{slowest:.6g}, {fastest:.6g}] rad/s of the fit runs; at most "
                f"{MAX_BINS} allowed"
            )
        edges = np.arange(first, last + 2, dtype=np.float64) * width
        bins = [bin_index(edges, run.velocity) for run in runs]
        return cls(edges, bins, periods, keep, runs[0].gain)

    def friction_basis(self, j: int) -> tuple[IntArray, FloatArray]:
        """Bins joint j visited and K_I/(s+K_I)·1{q̇_j ∈ bin} on the kept samples, stacked."""
        visited = np.unique(np.concatenate([index[:, j] for index in self.bins]))
        blocks = []
        for index, dt, k in zip(self.bins, self.periods, self.keep, strict=True):
            indicator = (index[:, j, None] == visited[None, :]).astype(np.float64)
            filtered, _ = first_order(indicator, self.gain[j], dt)
            blocks.append(filtered[k])
        return visited, np.concatenate(blocks)

    def fit(self, n_dof: int, n_tables: int, solve: Solver) -> tuple[FloatArray, list[FloatArray]]:
        """γ and ``n_tables`` per-bin offset tables (n_bins, n_dof), one least squares per joint.

        ``solve(j, basis)`` returns γ_j and the offsets of the bins joint j
        visited, shape (n_visited, n_tables); the other bins are filled from
        the nearest visited one.
        """
        n_bins = self.edges.shape[0] - 1
        gamma = np.empty(n_dof)
        tables = np.full((n_tables, n_bins, n_dof), np.nan)
        for j in range(n_dof):
            visited, basis = self.friction_basis(j)
            gamma[j], offsets = solve(j, basis)
            tables[:, visited, j] = offsets.T
        visited_bins = ~np.isnan(tables[0])
        return gamma, [fill_nearest(table, visited_bins) for table in tables]

    def bounds(
        self, runs: list[ObserverSignals], gamma: FloatArray, tau: FloatArray, margin: FloatArray
    ) -> tuple[FloatArray, FloatArray, IntArray]:
        """L and U per bin and joint (eq. 4.32), widened by ``margin``, and fit samples per bin."""
        n_bins, n_dof = tau.shape
        errors, centres = [], []
        for run, index, dt in zip(runs, self.bins, self.periods, strict=True):
            centre, _ = _centre(gamma, tau, index, run.model_torque, self.gain, dt, None)
            errors.append(run.residual - centre)
            centres.append(centre)
        kept = np.concatenate([i[k] for i, k in zip(self.bins, self.keep, strict=True)])
        error = np.concatenate([e[k] for e, k in zip(errors, self.keep, strict=True)])
        lower = np.full((n_bins, n_dof), np.inf)
        upper = np.full((n_bins, n_dof), -np.inf)
        counts = np.zeros((n_bins, n_dof), dtype=np.int64)
        for j in range(n_dof):
            np.minimum.at(lower[:, j], kept[:, j], error[:, j])
            np.maximum.at(upper[:, j], kept[:, j], error[:, j])
            np.add.at(counts[:, j], kept[:, j], 1)
        residual = np.concatenate([run.residual for run in runs])
        guard = rounding_guard(residual, np.concatenate(centres))
        lower = fill_nearest(lower, counts > 0) - margin - guard
        upper = fill_nearest(upper, counts > 0) + margin + guard
        return lower, upper, counts


def _centre(
    gamma: FloatArray,
    tau: FloatArray,
    index: IntArray,
    model_torque: FloatArray,
    gain: FloatArray,
    dt: float,
    zi: FloatArray | None,
) -> tuple[FloatArray, FloatArray]:
    """γ h + K_I/(s+K_I)·τ(q̇) and the filter state after the last sample."""
    friction, zf = first_order(tau[index, np.arange(tau.shape[1])], gain, dt, zi)
    return gamma * model_torque + friction, zf


def initial_friction(table: BinTable, velocity: FloatArray) -> FloatArray:
    """Filter state before the first sample: τ of its bin, held since forever."""
    index = bin_index(table.edges, velocity[0])
    return np.asarray(table.tau[index, np.arange(table.tau.shape[1])])


def table_bounds(
    table: BinTable, gain: FloatArray, extra: float, state: ThresholdState, inputs: ThresholdInputs
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """LT and UT of eq. (4.35)-(4.36) and the friction filter state after the last sample."""
    index = bin_index(table.edges, inputs.velocity)
    centre, zf = _centre(
        table.gamma, table.tau, index, inputs.model_torque, gain, state.dt, state.zi
    )
    joints = np.arange(table.tau.shape[1])
    lower = table.lower[index, joints] + centre
    upper = table.upper[index, joints] + centre
    if extra > 0.0:
        visited = table.counts > 0
        first = np.argmax(visited, axis=0)
        last = visited.shape[0] - 1 - np.argmax(visited[::-1], axis=0)
        velocity = inputs.velocity
        outside = (velocity < table.edges[first]) | (velocity >= table.edges[last + 1])
        lower = lower - extra * outside
        upper = upper + extra * outside
    return lower, upper, zf


class VelocityBinsThreshold(Threshold):
    """What the velocity-based families share: hyper-parameters, bin grid, file checks.

    Subclasses set ``_per_bin``, the names of their (n_bins, n_dof) attributes.
    """

    _integer_attributes = ("counts_",)
    _per_bin: ClassVar[tuple[str, ...]]

    bin_width: Any
    extrapolation_margin: Any

    gamma_: FloatArray
    bin_edges_: FloatArray
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
        super().__init__(margin, joints=joints, transient=transient)
        self.bin_width = bin_width
        self.extrapolation_margin = extrapolation_margin

    def _period(self, t: FloatArray, what: str) -> float:
        return regular_period(t, what)

    def _grid(self, runs: list[ObserverSignals], keep: list[BoolArray], what: str) -> BinGrid:
        """Check the hyper-parameters and lay the bins over checked fit runs."""
        width, _ = check_widths(self.bin_width, self.extrapolation_margin)
        return BinGrid.of_runs(runs, keep, width, what)

    def _check_attributes(self) -> None:
        check_widths(self.bin_width, self.extrapolation_margin)
        per_bin = {name: getattr(self, name) for name in self._per_bin}
        check_table(self.bin_edges_, self.gamma_, self.n_dof_, per_bin)

    def _table_bounds(
        self, table: BinTable, state: ThresholdState, inputs: ThresholdInputs
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """:func:`table_bounds` with this threshold's gain and (checked) extrapolation margin."""
        return table_bounds(table, self.gain_, float(self.extrapolation_margin), state, inputs)
