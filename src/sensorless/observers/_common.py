"""What both observers share: kinds, the output of one sample, checks and the nominal model.

Units and shapes as in :mod:`sensorless.observers`.
"""

from __future__ import annotations

import abc
import math
from typing import Any, ClassVar, NamedTuple

import numpy as np
from numpy.typing import ArrayLike

from .._validation import (
    FloatArray,
    as_joint_array,
    check_finite,
    check_type,
    first_irregular_step,
)
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..friction import FrictionModel, LuGre, Stribeck
from ..robots.model import RobotModel

__all__ = ["OBSERVER_KINDS", "TORQUE_KINDS", "VELOCITY_SOURCES", "ObserverSample"]

TORQUE_KINDS: tuple[str, ...] = ("motor", "joint")
"""Torque a momentum observer uses: motor torques τ_m (r̂, eq. 4.4) or joint-torque sensors (r̂_s)."""

OBSERVER_KINDS: tuple[str, ...] = ("motor", "joint", "acceleration")
"""Observers :func:`observe` can run."""

VELOCITY_SOURCES: tuple[str, ...] = ("auto", "measured", "filter", "true")
"""Where :func:`observe` takes the joint velocity from."""

# Relative tolerance on the sample period of a time column (that of sensorless.io).
_TIME_RTOL = 1e-6
# Samples per block in ``MomentumObserver.run``: bounds the memory of the
# per-sample Coriolis matrices (block x n_dof² floats) without slowing the loop.
_BLOCK = 8192
# Signals filtered by K_I/(s+K_I), in the order of ``ObserverState.filtered``.
_RESIDUAL, _MODEL_TORQUE, _FRICTION, _SIGN = range(4)


class ObserverSample(NamedTuple):
    """Output of an observer at one sample, each of shape (n_dof,).

    Attributes
    ----------
    residual : ndarray
        r̂ (eq. 4.4), r̂_s (eq. 4.9) or τ̂_c (eq. 3.16) [N m].
    model_torque : ndarray
        h = K_I/(s+K_I)·(M q̈ + C q̇ + g) (eq. 4.26), or M q̂̈ + C q̂̇ + g for the
        acceleration-based estimate [N m].
    friction : ndarray
        K_I/(s+K_I)·τ̂_fr (eq. 5.29), or τ̂_fr(q̂̇) for the acceleration-based estimate [N m].
    sign : ndarray
        K_I/(s+K_I)·sign(q̇) (eq. 5.39), or sign(q̂̇) [-].
    """

    residual: FloatArray
    model_torque: FloatArray
    friction: FloatArray
    sign: FloatArray


# ---------------------------------------------------------------- shared helpers
def _check_robot(robot: Any) -> RobotModel:
    return check_type(robot, RobotModel, "robot", " (e.g. sensorless.robots.load('panda'))")


def _check_torque_kind(torque: Any) -> str:
    if torque not in TORQUE_KINDS:
        raise InputValueError(
            f"torque must be one of {list(TORQUE_KINDS)} (motor torques τ_m, eq. 4.4, or "
            f"joint-torque-sensor torques τ_J, eq. 4.9); got {torque!r}"
        )
    return str(torque)


def _check_gain(gain: Any, n_dof: int) -> FloatArray:
    """Observer gain K_I [1/s] as an array of shape (n_dof,), positive and finite."""
    try:
        arr = np.array(gain, dtype=np.float64)
    except (TypeError, ValueError):
        raise InputValueError(
            f"gain K_I must be a positive number [1/s] or an array of shape ({n_dof},); "
            f"got {gain!r}"
        ) from None
    if arr.ndim > 1 or (arr.ndim == 1 and arr.shape[0] != n_dof):
        raise DimensionError(
            f"gain K_I must be a scalar or have shape ({n_dof},) for a robot with {n_dof} "
            f"joints; got shape {arr.shape}"
        )
    arr = np.broadcast_to(arr, (n_dof,)).copy()
    if not np.isfinite(arr).all() or (arr <= 0.0).any():
        raise InputValueError(
            f"gain K_I must be positive and finite [1/s] on every joint; got {arr}"
        )
    arr.setflags(write=False)
    return arr


