"""Command-line interface: a thin layer over the library (``sensorless --help``).

Each command is one call into the library. A user's mistake ends in one line on
stderr and a distinct exit code (see :mod:`sensorless.cli._common`);
``sensorless --debug COMMAND ...`` shows the traceback instead.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Annotated

import typer

from ._common import settings, user_errors
from .benchmark import benchmark_command
from .demo import demo_command
from .identify import excite_command, identify_friction_command, identify_inertial_command
from .importing import import_command
from .plan import plan_command
from .report import report_command
from .run import (
    detect_command,
    evaluate_command,
    robots_command,
    scenarios_command,
    simulate_command,
    tune_command,
)
from .train import train_detector_command
from .warmup import warm_up_command

__all__ = ["app", "main"]

app = typer.Typer(
    name="sensorless",
    help="Sensorless collision detection and external-torque estimation for robot arms.",
    no_args_is_help=True,
    add_completion=False,
    pretty_exceptions_enable=False,
)
identify_app = typer.Typer(help="Identify friction and inertial parameters from logs.")
app.add_typer(identify_app, name="identify")


@app.callback()
def _options(
    debug: Annotated[bool, typer.Option("--debug", help="Show the traceback of an error.")] = False,
) -> None:
    settings["debug"] = debug


COMMANDS: dict[str, Callable[..., None]] = {
    "robots": robots_command,
    "scenarios": scenarios_command,
    "simulate": simulate_command,
    "tune": tune_command,
    "detect": detect_command,
    "evaluate": evaluate_command,
    "demo": demo_command,
    "benchmark": benchmark_command,
    "excite": excite_command,
    "import": import_command,
    "plan": plan_command,
    "report": report_command,
    "train-detector": train_detector_command,
    "warm-up": warm_up_command,
}
for name, command in COMMANDS.items():
    app.command(name)(user_errors(command))
identify_app.command("friction")(user_errors(identify_friction_command))
identify_app.command("inertial")(user_errors(identify_inertial_command))


def main() -> None:
    """Entry point of the ``sensorless`` script."""
    app()
