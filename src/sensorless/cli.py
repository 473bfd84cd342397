"""Command-line interface: a thin layer over the library (``sensorless --help``)."""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Annotated

import numpy as np
import pandas as pd
import typer
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from . import robots as robot_registry
from .comparison import compare, write_comparison_report
from .detection import events_to_pandas
from .evaluation import comparison_table, evaluate, summary_table
from .exceptions import InputValueError, SensorlessError
from .io import Log, read_log, write_log
from .monitor import METHOD_NAMES, CollisionMonitor, ObserverSettings, load_tuned, save_tuned, tune
from .robots.base_parameters import base_parameters
from .robots.model import RobotModel
from .signals import Event
from .simulation.scenario import available_scenarios, load_scenario
from .simulation.simulator import SimulationResult

app = typer.Typer(
    name="sensorless",
    help="Sensorless collision detection and external-torque estimation for robot arms.",
    no_args_is_help=True,
    add_completion=False,
)
console = Console()


def _print_table(table: pd.DataFrame) -> None:
    console.print(table.to_string(), soft_wrap=True, highlight=False)


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


def _nominal_robot(robot: str | None, log: Log) -> RobotModel:
    """The nominal model: a built-in name, a URDF path, ``scenario:NAME``, or the log's scenario."""
    if robot is None:
        scenario = log.metadata.get("scenario")
        if not scenario:
            raise InputValueError(
                "give --robot (a built-in name, a URDF file or scenario:NAME); "
                "the log names no scenario"
            )
        robot = f"scenario:{scenario}"
    if robot.startswith("scenario:"):
        return load_scenario(robot.split(":", 1)[1]).robots()[1]
    if robot.endswith(".urdf"):
        return RobotModel.from_urdf(robot)
    return robot_registry.load(robot)


@app.command("tune")
def tune_command(
    logs: Annotated[list[Path], typer.Argument(help="Collision-free logs.")],
    method: Annotated[
        str, typer.Option("--method", help="constant, time-variant, hysteretic, velocity or model.")
    ],
    output: Annotated[Path, typer.Option("-o", "--output", help="Thresholds file (YAML).")] = Path(
        "thresholds.yaml"
    ),
    robot: Annotated[
        str | None, typer.Option("--robot", help="Nominal model (default: the log's scenario).")
    ] = None,
    gain: Annotated[float, typer.Option("--gain", help="Observer gain K_I [1/s].")] = 20.0,
    kind: Annotated[
        str | None, typer.Option("--kind", help="motor or joint (momentum methods).")
    ] = None,
    margin: Annotated[
        float, typer.Option("--margin", help="Margin added to the bounds [N m].")
    ] = 0.0,
) -> None:
    """Fit a threshold family on collision-free logs and save it with its observer settings."""
    try:
        runs = [read_log(path) for path in logs]
        nominal = _nominal_robot(robot, runs[0])
        settings = ObserverSettings(kind=kind or METHOD_NAMES.get(method, "motor"), gain=gain)
        threshold, settings = tune(runs, nominal, method, settings, margin=margin)
        path = save_tuned(output, threshold, settings)
    except SensorlessError as exc:
        raise _fail(exc) from None
    console.print(f"wrote {path}: {threshold!r} fitted on {len(runs)} log(s) of {nominal.name}")


def _detect(log_path: Path, thresholds: Path, robot: str | None) -> tuple[Log, str, list[Event]]:
    log = read_log(log_path)
    threshold, settings = load_tuned(thresholds)
    monitor = CollisionMonitor(_nominal_robot(robot, log), threshold, settings)
    return log, threshold.name, monitor.run(log)[1]


@app.command("detect")
def detect_command(
    log: Annotated[Path, typer.Argument(help="Log to check.")],
    thresholds: Annotated[Path, typer.Option("--thresholds", help="File written by `tune`.")],
    robot: Annotated[
        str | None, typer.Option("--robot", help="Nominal model (default: the log's scenario).")
    ] = None,
) -> None:
    """Detect collisions in a log and print the events."""
    try:
        _, method, events = _detect(log, thresholds, robot)
    except SensorlessError as exc:
        raise _fail(exc) from None
    console.print(f"{len(events)} event(s) detected by {method}")
    if events:
        _print_table(events_to_pandas(events))


@app.command("evaluate")
def evaluate_command(
    logs: Annotated[list[Path], typer.Argument(help="Logs with ground truth (collision ids).")],
    thresholds: Annotated[
        list[Path], typer.Option("--thresholds", help="Files written by `tune`.")
    ],
    robot: Annotated[
        str | None, typer.Option("--robot", help="Nominal model (default: the log's scenario).")
    ] = None,
) -> None:
    """Evaluate thresholds on labelled logs: detections, delays, false alarms."""
    try:
        for log_path in logs:
            evaluations = {}
            for path in thresholds:
                log, method, events = _detect(log_path, path, robot)
                evaluations[f"{method} ({path.name})"] = evaluate(events, log, method=method)
            console.print(f"[bold]{log_path}[/]")
            _print_table(summary_table(evaluations))
            _print_table(comparison_table(evaluations))
    except SensorlessError as exc:
        raise _fail(exc) from None


@app.command("demo")
def demo_command(
    output: Annotated[Path, typer.Option("--output", "-o", help="Output folder.")] = Path(
        "out/demo"
    ),
    quick: Annotated[bool, typer.Option("--quick", help="20 s runs instead of 60 s.")] = False,
) -> None:
    """The end-to-end demo: robots, then every shipped scenario tuned, detected and evaluated."""
    console.print(robot_summary())
    output.mkdir(parents=True, exist_ok=True)
    comparisons = []
    for name, joints in DEMO_SCENARIOS.items():
        scenario = load_scenario(name)
        if quick:
            scenario = scenario.with_duration(20.0)
        comparison = compare(scenario, joints=joints, progress=lambda text: console.log(text))
        comparisons.append(comparison)
        write_log(comparison.test_log, output / f"{name}-collision.parquet")
        console.print(f"[bold]{name}[/] (monitored joints: {list(joints) if joints else 'all'})")
        _print_table(comparison.summary())
        _print_table(comparison.per_collision())
        efficiency = comparison.efficiency()
        if efficiency is not None:
            _print_table(efficiency)
        for method, threshold in comparison.thresholds.items():
            save_tuned(
                output / f"{name}-{method}.yaml", threshold, ObserverSettings(kind=threshold.kind_)
            )
    report = write_comparison_report(comparisons, output / "report.html")
    console.print(f"report: {report}")


#: Scenarios of the demo and the joints it monitors (thesis §5.4 watches PUMA joints 1-3).
DEMO_SCENARIOS: dict[str, tuple[int, ...] | None] = {"puma560-thesis": (1, 2, 3), "panda-gaz": None}


def main() -> None:
    """Entry point of the ``sensorless`` script."""
    app()
