"""The end-to-end demo: every shipped scenario tuned, detected, evaluated and reported."""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Annotated

import typer
from rich.markup import escape
from rich.progress import (
    BarColumn,
    Progress,
    SpinnerColumn,
    TaskID,
    TextColumn,
    TimeElapsedColumn,
)
from threadpoolctl import threadpool_limits

from ..comparison import Comparison, compare, real_arm, write_comparison_report
from ..io import write_log
from ..monitor import ObserverSettings, save_tuned
from ..realarm import UR10_FOLDER
from ..simulation.scenario import load_scenario
from ..thresholds import CombinedVelocityThreshold
from ._common import console, print_table
from .run import robot_summary

__all__ = ["DEMO_SCENARIOS", "METHODS", "QUICK_DURATION", "demo_command"]


def demo_command(
    output: Annotated[Path, typer.Option("--output", "-o", help="Output folder.")] = Path(
        "out/demo"
    ),
    quick: Annotated[
        bool, typer.Option("--quick", help=f"{QUICK_DURATION:g} s runs of every scenario.")
    ] = False,
    real_data: Annotated[
        Path,
        typer.Option(
            "--real-data",
            help="Folder of the real UR10 recordings (ext_observer); absent: that section "
            "is skipped.",
        ),
    ] = UR10_FOLDER,
) -> None:
    """The end-to-end demo: robots, every shipped scenario tuned, detected and evaluated, then
    held-out false alarms on a real UR10 when its recordings are at hand.

    Every scenario runs two collision-free tuning runs and one collision run, each cut
    short (:data:`DEMO_SCENARIOS`): PUMA 21 s of 60 s (contacts 1-4), Panda 20 s of 60 s
    (3 random contacts), LWR 23 s of 160 s (contacts 1-3). The model-based threshold
    (PUMA, Panda) is fitted on one tuning run. The three runs of a scenario are simulated
    in three processes; the results equal a serial run's. (``compare`` can run them on
    Dask, ``scheduler=``; on 2 cores that took 5-12 s longer: its scheduler and nanny
    processes and the transfer of the logs cost more than overlapping the scenarios saved.)
    """
    # On a loaded machine OpenBLAS threads spin against the other processes: a velocity
    # least-squares fit took 4.5 s with the default threads, 1.0 s with one (load 3.3).
    _single_threaded_blas()
    console.print(robot_summary())
    output.mkdir(parents=True, exist_ok=True)
    scenarios = {}
    for name, (_, _, duration) in DEMO_SCENARIOS.items():
        seconds = QUICK_DURATION if quick else duration
        scenario = load_scenario(name)
        scenarios[name] = scenario if seconds is None else scenario.with_duration(seconds)
    comparisons = []
    for name, scenario in scenarios.items():
        joints, residuals, _ = DEMO_SCENARIOS[name]
        console.print(
            f"[bold]{name}[/]: {N_TUNING} tuning runs and a collision run of "
            f"{scenario.duration:g} s each"
        )
        with _stage_bars() as stage:
            comparison = compare(
                scenario,
                joints=joints,
                residuals=residuals,
                # The LWR comparison of the thesis is velocity-based vs time-variant.
                methods=METHODS if "joint" not in residuals else METHODS[:-1],
                n_tuning=N_TUNING,
                master_seed=MASTER_SEED,
                # One process per run: the 3 runs end together instead of 2 + 1 on 2 cores.
                workers=min(N_TUNING + 1, (os.cpu_count() or 1) + 1),
                progress=stage,
            )
        comparisons.append(comparison)
        _show(comparison, output)
    console.log(f"real arm: the UR10 recipe on {real_data}")
    real = real_arm(real_data)
    summary = real.summary()
    if summary is None:
        console.print(f"[bold]Real arm (UR10)[/]: skipped. {escape(real.skipped)}")
    else:
        console.print(
            f"[bold]Real arm (UR10)[/]: held-out false alarms, both folds pooled "
            f"({real.seconds:.1f} s)"
        )
        # Not print_table: its console markup would take the unit "[s]" for a style tag.
        console.print(summary.round(1).to_string(), markup=False, highlight=False, soft_wrap=True)
    report = write_comparison_report(comparisons, output / "report.html", real_arm=real)
    console.print(f"report: {report}")


def _show(comparison: Comparison, output: Path) -> None:
    """Print a comparison's tables; write its collision log and every tuned threshold."""
    name, joints = comparison.scenario, comparison.joints
    write_log(comparison.test_log, output / f"{name}-collision.parquet")
    console.print(f"[bold]{name}[/] (monitored joints: {list(joints) if joints else 'all'})")
    if "model" in comparison.thresholds:
        console.print(f"model-based threshold fitted on 1 tuning run of {name}")
    print_table(comparison.summary())
    print_table(comparison.per_collision())
    efficiency = comparison.efficiency()
    if efficiency is not None:
        print_table(efficiency)
    for label, threshold in comparison.thresholds.items():
        kind = comparison.kinds[label]
        if isinstance(threshold, CombinedVelocityThreshold):
            threshold = threshold.for_kind(kind)
        slug = label.replace(" (joint)", "-joint")
        save_tuned(output / f"{name}-{slug}.yaml", threshold, ObserverSettings(kind=kind))


def _single_threaded_blas() -> None:
    """Limit the BLAS libraries loaded in this process to one thread (``threadpoolctl``).

    The demo's worker processes simulate while this one tunes; BLAS threads of its
    own only spin against them (a least-squares fit of the velocity family took
    4.5 s with the default threads and 1.0 s with one, under load 3.3).
    """
    threadpool_limits(limits=1, user_api="blas")


@contextmanager
def _stage_bars() -> Iterator[Callable[[str], None]]:
    """One bar per stage of a comparison: each message opens a bar and completes the last."""
    columns = (
        SpinnerColumn(),
        TextColumn("{task.description}"),
        BarColumn(),
        TimeElapsedColumn(),
    )
    with Progress(*columns, console=console, transient=False) as progress:
        tasks: list[TaskID] = []

        def stage(text: str) -> None:
            if tasks:
                progress.update(tasks[-1], total=1.0, completed=1.0)
            tasks.append(progress.add_task(text, total=None))

        yield stage
        if tasks:
            progress.update(tasks[-1], total=1.0, completed=1.0)


#: Threshold families of the demo, the model-based one last.
METHODS = ("constant", "time-variant", "hysteretic", "velocity", "model")

#: Scenarios of the demo: monitored joints (the thesis watches joints 1-3 of the PUMA and of
#: the LWR), the residuals watched and the simulated time [s] of every run (None: the
#: scenario's). The cuts keep contacts 1-4 of the PUMA (15-50 N, the first two at the
#: thesis's times; its trajectory repeats every 5 s), 3 random contacts of the Panda and
#: contacts 1-3 of the LWR (25-60 N); the LWR's flexible joints simulate at about real
#: time, so its 160 s would take minutes.
DEMO_SCENARIOS: dict[str, tuple[tuple[int, ...] | None, tuple[str, ...], float | None]] = {
    "puma560-thesis": ((1, 2, 3), ("motor",), 21.0),
    "panda-gaz": (None, ("motor",), 20.0),
    "lwr4-thesis": ((1, 2, 3), ("motor", "joint"), 23.0),
}

#: Simulated time [s] of every run with ``--quick``.
QUICK_DURATION = 10.0

#: Tuning runs per scenario and the master seed of every run.
N_TUNING = 2
MASTER_SEED = 0
