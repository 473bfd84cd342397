"""Dynamic LuGre parameters sigma0, sigma1 from presliding motion (Canudas de Wit et al. 1995).

The static part of LuGre comes from a Stribeck fit of the steady-state map
(:func:`~sensorless.identification.friction.fit_stribeck`);
:func:`fit_lugre_dynamic` adds the bristle stiffness and damping.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike
from scipy.optimize import least_squares

from .._validation import FloatArray
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..friction import LuGre, Stribeck
from ._friction_map import check_series, uniform_period
from ._friction_models import FrictionFit, fit_from_residuals

__all__ = ["fit_lugre_dynamic"]


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
        Static friction of the joint (one joint), e.g. from
        :func:`~sensorless.identification.friction.fit_stribeck`.

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
    t_arr, q_arr, tau_arr = check_series(("t", "q", "tau"), t, q, tau, minimum=3)
    dt = uniform_period(t_arr)
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
    return fit_from_residuals(model, {"sigma0": sigma0, "sigma1": sigma1}, residual(solution.x))
