"""The comparison's HTML report: the summary first, then every scenario in detail."""

from __future__ import annotations

import shlex
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from .._version import __version__
from ..plots import (
    describe,
    headroom,
    plot_collision,
    plot_detection_vs_force,
    plot_evaluation,
    plot_missed,
    plot_residuals,
)
from ..report import (
    GLOSSARY,
    Glossary,
    Picture,
    ScenarioSummary,
    Subheading,
    Table,
    collision_table,
    write_report,
)
from .realarm import RealArm
from .results import Comparison

REAL_ARM_HEADING = "Real arm (UR10)"
"""Heading of the report's real-arm section."""


def _efficiency_table(comparison: Comparison) -> Table | None:
    table = comparison.efficiency()
    if table is None:
        return None
    table = table.rename(
        index={"alpha": "α [N m]", "gamma": "γ [-]", "eps_fr": "ε_fr [-]", "beta": "β [N m]"}
    )
    table.index.name = "quantity"
    return Table(
        table,
        f"{comparison.scenario}: time-variant threshold per joint (thesis Table 5.7)",
        note="eff = α/β: below 1, the time-variant band is tighter than the constant one.",
    )


def _scenario_items(comparison: Comparison, summary: ScenarioSummary) -> list[Any]:
    """Details of one comparison: run, per-collision table, timeline, force, residuals, zooms."""
    log, evaluations = comparison.test_log, comparison.evaluations
    joints = list(comparison.joints) if comparison.joints else None
    items: list[Any] = [
        f"Seeds: tuning runs {comparison.seeds.get('tuning')}, test run "
        f"{comparison.seeds.get('test')}. Monitored joints: {joints or 'all'}. Test run: "
        f"{log.duration:.1f} s, collisions: {summary.values['detected of'].iloc[0]:.0f}.",
        collision_table(comparison.scenario, evaluations),
    ]
    efficiency = _efficiency_table(comparison)
    if efficiency is not None:
        items.append(efficiency)
    items.append(
        Picture(
            plot_evaluation(evaluations, title=f"{comparison.scenario}: alarms over time"),
            f"Timeline of {comparison.scenario}: per method its detections (green), false alarms "
            "(red), missed (cross) and masked (square) collisions. " + summary.sentence,
        )
    )
    windows = next(iter(evaluations.values())).windows
    if any(np.isfinite(w.peak_force) for w in windows):
        items.append(
            Picture(
                plot_detection_vs_force(
                    evaluations, title=f"{comparison.scenario}: detection against peak force"
                ),
                f"Detection rate of every method per peak-force bin on {comparison.scenario}, "
                "and every collision at its peak force (filled: detected, open: missed, "
                "square: masked).",
            )
        )
    for kind, kind_signals in comparison.signals.items():
        kind_methods = [m for m in comparison.bounds if comparison.kinds.get(m) == kind]
        if not kind_methods:
            continue
        title = f"{comparison.scenario}: {kind} residual and bounds"
        items.append(
            Picture(
                plot_residuals(
                    kind_signals,
                    {m: comparison.bounds[m] for m in kind_methods},
                    log=log,
                    events={m: comparison.events[m] for m in kind_methods},
                    joints=comparison.joints,
                    title=title,
                ),
                f"{title} over the whole run, as min/max envelopes; triangles mark detections, "
                "white crosses false alarms, red bands the collisions.",
            )
        )
    if windows:
        items.append(Subheading(f"{comparison.scenario}: every collision, ±0.5 s"))
    options: dict[str, Any] = {"kinds": comparison.kinds, "joints": comparison.joints}
    for window in windows:
        verdicts = describe(evaluations, window)
        items.append(
            Picture(
                plot_collision(
                    window, log, comparison.signals, comparison.bounds, evaluations, **options
                ),
                f"Collision {window.id}: residual, bounds and true external torque on the joints "
                f"that feel it; {verdicts}.",
            )
        )
        missed = plot_missed(window, comparison.signals, comparison.bounds, evaluations, **options)
        if missed is not None:
            margins = []
            for method, evaluation in evaluations.items():
                if bool(evaluation.per_collision.loc[window.id, ["detected", "masked"]].any()):
                    continue
                closest = headroom(
                    window,
                    comparison.signals[comparison.kinds.get(method, "motor")],
                    comparison.bounds[method],
                    joints=comparison.joints,
                    max_delay=evaluation.max_delay,
                )
                margins.append(f"{method} {closest.margin:.2f} N m (joint {closest.joint})")
            items.append(
                Picture(
                    missed,
                    f"Why collision {window.id} was missed: closest approach of the residual "
                    f"to the bound: {', '.join(margins)}.",
                )
            )
    return items


def _provenance(comparisons: Sequence[Comparison], command: str | None) -> dict[str, str]:
    facts = {"sensorless version": __version__}
    for comparison in comparisons:
        if comparison.seeds:
            facts[f"seeds of {comparison.scenario}"] = ", ".join(
                f"{key} {value}" for key, value in comparison.seeds.items()
            )
    facts["command"] = command if command is not None else shlex.join(sys.argv)
    return facts


def write_comparison_report(
    comparisons: Sequence[Comparison],
    path: str | Path,
    real_arm: RealArm | None = None,
    *,
    command: str | None = None,
    sections: Sequence[tuple[str, list[Any]]] = (),
) -> Path:
    """One self-contained HTML report: the summary first, then every comparison in detail.

    The first section has, per comparison, a sentence generated from the
    numbers and the summary table (:meth:`Comparison.overview`, the best
    value of each column in bold). Then per comparison: the start delay per
    collision, the time-variant threshold per joint (Table 5.7), the
    timeline of alarms, detection against peak force, the whole-run residual
    plots (min/max envelopes), and per collision a ±0.5 s zoom plus, when a
    method missed it, how far the residual stayed inside the band. A
    glossary explains every column once. With ``real_arm``, a last section
    "Real arm (UR10)": the held-out false-alarm table and the residual of a
    held-out recording, or why the recipe was skipped. ``sections``
    (heading, items), e.g. :func:`~sensorless.report.levels_section`, come
    after the comparisons. The footer states the library version, the seeds
    and ``command`` (default: this process's command line).
    """
    summaries = [comparison.overview() for comparison in comparisons]
    extra, sections = list(sections), []
    if summaries:
        overview: list[Any] = []
        for summary in summaries:
            overview += [Subheading(summary.name), summary.sentence, summary.to_table()]
        sections.append(("Summary", overview))
    for comparison, summary in zip(comparisons, summaries, strict=True):
        sections.append((comparison.scenario, _scenario_items(comparison, summary)))
    sections += extra
    if summaries:
        sections.append(("Glossary", [Glossary(GLOSSARY)]))
    if real_arm is not None:
        items = [
            Table(item, "Held-out false alarms per family on the real UR10")
            if isinstance(item, pd.DataFrame)
            else item
            for item in real_arm.report_items()
        ]
        sections.append((REAL_ARM_HEADING, items))
    return write_report(
        path,
        title="sensorless: threshold comparison",
        sections=sections,
        provenance=_provenance(comparisons, command),
    )
