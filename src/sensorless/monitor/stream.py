"""The whole detection pipeline on a log or live: velocity estimate, observer, threshold, detector.

A :class:`CollisionMonitor` applies a fitted threshold to a recorded log
(:meth:`~CollisionMonitor.run`) or to a live stream one sample at a time
(:meth:`~CollisionMonitor.step`), with the same result on the same samples.
The fault, restart, settling and latching rules are those of
:mod:`sensorless.monitor.policy`. Units SI and radians; time along axis 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, cast

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_sample, check_dt
from ..detection import Detector, DetectorState, Verdict
from ..exceptions import DimensionError, InputTypeError, InputValueError
from ..io import Log
from ..observers import AccelerationObserver, MomentumObserver, ObserverSample, ObserverState
from ..robots.model import RobotModel
from ..signals import Event, ObserverSignals
from ..thresholds import ModelBasedThreshold, Threshold, ThresholdInputs
from .batch import FaultSpan, MonitorRun, run_log
from .policy import StreamPolicy
from .tuning import ObserverSettings

__all__ = ["CollisionMonitor"]


@dataclass
class _Stream:
    """Mutable state of a live stream; replaced field by field only after a good sample."""

    start: float  # time of the (re)start [s]
    t: float  # time of the last accepted sample [s]
    estimator: Any  # section states (position, velocity, acceleration) of the estimator
    observer: ObserverState | None  # None for the acceleration-based estimate
    detector: DetectorState | None  # None while settling


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
        Sample period of the stream [s]; default the threshold's. It must
        equal the tuned period within ``policy.period_rtol``.
    min_duration, hold : float
        Event filtering of :class:`~sensorless.detection.Detector` [s]: an
        excursion shorter than ``min_duration`` is not an event, and excursions
        closer than ``hold`` are one event (defaults 5 ms and 50 ms).
    policy : StreamPolicy, optional
        Time base, limits, settling and latching (see :mod:`sensorless.monitor.policy`).

    Raises
    ------
    NotFittedError
        The threshold is not fitted.
    DimensionError
        The robot and the threshold have different joint counts.
    InputValueError
        ``dt`` differs from the tuned period.
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
        policy: StreamPolicy | None = None,
    ) -> None:
        if not isinstance(robot, RobotModel):
            raise InputTypeError(f"robot must be a RobotModel; got {type(robot).__name__}")
        if not isinstance(threshold, Threshold):
            raise InputTypeError(
                f"threshold must be a fitted sensorless Threshold; got {type(threshold).__name__}"
            )
        if not isinstance(settings, ObserverSettings):
            raise InputTypeError(
                f"settings must be ObserverSettings; got {type(settings).__name__}"
            )
        self.detector = Detector(threshold, min_duration=min_duration, hold=hold)
        _ = self.detector.monitored_joints  # NotFittedError before anything else
        if robot.n_dof != threshold.n_dof_:
            raise DimensionError(
                f"threshold is for {threshold.n_dof_} joints ({threshold.robot_}); "
                f"robot {robot.name!r} has {robot.n_dof}"
            )
        self.robot = robot
        self.threshold = threshold
        self.settings = settings
        self.policy = policy or StreamPolicy()
        tuned = check_dt(threshold.dt_)
        self.dt = tuned if dt is None else check_dt(dt)
        if abs(self.dt - tuned) > self.policy.period_rtol * tuned:
            raise InputValueError(
                f"the threshold was tuned at dt = {tuned:g} s; the stream's dt = {self.dt:g} s. "
                "Tune on logs sampled like the stream, or resample them"
            )
        self.settle = (
            settings.settle_time(self.dt) if self.policy.settle is None else self.policy.settle
        )
        self.limits = self.policy.limits(robot)
        self._estimator = settings.estimator(self.dt)
        self._observer: Any
        if settings.kind == "acceleration":
            self._observer = AccelerationObserver(robot, self._estimator)
        else:
            self._observer = MomentumObserver(robot, self.dt, settings.gain, torque=settings.kind)
        # Estimator outputs the stream needs: never the filtered position (the
        # detector gets q), the acceleration only where it is used.
        needs_acceleration = settings.kind == "acceleration" or isinstance(
            threshold, ModelBasedThreshold
        )
        self._outputs = (False, True, needs_acceleration)
        self._early = self.policy.early * self.dt
        self._gap = self.policy.gap * self.dt
        self.reset()

    # ----------------------------------------------------------------- batch
    def run(self, log: Log) -> tuple[ObserverSignals, list[Event]]:
        """Residual signals and detected events of a whole log (see :meth:`process`)."""
        result = self.process(log)
        return result.signals, result.events

    def process(self, log: Log, *, strict: bool = False) -> MonitorRun:
        """The stream's verdicts for a whole log, computed over whole arrays.

        Samples the stream would call faults (outside the limits) are reported
        as :class:`~sensorless.monitor.batch.FaultSpan` and treated as a gap:
        the observer restarts after each span, with the settling window.

        Parameters
        ----------
        log : Log
            The run, sampled every ``dt`` (within ``policy.period_rtol``).
        strict : bool
            Refuse a log with any fault sample instead of skipping the spans.

        Returns
        -------
        MonitorRun
            Signals (NaN inside fault spans), events and fault spans.
        """
        if not isinstance(log, Log):
            raise InputTypeError(f"log must be a sensorless.io.Log; got {type(log).__name__}")
        if log.n_dof != self.robot.n_dof:
            raise DimensionError(f"robot has {self.robot.n_dof} joints, log has {log.n_dof}")
        if log.n_samples > 1 and abs(log.dt - self.dt) > self.policy.period_rtol * self.dt:
            raise InputValueError(
                f"the log is sampled every {log.dt:g} s but the threshold was tuned at "
                f"{self.dt:g} s; resample the log (sensorless.io.resample) or tune at its rate"
            )
        return run_log(self, log, strict=strict)

    # ----------------------------------------------------------------- stream
    def reset(self) -> None:
        """Forget the stream and release a latched collision: the next sample starts anew."""
        self._stream: _Stream | None = None
        self._pending = -math.inf  # time of the last faulted sample that may end a gap
        self._floor = -math.inf  # no sample may come at or before this time
        self._latched = False
        self._inside_since = math.nan

    @property
    def latched(self) -> bool:
        """Whether a collision verdict is latched (until :meth:`reset` or the release rule)."""
        return self._latched

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
            ``"ok"``, ``"collision"`` (latched), ``"settling"`` or ``"fault"``;
            a fault leaves every state exactly as it was (see
            :mod:`sensorless.monitor.policy`).
        """
        try:
            time = float(t)
        except (TypeError, ValueError):
            return self._fault(math.nan, f"time must be a number of seconds; got {t!r}")
        if not math.isfinite(time):
            return self._fault(time, f"time must be finite; got {time}")
        if time <= self._floor:
            return self._fault(time, f"time must increase: {time!r} s after {self._floor!r} s")
        q_arr, tau, message = self._sample(q, tau_m, tau_j)
        if message:
            self._pending = time
            return self._fault(time, message)
        stream = self._stream
        restart = stream is None
        if stream is not None:
            step = time - stream.t
            if step < self._early:
                return self._fault(
                    time, f"time step {step:.6g} s is shorter than {self._early:.6g} s (dt/2)"
                )
            if step > self._gap:
                if self._early <= time - self._pending <= self._gap:
                    restart = True  # the stream resumed after a real gap
                else:
                    self._pending = time
                    return self._fault(
                        time,
                        f"gap: {step:.6g} s since the last sample; expected dt = {self.dt:g} s "
                        "(time in ms, or a dropped sample?)",
                    )
        try:
            return self._judge(stream, restart, time, q_arr, tau)
        except Exception as exc:  # fail-safe: no data may crash the stream
            return self._fault(time, f"the sample could not be processed: {exc!r}")

    def _sample(self, q: Any, tau_m: Any, tau_j: Any) -> tuple[FloatArray, FloatArray, str]:
        """The checked position and torque of one sample, or a fault message."""
        n = self.robot.n_dof
        joint = self.settings.kind == "joint"
        if joint and tau_j is None:
            return _EMPTY, _EMPTY, "the joint-torque observer needs tau_j"
        q_arr, message = as_sample(q, n, "q")
        if message:
            return _EMPTY, _EMPTY, message
        if not self.limits.position_ok(q_arr):
            return _EMPTY, _EMPTY, self.limits.describe("q", q_arr)
        torques = {"tau_m": tau_m, "tau_j": tau_j} if joint else {"tau_m": tau_m}
        tau = _EMPTY
        for name, value in torques.items():
            tau, message = as_sample(value, n, name)
            if message:
                return _EMPTY, _EMPTY, message
            if not self.limits.torque_ok(tau):
                return _EMPTY, _EMPTY, self.limits.describe(name, tau)
        return q_arr, tau, ""

    def _judge(
        self, stream: _Stream | None, restart: bool, time: float, q: FloatArray, tau: FloatArray
    ) -> Verdict:
        """Run a sample with good inputs through the pipeline; commit only if all is finite."""
        closed: Event | None = None
        if restart:
            if stream is not None and stream.detector is not None:
                closed = self.detector.finish(stream.detector)[0]
            initial = self._estimator.initial_state(q)
            estimator = (initial.position, initial.velocity, initial.acceleration)
            observer = (
                None
                if self.settings.kind == "acceleration"
                else self._observer.initial_state(q, np.zeros_like(q))
            )
            stream = _Stream(time, time, estimator, observer, None)
        assert stream is not None  # set above on a restart
        (_, velocity, acceleration), estimator = self._estimator._step_outputs(
            q, stream.estimator, self._outputs
        )
        velocity = cast(FloatArray, velocity)
        if not self.limits.velocity_ok(velocity):
            self._pending = time
            return self._fault(time, self.limits.describe("qd", velocity))
        observer = stream.observer
        if observer is None:  # acceleration-based estimate: an algebraic function of the sample
            assert acceleration is not None  # always selected for this observer
            out = self._observer._estimate(q[None], velocity[None], acceleration[None], tau[None])
            sample = ObserverSample(*(row[0] for row in out))
            outputs = np.stack(sample)
        else:
            sample, observer = self._observer._step_checked(observer, q, velocity, tau)
            outputs = observer.filtered
        if not np.isfinite(outputs).all() or (
            acceleration is not None and not np.isfinite(acceleration).all()
        ):
            self._pending = time
            return self._fault(time, "the observer's output is not finite for this sample")
        residual, model_torque, friction, sign = sample
        settling = time - stream.start < self.settle
        detector = stream.detector
        if settling:
            nan = np.full(self.robot.n_dof, np.nan)
            verdict = Verdict("settling", time, (), residual, nan, nan.copy(), closed)
        else:
            if detector is None:
                detector = self.detector.initial_state(self.dt)
            inputs = ThresholdInputs(
                model_torque[None],
                friction[None],
                sign[None],
                velocity[None],
                q[None],
                None if acceleration is None else acceleration[None],
            )
            verdict, detector = self.detector._step_checked(detector, residual, inputs, time)
            if np.isnan(verdict.lower).any() or np.isnan(verdict.upper).any():
                self._pending = time
                return self._fault(time, "the threshold's bounds are not finite for this sample")
            if closed is not None and verdict.event is None:
                verdict = _with(verdict, verdict.status, closed)
            verdict = self._latch(verdict)
        # Commit: the sample was good from end to end.
        stream.t = time
        stream.estimator = estimator
        stream.observer = observer
        stream.detector = detector
        self._stream = stream
        self._floor = time
        self._pending = -math.inf
        return verdict

    def _latch(self, verdict: Verdict) -> Verdict:
        """Apply the latch: a collision stays a collision until released."""
        if verdict.status == "collision":
            self._latched = True
            self._inside_since = math.nan
            return verdict
        if not self._latched:
            return verdict
        release = self.policy.release
        if release is not None:
            if verdict.joints:
                self._inside_since = math.nan
            elif math.isnan(self._inside_since):
                self._inside_since = verdict.t
            if verdict.t - self._inside_since >= release:
                self._latched = False
                self._inside_since = math.nan
                return verdict
        return _with(verdict, "collision", verdict.event)

    def _fault(self, time: float, message: str) -> Verdict:
        nan = np.full(self.robot.n_dof, np.nan)
        return Verdict("fault", time, (), nan, nan.copy(), nan.copy(), None, message)

    def finish(self) -> Event | None:
        """Close the stream: the event still open, if any."""
        stream = self._stream
        if stream is None or stream.detector is None:
            return None
        event, stream.detector = self.detector.finish(stream.detector)
        return event

    # Batch access for :mod:`sensorless.monitor.batch` (one place builds the observer).
    @property
    def estimator(self) -> Any:
        """The velocity/acceleration estimator of the stream."""
        return self._estimator

    @property
    def fault_spans(self) -> type[FaultSpan]:
        """The type of the fault spans :meth:`process` reports."""
        return FaultSpan


_EMPTY = np.empty(0)


def _with(verdict: Verdict, status: Any, event: Event | None) -> Verdict:
    return Verdict(
        status,
        verdict.t,
        verdict.joints,
        verdict.residual,
        verdict.lower,
        verdict.upper,
        event,
        verdict.message,
    )
