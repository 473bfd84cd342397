"""Friction identification from constant-velocity sweeps and presliding motion.

The procedure of the thesis, §2.4.1-2.4.2: each joint is moved alone at
constant velocities (-2 ... +2 rad/s in 0.16 rad/s steps, and -0.11 ...
+0.11 rad/s in 0.01 rad/s steps, :func:`sweep_velocities`); the mean
friction torque on each plateau gives the steady-state friction map of
Fig. 2.2 (:func:`steady_state_map`, :func:`plot_friction_map`); a static
model is fitted to that map (:func:`fit_coulomb`, eq. (2.7) and Table 2.2;
:func:`fit_coulomb_viscous`; :func:`fit_stribeck`), and the dynamic LuGre
parameters sigma0, sigma1 are fitted to small presliding motion
(:func:`fit_lugre_dynamic`, Canudas de Wit et al. 1995).

Sign convention and units are those of :mod:`sensorless.friction`: the
friction torque [N m] has the sign of the joint velocity [rad/s]. The map
and fit functions work on one joint; arrays have shape ``(n_samples,)``;
:func:`identify_friction` runs them on every swept joint of a log. Fits return
a :class:`FrictionFit` holding the fitted model (with ``n_dof = 1``) and its
RMS residual.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np
import pandas as pd
from matplotlib.axes import Axes
from matplotlib.figure import Figure
from numpy.typing import ArrayLike
from scipy.optimize import least_squares, lsq_linear

from .._validation import FloatArray
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..friction import Coulomb, CoulombViscous, FrictionModel, LuGre, Stribeck
from ..io import Log
from ..robots.model import RobotModel
from .logs import savgol_derivatives

__all__ = [
    "FrictionFit",
    "FrictionIdentification",
    "fit_coulomb",
    "fit_coulomb_viscous",
    "fit_lugre_dynamic",
    "fit_stribeck",
    "identify_friction",
    "plot_friction_map",
    "steady_state_map",
    "sweep_velocities",
]


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


def _vector(x: ArrayLike, name: str) -> FloatArray:
    try:
        arr = np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise DimensionError(
            f"{name} must be a numeric array of shape (n_samples,); could not convert it: {exc}"
        ) from None
    if arr.ndim != 1:
        raise DimensionError(f"{name} must have shape (n_samples,); got shape {arr.shape}")
    if not np.isfinite(arr).all():
        bad = int(np.argmin(np.isfinite(arr)))
        raise InputValueError(f"{name} must be finite; found {arr[bad]} at index {bad}")
    return arr


def _vectors(names: tuple[str, ...], *arrays: ArrayLike, minimum: int = 1) -> list[FloatArray]:
    """Check 1-D finite arrays of one common length (at least ``minimum``)."""
    out = [_vector(a, n) for a, n in zip(arrays, names, strict=True)]
    lengths = {n: a.shape[0] for n, a in zip(names, out, strict=True)}
    if len(set(lengths.values())) != 1:
        raise DimensionError(f"{', '.join(names)} must have the same length; got {lengths}")
    if out[0].shape[0] < minimum:
        raise DimensionError(
            f"{', '.join(names)} need at least {minimum} samples; got {out[0].shape[0]}"
        )
    return out


def _grid(lo: float, hi: float, step: float) -> FloatArray:
    if not (np.isfinite([lo, hi, step]).all() and step > 0.0 and hi >= lo):
        raise InputValueError(
            f"a sweep must be (low, high, step) with low <= high and step > 0; got {(lo, hi, step)}"
        )
    n = int(np.floor((hi - lo) / step + 1e-9))
    # Rounding removes the float noise of lo + k*step so that both sweeps share values.
    return np.round(lo + step * np.arange(n + 1), 12)


def sweep_velocities(
    fast: tuple[float, float, float] = (-2.0, 2.0, 0.16),
    slow: tuple[float, float, float] = (-0.11, 0.11, 0.01),
) -> FloatArray:
    """Constant velocities of the friction experiments, thesis §2.4.1.

    Parameters
    ----------
    fast : tuple (low, high, step), default (-2, 2, 0.16)
        Wide sweep [rad/s].
    slow : tuple (low, high, step), default (-0.11, 0.11, 0.01)
        Slow sweep [rad/s].

    Returns
    -------
    velocities : ndarray of shape (n_velocities,)
        Sorted, unique velocities of both sweeps [rad/s]; zero is excluded.

    Examples
    --------
    >>> v = sweep_velocities()
    >>> v.size, float(v[0]), float(v[-1]), bool((v != 0).all())
    (46, -2.0, 2.0, True)
    """
    values = np.unique(np.concatenate([_grid(*fast), _grid(*slow)]))
    return values[values != 0.0]


def _plateaus(qd: FloatArray, tolerance: float) -> list[tuple[int, int]]:
    """Runs ``[start, stop)`` where ``qd`` stays within tolerance of the run's mean."""
    runs = []
    start, total = 0, qd[0]
    for k in range(1, qd.shape[0]):
        mean = total / (k - start)
        if abs(qd[k] - mean) < tolerance * max(abs(mean), 0.01):
            total += qd[k]
        else:
            runs.append((start, k))
            start, total = k, qd[k]
    runs.append((start, qd.shape[0]))
    return runs


