"""Friction of every joint from a constant-velocity sweep log (thesis §2.4.1-2.4.2).

:func:`identify_friction` estimates the velocity from the measured
positions, keeps the samples where one joint alone moves steadily, builds
each joint's steady-state map and fits the static models to it.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike

from .._validation import FloatArray, check_scalar, check_type
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..io import Log
from ..robots.model import RobotModel
from ._friction_map import steady_state_map, uniform_period
from ._friction_models import FITTERS, FrictionFit
from ._friction_result import FrictionIdentification
from .logs import savgol_derivatives

__all__ = ["identify_friction"]

_TORQUE_GROUPS = {"motor": "tau_m", "joint": "tau_j"}


def _check_models(models: str | tuple[str, ...] | list[str]) -> tuple[str, ...]:
    names = (models,) if isinstance(models, str) else tuple(models)
    unknown = [name for name in names if name not in FITTERS]
    if not names or unknown:
        raise InputValueError(
            f"models must be a non-empty sequence of {sorted(FITTERS)}; got {models!r}"
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
    _check_log_and_robot(log, robot)
    settle = check_scalar(settle, "settle", "s", "nonnegative")
    tolerance = check_scalar(tolerance, "tolerance", "-")
    rest_velocity = check_scalar(rest_velocity, "rest_velocity", "rad/s")
    max_acceleration = check_scalar(max_acceleration, "max_acceleration", "rad/s^2")
    window = check_scalar(window, "window", "s")
    names = _check_models(models)
    chosen = _check_sweep_joints(joints, robot.n_dof)
    friction = _friction_torque(log, robot, torque)
    solo = _solo_velocities(log, rest_velocity, max_acceleration, window)
    candidates = chosen or tuple(int(j) + 1 for j in np.flatnonzero(solo.any(axis=0)))
    maps, fits = [], {}
    for joint in candidates:
        j = joint - 1
        try:
            table = steady_state_map(
                log.t, solo[:, j], friction[:, j], settle=settle, tolerance=tolerance
            )
        except InputValueError:
            if chosen is None:
                continue
            raise InputValueError(
                f"joint {joint} has no constant-velocity plateau longer than settle = "
                f"{settle:g} s while the other joints rest (speed below {rest_velocity:g} "
                f"rad/s); its largest steady speed alone is {np.abs(solo[:, j]).max():.3g} rad/s"
            ) from None
        maps.append(table.assign(joint=joint))
        fits[joint] = {name: _fit_joint(joint, name, table) for name in names}
    if not maps:
        raise InputValueError(
            "no constant-velocity plateau found: joints move, but none alone "
            f"at a constant velocity (tolerance {tolerance:g}) for longer than settle = "
            f"{settle:g} s while the others rest"
        )
    columns = ["joint", "velocity", "torque", "torque_std", "n_samples"]
    return FrictionIdentification(
        maps=pd.concat(maps, ignore_index=True)[columns],
        fits=fits,
        torque=torque,
        settle=settle,
        tolerance=tolerance,
        rest_velocity=rest_velocity,
        max_acceleration=max_acceleration,
        window=window,
    )


def _check_log_and_robot(log: Log, robot: RobotModel) -> None:
    if not isinstance(log, Log):
        raise InputTypeError(f"log must be a sensorless.io.Log; got {type(log).__name__}")
    check_type(robot, RobotModel, "robot")
    if log.n_dof != robot.n_dof:
        raise DimensionError(
            f"the log has {log.n_dof} joints (columns q_1..q_{log.n_dof}) but robot "
            f"{robot.name!r} has {robot.n_dof}; pass the model of the robot that made the log"
        )


def _solo_velocities(
    log: Log, rest_velocity: float, max_acceleration: float, window: float
) -> FloatArray:
    """Velocity [rad/s] of each joint where it alone moves steadily, 0 elsewhere."""
    qd, qdd = savgol_derivatives(log.q, uniform_period(log.t), window)
    moving = np.abs(qd) > rest_velocity
    if not moving.any():
        raise InputValueError(
            f"the robot stands still in this log: every joint speed stays below "
            f"rest_velocity = {rest_velocity:g} rad/s (largest "
            f"{np.abs(qd).max():.3g} rad/s), so there is no constant-velocity plateau; "
            "friction needs each joint moved alone at constant velocities (VelocitySweep)"
        )
    alone = moving & (moving.sum(axis=1, keepdims=True) == 1)
    steady = alone & (np.abs(qdd) <= max_acceleration)
    return np.where(steady, qd, 0.0)


def _fit_joint(joint: int, name: str, table: pd.DataFrame) -> FrictionFit:
    try:
        return FITTERS[name](table["velocity"].to_numpy(), table["torque"].to_numpy())
    except InputValueError as exc:
        raise InputValueError(f"joint {joint}, model {name!r}: {exc}") from None
