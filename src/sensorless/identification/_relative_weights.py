"""Johnson's relative weights, their bootstrap test and the elimination of Table 2.7.

Relative weights (Johnson 2000) partition the R² of the regression with an
intercept among correlated predictors; :func:`relative_weight_significance`
tests them against a random predictor (Tonidandel & LeBreton 2009) and
:func:`eliminate` drops parameters with small |t| and small weight
(thesis §2.4.3). All work on data or on a :class:`RegressionAccumulator`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from .._validation import FloatArray, check_int
from ..exceptions import InputValueError
from ._accumulator import (
    RANK_TOLERANCE,
    RegressionAccumulator,
    RegressionResult,
    as_matrix,
    default_names,
)

__all__ = [
    "EliminationReport",
    "RelativeWeightSignificance",
    "eliminate",
    "relative_weight_significance",
    "relative_weights",
]


def _accumulate(
    data: RegressionAccumulator | ArrayLike, y: ArrayLike | None
) -> RegressionAccumulator:
    if isinstance(data, RegressionAccumulator):
        if y is not None:
            raise InputValueError("give y only with an X matrix, not with an accumulator")
        return data
    if y is None:
        raise InputValueError("y is required when the first argument is an X matrix")
    x_arr, y_arr = as_matrix(data, y, None)
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
    if eigval.min() <= RANK_TOLERANCE * eigval.max() * rxx.shape[0]:
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
    x_arr, y_arr = as_matrix(X, y, None)
    labels = default_names(x_arr.shape[1], names)
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
    labels = default_names(acc.n_parameters, names)
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
