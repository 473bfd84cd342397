"""A nominal model's missing friction and torque offset, identified joint by joint from logs.

When a rigid-body model (a URDF) is right about inertia and gravity but
knows no friction, and the logs are too poor in excitation for the
inertial identification of :func:`~sensorless.identification.identify_from_logs`
(a few constant-velocity moves leave the base parameters ill-conditioned),
what the model lacks can still be identified joint by joint from its error

    e = τ_m − τ_model(q, q̇, q̈)   [N m],

with q̇ the measured velocity of the log (the one the observer uses) and q̈
from a zero-phase Savitzky–Golay fit of q
(:func:`~sensorless.identification.logs.savgol_derivatives`):

- a **torque offset** o_j: the median of e_j while joint j rests (|q̇_j|
  below ``resting`` for at least ``min_time`` seconds of the data; else 0).
  Friction models give 0 at rest, so an offset cannot live in them; it is
  taken off the measured torque instead (:meth:`NominalCorrection.apply`),
  before the observer sees it, as a live monitor would take it off the stream;
- **asymmetric Coulomb and viscous friction** (C+ ≥ 0, C− ≤ 0, F_v ≥ 0,
  :class:`~sensorless.friction.CoulombViscous`, whose module states the sign
  convention) by bounded least squares (:func:`scipy.optimize.lsq_linear`)
  on the moving samples of e_j − o_j. C+ ≠ −C− carries the offset of a
  joint that never rests. A direction in which the joint moved for less than
  ``min_time`` gets the mirror of the other one; a joint that never moved
  gets no friction.

Units SI and radians; time along axis 0, arrays of shape (n_samples, n_dof).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from scipy.optimize import lsq_linear

from .._validation import FloatArray, check_duration, check_scalar, per_joint
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..friction import CoulombViscous
from ..io import Log
from ..robots.model import RobotModel
from .logs import savgol_derivatives, window_samples

__all__ = ["NominalCorrection", "identify_correction", "model_error"]

DEFAULT_WINDOW = 0.1
"""Savitzky–Golay window [s] for q̈."""
DEFAULT_RESTING = 0.005
"""Speed [rad/s] below which a joint counts as resting."""
DEFAULT_MIN_TIME = 0.5
"""Data [s] a joint needs at rest (offset) or in one direction (its Coulomb level)."""


@dataclass(frozen=True)
class NominalCorrection:
    """What logs add to a rigid-body model: joint friction and a motor-torque offset.

    Parameters
    ----------
    friction : CoulombViscous
        Joint friction: C+ [N m], C− [N m], F_v [N m s/rad], shape (n_dof,).
    offset : float or array-like of shape (n_dof,)
        Offset of the measured motor torque [N m], taken off ``tau_m``;
        ``n_dof`` is the friction model's.

    Examples
    --------
    >>> correction = NominalCorrection(CoulombViscous(1.0, -1.0, 0.5), [0.2])
    >>> correction.to_pandas().round(2).to_numpy().tolist()
    [[1.0, -1.0, 0.5, 0.2]]
    """

    friction: CoulombViscous
    offset: FloatArray

    def __post_init__(self) -> None:
        if not isinstance(self.friction, CoulombViscous):
            raise InputTypeError(
                f"friction must be a CoulombViscous; got {type(self.friction).__name__}"
            )
        offset = per_joint(self.offset, self.friction.n_dof, "offset", "N m")
        offset.setflags(write=False)
        object.__setattr__(self, "offset", offset)

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return int(self.offset.size)

    def model(self, robot: RobotModel) -> RobotModel:
        """``robot`` with this friction in place of its own (rigid-body parameters unchanged).

        Parameters
        ----------
        robot : RobotModel
            The rigid-body model the correction was identified against.

        Returns
        -------
        RobotModel
            Named ``"<robot>+friction"``.
        """
        self._check_joints(_robot(robot).n_dof, f"robot {robot.name!r}")
        return robot.with_standard_parameters(
            robot.standard_parameters(), friction=self.friction, name=f"{robot.name}+friction"
        )

    def apply(self, log: Log) -> Log:
        """``log`` with the offset taken off its motor torques ``tau_m`` [N m].

        The offset is recorded in the metadata as ``tau_m_offset``.

        Raises
        ------
        InputValueError
            The log has no motor torques.
        DimensionError
            The log has another number of joints.
        """
        if not isinstance(log, Log):
            raise InputTypeError(f"log must be a Log; got {type(log).__name__}")
        self._check_joints(log.n_dof, "the log")
        if log.tau_m is None:
            raise InputValueError(
                f"the log has no motor torques tau_m to correct; its groups: {log.groups}"
            )
        metadata = {**log.metadata, "tau_m_offset": [float(v) for v in self.offset]}
        return dataclasses.replace(log, tau_m=log.tau_m - self.offset, metadata=metadata)

    def to_pandas(self) -> pd.DataFrame:
        """One row per joint (``joint`` from 1): C+, C− [N m], F_v [N m s/rad], offset [N m]."""
        return pd.DataFrame(
            {
                "C+ [N m]": self.friction.c_pos,
                "C- [N m]": self.friction.c_neg,
                "Fv [N m s/rad]": self.friction.fv,
                "offset [N m]": self.offset,
            },
            index=pd.Index(range(1, self.n_dof + 1), name="joint"),
        )

    def _check_joints(self, n_dof: int, what: str) -> None:
        if n_dof != self.n_dof:
            raise DimensionError(f"the correction has {self.n_dof} joints; {what} has {n_dof}")


def _robot(robot: Any) -> RobotModel:
    if not isinstance(robot, RobotModel):
        raise InputTypeError(f"robot must be a RobotModel; got {type(robot).__name__}")
    return robot


def _checked_logs(
    logs: Any, robot: RobotModel, window: float
) -> list[tuple[Log, FloatArray, FloatArray]]:
    """(log, q̇, τ_m) of every log: a non-empty sequence, each long enough for the window."""
    if isinstance(logs, Log) or not isinstance(logs, Sequence) or not logs:
        raise InputValueError(
            f"logs must be a non-empty sequence of Log; got {type(logs).__name__}"
        )
    checked = []
    for index, log in enumerate(logs):
        if not isinstance(log, Log):
            raise InputTypeError(f"logs[{index}] must be a Log; got {type(log).__name__}")
        if log.n_dof != robot.n_dof:
            raise DimensionError(
                f"logs[{index}] has {log.n_dof} joints; robot {robot.name!r} has {robot.n_dof}"
            )
        if log.qd is None or log.tau_m is None:
            raise InputValueError(
                f"logs[{index}] must hold the measured velocity qd and the motor torque tau_m; "
                f"its groups: {log.groups}"
            )
        samples = window_samples(log.dt, window)
        if log.n_samples <= samples:
            raise InputValueError(
                f"logs[{index}] has {log.n_samples} samples; the {window} s window needs "
                f"more than {samples}"
            )
        checked.append((log, log.qd, log.tau_m))
    return checked


def model_error(
    logs: Sequence[Log], robot: RobotModel, *, window: float = DEFAULT_WINDOW
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """The rigid-body model's error on logs, stacked: e = τ_m − τ_model(q, q̇, q̈).

    Half a Savitzky–Golay window at each end of every log is dropped (the
    fit extrapolates there).

    Parameters
    ----------
    logs : sequence of Log
        Runs with joint positions ``q`` [rad], measured velocities ``qd``
        [rad/s] and motor torques ``tau_m`` [N m], time along axis 0.
    robot : RobotModel
        Rigid-body model; its friction, if any, is not used
        (:meth:`~sensorless.robots.RobotModel.inverse_dynamics`).
    window : float
        Savitzky–Golay window [s] (cubic fit) for q̈.

    Returns
    -------
    error : ndarray of shape (n_kept, n_dof)
        τ_m − τ_model [N m].
    velocity : ndarray of shape (n_kept, n_dof)
        The measured q̇ [rad/s] at the same samples.
    period : ndarray of shape (n_kept,)
        Sample period [s] of the log each sample comes from.
    """
    checked = _robot(robot)
    span = check_scalar(window, "window", "s")
    errors, velocities, periods = [], [], []
    for log, qd, tau_m in _checked_logs(logs, checked, span):
        _, qdd = savgol_derivatives(log.q, log.dt, span)
        half = window_samples(log.dt, span) // 2
        keep = slice(half, log.n_samples - half)
        tau = checked.inverse_dynamics(log.q[keep], qd[keep], qdd[keep])
        errors.append(tau_m[keep] - tau)
        velocities.append(qd[keep])
        periods.append(np.full(tau.shape[0], log.dt))
    return np.concatenate(errors), np.concatenate(velocities), np.concatenate(periods)


def identify_correction(
    logs: Sequence[Log],
    robot: RobotModel,
    *,
    window: float = DEFAULT_WINDOW,
    resting: float = DEFAULT_RESTING,
    min_time: float = DEFAULT_MIN_TIME,
) -> NominalCorrection:
    """Torque offset and asymmetric Coulomb + viscous friction per joint (module docstring).

    Parameters
    ----------
    logs : sequence of Log
        Collision-free runs with ``q`` [rad], measured ``qd`` [rad/s] and
        ``tau_m`` [N m], time along axis 0, of shape (n_samples, n_dof).
    robot : RobotModel
        The rigid-body model to correct (its own friction is ignored and
        replaced by :meth:`NominalCorrection.model`).
    window : float
        Savitzky–Golay window [s] for q̈.
    resting : float
        Speed [rad/s] below which a joint rests; at or above it, it moves.
    min_time : float
        Time [s] a joint must rest to get an offset, or move in one
        direction to get that direction's Coulomb level.

    Returns
    -------
    NominalCorrection

    Raises
    ------
    InputValueError
        No logs, a log without ``qd`` or ``tau_m`` or shorter than the window,
        or a setting that is not a positive number of its unit.
    DimensionError
        A log's joints differ from the robot's.

    Examples
    --------
    A joint that never rests: its offset (0.5 N m here) shows as C+ ≠ −C−.

    >>> import sensorless as sl
    >>> robot = sl.robots.load("ur10")
    >>> t = np.arange(0.0, 8.0, 0.01)
    >>> q = np.outer(0.5 * np.sin(np.pi / 2 * t), np.ones(6))
    >>> qd = np.gradient(q, t, axis=0)
    >>> friction = CoulombViscous([2.0] * 6, [-2.0] * 6, [1.0] * 6)
    >>> qdd = np.gradient(qd, t, axis=0)
    >>> tau = robot.inverse_dynamics(q, qd, qdd) + friction.torque(qd) + 0.5
    >>> log = Log(t, q, qd=qd, tau_m=tau)
    >>> identify_correction([log], robot).to_pandas().round(1).loc[1].tolist()
    [2.5, -1.5, 1.0, 0.0]
    """
    checked = _robot(robot)
    span = check_scalar(window, "window", "s")
    speed = check_scalar(resting, "resting", "rad/s")
    needed = check_duration(min_time, "min_time")
    error, velocity, period = model_error(logs, checked, window=span)
    n_dof = checked.n_dof
    c_pos, c_neg, fv, offset = (np.zeros(n_dof) for _ in range(4))
    for j in range(n_dof):
        e, v = error[:, j], velocity[:, j]
        at_rest = np.abs(v) < speed
        if period[at_rest].sum() >= needed:
            offset[j] = np.median(e[at_rest])
        # The directions (+1, -1) the joint moved in long enough to show their Coulomb level.
        seen = {sign: sign * v >= speed for sign in (1, -1)}
        seen = {sign: mask for sign, mask in seen.items() if period[mask].sum() >= needed}
        if not seen:
            continue
        moving = np.abs(v) >= speed
        design = np.column_stack([*(mask[moving] for mask in seen.values()), v[moving]])
        lower = [0.0 if sign > 0 else -np.inf for sign in seen] + [0.0]
        upper = [np.inf if sign > 0 else 0.0 for sign in seen] + [np.inf]
        fit = lsq_linear(design.astype(float), e[moving] - offset[j], bounds=(lower, upper))
        level = dict(zip(seen, fit.x[:-1], strict=True))
        c_pos[j] = level.get(1, -level.get(-1, 0.0))
        c_neg[j] = level.get(-1, -c_pos[j])
        fv[j] = fit.x[-1]
    return NominalCorrection(CoulombViscous(c_pos, c_neg, fv), offset)