def steady_state_map(
    t: ArrayLike,
    qd: ArrayLike,
    tau: ArrayLike,
    *,
    settle: float = 0.5,
    tolerance: float = 0.02,
) -> pd.DataFrame:
    """Steady-state friction map (Fig. 2.2) from a constant-velocity log of one joint.

    A plateau is a run of samples whose velocity stays within
    ``tolerance * max(|v|, 0.01 rad/s)`` of the run's mean ``v``. The first
    ``settle`` seconds of each plateau (the friction transient) are dropped;
    plateaus shorter than that, and plateaus at standstill
    (``|v| < 0.01 * tolerance``, where friction is not defined by the
    velocity), are ignored.

    Parameters
    ----------
    t : array-like of shape (n_samples,)
        Time [s], strictly increasing.
    qd : array-like of shape (n_samples,)
        Joint velocity [rad/s], piecewise constant.
    tau : array-like of shape (n_samples,)
        Friction torque estimate [N m], e.g. from eq. (2.6) or (2.10).
    settle : float, default 0.5
        Transient dropped at the start of each plateau [s], ``>= 0``.
    tolerance : float, default 0.02
        Relative velocity tolerance of a plateau [-], ``> 0``.

    Returns
    -------
    map : DataFrame
        One row per plateau, sorted by velocity, with columns ``velocity``
        [rad/s] (mean on the kept samples), ``torque`` [N m] (mean),
        ``torque_std`` [N m] (standard deviation) and ``n_samples``.

    Raises
    ------
    DimensionError
        If the arrays are not 1-D of one length (at least 2 samples).
    InputValueError
        If a value is not finite, ``t`` is not strictly increasing, the
        options are out of range, or no plateau is found.
    """
    t_arr, qd_arr, tau_arr = _vectors(("t", "qd", "tau"), t, qd, tau, minimum=2)
    if not np.all(np.diff(t_arr) > 0.0):
        raise InputValueError("t must be strictly increasing [s]")
    if not (np.isfinite(settle) and settle >= 0.0):
        raise InputValueError(f"settle must be a finite number of seconds >= 0; got {settle!r}")
    if not (np.isfinite(tolerance) and tolerance > 0.0):
        raise InputValueError(f"tolerance must be a finite number > 0; got {tolerance!r}")
    rows = []
    for start, stop in _plateaus(qd_arr, tolerance):
        kept = np.flatnonzero(t_arr[start:stop] >= t_arr[start] + settle) + start
        if kept.size < 2 or t_arr[stop - 1] - t_arr[start] < settle:
            continue
        velocity = float(np.mean(qd_arr[kept]))
        if abs(velocity) < 0.01 * tolerance:
            continue
        rows.append(
            {
                "velocity": velocity,
                "torque": float(np.mean(tau_arr[kept])),
                "torque_std": float(np.std(tau_arr[kept], ddof=1)),
                "n_samples": int(kept.size),
            }
        )
    if not rows:
        raise InputValueError(
            f"no constant-velocity plateau longer than settle={settle} s found in qd "
            f"(tolerance={tolerance}); expected piecewise-constant velocities, got a velocity "
            f"range [{qd_arr.min():.4g}, {qd_arr.max():.4g}] rad/s"
        )
    return pd.DataFrame(rows).sort_values("velocity", ignore_index=True)


