"""Two reaction levels on one observer: a contact band under the monitor's collision band.

A :class:`LevelledMonitor` wraps a :class:`~sensorless.monitor.CollisionMonitor`
(whose threshold is the *collision* level: it latches and stops the arm) and
adds a *contact* threshold on the same residual; the levels are those of
:class:`~sensorless.detection.LevelledDetector` (an event is an excursion
beyond the contact band; its level is ``"collision"`` when the collision band
was left during it too). The observer runs once:

* **batch** (:meth:`LevelledMonitor.process`): the collision monitor
  processes the log; both levels are then judged on its signals, segment by
  segment between its settling windows (a start or a restart), fault samples
  skipped;
* **stream** (:meth:`LevelledMonitor.step`): the collision monitor judges the
  sample, and its verdict is the collision level's; a judged sample's
  residual (from that verdict) and the threshold inputs of the same sample go
  to the contact level; a ``"settling"`` verdict closes the levels' open
  event and starts them anew; a fault changes nothing.

Both forms give the same events. A restart without a settling window
(``StreamPolicy(settle=0)``) is not visible in the verdicts: the levels then
carry on across it, in both forms alike.

The stream and the compiled monitor
-----------------------------------
A contact threshold of the constant family needs the residual alone. Every
other family also reads the observer's model torque, filtered friction and
sign and the velocity of the sample, which :meth:`CollisionMonitor.step`
computes but does not hand out: the stream reads them from the compiled
stream's committed state (``FusedStream.threshold_rows``), or on the Python
path from the monitor's record of its last sample. A model-based contact
threshold (it reads q̈̂) is refused by the stream.

:func:`tune_levels` tunes both levels on collision-free logs. Units SI and
radians; time along axis 0.
"""

from __future__ import annotations

import copy
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from .._validation import check_type
from ..detection import LEVELS, LevelledDetector, LevelledEvent, LevelledState, LevelledVerdict
from ..detection.levels import levelled_events_to_pandas
from ..exceptions import InputTypeError, InputValueError
from ..io import Log
from ..robots.model import RobotModel
from ..signals import Event, ObserverSignals
from ..thresholds import (
    ConstantThreshold,
    ModelBasedThreshold,
    PhasedThreshold,
    Threshold,
    ThresholdInputs,
)
from .batch import MonitorRun, _rows
from .calibration import DEFAULT_HOLD, DEFAULT_MIN_DURATION
from .policy import StreamPolicy
from .stream import CollisionMonitor
from .tuning import METHOD_NAMES, ObserverSettings, tune

__all__ = ["LevelSpec", "LevelledMonitor", "LevelledRun", "tune_levels"]

BoolArray = NDArray[np.bool_]

LevelSpec = str | Mapping[str, Any] | Threshold
"""How :func:`tune_levels` makes a level: a family name, keywords of
:func:`~sensorless.monitor.tune` (with ``method``), or an unfitted threshold."""


@dataclass(frozen=True, eq=False)
class LevelledRun:
    """What :meth:`LevelledMonitor.process` found in a log.

    Attributes
    ----------
    run : MonitorRun
        The collision monitor's run: signals, collision events, faults, settling.
    events : list of LevelledEvent
        Excursions beyond the contact band with their level, in time order.
    collisions : list of Event
        The collision level's events as the levels judged them (the same as
        ``run.events``, which the monitor found itself).
    crossed : ndarray of bool, shape (n_samples, n_dof)
        Where the contact band reached beyond the collision band and was
        clipped to it.
    """

    run: MonitorRun
    events: list[LevelledEvent]
    collisions: list[Event]
    crossed: BoolArray

    @property
    def signals(self) -> ObserverSignals:
        """Observer signals of the log (NaN at refused samples)."""
        return self.run.signals

    def counts(self) -> dict[str, int]:
        """Number of events per level: ``{"contact": ..., "collision": ...}``."""
        return {level: sum(e.level == level for e in self.events) for level in LEVELS}

    def events_to_pandas(self) -> pd.DataFrame:
        """The levelled events as a table (:func:`.levelled_events_to_pandas`)."""
        return levelled_events_to_pandas(self.events)


