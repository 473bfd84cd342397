"""The reference stream of :class:`~sensorless.monitor.CollisionMonitor`: the library, composed.

:func:`judge` runs one sample whose inputs the monitor has checked through
the estimator, the observer, the drift adapter, the threshold and the
detector (see ``ARCHITECTURE.md``, "one live sample"), and commits the new
:class:`PythonStream` state only when every output is finite; :func:`latch`
holds a collision until it is released. The compiled and numpy streams
(:mod:`._compiled`, :mod:`._numpy_stream`) do the same with numbers and are
held to this one by the tests. Units SI and radians.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np

from .._validation import FloatArray
from ..detection import TIME_TOLERANCE, DetectorState, Verdict
from ..observers import ObserverSample, ObserverState
from ..observers.adaptive import AdapterState
from ..signals import Event
from ..thresholds import ThresholdInputs
from .batch import BOUNDS_FAULT, OBSERVER_FAULT

if TYPE_CHECKING:
    from .stream import CollisionMonitor

__all__ = ["PythonStream", "adapter_start", "judge", "latch", "with_status"]


@dataclass
class PythonStream:
    """Mutable state of a live stream; replaced field by field only after a good sample."""

    start: float  # time of the (re)start [s]
    t: float  # time of the last accepted sample [s]
    estimator: Any  # section states (position, velocity, acceleration) of the estimator
    observer: ObserverState | None  # None for the acceleration-based estimate
    detector: DetectorState | None  # None while settling
    adapter: AdapterState | None = None  # drift adaptation, if any
    quiet_from: float = -math.inf  # the adapter may learn from this time on [s]


def judge(
    monitor: CollisionMonitor,
    stream: PythonStream | None,
    restart: bool,
    time: float,
    columns: tuple[FloatArray, FloatArray | None, FloatArray],
) -> Verdict:
    """Run a sample with good inputs through the pipeline; commit only if all is finite.

    ``columns``: q [rad], the measured q̇ [rad/s] or None, τ [N m].
    """
    q, measured, tau = columns
    closed: Event | None = None
    if restart:
        if stream is not None and stream.detector is not None:
            closed = monitor.detector.finish(stream.detector)[0]
        initial = monitor._estimator.initial_state(q)
        estimator = (initial.position, initial.velocity, initial.acceleration)
        observer = (
            None
            if monitor.settings.kind == "acceleration"
            else monitor._observer._initial_state_checked(
                q[None], np.zeros((1, q.size)) if measured is None else measured[None]
            )
        )
        # What the drift adapter learned survives the restart; its filters start anew.
        learned = None if stream is None else stream.adapter
        stream = PythonStream(
            time, time, estimator, observer, None, adapter_start(monitor, learned)
        )
    assert stream is not None  # set above on a restart
    adapter = stream.adapter
    (_, velocity, acceleration), estimator = monitor._estimator._step_outputs(
        q, stream.estimator, monitor._outputs
    )
    velocity = cast(FloatArray, velocity if measured is None else measured)
    if not monitor.limits.velocity_ok(velocity):
        monitor._pending = time
        return monitor._fault(time, monitor.limits.describe("qd", velocity))
    observer = stream.observer
    if observer is None:  # acceleration-based estimate: an algebraic function of the sample
        assert acceleration is not None  # always selected for this observer
        out = monitor._observer._estimate(q[None], velocity[None], acceleration[None], tau[None])
        sample = ObserverSample(*(row[0] for row in out))
        outputs = np.stack(sample)
    else:
        if not restart and stream.t == stream.start:
            # The first velocity estimate comes with the second sample: the observer
            # starts there, so a stream that begins in motion has no start-up excursion.
            observer = monitor._observer._initial_state_checked(q[None], velocity[None])
            adapter = adapter_start(monitor, adapter)
        sample, observer = monitor._observer._step_checked(observer, q, velocity, tau)
        outputs = observer.filtered
    if not np.isfinite(outputs).all() or (
        acceleration is not None and not np.isfinite(acceleration).all()
    ):
        monitor._pending = time
        return monitor._fault(time, OBSERVER_FAULT)
    residual, model_torque, friction, sign = sample
    settling = time - stream.start < monitor.settle - TIME_TOLERANCE
    if monitor._adapter is not None and adapter is not None:
        trusted = not settling and not monitor._latched and time >= stream.quiet_from
        residual, adapter = monitor._adapter._step_checked(
            adapter, residual, velocity, monitor._trust[int(trusted)], model_torque
        )
    detector = stream.detector
    if settling:
        nan = np.full(monitor.robot.n_dof, np.nan)
        verdict = Verdict("settling", time, (), residual, nan, nan.copy(), closed)
    else:
        if detector is None:
            detector = monitor.detector.initial_state(monitor.dt)
        inputs = ThresholdInputs(
            model_torque[None],
            friction[None],
            sign[None],
            velocity[None],
            q[None],
            None if acceleration is None else acceleration[None],
        )
        verdict, detector = monitor.detector._step_checked(detector, residual, inputs, time)
        if np.isnan(verdict.lower).any() or np.isnan(verdict.upper).any():
            monitor._pending = time
            return monitor._fault(time, BOUNDS_FAULT)
        if closed is not None and verdict.event is None:
            verdict = with_status(verdict, verdict.status, closed)
        verdict = latch(monitor, verdict)
    # Commit: the sample was good from end to end.
    stream.t = time
    stream.estimator = estimator
    stream.observer = observer
    stream.detector = detector
    stream.adapter = adapter
    if verdict.joints or verdict.status == "collision":
        stream.quiet_from = time + monitor._guard
    if monitor._record is not None:
        monitor._record.append((time, sample._replace(residual=residual), velocity))
    monitor._stream = stream
    monitor._floor = time
    monitor._pending = -math.inf
    return verdict


def adapter_start(monitor: CollisionMonitor, learned: AdapterState | None) -> AdapterState | None:
    """The drift adapter's state at a (re)start: filters from zero, θ and P kept."""
    if monitor._adapter is None:
        return None
    if learned is None:
        return monitor._adapter.initial_state()
    return monitor._adapter.restart(learned)


def latch(monitor: CollisionMonitor, verdict: Verdict) -> Verdict:
    """Apply the latch: a collision stays a collision until released."""
    if verdict.status == "collision":
        monitor._latched = True
        monitor._inside_since = math.nan
        return verdict
    if not monitor._latched:
        return verdict
    release = monitor.policy.release
    if release is not None:
        if verdict.joints:
            monitor._inside_since = math.nan
        elif math.isnan(monitor._inside_since):
            monitor._inside_since = verdict.t
        if verdict.t - monitor._inside_since >= release - TIME_TOLERANCE:
            monitor._latched = False
            monitor._inside_since = math.nan
            return verdict
    return with_status(verdict, "collision", verdict.event)


def with_status(verdict: Verdict, status: Any, event: Event | None) -> Verdict:
    """``verdict`` with another status and event."""
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
