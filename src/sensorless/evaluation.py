"""Evaluation of collision detection against ground-truth collision windows.

A log with ground-truth labels (``collision_id``, and the contact list in
``metadata["collisions"]`` that the simulator writes) defines one
:class:`Window` per collision. :func:`evaluate` matches the :class:`~sensorless.signals.Event`
list of one detection method to these windows and returns an :class:`Evaluation`:
per collision whether it was detected and the delays of the start and the end of
the detection, plus the false alarms and their rate per hour of motion.

:func:`comparison_table` and :func:`summary_table` put several methods side by
side in the style of the thesis' Tables 4.3, 5.4 and 5.9; :func:`efficiency_table`
is Table 5.7 (eff = α/β).

Matching rules
--------------
For a window ``[start, end]`` and the settings ``max_delay`` and ``tolerance`` [s]:

* an event *detects* the window when its interval ``[event.start, event.end]``
  overlaps ``[start, end + max_delay]``; an event may detect several windows;
* the *start delay* is the earliest start of a detecting event minus ``start``
  (negative when that event began before the contact), the *end delay* is the
  latest end of a detecting event minus ``end``;
* an event that detects no window and does not overlap any
  ``[start - tolerance, end + max_delay]`` is a *false alarm*; one that only
  touches the ``tolerance`` margin before a window is *excused*: neither a
  detection nor a false alarm (a residual may cross its bound just before a
  label whose onset is uncertain by a few samples).

The default ``max_delay`` of :data:`DEFAULT_MAX_DELAY` = 0.5 s is above the
largest detection delay the thesis reports (0.31 s, Table 5.4; 0.42 s,
Table 5.9) and below the 1 s minimum gap between simulated contacts.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np
import pandas as pd
from numpy.typing import ArrayLike, NDArray

from ._validation import FloatArray
from .exceptions import DimensionError, InputTypeError, InputValueError, LogFormatError
from .io import Log
from .signals import Event

__all__ = [
    "DEFAULT_MAX_DELAY",
    "Evaluation",
    "Window",
    "collision_windows",
    "comparison_table",
    "efficiency_table",
    "evaluate",
    "summary_table",
]

DEFAULT_MAX_DELAY = 0.5
"""Default time [s] after the end of a contact during which an event still detects it."""

SECONDS_PER_HOUR = 3600.0

_PER_COLLISION_COLUMNS = (
    "start",
    "end",
    "peak_force",
    "detected",
    "start_delay",
    "end_delay",
    "n_events",
    "joints",
)


@dataclass(frozen=True)
class Window:
    """Ground-truth time window of one collision.

    Attributes
    ----------
    id : int
        Collision id (the ``collision_id`` label, > 0).
    start, end : float
        First and last time [s] the contact acts.
    peak_force : float
        Peak contact force [N] from the log metadata; NaN when unknown.
    """

    id: int
    start: float
    end: float
    peak_force: float = math.nan

    @property
    def duration(self) -> float:
        """end − start [s]."""
        return self.end - self.start


def _metadata_collisions(log: Log) -> dict[int, dict[str, Any]]:
    """Entries of ``log.metadata["collisions"]`` by id, checked."""
    entries = log.metadata.get("collisions", [])
    if not isinstance(entries, list):
        raise LogFormatError(
            f"metadata['collisions'] must be a list of dicts; got {type(entries).__name__}"
        )
    found: dict[int, dict[str, Any]] = {}
    for index, entry in enumerate(entries):
        if not isinstance(entry, Mapping):
            raise LogFormatError(
                f"metadata['collisions'][{index}] must be a dict with 'id', 'start', 'end'; "
                f"got {type(entry).__name__}"
            )
        ident = entry.get("id")
        if isinstance(ident, bool) or not isinstance(ident, int) or ident < 1:
            raise LogFormatError(
                f"metadata['collisions'][{index}] must have a positive integer 'id'; got {ident!r}"
            )
        checked: dict[str, Any] = {"id": ident}
        for key in ("start", "end", "peak"):
            value = entry.get(key)
            if value is None and key == "peak":
                checked[key] = math.nan
                continue
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise LogFormatError(
                    f"metadata['collisions'][{index}] must have a numeric {key!r} "
                    f"[{'N' if key == 'peak' else 's'}]; got {value!r}"
                )
            checked[key] = float(value)
        if not checked["start"] <= checked["end"]:
            raise LogFormatError(
                f"metadata['collisions'][{index}] must have start <= end; got start = "
                f"{checked['start']!r} s, end = {checked['end']!r} s"
            )
        found[ident] = checked
    return found


def collision_windows(log: Log) -> list[Window]:
    """Ground-truth collision windows of a log.

    Parameters
    ----------
    log : Log
        A log with ``collision_id`` labels and/or ``metadata["collisions"]``
        (a list of dicts with ``id``, ``start`` [s], ``end`` [s] and optionally
        ``peak`` [N], as written by the simulator).

    Returns
    -------
    list of Window
        Sorted by start time. With ``collision_id``, each id gives one window
        from the first to the last sample carrying it (so a contact that is
        briefly masked by a stronger overlapping one stays one window). A
        contact listed in the metadata whose id never appears in
        ``collision_id`` (shorter than a sample period, or masked throughout)
        is taken from the metadata if its window meets the time span of the
        log. Without ``collision_id`` the metadata windows inside the span are
        used. The peak force comes from the metadata (NaN if absent). A log
        with neither gives an empty list.

    Raises
    ------
    LogFormatError
        ``metadata["collisions"]`` is not a list of dicts with a positive
        integer ``id`` and numeric ``start <= end``.

    Examples
    --------
    >>> import numpy as np
    >>> from sensorless.io import Log
    >>> t = np.arange(10) * 0.1
    >>> log = Log(t=t, q=np.zeros((10, 1)), collision_id=[0, 0, 1, 1, 1, 0, 0, 2, 2, 0])
    >>> [(w.id, round(w.start, 9), round(w.end, 9)) for w in collision_windows(log)]
    [(1, 0.2, 0.4), (2, 0.7, 0.8)]
    """
    meta = _metadata_collisions(log)
    windows: list[Window] = []
    seen: set[int] = set()
    if log.collision_id is not None:
        labels = log.collision_id
        for ident in np.unique(labels[labels > 0]).tolist():
            rows = np.flatnonzero(labels == ident)
            peak = meta[ident]["peak"] if ident in meta else math.nan
            windows.append(Window(int(ident), float(log.t[rows[0]]), float(log.t[rows[-1]]), peak))
            seen.add(int(ident))
    t_first, t_last = float(log.t[0]), float(log.t[-1])
    for ident, entry in meta.items():
        if ident in seen or entry["end"] < t_first or entry["start"] > t_last:
            continue
        windows.append(Window(ident, entry["start"], entry["end"], entry["peak"]))
    windows.sort(key=lambda w: (w.start, w.id))
    return windows


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
        ``start_delay``, ``end_delay`` [s] (NaN when missed), ``n_events``
        (events detecting the window) and ``joints`` (tuple of the 1-based
        joints of those events).
    events : list of Event
        All evaluated events, by start time.
    detections : list of Event
        Events that detect at least one window.
    false_alarms : list of Event
        Events outside every ``[start - tolerance, end + max_delay]``.
    excused : list of Event
        Events that only touch the ``tolerance`` margin before a window.
    duration : float
        Duration of the log [s] (last minus first time stamp).
    t_start : float
        First time stamp of the log [s].
    false_alarm_rate : float
        False alarms per hour of motion [1/h].
    n_detected, n_missed : int
        Detected and missed windows.
    mean_start_delay : float
        Mean start delay over detected windows [s]; NaN if none is detected.
    tolerance, max_delay : float
        Matching settings [s] (see the module docstring).
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

    def to_pandas(self) -> pd.DataFrame:
        """The per-collision table (a copy of :attr:`per_collision`)."""
        return self.per_collision.copy()

    def summary(self) -> dict[str, Any]:
        """One-row summary.

        Returns
        -------
        dict
            ``method``, ``n_collisions``, ``n_detected``, ``n_missed``,
            ``detected`` (text ``"k/n"``), ``n_false_alarms``,
            ``false_alarm_rate`` [1/h], ``mean_start_delay``,
            ``mean_end_delay``, ``max_start_delay`` [s] and ``duration`` [s].
        """
        return {
            "method": self.method,
            "n_collisions": self.n_collisions,
            "n_detected": self.n_detected,
            "n_missed": self.n_missed,
            "detected": f"{self.n_detected}/{self.n_collisions}",
            "n_false_alarms": self.n_false_alarms,
            "false_alarm_rate": self.false_alarm_rate,
            "mean_start_delay": self.mean_start_delay,
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
        Margin [s] before each window inside which an event is not counted as
        a false alarm (nor as a detection). Default 0.
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
    detects = _overlaps(starts, ends, w_start, w_end + delay)
    near = _overlaps(starts, ends, w_start - margin, w_end + delay)

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
                "start_delay": float(starts[hits].min() - window.start) if detected else math.nan,
                "end_delay": float(ends[hits].max() - window.end) if detected else math.nan,
                "n_events": int(hits.size),
                "joints": tuple(joints),
            }
        )
    per_collision = pd.DataFrame(rows, columns=["id", *_PER_COLLISION_COLUMNS]).set_index("id")
    per_collision["detected"] = per_collision["detected"].astype(bool)
    per_collision["n_events"] = per_collision["n_events"].astype(np.int64)

    is_detection = [bool(row.any()) for row in detects]
    is_false = [not row.any() for row in near]
    duration = log.duration
    n_false = sum(is_false)
    n_detected = int(per_collision["detected"].sum())
    delays = per_collision["start_delay"].to_numpy(dtype=float)
    return Evaluation(
        method=method,
        windows=windows,
        per_collision=per_collision,
        events=checked,
        detections=[e for e, hit in zip(checked, is_detection, strict=True) if hit],
        false_alarms=[e for e, bad in zip(checked, is_false, strict=True) if bad],
        excused=[
            e
            for e, hit, bad in zip(checked, is_detection, is_false, strict=True)
            if not (hit or bad)
        ],
        duration=duration,
        t_start=float(log.t[0]),
        false_alarm_rate=n_false / (duration / SECONDS_PER_HOUR),
        n_detected=n_detected,
        n_missed=len(windows) - n_detected,
        mean_start_delay=float(np.nanmean(delays)) if n_detected else math.nan,
        tolerance=margin,
        max_delay=delay,
    )


def _check_evaluations(evaluations: Mapping[str, Evaluation]) -> list[tuple[str, Evaluation]]:
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


def comparison_table(
    evaluations: Mapping[str, Evaluation], *, missed: str = "missed"
) -> pd.DataFrame:
    """Per-collision delays of several methods side by side (Tables 4.3, 5.4, 5.9).

    Parameters
    ----------
    evaluations : mapping of str to Evaluation
        Evaluations of the methods on the same log, by method name.
    missed : str
        Entry for a collision a method does not detect (the thesis writes
        "Does not Detect").

    Returns
    -------
    DataFrame
        Indexed by collision id (``"collision"``); two-level columns:
        ``("window", "start")``, ``("window", "end")`` [s] and
        ``("window", "peak_force")`` [N], then for each method
        ``(name, "start_delay")`` and ``(name, "end_delay")`` [s], holding a
        delay or ``missed``.

    Raises
    ------
    InputValueError
        The mapping is empty, a method is named ``"window"``, or the
        evaluations were made on different collision windows.
    TypeError
        ``evaluations`` is not a mapping of :class:`Evaluation`.
    """
    items = _check_evaluations(evaluations)
    if "window" in evaluations:
        raise InputValueError(
            "a method may not be named 'window' in comparison_table; that column group "
            "holds the ground-truth windows"
        )
    reference_name, reference = items[0]
    windows = reference.per_collision[["start", "end", "peak_force"]]
    for name, evaluation in items[1:]:
        other = evaluation.per_collision[["start", "end"]]
        if list(other.index) != list(windows.index) or not np.allclose(
            other.to_numpy(dtype=float), windows[["start", "end"]].to_numpy(dtype=float)
        ):
            raise InputValueError(
                f"evaluations must be made on the same collision windows; {name!r} has "
                f"windows {list(other.index)} and {reference_name!r} has {list(windows.index)} "
                "(ids or times differ)"
            )
    columns: dict[tuple[str, str], Any] = {
        ("window", key): windows[key].to_numpy(dtype=float)
        for key in ("start", "end", "peak_force")
    }
    for name, evaluation in items:
        table = evaluation.per_collision
        for key in ("start_delay", "end_delay"):
            columns[(name, key)] = [
                float(value) if hit else missed
                for value, hit in zip(table[key], table["detected"], strict=True)
            ]
    result = pd.DataFrame(columns, index=pd.Index(windows.index, name="collision"))
    result.columns = pd.MultiIndex.from_tuples(list(columns), names=["method", "quantity"])
    return result


def summary_table(evaluations: Mapping[str, Evaluation]) -> pd.DataFrame:
    """One row per method: detected/total, false alarms, rate per hour, delays.

    Parameters
    ----------
    evaluations : mapping of str to Evaluation
        Evaluations by method name (the names index the table).

    Returns
    -------
    DataFrame
        Indexed by method name (``"method"``), with the columns of
        :meth:`Evaluation.summary` except ``method``.

    Raises
    ------
    InputValueError
        The mapping is empty.
    TypeError
        ``evaluations`` is not a mapping of :class:`Evaluation`.
    """
    items = _check_evaluations(evaluations)
    rows = []
    for _, evaluation in items:
        row = evaluation.summary()
        del row["method"]
        rows.append(row)
    return pd.DataFrame(rows, index=pd.Index([name for name, _ in items], name="method"))


def _joint_vector(values: ArrayLike, name: str) -> FloatArray:
    try:
        arr = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise DimensionError(
            f"{name} must be a numeric array of shape (n_dof,); got {values!r}"
        ) from None
    if arr.ndim != 1 or arr.size == 0:
        raise DimensionError(f"{name} must have shape (n_dof,) with n_dof >= 1; got {arr.shape}")
    if not np.isfinite(arr).all():
        raise InputValueError(f"{name} must be finite; got {arr.tolist()}")
    return arr


def efficiency_table(
    alpha: ArrayLike,
    beta: ArrayLike,
    *,
    extra: Mapping[str, ArrayLike] | None = None,
) -> pd.DataFrame:
    """Effectiveness eff = α/β of a time-variant threshold per joint (Table 5.7).

    Smaller values mean that the time-variant threshold b_2H/b_2L (eq. 5.33,
    5.39), whose constant part is α, is tighter than the constant threshold
    β = max|r̂| of eq. (5.32).

    Parameters
    ----------
    alpha : array-like of shape (n_dof,)
        Constant part α of the time-variant threshold [N m].
    beta : array-like of shape (n_dof,)
        Constant threshold β [N m], positive.
    extra : mapping of str to array-like of shape (n_dof,), optional
        Further rows shown between α and β, e.g. ``{"gamma": ..., "C": ...}``.

    Returns
    -------
    DataFrame
        Rows ``alpha``, the ``extra`` rows, ``beta``, ``eff``; columns the
        1-based joint numbers (``"joint"``).

    Raises
    ------
    DimensionError
        An input is not one-dimensional or the lengths differ.
    InputValueError
        A value is not finite, ``beta`` is not positive, or an ``extra`` row
        is named ``alpha``, ``beta`` or ``eff``.

    Examples
    --------
    >>> table = efficiency_table([2.0137, 1.8727, 2.3715], [2.5662, 2.4758, 2.8413])
    >>> table.loc["eff"].round(4).tolist()  # Table 5.7, KUKA-LWR
    [0.7847, 0.7564, 0.8347]
    """
    a = _joint_vector(alpha, "alpha")
    reserved = {"alpha", "beta", "eff"} & {str(name) for name in (extra or {})}
    if reserved:
        raise InputValueError(
            f"extra rows may not be named 'alpha', 'beta' or 'eff'; got {sorted(reserved)}"
        )
    rows: dict[str, FloatArray] = {"alpha": a}
    labelled = [(str(name), f"extra[{name!r}]", values) for name, values in (extra or {}).items()]
    for row, label, values in [*labelled, ("beta", "beta", beta)]:
        vector = _joint_vector(values, label)
        if vector.shape != a.shape:
            raise DimensionError(
                f"{label} must have the shape of alpha, ({a.size},); got {vector.shape}"
            )
        rows[row] = vector
    b = rows["beta"]
    if not (b > 0.0).all():
        raise InputValueError(f"beta must be positive to form eff = alpha/beta; got {b.tolist()}")
    rows["eff"] = a / b
    return pd.DataFrame.from_dict(
        rows, orient="index", columns=pd.RangeIndex(1, a.size + 1, name="joint")
    )
