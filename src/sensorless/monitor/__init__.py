"""The whole detection pipeline: velocity estimation, observer, threshold, detector.

:func:`tune` fits a threshold family on collision-free logs (:mod:`.tuning`);
a :class:`CollisionMonitor` applies it to a recorded log
(:meth:`~CollisionMonitor.run`, :meth:`~CollisionMonitor.process`) or to a
live stream one sample at a time (:meth:`~CollisionMonitor.step`), with the
same result (:mod:`.stream`, :mod:`.batch`), under the fault, restart,
settling and latching rules of :mod:`.policy`, optionally adapting its
nominal friction to drift (:mod:`.adaptation`). :func:`tune` also
cross-validates the threshold on its collision-free logs and can set the
margin for a stated false-alarm rate (:func:`cross_validate`,
:func:`margin_for_rate`, :mod:`.calibration`); observer settings and that
:class:`Calibration` travel with the fitted threshold in one YAML file
(:func:`save_tuned`, :func:`load_tuned`).
Units SI and radians; time along axis 0.
"""

from __future__ import annotations

from ._codes import CompiledStep
from .adaptation import Adaptation
from .batch import FaultSpan, MonitorRun
from .calibration import (
    Calibration,
    RateMargin,
    calibration_of,
    cross_validate,
    hours_needed,
    margin_for_rate,
    poisson_interval,
)
from .levels import LevelledMonitor, LevelledRun, tune_levels
from .policy import Limits, StreamPolicy
from .stream import CollisionMonitor
from .tuning import (
    METHOD_NAMES,
    ObserverSettings,
    load_tuned,
    make_threshold,
    save_tuned,
    tune,
)

__all__ = [
    "METHOD_NAMES",
    "Adaptation",
    "Calibration",
    "CollisionMonitor",
    "CompiledStep",
    "FaultSpan",
    "LevelledMonitor",
    "LevelledRun",
    "Limits",
    "MonitorRun",
    "ObserverSettings",
    "RateMargin",
    "StreamPolicy",
    "calibration_of",
    "cross_validate",
    "hours_needed",
    "load_tuned",
    "make_threshold",
    "margin_for_rate",
    "poisson_interval",
    "save_tuned",
    "tune",
    "tune_levels",
]
