"""``sensorless report``: the comparison report's figures and HTML for one's own log."""

from __future__ import annotations

import shlex
from pathlib import Path
from typing import Annotated, Any

import typer

from ..comparison import Comparison, write_comparison_report
from ..evaluation import DEFAULT_MAX_DELAY, evaluate
from ..exceptions import InputValueError
from ..io import Log, read_log
from ..monitor import CollisionMonitor, LevelledMonitor, ObserverSettings, load_tuned
from ..report import levels_section
from ..signals import Event, ObserverSignals
from ..thresholds import Threshold
from ._common import console, nominal_robot, output_path

__all__ = ["build_comparison", "report_command"]

RULE = (
    "Scoring: an alarm detects a collision when it starts during the contact or at most "
    f"{DEFAULT_MAX_DELAY:g} s after its end; an alarm already on when a contact starts is "
    "a false alarm, and that contact counts as masked, never as detected with a negative delay."
)


def _label(path: Path, threshold: Threshold, names: list[str]) -> str:
    """The family name, or with the file name when two files hold the same family."""
    return threshold.name if names.count(threshold.name) == 1 else f"{threshold.name} ({path.name})"


def build_comparison(log: Log, name: str, thresholds: list[Path], robot: str | None) -> Comparison:
    """Run the monitor of every threshold file over ``log`` and score it, as :func:`compare` does.

    Methods whose observer settings agree share one residual; otherwise each
    gets its own.
    """
    if not thresholds:
        raise InputValueError("give at least one --thresholds FILE written by `sensorless tune`")
    tuned = [(path, *load_tuned(path)) for path in thresholds]
    names = [threshold.name for _, threshold, _ in tuned]
    fitted: dict[str, Threshold] = {}
    signals: dict[str, ObserverSignals] = {}
    shared: dict[str, ObserverSettings] = {}
    bounds: dict[str, Any] = {}
    events: dict[str, list[Event]] = {}
    evaluations = {}
    kinds: dict[str, str] = {}
    joints: set[int] = set()
    for path, threshold, settings in tuned:
        label = _label(path, threshold, names)
        if label in fitted:
            raise InputValueError(f"the threshold file {path} is given twice")
        monitor = CollisionMonitor(nominal_robot(robot, log, settings.kind), threshold, settings)
        run = monitor.process(log)
        key = settings.kind if shared.get(settings.kind, settings) == settings else label
        shared.setdefault(settings.kind, settings)
        signals.setdefault(key, run.signals)
        fitted[label], kinds[label], events[label] = threshold, key, run.events
        bounds[label] = threshold.bounds(run.signals)
        evaluations[label] = evaluate(run.events, log, method=label)
        joints |= set(threshold.monitored_joints_)
    seeds = {"simulation": log.metadata["seed"]} if "seed" in log.metadata else {}
    return Comparison(
        name, tuple(sorted(joints)), fitted, evaluations, signals, bounds, events, log, seeds, kinds
    )


def report_command(
    log: Annotated[Path, typer.Argument(help="Log to report on (labelled or not).")],
    thresholds: Annotated[
        list[Path], typer.Option("--thresholds", help="File written by `tune`; repeat to compare.")
    ],
    robot: Annotated[
        str | None, typer.Option("--robot", help="Nominal model (default: the log's scenario).")
    ] = None,
    output: Annotated[
        Path, typer.Option("-o", "--output", help="The HTML report to write.")
    ] = Path("report.html"),
    contact_threshold: Annotated[
        Path | None,
        typer.Option(
            "--contact-threshold",
            help="File written by `tune` for the lower, contact band: the report adds the "
            "events by level (contact, collision = the first --thresholds).",
        ),
    ] = None,
) -> None:
    """Write the HTML report (summary, tables, figures) of thresholds on one log."""
    destination = output_path(output, suffixes=(".html", ".htm"))
    data = read_log(log, allow_missing=True)
    comparison = build_comparison(data, log.name, thresholds, robot)
    command = ["sensorless", "report", str(log)]
    for path in thresholds:
        command += ["--thresholds", str(path)]
    if robot is not None:
        command += ["--robot", robot]
    command += ["-o", str(output)]
    sections = []
    if contact_threshold is not None:
        command += ["--contact-threshold", str(contact_threshold)]
        threshold, settings = load_tuned(thresholds[0])
        contact, _ = load_tuned(contact_threshold)
        monitor = CollisionMonitor(nominal_robot(robot, data, settings.kind), threshold, settings)
        levelled = LevelledMonitor(monitor, contact).process(data)
        sections.append(levels_section(levelled.events, log=data))
    summary = comparison.overview()
    console.print(summary.sentence, markup=False, highlight=False)
    console.print(RULE, markup=False, highlight=False)
    written = write_comparison_report(
        [comparison], destination, command=shlex.join(command), sections=sections
    )
    console.print(f"report: {written}", markup=False, highlight=False)
