"""The whole detection pipeline: velocity estimation, observer, threshold, detector.

:func:`tune` fits a threshold family on collision-free logs; a
:class:`CollisionMonitor` applies it to a recorded log (:meth:`~CollisionMonitor.run`)
or to a live stream one sample at a time (:meth:`~CollisionMonitor.step`),
with the same result. Observer settings travel with the fitted threshold in
one YAML file (:func:`save_tuned`, :func:`load_tuned`), so a threshold is never
applied to residuals computed differently from those it was fitted on.
Units SI and radians; time along axis 0.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any, cast

import numpy as np
import yaml
from numpy.typing import ArrayLike

from ._validation import FloatArray, check_dt
from .detection import Detector, DetectorState, Verdict
from .exceptions import DimensionError, InputTypeError, InputValueError, UnknownNameError
from .filters import Butterworth, CausalEstimator, DirtyDerivative, FiniteDifference
from .io import Log
from .observers import (
    AccelerationObserver,
    MomentumObserver,
    ObserverSample,
    default_estimator,
    observe,
)
from .robots.model import RobotModel
from .signals import Event, ObserverSignals
from .thresholds import (
    ConstantThreshold,
    ModelBasedThreshold,
    Threshold,
    ThresholdInputs,
    TimeVariantThreshold,
    VelocityThreshold,
)

__all__ = [
    "METHOD_NAMES",
    "CollisionMonitor",
    "ObserverSettings",
    "load_tuned",
    "make_threshold",
    "save_tuned",
    "tune",
]

#: Threshold families by the names the CLI uses, with the observer each one watches.
METHOD_NAMES: dict[str, str] = {
    "constant": "motor",
    "time-variant": "motor",
    "hysteretic": "motor",
    "velocity": "motor",
    "model": "acceleration",
}
_FILTERS = ("default", "finite_difference", "dirty_derivative", "butterworth")


@dataclass(frozen=True)
class ObserverSettings:
    """How residuals are computed from a log or a stream.

    Parameters
    ----------
    kind : {"motor", "joint", "acceleration"}
        r̂ from motor torques (eq. 4.4), r̂_s from joint torque sensors (eq. 4.9),
        or the acceleration-based τ̂_c (eq. 3.16).
    gain : float
        Observer gain K_I [1/s] (momentum observers; §5.4 uses 20).
    filter : {"default", "finite_difference", "dirty_derivative", "butterworth"}
        Velocity/acceleration estimator; "default" is
        :func:`sensorless.observers.default_estimator`.
    cutoff : float
        Cut-off [Hz] of the dirty derivative or Butterworth filter.
    order : int
        Butterworth order (the thesis used 5).
    """

    kind: str = "motor"
    gain: float = 20.0
    filter: str = "default"
    cutoff: float = 20.0
    order: int = 5

    def __post_init__(self) -> None:
        if self.kind not in ("motor", "joint", "acceleration"):
            raise InputValueError(
                f"observer kind must be motor, joint or acceleration; got {self.kind!r}"
            )
        if self.filter not in _FILTERS:
            raise InputValueError(f"filter must be one of {list(_FILTERS)}; got {self.filter!r}")
        if not np.isfinite(self.gain) or self.gain <= 0:
            raise InputValueError(f"observer gain K_I must be > 0 [1/s]; got {self.gain}")

    def estimator(self, dt: float) -> CausalEstimator:
        """The velocity/acceleration estimator for sample period ``dt`` [s]."""
        period = check_dt(dt)
        if self.filter == "finite_difference":
            return FiniteDifference(period)
        if self.filter == "dirty_derivative":
            return DirtyDerivative(period, self.cutoff)
        if self.filter == "butterworth":
            return Butterworth(period, self.cutoff, self.order)
        return default_estimator(period, self.kind)

    def observe(self, log: Log, robot: RobotModel) -> ObserverSignals:
        """Residual signals of a whole log (see :func:`sensorless.observers.observe`)."""
        return observe(log, robot, kind=self.kind, gain=self.gain, estimator=self.estimator(log.dt))

    def to_dict(self) -> dict[str, Any]:
        """Plain values for a YAML file."""
        return asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> ObserverSettings:
        """Inverse of :meth:`to_dict`; unknown keys are a TypeError listing the valid ones."""
        valid = set(cls.__dataclass_fields__)
        unknown = set(data) - valid
        if unknown:
            raise InputTypeError(
                f"unknown observer settings {sorted(unknown)}; valid: {sorted(valid)}"
            )
        return cls(**data)


def make_threshold(method: str, robot: RobotModel, **options: Any) -> Threshold:
    """An unfitted threshold of the family ``method`` (one of :data:`METHOD_NAMES`)."""
    if method == "constant":
        return ConstantThreshold(**options)
    if method == "time-variant":
        return TimeVariantThreshold(form="friction", **options)
    if method == "hysteretic":
        return TimeVariantThreshold(form="hysteretic", **options)
    if method == "velocity":
        return VelocityThreshold(**options)
    if method == "model":
        return ModelBasedThreshold(robot, **options)
    raise UnknownNameError(f"unknown threshold method {method!r}; options: {sorted(METHOD_NAMES)}")


def tune(
    logs: Sequence[Log],
    robot: RobotModel,
    method: str,
    settings: ObserverSettings | None = None,
    **options: Any,
) -> tuple[Threshold, ObserverSettings]:
    """Fit a threshold family on collision-free logs.

    Parameters
    ----------
    logs : sequence of Log
        Collision-free runs of the robot.
    robot : RobotModel
        The nominal model the observer uses.
    method : str
        One of :data:`METHOD_NAMES`.
    settings : ObserverSettings, optional
        Observer settings; by default the observer the method watches, K_I = 20.
    **options
        Hyper-parameters of the threshold (``margin``, ``joints``, ``transient``...).

    Returns
    -------
    threshold : Threshold
        Fitted.
    settings : ObserverSettings
        The settings used (save them with the threshold: :func:`save_tuned`).
    """
    if method not in METHOD_NAMES:
        raise UnknownNameError(
            f"unknown threshold method {method!r}; options: {sorted(METHOD_NAMES)}"
        )
    if not logs:
        raise InputValueError("tune needs at least one collision-free log")
    settings = settings or ObserverSettings(kind=METHOD_NAMES[method])
    needed = METHOD_NAMES[method]
    if (needed == "acceleration") != (settings.kind == "acceleration"):
        raise InputValueError(
            f"method {method!r} watches the {needed!r} residual; observer kind is {settings.kind!r}"
        )
    signals = [settings.observe(log, robot) for log in logs]
    return make_threshold(method, robot, **options).fit(signals), settings


def save_tuned(path: str | Path, threshold: Threshold, settings: ObserverSettings) -> Path:
    """Write a fitted threshold and its observer settings to one readable YAML file."""
    data = threshold.to_dict()
    data["observer"] = settings.to_dict()
    out = Path(path)
    out.write_text(
        "# sensorless fitted collision threshold (edit with care)\n"
        + yaml.safe_dump(data, sort_keys=False, default_flow_style=None, width=100),
        encoding="utf-8",
    )
    return out


def load_tuned(path: str | Path) -> tuple[Threshold, ObserverSettings]:
    """Read a file written by :func:`save_tuned` (or a bare threshold file: default settings)."""
    data = yaml.safe_load(Path(path).read_text(encoding="utf-8"))
    if not isinstance(data, dict):
        raise InputValueError(f"{path} is not a threshold file (expected a YAML mapping)")
    settings_data = data.pop("observer", None)
    threshold = Threshold.from_dict(data)
    if settings_data is None:
        settings = ObserverSettings(kind=threshold.kind_, gain=float(threshold.gain_[0]))
    else:
        settings = ObserverSettings.from_dict(settings_data)
    return threshold, settings


@dataclass
class _StreamState:
    """Mutable state of a live :class:`CollisionMonitor` (one object per stream)."""

    t: float
    estimator: Any  # section states (position, velocity, acceleration) of the estimator
    observer: Any
    detector: DetectorState


class CollisionMonitor:
    """Detect collisions with a fitted threshold, on a log or live.

    Parameters
    ----------
    robot : RobotModel
        Nominal model (the one the threshold was tuned with).
    threshold : Threshold
        Fitted threshold.
    settings : ObserverSettings
        Observer settings the threshold was tuned with.
    dt : float, optional
        Sample period of the stream [s]; default the threshold's.
    min_duration, hold : float
        Event filtering of :class:`~sensorless.detection.Detector` [s]: an
        excursion shorter than ``min_duration`` is not an event, and excursions
        closer than ``hold`` are one event (defaults 5 ms and 50 ms: one
        collision gives one event, not a burst of fragments).
    """

    def __init__(
        self,
        robot: RobotModel,
        threshold: Threshold,
        settings: ObserverSettings,
        *,
        dt: float | None = None,
        min_duration: float = 0.005,
        hold: float = 0.05,
    ) -> None:
        if robot.n_dof != threshold.n_dof_:
            raise DimensionError(
                f"threshold is for {threshold.n_dof_} joints ({threshold.robot_}); "
                f"robot {robot.name!r} has {robot.n_dof}"
            )
        self.robot = robot
        self.threshold = threshold
        self.settings = settings
        self.dt = check_dt(threshold.dt_ if dt is None else dt)
        self.detector = Detector(threshold, min_duration=min_duration, hold=hold)
        self._estimator = settings.estimator(self.dt)
        if settings.kind == "acceleration":
            self._observer: Any = AccelerationObserver(robot, self._estimator)
        else:
            self._observer = MomentumObserver(robot, self.dt, settings.gain, torque=settings.kind)
        self._state: _StreamState | None = None
        # Estimator outputs the stream needs: never the filtered position (the
        # detector gets q), the acceleration only where it is used.
        needs_acceleration = settings.kind == "acceleration" or isinstance(
            threshold, ModelBasedThreshold
        )
        self._outputs = (False, True, needs_acceleration)

    # ----------------------------------------------------------------- batch
    def run(self, log: Log) -> tuple[ObserverSignals, list[Event]]:
        """Residual signals and detected events of a whole log."""
        if log.n_dof != self.robot.n_dof:
            raise DimensionError(f"robot has {self.robot.n_dof} joints, log has {log.n_dof}")
        signals = self.settings.observe(log, self.robot)
        return signals, self.detector.detect(signals)

    # ----------------------------------------------------------------- stream
    def reset(self) -> None:
        """Forget the stream: the next :meth:`step` starts a new one."""
        self._state = None

    def step(
        self, t: float, q: ArrayLike, tau_m: ArrayLike, tau_j: ArrayLike | None = None
    ) -> Verdict:
        """Judge one sample of a live stream; never raises on bad data.

        Parameters
        ----------
        t : float
            Time of the sample [s].
        q : array-like of shape (n_dof,)
            Measured joint positions [rad].
        tau_m : array-like of shape (n_dof,)
            Motor (commanded) torques [N m], held until the next sample.
        tau_j : array-like of shape (n_dof,), optional
            Joint-torque-sensor torques [N m] (observer kind "joint").

        Returns
        -------
        Verdict
            ``"ok"``, ``"collision"`` or ``"fault"``; a fault (wrong length,
            NaN/inf, missing tau_j, time not increasing) leaves the state as it
            was, as if the sample had never arrived.
        """
        fault = self._fault(t, q, tau_m, tau_j)
        if fault:
            nan = np.full(self.robot.n_dof, np.nan)
            return Verdict("fault", _as_float(t), (), nan, nan, nan.copy(), None, fault)
        time = float(t)
        kind = self.settings.kind
        # Contiguous, as the observer's own checks would make them (Pinocchio takes them).
        q_arr = np.ascontiguousarray(q, dtype=float)
        tau = np.ascontiguousarray(tau_j if kind == "joint" else tau_m, dtype=float)
        state = self._state
        if state is None:
            initial = self._estimator.initial_state(q_arr)
            estimator = (initial.position, initial.velocity, initial.acceleration)
            # The acceleration observer's only state is the estimator's, kept above.
            observer = (
                None
                if kind == "acceleration"
                else self._observer.initial_state(q_arr, np.zeros_like(q_arr))
            )
            state = _StreamState(time, estimator, observer, self.detector.initial_state(self.dt))
        # Dot products propagate NaN/inf: ``total`` is finite when every value the
        # detector checks is (a huge finite value that merely overflows takes the
        # fully checked path, with the same result).
        if kind == "acceleration":
            # One pass of the estimator feeds both the observer and the threshold.
            velocity, acceleration = self._derivatives(state, q_arr)
            assert acceleration is not None  # always selected for this observer
            estimate = self._observer._estimate(
                q_arr[None], velocity[None], acceleration[None], tau[None]
            )
            sample = ObserverSample(*(row[0] for row in estimate))
            total = velocity @ velocity + sum(row @ row for row in sample)
        else:
            velocity, acceleration = self._derivatives(state, q_arr)
            total = velocity @ velocity
            if math.isfinite(total):
                # q and tau were checked by _fault: skip the observer's own checks.
                sample, state.observer = self._observer._step_checked(
                    state.observer, q_arr, velocity, tau
                )
            else:  # let the observer report the non-finite velocity
                sample, state.observer = self._observer.step(state.observer, q_arr, velocity, tau)
            # The sample's residual, model torque, friction and sign are its rows.
            filtered = state.observer.filtered.reshape(-1)
            total += filtered @ filtered
        if acceleration is not None:
            total += acceleration @ acceleration
        residual, model_torque, friction, sign = sample
        if math.isfinite(total):
            inputs = ThresholdInputs(
                model_torque[None],
                friction[None],
                sign[None],
                velocity[None],
                q_arr[None],
                None if acceleration is None else acceleration[None],
            )
            verdict, state.detector = self.detector._step_checked(
                state.detector, residual, inputs, time
            )
        else:  # the detector's own checks name the non-finite value
            verdict, state.detector = self.detector.step(
                state.detector,
                residual,
                model_torque,
                friction,
                sign,
                velocity,
                time,
                position=q_arr,
                acceleration=acceleration,
            )
        state.t = time
        self._state = state
        return verdict

    def _derivatives(
        self, state: _StreamState, q: FloatArray
    ) -> tuple[FloatArray, FloatArray | None]:
        """Velocity and (where needed) acceleration of a checked sample; advances the estimator."""
        (_, velocity, acceleration), state.estimator = self._estimator._step_outputs(
            q, state.estimator, self._outputs
        )
        return cast(FloatArray, velocity), acceleration  # velocity is always selected

    def finish(self) -> Event | None:
        """Close the stream: the event still open, if any."""
        if self._state is None:
            return None
        event, self._state.detector = self.detector.finish(self._state.detector)
        return event

    def _fault(self, t: Any, q: Any, tau_m: Any, tau_j: Any) -> str:
        n = self.robot.n_dof
        try:
            time = float(t)
        except (TypeError, ValueError):
            return f"time must be a number of seconds; got {t!r}"
        if not math.isfinite(time):
            return f"time must be finite; got {time}"
        if self._state is not None and time <= self._state.t:
            return f"time must increase: {time} s after {self._state.t} s"
        inputs = {"q": q, "tau_m": tau_m}
        if self.settings.kind == "joint":
            if tau_j is None:
                return "the joint-torque observer needs tau_j"
            inputs["tau_j"] = tau_j
        for name, value in inputs.items():
            try:
                arr = np.asarray(value, dtype=float)
            except (TypeError, ValueError):
                return f"{name} must be numeric; got {value!r}"
            if arr.shape != (n,):
                return f"{name} must have shape ({n},); got {arr.shape}"
            if not np.isfinite(arr).all():
                return f"{name} has a non-finite value: {arr}"
        return ""


def _as_float(t: Any) -> float:
    try:
        return float(t)
    except (TypeError, ValueError):
        return float("nan")
