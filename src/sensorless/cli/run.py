"""Commands over logs: list robots and scenarios, simulate, tune, detect, evaluate."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer
from rich.table import Table

from .. import robots as robot_registry
from .._validation import check_dt
from ..detection import events_to_pandas
from ..detection.levels import threshold_label
from ..evaluation import comparison_table, evaluate, summary_table
from ..exceptions import InputValueError
from ..io import Log, read_log, write_log
from ..monitor import (
    METHOD_NAMES,
    CollisionMonitor,
    LevelledMonitor,
    MonitorRun,
    ObserverSettings,
    calibration_of,
    load_tuned,
    save_tuned,
    tune,
)
from ..robots.base_parameters import base_parameters
from ..simulation.scenario import available_scenarios, load_scenario
from ..thresholds.files import family_name
from ._common import console, nominal_robot, output_path, print_table, run_with_progress

__all__ = [
    "MAX_SAMPLES",
    "detect_command",
    "evaluate_command",
    "robot_summary",
    "robots_command",
    "scenarios_command",
    "simulate_command",
    "tune_command",
]

MAX_SAMPLES = 1e8
"""Longest run ``simulate`` accepts [samples] (28 h at 1 kHz): longer ones do not fit in memory."""


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


def robots_command() -> None:
    """Summarise the built-in robots (joints, base-parameter count, Yπ = RNEA check)."""
    console.print(robot_summary())


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


def simulate_command(
    scenario: Annotated[str, typer.Argument(help="Shipped scenario name or path of a YAML file.")],
    output: Annotated[
        Path, typer.Option("-o", "--output", help="Log file (.parquet or .csv).")
    ] = Path("run.parquet"),
    seed: Annotated[
        int | None, typer.Option("--seed", min=0, help="Run seed (default: the scenario's).")
    ] = None,
    collisions: Annotated[
        bool, typer.Option("--collisions/--no-collisions", help="Include the contacts.")
    ] = True,
    duration: Annotated[
        float | None,
        typer.Option(
            "--duration",
            min=0.001,
            help="Simulated time [s] (default: the scenario's; random contacts scale with it).",
        ),
    ] = None,
) -> None:
    """Simulate a scenario and write its labelled log."""
    spec = load_scenario(scenario)
    if duration is not None:
        spec = spec.with_duration(check_dt(duration, "--duration"))
    n_samples = spec.duration / spec.dt
    if n_samples > MAX_SAMPLES:
        raise InputValueError(
            f"a run of {spec.duration:g} s at dt = {spec.dt:g} s is {n_samples:.3g} samples; "
            f"at most {MAX_SAMPLES:.0e} are simulated (lower --duration or the file's duration)"
        )
    output_path(output, suffixes=(".parquet", ".pq", ".csv"))
    result = run_with_progress(
        f"simulating {spec.name}",
        lambda report: spec.run(seed=seed, collisions=collisions, progress=report),
    )
    path = write_log(result.log, output)
    console.print(
        f"wrote {path} ({result.log.n_samples} samples, {result.substeps} RK4 substeps per period)"
    )


def tune_command(
    logs: Annotated[list[Path], typer.Argument(help="Collision-free logs.")],
    method: Annotated[
        str,
        typer.Option(
            "--method",
            help="constant, time-variant, hysteretic, velocity or model (model-based).",
        ),
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
    margin_fraction: Annotated[
        float | None,
        typer.Option(
            "--margin-fraction",
            min=0.0,
            help="Margin added to the bounds of each joint, as a fraction of the constant band "
            "β_j = max |r_j| of the logs (default 0.1: 10 %).",
        ),
    ] = None,
    margin: Annotated[
        float | None,
        typer.Option(
            "--margin",
            min=0.0,
            help="Margin added to the bounds [N m], the same on every joint "
            "(instead of --margin-fraction).",
        ),
    ] = None,
    false_alarm_rate: Annotated[
        float | None,
        typer.Option(
            "--false-alarm-rate",
            help="Stated false alarms per hour for the robot: sets the margin "
            "(not with --margin or --margin-fraction).",
        ),
    ] = None,
    folds: Annotated[
        str,
        typer.Option("--folds", help="Cross-validation folds: 'runs' or an integer >= 2."),
    ] = "runs",
) -> None:
    """Fit a threshold family on collision-free logs, cross-validate it and save it.

    Prints the false alarms per hour to expect (cross-validated on the logs,
    with its interval) and why the logs may not support that figure.
    """
    folds_value = int(folds) if folds.strip().isdigit() else folds  # the library names the rest
    output_path(output, suffixes=(".yaml", ".yml"))
    runs = [read_log(path) for path in logs]
    settings = ObserverSettings(kind=kind or METHOD_NAMES.get(method, "motor"), gain=gain)
    nominal = nominal_robot(robot, runs[0], settings.kind)
    options: dict[str, Any] = {} if margin is None else {"margin": margin}
    threshold, settings = tune(
        runs, nominal, method, settings, false_alarm_rate=false_alarm_rate, folds=folds_value,
        margin_fraction=margin_fraction, **options,
    )  # fmt: skip
    path = save_tuned(output, threshold, settings)
    console.print(
        f"wrote {path}: {family_name(threshold)} threshold fitted on {len(runs)} log(s) of "
        f"{nominal.name}",
        highlight=False,
    )
    margins = ", ".join(
        f"{value:.3g}" for value in np.broadcast_to(threshold.margin, (nominal.n_dof,))
    )
    console.print(f"margin per joint [N m]: {margins}", highlight=False)
    calibration = calibration_of(threshold)
    if calibration is not None:
        for line in calibration.summary():
            console.print(line, markup=False, highlight=False)


def _detect(log_path: Path, thresholds: Path, robot: str | None) -> tuple[Log, str, MonitorRun]:
    log = read_log(log_path, allow_missing=True)  # lost samples: reported as fault spans
    threshold, settings = load_tuned(thresholds)
    monitor = CollisionMonitor(nominal_robot(robot, log, settings.kind), threshold, settings)
    return log, family_name(threshold), monitor.process(log)


def _print_faults(result: MonitorRun) -> None:
    if result.faults:
        console.print(
            f"{len(result.faults)} span(s) refused as faults (the monitor restarted after each):"
        )
        print_table(result.faults_to_pandas())


def detect_command(
    log: Annotated[Path, typer.Argument(help="Log to check.")],
    thresholds: Annotated[Path, typer.Option("--thresholds", help="File written by `tune`.")],
    robot: Annotated[
        str | None, typer.Option("--robot", help="Nominal model (default: the log's scenario).")
    ] = None,
    contact_threshold: Annotated[
        Path | None,
        typer.Option(
            "--contact-threshold",
            help="File of a lower, contact-level threshold on the same residual: every "
            "excursion beyond it is printed with its level, contact or collision (the "
            "--thresholds file is the collision level).",
        ),
    ] = None,
) -> None:
    """Detect collisions in a log and print the events, and the false alarms tuning expected."""
    if contact_threshold is not None:
        _detect_levels(log, thresholds, contact_threshold, robot)
        return
    _, method, result = _detect(log, thresholds, robot)
    _print_faults(result)
    console.print(f"{len(result.events)} event(s) detected by {method}")
    if result.events:
        print_table(events_to_pandas(result.events))
    calibration = calibration_of(load_tuned(thresholds)[0])
    if calibration is not None:
        console.print("expected at tuning:", highlight=False)
        for line in calibration.summary():
            console.print(f"  {line}", markup=False, highlight=False)


def _detect_levels(log_path: Path, thresholds: Path, contact_path: Path, robot: str | None) -> None:
    """``detect --contact-threshold``: the events beyond the contact band, with their level."""
    log = read_log(log_path, allow_missing=True)
    threshold, settings = load_tuned(thresholds)
    contact, _ = load_tuned(contact_path)
    monitor = CollisionMonitor(nominal_robot(robot, log, settings.kind), threshold, settings)
    result = LevelledMonitor(monitor, contact).process(log)
    _print_faults(result.run)
    counts = result.counts()
    console.print(
        f"{len(result.events)} event(s) beyond the contact band ({threshold_label(contact)}): "
        f"{counts['contact']} contact, {counts['collision']} collision (also beyond the "
        f"collision band, {threshold_label(threshold)})",
        highlight=False,
    )
    if result.events:
        print_table(result.events_to_pandas())


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
    for log_path in logs:
        evaluations = {}
        for path in thresholds:
            log, method, result = _detect(log_path, path, robot)
            _print_faults(result)
            evaluations[f"{method} ({path.name})"] = evaluate(result.events, log, method=method)
        console.print(f"[bold]{log_path}[/]")
        print_table(summary_table(evaluations))
        print_table(comparison_table(evaluations))
