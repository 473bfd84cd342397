"""The detector: a residual outside its threshold bounds, grouped into events.

See :mod:`sensorless.detection` for the rules. Units SI and radians; arrays
have time along axis 0 and shape ``(n_samples, n_dof)``.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, check_dt, check_duration, check_type
from ..exceptions import InputTypeError, InputValueError
from ..signals import Event, ObserverSignals
from ..thresholds.base import Threshold
from ..thresholds.checks import as_inputs, as_samples, check_joints
from ..thresholds.files import family_name
from ..thresholds.state import ThresholdInputs
from ._results import BoolArray, DetectionResult, DetectorState, Verdict, _merged

__all__ = ["TIME_TOLERANCE", "Detector"]

TIME_TOLERANCE = 1e-9
"""A duration or a gap within this of ``min_duration`` or ``hold`` counts as equal to it [s].

Event times are sample times, so an event of k periods lasts k·dt only up to
rounding (0.105 - 0.1 = 0.004999… s): without a tolerance, ``min_duration`` =
5 ms would drop a 6-sample event at 1 kHz, and a gap of exactly ``hold``
would merge or not by chance. The rules are ``end - start >= min_duration -
TIME_TOLERANCE`` (kept) and ``gap < hold - TIME_TOLERANCE`` (merged). 1 ns
is above the rounding of a difference of time stamps below 10⁶ s and far
below any sample period.
"""

_STREAM_INPUTS = ("residual", "model_torque", "friction", "sign", "velocity")


def _excursion(residual: FloatArray, lower: FloatArray, upper: FloatArray) -> FloatArray:
    """How far beyond its bounds each residual is [N m] (> 0 outside)."""
    return np.asarray(np.maximum(residual - upper, lower - residual))


class Detector:
    """Detect collisions as residuals outside the bounds of a fitted threshold.

    Parameters
    ----------
    threshold : Threshold
        A fitted threshold of one residual (any family; for a
        :class:`~sensorless.thresholds.CombinedVelocityThreshold`, its
        ``for_kind(kind)``).
    joints : sequence of int, optional
        Joints to monitor (1-based); by default those of the threshold.
    min_duration : float
        Events shorter than this (``end - start``) are dropped [s], >= 0.
        An event of k samples lasts (k - 1)·dt, so at a period dt it needs
        ⌈min_duration/dt⌉ + 1 samples: 6 at 1 kHz, 2 at 100 Hz for 5 ms.
    hold : float
        Events separated by less than this are merged [s], >= 0.

    Notes
    -----
    Durations and gaps are compared up to :data:`TIME_TOLERANCE` (1 ns), so a
    whole number of sample periods equal to ``min_duration`` or ``hold`` counts
    as equal despite the rounding of the time stamps.
    """

    def __init__(
        self,
        threshold: Threshold,
        joints: Any = None,
        min_duration: float = 0.0,
        hold: float = 0.0,
    ) -> None:
        if not isinstance(threshold, Threshold):
            raise InputTypeError(
                f"threshold must be a Threshold (e.g. ConstantThreshold); got "
                f"{type(threshold).__name__}"
            )
        self.threshold = threshold
        self.joints = joints
        self.min_duration = check_duration(min_duration, "min_duration")
        self.hold = check_duration(hold, "hold")

    def __repr__(self) -> str:
        return (
            f"Detector({self.threshold!r}, joints={self.joints!r}, "
            f"min_duration={self.min_duration!r}, hold={self.hold!r})"
        )

    @property
    def monitored_joints(self) -> tuple[int, ...]:
        """Monitored joints, 1-based (needs a fitted threshold)."""
        fitted = self.threshold.monitored_joints_  # raises NotFittedError before fit
        return fitted if self.joints is None else check_joints(self.joints, self.threshold.n_dof_)

    # ----------------------------------------------------------------- events

    def _close(self, event: Event | None) -> Event | None:
        if event is None or not _lasted(event.duration, self.min_duration):
            return None
        return dataclasses.replace(event, method=family_name(self.threshold))

    def _group(
        self, t: FloatArray, excursion: FloatArray, residual: FloatArray, monitored: tuple[int, ...]
    ) -> list[Event]:
        """Events of accepted samples; ``excursion`` and ``residual`` of ``monitored`` joints."""
        joints = np.asarray(monitored)
        outside = excursion > 0.0
        rows = np.flatnonzero(outside.any(axis=1))
        if rows.size == 0:
            return []
        breaks = np.flatnonzero(np.diff(rows) > 1)
        starts = np.concatenate([rows[:1], rows[breaks + 1]])
        ends = np.concatenate([rows[breaks], rows[-1:]])
        events: list[Event] = []
        current: Event | None = None
        for first, last in zip(starts, ends, strict=True):
            segment = excursion[first : last + 1]
            row, col = np.unravel_index(int(np.argmax(segment)), segment.shape)
            run = Event(
                start=float(t[first]),
                end=float(t[last]),
                joints=tuple(int(j) for j in joints[outside[first : last + 1].any(axis=0)]),
                peak=float(segment[row, col]),
                peak_residual=float(residual[first + row, col]),
            )
            if current is not None and not _lasted(run.start - current.end, self.hold):
                current = _merged(current, run)
                continue
            closed = self._close(current)
            if closed is not None:
                events.append(closed)
            current = run
        closed = self._close(current)
        if closed is not None:
            events.append(closed)
        return events

    # ----------------------------------------------------------------- batch

    def run(self, signals: ObserverSignals, *, skip_nonfinite: bool = False) -> DetectionResult:
        """Bounds, outside samples and events over a recorded run.

        Parameters
        ----------
        signals : ObserverSignals
            Run of the robot, signal kind and gain the threshold was fitted for.
        skip_nonfinite : bool
            Skip samples with NaN/inf or a time that does not increase, as
            :meth:`step` does; by default they are an error.

        Returns
        -------
        DetectionResult
        """
        threshold = self.threshold
        threshold.check_signals(signals)
        joints = self.monitored_joints
        cols = np.asarray(joints) - 1
        valid = _valid_samples(signals)
        if not skip_nonfinite and not valid.all():
            raise InputValueError(_describe_invalid(signals, valid))
        shape = signals.residual.shape
        lower = np.full(shape, np.nan)
        upper = np.full(shape, np.nan)
        rows = np.flatnonzero(valid)
        dt = threshold.dt_
        if valid.all() and rows.size:
            # valid samples have finite, increasing time: only the family's own rule is left
            dt = threshold._period(signals.t, "signals")
        elif rows.size > 1:
            dt = float(np.median(np.diff(signals.t[rows])))
        if rows.size:
            # From here on the same path as the stream: no kind, as step has none.
            inputs = ThresholdInputs.from_signals(signals, rows)
            lower[rows], upper[rows] = threshold._bounds_checked(inputs, dt, None)
        excursion = _excursion(signals.residual, lower, upper)[:, cols]
        outside = np.zeros(shape, dtype=bool)
        outside[:, cols] = excursion > 0.0
        events = self._group(
            signals.t[valid], excursion[valid], signals.residual[valid][:, cols], joints
        )
        return DetectionResult(
            t=signals.t,
            residual=signals.residual,
            lower=lower,
            upper=upper,
            outside=outside,
            valid=valid,
            events=events,
            method=family_name(threshold),
            joints=joints,
            dt=dt,
        )

    def detect(self, signals: ObserverSignals, *, skip_nonfinite: bool = False) -> list[Event]:
        """Events of a recorded run (:meth:`run` without the per-sample arrays)."""
        return self.run(signals, skip_nonfinite=skip_nonfinite).events

    # ----------------------------------------------------------------- streaming

    def initial_state(self, dt: float | None = None) -> DetectorState:
        """State before the first sample of a stream.

        Parameters
        ----------
        dt : float, optional
            Sample period of the stream [s]; by default ``dt_`` of the
            threshold's fit runs. The threshold's filters start at the first
            accepted sample, held since forever.
        """
        _ = self.monitored_joints  # raises NotFittedError or a joints error before the stream
        period = check_dt(self.threshold.dt_ if dt is None else dt)
        return DetectorState(dt=period)

    def step(
        self,
        state: DetectorState,
        residual: ArrayLike,
        model_torque: ArrayLike,
        friction: ArrayLike,
        sign: ArrayLike,
        velocity: ArrayLike,
        t: float,
        *,
        position: ArrayLike | None = None,
        acceleration: ArrayLike | None = None,
    ) -> tuple[Verdict, DetectorState]:
        """Judge one sample of a stream.

        Parameters
        ----------
        state : DetectorState
            From :meth:`initial_state` or the previous call.
        residual : array-like of shape (n_dof,)
            Residual r̂ [N m].
        model_torque, friction, sign, velocity : array-like of shape (n_dof,)
            h [N m], K_I/(s+K_I)·τ̂_fr [N m], K_I/(s+K_I)·sign(q̇) [-], q̇ [rad/s].
        t : float
            Time of the sample [s].
        position, acceleration : array-like of shape (n_dof,), optional
            q [rad] and q̈ [rad/s²], for thresholds that use them.

        Returns
        -------
        verdict : Verdict
        state : DetectorState
            State for the next sample (the same object after a fault).

        Raises
        ------
        DimensionError
            An input of the wrong shape (a programming error, not a data fault).
        """
        check_type(state, DetectorState, "state", " from initial_state or step")
        n_dof = self.threshold.n_dof_
        # Non-finite values are data faults, reported in the verdict; shapes are errors.
        r = as_samples(residual, n_dof, "residual", one_sample="step", allow_nonfinite=True)[0]
        inputs = as_inputs(
            n_dof,
            model_torque,
            friction,
            sign,
            velocity,
            position,
            acceleration,
            one_sample="step",
            allow_nonfinite=True,
        )
        time = _as_time(t)
        fault = _fault(r, inputs, time, state.t)
        if fault:
            nan = np.full(n_dof, np.nan)
            return Verdict("fault", time, (), r, nan, nan.copy(), None, fault), state
        return self._step_checked(state, r, inputs, time)

    def _step_checked(
        self, state: DetectorState, r: FloatArray, inputs: ThresholdInputs, time: float
    ) -> tuple[Verdict, DetectorState]:
        """The core of :meth:`step` for a sample that is not a fault.

        ``r`` has shape (n_dof,); ``inputs`` hold one sample, each of shape
        (1, n_dof), all finite (or None); ``time`` is finite and past ``state.t``.
        """
        threshold_state = state.threshold
        if threshold_state is None:
            threshold_state = self.threshold._initial_state_checked(inputs, state.dt)
        lower, upper, threshold_state = self.threshold._step_checked(threshold_state, inputs)
        cols = np.asarray(self.monitored_joints) - 1
        excursion = _excursion(r, lower, upper)[cols]
        out = excursion > 0.0
        joints = tuple((cols[out] + 1).tolist())

        ended: Event | None = None
        current = state.open_event
        if joints:
            k = int(np.argmax(excursion))
            sample = Event(time, time, joints, float(excursion[k]), float(r[cols[k]]))
            if current is not None and (
                state.outside or not _lasted(time - current.end, self.hold)
            ):
                current = _merged(current, sample)
            else:
                ended = self._close(current)
                current = sample
        elif current is not None and _lasted(time - current.end, self.hold):
            ended = self._close(current)
            current = None
        confirmed = (
            bool(joints)
            and current is not None
            and _lasted(time - current.start, self.min_duration)
        )
        verdict = Verdict("collision" if confirmed else "ok", time, joints, r, lower, upper, ended)
        return verdict, DetectorState(state.dt, threshold_state, time, bool(joints), current)

    def finish(self, state: DetectorState) -> tuple[Event | None, DetectorState]:
        """Close the event in progress at the end of a stream.

        Returns
        -------
        event : Event or None
            The open event (None if there is none or it is shorter than ``min_duration``).
        state : DetectorState
            State without an open event.
        """
        if not isinstance(state, DetectorState):
            raise InputTypeError(f"state must be a DetectorState; got {type(state).__name__}")
        event = self._close(state.open_event)
        return event, DetectorState(state.dt, state.threshold, state.t, False, None)


# --------------------------------------------------------------------------- helpers


def _lasted(span: float, limit: float) -> bool:
    """``span >= limit`` [s] up to :data:`TIME_TOLERANCE` (the rounding of time differences)."""
    return span >= limit - TIME_TOLERANCE


def _valid_samples(signals: ObserverSignals) -> BoolArray:
    """Samples a stream would accept: all inputs finite and time past every earlier one."""
    finite = np.isfinite(signals.t)
    for name in (*_STREAM_INPUTS, "position", "acceleration"):
        values = getattr(signals, name)
        if values is not None:
            finite &= np.isfinite(values).all(axis=1)
    times = np.where(finite, signals.t, -np.inf)
    latest = np.concatenate([[-np.inf], np.maximum.accumulate(times)[:-1]])
    return np.asarray(finite & (signals.t > latest))


def _describe_invalid(signals: ObserverSignals, valid: BoolArray) -> str:
    k = int(np.flatnonzero(~valid)[0])
    hint = "; pass skip_nonfinite=True to skip such samples as the streaming detector does"
    if not np.isfinite(signals.t[k]):
        return f"t[{k}] is {signals.t[k]}{hint}"
    for name in (*_STREAM_INPUTS, "position", "acceleration"):
        values = getattr(signals, name)
        if values is not None and not np.isfinite(values[k]).all():
            j = int(np.flatnonzero(~np.isfinite(values[k]))[0])
            return f"{name} is {values[k, j]} at sample {k}, joint {j + 1}{hint}"
    return (
        f"t must be strictly increasing; t[{k}] = {signals.t[k]!r} s is not past the earlier{hint}"
    )


def _as_time(t: Any) -> float:
    try:
        return float(t)
    except (TypeError, ValueError):
        return math.nan


def _fault(residual: FloatArray, inputs: ThresholdInputs, t: float, last: float) -> str:
    """Why a sample (``residual`` of shape (n_dof,), ``inputs`` of one row) must be skipped."""
    if not math.isfinite(t):
        return f"time t = {t} is not finite"
    rows = zip(("residual", *ThresholdInputs._fields), (residual[None], *inputs), strict=True)
    for name, row in rows:
        if row is not None and not np.isfinite(row).all():
            j = int(np.flatnonzero(~np.isfinite(row[0]))[0])
            return f"{name} is {row[0, j]} at joint {j + 1}"
    if t <= last:
        return f"time t = {t!r} s does not increase past the last accepted sample ({last!r} s)"
    return ""