def _resolve_friction(friction: Any, robot: RobotModel) -> FrictionModel | None:
    """The nominal friction model τ̂_fr(q̇): stateless, LuGre replaced by its steady state."""
    if isinstance(friction, str):
        if friction != "model":
            raise InputValueError(
                "friction must be 'model' (the robot's own friction), None, a FrictionModel "
                f"or a LuGre model; got {friction!r}"
            )
        friction = robot.friction
    if friction is None:
        return None
    if isinstance(friction, LuGre):
        # Steady state of eq. (4.22): the Stribeck curve with fv = σ2 (LuGre.steady_state).
        friction = Stribeck(
            fc=friction.fc, fs=friction.fs, vs=friction.vs, fv=friction.sigma2,
            delta=friction.delta,
        )  # fmt: skip
    if not isinstance(friction, FrictionModel):
        raise InputTypeError(
            "friction must be 'model', None, a sensorless.friction.FrictionModel or LuGre; "
            f"got {type(friction).__name__}"
        )
    if friction.n_dof not in (1, robot.n_dof):
        raise DimensionError(
            f"friction model has {friction.n_dof} joints; the robot has {robot.n_dof}"
        )
    return friction


def _friction_name(friction: FrictionModel | None) -> str:
    return "none" if friction is None else type(friction).__name__


def _check_time(t: ArrayLike, n_samples: int, dt: float) -> FloatArray:
    """Time column [s] of ``n_samples`` samples spaced by ``dt`` (relative tolerance 1e-6)."""
    arr = np.asarray(t, dtype=np.float64)
    if arr.shape != (n_samples,):
        raise DimensionError(
            f"t must have shape (n_samples,) = ({n_samples},), one time stamp per row of q; "
            f"got shape {arr.shape}"
        )
    check_finite(arr, "t")
    k = first_irregular_step(arr, dt, _TIME_RTOL) if n_samples > 1 else None
    if k is not None:
        raise InputValueError(
            f"t must be sampled every dt = {dt:g} s (the observer's period); the step from "
            f"sample {k} to {k + 1} is {arr[k + 1] - arr[k]:.9g} s. Build the observer with the "
            "log's period, or resample the log with sensorless.io.resample(log, dt)"
        )
    return arr


def _series(x: ArrayLike, n_dof: int, name: str, n_samples: int | None = None) -> FloatArray:
    """A checked, C-contiguous array of shape (n_samples, n_dof) (NaN named by sample)."""
    arr, single = as_joint_array(x, n_dof, name)
    if single:
        raise DimensionError(
            f"{name} must have shape (n_samples, {n_dof}); got shape {np.shape(x)}; "
            "use step for one sample"
        )
    if n_samples is not None and arr.shape[0] != n_samples:
        raise DimensionError(f"{name} must have {n_samples} samples, as q; got shape {arr.shape}")
    return np.ascontiguousarray(arr)


def _one_sample(x: ArrayLike, n_dof: int, name: str) -> FloatArray:
    """One checked sample as an array of shape (1, n_dof)."""
    arr, single = as_joint_array(x, n_dof, name)
    if not single:
        raise DimensionError(
            f"{name} must be one sample of shape ({n_dof},); got shape {np.shape(x)}"
        )
    return np.ascontiguousarray(arr)


