"""Velocity bins: the per-bin tables behind both velocity-based thresholds (eq. 4.32-4.39).

All joints share one grid of bins of width ``bin_width`` [rad/s], from the
slowest to the fastest velocity of any joint in the fit runs; bin ``k``
covers ``[k w, (k + 1) w)``, so zero velocity is a bin edge. A bin of the
grid that a joint never visited takes the values of the nearest visited bin
of that joint (ties: the bin of lower velocity), and a velocity beyond the
grid uses the first or last bin. Where the velocity of a joint is outside
the range of the bins it visited during fit, its bounds are widened by
``extrapolation_margin`` [N m].

Sparse bins. L and U of a bin are the extremes of its fit errors, and the
extreme of n exchangeable errors is exceeded by a new one with probability
1/(n + 1): a bin the fit runs crossed in a few milliseconds (a via-point
motion accelerating through it) gets a band that a new run leaves at once.
So a bin with less than ``min_bin_time`` [s] of fit data takes L and U over
the smallest window of bins [k - w, k + w] around it that holds that much
(:func:`pool_sparse`); the whole grid when the joint has less. Every band
then rests on at least ``min_bin_time`` of data, pooling never narrows a
band, and a bin with enough data keeps its own. τ̂ of a sparse bin stays its
own least-squares value. The default, :data:`MIN_BIN_TIME` = 0.5 s, is the
fit time below which :class:`sensorless.monitor.Calibration` calls a bin
sparse; ``min_bin_time=0`` is the rule without pooling (a never-visited bin
takes the values of the nearest visited one).

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
    "MIN_BIN_TIME",
    "BinGrid",
    "BinTable",
    "VelocityBinsThreshold",
    "initial_friction",
    "table_bounds",
]

MAX_BINS = 10_000
"""Largest number of velocity bins; more means a ``bin_width`` far too small for the data."""

MIN_BIN_TIME = 0.5
"""Default ``min_bin_time`` [s]: fit data below which a bin's L and U are pooled with neighbours."""

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


def pooled_windows(counts: IntArray, least: float) -> IntArray:
    """Half-width w of the window of bins [k - w, k + w] behind the L and U of every bin.

    0 for a bin with at least ``least`` fit samples; otherwise the smallest w
    whose window (cut at the ends of the grid) holds ``least`` samples, or
    the whole grid when the joint has fewer. Shape (n_bins, n_dof).
    """
    n_bins = counts.shape[0]
    cumulative = np.vstack([np.zeros((1, counts.shape[1]), np.int64), np.cumsum(counts, axis=0)])
    k = np.arange(n_bins)[:, None]
    joints = np.arange(counts.shape[1])[None, :]

    def held(w: IntArray) -> IntArray:
        top = np.minimum(k + w + 1, n_bins)
        bottom = np.maximum(k - w, 0)
        return np.asarray(cumulative[top, joints] - cumulative[bottom, joints])

    # Bisection on w for all bins at once: held(w) grows with w.
    low = np.zeros(counts.shape, np.int64)  # held(low) may fall short
    high = np.full(counts.shape, n_bins, np.int64)  # the whole grid: enough, or all there is
    enough = counts >= least
    high[enough] = 0
    while np.any(high - low > 1):
        middle = (low + high) // 2
        ok = held(middle) >= least
        high = np.where(ok, middle, high)
        low = np.where(ok, low, middle)
    return high


