"""``sensorless train-detector``: train the learned family's network on simulated runs."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..learning import TrainingRecipe, scenario_for, train_detector
from ..thresholds import save_weights
from ._common import console, run_with_spinner

__all__ = ["train_detector_command"]


def train_detector_command(
    robot: Annotated[str, typer.Option("--robot", help="Built-in robot (panda, puma560, lwr4).")],
    output: Annotated[
        Path, typer.Option("-o", "--output", help="Weights stem: writes <stem>.npz and .json.")
    ],
    minutes: Annotated[float, typer.Option("--minutes", help="Simulated minutes.")] = 3.0,
    seed: Annotated[int, typer.Option("--seed", help="Master seed.")] = 0,
    scenario: Annotated[
        str | None, typer.Option("--scenario", help="Scenario name or file (default: the robot's).")
    ] = None,
    steps: Annotated[int, typer.Option("--steps", help="Adam steps.")] = 1500,
) -> None:
    """Simulate randomised labelled runs, train the network, write the weights file."""
    recipe = TrainingRecipe(
        scenario=scenario or scenario_for(robot), minutes=minutes, seed=seed, steps=steps
    )
    weights = run_with_spinner("training", lambda: train_detector(recipe))
    path = save_weights(weights, output)
    loss = weights.recipe["final_loss"]
    console.print(
        f"wrote {path} ({weights.network.n_parameters} parameters, final loss {loss:.3f})"
    )
