"""A report section on two reaction levels: events by level, and their score against the truth.

:func:`levels_section` turns the events of a
:class:`~sensorless.detection.LevelledDetector` or a
:class:`~sensorless.monitor.LevelledMonitor` into a section of
:func:`~sensorless.report.write_report`: a table of counts per level (with
detections, misses and false alarms per level when the log carries ground
truth) and a table of the events with their level.

The *contact* row scores every excursion beyond the contact band (each
event, whatever its level); the *collision* row scores the collision band's
own events (those inside the collision-level events), which is what a
collision reflex would have fired on.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
import pandas as pd

from ..detection.levels import LEVELS, LevelledEvent, levelled_events_to_pandas
from ..evaluation import evaluate
from ..exceptions import InputTypeError
from ..io import Log
from .html import ReportItem, Table

__all__ = ["level_counts_table", "levels_section"]

_ROW_NAMES = {
    "contact": "contact band (every event)",
    "collision": "collision band",
}


def level_counts_table(events: Sequence[LevelledEvent], log: Log | None = None) -> pd.DataFrame:
    """Per level: events, and with a labelled ``log`` detected, missed and false alarms.

    Parameters
    ----------
    events : sequence of LevelledEvent
        Events of one run.
    log : Log, optional
        The run with its ground truth (``collision_id`` column); None: counts only.

    Returns
    -------
    DataFrame
        One row per level (index ``level``): ``events``, ``contact-level`` and
        ``collision-level`` (for the contact row), and with a log
        ``collisions detected``, ``missed``, ``false alarms``,
        ``false alarms [1/h]``, ``mean delay [ms]``.
    """
    checked = _checked(events)
    by_level = {
        "contact": [e.event for e in checked],
        "collision": [c for e in checked for c in e.collisions],
    }
    rows = []
    for level in LEVELS:
        row: dict[str, object] = {"level": _ROW_NAMES[level], "events": len(by_level[level])}
        if level == "contact":
            row["of which collision-level"] = sum(e.level == "collision" for e in checked)
        else:
            row["of which collision-level"] = np.nan
        if log is not None:
            scored = evaluate(by_level[level], log, method=level)
            row["collisions detected"] = scored.n_detected
            row["missed"] = scored.n_missed
            row["false alarms"] = len(scored.false_alarms)
            row["false alarms [1/h]"] = scored.false_alarm_rate
            row["mean delay [ms]"] = 1e3 * scored.mean_start_delay
        rows.append(row)
    return pd.DataFrame(rows).set_index("level")


def levels_section(
    events: Sequence[LevelledEvent],
    *,
    log: Log | None = None,
    heading: str = "Events by reaction level",
) -> tuple[str, list[ReportItem]]:
    """A section of :func:`~sensorless.report.write_report` on contact and collision events.

    Parameters
    ----------
    events : sequence of LevelledEvent
        Events of one run (e.g. ``LevelledMonitor.process(log).events``).
    log : Log, optional
        The run with its ground truth, to score each level.
    heading : str
        Heading of the section.

    Returns
    -------
    (heading, items)
        A pair for ``write_report(..., sections=[...])``.
    """
    checked = _checked(events)
    counts = level_counts_table(checked, log)
    items: list[ReportItem] = [
        "An event is an excursion of the residual beyond the contact band; its level is "
        "collision when the residual also left the collision band during it.",
        Table(counts, "Events per level", note=_count_note(log)),
    ]
    if checked:
        table = levelled_events_to_pandas(checked).rename(
            columns={
                "start": "start [s]",
                "end": "end [s]",
                "duration": "duration [s]",
                "peak": "peak beyond contact band [N m]",
                "peak_residual": "residual at peak [N m]",
                "collision_start": "collision start [s]",
                "collision_peak": "peak beyond collision band [N m]",
            }
        )
        table.index = pd.RangeIndex(1, len(table) + 1, name="event")
        items.append(Table(table, "Events with their level"))
    return heading, items


def _count_note(log: Log | None) -> str:
    if log is None:
        return "Counts only: the run carries no ground truth."
    return (
        "The contact row scores every event against the true contacts; the collision row "
        "the collision band's own events. Delays from the start of each contact."
    )


def _checked(events: Sequence[LevelledEvent]) -> list[LevelledEvent]:
    listed = list(events)
    for k, event in enumerate(listed):
        if not isinstance(event, LevelledEvent):
            raise InputTypeError(
                f"events[{k}] must be a LevelledEvent (from a LevelledDetector or a "
                f"LevelledMonitor); got {type(event).__name__}"
            )
    return listed
