"""Identification from sampled M(q) and g(q), thesis §2.4.3 eq. (2.14)–(2.15).

Controllers such as KUKA's FRI or Franka's libfranka expose the joint-space
inertia matrix M(q) [kg m²] and the gravity torque g(q) [N m] that their own
model computes. Both are linear in the base parameters θ:

    g(q) = Y_g(q) θ                          (2.14a)
    M_i(q) = Y_{M_i}(q) θ,  1 ≤ i ≤ n        (2.15)

with M_i the i-th column of M. Both regressors come from the base regressor
Y_b(q, q̇, q̈) of :mod:`sensorless.robots.base_parameters`: with q̇ = 0 the
Coriolis terms vanish, so Y_g = Y_b(q, 0, 0) and Y_{M_i} = Y_b(q, 0, e_i) − Y_g.

The data are functions of q alone, so no velocities, accelerations or torque
measurements are needed, and there is no measurement noise: any set of
configurations that excites every parameter identifies θ exactly (up to
round-off). Every base parameter acts on M or g (the Coriolis terms are built
from M), so the two together identify all of them.

Exact data and the t-statistic
------------------------------
:class:`~sensorless.identification.regression.RegressionAccumulator` gets the
residual sum of squares as yᵀy − θ̂ᵀXᵀy. For an exact fit that difference is
pure cancellation: it is clipped to 0 (σ̂ = 0, every t = ±inf) or leaves a
spurious 1e-11. :func:`identify_from_matrices` therefore computes the RSS from
the residuals y − X θ̂ in a second pass over the segments. σ̂ is then the
round-off level of the data: parameters that act have |t| of 1e10 and more
on double-precision data, while a parameter the controller's model sets to
zero has an estimate of round-off size and |t| of order 1 to 10. That is the
reading of the t-statistic column of thesis Table 2.7 ("small t-statistic
values indicate that the corresponding minimal inertial parameters were not
considered"). t is ±inf only when the residual is exactly zero. The
confidence intervals are then as narrow as the round-off.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Iterable, Sequence

import numpy as np
import pandas as pd
import scipy.linalg
import scipy.stats
from numpy.typing import ArrayLike

from .._validation import (
    FloatArray,
    as_float_array,
    as_joint_array,
    check_finite,
    check_scalar,
    check_type,
)
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..robots.base_parameters import BaseParameters, base_parameters
from ..robots.model import RobotModel
from .regression import RegressionAccumulator, RegressionResult, _check_segment, _segments

__all__ = ["contributing_terms", "identify_from_matrices", "matrix_regressors"]

_TERMS = ("M", "g")
#: Samples per segment: a Panda sample gives 7 + 28 rows of 48 columns (13 kB).
_DEFAULT_SEGMENT = 1000


def _regressors(base: BaseParameters, q: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Y_M of shape (m, n, n, count) and Y_g of shape (m, n, count) for q of shape (m, n)."""
    m, n = q.shape
    # One regressor call for the states (q, 0, 0), (q, 0, e_1), ..., (q, 0, e_n).
    unit = np.vstack([np.zeros((1, n)), np.eye(n)])
    states = np.repeat(q, n + 1, axis=0)
    stacked = base.regressor(states, np.zeros_like(states), np.tile(unit, (m, 1)))
    stacked = stacked.reshape(m, n + 1, n, base.count)
    y_g = stacked[:, 0]
    y_m = stacked[:, 1:] - y_g[:, None]
    return y_m, y_g


def matrix_regressors(base: BaseParameters, q: ArrayLike) -> tuple[FloatArray, FloatArray]:
    """Regressors of the inertia matrix and of the gravity torque, eq. (2.14a), (2.15).

    Computed from the base regressor: Y_g(q) = Y_b(q, 0, 0) and
    Y_{M_i}(q) = Y_b(q, 0, e_i) − Y_g(q), with e_i the i-th unit acceleration.

    Parameters
    ----------
    base : BaseParameters
        Base parameters of the robot (:func:`sensorless.base_parameters`).
    q : array-like of shape (n_dof,) or (n_samples, n_dof)
        Joint positions [rad].

    Returns
    -------
    y_m : ndarray of shape (n_samples, n_dof, n_dof, count)
        ``y_m[k, i]`` is Y_{M_i}(q_k), of shape (n_dof [row], count), so that
        ``y_m[k, i] @ θ`` is column i of M(q_k) [kg m²]. Without the sample
        axis when ``q`` has shape (n_dof,).
    y_g : ndarray of shape (n_samples, n_dof, count)
        Y_g(q_k), so that ``y_g[k] @ θ`` is g(q_k) [N m].

    Examples
    --------
    >>> import numpy as np
    >>> import sensorless as sl
    >>> robot = sl.robots.load("planar2")
    >>> base = sl.base_parameters(robot)
    >>> y_m, y_g = matrix_regressors(base, [0.3, -0.5])
    >>> bool(np.allclose(np.einsum("irc,c->ri", y_m, base.values), robot.mass_matrix([0.3, -0.5])))
    True
    """
    base = check_type(base, BaseParameters, "base", " (from sensorless.base_parameters)")
    q_arr, single = as_joint_array(q, base.robot.n_dof, "q")
    y_m, y_g = _regressors(base, q_arr)
    if single:
        return y_m[0], y_g[0]
    return y_m, y_g


