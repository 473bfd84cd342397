"""Collision monitoring on a real arm: held-out false alarms on real recordings.

Real recordings carry no ground truth, and a nominal model from a URDF
knows no friction. The recipe: identify what the model lacks (a motor-torque
offset and friction, :func:`~sensorless.identification.identify_correction`)
on part of the recordings, tune each threshold family on part, and count the
alarms of the live monitor on the rest, cross-validated
(:func:`evaluate_folds` → :class:`RealArmEvaluation`, :mod:`.heldout`).
Spans that look like a hand on the arm are set apart
(:class:`Recording`, :mod:`.recordings`). :mod:`.ur10` applies it to the
UR10 recordings of ext_observer (:func:`evaluate_ur10`); the demo's "Real
arm (UR10)" section and ``examples/ur10_real_arm.py`` show the result.
Units SI and radians; time along axis 0.
"""

from __future__ import annotations

from .heldout import (
    DEFAULT_FAMILIES,
    DEFAULT_MARGIN_FRACTION,
    Fold,
    FoldResult,
    HeldOutRun,
    RealArmEvaluation,
    Tuned,
    Verdict,
    evaluate_folds,
)
from .recordings import Recording
from .ur10 import (
    APPARENT_CONTACTS,
    UR10_FOLDER,
    evaluate_ur10,
    load_ur10,
    missing_files,
    standing_residual,
    ur10_folds,
)

__all__ = [
    "APPARENT_CONTACTS",
    "DEFAULT_FAMILIES",
    "DEFAULT_MARGIN_FRACTION",
    "UR10_FOLDER",
    "Fold",
    "FoldResult",
    "HeldOutRun",
    "RealArmEvaluation",
    "Recording",
    "Tuned",
    "Verdict",
    "evaluate_folds",
    "evaluate_ur10",
    "load_ur10",
    "missing_files",
    "standing_residual",
    "ur10_folds",
]
