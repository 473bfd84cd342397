"""Compare threshold families on a scenario: the thesis's comparisons end to end.

:func:`compare` simulates collision-free (tuning) runs and a collision (test)
run of a scenario with seeds derived from one master seed, tunes every
threshold family on the tuning runs, detects on the test run and evaluates
against the ground truth. :func:`real_arm` runs the same families on the
real UR10 recordings when they are at hand (:mod:`sensorless.realarm`), or
says why not. :func:`write_comparison_report` turns the results into a
self-contained HTML report with tables and figures.
"""

from __future__ import annotations

from .realarm import RealArm, real_arm
from .results import Comparison
from .runs import compare
from .writing import REAL_ARM_HEADING, write_comparison_report

__all__ = [
    "REAL_ARM_HEADING",
    "Comparison",
    "RealArm",
    "compare",
    "real_arm",
    "write_comparison_report",
]
