"""Command-line interface: a thin layer over the library (``sensorless --help``)."""

from __future__ import annotations

from collections.abc import Callable
from functools import partial
from pathlib import Path
from typing import Annotated

import numpy as np
import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from . import robots as robot_registry
from .exceptions import SensorlessError
from .io import write_log
from .robots.base_parameters import base_parameters
from .simulation.scenario import Scenario, available_scenarios, load_scenario
from .simulation.simulator import SimulationResult

app = typer.Typer(
    name="sensorless",
    help="Sensorless collision detection and external-torque estimation for robot arms.",
    no_args_is_help=True,
    add_completion=False,
)
console = Console()


def _fail(exc: SensorlessError) -> typer.Exit:
    console.print(f"[bold red]error:[/] {exc}")
    return typer.Exit(code=2)


def robot_summary() -> Table:
    """Table of the built-in robots: joints, base parameters and a dynamics check."""
    table = Table(title="Built-in robots")
    for column in ("robot", "joints", "standard params", "base params", "max |Yπ − RNEA| [N m]"):
        table.add_column(column, justify="right" if column != "robot" else "left")
    rng = np.random.default_rng(0)
    for name in robot_registry.available():
        robot = robot_registry.load(name)
        bp = base_parameters(robot)
        shape = (20, robot.n_dof)
        q, qd, qdd = (
            rng.uniform(-2, 2, shape),
            rng.standard_normal(shape),
            rng.standard_normal(shape),
        )
        error = np.abs(
            bp.regressor(q, qd, qdd) @ bp.values - robot.inverse_dynamics(q, qd, qdd)
        ).max()
        table.add_row(
            name, str(robot.n_dof), str(len(robot.parameter_names())), str(bp.count), f"{error:.1e}"
        )
    return table


@app.command("robots")
def robots_command() -> None:
    """Summarise the built-in robots (joints, base-parameter count, Yπ = RNEA check)."""
    console.print(robot_summary())


@app.command("scenarios")
def scenarios_command() -> None:
    """List the shipped simulation scenarios."""
    table = Table(title="Shipped scenarios")
    table.add_column("name")
    table.add_column("duration [s]", justify="right")
    table.add_column("description")
    for name in available_scenarios():
        scenario = load_scenario(name)
        table.add_row(
            name,
            f"{scenario.duration:g}",
            " ".join(str(scenario.spec.get("description", "")).split()),
        )
    console.print(table)


def _run_with_progress(
    label: str, run: Callable[[Callable[[int, int], None]], SimulationResult]
) -> SimulationResult:
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        TextColumn("{task.percentage:>3.0f}%"),
        TimeRemainingColumn(),
    )
    with Progress(*columns, console=console, transient=False) as progress:
        task = progress.add_task(label, total=1.0)

        def report(done: int, total: int) -> None:
            progress.update(task, completed=done / total)

        return run(report)


@app.command("simulate")
def simulate_command(
    scenario: Annotated[str, typer.Argument(help="Shipped scenario name or path of a YAML file.")],
    output: Annotated[
        Path, typer.Option("-o", "--output", help="Log file (.parquet or .csv).")
    ] = Path("run.parquet"),
    seed: Annotated[
        int | None, typer.Option("--seed", help="Run seed (default: the scenario's).")
    ] = None,
    collisions: Annotated[
        bool, typer.Option("--collisions/--no-collisions", help="Include the contacts.")
    ] = True,
) -> None:
    """Simulate a scenario and write its labelled log."""
    try:
        spec = load_scenario(scenario)
        result = _run_with_progress(
            f"simulating {spec.name}",
            lambda report: spec.run(seed=seed, collisions=collisions, progress=report),
        )
        path = write_log(result.log, output)
    except SensorlessError as exc:
        raise _fail(exc) from None
    console.print(
        f"wrote {path} ({result.log.n_samples} samples, {result.substeps} RK4 substeps per period)"
    )


def _run_scenario(scenario: Scenario, report: Callable[[int, int], None]) -> SimulationResult:
    return scenario.run(progress=report)


@app.command("demo")
def demo_command(
    output: Annotated[Path, typer.Option("--output", "-o", help="Output folder.")] = Path(
        "out/demo"
    ),
) -> None:
    """The end-to-end demo: robot summary, then every shipped scenario simulated with collisions."""
    console.print(robot_summary())
    output.mkdir(parents=True, exist_ok=True)
    table = Table(title="Simulated scenarios")
    for column in (
        "scenario",
        "samples",
        "max tracking error [rad]",
        "contacts",
        "max |τ_c| [N m]",
        "log",
    ):
        table.add_column(column)
    for name in available_scenarios():
        scenario = load_scenario(name)
        result = _run_with_progress(f"simulating {name}", partial(_run_scenario, scenario))
        log = result.log
        tracking = float(np.abs(result.desired - np.asarray(log.q_true)).max())
        path = write_log(log, output / f"{name}.parquet")
        table.add_row(
            name,
            str(log.n_samples),
            f"{tracking:.2e}",
            str(len(log.metadata.get("collisions", []))),
            f"{np.abs(log.tau_c).max():.1f}" if log.tau_c is not None else "-",
            str(path),
        )
    console.print(table)


def main() -> None:
    """Entry point of the ``sensorless`` script."""
    app()
