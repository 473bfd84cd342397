"""The whole detection pipeline on a log or live: velocity estimate, observer, threshold, detector.

A :class:`CollisionMonitor` applies a fitted threshold to a recorded log
(:meth:`~CollisionMonitor.run`) or to a live stream one sample at a time
(:meth:`~CollisionMonitor.step`), with the same result on the same samples.
The fault, restart, settling and latching rules are those of
:mod:`sensorless.monitor.policy`. With numba installed, ``step`` runs one
compiled function per sample (:mod:`sensorless.monitor._compiled`) for the
families it covers; the Python path here is the reference it is tested
against. Units SI and radians; time along axis 0.
"""

from __future__ import annotations

import math
from types import ModuleType
from typing import TYPE_CHECKING, Any, cast

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, as_sample, check_dt
from ..detection import Detector, Status, Verdict
from ..exceptions import (
    DimensionError,
    InputTypeError,
    InputValueError,
    ModelMismatchError,
    UnknownNameError,
)
from ..io import Log
from ..observers import AccelerationObserver, MomentumObserver, ObserverSample
from ..robots.model import RobotModel
from ..signals import Event, ObserverSignals
from ..thresholds import ModelBasedThreshold, Threshold
from ..thresholds.checks import other_model, parameters_differ
from ..thresholds.files import family_name
from ._codes import EVENT, FAULT, JOINTS_SHIFT, UNJUDGED, CompiledStep
from ._numpy_stream import NumpyStream
from ._numpy_stream import unsupported as numpy_unsupported
from ._python_stream import PythonStream, judge
from .adaptation import Adaptation
from .batch import MonitorRun, run_log, value_fault
from .policy import StreamPolicy
from .tuning import ObserverSettings

if TYPE_CHECKING:
    from ._fused import FusedStream

_fused: ModuleType | None
try:
    from . import _fused
except ImportError:  # numba is an optional extra
    _fused = None

__all__ = ["BACKENDS", "CollisionMonitor"]

# The smallest code with a joint outside its bounds (see _codes).
_JOINTS_CODE = 1 << JOINTS_SHIFT

