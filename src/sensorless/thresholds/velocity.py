"""Velocity-based variable thresholds UT/LT of eq. (4.33)-(4.39), tuned by eq. (4.45)-(4.47).

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

Combined form (eq. 4.19-4.21, 4.47): :class:`CombinedVelocityThreshold`
------------------------------------------------------------------------
A robot with joint torque sensors gives two residuals of the same run: r̂
from the motor torques (``kind="motor"``) and r̂_s from the sensors
(``kind="joint"``). With a small apparent motor inertia, M ≈ M_s, so
γ ≈ γ_s (eq. 4.47), and the thesis fits both with one least squares. Per
joint, with F = K_I/(s+K_I), the stacked rows are

    r̂   ≈ γ h   + F·τ̂_fme(q̇)       (eq. 4.30; h from the motor observer)
    r̂_s ≈ γ h_s - F·τ̂_sfe(q̇)       (eq. 4.31; h_s from the sensor observer)

with one γ and two sets of per-bin offsets. τ̂_sfe keeps the sign of
eq. (4.17), (4.31) and (4.38)-(4.39) - not the "+" of eq. (4.46) - so that
``tau_fme_ + tau_sfe_`` is the quantity of eq. (4.20)-(4.21). The friction
columns of the two blocks are the same filtered indicators (same run, same
velocity), so the solve projects them out of h and r̂ of both blocks at
once (Frisch-Waugh-Lovell), takes γ from the projected blocks and then each
block's offsets: the exact least squares solution, with n_bins columns
instead of 1 + 2 n_bins.

Does the measured sum of eq. (4.21) add information? No, given how our
observers build the residuals. :class:`~sensorless.observers.MomentumObserver`
gives, sample by sample, r̂ = h - F·τ_m + F·τ̂_fr and r̂_s = h_s - F·τ_J +
F·τ̂_frL. Filtering eq. (4.20) by F therefore gives

    F·(τ̂_fme + τ̂_sfe) ≈ F·[τ_J - τ̂_frL] - F·[τ_m - τ̂_fr] - h_s + h = r̂ - r̂_s,

and eq. (4.21) is the same when h and h_s differ only by the inertia term.
A row block for the measured sum, r̂ - r̂_s ≈ γ (h - h_s) + F·(τ̂_fme +
τ̂_sfe), is the first block minus the second: it adds no equation, and
stacking it would only change the weighting of the two blocks. So the fit
uses the two blocks alone; what eq. (4.21) contributes is the coupling that
makes one γ (and ``tau_fme_ + tau_sfe_`` as the estimate of the sum) right.

``weighting="equal"`` (default) is the single unweighted least squares of
the thesis. When one residual is much noisier than the other (motor-current
torque estimates often are), its rows dominate γ; ``"inverse_variance"``
refits with each block weighted by the inverse mean square of its error in
the unweighted fit (one step of feasible generalised least squares), which
makes γ at least about as good as that of the cleaner residual alone.
L and U of each residual come from its own fit errors, as above.

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
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..signals import Event, ObserverSignals
from .base import (
    BoolArray,
    Threshold,
    ThresholdInputs,
    ThresholdState,
    _check_margin,
    _check_runs,
    check_joints,
    check_seconds,
    first_order,
    regular_period,
    rounding_guard,
    stack,
)

__all__ = [
    "COMBINED_KIND",
    "KINDS",
    "MAX_BINS",
    "WEIGHTINGS",
    "CombinedVelocityState",
    "CombinedVelocityThreshold",
    "VelocityThreshold",
]

MAX_BINS = 10_000
"""Largest number of velocity bins; more means a ``bin_width`` far too small for the data."""

KINDS = ("motor", "joint")
"""Residuals a :class:`CombinedVelocityThreshold` bounds: r̂ (motor torques) and r̂_s (sensors)."""

COMBINED_KIND = "motor+joint"
"""``kind_`` of a :class:`CombinedVelocityThreshold` (the ``kind`` of its file)."""

WEIGHTINGS = ("equal", "inverse_variance")
"""Weightings of the two row blocks in the combined fit."""

IntArray = np.ndarray[Any, np.dtype[np.int64]]

# Per-bin attributes of a CombinedVelocityThreshold, each (n_bins, n_dof).
_COMBINED_PER_BIN = (
    "tau_fme_",
    "tau_sfe_",
    "lower_motor_",
    "upper_motor_",
    "lower_joint_",
    "upper_joint_",
    "counts_",
)


# --------------------------------------------------------------------------- shared helpers


class _Table(NamedTuple):
    """What LT/UT of one residual need (eq. 4.35-4.36, or 4.38-4.39 with tau = -τ̂_sfe)."""

    edges: FloatArray
    gamma: FloatArray
    tau: FloatArray
    lower: FloatArray
    upper: FloatArray
    counts: IntArray


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


def _check_widths(bin_width: Any, extrapolation_margin: Any) -> tuple[float, float]:
    """``bin_width`` [rad/s] and ``extrapolation_margin`` [N m] as checked floats."""
    width = _as_float(bin_width)
    if not math.isfinite(width) or width <= 0:
        raise InputValueError(
            f"bin_width must be a positive, finite number [rad/s]; got {bin_width!r}"
        )
    extra = _as_float(extrapolation_margin)
    if not math.isfinite(extra) or extra < 0:
        raise InputValueError(
            f"extrapolation_margin must be a finite number >= 0 [N m]; got {extrapolation_margin!r}"
        )
    return width, extra


def _grid(runs: list[ObserverSignals], width: float) -> FloatArray:
    """Bin edges [rad/s] covering the velocities of all joints of all runs."""
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


def _check_table(edges: FloatArray, gamma: FloatArray, n_dof: int, per_bin: dict[str, Any]) -> None:
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


def _friction_basis(
    bins: list[IntArray], keep: list[BoolArray], periods: list[float], gain: FloatArray, j: int
) -> tuple[IntArray, FloatArray]:
    """Bins joint j visited and K_I/(s+K_I)·1{q̇_j ∈ bin} on the kept samples, stacked."""
    visited = np.unique(np.concatenate([index[:, j] for index in bins]))
    blocks = []
    for index, dt, k in zip(bins, periods, keep, strict=True):
        indicator = (index[:, j, None] == visited[None, :]).astype(np.float64)
        filtered, _ = first_order(indicator, gain[j], dt)
        blocks.append(filtered[k])
    return visited, np.concatenate(blocks)


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


def _bin_bounds(
    runs: list[ObserverSignals],
    keep: list[BoolArray],
    bins: list[IntArray],
    periods: list[float],
    gamma: FloatArray,
    tau: FloatArray,
    gain: FloatArray,
    margin: FloatArray,
) -> tuple[FloatArray, FloatArray, IntArray]:
    """L and U per bin and joint (eq. 4.32), widened by ``margin``, and the fit samples per bin."""
    n_bins, n_dof = tau.shape
    errors, centres = [], []
    for run, index, dt in zip(runs, bins, periods, strict=True):
        centre, _ = _centre(gamma, tau, index, run.model_torque, gain, dt, None)
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
    lower = _fill_nearest(lower, counts > 0) - margin - guard
    upper = _fill_nearest(upper, counts > 0) + margin + guard
    return lower, upper, counts


def _initial_friction(table: _Table, velocity: FloatArray) -> FloatArray:
    """Filter state before the first sample: τ of its bin, held since forever."""
    index = _bin_index(table.edges, velocity[0])
    return np.asarray(table.tau[index, np.arange(table.tau.shape[1])])


def _table_bounds(
    table: _Table, gain: FloatArray, extra: float, state: ThresholdState, inputs: ThresholdInputs
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """LT and UT of eq. (4.35)-(4.36) and the friction filter state after the last sample."""
    index = _bin_index(table.edges, inputs.velocity)
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


# --------------------------------------------------------------------------- one residual


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
        per_bin = {
            name: getattr(self, name) for name in ("tau_fme_", "lower_", "upper_", "counts_")
        }
        _check_table(self.bin_edges_, self.gamma_, self.n_dof_, per_bin)

    def _table(self) -> _Table:
        return _Table(
            self.bin_edges_, self.gamma_, self.tau_fme_, self.lower_, self.upper_, self.counts_
        )

    def _fit(self, runs: list[ObserverSignals], keep: list[BoolArray], margin: FloatArray) -> None:
        width, _ = _check_widths(self.bin_width, self.extrapolation_margin)
        periods = [regular_period(run.t, f"fit run {i}") for i, run in enumerate(runs)]
        edges = _grid(runs, width)
        n_bins, n_dof = edges.shape[0] - 1, runs[0].n_dof
        gain = runs[0].gain
        bins = [_bin_index(edges, run.velocity) for run in runs]
        model_torque = stack(runs, keep, "model_torque")
        residual = stack(runs, keep, "residual")
        gamma = np.empty(n_dof)
        tau = np.full((n_bins, n_dof), np.nan)
        for j in range(n_dof):
            visited, basis = _friction_basis(bins, keep, periods, gain, j)
            design = np.column_stack([model_torque[:, j], basis])
            solution = np.linalg.lstsq(design, residual[:, j], rcond=None)[0]
            gamma[j] = solution[0]
            tau[visited, j] = solution[1:]
        tau = _fill_nearest(tau, ~np.isnan(tau))
        lower, upper, counts = _bin_bounds(runs, keep, bins, periods, gamma, tau, gain, margin)
        self.gamma_ = gamma
        self.bin_edges_ = edges
        self.tau_fme_ = tau
        self.lower_ = lower
        self.upper_ = upper
        self.counts_ = counts

    def _initial_zi(self, inputs: ThresholdInputs, dt: float) -> FloatArray:
        return _initial_friction(self._table(), inputs.velocity)

    def _run(
        self, state: ThresholdState, inputs: ThresholdInputs
    ) -> tuple[FloatArray, FloatArray, ThresholdState]:
        _, extra = _check_widths(self.bin_width, self.extrapolation_margin)
        lower, upper, zf = _table_bounds(self._table(), self.gain_, extra, state, inputs)
        return lower, upper, ThresholdState(state.dt, zf)


# --------------------------------------------------------------------------- combined


@dataclass(frozen=True, eq=False)
class CombinedVelocityState(ThresholdState):
    """Streaming state of a :class:`CombinedVelocityThreshold`: which residual it bounds.

    Attributes
    ----------
    dt : float
        Sample period of the stream [s].
    zi : ndarray of shape (n_dof,)
        Next output of the K_I/(s+K_I) filter of the friction term [N m].
    kind : {"motor", "joint"}
        Residual the stream's bounds are for: r̂ or r̂_s.
    """

    kind: str


def _as_pairs(signals: Any) -> tuple[list[ObserverSignals], list[ObserverSignals]]:
    """Motor and joint runs of a (motor, joint) pair or a sequence of such pairs."""
    message = (
        "a combined fit takes paired runs: (motor_signals, joint_signals), the r̂ and the r̂_s "
        "of one run, or a sequence of such pairs; got "
    )
    if isinstance(signals, ObserverSignals):
        raise InputTypeError(f"{message}one ObserverSignals of kind {signals.kind!r}")
    if not isinstance(signals, Sequence) or isinstance(signals, str):
        raise InputTypeError(message + type(signals).__name__)
    if not signals:
        raise InputValueError(message + "an empty sequence")
    items = list(signals)
    pairs = [items] if all(isinstance(item, ObserverSignals) for item in items) else items
    for i, pair in enumerate(pairs):
        if (
            not isinstance(pair, Sequence)
            or len(pair) != 2
            or not all(isinstance(run, ObserverSignals) for run in pair)
        ):
            what = f"{len(pair)} items" if isinstance(pair, Sequence) else type(pair).__name__
            raise InputTypeError(f"{message}{what} as pair {i}")
        kinds = (pair[0].kind, pair[1].kind)
        if kinds != KINDS:
            raise InputValueError(
                f"pair {i} must be (motor, joint) signals: r̂ from the motor torques, then r̂_s "
                f"from the joint torque sensors; got kinds {kinds}"
            )
    return [pair[0] for pair in pairs], [pair[1] for pair in pairs]


def _first_difference(a: FloatArray, b: FloatArray) -> int | None:
    """Flat index of the first entry where ``a`` and ``b`` differ beyond rounding, or None."""
    same = np.isclose(a, b, rtol=1e-9, atol=1e-12)
    return None if bool(same.all()) else int(np.argmin(same.reshape(-1)))


def _check_pairs(motor: list[ObserverSignals], joint: list[ObserverSignals]) -> None:
    """Both residuals of every pair come from one robot, gain and run (t and q̇)."""
    _check_runs(motor)
    _check_runs(joint)
    m, s = motor[0], joint[0]
    if m.n_dof != s.n_dof or m.robot != s.robot:
        raise DimensionError(
            f"motor and joint signals must come from one robot; the motor runs are {m.robot!r} "
            f"({m.n_dof} joints), the joint runs {s.robot!r} ({s.n_dof} joints)"
        )
    if not np.allclose(m.gain, s.gain, rtol=1e-9, atol=0.0):
        raise InputValueError(
            "motor and joint signals must use one observer gain K_I; the motor runs have "
            f"{m.gain.tolist()}, the joint runs {s.gain.tolist()} [1/s]"
        )
    for i, (a, b) in enumerate(zip(motor, joint, strict=True)):
        if a.n_samples != b.n_samples:
            raise DimensionError(
                f"pair {i}: the motor signals have {a.n_samples} samples, the joint signals "
                f"{b.n_samples}; both residuals must come from the same run"
            )
        k = _first_difference(a.t, b.t)
        if k is not None:
            raise InputValueError(
                f"pair {i}: t of the joint signals differs from t of the motor signals at "
                f"sample {k} ({b.t[k]!r} s vs {a.t[k]!r} s); both residuals must come from "
                "the same run"
            )
        k = _first_difference(a.velocity, b.velocity)
        if k is not None:
            row, col = divmod(k, a.n_dof)
            raise InputValueError(
                f"pair {i}: the velocity of the joint signals differs from that of the motor "
                f"signals at sample {row}, joint {col + 1} ({b.velocity[row, col]!r} vs "
                f"{a.velocity[row, col]!r} rad/s); both observers must use the q̇ of the same run"
            )


def _shared_slope(h: FloatArray, r: FloatArray, weights: FloatArray, scale: float) -> float:
    """Weighted least squares slope of r on h over both blocks (columns); 0 if h carries none."""
    denominator = float(np.sum(weights * np.sum(h * h, axis=0)))
    if denominator <= scale:
        return 0.0
    return float(np.sum(weights * np.sum(h * r, axis=0))) / denominator


def _combined_least_squares(
    columns: FloatArray, basis: FloatArray, weighting: str
) -> tuple[float, FloatArray, FloatArray, FloatArray]:
    """γ, τ̂_fme, τ̂_sfe of the visited bins and the block weights of one joint.

    ``columns`` holds h, r̂, h_s, r̂_s of the kept samples (shape (n, 4)) and
    ``basis`` the filtered bin indicators (n, n_visited), common to both blocks.
    """
    coefficients = np.linalg.lstsq(basis, columns, rcond=None)[0]
    # Frisch-Waugh-Lovell: γ of the stacked problem is the slope of the
    # projected-out residuals on the projected-out h, pooled over the blocks.
    projected = columns - basis @ coefficients
    h, r = projected[:, 0::2], projected[:, 1::2]
    # Below this, h lies in the span of the indicators (rounding only): no γ.
    norms = np.sum(columns[:, 0::2] ** 2, axis=0)
    tiny = (np.finfo(np.float64).eps * columns.shape[0]) ** 2
    weights = np.ones(2)
    gamma = _shared_slope(h, r, weights, tiny * float(np.sum(weights * norms)))
    if weighting == "inverse_variance":
        # Errors at the rounding level of the residuals count as equal (noise-free blocks).
        floor = 1e-24 * float(np.mean(columns[:, 1::2] ** 2))
        if floor > 0.0:
            weights = 1.0 / np.maximum(np.mean((r - gamma * h) ** 2, axis=0), floor)
            gamma = _shared_slope(h, r, weights, tiny * float(np.sum(weights * norms)))
    offsets = coefficients[:, 1::2] - gamma * coefficients[:, 0::2]
    return gamma, offsets[:, 0], -offsets[:, 1], weights / weights.sum()


class CombinedVelocityThreshold(Threshold):
    """Velocity-based bounds of r̂ and r̂_s with one γ, fitted together (section 4.5.2).

    One least squares per joint over paired runs - the motor-torque residual
    r̂ and the torque-sensor residual r̂_s of the same run - with a shared γ
    (eq. 4.47) and per-bin offsets τ̂_fme of r̂ and τ̂_sfe of r̂_s (see the
    module notes for the rows, the sign of τ̂_sfe and why eq. (4.21) adds no
    further rows). Applied to ``"motor"`` signals it gives LT/UT of
    eq. (4.35)-(4.36); to ``"joint"`` signals, those of eq. (4.38)-(4.39).

    Parameters
    ----------
    bin_width : float
        Width of the velocity bins [rad/s] (0.06 in section 4.5.2).
    margin : float or array-like of shape (n_dof,)
        Subtracted from L and added to U of both residuals [N m], >= 0.
    extrapolation_margin : float
        Extra widening [N m] where a joint's velocity is outside the bins it
        visited during fit, >= 0.
    weighting : {"equal", "inverse_variance"}
        Weights of the r̂ and r̂_s rows: equal (the thesis's single least
        squares), or the inverse mean square of each block's error in the
        equal-weight fit.
    joints : sequence of int, optional
        Monitored joints (1-based); None for all.
    transient : float
        Time skipped at the start of every fit run [s].

    Attributes
    ----------
    gamma_ : ndarray of shape (n_dof,)
        γ ≈ γ_s, the coefficient of h and of h_s [-].
    bin_edges_ : ndarray of shape (n_bins + 1,)
        Edges of the velocity bins [rad/s], shared by all joints.
    tau_fme_ : ndarray of shape (n_bins, n_dof)
        τ̂_fme per bin and joint [N m]: r̂ ≈ γ h + K_I/(s+K_I)·τ̂_fme.
    tau_sfe_ : ndarray of shape (n_bins, n_dof)
        τ̂_sfe per bin and joint [N m]: r̂_s ≈ γ h_s - K_I/(s+K_I)·τ̂_sfe.
        ``tau_fme_ + tau_sfe_`` estimates the sum of eq. (4.21).
    lower_motor_, upper_motor_ : ndarray of shape (n_bins, n_dof)
        L and U of r̂ per bin and joint [N m] (include ``margin``).
    lower_joint_, upper_joint_ : ndarray of shape (n_bins, n_dof)
        L and U of r̂_s per bin and joint [N m] (include ``margin``).
    counts_ : ndarray of shape (n_bins, n_dof)
        Number of fit samples per bin and joint (the same for both
        residuals); 0 marks a bin filled from the nearest visited one.
    weights_ : ndarray of shape (2, n_dof)
        Relative weight of the r̂ rows (row 0) and the r̂_s rows (row 1) in
        the fit of each joint [-]; columns sum to 1.

    ``kind_`` is ``"motor+joint"``. Streaming needs the residual:
    ``initial_state(..., kind="motor")`` or ``kind="joint"``. A
    :class:`~sensorless.detection.Detector` or a monitor streams without it;
    give them :meth:`for_kind`, the plain :class:`VelocityThreshold` of one
    residual (which also saves as one).

    Examples
    --------
    >>> import numpy as np
    >>> from sensorless.signals import ObserverSignals
    >>> t = np.arange(2000) * 1e-3
    >>> v = np.sin(2 * t)[:, None]
    >>> h = np.cos(3 * t)[:, None]
    >>> z = np.zeros_like(v)
    >>> motor = ObserverSignals(t, 0.02 * h, h, z, z, v, gain=20.0, kind="motor")
    >>> joint = ObserverSignals(t, 0.02 * h + 0.1, h, z, z, v, gain=20.0, kind="joint")
    >>> th = CombinedVelocityThreshold(bin_width=0.1).fit((motor, joint))
    >>> th.gamma_.round(6), th.tau_sfe_[:2, 0].round(6)
    (array([0.02]), array([-0.1, -0.1]))
    >>> lower, upper = th.bounds(joint)
    >>> bool(np.all((lower <= joint.residual) & (joint.residual <= upper)))
    True
    """

    name = "velocity_combined"
    _integer_attributes = ("counts_",)

    gamma_: FloatArray
    bin_edges_: FloatArray
    tau_fme_: FloatArray
    tau_sfe_: FloatArray
    lower_motor_: FloatArray
    upper_motor_: FloatArray
    lower_joint_: FloatArray
    upper_joint_: FloatArray
    counts_: IntArray
    weights_: FloatArray

    def __init__(
        self,
        bin_width: float = 0.06,
        margin: Any = 0.0,
        extrapolation_margin: float = 0.0,
        *,
        weighting: str = "equal",
        joints: Any = None,
        transient: float = 0.0,
    ) -> None:
        self.bin_width = bin_width
        self.margin = margin
        self.extrapolation_margin = extrapolation_margin
        self.weighting = weighting
        self.joints = joints
        self.transient = transient

    def _attribute_names(self) -> tuple[str, ...]:
        return ("gamma_", "bin_edges_", *_COMBINED_PER_BIN, "weights_")

    def _period(self, t: FloatArray, what: str) -> float:
        return regular_period(t, what)

    def _check_weighting(self) -> str:
        if self.weighting not in WEIGHTINGS:
            raise InputValueError(
                f"weighting must be one of {list(WEIGHTINGS)}; got {self.weighting!r}"
            )
        return str(self.weighting)

    def _check_attributes(self) -> None:
        if self.kind_ != COMBINED_KIND:
            raise InputValueError(
                f"a {self.name!r} threshold has kind {COMBINED_KIND!r}; got {self.kind_!r}"
            )
        per_bin = {name: getattr(self, name) for name in _COMBINED_PER_BIN}
        _check_table(self.bin_edges_, self.gamma_, self.n_dof_, per_bin)
        if self.weights_.shape != (2, self.n_dof_):
            raise DimensionError(
                f"weights_ must have shape (2, {self.n_dof_}); got {self.weights_.shape}"
            )

    # ----------------------------------------------------------------- fit

    def fit(  # type: ignore[override]  # takes (motor, joint) pairs, not single runs
        self,
        signals: Sequence[ObserverSignals] | Sequence[Sequence[ObserverSignals]],
    ) -> CombinedVelocityThreshold:
        """Fit both residuals' bounds on paired collision-free runs.

        Parameters
        ----------
        signals : (ObserverSignals, ObserverSignals) or sequence of such pairs
            ``(motor, joint)``: the residual r̂ (``kind="motor"``) and the
            residual r̂_s (``kind="joint"``) of one run, with the same ``t``
            and velocity; all runs of one robot and observer gain. The
            samples of all pairs are pooled.

        Returns
        -------
        self

        Raises
        ------
        InputTypeError
            Not a pair or a sequence of pairs (e.g. a single ObserverSignals).
        InputValueError
            A pair not in (motor, joint) order, or whose two runs differ in
            time or velocity; an unknown ``weighting``; bad hyper-parameters.
        DimensionError
            Runs of different joint counts or lengths.
        """
        motor, joint = _as_pairs(signals)
        _check_pairs(motor, joint)
        first = motor[0]
        margin = _check_margin(self.margin, first.n_dof)
        check_joints(self.joints, first.n_dof)
        transient = check_seconds(self.transient, "transient")
        keep = [run.t - run.t[0] >= transient for run in motor]
        if not any(k.any() for k in keep):
            raise InputValueError(
                f"no fit sample is left after skipping transient = {transient} s at the start "
                "of every run"
            )
        runs = [run for pair in zip(motor, joint, strict=True) for run in pair]
        self._fit(runs, [k for k in keep for _ in KINDS], margin)
        steps = np.concatenate([np.diff(run.t) for run in motor])
        self.robot_ = first.robot
        self.kind_ = COMBINED_KIND
        self.n_dof_ = first.n_dof
        self.gain_ = first.gain.copy()
        self.dt_ = float(np.median(steps)) if steps.size else float("nan")
        return self

    def _fit(self, runs: list[ObserverSignals], keep: list[BoolArray], margin: FloatArray) -> None:
        """Fit on checked runs ordered motor, joint, motor, joint, ... (one mask per run)."""
        width, _ = _check_widths(self.bin_width, self.extrapolation_margin)
        weighting = self._check_weighting()
        motor, joint, keep = runs[0::2], runs[1::2], keep[0::2]
        periods = [regular_period(run.t, f"fit pair {i}") for i, run in enumerate(motor)]
        edges = _grid(motor, width)
        n_bins, n_dof = edges.shape[0] - 1, motor[0].n_dof
        gain = motor[0].gain
        bins = [_bin_index(edges, run.velocity) for run in motor]
        columns = np.stack(
            [
                stack(block, keep, name)
                for block in (motor, joint)
                for name in ("model_torque", "residual")
            ],
            axis=1,
        )
        gamma = np.empty(n_dof)
        weights = np.empty((2, n_dof))
        tau_fme = np.full((n_bins, n_dof), np.nan)
        tau_sfe = np.full((n_bins, n_dof), np.nan)
        for j in range(n_dof):
            visited, basis = _friction_basis(bins, keep, periods, gain, j)
            gamma[j], fme, sfe, weights[:, j] = _combined_least_squares(
                columns[:, :, j], basis, weighting
            )
            tau_fme[visited, j] = fme
            tau_sfe[visited, j] = sfe
        visited_bins = ~np.isnan(tau_fme)
        tau_fme = _fill_nearest(tau_fme, visited_bins)
        tau_sfe = _fill_nearest(tau_sfe, visited_bins)
        lower_m, upper_m, counts = _bin_bounds(
            motor, keep, bins, periods, gamma, tau_fme, gain, margin
        )
        lower_s, upper_s, _ = _bin_bounds(joint, keep, bins, periods, gamma, -tau_sfe, gain, margin)
        self.gamma_ = gamma
        self.bin_edges_ = edges
        self.tau_fme_ = tau_fme
        self.tau_sfe_ = tau_sfe
        self.lower_motor_, self.upper_motor_ = lower_m, upper_m
        self.lower_joint_, self.upper_joint_ = lower_s, upper_s
        self.counts_ = counts
        self.weights_ = weights

    # ----------------------------------------------------------------- one residual

    def _table(self, kind: Any) -> _Table:
        if kind not in KINDS:
            hint = (
                "; pass kind='motor' or kind='joint', or stream for_kind(kind) where a "
                "single-residual threshold is expected (Detector, monitor)"
                if kind is None
                else ""
            )
            raise InputValueError(
                f"a {self.name!r} threshold bounds 'motor' (r̂) and 'joint' (r̂_s) signals; "
                f"got kind {kind!r}{hint}"
            )
        if kind == "motor":
            tau, lower, upper = self.tau_fme_, self.lower_motor_, self.upper_motor_
        else:
            tau, lower, upper = -self.tau_sfe_, self.lower_joint_, self.upper_joint_
        return _Table(self.bin_edges_, self.gamma_, tau, lower, upper, self.counts_)

    def for_kind(self, kind: str) -> VelocityThreshold:
        """The fitted :class:`VelocityThreshold` of one residual.

        Its ``tau_fme_`` is ``tau_fme_`` for ``"motor"`` and ``-tau_sfe_`` for
        ``"joint"`` (the sign a single fit on r̂_s finds, see the module notes);
        it gives the same bounds as this threshold on signals of that kind,
        and works wherever a single-kind threshold is expected (detector,
        monitor, its own file).

        Parameters
        ----------
        kind : {"motor", "joint"}
            The residual: r̂ (motor torques) or r̂_s (joint torque sensors).

        Returns
        -------
        VelocityThreshold
        """
        self._check_fitted()
        table = self._table(kind)
        single = VelocityThreshold(
            self.bin_width,
            self.margin,
            self.extrapolation_margin,
            joints=self.joints,
            transient=self.transient,
        )
        single.robot_ = self.robot_
        single.kind_ = kind
        single.n_dof_ = self.n_dof_
        single.gain_ = self.gain_.copy()
        single.dt_ = self.dt_
        single.gamma_ = table.gamma.copy()
        single.bin_edges_ = table.edges.copy()
        single.tau_fme_ = np.array(table.tau, dtype=np.float64)
        single.lower_ = table.lower.copy()
        single.upper_ = table.upper.copy()
        single.counts_ = table.counts.copy()
        return single

    # ----------------------------------------------------------------- apply

    def check_signals(self, signals: ObserverSignals) -> None:
        """Raise unless ``signals`` are r̂ or r̂_s of the robot and gain the threshold fits.

        Raises
        ------
        NotFittedError
            Before :meth:`fit`.
        DimensionError
            Another number of joints.
        InputValueError
            A kind other than ``"motor"`` or ``"joint"``, another robot name
            or observer gain.
        """
        self._check_fitted()
        if not isinstance(signals, ObserverSignals):
            raise InputTypeError(
                f"signals must be an ObserverSignals; got {type(signals).__name__}"
            )
        self.for_kind(signals.kind).check_signals(signals)

    def bounds(self, signals: ObserverSignals) -> tuple[FloatArray, FloatArray]:
        """LT/UT of r̂ (eq. 4.35-4.36) or r̂_s (eq. 4.38-4.39), as ``signals.kind`` says.

        Parameters
        ----------
        signals : ObserverSignals
            Run of kind ``"motor"`` or ``"joint"`` of the robot and gain used for fit.

        Returns
        -------
        lower, upper : ndarray of shape (n_samples, n_dof)
            Bounds [N m]; ``-inf``/``+inf`` for joints that are not monitored.
        """
        self.check_signals(signals)
        return self.for_kind(signals.kind).bounds(signals)

    def detect(
        self, signals: ObserverSignals, *, min_duration: float = 0.0, hold: float = 0.0
    ) -> list[Event]:
        """Collision events of a recorded run of kind ``"motor"`` or ``"joint"``.

        Those of ``for_kind(signals.kind).detect(...)``, labelled ``"velocity"``.
        """
        self.check_signals(signals)
        return self.for_kind(signals.kind).detect(signals, min_duration=min_duration, hold=hold)

    def initial_state(
        self,
        model_torque: ArrayLike,
        friction: ArrayLike,
        sign: ArrayLike,
        velocity: ArrayLike,
        *,
        position: ArrayLike | None = None,
        acceleration: ArrayLike | None = None,
        dt: float | None = None,
        kind: str | None = None,
    ) -> CombinedVelocityState:
        """Streaming state before the first sample of r̂ (``kind="motor"``) or r̂_s (``"joint"``).

        Parameters
        ----------
        model_torque, friction, sign, velocity : array-like of shape (n_dof,)
            First sample of h (or h_s) [N m], K_I/(s+K_I)·τ̂_fr [N m],
            K_I/(s+K_I)·sign(q̇) [-] and q̇ [rad/s].
        position, acceleration : array-like of shape (n_dof,), optional
            Unused; accepted as by every family.
        dt : float, optional
            Sample period of the stream [s]; by default ``dt_`` of the fit runs.
        kind : {"motor", "joint"}
            Residual of the stream; required.

        Returns
        -------
        CombinedVelocityState
        """
        self._check_fitted()
        self._table(kind)
        state = super().initial_state(
            model_torque,
            friction,
            sign,
            velocity,
            position=position,
            acceleration=acceleration,
            dt=dt,
        )
        return CombinedVelocityState(state.dt, state.zi[KINDS.index(str(kind))], str(kind))

    def _initial_zi(self, inputs: ThresholdInputs, dt: float) -> FloatArray:
        """Filter states of both residuals (rows "motor", "joint"); initial_state keeps one."""
        return np.stack([_initial_friction(self._table(k), inputs.velocity) for k in KINDS])

    def _run(
        self, state: ThresholdState, inputs: ThresholdInputs
    ) -> tuple[FloatArray, FloatArray, ThresholdState]:
        if not isinstance(state, CombinedVelocityState):
            raise InputTypeError(
                f"state must be a CombinedVelocityState from initial_state(..., kind='motor' "
                f"or 'joint'), step or process; got {type(state).__name__}"
            )
        _, extra = _check_widths(self.bin_width, self.extrapolation_margin)
        table = self._table(state.kind)
        lower, upper, zf = _table_bounds(table, self.gain_, extra, state, inputs)
        return lower, upper, CombinedVelocityState(state.dt, zf, state.kind)
