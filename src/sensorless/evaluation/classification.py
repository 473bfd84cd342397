"""Scoring of the intended-contact vs collision classes against the ground truth.

The simulator writes each contact's class into the log's ground truth,
``metadata["collisions"][i]["kind"]`` ("intended" or "collision",
:mod:`sensorless.simulation.interactions`); an entry without ``kind`` gets
the label of its ``profile`` class (a guiding hand is intended, every other
profile a collision: :mod:`sensorless.simulation.interaction_profiles`).
:func:`ground_truth_kinds` reads them.

:func:`evaluate_classification` matches each classified event to the
ground-truth window it detects, by the rule of :func:`~sensorless.evaluation.evaluate`
(the event starts inside ``[start, end + max_delay]``; the earliest such
window), and returns a :class:`ClassificationEvaluation`: one record per
event, the confusion table of the matched events (true class × assigned
class) and the accuracy. Events that match no window (false alarms) have no
true class and stay out of the table; windows no event detects are not
classified at all. :func:`classification_table` puts several evaluations
side by side, one row each, for the tables of :mod:`sensorless.evaluation`.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass

import numpy as np
import pandas as pd

from .._validation import check_duration, check_type
from ..classification import KINDS, Classification
from ..exceptions import InputValueError, LogFormatError
from ..io import Log
from ..simulation.interaction_profiles import kind_of_profile
from .scoring import DEFAULT_MAX_DELAY
from .windows import collision_windows

__all__ = [
    "ClassificationEvaluation",
    "classification_table",
    "evaluate_classification",
    "ground_truth_kinds",
]

_RECORD_COLUMNS = ["start", "end", "window", "profile", "true", "assigned", "correct", "failed"]


def ground_truth_kinds(log: Log) -> dict[int, str]:
    """True class of every contact of a log, by contact id.

    Parameters
    ----------
    log : Log
        A log whose ``metadata["collisions"]`` lists its contacts (as the
        simulator writes it).

    Returns
    -------
    dict of int to str
        "intended" or "collision" per contact id: the entry's ``kind``, else
        the label of its ``profile``.

    Raises
    ------
    LogFormatError
        An entry's ``kind`` is not "intended" or "collision".
    """
    check_type(log, Log, "log")
    collision_windows(log)  # checks the entries' ids and times
    kinds: dict[int, str] = {}
    for index, entry in enumerate(log.metadata.get("collisions", [])):
        kind = entry.get("kind")
        if kind is None:
            kind = kind_of_profile(str(entry.get("profile", "")))
        if kind not in KINDS:
            raise LogFormatError(
                f"metadata['collisions'][{index}]['kind'] must be one of {list(KINDS)}; "
                f"got {kind!r}"
            )
        kinds[int(entry["id"])] = str(kind)
    return kinds


@dataclass(frozen=True)
class ClassificationEvaluation:
    """Classes of one run's events against the ground truth.

    Attributes
    ----------
    records : pandas.DataFrame
        One row per classified event: ``start``, ``end`` [s], ``window`` (id of
        the contact it detects, 0 if none), ``profile`` (the class name of
        that contact's force profile, empty if unknown), ``true`` and ``assigned`` class
        (``true`` is "none" for a false alarm), ``correct`` (bool; False for a
        false alarm), ``failed`` (the rules that said collision).
    n_windows : int
        Contacts in the ground truth.
    """

    records: pd.DataFrame
    n_windows: int

    @property
    def matched(self) -> pd.DataFrame:
        """The records of events that detect a contact."""
        return self.records[self.records["window"] > 0]

    @property
    def confusion(self) -> pd.DataFrame:
        """Counts of matched events: rows the true class, columns the assigned one."""
        matched = self.matched
        table = pd.crosstab(
            pd.Categorical(matched["true"], categories=list(KINDS)),
            pd.Categorical(matched["assigned"], categories=list(KINDS)),
            dropna=False,
        )
        table.index.name, table.columns.name = "true", "assigned"
        return table.astype(int)

    @property
    def accuracy(self) -> float:
        """Share of matched events with the right class (NaN without any)."""
        matched = self.matched
        return float(matched["correct"].mean()) if len(matched) else math.nan

    @property
    def n_false_alarms(self) -> int:
        """Classified events that detect no contact."""
        return int((self.records["window"] == 0).sum())

    def to_pandas(self) -> pd.DataFrame:
        """The per-event records."""
        return self.records.copy()

    @classmethod
    def pooled(cls, evaluations: Sequence[ClassificationEvaluation]) -> ClassificationEvaluation:
        """One evaluation of several runs: their records stacked, their contacts added."""
        chosen = [check_type(e, ClassificationEvaluation, "evaluation") for e in evaluations]
        if not chosen:
            raise InputValueError("pooled needs at least one ClassificationEvaluation; got none")
        records = pd.concat([e.records for e in chosen], ignore_index=True)
        return cls(records, sum(e.n_windows for e in chosen))


def evaluate_classification(
    classifications: Sequence[Classification],
    log: Log,
    *,
    max_delay: float = DEFAULT_MAX_DELAY,
) -> ClassificationEvaluation:
    """Score the classes of one run's events against its ground truth.

    Parameters
    ----------
    classifications : sequence of Classification
        Final classes of the run's events (:func:`~sensorless.classification.classify_events`).
    log : Log
        The run, with its ground truth (``metadata["collisions"]`` with ``kind``,
        or ``collision_id`` labels and the profile names).
    max_delay : float, default :data:`~sensorless.evaluation.DEFAULT_MAX_DELAY`
        Time after a contact's end during which an event still detects it [s].

    Returns
    -------
    ClassificationEvaluation
    """
    delay = check_duration(max_delay, "max_delay")
    kinds = ground_truth_kinds(log)
    profiles = {int(e["id"]): str(e.get("profile", "")) for e in log.metadata.get("collisions", [])}
    windows = collision_windows(log)
    rows = []
    for index, item in enumerate(classifications):
        check_type(item, Classification, f"classifications[{index}]")
        start = item.event.start if item.event is not None else item.features.start
        end = item.event.end if item.event is not None else item.features.end
        hits = [w for w in windows if w.start <= start <= w.end + delay]
        window = hits[0].id if hits else 0
        true = kinds.get(window, "collision") if window else "none"
        profile = profiles.get(window, "")
        failed = ",".join(item.failed)
        rows.append((start, end, window, profile, true, item.kind, true == item.kind, failed))
    records = pd.DataFrame(rows, columns=_RECORD_COLUMNS)
    records["window"] = records["window"].astype(np.int64)
    records["correct"] = records["correct"].astype(bool)
    return ClassificationEvaluation(records, len(windows))


def classification_table(evaluations: Mapping[str, ClassificationEvaluation]) -> pd.DataFrame:
    """One row per method: classified, correct, accuracy and the confusion counts.

    Parameters
    ----------
    evaluations : mapping of str to ClassificationEvaluation
        By method name (e.g. one per threshold family, or "exact model" and
        "model error").

    Returns
    -------
    pandas.DataFrame
        Index the names; columns ``n_windows``, ``n_classified`` (matched
        events), ``n_false_alarms``, ``accuracy`` and ``<true>-><assigned>``
        counts.
    """
    rows = {}
    for name, evaluation in evaluations.items():
        check_type(evaluation, ClassificationEvaluation, f"evaluations[{name!r}]")
        counts = evaluation.confusion.to_numpy()
        row: dict[str, float] = {
            "n_windows": evaluation.n_windows,
            "n_classified": len(evaluation.matched),
            "n_false_alarms": evaluation.n_false_alarms,
            "accuracy": evaluation.accuracy,
        }
        for i, true in enumerate(KINDS):
            for j, assigned in enumerate(KINDS):
                row[f"{true}->{assigned}"] = int(counts[i, j])
        rows[name] = row
    return pd.DataFrame.from_dict(rows, orient="index")
