"""Measurement models: encoders, motor-torque estimates and joint torque sensors.

A :class:`SensorModel` turns the true signals of a simulation into what a
controller reads (SPEC §8):

* position ``q`` [rad]: quantised to the encoder resolution, then white noise;
* motor torque ``tau_m`` [N m] (e.g. current times torque constant):
  ``(1 + eps) tau_m`` with a relative gain error ``eps``, then white noise;
* joint torque ``tau_j`` [N m] from a torque sensor: a play (backlash)
  operator of half-width ``w``, the hysteretic sensor error of thesis
  Fig. 5.11, then a constant bias, then white noise.

Every effect is off by default: ``SensorModel()`` is a perfect measurement
that returns its input unchanged and draws nothing from the random
generator. Every parameter is a scalar or a per-joint array of shape
``(n_dof,)``.

Randomness comes only from the :class:`numpy.random.Generator` passed to
each call. Each measurement draws at most one array of standard normal
numbers, of the shape of its input, and only when its noise is on
(quantisation, gain error, bias and play draw nothing). So a series measured
sample by sample gives the same numbers as the whole series at once with the
same generator. Sensors that share one generator share its stream: give each
sensor its own generator (``rng.spawn(3)``) when switching one noise on must
leave the noise of the others unchanged.

The play operator is the only state. It lives in an explicit
:class:`SensorState` that :meth:`SensorModel.measure_joint_torque` takes and
returns, as ``zi``/``zf`` in :func:`scipy.signal.lfilter`.

Examples
--------
>>> import numpy as np
>>> sensors = SensorModel(encoder_resolution=2 * np.pi / 2**17, torque_sensor_hysteresis=0.5)
>>> rng = np.random.default_rng(0)
>>> q_meas = sensors.measure_position([0.1, -0.2], rng)
>>> bool(np.all(np.abs(q_meas - [0.1, -0.2]) <= np.pi / 2**17))
True
>>> state = sensors.initial_state(2)
>>> reading, state = sensors.measure_joint_torque([[1.0, 0.2], [0.8, 0.0]], state, rng)
>>> reading
array([[0.5, 0. ],
       [0.5, 0. ]])
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_joint_array, joint_parameter
from ..exceptions import DimensionError, InputTypeError, InputValueError

__all__ = ["SensorModel", "SensorState"]

#: A per-joint parameter: a scalar for every joint or one value per joint.
PerJoint = float | Sequence[float] | FloatArray


def _bound(meaning: str, lower: float | None = 0.0, *, strict: bool = False) -> dict[str, Any]:
    """Metadata of a :class:`SensorModel` field: what it is (with unit) and its bound.

    The value must be ``> lower`` (``strict``) or ``>= lower``; ``lower=None``
    accepts any finite value.
    """
    return {"bound": (lower, strict, meaning)}


@dataclass(frozen=True, eq=False)
class SensorState:
    """State of the joint torque sensor: the play-operator output per joint.

    Parameters
    ----------
    torque_sensor_output : ndarray of shape (n_dof,)
        Last output of the play operator, before bias and noise [N m].
    """

    torque_sensor_output: FloatArray

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return int(self.torque_sensor_output.shape[0])


@dataclass(frozen=True)
class SensorModel:
    """Measurement model of position, motor torque and joint torque; perfect by default.

    Each parameter is a scalar or an array of shape ``(n_dof,)``; arrays are
    stored as tuples so that the model is immutable and comparable.

    Parameters
    ----------
    encoder_resolution : float or array-like of shape (n_dof,), default 0
        Quantisation step of the position reading [rad], ``>= 0``; 0 = none.
        E.g. ``2 * np.pi / 2**17`` for a 17-bit encoder on the joint.
    position_noise : float or array-like, default 0
        Standard deviation of white noise on the position [rad], ``>= 0``.
    motor_torque_noise : float or array-like, default 0
        Standard deviation of white noise on the motor torque [N m], ``>= 0``.
    motor_torque_gain_error : float or array-like, default 0
        Relative gain error ``eps`` [-], ``> -1``: the motor-torque reading is
        ``(1 + eps) tau_m`` (e.g. an error in the torque constant).
    torque_sensor_noise : float or array-like, default 0
        Standard deviation of white noise on the joint torque sensor [N m], ``>= 0``.
    torque_sensor_bias : float or array-like, default 0
        Constant offset of the joint torque sensor [N m].
    torque_sensor_hysteresis : float or array-like, default 0
        Half-width ``w`` of a play operator [N m], ``>= 0``: the reading ``y``
        follows the true torque ``x`` within ``±w``,
        ``y_k = min(max(y_{k-1}, x_k - w), x_k + w)``, which draws a loop of
        width ``2 w`` as the torque goes up and down (thesis Fig. 5.11).
    """

    encoder_resolution: PerJoint = field(default=0.0, metadata=_bound("quantisation step [rad]"))
    position_noise: PerJoint = field(default=0.0, metadata=_bound("standard deviation [rad]"))
    motor_torque_noise: PerJoint = field(default=0.0, metadata=_bound("standard deviation [N m]"))
    motor_torque_gain_error: PerJoint = field(
        default=0.0, metadata=_bound("relative gain error [-]; gain 1 + eps > 0", -1.0, strict=True)
    )
    torque_sensor_noise: PerJoint = field(default=0.0, metadata=_bound("standard deviation [N m]"))
    torque_sensor_bias: PerJoint = field(default=0.0, metadata=_bound("offset [N m]", None))
    torque_sensor_hysteresis: PerJoint = field(
        default=0.0, metadata=_bound("play half-width [N m]")
    )

    def __post_init__(self) -> None:
        for item in dataclasses.fields(self):
            value = _parameter(item.name, getattr(self, item.name), *item.metadata["bound"])
            object.__setattr__(self, item.name, value)

    # ------------------------------------------------------------------ construction
    @classmethod
    def perfect(cls) -> SensorModel:
        """The perfect measurement: every effect off."""
        return cls()

    @property
    def is_perfect(self) -> bool:
        """True when every effect is off (the readings equal the true signals)."""
        return all(not np.any(self._values(item.name)) for item in dataclasses.fields(self))

    @classmethod
    def from_dict(cls, values: Mapping[str, Any]) -> SensorModel:
        """Build a model from a mapping such as a YAML scenario section.

        Raises
        ------
        TypeError
            ``values`` is not a mapping or has a key that is not a field.
        """
        if not isinstance(values, Mapping):
            raise InputTypeError(
                f"SensorModel.from_dict expects a mapping; got {type(values).__name__}"
            )
        valid = [item.name for item in dataclasses.fields(cls)]
        unknown = sorted(str(key) for key in values if key not in valid)
        if unknown:
            raise InputTypeError(f"unknown SensorModel parameter(s) {unknown}; valid keys: {valid}")
        return cls(**values)

    def to_dict(self) -> dict[str, float | list[float]]:
        """All parameters as plain floats or lists of floats (YAML/JSON friendly)."""
        out: dict[str, float | list[float]] = {}
        for item in dataclasses.fields(self):
            value = getattr(self, item.name)
            out[item.name] = list(value) if isinstance(value, tuple) else float(value)
        return out

    def initial_state(self, n_dof: int, tau_j0: ArrayLike | None = None) -> SensorState:
        """State of the torque sensor before the first sample.

        Parameters
        ----------
        n_dof : int
            Number of joints.
        tau_j0 : array-like of shape (n_dof,), optional
            Initial play-operator output [N m]; default zeros. Starting at the
            initial true joint torque centres the play on it.

        Returns
        -------
        SensorState
        """
        if isinstance(n_dof, bool) or not isinstance(n_dof, int | np.integer) or n_dof < 1:
            raise InputValueError(f"n_dof must be a positive integer; got {n_dof!r}")
        if tau_j0 is None:
            return SensorState(np.zeros(int(n_dof)))
        start, single = as_joint_array(tau_j0, int(n_dof), "tau_j0")
        if not single:
            raise DimensionError(
                f"tau_j0 must be one sample of shape ({n_dof},); got shape {np.shape(tau_j0)}"
            )
        return SensorState(start[0].copy())

    # ------------------------------------------------------------------ measurements
    def measure_position(self, q: ArrayLike, rng: np.random.Generator | None = None) -> FloatArray:
        """Encoder reading: ``round(q / res) res`` then white noise.

        Parameters
        ----------
        q : array-like of shape (n_dof,) or (n_samples, n_dof)
            True joint positions [rad].
        rng : numpy.random.Generator, optional
            Source of noise; needed only when ``position_noise`` is on.

        Returns
        -------
        ndarray of the shape of ``q``
            Measured joint positions [rad].
        """
        values, single = _signal(q, "q")
        n_dof = values.shape[1]
        resolution = self._per_joint("encoder_resolution", n_dof)
        if np.any(resolution):
            step = np.where(resolution > 0.0, resolution, 1.0)
            values = np.where(resolution > 0.0, np.round(values / step) * step, values)
        return self._reading(values, "position_noise", rng, single)

    def position_parameters(self, n_dof: int) -> tuple[FloatArray, FloatArray]:
        """Encoder step [rad] and position-noise standard deviation [rad], each (n_dof,).

        What :meth:`position_reader` applies, for a compiled loop that reads
        the encoder itself (0 = no quantisation, no noise on that joint).
        """
        return (
            self._per_joint("encoder_resolution", n_dof).copy(),
            self._per_joint("position_noise", n_dof).copy(),
        )

    def position_reader(
        self, n_dof: int, rng: np.random.Generator | None = None
    ) -> Callable[[FloatArray], FloatArray]:
        """:meth:`measure_position` of one sample, with the checks done once, here.

        For a loop that reads the encoder at every sample (the simulator):
        the returned function takes a finite array of shape (n_dof,) [rad]
        and gives what ``measure_position(q, rng)`` gives, drawing the same
        numbers from ``rng``.
        """
        resolution = self._per_joint("encoder_resolution", n_dof)
        std = self._per_joint("position_noise", n_dof)
        noisy = bool(np.any(std))
        if noisy and not isinstance(rng, np.random.Generator):
            raise InputTypeError(
                "position_noise is on, so a numpy.random.Generator is needed "
                f"(numpy.random.default_rng(seed)); got rng={rng!r}"
            )
        quantised = bool(np.any(resolution))
        step = np.where(resolution > 0.0, resolution, 1.0)
        on = resolution > 0.0

        def read(q: FloatArray) -> FloatArray:
            values = np.where(on, np.round(q / step) * step, q) if quantised else q.copy()
            if noisy:
                assert rng is not None
                values = values + std * rng.standard_normal(n_dof)
            return values

        return read

    def measure_motor_torque(
        self, tau_m: ArrayLike, rng: np.random.Generator | None = None
    ) -> FloatArray:
        """Motor-torque estimate: ``(1 + eps) tau_m`` then white noise.

        Parameters
        ----------
        tau_m : array-like of shape (n_dof,) or (n_samples, n_dof)
            True motor torques, joint side [N m].
        rng : numpy.random.Generator, optional
            Source of noise; needed only when ``motor_torque_noise`` is on.

        Returns
        -------
        ndarray of the shape of ``tau_m``
            Measured motor torques [N m].
        """
        values, single = _signal(tau_m, "tau_m")
        gain_error = self._per_joint("motor_torque_gain_error", values.shape[1])
        if np.any(gain_error):
            values = (1.0 + gain_error) * values
        return self._reading(values, "motor_torque_noise", rng, single)

    def measure_joint_torque(
        self, tau_j: ArrayLike, state: SensorState, rng: np.random.Generator | None = None
    ) -> tuple[FloatArray, SensorState]:
        """Torque-sensor reading: play operator, then bias, then white noise.

        One sample is a step of the sensor; a series is the same steps in a
        loop, so a series cut into chunks with the state carried over gives
        the reading of the whole series.

        Parameters
        ----------
        tau_j : array-like of shape (n_dof,) or (n_samples, n_dof)
            True joint (link-side) torques [N m].
        state : SensorState
            Sensor state before the first sample (:meth:`initial_state`).
        rng : numpy.random.Generator, optional
            Source of noise; needed only when ``torque_sensor_noise`` is on.

        Returns
        -------
        tau_j_meas : ndarray of the shape of ``tau_j``
            Measured joint torques [N m].
        new_state : SensorState
            Sensor state after the last sample.
        """
        values, single = _signal(tau_j, "tau_j")
        n_dof = values.shape[1]
        if not isinstance(state, SensorState):
            raise InputTypeError(
                f"state must be a SensorState (SensorModel.initial_state); got "
                f"{type(state).__name__}"
            )
        if state.n_dof != n_dof:
            raise DimensionError(
                f"state is for {state.n_dof} joints; tau_j has {n_dof} (shape {np.shape(tau_j)})"
            )
        width = self._per_joint("torque_sensor_hysteresis", n_dof)
        output = state.torque_sensor_output.copy()
        if np.any(width):
            played = np.empty_like(values)
            for k in range(values.shape[0]):
                output = np.minimum(np.maximum(output, values[k] - width), values[k] + width)
                played[k] = output
        else:
            played = values.copy()
            if values.shape[0]:
                output = values[-1].copy()
        bias = self._per_joint("torque_sensor_bias", n_dof)
        if np.any(bias):
            played = played + bias
        return self._reading(played, "torque_sensor_noise", rng, single), SensorState(output)

    # ------------------------------------------------------------------ helpers
    def _values(self, name: str) -> FloatArray:
        return np.atleast_1d(np.asarray(getattr(self, name), dtype=np.float64))

    def _per_joint(self, name: str, n_dof: int) -> FloatArray:
        """Parameter ``name`` as an array of shape (n_dof,); DimensionError on a length mismatch."""
        return _per_joint(name, getattr(self, name), n_dof)

    def _reading(
        self, values: FloatArray, noise: str, rng: np.random.Generator | None, single: bool
    ) -> FloatArray:
        """Add the white noise of parameter ``noise``; one sample in gives one sample out."""
        std = self._per_joint(noise, values.shape[1])
        if np.any(std):
            if not isinstance(rng, np.random.Generator):
                raise InputTypeError(
                    f"{noise} is on, so a numpy.random.Generator is needed "
                    f"(numpy.random.default_rng(seed)); got rng={rng!r}"
                )
            values = values + std * rng.standard_normal(values.shape)
        return values[0] if single else values


def _parameter(
    name: str, value: Any, lower: float | None, strict: bool, meaning: str
) -> float | tuple[float, ...]:
    """Check one SensorModel parameter; a scalar becomes a float, an array a tuple."""
    arr = joint_parameter(value, f"SensorModel.{name}")
    if lower is not None and (arr <= lower if strict else arr < lower).any():
        relation = ">" if strict else ">="
        raise InputValueError(
            f"SensorModel.{name} must be {relation} {lower:g} ({meaning}); got {value!r}"
        )
    return float(arr) if arr.ndim == 0 else tuple(float(x) for x in arr)


def _signal(x: ArrayLike, name: str) -> tuple[FloatArray, bool]:
    """``x`` as (n_samples, n_dof) with n_dof read from its last axis."""
    shape = np.shape(x)
    if len(shape) not in (1, 2) or shape[-1] == 0:
        raise DimensionError(
            f"{name} must have shape (n_dof,) or (n_samples, n_dof) with n_dof >= 1; "
            f"got shape {shape}"
        )
    return as_joint_array(x, shape[-1], name)


@functools.cache
def _per_joint(name: str, value: float | tuple[float, ...], n_dof: int) -> FloatArray:
    """Cached per-joint array (read-only): a simulation asks for it at every sample."""
    values = np.atleast_1d(np.asarray(value, dtype=np.float64))
    if values.size == 1:
        values = np.full(n_dof, values[0])
    elif values.size != n_dof:
        raise DimensionError(
            f"SensorModel.{name} has {values.size} per-joint values; the signal has {n_dof} joints"
        )
    values.setflags(write=False)
    return values