def _check_use(use: str | Iterable[str]) -> tuple[str, ...]:
    terms = (use,) if isinstance(use, str) else tuple(use)
    unknown = [term for term in terms if term not in _TERMS]
    if unknown or not terms or len(set(terms)) != len(terms):
        raise InputValueError(
            f"use must be a non-empty selection without repeats of {list(_TERMS)}; got {terms!r}"
        )
    return terms


def _check_mass_matrix(
    mass_matrix: ArrayLike, n_samples: int, n_dof: int, tolerance: float
) -> FloatArray:
    arr = as_float_array(mass_matrix, "mass_matrix", f"(n_samples, {n_dof}, {n_dof})")
    if arr.ndim == 2:
        arr = arr[None]
    if arr.shape != (n_samples, n_dof, n_dof):
        raise DimensionError(
            f"mass_matrix must have shape (n_samples, n_dof, n_dof) = ({n_samples}, {n_dof}, "
            f"{n_dof}) to match q; got shape {np.shape(mass_matrix)}"
        )
    check_finite(arr, "mass_matrix")
    asymmetry = np.abs(arr - np.swapaxes(arr, 1, 2))
    allowed = tolerance * max(float(np.abs(arr).max()), np.finfo(float).tiny)
    if asymmetry.max() > allowed:
        k, r, c = (int(i) for i in np.unravel_index(np.argmax(asymmetry), asymmetry.shape))
        raise InputValueError(
            f"mass_matrix must be symmetric within {tolerance:g} of max|M| = {allowed:.3g} "
            f"kg m²; sample {k} has M[{r}, {c}] = {arr[k, r, c]:.6g} but M[{c}, {r}] = "
            f"{arr[k, c, r]:.6g}. Symmetrise noisy data with 0.5 * (M + M.swapaxes(1, 2))"
        )
    return arr


def _rows(
    base: BaseParameters,
    q: FloatArray,
    mass_matrix: FloatArray | None,
    gravity: FloatArray | None,
) -> tuple[FloatArray, FloatArray]:
    """Regression rows of one segment: g (n rows), then the upper triangle of M per sample."""
    n = base.robot.n_dof
    y_m, y_g = _regressors(base, q)
    rows, lhs = [], []
    if gravity is not None:
        rows.append(y_g)
        lhs.append(gravity)
    if mass_matrix is not None:
        # M is symmetric: its lower triangle would only repeat rows of the upper one.
        row, column = np.triu_indices(n)
        rows.append(y_m[:, column, row])
        lhs.append(mass_matrix[:, row, column])
    return (
        np.concatenate(rows, axis=1).reshape(-1, base.count),
        np.concatenate(lhs, axis=1).reshape(-1),
    )


def _with_exact_residual(
    acc: RegressionAccumulator, result: RegressionResult, rss: float
) -> RegressionResult:
    """Statistics of ``result`` recomputed with an RSS from the residuals themselves."""
    n, p = acc.n_samples, acc.n_parameters
    dof = n - p
    sigma2 = rss / dof
    scale = np.sqrt(np.diag(acc.xtx))
    factor = scipy.linalg.cho_factor(acc.xtx / np.outer(scale, scale))
    inverse = scipy.linalg.cho_solve(factor, np.eye(p)) / np.outer(scale, scale)
    std_errors = np.sqrt(np.clip(np.diag(inverse), 0.0, None) * sigma2)
    estimates = result.estimates
    with np.errstate(divide="ignore", invalid="ignore"):
        t_values = np.where(std_errors > 0, estimates / std_errors, np.inf * np.sign(estimates))
    quantile = float(scipy.stats.t.ppf(0.5 + result.level / 2.0, dof))
    tss = acc.yty - acc.sum_y**2 / n
    return dataclasses.replace(
        result,
        std_errors=std_errors,
        t_values=t_values,
        ci_lower=estimates - quantile * std_errors,
        ci_upper=estimates + quantile * std_errors,
        r_squared=1.0 - rss / tss if tss > 0 else float("nan"),
        rss=rss,
        residual_std=float(np.sqrt(sigma2)),
        covariance=inverse * sigma2,
    )


