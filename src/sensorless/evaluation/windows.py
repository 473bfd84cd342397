"""Ground truth: the collision windows of a labelled log.

Each collision of a log with ``collision_id`` labels and/or the contact list
``metadata["collisions"]`` that the simulator writes gives one :class:`Window`
(:func:`collision_windows`). Scoring against them: :mod:`sensorless.evaluation`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..exceptions import LogFormatError
from ..io import Log

__all__ = ["Window", "collision_windows"]


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
