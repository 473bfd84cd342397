"""Training of the learned threshold family on simulated, labelled runs.

``sensorless train-detector`` calls :func:`train_detector`.

:func:`train_detector` simulates randomised runs of a scenario, trains the
network of :class:`sensorless.thresholds.LearnedThreshold` on them and
returns :class:`~sensorless.thresholds.LearnedWeights`, which
:func:`~sensorless.thresholds.save_weights` writes. Numpy only (see
:mod:`.training`).
"""

from __future__ import annotations

from .training import (
    SCENARIOS,
    TrainingRecipe,
    TrainingRun,
    run_draws,
    scenario_for,
    train,
    train_detector,
    training_runs,
)

__all__ = [
    "SCENARIOS",
    "TrainingRecipe",
    "TrainingRun",
    "run_draws",
    "scenario_for",
    "train",
    "train_detector",
    "training_runs",
]
