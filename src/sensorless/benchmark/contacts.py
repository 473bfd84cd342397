"""Per event of a collision run: which link, where, how hard, and was it meant (issue 12).

For every event a detector raises on a collision run, :func:`score_events`
asks an :class:`~sensorless.isolation.Isolator` (capsules around the links
of the model the residual was computed with) for the contact link, point and
force, and :func:`~sensorless.classification.classify_events` (the stated
cut-offs) for its class, then scores both against the simulator's ground
truth: :func:`~sensorless.evaluation.evaluate_isolation` (the *true* robot
places the true point; the observer's gain gives the force through its
filter) and :func:`~sensorless.evaluation.evaluate_classification`. Both
match an event to the earliest contact whose window ``[start, end +
max_delay]`` holds the event's start; an event matched to no contact (a
false alarm) keeps its estimate and its class, with no errors. The columns
are :data:`CONTACT_COLUMNS`.

Which sample is isolated
------------------------
One per event: the sample of the largest excursion beyond a bound inside the
event, as :meth:`Isolator.isolate_events <sensorless.isolation.Isolator.isolate_events>`
does with ``window=0``. From the isolator's own design
(:mod:`sensorless.isolation.estimate`):

* its error has two parts. The residual lags τ_c through K_I/(s+K_I), an
  error that decays as exp(−K_I (t − t_p)) once the force stops rising at
  t_p (``tests/test_isolation.py``); and the model error, which the bands
  contain, adds at most the worst-case bound Σ_j |P_ij| δ_j, fixed by the
  band half-widths δ and not by the force. Both shrink relative to |F| where
  r̂ is furthest beyond its band: at the peak, which is where an impact's
  residual ends its rise and where a push's residual has converged on its
  plateau;
* its fit is 25–34 ms per sample in Python (``benchmarks/bench_isolation.py``),
  and a sample's estimate depends on that sample only, so one sample per
  event bounds the cost by the number of events, not by their length (a
  guiding hand's event lasts seconds);
* an average over a window around the peak (``window > 0``) assumes a
  constant force over it, which an impact of 3–100 ms is not.

Units: time [s], points [m], forces [N], directions [deg].
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from ..classification import classify_events
from ..evaluation import evaluate_classification, evaluate_isolation
from ..io import Log
from ..isolation import ContactEstimate, Isolator
from ..robots.model import RobotModel
from ..signals import Event, ObserverSignals

__all__ = ["CONTACT_COLUMNS", "DetectorRun", "score_events"]

CONTACT_COLUMNS: dict[str, str] = {
    "contact": "Int64",
    "true_kind": "string",
    "assigned_kind": "string",
    "kind_correct": "boolean",
    "rules_failed": "string",
    "isolated_at": "float64",
    "link_true": "Int64",
    "link": "Int64",
    "link_ok": "boolean",
    "point_identifiable": "boolean",
    "point_error": "float64",
    "line_distance": "float64",
    "force_true": "float64",
    "force_filtered": "float64",
    "force_estimated": "float64",
    "force_bound": "float64",
    "force_error": "float64",
    "force_error_rel": "float64",
    "force_error_filtered": "float64",
    "direction_error": "float64",
    "above_quasi_static_min": "boolean",
    "above_quasi_static_max": "boolean",
    "above_transient_min": "boolean",
}
"""Columns the events table gains for the events of collision runs (empty elsewhere).