def _sample(x: ArrayLike, n_dof: int, name: str) -> FloatArray:
    """One sample of shape (n_dof,): the cheap check of the streaming path."""
    try:
        arr = np.ascontiguousarray(x, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise DimensionError(
            f"{name} must be a numeric array of shape ({n_dof},); could not convert it: {exc}"
        ) from None
    if arr.shape != (n_dof,):
        raise DimensionError(
            f"{name} must be one sample of shape ({n_dof},); got shape {arr.shape}"
        )
    return arr


def _check_sample_finite(**arrays: FloatArray) -> None:
    """Raise :class:`InputValueError` naming the first array with a NaN or inf."""
    for name, arr in arrays.items():
        if not np.isfinite(arr).all():
            joint = int(np.flatnonzero(~np.isfinite(arr))[0])
            raise InputValueError(f"{name} must be finite; found {arr[joint]} at joint {joint}")


class _FrictionFunction:
    """τ̂_fr(q̇) [N m] of a stateless model without input checks (zeros without a model)."""

    __slots__ = ("_model",)

    def __init__(self, model: FrictionModel | None) -> None:
        self._model = model

    def __call__(self, qd: FloatArray) -> FloatArray:
        if self._model is None:
            return np.zeros(qd.shape, dtype=qd.dtype)
        # Per-joint parameters of shape (n_dof,) or (1,) broadcast against qd.
        return self._model.evaluate(qd)


# ---------------------------------------------------------------- momentum observer
class _NominalObserver(abc.ABC):
    """What both observers share: the nominal model, its friction and the torque kind."""

    _family: ClassVar[str]
    """The observer's name in :meth:`settings`."""

    def __init__(self, robot: RobotModel, friction: Any, torque: str) -> None:
        self._robot = _check_robot(robot)
        self._torque = _check_torque_kind(torque)
        self._friction_model = _resolve_friction(friction, robot)
        self._friction = _FrictionFunction(self._friction_model)
        self._pin_model = robot.pinocchio_model
        self._pin_data = robot.pinocchio_model.createData()

    @property
    def robot(self) -> RobotModel:
        """Nominal model."""
        return self._robot

    @property
    def torque(self) -> str:
        """``"motor"`` (τ_m, eq. 4.4) or ``"joint"`` (τ_J, eq. 4.9): which torque τ is used."""
        return self._torque

    @property
    def friction_model(self) -> FrictionModel | None:
        """Nominal friction τ̂_fr actually used (a LuGre model appears as its Stribeck curve)."""
        return self._friction_model

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return self.robot.n_dof

    @property
    @abc.abstractmethod
    def dt(self) -> float:
        """Sample period [s]."""

    @abc.abstractmethod
    def _settings(self) -> dict[str, Any]:
        """The settings of the family (its period ``dt`` last), as plain data."""

    @abc.abstractmethod
    def _repr_parameters(self) -> str:
        """What sets this observer apart in its ``repr``, e.g. ``"dt=0.001, gain=[20.0]"``."""

    def __repr__(self) -> str:
        return (
            f"{type(self).__name__}(robot={self.robot.name!r}, {self._repr_parameters()}, "
            f"friction={_friction_name(self.friction_model)}, torque={self.torque!r})"
        )

    # ------------------------------------------------------------ input checks
    def _first_sample(self, x: ArrayLike, name: str) -> FloatArray:
        """The sample of ``initial_state``, checked, as an array of shape (1, n_dof)."""
        return _one_sample(x, self.n_dof, name)

    def _step_inputs(self, **values: ArrayLike) -> list[FloatArray]:
        """The inputs of ``step``: finite, C-contiguous arrays of shape (n_dof,)."""
        n = self.n_dof
        arrays = [_sample(value, n, name) for name, value in values.items()]
        # Dot products propagate NaN/inf and cost less than isfinite on each array;
        # only then look for the culprit (a huge but finite value merely overflows).
        total = 0.0
        for arr in arrays:
            total += float(arr @ arr)
        if not math.isfinite(total):
            _check_sample_finite(**dict(zip(values, arrays, strict=True)))
        return arrays

    def _run_inputs(
        self, t: ArrayLike, started: bool, **series: ArrayLike
    ) -> tuple[FloatArray, list[FloatArray]]:
        """The inputs of ``run``: time [s] spaced by ``dt`` and series of one length.

        ``series`` start with ``q``, whose length the others must have; without
        a state (``started`` False) a run needs at least one sample to start at.
        """
        n = self.n_dof
        arrays: list[FloatArray] = []
        for name, value in series.items():
            arrays.append(_series(value, n, name, arrays[0].shape[0] if arrays else None))
        n_samples = arrays[0].shape[0]
        t_arr = _check_time(t, n_samples, self.dt)
        if not started and n_samples == 0:
            raise DimensionError(
                "q has no samples; pass a state to process an empty chunk, or at least one "
                "sample to start at q[0]"
            )
        return t_arr, arrays

    def settings(self) -> dict[str, Any]:
        """The observer's settings as plain data (for metadata)."""
        return {
            "observer": self._family,
            "torque": self.torque,
            **self._settings(),
            "friction": _friction_name(self.friction_model),
            "robot": self.robot.name,
        }
