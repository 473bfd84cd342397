"""Pooled least squares: sufficient statistics, estimates and their statistics.

:class:`RegressionAccumulator` keeps XᵀX, Xᵀy, yᵀy, Σx, Σy and n of the
segments added so far; :class:`RegressionResult` holds the estimates,
standard errors, confidence intervals and R² computed from them. The method
is described in :mod:`sensorless.identification.regression`.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
import scipy.linalg
import scipy.stats
from numpy.typing import ArrayLike

from .._validation import FloatArray, check_finite, check_int
from ..exceptions import DimensionError, InputValueError

__all__ = ["RegressionAccumulator", "RegressionResult", "least_squares"]

# Scaled eigenvalue ratio below which XᵀX is treated as singular: a condition
# number of the column-scaled X above ~1e6.5 leaves fewer than ~3 digits in a
# normal-equation solution.
RANK_TOLERANCE = 1e-13
_ZERO_COLUMN = 1e-24


def as_matrix(
    X: ArrayLike, y: ArrayLike, n_parameters: int | None
) -> tuple[FloatArray, FloatArray]:
    """X of shape (n_samples, n_parameters) and y of shape (n_samples,), finite floats."""
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


def default_names(p: int, names: Sequence[str] | None) -> list[str]:
    """``names`` as a list of ``p`` names; ``x1 ... xp`` when not given."""
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
        x_arr, y_arr = as_matrix(X, y, self.n_parameters)
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
        small = eigval <= RANK_TOLERANCE * eigval.max() * p
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
        labels = default_names(p, names)
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
    x_arr, y_arr = as_matrix(X, y, None)
    return RegressionAccumulator(x_arr.shape[1]).add(x_arr, y_arr).result(names)