#: Stream backends of :class:`CollisionMonitor`.
BACKENDS = ("auto", "numba", "numpy", "python")
_STATUSES: tuple[Status, ...] = ("ok", "collision", "settling")


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
    backend : {"auto", "numba", "numpy", "python"}
        How :meth:`step` runs: ``"numba"`` one compiled function per sample
        (:mod:`sensorless.monitor._compiled`; ``pip install sensorless[fast]``),
        for momentum observers with the constant, time-variant, hysteretic or
        velocity-based threshold; ``"numpy"`` the same families without numba,
        a few vectorised numpy calls per sample
        (:mod:`sensorless.monitor._numpy_stream`; no drift adaptation);
        ``"python"`` the reference path, which composes the library's objects;
        ``"auto"`` numba where it can run, else numpy where it can, else
        python. All give the same verdicts, and residuals and bounds within
        rounding. :meth:`process` runs the numba kernel over the log, or else
        the Python path's whole-array form.
    adaptation : Adaptation, optional
        Adapt the nominal friction and offsets to drift (momentum observers;
        compiled with the families above): see :mod:`sensorless.monitor.adaptation`.

    Raises
    ------
    NotFittedError
        The threshold is not fitted.
    DimensionError
        The robot and the threshold have different joint counts.
    ModelMismatchError
        The threshold was tuned for another robot model with the same joint
        count (robot name: another robot, a payload, other parameters).
    InputValueError
        ``dt`` differs from the tuned period, or ``backend="numba"`` cannot run
        (numba missing, or a monitor the compiled step does not cover).
    UnknownNameError
        An unknown ``backend``.
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
        backend: str = "auto",
        adaptation: Adaptation | None = None,
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
        fingerprint = threshold.model_fingerprint(settings.kind)
        if threshold.robot_ and other_model(
            threshold.robot_, fingerprint, robot.name, robot.fingerprint
        ):
            raise ModelMismatchError(
                f"threshold is for robot {threshold.robot_!r} ({threshold.n_dof_} joints); robot "
                f"{robot.name!r} has as many joints but is another model (another robot, a "
                "payload or other parameters"
                + parameters_differ(fingerprint, robot.fingerprint)
                + "): tune on logs observed with this model"
            )
        self.robot = robot
        self.threshold = threshold
        self._method = family_name(threshold)  # the events' label, once (not per sample)
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
        self._n_dof, self._joint = robot.n_dof, settings.kind == "joint"
        if adaptation is not None and not isinstance(adaptation, Adaptation):
            raise InputTypeError(
                f"adaptation must be an Adaptation; got {type(adaptation).__name__}"
            )
        if adaptation is not None and settings.kind == "acceleration":
            raise InputValueError(
                "drift adaptation corrects a momentum observer's residual; "
                "the acceleration observer has none"
            )
        self.adaptation = adaptation
        self._adapter = None if adaptation is None else adaptation.adapter(self._observer)
        self._guard = 0.0 if adaptation is None else float(adaptation.guard)
        self._trust = (np.zeros(self._n_dof, dtype=bool), np.ones(self._n_dof, dtype=bool))
        self._record: list[tuple[float, ObserverSample, FloatArray]] | None = None
        self._fused = self._fused_stream(backend)
        self._compiled: tuple[Any, Any, Any, FusedStream | NumpyStream] | None = (
            None if self._fused is None else (*self._fused.sample, self._fused)
        )
        self.reset()

    def _fused_stream(self, backend: str) -> FusedStream | NumpyStream | None:
        """The compiled or numpy stream for ``backend``, or None for the Python path."""
        if backend not in BACKENDS:
            raise UnknownNameError(f"unknown backend {backend!r}; options: {list(BACKENDS)}")
        if backend == "python":
            return None
        if backend == "numpy":
            why = numpy_unsupported(self)
            if why:
                raise InputValueError(f"backend 'numpy' cannot run this monitor: {why}")
            return NumpyStream(self)
        why = "numba is not installed (pip install sensorless[fast])"
        if _fused is not None:
            why = _fused.unsupported(self)
        if why:
            if backend == "numba":
                raise InputValueError(f"backend 'numba' cannot run this monitor: {why}")
            return None if numpy_unsupported(self) else NumpyStream(self)
        assert _fused is not None  # why is empty only with numba
        fused: FusedStream = _fused.FusedStream(self)
        return fused

    @property
    def backend(self) -> str:
        """``"numba"``, ``"numpy"`` or ``"python"``: how :meth:`step` runs."""
        if self._fused is None:
            return "python"
        return "numpy" if isinstance(self._fused, NumpyStream) else "numba"

    def compiled_step(self) -> CompiledStep:
        """This monitor's stream step for a loop compiled with numba (see :class:`CompiledStep`).

        Raises
        ------
        InputValueError
            If the monitor does not run on the ``"numba"`` backend.
        """
        if self.backend != "numba":
            raise InputValueError(
                f"compiled_step needs the 'numba' backend; this monitor runs on {self.backend!r}"
            )
        assert self._compiled is not None  # the numba backend has its compiled step
        return CompiledStep(*self._compiled[:3])

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
        self._stream: PythonStream | None = None
        self._pending = -math.inf  # time of the last faulted sample that may end a gap
        self._floor = -math.inf  # no sample may come at or before this time
        self._latched = False
        self._inside_since = math.nan
        if self._fused is not None:
            self._fused.reset()

    @property
    def latched(self) -> bool:
        """Whether a collision verdict is latched (until :meth:`reset` or the release rule)."""
        return self._latched if self._fused is None else self._fused.latched

    def step(
        self,
        t: float,
        q: ArrayLike,
        tau_m: ArrayLike,
        tau_j: ArrayLike | None = None,
        *,
        qd: ArrayLike | None = None,
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
        qd : array-like of shape (n_dof,), optional
            Measured joint velocities [rad/s]. They replace the estimate for
            this sample (the estimator keeps running), as a log's ``qd``
            columns do in :meth:`process`; the momentum observers only.

        Returns
        -------
        Verdict
            ``"ok"``, ``"collision"`` (latched), ``"settling"`` or ``"fault"``;
            a fault leaves every state exactly as it was (see
            :mod:`sensorless.monitor.policy`).
        """
        compiled = self._compiled
        if compiled is not None and qd is None:  # the compiled stream's common sample
            function, model, buffers, fused = compiled
            out = _empty((3, self._n_dof))
            sensed = tau_j if self._joint else tau_m
            try:  # a Python float: numba's dispatcher types a NumPy scalar slowly
                time = float(t)
                code = function(time, q, tau_m, sensed, model, buffers, out)
            except Exception:  # a type its signatures refuse: the checks below say why
                code = UNJUDGED
            status = code & 15
            if status < FAULT:
                joints = () if code < _JOINTS_CODE else fused.joints(code)
                event = fused.closed(self._method) if code & EVENT else None
                return Verdict._of_rows(_STATUSES[status], time, joints, out, event)
            if status != UNJUDGED:
                reason = fused.reason(status)
                sample = cast("tuple[FloatArray, ...]", (q, _EMPTY, tau_m, sensed))
                return self._fault(time, self._fused_fault(fused, reason, time, sample))
        try:
            time = float(t)
        except (TypeError, ValueError, OverflowError):
            return self._fault(math.nan, f"time must be a number of seconds; got {t!r}")
        if not math.isfinite(time):
            return self._fault(time, f"time must be finite; got {time}")
        if self._fused is not None:
            return self._step_fused(self._fused, time, q, qd, tau_m, tau_j)
        if time <= self._floor:
            return self._fault(time, self._back_message(time, self._floor))
        q_arr, qd_arr, tau, message = self._sample(q, qd, tau_m, tau_j)
        if message:
            self._pending = time
            return self._fault(time, message)
        stream = self._stream
        restart = stream is None
        if stream is not None:
            step = time - stream.t
            if step < self._early:
                return self._fault(time, self._early_message(step))
            if step > self._gap:
                if self._early <= time - self._pending <= self._gap:
                    restart = True  # the stream resumed after a real gap
                else:
                    self._pending = time
                    return self._fault(time, self._gap_message(step))
        try:
            return judge(self, stream, restart, time, (q_arr, qd_arr, tau))
        except Exception as exc:  # fail-safe: no data may crash the stream
            return self._fault(time, f"the sample could not be processed: {exc!r}")

    def _back_message(self, time: float, floor: float) -> str:
        return f"time must increase: {time!r} s after {floor!r} s"

    def _early_message(self, step: float) -> str:
        return f"time step {step:.6g} s is shorter than {self._early:.6g} s (dt/2)"

    def _gap_message(self, step: float) -> str:
        return (
            f"gap: {step:.6g} s since the last sample; expected dt = {self.dt:g} s "
            "(time in ms, or a dropped sample?)"
        )

    def _step_fused(
        self, fused: FusedStream | NumpyStream, time: float, q: Any, qd: Any, tau_m: Any, tau_j: Any
    ) -> Verdict:
        """:meth:`step` for a finite time, on the compiled path (which checks the floor)."""
        n = self._n_dof
        try:  # as_sample's conversion, inline: this path runs once per sample
            q_arr, tau_arr = _contiguous(q, _FLOAT), _contiguous(tau_m, _FLOAT)
            common = qd is None and not self._joint and q_arr.shape == tau_arr.shape == (n,)
        except (TypeError, ValueError, OverflowError):
            common = False
        if common:
            sample = (q_arr, _EMPTY, tau_arr, tau_arr)
        else:
            q_arr, message = as_sample(q, n, "q")
            qd_arr, message_v = (_EMPTY, "") if qd is None else as_sample(qd, n, "qd")
            tau_arr, message_m = as_sample(tau_m, n, "tau_m")
            sensed, message_j = as_sample(tau_j, n, "tau_j") if self._joint else (tau_arr, "")
            if message or message_v or message_m or message_j:  # the Python rules say which
                if time <= fused.floor:
                    return self._fault(time, self._back_message(time, fused.floor))
                fused.refuse(time)
                return self._fault(time, self._sample(q, qd, tau_m, tau_j)[3])
            sample = (q_arr, qd_arr, tau_arr, sensed)
        out = _empty((3, n))
        try:
            status, joints, event = fused.run(time, sample, out, self._method)
        except Exception as exc:  # fail-safe: no data may crash the stream
            return self._fault(time, f"the sample could not be processed: {exc!r}")
        if status in _STATUSES:
            return Verdict._of_rows(cast(Any, status), time, joints, out, event)
        return self._fault(time, self._fused_fault(fused, status, time, sample))

    def _fused_fault(
        self,
        fused: FusedStream | NumpyStream,
        reason: str,
        time: float,
        sample: tuple[FloatArray, ...],
    ) -> str:
        """The message of a fault the compiled step found: that of the Python path."""
        if reason == "time":
            return self._back_message(time, fused.floor)
        if reason == "early":
            return self._early_message(time - fused.last)
        if reason == "gap":
            return self._gap_message(time - fused.last)
        return value_fault(self.limits, reason, sample, fused.velocity)

    def _sample(
        self, q: Any, qd: Any, tau_m: Any, tau_j: Any
    ) -> tuple[FloatArray, FloatArray | None, FloatArray, str]:
        """The checked position, measured velocity (or None) and torque, or a fault message."""
        n = self.robot.n_dof
        joint = self.settings.kind == "joint"
        if joint and tau_j is None:
            return _EMPTY, None, _EMPTY, "the joint-torque observer needs tau_j"
        if qd is not None and self.settings.kind == "acceleration":
            return _EMPTY, None, _EMPTY, "the acceleration observer estimates qd; give none"
        q_arr, message = as_sample(q, n, "q")
        if message:
            return _EMPTY, None, _EMPTY, message
        if not self.limits.position_ok(q_arr):
            return _EMPTY, None, _EMPTY, self.limits.describe("q", q_arr)
        qd_arr = None
        if qd is not None:
            qd_arr, message = as_sample(qd, n, "qd")
            if message:
                return _EMPTY, None, _EMPTY, message
        torques = {"tau_m": tau_m, "tau_j": tau_j} if joint else {"tau_m": tau_m}
        tau = _EMPTY
        for name, value in torques.items():
            tau, message = as_sample(value, n, name)
            if message:
                return _EMPTY, None, _EMPTY, message
            if not self.limits.torque_ok(tau):
                return _EMPTY, None, _EMPTY, self.limits.describe(name, tau)
        return q_arr, qd_arr, tau, ""

    def _fault(self, time: float, message: str) -> Verdict:
        nan = np.full(self._n_dof, np.nan)
        return Verdict("fault", time, (), nan, nan.copy(), nan.copy(), None, message)

    def finish(self) -> Event | None:
        """Close the stream: the event still open, if any."""
        if self._fused is not None:
            return self._fused.finish(self._method)
        stream = self._stream
        if stream is None or stream.detector is None:
            return None
        event, stream.detector = self.detector.finish(stream.detector)
        return event

    @property
    def estimator(self) -> Any:
        """The velocity/acceleration estimator of the stream."""
        return self._estimator


_EMPTY = np.empty(0)
_FLOAT = np.dtype(np.float64)
_contiguous, _empty = np.ascontiguousarray, np.empty
