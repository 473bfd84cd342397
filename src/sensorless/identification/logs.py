"""Inertial identification from recorded logs (eq. 2.12–2.13 on measured data).

A log holds joint positions and torques only; the velocities and
accelerations the regressor needs come from a zero-phase Savitzky–Golay
fit of the positions (offline, no delay), as the band-pass differentiation
that Swevers et al. recommend. Samples within half a window of each log's
ends are dropped (the fit there is an extrapolation).
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .._validation import FloatArray
from ..exceptions import DimensionError, InputValueError
from ..filters import SavitzkyGolay
from ..io import Log
from ..robots.base_parameters import BaseParameters
from ..robots.model import RobotModel
from .regression import RegressionResult, identify_base_parameters

__all__ = ["identify_from_logs", "savgol_derivatives"]


def savgol_derivatives(q: FloatArray, dt: float, window: float) -> tuple[FloatArray, FloatArray]:
    """Zero-phase q̇ [rad/s] and q̈ [rad/s²] of ``q`` [rad], shape (n_samples, n_dof).

    A cubic Savitzky–Golay fit over the odd number of samples (at least 5)
    closest to ``window`` [s] at the sample period ``dt`` [s].
    """
    _, qd, qdd = SavitzkyGolay(dt, window_samples(dt, window), polyorder=3).filter(q)
    return qd, qdd


def window_samples(dt: float, window: float) -> int:
    """Odd number of samples (>= 5) closest to ``window`` [s] at period ``dt`` [s]."""
    return max(5, 2 * round(window / dt / 2.0) + 1)


def identify_from_logs(
    logs: Sequence[Log],
    robot: RobotModel,
    *,
    torque: str = "motor",
    zero: Sequence[str] = (),
    friction: str | None = "coulomb_viscous",
    window: float = 0.05,
) -> tuple[BaseParameters, RegressionResult]:
    """Base inertial and friction parameters from logs of a moving robot.

    Parameters
    ----------
    logs : sequence of Log
        Runs of the robot (time along axis 0, positions [rad], torques [N m]).
    robot : RobotModel
        Kinematics of the robot (its inertial values are not used).
    torque : {"motor", "joint"}
        Regress the motor torques ``tau_m`` (rigid model, eq. 2.11) or the
        joint-torque-sensor readings ``tau_j`` (link side, eq. 2.12 without the
        small D K⁻¹ τ̇_J term).
    zero : sequence of str
        Standard parameters known to be zero (see :func:`base_parameters`).
    friction : {"coulomb_viscous", None}
        Friction columns (see :func:`identify_base_parameters`).
    window : float
        Savitzky–Golay window [s] (cubic fit) for q̇ and q̈.

    Returns
    -------
    base : BaseParameters
    result : RegressionResult
    """
    if torque not in ("motor", "joint"):
        raise InputValueError(f"torque must be 'motor' or 'joint'; got {torque!r}")
    if not logs:
        raise InputValueError("give at least one log")
    parts: list[list[np.ndarray]] = [[], [], [], []]
    for index, log in enumerate(logs):
        if log.n_dof != robot.n_dof:
            raise DimensionError(
                f"log {index} has {log.n_dof} joints; robot {robot.name!r} has {robot.n_dof}"
            )
        tau = log.tau_m if torque == "motor" else log.tau_j
        if tau is None:
            raise InputValueError(
                f"log {index} has no {'motor torques' if torque == 'motor' else 'tau_j'}"
            )
        samples = window_samples(log.dt, window)
        if log.n_samples <= 2 * samples:
            raise InputValueError(
                f"log {index} has {log.n_samples} samples; the {window} s window needs "
                f"more than {2 * samples}"
            )
        qd, qdd = savgol_derivatives(log.q, log.dt, window)
        keep = slice(samples // 2, log.n_samples - samples // 2)
        for store, values in zip(parts, (log.q, qd, qdd, tau), strict=True):
            store.append(np.asarray(values)[keep])
    q, qd, qdd, tau_all = (np.concatenate(store) for store in parts)
    if np.ptp(q, axis=0).max() < 1e-6:
        raise InputValueError(
            "the logs show no motion (joint positions vary by less than 1e-6 rad): "
            "a robot standing still does not excite its dynamics"
        )
    return identify_base_parameters(robot, q, qd, qdd, tau_all, zero=zero, friction=friction)
