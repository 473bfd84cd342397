"""What two-level detection returns: levelled events, the result of a run, stream types.

See :mod:`sensorless.detection.levels`. Units SI and radians; arrays have
time along axis 0 and shape ``(n_samples, n_dof)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Literal

import pandas as pd

from ..signals import Event
from ..thresholds.fitting import BoolArray
from ._results import DetectionResult, DetectorState, Verdict

__all__ = [
    "LEVELS",
    "Level",
    "LevelledEvent",
    "LevelledResult",
    "LevelledState",
    "LevelledStatus",
    "LevelledVerdict",
    "levelled_events_to_pandas",
]

Level = Literal["contact", "collision"]
LEVELS: tuple[Level, Level] = ("contact", "collision")
"""The two reaction levels, the lower first."""

LevelledStatus = Literal["ok", "contact", "collision", "fault", "settling"]

_EVENT_COLUMNS = [
    "start", "end", "duration", "joints", "peak", "peak_residual", "level",
    "collision_start", "collision_peak", "method",
]  # fmt: skip


@dataclass(frozen=True)
class LevelledEvent:
    """An excursion beyond the contact band, with its reaction level.

    Attributes
    ----------
    event : Event
        The excursion beyond the contact band (start, end, joints, peak
        beyond the contact band [N m]).
    level : {"contact", "collision"}
        ``"collision"`` if the collision band was left during it too.
    collisions : tuple of Event
        The collision band's events inside it (empty for a contact), peak
        beyond the collision band [N m].
    """

    event: Event
    level: Level
    collisions: tuple[Event, ...] = ()

    @property
    def start(self) -> float:
        """First time outside the contact band [s]."""
        return self.event.start

    @property
    def end(self) -> float:
        """Last time outside the contact band [s]."""
        return self.event.end

    @property
    def duration(self) -> float:
        """end − start [s]."""
        return self.event.duration

    @property
    def joints(self) -> tuple[int, ...]:
        """Joints (1-based) outside the contact band during the event."""
        return self.event.joints

    @property
    def collision_start(self) -> float:
        """First time outside the collision band [s]; NaN for a contact."""
        return self.collisions[0].start if self.collisions else math.nan


def levelled_events_to_pandas(events: list[LevelledEvent]) -> pd.DataFrame:
    """Table of levelled events, one row each: start, end, duration [s], joints, peak,
    peak_residual [N m], level, collision_start [s] and collision_peak [N m] (NaN for a
    contact), method."""
    rows = [
        [
            e.start, e.end, e.duration, e.joints, e.event.peak, e.event.peak_residual, e.level,
            e.collision_start, max((c.peak for c in e.collisions), default=math.nan),
            e.event.method,
        ]
        for e in events
    ]  # fmt: skip
    return pd.DataFrame(rows, columns=_EVENT_COLUMNS)


@dataclass(frozen=True, eq=False)
class LevelledResult:
    """Two-level detection over a recorded run.

    Attributes
    ----------
    contact : DetectionResult
        The contact level: bounds (clipped to the collision band) and events.
    collision : DetectionResult
        The collision level, as a :class:`Detector` with the collision
        threshold alone gives it.
    events : list of LevelledEvent
        The contact level's events with their level.
    crossed : ndarray of bool, shape (n_samples, n_dof)
        Where the contact band reached beyond the collision band and was
        clipped to it.
    """

    contact: DetectionResult
    collision: DetectionResult
    events: list[LevelledEvent]
    crossed: BoolArray

    def events_to_pandas(self) -> pd.DataFrame:
        """The events as a table, see :func:`levelled_events_to_pandas`."""
        return levelled_events_to_pandas(self.events)

    def counts(self) -> dict[str, int]:
        """Number of events per level: ``{"contact": ..., "collision": ...}``."""
        return {level: sum(e.level == level for e in self.events) for level in LEVELS}


@dataclass(frozen=True, eq=False)
class LevelledState:
    """What a :class:`LevelledDetector` carries from one sample of a stream to the next.

    Attributes
    ----------
    contact, collision : DetectorState
        States of the two levels' detectors.
    pending : tuple of Event
        Collision events closed while their contact event is still open.
    """

    contact: DetectorState
    collision: DetectorState
    pending: tuple[Event, ...] = ()


class LevelledVerdict:
    """What :meth:`LevelledDetector.step` says about one sample (read-only).

    Attributes
    ----------
    status : {"ok", "contact", "collision", "fault", "settling"}
        ``"collision"`` when the collision level's verdict is a collision,
        else ``"contact"`` when the contact level's is, else that of the
        contact level (``"ok"``, ``"fault"``); ``"settling"`` only from a
        monitor.
    t : float
        Time of the sample [s].
    contact, collision : Verdict or None
        The two levels' verdicts (None while a monitor settles).
    event : LevelledEvent or None
        The levelled event that ended at this sample, else None.
    """

    __slots__ = ("_collision", "_contact", "_event", "_status", "_t")

    def __init__(
        self,
        status: LevelledStatus,
        t: float,
        contact: Verdict | None,
        collision: Verdict | None,
        event: LevelledEvent | None = None,
    ) -> None:
        self._status, self._t = status, t
        self._contact, self._collision, self._event = contact, collision, event

    @property
    def status(self) -> LevelledStatus:
        return self._status

    @property
    def t(self) -> float:
        return self._t

    @property
    def contact(self) -> Verdict | None:
        return self._contact

    @property
    def collision(self) -> Verdict | None:
        return self._collision

    @property
    def event(self) -> LevelledEvent | None:
        return self._event

    def __repr__(self) -> str:
        return (
            f"LevelledVerdict(status={self.status!r}, t={self.t!r}, contact={self.contact!r}, "
            f"collision={self.collision!r}, event={self.event!r})"
        )
