"""The monitor over a whole log: the stream's rules, computed over whole arrays.

A log is cut into segments at the samples the stream would call faults
(outside the limits of :class:`~sensorless.monitor.policy.StreamPolicy`, a
velocity estimate beyond its limit, a non-finite observer output). Each
segment runs as a stream that restarts at its first sample: observer from
scratch, settling window, then threshold and detector. Units SI and radians;
time along axis 0, arrays of shape ``(n_samples, n_dof)``.
"""

from __future__ import annotations

import copy
import dataclasses
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, cast

import numpy as np
import pandas as pd

from .._validation import FloatArray
from ..detection import TIME_TOLERANCE
from ..exceptions import InputValueError
from ..io import Log
from ..signals import Event, ObserverSignals

if TYPE_CHECKING:
    from ._fused import FusedStream
    from .policy import Limits
    from .stream import CollisionMonitor

__all__ = ["FaultSpan", "MonitorRun"]

_SERIES = ("residual", "model_torque", "friction", "sign", "velocity", "acceleration")
OBSERVER_FAULT = "the observer's output is not finite for this sample"
BOUNDS_FAULT = "the threshold's bounds are not finite for this sample"


@dataclass(frozen=True)
class FaultSpan:
    """Consecutive samples of a log that the monitor refused.

    Attributes
    ----------
    start, end : float
        Time of the first and the last refused sample [s].
    n_samples : int
        Number of refused samples.
    reason : str
        Why the first of them was refused.
    """

    start: float
    end: float
    n_samples: int
    reason: str


@dataclass(frozen=True, eq=False)
class MonitorRun:
    """What :meth:`CollisionMonitor.process` found in a log.

    Attributes
    ----------
    signals : ObserverSignals
        Observer signals of the whole log; NaN at refused samples.
    events : list of Event
        Detected events, in time order.
    faults : list of FaultSpan
        Refused spans; the stream restarts after each.
    settling : ndarray of bool, shape (n_samples,)
        Samples inside a settling window (judged by nothing).
    """

    signals: ObserverSignals
    events: list[Event]
    faults: list[FaultSpan]
    settling: np.ndarray

    def faults_to_pandas(self) -> pd.DataFrame:
        """One row per fault span: start [s], end [s], n_samples, reason."""
        return pd.DataFrame(
            [(f.start, f.end, f.n_samples, f.reason) for f in self.faults],
            columns=["start", "end", "n_samples", "reason"],
        )


def run_log(monitor: CollisionMonitor, log: Log, *, strict: bool) -> MonitorRun:
    """Process ``log`` as :meth:`CollisionMonitor.step` would, segment by segment."""
    kind = monitor.settings.kind
    tau = np.asarray(log.tau_j if kind == "joint" else log.tau_m)
    if tau is None or tau.ndim != 2:
        group = "tau_j" if kind == "joint" else "tau_m"
        raise InputValueError(f"observer kind {kind!r} needs the {group} columns; the log has none")
    t, q = np.asarray(log.t), np.asarray(log.q)
    # A measured velocity (real arms log it) replaces the estimate, as in ``observe``.
    measured = None if kind == "acceleration" or log.qd is None else np.asarray(log.qd)
    fused = monitor._fused
    if fused is not None and monitor.backend == "numba":  # numpy's stream: the arrays below
        return _run_fused(monitor, cast("FusedStream", fused), log, measured, strict=strict)
    if monitor.adaptation is not None:
        return _run_stepwise(monitor, log, measured, strict=strict)
    n_samples, n_dof = q.shape
    bad = monitor.limits.bad_rows(q, measured, tau)
    reasons: dict[int, str] = {}  # refused inside a segment, by sample index
    out = {name: np.full((n_samples, n_dof), np.nan) for name in _SERIES}
    settling = np.zeros(n_samples, dtype=bool)
    events: list[Event] = []
    start = 0
    while start < n_samples:
        if bad[start]:
            start += 1
            continue
        stop = start + int(np.argmax(bad[start:])) if bad[start:].any() else n_samples
        end, reason = _segment(monitor, t, q, measured, tau, (start, stop), out, settling, events)
        if end < stop:  # a fault found inside the segment: refuse that sample, restart after it
            bad[end] = True
            reasons[end] = reason
        start = end + 1 if end < stop else stop
    if strict and bad.any():
        k = int(np.flatnonzero(bad)[0])
        why = reasons.get(k) or _reason(
            monitor, q[k], None if measured is None else measured[k], tau[k]
        )
        raise InputValueError(f"sample {k} (t = {t[k]:.6g} s) is a fault: {why}")
    faults = _spans(
        t,
        bad,
        lambda k: (
            reasons.get(k)
            or _reason(monitor, q[k], None if measured is None else measured[k], tau[k])
        ),
    )
    return _result(monitor, log, out, measured is not None, (events, faults, settling))


