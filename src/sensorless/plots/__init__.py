"""Figures of residuals, thresholds, collision windows and evaluations.

Every function returns a :class:`matplotlib.figure.Figure` built without
:mod:`matplotlib.pyplot`, so no GUI backend is needed or selected and nothing
is shown: save it with ``fig.savefig(path)`` or embed it in a report
(:func:`sensorless.report.write_report`). Time is in seconds, joint torques
in N m, joints are numbered from 1. Figures are 11 in wide (1100 px at
100 dpi, the report's content column) and keep their legend off the data.

* :func:`plot_residuals` — residual of each joint against the lower/upper
  bounds of one or more threshold methods, with the ground-truth collision
  windows shaded, detections and false alarms marked differently, and long
  runs drawn as min/max envelopes (thesis Figs. 4.6, 5.6, 5.13).
* :func:`plot_tau_c` — ground-truth external torque τ_c against the residual.
* :func:`plot_evaluation` — timeline of windows, detections, false alarms,
  missed and masked collisions of one or more
  :class:`~sensorless.evaluation.Evaluation` objects.
* :func:`plot_detection_vs_force` — detection rate per peak-force bin, and
  every collision by force.
* :func:`plot_collision` — ±0.5 s around one collision on the joints that
  feel it: residual, every method's bounds, the true τ_c, detection instants.
* :func:`plot_missed` — for the methods that missed a collision, how far the
  residual stayed from the bound (:func:`headroom`).
* :func:`plot_planned_trajectory` — a trajectory planned by
  :func:`sensorless.metric.optimize_trajectory` against the quintic, and the
  bound B_c(t) along both.
* :func:`plot_held_out` — a held-out real recording of
  :func:`sensorless.realarm.evaluate_folds`: its residual against every
  family's bounds, apparent contacts shaded.
* :func:`plot_isolation` — estimated against true contact force over each
  event (:func:`sensorless.evaluation.evaluate_isolation`).
"""

from __future__ import annotations

from .collisions import (
    Headroom,
    describe,
    headroom,
    joints_that_matter,
    plot_collision,
    plot_missed,
)
from .isolation import plot_isolation
from .residuals import plot_held_out, plot_residuals, plot_tau_c
from .timeline import force_bins, plot_detection_vs_force, plot_evaluation
from .trajectory import plot_planned_trajectory

__all__ = [
    "Headroom",
    "describe",
    "force_bins",
    "headroom",
    "joints_that_matter",
    "plot_collision",
    "plot_detection_vs_force",
    "plot_evaluation",
    "plot_held_out",
    "plot_isolation",
    "plot_missed",
    "plot_planned_trajectory",
    "plot_residuals",
    "plot_tau_c",
]