def identify_from_matrices(
    robot_or_base: RobotModel | BaseParameters,
    q: ArrayLike,
    mass_matrix: ArrayLike | None,
    gravity: ArrayLike | None,
    *,
    zero: Sequence[str] = (),
    segment: int = _DEFAULT_SEGMENT,
    use: str | Sequence[str] = ("M", "g"),
    level: float = 0.95,
    symmetry_tolerance: float = 1e-6,
) -> tuple[BaseParameters, RegressionResult]:
    """Identify base parameters from sampled M(q) and g(q), eq. (2.14a) and (2.15).

    For every sample the n equations g(q) = Y_g θ and the n(n+1)/2 equations
    of the upper triangle (diagonal included) of M(q) = [Y_{M_1} θ ... Y_{M_n} θ]
    are stacked and solved by least squares, pooled segment by segment through
    :class:`~sensorless.identification.regression.RegressionAccumulator`, so
    memory does not grow with the number of samples. The residual sum of
    squares is recomputed from the residuals in a second pass (see the module
    docstring: with exact data the t-statistics are then meaningful, as in
    thesis Table 2.7). The statistics assume one noise variance for all rows,
    M [kg m²] and g [N m] alike.

    Parameters
    ----------
    robot_or_base : RobotModel or BaseParameters
        Robot whose kinematics define the regressors, or its base parameters.
    q : array-like of shape (n_samples, n_dof)
        Joint positions [rad] at which the controller gave M and g.
    mass_matrix : array-like of shape (n_samples, n_dof, n_dof) or None
        Joint-space inertia matrices M(q) [kg m²], symmetric; may be None when
        ``use`` leaves out ``"M"`` (if given anyway it is checked, not used).
    gravity : array-like of shape (n_samples, n_dof) or None
        Gravity torques g(q) [N m]; may be None when ``use`` leaves out ``"g"``.
    zero : sequence of str
        Standard parameters known to be zero (see
        :func:`~sensorless.robots.base_parameters.base_parameters`); only with
        a RobotModel.
    segment : int
        Samples per segment of the pooled regression.
    use : {"M", "g"} or a sequence of them
        Which equations to stack. With one of them alone, the parameters that
        do not act on it (see :func:`contributing_terms`) make the regression
        rank-deficient.
    level : float
        Confidence level of the intervals, 0 < level < 1.
    symmetry_tolerance : float
        Largest accepted |M − Mᵀ|, relative to max|M| over all samples.

    Returns
    -------
    base : BaseParameters
    result : RegressionResult
        One row per base parameter, in the order of ``base.names``.

    Raises
    ------
    InputTypeError
        If ``robot_or_base`` is neither a RobotModel nor a BaseParameters.
    DimensionError
        If an array has the wrong shape or the sample counts differ.
    InputValueError
        For NaN/inf, a non-symmetric M, a bad ``use``, ``segment`` or ``level``,
        ``zero`` given with a BaseParameters, too few samples, or data that do
        not excite every base parameter (e.g. all samples at one configuration).

    Examples
    --------
    >>> import numpy as np
    >>> import sensorless as sl
    >>> robot = sl.robots.load("planar2")
    >>> q = np.random.default_rng(0).uniform(-np.pi, np.pi, (20, 2))
    >>> base, res = identify_from_matrices(robot, q, robot.mass_matrix(q), robot.gravity(q))
    >>> bool(np.allclose(res.estimates, base.values))
    True
    """
    if isinstance(robot_or_base, BaseParameters):
        if tuple(zero):
            raise InputValueError(
                f"zero={tuple(zero)!r} applies only when a RobotModel is given; the "
                "BaseParameters already fix the zero parameters "
                f"{robot_or_base.zero!r}"
            )
        base = robot_or_base
    elif isinstance(robot_or_base, RobotModel):
        base = base_parameters(robot_or_base, zero=zero)
    else:
        raise InputTypeError(
            f"robot_or_base must be a RobotModel or a BaseParameters; "
            f"got {type(robot_or_base).__name__}"
        )
    terms = _check_use(use)
    segment = _check_segment(segment)
    if not 0.0 < level < 1.0:
        raise InputValueError(f"level must lie in (0, 1); got {level!r}")
    symmetry_tolerance = check_scalar(symmetry_tolerance, "symmetry_tolerance", "-", "nonnegative")
    n = base.robot.n_dof
    q_arr, _ = as_joint_array(q, n, "q")
    m_arr = g_arr = None
    for term, value in (("M", mass_matrix), ("g", gravity)):
        if term in terms and value is None:
            name = "mass_matrix" if term == "M" else "gravity"
            raise InputValueError(f"{name} is None but use={terms!r} includes {term!r}")
    if mass_matrix is not None:
        m_arr = _check_mass_matrix(mass_matrix, q_arr.shape[0], n, symmetry_tolerance)
    if gravity is not None:
        g_arr, _ = as_joint_array(gravity, n, "gravity")
        if g_arr.shape[0] != q_arr.shape[0]:
            raise DimensionError(
                f"gravity must have as many samples as q ({q_arr.shape[0]}); "
                f"got shape {np.shape(gravity)}"
            )
    m_used = m_arr if "M" in terms else None
    g_used = g_arr if "g" in terms else None
    per_sample = ("g" in terms) * n + ("M" in terms) * n * (n + 1) // 2
    needed = base.count // per_sample + 1
    if q_arr.shape[0] < needed:
        raise InputValueError(
            f"too few samples: {base.count} base parameters need more than {base.count} "
            f"equations, i.e. at least {needed} configurations of {per_sample} equations "
            f"each (use={terms!r}); got {q_arr.shape[0]}"
        )

    acc = RegressionAccumulator(base.count)
    for part in _segments(q_arr.shape[0], segment):
        acc.add(*_rows(base, q_arr[part], _part(m_used, part), _part(g_used, part)))
    result = acc.result(base.names, level=level)
    rss = 0.0
    for part in _segments(q_arr.shape[0], segment):
        rows, lhs = _rows(base, q_arr[part], _part(m_used, part), _part(g_used, part))
        rss += float(np.sum((lhs - rows @ result.estimates) ** 2))
    return base, _with_exact_residual(acc, result, rss)


