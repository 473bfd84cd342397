"""Collision detection: a residual outside its threshold bounds, grouped into events.

A sample is *outside* when the residual of any monitored joint is below its
lower or above its upper bound (eq. 3.37/3.39, 4.34, 5.31). Consecutive
outside samples form an event; ``start`` and ``end`` are the times of its
first and last outside sample. Two events whose gap (start of the second
minus end of the first) is shorter than ``hold`` [s] are merged, and events
lasting less than ``min_duration`` [s] (``end - start``) are dropped, after
merging; both compare up to :data:`TIME_TOLERANCE` (1 ns), so that a whole
number of sample periods equal to ``hold`` or ``min_duration`` counts as
equal at every sample rate. An event's ``joints`` are those outside at any
of its samples and its ``peak`` is the largest excursion beyond a bound (the
first one if several are equal).

:meth:`Detector.run` / :meth:`Detector.detect` work on a recorded run;
:meth:`Detector.initial_state`, :meth:`Detector.step` and
:meth:`Detector.finish` on a live stream, and give the same events.

Faulty samples in a stream
--------------------------
:meth:`Detector.step` never raises on bad data. A sample with a NaN or an
infinity in any input, or whose time does not increase past the last
accepted sample, gives a verdict with status ``"fault"`` and returns the
state unchanged: the sample is skipped as if it had not arrived, so the
filters of the threshold do not advance and every later verdict equals the
one of the same stream without that sample. The threshold's filters treat
the next accepted sample as one period ``dt`` later. ``run(...,
skip_nonfinite=True)`` applies the same rule to a recorded run; by default
it raises instead.

Examples
--------
Two bumps 10 ms apart are one event when ``hold`` is longer than the gap:

>>> import numpy as np
>>> from sensorless.signals import ObserverSignals
>>> from sensorless.thresholds import ConstantThreshold
>>> def run(r):  # a residual r [N m] at 1 kHz, the other signals zero
...     z = np.zeros_like(r)
...     return ObserverSignals(np.arange(len(r)) * 1e-3, r, z, z, z, z, gain=20.0)
>>> quiet = 0.1 * np.sin(np.arange(100) * 0.04)[:, None]
>>> detector = Detector(ConstantThreshold(margin=0.05).fit(run(quiet)), hold=0.02)
>>> hit = quiet.copy()
>>> hit[40:45] += 1.0
>>> hit[55:60] += 1.0
>>> [(round(e.start, 3), round(e.end, 3), e.joints) for e in detector.detect(run(hit))]
[(0.04, 0.059, (1,))]
"""

from __future__ import annotations

from ._results import DetectionResult, DetectorState, Status, Verdict, events_to_pandas
from .detector import TIME_TOLERANCE, Detector
from .levels import (
    LEVELS,
    LevelledDetector,
    LevelledEvent,
    LevelledResult,
    LevelledState,
    LevelledVerdict,
    levelled_events_to_pandas,
)

__all__ = [
    "LEVELS",
    "TIME_TOLERANCE",
    "DetectionResult",
    "Detector",
    "DetectorState",
    "LevelledDetector",
    "LevelledEvent",
    "LevelledResult",
    "LevelledState",
    "LevelledVerdict",
    "Status",
    "Verdict",
    "events_to_pandas",
    "levelled_events_to_pandas",
]
