"""Two reaction levels: a lower *contact* band and an upper *collision* band per joint.

Arms with a two-level reflex (libfranka's ``setCollisionBehavior``: a contact
and a collision threshold per joint) react softly to a light contact and
stop on a collision. :class:`LevelledDetector` takes two fitted thresholds of
any family (:class:`~sensorless.thresholds.PhasedThreshold` included) on the
same residual:

* an **event** is an excursion beyond the contact band, grouped by the rules
  of :class:`~sensorless.detection.Detector` (``min_duration``, ``hold``);
* its **level** is ``"collision"`` when the residual also left the collision
  band during it, i.e. when the collision band alone (the same rules) gives
  an event inside it; ``"contact"`` otherwise. Those collision events are
  the event's ``collisions``: the collision level's own events, each inside
  exactly one contact event.

The contact band lies inside the collision band
-----------------------------------------------
Two thresholds fitted separately, or of two families, may cross: at some
sample the "contact" bound may lie beyond the collision bound. Two constant
thresholds whose collision band is narrower than the contact band on a
monitored joint are refused (:class:`~sensorless.exceptions.InputValueError`).
Otherwise, at every sample the contact band is clipped to the collision band
(lower bound max(l_contact, l_collision), upper bound min(u_contact,
u_collision)), and :attr:`LevelledResult.crossed` marks where that happened.
So a sample outside the collision band is always outside the contact band,
every collision event lies inside one contact event, and there are never
fewer contact events than collision events.

:meth:`LevelledDetector.run` works on a recorded run;
:meth:`LevelledDetector.initial_state`, :meth:`~LevelledDetector.step` and
:meth:`~LevelledDetector.finish` on a live stream, with the same events.
Faulty samples are skipped as by :class:`~sensorless.detection.Detector`.
Units SI and radians; arrays have time along axis 0 and shape (n_samples, n_dof).

Examples
--------
A residual that rises to 1.5 N m crosses a contact band of 0.5 N m and a
collision band of 1 N m:

>>> import numpy as np
>>> from sensorless.signals import ObserverSignals
>>> from sensorless.thresholds import ConstantThreshold
>>> def run(r):  # a residual r [N m] at 1 kHz, the other signals zero
...     z = np.zeros_like(r)
...     return ObserverSignals(np.arange(len(r)) * 1e-3, r, z, z, z, z, gain=20.0)
>>> quiet = run(np.full((10, 1), 0.1))
>>> contact = ConstantThreshold(margin=0.4).fit(quiet)      # ±0.5 N m
>>> collision = ConstantThreshold(margin=0.9).fit(quiet)    # ±1.0 N m
>>> r = np.zeros((300, 1))
>>> r[50:80, 0] = 0.8                                          # a light touch
>>> r[150:200, 0] = 1.5                                        # a collision
>>> levels = LevelledDetector(contact, collision, min_duration=0.005)
>>> [(e.start, e.level) for e in levels.detect(run(r))]
[(0.05, 'contact'), (0.15, 'collision')]
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from .._validation import FloatArray, check_type
from ..exceptions import InputTypeError, InputValueError
from ..signals import Event, ObserverSignals
from ..thresholds.base import StreamBounds, Threshold
from ..thresholds.checks import as_inputs, as_samples, check_joints, check_same_residual
from ..thresholds.constant import ConstantThreshold
from ..thresholds.files import family_name
from ..thresholds.fitting import BoolArray
from ..thresholds.phased import PhasedThreshold, check_threshold
from ..thresholds.state import ThresholdInputs, ThresholdState
from ._level_results import (
    LEVELS,
    Level,
    LevelledEvent,
    LevelledResult,
    LevelledState,
    LevelledStatus,
    LevelledVerdict,
    levelled_events_to_pandas,
)
from ._results import Verdict
from .detector import TIME_TOLERANCE, Detector, _as_time, _fault

__all__ = [
    "LEVELS",
    "Level",
    "LevelledDetector",
    "LevelledEvent",
    "LevelledResult",
    "LevelledState",
    "LevelledVerdict",
    "levelled_events_to_pandas",
    "threshold_label",
]


def threshold_label(threshold: Threshold) -> str:
    """The family name of ``threshold``; ``phased(<accelerating>/<steady>)`` for a phased one."""
    if isinstance(threshold, PhasedThreshold):
        parts = getattr(threshold, "accelerating_", threshold.accelerating)
        steady = getattr(threshold, "steady_", threshold.steady)
        return f"phased({threshold_label(parts)}/{threshold_label(steady)})"
    return family_name(threshold)


# --------------------------------------------------------------------------- the clipped band


@dataclass(frozen=True, eq=False)
class _PairState(ThresholdState):
    contact: ThresholdState
    collision: ThresholdState


class _ContactBand(Threshold):
    """The contact threshold's bounds, clipped at every sample to the collision threshold's.

    Fitted by construction from two fitted thresholds; not a family (no
    name, no file), only what the contact level's detector reads.
    """

    def __init__(self, contact: Threshold, collision: Threshold) -> None:
        super().__init__()
        self.contact = contact
        self.collision = collision
        for name in ("robot_", "fingerprint_", "kind_", "n_dof_", "gain_", "dt_"):
            setattr(self, name, getattr(contact, name))

    def _attribute_names(self) -> tuple[str, ...]:
        return ()

    def _fit(self, runs: list[ObserverSignals], keep: list[BoolArray], margin: FloatArray) -> None:
        raise InputValueError("the contact band is made of fitted thresholds; fit them instead")

    @property
    def monitored_joints_(self) -> tuple[int, ...]:
        return tuple(
            sorted(set(self.contact.monitored_joints_) | set(self.collision.monitored_joints_))
        )

    def model_fingerprint(self, kind: str) -> str:
        return self.contact.model_fingerprint(kind)

    def _check_kind(self, kind: str | None) -> None:
        self.contact._check_kind(kind)
        self.collision._check_kind(kind)

    def _period(self, t: FloatArray, what: str) -> float:
        self.collision._period(t, what)
        return self.contact._period(t, what)

    def _initial_state_checked(
        self, inputs: ThresholdInputs, dt: float, kind: str | None = None
    ) -> ThresholdState:
        return _PairState(
            dt,
            np.zeros(0),
            self.contact._initial_state_checked(inputs, dt, kind),
            self.collision._initial_state_checked(inputs, dt, kind),
        )

    def _run(self, state: ThresholdState, inputs: ThresholdInputs) -> StreamBounds:
        assert isinstance(state, _PairState)  # made by _initial_state_checked
        lower, upper, contact = self.contact._process_checked(state.contact, inputs)
        low, high, collision = self.collision._process_checked(state.collision, inputs)
        np.maximum(lower, low, out=lower)
        np.minimum(upper, high, out=upper)
        return lower, upper, _PairState(state.dt, state.zi, contact, collision)


# --------------------------------------------------------------------------- the detector


class LevelledDetector:
    """Contact and collision events from two fitted thresholds on one residual.

    Parameters
    ----------
    contact : Threshold
        Fitted threshold of the lower, contact level (any family).
    collision : Threshold
        Fitted threshold of the upper, collision level (any family), on the
        residual of the same robot model, signal kind and observer gain.
    joints : sequence of int, optional
        Joints to monitor (1-based); by default those either threshold monitors.
    min_duration, hold : float
        Event rules of :class:`~sensorless.detection.Detector` [s], the same
        for both levels.

    Raises
    ------
    InputTypeError
        A threshold is not a :class:`~sensorless.thresholds.Threshold`.
    NotFittedError
        A threshold is not fitted.
    DimensionError
        The thresholds are for different joint counts.
    ModelMismatchError
        ... for different robot models.
    InputValueError
        ... for different signal kinds or observer gains; or two constant
        thresholds whose collision band is narrower than the contact band.
    """

    def __init__(
        self,
        contact: Threshold,
        collision: Threshold,
        *,
        joints: Any = None,
        min_duration: float = 0.0,
        hold: float = 0.0,
    ) -> None:
        check_threshold(contact, "contact", "a fitted threshold")
        check_threshold(collision, "collision", "a fitted threshold")
        contact._check_fitted()
        collision._check_fitted()
        _check_pair(contact, collision)
        self.contact = contact
        self.collision = collision
        self._band = _ContactBand(contact, collision)
        monitored = (
            self._band.monitored_joints_ if joints is None else check_joints(joints, contact.n_dof_)
        )
        self.joints = joints
        self._contact = Detector(self._band, monitored, min_duration, hold)
        self._collision = Detector(collision, monitored, min_duration, hold)
        self.min_duration = self._contact.min_duration
        self.hold = self._contact.hold
        self._method = threshold_label(contact)
        _check_constant_widths(contact, collision, monitored)

    def __repr__(self) -> str:
        return (
            f"LevelledDetector({self.contact!r}, {self.collision!r}, joints={self.joints!r}, "
            f"min_duration={self.min_duration!r}, hold={self.hold!r})"
        )

    @property
    def monitored_joints(self) -> tuple[int, ...]:
        """Monitored joints, 1-based."""
        return self._contact.monitored_joints

    @property
    def n_dof(self) -> int:
        """Number of joints."""
        return int(self.contact.n_dof_)

    # ----------------------------------------------------------------- levels

    def _levelled(self, event: Event, collisions: list[Event]) -> tuple[LevelledEvent, list[Event]]:
        """``event`` with its level and the collision events inside it; the others remain."""
        inside = [
            c
            for c in collisions
            if c.start >= event.start - TIME_TOLERANCE and c.end <= event.end + TIME_TOLERANCE
        ]
        rest = [c for c in collisions if c not in inside]
        level: Level = "collision" if inside else "contact"
        labelled = dataclasses.replace(event, method=self._method, level=level)
        return LevelledEvent(labelled, level, tuple(inside)), rest

    def _assign(self, events: list[Event], collisions: list[Event]) -> list[LevelledEvent]:
        out: list[LevelledEvent] = []
        for event in events:
            levelled, collisions = self._levelled(event, collisions)
            out.append(levelled)
        return out

    # ----------------------------------------------------------------- batch

    def run(self, signals: ObserverSignals, *, skip_nonfinite: bool = False) -> LevelledResult:
        """Both levels over a recorded run.

        Parameters
        ----------
        signals : ObserverSignals
            Run of the robot, signal kind and gain the thresholds were fitted for.
        skip_nonfinite : bool
            Skip samples with NaN/inf or a time that does not increase, as
            :meth:`step` does; by default they are an error.

        Returns
        -------
        LevelledResult
        """
        collision = self._collision.run(signals, skip_nonfinite=skip_nonfinite)
        contact = self._contact.run(signals, skip_nonfinite=skip_nonfinite)
        crossed = np.zeros(signals.residual.shape, dtype=bool)
        rows = np.flatnonzero(contact.valid)
        if rows.size:
            inputs = ThresholdInputs.from_signals(signals, rows)
            lower, upper = self.contact._bounds_checked(inputs, contact.dt, None)
            crossed[rows] = (lower < collision.lower[rows]) | (upper > collision.upper[rows])
        events = self._assign(contact.events, collision.events)
        contact = dataclasses.replace(contact, events=[e.event for e in events])
        return LevelledResult(contact, collision, events, crossed)

    def detect(
        self, signals: ObserverSignals, *, skip_nonfinite: bool = False
    ) -> list[LevelledEvent]:
        """Levelled events of a recorded run (:meth:`run` without the per-sample arrays)."""
        return self.run(signals, skip_nonfinite=skip_nonfinite).events

    # ----------------------------------------------------------------- stream

    def initial_state(self, dt: float | None = None) -> LevelledState:
        """State before the first sample of a stream; ``dt`` [s] as for :class:`Detector`."""
        return LevelledState(self._contact.initial_state(dt), self._collision.initial_state(dt))

    def step(
        self,
        state: LevelledState,
        residual: ArrayLike,
        model_torque: ArrayLike,
        friction: ArrayLike,
        sign: ArrayLike,
        velocity: ArrayLike,
        t: float,
        *,
        position: ArrayLike | None = None,
        acceleration: ArrayLike | None = None,
    ) -> tuple[LevelledVerdict, LevelledState]:
        """Judge one sample of a stream at both levels (inputs as :meth:`Detector.step`).

        Returns
        -------
        verdict : LevelledVerdict
        state : LevelledState
            State for the next sample (the same object after a fault).

        Raises
        ------
        DimensionError
            An input of the wrong shape (a programming error, not a data fault).
        """
        check_type(state, LevelledState, "state", " from initial_state or step")
        n_dof = self.n_dof
        r = as_samples(residual, n_dof, "residual", one_sample="step", allow_nonfinite=True)[0]
        inputs = as_inputs(
            n_dof, model_torque, friction, sign, velocity, position, acceleration,
            one_sample="step", allow_nonfinite=True,
        )  # fmt: skip
        time = _as_time(t)
        fault = _fault(r, inputs, time, state.contact.t)
        if fault:
            nan = np.full(n_dof, np.nan)
            verdict = Verdict("fault", time, (), r, nan, nan.copy(), None, fault)
            return LevelledVerdict("fault", time, verdict, verdict), state
        return self._step_checked(state, r, inputs, time)

    def _step_checked(
        self, state: LevelledState, r: FloatArray, inputs: ThresholdInputs, time: float
    ) -> tuple[LevelledVerdict, LevelledState]:
        """The core of :meth:`step` for a good sample (see :meth:`Detector._step_checked`)."""
        collision, collision_state = self._collision._step_checked(state.collision, r, inputs, time)
        return self._step_contact(
            LevelledState(state.contact, collision_state, state.pending), r, inputs, time, collision
        )

    def _step_contact(
        self,
        state: LevelledState,
        r: FloatArray,
        inputs: ThresholdInputs,
        time: float,
        collision: Verdict,
    ) -> tuple[LevelledVerdict, LevelledState]:
        """The contact level of a good sample whose collision level judged ``collision``.

        A monitor passes its own verdict here (its detector is the collision
        level's, with the same rules), so the collision band is judged once.
        """
        contact, contact_state = self._contact._step_checked(state.contact, r, inputs, time)
        pending = list(state.pending)
        if collision.event is not None:
            pending.append(collision.event)
        event = None
        if contact.event is not None:
            event, pending = self._levelled(contact.event, pending)
        if collision.status == "collision":
            status: LevelledStatus = "collision"
        elif contact.status == "collision":
            status = "contact"
        else:
            status = "ok"
        verdict = LevelledVerdict(status, time, contact, collision, event)
        return verdict, LevelledState(contact_state, state.collision, tuple(pending))

    def _finish_contact(
        self, state: LevelledState, closed: Event | None
    ) -> tuple[LevelledEvent | None, LevelledState]:
        """Close the contact level, the collision level having closed ``closed`` (or nothing)."""
        pending = list(state.pending) + ([] if closed is None else [closed])
        ended, contact_state = self._contact.finish(state.contact)
        event = None
        if ended is not None:
            event, pending = self._levelled(ended, pending)
        return event, LevelledState(contact_state, state.collision, tuple(pending))

    def finish(self, state: LevelledState) -> tuple[LevelledEvent | None, LevelledState]:
        """Close the event in progress at the end of a stream (None if there is none)."""
        if not isinstance(state, LevelledState):
            raise InputTypeError(f"state must be a LevelledState; got {type(state).__name__}")
        closed, collision_state = self._collision.finish(state.collision)
        return self._finish_contact(
            LevelledState(state.contact, collision_state, state.pending), closed
        )


# --------------------------------------------------------------------------- checks


def _check_pair(contact: Threshold, collision: Threshold) -> None:
    """Raise unless both thresholds bound the residual of one model, signal kind and gain."""
    check_same_residual(contact, collision, "the contact threshold", "the collision threshold")


def _check_constant_widths(
    contact: Threshold, collision: Threshold, monitored: tuple[int, ...]
) -> None:
    """Refuse two constant bands where the collision band is the narrower (module docstring)."""
    if not (isinstance(contact, ConstantThreshold) and isinstance(collision, ConstantThreshold)):
        return
    cols = np.asarray(monitored) - 1
    narrower = cols[collision.beta_[cols] < contact.beta_[cols]]
    if narrower.size:
        j = int(narrower[0])
        raise InputValueError(
            f"the collision band must be at least as wide as the contact band; on joint {j + 1} "
            f"it is ±{collision.beta_[j]:.6g} N m, the contact band ±{contact.beta_[j]:.6g} N m "
            "(swap the thresholds, or give the collision level a larger margin)"
        )