def _result(
    monitor: CollisionMonitor,
    log: Log,
    out: dict[str, FloatArray],
    measured: bool,
    found: tuple[list[Event], list[FaultSpan], np.ndarray],
) -> MonitorRun:
    """The :class:`MonitorRun` of ``log`` from the series ``out`` and what was found."""
    events, faults, settling = found
    kind = monitor.settings.kind
    signals = ObserverSignals(
        t=np.asarray(log.t),
        residual=out["residual"],
        model_torque=out["model_torque"],
        friction=out["friction"],
        sign=out["sign"],
        velocity=out["velocity"],
        gain=monitor._observer.gain if kind != "acceleration" else np.full(log.n_dof, np.nan),
        kind=kind,
        robot=monitor.robot.name,
        fingerprint=monitor.robot.fingerprint,
        position=np.asarray(log.q),
        acceleration=out["acceleration"] if kind == "acceleration" else None,
        metadata={
            **log.metadata,
            "observer": {
                **monitor._observer.settings(),
                "velocity": "measured" if measured else "filter",
            },
            "faults": len(faults),
        },
    )
    return MonitorRun(signals, sorted(events, key=lambda e: e.start), faults, settling)


def _run_fused(
    monitor: CollisionMonitor,
    fused: FusedStream,
    log: Log,
    measured: FloatArray | None,
    *,
    strict: bool,
) -> MonitorRun:
    """:func:`run_log` on the compiled path: the stream's kernel over the whole log."""
    t = np.ascontiguousarray(log.t, dtype=np.float64)
    q = np.ascontiguousarray(log.q, dtype=np.float64)
    n_samples = q.shape[0]
    qd = (
        np.empty((n_samples, 0))
        if measured is None
        else np.ascontiguousarray(measured, dtype=np.float64)
    )
    sensed = monitor.settings.kind == "joint"
    tau_j = np.ascontiguousarray(log.tau_j if sensed else log.tau_m, dtype=np.float64)
    # The joint-torque stream checks the motor torques' limits too, when the log has them.
    tau_m = tau_j if log.tau_m is None else np.ascontiguousarray(log.tau_m, dtype=np.float64)
    codes, series, events = fused.block(t, (q, qd, tau_m, tau_j), monitor._method)
    status = codes & 15
    bad = status >= fused.FAULT
    settling = status == fused.SETTLING
    names = ("residual", "model_torque", "friction", "sign", "velocity")
    out = {name: series[row] for name, row in zip(names, (0, 3, 4, 5, 6), strict=True)}

    def reason(k: int) -> str:
        return _fused_reason(
            monitor, fused.reason(int(status[k])), k, (t, q, qd, tau_m, tau_j), series[6, k]
        )

    if strict and bad.any():
        k = int(np.flatnonzero(bad)[0])
        raise InputValueError(f"sample {k} (t = {t[k]:.6g} s) is a fault: {reason(k)}")
    return _result(
        monitor, log, out, measured is not None, (events, _spans(t, bad, reason), settling)
    )


