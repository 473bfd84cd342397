"""Static friction models fitted to a steady-state friction map (thesis §2.4.1).

Asymmetric Coulomb friction, eq. (2.7) and Table 2.2 (:func:`fit_coulomb`),
Coulomb plus viscous friction (:func:`fit_coulomb_viscous`) and the
Stribeck curve, the steady state of LuGre (:func:`fit_stribeck`). Each fit
works on the map of one joint (``v``, ``f`` of shape ``(n_points,)``, e.g.
the columns of :func:`~sensorless.identification.friction.steady_state_map`)
and returns a :class:`FrictionFit` holding a model of
:mod:`sensorless.friction` with ``n_dof = 1`` and its RMS residual.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike
from scipy.optimize import least_squares, lsq_linear

from .._validation import FloatArray, check_scalar
from ..exceptions import InputValueError
from ..friction import Coulomb, CoulombViscous, FrictionModel, LuGre, Stribeck
from ._friction_map import check_series

__all__ = ["FrictionFit", "fit_coulomb", "fit_coulomb_viscous", "fit_stribeck"]


@dataclass(frozen=True)
class FrictionFit:
    """Result of a friction fit.

    Attributes
    ----------
    model : FrictionModel or LuGre
        Fitted model of :mod:`sensorless.friction`, one joint.
    parameters : dict of str to float
        Fitted parameters by name, SI units.
    rms : float
        Root mean square of the residuals ``model - measured`` [N m].
    residuals : ndarray of shape (n_samples,)
        Residuals ``model - measured`` [N m].
    """

    model: FrictionModel | LuGre
    parameters: dict[str, float]
    rms: float
    residuals: FloatArray = field(repr=False)

    def to_pandas(self) -> pd.Series:
        """Parameters and ``rms`` as a :class:`pandas.Series`."""
        return pd.Series({**self.parameters, "rms": self.rms}, dtype=float)


def fit_from_residuals(
    model: FrictionModel | LuGre, parameters: dict[str, float], residuals: FloatArray
) -> FrictionFit:
    """A :class:`FrictionFit` whose ``rms`` [N m] is that of ``residuals`` [N m]."""
    rms = float(np.sqrt(np.mean(residuals**2)))
    return FrictionFit(model=model, parameters=parameters, rms=rms, residuals=residuals)


def _require_both_signs(v: FloatArray, needed: int = 1) -> None:
    n_pos, n_neg = int(np.sum(v > 0.0)), int(np.sum(v < 0.0))
    if n_pos < needed or n_neg < needed:
        raise InputValueError(
            f"v must contain at least {needed} positive and {needed} negative velocities; "
            f"got {n_pos} positive and {n_neg} negative"
        )


def fit_coulomb(v: ArrayLike, f: ArrayLike) -> FrictionFit:
    """Fit asymmetric Coulomb friction, eq. (2.7), to a steady-state map.

    Least squares of ``f = C+`` on the points with ``v > 0`` and of
    ``f = C-`` on those with ``v < 0`` (no slope), i.e. ``C+`` and ``C-``
    are the means of the torque at positive and at negative velocity, the
    values of Table 2.2. Points at ``v == 0`` are ignored.

    Parameters
    ----------
    v : array-like of shape (n_points,)
        Plateau velocities [rad/s], both signs.
    f : array-like of shape (n_points,)
        Steady-state friction torque [N m].

    Returns
    -------
    fit : FrictionFit
        ``model`` is a :class:`~sensorless.friction.Coulomb`; parameters
        ``c_pos``, ``c_neg``.

    Raises
    ------
    InputValueError
        If ``v`` lacks positive or negative velocities, or the fitted
        constants do not have the sign of the velocity (not dissipative).

    Examples
    --------
    >>> fit = fit_coulomb([-1.0, -0.5, 0.5, 1.0], [-0.26, -0.26, 0.25, 0.25])
    >>> fit.parameters
    {'c_pos': 0.25, 'c_neg': -0.26}
    """
    v_arr, f_arr = check_series(("v", "f"), v, f)
    _require_both_signs(v_arr)
    c_pos = float(np.mean(f_arr[v_arr > 0.0]))
    c_neg = float(np.mean(f_arr[v_arr < 0.0]))
    if c_pos < 0.0 or c_neg > 0.0:
        raise InputValueError(
            f"friction must have the sign of the velocity: expected C+ >= 0 and C- <= 0; "
            f"got C+ = {c_pos:.4g} N m, C- = {c_neg:.4g} N m"
        )
    model = Coulomb(c_pos=c_pos, c_neg=c_neg)
    moving = v_arr != 0.0
    residuals = model.evaluate(v_arr[moving]) - f_arr[moving]
    return fit_from_residuals(model, {"c_pos": c_pos, "c_neg": c_neg}, residuals)


def fit_coulomb_viscous(v: ArrayLike, f: ArrayLike) -> FrictionFit:
    """Fit Coulomb plus viscous friction ``f = C± + fv v`` to a steady-state map.

    Linear least squares with one intercept per velocity sign and a shared
    slope, bounded to ``C+ >= 0``, ``C- <= 0``, ``fv >= 0``
    (:func:`scipy.optimize.lsq_linear`). Points at ``v == 0`` are ignored.

    Parameters
    ----------
    v : array-like of shape (n_points,)
        Plateau velocities [rad/s], both signs, at least 3 distinct nonzero.
    f : array-like of shape (n_points,)
        Steady-state friction torque [N m].

    Returns
    -------
    fit : FrictionFit
        ``model`` is a :class:`~sensorless.friction.CoulombViscous`;
        parameters ``c_pos``, ``c_neg``, ``fv``.
    """
    v_arr, f_arr = check_series(("v", "f"), v, f)
    _require_both_signs(v_arr)
    moving = v_arr != 0.0
    v_m, f_m = v_arr[moving], f_arr[moving]
    if np.unique(v_m).size < 3:
        raise InputValueError(
            f"v must contain at least 3 distinct nonzero velocities; got {np.unique(v_m).size}"
        )
    design = np.column_stack([v_m > 0.0, v_m < 0.0, v_m]).astype(np.float64)
    solution = lsq_linear(
        design, f_m, bounds=([0.0, -np.inf, 0.0], [np.inf, 0.0, np.inf]), method="bvls"
    )
    c_pos, c_neg, fv = (float(x) for x in solution.x)
    model = CoulombViscous(c_pos=c_pos, c_neg=c_neg, fv=fv)
    residuals = model.evaluate(v_m) - f_m
    return fit_from_residuals(model, {"c_pos": c_pos, "c_neg": c_neg, "fv": fv}, residuals)


def _stribeck_design(v: FloatArray, vs: float, delta: float) -> FloatArray:
    """Columns multiplying fc, fs, fv: the Stribeck curve is linear in them for fixed vs."""
    decay = np.exp(-(np.abs(v / vs) ** delta))
    sign = np.sign(v)
    return np.column_stack([sign * (1.0 - decay), sign * decay, v])


def fit_stribeck(v: ArrayLike, f: ArrayLike, *, delta: float = 2.0) -> FrictionFit:
    """Fit the symmetric Stribeck curve (steady state of LuGre) to a steady-state map.

    ``f = sign(v) (fc + (fs - fc) exp(-|v/vs|**delta)) + fv v`` with the
    exponent ``delta`` fixed (2: Gaussian of Canudas de Wit et al.; 1: the
    thesis's eq. (4.22c)). For fixed ``vs`` the curve is linear in ``fc``,
    ``fs``, ``fv``; the start is the best of a logarithmic grid of ``vs``
    over the measured speeds, each with a bounded linear fit, and
    :func:`scipy.optimize.least_squares` then refines all four parameters
    with ``fc, fs, fv >= 0`` and ``vs > 0``.

    Parameters
    ----------
    v : array-like of shape (n_points,)
        Plateau velocities [rad/s]; at least 4 distinct nonzero speeds.
    f : array-like of shape (n_points,)
        Steady-state friction torque [N m].
    delta : float, default 2.0
        Stribeck exponent [-], ``> 0``.

    Returns
    -------
    fit : FrictionFit
        ``model`` is a :class:`~sensorless.friction.Stribeck`; parameters
        ``fc``, ``fs``, ``vs``, ``fv``.
    """
    v_arr, f_arr = check_series(("v", "f"), v, f)
    delta = check_scalar(delta, "delta", "-")
    moving = v_arr != 0.0
    v_m, f_m = v_arr[moving], f_arr[moving]
    speeds = np.unique(np.abs(v_m))
    if speeds.size < 4:
        raise InputValueError(
            f"v must contain at least 4 distinct nonzero speeds for 4 parameters; got {speeds.size}"
        )
    bounds = ([0.0, 0.0, 0.0], [np.inf, np.inf, np.inf])
    best_cost, start = np.inf, np.zeros(4)
    for vs in np.geomspace(speeds[0] / 10.0, speeds[-1], 60):
        linear = lsq_linear(_stribeck_design(v_m, vs, delta), f_m, bounds=bounds, method="bvls")
        if linear.cost < best_cost:
            best_cost, start = float(linear.cost), np.array([*linear.x[:2], vs, linear.x[2]])
    scale = np.maximum(np.abs(start), [1e-6, 1e-6, 1e-9, 1e-6])

    def residual(x: FloatArray) -> FloatArray:
        fc, fs, vs, fv = x
        return np.asarray(_stribeck_design(v_m, vs, delta) @ [fc, fs, fv] - f_m)

    solution = least_squares(
        residual,
        start,
        bounds=([0.0, 0.0, speeds[0] * 1e-3, 0.0], np.inf),
        x_scale=scale,
        ftol=1e-14,
        xtol=1e-14,
        gtol=1e-14,
    )
    fc, fs, vs, fv = (float(x) for x in solution.x)
    model = Stribeck(fc=fc, fs=fs, vs=vs, fv=fv, delta=delta)
    residuals = model.evaluate(v_m) - f_m
    return fit_from_residuals(model, {"fc": fc, "fs": fs, "vs": vs, "fv": fv}, residuals)


#: The static fits by the model name of
#: :func:`~sensorless.identification.friction.identify_friction`.
FITTERS: dict[str, Callable[[ArrayLike, ArrayLike], FrictionFit]] = {
    "coulomb": fit_coulomb,
    "coulomb_viscous": fit_coulomb_viscous,
    "stribeck": fit_stribeck,
}
