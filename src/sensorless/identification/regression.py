"""Linear regression for parameter identification, pooled over segments.

The identification problem of thesis §2.4.3, eq. (2.12)–(2.13), stacks the
regressor Y(q, q̇, q̈) of every sample into a tall matrix X and solves
X θ = τ. Thirty minutes of data do not fit in memory, so the thesis splits
them into one-minute segments and combines the per-segment regressions
("meta-analysis"). Here that is exact: :class:`RegressionAccumulator` keeps
the sufficient statistics XᵀX, Xᵀy, yᵀy, Σx, Σy and n, whose sums over
segments equal those of the whole data, so estimates, standard errors, R² and
Johnson's relative weights of pooled data equal those of one regression.

The regression has no intercept (eq. 2.12 has none). :attr:`RegressionResult.r_squared`
is 1 − RSS/Σ(y − ȳ)². Relative weights (Johnson 2000) work on correlations,
so they partition the R² of the regression *with* an intercept; the two
agree when the model explains the mean of y, as a dynamic model does.

Friction columns (:func:`identify_base_parameters`) follow the sign
convention of :mod:`sensorless.friction`: the measured torque is
τ = Y_b θ + τ_f with τ_f = c₊ for q̇ > 0, c₋ (signed, negative) for q̇ < 0,
plus f_v q̇.

This module is the public home of the regression names; the pooled least
squares live in ``_accumulator`` and the relative weights and the
elimination in ``_relative_weights``.
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from typing import TYPE_CHECKING

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_joint_array
from ..exceptions import DimensionError, InputValueError
from ._accumulator import RegressionAccumulator, RegressionResult, least_squares
from ._relative_weights import (
    EliminationReport,
    RelativeWeightSignificance,
    eliminate,
    relative_weight_significance,
    relative_weights,
)

if TYPE_CHECKING:
    from ..robots.base_parameters import BaseParameters
    from ..robots.model import RobotModel

__all__ = [
    "EliminationReport",
    "RegressionAccumulator",
    "RegressionResult",
    "RelativeWeightSignificance",
    "eliminate",
    "identify_base_parameters",
    "least_squares",
    "relative_weight_significance",
    "relative_weights",
]

_FRICTION_OPTIONS = ("coulomb_viscous", None)
#: Samples per call of the base regressor when a segment is filled (a few MB each).
_REGRESSOR_BLOCK = 4096


def _check_segment(segment: int) -> int:
    """Samples per segment of a pooled regression, a positive integer."""
    if isinstance(segment, bool) or not isinstance(segment, (int, np.integer)) or segment < 1:
        raise InputValueError(f"segment must be a positive integer of samples; got {segment!r}")
    return int(segment)


def _segments(n_samples: int, segment: int) -> Iterator[slice]:
    """Consecutive slices of ``segment`` samples (the last may be shorter)."""
    for start in range(0, n_samples, segment):
        yield slice(start, start + segment)


def _fill_friction_columns(cols: FloatArray, qd: FloatArray) -> None:
    """Write the c₊, c₋, f_v columns of ``qd`` into ``cols`` of shape (m, n_dof, 3 n_dof)."""
    n_dof = qd.shape[1]
    cols.fill(0.0)
    joints = np.arange(n_dof)
    cols[:, joints, joints] = qd > 0.0
    cols[:, joints, n_dof + joints] = qd < 0.0
    cols[:, joints, 2 * n_dof + joints] = qd


def identify_base_parameters(
    robot: RobotModel,
    q: ArrayLike,
    qd: ArrayLike,
    qdd: ArrayLike,
    tau: ArrayLike,
    *,
    zero: Sequence[str] = (),
    friction: str | None = "coulomb_viscous",
    segment: int = 60_000,
) -> tuple[BaseParameters, RegressionResult]:
    """Identify base inertial (and friction) parameters, eq. (2.12)–(2.13).

    Parameters
    ----------
    robot : RobotModel
        Kinematics used for the base regressor.
    q, qd, qdd : array-like of shape (n_samples, n_dof)
        Joint positions [rad], velocities [rad/s], accelerations [rad/s²].
    tau : array-like of shape (n_samples, n_dof)
        Measured joint torques [N m].
    zero : sequence of str
        Standard parameters known to be zero (see ``base_parameters``).
    friction : {"coulomb_viscous", None}
        Add per-joint columns for c₊ (q̇ > 0), c₋ (q̇ < 0) [N m] and f_v
        [N m s/rad], named ``c_pos<j>``, ``c_neg<j>``, ``fv<j>``.
    segment : int
        Samples per segment pooled through :class:`RegressionAccumulator`.

    Returns
    -------
    base : BaseParameters
    result : RegressionResult
        Base parameters first, then friction parameters.
    """
    from ..robots.base_parameters import base_parameters

    if friction not in _FRICTION_OPTIONS:
        raise InputValueError(f"friction must be one of {_FRICTION_OPTIONS}; got {friction!r}")
    segment = _check_segment(segment)
    n_dof = robot.n_dof
    arrays = [as_joint_array(a, n_dof, nm)[0] for a, nm in ((q, "q"), (qd, "qd"), (qdd, "qdd"))]
    tau_arr = as_joint_array(tau, n_dof, "tau")[0]
    lengths = {a.shape[0] for a in [*arrays, tau_arr]}
    if len(lengths) != 1:
        raise DimensionError(
            f"q, qd, qdd and tau must have the same number of samples; got {sorted(lengths)}"
        )
    base = base_parameters(robot, zero=zero)
    names = list(base.names)
    if friction is not None:
        for kind in ("c_pos", "c_neg", "fv"):
            names += [f"{kind}{j + 1}" for j in range(n_dof)]
    acc = RegressionAccumulator(len(names))
    n_base = len(base.names)
    # One design buffer for every segment, filled in place, the regressor a
    # block of samples at a time: the full regressor of a whole segment (all
    # standard columns, then the base ones copied out, then the friction
    # columns joined) was several hundred MB. The accumulator still sees one
    # segment at a time, so the sums are those of the segment as a whole.
    design = np.empty((min(segment, tau_arr.shape[0]), n_dof, len(names)))
    for part in _segments(tau_arr.shape[0], segment):
        q_s, qd_s, qdd_s = (a[part] for a in arrays)
        rows = design[: q_s.shape[0]]
        for block in _segments(q_s.shape[0], _REGRESSOR_BLOCK):
            rows[block, :, :n_base] = base.regressor(q_s[block], qd_s[block], qdd_s[block])
        if friction is not None:
            _fill_friction_columns(rows[:, :, n_base:], qd_s)
        acc.add(rows.reshape(-1, len(names)), tau_arr[part].reshape(-1))
    return base, acc.result(names)