def _run_stepwise(
    monitor: CollisionMonitor, log: Log, measured: FloatArray | None, *, strict: bool
) -> MonitorRun:
    """:func:`run_log` for a monitor that learns as it goes (drift adaptation).

    What it learns depends on its own verdicts, so the log runs through
    :meth:`CollisionMonitor.step` sample by sample, on a copy of the monitor
    (the live stream's state is left alone).
    """
    stream = copy.copy(monitor)
    stream.reset()
    stream._record = []
    t, q = np.asarray(log.t), np.asarray(log.q)
    sensed = monitor.settings.kind == "joint"
    tau_j = np.asarray(log.tau_j) if sensed else None
    tau_m = np.asarray(log.tau_m if log.tau_m is not None else log.tau_j)
    events: list[Event] = []
    bad = np.zeros(t.size, dtype=bool)
    settling = np.zeros(t.size, dtype=bool)
    messages: dict[int, str] = {}
    for k in range(t.size):
        verdict = stream.step(
            t[k],
            q[k],
            tau_m[k],
            None if tau_j is None else tau_j[k],
            qd=None if measured is None else measured[k],
        )
        if verdict.status == "fault":
            if strict:
                raise InputValueError(
                    f"sample {k} (t = {t[k]:.6g} s) is a fault: {verdict.message}"
                )
            bad[k], messages[k] = True, verdict.message
        settling[k] = verdict.status == "settling"
        if verdict.event is not None:
            events.append(verdict.event)
    last = stream.finish()
    events += [] if last is None else [last]
    out = {name: np.full(q.shape, np.nan) for name in _SERIES}
    rows = np.searchsorted(t, [time for time, _, _ in stream._record])
    for k, (_, sample, velocity) in zip(rows, stream._record, strict=True):
        for name in ("residual", "model_torque", "friction", "sign"):
            out[name][k] = getattr(sample, name)
        out["velocity"][k] = velocity
    faults = _spans(t, bad, messages.__getitem__)
    return _result(monitor, log, out, measured is not None, (events, faults, settling))


def value_fault(
    limits: Limits, reason: str, sample: tuple[FloatArray, ...], velocity: FloatArray
) -> str:
    """The message of a value fault the kernel found: that of the Python path.

    ``reason`` is one of the kernel's ``REASONS`` but the time rules; ``sample``
    is (q, measured q̇ or empty, τ_m, τ_J) of the sample and ``velocity`` the
    velocity it ran with [rad/s].
    """
    if reason in ("q", "tau_m", "tau_j"):
        return limits.describe(reason, sample[("q", "", "tau_m", "tau_j").index(reason)])
    if reason == "qd":
        return limits.describe("qd", velocity)
    return OBSERVER_FAULT if reason == "observer" else BOUNDS_FAULT


def _fused_reason(
    monitor: CollisionMonitor,
    reason: str,
    k: int,
    columns: tuple[FloatArray, ...],
    velocity: FloatArray,
) -> str:
    """The message of the fault the kernel found at sample ``k`` of a log."""
    t, q, qd, tau_m, tau_j = columns
    if reason in ("time", "early", "gap"):
        return f"the time rule {reason!r} refused t = {t[k]:.9g} s (previous {t[k - 1]:.9g} s)"
    return value_fault(monitor.limits, reason, (q[k], qd[k], tau_m[k], tau_j[k]), velocity)


def _segment(
    monitor: CollisionMonitor,
    t: FloatArray,
    q: FloatArray,
    measured: FloatArray | None,
    tau: FloatArray,
    span: tuple[int, int],
    out: dict[str, FloatArray],
    settling: np.ndarray,
    events: list[Event],
) -> tuple[int, str]:
    """Run samples [start, stop) = ``span`` as one stream; return where it ended and why.

    The stream ends early at the first sample the stream would refuse (a
    velocity estimate beyond its limit, a non-finite observer output): the
    samples before it are kept, and that index and the reason are returned,
    else ``(stop, "")``.
    """
    start, stop = span
    block = slice(start, stop)
    estimator = monitor.estimator
    initial = estimator.initial_state(q[start])
    derivatives, _ = estimator._run(q[block], initial)
    velocity, acceleration = derivatives.velocity, derivatives.acceleration
    if measured is not None:
        velocity = measured[block]
    observer: Any = monitor._observer
    if monitor.settings.kind == "acceleration":
        signals, _ = observer._run_checked(t[block], q[block], tau[block], initial)
    else:
        signals = _momentum_signals(observer, t, q, measured, tau, span, velocity)
    finite = np.isfinite(
        np.stack([signals.residual, signals.model_torque, signals.friction, signals.sign])
    ).all(axis=(0, 2))
    if monitor.settings.kind == "acceleration" or _uses_acceleration(monitor):
        finite &= np.isfinite(acceleration).all(axis=1)
    fast = ~(np.abs(velocity) <= monitor.limits.velocity).all(axis=1)
    refused = ~finite | fast
    end = stop
    reason = ""
    if refused.any():
        k = int(np.argmax(refused))
        end = start + k
        reason = monitor.limits.describe("qd", velocity[k]) if fast[k] else OBSERVER_FAULT
        if k == 0:
            return end, reason
        # Everything here is causal: the samples before k are those of a stream ending there.
        stop, block = end, slice(start, end)
        signals = _rows(signals, slice(0, k), None)
        velocity = velocity[:k]
        acceleration = None if acceleration is None else acceleration[:k]
    for name in _SERIES:
        values = acceleration if name == "acceleration" else getattr(signals, name)
        if values is not None:
            out[name][block] = values
    settled = int(
        np.searchsorted(t[block] - t[start], monitor.settle - TIME_TOLERANCE, side="left")
    )
    settling[start : start + settled] = True
    if settled < stop - start:
        part = _rows(signals, slice(settled, None), acceleration)
        events.extend(monitor.detector.detect(part))
    return end, reason


