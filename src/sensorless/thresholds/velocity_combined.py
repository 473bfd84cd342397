"""Velocity-based bounds of r̂ and r̂_s with one γ, fitted together (eq. 4.19-4.21, 4.47).

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
L and U of each residual come from its own fit errors, as for one residual.

The bins, their fill and ``extrapolation_margin`` are those of
:mod:`sensorless.thresholds.velocity_bins`; the model of one residual is in
:mod:`sensorless.thresholds.velocity`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, cast

import numpy as np

from .._validation import FloatArray
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..signals import ObserverSignals
from .base import StreamBounds
from .checks import check_runs, robot_mismatch
from .fitting import BoolArray, stack
from .state import ThresholdInputs, ThresholdState
from .velocity_bins import MIN_BIN_TIME, BinTable, VelocityBinsThreshold, initial_friction
from .velocity_single import VelocityThreshold

__all__ = [
    "COMBINED_KIND",
    "KINDS",
    "WEIGHTINGS",
    "CombinedVelocityState",
    "CombinedVelocityThreshold",
]

KINDS = ("motor", "joint")
"""Residuals a :class:`CombinedVelocityThreshold` bounds: r̂ (motor torques) and r̂_s (sensors)."""

COMBINED_KIND = "motor+joint"
"""``kind_`` of a :class:`CombinedVelocityThreshold` (the ``kind`` of its file)."""

WEIGHTINGS = ("equal", "inverse_variance")
"""Weightings of the two row blocks in the combined fit."""


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
    check_runs(motor)
    check_runs(joint)
    m, s = motor[0], joint[0]
    # By name only: the two observers use two nominal models of one robot by design (the
    # motor side carries the rotor inertia as armature); each kind keeps its fingerprint.
    if m.n_dof != s.n_dof or m.robot != s.robot:
        raise robot_mismatch(
            f"motor and joint signals must come from one robot; the motor runs are {m.robot!r} "
            f"({m.n_dof} joints), the joint runs {s.robot!r} ({s.n_dof} joints)",
            m.n_dof,
            s.n_dof,
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


class CombinedVelocityThreshold(VelocityBinsThreshold):
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
    min_bin_time : float
        Fit data [s] a bin needs for its own L and U, >= 0; a sparser bin
        takes them over the nearest bins that together hold this much (see
        :mod:`sensorless.thresholds.velocity_bins`). 0: no pooling.
    joints, transient
        As for every family, see :class:`~sensorless.thresholds.base.Threshold`.

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
        residuals); 0 marks a bin the fit runs never visited.
    pooled_bins_ : ndarray of bool, shape (n_bins, n_dof)
        Bins whose L and U are pooled (less than ``min_bin_time`` of fit
        data); ``pooled_bins_.sum(axis=0)`` counts them per joint.
    weights_ : ndarray of shape (2, n_dof)
        Relative weight of the r̂ rows (row 0) and the r̂_s rows (row 1) in
        the fit of each joint [-]; columns sum to 1.
    joint_fingerprint_ : str
        Fingerprint of the nominal model of the r̂_s runs (``fingerprint_`` is
        that of the r̂ runs; the motor side's model carries the rotor inertia).

    ``kind_`` is ``"motor+joint"``. :meth:`bounds` takes the residual from
    ``signals.kind``; streaming needs it: ``initial_state(..., kind="motor")``
    or ``kind="joint"``. A :class:`~sensorless.detection.Detector` or a
    monitor streams without it; give them :meth:`for_kind`, the plain
    :class:`VelocityThreshold` of one residual (which also saves as one):
    ``Detector(threshold.for_kind(signals.kind)).detect(signals)``.

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

    name = "velocity-combined"
    _per_bin = (
        "tau_fme_",
        "tau_sfe_",
        "lower_motor_",
        "upper_motor_",
        "lower_joint_",
        "upper_joint_",
        "counts_",
    )
    _state_type = CombinedVelocityState

    tau_fme_: FloatArray
    tau_sfe_: FloatArray
    lower_motor_: FloatArray
    upper_motor_: FloatArray
    lower_joint_: FloatArray
    upper_joint_: FloatArray
    weights_: FloatArray
    joint_fingerprint_: str = ""

    def __init__(
        self,
        bin_width: float = 0.06,
        margin: Any = 0.0,
        extrapolation_margin: float = 0.0,
        *,
        weighting: str = "equal",
        min_bin_time: float = MIN_BIN_TIME,
        joints: Any = None,
        transient: float = 0.0,
    ) -> None:
        super().__init__(
            bin_width,
            margin,
            extrapolation_margin,
            min_bin_time=min_bin_time,
            joints=joints,
            transient=transient,
        )
        self.weighting = weighting

    def _attribute_names(self) -> tuple[str, ...]:
        return ("gamma_", "bin_edges_", *self._per_bin, "weights_")

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
        super()._check_attributes()
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
        ModelMismatchError
            Runs of different robot models with the same joint count.
        """
        motor, joint = _as_pairs(signals)
        _check_pairs(motor, joint)
        runs = [run for pair in zip(motor, joint, strict=True) for run in pair]
        self._fit_checked(runs, COMBINED_KIND)
        self.joint_fingerprint_ = joint[0].fingerprint
        return self

    def _fit(self, runs: list[ObserverSignals], keep: list[BoolArray], margin: FloatArray) -> None:
        """Fit on checked runs ordered motor, joint, motor, joint, ... (one mask per run)."""
        weighting = self._check_weighting()
        # The two runs of a pair share t: the masks of the motor runs serve both.
        motor, joint, keep = runs[0::2], runs[1::2], keep[0::2]
        grid = self._grid(motor, keep, "fit pair")
        columns = np.stack(
            [
                stack(block, keep, name)
                for block in (motor, joint)
                for name in ("model_torque", "residual")
            ],
            axis=1,
        )
        weights = np.empty((2, motor[0].n_dof))

        def solve(j: int, basis: FloatArray) -> tuple[float, FloatArray]:
            gamma, fme, sfe, weights[:, j] = _combined_least_squares(
                columns[:, :, j], basis, weighting
            )
            return gamma, np.column_stack([fme, sfe])

        gamma, (tau_fme, tau_sfe) = grid.fit(motor[0].n_dof, 2, solve)
        self.gamma_ = gamma
        self.bin_edges_ = grid.edges
        self.tau_fme_ = tau_fme
        self.tau_sfe_ = tau_sfe
        least = self._fit_least(motor)
        self.lower_motor_, self.upper_motor_, self.counts_ = grid.bounds(
            motor, gamma, tau_fme, margin, least
        )
        self.lower_joint_, self.upper_joint_, _ = grid.bounds(joint, gamma, -tau_sfe, margin, least)
        self.weights_ = weights

    # ----------------------------------------------------------------- one residual

    def _table(self, kind: str | None) -> BinTable:
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
        return BinTable(self.bin_edges_, self.gamma_, tau, lower, upper, self.counts_)

    def model_fingerprint(self, kind: str) -> str:
        """Fingerprint of the nominal model of the ``kind`` runs: "motor" or "joint"."""
        return self.joint_fingerprint_ if kind == "joint" else self.fingerprint_

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
            min_bin_time=self.min_bin_time,
            joints=self.joints,
            transient=self.transient,
        )
        single.robot_ = self.robot_
        single.fingerprint_ = self.model_fingerprint(kind)
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

    def _check_kind(self, kind: str | None) -> None:
        self._table(kind)

    def _initial_state_checked(
        self, inputs: ThresholdInputs, dt: float, kind: str | None = None
    ) -> CombinedVelocityState:
        """State before the first sample of r̂ (``kind="motor"``) or r̂_s (``"joint"``)."""
        zi = initial_friction(self._table(kind), inputs.velocity)
        return CombinedVelocityState(dt, zi, str(kind))

    def _run(self, state: ThresholdState, inputs: ThresholdInputs) -> StreamBounds:
        # step and process check the type; bounds and the detector make the state
        kind = cast(CombinedVelocityState, state).kind
        lower, upper, zf = self._table_bounds(self._table(kind), state, inputs)
        return lower, upper, CombinedVelocityState(state.dt, zf, kind)
