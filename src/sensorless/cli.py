"""Command-line interface: a thin layer over the library (``sensorless --help``)."""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import pandas as pd
import typer
import yaml
from rich.console import Console
from rich.progress import BarColumn, Progress, TextColumn, TimeRemainingColumn
from rich.table import Table

from . import robots as robot_registry
from .comparison import compare, write_comparison_report
from .detection import events_to_pandas
from .evaluation import comparison_table, evaluate, summary_table
from .exceptions import InputValueError, SensorlessError
from .identification.excitation import optimize_excitation
from .identification.friction import identify_friction
from .identification.logs import identify_from_logs
from .io import Log, read_log, write_log
from .monitor import METHOD_NAMES, CollisionMonitor, ObserverSettings, load_tuned, save_tuned, tune
from .report import write_report
from .robots.base_parameters import base_parameters
from .robots.model import RobotModel
from .signals import Event
from .simulation.scenario import available_scenarios, load_scenario
from .simulation.simulator import SimulationResult
from .thresholds import CombinedVelocityThreshold

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


def _nominal_robot(robot: str | None, log: Log | None, kind: str = "motor") -> RobotModel:
    """The nominal model: a built-in name, a URDF path, ``scenario:NAME``, or the log's scenario.

    A scenario gives the model the observer ``kind`` needs (:meth:`Scenario.nominal`).
    """
    if robot is None:
        scenario = None if log is None else log.metadata.get("scenario")
        if not scenario:
            raise InputValueError(
                "give --robot (a built-in name, a URDF file or scenario:NAME); "
                "the log names no scenario"
            )
        robot = f"scenario:{scenario}"
    if robot.startswith("scenario:"):
        return load_scenario(robot.split(":", 1)[1]).nominal(kind)
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
        settings = ObserverSettings(kind=kind or METHOD_NAMES.get(method, "motor"), gain=gain)
        nominal = _nominal_robot(robot, runs[0], settings.kind)
        threshold, settings = tune(runs, nominal, method, settings, margin=margin)
        path = save_tuned(output, threshold, settings)
    except SensorlessError as exc:
        raise _fail(exc) from None
    console.print(f"wrote {path}: {threshold!r} fitted on {len(runs)} log(s) of {nominal.name}")


def _detect(log_path: Path, thresholds: Path, robot: str | None) -> tuple[Log, str, list[Event]]:
    log = read_log(log_path)
    threshold, settings = load_tuned(thresholds)
    monitor = CollisionMonitor(_nominal_robot(robot, log, settings.kind), threshold, settings)
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
    for name, (joints, residuals, duration) in DEMO_SCENARIOS.items():
        scenario = load_scenario(name)
        if quick:
            scenario = scenario.with_duration(20.0)
        elif duration is not None:
            scenario = scenario.with_duration(duration)
        comparison = compare(
            scenario,
            joints=joints,
            residuals=residuals,
            # The LWR comparison of the thesis is velocity-based vs time-variant; the
            # model-based fit on 100 s of a 7-joint flexible arm would double the demo.
            methods=METHODS if "joint" not in residuals else METHODS[:-1],
            workers=min(3, os.cpu_count() or 1),
            progress=lambda text: console.log(text),
        )
        comparisons.append(comparison)
        write_log(comparison.test_log, output / f"{name}-collision.parquet")
        console.print(f"[bold]{name}[/] (monitored joints: {list(joints) if joints else 'all'})")
        _print_table(comparison.summary())
        _print_table(comparison.per_collision())
        efficiency = comparison.efficiency()
        if efficiency is not None:
            _print_table(efficiency)
        for label, threshold in comparison.thresholds.items():
            kind = comparison.kinds[label]
            if isinstance(threshold, CombinedVelocityThreshold):
                threshold = threshold.for_kind(kind)
            slug = label.replace(" (joint)", "-joint")
            save_tuned(output / f"{name}-{slug}.yaml", threshold, ObserverSettings(kind=kind))
    report = write_comparison_report(comparisons, output / "report.html")
    console.print(f"report: {report}")


#: Threshold families of the demo, the model-based one last.
METHODS = ("constant", "time-variant", "hysteretic", "velocity", "model")

#: Scenarios of the demo: monitored joints (the thesis watches joints 1-3 of the PUMA and of
#: the LWR), the residuals watched and the simulated time [s] (None: the scenario's; the
#: LWR run is cut after its last contact, at 98.4 s, to keep the demo short).
DEMO_SCENARIOS: dict[str, tuple[tuple[int, ...] | None, tuple[str, ...], float | None]] = {
    "puma560-thesis": ((1, 2, 3), ("motor",), None),
    "panda-gaz": (None, ("motor",), None),
    "lwr4-thesis": ((1, 2, 3), ("motor", "joint"), 100.0),
}


identify_app = typer.Typer(help="Identify friction and inertial parameters from logs.")
app.add_typer(identify_app, name="identify")


def _write_yaml(path: Path, content: dict[str, Any]) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(yaml.safe_dump(content, sort_keys=False, allow_unicode=True), encoding="utf-8")
    return path


