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
"""

from __future__ import annotations

from collections.abc import Iterator, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np
import pandas as pd
import scipy.linalg
import scipy.stats
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_joint_array, check_finite, check_int
from ..exceptions import DimensionError, InputValueError

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

# Scaled eigenvalue ratio below which XᵀX is treated as singular: a condition
# number of the column-scaled X above ~1e6.5 leaves fewer than ~3 digits in a
# normal-equation solution.
_RANK_TOLERANCE = 1e-13
_ZERO_COLUMN = 1e-24
_FRICTION_OPTIONS = ("coulomb_viscous", None)


def _as_matrix(
    X: ArrayLike, y: ArrayLike, n_parameters: int | None
) -> tuple[FloatArray, FloatArray]:
    x_arr = np.asarray(X, dtype=np.float64)
    y_arr = np.asarray(y, dtype=np.float64)
    if x_arr.ndim != 2:
        raise DimensionError(f"X must have shape (n_samples, n_parameters); got {x_arr.shape}")
    if n_parameters is not None and x_arr.shape[1] != n_parameters:
        raise DimensionError(
            f"X must have {n_parameters} columns (n_parameters); got shape {x_arr.shape}"
        )
    if y_arr.shape != (x_arr.shape[0],):
        raise DimensionError(
            f"y must have shape ({x_arr.shape[0]},) to match X {x_arr.shape}; got {y_arr.shape}"
        )
    check_finite(x_arr, "X")
    check_finite(y_arr, "y")
    return x_arr, y_arr


def _default_names(p: int, names: Sequence[str] | None) -> list[str]:
    if names is None:
        return [f"x{k + 1}" for k in range(p)]
    names = list(names)
    if len(names) != p:
        raise DimensionError(f"expected {p} names (one per column); got {len(names)}")
    return names


class RegressionAccumulator:
    """Sufficient statistics of a linear regression, accumulated segment by segment.

    Memory is O(p²) whatever the number of samples; ``add`` over segments
    gives the same statistics as one ``add`` of the stacked data.

    Parameters
    ----------
    n_parameters : int
        Number of columns p of the regressor X.

    Examples
    --------
    >>> import numpy as np
    >>> acc = RegressionAccumulator(2)
    >>> X = np.array([[1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0, 2.0]])
    >>> acc.add(X[:2], np.array([1.0, 2.0])).add(X[2:], np.array([3.0, 5.0])).n_samples
    4
    >>> np.round(acc.result().estimates, 6)
    array([1., 2.])
    """

    def __init__(self, n_parameters: int) -> None:
        p = check_int(n_parameters, "n_parameters", 1, "RegressionAccumulator")
        self.n_parameters = p
        self.xtx: FloatArray = np.zeros((p, p))
        self.xty: FloatArray = np.zeros(p)
        self.yty = 0.0
        self.sum_x: FloatArray = np.zeros(p)
        self.sum_y = 0.0
        self.n_samples = 0

    def add(self, X: ArrayLike, y: ArrayLike) -> RegressionAccumulator:
        """Add one segment of rows.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_parameters)
            Regressor rows [units of the model].
        y : array-like of shape (n_samples,)
            Responses, e.g. joint torques [N m].

        Returns
        -------
        self
        """
        x_arr, y_arr = _as_matrix(X, y, self.n_parameters)
        self.xtx += x_arr.T @ x_arr
        self.xty += x_arr.T @ y_arr
        self.yty += float(y_arr @ y_arr)
        self.sum_x += x_arr.sum(axis=0)
        self.sum_y += float(y_arr.sum())
        self.n_samples += x_arr.shape[0]
        return self

    def subset(self, columns: ArrayLike) -> RegressionAccumulator:
        """Statistics of the regression on the given columns only (no data needed)."""
        idx = np.asarray(columns, dtype=np.intp)
        out = RegressionAccumulator(idx.size)
        out.xtx = self.xtx[np.ix_(idx, idx)].copy()
        out.xty = self.xty[idx].copy()
        out.yty = self.yty
        out.sum_x = self.sum_x[idx].copy()
        out.sum_y = self.sum_y
        out.n_samples = self.n_samples
        return out

    def _check_solvable(self, names: list[str]) -> FloatArray:
        """Return the column scales sqrt(diag XᵀX) after checking the rank."""
        p = self.n_parameters
        if self.n_samples <= p:
            raise InputValueError(
                f"need more samples than parameters (n > p = {p}) for standard errors; "
                f"got n = {self.n_samples}"
            )
        diag = np.diag(self.xtx).copy()
        if diag.max() <= _ZERO_COLUMN:
            raise InputValueError(
                "no excitation: the regressor X is (numerically) zero, as for a robot "
                "standing still at a pose where no modelled term acts; record moving data"
            )
        zero = diag <= _ZERO_COLUMN * diag.max()
        if zero.any():
            bad = [names[k] for k in np.flatnonzero(zero)]
            raise InputValueError(
                f"rank-deficient data: columns {bad} are zero (not excited by the data)"
            )
        scale = np.sqrt(diag)
        scaled = self.xtx / np.outer(scale, scale)
        eigval, eigvec = np.linalg.eigh(scaled)
        small = eigval <= _RANK_TOLERANCE * eigval.max() * p
        if small.any():
            relations = []
            for k in np.flatnonzero(small):
                v = eigvec[:, k]
                members = np.flatnonzero(np.abs(v) > 0.1 * np.abs(v).max())
                relations.append([names[m] for m in members])
            raise InputValueError(
                f"rank-deficient data: rank {int(np.count_nonzero(~small))} < {p} parameters; "
                f"dependent column groups: {relations}; remove or regroup them"
            )
        return scale

    def result(self, names: Sequence[str] | None = None, level: float = 0.95) -> RegressionResult:
        """Least-squares fit from the accumulated statistics.

        Parameters
        ----------
        names : sequence of str, optional
            Parameter names; ``x1, x2, ...`` by default.
        level : float
            Confidence level of the intervals (0 < level < 1).

        Returns
        -------
        RegressionResult
        """
        if not 0.0 < level < 1.0:
            raise InputValueError(f"level must lie in (0, 1); got {level!r}")
        p, n = self.n_parameters, self.n_samples
        labels = _default_names(p, names)
        scale = self._check_solvable(labels)
        scaled = self.xtx / np.outer(scale, scale)
        factor = scipy.linalg.cho_factor(scaled)
        estimates = scipy.linalg.cho_solve(factor, self.xty / scale) / scale
        inverse = scipy.linalg.cho_solve(factor, np.eye(p)) / np.outer(scale, scale)
        rss = max(self.yty - float(estimates @ self.xty), 0.0)
        dof = n - p
        sigma2 = rss / dof
        std_errors = np.sqrt(np.clip(np.diag(inverse), 0.0, None) * sigma2)
        with np.errstate(divide="ignore", invalid="ignore"):
            t_values = np.where(std_errors > 0, estimates / std_errors, np.inf * np.sign(estimates))
        quantile = float(scipy.stats.t.ppf(0.5 + level / 2.0, dof))
        tss = self.yty - self.sum_y**2 / n
        r_squared = 1.0 - rss / tss if tss > 0 else float("nan")
        eig = np.linalg.eigvalsh(self.xtx)
        condition = float(np.sqrt(eig.max() / eig.min())) if eig.min() > 0 else float("inf")
        return RegressionResult(
            names=labels,
            estimates=estimates,
            std_errors=std_errors,
            t_values=t_values,
            ci_lower=estimates - quantile * std_errors,
            ci_upper=estimates + quantile * std_errors,
            level=level,
            r_squared=float(r_squared),
            rss=rss,
            residual_std=float(np.sqrt(sigma2)),
            condition_number=condition,
            n_samples=n,
            covariance=inverse * sigma2,
        )


@dataclass(frozen=True)
class RegressionResult:
    """Least-squares estimates and their statistics.

    Attributes
    ----------
    names : list of str
        Parameter names, one per column of X.
    estimates : ndarray of shape (p,)
        θ̂ = (XᵀX)⁻¹Xᵀy [units of the parameters].
    std_errors : ndarray of shape (p,)
        sqrt of diag σ̂²(XᵀX)⁻¹ with σ̂² = RSS/(n − p).
    t_values : ndarray of shape (p,)
        estimates / std_errors.
    ci_lower, ci_upper : ndarray of shape (p,)
        Confidence interval at ``level`` (Student t with n − p dof).
    level : float
        Confidence level of the interval [-], in (0, 1).
    r_squared : float
        1 − RSS/Σ(y − ȳ)².
    rss : float
        Residual sum of squares [units of y²].
    residual_std : float
        σ̂ [units of y].
    condition_number : float
        Condition number of X, sqrt(λ_max/λ_min) of XᵀX.
    n_samples : int
        Rows of X pooled into the fit.
    covariance : ndarray of shape (p, p)
        σ̂²(XᵀX)⁻¹.
    """

    names: list[str]
    estimates: FloatArray
    std_errors: FloatArray
    t_values: FloatArray
    ci_lower: FloatArray
    ci_upper: FloatArray
    level: float
    r_squared: float
    rss: float
    residual_std: float
    condition_number: float
    n_samples: int
    covariance: FloatArray = field(repr=False)

    def to_pandas(self) -> pd.DataFrame:
        """One row per parameter: estimate, std_error, t, ci_lower, ci_upper."""
        return pd.DataFrame(
            {
                "estimate": self.estimates,
                "std_error": self.std_errors,
                "t": self.t_values,
                "ci_lower": self.ci_lower,
                "ci_upper": self.ci_upper,
            },
            index=pd.Index(self.names, name="parameter"),
        )


def least_squares(
    X: ArrayLike, y: ArrayLike, names: Sequence[str] | None = None
) -> RegressionResult:
    """Ordinary least squares X θ ≈ y without intercept, with statistics.

    Parameters
    ----------
    X : array-like of shape (n_samples, n_parameters)
        Regressor.
    y : array-like of shape (n_samples,)
        Response.
    names : sequence of str, optional
        Parameter names.
    """
    x_arr, y_arr = _as_matrix(X, y, None)
    return RegressionAccumulator(x_arr.shape[1]).add(x_arr, y_arr).result(names)


def _check_segment(segment: int) -> int:
    """Samples per segment of a pooled regression, a positive integer."""
    if isinstance(segment, bool) or not isinstance(segment, (int, np.integer)) or segment < 1:
        raise InputValueError(f"segment must be a positive integer of samples; got {segment!r}")
    return int(segment)


def _segments(n_samples: int, segment: int) -> Iterator[slice]:
    """Consecutive slices of ``segment`` samples (the last may be shorter)."""
    for start in range(0, n_samples, segment):
        yield slice(start, start + segment)


def _friction_columns(qd: FloatArray) -> FloatArray:
    m, n_dof = qd.shape
    cols = np.zeros((m, n_dof, 3 * n_dof))
    joints = np.arange(n_dof)
    cols[:, joints, joints] = qd > 0.0
    cols[:, joints, n_dof + joints] = qd < 0.0
    cols[:, joints, 2 * n_dof + joints] = qd
    return cols


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
    for part in _segments(tau_arr.shape[0], segment):
        q_s, qd_s, qdd_s = (a[part] for a in arrays)
        blocks = base.regressor(q_s, qd_s, qdd_s)
        if friction is not None:
            blocks = np.concatenate([blocks, _friction_columns(qd_s)], axis=2)
        acc.add(blocks.reshape(-1, len(names)), tau_arr[part].reshape(-1))
    return base, acc.result(names)


def _accumulate(
    data: RegressionAccumulator | ArrayLike, y: ArrayLike | None
) -> RegressionAccumulator:
    if isinstance(data, RegressionAccumulator):
        if y is not None:
            raise InputValueError("give y only with an X matrix, not with an accumulator")
        return data
    if y is None:
        raise InputValueError("y is required when the first argument is an X matrix")
    x_arr, y_arr = _as_matrix(data, y, None)
    return RegressionAccumulator(x_arr.shape[1]).add(x_arr, y_arr)


def relative_weights(
    data: RegressionAccumulator | ArrayLike, y: ArrayLike | None = None
) -> tuple[FloatArray, FloatArray]:
    """Johnson's (2000) relative weights from correlations.

    With the correlation matrix Rxx = VΛVᵀ: λ* = VΛ^{1/2}Vᵀ, β* = λ*⁻¹Rxy and
    ε = (λ*∘λ*)(β*∘β*), which sums to R² of the regression with intercept.

    Parameters
    ----------
    data : RegressionAccumulator or array-like of shape (n_samples, p)
        Accumulated statistics, or X (then ``y`` is required).
    y : array-like of shape (n_samples,), optional

    Returns
    -------
    raw : ndarray of shape (p,)
        ε_j, summing to R².
    rescaled : ndarray of shape (p,)
        ε_j / R² · 100 [%].
    """
    acc = _accumulate(data, y)
    n = acc.n_samples
    if n < 2:
        raise InputValueError(f"relative weights need at least 2 samples; got {n}")
    mean_x = acc.sum_x / n
    sxx = acc.xtx - n * np.outer(mean_x, mean_x)
    sxy = acc.xty - acc.sum_y * mean_x
    syy = acc.yty - acc.sum_y**2 / n
    var_x = np.diag(sxx)
    constant = var_x <= 1e-12 * max(float(np.diag(acc.xtx).max()), 1e-300)
    if constant.any() or syy <= 0:
        raise InputValueError(
            "relative weights need non-constant predictors and response; constant "
            f"columns: {np.flatnonzero(constant).tolist()}, var(y) > 0: {syy > 0}"
        )
    sd_x = np.sqrt(var_x)
    rxx = sxx / np.outer(sd_x, sd_x)
    rxy = sxy / (sd_x * np.sqrt(syy))
    eigval, eigvec = np.linalg.eigh(rxx)
    if eigval.min() <= _RANK_TOLERANCE * eigval.max() * rxx.shape[0]:
        raise InputValueError("relative weights need linearly independent predictors")
    lam = (eigvec * np.sqrt(eigval)) @ eigvec.T
    beta = (eigvec / np.sqrt(eigval)) @ (eigvec.T @ rxy)
    raw = (lam**2) @ (beta**2)
    return raw, raw / raw.sum() * 100.0


@dataclass(frozen=True)
class RelativeWeightSignificance:
    """Bootstrap test of relative weights against a random predictor.

    Attributes
    ----------
    names : list of str
        Predictor names, one per column of X (the noise column excluded).
    raw : ndarray of shape (p,)
        Relative weights of the original predictors [-] (they sum to R²).
    lower, upper : ndarray of shape (p,)
        Percentile confidence interval of ε_j − ε_noise.
    significant : ndarray of bool, shape (p,)
        True when the interval excludes 0 (lower > 0).
    alpha : float
        1 − confidence level of the interval [-].
    """

    names: list[str]
    raw: FloatArray
    lower: FloatArray
    upper: FloatArray
    significant: np.ndarray
    alpha: float

    def to_pandas(self) -> pd.DataFrame:
        """One row per predictor."""
        return pd.DataFrame(
            {
                "relative_weight": self.raw,
                "ci_lower": self.lower,
                "ci_upper": self.upper,
                "significant": self.significant,
            },
            index=pd.Index(self.names, name="parameter"),
        )


def relative_weight_significance(
    X: ArrayLike,
    y: ArrayLike,
    names: Sequence[str] | None = None,
    *,
    n_boot: int = 200,
    seed: int = 0,
    alpha: float = 0.05,
) -> RelativeWeightSignificance:
    """Significance of relative weights (Tonidandel & LeBreton 2009).

    A standard-normal noise predictor is appended; rows are bootstrapped and
    the percentile interval of ε_j − ε_noise decides significance.

    Parameters
    ----------
    X : array-like of shape (n_samples, p)
    y : array-like of shape (n_samples,)
    names : sequence of str, optional
    n_boot : int
        Bootstrap resamples.
    seed : int
        Seed of the noise predictor and of the resampling.
    alpha : float
        1 − confidence level of the interval.
    """
    x_arr, y_arr = _as_matrix(X, y, None)
    labels = _default_names(x_arr.shape[1], names)
    n_boot = check_int(n_boot, "n_boot", 10)
    if not 0.0 < alpha < 1.0:
        raise InputValueError(f"alpha must lie in (0, 1); got {alpha!r}")
    rng = np.random.default_rng(seed)
    augmented = np.column_stack([x_arr, rng.standard_normal(x_arr.shape[0])])
    n = x_arr.shape[0]
    diffs = np.empty((n_boot, x_arr.shape[1]))
    for b in range(n_boot):
        rows = rng.integers(0, n, n)
        raw_b = relative_weights(augmented[rows], y_arr[rows])[0]
        diffs[b] = raw_b[:-1] - raw_b[-1]
    lower, upper = np.percentile(diffs, [50 * alpha, 100 - 50 * alpha], axis=0)
    return RelativeWeightSignificance(
        names=labels,
        raw=relative_weights(x_arr, y_arr)[0],
        lower=lower,
        upper=upper,
        significant=lower > 0.0,
        alpha=alpha,
    )


@dataclass(frozen=True)
class EliminationReport:
    """Iterations of the t-statistic / relative-weight elimination (Table 2.7).

    Attributes
    ----------
    names : list of str
        All parameter names, one per column of X.
    iterations : list of DataFrame
        One per fit, indexed by all names, columns ``estimate``, ``t``,
        ``relative_weight`` [%] and ``kept``; parameters dropped earlier show 0.
    final_estimates : ndarray of shape (p,)
        Estimates of the last fit, zero for dropped parameters.
    kept : list of str
        Names of the parameters left after the elimination.
    converged : bool
        False when ``max_iterations`` ended while parameters were still dropped.
    result : RegressionResult
        Last fit (kept parameters only).
    """

    names: list[str]
    iterations: list[pd.DataFrame]
    final_estimates: FloatArray
    kept: list[str]
    converged: bool
    result: RegressionResult

    def to_pandas(self) -> pd.DataFrame:
        """Table 2.7 layout: (Iteration k, field) columns, then Final estimation."""
        frames = {f"Iteration {k + 1}": df for k, df in enumerate(self.iterations)}
        table = pd.concat(frames, axis=1)
        table[("Final", "estimate")] = self.final_estimates
        return table


def eliminate(
    X: RegressionAccumulator | ArrayLike,
    y: ArrayLike | None,
    names: Sequence[str] | None = None,
    *,
    t_threshold: float = 145.0,
    weight_threshold: float = 0.5,
    max_iterations: int = 10,
) -> EliminationReport:
    """Drop parameters with small |t| *and* small relative weight, refit, repeat.

    The procedure of thesis §2.4.3 / Table 2.7: a parameter is dropped when
    |t| < ``t_threshold`` and its rescaled relative weight < ``weight_threshold``
    [%]; the regression is refitted on the rest until nothing is dropped.

    Parameters
    ----------
    X : RegressionAccumulator or array-like of shape (n_samples, p)
        Regressor, or pooled statistics (then ``y`` is None).
    y : array-like of shape (n_samples,) or None
    names : sequence of str, optional
    t_threshold : float
        Depends on the amount of data (145 for 30 min at 1 kHz in the thesis).
    weight_threshold : float
        Rescaled relative weight [%].
    max_iterations : int
    """
    acc = _accumulate(X, y)
    labels = _default_names(acc.n_parameters, names)
    max_iterations = check_int(max_iterations, "max_iterations", 1)
    active = np.arange(acc.n_parameters)
    iterations: list[pd.DataFrame] = []
    converged = False
    final = np.zeros(acc.n_parameters)
    kept = active
    result = acc.result(labels)
    for iteration in range(max_iterations):
        sub = acc.subset(active)
        if iteration > 0:
            result = sub.result([labels[k] for k in active])
        rescaled = relative_weights(sub)[1]
        drop = (np.abs(result.t_values) < t_threshold) & (rescaled < weight_threshold)
        table = pd.DataFrame(
            {"estimate": 0.0, "t": 0.0, "relative_weight": 0.0, "kept": False},
            index=pd.Index(labels, name="parameter"),
        )
        table.iloc[active, 0] = result.estimates
        table.iloc[active, 1] = result.t_values
        table.iloc[active, 2] = rescaled
        table.iloc[active, 3] = ~drop
        iterations.append(table)
        final = np.zeros(acc.n_parameters)
        final[active[~drop]] = result.estimates[~drop]
        kept = active[~drop]
        if not drop.any():
            converged = True
            break
        if drop.all():
            raise InputValueError(
                f"every remaining parameter {[labels[k] for k in active]} falls below "
                f"t_threshold={t_threshold} and weight_threshold={weight_threshold}; "
                "lower the thresholds"
            )
        active = active[~drop]
    return EliminationReport(
        names=labels,
        iterations=iterations,
        final_estimates=final,
        kept=[labels[k] for k in kept],
        converged=converged,
        result=result,
    )