def _map_arrays(v: ArrayLike, f: ArrayLike) -> tuple[FloatArray, FloatArray]:
    v_arr, f_arr = _vectors(("v", "f"), v, f)
    return v_arr, f_arr


def _require_both_signs(v: FloatArray, needed: int = 1) -> None:
    n_pos, n_neg = int(np.sum(v > 0.0)), int(np.sum(v < 0.0))
    if n_pos < needed or n_neg < needed:
        raise InputValueError(
            f"v must contain at least {needed} positive and {needed} negative velocities; "
            f"got {n_pos} positive and {n_neg} negative"
        )


def _result(
    model: FrictionModel | LuGre, parameters: dict[str, float], residuals: FloatArray
) -> FrictionFit:
    rms = float(np.sqrt(np.mean(residuals**2)))
    return FrictionFit(model=model, parameters=parameters, rms=rms, residuals=residuals)


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
    v_arr, f_arr = _map_arrays(v, f)
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
    return _result(model, {"c_pos": c_pos, "c_neg": c_neg}, residuals)


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
    v_arr, f_arr = _map_arrays(v, f)
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
    return _result(model, {"c_pos": c_pos, "c_neg": c_neg, "fv": fv}, residuals)


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
    v_arr, f_arr = _map_arrays(v, f)
    if not (np.isfinite(delta) and delta > 0.0):
        raise InputValueError(f"delta must be a finite number > 0; got {delta!r}")
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
    return _result(model, {"fc": fc, "fs": fs, "vs": vs, "fv": fv}, residuals)


def _uniform_period(t: FloatArray) -> float:
    steps = np.diff(t)
    dt = float(np.median(steps))
    if dt <= 0.0 or not np.allclose(steps, dt, rtol=1e-6, atol=0.0):
        raise InputValueError(
            f"t must be uniformly sampled with a positive period; got periods from "
            f"{steps.min():.6g} to {steps.max():.6g} s (resample the log explicitly)"
        )
    return dt


def fit_lugre_dynamic(
    t: ArrayLike,
    q: ArrayLike,
    tau: ArrayLike,
    static: Stribeck,
) -> FrictionFit:
    """Fit the LuGre bristle stiffness sigma0 and damping sigma1 to presliding motion.

    The static part of eq. (4.22) is fixed from ``static``: ``fc``, ``fs``,
    ``vs``, ``delta`` and ``sigma2 = fv``. The velocity over sample period
    ``k`` is ``(q[k+1] - q[k]) / dt`` (the held-velocity convention of
    :meth:`sensorless.friction.LuGre.step`; the last period repeats the one
    before), the bristles start at rest (``z = 0``) and ``tau[k]`` is
    compared with the simulated torque at the end of period ``k``. The start
    values come from the linear presliding approximation
    ``tau ≈ sigma0 (q - q[0]) + (sigma1 + sigma2) qd``; then
    :func:`scipy.optimize.least_squares` refines ``log sigma0`` and
    ``log sigma1`` (positivity by construction). Use a motion well inside
    presliding (``|q - q[0]|`` a fraction of ``fc / sigma0``) with a
    frequency at which ``sigma1 qd`` is not negligible against ``sigma0 q``.

    Parameters
    ----------
    t : array-like of shape (n_samples,)
        Time [s], uniformly sampled.
    q : array-like of shape (n_samples,)
        Joint position [rad], starting at rest.
    tau : array-like of shape (n_samples,)
        Measured friction torque [N m].
    static : Stribeck
        Static friction of the joint (one joint), e.g. from :func:`fit_stribeck`.

    Returns
    -------
    fit : FrictionFit
        ``model`` is a :class:`~sensorless.friction.LuGre`; parameters
        ``sigma0``, ``sigma1``.
    """
    if not isinstance(static, Stribeck):
        raise InputTypeError(
            f"static must be a sensorless.friction.Stribeck model; got {type(static).__name__}"
        )
    if static.n_dof != 1:
        raise DimensionError(f"static must describe one joint; got n_dof = {static.n_dof}")
    t_arr, q_arr, tau_arr = _vectors(("t", "q", "tau"), t, q, tau, minimum=3)
    dt = _uniform_period(t_arr)
    qd = np.diff(q_arr) / dt
    qd = np.append(qd, qd[-1])
    fixed: dict[str, Any] = {
        "sigma2": static.fv,
        "fc": static.fc,
        "fs": static.fs,
        "vs": static.vs,
        "delta": static.delta,
    }
    if np.any(static.fc <= 0.0) or np.any(static.fs <= 0.0):
        raise InputValueError(
            f"static must have fc > 0 and fs > 0 for LuGre; got fc = {static.fc[0]}, "
            f"fs = {static.fs[0]}"
        )
    # z follows q - q[0] at the end of each period while presliding.
    z_approx = np.cumsum(qd) * dt
    design = np.column_stack([z_approx, qd])
    coef, *_ = np.linalg.lstsq(design, tau_arr - static.fv[0] * qd, rcond=None)
    sigma0_start = coef[0] if coef[0] > 0.0 else float(static.fs[0] / max(np.ptp(q_arr), 1e-12))
    sigma1_start = coef[1] if coef[1] > 0.0 else np.sqrt(sigma0_start)
    velocity = qd[:, None]

    def simulate(x: FloatArray) -> FloatArray:
        model = LuGre(sigma0=np.exp(x[0]), sigma1=np.exp(x[1]), **fixed)
        return model.torque(velocity, dt)[0][:, 0]

    def residual(x: FloatArray) -> FloatArray:
        return simulate(x) - tau_arr

    solution = least_squares(residual, np.log([sigma0_start, sigma1_start]), xtol=1e-10, ftol=1e-10)
    sigma0, sigma1 = (float(x) for x in np.exp(solution.x))
    model = LuGre(sigma0=sigma0, sigma1=sigma1, **fixed)
    return _result(model, {"sigma0": sigma0, "sigma1": sigma1}, residual(solution.x))


