"""Steady-state friction map from constant-velocity motion of one joint (thesis §2.4.1).

:func:`sweep_velocities` gives the velocities of the experiment and
:func:`steady_state_map` turns a log of one joint into the map of Fig. 2.2:
mean friction torque per constant-velocity plateau. The checks of the
one-joint series (:func:`check_series`, :func:`uniform_period`) are shared by
the other friction modules of this package.
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from .._validation import (
    FloatArray,
    as_float_array,
    check_finite,
    check_increasing,
    check_scalar,
)
from ..exceptions import DimensionError, InputValueError
from ..trajectories.sweeps import sweep_velocities

__all__ = ["steady_state_map", "sweep_velocities"]

# The experiment's velocities belong to the trajectory that makes them; re-exported here.


def _series(x: ArrayLike, name: str) -> FloatArray:
    arr = as_float_array(x, name, "(n_samples,)")
    if arr.ndim != 1:
        raise DimensionError(f"{name} must have shape (n_samples,); got shape {arr.shape}")
    check_finite(arr, name)
    return arr


def check_series(names: tuple[str, ...], *arrays: ArrayLike, minimum: int = 1) -> list[FloatArray]:
    """Check 1-D finite arrays of one common length (at least ``minimum`` samples).

    Parameters
    ----------
    names : tuple of str
        Name of each array, for the error messages.
    *arrays : array-like of shape (n_samples,)
        The series, in the order of ``names``.
    minimum : int, default 1
        Fewest samples accepted.

    Returns
    -------
    list of ndarray of shape (n_samples,)
        Float copies of the arrays.
    """
    out = [_series(a, n) for a, n in zip(arrays, names, strict=True)]
    lengths = {n: a.shape[0] for n, a in zip(names, out, strict=True)}
    if len(set(lengths.values())) != 1:
        raise DimensionError(f"{', '.join(names)} must have the same length; got {lengths}")
    if out[0].shape[0] < minimum:
        raise DimensionError(
            f"{', '.join(names)} need at least {minimum} samples; got {out[0].shape[0]}"
        )
    return out


def uniform_period(t: FloatArray) -> float:
    """The sample period [s] of the time stamps ``t`` [s], which must be uniform."""
    steps = np.diff(t)
    dt = float(np.median(steps))
    if dt <= 0.0 or not np.allclose(steps, dt, rtol=1e-6, atol=0.0):
        raise InputValueError(
            f"t must be uniformly sampled with a positive period; got periods from "
            f"{steps.min():.6g} to {steps.max():.6g} s (resample the log explicitly)"
        )
    return dt


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
    t_arr, qd_arr, tau_arr = check_series(("t", "qd", "tau"), t, qd, tau, minimum=2)
    check_increasing(t_arr, "the friction log")
    settle = check_scalar(settle, "settle", "s", "nonnegative")
    tolerance = check_scalar(tolerance, "tolerance", "-")
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