def _part(arr: FloatArray | None, part: slice) -> FloatArray | None:
    return None if arr is None else arr[part]


def contributing_terms(
    base: BaseParameters, q: ArrayLike, *, tolerance: float = 1e-9, segment: int = 1000
) -> pd.DataFrame:
    """Which of g and the columns of M each base parameter acts on (Table 2.7).

    The "Contributing Terms" column of thesis Table 2.7: base parameter θ_c
    contributes to term T (Y_g or Y_{M_i}) when column c of that regressor is
    non-zero at some sampled configuration, i.e. larger than ``tolerance``
    times the largest entry of column c over all terms and samples.

    Parameters
    ----------
    base : BaseParameters
        Base parameters of the robot.
    q : array-like of shape (n_samples, n_dof)
        Joint positions [rad] to look at (a parameter may vanish at special
        configurations: sample widely).
    tolerance : float
        Relative threshold, 0 <= tolerance < 1; it absorbs the round-off of the
        difference Y_b(q, 0, e_i) − Y_g.
    segment : int
        Samples per batch (memory only).

    Returns
    -------
    DataFrame of bool, shape (count, 1 + n_dof)
        Index ``base.names``; columns ``Y_g, Y_M1, ..., Y_Mn``.

    Examples
    --------
    >>> import numpy as np
    >>> import sensorless as sl
    >>> base = sl.base_parameters(sl.robots.load("planar2"))
    >>> q = np.random.default_rng(0).uniform(-np.pi, np.pi, (10, 2))
    >>> contributing_terms(base, q).loc["mX1R"].tolist()
    [True, False, False]
    """
    base = check_type(base, BaseParameters, "base", " (from sensorless.base_parameters)")
    if not (np.isfinite(tolerance) and 0.0 <= tolerance < 1.0):
        raise InputValueError(f"tolerance must lie in [0, 1); got {tolerance!r}")
    segment = _check_segment(segment)
    n = base.robot.n_dof
    q_arr, _ = as_joint_array(q, n, "q")
    peak = np.zeros((1 + n, base.count))
    for part in _segments(q_arr.shape[0], segment):
        y_m, y_g = _regressors(base, q_arr[part])
        peak[0] = np.maximum(peak[0], np.abs(y_g).max(axis=(0, 1)))
        peak[1:] = np.maximum(peak[1:], np.abs(y_m).max(axis=(0, 2)))
    largest = peak.max(axis=0)
    acts = (peak > tolerance * largest) & (largest > 0.0)
    columns = ["Y_g"] + [f"Y_M{i}" for i in range(1, n + 1)]
    return pd.DataFrame(acts.T, index=pd.Index(base.names, name="base parameter"), columns=columns)
