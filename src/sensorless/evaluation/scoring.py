"""Scoring of one detection method: events matched to the ground-truth windows.

:func:`evaluate` applies the matching rules of :mod:`sensorless.evaluation`
and returns an :class:`Evaluation`; :func:`check_evaluations` checks a
mapping of them for the tables and the plots.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from .._validation import FloatArray
from ..exceptions import InputTypeError, InputValueError
from ..io import Log
from ..signals import Event
from .windows import Window, collision_windows

__all__ = ["DEFAULT_MAX_DELAY", "Evaluation", "check_evaluations", "evaluate"]

DEFAULT_MAX_DELAY = 0.5
"""Default time [s] after the end of a contact during which an event still detects it."""

SECONDS_PER_HOUR = 3600.0

_PER_COLLISION_COLUMNS = (
    "start",
    "end",
    "peak_force",
    "detected",
    "masked",
    "start_delay",
    "end_delay",
    "n_events",
    "joints",
)


def _check_time_margin(value: Any, name: str) -> float:
    try:
        number = float(value)
    except (TypeError, ValueError):
        raise InputValueError(
            f"{name} must be a non-negative number of seconds; got {value!r}"
        ) from None
    if not math.isfinite(number) or number < 0.0:
        raise InputValueError(
            f"{name} must be a finite, non-negative number of seconds; got {value!r}"
        )
    return number


def _check_events(events: Iterable[Event]) -> list[Event]:
    checked = list(events)
    for index, event in enumerate(checked):
        if not isinstance(event, Event):
            raise InputTypeError(
                f"events must be sensorless.signals.Event objects; item {index} is a "
                f"{type(event).__name__}"
            )
        if not (math.isfinite(event.start) and math.isfinite(event.end)):
            raise InputValueError(
                f"event {index} must have finite start and end times; got start = "
                f"{event.start!r} s, end = {event.end!r} s"
            )
        if event.end < event.start:
            raise InputValueError(
                f"event {index} ends before it starts: start = {event.start!r} s, "
                f"end = {event.end!r} s"
            )
    return checked


@dataclass(frozen=True, eq=False)
class Evaluation:
    """Detection performance of one method on one log (returned by :func:`evaluate`).

    Attributes
    ----------
    method : str
        Name of the detection method.
    windows : list of Window
        Ground-truth collision windows, by start time.
    per_collision : DataFrame
        One row per window, indexed by collision ``id``, with columns ``start``,
        ``end`` [s], ``peak_force`` [N] (NaN if unknown), ``detected`` (bool),
        ``masked`` (bool: not detected, and an alarm that began before the
        contact was still on when it started), ``start_delay``, ``end_delay``
        [s] (NaN unless detected; the start delay is never negative),
        ``n_events`` (events detecting the window) and ``joints`` (tuple of
        the 1-based joints of those events).
    events : list of Event
        All evaluated events, by start time.
    detections : list of Event
        Events that detect at least one window.
    false_alarms : list of Event
        Events that detect no window and are not excused, among them every
        alarm that began before a contact and was still on when it started.
    excused : list of Event
        Events that start inside the ``tolerance`` margin before a window, or
        only touch it without masking a window.
    duration : float
        Duration of the log [s] (last minus first time stamp).
    t_start : float
        First time stamp of the log [s].
    false_alarm_rate : float
        False alarms per hour of motion [1/h].
    n_detected, n_masked, n_missed : int
        Detected, masked and missed windows; they add up to the number of
        windows.
    mean_start_delay : float
        Mean start delay over detected windows [s]; NaN if none is detected.
    tolerance, max_delay : float
        Matching settings [s] (see :mod:`sensorless.evaluation`).
    """

    method: str
    windows: list[Window]
    per_collision: pd.DataFrame
    events: list[Event]
    detections: list[Event]
    false_alarms: list[Event]
    excused: list[Event]
    duration: float
    t_start: float
    false_alarm_rate: float
    n_detected: int
    n_missed: int
    mean_start_delay: float
    tolerance: float = 0.0
    max_delay: float = DEFAULT_MAX_DELAY
    n_masked: int = 0

    @property
    def n_collisions(self) -> int:
        """Number of ground-truth windows."""
        return len(self.windows)

    @property
    def n_false_alarms(self) -> int:
        """Number of false alarms."""
        return len(self.false_alarms)

    @property
    def mean_end_delay(self) -> float:
        """Mean end delay over detected windows [s]; NaN if none is detected."""
        delays = self.per_collision["end_delay"].to_numpy(dtype=float)
        return float(np.nanmean(delays)) if np.isfinite(delays).any() else math.nan

    @property
    def max_start_delay(self) -> float:
        """Largest start delay over detected windows [s]; NaN if none is detected."""
        delays = self.per_collision["start_delay"].to_numpy(dtype=float)
        return float(np.nanmax(delays)) if np.isfinite(delays).any() else math.nan

    @property
    def median_start_delay(self) -> float:
        """Median start delay over detected windows [s]; NaN if none is detected."""
        delays = self.per_collision["start_delay"].to_numpy(dtype=float)
        return float(np.nanmedian(delays)) if np.isfinite(delays).any() else math.nan

    def to_pandas(self) -> pd.DataFrame:
        """The per-collision table (a copy of :attr:`per_collision`)."""
        return self.per_collision.copy()

    def summary(self) -> dict[str, Any]:
        """One-row summary.

        Returns
        -------
        dict
            ``method``, ``n_collisions``, ``n_detected``, ``n_masked``,
            ``n_missed``, ``detected`` (text ``"k/n"``), ``n_false_alarms``,
            ``false_alarm_rate`` [1/h], ``mean_start_delay``,
            ``median_start_delay``, ``mean_end_delay``, ``max_start_delay``
            [s] and ``duration`` [s].
        """
        return {
            "method": self.method,
            "n_collisions": self.n_collisions,
            "n_detected": self.n_detected,
            "n_masked": self.n_masked,
            "n_missed": self.n_missed,
            "detected": f"{self.n_detected}/{self.n_collisions}",
            "n_false_alarms": self.n_false_alarms,
            "false_alarm_rate": self.false_alarm_rate,
            "mean_start_delay": self.mean_start_delay,
            "median_start_delay": self.median_start_delay,
            "mean_end_delay": self.mean_end_delay,
            "max_start_delay": self.max_start_delay,
            "duration": self.duration,
        }


def _overlaps(
    starts: FloatArray, ends: FloatArray, lower: FloatArray, upper: FloatArray
) -> NDArray[np.bool_]:
    """Matrix (n_events, n_windows): closed interval [start, end] meets [lower, upper]."""
    return (starts[:, None] <= upper[None, :]) & (ends[:, None] >= lower[None, :])


def evaluate(
    events: Iterable[Event],
    log: Log,
    *,
    method: str = "",
    tolerance: float = 0.0,
    max_delay: float | None = None,
) -> Evaluation:
    """Match detected events to the ground-truth collision windows of a log.

    The rules are those of :mod:`sensorless.evaluation`. In short: an event
    detects a window when it starts inside ``[start, end + max_delay]``; an
    alarm that began before a contact and is still on when the contact
    starts is a false alarm, and the contact counts as *masked* (unless a
    later event detects it), never as detected with a negative delay.

    Parameters
    ----------
    events : iterable of Event
        Events of one detection method (e.g. from a threshold's ``detect``).
    log : Log
        The labelled run the events were detected on (see
        :func:`collision_windows`); its duration sets the false-alarm rate.
    method : str
        Name of the method; by default the ``method`` shared by all events
        (empty if they disagree).
    tolerance : float
        Margin [s] before each window: an event that starts inside it is
        excused (neither a false alarm nor a detection; the window it covers
        is masked). Default 0.
    max_delay : float, optional
        Time [s] after the end of a window during which an event still
        detects it. Default :data:`DEFAULT_MAX_DELAY` (0.5 s).

    Returns
    -------
    Evaluation

    Raises
    ------
    InputValueError
        ``tolerance`` or ``max_delay`` is negative or not finite; an event
        has a non-finite time or ends before it starts.
    TypeError
        An item of ``events`` is not an :class:`~sensorless.signals.Event`.
    LogFormatError
        The log's collision metadata is malformed (see :func:`collision_windows`).

    Examples
    --------
    >>> import numpy as np
    >>> from sensorless.io import Log
    >>> from sensorless.signals import Event
    >>> t = np.arange(0.0, 10.0, 0.01)
    >>> label = ((t >= 2.0) & (t <= 2.5)).astype(int)
    >>> log = Log(t=t, q=np.zeros((t.size, 1)), collision_id=label)
    >>> events = [Event(2.05, 2.6, (1,), 1.0, 3.0), Event(7.0, 7.1, (1,), 0.2, 2.0)]
    >>> result = evaluate(events, log, method="constant")
    >>> result.n_detected, result.n_false_alarms
    (1, 1)
    >>> round(float(result.per_collision.loc[1, "start_delay"]), 9)
    0.05
    >>> round(result.false_alarm_rate)  # one false alarm in 9.99 s of motion
    360
    >>> early = evaluate([Event(1.0, 2.2, (1,), 1.0, 3.0)], log)  # on since 1 s before
    >>> early.n_detected, early.n_masked, early.n_false_alarms
    (0, 1, 1)
    """
    margin = _check_time_margin(tolerance, "tolerance")
    delay = _check_time_margin(DEFAULT_MAX_DELAY if max_delay is None else max_delay, "max_delay")
    checked = sorted(_check_events(events), key=lambda e: (e.start, e.end))
    if not method:
        names = {event.method for event in checked}
        method = names.pop() if len(names) == 1 else ""
    windows = collision_windows(log)

    starts = np.array([e.start for e in checked], dtype=float)
    ends = np.array([e.end for e in checked], dtype=float)
    w_start = np.array([w.start for w in windows], dtype=float)
    w_end = np.array([w.end for w in windows], dtype=float)
    # Matrices (n_events, n_windows) of the matching rules in the package docstring.
    detects = (starts[:, None] >= w_start[None, :]) & (starts[:, None] <= (w_end + delay)[None, :])
    masks = (starts[:, None] < w_start[None, :]) & (ends[:, None] >= w_start[None, :])
    in_margin = (starts[:, None] >= (w_start - margin)[None, :]) & (
        starts[:, None] < w_start[None, :]
    )
    touches = _overlaps(starts, ends, w_start - margin, w_start) if margin > 0.0 else in_margin

    rows = []
    for k, window in enumerate(windows):
        hits = np.flatnonzero(detects[:, k])
        detected = hits.size > 0
        joints = sorted({j for i in hits for j in checked[i].joints})
        rows.append(
            {
                "id": window.id,
                "start": window.start,
                "end": window.end,
                "peak_force": window.peak_force,
                "detected": detected,
                "masked": not detected and bool(masks[:, k].any()),
                "start_delay": float(starts[hits].min() - window.start) if detected else math.nan,
                "end_delay": float(ends[hits].max() - window.end) if detected else math.nan,
                "n_events": int(hits.size),
                "joints": tuple(joints),
            }
        )
    per_collision = pd.DataFrame(rows, columns=["id", *_PER_COLLISION_COLUMNS]).set_index("id")
    for column in ("detected", "masked"):
        per_collision[column] = per_collision[column].astype(bool)
    per_collision["n_events"] = per_collision["n_events"].astype(np.int64)

    is_detection: NDArray[np.bool_] = np.asarray(detects.any(axis=1), dtype=bool)
    is_excused: NDArray[np.bool_] = ~is_detection & (
        in_margin.any(axis=1) | (touches.any(axis=1) & ~masks.any(axis=1))
    )
    is_false: NDArray[np.bool_] = ~is_detection & ~is_excused
    duration = log.duration
    n_false = int(is_false.sum())
    n_detected = int(per_collision["detected"].sum())
    n_masked = int(per_collision["masked"].sum())
    delays = per_collision["start_delay"].to_numpy(dtype=float)
    return Evaluation(
        method=method,
        windows=windows,
        per_collision=per_collision,
        events=checked,
        detections=[e for e, hit in zip(checked, is_detection, strict=True) if hit],
        false_alarms=[e for e, bad in zip(checked, is_false, strict=True) if bad],
        excused=[e for e, excused in zip(checked, is_excused, strict=True) if excused],
        duration=duration,
        t_start=float(log.t[0]),
        false_alarm_rate=n_false / (duration / SECONDS_PER_HOUR),
        n_detected=n_detected,
        n_missed=len(windows) - n_detected - n_masked,
        mean_start_delay=float(np.nanmean(delays)) if n_detected else math.nan,
        tolerance=margin,
        max_delay=delay,
        n_masked=n_masked,
    )


def check_evaluations(evaluations: Mapping[str, Evaluation]) -> list[tuple[str, Evaluation]]:
    """The (name, evaluation) pairs of a non-empty mapping of :class:`Evaluation` objects."""
    if not isinstance(evaluations, Mapping):
        raise InputTypeError(
            "evaluations must be a mapping {method name: Evaluation}; got "
            f"{type(evaluations).__name__}"
        )
    items = list(evaluations.items())
    if not items:
        raise InputValueError("evaluations must hold at least one {method name: Evaluation}")
    for name, evaluation in items:
        if not isinstance(evaluation, Evaluation):
            raise InputTypeError(
                f"evaluations[{name!r}] must be an Evaluation; got {type(evaluation).__name__}"
            )
    return items
