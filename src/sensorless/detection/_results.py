"""What detection returns: a verdict per sample, the stream state, the result of a run.

Units SI and radians; arrays have time along axis 0 and shape ``(n_samples, n_dof)``.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Any, Literal

import numpy as np
import pandas as pd
from numpy.typing import NDArray

from .._validation import FloatArray
from ..signals import Event
from ..thresholds.state import ThresholdState

__all__ = ["DetectionResult", "DetectorState", "Status", "Verdict", "events_to_pandas"]

BoolArray = NDArray[np.bool_]
Status = Literal["ok", "collision", "fault", "settling"]

_EVENT_COLUMNS = [
    "start", "end", "duration", "joints", "peak", "peak_residual", "method", "level",
]  # fmt: skip


def _merged(earlier: Event, later: Event) -> Event:
    """One event from ``earlier`` to ``later``: joints of both, the larger peak (first if equal)."""
    peak = earlier if later.peak <= earlier.peak else later
    joints = tuple(sorted(set(earlier.joints) | set(later.joints)))
    return dataclasses.replace(peak, start=earlier.start, end=later.end, joints=joints)


class Verdict:
    """What :meth:`Detector.step` says about one sample.

    Read-only; a plain class with slots rather than a frozen dataclass,
    because a stream builds one per sample and a frozen dataclass costs
    about 2.5 µs to build, more than the compiled step itself.

    Parameters
    ----------
    status : {"ok", "collision", "fault", "settling"}
        ``"collision"``: the sample is outside its bounds and the event it
        belongs to has lasted at least ``min_duration``; ``"fault"``: the
        sample was skipped (non-finite input or time not increasing);
        ``"settling"``: a monitor's observer has just (re)started and the
        sample is not judged (never given by :meth:`Detector.step`).
    t : float
        Time of the sample [s].
    joints : tuple of int
        Monitored joints (1-based) outside their bounds at this sample; may
        be non-empty with status ``"ok"`` while an event is shorter than
        ``min_duration``.
    residual, lower, upper : ndarray of shape (n_dof,)
        Residual and bounds at this sample [N m] (bounds NaN on a fault).
    event : Event or None
        The event that ended at this sample (after ``hold`` and
        ``min_duration``), else None.
    message : str
        Why the sample is a fault; empty otherwise.

    The attributes of the same names are read-only.
    """

    __slots__ = ("_event", "_joints", "_message", "_rows", "_status", "_t")

    def __init__(
        self,
        status: Status,
        t: float,
        joints: tuple[int, ...],
        residual: FloatArray,
        lower: FloatArray,
        upper: FloatArray,
        event: Event | None = None,
        message: str = "",
    ) -> None:
        self._status, self._t, self._joints = status, t, joints
        self._rows: FloatArray | tuple[FloatArray, ...] = (residual, lower, upper)
        self._event, self._message = event, message

    @classmethod
    def _of_rows(
        cls,
        status: Status,
        t: float,
        joints: tuple[int, ...],
        rows: FloatArray,
        event: Event | None,
    ) -> Verdict:
        """A verdict whose residual, lower and upper are the rows of ``rows`` (3, n_dof)."""
        verdict = cls.__new__(cls)
        verdict._status, verdict._t, verdict._joints = status, t, joints
        verdict._rows, verdict._event, verdict._message = rows, event, ""
        return verdict

    @property
    def status(self) -> Status:
        return self._status

    @property
    def t(self) -> float:
        return self._t

    @property
    def joints(self) -> tuple[int, ...]:
        return self._joints

    @property
    def residual(self) -> FloatArray:
        return self._rows[0]

    @property
    def lower(self) -> FloatArray:
        return self._rows[1]

    @property
    def upper(self) -> FloatArray:
        return self._rows[2]

    @property
    def event(self) -> Event | None:
        return self._event

    @property
    def message(self) -> str:
        return self._message

    def __repr__(self) -> str:
        return (
            f"Verdict(status={self.status!r}, t={self.t!r}, joints={self.joints!r}, "
            f"residual={self.residual!r}, lower={self.lower!r}, upper={self.upper!r}, "
            f"event={self.event!r}, message={self.message!r})"
        )


@dataclass(frozen=True, eq=False)
class DetectorState:
    """What a :class:`Detector` carries from one sample of a stream to the next.

    :meth:`Detector.initial_state` gives the first one, :meth:`Detector.step`
    and :meth:`Detector.finish` the next.

    Attributes
    ----------
    dt : float
        Sample period of the stream [s], with which the threshold's state starts.
    threshold : ThresholdState or None
        State of the threshold; None until the first accepted sample.
    t : float
        Time of the last accepted sample [s] (``-inf`` before any).
    outside : bool
        Whether the last accepted sample was outside its bounds.
    open_event : Event or None
        The event in progress (possibly in its ``hold`` gap), without ``method`` yet.
    """

    dt: float
    threshold: ThresholdState | None = None
    t: float = -math.inf
    outside: bool = False
    open_event: Event | None = None


@dataclass(frozen=True, eq=False)
class DetectionResult:
    """Detection over a recorded run.

    Attributes
    ----------
    t : ndarray of shape (n_samples,)
        Time [s].
    residual, lower, upper : ndarray of shape (n_samples, n_dof)
        Residual and bounds [N m]; bounds are NaN at skipped samples.
    outside : ndarray of bool, shape (n_samples, n_dof)
        Monitored joint outside its bounds.
    valid : ndarray of bool, shape (n_samples,)
        Sample used (False: skipped, see the module docstring).
    events : list of Event
        Detected events.
    method : str
        Name of the threshold family.
    joints : tuple of int
        Monitored joints (1-based).
    dt : float
        Sample period the threshold's filters used [s]: the median step of
        the accepted samples. Stream with this ``dt`` to reproduce the run.
    """

    t: FloatArray
    residual: FloatArray
    lower: FloatArray
    upper: FloatArray
    outside: BoolArray
    valid: BoolArray
    events: list[Event]
    method: str
    joints: tuple[int, ...]
    dt: float

    def to_pandas(self) -> pd.DataFrame:
        """Per-sample table: ``t``, ``valid`` and ``residual_j``, ``lower_j``, ``upper_j``,
        ``outside_j`` for joints j = 1..n_dof."""
        columns: dict[str, Any] = {"t": self.t, "valid": self.valid}
        for name in ("residual", "lower", "upper", "outside"):
            values = getattr(self, name)
            for j in range(values.shape[1]):
                columns[f"{name}_{j + 1}"] = values[:, j]
        return pd.DataFrame(columns)

    def events_to_pandas(self) -> pd.DataFrame:
        """The events as a table, see :func:`events_to_pandas`."""
        return events_to_pandas(self.events)


def events_to_pandas(events: list[Event]) -> pd.DataFrame:
    """Table of events: start, end, duration [s], joints (tuple, 1-based), peak,
    peak_residual [N m], method, level; one row per event."""
    rows = [
        [e.start, e.end, e.duration, e.joints, e.peak, e.peak_residual, e.method, e.level]
        for e in events
    ]
    return pd.DataFrame(rows, columns=_EVENT_COLUMNS)
