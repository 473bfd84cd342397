"""Intended contact or accidental collision: the class of each detected event (thesis §6.2 item 7).

A detected event is a person's *intended* interaction (a hand guiding or
pushing the arm: a slow force build-up, sustained, feeding the robot energy
at low power) or an accidental *collision* (an impact: a fast rise, short;
or a clamp against an obstacle). :func:`classify_events` tells them apart by
four stated rules on the event's residual (:mod:`.classifier`) from the
features of :mod:`.features`: the rise rate [N m/s], the duration [s], the
high-frequency fraction of the residual [-] and the mean power τ̂_cᵀq̇ [W].
:meth:`InteractionClassifier.fit` sets the cut-offs from labelled events;
:meth:`InteractionClassifier.step` follows a detector stream, with a
provisional class ``window`` seconds into an event and the final class, equal
to the batch one, when it ends. Scoring against ground truth:
:mod:`sensorless.evaluation.classification`.
"""

from __future__ import annotations

from .classifier import (
    KINDS,
    Classification,
    ClassifierState,
    Cutoffs,
    InteractionClassifier,
    classifications_to_pandas,
    classify_events,
)
from .features import FEATURE_NAMES, EventFeatures

__all__ = [
    "FEATURE_NAMES",
    "KINDS",
    "Classification",
    "ClassifierState",
    "Cutoffs",
    "EventFeatures",
    "InteractionClassifier",
    "classifications_to_pandas",
    "classify_events",
]
