"""``sensorless benchmark``: the detection benchmark on Dask (or in this process)."""

from __future__ import annotations

import dataclasses
import time
from pathlib import Path
from typing import Annotated, Any

import typer
from rich.progress import BarColumn, MofNCompleteColumn, Progress, TextColumn, TimeElapsedColumn

from ..benchmark import BenchmarkScenario, full_config, quick_config, run_benchmark
from ..exceptions import InputValueError, one_line
from ._common import console, print_table

__all__ = ["MAX_DURATION", "MAX_RUNS", "benchmark_command"]

MAX_RUNS = 100_000
"""Most runs of each kind (--tuning, --collision, --free) ``benchmark`` accepts."""
MAX_DURATION = 100_000.0
"""Longest run [s] ``benchmark`` accepts (28 h)."""

_SHOWN = [
    "scenario", "method", "n_detected", "n_collisions", "detection_rate", "strong_rate",
    "false_alarms_per_hour", "false_alarms_high", "delay_median", "delay_p95", "delay_ratio",
    "eff",
]  # fmt: skip
_CONTACTS = [
    "scenario", "method", "n_scored", "link_rate", "link_low", "link_high",
    "point_error_median", "force_error_median", "force_error_p95",
    "force_error_filtered_median", "direction_error_median", "accuracy",
]  # fmt: skip


def benchmark_command(
    output: Annotated[Path, typer.Option("--output", "-o", help="Output folder.")] = Path(
        "out/benchmark"
    ),
    quick: Annotated[
        bool,
        typer.Option(
            "--quick", help="Two short scenarios, 3/10/5 runs each (under 5 min on 2 cores)."
        ),
    ] = False,
    scenario: Annotated[
        list[str] | None,
        typer.Option(
            "--scenario", help="Scenario name or YAML file (repeat; replaces the preset)."
        ),
    ] = None,
    duration: Annotated[
        float | None, typer.Option("--duration", help="Simulated time of each run, in seconds.")
    ] = None,
    method: Annotated[
        list[str] | None,
        typer.Option("--method", help="Threshold family (repeat); default the four fast ones."),
    ] = None,
    n_tuning: Annotated[
        int | None, typer.Option("--tuning", min=1, max=MAX_RUNS, help="Tuning runs N.")
    ] = None,
    n_collision: Annotated[
        int | None, typer.Option("--collision", min=1, max=MAX_RUNS, help="Collision test runs M.")
    ] = None,
    n_free: Annotated[
        int | None, typer.Option("--free", min=1, max=MAX_RUNS, help="Collision-free test runs K.")
    ] = None,
    seed: Annotated[int, typer.Option("--seed", help="Master seed of every run.")] = 0,
    false_alarm_rate: Annotated[
        float | None,
        typer.Option("--false-alarm-rate", help="Tune every method for this many false alarms/h."),
    ] = None,
    scheduler: Annotated[
        str,
        typer.Option(
            "--scheduler", help="local (a Dask LocalCluster), serial, or tcp://host:port."
        ),
    ] = "local",
    workers: Annotated[
        int | None, typer.Option("--workers", help="Worker processes of the local cluster.")
    ] = None,
    retries: Annotated[int, typer.Option("--retries", help="Retries of a failed task.")] = 2,
    logs: Annotated[
        str | None,
        typer.Option("--logs", help="Write every run's log here (folder or fsspec URL)."),
    ] = None,
    interactions: Annotated[
        int | None,
        typer.Option(
            "--interactions",
            help="Collision runs carry this many random guiding/clamp/impact contacts instead "
            "of the scenario's own (intended and collision classes).",
        ),
    ] = None,
    isolation: Annotated[
        bool,
        typer.Option(
            "--isolation/--no-isolation",
            help="Isolate and classify every event of the collision runs.",
        ),
    ] = True,
) -> None:
    """Tune every method on N runs, judge it on M collision and K collision-free runs.

    Writes Parquet tables of every run, collision and event, a summary with
    Wilson and Poisson intervals (Parquet + CSV), the isolation and
    classification of the collision runs' events (contacts and confusion
    tables), PNG figures and index.html.
    """
    if duration is not None and not 0.0 < duration <= MAX_DURATION:  # NaN fails too
        raise InputValueError(f"--duration must be > 0 and <= {MAX_DURATION:g} s; got {duration!r}")
    if logs is not None and "://" in logs:
        import fsspec  # type: ignore[import-untyped]  # a dependency of dask

        protocol = logs.split("://", 1)[0]
        try:
            fsspec.get_filesystem_class(protocol)
        except (ImportError, ValueError) as exc:
            raise InputValueError(f"--logs {logs!r}: {one_line(exc)}") from None
    overrides: dict[str, Any] = {"false_alarm_rate": false_alarm_rate, "isolation": isolation}
    for key, value in (("n_tuning", n_tuning), ("n_collision", n_collision), ("n_free", n_free)):
        if value is not None:
            overrides[key] = value
    if method:
        overrides["methods"] = tuple(method)
    if scenario:
        overrides["scenarios"] = tuple(BenchmarkScenario(name, duration) for name in scenario)
    config = (quick_config if quick else full_config)(seed, **overrides)
    if duration is not None and not scenario:
        cut = tuple(dataclasses.replace(c, duration=duration) for c in config.scenarios)
        config = dataclasses.replace(config, scenarios=cut)
    if interactions is not None:
        drawn = tuple(dataclasses.replace(c, interactions=interactions) for c in config.scenarios)
        config = dataclasses.replace(config, scenarios=drawn)
    output.mkdir(parents=True, exist_ok=True)
    columns = (
        TextColumn("{task.description}"),
        BarColumn(),
        MofNCompleteColumn(),
        TimeElapsedColumn(),
    )
    start = time.perf_counter()
    with Progress(*columns, console=console) as bar:
        task = bar.add_task("benchmark", total=None)

        def report(done: int, total: int, name: str) -> None:
            bar.update(task, completed=done, total=total, description=name)

        result = run_benchmark(
            config, scheduler=scheduler, n_workers=workers, retries=retries, log_dir=logs,
            progress=report,
        )  # fmt: skip
    seconds = time.perf_counter() - start
    written = result.write(output)
    print_table(result.summary()[_SHOWN].set_index(["scenario", "method"]))
    if config.isolation:
        print_table(result.contacts()[_CONTACTS].set_index(["scenario", "method"]))
    console.print(
        f"{len(result.timings)} tasks on {result.workers} process(es) in {seconds:.1f} s "
        f"(task time {result.timings['seconds'].sum():.1f} s); outputs: {written['index']}"
    )
