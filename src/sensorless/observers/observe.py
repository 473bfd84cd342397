"""Either observer over a whole :class:`~sensorless.io.Log`, with the default estimators.

Units and shapes as in :mod:`sensorless.observers`.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, check_dt
from ..exceptions import DimensionError, InputTypeError, InputValueError, LogFormatError
from ..filters import Butterworth, CausalEstimator, FiniteDifference
from ..io import Log
from ..robots.model import RobotModel
from ..signals import ObserverSignals
from ._common import _TIME_RTOL, OBSERVER_KINDS, VELOCITY_SOURCES, _check_robot
from .acceleration import AccelerationObserver
from .momentum import MomentumObserver

__all__ = ["default_estimator", "observe"]


# ---------------------------------------------------------------- convenience
def default_estimator(dt: float, kind: str = "motor") -> CausalEstimator:
    """The velocity/acceleration estimator :func:`observe` uses when none is given.

    * Momentum observers (``kind`` "motor" or "joint"): backward differences,
      :class:`~sensorless.filters.FiniteDifference`. The observer's own
      K_I/(s+K_I) already low-passes the momentum, while any delay d of q̂̇
      puts an error of about d·(dτ/dt) into the residual. On the PUMA 560
      benchmark (exact model, 1e-5 rad encoders, 0.02 N m torque noise,
      K_I = 20) the collision-free peak of joint 1 was 1.0 N m with backward
      differences, 4.7 N m with a 2nd-order 50-Hz Butterworth and 15 N m with
      the thesis's 5th-order 20-Hz one. With coarse encoders pass a filter.
    * The acceleration-based estimate needs q̂̈, which differentiation makes
      much noisier: the thesis's 5th-order Butterworth at 20 Hz (§ 3.6;
      velocity delay ≈ 26 ms at 1 kHz), its cutoff lowered to 0.25/dt [Hz]
      (half the Nyquist frequency) for slow sampling.

    Parameters
    ----------
    dt : float
        Sample period [s].
    kind : {"motor", "joint", "acceleration"}
        Observer the estimator is for.

    Returns
    -------
    CausalEstimator

    Examples
    --------
    >>> default_estimator(1e-3, "motor")
    FiniteDifference(dt=0.001)
    >>> default_estimator(1e-3, "acceleration")
    Butterworth(dt=0.001, cutoff=20.0, order=5)
    """
    period = check_dt(dt)
    if _check_observer_kind(kind) == "acceleration":
        return Butterworth(period, cutoff=min(20.0, 0.25 / period), order=5)
    return FiniteDifference(period)


def _check_observer_kind(kind: Any) -> str:
    if kind not in OBSERVER_KINDS:
        raise InputValueError(
            f"kind must be one of {list(OBSERVER_KINDS)} (momentum residual with motor "
            f"torques, with joint-torque sensors, or the acceleration-based estimate); "
            f"got {kind!r}"
        )
    return str(kind)


def _log_torque(log: Log, kind: str) -> FloatArray:
    group = "tau_j" if kind == "joint" else "tau_m"
    values = getattr(log, group)
    if values is None:
        meaning = "joint-torque-sensor" if group == "tau_j" else "motor"
        raise LogFormatError(
            f"kind={kind!r} needs the {meaning} torques {group}_1..{group}_{log.n_dof}; "
            f"the log has no {group} columns (present groups: {log.groups})"
        )
    return np.asarray(values)


def observe(
    log: Log,
    robot: RobotModel,
    *,
    kind: str = "motor",
    gain: ArrayLike = 20.0,
    velocity: str = "auto",
    estimator: CausalEstimator | None = None,
    friction: Any = "model",
) -> ObserverSignals:
    """Run an observer over a log.

    Parameters
    ----------
    log : Log
        The run; its time column must be regular.
    robot : RobotModel
        Nominal model (link-side for ``kind="joint"``, see :class:`MomentumObserver`).
    kind : {"motor", "joint", "acceleration"}
        ``"motor"``: r̂ (eq. 4.4) from ``log.tau_m``; ``"joint"``: r̂_s (eq. 4.9)
        from ``log.tau_j``; ``"acceleration"``: τ̂_c (eq. 3.16) from ``log.tau_m``.
    gain : float or array-like of shape (n_dof,)
        K_I [1/s] of the momentum observers (ignored by ``"acceleration"``).
    velocity : {"auto", "measured", "filter", "true"}
        Joint velocity of the momentum observers: ``"measured"`` is the
        recorded ``log.qd`` (real arms log it); ``"filter"`` estimates it from
        ``log.q`` with ``estimator``; ``"auto"`` takes ``log.qd`` when the log
        has it and the estimate otherwise; ``"true"`` uses the simulator's
        ground truth ``log.qd_true`` (ideal studies and tests). The choice is
        recorded in ``metadata["observer"]["velocity"]``. The acceleration-based
        estimate always uses ``estimator``.
    estimator : CausalEstimator, optional
        Causal velocity/acceleration estimator with ``dt`` = the log's period;
        default :func:`default_estimator` (backward differences for the momentum
        observers, the thesis's 5th-order 20-Hz Butterworth for ``"acceleration"``).
    friction : "model", None, FrictionModel or LuGre
        Nominal friction, see :class:`MomentumObserver`.

    Returns
    -------
    ObserverSignals
        ``position`` is ``log.q``; ``metadata`` holds the log's metadata plus
        the settings under the key ``"observer"``.

    Raises
    ------
    DimensionError
        The robot and the log have different joint counts.
    LogFormatError
        A needed column group (tau_m, tau_j, qd_true) is absent.
    InputValueError
        Unknown ``kind`` or ``velocity``, or an estimator of another period.
    """
    if not isinstance(log, Log):
        raise InputTypeError(f"log must be a sensorless.io.Log; got {type(log).__name__}")
    robot = _check_robot(robot)
    if robot.n_dof != log.n_dof:
        raise DimensionError(
            f"robot has {robot.n_dof} joints, log has {log.n_dof} (robot {robot.name!r})"
        )
    kind = _check_observer_kind(kind)
    if velocity not in VELOCITY_SOURCES:
        raise InputValueError(
            f"velocity must be one of {list(VELOCITY_SOURCES)} (the log's measured qd, an "
            f"estimate from q, or the ground-truth qd_true); got {velocity!r}"
        )
    if kind == "acceleration" and velocity in ("true", "measured"):
        raise InputValueError(
            f"velocity={velocity!r} applies to the momentum observers (kind 'motor' or "
            "'joint'); the acceleration-based estimate takes velocity and acceleration from "
            "q with its estimator: use velocity='filter'"
        )
    if velocity == "auto":
        velocity = "measured" if kind != "acceleration" and log.qd is not None else "filter"
    if velocity == "measured" and log.qd is None:
        raise LogFormatError(
            f"velocity='measured' needs the measured velocities qd_1..qd_{log.n_dof}; the "
            f"log has none (present groups: {log.groups}). Use velocity='filter'"
        )
    tau = _log_torque(log, kind)
    dt = log.dt
    settings: dict[str, Any] = {"velocity": velocity}
    if velocity == "filter" or kind == "acceleration":
        if estimator is None:
            estimator = default_estimator(dt, kind)
        elif not isinstance(estimator, CausalEstimator):
            raise InputTypeError(
                "estimator must be a causal estimator of sensorless.filters; got "
                f"{type(estimator).__name__}"
            )
        if not math.isclose(estimator.dt, dt, rel_tol=_TIME_RTOL):
            raise InputValueError(
                f"estimator has dt = {estimator.dt:g} s but the log is sampled every "
                f"{dt:g} s; build the estimator with dt = log.dt"
            )
        settings["estimator"] = repr(estimator)

    if kind == "acceleration":
        assert estimator is not None  # set above
        observer = AccelerationObserver(robot, estimator, friction=friction, torque="motor")
        signals, _ = observer.run(log.t, log.q, tau)
        settings |= observer.settings()
    else:
        if velocity == "true":
            if log.qd_true is None:
                raise LogFormatError(
                    "velocity='true' needs the ground-truth velocities qd_true_1..qd_true_"
                    f"{log.n_dof}; the log has none (present groups: {log.groups}). Use "
                    "velocity='filter'"
                )
            qd = np.asarray(log.qd_true)
        elif velocity == "measured":
            qd = np.asarray(log.qd)
        else:
            assert estimator is not None  # set above
            qd = estimator.filter(log.q)[0].velocity
        momentum = MomentumObserver(robot, dt, gain, friction=friction, torque=kind)
        signals, _ = momentum.run(log.t, log.q, qd, tau)
        settings |= momentum.settings()
    metadata = dict(log.metadata)
    metadata["observer"] = settings
    return dataclasses.replace(signals, metadata=metadata)