class LevelledMonitor:
    """A collision monitor with a lower contact level on the same residual (module docstring).

    Parameters
    ----------
    monitor : CollisionMonitor
        The collision level: observer, policy, collision threshold, event
        rules (``min_duration``, ``hold``, shared by the contact level).
    contact : Threshold
        Fitted contact threshold (any family) on the monitor's residual.

    Raises
    ------
    InputTypeError, NotFittedError, DimensionError, ModelMismatchError, InputValueError
        As :class:`~sensorless.detection.LevelledDetector` for the pair
        (``contact``, ``monitor.threshold``).
    """

    def __init__(self, monitor: CollisionMonitor, contact: Threshold) -> None:
        check_type(monitor, CollisionMonitor, "monitor", " (the collision level)")
        detector = monitor.detector
        self.monitor = monitor
        self.contact = contact
        self.levels = LevelledDetector(
            contact, monitor.threshold, min_duration=detector.min_duration, hold=detector.hold
        )
        self._inputs = _reads_inputs(contact)
        self._state: LevelledState | None = None

    def __repr__(self) -> str:
        return f"LevelledMonitor({self.monitor.threshold!r}, contact={self.contact!r})"

    # ----------------------------------------------------------------- batch

    def process(self, log: Log, *, strict: bool = False) -> LevelledRun:
        """Both levels over a whole log (see :meth:`CollisionMonitor.process`).

        Returns
        -------
        LevelledRun
        """
        run = self.monitor.process(log, strict=strict)
        signals = run.signals
        events: list[LevelledEvent] = []
        collisions: list[Event] = []
        crossed = np.zeros(signals.residual.shape, dtype=bool)
        judged = np.asarray(np.isfinite(signals.residual).all(axis=1), dtype=bool)
        for first, last in _segments(run.settling, judged):
            rows = slice(first, last)
            part = _rows(
                signals,
                rows,
                None if signals.acceleration is None else signals.acceleration[rows],
            )
            result = self.levels.run(part, skip_nonfinite=True)
            events += result.events
            collisions += result.collision.events
            crossed[rows] = result.crossed
        return LevelledRun(run, events, collisions, crossed)

    # ----------------------------------------------------------------- stream

    def reset(self) -> None:
        """Forget the stream (both levels) and release the collision monitor's latch."""
        self.monitor.reset()
        self._state = None

    def step(
        self,
        t: float,
        q: ArrayLike,
        tau_m: ArrayLike,
        tau_j: ArrayLike | None = None,
        *,
        qd: ArrayLike | None = None,
    ) -> LevelledVerdict:
        """Judge one sample at both levels; arguments as :meth:`CollisionMonitor.step`.

        Returns
        -------
        LevelledVerdict
            ``"collision"`` (the monitor's verdict, latched), ``"contact"``,
            ``"ok"``, ``"settling"`` or ``"fault"``; ``collision`` is the
            monitor's verdict, ``contact`` the contact level's.

        Raises
        ------
        InputValueError
            The contact threshold reads q̈̂, which the stream does not hand out
            (module docstring): a configuration error, raised at the first sample.
        """
        monitor = self.monitor
        fused = monitor._fused
        if self._inputs:
            self._check_stream()
            monitor._record = [] if fused is None else None
        try:
            verdict = monitor.step(t, q, tau_m, tau_j, qd=qd)
            record = monitor._record
        finally:
            monitor._record = None
        if verdict.status == "fault":
            return LevelledVerdict("fault", verdict.t, None, verdict)
        if verdict.status == "settling":  # a (re)start: the levels start anew after it
            ended = self._close(verdict.event)
            return LevelledVerdict("settling", verdict.t, None, verdict, ended)
        residual = verdict.residual
        if self._inputs and fused is not None:
            h, friction, sign, velocity = fused.threshold_rows()[:, None]
            inputs = ThresholdInputs(
                h, friction, sign, velocity, np.asarray(q, dtype=np.float64).reshape(1, -1)
            )
        elif record:
            _, sample, velocity = record[-1]
            inputs = ThresholdInputs(
                sample.model_torque[None],
                sample.friction[None],
                sample.sign[None],
                velocity[None],
                np.asarray(q, dtype=np.float64).reshape(1, -1),
            )
        else:  # a constant contact band reads the residual alone
            zero = np.zeros((1, residual.shape[0]))
            inputs = ThresholdInputs(zero, zero, zero, zero)
        state = self._state
        if state is None:
            state = self.levels.initial_state(monitor.dt)
        # The monitor's verdict is the collision level's (same threshold and rules): reused.
        levelled, self._state = self.levels._step_contact(
            state, residual, inputs, verdict.t, verdict
        )
        return levelled

    def finish(self) -> LevelledEvent | None:
        """Close the stream: the levelled event still open, if any."""
        return self._close(self.monitor.finish())

    def _close(self, closed: Event | None) -> LevelledEvent | None:
        """Close the levels; ``closed`` is the collision event the monitor closed with them."""
        if self._state is None:
            return None
        event, _ = self.levels._finish_contact(self._state, closed)
        self._state = None
        return event

    def _check_stream(self) -> None:
        if _reads_acceleration(self.contact):
            raise InputValueError(
                "a model-based contact threshold reads the acceleration estimate, which the "
                "monitor's stream does not hand out; use it in process() only"
            )


def _reads_inputs(threshold: Threshold) -> bool:
    """Whether the bounds read more than the residual (every family but the constant)."""
    if isinstance(threshold, PhasedThreshold):
        return True  # the phase reads the velocity
    return not isinstance(threshold, ConstantThreshold)


def _reads_acceleration(threshold: Threshold) -> bool:
    if isinstance(threshold, PhasedThreshold):
        parts = (
            getattr(threshold, "accelerating_", threshold.accelerating),
            getattr(threshold, "steady_", threshold.steady),
        )
        return any(_reads_acceleration(part) for part in parts)
    return isinstance(threshold, ModelBasedThreshold)


