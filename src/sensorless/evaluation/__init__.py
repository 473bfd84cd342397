"""Evaluation of collision detection against ground-truth collision windows.

A log with ground-truth labels (``collision_id``, and the contact list in
``metadata["collisions"]`` that the simulator writes) defines one
:class:`Window` per collision. :func:`evaluate` matches the :class:`~sensorless.signals.Event`
list of one detection method to these windows and returns an :class:`Evaluation`:
per collision whether it was detected, masked by an alarm already on, or missed,
and the delays of the start and the end of the detection, plus the false alarms
and their rate per hour of motion.

:func:`comparison_table` and :func:`summary_table` put several methods side by
side in the style of the thesis' Tables 4.3, 5.4 and 5.9; :func:`efficiency_table`
is Table 5.7 (eff = α/β).

Matching rules
--------------
For a window ``[start, end]`` and the settings ``max_delay`` and ``tolerance`` [s]:

* an event *detects* the window when it starts inside ``[start, end + max_delay]``;
  an event may detect several windows. The *start delay* is the earliest start
  of a detecting event minus ``start`` (never negative), the *end delay* the
  latest end of a detecting event minus ``end``;
* an alarm that began before a contact and is still on when the contact
  starts (``event.start < start <= event.end``) cannot tell anything about
  that contact: the event is a *false alarm* (unless it detects another
  window or is excused, below), and the window, when no event detects it,
  is *masked*: neither detected nor missed, counted apart (``masked``
  column, ``n_masked``). So a detection is never credited with a negative
  delay;
* every window is exactly one of detected, masked or missed;
* an event that detects no window is a *false alarm*, except that one that
  starts inside the ``tolerance`` margin ``[start - tolerance, start)`` of a
  window, or only touches that margin without masking a window, is
  *excused*: neither a detection nor a false alarm (a residual may cross its
  bound just before a label whose onset is uncertain by a few samples).

The default ``max_delay`` of :data:`DEFAULT_MAX_DELAY` = 0.5 s is above the
largest detection delay the thesis reports (0.31 s, Table 5.4; 0.42 s,
Table 5.9) and below the 1 s minimum gap between simulated contacts.
"""

from __future__ import annotations

from .classification import (
    ClassificationEvaluation,
    classification_table,
    evaluate_classification,
    ground_truth_kinds,
)
from .isolation import IsolationEvaluation, evaluate_isolation
from .scoring import DEFAULT_MAX_DELAY, Evaluation, evaluate
from .tables import comparison_table, efficiency_table, summary_table
from .windows import Window, collision_windows

__all__ = [
    "DEFAULT_MAX_DELAY",
    "ClassificationEvaluation",
    "Evaluation",
    "IsolationEvaluation",
    "Window",
    "classification_table",
    "collision_windows",
    "comparison_table",
    "efficiency_table",
    "evaluate",
    "evaluate_classification",
    "evaluate_isolation",
    "ground_truth_kinds",
    "summary_table",
]
