"""``sensorless train-detector``: train the learned family's network on simulated runs."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from ..exceptions import InputValueError
from ..learning import TrainingRecipe, scenario_for, train_detector
from ..thresholds import save_weights
from ._common import console, output_path, run_with_spinner

__all__ = ["MAX_MINUTES", "MAX_STEPS", "train_detector_command"]

MAX_MINUTES = 10_080.0
"""Most simulated minutes ``train-detector`` accepts (a week)."""
MAX_STEPS = 1_000_000
"""Most Adam steps ``train-detector`` accepts."""


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
    steps: Annotated[int, typer.Option("--steps", min=1, max=MAX_STEPS, help="Adam steps.")] = 1500,
    payload_max: Annotated[
        float,
        typer.Option(
            "--payload-max",
            help="Largest payload mass in kg on the true robot (half the runs carry one, "
            "U(0, this)); 0: none, as the shipped weights (a payload the network cannot "
            "see widens its band on an arm that carries none).",
        ),
    ] = 0.0,
    rate_factor: Annotated[
        tuple[float, float],
        typer.Option(
            "--rate-factor",
            help="Range of the factor on the scenario's sample rate; the weights accept "
            "periods in the band it spans. 1 1: the scenario's period only.",
        ),
    ] = (0.8, 1.25),
) -> None:
    """Simulate randomised labelled runs, train the network, write the weights file.

    Each run draws its model error, noise, speed, payload (on the true robot)
    and sample rate; the weights file records the ranges and the draws.
    """
    if not output.name or output.is_dir():
        raise InputValueError(f"-o must be a file stem such as weights/panda; got {str(output)!r}")
    for suffix in (".npz", ".json"):  # before the training, not after it
        output_path(output.with_suffix(suffix))
    if not 0.0 < minutes <= MAX_MINUTES:  # NaN fails too
        raise InputValueError(f"--minutes must be > 0 and <= {MAX_MINUTES:g}; got {minutes!r}")
    recipe = TrainingRecipe(
        scenario=scenario or scenario_for(robot),
        minutes=minutes,
        seed=seed,
        steps=steps,
        payload_mass=(0.0, payload_max),
        payload_share=0.5 if payload_max > 0 else 0.0,
        rate_factor=rate_factor,
    )
    weights = run_with_spinner("training", lambda: train_detector(recipe))
    path = save_weights(weights, output)
    loss = weights.recipe["final_loss"]
    console.print(
        f"wrote {path} ({weights.network.n_parameters} parameters, final loss {loss:.3f})"
    )