``contact``: id of the matched contact (0: none); ``true_kind`` ("intended",
"collision"; "none" unmatched), ``assigned_kind``, ``kind_correct``,
``rules_failed`` (the classifier's rules that said collision);
``isolated_at`` [s], the isolated sample; ``link_true``, ``link``,
``link_ok``, ``point_identifiable``; ``point_error`` [m] (right link only)
and ``line_distance`` [m] of the true point from the estimated line of
action; ``force_true`` |F| and ``force_filtered`` |K_I/(s+K_I)·F| at that
sample, ``force_estimated`` |F̂| and its worst-case ``force_bound`` [N];
``force_error`` = |F̂| − |F| [N], ``force_error_rel`` = that / |F| [-],
``force_error_filtered`` = |F̂| − |K_I/(s+K_I)·F| [N] (the lag left out);
``direction_error`` [deg] between F̂ and F; and |F̂| against the ISO/TS 15066
limits (:data:`~sensorless.isolation.QUASI_STATIC_LIMITS`: above 65 N, above
210 N, above twice 65 N).
"""


@dataclass(frozen=True)
class DetectorRun:
    """One detector's events on one collision run, with what isolating them needs.

    Attributes
    ----------
    events : sequence of Event
        The detector's events.
    signals : ObserverSignals
        The observer signals they were detected on.
    bounds : DetectionResult or (lower, upper)
        The detector's bounds over the run [N m].
    isolator : Isolator
        Built on the model the residual was computed with.
    """

    events: Sequence[Event]
    signals: ObserverSignals
    bounds: Any
    isolator: Isolator


def _number(value: Any) -> float:
    return float(value) if value is not None and np.isfinite(value) else math.nan


def score_events(
    runs: Sequence[DetectorRun], log: Log, true_robot: RobotModel, max_delay: float
) -> list[list[dict[str, Any]]]:
    """The :data:`CONTACT_COLUMNS` of each event of each detector on one collision run.

    The true force of every contact (a Jacobian per contact sample) is
    computed once per observer gain, for the estimates of every detector
    with that gain together.

    Parameters
    ----------
    runs : sequence of DetectorRun
        Every detector's events on ``log``.
    log : Log
        The simulated run with its ground truth.
    true_robot : RobotModel
        The simulated robot (its kinematics place the true point).
    max_delay : float
        Time after a contact's end during which an event still matches it [s].

    Returns
    -------
    list of list of dict
        Per detector, one dict per event, in the order of ``runs`` and their events.
    """
    estimates = [
        run.isolator.isolate_events(
            run.events, run.signals.t,
            run.signals.position if run.signals.position is not None else log.q,
            run.signals.residual, run.bounds, skip_nonfinite=True,
        ) if run.events else []
        for run in runs
    ]  # fmt: skip
    fits: list[list[Any]] = [[] for _ in runs]
    gains = {float(run.signals.gain[0]) for run in runs if run.events}
    for gain in sorted(gains):
        mine = [i for i, run in enumerate(runs) if run.events and run.signals.gain[0] == gain]
        pooled = [e for i in mine for e in estimates[i]]
        table = evaluate_isolation(pooled, log, true_robot, gain=gain, max_delay=max_delay)
        rows = list(table.per_event.itertuples(index=False))
        for i in mine:
            fits[i], rows = rows[: len(estimates[i])], rows[len(estimates[i]) :]
    out: list[list[dict[str, Any]]] = []
    for run, found, judged in zip(runs, estimates, fits, strict=True):
        if not run.events:
            out.append([])
            continue
        classes = evaluate_classification(
            classify_events(run.events, run.signals), log, max_delay=max_delay
        ).records
        out.append(
            [
                _row(estimate, fit, kind)
                for estimate, fit, kind in zip(
                    found, judged, classes.itertuples(index=False), strict=True
                )
            ]
        )
    return out


def _row(estimate: ContactEstimate, fit: Any, kind: Any) -> dict[str, Any]:
    """One event's columns from its estimate, its isolation score and its class record."""
    matched = int(fit.id) > 0
    return {
        "contact": int(fit.id),
        "true_kind": str(kind.true),
        "assigned_kind": str(kind.assigned),
        "kind_correct": bool(kind.correct) if matched else None,
        "rules_failed": str(kind.failed),
        "isolated_at": float(estimate.t),
        "link_true": int(fit.link_true),
        "link": int(estimate.link),
        "link_ok": bool(fit.link_ok) if matched else None,
        "point_identifiable": bool(estimate.point_identifiable),
        "point_error": _number(fit.point_error),
        "line_distance": _number(fit.line_distance),
        "force_true": _number(fit.force_true),
        "force_filtered": _number(fit.force_filtered),
        "force_estimated": float(estimate.magnitude),
        "force_bound": float(estimate.magnitude_bound),
        "force_error": float(estimate.magnitude) - _number(fit.force_true),
        "force_error_rel": _number(fit.magnitude_error),
        "force_error_filtered": float(estimate.magnitude) - _number(fit.force_filtered),
        "direction_error": math.degrees(_number(fit.direction_error)),
        "above_quasi_static_min": bool(estimate.exceeds_quasi_static_min),
        "above_quasi_static_max": bool(estimate.exceeds_quasi_static_max),
        "above_transient_min": bool(estimate.exceeds_transient_min),
    }