def pool_sparse(
    lower: FloatArray, upper: FloatArray, counts: IntArray, least: float
) -> tuple[FloatArray, FloatArray]:
    """L and U of every bin from the fit samples of its window (:func:`pooled_windows`).

    ``lower`` and ``upper`` are the per-bin extremes of the fit errors (+/-inf
    in empty bins). A bin with ``least`` samples or more keeps its own; a
    sparser one takes the extremes over the smallest window of bins around it
    that holds ``least`` samples. With ``least <= 0`` nothing is pooled and an
    empty bin takes the values of the nearest visited one (ties: lower).
    """
    if least <= 0:
        visited = counts > 0
        return fill_nearest(lower, visited), fill_nearest(upper, visited)
    windows = pooled_windows(counts, least)
    pooled_lower, pooled_upper = lower.copy(), upper.copy()
    for k, j in np.argwhere(windows > 0):
        window = slice(max(k - windows[k, j], 0), k + windows[k, j] + 1)
        pooled_lower[k, j] = lower[window, j].min()
        pooled_upper[k, j] = upper[window, j].max()
    return pooled_lower, pooled_upper


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
        self,
        runs: list[ObserverSignals],
        gamma: FloatArray,
        tau: FloatArray,
        margin: FloatArray,
        least: float,
    ) -> tuple[FloatArray, FloatArray, IntArray]:
        """L and U per bin and joint (eq. 4.32), widened by ``margin``, and fit samples per bin.

        Bins with fewer than ``least`` fit samples take the extremes of their
        neighbours' (:func:`pool_sparse`).
        """
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
        lower, upper = pool_sparse(lower, upper, counts, least)
        lower = lower - margin - guard
        upper = upper + margin + guard
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
    min_bin_time: Any

    gamma_: FloatArray
    bin_edges_: FloatArray
    counts_: IntArray

    def __init__(
        self,
        bin_width: float = 0.06,
        margin: Any = 0.0,
        extrapolation_margin: float = 0.0,
        *,
        min_bin_time: float = MIN_BIN_TIME,
        joints: Any = None,
        transient: float = 0.0,
    ) -> None:
        super().__init__(margin, joints=joints, transient=transient)
        self.bin_width = bin_width
        self.extrapolation_margin = extrapolation_margin
        self.min_bin_time = min_bin_time

    @property
    def pooled_bins_(self) -> BoolArray:
        """Bins whose L and U are pooled with neighbours, shape (n_bins, n_dof).

        The bins with less than ``min_bin_time`` of fit data (``counts_ *
        dt_``), never-visited ones included; ``pooled_bins_.sum(axis=0)``
        counts them per joint.
        """
        self._check_fitted()
        return np.asarray(self.counts_ < self._least(self.dt_))

    def _least(self, period: float) -> float:
        """Fit samples [-] a bin needs for its own L and U at sample period ``period`` [s]."""
        return check_scalar(self.min_bin_time, "min_bin_time", "s", "nonnegative") / period

    def _fit_least(self, runs: list[ObserverSignals]) -> float:
        """:meth:`_least` at the median period of checked fit runs (what becomes ``dt_``)."""
        return self._least(float(np.median(np.concatenate([np.diff(run.t) for run in runs]))))

    def _period(self, t: FloatArray, what: str) -> float:
        return regular_period(t, what)

    def _grid(self, runs: list[ObserverSignals], keep: list[BoolArray], what: str) -> BinGrid:
        """Check the hyper-parameters and lay the bins over checked fit runs."""
        width, _ = check_widths(self.bin_width, self.extrapolation_margin)
        check_scalar(self.min_bin_time, "min_bin_time", "s", "nonnegative")
        return BinGrid.of_runs(runs, keep, width, what)

    def _check_attributes(self) -> None:
        check_widths(self.bin_width, self.extrapolation_margin)
        check_scalar(self.min_bin_time, "min_bin_time", "s", "nonnegative")
        per_bin = {name: getattr(self, name) for name in self._per_bin}
        check_table(self.bin_edges_, self.gamma_, self.n_dof_, per_bin)

    def _table_bounds(
        self, table: BinTable, state: ThresholdState, inputs: ThresholdInputs
    ) -> tuple[FloatArray, FloatArray, FloatArray]:
        """:func:`table_bounds` with this threshold's gain and (checked) extrapolation margin."""
        return table_bounds(table, self.gain_, float(self.extrapolation_margin), state, inputs)