def plot_friction_map(
    map_df: pd.DataFrame, model: FrictionModel | LuGre | FrictionFit | None = None
) -> Figure:
    """Plot a steady-state friction map with error bars and a fitted curve (Fig. 2.2).

    Parameters
    ----------
    map_df : DataFrame
        Output of :func:`steady_state_map` (columns ``velocity`` [rad/s],
        ``torque`` [N m], optionally ``torque_std`` [N m]).
    model : FrictionModel, LuGre or FrictionFit, optional
        One-joint model drawn as a curve over the velocity range; for
        :class:`~sensorless.friction.LuGre` its steady state.

    Returns
    -------
    figure : matplotlib.figure.Figure
    """
    missing = {"velocity", "torque"} - set(map_df.columns)
    if missing:
        raise InputValueError(
            f"map_df must have columns 'velocity' and 'torque'; missing {sorted(missing)}"
        )
    figure = Figure(figsize=(6.0, 4.0))
    axes = figure.add_subplot()
    std = map_df["torque_std"].to_numpy() if "torque_std" in map_df.columns else None
    axes.errorbar(
        map_df["velocity"].to_numpy(),
        map_df["torque"].to_numpy(),
        yerr=std,
        fmt="o",
        markersize=3,
        capsize=2,
        label="measured",
    )
    if isinstance(model, FrictionFit):
        model = model.model
    if model is not None:
        v = map_df["velocity"].to_numpy()
        grid = np.linspace(v.min(), v.max(), 801)
        grid = grid[grid != 0.0][:, None]
        curve = model.steady_state(grid) if isinstance(model, LuGre) else model.torque(grid)
        axes.plot(grid[:, 0], curve[:, 0], "-", label=type(model).__name__)
    axes.axhline(0.0, color="0.7", linewidth=0.5)
    axes.axvline(0.0, color="0.7", linewidth=0.5)
    axes.set_xlabel("joint velocity [rad/s]")
    axes.set_ylabel("friction torque [N m]")
    axes.legend()
    figure.tight_layout()
    return figure


# ------------------------------------------------------------ whole-robot sweep logs
_FITTERS = {
    "coulomb": fit_coulomb,
    "coulomb_viscous": fit_coulomb_viscous,
    "stribeck": fit_stribeck,
}
_TORQUE_GROUPS = {"motor": "tau_m", "joint": "tau_j"}
#: Units of the map columns and of every fitted parameter, for ``to_dict``.
_UNITS = {
    "velocity": "rad/s",
    "torque": "N m",
    "torque_std": "N m",
    "c_pos": "N m",
    "c_neg": "N m",
    "fv": "N m s/rad",
    "fc": "N m",
    "fs": "N m",
    "vs": "rad/s",
    "rms": "N m",
    "settle": "s",
    "rest_velocity": "rad/s",
    "max_acceleration": "rad/s^2",
    "window": "s",
}