def _segments(settling: BoolArray, judged: BoolArray) -> list[tuple[int, int]]:
    """[first, last) spans between settling samples that hold at least one judged sample."""
    edges = np.flatnonzero(np.diff(np.concatenate([[1], settling.astype(np.int8), [1]])))
    spans = [(int(a), int(b)) for a, b in zip(edges[::2], edges[1::2], strict=True)]
    return [(a, b) for a, b in spans if judged[a:b].any()]


# --------------------------------------------------------------------------- tuning


def tune_levels(
    logs: Log | Sequence[Log],
    robot: RobotModel,
    *,
    contact: LevelSpec = "constant",
    collision: LevelSpec | None = None,
    settings: ObserverSettings | None = None,
    folds: str | int | None = "runs",
    min_duration: float = DEFAULT_MIN_DURATION,
    hold: float = DEFAULT_HOLD,
    seed: int = 0,
    policy: StreamPolicy | None = None,
    backend: str = "auto",
) -> LevelledMonitor:
    """Tune a contact and a collision level on collision-free logs.

    Parameters
    ----------
    logs : Log or sequence of Log
        Collision-free runs of the robot.
    robot : RobotModel
        The nominal model the observer uses.
    contact : str, mapping or Threshold
        The contact level: a family name (tuned with margin 0:
        ``{"method": name, "margin_fraction": 0.0}``), keywords of
        :func:`~sensorless.monitor.tune` with ``method`` (``margin``,
        ``margin_fraction``, ``false_alarm_rate``, ``joints``, ...), or an
        unfitted threshold of any family (e.g. a
        :class:`~sensorless.thresholds.PhasedThreshold`), fitted as given on
        the observed logs (set its ``transient``, e.g. to
        ``settings.settle_time(dt)`` as :func:`tune` does).
    collision : str, mapping or Threshold, optional
        The collision level, in the same forms; a family name is tuned with
        :func:`tune`'s default margin (10 % of the constant band). By default
        the contact level's family with that margin.
    settings : ObserverSettings, optional
        Observer settings of both levels; by default the observer the first
        named family watches (K_I = 20).
    folds, min_duration, hold, seed
        As for :func:`~sensorless.monitor.tune` (cross-validated false alarms
        per level: ``calibration_of(threshold)``); ``min_duration`` and
        ``hold`` also go to the monitor.
    policy : StreamPolicy, optional
        Policy of the monitor.
    backend : {"auto", "numba", "python"}
        Stream backend of the collision monitor (:class:`CollisionMonitor`).

    Returns
    -------
    LevelledMonitor
        ``monitor.threshold`` is the collision level, ``contact`` the contact level.
    """
    if isinstance(logs, Log):
        logs = [logs]
    specs = {
        "contact": _spec(contact, "contact", margin_zero=True),
        "collision": _spec(_default_collision(contact) if collision is None else collision,
                           "collision", margin_zero=False),
    }  # fmt: skip
    if settings is None:
        named = [s for s in specs.values() if isinstance(s, dict)]
        kind = METHOD_NAMES.get(str(named[0]["method"]), "motor") if named else "motor"
        settings = ObserverSettings(kind=kind)
    check_type(settings, ObserverSettings, "settings")
    common = {"folds": folds, "min_duration": min_duration, "hold": hold, "seed": seed}
    fitted: dict[str, Threshold] = {}
    signals: list[ObserverSignals] | None = None
    for name, spec in specs.items():
        if isinstance(spec, Threshold):
            if signals is None:
                signals = [settings.observe(log, robot) for log in logs]
            fitted[name] = copy.deepcopy(spec).fit(signals)
        else:
            options = dict(spec)
            method = options.pop("method")
            fitted[name], _ = tune(logs, robot, method, settings, **{**common, **options})
    monitor = CollisionMonitor(
        robot, fitted["collision"], settings, min_duration=min_duration, hold=hold,
        policy=policy, backend=backend,
    )  # fmt: skip
    return LevelledMonitor(monitor, fitted["contact"])


def _default_collision(contact: LevelSpec) -> LevelSpec:
    if isinstance(contact, str):
        return contact
    if isinstance(contact, Mapping) and "method" in contact:
        return str(contact["method"])
    raise InputValueError(
        "give the collision level when the contact level is a threshold instance; "
        f"got contact={contact!r} and collision=None"
    )


def _spec(value: Any, name: str, *, margin_zero: bool) -> dict[str, Any] | Threshold:
    """A level's spec as ``tune`` keywords (with ``method``) or an unfitted threshold."""
    if isinstance(value, Threshold):
        return value
    if isinstance(value, str):
        return {"method": value, "margin_fraction": 0.0} if margin_zero else {"method": value}
    if isinstance(value, Mapping):
        if "method" not in value:
            raise InputValueError(
                f"{name} keywords must name the family with 'method' (one of "
                f"{sorted(METHOD_NAMES)}); got keys {sorted(value)}"
            )
        return dict(value)
    raise InputTypeError(
        f"{name} must be a family name, a mapping of tune() keywords with 'method', or an "
        f"unfitted Threshold; got {type(value).__name__}"
    )