def _momentum_signals(
    observer: Any,
    t: FloatArray,
    q: FloatArray,
    measured: FloatArray | None,
    tau: FloatArray,
    span: tuple[int, int],
    velocity: FloatArray,
) -> ObserverSignals:
    """The momentum observer over [start, stop), started as the stream starts it.

    The first sample starts it at (q, q̇) with q̇ measured or at rest; the
    second, whose velocity estimate is the first one, starts it again there,
    so a segment that begins in motion has no start-up excursion.
    """
    start, stop = span
    velocity = np.ascontiguousarray(velocity)
    first = np.zeros((1, q.shape[1])) if measured is None else measured[start : start + 1]
    starts = [(start, first)] + ([(start + 1, velocity[1:2])] if stop > start + 1 else [])
    parts = []
    for k, (a, v0) in enumerate(starts):
        b = starts[k + 1][0] if k + 1 < len(starts) else stop
        state = observer._initial_state_checked(q[a : a + 1], v0)
        v = velocity[a - start : b - start]
        part, _ = observer._run_checked(t[a:b], q[a:b], v, tau[a:b], state)
        parts.append(part)
    if len(parts) == 1:
        return parts[0]
    return dataclasses.replace(
        parts[0],
        t=np.concatenate([p.t for p in parts]),
        **{
            name: np.concatenate([getattr(p, name) for p in parts])
            for name in ("residual", "model_torque", "friction", "sign", "velocity", "position")
        },
    )


def _uses_acceleration(monitor: CollisionMonitor) -> bool:
    return bool(monitor._outputs[2])


def _rows(
    signals: ObserverSignals, rows: slice, acceleration: FloatArray | None
) -> ObserverSignals:
    """The samples ``rows`` of ``signals``, with ``acceleration`` as its acceleration."""
    return ObserverSignals(
        t=signals.t[rows],
        residual=signals.residual[rows],
        model_torque=signals.model_torque[rows],
        friction=signals.friction[rows],
        sign=signals.sign[rows],
        velocity=signals.velocity[rows],
        gain=signals.gain,
        kind=signals.kind,
        robot=signals.robot,
        fingerprint=signals.fingerprint,
        position=None if signals.position is None else signals.position[rows],
        acceleration=None if acceleration is None else acceleration[rows],
        metadata=signals.metadata,
    )


def _reason(
    monitor: CollisionMonitor, q: FloatArray, qd: FloatArray | None, tau: FloatArray
) -> str:
    limits = monitor.limits
    if not limits.position_ok(q):
        return limits.describe("q", q)
    if qd is not None and not limits.velocity_ok(qd):
        return limits.describe("qd", qd)
    return limits.describe("tau_j" if monitor.settings.kind == "joint" else "tau_m", tau)


def _spans(t: FloatArray, bad: np.ndarray, reason: Any) -> list[FaultSpan]:
    """Group consecutive refused samples into spans."""
    if not bad.any():
        return []
    edges = np.diff(np.concatenate([[0], bad.astype(np.int8), [0]]))
    starts, stops = np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)
    return [
        FaultSpan(float(t[a]), float(t[b - 1]), int(b - a), reason(int(a)))
        for a, b in zip(starts, stops, strict=True)
    ]