@dataclass(frozen=True)
class FrictionIdentification:
    """Friction maps and fitted models of the joints swept in one log.

    Returned by :func:`identify_friction`.

    Attributes
    ----------
    maps : DataFrame
        Steady-state maps of all identified joints: columns ``joint``
        (numbered from 1), ``velocity`` [rad/s], ``torque`` [N m],
        ``torque_std`` [N m] and ``n_samples``, as :func:`steady_state_map`.
    fits : dict of int to dict of str to FrictionFit
        ``fits[joint][model]`` for each identified joint and requested model
        (``"coulomb"``, ``"coulomb_viscous"``, ``"stribeck"``).
    torque : {"motor", "joint"}
        Torque the friction was computed from: ``tau_m - g(q)`` (eq. (2.6)
        at constant velocity) or ``tau_j - g(q)`` (eq. (2.10), link side).
    settle : float
        Transient dropped at the start of each plateau [s].
    tolerance : float
        Relative velocity tolerance of a plateau [-].
    rest_velocity : float
        Speed [rad/s] under which a joint counted as resting.
    max_acceleration : float
        Largest acceleration [rad/s²] of a steady-state sample.
    window : float
        Length of the Savitzky-Golay velocity window [s].
    """

    maps: pd.DataFrame
    fits: dict[int, dict[str, FrictionFit]]
    torque: str
    settle: float
    tolerance: float
    rest_velocity: float
    max_acceleration: float
    window: float

    @property
    def joints(self) -> tuple[int, ...]:
        """Identified joints, numbered from 1, in increasing order."""
        return tuple(sorted(self.fits))

    def joint_map(self, joint: int) -> pd.DataFrame:
        """Steady-state map of one identified joint (columns of :func:`steady_state_map`)."""
        if joint not in self.fits:
            raise InputValueError(
                f"joint {joint!r} was not identified; identified joints: {list(self.joints)}"
            )
        rows = self.maps[self.maps["joint"] == joint].drop(columns="joint")
        return rows.reset_index(drop=True)

    def to_pandas(self) -> pd.DataFrame:
        """One row per joint and model: ``joint``, ``model``, the parameters, ``rms``.

        Parameters a model does not have are NaN; ``n_plateaus`` counts the
        points of the joint's map.
        """
        counts = self.maps.groupby("joint").size()
        rows = [
            {
                "joint": joint,
                "model": name,
                **fit.parameters,
                "rms": fit.rms,
                "n_plateaus": int(counts[joint]),
            }
            for joint in self.joints
            for name, fit in self.fits[joint].items()
        ]
        parameters = dict.fromkeys(
            key for row in rows for key in row if key not in ("joint", "model", "rms", "n_plateaus")
        )
        return pd.DataFrame(rows, columns=["joint", "model", *parameters, "rms", "n_plateaus"])

    def to_dict(self) -> dict[str, Any]:
        """Plain Python values (lists, floats, str) for a YAML or JSON file, SI units.

        Returns
        -------
        dict
            ``torque``, ``settle``, ``tolerance``, ``rest_velocity``,
            ``max_acceleration``, ``window``, a ``units`` entry naming the unit of every number, and
            ``joints``: a list with, per joint, its number, its map (lists
            ``velocity``, ``torque``, ``torque_std``, ``n_samples``) and its
            fitted ``models`` (parameters and ``rms`` by model name).
        """
        joints = []
        for joint in self.joints:
            table = self.joint_map(joint)
            joints.append(
                {
                    "joint": int(joint),
                    "map": {
                        column: [float(v) for v in table[column]]
                        for column in ("velocity", "torque", "torque_std")
                    }
                    | {"n_samples": [int(v) for v in table["n_samples"]]},
                    "models": {
                        name: {**{k: float(v) for k, v in fit.parameters.items()}, "rms": fit.rms}
                        for name, fit in self.fits[joint].items()
                    },
                }
            )
        return {
            "torque": self.torque,
            "settle": float(self.settle),
            "tolerance": float(self.tolerance),
            "rest_velocity": float(self.rest_velocity),
            "max_acceleration": float(self.max_acceleration),
            "window": float(self.window),
            "units": dict(_UNITS),
            "joints": joints,
        }

    def plot(self) -> Figure:
        """Friction map and fitted curves, one panel per joint (Fig. 2.2).

        Returns
        -------
        figure : matplotlib.figure.Figure
        """
        n = len(self.joints)
        ncols = min(n, 4)
        nrows = -(-n // ncols)
        figure = Figure(figsize=(4.0 * ncols, 3.2 * nrows))
        for k, joint in enumerate(self.joints):
            axes = figure.add_subplot(nrows, ncols, k + 1)
            _draw_friction_map(axes, self.joint_map(joint), self.fits[joint])
            axes.set_title(f"joint {joint} ({self.torque} torque)")
        figure.tight_layout()
        return figure


def _draw_friction_map(axes: Axes, map_df: pd.DataFrame, fits: dict[str, FrictionFit]) -> None:
    """Measured map with error bars and one curve per fitted model on ``axes``."""
    v = map_df["velocity"].to_numpy()
    axes.errorbar(
        v,
        map_df["torque"].to_numpy(),
        yerr=map_df["torque_std"].to_numpy(),
        fmt="o",
        markersize=3,
        capsize=2,
        color="0.2",
        label="measured",
    )
    grid = np.linspace(v.min(), v.max(), 801)
    grid = grid[grid != 0.0][:, None]
    for name, fit in fits.items():
        model = fit.model
        curve = model.steady_state(grid) if isinstance(model, LuGre) else model.torque(grid)
        axes.plot(grid[:, 0], curve[:, 0], "-", label=name)
    axes.axhline(0.0, color="0.7", linewidth=0.5)
    axes.axvline(0.0, color="0.7", linewidth=0.5)
    axes.set_xlabel("joint velocity [rad/s]")
    axes.set_ylabel("friction torque [N m]")
    axes.legend(fontsize="small")


def _check_options(**values: float) -> dict[str, float]:
    """Check ``settle >= 0`` and the other options ``> 0``, all finite."""
    out = {}
    for name, value in values.items():
        try:
            number = float(value)
        except (TypeError, ValueError):
            number = np.nan
        bound = ">= 0" if name == "settle" else "> 0"
        if not (np.isfinite(number) and (number >= 0.0 if name == "settle" else number > 0.0)):
            raise InputValueError(
                f"{name} must be a finite number {bound} [{_UNITS.get(name, '-')}]; got {value!r}"
            )
        out[name] = number
    return out


def _check_models(models: str | tuple[str, ...] | list[str]) -> tuple[str, ...]:
    names = (models,) if isinstance(models, str) else tuple(models)
    unknown = [name for name in names if name not in _FITTERS]
    if not names or unknown:
        raise InputValueError(
            f"models must be a non-empty sequence of {sorted(_FITTERS)}; got {models!r}"
        )
    return names


def _check_sweep_joints(joints: Any, n_dof: int) -> tuple[int, ...] | None:
    if joints is None:
        return None
    values = np.atleast_1d(np.asarray(joints))
    valid = values.ndim == 1 and values.size > 0 and values.dtype.kind in "iu"
    if not valid or np.any((values < 1) | (values > n_dof)) or np.unique(values).size < values.size:
        raise InputValueError(
            f"joints must be distinct joint numbers from 1 to n_dof = {n_dof}; got {joints!r}"
        )
    return tuple(int(j) for j in values)


def _friction_torque(log: Log, robot: RobotModel, torque: str) -> FloatArray:
    """``tau - g(q)`` [N m]: the friction torque on a constant-velocity plateau."""
    if torque not in _TORQUE_GROUPS:
        raise InputValueError(f"torque must be one of {sorted(_TORQUE_GROUPS)}; got {torque!r}")
    group = _TORQUE_GROUPS[torque]
    tau = getattr(log, group)
    if tau is None:
        raise InputValueError(
            f"torque={torque!r} needs the columns {group}_1..{group}_{log.n_dof} in the log; "
            f"this log has none (use torque='motor' for the motor torque tau_m)"
            if torque == "joint"
            else f"torque='motor' needs the motor torque columns tau_m_1..tau_m_{log.n_dof} in "
            f"the log; this log has none"
        )
    return np.asarray(tau - robot.gravity(log.q), dtype=np.float64)


def identify_friction(
    log: Log,
    robot: RobotModel,
    *,
    joints: int | ArrayLike | None = None,
    torque: str = "motor",
    models: str | tuple[str, ...] | list[str] = ("coulomb", "coulomb_viscous", "stribeck"),
    settle: float = 0.5,
    tolerance: float = 0.02,
    rest_velocity: float = 0.005,
    max_acceleration: float = 0.1,
    window: float = 0.1,
) -> FrictionIdentification:
    """Identify joint friction from a constant-velocity sweep log (thesis §2.4.1-2.4.2).

    In the experiment each joint moves alone at constant velocities while
    the others rest (e.g. :class:`sensorless.trajectories.VelocitySweep`).
    With ``q̈ = 0`` and, the other joints at rest, no Coriolis or centrifugal
    torque on the moving joint, its friction torque is

    * ``tau_fr = tau_m - g(q)`` for ``torque="motor"`` (eq. (2.6) at constant
      velocity; on a flexible arm this is the total, motor plus link, friction);
    * ``tau_frL = tau_J - g(q)`` for ``torque="joint"`` (eq. (2.10), the
      link-side friction seen by joint torque sensors),

    with ``g`` the gravity of ``robot``. The velocity is estimated from the
    measured ``q`` with a zero-phase :class:`sensorless.filters.SavitzkyGolay`
    filter (ground-truth velocities in the log are not used). A sample
    counts for joint ``j`` when ``|qd_j| > rest_velocity``, every other
    joint is below it, and ``|qdd_j| <= max_acceleration`` (the ``q̈ = 0`` of
    the method, enforced: at the edges of a plateau the velocity may still be
    within tolerance while the inertia torque ``M_jj q̈_j`` is not negligible
    against friction). The other samples are set to rest for joint ``j``, so
    the sweeps of the other joints do not enter its map.
    :func:`steady_state_map` then finds the plateaus (dropping ``settle``
    seconds of transient from each) and the requested models are fitted
    to the map.

    Parameters
    ----------
    log : Log
        Uniformly sampled run with ``tau_m`` (or ``tau_j``).
    robot : RobotModel
        Model whose gravity torque is removed; same joint count as the log.
    joints : int or sequence of int, optional
        Joints to identify, numbered from 1. By default every joint that
        moves alone at a constant velocity somewhere in the log.
    torque : {"motor", "joint"}, default "motor"
        Torque the friction is computed from (see above).
    models : sequence of {"coulomb", "coulomb_viscous", "stribeck"}
        Models fitted to each map (:func:`fit_coulomb`,
        :func:`fit_coulomb_viscous`, :func:`fit_stribeck`).
    settle : float, default 0.5
        Transient dropped at the start of each plateau [s], ``>= 0``.
    tolerance : float, default 0.02
        Relative velocity tolerance of a plateau [-], ``> 0``.
    rest_velocity : float, default 0.005
        Speed under which a joint counts as resting [rad/s]; half the
        slowest velocity of the thesis's slow sweep by default.
    max_acceleration : float, default 0.1
        Largest acceleration of the moving joint in a steady-state sample
        [rad/s²], ``> 0``. Raise it for noisy positions (the Savitzky-Golay
        acceleration is noisier than the velocity).
    window : float, default 0.1
        Length of the Savitzky-Golay window [s] of the velocity and
        acceleration estimates (cubic fit; at least 5 samples). Longer
        windows average out the ripple of a flexible or stick-slipping joint
        before the acceleration test; the plateaus must be much longer.

    Returns
    -------
    FrictionIdentification

    Raises
    ------
    InputTypeError
        If ``log`` is not a :class:`~sensorless.io.Log` or ``robot`` not a
        :class:`~sensorless.robots.model.RobotModel`.
    DimensionError
        If the log and the robot have different joint counts.
    InputValueError
        If an option is out of range, the log lacks the requested torque or
        is not uniformly sampled, the robot stands still, no joint moves
        alone at a constant velocity, a requested joint has no plateau, or
        a fit fails (the message names the joint and the model).

    Examples
    --------
    >>> import numpy as np
    >>> from sensorless.io import Log
    >>> from sensorless.robots import load
    >>> robot = load("planar2")
    >>> t = np.arange(0.0, 8.0, 1e-3)
    >>> v = np.select([t < 2, t < 4, t < 6], [0.5, -0.5, 1.0], -1.0)
    >>> q = np.column_stack([np.cumsum(v) * 1e-3, np.zeros_like(t)])
    >>> tau = robot.gravity(q) + np.column_stack([0.3 * np.sign(v) + 0.1 * v, 0 * t])
    >>> result = identify_friction(Log(t=t, q=q, tau_m=tau), robot, models="coulomb_viscous")
    >>> result.joints
    (1,)
    >>> {k: round(v, 4) for k, v in result.fits[1]["coulomb_viscous"].parameters.items()}
    {'c_pos': 0.3, 'c_neg': -0.3, 'fv': 0.1}
    """
    if not isinstance(log, Log):
        raise InputTypeError(f"log must be a sensorless.io.Log; got {type(log).__name__}")
    if not isinstance(robot, RobotModel):
        raise InputTypeError(f"robot must be a RobotModel; got {type(robot).__name__}")
    if log.n_dof != robot.n_dof:
        raise DimensionError(
            f"the log has {log.n_dof} joints (columns q_1..q_{log.n_dof}) but robot "
            f"{robot.name!r} has {robot.n_dof}; pass the model of the robot that made the log"
        )
    options = _check_options(
        settle=settle,
        tolerance=tolerance,
        rest_velocity=rest_velocity,
        max_acceleration=max_acceleration,
        window=window,
    )
    names = _check_models(models)
    chosen = _check_sweep_joints(joints, robot.n_dof)
    friction = _friction_torque(log, robot, torque)
    solo = _solo_velocities(log, options)
    candidates = chosen or tuple(int(j) + 1 for j in np.flatnonzero(solo.any(axis=0)))
    maps, fits = [], {}
    for joint in candidates:
        j = joint - 1
        try:
            table = steady_state_map(
                log.t,
                solo[:, j],
                friction[:, j],
                settle=options["settle"],
                tolerance=options["tolerance"],
            )
        except InputValueError:
            if chosen is None:
                continue
            raise InputValueError(
                f"joint {joint} has no constant-velocity plateau longer than settle = "
                f"{options['settle']:g} s while the other joints rest (speed below "
                f"{options['rest_velocity']:g} rad/s); its largest steady speed alone is "
                f"{np.abs(solo[:, j]).max():.3g} rad/s"
            ) from None
        maps.append(table.assign(joint=joint))
        fits[joint] = {name: _fit_joint(joint, name, table) for name in names}
    if not maps:
        raise InputValueError(
            "no constant-velocity plateau found: joints move, but none alone "
            f"at a constant velocity (tolerance {options['tolerance']:g}) for longer than settle = "
            f"{options['settle']:g} s while the others rest"
        )
    columns = ["joint", "velocity", "torque", "torque_std", "n_samples"]
    return FrictionIdentification(
        maps=pd.concat(maps, ignore_index=True)[columns],
        fits=fits,
        torque=torque,
        settle=options["settle"],
        tolerance=options["tolerance"],
        rest_velocity=options["rest_velocity"],
        max_acceleration=options["max_acceleration"],
        window=options["window"],
    )


def _solo_velocities(log: Log, options: dict[str, float]) -> FloatArray:
    """Velocity [rad/s] of each joint where it alone moves steadily, 0 elsewhere."""
    dt = _uniform_period(log.t)
    qd, qdd = savgol_derivatives(log.q, dt, options["window"])
    moving = np.abs(qd) > options["rest_velocity"]
    if not moving.any():
        raise InputValueError(
            f"the robot stands still in this log: every joint speed stays below "
            f"rest_velocity = {options['rest_velocity']:g} rad/s (largest "
            f"{np.abs(qd).max():.3g} rad/s), so there is no constant-velocity plateau; "
            "friction needs each joint moved alone at constant velocities (VelocitySweep)"
        )
    alone = moving & (moving.sum(axis=1, keepdims=True) == 1)
    steady = alone & (np.abs(qdd) <= options["max_acceleration"])
    return np.where(steady, qd, 0.0)


def _fit_joint(joint: int, name: str, table: pd.DataFrame) -> FrictionFit:
    try:
        return _FITTERS[name](table["velocity"].to_numpy(), table["torque"].to_numpy())
    except InputValueError as exc:
        raise InputValueError(f"joint {joint}, model {name!r}: {exc}") from None