@identify_app.command("friction")
def identify_friction_command(
    logs: Annotated[list[Path], typer.Argument(help="Constant-velocity sweep logs.")],
    robot: Annotated[
        str | None, typer.Option("--robot", help="Nominal model for g(q) (default: the log's).")
    ] = None,
    output: Annotated[
        Path, typer.Option("-o", "--output", help="Result file (YAML); a .html report beside it.")
    ] = Path("friction.yaml"),
    torque: Annotated[
        str, typer.Option("--torque", help="motor (eq. 2.6) or joint (eq. 2.10) torques.")
    ] = "motor",
) -> None:
    """Friction maps and Coulomb, Coulomb + viscous and Stribeck fits from sweeps (§2.4.1)."""
    try:
        results = []
        for path in logs:
            log = read_log(path)
            model = _nominal_robot(robot, log, "joint" if torque == "joint" else "motor")
            results.append((path, identify_friction(log, model, torque=torque)))
    except SensorlessError as exc:
        raise _fail(exc) from None
    _write_yaml(output, {str(path): result.to_dict() for path, result in results})
    sections: list[tuple[str, Any]] = [
        (str(path), [result.to_pandas(), result.plot()]) for path, result in results
    ]
    report = write_report(
        output.with_suffix(".html"), title="sensorless: friction identification", sections=sections
    )
    for path, result in results:
        console.print(f"[bold]{path}[/]")
        _print_table(result.to_pandas())
    console.print(f"wrote {output} and {report}")


@identify_app.command("inertial")
def identify_inertial_command(
    logs: Annotated[list[Path], typer.Argument(help="Logs of the moving robot.")],
    robot: Annotated[str, typer.Option("--robot", help="Built-in name, URDF or scenario:NAME.")],
    output: Annotated[
        Path, typer.Option("-o", "--output", help="Result file (YAML); a .html report beside it.")
    ] = Path("inertial.yaml"),
    torque: Annotated[str, typer.Option("--torque", help="motor or joint torques.")] = "motor",
    zero: Annotated[
        list[str] | None, typer.Option("--zero", help="Standard parameter known to be zero.")
    ] = None,
) -> None:
    """Base inertial and friction parameters by least squares (eq. 2.12-2.13)."""
    try:
        runs = [read_log(path) for path in logs]
        model = _nominal_robot(robot, runs[0], "joint" if torque == "joint" else "motor")
        base, result = identify_from_logs(runs, model, torque=torque, zero=zero or ())
    except SensorlessError as exc:
        raise _fail(exc) from None
    table = result.to_pandas()
    nominal = dict(zip(base.names, base.values, strict=True))
    table.insert(0, "nominal", [nominal.get(name, np.nan) for name in table.index])
    table.insert(0, "formula", [base.formula(n) if n in nominal else "" for n in table.index])
    stats = {
        "r_squared": result.r_squared,
        "residual_std [N m]": result.residual_std,
        "condition_number": result.condition_number,
        "n_rows": result.n_samples,
    }
    _write_yaml(
        output,
        {
            "robot": model.name,
            "torque": torque,
            "logs": [str(path) for path in logs],
            "statistics": stats,
            "units": "kg m² (XX..ZZ, Ia), kg m (mX..mZ), kg (m), N m (c_pos, c_neg), "
            "N m s/rad (fv)",
            "parameters": {
                name: {
                    key: float(value) if key != "formula" else value for key, value in row.items()
                }
                for name, row in table.to_dict(orient="index").items()
            },
        },
    )
    report = write_report(
        output.with_suffix(".html"),
        title=f"sensorless: inertial identification of {model.name}",
        sections=[("Statistics", pd.Series(stats)), ("Parameters", table)],
    )
    _print_table(table)
    console.print(f"R² = {result.r_squared:.6f}; wrote {output} and {report}")


@app.command("excite")
def excite_command(
    robot: Annotated[str, typer.Option("--robot", help="Built-in name or URDF.")],
    output: Annotated[Path, typer.Option("-o", "--output", help="Trajectory (YAML).")] = Path(
        "excitation.yaml"
    ),
    harmonics: Annotated[int, typer.Option("--harmonics", help="Fourier harmonics.")] = 5,
    frequency: Annotated[
        float, typer.Option("--frequency", help="Fundamental frequency [Hz].")
    ] = 0.1,
    seed: Annotated[int, typer.Option("--seed", help="Seed of the random starts.")] = 0,
    iterations: Annotated[int, typer.Option("--iterations", help="SLSQP iterations.")] = 100,
) -> None:
    """Optimise a Fourier excitation trajectory (Swevers 1997) for the base regressor."""
    try:
        model = _nominal_robot(robot, None)
        result = optimize_excitation(
            model,
            n_harmonics=harmonics,
            base_frequency=frequency,
            seed=seed,
            max_iterations=iterations,
        )
        path = result.to_yaml(output)
    except SensorlessError as exc:
        raise _fail(exc) from None
    _print_table(result.to_pandas())
    console.print(
        f"condition number {result.initial_condition_number:.4g} -> "
        f"{result.condition_number:.4g}; wrote {path}"
    )


def main() -> None:
    """Entry point of the ``sensorless`` script."""
    app()
